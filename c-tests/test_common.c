/* IOPCCommon through the public header: every method, every error path, reference counting,
 * identity, aggregation into a C outer object, and two sessions kept apart. */
#include <stddef.h>

#include "test_util.h"

#define CODE_INVALIDHANDLE ((HRESULT)0xC0040001u)
#define CODE_INUSE ((HRESULT)0x0004000Fu)
#define CODE_UNKNOWN ((HRESULT)0x12345678u)
#define CODE_VENDOR ((HRESULT)0xE0000001u)

static const IID IID_Bogus_ = {0x01234567, 0x89AB, 0xCDEF, {1, 2, 3, 4, 5, 6, 7, 8}};

static IOPCCommon *create_common(const OpcCommonOptions *options) {
    void *p = GARBAGE_PTR;
    HRESULT hr = OpcCommonCreate(options, NULL, &IID_IOPCCommon, &p);
    CHECK_HR(hr, S_OK);
    CHECK(p != NULL && p != GARBAGE_PTR);
    return hr == S_OK ? (IOPCCommon *)p : NULL;
}

static void test_create_errors(void) {
    uint32_t before = OpcObjectCount();
    void *p = GARBAGE_PTR;
    OpcCommonOptions o;

    CHECK_HR(OpcCommonCreate(NULL, NULL, &IID_IOPCCommon, NULL), E_POINTER);
    CHECK_HR(OpcCommonCreate(NULL, NULL, NULL, &p), E_POINTER);
    CHECK(p == NULL);

    p = GARBAGE_PTR;
    CHECK_HR(OpcCommonCreate(NULL, NULL, &IID_Bogus_, &p), E_NOINTERFACE);
    CHECK(p == NULL);

    memset(&o, 0, sizeof o); /* struct_size 0 */
    p = GARBAGE_PTR;
    CHECK_HR(OpcCommonCreate(&o, NULL, &IID_IOPCCommon, &p), E_INVALIDARG);
    CHECK(p == NULL);

    o.struct_size = sizeof o + 8; /* from a newer header than the library knows */
    p = GARBAGE_PTR;
    CHECK_HR(OpcCommonCreate(&o, NULL, &IID_IOPCCommon, &p), E_INVALIDARG);
    CHECK(p == NULL);

    o.struct_size = (uint32_t)(offsetof(OpcCommonOptions, locales) + sizeof o.locales / 2); /* ends inside a pointer */
    p = GARBAGE_PTR;
    CHECK_HR(OpcCommonCreate(&o, NULL, &IID_IOPCCommon, &p), E_INVALIDARG);
    CHECK(p == NULL);

    o.struct_size = sizeof o;
    o.server_kind = 99;
    CHECK_HR(OpcCommonCreate(&o, NULL, &IID_IOPCCommon, &p), E_INVALIDARG);
    CHECK(p == NULL);

    o.server_kind = 0;
    o.locale_count = 1; /* a count without an array */
    CHECK_HR(OpcCommonCreate(&o, NULL, &IID_IOPCCommon, &p), E_INVALIDARG);
    {
        static LCID many[5000];
        o.locales = many;
        o.locale_count = 5000;
        CHECK_HR(OpcCommonCreate(&o, NULL, &IID_IOPCCommon, &p), E_INVALIDARG);
        CHECK(p == NULL);
    }
    CHECK(OpcObjectCount() == before);
}

