/* Registration and the category helpers whether or not COM is initialised on the calling thread.
 *
 * Hand-written EXE servers often register before CoInitializeEx. Every function of the header that
 * registers or touches categories is called here on a thread where COM is not initialised, then on a
 * thread of the multithreaded apartment and on one of a single-threaded apartment, against the
 * system registry (under Wine: the real one, with the Component Categories Manager when COM is
 * there) and a registry held in memory: each succeeds, writes what the header says (the keys, the
 * categories with their descriptions), and its counterpart leaves the registry as it was. The
 * functions: OpcRegisterServer, OpcUnregisterServer, OpcRegistrationExport,
 * OpcCreateComponentCategory, OpcRegisterClassInCategory, OpcUnregisterClassInCategory,
 * OpcCategoryDescription, OpcModuleRegister, OpcModuleUnregister, OpcRegistryApply,
 * OpcRegisterProxyStub, OpcUnregisterProxyStub, OpcDllRegisterServer, OpcDllUnregisterServer,
 * OpcDllInstall, and OpcExeServerRun with /RegServer and /UnregServer. Off Windows there is no COM:
 * the same calls, on the main thread and on another. */
#include <stddef.h>
#include <stdint.h>

#include "test_util.h"

#ifdef _WIN32
#include <objbase.h>
#else
#include <pthread.h>
#endif

static const CLSID CLSID_Server = {0xC4000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0xA1}};
static const CLSID CLSID_Helped = {0xC4000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0xB1}};
static const CLSID APPID_Server = {0xC4000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0xAA}};
static const CATID CATID_Vendor = {0xC4000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0xCA}};
static const CATID CATID_Helper = {0xC4000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0xCB}};

#define SERVER "{C4000000-5EED-4000-8000-0000000000A1}"
#define HELPED "{C4000000-5EED-4000-8000-0000000000B1}"
#define VENDOR_CAT "{C4000000-5EED-4000-8000-0000000000CA}"
#define HELPER_CAT "{C4000000-5EED-4000-8000-0000000000CB}"
#define DA20 "{63D5F432-CFE4-11D1-B2C8-0060083BA1FB}"

/* What these calls write, and what must be as before once they are undone. */
static const char *const WATCHED[] = {
    "CLSID\\" SERVER,
    "CLSID\\" HELPED,
    "NoCom.Server.1",
    "NoCom.Server",
    "AppID\\{C4000000-5EED-4000-8000-0000000000AA}",
    "AppID\\nocom_server.exe",
    "Component Categories\\" VENDOR_CAT,
    "Component Categories\\" HELPER_CAT,
    "Component Categories\\" DA20,
    "CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}", /* the server list, OpcDllRegisterServer */
    "OPC.ServerList.1",
    "OPC.ServerList",
    "CLSID\\{3D738B71-0B9D-4337-A725-E8541A96D1C9}", /* the proxy/stub's class */
    "Interface\\{F31DFDE1-07B6-11D2-B2D8-0060083BA1FB}", /* IOPCShutdown */
};
#define NWATCHED (sizeof WATCHED / sizeof WATCHED[0])

typedef struct {
    LPWSTR text[NWATCHED];
} Snapshot;

static void snapshot(OpcRegistry *reg, Snapshot *s) {
    size_t i;
    for (i = 0; i < NWATCHED; i++) {
        s->text[i] = NULL;
        OpcRegistryExport(reg, W(WATCHED[i]), &s->text[i]); /* NULL when the key does not exist */
    }
}

static void expect_unchanged(const Snapshot *before, OpcRegistry *reg, const char *when) {
    Snapshot after;
    size_t i;
    snapshot(reg, &after);
    for (i = 0; i < NWATCHED; i++) {
        int same = wsame(before->text[i], after.text[i]);
        CHECK(same);
        if (!same) fprintf(stderr, "  %s: %s differs\n", when, WATCHED[i]);
        OpcTaskMemFree(after.text[i]);
    }
}

static void free_snapshot(Snapshot *s) {
    size_t i;
    for (i = 0; i < NWATCHED; i++) OpcTaskMemFree(s->text[i]);
}

static int key_exists(OpcRegistry *reg, const char *key) {
    LPWSTR text = NULL;
    HRESULT hr = OpcRegistryExport(reg, W(key), &text);
    OpcTaskMemFree(text);
    return hr == S_OK;
}

