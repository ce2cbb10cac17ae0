/* The stubs of opccomn.dll's proxy/stub against crafted requests, straight into IRpcStubBuffer::Invoke
 * of each of the five interfaces' stubs (docs/proxy-stub-robustness.md): well-formed requests reach
 * the server; conformance that disagrees with the count, truncation at every length, counts beyond the
 * bound, big-endian data representations, unterminated strings, unknown methods and misaligned
 * buffers are refused before the server runs; then random mutations of well-formed requests. Every
 * request ends where an inaccessible page begins, and the test server reads each [in] array by the
 * count it is given (as the server browser does), so a read past the received bytes is an access
 * violation; those are counted even when the runtime catches them. Required: 0 access violations,
 * no server call for a refused request, no allocation beyond what the bounds allow (an IMallocSpy
 * sees every allocation the NDR engine makes).
 *
 * `test_stub_requests widl` runs the deterministic part against the unchecked stand-in proxy/stub
 * (opccomn_widl_ps.dll) and fails: that is what the checks prevent. */
#include "ps_harness.h"

/* ---- The server the stubs call: the five interfaces on one object ---- */

static LONG server_calls;
static volatile unsigned char sink;
/* Set: EnumClassesOfCategories and Clone return the server's own enumerator instead of NULL. */
static int return_objects;

typedef struct server {
    IOPCShutdown IOPCShutdown_iface;
    IOPCCommon IOPCCommon_iface;
    IOPCServerList IOPCServerList_iface;
    IOPCEnumGUID IOPCEnumGUID_iface;
    IOPCServerList2 IOPCServerList2_iface;
    LONG refs;
} server;

static server the_server;

static HRESULT server_qi(REFIID riid, void **ppv) {
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCShutdown)) *ppv = &the_server.IOPCShutdown_iface;
    else if (IsEqualIID(riid, &IID_IOPCCommon)) *ppv = &the_server.IOPCCommon_iface;
    else if (IsEqualIID(riid, &IID_IOPCServerList)) *ppv = &the_server.IOPCServerList_iface;
    else if (IsEqualIID(riid, &IID_IOPCEnumGUID) || IsEqualIID(riid, &IID_IEnumGUID)) *ppv = &the_server.IOPCEnumGUID_iface;
    else if (IsEqualIID(riid, &IID_IOPCServerList2)) *ppv = &the_server.IOPCServerList2_iface;
    else {
        *ppv = NULL;
        return E_NOINTERFACE;
    }
    InterlockedIncrement(&the_server.refs);
    return S_OK;
}

#define SERVER_UNKNOWN(Iface)                                                                           \
    static HRESULT STDMETHODCALLTYPE Iface##_qi(Iface *This, REFIID riid, void **ppv) {                 \
        (void)This;                                                                                     \
        return server_qi(riid, ppv);                                                                    \
    }                                                                                                   \
    static ULONG STDMETHODCALLTYPE Iface##_addref(Iface *This) {                                        \
        (void)This;                                                                                     \
        return (ULONG)InterlockedIncrement(&the_server.refs);                                           \
    }                                                                                                   \
    static ULONG STDMETHODCALLTYPE Iface##_release(Iface *This) {                                       \
        (void)This;                                                                                     \
        return (ULONG)InterlockedDecrement(&the_server.refs);                                           \
    }
SERVER_UNKNOWN(IOPCShutdown)
SERVER_UNKNOWN(IOPCCommon)
SERVER_UNKNOWN(IOPCServerList)
SERVER_UNKNOWN(IOPCEnumGUID)
SERVER_UNKNOWN(IOPCServerList2)

/* Reads a string to its end and an array by its count, as a server does. */
static void read_string(LPCWSTR s) {
    while (s && *s) sink ^= (unsigned char)*s++;
}

static void read_guids(const GUID *g, ULONG count) {
    const unsigned char *b = (const unsigned char *)g;
    size_t i;
    for (i = 0; g && i < (size_t)count * sizeof(GUID); i++) sink ^= b[i];
}

static LPWSTR task_string(const char *ascii) {
    size_t n = strlen(ascii) + 1, i;
    LPWSTR s = (LPWSTR)CoTaskMemAlloc(n * sizeof(WCHAR));
    for (i = 0; s && i < n; i++) s[i] = (WCHAR)ascii[i];
    return s;
}

