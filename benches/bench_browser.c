/* Benchmark (not a test) of the server browser under load: 600 Data Access 2.0 servers registered in
   HKEY_CLASSES_ROOT (class key, ProgID, implemented category), browsed with
   IOPCServerList2::EnumClassesOfCategories(CATID_OPCDAServer20) and the enumerator drained.

   1. One enumeration, in this process, by a server list that answers from its last scan of the
      registry (the library's default) against one that scans the registry on every call (created
      while the environment has OPCCOMN_SERVER_LIST_CACHE=0), in interleaved rounds, wall clock (the
      registry lives in wineserver). Goal: cached at most 0.2x the scan.
   2. The browser service (opccomn_browser.exe, started by COM for CLSCTX_LOCAL_SERVER) with client
      processes of this program: in each round one client alone makes 100 enumerations, then 8 clients
      at once make 100 each; each client's figure is the median of its calls' wall times. Goal: the
      slowest of the 8 clients at most 3x the single client (median over the rounds). Before it, for
      information, the same with a browser that scans the registry on every call (3 rounds of 10).
      Printed with it, for information: how many of the machine's processors were busy (anything on
      the machine: the clients, the browser, wineserver, other programs) with one client alone and with
      8, and the ratio the processors alone would give if an enumeration cost the same processor time
      with 8 clients as with one: 8 x (processors busy alone) / P on P processors. On 2 processors, with
      one client keeping 0.7-0.8 of them busy (the client, the browser and wineserver taking turns),
      that is 2.8-3.2x: the goal is at what this machine allows, and met on it only when quiet.
   3. The browser's memory (working set and committed memory, as GetProcessMemoryInfo reports them)
      while 8 clients make 1,000 enumerations each, in 4 batches of 250, after a warm-up of 8 x 100.
      Goal: flat, the memory after the last batch at most 1.05x that after the first.

   What it registers (the 600 servers; the browser and the proxy/stub unless they were registered
   before) is removed at the end. Windows only (run: scripts/bench.sh --wine browser).

   `--quick` (the test bench.browser_figures, in CI): the same cases and goals in fewer rounds (5 in
   process within 30 s, 3 of 30 enumerations per client, 1 of 5 for the scanning browser); the memory
   case unchanged (its goal is stated for 8 x 1,000). */
#define BENCH_WALL_CLOCK /* the registry lives in wineserver, another process: its time counts */
#include "bench.h"

#include <opccomn/opccomn.h>

#if !defined(_WIN32)
int main(void)
{
    printf("bench_browser browses the Windows registry: run it with scripts/bench.sh --wine browser\n");
    return 0;
}
#else

#include <psapi.h>
#include <tlhelp32.h>

#define SERVERS 600
#define CLIENTS 8
#define CALLS_PER_ROUND 100
#define MEMORY_CALLS 1000
#define MEMORY_BATCHES 4
#define CLIENT_ROUNDS 5
/* A run of clients that does not end within this long has stalled (under Wine 8 a stub's teardown can
   wait for ever in RpcServerUnregisterIf, and its client in IUnknown_Release_Proxy: each enumeration
   hands out an enumerator object, whose stub goes with its release). */
#define CLIENT_TIMEOUT_MS 180000
#define GO_EVENT L"Local\\OpcComnBenchBrowserGo"
#define READY_SEMAPHORE L"Local\\OpcComnBenchBrowserReady"

static WCHAR dir[MAX_PATH], self[MAX_PATH];
/* The client cases' rounds and enumerations per client and round (--quick makes them fewer). */
static int client_rounds = CLIENT_ROUNDS, client_calls = CALLS_PER_ROUND, scanning_rounds = 3, scanning_calls = 10;
/* What the browser cases registered, to remove at the end (also after a stall). */
static int own_browser, own_proxy_stub;

static GUID bench_clsid(unsigned i)
{
    GUID g = {0xBE0C0020u, 0x0000, 0x4000, {0x80, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}};
    g.Data4[6] = (BYTE)(i >> 8);
    g.Data4[7] = (BYTE)i;
    return g;
}