static void test_locale(void) {
    IOPCCommon *c = create_common(NULL);
    LCID lcid = GARBAGE_U32;
    DWORD count = GARBAGE_U32;
    LCID *list = (LCID *)GARBAGE_PTR;
    DWORD i;
    int has_system = 0, has_user = 0, has_neutral = 0, has_invariant = 0, has_english = 0;
    if (!c) return;

    CHECK_HR(c->lpVtbl->GetLocaleID(c, &lcid), S_OK);
    CHECK(lcid == LOCALE_SYSTEM_DEFAULT);
    CHECK_HR(c->lpVtbl->GetLocaleID(c, NULL), E_INVALIDARG);

    CHECK_HR(c->lpVtbl->QueryAvailableLocaleIDs(c, &count, &list), S_OK);
    CHECK(list != NULL && list != (LCID *)GARBAGE_PTR);
    CHECK(count >= 5);
    for (i = 0; list && i < count; i++) {
        has_system |= list[i] == LOCALE_SYSTEM_DEFAULT;
        has_user |= list[i] == LOCALE_USER_DEFAULT;
        has_neutral |= list[i] == LOCALE_NEUTRAL;
        has_invariant |= list[i] == LOCALE_INVARIANT;
        has_english |= list[i] == 0x0409;
        /* SetLocaleID accepts exactly what QueryAvailableLocaleIDs reports. */
        CHECK_HR(c->lpVtbl->SetLocaleID(c, list[i]), S_OK);
        CHECK_HR(c->lpVtbl->GetLocaleID(c, &lcid), S_OK);
        CHECK(lcid == list[i]);
    }
    CHECK(has_system && has_user && has_neutral && has_invariant && has_english);
    OpcTaskMemFree(list);

    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0409), S_OK);
    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x040C), E_INVALIDARG); /* French: not declared */
    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0xFFFFFFFFu), E_INVALIDARG);
    CHECK_HR(c->lpVtbl->GetLocaleID(c, &lcid), S_OK);
    CHECK(lcid == 0x0409); /* a refused locale changes nothing */

    /* Either out-parameter NULL: E_INVALIDARG, and the other one is still written. */
    count = GARBAGE_U32;
    CHECK_HR(c->lpVtbl->QueryAvailableLocaleIDs(c, &count, NULL), E_INVALIDARG);
    CHECK(count == 0);
    list = (LCID *)GARBAGE_PTR;
    CHECK_HR(c->lpVtbl->QueryAvailableLocaleIDs(c, NULL, &list), E_INVALIDARG);
    CHECK(list == NULL);

    CHECK(c->lpVtbl->Release(c) == 0);
}

static void test_declared_locales(void) {
    static const LCID declared[] = {0x0407, 0x0409, 0x0407, LOCALE_SYSTEM_DEFAULT};
    OpcCommonOptions o;
    IOPCCommon *c;
    DWORD count = 0, i, german = 0, system = 0;
    LCID *list = NULL, lcid = 0;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.locales = declared;
    o.locale_count = 4;
    c = create_common(&o);
    if (!c) return;
    CHECK_HR(c->lpVtbl->QueryAvailableLocaleIDs(c, &count, &list), S_OK);
    CHECK(count == 6); /* 0407, 0409, 0800, 0400, 0000, 007F: duplicates reported once */
    for (i = 0; list && i < count; i++) {
        german += list[i] == 0x0407;
        system += list[i] == LOCALE_SYSTEM_DEFAULT;
    }
    CHECK(german == 1 && system == 1);
    CHECK(list && list[0] == 0x0407 && list[1] == 0x0409);
    OpcTaskMemFree(list);
    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0407), S_OK);
    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0807), E_INVALIDARG); /* de-CH was not declared */
    CHECK_HR(c->lpVtbl->GetLocaleID(c, &lcid), S_OK);
    CHECK(lcid == 0x0407);
    c->lpVtbl->Release(c);
}

static void test_error_string(void) {
    IOPCCommon *c = create_common(NULL);
    LPWSTR text = (LPWSTR)GARBAGE_PTR;
    if (!c) return;
    /* English explicitly: the default session locale follows the machine's language. */
    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0409), S_OK);
    CHECK_HR(c->lpVtbl->GetErrorString(c, CODE_INVALIDHANDLE, &text), S_OK);
    CHECK(wstr_is(text, "The value of the handle is invalid."));
    OpcTaskMemFree(text);
    text = NULL;
    CHECK_HR(c->lpVtbl->GetErrorString(c, CODE_INUSE, &text), S_OK);
    CHECK(wstr_is(text, "The operation cannot be performed because the object is bering referenced."));
#if defined(_WIN32)
    CoTaskMemFree(text); /* on Windows library memory is COM task memory */
#else
    OpcTaskMemFree(text);
