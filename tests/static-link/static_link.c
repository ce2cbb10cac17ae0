/* Calls into every area of the library, for scripts/test-static-link.sh, which links it against the
   static library (libopccomn.a) with exactly the libraries the documentation lists and with those
   `pkg-config --static --libs opccomn` gives, on Linux and with mingw-w64 (x64, x86), and runs it
   (Windows under Wine). A library missing from a list fails the link; the run shows the linked code
   works. One line per area, then "static link: N areas, M failed".

   Areas: error texts, IOPCCommon, MatchPattern, shutdown (server and client side), registration and
   the server browser (over an in-memory registry), the version convention, a server's COM plumbing
   (class factory, the module, the EXE host), DCOM security, the COM entry points, the proxy/stub. */
#include <opccomn/opccomn.h>

#include <stdio.h>
#include <string.h>

/* UTF-16 text on every platform (WCHAR is 16 bits; L"" is 32 bits off Windows). */
#define W(s) ((LPCWSTR)u"" s)

static int areas, failed;

static void area(const char *name, int ok, HRESULT hr) {
    areas++;
    failed += !ok;
    printf("%s %s (last HRESULT 0x%08lX)\n", ok ? "ok  " : "FAIL", name, (unsigned long)(uint32_t)hr);
}

static int same_guid(const GUID *a, const GUID *b) { return memcmp(a, b, sizeof *a) == 0; }

/* {5A1C0DE0-77A2-4C51-9C31-0B5E2A000001}: the class this program registers and serves. */
static const CLSID CLSID_StaticLinkServer = {0x5A1C0DE0, 0x77A2, 0x4C51, {0x9C, 0x31, 0x0B, 0x5E, 0x2A, 0x00, 0x00, 0x01}};

static HRESULT OPCCOMN_CDECL create_server(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    (void)context;
    return OpcCommonCreate(NULL, outer, riid, ppv);
}

static int shutdown_calls;
static void OPCCOMN_CDECL on_shutdown(void *context, LPCWSTR reason) {
    (void)reason;
    ++*(int *)context;
}

static void error_texts(void) {
    LPWSTR text = NULL, symbol = NULL;
    HRESULT hr = OpcGetErrorString(OPC_E_INVALIDFILTER, 0x0409, &text);
    int ok = hr == S_OK && text != NULL;
    OpcTaskMemFree(text);
    hr = OpcErrorSymbol(OPC_E_INVALIDFILTER, 0, &symbol);
    ok = ok && hr == S_OK && symbol != NULL;
    OpcTaskMemFree(symbol);
    area("error texts", ok, hr);
}

static void iopccommon(void) {
    void *p = NULL;
    LPWSTR text = NULL;
    HRESULT hr = OpcCommonCreate(NULL, NULL, OPCCOMN_RIID(IID_IOPCCommon), &p);
    int ok = hr == S_OK && p != NULL;
    if (ok) {
        IOPCCommon *common = (IOPCCommon *)p;
        hr = common->lpVtbl->SetLocaleID(common, 0x0409);
        ok = hr == S_OK;
        hr = common->lpVtbl->GetErrorString(common, OPC_E_INVALIDFILTER, &text);
        ok = ok && hr == S_OK && text != NULL;
        OpcTaskMemFree(text);
        ok = ok && common->lpVtbl->Release(common) == 0;
    }
    area("IOPCCommon", ok, hr);
}

static void match_pattern(void) {
    OpcPattern *pattern = NULL;
    int ok = MatchPatternW(W("Channel1.Device2.Tag7"), W("Channel?.Device[1-3].Tag*"), FALSE) == TRUE;
    HRESULT hr = OpcPatternCompileA("*.Tag#", TRUE, &pattern);
    ok = ok && hr == S_OK && OpcPatternMatchA(pattern, "Device.Tag1") == TRUE &&
         OpcPatternMatchA(pattern, "Device.TagA") == FALSE;
    OpcPatternFree(pattern);
    area("MatchPattern", ok, hr);
}

static void shutdown_both_sides(void) {
    void *server = NULL, *sink = NULL;
    DWORD cookie = 0;
    ULONG notified = 0, not_notified = 0;
    HRESULT hr = OpcShutdownCreate(NULL, OPCCOMN_RIID(IID_IUnknown), &server);
    int ok = hr == S_OK;
    if (ok) hr = OpcShutdownSinkCreate(on_shutdown, &shutdown_calls, OPCCOMN_RIID(IID_IUnknown), &sink);
    ok = ok && hr == S_OK;
    if (ok) hr = OpcShutdownAdvise((IUnknown *)server, (IUnknown *)sink, &cookie);
    ok = ok && hr == S_OK;
    if (ok) hr = OpcShutdownNotifyEx((IUnknown *)server, W("static link"), &notified, &not_notified);
    ok = ok && hr == S_OK && notified == 1 && not_notified == 0 && shutdown_calls == 1;
    if (ok) hr = OpcShutdownUnadvise((IUnknown *)server, cookie);
    ok = ok && hr == S_OK;
    if (sink) ((IUnknown *)sink)->lpVtbl->Release((IUnknown *)sink);
    if (server) ((IUnknown *)server)->lpVtbl->Release((IUnknown *)server);
    area("shutdown (server and client side)", ok, hr);
}

static OpcServerRegistration registration(void) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = CLSID_StaticLinkServer;
    r.prog_id = W("OpcComn.StaticLink.1");
    r.version_independent_prog_id = W("OpcComn.StaticLink");
    r.user_type = W("opccomn static link test");
    r.module_path = W("C:\\StaticLink\\server.exe");
    r.implemented_categories = &CATID_OPCDAServer20;
    r.implemented_category_count = 1;
    return r;
}

