/* The server browser service (service/opccomn_browser.c) under Wine: registered as LocalServer32 with
 * its AppID (hardened: PKT_INTEGRITY and the documented permissions, read back through Windows' own
 * descriptor conversion), a client in this process enumerates fake servers registered in the system registry
 * through CLSCTX_LOCAL_SERVER, the browser process exits when the client lets go (and not before: a
 * client holding only the enumerator keeps it), and next to an
 * OpcEnum-style registration it stays inactive unless told to take over, after which unregistration
 * restores OpcEnum's registration exactly.
 *
 * With an argument it is one step of the WOW64 run (scripts/test.sh, when 32-bit Wine is there): the
 * 64-bit build's `test_browser wow64-serve` registers the 64-bit browser, the 64-bit proxy/stub and
 * fakes 0..2 in the 64-bit view; the 32-bit build's `test_browser wow64-client` registers its own
 * proxy/stub and fakes 3..5 in the 32-bit view and browses through CLSCTX_LOCAL_SERVER, which only the
 * 64-bit browser serves, expecting all six; `test_browser wow64-cleanup` (64-bit) undoes the first. */
#include "oop.h"

#include <sddl.h>

static WCHAR dir[MAX_PATH];
static const CATID CATID_DA2 = {0x63D5F432, 0xCFE4, 0x11D1, {0xB2, 0xC8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
static CLSID fake(unsigned n) {
    CLSID c = {0xC3200000 + n, 0x5eed, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0x20}};
    return c;
}
#define FAKES 3
/* Fakes 0..2 are registered by the process under test; for the WOW64 run, 3..5 by a 32-bit client. */
static const WCHAR *const FAKE_PROGIDS[2 * FAKES] = {L"Oop.Browse0.1", L"Oop.Browse1.1", L"Oop.Browse2.1",
                                                     L"Oop.Browse3.1", L"Oop.Browse4.1", L"Oop.Browse5.1"};

/* Runs the browser installed in `where` with the arguments `args`; its exit code. */
static DWORD run_from(const WCHAR *where, const WCHAR *args) {
    WCHAR cmd[1200];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    DWORD code = 999;
    swprintf(cmd, 1200, L"\"%ls\\opccomn_browser.exe\" %ls", where, args);
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    if (!CreateProcessW(NULL, cmd, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi)) return 998;
    WaitForSingleObject(pi.hProcess, 60000);
    GetExitCodeProcess(pi.hProcess, &code);
    CloseHandle(pi.hProcess);
    CloseHandle(pi.hThread);
    return code;
}

static DWORD run(const WCHAR *args) { return run_from(dir, args); }

static int browser_running(void) { return process_running(L"opccomn_browser.exe"); }

/* The browser serves 5 s after its last release and pauses 1 s (the host's defaults): 20 s at most. */
static int wait_browser_gone(void) {
    int i;
    for (i = 0; i < 200; i++) {
        if (browser_running() == 0) return 1;
        Sleep(100);
    }
    return 0;
}

static OpcServerRegistration fake_registration(unsigned n, CLSID *clsid) {
    OpcServerRegistration r;
    *clsid = fake(n);
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = *clsid;
    r.prog_id = FAKE_PROGIDS[n];
    r.user_type = L"Oop browse test server";
    r.module_path = L"C:\\oop\\fake.exe";
    r.implemented_categories = &CATID_DA2;
    r.implemented_category_count = 1;
    return r;
}

/* Whether a DA 2.0 enumeration through `l2` has fake `n`. */
static int enumeration_has(IOPCServerList2 *l2, unsigned n) {
    IOPCEnumGUID *e = NULL;
    GUID got[256];
    ULONG count = 0, i;
    CLSID f = fake(n);
    int found = 0;
    CHECK_HR(l2->lpVtbl->EnumClassesOfCategories(l2, 1, (CATID *)&CATID_DA2, 0, NULL, &e), S_OK);
    if (!e) return 0;
    CHECK(SUCCEEDED(e->lpVtbl->Next(e, 256, got, &count)));
    for (i = 0; i < count; i++) found |= IsEqualGUID(&got[i], &f);
    e->lpVtbl->Release(e);
    return found;
}

/* The browser answers from its last scan of the registry while the registry reports no change: a
   server this process registers a moment before a call is in the browser's next answer, and gone
   from the one after its unregistration. */
static void registered_a_moment_before(IOPCServerList2 *l2) {
    const unsigned n = 2 * FAKES - 1; /* not registered by the other runs */
    OpcServerRegistration r;
    CLSID c;
    LPOLESTR prog = NULL, user = NULL, vi = NULL;
    int round;
    CHECK(!enumeration_has(l2, n));
    CHECK(!enumeration_has(l2, n));
    r = fake_registration(n, &c);
    for (round = 0; round < 3; round++) {
        CHECK_HR(OpcRegisterServer(&r, NULL), S_OK);
        CHECK(enumeration_has(l2, n));
        CHECK_HR(l2->lpVtbl->GetClassDetails(l2, &c, &prog, &user, &vi), S_OK);
        CHECK(prog && wcscmp(prog, FAKE_PROGIDS[n]) == 0);
        CoTaskMemFree(prog);
        CoTaskMemFree(user);
        CoTaskMemFree(vi);
        prog = user = vi = NULL;
        CHECK_HR(OpcUnregisterServer(&r, NULL), S_OK);
        CHECK(!enumeration_has(l2, n));
        CHECK_HR(l2->lpVtbl->GetClassDetails(l2, &c, &prog, &user, &vi), REGDB_E_CLASSNOTREG);
    }
}

/* Browses through the out-of-process server list: every fake server must be there. */
static void browse(void) {
    IOPCServerList2 *l2 = NULL;
    IOPCServerList *l1 = NULL;
    IOPCEnumGUID *e = NULL;
    GUID got[256];
    ULONG n = 0, i, found = 0;
    unsigned k;
    LPOLESTR prog = NULL, user = NULL, vi = NULL;
    CLSID one = fake(1);
    CHECK_HR(CoCreateInstance(&CLSID_OPCServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&l2), S_OK);
    if (!l2) return;
    CHECK(browser_running() == 1);
    CHECK_HR(l2->lpVtbl->EnumClassesOfCategories(l2, 1, (CATID *)&CATID_DA2, 0, NULL, &e), S_OK);
    if (e) {
        CHECK_HR(e->lpVtbl->Next(e, 256, got, &n), S_FALSE);
        for (k = 0; k < FAKES; k++) {
            CLSID f = fake(k);
            for (i = 0; i < n; i++) found += IsEqualGUID(&got[i], &f);
        }
        CHECK(found == FAKES);
        e->lpVtbl->Release(e);
    }
    registered_a_moment_before(l2);
    CHECK_HR(l2->lpVtbl->GetClassDetails(l2, &one, &prog, &user, &vi), S_OK);
    CHECK(wstr_is(prog, "Oop.Browse1.1") && wstr_is(user, "Oop browse test server"));
    CHECK(wstr_is(vi, "")); /* no version-independent ProgID registered: an empty string */
    CoTaskMemFree(prog);
    CoTaskMemFree(user);
    CoTaskMemFree(vi);
    CHECK_HR(l2->lpVtbl->QueryInterface(l2, &IID_IOPCServerList, (void **)&l1), S_OK);
    if (l1) {
        CLSID c;
        CHECK_HR(l1->lpVtbl->CLSIDFromProgID(l1, L"Oop.Browse2.1", &c), S_OK);
        {
            CLSID two = fake(2);
            CHECK(IsEqualGUID(&c, &two));
        }
        l1->lpVtbl->Release(l1);
    }
    l2->lpVtbl->Release(l2);
    CHECK(wait_browser_gone()); /* it exits when its last client goes */
}

/* The client's way of many OPC clients (and of the opc_da crate's get_servers): it gets the
 * enumerator, releases the server list and only then walks the enumerator. The browser must stay
 * while the client holds the enumerator (COM's rule for local servers) and exit once it lets go. */
static void walk_after_releasing_the_list(void) {
    IOPCServerList2 *l2 = NULL;
    IOPCEnumGUID *e = NULL, *clone = NULL;
    GUID got[256];
    ULONG n = 0;
    CHECK_HR(CoCreateInstance(&CLSID_OPCServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&l2), S_OK);
    if (!l2) return;
    CHECK_HR(l2->lpVtbl->EnumClassesOfCategories(l2, 1, (CATID *)&CATID_DA2, 0, NULL, &e), S_OK);
    l2->lpVtbl->Release(l2);
    if (!e) return;
    CHECK(process_stays(L"opccomn_browser.exe", 2000)); /* the enumerator keeps it */
    CHECK_HR(e->lpVtbl->Clone(e, &clone), S_OK);
    CHECK_HR(e->lpVtbl->Next(e, 256, got, &n), S_FALSE);
    CHECK(n >= FAKES);
    e->lpVtbl->Release(e);
    if (clone) { /* and so does a clone, alone */
        CHECK(process_stays(L"opccomn_browser.exe", 1000));
        n = 0;
        CHECK_HR(clone->lpVtbl->Next(clone, 256, got, &n), S_FALSE);
        CHECK(n >= FAKES);
        clone->lpVtbl->Release(clone);
    }
    CHECK(wait_browser_gone()); /* it exits when the last object goes */
}

static LPWSTR snapshot(OpcRegistry *sys) {
    static const WCHAR *const keys[] = {L"CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}",
                                        L"AppID\\{13486D44-4821-11D2-A494-3CB306C10000}", L"AppID\\OpcEnum.exe",
                                        L"OPC.ServerList.1", L"OPC.ServerList",
                                        L"AppID\\{CCD63ADF-D02D-46DD-B170-FA6E0F086FE3}",
                                        L"AppID\\opccomn_browser.exe"};
    return registry_snapshot(sys, keys, sizeof keys / sizeof keys[0]);
}

/* What the Foundation's OpcEnum.exe registers for itself. */
static const WCHAR OPCENUM_REG[] =
    L"Windows Registry Editor Version 5.00\r\n\r\n"
    L"[HKEY_CLASSES_ROOT\\CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}]\r\n@=\"OpcServerList Class\"\r\n"
    L"\"AppID\"=\"{13486D44-4821-11D2-A494-3CB306C10000}\"\r\n\r\n"
    L"[HKEY_CLASSES_ROOT\\CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}\\LocalServer32]\r\n"
    L"@=\"C:\\\\Windows\\\\System32\\\\OpcEnum.exe\"\r\n\r\n"
    L"[HKEY_CLASSES_ROOT\\CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}\\ProgID]\r\n@=\"OPC.ServerList.1\"\r\n\r\n"
    L"[HKEY_CLASSES_ROOT\\AppID\\{13486D44-4821-11D2-A494-3CB306C10000}]\r\n@=\"OpcEnum\"\r\n"
    L"\"LocalService\"=\"OpcEnum\"\r\n\r\n"
    L"[HKEY_CLASSES_ROOT\\AppID\\OpcEnum.exe]\r\n\"AppID\"=\"{13486D44-4821-11D2-A494-3CB306C10000}\"\r\n\r\n"
    L"[HKEY_CLASSES_ROOT\\OPC.ServerList.1]\r\n@=\"OpcServerList Class\"\r\n\r\n"
    L"[HKEY_CLASSES_ROOT\\OPC.ServerList.1\\CLSID]\r\n@=\"{13486D51-4821-11D2-A494-3CB306C10000}\"\r\n\r\n";

static const WCHAR OPCENUM_DELETE[] =
    L"Windows Registry Editor Version 5.00\r\n\r\n"
    L"[-HKEY_CLASSES_ROOT\\CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}]\r\n\r\n"
    L"[-HKEY_CLASSES_ROOT\\AppID\\{13486D44-4821-11D2-A494-3CB306C10000}]\r\n\r\n"
    L"[-HKEY_CLASSES_ROOT\\AppID\\OpcEnum.exe]\r\n\r\n"
    L"[-HKEY_CLASSES_ROOT\\OPC.ServerList.1]\r\n\r\n";

/* The string value `name` (NULL: default) of `key` in the system registry, or "" (static buffer). */
static const WCHAR *reg_string(OpcRegistry *sys, const WCHAR *key, const WCHAR *name) {
    static WCHAR text[600];
    LPWSTR v = NULL;
    text[0] = 0;
    if (SUCCEEDED(OpcRegistryGetString(sys, key, name, &v)) && v) {
        swprintf(text, 600, L"%ls", v);
        CoTaskMemFree(v);
    }
    return text;
}

#define BROWSER_KEY L"CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}"

/* Installed under a path with blanks and the names of switches in it: the path is no argument (a
 * browser under ...\Plant-Status\ registers, one under "OPC Tools -TakeOver" takes nothing over), and
 * LocalServer32 holds the path quoted, through which COM starts it. */
static void installed_under_an_awkward_path(OpcRegistry *sys) {
    static const WCHAR *const files[2] = {L"opccomn_browser.exe", L"opccomn.dll"};
    WCHAR top[MAX_PATH], odd[MAX_PATH], from[MAX_PATH], to[MAX_PATH], quoted[MAX_PATH + 4];
    LPWSTR before, after;
    unsigned k;
    swprintf(top, MAX_PATH, L"%ls\\OPC Tools -TakeOver", dir);
    swprintf(odd, MAX_PATH, L"%ls\\Plant-Status", top);
    CreateDirectoryW(top, NULL);
    CreateDirectoryW(odd, NULL);
    for (k = 0; k < 2; k++) {
        swprintf(from, MAX_PATH, L"%ls\\%ls", dir, files[k]);
        swprintf(to, MAX_PATH, L"%ls\\%ls", odd, files[k]);
        CHECK(CopyFileW(from, to, FALSE));
    }
    before = snapshot(sys);
    CHECK(run_from(odd, L"/RegServer") == 0);
    swprintf(quoted, MAX_PATH + 4, L"\"%ls\\opccomn_browser.exe\"", odd);
    CHECK(wcscmp(reg_string(sys, BROWSER_KEY L"\\LocalServer32", NULL), quoted) == 0);
    CHECK(run_from(odd, L"/status") == 0);
    browse();
    CHECK(run_from(odd, L"-UNREGSERVER") == 0);
    after = snapshot(sys);
    CHECK(wsame(before, after));
    free(before);
    free(after);
    /* Next to OpcEnum, without /TakeOver on the command line: nothing changes. */
    CHECK_HR(OpcRegistryApply(sys, OPCENUM_REG), S_OK);
    before = snapshot(sys);
    CHECK(run_from(odd, L"/RegServer") == 2);
    after = snapshot(sys);
    CHECK(wsame(before, after));
    free(before);
    free(after);
    CHECK_HR(OpcRegistryApply(sys, OPCENUM_DELETE), S_OK);
    for (k = 0; k < 2; k++) {
        swprintf(to, MAX_PATH, L"%ls\\%ls", odd, files[k]);
        CHECK(DeleteFileW(to));
    }
    CHECK(RemoveDirectoryW(odd));
    CHECK(RemoveDirectoryW(top));
}

/* OpcEnum installed after the browser, or re-registered after /TakeOver: /UnregServer leaves its
 * registration as OpcEnum wrote it last. */
static void opcenum_installed_later_stays(OpcRegistry *sys) {
    static const WCHAR NEWER[] =
        L"Windows Registry Editor Version 5.00\r\n\r\n"
        L"[HKEY_CLASSES_ROOT\\CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}\\LocalServer32]\r\n"
        L"@=\"\\\"D:\\\\OPC Core\\\\OpcEnum.exe\\\"\"\r\n\r\n";
    /* Browser first, OpcEnum installed over it. */
    CHECK(run(L"/RegServer") == 0);
    CHECK_HR(OpcRegistryApply(sys, OPCENUM_REG), S_OK);
    CHECK(run(L"/UnregServer") == 0);
    CHECK(wstr_is(reg_string(sys, BROWSER_KEY L"\\LocalServer32", NULL), "C:\\Windows\\System32\\OpcEnum.exe"));
    CHECK(wstr_is(reg_string(sys, BROWSER_KEY, L"AppID"), "{13486D44-4821-11D2-A494-3CB306C10000}"));
    CHECK(wstr_is(reg_string(sys, BROWSER_KEY, NULL), "OpcServerList Class"));
    CHECK(wstr_is(reg_string(sys, L"OPC.ServerList.1\\CLSID", NULL), "{13486D51-4821-11D2-A494-3CB306C10000}"));
    CHECK(wstr_is(reg_string(sys, L"OPC.ServerList.1", NULL), "OpcServerList Class"));
    CHECK(reg_string(sys, L"AppID\\opccomn_browser.exe", L"AppID")[0] == 0);
    CHECK(run(L"/Status") == 2);
    /* OpcEnum active; the browser takes over; OpcEnum re-registers at a new path; the browser leaves. */
    CHECK(run(L"/RegServer /TakeOver") == 0);
    CHECK_HR(OpcRegistryApply(sys, NEWER), S_OK);
    CHECK(run(L"/UnregServer") == 0);
    CHECK(wstr_is(reg_string(sys, BROWSER_KEY L"\\LocalServer32", NULL), "\"D:\\OPC Core\\OpcEnum.exe\""));
    CHECK(wstr_is(reg_string(sys, BROWSER_KEY, L"AppID"), "{13486D44-4821-11D2-A494-3CB306C10000}"));
    CHECK(wstr_is(reg_string(sys, L"OPC.ServerList.1\\CLSID", NULL), "{13486D51-4821-11D2-A494-3CB306C10000}"));
    CHECK_HR(OpcRegistryApply(sys, OPCENUM_DELETE), S_OK);
    /* What the browser added next to OpcEnum's (the version-independent ProgID) stays with the class;
     * it goes with the class. */
    CHECK_HR(OpcRegistryApply(sys, L"Windows Registry Editor Version 5.00\r\n\r\n[-HKEY_CLASSES_ROOT\\OPC.ServerList]\r\n"), S_OK);
}

/* ---- The WOW64 run: a 32-bit client browsing through the 64-bit service ---- */

static int clsid_key_exists(REGSAM view, const WCHAR *sub) {
    HKEY h;
    WCHAR key[128];
    swprintf(key, 128, L"CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}%ls", sub);
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_READ | view, &h) != ERROR_SUCCESS) return 0;
    RegCloseKey(h);
    return 1;
}

