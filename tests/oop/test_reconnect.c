/* Clients that release their last object of an EXE server and connect again after a gap, as clients
 * that browse and then connect do, under the real COM runtime (Wine in CI): every reconnect must
 * succeed, whatever the gap, on servers that run the library's EXE host at its defaults.
 *
 *   test_reconnect [-burst] TARGET...   TARGET: "browser" (the server browser, opccomn_browser.exe beside this
 *                              program, registered here), "server" (the cross-process test server
 *                              with the host's default linger, registered here), "example" (the C++
 *                              example's EXE server, registered by the caller)
 *
 * For each target, CHILDREN processes each connect ROUNDS times: create the class, call one method,
 * release everything, wait a gap. The CHILDREN x ROUNDS gaps are distinct and spread evenly over 0 to
 * 3 s, so the server's count falls to zero and rises again at every distance from the last release,
 * from several processes at once. The targets run at the same time.
 *
 * With -burst: BURST_CHILDREN processes x BURST_ROUNDS reconnects without gaps, each release right
 * after the reply to the call: a server's last object, and with it the last stub of an interface,
 * goes while the thread that served the call is still finishing it. A create that fails with
 * RPC_E_DISCONNECTED is made once more (said on the output), only in this mode. (tests/oop/interfaces-kept.sh
 * runs it and checks that the served interfaces stay registered with the RPC runtime throughout.) */
#include "oop.h"

#define CHILDREN 8
#define ROUNDS 25
#define MAX_GAP_MS 3000
#define BURST_CHILDREN 2
#define BURST_ROUNDS 200

/* This run's children, reconnects per child, longest gap (-burst: the BURST_ figures, no gaps). */
static int children_n = CHILDREN, rounds_n = ROUNDS, max_gap = MAX_GAP_MS;
/* How long all children together may take (each takes about 40 s on an idle machine, far more on a
 * loaded one: every activation then waits for the CPU). */
#define DEADLINE_MS 240000

/* The example's EXE server (examples/cpp-server). */
static const CLSID CLSID_Example = {0xBF0AE666, 0xD841, 0x4412, {0xB5, 0x87, 0xA7, 0x0F, 0x6A, 0x67, 0xBA, 0x2E}};
/* The test server's classes at the host's defaults: set 3, started with -linger:default. */
#define SERVER_SET 3

static WCHAR dir[MAX_PATH];

/* One reconnect: create, call, release (or, with `keep`, the object in *keep). The failing step in
 * *stage. */
static HRESULT connect_to(const char *target, const char **stage, IUnknown **keep) {
    HRESULT hr;
    void *p = NULL;
    if (!strcmp(target, "browser")) {
        IOPCServerList2 *l;
        CLSID c;
        *stage = "create";
        hr = CoCreateInstance(&CLSID_OPCServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, &p);
        if (FAILED(hr)) return hr;
        l = (IOPCServerList2 *)p;
        *stage = "call";
        hr = l->lpVtbl->CLSIDFromProgID(l, L"Oop.No.Such.Server.1", &c);
        if (hr == REGDB_E_CLASSNOTREG) hr = S_OK; /* the right answer */
        if (keep) *keep = (IUnknown *)l;
        else l->lpVtbl->Release(l);
    } else {
        CLSID clsid = !strcmp(target, "example") ? CLSID_Example : oop_class(SERVER_SET, 0);
        IOPCCommon *c;
        LCID lcid = 0;
        *stage = "create";
        hr = CoCreateInstance(&clsid, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, &p);
        if (FAILED(hr)) return hr;
        c = (IOPCCommon *)p;
        *stage = "call";
        hr = c->lpVtbl->GetLocaleID(c, &lcid);
        if (keep) *keep = (IUnknown *)c;
        else c->lpVtbl->Release(c);
    }
    return hr;
}

/* The gap after reconnect `round` of child `child`: the CHILDREN x ROUNDS gaps are the multiples
 * of a step coprime with MAX_GAP_MS + 1 (a prime), taken modulo it: all distinct, spread over 0 to
 * MAX_GAP_MS. */
static DWORD gap_ms(int child, int round) {
    unsigned k = (unsigned)(round * CHILDREN + child);
    return (DWORD)((k * 1543u) % (unsigned)(max_gap + 1));
}

