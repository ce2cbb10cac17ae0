/* The EXE server of the cross-process test of the Historical Data Access proxy/stub
 * (test_hda_tables.c): a small OPC HDA server written in C (LocalServer32, started by COM with
 * -Embedding, hosted by OpcExeServerRun), reached through opccomn.dll's proxies and stubs, which it
 * registers for this process (classic_oop.h). It serves the items of hda.h and checks what it
 * receives: a request that does not arrive as the client sent it is answered with E_INVALIDARG (or a
 * per-item error), which the client sees.
 *
 * One object: IOPCHDA_Server (GetItemAttributes, GetHistorianStatus, GetItemHandles, CreateBrowse:
 * an IOPCHDA_Browser with its IEnumStrings), IOPCHDA_SyncRead (ReadRaw, ReadProcessed, ReadAtTime,
 * ReadModified), IOPCHDA_AsyncRead (ReadRaw, ReadProcessed: an OnReadComplete from a thread of the
 * server; AdviseRaw: an OnDataChange, then Cancel: an OnCancelComplete), IOPCHDA_SyncAnnotations
 * (QueryCapabilities, Read, Insert), IOPCHDA_SyncUpdate (all six methods), IOPCHDA_AsyncUpdate
 * (QueryCapabilities, Insert, Replace, InsertReplace, DeleteRaw, DeleteAtTime: an OnUpdateComplete),
 * IOPCHDA_AsyncAnnotations (QueryCapabilities, Read: an OnReadAnnotations; Insert: an
 * OnInsertAnnotations), IOPCHDA_Playback (ReadRawWithUpdate: an OnPlayback, ReadProcessedWithUpdate:
 * the request checked, a cancel ID given; Cancel) and IConnectionPointContainer with the
 * IOPCHDA_DataCallback connection point. What the test does not call answers E_NOTIMPL. */
#include "hda.h"

#include "enum_strings.h"
#include "sink_point.h"

#define CONTAINER(type, field, p) ((type *)((char *)(p) - offsetof(type, field)))

typedef struct Server {
    IOPCHDA_Server server; /* the identity */
    IOPCHDA_SyncRead sync;
    IOPCHDA_AsyncRead async;
    IOPCHDA_SyncAnnotations annotations;
    IOPCHDA_SyncUpdate update;
    IOPCHDA_Playback playback;
    IOPCHDA_AsyncUpdate async_update;
    IOPCHDA_AsyncAnnotations async_annotations;
    SinkPoint cp; /* IOPCHDA_DataCallback */
    LONG refs;
    CRITICAL_SECTION lock;
    int handed_out[HDA_ITEMS]; /* GetItemHandles gave the item's handle */
    DWORD advise_cancel;       /* the cancel ID of AdviseRaw's advise, or 0 */
    DWORD playback_cancel[2];  /* the cancel IDs of the playbacks going on, or 0 */
} Server;

static HRESULT server_qi(Server *s, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCHDA_Server)) *ppv = &s->server;
    else if (IsEqualIID(riid, &IID_IOPCHDA_SyncRead)) *ppv = &s->sync;
    else if (IsEqualIID(riid, &IID_IOPCHDA_AsyncRead)) *ppv = &s->async;
    else if (IsEqualIID(riid, &IID_IOPCHDA_SyncAnnotations)) *ppv = &s->annotations;
    else if (IsEqualIID(riid, &IID_IOPCHDA_SyncUpdate)) *ppv = &s->update;
    else if (IsEqualIID(riid, &IID_IOPCHDA_Playback)) *ppv = &s->playback;
    else if (IsEqualIID(riid, &IID_IOPCHDA_AsyncUpdate)) *ppv = &s->async_update;
    else if (IsEqualIID(riid, &IID_IOPCHDA_AsyncAnnotations)) *ppv = &s->async_annotations;
    else if (IsEqualIID(riid, &IID_IConnectionPointContainer)) *ppv = &s->cp.container;
    else return E_NOINTERFACE;
    InterlockedIncrement(&s->refs);
    return S_OK;
}

static ULONG server_release(Server *s) {
    LONG n = InterlockedDecrement(&s->refs);
    if (n == 0) {
        sink_point_end(&s->cp);
        DeleteCriticalSection(&s->lock);
        free(s);
        OpcServerUnlock();
    }
    return (ULONG)n;
}

#define SERVER_UNKNOWN(prefix, Iface, field)                                                                    \
    static HRESULT STDMETHODCALLTYPE prefix##_qi(Iface *This, REFIID riid, void **ppv) {                       \
        return server_qi(CONTAINER(Server, field, This), riid, ppv);                                            \
    }                                                                                                           \
    static ULONG STDMETHODCALLTYPE prefix##_add_ref(Iface *This) {                                             \
        return (ULONG)InterlockedIncrement(&CONTAINER(Server, field, This)->refs);                              \
    }                                                                                                           \
    static ULONG STDMETHODCALLTYPE prefix##_release(Iface *This) { return server_release(CONTAINER(Server, field, This)); }

SERVER_UNKNOWN(srv, IOPCHDA_Server, server)
SERVER_UNKNOWN(sync, IOPCHDA_SyncRead, sync)
SERVER_UNKNOWN(async, IOPCHDA_AsyncRead, async)
SERVER_UNKNOWN(ann, IOPCHDA_SyncAnnotations, annotations)
SERVER_UNKNOWN(upd, IOPCHDA_SyncUpdate, update)
SERVER_UNKNOWN(play, IOPCHDA_Playback, playback)
SERVER_UNKNOWN(aupd, IOPCHDA_AsyncUpdate, async_update)
SERVER_UNKNOWN(aann, IOPCHDA_AsyncAnnotations, async_annotations)

/* A copy in task memory of the UTF-8 texts `names[0..count)`, or NULL. */
static LPWSTR *task_names(const char *const *names, DWORD count) {
    LPWSTR *copy = (LPWSTR *)task_zero(count * sizeof *copy);
    DWORD k;
    for (k = 0; copy && k < count; k++) copy[k] = task_utf8(names[k]);
    return copy;
}

/* -- IOPCHDA_Server -- */

