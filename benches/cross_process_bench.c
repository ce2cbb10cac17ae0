/* Benchmark: round trips across processes through opccomn.dll's proxy/stub against the widl-generated
 * one (opccomn_widl_ps.dll, the stand-in for the Foundation's opccomn_ps.dll), in the same run, under
 * the same COM runtime.
 *
 *   GetErrorString     IOPCCommon::GetErrorString(OPC_E_UNKNOWNITEMID) + CoTaskMemFree
 *   Enum+Next(100)     IOPCServerList2::EnumClassesOfCategories + IOPCEnumGUID::Next of 100 + Release
 *
 * Three test servers (tests/oop/oop_server.c, each serving its own CLSIDs) run at once: one with
 * opccomn.dll's proxy/stub, two with the stand-in's. The second stand-in is the control: the same
 * proxy/stub measured against itself shows how far this run's machine lets two equal contenders
 * differ. This client holds proxies to each server, made while the matching proxy/stub was the one
 * registered for the five interfaces here (CoRegisterPSClsid; both class objects are registered in
 * this process, so that neither pays a registry lookup the other does not); before each batch of
 * Enum+Next it registers the batch's one again, as every call makes a new enumerator proxy. Each
 * server and each kind of proxy is checked to be the one it should be before anything is timed.
 * Client and servers register their proxy/stubs in their own processes only (COM prefers them to the
 * registry): the machine's registration of the five interfaces (Interface\{iid}\ProxyStubClsid32,
 * opccomn's or the Foundation's) is not changed, so out-of-process clients of that machine keep
 * working during and after a run. What the benchmark registers is its three servers' classes,
 * removed at its end, after a failure and after a stall (and by `--unregister`, for a run killed from
 * outside).
 *
 * The contenders run in interleaved rounds (--rounds, 51 by default, the order rotating), a batch of
 * calls a round. Printed per operation: the median wall-clock time per round trip of each, the median
 * of the rounds' ratios with their spread (lowest-highest), the CPU time of this process and the
 * server (summed over the run: it advances in 10 ms ticks under Wine), and a GOAL line (median ratio
 * opccomn/widl <= 1.1x) with met or NOT MET, as the other benchmarks do.
 *
 * Bounded in time. A round trip can hang for ever under Wine (Wine 8: a stub's teardown waiting in
 * RpcServerUnregisterIf while the client waits in IUnknown_Release_Proxy), so a watchdog thread
 * watches each step: a batch of round trips that does not end within --stall-s seconds (60 by
 * default), or a server's start or end within twice that (120 s at least), is a stall. The watchdog
 * then prints the figures of the rounds complete so far, marked partial (none when no round was), and
 * what stalled, removes the benchmark's classes, ends its servers and ends the process with exit code
 * 3. Rounds also stop once --budget-s seconds (1200 by default) have passed since the first; the
 * figures then say how many of the rounds they come from.
 *
 * Exit code: 0 when every goal is met, 1 when one is missed or a round trip failed (the failing call
 * and its HRESULT are printed), 3 after a stall, 2 for a usage error. Run with
 * scripts/bench-cross-process.sh [N]: N GetErrorString and N/5 Enum+Next per contender in all
 * (default 10200).
 *
 *   cross_process_bench [--rounds R] [--budget-s S] [--stall-s S] [--simulate-stall ROUND] [--sets F] [N]
 *   cross_process_bench [--sets F] --unregister   removes the classes a run killed from outside left
 *
 * --sets F gives the contenders the test server's classes of sets F, F+1 and F+2 (oop.h; default 1).
 *
 * --simulate-stall ROUND makes the first batch of that round hang as a round trip that never returns
 * does (tests/oop/test_bench_registration.c uses it). */
#include "oop.h"

#define OOP_BENCH_PROGRAM "cross_process_bench"
#define OOP_BENCH_USER_TYPE L"opccomn cross-process benchmark server"
#include "oop_bench.h"

