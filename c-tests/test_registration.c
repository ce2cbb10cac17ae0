/* Registration helpers through the public header, against registries held in memory: what
 * OpcRegisterServer writes, that OpcUnregisterServer leaves the registry exactly as it found it
 * (compared as full .reg dumps) also over another product's registration of the same class, the .reg
 * export and its round trip, the category helpers, EXE command-line parsing, the version convention
 * and bad input. */
#include <stddef.h>
#include <stdint.h>

#include "test_util.h"

static const CLSID CLSID_Test = {0xC1000000, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0x01}};
static const CLSID APPID_Test = {0xC1000000, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0x02}};
static const CATID CATID_Vendor = {0xC1000000, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0x03}};

/* True when the UTF-16 text contains the ASCII `needle`. */
static int wcontains(const WCHAR *text, const char *needle) {
    size_t n = strlen(needle), i, j;
    if (!text) return 0;
    for (i = 0; text[i]; i++) {
        for (j = 0; j < n && text[i + j] == (WCHAR)(unsigned char)needle[j]; j++) {
        }
        if (j == n) return 1;
    }
    return 0;
}

static LPWSTR dump(OpcRegistry *reg) {
    LPWSTR text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(OpcRegistryExport(reg, NULL, &text), S_OK);
    return text;
}

static OpcRegistry *memory_registry(const char *reg_text) {
    OpcRegistry *reg = NULL;
    CHECK_HR(OpcRegistryCreateMemory(&reg), S_OK);
    if (reg_text) {
        WCHAR *w = wdup(reg_text);
        CHECK_HR(OpcRegistryApply(reg, w), S_OK);
        free(w);
    }
    return reg;
}

/* Checks the string value `name` of `key`. */
static void expect_value(OpcRegistry *reg, const char *key, const char *name, const char *want) {
    LPWSTR got = (LPWSTR)GARBAGE_PTR;
    HRESULT hr = OpcRegistryGetString(reg, W(key), name ? W(name) : NULL, &got);
    if (want) {
        CHECK_HR(hr, S_OK);
        CHECK(wstr_is(got, want));
        if (!wstr_is(got, want)) {
            fprintf(stderr, "  %s [%s]: ", key, name ? name : "@");
            wprint(stderr, got);
            fputc('\n', stderr);
        }
    } else {
        CHECK_HR(hr, REGDB_E_KEYMISSING);
        CHECK(got == NULL);
    }
    OpcTaskMemFree(got);
}

/* Strings that must outlive many W() calls (W() reuses a ring of buffers). */
static WCHAR *kept[64];
static unsigned nkept;
static const WCHAR *K(const char *ascii) {
    unsigned i;
    WCHAR *w = wdup(ascii);
    for (i = 0; i < nkept; i++) {
        if (wsame(kept[i], w)) {
            free(w);
            return kept[i];
        }
    }
    if (nkept == 64) abort(); /* more distinct strings than the test needs */
    kept[nkept++] = w;
    return w;
}

static CATID categories[2];
static LPCWSTR category_texts[2];

static OpcServerRegistration local_server(void) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = CLSID_Test;
    r.prog_id = K("Vendor.TestServer.1");
    r.version_independent_prog_id = K("Vendor.TestServer");
    r.user_type = K("Vendor Test Server");
    r.module_path = K("C:\\Program Files\\Vendor\\TestServer.exe");
    categories[0] = CATID_OPCDAServer20;
    categories[1] = CATID_Vendor;
    category_texts[0] = NULL; /* the standard text */
    category_texts[1] = K("Vendor Special Servers");
    r.implemented_categories = categories;
    r.implemented_category_count = 2;
    r.implemented_category_descriptions = category_texts;
    r.required_categories = &categories[1];
    r.required_category_count = 1;
    r.da10_vendor = K("Vendor Inc.");
    r.app_id = &APPID_Test;
    r.app_id_run_as = K("Interactive User");
    return r;
}

