// The run (run.h): the checks in order, each on a worker thread while the main thread watches the
// clock; a hang or a crash fails the check it happened in, and a new worker with a new server object
// goes on with the next.
#include "run.h"

#include <cstdio>

namespace checker {

std::vector<CheckDef> AllChecks() {
    std::vector<CheckDef> all;
    for (const std::vector<CheckDef> &area : {ServerChecks(), CommonChecks(), ShutdownChecks(), RegistrationChecks(),
                                              BrowseChecks(), DcomChecks(), HostileChecks()})
        all.insert(all.end(), area.begin(), area.end());
    return all;
}

bool Run::Selected(int i) const {
    const CheckDef &check = checks[static_cast<size_t>(i)];
    return check.set == kDefault || (check.set == kHostile && opt.hostile) || (check.set == kDcom && opt.dcom);
}

namespace {

void Record(Run &run, int index, const Result &r) {
    EnterCriticalSection(&run.results_lock);
    run.results[static_cast<size_t>(index)] = r;
    LeaveCriticalSection(&run.results_lock);
}

// Whether the server behind the session's proxy is gone (its process ended): a call the proxy
// cannot answer by itself (QueryInterface for an interface OPC servers do not have goes to the
// server) fails with one of the codes COM gives for a vanished server.
bool ServerGone(Run &run, Session &s, HRESULT *why) {
    if (!s.server) return false;
    void *p = nullptr;
    HRESULT hr;
    {
        Call c(run.watchdog, "IUnknown::QueryInterface (is the server process still there?)");
        hr = s.server->QueryInterface(IID_IOPCEnumGUID, &p);
    }
    if (SUCCEEDED(hr) && p) static_cast<IUnknown *>(p)->Release();
    *why = hr;
    return hr == RPC_E_DISCONNECTED || hr == HRESULT_FROM_WIN32(RPC_S_SERVER_UNAVAILABLE) ||
           hr == HRESULT_FROM_WIN32(RPC_S_CALL_FAILED) || hr == HRESULT_FROM_WIN32(RPC_S_CALL_FAILED_DNE) ||
           hr == CO_E_OBJNOTCONNECTED || hr == RPC_E_SERVERFAULT;
}

DWORD WINAPI Worker(void *param) {
    Run &run = *static_cast<Run *>(param);
    BeginWorker(run.watchdog);
    CoInitializeEx(nullptr, COINIT_MULTITHREADED);
    Session *session = new Session();  // leaked with the thread if the server crashes or hangs
    const int count = static_cast<int>(run.checks.size());
    int selected_total = 0, position = 0;
    for (int i = 0; i < count; i++) selected_total += run.Selected(i);
    for (int i = 0; i < static_cast<int>(run.next_check); i++) position += run.Selected(i);
    for (int i = run.next_check; i < count; i++) {
        if (!run.Selected(i)) continue;
        const CheckDef &check = run.checks[static_cast<size_t>(i)];
        InterlockedExchange(&run.watchdog.current_check, i);
        fprintf(stderr, "opccomn-check: [%2d/%d] %s\n", ++position, selected_total, check.id);
        Ctx x(run, *session);
        x.r.id = check.id, x.r.section = check.section, x.r.title = check.title;
        check.fn(x);
        EndIfStale(run.watchdog);
        if (x.r.status == kNotRun) x.Fail("a result", "the check returned none (a bug of opccomn-check)");
        HRESULT gone = S_OK;
        if (x.r.status == kFailed && ServerGone(run, *session, &gone)) {
            // An out-of-process server that crashed: the check that made it crash fails, and the
            // rest runs against a new server process.
            x.r.got = "the server process ended during the check (" + x.Hr(gone) + "); the call had returned: " + x.r.got;
            x.r.detail = "the server crashed; the checker goes on with a new server object";
            fprintf(stderr, "opccomn-check: %s: %s\n", x.r.id.c_str(), x.r.got.c_str());
            session = new Session();  // the old one's proxies are dead: leaked, not released
        }
        Record(run, i, x.r);
    }
    InterlockedExchange(&run.watchdog.current_check, -1);
    // The session's objects: released in reverse order, each call still watched.
    {
        Call c(run.watchdog, "releasing the server's interfaces");
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

}  // namespace

bool RunAll(Run &run) {
    Watchdog &w = run.watchdog;
    bool abandoned = false;
    run.next_check = 0;
    for (;;) {
        InterlockedExchange(&w.worker_crashed, 0);
        InterlockedExchange(&w.call_active, 0);
        HANDLE worker = CreateThread(nullptr, 0, Worker, &run, 0, nullptr);
        if (!worker) {
            fprintf(stderr, "opccomn-check: cannot create a thread\n");
            ExitProcess(2);
        }
        bool hung = false;
        for (;;) {
            if (WaitForSingleObject(worker, 50) == WAIT_OBJECT_0) break;
            if (w.call_active && GetTickCount64() - w.call_started > run.opt.timeout_ms) {
                hung = true;
                break;
            }
        }
        int at = w.current_check;
        if (!hung && !w.worker_crashed) {
            if (at >= 0) {  // the thread ended inside the server without a crash report
                w.crash_code = 0xFFFFFFFF;
            } else {
                CloseHandle(worker);
                return !abandoned;
            }
        }
        if (hung && at < 0) {  // stuck releasing the objects after the last check
            fprintf(stderr, "opccomn-check: %s did not return within %lu ms after the last check\n", w.call_name,
                    static_cast<unsigned long>(run.opt.timeout_ms));
            CloseHandle(worker);
            return false;
        }
        const CheckDef &check = run.checks[static_cast<size_t>(at)];
        Result r;
        r.id = check.id, r.section = check.section, r.title = check.title;
        r.status = kFailed;
        r.expected = std::string("the call returns");
        if (hung) {
            r.got = Format("%s did not return within %lu ms", w.call_name, static_cast<unsigned long>(run.opt.timeout_ms));
            r.detail = "the server hangs; the checker goes on with a new server object";
            abandoned = true;
        } else {
            r.got = w.crash_code == 0xFFFFFFFF
                        ? Format("the checker's thread ended inside %s (no exception was reported)", w.call_name)
                        : Format("the server crashed in %s (exception 0x%08lX)", w.call_name, static_cast<unsigned long>(w.crash_code));
            r.detail = "an unhandled exception inside the server; the checker goes on with a new server object";
        }
        fprintf(stderr, "opccomn-check: %s: %s\n", r.id.c_str(), r.got.c_str());
        InterlockedIncrement(&w.generation);  // the old worker, if it ever returns, ends there
        Record(run, at, r);
        CloseHandle(worker);
        run.next_check = at + 1;
    }
}

}  // namespace checker
