/* Registration of opccomn's proxy/stub under Wine's real registry and regsvr32, next to a
 * Foundation-style opccomn_ps.dll (the stand-in opccomn_widl_ps.dll, which registers itself through
 * rpcrt4's NdrDllRegisterProxy as MIDL proxy DLLs do):
 *   - plain `regsvr32 opccomn.dll` registers no proxy/stub;
 *   - `regsvr32 /n /i:ProxyStub opccomn.dll` leaves the installed proxy/stub's interfaces alone,
 *     `/i:ProxyStub,TakeOver` takes them over, `/u /n /i:ProxyStub` gives them back exactly;
 *   - with opccomn registered first and opccomn_ps.dll installed later, unregistering opccomn leaves
 *     opccomn_ps.dll's registration intact;
 *   - `/i:ProxyStub,DA` registers the Data Access interfaces alone, `/i:ProxyStub,Common` adds OPC
 *     Common's, `/u /n /i:ProxyStub,DA` takes back Data Access's and keeps the rest registered;
 *   - an unknown /i: command fails. */
#include "oop.h"

static WCHAR dir[MAX_PATH];
static const WCHAR *const OUR_CLSID = L"{3D738B71-0B9D-4337-A725-E8541A96D1C9}";
static const WCHAR *const THEIR_CLSID = L"{13486D50-4821-11D2-A494-3CB306C10000}";

static DWORD regsvr32(const WCHAR *options, const WCHAR *dll) {
    WCHAR cmd[1200];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    DWORD code = 999;
    swprintf(cmd, 1200, L"regsvr32.exe /s %ls \"%ls\\%ls\"", options, dir, dll);
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    if (!CreateProcessW(NULL, cmd, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi)) return 998;
    WaitForSingleObject(pi.hProcess, 60000);
    GetExitCodeProcess(pi.hProcess, &code);
    CloseHandle(pi.hProcess);
    CloseHandle(pi.hThread);
    return code;
}

/* The ProxyStubClsid32 of interface i, or "" when missing (static buffer). */
static const WCHAR *proxy_stub_of(int i) {
    static WCHAR data[64];
    WCHAR key[96], guid[40];
    DWORD size = sizeof data;
    StringFromGUID2(OOP_IIDS[i], guid, 40);
    swprintf(key, 96, L"Interface\\%ls\\ProxyStubClsid32", guid);
    data[0] = 0;
    if (RegGetValueW(HKEY_CLASSES_ROOT, key, NULL, RRF_RT_REG_SZ, NULL, data, &size) != ERROR_SUCCESS) data[0] = 0;
    return data;
}

static int all_are(const WCHAR *clsid) {
    int i, ok = 1;
    for (i = 0; i < 5; i++) ok &= _wcsicmp(proxy_stub_of(i), clsid) == 0;
    return ok;
}

/* Some of the 19 Data Access interfaces: IOPCServer, IOPCDataCallback (the callback), IOPCSyncIO2
 * (a derived one) and IOPCGroupStateMgt2 (the last). */
static const WCHAR *const DA_SOME[] = {L"{39C13A4D-011E-11D0-9675-0020AFD8ADB3}", L"{39C13A70-011E-11D0-9675-0020AFD8ADB3}",
                                       L"{730F5F0F-55B1-4C81-9E18-FF8A0904E1FA}", L"{8E368666-D72E-4F78-87ED-647611C61C9F}"};

static int da_are(const WCHAR *clsid) {
    static WCHAR data[64];
    WCHAR key[96];
    int i, ok = 1;
    for (i = 0; i < 4; i++) {
        DWORD size = sizeof data;
        swprintf(key, 96, L"Interface\\%ls\\ProxyStubClsid32", DA_SOME[i]);
        data[0] = 0;
        if (RegGetValueW(HKEY_CLASSES_ROOT, key, NULL, RRF_RT_REG_SZ, NULL, data, &size) != ERROR_SUCCESS) data[0] = 0;
        ok &= _wcsicmp(data, clsid) == 0;
    }
    return ok;
}

static int key_exists(const WCHAR *key) {
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_READ, &h) != ERROR_SUCCESS) return 0;
    RegCloseKey(h);
    return 1;
}

/* The .reg text of the five Interface keys and both proxy/stub classes (for "exactly as before"). */
static LPWSTR snapshot(OpcRegistry *sys) {
    static const WCHAR *const keys[] = {
        L"Interface\\{F31DFDE1-07B6-11D2-B2D8-0060083BA1FB}", L"Interface\\{F31DFDE2-07B6-11D2-B2D8-0060083BA1FB}",
        L"Interface\\{13486D50-4821-11D2-A494-3CB306C10000}", L"Interface\\{9DD0B56C-AD9E-43EE-8305-487F3188BF7A}",
        L"Interface\\{55C382C8-21C7-4E88-96C1-BECFB1E3F483}", L"CLSID\\{13486D50-4821-11D2-A494-3CB306C10000}",
        L"CLSID\\{3D738B71-0B9D-4337-A725-E8541A96D1C9}"};
    return registry_snapshot(sys, keys, sizeof keys / sizeof keys[0]);
}

