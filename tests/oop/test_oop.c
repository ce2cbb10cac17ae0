/* Every method of the OPC Common interfaces across processes, under the real COM runtime (Wine in
 * CI): this client and the EXE server oop_server.c (LocalServer32), talking through a proxy/stub on
 * each side.
 *
 *   test_oop CLIENT SERVER     CLIENT, SERVER: "opccomn" (opccomn.dll's proxy/stub, registered with
 *                              OpcRegisterProxyStub) or "widl" (the stand-in for the Foundation's
 *                              opccomn_ps.dll, see oop.h)
 *
 * Covered: SetLocaleID / GetLocaleID / QueryAvailableLocaleIDs (4096 locales arrive whole) /
 * GetErrorString (texts allocated for the client; NULL on failure) / SetClientName (the server sees
 * it); strings up to the library's bound of 2^19 code units through, longer ones refused with a
 * defined error and both processes still answering; a shutdown sink in this process advised through
 * the connection point, OpcShutdownNotify in the server reaching it with the reason, Unadvise from
 * inside the callback; OpcShutdownNotifyBounded with a client hung in ShutdownRequest, one that answers
 * and one that was killed after advising (a child process of this program); IOPCServerList2 / IOPCServerList over 100 fake servers with IOPCEnumGUID and
 * IEnumGUID Next of several elements, Skip, Reset, Clone, GetClassDetails, CLSIDFromProgID, category
 * arrays up to the library's 4096 and beyond; OpcSetProxyBlanket on the IOPCCommon proxy. Registration is
 * undone at the end and checked. */
#include "oop.h"

#include <comcat.h>
#include <olectl.h> /* CONNECT_E_NOCONNECTION */

static int widl_client, widl_server;
static WCHAR server_path[MAX_PATH];
static const CATID CATID_DA2 = {0x63D5F432, 0xCFE4, 0x11D1, {0xB2, 0xC8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};

#define STRING_BOUND (1u << 19)

static WCHAR *long_name(size_t units) {
    WCHAR *s = (WCHAR *)malloc((units + 1) * sizeof(WCHAR));
    size_t i;
    for (i = 0; s && i < units; i++) s[i] = (WCHAR)(0x41 + i % 26);
    if (s) s[units] = 0;
    return s;
}

static int key_exists(const WCHAR *key) {
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_READ, &h) != ERROR_SUCCESS) return 0;
    RegCloseKey(h);
    return 1;
}

static OpcServerRegistration server_registration(const CLSID *clsid, const WCHAR *prog_id) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = *clsid;
    r.prog_id = prog_id;
    r.user_type = L"opccomn cross-process test server";
    r.module_path = server_path;
    return r;
}

static void set_server_command(const CLSID *clsid) {
    WCHAR key[80], command[MAX_PATH + 32], guid[40];
    HKEY h;
    StringFromGUID2(clsid, guid, 40);
    swprintf(key, 80, L"CLSID\\%ls\\LocalServer32", guid);
    swprintf(command, MAX_PATH + 32, L"\"%ls\" -ps:widl", server_path);
    CHECK(RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_WRITE, &h) == ERROR_SUCCESS);
    CHECK(RegSetValueExW(h, NULL, 0, REG_SZ, (const BYTE *)command, (DWORD)((wcslen(command) + 1) * sizeof(WCHAR))) ==
          ERROR_SUCCESS);
    RegCloseKey(h);
}

/* GetErrorString of a vendor code of the test server, as a malloc'd copy (NULL on failure). */
static WCHAR *ask(IOPCCommon *c, HRESULT code) {
    LPWSTR text = (LPWSTR)GARBAGE_PTR;
    WCHAR *copy = NULL;
    HRESULT hr = c->lpVtbl->GetErrorString(c, code, &text);
    if (SUCCEEDED(hr) && text) {
        size_t n = wlen(text);
        copy = (WCHAR *)malloc((n + 1) * sizeof(WCHAR));
        memcpy(copy, text, (n + 1) * sizeof(WCHAR));
    }
    if (SUCCEEDED(hr)) CoTaskMemFree(text);
    return copy;
}