static HRESULT STDMETHODCALLTYPE srv_attributes(IOPCHDA_Server *This, DWORD *count, DWORD **ids, LPWSTR **names,
                                                LPWSTR **texts, VARTYPE **types) {
    (void)This;
    if (!count || !ids || !names || !texts || !types) return E_POINTER;
    *count = HDA_ATTRS;
    *ids = (DWORD *)task_zero(sizeof HDA_ATTR_IDS);
    *names = task_names(HDA_ATTR_NAMES, HDA_ATTRS);
    *texts = task_names(HDA_ATTR_TEXTS, HDA_ATTRS);
    *types = (VARTYPE *)task_zero(sizeof HDA_ATTR_TYPES);
    if (!*ids || !*names || !*texts || !*types) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    memcpy(*ids, HDA_ATTR_IDS, sizeof HDA_ATTR_IDS);
    memcpy(*types, HDA_ATTR_TYPES, sizeof HDA_ATTR_TYPES);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE srv_aggregates(IOPCHDA_Server *This, DWORD *count, DWORD **ids, LPWSTR **names,
                                                LPWSTR **texts) {
    (void)This;
    if (count) *count = 0;
    if (ids) *ids = NULL;
    if (names) *names = NULL;
    if (texts) *texts = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE srv_status(IOPCHDA_Server *This, OPCHDA_SERVERSTATUS *status, FILETIME **current,
                                            FILETIME **start, WORD *major, WORD *minor, WORD *build,
                                            DWORD *max_values, LPWSTR *text, LPWSTR *vendor) {
    (void)This;
    if (!status || !current || !start || !major || !minor || !build || !max_values || !text || !vendor)
        return E_POINTER;
    *status = OPCHDA_UP;
    *current = (FILETIME *)task_zero(sizeof(FILETIME));
    *start = (FILETIME *)task_zero(sizeof(FILETIME));
    if (*current) **current = test_time(1);
    if (*start) **start = test_time(0);
    *major = 1;
    *minor = 20;
    *build = 42;
    *max_values = 1000;
    *text = task_utf8(HDA_STATUS_TEXT);
    *vendor = task_utf8(proxy_stub_is_opccomn_for(HDA_IIDS, HDA_IID_COUNT) ? HDA_VENDOR_INFO : HDA_VENDOR_INFO_OTHER);
    return *current && *start && *text && *vendor ? S_OK : E_OUTOFMEMORY;
}

/* The item whose ID is `id`, or -1. */
static int item_index(const WCHAR *id) {
    int i;
    for (i = 0; id && i < HDA_ITEMS; i++)
        if (is_utf8(id, HDA_ITEM_IDS[i])) return i;
    return -1;
}

/* The item whose server handle is `h` (handed out), or -1. */
static int item_of_handle(Server *s, OPCHANDLE h) {
    int i = h >= HDA_SERVER_HANDLE(0) && h < HDA_SERVER_HANDLE(HDA_ITEMS) ? (int)(h - HDA_SERVER_HANDLE(0)) : -1;
    int out;
    if (i < 0) return -1;
    EnterCriticalSection(&s->lock);
    out = s->handed_out[i];
    LeaveCriticalSection(&s->lock);
    return out ? i : -1;
}

static HRESULT STDMETHODCALLTYPE srv_handles(IOPCHDA_Server *This, DWORD count, LPWSTR *ids, OPCHANDLE *clients,
                                             OPCHANDLE **servers, HRESULT **errors) {
    Server *s = CONTAINER(Server, server, This);
    HRESULT hr = S_OK;
    DWORD k;
    if (!servers || !errors) return E_POINTER;
    *servers = NULL;
    *errors = NULL;
    if (count == 0 || !ids || !clients) return E_INVALIDARG;
    *servers = (OPCHANDLE *)task_zero(count * sizeof(OPCHANDLE));
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*servers || !*errors) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    EnterCriticalSection(&s->lock);
    for (k = 0; k < count; k++) {
        int i = item_index(ids[k]);
        if (i < 0) {
            (*errors)[k] = HDA_E_UNKNOWNITEMID;
            hr = S_FALSE;
        } else if (clients[k] != HDA_CLIENT_HANDLE(i)) { /* not as the client sent it */
            (*errors)[k] = E_INVALIDARG;
            hr = S_FALSE;
        } else {
            s->handed_out[i] = 1;
            (*servers)[k] = HDA_SERVER_HANDLE(i);
        }
    }
    LeaveCriticalSection(&s->lock);
    return hr;
}

static HRESULT STDMETHODCALLTYPE srv_release_handles(IOPCHDA_Server *This, DWORD count, OPCHANDLE *servers,
                                                     HRESULT **errors) {
    (void)This, (void)count, (void)servers;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE srv_validate(IOPCHDA_Server *This, DWORD count, LPWSTR *ids, HRESULT **errors) {
    (void)This, (void)count, (void)ids;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

/* -- IOPCHDA_Browser: the tree of hda.h ("Plant", "Plant.Tank1" with the items as leaves), the
 * items found those whose data type the filters let through -- */

/* An enumerator of the UTF-8 texts `texts[0..count)`, or NULL. */
static IEnumString *new_strings(const char *const *texts, ULONG count) {
    Strings *e = strings_new(count);
    ULONG k;
    if (!e) return NULL;
    for (k = 0; k < count; k++) {
        LPWSTR text = task_utf8(texts[k]);
        if (!text || !strings_add(e, text)) {
            str_release(&e->iface);
            return NULL;
        }
    }
    return &e->iface;
}

typedef struct Browser {
    IOPCHDA_Browser iface;
    LONG refs;
    CRITICAL_SECTION lock;
    int depth;           /* the position: 0 the root, 1 "Plant", 2 "Plant.Tank1" */
    int found[HDA_ITEMS]; /* the items the filters let through */
} Browser;

static HRESULT STDMETHODCALLTYPE br_qi(IOPCHDA_Browser *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!IsEqualIID(riid, &IID_IUnknown) && !IsEqualIID(riid, &IID_IOPCHDA_Browser)) return E_NOINTERFACE;
    *ppv = This;
    InterlockedIncrement(&((Browser *)This)->refs);
    return S_OK;
}
static ULONG STDMETHODCALLTYPE br_add_ref(IOPCHDA_Browser *This) {
    return (ULONG)InterlockedIncrement(&((Browser *)This)->refs);
}
static ULONG STDMETHODCALLTYPE br_release(IOPCHDA_Browser *This) {
    Browser *b = (Browser *)This;
    LONG n = InterlockedDecrement(&b->refs);
    if (n == 0) {
        DeleteCriticalSection(&b->lock);
        free(b);
        OpcServerUnlock(); /* a browser counts on the process while it lives */
    }
    return (ULONG)n;
}

/* The branches below the position, the leaves at it (the items found), or every item found by its
 * ID (OPCHDA_FLAT, and OPCHDA_ITEMS below the position). */
static HRESULT STDMETHODCALLTYPE br_get_enum(IOPCHDA_Browser *This, OPCHDA_BROWSETYPE type, LPENUMSTRING *out) {
    Browser *b = (Browser *)This;
    static const char *const top[1] = {HDA_TOP_BRANCH};
    static const char *const branch[1] = {HDA_BRANCH};
    const char *texts[HDA_ITEMS];
    ULONG count = 0;
    int depth, i;
    if (!out) return E_POINTER;
    *out = NULL;
    EnterCriticalSection(&b->lock);
    depth = b->depth;
    LeaveCriticalSection(&b->lock);
    switch (type) {
    case OPCHDA_BRANCH:
        if (depth < 2) {
            *out = new_strings(depth == 0 ? top : branch, 1);
            return *out ? S_OK : E_OUTOFMEMORY;
        }
        break;
    case OPCHDA_LEAF:
        for (i = 0; depth == 2 && i < HDA_ITEMS; i++)
            if (b->found[i]) texts[count++] = HDA_LEAVES[i];
        break;
    case OPCHDA_FLAT:
    case OPCHDA_ITEMS:
        for (i = 0; i < HDA_ITEMS; i++)
            if (b->found[i]) texts[count++] = HDA_ITEM_IDS[i];
        break;
    default: return E_INVALIDARG;
    }
    *out = new_strings(texts, count);
    return !*out ? E_OUTOFMEMORY : count ? S_OK : S_FALSE;
}

static HRESULT STDMETHODCALLTYPE br_change(IOPCHDA_Browser *This, OPCHDA_BROWSEDIRECTION direction,
                                           LPCWSTR name) {
    Browser *b = (Browser *)This;
    HRESULT hr = S_OK;
    if (!name) return E_INVALIDARG;
    EnterCriticalSection(&b->lock);
    if (direction == OPCHDA_BROWSE_UP && b->depth > 0 && name[0] == 0) b->depth--;
    else if (direction == OPCHDA_BROWSE_DOWN && b->depth == 0 && is_utf8(name, HDA_TOP_BRANCH)) b->depth = 1;
    else if (direction == OPCHDA_BROWSE_DOWN && b->depth == 1 && is_utf8(name, HDA_BRANCH)) b->depth = 2;
    else if (direction == OPCHDA_BROWSE_DIRECT && name[0] == 0) b->depth = 0;
    else if (direction == OPCHDA_BROWSE_DIRECT && is_utf8(name, HDA_TOP_BRANCH)) b->depth = 1;
    else if (direction == OPCHDA_BROWSE_DIRECT && is_utf8(name, HDA_BRANCH_POSITION)) b->depth = 2;
    else hr = E_INVALIDARG;
    LeaveCriticalSection(&b->lock);
    return hr;
}

/* The ID of the leaf `node` at the position (an item found). */
static HRESULT STDMETHODCALLTYPE br_item_id(IOPCHDA_Browser *This, LPCWSTR node, LPWSTR *id) {
    Browser *b = (Browser *)This;
    int i, depth;
    if (!id) return E_POINTER;
    *id = NULL;
    EnterCriticalSection(&b->lock);
    depth = b->depth;
    LeaveCriticalSection(&b->lock);
    for (i = 0; node && depth == 2 && i < HDA_ITEMS; i++)
        if (b->found[i] && is_utf8(node, HDA_LEAVES[i])) {
            *id = task_utf8(HDA_ITEM_IDS[i]);
            return *id ? S_OK : E_OUTOFMEMORY;
        }
    return E_INVALIDARG;
}

static HRESULT STDMETHODCALLTYPE br_position(IOPCHDA_Browser *This, LPWSTR *position) {
    Browser *b = (Browser *)This;
    int depth;
    if (!position) return E_POINTER;
    EnterCriticalSection(&b->lock);
    depth = b->depth;
    LeaveCriticalSection(&b->lock);
    *position = task_utf8(depth == 0 ? "" : depth == 1 ? HDA_TOP_BRANCH : HDA_BRANCH_POSITION);
    return *position ? S_OK : E_OUTOFMEMORY;
}

static IOPCHDA_BrowserVtbl br_vtbl = {br_qi,     br_add_ref, br_release, br_get_enum,
                                      br_change, br_item_id, br_position};

/* A browser with the client's filters (hda.h), each element answered as it arrived: the data type
 * equal to VT_BSTR finds item 1 alone, the description filter finds both, an unknown attribute is
 * HDA_E_UNKNOWNATTRID; a filter not as sent E_INVALIDARG (and it filters nothing). */
static HRESULT STDMETHODCALLTYPE srv_browse(IOPCHDA_Server *This, DWORD count, DWORD *ids,
                                            OPCHDA_OPERATORCODES *operators, VARIANT *filters,
                                            IOPCHDA_Browser **browser, HRESULT **errors) {
    Browser *b;
    HRESULT hr = S_OK;
    DWORD k;
    (void)This;
    if (!browser || !errors) return E_POINTER;
    *browser = NULL;
    *errors = NULL;
    if (count != HDA_FILTERS || !ids || !operators || !filters) return E_INVALIDARG;
    b = (Browser *)calloc(1, sizeof *b);
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!b || !*errors) {
        free(b);
        CoTaskMemFree(*errors);
        *errors = NULL;
        return E_OUTOFMEMORY;
    }
    b->iface.lpVtbl = &br_vtbl;
    b->refs = 1;
    InitializeCriticalSection(&b->lock);
    b->found[0] = b->found[1] = 1;
    for (k = 0; k < count; k++) {
        VARIANT want = hda_filter(k);
        int as_sent = ids[k] == HDA_FILTER_IDS[k] && operators[k] == HDA_FILTER_OPS[k] &&
                      hda_same_variant(&filters[k], &want);
        VariantClear(&want);
        if (!as_sent) (*errors)[k] = E_INVALIDARG;
        else if (ids[k] == HDA_UNKNOWN_ATTR) (*errors)[k] = HDA_E_UNKNOWNATTRID;
        else if (k == 0) b->found[0] = 0; /* item 0's data type is VT_R8 */
        if ((*errors)[k] != S_OK) hr = S_FALSE;
    }
    OpcServerLock();
    *browser = &b->iface;
    return hr;
}

static IOPCHDA_ServerVtbl srv_vtbl = {srv_qi,      srv_add_ref,         srv_release,  srv_attributes,
                                      srv_aggregates, srv_status,       srv_handles,  srv_release_handles,
                                      srv_validate, srv_browse};

/* -- Reading -- */

/* Whether the time range is the client's (hda.h); if so it is resolved as the server resolves it. */
static int take_range(OPCHDA_TIME *start, OPCHDA_TIME *end) {
    if (!start || !end || !start->bString || !is_utf8(start->szTime, HDA_START_TEXT) || end->bString ||
        end->szTime || !same_filetime(end->ftTime, test_time(HDA_END_ASKED)))
        return 0;
    start->ftTime = test_time(HDA_START_RESOLVED);
    end->ftTime = test_time(HDA_END_RESOLVED);
    return 1;
}

/* The histories of `count` items (raw when `aggregates` is NULL), an invalid handle an error of its
 * own with an empty item. */
static HRESULT read_items(Server *s, DWORD count, const OPCHANDLE *handles, const DWORD *aggregates,
                          OPCHDA_ITEM **items, HRESULT **errors) {
    HRESULT hr = S_OK;
    DWORD k;
    *items = (OPCHDA_ITEM *)task_zero(count * sizeof(OPCHDA_ITEM));
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*items || !*errors) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    for (k = 0; k < count; k++) {
        int i = item_of_handle(s, handles[k]);
        if (i < 0) {
            (*errors)[k] = HDA_E_INVALIDHANDLE;
            hr = S_FALSE;
        } else if (aggregates && aggregates[k] != OPCHDA_AVERAGE && aggregates[k] != OPCHDA_MAXIMUM) {
            (*errors)[k] = E_INVALIDARG; /* not as the client sent it */
            hr = S_FALSE;
        } else {
            hda_fill_item(i, aggregates ? aggregates[k] : 0, &(*items)[k]);
        }
    }
    return hr;
}

