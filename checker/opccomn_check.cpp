// opccomn-check: a conformance checker for the OPC Common interfaces of any OPC Classic server.
//
//   opccomn-check <ProgID | {CLSID}> [--host NAME] [--kind da|ae|hda] [--format text|json|junit]
//                 [--context all|inproc|local|remote] [--hostile] [--dcom] [--timeout MS]
//
// It creates the server as a client would and runs the checks of the OPC Common specification
// (IOPCCommon, the IOPCShutdown connection point, registration, server browsing; the opt-in
// --hostile set passes NULL out-parameters and absurd counts; the opt-in --dcom set reads the
// server's AppID and the machine's DCOM settings as Windows' hardening, KB5004442, needs them).
// One line per check: passed, failed
// (what was expected and what came back), warning, or not applicable, each citing the section of
// the specification it comes from; then a summary. The exit code is 0 when nothing failed, 1 when a
// check failed, 2 for a usage error.
//
// Every call into the server is made from a worker thread while the main thread watches the clock:
// a call that does not return within the timeout is reported as a failure of its check, and so is a
// crash inside an in-process server (an unhandled exception on the worker thread). Either way the
// checker carries on with a new worker thread and a new server object.
//
// Built from the library's client pieces: the shutdown sink (OpcShutdownSinkCreate), the advise
// helpers (OpcShutdownAdvise / OpcShutdownUnadvise), the server browser (OpcServerListCreate, or
// CLSID_OPCServerList on another machine), the registry reader, the category descriptions and the
// error catalog (OpcErrorCodesOfKind, OpcErrorSymbol, OpcGetErrorStringEx) for the published codes
// and their standard texts, and the version convention (OpcVersionFromFileVersion).
#include <windows.h>
#include <objbase.h>
#include <ocidl.h>
#include <olectl.h>
#include <sddl.h>

#include <opccomn/opccomn.h>

#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <cwchar>
#include <cwctype>
#include <string>
#include <vector>

// The checker is the library's version ("0.3.0-dev" while that version is in development), from the
// header, which takes it from Cargo.toml.
#define OPCCOMN_CHECK_VERSION OPCCOMN_VERSION

namespace {

// ---------------------------------------------------------------------------------------------
// Strings
// ---------------------------------------------------------------------------------------------

std::string Utf8(const wchar_t *w) {
    if (!w) return "(null)";
    int n = WideCharToMultiByte(CP_UTF8, 0, w, -1, nullptr, 0, nullptr, nullptr);
    if (n <= 0) return "?";
    std::string s(static_cast<size_t>(n - 1), '\0');
    WideCharToMultiByte(CP_UTF8, 0, w, -1, &s[0], n, nullptr, nullptr);
    return s;
}

std::string Format(const char *fmt, ...) {
    char buf[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    return buf;
}

std::string GuidText(const GUID &g) {
    WCHAR buf[64];
    StringFromGUID2(g, buf, 64);
    return Utf8(buf);
}

std::wstring GuidWide(const GUID &g) {
    WCHAR buf[64];
    StringFromGUID2(g, buf, 64);
    return buf;
}

// The name of a code the report mentions: the catalog's symbol (OPC, connection point and COM codes)
// with its value, e.g. "CONNECT_E_NOCONNECTION (0x80040200)".
uint32_t g_kind = OPC_SERVER_KIND_DATA_ACCESS;

std::string Hr(HRESULT hr) {
    LPWSTR symbol = nullptr;
    std::string s;
    if (hr == S_OK) return "S_OK";
    if (hr == S_FALSE) return "S_FALSE";
    if (SUCCEEDED(OpcErrorSymbol(hr, g_kind, &symbol)) && symbol) {
        s = Utf8(symbol) + Format(" (0x%08lX)", static_cast<unsigned long>(hr));
        OpcTaskMemFree(symbol);
        return s;
    }
    // What COM's stub answers for an exception inside an out-of-process server it caught.
    if (hr == HRESULT_FROM_WIN32(ERROR_NOACCESS))
        return Format("0x%08lX (ERROR_NOACCESS: an access violation inside the server, caught by COM)", static_cast<unsigned long>(hr));
    return Format("0x%08lX", static_cast<unsigned long>(hr));
}

// ---------------------------------------------------------------------------------------------
// Results
// ---------------------------------------------------------------------------------------------

enum Status { kPassed, kFailed, kWarning, kNotApplicable, kNotRun };
const char *const kStatusText[] = {"passed", "failed", "warning", "not applicable", "not run"};
const char *const kStatusTag[] = {"PASS", "FAIL", "WARN", "N/A ", "SKIP"};

struct Result {
    std::string id, section, title;
    Status status = kNotRun;
    std::string expected, got, detail;
};

CRITICAL_SECTION g_results_lock;
std::vector<Result> g_results;

// ---------------------------------------------------------------------------------------------
// Options and the server under test
// ---------------------------------------------------------------------------------------------

struct Options {
    std::wstring server;  // ProgID or {CLSID} as given
    std::wstring host;
    std::string kind;     // "", "da", "ae", "hda"
    std::string format = "text";
    DWORD context = CLSCTX_ALL;
    bool hostile = false;
    bool dcom = false;
    DWORD timeout_ms = 10000;
} g_opt;

// CoInitializeSecurity's result: the checker's calls go out at RPC_C_AUTHN_LEVEL_PKT_INTEGRITY.
HRESULT g_security_hr = E_FAIL;

// What the registration and browsing checks learn; filled once, read by later checks.
struct Facts {
    CLSID clsid = {};
    bool clsid_known = false;
    std::wstring prog_id, vi_prog_id, user_type, module, module_key;
    std::vector<CATID> categories;  // CLSID\{clsid}\Implemented Categories
    bool categories_read = false;
    bool clsid_key = false;         // HKCR\CLSID\{clsid} exists (reg.clsid)
} g_facts;

// The objects of one worker; a new worker (after a hang or a crash) starts with a new set.
struct Session {
    IUnknown *server = nullptr;
    bool proxy = false;  // the server object is reached through a proxy (out of process)
    HRESULT create_hr = E_FAIL;
    bool create_tried = false;
    IOPCCommon *common = nullptr;
    IConnectionPointContainer *container = nullptr;
    IConnectionPoint *point = nullptr;
    IUnknown *sink = nullptr;
    IUnknown *sink2 = nullptr;
    DWORD cookie = 0;
    bool advised = false;
    std::vector<LCID> locales;
    bool locales_read = false;
};

// ---------------------------------------------------------------------------------------------
// The watchdog: each call into the server is bracketed, the main thread watches the clock
// ---------------------------------------------------------------------------------------------

volatile LONG g_call_active;             // 1 while a call into the server runs
volatile ULONGLONG g_call_started;       // GetTickCount64 at its start
char g_call_name[160];                   // what it is, for the report
volatile LONG g_current_check = -1;      // index of the running check
volatile LONG g_worker_crashed;
volatile DWORD g_crash_code;

// Each worker's generation; a worker the watchdog gave up on (its call hung) is stale, and ends as
// soon as that call returns, before it touches the shared state of the worker that replaced it.
volatile LONG g_generation;
thread_local LONG t_generation = -1;

void EndIfStale() {
    if (t_generation != g_generation) ExitThread(0);
}

// Brackets one call into the server: `Call c("IOPCCommon::SetLocaleID"); hr = ...;`.
class Call {
public:
    explicit Call(const char *name) {
        EndIfStale();
        snprintf(g_call_name, sizeof g_call_name, "%s", name);
        g_call_started = GetTickCount64();
        InterlockedExchange(&g_call_active, 1);
    }
    ~Call() {
        EndIfStale();
        InterlockedExchange(&g_call_active, 0);
    }
};

// A crash on the worker thread (an exception nothing in the server handled): recorded, and the
// worker thread ends; the main thread reports it and goes on with a new worker.
LONG WINAPI CrashFilter(EXCEPTION_POINTERS *info) {
    if (t_generation >= 0 && t_generation != g_generation) ExitThread(0);  // a stale worker: already reported
    if (t_generation >= 0) {
        g_crash_code = info && info->ExceptionRecord ? info->ExceptionRecord->ExceptionCode : 0;
        InterlockedExchange(&g_worker_crashed, 1);
        ExitThread(3);
    }
    return EXCEPTION_CONTINUE_SEARCH;
}

// ---------------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------------

struct Ctx;
typedef void (*CheckFn)(Ctx &);

enum { kDefault = 0, kHostile = 1, kDcom = 2 };

struct CheckDef {
    const char *id;
    const char *section;
    const char *title;
    CheckFn fn;
    int set;
};

struct Ctx {
    Session &s;
    Result r;
    explicit Ctx(Session &session) : s(session) {}
    void Pass(const std::string &detail) { r.status = kPassed, r.detail = detail; }
    void Fail(const std::string &expected, const std::string &got, const std::string &detail = "") {
        r.status = kFailed, r.expected = expected, r.got = got, r.detail = detail;
    }
    void Warn(const std::string &expected, const std::string &got, const std::string &detail = "") {
        r.status = kWarning, r.expected = expected, r.got = got, r.detail = detail;
    }
    void NotApplicable(const std::string &why) { r.status = kNotApplicable, r.detail = why; }
};

bool Local() { return g_opt.host.empty(); }

// The context of a creation on --host, as remote OPC clients ask: the host's local server, which COM
// reaches by DCOM, or this machine's when the host names this machine ("localhost", its own name).
constexpr DWORD kHostContext = CLSCTX_REMOTE_SERVER | CLSCTX_LOCAL_SERVER;

COSERVERINFO *ServerInfo(COSERVERINFO *info) {
    if (Local()) return nullptr;
    memset(info, 0, sizeof *info);
    info->pwszName = const_cast<LPWSTR>(g_opt.host.c_str());
    return info;
}

// The server object, created once per session as a client creates it.
IUnknown *Server(Session &s) {
    if (!s.create_tried) {
        s.create_tried = true;
        COSERVERINFO info;
        MULTI_QI mqi = {&IID_IUnknown, nullptr, S_OK};
        DWORD context = Local() ? g_opt.context : kHostContext;
        Call c("CoCreateInstanceEx");
        s.create_hr = CoCreateInstanceEx(g_facts.clsid, nullptr, context, ServerInfo(&info), 1, &mqi);
        if (SUCCEEDED(s.create_hr)) s.create_hr = mqi.hr;
        if (SUCCEEDED(s.create_hr) && mqi.pItf) {
            s.server = mqi.pItf;
            // Proxies have IClientSecurity; in-process objects (practically) never.
            void *security = nullptr;
            if (SUCCEEDED(s.server->QueryInterface(IID_IClientSecurity, &security)) && security) {
                s.proxy = true;
                static_cast<IUnknown *>(security)->Release();
            }
        } else if (SUCCEEDED(s.create_hr)) {
            s.create_hr = E_POINTER;
        }
    }
    return s.server;
}

// The server's IOPCCommon, or NULL (the check is then "not applicable": the QI check failed).
IOPCCommon *Common(Ctx &x) {
    if (!x.s.common && Server(x.s)) {
        void *p = nullptr;
        Call c("IUnknown::QueryInterface(IID_IOPCCommon)");
        if (SUCCEEDED(x.s.server->QueryInterface(IID_IOPCCommon, &p))) x.s.common = static_cast<IOPCCommon *>(p);
    }
    if (!x.s.common) x.NotApplicable("the server object has no IOPCCommon (see common.interface)");
    return x.s.common;
}

IConnectionPointContainer *Container(Ctx &x) {
    if (!x.s.container && Server(x.s)) {
        void *p = nullptr;
        Call c("IUnknown::QueryInterface(IID_IConnectionPointContainer)");
        if (SUCCEEDED(x.s.server->QueryInterface(IID_IConnectionPointContainer, &p)))
            x.s.container = static_cast<IConnectionPointContainer *>(p);
    }
    if (!x.s.container) x.NotApplicable("the server object has no IConnectionPointContainer (see shutdown.container)");
    return x.s.container;
}

IConnectionPoint *Point(Ctx &x) {
    if (!x.s.point && Container(x)) {
        IConnectionPoint *p = nullptr;
        Call c("IConnectionPointContainer::FindConnectionPoint(IID_IOPCShutdown)");
        if (SUCCEEDED(x.s.container->FindConnectionPoint(IID_IOPCShutdown, &p))) x.s.point = p;
    }
    if (!x.s.point && x.r.status == kNotRun)
        x.NotApplicable("the server has no IOPCShutdown connection point (see shutdown.find)");
    return x.s.point;
}

void OnShutdown(void *, LPCWSTR reason) {
    fprintf(stderr, "opccomn-check: the server sent ShutdownRequest(\"%s\")\n", Utf8(reason).c_str());
}

// A new client shutdown sink (the library's), or NULL.
IUnknown *NewSink() {
    void *sink = nullptr;
    return SUCCEEDED(OpcShutdownSinkCreate(OnShutdown, nullptr, IID_IUnknown, &sink)) ? static_cast<IUnknown *>(sink)
                                                                                     : nullptr;
}

std::string OtherViewHint();

// Out of process an interface crosses through its proxy/stub, registered on both machines
// (Interface\{iid}\ProxyStubClsid32). Without one, QueryInterface gives E_NOINTERFACE and the server
// cannot call the client's sink: say so.
std::string ProxyHint(const IID &iid, const char *name) {
    HKEY h;
    std::wstring key = L"Interface\\" + GuidWide(iid) + L"\\ProxyStubClsid32";
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key.c_str(), 0, KEY_READ, &h) == ERROR_SUCCESS) {
        RegCloseKey(h);
        return "";
    }
    return std::string("no proxy/stub is registered for ") + name +
           " on this machine (regsvr32 /n /i:ProxyStub opccomn.dll, or the OPC Foundation's opccomn_ps.dll)";
}

// ---- creation ----

void CheckCreate(Ctx &x) {
    if (Server(x.s)) {
        x.Pass(Format("CoCreateInstanceEx(%s, %s) gave the server object", GuidText(g_facts.clsid).c_str(),
                      Local() ? "local" : Utf8(g_opt.host.c_str()).c_str()));
    } else {
        x.Fail("S_OK and an object", Hr(x.s.create_hr), "the server could not be created; its other checks cannot run" + OtherViewHint());
    }
}

