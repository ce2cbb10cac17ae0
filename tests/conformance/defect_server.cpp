// A test server for opccomn-check with one seeded defect (or none): an in-process OPC server object
// whose IOPCCommon and IOPCShutdown connection point are the library's, reached through thin
// wrappers that forward every call, except the one call the defect breaks. Built once per line of
// defects.txt with -DOPCCOMN_DEFECT=<number> -DOPCCOMN_DEFECT_NAME=L"<name>"; each build registers
// its own class, {7E57DEF0-C0DE-4C0D-9000-0000000000<number, hex>}, as OpcComnTest.Defect.<name>.1.
//
// The defects are those known from widely used implementations (defects.txt lists them, one a line):
// a cookie of 0, S_OK and a text for an unknown code, locales accepted that are not listed,
// EnumConnections that crashes, E_NOINTERFACE where COM says CONNECT_E_NOCONNECTION, S_OK for an
// unknown cookie, no CurVer, an LCID array not in task memory, the sink's QueryInterface failure
// passed on raw, no version resource, a category with a non-standard description, a DA 1.0 server
// without its OPC key, a call that never returns, a NULL out-pointer written through, and an Alarms &
// Events server answering with Data Access texts (a warning, not a failure); number 16 is an Alarms &
// Events server without a defect; 17 and 18 register their AppID with AuthenticationLevel 1 (NONE) and
// 2 (CONNECT), set explicitly, as installers wrote it before Windows' DCOM hardening (KB5004442); 19
// and 20 a connection point that cannot name its container (E_POINTER and NULL) or names another
// object (the library's own container, as a server that forwards without aggregating gets it); 21 and
// 22 error texts that only restate the code ("HRESULT 0xC0040001") or are one text for every code; 23
// a server that lists no English locale (German only), whose texts cannot be compared with the
// published ones (a warning, not a failure).
#include <windows.h>
#include <objbase.h>
#include <ocidl.h>
#include <olectl.h>

#include <opccomn/opccomn.h>

#include <cstdlib>
#include <cstring>
#include <cwchar>

#ifndef OPCCOMN_DEFECT
#error "build with -DOPCCOMN_DEFECT=<number> -DOPCCOMN_DEFECT_NAME=L\"<name>\" (see defects.txt)"
#endif

enum Defect {
    kNone = 0,
    kCookieZero = 1,
    kUnknownCodeOk = 2,
    kLocaleNotListed = 3,
    kEnumConnectionsCrash = 4,
    kFindNonInterface = 5,
    kUnadviseUnknownOk = 6,
    kMissingCurVer = 7,
    kLocalesNotTaskMemory = 8,
    kAdviseRawQi = 9,
    kNoVersionResource = 10,  // (the build leaves out version.rc)
    kCategoryText = 11,
    kDa10NoOpcKey = 12,
    kHangSetClientName = 13,
    kGetLocaleNullCrash = 14,
    kAlarmsEventsDaTexts = 15,  // an Alarms & Events server that tells the library it is Data Access
    kAlarmsEvents = 16,         // an Alarms & Events server without a defect
    kAppIdLevelNone = 17,       // AppID AuthenticationLevel 1 (RPC_C_AUTHN_LEVEL_NONE), given explicitly
    kAppIdLevelConnect = 18,    // AppID AuthenticationLevel 2 (RPC_C_AUTHN_LEVEL_CONNECT), given explicitly
    kPointContainerFails = 19,  // GetConnectionPointContainer: E_POINTER and NULL
    kPointContainerOther = 20,  // GetConnectionPointContainer: the library's container, not the server
    kErrorTextCode = 21,        // every text "HRESULT 0x<code>"
    kErrorTextSame = 22,        // one text for every code
    kNoEnglishLocale = 23,      // only de-DE listed: German texts
};
const int kDefect = OPCCOMN_DEFECT;

#if defined(__GNUC__)
#define DEFECT_EXPORT(type) EXTERN_C __declspec(dllexport) type STDAPICALLTYPE
#else
#define DEFECT_EXPORT(type) EXTERN_C type STDAPICALLTYPE
#endif

