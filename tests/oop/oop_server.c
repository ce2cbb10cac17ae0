/* The cross-process tests' EXE server (LocalServer32, started by COM with -Embedding): a server
 * object written in C that aggregates OpcCommonCreate (IOPCCommon) and OpcShutdownCreate
 * (IConnectionPointContainer with the IOPCShutdown connection point), as an OPC server does, and a
 * server list over a registry held in memory with OOP_FAKE_SERVERS classes. Runs in the multithreaded
 * apartment and exits when its last object is released (or after two minutes without one, or 20
 * minutes after its first when objects are never released: a client that died), OOP_LINGER_MS after
 * the last release (with "-linger:default": the host's default linger).
 *
 * With "-ps:widl" on its command line it uses the stand-in for the Foundation's proxy/stub
 * (opccomn_widl_ps.dll) for the five interfaces; otherwise what the registry names (opccomn.dll).
 * With "-set:N" it serves its two classes under the CLSIDs oop_class(N, ...) instead (oop.h).
 *
 * It offers to run as the Windows service OOP_SERVICE (oop.h): registered so (`/Service`, by the test
 * of tests/oop/test_service.c through the library's host), the service manager starts it with
 * -RunService, and it serves until stopped. "-release:MS" sets the host's release_timeout_ms (the
 * service test's bound). A stop by the service manager (or any stop but OOP_CODE_STOP's) notifies the
 * sinks of every server object, bounded by OOP_BOUNDED_MS.
 *
 * The server answers the vendor codes of oop.h in GetErrorString, so the client can ask what the
 * server saw: the client name, the result of a shutdown notification, the proxy/stub in use. */
#include "oop.h"

static int widl_mode;
static OpcRegistry *fake_registry; /* the server list's registry */

/* ---- The server object ---- */
typedef struct Server {
    IUnknown unk;
    LONG refs;
    struct Server *next, *prev; /* the live server objects (all_servers) */
    IUnknown *common;   /* inner IUnknown of the IOPCCommon session */
    IUnknown *shutdown; /* inner IUnknown of the shutdown connection point */
    CRITICAL_SECTION lock;
    WCHAR *client_name; /* the last name SetClientName gave, or NULL */
    WCHAR answer[64];   /* text of the last OOP_CODE_SHUTDOWN / OOP_CODE_PROXY_STUB answer */
} Server;

/* The live server objects, for a stop that tells every client. */
static CRITICAL_SECTION servers_lock;
static Server all_servers; /* the list's head (main links it to itself) */

static HRESULT STDMETHODCALLTYPE server_qi(IUnknown *This, REFIID riid, void **ppv) {
    Server *s = (Server *)This;
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (IsEqualIID(riid, &IID_IUnknown)) {
        *ppv = This;
        This->lpVtbl->AddRef(This);
        return S_OK;
    }
    if (IsEqualIID(riid, &IID_IOPCCommon)) return s->common->lpVtbl->QueryInterface(s->common, riid, ppv);
    if (IsEqualIID(riid, &IID_IConnectionPointContainer))
        return s->shutdown->lpVtbl->QueryInterface(s->shutdown, riid, ppv);
    return E_NOINTERFACE;
}

static ULONG STDMETHODCALLTYPE server_add_ref(IUnknown *This) { return (ULONG)InterlockedIncrement(&((Server *)This)->refs); }

static ULONG STDMETHODCALLTYPE server_release(IUnknown *This) {
    Server *s = (Server *)This;
    LONG n = InterlockedDecrement(&s->refs);
    if (n == 0) {
        EnterCriticalSection(&servers_lock);
        s->prev->next = s->next;
        s->next->prev = s->prev;
        LeaveCriticalSection(&servers_lock);
        s->refs = 1; /* guard against the inner objects' releases coming back */
        if (s->common) s->common->lpVtbl->Release(s->common);
        if (s->shutdown) s->shutdown->lpVtbl->Release(s->shutdown);
        DeleteCriticalSection(&s->lock);
        free(s->client_name);
        free(s);
        OpcServerUnlock();
    }
    return (ULONG)n;
}

static IUnknownVtbl server_vtbl = {server_qi, server_add_ref, server_release};

