/* OpcShutdownNotifyBounded with clients hung in ShutdownRequest, through the public header: however
 * often the server notifies, a hung client is called once and holds one thread, the process never
 * has more than OPC_SHUTDOWN_MAX_NOTIFY_THREADS notification threads (counted as the process's
 * threads: Toolhelp32 on Windows, /proc/self/task on Linux), and a healthy client is notified every
 * time, also once hung clients hold every one of those threads (the notifying thread then calls it
 * itself). Its own process: it fills the library's process-wide pool of notification threads. */
#ifdef _WIN32
#include <windows.h>
#include <tlhelp32.h>
#else
#include <dirent.h>
#include <pthread.h>
#include <time.h>
#endif

#include "test_util.h"

#define HUNG 10        /* clients hung on the first server object */
#define ROUNDS 30      /* notifications of it */
#define TIMEOUT_MS 1000 /* each notification's deadline: a healthy client answers well within it (hung
                           clients cost it twice: the first time each group of them is called) */

/* ---- What differs between Windows and Linux: threads, a gate, atomic counts. ---- */
#ifdef _WIN32
typedef DWORD thread_id;
static thread_id this_thread(void) { return GetCurrentThreadId(); }
static int same_thread(thread_id a, thread_id b) { return a == b; }
static void pause_a_little(void) { Sleep(10); }
static long count_up(volatile long *n) { return InterlockedIncrement(n); }
static long count_read(volatile long *n) { return InterlockedCompareExchange(n, 0, 0); }

static unsigned long process_threads(void) {
    HANDLE snap = CreateToolhelp32Snapshot(TH32CS_SNAPTHREAD, 0);
    THREADENTRY32 te;
    unsigned long n = 0;
    DWORD me = GetCurrentProcessId();
    if (snap == INVALID_HANDLE_VALUE) return 0;
    te.dwSize = sizeof te;
    if (Thread32First(snap, &te)) {
        do {
            if (te.th32OwnerProcessID == me) n++;
        } while (Thread32Next(snap, &te));
    }
    CloseHandle(snap);
    return n;
}

static HANDLE gate;
static void gate_init(void) { gate = CreateEventW(NULL, TRUE, FALSE, NULL); }
static void gate_wait(void) { WaitForSingleObject(gate, INFINITE); }
static void gate_open(void) { SetEvent(gate); }
#else
typedef pthread_t thread_id;
static thread_id this_thread(void) { return pthread_self(); }
static int same_thread(thread_id a, thread_id b) { return pthread_equal(a, b); }
static void pause_a_little(void) {
    struct timespec t = {0, 10 * 1000 * 1000};
    nanosleep(&t, NULL);
}
static long count_up(volatile long *n) { return __atomic_add_fetch(n, 1, __ATOMIC_SEQ_CST); }
static long count_read(volatile long *n) { return __atomic_load_n(n, __ATOMIC_SEQ_CST); }

static unsigned long process_threads(void) {
    DIR *d = opendir("/proc/self/task");
    struct dirent *e;
    unsigned long n = 0;
    if (!d) return 0;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] != '.') n++;
    }
    closedir(d);
    return n;
}

static pthread_mutex_t gate_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t gate_changed = PTHREAD_COND_INITIALIZER;
static int gate_is_open;
static void gate_init(void) {}
static void gate_wait(void) {
    pthread_mutex_lock(&gate_lock);
    while (!gate_is_open) pthread_cond_wait(&gate_changed, &gate_lock);
    pthread_mutex_unlock(&gate_lock);
}
static void gate_open(void) {
    pthread_mutex_lock(&gate_lock);
    gate_is_open = 1;
    pthread_cond_broadcast(&gate_changed);
    pthread_mutex_unlock(&gate_lock);
}
#endif

/* ---- A client sink: hung (waits for the gate) or healthy (answers at once). ---- */
typedef struct Sink {
    IOPCShutdown iface;
    volatile long refs;
    volatile long calls;
    int hung;
    thread_id last_thread; /* where the last call came from (healthy sinks) */
} Sink;

