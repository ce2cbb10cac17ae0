/* The proxies of opccomn.dll's proxy/stub against crafted replies (docs/proxy-stub-robustness.md):
 * each proxy is connected to a channel that answers every call with a reply the test chose, ending
 * where an inaccessible page begins, and every out-parameter lies in a zone of canary bytes. Well-
 * formed replies come through with their values; replies whose counts disagree with the arrays or
 * with the caller's buffer (the audit's Next reply with conformance 64 for a one-GUID buffer, a
 * QueryAvailableLocaleIDs reply counting 100000 locales with one on the wire), truncation at every
 * length, big-endian data representations and unterminated strings fail the call before anything
 * is written to the caller's memory; then random mutations of the well-formed replies. Required: 0
 * access violations, 0 bytes changed outside the out-parameters, out-pointers NULL after a failure,
 * every channel buffer freed once.
 *
 * `test_proxy_replies widl` runs the deterministic part against the unchecked stand-in proxy/stub
 * (opccomn_widl_ps.dll) and fails: that is what the checks prevent. */
#include "ps_harness.h"

/* ---- The outer object the proxies are aggregated into ---- */

static HRESULT STDMETHODCALLTYPE outer_qi(IUnknown *This, REFIID riid, void **ppv) {
    if (IsEqualIID(riid, &IID_IUnknown)) {
        *ppv = This;
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE outer_addref(IUnknown *This) {
    (void)This;
    return 2;
}
static ULONG STDMETHODCALLTYPE outer_release(IUnknown *This) {
    (void)This;
    return 1;
}
static IUnknownVtbl outer_vtbl = {outer_qi, outer_addref, outer_release};
static IUnknown outer = {&outer_vtbl};

/* ---- The client side's channel: every call gets the reply the test chose ---- */

static ndr_msg reply;
static unsigned reply_drep = NDR_LOCAL;
static guarded reply_memory;
static LONG buffers_out, sends;

static HRESULT STDMETHODCALLTYPE chan_get_buffer(IRpcChannelBuffer *This, RPCOLEMESSAGE *msg, REFIID riid) {
    (void)This, (void)riid;
    msg->Buffer = HeapAlloc(GetProcessHeap(), HEAP_ZERO_MEMORY, msg->cbBuffer ? msg->cbBuffer : 1);
    if (!msg->Buffer) return E_OUTOFMEMORY;
    buffers_out++;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE chan_send_receive(IRpcChannelBuffer *This, RPCOLEMESSAGE *msg, ULONG *status) {
    (void)This;
    sends++;
    HeapFree(GetProcessHeap(), 0, msg->Buffer);
    reply_memory = guarded_copy(reply.b, reply.n);
    msg->Buffer = reply_memory.data;
    msg->cbBuffer = (ULONG)reply.n;
    msg->dataRepresentation = reply_drep;
    if (status) *status = 0;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE chan_free_buffer(IRpcChannelBuffer *This, RPCOLEMESSAGE *msg) {
    (void)This;
    if (reply_memory.base && msg->Buffer == reply_memory.data) guarded_free(&reply_memory);
    else HeapFree(GetProcessHeap(), 0, msg->Buffer);
    msg->Buffer = NULL;
    buffers_out--;
    return S_OK;
}
static IRpcChannelBufferVtbl chan_vtbl = PS_CHANNEL_VTBL(chan_get_buffer, chan_send_receive, chan_free_buffer);
static IRpcChannelBuffer client_channel = {&chan_vtbl};

/* ---- The caller's memory: out-parameters in a zone of canary bytes ---- */

#define ZONE_SIZE 65536
#define CANARY 0xA5
#define OUT_A 16384          /* first out-parameter (Next's GUIDs) */
#define OUT_B (OUT_A + 8192) /* second */
#define OUT_C (OUT_B + 64)   /* third */
#define OUT_D (OUT_C + 64)   /* fourth */

static unsigned char *zone;
static size_t written_from[4], written_to[4];
static unsigned written;

static void zone_fill(void) {
    memset(zone, CANARY, ZONE_SIZE);
    written = 0;
}

/* The caller's out-parameter of `size` bytes at `offset`: bytes it may change. */
static void *out_param(size_t offset, size_t size) {
    written_from[written] = offset;
    written_to[written] = offset + size;
    written++;
    return zone + offset;
}

/* Bytes changed outside the out-parameters. */
static unsigned zone_damage(void) {
    unsigned damage = 0, k;
    size_t i;
    for (i = 0; i < ZONE_SIZE; i++) {
        int inside = 0;
        for (k = 0; k < written; k++) inside |= i >= written_from[k] && i < written_to[k];
        if (!inside && zone[i] != CANARY) damage++;
    }
    return damage;
}

/* ---- Calls through the proxies ---- */

static void *proxies[PS_INTERFACES];
static IRpcProxyBuffer *proxy_buffers[PS_INTERFACES];

typedef struct result {
    HRESULT hr;
    unsigned damage;
    int outs_cleared; /* every out-pointer NULL and every count 0 */
    LONG access_violations;
    void *object; /* the interface pointer an EnumClassesOfCategories or Clone returned (released) */
} result;

static const GUID reply_guid = {0x40414243, 0x4445, 0x4647, {0x48, 0x49, 0x4a, 0x4b, 0x4c, 0x4d, 0x4e, 0x4f}};

/* Calls `method` of `iface` (Next with `celt`) against the current reply. */
static result call(unsigned iface, unsigned method, ULONG celt) {
    LONG avs = access_violations;
    result r;
    void *p = proxies[iface];
    void **a = NULL, **b = NULL, **c = NULL;
    ULONG *count = NULL;
    zone_fill();
    r.outs_cleared = 1;
    switch (iface * 16 + method) {
    case PS_SHUTDOWN * 16 + 3:
        r.hr = ((IOPCShutdown *)p)->lpVtbl->ShutdownRequest(p, L"reason");
        break;
    case PS_COMMON * 16 + 3:
        r.hr = ((IOPCCommon *)p)->lpVtbl->SetLocaleID(p, 0x0407);
        break;
    case PS_COMMON * 16 + 4:
        count = (ULONG *)out_param(OUT_A, sizeof(LCID));
        r.hr = ((IOPCCommon *)p)->lpVtbl->GetLocaleID(p, count);
        break;
    case PS_COMMON * 16 + 5:
        count = (ULONG *)out_param(OUT_B, sizeof(DWORD));
        a = (void **)out_param(OUT_A, sizeof(void *));
        r.hr = ((IOPCCommon *)p)->lpVtbl->QueryAvailableLocaleIDs(p, count, (LCID **)a);
        break;
    case PS_COMMON * 16 + 6:
        a = (void **)out_param(OUT_A, sizeof(void *));
        r.hr = ((IOPCCommon *)p)->lpVtbl->GetErrorString(p, E_FAIL, (LPWSTR *)a);
        break;
    case PS_COMMON * 16 + 7:
        r.hr = ((IOPCCommon *)p)->lpVtbl->SetClientName(p, L"client");
        break;
    case PS_SERVER_LIST * 16 + 3:
        a = (void **)out_param(OUT_A, sizeof(void *));
        r.hr = ((IOPCServerList *)p)->lpVtbl->EnumClassesOfCategories(p, 1, (CATID *)&reply_guid, 0, NULL, (IEnumGUID **)a);
        break;
    case PS_SERVER_LIST2 * 16 + 3:
        a = (void **)out_param(OUT_A, sizeof(void *));
        r.hr = ((IOPCServerList2 *)p)->lpVtbl->EnumClassesOfCategories(p, 1, (CATID *)&reply_guid, 0, NULL,
                                                                       (IOPCEnumGUID **)a);
        break;
    case PS_SERVER_LIST * 16 + 4:
        a = (void **)out_param(OUT_A, sizeof(void *));
        b = (void **)out_param(OUT_B, sizeof(void *));
        r.hr = ((IOPCServerList *)p)->lpVtbl->GetClassDetails(p, &reply_guid, (LPOLESTR *)a, (LPOLESTR *)b);
        break;
    case PS_SERVER_LIST2 * 16 + 4:
        a = (void **)out_param(OUT_A, sizeof(void *));
        b = (void **)out_param(OUT_B, sizeof(void *));
        c = (void **)out_param(OUT_C, sizeof(void *));
        r.hr = ((IOPCServerList2 *)p)->lpVtbl->GetClassDetails(p, &reply_guid, (LPOLESTR *)a, (LPOLESTR *)b,
                                                               (LPOLESTR *)c);
        break;
    case PS_SERVER_LIST * 16 + 5:
        out_param(OUT_A, sizeof(GUID));
        r.hr = ((IOPCServerList *)p)->lpVtbl->CLSIDFromProgID(p, L"Test.Server.1", (CLSID *)(zone + OUT_A));
        break;
    case PS_SERVER_LIST2 * 16 + 5:
        out_param(OUT_A, sizeof(GUID));
        r.hr = ((IOPCServerList2 *)p)->lpVtbl->CLSIDFromProgID(p, L"Test.Server.1", (CLSID *)(zone + OUT_A));
        break;
    case PS_ENUM_GUID * 16 + 3:
        out_param(OUT_A, (size_t)celt * sizeof(GUID));
        count = (ULONG *)out_param(OUT_D, sizeof(ULONG));
        r.hr = ((IOPCEnumGUID *)p)->lpVtbl->Next(p, celt, (GUID *)(zone + OUT_A), count);
        break;
    case PS_ENUM_GUID * 16 + 4:
        r.hr = ((IOPCEnumGUID *)p)->lpVtbl->Skip(p, 2);
        break;
    case PS_ENUM_GUID * 16 + 5:
        r.hr = ((IOPCEnumGUID *)p)->lpVtbl->Reset(p);
        break;
    case PS_ENUM_GUID * 16 + 6:
        a = (void **)out_param(OUT_A, sizeof(void *));
        r.hr = ((IOPCEnumGUID *)p)->lpVtbl->Clone(p, (IOPCEnumGUID **)a);
        break;
    default:
        r.hr = E_NOTIMPL;
    }
    r.damage = zone_damage();
    r.object = a && (method == 3 ? iface == PS_SERVER_LIST || iface == PS_SERVER_LIST2 : method == 6 && iface == PS_ENUM_GUID)
                   ? *a
                   : NULL;
    if (FAILED(r.hr)) {
        r.outs_cleared = (!a || !*a) && (!b || !*b) && (!c || !*c) && (!count || !*count || iface == PS_ENUM_GUID);
        /* An object a failing peer returned all the same is the caller's to release. */
        if (r.object) ((IUnknown *)r.object)->lpVtbl->Release((IUnknown *)r.object);
    } else {
        /* What a caller frees after success. */
        if (iface == PS_COMMON || iface == PS_SERVER_LIST || iface == PS_SERVER_LIST2) {
            if (a && *a && method != 3) CoTaskMemFree(*a);
            if (a && *a && method == 3) ((IUnknown *)*a)->lpVtbl->Release((IUnknown *)*a);
            if (b && *b) CoTaskMemFree(*b);
            if (c && *c) CoTaskMemFree(*c);
        } else if (a && *a) {
            ((IUnknown *)*a)->lpVtbl->Release((IUnknown *)*a);
        }
    }
    r.access_violations = access_violations - avs;
    return r;
}

/* The call failed and nothing of the caller's outside its out-parameters changed. */
#define CHECK_REJECTED(r, what)                                                                               \
    do {                                                                                                      \
        result check_r_ = (r);                                                                                \
        if (FAILED(check_r_.hr) && check_r_.damage == 0 && check_r_.outs_cleared && !check_r_.access_violations) { \
            test_passed++;                                                                                    \
        } else {                                                                                              \
            test_failed++;                                                                                    \
            fprintf(stderr, "%s:%d: %s: hr 0x%08lX, %u bytes changed outside the out-parameters, outs %s, %ld access violations\n", \
                    __FILE__, __LINE__, what, (unsigned long)check_r_.hr, check_r_.damage,                    \
                    check_r_.outs_cleared ? "cleared" : "NOT cleared", (long)check_r_.access_violations);    \
        }                                                                                                     \
    } while (0)

/* ---- Well-formed replies, one per method ---- */

typedef struct good_reply {
    unsigned iface, method;
    ULONG celt;
    HRESULT hr;
    ndr_msg m;
} good_reply;

static good_reply good[32];
static unsigned good_count;

static ndr_msg *add_good(unsigned iface, unsigned method, ULONG celt, HRESULT hr) {
    good_reply *g = &good[good_count++];
    g->iface = iface;
    g->method = method;
    g->celt = celt;
    g->hr = hr;
    g->m = msg_empty();
    return &g->m;
}

static void end_reply(ndr_msg *m, HRESULT hr) {
    put_u32(m, (unsigned)hr);
}

static void build_good_replies(void) {
    ndr_msg *m;
    unsigned l;
    end_reply(add_good(PS_SHUTDOWN, 3, 0, S_OK), S_OK);
    end_reply(add_good(PS_COMMON, 3, 0, S_OK), S_OK);
    m = add_good(PS_COMMON, 4, 0, S_OK);
    put_u32(m, 0x0407);
    end_reply(m, S_OK);
    m = add_good(PS_COMMON, 5, 0, S_OK);
    put_u32(m, 2);
    put_u32(m, 0x20000);
    put_u32(m, 2);
    put_u32(m, 0x0409);
    put_u32(m, 0x0407);
    end_reply(m, S_OK);
    m = add_good(PS_COMMON, 6, 0, S_OK);
    put_u32(m, 0x20000);
    put_string(m, "error text");
    end_reply(m, S_OK);
    end_reply(add_good(PS_COMMON, 7, 0, S_OK), S_OK);
    for (l = 0; l < 2; l++) {
        unsigned iface = l ? PS_SERVER_LIST2 : PS_SERVER_LIST, k;
        m = add_good(iface, 3, 0, S_FALSE);
        put_u32(m, 0); /* a NULL enumerator (Wine's layout: its size, 0) */
        end_reply(m, S_FALSE);
        m = add_good(iface, 4, 0, S_OK);
        for (k = 0; k < (l ? 3u : 2u); k++) {
            put_u32(m, 0x20000 + 4 * k);
            put_string(m, k == 1 ? "Test server" : "Test.Server.1");
        }
        end_reply(m, S_OK);
        m = add_good(iface, 5, 0, S_OK);
        put_guids(m, 1);
        end_reply(m, S_OK);
    }
    m = add_good(PS_ENUM_GUID, 3, 3, S_FALSE);
    put_u32(m, 3);
    put_u32(m, 0);
    put_u32(m, 2);
    put_guids(m, 2);
    put_u32(m, 2);
    end_reply(m, S_FALSE);
    m = add_good(PS_ENUM_GUID, 3, 1, S_OK);
    put_u32(m, 1);
    put_u32(m, 0);
    put_u32(m, 1);
    put_guids(m, 1);
    put_u32(m, 1);
    end_reply(m, S_OK);
    end_reply(add_good(PS_ENUM_GUID, 4, 0, S_OK), S_OK);
    end_reply(add_good(PS_ENUM_GUID, 5, 0, S_OK), S_OK);
    m = add_good(PS_ENUM_GUID, 6, 0, E_NOTIMPL);
    put_u32(m, 0);
    end_reply(m, E_NOTIMPL);
}

static result call_with(const ndr_msg *m, unsigned drep, unsigned iface, unsigned method, ULONG celt) {
    reply = *m;
    reply_drep = drep;
    return call(iface, method, celt);
}

static void well_formed_replies_come_through(void) {
    unsigned i;
    for (i = 0; i < good_count; i++) {
        result r = call_with(&good[i].m, NDR_LOCAL, good[i].iface, good[i].method, good[i].celt);
        if (r.hr != good[i].hr || r.damage)
            fprintf(stderr, "%s method %u: hr 0x%08lX, %u bytes damaged\n", PS_NAMES[good[i].iface], good[i].method,
                    (unsigned long)r.hr, r.damage);
        CHECK(r.hr == good[i].hr && r.damage == 0 && r.access_violations == 0);
    }
    /* Values arrive: Next's GUIDs and count, GetLocaleID's locale. */
    call_with(&good[good_count - 5].m, NDR_LOCAL, PS_ENUM_GUID, 3, 3);
    CHECK(*(ULONG *)(zone + OUT_D) == 2);
    CHECK(zone[OUT_A] == 0x40 && zone[OUT_A + 31] == 0x40 + 31 && zone[OUT_A + 32] == 0);
    call_with(&good[2].m, NDR_LOCAL, PS_COMMON, 4, 0);
    CHECK(*(LCID *)(zone + OUT_A) == 0x0407);
}

static void truncated_and_foreign_replies_are_rejected(void) {
    unsigned i;
    for (i = 0; i < good_count; i++) {
        ndr_msg m = good[i].m;
        for (m.n = 0; m.n < good[i].m.n; m.n++)
            CHECK_REJECTED(call_with(&m, NDR_LOCAL, good[i].iface, good[i].method, good[i].celt), "truncated reply");
        CHECK_REJECTED(call_with(&good[i].m, NDR_BIG_ENDIAN_REP, good[i].iface, good[i].method, good[i].celt),
                       "big-endian reply");
    }
}

/* The audit's replies and their relatives. */
static void counts_must_fit_the_callers_buffers(void) {
    ndr_msg m;
    unsigned k;
    /* Next(celt 1, one-GUID buffer), reply conformance and count 64. */
    m = msg_empty();
    put_u32(&m, 64);
    put_u32(&m, 0);
    put_u32(&m, 64);
    put_guids(&m, 64);
    put_u32(&m, 64);
    end_reply(&m, S_OK);
    CHECK_REJECTED(call_with(&m, NDR_LOCAL, PS_ENUM_GUID, 3, 1), "Next reply with 64 GUIDs for a buffer of 1");
    /* Conformance = celt, but two elements. */
    m = msg_empty();
    put_u32(&m, 1);
    put_u32(&m, 0);
    put_u32(&m, 2);
    put_guids(&m, 2);
    put_u32(&m, 2);
    end_reply(&m, S_OK);
    CHECK_REJECTED(call_with(&m, NDR_LOCAL, PS_ENUM_GUID, 3, 1), "Next reply with more GUIDs than its conformance");
    /* *pceltFetched beyond the GUIDs sent. */
    m = msg_empty();
    put_u32(&m, 3);
    put_u32(&m, 0);
    put_u32(&m, 1);
    put_guids(&m, 1);
    put_u32(&m, 3);
    end_reply(&m, S_OK);
    CHECK_REJECTED(call_with(&m, NDR_LOCAL, PS_ENUM_GUID, 3, 3), "Next reply counting more than it carries");
    /* An offset into the caller's buffer. */
    m = msg_empty();
    put_u32(&m, 3);
    put_u32(&m, 2);
    put_u32(&m, 1);
    put_guids(&m, 1);
    put_u32(&m, 1);
    end_reply(&m, S_OK);
    CHECK_REJECTED(call_with(&m, NDR_LOCAL, PS_ENUM_GUID, 3, 3), "Next reply with an offset");
    /* QueryAvailableLocaleIDs: 100000 counted, one sent; 5 counted, none. */
    m = msg_empty();
    put_u32(&m, 100000);
    put_u32(&m, 0x20000);
    put_u32(&m, 1);
    put_u32(&m, 0x0409);
    end_reply(&m, S_OK);
    CHECK_REJECTED(call_with(&m, NDR_LOCAL, PS_COMMON, 5, 0), "100000 locales counted, one sent");
    m = msg_empty();
    put_u32(&m, 3);
    put_u32(&m, 0x20000);
    put_u32(&m, 1);
    put_u32(&m, 0x0409);
    end_reply(&m, S_OK);
    CHECK_REJECTED(call_with(&m, NDR_LOCAL, PS_COMMON, 5, 0), "3 locales counted, one sent");
    m = msg_empty();
    put_u32(&m, 5);
    put_u32(&m, 0);
    end_reply(&m, S_OK);
    CHECK_REJECTED(call_with(&m, NDR_LOCAL, PS_COMMON, 5, 0), "5 locales counted, no array");
    /* Strings: a maximum the bytes do not back, no NUL. */
    m = msg_empty();
    put_u32(&m, 0x20000);
    put_u32(&m, 0x7FFFFFFF);
    put_u32(&m, 0);
    put_u32(&m, 1);
    put_u32(&m, 0);
    end_reply(&m, S_OK);
    CHECK_REJECTED(call_with(&m, NDR_LOCAL, PS_COMMON, 6, 0), "error string with a huge maximum");
    m = msg_empty();
    put_u32(&m, 0x20000);
    put_u32(&m, 2);
    put_u32(&m, 0);
    put_u32(&m, 2);
    put_u32(&m, 0x00420041);
    end_reply(&m, S_OK);
    CHECK_REJECTED(call_with(&m, NDR_LOCAL, PS_COMMON, 6, 0), "unterminated error string");
    for (k = 0; k < 2; k++) {
        m = msg_empty();
        put_u32(&m, 0x20000);
        put_string(&m, "Test.Server.1");
        put_u32(&m, 0x20004);
        put_u32(&m, 0x40000000);
        put_u32(&m, 0);
        put_u32(&m, 0x40000000);
        end_reply(&m, S_OK);
        CHECK_REJECTED(call_with(&m, NDR_LOCAL, k ? PS_SERVER_LIST2 : PS_SERVER_LIST, 4, 0),
                       "class details with a string longer than the reply");
        /* An interface pointer larger than the reply. */
        m = msg_empty();
        put_u32(&m, 0x10000);
        put_u32(&m, 0x574f454d);
        end_reply(&m, S_OK);
        if (!testing_widl) /* the stand-in's runtime would read the 64 KiB past the reply */
            CHECK_REJECTED(call_with(&m, NDR_LOCAL, k ? PS_SERVER_LIST2 : PS_SERVER_LIST, 3, 0),
                           "an enumerator larger than the reply");
    }
}

/* Next asks for at most the bound: beyond it the proxy sends nothing. */
static void next_beyond_the_bound_is_not_sent(void) {
    LONG before = sends;
    /* The room the caller promises (the proxy clears it after a failure). */
    GUID *room = (GUID *)malloc((PS_MAX_ELEMENTS + 1) * sizeof(GUID));
    ULONG fetched = GARBAGE_U32;
    reply = good[good_count - 4].m;
    CHECK_HR(((IOPCEnumGUID *)proxies[PS_ENUM_GUID])->lpVtbl->Next(proxies[PS_ENUM_GUID], PS_MAX_ELEMENTS + 1, room, &fetched),
             INVALID_BOUND);
    CHECK(sends == before);
    free(room);
}

/* ---- Interface pointers in both layouts ---- */

/* The object whose OBJREFs the replies carry: an IOPCEnumGUID (and IEnumGUID, the same vtable) of this
 * apartment, so that COM unmarshals it as the object itself. */
static LONG enum_refs;
static HRESULT STDMETHODCALLTYPE local_qi(IOPCEnumGUID *This, REFIID riid, void **ppv) {
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCEnumGUID) || IsEqualIID(riid, &IID_IEnumGUID)) {
        *ppv = This;
        InterlockedIncrement(&enum_refs);
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE local_addref(IOPCEnumGUID *This) {
    (void)This;
    return (ULONG)InterlockedIncrement(&enum_refs);
}
static ULONG STDMETHODCALLTYPE local_release(IOPCEnumGUID *This) {
    (void)This;
    return (ULONG)InterlockedDecrement(&enum_refs);
}
static HRESULT STDMETHODCALLTYPE local_next(IOPCEnumGUID *This, ULONG celt, GUID *rgelt, ULONG *fetched) {
    (void)This, (void)celt, (void)rgelt;
    if (fetched) *fetched = 0;
    return S_FALSE;
}
static HRESULT STDMETHODCALLTYPE local_skip(IOPCEnumGUID *This, ULONG celt) {
    (void)This, (void)celt;
    return S_FALSE;
}
static HRESULT STDMETHODCALLTYPE local_reset(IOPCEnumGUID *This) {
    (void)This;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE local_clone(IOPCEnumGUID *This, IOPCEnumGUID **out) {
    (void)This;
    *out = NULL;
    return E_NOTIMPL;
}
static IOPCEnumGUIDVtbl local_enum_vtbl = {local_qi, local_addref, local_release, local_next,
                                          local_skip, local_reset, local_clone};
static IOPCEnumGUID local_enum = {&local_enum_vtbl};

/* The three methods that return an interface pointer, with the IID each declares. */
static const struct {
    unsigned iface, method;
    const IID *iid;
} ip_methods[3] = {{PS_SERVER_LIST, 3, &IID_IEnumGUID},
                   {PS_SERVER_LIST2, 3, &IID_IOPCEnumGUID},
                   {PS_ENUM_GUID, 6, &IID_IOPCEnumGUID}};

/* A reply to an interface-pointer method: the pointer in Wine's layout (`wine`) or NDR's, then the HRESULT. */
static ndr_msg ip_reply(int wine, const unsigned char *objref, ULONG len, HRESULT hr) {
    ndr_msg m = msg_empty();
    if (wine) put_wine_interface_pointer(&m, objref, len);
    else put_ndr_interface_pointer(&m, objref, len);
    end_reply(&m, hr);
    return m;
}

/* The reply refused by opccomn's checks (RPC_X_BAD_STUB_DATA; the unchecked stand-in's runtime fails
 * otherwise), nothing written, and the OBJREF's references given back. */
#define CHECK_IP_REFUSED(m, k, objref, len, what)                                                            \
    do {                                                                                                     \
        result ip_r_ = call_with(&(m), NDR_LOCAL, ip_methods[k].iface, ip_methods[k].method, 0);              \
        CHECK_REJECTED(ip_r_, what);                                                                         \
        if (!testing_widl && ip_r_.hr != BAD_STUB_DATA)                                                      \
            fprintf(stderr, "%s:%d: %s: 0x%08lX, not RPC_X_BAD_STUB_DATA\n", __FILE__, __LINE__, what,        \
                    (unsigned long)ip_r_.hr);                                                                \
        CHECK(testing_widl || ip_r_.hr == BAD_STUB_DATA);                                                    \
        release_objref((objref), (len));                                                                     \
    } while (0)

/* Replies carrying an OBJREF the runtime itself wrote for an object of this apartment, in the layout
 * this runtime writes and reads (Wine's: a byte count, then the OBJREF) and in the other (NDR's, as
 * Windows' rpcrt4 writes it, [MS-DCOM] 2.2.14: referent ID, conformance, ulCntData, OBJREF): the first
 * comes through as the object itself; the second is refused, as this runtime would misread it (Wine's
 * rpcrt4 takes a referent ID for a byte count); an OBJREF for another interface than the method
 * declares is refused in either (Wine's rpcrt4 unmarshals with IID_NULL and would hand the caller an
 * object of whatever interface the OBJREF names); and each malformed framing or OBJREF, and every
 * truncation, is refused with nothing written and nothing unmarshalled. */
static void interface_pointers_in_both_layouts(void) {
    unsigned char objref[OBJREF_MAX];
    unsigned k, j;
    int native = runtime_reads_wine_layout(), foreign = !native;
    LONG refs_before = enum_refs;
    printf("proxy: this runtime reads interface pointers in %s layout\n", native ? "Wine's" : "NDR's");
    for (k = 0; k < 3; k++) {
        ULONG len;
        ndr_msg m;
        result r;
        /* This runtime's layout, its own OBJREF: the object itself comes back. */
        len = marshal_objref((IUnknown *)&local_enum, ip_methods[k].iid, objref);
        CHECK(len >= 68 && get_u32(objref) == OBJREF_SIGNATURE && get_u32(objref + 4) == OBJREF_STANDARD);
        if (len < 68) return;
        m = ip_reply(native, objref, len, S_OK);
        r = call_with(&m, NDR_LOCAL, ip_methods[k].iface, ip_methods[k].method, 0);
        if (r.hr != S_OK || r.object != &local_enum)
            fprintf(stderr, "%s method %u, this runtime's layout: hr 0x%08lX, object %p (expected %p)\n",
                    PS_NAMES[ip_methods[k].iface], ip_methods[k].method, (unsigned long)r.hr, r.object,
                    (void *)&local_enum);
        CHECK(r.hr == S_OK && r.object == &local_enum && r.damage == 0 && r.access_violations == 0);
        /* ... and refused at every length short of the whole. */
        len = marshal_objref((IUnknown *)&local_enum, ip_methods[k].iid, objref);
        m = ip_reply(native, objref, len, S_OK);
        {
            ndr_msg cut = m;
            for (cut.n = 0; cut.n < m.n; cut.n++) {
                result c = call_with(&cut, NDR_LOCAL, ip_methods[k].iface, ip_methods[k].method, 0);
                CHECK_REJECTED(c, "interface pointer cut short");
            }
        }
        release_objref(objref, len);
        /* The other runtime's layout. */
        len = marshal_objref((IUnknown *)&local_enum, ip_methods[k].iid, objref);
        m = ip_reply(foreign, objref, len, S_OK);
        CHECK_IP_REFUSED(m, k, objref, len, "the layout this runtime does not read");
        /* An OBJREF for IUnknown, in either layout. */
        for (j = 0; j < 2; j++) {
            len = marshal_objref((IUnknown *)&local_enum, &IID_IUnknown, objref);
            m = ip_reply((int)j, objref, len, S_OK);
            CHECK_IP_REFUSED(m, k, objref, len, "an OBJREF of another interface");
        }
        /* The enumerator of the other list's method. */
        len = marshal_objref((IUnknown *)&local_enum, k ? &IID_IEnumGUID : &IID_IOPCEnumGUID, objref);
        m = ip_reply(native, objref, len, S_OK);
        CHECK_IP_REFUSED(m, k, objref, len, "an OBJREF of the other enumerator");
        /* Malformed: the framing, then the OBJREF (each changed in the reply's copy; the OBJREF's
         * references given back once at the end). */
        len = marshal_objref((IUnknown *)&local_enum, ip_methods[k].iid, objref);
        for (j = 0; j < 9; j++) {
            static const char *const what[9] = {
                "NDR: ulCntData unlike the conformance", "NDR: a conformance beyond the reply",
                "Wine: a byte count beyond the reply", "Wine: a byte count short of the OBJREF",
                "no OBJREF signature", "no OBJREF flavour", "an unknown OBJREF flavour",
                "string bindings beyond the OBJREF", "no HRESULT after the pointer"};
            unsigned v;
            m = ip_reply(j != 0 && j != 1, objref, len, S_OK);
            switch (j) {
            case 0: v = len + 4; memcpy(m.b + 8, &v, 4); break;
            case 1: v = 0x10000; memcpy(m.b + 4, &v, 4); memcpy(m.b + 8, &v, 4); break;
            case 2: v = 0x10000; memcpy(m.b, &v, 4); break;
            case 3: v = 40; memcpy(m.b, &v, 4); break;
            case 4: memcpy(m.b + 4, "WOEM", 4); break;
            case 5: v = 0; memcpy(m.b + 8, &v, 4); break;
            case 6: v = 16; memcpy(m.b + 8, &v, 4); break;
            case 7: m.b[4 + 64] = 0xFF; m.b[4 + 65] = 0x7F; break;
            default: m.n -= 4;
            }
            /* (The stand-in's runtime would read by these counts, past the reply.) */
            if (testing_widl && (j == 1 || j == 2)) continue;
            {
                result c = call_with(&m, NDR_LOCAL, ip_methods[k].iface, ip_methods[k].method, 0);
                CHECK_REJECTED(c, what[j]);
                CHECK(testing_widl || c.hr == BAD_STUB_DATA);
            }
        }
        release_objref(objref, len);
    }
    /* Every reference the OBJREFs held came back. */
    if (enum_refs != refs_before) fprintf(stderr, "local enumerator: %ld references left\n", (long)(enum_refs - refs_before));
    CHECK(enum_refs == refs_before);
}

/* Random mutations of interface-pointer replies carrying the runtime's own OBJREF, in either layout:
 * a framing word or the HRESULT replaced, the reply cut or extended. (The OBJREF itself is left as
 * the runtime wrote it: a made-up OXID or IPID would have COM look for a made-up server; its fields
 * are fuzzed against the checks themselves, fuzz/fuzz_targets/wire.rs.) Whatever passes the checks
 * is unmarshalled as the object itself; the rest is refused with nothing written. */
static void mutated_interface_pointers_are_answered_safely(unsigned rounds) {
    static const unsigned values[] = {0, 1, 4, 24, 64, 67, 68, 69, 72, 0x10000, 0x7FFFFFFFu, 0xFFFFFFFFu,
                                      OBJREF_SIGNATURE, NDR_REFERENT_ID};
    unsigned char objref[OBJREF_MAX];
    unsigned i, accepted = 0, rejected = 0, damaged = 0;
    LONG avs = access_violations, refs_before = enum_refs;
    for (i = 0; i < rounds; i++) {
        /* Mostly this runtime's layout (the other's is refused whatever its framing). */
        int wine = ps_random() % 4 != 0 ? runtime_reads_wine_layout() : !runtime_reads_wine_layout();
        unsigned k = ps_random() % 3, header = wine ? 1 : 3;
        ULONG len = marshal_objref((IUnknown *)&local_enum, ip_methods[k].iid, objref);
        ndr_msg m = ip_reply(wine, objref, len, S_OK);
        unsigned v = values[ps_random() % (sizeof(values) / sizeof(values[0]))];
        result r;
        switch (ps_random() % 4) {
        case 0: memcpy(m.b + 4 * (ps_random() % header), &v, 4); break;
        case 1: memcpy(m.b + m.n - 4, &v, 4); break;
        case 2: m.n = ps_random() % m.n; break;
        default: {
            unsigned extra = 1 + ps_random() % 64;
            while (extra-- && m.n < sizeof(m.b)) m.b[m.n++] = (unsigned char)ps_random();
        }
        }
        r = call_with(&m, NDR_LOCAL, ip_methods[k].iface, ip_methods[k].method, 0);
        if (r.object) accepted++;
        else {
            rejected++;
            release_objref(objref, len);
        }
        if (r.damage || (r.object && r.object != &local_enum) || ((r.hr == BAD_STUB_DATA) && !r.outs_cleared)) {
            damaged++;
            fprintf(stderr, "mutated interface pointer reply to %s method %u: hr 0x%08lX, %u bytes changed, object %p\n",
                    PS_NAMES[ip_methods[k].iface], ip_methods[k].method, (unsigned long)r.hr, r.damage, r.object);
        }
    }
    CHECK(damaged == 0);
    CHECK(access_violations == avs);
    CHECK(enum_refs == refs_before);
    printf("interface pointer fuzz: %u mutated replies, %u unmarshalled, %u not, %u with caller memory changed, "
           "%ld access violations, %ld references left\n",
           rounds, accepted, rejected, damaged, (long)(access_violations - avs), (long)(enum_refs - refs_before));
}

/* Random mutations of the well-formed replies (interface pointers excepted: an OBJREF's contents are
 * COM's to check, and a made-up one would have COM look for a made-up server). */
static void mutated_replies_are_answered_safely(unsigned rounds) {
    static const unsigned values[] = {0, 1, 2, 3, 4, 64, 4096, 65536, 65537, 100000, 0x7FFFFFFFu, 0xFFFFFFFFu};
    unsigned i, accepted = 0, rejected = 0, damaged = 0;
    LONG avs = access_violations;
    for (i = 0; i < rounds; i++) {
        const good_reply *g = &good[ps_random() % good_count];
        ndr_msg m = g->m;
        unsigned mutations = 1 + ps_random() % 3, k;
        result r;
        if (g->method == 3 && g->iface != PS_ENUM_GUID && g->iface != PS_SHUTDOWN && g->iface != PS_COMMON) continue;
        if (g->method == 6 && g->iface == PS_ENUM_GUID) continue;
        for (k = 0; k < mutations; k++) {
            switch (ps_random() % 4) {
            case 0:
                if (m.n >= 4) {
                    unsigned v = values[ps_random() % (sizeof(values) / sizeof(values[0]))];
                    memcpy(m.b + (ps_random() % (m.n / 4)) * 4, &v, 4);
                }
                break;
            case 1:
                if (m.n) m.b[ps_random() % m.n] ^= (unsigned char)(1u << (ps_random() % 8));
                break;
            case 2:
                if (m.n) m.n = ps_random() % m.n;
                break;
            default: {
                unsigned extra = ps_random() % 64;
                while (extra-- && m.n < sizeof(m.b)) m.b[m.n++] = (unsigned char)ps_random();
            }
            }
        }
        r = call_with(&m, NDR_LOCAL, g->iface, g->method, g->celt);
        if (FAILED(r.hr)) rejected++;
        else accepted++;
        /* A failure the peer reports may come with out-parameters (the peer's business); one the
         * proxy/stub reports may not. */
        if (r.damage || ((r.hr == BAD_STUB_DATA || r.hr == INVALID_BOUND) && !r.outs_cleared)) {
            damaged++;
            fprintf(stderr, "mutated reply to %s method %u: hr 0x%08lX, %u bytes changed, outs %s\n",
                    PS_NAMES[g->iface], g->method, (unsigned long)r.hr, r.damage, r.outs_cleared ? "cleared" : "not cleared");
        }
    }
    CHECK(damaged == 0);
    CHECK(access_violations == avs);
    printf("proxy fuzz: %u mutated replies, %u accepted, %u rejected, %u with caller memory changed, %ld access violations\n",
           accepted + rejected, accepted, rejected, damaged, (long)(access_violations - avs));
}

int main(int argc, char **argv) {
    IPSFactoryBuffer *factory;
    unsigned i;
    CoInitializeEx(NULL, COINIT_MULTITHREADED);
    count_access_violations();
    zone = (unsigned char *)VirtualAlloc(NULL, ZONE_SIZE, MEM_COMMIT | MEM_RESERVE, PAGE_READWRITE);
    factory = load_factory(argc, argv);
    for (i = 0; i < PS_INTERFACES; i++) {
        CHECK_HR(factory->lpVtbl->CreateProxy(factory, &outer, PS_IIDS[i], &proxy_buffers[i], &proxies[i]), S_OK);
        if (!proxy_buffers[i]) return test_summary("test_proxy_replies");
        CHECK_HR(proxy_buffers[i]->lpVtbl->Connect(proxy_buffers[i], &client_channel), S_OK);
    }
    build_good_replies();
    well_formed_replies_come_through();
    truncated_and_foreign_replies_are_rejected();
    counts_must_fit_the_callers_buffers();
    if (FAILED(testing_widl ? use_widl_proxy_stub() : use_opccomn_proxy_stub_directly())) {
        fprintf(stderr, "the proxy/stub could not be registered in this process\n");
        test_failed++;
    } else {
        interface_pointers_in_both_layouts();
    }
    if (!testing_widl) {
        next_beyond_the_bound_is_not_sent();
        mutated_replies_are_answered_safely(20000);
        mutated_interface_pointers_are_answered_safely(2000);
    }
    printf("proxy: %ld access violations in all, %ld channel buffers not freed\n", (long)access_violations,
           (long)buffers_out);
    CHECK(access_violations == 0);
    CHECK(buffers_out == 0);
    for (i = 0; i < PS_INTERFACES; i++) {
        proxy_buffers[i]->lpVtbl->Disconnect(proxy_buffers[i]);
        ((IUnknown *)proxies[i])->lpVtbl->Release((IUnknown *)proxies[i]);
        proxy_buffers[i]->lpVtbl->Release(proxy_buffers[i]);
    }
    factory->lpVtbl->Release(factory);
    CoUninitialize();
    return test_summary("test_proxy_replies");
}
