/* An IEnumString of texts it owns, for the test servers of the Alarms & Events and Historical Data
 * Access proxy/stubs (ae_server.c's area browser, hda_server.c's IOPCHDA_Browser). It counts on the
 * server process while it lives (OpcServerLock when made, OpcServerUnlock at its last release).
 * Next hands out copies (CoTaskMemAlloc); Clone is not implemented. Windows only. */
#ifndef OPCCOMN_ENUM_STRINGS_H
#define OPCCOMN_ENUM_STRINGS_H

#include <objidl.h>
#include <stdlib.h>
#include <wchar.h>

typedef struct Strings {
    IEnumString iface;
    LONG refs;
    ULONG count, next, capacity;
    LPWSTR texts[]; /* `capacity` places, the first `count` CoTaskMemAlloc'd texts */
} Strings;

static HRESULT STDMETHODCALLTYPE str_qi(IEnumString *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!IsEqualIID(riid, &IID_IUnknown) && !IsEqualIID(riid, &IID_IEnumString)) return E_NOINTERFACE;
    *ppv = This;
    InterlockedIncrement(&((Strings *)This)->refs);
    return S_OK;
}
static ULONG STDMETHODCALLTYPE str_add_ref(IEnumString *This) {
    return (ULONG)InterlockedIncrement(&((Strings *)This)->refs);
}
static ULONG STDMETHODCALLTYPE str_release(IEnumString *This) {
    Strings *e = (Strings *)This;
    LONG n = InterlockedDecrement(&e->refs);
    ULONG k;
    if (n == 0) {
        for (k = 0; k < e->count; k++) CoTaskMemFree(e->texts[k]);
        free(e);
        OpcServerUnlock(); /* an enumerator counts on the process while it lives */
    }
    return (ULONG)n;
}
static HRESULT STDMETHODCALLTYPE str_next(IEnumString *This, ULONG celt, LPOLESTR *out, ULONG *fetched) {
    Strings *e = (Strings *)This;
    ULONG n = 0;
    if (!out || (celt > 1 && !fetched)) return E_POINTER;
    while (n < celt && e->next < e->count) {
        out[n] = (LPOLESTR)CoTaskMemAlloc((wcslen(e->texts[e->next]) + 1) * sizeof(WCHAR));
        if (!out[n]) break;
        wcscpy(out[n], e->texts[e->next]);
        n++;
        e->next++;
    }
    if (fetched) *fetched = n;
    return n == celt ? S_OK : S_FALSE;
}
static HRESULT STDMETHODCALLTYPE str_skip(IEnumString *This, ULONG celt) {
    Strings *e = (Strings *)This;
    ULONG left = e->count - e->next;
    e->next += celt < left ? celt : left;
    return celt <= left ? S_OK : S_FALSE;
}
static HRESULT STDMETHODCALLTYPE str_reset(IEnumString *This) {
    ((Strings *)This)->next = 0;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE str_clone(IEnumString *This, IEnumString **out) {
    (void)This;
    if (out) *out = NULL;
    return E_NOTIMPL;
}
static IEnumStringVtbl str_vtbl = {str_qi, str_add_ref, str_release, str_next, str_skip, str_reset, str_clone};

/* An empty enumerator with room for `capacity` texts (one reference), or NULL. */
static Strings *strings_new(ULONG capacity) {
    Strings *e = (Strings *)calloc(1, sizeof *e + capacity * sizeof(LPWSTR));
    if (!e) return NULL;
    e->iface.lpVtbl = &str_vtbl;
    e->refs = 1;
    e->capacity = capacity;
    OpcServerLock();
    return e;
}

/* Adds `text` (CoTaskMemAlloc'd; the enumerator owns it from now on, also when it is full: then it is
 * freed and 0 returned). */
static int strings_add(Strings *e, LPWSTR text) {
    if (e->count == e->capacity) {
        CoTaskMemFree(text);
        return 0;
    }
    e->texts[e->count++] = text;
    return 1;
}

#endif