#endif
    text = NULL;
    CHECK_HR(c->lpVtbl->GetErrorString(c, E_INVALIDARG, &text), S_OK);
    CHECK(text != NULL && wlen(text) > 0);
    OpcTaskMemFree(text);

    text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(c->lpVtbl->GetErrorString(c, CODE_UNKNOWN, &text), E_INVALIDARG);
    CHECK(text == NULL);
    CHECK_HR(c->lpVtbl->GetErrorString(c, CODE_INVALIDHANDLE, NULL), E_INVALIDARG);

    /* The standalone function gives the same texts. */
    text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(OpcGetErrorString(CODE_INVALIDHANDLE, 0x0409, &text), S_OK);
    CHECK(wstr_is(text, "The value of the handle is invalid."));
    OpcTaskMemFree(text);
    text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(OpcGetErrorString(CODE_UNKNOWN, 0x0409, &text), E_INVALIDARG);
    CHECK(text == NULL);
    CHECK_HR(OpcGetErrorString(CODE_INVALIDHANDLE, 0x0409, NULL), E_INVALIDARG);
    c->lpVtbl->Release(c);
}

/* A vendor callback that knows one code and declines everything else. */
struct vendor_log {
    int calls;
    LCID last_locale;
};

static HRESULT vendor_text(void *context, HRESULT code, LCID locale, LPCWSTR *text) {
    struct vendor_log *log = (struct vendor_log *)context;
    static WCHAR buf[64];
    const WCHAR *src = W("Valve 7 is stuck.");
    size_t i;
    log->calls++;
    log->last_locale = locale;
    if (code != CODE_VENDOR) return S_FALSE;
    for (i = 0; src[i]; i++) buf[i] = src[i];
    buf[i] = 0;
    *text = buf;
    return S_OK;
}

static void test_vendor_callback(void) {
    struct vendor_log log = {0, 0};
    OpcCommonOptions o;
    IOPCCommon *c;
    LPWSTR text = NULL;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.vendor_error_string = vendor_text;
    o.vendor_error_context = &log;
    c = create_common(&o);
    if (!c) return;
    CHECK_HR(c->lpVtbl->GetErrorString(c, CODE_VENDOR, &text), S_OK);
    CHECK(wstr_is(text, "Valve 7 is stuck."));
    OpcTaskMemFree(text);
    CHECK(log.calls == 1);
    CHECK(log.last_locale != LOCALE_SYSTEM_DEFAULT); /* the callback sees a concrete locale */

    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0409), S_OK);
    text = NULL;
    CHECK_HR(c->lpVtbl->GetErrorString(c, CODE_INVALIDHANDLE, &text), S_OK); /* declined: catalog */
    CHECK(wstr_is(text, "The value of the handle is invalid."));
    OpcTaskMemFree(text);
    CHECK(log.calls == 2);

    text = NULL;
    CHECK_HR(c->lpVtbl->GetErrorString(c, CODE_VENDOR, &text), S_OK);
    OpcTaskMemFree(text);
    CHECK(log.last_locale == 0x0409);
    c->lpVtbl->Release(c);

    /* A struct from an older header: fields past struct_size are never read. */
    o.struct_size = (uint32_t)offsetof(OpcCommonOptions, vendor_error_string);
    o.vendor_error_string = (OpcVendorErrorStringFn)GARBAGE_PTR;
    c = create_common(&o);
    if (!c) return;
    text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(c->lpVtbl->GetErrorString(c, CODE_VENDOR, &text), E_INVALIDARG);
    CHECK(text == NULL);
    c->lpVtbl->Release(c);
}

struct name_log {
    int calls;
    WCHAR last[64];
};

static void name_changed(void *context, LPCWSTR name) {
    struct name_log *log = (struct name_log *)context;
    size_t i;
    log->calls++;
    for (i = 0; name[i] && i < 63; i++) log->last[i] = name[i];
    log->last[i] = 0;
}