/* A child: ROUNDS reconnects; its exit code is the number that failed. */
static int child_main(const char *target, int child) {
    int round, failed = 0;
    if (FAILED(CoInitializeEx(NULL, COINIT_MULTITHREADED))) return rounds_n;
    for (round = 0; round < rounds_n; round++) {
        const char *stage = "";
        DWORD gap = gap_ms(child, round);
        DWORD t0 = GetTickCount();
        HRESULT hr = connect_to(target, &stage, NULL);
        DWORD took;
        if (max_gap == 0 && hr == RPC_E_DISCONNECTED && !strcmp(stage, "create")) {
            /* -burst: an activation that Wine's runtime answers with RPC_E_DISCONNECTED (2 in 800 on
             * x86 under load; seen once in the gapped run too) is made once more, said here; the burst
             * is about the interfaces' registration, the gapped run keeps every reconnect strict. */
            printf("test_reconnect: %s, child %d, reconnect %d: create failed with 0x%08lX, made again\n", target,
                   child, round, (unsigned long)hr);
            fflush(stdout);
            hr = connect_to(target, &stage, NULL);
        }
        took = GetTickCount() - t0;
        if (took > 10000) {
            printf("test_reconnect: %s, child %d, reconnect %d took %lu ms\n", target, child, round, (unsigned long)took);
            fflush(stdout);
        }
        if (FAILED(hr)) {
            failed++;
            printf("test_reconnect: %s, child %d, reconnect %d: %s failed with 0x%08lX\n", target, child, round,
                   stage, (unsigned long)hr);
            fflush(stdout);
        }
        Sleep(gap);
    }
    CoUninitialize();
    return failed;
}

static HANDLE spawn(const WCHAR *args) {
    WCHAR self[MAX_PATH], cmd[MAX_PATH + 200];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    GetModuleFileNameW(NULL, self, MAX_PATH);
    swprintf(cmd, MAX_PATH + 200, L"\"%ls\" %ls", self, args);
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    if (!CreateProcessW(NULL, cmd, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi)) return NULL;
    CloseHandle(pi.hThread);
    return pi.hProcess;
}

/* Runs the browser beside this program with `args`; its exit code. */
static DWORD browser(const WCHAR *args) {
    WCHAR cmd[MAX_PATH + 100];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    DWORD code = 999;
    swprintf(cmd, MAX_PATH + 100, L"\"%ls\\opccomn_browser.exe\" %ls", dir, args);
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    if (!CreateProcessW(NULL, cmd, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi)) return 998;
    WaitForSingleObject(pi.hProcess, 60000);
    GetExitCodeProcess(pi.hProcess, &code);
    CloseHandle(pi.hProcess);
    CloseHandle(pi.hThread);
    return code;
}

static OpcServerRegistration test_server_registration(CLSID *clsid, WCHAR *path) {
    OpcServerRegistration r;
    *clsid = oop_class(SERVER_SET, 0);
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = *clsid;
    r.prog_id = L"Oop.ReconnectServer.1";
    r.user_type = L"opccomn reconnect test server";
    r.module_path = path;
    return r;
}

/* LocalServer32 of the test server: its set, and the host's defaults. */
static void set_test_server_command(const CLSID *clsid, const WCHAR *path) {
    WCHAR key[80], command[MAX_PATH + 64], guid[40];
    HKEY h;
    StringFromGUID2(clsid, guid, 40);
    swprintf(key, 80, L"CLSID\\%ls\\LocalServer32", guid);
    swprintf(command, MAX_PATH + 64, L"\"%ls\" -set:%d -linger:default", path, SERVER_SET);
    CHECK(RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_WRITE, &h) == ERROR_SUCCESS);
    CHECK(RegSetValueExW(h, NULL, 0, REG_SZ, (const BYTE *)command, (DWORD)((wcslen(command) + 1) * sizeof(WCHAR))) ==
          ERROR_SUCCESS);
    RegCloseKey(h);
}