static void test_what_registration_writes(void) {
    OpcRegistry *reg = memory_registry(NULL);
    OpcServerRegistration r = local_server();
    const char *cls = "CLSID\\{C1000000-1111-2222-3333-444455556601}";
    char key[256];

    CHECK_HR(OpcRegisterServer(&r, reg), S_OK);
    expect_value(reg, cls, NULL, "Vendor Test Server");
    snprintf(key, sizeof key, "%s\\ProgID", cls);
    expect_value(reg, key, NULL, "Vendor.TestServer.1");
    snprintf(key, sizeof key, "%s\\VersionIndependentProgID", cls);
    expect_value(reg, key, NULL, "Vendor.TestServer");
    snprintf(key, sizeof key, "%s\\LocalServer32", cls);
    /* A command line: the path in quotes (unquoted, a path with blanks could start C:\Program.exe). */
    expect_value(reg, key, NULL, "\"C:\\Program Files\\Vendor\\TestServer.exe\"");
    snprintf(key, sizeof key, "%s\\InprocServer32", cls);
    expect_value(reg, key, NULL, NULL);
    expect_value(reg, cls, "AppID", "{C1000000-1111-2222-3333-444455556602}");
    expect_value(reg, "AppID\\{C1000000-1111-2222-3333-444455556602}", NULL, "Vendor Test Server");
    expect_value(reg, "AppID\\{C1000000-1111-2222-3333-444455556602}", "RunAs", "Interactive User");
    expect_value(reg, "AppID\\TestServer.exe", "AppID", "{C1000000-1111-2222-3333-444455556602}");
    expect_value(reg, "Vendor.TestServer.1", NULL, "Vendor Test Server");
    expect_value(reg, "Vendor.TestServer.1\\CLSID", NULL, "{C1000000-1111-2222-3333-444455556601}");
    expect_value(reg, "Vendor.TestServer.1\\OPC\\Vendor", NULL, "Vendor Inc.");
    expect_value(reg, "Vendor.TestServer\\CLSID", NULL, "{C1000000-1111-2222-3333-444455556601}");
    expect_value(reg, "Vendor.TestServer\\CurVer", NULL, "Vendor.TestServer.1");
    expect_value(reg, "Component Categories\\{63D5F432-CFE4-11D1-B2C8-0060083BA1FB}", "409",
                 "OPC Data Access Servers Version 2.0");
    expect_value(reg, "Component Categories\\{C1000000-1111-2222-3333-444455556603}", "409",
                 "Vendor Special Servers");
    {
        LPWSTR text = dump(reg);
        CHECK(wcontains(text, "[HKEY_CLASSES_ROOT\\CLSID\\{C1000000-1111-2222-3333-444455556601}\\Implemented "
                              "Categories\\{63D5F432-CFE4-11D1-B2C8-0060083BA1FB}]"));
        CHECK(wcontains(text, "[HKEY_CLASSES_ROOT\\CLSID\\{C1000000-1111-2222-3333-444455556601}\\Required "
                              "Categories\\{C1000000-1111-2222-3333-444455556603}]"));
        /* Proxies and stubs are never registered. */
        CHECK(!wcontains(text, "Interface"));
        OpcTaskMemFree(text);
    }
    OpcRegistryRelease(reg);
}

static void test_in_process_server(void) {
    OpcRegistry *reg = memory_registry(NULL);
    OpcServerRegistration r = local_server();
    r.server_type = OPC_SERVER_TYPE_INPROC;
    r.module_path = K("C:\\Vendor\\server.dll");
    r.threading_model = K("Both");
    r.app_id = NULL;
    CHECK_HR(OpcRegisterServer(&r, reg), S_OK);
    expect_value(reg, "CLSID\\{C1000000-1111-2222-3333-444455556601}\\InprocServer32", NULL, "C:\\Vendor\\server.dll");
    expect_value(reg, "CLSID\\{C1000000-1111-2222-3333-444455556601}\\InprocServer32", "ThreadingModel", "Both");
    expect_value(reg, "CLSID\\{C1000000-1111-2222-3333-444455556601}\\LocalServer32", NULL, NULL);
    CHECK_HR(OpcUnregisterServer(&r, reg), S_OK);
    {
        LPWSTR text = dump(reg);
        CHECK(wstr_is(text, "Windows Registry Editor Version 5.00\r\n\r\n"));
        OpcTaskMemFree(text);
    }
    OpcRegistryRelease(reg);
}