static void check_common(IOPCCommon *c) {
    LCID lcid = GARBAGE_U32, *lcids = (LCID *)GARBAGE_PTR;
    DWORD count = GARBAGE_U32, i;
    LPWSTR text = (LPWSTR)GARBAGE_PTR, local = NULL;
    WCHAR *name, *seen;
    int all = 1;

    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0407), S_OK);
    CHECK_HR(c->lpVtbl->GetLocaleID(c, &lcid), S_OK);
    CHECK(lcid == 0x0407);
    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0C0C), E_INVALIDARG); /* not one the server declared */
    CHECK_HR(c->lpVtbl->GetLocaleID(c, &lcid), S_OK);
    CHECK(lcid == 0x0407);
    CHECK(FAILED(c->lpVtbl->GetLocaleID(c, NULL))); /* the proxy refuses a NULL [out] pointer */

    /* The array arrives whole: every declared locale, in order, at the start. */
    CHECK_HR(c->lpVtbl->QueryAvailableLocaleIDs(c, &count, &lcids), S_OK);
    CHECK(count >= OOP_LOCALES && count <= OOP_LOCALES + 4);
    for (i = 0; lcids && i < OOP_LOCALES && i < count; i++) all &= lcids[i] == oop_locale(i);
    CHECK(all && lcids != NULL);
    CoTaskMemFree(lcids);

    /* Texts are allocated for this process, in the session's language. */
    CHECK_HR(c->lpVtbl->GetErrorString(c, (HRESULT)0xC0040007L, &text), S_OK); /* OPC_E_UNKNOWNITEMID */
    CHECK_HR(OpcGetErrorString((HRESULT)0xC0040007L, 0x0407, &local), S_OK);
    CHECK(text != NULL && wsame(text, local));
    CoTaskMemFree(text);
    OpcTaskMemFree(local);
    text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(c->lpVtbl->GetErrorString(c, (HRESULT)0x12345678L, &text), E_INVALIDARG);
    CHECK(text == NULL); /* a failing call still gives NULL on the client side */

    /* SetClientName: the server sees it. */
    CHECK_HR(c->lpVtbl->SetClientName(c, W("Client \xc3\x84 \xf0\x9f\x98\x80 1")), S_OK);
    seen = ask(c, OOP_CODE_CLIENT_NAME);
    CHECK(wstr_is(seen, "Client \xc3\x84 \xf0\x9f\x98\x80 1"));
    free(seen);

    /* The library's bound: 2^19 code units go through both ways, one more is refused. */
    name = long_name(STRING_BOUND);
    CHECK_HR(c->lpVtbl->SetClientName(c, name), S_OK);
    seen = ask(c, OOP_CODE_CLIENT_NAME);
    CHECK(seen && wlen(seen) == STRING_BOUND && wsame(seen, name));
    free(seen);
    free(name);
    name = long_name(STRING_BOUND + 1);
    CHECK_HR(c->lpVtbl->SetClientName(c, name), E_INVALIDARG);
    free(name);
    name = long_name((size_t)1 << 22); /* 8 MiB on the wire */
    CHECK_HR(c->lpVtbl->SetClientName(c, name), E_INVALIDARG);
    free(name);
    seen = ask(c, OOP_CODE_CLIENT_NAME); /* the server kept the last accepted name and still answers */
    CHECK(seen && wlen(seen) == STRING_BOUND);
    free(seen);
    CHECK(FAILED(c->lpVtbl->SetClientName(c, NULL)));
    CHECK_HR(c->lpVtbl->GetLocaleID(c, &lcid), S_OK);
}

/* Wine's proxies implement IClientSecurity with SetBlanket and QueryBlanket as stubs answering
 * E_NOTIMPL (Wine 8); Windows' set and report the blanket. */
static int under_wine(void) {
    HMODULE ntdll = GetModuleHandleW(L"ntdll.dll");
    return ntdll && GetProcAddress(ntdll, "wine_get_version") != NULL;
}

/* OpcSetProxyBlanket on a real proxy. On Windows it succeeds and the levels reach the proxy
 * (CoQueryProxyBlanket reads them back). Under Wine it reaches the proxy's IClientSecurity (an
 * in-process object has none: E_NOINTERFACE, c-tests/test_security.c) and passes on its E_NOTIMPL.
 * Either way the proxy and its IUnknown keep working, and a weak level is refused before COM. */
