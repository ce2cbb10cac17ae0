/* The Windows part of test_server_list.c, run under Wine against the real COM runtime and registry:
 * regsvr32 over an OpcEnum-style registration of the same CLSID, CoCreateInstance by CLSID and by
 * ProgID, fake servers registered with the helpers (and one only in the 32-bit registry view) found
 * through IOPCServerList and IOPCServerList2 and through the system's ICatInformation (which agrees
 * with the server list on implemented and required categories), answers never staler than the
 * registry (a category entry or ProgID written a moment before, in either view or by another
 * process, is in the next answer), then everything unregistered and the registry compared with what
 * it was. */
#include <comcat.h>

static const CLSID CLSID_Fake1 = {0xC2000000, 0x5eed, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0x01}};
static const CLSID CLSID_Fake2 = {0xC2000000, 0x5eed, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0x02}};
static const CLSID CLSID_Fake3 = {0xC2000000, 0x5eed, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0x03}};
static const CLSID CLSID_Fake4 = {0xC2000000, 0x5eed, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0x04}};
#define FAKE4_KEY L"CLSID\\{C2000000-5EED-4000-8000-000000000004}"
#define LIST_KEY L"CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}"

static const CLSID CLSID_CatMgr_ = {0x0002E005, 0, 0, {0xC0, 0, 0, 0, 0, 0, 0, 0x46}};
static const IID IID_CatInformation_ = {0x0002E013, 0, 0, {0xC0, 0, 0, 0, 0, 0, 0, 0x46}};

/* The keys whose contents must be the same before and after. */
static const char *const WATCHED[] = {
    "CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}",
    "OPC.ServerList.1",
    "OPC.ServerList",
    "Component Categories\\{63D5F430-CFE4-11D1-B2C8-0060083BA1FB}",
    "Component Categories\\{63D5F432-CFE4-11D1-B2C8-0060083BA1FB}",
    "Component Categories\\{CC603642-66D7-48F1-B69A-B625E73652D7}",
    "CLSID\\{C2000000-5EED-4000-8000-000000000001}",
    "CLSID\\{C2000000-5EED-4000-8000-000000000002}",
    "CLSID\\{C2000000-5EED-4000-8000-000000000003}",
    "Fake.One.1",
    "Fake.One",
    "Fake.Two.1",
    "Fake.Three.1",
};
#define NWATCHED (sizeof WATCHED / sizeof WATCHED[0])

typedef struct {
    LPWSTR text[NWATCHED];
} Snapshot;

static void snapshot(OpcRegistry *sys, Snapshot *s) {
    size_t i;
    for (i = 0; i < NWATCHED; i++) {
        s->text[i] = NULL;
        OpcRegistryExport(sys, W(WATCHED[i]), &s->text[i]); /* NULL when the key does not exist */
    }
}

static void expect_same(const Snapshot *a, const Snapshot *b, const char *when) {
    size_t i;
    for (i = 0; i < NWATCHED; i++) {
        int same = wsame(a->text[i], b->text[i]);
        CHECK(same);
        if (!same) {
            fprintf(stderr, "  %s: %s differs\n  before: ", when, WATCHED[i]);
            wprint(stderr, a->text[i]);
            fputs("\n  after: ", stderr);
            wprint(stderr, b->text[i]);
            fputc('\n', stderr);
        }
    }
}

static void free_snapshot(Snapshot *s) {
    size_t i;
    for (i = 0; i < NWATCHED; i++) OpcTaskMemFree(s->text[i]);
}

static LONG set_sz(REGSAM view, const wchar_t *key, const wchar_t *name, const wchar_t *data) {
    HKEY h;
    LONG e = RegCreateKeyExW(HKEY_CLASSES_ROOT, key, 0, NULL, 0, KEY_WRITE | view, NULL, &h, NULL);
    if (e != ERROR_SUCCESS) return e;
    if (data) e = RegSetValueExW(h, name, 0, REG_SZ, (const BYTE *)data, (DWORD)((wcslen(data) + 1) * sizeof(wchar_t)));
    RegCloseKey(h);
    return e;
}

