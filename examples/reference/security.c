/* The examples of the C API reference's pages "DCOM security" and "Proxy/stub" (docs/reference/areas.dox
 * shows the lines between their snippet markers), built and run by ctest
 * (example.reference_security) on Linux and under Wine, C11 with warnings as errors. Off Windows the
 * security functions check their arguments and return E_NOTIMPL. */
#include <string.h>

#include "example.h"

/* [security] */
/* A server, early in main: after CoInitializeEx, before registering its class objects. PKT_INTEGRITY,
 * and who may call from its AppID's access permission (dcomcnfg's settings). */
static HRESULT SecureServerProcess(const CLSID *app_id) {
    OpcSecurityOptions options;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.appid = app_id; /* NULL: everyone who authenticates at PKT_INTEGRITY */
    return OpcInitializeServerSecurity(&options);
}

/* A client that cannot set its process security (a plug-in): PKT_INTEGRITY on one proxy. */
static HRESULT SecureProxy(IUnknown *proxy) {
    return OpcSetProxyBlanket(proxy, NULL); /* and on each further interface queried from it */
}
/* [security] */

/* [proxystub] */
/* An installer makes opccomn.dll the proxy/stub of the OPC Common, DA, A&E and HDA interfaces (what
 * `regsvr32 /n /i:ProxyStub opccomn.dll` does), leaving the OPC Foundation's where it is installed;
 * at uninstall it takes back only what it wrote. NULL is the system registry. */
static HRESULT InstallProxyStub(const OpcRegistry *reg) {
    HRESULT hr = OpcRegisterProxyStub(reg, 0); /* OPC_PROXY_STUB_TAKE_OVER: replace the Foundation's */
    return hr;                                 /* S_OK; S_FALSE when some interfaces keep another */
}

static HRESULT UninstallProxyStub(const OpcRegistry *reg) {
    return OpcUnregisterProxyStub(reg);
}
/* [proxystub] */

int main(void) {
#if defined(_WIN32)
    CoInitializeEx(NULL, COINIT_MULTITHREADED);
    const HRESULT expected = S_OK;
#else
    const HRESULT expected = E_NOTIMPL;
#endif
    check(SecureServerProcess(NULL) == expected, "OpcInitializeServerSecurity");
    IUnknown *object = NULL;
    check(OpcCommonCreate(NULL, NULL, &IID_IUnknown, (void **)&object) == S_OK, "an in-process object");
    if (object) {
#if defined(_WIN32)
        check(SecureProxy(object) == E_NOINTERFACE, "an in-process object is no proxy");
#else
        check(SecureProxy(object) == E_NOTIMPL, "OpcSetProxyBlanket off Windows");
#endif
        object->lpVtbl->Release(object);
    }

    OpcRegistry *reg = NULL;
    check(OpcRegistryCreateMemory(&reg) == S_OK, "a registry in memory");
    check(InstallProxyStub(reg) == S_OK, "OpcRegisterProxyStub");
    LPWSTR clsid = NULL;
    check(OpcRegistryGetString(reg, u"Interface\\{F31DFDE2-07B6-11d2-B2D8-0060083BA1FB}\\ProxyStubClsid32", NULL,
                               &clsid) == S_OK,
          "IOPCCommon's proxy/stub");
    OpcTaskMemFree(clsid);
    check(UninstallProxyStub(reg) == S_OK, "OpcUnregisterProxyStub");
    check(OpcRegistryGetString(reg, u"Interface\\{F31DFDE2-07B6-11d2-B2D8-0060083BA1FB}\\ProxyStubClsid32", NULL,
                               &clsid) == REGDB_E_KEYMISSING,
          "nothing left");
    OpcRegistryRelease(reg);
    check(OpcObjectCount() == 0, "every object released");
#if defined(_WIN32)
    CoUninitialize();
#endif
    return report("reference security (DCOM security, proxy/stub)");
}