static int value_is(OpcRegistry *reg, const char *key, const char *name, const char *want) {
    LPWSTR got = NULL;
    HRESULT hr = OpcRegistryGetString(reg, W(key), name ? W(name) : NULL, &got);
    int same = hr == S_OK && wstr_is(got, want);
    OpcTaskMemFree(got);
    return same;
}

static WCHAR prog_id[] = {'N', 'o', 'C', 'o', 'm', '.', 'S', 'e', 'r', 'v', 'e', 'r', '.', '1', 0};
static WCHAR vi_prog_id[] = {'N', 'o', 'C', 'o', 'm', '.', 'S', 'e', 'r', 'v', 'e', 'r', 0};
static WCHAR user_type[] = {'N', 'o', ' ', 'C', 'O', 'M', ' ', 's', 'e', 'r', 'v', 'e', 'r', 0};
static WCHAR module_path[] = {'C', ':', '\\', 'V', 'e', 'n', 'd', 'o', 'r', '\\', 'n', 'o', 'c', 'o', 'm', '_',
                              's', 'e', 'r', 'v', 'e', 'r', '.', 'e', 'x', 'e', 0};
static WCHAR vendor_text[] = {'N', 'o', ' ', 'C', 'O', 'M', ' ', 's', 'e', 'r', 'v', 'e', 'r', 's', 0};
static WCHAR vendor_name[] = {'N', 'o', 'C', 'o', 'm', ' ', 'I', 'n', 'c', '.', 0};
static CATID implemented[2];
static LPCWSTR implemented_texts[2];

/* A local Data Access server with implemented and required categories, a DA 1.0 vendor and an AppID:
 * the registration that crashed without COM. */
static OpcServerRegistration server_registration(void) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = CLSID_Server;
    r.prog_id = prog_id;
    r.version_independent_prog_id = vi_prog_id;
    r.user_type = user_type;
    r.module_path = module_path;
    implemented[0] = CATID_OPCDAServer20;
    implemented[1] = CATID_Vendor;
    implemented_texts[0] = NULL; /* the standard text */
    implemented_texts[1] = vendor_text;
    r.implemented_categories = implemented;
    r.implemented_category_count = 2;
    r.implemented_category_descriptions = implemented_texts;
    r.required_categories = &CATID_Vendor;
    r.required_category_count = 1;
    r.da10_vendor = vendor_name;
    r.app_id = &APPID_Server;
    return r;
}

/* What OpcRegisterServer writes for server_registration(), categories included. */
static void expect_server_registered(OpcRegistry *reg, const char *how) {
    int ok = value_is(reg, "CLSID\\" SERVER, NULL, "No COM server") &&
             value_is(reg, "CLSID\\" SERVER "\\LocalServer32", NULL, "\"C:\\Vendor\\nocom_server.exe\"") &&
             value_is(reg, "CLSID\\" SERVER, "AppID", "{C4000000-5EED-4000-8000-0000000000AA}") &&
             key_exists(reg, "CLSID\\" SERVER "\\Implemented Categories\\" DA20) &&
             key_exists(reg, "CLSID\\" SERVER "\\Implemented Categories\\" VENDOR_CAT) &&
             key_exists(reg, "CLSID\\" SERVER "\\Required Categories\\" VENDOR_CAT) &&
             value_is(reg, "Component Categories\\" VENDOR_CAT, "409", "No COM servers") &&
             value_is(reg, "Component Categories\\" DA20, "409", "OPC Data Access Servers Version 2.0") &&
             value_is(reg, "NoCom.Server.1\\OPC\\Vendor", NULL, "NoCom Inc.") &&
             value_is(reg, "NoCom.Server\\CurVer", NULL, "NoCom.Server.1") &&
             value_is(reg, "AppID\\nocom_server.exe", "AppID", "{C4000000-5EED-4000-8000-0000000000AA}");
    CHECK(ok);
    if (!ok) fprintf(stderr, "  %s: the registration is incomplete\n", how);
}

static HRESULT OPCCOMN_CDECL create(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    (void)context;
    return OpcCommonCreate(NULL, outer, riid, ppv);
}

static OpcServerClass server_class(const OpcServerRegistration *r) {
    OpcServerClass c;
    memset(&c, 0, sizeof c);
    c.struct_size = sizeof c;
    c.clsid = &CLSID_Server;
    c.create = create;
    c.registration = r;
    return c;
}

/* Every registration and category function against `reg` (system: NULL's registry as well), on the
 * calling thread, as `how` says. */