/* The string value, or an empty string when missing (in a static buffer). */
static const wchar_t *get_sz(const wchar_t *key, const wchar_t *name) {
    static wchar_t buf[1024];
    DWORD size = sizeof buf;
    if (RegGetValueW(HKEY_CLASSES_ROOT, key, name, RRF_RT_REG_SZ, NULL, buf, &size) != ERROR_SUCCESS) buf[0] = 0;
    return buf;
}

static int key_exists(REGSAM view, const wchar_t *key) {
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_READ | view, &h) != ERROR_SUCCESS) return 0;
    RegCloseKey(h);
    return 1;
}

/* Runs `regsvr32 /s [/u] <this library>` and returns its exit code. */
static DWORD regsvr32(const wchar_t *dll, int unregister) {
    wchar_t cmd[1200];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    DWORD code = 999;
    swprintf(cmd, 1200, L"regsvr32.exe /s %ls\"%ls\"", unregister ? L"/u " : L"", dll);
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    if (!CreateProcessW(NULL, cmd, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi)) return 998;
    WaitForSingleObject(pi.hProcess, 60000);
    GetExitCodeProcess(pi.hProcess, &code);
    CloseHandle(pi.hProcess);
    CloseHandle(pi.hThread);
    return code;
}

/* The classes an enumeration returns. */
static ULONG collect(IEnumGUID *e, CLSID *out, ULONG max) {
    ULONG n = 0, got = 0;
    while (n < max && e->lpVtbl->Next(e, 1, &out[n], &got) == S_OK && got == 1) n++;
    e->lpVtbl->Release(e);
    return n;
}

static int contains(const CLSID *list, ULONG n, const CLSID *c) {
    ULONG i;
    for (i = 0; i < n; i++)
        if (same_guid(&list[i], c)) return 1;
    return 0;
}

/* Which of the fake classes 1-3 an enumeration returns (bit n-1 for class n); releases it. */
static unsigned fake_mask(IEnumGUID *e) {
    static CLSID found[20000];
    ULONG n = e ? collect(e, found, 20000) : 0;
    return (contains(found, n, &CLSID_Fake1) ? 1u : 0u) | (contains(found, n, &CLSID_Fake2) ? 2u : 0u) |
           (contains(found, n, &CLSID_Fake3) ? 4u : 0u);
}

/* The server list and the system's ICatInformation give the same answer over the same registry, and
 * it is `want` (fake_mask bits). Both counts at least 1. */
static void cross_check(IOPCServerList *list, ICatInformation *cats, ULONG ci, CATID *impl, ULONG cr, CATID *req,
                        unsigned want) {
    IEnumGUID *e = NULL;
    unsigned ours, system;
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, ci, impl, cr, req, &e), S_OK);
    ours = fake_mask(e);
    e = NULL;
    CHECK_HR(cats->lpVtbl->EnumClassesOfCategories(cats, ci, impl, cr, req, &e), S_OK);
    system = fake_mask(e);
    CHECK(ours == want && system == want);
    if (ours != want || system != want)
        fprintf(stderr, "  categories %lu/%lu: opccomn %u, ICatInformation %u, expected %u\n", (unsigned long)ci,
                (unsigned long)cr, ours, system, want);
}

static OpcServerRegistration fake(const CLSID *clsid, uint32_t type, const wchar_t *prog, const wchar_t *vi,
                                  const wchar_t *user, const wchar_t *path) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = type;
    r.clsid = *clsid;
    r.prog_id = (LPCWSTR)prog;
    r.version_independent_prog_id = (LPCWSTR)vi;
    r.user_type = (LPCWSTR)user;
    r.module_path = (LPCWSTR)path;
    return r;
}