// ---- IOPCCommon (chapter 5) ----

void CheckCommonInterface(Ctx &x) {
    if (!Server(x.s)) return x.NotApplicable("no server object (see server.create)");
    void *p = nullptr;
    HRESULT hr;
    {
        Call c("IUnknown::QueryInterface(IID_IOPCCommon)");
        hr = x.s.server->QueryInterface(IID_IOPCCommon, &p);
    }
    if (SUCCEEDED(hr) && p) {
        if (!x.s.common) x.s.common = static_cast<IOPCCommon *>(p);
        else static_cast<IUnknown *>(p)->Release();
        x.Pass("QueryInterface(IID_IOPCCommon) succeeded");
    } else {
        x.Fail("S_OK and an interface", Hr(hr) + (p ? "" : ", NULL"), hr == E_NOINTERFACE ? ProxyHint(IID_IOPCCommon, "IOPCCommon") : "");
    }
}

void CheckDefaultLocale(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    LCID lcid = 0xDEADBEEF;
    HRESULT hr;
    {
        Call c("IOPCCommon::GetLocaleID");
        hr = common->GetLocaleID(&lcid);
    }
    if (hr != S_OK) return x.Fail("S_OK", Hr(hr));
    if (lcid == LOCALE_SYSTEM_DEFAULT) return x.Pass("a new session starts in LOCALE_SYSTEM_DEFAULT (0x0800)");
    x.Warn("LOCALE_SYSTEM_DEFAULT (0x0800)", Format("0x%04lX", static_cast<unsigned long>(lcid)),
           "the specification says the default should be LOCALE_SYSTEM_DEFAULT");
}

// QueryAvailableLocaleIDs: S_OK, a count, an array in task memory (IMalloc::DidAlloc).
void CheckLocaleArray(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    DWORD count = 0xDEADBEEF;
    LCID *array = reinterpret_cast<LCID *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c("IOPCCommon::QueryAvailableLocaleIDs");
        hr = common->QueryAvailableLocaleIDs(&count, &array);
    }
    if (hr != S_OK) return x.Fail("S_OK", Hr(hr));
    if (count == 0 || !array)
        return x.Fail("at least one locale in a task-memory array", Format("count %lu, array %p", static_cast<unsigned long>(count), static_cast<void *>(array)));
    if (count > 4096) return x.Fail("a plausible count", Format("count %lu", static_cast<unsigned long>(count)));
    x.s.locales.assign(array, array + count);
    x.s.locales_read = true;
    std::string list;
    for (DWORD i = 0; i < count; i++) list += Format("%s0x%04lX", i ? ", " : "", static_cast<unsigned long>(array[i]));
    // In-process the array comes straight from the server: it must be the COM task allocator's, or
    // the client's CoTaskMemFree corrupts the heap. (Through a proxy the proxy allocated it.)
    IMalloc *malloc = nullptr;
    int owned = -1;
    if (SUCCEEDED(CoGetMalloc(1, &malloc)) && malloc) {
        owned = malloc->DidAlloc(array);
        malloc->Release();
    }
    if (owned == 0) {
        // Not ours to free with CoTaskMemFree: leak it rather than corrupt the heap.
        return x.Fail("an array allocated with CoTaskMemAlloc (IMalloc::DidAlloc = 1)",
                      "an array the COM task allocator did not allocate (DidAlloc = 0)", "locales " + list);
    }
    CoTaskMemFree(array);
    x.Pass(Format("%lu locale(s): ", static_cast<unsigned long>(count)) + list +
           (owned == 1 ? "; the array is task memory (IMalloc::DidAlloc)" : "; DidAlloc could not tell"));
}

bool ReadLocales(Ctx &x) {
    if (x.s.locales_read) return true;
    IOPCCommon *common = Common(x);
    if (!common) return false;
    DWORD count = 0;
    LCID *array = nullptr;
    HRESULT hr;
    {
        Call c("IOPCCommon::QueryAvailableLocaleIDs");
        hr = common->QueryAvailableLocaleIDs(&count, &array);
    }
    if (hr != S_OK || !array || count == 0 || count > 4096) {
        x.NotApplicable("QueryAvailableLocaleIDs gave no list (see common.locales.array)");
        return false;
    }
    x.s.locales.assign(array, array + count);
    x.s.locales_read = true;
    return true;  // the array is leaked on purpose: it may not be task memory (common.locales.array)
}

void CheckSetEveryLocale(Ctx &x) {
    if (!ReadLocales(x)) return;
    IOPCCommon *common = x.s.common;
    std::string done;
    for (LCID lcid : x.s.locales) {
        HRESULT hr;
        LCID back = 0xDEADBEEF;
        {
            Call c("IOPCCommon::SetLocaleID");
            hr = common->SetLocaleID(lcid);
        }
        if (hr != S_OK)
            return x.Fail(Format("SetLocaleID(0x%04lX) = S_OK (it is in the list)", static_cast<unsigned long>(lcid)), Hr(hr));
        {
            Call c("IOPCCommon::GetLocaleID");
            hr = common->GetLocaleID(&back);
        }
        if (hr != S_OK || back != lcid)
            return x.Fail(Format("GetLocaleID = S_OK, 0x%04lX", static_cast<unsigned long>(lcid)),
                          Hr(hr) + Format(", 0x%04lX", static_cast<unsigned long>(back)));
        done += Format("%s0x%04lX", done.empty() ? "" : ", ", static_cast<unsigned long>(lcid));
    }
    x.Pass("set and read back: " + done);
}

bool Listed(const std::vector<LCID> &locales, LCID lcid) {
    for (LCID l : locales)
        if (l == lcid) return true;
    return false;
}

void CheckUnsupportedLocale(Ctx &x) {
    if (!ReadLocales(x)) return;
    IOPCCommon *common = x.s.common;
    // A real locale that is not in the list: the first of a few that few servers offer.
    static const LCID candidates[] = {0x0419, 0x0411, 0x041F, 0x0408, 0x042A, 0x0439};
    LCID bad = 0;
    for (LCID c : candidates)
        if (!Listed(x.s.locales, c)) {
            bad = c;
            break;
        }
    if (!bad) return x.NotApplicable("the server lists every candidate locale");
    LCID before = 0, after = 0;
    HRESULT hr;
    {
        Call c("IOPCCommon::GetLocaleID");
        hr = common->GetLocaleID(&before);
    }
    if (hr != S_OK) return x.Fail("GetLocaleID = S_OK", Hr(hr));
    {
        Call c("IOPCCommon::SetLocaleID");
        hr = common->SetLocaleID(bad);
    }
    {
        Call c("IOPCCommon::GetLocaleID");
        common->GetLocaleID(&after);
    }
    std::string what = Format("SetLocaleID(0x%04lX), a locale QueryAvailableLocaleIDs does not list", static_cast<unsigned long>(bad));
    if (hr != E_INVALIDARG)
        return x.Fail("E_INVALIDARG, locale unchanged", Hr(hr) + Format(", locale now 0x%04lX", static_cast<unsigned long>(after)), what);
    if (after != before)
        return x.Fail(Format("E_INVALIDARG, locale still 0x%04lX", static_cast<unsigned long>(before)),
                      Format("E_INVALIDARG, locale now 0x%04lX", static_cast<unsigned long>(after)), what);
    x.Pass(what + ": E_INVALIDARG, locale unchanged");
}

// The kind of server, as --kind says or as its categories tell (Data Access by default).
const char *KindName() {
    switch (g_kind) {
    case OPC_SERVER_KIND_ALARMS_EVENTS: return "ae";
    case OPC_SERVER_KIND_HISTORICAL_DATA: return "hda";
    default: return "da";
    }
}

// ---- What an error text must say (5.1.4: "the server's textual representation" of the code) ----

bool AsciiAlnum(wchar_t c) { return (c >= L'0' && c <= L'9') || (c >= L'a' && c <= L'z') || (c >= L'A' && c <= L'Z'); }

// The words of a text: runs of characters between blanks and punctuation ('_' joins them, as in
// OPC_E_INVALIDHANDLE), ASCII letters in lower case. A character beyond ASCII is part of a word
// unless the runtime calls it a blank or punctuation, so a text in any script has words.
std::vector<std::wstring> Words(const std::wstring &text) {
    std::vector<std::wstring> words(1);
    for (wchar_t c : text) {
        bool part = c == L'_' || (c < 0x80 ? AsciiAlnum(c) : !iswspace(c) && !iswpunct(c));
        if (part) words.back() += c < 0x80 ? static_cast<wchar_t>(towlower(c)) : c;
        else if (!words.back().empty()) words.emplace_back();
    }
    if (words.back().empty()) words.pop_back();
    return words;
}

bool AllIn(const std::wstring &s, const wchar_t *set) { return !s.empty() && s.find_first_not_of(set) == std::wstring::npos; }

// Whether a word is a number: decimal, hexadecimal with 0x, or the code itself in hexadecimal (bare,
// after VB's &H, whose '&' is punctuation, or with the assembler's h after it).
bool NumberWord(const std::wstring &w, HRESULT code) {
    static const wchar_t hex_digits[] = L"0123456789abcdef";
    if (AllIn(w, L"0123456789")) return true;
    if (w.size() > 2 && w.compare(0, 2, L"0x") == 0 && AllIn(w.substr(2), hex_digits)) return true;
    std::wstring hex = w;
    if (hex.size() > 1 && hex.front() == L'h') hex.erase(0, 1);
    else if (hex.size() > 1 && hex.back() == L'h') hex.pop_back();
    return AllIn(hex, hex_digits) && hex.size() <= 16 &&
           wcstoull(hex.c_str(), nullptr, 16) == static_cast<unsigned long long>(static_cast<uint32_t>(code));
}

// Whether `text` says nothing beyond the code: it has no word, or each word is a number (the code
// in hexadecimal or decimal, signed or not, or any other), the code's symbol, or a word that only
// announces a code ("error", "code", "HRESULT", "unknown", ...; English and a few other languages).
bool SaysNothing(const std::wstring &text, HRESULT code, const std::wstring &symbol) {
    static const wchar_t *const announce[] = {
        L"error", L"errors", L"err", L"hresult", L"hr", L"scode", L"code", L"codes", L"errorcode", L"result",
        L"status", L"unknown", L"undefined", L"unspecified", L"opc", L"no", L"nr", L"num", L"number", L"value",
        L"id", L"message", L"text", L"string", L"description", L"the", L"a", L"an", L"of", L"for", L"is",
        L"with", L"returned", L"fehler", L"fehlercode", L"unbekannter", L"unbekannt", L"erreur", L"inconnue",
        L"errore", L"erro", L"codigo"};
    std::wstring lower_symbol;
    for (wchar_t c : symbol) lower_symbol += c < 0x80 ? static_cast<wchar_t>(towlower(c)) : c;
    for (const std::wstring &w : Words(text)) {
        bool filler = NumberWord(w, code) || (!lower_symbol.empty() && w == lower_symbol);
        for (const wchar_t *a : announce) filler = filler || w == a;
        if (!filler) return false;
    }
    return true;
}

// The locale GetErrorString is asked in: an English one when the server lists one (its texts can then
// be compared with the published ones), otherwise the first it lists. *english tells which.
void SetTextLocale(Ctx &x, bool *english) {
    *english = false;
    if (!ReadLocales(x)) return;
    LCID chosen = x.s.locales.front();
    for (LCID l : x.s.locales)
        if (PRIMARYLANGID(LANGIDFROMLCID(l)) == LANG_ENGLISH) {
            chosen = l;
            *english = true;
            break;
        }
    Call c("IOPCCommon::SetLocaleID");
    if (x.s.common->SetLocaleID(chosen) != S_OK) *english = false;
}

std::string LocaleList(const std::vector<LCID> &locales) {
    std::string list;
    for (LCID l : locales) list += Format("%s0x%04lX", list.empty() ? "" : ", ", static_cast<unsigned long>(l));
    return list.empty() ? "none" : list;
}