static const CATID CATID_DA2 = {0x63D5F432, 0xCFE4, 0x11D1, {0xB2, 0xC8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
static const char *const OPERATIONS[2] = {"GetErrorString", "Enum+Next(100)"};

typedef struct {
    const char *name;
    int widl;                /* the stand-in's proxy/stub (else opccomn.dll's) */
    unsigned set;            /* the server's CLSIDs: oop_class(set, ...) */
    IOPCCommon *common;
    IOPCServerList2 *list;
    DWORD server_pid;        /* its server's process, ended after a stall */
    double wall[2][MAX_ROUNDS]; /* per operation and round: seconds per round trip */
    unsigned long long cpu[2]; /* per operation: CPU time of both processes over the run, 100 ns units */
    long long calls[2];      /* per operation: timed round trips */
} Contender;

static Contender contenders[CONTENDERS] = {
    {.name = "opccomn", .widl = 0, .set = 1}, {.name = "widl", .widl = 1, .set = 2}, {.name = "widl (control)", .widl = 1, .set = 3}};

/* The run's settings (command line), beside rounds and stall_s (oop_bench.h). */
static double budget_s = 1200;
static int simulate_stall_round = -2; /* (-1 is the warm-up) */
static int batch_calls[2];            /* per operation: round trips a batch */

/* Makes the contender's proxy/stub the one this process uses for the five interfaces. */
static HRESULT select_proxy_stub(const Contender *k) {
    HRESULT hr = S_OK;
    int i;
    for (i = 0; SUCCEEDED(hr) && i < 5; i++)
        hr = CoRegisterPSClsid(OOP_IIDS[i], k->widl ? &CLSID_WidlProxyStub : &CLSID_OpcComnProxyStub);
    return hr;
}

static void prog_id(const Contender *k, int list, WCHAR *out) {
    swprintf(out, 40, L"Oop.Bench%u.%ls.1", k->set, list ? L"ServerList" : L"Server");
}

/* The contender's two classes, whose server's command line names its proxy/stub and its CLSIDs. */
static HRESULT register_classes(const Contender *k) {
    WCHAR arguments[40], name[40];
    HRESULT hr = S_OK;
    int list;
    swprintf(arguments, 40, L" %ls -set:%u", k->widl ? L"-ps:widl" : L"-ps:opccomn-direct", k->set);
    for (list = 0; SUCCEEDED(hr) && list < 2; list++) {
        CLSID clsid = oop_class(k->set, list);
        prog_id(k, list, name);
        hr = register_class(&clsid, name, arguments);
    }
    return hr;
}

static void unregister_all(void) {
    WCHAR name[40];
    int i, list;
    for (i = 0; i < CONTENDERS; i++)
        for (list = 0; list < 2; list++) {
            CLSID clsid = oop_class(contenders[i].set, list);
            prog_id(&contenders[i], list, name);
            unregister_class(&clsid, name);
        }
}

static DWORD server_pid(int i) { return contenders[i].server_pid; }
static unsigned *contender_set(int i) { return &contenders[i].set; }

/* A vendor code's answer from the contender's server, as text (0 when it gave none). */
static int ask_server(Contender *k, HRESULT code, char *out, size_t size) {
    LPWSTR text = NULL;
    HRESULT hr = k->common->lpVtbl->GetErrorString(k->common, code, &text);
    return server_answer(k->name, hr, text, out, size);
}

/* The contender's server makes its stubs with the proxy/stub it should. */
static int server_checked(Contender *k) {
    char narrow[32];
    const char *expected = k->widl ? "widl" : "opccomn";
    if (!ask_server(k, OOP_CODE_PROXY_STUB, narrow, sizeof narrow)) return 0;
    if (strcmp(narrow, expected) != 0) {
        fprintf(stderr, "cross_process_bench: the %s server's stubs come from %s\n", k->name, narrow);
        return 0;
    }
    return 1;
}

/* One enumeration; *made_widl_proxy (when given) tells whether its proxy came from the stand-in. */
static HRESULT enumerate(Contender *k, int *made_widl_proxy) {
    IOPCEnumGUID *e = NULL;
    GUID buf[OOP_FAKE_SERVERS];
    ULONG fetched = 0;
    LONG before = made_widl_proxy ? widl_proxy_stub_refs() : 0; /* (not in the timed loop) */
    HRESULT hr = k->list->lpVtbl->EnumClassesOfCategories(k->list, 1, (CATID *)&CATID_DA2, 0, NULL, &e);
    if (FAILED(hr)) return hr;
    if (made_widl_proxy) *made_widl_proxy = widl_proxy_stub_refs() > before;
    hr = e->lpVtbl->Next(e, OOP_FAKE_SERVERS, buf, &fetched);
    e->lpVtbl->Release(e);
    if (FAILED(hr)) return hr;
    return hr == S_OK && fetched == OOP_FAKE_SERVERS ? S_OK : E_FAIL;
}

/* The contender's server objects, made with its proxy/stub, and checked to be what they should be. */
static int connect_contender(Contender *k) {
    HRESULT hr = select_proxy_stub(k);
    CLSID server = oop_class(k->set, 0), list = oop_class(k->set, 1);
    LONG before = widl_proxy_stub_refs();
    int widl_enum = -1;
    char pid[32];
    if (FAILED(hr)) return failed(k->name, "CoRegisterPSClsid", hr);
    step(setup_limit_s(), "starting the %s server (CoCreateInstance)", k->name);
    hr = CoCreateInstance(&server, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&k->common);
    if (FAILED(hr)) return failed(k->name, "creating the server", hr);
    step(setup_limit_s(), "checking the %s server", k->name);
    if (!ask_server(k, OOP_CODE_PROCESS_ID, pid, sizeof pid)) return 1;
    k->server_pid = (DWORD)strtoul(pid, NULL, 10);
    hr = CoCreateInstance(&list, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&k->list);
    if (FAILED(hr)) return failed(k->name, "creating the server list", hr);
    if ((widl_proxy_stub_refs() > before) != k->widl) {
        fprintf(stderr, "cross_process_bench: the %s proxies came from the other proxy/stub\n", k->name);
        return 1;
    }
    if (!server_checked(k)) return 1;
    if (FAILED(hr = enumerate(k, &widl_enum))) return failed(k->name, "EnumClassesOfCategories + Next", hr);
    if (widl_enum != k->widl) {
        fprintf(stderr, "cross_process_bench: the %s enumerator proxy came from the other proxy/stub\n", k->name);
        return 1;
    }
    return 0;
}

/* CPU time (100 ns units) this process and the contender's server process have used so far. */
static HRESULT cpu_time(Contender *k, unsigned long long *total) {
    LPWSTR text = NULL;
    HRESULT hr = k->common->lpVtbl->GetErrorString(k->common, OOP_CODE_CPU_TIME, &text);
    if (hr != S_OK) return FAILED(hr) ? hr : E_FAIL;
    *total = (unsigned long long)_wcstoui64(text, NULL, 10) + process_cpu_time();
    CoTaskMemFree(text);
    return S_OK;
}

static int contender_batch(int which, int op, int round) {
    Contender *k = &contenders[which];
    unsigned long long cpu_before = 0, cpu_after = 0;
    double t0, t1;
    HRESULT hr = S_OK;
    int i;
    if (round < 0) step(stall_s, "the warm-up's %s batch of the %s contender", OPERATIONS[op], k->name);
    else step(stall_s, "round %d: the %s batch of the %s contender", round + 1, OPERATIONS[op], k->name);
    if (op == 1 && FAILED(hr = select_proxy_stub(k))) return failed(k->name, "CoRegisterPSClsid", hr);
    if (FAILED(hr = cpu_time(k, &cpu_before))) return failed(k->name, "reading CPU times", hr);
    if (round == simulate_stall_round) Sleep(INFINITE); /* a round trip that never returns */
    t0 = now();
    for (i = 0; i < batch_calls[op]; i++) {
        if (op == 0) {
            LPWSTR text = NULL;
            hr = k->common->lpVtbl->GetErrorString(k->common, (HRESULT)0xC0040007L, &text);
            if (FAILED(hr) || !text) return failed(k->name, "GetErrorString", FAILED(hr) ? hr : E_POINTER);
            CoTaskMemFree(text);
        } else if (FAILED(hr = enumerate(k, NULL))) {
            return failed(k->name, "EnumClassesOfCategories + Next", hr);
        }
    }
    t1 = now();
    if (FAILED(hr = cpu_time(k, &cpu_after))) return failed(k->name, "reading CPU times", hr);
    if (round >= 0) {
        k->wall[op][round] = (t1 - t0) / batch_calls[op];
        k->cpu[op] += cpu_after - cpu_before;
        k->calls[op] += batch_calls[op];
    }
    return 0;
}

static double cpu_per_call(const Contender *k, int op) {
    return k->calls[op] ? (double)k->cpu[op] / 10.0 / (double)k->calls[op] : 0;
}

static int print_table(int n) {
    int op, missed = 0;
    printf("%-16s %-44s | %-31s\n", "", "wall clock: median per round trip (us), ratio", "CPU, both processes (us)");
    printf("%-16s %8s %8s %8s %10s %8s | %8s %8s %8s\n", "round trip", "opccomn", "widl", "ratio", "spread",
           "control", "opccomn", "widl", "ratio");
    for (op = 0; op < 2; op++) {
        double lo, hi, clo, chi, ratio, control;
        double cpu_ours = cpu_per_call(&contenders[0], op), cpu_widl = cpu_per_call(&contenders[1], op);
        char cpu_ratio[16] = "       -"; /* a short run can see no 10 ms tick of CPU time */
        if (cpu_ours > 0 && cpu_widl > 0) snprintf(cpu_ratio, sizeof cpu_ratio, "%7.2fx", cpu_ours / cpu_widl);
        ratio = paired_ratio(contenders[0].wall[op], contenders[1].wall[op], n, &lo, &hi);
        control = paired_ratio(contenders[2].wall[op], contenders[1].wall[op], n, &clo, &chi);
        printf("%-16s %8.1f %8.1f %7.2fx %4.2f-%.2fx %7.2fx | %8.1f %8.1f %s\n", OPERATIONS[op],
               median(contenders[0].wall[op], n) * 1e6, median(contenders[1].wall[op], n) * 1e6, ratio, lo, hi,
               control, cpu_ours, cpu_widl, cpu_ratio);
    }
    printf("(control: the stand-in against itself, %s; spread: the lowest and highest of the rounds' ratios)\n",
           "the difference this run's machine makes between equal contenders");
    for (op = 0; op < 2; op++) {
        double lo, hi, ratio = paired_ratio(contenders[0].wall[op], contenders[1].wall[op], n, &lo, &hi);
        missed |= !goal_met(OPERATIONS[op], ratio, n);
    }
    return missed;
}

static int usage(void) {
    fprintf(stderr, "usage: cross_process_bench [--rounds R] [--budget-s S] [--stall-s S] [--simulate-stall ROUND] [--sets F] [N]\n"
                    "       cross_process_bench --unregister\n");
    return 2;
}

int main(int argc, char **argv) {
    int total = 10200, i, a, failure = 0, missed = 0;
    HANDLE thread;
    begin(L"opccomn_test_server.exe");
    for (a = 1; a < argc; a++) {
        const char *value = a + 1 < argc ? argv[a + 1] : NULL;
        if (common_option(argc, argv, &a, &budget_s)) continue;
        if (!strcmp(argv[a], "--simulate-stall") && value && atoi(value) >= 1) {
            simulate_stall_round = atoi(value) - 1, a++;
        } else if (argv[a][0] != '-' && atoi(argv[a]) > 0) {
            total = atoi(argv[a]);
        } else {
            return usage();
        }
    }
    if (rounds < 1 || rounds > MAX_ROUNDS || budget_s <= 0 || stall_s <= 0) return usage();
    if (total < 5 * rounds) total = 5 * rounds;
    batch_calls[0] = total / rounds;
    batch_calls[1] = total / 5 / rounds;
    printf("%d rounds of each contender, interleaved: %d x GetErrorString and %d x Enum+Next(100) a round "
           "(limits: %.0f s for the rounds, %.0f s for a batch)\n", rounds, batch_calls[0], batch_calls[1], budget_s, stall_s);
    thread = start_watchdog();
    if (!thread) return failed(contenders[0].name, "starting the watchdog", HRESULT_FROM_WIN32(GetLastError()));
    if (FAILED(CoInitializeEx(NULL, COINIT_MULTITHREADED)) || FAILED(use_widl_proxy_stub()) ||
        FAILED(use_opccomn_proxy_stub_directly()))
        return 1;
    for (i = 0; i < CONTENDERS && !failure; i++) {
        HRESULT hr = register_classes(&contenders[i]);
        if (FAILED(hr)) failure = failed(contenders[i].name, "registering the test server", hr);
    }
    for (i = 0; i < CONTENDERS && !failure; i++) failure = connect_contender(&contenders[i]);
    if (!failure) failure = run_rounds(2, budget_s, &missed);
    for (i = 0; i < CONTENDERS; i++) {
        step(setup_limit_s(), "releasing the %s server's objects", contenders[i].name);
        if (contenders[i].list) contenders[i].list->lpVtbl->Release(contenders[i].list);
        if (contenders[i].common) contenders[i].common->lpVtbl->Release(contenders[i].common);
    }
    unregister_all();
    end_run(thread);
    if (failure) {
        fprintf(stderr, "cross_process_bench: stopped, no figures\n");
        return 1;
    }
    return missed;
}
