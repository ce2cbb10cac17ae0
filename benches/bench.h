/* The benchmark harness shared by benches/bench_*.c (benchmarks, not tests: scripts/bench.sh runs them).

   Rules that make a figure trustworthy on a shared machine:
   - every contender of a case runs in the same process, in interleaved rounds (round r runs the
     contenders in an order rotated by r), each round long enough to dwarf the clock's resolution and
     short enough to fit in a scheduler time slice;
   - a contender's figure is the median of its rounds, with the spread (lowest and highest round) beside
     it; a ratio is the median over rounds of the ratio measured within the round (neighbours in time
     see the same machine), with its spread too;
   - every goal is printed with its threshold and "met" or "NOT MET", and the program exits with 1 when
     any goal is not met, so nobody has to compute anything from the table.

   Only the public header is used, as a server would. */
#ifndef OPCCOMN_BENCH_H
#define OPCCOMN_BENCH_H

#if !defined(_WIN32) && !defined(_POSIX_C_SOURCE)
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <windows.h>
/* On Windows the wall clock (QueryPerformanceCounter). Under Wine a Windows thread is a Linux thread,
   and Linux keeps its CPU time to the nanosecond (Wine's GetThreadTimes has the scheduler tick's 10 ms
   resolution and QueryThreadCycleTime is missing), so there the benchmark asks the Linux kernel
   directly, as the Linux build does: other processes on a shared machine then do not count against
   either side. A benchmark whose work happens partly in another process (under Wine the registry lives
   in wineserver) defines BENCH_WALL_CLOCK before including this header and keeps the wall clock. */
static int bench_linux_thread_cpu_ns(double *ns)
{
    long ret;
#if defined(__x86_64__)
    struct {
        long long sec, nsec;
    } t;
    /* clock_gettime(CLOCK_THREAD_CPUTIME_ID = 3, &t): x86_64 system call 228 */
    __asm__ volatile("syscall" : "=a"(ret) : "a"(228L), "D"(3L), "S"(&t) : "rcx", "r11", "memory");
#elif defined(__i386__)
    struct {
        long sec, nsec;
    } t;
    /* clock_gettime(CLOCK_THREAD_CPUTIME_ID = 3, &t): i386 system call 265 */
    __asm__ volatile("int $0x80" : "=a"(ret) : "a"(265L), "b"(3L), "c"(&t) : "memory");
#else
    struct {
        long sec, nsec;
    } t = {0, 0};
    ret = -1;
#endif
    if (ret != 0)
        return 0;
    *ns = (double)t.sec * 1e9 + (double)t.nsec;
    return 1;
}

static int bench_thread_cpu; /* set by bench_init: the Linux thread CPU clock under Wine */
static const char *bench_clock = "wall clock (QueryPerformanceCounter)";

static void bench_choose_clock(void)
{
#if !defined(BENCH_WALL_CLOCK)
    double ns;
    /* Only Wine's ntdll exports wine_get_version; on Windows the system call would be meaningless. */
    HMODULE ntdll = GetModuleHandleA("ntdll.dll");
    if (ntdll && GetProcAddress(ntdll, "wine_get_version") && bench_linux_thread_cpu_ns(&ns)) {
        bench_thread_cpu = 1;
        bench_clock = "thread CPU time (Wine: the Linux thread's CLOCK_THREAD_CPUTIME_ID)";
    }
#endif
}

static double bench_now_ns(void)
{
    static LARGE_INTEGER frequency;
    LARGE_INTEGER t;
    double ns;
    if (bench_thread_cpu && bench_linux_thread_cpu_ns(&ns))
        return ns;
    if (!frequency.QuadPart)
        QueryPerformanceFrequency(&frequency);
    QueryPerformanceCounter(&t);
    return (double)t.QuadPart * 1e9 / (double)frequency.QuadPart;
}
#else
#include <time.h>
/* The thread's CPU time: the time it ran, not the time other processes ran on its core. */
static double bench_now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}
static const char *bench_clock = "thread CPU time (CLOCK_THREAD_CPUTIME_ID)";
static void bench_choose_clock(void) {}
#endif