static void check_blanket(IOPCCommon *c) {
    OpcSecurityOptions o;
    DWORD authn = 0, imp = 0;
    LCID lcid = 0;
    IUnknown *container = NULL;
    int wine = under_wine();
    HRESULT expected = wine ? E_NOTIMPL : S_OK;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    CHECK_HR(OpcSetProxyBlanket((IUnknown *)c, NULL), expected);
    if (!wine) {
        CHECK_HR(CoQueryProxyBlanket((IUnknown *)c, NULL, NULL, NULL, &authn, &imp, NULL, NULL), S_OK);
        CHECK(authn == RPC_C_AUTHN_LEVEL_PKT_INTEGRITY && imp == RPC_C_IMP_LEVEL_IMPERSONATE);
    }
    o.authn_level = RPC_C_AUTHN_LEVEL_PKT_PRIVACY;
    o.imp_level = RPC_C_IMP_LEVEL_IDENTIFY;
    CHECK_HR(OpcSetProxyBlanket((IUnknown *)c, &o), expected);
    if (!wine) {
        CHECK_HR(CoQueryProxyBlanket((IUnknown *)c, NULL, NULL, NULL, &authn, &imp, NULL, NULL), S_OK);
        CHECK(authn == RPC_C_AUTHN_LEVEL_PKT_PRIVACY && imp == RPC_C_IMP_LEVEL_IDENTIFY);
    }
    /* A weak level is refused before COM is asked. */
    o.authn_level = RPC_C_AUTHN_LEVEL_CONNECT;
    CHECK_HR(OpcSetProxyBlanket((IUnknown *)c, &o), E_INVALIDARG);
    /* The proxy still calls, and QueryInterface still goes through the IUnknown. */
    CHECK_HR(c->lpVtbl->GetLocaleID(c, &lcid), S_OK);
    CHECK_HR(c->lpVtbl->QueryInterface(c, &IID_IConnectionPointContainer, (void **)&container), S_OK);
    if (container) {
        CHECK_HR(OpcSetProxyBlanket(container, NULL), expected);
        container->lpVtbl->Release(container);
    }
}

typedef struct SinkState {
    IUnknown *server;
    DWORD cookie;
    LONG calls;
    HRESULT unadvise;
    DWORD thread;
    WCHAR reason[128];
} SinkState;

static void on_shutdown(void *context, LPCWSTR reason) {
    SinkState *s = (SinkState *)context;
    size_t n = wlen(reason);
    InterlockedIncrement(&s->calls);
    s->thread = GetCurrentThreadId();
    if (n < 128) memcpy(s->reason, reason, (n + 1) * sizeof(WCHAR));
    s->unadvise = OpcShutdownUnadvise(s->server, s->cookie); /* from inside the callback */
}

static void check_shutdown(IOPCCommon *c) {
    IUnknown *sink = NULL, *cpc = NULL;
    SinkState state;
    WCHAR *answer;
    memset(&state, 0, sizeof state);
    state.server = (IUnknown *)c;
    state.unadvise = E_FAIL;
    CHECK_HR(c->lpVtbl->QueryInterface(c, &IID_IConnectionPointContainer, (void **)&cpc), S_OK);
    if (cpc) cpc->lpVtbl->Release(cpc);
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown, &state, &IID_IUnknown, (void **)&sink), S_OK);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)c, sink, &state.cookie), S_OK);
    CHECK(state.cookie != 0);
    sink->lpVtbl->Release(sink); /* the server's connection keeps the sink alive */

    answer = ask(c, OOP_CODE_SHUTDOWN);
    CHECK(wstr_is(answer, "hr=00000000 notified=1 failed=0"));
    if (answer && !wstr_is(answer, "hr=00000000 notified=1 failed=0")) {
        fputs("  shutdown answer: ", stderr);
        wprint(stderr, answer);
        fputc('\n', stderr);
    }
    free(answer);
    CHECK(state.calls == 1);
    CHECK(wstr_is(state.reason, OOP_REASON));
    CHECK_HR(state.unadvise, S_OK);
    CHECK(state.thread != 0 && state.thread != GetCurrentThreadId()); /* it came in through RPC */

    answer = ask(c, OOP_CODE_SHUTDOWN); /* unadvised: nobody left to notify */
    CHECK(wstr_is(answer, "hr=00000000 notified=0 failed=0"));
    free(answer);
    CHECK(state.calls == 1);
    CHECK_HR(OpcShutdownUnadvise((IUnknown *)c, state.cookie), CONNECT_E_NOCONNECTION);
}

/* ---- The bounded notification: a client that blocks, a client that was killed ---- */
#define OOP_ADVISED_EVENT L"Local\\OpcComnOopSinkAdvised"

typedef struct BlockingSink {
    HANDLE entered, release; /* set when ShutdownRequest came in; set by the test to let it return */
    LONG calls;
} BlockingSink;

static void on_shutdown_blocking(void *context, LPCWSTR reason) {
    BlockingSink *b = (BlockingSink *)context;
    (void)reason;
    InterlockedIncrement(&b->calls);
    SetEvent(b->entered);
    WaitForSingleObject(b->release, INFINITE); /* a hung client, until the test lets it go */
}

