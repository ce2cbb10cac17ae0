/* Shutdown (specification chapter 4) through the public header: the server's connection point with
 * every return code, re-entrant and failing sinks, enumerations, the advise limit, aggregation into a
 * C server object, a C server object that forwards to it and names itself as the container (COM
 * identity, lifetimes), exact reference counts with counting mock sinks, the client-side sink and advise
 * helpers, and (on Windows) a sink living in another apartment. */
#include <stddef.h>

#include "test_util.h"

#ifdef _WIN32
#include <process.h>
#endif

static const IID IID_Bogus_ = {0x01234567, 0x89AB, 0xCDEF, {1, 2, 3, 4, 5, 6, 7, 8}};
static const IID IID_Marshal_ = {0x00000003, 0x0000, 0x0000, {0xC0, 0, 0, 0, 0, 0, 0, 0x46}};

#define CONNECT_E_NOCONNECTION_ ((HRESULT)0x80040200u)
#define CONNECT_E_ADVISELIMIT_ ((HRESULT)0x80040201u)
#define CONNECT_E_CANNOTCONNECT_ ((HRESULT)0x80040202u)
#define RPC_E_WRONG_THREAD_ ((HRESULT)0x8001010Eu)


/* ---- A client sink written by hand: counts references, records calls, runs a hook. ---- */
typedef struct Mock Mock;
typedef void (*MockHook)(Mock *m);
struct Mock {
    IOPCShutdown iface; /* also its IUnknown */
    long refs, add_refs, releases;
    int has_shutdown;  /* answers QueryInterface(IID_IOPCShutdown) */
    HRESULT result;    /* what ShutdownRequest returns */
    int calls;
    int null_reason;   /* a NULL reason was seen (never allowed) */
    WCHAR reason[64];  /* the last reason */
    MockHook hook;     /* run inside ShutdownRequest */
    void *hook_arg;
    DWORD hook_cookie;
    HRESULT hook_hr;
    IUnknown *marshaler; /* Windows: an aggregated free-threaded marshaler, making the sink agile */
    int marshal_queries;
#ifdef _WIN32
    DWORD call_thread;
#endif
};

static HRESULT STDMETHODCALLTYPE mock_qi(IOPCShutdown *This, REFIID riid, void **ppv) {
    Mock *m = (Mock *)This;
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (same_iid(riid, &IID_Unknown_) || (m->has_shutdown && same_iid(riid, &IID_IOPCShutdown))) {
        *ppv = &m->iface;
        This->lpVtbl->AddRef(This);
        return S_OK;
    }
    if (same_iid(riid, &IID_Marshal_)) {
        m->marshal_queries++;
        if (m->marshaler) return m->marshaler->lpVtbl->QueryInterface(m->marshaler, riid, ppv);
    }
    return E_NOINTERFACE;
}

static ULONG STDMETHODCALLTYPE mock_add_ref(IOPCShutdown *This) {
    Mock *m = (Mock *)This;
    m->add_refs++;
    return (ULONG)++m->refs;
}

static ULONG STDMETHODCALLTYPE mock_release(IOPCShutdown *This) {
    Mock *m = (Mock *)This;
    m->releases++;
    CHECK(m->refs > 0); /* never released more often than referenced */
    return (ULONG)--m->refs;
}

static HRESULT STDMETHODCALLTYPE mock_shutdown_request(IOPCShutdown *This, LPCWSTR reason) {
    Mock *m = (Mock *)This;
    size_t i = 0;
    m->calls++;
#ifdef _WIN32
    m->call_thread = GetCurrentThreadId();
#endif
    if (!reason) {
        m->null_reason = 1;
    } else {
        for (; reason[i] && i < 63; i++) m->reason[i] = reason[i];
    }
    m->reason[i] = 0;
    if (m->hook) m->hook(m);
    return m->result;
}

static IOPCShutdownVtbl mock_vtbl = {mock_qi, mock_add_ref, mock_release, mock_shutdown_request};

static void mock_init(Mock *m, int has_shutdown, HRESULT result) {
    memset(m, 0, sizeof *m);
    m->iface.lpVtbl = &mock_vtbl;
    m->refs = 1;
    m->has_shutdown = has_shutdown;
    m->result = result;
}

static IUnknown *mock_unk(Mock *m) { return (IUnknown *)&m->iface; }

/* ---- Helpers over the server's interfaces. ---- */
static IConnectionPointContainer *create_server(const OpcShutdownOptions *options) {
    void *p = GARBAGE_PTR;
    HRESULT hr = OpcShutdownCreateEx(options, NULL, &IID_IConnectionPointContainer, &p);
    CHECK_HR(hr, S_OK);
    CHECK(p != NULL && p != GARBAGE_PTR);
    return hr == S_OK ? (IConnectionPointContainer *)p : NULL;
}

static IConnectionPointContainer *create_server_limit(uint32_t limit) {
    OpcShutdownOptions o;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.advise_limit = limit;
    return create_server(&o);
}

static IConnectionPoint *find_point(IConnectionPointContainer *cpc) {
    IConnectionPoint *cp = (IConnectionPoint *)GARBAGE_PTR;
    CHECK_HR(cpc->lpVtbl->FindConnectionPoint(cpc, &IID_IOPCShutdown, &cp), S_OK);
    CHECK(cp != NULL && cp != (IConnectionPoint *)GARBAGE_PTR);
    return cp;
}

static HRESULT notify(IConnectionPointContainer *cpc, LPCWSTR reason, ULONG *notified, ULONG *failed) {
    *notified = GARBAGE_U32;
    *failed = GARBAGE_U32;
    return OpcShutdownNotifyEx((IUnknown *)cpc, reason, notified, failed);
}

/* ---------------------------------------------------------------------------------------------- */

static void test_create_errors(void) {
    uint32_t before = OpcObjectCount();
    void *p = GARBAGE_PTR;
    OpcShutdownOptions o;
    Mock outer;
    mock_init(&outer, 0, S_OK);

    CHECK_HR(OpcShutdownCreate(NULL, &IID_IConnectionPointContainer, NULL), E_POINTER);
    CHECK_HR(OpcShutdownCreate(NULL, NULL, &p), E_POINTER);
    CHECK(p == NULL);
    p = GARBAGE_PTR;
    CHECK_HR(OpcShutdownCreate(NULL, &IID_Bogus_, &p), E_NOINTERFACE);
    CHECK(p == NULL);
    p = GARBAGE_PTR;
    CHECK_HR(OpcShutdownCreate(mock_unk(&outer), &IID_IConnectionPointContainer, &p), CLASS_E_NOAGGREGATION);
    CHECK(p == NULL);
    CHECK(outer.add_refs == 0 && outer.releases == 0);

    memset(&o, 0, sizeof o); /* struct_size 0 */
    p = GARBAGE_PTR;
    CHECK_HR(OpcShutdownCreateEx(&o, NULL, &IID_IConnectionPointContainer, &p), E_INVALIDARG);
    CHECK(p == NULL);
    o.struct_size = sizeof o + 4; /* from a newer header than the library knows */
    CHECK_HR(OpcShutdownCreateEx(&o, NULL, &IID_IConnectionPointContainer, &p), E_INVALIDARG);
    CHECK(p == NULL);
    o.struct_size = 6; /* ends inside advise_limit */
    CHECK_HR(OpcShutdownCreateEx(&o, NULL, &IID_IConnectionPointContainer, &p), E_INVALIDARG);
    CHECK(p == NULL);
    o.struct_size = 4; /* an older header without advise_limit: the default applies */
    CHECK_HR(OpcShutdownCreateEx(&o, NULL, &IID_Unknown_, &p), S_OK);
    if (p) ((IUnknown *)p)->lpVtbl->Release((IUnknown *)p);
    CHECK(OpcObjectCount() == before);
}

