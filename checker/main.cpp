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
// The checks are split by area (run.h lists the files); this file reads the command line, finds the
// class and the kind of server to check, runs the checks (run.cpp) and writes the report (report.cpp).
//
// Built from the library's client pieces: the shutdown sink (OpcShutdownSinkCreate), the advise
// helpers (OpcShutdownAdvise / OpcShutdownUnadvise), the server browser (OpcServerListCreate, or
// CLSID_OPCServerList on another machine), the registry reader, the category descriptions and the
// error catalog (OpcErrorCodesOfKind, OpcErrorSymbol, OpcGetErrorStringEx) for the published codes
// and their standard texts, and the version convention (OpcVersionFromFileVersion).
#include <windows.h>
#include <objbase.h>

#include <opccomn/opccomn.h>

#include <cstdio>
#include <cwchar>
#include <string>
#include <vector>

#include "registration.h"
#include "report.h"
#include "run.h"
#include "server.h"

using namespace checker;

namespace {

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

bool ParseArgs(int argc, wchar_t **argv, Options &opt) {
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
            opt.host = value("--host");
            if (opt.host.empty()) return false;
        } else if (a == L"--kind") {
            std::string k = Utf8(value("--kind").c_str());
            if (k != "da" && k != "ae" && k != "hda") return false;
            opt.kind = k;
        } else if (a == L"--format") {
            std::string f = Utf8(value("--format").c_str());
            if (f != "text" && f != "json" && f != "junit") return false;
            opt.format = f;
        } else if (a == L"--context") {
            std::string c = Utf8(value("--context").c_str());
            if (c == "all") opt.context = CLSCTX_ALL;
            else if (c == "inproc") opt.context = CLSCTX_INPROC_SERVER;
            else if (c == "local") opt.context = CLSCTX_LOCAL_SERVER;
            else if (c == "remote") opt.context = CLSCTX_REMOTE_SERVER;
            else return false;
        } else if (a == L"--hostile") {
            opt.hostile = true;
        } else if (a == L"--dcom") {
            opt.dcom = true;
        } else if (a == L"--timeout") {
            std::wstring v = value("--timeout");
            wchar_t *end = nullptr;
            unsigned long ms = wcstoul(v.c_str(), &end, 10);
            if (v.empty() || *end || ms == 0 || ms > 3600000) return false;
            opt.timeout_ms = ms;
        } else if (a == L"--help" || a == L"-h") {
            return false;
        } else if (!a.empty() && a[0] == L'-' && a.size() > 1 && a[1] == L'-') {
            fprintf(stderr, "opccomn-check: unknown option %s\n", Utf8(a.c_str()).c_str());
            return false;
        } else if (opt.server.empty()) {
            opt.server = a;
        } else {
            return false;
        }
    }
    return !opt.server.empty();
}

// The class to check: a {CLSID} as given, or the ProgID's class (locally from the registry, on
// another machine from its server list).
HRESULT Resolve(Run &run) {
    if (run.opt.server[0] == L'{') return CLSIDFromString(run.opt.server.c_str(), &run.facts.clsid);
    if (run.Local()) return CLSIDFromProgID(run.opt.server.c_str(), &run.facts.clsid);
    COSERVERINFO info;
    MULTI_QI mqi = {&IID_IOPCServerList, nullptr, S_OK};
    HRESULT hr = CoCreateInstanceEx(CLSID_OPCServerList, nullptr, kHostContext, ServerInfo(run.opt, &info), 1, &mqi);
    if (SUCCEEDED(hr)) hr = mqi.hr;
    if (FAILED(hr)) return hr;
    IOPCServerList *list = static_cast<IOPCServerList *>(mqi.pItf);
    hr = list->CLSIDFromProgID(run.opt.server.c_str(), &run.facts.clsid);
    list->Release();
    return hr;
}

