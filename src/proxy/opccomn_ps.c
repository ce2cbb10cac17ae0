/* The proxy/stub class of opccomn.dll (a MIDL "merged proxy/stub"): the PSFactoryBuffer for
 * IOPCShutdown, IOPCCommon, IOPCServerList, IOPCServerList2 and IOPCEnumGUID.
 *
 * The marshalling itself is the system RPC runtime's: the generated files in generated/ hold only NDR
 * format strings and tables (tools/gen-proxy.py makes them from idl/opccomn.idl with widl -Oif), which
 * NdrClientCall2 / NdrStubCall2 interpret, as they interpret the format strings of MIDL's /Oicf
 * proxies. This file adds what MIDL's dlldata.c would: the factory object and its two entry points,
 * under opccomn's names, because DllGetClassObject / DllCanUnloadNow are opccomn's own (src/proxy/mod.rs
 * dispatches to these). Built by buildscript/proxy.rs for Windows targets. */
#define USE_STUBLESS_PROXY
#include <objbase.h>
#include <rpcproxy.h>

/* mingw-w64 declares these runtime functions only for C++; the generated vtables name them. */
HRESULT STDMETHODCALLTYPE IUnknown_QueryInterface_Proxy(IUnknown *This, REFIID riid, void **ppvObject);
ULONG STDMETHODCALLTYPE IUnknown_AddRef_Proxy(IUnknown *This);
ULONG STDMETHODCALLTYPE IUnknown_Release_Proxy(IUnknown *This);

#ifdef _WIN64
#include "generated/opccomn_p_win64.c"
#else
#include "generated/opccomn_p_win32.c"
#endif

/* Defined in Rust (src/proxy/mod.rs), exported, declared in opccomn.h. */
extern const CLSID CLSID_OpcComnProxyStub;

static const ProxyFileInfo *const proxy_files[] = {
    (const ProxyFileInfo *)&opccomn_ProxyFileInfo,
    NULL,
};

/* The one factory object; the runtime initialises it on first use and counts its references. */
static CStdPSFactoryBuffer factory = {0};

/* The stub vtables name CStdStubBuffer_Release; as in MIDL's dlldata.c it releases the factory's
 * reference too, so OpcProxyStubCanUnloadNow sees the stubs still alive. */
ULONG STDMETHODCALLTYPE CStdStubBuffer_Release(IRpcStubBuffer *This)
{
    return NdrCStdStubBuffer_Release(This, (IPSFactoryBuffer *)&factory);
}

HRESULT OpcProxyStubGetClassObject(REFCLSID rclsid, REFIID riid, void **ppv)
{
    return NdrDllGetClassObject(rclsid, riid, ppv, (const ProxyFileInfo **)proxy_files, &CLSID_OpcComnProxyStub,
                                &factory);
}

HRESULT OpcProxyStubCanUnloadNow(void)
{
    return NdrDllCanUnloadNow(&factory);
}
