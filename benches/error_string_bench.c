/* Benchmark (not a test): IOPCCommon::GetErrorString per call, through the COM vtable, including the
   allocation of the returned string and its free, against the plainest C implementation measured in
   the same run: a switch returning a literal, copied into OpcTaskMem memory and freed.

   Run: scripts/bench-error-strings.sh [--wine] (builds the release library and this program, prints
   the ratio; the goal is at most 1.5x the baseline). Only the public header is used, as a server
   would. */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <opccomn/opccomn.h>

#if defined(_WIN32)
static double now_ns(void)
{
    static LARGE_INTEGER frequency;
    LARGE_INTEGER t;
    if (!frequency.QuadPart)
        QueryPerformanceFrequency(&frequency);
    QueryPerformanceCounter(&t);
    return (double)t.QuadPart * 1e9 / (double)frequency.QuadPart;
}
#else
#include <time.h>
static double now_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}
#endif

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

static double run_library(IOPCCommon *common, long calls)
{
    double start = now_ns();
    for (long i = 0; i < calls; i++) {
        LPWSTR s;
        if (common->lpVtbl->GetErrorString(common, CODES[i & 7], &s) == S_OK) {
            sink += s[0];
            OpcTaskMemFree(s);
        }
    }
    return (now_ns() - start) / (double)calls;
}

static double run_baseline(long calls)
{
    double start = now_ns();
    for (long i = 0; i < calls; i++) {
        LPWSTR s;
        if (baseline(CODES[i & 7], &s) == S_OK) {
            sink += s[0];
            OpcTaskMemFree(s);
        }
    }
    return (now_ns() - start) / (double)calls;
}

int main(int argc, char **argv)
{
    long calls = argc > 1 ? atol(argv[1]) : 2000000;
    if (calls < 1000)
        calls = 1000;
    void *p = NULL;
    if (OpcCommonCreate(NULL, NULL, &IID_IOPCCommon, &p) != S_OK) {
        fprintf(stderr, "OpcCommonCreate failed\n");
        return 1;
    }
    IOPCCommon *common = p;
    /* Best of several alternating rounds, so both sides see the same machine state. */
    const LCID locales[2] = {LOCALE_SYSTEM_DEFAULT, 0x0407};
    const char *names[2] = {"session locale LOCALE_SYSTEM_DEFAULT", "session locale de-DE (0x0407)"};
    double worst_ratio = 0;
    for (int l = 0; l < 2; l++) {
        common->lpVtbl->SetLocaleID(common, locales[l]);
        double lib = 1e30, base = 1e30;
        run_library(common, calls / 10); /* warm up */
        run_baseline(calls / 10);
        for (int round = 0; round < 7; round++) {
            double b = run_baseline(calls), t = run_library(common, calls);
            base = b < base ? b : base;
            lib = t < lib ? t : lib;
        }
        double ratio = lib / base;
        worst_ratio = ratio > worst_ratio ? ratio : worst_ratio;
        printf("%s: GetErrorString %.1f ns/call, C baseline %.1f ns/call, ratio %.2fx\n", names[l], lib, base,
               ratio);
    }
    printf("ratio %.2fx (goal <= 1.50x: %s)\n", worst_ratio, worst_ratio <= 1.5 ? "met" : "NOT met");
    common->lpVtbl->Release(common);
    return 0;
}