static void on_shutdown_counting(void *context, LPCWSTR reason) {
    (void)reason;
    InterlockedIncrement((LONG *)context);
}

/* The child process of the killed-client case: advises a sink of its own on the server object
 * marshaled into `hex`, releases every reference to the server, says so and waits to be killed. */
static int advise_and_wait_to_die(const char *hex) {
    size_t n = strlen(hex) / 2, i;
    HGLOBAL mem = GlobalAlloc(GMEM_MOVEABLE, n ? n : 1);
    unsigned char *bytes = mem ? (unsigned char *)GlobalLock(mem) : NULL;
    IStream *stream = NULL;
    IUnknown *server = NULL, *sink = NULL;
    DWORD cookie = 0;
    LONG calls = 0;
    HANDLE advised = OpenEventW(EVENT_MODIFY_STATE, FALSE, OOP_ADVISED_EVENT);
    if (!bytes || !advised) return 10;
    for (i = 0; i < n; i++) {
        unsigned v = 0;
        sscanf(hex + 2 * i, "%2x", &v);
        bytes[i] = (unsigned char)v;
    }
    GlobalUnlock(mem);
    if (FAILED(CoInitializeEx(NULL, COINIT_MULTITHREADED))) return 11;
    if (FAILED(CreateStreamOnHGlobal(mem, TRUE, &stream))) return 12;
    if (FAILED(CoUnmarshalInterface(stream, &IID_IUnknown, (void **)&server))) return 13;
    stream->lpVtbl->Release(stream);
    if (FAILED(OpcShutdownSinkCreate(on_shutdown_counting, &calls, &IID_IUnknown, (void **)&sink))) return 14;
    if (FAILED(OpcShutdownAdvise(server, sink, &cookie))) return 15;
    server->lpVtbl->Release(server); /* so that its death leaves no reference in the server */
    SetEvent(advised);
    Sleep(INFINITE);
    return 0;
}

/* Starts the child of the killed-client case on the server object `c` and kills it once its sink is
 * advised. Returns whether that happened. */
static int advise_from_a_client_that_dies(IOPCCommon *c) {
    IStream *stream = NULL;
    HGLOBAL mem = NULL;
    unsigned char *bytes;
    SIZE_T size, i;
    char *cmd;
    WCHAR *wcmd, self[MAX_PATH];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    HANDLE advised = CreateEventW(NULL, TRUE, FALSE, OOP_ADVISED_EVENT), both[2];
    int ok = 0;
    if (!advised) return 0;
    if (FAILED(CreateStreamOnHGlobal(NULL, TRUE, &stream))) return 0;
    if (FAILED(CoMarshalInterface(stream, &IID_IUnknown, (IUnknown *)c, MSHCTX_LOCAL, NULL, MSHLFLAGS_NORMAL)) ||
        FAILED(GetHGlobalFromStream(stream, &mem))) {
        stream->lpVtbl->Release(stream);
        return 0;
    }
    size = GlobalSize(mem);
    bytes = (unsigned char *)GlobalLock(mem);
    GetModuleFileNameW(NULL, self, MAX_PATH);
    cmd = (char *)malloc(2 * size + 1);
    wcmd = (WCHAR *)malloc((2 * size + MAX_PATH + 32) * sizeof(WCHAR));
    if (bytes && cmd && wcmd) {
        for (i = 0; i < size; i++) snprintf(cmd + 2 * i, 3, "%02x", bytes[i]);
        swprintf(wcmd, 2 * size + MAX_PATH + 32, L"\"%ls\" die-advised %hs", self, cmd);
        memset(&si, 0, sizeof si);
        si.cb = sizeof si;
        if (CreateProcessW(NULL, wcmd, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi)) {
            both[0] = advised;
            both[1] = pi.hProcess;
            ok = WaitForMultipleObjects(2, both, FALSE, 60000) == WAIT_OBJECT_0;
            TerminateProcess(pi.hProcess, 9); /* killed: it never unadvises */
            WaitForSingleObject(pi.hProcess, 60000);
            CloseHandle(pi.hProcess);
            CloseHandle(pi.hThread);
        }
    }
    if (bytes) GlobalUnlock(mem);
    free(cmd);
    free(wcmd);
    stream->lpVtbl->Release(stream);
    CloseHandle(advised);
    return ok;
}

/* OpcShutdownNotifyBounded in the server: a client hung in ShutdownRequest times out without
 * holding up a client that answers, a killed client counts as failed (it neither hangs the
 * notification nor is counted as notified), and the hung call returning late harms nobody. */
