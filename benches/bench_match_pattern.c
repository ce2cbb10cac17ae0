/* Benchmark (not a test) of MatchPattern against the specification's own sample (Appendix B), compiled
   here with the same compiler and -O2, for wide strings (as MatchPatternW) and narrow ones (as
   MatchPatternA). Run: scripts/bench.sh match-pattern [--wine]; `scripts/bench.sh` passes its extra
   words on, so `bench_match_pattern typical` runs one set and `bench_match_pattern typical Device` only
   the typical filters containing "Device".

   Sets:
   - typical: 100,000 item IDs ChannelN.DeviceM.TagK against the filters a browse gets, both case modes.
     Contenders: the sample (wide), MatchPatternW, the compiled filter (OpcPatternMatchW), the sample
     (narrow), MatchPatternA, and glibc fnmatch for information (Linux). Goals per filter and mode:
     MatchPatternW and MatchPatternA >= 1.0x their sample, the compiled filter >= 2.0x the wide sample;
     over the set, MatchPatternW and MatchPatternA >= 4x the sample in geometric mean.
   - adversarial: patterns on which the sample's recursion explodes; goal: at most 2 us per call.
   - worst: 4 KiB patterns built to cost len(string) x len(pattern) / 4 steps; goal: at most 50 ms.
   Ratios are speed-ups (the sample's time divided by ours): above 1 we are faster. */
#if !defined(_WIN32)
#define _GNU_SOURCE /* FNM_CASEFOLD */
#include <fnmatch.h>
#endif
#include "bench.h"

#include <ctype.h>
#include <math.h>
#include <wctype.h>

#include <opccomn/opccomn.h>

/* ---- The sample, once per character type; the typical set calls it through a pointer, as a program
   calls the library's functions. ---- */
#define SAMPLE_TCHAR WCHAR
#define SAMPLE_NAME sample_w
#define SAMPLE_ISTDIGIT(c) iswdigit((wint_t)(c))
#include "spec_sample.h"
#undef SAMPLE_TCHAR
#undef SAMPLE_NAME
#undef SAMPLE_ISTDIGIT
#define SAMPLE_TCHAR char
#define SAMPLE_NAME sample_a
#define SAMPLE_ISTDIGIT(c) isdigit((unsigned char)(c))
#include "spec_sample.h"
#undef SAMPLE_NAME
#undef SAMPLE_TCHAR
#undef SAMPLE_ISTDIGIT
/* With a budget of recursive calls, for the adversarial and worst sets (the sample would run for hours). */
static long sample_budget;
#define SAMPLE_TCHAR WCHAR
#define SAMPLE_NAME sample_w_budgeted
#define SAMPLE_ISTDIGIT(c) iswdigit((wint_t)(c))
#define SAMPLE_BUDGET sample_budget
#include "spec_sample.h"

typedef BOOL (*WideMatcher)(const WCHAR *, const WCHAR *, BOOL);
typedef BOOL (*NarrowMatcher)(const char *, const char *, BOOL);
static WideMatcher volatile sample_wide = sample_w;
static NarrowMatcher volatile sample_narrow = sample_a;

/* ---- Inputs ---- */

static WCHAR *widen(const char *s)
{
    size_t n = strlen(s);
    WCHAR *w = malloc((n + 1) * sizeof *w);
    for (size_t i = 0; i <= n; i++)
        w[i] = (unsigned char)s[i];
    return w;
}

#define ITEMS 100000
static char *ids_a[ITEMS];
static WCHAR *ids_w[ITEMS];

static void make_ids(void)
{
    /* One block per form, the strings back to back as an address space keeps them. */
    static char narrow[ITEMS * 32];
    static WCHAR wide[ITEMS * 32];
    size_t at = 0;
    int k = 0;
    for (int c = 1; c <= 10; c++)
        for (int d = 1; d <= 10; d++)
            for (int t = 1; t <= 1000; t++, k++) {
                int n = snprintf(narrow + at, 32, "Channel%d.Device%d.Tag%d", c, d, t);
                ids_a[k] = narrow + at;
                ids_w[k] = wide + at;
                for (int i = 0; i <= n; i++)
                    wide[at + (size_t)i] = (unsigned char)narrow[at + (size_t)i];
                at += (size_t)n + 1;
            }
}

/* ---- Typical set ---- */

typedef struct {
    const char *pattern_a;
    const WCHAR *pattern_w;
    char fnmatch_pattern[64];
    BOOL case_sensitive;
    OpcPattern *compiled;
    long next; /* the next item, so rounds of any length walk the whole list */
} Filter;

