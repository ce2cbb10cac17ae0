/* The proxy/stub class of opccomn.dll (a MIDL "merged proxy/stub"): the PSFactoryBuffer for
 * IOPCShutdown, IOPCCommon, IOPCServerList, IOPCServerList2 and IOPCEnumGUID, and for the OPC Data
 * Access, Alarms & Events and Historical Data Access interfaces (their tables in opcda_ps.c,
 * opc_ae_ps.c and opchda_ps.c, translation units of their own).
 *
 * The marshalling itself is the system RPC runtime's: the generated files in generated/ hold only NDR
 * format strings and tables (tools/gen-proxy.py makes them from idl/opccomn.idl and idl/opcda.idl with widl -Oif), which
 * NdrClientCall2 / NdrStubCall2 interpret, as they interpret the format strings of MIDL's /Oicf
 * proxies. This file adds what MIDL's dlldata.c would (the factory and its two entry points, under
 * opccomn's names, because DllGetClassObject / DllCanUnloadNow are opccomn's own; src/proxy/mod.rs
 * dispatches to these) and the checks the runtime does not make (src/proxy/ndr, reading the layouts
 * tools/gen-header generates from the IDL):
 *
 * - every stub's IRpcStubBuffer::Invoke is OpcStubBuffer_Invoke, which has the request checked before
 *   the runtime's CStdStubBuffer_Invoke unmarshals it and calls the server;
 * - the factory handed out is checked_factory, which wraps each proxy's IRpcProxyBuffer so that the
 *   proxy is connected to checked_channel, a channel that has each reply checked (knowing the request,
 *   e.g. Next's celt) before the runtime unmarshals it into the caller's memory.
 *
 * Built by buildscript/proxy.rs for Windows targets. */
#define USE_STUBLESS_PROXY
#define COBJMACROS
#include <objbase.h>
#include <rpcproxy.h>

/* mingw-w64 declares these runtime functions only for C++; the generated vtables name them. */
HRESULT STDMETHODCALLTYPE IUnknown_QueryInterface_Proxy(IUnknown *This, REFIID riid, void **ppvObject);
ULONG STDMETHODCALLTYPE IUnknown_AddRef_Proxy(IUnknown *This);
ULONG STDMETHODCALLTYPE IUnknown_Release_Proxy(IUnknown *This);

/* The IIDs of the Data Access interfaces under the proxy/stub's own names (opcda_ps.c defines them). */
#define OPC_PS_PART_NAMES
#include "generated/interfaces.h"
#undef OPC_PS_PART_NAMES

/* The generated stub vtables (CStdStubBuffer_METHODS) get the checking Invoke. */
HRESULT STDMETHODCALLTYPE OpcStubBuffer_Invoke(IRpcStubBuffer *This, RPCOLEMESSAGE *msg, IRpcChannelBuffer *channel);
#define CStdStubBuffer_Invoke OpcStubBuffer_Invoke
#ifdef _WIN64
#include "generated/opccomn_p_win64.c"
#else
#include "generated/opccomn_p_win32.c"
#endif
#undef CStdStubBuffer_Invoke

/* The Data Access interfaces: their IIDs (renamed above, defined in opcda_ps.c) and tables. */
#include "generated/opcda_idl.h"
extern const ExtendedProxyFileInfo opcda_ProxyFileInfo;
/* Alarms & Events and Historical Data Access: the same (opc_ae_ps.c, opchda_ps.c). */
#include "generated/opc_ae_idl.h"
#include "generated/opchda_idl.h"
extern const ExtendedProxyFileInfo opc_ae_ProxyFileInfo;
extern const ExtendedProxyFileInfo opchda_ProxyFileInfo;

/* The interfaces by number, as the checks number them (generated from the IDL with the checks' layouts). */
#include "generated/interfaces.h"

/* The checks, in Rust (src/proxy/ndr reading the layouts tools/gen-header generates from the IDL, through
 * src/proxy/mod.rs). Interfaces by their number in opc_ps_interfaces, methods by their vtable index.
 * Failures are HRESULTs (RPC_X_BAD_STUB_DATA, RPC_S_INVALID_BOUND, ...). `wine_reader`: nonzero when this
 * process's runtime is Wine's, which reads some constructs differently (interface pointers among them).
 * `request` writes what the reply check will need of the request into `context` when it is not NULL. */
