/* The cross-process benchmark (benches/cross_process_bench.c) leaves a machine's proxy/stub
 * registration as it found it, after a run to its end and after a run that stalls. Installed before
 * each run, as on a machine with OPC software: the Foundation's opccomn_ps.dll (the stand-in
 * opccomn_widl_ps.dll, registered as MIDL proxy DLLs register themselves) for the five interfaces,
 * and opccomn's proxy/stub registered beside it (OpcRegisterProxyStub, what
 * `regsvr32 /n /i:ProxyStub opccomn.dll` does). Then:
 *   - a short run (3 rounds): the five Interface keys and both proxy/stub classes exactly as before,
 *     none of the benchmark's classes left, the GOAL lines printed;
 *   - a run whose second round stalls (--simulate-stall 2, a batch limit of 3 s): exit code 3, the
 *     stall named, the figures of the one complete round marked partial, the registration exactly as
 *     before, none of its classes left, and its servers ended (a client that died leaves a server
 *     waiting for ever otherwise). */
#include "oop.h"

static WCHAR dir[MAX_PATH];

/* The .reg text of the five Interface keys and both proxy/stub classes. */
static LPWSTR snapshot(OpcRegistry *sys) {
    static const WCHAR *const keys[] = {
        L"Interface\\{F31DFDE1-07B6-11D2-B2D8-0060083BA1FB}", L"Interface\\{F31DFDE2-07B6-11D2-B2D8-0060083BA1FB}",
        L"Interface\\{13486D50-4821-11D2-A494-3CB306C10000}", L"Interface\\{9DD0B56C-AD9E-43EE-8305-487F3188BF7A}",
        L"Interface\\{55C382C8-21C7-4E88-96C1-BECFB1E3F483}", L"CLSID\\{13486D50-4821-11D2-A494-3CB306C10000}",
        L"CLSID\\{3D738B71-0B9D-4337-A725-E8541A96D1C9}"};
    return registry_snapshot(sys, keys, sizeof keys / sizeof keys[0]);
}

static int key_exists(const WCHAR *key) {
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_READ, &h) != ERROR_SUCCESS) return 0;
    RegCloseKey(h);
    return 1;
}

/* How many of the benchmark's classes (sets 1-3, server and server list) and ProgIDs are registered. */
/* The stalled run's sets (see main): x64 4-6, x86 7-9; the other runs use 1-3, the reconnect test 3. */
#define STALL_SETS (sizeof(void *) == 8 ? 4u : 7u)

static int bench_keys_left(unsigned first) {
    WCHAR key[80], guid[40];
    unsigned set;
    int list, left = 0;
    for (set = first; set < first + 3; set++)
        for (list = 0; list < 2; list++) {
            CLSID clsid = oop_class(set, list);
            StringFromGUID2(&clsid, guid, 40);
            swprintf(key, 80, L"CLSID\\%ls", guid);
            left += key_exists(key);
            swprintf(key, 80, L"Oop.Bench%u.%ls.1", set, list ? L"ServerList" : L"Server");
            left += key_exists(key);
        }
    return left;
}

/* Calls DllRegisterServer or DllUnregisterServer of the stand-in for the Foundation's opccomn_ps.dll. */
static HRESULT foundation_proxy_stub(int add) {
    HMODULE dll = LoadLibraryW(L"opccomn_widl_ps.dll");
    HRESULT(STDAPICALLTYPE * entry)(void);
    if (!dll) return HRESULT_FROM_WIN32(GetLastError());
    entry = (HRESULT(STDAPICALLTYPE *)(void))(void (*)(void))GetProcAddress(dll, add ? "DllRegisterServer" : "DllUnregisterServer");
    return entry ? entry() : E_NOINTERFACE;
}

/* Runs cross_process_bench.exe with `args`; its output (stdout and stderr) into `out`. Returns its exit
 * code, or 999 when it could not be started or did not end within 5 minutes (it is then ended). */
