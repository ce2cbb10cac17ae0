// A client of the example server, as an OPC client would use it, checking every result:
//
// In-process (opccomn_example_inproc.dll, InprocServer32): registers it with regsvr32, creates it with
// CoCreateInstance by ProgID, calls IOPCCommon, advises shutdown sinks, browses with filters, reads,
// has the server shut down, then unregisters it and checks that the registry is clean.
//
// Out of process (opccomn_example_server.exe, LocalServer32): registers it with `/RegServer` and
// opccomn.dll's proxy/stub of the OPC Common interfaces, activates the EXE with
// CoCreateInstance(CLSCTX_LOCAL_SERVER), calls IOPCCommon across processes, advises a shutdown sink
// that the server calls back when its operator stops it, then unregisters both and checks the
// registry.
//
// Prints "example_client: N passed, M failed"; the exit code is non-zero when a check failed.
#include "example_server.h"

#include <olectl.h>  // CONNECT_E_NOCONNECTION
#include <tlhelp32.h>

#include <cstdio>
#include <cwchar>

namespace {
int g_passed, g_failed;

#define CHECK(cond) check((cond), __LINE__, #cond)
#define CHECK_HR(expr, want) check_hr((expr), (want), __LINE__, #expr)

void check(bool ok, int line, const char *what) {
    if (ok) {
        g_passed++;
    } else {
        g_failed++;
        fprintf(stderr, "example_client.cpp:%d: CHECK failed: %s\n", line, what);
    }
}

void check_hr(HRESULT got, HRESULT want, int line, const char *what) {
    if (got == want) {
        g_passed++;
    } else {
        g_failed++;
        fprintf(stderr, "example_client.cpp:%d: %s returned 0x%08lX, expected 0x%08lX\n", line, what,
                static_cast<unsigned long>(got), static_cast<unsigned long>(want));
    }
}

bool Same(LPCWSTR a, LPCWSTR b) { return a && b && wcscmp(a, b) == 0; }

WCHAR g_dir[MAX_PATH];  // this program's directory, where the servers are

void ModulePath(LPCWSTR name, WCHAR *path) {
    swprintf(path, MAX_PATH, L"%ls\\%ls", g_dir, name);
}

// Runs a program and returns its exit code (-1 if it did not start).
long Run(LPCWSTR command_line) {
    WCHAR line[2 * MAX_PATH + 64];
    wcsncpy(line, command_line, sizeof line / sizeof line[0] - 1);
    line[sizeof line / sizeof line[0] - 1] = 0;
    STARTUPINFOW startup = {};
    startup.cb = sizeof startup;
    PROCESS_INFORMATION process = {};
    if (!CreateProcessW(nullptr, line, nullptr, nullptr, FALSE, 0, nullptr, nullptr, &startup, &process)) return -1;
    WaitForSingleObject(process.hProcess, 60000);
    DWORD code = 0;
    if (!GetExitCodeProcess(process.hProcess, &code)) code = static_cast<DWORD>(-1);
    CloseHandle(process.hThread);
    CloseHandle(process.hProcess);
    return static_cast<long>(code);
}

// Whether a process runs this program (by file name, e.g. the EXE server COM started).
bool ProcessRunning(LPCWSTR exe_name) {
    HANDLE snapshot = CreateToolhelp32Snapshot(TH32CS_SNAPPROCESS, 0);
    if (snapshot == INVALID_HANDLE_VALUE) return false;
    PROCESSENTRY32W entry = {};
    entry.dwSize = sizeof entry;
    bool found = false;
    for (BOOL more = Process32FirstW(snapshot, &entry); more && !found; more = Process32NextW(snapshot, &entry))
        found = lstrcmpiW(entry.szExeFile, exe_name) == 0;
    CloseHandle(snapshot);
    return found;
}

// Registry checks, under HKEY_CLASSES_ROOT.
void GuidString(REFGUID guid, WCHAR *text) { StringFromGUID2(guid, text, 39); }

bool KeyExists(LPCWSTR key) {
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_READ, &h) != ERROR_SUCCESS) return false;
    RegCloseKey(h);
    return true;
}