static int wow64_serve(int cleanup) {
    OpcServerRegistration r;
    CLSID c;
    unsigned k;
    BOOL wow = TRUE;
    CHECK(sizeof(void *) == 8);
    CHECK(IsWow64Process(GetCurrentProcess(), &wow) && !wow);
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    if (!cleanup) {
        OpcUnregisterProxyStub(NULL);
        CHECK_HR(OpcRegisterProxyStub(NULL, 0), S_OK);
        for (k = 0; k < FAKES; k++) {
            r = fake_registration(k, &c);
            CHECK_HR(OpcRegisterServer(&r, NULL), S_OK);
        }
        CHECK(run(L"/RegServer") == 0);
        CHECK(run(L"/Status") == 0);
    } else {
        CHECK(run(L"/UnregServer") == 0);
        for (k = 0; k < FAKES; k++) {
            r = fake_registration(k, &c);
            CHECK_HR(OpcUnregisterServer(&r, NULL), S_OK);
        }
        CHECK_HR(OpcUnregisterProxyStub(NULL), S_OK);
        CHECK(!clsid_key_exists(KEY_WOW64_64KEY, L""));
    }
    CoUninitialize();
    return test_summary(cleanup ? "test_browser (wow64-cleanup)" : "test_browser (wow64-serve)");
}

