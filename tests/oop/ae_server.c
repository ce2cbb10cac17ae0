/* The EXE server of the cross-process test of the Alarms & Events proxy/stub (test_ae_tables.c): a
 * small OPC A&E server written in C (LocalServer32, started by COM with -Embedding, hosted by
 * OpcExeServerRun), reached through opccomn.dll's proxies and stubs, which it registers for this
 * process (classic_oop.h). It serves what ae.h describes and checks what it receives: a request that
 * does not arrive as the client sent it is answered with E_INVALIDARG (or a per-element error),
 * which the client sees.
 *
 * Server object: IOPCEventServer2 (GetStatus, CreateEventSubscription, QueryAvailableFilters,
 * QueryEventCategories, QueryConditionNames, QuerySubConditionNames, QuerySourceConditions,
 * QueryEventAttributes, TranslateToItemIDs, GetConditionState, the Enable/Disable methods of both
 * versions, GetEnableStateByArea/BySource, AckCondition, CreateAreaBrowser). Area browser object:
 * IOPCEventAreaBrowser over the areas and sources of ae.h (BrowseOPCAreas with MatchPatternW's
 * filters: an IEnumString of the names).
 * Subscription object: IOPCEventSubscriptionMgt2 (SetFilter, GetFilter, SelectReturnedAttributes,
 * GetReturnedAttributes, GetState, SetState, Refresh: an OnEvent of the two events of ae.h from a
 * thread of the server; CancelRefresh; SetKeepAlive, GetKeepAlive) and IConnectionPointContainer
 * with the IOPCEventSink connection point. What the test does not call answers E_NOTIMPL. */
#include "ae.h"

#include "enum_strings.h"
#include "sink_point.h"

#define CONTAINER(type, field, p) ((type *)((char *)(p) - offsetof(type, field)))

/* The area (by_area) or source whose name is `name`, or -1. */
static int name_index(int by_area, const WCHAR *name) {
    int i;
    for (i = 0; name && i < (by_area ? AE_AREAS : AE_SOURCES); i++)
        if (is_utf8(name, by_area ? AE_AREA_NAMES[i] : AE_SOURCE_NAMES[i])) return i;
    return -1;
}

/* ---- The subscription ---- */

typedef struct Subscription {
    IOPCEventSubscriptionMgt2 mgt; /* the identity (IOPCEventSubscriptionMgt too) */
    SinkPoint cp;                 /* IOPCEventSink */
    LONG refs;
    CRITICAL_SECTION lock;
    BOOL active;
    DWORD buffer_time, max_size;
    OPCHANDLE client;
    DWORD keep_alive; /* SetKeepAlive's revised time */
    int filtered; /* SetFilter received the client's filter */
    DWORD selected[AE_CATEGORIES][AE_EVENT_ATTRS]; /* SelectReturnedAttributes' IDs per category */
    DWORD nselected[AE_CATEGORIES];
} Subscription;

static HRESULT sub_query(Subscription *s, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCEventSubscriptionMgt) ||
        IsEqualIID(riid, &IID_IOPCEventSubscriptionMgt2))
        *ppv = &s->mgt;
    else if (IsEqualIID(riid, &IID_IConnectionPointContainer)) *ppv = &s->cp.container;
    else return E_NOINTERFACE;
    InterlockedIncrement(&s->refs);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE sub_qi(IOPCEventSubscriptionMgt2 *This, REFIID riid, void **ppv) {
    return sub_query(CONTAINER(Subscription, mgt, This), riid, ppv);
}
static ULONG STDMETHODCALLTYPE sub_add_ref(IOPCEventSubscriptionMgt2 *This) {
    return (ULONG)InterlockedIncrement(&CONTAINER(Subscription, mgt, This)->refs);
}
static ULONG STDMETHODCALLTYPE sub_release(IOPCEventSubscriptionMgt2 *This) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    LONG n = InterlockedDecrement(&s->refs);
    if (n == 0) {
        sink_point_end(&s->cp);
        DeleteCriticalSection(&s->lock);
        free(s);
        OpcServerUnlock(); /* a subscription counts on the process while it lives */
    }
    return (ULONG)n;
}

/* Whether `names` are the UTF-8 texts `want[0..count)`. */
static int names_are(const LPWSTR *names, DWORD count, const char *const *want) {
    DWORD k;
    if (count && !names) return 0;
    for (k = 0; k < count; k++)
        if (!is_utf8(names[k], want[k])) return 0;
    return 1;
}

static HRESULT STDMETHODCALLTYPE sub_set_filter(IOPCEventSubscriptionMgt2 *This, DWORD type, DWORD ncat, DWORD *cats,
                                                DWORD low, DWORD high, DWORD nareas, LPWSTR *areas, DWORD nsources,
                                                LPWSTR *sources) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    int as_sent = type == (AE_CONDITION_EVENT | AE_TRACKING_EVENT) && ncat == AE_FILTER_CATEGORIES && cats &&
                  memcmp(cats, AE_FILTER_CATEGORY_IDS, sizeof AE_FILTER_CATEGORY_IDS) == 0 && low == AE_FILTER_LOW &&
                  high == AE_FILTER_HIGH && nareas == AE_FILTER_AREAS &&
                  names_are(areas, nareas, AE_AREA_NAMES + 1) && nsources == AE_FILTER_SOURCES &&
                  names_are(sources, nsources, AE_SOURCE_NAMES);
    if (!as_sent) return E_INVALIDARG;
    EnterCriticalSection(&s->lock);
    s->filtered = 1;
    LeaveCriticalSection(&s->lock);
    return S_OK;
}