bool DefaultValue(LPCWSTR key, WCHAR *value, DWORD chars) {
    DWORD bytes = chars * sizeof(WCHAR);
    value[0] = 0;
    return RegGetValueW(HKEY_CLASSES_ROOT, key, nullptr, RRF_RT_REG_SZ, nullptr, value, &bytes) == ERROR_SUCCESS;
}

struct Keys {
    WCHAR clsid[64], module[80], category[128], prog_id[96], prog_id_clsid[112], independent[96];
};

Keys KeysOf(REFCLSID clsid, LPCWSTR module_key, LPCWSTR prog_id, LPCWSTR independent) {
    Keys k;
    WCHAR guid[40], catid[40];
    GuidString(clsid, guid);
    GuidString(CATID_ExampleServers, catid);
    swprintf(k.clsid, 64, L"CLSID\\%ls", guid);
    swprintf(k.module, 80, L"%ls\\%ls", k.clsid, module_key);
    swprintf(k.category, 128, L"%ls\\Implemented Categories\\%ls", k.clsid, catid);
    swprintf(k.prog_id, 96, L"%ls", prog_id);
    swprintf(k.prog_id_clsid, 112, L"%ls\\CLSID", prog_id);
    swprintf(k.independent, 96, L"%ls", independent);
    return k;
}

// The registration the server wrote: its module path, ProgIDs and category.
void CheckRegistered(const Keys &k, LPCWSTR module_path, REFCLSID clsid) {
    WCHAR value[MAX_PATH + 32], guid[40];
    CHECK(DefaultValue(k.module, value, MAX_PATH + 32));
    CHECK(wcsstr(value, module_path) != nullptr || lstrcmpiW(value, module_path) == 0);
    CHECK(KeyExists(k.category));
    GuidString(clsid, guid);
    CHECK(DefaultValue(k.prog_id_clsid, value, MAX_PATH + 32) && lstrcmpiW(value, guid) == 0);
    CHECK(KeyExists(k.independent));
    CLSID from_prog_id = {};
    CHECK_HR(CLSIDFromProgID(k.prog_id, &from_prog_id), S_OK);
    CHECK(IsEqualCLSID(from_prog_id, clsid));
}

// Nothing of the registration is left.
void CheckUnregistered(const Keys &k) {
    CHECK(!KeyExists(k.clsid));
    CHECK(!KeyExists(k.prog_id));
    CHECK(!KeyExists(k.independent));
}

// ---- A shutdown sink written in C++, derived from the MIDL-style IOPCShutdown ----
class ShutdownSink final : public IOPCShutdown {
public:
    HRESULT STDMETHODCALLTYPE QueryInterface(REFIID riid, void **ppv) override {
        if (!ppv) return E_POINTER;
        *ppv = nullptr;
        if (!IsEqualIID(riid, IID_IUnknown) && !IsEqualIID(riid, IID_IOPCShutdown)) return E_NOINTERFACE;
        *ppv = static_cast<IOPCShutdown *>(this);
        AddRef();
        return S_OK;
    }
    ULONG STDMETHODCALLTYPE AddRef() override { return static_cast<ULONG>(InterlockedIncrement(&refs)); }
    ULONG STDMETHODCALLTYPE Release() override { return static_cast<ULONG>(InterlockedDecrement(&refs)); }
    HRESULT STDMETHODCALLTYPE ShutdownRequest(LPCWSTR szReason) override {
        calls++;
        wcsncpy(reason, szReason ? szReason : L"(null)", 127);
        return S_OK;
    }
    volatile LONG refs = 1;  // the client's own; lives on the stack, so Release never deletes
    int calls = 0;
    WCHAR reason[128] = {};
};

// The callback of a sink made by the library (OpcShutdownSinkCreate).
struct CallbackRecord {
    int calls;
    WCHAR reason[128];
};
void OnShutdown(void *context, LPCWSTR reason) {
    CallbackRecord *record = static_cast<CallbackRecord *>(context);
    record->calls++;
    wcsncpy(record->reason, reason, 127);
}

void FreeIds(DWORD count, LPWSTR *ids) {
    for (DWORD i = 0; i < count; i++) CoTaskMemFree(ids[i]);
    CoTaskMemFree(ids);
}