static void test_find_and_enumerate_points(void) {
    uint32_t before = OpcObjectCount();
    IConnectionPointContainer *cpc = create_server(NULL);
    IConnectionPoint *cp = (IConnectionPoint *)GARBAGE_PTR, *got[3];
    IConnectionPointContainer *back = NULL;
    IEnumConnectionPoints *e = NULL, *clone = NULL;
    IUnknown *u1 = NULL, *u2 = NULL;
    IID iid;
    ULONG fetched = GARBAGE_U32;
    if (!cpc) return;

    CHECK_HR(cpc->lpVtbl->FindConnectionPoint(cpc, &IID_Bogus_, &cp), CONNECT_E_NOCONNECTION_);
    CHECK(cp == NULL);
    cp = (IConnectionPoint *)GARBAGE_PTR;
    CHECK_HR(cpc->lpVtbl->FindConnectionPoint(cpc, NULL, &cp), E_POINTER);
    CHECK(cp == NULL);
    CHECK_HR(cpc->lpVtbl->FindConnectionPoint(cpc, &IID_IOPCShutdown, NULL), E_POINTER);
    CHECK_HR(cpc->lpVtbl->EnumConnectionPoints(cpc, NULL), E_POINTER);

    cp = find_point(cpc);
    CHECK_HR(cp->lpVtbl->GetConnectionInterface(cp, &iid), S_OK);
    CHECK(same_iid(&iid, &IID_IOPCShutdown));
    CHECK_HR(cp->lpVtbl->GetConnectionInterface(cp, NULL), E_POINTER);
    CHECK_HR(cp->lpVtbl->GetConnectionPointContainer(cp, &back), S_OK);
    CHECK(back == cpc);
    back->lpVtbl->Release(back);
    CHECK_HR(cp->lpVtbl->GetConnectionPointContainer(cp, NULL), E_POINTER);

    /* The connection point is an object of its own: a different identity, no container interface. */
    CHECK_HR(cp->lpVtbl->QueryInterface(cp, &IID_Unknown_, (void **)&u1), S_OK);
    CHECK_HR(cpc->lpVtbl->QueryInterface(cpc, &IID_Unknown_, (void **)&u2), S_OK);
    CHECK(u1 != NULL && u1 != u2);
    u1->lpVtbl->Release(u1);
    u2->lpVtbl->Release(u2);
    u1 = (IUnknown *)GARBAGE_PTR;
    CHECK_HR(cp->lpVtbl->QueryInterface(cp, &IID_IConnectionPointContainer, (void **)&u1), E_NOINTERFACE);
    CHECK(u1 == NULL);

    CHECK_HR(cpc->lpVtbl->EnumConnectionPoints(cpc, &e), S_OK);
    if (e) {
        CHECK_HR(e->lpVtbl->Next(e, 3, got, &fetched), S_FALSE);
        CHECK(fetched == 1);
        CHECK(got[0] == cp); /* the same connection point FindConnectionPoint returns */
        if (fetched == 1) got[0]->lpVtbl->Release(got[0]);
        fetched = GARBAGE_U32;
        CHECK_HR(e->lpVtbl->Next(e, 1, got, &fetched), S_FALSE);
        CHECK(fetched == 0);
        CHECK_HR(e->lpVtbl->Next(e, 2, got, NULL), E_POINTER); /* pcFetched may be NULL only for one */
        CHECK_HR(e->lpVtbl->Next(e, 1, NULL, &fetched), E_POINTER);
        CHECK_HR(e->lpVtbl->Reset(e), S_OK);
        CHECK_HR(e->lpVtbl->Skip(e, 1), S_OK);
        CHECK_HR(e->lpVtbl->Skip(e, 1), S_FALSE);
        CHECK_HR(e->lpVtbl->Reset(e), S_OK);
        CHECK_HR(e->lpVtbl->Skip(e, 0xFFFFFFFFu), S_FALSE);
        CHECK_HR(e->lpVtbl->Reset(e), S_OK);
        /* A huge count with a small array: only the elements that exist are written. */
        got[1] = (IConnectionPoint *)GARBAGE_PTR;
        CHECK_HR(e->lpVtbl->Next(e, 0xFFFFFFFFu, got, &fetched), S_FALSE);
        CHECK(fetched == 1 && got[1] == (IConnectionPoint *)GARBAGE_PTR);
        if (fetched == 1) got[0]->lpVtbl->Release(got[0]);
        CHECK_HR(e->lpVtbl->Next(e, 0, NULL, NULL), S_OK); /* nothing asked, nothing done */
        CHECK_HR(e->lpVtbl->Reset(e), S_OK);
        CHECK_HR(e->lpVtbl->Clone(e, NULL), E_POINTER);
        CHECK_HR(e->lpVtbl->Clone(e, &clone), S_OK);
        CHECK(e->lpVtbl->Release(e) == 0);
        if (clone) {
            CHECK_HR(clone->lpVtbl->Next(clone, 1, got, NULL), S_OK);
            got[0]->lpVtbl->Release(got[0]);
            CHECK_HR(clone->lpVtbl->Next(clone, 1, got, NULL), S_FALSE);
            CHECK(clone->lpVtbl->Release(clone) == 0);
        }
    }
    cp->lpVtbl->Release(cp);
    CHECK(cpc->lpVtbl->Release(cpc) == 0);
    CHECK(OpcObjectCount() == before);
}