static void registration_and_browser(void) {
    OpcRegistry *reg = NULL;
    OpcServerRegistration r = registration();
    void *p = NULL;
    CLSID found;
    HRESULT hr = OpcRegistryCreateMemory(&reg);
    int ok = hr == S_OK;
    if (ok) hr = OpcRegisterServer(&r, reg);
    ok = ok && hr == S_OK;
    if (ok) hr = OpcServerListCreateOver(reg, NULL, OPCCOMN_RIID(IID_IOPCServerList2), &p);
    ok = ok && hr == S_OK;
    if (ok) {
        IOPCServerList2 *list = (IOPCServerList2 *)p;
        memset(&found, 0, sizeof found);
        hr = list->lpVtbl->CLSIDFromProgID(list, W("OpcComn.StaticLink.1"), &found);
        ok = hr == S_OK && same_guid(&found, &CLSID_StaticLinkServer);
        list->lpVtbl->Release(list);
    }
    if (ok) hr = OpcUnregisterServer(&r, reg);
    ok = ok && hr == S_OK;
    OpcRegistryRelease(reg);
    area("registration and the server browser", ok, hr);
}

static void versions(void) {
    OpcVersion v = {0, 0, 0};
    DWORD ms = 0, ls = 0;
    HRESULT hr = OpcVersionParse(W("2.1.7"), &v);
    int ok = hr == S_OK && v.major == 2 && v.minor == 1 && v.build == 7;
    if (ok) hr = OpcVersionToFileVersion(&v, &ms, &ls);
    ok = ok && hr == S_OK && ms == 0x00020001u && ls == 7u;
    area("version convention", ok, hr);
}

static void server_plumbing(void) {
    OpcServerRegistration r = registration();
    OpcServerClass cls;
    OpcExeServerOptions options;
    void *p = NULL, *object = NULL;
    HRESULT hr;
    int ok;
    memset(&cls, 0, sizeof cls);
    cls.struct_size = sizeof cls;
    cls.clsid = &CLSID_StaticLinkServer;
    cls.create = create_server;
    cls.registration = &r;
    hr = OpcClassFactoryCreate(&cls, OPCCOMN_RIID(IID_IClassFactory), &p);
    ok = hr == S_OK;
    if (ok) {
        IClassFactory *factory = (IClassFactory *)p;
        hr = factory->lpVtbl->CreateInstance(factory, NULL, OPCCOMN_RIID(IID_IOPCCommon), &object);
        ok = hr == S_OK && object != NULL;
        if (object) ((IUnknown *)object)->lpVtbl->Release((IUnknown *)object);
        factory->lpVtbl->Release(factory);
    }
    ok = ok && OpcModuleCanUnloadNow() == S_OK;
    /* The EXE host, started as COM starts a server, with no client coming: it registers the class
       object, gives up after 1 ms and ends. Off Windows it checks its options and answers E_NOTIMPL. */
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.classes = &cls;
    options.class_count = 1;
    options.first_client_timeout_ms = 1;
    options.idle_linger_ms = 1;
    hr = OpcExeServerRun(&options, W("server.exe -Embedding"));
#if defined(_WIN32)
    ok = ok && SUCCEEDED(hr);
#else
    ok = ok && hr == E_NOTIMPL;
#endif
    area("server plumbing (class factory, module, EXE host)", ok, hr);
}

static void security(void) {
    /* A proxy is needed for a blanket; the call checks it first, on every platform. */
    HRESULT hr = OpcSetProxyBlanket(NULL, NULL);
    area("DCOM security", hr == E_INVALIDARG, hr);
}

static void com_entry_points(void) {
    void *p = NULL;
    HRESULT hr = OpcDllGetClassObject(&CLSID_OPCServerList, OPCCOMN_RIID(IID_IClassFactory), &p);
    int ok = hr == S_OK && p != NULL;
    if (p) ((IUnknown *)p)->lpVtbl->Release((IUnknown *)p);
    area("COM entry points (the server browser's class object)", ok, hr);
}

static void proxy_stub(void) {
    OpcRegistry *reg = NULL;
    HRESULT hr = OpcRegistryCreateMemory(&reg);
    int ok = hr == S_OK;
#if defined(_WIN32)
    void *p = NULL;
    if (ok) hr = OpcRegisterProxyStub(reg, 0);
    ok = ok && hr == S_OK;
    if (ok) hr = OpcUnregisterProxyStub(reg);
    ok = ok && hr == S_OK;
    /* The factory COM asks opccomn.dll (here, this program) for: the NDR engine's (rpcrt4). */
    if (ok) hr = OpcDllGetClassObject(&CLSID_OpcComnProxyStub, &IID_IPSFactoryBuffer, &p);
    ok = ok && hr == S_OK && p != NULL;
    if (p) ((IUnknown *)p)->lpVtbl->Release((IUnknown *)p);
#else
    if (ok) hr = OpcRegisterProxyStub(reg, 0x80000000u); /* an unknown flag: refused before anything */
    ok = ok && hr == E_INVALIDARG;
#endif
    OpcRegistryRelease(reg);
    area("proxy/stub", ok, hr);
}

int main(void) {
    error_texts();
    iopccommon();
    match_pattern();
    shutdown_both_sides();
    registration_and_browser();
    versions();
    server_plumbing();
    security();
    com_entry_points();
    proxy_stub();
    printf("static link: %d areas, %d failed\n", areas, failed);
    return failed != 0;
}