static void test_client_name(void) {
    struct name_log log;
    OpcCommonOptions o;
    IOPCCommon *c;
    LPWSTR name = (LPWSTR)GARBAGE_PTR;
    static const WCHAR lone_surrogate[] = {'a', 0xD800, 'b', 0};
    memset(&log, 0, sizeof log);
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.client_name_changed = name_changed;
    o.client_name_context = &log;
    c = create_common(&o);
    if (!c) return;

    CHECK_HR(OpcCommonGetClientName((IUnknown *)c, &name), S_OK); /* none set yet: empty */
    CHECK(name != NULL && name[0] == 0);
    OpcTaskMemFree(name);

    CHECK_HR(c->lpVtbl->SetClientName(c, NULL), E_INVALIDARG);
    CHECK(log.calls == 0);
    CHECK_HR(c->lpVtbl->SetClientName(c, W("NODE7\\historian.exe")), S_OK);
    CHECK(log.calls == 1);
    CHECK(wstr_is(log.last, "NODE7\\historian.exe"));
    name = NULL;
    CHECK_HR(OpcCommonGetClientName((IUnknown *)c, &name), S_OK);
    CHECK(wstr_is(name, "NODE7\\historian.exe"));
    OpcTaskMemFree(name);

    /* Invalid UTF-16 is kept exactly, not rejected. */
    CHECK_HR(c->lpVtbl->SetClientName(c, lone_surrogate), S_OK);
    name = NULL;
    CHECK_HR(OpcCommonGetClientName((IUnknown *)c, &name), S_OK);
    CHECK(name && name[0] == 'a' && name[1] == 0xD800 && name[2] == 'b' && name[3] == 0);
    OpcTaskMemFree(name);

    CHECK_HR(c->lpVtbl->SetClientName(c, W("")), S_OK);
    name = NULL;
    CHECK_HR(OpcCommonGetClientName((IUnknown *)c, &name), S_OK);
    CHECK(name && name[0] == 0);
    OpcTaskMemFree(name);

    name = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(OpcCommonGetClientName(NULL, &name), E_INVALIDARG);
    CHECK(name == NULL);
    CHECK_HR(OpcCommonGetClientName((IUnknown *)c, NULL), E_INVALIDARG);
    c->lpVtbl->Release(c);
}

static void test_sessions_apart(void) {
    IOPCCommon *a = create_common(NULL);
    IOPCCommon *b = create_common(NULL);
    LCID lcid = 0;
    LPWSTR name = NULL;
    if (!a || !b) return;
    CHECK_HR(a->lpVtbl->SetLocaleID(a, 0x0409), S_OK);
    CHECK_HR(a->lpVtbl->SetClientName(a, W("client A")), S_OK);
    CHECK_HR(b->lpVtbl->GetLocaleID(b, &lcid), S_OK);
    CHECK(lcid == LOCALE_SYSTEM_DEFAULT);
    CHECK_HR(OpcCommonGetClientName((IUnknown *)b, &name), S_OK);
    CHECK(name && name[0] == 0);
    OpcTaskMemFree(name);
    CHECK_HR(b->lpVtbl->SetClientName(b, W("client B")), S_OK);
    name = NULL;
    CHECK_HR(OpcCommonGetClientName((IUnknown *)a, &name), S_OK);
    CHECK(wstr_is(name, "client A"));
    OpcTaskMemFree(name);
    a->lpVtbl->Release(a);
    b->lpVtbl->Release(b);
}

static void test_refcount_and_identity(void) {
    uint32_t before = OpcObjectCount();
    IOPCCommon *c = create_common(NULL);
    IUnknown *u1 = (IUnknown *)GARBAGE_PTR, *u2 = NULL;
    void *p = GARBAGE_PTR;
    if (!c) return;
    CHECK(OpcObjectCount() == before + 1);
    CHECK(c->lpVtbl->AddRef(c) == 2);
    CHECK(c->lpVtbl->Release(c) == 1);

    CHECK_HR(c->lpVtbl->QueryInterface(c, &IID_Unknown_, (void **)&u1), S_OK);
    CHECK_HR(c->lpVtbl->QueryInterface(c, &IID_Unknown_, (void **)&u2), S_OK);
    CHECK(u1 == u2 && u1 != NULL); /* one identity */
    CHECK_HR(u1->lpVtbl->QueryInterface(u1, &IID_IOPCCommon, &p), S_OK);
    CHECK(p == (void *)c);
    ((IOPCCommon *)p)->lpVtbl->Release((IOPCCommon *)p);
    u2->lpVtbl->Release(u2);

    p = GARBAGE_PTR;
    CHECK_HR(c->lpVtbl->QueryInterface(c, &IID_Bogus_, &p), E_NOINTERFACE);
    CHECK(p == NULL);
    CHECK_HR(c->lpVtbl->QueryInterface(c, &IID_IOPCCommon, NULL), E_POINTER);
    p = GARBAGE_PTR;
    CHECK_HR(c->lpVtbl->QueryInterface(c, NULL, &p), E_POINTER);
    CHECK(p == NULL);
    CHECK(u1->lpVtbl->Release(u1) == 1);
    CHECK(c->lpVtbl->Release(c) == 0);
    CHECK(OpcObjectCount() == before);
}