static void test_advise_return_codes(void) {
    uint32_t before = OpcObjectCount();
    IConnectionPointContainer *cpc = create_server(NULL);
    IConnectionPoint *cp;
    Mock plain, sink, other;
    DWORD cookie = GARBAGE_U32, cookie2 = GARBAGE_U32;
    if (!cpc) return;
    cp = find_point(cpc);
    mock_init(&plain, 0, S_OK);
    mock_init(&sink, 1, S_OK);
    mock_init(&other, 1, S_OK);

    CHECK_HR(cp->lpVtbl->Advise(cp, NULL, &cookie), E_POINTER);
    CHECK(cookie == 0);
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&sink), NULL), E_POINTER);
    CHECK(sink.add_refs == 0);

    cookie = GARBAGE_U32;
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&plain), &cookie), CONNECT_E_CANNOTCONNECT_);
    CHECK(cookie == 0);
    CHECK(plain.refs == 1 && plain.add_refs == 0); /* refused sinks keep no reference */

    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&sink), &cookie), S_OK);
    CHECK(cookie != 0 && cookie != GARBAGE_U32);
    CHECK(sink.refs == 2); /* exactly one reference, held by the connection */

    /* The default limit is one sink. */
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&other), &cookie2), CONNECT_E_ADVISELIMIT_);
    CHECK(cookie2 == 0);
    CHECK(other.refs == 1 && other.add_refs == other.releases);

    CHECK_HR(cp->lpVtbl->Unadvise(cp, 0), CONNECT_E_NOCONNECTION_);
    CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie + 1), CONNECT_E_NOCONNECTION_);
    CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie), S_OK);
    CHECK(sink.refs == 1 && sink.add_refs == sink.releases);
    CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie), CONNECT_E_NOCONNECTION_);

    /* Cookies are never reused, not even after Unadvise. */
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&other), &cookie2), S_OK);
    CHECK(cookie2 != 0 && cookie2 != cookie);
    CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie2), S_OK);

    cp->lpVtbl->Release(cp);
    CHECK(cpc->lpVtbl->Release(cpc) == 0);
    CHECK(other.refs == 1 && other.add_refs == other.releases);
    CHECK(OpcObjectCount() == before);
}

static void test_advise_limit_raised(void) {
    uint32_t before = OpcObjectCount();
    IConnectionPointContainer *cpc = create_server_limit(3);
    IConnectionPoint *cp;
    Mock s[4];
    DWORD cookies[4];
    int i;
    if (!cpc) return;
    cp = find_point(cpc);
    for (i = 0; i < 4; i++) mock_init(&s[i], 1, S_OK);
    for (i = 0; i < 3; i++) CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&s[i]), &cookies[i]), S_OK);
    CHECK(cookies[0] != cookies[1] && cookies[1] != cookies[2] && cookies[0] != cookies[2]);
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&s[3]), &cookies[3]), CONNECT_E_ADVISELIMIT_);
    CHECK_HR(cp->lpVtbl->Unadvise(cp, cookies[1]), S_OK);
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&s[3]), &cookies[3]), S_OK);
    CHECK(cookies[3] != cookies[0] && cookies[3] != cookies[1] && cookies[3] != cookies[2]);
    cp->lpVtbl->Release(cp);
    /* The server dies with advised sinks and releases every one of them. */
    CHECK(cpc->lpVtbl->Release(cpc) == 0);
    for (i = 0; i < 4; i++) CHECK(s[i].refs == 1 && s[i].add_refs == s[i].releases);
    CHECK(OpcObjectCount() == before);
}

static void test_notify(void) {
    uint32_t before = OpcObjectCount();
    IConnectionPointContainer *cpc = create_server_limit(3);
    IConnectionPoint *cp;
    Mock good1, bad, good2, unrelated;
    DWORD c1, c2, c3;
    ULONG n, f;
    if (!cpc) return;
    cp = find_point(cpc);
    mock_init(&good1, 1, S_OK);
    mock_init(&bad, 1, E_FAIL);
    mock_init(&good2, 1, S_OK);
    mock_init(&unrelated, 1, S_OK);

    CHECK_HR(notify(cpc, W("nobody listens"), &n, &f), S_OK);
    CHECK(n == 0 && f == 0);

    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&good1), &c1), S_OK);
    CHECK_HR(notify(cpc, W("Server is shutting down"), &n, &f), S_OK);
    CHECK(n == 1 && f == 0);
    CHECK(wstr_is(good1.reason, "Server is shutting down"));

    CHECK_HR(notify(cpc, NULL, &n, &f), S_OK); /* NULL becomes a NUL string */
    CHECK(good1.calls == 2 && !good1.null_reason && good1.reason[0] == 0);

    /* A failing sink does not stop the others. */
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&bad), &c2), S_OK);
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&good2), &c3), S_OK);
    CHECK_HR(notify(cpc, W("again"), &n, &f), S_FALSE);
    CHECK(n == 2 && f == 1);
    CHECK(good1.calls == 3 && bad.calls == 1 && good2.calls == 1);
    CHECK_HR(OpcShutdownNotify((IUnknown *)cpc, W("plain")), S_FALSE);
    CHECK_HR(OpcShutdownNotifyEx((IUnknown *)cpc, NULL, NULL, NULL), S_FALSE);
    CHECK(good2.calls == 3);

    /* Only shutdown objects of this library can be notified. */
    n = f = GARBAGE_U32;
    CHECK_HR(OpcShutdownNotifyEx(NULL, NULL, &n, &f), E_INVALIDARG);
    CHECK(n == 0 && f == 0);
    CHECK_HR(OpcShutdownNotify(mock_unk(&unrelated), NULL), E_INVALIDARG);
    CHECK_HR(OpcShutdownNotify((IUnknown *)cp, NULL), E_INVALIDARG); /* the point is not the container */
    CHECK(unrelated.refs == 1 && unrelated.calls == 0);

    cp->lpVtbl->Release(cp);
    CHECK(cpc->lpVtbl->Release(cpc) == 0);
    CHECK(good1.refs == 1 && bad.refs == 1 && good2.refs == 1);
    CHECK(good1.add_refs == good1.releases && bad.add_refs == bad.releases && good2.add_refs == good2.releases);
    CHECK(OpcObjectCount() == before);
}

/* Hooks run inside ShutdownRequest: each would deadlock if the server held its lock while calling. */
static void hook_unadvise_self(Mock *m) {
    m->hook_hr = OpcShutdownUnadvise((IUnknown *)m->hook_arg, m->hook_cookie);
}

static void hook_unadvise_other(Mock *m) {
    IConnectionPoint *cp = (IConnectionPoint *)m->hook_arg;
    m->hook_hr = cp->lpVtbl->Unadvise(cp, m->hook_cookie);
}

static void hook_release_server(Mock *m) {
    IUnknown *server = (IUnknown *)m->hook_arg;
    m->hook_hr = server->lpVtbl->Release(server) == 0 ? S_OK : S_FALSE;
}

static void hook_call_back_in(Mock *m) {
    IConnectionPointContainer *cpc = (IConnectionPointContainer *)m->hook_arg;
    IConnectionPoint *cp = NULL;
    IEnumConnections *e = NULL;
    m->hook_hr = cpc->lpVtbl->FindConnectionPoint(cpc, &IID_IOPCShutdown, &cp);
    if (cp) {
        if (cp->lpVtbl->EnumConnections(cp, &e) == S_OK) e->lpVtbl->Release(e);
        cp->lpVtbl->Release(cp);
    }
}