/* A copy in task memory of the UTF-8 texts `names[0..count)`, or NULL. */
static LPWSTR *task_names(const char *const *names, DWORD count) {
    LPWSTR *copy = (LPWSTR *)task_zero(count * sizeof *copy);
    DWORD k;
    for (k = 0; copy && k < count; k++) copy[k] = task_utf8(names[k]);
    return copy;
}

static HRESULT STDMETHODCALLTYPE sub_get_filter(IOPCEventSubscriptionMgt2 *This, DWORD *type, DWORD *ncat, DWORD **cats,
                                                DWORD *low, DWORD *high, DWORD *nareas, LPWSTR **areas,
                                                DWORD *nsources, LPWSTR **sources) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    int filtered;
    if (!type || !ncat || !cats || !low || !high || !nareas || !areas || !nsources || !sources) return E_POINTER;
    EnterCriticalSection(&s->lock);
    filtered = s->filtered;
    LeaveCriticalSection(&s->lock);
    *cats = NULL;
    *areas = NULL;
    *sources = NULL;
    *ncat = *nareas = *nsources = 0;
    *low = filtered ? AE_FILTER_LOW : 1;
    *high = filtered ? AE_FILTER_HIGH : 1000;
    *type = filtered ? AE_CONDITION_EVENT | AE_TRACKING_EVENT : AE_ALL_EVENTS;
    if (!filtered) return S_OK;
    *cats = (DWORD *)task_zero(sizeof AE_FILTER_CATEGORY_IDS);
    if (*cats) memcpy(*cats, AE_FILTER_CATEGORY_IDS, sizeof AE_FILTER_CATEGORY_IDS);
    *areas = task_names(AE_AREA_NAMES + 1, AE_FILTER_AREAS);
    *sources = task_names(AE_SOURCE_NAMES, AE_FILTER_SOURCES);
    *ncat = AE_FILTER_CATEGORIES;
    *nareas = AE_FILTER_AREAS;
    *nsources = AE_FILTER_SOURCES;
    return *cats && *areas && *sources ? S_OK : E_OUTOFMEMORY;
}

/* The index of category `category` in AE_CATEGORY_IDS, or -1. */
static int category_index(DWORD category) {
    int i;
    for (i = 0; i < AE_CATEGORIES; i++)
        if (AE_CATEGORY_IDS[i] == category) return i;
    return -1;
}

/* The attributes returned for a category: each an attribute of it, none twice, or the call is refused. */
static HRESULT STDMETHODCALLTYPE sub_select_attrs(IOPCEventSubscriptionMgt2 *This, DWORD category, DWORD count,
                                                  DWORD *ids) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    int c = category_index(category);
    DWORD k, j;
    if (c < 0 || count > AE_EVENT_ATTRS || (count && !ids)) return E_INVALIDARG;
    for (k = 0; k < count; k++) {
        if (ae_event_attr(category, ids[k]) < 0) return E_INVALIDARG;
        for (j = 0; j < k; j++)
            if (ids[j] == ids[k]) return E_INVALIDARG;
    }
    EnterCriticalSection(&s->lock);
    memcpy(s->selected[c], ids, count * sizeof *ids);
    s->nselected[c] = count;
    LeaveCriticalSection(&s->lock);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE sub_returned_attrs(IOPCEventSubscriptionMgt2 *This, DWORD category, DWORD *count,
                                                    DWORD **ids) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    int c = category_index(category);
    if (!count || !ids) return E_POINTER;
    *count = 0;
    *ids = NULL;
    if (c < 0) return E_INVALIDARG;
    EnterCriticalSection(&s->lock);
    if (s->nselected[c] && (*ids = (DWORD *)task_zero(s->nselected[c] * sizeof(DWORD))) != NULL) {
        memcpy(*ids, s->selected[c], s->nselected[c] * sizeof(DWORD));
        *count = s->nselected[c];
    }
    LeaveCriticalSection(&s->lock);
    return *count || !s->nselected[c] ? S_OK : E_OUTOFMEMORY;
}

/* The OnEvent of a refresh, from a thread of the server. */
static DWORD WINAPI refresh_thread(void *param) {
    Subscription *s = (Subscription *)param;
    ONEVENTSTRUCT events[AE_EVENTS];
    VARIANT attrs[AE_EVENTS][2];
    IOPCEventSink *sink;
    OPCHANDLE client;
    int i;
    CoInitializeEx(NULL, COINIT_MULTITHREADED);
    sink = (IOPCEventSink *)sink_point_sink(&s->cp);
    EnterCriticalSection(&s->lock);
    client = s->client;
    LeaveCriticalSection(&s->lock);
    for (i = 0; i < AE_EVENTS; i++) ae_fill_event(i, &events[i], attrs[i]);
    if (sink) {
        sink->lpVtbl->OnEvent(sink, client, TRUE, TRUE, AE_EVENTS, events);
        sink->lpVtbl->Release(sink);
    }
    for (i = 0; i < AE_EVENTS; i++) ae_free_event(&events[i]);
    sub_release(&s->mgt);
    CoUninitialize();
    return 0;
}

