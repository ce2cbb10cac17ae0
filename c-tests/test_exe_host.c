/* The EXE host (OpcExeServerRun) run on a thread of this process, with a client in the same process
 * getting its class object from COM's class table (CoGetClassObject, CLSCTX_LOCAL_SERVER), under the
 * real COM runtime (Wine in CI). What its callers can do wrong, and what it must survive:
 *
 * - LockServer(FALSE) without a LockServer(TRUE) (any client can send one, through the wire form
 *   too): it gives back nothing (S_FALSE) and the host serves on while a client holds an object.
 * - A client that comes and goes while the host lingers after the last release: the linger counts
 *   from the last release, not the first.
 * - The operator's stop event: a name someone else took first (a set event anyone may use, a mutex,
 *   an event this process may not open) is refused with HRESULT_FROM_WIN32(ERROR_ALREADY_EXISTS)
 *   before anything is served, and never stops the server; the event the host creates lets only
 *   SYSTEM, the administrators and this account in; a second instance of the same server (a child
 *   process here) shares it, and setting it stops both.
 *
 * Off Windows the host serves nothing: OpcExeServerRun answers E_NOTIMPL after checking its
 * arguments, the stop event's name included. */
#include "test_util.h"

#if defined(_WIN32)
#include <aclapi.h>
#include <sddl.h>

static const CLSID CLSID_Host = {0x5EC0E5E1, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0x77}};

static volatile LONG stops;

static HRESULT OPCCOMN_CDECL create(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    (void)context;
    return OpcCommonCreate(NULL, outer, riid, ppv);
}

static void OPCCOMN_CDECL on_stop(void *context) {
    (void)context;
    InterlockedIncrement(&stops);
}

/* One run of the host: its command line, stop event, linger, and what it returned. */
typedef struct Host {
    const WCHAR *command_line;
    const WCHAR *stop_name;
    uint32_t linger_ms;
    HRESULT hr;
} Host;

static HRESULT run(Host *h) {
    OpcServerClass cls;
    OpcExeServerOptions o;
    memset(&cls, 0, sizeof cls);
    cls.struct_size = sizeof cls;
    cls.clsid = &CLSID_Host;
    cls.create = create;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.classes = &cls;
    o.class_count = 1;
    o.stop_event_name = h->stop_name;
    o.on_stop = on_stop;
    o.first_client_timeout_ms = 20000;
    o.release_timeout_ms = 2000;
    o.idle_linger_ms = h->linger_ms;
    h->hr = OpcExeServerRun(&o, h->command_line);
    return h->hr;
}

static DWORD WINAPI host_thread(void *p) {
    run((Host *)p);
    return 0;
}

static HANDLE start(Host *h) {
    HANDLE t = CreateThread(NULL, 0, host_thread, h, 0, NULL);
    CHECK(t != NULL);
    return t;
}

/* Whether the host thread is still serving. */
static int serving(HANDLE thread) { return WaitForSingleObject(thread, 0) == WAIT_TIMEOUT; }

/* The host's class object from COM's class table, once the host registered it (10 s at most). */
static IClassFactory *class_object(void) {
    void *p = NULL;
    int i;
    for (i = 0; i < 200; i++) {
        if (SUCCEEDED(CoGetClassObject(&CLSID_Host, CLSCTX_LOCAL_SERVER, NULL, &IID_IClassFactory, &p)) && p)
            return (IClassFactory *)p;
        Sleep(50);
    }
    return NULL;
}

static IOPCCommon *instance(IClassFactory *f) {
    void *p = NULL;
    HRESULT hr = f->lpVtbl->CreateInstance(f, NULL, &IID_IOPCCommon, &p);
    CHECK_HR(hr, S_OK);
    return SUCCEEDED(hr) ? (IOPCCommon *)p : NULL;
}

