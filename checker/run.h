// The state of one run of opccomn-check, made once by wmain and passed by reference to all that reads
// or changes it: the options, what is learnt about the server under test, the results, the watchdog.
// Each check gets a Ctx: the run, the worker's session with the server object, and its own result.
//
// The checks live in one file per area, as the OPC Common specification's chapters divide them, each
// with its list of checks in the order they run (RunAll runs the lists in the order of AllChecks):
//   server.cpp        the server object as a client creates it (server.*), the server's interfaces
//   common.cpp        IOPCCommon, chapter 5 (common.*)
//   shutdown.cpp      the IOPCShutdown connection point, chapter 4 (shutdown.*)
//   registration.cpp  the registry entries, chapter 6 (reg.*), and the registry reading others share
//   browse.cpp        the server browser, chapter 7 (browse.*)
//   dcom.cpp          the AppID's and the machine's DCOM security, --dcom (dcom.*)
//   hostile.cpp       NULL out-parameters and absurd counts, --hostile (hostile.*)
// The run itself: run.cpp (the worker thread and the watchdog's loop), watchdog.cpp, report.cpp (text,
// JSON and JUnit), main.cpp (the command line, the class and the kind to check).
#ifndef OPCCOMN_CHECK_RUN_H
#define OPCCOMN_CHECK_RUN_H

#include <windows.h>
#include <objbase.h>
#include <ocidl.h>

#include <opccomn/opccomn.h>

#include <string>
#include <vector>

#include "text.h"
#include "watchdog.h"

namespace checker {

struct Options {
    std::wstring server;  // ProgID or {CLSID} as given
    std::wstring host;
    std::string kind;     // "", "da", "ae", "hda"
    std::string format = "text";
    DWORD context = CLSCTX_ALL;
    bool hostile = false;
    bool dcom = false;
    DWORD timeout_ms = 10000;

    // The server is on this machine (no --host).
    bool Local() const { return host.empty(); }
};

enum Status { kPassed, kFailed, kWarning, kNotApplicable, kNotRun };

struct Result {
    std::string id, section, title;
    Status status = kNotRun;
    std::string expected, got, detail;
};

// The class's AppID and its EXE's, as registered (dcom.cpp); read once.
struct AppIdFacts {
    bool read = false;
    bool named = false;      // CLSID\{clsid} has an AppID value
    bool key = false;        // HKCR\AppID\{appid} exists
    bool local = false;      // the class has a LocalServer32
    std::wstring app_id;     // "{...}" as registered
    std::wstring exe;        // the LocalServer32 program's file name
    std::wstring exe_app_id; // HKCR\AppID\<exe> AppID, if any
};

// What the registration and browsing checks learn; filled once, read by later checks.
struct Facts {
    CLSID clsid = {};
    bool clsid_known = false;
    std::wstring prog_id, vi_prog_id, user_type, module, module_key;
    std::vector<CATID> categories;  // CLSID\{clsid}\Implemented Categories
    bool categories_read = false;
    bool clsid_key = false;         // HKCR\CLSID\{clsid} exists (reg.clsid)
    AppIdFacts app;
};

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

struct Ctx;
typedef void (*CheckFn)(Ctx &);

// Which checks run: the default set always, the others with --hostile or --dcom.
enum { kDefault = 0, kHostile = 1, kDcom = 2 };

struct CheckDef {
    const char *id;
    const char *section;
    const char *title;
    CheckFn fn;
    int set;
};

struct Run {
    Options opt;
    uint32_t kind = OPC_SERVER_KIND_DATA_ACCESS;  // as --kind says or as the server's categories tell
    // CoInitializeSecurity's result: the checker's calls go out at RPC_C_AUTHN_LEVEL_PKT_INTEGRITY.
    HRESULT security_hr = E_FAIL;
    Facts facts;
    std::string server_text;  // "OpcComn.ExampleServer.1 {...}", for the report
    IOPCServerList2 *server_list = nullptr;  // created by the first browsing check (any worker), kept
    std::string server_list_source;         // which server list it is, for the report
    std::vector<CheckDef> checks;           // AllChecks()
    CRITICAL_SECTION results_lock;
    std::vector<Result> results;            // one per check, by index in `checks`
    Watchdog watchdog;
    volatile LONG next_check = 0;           // where a (new) worker starts

    bool Local() const { return opt.Local(); }
    // Whether check `i` runs with these options.
    bool Selected(int i) const;
};

// What a check works with, and its result.
struct Ctx {
    Run &run;
    const Options &opt;
    Facts &facts;
    Watchdog &watchdog;
    Session &s;
    Result r;
    Ctx(Run &the_run, Session &session)
        : run(the_run), opt(the_run.opt), facts(the_run.facts), watchdog(the_run.watchdog), s(session) {}
    bool Local() const { return opt.Local(); }
    std::string Hr(HRESULT hr) const { return HrText(hr, run.kind); }
    void Pass(const std::string &detail) { r.status = kPassed, r.detail = detail; }
    void Fail(const std::string &expected, const std::string &got, const std::string &detail = "") {
        r.status = kFailed, r.expected = expected, r.got = got, r.detail = detail;
    }
    void Warn(const std::string &expected, const std::string &got, const std::string &detail = "") {
        r.status = kWarning, r.expected = expected, r.got = got, r.detail = detail;
    }
    void NotApplicable(const std::string &why) { r.status = kNotApplicable, r.detail = why; }
};

// The checks of each area, in the order they run.
std::vector<CheckDef> ServerChecks();
std::vector<CheckDef> CommonChecks();
std::vector<CheckDef> ShutdownChecks();
std::vector<CheckDef> RegistrationChecks();
std::vector<CheckDef> BrowseChecks();
std::vector<CheckDef> DcomChecks();
std::vector<CheckDef> HostileChecks();

// Every check, the areas in the order above.
std::vector<CheckDef> AllChecks();

// Runs the selected checks on worker threads, watching each call; returns false when a worker had to
// be abandoned (still stuck in a call).
bool RunAll(Run &run);

}  // namespace checker

#endif