static DWORD run_bench(const WCHAR *args, char *out, size_t size) {
    WCHAR cmd[MAX_PATH + 200], log[MAX_PATH + 40];
    SECURITY_ATTRIBUTES inherit = {sizeof inherit, NULL, TRUE};
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    DWORD code = 999, got = 0;
    HANDLE file;
    swprintf(log, MAX_PATH + 40, L"%ls\\test_bench_registration.log", dir);
    swprintf(cmd, MAX_PATH + 200, L"\"%ls\\cross_process_bench.exe\" %ls", dir, args);
    file = CreateFileW(log, GENERIC_READ | GENERIC_WRITE, FILE_SHARE_READ | FILE_SHARE_WRITE, &inherit, CREATE_ALWAYS,
                       FILE_ATTRIBUTE_NORMAL, NULL);
    out[0] = 0;
    if (file == INVALID_HANDLE_VALUE) return 999;
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    si.dwFlags = STARTF_USESTDHANDLES;
    si.hStdInput = GetStdHandle(STD_INPUT_HANDLE);
    si.hStdOutput = si.hStdError = file;
    if (CreateProcessW(NULL, cmd, NULL, NULL, TRUE, 0, NULL, dir, &si, &pi)) {
        if (WaitForSingleObject(pi.hProcess, 300000) == WAIT_OBJECT_0) GetExitCodeProcess(pi.hProcess, &code);
        else TerminateProcess(pi.hProcess, 999);
        CloseHandle(pi.hProcess);
        CloseHandle(pi.hThread);
    }
    SetFilePointer(file, 0, NULL, FILE_BEGIN);
    ReadFile(file, out, (DWORD)size - 1, &got, NULL);
    out[got] = 0;
    CloseHandle(file);
    DeleteFileW(log);
    printf("cross_process_bench %ls: exit code %lu\n%s", args, (unsigned long)code, out);
    return code;
}

/* Whether the registration is exactly as `before`; prints both when not. */
static int as_before(OpcRegistry *sys, const WCHAR *before) {
    LPWSTR after = snapshot(sys);
    int same = wsame(before, after);
    if (!same) {
        fputs("  registration before the run: ", stderr);
        wprint(stderr, before);
        fputs("\n  after it: ", stderr);
        wprint(stderr, after);
        fputc('\n', stderr);
    }
    free(after);
    return same;
}

int main(void) {
    static char out[65536];
    WCHAR args[80];
    OpcRegistry *sys = NULL;
    LPWSTR before;
    WCHAR *slash;
    int waited;
    GetModuleFileNameW(NULL, dir, MAX_PATH);
    slash = wcsrchr(dir, L'\\');
    if (slash) *slash = 0;
    CHECK_HR(OpcRegistryOpenSystem(&sys), S_OK);
    /* The machine's proxy/stubs: the Foundation's for the five interfaces, opccomn's beside it. */
    CHECK_HR(foundation_proxy_stub(1), S_OK);
    CHECK_HR(OpcRegisterProxyStub(NULL, 0), S_FALSE);
    before = snapshot(sys);
    CHECK(before && wcsstr(before, L"PSFactoryBuffer") && wcsstr(before, L"{13486D50-4821-11D2-A494-3CB306C10000}"));

    /* A run to its end. */
    CHECK(run_bench(L"--rounds 3 15", out, sizeof out) <= 1); /* 1: a goal missed in so short a run */
    CHECK(strstr(out, "GOAL GetErrorString") != NULL && strstr(out, "GOAL Enum+Next(100)") != NULL);
    CHECK(strstr(out, "STALLED") == NULL && strstr(out, "no figures") == NULL);
    CHECK(as_before(sys, before));
    CHECK(bench_keys_left(1) == 0);

    /* A run that stalls in its second round. Its servers are ended, and Wine's COM keeps the class
     * registration of an ended server until the Wine session ends (later activations of those
     * CLSIDs fail with RPC_S_SERVER_UNAVAILABLE): this run uses classes of its own, other ones for each
     * architecture, which nothing else in the session activates. */
    swprintf(args, 80, L"--rounds 3 --stall-s 3 --simulate-stall 2 --sets %u 15", STALL_SETS);
    CHECK(run_bench(args, out, sizeof out) == 3);
    CHECK(strstr(out, "STALLED: round 2: the GetErrorString batch") != NULL);
    CHECK(strstr(out, "PARTIAL: the figures of 1 of the 3 rounds") != NULL);
    CHECK(strstr(out, "GOAL GetErrorString") != NULL);
    CHECK(as_before(sys, before));
    CHECK(bench_keys_left(STALL_SETS) == 0);
    /* Its three servers were ended (the first run's end by themselves once released). */
    for (waited = 0; waited < 150 && process_running(L"opccomn_test_server.exe") == 1; waited++) Sleep(100);
    CHECK(process_running(L"opccomn_test_server.exe") == 0);

    free(before);
    CHECK_HR(OpcUnregisterProxyStub(NULL), S_OK);
    CHECK_HR(foundation_proxy_stub(0), S_OK);
    OpcRegistryRelease(sys);
    return test_summary("test_bench_registration");
}