// Every published code of the kind needs S_OK and a text of its own: not empty, not the code restated
// (SaysNothing), not the text of another code whose published text differs. Texts read in an English
// locale are compared with the published ones (a warning where they differ, as vendors may word them
// otherwise); without one, texts that are exactly the published English ones pass, and others are a
// warning saying they could not be compared, never a pass.
void CheckPublishedCodes(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    bool english = false;
    SetTextLocale(x, &english);
    LCID locale = 0xFFFFFFFF;
    {
        Call c("IOPCCommon::GetLocaleID");
        if (common->GetLocaleID(&locale) != S_OK) locale = 0xFFFFFFFF;
    }
    DWORD count = 0;
    HRESULT *codes = nullptr;
    if (FAILED(OpcErrorCodesOfKind(g_kind, &count, &codes))) return x.NotApplicable("no published codes for this kind");
    struct Answer {
        HRESULT code;
        std::wstring text, published;
    };
    std::vector<Answer> answers;
    std::string failed, restated, shared, differs;
    DWORD n_failed = 0, n_restated = 0, n_shared = 0, different = 0;
    auto add = [](std::string &list, const std::string &item) {
        if (list.size() < 600) list += (list.empty() ? "" : "; ") + item;
    };
    for (DWORD i = 0; i < count; i++) {
        LPWSTR text = reinterpret_cast<LPWSTR>(static_cast<uintptr_t>(0xDEADBEEF));
        HRESULT hr;
        {
            Call c("IOPCCommon::GetErrorString");
            hr = common->GetErrorString(codes[i], &text);
        }
        if (hr != S_OK || !text) {
            n_failed++;
            add(failed, Hr(codes[i]) + ": " + Hr(hr) + (hr == S_OK ? " with NULL" : ""));
            continue;
        }
        Answer a = {codes[i], text, L""};
        CoTaskMemFree(text);
        LPWSTR published = nullptr, symbol = nullptr;
        if (SUCCEEDED(OpcGetErrorStringEx(codes[i], 0x0409, g_kind, &published)) && published) a.published = published;
        OpcTaskMemFree(published);
        std::wstring symbol_text;
        if (SUCCEEDED(OpcErrorSymbol(codes[i], g_kind, &symbol)) && symbol) symbol_text = symbol;
        OpcTaskMemFree(symbol);
        if (SaysNothing(a.text, a.code, symbol_text)) {
            n_restated++;
            add(restated, Hr(a.code) + ": \"" + Utf8(a.text.c_str()) + "\"");
        } else {
            for (const Answer &before : answers)
                if (before.text == a.text && before.published != a.published) {
                    n_shared++;
                    add(shared, Hr(before.code) + " and " + Hr(a.code) + ": \"" + Utf8(a.text.c_str()) + "\"");
                    break;
                }
        }
        if (a.text != a.published) {
            different++;
            add(differs, Hr(a.code) + ": \"" + Utf8(a.text.c_str()) + "\" (published: \"" + Utf8(a.published.c_str()) + "\")");
        }
        answers.push_back(a);
    }
    OpcTaskMemFree(codes);
    std::string summary = Format("%lu of %lu published %s codes answered", static_cast<unsigned long>(answers.size()),
                                 static_cast<unsigned long>(count), KindName());
    std::string read_in = locale == 0xFFFFFFFF ? "the session's locale" : Format("locale 0x%04lX", static_cast<unsigned long>(locale));
    if (n_failed || n_restated || n_shared) {
        std::string got;
        if (n_failed) got += Format("%lu without S_OK and a text: ", static_cast<unsigned long>(n_failed)) + failed;
        if (n_restated)
            got += (got.empty() ? "" : "; ") + Format("%lu are empty or only restate the code: ", static_cast<unsigned long>(n_restated)) + restated;
        if (n_shared)
            got += (got.empty() ? "" : "; ") + Format("%lu give the text of another code: ", static_cast<unsigned long>(n_shared)) + shared;
        return x.Fail("S_OK and, for every published code, a text of its own that says more than the code", got,
                      summary + ", read in " + read_in);
    }
    if (!different)
        return x.Pass(summary + ", every text as published" +
                      (english ? "" : " (read in " + read_in + "; the server lists no English locale)"));
    if (english)
        return x.Warn("the texts the OPC Foundation publishes", Format("%lu differ: ", static_cast<unsigned long>(different)) + differs, summary);
    x.Warn("an English locale, to compare the texts with those the OPC Foundation publishes",
           "no English locale among those listed (" + LocaleList(x.s.locales) + ")",
           summary + ", read in " + read_in + Format(": %lu differ from the published English texts, ", static_cast<unsigned long>(different)) +
               "so they were not compared");
}

void CheckUnknownCode(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    // Facility 0xFFF is used by nobody: no catalog, no system and no vendor text exists for it.
    const HRESULT unknown = static_cast<HRESULT>(0x8FFF7A3Eu);
    LPWSTR text = reinterpret_cast<LPWSTR>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c("IOPCCommon::GetErrorString");
        hr = common->GetErrorString(unknown, &text);
    }
    std::string got = Hr(hr);
    if (hr == S_OK) {
        got += text ? ", \"" + Utf8(text) + "\"" : ", NULL";
        if (text) CoTaskMemFree(text);
        return x.Fail("E_INVALIDARG and NULL", got, "GetErrorString(0x8FFF7A3E), a code without a text");
    }
    if (hr != E_INVALIDARG || text != nullptr)
        return x.Fail("E_INVALIDARG and NULL", got + (text ? ", the out-pointer not set to NULL" : ", NULL"),
                      "GetErrorString(0x8FFF7A3E), a code without a text");
    x.Pass("GetErrorString(0x8FFF7A3E) = E_INVALIDARG with NULL");
}

void CheckClientName(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    HRESULT hr;
    {
        Call c("IOPCCommon::SetClientName");
        hr = common->SetClientName(L"opccomn-check");
    }
    if (hr != S_OK) return x.Fail("S_OK", Hr(hr), "SetClientName(L\"opccomn-check\")");
    x.Pass("SetClientName(L\"opccomn-check\") = S_OK");
}

// ---- Shutdown (chapter 4) ----

void CheckContainer(Ctx &x) {
    if (!Server(x.s)) return x.NotApplicable("no server object (see server.create)");
    void *p = nullptr;
    HRESULT hr;
    {
        Call c("IUnknown::QueryInterface(IID_IConnectionPointContainer)");
        hr = x.s.server->QueryInterface(IID_IConnectionPointContainer, &p);
    }
    if (FAILED(hr) || !p) return x.Fail("S_OK and an interface", Hr(hr));
    if (!x.s.container) x.s.container = static_cast<IConnectionPointContainer *>(p);
    else static_cast<IUnknown *>(p)->Release();
    x.Pass("QueryInterface(IID_IConnectionPointContainer) succeeded");
}

void CheckFind(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    IConnectionPoint *point = reinterpret_cast<IConnectionPoint *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c("IConnectionPointContainer::FindConnectionPoint(IID_IOPCShutdown)");
        hr = container->FindConnectionPoint(IID_IOPCShutdown, &point);
    }
    if (hr != S_OK || !point || point == reinterpret_cast<IConnectionPoint *>(static_cast<uintptr_t>(0xDEADBEEF)))
        return x.Fail("S_OK and the connection point", Hr(hr));
    IID iid = {};
    {
        Call c("IConnectionPoint::GetConnectionInterface");
        hr = point->GetConnectionInterface(&iid);
    }
    if (!x.s.point) x.s.point = point;
    else point->Release();
    if (hr != S_OK || !IsEqualIID(iid, IID_IOPCShutdown))
        return x.Fail("GetConnectionInterface = S_OK, IID_IOPCShutdown", Hr(hr) + ", " + GuidText(iid));
    x.Pass("FindConnectionPoint(IID_IOPCShutdown) gave the point; GetConnectionInterface says IID_IOPCShutdown");
}

// IConnectionPoint::GetConnectionPointContainer gives back the container the point belongs to, which
// for IOPCShutdown is the server object: a client holding only the point (from EnumConnectionPoints,
// or kept after the server object was released) finds its server this way. COM identity decides:
// the container's IUnknown must be the server object's. A server that forwards to a connection point
// object it does not aggregate gets that object's own container back, another object.
void CheckPointContainer(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    IConnectionPointContainer *const garbage = reinterpret_cast<IConnectionPointContainer *>(static_cast<uintptr_t>(0xDEADBEEF));
    IConnectionPointContainer *back = garbage;
    HRESULT hr;
    {
        Call c("IConnectionPoint::GetConnectionPointContainer");
        hr = point->GetConnectionPointContainer(&back);
    }
    const std::string want = "S_OK and the server object's IConnectionPointContainer";
    if (back == garbage) return x.Fail(want, Hr(hr) + ", the out-pointer not written");
    if (hr != S_OK || !back) {
        // On failure a non-NULL pointer may be anything: it is left alone, not released.
        return x.Fail(want, Hr(hr) + (back ? ", the out-pointer not set to NULL" : ", NULL"),
                      "the connection point cannot name its container");
    }
    void *server = nullptr, *container = nullptr;
    {
        Call c("IUnknown::QueryInterface(IID_IUnknown)");
        x.s.server->QueryInterface(IID_IUnknown, &server);
        back->QueryInterface(IID_IUnknown, &container);
    }
    bool same = server && server == container;
    if (server) static_cast<IUnknown *>(server)->Release();
    if (container) static_cast<IUnknown *>(container)->Release();
    back->Release();
    if (!container) return x.Fail(want, "an object whose QueryInterface(IID_IUnknown) fails");
    if (!same)
        return x.Fail(want + " (the same IUnknown as the server object)", "another object (another IUnknown)",
                      "the container is not the server object: a connection point object forwarded to without "
                      "aggregating it names its own container");
    x.Pass("GetConnectionPointContainer gave the server object back (the same IUnknown)");
}

void CheckEnumPoints(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    IEnumConnectionPoints *points = nullptr;
    HRESULT hr;
    {
        Call c("IConnectionPointContainer::EnumConnectionPoints");
        hr = container->EnumConnectionPoints(&points);
    }
    if (hr != S_OK || !points) return x.Fail("S_OK and an enumerator", Hr(hr));
    bool found = false;
    ULONG seen = 0;
    for (int guard = 0; guard < 64; guard++) {
        IConnectionPoint *p = nullptr;
        ULONG fetched = 0;
        {
            Call c("IEnumConnectionPoints::Next");
            hr = points->Next(1, &p, &fetched);
        }
        if (hr != S_OK || fetched != 1 || !p) break;
        seen++;
        IID iid = {};
        {
            Call c("IConnectionPoint::GetConnectionInterface");
            if (p->GetConnectionInterface(&iid) == S_OK && IsEqualIID(iid, IID_IOPCShutdown)) found = true;
        }
        p->Release();
    }
    points->Release();
    if (!found) return x.Fail("an enumerator that includes IOPCShutdown", Format("%lu point(s), none for IOPCShutdown", static_cast<unsigned long>(seen)));
    x.Pass(Format("%lu connection point(s), IOPCShutdown among them", static_cast<unsigned long>(seen)));
}

void CheckAdvise(Ctx &x) {
    if (!Container(x)) return;
    IUnknown *sink = NewSink();
    if (!sink) return x.Fail("a client sink", "OpcShutdownSinkCreate failed");
    DWORD cookie = 0xDEADBEEF;
    HRESULT hr;
    {
        Call c("IConnectionPoint::Advise (OpcShutdownAdvise)");
        hr = OpcShutdownAdvise(x.s.server, sink, &cookie);
    }
    if (hr != S_OK) {
        sink->Release();
        return x.Fail("S_OK and a non-zero cookie", Hr(hr), hr == CONNECT_E_CANNOTCONNECT ? ProxyHint(IID_IOPCShutdown, "IOPCShutdown") : "");
    }
    x.s.sink = sink;  // kept until the connection is gone
    x.s.cookie = cookie;
    x.s.advised = true;
    if (cookie == 0) return x.Fail("S_OK and a non-zero cookie", "S_OK and cookie 0", "0 is the cookie COM reserves for \"no connection\"");
    x.Pass(Format("Advise of the library's shutdown sink: S_OK, cookie %lu", static_cast<unsigned long>(cookie)));
}

void CheckSecondAdvise(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    if (!x.s.advised) return x.NotApplicable("the first Advise did not succeed (see shutdown.advise)");
    IUnknown *sink = NewSink();
    if (!sink) return x.Fail("a client sink", "OpcShutdownSinkCreate failed");
    DWORD cookie = 0xDEADBEEF;
    HRESULT hr;
    {
        Call c("IConnectionPoint::Advise");
        hr = point->Advise(sink, &cookie);
    }
    if (hr == CONNECT_E_ADVISELIMIT) {
        sink->Release();
        if (cookie != 0) return x.Fail("CONNECT_E_ADVISELIMIT with cookie 0", Format("CONNECT_E_ADVISELIMIT with cookie %lu", static_cast<unsigned long>(cookie)));
        return x.Pass("a second Advise: CONNECT_E_ADVISELIMIT (one connection per client, as the specification allows)");
    }
    if (hr != S_OK) {
        sink->Release();
        return x.Fail("S_OK or CONNECT_E_ADVISELIMIT", Hr(hr));
    }
    x.s.sink2 = sink;
    std::string got = Format("S_OK, cookie %lu", static_cast<unsigned long>(cookie));
    HRESULT un;
    {
        Call c("IConnectionPoint::Unadvise");
        un = point->Unadvise(cookie);
    }
    if (cookie == 0 || cookie == x.s.cookie)
        return x.Fail("S_OK with a non-zero cookie of its own", got + Format(" (the first was %lu)", static_cast<unsigned long>(x.s.cookie)));
    if (un != S_OK) return x.Fail("Unadvise of the second connection = S_OK", Hr(un));
    x.Pass("a second Advise: " + got + ", unadvised again");
}

void CheckUnadviseUnknown(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    // A cookie no Advise handed out: far from the first one (cookies usually count up).
    DWORD unknown = x.s.cookie ^ 0x5A5A0000u;
    if (unknown == 0) unknown = 0x5A5A0001u;
    HRESULT hr;
    {
        Call c("IConnectionPoint::Unadvise");
        hr = point->Unadvise(unknown);
    }
    std::string what = Format("Unadvise(%lu), a cookie no Advise returned", static_cast<unsigned long>(unknown));
    if (hr != CONNECT_E_NOCONNECTION) return x.Fail("CONNECT_E_NOCONNECTION", Hr(hr), what);
    x.Pass(what + ": CONNECT_E_NOCONNECTION");
}

void CheckFindOther(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    IConnectionPoint *point = reinterpret_cast<IConnectionPoint *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c("IConnectionPointContainer::FindConnectionPoint(IID_IOPCCommon)");
        hr = container->FindConnectionPoint(IID_IOPCCommon, &point);
    }
    std::string what = "FindConnectionPoint(IID_IOPCCommon), an interface with no connection point";
    if (hr == S_OK) {
        if (point) point->Release();
        return x.Fail("CONNECT_E_NOCONNECTION and NULL", "S_OK", what);
    }
    if (hr != CONNECT_E_NOCONNECTION) return x.Fail("CONNECT_E_NOCONNECTION and NULL", Hr(hr), what);
    if (point != nullptr) return x.Fail("CONNECT_E_NOCONNECTION and NULL", "CONNECT_E_NOCONNECTION, the out-pointer not set to NULL", what);
    x.Pass(what + ": CONNECT_E_NOCONNECTION with NULL");
}

// A sink without IOPCShutdown: the library's IOPCCommon object, which has IUnknown only besides it.
void CheckWrongSink(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    IUnknown *not_a_sink = nullptr;
    if (FAILED(OpcCommonCreate(nullptr, nullptr, IID_IUnknown, reinterpret_cast<void **>(&not_a_sink))))
        return x.Fail("an object without IOPCShutdown", "OpcCommonCreate failed");
    DWORD cookie = 0xDEADBEEF;
    HRESULT hr;
    {
        Call c("IConnectionPoint::Advise");
        hr = point->Advise(not_a_sink, &cookie);
    }
    if (hr == S_OK) {
        Call c("IConnectionPoint::Unadvise");
        point->Unadvise(cookie);
    }
    not_a_sink->Release();
    std::string what = "Advise of an object without IOPCShutdown";
    if (hr != CONNECT_E_CANNOTCONNECT) return x.Fail("CONNECT_E_CANNOTCONNECT, cookie 0", Hr(hr), what);
    if (cookie != 0) return x.Fail("CONNECT_E_CANNOTCONNECT, cookie 0", Format("CONNECT_E_CANNOTCONNECT, cookie %lu", static_cast<unsigned long>(cookie)), what);
    x.Pass(what + ": CONNECT_E_CANNOTCONNECT, cookie 0");
}

