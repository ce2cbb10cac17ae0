/* Every stub of opccomn.dll's proxy/stub against crafted requests, for every method of every interface
 * it serves (OPC Common and Data Access): nothing here is written per method. The messages come from
 * the layouts the checks are generated from (ps_served.h, made by src/proxy/ndr/tests/served.rs: a
 * request and a reply of each method in this runtime's dialect), and go straight into
 * IRpcStubBuffer::Invoke of the stub of their interface, over a server object whose every method
 * answers E_NOTIMPL without reading its arguments:
 *
 * - the request as made reaches the server;
 * - every proper prefix of it is refused before the server runs;
 * - mutations of it (bytes changed, words set to 0, 1, the bounds and past them, all ones, the
 *   message's length; bytes added) are answered, accepted or refused, without an access violation;
 * - the largest allocation the NDR engine makes for any of them stays within ALLOCATION_LIMIT: what
 *   the bounds allow a count a few bytes can set (IOPCEnumGUID::Next's 65,536 GUIDs, 1 MiB, which the
 *   stub allocates before the server runs); every other array must arrive with its elements.
 *
 * Every request ends where an inaccessible page begins (rounded up to 8 bytes: the checks require a
 * method that aligns to 8 to start at an 8-byte boundary, as the runtime's buffers do), and access
 * violations are counted at first chance, so those the runtime catches count too. Required: 0.
 * `test_served_messages widl` is not offered: the stand-in for the Foundation's proxy/stub has no
 * checks to test (test_stub_requests shows the difference on OPC Common's interfaces). */
#include "ps_harness.h"

#include "ps_served.h"

/* ---- The server: one object answering every method of every interface with E_NOTIMPL ---- */

static LONG server_calls;
static LONG server_refs;

typedef struct any_server {
    const void *const *lpVtbl;
} any_server;

static HRESULT STDMETHODCALLTYPE any_qi(any_server *This, REFIID riid, void **ppv) {
    (void)riid;
    *ppv = This;
    InterlockedIncrement(&server_refs);
    return S_OK;
}
static ULONG STDMETHODCALLTYPE any_addref(any_server *This) {
    (void)This;
    return (ULONG)InterlockedIncrement(&server_refs);
}
static ULONG STDMETHODCALLTYPE any_release(any_server *This) {
    (void)This;
    return (ULONG)InterlockedDecrement(&server_refs);
}
/* Every method after IUnknown's: counts the call and reads nothing. Declared without parameters
 * (cdecl): it pops nothing, and the runtime's call of a server method restores its stack pointer
 * itself, so one function serves every signature on x86 as on x64. */
static HRESULT any_method(void) {
    InterlockedIncrement(&server_calls);
    return E_NOTIMPL;
}

#define ANY_METHODS 16
static const void *any_vtbl[3 + ANY_METHODS];
static any_server the_server = {any_vtbl};

static void make_server(void) {
    unsigned i;
    any_vtbl[0] = (const void *)any_qi;
    any_vtbl[1] = (const void *)any_addref;
    any_vtbl[2] = (const void *)any_release;
    for (i = 3; i < 3 + ANY_METHODS; i++) any_vtbl[i] = (const void *)any_method;
}

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

typedef struct outcome {
    HRESULT hr;
    LONG server_calls;
    LONG access_violations;
} outcome;

/* A copy of `len` bytes ending where an inaccessible page begins, rounded up to 8 (the copy starts at
 * an 8-byte boundary); the bytes between `len` and the page are 0xCC. */
static guarded guarded_copy8(const void *bytes, size_t len) {
    guarded g = guarded_copy(NULL, (len + 7) & ~(size_t)7);
    if (len) memcpy(g.data, bytes, len);
    g.len = len;
    return g;
}

static outcome invoke(IRpcStubBuffer *stub, unsigned method, const unsigned char *bytes, size_t len) {
    RPCOLEMESSAGE msg;
    guarded g = guarded_copy8(bytes, len);
    LONG calls = server_calls, avs = access_violations;
    outcome o;
    memset(&msg, 0, sizeof msg);
    msg.Buffer = g.data;
    msg.cbBuffer = (ULONG)len;
    msg.iMethod = method;
    msg.dataRepresentation = NDR_LOCAL;
    o.hr = stub->lpVtbl->Invoke(stub, &msg, &server_channel);
    o.server_calls = server_calls - calls;
    o.access_violations = access_violations - avs;
    if (reply_buffer) {
        HeapFree(GetProcessHeap(), 0, reply_buffer);
        reply_buffer = NULL;
    }
    guarded_free(&g);
    return o;
}

static void report(const ps_served *m, const char *what, size_t len, outcome o) {
    fprintf(stderr, "%s::%s %s (%u bytes): hr 0x%08lX, %ld server calls, %ld access violations\n", m->iface,
            m->name, what, (unsigned)len, (unsigned long)o.hr, (long)o.server_calls, (long)o.access_violations);
}

