/* The examples of the C API reference's pages "Registry", "Registration" and "Server browser"
 * (docs/reference/areas.dox shows the lines between their snippet markers), built and run by ctest (example.reference_registration) on Linux and under Wine, C11 with
 * warnings as errors. Everything goes to a registry in memory: nothing of the machine changes. */
#include <string.h>

#include "example.h"

static const CLSID CLSID_MyServer = {0x8a3f54c2, 0x1b7d, 0x4e09, {0x9c, 0x61, 0x2d, 0x5e, 0x70, 0x13, 0xa4, 0xb8}};

/* [registration] */
/* How a Data Access server is registered: written once, used by /RegServer and /UnregServer alike
 * (OpcExeServerRun() and OpcModuleRegister() take it in OpcServerClass::registration). */
static OpcServerRegistration MyRegistration(void) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = CLSID_MyServer;
    r.prog_id = u"MyVendor.MyServer.1";
    r.version_independent_prog_id = u"MyVendor.MyServer";
    r.user_type = u"My OPC Server";
    r.module_path = u"C:\\Program Files\\MyVendor\\my_server.exe"; /* NULL: this process's module */
    r.implemented_categories = &CATID_OPCDAServer20;
    r.implemented_category_count = 1;
    return r;
}

/* An installer that imports a file instead: the same keys as the text of a .reg file. */
static void WriteRegFile(void) {
    OpcServerRegistration r = MyRegistration();
    LPWSTR text = NULL;
    if (OpcRegistrationExport(&r, &text) == S_OK) {
        /* "Windows Registry Editor Version 5.00\r\n..." (save it as UTF-16LE with a BOM) */
        OpcTaskMemFree(text);
    }
}
/* [registration] */

/* [registry] */
/* A registry held in memory: what registration would write, looked at without touching the machine's. */
static OpcRegistry *RegisteredInMemory(void) {
    OpcRegistry *reg = NULL;
    if (OpcRegistryCreateMemory(&reg) != S_OK) return NULL;
    OpcServerRegistration r = MyRegistration();
    if (OpcRegisterServer(&r, reg) != S_OK) {
        OpcRegistryRelease(reg);
        return NULL;
    }
    LPWSTR current = NULL;
    OpcRegistryGetString(reg, u"MyVendor.MyServer\\CurVer", NULL, &current); /* "MyVendor.MyServer.1" */
    OpcTaskMemFree(current);
    return reg; /* OpcRegistryExport() gives it as a .reg file; OpcRegistryRelease() frees it */
}
/* [registry] */

/* [browser] */
/* A client finds the Data Access 2 servers of a machine (here: of the registry in memory). */
static void BrowseDataAccessServers(OpcRegistry *reg) {
    IOPCServerList2 *list = NULL;
    if (OpcServerListCreateOver(reg, NULL, OPCCOMN_RIID(IID_IOPCServerList2), (void **)&list) != S_OK) return;
    CATID categories[1];
    categories[0] = CATID_OPCDAServer20;
    IOPCEnumGUID *found = NULL;
    if (list->lpVtbl->EnumClassesOfCategories(list, 1, categories, 0, categories, &found) == S_OK) {
        CLSID clsid;
        ULONG fetched = 0;
        while (found->lpVtbl->Next(found, 1, &clsid, &fetched) == S_OK) {
            LPOLESTR prog_id = NULL, user_type = NULL, independent = NULL;
            if (list->lpVtbl->GetClassDetails(list, &clsid, &prog_id, &user_type, &independent) == S_OK) {
                /* "MyVendor.MyServer.1", "My OPC Server", "MyVendor.MyServer" */
                OpcTaskMemFree(prog_id);
                OpcTaskMemFree(user_type);
                OpcTaskMemFree(independent);
            }
        }
        found->lpVtbl->Release(found);
    }
    list->lpVtbl->Release(list);
}
/* [browser] */

int main(void) {
    WriteRegFile();
    OpcServerRegistration r = MyRegistration();
    LPWSTR text = NULL;
    check(OpcRegistrationExport(&r, &text) == S_OK, "OpcRegistrationExport");
    OpcTaskMemFree(text);

    OpcRegistry *reg = RegisteredInMemory();
    check(reg != NULL, "registered in memory");
    if (reg) {
        LPWSTR current = NULL;
        check(OpcRegistryGetString(reg, u"MyVendor.MyServer\\CurVer", NULL, &current) == S_OK &&
                  same(current, "MyVendor.MyServer.1"),
              "CurVer");
        OpcTaskMemFree(current);
        BrowseDataAccessServers(reg);

        /* What the browser finds. */
        IOPCServerList2 *list = NULL;
        CATID categories[1];
        categories[0] = CATID_OPCDAServer20;
        IOPCEnumGUID *found = NULL;
        CLSID clsid;
        ULONG fetched = 0;
        check(OpcServerListCreateOver(reg, NULL, OPCCOMN_RIID(IID_IOPCServerList2), (void **)&list) == S_OK,
              "the server list");
        if (list) {
            check(list->lpVtbl->EnumClassesOfCategories(list, 1, categories, 0, categories, &found) == S_OK,
                  "EnumClassesOfCategories");
            if (found) {
                check(found->lpVtbl->Next(found, 1, &clsid, &fetched) == S_OK && fetched == 1 &&
                          memcmp(&clsid, &CLSID_MyServer, sizeof clsid) == 0,
                      "the server is found");
                check(found->lpVtbl->Next(found, 1, &clsid, &fetched) == S_FALSE && fetched == 0, "and only it");
                found->lpVtbl->Release(found);
            }
            LPOLESTR prog_id = NULL, user_type = NULL, independent = NULL;
            check(list->lpVtbl->GetClassDetails(list, &CLSID_MyServer, &prog_id, &user_type, &independent) == S_OK &&
                      same(prog_id, "MyVendor.MyServer.1") && same(user_type, "My OPC Server") &&
                      same(independent, "MyVendor.MyServer"),
                  "GetClassDetails");
            OpcTaskMemFree(prog_id);
            OpcTaskMemFree(user_type);
            OpcTaskMemFree(independent);
            list->lpVtbl->Release(list);
        }
        check(OpcUnregisterServer(&r, reg) == S_OK, "OpcUnregisterServer");
        OpcRegistryRelease(reg);
    }
    check(OpcObjectCount() == 0, "every object released");
    return report("reference registration (registry, registration, server browser)");
}