// Browses with a filter and checks the exact result.
void CheckBrowse(IExampleAddressSpace *space, LPCWSTR filter, HRESULT want_hr, DWORD want_count, const LPCWSTR *want) {
    int failed_before = g_failed;
    DWORD count = 0xDEADBEEF;  // garbage: the server must write both out-parameters
    LPWSTR *ids = reinterpret_cast<LPWSTR *>(static_cast<size_t>(0xDEADBEEF));
    HRESULT hr = space->BrowseItemIDs(filter, &count, &ids);
    CHECK_HR(hr, want_hr);
    CHECK(count == want_count);
    CHECK(want_count == 0 ? ids == nullptr : ids != nullptr);
    for (DWORD i = 0; ids && i < count && i < want_count; i++) CHECK(Same(ids[i], want[i]));
    if (ids && count <= 16) FreeIds(count, ids);
    if (g_failed != failed_before) fprintf(stderr, "  (browsing with the filter \"%ls\")\n", filter ? filter : L"(null)");
}

// ---- In-process: the DLL server ----
void TestInProc() {
    WCHAR dll[MAX_PATH], command[2 * MAX_PATH];
    ModulePath(L"opccomn_example_inproc.dll", dll);
    Keys keys = KeysOf(CLSID_ExampleServerInProc, L"InprocServer32", EXAMPLE_INPROC_PROGID,
                       EXAMPLE_INPROC_VERSION_INDEPENDENT_PROGID);
    if (KeyExists(keys.clsid)) {
        printf("example_client: unregistering what an earlier run left registered\n");
        swprintf(command, 2 * MAX_PATH, L"regsvr32.exe /s /u \"%ls\"", dll);
        Run(command);
    }
    CheckUnregistered(keys);

    swprintf(command, 2 * MAX_PATH, L"regsvr32.exe /s \"%ls\"", dll);
    CHECK(Run(command) == 0);
    CheckRegistered(keys, dll, CLSID_ExampleServerInProc);

    // Two clients of the server, each with its own server object (and IOPCCommon session).
    CLSID clsid = {};
    CHECK_HR(CLSIDFromProgID(EXAMPLE_INPROC_PROGID, &clsid), S_OK);
    IOPCCommon *common = nullptr;
    CHECK_HR(CoCreateInstance(clsid, nullptr, CLSCTX_INPROC_SERVER, IID_IOPCCommon, reinterpret_cast<void **>(&common)), S_OK);
    IUnknown *other = nullptr;
    CHECK_HR(CoCreateInstance(clsid, nullptr, CLSCTX_INPROC_SERVER, IID_IUnknown, reinterpret_cast<void **>(&other)), S_OK);
    if (!common || !other) return;

    // IOPCCommon, called C++-style.
    const LCID german = MAKELCID(MAKELANGID(LANG_GERMAN, SUBLANG_GERMAN), SORT_DEFAULT);
    const LCID english = MAKELCID(MAKELANGID(LANG_ENGLISH, SUBLANG_ENGLISH_US), SORT_DEFAULT);
    const LCID japanese = MAKELCID(MAKELANGID(LANG_JAPANESE, SUBLANG_DEFAULT), SORT_DEFAULT);
    LCID lcid = 0;
    CHECK_HR(common->GetLocaleID(&lcid), S_OK);
    CHECK(lcid == LOCALE_SYSTEM_DEFAULT);
    CHECK_HR(common->SetLocaleID(german), S_OK);
    CHECK_HR(common->SetLocaleID(japanese), E_INVALIDARG);  // not one of the server's locales
    CHECK_HR(common->GetLocaleID(&lcid), S_OK);
    CHECK(lcid == german);
    DWORD locale_count = 0;
    LCID *locales = nullptr;
    CHECK_HR(common->QueryAvailableLocaleIDs(&locale_count, &locales), S_OK);
    bool has_english = false, has_german = false, has_japanese = false;
    for (DWORD i = 0; locales && i < locale_count; i++) {
        has_english |= locales[i] == english;
        has_german |= locales[i] == german;
        has_japanese |= locales[i] == japanese;
    }
    CHECK(has_english && has_german && !has_japanese);
    CoTaskMemFree(locales);

    LPWSTR text = nullptr;
    CHECK_HR(common->GetErrorString(OPC_E_UNKNOWNITEMID, &text), S_OK);  // the catalog's German text
    CHECK(Same(text, L"Die Element-ID ist im Adressraum des Servers nicht definiert oder existiert dort nicht mehr."));
    CoTaskMemFree(text);
    CHECK_HR(common->GetErrorString(EXAMPLE_E_DEVICEOFFLINE, &text), S_OK);  // the server's own text
    CHECK(Same(text, L"Das Ger\u00e4t antwortet nicht."));
    CoTaskMemFree(text);
    CHECK_HR(common->SetLocaleID(english), S_OK);
    CHECK_HR(common->GetErrorString(EXAMPLE_E_DEVICEOFFLINE, &text), S_OK);
    CHECK(Same(text, L"The device does not answer."));
    CoTaskMemFree(text);
    CHECK_HR(common->GetErrorString(OPC_E_UNKNOWNITEMID, &text), S_OK);
    CHECK(Same(text, L"The item ID is not defined in the server address space or no longer exists in the server address space."));
    CoTaskMemFree(text);
    CHECK_HR(common->GetErrorString(OPC_E_UNKNOWNITEMID, nullptr), E_INVALIDARG);
    CHECK_HR(common->SetClientName(L"opccomn example client"), S_OK);
    LPWSTR name = nullptr;
    CHECK_HR(OpcCommonGetClientName(common, &name), S_OK);  // what the server sees
    CHECK(Same(name, L"opccomn example client"));
    OpcTaskMemFree(name);

    // The second client's session is its own.
    IOPCCommon *other_common = nullptr;
    CHECK_HR(other->QueryInterface(IID_IOPCCommon, reinterpret_cast<void **>(&other_common)), S_OK);
    if (other_common) {
        CHECK_HR(other_common->GetLocaleID(&lcid), S_OK);
        CHECK(lcid == LOCALE_SYSTEM_DEFAULT);
        other_common->Release();
    }

    // One COM object: every interface leads to the same IUnknown, the aggregated ones included.
    IExampleAddressSpace *space = nullptr;
    IConnectionPointContainer *container = nullptr;
    IUnknown *id_common = nullptr, *id_space = nullptr, *id_container = nullptr;
    CHECK_HR(common->QueryInterface(IID_IConnectionPointContainer, reinterpret_cast<void **>(&container)), S_OK);
    if (!container) return;
    CHECK_HR(container->QueryInterface(IID_IExampleAddressSpace, reinterpret_cast<void **>(&space)), S_OK);
    if (!space) return;
    CHECK_HR(common->QueryInterface(IID_IUnknown, reinterpret_cast<void **>(&id_common)), S_OK);
    CHECK_HR(space->QueryInterface(IID_IUnknown, reinterpret_cast<void **>(&id_space)), S_OK);
    CHECK_HR(container->QueryInterface(IID_IUnknown, reinterpret_cast<void **>(&id_container)), S_OK);
    CHECK(id_common && id_common == id_space && id_space == id_container);
    if (id_common) id_common->Release();
    if (id_space) id_space->Release();
    if (id_container) id_container->Release();
    IOPCShutdown *not_there = nullptr;
    CHECK_HR(space->QueryInterface(IID_IOPCShutdown, reinterpret_cast<void **>(&not_there)), E_NOINTERFACE);

    // Shutdown sinks: one C++ sink advised on the connection point by hand, one library sink
    // advised on the other server object with OpcShutdownAdvise.
    ShutdownSink sink;
    IConnectionPoint *point = nullptr;
    DWORD cookie = 0;
    CHECK_HR(container->FindConnectionPoint(IID_IOPCShutdown, &point), S_OK);
    if (!point) return;
    CHECK_HR(point->Advise(static_cast<IOPCShutdown *>(&sink), &cookie), S_OK);
    CHECK(cookie != 0);
    CHECK(sink.refs > 1);  // the connection holds the sink
    CallbackRecord record = {};
    IUnknown *library_sink = nullptr;
    DWORD other_cookie = 0;
    CHECK_HR(OpcShutdownSinkCreate(OnShutdown, &record, IID_IUnknown, reinterpret_cast<void **>(&library_sink)), S_OK);
    CHECK_HR(OpcShutdownAdvise(other, library_sink, &other_cookie), S_OK);
    CHECK(other_cookie != 0);
    if (library_sink) library_sink->Release();  // the connection keeps its own reference

    // Browsing with filters (MatchPattern syntax, case-insensitive in this server).
    const LPCWSTR all[] = {L"Device1.Pressure", L"Device1.Temperature", L"Device2.Level", L"Device2.Temperature", L"Simulation.Ramp"};
    const LPCWSTR device1[] = {L"Device1.Pressure", L"Device1.Temperature"};
    const LPCWSTR temperatures[] = {L"Device1.Temperature", L"Device2.Temperature"};
    const LPCWSTR not_t[] = {L"Device1.Pressure", L"Device2.Level"};
    CheckBrowse(space, nullptr, S_OK, 5, all);
    CheckBrowse(space, L"", S_OK, 5, all);
    CheckBrowse(space, L"Device1.*", S_OK, 2, device1);
    CheckBrowse(space, L"*TEMP*", S_OK, 2, temperatures);
    CheckBrowse(space, L"Device#.[!T]*", S_OK, 2, not_t);
    CheckBrowse(space, L"Device3.*", S_FALSE, 0, nullptr);
    CheckBrowse(space, L"Device[1.*", OPC_E_INVALIDFILTER, 0, nullptr);  // unclosed [
    CheckBrowse(space, L"[Z-A]*", OPC_E_INVALIDFILTER, 0, nullptr);      // reversed range
    DWORD count = 7;
    CHECK_HR(space->BrowseItemIDs(L"*", &count, nullptr), E_INVALIDARG);
    CHECK(count == 0);

    double value = -1;
    CHECK_HR(space->ReadValue(L"Device1.Temperature", &value), S_OK);
    CHECK(value == 21.5);
    CHECK_HR(space->ReadValue(L"Device9.Temperature", &value), OPC_E_UNKNOWNITEMID);
    CHECK(value == 0.0);
    CHECK_HR(space->ReadValue(L"Device2.Level", &value), EXAMPLE_E_DEVICEOFFLINE);
    CHECK_HR(space->ReadValue(nullptr, &value), E_INVALIDARG);

    // The operator takes the server down: both clients are asked to disconnect.
    CHECK_HR(space->RequestShutdown(L"Maintenance"), S_OK);
    CHECK(sink.calls == 1 && Same(sink.reason, L"Maintenance"));
    CHECK(record.calls == 1 && Same(record.reason, L"Maintenance"));

    // The clients disconnect.
    CHECK_HR(point->Unadvise(cookie), S_OK);
    CHECK_HR(point->Unadvise(cookie), CONNECT_E_NOCONNECTION);
    CHECK(sink.refs == 1);  // the connection let go of the sink
    CHECK_HR(OpcShutdownUnadvise(other, other_cookie), S_OK);
    point->Release();
    container->Release();
    space->Release();
    common->Release();
    other->Release();

    // Nothing keeps the DLL loaded any more.
    HMODULE module = GetModuleHandleW(dll);
    CHECK(module != nullptr);
    typedef HRESULT(STDAPICALLTYPE * CanUnloadFn)();
    CanUnloadFn can_unload = module ? reinterpret_cast<CanUnloadFn>(reinterpret_cast<void *>(GetProcAddress(module, "DllCanUnloadNow"))) : nullptr;
    CHECK(can_unload != nullptr);
    if (can_unload) CHECK_HR(can_unload(), S_OK);

    swprintf(command, 2 * MAX_PATH, L"regsvr32.exe /s /u \"%ls\"", dll);
    CHECK(Run(command) == 0);
    CheckUnregistered(keys);
    CHECK_HR(CLSIDFromProgID(EXAMPLE_INPROC_PROGID, &clsid), CO_E_CLASSSTRING);
}

