/* opc_classic_widl_ps.dll: a proxy/stub DLL for the OPC Data Access, Alarms & Events and Historical
 * Data Access interfaces, built the way a MIDL proxy/stub DLL is, from the tables widl generates from
 * idl/opcda.idl, idl/opc_ae.idl and idl/opchda.idl (made at build time by tools/gen-proxy.py --out,
 * corrected like the committed copy; one object per file, classic_ps_tables.c) and MIDL's dlldata
 * routines: the stand-in for the Foundation's proxy/stub of those interfaces. The cross-process DA test
 * (test_da_tables.c with da_server.c) uses it on the client's side against opccomn.dll's on the
 * server's ("classic"), registered per process (da.h). Its CLSID is the tests' own. A test fixture,
 * never shipped. */
#define USE_STUBLESS_PROXY
#define REGISTER_PROXY_DLL
#define PROXY_CLSID_IS {0xC3000000, 0x5EED, 0x4000, {0x80, 0x00, 0x00, 0x00, 0x00, 0x00, 0xDA, 0x01}}
#include <objbase.h>
#include <rpcproxy.h>

extern const ExtendedProxyFileInfo opcda_ProxyFileInfo;
extern const ExtendedProxyFileInfo opc_ae_ProxyFileInfo;
extern const ExtendedProxyFileInfo opchda_ProxyFileInfo;

PROXYFILE_LIST_START
REFERENCE_PROXY_FILE(opcda),
REFERENCE_PROXY_FILE(opc_ae),
REFERENCE_PROXY_FILE(opchda),
PROXYFILE_LIST_END

DLLDATA_ROUTINES(aProxyFileList, GET_DLL_CLSID)

/* For the tests: the factory's reference count (every live proxy and stub holds one), so a process can
 * tell whether its calls go through this DLL. */
LONG WINAPI ClassicProxyStubRefs(void)
{
    return gPFactory.RefCount;
}