static void test_fake_servers(IOPCServerList *list, IOPCServerList2 *list2, OpcRegistry *sys) {
    CATID da10 = CATID_OPCDAServer10, da20 = CATID_OPCDAServer20, da30 = CATID_OPCDAServer30,
          ae = CATID_OPCAEServer10;
    OpcServerRegistration r1 = fake(&CLSID_Fake1, OPC_SERVER_TYPE_LOCAL, L"Fake.One.1", L"Fake.One", L"Fake One",
                                    L"C:\\fake\\fake1.exe");
    OpcServerRegistration r2 = fake(&CLSID_Fake2, OPC_SERVER_TYPE_INPROC, L"Fake.Two.1", NULL, L"Fake Two",
                                    L"C:\\fake\\fake2.dll");
    OpcServerRegistration r3 = fake(&CLSID_Fake3, OPC_SERVER_TYPE_LOCAL, L"Fake.Three.1", NULL, L"Fake Three",
                                    L"C:\\fake\\fake3.exe");
    CLSID found[256];
    ULONG n;
    IEnumGUID *e = NULL;
    IOPCEnumGUID *oe = NULL;
    ICatInformation *cats = NULL;
    LPOLESTR prog = NULL, user = NULL, vi = NULL;
    CLSID c;

    r1.implemented_categories = &da20;
    r1.implemented_category_count = 1;
    r2.implemented_categories = &da30;
    r2.implemented_category_count = 1;
    r2.required_categories = &ae;
    r2.required_category_count = 1;
    r2.threading_model = L"Apartment";
    r3.da10_vendor = L"Fake Vendor";
    CHECK_HR(OpcRegisterServer(&r1, NULL), S_OK);
    CHECK_HR(OpcRegisterServer(&r2, NULL), S_OK);
    CHECK_HR(OpcRegisterServer(&r3, NULL), S_OK);
    /* A server registered by its 32-bit installer only: invisible in the 64-bit view. */
    CHECK(set_sz(KEY_WOW64_32KEY, FAKE4_KEY, NULL, L"Fake Four (32-bit)") == ERROR_SUCCESS);
    CHECK(set_sz(KEY_WOW64_32KEY, FAKE4_KEY L"\\ProgID", NULL, L"Fake.Four.1") == ERROR_SUCCESS);
    CHECK(set_sz(KEY_WOW64_32KEY, FAKE4_KEY L"\\Implemented Categories\\{63D5F432-CFE4-11d1-B2C8-0060083BA1FB}", NULL,
                 NULL) == ERROR_SUCCESS);
    CHECK(key_exists(KEY_WOW64_32KEY, FAKE4_KEY) && !key_exists(KEY_WOW64_64KEY, FAKE4_KEY));

    CHECK(wcscmp(get_sz(L"Fake.One\\CurVer", NULL), L"Fake.One.1") == 0);
    CHECK(wcscmp(get_sz(L"Fake.Three.1\\OPC\\Vendor", NULL), L"Fake Vendor") == 0);
    CHECK(wcscmp(get_sz(L"CLSID\\{C2000000-5EED-4000-8000-000000000002}\\InprocServer32", L"ThreadingModel"),
                 L"Apartment") == 0);

    /* The system's Component Categories Manager sees the registration (it went through ICatRegister). */
    CHECK_HR(CoCreateInstance(&CLSID_CatMgr_, NULL, CLSCTX_INPROC_SERVER, &IID_CatInformation_, (void **)&cats), S_OK);
    if (cats) {
        CHECK_HR(cats->lpVtbl->EnumClassesOfCategories(cats, 1, &da20, (ULONG)-1, NULL, &e), S_OK);
        n = e ? collect(e, found, 256) : 0;
        CHECK(contains(found, n, &CLSID_Fake1));
        /* Required categories as COM defines them: rgcatidReq is what the caller supports, and a
           class qualifies when everything it requires is listed (Fake2 requires A&E). One implemented
           category per call: Wine's ICatInformation answers nothing for our classes when given
           several (the server list answers any of them, as Windows documents; tested above and on
           Linux). */
        {
            CATID two[2];
            two[0] = da20;
            two[1] = ae;
            cross_check(list, cats, 1, &da20, 1, &da20, 1u); /* what OPC clients call */
            cross_check(list, cats, 1, &da30, 1, &da20, 0u); /* Fake2's A&E is not supported */
            cross_check(list, cats, 1, &da30, 1, &ae, 2u);
            cross_check(list, cats, 1, &da30, 2, two, 2u);
            cross_check(list, cats, 1, &da20, 2, two, 1u);
            cross_check(list, cats, 1, &ae, 1, &ae, 0u); /* no fake implements A&E */
            /* No required list: the specification's 0 means regardless of required categories, and
               the server list takes -1 as 0. ICatInformation's -1 (and 0) means "supports none",
               which only classes requiring nothing meet. */
            e = NULL;
            CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, &da30, 0, NULL, &e), S_OK);
            CHECK(fake_mask(e) == 2u);
            e = NULL;
            CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, &da30, (ULONG)-1, NULL, &e), S_OK);
            CHECK(fake_mask(e) == 2u);
            e = NULL;
            CHECK_HR(cats->lpVtbl->EnumClassesOfCategories(cats, 1, &da30, (ULONG)-1, NULL, &e), S_OK);
            CHECK(fake_mask(e) == 0u);
            e = NULL;
            CHECK_HR(cats->lpVtbl->EnumClassesOfCategories(cats, 1, &da20, (ULONG)-1, NULL, &e), S_OK);
            CHECK(fake_mask(e) == 1u);
        }
    }

    /* IOPCServerList: DA 2.0 finds the 64-bit and the 32-bit-only server, not the others. */
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, &da20, 0, NULL, &e), S_OK);
    n = collect(e, found, 256);
    CHECK(contains(found, n, &CLSID_Fake1) && contains(found, n, &CLSID_Fake4));
    CHECK(!contains(found, n, &CLSID_Fake2) && !contains(found, n, &CLSID_Fake3));
    /* IOPCServerList2: DA 3.0 requiring A&E; DA 1.0 the old way. */
    CHECK_HR(list2->lpVtbl->EnumClassesOfCategories(list2, 1, &da30, 1, &ae, &oe), S_OK);
    n = collect((IEnumGUID *)oe, found, 256);
    CHECK(n == 1 && contains(found, n, &CLSID_Fake2));
    CHECK_HR(list2->lpVtbl->EnumClassesOfCategories(list2, 1, &da10, 0, NULL, &oe), S_OK);
    n = collect((IEnumGUID *)oe, found, 256);
    CHECK(n == 1 && contains(found, n, &CLSID_Fake3));
    /* 0 = any category: every class of the machine, ours among them, each once. */
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 0, NULL, 0, NULL, &e), S_OK);
    {
        static CLSID all[20000];
        ULONG i, m = collect(e, all, 20000);
        int sorted_unique = 1;
        CHECK(m > 100 && contains(all, m, &CLSID_Fake3) && contains(all, m, &CLSID_Fake4));
        for (i = 1; i < m; i++)
            if (memcmp(&all[i - 1], &all[i], sizeof(CLSID)) == 0) sorted_unique = 0;
        CHECK(sorted_unique);
    }

    CHECK_HR(list2->lpVtbl->GetClassDetails(list2, &CLSID_Fake1, &prog, &user, &vi), S_OK);
    CHECK(wstr_is(prog, "Fake.One.1") && wstr_is(user, "Fake One") && wstr_is(vi, "Fake.One"));
    CoTaskMemFree(prog);
    CoTaskMemFree(user);
    CoTaskMemFree(vi);
    CHECK_HR(list->lpVtbl->GetClassDetails(list, &CLSID_Fake4, &prog, &user), S_OK);
    CHECK(wstr_is(prog, "Fake.Four.1") && wstr_is(user, "Fake Four (32-bit)"));
    CoTaskMemFree(prog);
    CoTaskMemFree(user);
    CHECK_HR(list2->lpVtbl->CLSIDFromProgID(list2, L"Fake.Two.1", &c), S_OK);
    CHECK(same_guid(&c, &CLSID_Fake2));

    /* Unregistration. */
    CHECK_HR(OpcUnregisterServer(&r1, NULL), S_OK);
    CHECK_HR(OpcUnregisterServer(&r2, NULL), S_OK);
    CHECK_HR(OpcUnregisterServer(&r3, NULL), S_OK);
    RegDeleteTreeW(HKEY_CLASSES_ROOT, L"WOW6432Node\\" FAKE4_KEY);
    RegDeleteKeyExW(HKEY_CLASSES_ROOT, FAKE4_KEY L"\\Implemented Categories\\{63D5F432-CFE4-11d1-B2C8-0060083BA1FB}",
                    KEY_WOW64_32KEY, 0);
    RegDeleteKeyExW(HKEY_CLASSES_ROOT, FAKE4_KEY L"\\Implemented Categories", KEY_WOW64_32KEY, 0);
    RegDeleteKeyExW(HKEY_CLASSES_ROOT, FAKE4_KEY L"\\ProgID", KEY_WOW64_32KEY, 0);
    RegDeleteKeyExW(HKEY_CLASSES_ROOT, FAKE4_KEY, KEY_WOW64_32KEY, 0);
    CHECK(!key_exists(KEY_WOW64_32KEY, FAKE4_KEY));
    CHECK(!key_exists(0, L"CLSID\\{C2000000-5EED-4000-8000-000000000001}") && !key_exists(0, L"Fake.One.1"));
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, &da20, 0, NULL, &e), S_OK);
    n = collect(e, found, 256);
    CHECK(!contains(found, n, &CLSID_Fake1) && !contains(found, n, &CLSID_Fake4));
    if (cats) {
        CHECK_HR(cats->lpVtbl->EnumClassesOfCategories(cats, 1, &da20, (ULONG)-1, NULL, &e), S_OK);
        n = e ? collect(e, found, 256) : 0;
        CHECK(!contains(found, n, &CLSID_Fake1));
        cats->lpVtbl->Release(cats);
    }
    (void)sys;
}