// ---- Out of process: the EXE server ----

// IOPCCommon and the shutdown callback across processes.
void CrossProcessCalls(IOPCCommon *common) {
    const LCID german = MAKELCID(MAKELANGID(LANG_GERMAN, SUBLANG_GERMAN), SORT_DEFAULT);
    LCID lcid = 0;
    CHECK_HR(common->SetLocaleID(german), S_OK);
    CHECK_HR(common->SetLocaleID(MAKELCID(MAKELANGID(LANG_JAPANESE, SUBLANG_DEFAULT), SORT_DEFAULT)), E_INVALIDARG);
    CHECK_HR(common->GetLocaleID(&lcid), S_OK);
    CHECK(lcid == german);
    DWORD locale_count = 0;
    LCID *locales = nullptr;
    CHECK_HR(common->QueryAvailableLocaleIDs(&locale_count, &locales), S_OK);
    bool has_german = false;
    for (DWORD i = 0; locales && i < locale_count; i++) has_german |= locales[i] == german;
    CHECK(has_german);
    CoTaskMemFree(locales);
    LPWSTR text = nullptr;
    CHECK_HR(common->GetErrorString(OPC_E_UNKNOWNITEMID, &text), S_OK);
    CHECK(Same(text, L"Die Element-ID ist im Adressraum des Servers nicht definiert oder existiert dort nicht mehr."));
    CoTaskMemFree(text);
    text = nullptr;
    CHECK_HR(common->GetErrorString(EXAMPLE_E_DEVICEOFFLINE, &text), S_OK);  // asked in the server process
    CHECK(Same(text, L"Das Ger\u00e4t antwortet nicht."));
    CoTaskMemFree(text);
    CHECK_HR(common->SetClientName(L"opccomn example client"), S_OK);

    // The example's own interface has no proxy/stub (a vendor builds one from its IDL), so COM
    // cannot hand it out across processes.
    IExampleAddressSpace *space = nullptr;
    CHECK_HR(common->QueryInterface(IID_IExampleAddressSpace, reinterpret_cast<void **>(&space)), E_NOINTERFACE);

    // A shutdown sink in this process, called from the server's process when its operator
    // stops it (the named event stands for the operator's command).
    ShutdownSink sink;
    IConnectionPointContainer *container = nullptr;
    IConnectionPoint *point = nullptr;
    DWORD cookie = 0;
    CHECK_HR(common->QueryInterface(IID_IConnectionPointContainer, reinterpret_cast<void **>(&container)), S_OK);
    if (container) CHECK_HR(container->FindConnectionPoint(IID_IOPCShutdown, &point), S_OK);
    if (point) CHECK_HR(point->Advise(static_cast<IOPCShutdown *>(&sink), &cookie), S_OK);
    CHECK(cookie != 0);
    HANDLE stop = OpenEventW(EVENT_MODIFY_STATE, FALSE, EXAMPLE_STOP_EVENT);
    CHECK(stop != nullptr);
    if (stop && cookie) {
        SetEvent(stop);
        // An apartment-threaded client receives calls through its message queue.
        for (DWORD start = GetTickCount(); sink.calls == 0 && GetTickCount() - start < 10000;) {
            MsgWaitForMultipleObjects(0, nullptr, FALSE, 100, QS_ALLINPUT);
            MSG msg;
            while (PeekMessageW(&msg, nullptr, 0, 0, PM_REMOVE)) DispatchMessageW(&msg);
        }
        CHECK(sink.calls == 1 && Same(sink.reason, L"The operator stopped the server."));
    }
    if (stop) CloseHandle(stop);
    if (point) {
        CHECK_HR(point->Unadvise(cookie), S_OK);
        point->Release();
    }
    if (container) container->Release();
    CoDisconnectObject(static_cast<IOPCShutdown *>(&sink), 0);  // no stub may outlive the sink
}