typedef struct OpcProxyStubChecks {
    HRESULT (*request)(ULONG iface, ULONG method, const unsigned char *buf, ULONG len, ULONG drep, ULONG wine_reader,
                       ULONG context[OPC_PS_CONTEXT_WORDS]);
    HRESULT (*reply)(ULONG iface, ULONG method, const ULONG context[OPC_PS_CONTEXT_WORDS], const unsigned char *buf,
                     ULONG len, ULONG drep, ULONG wine_reader);
} OpcProxyStubChecks;

static const OpcProxyStubChecks *volatile checks;

#define BAD_STUB_DATA HRESULT_FROM_WIN32(RPC_X_BAD_STUB_DATA)

/* The method a message is for: its procedure number without the runtime's flag bit, as NdrStubCall2
 * reads it. */
static ULONG method_of(const RPCOLEMESSAGE *msg)
{
    return msg->iMethod & ~(ULONG)RPC_FLAGS_VALID_BIT;
}

/* Defined in Rust (src/proxy/mod.rs), exported, declared in opccomn.h. */
extern const CLSID CLSID_OpcComnProxyStub;

static const ProxyFileInfo *const proxy_files[] = {
    (const ProxyFileInfo *)&opccomn_ProxyFileInfo,
    (const ProxyFileInfo *)&opcda_ProxyFileInfo,
    (const ProxyFileInfo *)&opc_ae_ProxyFileInfo,
    (const ProxyFileInfo *)&opchda_ProxyFileInfo,
    NULL,
};

/* The one factory object of the runtime; it initialises it on first use and counts its references. */
static CStdPSFactoryBuffer factory = {0};
/* Held while the runtime initialises or hands out the factory (OpcProxyStubGetClassObject). */
static SRWLOCK factory_lock = SRWLOCK_INIT;

/* The stub vtables name CStdStubBuffer_Release; as in MIDL's dlldata.c it releases the factory's
 * reference too, so OpcProxyStubCanUnloadNow sees the stubs still alive. */
ULONG STDMETHODCALLTYPE CStdStubBuffer_Release(IRpcStubBuffer *This)
{
    return NdrCStdStubBuffer_Release(This, (IPSFactoryBuffer *)&factory);
}

static int interface_index(REFIID riid)
{
    int i;
    for (i = 0; i < OPC_PS_INTERFACE_COUNT; i++)
        if (IsEqualIID(riid, opc_ps_interfaces[i])) return i;
    return -1;
}

/* Whether this process's rpcrt4 reads interface pointers in Wine's layout (a byte count, then the
 * OBJREF) rather than NDR's (MInterfacePointer, as Windows' rpcrt4 reads it). A reply says which layout
 * it is in (src/proxy/ndr/objref.rs tells them apart), not which runtime will read it: that is asked of the
 * process, once: Wine's ntdll exports wine_get_version. A reply in the layout this runtime does not
 * read is refused. */
static ULONG reads_wine_layout(void)
{
    static LONG known = -1;
    if (known < 0) {
        HMODULE ntdll = GetModuleHandleW(L"ntdll.dll");
        known = ntdll && GetProcAddress(ntdll, "wine_get_version") ? 1 : 0;
    }
    return (ULONG)known;
}

/* ---- Stub side ---- */

HRESULT STDMETHODCALLTYPE OpcStubBuffer_Invoke(IRpcStubBuffer *This, RPCOLEMESSAGE *msg, IRpcChannelBuffer *channel)
{
    const CInterfaceStubVtbl *vtbl = CONTAINING_RECORD(This->lpVtbl, CInterfaceStubVtbl, Vtbl);
    const OpcProxyStubChecks *c = checks;
    int index = interface_index(vtbl->header.piid);
    HRESULT hr;

    if (!msg || index < 0 || !c) return BAD_STUB_DATA;
    hr = c->request((ULONG)index, method_of(msg), msg->Buffer, msg->cbBuffer, msg->dataRepresentation,
                    reads_wine_layout(), NULL);
    if (FAILED(hr)) return hr;
    return CStdStubBuffer_Invoke(This, msg, channel);
}