void CheckEnumConnections(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    IEnumConnections *connections = reinterpret_cast<IEnumConnections *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c("IConnectionPoint::EnumConnections");
        hr = point->EnumConnections(&connections);
    }
    if (hr == E_NOTIMPL) {
        if (connections != nullptr) return x.Fail("E_NOTIMPL with NULL", "E_NOTIMPL, the out-pointer not set to NULL");
        return x.Pass("E_NOTIMPL (allowed for IOPCShutdown, specification 4.1)");
    }
    if (hr != S_OK || !connections || connections == reinterpret_cast<IEnumConnections *>(static_cast<uintptr_t>(0xDEADBEEF)))
        return x.Fail("S_OK and an enumerator, or E_NOTIMPL", Hr(hr));
    ULONG seen = 0;
    bool found = false;
    HRESULT last = S_OK;
    for (int guard = 0; guard < 64; guard++) {
        CONNECTDATA data = {nullptr, 0};
        ULONG fetched = 0;
        {
            Call c("IEnumConnections::Next");
            hr = connections->Next(1, &data, &fetched);
        }
        last = hr;
        // S_OK means all `celt` were fetched (Wine's cross-process IEnumConnections proxy leaves
        // *pcFetched unwritten, so the count is taken from the code).
        if (hr != S_OK) break;
        seen++;
        if (data.dwCookie == x.s.cookie && data.pUnk) found = true;
        if (data.pUnk) data.pUnk->Release();
    }
    connections->Release();
    if (x.s.advised && !found)
        return x.Fail(Format("an enumerator listing cookie %lu", static_cast<unsigned long>(x.s.cookie)),
                      Format("%lu connection(s), not that one (Next: ", static_cast<unsigned long>(seen)) + Hr(last) + ")");
    x.Pass(Format("S_OK; %lu connection(s)", static_cast<unsigned long>(seen)) + (x.s.advised ? ", the checker's among them" : ""));
}

void CheckUnadvise(Ctx &x) {
    if (!Container(x)) return;
    if (!x.s.advised) return x.NotApplicable("no connection to remove (see shutdown.advise)");
    HRESULT hr;
    {
        Call c("IConnectionPoint::Unadvise (OpcShutdownUnadvise)");
        hr = OpcShutdownUnadvise(x.s.server, x.s.cookie);
    }
    if (hr != S_OK) return x.Fail("S_OK", Hr(hr), Format("Unadvise(%lu), the cookie Advise returned", static_cast<unsigned long>(x.s.cookie)));
    x.s.advised = false;
    HRESULT again;
    {
        Call c("IConnectionPoint::Unadvise (OpcShutdownUnadvise)");
        again = OpcShutdownUnadvise(x.s.server, x.s.cookie);
    }
    if (again != CONNECT_E_NOCONNECTION)
        return x.Fail("a second Unadvise of the same cookie = CONNECT_E_NOCONNECTION", Hr(again));
    x.Pass(Format("Unadvise(%lu) = S_OK; once more = CONNECT_E_NOCONNECTION", static_cast<unsigned long>(x.s.cookie)));
}

// ---- Registration (chapter 6) ----

std::wstring ClsidKey() { return L"CLSID\\" + GuidWide(g_facts.clsid); }

// A string value under HKEY_CLASSES_ROOT through the library's registry reader; `ok` tells whether it exists.
std::wstring RegString(const std::wstring &key, LPCWSTR name, bool *ok) {
    LPWSTR data = nullptr;
    HRESULT hr = OpcRegistryGetString(nullptr, key.c_str(), name, &data);
    *ok = SUCCEEDED(hr) && data;
    std::wstring s = *ok ? data : L"";
    OpcTaskMemFree(data);
    return s;
}

bool KeyExists(const std::wstring &key) {
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key.c_str(), 0, KEY_READ, &h) != ERROR_SUCCESS) return false;
    RegCloseKey(h);
    return true;
}

// Whether the other registry view (32-bit for a 64-bit checker and the other way round) has `key`
// under HKEY_CLASSES_ROOT: the most common reason a client does not find a server.
bool OtherViewHas(const std::wstring &key) {
    BOOL wow64 = FALSE;
    IsWow64Process(GetCurrentProcess(), &wow64);
    REGSAM other = sizeof(void *) == 8 ? KEY_WOW64_32KEY : (wow64 ? KEY_WOW64_64KEY : 0);
    if (!other) return false;
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key.c_str(), 0, KEY_READ | other, &h) != ERROR_SUCCESS) return false;
    RegCloseKey(h);
    return true;
}

std::string OtherViewHint() {
    if (!Local() || !OtherViewHas(L"CLSID\\" + GuidWide(g_facts.clsid))) return "";
    return sizeof(void *) == 8 ? "; the class is registered in the 32-bit registry view only: run the x86 opccomn-check"
                               : "; the class is registered in the 64-bit registry view only: run the x64 opccomn-check";
}

void ReadCategories() {
    if (g_facts.categories_read) return;
    g_facts.categories_read = true;
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, (ClsidKey() + L"\\Implemented Categories").c_str(), 0, KEY_READ, &h) != ERROR_SUCCESS)
        return;
    for (DWORD i = 0;; i++) {
        WCHAR name[64];
        DWORD len = 64;
        if (RegEnumKeyExW(h, i, name, &len, nullptr, nullptr, nullptr, nullptr) != ERROR_SUCCESS) break;
        CATID catid;
        if (SUCCEEDED(CLSIDFromString(name, &catid))) g_facts.categories.push_back(catid);
    }
    RegCloseKey(h);
}

void CheckRegClsid(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    bool ok;
    g_facts.user_type = RegString(ClsidKey(), nullptr, &ok);
    g_facts.clsid_key = KeyExists(ClsidKey());
    if (!g_facts.clsid_key) return x.Fail("HKCR\\" + Utf8(ClsidKey().c_str()), "no such key" + OtherViewHint());
    if (!ok || g_facts.user_type.empty())
        return x.Fail("a description (the user type) as the default value of HKCR\\" + Utf8(ClsidKey().c_str()), "none");
    x.Pass("HKCR\\" + Utf8(ClsidKey().c_str()) + " = \"" + Utf8(g_facts.user_type.c_str()) + "\"");
}

void CheckRegProgId(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!g_facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    bool ok;
    std::wstring prog_id = RegString(ClsidKey() + L"\\ProgID", nullptr, &ok);
    if (!ok || prog_id.empty()) return x.Fail("CLSID\\{...}\\ProgID", "none");
    g_facts.prog_id = prog_id;
    std::wstring back = RegString(prog_id + L"\\CLSID", nullptr, &ok);
    CLSID clsid = {};
    if (!ok || FAILED(CLSIDFromString(back.c_str(), &clsid)) || !IsEqualCLSID(clsid, g_facts.clsid))
        return x.Fail("HKCR\\" + Utf8(prog_id.c_str()) + "\\CLSID = " + GuidText(g_facts.clsid), ok ? Utf8(back.c_str()) : "no such value");
    RegString(prog_id, nullptr, &ok);
    if (!ok) return x.Fail("a description as the default value of HKCR\\" + Utf8(prog_id.c_str()), "none");
    x.Pass("ProgID " + Utf8(prog_id.c_str()) + ", whose CLSID key names the class");
}

void CheckRegVersionIndependent(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!g_facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    bool ok;
    std::wstring vi = RegString(ClsidKey() + L"\\VersionIndependentProgID", nullptr, &ok);
    if (!ok || vi.empty()) return x.NotApplicable("no VersionIndependentProgID registered");
    g_facts.vi_prog_id = vi;
    std::wstring back = RegString(vi + L"\\CLSID", nullptr, &ok);
    CLSID clsid = {};
    if (!ok || FAILED(CLSIDFromString(back.c_str(), &clsid)) || !IsEqualCLSID(clsid, g_facts.clsid))
        return x.Fail("HKCR\\" + Utf8(vi.c_str()) + "\\CLSID = " + GuidText(g_facts.clsid), ok ? Utf8(back.c_str()) : "no such value");
    std::wstring cur = RegString(vi + L"\\CurVer", nullptr, &ok);
    if (!ok) return x.Fail("HKCR\\" + Utf8(vi.c_str()) + "\\CurVer = " + Utf8(g_facts.prog_id.c_str()), "no CurVer key");
    if (!g_facts.prog_id.empty() && _wcsicmp(cur.c_str(), g_facts.prog_id.c_str()) != 0)
        return x.Fail("HKCR\\" + Utf8(vi.c_str()) + "\\CurVer = " + Utf8(g_facts.prog_id.c_str()), Utf8(cur.c_str()));
    x.Pass("VersionIndependentProgID " + Utf8(vi.c_str()) + ", CLSID and CurVer (" + Utf8(cur.c_str()) + ") consistent");
}

// The program path of an InprocServer32 / LocalServer32 value: quotes removed, arguments dropped.
std::wstring ModulePathOf(const std::wstring &value) {
    std::wstring v = value;
    if (!v.empty() && v[0] == L'"') {
        size_t end = v.find(L'"', 1);
        return v.substr(1, end == std::wstring::npos ? std::wstring::npos : end - 1);
    }
    if (GetFileAttributesW(v.c_str()) != INVALID_FILE_ATTRIBUTES) return v;
    // Unquoted with arguments: the longest prefix ending at a space that names a file.
    for (size_t i = v.size(); i > 0; i--)
        if (v[i - 1] == L' ') {
            std::wstring p = v.substr(0, i - 1);
            if (GetFileAttributesW(p.c_str()) != INVALID_FILE_ATTRIBUTES) return p;
        }
    size_t space = v.find(L' ');
    return space == std::wstring::npos ? v : v.substr(0, space);
}

void CheckRegModule(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!g_facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    bool ok;
    LPCWSTR keys[] = {L"InprocServer32", L"LocalServer32"};
    for (LPCWSTR k : keys) {
        std::wstring value = RegString(ClsidKey() + L"\\" + k, nullptr, &ok);
        if (!ok) continue;
        g_facts.module_key = k;
        g_facts.module = ModulePathOf(value);
        DWORD attr = GetFileAttributesW(g_facts.module.c_str());
        if (attr == INVALID_FILE_ATTRIBUTES || (attr & FILE_ATTRIBUTE_DIRECTORY))
            return x.Fail(Utf8(k) + " naming an existing file", "\"" + Utf8(value.c_str()) + "\": no such file");
        bool full = g_facts.module.size() > 2 && (g_facts.module[1] == L':' || (g_facts.module[0] == L'\\' && g_facts.module[1] == L'\\'));
        if (!full) return x.Fail(Utf8(k) + " with the module's full path", "\"" + Utf8(value.c_str()) + "\"");
        return x.Pass(Utf8(k) + " = " + Utf8(g_facts.module.c_str()) + " (exists)");
    }
    x.Fail("InprocServer32 or LocalServer32", "neither is registered");
}

void CheckRegCategories(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!g_facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    ReadCategories();
    bool ok;
    if (g_facts.categories.empty()) {
        if (!g_facts.prog_id.empty() && KeyExists(g_facts.prog_id + L"\\OPC"))
            return x.NotApplicable("no Implemented Categories: a Data Access 1.0 server registered the old way (ProgID\\OPC)");
        return x.Fail("at least one category under Implemented Categories", "none");
    }
    std::string list;
    bool any_opc = false;
    for (const CATID &cat : g_facts.categories) {
        std::wstring key = L"Component Categories\\" + GuidWide(cat);
        std::wstring description = RegString(key, L"409", &ok);
        LPWSTR standard = nullptr;
        bool opc = SUCCEEDED(OpcCategoryDescription(&cat, &standard));
        any_opc = any_opc || opc;
        std::wstring want = opc ? standard : L"";
        OpcTaskMemFree(standard);
        if (!ok)
            return x.Fail("HKCR\\" + Utf8(key.c_str()) + "\\409" + (opc ? " = \"" + Utf8(want.c_str()) + "\"" : " (a description)"), "not registered");
        if (opc && description != want)
            return x.Fail("\"" + Utf8(want.c_str()) + "\" for " + GuidText(cat), "\"" + Utf8(description.c_str()) + "\"",
                          "the standard description of an OPC category");
        list += (list.empty() ? "" : "; ") + Utf8(description.c_str());
    }
    x.Pass(Format("%u categor%s registered, each with its description%s: ", static_cast<unsigned>(g_facts.categories.size()),
                  g_facts.categories.size() == 1 ? "y" : "ies", any_opc ? " (the standard one for OPC categories)" : "") + list);
}

void CheckRegDa10(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!g_facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    ReadCategories();
    bool da10 = false;
    for (const CATID &c : g_facts.categories) da10 = da10 || IsEqualGUID(c, CATID_OPCDAServer10);
    if (!da10) return x.NotApplicable("not in the Data Access 1.0 category");
    if (g_facts.prog_id.empty()) return x.NotApplicable("no ProgID (see reg.progid)");
    if (!KeyExists(g_facts.prog_id + L"\\OPC")) return x.Fail("HKCR\\" + Utf8(g_facts.prog_id.c_str()) + "\\OPC", "no such key");
    bool ok;
    std::wstring vendor = RegString(g_facts.prog_id + L"\\OPC\\Vendor", nullptr, &ok);
    if (!ok) return x.Fail("HKCR\\" + Utf8(g_facts.prog_id.c_str()) + "\\OPC\\Vendor", "no such key");
    x.Pass("HKCR\\" + Utf8(g_facts.prog_id.c_str()) + "\\OPC\\Vendor = \"" + Utf8(vendor.c_str()) + "\"");
}