// Waits until the EXE server's process is gone (20 s at most: it serves 5 s after its last release,
// then pauses 1 s, as the library's host does by default); whether it went.
bool LocalServerExits() {
    for (int i = 0; i < 200; i++) {
        if (!ProcessRunning(L"opccomn_example_server.exe")) return true;
        Sleep(100);
    }
    return !ProcessRunning(L"opccomn_example_server.exe");
}

// Whether the EXE server's process is still there after `ms` of looking (it must not exit meanwhile).
bool LocalServerStays(DWORD ms) {
    for (DWORD waited = 0; waited < ms; waited += 100) {
        if (!ProcessRunning(L"opccomn_example_server.exe")) return false;
        Sleep(100);
    }
    return ProcessRunning(L"opccomn_example_server.exe");
}

// COM's rule for local servers: every object the server hands out keeps its process until released,
// not only the server object. Here the client keeps only the connection point's IEnumConnections
// (an object of the library, made by the connection point the server aggregates).
void EnumeratorKeepsTheServer() {
    IOPCCommon *common = nullptr;
    CHECK_HR(CoCreateInstance(CLSID_ExampleServer, nullptr, CLSCTX_LOCAL_SERVER, IID_IOPCCommon, reinterpret_cast<void **>(&common)), S_OK);
    if (!common) return;
    IConnectionPointContainer *container = nullptr;
    IConnectionPoint *point = nullptr;
    IEnumConnections *connections = nullptr;
    CHECK_HR(common->QueryInterface(IID_IConnectionPointContainer, reinterpret_cast<void **>(&container)), S_OK);
    if (container) CHECK_HR(container->FindConnectionPoint(IID_IOPCShutdown, &point), S_OK);
    if (point) CHECK_HR(point->EnumConnections(&connections), S_OK);
    if (point) point->Release();
    if (container) container->Release();
    common->Release();
    if (!connections) return;
    CHECK(LocalServerStays(2000));
    CONNECTDATA data = {};
    ULONG fetched = 99;
    CHECK_HR(connections->Next(1, &data, &fetched), S_FALSE);  // reaches the server: nobody is advised
    CHECK(fetched == 0);
    connections->Release();
    CHECK(LocalServerExits());
}