static void client_name_changed(void *context, LPCWSTR name) {
    Server *s = (Server *)context;
    size_t n = wlen(name);
    WCHAR *copy = (WCHAR *)malloc((n + 1) * sizeof(WCHAR));
    if (!copy) return;
    memcpy(copy, name, (n + 1) * sizeof(WCHAR));
    EnterCriticalSection(&s->lock);
    free(s->client_name);
    s->client_name = copy;
    LeaveCriticalSection(&s->lock);
}

/* The server object whose client asked for the operator's stop (OOP_CODE_STOP), held for on_stop. */
static Server *volatile stopping;

static void set_answer(Server *s, const char *text) {
    size_t i;
    for (i = 0; text[i] && i + 1 < sizeof s->answer / sizeof s->answer[0]; i++) s->answer[i] = (WCHAR)text[i];
    s->answer[i] = 0;
}

static HRESULT vendor_text(void *context, HRESULT code, LCID locale, LPCWSTR *text) {
    Server *s = (Server *)context;
    char buf[64];
    (void)locale;
    if (code == OOP_CODE_CLIENT_NAME) {
        /* The library copies the text before returning; the test's client sets no name meanwhile. */
        if (!s->client_name) return S_FALSE;
        *text = s->client_name;
        return S_OK;
    }
    if (code == OOP_CODE_SHUTDOWN) {
        ULONG notified = 99, failed = 99;
        HRESULT hr = OpcShutdownNotifyEx(&s->unk, W(OOP_REASON), &notified, &failed);
        snprintf(buf, sizeof buf, "hr=%08lX notified=%lu failed=%lu", (unsigned long)hr, (unsigned long)notified,
                 (unsigned long)failed);
        set_answer(s, buf);
        *text = s->answer;
        return S_OK;
    }
    if (code == OOP_CODE_SHUTDOWN_BOUNDED) {
        ULONG notified = 99, failed = 99, timed_out = 99;
        OpcShutdownNotifyOptions bounds;
        HRESULT hr;
        memset(&bounds, 0, sizeof bounds);
        bounds.struct_size = sizeof bounds;
        bounds.timeout_ms = OOP_BOUNDED_MS;
        hr = OpcShutdownNotifyBounded(&s->unk, W(OOP_REASON), &bounds, &notified, &failed, &timed_out);
        snprintf(buf, sizeof buf, "hr=%08lX notified=%lu failed=%lu timed_out=%lu", (unsigned long)hr,
                 (unsigned long)notified, (unsigned long)failed, (unsigned long)timed_out);
        set_answer(s, buf);
        *text = s->answer;
        return S_OK;
    }
    if (code == OOP_CODE_STOP) {
        HRESULT hr;
        s->unk.lpVtbl->AddRef(&s->unk);
        if (InterlockedCompareExchangePointer((void *volatile *)&stopping, s, NULL) != NULL)
            s->unk.lpVtbl->Release(&s->unk);
        hr = OpcExeServerStop();
        snprintf(buf, sizeof buf, "stop=%08lX", (unsigned long)hr);
        set_answer(s, buf);
        *text = s->answer;
        return S_OK;
    }
    if (code == OOP_CODE_PROCESS_ID) {
        snprintf(buf, sizeof buf, "%lu", (unsigned long)GetCurrentProcessId());
        set_answer(s, buf);
        *text = s->answer;
        return S_OK;
    }
    if (code == OOP_CODE_CPU_TIME) {
        snprintf(buf, sizeof buf, "%llu", process_cpu_time());
        set_answer(s, buf);
        *text = s->answer;
        return S_OK;
    }
    if (code == OOP_CODE_PROXY_STUB) {
        /* During this call a stub of the serving proxy/stub is alive. */
        HRESULT in_use = widl_proxy_stub_in_use();
        set_answer(s, in_use == E_FAIL ? "opccomn" : in_use == S_FALSE ? "widl" : "widl-unused");
        *text = s->answer;
        return S_OK;
    }
    return S_FALSE;
}