static void check_bounded_shutdown(IOPCCommon *c) {
    BlockingSink blocking;
    LONG quick_calls = 0;
    int retries, back = 0;
    IUnknown *blocking_sink = NULL, *quick_sink = NULL;
    DWORD blocking_cookie = 0, quick_cookie = 0;
    WCHAR *answer;
    blocking.entered = CreateEventW(NULL, TRUE, FALSE, NULL);
    blocking.release = CreateEventW(NULL, TRUE, FALSE, NULL);
    blocking.calls = 0;

    CHECK(advise_from_a_client_that_dies(c));
    /* The notification that waits for every sink does not hang on a dead client either. */
    answer = ask(c, OOP_CODE_SHUTDOWN);
    CHECK(wstr_is(answer, "hr=00000001 notified=0 failed=1"));
    free(answer);
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown_blocking, &blocking, &IID_IUnknown, (void **)&blocking_sink), S_OK);
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown_counting, &quick_calls, &IID_IUnknown, (void **)&quick_sink), S_OK);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)c, blocking_sink, &blocking_cookie), S_OK);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)c, quick_sink, &quick_cookie), S_OK);

    answer = ask(c, OOP_CODE_SHUTDOWN_BOUNDED);
    /* The answer came while the blocking sink is still inside ShutdownRequest (released below). */
    CHECK(WaitForSingleObject(blocking.entered, 0) == WAIT_OBJECT_0);
    CHECK(wstr_is(answer, "hr=00000001 notified=1 failed=1 timed_out=1"));
    if (answer && !wstr_is(answer, "hr=00000001 notified=1 failed=1 timed_out=1")) {
        fputs("  bounded shutdown answer: ", stderr);
        wprint(stderr, answer);
        fputc('\n', stderr);
    }
    free(answer);
    CHECK(quick_calls == 1 && blocking.calls == 1);

    /* The late return: the server's worker gets the answer after the notification is over. The
     * server goes on answering; until the late call is back in the server, a notification counts
     * the hung client as timed out without calling it again, and then notifies it normally. */
    SetEvent(blocking.release);
    for (retries = 0;; retries++) {
        answer = ask(c, OOP_CODE_SHUTDOWN_BOUNDED);
        back = wstr_is(answer, "hr=00000001 notified=2 failed=1 timed_out=0");
        if (!back) CHECK(wstr_is(answer, "hr=00000001 notified=1 failed=1 timed_out=1"));
        free(answer);
        if (back || retries == 1000) break;
        Sleep(5);
    }
    CHECK(back);
    CHECK(quick_calls == 2 + retries && blocking.calls == 2);

    CHECK_HR(OpcShutdownUnadvise((IUnknown *)c, blocking_cookie), S_OK);
    CHECK_HR(OpcShutdownUnadvise((IUnknown *)c, quick_cookie), S_OK);
    if (blocking_sink) blocking_sink->lpVtbl->Release(blocking_sink);
    if (quick_sink) quick_sink->lpVtbl->Release(quick_sink);
    CloseHandle(blocking.entered);
    CloseHandle(blocking.release);
}

static int is_fake(const GUID *g, int *seen) {
    unsigned n;
    for (n = 0; n < OOP_FAKE_SERVERS; n++) {
        CLSID f = oop_fake_clsid(n);
        if (IsEqualGUID(g, &f)) {
            if (seen[n]) return 0;
            seen[n] = 1;
            return 1;
        }
    }
    return 0;
}