static HRESULT STDMETHODCALLTYPE sync_raw(IOPCHDA_SyncRead *This, OPCHDA_TIME *start, OPCHDA_TIME *end,
                                          DWORD num_values, BOOL bounds, DWORD count, OPCHANDLE *handles,
                                          OPCHDA_ITEM **items, HRESULT **errors) {
    if (!items || !errors) return E_POINTER;
    *items = NULL;
    *errors = NULL;
    if (count == 0 || !handles || num_values != HDA_RAW_VALUES || bounds || !take_range(start, end))
        return E_INVALIDARG;
    return read_items(CONTAINER(Server, sync, This), count, handles, NULL, items, errors);
}

static HRESULT STDMETHODCALLTYPE sync_processed(IOPCHDA_SyncRead *This, OPCHDA_TIME *start, OPCHDA_TIME *end,
                                                FILETIME interval, DWORD count, OPCHANDLE *handles,
                                                DWORD *aggregates, OPCHDA_ITEM **items, HRESULT **errors) {
    if (!items || !errors) return E_POINTER;
    *items = NULL;
    *errors = NULL;
    if (count == 0 || !handles || !aggregates || !same_filetime(interval, hda_interval()) || !take_range(start, end))
        return E_INVALIDARG;
    return read_items(CONTAINER(Server, sync, This), count, handles, aggregates, items, errors);
}

/* The values at the client's times (hda_at_time(), each checked) of each item, an invalid handle an
 * error of its own with an empty item. */