static void test_reentrant_sinks(void) {
    uint32_t before = OpcObjectCount();
    IConnectionPointContainer *cpc = create_server_limit(2);
    IConnectionPoint *cp;
    Mock a, b;
    DWORD ca, cb;
    ULONG n, f;
    if (!cpc) return;
    cp = find_point(cpc);

    /* A sink that unadvises itself. */
    mock_init(&a, 1, S_OK);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)cpc, mock_unk(&a), &ca), S_OK);
    a.hook = hook_unadvise_self;
    a.hook_arg = cpc;
    a.hook_cookie = ca;
    a.hook_hr = E_UNEXPECTED;
    CHECK_HR(notify(cpc, W("bye"), &n, &f), S_OK);
    CHECK(n == 1 && f == 0);
    CHECK_HR(a.hook_hr, S_OK);
    CHECK(a.refs == 1 && a.add_refs == a.releases); /* unadvised: the server let go of it */
    CHECK_HR(notify(cpc, W("bye"), &n, &f), S_OK);
    CHECK(n == 0 && a.calls == 1);

    /* A sink that unadvises another one before its turn: that one is not called any more. */
    mock_init(&a, 1, S_OK);
    mock_init(&b, 1, S_OK);
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&a), &ca), S_OK);
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&b), &cb), S_OK);
    a.hook = hook_unadvise_other;
    a.hook_arg = cp;
    a.hook_cookie = cb;
    CHECK_HR(notify(cpc, NULL, &n, &f), S_OK);
    CHECK_HR(a.hook_hr, S_OK);
    CHECK(n == 1 && f == 0 && a.calls == 1 && b.calls == 0);
    CHECK(b.refs == 1);

    /* A sink that calls back into the server. */
    a.hook = hook_call_back_in;
    a.hook_arg = cpc;
    a.hook_hr = E_UNEXPECTED;
    CHECK_HR(notify(cpc, NULL, &n, &f), S_OK);
    CHECK_HR(a.hook_hr, S_OK);
    CHECK_HR(cp->lpVtbl->Unadvise(cp, ca), S_OK);

    cp->lpVtbl->Release(cp);

    /* A sink that releases the last reference to the server. */
    mock_init(&a, 1, S_OK);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)cpc, mock_unk(&a), &ca), S_OK);
    a.hook = hook_release_server;
    a.hook_arg = cpc; /* the sink now owns the test's reference */
    a.hook_hr = E_UNEXPECTED;
    CHECK_HR(OpcShutdownNotifyEx((IUnknown *)cpc, W("last"), &n, &f), S_OK);
    CHECK(n == 1 && f == 0);
    CHECK_HR(a.hook_hr, S_FALSE); /* the notification itself still held a reference */
    CHECK(a.refs == 1 && a.add_refs == a.releases); /* then the server died and released the sink */
    CHECK(OpcObjectCount() == before);
}

static void test_enumerate_connections(void) {
    uint32_t before = OpcObjectCount();
    IConnectionPointContainer *cpc = create_server_limit(2);
    IConnectionPoint *cp;
    IEnumConnections *e = NULL, *clone = NULL;
    CONNECTDATA cd[4];
    Mock a, b;
    DWORD ca, cb;
    ULONG fetched = GARBAGE_U32;
    if (!cpc) return;
    cp = find_point(cpc);
    mock_init(&a, 1, S_OK);
    mock_init(&b, 1, S_OK);

    CHECK_HR(cp->lpVtbl->EnumConnections(cp, NULL), E_POINTER);
    CHECK_HR(cp->lpVtbl->EnumConnections(cp, &e), S_OK); /* none yet */
    if (e) {
        CHECK_HR(e->lpVtbl->Next(e, 1, cd, &fetched), S_FALSE);
        CHECK(fetched == 0);
        CHECK(e->lpVtbl->Release(e) == 0);
        e = NULL;
    }

    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&a), &ca), S_OK);
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&b), &cb), S_OK);
    CHECK_HR(cp->lpVtbl->EnumConnections(cp, &e), S_OK);
    if (!e) return;
    CHECK(a.refs == 3 && b.refs == 3); /* the snapshot holds one reference to each sink */
    CHECK_HR(cp->lpVtbl->Unadvise(cp, cb), S_OK); /* later changes do not affect the snapshot */
    CHECK(b.refs == 2);

    memset(cd, 0, sizeof cd);
    CHECK_HR(e->lpVtbl->Next(e, 4, cd, &fetched), S_FALSE);
    CHECK(fetched == 2);
    CHECK(cd[0].dwCookie == ca && cd[1].dwCookie == cb);
    CHECK(cd[0].pUnk == mock_unk(&a) && cd[1].pUnk == mock_unk(&b));
    CHECK(b.refs == 3); /* handed out AddRef'd: the caller releases */
    if (fetched == 2) {
        cd[0].pUnk->lpVtbl->Release(cd[0].pUnk);
        cd[1].pUnk->lpVtbl->Release(cd[1].pUnk);
    }
    CHECK_HR(e->lpVtbl->Reset(e), S_OK);
    CHECK_HR(e->lpVtbl->Skip(e, 1), S_OK);
    CHECK_HR(e->lpVtbl->Clone(e, &clone), S_OK);
    CHECK_HR(e->lpVtbl->Skip(e, 5), S_FALSE);
    CHECK_HR(e->lpVtbl->Next(e, 1, cd, NULL), S_FALSE);
    CHECK(e->lpVtbl->Release(e) == 0);
    CHECK(b.refs == 2); /* the clone still shares the snapshot */
    if (clone) {
        CHECK_HR(clone->lpVtbl->Next(clone, 1, cd, NULL), S_OK); /* the clone kept the position */
        CHECK(cd[0].dwCookie == cb);
        cd[0].pUnk->lpVtbl->Release(cd[0].pUnk);
        CHECK(clone->lpVtbl->Release(clone) == 0);
    }
    CHECK(b.refs == 1 && b.add_refs == b.releases);
    CHECK(a.refs == 2);
    cp->lpVtbl->Release(cp);
    CHECK(cpc->lpVtbl->Release(cpc) == 0);
    CHECK(a.refs == 1 && a.add_refs == a.releases);
    CHECK(OpcObjectCount() == before);
}