static void check_server_list(void) {
    IOPCServerList2 *l2 = NULL;
    IOPCServerList *l1 = NULL;
    IOPCEnumGUID *e = NULL, *clone = NULL;
    IEnumGUID *e1 = NULL;
    GUID buf[128];
    ULONG fetched = GARBAGE_U32, total = 0;
    int seen[OOP_FAKE_SERVERS] = {0}, ok = 1;
    LPOLESTR prog = (LPOLESTR)GARBAGE_PTR, user = (LPOLESTR)GARBAGE_PTR, vi = (LPOLESTR)GARBAGE_PTR;
    CLSID clsid, five = oop_fake_clsid(5), unknown = oop_fake_clsid(1000);
    static CATID many[4097];
    unsigned i;

    CHECK_HR(CoCreateInstance(&CLSID_OopServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&l2), S_OK);
    if (!l2) return;
    CHECK_HR(l2->lpVtbl->EnumClassesOfCategories(l2, 1, (CATID *)&CATID_DA2, 0, NULL, &e), S_OK);
    if (e) {
        /* Several elements per Next across the boundary, then the rest, then nothing. */
        CHECK_HR(e->lpVtbl->Next(e, 7, buf, &fetched), S_OK);
        CHECK(fetched == 7);
        for (i = 0; i < fetched && i < 7; i++) ok &= is_fake(&buf[i], seen);
        total += fetched;
        CHECK_HR(e->lpVtbl->Skip(e, 3), S_OK);
        total += 3;
        CHECK_HR(e->lpVtbl->Clone(e, &clone), S_OK);
        fetched = GARBAGE_U32;
        CHECK_HR(e->lpVtbl->Next(e, 128, buf, &fetched), S_FALSE);
        CHECK(fetched == OOP_FAKE_SERVERS - 10);
        for (i = 0; i < fetched && i < 128; i++) ok &= is_fake(&buf[i], seen);
        total += fetched;
        CHECK(ok && total == OOP_FAKE_SERVERS);
        CHECK_HR(e->lpVtbl->Next(e, 5, buf, &fetched), S_FALSE);
        CHECK(fetched == 0);
        if (clone) { /* the clone continues where the original was */
            CHECK_HR(clone->lpVtbl->Next(clone, 128, buf, &fetched), S_FALSE);
            CHECK(fetched == OOP_FAKE_SERVERS - 10);
            clone->lpVtbl->Release(clone);
        }
        CHECK_HR(e->lpVtbl->Reset(e), S_OK);
        /* A count far beyond what exists, with the room for it that the caller must provide (the
         * proxy clears that much): up to the bound of 65536 GUIDs (1 MiB) the stub allocates it on the
         * server side and only the elements that exist come back; beyond it opccomn's proxy refuses to
         * send the call and opccomn's stub refuses to run it (RPC_S_INVALID_BOUND), before anything is
         * allocated (docs/proxy-stub-robustness.md). */
        {
            GUID *big = (GUID *)malloc((OOP_NEXT_BOUND + 1) * sizeof(GUID));
            fetched = GARBAGE_U32;
            CHECK_HR(e->lpVtbl->Next(e, OOP_NEXT_BOUND, big, &fetched), S_FALSE);
            CHECK(fetched == OOP_FAKE_SERVERS);
            CHECK_HR(e->lpVtbl->Reset(e), S_OK);
            fetched = GARBAGE_U32;
            CHECK_HR(e->lpVtbl->Next(e, OOP_NEXT_BOUND + 1, big, &fetched), HRESULT_FROM_WIN32(RPC_S_INVALID_BOUND));
            free(big);
        }
        e->lpVtbl->Release(e);
    }

    CHECK_HR(l2->lpVtbl->GetClassDetails(l2, &five, &prog, &user, &vi), S_OK);
    CHECK(wstr_is(prog, "Oop.Fake5.1") && wstr_is(user, "Oop fake server 5") && wstr_is(vi, "Oop.Fake5"));
    CoTaskMemFree(prog);
    CoTaskMemFree(user);
    CoTaskMemFree(vi);
    prog = user = vi = (LPOLESTR)GARBAGE_PTR;
    CHECK(FAILED(l2->lpVtbl->GetClassDetails(l2, &unknown, &prog, &user, &vi)));
    CHECK(prog == NULL && user == NULL && vi == NULL);
    CHECK_HR(l2->lpVtbl->CLSIDFromProgID(l2, W("Oop.Fake9.1"), &clsid), S_OK);
    {
        CLSID nine = oop_fake_clsid(9);
        CHECK(IsEqualGUID(&clsid, &nine));
    }
    memset(&clsid, 0xAB, sizeof clsid);
    CHECK(FAILED(l2->lpVtbl->CLSIDFromProgID(l2, W("Oop.Nothing.1"), &clsid)));
    CHECK(IsEqualGUID(&clsid, &GUID_NULL));

    /* Category arrays up to the library's limit of 4096 go through; 4097 are refused. */
    for (i = 0; i < 4097; i++) many[i] = CATID_DA2;
    e = (IOPCEnumGUID *)GARBAGE_PTR;
    CHECK_HR(l2->lpVtbl->EnumClassesOfCategories(l2, 4096, many, 0, NULL, &e), S_OK);
    if (e && e != GARBAGE_PTR) {
        CHECK_HR(e->lpVtbl->Next(e, 128, buf, &fetched), S_FALSE);
        CHECK(fetched == OOP_FAKE_SERVERS);
        e->lpVtbl->Release(e);
    }
    e = (IOPCEnumGUID *)GARBAGE_PTR;
    CHECK_HR(l2->lpVtbl->EnumClassesOfCategories(l2, 4097, many, 0, NULL, &e), E_INVALIDARG);
    CHECK(e == NULL);

    /* IOPCServerList with the system's IEnumGUID. */
    CHECK_HR(l2->lpVtbl->QueryInterface(l2, &IID_IOPCServerList, (void **)&l1), S_OK);
    if (l1) {
        CHECK_HR(l1->lpVtbl->EnumClassesOfCategories(l1, 1, (CATID *)&CATID_DA2, 0, NULL, &e1), S_OK);
        if (e1) {
            CHECK_HR(e1->lpVtbl->Next(e1, 10, buf, &fetched), S_OK);
            CHECK(fetched == 10);
            e1->lpVtbl->Release(e1);
        }
        prog = user = (LPOLESTR)GARBAGE_PTR;
        CHECK_HR(l1->lpVtbl->GetClassDetails(l1, &five, &prog, &user), S_OK);
        CHECK(wstr_is(prog, "Oop.Fake5.1") && wstr_is(user, "Oop fake server 5"));
        CoTaskMemFree(prog);
        CoTaskMemFree(user);
        l1->lpVtbl->Release(l1);
    }
    l2->lpVtbl->Release(l2);
}