static HRESULT STDMETHODCALLTYPE sub_refresh(IOPCEventSubscriptionMgt2 *This, DWORD connection) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    IUnknown *sink = sink_point_sink(&s->cp);
    HANDLE thread;
    if (!sink) return CONNECT_E_NOCONNECTION;
    sink->lpVtbl->Release(sink);
    if (connection != 1) return E_INVALIDARG;
    sub_add_ref(This);
    thread = CreateThread(NULL, 0, refresh_thread, s, 0, NULL);
    if (!thread) {
        sub_release(This);
        return E_OUTOFMEMORY;
    }
    CloseHandle(thread);
    return S_OK;
}

/* No refresh is under way when the client cancels one (the test cancels before it refreshes): E_FAIL
 * for the client's connection, E_INVALIDARG for another. */
static HRESULT STDMETHODCALLTYPE sub_cancel_refresh(IOPCEventSubscriptionMgt2 *This, DWORD connection) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    IUnknown *sink = sink_point_sink(&s->cp);
    if (!sink) return CONNECT_E_NOCONNECTION;
    sink->lpVtbl->Release(sink);
    return connection == 1 ? E_FAIL : E_INVALIDARG;
}

static HRESULT STDMETHODCALLTYPE sub_get_state(IOPCEventSubscriptionMgt2 *This, BOOL *active, DWORD *buffer_time,
                                               DWORD *max_size, OPCHANDLE *client) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    if (!active || !buffer_time || !max_size || !client) return E_POINTER;
    EnterCriticalSection(&s->lock);
    *active = s->active;
    *buffer_time = s->buffer_time;
    *max_size = s->max_size;
    *client = s->client;
    LeaveCriticalSection(&s->lock);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE sub_set_state(IOPCEventSubscriptionMgt2 *This, BOOL *active, DWORD *buffer_time,
                                               DWORD *max_size, OPCHANDLE client, DWORD *revised_buffer_time,
                                               DWORD *revised_max_size) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    if (!revised_buffer_time || !revised_max_size) return E_POINTER;
    EnterCriticalSection(&s->lock);
    if (active) s->active = *active;
    if (buffer_time) s->buffer_time = *buffer_time < 500 ? 500 : *buffer_time;
    if (max_size) s->max_size = *max_size;
    s->client = client;
    *revised_buffer_time = s->buffer_time;
    *revised_max_size = s->max_size;
    LeaveCriticalSection(&s->lock);
    return S_OK;
}

/* The keep-alive time: the one the client asks (AE_KEEP_ALIVE) revised to AE_REVISED_KEEP_ALIVE, or 0
 * (none); another is not as the client sent it. */
static HRESULT STDMETHODCALLTYPE sub_set_keep_alive(IOPCEventSubscriptionMgt2 *This, DWORD time, DWORD *revised) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    if (!revised) return E_POINTER;
    *revised = 0;
    if (time != AE_KEEP_ALIVE && time != 0) return E_INVALIDARG;
    EnterCriticalSection(&s->lock);
    s->keep_alive = time ? AE_REVISED_KEEP_ALIVE : 0;
    *revised = s->keep_alive;
    LeaveCriticalSection(&s->lock);
    return time ? OPC_S_INVALIDKEEPALIVETIME_AE : S_OK;
}

static HRESULT STDMETHODCALLTYPE sub_get_keep_alive(IOPCEventSubscriptionMgt2 *This, DWORD *time) {
    Subscription *s = CONTAINER(Subscription, mgt, This);
    if (!time) return E_POINTER;
    EnterCriticalSection(&s->lock);
    *time = s->keep_alive;
    LeaveCriticalSection(&s->lock);
    return S_OK;
}

static IOPCEventSubscriptionMgt2Vtbl sub_vtbl = {
    sub_qi,      sub_add_ref,        sub_release,   sub_set_filter, sub_get_filter, sub_select_attrs,
    sub_returned_attrs, sub_refresh, sub_cancel_refresh, sub_get_state, sub_set_state, sub_set_keep_alive,
    sub_get_keep_alive};

/* ---- The server ---- */

typedef struct Server {
    IOPCEventServer2 iface; /* the identity */
    LONG refs;
    CRITICAL_SECTION lock;
    BOOL area_enabled[AE_AREAS];
    BOOL source_enabled[AE_SOURCES];
} Server;

#define SERVER(This) CONTAINER(Server, iface, This)

static HRESULT STDMETHODCALLTYPE srv_qi(IOPCEventServer2 *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!IsEqualIID(riid, &IID_IUnknown) && !IsEqualIID(riid, &IID_IOPCEventServer) &&
        !IsEqualIID(riid, &IID_IOPCEventServer2))
        return E_NOINTERFACE;
    *ppv = This;
    InterlockedIncrement(&SERVER(This)->refs);
    return S_OK;
}
static ULONG STDMETHODCALLTYPE srv_add_ref(IOPCEventServer2 *This) {
    return (ULONG)InterlockedIncrement(&SERVER(This)->refs);
}
static ULONG STDMETHODCALLTYPE srv_release(IOPCEventServer2 *This) {
    Server *s = SERVER(This);
    LONG n = InterlockedDecrement(&s->refs);
    if (n == 0) {
        DeleteCriticalSection(&s->lock);
        free(s);
        OpcServerUnlock();
    }
    return (ULONG)n;
}