/* LockServer(FALSE) without TRUE takes nothing: the host serves on under the object a client holds. */
static void unmatched_lock_server(void) {
    Host h = {W("test_exe_host.exe -Embedding"), NULL, 100, E_FAIL};
    HANDLE t = start(&h);
    IClassFactory *f = class_object();
    IOPCCommon *held, *other;
    LCID lcid = 0;
    CHECK(f != NULL);
    if (!f) return;
    held = instance(f);
    CHECK_HR(f->lpVtbl->LockServer(f, FALSE), S_FALSE);
    CHECK_HR(f->lpVtbl->LockServer(f, FALSE), S_FALSE);
    OpcServerUnlock(); /* one the server never took: ignored as well */
    /* The linger (100 ms) and the end's pause (1 s) pass: still serving the object. */
    Sleep(100 + 1000 + 700);
    CHECK(serving(t));
    CHECK(held && SUCCEEDED(held->lpVtbl->GetLocaleID(held, &lcid)));
    other = instance(f);
    if (other) other->lpVtbl->Release((IOPCCommon *)other);
    /* A matched pair counts and gives back; a third FALSE gives back nothing. */
    CHECK_HR(f->lpVtbl->LockServer(f, TRUE), S_OK);
    CHECK_HR(f->lpVtbl->LockServer(f, FALSE), S_OK);
    CHECK_HR(f->lpVtbl->LockServer(f, FALSE), S_FALSE);
    f->lpVtbl->Release(f);
    if (held) held->lpVtbl->Release(held);
    /* The last release ends it. */
    CHECK(WaitForSingleObject(t, 15000) == WAIT_OBJECT_0);
    CHECK_HR(h.hr, S_OK);
    CHECK(stops == 0);
    CloseHandle(t);
}

/* A client that comes and goes while the host lingers starts the linger again: the host serves
 * `idle_linger_ms` after the last release, not after the first. */
static void linger_counts_from_the_last_release(void) {
    Host h = {W("test_exe_host.exe -Embedding"), NULL, 2000, E_FAIL};
    HANDLE t = start(&h);
    IClassFactory *f = class_object();
    IOPCCommon *o;
    CHECK(f != NULL);
    if (!f) return;
    o = instance(f);
    f->lpVtbl->Release(f);
    if (o) o->lpVtbl->Release(o); /* the first last release: t = 0 */
    Sleep(1000);
    f = class_object();
    CHECK(f != NULL);
    if (!f) return;
    o = instance(f);
    f->lpVtbl->Release(f);
    if (o) o->lpVtbl->Release(o); /* the last release: t = 1 s */
    Sleep(1500);                  /* t = 2.5 s: past 2 s after the first, within 2 s of the last */
    CHECK(serving(t));
    f = class_object();
    CHECK(f != NULL);
    if (f) {
        o = instance(f);
        f->lpVtbl->Release(f);
        if (o) o->lpVtbl->Release(o);
    }
    CHECK(WaitForSingleObject(t, 15000) == WAIT_OBJECT_0);
    CHECK_HR(h.hr, S_OK);
    CloseHandle(t);
}

#define NAME_TAKEN ((HRESULT)0x800700B7L) /* HRESULT_FROM_WIN32(ERROR_ALREADY_EXISTS) */

/* A stop event's name someone else took first: refused at once, no stop, nothing served. */
static void squatted(const char *what, HANDLE squatter, const WCHAR *name) {
    Host h = {W(""), name, 100, E_FAIL};
    DWORD t0 = GetTickCount();
    void *p = NULL;
    CHECK(squatter != NULL);
    CHECK_HR(run(&h), NAME_TAKEN);
    if (h.hr != NAME_TAKEN) fprintf(stderr, "  (squatter: %s)\n", what);
    CHECK(GetTickCount() - t0 < 5000);
    CHECK(stops == 0);
    /* Nothing was served: no class object is in COM's table. */
    CHECK(FAILED(CoGetClassObject(&CLSID_Host, CLSCTX_LOCAL_SERVER, NULL, &IID_IClassFactory, &p)) && p == NULL);
    if (p) ((IUnknown *)p)->lpVtbl->Release((IUnknown *)p);
    CloseHandle(squatter);
}