static void test_lifetimes(void) {
    uint32_t before = OpcObjectCount();
    IConnectionPointContainer *cpc = create_server(NULL), *back = NULL;
    IConnectionPoint *cp;
    IEnumConnectionPoints *e = NULL;
    Mock s;
    DWORD cookie;
    if (!cpc) return;
    mock_init(&s, 1, S_OK);
    cp = find_point(cpc);
    CHECK_HR(cp->lpVtbl->Advise(cp, mock_unk(&s), &cookie), S_OK);
    CHECK_HR(cpc->lpVtbl->EnumConnectionPoints(cpc, &e), S_OK);
    CHECK(OpcObjectCount() == before + 2); /* the server (with its point) and the enumerator */

    /* The connection point keeps the server alive... */
    CHECK(cpc->lpVtbl->Release(cpc) > 0);
    CHECK(s.refs == 2);
    CHECK_HR(cp->lpVtbl->GetConnectionPointContainer(cp, &back), S_OK);
    CHECK_HR(OpcShutdownNotify((IUnknown *)back, NULL), S_OK);
    CHECK(s.calls == 1);
    back->lpVtbl->Release(back);
    /* ...and so does the enumerator, but nothing keeps it alive beyond the last reference. */
    cp->lpVtbl->Release(cp);
    CHECK(OpcObjectCount() == before + 2);
    CHECK(s.refs == 2);
    if (e) CHECK(e->lpVtbl->Release(e) == 0);
    CHECK(OpcObjectCount() == before);
    CHECK(s.refs == 1 && s.add_refs == s.releases);
}


static void test_aggregation(void) {
    uint32_t before = OpcObjectCount();
    AggregatingServer s;
    Mock sink;
    IConnectionPointContainer *cpc = NULL, *back = NULL;
    IConnectionPoint *cp = NULL;
    IUnknown *identity = NULL;
    DWORD cookie = 0;
    ULONG n, f;
    aggregating_server_init(&s, &IID_IConnectionPointContainer);
    mock_init(&sink, 1, S_OK);

    CHECK_HR(OpcShutdownCreate(&s.unk, &IID_Unknown_, (void **)&s.inner), S_OK);
    if (!s.inner) return;
    CHECK(s.add_refs == 0 && s.releases == 0);
    CHECK(OpcObjectCount() == before + 1);

    CHECK_HR(aggregating_qi(&s.unk, &IID_IConnectionPointContainer, (void **)&cpc), S_OK);
    if (!cpc) return;
    CHECK(s.refs == 2); /* the container's AddRef went to the outer object */
    CHECK_HR(cpc->lpVtbl->QueryInterface(cpc, &IID_Unknown_, (void **)&identity), S_OK);
    CHECK(identity == &s.unk); /* identity is the outer object */
    identity->lpVtbl->Release(identity);

    cp = find_point(cpc);
    CHECK(s.refs == 3); /* the point counts on the outer object too */
    CHECK_HR(cp->lpVtbl->GetConnectionPointContainer(cp, &back), S_OK);
    CHECK(back == cpc);
    CHECK(s.refs == 4);
    back->lpVtbl->Release(back);

    /* The helpers and Notify find the shutdown object through the outer object. */
    CHECK_HR(OpcShutdownAdvise(&s.unk, mock_unk(&sink), &cookie), S_OK);
    CHECK_HR(OpcShutdownNotifyEx(&s.unk, W("aggregated"), &n, &f), S_OK);
    CHECK(n == 1 && f == 0 && wstr_is(sink.reason, "aggregated"));
    CHECK_HR(OpcShutdownUnadvise(&s.unk, cookie), S_OK);
    CHECK(sink.refs == 1);

    cp->lpVtbl->Release(cp);
    cpc->lpVtbl->Release(cpc);
    CHECK(s.refs == 1);
    CHECK(aggregating_release(&s.unk) == 0);
    CHECK(s.destroyed);
    CHECK(s.add_refs == s.releases - 1); /* balanced: the initial reference was the last Release */
    CHECK(sink.add_refs == sink.releases);
    CHECK(OpcObjectCount() == before);
}

/* ---- A server object that forwards to the shutdown object instead of aggregating it, as a server
 * whose objects cannot be aggregated (windows-rs) does: its own IUnknown and IConnectionPointContainer,
 * passing FindConnectionPoint and EnumConnectionPoints on to the shutdown object it keeps, and named
 * as the connection point's container (OpcShutdownOptions::container). Counts its references; lets
 * go of the shutdown object when the last one goes. ---- */
typedef struct ForwardingServer {
    IUnknown unk; /* the identity */
    IConnectionPointContainer cpc;
    ULONG refs;
    int destroyed;
    IConnectionPointContainer *shutdown; /* the shutdown object's own container: counts on it only */
} ForwardingServer;

#define FORWARDING_OF_CPC(p) ((ForwardingServer *)((char *)(p) - offsetof(ForwardingServer, cpc)))

static HRESULT STDMETHODCALLTYPE fwd_qi(IUnknown *This, REFIID riid, void **ppv) {
    ForwardingServer *s = (ForwardingServer *)This;
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (same_iid(riid, &IID_Unknown_)) *ppv = &s->unk;
    else if (same_iid(riid, &IID_IConnectionPointContainer)) *ppv = &s->cpc;
    else return E_NOINTERFACE;
    s->refs++;
    return S_OK;
}
static ULONG STDMETHODCALLTYPE fwd_add_ref(IUnknown *This) { return ++((ForwardingServer *)This)->refs; }
static ULONG STDMETHODCALLTYPE fwd_release(IUnknown *This) {
    ForwardingServer *s = (ForwardingServer *)This;
    CHECK(s->refs > 0);
    if (--s->refs == 0) {
        IConnectionPointContainer *shutdown = s->shutdown;
        s->destroyed = 1;
        s->shutdown = NULL;
        if (shutdown) shutdown->lpVtbl->Release(shutdown);
    }
    return s->refs;
}
static HRESULT STDMETHODCALLTYPE fwd_cpc_qi(IConnectionPointContainer *This, REFIID riid, void **ppv) {
    return fwd_qi(&FORWARDING_OF_CPC(This)->unk, riid, ppv);
}
static ULONG STDMETHODCALLTYPE fwd_cpc_add_ref(IConnectionPointContainer *This) {
    return fwd_add_ref(&FORWARDING_OF_CPC(This)->unk);
}
static ULONG STDMETHODCALLTYPE fwd_cpc_release(IConnectionPointContainer *This) {
    return fwd_release(&FORWARDING_OF_CPC(This)->unk);
}
static HRESULT STDMETHODCALLTYPE fwd_enum_points(IConnectionPointContainer *This, IEnumConnectionPoints **ppEnum) {
    IConnectionPointContainer *shutdown = FORWARDING_OF_CPC(This)->shutdown;
    return shutdown->lpVtbl->EnumConnectionPoints(shutdown, ppEnum);
}
static HRESULT STDMETHODCALLTYPE fwd_find_point(IConnectionPointContainer *This, REFIID riid, IConnectionPoint **ppCP) {
    IConnectionPointContainer *shutdown = FORWARDING_OF_CPC(This)->shutdown;
    return shutdown->lpVtbl->FindConnectionPoint(shutdown, riid, ppCP);
}
static IUnknownVtbl fwd_vtbl = {fwd_qi, fwd_add_ref, fwd_release};
static IConnectionPointContainerVtbl fwd_cpc_vtbl = {fwd_cpc_qi, fwd_cpc_add_ref, fwd_cpc_release, fwd_enum_points,
                                                     fwd_find_point};