#define BENCH_MAX_CONTENDERS 8
#define BENCH_MAX_ROUNDS 101

/* One contender: `run(context, reps)` does `reps` repetitions of the measured work; `per_rep` is how many
   calls (or items) one repetition is, so figures are per call. */
typedef struct {
    const char *name;
    void (*run)(void *context, long reps);
    void *context;
    double per_rep;
} BenchContender;

/* The result of one case: per contender, its time per call in every round (ns). */
typedef struct {
    int contenders;
    int rounds;
    double ns[BENCH_MAX_CONTENDERS][BENCH_MAX_ROUNDS];
} BenchResult;

/* Many short rounds: a round well under a scheduler time slice is rarely interrupted, so on a busy
   machine most rounds are clean and the median is theirs. */
static int bench_rounds = 31;        /* BENCH_ROUNDS overrides (3-101) */
static double bench_round_ms = 2.0;  /* one contender's round; BENCH_ROUND_MS overrides */
/* A case stops adding rounds once it has run this long (seconds on the benchmark's clock; 0: never)
   and has BENCH_MIN_ROUNDS; BENCH_BUDGET_S overrides. For benchmarks whose round is one slow operation
   (a registry scan): on a loaded machine each of its calls into another process waits for the scheduler,
   a round then takes minutes instead of seconds, and a fixed count of rounds would not finish. */
static double bench_budget_s;
#define BENCH_MIN_ROUNDS 5
static int bench_fewest_rounds;       /* the fewest rounds a case ran, when the budget cut one short */
static int bench_failures;            /* goals not met */
static int bench_goals;

/* Reads BENCH_ROUNDS and BENCH_ROUND_MS (a benchmark may set other defaults before), picks the clock and
   makes the output unbuffered. */
static void bench_init(void)
{
    /* Each line as it is printed (Windows' C runtime has no line buffering): what a run stopped by
       scripts/bench.sh's time limit printed is not lost with its buffer. */
#if defined(_WIN32)
    setvbuf(stdout, NULL, _IONBF, 0);
#else
    setvbuf(stdout, NULL, _IOLBF, BUFSIZ);
#endif
    bench_choose_clock();
    const char *r = getenv("BENCH_ROUNDS"), *ms = getenv("BENCH_ROUND_MS"), *budget = getenv("BENCH_BUDGET_S");
    if (r && atoi(r) >= 3)
        bench_rounds = atoi(r) > BENCH_MAX_ROUNDS ? BENCH_MAX_ROUNDS : atoi(r);
    if (ms && atof(ms) > 0)
        bench_round_ms = atof(ms);
    if (budget && atof(budget) >= 0)
        bench_budget_s = atof(budget);
}

static int bench_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median, lowest and highest of `n` values. */
static void bench_stats(const double *values, int n, double *median, double *lo, double *hi)
{
    double sorted[BENCH_MAX_ROUNDS];
    memcpy(sorted, values, (size_t)n * sizeof *values);
    qsort(sorted, (size_t)n, sizeof *sorted, bench_cmp);
    *median = n % 2 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2;
    *lo = sorted[0];
    *hi = sorted[n - 1];
}

/* How many repetitions make one round of `c` last about bench_round_ms: grows a trial until it lasts a
   tenth of a round, then takes the fastest of five such trials (a trial that was interrupted must not
   make every round of this contender too long). `warm_ms` is how long the warm-up repetition took: one
   that lasted ten rounds already makes a round of one repetition, without another trial. */
static long bench_calibrate(const BenchContender *c, double warm_ms)
{
    if (warm_ms >= 10 * bench_round_ms)
        return 1;
    long reps = 1;
    double ms;
    for (;;) {
        double start = bench_now_ns();
        c->run(c->context, reps);
        ms = (bench_now_ns() - start) / 1e6;
        if (reps == 1 && ms >= bench_round_ms)
            return 1; /* one repetition fills a round already */
        if (ms >= bench_round_ms / 10 || reps >= (1L << 28))
            break;
        reps *= ms < bench_round_ms / 1000 ? 16 : 2;
    }
    for (int trial = 0; trial < 4; trial++) {
        double start = bench_now_ns();
        c->run(c->context, reps);
        double t = (bench_now_ns() - start) / 1e6;
        ms = t < ms ? t : ms;
    }
    return ms <= 0 ? reps * 10 : (long)((double)reps * bench_round_ms / ms) + 1;
}