static void test_unregistration_is_symmetric(void) {
    /* Another product already registered this class (an EXE, its own description and AppID), and
     * something unrelated lives in the registry too. */
    OpcRegistry *reg = memory_registry(
        "Windows Registry Editor Version 5.00\r\n"
        "[HKEY_CLASSES_ROOT\\CLSID\\{C1000000-1111-2222-3333-444455556601}]\r\n@=\"Their Description\"\r\n"
        "\"AppID\"=\"{00000000-0000-0000-0000-00000000AAAA}\"\r\n"
        "[HKEY_CLASSES_ROOT\\CLSID\\{C1000000-1111-2222-3333-444455556601}\\LocalServer32]\r\n@=\"C:\\\\their.exe\"\r\n"
        "[HKEY_CLASSES_ROOT\\Component Categories\\{63D5F432-CFE4-11D1-B2C8-0060083BA1FB}]\r\n\"409\"=\"Custom text\"\r\n"
        "[HKEY_CLASSES_ROOT\\Unrelated.Thing]\r\n@=\"x\"\r\n");
    OpcServerRegistration r = local_server();
    LPWSTR before = dump(reg), during, after;

    r.server_type = OPC_SERVER_TYPE_INPROC;
    r.module_path = K("C:\\Vendor\\server.dll");
    r.app_id = NULL;
    r.flags = OPC_REGISTRATION_KEEP_EXISTING;
    CHECK_HR(OpcRegisterServer(&r, reg), S_OK);
    CHECK_HR(OpcRegisterServer(&r, reg), S_OK); /* twice is harmless */
    during = dump(reg);
    CHECK(!wsame(before, during));
    /* What was there stays as it was. */
    expect_value(reg, "CLSID\\{C1000000-1111-2222-3333-444455556601}", NULL, "Their Description");
    expect_value(reg, "CLSID\\{C1000000-1111-2222-3333-444455556601}\\LocalServer32", NULL, "C:\\their.exe");
    expect_value(reg, "Component Categories\\{63D5F432-CFE4-11D1-B2C8-0060083BA1FB}", "409", "Custom text");
    CHECK_HR(OpcUnregisterServer(&r, reg), S_OK);
    after = dump(reg);
    CHECK(wsame(before, after));
    OpcTaskMemFree(during);
    OpcTaskMemFree(after);

    /* Without OPC_REGISTRATION_KEEP_EXISTING the description is replaced, and restored afterwards. */
    r.flags = 0;
    CHECK_HR(OpcRegisterServer(&r, reg), S_OK);
    expect_value(reg, "CLSID\\{C1000000-1111-2222-3333-444455556601}", NULL, "Vendor Test Server");
    CHECK_HR(OpcUnregisterServer(&r, reg), S_OK);
    after = dump(reg);
    CHECK(wsame(before, after));
    OpcTaskMemFree(after);

    /* A local server with everything, into the same registry. */
    r = local_server();
    CHECK_HR(OpcRegisterServer(&r, reg), S_OK);
    CHECK_HR(OpcUnregisterServer(&r, reg), S_OK);
    after = dump(reg);
    CHECK(wsame(before, after));
    OpcTaskMemFree(after);
    OpcTaskMemFree(before);
    OpcRegistryRelease(reg);
}