static HRESULT STDMETHODCALLTYPE srv_status(IOPCEventServer2 *This, OPCEVENTSERVERSTATUS **status) {
    OPCEVENTSERVERSTATUS *st;
    (void)This;
    if (!status) return E_POINTER;
    *status = NULL;
    st = (OPCEVENTSERVERSTATUS *)task_zero(sizeof *st);
    if (!st) return E_OUTOFMEMORY;
    st->ftStartTime = test_time(0);
    st->ftCurrentTime = test_time(1);
    st->ftLastUpdateTime = test_time(2);
    st->dwServerState = OPCAE_STATUS_RUNNING;
    st->wMajorVersion = 1;
    st->wMinorVersion = 10;
    st->wBuildNumber = 42;
    st->wReserved = 0;
    st->szVendorInfo =
        task_utf8(proxy_stub_is_opccomn_for(AE_IIDS, AE_IID_COUNT) ? AE_VENDOR_INFO : AE_VENDOR_INFO_OTHER);
    *status = st;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE srv_create_subscription(IOPCEventServer2 *This, BOOL active, DWORD buffer_time,
                                                         DWORD max_size, OPCHANDLE client, REFIID riid,
                                                         LPUNKNOWN *unk, DWORD *revised_buffer_time,
                                                         DWORD *revised_max_size) {
    Subscription *s;
    HRESULT hr;
    (void)This;
    if (!unk || !revised_buffer_time || !revised_max_size) return E_POINTER;
    *unk = NULL;
    *revised_buffer_time = 0;
    *revised_max_size = 0;
    if (!active || buffer_time != AE_BUFFER_TIME || max_size != AE_MAX_SIZE || client != AE_CLIENT_SUBSCRIPTION)
        return E_INVALIDARG;
    s = (Subscription *)calloc(1, sizeof *s);
    if (!s) return E_OUTOFMEMORY;
    s->mgt.lpVtbl = &sub_vtbl;
    s->refs = 1;
    OpcServerLock();
    InitializeCriticalSection(&s->lock);
    sink_point_init(&s->cp, (IUnknown *)&s->mgt, &IID_IOPCEventSink);
    s->active = TRUE;
    s->buffer_time = AE_REVISED_BUFFER_TIME;
    s->max_size = AE_REVISED_MAX_SIZE;
    s->client = client;
    hr = sub_query(s, riid, (void **)unk);
    sub_release(&s->mgt);
    if (FAILED(hr)) return hr;
    *revised_buffer_time = AE_REVISED_BUFFER_TIME;
    *revised_max_size = AE_REVISED_MAX_SIZE;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE srv_filters(IOPCEventServer2 *This, DWORD *mask) {
    (void)This;
    if (!mask) return E_POINTER;
    *mask = AE_FILTER_MASK;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE srv_categories(IOPCEventServer2 *This, DWORD type, DWORD *count, DWORD **ids,
                                                LPWSTR **texts) {
    (void)This;
    if (!count || !ids || !texts) return E_POINTER;
    *count = 0;
    *ids = NULL;
    *texts = NULL;
    if (type != AE_ALL_EVENTS) return E_INVALIDARG;
    *ids = (DWORD *)task_zero(sizeof AE_CATEGORY_IDS);
    *texts = task_names(AE_CATEGORY_TEXTS, AE_CATEGORIES);
    if (!*ids || !*texts) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    memcpy(*ids, AE_CATEGORY_IDS, sizeof AE_CATEGORY_IDS);
    *count = AE_CATEGORIES;
    return S_OK;
}

/* A names reply: the UTF-8 texts `want[0..n)` (n may be 0: NULL), or the error `refused`. */
static HRESULT names_reply(const char *const *want, DWORD n, HRESULT refused, DWORD *count, LPWSTR **names) {
    if (!count || !names) return E_POINTER;
    *count = 0;
    *names = NULL;
    if (FAILED(refused)) return refused;
    if (!n) return S_OK;
    *names = task_names(want, n);
    if (!*names) return E_OUTOFMEMORY;
    *count = n;
    return S_OK;
}

/* Category 1001's conditions; the other categories have none. */
static HRESULT STDMETHODCALLTYPE srv_condition_names(IOPCEventServer2 *This, DWORD category, DWORD *count,
                                                     LPWSTR **names) {
    (void)This;
    return names_reply(AE_CONDITION_NAMES, category == AE_CATEGORY_IDS[0] ? AE_CONDITIONS : 0,
                       category_index(category) < 0 ? E_INVALIDARG : S_OK, count, names);
}

/* AE_CONDITION's sub-conditions; the other condition has none. */
static HRESULT STDMETHODCALLTYPE srv_subcondition_names(IOPCEventServer2 *This, LPWSTR condition, DWORD *count,
                                                        LPWSTR **names) {
    int level = is_utf8(condition, AE_CONDITION_NAMES[0]);
    (void)This;
    return names_reply(AE_SC_NAMES, level ? AE_SUBCONDITIONS : 0,
                       level || is_utf8(condition, AE_CONDITION_NAMES[1]) ? S_OK : E_INVALIDARG, count, names);
}

static HRESULT STDMETHODCALLTYPE srv_source_conditions(IOPCEventServer2 *This, LPWSTR source, DWORD *count,
                                                       LPWSTR **names) {
    int i = name_index(0, source);
    (void)This;
    return names_reply(i < 0 ? NULL : AE_CONDITION_NAMES + AE_SOURCE_CONDITION[i], i < 0 ? 0 : 1,
                       i < 0 ? E_INVALIDARG : S_OK, count, names);
}

static HRESULT STDMETHODCALLTYPE srv_event_attributes(IOPCEventServer2 *This, DWORD category, DWORD *count,
                                                      DWORD **ids, LPWSTR **texts, VARTYPE **types) {
    int rows[AE_EVENT_ATTRS], n, k;
    (void)This;
    if (!count || !ids || !texts || !types) return E_POINTER;
    *count = 0;
    *ids = NULL;
    *texts = NULL;
    *types = NULL;
    n = ae_category_attrs(category, rows);
    if (n < 0) return E_INVALIDARG;
    if (n == 0) return S_OK;
    *ids = (DWORD *)task_zero(n * sizeof(DWORD));
    *texts = (LPWSTR *)task_zero(n * sizeof(LPWSTR));
    *types = (VARTYPE *)task_zero(n * sizeof(VARTYPE));
    if (!*ids || !*texts || !*types) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    for (k = 0; k < n; k++) {
        (*ids)[k] = AE_EVENT_ATTR_TABLE[rows[k]].id;
        (*texts)[k] = task_utf8(AE_EVENT_ATTR_TABLE[rows[k]].desc);
        (*types)[k] = AE_EVENT_ATTR_TABLE[rows[k]].type;
    }
    *count = (DWORD)n;
    return S_OK;
}

/* The items of the attributes asked: only AE_SOURCE_NAMES[0]'s AE_CONDITION, sub-condition
 * AE_SC_NAMES[1], category 1001 and attributes of it, as the client sent them. */
static HRESULT STDMETHODCALLTYPE srv_translate(IOPCEventServer2 *This, LPWSTR source, DWORD category,
                                               LPWSTR condition, LPWSTR subcondition, DWORD count, DWORD *ids,
                                               LPWSTR **item_ids, LPWSTR **nodes, CLSID **clsids) {
    DWORD k;
    (void)This;
    if (!item_ids || !nodes || !clsids) return E_POINTER;
    *item_ids = NULL;
    *nodes = NULL;
    *clsids = NULL;
    if (!is_utf8(source, AE_SOURCE_NAMES[0]) || category != AE_CATEGORY_IDS[0] || !is_utf8(condition, AE_CONDITION) ||
        !is_utf8(subcondition, AE_SC_NAMES[1]) || count != AE_TRANSLATED || !ids)
        return E_INVALIDARG;
    for (k = 0; k < count; k++)
        if (ae_event_attr(category, ids[k]) < 0) return E_INVALIDARG;
    *item_ids = (LPWSTR *)task_zero(count * sizeof(LPWSTR));
    *nodes = (LPWSTR *)task_zero(count * sizeof(LPWSTR));
    *clsids = (CLSID *)task_zero(count * sizeof(CLSID));
    if (!*item_ids || !*nodes || !*clsids) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    for (k = 0; k < count; k++) {
        const AeEventAttr *a = &AE_EVENT_ATTR_TABLE[ae_event_attr(category, ids[k])];
        (*item_ids)[k] = task_utf8(a->item_id);
        (*nodes)[k] = task_utf8(a->node);
        (*clsids)[k] = a->clsid;
    }
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE srv_condition_state(IOPCEventServer2 *This, LPWSTR source, LPWSTR condition,
                                                     DWORD nattrs, DWORD *ids, OPCCONDITIONSTATE **state) {
    OPCCONDITIONSTATE *c;
    DWORD k;
    (void)This;
    if (!state) return E_POINTER;
    *state = NULL;
    if (!is_utf8(source, AE_SOURCE_NAMES[0]) || !is_utf8(condition, AE_CONDITION) || nattrs != AE_ATTRS_ASKED ||
        !ids || memcmp(ids, AE_ATTR_IDS, sizeof AE_ATTR_IDS) != 0)
        return E_INVALIDARG;
    c = (OPCCONDITIONSTATE *)task_zero(sizeof *c);
    if (!c) return E_OUTOFMEMORY;
    c->wState = 0x0003; /* enabled, active */
    c->szActiveSubCondition = task_utf8(AE_SC_NAMES[0]);
    c->szASCDefinition = task_utf8(AE_SC_DEFINITIONS[0]);
    c->dwASCSeverity = AE_SC_SEVERITIES[0];
    c->szASCDescription = task_utf8(AE_SC_DESCRIPTIONS[0]);
    c->wQuality = 0xC0;
    c->ftLastAckTime = test_time(1);
    c->ftSubCondLastActive = test_time(2);
    c->ftCondLastActive = test_time(3);
    c->ftCondLastInactive.dwLowDateTime = 0;
    c->ftCondLastInactive.dwHighDateTime = 0;
    c->szAcknowledgerID = task_utf8("operator \xc3\xa4");
    c->szComment = NULL;
    c->dwNumSCs = AE_SUBCONDITIONS;
    c->pszSCNames = task_names(AE_SC_NAMES, AE_SUBCONDITIONS);
    c->pszSCDefinitions = task_names(AE_SC_DEFINITIONS, AE_SUBCONDITIONS);
    c->pdwSCSeverities = (DWORD *)task_zero(sizeof AE_SC_SEVERITIES);
    if (c->pdwSCSeverities) memcpy(c->pdwSCSeverities, AE_SC_SEVERITIES, sizeof AE_SC_SEVERITIES);
    c->pszSCDescriptions = task_names(AE_SC_DESCRIPTIONS, AE_SUBCONDITIONS);
    c->dwNumEventAttrs = nattrs;
    c->pEventAttributes = (VARIANT *)task_zero(nattrs * sizeof(VARIANT));
    c->pErrors = (HRESULT *)task_zero(nattrs * sizeof(HRESULT));
    if (!c->pEventAttributes || !c->pErrors || !c->pszSCNames || !c->pszSCDefinitions || !c->pdwSCSeverities ||
        !c->pszSCDescriptions) {
        *state = NULL;
        return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    }
    for (k = 0; k < nattrs; k++) c->pErrors[k] = ae_attribute(ids[k], &c->pEventAttributes[k]);
    *state = c;
    return S_OK;
}

/* Enables or disables the areas or sources `names`; their errors in `errors` (or none). */
static HRESULT set_enabled(Server *s, int by_area, BOOL enable, DWORD count, LPWSTR *names, HRESULT **errors) {
    HRESULT *e = NULL, hr = S_OK;
    DWORD k;
    if (errors) *errors = NULL;
    if (count == 0 || !names) return E_INVALIDARG;
    if (errors && !(e = (HRESULT *)task_zero(count * sizeof *e))) return E_OUTOFMEMORY;
    EnterCriticalSection(&s->lock);
    for (k = 0; k < count; k++) {
        int i = name_index(by_area, names[k]);
        if (i < 0) {
            hr = S_FALSE;
            if (e) e[k] = E_INVALIDARG;
        } else if (by_area) {
            s->area_enabled[i] = enable;
        } else {
            s->source_enabled[i] = enable;
        }
    }
    LeaveCriticalSection(&s->lock);
    if (errors) *errors = e;
    else if (hr == S_FALSE) hr = E_INVALIDARG; /* version 1: one result for the call */
    return hr;
}

static HRESULT STDMETHODCALLTYPE srv_enable_area(IOPCEventServer2 *This, DWORD n, LPWSTR *names) {
    return set_enabled(SERVER(This), 1, TRUE, n, names, NULL);
}
static HRESULT STDMETHODCALLTYPE srv_enable_source(IOPCEventServer2 *This, DWORD n, LPWSTR *names) {
    return set_enabled(SERVER(This), 0, TRUE, n, names, NULL);
}
static HRESULT STDMETHODCALLTYPE srv_disable_area(IOPCEventServer2 *This, DWORD n, LPWSTR *names) {
    return set_enabled(SERVER(This), 1, FALSE, n, names, NULL);
}
static HRESULT STDMETHODCALLTYPE srv_disable_source(IOPCEventServer2 *This, DWORD n, LPWSTR *names) {
    return set_enabled(SERVER(This), 0, FALSE, n, names, NULL);
}

/* Acknowledges conditions: each element as ae.h's AE_ACKS says (the acknowledger and the comment as
 * the client sent them, or the call is refused). */
static HRESULT STDMETHODCALLTYPE srv_ack(IOPCEventServer2 *This, DWORD count, LPWSTR acknowledger, LPWSTR comment,
                                         LPWSTR *sources, LPWSTR *conditions, FILETIME *active_times,
                                         DWORD *cookies, HRESULT **errors) {
    HRESULT hr = S_OK;
    DWORD k;
    (void)This;
    if (!errors) return E_POINTER;
    *errors = NULL;
    if (count != AE_ACKS || !sources || !conditions || !active_times || !cookies ||
        !is_utf8(acknowledger, AE_ACKNOWLEDGER) || !is_utf8(comment, AE_ACK_COMMENT))
        return E_INVALIDARG;
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*errors) return E_OUTOFMEMORY;
    for (k = 0; k < count; k++) {
        AeAck want = ae_ack(k);
        if (!is_utf8(sources[k], want.source) || !is_utf8(conditions[k], want.condition) ||
            !same_filetime(active_times[k], want.active_time) || cookies[k] != want.cookie)
            (*errors)[k] = E_INVALIDARG; /* not as the client sent it */
        else
            (*errors)[k] = want.result;
        if ((*errors)[k] != S_OK) hr = S_FALSE;
    }
    return hr;
}

/* ---- The area browser: the areas of ae.h as a tree, their sources as leaves ---- */

typedef struct Browser {
    IOPCEventAreaBrowser iface;
    LONG refs;
    CRITICAL_SECTION lock;
    int area; /* the position: an index of AE_AREA_NAMES, or -1 for the root */
} Browser;

static HRESULT STDMETHODCALLTYPE br_qi(IOPCEventAreaBrowser *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!IsEqualIID(riid, &IID_IUnknown) && !IsEqualIID(riid, &IID_IOPCEventAreaBrowser)) return E_NOINTERFACE;
    *ppv = This;
    InterlockedIncrement(&((Browser *)This)->refs);
    return S_OK;
}
static ULONG STDMETHODCALLTYPE br_add_ref(IOPCEventAreaBrowser *This) {
    return (ULONG)InterlockedIncrement(&((Browser *)This)->refs);
}
static ULONG STDMETHODCALLTYPE br_release(IOPCEventAreaBrowser *This) {
    Browser *b = (Browser *)This;
    LONG n = InterlockedDecrement(&b->refs);
    if (n == 0) {
        DeleteCriticalSection(&b->lock);
        free(b);
        OpcServerUnlock();
    }
    return (ULONG)n;
}

/* The part of qualified name `name` after the area `area` (-1: the root) and its dot, when `name` is
 * a child of it (no further dot), else NULL. */
static const char *child_part(int area, const char *name) {
    const char *rest = name;
    if (area >= 0) {
        size_t n = strlen(AE_AREA_NAMES[area]);
        if (strncmp(name, AE_AREA_NAMES[area], n) != 0 || name[n] != '.') return NULL;
        rest = name + n + 1;
    }
    return strchr(rest, '.') ? NULL : rest;
}

/* The child area (by_area) or source named `name` of the position, or -1. */
static int child_index(int area, int by_area, const WCHAR *name) {
    int i;
    for (i = 0; name && i < (by_area ? AE_AREAS : AE_SOURCES); i++) {
        const char *part = child_part(area, by_area ? AE_AREA_NAMES[i] : AE_SOURCE_NAMES[i]);
        if (part && is_utf8(name, part)) return i;
    }
    return -1;
}

static HRESULT STDMETHODCALLTYPE br_change(IOPCEventAreaBrowser *This, OPCAEBROWSEDIRECTION direction,
                                           LPCWSTR name) {
    Browser *b = (Browser *)This;
    HRESULT hr = S_OK;
    int i;
    EnterCriticalSection(&b->lock);
    if (direction == OPCAE_BROWSE_UP && name && !name[0]) {
        if (b->area < 0) hr = E_FAIL;
        else b->area = b->area == 0 ? -1 : 0; /* the tree is two levels deep */
    } else if (direction == OPCAE_BROWSE_DOWN && (i = child_index(b->area, 1, name)) >= 0) {
        b->area = i;
    } else {
        hr = E_INVALIDARG;
    }
    LeaveCriticalSection(&b->lock);
    return hr;
}

static HRESULT STDMETHODCALLTYPE br_browse(IOPCEventAreaBrowser *This, OPCAEBROWSETYPE type, LPCWSTR filter,
                                           LPENUMSTRING *out) {
    Browser *b = (Browser *)This;
    Strings *e;
    int i, by_area = type == OPC_AREA;
    if (!out) return E_POINTER;
    *out = NULL;
    if ((type != OPC_AREA && type != OPC_SOURCE) || !filter) return E_INVALIDARG;
    e = strings_new(AE_AREAS + AE_SOURCES);
    if (!e) return E_OUTOFMEMORY;
    EnterCriticalSection(&b->lock);
    for (i = 0; i < (by_area ? AE_AREAS : AE_SOURCES); i++) {
        const char *part = child_part(b->area, by_area ? AE_AREA_NAMES[i] : AE_SOURCE_NAMES[i]);
        LPWSTR text = part ? task_utf8(part) : NULL;
        if (text && (!filter[0] || MatchPatternW(text, filter, FALSE))) strings_add(e, text);
        else CoTaskMemFree(text);
    }
    LeaveCriticalSection(&b->lock);
    *out = &e->iface;
    return e->count ? S_OK : S_FALSE;
}

/* The qualified name of the child area (by_area) or source `name` of the position. */
static HRESULT qualified(Browser *b, int by_area, LPCWSTR name, LPWSTR *out) {
    int i;
    if (!out) return E_POINTER;
    *out = NULL;
    EnterCriticalSection(&b->lock);
    i = child_index(b->area, by_area, name);
    LeaveCriticalSection(&b->lock);
    if (i < 0) return E_INVALIDARG;
    *out = task_utf8(by_area ? AE_AREA_NAMES[i] : AE_SOURCE_NAMES[i]);
    return *out ? S_OK : E_OUTOFMEMORY;
}

static HRESULT STDMETHODCALLTYPE br_area_name(IOPCEventAreaBrowser *This, LPCWSTR name, LPWSTR *out) {
    return qualified((Browser *)This, 1, name, out);
}
static HRESULT STDMETHODCALLTYPE br_source_name(IOPCEventAreaBrowser *This, LPCWSTR name, LPWSTR *out) {
    return qualified((Browser *)This, 0, name, out);
}

static IOPCEventAreaBrowserVtbl br_vtbl = {br_qi,     br_add_ref,   br_release,    br_change,
                                           br_browse, br_area_name, br_source_name};

static HRESULT STDMETHODCALLTYPE srv_area_browser(IOPCEventServer2 *This, REFIID riid, LPUNKNOWN *unk) {
    Browser *b;
    HRESULT hr;
    (void)This;
    if (!unk) return E_POINTER;
    *unk = NULL;
    b = (Browser *)calloc(1, sizeof *b);
    if (!b) return E_OUTOFMEMORY;
    b->iface.lpVtbl = &br_vtbl;
    b->refs = 1;
    b->area = -1;
    InitializeCriticalSection(&b->lock);
    OpcServerLock();
    hr = br_qi(&b->iface, riid, (void **)unk);
    br_release(&b->iface);
    return hr;
}

static HRESULT STDMETHODCALLTYPE srv_enable_area2(IOPCEventServer2 *This, DWORD n, LPWSTR *names, HRESULT **errors) {
    if (!errors) return E_POINTER;
    return set_enabled(SERVER(This), 1, TRUE, n, names, errors);
}
static HRESULT STDMETHODCALLTYPE srv_enable_source2(IOPCEventServer2 *This, DWORD n, LPWSTR *names,
                                                    HRESULT **errors) {
    if (!errors) return E_POINTER;
    return set_enabled(SERVER(This), 0, TRUE, n, names, errors);
}
static HRESULT STDMETHODCALLTYPE srv_disable_area2(IOPCEventServer2 *This, DWORD n, LPWSTR *names,
                                                   HRESULT **errors) {
    if (!errors) return E_POINTER;
    return set_enabled(SERVER(This), 1, FALSE, n, names, errors);
}
static HRESULT STDMETHODCALLTYPE srv_disable_source2(IOPCEventServer2 *This, DWORD n, LPWSTR *names,
                                                     HRESULT **errors) {
    if (!errors) return E_POINTER;
    return set_enabled(SERVER(This), 0, FALSE, n, names, errors);
}

/* The state of areas or sources: a source is effectively enabled when it, its area and the root area
 * ("Plant") are; an area when it and the root are. */
static HRESULT enable_state(Server *s, int by_area, DWORD count, LPWSTR *names, BOOL **enabled, BOOL **effective,
                            HRESULT **errors) {
    HRESULT hr = S_OK;
    DWORD k;
    if (!enabled || !effective || !errors) return E_POINTER;
    *enabled = *effective = NULL;
    *errors = NULL;
    if (count == 0 || !names) return E_INVALIDARG;
    *enabled = (BOOL *)task_zero(count * sizeof(BOOL));
    *effective = (BOOL *)task_zero(count * sizeof(BOOL));
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*enabled || !*effective || !*errors) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    EnterCriticalSection(&s->lock);
    for (k = 0; k < count; k++) {
        int i = name_index(by_area, names[k]);
        if (i < 0) {
            (*errors)[k] = E_INVALIDARG;
            hr = S_FALSE;
        } else if (by_area) {
            (*enabled)[k] = s->area_enabled[i];
            (*effective)[k] = s->area_enabled[i] && s->area_enabled[0];
        } else {
            (*enabled)[k] = s->source_enabled[i];
            (*effective)[k] = s->source_enabled[i] && s->area_enabled[AE_SOURCE_AREA[i]] && s->area_enabled[0];
        }
    }
    LeaveCriticalSection(&s->lock);
    return hr;
}

static HRESULT STDMETHODCALLTYPE srv_state_by_area(IOPCEventServer2 *This, DWORD n, LPWSTR *names, BOOL **enabled,
                                                   BOOL **effective, HRESULT **errors) {
    return enable_state(SERVER(This), 1, n, names, enabled, effective, errors);
}
static HRESULT STDMETHODCALLTYPE srv_state_by_source(IOPCEventServer2 *This, DWORD n, LPWSTR *names, BOOL **enabled,
                                                     BOOL **effective, HRESULT **errors) {
    return enable_state(SERVER(This), 0, n, names, enabled, effective, errors);
}

static IOPCEventServer2Vtbl srv_vtbl = {
    srv_qi,           srv_add_ref,          srv_release,          srv_status,          srv_create_subscription,
    srv_filters,      srv_categories,       srv_condition_names,  srv_subcondition_names, srv_source_conditions,
    srv_event_attributes, srv_translate,    srv_condition_state,  srv_enable_area,     srv_enable_source,
    srv_disable_area, srv_disable_source,   srv_ack,              srv_area_browser,    srv_enable_area2,
    srv_enable_source2, srv_disable_area2,  srv_disable_source2,  srv_state_by_area,   srv_state_by_source};

static HRESULT OPCCOMN_CDECL create_server(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    Server *s;
    HRESULT hr;
    int i;
    (void)context;
    (void)outer; /* not aggregatable: the library refuses an outer object */
    s = (Server *)calloc(1, sizeof *s);
    if (!s) return E_OUTOFMEMORY;
    s->iface.lpVtbl = &srv_vtbl;
    s->refs = 1;
    InitializeCriticalSection(&s->lock);
    for (i = 0; i < AE_AREAS; i++) s->area_enabled[i] = TRUE;
    for (i = 0; i < AE_SOURCES; i++) s->source_enabled[i] = TRUE;
    OpcServerLock(); /* the server object counts on the process while it lives */
    hr = srv_qi(&s->iface, riid, ppv);
    srv_release(&s->iface);
    return hr;
}

int main(void) {
    return run_test_server("ae_server", &CLSID_AeTestServer, L"Oop.AeServer.1", L"opccomn A&E tables test server",
                           create_server, AE_IIDS, AE_IID_COUNT);
}