void CheckRegVersion(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its files are not read");
    if (g_facts.module.empty()) return x.NotApplicable("no module path (see reg.module)");
    DWORD handle = 0;
    DWORD size = GetFileVersionInfoSizeW(g_facts.module.c_str(), &handle);
    if (size == 0) return x.Fail("a VERSIONINFO resource in " + Utf8(g_facts.module.c_str()), "none");
    std::vector<BYTE> data(size);
    VS_FIXEDFILEINFO *fixed = nullptr;
    UINT len = 0;
    if (!GetFileVersionInfoW(g_facts.module.c_str(), 0, size, data.data()) ||
        !VerQueryValueW(data.data(), L"\\", reinterpret_cast<void **>(&fixed), &len) || !fixed || len < sizeof *fixed)
        return x.Fail("a VERSIONINFO resource with a fixed part", "unreadable");
    std::string file = Format("%u,%u,%u,%u", HIWORD(fixed->dwFileVersionMS), LOWORD(fixed->dwFileVersionMS),
                              HIWORD(fixed->dwFileVersionLS), LOWORD(fixed->dwFileVersionLS));
    std::string product = Format("%u,%u,%u,%u", HIWORD(fixed->dwProductVersionMS), LOWORD(fixed->dwProductVersionMS),
                                 HIWORD(fixed->dwProductVersionLS), LOWORD(fixed->dwProductVersionLS));
    OpcVersion version;
    if (FAILED(OpcVersionFromFileVersion(fixed->dwFileVersionMS, fixed->dwFileVersionLS, &version)))
        return x.Fail("FILEVERSION MM,mm,0,bb (the third number 0)", "FILEVERSION " + file);
    if (file != product) return x.Fail("PRODUCTVERSION the same as FILEVERSION " + file, "PRODUCTVERSION " + product);
    LPWSTR text = nullptr;
    std::string mmb = SUCCEEDED(OpcVersionFormat(&version, &text)) ? Utf8(text) : "?";
    OpcTaskMemFree(text);
    x.Pass("FILEVERSION and PRODUCTVERSION " + file + ": version " + mmb);
}

// ---- Server browsing (chapter 7) ----

IOPCServerList2 *g_list2;  // created by the first browsing check (any worker), kept
std::string g_list_source;

IOPCServerList2 *ServerList(Ctx &x) {
    if (g_list2) return g_list2;
    void *p = nullptr;
    HRESULT hr;
    if (Local()) {
        // What clients use: CLSID_OPCServerList as registered (OpcEnum, or opccomn.dll registered
        // with regsvr32); where none is registered or it cannot be created, the library's own.
        {
            Call c("CoCreateInstance(CLSID_OPCServerList)");
            hr = CoCreateInstance(CLSID_OPCServerList, nullptr, CLSCTX_ALL, IID_IOPCServerList2, &p);
        }
        if (SUCCEEDED(hr) && p) {
            g_list_source = "the registered OPCServerList (CLSID_OPCServerList)";
        } else {
            std::string why = Hr(hr);
            hr = OpcServerListCreate(nullptr, IID_IOPCServerList2, &p);
            g_list_source = "the library's server browser (OpcServerListCreate; CLSID_OPCServerList: " + why + ")";
        }
    } else {
        COSERVERINFO info;
        MULTI_QI mqi = {&IID_IOPCServerList2, nullptr, S_OK};
        Call c("CoCreateInstanceEx(CLSID_OPCServerList)");
        hr = CoCreateInstanceEx(CLSID_OPCServerList, nullptr, kHostContext, ServerInfo(&info), 1, &mqi);
        if (SUCCEEDED(hr)) hr = mqi.hr;
        p = mqi.pItf;
        g_list_source = "OPCServerList on " + Utf8(g_opt.host.c_str());
    }
    if (FAILED(hr) || !p) {
        x.NotApplicable("no server list: " + Hr(hr));
        return nullptr;
    }
    g_list2 = static_cast<IOPCServerList2 *>(p);
    return g_list2;
}

void CheckBrowseListed(Ctx &x) {
    IOPCServerList2 *list = ServerList(x);
    if (!list) return;
    ReadCategories();
    std::vector<CATID> cats = g_facts.categories;
    if (cats.empty()) {
        if (!Local()) return x.NotApplicable("the categories of a server on another machine are not known");
        if (!g_facts.prog_id.empty() && KeyExists(g_facts.prog_id + L"\\OPC")) cats.push_back(CATID_OPCDAServer10);
        else return x.NotApplicable("the server claims no category (see reg.categories)");
    }
    std::string found;
    for (CATID cat : cats) {
        IOPCEnumGUID *classes = nullptr;
        HRESULT hr;
        {
            Call c("IOPCServerList2::EnumClassesOfCategories");
            hr = list->EnumClassesOfCategories(1, &cat, 0, nullptr, &classes);
        }
        if (FAILED(hr) || !classes) return x.Fail("EnumClassesOfCategories = S_OK", Hr(hr), "category " + GuidText(cat));
        bool listed = false;
        for (;;) {
            GUID g[16];
            ULONG fetched = 0;
            {
                Call c("IOPCEnumGUID::Next");
                hr = classes->Next(16, g, &fetched);
            }
            for (ULONG i = 0; i < fetched && i < 16; i++) listed = listed || IsEqualCLSID(g[i], g_facts.clsid);
            if (hr != S_OK || fetched == 0) break;
        }
        classes->Release();
        if (!listed) return x.Fail("the class listed under category " + GuidText(cat), "not listed", g_list_source);
        found += (found.empty() ? "" : ", ") + GuidText(cat);
    }
    x.Pass("listed by " + g_list_source + " under " + found);
}

void CheckBrowseDetails(Ctx &x) {
    IOPCServerList2 *list = ServerList(x);
    if (!list) return;
    LPOLESTR prog_id = nullptr, user_type = nullptr, vi = nullptr;
    HRESULT hr;
    {
        Call c("IOPCServerList2::GetClassDetails");
        hr = list->GetClassDetails(g_facts.clsid, &prog_id, &user_type, &vi);
    }
    std::string got = Hr(hr) + ": \"" + Utf8(prog_id) + "\", \"" + Utf8(user_type) + "\", \"" + Utf8(vi) + "\"";
    std::wstring p = prog_id ? prog_id : L"", u = user_type ? user_type : L"", v = vi ? vi : L"";
    CoTaskMemFree(prog_id);
    CoTaskMemFree(user_type);
    CoTaskMemFree(vi);
    if (FAILED(hr)) return x.Fail("S_OK and the class's details", got);
    if (Local() && g_facts.clsid_key && !g_facts.prog_id.empty()) {
        std::string want = "\"" + Utf8(g_facts.prog_id.c_str()) + "\", \"" + Utf8(g_facts.user_type.c_str()) + "\", \"" + Utf8(g_facts.vi_prog_id.c_str()) + "\"";
        if (p != g_facts.prog_id || u != g_facts.user_type || v != g_facts.vi_prog_id)
            return x.Fail("the registry's " + want, got, g_list_source);
        return x.Pass("GetClassDetails: " + want + ", as in the registry");
    }
    if (p.empty()) return x.Fail("a ProgID", got);
    g_facts.prog_id = p, g_facts.user_type = u, g_facts.vi_prog_id = v;
    x.Pass("GetClassDetails: " + got + (Local() ? " (nothing to compare: the registry checks found no registration)" : ""));
}

void CheckBrowseProgId(Ctx &x) {
    IOPCServerList2 *list = ServerList(x);
    if (!list) return;
    if (g_facts.prog_id.empty()) return x.NotApplicable("no ProgID known (see reg.progid)");
    CLSID clsid = {};
    HRESULT hr;
    {
        Call c("IOPCServerList2::CLSIDFromProgID");
        hr = list->CLSIDFromProgID(g_facts.prog_id.c_str(), &clsid);
    }
    if (hr != S_OK || !IsEqualCLSID(clsid, g_facts.clsid))
        return x.Fail("S_OK, " + GuidText(g_facts.clsid), Hr(hr) + ", " + GuidText(clsid));
    x.Pass("CLSIDFromProgID(" + Utf8(g_facts.prog_id.c_str()) + ") = " + GuidText(clsid));
}

// ---- DCOM security (--dcom): the AppID and the machine's settings, as Windows' DCOM hardening
// (KB5004442, CVE-2021-26414, enforced since March 2023) needs them ----

const wchar_t kOleKey[] = L"SOFTWARE\\Microsoft\\Ole";
const wchar_t kAppCompatKey[] = L"SOFTWARE\\Microsoft\\Ole\\AppCompat";
const DWORD kPktIntegrity = 5;  // RPC_C_AUTHN_LEVEL_PKT_INTEGRITY

// A registry value of any type: false when it does not exist.
bool RegRaw(HKEY root, const std::wstring &key, LPCWSTR name, DWORD *type, std::vector<BYTE> *data) {
    DWORD size = 0;
    if (RegGetValueW(root, key.c_str(), name, RRF_RT_ANY | RRF_NOEXPAND, type, nullptr, &size) != ERROR_SUCCESS) return false;
    data->assign(size, 0);
    if (size && RegGetValueW(root, key.c_str(), name, RRF_RT_ANY | RRF_NOEXPAND, type, data->data(), &size) != ERROR_SUCCESS)
        return false;
    data->resize(size);
    return true;
}

// A value read for the report: "not set", a number, text, or what it is when it is neither.
struct RegFact {
    bool exists = false;
    DWORD type = REG_NONE;
    std::vector<BYTE> data;
    bool Dword(DWORD *v) const {
        if (!exists || type != REG_DWORD || data.size() != 4) return false;
        memcpy(v, data.data(), 4);
        return true;
    }
};

RegFact ReadFact(HKEY root, const std::wstring &key, LPCWSTR name) {
    RegFact f;
    f.exists = RegRaw(root, key, name, &f.type, &f.data);
    return f;
}

const char *LevelName(DWORD level) {
    static const char *const names[] = {"DEFAULT", "NONE", "CONNECT", "CALL", "PKT", "PKT_INTEGRITY", "PKT_PRIVACY"};
    return level < 7 ? names[level] : "not a level";
}

std::string LevelText(DWORD level) { return Format("%lu (RPC_C_AUTHN_LEVEL_%s)", static_cast<unsigned long>(level), LevelName(level)); }

// The SDDL of a binary self-relative security descriptor, as Windows writes it; false when it is
// not a valid descriptor.
bool SddlOf(const std::vector<BYTE> &sd, std::string *sddl) {
    if (sd.size() < 20 || !IsValidSecurityDescriptor(const_cast<BYTE *>(sd.data()))) return false;
    LPWSTR text = nullptr;
    if (!ConvertSecurityDescriptorToStringSecurityDescriptorW(const_cast<BYTE *>(sd.data()), SDDL_REVISION_1,
                                                              OWNER_SECURITY_INFORMATION | GROUP_SECURITY_INFORMATION |
                                                                  DACL_SECURITY_INFORMATION,
                                                              &text, nullptr))
        return false;
    *sddl = Utf8(text);
    LocalFree(text);
    return true;
}

// What the machine's value `name` under HKLM\SOFTWARE\Microsoft\Ole says, for reports.
std::string MachineLevelText() {
    RegFact f = ReadFact(HKEY_LOCAL_MACHINE, kOleKey, L"LegacyAuthenticationLevel");
    DWORD v;
    if (f.Dword(&v)) return "HKLM\\SOFTWARE\\Microsoft\\Ole LegacyAuthenticationLevel = " + LevelText(v);
    return "HKLM\\SOFTWARE\\Microsoft\\Ole LegacyAuthenticationLevel not set (Windows then uses CONNECT)";
}

std::string MachinePermissionText(LPCWSTR name) {
    RegFact f = ReadFact(HKEY_LOCAL_MACHINE, kOleKey, name);
    std::string sddl;
    if (!f.exists) return "HKLM\\SOFTWARE\\Microsoft\\Ole " + Utf8(name) + " not set (Windows' built-in default)";
    if (f.type != REG_BINARY || !SddlOf(f.data, &sddl)) return "HKLM\\SOFTWARE\\Microsoft\\Ole " + Utf8(name) + " is not a valid security descriptor";
    return "HKLM\\SOFTWARE\\Microsoft\\Ole " + Utf8(name) + " = " + sddl;
}

struct AppIdFacts {
    bool read = false;
    bool named = false;      // CLSID\{clsid} has an AppID value
    bool key = false;        // HKCR\AppID\{appid} exists
    bool local = false;      // the class has a LocalServer32
    std::wstring app_id;     // "{...}" as registered
    std::wstring exe;        // the LocalServer32 program's file name
    std::wstring exe_app_id; // HKCR\AppID\<exe> AppID, if any
} g_app;

void ReadAppId() {
    if (g_app.read) return;
    g_app.read = true;
    bool ok;
    g_app.app_id = RegString(ClsidKey(), L"AppID", &ok);
    g_app.named = ok && !g_app.app_id.empty();
    if (g_app.named) g_app.key = KeyExists(L"AppID\\" + g_app.app_id);
    std::wstring command = RegString(ClsidKey() + L"\\LocalServer32", nullptr, &ok);
    g_app.local = ok;
    if (ok) {
        std::wstring path = ModulePathOf(command);
        size_t slash = path.find_last_of(L"\\/");
        g_app.exe = slash == std::wstring::npos ? path : path.substr(slash + 1);
        if (!g_app.exe.empty()) {
            g_app.exe_app_id = RegString(L"AppID\\" + g_app.exe, L"AppID", &ok);
            if (!ok) g_app.exe_app_id.clear();
        }
    }
}

std::wstring AppKey() { return L"AppID\\" + g_app.app_id; }

// Why a DCOM check does not apply, or "" when it does.
std::string DcomNotApplicable() {
    if (!Local()) return "a server on another machine: its registry is not read";
    if (!g_facts.clsid_key) return "no CLSID key (see reg.clsid)";
    ReadAppId();
    if (!g_app.named || !g_app.key) return "no AppID (see dcom.appid)";
    return "";
}

