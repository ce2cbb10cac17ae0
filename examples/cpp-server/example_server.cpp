// The example server object: see example_server.h.
#include "example_server.h"

#include <cstring>
#include <cwchar>
#include <new>

namespace {

// ---- The address space: a few items, sorted by item ID ----
struct Item {
    LPCWSTR id;
    double value;
    bool online;  // false: the device does not answer
};
const Item kItems[] = {
    {L"Device1.Pressure", 1.013, true},
    {L"Device1.Temperature", 21.5, true},
    {L"Device2.Level", 0.0, false},
    {L"Device2.Temperature", 19.25, true},
    {L"Simulation.Ramp", 42.0, true},
};
const DWORD kItemCount = sizeof kItems / sizeof kItems[0];

LPWSTR CoTaskMemStrDup(LPCWSTR s) {
    size_t bytes = (wcslen(s) + 1) * sizeof(WCHAR);
    LPWSTR copy = static_cast<LPWSTR>(CoTaskMemAlloc(bytes));
    if (copy) memcpy(copy, s, bytes);
    return copy;
}

// ---- IOPCCommon configuration: the server's locales and the texts of its own error codes ----
const LCID kLocales[] = {MAKELCID(MAKELANGID(LANG_ENGLISH, SUBLANG_ENGLISH_US), SORT_DEFAULT),
                         MAKELCID(MAKELANGID(LANG_GERMAN, SUBLANG_GERMAN), SORT_DEFAULT)};

// Asked by GetErrorString before the library's catalog of OPC texts; S_FALSE leaves a code to it.
HRESULT VendorErrorString(void *, HRESULT code, LCID locale, LPCWSTR *text) {
    if (code != EXAMPLE_E_DEVICEOFFLINE) return S_FALSE;
    *text = PRIMARYLANGID(LANGIDFROMLCID(locale)) == LANG_GERMAN ? L"Das Ger\u00e4t antwortet nicht."
                                                                  : L"The device does not answer.";
    return S_OK;
}

// ---- The server object ----
class ExampleServer final : public IExampleAddressSpace {
public:
    static HRESULT Create(REFIID riid, void **ppv);

    // IUnknown: the controlling unknown of the aggregate.
    HRESULT STDMETHODCALLTYPE QueryInterface(REFIID riid, void **ppv) override;
    ULONG STDMETHODCALLTYPE AddRef() override { return static_cast<ULONG>(InterlockedIncrement(&m_refs)); }
    ULONG STDMETHODCALLTYPE Release() override;

    // IExampleAddressSpace
    HRESULT STDMETHODCALLTYPE BrowseItemIDs(LPCWSTR szFilterCriteria, DWORD *pdwCount, LPWSTR **ppszItemIDs) override;
    HRESULT STDMETHODCALLTYPE ReadValue(LPCWSTR szItemID, double *pdblValue) override;
    HRESULT STDMETHODCALLTYPE RequestShutdown(LPCWSTR szReason) override;

    // Notifies the clients of every live server object; see ExampleNotifyAllServers.
    static HRESULT NotifyAll(LPCWSTR reason, ULONG *servers, const OpcShutdownNotifyOptions *bounded);

private:
    ExampleServer() { OpcServerLock(); }  // counts on the DLL or EXE (OpcModuleCanUnloadNow, the EXE host)
    ~ExampleServer();
    HRESULT Init();
    bool TryAddRef();

    volatile LONG m_refs = 1;       // the creator's reference
    IUnknown *m_common = nullptr;   // inner IUnknown of the IOPCCommon session (OpcCommonCreate)
    IUnknown *m_shutdown = nullptr; // inner IUnknown of the IOPCShutdown connection point (OpcShutdownCreate)
    ExampleServer *m_next = nullptr;
    bool m_linked = false;