static volatile long sink;

#define TYPICAL_RUN(fn, expr)                          \
    static void fn(void *context, long reps)           \
    {                                                  \
        Filter *f = context;                           \
        long i = f->next, hits = 0;                    \
        for (long r = 0; r < reps; r++) {              \
            hits += (expr);                            \
            if (++i == ITEMS)                          \
                i = 0;                                 \
        }                                              \
        f->next = i;                                   \
        sink += hits;                                  \
    }
TYPICAL_RUN(run_sample_w, sample_wide(ids_w[i], f->pattern_w, f->case_sensitive))
TYPICAL_RUN(run_match_w, MatchPatternW(ids_w[i], f->pattern_w, f->case_sensitive))
TYPICAL_RUN(run_compiled, OpcPatternMatchW(f->compiled, ids_w[i]))
TYPICAL_RUN(run_sample_a, sample_narrow(ids_a[i], f->pattern_a, f->case_sensitive))
TYPICAL_RUN(run_match_a, MatchPatternA(ids_a[i], f->pattern_a, f->case_sensitive))
#if !defined(_WIN32)
TYPICAL_RUN(run_fnmatch, fnmatch(f->fnmatch_pattern, ids_a[i], FNM_NOESCAPE | (f->case_sensitive ? 0 : FNM_CASEFOLD)) == 0)
#endif

enum { SAMPLE_W, MATCH_W, COMPILED, SAMPLE_A, MATCH_A, FNMATCH, CONTENDERS };
static const char *const CONTENDER_NAMES[CONTENDERS] = {"sample W", "MatchPatternW", "compiled", "sample A",
                                                        "MatchPatternA", "fnmatch"};

static int count_hits(BenchContender *c, Filter *f)
{
    long before = sink;
    f->next = 0;
    c->run(c->context, ITEMS);
    return (int)(sink - before);
}

/* The typical filters (add to them, never drop one). */
static const char *const TYPICAL[] = {
    "*Device1.Tag1#*", "Channel1.*", "*.Tag12?", "Channel?.Device[1-3].Tag*",
    "*[!0-9]",         "*",          "*Tag999",  "*e*e*e*9",
};

static void typical_set(const char *only)
{
    const int n_filters = (int)(sizeof TYPICAL / sizeof *TYPICAL);
    int n_contenders = CONTENDERS;
#if defined(_WIN32)
    n_contenders = CONTENDERS - 1; /* no fnmatch */
#endif
    double log_sum_w = 0, log_sum_a = 0;
    int cases = 0;
    printf("\nTypical set: %d item IDs Channel{1..10}.Device{1..10}.Tag{1..1000}; ns per item, median "
           "(lowest-highest round); speed-up = sample / ours\n",
           ITEMS);
    printf("%-34s", "filter [mode] (hits)");
    for (int i = 0; i < n_contenders; i++)
        printf(" %26s", CONTENDER_NAMES[i]);
    printf("\n");
    for (int cs = 1; cs >= 0; cs--) {
        for (int k = 0; k < n_filters; k++) {
            if (only && !strstr(TYPICAL[k], only))
                continue;
            Filter f = {0};
            f.pattern_a = TYPICAL[k];
            f.pattern_w = widen(TYPICAL[k]);
            f.case_sensitive = cs;
            /* fnmatch syntax: `#` is [0-9]; the rest of these filters means the same. */
            for (const char *s = TYPICAL[k]; *s; s++)
                strcat(f.fnmatch_pattern, *s == '#' ? "[0-9]" : (char[]){*s, 0});
            if (OpcPatternCompileW(f.pattern_w, cs, &f.compiled) != S_OK) {
                fprintf(stderr, "OpcPatternCompileW failed for %s\n", TYPICAL[k]);
                exit(2);
            }
            BenchContender c[CONTENDERS] = {
                {CONTENDER_NAMES[SAMPLE_W], run_sample_w, &f, 1}, {CONTENDER_NAMES[MATCH_W], run_match_w, &f, 1},
                {CONTENDER_NAMES[COMPILED], run_compiled, &f, 1}, {CONTENDER_NAMES[SAMPLE_A], run_sample_a, &f, 1},
                {CONTENDER_NAMES[MATCH_A], run_match_a, &f, 1},
#if !defined(_WIN32)
                {CONTENDER_NAMES[FNMATCH], run_fnmatch, &f, 1},
#endif
            };
            /* Every contender selects the same items. */
            int hits = count_hits(&c[0], &f);
            for (int i = 1; i < n_contenders; i++) {
                int h = count_hits(&c[i], &f);
                if (h != hits) {
                    fprintf(stderr, "%s selects %d items of %s, the sample %d\n", c[i].name, h, TYPICAL[k], hits);
                    exit(2);
                }
            }
            BenchResult r = bench_case(c, n_contenders);
            char label[64], cell[96];
            snprintf(label, sizeof label, "%s [%s] (%d)", TYPICAL[k], cs ? "cs" : "ci", hits);
            printf("%-34s", label);
            for (int i = 0; i < n_contenders; i++) {
                bench_format_time(cell, sizeof cell, &r, i);
                printf(" %26s", cell);
            }
            printf("\n");
            double lo, hi, x;
            char what[128];
            x = bench_ratio(&r, SAMPLE_W, MATCH_W, &lo, &hi);
            log_sum_w += log(x);
            snprintf(what, sizeof what, "MatchPatternW speed-up, %s", label);
            bench_goal(what, x, lo, hi, 1, 1.0, "x");
            x = bench_ratio(&r, SAMPLE_A, MATCH_A, &lo, &hi);
            log_sum_a += log(x);
            snprintf(what, sizeof what, "MatchPatternA speed-up, %s", label);
            bench_goal(what, x, lo, hi, 1, 1.0, "x");
            x = bench_ratio(&r, SAMPLE_W, COMPILED, &lo, &hi);
            snprintf(what, sizeof what, "compiled filter speed-up, %s", label);
            bench_goal(what, x, lo, hi, 1, 2.0, "x");
            cases++;
            OpcPatternFree(f.compiled);
            free((void *)f.pattern_w);
        }
    }
    if (cases && !only) {
        double gw = exp(log_sum_w / cases), ga = exp(log_sum_a / cases);
        bench_goal("MatchPatternW speed-up, geometric mean over the typical set", gw, gw, gw, 1, 4.0, "x");
        bench_goal("MatchPatternA speed-up, geometric mean over the typical set", ga, ga, ga, 1, 4.0, "x");
    }
}