// A server built from this example exits every time its last client goes (it once could hang for
// good in CoUninitialize under Wine): a run of clients, each starting the server, calling it and
// letting go.
void ServerExitsAfterEveryClient() {
    const int kRuns = 10;
    int exits = 0;
    for (int run = 0; run < kRuns; run++) {
        IOPCCommon *common = nullptr;
        HRESULT hr = CoCreateInstance(CLSID_ExampleServer, nullptr, CLSCTX_LOCAL_SERVER, IID_IOPCCommon,
                                      reinterpret_cast<void **>(&common));
        if (FAILED(hr) || !common) {
            CHECK_HR(hr, S_OK);
            break;
        }
        LCID lcid = 0;
        CHECK_HR(common->GetLocaleID(&lcid), S_OK);
        common->Release();
        if (!LocalServerExits()) break;
        exits++;
    }
    CHECK(exits == kRuns);
    if (exits != kRuns) printf("example_client: the server exited after %d of %d clients\n", exits, kRuns);
}

void TestLocalServer() {
    WCHAR exe[MAX_PATH], command[2 * MAX_PATH];
    ModulePath(L"opccomn_example_server.exe", exe);
    Keys keys = KeysOf(CLSID_ExampleServer, L"LocalServer32", EXAMPLE_PROGID, EXAMPLE_VERSION_INDEPENDENT_PROGID);
    if (KeyExists(keys.clsid)) {
        printf("example_client: unregistering what an earlier run left registered\n");
        swprintf(command, 2 * MAX_PATH, L"\"%ls\" /UnregServer", exe);
        Run(command);
    }
    CheckUnregistered(keys);

    swprintf(command, 2 * MAX_PATH, L"\"%ls\" /RegServer", exe);
    CHECK(Run(command) == 0);
    CheckRegistered(keys, exe, CLSID_ExampleServer);

    // IOPCCommon and IOPCShutdown cross processes through opccomn.dll's proxy/stub, registered here
    // for the test and removed again below (the connection point interfaces use the system's). The
    // registration functions are looked up at run time: against an opccomn.dll without them, COM can
    // only activate the EXE, and the client says so.
    typedef HRESULT(OPCCOMN_CDECL * RegisterProxyStubFn)(const OpcRegistry *, uint32_t);
    typedef HRESULT(OPCCOMN_CDECL * UnregisterProxyStubFn)(const OpcRegistry *);
    HMODULE opccomn = GetModuleHandleW(L"opccomn.dll");
    RegisterProxyStubFn register_proxy_stub =
        reinterpret_cast<RegisterProxyStubFn>(reinterpret_cast<void *>(GetProcAddress(opccomn, "OpcRegisterProxyStub")));
    UnregisterProxyStubFn unregister_proxy_stub =
        reinterpret_cast<UnregisterProxyStubFn>(reinterpret_cast<void *>(GetProcAddress(opccomn, "OpcUnregisterProxyStub")));
    bool across = register_proxy_stub && unregister_proxy_stub;
    WCHAR iid[40], proxy_key[96];
    GuidString(IID_IOPCCommon, iid);
    swprintf(proxy_key, 96, L"Interface\\%ls\\ProxyStubClsid32", iid);
    bool had_proxy_stub = KeyExists(proxy_key);  // another product's (or another test's) registration
    if (across) {
        HRESULT hr = register_proxy_stub(nullptr, 0);
        CHECK(hr == S_OK || hr == S_FALSE);  // S_FALSE: another proxy/stub was kept
        CHECK(KeyExists(proxy_key));
    } else {
        printf("example_client: this opccomn.dll has no proxy/stub (OpcRegisterProxyStub): out of process, "
               "only activation and COM's E_NOINTERFACE for IOPCCommon are tested\n");
    }

    // COM starts the EXE (-Embedding) and hands out a reference to a server object in it.
    CHECK(!ProcessRunning(L"opccomn_example_server.exe"));
    IUnknown *server = nullptr;
    CHECK_HR(CoCreateInstance(CLSID_ExampleServer, nullptr, CLSCTX_LOCAL_SERVER, IID_IUnknown, reinterpret_cast<void **>(&server)), S_OK);
    if (server) {
        CHECK(ProcessRunning(L"opccomn_example_server.exe"));
        IOPCCommon *common = nullptr;
        HRESULT hr = server->QueryInterface(IID_IOPCCommon, reinterpret_cast<void **>(&common));
        if (across || had_proxy_stub) {
            CHECK_HR(hr, S_OK);
            if (common) CrossProcessCalls(common);
        } else {
            CHECK_HR(hr, E_NOINTERFACE);  // without a proxy/stub COM cannot marshal IOPCCommon
        }
        if (common) common->Release();
        server->Release();  // the EXE exits when its last object is gone
        CHECK(LocalServerExits());
        if (across || had_proxy_stub) {
            EnumeratorKeepsTheServer();
            ServerExitsAfterEveryClient();
        }
    }
    if (across) {
        CHECK_HR(unregister_proxy_stub(nullptr), S_OK);
        CHECK(KeyExists(proxy_key) == had_proxy_stub);  // what was there before, nothing more
    }

    swprintf(command, 2 * MAX_PATH, L"\"%ls\" /UnregServer", exe);
    CHECK(Run(command) == 0);
    CheckUnregistered(keys);
}
}  // namespace

int main() {
    DWORD length = GetModuleFileNameW(nullptr, g_dir, MAX_PATH);
    if (length == 0 || length >= MAX_PATH) return 2;
    *wcsrchr(g_dir, L'\\') = 0;

    HRESULT hr = CoInitializeEx(nullptr, COINIT_APARTMENTTHREADED);
    if (FAILED(hr)) return 2;
    // Process security before anything is marshalled: packet integrity (what Windows' DCOM hardening,
    // KB5004442, requires), impersonation. This client receives IOPCShutdown callbacks, for which it
    // is the DCOM server: from another machine they arrive only at PKT_INTEGRITY or above.
    CHECK_HR(OpcInitializeClientSecurity(nullptr), S_OK);
    TestInProc();
    TestLocalServer();
    CoUninitialize();
    printf("example_client: %d passed, %d failed\n", g_passed, g_failed);
    return g_failed == 0 ? 0 : 1;
}