namespace {

HMODULE g_module;

const CLSID kClsid = {0x7E57DEF0, 0xC0DE, 0x4C0D, {0x90, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, static_cast<unsigned char>(OPCCOMN_DEFECT)}};

WCHAR g_prog_id[128], g_vi_prog_id[128];
void Names() {
    swprintf(g_prog_id, 128, L"OpcComnTest.Defect.%ls.1", OPCCOMN_DEFECT_NAME);
    swprintf(g_vi_prog_id, 128, L"OpcComnTest.Defect.%ls", OPCCOMN_DEFECT_NAME);
}

// The server object: the controlling IUnknown, with three wrappers as its other interfaces.
class Server;

class CommonWrap final : public IOPCCommon {
public:
    Server *outer = nullptr;
    IOPCCommon *inner = nullptr;
    HRESULT STDMETHODCALLTYPE QueryInterface(REFIID riid, void **ppv) override;
    ULONG STDMETHODCALLTYPE AddRef() override;
    ULONG STDMETHODCALLTYPE Release() override;
    HRESULT STDMETHODCALLTYPE SetLocaleID(LCID lcid) override {
        if (kDefect == kLocaleNotListed) {
            // Accepts whatever it is given: the list and SetLocaleID disagree.
            HRESULT hr = inner->SetLocaleID(lcid);
            if (hr == E_INVALIDARG) m_forced = lcid, m_forced_set = true;
            else m_forced_set = false;
            return S_OK;
        }
        return inner->SetLocaleID(lcid);
    }
    HRESULT STDMETHODCALLTYPE GetLocaleID(LCID *pdwLcid) override {
        if (kDefect == kGetLocaleNullCrash) {
            LCID lcid = 0;
            inner->GetLocaleID(&lcid);
            LCID *volatile out = pdwLcid;
            *out = lcid;  // no NULL check
            return S_OK;
        }
        if (kDefect == kLocaleNotListed && m_forced_set && pdwLcid) {
            *pdwLcid = m_forced;
            return S_OK;
        }
        return inner->GetLocaleID(pdwLcid);
    }
    HRESULT STDMETHODCALLTYPE QueryAvailableLocaleIDs(DWORD *pdwCount, LCID **pdwLcid) override {
        HRESULT hr = inner->QueryAvailableLocaleIDs(pdwCount, pdwLcid);
        if (kDefect == kLocalesNotTaskMemory && hr == S_OK) {
            // The array copied into memory of the C runtime's heap, as `new LCID[n]` gives.
            LCID *copy = static_cast<LCID *>(malloc(*pdwCount * sizeof(LCID) + 64));
            memcpy(copy, *pdwLcid, *pdwCount * sizeof(LCID));
            CoTaskMemFree(*pdwLcid);
            *pdwLcid = copy;
        }
        return hr;
    }
    HRESULT STDMETHODCALLTYPE GetErrorString(HRESULT dwError, LPWSTR *ppString) override {
        HRESULT hr = inner->GetErrorString(dwError, ppString);
        if (kDefect == kUnknownCodeOk && hr == E_INVALIDARG && ppString) {
            static const WCHAR unknown[] = L"<UNKNOWN ERROR>";
            *ppString = static_cast<LPWSTR>(CoTaskMemAlloc(sizeof unknown));
            memcpy(*ppString, unknown, sizeof unknown);
            return S_OK;
        }
        if ((kDefect == kErrorTextCode || kDefect == kErrorTextSame) && hr == S_OK && ppString && *ppString) {
            WCHAR text[64] = L"The server could not complete the operation.";  // whatever the code
            if (kDefect == kErrorTextCode) swprintf(text, 64, L"HRESULT 0x%08lX", static_cast<unsigned long>(dwError));
            size_t size = (wcslen(text) + 1) * sizeof(WCHAR);
            CoTaskMemFree(*ppString);
            *ppString = static_cast<LPWSTR>(CoTaskMemAlloc(size));
            if (!*ppString) return E_OUTOFMEMORY;
            memcpy(*ppString, text, size);
        }
        return hr;
    }
    HRESULT STDMETHODCALLTYPE SetClientName(LPCWSTR szName) override {
        if (kDefect == kHangSetClientName) Sleep(INFINITE);  // deadlocked on an internal lock, say
        return inner->SetClientName(szName);
    }

private:
    LCID m_forced = 0;
    bool m_forced_set = false;
};

class PointWrap final : public IConnectionPoint {
public:
    Server *outer = nullptr;
    IConnectionPoint *inner = nullptr;  // the library's connection point
    HRESULT STDMETHODCALLTYPE QueryInterface(REFIID riid, void **ppv) override {
        if (!ppv) return E_POINTER;
        *ppv = nullptr;
        if (!IsEqualIID(riid, IID_IUnknown) && !IsEqualIID(riid, IID_IConnectionPoint)) return E_NOINTERFACE;
        *ppv = static_cast<IConnectionPoint *>(this);
        AddRef();
        return S_OK;
    }
    ULONG STDMETHODCALLTYPE AddRef() override;
    ULONG STDMETHODCALLTYPE Release() override;
    HRESULT STDMETHODCALLTYPE GetConnectionInterface(IID *piid) override { return inner->GetConnectionInterface(piid); }
    HRESULT STDMETHODCALLTYPE GetConnectionPointContainer(IConnectionPointContainer **pp) override;
    HRESULT STDMETHODCALLTYPE Advise(IUnknown *sink, DWORD *pdwCookie) override {
        if (kDefect == kAdviseRawQi && sink && pdwCookie) {
            void *p = nullptr;
            HRESULT hr = sink->QueryInterface(IID_IOPCShutdown, &p);
            if (FAILED(hr)) {
                *pdwCookie = 0;
                return hr;  // E_NOINTERFACE passed on instead of CONNECT_E_CANNOTCONNECT
            }
            static_cast<IUnknown *>(p)->Release();
        }
        HRESULT hr = inner->Advise(sink, pdwCookie);
        if (SUCCEEDED(hr) && pdwCookie) {
            if (*pdwCookie > m_highest) m_highest = *pdwCookie;
            if (kDefect == kCookieZero) *pdwCookie -= 1;  // cookies counted from 0
        }
        return hr;
    }
    HRESULT STDMETHODCALLTYPE Unadvise(DWORD cookie) override {
        if (kDefect == kCookieZero) cookie += 1;
        // Only checks the cookies it handed out: a larger one "succeeds".
        if (kDefect == kUnadviseUnknownOk && cookie > m_highest) return S_OK;
        return inner->Unadvise(cookie);
    }
    HRESULT STDMETHODCALLTYPE EnumConnections(IEnumConnections **ppEnum) override {
        if (kDefect == kEnumConnectionsCrash) {
            // Hands out an enumerator it never created, through a pointer it never checked.
            IEnumConnections *volatile never_created = nullptr;
            return never_created->Clone(ppEnum);
        }
        if (kDefect == kCookieZero) {  // its cookies would not match the library's: not offered
            if (ppEnum) *ppEnum = nullptr;
            return E_NOTIMPL;
        }
        return inner->EnumConnections(ppEnum);
    }

private:
    DWORD m_highest = 0;
};

class ContainerWrap final : public IConnectionPointContainer {
public:
    Server *outer = nullptr;
    IConnectionPointContainer *inner = nullptr;
    HRESULT STDMETHODCALLTYPE QueryInterface(REFIID riid, void **ppv) override;
    ULONG STDMETHODCALLTYPE AddRef() override;
    ULONG STDMETHODCALLTYPE Release() override;
    HRESULT STDMETHODCALLTYPE EnumConnectionPoints(IEnumConnectionPoints **ppEnum) override {
        return inner->EnumConnectionPoints(ppEnum);
    }
    HRESULT STDMETHODCALLTYPE FindConnectionPoint(REFIID riid, IConnectionPoint **ppCP) override;
};

class Server final : public IUnknown {
public:
    static HRESULT Create(REFIID riid, void **ppv) {
        Server *s = new Server();
        HRESULT hr = s->Init();
        if (SUCCEEDED(hr)) hr = s->QueryInterface(riid, ppv);
        s->Release();
        return hr;
    }
    HRESULT STDMETHODCALLTYPE QueryInterface(REFIID riid, void **ppv) override {
        if (!ppv) return E_POINTER;
        *ppv = nullptr;
        if (IsEqualIID(riid, IID_IUnknown)) *ppv = static_cast<IUnknown *>(this);
        else if (IsEqualIID(riid, IID_IOPCCommon)) *ppv = static_cast<IOPCCommon *>(&m_common);
        else if (IsEqualIID(riid, IID_IConnectionPointContainer)) *ppv = static_cast<IConnectionPointContainer *>(&m_container);
        else return E_NOINTERFACE;
        AddRef();
        return S_OK;
    }
    ULONG STDMETHODCALLTYPE AddRef() override { return static_cast<ULONG>(InterlockedIncrement(&m_refs)); }
    ULONG STDMETHODCALLTYPE Release() override {
        LONG refs = InterlockedDecrement(&m_refs);
        if (refs == 0) delete this;
        return static_cast<ULONG>(refs);
    }
    CommonWrap m_common;
    ContainerWrap m_container;
    PointWrap m_point;

private:
    Server() { OpcServerLock(); }
    ~Server() {
        if (m_point.inner) m_point.inner->Release();
        if (m_container.inner) m_container.inner->Release();
        if (m_common.inner) m_common.inner->Release();
        OpcServerUnlock();
    }
    HRESULT Init() {
        m_common.outer = m_container.outer = m_point.outer = this;
        OpcCommonOptions options = {};
        options.struct_size = sizeof options;
        // The kind decides the text of colliding codes: C0040203 is OPC_E_INVALIDBRANCHNAME to an
        // Alarms & Events server, OPC_E_INVALID_PID to Data Access.
        options.server_kind = kDefect == kAlarmsEvents ? OPC_SERVER_KIND_ALARMS_EVENTS : OPC_SERVER_KIND_DATA_ACCESS;
        static const LCID locales[] = {0x0409, 0x0407};
        options.locales = locales;
        options.locale_count = 2;
        if (kDefect == kNoEnglishLocale) options.locales = locales + 1, options.locale_count = 1;
        HRESULT hr = OpcCommonCreate(&options, nullptr, IID_IOPCCommon, reinterpret_cast<void **>(&m_common.inner));
        if (SUCCEEDED(hr))
            hr = OpcShutdownCreate(nullptr, IID_IConnectionPointContainer, reinterpret_cast<void **>(&m_container.inner));
        if (SUCCEEDED(hr)) hr = m_container.inner->FindConnectionPoint(IID_IOPCShutdown, &m_point.inner);
        return hr;
    }
    volatile LONG m_refs = 1;
};

HRESULT CommonWrap::QueryInterface(REFIID riid, void **ppv) { return outer->QueryInterface(riid, ppv); }
ULONG CommonWrap::AddRef() { return outer->AddRef(); }
ULONG CommonWrap::Release() { return outer->Release(); }
HRESULT ContainerWrap::QueryInterface(REFIID riid, void **ppv) { return outer->QueryInterface(riid, ppv); }
ULONG ContainerWrap::AddRef() { return outer->AddRef(); }
ULONG ContainerWrap::Release() { return outer->Release(); }
// The connection point keeps the server object alive, as COM's rules want.
ULONG PointWrap::AddRef() { return outer->AddRef(); }
ULONG PointWrap::Release() { return outer->Release(); }

// The container is the server object; the library's connection point would name its own container
// object, which this server only forwards to.
HRESULT PointWrap::GetConnectionPointContainer(IConnectionPointContainer **pp) {
    if (kDefect == kPointContainerFails) {
        if (pp) *pp = nullptr;
        return E_POINTER;  // as if the point kept no way back to its container
    }
    if (kDefect == kPointContainerOther) return inner->GetConnectionPointContainer(pp);
    if (!pp) return E_POINTER;
    *pp = &outer->m_container;
    outer->AddRef();
    return S_OK;
}

HRESULT ContainerWrap::FindConnectionPoint(REFIID riid, IConnectionPoint **ppCP) {
    if (!ppCP) return E_POINTER;
    *ppCP = nullptr;
    if (IsEqualIID(riid, IID_IOPCShutdown)) {
        *ppCP = &outer->m_point;
        outer->AddRef();
        return S_OK;
    }
    if (kDefect == kFindNonInterface) return E_NOINTERFACE;
    return inner->FindConnectionPoint(riid, ppCP);
}

HRESULT OPCCOMN_CDECL CreateServer(void *, IUnknown *, REFIID riid, void **ppv) { return Server::Create(riid, ppv); }

// The class for the library's class object (no aggregation: the library refuses an outer object).
const OpcServerClass kClass = {sizeof(OpcServerClass), &kClsid, CreateServer, nullptr, 0, nullptr};

// DX 1.0 with a description of its own making (the standard one is "OPC Data Exchange Servers Version 1.0").
const CATID kDx10 = {0xA0C85BB8, 0x4161, 0x4fd6, {0x86, 0x55, 0xBB, 0x58, 0x46, 0x01, 0xC9, 0xE0}};

HRESULT Register(bool add) {
    Names();
    WCHAR path[MAX_PATH];
    DWORD length = GetModuleFileNameW(g_module, path, MAX_PATH);
    if (length == 0 || length >= MAX_PATH) return E_FAIL;
    static const CATID da20[] = {CATID_OPCDAServer20};
    static const CATID ae10[] = {CATID_OPCAEServer10};
    static const CATID da10[] = {CATID_OPCDAServer10, CATID_OPCDAServer20};
    static const CATID with_dx[] = {CATID_OPCDAServer20, kDx10};
    static const LPCWSTR dx_texts[] = {nullptr, L"OPC DX Servers"};
    OpcServerRegistration r = {};
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_INPROC;
    r.clsid = kClsid;
    r.prog_id = g_prog_id;
    r.version_independent_prog_id = g_vi_prog_id;
    r.user_type = L"opccomn conformance test server";
    r.module_path = path;
    r.threading_model = L"Both";
    // An AppID with a DllSurrogate: CLSCTX_LOCAL_SERVER runs the DLL in the system's surrogate
    // (dllhost.exe), so the same defects are checked out of process, through the proxy/stub. "" means
    // the system's surrogate of the DLL's bitness; the 64-bit build names the 64-bit dllhost.exe
    // explicitly, because Wine (8.0) starts the 32-bit one for "" whatever the client's bitness.
    WCHAR surrogate[MAX_PATH + 16] = L"";
    if (sizeof(void *) == 8) {
        UINT n = GetSystemDirectoryW(surrogate, MAX_PATH);
        if (n == 0 || n >= MAX_PATH) return E_FAIL;
        wcscat(surrogate, L"\\dllhost.exe");
    }
    r.app_id = &kClsid;
    r.app_id_dll_surrogate = surrogate;
    r.implemented_categories = da20;
    r.implemented_category_count = 1;
    if (kDefect == kCategoryText) {
        r.implemented_categories = with_dx;
        r.implemented_category_count = 2;
        r.implemented_category_descriptions = dx_texts;
    }
    if (kDefect == kAlarmsEventsDaTexts || kDefect == kAlarmsEvents) r.implemented_categories = ae10;
    if (kDefect == kDa10NoOpcKey) {
        r.implemented_categories = da10;  // DA 1.0 claimed, but no da10_vendor: no ProgID\OPC key
        r.implemented_category_count = 2;
    }
    if (kDefect == kAppIdLevelNone || kDefect == kAppIdLevelConnect) {
        // Permissions as the library's examples set them, so that the level is the one defect.
        r.app_id_access_permission = L"O:BAG:BAD:(A;;0x7;;;AU)(A;;0x7;;;SY)";
        r.app_id_launch_permission = L"O:BAG:BAD:(A;;0x1F;;;AU)(A;;0x1F;;;SY)";
        r.app_id_authentication_level = kDefect == kAppIdLevelNone ? 1 : 2;
    }
    if (!add) return OpcUnregisterServer(&r, nullptr);
    HRESULT hr = OpcRegisterServer(&r, nullptr);
    if (SUCCEEDED(hr) && kDefect == kMissingCurVer) {
        WCHAR key[160];
        swprintf(key, 160, L"%ls\\CurVer", g_vi_prog_id);
        RegDeleteKeyW(HKEY_CLASSES_ROOT, key);
    }
    return hr;
}

}  // namespace

extern "C" BOOL WINAPI DllMain(HINSTANCE instance, DWORD reason, LPVOID) {
    if (reason == DLL_PROCESS_ATTACH) {
        g_module = instance;
        DisableThreadLibraryCalls(instance);
    }
    return TRUE;
}

DEFECT_EXPORT(HRESULT) DllGetClassObject(REFCLSID rclsid, REFIID riid, void **ppv) {
    return OpcModuleGetClassObject(&kClass, 1, rclsid, riid, ppv);
}

DEFECT_EXPORT(HRESULT) DllCanUnloadNow() { return OpcModuleCanUnloadNow(); }
DEFECT_EXPORT(HRESULT) DllRegisterServer() { return Register(true); }
DEFECT_EXPORT(HRESULT) DllUnregisterServer() { return Register(false); }
