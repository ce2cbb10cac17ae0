// A small OPC Data Access-like server object in plain C++ (no ATL), built on opccomn:
//
// - IOPCCommon comes from OpcCommonCreate and IConnectionPointContainer (the IOPCShutdown connection
//   point) from OpcShutdownCreate, both aggregated: QueryInterface forwards those IIDs to the inner
//   objects, the destructor releases them.
// - IExampleAddressSpace, the server's own interface, browses a few items with a compiled filter
//   (OpcPatternCompileW / OpcPatternMatchW) and reads their values.
// - Registration is described once, in ExampleRegistration, and written and removed by the library's
//   EXE host (OpcExeServerRun: /RegServer, /UnregServer) and DLL entry points (OpcModuleRegister,
//   OpcModuleUnregister).
//
// The same class is served by an EXE (LocalServer32, exe_main.cpp) and by a DLL (InprocServer32,
// dll_main.cpp) under two class identifiers.
#ifndef OPCCOMN_EXAMPLE_SERVER_H
#define OPCCOMN_EXAMPLE_SERVER_H

#include <opccomn/opccomn.h>

// The example's interface, declared as MIDL declares interfaces (what `midl example.idl` would give
// for `interface IExampleAddressSpace : IUnknown`).
//
// [object, uuid(9834816C-39E4-4BB0-81F9-E2B53C38BE33), pointer_default(unique)]
// interface IExampleAddressSpace : IUnknown {
//     HRESULT BrowseItemIDs([in, string, unique] LPCWSTR szFilterCriteria, [out] DWORD *pdwCount,
//                           [out, size_is(,*pdwCount), string] LPWSTR **ppszItemIDs);
//     HRESULT ReadValue([in, string] LPCWSTR szItemID, [out] double *pdblValue);
//     HRESULT RequestShutdown([in, string, unique] LPCWSTR szReason);
// };
EXTERN_C const IID IID_IExampleAddressSpace;
MIDL_INTERFACE("9834816C-39E4-4BB0-81F9-E2B53C38BE33")
IExampleAddressSpace : public IUnknown {
public:
    // The item IDs matching `szFilterCriteria` (MatchPattern syntax, case-insensitive; NULL or ""
    // matches every item), sorted, as a CoTaskMem array of CoTaskMem strings.
    // OPC_E_INVALIDFILTER for a malformed filter; E_INVALIDARG for NULL out-parameters.
    virtual HRESULT STDMETHODCALLTYPE BrowseItemIDs(LPCWSTR szFilterCriteria, DWORD *pdwCount, LPWSTR **ppszItemIDs) = 0;
    // The current value of an item. OPC_E_UNKNOWNITEMID for an item the server does not have,
    // EXAMPLE_E_DEVICEOFFLINE for an item whose device does not answer.
    virtual HRESULT STDMETHODCALLTYPE ReadValue(LPCWSTR szItemID, double *pdblValue) = 0;
    // What the server's operator does when taking the server down: asks every client of every
    // server object of this module to disconnect (IOPCShutdown::ShutdownRequest, through
    // OpcShutdownNotify). S_OK when every advised client accepted, S_FALSE when one failed.
    virtual HRESULT STDMETHODCALLTYPE RequestShutdown(LPCWSTR szReason) = 0;
};
#ifdef __CRT_UUID_DECL
__CRT_UUID_DECL(IExampleAddressSpace, 0x9834816c, 0x39e4, 0x4bb0, 0x81, 0xf9, 0xe2, 0xb5, 0x3c, 0x38, 0xbe, 0x33)
#endif

// The EXE server (LocalServer32) and the DLL server (InprocServer32): the same class.
EXTERN_C const CLSID CLSID_ExampleServer;
EXTERN_C const CLSID CLSID_ExampleServerInProc;
// The EXE server's AppID (DCOM settings; see ExampleRegistration).
EXTERN_C const GUID APPID_ExampleServer;
// The category both are registered in.
EXTERN_C const CATID CATID_ExampleServers;
#define EXAMPLE_PROGID L"OpcComn.ExampleServer.1"
#define EXAMPLE_VERSION_INDEPENDENT_PROGID L"OpcComn.ExampleServer"
#define EXAMPLE_INPROC_PROGID L"OpcComn.ExampleServerInProc.1"
#define EXAMPLE_INPROC_VERSION_INDEPENDENT_PROGID L"OpcComn.ExampleServerInProc"

// The EXE server's stop command: a named event its operator's tools (a service manager, an installer)
// set to take the server down; the server then asks its clients to disconnect. Ctrl+C does the same.
#define EXAMPLE_STOP_EVENT L"Local\\OpcComnExampleServerStop"

// OPC Data Access codes the example returns (as opcerror.h defines them).
#ifndef OPC_E_UNKNOWNITEMID
#define OPC_E_UNKNOWNITEMID ((HRESULT)0xC0040007L)
#endif
// The server's own code: FACILITY_ITF, with a number no OPC specification uses (their codes stay
// below 0x8000 in the low word).
#define EXAMPLE_E_DEVICEOFFLINE ((HRESULT)0xC0048001L)

// The registration of either server, for its class (OpcServerClass::registration). `module_path`
// NULL means this EXE; a DLL passes its own path.
OpcServerRegistration ExampleRegistration(bool inproc, LPCWSTR module_path);

// Creates a server object (one per client connection, as OPC DA servers do) and returns the
// interface `riid` of it. CLASS_E_NOAGGREGATION when `outer` is not NULL.
HRESULT ExampleServerCreate(IUnknown *outer, REFIID riid, void **ppv);

// The server's class, for the library's class object and its DLL and EXE plumbing
// (OpcModuleGetClassObject, OpcExeServerRun), with what /RegServer and DllRegisterServer write for it
// (`registration`, may be NULL). Each server object counts on the module (OpcServerLock) while it lives.
OpcServerClass ExampleClass(bool inproc, const OpcServerRegistration *registration);

// Asks the clients of every live server object of this module to disconnect (RequestShutdown, and
// the EXE when its operator stops it). `*servers` (optional) receives the number of server objects.
// S_OK when every advised client accepted, S_FALSE when one failed (or did not answer in time).
// Call it with COM initialised. With `bounded` (the EXE, from its multithreaded apartment) the
// clients are notified at once and waited for only until its deadlines (OpcShutdownNotifyBounded):
// a hung client cannot keep the server from stopping. Without it each is waited for in turn
// (OpcShutdownNotify), which a caller in a single-threaded apartment whose own sinks must be called
// on its thread needs (the in-process server's RequestShutdown).
HRESULT ExampleNotifyAllServers(LPCWSTR reason, ULONG *servers, const OpcShutdownNotifyOptions *bounded = nullptr);

#endif