/* The server with one reference (the creator's) and its shutdown object, naming the server. */
static void forwarding_server_init(ForwardingServer *s) {
    OpcShutdownOptions o;
    memset(s, 0, sizeof *s);
    s->unk.lpVtbl = &fwd_vtbl;
    s->cpc.lpVtbl = &fwd_cpc_vtbl;
    s->refs = 1;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.container = &s->unk;
    CHECK_HR(OpcShutdownCreateEx(&o, NULL, &IID_IConnectionPointContainer, (void **)&s->shutdown), S_OK);
}

/* The identity of `p` (QueryInterface(IID_IUnknown), released at once). */
static IUnknown *identity_of(IUnknown *p) {
    IUnknown *id = NULL;
    CHECK_HR(p->lpVtbl->QueryInterface(p, &IID_Unknown_, (void **)&id), S_OK);
    if (id) id->lpVtbl->Release(id);
    return id;
}

static void test_forwarding_server(void) {
    uint32_t before = OpcObjectCount();
    ForwardingServer s;
    Mock sink;
    IConnectionPointContainer *cpc = NULL, *back = (IConnectionPointContainer *)GARBAGE_PTR;
    IConnectionPoint *cp = NULL, *got[2] = {NULL, NULL};
    IEnumConnectionPoints *e = NULL;
    IUnknown *inner = (IUnknown *)GARBAGE_PTR;
    OpcShutdownOptions o;
    AggregatingServer outer;
    DWORD cookie = 0;
    ULONG n, f, fetched = 0;
    mock_init(&sink, 1, S_OK);

    forwarding_server_init(&s);
    if (!s.shutdown) return;
    CHECK(s.refs == 1); /* the shutdown object holds no reference to the server: no cycle */
    CHECK(OpcObjectCount() == before + 1);
    CHECK_HR(fwd_qi(&s.unk, &IID_IConnectionPointContainer, (void **)&cpc), S_OK);
    CHECK(cpc == &s.cpc);
    cp = find_point(cpc); /* through the server: forwarded */
    CHECK(s.refs == 3);   /* the connection point counts on the server */

    /* The point names the server as its container: the server's own IConnectionPointContainer, with
       the server's COM identity. */
    CHECK_HR(cp->lpVtbl->GetConnectionPointContainer(cp, &back), S_OK);
    CHECK(back == &s.cpc);
    if (back == &s.cpc) {
        CHECK(identity_of((IUnknown *)back) == identity_of((IUnknown *)cpc));
        CHECK(identity_of((IUnknown *)back) == &s.unk);
        back->lpVtbl->Release(back);
    }
    CHECK(s.refs == 3);

    /* Enumerated connection points count on the server too. */
    CHECK_HR(cpc->lpVtbl->EnumConnectionPoints(cpc, &e), S_OK);
    if (e) {
        CHECK_HR(e->lpVtbl->Next(e, 2, got, &fetched), S_FALSE);
        CHECK(fetched == 1 && got[0] == cp);
        CHECK(s.refs == 5); /* the enumerator's point and the one it handed out */
        if (got[0]) got[0]->lpVtbl->Release(got[0]);
        e->lpVtbl->Release(e);
    }
    CHECK(s.refs == 3);

    /* The helpers and the notification take the server object. */
    CHECK_HR(OpcShutdownAdvise(&s.unk, mock_unk(&sink), &cookie), S_OK);
    CHECK_HR(OpcShutdownNotifyEx(&s.unk, W("forwarded"), &n, &f), S_OK);
    CHECK(n == 1 && f == 0 && sink.calls == 1 && wstr_is(sink.reason, "forwarded"));

    /* The client lets go of everything but the connection point: the server stays, and is still
       its container. */
    cpc->lpVtbl->Release(cpc);
    CHECK(fwd_release(&s.unk) == 1);
    CHECK(!s.destroyed);
    back = NULL;
    CHECK_HR(cp->lpVtbl->GetConnectionPointContainer(cp, &back), S_OK);
    CHECK(back == &s.cpc);
    if (back) back->lpVtbl->Release(back);
    CHECK(sink.refs == 2); /* still advised */

    /* The point's last reference is the server's: it goes, and the shutdown object with it. */
    CHECK(cp->lpVtbl->Release(cp) == 0);
    CHECK(s.destroyed);
    CHECK(sink.refs == 1 && sink.add_refs == sink.releases);
    CHECK(OpcObjectCount() == before);

    /* An aggregated shutdown object's container is its outer object: naming another is refused. */
    aggregating_server_init(&outer, &IID_IConnectionPointContainer);
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.container = mock_unk(&sink);
    CHECK_HR(OpcShutdownCreateEx(&o, &outer.unk, &IID_Unknown_, (void **)&inner), E_INVALIDARG);
    CHECK(inner == NULL);
    CHECK(outer.refs == 1 && sink.refs == 1);
    /* The sizes of the struct's versions: 4, 8 (no container) and sizeof; none between. */
    CHECK(sizeof o == offsetof(OpcShutdownOptions, container) + sizeof(void *));
    o.struct_size = (uint32_t)offsetof(OpcShutdownOptions, container) + 4;
    if (sizeof(void *) == 8) {
        CHECK_HR(OpcShutdownCreateEx(&o, NULL, &IID_Unknown_, (void **)&inner), E_INVALIDARG);
        CHECK(inner == NULL);
    }
    o.struct_size = (uint32_t)offsetof(OpcShutdownOptions, container);
    CHECK_HR(OpcShutdownCreateEx(&o, NULL, &IID_Unknown_, (void **)&inner), S_OK);
    if (inner) inner->lpVtbl->Release(inner);
    CHECK(sink.refs == 1);
    CHECK(OpcObjectCount() == before);
}

/* ---- The client side. ---- */
typedef struct Received {
    int calls;
    WCHAR reason[64];
    IUnknown *server; /* when set, the callback unadvises itself from it */
    DWORD cookie;
    HRESULT unadvise_hr;
#ifdef _WIN32
    DWORD thread;
#endif
} Received;

static void on_shutdown(void *context, LPCWSTR reason) {
    Received *r = (Received *)context;
    size_t i = 0;
    r->calls++;
#ifdef _WIN32
    r->thread = GetCurrentThreadId();
#endif
    CHECK(reason != NULL);
    if (reason)
        for (; reason[i] && i < 63; i++) r->reason[i] = reason[i];
    r->reason[i] = 0;
    if (r->server) r->unadvise_hr = OpcShutdownUnadvise(r->server, r->cookie);
}

