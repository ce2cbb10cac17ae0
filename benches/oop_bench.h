/* What the cross-process benchmarks (benches/cross_process_bench.c, benches/da_bench.c) share: the
 * watchdog that bounds a run in time, the interleaved rounds, the registration of their test servers'
 * classes and the paired-ratio statistics.
 *
 * A benchmark defines before including this header:
 *   OOP_BENCH_PROGRAM    its name, the prefix of its messages ("da_bench")
 *   OOP_BENCH_USER_TYPE  the user type of the classes it registers (a wide string)
 * and defines the functions declared under "The benchmark's part" below.
 *
 * The watchdog: every step of the run is named and timed (step()); a step that does not end within its
 * limit is a stall. The watchdog thread then prints what stalled and the figures of the rounds complete
 * so far (print_figures, marked partial; none when no round was), removes the benchmark's classes
 * (unregister_all), ends its servers and ends the process with exit code 3. The stalled thread is never
 * waited for. */
#ifndef OPCCOMN_OOP_BENCH_H
#define OPCCOMN_OOP_BENCH_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <windows.h>

#include <opccomn/opccomn.h>

#define MAX_ROUNDS 101
#define CONTENDERS 3 /* opccomn.dll's proxy/stub, the stand-in's, and the stand-in again as the control */

/* ---- The benchmark's part ---- */

/* Prints the figures of the first n rounds (n >= 1) and a GOAL line per goal; returns 1 when a goal is
 * missed. */
static int print_table(int n);
/* Removes the classes of the benchmark's servers. */
static void unregister_all(void);
/* The process of contender i's server, 0 when none was started. */
static DWORD server_pid(int i);
/* The set of contender i's test server classes (--sets F gives contender i the set F + i). */
static unsigned *contender_set(int i);
/* One round's batch of operation op by contender i (round -1: a warm-up, not recorded); 1 when a call
 * failed (said on stderr). */
static int contender_batch(int i, int op, int round);

/* ---- The run's settings (command line) ---- */

static WCHAR server_path[MAX_PATH]; /* the test server, beside this program */
static int rounds = 51;
static double stall_s = 60;

/* One of the options every benchmark takes (--sets F, --unregister, --rounds R, --budget-s S, --stall-s S)
 * at argv[*a], its value consumed; 0 when argv[*a] is none of them. --unregister removes the classes a
 * run killed from outside left and ends the process (exit code 0). */
static int common_option(int argc, char **argv, int *a, double *budget_s) {
    const char *value = *a + 1 < argc ? argv[*a + 1] : NULL;
    int i;
    if (!strcmp(argv[*a], "--sets") && value && atoi(value) >= 1 && atoi(value) + CONTENDERS - 1 <= 9) {
        for (i = 0; i < CONTENDERS; i++) *contender_set(i) = (unsigned)(atoi(value) + i);
    } else if (!strcmp(argv[*a], "--unregister")) {
        unregister_all();
        printf(OOP_BENCH_PROGRAM ": the benchmark's classes removed\n");
        exit(0);
    } else if (!strcmp(argv[*a], "--rounds") && value) {
        rounds = atoi(value);
    } else if (!strcmp(argv[*a], "--budget-s") && value) {
        *budget_s = atof(value);
    } else if (!strcmp(argv[*a], "--stall-s") && value) {
        stall_s = atof(value);
    } else {
        return 0;
    }
    ++*a;
    return 1;
}

/* ---- The watchdog ---- */

static CRITICAL_SECTION step_lock;   /* the step's name, start and limit */
static char step_name[160];
static ULONGLONG step_started;       /* GetTickCount64 */
static ULONGLONG step_limit_ms;
static volatile LONG rounds_done;    /* complete rounds: each contender's batch of every operation */
static CRITICAL_SECTION output_lock; /* the figures, printed once, by the run or by the watchdog */
static int figures_printed;
static HANDLE run_finished;

/* A new step (what it is, for the report) with its time limit. */
static void step(double limit_s, const char *format, ...) {
    va_list ap;
    EnterCriticalSection(&step_lock);
    va_start(ap, format);
    vsnprintf(step_name, sizeof step_name, format, ap);
    va_end(ap);
    step_started = GetTickCount64();
    step_limit_ms = (ULONGLONG)(limit_s * 1000);
    LeaveCriticalSection(&step_lock);
}
/* A server's start or end: under Wine on a loaded machine it takes seconds, at times tens of them. */
static double setup_limit_s(void) { return stall_s * 2 > 120 ? stall_s * 2 : 120; }