/* A client that releases its last object and connects again at once (as clients do that browse and
 * then connect) is served every time, never by a process that exits under its call: within the
 * server's linger by the same process, which serves on; after it by a new one. The pauses stay far
 * from the linger's end, where under Wine an activation can still meet the end (see
 * docs/guide/server-plumbing.md). */
static void check_reconnect_at_once(void) {
    static const DWORD pauses[] = {0, 0, 1, 20, OOP_LINGER_MS + 1500, 0};
    IOPCCommon *c;
    WCHAR *pid, *last = NULL;
    size_t i;
    for (i = 0; i < sizeof pauses / sizeof pauses[0]; i++) {
        c = NULL;
        CHECK_HR(CoCreateInstance(&CLSID_OopServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&c), S_OK);
        if (!c) {
            printf("test_oop: the activation above came %lu ms after the last release\n", (unsigned long)(i ? pauses[i - 1] : 0));
            continue;
        }
        pid = ask(c, OOP_CODE_PROCESS_ID);
        CHECK(pid != NULL);
        if (pid && last) {
            /* The same process within the linger, a new one after it. */
            int same = wcscmp(pid, last) == 0;
            CHECK(same == (pauses[i - 1] < OOP_LINGER_MS));
        }
        free(last);
        last = pid;
        c->lpVtbl->Release(c);
        Sleep(pauses[i]);
    }
    free(last);
}

/* A client that releases the server list and then walks the enumerator it got (as many OPC clients
 * do) keeps the server process: every object an EXE server hands out counts until it is released. */
static void check_enumerator_outlives_list(void) {
    IOPCServerList2 *l2 = NULL;
    IOPCEnumGUID *e = NULL;
    GUID buf[128];
    ULONG fetched = 0;
    int waited;
    CHECK_HR(CoCreateInstance(&CLSID_OopServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&l2), S_OK);
    if (!l2) return;
    CHECK_HR(l2->lpVtbl->EnumClassesOfCategories(l2, 1, (CATID *)&CATID_DA2, 0, NULL, &e), S_OK);
    l2->lpVtbl->Release(l2);
    if (!e) return;
    CHECK(process_stays(L"opccomn_test_server.exe", 2000));
    CHECK_HR(e->lpVtbl->Next(e, 128, buf, &fetched), S_FALSE);
    CHECK(fetched == OOP_FAKE_SERVERS);
    e->lpVtbl->Release(e);
    for (waited = 0; waited < 100 && process_running(L"opccomn_test_server.exe") == 1; waited++) Sleep(100);
    CHECK(process_running(L"opccomn_test_server.exe") == 0); /* and exits once it is released */
}

/* The operator stops the server while a client is connected, by OpcExeServerStop (what a service's
 * control handler or the server's own window calls): the host calls the server's on_stop, which tells
 * the client's sink across processes, waits for the client to let go, and then the process exits. */