void CheckDcomAppId(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!g_facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    ReadAppId();
    std::string app = Utf8(g_app.app_id.c_str());
    if (!g_app.named) {
        if (!g_app.local)
            return x.NotApplicable("an in-process server without an AppID: the client's process security applies");
        return x.Warn("an AppID for the EXE server's DCOM settings (CLSID\\{clsid} AppID)", "none",
                      "the machine's defaults apply: " + MachineLevelText() + "; " + MachinePermissionText(L"DefaultAccessPermission") +
                          "; " + MachinePermissionText(L"DefaultLaunchPermission"));
    }
    if (!g_app.key) return x.Fail("HKCR\\AppID\\" + app, "no such key (CLSID\\{clsid} names AppID " + app + ")");
    bool ok;
    std::wstring name = RegString(AppKey(), nullptr, &ok);
    std::string detail = "AppID " + app + (ok ? " \"" + Utf8(name.c_str()) + "\"" : "");
    if (g_app.local) {
        if (g_app.exe_app_id.empty())
            return x.Warn("HKCR\\AppID\\" + Utf8(g_app.exe.c_str()) + " AppID = " + app, "no such value",
                          "COM finds the AppID of an EXE server started by hand (not by COM) through its file name");
        if (_wcsicmp(g_app.exe_app_id.c_str(), g_app.app_id.c_str()) != 0)
            return x.Fail("HKCR\\AppID\\" + Utf8(g_app.exe.c_str()) + " AppID = " + app, Utf8(g_app.exe_app_id.c_str()));
        detail += "; AppID\\" + Utf8(g_app.exe.c_str()) + " names it";
    }
    x.Pass(detail);
}

void CheckDcomLevel(Ctx &x) {
    std::string why = DcomNotApplicable();
    if (!why.empty()) return x.NotApplicable(why);
    RegFact f = ReadFact(HKEY_CLASSES_ROOT, AppKey(), L"AuthenticationLevel");
    DWORD level = 0;
    if (!f.exists || (f.Dword(&level) && level == 0))
        return x.Warn("AuthenticationLevel 5 (PKT_INTEGRITY) or 6 (PKT_PRIVACY)", f.exists ? "0 (DEFAULT)" : "not set",
                      "the machine default applies: " + MachineLevelText());
    if (!f.Dword(&level)) return x.Fail("AuthenticationLevel as a REG_DWORD", Format("a value of type %lu", static_cast<unsigned long>(f.type)));
    if (level > 6) return x.Fail("AuthenticationLevel 5 (PKT_INTEGRITY) or 6 (PKT_PRIVACY)", Format("%lu, not an authentication level", static_cast<unsigned long>(level)));
    if (level < kPktIntegrity)
        return x.Fail("AuthenticationLevel 5 (PKT_INTEGRITY) or 6 (PKT_PRIVACY)", LevelText(level),
                      "below PKT_INTEGRITY: since Windows' DCOM hardening (KB5004442, CVE-2021-26414; enforced since "
                      "March 2023) clients on other machines are refused or lose their calls; register the AppID "
                      "with level 5 or more");
    x.Pass("AuthenticationLevel = " + LevelText(level));
}

// A permission of the AppID: set (printed as SDDL) or the machine default.
void CheckDcomPermission(Ctx &x, LPCWSTR name, LPCWSTR machine_default) {
    std::string why = DcomNotApplicable();
    if (!why.empty()) return x.NotApplicable(why);
    RegFact f = ReadFact(HKEY_CLASSES_ROOT, AppKey(), name);
    std::string sddl;
    if (!f.exists)
        return x.Warn(Utf8(name) + " of the AppID", "not set", "the machine default applies: " + MachinePermissionText(machine_default));
    if (f.type != REG_BINARY || !SddlOf(f.data, &sddl))
        return x.Fail(Utf8(name) + " as a REG_BINARY self-relative security descriptor", "a value that is not one");
    // Everyone and ANONYMOUS LOGON allowed in: what the hardening is meant to end.
    for (const char *who : {";WD)", ";AN)"}) {
        for (size_t at = sddl.find("(A;"); at != std::string::npos; at = sddl.find("(A;", at + 1)) {
            size_t end = sddl.find(')', at);
            if (end != std::string::npos && sddl.compare(end - 3, 4, who) == 0)
                return x.Warn(Utf8(name) + " without Everyone (WD) or ANONYMOUS LOGON (AN) allowed", sddl,
                              "anyone on the network may use the server as far as the machine limits allow");
        }
    }
    x.Pass(Utf8(name) + " = " + sddl);
}

void CheckDcomAccess(Ctx &x) { CheckDcomPermission(x, L"AccessPermission", L"DefaultAccessPermission"); }
void CheckDcomLaunch(Ctx &x) { CheckDcomPermission(x, L"LaunchPermission", L"DefaultLaunchPermission"); }

void CheckDcomRunAs(Ctx &x) {
    std::string why = DcomNotApplicable();
    if (!why.empty()) return x.NotApplicable(why);
    bool ok, service;
    std::wstring run_as = RegString(AppKey(), L"RunAs", &ok);
    std::wstring local_service = RegString(AppKey(), L"LocalService", &service);
    if (service) return x.Pass("LocalService = " + Utf8(local_service.c_str()) + " (runs as that Windows service's account)");
    if (!ok) return x.Pass("no RunAs: the server runs as the user who launched it");
    if (_wcsicmp(run_as.c_str(), L"Interactive User") == 0)
        return x.Pass("RunAs = Interactive User (runs in the logged-on user's session; not without one)");
    x.Pass("RunAs = " + Utf8(run_as.c_str()));
}

void CheckDcomMachine(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    std::string detail;
    auto dword = [&](const wchar_t *key, LPCWSTR name, const char *missing) {
        DWORD v;
        RegFact f = ReadFact(HKEY_LOCAL_MACHINE, key, name);
        detail += (detail.empty() ? "" : "; ") + Utf8(name) + " = " +
                  (f.Dword(&v) ? Format("%lu", static_cast<unsigned long>(v)) : f.exists ? std::string("(not a DWORD)") : std::string(missing));
        return f.Dword(&v) ? static_cast<long>(v) : -1L;
    };
    bool ok;
    std::wstring enable = L"";
    {
        RegFact f = ReadFact(HKEY_LOCAL_MACHINE, kOleKey, L"EnableDCOM");
        if (f.exists && (f.type == REG_SZ || f.type == REG_EXPAND_SZ) && f.data.size() >= 2) enable = reinterpret_cast<const wchar_t *>(f.data.data());
        ok = f.exists;
    }
    detail = "EnableDCOM = " + (ok ? "\"" + Utf8(enable.c_str()) + "\"" : std::string("not set (Y)"));
    dword(kOleKey, L"LegacyAuthenticationLevel", "not set (CONNECT)");
    dword(kOleKey, L"LegacyImpersonationLevel", "not set (IDENTIFY)");
    for (LPCWSTR name : {L"DefaultAccessPermission", L"DefaultLaunchPermission", L"MachineAccessRestriction", L"MachineLaunchRestriction"})
        detail += std::string("; ") + Utf8(name) + (ReadFact(HKEY_LOCAL_MACHINE, kOleKey, name).exists ? " set" : " not set");
    long require = dword(kAppCompatKey, L"RequireIntegrityActivationAuthenticationLevel", "not set (on)");
    dword(kAppCompatKey, L"RaiseActivationAuthenticationLevel", "not set (2 since November 2022)");
    detail += Format("; this checker's calls: CoInitializeSecurity(RPC_C_AUTHN_LEVEL_PKT_INTEGRITY) = %s", Hr(g_security_hr).c_str());
    if (ok && (enable == L"N" || enable == L"n")) return x.Warn("EnableDCOM = \"Y\"", "\"N\"", "no remote client reaches any server here; " + detail);
    if (require == 0)
        return x.Warn("RequireIntegrityActivationAuthenticationLevel on", "0 (off)",
                      "the KB5004442 hardening is turned off on this machine (Windows updates since March 2023 ignore that); " + detail);
    x.Pass(detail);
}

void CheckDcomBrowser(Ctx &x) {
    if (!Local()) return x.NotApplicable("a server on another machine: its registry is not read (its browser answered if the ProgID resolved)");
    std::wstring key = L"CLSID\\" + GuidWide(CLSID_OPCServerList);
    bool ok;
    std::wstring command = RegString(key + L"\\LocalServer32", nullptr, &ok);
    if (!ok) {
        bool inproc = KeyExists(key + L"\\InprocServer32");
        return x.Warn("CLSID_OPCServerList registered as an EXE server (OpcEnum or opccomn_browser)",
                      inproc ? "an in-process server list only" : "none",
                      "clients on other machines cannot browse this machine's servers (specification 7.1)");
    }
    std::string detail = "CLSID_OPCServerList: " + Utf8(command.c_str());
    std::wstring app = RegString(key, L"AppID", &ok);
    if (ok) {
        RegFact f = ReadFact(HKEY_CLASSES_ROOT, L"AppID\\" + app, L"AuthenticationLevel");
        DWORD level;
        if (f.Dword(&level) && level != 0 && level < kPktIntegrity)
            return x.Warn("the browser's AppID at PKT_INTEGRITY or above", LevelText(level),
                          "remote browsing fails since KB5004442; " + detail);
        detail += ", AppID " + Utf8(app.c_str()) + " AuthenticationLevel " + (f.Dword(&level) ? LevelText(level) : std::string("not set"));
    }
    x.Pass(detail);
}

// ---- Hostile (--hostile): NULL out-parameters and absurd counts ----

void HostileNullLocale(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    HRESULT hr;
    {
        Call c("IOPCCommon::GetLocaleID(NULL)");
        hr = common->GetLocaleID(nullptr);
    }
    if (hr != E_INVALIDARG && hr != E_POINTER && hr != HRESULT_FROM_WIN32(RPC_X_NULL_REF_POINTER))
        return x.Fail("E_INVALIDARG (E_POINTER accepted; through a proxy RPC_X_NULL_REF_POINTER)", Hr(hr));
    x.Pass("GetLocaleID(NULL) = " + Hr(hr));
}

void HostileNullLocaleArray(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    DWORD count = 0xDEADBEEF;
    LCID *array = reinterpret_cast<LCID *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT a, b;
    {
        Call c("IOPCCommon::QueryAvailableLocaleIDs(&count, NULL)");
        a = common->QueryAvailableLocaleIDs(&count, nullptr);
    }
    {
        Call c("IOPCCommon::QueryAvailableLocaleIDs(NULL, &array)");
        b = common->QueryAvailableLocaleIDs(nullptr, &array);
    }
    if (SUCCEEDED(a) || SUCCEEDED(b))
        return x.Fail("a failure code for each NULL out-parameter", Hr(a) + ", " + Hr(b));
    // Through a proxy the NULL never reaches the server: the proxy refuses the call and leaves the
    // other out-parameter alone, which says nothing about the server.
    if (!x.s.proxy) {
        if (count != 0) return x.Fail("the count set to 0 on failure (3.1.3)", Format("%lu", static_cast<unsigned long>(count)));
        if (array != nullptr) return x.Fail("the array set to NULL on failure (3.1.3)", "left as it was");
    }
    x.Pass("NULL count: " + Hr(b) + "; NULL array: " + Hr(a) + (x.s.proxy ? " (refused by the proxy)" : "; the other out-parameter cleared"));
}

// A call with a NULL where the method needs a pointer, which must fail: `call` is what the progress line
// names, `shown` what the report says was called.
template <typename F>
void MustFail(Ctx &x, const char *call, const char *shown, const char *expected, F f) {
    HRESULT hr;
    {
        Call c(call);
        hr = f();
    }
    if (SUCCEEDED(hr)) return x.Fail(expected, Hr(hr));
    x.Pass(std::string(shown) + " = " + Hr(hr));
}

void HostileNullErrorString(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    MustFail(x, "IOPCCommon::GetErrorString(code, NULL)", "GetErrorString(E_FAIL, NULL)", "E_INVALIDARG",
             [&] { return common->GetErrorString(E_FAIL, nullptr); });
}

void HostileNullClientName(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    MustFail(x, "IOPCCommon::SetClientName(NULL)", "SetClientName(NULL)", "E_INVALIDARG",
             [&] { return common->SetClientName(nullptr); });
}

void HostileLongClientName(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    std::wstring name(1u << 20, L'x');  // a million characters
    HRESULT hr;
    {
        Call c("IOPCCommon::SetClientName(1,048,576 characters)");
        hr = common->SetClientName(name.c_str());
    }
    if (hr != S_OK && hr != E_INVALIDARG && hr != E_OUTOFMEMORY)
        return x.Fail("S_OK, E_INVALIDARG or E_OUTOFMEMORY", Hr(hr));
    x.Pass("SetClientName of 1,048,576 characters = " + Hr(hr));
}

void HostileFindNull(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    MustFail(x, "IConnectionPointContainer::FindConnectionPoint(IID_IOPCShutdown, NULL)",
             "FindConnectionPoint(IID_IOPCShutdown, NULL)", "E_POINTER",
             [&] { return container->FindConnectionPoint(IID_IOPCShutdown, nullptr); });
}

void HostileAdviseNull(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    DWORD cookie = 0xDEADBEEF;
    HRESULT a, b;
    {
        Call c("IConnectionPoint::Advise(NULL, &cookie)");
        a = point->Advise(nullptr, &cookie);
    }
    IUnknown *sink = NewSink();
    {
        Call c("IConnectionPoint::Advise(sink, NULL)");
        b = point->Advise(sink, nullptr);
    }
    if (sink) sink->Release();
    if (SUCCEEDED(a) || SUCCEEDED(b)) return x.Fail("a failure code for each", Hr(a) + ", " + Hr(b));
    if (cookie != 0 && !x.s.proxy) return x.Fail("the cookie set to 0 on failure (3.1.3)", Format("%lu", static_cast<unsigned long>(cookie)));
    x.Pass("Advise(NULL, &cookie) = " + Hr(a) + " with cookie 0; Advise(sink, NULL) = " + Hr(b));
}

void HostileUnadviseZero(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    HRESULT hr;
    {
        Call c("IConnectionPoint::Unadvise(0)");
        hr = point->Unadvise(0);
    }
    if (hr != CONNECT_E_NOCONNECTION) return x.Fail("CONNECT_E_NOCONNECTION", Hr(hr));
    x.Pass("Unadvise(0) = CONNECT_E_NOCONNECTION");
}