static HRESULT STDMETHODCALLTYPE shutdown_request(IOPCShutdown *This, LPCWSTR reason) {
    (void)This;
    InterlockedIncrement(&server_calls);
    read_string(reason);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE set_locale(IOPCCommon *This, LCID lcid) {
    (void)This, (void)lcid;
    InterlockedIncrement(&server_calls);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE get_locale(IOPCCommon *This, LCID *lcid) {
    (void)This;
    InterlockedIncrement(&server_calls);
    *lcid = 0x0409;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE query_locales(IOPCCommon *This, DWORD *count, LCID **lcids) {
    (void)This;
    InterlockedIncrement(&server_calls);
    *lcids = (LCID *)CoTaskMemAlloc(2 * sizeof(LCID));
    if (!*lcids) return E_OUTOFMEMORY;
    (*lcids)[0] = 0x0409;
    (*lcids)[1] = 0x0407;
    *count = 2;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE get_error_string(IOPCCommon *This, HRESULT code, LPWSTR *text) {
    (void)This, (void)code;
    InterlockedIncrement(&server_calls);
    *text = task_string("error text");
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE set_client_name(IOPCCommon *This, LPCWSTR name) {
    (void)This;
    InterlockedIncrement(&server_calls);
    read_string(name);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE enum_classes(IOPCServerList *This, ULONG ci, CATID *impl, ULONG cr, CATID *req,
                                              IEnumGUID **out) {
    (void)This;
    InterlockedIncrement(&server_calls);
    read_guids(impl, ci);
    read_guids(req, cr);
    if (return_objects) return server_qi(&IID_IEnumGUID, (void **)out);
    *out = NULL;
    return S_FALSE;
}

static HRESULT STDMETHODCALLTYPE class_details(IOPCServerList *This, REFCLSID clsid, LPOLESTR *prog, LPOLESTR *user) {
    (void)This;
    InterlockedIncrement(&server_calls);
    read_guids(clsid, 1);
    *prog = task_string("Test.Server.1");
    *user = task_string("Test server");
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE clsid_from_progid(IOPCServerList *This, LPCOLESTR progid, LPCLSID clsid) {
    (void)This;
    InterlockedIncrement(&server_calls);
    read_string(progid);
    *clsid = CLSID_WidlProxyStub;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE enum_classes2(IOPCServerList2 *This, ULONG ci, CATID *impl, ULONG cr, CATID *req,
                                               IOPCEnumGUID **out) {
    (void)This;
    InterlockedIncrement(&server_calls);
    read_guids(impl, ci);
    read_guids(req, cr);
    if (return_objects) return server_qi(&IID_IOPCEnumGUID, (void **)out);
    *out = NULL;
    return S_FALSE;
}

static HRESULT STDMETHODCALLTYPE class_details2(IOPCServerList2 *This, REFCLSID clsid, LPOLESTR *prog, LPOLESTR *user,
                                                LPOLESTR *vi) {
    (void)This;
    InterlockedIncrement(&server_calls);
    read_guids(clsid, 1);
    *prog = task_string("Test.Server.1");
    *user = task_string("Test server");
    *vi = task_string("Test.Server");
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE clsid_from_progid2(IOPCServerList2 *This, LPCOLESTR progid, LPCLSID clsid) {
    (void)This;
    InterlockedIncrement(&server_calls);
    read_string(progid);
    *clsid = CLSID_WidlProxyStub;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE enum_next(IOPCEnumGUID *This, ULONG celt, GUID *rgelt, ULONG *fetched) {
    ULONG i, n = celt < 3 ? celt : 3;
    (void)This;
    InterlockedIncrement(&server_calls);
    for (i = 0; i < n; i++) rgelt[i] = CLSID_WidlProxyStub;
    *fetched = n;
    return n == celt ? S_OK : S_FALSE;
}

static HRESULT STDMETHODCALLTYPE enum_skip(IOPCEnumGUID *This, ULONG celt) {
    (void)This, (void)celt;
    InterlockedIncrement(&server_calls);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE enum_reset(IOPCEnumGUID *This) {
    (void)This;
    InterlockedIncrement(&server_calls);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE enum_clone(IOPCEnumGUID *This, IOPCEnumGUID **out) {
    (void)This;
    InterlockedIncrement(&server_calls);
    if (return_objects) return server_qi(&IID_IOPCEnumGUID, (void **)out);
    *out = NULL;
    return E_NOTIMPL;
}

static IOPCShutdownVtbl shutdown_vtbl = {IOPCShutdown_qi, IOPCShutdown_addref, IOPCShutdown_release, shutdown_request};
static IOPCCommonVtbl common_vtbl = {IOPCCommon_qi,  IOPCCommon_addref,     IOPCCommon_release, set_locale,
                                     get_locale,     query_locales,         get_error_string,   set_client_name};
static IOPCServerListVtbl list_vtbl = {IOPCServerList_qi, IOPCServerList_addref, IOPCServerList_release,
                                       enum_classes,      class_details,         clsid_from_progid};
static IOPCEnumGUIDVtbl enum_vtbl = {IOPCEnumGUID_qi, IOPCEnumGUID_addref, IOPCEnumGUID_release, enum_next,
                                     enum_skip,       enum_reset,          enum_clone};
static IOPCServerList2Vtbl list2_vtbl = {IOPCServerList2_qi, IOPCServerList2_addref, IOPCServerList2_release,
                                         enum_classes2,      class_details2,         clsid_from_progid2};

/* ---- The server side's channel: reply buffers ---- */

static void *reply_buffer;

static HRESULT STDMETHODCALLTYPE chan_get_buffer(IRpcChannelBuffer *This, RPCOLEMESSAGE *msg, REFIID riid) {
    (void)This, (void)riid;
    if (reply_buffer) HeapFree(GetProcessHeap(), 0, reply_buffer);
    reply_buffer = HeapAlloc(GetProcessHeap(), HEAP_ZERO_MEMORY, msg->cbBuffer ? msg->cbBuffer : 1);
    if (!reply_buffer) return E_OUTOFMEMORY;
    msg->Buffer = reply_buffer;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE chan_send_receive(IRpcChannelBuffer *This, RPCOLEMESSAGE *msg, ULONG *status) {
    (void)This, (void)msg, (void)status;
    return E_NOTIMPL;
}
static HRESULT STDMETHODCALLTYPE chan_free_buffer(IRpcChannelBuffer *This, RPCOLEMESSAGE *msg) {
    (void)This, (void)msg;
    return S_OK;
}
static IRpcChannelBufferVtbl chan_vtbl = PS_CHANNEL_VTBL(chan_get_buffer, chan_send_receive, chan_free_buffer);
static IRpcChannelBuffer server_channel = {&chan_vtbl};

/* ---- Invoking a stub ---- */

static IRpcStubBuffer *stubs[PS_INTERFACES];
/* The reply of the last request the server answered (what the stub marshalled). */
static ndr_msg last_reply;

typedef struct outcome {
    HRESULT hr;
    LONG server_calls;
    LONG access_violations;
} outcome;

/* One request of `len` bytes ending at an inaccessible page (`misalign`: one byte further on). */
static outcome invoke_at(unsigned iface, unsigned method, const void *bytes, size_t len, unsigned drep, int misalign) {
    RPCOLEMESSAGE msg;
    guarded g = guarded_copy(NULL, len + (misalign ? 4 : 0));
    LONG calls = server_calls, avs = access_violations;
    outcome o;
    unsigned char *data = g.data + (misalign ? 1 : 0);
    if (len) memcpy(data, bytes, len);
    memset(&msg, 0, sizeof(msg));
    msg.Buffer = data;
    msg.cbBuffer = (ULONG)len;
    msg.iMethod = method;
    msg.dataRepresentation = drep;
    o.hr = stubs[iface]->lpVtbl->Invoke(stubs[iface], &msg, &server_channel);
    o.server_calls = server_calls - calls;
    o.access_violations = access_violations - avs;
    last_reply.n = 0;
    if (reply_buffer && msg.Buffer == reply_buffer && msg.cbBuffer <= sizeof(last_reply.b)) {
        memcpy(last_reply.b, reply_buffer, msg.cbBuffer);
        last_reply.n = msg.cbBuffer;
    }
    if (reply_buffer) {
        HeapFree(GetProcessHeap(), 0, reply_buffer);
        reply_buffer = NULL;
    }
    guarded_free(&g);
    return o;
}

static outcome invoke(unsigned iface, unsigned method, const ndr_msg *m, unsigned drep) {
    return invoke_at(iface, method, m->b, m->n, drep, 0);
}

/* Refused: a failure, the server not called, nothing read out of bounds. */
#define CHECK_REFUSED(o, what)                                                                            \
    do {                                                                                                  \
        outcome check_o_ = (o);                                                                           \
        if (FAILED(check_o_.hr) && check_o_.server_calls == 0 && check_o_.access_violations == 0) {       \
            test_passed++;                                                                                \
        } else {                                                                                          \
            test_failed++;                                                                                \
            fprintf(stderr, "%s:%d: %s not refused: hr 0x%08lX, %ld server calls, %ld access violations\n", \
                    __FILE__, __LINE__, what, (unsigned long)check_o_.hr, (long)check_o_.server_calls,    \
                    (long)check_o_.access_violations);                                                    \
        }                                                                                                 \
    } while (0)

/* ---- Well-formed requests, one per method ---- */

typedef struct request {
    unsigned iface, method;
    ndr_msg m;
} request;

static request requests[32];
static unsigned request_count;

static ndr_msg *add_request(unsigned iface, unsigned method) {
    request *r = &requests[request_count++];
    r->iface = iface;
    r->method = method;
    r->m = msg_empty();
    return &r->m;
}

static void build_requests(void) {
    ndr_msg *m;
    unsigned l;
    put_string(add_request(PS_SHUTDOWN, 3), "Server shutting down");
    put_u32(add_request(PS_COMMON, 3), 0x0407);
    add_request(PS_COMMON, 4);
    add_request(PS_COMMON, 5);
    put_u32(add_request(PS_COMMON, 6), 0x80004005u);
    put_string(add_request(PS_COMMON, 7), "Client A");
    for (l = 0; l < 2; l++) {
        unsigned iface = l ? PS_SERVER_LIST2 : PS_SERVER_LIST;
        m = add_request(iface, 3);
        put_u32(m, 2);
        put_u32(m, 2);
        put_guids(m, 2);
        put_u32(m, 1);
        put_u32(m, 1);
        put_guids(m, 1);
        put_guids(add_request(iface, 4), 1);
        put_string(add_request(iface, 5), "Test.Server.1");
    }
    put_u32(add_request(PS_ENUM_GUID, 3), 5);
    put_u32(add_request(PS_ENUM_GUID, 4), 2);
    add_request(PS_ENUM_GUID, 5);
    add_request(PS_ENUM_GUID, 6);
}

static void well_formed_requests_reach_the_server(void) {
    unsigned i;
    for (i = 0; i < request_count; i++) {
        outcome o = invoke(requests[i].iface, requests[i].method, &requests[i].m, NDR_LOCAL);
        if (o.hr != S_OK || o.server_calls != 1 || o.access_violations)
            fprintf(stderr, "%s method %u: hr 0x%08lX, %ld calls\n", PS_NAMES[requests[i].iface], requests[i].method,
                    (unsigned long)o.hr, (long)o.server_calls);
        CHECK(o.hr == S_OK && o.server_calls == 1 && o.access_violations == 0);
    }
}

static void truncated_requests_are_refused(void) {
    unsigned i;
    size_t len;
    for (i = 0; i < request_count; i++)
        for (len = 0; len < requests[i].m.n; len++)
            CHECK_REFUSED(invoke_at(requests[i].iface, requests[i].method, requests[i].m.b, len, NDR_LOCAL, 0),
                          "truncated request");
}

static void foreign_representations_unknown_methods_and_misaligned_buffers_are_refused(void) {
    unsigned i, k;
    static const unsigned foreign[] = {NDR_BIG_ENDIAN_REP, 0x01u, 0x0110u};
    for (i = 0; i < request_count; i++) {
        for (k = 0; k < sizeof(foreign) / sizeof(foreign[0]); k++)
            CHECK_REFUSED(invoke(requests[i].iface, requests[i].method, &requests[i].m, foreign[k]),
                          "foreign data representation");
        if (requests[i].m.n)
            CHECK_REFUSED(invoke_at(requests[i].iface, requests[i].method, requests[i].m.b, requests[i].m.n, NDR_LOCAL, 1),
                          "misaligned buffer");
    }
    for (i = 0; i < PS_INTERFACES; i++) {
        static const unsigned beyond[] = {0, 1, 2, 0x7FFF, 0xFFFF};
        ndr_msg m = msg_empty();
        put_u32(&m, 1);
        put_u32(&m, 1);
        for (k = 0; k < sizeof(beyond) / sizeof(beyond[0]); k++)
            CHECK_REFUSED(invoke(i, beyond[k], &m, NDR_LOCAL), "unknown method");
        CHECK_REFUSED(invoke(i, PS_METHODS[i], &m, NDR_LOCAL), "method past the last");
    }
}

/* The audit's requests: cImplemented = 4096 with one GUID on the wire, and the like. */
static void category_counts_must_match_the_wire(void) {
    unsigned l;
    for (l = 0; l < 2; l++) {
        unsigned iface = l ? PS_SERVER_LIST2 : PS_SERVER_LIST;
        ndr_msg m = msg_empty();
        put_u32(&m, 4096);
        put_u32(&m, 1);
        put_guids(&m, 1);
        put_u32(&m, 0);
        put_u32(&m, 0);
        CHECK_REFUSED(invoke(iface, 3, &m, NDR_LOCAL), "cImplemented 4096, one GUID");
        m = msg_empty();
        put_u32(&m, 0);
        put_u32(&m, 0);
        put_u32(&m, 64);
        put_u32(&m, 1);
        put_guids(&m, 1);
        CHECK_REFUSED(invoke(iface, 3, &m, NDR_LOCAL), "cRequired 64, one GUID");
        m = msg_empty();
        put_u32(&m, 4096);
        put_u32(&m, 4096);
        put_guids(&m, 1);
        CHECK_REFUSED(invoke(iface, 3, &m, NDR_LOCAL), "4096 GUIDs claimed, one sent");
        m = msg_empty();
        put_u32(&m, 1);
        put_u32(&m, 4096);
        put_guids(&m, 1);
        put_u32(&m, 0);
        put_u32(&m, 0);
        CHECK_REFUSED(invoke(iface, 3, &m, NDR_LOCAL), "conformance 4096, count 1");
    }
}

/* Next(celt = 0x0FFFFFFF) from a 4-byte request: refused before anything is allocated. */
static void next_counts_are_bounded(void) {
    ndr_msg m = msg_empty();
    outcome o;
    /* The unchecked stand-in would allocate celt x 16 bytes: 4 GB; 16 MiB shows it as well. */
    put_u32(&m, testing_widl ? 0x00100000u : 0x0FFFFFFFu);
    largest_allocation = 0;
    o = invoke(PS_ENUM_GUID, 3, &m, NDR_LOCAL);
    CHECK_REFUSED(o, "Next with a huge celt");
    CHECK_HR(o.hr, INVALID_BOUND);
    CHECK(largest_allocation < 4096);
    printf("stub: Next(celt %s) -> 0x%08lX, largest allocation %lu bytes\n", testing_widl ? "0x00100000" : "0x0FFFFFFF",
           (unsigned long)o.hr, (unsigned long)largest_allocation);
    m = msg_empty();
    put_u32(&m, PS_MAX_ELEMENTS);
    o = invoke(PS_ENUM_GUID, 3, &m, NDR_LOCAL);
    CHECK(o.hr == S_OK && o.server_calls == 1);
    m = msg_empty();
    put_u32(&m, PS_MAX_ELEMENTS + 1);
    CHECK_REFUSED(invoke(PS_ENUM_GUID, 3, &m, NDR_LOCAL), "Next one past the bound");
}

static void strings_must_be_whole(void) {
    static const unsigned targets[][2] = {{PS_SHUTDOWN, 3}, {PS_COMMON, 7}, {PS_SERVER_LIST, 5}, {PS_SERVER_LIST2, 5}};
    unsigned t;
    for (t = 0; t < 4; t++) {
        unsigned iface = targets[t][0], method = targets[t][1];
        ndr_msg m = msg_empty();
        put_u32(&m, 2); /* no NUL */
        put_u32(&m, 0);
        put_u32(&m, 2);
        put_u32(&m, 0x00420041u);
        CHECK_REFUSED(invoke(iface, method, &m, NDR_LOCAL), "unterminated string");
        m = msg_empty();
        put_u32(&m, 0x7FFFFFFFu); /* maximum far beyond the actual count */
        put_u32(&m, 0);
        put_u32(&m, 1);
        put_u32(&m, 0);
        CHECK_REFUSED(invoke(iface, method, &m, NDR_LOCAL), "string maximum beyond its length");
        m = msg_empty();
        put_u32(&m, 0x40000000u); /* a length the bytes do not back */
        put_u32(&m, 0);
        put_u32(&m, 0x40000000u);
        put_u32(&m, 0);
        CHECK_REFUSED(invoke(iface, method, &m, NDR_LOCAL), "string longer than the message");
        m = msg_empty();
        put_u32(&m, 2); /* an offset */
        put_u32(&m, 1);
        put_u32(&m, 1);
        put_u32(&m, 0);
        CHECK_REFUSED(invoke(iface, method, &m, NDR_LOCAL), "string with an offset");
    }
}

/* Random mutations of the well-formed requests: counts replaced by boundary values, bytes flipped,
 * the message cut or lengthened. */
static void mutated_requests_are_answered_safely(unsigned rounds) {
    static const unsigned values[] = {0, 1, 2, 3, 4, 16, 255, 4096, 65535, 65536, 65537, 0x7FFFFFFFu, 0x80000000u,
                                      0x0FFFFFFFu, 0xFFFFFFFFu, 0x10000000u};
    unsigned i, accepted = 0, refused = 0;
    LONG avs = access_violations;
    largest_allocation = 0;
    for (i = 0; i < rounds; i++) {
        const request *r = &requests[ps_random() % request_count];
        ndr_msg m = r->m;
        unsigned mutations = 1 + ps_random() % 3, k;
        outcome o;
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
        o = invoke(r->iface, r->method, &m, NDR_LOCAL);
        if (SUCCEEDED(o.hr)) accepted++;
        else refused++;
        if (o.hr == (HRESULT)EXCEPTION_ACCESS_VIOLATION || o.server_calls > 1 || (FAILED(o.hr) && o.server_calls)) {
            test_failed++;
            fprintf(stderr, "mutated request to %s method %u: hr 0x%08lX, %ld server calls\n", PS_NAMES[r->iface],
                    r->method, (unsigned long)o.hr, (long)o.server_calls);
        }
    }
    CHECK(access_violations == avs);
    /* At most Next's bound of GUIDs (1 MiB) for one call, and the runtime's bookkeeping. */
    CHECK(largest_allocation <= PS_MAX_ELEMENTS * sizeof(GUID) + 64);
    printf("stub fuzz: %u mutated requests, %u accepted, %u refused, %ld access violations, largest allocation %lu bytes\n",
           rounds, accepted, refused, (long)(access_violations - avs), (unsigned long)largest_allocation);
}

/* The interface pointers the stubs write (EnumClassesOfCategories of both lists, Clone) when the server
 * returns an object: in the layout this process's runtime reads, which is what opccomn's reply check
 * (src/proxy/wire.rs) takes for it: under Wine a byte count then the OBJREF, under Windows NDR's
 * MInterfacePointer ([MS-DCOM] 2.2.14: referent ID, conformance = ulCntData, the OBJREF). Either way
 * a standard OBJREF ([MS-DCOM] 2.2.18) for the IID the method declares, then the server's HRESULT. The
 * OBJREF's references are given back (nothing unmarshals it here) and the server's count returns. */
static void interface_pointers_the_stubs_write(void) {
    static const struct {
        unsigned iface, method;
        const IID *iid;
    } methods[3] = {{PS_SERVER_LIST, 3, &IID_IEnumGUID}, {PS_SERVER_LIST2, 3, &IID_IOPCEnumGUID},
                    {PS_ENUM_GUID, 6, &IID_IOPCEnumGUID}};
    int wine = runtime_reads_wine_layout();
    unsigned k, i;
    for (k = 0; k < 3; k++) {
        const request *r = NULL;
        LONG refs = the_server.refs;
        outcome o;
        size_t at, len = 0, end;
        for (i = 0; i < request_count; i++)
            if (requests[i].iface == methods[k].iface && requests[i].method == methods[k].method) r = &requests[i];
        if (!r) continue;
        return_objects = 1;
        o = invoke(r->iface, r->method, &r->m, NDR_LOCAL);
        return_objects = 0;
        CHECK(o.hr == S_OK && o.server_calls == 1 && o.access_violations == 0);
        if (last_reply.n < 8 || get_u32(last_reply.b) == 0) {
            fprintf(stderr, "%s method %u: no interface pointer in the reply (%u bytes)\n", PS_NAMES[methods[k].iface],
                    methods[k].method, (unsigned)last_reply.n);
            test_failed++;
            continue;
        }
        if (wine) {
            at = 4;
            len = get_u32(last_reply.b);
        } else {
            at = 12;
            len = last_reply.n >= 12 && get_u32(last_reply.b + 4) == get_u32(last_reply.b + 8) ? get_u32(last_reply.b + 8) : 0;
        }
        end = (at + len + 3) & ~(size_t)3;
        CHECK(len >= 68 && end + 4 <= last_reply.n);
        if (len < 68 || end + 4 > last_reply.n) continue;
        CHECK(get_u32(last_reply.b + at) == OBJREF_SIGNATURE);
        CHECK(get_u32(last_reply.b + at + 4) == OBJREF_STANDARD);
        CHECK(memcmp(last_reply.b + at + 8, methods[k].iid, sizeof(IID)) == 0);
        CHECK(get_u32(last_reply.b + end) == S_OK);
        printf("stub: %s method %u wrote its interface pointer in %s layout: %s%u bytes of OBJREF, then the HRESULT\n",
               PS_NAMES[methods[k].iface], methods[k].method, wine ? "Wine's" : "NDR's",
               wine ? "a byte count, " : "a referent ID, conformance = ulCntData, ", (unsigned)len);
        release_objref(last_reply.b + at, (ULONG)len);
        if (the_server.refs != refs)
            fprintf(stderr, "%s method %u: %ld server references left\n", PS_NAMES[methods[k].iface], methods[k].method,
                    (long)(the_server.refs - refs));
        CHECK(the_server.refs == refs);
    }
}

int main(int argc, char **argv) {
    IPSFactoryBuffer *factory;
    unsigned i;
    the_server.IOPCShutdown_iface.lpVtbl = &shutdown_vtbl;
    the_server.IOPCCommon_iface.lpVtbl = &common_vtbl;
    the_server.IOPCServerList_iface.lpVtbl = &list_vtbl;
    the_server.IOPCEnumGUID_iface.lpVtbl = &enum_vtbl;
    the_server.IOPCServerList2_iface.lpVtbl = &list2_vtbl;
    CoInitializeEx(NULL, COINIT_MULTITHREADED);
    count_access_violations();
    watch_allocations();
    factory = load_factory(argc, argv);
    for (i = 0; i < PS_INTERFACES; i++) {
        CHECK_HR(factory->lpVtbl->CreateStub(factory, PS_IIDS[i], (IUnknown *)&the_server.IOPCShutdown_iface, &stubs[i]),
                 S_OK);
        if (!stubs[i]) return test_summary("test_stub_requests");
    }
    build_requests();
    well_formed_requests_reach_the_server();
    truncated_requests_are_refused();
    foreign_representations_unknown_methods_and_misaligned_buffers_are_refused();
    category_counts_must_match_the_wire();
    next_counts_are_bounded();
    strings_must_be_whole();
    if (FAILED(testing_widl ? use_widl_proxy_stub() : use_opccomn_proxy_stub_directly())) {
        fprintf(stderr, "the proxy/stub could not be registered in this process\n");
        test_failed++;
    } else {
        interface_pointers_the_stubs_write();
    }
    if (!testing_widl) mutated_requests_are_answered_safely(20000);
    printf("stub: %ld access violations in all\n", (long)access_violations);
    CHECK(access_violations == 0);
    for (i = 0; i < PS_INTERFACES; i++) stubs[i]->lpVtbl->Release(stubs[i]);
    factory->lpVtbl->Release(factory);
    CoUninitialize();
    return test_summary("test_stub_requests");
}