/* ---- Proxy side: the checking channel ---- */
/* (The vtables below are not const: mingw-w64 declares lpVtbl without const unless CONST_VTABLE.) */

/* Where a refused reply's buffer points once the real channel has freed it, so that the proxy's
 * FreeBuffer afterwards frees nothing twice. */
static const unsigned char refused_reply[4];

typedef struct checked_channel {
    IRpcChannelBuffer IRpcChannelBuffer_iface;
    LONG refs;
    IRpcChannelBuffer *inner;
    ULONG index;
} checked_channel;

static checked_channel *channel_impl(IRpcChannelBuffer *iface)
{
    return CONTAINING_RECORD(iface, checked_channel, IRpcChannelBuffer_iface);
}

static HRESULT STDMETHODCALLTYPE channel_QueryInterface(IRpcChannelBuffer *iface, REFIID riid, void **ppv)
{
    if (!ppv) return E_POINTER;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IRpcChannelBuffer)) {
        *ppv = iface;
        IRpcChannelBuffer_AddRef(iface);
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}

static ULONG STDMETHODCALLTYPE channel_AddRef(IRpcChannelBuffer *iface)
{
    return (ULONG)InterlockedIncrement(&channel_impl(iface)->refs);
}

static ULONG STDMETHODCALLTYPE channel_Release(IRpcChannelBuffer *iface)
{
    checked_channel *This = channel_impl(iface);
    LONG refs = InterlockedDecrement(&This->refs);
    if (!refs) {
        IRpcChannelBuffer_Release(This->inner);
        HeapFree(GetProcessHeap(), 0, This);
    }
    return (ULONG)refs;
}

static HRESULT STDMETHODCALLTYPE channel_GetBuffer(IRpcChannelBuffer *iface, RPCOLEMESSAGE *msg, REFIID riid)
{
    return IRpcChannelBuffer_GetBuffer(channel_impl(iface)->inner, msg, riid);
}

static HRESULT STDMETHODCALLTYPE channel_SendReceive(IRpcChannelBuffer *iface, RPCOLEMESSAGE *msg, ULONG *status)
{
    checked_channel *This = channel_impl(iface);
    const OpcProxyStubChecks *c = checks;
    ULONG method = method_of(msg), context[OPC_PS_CONTEXT_WORDS];
    HRESULT hr, check;

    if (!c) return BAD_STUB_DATA;
    /* The proxy sends nothing opccomn's stub would refuse (a count beyond the bound), whoever the peer
     * is; the proxy then frees its request buffer through FreeBuffer as after any failed call. The
     * check keeps what the reply check needs of the request (Next's celt). */
    hr = c->request(This->index, method, msg->Buffer, msg->cbBuffer, NDR_LOCAL_DATA_REPRESENTATION,
                    reads_wine_layout(), context);
    if (FAILED(hr)) return hr;
    hr = IRpcChannelBuffer_SendReceive(This->inner, msg, status);
    if (hr == (HRESULT)RPC_S_CALL_FAILED)
        /* The proxy reads the fault code from the buffer. */
        check = msg->cbBuffer >= sizeof(DWORD) ? S_OK : BAD_STUB_DATA;
    else if (hr != S_OK)
        return hr;
    else
        check = c->reply(This->index, method, context, msg->Buffer, msg->cbBuffer, msg->dataRepresentation,
                         reads_wine_layout());
    if (FAILED(check)) {
        IRpcChannelBuffer_FreeBuffer(This->inner, msg);
        msg->Buffer = (void *)refused_reply;
        msg->cbBuffer = 0;
        return check;
    }
    return hr;
}

static HRESULT STDMETHODCALLTYPE channel_FreeBuffer(IRpcChannelBuffer *iface, RPCOLEMESSAGE *msg)
{
    if (msg && msg->Buffer == (void *)refused_reply) {
        msg->Buffer = NULL;
        return S_OK;
    }
    return IRpcChannelBuffer_FreeBuffer(channel_impl(iface)->inner, msg);
}

