/* Benchmark: round trips of the Data Access interfaces across processes through opccomn.dll's
 * proxy/stub against the widl-generated one (opc_classic_widl_ps.dll, the stand-in for the
 * Foundation's DA proxy/stub, made from the same IDL), in the same run, under the same COM runtime.
 *
 *   Read(100)            IOPCSyncIO::Read from the cache of 100 items (VT_I4 and VT_R8 alternating)
 *   Write(4)             IOPCSyncIO::Write of 4 items (VT_I4, VT_R8, VT_I4, VT_R8)
 *   AddItems+Remove(100) IOPCItemMgt::AddItems of 100 items, then RemoveItems of them
 *   OnDataChange(100)    IOPCAsyncIO2::Refresh2, and the server's IOPCDataCallback::OnDataChange of the
 *                        group's 100 items into this process's sink (from a thread the server starts
 *                        for it, as tests/oop/da_server.c delivers every callback), waited for
 *   Unadvise+Advise      IConnectionPoint::Unadvise and Advise of the sink: the server lets go of its
 *                        callback proxy and makes a new one
 *
 * Three DA test servers (tests/oop/da_server.c, each serving its own CLSID, "-set:N") run at once:
 * one with opccomn.dll's proxy/stub, two with the stand-in's ("-ps:widl"). The second stand-in is the
 * control: the same proxy/stub measured against itself shows how far this run's machine lets two equal
 * contenders differ. This client uses the same proxy/stub as the contender's server, on both sides of
 * every call and callback: before a contender's objects are made, and before each of its batches
 * (Advise makes new stubs), it registers that proxy/stub for the DA interfaces in this process
 * (CoRegisterPSClsid; both class objects are registered here, so that neither pays a registry lookup
 * the other does not). Each server's proxy/stub, and this process's proxies and the sink's stub of
 * each contender, are checked to be the ones they should be before anything is timed. The machine's
 * registration of the DA interfaces is not changed; what the benchmark registers is its three
 * servers' classes, removed at its end, after a failure and after a stall (and by `--unregister`).
 *
 * The contenders run in interleaved rounds (--rounds, 51 by default, the order rotating), a batch of
 * calls of each operation a round (60 Read, 60 Write, 30 AddItems+Remove, 30 OnDataChange and 12
 * Unadvise+Advise; --scale S makes them S/3 times as many, 3 the default). Measured per batch: the CPU
 * time of this process and the contender's server (under Wine Linux's CLOCK_PROCESS_CPUTIME_ID of each,
 * to the nanosecond: the other processes of a shared machine do not count against either side; the
 * server reads its own and answers it), the CPU time of the calling thread (the proxy's side of the
 * calls), and the wall clock. Printed per operation and measure: the median per call of each
 * contender, the median of the rounds' ratios opccomn/widl with their spread (lowest-highest), and the
 * control's ratio; then a GOAL line per operation (median ratio of the CPU time of both processes
 * <= 1.1x) with met or NOT MET, as the other benchmarks do, and a closing line
 * "da_bench: 5 goals, N met, ...".
 *
 * Bounded in time as cross_process_bench is: a watchdog thread ends the run (exit code 3, the figures
 * of the rounds complete so far marked partial) when a batch does not end within --stall-s seconds
 * (60 by default), or a server's start or end within twice that (120 s at least); rounds stop after
 * --budget-s seconds (600 by default: the test server ends itself 20 minutes after its start). At its
 * end the benchmark waits for its servers to exit and prints "servers ended: N of M" (M the servers started).
 *
 * Exit code: 0 when every goal is met, 1 when one is missed or a call failed (the failing call and its
 * HRESULT are printed), 3 after a stall, 2 for a usage error.
 *
 *   da_bench [--rounds R] [--scale S] [--budget-s S] [--stall-s S] [--sets F]
 *   da_bench [--sets F] --unregister   removes the classes a run killed from outside left
 *
 * --sets F gives the contenders the DA server's classes of sets F, F+1 and F+2 (da.h; default 1). */
#include "da.h"

#include <olectl.h>

#define OOP_BENCH_PROGRAM "da_bench"
#define OOP_BENCH_USER_TYPE L"opccomn DA benchmark server"
#include "oop_bench.h"