static int wow64_client(void) {
    OpcServerRegistration r[FAKES];
    IOPCServerList2 *l2 = NULL;
    IOPCEnumGUID *e = NULL;
    GUID got[256];
    ULONG n = 0, i;
    unsigned k, found = 0;
    BOOL wow = FALSE;
    CLSID c;
    LPOLESTR prog = NULL, user = NULL, vi = NULL;
    CHECK(sizeof(void *) == 4);
    CHECK(IsWow64Process(GetCurrentProcess(), &wow) && wow);
    /* Only the 64-bit view has the browser: whatever answers CLSCTX_LOCAL_SERVER is the 64-bit one. */
    CHECK(clsid_key_exists(KEY_WOW64_64KEY, L"\\LocalServer32"));
    CHECK(!clsid_key_exists(KEY_WOW64_32KEY, L"\\LocalServer32"));
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    OpcUnregisterProxyStub(NULL);
    CHECK_HR(OpcRegisterProxyStub(NULL, 0), S_OK); /* the 32-bit view's proxy/stub, for this side */
    for (k = 0; k < FAKES; k++) {
        r[k] = fake_registration(FAKES + k, &c);
        CHECK_HR(OpcRegisterServer(&r[k], NULL), S_OK);
    }
    CHECK_HR(CoCreateInstance(&CLSID_OPCServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&l2), S_OK);
    if (l2) {
        CHECK(browser_running() == 1);
        CHECK_HR(l2->lpVtbl->EnumClassesOfCategories(l2, 1, (CATID *)&CATID_DA2, 0, NULL, &e), S_OK);
        if (e) {
            CHECK_HR(e->lpVtbl->Next(e, 256, got, &n), S_FALSE);
            for (k = 0; k < 2 * FAKES; k++) {
                CLSID f = fake(k);
                for (i = 0; i < n; i++) found += IsEqualGUID(&got[i], &f);
            }
            CHECK(found == 2 * FAKES); /* both registry views */
            e->lpVtbl->Release(e);
        }
        for (k = 0; k < 2 * FAKES; k += FAKES + 1) { /* one of each view: 0 (64-bit), 4 (32-bit) */
            CLSID f = fake(k);
            CHECK_HR(l2->lpVtbl->GetClassDetails(l2, &f, &prog, &user, &vi), S_OK);
            CHECK(prog && wcscmp(prog, FAKE_PROGIDS[k]) == 0);
            CHECK(wstr_is(user, "Oop browse test server"));
            CoTaskMemFree(prog);
            CoTaskMemFree(user);
            CoTaskMemFree(vi);
            prog = user = vi = NULL;
        }
        l2->lpVtbl->Release(l2);
        CHECK(wait_browser_gone());
    }
    for (k = 0; k < FAKES; k++) CHECK_HR(OpcUnregisterServer(&r[k], NULL), S_OK);
    CHECK_HR(OpcUnregisterProxyStub(NULL), S_OK);
    CoUninitialize();
    return test_summary("test_browser (wow64-client)");
}

