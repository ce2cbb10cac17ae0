// The example as a DLL server (InprocServer32): the four standard exports, each a call of the
// library's DLL plumbing over the example's class. `regsvr32` registers it.
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
}  // namespace

extern "C" BOOL WINAPI DllMain(HINSTANCE instance, DWORD reason, LPVOID) {
    if (reason == DLL_PROCESS_ATTACH) {
        g_module = instance;  // for the InprocServer32 path
        DisableThreadLibraryCalls(instance);
    }
    return TRUE;
}

EXAMPLE_EXPORT(HRESULT) DllGetClassObject(REFCLSID rclsid, REFIID riid, void **ppv) {
    static const OpcServerClass cls = ExampleClass(true, nullptr);
    return OpcModuleGetClassObject(&cls, 1, rclsid, riid, ppv);
}

// Unloadable when no server object, no LockServer and no object of the library is left.
EXAMPLE_EXPORT(HRESULT) DllCanUnloadNow() { return OpcModuleCanUnloadNow(); }

namespace {
// This DLL uses opccomn.dll, so it names its own path (NULL would be opccomn.dll's).
HRESULT Register(bool add) {
    WCHAR path[MAX_PATH];
    DWORD length = GetModuleFileNameW(g_module, path, MAX_PATH);
    if (length == 0 || length >= MAX_PATH) return E_FAIL;
    OpcServerRegistration registration = ExampleRegistration(true, path);
    OpcServerClass cls = ExampleClass(true, &registration);
    return add ? OpcModuleRegister(&cls, 1, nullptr) : OpcModuleUnregister(&cls, 1, nullptr);
}
}  // namespace

EXAMPLE_EXPORT(HRESULT) DllRegisterServer() { return Register(true); }
EXAMPLE_EXPORT(HRESULT) DllUnregisterServer() { return Register(false); }