static double now(void) {
    LARGE_INTEGER f, c;
    QueryPerformanceFrequency(&f);
    QueryPerformanceCounter(&c);
    return (double)c.QuadPart / (double)f.QuadPart;
}

/* A failed call of the contender named, on stderr; returns 1 (a failure). */
static int failed(const char *contender, const char *what, HRESULT hr) {
    fprintf(stderr, OOP_BENCH_PROGRAM ": %s (%s): 0x%08lX\n", what, contender, (unsigned long)hr);
    return 1;
}

/* The figures of the first n rounds, printed once (by the run, or by the watchdog after a stall); returns
 * 1 when a goal is missed or there are none. `why`, when given, says why there are fewer rounds than
 * asked for. */
static int print_figures(int n, const char *why) {
    int missed;
    EnterCriticalSection(&output_lock);
    figures_printed = 1;
    if (n == 0) {
        printf("no round was complete: no figures (%s)\n", why ? why : "");
        LeaveCriticalSection(&output_lock);
        return 1;
    }
    if (why) printf("PARTIAL: the figures of %d of the %d rounds (%s)\n", n, rounds, why);
    missed = print_table(n);
    fflush(stdout);
    LeaveCriticalSection(&output_lock);
    return missed;
}

/* After a stall: what stalled, the figures so far, then the benchmark's classes and servers go. */
static void end_stalled(const char *what, ULONGLONG waited_ms) {
    char why[300];
    int i;
    EnterCriticalSection(&output_lock);
    printf("STALLED: %s did not end within %.0f s (waited %.1f s)\n", what, (double)step_limit_ms / 1000,
           (double)waited_ms / 1000);
    snprintf(why, sizeof why, "stalled in %s", what);
    if (!figures_printed) print_figures((int)rounds_done, why);
    else printf("(the figures above are complete: the stall came after the last round)\n");
    LeaveCriticalSection(&output_lock);
    unregister_all();
    for (i = 0; i < CONTENDERS; i++) {
        HANDLE process = server_pid(i) ? OpenProcess(PROCESS_TERMINATE, FALSE, server_pid(i)) : NULL;
        if (process) {
            TerminateProcess(process, 3);
            CloseHandle(process);
        }
    }
    printf(OOP_BENCH_PROGRAM ": stopped after a stall; its classes removed, its servers ended\n");
    fflush(stdout);
    fflush(stderr);
    TerminateProcess(GetCurrentProcess(), 3);
}

static DWORD WINAPI watchdog(void *unused) {
    (void)unused;
    while (WaitForSingleObject(run_finished, 250) == WAIT_TIMEOUT) {
        char what[sizeof step_name];
        ULONGLONG waited;
        int late;
        EnterCriticalSection(&step_lock);
        waited = GetTickCount64() - step_started;
        late = waited > step_limit_ms;
        memcpy(what, step_name, sizeof what);
        LeaveCriticalSection(&step_lock);
        if (late) end_stalled(what, waited);
    }
    return 0;
}

/* Output unbuffered (what was printed survives a kill from outside); the test server `exe` is the one
 * beside this program. */
static void begin(const WCHAR *exe) {
    WCHAR *slash;
    setvbuf(stdout, NULL, _IONBF, 0);
    GetModuleFileNameW(NULL, server_path, MAX_PATH);
    slash = wcsrchr(server_path, L'\\');
    wcscpy(slash ? slash + 1 : server_path, exe);
}

/* The watchdog's thread, watching the first step (the start); NULL when it could not start. */
static HANDLE start_watchdog(void) {
    InitializeCriticalSection(&step_lock);
    InitializeCriticalSection(&output_lock);
    run_finished = CreateEventW(NULL, TRUE, FALSE, NULL);
    step(setup_limit_s(), "the start (COM, the proxy/stubs' class objects)");
    return run_finished ? CreateThread(NULL, 0, watchdog, NULL, 0, NULL) : NULL;
}

/* The last step, CoUninitialize, then the watchdog ends. */
static void end_run(HANDLE watchdog_thread) {
    step(setup_limit_s(), "CoUninitialize");
    CoUninitialize();
    SetEvent(run_finished);
    WaitForSingleObject(watchdog_thread, INFINITE);
}

/* ---- The rounds ---- */