/* Runs the contenders in interleaved rounds. */
static BenchResult bench_case(const BenchContender *contenders, int n)
{
    BenchResult r;
    long reps[BENCH_MAX_CONTENDERS];
    r.contenders = n;
    r.rounds = bench_rounds;
    for (int i = 0; i < n; i++) {
        double start = bench_now_ns();
        contenders[i].run(contenders[i].context, 1); /* warm up caches */
        reps[i] = bench_calibrate(&contenders[i], (bench_now_ns() - start) / 1e6);
    }
    double start_rounds = bench_now_ns();
    for (int round = 0; round < r.rounds; round++) {
        for (int k = 0; k < n; k++) {
            int i = (k + round) % n;
            double start = bench_now_ns();
            contenders[i].run(contenders[i].context, reps[i]);
            r.ns[i][round] = (bench_now_ns() - start) / ((double)reps[i] * contenders[i].per_rep);
        }
        if (bench_budget_s > 0 && round + 1 >= BENCH_MIN_ROUNDS && round + 1 < r.rounds &&
            bench_now_ns() - start_rounds > bench_budget_s * 1e9) {
            r.rounds = round + 1;
            if (!bench_fewest_rounds || r.rounds < bench_fewest_rounds)
                bench_fewest_rounds = r.rounds;
        }
    }
    return r;
}

static void bench_format_ns(char *out, size_t size, double ns)
{
    if (ns >= 1e6)
        snprintf(out, size, "%.2f ms", ns / 1e6);
    else if (ns >= 1e3)
        snprintf(out, size, "%.2f us", ns / 1e3);
    else
        snprintf(out, size, "%.1f ns", ns);
}

/* "median (lowest-highest)" of contender `i`. */
static void bench_format_time(char *out, size_t size, const BenchResult *r, int i)
{
    double m, lo, hi;
    char a[24], b[24], c[24];
    bench_stats(r->ns[i], r->rounds, &m, &lo, &hi);
    bench_format_ns(a, sizeof a, m);
    bench_format_ns(b, sizeof b, lo);
    bench_format_ns(c, sizeof c, hi);
    snprintf(out, size, "%s (%s-%s)", a, b, c);
}

/* The median over rounds of ns[num] / ns[den] within each round, and its spread. */
static double bench_ratio(const BenchResult *r, int num, int den, double *lo, double *hi)
{
    double ratios[BENCH_MAX_ROUNDS], m;
    for (int k = 0; k < r->rounds; k++)
        ratios[k] = r->ns[num][k] / r->ns[den][k];
    bench_stats(ratios, r->rounds, &m, lo, hi);
    return m;
}

/* Prints one goal line and counts it. `value` is compared with `goal`: at least when `at_least`,
   otherwise at most. */
static int bench_goal(const char *what, double value, double lo, double hi, int at_least, double goal,
                      const char *unit)
{
    int met = at_least ? value >= goal : value <= goal;
    bench_goals++;
    if (!met)
        bench_failures++;
    printf("GOAL %-64s %7.2f%s (rounds %.2f-%.2f)  goal %s %.2f%s  %s\n", what, value, unit, lo, hi,
           at_least ? ">=" : "<=", goal, unit, met ? "met" : "NOT MET");
    return met;
}

/* The last line of every benchmark, and its exit status. */
static int bench_finish(const char *name)
{
    char rounds[160] = "";
    if (bench_fewest_rounds)
        snprintf(rounds, sizeof rounds, ", the %.0f s budget stopped a case after %d of them", bench_budget_s,
                 bench_fewest_rounds);
    printf("\n%s: %d goals, %d met, %d NOT MET (%d interleaved rounds of about %.0f ms per contender and case%s; %s)\n",
           name, bench_goals, bench_goals - bench_failures, bench_failures, bench_rounds, bench_round_ms, rounds,
           bench_clock);
    return bench_failures ? 1 : 0;
}

#endif