static void guid_text(const GUID *g, WCHAR *out)
{
    swprintf(out, 40, L"{%08lX-%04X-%04X-%02X%02X-%02X%02X%02X%02X%02X%02X}", (unsigned long)g->Data1, g->Data2,
             g->Data3, g->Data4[0], g->Data4[1], g->Data4[2], g->Data4[3], g->Data4[4], g->Data4[5], g->Data4[6],
             g->Data4[7]);
}

static void set_default(const WCHAR *path, const WCHAR *text)
{
    HKEY k;
    if (RegCreateKeyExW(HKEY_CLASSES_ROOT, path, 0, NULL, 0, KEY_WRITE, NULL, &k, NULL) != ERROR_SUCCESS) {
        fwprintf(stderr, L"cannot create %ls\n", path);
        exit(2);
    }
    if (text)
        RegSetValueExW(k, L"", 0, REG_SZ, (const BYTE *)text, (DWORD)((wcslen(text) + 1) * sizeof(WCHAR)));
    RegCloseKey(k);
}

static void registration(int add)
{
    WCHAR key[128], sub[220], clsid[40], catid[40], text[64];
    guid_text(&CATID_OPCDAServer20, catid);
    for (unsigned i = 0; i < SERVERS; i++) {
        GUID g = bench_clsid(i);
        guid_text(&g, clsid);
        swprintf(key, 128, L"CLSID\\%ls", clsid);
        swprintf(text, 64, L"OpcBench.Browse%u.1", i);
        if (!add) {
            RegDeleteTreeW(HKEY_CLASSES_ROOT, key);
            RegDeleteTreeW(HKEY_CLASSES_ROOT, text);
            continue;
        }
        swprintf(sub, 220, L"%ls\\ProgID", key);
        set_default(sub, text);
        swprintf(sub, 220, L"%ls\\CLSID", text);
        set_default(sub, clsid);
        swprintf(sub, 220, L"%ls\\Implemented Categories\\%ls", key, catid);
        set_default(sub, NULL);
        swprintf(text, 64, L"Benchmark DA server %u", i);
        set_default(key, text);
    }
}

/* One enumeration of the DA 2.0 servers, drained; how many classes it gave. */
static ULONG enumerate(IOPCServerList2 *list)
{
    CATID cat = CATID_OPCDAServer20;
    IOPCEnumGUID *e = NULL;
    ULONG total = 0;
    if (list->lpVtbl->EnumClassesOfCategories(list, 1, &cat, 0, NULL, &e) != S_OK || !e) {
        fprintf(stderr, "EnumClassesOfCategories failed\n");
        exit(2);
    }
    for (;;) {
        GUID buf[256];
        ULONG n = 0;
        HRESULT hr = e->lpVtbl->Next(e, 256, buf, &n);
        total += n;
        if (hr != S_OK)
            break;
    }
    e->lpVtbl->Release(e);
    return total;
}

/* ---- 1. One enumeration, cached and scanning, in this process ---- */

static void run_enumerations(void *context, long reps)
{
    for (long r = 0; r < reps; r++)
        if (enumerate(context) < SERVERS)
            exit(2);
}

static IOPCServerList2 *create_list(int cached)
{
    void *p = NULL;
    SetEnvironmentVariableW(L"OPCCOMN_SERVER_LIST_CACHE", cached ? NULL : L"0");
    HRESULT hr = OpcServerListCreate(NULL, &IID_IOPCServerList2, &p);
    SetEnvironmentVariableW(L"OPCCOMN_SERVER_LIST_CACHE", NULL);
    if (hr != S_OK) {
        fprintf(stderr, "OpcServerListCreate failed: 0x%08lX\n", (unsigned long)hr);
        exit(2);
    }
    return p;
}

