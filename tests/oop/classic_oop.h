/* Shared by the cross-process tests of the Data Access, Alarms & Events and Historical Data Access
 * proxy/stubs (test_da_tables.c with da_server.c and da_bench.c, through da.h; test_ae_tables.c with
 * ae_server.c, test_hda_tables.c with hda_server.c): opccomn.dll's
 * proxy/stub registered as this process's for a list of interfaces, without the registry; text in
 * UTF-8 copied to and compared with UTF-16 without W()'s shared buffers (the servers' callback
 * threads and the clients' sinks run beside the main thread); the times the servers stamp values
 * with. Windows only. */
#ifndef OPCCOMN_CLASSIC_OOP_H
#define OPCCOMN_CLASSIC_OOP_H

#include "oop.h" /* test_util.h, process_running() */

/* Makes COM use opccomn.dll's proxy/stub (CLSID_OpcComnProxyStub) for `iids` in this process (the
 * multithreaded apartment), without the registry. */
static HRESULT use_opccomn_proxy_stub_for(const IID *const *iids, size_t count) {
    IUnknown *factory = NULL;
    DWORD cookie;
    HRESULT hr;
    size_t i;
    hr = OpcDllGetClassObject(&CLSID_OpcComnProxyStub, &IID_IUnknown, (void **)&factory);
    if (FAILED(hr)) return hr;
    hr = CoRegisterClassObject(&CLSID_OpcComnProxyStub, factory, CLSCTX_INPROC_SERVER, REGCLS_MULTIPLEUSE, &cookie);
    factory->lpVtbl->Release(factory);
    for (i = 0; SUCCEEDED(hr) && i < count; i++) hr = CoRegisterPSClsid(iids[i], &CLSID_OpcComnProxyStub);
    return hr;
}

/* Whether COM takes this process's proxies and stubs of every one of `iids` from opccomn.dll. */
static int proxy_stub_is_opccomn_for(const IID *const *iids, size_t count) {
    CLSID clsid;
    size_t i;
    for (i = 0; i < count; i++)
        if (FAILED(CoGetPSClsid(iids[i], &clsid)) || !IsEqualCLSID(&clsid, &CLSID_OpcComnProxyStub)) return 0;
    return 1;
}

/* A copy of UTF-8 text in task memory (what the NDR engine frees on the other side), or NULL. */
static LPWSTR task_utf8(const char *utf8) {
    int n;
    LPWSTR copy;
    if (!utf8) return NULL;
    n = MultiByteToWideChar(CP_UTF8, 0, utf8, -1, NULL, 0);
    if (n <= 0) return NULL;
    copy = (LPWSTR)CoTaskMemAlloc((size_t)n * sizeof(WCHAR));
    if (copy) MultiByteToWideChar(CP_UTF8, 0, utf8, -1, copy, n);
    return copy;
}

/* A BSTR of UTF-8 text, or NULL. */
static BSTR bstr_utf8(const char *utf8) {
    LPWSTR w = task_utf8(utf8);
    BSTR b = w ? SysAllocString(w) : NULL;
    CoTaskMemFree(w);
    return b;
}

/* Whether `got` is the UTF-8 text `want` (NULL only when `want` is NULL). */
static int is_utf8(const WCHAR *got, const char *want) {
    LPWSTR w;
    int same;
    if (!got || !want) return !got && !want;
    w = task_utf8(want);
    same = w && wcscmp(got, w) == 0;
    CoTaskMemFree(w);
    return same;
}

/* Whether `v` is a VT_BSTR of the UTF-8 text `want`, its length exact. */
static int is_bstr_utf8(const VARIANT *v, const char *want) {
    return V_VT(v) == VT_BSTR && is_utf8(V_BSTR(v), want) && SysStringLen(V_BSTR(v)) == wcslen(V_BSTR(v));
}

/* A FILETIME the servers stamp values with: 2026-12-04 12:00:00 UTC, plus i seconds. */
static FILETIME test_time(unsigned i) {
    ULARGE_INTEGER t;
    FILETIME f;
    t.QuadPart = 134095536000000000ULL + (ULONGLONG)i * 10000000ULL;
    f.dwLowDateTime = t.LowPart;
    f.dwHighDateTime = t.HighPart;
    return f;
}