void HostileEnumHuge(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    IEnumConnectionPoints *points = nullptr;
    HRESULT hr;
    {
        Call c("IConnectionPointContainer::EnumConnectionPoints");
        hr = container->EnumConnectionPoints(&points);
    }
    if (hr != S_OK || !points) return x.NotApplicable("no connection point enumerator (see shutdown.enum-points)");
    // Room for 8; a count of 0xFFFFFFFF must give at most what the server has.
    IConnectionPoint *buf[8] = {};
    ULONG fetched = 0xDEADBEEF;
    {
        Call c("IEnumConnectionPoints::Next(0xFFFFFFFF, ...)");
        // In-process the absurd count reaches the server; a proxy would make the stub allocate for it.
        hr = points->Next(x.s.proxy ? 8u : 0xFFFFFFFFu, buf, &fetched);
    }
    ULONG got = fetched;
    for (ULONG i = 0; i < 8; i++)
        if (buf[i] && i < got) buf[i]->Release();
    HRESULT skip;
    {
        Call c("IEnumConnectionPoints::Skip(0xFFFFFFFF)");
        skip = points->Skip(0xFFFFFFFFu);
    }
    points->Release();
    if (SUCCEEDED(hr) && got > 8) return x.Fail("at most the enumerator's elements", Format("%lu fetched", static_cast<unsigned long>(got)));
    if (FAILED(skip) && skip != E_INVALIDARG) return x.Fail("Skip(0xFFFFFFFF) = S_FALSE", Hr(skip));
    x.Pass("Next(0xFFFFFFFF) = " + Hr(hr) + Format(", %lu fetched; Skip(0xFFFFFFFF) = ", static_cast<unsigned long>(got)) + Hr(skip));
}

const CheckDef kChecks[] = {
    {"server.create", "6.3", "the server object is created as a client creates it", CheckCreate, kDefault},
    {"common.interface", "5", "the server object has IOPCCommon", CheckCommonInterface, kDefault},
    {"common.locale.default", "5.1.1", "a new session's locale is LOCALE_SYSTEM_DEFAULT", CheckDefaultLocale, kDefault},
    {"common.locales.array", "5.1.3, 3.1.3", "QueryAvailableLocaleIDs returns a task-memory array", CheckLocaleArray, kDefault},
    {"common.locales.set", "5.1.1, 5.1.2", "every available locale can be set and read back", CheckSetEveryLocale, kDefault},
    {"common.locales.unsupported", "5.1.1", "an unlisted LCID gives E_INVALIDARG and leaves the locale", CheckUnsupportedLocale, kDefault},
    {"common.errorstring.published", "5.1.4", "GetErrorString answers every published code of the kind with a text of its own", CheckPublishedCodes, kDefault},
    {"common.errorstring.unknown", "5.1.4", "GetErrorString of an unknown code gives E_INVALIDARG and NULL", CheckUnknownCode, kDefault},
    {"common.clientname", "5.1.5", "SetClientName accepts a name", CheckClientName, kDefault},
    {"shutdown.container", "4.1", "the server object has IConnectionPointContainer", CheckContainer, kDefault},
    {"shutdown.find", "4.1.2", "FindConnectionPoint(IID_IOPCShutdown) gives the connection point", CheckFind, kDefault},
    {"shutdown.point-container", "4.1", "the connection point's GetConnectionPointContainer gives the server object", CheckPointContainer, kDefault},
    {"shutdown.enum-points", "4.1.1", "EnumConnectionPoints includes IOPCShutdown", CheckEnumPoints, kDefault},
    {"shutdown.advise-wrong-sink", "4.2", "Advise of an object without IOPCShutdown gives CONNECT_E_CANNOTCONNECT", CheckWrongSink, kDefault},
    {"shutdown.advise", "4.2", "Advise of a shutdown sink gives S_OK and a non-zero cookie", CheckAdvise, kDefault},
    {"shutdown.advise-second", "4.1", "a second Advise gives S_OK or CONNECT_E_ADVISELIMIT", CheckSecondAdvise, kDefault},
    {"shutdown.unadvise-unknown", "4.1", "Unadvise of an unknown cookie gives CONNECT_E_NOCONNECTION", CheckUnadviseUnknown, kDefault},
    {"shutdown.find-other", "4.1.2", "FindConnectionPoint of another IID gives CONNECT_E_NOCONNECTION and NULL", CheckFindOther, kDefault},
    {"shutdown.enum-connections", "4.1", "EnumConnections works or is E_NOTIMPL", CheckEnumConnections, kDefault},
    {"shutdown.unadvise", "4.2", "Unadvise of the connection succeeds, once", CheckUnadvise, kDefault},
    {"reg.clsid", "6.3", "HKCR\\CLSID\\{clsid} with a description", CheckRegClsid, kDefault},
    {"reg.progid", "6.3", "ProgID registered both ways", CheckRegProgId, kDefault},
    {"reg.version-independent", "6.3", "VersionIndependentProgID, its CLSID and CurVer consistent", CheckRegVersionIndependent, kDefault},
    {"reg.module", "6.3", "the registered module path exists", CheckRegModule, kDefault},
    {"reg.categories", "6.1.1.1", "the claimed categories are registered with their standard descriptions", CheckRegCategories, kDefault},
    {"reg.da10", "6.3", "a Data Access 1.0 server has its ProgID\\OPC\\Vendor key", CheckRegDa10, kDefault},
    {"reg.version", "6.4", "the module has a version resource in the MM.mm.bb convention", CheckRegVersion, kDefault},
    {"browse.listed", "7.5.1", "IOPCServerList lists the server under each category it claims", CheckBrowseListed, kDefault},
    {"browse.details", "7.5.2", "GetClassDetails gives the registry's ProgID, user type and version-independent ProgID", CheckBrowseDetails, kDefault},
    {"browse.progid", "7.5.3", "CLSIDFromProgID gives the class", CheckBrowseProgId, kDefault},
    {"dcom.appid", "6.3", "the class's AppID (its DCOM settings) is registered", CheckDcomAppId, kDcom},
    {"dcom.authentication-level", "6.3", "the AppID's AuthenticationLevel is PKT_INTEGRITY or above (KB5004442)", CheckDcomLevel, kDcom},
    {"dcom.access-permission", "6.3", "the AppID's AccessPermission is set (SDDL) or the machine default applies", CheckDcomAccess, kDcom},
    {"dcom.launch-permission", "6.3", "the AppID's LaunchPermission is set (SDDL) or the machine default applies", CheckDcomLaunch, kDcom},
    {"dcom.runas", "6.3", "whom the server runs as (RunAs, LocalService)", CheckDcomRunAs, kDcom},
    {"dcom.machine", "6.3", "the machine's DCOM and hardening settings", CheckDcomMachine, kDcom},
    {"dcom.browser", "7.1, 7.2", "a server browser (CLSID_OPCServerList) serves remote clients", CheckDcomBrowser, kDcom},
    {"hostile.getlocale-null", "5.1.2, 3.1.3", "GetLocaleID(NULL) fails cleanly", HostileNullLocale, kHostile},
    {"hostile.locales-null", "5.1.3, 3.1.3", "QueryAvailableLocaleIDs with a NULL out-parameter fails and clears the other", HostileNullLocaleArray, kHostile},
    {"hostile.errorstring-null", "5.1.4", "GetErrorString(code, NULL) fails cleanly", HostileNullErrorString, kHostile},
    {"hostile.clientname-null", "5.1.5", "SetClientName(NULL) fails cleanly", HostileNullClientName, kHostile},
    {"hostile.clientname-long", "5.1.5", "SetClientName of a million characters is handled", HostileLongClientName, kHostile},
    {"hostile.find-null", "4.1.2", "FindConnectionPoint with a NULL out-pointer fails cleanly", HostileFindNull, kHostile},
    {"hostile.advise-null", "4.2, 3.1.3", "Advise with a NULL sink or cookie pointer fails cleanly", HostileAdviseNull, kHostile},
    {"hostile.unadvise-zero", "4.1", "Unadvise(0) gives CONNECT_E_NOCONNECTION", HostileUnadviseZero, kHostile},
    {"hostile.enum-huge", "4.1.1", "IEnumConnectionPoints::Next and Skip with a count of 0xFFFFFFFF", HostileEnumHuge, kHostile},
};
const int kCheckCount = static_cast<int>(sizeof kChecks / sizeof kChecks[0]);

bool Selected(int i) {
    return kChecks[i].set == kDefault || (kChecks[i].set == kHostile && g_opt.hostile) || (kChecks[i].set == kDcom && g_opt.dcom);
}

// ---------------------------------------------------------------------------------------------
// The worker thread and the watchdog
// ---------------------------------------------------------------------------------------------

volatile LONG g_next_check;  // where a (new) worker starts

bool ServerGone(Session &s, HRESULT *why);

void Record(int index, const Result &r) {
    EnterCriticalSection(&g_results_lock);
    g_results[static_cast<size_t>(index)] = r;
    LeaveCriticalSection(&g_results_lock);
}

DWORD WINAPI Worker(void *) {
    t_generation = g_generation;
    CoInitializeEx(nullptr, COINIT_MULTITHREADED);
    Session *session = new Session();  // leaked with the thread if the server crashes or hangs
    int selected_total = 0, position = 0;
    for (int i = 0; i < kCheckCount; i++) selected_total += Selected(i);
    for (int i = 0; i < static_cast<int>(g_next_check); i++) position += Selected(i);
    for (int i = g_next_check; i < kCheckCount; i++) {
        if (!Selected(i)) continue;
        InterlockedExchange(&g_current_check, i);
        fprintf(stderr, "opccomn-check: [%2d/%d] %s\n", ++position, selected_total, kChecks[i].id);
        Ctx x(*session);
        x.r.id = kChecks[i].id, x.r.section = kChecks[i].section, x.r.title = kChecks[i].title;
        kChecks[i].fn(x);
        EndIfStale();
        if (x.r.status == kNotRun) x.Fail("a result", "the check returned none (a bug of opccomn-check)");
        HRESULT gone = S_OK;
        if (x.r.status == kFailed && ServerGone(*session, &gone)) {
            // An out-of-process server that crashed: the check that made it crash fails, and the
            // rest runs against a new server process.
            x.r.got = "the server process ended during the check (" + Hr(gone) + "); the call had returned: " + x.r.got;
            x.r.detail = "the server crashed; the checker goes on with a new server object";
            fprintf(stderr, "opccomn-check: %s: %s\n", x.r.id.c_str(), x.r.got.c_str());
            session = new Session();  // the old one's proxies are dead: leaked, not released
        }
        Record(i, x.r);
    }
    InterlockedExchange(&g_current_check, -1);
    // The session's objects: released in reverse order, each call still watched.
    {
        Call c("releasing the server's interfaces");
        if (session->advised && session->server) OpcShutdownUnadvise(session->server, session->cookie);
        if (session->point) session->point->Release();
        if (session->container) session->container->Release();
        if (session->common) session->common->Release();
        if (session->server) session->server->Release();
        if (session->sink) session->sink->Release();
        if (session->sink2) session->sink2->Release();
    }
    delete session;
    CoUninitialize();
    return 0;
}

// Whether the server behind the session's proxy is gone (its process ended): a call the proxy
// cannot answer by itself (QueryInterface for an interface OPC servers do not have goes to the
// server) fails with one of the codes COM gives for a vanished server.
bool ServerGone(Session &s, HRESULT *why) {
    if (!s.server) return false;
    void *p = nullptr;
    HRESULT hr;
    {
        Call c("IUnknown::QueryInterface (is the server process still there?)");
        hr = s.server->QueryInterface(IID_IOPCEnumGUID, &p);
    }
    if (SUCCEEDED(hr) && p) static_cast<IUnknown *>(p)->Release();
    *why = hr;
    return hr == RPC_E_DISCONNECTED || hr == HRESULT_FROM_WIN32(RPC_S_SERVER_UNAVAILABLE) ||
           hr == HRESULT_FROM_WIN32(RPC_S_CALL_FAILED) || hr == HRESULT_FROM_WIN32(RPC_S_CALL_FAILED_DNE) ||
           hr == CO_E_OBJNOTCONNECTED || hr == RPC_E_SERVERFAULT;
}

// Runs the checks; returns false when a worker had to be abandoned (still stuck in a call).
bool RunAll() {
    bool abandoned = false;
    g_next_check = 0;
    for (;;) {
        InterlockedExchange(&g_worker_crashed, 0);
        InterlockedExchange(&g_call_active, 0);
        HANDLE worker = CreateThread(nullptr, 0, Worker, nullptr, 0, nullptr);
        if (!worker) {
            fprintf(stderr, "opccomn-check: cannot create a thread\n");
            ExitProcess(2);
        }
        bool hung = false;
        for (;;) {
            if (WaitForSingleObject(worker, 50) == WAIT_OBJECT_0) break;
            if (g_call_active && GetTickCount64() - g_call_started > g_opt.timeout_ms) {
                hung = true;
                break;
            }
        }
        int at = g_current_check;
        if (!hung && !g_worker_crashed) {
            if (at >= 0) {  // the thread ended inside the server without a crash report
                g_crash_code = 0xFFFFFFFF;
            } else {
                CloseHandle(worker);
                return !abandoned;
            }
        }
        if (hung && at < 0) {  // stuck releasing the objects after the last check
            fprintf(stderr, "opccomn-check: %s did not return within %lu ms after the last check\n", g_call_name,
                    static_cast<unsigned long>(g_opt.timeout_ms));
            CloseHandle(worker);
            return false;
        }
        Result r;
        r.id = kChecks[at].id, r.section = kChecks[at].section, r.title = kChecks[at].title;
        r.status = kFailed;
        r.expected = std::string("the call returns");
        if (hung) {
            r.got = Format("%s did not return within %lu ms", g_call_name, static_cast<unsigned long>(g_opt.timeout_ms));
            r.detail = "the server hangs; the checker goes on with a new server object";
            abandoned = true;
        } else {
            r.got = g_crash_code == 0xFFFFFFFF
                        ? Format("the checker's thread ended inside %s (no exception was reported)", g_call_name)
                        : Format("the server crashed in %s (exception 0x%08lX)", g_call_name, static_cast<unsigned long>(g_crash_code));
            r.detail = "an unhandled exception inside the server; the checker goes on with a new server object";
        }
        fprintf(stderr, "opccomn-check: %s: %s\n", r.id.c_str(), r.got.c_str());
        InterlockedIncrement(&g_generation);  // the old worker, if it ever returns, ends there
        Record(at, r);
        CloseHandle(worker);
        g_next_check = at + 1;
    }
}