static void test_client_sink(void) {
    uint32_t before = OpcObjectCount();
    Received r;
    void *p = GARBAGE_PTR;
    IOPCShutdown *sink;
    IUnknown *unk = NULL;
    memset(&r, 0, sizeof r);

    CHECK_HR(OpcShutdownSinkCreate(NULL, &r, &IID_IOPCShutdown, &p), E_POINTER);
    CHECK(p == NULL);
    p = GARBAGE_PTR;
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown, &r, &IID_Bogus_, &p), E_NOINTERFACE);
    CHECK(p == NULL);
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown, &r, NULL, &p), E_POINTER);
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown, &r, &IID_IOPCShutdown, NULL), E_POINTER);
    CHECK(OpcObjectCount() == before);

    CHECK_HR(OpcShutdownSinkCreate(on_shutdown, &r, &IID_IOPCShutdown, &p), S_OK);
    sink = (IOPCShutdown *)p;
    if (!sink) return;
    CHECK_HR(sink->lpVtbl->ShutdownRequest(sink, W("maintenance window")), S_OK);
    CHECK(r.calls == 1 && wstr_is(r.reason, "maintenance window"));
    CHECK_HR(sink->lpVtbl->ShutdownRequest(sink, NULL), S_OK);
    CHECK(r.calls == 2 && r.reason[0] == 0);
    CHECK_HR(sink->lpVtbl->QueryInterface(sink, &IID_Unknown_, (void **)&unk), S_OK);
    CHECK(unk != NULL && unk != (IUnknown *)sink);
    CHECK(unk->lpVtbl->Release(unk) == 1);
    CHECK(sink->lpVtbl->Release(sink) == 0);
    CHECK(OpcObjectCount() == before);
}

static void test_client_and_server(void) {
    uint32_t before = OpcObjectCount();
    IConnectionPointContainer *cpc = create_server(NULL);
    Received r;
    IUnknown *sink = NULL;
    Mock not_a_server, plain;
    DWORD cookie = GARBAGE_U32;
    ULONG n, f;
    if (!cpc) return;
    memset(&r, 0, sizeof r);
    mock_init(&not_a_server, 1, S_OK);
    mock_init(&plain, 0, S_OK);
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown, &r, &IID_Unknown_, (void **)&sink), S_OK);
    if (!sink) return;

    /* Errors of the helpers. */
    CHECK_HR(OpcShutdownAdvise(mock_unk(&not_a_server), sink, &cookie), E_NOINTERFACE);
    CHECK(cookie == 0);
    CHECK_HR(OpcShutdownUnadvise(mock_unk(&not_a_server), 1), E_NOINTERFACE);
    CHECK(not_a_server.refs == 1);
    cookie = GARBAGE_U32;
    CHECK_HR(OpcShutdownAdvise(NULL, sink, &cookie), E_INVALIDARG);
    CHECK(cookie == 0);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)cpc, NULL, &cookie), E_INVALIDARG);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)cpc, sink, NULL), E_INVALIDARG);
    CHECK_HR(OpcShutdownUnadvise(NULL, 1), E_INVALIDARG);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)cpc, mock_unk(&plain), &cookie), CONNECT_E_CANNOTCONNECT_);
    CHECK_HR(OpcShutdownUnadvise((IUnknown *)cpc, 4242), CONNECT_E_NOCONNECTION_);

    /* The library on both sides; the client lets go of its sink reference after advising. */
    CHECK_HR(OpcShutdownAdvise((IUnknown *)cpc, sink, &cookie), S_OK);
    CHECK(cookie != 0);
    CHECK(sink->lpVtbl->Release(sink) == 1); /* the connection's reference */
    CHECK(OpcObjectCount() == before + 2);
    r.server = (IUnknown *)cpc; /* the callback unadvises itself, as the specification asks */
    r.cookie = cookie;
    r.unadvise_hr = E_UNEXPECTED;
    CHECK_HR(notify(cpc, W("Going down for maintenance"), &n, &f), S_OK);
    CHECK(n == 1 && f == 0);
    CHECK(r.calls == 1 && wstr_is(r.reason, "Going down for maintenance"));
    CHECK_HR(r.unadvise_hr, S_OK);
    CHECK(OpcObjectCount() == before + 1); /* the sink died with the server's reference */
    CHECK(cpc->lpVtbl->Release(cpc) == 0);
    CHECK(OpcObjectCount() == before);
}

#ifdef _WIN32
/* ---- A client in another apartment: a thread with its own single-threaded apartment and message
 * loop advises sinks on a server object of the main (multithreaded) apartment. ---- */
#define WM_APP_NOTIFY (WM_APP + 1)

typedef struct Apartment {
    IConnectionPointContainer *cpc;
    HANDLE ready;
    DWORD thread;
    Mock bound;   /* an apartment-bound sink (no marshaler, no proxy/stub for IOPCShutdown) */
    Mock agile;   /* a sink aggregating the free-threaded marshaler */
    DWORD bound_cookie, agile_cookie;
    HRESULT init_hr, advise_bound_hr, advise_agile_hr, ftm_hr, notify_here_hr;
    ULONG here_notified, here_failed;
    HRESULT unadvise_bound_hr, unadvise_agile_hr;
} Apartment;

static unsigned __stdcall apartment_thread(void *arg) {
    Apartment *a = (Apartment *)arg;
    MSG msg;
    a->init_hr = CoInitializeEx(NULL, COINIT_APARTMENTTHREADED);
    a->thread = GetCurrentThreadId();
    PeekMessageW(&msg, NULL, 0, 0, PM_NOREMOVE); /* create the message queue */
    mock_init(&a->bound, 1, S_OK);
    mock_init(&a->agile, 1, S_OK);
    a->ftm_hr = CoCreateFreeThreadedMarshaler(mock_unk(&a->agile), &a->agile.marshaler);
    a->advise_bound_hr = OpcShutdownAdvise((IUnknown *)a->cpc, mock_unk(&a->bound), &a->bound_cookie);
    a->advise_agile_hr = OpcShutdownAdvise((IUnknown *)a->cpc, mock_unk(&a->agile), &a->agile_cookie);
    SetEvent(a->ready);
    while (GetMessageW(&msg, NULL, 0, 0) > 0) {
        if (msg.message == WM_APP_NOTIFY) {
            /* Notify from this apartment: every sink is reachable here. */
            a->notify_here_hr = OpcShutdownNotifyEx((IUnknown *)a->cpc, W("from the STA"), &a->here_notified,
                                                    &a->here_failed);
            SetEvent(a->ready);
            continue;
        }
        TranslateMessage(&msg);
        DispatchMessageW(&msg);
    }
    a->unadvise_bound_hr = OpcShutdownUnadvise((IUnknown *)a->cpc, a->bound_cookie);
    a->unadvise_agile_hr = OpcShutdownUnadvise((IUnknown *)a->cpc, a->agile_cookie);
    if (a->agile.marshaler) {
        a->agile.marshaler->lpVtbl->Release(a->agile.marshaler);
        a->agile.marshaler = NULL;
    }
    CoUninitialize();
    return 0;
}

