/* The Data Access interfaces' part of opccomn.dll's proxy/stub: the NDR tables tools/gen-proxy.py
 * generates from idl/opcda.idl (generated/opcda_p_win64.c, opcda_p_win32.c), compiled on their own
 * because each generated file defines its format strings and stub descriptor under the same static
 * names as opccomn's. Like opccomn's, every stub's IRpcStubBuffer::Invoke is OpcStubBuffer_Invoke
 * (opccomn_ps.c), which has the request checked before the runtime unmarshals it; opccomn_ps.c lists
 * opcda_ProxyFileInfo with opccomn's, and its factory wraps these proxies in the checking channel.
 *
 * Built by buildscript/proxy.rs for Windows targets. */
#define USE_STUBLESS_PROXY
#include <objbase.h>
#include <rpcproxy.h>

/* The IIDs of the Data Access interfaces under the proxy/stub's own names, so that a program that
 * links opccomn statically may define IID_IOPCServer and the others itself. */
#define OPC_PS_PART_NAMES
#include "generated/interfaces.h"
#undef OPC_PS_PART_NAMES

/* mingw-w64 declares these runtime functions only for C++; the generated vtables name them. */
HRESULT STDMETHODCALLTYPE IUnknown_QueryInterface_Proxy(IUnknown *This, REFIID riid, void **ppvObject);
ULONG STDMETHODCALLTYPE IUnknown_AddRef_Proxy(IUnknown *This);
ULONG STDMETHODCALLTYPE IUnknown_Release_Proxy(IUnknown *This);

/* The generated stub vtables (CStdStubBuffer_METHODS) get the checking Invoke. */
HRESULT STDMETHODCALLTYPE OpcStubBuffer_Invoke(IRpcStubBuffer *This, RPCOLEMESSAGE *msg, IRpcChannelBuffer *channel);
#define CStdStubBuffer_Invoke OpcStubBuffer_Invoke
#ifdef _WIN64
#include "generated/opcda_p_win64.c"
#else
#include "generated/opcda_p_win32.c"
#endif
#undef CStdStubBuffer_Invoke

/* Their definitions, and those of the Alarms & Events and HDA interfaces (opc_ae_ps.c, opchda_ps.c). */
#define OPC_PS_PART_IIDS
#include "generated/interfaces.h"