static void every_entry_point(OpcRegistry *reg, int system, const char *how) {
    OpcServerRegistration r = server_registration();
    OpcServerClass table[1];
    Snapshot before;
    LPWSTR text = (LPWSTR)GARBAGE_PTR;
    const char *proxy_key = "Interface\\{F31DFDE1-07B6-11D2-B2D8-0060083BA1FB}\\ProxyStubClsid32";

    table[0] = server_class(&r);
    /* A category description stays while another class implements it (another product's DA 2.0
       server on this machine): create it first, so the comparisons do not depend on that. */
    CHECK_HR(OpcCreateComponentCategory(reg, &CATID_OPCDAServer20, NULL), S_OK);
    if (system) {
        /* Whatever an interrupted earlier run left. */
        OpcUnregisterServer(&r, reg);
        OpcUnregisterProxyStub(reg);
        OpcDllUnregisterServer();
    }
    snapshot(reg, &before);

    /* OpcRegisterServer / OpcUnregisterServer, with categories. */
    CHECK_HR(OpcRegisterServer(&r, reg), S_OK);
    expect_server_registered(reg, how);
    CHECK_HR(OpcRegisterServer(&r, reg), S_OK); /* again: harmless */
    CHECK_HR(OpcUnregisterServer(&r, reg), S_OK);
    CHECK(!key_exists(reg, "CLSID\\" SERVER));
    expect_unchanged(&before, reg, how);

    /* OpcModuleRegister / OpcModuleUnregister: the same registration through a class table. */
    CHECK_HR(OpcModuleRegister(table, 1, reg), S_OK);
    expect_server_registered(reg, how);
    CHECK_HR(OpcModuleUnregister(table, 1, reg), S_OK);
    expect_unchanged(&before, reg, how);

    /* The specification's category helpers. */
    CHECK_HR(OpcCreateComponentCategory(reg, &CATID_Helper, W("Helped servers")), S_OK);
    CHECK(value_is(reg, "Component Categories\\" HELPER_CAT, "409", "Helped servers"));
    CHECK_HR(OpcRegisterClassInCategory(reg, &CLSID_Helped, &CATID_Helper), S_OK);
    CHECK(key_exists(reg, "CLSID\\" HELPED "\\Implemented Categories\\" HELPER_CAT));
    CHECK_HR(OpcUnregisterClassInCategory(reg, &CLSID_Helped, &CATID_Helper), S_OK);
    CHECK(!key_exists(reg, "CLSID\\" HELPED "\\Implemented Categories\\" HELPER_CAT));
    CHECK_HR(OpcUnregisterClassInCategory(reg, &CLSID_Helped, &CATID_Helper), S_OK); /* not there: fine */
    CHECK_HR(OpcCategoryDescription(&CATID_OPCDAServer20, &text), S_OK);
    CHECK(wstr_is(text, "OPC Data Access Servers Version 2.0"));
    OpcTaskMemFree(text);
    /* OpcRegistryApply: a category registered by a .reg text, then what the helpers left (the
       description, the class's Implemented Categories key) deleted by one. */
    CHECK_HR(OpcRegistryApply(reg, W("Windows Registry Editor Version 5.00\r\n\r\n"
                                     "[HKEY_CLASSES_ROOT\\CLSID\\" HELPED "\\Implemented Categories\\" HELPER_CAT "]\r\n")),
             S_OK);
    CHECK(key_exists(reg, "CLSID\\" HELPED "\\Implemented Categories\\" HELPER_CAT));
    CHECK_HR(OpcRegistryApply(reg, W("Windows Registry Editor Version 5.00\r\n\r\n"
                                     "[-HKEY_CLASSES_ROOT\\CLSID\\" HELPED "]\r\n"
                                     "[-HKEY_CLASSES_ROOT\\Component Categories\\" HELPER_CAT "]\r\n")),
             S_OK);
    expect_unchanged(&before, reg, how);

    /* OpcRegistrationExport: the same registration as .reg text (into a registry of its own). */
    text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(OpcRegistrationExport(&r, &text), S_OK);
    CHECK(text != NULL && wlen(text) > 0);
    OpcTaskMemFree(text);

    /* The proxy/stub. */
    CHECK_HR(OpcRegisterProxyStub(reg, 0), S_OK);
    CHECK(value_is(reg, proxy_key, NULL, "{3D738B71-0B9D-4337-A725-E8541A96D1C9}"));
    CHECK_HR(OpcUnregisterProxyStub(reg), S_OK);
    expect_unchanged(&before, reg, how);

    if (system) {
        /* The library's own registrations, always in the system registry. */
        CHECK_HR(OpcDllRegisterServer(), S_OK);
        CHECK(value_is(reg, "OPC.ServerList\\CurVer", NULL, "OPC.ServerList.1"));
        CHECK(key_exists(reg, "CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}\\InprocServer32"));
        CHECK_HR(OpcDllUnregisterServer(), S_OK);
        CHECK_HR(OpcDllInstall(TRUE, W("ProxyStub")), S_OK);
        CHECK(value_is(reg, proxy_key, NULL, "{3D738B71-0B9D-4337-A725-E8541A96D1C9}"));
        CHECK_HR(OpcDllInstall(FALSE, W("ProxyStub")), S_OK);
        expect_unchanged(&before, reg, how);
    }
    free_snapshot(&before);
}

