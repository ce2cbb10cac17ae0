/* Shared by the proxy/stub robustness tests (test_stub_requests.c, test_proxy_replies.c; Windows, run
 * under Wine): the proxy/stub factory under test (opccomn.dll's, or with "widl" the unchecked stand-in
 * for the Foundation's opccomn_ps.dll, to show that the tests catch what the checks prevent), NDR
 * messages built by hand, buffers that end at an inaccessible page, a count of access violations
 * (first chance, so those the runtime catches count too) and the process's private memory. */
#ifndef OPCCOMN_PS_HARNESS_H
#define OPCCOMN_PS_HARNESS_H

#include "oop.h"


#define NDR_LOCAL 0x10u
#define NDR_BIG_ENDIAN_REP 0x00u
#define BAD_STUB_DATA HRESULT_FROM_WIN32(RPC_X_BAD_STUB_DATA)
#define INVALID_BOUND HRESULT_FROM_WIN32(RPC_S_INVALID_BOUND)
#define PROCNUM_OUT_OF_RANGE HRESULT_FROM_WIN32(RPC_S_PROCNUM_OUT_OF_RANGE)
/* The most elements of an array (src/proxy/wire.rs, MAX_ELEMENTS). */
#define PS_MAX_ELEMENTS 65536u

/* Interface numbers as src/proxy/opccomn_ps.c numbers them, and their method counts. */
enum { PS_SHUTDOWN, PS_COMMON, PS_SERVER_LIST, PS_ENUM_GUID, PS_SERVER_LIST2, PS_INTERFACES };
static const IID *const PS_IIDS[PS_INTERFACES] = {&IID_IOPCShutdown, &IID_IOPCCommon, &IID_IOPCServerList,
                                                  &IID_IOPCEnumGUID, &IID_IOPCServerList2};
static const char *const PS_NAMES[PS_INTERFACES] = {"IOPCShutdown", "IOPCCommon", "IOPCServerList", "IOPCEnumGUID",
                                                    "IOPCServerList2"};
static const unsigned PS_METHODS[PS_INTERFACES] = {4, 8, 6, 7, 6};

/* ---- Access violations ---- */

static volatile LONG access_violations;

static LONG CALLBACK count_access_violation(EXCEPTION_POINTERS *info) {
    if (info->ExceptionRecord->ExceptionCode == EXCEPTION_ACCESS_VIOLATION) InterlockedIncrement(&access_violations);
    return EXCEPTION_CONTINUE_SEARCH;
}

static void count_access_violations(void) {
    AddVectoredExceptionHandler(1, count_access_violation);
}

/* ---- The largest task-memory allocation (what the NDR engine allocates for a call) ---- */

static volatile SIZE_T largest_allocation;

