// The watchdog (watchdog.h).
#include "watchdog.h"

#include <cstdio>

namespace checker {

namespace {

// The worker the calling thread is, for the exception filter, which is given nothing else: its
// watchdog and the generation it started in (none and -1 on other threads).
thread_local Watchdog *t_watchdog = nullptr;
thread_local LONG t_generation = -1;

}  // namespace

void BeginWorker(Watchdog &watchdog) {
    t_watchdog = &watchdog;
    t_generation = watchdog.generation;
}

void EndIfStale(Watchdog &watchdog) {
    if (t_generation != watchdog.generation) ExitThread(0);
}

Call::Call(Watchdog &watchdog, const char *name) : watchdog_(watchdog) {
    EndIfStale(watchdog_);
    snprintf(watchdog_.call_name, sizeof watchdog_.call_name, "%s", name);
    watchdog_.call_started = GetTickCount64();
    InterlockedExchange(&watchdog_.call_active, 1);
}

Call::~Call() {
    EndIfStale(watchdog_);
    InterlockedExchange(&watchdog_.call_active, 0);
}

LONG WINAPI CrashFilter(EXCEPTION_POINTERS *info) {
    Watchdog *watchdog = t_watchdog;
    if (watchdog && t_generation != watchdog->generation) ExitThread(0);  // a stale worker: already reported
    if (watchdog) {
        watchdog->crash_code = info && info->ExceptionRecord ? info->ExceptionRecord->ExceptionCode : 0;
        InterlockedExchange(&watchdog->worker_crashed, 1);
        ExitThread(3);
    }
    return EXCEPTION_CONTINUE_SEARCH;
}

}  // namespace checker
