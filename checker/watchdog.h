// The watchdog: every call into the server is made on a worker thread and bracketed (Call), while the
// main thread watches the clock (RunAll, run.cpp). A call that does not return within the timeout, or
// a crash on the worker thread (CrashFilter), ends that worker; the main thread reports it and goes
// on with a new worker.
#ifndef OPCCOMN_CHECK_WATCHDOG_H
#define OPCCOMN_CHECK_WATCHDOG_H

#include <windows.h>

namespace checker {

// What the main thread watches, written by the running worker.
struct Watchdog {
    volatile LONG call_active = 0;        // 1 while a call into the server runs
    volatile ULONGLONG call_started = 0;  // GetTickCount64 at its start
    char call_name[160] = {};             // what it is, for the report
    volatile LONG current_check = -1;     // index of the running check
    volatile LONG worker_crashed = 0;
    volatile DWORD crash_code = 0;
    // Each worker's generation; a worker the watchdog gave up on (its call hung) is stale, and ends as
    // soon as that call returns, before it touches the shared state of the worker that replaced it.
    volatile LONG generation = 0;
};

// Makes the calling thread a worker of `watchdog`, of its current generation.
void BeginWorker(Watchdog &watchdog);

// Ends the calling worker when the watchdog has given up on it.
void EndIfStale(Watchdog &watchdog);

// Brackets one call into the server: `Call c(x.watchdog, "IOPCCommon::SetLocaleID"); hr = ...;`.
class Call {
public:
    Call(Watchdog &watchdog, const char *name);
    ~Call();
    Call(const Call &) = delete;
    Call &operator=(const Call &) = delete;

private:
    Watchdog &watchdog_;
};

// The process's unhandled exception filter. A crash on a worker thread (an exception nothing in the
// server handled) is recorded in that worker's watchdog and the thread ends; the main thread reports
// it and goes on with a new worker.
LONG WINAPI CrashFilter(EXCEPTION_POINTERS *info);

}  // namespace checker

#endif