    // Every live server object of the module, so that a shutdown reaches all clients.
    static SRWLOCK s_lock;
    static ExampleServer *s_first;
};

SRWLOCK ExampleServer::s_lock = SRWLOCK_INIT;
ExampleServer *ExampleServer::s_first = nullptr;

HRESULT ExampleServer::Create(REFIID riid, void **ppv) {
    ExampleServer *server = new (std::nothrow) ExampleServer();
    if (!server) return E_OUTOFMEMORY;
    HRESULT hr = server->Init();
    if (SUCCEEDED(hr)) hr = server->QueryInterface(riid, ppv);
    server->Release();  // the creator's reference: destroys the object if Init or QueryInterface failed
    return hr;
}

// The aggregated library objects get this object as their outer unknown: their own interfaces'
// QueryInterface, AddRef and Release come back here, so the client sees one COM object.
HRESULT ExampleServer::Init() {
    IUnknown *outer = static_cast<IExampleAddressSpace *>(this);
    OpcCommonOptions options = {};
    options.struct_size = sizeof options;
    options.server_kind = OPC_SERVER_KIND_DATA_ACCESS;
    options.locales = kLocales;
    options.locale_count = sizeof kLocales / sizeof kLocales[0];
    options.vendor_error_string = VendorErrorString;
    HRESULT hr = OpcCommonCreate(&options, outer, IID_IUnknown, reinterpret_cast<void **>(&m_common));
    if (SUCCEEDED(hr)) hr = OpcShutdownCreate(outer, IID_IUnknown, reinterpret_cast<void **>(&m_shutdown));
    if (FAILED(hr)) return hr;
    AcquireSRWLockExclusive(&s_lock);
    m_next = s_first;
    s_first = this;
    m_linked = true;
    ReleaseSRWLockExclusive(&s_lock);
    return S_OK;
}

ExampleServer::~ExampleServer() {
    // The outer object owns the inner objects: one Release each.
    if (m_shutdown) m_shutdown->Release();
    if (m_common) m_common->Release();
    OpcServerUnlock();
}

HRESULT ExampleServer::QueryInterface(REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = nullptr;
    if (IsEqualIID(riid, IID_IUnknown) || IsEqualIID(riid, IID_IExampleAddressSpace)) {
        *ppv = static_cast<IExampleAddressSpace *>(this);
        AddRef();
        return S_OK;
    }
    // ATL: COM_INTERFACE_ENTRY_AGGREGATE(IID_IOPCCommon, m_common) and
    //      COM_INTERFACE_ENTRY_AGGREGATE(IID_IConnectionPointContainer, m_shutdown).
    if (IsEqualIID(riid, IID_IOPCCommon)) return m_common->QueryInterface(riid, ppv);
    if (IsEqualIID(riid, IID_IConnectionPointContainer)) return m_shutdown->QueryInterface(riid, ppv);
    return E_NOINTERFACE;
}

ULONG ExampleServer::Release() {
    LONG refs = InterlockedDecrement(&m_refs);
    if (refs == 0) {
        if (m_linked) {
            AcquireSRWLockExclusive(&s_lock);
            ExampleServer **p = &s_first;
            while (*p != this) p = &(*p)->m_next;
            *p = m_next;
            ReleaseSRWLockExclusive(&s_lock);
        }
        delete this;
    }
    return static_cast<ULONG>(refs);
}

// A reference for NotifyAll, unless the object is already on its way out (count 0).
bool ExampleServer::TryAddRef() {
    LONG refs = m_refs;
    while (refs != 0) {
        LONG seen = InterlockedCompareExchange(&m_refs, refs + 1, refs);
        if (seen == refs) return true;
        refs = seen;
    }
    return false;
}

HRESULT ExampleServer::BrowseItemIDs(LPCWSTR szFilterCriteria, DWORD *pdwCount, LPWSTR **ppszItemIDs) {
    if (pdwCount) *pdwCount = 0;
    if (ppszItemIDs) *ppszItemIDs = nullptr;
    if (!pdwCount || !ppszItemIDs) return E_INVALIDARG;

    // The filter is checked and compiled once, then matched against every item.
    OpcPattern *filter = nullptr;
    if (szFilterCriteria && szFilterCriteria[0]) {
        HRESULT hr = OpcPatternCompileW(szFilterCriteria, FALSE, &filter);
        if (FAILED(hr)) return hr;  // OPC_E_INVALIDFILTER for a malformed filter
    }
    LPWSTR found[kItemCount];
    DWORD count = 0;
    HRESULT hr = S_OK;
    for (const Item &item : kItems) {
        if (filter && !OpcPatternMatchW(filter, item.id)) continue;
        if (!(found[count] = CoTaskMemStrDup(item.id))) {
            hr = E_OUTOFMEMORY;
            break;
        }
        count++;
    }
    OpcPatternFree(filter);

    LPWSTR *ids = nullptr;
    if (SUCCEEDED(hr) && count > 0 && !(ids = static_cast<LPWSTR *>(CoTaskMemAlloc(count * sizeof(LPWSTR)))))
        hr = E_OUTOFMEMORY;
    if (FAILED(hr)) {
        for (DWORD i = 0; i < count; i++) CoTaskMemFree(found[i]);
        return hr;
    }
    if (count > 0) memcpy(ids, found, count * sizeof(LPWSTR));
    *pdwCount = count;
    *ppszItemIDs = ids;
    return count > 0 ? S_OK : S_FALSE;  // S_FALSE: nothing matched, as DA's BrowseOPCItemIDs
}

HRESULT ExampleServer::ReadValue(LPCWSTR szItemID, double *pdblValue) {
    if (pdblValue) *pdblValue = 0.0;
    if (!szItemID || !pdblValue) return E_INVALIDARG;
    for (const Item &item : kItems) {
        if (wcscmp(item.id, szItemID) != 0) continue;
        if (!item.online) return EXAMPLE_E_DEVICEOFFLINE;
        *pdblValue = item.value;
        return S_OK;
    }
    return OPC_E_UNKNOWNITEMID;
}

HRESULT ExampleServer::RequestShutdown(LPCWSTR szReason) { return NotifyAll(szReason, nullptr, nullptr); }

HRESULT ExampleServer::NotifyAll(LPCWSTR reason, ULONG *servers, const OpcShutdownNotifyOptions *bounded) {
    if (servers) *servers = 0;
    // A snapshot with a reference on each object, taken under the lock; the clients are called
    // without it, since a client may release its server object from inside ShutdownRequest.
    AcquireSRWLockExclusive(&s_lock);
    ULONG count = 0;
    for (ExampleServer *s = s_first; s; s = s->m_next) count++;
    ExampleServer **snapshot = new (std::nothrow) ExampleServer *[count ? count : 1];
    ULONG taken = 0;
    if (snapshot) {
        for (ExampleServer *s = s_first; s; s = s->m_next)
            if (s->TryAddRef()) snapshot[taken++] = s;
    }
    ReleaseSRWLockExclusive(&s_lock);
    if (!snapshot) return E_OUTOFMEMORY;

    HRESULT result = S_OK;
    for (ULONG i = 0; i < taken; i++) {
        // IOPCShutdown::ShutdownRequest on every sink advised on this server object.
        IUnknown *server = static_cast<IExampleAddressSpace *>(snapshot[i]);
        HRESULT hr = bounded ? OpcShutdownNotifyBounded(server, reason, bounded, nullptr, nullptr, nullptr)
                             : OpcShutdownNotify(server, reason);
        if (hr != S_OK) result = S_FALSE;
        snapshot[i]->Release();
    }
    delete[] snapshot;
    if (servers) *servers = taken;
    return result;
}

// ---- The class, for the library's class object (IClassFactory) ----
HRESULT OPCCOMN_CDECL CreateExampleServer(void *, IUnknown *outer, REFIID riid, void **ppv) {
    return ExampleServerCreate(outer, riid, ppv);
}

}  // namespace