static void test_reg_file_round_trip(void) {
    OpcServerRegistration r = local_server();
    OpcRegistry *direct = memory_registry(NULL), *imported = memory_registry(NULL);
    LPWSTR text = (LPWSTR)GARBAGE_PTR, a, b;

    CHECK_HR(OpcRegistrationExport(&r, &text), S_OK);
    CHECK(wcontains(text, "Windows Registry Editor Version 5.00\r\n"));
    CHECK(wcontains(text, "[HKEY_CLASSES_ROOT\\Vendor.TestServer.1\\OPC\\Vendor]\r\n@=\"Vendor Inc.\""));
    /* Backslashes and quotes in data are escaped. */
    CHECK(wcontains(text, "@=\"\\\"C:\\\\Program Files\\\\Vendor\\\\TestServer.exe\\\"\""));
    CHECK_HR(OpcRegistryApply(imported, text), S_OK);
    CHECK_HR(OpcRegisterServer(&r, direct), S_OK);
    a = dump(direct);
    b = dump(imported);
    CHECK(wsame(a, b));
    /* What was imported unregisters cleanly. */
    CHECK_HR(OpcUnregisterServer(&r, imported), S_OK);
    OpcTaskMemFree(b);
    b = dump(imported);
    CHECK(wstr_is(b, "Windows Registry Editor Version 5.00\r\n\r\n"));
    /* A subtree export. */
    OpcTaskMemFree(a);
    CHECK_HR(OpcRegistryExport(direct, W("Vendor.TestServer\\CurVer"), &a), S_OK);
    CHECK(wstr_is(a, "Windows Registry Editor Version 5.00\r\n\r\n[HKEY_CLASSES_ROOT\\Vendor.TestServer\\CurVer]\r\n"
                     "@=\"Vendor.TestServer.1\"\r\n\r\n"));
    OpcTaskMemFree(a);
    a = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(OpcRegistryExport(direct, W("No.Such.Key"), &a), REGDB_E_KEYMISSING);
    CHECK(a == NULL);
    OpcTaskMemFree(b);
    OpcTaskMemFree(text);

    /* Malformed files change nothing. */
    CHECK_HR(OpcRegistryApply(imported, W("REGEDIT4\n[HKEY_CLASSES_ROOT\\A]\n\"x\"=\"unterminated")), E_INVALIDARG);
    CHECK_HR(OpcRegistryApply(imported, W("Windows Registry Editor Version 5.00\n[HKEY_CURRENT_USER\\A]\n")),
             E_INVALIDARG);
    CHECK_HR(OpcRegistryApply(imported, W("not a registry file")), E_INVALIDARG);
    CHECK_HR(OpcRegistryApply(imported, NULL), E_INVALIDARG);
    b = dump(imported);
    CHECK(wstr_is(b, "Windows Registry Editor Version 5.00\r\n\r\n"));
    OpcTaskMemFree(b);
    /* Deletions. */
    CHECK_HR(OpcRegistryApply(direct, W("REGEDIT4\n[-HKEY_CLASSES_ROOT\\Vendor.TestServer]\n")), S_OK);
    expect_value(direct, "Vendor.TestServer\\CurVer", NULL, NULL);
    OpcRegistryRelease(direct);
    OpcRegistryRelease(imported);
}

