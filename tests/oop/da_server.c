/* The EXE server of the cross-process test of the Data Access proxy/stub (test_da_tables.c): a small
 * OPC DA server written in C (LocalServer32, started by COM with -Embedding, hosted by
 * OpcExeServerRun), reached through opccomn.dll's proxies and stubs, which it registers for this
 * process (da.h); GetErrorString of DA_CODE_PROXY_STUB says whether they are opccomn's. It serves the
 * items of da.h and checks what it receives: a request that does not arrive as the client sent it is
 * answered with E_INVALIDARG or a per-item error, which the client sees.
 *
 * For the DA benchmark (benches/da_bench.c): "-ps:widl" on its command line makes it use the stand-in
 * (opc_classic_widl_ps.dll) instead, "-set:N" serve its class under da_server_class(N), and it also
 * serves the benchmark's 200 items of da.h ("Bench.N", VT_I4 and VT_R8) besides the four; its
 * GetErrorString answers DA_CODE_CPU_TIME and DA_CODE_PROCESS_ID.
 *
 * Server object: IOPCServer (AddGroup of one group, GetErrorString, GetGroupByName, GetStatus,
 * RemoveGroup), IOPCItemProperties, IOPCBrowse (GetProperties, Browse with a continuation point),
 * and, aggregated, the library's IOPCCommon (OpcCommonCreate) and IOPCShutdown connection point
 * (OpcShutdownCreate), which a DA 2.0 client expects of a server object.
 * Group object: IOPCItemMgt (AddItems, RemoveItems), IOPCSyncIO (Read, Write), IOPCGroupStateMgt
 * (GetState, SetState, SetName), IOPCAsyncIO2 (Read: an OnReadComplete, Refresh2: an OnDataChange,
 * each from a thread of the server), IConnectionPointContainer with the IOPCDataCallback connection
 * point. What the tests do not call answers E_NOTIMPL. `/RegServer` and `/UnregServer` register and
 * unregister it (LocalServer32, ProgID Oop.DaServer.1). Exits when its last object is released (or
 * after two minutes without a client, or 20 minutes after the start: a client that died). */
#include "da.h"

#include <olectl.h> /* CONNECT_E_* */
#include <stddef.h>

#define OPC_S_INUSE_ ((HRESULT)0x0004000FL)
#define OPC_E_BADTYPE_ ((HRESULT)0xC0040004L)
#define OPC_E_INVALID_PID_ ((HRESULT)0xC0040203L)
#define OPC_BROWSE_ISITEM_ 2
#define DA_SERVER_GROUP 7 /* the group's server handle */
#define DA_SERVER_ITEM(i) ((OPCHANDLE)(100 + (i)))

#define CONTAINER(type, field, p) ((type *)((char *)(p) - offsetof(type, field)))

/* The item whose ID is `id`, or -1. */
static int item_index(const WCHAR *id) {
    int i;
    for (i = 0; id && i < DA_ITEMS; i++)
        if (wsame(id, W(DA_ITEM_IDS[i]))) return i;
    return -1;
}

/* The item whose ID is `id` among the four and the benchmark's ("Bench.N", index DA_ITEMS + N), or -1. */
static int any_item_index(const WCHAR *id) {
    static const WCHAR prefix[] = L"Bench.";
    unsigned n = 0, k;
    int i = item_index(id);
    if (i >= 0 || !id) return i;
    for (k = 0; prefix[k]; k++)
        if (id[k] != prefix[k]) return -1;
    if (!id[k] || (id[k] == L'0' && id[k + 1])) return -1;
    for (; id[k]; k++) {
        if (id[k] < L'0' || id[k] > L'9' || n >= DA_BENCH_ITEMS) return -1;
        n = n * 10 + (unsigned)(id[k] - L'0');
    }
    return n < DA_BENCH_ITEMS ? DA_ITEMS + (int)n : -1;
}

/* The canonical type of item `i` (of DA_ALL_ITEMS). */
static VARTYPE item_type(int i) {
    return i < DA_ITEMS ? DA_ITEM_TYPES[i] : (i - DA_ITEMS) % 2 ? VT_R8 : VT_I4;
}

/* The item whose server handle is `h`, or -1. */
static int item_of_handle(OPCHANDLE h) {
    return h >= DA_SERVER_ITEM(0) && h < DA_SERVER_ITEM(DA_ALL_ITEMS) ? (int)(h - DA_SERVER_ITEM(0)) : -1;
}

static void *task_alloc_zero(size_t size) {
    void *p = CoTaskMemAlloc(size ? size : 1);
    if (p) memset(p, 0, size ? size : 1);
    return p;
}

/* ---- The group ---- */

typedef struct Group {
    IOPCItemMgt items; /* the identity */
    IOPCSyncIO sync;
    IOPCGroupStateMgt state;
    IOPCAsyncIO2 async;
    IConnectionPointContainer container;
    IConnectionPoint point;
    LONG refs;
    CRITICAL_SECTION lock;
    WCHAR name[64];
    DWORD rate, lcid;
    BOOL active;
    LONG bias;
    FLOAT deadband;
    OPCHANDLE client_group;
    int added[DA_ALL_ITEMS];
    OPCHANDLE client_item[DA_ALL_ITEMS];
    VARIANT values[DA_ALL_ITEMS];
    IOPCDataCallback *sink; /* the advised callback, cookie 1 */
} Group;

typedef struct Server {
    IOPCServer server; /* the identity */
    IOPCItemProperties properties;
    IOPCBrowse browse;
    IUnknown *common;   /* inner IUnknown of the aggregated IOPCCommon session */
    IUnknown *shutdown; /* inner IUnknown of the aggregated IOPCShutdown connection point */
    LONG refs;
    Group *group; /* the one group the server keeps (AddGroup to RemoveGroup, or to its own end) */
} Server;

static HRESULT group_qi(Group *g, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCItemMgt)) *ppv = &g->items;
    else if (IsEqualIID(riid, &IID_IOPCSyncIO)) *ppv = &g->sync;
    else if (IsEqualIID(riid, &IID_IOPCGroupStateMgt)) *ppv = &g->state;
    else if (IsEqualIID(riid, &IID_IOPCAsyncIO2)) *ppv = &g->async;
    else if (IsEqualIID(riid, &IID_IConnectionPointContainer)) *ppv = &g->container;
    else return E_NOINTERFACE;
    InterlockedIncrement(&g->refs);
    return S_OK;
}