HRESULT ExampleServerCreate(IUnknown *outer, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = nullptr;
    if (outer) return CLASS_E_NOAGGREGATION;
    return ExampleServer::Create(riid, ppv);
}

OpcServerClass ExampleClass(bool inproc, const OpcServerRegistration *registration) {
    OpcServerClass c = {};
    c.struct_size = sizeof c;
    c.clsid = inproc ? &CLSID_ExampleServerInProc : &CLSID_ExampleServer;
    c.create = CreateExampleServer;  // no aggregation (flags 0): the library refuses an outer object
    c.registration = registration;
    return c;
}

HRESULT ExampleNotifyAllServers(LPCWSTR reason, ULONG *servers, const OpcShutdownNotifyOptions *bounded) {
    return ExampleServer::NotifyAll(reason, servers, bounded);
}

OpcServerRegistration ExampleRegistration(bool inproc, LPCWSTR module_path) {
    static const CATID categories[] = {CATID_ExampleServers};
    static const LPCWSTR descriptions[] = {L"opccomn example servers"};
    OpcServerRegistration r = {};
    r.struct_size = sizeof r;
    r.server_type = inproc ? OPC_SERVER_TYPE_INPROC : OPC_SERVER_TYPE_LOCAL;
    r.clsid = inproc ? CLSID_ExampleServerInProc : CLSID_ExampleServer;
    r.prog_id = inproc ? EXAMPLE_INPROC_PROGID : EXAMPLE_PROGID;
    r.version_independent_prog_id = inproc ? EXAMPLE_INPROC_VERSION_INDEPENDENT_PROGID : EXAMPLE_VERSION_INDEPENDENT_PROGID;
    r.user_type = inproc ? L"opccomn example server (in-process)" : L"opccomn example server";
    r.module_path = module_path;               // NULL: this EXE
    r.threading_model = inproc ? L"Both" : nullptr;  // the object is thread-safe
    r.implemented_categories = categories;
    r.implemented_category_count = 1;
    r.implemented_category_descriptions = descriptions;  // creates the category if it is new
    if (!inproc) {
        // The EXE server's DCOM settings, hardened for Windows' DCOM hardening (KB5004442): calls at
        // PKT_INTEGRITY or above only; authenticated users (AU) and SYSTEM may call it
        // (COM_RIGHTS_EXECUTE | EXECUTE_LOCAL | EXECUTE_REMOTE = 0x7) and start it (and
        // ACTIVATE_LOCAL | ACTIVATE_REMOTE: 0x1F), locally and remotely; anonymous callers may not.
        // The server does not call CoInitializeSecurity, so COM takes these from the AppID.
        // docs/guide/dcom-appid.md explains each part.
        r.app_id = &APPID_ExampleServer;
        r.app_id_access_permission = L"O:BAG:BAD:(A;;0x7;;;AU)(A;;0x7;;;SY)";
        r.app_id_launch_permission = L"O:BAG:BAD:(A;;0x1F;;;AU)(A;;0x1F;;;SY)";
        r.app_id_authentication_level = OPC_AUTHN_LEVEL_PKT_INTEGRITY;
    }
    return r;
}