static HRESULT STDMETHODCALLTYPE sync_at_time(IOPCHDA_SyncRead *This, DWORD ntimes, FILETIME *times, DWORD count,
                                              OPCHANDLE *handles, OPCHDA_ITEM **items, HRESULT **errors) {
    Server *s = CONTAINER(Server, sync, This);
    HRESULT hr = S_OK;
    DWORD k;
    if (!items || !errors) return E_POINTER;
    *items = NULL;
    *errors = NULL;
    if (ntimes != HDA_AT_TIMES || !times || count == 0 || !handles) return E_INVALIDARG;
    for (k = 0; k < ntimes; k++)
        if (!same_filetime(times[k], hda_at_time(k))) return E_INVALIDARG; /* not as the client sent it */
    *items = (OPCHDA_ITEM *)task_zero(count * sizeof(OPCHDA_ITEM));
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*items || !*errors) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    for (k = 0; k < count; k++) {
        int i = item_of_handle(s, handles[k]);
        if (i < 0) {
            (*errors)[k] = HDA_E_INVALIDHANDLE;
            hr = S_FALSE;
        } else {
            hda_fill_at_time(i, &(*items)[k]);
        }
    }
    return hr;
}

/* The modified values of each item in the range (take_range), HDA_MODIFIED_VALUES of each, an invalid
 * handle an error of its own with an empty item. */
static HRESULT STDMETHODCALLTYPE sync_modified(IOPCHDA_SyncRead *This, OPCHDA_TIME *start, OPCHDA_TIME *end,
                                               DWORD num_values, DWORD count, OPCHANDLE *handles,
                                               OPCHDA_MODIFIEDITEM **items, HRESULT **errors) {
    Server *s = CONTAINER(Server, sync, This);
    HRESULT hr = S_OK;
    DWORD k;
    if (!items || !errors) return E_POINTER;
    *items = NULL;
    *errors = NULL;
    if (num_values != HDA_MODIFIED_VALUES || count == 0 || !handles || !take_range(start, end)) return E_INVALIDARG;
    *items = (OPCHDA_MODIFIEDITEM *)task_zero(count * sizeof(OPCHDA_MODIFIEDITEM));
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*items || !*errors) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    for (k = 0; k < count; k++) {
        int i = item_of_handle(s, handles[k]);
        if (i < 0) {
            (*errors)[k] = HDA_E_INVALIDHANDLE;
            hr = S_FALSE;
        } else {
            hda_fill_modified(i, &(*items)[k]);
        }
    }
    return hr;
}

static HRESULT STDMETHODCALLTYPE sync_attribute(IOPCHDA_SyncRead *This, OPCHDA_TIME *start, OPCHDA_TIME *end,
                                                OPCHANDLE handle, DWORD count, DWORD *ids,
                                                OPCHDA_ATTRIBUTE **values, HRESULT **errors) {
    (void)This, (void)start, (void)end, (void)handle, (void)count, (void)ids;
    if (values) *values = NULL;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static IOPCHDA_SyncReadVtbl sync_vtbl = {sync_qi,      sync_add_ref,  sync_release,  sync_raw,
                                         sync_processed, sync_at_time, sync_modified, sync_attribute};


/* An asynchronous read (its OnReadComplete), an advise's data (OnDataChange), a raw playback's data
 * (OnPlayback), a cancel's completion (OnCancelComplete of the cancel ID `transaction`), an
 * asynchronous update's or annotations' insertion's results (OnUpdateComplete, OnInsertAnnotations:
 * `clients` and `results`) or an asynchronous read of annotations (OnReadAnnotations), from a thread
 * of the server. */
typedef struct AsyncRead {
    Server *server; /* a reference */
    int call;
    DWORD transaction, count;
    OPCHANDLE handles[HDA_ITEMS];
    DWORD aggregates[HDA_ITEMS];
    int processed;
    OPCHANDLE clients[HDA_UPDATES];
    HRESULT results[HDA_UPDATES];
} AsyncRead;

/* The annotations of `count` items (item 0's HDA_ANNOTATIONS, none of item 1's), an invalid handle an
 * error of its own. */
static HRESULT read_annotations(Server *s, DWORD count, const OPCHANDLE *handles, OPCHDA_ANNOTATION **values,
                                HRESULT **errors) {
    HRESULT hr = S_OK;
    DWORD k, n;
    *values = (OPCHDA_ANNOTATION *)task_zero(count * sizeof(OPCHDA_ANNOTATION));
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*values || !*errors) return E_OUTOFMEMORY; /* a test server: what it allocated stays */
    for (k = 0; k < count; k++) {
        OPCHDA_ANNOTATION *a = &(*values)[k];
        int i = item_of_handle(s, handles[k]);
        if (i < 0) {
            (*errors)[k] = HDA_E_INVALIDHANDLE;
            hr = S_FALSE;
            continue;
        }
        a->hClient = HDA_CLIENT_HANDLE(i);
        if (i != 0) continue; /* no annotations */
        a->ftTimeStamps = (FILETIME *)task_zero(HDA_ANNOTATIONS * sizeof(FILETIME));
        a->ftAnnotationTime = (FILETIME *)task_zero(HDA_ANNOTATIONS * sizeof(FILETIME));
        a->szAnnotation = task_names(HDA_ANNOTATION_TEXTS, HDA_ANNOTATIONS);
        a->szUser = task_names(HDA_ANNOTATION_USERS, HDA_ANNOTATIONS);
        if (!a->ftTimeStamps || !a->ftAnnotationTime || !a->szAnnotation || !a->szUser) return E_OUTOFMEMORY;
        for (n = 0; n < HDA_ANNOTATIONS; n++) {
            a->ftTimeStamps[n] = test_time(HDA_START_RESOLVED + n);
            a->ftAnnotationTime[n] = test_time(100 + n);
        }
        a->dwNumValues = HDA_ANNOTATIONS;
    }
    return hr;
}

static DWORD WINAPI read_thread(void *param) {
    AsyncRead *r = (AsyncRead *)param;
    IOPCHDA_DataCallback *sink;
    OPCHDA_ITEM *items = NULL;
    HRESULT *errors = NULL;
    DWORD k;
    CoInitializeEx(NULL, COINIT_MULTITHREADED);
    sink = (IOPCHDA_DataCallback *)sink_point_sink(&r->server->cp);
    if (r->call == CALL_CANCEL_COMPLETE) {
        if (sink) sink->lpVtbl->OnCancelComplete(sink, r->transaction);
    } else if (r->call == CALL_UPDATE_COMPLETE) {
        if (sink) sink->lpVtbl->OnUpdateComplete(sink, r->transaction, S_OK, r->count, r->clients, r->results);
    } else if (r->call == CALL_INSERT_ANNOTATIONS) {
        if (sink) sink->lpVtbl->OnInsertAnnotations(sink, r->transaction, S_OK, r->count, r->clients, r->results);
    } else if (r->call == CALL_READ_ANNOTATIONS) {
        OPCHDA_ANNOTATION *values = NULL;
        if (read_annotations(r->server, r->count, r->handles, &values, &errors) == S_OK && sink)
            sink->lpVtbl->OnReadAnnotations(sink, r->transaction, S_OK, r->count, values, errors);
        for (k = 0; values && k < r->count; k++) hda_free_annotation(&values[k]);
        CoTaskMemFree(values);
    } else if (read_items(r->server, r->count, r->handles, r->processed ? r->aggregates : NULL, &items, &errors) ==
                   S_OK &&
               sink) {
        OPCHDA_ITEM *each[HDA_ITEMS]; /* OnPlayback's array of pointers */
        for (k = 0; k < r->count; k++) each[k] = &items[k];
        if (r->call == CALL_DATA_CHANGE) sink->lpVtbl->OnDataChange(sink, r->transaction, S_OK, r->count, items, errors);
        else if (r->call == CALL_PLAYBACK) sink->lpVtbl->OnPlayback(sink, r->transaction, S_OK, r->count, each, errors);
        else sink->lpVtbl->OnReadComplete(sink, r->transaction, S_OK, r->count, items, errors);
    }
    if (sink) sink->lpVtbl->Release(sink);
    for (k = 0; items && k < r->count; k++) hda_free_item(&items[k]);
    CoTaskMemFree(items);
    CoTaskMemFree(errors);
    server_release(r->server);
    free(r);
    CoUninitialize();
    return 0;
}

