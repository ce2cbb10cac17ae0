/* Calling conventions across the C boundary, proven by the stack pointer. On 32-bit Windows a COM
 * method is __stdcall (the callee pops its arguments): a header that declared the vtables without
 * STDMETHODCALLTYPE would make every call leave the stack off by the argument size, which compiles and
 * often even runs for a few calls. Here each kind of call runs many times in a loop and the stack
 * pointer must be exactly where it was: vtable calls from C into the library, the library calling a
 * C object's vtable (a shutdown sink), a C object aggregating a library object, and the exported
 * functions. On x86_64 (and Linux) there is one calling convention and the same loops must hold too. */
#include "test_util.h"

#if defined(__i386__)
#define READ_STACK_POINTER(v) __asm__ volatile("movl %%esp, %0" : "=r"(v))
#elif defined(__x86_64__)
#define READ_STACK_POINTER(v) __asm__ volatile("movq %%rsp, %0" : "=r"(v))
#else
#define READ_STACK_POINTER(v) ((v) = 0)
#endif

#define ROUNDS 200000

static const IID IID_Shutdown_ = {0xF31DFDE1, 0x07B6, 0x11d2, {0xB2, 0xD8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
static const IID IID_CPC_ = {0xB196B284, 0xBAB4, 0x101A, {0xB6, 0x9C, 0x00, 0xAA, 0x00, 0x34, 0x1D, 0x07}};

/* ---- A shutdown sink in C, called by the library through its vtable. ---- */
typedef struct CountingSink {
    IOPCShutdown iface;
    ULONG refs;
    unsigned long requests;
} CountingSink;

static HRESULT STDMETHODCALLTYPE sink_qi(IOPCShutdown *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (same_iid(riid, &IID_Unknown_) || same_iid(riid, &IID_Shutdown_)) {
        *ppv = This;
        This->lpVtbl->AddRef(This);
        return S_OK;
    }
    return E_NOINTERFACE;
}

static ULONG STDMETHODCALLTYPE sink_add_ref(IOPCShutdown *This) { return ++((CountingSink *)This)->refs; }
static ULONG STDMETHODCALLTYPE sink_release(IOPCShutdown *This) { return --((CountingSink *)This)->refs; }

static HRESULT STDMETHODCALLTYPE sink_shutdown_request(IOPCShutdown *This, LPCWSTR reason) {
    ((CountingSink *)This)->requests += reason != NULL;
    return S_OK;
}

static IOPCShutdownVtbl sink_vtbl = {sink_qi, sink_add_ref, sink_release, sink_shutdown_request};

static void test_vtable_calls_into_the_library(void) {
    IOPCCommon *common = NULL;
    IUnknown *unk = NULL;
    size_t before, after;
    unsigned long i, ok = 0;
    LCID lcid = 0;

    CHECK_HR(OpcCommonCreate(NULL, NULL, &IID_IOPCCommon, (void **)&common), S_OK);
    if (!common) return;
    READ_STACK_POINTER(before);
    for (i = 0; i < ROUNDS; i++) {
        ok += common->lpVtbl->SetLocaleID(common, (i & 1) ? 0x0407 : 0x0409) == S_OK;
        ok += common->lpVtbl->GetLocaleID(common, &lcid) == S_OK && lcid == ((i & 1) ? 0x0407u : 0x0409u);
        ok += common->lpVtbl->AddRef(common) == 2;
        ok += common->lpVtbl->Release(common) == 1;
        ok += common->lpVtbl->QueryInterface(common, &IID_Unknown_, (void **)&unk) == S_OK;
        ok += unk->lpVtbl->Release(unk) == 1;
        ok += common->lpVtbl->SetClientName(common, NULL) == E_INVALIDARG;
    }
    READ_STACK_POINTER(after);
    CHECK(ok == 7ul * ROUNDS);
    CHECK(before == after);
    if (before != after) fprintf(stderr, "stack pointer moved by %ld bytes\n", (long)(after - before));
    CHECK(common->lpVtbl->Release(common) == 0);
}

static void test_error_strings_through_the_vtable(void) {
    IOPCCommon *common = NULL;
    size_t before, after;
    unsigned long i, ok = 0;

    CHECK_HR(OpcCommonCreate(NULL, NULL, &IID_IOPCCommon, (void **)&common), S_OK);
    if (!common) return;
    READ_STACK_POINTER(before);
    for (i = 0; i < ROUNDS / 10; i++) {
        LPWSTR text = (LPWSTR)GARBAGE_PTR;
        ok += common->lpVtbl->GetErrorString(common, (HRESULT)0xC0040007u, &text) == S_OK && text != NULL;
        OpcTaskMemFree(text);
        ok += common->lpVtbl->GetErrorString(common, (HRESULT)0x12345678u, NULL) == E_INVALIDARG;
    }
    READ_STACK_POINTER(after);
    CHECK(ok == 2ul * (ROUNDS / 10));
    CHECK(before == after);
    common->lpVtbl->Release(common);
}

static void test_library_calls_into_c(void) {
    CountingSink sink = {{&sink_vtbl}, 1, 0};
    IUnknown *shutdown = NULL;
    DWORD cookie = 0;
    ULONG notified = 0, failed = 0;
    size_t before, after;
    unsigned long i, ok = 0;

    CHECK_HR(OpcShutdownCreate(NULL, &IID_CPC_, (void **)&shutdown), S_OK);
    if (!shutdown) return;
    CHECK_HR(OpcShutdownAdvise(shutdown, (IUnknown *)&sink.iface, &cookie), S_OK);
    READ_STACK_POINTER(before);
    for (i = 0; i < ROUNDS / 10; i++) {
        ok += OpcShutdownNotifyEx(shutdown, W("balance"), &notified, &failed) == S_OK && notified == 1 && failed == 0;
    }
    READ_STACK_POINTER(after);
    CHECK(ok == ROUNDS / 10);
    CHECK(sink.requests == ROUNDS / 10);
    CHECK(before == after);
    CHECK_HR(OpcShutdownUnadvise(shutdown, cookie), S_OK);
    CHECK(sink.refs == 1);
    shutdown->lpVtbl->Release(shutdown);
}

static void test_aggregation_calls(void) {
    AggregatingServer server;
    IOPCCommon *common = NULL;
    size_t before, after;
    unsigned long i, ok = 0;

    aggregating_server_init(&server, &IID_IOPCCommon);
    CHECK_HR(OpcCommonCreate(NULL, &server.unk, &IID_Unknown_, (void **)&server.inner), S_OK);
    if (!server.inner) return;
    CHECK_HR(server.unk.lpVtbl->QueryInterface(&server.unk, &IID_IOPCCommon, (void **)&common), S_OK);
    if (!common) return;
    READ_STACK_POINTER(before);
    for (i = 0; i < ROUNDS; i++) {
        /* The library's delegating IUnknown calls the C outer object's AddRef and Release. */
        ok += common->lpVtbl->AddRef(common) > 1;
        ok += common->lpVtbl->Release(common) >= 1;
    }
    READ_STACK_POINTER(after);
    CHECK(ok == 2ul * ROUNDS);
    CHECK(server.add_refs >= ROUNDS && server.releases >= ROUNDS);
    CHECK(before == after);
    common->lpVtbl->Release(common);
    server.unk.lpVtbl->Release(&server.unk);
    CHECK(server.destroyed);
}

static void test_exported_functions(void) {
    size_t before, after;
    unsigned long i, ok = 0;
    OpcPattern *filter = NULL;

    CHECK_HR(OpcPatternCompileW(W("Channel?.Device[1-3].*"), TRUE, &filter), S_OK);
    READ_STACK_POINTER(before);
    for (i = 0; i < ROUNDS; i++) {
        ok += MatchPatternW(W("Channel1.Device2.Tag"), W("Channel?.Device[1-3].*"), TRUE) == TRUE;
        ok += MatchPatternA("abc", "a#c", FALSE) == FALSE;
        ok += OpcPatternMatchW(filter, W("Channel7.Device3.X")) == TRUE;
        ok += OpcObjectCount() < 1000u;
    }
    READ_STACK_POINTER(after);
    CHECK(ok == 4ul * ROUNDS);
    CHECK(before == after);
    OpcPatternFree(filter);
}

#ifdef _WIN32
/* The exports carry their plain names on x86 too (no _Name@12 decoration): regsvr32 and
 * GetProcAddress("MatchPatternW") find them, and they are the functions the program links. */
static void test_export_names(void) {
    static const char *const names[] = {"MatchPatternW",     "MatchPatternA",       "OpcCommonCreate",
                                        "OpcGetErrorString", "DllGetClassObject",   "DllCanUnloadNow",
                                        "DllRegisterServer", "DllUnregisterServer", "IID_IOPCCommon"};
    HMODULE dll = GetModuleHandleW(L"opccomn.dll");
    size_t i;
    CHECK(dll != NULL);
    if (!dll) return;
    for (i = 0; i < sizeof names / sizeof names[0]; i++) {
        int found = GetProcAddress(dll, names[i]) != NULL;
        CHECK(found);
        if (!found) fprintf(stderr, "GetProcAddress(\"%s\") failed\n", names[i]);
    }
    CHECK(GetProcAddress(dll, "_DllGetClassObject@12") == NULL && GetProcAddress(dll, "DllGetClassObject@12") == NULL);
    {
        typedef __typeof__(&MatchPatternW) MatchPatternW_fn; /* with the calling convention the header states */
        MatchPatternW_fn match = (MatchPatternW_fn)(void (*)(void))GetProcAddress(dll, "MatchPatternW");
        CHECK(match && match(W("Tag1"), W("Tag#"), TRUE) == TRUE && match(W("TagX"), W("Tag#"), TRUE) == FALSE);
    }
    CHECK(memcmp(GetProcAddress(dll, "IID_IOPCCommon"), &IID_IOPCCommon, sizeof(IID)) == 0);
}
#endif

int main(void) {
    uint32_t objects = OpcObjectCount();
    printf("pointer size %u bytes, %d rounds per loop\n", (unsigned)sizeof(void *), ROUNDS);
    test_vtable_calls_into_the_library();
    test_error_strings_through_the_vtable();
    test_library_calls_into_c();
    test_aggregation_calls();
    test_exported_functions();
#ifdef _WIN32
    test_export_names();
#endif
    CHECK(OpcObjectCount() == objects);
    return test_summary("test_call_balance");
}