static void one_enumeration_case(void)
{
    IOPCServerList2 *scanning = create_list(0), *cached = create_list(1);
    ULONG classes = enumerate(scanning);
    if (enumerate(cached) != classes) {
        fprintf(stderr, "the cached and the scanning server list disagree\n");
        exit(2);
    }
    printf("One enumeration of %d DA 2.0 servers (%lu classes found), in this process\n", SERVERS,
           (unsigned long)classes);
    BenchContender c[2] = {
        {"scanning the registry on every call (OPCCOMN_SERVER_LIST_CACHE=0)", run_enumerations, scanning, 1},
        {"from the last scan (default)", run_enumerations, cached, 1},
    };
    BenchResult r = bench_case(c, 2);
    char a[96], b[96];
    bench_format_time(a, sizeof a, &r, 0);
    bench_format_time(b, sizeof b, &r, 1);
    printf("time per enumeration, median of %d rounds (lowest-highest round): scanning %s, cached %s\n", r.rounds, a,
           b);
    double lo, hi, ratio = bench_ratio(&r, 1, 0, &lo, &hi);
    printf("cached / scanning: %.5fx (rounds %.5f-%.5f)\n", ratio, lo, hi);
    bench_goal("one enumeration, cached / scanning the registry", ratio, lo, hi, 0, 0.2, "x");
    scanning->lpVtbl->Release(scanning);
    cached->lpVtbl->Release(cached);
}

/* ---- 2 and 3. Client processes and the browser service ---- */

static int double_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* `bench_browser client CALLS OUTFILE`: connects to the browser, says it is ready, waits for the go,
   makes CALLS enumerations and writes the median and the highest wall time of one (ns) to OUTFILE. */
static int client_main(int calls, const char *outfile)
{
    IOPCServerList2 *list = NULL;
    HANDLE go = OpenEventW(SYNCHRONIZE, FALSE, GO_EVENT), ready = OpenSemaphoreW(SEMAPHORE_MODIFY_STATE, FALSE, READY_SEMAPHORE);
    double *ns = calloc((size_t)calls, sizeof *ns);
    if (!go || !ready || !ns || calls < 1)
        return 3;
    CoInitializeEx(NULL, COINIT_MULTITHREADED);
    if (CoCreateInstance(&CLSID_OPCServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&list) != S_OK)
        return 4;
    if (enumerate(list) < SERVERS)
        return 5;
    ReleaseSemaphore(ready, 1, NULL);
    if (WaitForSingleObject(go, CLIENT_TIMEOUT_MS) != WAIT_OBJECT_0)
        return 6;
    for (int i = 0; i < calls; i++) {
        double start = bench_now_ns();
        if (enumerate(list) < SERVERS)
            return 5;
        ns[i] = bench_now_ns() - start;
    }
    list->lpVtbl->Release(list);
    CoUninitialize();
    qsort(ns, (size_t)calls, sizeof *ns, double_cmp);
    FILE *f = fopen(outfile, "w");
    if (!f)
        return 7;
    fprintf(f, "%.0f %.0f\n", ns[calls / 2], ns[calls - 1]);
    fclose(f);
    return 0;
}

static DWORD browser_pid(void)
{
    PROCESSENTRY32W e;
    DWORD pid = 0;
    HANDLE snap = CreateToolhelp32Snapshot(TH32CS_SNAPPROCESS, 0);
    if (snap == INVALID_HANDLE_VALUE)
        return 0;
    e.dwSize = sizeof e;
    if (Process32FirstW(snap, &e)) {
        do
            if (_wcsicmp(e.szExeFile, L"opccomn_browser.exe") == 0)
                pid = e.th32ProcessID;
        while (Process32NextW(snap, &e));
    }
    CloseHandle(snap);
    return pid;
}

typedef struct {
    double working_set_mb, pagefile_mb;
} Memory;

/* The browser's working set and committed memory (PagefileUsage; under Wine its virtual size less
   what is shared, as Wine reads it from the Linux process). */
static Memory browser_memory(HANDLE browser)
{
    PROCESS_MEMORY_COUNTERS m;
    Memory out = {0, 0};
    memset(&m, 0, sizeof m);
    m.cb = sizeof m;
    if (browser && GetProcessMemoryInfo(browser, &m, sizeof m)) {
        out.working_set_mb = (double)m.WorkingSetSize / (1024.0 * 1024.0);
        out.pagefile_mb = (double)m.PagefileUsage / (1024.0 * 1024.0);
    }
    return out;
}

static void cleanup(void);
static DWORD run_browser(const WCHAR *args);

