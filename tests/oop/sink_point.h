/* A connection point taking one sink (cookie 1) and its container, for the test servers of the
 * Alarms & Events and Historical Data Access proxy/stubs (ae_server.c, hda_server.c). The two live in
 * their owner's object: the container answers QueryInterface through the owner; the point is an
 * object of its own identity (IUnknown, IConnectionPoint) that keeps its owner alive. Windows only. */
#ifndef OPCCOMN_SINK_POINT_H
#define OPCCOMN_SINK_POINT_H

#include <olectl.h> /* CONNECT_E_* */
#include <ocidl.h>
#include <stddef.h>

typedef struct SinkPoint {
    IConnectionPointContainer container;
    IConnectionPoint point;
    IUnknown *owner;  /* not a reference: the point lives in the owner */
    const IID *iid;   /* the sink's interface */
    CRITICAL_SECTION lock;
    IUnknown *sink;   /* the advised sink as its interface `iid`, cookie 1 */
} SinkPoint;

#define SINK_POINT_OF(field, p) ((SinkPoint *)((char *)(p) - offsetof(SinkPoint, field)))

static HRESULT STDMETHODCALLTYPE spc_qi(IConnectionPointContainer *This, REFIID riid, void **ppv) {
    IUnknown *owner = SINK_POINT_OF(container, This)->owner;
    return owner->lpVtbl->QueryInterface(owner, riid, ppv);
}
static ULONG STDMETHODCALLTYPE spc_add_ref(IConnectionPointContainer *This) {
    IUnknown *owner = SINK_POINT_OF(container, This)->owner;
    return owner->lpVtbl->AddRef(owner);
}
static ULONG STDMETHODCALLTYPE spc_release(IConnectionPointContainer *This) {
    IUnknown *owner = SINK_POINT_OF(container, This)->owner;
    return owner->lpVtbl->Release(owner);
}
static HRESULT STDMETHODCALLTYPE spc_enum(IConnectionPointContainer *This, IEnumConnectionPoints **e) {
    (void)This;
    if (e) *e = NULL;
    return E_NOTIMPL;
}
static HRESULT STDMETHODCALLTYPE spc_find(IConnectionPointContainer *This, REFIID riid, IConnectionPoint **cp) {
    SinkPoint *s = SINK_POINT_OF(container, This);
    if (!cp) return E_POINTER;
    *cp = NULL;
    if (!IsEqualIID(riid, s->iid)) return CONNECT_E_NOCONNECTION;
    *cp = &s->point;
    s->owner->lpVtbl->AddRef(s->owner);
    return S_OK;
}
static IConnectionPointContainerVtbl sink_container_vtbl = {spc_qi, spc_add_ref, spc_release, spc_enum, spc_find};

static HRESULT STDMETHODCALLTYPE sp_qi(IConnectionPoint *This, REFIID riid, void **ppv) {
    SinkPoint *s = SINK_POINT_OF(point, This);
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!IsEqualIID(riid, &IID_IUnknown) && !IsEqualIID(riid, &IID_IConnectionPoint)) return E_NOINTERFACE;
    *ppv = This;
    s->owner->lpVtbl->AddRef(s->owner);
    return S_OK;
}
static ULONG STDMETHODCALLTYPE sp_add_ref(IConnectionPoint *This) {
    IUnknown *owner = SINK_POINT_OF(point, This)->owner;
    return owner->lpVtbl->AddRef(owner);
}
static ULONG STDMETHODCALLTYPE sp_release(IConnectionPoint *This) {
    IUnknown *owner = SINK_POINT_OF(point, This)->owner;
    return owner->lpVtbl->Release(owner);
}
static HRESULT STDMETHODCALLTYPE sp_iid(IConnectionPoint *This, IID *iid) {
    if (!iid) return E_POINTER;
    *iid = *SINK_POINT_OF(point, This)->iid;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE sp_container(IConnectionPoint *This, IConnectionPointContainer **c) {
    SinkPoint *s = SINK_POINT_OF(point, This);
    if (!c) return E_POINTER;
    *c = &s->container;
    s->owner->lpVtbl->AddRef(s->owner);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE sp_advise(IConnectionPoint *This, IUnknown *unk, DWORD *cookie) {
    SinkPoint *s = SINK_POINT_OF(point, This);
    IUnknown *sink = NULL;
    HRESULT hr;
    if (!cookie) return E_POINTER;
    *cookie = 0;
    if (!unk) return E_POINTER;
    hr = unk->lpVtbl->QueryInterface(unk, s->iid, (void **)&sink);
    if (FAILED(hr)) return CONNECT_E_CANNOTCONNECT;
    EnterCriticalSection(&s->lock);
    if (s->sink) {
        hr = CONNECT_E_ADVISELIMIT;
    } else {
        s->sink = sink;
        sink = NULL;
        *cookie = 1;
    }
    LeaveCriticalSection(&s->lock);
    if (sink) sink->lpVtbl->Release(sink);
    return hr;
}
static HRESULT STDMETHODCALLTYPE sp_unadvise(IConnectionPoint *This, DWORD cookie) {
    SinkPoint *s = SINK_POINT_OF(point, This);
    IUnknown *sink = NULL;
    EnterCriticalSection(&s->lock);
    if (cookie == 1) {
        sink = s->sink;
        s->sink = NULL;
    }
    LeaveCriticalSection(&s->lock);
    if (!sink) return CONNECT_E_NOCONNECTION;
    sink->lpVtbl->Release(sink);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE sp_enum(IConnectionPoint *This, IEnumConnections **e) {
    (void)This;
    if (e) *e = NULL;
    return E_NOTIMPL;
}
static IConnectionPointVtbl sink_point_vtbl = {sp_qi,        sp_add_ref,  sp_release,  sp_iid,
                                               sp_container, sp_advise,   sp_unadvise, sp_enum};

static void sink_point_init(SinkPoint *s, IUnknown *owner, const IID *iid) {
    s->container.lpVtbl = &sink_container_vtbl;
    s->point.lpVtbl = &sink_point_vtbl;
    s->owner = owner;
    s->iid = iid;
    s->sink = NULL;
    InitializeCriticalSection(&s->lock);
}

/* The advised sink, referenced for the caller, or NULL. */
static IUnknown *sink_point_sink(SinkPoint *s) {
    IUnknown *sink;
    EnterCriticalSection(&s->lock);
    sink = s->sink;
    if (sink) sink->lpVtbl->AddRef(sink);
    LeaveCriticalSection(&s->lock);
    return sink;
}

/* At the owner's end: lets go of the sink. */
static void sink_point_end(SinkPoint *s) {
    if (s->sink) s->sink->lpVtbl->Release(s->sink);
    s->sink = NULL;
    DeleteCriticalSection(&s->lock);
}

#endif