static void test_category_helpers(void) {
    OpcRegistry *reg = memory_registry(NULL);
    LPWSTR text = (LPWSTR)GARBAGE_PTR;
    CATID bogus = CATID_Vendor;

    CHECK_HR(OpcCreateComponentCategory(reg, &CATID_OPCAEServer10, NULL), S_OK);
    expect_value(reg, "Component Categories\\{58E13251-AC87-11D1-84D5-00608CB8A7E9}", "409",
                 "OPC Alarm & Event Server Version 1.0");
    CHECK_HR(OpcCreateComponentCategory(reg, &bogus, NULL), E_INVALIDARG); /* no standard text */
    CHECK_HR(OpcCreateComponentCategory(reg, &bogus, W("Mine")), S_OK);
    CHECK_HR(OpcCreateComponentCategory(reg, NULL, W("Mine")), E_INVALIDARG);
    CHECK_HR(OpcRegisterClassInCategory(reg, &CLSID_Test, &CATID_OPCAEServer10), S_OK);
    CHECK_HR(OpcRegistryExport(reg, W("CLSID\\{C1000000-1111-2222-3333-444455556601}\\Implemented Categories\\{58E13251-"
                                      "AC87-11D1-84D5-00608CB8A7E9}"),
                               &text),
             S_OK);
    OpcTaskMemFree(text);
    CHECK_HR(OpcUnregisterClassInCategory(reg, &CLSID_Test, &CATID_OPCAEServer10), S_OK);
    text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(OpcRegistryExport(reg, W("CLSID\\{C1000000-1111-2222-3333-444455556601}\\Implemented Categories\\{58E13251-"
                                      "AC87-11D1-84D5-00608CB8A7E9}"),
                               &text),
             REGDB_E_KEYMISSING);
    CHECK(text == NULL);
    CHECK_HR(OpcUnregisterClassInCategory(reg, &CLSID_Test, &CATID_OPCAEServer10), S_OK); /* not there: fine */
    CHECK_HR(OpcRegisterClassInCategory(reg, NULL, &CATID_OPCAEServer10), E_INVALIDARG);

    CHECK_HR(OpcCategoryDescription(&CATID_OPCDAServer30, &text), S_OK);
    CHECK(wstr_is(text, "OPC Data Access Servers Version 3.0"));
    OpcTaskMemFree(text);
    text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(OpcCategoryDescription(&bogus, &text), E_INVALIDARG);
    CHECK(text == NULL);
    OpcRegistryRelease(reg);
}

static void test_bad_registrations(void) {
    OpcRegistry *reg = memory_registry(NULL);
    OpcServerRegistration r;
    LPWSTR text = (LPWSTR)GARBAGE_PTR;

    CHECK_HR(OpcRegisterServer(NULL, reg), E_INVALIDARG);
    r = local_server();
    r.struct_size = 8;
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    r = local_server();
    r.prog_id = NULL;
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    r = local_server();
    r.prog_id = K("Bad\\ProgID");
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    r = local_server();
    r.server_type = 7;
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    r = local_server();
    r.flags = 0x80;
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    r = local_server();
    r.implemented_categories = NULL; /* a count without an array */
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    r = local_server();
    r.implemented_category_count = 100000;
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    r = local_server();
    {
        static const WCHAR lone_surrogate[] = {'X', 0xDC00, 0};
        r.user_type = lone_surrogate;
        CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    }
    CHECK_HR(OpcRegistrationExport(NULL, &text), E_INVALIDARG);
    CHECK(text == NULL);
    /* Nothing was written by any of these. */
    text = dump(reg);
    CHECK(wstr_is(text, "Windows Registry Editor Version 5.00\r\n\r\n"));
    OpcTaskMemFree(text);
    /* Unregistering what is not registered. */
    r = local_server();
    CHECK_HR(OpcUnregisterServer(&r, reg), REGDB_E_KEYMISSING);
    OpcRegistryRelease(reg);
    OpcRegistryRelease(NULL);
    CHECK_HR(OpcRegistryCreateMemory(NULL), E_INVALIDARG);
}

static void expect_command(const char *line, uint32_t want) {
    uint32_t got = GARBAGE_U32;
    CHECK_HR(OpcParseCommandLine(W(line), &got), S_OK);
    CHECK(got == want);
    if (got != want) fprintf(stderr, "  command line \"%s\": %u\n", line, (unsigned)got);
}

