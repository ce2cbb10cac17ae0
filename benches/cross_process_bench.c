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
 *
 * The contenders run in interleaved rounds (ROUNDS of each, the order rotating), a batch of calls a
 * round. Printed per operation: the median wall-clock time per round trip of each, the median of the
 * rounds' ratios with their spread (lowest-highest), the CPU time of this process and the server
 * (summed over the run: it advances in 10 ms ticks under Wine), and a GOAL line (median ratio
 * opccomn/widl <= 1.1x) with met or NOT MET, as the other benchmarks do; exit code 1 when a goal is
 * missed or a round trip failed (the failing call and its HRESULT are printed). Run with
 * scripts/bench-cross-process.sh [N]: N GetErrorString and N/5 Enum+Next per contender in all
 * (default 10200). */
#include "oop.h"

#define ROUNDS 51
#define CONTENDERS 3
static const CATID CATID_DA2 = {0x63D5F432, 0xCFE4, 0x11D1, {0xB2, 0xC8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
static WCHAR server_path[MAX_PATH];
static const char *const OPERATIONS[2] = {"GetErrorString", "Enum+Next(100)"};

typedef struct {
    const char *name;
    int widl;                /* the stand-in's proxy/stub (else opccomn.dll's) */
    unsigned set;            /* the server's CLSIDs: oop_class(set, ...) */
    IOPCCommon *common;
    IOPCServerList2 *list;
    double wall[2][ROUNDS];  /* per operation and round: seconds per round trip */
    unsigned long long cpu[2]; /* per operation: CPU time of both processes over the run, 100 ns units */
    long long calls[2];      /* per operation: timed round trips */
} Contender;

static Contender contenders[CONTENDERS] = {
    {.name = "opccomn", .widl = 0, .set = 1}, {.name = "widl", .widl = 1, .set = 2}, {.name = "widl (control)", .widl = 1, .set = 3}};

static double now(void) {
    LARGE_INTEGER f, c;
    QueryPerformanceFrequency(&f);
    QueryPerformanceCounter(&c);
    return (double)c.QuadPart / (double)f.QuadPart;
}

static int failed(const Contender *k, const char *what, HRESULT hr) {
    fprintf(stderr, "cross_process_bench: %s (%s): 0x%08lX\n", what, k->name, (unsigned long)hr);
    return 1;
}

/* Makes the contender's proxy/stub the one this process uses for the five interfaces. */
static HRESULT select_proxy_stub(const Contender *k) {
    HRESULT hr = S_OK;
    int i;
    for (i = 0; SUCCEEDED(hr) && i < 5; i++)
        hr = CoRegisterPSClsid(OOP_IIDS[i], k->widl ? &CLSID_WidlProxyStub : &CLSID_OpcComnProxyStub);
    return hr;
}

static OpcServerRegistration registration(const CLSID *clsid, const WCHAR *prog_id) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = *clsid;
    r.prog_id = prog_id;
    r.user_type = L"opccomn cross-process benchmark server";
    r.module_path = server_path;
    return r;
}

static void prog_id(const Contender *k, int list, WCHAR *out) {
    swprintf(out, 40, L"Oop.Bench%u.%ls.1", k->set, list ? L"ServerList" : L"Server");
}

/* The contender's two classes, whose server's command line names its proxy/stub and its CLSIDs. */
static HRESULT register_classes(const Contender *k) {
    WCHAR command[MAX_PATH + 40], key[80], guid[40], name[40];
    HRESULT hr = S_OK;
    int list;
    for (list = 0; SUCCEEDED(hr) && list < 2; list++) {
        CLSID clsid = oop_class(k->set, list);
        OpcServerRegistration r;
        HKEY h;
        prog_id(k, list, name);
        r = registration(&clsid, name);
        if (FAILED(hr = OpcRegisterServer(&r, NULL))) break;
        StringFromGUID2(&clsid, guid, 40);
        swprintf(key, 80, L"CLSID\\%ls\\LocalServer32", guid);
        swprintf(command, MAX_PATH + 40, L"\"%ls\" %ls -set:%u", server_path,
                 k->widl ? L"-ps:widl" : L"-ps:opccomn-direct", k->set);
        if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_WRITE, &h) != ERROR_SUCCESS) return E_FAIL;
        if (RegSetValueExW(h, NULL, 0, REG_SZ, (const BYTE *)command, (DWORD)((wcslen(command) + 1) * sizeof(WCHAR))))
            hr = E_FAIL;
        RegCloseKey(h);
    }
    return hr;
}

