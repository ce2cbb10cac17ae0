// The example as a DLL server (InprocServer32): the four standard exports. `regsvr32` registers it.
#include "example_server.h"

// The four exports under their undecorated names, also on 32-bit Windows where STDAPI is __stdcall
// (`DllRegisterServer@0`): with mingw, dllexport and -Wl,--kill-at (a .def naming them works as well:
// opccomn's import libraries keep its own Dll* entry points private); with Visual Studio, dll_exports.def.
#if defined(__GNUC__)
#define EXAMPLE_EXPORT(type) EXTERN_C __declspec(dllexport) type STDAPICALLTYPE
#else
#define EXAMPLE_EXPORT(type) EXTERN_C type STDAPICALLTYPE
#endif

namespace {
HMODULE g_module;
volatile LONG g_locks;  // live server objects and LockServer(TRUE) calls
}  // namespace

void ExampleModuleLock() { InterlockedIncrement(&g_locks); }
void ExampleModuleUnlock() { InterlockedDecrement(&g_locks); }

extern "C" BOOL WINAPI DllMain(HINSTANCE instance, DWORD reason, LPVOID) {
    if (reason == DLL_PROCESS_ATTACH) {
        g_module = instance;  // for the InprocServer32 path
        DisableThreadLibraryCalls(instance);
    }
    return TRUE;
}

EXAMPLE_EXPORT(HRESULT) DllGetClassObject(REFCLSID rclsid, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = nullptr;
    if (!IsEqualCLSID(rclsid, CLSID_ExampleServerInProc)) return CLASS_E_CLASSNOTAVAILABLE;
    return ExampleClassFactory()->QueryInterface(riid, ppv);
}

EXAMPLE_EXPORT(HRESULT) DllCanUnloadNow() { return g_locks == 0 && ExampleClassFactoryReferences() == 0 ? S_OK : S_FALSE; }

namespace {
// This DLL uses opccomn.dll, so it names its own path (NULL would be opccomn.dll's).
HRESULT Register(bool add) {
    WCHAR path[MAX_PATH];
    DWORD length = GetModuleFileNameW(g_module, path, MAX_PATH);
    if (length == 0 || length >= MAX_PATH) return E_FAIL;
    OpcServerRegistration registration = ExampleRegistration(true, path);
    return add ? OpcRegisterServer(&registration, nullptr) : OpcUnregisterServer(&registration, nullptr);
}
}  // namespace

EXAMPLE_EXPORT(HRESULT) DllRegisterServer() { return Register(true); }
EXAMPLE_EXPORT(HRESULT) DllUnregisterServer() { return Register(false); }