#define BROWSER_APPID_KEY L"AppID\\{CCD63ADF-D02D-46DD-B170-FA6E0F086FE3}"

/* One permission of the browser's AppID as Windows reads it back (REG_BINARY, a self-relative
 * descriptor, converted by ConvertSecurityDescriptorToStringSecurityDescriptorW). */
static void check_permission(const WCHAR *name, const char *sddl) {
    BYTE sd[1024];
    DWORD size = sizeof sd, type = 0;
    LPWSTR text = NULL;
    CHECK(RegGetValueW(HKEY_CLASSES_ROOT, BROWSER_APPID_KEY, name, RRF_RT_ANY, &type, sd, &size) == ERROR_SUCCESS);
    CHECK(type == REG_BINARY && IsValidSecurityDescriptor(sd));
    CHECK(ConvertSecurityDescriptorToStringSecurityDescriptorW(
        sd, SDDL_REVISION_1, OWNER_SECURITY_INFORMATION | GROUP_SECURITY_INFORMATION | DACL_SECURITY_INFORMATION, &text, NULL));
    CHECK(text && wstr_is(text, sddl));
    if (text && !wstr_is(text, sddl)) {
        fputs("  got: ", stderr);
        wprint(stderr, text);
        fputc('\n', stderr);
    }
    LocalFree(text);
}