static void unregister_classes(const Contender *k) {
    WCHAR name[40];
    int list;
    for (list = 0; list < 2; list++) {
        CLSID clsid = oop_class(k->set, list);
        OpcServerRegistration r;
        prog_id(k, list, name);
        r = registration(&clsid, name);
        OpcUnregisterServer(&r, NULL);
    }
}

/* The contender's server makes its stubs with the proxy/stub it should. */
static int server_checked(Contender *k) {
    LPWSTR text = NULL;
    char narrow[32];
    const char *expected = k->widl ? "widl" : "opccomn";
    HRESULT hr = k->common->lpVtbl->GetErrorString(k->common, OOP_CODE_PROXY_STUB, &text);
    if (FAILED(hr) || !text) return failed(k, "asking the server for its proxy/stub", hr), 0;
    snprintf(narrow, sizeof narrow, "%ls", text);
    CoTaskMemFree(text);
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
    if (FAILED(hr)) return failed(k, "CoRegisterPSClsid", hr);
    hr = CoCreateInstance(&server, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&k->common);
    if (FAILED(hr)) return failed(k, "creating the server", hr);
    hr = CoCreateInstance(&list, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&k->list);
    if (FAILED(hr)) return failed(k, "creating the server list", hr);
    if ((widl_proxy_stub_refs() > before) != k->widl) {
        fprintf(stderr, "cross_process_bench: the %s proxies came from the other proxy/stub\n", k->name);
        return 1;
    }
    if (!server_checked(k)) return 1;
    if (FAILED(hr = enumerate(k, &widl_enum))) return failed(k, "EnumClassesOfCategories + Next", hr);
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

/* One round's batch of one operation (round -1: a warm-up, not recorded). */
static int batch(Contender *k, int op, int round, int calls) {
    unsigned long long cpu_before = 0, cpu_after = 0;
    double t0, t1;
    HRESULT hr = S_OK;
    int i;
    if (op == 1 && FAILED(hr = select_proxy_stub(k))) return failed(k, "CoRegisterPSClsid", hr);
    if (FAILED(hr = cpu_time(k, &cpu_before))) return failed(k, "reading CPU times", hr);
    t0 = now();
    for (i = 0; i < calls; i++) {
        if (op == 0) {
            LPWSTR text = NULL;
            hr = k->common->lpVtbl->GetErrorString(k->common, (HRESULT)0xC0040007L, &text);
            if (FAILED(hr) || !text) return failed(k, "GetErrorString", FAILED(hr) ? hr : E_POINTER);
            CoTaskMemFree(text);
        } else if (FAILED(hr = enumerate(k, NULL))) {
            return failed(k, "EnumClassesOfCategories + Next", hr);
        }
    }
    t1 = now();
    if (FAILED(hr = cpu_time(k, &cpu_after))) return failed(k, "reading CPU times", hr);
    if (round >= 0) {
        k->wall[op][round] = (t1 - t0) / calls;
        k->cpu[op] += cpu_after - cpu_before;
        k->calls[op] += calls;
    }
    return 0;
}

static int compare(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}
static double median(const double *v) {
    double s[ROUNDS];
    memcpy(s, v, sizeof s);
    qsort(s, ROUNDS, sizeof s[0], compare);
    return s[ROUNDS / 2];
}

/* The median of the rounds' ratios a/b, and their lowest and highest. */
static double paired_ratio(const double *a, const double *b, double *lo, double *hi) {
    double r[ROUNDS];
    int i;
    *lo = 1e9;
    *hi = 0;
    for (i = 0; i < ROUNDS; i++) {
        r[i] = a[i] / b[i];
        if (r[i] < *lo) *lo = r[i];
        if (r[i] > *hi) *hi = r[i];
    }
    return median(r);
}

static double cpu_per_call(const Contender *k, int op) { return (double)k->cpu[op] / 10.0 / (double)k->calls[op]; }

int main(int argc, char **argv) {
    int total = 10200, calls[2], round, op, i, failure = 0, missed = 0;
    double goal_ratio[2];
    WCHAR *slash;
    if (argc > 1 && atoi(argv[1]) >= 5 * ROUNDS) total = atoi(argv[1]);
    calls[0] = total / ROUNDS;
    calls[1] = total / 5 / ROUNDS;
    printf("%d rounds of each contender, interleaved: %d x GetErrorString and %d x Enum+Next(100) a round\n", ROUNDS,
           calls[0], calls[1]);
    GetModuleFileNameW(NULL, server_path, MAX_PATH);
    slash = wcsrchr(server_path, L'\\');
    wcscpy(slash ? slash + 1 : server_path, L"opccomn_test_server.exe");
    if (FAILED(CoInitializeEx(NULL, COINIT_MULTITHREADED)) || FAILED(use_widl_proxy_stub()) ||
        FAILED(use_opccomn_proxy_stub_directly()))
        return 1;
    OpcUnregisterProxyStub(NULL); /* whatever an interrupted earlier run left */
    if (FAILED(OpcRegisterProxyStub(NULL, 0))) failure = failed(&contenders[0], "OpcRegisterProxyStub", E_FAIL);
    for (i = 0; i < CONTENDERS && !failure; i++) {
        HRESULT hr = register_classes(&contenders[i]);
        if (FAILED(hr)) failure = failed(&contenders[i], "registering the test server", hr);
    }
    for (i = 0; i < CONTENDERS && !failure; i++) failure = connect_contender(&contenders[i]);
    for (op = 0; op < 2 && !failure; op++)
        for (i = 0; i < CONTENDERS && !failure; i++) failure = batch(&contenders[i], op, -1, calls[op]);
    for (round = 0; round < ROUNDS && !failure; round++)
        for (op = 0; op < 2 && !failure; op++)
            for (i = 0; i < CONTENDERS && !failure; i++)
                failure = batch(&contenders[(round + i) % CONTENDERS], op, round, calls[op]);
    for (i = 0; i < CONTENDERS; i++) {
        if (contenders[i].list) contenders[i].list->lpVtbl->Release(contenders[i].list);
        if (contenders[i].common) contenders[i].common->lpVtbl->Release(contenders[i].common);
        unregister_classes(&contenders[i]);
    }
    OpcUnregisterProxyStub(NULL);
    CoUninitialize();
    if (failure) {
        fprintf(stderr, "cross_process_bench: stopped, no figures\n");
        return 1;
    }
    printf("%-16s %-44s | %-31s\n", "", "wall clock: median per round trip (us), ratio", "CPU, both processes (us)");
    printf("%-16s %8s %8s %8s %10s %8s | %8s %8s %8s\n", "round trip", "opccomn", "widl", "ratio", "spread",
           "control", "opccomn", "widl", "ratio");
    for (op = 0; op < 2; op++) {
        double lo, hi, clo, chi, control;
        goal_ratio[op] = paired_ratio(contenders[0].wall[op], contenders[1].wall[op], &lo, &hi);
        control = paired_ratio(contenders[2].wall[op], contenders[1].wall[op], &clo, &chi);
        printf("%-16s %8.1f %8.1f %7.2fx %4.2f-%.2fx %7.2fx | %8.1f %8.1f %7.2fx\n", OPERATIONS[op],
               median(contenders[0].wall[op]) * 1e6, median(contenders[1].wall[op]) * 1e6, goal_ratio[op], lo, hi,
               control, cpu_per_call(&contenders[0], op), cpu_per_call(&contenders[1], op),
               cpu_per_call(&contenders[0], op) / cpu_per_call(&contenders[1], op));
    }
    printf("(control: the stand-in against itself, %s; spread: the lowest and highest of the rounds' ratios)\n",
           "the difference this run's machine makes between equal contenders");
    for (op = 0; op < 2; op++) {
        int met = goal_ratio[op] <= 1.1;
        printf("GOAL %-40s %7.2fx  goal <= 1.10x  %s\n", OPERATIONS[op], goal_ratio[op], met ? "met" : "NOT MET");
        missed |= !met;
    }
    return missed;
}
