/* One of the NDR table files tools/gen-proxy.py generates for the OPC Classic interfaces (opcda,
 * opc_ae, opchda), compiled on its own: each defines its own format strings and stub descriptor under
 * the same static names. The build names the file in CLASSIC_PS_TABLES (the one for this target's
 * architecture) and links the three objects into opc_classic_widl_ps.dll (classic_widl_ps.c). A test
 * fixture, never shipped. */
#include <initguid.h> /* the interfaces' IIDs, defined here (selectany: once per DLL) */
#include <objbase.h>

/* mingw-w64 declares these only for C++ (docs: windows-under-wine). */
HRESULT STDMETHODCALLTYPE IUnknown_QueryInterface_Proxy(IUnknown *This, REFIID riid, void **ppvObject);
ULONG STDMETHODCALLTYPE IUnknown_AddRef_Proxy(IUnknown *This);
ULONG STDMETHODCALLTYPE IUnknown_Release_Proxy(IUnknown *This);

#include CLASSIC_PS_TABLES