/* Removes the browser's and the proxy/stub's registration when a case made them. */
static void unregister_browser(void)
{
    if (own_browser)
        run_browser(L"/UnregServer");
    if (own_proxy_stub)
        OpcUnregisterProxyStub(NULL);
    own_browser = own_proxy_stub = 0;
}

/* After a stall: ends the browser, removes what the benchmark registered, prints the closing line
   and exits with 3. */
static void stalled(HANDLE browser)
{
    if (browser)
        TerminateProcess(browser, 9);
    cleanup();
    bench_goals++;
    bench_failures++;
    bench_finish("bench_browser");
    exit(3);
}

/* The machine's processor time so far, busy and idle, summed over its processors (100 ns units). */
typedef struct {
    ULONGLONG busy, idle;
} CpuTimes;

static CpuTimes cpu_times(void)
{
    FILETIME idle, kernel, user;
    CpuTimes t = {0, 0};
    if (GetSystemTimes(&idle, &kernel, &user)) {
        ULONGLONG i = ((ULONGLONG)idle.dwHighDateTime << 32) | idle.dwLowDateTime;
        ULONGLONG k = ((ULONGLONG)kernel.dwHighDateTime << 32) | kernel.dwLowDateTime;
        ULONGLONG u = ((ULONGLONG)user.dwHighDateTime << 32) | user.dwLowDateTime;
        t.idle = i;
        t.busy = k + u > i ? k + u - i : 0; /* kernel time includes the idle time */
    }
    return t;
}

static int processors(void)
{
    SYSTEM_INFO si;
    GetSystemInfo(&si);
    return si.dwNumberOfProcessors ? (int)si.dwNumberOfProcessors : 1;
}

/* How many of the machine's processors were busy on average between two readings (whatever kept
   them busy: these processes, wineserver, other programs). */
static double busy_processors(CpuTimes before, CpuTimes after)
{
    double busy = (double)(after.busy - before.busy), idle = (double)(after.idle - before.idle);
    return busy + idle > 0 ? processors() * busy / (busy + idle) : 0;
}

/* Runs `clients` client processes of `calls` enumerations each, all started by one event; their
   medians (ns) in `medians`, and in `busy` (when not NULL) how many of the machine's processors were
   busy while they ran. While they run, samples the browser's memory every 250 ms into `peak` (when
   not NULL). Exits the benchmark when a client fails or does not end in time. */