static HRESULT STDMETHODCALLTYPE channel_GetDestCtx(IRpcChannelBuffer *iface, DWORD *context, void **pv)
{
    return IRpcChannelBuffer_GetDestCtx(channel_impl(iface)->inner, context, pv);
}

static HRESULT STDMETHODCALLTYPE channel_IsConnected(IRpcChannelBuffer *iface)
{
    return IRpcChannelBuffer_IsConnected(channel_impl(iface)->inner);
}

static IRpcChannelBufferVtbl checked_channel_vtbl = {
    channel_QueryInterface, channel_AddRef,    channel_Release,    channel_GetBuffer,
    channel_SendReceive,    channel_FreeBuffer, channel_GetDestCtx, channel_IsConnected,
};

/* ---- Proxy side: the proxy buffer that connects the proxy to a checked channel ---- */

typedef struct checked_proxy {
    IRpcProxyBuffer IRpcProxyBuffer_iface;
    LONG refs;
    IRpcProxyBuffer *inner;
    ULONG index;
} checked_proxy;

static checked_proxy *proxy_impl(IRpcProxyBuffer *iface)
{
    return CONTAINING_RECORD(iface, checked_proxy, IRpcProxyBuffer_iface);
}

static HRESULT STDMETHODCALLTYPE proxy_QueryInterface(IRpcProxyBuffer *iface, REFIID riid, void **ppv)
{
    if (!ppv) return E_POINTER;
    if (IsEqualIID(riid, &IID_IRpcProxyBuffer)) {
        *ppv = iface;
        IRpcProxyBuffer_AddRef(iface);
        return S_OK;
    }
    /* IUnknown and the interface: the runtime's proxy, as without the wrapper. */
    return IRpcProxyBuffer_QueryInterface(proxy_impl(iface)->inner, riid, ppv);
}

static ULONG STDMETHODCALLTYPE proxy_AddRef(IRpcProxyBuffer *iface)
{
    return (ULONG)InterlockedIncrement(&proxy_impl(iface)->refs);
}

static ULONG STDMETHODCALLTYPE proxy_Release(IRpcProxyBuffer *iface)
{
    checked_proxy *This = proxy_impl(iface);
    LONG refs = InterlockedDecrement(&This->refs);
    if (!refs) {
        IRpcProxyBuffer_Release(This->inner);
        HeapFree(GetProcessHeap(), 0, This);
    }
    return (ULONG)refs;
}

static HRESULT STDMETHODCALLTYPE proxy_Connect(IRpcProxyBuffer *iface, IRpcChannelBuffer *channel)
{
    checked_proxy *This = proxy_impl(iface);
    checked_channel *checked;
    HRESULT hr;

    if (!channel) return E_POINTER;
    checked = HeapAlloc(GetProcessHeap(), 0, sizeof(*checked));
    if (!checked) return E_OUTOFMEMORY;
    checked->IRpcChannelBuffer_iface.lpVtbl = &checked_channel_vtbl;
    checked->refs = 1;
    checked->inner = channel;
    checked->index = This->index;
    IRpcChannelBuffer_AddRef(channel);
    /* The proxy keeps its own reference until Disconnect; ours goes. */
    hr = IRpcProxyBuffer_Connect(This->inner, &checked->IRpcChannelBuffer_iface);
    IRpcChannelBuffer_Release(&checked->IRpcChannelBuffer_iface);
    return hr;
}

static void STDMETHODCALLTYPE proxy_Disconnect(IRpcProxyBuffer *iface)
{
    IRpcProxyBuffer_Disconnect(proxy_impl(iface)->inner);
}

static IRpcProxyBufferVtbl checked_proxy_vtbl = {
    proxy_QueryInterface, proxy_AddRef, proxy_Release, proxy_Connect, proxy_Disconnect,
};

/* ---- The factory: the runtime's, with checked proxies ---- */

static IPSFactoryBuffer *runtime_factory(void)
{
    return (IPSFactoryBuffer *)&factory;
}

