/* Minimal test harness for the C tests: CHECK macros, UTF-16 helpers, a closing summary line
 * (test_check.h, shared with the C++ tests), and objects the C tests build through lpVtbl. Uses only
 * the public header, exactly as a user program would. */
#ifndef OPCCOMN_TEST_UTIL_H
#define OPCCOMN_TEST_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <opccomn/opccomn.h>

#include "test_check.h"

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