static void run_clients(int clients, int calls, double *medians, HANDLE browser, Memory *peak, double *busy)
{
    HANDLE go = CreateEventW(NULL, TRUE, FALSE, GO_EVENT), ready = CreateSemaphoreW(NULL, 0, CLIENTS, READY_SEMAPHORE);
    HANDLE procs[CLIENTS];
    char out[CLIENTS][MAX_PATH];
    WCHAR tmp[MAX_PATH];
    GetTempPathW(MAX_PATH, tmp);
    for (int i = 0; i < clients; i++) {
        WCHAR cmd[3 * MAX_PATH];
        STARTUPINFOW si;
        PROCESS_INFORMATION pi;
        snprintf(out[i], MAX_PATH, "%lsopccomn-bench-browser-%lu-%d.txt", tmp, (unsigned long)GetCurrentProcessId(), i);
        swprintf(cmd, 3 * MAX_PATH, L"\"%ls\" client %d \"%hs\"", self, calls, out[i]);
        memset(&si, 0, sizeof si);
        si.cb = sizeof si;
        if (!CreateProcessW(NULL, cmd, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi)) {
            fprintf(stderr, "cannot start a client\n");
            exit(2);
        }
        CloseHandle(pi.hThread);
        procs[i] = pi.hProcess;
    }
    /* Every client connected (a client that ended before is a failure). */
    for (int i = 0, waited = 0; i < clients;) {
        if (WaitForSingleObject(ready, 1000) == WAIT_OBJECT_0) {
            i++;
            continue;
        }
        if (WaitForMultipleObjects((DWORD)clients, procs, FALSE, 0) != WAIT_TIMEOUT || ++waited > CLIENT_TIMEOUT_MS / 1000) {
            fprintf(stderr, "a client ended or did not connect within %d s\n", CLIENT_TIMEOUT_MS / 1000);
            for (int k = 0; k < clients; k++)
                TerminateProcess(procs[k], 9);
            exit(2);
        }
    }
    CpuTimes cpu_before = cpu_times();
    SetEvent(go);
    ULONGLONG deadline = GetTickCount64() + CLIENT_TIMEOUT_MS;
    for (;;) {
        DWORD w = WaitForMultipleObjects((DWORD)clients, procs, TRUE, 250);
        if (peak) {
            Memory m = browser_memory(browser);
            if (m.pagefile_mb > peak->pagefile_mb)
                peak->pagefile_mb = m.pagefile_mb;
            if (m.working_set_mb > peak->working_set_mb)
                peak->working_set_mb = m.working_set_mb;
        }
        if (w != WAIT_TIMEOUT) {
            if (busy)
                *busy = busy_processors(cpu_before, cpu_times());
            break;
        }
        if (GetTickCount64() > deadline) {
            printf("STALL: %d client(s) did not end within %d s (a call into the browser never returned): the "
                   "clients and the browser are stopped, the figures above are those of the rounds complete\n",
                   clients, CLIENT_TIMEOUT_MS / 1000);
            for (int i = 0; i < clients; i++)
                TerminateProcess(procs[i], 9);
            stalled(browser);
        }
    }
    for (int i = 0; i < clients; i++) {
        DWORD code = 99;
        double median = 0, highest = 0;
        GetExitCodeProcess(procs[i], &code);
        CloseHandle(procs[i]);
        FILE *f = fopen(out[i], "r");
        if (code != 0 || !f || fscanf(f, "%lf %lf", &median, &highest) != 2) {
            fprintf(stderr, "client %d failed (exit code %lu)\n", i, (unsigned long)code);
            exit(2);
        }
        fclose(f);
        remove(out[i]);
        medians[i] = median;
    }
    CloseHandle(go);
    CloseHandle(ready);
}

static DWORD run_browser(const WCHAR *args)
{
    WCHAR cmd[2 * MAX_PATH];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    DWORD code = 999;
    swprintf(cmd, 2 * MAX_PATH, L"\"%ls\\opccomn_browser.exe\" %ls", dir, args);
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    if (!CreateProcessW(NULL, cmd, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi))
        return 998;
    WaitForSingleObject(pi.hProcess, 60000);
    GetExitCodeProcess(pi.hProcess, &code);
    CloseHandle(pi.hProcess);
    CloseHandle(pi.hThread);
    return code;
}

static int key_exists(const WCHAR *key)
{
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_READ, &h) != ERROR_SUCCESS)
        return 0;
    RegCloseKey(h);
    return 1;
}

/* Lets go of the browser and waits for its process to end (60 s at most), then unregisters what
   the case registered. */
static void end_clients_case(IOPCServerList2 *holder, HANDLE browser)
{
    holder->lpVtbl->Release(holder);
    if (browser) {
        if (WaitForSingleObject(browser, 60000) != WAIT_OBJECT_0) {
            printf("STALL: the browser did not end within 60 s of its last client: stopped\n");
            stalled(browser);
        }
        CloseHandle(browser);
    }
    unregister_browser();
}

/* The browser service with client processes. `cached` false: the browser scans the registry on
   every call (COM starts it from this process, with OPCCOMN_SERVER_LIST_CACHE=0 in the environment
   it inherits), fewer rounds and calls, for information. */