static void test_aggregation(void) {
    uint32_t before = OpcObjectCount();
    AggregatingServer s;
    void *p = GARBAGE_PTR;
    IOPCCommon *c = NULL;
    IUnknown *identity = NULL;
    LPWSTR name = NULL;
    aggregating_server_init(&s, &IID_IOPCCommon);

    /* With an outer object only IID_IUnknown may be asked for. */
    CHECK_HR(OpcCommonCreate(NULL, &s.unk, &IID_IOPCCommon, &p), CLASS_E_NOAGGREGATION);
    CHECK(p == NULL);
    CHECK(s.add_refs == 0); /* the outer object was not touched */

    CHECK_HR(OpcCommonCreate(NULL, &s.unk, &IID_Unknown_, (void **)&s.inner), S_OK);
    if (!s.inner) return;
    CHECK(s.add_refs == 0 && s.releases == 0); /* creating the inner object does not count on the outer */
    CHECK(OpcObjectCount() == before + 1);

    CHECK_HR(aggregating_qi(&s.unk, &IID_IOPCCommon, (void **)&c), S_OK);
    if (!c) return;
    CHECK(s.refs == 2 && s.add_refs == 1); /* the interface's AddRef went to the outer object */
    CHECK(c->lpVtbl->AddRef(c) == 3);
    CHECK(c->lpVtbl->Release(c) == 2);
    CHECK(s.releases == 1);

    CHECK_HR(c->lpVtbl->QueryInterface(c, &IID_Unknown_, (void **)&identity), S_OK);
    CHECK(identity == &s.unk); /* identity is the outer object */
    identity->lpVtbl->Release(identity);

    CHECK_HR(c->lpVtbl->SetClientName(c, W("aggregated client")), S_OK);
    CHECK_HR(OpcCommonGetClientName(&s.unk, &name), S_OK); /* found through the outer object */
    CHECK(wstr_is(name, "aggregated client"));
    OpcTaskMemFree(name);

    CHECK(c->lpVtbl->Release(c) == 1);
    CHECK(OpcObjectCount() == before + 1);
    CHECK(aggregating_release(&s.unk) == 0);
    CHECK(s.destroyed);
    CHECK(s.add_refs == s.releases - 1); /* balanced: the initial reference was the last Release */
    CHECK(OpcObjectCount() == before);
}

static void test_allocator(void) {
    void *p = OpcTaskMemAlloc(0);
    CHECK(p != NULL);
    OpcTaskMemFree(p);
    p = OpcTaskMemAlloc(1000);
    CHECK(p != NULL);
    if (p) memset(p, 0xAB, 1000);
    OpcTaskMemFree(p);
    OpcTaskMemFree(NULL);
}

/* The server decides each locale (listed or not) and is told of every change; it reads the session's
 * locale cheaply through the IOPCCommon pointer. */
struct locale_log {
    int asked, changes;
    LCID last_asked, last_changed;
    int32_t last_listed;
};

static int32_t OPCCOMN_CDECL accept_locale(void *context, LCID locale, int32_t listed) {
    struct locale_log *log = (struct locale_log *)context;
    log->asked++;
    log->last_asked = locale;
    log->last_listed = listed;
    return locale == 0x0411 ? 1 : locale == 0x0407 ? 0 : listed;
}

static void OPCCOMN_CDECL locale_changed(void *context, LCID locale) {
    struct locale_log *log = (struct locale_log *)context;
    log->changes++;
    log->last_changed = locale;
}

static void test_locale_hooks(void) {
    static const LCID declared[] = {0x0409, 0x0407};
    struct locale_log log;
    OpcCommonOptions o;
    IOPCCommon *c;
    LCID lcid = 0x1234;
    memset(&log, 0, sizeof log);
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.locales = declared;
    o.locale_count = 2;
    o.accept_locale = accept_locale;
    o.accept_locale_context = &log;
    o.locale_changed = locale_changed;
    o.locale_changed_context = &log;
    c = create_common(&o);
    if (!c) return;

    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0411), S_OK);
    CHECK(log.asked == 1 && log.last_asked == 0x0411 && log.last_listed == 0);
    CHECK(log.changes == 1 && log.last_changed == 0x0411);
    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0407), E_INVALIDARG);
    CHECK(log.asked == 2 && log.last_listed == 1);
    CHECK(log.changes == 1);
    CHECK_HR(OpcCommonGetLocale((IUnknown *)c, &lcid), S_OK);
    CHECK(lcid == 0x0411);

    lcid = 0x1234;
    CHECK_HR(OpcCommonGetLocale(NULL, &lcid), E_INVALIDARG);
    CHECK(lcid == 0);
    CHECK_HR(OpcCommonGetLocale((IUnknown *)c, NULL), E_INVALIDARG);
    c->lpVtbl->Release(c);
}