static HRESULT STDMETHODCALLTYPE sink_qi(IOPCShutdown *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (same_iid(riid, &IID_Unknown_) || same_iid(riid, &IID_IOPCShutdown)) {
        *ppv = This;
        This->lpVtbl->AddRef(This);
        return S_OK;
    }
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE sink_add_ref(IOPCShutdown *This) { return (ULONG)count_up(&((Sink *)This)->refs); }
static ULONG STDMETHODCALLTYPE sink_release(IOPCShutdown *This) {
    Sink *s = (Sink *)This;
#ifdef _WIN32
    return (ULONG)InterlockedDecrement(&s->refs);
#else
    return (ULONG)__atomic_sub_fetch(&s->refs, 1, __ATOMIC_SEQ_CST);
#endif
}
static HRESULT STDMETHODCALLTYPE sink_shutdown_request(IOPCShutdown *This, LPCWSTR reason) {
    Sink *s = (Sink *)This;
    (void)reason;
    if (s->hung) {
        count_up(&s->calls);
        gate_wait();
    } else {
        s->last_thread = this_thread();
        count_up(&s->calls);
    }
    return S_OK;
}
static IOPCShutdownVtbl sink_vtbl = {sink_qi, sink_add_ref, sink_release, sink_shutdown_request};

static void sink_init(Sink *s, int hung) {
    memset(s, 0, sizeof *s);
    s->iface.lpVtbl = &sink_vtbl;
    s->refs = 1;
    s->hung = hung;
}

/* A shutdown object that takes `limit` sinks. */
static IUnknown *create_server(uint32_t limit) {
    OpcShutdownOptions o;
    IUnknown *server = NULL;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.advise_limit = limit;
    CHECK_HR(OpcShutdownCreateEx(&o, NULL, &IID_Unknown_, (void **)&server), S_OK);
    return server;
}

static void advise(IUnknown *server, Sink *s) {
    DWORD cookie = 0;
    CHECK_HR(OpcShutdownAdvise(server, (IUnknown *)&s->iface, &cookie), S_OK);
}

static HRESULT notify(IUnknown *server, ULONG *notified, ULONG *failed, ULONG *timed_out) {
    OpcShutdownNotifyOptions o;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.timeout_ms = TIMEOUT_MS;
    *notified = *failed = *timed_out = GARBAGE_U32;
    return OpcShutdownNotifyBounded(server, W("going down"), &o, notified, failed, timed_out);
}

static Sink hung_first[HUNG], hung_rest[OPC_SHUTDOWN_MAX_NOTIFY_THREADS - HUNG], healthy;

int main(void) {
    uint32_t objects = OpcObjectCount();
    unsigned long base, most = 0, now;
    IUnknown *first, *rest;
    ULONG n, f, t;
    long total;
    int i, waited;
#ifdef _WIN32
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
#endif
    setvbuf(stdout, NULL, _IONBF, 0);
    gate_init();

    /* 1. Ten hung clients and a healthy one on one server object, notified again and again. */
    first = create_server(HUNG + 1);
    for (i = 0; i < HUNG; i++) {
        sink_init(&hung_first[i], 1);
        advise(first, &hung_first[i]);
    }
    sink_init(&healthy, 0);
    advise(first, &healthy);
    /* Counted once COM is at work (Advise used the Global Interface Table): Wine starts threads of
       its own on first use. */
    base = process_threads();
    CHECK(base >= 1);
    printf("%d-bit; threads before notifying: %lu; the bound: %d\n", (int)(sizeof(void *) * 8), base,
           OPC_SHUTDOWN_MAX_NOTIFY_THREADS);
    for (i = 0; i < ROUNDS; i++) {
        HRESULT hr = notify(first, &n, &f, &t);
        CHECK_HR(hr, S_FALSE);
        /* The hung clients time out (the first time at the deadline, later without a call); the
           healthy one answers at once, but on a loaded machine may miss the deadline too. */
        CHECK(f == 0 && t >= HUNG && n + t == HUNG + 1);
        CHECK(count_read(&healthy.calls) == i + 1);
        now = process_threads();
        if (now > most) most = now;
    }
    total = 0;
    for (i = 0; i < HUNG; i++) total += count_read(&hung_first[i].calls);
    printf("after %d notifications: threads %lu (most %lu), calls to the hung clients %ld\n", ROUNDS, now, most, total);
    CHECK(total == HUNG); /* each hung client was called once */
    CHECK(most - base <= OPC_SHUTDOWN_MAX_NOTIFY_THREADS);

    /* 2. More hung clients, on another object, until they hold every notification thread there is. */
    rest = create_server(OPC_SHUTDOWN_MAX_NOTIFY_THREADS - HUNG);
    for (i = 0; i < OPC_SHUTDOWN_MAX_NOTIFY_THREADS - HUNG; i++) {
        sink_init(&hung_rest[i], 1);
        advise(rest, &hung_rest[i]);
    }
    CHECK_HR(notify(rest, &n, &f, &t), S_FALSE);
    CHECK(n == 0 && f == 0 && t == OPC_SHUTDOWN_MAX_NOTIFY_THREADS - HUNG);
    /* The healthy client is still notified every time: the notifying thread calls it itself. */
    for (i = 0; i < 5; i++) {
        healthy.last_thread = (thread_id)0;
        CHECK_HR(notify(first, &n, &f, &t), S_FALSE);
        CHECK(f == 0 && t >= HUNG && n + t == HUNG + 1);
        CHECK(count_read(&healthy.calls) == ROUNDS + i + 1);
        CHECK(same_thread(healthy.last_thread, this_thread()));
        CHECK_HR(notify(rest, &n, &f, &t), S_FALSE);
        CHECK(n == 0 && f == 0 && t == OPC_SHUTDOWN_MAX_NOTIFY_THREADS - HUNG);
        now = process_threads();
        if (now > most) most = now;
    }
    total = 0;
    for (i = 0; i < HUNG; i++) total += count_read(&hung_first[i].calls);
    for (i = 0; i < OPC_SHUTDOWN_MAX_NOTIFY_THREADS - HUNG; i++) total += count_read(&hung_rest[i].calls);
    printf("with every notification thread held: threads %lu (most %lu), calls to the hung clients %ld\n", now, most,
           total);
    CHECK(total == OPC_SHUTDOWN_MAX_NOTIFY_THREADS);
    CHECK(most - base <= OPC_SHUTDOWN_MAX_NOTIFY_THREADS);
    CHECK_HR(OpcDllCanUnloadNow(), S_FALSE);

    /* 3. The hung clients return: the threads end and let go of everything. */
    first->lpVtbl->Release(first);
    rest->lpVtbl->Release(rest);
    gate_open();
    for (waited = 0; waited < 3000 && OpcDllCanUnloadNow() != S_OK; waited++) pause_a_little();
    CHECK_HR(OpcDllCanUnloadNow(), S_OK);
    CHECK(OpcObjectCount() == objects);
    CHECK(healthy.refs == 1);
    for (i = 0; i < HUNG; i++) CHECK(hung_first[i].refs == 1);
    for (i = 0; i < OPC_SHUTDOWN_MAX_NOTIFY_THREADS - HUNG; i++) CHECK(hung_rest[i].refs == 1);
    /* The workers let go of the module before their threads have quite ended: the threads end too
       (here, not with the process: valgrind would count a thread still ending as memory possibly
       lost). Under Wine, COM starts threads of its own meanwhile: there the count is not asserted. */
    for (waited = 0; waited < 3000 && process_threads() > base; waited++) pause_a_little();
#ifndef _WIN32
    CHECK(process_threads() <= base);
#endif
#ifdef _WIN32
    CoUninitialize();
#endif
    return test_summary("test_shutdown_threads");
}