static HANDLE with_sddl_event(const char *sddl, BOOL set, const WCHAR *name) {
    SECURITY_ATTRIBUTES sa;
    PSECURITY_DESCRIPTOR sd = NULL;
    HANDLE h;
    CHECK(ConvertStringSecurityDescriptorToSecurityDescriptorA(sddl, SDDL_REVISION_1, &sd, NULL));
    sa.nLength = sizeof sa;
    sa.lpSecurityDescriptor = sd;
    sa.bInheritHandle = FALSE;
    h = CreateEventW(&sa, TRUE, set, name);
    LocalFree(sd);
    return h;
}

static void stop_event_taken_first(void) {
    SECURITY_ATTRIBUTES sa;
    SECURITY_DESCRIPTOR sd;
    const WCHAR *name = W("Local\\opccomn-test-exe-host-squatted");
    /* A set event with a NULL DACL (anyone may set it): this account made it, but not as a host. */
    InitializeSecurityDescriptor(&sd, SECURITY_DESCRIPTOR_REVISION);
    SetSecurityDescriptorDacl(&sd, TRUE, NULL, FALSE);
    sa.nLength = sizeof sa;
    sa.lpSecurityDescriptor = &sd;
    sa.bInheritHandle = FALSE;
    squatted("a set event with a NULL DACL", CreateEventW(&sa, TRUE, TRUE, name), name);
    /* An event with default security, not set. */
    squatted("an event with default security", CreateEventW(NULL, TRUE, FALSE, name), name);
    /* An event everyone may use, owned by this account. */
    squatted("an event everyone may use", with_sddl_event("D:(A;;GA;;;WD)", FALSE, name), name);
    /* Another kind of object. */
    squatted("a mutex", CreateMutexW(NULL, FALSE, name), name);
    /* An event this process may not open at all. */
    squatted("an event nobody may open", with_sddl_event("D:(D;;GA;;;WD)", FALSE, name), name);
}

/* The event the host makes: its access list, and the operator's stop through it. */
static void stop_event_made_by_the_host(void) {
    const WCHAR *name = W("Local\\opccomn-test-exe-host-stop");
    Host h = {W(""), name, 100, E_FAIL};
    HANDLE t = start(&h), e = NULL, token = NULL;
    PSID user = NULL;
    PACL dacl = NULL;
    PSECURITY_DESCRIPTOR sd = NULL;
    BYTE buffer[512];
    DWORD size = 0, i;
    int found_sy = 0, found_ba = 0, found_user = 0, others = 0;
    IClassFactory *f = class_object(); /* the host serves: the event is there */
    CHECK(f != NULL);
    if (f) f->lpVtbl->Release(f);
    e = OpenEventW(READ_CONTROL | EVENT_MODIFY_STATE | SYNCHRONIZE, FALSE, name);
    CHECK(e != NULL);
    if (!e) return;
    CHECK(WaitForSingleObject(e, 0) == WAIT_TIMEOUT); /* not set */
    CHECK(OpenProcessToken(GetCurrentProcess(), TOKEN_QUERY, &token));
    CHECK(GetTokenInformation(token, TokenUser, buffer, sizeof buffer, &size));
    user = ((TOKEN_USER *)buffer)->User.Sid;
    CHECK(GetSecurityInfo(e, SE_KERNEL_OBJECT, DACL_SECURITY_INFORMATION, NULL, NULL, &dacl, NULL, &sd) == ERROR_SUCCESS);
    CHECK(dacl != NULL); /* not a NULL DACL */
    for (i = 0; dacl && i < dacl->AceCount; i++) {
        ACCESS_ALLOWED_ACE *ace = NULL;
        PSID sid;
        char *text = NULL;
        if (!GetAce(dacl, i, (void **)&ace)) continue;
        sid = (PSID)&ace->SidStart;
        CHECK(ace->Header.AceType == ACCESS_ALLOWED_ACE_TYPE);
        if (ConvertSidToStringSidA(sid, &text)) {
            if (!strcmp(text, "S-1-5-18")) found_sy = 1;
            else if (!strcmp(text, "S-1-5-32-544")) found_ba = 1;
            else if (EqualSid(sid, user)) found_user = 1;
            else others++;
            LocalFree(text);
        }
    }
    CHECK(found_sy && found_ba && found_user && others == 0);
    if (sd) LocalFree(sd);
    CloseHandle(token);
    /* The operator sets it: on_stop, and the host returns. */
    CHECK(SetEvent(e));
    CHECK(WaitForSingleObject(t, 15000) == WAIT_OBJECT_0);
    CHECK_HR(h.hr, S_OK);
    CHECK(stops == 1);
    stops = 0;
    CloseHandle(e);
    CloseHandle(t);
}