int main(void) {
    OpcRegistry *sys = NULL;
    WCHAR our_class[64];
    LPWSTR before, after;
    WCHAR *slash;
    GetModuleFileNameW(NULL, dir, MAX_PATH);
    slash = wcsrchr(dir, L'\\');
    if (slash) *slash = 0;
    swprintf(our_class, 64, L"CLSID\\%ls", OUR_CLSID);
    CHECK_HR(OpcRegistryOpenSystem(&sys), S_OK);
    /* Start clean, whatever an interrupted earlier run left. */
    regsvr32(L"/u /n /i:ProxyStub", L"opccomn.dll");
    if (!all_are(L"")) regsvr32(L"/u", L"opccomn_widl_ps.dll");
    CHECK(all_are(L""));
    CHECK(da_are(L""));

    /* Plain regsvr32 registers the server list only. */
    CHECK(regsvr32(L"", L"opccomn.dll") == 0);
    CHECK(all_are(L""));
    CHECK(!key_exists(our_class));
    CHECK(regsvr32(L"/u", L"opccomn.dll") == 0);

    /* opccomn_ps.dll installed: opccomn keeps off its interfaces unless asked to take over. */
    CHECK(regsvr32(L"", L"opccomn_widl_ps.dll") == 0);
    CHECK(all_are(THEIR_CLSID));
    before = snapshot(sys);
    CHECK(regsvr32(L"/n /i:ProxyStub", L"opccomn.dll") == 0);
    CHECK(all_are(THEIR_CLSID));
    CHECK(key_exists(our_class));
    CHECK(regsvr32(L"/n /i:ProxyStub,TakeOver", L"opccomn.dll") == 0);
    CHECK(all_are(OUR_CLSID));
    CHECK(regsvr32(L"/u /n /i:ProxyStub", L"opccomn.dll") == 0);
    CHECK(all_are(THEIR_CLSID));
    after = snapshot(sys);
    CHECK(wsame(before, after));
    if (!wsame(before, after)) {
        fputs("  before: ", stderr);
        wprint(stderr, before);
        fputs("\n  after: ", stderr);
        wprint(stderr, after);
        fputc('\n', stderr);
    }
    free(before);
    free(after);
    CHECK(!key_exists(our_class));
    CHECK(regsvr32(L"/u", L"opccomn_widl_ps.dll") == 0);
    CHECK(all_are(L""));

    /* opccomn first, opccomn_ps.dll later: unregistering opccomn leaves opccomn_ps.dll's entries. */
    CHECK(regsvr32(L"/n /i:ProxyStub", L"opccomn.dll") == 0);
    CHECK(all_are(OUR_CLSID));
    CHECK(regsvr32(L"", L"opccomn_widl_ps.dll") == 0);
    CHECK(all_are(THEIR_CLSID));
    before = snapshot(sys);
    CHECK(regsvr32(L"/u /n /i:ProxyStub", L"opccomn.dll") == 0);
    after = snapshot(sys);
    CHECK(all_are(THEIR_CLSID));
    /* Only our class key went away. */
    CHECK(!key_exists(our_class));
    CHECK(wcslen(after) < wcslen(before) && wcsstr(before, L"PSFactoryBuffer") != NULL);
    free(before);
    free(after);
    CHECK(regsvr32(L"/u", L"opccomn_widl_ps.dll") == 0);
    CHECK(all_are(L""));

    /* One specification at a time. */
    CHECK(regsvr32(L"/n /i:ProxyStub,DA", L"opccomn.dll") == 0);
    CHECK(da_are(OUR_CLSID));
    CHECK(all_are(L""));
    CHECK(regsvr32(L"/n /i:ProxyStub,Common", L"opccomn.dll") == 0);
    CHECK(all_are(OUR_CLSID));
    CHECK(regsvr32(L"/u /n /i:ProxyStub,DA", L"opccomn.dll") == 0);
    CHECK(da_are(L""));
    CHECK(all_are(OUR_CLSID));
    CHECK(key_exists(our_class));
    CHECK(regsvr32(L"/u /n /i:ProxyStub", L"opccomn.dll") == 0);
    CHECK(all_are(L""));
    CHECK(!key_exists(our_class));
    /* Without a specification: all of them. */
    CHECK(regsvr32(L"/n /i:ProxyStub", L"opccomn.dll") == 0);
    CHECK(all_are(OUR_CLSID) && da_are(OUR_CLSID));
    CHECK(regsvr32(L"/u /n /i:ProxyStub", L"opccomn.dll") == 0);
    CHECK(all_are(L"") && da_are(L""));

    /* An unknown command fails and writes nothing. */
    CHECK(regsvr32(L"/n /i:Everything", L"opccomn.dll") != 0);
    CHECK(regsvr32(L"/n /i:ProxyStub,HDA3", L"opccomn.dll") != 0);
    CHECK(!key_exists(our_class));
    OpcRegistryRelease(sys);
    return test_summary("test_ps_registration");
}