/* ---- Adversarial and worst cases: one string against one pattern ---- */

typedef struct {
    const WCHAR *s, *p;
    const char *sa, *pa;
    BOOL cs;
    OpcPattern *compiled;
} Single;

static void run_single_w(void *context, long reps)
{
    Single *x = context;
    for (long r = 0; r < reps; r++)
        sink += MatchPatternW(x->s, x->p, x->cs);
}
static void run_single_compiled(void *context, long reps)
{
    Single *x = context;
    for (long r = 0; r < reps; r++)
        sink += OpcPatternMatchW(x->compiled, x->s);
}
static void run_single_a(void *context, long reps)
{
    Single *x = context;
    for (long r = 0; r < reps; r++)
        sink += MatchPatternA(x->sa, x->pa, x->cs);
}

/* Times one case; returns the slowest of our three medians. */
static double single_case(const char *name, const char *s, const char *p, BOOL cs, BOOL expected)
{
    Single x = {widen(s), widen(p), s, p, cs, NULL};
    if (OpcPatternCompileW(x.p, cs, &x.compiled) != S_OK || MatchPatternW(x.s, x.p, cs) != expected ||
        MatchPatternA(s, p, cs) != expected || OpcPatternMatchW(x.compiled, x.s) != expected) {
        fprintf(stderr, "wrong answer: %s\n", name);
        exit(2);
    }
    /* The sample once, with a budget of 20,000,000 recursive calls. */
    sample_budget = 20000000;
    sample_cut = 0;
    double start = bench_now_ns();
    BOOL got = sample_w_budgeted(x.s, x.p, cs);
    double sample_ns = bench_now_ns() - start;
    if (!sample_cut && got != expected) {
        fprintf(stderr, "the sample disagrees: %s\n", name);
        exit(2);
    }
    BenchContender c[3] = {
        {"MatchPatternW", run_single_w, &x, 1},
        {"compiled", run_single_compiled, &x, 1},
        {"MatchPatternA", run_single_a, &x, 1},
    };
    BenchResult r = bench_case(c, 3);
    char cells[3][96], sample[64];
    for (int i = 0; i < 3; i++)
        bench_format_time(cells[i], sizeof cells[i], &r, i);
    bench_format_ns(sample, sizeof sample, sample_ns);
    printf("%-34s %20s%s %26s %26s %26s\n", name, sample_cut ? ">= " : "", sample, cells[0], cells[1], cells[2]);
    double worst = 0;
    for (int i = 0; i < 3; i++) {
        double m, lo, hi;
        bench_stats(r.ns[i], r.rounds, &m, &lo, &hi);
        worst = m > worst ? m : worst;
    }
    OpcPatternFree(x.compiled);
    free((void *)x.s);
    free((void *)x.p);
    return worst;
}

