/* opccomn_widl_ps.dll: the cross-process tests' stand-in for the OPC Foundation's opccomn_ps.dll,
 * built the way a MIDL proxy/stub DLL is: the generated proxy file (widl from idl/opccomn.idl, made
 * at build time by tools/gen-proxy.py --out, corrected like opccomn's) and MIDL's dlldata routines,
 * with MIDL's default CLSID (the first IID of the sorted list, {13486D50-...}) and DllRegisterServer /
 * DllUnregisterServer from NdrDllRegisterProxy, which write the Interface keys as opccomn_ps.dll does.
 * A test fixture, never shipped. */
#define USE_STUBLESS_PROXY
#define REGISTER_PROXY_DLL
#include <initguid.h>
#include <objbase.h>
#include <rpcproxy.h>

HRESULT STDMETHODCALLTYPE IUnknown_QueryInterface_Proxy(IUnknown *This, REFIID riid, void **ppvObject);
ULONG STDMETHODCALLTYPE IUnknown_AddRef_Proxy(IUnknown *This);
ULONG STDMETHODCALLTYPE IUnknown_Release_Proxy(IUnknown *This);

#ifdef _WIN64
#include "opccomn_p_win64.c"
#else
#include "opccomn_p_win32.c"
#endif

PROXYFILE_LIST_START
REFERENCE_PROXY_FILE(opccomn),
PROXYFILE_LIST_END

DLLDATA_ROUTINES(aProxyFileList, GET_DLL_CLSID)

/* For the tests: the factory's reference count (every live proxy and stub holds one), so a process can
 * tell whether its calls go through this DLL. */
LONG WINAPI WidlProxyStubRefs(void)
{
    return gPFactory.RefCount;
}