/* A warm-up batch of each of the `ops` operations by each contender, then the interleaved rounds (the
 * contenders' order rotating), stopped once budget_s seconds have passed since the first; then the
 * figures. Returns 1 when a batch failed (no figures then); *missed: whether a goal was missed. */
static int run_rounds(int ops, double budget_s, int *missed) {
    int round, op, i, failure = 0, cut = 0;
    char why[120] = "";
    double started;
    for (op = 0; op < ops && !failure; op++)
        for (i = 0; i < CONTENDERS && !failure; i++) failure = contender_batch(i, op, -1);
    started = now();
    for (round = 0; round < rounds && !failure; round++) {
        if (round > 0 && now() - started > budget_s) {
            cut = 1;
            snprintf(why, sizeof why, "the rounds' time limit of %.0f s (--budget-s) was reached", budget_s);
            break;
        }
        for (op = 0; op < ops && !failure; op++)
            for (i = 0; i < CONTENDERS && !failure; i++) failure = contender_batch((round + i) % CONTENDERS, op, round);
        if (!failure) InterlockedIncrement(&rounds_done);
    }
    if (!failure) *missed = print_figures((int)rounds_done, cut ? why : NULL);
    return failure;
}

/* ---- The test servers ---- */

/* A server's answer to GetErrorString of one of its vendor codes, as text into `out`, `text` freed; 0
 * when it gave none (said on stderr). */
static int server_answer(const char *contender, HRESULT hr, LPWSTR text, char *out, size_t size) {
    if (FAILED(hr) || !text) return failed(contender, "asking the server", hr), 0;
    snprintf(out, size, "%ls", text);
    CoTaskMemFree(text);
    return 1;
}

static OpcServerRegistration registration(const CLSID *clsid, const WCHAR *prog_id) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = *clsid;
    r.prog_id = prog_id;
    r.user_type = OOP_BENCH_USER_TYPE;
    r.module_path = server_path;
    return r;
}

/* A class of the test server, started with `arguments` after its path (they name its proxy/stub and its
 * CLSIDs). */
static HRESULT register_class(const CLSID *clsid, const WCHAR *prog_id, const WCHAR *arguments) {
    WCHAR command[MAX_PATH + 40], key[80], guid[40];
    OpcServerRegistration r = registration(clsid, prog_id);
    HRESULT hr;
    HKEY h;
    if (FAILED(hr = OpcRegisterServer(&r, NULL))) return hr;
    StringFromGUID2(clsid, guid, 40);
    swprintf(key, 80, L"CLSID\\%ls\\LocalServer32", guid);
    swprintf(command, MAX_PATH + 40, L"\"%ls\"%ls", server_path, arguments);
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_WRITE, &h) != ERROR_SUCCESS) return E_FAIL;
    if (RegSetValueExW(h, NULL, 0, REG_SZ, (const BYTE *)command, (DWORD)((wcslen(command) + 1) * sizeof(WCHAR))))
        hr = E_FAIL;
    RegCloseKey(h);
    return hr;
}

static void unregister_class(const CLSID *clsid, const WCHAR *prog_id) {
    OpcServerRegistration r = registration(clsid, prog_id);
    OpcUnregisterServer(&r, NULL);
}

/* ---- The statistics ---- */

static int compare(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}
static double median(const double *v, int n) {
    double s[MAX_ROUNDS];
    memcpy(s, v, (size_t)n * sizeof s[0]);
    qsort(s, (size_t)n, sizeof s[0], compare);
    return n % 2 ? s[n / 2] : (s[n / 2 - 1] + s[n / 2]) / 2;
}

/* The GOAL line of `label` (the goal: a median ratio of at most 1.1x) over the first n rounds; 1 when met. */
static int goal_met(const char *label, double ratio, int n) {
    int met = ratio <= 1.1;
    printf("GOAL %-40s %7.2fx  goal <= 1.10x  %s%s\n", label, ratio, met ? "met" : "NOT MET",
           n < rounds ? " (partial)" : "");
    return met;
}

/* The median of the first n rounds' ratios a/b, and their lowest and highest. */
static double paired_ratio(const double *a, const double *b, int n, double *lo, double *hi) {
    double r[MAX_ROUNDS];
    int i;
    *lo = 1e9;
    *hi = 0;
    for (i = 0; i < n; i++) {
        r[i] = a[i] / b[i];
        if (r[i] < *lo) *lo = r[i];
        if (r[i] > *hi) *hi = r[i];
    }
    return median(r, n);
}

#endif