static void clients_case(int cached)
{
    int rounds = cached ? client_rounds : scanning_rounds, calls = cached ? client_calls : scanning_calls;
    /* The proxy/stub of the interfaces and the browser, unless the machine has them already. */
    own_proxy_stub = !key_exists(L"Interface\\{13486D50-4821-11D2-A494-3CB306C10000}\\ProxyStubClsid32");
    own_browser = !key_exists(L"CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}\\LocalServer32");
    if (own_proxy_stub && OpcRegisterProxyStub(NULL, 0) != S_OK) {
        fprintf(stderr, "cannot register the proxy/stub\n");
        exit(2);
    }
    if (own_browser && run_browser(L"/RegServer") != 0) {
        fprintf(stderr, "cannot register the browser\n");
        exit(2);
    }
    /* This process holds the browser for the whole case (COM starts it for the first client). */
    IOPCServerList2 *holder = NULL;
    /* One that a client before this run left may still be ending (an EXE server ends after its last
       client's release): it gets 30 s. */
    for (int waited = 0; browser_pid() && waited < 300; waited++)
        Sleep(100);
    if (browser_pid()) {
        fprintf(stderr, "a browser runs already: this case needs one of its own\n");
        exit(2);
    }
    SetEnvironmentVariableW(L"OPCCOMN_SERVER_LIST_CACHE", cached ? NULL : L"0");
    if (CoCreateInstance(&CLSID_OPCServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&holder) !=
            S_OK ||
        enumerate(holder) < SERVERS) {
        fprintf(stderr, "cannot browse through the browser service\n");
        exit(2);
    }
    SetEnvironmentVariableW(L"OPCCOMN_SERVER_LIST_CACHE", NULL);
    DWORD pid = browser_pid();
    HANDLE browser =
        pid ? OpenProcess(PROCESS_QUERY_INFORMATION | PROCESS_VM_READ | SYNCHRONIZE | PROCESS_TERMINATE, FALSE, pid) : NULL;

    printf("\nThe browser service (opccomn_browser.exe, pid %lu) %s, with client processes, %d enumerations per "
           "client and round, %d rounds\n",
           (unsigned long)pid,
           cached ? "answering from its last scan (default)" : "scanning the registry on every call (OPCCOMN_SERVER_LIST_CACHE=0)",
           calls, rounds);
    double single[CLIENT_ROUNDS], worst[CLIENT_ROUNDS], ratio[CLIENT_ROUNDS], floor_ratio[CLIENT_ROUNDS];
    int cpus = processors();
    for (int round = 0; round < rounds; round++) {
        double alone[1], many[CLIENTS], busy_alone = 0, busy_many = 0;
        run_clients(1, calls, alone, browser, NULL, &busy_alone);
        run_clients(CLIENTS, calls, many, browser, NULL, &busy_many);
        single[round] = alone[0];
        worst[round] = many[0];
        for (int i = 1; i < CLIENTS; i++)
            if (many[i] > worst[round])
                worst[round] = many[i];
        ratio[round] = worst[round] / single[round];
        char a[24], b[24];
        bench_format_ns(a, sizeof a, single[round]);
        bench_format_ns(b, sizeof b, worst[round]);
        /* What the processors alone would allow: the 8 clients need 8 times the processor time one
           client used (if an enumeration costs the same), and have `cpus` processors (less what else
           runs) to share. */
        floor_ratio[round] = CLIENTS * busy_alone / cpus;
        printf("round %d: one client alone %s per enumeration (median), the slowest of %d at once %s (%.2fx); "
               "processors busy: %.2f alone, %.2f with %d at once, of %d\n",
               round + 1, a, CLIENTS, b, ratio[round], busy_alone, busy_many, CLIENTS, cpus);
    }
    double m, lo, hi, fm, flo, fhi;
    bench_stats(ratio, rounds, &m, &lo, &hi);
    bench_stats(floor_ratio, rounds, &fm, &flo, &fhi);
    printf("for information: the ratio the processors alone would give if an enumeration cost the same "
           "processor time with %d clients as with one (%d x the processors busy with one client alone / %d "
           "processors): %.2fx (rounds %.2f-%.2f)\n",
           CLIENTS, CLIENTS, cpus, fm, flo, fhi);
    if (!cached) {
        printf("for information: 8 clients at once, the slowest client's median / one client alone: %.2fx (rounds "
               "%.2f-%.2f)\n",
               m, lo, hi);
        end_clients_case(holder, browser);
        return;
    }
    bench_goal("8 clients at once: the slowest client's median / one client alone", m, lo, hi, 0, 3.0, "x");

    /* 3. Memory over 8 x 1,000 enumerations (4 batches of 8 x 250), after a warm-up of 8 x 100. */
    double medians[CLIENTS];
    Memory after[MEMORY_BATCHES + 1], peak = {0, 0};
    run_clients(CLIENTS, CALLS_PER_ROUND, medians, browser, NULL, NULL);
    after[0] = browser_memory(browser);
    printf("\nThe browser's memory over %d x %d enumerations (working set, committed; MB): after a warm-up of %d x %d "
           "%.1f, %.1f",
           CLIENTS, MEMORY_CALLS, CLIENTS, CALLS_PER_ROUND, after[0].working_set_mb, after[0].pagefile_mb);
    for (int b = 1; b <= MEMORY_BATCHES; b++) {
        run_clients(CLIENTS, MEMORY_CALLS / MEMORY_BATCHES, medians, browser, &peak, NULL);
        after[b] = browser_memory(browser);
        printf("; after %d x %d %.1f, %.1f", CLIENTS, b * MEMORY_CALLS / MEMORY_BATCHES, after[b].working_set_mb,
               after[b].pagefile_mb);
    }
    printf("; at most %.1f, %.1f while the clients ran\n", peak.working_set_mb, peak.pagefile_mb);
    if (after[0].working_set_mb <= 0) {
        fprintf(stderr, "the browser's memory cannot be read\n");
        exit(2);
    }
    /* Flat: what the last 3/4 of the enumerations added, against the memory after the first 1/4. */
    double ws = after[MEMORY_BATCHES].working_set_mb / after[1].working_set_mb;
    double lo_ws = ws, hi_ws = ws;
    for (int b = 2; b <= MEMORY_BATCHES; b++) {
        double x = after[b].working_set_mb / after[1].working_set_mb;
        lo_ws = x < lo_ws ? x : lo_ws;
        hi_ws = x > hi_ws ? x : hi_ws;
    }
    bench_goal("browser's working set after 8 x 1,000 / after 8 x 250", ws, lo_ws, hi_ws, 0, 1.05, "x");
    if (after[1].pagefile_mb > 0) {
        double c = after[MEMORY_BATCHES].pagefile_mb / after[1].pagefile_mb;
        bench_goal("browser's committed memory after 8 x 1,000 / after 8 x 250", c, c, c, 0, 1.05, "x");
    }

    end_clients_case(holder, browser);
}