static void test_command_line(void) {
    uint32_t got = GARBAGE_U32;
    expect_command("/RegServer", OPC_SERVER_COMMAND_REGISTER);
    expect_command("-regserver", OPC_SERVER_COMMAND_REGISTER);
    expect_command("\"C:\\Program Files\\V\\s.exe\" /REGSERVER", OPC_SERVER_COMMAND_REGISTER);
    expect_command("server.exe -UnregServer", OPC_SERVER_COMMAND_UNREGISTER);
    expect_command("/unregserver", OPC_SERVER_COMMAND_UNREGISTER);
    expect_command("server.exe -Embedding", OPC_SERVER_COMMAND_EMBEDDING);
    expect_command("/embedding", OPC_SERVER_COMMAND_EMBEDDING);
    expect_command("server.exe", OPC_SERVER_COMMAND_NONE);
    expect_command("", OPC_SERVER_COMMAND_NONE);
    expect_command("/RegServerX RegServer --RegServer", OPC_SERVER_COMMAND_NONE);
    CHECK_HR(OpcParseCommandLine(W("/RegServer /UnregServer"), &got), E_INVALIDARG);
    CHECK(got == OPC_SERVER_COMMAND_NONE);
    CHECK_HR(OpcParseCommandLine(NULL, &got), E_INVALIDARG);
    CHECK_HR(OpcParseCommandLine(W("/RegServer"), NULL), E_INVALIDARG);
}

static void test_versions(void) {
    OpcVersion v, w;
    DWORD ms = GARBAGE_U32, ls = GARBAGE_U32;
    LPWSTR text = (LPWSTR)GARBAGE_PTR;

    CHECK_HR(OpcVersionParse(W("5.2.41"), &v), S_OK);
    CHECK(v.major == 5 && v.minor == 2 && v.build == 41);
    CHECK_HR(OpcVersionToFileVersion(&v, &ms, &ls), S_OK);
    CHECK(ms == 0x00050002u && ls == 41u); /* FILEVERSION 5,2,0,41 */
    CHECK_HR(OpcVersionFromFileVersion(ms, ls, &w), S_OK);
    CHECK(OpcVersionCompare(&v, &w) == 0);
    CHECK_HR(OpcVersionFromFileVersion(0x00050002u, 0x00010029u, &w), E_INVALIDARG); /* third field not 0 */
    CHECK(w.major == 0 && w.minor == 0 && w.build == 0);
    CHECK_HR(OpcVersionFormat(&v, &text), S_OK);
    CHECK(wstr_is(text, "5.2.41"));
    OpcTaskMemFree(text);

    CHECK_HR(OpcVersionParse(W("5.2.42"), &w), S_OK);
    CHECK(OpcVersionIsNewer(&w, &v) == TRUE);
    CHECK(OpcVersionIsNewer(&v, &w) == FALSE);
    CHECK(OpcVersionIsNewer(&v, &v) == FALSE);
    CHECK_HR(OpcVersionParse(W("5.10.0"), &w), S_OK); /* 10 > 2 numerically, not as text */
    CHECK(OpcVersionIsNewer(&w, &v) == TRUE);
    CHECK_HR(OpcVersionParse(W("4.99.99"), &w), S_OK);
    CHECK(OpcVersionCompare(&w, &v) < 0);
    CHECK(OpcVersionIsNewer(&v, NULL) == TRUE);
    CHECK(OpcVersionIsNewer(NULL, &v) == FALSE);

    CHECK_HR(OpcVersionParse(W("5.2"), &w), E_INVALIDARG);
    CHECK(w.major == 0 && w.minor == 0 && w.build == 0);
    CHECK_HR(OpcVersionParse(W("5.2.41.0"), &w), E_INVALIDARG);
    CHECK_HR(OpcVersionParse(W("5.2.x"), &w), E_INVALIDARG);
    CHECK_HR(OpcVersionParse(W("70000.0.0"), &w), E_INVALIDARG);
    CHECK_HR(OpcVersionParse(W(" 5.2.41"), &w), E_INVALIDARG);
    CHECK_HR(OpcVersionParse(NULL, &w), E_INVALIDARG);
    CHECK_HR(OpcVersionParse(W("1.2.3"), NULL), E_INVALIDARG);
    CHECK_HR(OpcVersionToFileVersion(NULL, &ms, &ls), E_INVALIDARG);
    CHECK(ms == 0 && ls == 0);
    CHECK_HR(OpcVersionFormat(NULL, &text), E_INVALIDARG);
    CHECK(text == NULL);
}