// ---------------------------------------------------------------------------------------------
// Reports
// ---------------------------------------------------------------------------------------------

std::string Json(const std::string &s) {
    std::string o = "\"";
    for (unsigned char c : s) {
        if (c == '"') o += "\\\"";
        else if (c == '\\') o += "\\\\";
        else if (c == '\n') o += "\\n";
        else if (c == '\r') o += "\\r";
        else if (c == '\t') o += "\\t";
        else if (c < 0x20) o += Format("\\u%04x", c);
        else o += static_cast<char>(c);
    }
    return o + "\"";
}

std::string Xml(const std::string &s) {
    std::string o;
    for (unsigned char c : s) {
        if (c == '<') o += "&lt;";
        else if (c == '>') o += "&gt;";
        else if (c == '&') o += "&amp;";
        else if (c == '"') o += "&quot;";
        else if (c < 0x20 && c != '\n' && c != '\t') o += ' ';
        else o += static_cast<char>(c);
    }
    return o;
}

struct Counts {
    int n[5] = {0, 0, 0, 0, 0};
};

std::string g_server_text;  // "OpcComn.ExampleServer.1 {...}"

void Out(const std::string &s) { fwrite(s.data(), 1, s.size(), stdout); }

void ReportText(const std::vector<Result> &results, const Counts &c) {
    Out("opccomn-check " OPCCOMN_CHECK_VERSION ": " + g_server_text + "\n");
    for (const Result &r : results) {
        std::string line = Format("%s  %-13s %-30s ", kStatusTag[r.status], r.section.c_str(), r.id.c_str());
        if (r.status == kFailed || r.status == kWarning) {
            line += "expected " + r.expected + "; got " + r.got;
            if (!r.detail.empty()) line += " (" + r.detail + ")";
        } else {
            line += r.detail;
        }
        Out(line + "\n");
    }
    Out(Format("summary: %d passed, %d failed, %d warnings, %d not applicable, %d not run\n", c.n[kPassed], c.n[kFailed],
               c.n[kWarning], c.n[kNotApplicable], c.n[kNotRun]));
}

void ReportJson(const std::vector<Result> &results, const Counts &c) {
    Out("{\n  \"tool\": \"opccomn-check\",\n  \"version\": \"" OPCCOMN_CHECK_VERSION "\",\n");
    Out("  \"server\": {\"argument\": " + Json(Utf8(g_opt.server.c_str())) + ", \"clsid\": " +
        Json(g_facts.clsid_known ? GuidText(g_facts.clsid) : "") + ", \"host\": " + Json(Utf8(g_opt.host.c_str())) +
        ", \"kind\": " + Json(KindName()) + "},\n  \"checks\": [\n");
    for (size_t i = 0; i < results.size(); i++) {
        const Result &r = results[i];
        Out("    {\"id\": " + Json(r.id) + ", \"section\": " + Json(r.section) + ", \"title\": " + Json(r.title) +
            ", \"status\": " + Json(kStatusText[r.status]));
        if (r.status == kFailed || r.status == kWarning) Out(", \"expected\": " + Json(r.expected) + ", \"got\": " + Json(r.got));
        Out(", \"detail\": " + Json(r.detail) + "}" + (i + 1 < results.size() ? "," : "") + "\n");
    }
    Out(Format("  ],\n  \"summary\": {\"passed\": %d, \"failed\": %d, \"warnings\": %d, \"not_applicable\": %d, \"not_run\": %d}\n}\n",
               c.n[kPassed], c.n[kFailed], c.n[kWarning], c.n[kNotApplicable], c.n[kNotRun]));
}

void ReportJunit(const std::vector<Result> &results, const Counts &c) {
    Out("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    Out(Format("<testsuites name=\"opccomn-check\" tests=\"%d\" failures=\"%d\" skipped=\"%d\">\n", static_cast<int>(results.size()),
               c.n[kFailed], c.n[kNotApplicable] + c.n[kNotRun]));
    Out(Format("  <testsuite name=\"%s\" tests=\"%d\" failures=\"%d\" errors=\"0\" skipped=\"%d\">\n", Xml(g_server_text).c_str(),
               static_cast<int>(results.size()), c.n[kFailed], c.n[kNotApplicable] + c.n[kNotRun]));
    for (const Result &r : results) {
        std::string group = r.id.substr(0, r.id.find('.'));
        Out("    <testcase classname=\"opccomn-check." + Xml(group) + "\" name=\"" + Xml(r.id) + " (" + Xml(r.section) + ")\">");
        if (r.status == kFailed)
            Out("<failure message=\"" + Xml("expected " + r.expected + "; got " + r.got) + "\">" + Xml(r.title + ". " + r.detail) + "</failure>");
        else if (r.status == kNotApplicable || r.status == kNotRun)
            Out("<skipped message=\"" + Xml(kStatusText[r.status] + std::string(": ") + r.detail) + "\"/>");
        else if (r.status == kWarning)
            Out("<system-out>" + Xml("warning: expected " + r.expected + "; got " + r.got + ". " + r.detail) + "</system-out>");
        else
            Out("<system-out>" + Xml(r.detail) + "</system-out>");
        Out("</testcase>\n");
    }
    Out("  </testsuite>\n</testsuites>\n");
}

int Usage(const char *why) {
    if (why) fprintf(stderr, "opccomn-check: %s\n", why);
    fprintf(stderr,
            "usage: opccomn-check <ProgID | {CLSID}> [--host NAME] [--kind da|ae|hda] [--format text|json|junit]\n"
            "                     [--context all|inproc|local|remote] [--hostile] [--dcom] [--timeout MS]\n"
            "Checks the OPC Common interfaces of an OPC server (IOPCCommon, IOPCShutdown, registration, browsing);\n"
            "--dcom adds the AppID's and the machine's DCOM security (KB5004442).\n"
            "Exit code: 0 nothing failed, 1 a check failed, 2 usage error.\n");
    return 2;
}

bool ParseArgs(int argc, wchar_t **argv) {
    for (int i = 1; i < argc; i++) {
        std::wstring a = argv[i];
        auto value = [&](const char *name) -> std::wstring {
            if (i + 1 >= argc) {
                fprintf(stderr, "opccomn-check: %s needs a value\n", name);
                return L"";
            }
            return argv[++i];
        };
        if (a == L"--host") {
            g_opt.host = value("--host");
            if (g_opt.host.empty()) return false;
        } else if (a == L"--kind") {
            std::string k = Utf8(value("--kind").c_str());
            if (k != "da" && k != "ae" && k != "hda") return false;
            g_opt.kind = k;
        } else if (a == L"--format") {
            std::string f = Utf8(value("--format").c_str());
            if (f != "text" && f != "json" && f != "junit") return false;
            g_opt.format = f;
        } else if (a == L"--context") {
            std::string c = Utf8(value("--context").c_str());
            if (c == "all") g_opt.context = CLSCTX_ALL;
            else if (c == "inproc") g_opt.context = CLSCTX_INPROC_SERVER;
            else if (c == "local") g_opt.context = CLSCTX_LOCAL_SERVER;
            else if (c == "remote") g_opt.context = CLSCTX_REMOTE_SERVER;
            else return false;
        } else if (a == L"--hostile") {
            g_opt.hostile = true;
        } else if (a == L"--dcom") {
            g_opt.dcom = true;
        } else if (a == L"--timeout") {
            std::wstring v = value("--timeout");
            wchar_t *end = nullptr;
            unsigned long ms = wcstoul(v.c_str(), &end, 10);
            if (v.empty() || *end || ms == 0 || ms > 3600000) return false;
            g_opt.timeout_ms = ms;
        } else if (a == L"--help" || a == L"-h") {
            return false;
        } else if (!a.empty() && a[0] == L'-' && a.size() > 1 && a[1] == L'-') {
            fprintf(stderr, "opccomn-check: unknown option %s\n", Utf8(a.c_str()).c_str());
            return false;
        } else if (g_opt.server.empty()) {
            g_opt.server = a;
        } else {
            return false;
        }
    }
    return !g_opt.server.empty();
}

// The class to check: a {CLSID} as given, or the ProgID's class (locally from the registry, on
// another machine from its server list).
HRESULT Resolve() {
    if (g_opt.server[0] == L'{') return CLSIDFromString(g_opt.server.c_str(), &g_facts.clsid);
    if (Local()) return CLSIDFromProgID(g_opt.server.c_str(), &g_facts.clsid);
    COSERVERINFO info;
    MULTI_QI mqi = {&IID_IOPCServerList, nullptr, S_OK};
    HRESULT hr = CoCreateInstanceEx(CLSID_OPCServerList, nullptr, kHostContext, ServerInfo(&info), 1, &mqi);
    if (SUCCEEDED(hr)) hr = mqi.hr;
    if (FAILED(hr)) return hr;
    IOPCServerList *list = static_cast<IOPCServerList *>(mqi.pItf);
    hr = list->CLSIDFromProgID(g_opt.server.c_str(), &g_facts.clsid);
    list->Release();
    return hr;
}

// The kind from --kind, else from the claimed categories (Data Access when none says otherwise).
void DecideKind() {
    if (g_opt.kind == "ae") g_kind = OPC_SERVER_KIND_ALARMS_EVENTS;
    else if (g_opt.kind == "hda") g_kind = OPC_SERVER_KIND_HISTORICAL_DATA;
    else if (g_opt.kind == "da") g_kind = OPC_SERVER_KIND_DATA_ACCESS;
    else if (Local()) {
        ReadCategories();
        bool da = false, ae = false, hda = false;
        for (const CATID &c : g_facts.categories) {
            da = da || IsEqualGUID(c, CATID_OPCDAServer10) || IsEqualGUID(c, CATID_OPCDAServer20) || IsEqualGUID(c, CATID_OPCDAServer30);
            ae = ae || IsEqualGUID(c, CATID_OPCAEServer10);
            hda = hda || IsEqualGUID(c, CATID_OPCHDAServer10);
        }
        if (!da && ae) g_kind = OPC_SERVER_KIND_ALARMS_EVENTS;
        else if (!da && hda) g_kind = OPC_SERVER_KIND_HISTORICAL_DATA;
    }
}

}  // namespace

int wmain(int argc, wchar_t **argv) {
    if (!ParseArgs(argc, argv)) return Usage(nullptr);
    InitializeCriticalSection(&g_results_lock);
    SetUnhandledExceptionFilter(CrashFilter);
    SetErrorMode(SEM_FAILCRITICALERRORS | SEM_NOGPFAULTERRORBOX);
    // The main thread stays in the multithreaded apartment for the whole run, so objects a worker
    // created stay usable after that worker is gone.
    CoInitializeEx(nullptr, COINIT_MULTITHREADED);
    // Calls go out at PKT_INTEGRITY, the least a hardened Windows server accepts (KB5004442), and the
    // checker's own shutdown sink accepts no less from servers calling back.
    g_security_hr = CoInitializeSecurity(nullptr, -1, nullptr, nullptr, RPC_C_AUTHN_LEVEL_PKT_INTEGRITY, RPC_C_IMP_LEVEL_IMPERSONATE,
                                         nullptr, EOAC_NONE, nullptr);

    HRESULT hr = Resolve();
    if (FAILED(hr)) {
        bool other = Local() && g_opt.server[0] != L'{' && OtherViewHas(g_opt.server);
        fprintf(stderr, "opccomn-check: %s: no such server (%s)%s\n", Utf8(g_opt.server.c_str()).c_str(), Hr(hr).c_str(),
                other ? (sizeof(void *) == 8 ? "; it is registered in the 32-bit registry view: run the x86 opccomn-check"
                                             : "; it is registered in the 64-bit registry view: run the x64 opccomn-check")
                      : "");
        return 2;
    }
    g_facts.clsid_known = true;
    DecideKind();
    g_server_text = Utf8(g_opt.server.c_str()) + (g_opt.server[0] == L'{' ? "" : " " + GuidText(g_facts.clsid)) + (Local() ? "" : " on " + Utf8(g_opt.host.c_str())) +
                    ", kind " + KindName() + (g_opt.hostile ? ", hostile checks on" : "") + (g_opt.dcom ? ", DCOM checks on" : "");
    fprintf(stderr, "opccomn-check: checking %s (timeout %lu ms per call)\n", g_server_text.c_str(),
            static_cast<unsigned long>(g_opt.timeout_ms));

    g_results.resize(static_cast<size_t>(kCheckCount));
    bool clean = RunAll();

    std::vector<Result> results;
    Counts counts;
    EnterCriticalSection(&g_results_lock);
    for (int i = 0; i < kCheckCount; i++) {
        if (!Selected(i)) continue;
        Result r = g_results[static_cast<size_t>(i)];
        if (r.id.empty()) {
            r.id = kChecks[i].id, r.section = kChecks[i].section, r.title = kChecks[i].title;
            r.status = kNotRun, r.detail = "not reached";
        }
        counts.n[r.status]++;
        results.push_back(r);
    }
    LeaveCriticalSection(&g_results_lock);
    if (g_opt.format == "json") ReportJson(results, counts);
    else if (g_opt.format == "junit") ReportJunit(results, counts);
    else ReportText(results, counts);
    fflush(stdout);
    fflush(stderr);
    int code = counts.n[kFailed] ? 1 : 0;
    // A worker still stuck inside the server would keep the process from ending (or hang in the
    // server's DLL_PROCESS_DETACH): end it as it is.
    if (!clean) TerminateProcess(GetCurrentProcess(), static_cast<UINT>(code));
    if (g_list2) g_list2->Release();
    CoUninitialize();
    return code;
}