static int same_filetime(FILETIME a, FILETIME b) {
    return a.dwLowDateTime == b.dwLowDateTime && a.dwHighDateTime == b.dwHighDateTime;
}

static void *task_zero(size_t size) {
    void *p = CoTaskMemAlloc(size ? size : 1);
    if (p) memset(p, 0, size ? size : 1);
    return p;
}

/* Checks a call's per-element results (CoTaskMemAlloc'd; freed here): element k must be the k-th
 * HRESULT listed. None (NULL, or still the garbage the pointer was pre-filled with) is a failure. */
#define CHECK_RESULTS(results, ...)                                                          \
    check_results_at(__FILE__, __LINE__, (results), (const HRESULT[]){__VA_ARGS__},          \
                     sizeof((const HRESULT[]){__VA_ARGS__}) / sizeof(HRESULT))

static inline void check_results_at(const char *file, int line, HRESULT *results, const HRESULT *want, size_t n) {
    size_t k;
    if (!results || results == (HRESULT *)GARBAGE_PTR) {
        test_failed++;
        fprintf(stderr, "%s:%d: no per-element results\n", file, line);
        return;
    }
    for (k = 0; k < n; k++) {
        if (results[k] == want[k]) {
            test_passed++;
        } else {
            test_failed++;
            fprintf(stderr, "%s:%d: element %u's result is 0x%08lX, expected 0x%08lX\n", file, line, (unsigned)k,
                    (unsigned long)(unsigned int)results[k], (unsigned long)(unsigned int)want[k]);
        }
    }
    CoTaskMemFree(results);
}

/* The path of a program beside this one (a server beside its client). */
static void beside_this_program(WCHAR *path, const WCHAR *name) {
    WCHAR *slash;
    GetModuleFileNameW(NULL, path, MAX_PATH);
    slash = wcsrchr(path, L'\\');
    wcscpy(slash ? slash + 1 : path, name);
}

/* A client that died leaves its references (Wine runs no rundown of a dead client's references): 20
 * minutes after the start a test server stops as its operator would. */
static DWORD WINAPI server_watchdog(void *unused) {
    (void)unused;
    Sleep(1200000);
    OpcExeServerStop();
    return 0;
}

/* The main of an EXE test server of `clsid` (LocalServer32, started by COM with -Embedding, hosted
 * by OpcExeServerRun), its proxy/stub for `iids` opccomn.dll's. Exits when its last object is
 * released (or after two minutes without a client, or 20 minutes after the start). */
static int run_test_server(const char *name, const CLSID *clsid, const WCHAR *prog_id, const WCHAR *user_type,
                           OpcCreateInstanceFn create, const IID *const *iids, size_t count) {
    OpcServerRegistration reg;
    OpcServerClass cls;
    OpcExeServerOptions options;
    HANDLE timer;
    HRESULT hr;
    memset(&reg, 0, sizeof reg);
    reg.struct_size = sizeof reg;
    reg.server_type = OPC_SERVER_TYPE_LOCAL;
    reg.clsid = *clsid;
    reg.prog_id = prog_id;
    reg.user_type = user_type;
    memset(&cls, 0, sizeof cls);
    cls.struct_size = sizeof cls;
    cls.clsid = clsid;
    cls.create = create;
    cls.registration = &reg;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.classes = &cls;
    options.class_count = 1;
    options.first_client_timeout_ms = 120000;
    options.release_timeout_ms = 30000;
    options.idle_linger_ms = 100;
    hr = CoInitializeEx(NULL, COINIT_MULTITHREADED);
    if (SUCCEEDED(hr)) hr = use_opccomn_proxy_stub_for(iids, count);
    timer = CreateThread(NULL, 0, server_watchdog, NULL, 0, NULL);
    if (timer) CloseHandle(timer);
    if (SUCCEEDED(hr)) hr = OpcExeServerRun(&options, NULL);
    if (FAILED(hr)) {
        fprintf(stderr, "%s: start failed: 0x%08lX\n", name, (unsigned long)hr);
        return 1;
    }
    if (hr == S_FALSE) {
        fprintf(stderr, "%s: exiting with objects a client never released\n", name);
        return 3;
    }
    return 0; /* without CoUninitialize (OpcExeServerRun) */
}

#endif