/* The AppID's DCOM security: PKT_INTEGRITY unless told otherwise, the permissions from SDDL as
 * binary security descriptors (REG_BINARY), all of it gone with unregistration. */
static void test_app_id_security(void) {
    OpcRegistry *reg = memory_registry(NULL);
    OpcServerRegistration r = local_server();
    LPWSTR text = (LPWSTR)(uintptr_t)0x1;
    CHECK_HR(OpcRegisterServer(&r, reg), S_OK);
    text = dump(reg);
    CHECK(wcontains(text, "\"AuthenticationLevel\"=dword:00000005\r\n"));
    CHECK(!wcontains(text, "Permission"));
    OpcTaskMemFree(text);
    CHECK_HR(OpcUnregisterServer(&r, reg), S_OK);

    r.app_id_access_permission = K("O:BAG:BAD:(A;;0x7;;;AU)(A;;0x7;;;SY)");
    r.app_id_launch_permission = K("O:BAG:BAD:(A;;0x1F;;;BA)(A;;0x1F;;;SY)(A;;0xB;;;IU)");
    r.app_id_authentication_level = 6; /* RPC_C_AUTHN_LEVEL_PKT_PRIVACY */
    CHECK_HR(OpcRegisterServer(&r, reg), S_OK);
    text = dump(reg);
    CHECK(wcontains(text, "\"AuthenticationLevel\"=dword:00000006\r\n"));
    /* Revision 1, self-relative with a DACL; owner at 0x14, group at 0x24, DACL at 0x34. */
    CHECK(wcontains(text, "\"AccessPermission\"=hex:01,00,04,80,14,00,00,00,24,00,00,00,00,00,00,00,34,00,00,00,"));
    CHECK(wcontains(text, "\"LaunchPermission\"=hex:01,00,04,80,"));
    OpcTaskMemFree(text);
    CHECK_HR(OpcUnregisterServer(&r, reg), S_OK);
    text = dump(reg);
    CHECK(wstr_is(text, "Windows Registry Editor Version 5.00\r\n\r\n"));
    OpcTaskMemFree(text);

    /* Refused before anything is written: SDDL outside the subset, a level above 6, security
     * without an AppID. */
    r.app_id_access_permission = K("D:(A;;0xB;;;AU");
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    r.app_id_access_permission = NULL;
    r.app_id_authentication_level = 7;
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    r.app_id_authentication_level = 5;
    r.app_id = NULL;
    CHECK_HR(OpcRegisterServer(&r, reg), E_INVALIDARG);
    text = dump(reg);
    CHECK(wstr_is(text, "Windows Registry Editor Version 5.00\r\n\r\n"));
    OpcTaskMemFree(text);
    OpcRegistryRelease(reg);
}

/* One product, two classes, one AppID (the usual layout): the AppID stays whole while either class is
 * registered and goes with the last, in either order, back to what was there before the first (a
 * level an older installation left, another product's value); with different access permissions the
 * AppID holds the latest registration's. */
static OpcServerRegistration sharing_server(const CLSID *clsid, const char *prog_id, const char *access) {
    static const CLSID app_id = {0xC1000000, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0xAA}};
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = *clsid;
    r.prog_id = K(prog_id);
    r.user_type = K(prog_id);
    r.module_path = K("C:\\Vendor\\server.exe");
    r.app_id = &app_id;
    r.app_id_access_permission = K(access);
    r.app_id_launch_permission = K("O:BAG:BAD:(A;;0x1F;;;AU)(A;;0x1F;;;SY)");
    return r;
}

static LPWSTR export_key(OpcRegistry *reg, const char *key) {
    LPWSTR text = NULL;
    OpcRegistryExport(reg, W(key), &text); /* NULL when the key is missing */
    return text;
}