/* Starts a thread calling back `r` (calloc'ed, taken). */
static HRESULT start_call(Server *s, AsyncRead *r) {
    HANDLE thread;
    r->server = s;
    InterlockedIncrement(&s->refs);
    thread = CreateThread(NULL, 0, read_thread, r, 0, NULL);
    if (!thread) {
        server_release(s);
        free(r);
        return E_OUTOFMEMORY;
    }
    CloseHandle(thread);
    return S_OK;
}

/* Starts the read (or, `call` CALL_DATA_CHANGE, the advise) of `count` items (at most HDA_ITEMS, each
 * valid) with `aggregates` or raw. */
static HRESULT start_read(Server *s, int call, DWORD transaction, DWORD count, const OPCHANDLE *handles,
                          const DWORD *aggregates, DWORD *cancel, HRESULT **errors) {
    IUnknown *sink = sink_point_sink(&s->cp);
    AsyncRead *r;
    DWORD k;
    if (!sink) return CONNECT_E_NOCONNECTION;
    sink->lpVtbl->Release(sink);
    if (count == 0 || count > HDA_ITEMS || !handles) return E_INVALIDARG;
    for (k = 0; k < count; k++)
        if (item_of_handle(s, handles[k]) < 0) return E_INVALIDARG; /* not as the client sent them */
    r = (AsyncRead *)calloc(1, sizeof *r);
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!r || !*errors) {
        free(r);
        CoTaskMemFree(*errors);
        *errors = NULL;
        return E_OUTOFMEMORY;
    }
    r->call = call;
    r->transaction = transaction;
    r->count = count;
    memcpy(r->handles, handles, count * sizeof *handles);
    if (aggregates) memcpy(r->aggregates, aggregates, count * sizeof *aggregates);
    r->processed = aggregates != NULL;
    if (FAILED(start_call(s, r))) {
        CoTaskMemFree(*errors);
        *errors = NULL;
        return E_OUTOFMEMORY;
    }
    *cancel = transaction + 1;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE async_raw(IOPCHDA_AsyncRead *This, DWORD transaction, OPCHDA_TIME *start,
                                           OPCHDA_TIME *end, DWORD num_values, BOOL bounds, DWORD count,
                                           OPCHANDLE *handles, DWORD *cancel, HRESULT **errors) {
    if (!cancel || !errors) return E_POINTER;
    *cancel = 0;
    *errors = NULL;
    if (num_values != HDA_RAW_VALUES || bounds || !take_range(start, end)) return E_INVALIDARG;
    return start_read(CONTAINER(Server, async, This), CALL_READ_COMPLETE, transaction, count, handles, NULL, cancel,
                      errors);
}

/* An advise of raw data from "NOW-1H" (resolved as take_range resolves it) every hda_update_interval():
 * one OnDataChange of the items' history from a thread of the server, until Cancel. */
static HRESULT STDMETHODCALLTYPE async_advise_raw(IOPCHDA_AsyncRead *This, DWORD transaction, OPCHDA_TIME *start,
                                                  FILETIME interval, DWORD count, OPCHANDLE *handles, DWORD *cancel,
                                                  HRESULT **errors) {
    Server *s = CONTAINER(Server, async, This);
    HRESULT hr;
    if (!cancel || !errors) return E_POINTER;
    *cancel = 0;
    *errors = NULL;
    if (!start || !start->bString || !is_utf8(start->szTime, HDA_START_TEXT) ||
        !same_filetime(interval, hda_update_interval()))
        return E_INVALIDARG;
    EnterCriticalSection(&s->lock);
    hr = s->advise_cancel ? E_FAIL : S_OK; /* one advise at a time */
    LeaveCriticalSection(&s->lock);
    if (FAILED(hr)) return hr;
    start->ftTime = test_time(HDA_START_RESOLVED);
    hr = start_read(s, CALL_DATA_CHANGE, transaction, count, handles, NULL, cancel, errors);
    if (SUCCEEDED(hr)) {
        EnterCriticalSection(&s->lock);
        s->advise_cancel = *cancel;
        LeaveCriticalSection(&s->lock);
    }
    return hr;
}

static HRESULT STDMETHODCALLTYPE async_processed(IOPCHDA_AsyncRead *This, DWORD transaction, OPCHDA_TIME *start,
                                                 OPCHDA_TIME *end, FILETIME interval, DWORD count, OPCHANDLE *handles,
                                                 DWORD *aggregates, DWORD *cancel, HRESULT **errors) {
    if (!cancel || !errors) return E_POINTER;
    *cancel = 0;
    *errors = NULL;
    if (!aggregates || !same_filetime(interval, hda_interval()) || !take_range(start, end)) return E_INVALIDARG;
    return start_read(CONTAINER(Server, async, This), CALL_READ_COMPLETE, transaction, count, handles, aggregates,
                      cancel, errors);
}