static HRESULT STDMETHODCALLTYPE factory_QueryInterface(IPSFactoryBuffer *iface, REFIID riid, void **ppv)
{
    if (!ppv) return E_POINTER;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IPSFactoryBuffer)) {
        *ppv = iface;
        IPSFactoryBuffer_AddRef(iface);
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}

/* The runtime's factory counts the references, so that NdrDllCanUnloadNow sees them. */
static ULONG STDMETHODCALLTYPE factory_AddRef(IPSFactoryBuffer *iface)
{
    (void)iface;
    return IPSFactoryBuffer_AddRef(runtime_factory());
}

static ULONG STDMETHODCALLTYPE factory_Release(IPSFactoryBuffer *iface)
{
    (void)iface;
    return IPSFactoryBuffer_Release(runtime_factory());
}

static HRESULT STDMETHODCALLTYPE factory_CreateProxy(IPSFactoryBuffer *iface, IUnknown *outer, REFIID riid,
                                                     IRpcProxyBuffer **proxy, void **ppv)
{
    IRpcProxyBuffer *inner = NULL;
    checked_proxy *checked;
    int index = interface_index(riid);
    HRESULT hr;

    (void)iface;
    if (!proxy || !ppv) return E_POINTER;
    *proxy = NULL;
    *ppv = NULL;
    if (index < 0) return E_NOINTERFACE;
    checked = HeapAlloc(GetProcessHeap(), 0, sizeof(*checked));
    if (!checked) return E_OUTOFMEMORY;
    hr = IPSFactoryBuffer_CreateProxy(runtime_factory(), outer, riid, &inner, ppv);
    if (FAILED(hr)) {
        HeapFree(GetProcessHeap(), 0, checked);
        return hr;
    }
    checked->IRpcProxyBuffer_iface.lpVtbl = &checked_proxy_vtbl;
    checked->refs = 1;
    checked->inner = inner;
    checked->index = (ULONG)index;
    *proxy = &checked->IRpcProxyBuffer_iface;
    return hr;
}

static HRESULT STDMETHODCALLTYPE factory_CreateStub(IPSFactoryBuffer *iface, REFIID riid, IUnknown *server,
                                                    IRpcStubBuffer **stub)
{
    (void)iface;
    /* The stubs' vtables already have the checking Invoke. */
    return IPSFactoryBuffer_CreateStub(runtime_factory(), riid, server, stub);
}

static IPSFactoryBufferVtbl checked_factory_vtbl = {
    factory_QueryInterface, factory_AddRef, factory_Release, factory_CreateProxy, factory_CreateStub,
};

static IPSFactoryBuffer checked_factory = {&checked_factory_vtbl};

HRESULT OpcProxyStubGetClassObject(REFCLSID rclsid, REFIID riid, void **ppv, const OpcProxyStubChecks *library_checks)
{
    IPSFactoryBuffer *runtime = NULL;
    HRESULT hr;

    if (!ppv) return E_POINTER;
    *ppv = NULL;
    checks = library_checks;
    /* Initialises the runtime's factory (and checks rclsid) on first use: one call at a time. The
     * runtime's first call marks the factory initialised before it has filled in the stub vtables'
     * missing methods (Wine's NdrDllGetClassObject does), so a second thread calling meanwhile (COM
     * loads a proxy/stub on whichever threads first marshal its interfaces) would get a factory whose
     * stubs call through NULL. */
    AcquireSRWLockExclusive(&factory_lock);
    hr = NdrDllGetClassObject(rclsid, &IID_IPSFactoryBuffer, (void **)&runtime, (const ProxyFileInfo **)proxy_files,
                              &CLSID_OpcComnProxyStub, &factory);
    ReleaseSRWLockExclusive(&factory_lock);
    if (FAILED(hr)) return hr;
    hr = IPSFactoryBuffer_QueryInterface(&checked_factory, riid, ppv);
    IPSFactoryBuffer_Release(runtime);
    return hr;
}

HRESULT OpcProxyStubCanUnloadNow(void)
{
    return NdrDllCanUnloadNow(&factory);
}
