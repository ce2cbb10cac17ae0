/* A client of what an MSI package installed (scripts/test-msi.sh), using nothing of opccomn but the
 * header's interface declarations: it does not load opccomn.dll itself, so whatever opccomn code runs
 * in it is the proxy/stub COM loaded as the registry names it.
 *
 *   msi_client browse PROXY_DLL   registers a fake OPC server (this process's registry view), browses
 *                                 through CLSID_OPCServerList out of process (IOPCServerList2 and
 *                                 IOPCEnumGUID marshalled), expects the fake server and its ProgID, and
 *                                 expects the proxy/stub loaded into this process to be PROXY_DLL (a
 *                                 full path); removes the fake server and waits for the browser to
 *                                 exit (not with nowait: a second client can then reach the same
 *                                 browser; two clients activating it at once may start two under Wine)
 *   msi_client browse PROXY_DLL service
 *                                 the same with the browser registered as the service OpcComnBrowser:
 *                                 the activation started it through the service manager (the service
 *                                 is running, in an opccomn_browser.exe process), and it keeps running
 *   msi_client absent             CLSID_OPCServerList is not registered (REGDB_E_CLASSNOTREG)
 *
 * Exit code 0 when every check passed. */
#include <windows.h>
#include <tlhelp32.h>

#include "test_check.h"

/* Defined here rather than taken from opccomn.dll, which this program does not load. */
static const CLSID SERVER_LIST = {0x13486D51, 0x4821, 0x11D2, {0xA4, 0x94, 0x3C, 0xB3, 0x06, 0xC1, 0x00, 0x00}};
static const IID LIST2 = {0x9DD0B56C, 0xAD9E, 0x43EE, {0x83, 0x05, 0x48, 0x7F, 0x31, 0x88, 0xBF, 0x7A}};
static const CATID CATID_DA2 = {0x63D5F432, 0xCFE4, 0x11D1, {0xB2, 0xC8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
/* The fake server: one CLSID per bitness, so a 32-bit and a 64-bit client do not share one. */
#define FAKE_KEY_64 L"CLSID\\{C3400064-5EED-4000-8000-000000000040}"
#define FAKE_KEY_32 L"CLSID\\{C3400032-5EED-4000-8000-000000000040}"
static const CLSID FAKE_64 = {0xC3400064, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0x40}};
static const CLSID FAKE_32 = {0xC3400032, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0x40}};
#define FAKE_PROGID L"Msi.TestServer.1"

static int set_string(const WCHAR *key, const WCHAR *value) {
    HKEY h;
    WCHAR path[300];
    LONG rc;
    swprintf(path, 300, L"Software\\Classes\\%ls", key);
    if (RegCreateKeyExW(HKEY_LOCAL_MACHINE, path, 0, NULL, 0, KEY_WRITE, NULL, &h, NULL) != ERROR_SUCCESS) return 0;
    rc = RegSetValueExW(h, NULL, 0, REG_SZ, (const BYTE *)value, (DWORD)((wcslen(value) + 1) * sizeof(WCHAR)));
    RegCloseKey(h);
    return rc == ERROR_SUCCESS;
}

static void delete_tree(const WCHAR *key) {
    WCHAR path[300];
    swprintf(path, 300, L"Software\\Classes\\%ls", key);
    RegDeleteTreeW(HKEY_LOCAL_MACHINE, path);
    RegDeleteKeyW(HKEY_LOCAL_MACHINE, path);
}

/* Whether an opccomn_browser.exe process runs (pid 0), or process `pid` is one. */
static int browser_process(DWORD pid) {
    PROCESSENTRY32W e;
    int found = 0;
    HANDLE snap = CreateToolhelp32Snapshot(TH32CS_SNAPPROCESS, 0);
    if (snap == INVALID_HANDLE_VALUE) return 0;
    e.dwSize = sizeof e;
    if (Process32FirstW(snap, &e)) {
        do found |= _wcsicmp(e.szExeFile, L"opccomn_browser.exe") == 0 && (pid == 0 || e.th32ProcessID == pid);
        while (Process32NextW(snap, &e));
    }
    CloseHandle(snap);
    return found;
}

static int browser_running(void) {
    return browser_process(0);
}

/* The state of the service OpcComnBrowser (SERVICE_RUNNING...) and its process; 0 when unreadable. */
static DWORD service_state(DWORD *pid) {
    SERVICE_STATUS_PROCESS st;
    DWORD needed;
    SC_HANDLE scm = OpenSCManagerW(NULL, NULL, SC_MANAGER_CONNECT), s = NULL;
    memset(&st, 0, sizeof st);
    if (scm) s = OpenServiceW(scm, L"OpcComnBrowser", SERVICE_QUERY_STATUS);
    if (s && !QueryServiceStatusEx(s, SC_STATUS_PROCESS_INFO, (BYTE *)&st, sizeof st, &needed)) st.dwCurrentState = 0;
    if (s) CloseServiceHandle(s);
    if (scm) CloseServiceHandle(scm);
    *pid = st.dwProcessId;
    return st.dwCurrentState;
}

