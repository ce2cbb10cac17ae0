/* Every stub of opccomn.dll's proxy/stub against crafted requests, for every method of every interface
 * it serves (OPC Common, Data Access, Alarms & Events and HDA): nothing here is written per method. The messages come from
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
 * Then every proxy, connected to a channel that answers with a chosen reply (ending where an
 * inaccessible page begins), called with the same arguments the requests were made from (every
 * integer 1, every pointer to 64 zero bytes followed by canary bytes: ps_args.h, generated from the
 * IDL, says which parameter is which): the reply as made comes through with its HRESULT; every
 * proper prefix of it fails; mutations of it are answered either way; never an access violation or
 * a canary byte changed.
 *
 * Every request ends where an inaccessible page begins (rounded up to 8 bytes: the checks require a
 * method that aligns to 8 to start at an 8-byte boundary, as the runtime's buffers do), and access
 * violations are counted at first chance, so those the runtime catches count too. Required: 0.
 * `test_served_messages unchecked` runs the same against the widl stand-in for the Foundation's
 * proxy/stub of the Data Access interfaces (opc_classic_widl_ps.dll, no checks): requests and replies
 * cut short make its stubs and proxies fault hundreds of times (x64 under Wine), and under 32-bit Wine
 * it does not end within 300 s. That is what the checks prevent; it is run by hand, not in CI. */
#include "ps_harness.h"

#include "ps_args.h"
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

/* Enough slots for the largest method number served (IOPCEventServer2 has 25); make_server checks. */
#define ANY_METHODS 61
static const void *any_vtbl[3 + ANY_METHODS];
static any_server the_server = {any_vtbl};

static void make_server(void) {
    unsigned i;
    for (i = 0; i < PS_SERVED_COUNT; i++) {
        if (PS_SERVED[i].method >= 3 + ANY_METHODS) {
            fprintf(stderr, "%s::%s is method %u: the test server has %u slots\n", PS_SERVED[i].iface,
                    PS_SERVED[i].name, PS_SERVED[i].method, 3 + ANY_METHODS);
            exit(1);
        }
    }
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

/* Testing the unchecked stand-in (all but OPC Common's interfaces). */
static int unchecked;

/* The methods of ps_served.h this run covers. */
static unsigned expected_methods(int wine) {
    unsigned i, n = 0;
    for (i = 0; i < PS_SERVED_COUNT; i++) n += PS_SERVED[i].wine == (unsigned)wine && !(unchecked && PS_SERVED[i].spec_common);
    return n;
}

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
        if (m->wine != (unsigned)wine || (unchecked && m->spec_common)) continue;
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
    CHECK(methods == expected_methods(wine));
}


/* ---- The proxies: replies from a channel, calls with generic arguments ---- */

/* The reply the client channel answers with, and where the proxy's request went. */
static const unsigned char *answer;
static size_t answer_len;
static guarded answer_copy;
static LONG requests_sent;