/* The values a mutation writes over a word: what counts are compared with. */
static unsigned mutation_word(unsigned len) {
    static const unsigned words[] = {0u,        1u,          2u,         0xFFFFu,     0x10000u, 0x10001u,
                                     0x100000u, 0x100001u,   0x7FFFFFFFu, 0xFFFFFFFFu, 0x20000u, 0x72657355u};
    unsigned pick = ps_random() % (sizeof words / sizeof words[0] + 1);
    return pick < sizeof words / sizeof words[0] ? words[pick] : len;
}

#define MUTATIONS 48
#define ALLOCATION_LIMIT (1024 * 1024 + 4096)

static void check_requests(IPSFactoryBuffer *factory, int wine) {
    IRpcStubBuffer *stub = NULL;
    const GUID *stub_iid = NULL;
    unsigned char buf[4096];
    unsigned i, methods = 0;
    for (i = 0; i < PS_SERVED_COUNT; i++) {
        const ps_served *m = &PS_SERVED[i];
        outcome o;
        size_t len, k;
        SIZE_T before;
        unsigned r;
        if (m->wine != (unsigned)wine) continue;
        if (!stub_iid || !IsEqualGUID(stub_iid, &m->iid)) {
            if (stub) stub->lpVtbl->Release(stub);
            stub = NULL;
            CHECK_HR(factory->lpVtbl->CreateStub(factory, &m->iid, (IUnknown *)&the_server, &stub), S_OK);
            stub_iid = &m->iid;
            if (!stub) continue;
        }
        methods++;
        /* As made: it reaches the server. */
        o = invoke(stub, m->method, m->request, m->request_len);
        if (o.hr == S_OK && o.server_calls == 1 && o.access_violations == 0) test_passed++;
        else {
            test_failed++;
            report(m, "well-formed request not served", m->request_len, o);
        }
        /* Cut short anywhere: refused before the server runs. */
        for (len = 0; len < m->request_len; len++) {
            o = invoke(stub, m->method, m->request, len);
            if (FAILED(o.hr) && o.server_calls == 0 && o.access_violations == 0) test_passed++;
            else {
                test_failed++;
                report(m, "prefix not refused", len, o);
            }
        }
        /* Mutated: answered either way, never read out of bounds. */
        for (r = 0; r < MUTATIONS && m->request_len <= sizeof buf - 64; r++) {
            unsigned changes = 1 + ps_random() % 3, c;
            len = m->request_len;
            memcpy(buf, m->request, len);
            for (c = 0; c < changes && len; c++) {
                size_t at = ps_random() % len;
                unsigned w;
                switch (ps_random() % 3) {
                case 0:
                    buf[at] = (unsigned char)ps_random();
                    break;
                case 1:
                    at &= ~(size_t)3;
                    if (at + 4 > len) break;
                    w = mutation_word((unsigned)len);
                    memcpy(buf + at, &w, 4);
                    break;
                default:
                    for (k = 0; k < 1 + ps_random() % 16; k++) buf[len++] = (unsigned char)ps_random();
                    break;
                }
            }
            before = largest_allocation;
            o = invoke(stub, m->method, buf, len);
            if (largest_allocation > ALLOCATION_LIMIT && before <= ALLOCATION_LIMIT) {
                size_t b;
                report(m, "mutated request made a large allocation", len, o);
                for (b = 0; b < len; b++) fprintf(stderr, "%02x", buf[b]);
                fprintf(stderr, "\n");
            }
            if (o.access_violations == 0) test_passed++;
            else {
                test_failed++;
                report(m, "mutated request read out of bounds", len, o);
            }
        }
        /* One past the interface's last method: refused. */
        if (i + 1 == PS_SERVED_COUNT || !IsEqualGUID(&PS_SERVED[i + 1].iid, &m->iid)) {
            o = invoke(stub, m->method + 1, m->request, m->request_len);
            if (FAILED(o.hr) && o.server_calls == 0) test_passed++;
            else {
                test_failed++;
                report(m, "method past the last not refused", m->request_len, o);
            }
        }
    }
    if (stub) stub->lpVtbl->Release(stub);
    printf("requests of %u methods, each whole, cut short at every length and mutated %u times\n", methods,
           MUTATIONS);
    CHECK(methods >= 96);
}

int main(int argc, char **argv) {
    IPSFactoryBuffer *factory;
    int wine;
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    count_access_violations();
    watch_allocations();
    make_server();
    (void)argc, (void)argv;
    CHECK_HR(OpcDllGetClassObject(&CLSID_OpcComnProxyStub, &IID_IPSFactoryBuffer, (void **)&factory), S_OK);
    wine = runtime_reads_wine_layout();
    printf("messages in %s's dialect\n", wine ? "Wine" : "NDR");
    check_requests(factory, wine);
    CHECK(access_violations == 0);
    printf("largest allocation of the NDR engine: %lu bytes\n", (unsigned long)largest_allocation);
    CHECK(largest_allocation <= ALLOCATION_LIMIT);
    factory->lpVtbl->Release(factory);
    CoRevokeMallocSpy();
    CoUninitialize();
    return test_summary("test_served_messages");
}