/* Runs `cmd` (a command line) in another process; its exit code. */
static DWORD run_command(const wchar_t *cmd) {
    wchar_t line[1200];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    DWORD code = 999;
    swprintf(line, 1200, L"%ls", cmd);
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    if (!CreateProcessW(NULL, line, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi)) return 998;
    WaitForSingleObject(pi.hProcess, 60000);
    GetExitCodeProcess(pi.hProcess, &code);
    CloseHandle(pi.hProcess);
    CloseHandle(pi.hThread);
    return code;
}

/* Whether a DA 2.0 enumeration has `c` (and the enumerator is released). */
static int da20_has(IOPCServerList *list, const CLSID *c) {
    static CLSID all[20000];
    CATID da20 = CATID_OPCDAServer20;
    IEnumGUID *e = NULL;
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, &da20, 0, NULL, &e), S_OK);
    return e ? contains(all, collect(e, all, 20000), c) : 0;
}

#define FAKE5_KEY L"CLSID\\{C2000000-5EED-4000-8000-000000000005}"
#define FAKE5_DA20 FAKE5_KEY L"\\Implemented Categories\\{63D5F432-CFE4-11d1-B2C8-0060083BA1FB}"

/* The server list keeps its last scan of the registry while the registry reports no change: a
   category entry written a moment before an enumeration is in it, by this process in either view or
   by another process, and so is its removal; GetClassDetails sees a ProgID written a moment before. */
