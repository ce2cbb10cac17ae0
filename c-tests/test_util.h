/* Minimal test harness for the C tests: CHECK macros, UTF-16 helpers, a closing summary line.
 * Uses only the public header, exactly as a user program would. */
#ifndef OPCCOMN_TEST_UTIL_H
#define OPCCOMN_TEST_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <opccomn/opccomn.h>

static int test_passed;
static int test_failed;

#define CHECK(cond)                                                                   \
    do {                                                                              \
        if (cond) {                                                                   \
            test_passed++;                                                            \
        } else {                                                                      \
            test_failed++;                                                            \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
        }                                                                             \
    } while (0)

#define CHECK_HR(expr, expected)                                                                      \
    do {                                                                                              \
        HRESULT check_hr_got_ = (expr);                                                               \
        HRESULT check_hr_want_ = (expected);                                                          \
        if (check_hr_got_ == check_hr_want_) {                                                        \
            test_passed++;                                                                            \
        } else {                                                                                      \
            test_failed++;                                                                            \
            fprintf(stderr, "%s:%d: %s returned 0x%08lX, expected 0x%08lX\n", __FILE__, __LINE__, #expr, \
                    (unsigned long)(unsigned int)check_hr_got_, (unsigned long)(unsigned int)check_hr_want_); \
        }                                                                                             \
    } while (0)

/* Garbage to pre-fill out-parameters with, proving the callee writes them. */
#define GARBAGE_PTR ((void *)(size_t)0xDEADBEEFu)
#define GARBAGE_U32 0xDEADBEEFu

/* Prints the closing line ctest logs show ("N passed, M failed") and returns the exit code. */
static int test_summary(const char *name) {
    printf("%s: %d passed, %d failed\n", name, test_passed, test_failed);
    return test_failed == 0 ? 0 : 1;
}

/* UTF-8 to NUL-terminated UTF-16 in one of a ring of static buffers (tests only; up to 1023 units). */
static const WCHAR *W(const char *utf8) {
    static WCHAR ring[16][1024];
    static unsigned next;
    WCHAR *out = ring[next++ % 16];
    const unsigned char *s = (const unsigned char *)utf8;
    size_t n = 0;
    while (*s && n < 1020) {
        unsigned long cp;
        if (*s < 0x80) {
            cp = *s++;
        } else if ((*s & 0xE0) == 0xC0) {
            cp = (unsigned long)(*s++ & 0x1F) << 6;
            cp |= *s++ & 0x3F;
        } else if ((*s & 0xF0) == 0xE0) {
            cp = (unsigned long)(*s++ & 0x0F) << 12;
            cp |= (unsigned long)(*s++ & 0x3F) << 6;
            cp |= *s++ & 0x3F;
        } else {
            cp = (unsigned long)(*s++ & 0x07) << 18;
            cp |= (unsigned long)(*s++ & 0x3F) << 12;
            cp |= (unsigned long)(*s++ & 0x3F) << 6;
            cp |= *s++ & 0x3F;
        }
        if (cp >= 0x10000) {
            cp -= 0x10000;
            out[n++] = (WCHAR)(0xD800 + (cp >> 10));
            out[n++] = (WCHAR)(0xDC00 + (cp & 0x3FF));
        } else {
            out[n++] = (WCHAR)cp;
        }
    }
    out[n] = 0;
    return out;
}

/* Number of UTF-16 units before the NUL. */
static size_t wlen(const WCHAR *s) {
    size_t n = 0;
    while (s[n]) n++;
    return n;
}

/* True when the NUL-terminated UTF-16 string `got` equals `want_utf8`. */
static int wstr_is(const WCHAR *got, const char *want_utf8) {
    const WCHAR *want = W(want_utf8);
    size_t i = 0;
    if (!got) return 0;
    for (;; i++) {
        if (got[i] != want[i]) return 0;
        if (!got[i]) return 1;
    }
}

/* Prints a UTF-16 string as UTF-8-ish ASCII for diagnostics (non-ASCII as \uXXXX). */
static void wprint(FILE *f, const WCHAR *s) {
    if (!s) {
        fputs("(null)", f);
        return;
    }
    for (; *s; s++) {
        if (*s < 0x80) fputc((int)*s, f);
        else fprintf(f, "\\u%04X", (unsigned)*s);
    }
}

/* IID_IUnknown, for tests that must not depend on a system library providing it. */
static const IID IID_Unknown_ = {0x00000000, 0x0000, 0x0000, {0xC0, 0, 0, 0, 0, 0, 0, 0x46}};

static int same_iid(const IID *a, const IID *b) { return memcmp(a, b, sizeof(IID)) == 0; }

/* A heap copy (malloc) of an ASCII text as UTF-16, for texts longer than W() allows. */
static WCHAR *wdup(const char *ascii) {
    size_t n = strlen(ascii), i;
    WCHAR *w = (WCHAR *)malloc((n + 1) * sizeof(WCHAR));
    for (i = 0; w && i <= n; i++) w[i] = (WCHAR)(unsigned char)ascii[i];
    return w;
}

/* True when two UTF-16 strings are equal (two NULLs are equal too). */
static int wsame(const WCHAR *a, const WCHAR *b) {
    size_t i = 0;
    if (!a || !b) return a == b;
    for (;; i++) {
        if (a[i] != b[i]) return 0;
        if (!a[i]) return 1;
    }
}

/* ---- A server object written in C that aggregates a library object, as a C++ server does with
 * COM_INTERFACE_ENTRY_AGGREGATE: it forwards QueryInterface for one IID to the library object's
 * inner IUnknown and counts every AddRef and Release it receives. ---- */
typedef struct AggregatingServer {
    IUnknown unk; /* the identity */
    ULONG refs;
    int add_refs, releases, destroyed;
    IUnknown *inner;          /* the library object's non-delegating IUnknown */
    const IID *forwarded_iid; /* the interface the library object provides */
} AggregatingServer;

static HRESULT STDMETHODCALLTYPE aggregating_qi(IUnknown *This, REFIID riid, void **ppv) {
    AggregatingServer *s = (AggregatingServer *)This;
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (same_iid(riid, &IID_Unknown_)) {
        *ppv = &s->unk;
        This->lpVtbl->AddRef(This);
        return S_OK;
    }
    if (same_iid(riid, s->forwarded_iid)) return s->inner->lpVtbl->QueryInterface(s->inner, riid, ppv);
    return E_NOINTERFACE;
}

static ULONG STDMETHODCALLTYPE aggregating_add_ref(IUnknown *This) {
    AggregatingServer *s = (AggregatingServer *)This;
    s->add_refs++;
    return ++s->refs;
}

static ULONG STDMETHODCALLTYPE aggregating_release(IUnknown *This) {
    AggregatingServer *s = (AggregatingServer *)This;
    s->releases++;
    if (--s->refs == 0) {
        s->destroyed = 1;
        s->inner->lpVtbl->Release(s->inner);
        s->inner = NULL;
        return 0;
    }
    return s->refs;
}

/* Not const: <windows.h> declares IUnknown::lpVtbl without const. */
static IUnknownVtbl aggregating_vtbl = {aggregating_qi, aggregating_add_ref, aggregating_release};

/* One reference held by the creator; `inner` is set by the test after creating the library object. */
static void aggregating_server_init(AggregatingServer *s, const IID *forwarded_iid) {
    memset(s, 0, sizeof *s);
    s->unk.lpVtbl = &aggregating_vtbl;
    s->refs = 1;
    s->forwarded_iid = forwarded_iid;
}

#endif /* OPCCOMN_TEST_UTIL_H */