#define OPS 5
#define READ_ITEMS 100 /* Bench.0 to Bench.99: read, written (the first 4), refreshed */
#define WRITE_ITEMS 4
#define CHURN_ITEMS 100 /* Bench.100 to Bench.199: added and removed */
#define GROUP_HANDLE 42
static const char *const OPERATIONS[OPS] = {"Read(100)", "Write(4)", "AddItems+Remove(100)", "OnDataChange(100)",
                                            "Unadvise+Advise"};
static const int WEIGHTS[OPS] = {20, 20, 10, 10, 4}; /* calls a round at --scale 1 */

/* The sink of a contender: counts the OnDataChange calls of 100 good items. */
typedef struct Sink {
    IOPCDataCallback iface;
    LONG refs;
    HANDLE changed;         /* set by OnDataChange */
    volatile LONG good, bad; /* OnDataChange calls with the 100 items as served, and others */
} Sink;

typedef struct {
    const char *name;
    int widl;     /* the stand-in's proxy/stub on both sides (else opccomn.dll's) */
    unsigned set; /* the server's CLSID: da_server_class(set) */
    IOPCServer *server;
    IOPCItemMgt *items;
    IOPCSyncIO *sync;
    IOPCAsyncIO2 *async;
    IConnectionPoint *point;
    DWORD cookie;
    OPCHANDLE read_handles[READ_ITEMS];
    Sink sink;
    DWORD server_pid;
    double wall[OPS][MAX_ROUNDS]; /* per operation and round: wall-clock seconds per call */
    double cpu[OPS][MAX_ROUNDS];  /* per operation and round: CPU seconds of both processes per call */
    double thread[OPS][MAX_ROUNDS]; /* per operation and round: CPU seconds of the calling thread per call */
} Contender;

static Contender contenders[CONTENDERS] = {
    {.name = "opccomn", .widl = 0, .set = 1}, {.name = "widl", .widl = 1, .set = 2}, {.name = "widl (control)", .widl = 1, .set = 3}};

/* The run's settings (command line), beside rounds and stall_s (oop_bench.h). */
static int scale = 3;
static double budget_s = 600;
static OPCITEMDEF read_defs[READ_ITEMS], churn_defs[CHURN_ITEMS];
static WCHAR item_ids[READ_ITEMS + CHURN_ITEMS][16];

/* ---- The sink ---- */