/* Vendor texts handed over in task memory: the client receives the server's own allocation. */
static LPWSTR handed_text;

static HRESULT OPCCOMN_CDECL vendor_text_handed_over(void *context, HRESULT code, LCID locale, LPWSTR *text) {
    static const char message[] = "driver 7: link down";
    size_t i;
    (void)context;
    (void)locale;
    if (code != (HRESULT)0xE0000007) return S_FALSE;
    handed_text = (LPWSTR)OpcTaskMemAlloc(sizeof message * sizeof(WCHAR));
    if (!handed_text) return E_OUTOFMEMORY;
    for (i = 0; i < sizeof message; i++) handed_text[i] = (WCHAR)message[i];
    *text = handed_text;
    return S_OK;
}

static void test_vendor_text_in_task_memory(void) {
    OpcCommonOptions o;
    IOPCCommon *c;
    LPWSTR text = (LPWSTR)GARBAGE_PTR;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    o.vendor_error_text = vendor_text_handed_over;
    c = create_common(&o);
    if (!c) return;
    CHECK_HR(c->lpVtbl->GetErrorString(c, (HRESULT)0xE0000007, &text), S_OK);
    CHECK(text == handed_text);
    CHECK(wstr_is(text, "driver 7: link down"));
    OpcTaskMemFree(text);
    c->lpVtbl->Release(c);
}

/* What docs/guide/iopccommon-and-errors.md tells a server that aggregates its session: keep the inner
 * IUnknown, which does not count on the server object, and read the session through it; an IOPCCommon
 * pointer kept instead counts on the server object, which then outlives its last client (a cycle). */
static void test_aggregating_server_keeps_the_inner_unknown(void) {
    AggregatingServer s;
    IOPCCommon *c = NULL, *kept = NULL;
    LCID lcid = 0x1234;
    uint32_t before = OpcObjectCount();
    aggregating_server_init(&s, &IID_IOPCCommon);
    CHECK_HR(OpcCommonCreate(NULL, &s.unk, &IID_Unknown_, (void **)&s.inner), S_OK);
    if (!s.inner) return;

    /* A client sets its locale through the server object and lets go of the interface. */
    CHECK_HR(aggregating_qi(&s.unk, &IID_IOPCCommon, (void **)&c), S_OK);
    if (!c) return;
    CHECK_HR(c->lpVtbl->SetLocaleID(c, 0x0407), S_OK);
    c->lpVtbl->Release(c);

    /* The server reads it through the inner IUnknown; what that costs the server object's count is
     * given back at once. */
    CHECK_HR(OpcCommonGetLocale(s.inner, &lcid), S_OK);
    CHECK(lcid == 0x0407);
    CHECK(s.refs == 1 && s.add_refs == s.releases);

    /* An IOPCCommon pointer the server keeps is a reference the server object holds on itself: the
     * client's last Release leaves it alive. */
    CHECK_HR(s.inner->lpVtbl->QueryInterface(s.inner, &IID_IOPCCommon, (void **)&kept), S_OK);
    if (!kept) return;
    CHECK(s.refs == 2);
    CHECK(aggregating_release(&s.unk) == 1); /* the client's last reference */
    CHECK(!s.destroyed);
    kept->lpVtbl->Release(kept); /* the cycle broken by hand */
    CHECK(s.destroyed);
    CHECK(OpcObjectCount() == before);
}

int main(void) {
    test_create_errors();
    test_locale();
    test_declared_locales();
    test_error_string();
    test_vendor_callback();
    test_client_name();
    test_locale_hooks();
    test_vendor_text_in_task_memory();
    test_sessions_apart();
    test_refcount_and_identity();
    test_aggregation();
    test_aggregating_server_keeps_the_inner_unknown();
    test_allocator();
    CHECK(OpcObjectCount() == 0);
    return test_summary("test_common");
}