static HRESULT STDMETHODCALLTYPE spy_qi(IMallocSpy *This, REFIID riid, void **ppv) {
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IMallocSpy)) {
        *ppv = This;
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE spy_addref(IMallocSpy *This) { (void)This; return 2; }
static ULONG STDMETHODCALLTYPE spy_release(IMallocSpy *This) { (void)This; return 1; }
static SIZE_T STDMETHODCALLTYPE spy_pre_alloc(IMallocSpy *This, SIZE_T size) {
    (void)This;
    if (size > largest_allocation) largest_allocation = size;
    return size;
}
static void *STDMETHODCALLTYPE spy_post_alloc(IMallocSpy *This, void *p) { (void)This; return p; }
static void *STDMETHODCALLTYPE spy_pre_free(IMallocSpy *This, void *p, BOOL spyed) { (void)This, (void)spyed; return p; }
static void STDMETHODCALLTYPE spy_post_free(IMallocSpy *This, BOOL spyed) { (void)This, (void)spyed; }
static SIZE_T STDMETHODCALLTYPE spy_pre_realloc(IMallocSpy *This, void *p, SIZE_T size, void **out, BOOL spyed) {
    (void)This, (void)spyed;
    if (size > largest_allocation) largest_allocation = size;
    *out = p;
    return size;
}
static void *STDMETHODCALLTYPE spy_post_realloc(IMallocSpy *This, void *p, BOOL spyed) { (void)This, (void)spyed; return p; }
static void *STDMETHODCALLTYPE spy_pre_get_size(IMallocSpy *This, void *p, BOOL spyed) { (void)This, (void)spyed; return p; }
static SIZE_T STDMETHODCALLTYPE spy_post_get_size(IMallocSpy *This, SIZE_T size, BOOL spyed) { (void)This, (void)spyed; return size; }
static void *STDMETHODCALLTYPE spy_pre_did_alloc(IMallocSpy *This, void *p, BOOL spyed) { (void)This, (void)spyed; return p; }
static int STDMETHODCALLTYPE spy_post_did_alloc(IMallocSpy *This, void *p, BOOL spyed, int actual) {
    (void)This, (void)p, (void)spyed;
    return actual;
}
static void STDMETHODCALLTYPE spy_pre_heap_minimize(IMallocSpy *This) { (void)This; }
static void STDMETHODCALLTYPE spy_post_heap_minimize(IMallocSpy *This) { (void)This; }
static IMallocSpyVtbl spy_vtbl = {spy_qi,           spy_addref,        spy_release,         spy_pre_alloc,
                                  spy_post_alloc,   spy_pre_free,      spy_post_free,       spy_pre_realloc,
                                  spy_post_realloc, spy_pre_get_size,  spy_post_get_size,   spy_pre_did_alloc,
                                  spy_post_did_alloc, spy_pre_heap_minimize, spy_post_heap_minimize};
static IMallocSpy allocation_spy = {&spy_vtbl};

/* Watches every CoTaskMemAlloc of this process from now on (the NDR engine's allocations). */
static void watch_allocations(void) {
    HRESULT hr = CoRegisterMallocSpy(&allocation_spy);
    if (FAILED(hr)) {
        fprintf(stderr, "CoRegisterMallocSpy: 0x%08lX\n", (unsigned long)hr);
        exit(2);
    }
}

/* ---- The factory under test ---- */

static int testing_widl;

static IPSFactoryBuffer *load_factory(int argc, char **argv) {
    IPSFactoryBuffer *factory = NULL;
    HRESULT hr;
    testing_widl = argc > 1 && strcmp(argv[1], "widl") == 0;
    if (testing_widl) {
        HMODULE dll = LoadLibraryW(L"opccomn_widl_ps.dll");
        OopGetClassObjectFn get = dll ? (OopGetClassObjectFn)(void (*)(void))GetProcAddress(dll, "DllGetClassObject") : NULL;
        hr = get ? get(&CLSID_WidlProxyStub, &IID_IPSFactoryBuffer, (void **)&factory) : E_FAIL;
    } else {
        hr = OpcDllGetClassObject(&CLSID_OpcComnProxyStub, &IID_IPSFactoryBuffer, (void **)&factory);
    }
    if (FAILED(hr) || !factory) {
        fprintf(stderr, "no proxy/stub factory: 0x%08lX\n", (unsigned long)hr);
        exit(2);
    }
    printf("proxy/stub under test: %s\n", testing_widl ? "opccomn_widl_ps.dll (unchecked stand-in)" : "opccomn.dll");
    return factory;
}

/* ---- NDR messages ---- */

/* ---- A test's stand-in RPC channel: a static object (no reference count), local destination ---- */

static HRESULT STDMETHODCALLTYPE ps_chan_qi(IRpcChannelBuffer *This, REFIID riid, void **ppv) {
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IRpcChannelBuffer)) {
        *ppv = This;
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE ps_chan_addref(IRpcChannelBuffer *This) {
    (void)This;
    return 2;
}
static ULONG STDMETHODCALLTYPE ps_chan_release(IRpcChannelBuffer *This) {
    (void)This;
    return 1;
}
static HRESULT STDMETHODCALLTYPE ps_chan_get_dest_ctx(IRpcChannelBuffer *This, DWORD *ctx, void **pv) {
    (void)This;
    *ctx = MSHCTX_LOCAL;
    *pv = NULL;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE ps_chan_is_connected(IRpcChannelBuffer *This) {
    (void)This;
    return S_OK;
}

/* The vtable of a channel whose buffer handling is the test's own. */
#define PS_CHANNEL_VTBL(get_buffer, send_receive, free_buffer)                                            \
    {ps_chan_qi,   ps_chan_addref,       ps_chan_release,      (get_buffer),                             \
     (send_receive), (free_buffer), ps_chan_get_dest_ctx, ps_chan_is_connected}

typedef struct ndr_msg {
    unsigned char b[8192];
    size_t n;
} ndr_msg;

static void put_u32(ndr_msg *m, unsigned v) {
    while (m->n % 4) m->b[m->n++] = 0;
    memcpy(m->b + m->n, &v, 4);
    m->n += 4;
}

static void put_guids(ndr_msg *m, unsigned count) {
    unsigned i;
    while (m->n % 4) m->b[m->n++] = 0;
    for (i = 0; i < count * 16; i++) m->b[m->n++] = (unsigned char)(0x40 + i);
}

/* A [string] wide string: maximum = actual = units with the NUL, offset 0. */
static void put_string(ndr_msg *m, const char *ascii) {
    unsigned units = (unsigned)strlen(ascii) + 1, i;
    put_u32(m, units);
    put_u32(m, 0);
    put_u32(m, units);
    for (i = 0; i < units; i++) {
        m->b[m->n++] = (unsigned char)ascii[i];
        m->b[m->n++] = 0;
    }
}

/* Bytes as they are, from a 4-byte boundary (an OBJREF is bytes to NDR). */
static void put_bytes(ndr_msg *m, const void *bytes, size_t n) {
    while (m->n % 4) m->b[m->n++] = 0;
    memcpy(m->b + m->n, bytes, n);
    m->n += n;
}

/* ---- Interface pointers ([MS-DCOM] 2.2.14 MInterfacePointer, 2.2.18 OBJREF) ---- */

#define OBJREF_SIGNATURE 0x574F454Du /* "MEOW" */
#define OBJREF_STANDARD 1u
#define OBJREF_MAX 1024u
/* The referent ID Windows gives the first pointer of a message (any value but 0 is a pointer). */
#define NDR_REFERENT_ID 0x00020000u

/* Whether this process's rpcrt4 is Wine's, which writes and reads interface pointers in its own layout
 * (a byte count, then the OBJREF) rather than NDR's (as Windows' does): Wine's ntdll exports
 * wine_get_version. */
static int runtime_reads_wine_layout(void) {
    HMODULE ntdll = GetModuleHandleW(L"ntdll.dll");
    return ntdll && GetProcAddress(ntdll, "wine_get_version");
}

/* What the runtime writes for `unk` as `iid` (CoMarshalInterface: MSHCTX_LOCAL, MSHLFLAGS_NORMAL, so
 * the references it holds go to whoever unmarshals it, or back with release_objref): its length, 0
 * when it cannot. */
static ULONG marshal_objref(IUnknown *unk, REFIID iid, unsigned char out[OBJREF_MAX]) {
    IStream *stream = NULL;
    HGLOBAL global = NULL;
    ULARGE_INTEGER end;
    LARGE_INTEGER zero;
    ULONG len = 0;
    void *bytes;
    zero.QuadPart = 0;
    if (FAILED(CreateStreamOnHGlobal(NULL, TRUE, &stream))) return 0;
    if (SUCCEEDED(CoMarshalInterface(stream, iid, unk, MSHCTX_LOCAL, NULL, MSHLFLAGS_NORMAL)) &&
        SUCCEEDED(stream->lpVtbl->Seek(stream, zero, STREAM_SEEK_CUR, &end)) && end.QuadPart <= OBJREF_MAX &&
        SUCCEEDED(GetHGlobalFromStream(stream, &global)) && (bytes = GlobalLock(global)) != NULL) {
        len = (ULONG)end.QuadPart;
        memcpy(out, bytes, len);
        GlobalUnlock(global);
    }
    stream->lpVtbl->Release(stream);
    return len;
}

/* Gives back the references of an OBJREF nobody unmarshalled (CoReleaseMarshalData). */
static void release_objref(const unsigned char *objref, ULONG len) {
    IStream *stream = NULL;
    LARGE_INTEGER zero;
    zero.QuadPart = 0;
    if (FAILED(CreateStreamOnHGlobal(NULL, TRUE, &stream))) return;
    if (SUCCEEDED(stream->lpVtbl->Write(stream, objref, len, NULL)) &&
        SUCCEEDED(stream->lpVtbl->Seek(stream, zero, STREAM_SEEK_SET, NULL)))
        CoReleaseMarshalData(stream);
    stream->lpVtbl->Release(stream);
}

/* `[out] I **` in NDR's layout, [MS-DCOM] 2.2.14 PMInterfacePointer as Windows writes it: a referent
 * ID, then MInterfacePointer (a conformant structure: its conformance, ulCntData, the OBJREF). */
static void put_ndr_interface_pointer(ndr_msg *m, const unsigned char *objref, ULONG len) {
    put_u32(m, NDR_REFERENT_ID);
    put_u32(m, len);
    put_u32(m, len);
    put_bytes(m, objref, len);
}

/* The same in Wine's layout: the byte count, the OBJREF. */
static void put_wine_interface_pointer(ndr_msg *m, const unsigned char *objref, ULONG len) {
    put_u32(m, len);
    put_bytes(m, objref, len);
}

static unsigned get_u32(const unsigned char *b) {
    unsigned v;
    memcpy(&v, b, 4);
    return v;
}

static ndr_msg msg_empty(void) {
    ndr_msg m;
    m.n = 0;
    return m;
}

/* ---- Buffers that end at an inaccessible page ---- */

typedef struct guarded {
    unsigned char *base; /* the allocation */
    unsigned char *data; /* 4-byte aligned; the inaccessible page starts at data + round_up(len, 4) */
    size_t len;
} guarded;

static guarded guarded_copy(const void *bytes, size_t len) {
    SYSTEM_INFO si;
    size_t page, room = (len + 3) & ~(size_t)3, pages;
    DWORD old;
    guarded g;
    GetSystemInfo(&si);
    page = si.dwPageSize;
    pages = (room + page - 1) / page + 1;
    g.base = (unsigned char *)VirtualAlloc(NULL, (pages + 1) * page, MEM_COMMIT | MEM_RESERVE, PAGE_READWRITE);
    if (!g.base) {
        fprintf(stderr, "VirtualAlloc failed\n");
        exit(2);
    }
    VirtualProtect(g.base + pages * page, page, PAGE_NOACCESS, &old);
    g.data = g.base + pages * page - room;
    memset(g.data, 0xCC, room);
    if (len && bytes) memcpy(g.data, bytes, len);
    g.len = len;
    return g;
}

static void guarded_free(guarded *g) {
    if (g->base) VirtualFree(g->base, 0, MEM_RELEASE);
    g->base = g->data = NULL;
}

/* ---- A deterministic random source ---- */

static unsigned long long ps_seed = 0x9E3779B97F4A7C15ull;

static unsigned ps_random(void) {
    ps_seed ^= ps_seed << 13;
    ps_seed ^= ps_seed >> 7;
    ps_seed ^= ps_seed << 17;
    return (unsigned)(ps_seed >> 16);
}

#endif