static void test_other_apartment(void) {
    uint32_t before = OpcObjectCount();
    Apartment a;
    HANDLE thread;
    ULONG n = 0, f = 0;
    HRESULT hr;
    memset(&a, 0, sizeof a);
    a.cpc = create_server_limit(2);
    if (!a.cpc) return;
    a.ready = CreateEventW(NULL, FALSE, FALSE, NULL);
    thread = (HANDLE)_beginthreadex(NULL, 0, apartment_thread, &a, 0, NULL);
    CHECK(thread != NULL);
    if (!thread) return;
    CHECK(WaitForSingleObject(a.ready, 10000) == WAIT_OBJECT_0);
    CHECK_HR(a.init_hr, S_OK);
    CHECK_HR(a.ftm_hr, S_OK);
    CHECK_HR(a.advise_bound_hr, S_OK);
    CHECK_HR(a.advise_agile_hr, S_OK);
    /* The agile sink went through the Global Interface Table (which asked it for IMarshal). */
    CHECK(a.agile.marshal_queries > 0);

    /* Notify from the main thread (another apartment). The agile sink is called here; the
       apartment-bound one cannot be reached without a proxy/stub, so it is reported as failed
       instead of being called on the wrong thread. */
    hr = OpcShutdownNotifyEx((IUnknown *)a.cpc, W("from the MTA"), &n, &f);
    CHECK_HR(hr, S_FALSE);
    CHECK(n == 1 && f == 1);
    CHECK(a.agile.calls == 1 && wstr_is(a.agile.reason, "from the MTA"));
    CHECK(a.agile.call_thread == GetCurrentThreadId());
    CHECK(a.bound.calls == 0);

    /* Notify from the sinks' own apartment: both are called, on that thread. */
    CHECK(PostThreadMessageW(a.thread, WM_APP_NOTIFY, 0, 0));
    CHECK(WaitForSingleObject(a.ready, 10000) == WAIT_OBJECT_0);
    CHECK_HR(a.notify_here_hr, S_OK);
    CHECK(a.here_notified == 2 && a.here_failed == 0);
    CHECK(a.bound.calls == 1 && a.bound.call_thread == a.thread && wstr_is(a.bound.reason, "from the STA"));
    CHECK(a.agile.calls == 2);

    CHECK(PostThreadMessageW(a.thread, WM_QUIT, 0, 0));
    CHECK(WaitForSingleObject(thread, 10000) == WAIT_OBJECT_0);
    CloseHandle(thread);
    CloseHandle(a.ready);
    CHECK_HR(a.unadvise_bound_hr, S_OK);
    CHECK_HR(a.unadvise_agile_hr, S_OK);
    CHECK(a.bound.refs == 1 && a.bound.add_refs == a.bound.releases);
    CHECK(a.agile.refs == 1);
    CHECK(a.cpc->lpVtbl->Release(a.cpc) == 0);
    CHECK(OpcObjectCount() == before);
}

/* The library's own sink advised from another apartment: it is agile, so the main thread can call it. */
static unsigned __stdcall library_sink_thread(void *arg) {
    Apartment *a = (Apartment *)arg;
    IUnknown *sink = NULL;
    MSG msg;
    a->init_hr = CoInitializeEx(NULL, COINIT_APARTMENTTHREADED);
    a->thread = GetCurrentThreadId();
    PeekMessageW(&msg, NULL, 0, 0, PM_NOREMOVE);
    a->advise_agile_hr = OpcShutdownSinkCreate(on_shutdown, a->bound.hook_arg, &IID_Unknown_, (void **)&sink);
    if (sink) {
        a->advise_agile_hr = OpcShutdownAdvise((IUnknown *)a->cpc, sink, &a->agile_cookie);
        sink->lpVtbl->Release(sink);
    }
    SetEvent(a->ready);
    while (GetMessageW(&msg, NULL, 0, 0) > 0) {
        TranslateMessage(&msg);
        DispatchMessageW(&msg);
    }
    a->unadvise_agile_hr = OpcShutdownUnadvise((IUnknown *)a->cpc, a->agile_cookie);
    CoUninitialize();
    return 0;
}

static void test_library_sink_other_apartment(void) {
    uint32_t before = OpcObjectCount();
    Apartment a;
    Received r;
    HANDLE thread;
    ULONG n = 0, f = 0;
    memset(&a, 0, sizeof a);
    memset(&r, 0, sizeof r);
    a.bound.hook_arg = &r;
    a.cpc = create_server(NULL);
    if (!a.cpc) return;
    a.ready = CreateEventW(NULL, FALSE, FALSE, NULL);
    thread = (HANDLE)_beginthreadex(NULL, 0, library_sink_thread, &a, 0, NULL);
    CHECK(thread != NULL);
    if (!thread) return;
    CHECK(WaitForSingleObject(a.ready, 10000) == WAIT_OBJECT_0);
    CHECK_HR(a.init_hr, S_OK);
    CHECK_HR(a.advise_agile_hr, S_OK);
    CHECK_HR(OpcShutdownNotifyEx((IUnknown *)a.cpc, W("to the other apartment"), &n, &f), S_OK);
    CHECK(n == 1 && f == 0);
    CHECK(r.calls == 1 && wstr_is(r.reason, "to the other apartment"));
    CHECK(r.thread == GetCurrentThreadId()); /* the callback runs on the notifying thread */
    CHECK(PostThreadMessageW(a.thread, WM_QUIT, 0, 0));
    CHECK(WaitForSingleObject(thread, 10000) == WAIT_OBJECT_0);
    CloseHandle(thread);
    CloseHandle(a.ready);
    CHECK_HR(a.unadvise_agile_hr, S_OK);
    CHECK(a.cpc->lpVtbl->Release(a.cpc) == 0);
    CHECK(OpcObjectCount() == before);
}
#endif

int main(void) {
#ifdef _WIN32
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
#endif
    test_create_errors();
    test_find_and_enumerate_points();
    test_advise_return_codes();
    test_advise_limit_raised();
    test_notify();
    test_reentrant_sinks();
    test_enumerate_connections();
    test_lifetimes();
    test_aggregation();
    test_forwarding_server();
    test_client_sink();
    test_client_and_server();
#ifdef _WIN32
    test_other_apartment();
    test_library_sink_other_apartment();
#endif
    CHECK(OpcObjectCount() == 0);
#ifdef _WIN32
    CoUninitialize();
#endif
    return test_summary("test_shutdown");
}