static ULONG group_add_ref(Group *g) { return (ULONG)InterlockedIncrement(&g->refs); }

static ULONG group_release(Group *g) {
    LONG n = InterlockedDecrement(&g->refs);
    int i;
    if (n == 0) {
        for (i = 0; i < DA_ALL_ITEMS; i++) VariantClear(&g->values[i]);
        if (g->sink) g->sink->lpVtbl->Release(g->sink);
        DeleteCriticalSection(&g->lock);
        free(g);
        OpcServerUnlock(); /* a group counts on the process while it lives, as its server does */
    }
    return (ULONG)n;
}

/* IUnknown of each of the group's interfaces. */
#define GROUP_UNKNOWN(prefix, Iface, field)                                                                     \
    static HRESULT STDMETHODCALLTYPE prefix##_qi(Iface *This, REFIID riid, void **ppv) {                       \
        return group_qi(CONTAINER(Group, field, This), riid, ppv);                                              \
    }                                                                                                           \
    static ULONG STDMETHODCALLTYPE prefix##_add_ref(Iface *This) { return group_add_ref(CONTAINER(Group, field, This)); } \
    static ULONG STDMETHODCALLTYPE prefix##_release(Iface *This) { return group_release(CONTAINER(Group, field, This)); }

GROUP_UNKNOWN(items, IOPCItemMgt, items)
GROUP_UNKNOWN(sync, IOPCSyncIO, sync)
GROUP_UNKNOWN(state, IOPCGroupStateMgt, state)
GROUP_UNKNOWN(async, IOPCAsyncIO2, async)
GROUP_UNKNOWN(container, IConnectionPointContainer, container)

/* The connection point is an object of its own (its own identity), living as long as its group. */
static HRESULT STDMETHODCALLTYPE point_qi(IConnectionPoint *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!IsEqualIID(riid, &IID_IUnknown) && !IsEqualIID(riid, &IID_IConnectionPoint)) return E_NOINTERFACE;
    *ppv = This;
    group_add_ref(CONTAINER(Group, point, This));
    return S_OK;
}
static ULONG STDMETHODCALLTYPE point_add_ref(IConnectionPoint *This) { return group_add_ref(CONTAINER(Group, point, This)); }
static ULONG STDMETHODCALLTYPE point_release(IConnectionPoint *This) { return group_release(CONTAINER(Group, point, This)); }

/* The value an item holds at first. */
static void initial_value(int i, VARIANT *v) {
    VariantInit(v);
    V_VT(v) = item_type(i);
    switch (i) {
    case 0: V_I4(v) = DA_I4; break;
    case 1: V_R8(v) = DA_R8; break;
    case 2: V_BSTR(v) = bstr_utf8(DA_TEXT); break;
    case 3: V_ARRAY(v) = da_doubles(DA_PROFILE, DA_PROFILE_COUNT); break;
    default: /* the benchmark's */
        if (V_VT(v) == VT_I4) V_I4(v) = i - DA_ITEMS;
        else V_R8(v) = i - DA_ITEMS + 0.5;
        break;
    }
}
/* -- IOPCItemMgt -- */

static HRESULT STDMETHODCALLTYPE items_add(IOPCItemMgt *This, DWORD count, OPCITEMDEF *defs, OPCITEMRESULT **results,
                                           HRESULT **errors) {
    Group *g = CONTAINER(Group, items, This);
    OPCITEMRESULT *r;
    HRESULT *e, hr = S_OK;
    DWORD k;
    if (!results || !errors) return E_POINTER;
    *results = NULL;
    *errors = NULL;
    if (count == 0 || !defs) return E_INVALIDARG;
    r = (OPCITEMRESULT *)task_alloc_zero(count * sizeof *r);
    e = (HRESULT *)task_alloc_zero(count * sizeof *e);
    if (!r || !e) {
        CoTaskMemFree(r);
        CoTaskMemFree(e);
        return E_OUTOFMEMORY;
    }
    EnterCriticalSection(&g->lock);
    for (k = 0; k < count; k++) {
        int i = any_item_index(defs[k].szItemID);
        /* What the client sent: an empty access path, active, no requested type, and DA_BLOB or no
         * blob. */
        int as_sent = defs[k].szAccessPath && defs[k].szAccessPath[0] == 0 && defs[k].bActive &&
                      defs[k].vtRequestedDataType == VT_EMPTY &&
                      (defs[k].dwBlobSize == 0 ? !defs[k].pBlob
                                               : defs[k].dwBlobSize == DA_BLOB_SIZE && defs[k].pBlob &&
                                                     memcmp(defs[k].pBlob, DA_BLOB, DA_BLOB_SIZE) == 0);
        if (!as_sent) {
            e[k] = E_INVALIDARG;
        } else if (i < 0) {
            e[k] = OPC_E_UNKNOWNITEMID_;
        } else {
            g->added[i] = 1;
            g->client_item[i] = defs[k].hClient;
            r[k].hServer = DA_SERVER_ITEM(i);
            r[k].vtCanonicalDataType = item_type(i);
            r[k].dwAccessRights = OPC_READABLE_ | OPC_WRITEABLE_;
            if (defs[k].dwBlobSize) { /* the server's blob for the item: the client's, reversed */
                DWORD b;
                r[k].pBlob = (BYTE *)CoTaskMemAlloc(defs[k].dwBlobSize);
                if (r[k].pBlob) {
                    for (b = 0; b < defs[k].dwBlobSize; b++) r[k].pBlob[b] = defs[k].pBlob[defs[k].dwBlobSize - 1 - b];
                    r[k].dwBlobSize = defs[k].dwBlobSize;
                }
            }
            e[k] = S_OK;
        }
        if (e[k] != S_OK) hr = S_FALSE;
    }
    LeaveCriticalSection(&g->lock);
    *results = r;
    *errors = e;
    return hr;
}