/* The full path of the loaded module whose file name is that of `path`, or "" (static buffer). */
static const WCHAR *loaded(const WCHAR *path) {
    static WCHAR got[MAX_PATH];
    const WCHAR *name = wcsrchr(path, L'\\');
    HMODULE m = GetModuleHandleW(name ? name + 1 : path);
    got[0] = 0;
    if (m) GetModuleFileNameW(m, got, MAX_PATH);
    return got;
}

enum { WAIT_FOR_EXIT, NO_WAIT, AS_SERVICE };

static int browse(const WCHAR *proxy_dll, int mode) {
    const int wide = sizeof(void *) == 8;
    const WCHAR *fake_key = wide ? FAKE_KEY_64 : FAKE_KEY_32;
    const CLSID *fake = wide ? &FAKE_64 : &FAKE_32;
    WCHAR key[300], clsid_text[40];
    IOPCServerList2 *list = NULL;
    IOPCEnumGUID *e = NULL;
    GUID got[64];
    ULONG n = 0, i, found = 0;
    DWORD pid = 0;
    LPOLESTR prog = NULL, user = NULL, vi = NULL;
    int k;
    StringFromGUID2(fake, clsid_text, 40);
    CHECK(set_string(fake_key, L"Msi test server"));
    swprintf(key, 300, L"%ls\\ProgID", fake_key);
    CHECK(set_string(key, FAKE_PROGID));
    swprintf(key, 300, L"%ls\\Implemented Categories\\{63D5F432-CFE4-11D1-B2C8-0060083BA1FB}", fake_key);
    CHECK(set_string(key, L""));
    CHECK(set_string(FAKE_PROGID L"\\CLSID", clsid_text));
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    CHECK_HR(CoCreateInstance(&SERVER_LIST, NULL, CLSCTX_LOCAL_SERVER, &LIST2, (void **)&list), S_OK);
    if (list) {
        CHECK(browser_running());
        if (mode == AS_SERVICE) {
            CHECK(service_state(&pid) == SERVICE_RUNNING);
            CHECK(pid != 0 && browser_process(pid));
        }
        CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, (CATID *)&CATID_DA2, 0, NULL, &e), S_OK);
        if (e) {
            CHECK_HR(e->lpVtbl->Next(e, 64, got, &n), S_FALSE);
            for (i = 0; i < n; i++) found += IsEqualGUID(&got[i], fake);
            CHECK(found == 1);
            e->lpVtbl->Release(e);
        }
        CHECK_HR(list->lpVtbl->GetClassDetails(list, fake, &prog, &user, &vi), S_OK);
        CHECK(prog && wcscmp(prog, FAKE_PROGID) == 0);
        CHECK(user && wcscmp(user, L"Msi test server") == 0);
        CoTaskMemFree(prog);
        CoTaskMemFree(user);
        CoTaskMemFree(vi);
        /* The proxy of IOPCServerList2 came from the proxy/stub the registry names. */
        CHECK(_wcsicmp(loaded(proxy_dll), proxy_dll) == 0);
        if (_wcsicmp(loaded(proxy_dll), proxy_dll) != 0)
            fprintf(stderr, "proxy/stub loaded: %ls; expected %ls\n", loaded(proxy_dll), proxy_dll);
        list->lpVtbl->Release(list);
    }
    delete_tree(FAKE_PROGID);
    delete_tree(fake_key);
    CoUninitialize();
    /* The browser exits after its last client (about 6 s): the files can go once it has. */
    if (mode == WAIT_FOR_EXIT) {
        for (k = 0; k < 300 && browser_running(); k++) Sleep(100);
        CHECK(!browser_running());
    }
    if (mode == AS_SERVICE) CHECK(service_state(&pid) == SERVICE_RUNNING); /* serves until stopped */
    return test_summary("msi_client browse");
}

static int absent(void) {
    IOPCServerList2 *list = NULL;
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    CHECK_HR(CoCreateInstance(&SERVER_LIST, NULL, CLSCTX_LOCAL_SERVER, &LIST2, (void **)&list), REGDB_E_CLASSNOTREG);
    if (list) list->lpVtbl->Release(list);
    CoUninitialize();
    return test_summary("msi_client absent");
}

int main(void) {
    int argc = 0;
    LPWSTR *argv = CommandLineToArgvW(GetCommandLineW(), &argc);
    (void)W; /* test_check.h's, unused here */
    if (argv && argc == 3 && wcscmp(argv[1], L"browse") == 0) return browse(argv[2], WAIT_FOR_EXIT);
    if (argv && argc == 4 && wcscmp(argv[1], L"browse") == 0 && wcscmp(argv[3], L"nowait") == 0)
        return browse(argv[2], NO_WAIT);
    if (argv && argc == 4 && wcscmp(argv[1], L"browse") == 0 && wcscmp(argv[3], L"service") == 0)
        return browse(argv[2], AS_SERVICE);
    if (argv && argc == 2 && wcscmp(argv[1], L"absent") == 0) return absent();
    fprintf(stderr, "usage: msi_client browse PROXY_DLL [nowait|service] | absent\n");
    return 2;
}
