/* Benchmark (not a test): IOPCCommon::GetErrorString per call, through the COM vtable, including the
   allocation of the returned string and its free, against the plainest C implementation measured in
   the same run: a switch returning a literal, copied into OpcTaskMem memory and freed.

   Run: scripts/bench.sh error-string [--wine]. Goal: at most 1.5x the baseline, in the session's
   default locale (LOCALE_SYSTEM_DEFAULT) and in an explicit one (de-DE). */
#include "bench.h"

#include <opccomn/opccomn.h>

/* The codes asked for, a mix of Data Access texts of different lengths. */
static const HRESULT CODES[8] = {
    (HRESULT)0xC0040001u, (HRESULT)0xC0040004u, (HRESULT)0xC0040007u, (HRESULT)0xC004000Au,
    (HRESULT)0x0004000Du, (HRESULT)0xC0040203u, (HRESULT)0xC0040400u, (HRESULT)0x00040404u,
};

/* A UTF-16 literal as the header's WCHAR, with its size in bytes (NUL included) known at compile time. */
#define T(s) ((const WCHAR *)u##s), bytes = sizeof(u##s)

/* The baseline: what a hand-written server does at best. Called through a pointer, like the vtable. */
static HRESULT baseline_get_error_string(HRESULT code, LPWSTR *out)
{
    const WCHAR *text;
    size_t bytes;
    switch ((uint32_t)code) {
    case 0xC0040001u: text = T("The value of the handle is invalid."); break;
    case 0xC0040004u:
        text = T("The server cannot convert the data between the specified format and/or requested data type and the "
               "canonical data type.");
        break;
    case 0xC0040007u:
        text = T("The item ID is not defined in the server address space or no longer exists in the server address "
               "space.");
        break;
    case 0xC004000Au: text = T("The item's access path is not known to the server."); break;
    case 0x0004000Du:
        text = T("The server does not support the requested data rate but will use the closest available rate.");
        break;
    case 0xC0040203u: text = T("The specified property ID is not valid for the item."); break;
    case 0xC0040400u: text = T("The item deadband has not been set for this item."); break;
    case 0x00040404u:
        text = T("Not every detected change has been returned since the server's buffer reached its limit and had to "
               "purge out the oldest data.");
        break;
    default: *out = NULL; return E_INVALIDARG;
    }
    LPWSTR s = OpcTaskMemAlloc(bytes);
    if (!s) {
        *out = NULL;
        return E_OUTOFMEMORY;
    }
    memcpy(s, text, bytes);
    *out = s;
    return S_OK;
}

static HRESULT (*volatile baseline)(HRESULT, LPWSTR *) = baseline_get_error_string;

static volatile unsigned long sink;

typedef struct {
    IOPCCommon *common;
} Library;

static void run_library(void *context, long reps)
{
    IOPCCommon *common = ((Library *)context)->common;
    for (long i = 0; i < reps; i++) {
        LPWSTR s;
        if (common->lpVtbl->GetErrorString(common, CODES[i & 7], &s) == S_OK) {
            sink += s[0];
            OpcTaskMemFree(s);
        }
    }
}

static void run_baseline(void *context, long reps)
{
    (void)context;
    for (long i = 0; i < reps; i++) {
        LPWSTR s;
        if (baseline(CODES[i & 7], &s) == S_OK) {
            sink += s[0];
            OpcTaskMemFree(s);
        }
    }
}

int main(void)
{
    bench_init();
    void *p = NULL;
    if (OpcCommonCreate(NULL, NULL, &IID_IOPCCommon, &p) != S_OK) {
        fprintf(stderr, "OpcCommonCreate failed\n");
        return 2;
    }
    Library library = {p};
    printf("GetErrorString through the IOPCCommon vtable (string allocated and freed) against a C switch\n"
           "copying a literal into OpcTaskMemAlloc memory; ns per call, median (lowest-highest round)\n\n");
    const LCID locales[2] = {LOCALE_SYSTEM_DEFAULT, 0x0407};
    const char *names[2] = {"LOCALE_SYSTEM_DEFAULT", "de-DE (0x0407)"};
    for (int l = 0; l < 2; l++) {
        if (library.common->lpVtbl->SetLocaleID(library.common, locales[l]) != S_OK) {
            fprintf(stderr, "SetLocaleID failed\n");
            return 2;
        }
        BenchContender c[2] = {
            {"C baseline", run_baseline, NULL, 1},
            {"GetErrorString", run_library, &library, 1},
        };
        BenchResult r = bench_case(c, 2);
        char base[96], lib[96], what[128];
        bench_format_time(base, sizeof base, &r, 0);
        bench_format_time(lib, sizeof lib, &r, 1);
        printf("session locale %-22s  C baseline %-28s GetErrorString %s\n", names[l], base, lib);
        double lo, hi, ratio = bench_ratio(&r, 1, 0, &lo, &hi);
        snprintf(what, sizeof what, "GetErrorString / C baseline, %s", names[l]);
        bench_goal(what, ratio, lo, hi, 0, 1.5, "x");
    }
    library.common->lpVtbl->Release(library.common);
    return bench_finish("bench_error_string");
}