static HRESULT OPCCOMN_CDECL create_server(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    OpcCommonOptions options;
    OpcShutdownOptions shutdown_options;
    static LCID locales[OOP_LOCALES];
    unsigned i;
    HRESULT hr;
    Server *s = (Server *)calloc(1, sizeof *s);
    (void)context;
    (void)outer; /* the class is not aggregatable: the library refuses an outer object */
    if (!s) return E_OUTOFMEMORY;
    s->unk.lpVtbl = &server_vtbl;
    s->refs = 1;
    InitializeCriticalSection(&s->lock);
    EnterCriticalSection(&servers_lock);
    s->next = all_servers.next;
    s->prev = &all_servers;
    all_servers.next->prev = s;
    all_servers.next = s;
    LeaveCriticalSection(&servers_lock);
    OpcServerLock(); /* the server object counts on the process while it lives */
    for (i = 0; i < OOP_LOCALES; i++) locales[i] = oop_locale(i);
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.locales = locales;
    options.locale_count = OOP_LOCALES;
    options.vendor_error_string = vendor_text;
    options.vendor_error_context = s;
    options.client_name_changed = client_name_changed;
    options.client_name_context = s;
    hr = OpcCommonCreate(&options, &s->unk, &IID_IUnknown, (void **)&s->common);
    memset(&shutdown_options, 0, sizeof shutdown_options);
    shutdown_options.struct_size = sizeof shutdown_options;
    shutdown_options.advise_limit = OOP_ADVISE_LIMIT;
    if (SUCCEEDED(hr)) hr = OpcShutdownCreateEx(&shutdown_options, &s->unk, &IID_IUnknown, (void **)&s->shutdown);
    if (SUCCEEDED(hr)) hr = server_qi(&s->unk, riid, ppv);
    server_release(&s->unk);
    return hr;
}

/* The server list is the library's object over the fake registry (counted through the module lock). */
static HRESULT OPCCOMN_CDECL create_list(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    (void)context;
    (void)outer;
    return OpcServerListCreateOver(fake_registry, NULL, riid, ppv);
}

/* Tells the sinks of `s` that the server goes, within OOP_BOUNDED_MS. */
static void notify_bounded(Server *s) {
    OpcShutdownNotifyOptions bounds;
    memset(&bounds, 0, sizeof bounds);
    bounds.struct_size = sizeof bounds;
    bounds.timeout_ms = OOP_BOUNDED_MS;
    OpcShutdownNotifyBounded(&s->unk, W(OOP_REASON), &bounds, NULL, NULL, NULL);
}

/* The operator's stop (the host calls it on its own thread, or the service's): the client of the
 * server object that asked (OOP_CODE_STOP) is told to disconnect, within a bound; any other stop (the
 * service manager's, the system's shutdown, the watchdog's) tells every server object's clients. Then
 * the host waits for the clients to let go. */
static void OPCCOMN_CDECL on_stop(void *context) {
    Server *s = (Server *)InterlockedExchangePointer((void *volatile *)&stopping, NULL), *each[64];
    size_t n = 0, i;
    (void)context;
    if (s) {
        notify_bounded(s);
        s->unk.lpVtbl->Release(&s->unk);
        return;
    }
    EnterCriticalSection(&servers_lock);
    for (s = all_servers.next; s != &all_servers && n < 64; s = s->next) {
        /* An object on its way out (its count already zero) is not taken. */
        if (InterlockedCompareExchange(&s->refs, 0, 0) > 0) {
            s->unk.lpVtbl->AddRef(&s->unk);
            each[n++] = s;
        }
    }
    LeaveCriticalSection(&servers_lock);
    for (i = 0; i < n; i++) {
        notify_bounded(each[i]);
        each[i]->unk.lpVtbl->Release(&each[i]->unk);
    }
}

/* A client that died leaves its references (Wine runs no rundown of a dead client's references):
 * 20 minutes after the start, however long a client's calls take (a benchmark runs for minutes on a
 * loaded machine), the server stops as its operator would, so it cannot keep this process, and the
 * test runner's output pipe it inherited, alive for ever. */
static DWORD WINAPI watchdog(void *unused) {
    (void)unused;
    Sleep(1200000);
    OpcExeServerStop();
    return 0;
}