static void check_operator_stop(void) {
    IOPCCommon *c = NULL;
    IUnknown *sink = NULL;
    LONG calls = 0;
    DWORD cookie = 0;
    WCHAR *answer;
    int waited;
    CHECK_HR(CoCreateInstance(&CLSID_OopServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&c), S_OK);
    if (!c) return;
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown_counting, &calls, &IID_IUnknown, (void **)&sink), S_OK);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)c, sink, &cookie), S_OK);
    answer = ask(c, OOP_CODE_STOP);
    CHECK(wstr_is(answer, "stop=00000000"));
    free(answer);
    for (waited = 0; waited < 100 && InterlockedCompareExchange(&calls, 0, 0) == 0; waited++) Sleep(100);
    CHECK(InterlockedCompareExchange(&calls, 0, 0) == 1);     /* on_stop told the client */
    CHECK(process_stays(L"opccomn_test_server.exe", 1000));    /* and the server waits for it */
    CHECK_HR(OpcShutdownUnadvise((IUnknown *)c, cookie), S_OK);
    c->lpVtbl->Release(c);
    if (sink) sink->lpVtbl->Release(sink);
    for (waited = 0; waited < 100 && process_running(L"opccomn_test_server.exe") == 1; waited++) Sleep(100);
    CHECK(process_running(L"opccomn_test_server.exe") == 0); /* gone once the client let go */
}

int main(int argc, char **argv) {
    OpcServerRegistration server, list;
    IOPCCommon *c = NULL;
    WCHAR *which;
    WCHAR *slash;
    int i;
    if (argc == 3 && strcmp(argv[1], "die-advised") == 0) return advise_and_wait_to_die(argv[2]);
    if (argc != 3) {
        fprintf(stderr, "usage: test_oop opccomn|widl opccomn|widl\n");
        return 2;
    }
    widl_client = strcmp(argv[1], "widl") == 0;
    widl_server = strcmp(argv[2], "widl") == 0;
    printf("test_oop: client proxy/stub %s, server proxy/stub %s\n", argv[1], argv[2]);
    GetModuleFileNameW(NULL, server_path, MAX_PATH);
    slash = wcsrchr(server_path, L'\\');
    wcscpy(slash ? slash + 1 : server_path, L"opccomn_test_server.exe");

    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    if (widl_client) CHECK_HR(use_widl_proxy_stub(), S_OK);
    OpcUnregisterProxyStub(NULL); /* whatever an interrupted earlier run left */
    CHECK_HR(OpcRegisterProxyStub(NULL, 0), S_OK);
    server = server_registration(&CLSID_OopServer, L"Oop.Server.1");
    list = server_registration(&CLSID_OopServerList, L"Oop.ServerList.1");
    CHECK_HR(OpcRegisterServer(&server, NULL), S_OK);
    CHECK_HR(OpcRegisterServer(&list, NULL), S_OK);
    if (widl_server) {
        set_server_command(&CLSID_OopServer);
        set_server_command(&CLSID_OopServerList);
    }

    CHECK_HR(CoCreateInstance(&CLSID_OopServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&c), S_OK);
    if (c) {
        /* Which proxy/stub serves: in this process, and in the server's. */
        if (widl_client) {
            CHECK_HR(widl_proxy_stub_in_use(), S_FALSE);
            CHECK_HR(OpcDllCanUnloadNow(), S_OK);
        } else {
            CHECK(OpcObjectCount() == 0);
            CHECK_HR(OpcDllCanUnloadNow(), S_FALSE); /* our proxy is alive */
            CHECK_HR(widl_proxy_stub_in_use(), E_FAIL);
        }
        which = ask(c, OOP_CODE_PROXY_STUB);
        CHECK(wstr_is(which, widl_server ? "widl" : "opccomn"));
        free(which);

        check_common(c);
        check_blanket(c);
        check_shutdown(c);
        check_bounded_shutdown(c);
        c->lpVtbl->Release(c);
    }
    check_server_list();
    /* The server's lifetime does not depend on the proxy/stub: checked once. */
    if (!widl_client && !widl_server) check_reconnect_at_once();
    check_enumerator_outlives_list();
    check_operator_stop();
    CoUninitialize();
    CHECK(OpcObjectCount() == 0); /* the shutdown sink is gone in this process too */
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);

    /* Undo the registration and check nothing of it is left. */
    CHECK_HR(OpcUnregisterServer(&server, NULL), S_OK);
    CHECK_HR(OpcUnregisterServer(&list, NULL), S_OK);
    CHECK_HR(OpcUnregisterProxyStub(NULL), S_OK);
    CHECK(!key_exists(L"CLSID\\{3D738B71-0B9D-4337-A725-E8541A96D1C9}"));
    CHECK(!key_exists(L"CLSID\\{C3000000-5EED-4000-8000-000000000001}"));
    for (i = 0; i < 5; i++) {
        WCHAR key[64], guid[40];
        StringFromGUID2(OOP_IIDS[i], guid, 40);
        swprintf(key, 64, L"Interface\\%ls", guid);
        CHECK(!key_exists(key));
    }
    CoUninitialize();
    return test_summary("test_oop");
}