static HRESULT STDMETHODCALLTYPE items_validate(IOPCItemMgt *This, DWORD count, OPCITEMDEF *defs, BOOL blob,
                                                OPCITEMRESULT **results, HRESULT **errors) {
    (void)This, (void)count, (void)defs, (void)blob;
    if (results) *results = NULL;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE items_remove(IOPCItemMgt *This, DWORD count, OPCHANDLE *handles, HRESULT **errors) {
    Group *g = CONTAINER(Group, items, This);
    HRESULT *e, hr = S_OK;
    DWORD k;
    if (!errors) return E_POINTER;
    *errors = NULL;
    if (count == 0 || !handles) return E_INVALIDARG;
    e = (HRESULT *)task_alloc_zero(count * sizeof *e);
    if (!e) return E_OUTOFMEMORY;
    EnterCriticalSection(&g->lock);
    for (k = 0; k < count; k++) {
        int i = item_of_handle(handles[k]);
        if (i < 0 || !g->added[i]) {
            e[k] = OPC_E_INVALIDHANDLE_;
            hr = S_FALSE;
        } else {
            g->added[i] = 0;
        }
    }
    LeaveCriticalSection(&g->lock);
    *errors = e;
    return hr;
}

static HRESULT STDMETHODCALLTYPE items_set_active(IOPCItemMgt *This, DWORD count, OPCHANDLE *handles, BOOL active,
                                                  HRESULT **errors) {
    (void)This, (void)count, (void)handles, (void)active;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE items_set_handles(IOPCItemMgt *This, DWORD count, OPCHANDLE *handles,
                                                   OPCHANDLE *clients, HRESULT **errors) {
    (void)This, (void)count, (void)handles, (void)clients;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE items_set_types(IOPCItemMgt *This, DWORD count, OPCHANDLE *handles, VARTYPE *types,
                                                 HRESULT **errors) {
    (void)This, (void)count, (void)handles, (void)types;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE items_enumerator(IOPCItemMgt *This, REFIID riid, LPUNKNOWN *unk) {
    (void)This, (void)riid;
    if (unk) *unk = NULL;
    return E_NOTIMPL;
}

static IOPCItemMgtVtbl items_vtbl = {items_qi,         items_add_ref,     items_release,   items_add,
                                     items_validate,   items_remove,      items_set_active, items_set_handles,
                                     items_set_types,  items_enumerator};

/* -- IOPCSyncIO -- */

static HRESULT STDMETHODCALLTYPE sync_read(IOPCSyncIO *This, OPCDATASOURCE source, DWORD count, OPCHANDLE *handles,
                                           OPCITEMSTATE **states, HRESULT **errors) {
    Group *g = CONTAINER(Group, sync, This);
    OPCITEMSTATE *s;
    HRESULT *e, hr = S_OK;
    DWORD k;
    if (!states || !errors) return E_POINTER;
    *states = NULL;
    *errors = NULL;
    if (count == 0 || !handles || (source != OPC_DS_CACHE && source != OPC_DS_DEVICE)) return E_INVALIDARG;
    s = (OPCITEMSTATE *)task_alloc_zero(count * sizeof *s);
    e = (HRESULT *)task_alloc_zero(count * sizeof *e);
    if (!s || !e) {
        CoTaskMemFree(s);
        CoTaskMemFree(e);
        return E_OUTOFMEMORY;
    }
    EnterCriticalSection(&g->lock);
    for (k = 0; k < count; k++) {
        int i = item_of_handle(handles[k]);
        VariantInit(&s[k].vDataValue);
        if (i < 0 || !g->added[i]) {
            e[k] = OPC_E_INVALIDHANDLE_;
            hr = S_FALSE;
            continue;
        }
        s[k].hClient = g->client_item[i];
        /* The device's time of the value: a second later than the cache's. */
        s[k].ftTimeStamp = test_time((unsigned)i + (source == OPC_DS_DEVICE ? 10 : 0));
        s[k].wQuality = OPC_QUALITY_GOOD_;
        e[k] = VariantCopy(&s[k].vDataValue, &g->values[i]);
        if (e[k] != S_OK) hr = S_FALSE;
    }
    LeaveCriticalSection(&g->lock);
    *states = s;
    *errors = e;
    return hr;
}

static HRESULT STDMETHODCALLTYPE sync_write(IOPCSyncIO *This, DWORD count, OPCHANDLE *handles, VARIANT *values,
                                            HRESULT **errors) {
    Group *g = CONTAINER(Group, sync, This);
    HRESULT *e, hr = S_OK;
    DWORD k;
    if (!errors) return E_POINTER;
    *errors = NULL;
    if (count == 0 || !handles || !values) return E_INVALIDARG;
    e = (HRESULT *)task_alloc_zero(count * sizeof *e);
    if (!e) return E_OUTOFMEMORY;
    EnterCriticalSection(&g->lock);
    for (k = 0; k < count; k++) {
        int i = item_of_handle(handles[k]);
        if (i < 0 || !g->added[i]) e[k] = OPC_E_INVALIDHANDLE_;
        else if (V_VT(&values[k]) != item_type(i)) e[k] = OPC_E_BADTYPE_;
        else e[k] = VariantCopy(&g->values[i], &values[k]);
        if (e[k] != S_OK) hr = S_FALSE;
    }
    LeaveCriticalSection(&g->lock);
    *errors = e;
    return hr;
}

static IOPCSyncIOVtbl sync_vtbl = {sync_qi, sync_add_ref, sync_release, sync_read, sync_write};

/* -- IOPCGroupStateMgt -- */

static HRESULT STDMETHODCALLTYPE state_get(IOPCGroupStateMgt *This, DWORD *rate, BOOL *active, LPWSTR *name,
                                           LONG *bias, FLOAT *deadband, DWORD *lcid, OPCHANDLE *client,
                                           OPCHANDLE *server) {
    Group *g = CONTAINER(Group, state, This);
    size_t n;
    if (!rate || !active || !name || !bias || !deadband || !lcid || !client || !server) return E_POINTER;
    EnterCriticalSection(&g->lock);
    n = wlen(g->name);
    *name = (LPWSTR)CoTaskMemAlloc((n + 1) * sizeof(WCHAR));
    if (*name) memcpy(*name, g->name, (n + 1) * sizeof(WCHAR));
    *rate = g->rate;
    *active = g->active;
    *bias = g->bias;
    *deadband = g->deadband;
    *lcid = g->lcid;
    *client = g->client_group;
    *server = DA_SERVER_GROUP;
    LeaveCriticalSection(&g->lock);
    return *name ? S_OK : E_OUTOFMEMORY;
}

static HRESULT STDMETHODCALLTYPE state_set(IOPCGroupStateMgt *This, DWORD *rate, DWORD *revised, BOOL *active,
                                           LONG *bias, FLOAT *deadband, DWORD *lcid, OPCHANDLE *client) {
    Group *g = CONTAINER(Group, state, This);
    if (!revised) return E_POINTER;
    EnterCriticalSection(&g->lock);
    if (rate) g->rate = *rate < 100 ? 100 : *rate;
    if (active) g->active = *active;
    if (bias) g->bias = *bias;
    if (deadband) g->deadband = *deadband;
    if (lcid) g->lcid = *lcid;
    if (client) g->client_group = *client;
    *revised = g->rate;
    LeaveCriticalSection(&g->lock);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE state_set_name(IOPCGroupStateMgt *This, LPCWSTR name) {
    Group *g = CONTAINER(Group, state, This);
    size_t n = name ? wlen(name) : 0;
    if (!name || n + 1 > sizeof g->name / sizeof g->name[0]) return E_INVALIDARG;
    EnterCriticalSection(&g->lock);
    memcpy(g->name, name, (n + 1) * sizeof(WCHAR));
    LeaveCriticalSection(&g->lock);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE state_clone(IOPCGroupStateMgt *This, LPCWSTR name, REFIID riid, LPUNKNOWN *unk) {
    (void)This, (void)name, (void)riid;
    if (unk) *unk = NULL;
    return E_NOTIMPL;
}

static IOPCGroupStateMgtVtbl state_vtbl = {state_qi,  state_add_ref,  state_release,
                                           state_get, state_set,      state_set_name, state_clone};

/* -- IOPCAsyncIO2 -- */

typedef struct Refresh {
    Group *group; /* a reference */
    DWORD transaction;
    int read;                /* an IOPCAsyncIO2::Read of `items`, else a refresh of every added item */
    DWORD count;             /* a read's items, in the order asked */
    int items[DA_ITEMS];
} Refresh;

/* The callback of a refresh (OnDataChange of every added item, stamped as the cache's + 20 s) or of a
 * read (OnReadComplete of the items read, stamped as a sync read from the device), from a thread of
 * the server, as the specification has them delivered. */
static DWORD WINAPI refresh_thread(void *param) {
    Refresh *r = (Refresh *)param;
    Group *g = r->group;
    OPCHANDLE handles[DA_ALL_ITEMS];
    VARIANT values[DA_ALL_ITEMS];
    WORD qualities[DA_ALL_ITEMS];
    FILETIME times[DA_ALL_ITEMS];
    HRESULT errors[DA_ALL_ITEMS];
    IOPCDataCallback *sink;
    OPCHANDLE group_handle;
    DWORD n = 0, k;
    int i;
    CoInitializeEx(NULL, COINIT_MULTITHREADED);
    EnterCriticalSection(&g->lock);
    sink = g->sink;
    if (sink) sink->lpVtbl->AddRef(sink);
    group_handle = g->client_group;
    for (k = 0; k < (r->read ? r->count : (DWORD)DA_ALL_ITEMS); k++) {
        i = r->read ? r->items[k] : (int)k;
        if (!g->added[i]) continue;
        handles[n] = g->client_item[i];
        VariantInit(&values[n]);
        errors[n] = VariantCopy(&values[n], &g->values[i]);
        qualities[n] = OPC_QUALITY_GOOD_;
        times[n] = test_time((unsigned)i + (r->read ? 10 : 20));
        n++;
    }
    LeaveCriticalSection(&g->lock);
    if (sink && r->read) {
        sink->lpVtbl->OnReadComplete(sink, r->transaction, group_handle, S_OK, S_OK, n, handles, values, qualities,
                                     times, errors);
    } else if (sink) {
        sink->lpVtbl->OnDataChange(sink, r->transaction, group_handle, S_OK, S_OK, n, handles, values, qualities,
                                   times, errors);
    }
    if (sink) sink->lpVtbl->Release(sink);
    while (n) VariantClear(&values[--n]);
    group_release(g);
    free(r);
    CoUninitialize();
    return 0;
}

/* Starts the callback of `r` (its group referenced here) on a thread of its own. */
static HRESULT start_callback(Refresh *r) {
    HANDLE thread;
    group_add_ref(r->group);
    thread = CreateThread(NULL, 0, refresh_thread, r, 0, NULL);
    if (!thread) {
        group_release(r->group);
        free(r);
        return E_OUTOFMEMORY;
    }
    CloseHandle(thread);
    return S_OK;
}

/* Whether a callback is advised on the group's connection point. */
static int group_connected(Group *g) {
    int connected;
    EnterCriticalSection(&g->lock);
    connected = g->sink != NULL;
    LeaveCriticalSection(&g->lock);
    return connected;
}

/* A read from the device of at most DA_ITEMS items: an invalid handle gets OPC_E_INVALIDHANDLE and
 * is left out of the OnReadComplete; with none valid there is no callback (S_FALSE, cancel ID 0). */
static HRESULT STDMETHODCALLTYPE async_read(IOPCAsyncIO2 *This, DWORD count, OPCHANDLE *handles, DWORD transaction,
                                            DWORD *cancel, HRESULT **errors) {
    Group *g = CONTAINER(Group, async, This);
    Refresh *r;
    HRESULT *e, hr = S_OK;
    DWORD k;
    if (cancel) *cancel = 0;
    if (errors) *errors = NULL;
    if (!cancel || !errors) return E_POINTER;
    if (count == 0 || count > DA_ITEMS || !handles) return E_INVALIDARG;
    if (!group_connected(g)) return CONNECT_E_NOCONNECTION;
    r = (Refresh *)calloc(1, sizeof *r);
    e = (HRESULT *)task_alloc_zero(count * sizeof *e);
    if (!r || !e) {
        free(r);
        CoTaskMemFree(e);
        return E_OUTOFMEMORY;
    }
    r->group = g;
    r->transaction = transaction;
    r->read = 1;
    EnterCriticalSection(&g->lock);
    for (k = 0; k < count; k++) {
        int i = item_of_handle(handles[k]);
        if (i < 0 || !g->added[i]) {
            e[k] = OPC_E_INVALIDHANDLE_;
            hr = S_FALSE;
        } else {
            r->items[r->count++] = i;
        }
    }
    LeaveCriticalSection(&g->lock);
    if (r->count == 0) {
        free(r);
    } else {
        HRESULT started = start_callback(r);
        if (FAILED(started)) {
            CoTaskMemFree(e);
            return started;
        }
        *cancel = transaction + 1;
    }
    *errors = e;
    return hr;
}

static HRESULT STDMETHODCALLTYPE async_write(IOPCAsyncIO2 *This, DWORD count, OPCHANDLE *handles, VARIANT *values,
                                             DWORD transaction, DWORD *cancel, HRESULT **errors) {
    (void)This, (void)count, (void)handles, (void)values, (void)transaction;
    if (cancel) *cancel = 0;
    if (errors) *errors = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE async_refresh(IOPCAsyncIO2 *This, OPCDATASOURCE source, DWORD transaction,
                                               DWORD *cancel) {
    Group *g = CONTAINER(Group, async, This);
    Refresh *r;
    HRESULT hr;
    if (!cancel) return E_POINTER;
    *cancel = 0;
    if (source != OPC_DS_CACHE && source != OPC_DS_DEVICE) return E_INVALIDARG;
    if (!group_connected(g)) return CONNECT_E_NOCONNECTION;
    r = (Refresh *)calloc(1, sizeof *r);
    if (!r) return E_OUTOFMEMORY;
    r->group = g;
    r->transaction = transaction;
    hr = start_callback(r);
    if (FAILED(hr)) return hr;
    *cancel = transaction + 1;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE async_cancel(IOPCAsyncIO2 *This, DWORD cancel) {
    (void)This, (void)cancel;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE async_set_enable(IOPCAsyncIO2 *This, BOOL enable) {
    (void)This, (void)enable;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE async_get_enable(IOPCAsyncIO2 *This, BOOL *enable) {
    (void)This;
    if (enable) *enable = FALSE;
    return E_NOTIMPL;
}

static IOPCAsyncIO2Vtbl async_vtbl = {async_qi,      async_add_ref, async_release,    async_read,      async_write,
                                      async_refresh, async_cancel,  async_set_enable, async_get_enable};

/* -- The connection point of IOPCDataCallback -- */

static HRESULT STDMETHODCALLTYPE container_enum(IConnectionPointContainer *This, IEnumConnectionPoints **e) {
    (void)This;
    if (e) *e = NULL;
    return E_NOTIMPL;
}

static HRESULT STDMETHODCALLTYPE container_find(IConnectionPointContainer *This, REFIID riid, IConnectionPoint **cp) {
    Group *g = CONTAINER(Group, container, This);
    if (!cp) return E_POINTER;
    *cp = NULL;
    if (!IsEqualIID(riid, &IID_IOPCDataCallback)) return CONNECT_E_NOCONNECTION;
    *cp = &g->point;
    group_add_ref(g);
    return S_OK;
}

static IConnectionPointContainerVtbl container_vtbl = {container_qi, container_add_ref, container_release,
                                                       container_enum, container_find};

static HRESULT STDMETHODCALLTYPE point_iid(IConnectionPoint *This, IID *iid) {
    (void)This;
    if (!iid) return E_POINTER;
    *iid = IID_IOPCDataCallback;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE point_container(IConnectionPoint *This, IConnectionPointContainer **c) {
    Group *g = CONTAINER(Group, point, This);
    if (!c) return E_POINTER;
    *c = &g->container;
    group_add_ref(g);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE point_advise(IConnectionPoint *This, IUnknown *unk, DWORD *cookie) {
    Group *g = CONTAINER(Group, point, This);
    IOPCDataCallback *sink = NULL;
    HRESULT hr;
    if (!cookie) return E_POINTER;
    *cookie = 0;
    if (!unk) return E_POINTER;
    hr = unk->lpVtbl->QueryInterface(unk, &IID_IOPCDataCallback, (void **)&sink);
    if (FAILED(hr)) return CONNECT_E_CANNOTCONNECT;
    EnterCriticalSection(&g->lock);
    if (g->sink) {
        hr = CONNECT_E_ADVISELIMIT;
    } else {
        g->sink = sink;
        sink = NULL;
        *cookie = 1;
    }
    LeaveCriticalSection(&g->lock);
    if (sink) sink->lpVtbl->Release(sink);
    return hr;
}

static HRESULT STDMETHODCALLTYPE point_unadvise(IConnectionPoint *This, DWORD cookie) {
    Group *g = CONTAINER(Group, point, This);
    IOPCDataCallback *sink = NULL;
    EnterCriticalSection(&g->lock);
    if (cookie == 1) {
        sink = g->sink;
        g->sink = NULL;
    }
    LeaveCriticalSection(&g->lock);
    if (!sink) return CONNECT_E_NOCONNECTION;
    sink->lpVtbl->Release(sink);
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE point_enum(IConnectionPoint *This, IEnumConnections **e) {
    (void)This;
    if (e) *e = NULL;
    return E_NOTIMPL;
}

static IConnectionPointVtbl point_vtbl = {point_qi,     point_add_ref,  point_release, point_iid,
                                          point_container, point_advise, point_unadvise, point_enum};

/* ---- The server ---- */

static HRESULT server_qi(Server *s, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCServer)) *ppv = &s->server;
    else if (IsEqualIID(riid, &IID_IOPCItemProperties)) *ppv = &s->properties;
    else if (IsEqualIID(riid, &IID_IOPCBrowse)) *ppv = &s->browse;
    else if (IsEqualIID(riid, &IID_IOPCCommon) && s->common)
        return s->common->lpVtbl->QueryInterface(s->common, riid, ppv);
    else if (IsEqualIID(riid, &IID_IConnectionPointContainer) && s->shutdown)
        return s->shutdown->lpVtbl->QueryInterface(s->shutdown, riid, ppv);
    else return E_NOINTERFACE;
    InterlockedIncrement(&s->refs);
    return S_OK;
}

static ULONG server_release(Server *s) {
    LONG n = InterlockedDecrement(&s->refs);
    if (n == 0) {
        if (s->group) group_release(s->group);
        if (s->common) s->common->lpVtbl->Release(s->common);
        if (s->shutdown) s->shutdown->lpVtbl->Release(s->shutdown);
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
        return (ULONG)InterlockedIncrement(&CONTAINER(Server, field, This)->refs);                               \
    }                                                                                                           \
    static ULONG STDMETHODCALLTYPE prefix##_release(Iface *This) {                                             \
        return server_release(CONTAINER(Server, field, This));                                                  \
    }

SERVER_UNKNOWN(opc, IOPCServer, server)
SERVER_UNKNOWN(props, IOPCItemProperties, properties)
SERVER_UNKNOWN(browse, IOPCBrowse, browse)

/* -- IOPCServer -- */

static HRESULT STDMETHODCALLTYPE opc_add_group(IOPCServer *This, LPCWSTR name, BOOL active, DWORD rate,
                                               OPCHANDLE client_group, LONG *bias, FLOAT *deadband, DWORD lcid,
                                               OPCHANDLE *server_group, DWORD *revised, REFIID riid, LPUNKNOWN *unk) {
    Server *s = CONTAINER(Server, server, This);
    Group *g;
    HRESULT hr;
    int i;
    if (!server_group || !revised || !unk) return E_POINTER;
    *server_group = 0;
    *revised = 0;
    *unk = NULL;
    if (!name || wlen(name) + 1 > sizeof g->name / sizeof g->name[0]) return E_INVALIDARG;
    if (s->group) return E_FAIL; /* this server serves one group */
    g = (Group *)calloc(1, sizeof *g);
    if (!g) return E_OUTOFMEMORY;
    g->items.lpVtbl = &items_vtbl;
    g->sync.lpVtbl = &sync_vtbl;
    g->state.lpVtbl = &state_vtbl;
    g->async.lpVtbl = &async_vtbl;
    g->container.lpVtbl = &container_vtbl;
    g->point.lpVtbl = &point_vtbl;
    g->refs = 1; /* the server's */
    OpcServerLock();
    InitializeCriticalSection(&g->lock);
    memcpy(g->name, name, (wlen(name) + 1) * sizeof(WCHAR));
    g->active = active;
    g->rate = rate < 100 ? 100 : rate;
    g->client_group = client_group;
    g->bias = bias ? *bias : 0;
    g->deadband = deadband ? *deadband : 0.0f;
    g->lcid = lcid;
    for (i = 0; i < DA_ALL_ITEMS; i++) initial_value(i, &g->values[i]);
    hr = group_qi(g, riid, (void **)unk);
    if (FAILED(hr)) {
        group_release(g);
        return hr;
    }
    s->group = g;
    *server_group = DA_SERVER_GROUP;
    *revised = g->rate;
    return g->rate == rate ? S_OK : (HRESULT)0x0004000DL; /* OPC_S_UNSUPPORTEDRATE */
}

static HRESULT STDMETHODCALLTYPE opc_error_string(IOPCServer *This, HRESULT code, LCID locale, LPWSTR *text) {
    (void)This;
    if (!text) return E_POINTER;
    *text = NULL;
    if (code == DA_CODE_PROXY_STUB) {
        *text = task_utf8(da_proxy_stub_is_opccomn() ? "opccomn" : da_proxy_stub_is_classic() ? "widl" : "other");
        return *text ? S_OK : E_OUTOFMEMORY;
    }
    if (code == DA_CODE_CPU_TIME || code == DA_CODE_PROCESS_ID) {
        char number[32];
        if (code == DA_CODE_CPU_TIME) snprintf(number, sizeof number, "%llu", da_process_cpu_ns());
        else snprintf(number, sizeof number, "%lu", (unsigned long)GetCurrentProcessId());
        *text = task_utf8(number);
        return *text ? S_OK : E_OUTOFMEMORY;
    }
    if (code != DA_ERROR_CODE || locale != 0x0409) return E_INVALIDARG;
    *text = task_utf8(DA_ERROR_TEXT);
    return *text ? S_OK : E_OUTOFMEMORY;
}

static HRESULT STDMETHODCALLTYPE opc_group_by_name(IOPCServer *This, LPCWSTR name, REFIID riid, LPUNKNOWN *unk) {
    Server *s = CONTAINER(Server, server, This);
    if (!unk) return E_POINTER;
    *unk = NULL;
    if (!name || !s->group || !wsame(name, s->group->name)) return E_INVALIDARG;
    return group_qi(s->group, riid, (void **)unk);
}

static HRESULT STDMETHODCALLTYPE opc_status(IOPCServer *This, OPCSERVERSTATUS **status) {
    Server *s = CONTAINER(Server, server, This);
    OPCSERVERSTATUS *st;
    if (!status) return E_POINTER;
    *status = NULL;
    st = (OPCSERVERSTATUS *)task_alloc_zero(sizeof *st);
    if (!st) return E_OUTOFMEMORY;
    st->ftStartTime = test_time(0);
    st->ftCurrentTime = test_time(1);
    st->ftLastUpdateTime = test_time(2);
    st->dwServerState = OPC_STATUS_RUNNING;
    st->dwGroupCount = s->group ? 1 : 0;
    st->dwBandWidth = 0xFFFFFFFF;
    st->wMajorVersion = 3;
    st->wMinorVersion = 0;
    st->wBuildNumber = 42;
    st->szVendorInfo = task_utf8(DA_VENDOR_INFO);
    *status = st;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE opc_remove_group(IOPCServer *This, OPCHANDLE handle, BOOL force) {
    Server *s = CONTAINER(Server, server, This);
    Group *g = s->group;
    int in_use;
    (void)force;
    if (!g || handle != DA_SERVER_GROUP) return E_INVALIDARG;
    s->group = NULL;
    in_use = g->refs > 1; /* the client still holds it: it goes with the client's last release */
    group_release(g);
    return in_use ? OPC_S_INUSE_ : S_OK;
}

static HRESULT STDMETHODCALLTYPE opc_enum_groups(IOPCServer *This, OPCENUMSCOPE scope, REFIID riid, LPUNKNOWN *unk) {
    (void)This, (void)scope, (void)riid;
    if (unk) *unk = NULL;
    return E_NOTIMPL;
}

static IOPCServerVtbl opc_vtbl = {opc_qi,     opc_add_ref,       opc_release,      opc_add_group, opc_error_string,
                                  opc_group_by_name, opc_status, opc_remove_group, opc_enum_groups};

/* -- Item properties: 1 (the canonical type, VT_I2) and 101 (a description, VT_BSTR) of each item -- */

static const char *property_description(DWORD id) {
    return id == 1 ? "Item Canonical Data Type" : id == 101 ? "Item Description" : NULL;
}

/* The value of property `id` of item `i`. */
static HRESULT property_value(int i, DWORD id, VARIANT *v) {
    char text[96];
    VariantInit(v);
    if (id == 1) {
        V_VT(v) = VT_I2;
        V_I2(v) = (SHORT)DA_ITEM_TYPES[i];
        return S_OK;
    }
    if (id == 101) {
        snprintf(text, sizeof text, "Description of %s", DA_ITEM_IDS[i]);
        V_VT(v) = VT_BSTR;
        V_BSTR(v) = bstr_utf8(text);
        return V_BSTR(v) ? S_OK : E_OUTOFMEMORY;
    }
    return OPC_E_INVALID_PID_;
}

/* The item ID of property `id` of item `i` (101 has one; 1 has none). */
static LPWSTR property_item_id(int i, DWORD id) {
    char text[96];
    if (id != 101) return NULL;
    snprintf(text, sizeof text, "%s.Description", DA_ITEM_IDS[i]);
    return task_utf8(text);
}

static HRESULT STDMETHODCALLTYPE props_query(IOPCItemProperties *This, LPWSTR item, DWORD *count, DWORD **ids,
                                             LPWSTR **descriptions, VARTYPE **types) {
    DWORD k;
    (void)This;
    if (!count || !ids || !descriptions || !types) return E_POINTER;
    *count = 0;
    *ids = NULL;
    *descriptions = NULL;
    *types = NULL;
    if (item_index(item) < 0) return OPC_E_UNKNOWNITEMID_;
    *ids = (DWORD *)task_alloc_zero(DA_PROPERTY_COUNT * sizeof **ids);
    *descriptions = (LPWSTR *)task_alloc_zero(DA_PROPERTY_COUNT * sizeof **descriptions);
    *types = (VARTYPE *)task_alloc_zero(DA_PROPERTY_COUNT * sizeof **types);
    if (!*ids || !*descriptions || !*types) {
        CoTaskMemFree(*ids);
        CoTaskMemFree(*descriptions);
        CoTaskMemFree(*types);
        *ids = NULL;
        *descriptions = NULL;
        *types = NULL;
        return E_OUTOFMEMORY;
    }
    for (k = 0; k < DA_PROPERTY_COUNT; k++) {
        (*ids)[k] = DA_PROPERTY_IDS[k];
        (*descriptions)[k] = task_utf8(property_description(DA_PROPERTY_IDS[k]));
        (*types)[k] = DA_PROPERTY_IDS[k] == 1 ? VT_I2 : VT_BSTR;
    }
    *count = DA_PROPERTY_COUNT;
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE props_get(IOPCItemProperties *This, LPWSTR item, DWORD count, DWORD *ids,
                                           VARIANT **values, HRESULT **errors) {
    int i = item_index(item);
    HRESULT hr = S_OK;
    DWORD k;
    (void)This;
    if (!values || !errors) return E_POINTER;
    *values = NULL;
    *errors = NULL;
    if (i < 0) return OPC_E_UNKNOWNITEMID_;
    if (count == 0 || !ids) return E_INVALIDARG;
    *values = (VARIANT *)task_alloc_zero(count * sizeof **values);
    *errors = (HRESULT *)task_alloc_zero(count * sizeof **errors);
    if (!*values || !*errors) {
        CoTaskMemFree(*values);
        CoTaskMemFree(*errors);
        *values = NULL;
        *errors = NULL;
        return E_OUTOFMEMORY;
    }
    for (k = 0; k < count; k++) {
        (*errors)[k] = property_value(i, ids[k], &(*values)[k]);
        if ((*errors)[k] != S_OK) hr = S_FALSE;
    }
    return hr;
}

static HRESULT STDMETHODCALLTYPE props_lookup(IOPCItemProperties *This, LPWSTR item, DWORD count, DWORD *ids,
                                              LPWSTR **new_ids, HRESULT **errors) {
    int i = item_index(item);
    HRESULT hr = S_OK;
    DWORD k;
    (void)This;
    if (!new_ids || !errors) return E_POINTER;
    *new_ids = NULL;
    *errors = NULL;
    if (i < 0) return OPC_E_UNKNOWNITEMID_;
    if (count == 0 || !ids) return E_INVALIDARG;
    *new_ids = (LPWSTR *)task_alloc_zero(count * sizeof **new_ids);
    *errors = (HRESULT *)task_alloc_zero(count * sizeof **errors);
    if (!*new_ids || !*errors) {
        CoTaskMemFree(*new_ids);
        CoTaskMemFree(*errors);
        *new_ids = NULL;
        *errors = NULL;
        return E_OUTOFMEMORY;
    }
    for (k = 0; k < count; k++) {
        (*new_ids)[k] = property_item_id(i, ids[k]);
        (*errors)[k] = (*new_ids)[k] ? S_OK : OPC_E_INVALID_PID_;
        if ((*errors)[k] != S_OK) hr = S_FALSE;
    }
    return hr;
}

static IOPCItemPropertiesVtbl props_vtbl = {props_qi,    props_add_ref, props_release,
                                            props_query, props_get,     props_lookup};

/* -- IOPCBrowse -- */

/* The properties `ids` (all when `count` is 0) of item `i`, with their values when asked. */
static HRESULT fill_properties(OPCITEMPROPERTIES *p, int i, BOOL with_values, DWORD count, const DWORD *ids) {
    DWORD k;
    if (count == 0) {
        count = DA_PROPERTY_COUNT;
        ids = DA_PROPERTY_IDS;
    }
    p->pItemProperties = (OPCITEMPROPERTY *)task_alloc_zero(count * sizeof *p->pItemProperties);
    if (!p->pItemProperties) return E_OUTOFMEMORY;
    p->dwNumProperties = count;
    for (k = 0; k < count; k++) {
        OPCITEMPROPERTY *q = &p->pItemProperties[k];
        const char *description = property_description(ids[k]);
        VariantInit(&q->vValue);
        q->dwPropertyID = ids[k];
        if (!description) {
            q->hrErrorID = OPC_E_INVALID_PID_;
            p->hrErrorID = S_FALSE;
            continue;
        }
        q->vtDataType = ids[k] == 1 ? VT_I2 : VT_BSTR;
        q->szDescription = task_utf8(description);
        q->szItemID = property_item_id(i, ids[k]);
        q->hrErrorID = with_values ? property_value(i, ids[k], &q->vValue) : S_OK;
    }
    return S_OK;
}

static HRESULT STDMETHODCALLTYPE browse_properties(IOPCBrowse *This, DWORD count, LPWSTR *items, BOOL with_values,
                                                   DWORD property_count, DWORD *property_ids,
                                                   OPCITEMPROPERTIES **properties) {
    OPCITEMPROPERTIES *p;
    HRESULT hr = S_OK;
    DWORD k;
    (void)This;
    if (!properties) return E_POINTER;
    *properties = NULL;
    if (count == 0 || !items || (property_count && !property_ids)) return E_INVALIDARG;
    p = (OPCITEMPROPERTIES *)task_alloc_zero(count * sizeof *p);
    if (!p) return E_OUTOFMEMORY;
    for (k = 0; k < count; k++) {
        int i = item_index(items[k]);
        if (i < 0) p[k].hrErrorID = OPC_E_UNKNOWNITEMID_;
        else fill_properties(&p[k], i, with_values, property_count, property_ids);
        if (p[k].hrErrorID != S_OK) hr = S_FALSE;
    }
    *properties = p;
    return hr;
}

/* The root holds the four items; a continuation point is "cp:N", N the next item. */
static HRESULT STDMETHODCALLTYPE browse_browse(IOPCBrowse *This, LPWSTR item, LPWSTR *continuation, DWORD max,
                                               OPCBROWSEFILTER filter, LPWSTR name_filter, LPWSTR vendor_filter,
                                               BOOL all_properties, BOOL with_values, DWORD property_count,
                                               DWORD *property_ids, BOOL *more, DWORD *count,
                                               OPCBROWSEELEMENT **elements) {
    OPCBROWSEELEMENT *e;
    unsigned start = 0, end, i;
    (void)This;
    if (!continuation || !more || !count || !elements) return E_POINTER;
    *more = FALSE;
    *count = 0;
    *elements = NULL;
    (void)property_ids; /* a reference pointer: never NULL, and unused with no properties asked */
    if (!item || item[0] || filter != OPC_BROWSE_FILTER_ALL || !name_filter || name_filter[0] || !vendor_filter ||
        vendor_filter[0] || property_count)
        return E_INVALIDARG;
    if (*continuation && (*continuation)[0]) {
        if ((*continuation)[0] != L'c' || (*continuation)[1] != L'p' || (*continuation)[2] != L':' ||
            (*continuation)[3] < L'0' || (*continuation)[3] >= L'0' + DA_ITEMS || (*continuation)[4])
            return (HRESULT)0xC0040403L; /* OPC_E_INVALIDCONTINUATIONPOINT */
        start = (unsigned)((*continuation)[3] - L'0');
    }
    end = max && start + max < DA_ITEMS ? start + max : DA_ITEMS;
    e = (OPCBROWSEELEMENT *)task_alloc_zero((end - start) * sizeof *e);
    if (!e) return E_OUTOFMEMORY;
    for (i = start; i < end; i++) {
        OPCBROWSEELEMENT *x = &e[i - start];
        x->szName = task_utf8(DA_ITEM_IDS[i]);
        x->szItemID = task_utf8(DA_ITEM_IDS[i]);
        x->dwFlagValue = OPC_BROWSE_ISITEM_;
        if (all_properties) fill_properties(&x->ItemProperties, (int)i, with_values, 0, NULL);
    }
    /* The client's continuation point goes; the next one, or none, comes back. */
    CoTaskMemFree(*continuation);
    *continuation = NULL;
    if (end < DA_ITEMS) {
        char next[8];
        snprintf(next, sizeof next, "cp:%u", end);
        *continuation = task_utf8(next);
        *more = TRUE;
    }
    *count = end - start;
    *elements = e;
    return S_OK;
}

static IOPCBrowseVtbl browse_vtbl = {browse_qi, browse_add_ref, browse_release, browse_properties, browse_browse};

/* ---- The process ---- */

static HRESULT OPCCOMN_CDECL create_server(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    Server *s;
    HRESULT hr;
    (void)context;
    (void)outer; /* not aggregatable: the library refuses an outer object */
    s = (Server *)calloc(1, sizeof *s);
    if (!s) return E_OUTOFMEMORY;
    s->server.lpVtbl = &opc_vtbl;
    s->properties.lpVtbl = &props_vtbl;
    s->browse.lpVtbl = &browse_vtbl;
    s->refs = 1;
    OpcServerLock(); /* the server object counts on the process while it lives */
    hr = OpcCommonCreate(NULL, (IUnknown *)&s->server, &IID_IUnknown, (void **)&s->common);
    if (SUCCEEDED(hr)) hr = OpcShutdownCreate((IUnknown *)&s->server, &IID_IUnknown, (void **)&s->shutdown);
    if (SUCCEEDED(hr)) hr = server_qi(s, riid, ppv);
    server_release(s); /* frees the object when creating or QueryInterface failed */
    return hr;
}

/* A client that died leaves its references (Wine runs no rundown of a dead client's references): 20
 * minutes after the start the server stops as its operator would. */
static DWORD WINAPI watchdog(void *unused) {
    (void)unused;
    Sleep(1200000);
    OpcExeServerStop();
    return 0;
}

int main(void) {
    const WCHAR *set_flag = wcsstr(GetCommandLineW(), L" -set:");
    unsigned set = set_flag ? (unsigned)(set_flag[6] - L'0') % 10 : 0;
    CLSID clsid = da_server_class(set);
    OpcServerRegistration reg;
    OpcServerClass cls;
    OpcExeServerOptions options;
    HANDLE timer;
    HRESULT hr;
    /* What /RegServer writes (this EXE), as test_da_tables registers it. */
    memset(&reg, 0, sizeof reg);
    reg.struct_size = sizeof reg;
    reg.server_type = OPC_SERVER_TYPE_LOCAL;
    reg.clsid = clsid;
    reg.prog_id = L"Oop.DaServer.1";
    reg.user_type = L"opccomn DA tables test server";
    memset(&cls, 0, sizeof cls);
    cls.struct_size = sizeof cls;
    cls.clsid = &clsid;
    cls.create = create_server;
    cls.registration = &reg;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.classes = &cls;
    options.class_count = 1;
    options.first_client_timeout_ms = 120000; /* a server nobody connects to gives up after two minutes */
    options.release_timeout_ms = 30000;
    options.idle_linger_ms = 100;
    hr = CoInitializeEx(NULL, COINIT_MULTITHREADED);
    if (SUCCEEDED(hr))
        hr = wcsstr(GetCommandLineW(), L" -ps:widl") ? use_classic_proxy_stub() : use_opccomn_proxy_stub();
    timer = CreateThread(NULL, 0, watchdog, NULL, 0, NULL);
    if (timer) CloseHandle(timer);
    if (SUCCEEDED(hr)) hr = OpcExeServerRun(&options, NULL);
    if (FAILED(hr)) {
        fprintf(stderr, "da_server: start failed: 0x%08lX\n", (unsigned long)hr);
        return 1;
    }
    if (hr == S_FALSE) {
        fprintf(stderr, "da_server: exiting with objects a client never released\n");
        return 3;
    }
    return 0; /* without CoUninitialize (OpcExeServerRun) */
}