static HRESULT STDMETHODCALLTYPE cchan_get_buffer(IRpcChannelBuffer *This, RPCOLEMESSAGE *msg, REFIID riid) {
    (void)This, (void)riid;
    msg->Buffer = HeapAlloc(GetProcessHeap(), HEAP_ZERO_MEMORY, msg->cbBuffer ? msg->cbBuffer : 1);
    return msg->Buffer ? S_OK : E_OUTOFMEMORY;
}
static HRESULT STDMETHODCALLTYPE cchan_send_receive(IRpcChannelBuffer *This, RPCOLEMESSAGE *msg, ULONG *status) {
    (void)This;
    InterlockedIncrement(&requests_sent);
    HeapFree(GetProcessHeap(), 0, msg->Buffer);
    answer_copy = guarded_copy8(answer, answer_len);
    msg->Buffer = answer_copy.data;
    msg->cbBuffer = (ULONG)answer_len;
    msg->dataRepresentation = NDR_LOCAL;
    if (status) *status = 0;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cchan_free_buffer(IRpcChannelBuffer *This, RPCOLEMESSAGE *msg) {
    (void)This;
    if (answer_copy.base && msg->Buffer == answer_copy.data) guarded_free(&answer_copy);
    else if (msg->Buffer) HeapFree(GetProcessHeap(), 0, msg->Buffer);
    msg->Buffer = NULL;
    return S_OK;
}
static IRpcChannelBufferVtbl cchan_vtbl = PS_CHANNEL_VTBL(cchan_get_buffer, cchan_send_receive, cchan_free_buffer);
static IRpcChannelBuffer client_channel = {&cchan_vtbl};

/* Each pointer argument: 128 zero bytes (a valid value of every parameter type: an empty string, a
 * NULL pointer, VT_EMPTY, a zero structure or GUID; the largest structure passed [in], A&E's
 * ONEVENTSTRUCT, has 104 bytes on x64) then canary bytes up to 4 KiB. */
#define ARG_BYTES 4096
#define ARG_VALUE 128
#define CANARY 0xCD
#define MAX_ARGS 16
static unsigned char (*arg_memory)[ARG_BYTES];

static void reset_arguments(void) {
    unsigned i;
    for (i = 0; i < MAX_ARGS; i++) {
        memset(arg_memory[i], 0, ARG_VALUE);
        memset(arg_memory[i] + ARG_VALUE, CANARY, ARG_BYTES - ARG_VALUE);
    }
}

/* Whether every canary byte is intact. */
static int canaries_intact(void) {
    unsigned i, k;
    for (i = 0; i < MAX_ARGS; i++)
        for (k = ARG_VALUE; k < ARG_BYTES; k++)
            if (arg_memory[i][k] != CANARY) return 0;
    return 1;
}

/* Calls vtable entry `method` of `self` with `n` arguments of pointer size. */
#if defined(__i386__)
static HRESULT call_method(void *self, unsigned method, const UINT_PTR *args, UINT_PTR n) {
    void *fn = (*(void ***)self)[method];
    HRESULT hr;
    /* stdcall: the method pops what it takes; the stack pointer is restored from esi whatever that is. */
    __asm__ volatile("movl %%esp, %%esi\n\t"
                     "1:\n\t"
                     "testl %%ecx, %%ecx\n\t"
                     "jz 2f\n\t"
                     "decl %%ecx\n\t"
                     "pushl (%%edx,%%ecx,4)\n\t"
                     "jmp 1b\n"
                     "2:\n\t"
                     "pushl %%edi\n\t"
                     "call *%%ebx\n\t"
                     "movl %%esi, %%esp\n\t"
                     : "=a"(hr), "+c"(n), "+d"(args)
                     : "b"(fn), "D"(self)
                     : "esi", "memory", "cc");
    return hr;
}
#else
typedef HRESULT(STDMETHODCALLTYPE *method16)(void *, UINT_PTR, UINT_PTR, UINT_PTR, UINT_PTR, UINT_PTR, UINT_PTR,
                                             UINT_PTR, UINT_PTR, UINT_PTR, UINT_PTR, UINT_PTR, UINT_PTR, UINT_PTR,
                                             UINT_PTR, UINT_PTR, UINT_PTR);
static HRESULT call_method(void *self, unsigned method, const UINT_PTR *a, UINT_PTR n) {
    /* The caller cleans the stack: arguments past the method's own are ignored. */
    method16 fn = (method16)(*(void ***)self)[method];
    (void)n;
    return fn(self, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12], a[13], a[14],
              a[15]);
}
#endif

static const char *args_of(const ps_served *m) {
    unsigned i;
    for (i = 0; i < PS_ARGS_COUNT; i++)
        if (strcmp(PS_ARGS[i][0], m->iface) == 0 && strcmp(PS_ARGS[i][1], m->name) == 0) return PS_ARGS[i][2];
    return NULL;
}

/* The argument slots a shape takes (a FILETIME by value two on x86). */
static size_t slots_of(const char *shape) {
    size_t n = 0;
    for (; *shape; shape++) n += *shape == 'f' && sizeof(void *) == 4 ? 2 : 1;
    return n;
}

typedef struct call_outcome {
    HRESULT hr;
    LONG access_violations;
    int canaries;
} call_outcome;

static call_outcome call_with_reply(void *proxy, const ps_served *m, const char *shape, const unsigned char *reply,
                                    size_t len) {
    UINT_PTR args[MAX_ARGS];
    LONG avs = access_violations;
    call_outcome o;
    unsigned k, slot = 0;
    memset(args, 0, sizeof args);
    reset_arguments();
    for (k = 0; shape[k] && slot < MAX_ARGS; k++) {
        if (shape[k] == 'p') args[slot++] = (UINT_PTR)arg_memory[k];
        else args[slot++] = 1;
        /* A FILETIME {1, 0} by value: one slot on x64, two on x86 (its high half 0). */
        if (shape[k] == 'f' && sizeof(void *) == 4 && slot < MAX_ARGS) args[slot++] = 0;
    }
    answer = reply;
    answer_len = len;
    o.hr = call_method(proxy, m->method, args, (UINT_PTR)slot);
    o.access_violations = access_violations - avs;
    o.canaries = canaries_intact();
    return o;
}