static HRESULT STDMETHODCALLTYPE sink_qi(IOPCDataCallback *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCDataCallback)) {
        *ppv = This;
        This->lpVtbl->AddRef(This);
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE sink_add_ref(IOPCDataCallback *This) { return (ULONG)InterlockedIncrement(&((Sink *)This)->refs); }
static ULONG STDMETHODCALLTYPE sink_release(IOPCDataCallback *This) {
    return (ULONG)InterlockedDecrement(&((Sink *)This)->refs); /* static: nothing to free */
}
static HRESULT STDMETHODCALLTYPE sink_data_change(IOPCDataCallback *This, DWORD transaction, OPCHANDLE group,
                                                  HRESULT quality, HRESULT error, DWORD count, OPCHANDLE *handles,
                                                  VARIANT *values, WORD *qualities, FILETIME *times, HRESULT *errors) {
    Sink *s = (Sink *)This;
    int good = group == GROUP_HANDLE && quality == S_OK && error == S_OK && count == READ_ITEMS && handles &&
               values && qualities && times && errors;
    DWORD k;
    (void)transaction;
    for (k = 0; good && k < count; k++)
        good = handles[k] == (OPCHANDLE)k && errors[k] == S_OK &&
               (k % 2 ? V_VT(&values[k]) == VT_R8 : V_VT(&values[k]) == VT_I4);
    InterlockedIncrement(good ? &s->good : &s->bad);
    SetEvent(s->changed);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE sink_read_complete(IOPCDataCallback *This, DWORD transaction, OPCHANDLE group,
                                                    HRESULT quality, HRESULT error, DWORD count, OPCHANDLE *handles,
                                                    VARIANT *values, WORD *qualities, FILETIME *times, HRESULT *errors) {
    (void)This, (void)transaction, (void)group, (void)quality, (void)error, (void)count, (void)handles;
    (void)values, (void)qualities, (void)times, (void)errors;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE sink_write_complete(IOPCDataCallback *This, DWORD transaction, OPCHANDLE group,
                                                     HRESULT error, DWORD count, OPCHANDLE *handles, HRESULT *errors) {
    (void)This, (void)transaction, (void)group, (void)error, (void)count, (void)handles, (void)errors;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE sink_cancel_complete(IOPCDataCallback *This, DWORD transaction, OPCHANDLE group) {
    (void)This, (void)transaction, (void)group;
    return S_OK;
}
static IOPCDataCallbackVtbl sink_vtbl = {sink_qi,            sink_add_ref,        sink_release,        sink_data_change,
                                         sink_read_complete, sink_write_complete, sink_cancel_complete};

/* The factory references of opc_classic_widl_ps.dll (each live proxy and stub holds one). */
static LONG classic_refs(void) {
    HMODULE dll = GetModuleHandleW(L"opc_classic_widl_ps.dll");
    LONG(WINAPI * refs)(void);
    if (!dll) return -1;
    refs = (LONG(WINAPI *)(void))(void (*)(void))GetProcAddress(dll, "ClassicProxyStubRefs");
    return refs ? refs() : -1;
}

/* Makes the contender's proxy/stub the one this process uses for the DA interfaces. */
static HRESULT select_proxy_stub(const Contender *k) {
    HRESULT hr = S_OK;
    size_t i;
    for (i = 0; SUCCEEDED(hr) && i < DA_IID_COUNT; i++)
        hr = CoRegisterPSClsid(DA_IIDS[i], k->widl ? &CLSID_ClassicWidlProxyStub : &CLSID_OpcComnProxyStub);
    return hr;
}

static void prog_id(const Contender *k, WCHAR *out) { swprintf(out, 40, L"Oop.DaBench%u.1", k->set); }

/* The contender's class, whose server's command line names its proxy/stub and its CLSID. */
static HRESULT register_contender(const Contender *k) {
    WCHAR arguments[40], name[40];
    CLSID clsid = da_server_class(k->set);
    prog_id(k, name);
    swprintf(arguments, 40, L"%ls -set:%u", k->widl ? L" -ps:widl" : L"", k->set);
    return register_class(&clsid, name, arguments);
}

static void unregister_all(void) {
    WCHAR name[40];
    int i;
    for (i = 0; i < CONTENDERS; i++) {
        CLSID clsid = da_server_class(contenders[i].set);
        prog_id(&contenders[i], name);
        unregister_class(&clsid, name);
    }
}

static DWORD server_pid(int i) { return contenders[i].server_pid; }
static unsigned *contender_set(int i) { return &contenders[i].set; }

/* The server's answer to a vendor code, as text (0 when it gave none). */
static int ask_server(Contender *k, HRESULT code, char *out, size_t size) {
    LPWSTR text = NULL;
    HRESULT hr = k->server->lpVtbl->GetErrorString(k->server, code, 0x0409, &text);
    return server_answer(k->name, hr, text, out, size);
}

static HRESULT read_items(Contender *k) {
    OPCITEMSTATE *states = NULL;
    HRESULT *errors = NULL;
    HRESULT hr = k->sync->lpVtbl->Read(k->sync, OPC_DS_CACHE, READ_ITEMS, k->read_handles, &states, &errors);
    if (hr == S_OK && (!states || !errors || V_VT(&states[READ_ITEMS - 1].vDataValue) != VT_R8)) hr = E_FAIL;
    CoTaskMemFree(states); /* VT_I4 and VT_R8: nothing else to free */
    CoTaskMemFree(errors);
    return hr;
}

static HRESULT write_items(Contender *k) {
    VARIANT values[WRITE_ITEMS];
    HRESULT *errors = NULL, hr;
    int i;
    for (i = 0; i < WRITE_ITEMS; i++) {
        VariantInit(&values[i]);
        V_VT(&values[i]) = i % 2 ? VT_R8 : VT_I4;
        if (i % 2) V_R8(&values[i]) = i + 0.5;
        else V_I4(&values[i]) = i;
    }
    hr = k->sync->lpVtbl->Write(k->sync, WRITE_ITEMS, k->read_handles, values, &errors);
    if (hr == S_OK && !errors) hr = E_FAIL;
    CoTaskMemFree(errors);
    return hr;
}

/* AddItems of `count` definitions; their server handles into `handles` (when given). */
static HRESULT add_items(Contender *k, OPCITEMDEF *defs, DWORD count, OPCHANDLE *handles) {
    OPCITEMRESULT *results = NULL;
    HRESULT *errors = NULL;
    HRESULT hr = k->items->lpVtbl->AddItems(k->items, count, defs, &results, &errors);
    DWORD i;
    if (hr == S_OK && (!results || !errors)) hr = E_FAIL;
    for (i = 0; hr == S_OK && i < count; i++) {
        if (handles) handles[i] = results[i].hServer;
        CoTaskMemFree(results[i].pBlob);
    }
    CoTaskMemFree(results);
    CoTaskMemFree(errors);
    return hr;
}

static HRESULT churn_items(Contender *k) {
    OPCHANDLE handles[CHURN_ITEMS];
    HRESULT *errors = NULL;
    HRESULT hr = add_items(k, churn_defs, CHURN_ITEMS, handles);
    if (FAILED(hr)) return hr;
    hr = k->items->lpVtbl->RemoveItems(k->items, CHURN_ITEMS, handles, &errors);
    if (hr == S_OK && !errors) hr = E_FAIL;
    CoTaskMemFree(errors);
    return hr;
}

/* Refresh2 and its OnDataChange, waited for (a lost one ends the run as a stall). */
static HRESULT data_change(Contender *k) {
    DWORD cancel = 0;
    LONG good = k->sink.good;
    HRESULT hr = k->async->lpVtbl->Refresh2(k->async, OPC_DS_CACHE, 1, &cancel);
    if (FAILED(hr)) return hr;
    WaitForSingleObject(k->sink.changed, INFINITE);
    return k->sink.good == good + 1 && k->sink.bad == 0 ? S_OK : E_FAIL;
}

static HRESULT readvise(Contender *k) {
    HRESULT hr = k->point->lpVtbl->Unadvise(k->point, k->cookie);
    if (FAILED(hr)) return hr;
    k->cookie = 0;
    return k->point->lpVtbl->Advise(k->point, (IUnknown *)&k->sink.iface, &k->cookie);
}

static HRESULT operation(Contender *k, int op) {
    switch (op) {
    case 0: return read_items(k);
    case 1: return write_items(k);
    case 2: return churn_items(k);
    case 3: return data_change(k);
    default: return readvise(k);
    }
}

/* The contender's server, group and sink, made with its proxy/stub and checked to be what they should
 * be. */
static int connect_contender(Contender *k) {
    CLSID clsid = da_server_class(k->set);
    IConnectionPointContainer *container = NULL;
    LONG before = classic_refs(), after_proxies, after_advise;
    OPCHANDLE server_group = 0;
    DWORD revised = 0;
    IUnknown *group = NULL;
    char text[32];
    HRESULT hr = select_proxy_stub(k);
    if (FAILED(hr)) return failed(k->name, "CoRegisterPSClsid", hr);
    step(setup_limit_s(), "starting the %s server (CoCreateInstance)", k->name);
    hr = CoCreateInstance(&clsid, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServer, (void **)&k->server);
    if (FAILED(hr)) return failed(k->name, "creating the server", hr);
    step(setup_limit_s(), "checking the %s server", k->name);
    if (!ask_server(k, DA_CODE_PROCESS_ID, text, sizeof text)) return 1;
    k->server_pid = (DWORD)strtoul(text, NULL, 10);
    if (!ask_server(k, DA_CODE_PROXY_STUB, text, sizeof text)) return 1;
    if (strcmp(text, k->widl ? "widl" : "opccomn") != 0) {
        fprintf(stderr, "da_bench: the %s server's stubs come from %s\n", k->name, text);
        return 1;
    }
    hr = k->server->lpVtbl->AddGroup(k->server, L"bench", TRUE, 1000, GROUP_HANDLE, NULL, NULL, 0x0409, &server_group,
                                     &revised, &IID_IOPCItemMgt, &group);
    if (FAILED(hr)) return failed(k->name, "AddGroup", hr);
    k->items = (IOPCItemMgt *)group;
    if (FAILED(hr = group->lpVtbl->QueryInterface(group, &IID_IOPCSyncIO, (void **)&k->sync)) ||
        FAILED(hr = group->lpVtbl->QueryInterface(group, &IID_IOPCAsyncIO2, (void **)&k->async)) ||
        FAILED(hr = group->lpVtbl->QueryInterface(group, &IID_IConnectionPointContainer, (void **)&container)))
        return failed(k->name, "QueryInterface of the group", hr);
    after_proxies = classic_refs();
    if ((after_proxies > before) != k->widl) {
        fprintf(stderr, "da_bench: the %s proxies came from the other proxy/stub\n", k->name);
        container->lpVtbl->Release(container);
        return 1;
    }
    hr = add_items(k, read_defs, READ_ITEMS, k->read_handles);
    if (FAILED(hr) || hr != S_OK) return failed(k->name, "AddItems", hr == S_OK ? E_FAIL : hr);
    k->sink.iface.lpVtbl = &sink_vtbl;
    k->sink.refs = 1;
    k->sink.changed = CreateEventW(NULL, FALSE, FALSE, NULL);
    hr = container->lpVtbl->FindConnectionPoint(container, &IID_IOPCDataCallback, &k->point);
    container->lpVtbl->Release(container);
    if (FAILED(hr)) return failed(k->name, "FindConnectionPoint", hr);
    hr = k->point->lpVtbl->Advise(k->point, (IUnknown *)&k->sink.iface, &k->cookie);
    if (FAILED(hr)) return failed(k->name, "Advise", hr);
    after_advise = classic_refs(); /* the sink's stub */
    if ((after_advise > after_proxies) != k->widl) {
        fprintf(stderr, "da_bench: the %s sink's stub came from the other proxy/stub\n", k->name);
        return 1;
    }
    return 0;
}

/* The CPU time (ns) this process and the contender's server have used so far. */
static HRESULT cpu_time(Contender *k, unsigned long long *total) {
    char text[32];
    if (!ask_server(k, DA_CODE_CPU_TIME, text, sizeof text)) return E_FAIL;
    *total = (unsigned long long)_strtoui64(text, NULL, 10) + da_process_cpu_ns();
    return S_OK;
}

/* The CPU time (ns) of the calling thread: under Wine Linux's CLOCK_THREAD_CPUTIME_ID (Wine's
 * GetThreadTimes has a 10 ms resolution), elsewhere GetThreadTimes. */
static unsigned long long thread_cpu_ns(void) {
    FILETIME created, exited, kernel, user;
    HMODULE ntdll = GetModuleHandleA("ntdll.dll");
    if (ntdll && GetProcAddress(ntdll, "wine_get_version")) {
        long ret;
#if defined(__x86_64__)
        struct {
            long long sec, nsec;
        } t;
        /* clock_gettime(CLOCK_THREAD_CPUTIME_ID = 3, &t): x86_64 system call 228 */
        __asm__ volatile("syscall" : "=a"(ret) : "a"(228L), "D"(3L), "S"(&t) : "rcx", "r11", "memory");
#elif defined(__i386__)
        struct {
            long sec, nsec;
        } t;
        /* clock_gettime(CLOCK_THREAD_CPUTIME_ID = 3, &t): i386 system call 265 */
        __asm__ volatile("int $0x80" : "=a"(ret) : "a"(265L), "b"(3L), "c"(&t) : "memory");
#else
        struct {
            long sec, nsec;
        } t = {0, 0};
        ret = -1;
#endif
        if (ret == 0) return (unsigned long long)t.sec * 1000000000ULL + (unsigned long long)t.nsec;
    }
    if (!GetThreadTimes(GetCurrentThread(), &created, &exited, &kernel, &user)) return 0;
    return ((((unsigned long long)kernel.dwHighDateTime << 32) | kernel.dwLowDateTime) +
            (((unsigned long long)user.dwHighDateTime << 32) | user.dwLowDateTime)) * 100ULL;
}

static int contender_batch(int which, int op, int round) {
    Contender *k = &contenders[which];
    unsigned long long cpu_before = 0, cpu_after = 0;
    int calls = WEIGHTS[op] * scale, i;
    double t0, t1;
    unsigned long long thread0, thread1;
    HRESULT hr;
    if (round < 0) step(stall_s, "the warm-up's %s batch of the %s contender", OPERATIONS[op], k->name);
    else step(stall_s, "round %d: the %s batch of the %s contender", round + 1, OPERATIONS[op], k->name);
    if (FAILED(hr = select_proxy_stub(k))) return failed(k->name, "CoRegisterPSClsid", hr);
    if (FAILED(hr = cpu_time(k, &cpu_before))) return failed(k->name, "reading CPU times", hr);
    thread0 = thread_cpu_ns();
    t0 = now();
    for (i = 0; i < calls; i++)
        if ((hr = operation(k, op)) != S_OK) return failed(k->name, OPERATIONS[op], hr == S_OK ? E_FAIL : hr);
    t1 = now();
    thread1 = thread_cpu_ns();
    if (FAILED(hr = cpu_time(k, &cpu_after))) return failed(k->name, "reading CPU times", hr);
    if (round >= 0) {
        k->wall[op][round] = (t1 - t0) / calls;
        k->cpu[op][round] = (double)(cpu_after - cpu_before) * 1e-9 / calls;
        k->thread[op][round] = (double)(thread1 - thread0) * 1e-9 / calls;
    }
    return 0;
}

static int goals_met = -1; /* of OPS, once the figures are printed */

static int print_table(int n) {
    int op, missed = 0, met_count;
    printf("%-20s | %-45s | %-45s\n", "", "CPU time of both processes: us per call, ratio",
           "wall clock: us per call, ratio");
    printf("%-20s | %7s %7s %6s %11s %7s | %7s %7s %6s %11s %7s\n", "call", "opccomn", "widl", "ratio", "spread",
           "control", "opccomn", "widl", "ratio", "spread", "control");
    for (op = 0; op < OPS; op++) {
        double lo, hi, clo, chi, ratio, control, wlo, whi, wall, wall_control;
        ratio = paired_ratio(contenders[0].cpu[op], contenders[1].cpu[op], n, &lo, &hi);
        control = paired_ratio(contenders[2].cpu[op], contenders[1].cpu[op], n, &clo, &chi);
        wall = paired_ratio(contenders[0].wall[op], contenders[1].wall[op], n, &wlo, &whi);
        wall_control = paired_ratio(contenders[2].wall[op], contenders[1].wall[op], n, &clo, &chi);
        printf("%-20s | %7.1f %7.1f %5.2fx %4.2f-%4.2fx %6.2fx | %7.1f %7.1f %5.2fx %4.2f-%4.2fx %6.2fx\n",
               OPERATIONS[op], median(contenders[0].cpu[op], n) * 1e6, median(contenders[1].cpu[op], n) * 1e6, ratio,
               lo, hi, control, median(contenders[0].wall[op], n) * 1e6, median(contenders[1].wall[op], n) * 1e6, wall,
               wlo, whi, wall_control);
    }
    printf("%-20s | %-45s\n", "", "CPU time of the calling thread (the proxy's side)");
    for (op = 0; op < OPS; op++) {
        double lo, hi, clo, chi, ratio, control;
        ratio = paired_ratio(contenders[0].thread[op], contenders[1].thread[op], n, &lo, &hi);
        control = paired_ratio(contenders[2].thread[op], contenders[1].thread[op], n, &clo, &chi);
        printf("%-20s | %7.1f %7.1f %5.2fx %4.2f-%4.2fx %6.2fx\n", OPERATIONS[op],
               median(contenders[0].thread[op], n) * 1e6, median(contenders[1].thread[op], n) * 1e6, ratio, lo, hi,
               control);
    }
    printf("(medians over the rounds; ratio: the median of the rounds' ratios opccomn/widl, spread their lowest and\n"
           " highest; control: the stand-in against itself, what this run's machine makes of equal contenders)\n");
    met_count = 0;
    for (op = 0; op < OPS; op++) {
        double lo, hi;
        char label[48];
        int met;
        snprintf(label, sizeof label, "DA %s", OPERATIONS[op]);
        met = goal_met(label, paired_ratio(contenders[0].cpu[op], contenders[1].cpu[op], n, &lo, &hi), n);
        missed |= !met;
        met_count += met;
    }
    goals_met = met_count;
    return missed;
}

/* Lets go of the contender's objects; its server then exits. */
static void disconnect(Contender *k) {
    step(setup_limit_s(), "releasing the %s server's objects", k->name);
    if (k->point && k->cookie) k->point->lpVtbl->Unadvise(k->point, k->cookie);
    if (k->point) k->point->lpVtbl->Release(k->point);
    if (k->async) k->async->lpVtbl->Release(k->async);
    if (k->sync) k->sync->lpVtbl->Release(k->sync);
    if (k->items) k->items->lpVtbl->Release(k->items);
    if (k->server) {
        k->server->lpVtbl->RemoveGroup(k->server, 7, FALSE);
        k->server->lpVtbl->Release(k->server);
    }
}

/* How many of the servers started have exited (each waited for up to 30 s); *started: how many were. */
static int servers_ended(int *started) {
    int i, ended = 0;
    *started = 0;
    step(setup_limit_s(), "waiting for the servers to exit");
    for (i = 0; i < CONTENDERS; i++) {
        HANDLE process;
        if (!contenders[i].server_pid) continue;
        ++*started;
        process = OpenProcess(SYNCHRONIZE, FALSE, contenders[i].server_pid);
        if (!process) { /* gone already */
            ended++;
            continue;
        }
        ended += WaitForSingleObject(process, 30000) == WAIT_OBJECT_0;
        CloseHandle(process);
    }
    return ended;
}

static int usage(void) {
    fprintf(stderr, "usage: da_bench [--rounds R] [--scale S] [--budget-s S] [--stall-s S] [--sets F]\n"
                    "       da_bench [--sets F] --unregister\n");
    return 2;
}

int main(int argc, char **argv) {
    int i, a, failure = 0, missed = 0, ended, started_servers;
    HANDLE thread;
    begin(L"opc_da_test_server.exe");
    for (a = 1; a < argc; a++) {
        if (common_option(argc, argv, &a, &budget_s)) continue;
        if (!strcmp(argv[a], "--scale") && a + 1 < argc) scale = atoi(argv[++a]);
        else return usage();
    }
    if (rounds < 1 || rounds > MAX_ROUNDS || scale < 1 || scale > 1000 || budget_s <= 0 || stall_s <= 0) return usage();
    for (i = 0; i < READ_ITEMS + CHURN_ITEMS; i++) {
        OPCITEMDEF *d = i < READ_ITEMS ? &read_defs[i] : &churn_defs[i - READ_ITEMS];
        swprintf(item_ids[i], 16, L"Bench.%d", i);
        memset(d, 0, sizeof *d);
        d->szAccessPath = (LPWSTR)L"";
        d->szItemID = item_ids[i];
        d->bActive = TRUE;
        d->hClient = (OPCHANDLE)i;
        d->vtRequestedDataType = VT_EMPTY;
    }
    printf("%d rounds of each contender, interleaved; a round: %d Read(100), %d Write(4), %d AddItems+Remove(100), "
           "%d OnDataChange(100), %d Unadvise+Advise (limits: %.0f s for the rounds, %.0f s for a batch)\n",
           rounds, WEIGHTS[0] * scale, WEIGHTS[1] * scale, WEIGHTS[2] * scale, WEIGHTS[3] * scale,
           WEIGHTS[4] * scale, budget_s, stall_s);
    thread = start_watchdog();
    if (!thread) return failed(contenders[0].name, "starting the watchdog", HRESULT_FROM_WIN32(GetLastError()));
    /* Both class objects registered here (the last one's IIDs are overridden per batch). */
    if (FAILED(CoInitializeEx(NULL, COINIT_MULTITHREADED)) || FAILED(use_classic_proxy_stub()) ||
        FAILED(use_opccomn_proxy_stub()))
        return 1;
    for (i = 0; i < CONTENDERS && !failure; i++) {
        HRESULT hr = register_contender(&contenders[i]);
        if (FAILED(hr)) failure = failed(contenders[i].name, "registering the DA test server", hr);
    }
    for (i = 0; i < CONTENDERS && !failure; i++) failure = connect_contender(&contenders[i]);
    if (!failure) failure = run_rounds(OPS, budget_s, &missed);
    for (i = 0; i < CONTENDERS; i++) disconnect(&contenders[i]);
    unregister_all();
    ended = servers_ended(&started_servers);
    printf("servers ended: %d of %d; classes removed\n", ended, started_servers);
    if (goals_met >= 0)
        printf("\nda_bench: %d goals, %d met, %d NOT MET (%d interleaved rounds; CPU time of client and server, Linux's "
               "CLOCK_PROCESS_CPUTIME_ID under Wine; the wall clock for information)\n",
               OPS, goals_met, OPS - goals_met, (int)rounds_done);
    end_run(thread);
    if (failure) {
        fprintf(stderr, "da_bench: stopped, no figures\n");
        return 1;
    }
    return ended == started_servers ? missed : 1;
}