// The kind from --kind, else from the claimed categories (Data Access when none says otherwise).
void DecideKind(Run &run) {
    if (run.opt.kind == "ae") run.kind = OPC_SERVER_KIND_ALARMS_EVENTS;
    else if (run.opt.kind == "hda") run.kind = OPC_SERVER_KIND_HISTORICAL_DATA;
    else if (run.opt.kind == "da") run.kind = OPC_SERVER_KIND_DATA_ACCESS;
    else if (run.Local()) {
        ReadCategories(run.facts);
        bool da = false, ae = false, hda = false;
        for (const CATID &c : run.facts.categories) {
            da = da || IsEqualGUID(c, CATID_OPCDAServer10) || IsEqualGUID(c, CATID_OPCDAServer20) || IsEqualGUID(c, CATID_OPCDAServer30);
            ae = ae || IsEqualGUID(c, CATID_OPCAEServer10);
            hda = hda || IsEqualGUID(c, CATID_OPCHDAServer10);
        }
        if (!da && ae) run.kind = OPC_SERVER_KIND_ALARMS_EVENTS;
        else if (!da && hda) run.kind = OPC_SERVER_KIND_HISTORICAL_DATA;
    }
}

}  // namespace

int wmain(int argc, wchar_t **argv) {
    Run run;
    if (!ParseArgs(argc, argv, run.opt)) return Usage(nullptr);
    InitializeCriticalSection(&run.results_lock);
    SetUnhandledExceptionFilter(CrashFilter);
    SetErrorMode(SEM_FAILCRITICALERRORS | SEM_NOGPFAULTERRORBOX);
    // The main thread stays in the multithreaded apartment for the whole run, so objects a worker
    // created stay usable after that worker is gone.
    CoInitializeEx(nullptr, COINIT_MULTITHREADED);
    // Calls go out at PKT_INTEGRITY, the least a hardened Windows server accepts (KB5004442), and the
    // checker's own shutdown sink accepts no less from servers calling back.
    run.security_hr = CoInitializeSecurity(nullptr, -1, nullptr, nullptr, RPC_C_AUTHN_LEVEL_PKT_INTEGRITY, RPC_C_IMP_LEVEL_IMPERSONATE,
                                           nullptr, EOAC_NONE, nullptr);

    HRESULT hr = Resolve(run);
    if (FAILED(hr)) {
        bool other = run.Local() && run.opt.server[0] != L'{' && OtherViewHas(run.opt.server);
        fprintf(stderr, "opccomn-check: %s: no such server (%s)%s\n", Utf8(run.opt.server.c_str()).c_str(), HrText(hr, run.kind).c_str(),
                other ? (sizeof(void *) == 8 ? "; it is registered in the 32-bit registry view: run the x86 opccomn-check"
                                             : "; it is registered in the 64-bit registry view: run the x64 opccomn-check")
                      : "");
        return 2;
    }
    run.facts.clsid_known = true;
    DecideKind(run);
    run.server_text = Utf8(run.opt.server.c_str()) + (run.opt.server[0] == L'{' ? "" : " " + GuidText(run.facts.clsid)) + (run.Local() ? "" : " on " + Utf8(run.opt.host.c_str())) +
                    ", kind " + KindName(run.kind) + (run.opt.hostile ? ", hostile checks on" : "") + (run.opt.dcom ? ", DCOM checks on" : "");
    fprintf(stderr, "opccomn-check: checking %s (timeout %lu ms per call)\n", run.server_text.c_str(),
            static_cast<unsigned long>(run.opt.timeout_ms));

    run.checks = AllChecks();
    run.results.resize(run.checks.size());
    bool clean = RunAll(run);

    std::vector<Result> results;
    Counts counts;
    EnterCriticalSection(&run.results_lock);
    for (int i = 0; i < static_cast<int>(run.checks.size()); i++) {
        if (!run.Selected(i)) continue;
        const CheckDef &check = run.checks[static_cast<size_t>(i)];
        Result r = run.results[static_cast<size_t>(i)];
        if (r.id.empty()) {
            r.id = check.id, r.section = check.section, r.title = check.title;
            r.status = kNotRun, r.detail = "not reached";
        }
        counts.n[r.status]++;
        results.push_back(r);
    }
    LeaveCriticalSection(&run.results_lock);
    Report(run, results, counts);
    fflush(stdout);
    fflush(stderr);
    int code = counts.n[kFailed] ? 1 : 0;
    // A worker still stuck inside the server would keep the process from ending (or hang in the
    // server's DLL_PROCESS_DETACH): end it as it is.
    if (!clean) TerminateProcess(GetCurrentProcess(), static_cast<UINT>(code));
    if (run.server_list) run.server_list->Release();
    CoUninitialize();
    return code;
}