static void check_replies(IPSFactoryBuffer *factory, int wine) {
    unsigned char buf[4096];
    unsigned i, methods = 0;
    arg_memory = (unsigned char(*)[ARG_BYTES])VirtualAlloc(NULL, MAX_ARGS * ARG_BYTES, MEM_COMMIT | MEM_RESERVE,
                                                          PAGE_READWRITE);
    if (!arg_memory) {
        CHECK(0);
        return;
    }
    for (i = 0; i < PS_SERVED_COUNT; i++) {
        const ps_served *m = &PS_SERVED[i];
        const char *shape = args_of(m);
        IRpcProxyBuffer *buffer = NULL;
        void *proxy = NULL;
        call_outcome o;
        size_t len, k;
        unsigned r;
        if (m->wine != (unsigned)wine || (unchecked && m->spec_common)) continue;
        if (!shape || strchr(shape, 'v') || strchr(shape, 'h') || slots_of(shape) > MAX_ARGS) {
            fprintf(stderr, "%s::%s: no generic call for its parameters\n", m->iface, m->name);
            test_failed++;
            continue;
        }
        CHECK_HR(factory->lpVtbl->CreateProxy(factory, NULL, &m->iid, &buffer, &proxy), S_OK);
        if (!buffer || !proxy) continue;
        CHECK_HR(buffer->lpVtbl->Connect(buffer, &client_channel), S_OK);
        methods++;
        /* As made: its HRESULT (1, S_FALSE) comes back. */
        o = call_with_reply(proxy, m, shape, m->reply, m->reply_len);
        if (o.hr == S_FALSE && o.access_violations == 0 && o.canaries) test_passed++;
        else {
            test_failed++;
            fprintf(stderr, "%s::%s: well-formed reply: hr 0x%08lX, %ld access violations, canaries %s\n", m->iface,
                    m->name, (unsigned long)o.hr, (long)o.access_violations, o.canaries ? "intact" : "changed");
        }
        /* Cut short anywhere: the call fails. */
        for (len = 0; len < m->reply_len; len++) {
            o = call_with_reply(proxy, m, shape, m->reply, len);
            if (FAILED(o.hr) && o.access_violations == 0 && o.canaries) test_passed++;
            else {
                test_failed++;
                fprintf(stderr, "%s::%s: reply cut at %u: hr 0x%08lX, %ld access violations, canaries %s\n", m->iface,
                        m->name, (unsigned)len, (unsigned long)o.hr, (long)o.access_violations,
                        o.canaries ? "intact" : "changed");
            }
        }
        /* Mutated: either way, nothing out of bounds. */
        for (r = 0; r < MUTATIONS && m->reply_len <= sizeof buf - 64; r++) {
            unsigned changes = 1 + ps_random() % 3, c, w;
            len = m->reply_len;
            memcpy(buf, m->reply, len);
            for (c = 0; c < changes && len; c++) {
                size_t at = ps_random() % len;
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
            o = call_with_reply(proxy, m, shape, buf, len);
            if (o.access_violations == 0 && o.canaries) test_passed++;
            else {
                test_failed++;
                fprintf(stderr, "%s::%s: mutated reply (%u bytes): hr 0x%08lX, %ld access violations, canaries %s\n",
                        m->iface, m->name, (unsigned)len, (unsigned long)o.hr, (long)o.access_violations,
                        o.canaries ? "intact" : "changed");
            }
        }
        buffer->lpVtbl->Disconnect(buffer);
        ((IUnknown *)proxy)->lpVtbl->Release((IUnknown *)proxy);
        buffer->lpVtbl->Release(buffer);
    }
    printf("replies of %u methods, each whole, cut short at every length and mutated %u times; %ld requests sent\n",
           methods, MUTATIONS, (long)requests_sent);
    CHECK(methods == expected_methods(wine));
    VirtualFree(arg_memory, 0, MEM_RELEASE);
}

int main(int argc, char **argv) {
    IPSFactoryBuffer *factory;
    int wine;
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    count_access_violations();
    watch_allocations();
    make_server();
    unchecked = argc > 1 && strcmp(argv[1], "unchecked") == 0;
    if (unchecked) {
        static const CLSID classic = {0xC3000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0xDA, 0x01}};
        HMODULE dll = LoadLibraryW(L"opc_classic_widl_ps.dll");
        OopGetClassObjectFn get =
            dll ? (OopGetClassObjectFn)(void (*)(void))GetProcAddress(dll, "DllGetClassObject") : NULL;
        if (!get || FAILED(get(&classic, &IID_IPSFactoryBuffer, (void **)&factory))) {
            fprintf(stderr, "no opc_classic_widl_ps.dll\n");
            return 2;
        }
        printf("proxy/stub under test: opc_classic_widl_ps.dll (unchecked stand-in)\n");
    } else {
        CHECK_HR(OpcDllGetClassObject(&CLSID_OpcComnProxyStub, &IID_IPSFactoryBuffer, (void **)&factory), S_OK);
    }
    wine = runtime_reads_wine_layout();
    printf("messages in %s's dialect\n", wine ? "Wine" : "NDR");
    check_requests(factory, wine);
    check_replies(factory, wine);
    CHECK(access_violations == 0);
    printf("largest allocation of the NDR engine: %lu bytes\n", (unsigned long)largest_allocation);
    CHECK(largest_allocation <= ALLOCATION_LIMIT);
    factory->lpVtbl->Release(factory);
    CoRevokeMallocSpy();
    CoUninitialize();
    return test_summary("test_served_messages");
}