static void test_no_stale_answers(IOPCServerList *list, IOPCServerList2 *list2) {
    static const CLSID fake5 = {0xC2000000, 0x5eed, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0x05}};
    static const REGSAM views[2] = {KEY_WOW64_32KEY, KEY_WOW64_64KEY};
    LPOLESTR prog = NULL, user = NULL, vi = NULL;
    int round, v;
    for (v = 0; v < 2; v++) { /* what an interrupted earlier run left */
        HKEY h;
        if (RegOpenKeyExW(HKEY_CLASSES_ROOT, FAKE5_KEY, 0, KEY_ALL_ACCESS | views[v], &h) == ERROR_SUCCESS) {
            RegDeleteTreeW(h, NULL);
            RegCloseKey(h);
            RegDeleteKeyExW(HKEY_CLASSES_ROOT, FAKE5_KEY, views[v], 0);
        }
    }
    CHECK(!da20_has(list, &fake5)); /* the scan the next calls are served from */
    CHECK(!da20_has(list, &fake5));
    for (round = 0; round < 3; round++) {
        for (v = 0; v < 2; v++) {
            CHECK(set_sz(views[v], FAKE5_DA20, NULL, NULL) == ERROR_SUCCESS);
            CHECK(da20_has(list, &fake5));
            CHECK(da20_has(list, &fake5));
            CHECK_HR(list2->lpVtbl->GetClassDetails(list2, &fake5, &prog, &user, &vi), REGDB_E_KEYMISSING);
            CHECK(set_sz(views[v], FAKE5_KEY L"\\ProgID", NULL, L"Fake.Five.1") == ERROR_SUCCESS);
            CHECK_HR(list2->lpVtbl->GetClassDetails(list2, &fake5, &prog, &user, &vi), S_OK);
            CHECK(wstr_is(prog, "Fake.Five.1"));
            CoTaskMemFree(prog);
            CoTaskMemFree(user);
            CoTaskMemFree(vi);
            CHECK(set_sz(views[v], FAKE5_KEY L"\\ProgID", NULL, L"Fake.Five.2") == ERROR_SUCCESS);
            CHECK_HR(list2->lpVtbl->GetClassDetails(list2, &fake5, &prog, &user, &vi), S_OK);
            CHECK(wstr_is(prog, "Fake.Five.2"));
            CoTaskMemFree(prog);
            CoTaskMemFree(user);
            CoTaskMemFree(vi);
            {
                HKEY h;
                LONG e = RegOpenKeyExW(HKEY_CLASSES_ROOT, FAKE5_KEY, 0, KEY_ALL_ACCESS | views[v], &h);
                CHECK(e == ERROR_SUCCESS);
                if (e == ERROR_SUCCESS) {
                    CHECK(RegDeleteTreeW(h, NULL) == ERROR_SUCCESS); /* the class key's subkeys */
                    RegCloseKey(h);
                }
            }
            CHECK(RegDeleteKeyExW(HKEY_CLASSES_ROOT, FAKE5_KEY, views[v], 0) == ERROR_SUCCESS);
            CHECK(!da20_has(list, &fake5));
            CHECK_HR(list2->lpVtbl->GetClassDetails(list2, &fake5, &prog, &user, &vi), REGDB_E_CLASSNOTREG);
        }
    }
    /* Written and removed by another process (reg.exe). */
    CHECK(run_command(L"reg.exe add \"HKCR\\" FAKE5_DA20 L"\" /f") == 0);
    CHECK(da20_has(list, &fake5));
    CHECK(run_command(L"reg.exe delete \"HKCR\\" FAKE5_KEY L"\" /f") == 0);
    CHECK(!da20_has(list, &fake5));
}