/* The fake servers: OOP_FAKE_SERVERS Data Access 2.0 servers with ProgIDs Oop.Fake<N>.1. */
static HRESULT fill_fake_registry(void) {
    static const CATID da2 = {0x63D5F432, 0xCFE4, 0x11D1, {0xB2, 0xC8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
    unsigned n;
    HRESULT hr = OpcRegistryCreateMemory(&fake_registry);
    for (n = 0; SUCCEEDED(hr) && n < OOP_FAKE_SERVERS; n++) {
        char prog[32], vi[32], user[32];
        WCHAR wprog[32], wvi[32], wuser[32];
        OpcServerRegistration r;
        size_t i;
        snprintf(prog, sizeof prog, "Oop.Fake%u.1", n);
        snprintf(vi, sizeof vi, "Oop.Fake%u", n);
        snprintf(user, sizeof user, "Oop fake server %u", n);
        for (i = 0; i < sizeof prog; i++) wprog[i] = (WCHAR)prog[i];
        for (i = 0; i < sizeof vi; i++) wvi[i] = (WCHAR)vi[i];
        for (i = 0; i < sizeof user; i++) wuser[i] = (WCHAR)user[i];
        memset(&r, 0, sizeof r);
        r.struct_size = sizeof r;
        r.server_type = OPC_SERVER_TYPE_LOCAL;
        r.clsid = oop_fake_clsid(n);
        r.prog_id = wprog;
        r.version_independent_prog_id = wvi;
        r.user_type = wuser;
        r.module_path = L"C:\\oop\\fake.exe";
        r.implemented_categories = &da2;
        r.implemented_category_count = 1;
        hr = OpcRegisterServer(&r, fake_registry);
    }
    return hr;
}

int main(void) {
    HRESULT hr;
    const WCHAR *set_flag = wcsstr(GetCommandLineW(), L" -set:");
    unsigned set = set_flag ? (unsigned)(set_flag[6] - L'0') % 10 : 0;
    CLSID server_clsid = oop_class(set, 0), list_clsid = oop_class(set, 1);
    OpcServerClass classes[2];
    OpcExeServerOptions options;
    HANDLE timer;
    memset(classes, 0, sizeof classes);
    classes[0].struct_size = classes[1].struct_size = sizeof classes[0];
    classes[0].clsid = &server_clsid;
    classes[0].create = create_server;
    classes[1].clsid = &list_clsid;
    classes[1].create = create_list;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.classes = classes;
    options.class_count = 2;
    options.first_client_timeout_ms = 120000; /* a server nobody connects to gives up after two minutes */
    options.release_timeout_ms = 30000;       /* after a stop: 30 s for what is left */
    if (wcsstr(GetCommandLineW(), L" -release:"))
        options.release_timeout_ms = (uint32_t)_wtoi(wcsstr(GetCommandLineW(), L" -release:") + 10);
    options.service_name = OOP_SERVICE;       /* -RunService: the service manager started it */
    options.idle_linger_ms = OOP_LINGER_MS;   /* the reconnect test's pauses stay far from its end */
    if (wcsstr(GetCommandLineW(), L" -linger:default")) options.idle_linger_ms = 0; /* the host's default */
    options.on_stop = on_stop;
    widl_mode = wcsstr(GetCommandLineW(), L"-ps:widl") != NULL;
    InitializeCriticalSection(&servers_lock);
    all_servers.next = all_servers.prev = &all_servers;
    hr = CoInitializeEx(NULL, COINIT_MULTITHREADED);
    if (SUCCEEDED(hr) && widl_mode) hr = use_widl_proxy_stub();
    if (SUCCEEDED(hr) && wcsstr(GetCommandLineW(), L"-ps:opccomn-direct")) hr = use_opccomn_proxy_stub_directly();
    if (SUCCEEDED(hr)) hr = fill_fake_registry();
    timer = CreateThread(NULL, 0, watchdog, NULL, 0, NULL);
    if (timer) CloseHandle(timer);
    /* Until the last object goes (the host: -Embedding is on the command line COM started it with). */
    if (SUCCEEDED(hr)) hr = OpcExeServerRun(&options, NULL);
    if (FAILED(hr)) {
        fprintf(stderr, "oop_server: start failed: 0x%08lX\n", (unsigned long)hr);
        return 1;
    }
    if (hr == S_FALSE) {
        fprintf(stderr, "oop_server: exiting with objects a client never released\n");
        return 3;
    }
    OpcRegistryRelease(fake_registry);
    return 0; /* without CoUninitialize (OpcExeServerRun) */
}
