/* A COM server DLL built the way an existing product builds it, migrated onto opccomn: its own
 * DllGetClassObject, DllCanUnloadNow, DllRegisterServer and DllUnregisterServer (STDAPI, so __stdcall
 * `_DllRegisterServer@0` on x86), exported under their undecorated names by its own .def
 * (own_def_server.def), linked against opccomn's import library because it registers itself with
 * OpcRegisterServer. scripts/test-coexistence.sh builds it for x64 and x86 against libopccomn.dll.a
 * and opccomn.lib, requires its export table to hold its own functions (nothing of them imported from
 * opccomn.dll) and runs regsvr32 on it under Wine: its own class must be registered, and removed by
 * regsvr32 /u. Before opccomn's import libraries kept their Dll* names private, the x86 link bound the
 * .def's undecorated names to opccomn's import thunks, and regsvr32 registered opccomn instead. */
#include <opccomn/opccomn.h>

/* {6C1E0B57-3A2D-4F7E-9B14-2E8D5A1C7F30}: this test's class, registered nowhere else. */
static const CLSID CLSID_OwnDefServer = {0x6C1E0B57, 0x3A2D, 0x4F7E, {0x9B, 0x14, 0x2E, 0x8D, 0x5A, 0x1C, 0x7F, 0x30}};
static HINSTANCE own_module;

BOOL WINAPI DllMain(HINSTANCE instance, DWORD reason, LPVOID reserved);
BOOL WINAPI DllMain(HINSTANCE instance, DWORD reason, LPVOID reserved) {
    (void)reserved;
    if (reason == DLL_PROCESS_ATTACH) own_module = instance;
    return TRUE;
}

static HRESULT describe(OpcServerRegistration *server, WCHAR *path, DWORD path_size) {
    DWORD n = GetModuleFileNameW(own_module, path, path_size);
    if (n == 0 || n >= path_size) return E_FAIL;
    ZeroMemory(server, sizeof *server);
    server->struct_size = sizeof *server;
    server->server_type = OPC_SERVER_TYPE_INPROC;
    server->clsid = CLSID_OwnDefServer;
    server->prog_id = L"OpcComnTest.OwnDefServer.1";
    server->version_independent_prog_id = L"OpcComnTest.OwnDefServer";
    server->user_type = L"opccomn test: a server DLL with its own .def";
    server->module_path = path;
    server->threading_model = L"Both";
    return S_OK;
}

STDAPI DllRegisterServer(void) {
    OpcServerRegistration server;
    WCHAR path[MAX_PATH];
    HRESULT hr = describe(&server, path, MAX_PATH);
    return FAILED(hr) ? hr : OpcRegisterServer(&server, NULL);
}

STDAPI DllUnregisterServer(void) {
    OpcServerRegistration server;
    WCHAR path[MAX_PATH];
    HRESULT hr = describe(&server, path, MAX_PATH);
    return FAILED(hr) ? hr : OpcUnregisterServer(&server, NULL);
}

STDAPI DllGetClassObject(REFCLSID clsid, REFIID riid, void **ppv) {
    (void)clsid;
    (void)riid;
    if (ppv == NULL) return E_POINTER;
    *ppv = NULL;
    return CLASS_E_CLASSNOTAVAILABLE;
}

STDAPI DllCanUnloadNow(void) {
    return S_OK;
}