static void test_shared_app_id(void) {
    static const CLSID a_clsid = {0xC1000000, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0xA1}};
    static const CLSID b_clsid = {0xC1000000, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0xB1}};
    const char *app_key = "AppID\\{C1000000-1111-2222-3333-4444555566AA}";
    const char *access = "O:BAG:BAD:(A;;0x7;;;AU)(A;;0x7;;;SY)";
    int round, first;
    for (round = 0; round < 3; round++) {
        for (first = 0; first < 2; first++) {
            /* As on Windows, CLSID and AppID exist; round 2: an older installation's level and another
               product's value in the AppID. */
            OpcRegistry *reg = memory_registry(
                round == 2 ? "Windows Registry Editor Version 5.00\r\n[HKEY_CLASSES_ROOT\\CLSID]\r\n"
                             "[HKEY_CLASSES_ROOT\\AppID\\{C1000000-1111-2222-3333-4444555566AA}]\r\n"
                             "\"AuthenticationLevel\"=dword:00000002\r\n\"TheirValue\"=\"theirs\"\r\n"
                           : "Windows Registry Editor Version 5.00\r\n[HKEY_CLASSES_ROOT\\CLSID]\r\n"
                             "[HKEY_CLASSES_ROOT\\AppID]\r\n");
            OpcServerRegistration a = sharing_server(&a_clsid, "Vendor.A.1", access);
            OpcServerRegistration b =
                sharing_server(&b_clsid, "Vendor.B.1", round == 1 ? "O:BAG:BAD:(A;;0x7;;;SY)" : access);
            OpcServerRegistration *order[2];
            LPWSTR before = dump(reg), whole, now;
            order[0] = first == 0 ? &a : &b;
            order[1] = first == 0 ? &b : &a;
            CHECK_HR(OpcRegisterServer(&a, reg), S_OK);
            CHECK_HR(OpcRegisterServer(&b, reg), S_OK);
            whole = export_key(reg, app_key);
            CHECK(wcontains(whole, "\"AuthenticationLevel\"=dword:00000005\r\n"));
            CHECK(wcontains(whole, "\"AccessPermission\"=hex:"));
            CHECK(wcontains(whole, "\"LaunchPermission\"=hex:"));
            if (round < 2) {
                /* What the latest registration (B) wrote, as if it were alone: its description, and
                   in round 1 its access permission, not A's. */
                OpcRegistry *alone = memory_registry(NULL);
                LPWSTR b_alone;
                CHECK_HR(OpcRegisterServer(&b, alone), S_OK);
                b_alone = export_key(alone, app_key);
                CHECK(wsame(whole, b_alone));
                OpcTaskMemFree(b_alone);
                OpcRegistryRelease(alone);
            }
            CHECK_HR(OpcUnregisterServer(order[0], reg), S_OK);
            now = export_key(reg, app_key);
            CHECK(wsame(now, whole)); /* the other class still names it: all of it stays */
            OpcTaskMemFree(now);
            now = export_key(reg, "AppID\\server.exe");
            CHECK(wcontains(now, "\"AppID\"=\"{C1000000-1111-2222-3333-4444555566AA}\""));
            OpcTaskMemFree(now);
            CHECK_HR(OpcUnregisterServer(order[1], reg), S_OK);
            now = dump(reg);
            CHECK(wsame(now, before)); /* as it was before the first */
            if (!wsame(now, before)) {
                fprintf(stderr, "  shared AppID, round %d, %s first: left\n", round, first == 0 ? "A" : "B");
                wprint(stderr, now);
                fputc('\n', stderr);
            }
            OpcTaskMemFree(now);
            OpcTaskMemFree(whole);
            OpcTaskMemFree(before);
            OpcRegistryRelease(reg);
        }
    }
}

int main(void) {
    uint32_t before = OpcObjectCount();
    test_app_id_security();
    test_shared_app_id();
    test_what_registration_writes();
    test_in_process_server();
    test_unregistration_is_symmetric();
    test_reg_file_round_trip();
    test_category_helpers();
    test_bad_registrations();
    test_command_line();
    test_versions();
    CHECK(OpcObjectCount() == before);
    while (nkept) free(kept[--nkept]);
    return test_summary("test_registration");
}