static void test_com_activation(void) {
    wchar_t dll[MAX_PATH];
    OpcRegistry *sys = NULL;
    Snapshot pristine, before, registered, after;
    IOPCServerList *list = NULL;
    IOPCServerList2 *list2 = NULL;
    CLSID c;
    HRESULT hr;

    GetModuleFileNameW(GetModuleHandleW(L"opccomn.dll"), dll, MAX_PATH);
    CHECK_HR(CoInitializeEx(NULL, COINIT_APARTMENTTHREADED), S_OK);
    CHECK_HR(OpcRegistryOpenSystem(&sys), S_OK);
    /* Component categories are shared machine state: registering a server creates them, unregistering
       leaves them. Create the ones the fake servers use first, so that the comparisons below do not
       depend on whether an earlier program (of this bitness's registry view) already did. */
    {
        const CATID *used[] = {&CATID_OPCDAServer10, &CATID_OPCDAServer20, &CATID_OPCDAServer30};
        size_t i;
        for (i = 0; i < sizeof used / sizeof used[0]; i++) CHECK_HR(OpcCreateComponentCategory(sys, used[i], NULL), S_OK);
    }
    snapshot(sys, &pristine);

    /* OpcEnum as the OPC Foundation installs it: an EXE server under the same CLSID. */
    CHECK(set_sz(0, LIST_KEY, NULL, L"OpcServerList Class") == ERROR_SUCCESS);
    CHECK(set_sz(0, LIST_KEY, L"AppID", L"{13486D51-4821-11D2-A494-3CB306C10000}") == ERROR_SUCCESS);
    CHECK(set_sz(0, LIST_KEY L"\\LocalServer32", NULL, L"C:\\windows\\system32\\OpcEnum.exe") == ERROR_SUCCESS);
    CHECK(set_sz(0, LIST_KEY L"\\ProgID", NULL, L"OPC.ServerList.1") == ERROR_SUCCESS);
    CHECK(set_sz(0, L"OPC.ServerList.1", NULL, L"OpcServerList Class") == ERROR_SUCCESS);
    CHECK(set_sz(0, L"OPC.ServerList.1\\CLSID", NULL, L"{13486D51-4821-11D2-A494-3CB306C10000}") == ERROR_SUCCESS);
    snapshot(sys, &before);

    CHECK(regsvr32(dll, 0) == 0);
    snapshot(sys, &registered);
    /* regsvr32 writes the registry view of the DLL's bitness: a 32-bit DLL on 64-bit Windows lands in
       the 32-bit view (HKCR\WOW6432Node\CLSID as the 64-bit view names it), a 64-bit DLL in the 64-bit
       view. Neither touches the other view. */
    if (sizeof(void *) == 4) {
        CHECK(key_exists(KEY_WOW64_32KEY, LIST_KEY L"\\InprocServer32"));
        CHECK(!key_exists(KEY_WOW64_64KEY, LIST_KEY L"\\InprocServer32"));
        CHECK(key_exists(KEY_WOW64_64KEY, L"WOW6432Node\\" LIST_KEY L"\\InprocServer32"));
    } else {
        CHECK(key_exists(KEY_WOW64_64KEY, LIST_KEY L"\\InprocServer32"));
        CHECK(!key_exists(KEY_WOW64_32KEY, LIST_KEY L"\\InprocServer32"));
    }
    CHECK(wcsicmp(get_sz(LIST_KEY L"\\InprocServer32", NULL), dll) == 0);
    CHECK(wcscmp(get_sz(LIST_KEY L"\\InprocServer32", L"ThreadingModel"), L"Both") == 0);
    CHECK(wcscmp(get_sz(LIST_KEY L"\\LocalServer32", NULL), L"C:\\windows\\system32\\OpcEnum.exe") == 0);
    CHECK(wcscmp(get_sz(LIST_KEY, NULL), L"OpcServerList Class") == 0); /* OpcEnum's description kept */
    CHECK(wcscmp(get_sz(L"OPC.ServerList\\CurVer", NULL), L"OPC.ServerList.1") == 0);

    /* By CLSID, as every OPC client does. */
    hr = CoCreateInstance(&CLSID_OPCServerList, NULL, CLSCTX_INPROC_SERVER, &IID_IOPCServerList, (void **)&list);
    CHECK_HR(hr, S_OK);
    /* By ProgID, version-dependent and version-independent. */
    CHECK_HR(CLSIDFromProgID(L"OPC.ServerList.1", &c), S_OK);
    CHECK(same_guid(&c, &CLSID_OPCServerList));
    CHECK_HR(CLSIDFromProgID(L"OPC.ServerList", &c), S_OK);
    CHECK(same_guid(&c, &CLSID_OPCServerList));
    hr = CoCreateInstance(&c, NULL, CLSCTX_ALL, &IID_IOPCServerList2, (void **)&list2);
    CHECK_HR(hr, S_OK);

    if (list && list2) test_fake_servers(list, list2, sys);
    if (list && list2) test_no_stale_answers(list, list2);
    if (list) list->lpVtbl->Release(list);
    if (list2) list2->lpVtbl->Release(list2);
    CoFreeUnusedLibraries();
    CoUninitialize();

    CHECK(regsvr32(dll, 1) == 0);
    snapshot(sys, &after);
    expect_same(&before, &after, "after regsvr32 /u");
    CHECK(wcscmp(get_sz(LIST_KEY L"\\LocalServer32", NULL), L"C:\\windows\\system32\\OpcEnum.exe") == 0);
    CHECK(!key_exists(0, LIST_KEY L"\\InprocServer32"));

    /* Without OpcEnum: regsvr32 and regsvr32 /u leave nothing behind. */
    RegDeleteTreeW(HKEY_CLASSES_ROOT, LIST_KEY);
    RegDeleteTreeW(HKEY_CLASSES_ROOT, L"OPC.ServerList.1");
    free_snapshot(&after);
    snapshot(sys, &after);
    expect_same(&pristine, &after, "after removing the OpcEnum keys");
    CHECK(regsvr32(dll, 0) == 0);
    CHECK(key_exists(0, LIST_KEY L"\\InprocServer32") && key_exists(0, L"OPC.ServerList.1\\CLSID"));
    CHECK(wcscmp(get_sz(LIST_KEY, NULL), L"Opc ServerList Class") == 0);
    CHECK(regsvr32(dll, 1) == 0);
    free_snapshot(&after);
    snapshot(sys, &after);
    expect_same(&pristine, &after, "after regsvr32 and regsvr32 /u");

    /* OpcEnum installed after opccomn: regsvr32 /u takes back only InprocServer32, and OpcEnum's
       registration (which shares the class key and the ProgIDs) keeps working. */
    CHECK(regsvr32(dll, 0) == 0);
    CHECK(set_sz(0, LIST_KEY L"\\LocalServer32", NULL, L"C:\\windows\\system32\\OpcEnum.exe") == ERROR_SUCCESS);
    CHECK(regsvr32(dll, 1) == 0);
    CHECK(!key_exists(0, LIST_KEY L"\\InprocServer32"));
    CHECK(wcscmp(get_sz(LIST_KEY L"\\LocalServer32", NULL), L"C:\\windows\\system32\\OpcEnum.exe") == 0);
    CHECK(wcscmp(get_sz(L"OPC.ServerList.1\\CLSID", NULL), L"{13486D51-4821-11D2-A494-3CB306C10000}") == 0);
    CHECK(wcscmp(get_sz(LIST_KEY L"\\ProgID", NULL), L"OPC.ServerList.1") == 0);
    RegDeleteTreeW(HKEY_CLASSES_ROOT, LIST_KEY);
    RegDeleteTreeW(HKEY_CLASSES_ROOT, L"OPC.ServerList.1");
    RegDeleteTreeW(HKEY_CLASSES_ROOT, L"OPC.ServerList");
    free_snapshot(&after);
    snapshot(sys, &after);
    expect_same(&pristine, &after, "after removing OpcEnum installed later");

    free_snapshot(&pristine);
    free_snapshot(&before);
    free_snapshot(&registered);
    free_snapshot(&after);
    OpcRegistryRelease(sys);
}