/* Another instance of the same server (a child process running its own host with the same stop
 * event) shares the event: this host serves too, and one SetEvent stops both. */
static void stop_event_shared_with_another_instance(void) {
    const WCHAR *name = W("Local\\opccomn-test-exe-host-shared");
    WCHAR self[MAX_PATH], command[MAX_PATH + 64];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    HANDLE e = NULL, t;
    Host h = {W(""), name, 100, E_FAIL};
    DWORD code = 99;
    int i;
    GetModuleFileNameW(NULL, self, MAX_PATH);
    swprintf(command, MAX_PATH + 64, L"\"%ls\" instance", self);
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    CHECK(CreateProcessW(self, command, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi));
    for (i = 0; i < 200 && !e; i++) {
        e = OpenEventW(EVENT_MODIFY_STATE | SYNCHRONIZE, FALSE, name);
        if (!e) Sleep(50);
    }
    CHECK(e != NULL);
    t = start(&h);
    {
        IClassFactory *f = class_object(); /* this instance serves */
        CHECK(f != NULL);
        if (f) f->lpVtbl->Release(f);
    }
    CHECK(serving(t));
    if (e) CHECK(SetEvent(e));
    CHECK(WaitForSingleObject(t, 15000) == WAIT_OBJECT_0);
    CHECK_HR(h.hr, S_OK);
    CHECK(stops == 1);
    stops = 0;
    CHECK(WaitForSingleObject(pi.hProcess, 15000) == WAIT_OBJECT_0);
    CHECK(GetExitCodeProcess(pi.hProcess, &code) && code == 0);
    CloseHandle(pi.hProcess);
    CloseHandle(pi.hThread);
    if (e) CloseHandle(e);
    CloseHandle(t);
}

/* The child of stop_event_shared_with_another_instance: a host by hand with the shared stop event,
 * until it is set. Exit 0 when it served and was stopped. */
static int instance_main(void) {
    Host h = {W(""), W("Local\\opccomn-test-exe-host-shared"), 100, E_FAIL};
    CoInitializeEx(NULL, COINIT_MULTITHREADED);
    run(&h);
    return h.hr == S_OK && stops == 1 ? 0 : 1;
}

int main(int argc, char **argv) {
    if (argc > 1 && !strcmp(argv[1], "instance")) return instance_main();
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    unmatched_lock_server();
    linger_counts_from_the_last_release();
    stop_event_taken_first();
    stop_event_made_by_the_host();
    stop_event_shared_with_another_instance();
    CoUninitialize();
    return test_summary("test_exe_host");
}

#else

static HRESULT OPCCOMN_CDECL create(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    (void)context;
    return OpcCommonCreate(NULL, outer, riid, ppv);
}

int main(void) {
    static const CLSID clsid = {0x5EC0E5E1, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0x77}};
    OpcServerClass cls;
    OpcExeServerOptions o;
    memset(&cls, 0, sizeof cls);
    cls.struct_size = sizeof cls;
    cls.clsid = &clsid;
    cls.create = create;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.classes = &cls;
    o.class_count = 1;
    o.stop_event_name = W("Local\\opccomn-test-exe-host-stop");
    /* Checked, then not served here. */
    CHECK_HR(OpcExeServerRun(&o, W("")), E_NOTIMPL);
    o.struct_size = 3;
    CHECK_HR(OpcExeServerRun(&o, W("")), E_INVALIDARG);
    CHECK_HR(OpcExeServerStop(), S_FALSE);
    return test_summary("test_exe_host");
}

#endif