/* Both registries, on the calling thread. */
static void both_registries(const char *how) {
    OpcRegistry *memory = NULL, *system = NULL;
    char label[96];
    CHECK_HR(OpcRegistryCreateMemory(&memory), S_OK);
    CHECK_HR(OpcRegistryOpenSystem(&system), S_OK);
    snprintf(label, sizeof label, "%s, system registry", how);
    every_entry_point(system, 1, label);
    snprintf(label, sizeof label, "%s, memory registry", how);
    every_entry_point(memory, 0, label);
    OpcRegistryRelease(memory);
    OpcRegistryRelease(system);
}

/* OpcExeServerRun's /RegServer and /UnregServer (the system registry). On Windows the host initialises
 * COM itself (the multithreaded apartment) and leaves it so: run on a thread of its own, last. */
static void exe_host_registration(void) {
    OpcServerRegistration r = server_registration();
    OpcServerClass table[1];
    OpcExeServerOptions exe;
    OpcRegistry *system = NULL;
    table[0] = server_class(&r);
    memset(&exe, 0, sizeof exe);
    exe.struct_size = sizeof exe;
    exe.classes = table;
    exe.class_count = 1;
    CHECK_HR(OpcRegistryOpenSystem(&system), S_OK);
#ifdef _WIN32
    CHECK_HR(OpcExeServerRun(&exe, W("\"C:\\Vendor\\nocom_server.exe\" /RegServer")), S_OK);
    expect_server_registered(system, "OpcExeServerRun /RegServer");
    CHECK_HR(OpcExeServerRun(&exe, W("\"C:\\Vendor\\nocom_server.exe\" /UnregServer")), S_OK);
    CHECK(!key_exists(system, "CLSID\\" SERVER));
    CoUninitialize();
#else
    CHECK_HR(OpcExeServerRun(&exe, W("/RegServer")), E_NOTIMPL);
#endif
    OpcRegistryRelease(system);
}

#ifdef _WIN32
static DWORD WINAPI in_mta(void *unused) {
    (void)unused;
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    both_registries("multithreaded apartment");
    CoUninitialize();
    return 0;
}

static DWORD WINAPI exe_host_thread(void *unused) {
    (void)unused;
    exe_host_registration();
    return 0;
}

static void on_a_thread(LPTHREAD_START_ROUTINE f) {
    HANDLE t = CreateThread(NULL, 0, f, NULL, 0, NULL);
    CHECK(t != NULL);
    if (!t) return;
    WaitForSingleObject(t, INFINITE);
    CloseHandle(t);
}
#else
static void *other_thread(void *unused) {
    (void)unused;
    both_registries("another thread");
    return NULL;
}
#endif

int main(void) {
    /* First, before anything in the process initialised COM: no apartment at all (under Wine the
       Component Categories Manager cannot be created, and the keys are written directly). */
    both_registries("COM not initialised");
#ifdef _WIN32
    on_a_thread(in_mta);
    CHECK_HR(CoInitializeEx(NULL, COINIT_APARTMENTTHREADED), S_OK);
    both_registries("single-threaded apartment");
    CoUninitialize();
    /* Once more without COM, now that the process had apartments. */
    both_registries("COM not initialised again");
    on_a_thread(exe_host_thread);
#else
    {
        pthread_t t;
        CHECK(pthread_create(&t, NULL, other_thread, NULL) == 0);
        pthread_join(t, NULL);
    }
    exe_host_registration();
#endif
    CHECK(OpcObjectCount() == 0);
    return test_summary("test_registration_com");
}