/* The browser's AppID after /RegServer: PKT_INTEGRITY, and the documented permissions
 * (authenticated users and SYSTEM may call, 0x7, and launch, 0x1F; Windows writes the COM rights
 * with the directory-service letters). */
static void check_app_id(void) {
    DWORD level = 0, size = sizeof level;
    CHECK(RegGetValueW(HKEY_CLASSES_ROOT, BROWSER_APPID_KEY, L"AuthenticationLevel", RRF_RT_REG_DWORD, NULL, &level, &size) ==
              ERROR_SUCCESS &&
          level == 5);
    check_permission(L"AccessPermission", "O:BAG:BAD:(A;;CCDCLC;;;AU)(A;;CCDCLC;;;SY)");
    check_permission(L"LaunchPermission", "O:BAG:BAD:(A;;CCDCLCSWRP;;;AU)(A;;CCDCLCSWRP;;;SY)");
}

int main(int argc, char **argv) {
    OpcRegistry *sys = NULL;
    OpcServerRegistration fakes[FAKES];
    CLSID clsids[FAKES];
    LPWSTR before, after;
    WCHAR *slash;
    unsigned k;
    GetModuleFileNameW(NULL, dir, MAX_PATH);
    slash = wcsrchr(dir, L'\\');
    if (slash) *slash = 0;
    if (argc == 2 && strcmp(argv[1], "wow64-serve") == 0) return wow64_serve(0);
    if (argc == 2 && strcmp(argv[1], "wow64-cleanup") == 0) return wow64_serve(1);
    if (argc == 2 && strcmp(argv[1], "wow64-client") == 0) return wow64_client();
    if (argc != 1) {
        fprintf(stderr, "usage: test_browser [wow64-serve | wow64-client | wow64-cleanup]\n");
        return 2;
    }
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    CHECK_HR(OpcRegistryOpenSystem(&sys), S_OK);
    OpcUnregisterProxyStub(NULL); /* whatever an interrupted earlier run left */
    CHECK_HR(OpcRegisterProxyStub(NULL, 0), S_OK);
    for (k = 0; k < FAKES; k++) {
        fakes[k] = fake_registration(k, &clsids[k]);
        CHECK_HR(OpcRegisterServer(&fakes[k], NULL), S_OK);
    }

    /* Alone: /RegServer makes it the active browser; clients reach it through CLSCTX_LOCAL_SERVER. */
    before = snapshot(sys);
    CHECK(run(L"/RegServer") == 0);
    CHECK(run(L"/Status") == 0);
    check_app_id();
    browse();
    walk_after_releasing_the_list();
    CHECK(run(L"/UnregServer") == 0);
    CHECK(run(L"/Status") == 2);
    after = snapshot(sys);
    CHECK(wsame(before, after));
    free(before);
    free(after);

    /* Next to OpcEnum: inactive unless it takes over; unregistration restores OpcEnum exactly. */
    CHECK_HR(OpcRegistryApply(sys, OPCENUM_REG), S_OK);
    before = snapshot(sys);
    CHECK(run(L"/RegServer") == 2);
    after = snapshot(sys);
    CHECK(wsame(before, after));
    free(after);
    CHECK(run(L"/RegServer /TakeOver") == 0);
    CHECK(run(L"/Status") == 0);
    browse();
    CHECK(run(L"/UnregServer") == 0);
    CHECK(run(L"/Status") == 2);
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
    CHECK_HR(OpcRegistryApply(sys, OPCENUM_DELETE), S_OK);

    installed_under_an_awkward_path(sys);
    opcenum_installed_later_stays(sys);

    for (k = 0; k < FAKES; k++) CHECK_HR(OpcUnregisterServer(&fakes[k], NULL), S_OK);
    CHECK_HR(OpcUnregisterProxyStub(NULL), S_OK);
    OpcRegistryRelease(sys);
    CoUninitialize();
    return test_summary("test_browser");
}