int main(int argc, char **argv) {
    HANDLE children[8 * CHILDREN];
    const char *targets[8];
    IUnknown *warm[8];
    int count = 0, n = 0, i, t, with_browser = 0, with_server = 0, failed_total = 0;
    DWORD start;
    WCHAR server_path[MAX_PATH], *slash;
    OpcServerRegistration server;
    CLSID server_clsid;
    if (argc >= 2 && !strcmp(argv[1], "-burst")) {
        children_n = BURST_CHILDREN, rounds_n = BURST_ROUNDS, max_gap = 0;
        argv++, argc--;
    }
    if (argc == 4 && !strcmp(argv[1], "child")) return child_main(argv[2], atoi(argv[3]));
    for (i = 1; i < argc && count < 8; i++) {
        if (strcmp(argv[i], "browser") && strcmp(argv[i], "server") && strcmp(argv[i], "example")) count = 0, i = argc;
        else targets[count++] = argv[i];
    }
    if (count == 0) {
        fprintf(stderr, "usage: test_reconnect [-burst] browser|server|example...\n");
        return 2;
    }
    GetModuleFileNameW(NULL, dir, MAX_PATH);
    slash = wcsrchr(dir, L'\\');
    if (slash) *slash = 0;
    swprintf(server_path, MAX_PATH, L"%ls\\opccomn_test_server.exe", dir);
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    OpcUnregisterProxyStub(NULL); /* whatever an interrupted earlier run left */
    CHECK_HR(OpcRegisterProxyStub(NULL, 0), S_OK);
    for (t = 0; t < count; t++) {
        if (!strcmp(targets[t], "browser") && !with_browser) {
            with_browser = 1;
            CHECK(browser(L"/RegServer") == 0);
        }
        if (!strcmp(targets[t], "server") && !with_server) {
            with_server = 1;
            server = test_server_registration(&server_clsid, server_path);
            CHECK_HR(OpcRegisterServer(&server, NULL), S_OK);
            set_test_server_command(&server_clsid, server_path);
        }
    }
    printf("test_reconnect: %d processes x %d reconnects per target, gaps 0 to %d ms\n", children_n, rounds_n, max_gap);
    fflush(stdout);
    /* Each server is started by one activation first: under Wine, clients that activate a class at
     * the same moment while no process serves it can make COM start one process each, and those no
     * client reaches wait for their first client. The children's first activations find it running;
     * the first object is released once they have come (the count then falls and rises as they
     * come and go). */
    for (t = 0; t < count; t++) {
        const char *stage = "";
        warm[t] = NULL;
        CHECK_HR(connect_to(targets[t], &stage, &warm[t]), S_OK);
    }
    for (t = 0; t < count; t++) {
        for (i = 0; i < children_n; i++) {
            WCHAR args[64];
            swprintf(args, 64, L"%ls child %hs %d", max_gap ? L"" : L"-burst", targets[t], i);
            children[n] = spawn(args);
            CHECK(children[n] != NULL);
            if (children[n]) n++;
        }
    }
    Sleep(2000);
    for (t = 0; t < count; t++)
        if (warm[t]) warm[t]->lpVtbl->Release(warm[t]);
    start = GetTickCount();
    for (i = 0; i < n; i++) {
        DWORD code = 999, spent = GetTickCount() - start;
        /* 25 gaps of 1.5 s on average, and the activations: far less than this, all together. */
        DWORD left = spent < DEADLINE_MS ? DEADLINE_MS - spent : 0;
        if (WaitForSingleObject(children[i], left) != WAIT_OBJECT_0) {
            printf("test_reconnect: child %d of %s did not finish within %d s\n", i % children_n,
                   targets[i / children_n], DEADLINE_MS / 1000);
            TerminateProcess(children[i], 999);
            WaitForSingleObject(children[i], 5000);
        }
        GetExitCodeProcess(children[i], &code);
        CHECK(code == 0);
        failed_total += code == 0 ? 0 : (code <= (DWORD)rounds_n ? (int)code : rounds_n);
        CloseHandle(children[i]);
    }
    for (t = 0; t < count; t++) printf("test_reconnect: %s: %d reconnects\n", targets[t], children_n * rounds_n);
    printf("test_reconnect: %d of %d reconnects failed\n", failed_total, n * rounds_n);

    /* The servers end on their own, the linger (5 s) and the end's pause (1 s) after their last
     * release. */
    for (t = 0; t < count; t++) {
        const WCHAR *exe = !strcmp(targets[t], "browser")  ? L"opccomn_browser.exe"
                           : !strcmp(targets[t], "server") ? L"opccomn_test_server.exe"
                                                           : L"opccomn_example_server.exe";
        for (i = 0; i < 300 && process_running(exe) != 0; i++) Sleep(100);
        CHECK(process_running(exe) == 0);
    }
    if (with_browser) CHECK(browser(L"/UnregServer") == 0);
    if (with_server) CHECK_HR(OpcUnregisterServer(&server, NULL), S_OK);
    CHECK_HR(OpcUnregisterProxyStub(NULL), S_OK);
    CoUninitialize();
    return test_summary("test_reconnect");
}