/* Removes the 600 servers, and what unregister_browser removes. */
static void cleanup(void)
{
    unregister_browser();
    registration(0);
}

/* `bench_browser [--quick] [enumeration | clients | scanning-clients]` runs one case (`clients` both
   the scanning and the cached browser, `scanning-clients` the first only); `bench_browser client ...`
   is a client. */
int main(int argc, char **argv)
{
    GetModuleFileNameW(NULL, self, MAX_PATH);
    wcscpy(dir, self);
    WCHAR *slash = wcsrchr(dir, L'\\');
    if (slash)
        *slash = 0;
    if (argc == 4 && !strcmp(argv[1], "client"))
        return client_main(atoi(argv[2]), argv[3]);
    const char *only = NULL;
    int quick = 0;
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--quick"))
            quick = 1;
        else if (!only && (!strcmp(argv[a], "enumeration") || !strcmp(argv[a], "clients") ||
                           !strcmp(argv[a], "scanning-clients")))
            only = argv[a];
        else {
            fprintf(stderr, "usage: bench_browser [--quick] [enumeration | clients | scanning-clients]\n");
            return 2;
        }
    }
    bench_rounds = quick ? 5 : 15;
    bench_budget_s = quick ? 30 : 240;
    if (quick) {
        client_rounds = 3;
        client_calls = 30;
        scanning_rounds = 1;
        scanning_calls = 5;
    }
    bench_init();
    CoInitializeEx(NULL, COINIT_MULTITHREADED);
    registration(0); /* what a stopped run left */
    registration(1);
    if (!only || !strcmp(only, "enumeration"))
        one_enumeration_case();
    if (!only || !strcmp(only, "clients") || !strcmp(only, "scanning-clients"))
        clients_case(0);
    if (!only || !strcmp(only, "clients"))
        clients_case(1);
    cleanup();
    CoUninitialize();
    return bench_finish("bench_browser");
}
#endif