static char *repeat(const char *unit, int times, const char *tail)
{
    size_t n = strlen(unit), t = strlen(tail);
    char *s = malloc(n * (size_t)times + t + 1);
    for (int i = 0; i < times; i++)
        memcpy(s + n * (size_t)i, unit, n);
    memcpy(s + n * (size_t)times, tail, t + 1);
    return s;
}

static void adversarial_set(void)
{
    printf("\nAdversarial set: time per call, median (lowest-highest round); the sample once, cut off after "
           "20,000,000 recursive calls\n%-34s %23s %26s %26s %26s\n",
           "case", "sample W", "MatchPatternW", "compiled", "MatchPatternA");
    char *a100 = repeat("a", 100, "");
    double worst = 0;
    for (int k = 4; k <= 12; k++) {
        char name[64];
        char *p = repeat("a*", k, "b");
        snprintf(name, sizeof name, "(a*)^%d b vs 100 a", k);
        double t = single_case(name, a100, p, TRUE, FALSE);
        worst = t > worst ? t : worst;
        free(p);
    }
    char *a24 = repeat("a", 24, ""), *p = repeat("*", 12, "b");
    double t = single_case("12 * then b vs 24 a", a24, p, TRUE, FALSE);
    worst = t > worst ? t : worst;
    bench_goal("adversarial: slowest median of ours (us per call)", worst / 1e3, worst / 1e3, worst / 1e3, 0, 2.0,
               " us");
    free(a100);
    free(a24);
    free(p);
}

static void worst_set(void)
{
    printf("\nWorst case: 4 KiB pattern vs 4 KiB string, time per call\n%-34s %23s %26s %26s %26s\n", "case",
           "sample W", "MatchPatternW", "compiled", "MatchPatternA");
    char *a4096 = repeat("a", 4096, "");
    /* Each pattern is 4096 characters, padded with trailing `*`s; a middle segment that matches
       everywhere but at its last token makes the search try it at every place. */
    struct {
        const char *name;
        const char *unit;
        int times;
        BOOL cs;
        int plain; /* no leading `*`, no `#`, no padding: (*?){2047}b */
    } cases[] = {
        {"*?{2046}#* vs a{4096} [cs]", "?", 2046, TRUE, 0},
        {"*(a?){1023}#* vs a{4096} [cs]", "a?", 1023, TRUE, 0},
        {"*[a-z]{818}#* vs a{4096} [ci]", "[a-z]", 818, FALSE, 0},
        {"*a{2046}#* vs a{4096} [ci]", "a", 2046, FALSE, 0},
        {"(*?){2047}b vs a{4096} [cs]", "*?", 2047, TRUE, 1},
    };
    double worst = 0;
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char *body = repeat(cases[k].unit, cases[k].times, cases[k].plain ? "b" : "#");
        char *p;
        if (cases[k].plain) {
            p = body;
        } else {
            size_t n = strlen(body) + 1;
            char *stars = repeat("*", n < 4096 ? (int)(4096 - n) : 0, "");
            p = malloc(strlen(body) + strlen(stars) + 2);
            sprintf(p, "*%s%s", body, stars);
            free(body);
            free(stars);
        }
        double t = single_case(cases[k].name, a4096, p, cases[k].cs, FALSE);
        worst = t > worst ? t : worst;
        free(p);
    }
    bench_goal("worst case: slowest median of ours (ms per call)", worst / 1e6, worst / 1e6, worst / 1e6, 0, 50.0,
               " ms");
    free(a4096);
}

int main(int argc, char **argv)
{
    bench_init();
    const char *set = argc > 1 ? argv[1] : NULL;
    const char *only = argc > 2 ? argv[2] : NULL;
    make_ids();
    printf("MatchPattern against the specification's sample (Appendix B, recursive, this compiler at -O2)\n");
    if (!set || !strcmp(set, "typical"))
        typical_set(only);
    if (!set || !strcmp(set, "adversarial"))
        adversarial_set();
    if (!set || !strcmp(set, "worst"))
        worst_set();
    return bench_finish("bench_match_pattern");
}