static HRESULT STDMETHODCALLTYPE async_advise_processed(IOPCHDA_AsyncRead *This, DWORD transaction,
                                                        OPCHDA_TIME *start, FILETIME interval, DWORD count,
                                                        OPCHANDLE *handles, DWORD *aggregates, DWORD intervals,
                                                        DWORD *cancel, HRESULT **errors) {
    (void)This, (void)transaction, (void)start, (void)interval, (void)count, (void)handles, (void)aggregates;
    (void)intervals;
    if (cancel) *cancel = 0;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE async_at_time(IOPCHDA_AsyncRead *This, DWORD transaction, DWORD ntimes,
                                               FILETIME *times, DWORD count, OPCHANDLE *handles, DWORD *cancel,
                                               HRESULT **errors) {
    (void)This, (void)transaction, (void)ntimes, (void)times, (void)count, (void)handles;
    if (cancel) *cancel = 0;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE async_modified(IOPCHDA_AsyncRead *This, DWORD transaction, OPCHDA_TIME *start,
                                                OPCHDA_TIME *end, DWORD num_values, DWORD count, OPCHANDLE *handles,
                                                DWORD *cancel, HRESULT **errors) {
    (void)This, (void)transaction, (void)start, (void)end, (void)num_values, (void)count, (void)handles;
    if (cancel) *cancel = 0;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE async_attribute(IOPCHDA_AsyncRead *This, DWORD transaction, OPCHDA_TIME *start,
                                                 OPCHDA_TIME *end, OPCHANDLE handle, DWORD count, DWORD *ids,
                                                 DWORD *cancel, HRESULT **errors) {
    (void)This, (void)transaction, (void)start, (void)end, (void)handle, (void)count, (void)ids;
    if (cancel) *cancel = 0;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

/* Cancels the advise (its cancel ID as AdviseRaw gave it): OnCancelComplete from a thread of the
 * server. */
static HRESULT STDMETHODCALLTYPE async_cancel(IOPCHDA_AsyncRead *This, DWORD cancel) {
    Server *s = CONTAINER(Server, async, This);
    AsyncRead *r;
    int known;
    EnterCriticalSection(&s->lock);
    known = cancel != 0 && cancel == s->advise_cancel;
    if (known) s->advise_cancel = 0;
    LeaveCriticalSection(&s->lock);
    if (!known) return E_INVALIDARG;
    r = (AsyncRead *)calloc(1, sizeof *r);
    if (!r) return E_OUTOFMEMORY;
    r->call = CALL_CANCEL_COMPLETE;
    r->transaction = cancel;
    return start_call(s, r);
}

static IOPCHDA_AsyncReadVtbl async_vtbl = {
    async_qi,          async_add_ref,   async_release,          async_raw,     async_advise_raw,
    async_processed,   async_advise_processed, async_at_time,   async_modified, async_attribute, async_cancel};

/* -- IOPCHDA_SyncUpdate -- */

static HRESULT STDMETHODCALLTYPE upd_capabilities(IOPCHDA_SyncUpdate *This, OPCHDA_UPDATECAPABILITIES *capabilities) {
    (void)This;
    if (!capabilities) return E_POINTER;
    *capabilities = (OPCHDA_UPDATECAPABILITIES)HDA_UPDATE_CAPS;
    return S_OK;
}

/* The answer to `count` updates of `method` (hda.h), or to DeleteAtTime's times (method 3, `values`
 * and `qualities` NULL): each element as hda_update() says when it arrived as sent, else
 * E_INVALIDARG. */
static HRESULT update(int method, DWORD count, const OPCHANDLE *handles, const FILETIME *times, const VARIANT *values,
                      const DWORD *qualities, HRESULT **errors) {
    HRESULT hr = S_OK;
    DWORD k;
    if (!errors) return E_POINTER;
    *errors = NULL;
    if (count != HDA_UPDATES || !handles || !times || (method < 3 && (!values || !qualities))) return E_INVALIDARG;
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*errors) return E_OUTOFMEMORY;
    for (k = 0; k < count; k++) {
        HdaUpdate want = hda_update(method, k);
        int as_sent = handles[k] == want.handle && same_filetime(times[k], want.time) &&
                      (method == 3 || (hda_same_variant(&values[k], &want.value) && qualities[k] == want.quality));
        (*errors)[k] = as_sent ? want.result : E_INVALIDARG;
        if ((*errors)[k] != S_OK) hr = S_FALSE;
        VariantClear(&want.value);
    }
    return hr;
}

static HRESULT STDMETHODCALLTYPE upd_insert(IOPCHDA_SyncUpdate *This, DWORD count, OPCHANDLE *handles,
                                            FILETIME *times, VARIANT *values, DWORD *qualities, HRESULT **errors) {
    (void)This;
    return update(0, count, handles, times, values, qualities, errors);
}
static HRESULT STDMETHODCALLTYPE upd_replace(IOPCHDA_SyncUpdate *This, DWORD count, OPCHANDLE *handles,
                                             FILETIME *times, VARIANT *values, DWORD *qualities, HRESULT **errors) {
    (void)This;
    return update(1, count, handles, times, values, qualities, errors);
}
static HRESULT STDMETHODCALLTYPE upd_insert_replace(IOPCHDA_SyncUpdate *This, DWORD count, OPCHANDLE *handles,
                                                    FILETIME *times, VARIANT *values, DWORD *qualities,
                                                    HRESULT **errors) {
    (void)This;
    return update(2, count, handles, times, values, qualities, errors);
}
static HRESULT STDMETHODCALLTYPE upd_delete_at_time(IOPCHDA_SyncUpdate *This, DWORD count, OPCHANDLE *handles,
                                                    FILETIME *times, HRESULT **errors) {
    (void)This;
    return update(3, count, handles, times, NULL, NULL, errors);
}

/* Deletes the history of the range (take_range): the items handed out, an invalid handle an error. */
static HRESULT STDMETHODCALLTYPE upd_delete_raw(IOPCHDA_SyncUpdate *This, OPCHDA_TIME *start, OPCHDA_TIME *end,
                                                DWORD count, OPCHANDLE *handles, HRESULT **errors) {
    Server *s = CONTAINER(Server, update, This);
    HRESULT hr = S_OK;
    DWORD k;
    if (!errors) return E_POINTER;
    *errors = NULL;
    if (count == 0 || !handles || !take_range(start, end)) return E_INVALIDARG;
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*errors) return E_OUTOFMEMORY;
    for (k = 0; k < count; k++)
        if (item_of_handle(s, handles[k]) < 0) {
            (*errors)[k] = HDA_E_INVALIDHANDLE;
            hr = S_FALSE;
        }
    return hr;
}

static IOPCHDA_SyncUpdateVtbl upd_vtbl = {upd_qi,      upd_add_ref,        upd_release,    upd_capabilities,
                                          upd_insert,  upd_replace,        upd_insert_replace, upd_delete_raw,
                                          upd_delete_at_time};

/* -- IOPCHDA_Playback: the request checked and a cancel ID given; a raw playback's history comes
 * in one OnPlayback from a thread of the server (when a callback is advised) -- */

/* Starts playback `which` (0 raw, 1 processed) of `count` valid items; its cancel ID transaction + 1. */
static HRESULT start_playback(Server *s, int which, DWORD transaction, DWORD count, const OPCHANDLE *handles,
                              DWORD *cancel, HRESULT **errors) {
    DWORD k;
    if (count == 0 || count > HDA_ITEMS || !handles) return E_INVALIDARG;
    for (k = 0; k < count; k++)
        if (item_of_handle(s, handles[k]) < 0) return E_INVALIDARG;
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*errors) return E_OUTOFMEMORY;
    EnterCriticalSection(&s->lock);
    s->playback_cancel[which] = transaction + 1;
    LeaveCriticalSection(&s->lock);
    *cancel = transaction + 1;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE play_raw(IOPCHDA_Playback *This, DWORD transaction, OPCHDA_TIME *start,
                                          OPCHDA_TIME *end, DWORD num_values, FILETIME duration, FILETIME interval,
                                          DWORD count, OPCHANDLE *handles, DWORD *cancel, HRESULT **errors) {
    Server *s = CONTAINER(Server, playback, This);
    IUnknown *sink;
    AsyncRead *r;
    HRESULT hr;
    if (!cancel || !errors) return E_POINTER;
    *cancel = 0;
    *errors = NULL;
    if (num_values != HDA_RAW_VALUES || !same_filetime(duration, hda_duration()) ||
        !same_filetime(interval, hda_update_interval()) || !take_range(start, end))
        return E_INVALIDARG;
    hr = start_playback(s, 0, transaction, count, handles, cancel, errors);
    sink = sink_point_sink(&s->cp);
    if (FAILED(hr) || !sink) return hr;
    sink->lpVtbl->Release(sink);
    r = (AsyncRead *)calloc(1, sizeof *r);
    if (!r) return hr; /* a test server: the playback goes on without data */
    r->call = CALL_PLAYBACK;
    r->transaction = transaction;
    r->count = count;
    memcpy(r->handles, handles, count * sizeof *handles);
    start_call(s, r);
    return hr;
}

static HRESULT STDMETHODCALLTYPE play_processed(IOPCHDA_Playback *This, DWORD transaction, OPCHDA_TIME *start,
                                                OPCHDA_TIME *end, FILETIME resample, DWORD intervals,
                                                FILETIME interval, DWORD count, OPCHANDLE *handles, DWORD *aggregates,
                                                DWORD *cancel, HRESULT **errors) {
    DWORD k;
    if (!cancel || !errors) return E_POINTER;
    *cancel = 0;
    *errors = NULL;
    if (!same_filetime(resample, hda_interval()) || intervals != HDA_INTERVALS ||
        !same_filetime(interval, hda_update_interval()) || !aggregates || !take_range(start, end))
        return E_INVALIDARG;
    for (k = 0; k < count && k < HDA_ITEMS; k++)
        if (aggregates[k] != OPCHDA_AVERAGE && aggregates[k] != OPCHDA_MAXIMUM) return E_INVALIDARG;
    return start_playback(CONTAINER(Server, playback, This), 1, transaction, count, handles, cancel, errors);
}

static HRESULT STDMETHODCALLTYPE play_cancel(IOPCHDA_Playback *This, DWORD cancel) {
    Server *s = CONTAINER(Server, playback, This);
    HRESULT hr = E_INVALIDARG;
    int i;
    EnterCriticalSection(&s->lock);
    for (i = 0; i < 2; i++)
        if (cancel != 0 && s->playback_cancel[i] == cancel) {
            s->playback_cancel[i] = 0;
            hr = S_OK;
        }
    LeaveCriticalSection(&s->lock);
    return hr;
}

static IOPCHDA_PlaybackVtbl play_vtbl = {play_qi, play_add_ref, play_release, play_raw, play_processed, play_cancel};

/* -- IOPCHDA_SyncAnnotations -- */

static HRESULT STDMETHODCALLTYPE ann_capabilities(IOPCHDA_SyncAnnotations *This,
                                                  OPCHDA_ANNOTATIONCAPABILITIES *capabilities) {
    (void)This;
    if (!capabilities) return E_POINTER;
    *capabilities = (OPCHDA_ANNOTATIONCAPABILITIES)(OPCHDA_READANNOTATIONCAP | OPCHDA_INSERTANNOTATIONCAP);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE ann_read(IOPCHDA_SyncAnnotations *This, OPCHDA_TIME *start, OPCHDA_TIME *end,
                                          DWORD count, OPCHANDLE *handles, OPCHDA_ANNOTATION **values,
                                          HRESULT **errors) {
    if (!values || !errors) return E_POINTER;
    *values = NULL;
    *errors = NULL;
    if (count == 0 || !handles || !take_range(start, end)) return E_INVALIDARG;
    return read_annotations(CONTAINER(Server, annotations, This), count, handles, values, errors);
}

/* The answer to the insertion of `count` annotations: each element as hda.h says when it arrived as
 * sent (an invalid handle HDA_E_INVALIDHANDLE), else E_INVALIDARG. */
static HRESULT insert_annotations(DWORD count, const OPCHANDLE *handles, const FILETIME *times,
                                  const OPCHDA_ANNOTATION *values, HRESULT **errors) {
    HRESULT hr = S_OK;
    DWORD k;
    if (!errors) return E_POINTER;
    *errors = NULL;
    if (count != HDA_UPDATES || !handles || !times || !values) return E_INVALIDARG;
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!*errors) return E_OUTOFMEMORY;
    for (k = 0; k < count; k++) {
        int as_sent = handles[k] == (k < 2 ? HDA_SERVER_HANDLE(k) : HDA_INVALID_HANDLE) &&
                      same_filetime(times[k], hda_insert_time(k)) && hda_is_insert_annotation(&values[k], k);
        (*errors)[k] = !as_sent ? E_INVALIDARG : k < 2 ? S_OK : HDA_E_INVALIDHANDLE;
        if ((*errors)[k] != S_OK) hr = S_FALSE;
    }
    return hr;
}

static HRESULT STDMETHODCALLTYPE ann_insert(IOPCHDA_SyncAnnotations *This, DWORD count, OPCHANDLE *handles,
                                            FILETIME *times, OPCHDA_ANNOTATION *values, HRESULT **errors) {
    (void)This;
    return insert_annotations(count, handles, times, values, errors);
}

static IOPCHDA_SyncAnnotationsVtbl ann_vtbl = {ann_qi, ann_add_ref, ann_release, ann_capabilities, ann_read,
                                               ann_insert};

/* -- IOPCHDA_AsyncUpdate and IOPCHDA_AsyncAnnotations: the request checked as the synchronous
 * methods check it (one element not as sent refuses the whole request), the invalid handle's error
 * in the reply, the other elements' results in OnUpdateComplete or OnInsertAnnotations from a thread
 * of the server (the cancel ID transaction + 1) -- */

/* Calls back `results[0..count)` (per element; an invalid handle's answered now) with the client
 * handles of the valid elements (handles[k] == HDA_SERVER_HANDLE(k)), or refuses the request when an
 * element is E_INVALIDARG. Frees `results`. */
static HRESULT complete_later(Server *s, int call, DWORD transaction, DWORD count, const OPCHANDLE *handles,
                              HRESULT *results, DWORD *cancel, HRESULT **errors) {
    AsyncRead *r;
    HRESULT hr = S_OK;
    DWORD k;
    IUnknown *sink = sink_point_sink(&s->cp);
    if (!sink) {
        CoTaskMemFree(results);
        return CONNECT_E_NOCONNECTION;
    }
    sink->lpVtbl->Release(sink);
    for (k = 0; k < count; k++)
        if (results[k] == E_INVALIDARG) hr = E_INVALIDARG;
    r = SUCCEEDED(hr) ? (AsyncRead *)calloc(1, sizeof *r) : NULL;
    if (!r) {
        CoTaskMemFree(results);
        return FAILED(hr) ? hr : E_OUTOFMEMORY;
    }
    r->call = call;
    r->transaction = transaction;
    for (k = 0; k < count && k < HDA_UPDATES; k++) {
        int i = item_of_handle(s, handles[k]);
        if (results[k] == HDA_E_INVALIDHANDLE || i < 0) {
            hr = S_FALSE;
            continue;
        }
        r->clients[r->count] = HDA_CLIENT_HANDLE(i);
        r->results[r->count++] = results[k];
        results[k] = S_OK;
    }
    if (FAILED(start_call(s, r))) {
        CoTaskMemFree(results);
        return E_OUTOFMEMORY;
    }
    *errors = results;
    *cancel = transaction + 1;
    return hr;
}

static HRESULT STDMETHODCALLTYPE aupd_capabilities(IOPCHDA_AsyncUpdate *This, OPCHDA_UPDATECAPABILITIES *capabilities) {
    (void)This;
    if (!capabilities) return E_POINTER;
    *capabilities = (OPCHDA_UPDATECAPABILITIES)HDA_UPDATE_CAPS;
    return S_OK;
}

/* Insert (method 0), Replace (1), InsertReplace (2) or DeleteAtTime (3, `values` and `qualities`
 * NULL) of HDA_UPDATES elements, completed by OnUpdateComplete. */
static HRESULT async_update(Server *s, int method, DWORD transaction, DWORD count, const OPCHANDLE *handles,
                            const FILETIME *times, const VARIANT *values, const DWORD *qualities, DWORD *cancel,
                            HRESULT **errors) {
    HRESULT *results = NULL, hr;
    if (!cancel || !errors) return E_POINTER;
    *cancel = 0;
    *errors = NULL;
    hr = update(method, count, handles, times, values, qualities, &results);
    if (FAILED(hr)) return hr;
    return complete_later(s, CALL_UPDATE_COMPLETE, transaction, count, handles, results, cancel, errors);
}

static HRESULT STDMETHODCALLTYPE aupd_insert(IOPCHDA_AsyncUpdate *This, DWORD transaction, DWORD count,
                                             OPCHANDLE *handles, FILETIME *times, VARIANT *values, DWORD *qualities,
                                             DWORD *cancel, HRESULT **errors) {
    return async_update(CONTAINER(Server, async_update, This), 0, transaction, count, handles, times, values,
                        qualities, cancel, errors);
}
static HRESULT STDMETHODCALLTYPE aupd_replace(IOPCHDA_AsyncUpdate *This, DWORD transaction, DWORD count,
                                              OPCHANDLE *handles, FILETIME *times, VARIANT *values, DWORD *qualities,
                                              DWORD *cancel, HRESULT **errors) {
    return async_update(CONTAINER(Server, async_update, This), 1, transaction, count, handles, times, values,
                        qualities, cancel, errors);
}
static HRESULT STDMETHODCALLTYPE aupd_insert_replace(IOPCHDA_AsyncUpdate *This, DWORD transaction, DWORD count,
                                                     OPCHANDLE *handles, FILETIME *times, VARIANT *values,
                                                     DWORD *qualities, DWORD *cancel, HRESULT **errors) {
    return async_update(CONTAINER(Server, async_update, This), 2, transaction, count, handles, times, values,
                        qualities, cancel, errors);
}
static HRESULT STDMETHODCALLTYPE aupd_delete_at_time(IOPCHDA_AsyncUpdate *This, DWORD transaction, DWORD count,
                                                     OPCHANDLE *handles, FILETIME *times, DWORD *cancel,
                                                     HRESULT **errors) {
    return async_update(CONTAINER(Server, async_update, This), 3, transaction, count, handles, times, NULL, NULL,
                        cancel, errors);
}

/* Deletes the history of the range (take_range) of the items handed out; each valid element's S_OK
 * comes in OnUpdateComplete. */
static HRESULT STDMETHODCALLTYPE aupd_delete_raw(IOPCHDA_AsyncUpdate *This, DWORD transaction, OPCHDA_TIME *start,
                                                 OPCHDA_TIME *end, DWORD count, OPCHANDLE *handles, DWORD *cancel,
                                                 HRESULT **errors) {
    Server *s = CONTAINER(Server, async_update, This);
    HRESULT *results;
    DWORD k;
    if (!cancel || !errors) return E_POINTER;
    *cancel = 0;
    *errors = NULL;
    if (count == 0 || count > HDA_UPDATES || !handles || !take_range(start, end)) return E_INVALIDARG;
    results = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!results) return E_OUTOFMEMORY;
    for (k = 0; k < count; k++)
        if (item_of_handle(s, handles[k]) < 0) results[k] = HDA_E_INVALIDHANDLE;
    return complete_later(s, CALL_UPDATE_COMPLETE, transaction, count, handles, results, cancel, errors);
}

static HRESULT STDMETHODCALLTYPE aupd_cancel(IOPCHDA_AsyncUpdate *This, DWORD cancel) {
    (void)This, (void)cancel;
    return E_NOTIMPL;
}

static IOPCHDA_AsyncUpdateVtbl aupd_vtbl = {aupd_qi,          aupd_add_ref,        aupd_release,
                                            aupd_capabilities, aupd_insert,         aupd_replace,
                                            aupd_insert_replace, aupd_delete_raw,   aupd_delete_at_time,
                                            aupd_cancel};

static HRESULT STDMETHODCALLTYPE aann_capabilities(IOPCHDA_AsyncAnnotations *This,
                                                   OPCHDA_ANNOTATIONCAPABILITIES *capabilities) {
    (void)This;
    if (!capabilities) return E_POINTER;
    *capabilities = (OPCHDA_ANNOTATIONCAPABILITIES)(OPCHDA_READANNOTATIONCAP | OPCHDA_INSERTANNOTATIONCAP);
    return S_OK;
}

/* The annotations of the range (take_range) of `count` valid items, in OnReadAnnotations. */
static HRESULT STDMETHODCALLTYPE aann_read(IOPCHDA_AsyncAnnotations *This, DWORD transaction, OPCHDA_TIME *start,
                                           OPCHDA_TIME *end, DWORD count, OPCHANDLE *handles, DWORD *cancel,
                                           HRESULT **errors) {
    Server *s = CONTAINER(Server, async_annotations, This);
    IUnknown *sink = sink_point_sink(&s->cp);
    AsyncRead *r;
    DWORD k;
    if (sink) sink->lpVtbl->Release(sink);
    if (!cancel || !errors) return E_POINTER;
    *cancel = 0;
    *errors = NULL;
    if (!sink) return CONNECT_E_NOCONNECTION;
    if (count == 0 || count > HDA_ITEMS || !handles || !take_range(start, end)) return E_INVALIDARG;
    for (k = 0; k < count; k++)
        if (item_of_handle(s, handles[k]) < 0) return E_INVALIDARG; /* not as the client sent them */
    r = (AsyncRead *)calloc(1, sizeof *r);
    *errors = (HRESULT *)task_zero(count * sizeof(HRESULT));
    if (!r || !*errors) {
        free(r);
        CoTaskMemFree(*errors);
        *errors = NULL;
        return E_OUTOFMEMORY;
    }
    r->call = CALL_READ_ANNOTATIONS;
    r->transaction = transaction;
    r->count = count;
    memcpy(r->handles, handles, count * sizeof *handles);
    if (FAILED(start_call(s, r))) {
        CoTaskMemFree(*errors);
        *errors = NULL;
        return E_OUTOFMEMORY;
    }
    *cancel = transaction + 1;
    return S_OK;
}

/* The annotations of hda.h inserted (each element checked as IOPCHDA_SyncAnnotations::Insert checks
 * it), the valid elements' results in OnInsertAnnotations. */
static HRESULT STDMETHODCALLTYPE aann_insert(IOPCHDA_AsyncAnnotations *This, DWORD transaction, DWORD count,
                                             OPCHANDLE *handles, FILETIME *times, OPCHDA_ANNOTATION *values,
                                             DWORD *cancel, HRESULT **errors) {
    HRESULT *results = NULL, hr;
    if (!cancel || !errors) return E_POINTER;
    *cancel = 0;
    *errors = NULL;
    hr = insert_annotations(count, handles, times, values, &results);
    if (FAILED(hr)) return hr;
    return complete_later(CONTAINER(Server, async_annotations, This), CALL_INSERT_ANNOTATIONS, transaction, count,
                          handles, results, cancel, errors);
}

static HRESULT STDMETHODCALLTYPE aann_cancel(IOPCHDA_AsyncAnnotations *This, DWORD cancel) {
    (void)This, (void)cancel;
    return E_NOTIMPL;
}

static IOPCHDA_AsyncAnnotationsVtbl aann_vtbl = {aann_qi,   aann_add_ref, aann_release, aann_capabilities,
                                                 aann_read, aann_insert,  aann_cancel};

static HRESULT OPCCOMN_CDECL create_server(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    Server *s;
    HRESULT hr;
    (void)context;
    (void)outer; /* not aggregatable: the library refuses an outer object */
    s = (Server *)calloc(1, sizeof *s);
    if (!s) return E_OUTOFMEMORY;
    s->server.lpVtbl = &srv_vtbl;
    s->sync.lpVtbl = &sync_vtbl;
    s->async.lpVtbl = &async_vtbl;
    s->annotations.lpVtbl = &ann_vtbl;
    s->update.lpVtbl = &upd_vtbl;
    s->playback.lpVtbl = &play_vtbl;
    s->async_update.lpVtbl = &aupd_vtbl;
    s->async_annotations.lpVtbl = &aann_vtbl;
    s->refs = 1;
    InitializeCriticalSection(&s->lock);
    sink_point_init(&s->cp, (IUnknown *)&s->server, &IID_IOPCHDA_DataCallback);
    OpcServerLock(); /* the server object counts on the process while it lives */
    hr = server_qi(s, riid, ppv);
    server_release(s);
    return hr;
}

int main(void) {
    return run_test_server("hda_server", &CLSID_HdaTestServer, L"Oop.HdaServer.1", L"opccomn HDA tables test server",
                           create_server, HDA_IIDS, HDA_IID_COUNT);
}
