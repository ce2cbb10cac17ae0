/* opccomn.dll's proxy/stub of the Historical Data Access 1.20 interfaces (the NDR tables
 * tools/gen-proxy.py makes from idl/opchda.idl, with the checks generated from the same IDL) across
 * processes, under the real COM runtime (Wine in CI): this client and the EXE server hda_server.c,
 * both with opccomn.dll's proxy/stub as theirs for the HDA interfaces (registered per process,
 * classic_oop.h). Every value crosses the wire and is checked on the other side: the server answers a
 * request it did not receive as sent with an error. A count beyond its bound never leaves the client.
 *
 * Covered: IOPCHDA_Server::GetHistorianStatus (FILETIME ** and two strings), GetItemAttributes
 * ([out, size_is(,*n), string] LPWSTR ** beside DWORD ** and VARTYPE **), GetItemHandles,
 * CreateBrowse (filters: attribute IDs, operator codes, VARIANTs; per-element results) and
 * IOPCHDA_Browser (GetEnum: an IEnumString out; ChangeBrowsePosition, GetItemID,
 * GetBranchPosition); IOPCHDA_SyncRead::ReadRaw ([in, out] OPCHDA_TIME with a string and without,
 * OPCHDA_ITEM arrays of VT_R8 and VT_BSTR values, FILETIMEs and qualities, an invalid handle's empty
 * item), ReadProcessed (a FILETIME by value, whose two halves the server checks), ReadAtTime (an
 * array of FILETIMEs in, each checked by the server), ReadModified (OPCHDA_MODIFIEDITEM: values,
 * qualities, timestamps, modification times, edit types, user names), ReadAttribute (the bound);
 * IOPCHDA_SyncAnnotations::QueryCapabilities, Read (OPCHDA_ANNOTATION, one with no values), Insert
 * (OPCHDA_ANNOTATION in, checked element by element); IOPCHDA_AsyncUpdate's Insert, Replace,
 * InsertReplace, DeleteAtTime and DeleteRaw, answered by OnUpdateComplete; IOPCHDA_AsyncAnnotations
 * Read and Insert, answered by OnReadAnnotations and OnInsertAnnotations;
 * IOPCHDA_AsyncRead::ReadRaw and ReadProcessed, each answered by IOPCHDA_DataCallback::OnReadComplete
 * through the server's connection point, AdviseRaw (a FILETIME by value) answered by OnDataChange,
 * and Cancel answered by OnCancelComplete; IOPCHDA_SyncUpdate's six methods (VARIANT values of
 * VT_R8, VT_BSTR and VT_I4, FILETIMEs, qualities, per-element results with success codes among
 * them); IOPCHDA_Playback::ReadRawWithUpdate (answered by OnPlayback: an array of pointers to
 * items) and ReadProcessedWithUpdate (two FILETIMEs by value each, which take four stack slots on
 * x86, checked by the server) and Cancel. */
#include "hda.h"

#include <olectl.h> /* CONNECT_E_* */

static WCHAR server_path[MAX_PATH];

/* ---- The client's callback: checks what OnReadComplete brings (the main thread waits meanwhile) ---- */

typedef struct Callback {
    IOPCHDA_DataCallback iface;
    LONG refs;
    HANDLE called; /* set by OnReadComplete, OnDataChange, OnCancelComplete */
    int calls;
    /* What the next call must be (CALL_*) and bring: the transaction (the cancel ID of
     * OnCancelComplete), the items, raw or by `aggregate`. */
    int expected;
    DWORD transaction, count, aggregate;
    /* What OnUpdateComplete and OnInsertAnnotations must bring: `count` client handles and results. */
    OPCHANDLE clients[HDA_UPDATES];
    HRESULT results[HDA_UPDATES];
} Callback;

/* Whether `a` holds item 0's annotations as the server reads them (hda.h). */
static int is_read_annotation(const OPCHDA_ANNOTATION *a) {
    DWORD n;
    int same = a->hClient == HDA_CLIENT_HANDLE(0) && a->dwNumValues == HDA_ANNOTATIONS && a->ftTimeStamps &&
               a->szAnnotation && a->ftAnnotationTime && a->szUser;
    for (n = 0; same && n < HDA_ANNOTATIONS; n++)
        same = same_filetime(a->ftTimeStamps[n], test_time(HDA_START_RESOLVED + n)) &&
               same_filetime(a->ftAnnotationTime[n], test_time(100 + n)) &&
               is_utf8(a->szAnnotation[n], HDA_ANNOTATION_TEXTS[n]) && is_utf8(a->szUser[n], HDA_ANNOTATION_USERS[n]);
    return same;
}

/* Whether `a` is item 1's (no annotations). */
static int is_no_annotation(const OPCHDA_ANNOTATION *a) {
    return a->hClient == HDA_CLIENT_HANDLE(1) && a->dwNumValues == 0 && !a->ftTimeStamps && !a->szAnnotation &&
           !a->ftAnnotationTime && !a->szUser;
}

/* Checks what OnUpdateComplete or OnInsertAnnotations brings against what `c` expects. */
static void check_results(Callback *c, int call, DWORD transaction, HRESULT status, DWORD count,
                          const OPCHANDLE *clients, const HRESULT *errors) {
    DWORD k;
    c->calls++;
    CHECK(c->expected == call);
    CHECK(transaction == c->transaction);
    CHECK_HR(status, S_OK);
    CHECK(count == c->count && clients && errors);
    for (k = 0; clients && errors && k < count && k < c->count; k++) {
        CHECK(clients[k] == c->clients[k]);
        CHECK_HR(errors[k], c->results[k]);
    }
    SetEvent(c->called);
}

/* Checks the items of an OnReadComplete or OnDataChange against what `c` expects. */
static void check_items(Callback *c, int call, DWORD transaction, HRESULT status, DWORD count, OPCHDA_ITEM *items,
                        HRESULT *errors) {
    DWORD k;
    c->calls++;
    CHECK(c->expected == call);
    CHECK(transaction == c->transaction);
    CHECK_HR(status, S_OK);
    CHECK(count == c->count && items && errors);
    for (k = 0; items && errors && k < count && k < c->count; k++) {
        CHECK(hda_is_item(&items[k], c->aggregate ? 0 : (int)k, c->aggregate));
        CHECK_HR(errors[k], S_OK);
    }
    SetEvent(c->called);
}

static HRESULT STDMETHODCALLTYPE cb_qi(IOPCHDA_DataCallback *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCHDA_DataCallback)) {
        *ppv = This;
        This->lpVtbl->AddRef(This);
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE cb_add_ref(IOPCHDA_DataCallback *This) {
    return (ULONG)InterlockedIncrement(&((Callback *)This)->refs);
}
static ULONG STDMETHODCALLTYPE cb_release(IOPCHDA_DataCallback *This) {
    return (ULONG)InterlockedDecrement(&((Callback *)This)->refs); /* static: nothing to free */
}
static HRESULT STDMETHODCALLTYPE cb_data_change(IOPCHDA_DataCallback *This, DWORD transaction, HRESULT status,
                                                DWORD count, OPCHDA_ITEM *items, HRESULT *errors) {
    check_items((Callback *)This, CALL_DATA_CHANGE, transaction, status, count, items, errors);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cb_read_complete(IOPCHDA_DataCallback *This, DWORD transaction, HRESULT status,
                                                  DWORD count, OPCHDA_ITEM *items, HRESULT *errors) {
    check_items((Callback *)This, CALL_READ_COMPLETE, transaction, status, count, items, errors);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cb_read_modified(IOPCHDA_DataCallback *This, DWORD transaction, HRESULT status,
                                                  DWORD count, OPCHDA_MODIFIEDITEM *items, HRESULT *errors) {
    (void)This, (void)transaction, (void)status, (void)count, (void)items, (void)errors;
    CHECK(0);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cb_read_attribute(IOPCHDA_DataCallback *This, DWORD transaction, HRESULT status,
                                                   OPCHANDLE client, DWORD count, OPCHDA_ATTRIBUTE *values,
                                                   HRESULT *errors) {
    (void)This, (void)transaction, (void)status, (void)client, (void)count, (void)values, (void)errors;
    CHECK(0);
    return S_OK;
}
/* An asynchronous read of both items' annotations (item 0's, and none of item 1's). */
static HRESULT STDMETHODCALLTYPE cb_read_annotations(IOPCHDA_DataCallback *This, DWORD transaction, HRESULT status,
                                                     DWORD count, OPCHDA_ANNOTATION *values, HRESULT *errors) {
    Callback *c = (Callback *)This;
    c->calls++;
    CHECK(c->expected == CALL_READ_ANNOTATIONS);
    CHECK(transaction == c->transaction);
    CHECK_HR(status, S_OK);
    CHECK(count == 2 && values && errors);
    if (count == 2 && values && errors) {
        CHECK(is_read_annotation(&values[0]));
        CHECK(is_no_annotation(&values[1]));
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], S_OK);
    }
    SetEvent(c->called);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cb_insert_annotations(IOPCHDA_DataCallback *This, DWORD transaction, HRESULT status,
                                                       DWORD count, OPCHANDLE *clients, HRESULT *errors) {
    check_results((Callback *)This, CALL_INSERT_ANNOTATIONS, transaction, status, count, clients, errors);
    return S_OK;
}
/* A raw playback's history: an array of pointers to items ([in, size_is(n)] OPCHDA_ITEM **). */
static HRESULT STDMETHODCALLTYPE cb_playback(IOPCHDA_DataCallback *This, DWORD transaction, HRESULT status,
                                             DWORD count, OPCHDA_ITEM **items, HRESULT *errors) {
    Callback *c = (Callback *)This;
    DWORD k;
    c->calls++;
    CHECK(c->expected == CALL_PLAYBACK);
    CHECK(transaction == c->transaction);
    CHECK_HR(status, S_OK);
    CHECK(count == c->count && items && errors);
    for (k = 0; items && errors && k < count && k < c->count; k++) {
        CHECK(items[k] && hda_is_item(items[k], (int)k, 0));
        CHECK_HR(errors[k], S_OK);
    }
    SetEvent(c->called);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cb_update_complete(IOPCHDA_DataCallback *This, DWORD transaction, HRESULT status,
                                                    DWORD count, OPCHANDLE *clients, HRESULT *errors) {
    check_results((Callback *)This, CALL_UPDATE_COMPLETE, transaction, status, count, clients, errors);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cb_cancel_complete(IOPCHDA_DataCallback *This, DWORD cancel) {
    Callback *c = (Callback *)This;
    c->calls++;
    CHECK(c->expected == CALL_CANCEL_COMPLETE && cancel == c->transaction);
    SetEvent(c->called);
    return S_OK;
}
static IOPCHDA_DataCallbackVtbl cb_vtbl = {cb_qi,          cb_add_ref,          cb_release,
                                           cb_data_change, cb_read_complete,    cb_read_modified,
                                           cb_read_attribute, cb_read_annotations, cb_insert_annotations,
                                           cb_playback,    cb_update_complete,  cb_cancel_complete};

/* Static, as the server's proxy may release it after the test's function returned. */
static Callback cb;

/* ---- Checks ---- */

/* The time range hda.h asks for: its string in task memory (an [in, out] structure's string the
 * proxy may replace). */
static void make_range(OPCHDA_TIME *start, OPCHDA_TIME *end) {
    memset(start, 0, sizeof *start);
    memset(end, 0, sizeof *end);
    start->bString = TRUE;
    start->szTime = task_utf8(HDA_START_TEXT);
    end->bString = FALSE;
    end->szTime = NULL;
    end->ftTime = test_time(HDA_END_ASKED);
}

/* Whether the range came back as the server resolved it (the strings as they were); frees them. */
static int range_resolved(OPCHDA_TIME *start, OPCHDA_TIME *end) {
    int ok = start->bString && is_utf8(start->szTime, HDA_START_TEXT) &&
             same_filetime(start->ftTime, test_time(HDA_START_RESOLVED)) && !end->bString && end->szTime == NULL &&
             same_filetime(end->ftTime, test_time(HDA_END_RESOLVED));
    CoTaskMemFree(start->szTime);
    CoTaskMemFree(end->szTime);
    start->szTime = end->szTime = NULL;
    return ok;
}

/* Both processes use opccomn.dll's proxy/stub (the server says so in its status). */
static void check_status(IOPCHDA_Server *server) {
    OPCHDA_SERVERSTATUS status = (OPCHDA_SERVERSTATUS)0;
    FILETIME *current = (FILETIME *)GARBAGE_PTR, *start = (FILETIME *)GARBAGE_PTR;
    WORD major = 0, minor = 0, build = 0;
    DWORD max_values = GARBAGE_U32;
    LPWSTR text = (LPWSTR)GARBAGE_PTR, vendor = (LPWSTR)GARBAGE_PTR;
    CHECK(proxy_stub_is_opccomn_for(HDA_IIDS, HDA_IID_COUNT));
    CHECK_HR(server->lpVtbl->GetHistorianStatus(server, &status, &current, &start, &major, &minor, &build, &max_values,
                                                &text, &vendor),
             S_OK);
    CHECK(status == OPCHDA_UP && major == 1 && minor == 20 && build == 42 && max_values == 1000);
    CHECK(current && current != GARBAGE_PTR && start && start != GARBAGE_PTR);
    if (current && current != GARBAGE_PTR) CHECK(same_filetime(*current, test_time(1)));
    if (start && start != GARBAGE_PTR) CHECK(same_filetime(*start, test_time(0)));
    CHECK(text != GARBAGE_PTR && is_utf8(text, HDA_STATUS_TEXT));
    CHECK(vendor != GARBAGE_PTR && is_utf8(vendor, HDA_VENDOR_INFO));
    if (current != GARBAGE_PTR) CoTaskMemFree(current);
    if (start != GARBAGE_PTR) CoTaskMemFree(start);
    if (text != GARBAGE_PTR) CoTaskMemFree(text);
    if (vendor != GARBAGE_PTR) CoTaskMemFree(vendor);
}

static void check_attributes(IOPCHDA_Server *server) {
    DWORD count = GARBAGE_U32, *ids = (DWORD *)GARBAGE_PTR, k;
    LPWSTR *names = (LPWSTR *)GARBAGE_PTR, *texts = (LPWSTR *)GARBAGE_PTR;
    VARTYPE *types = (VARTYPE *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->GetItemAttributes(server, &count, &ids, &names, &texts, &types), S_OK);
    CHECK(count == HDA_ATTRS && ids != GARBAGE_PTR && names != GARBAGE_PTR && texts != GARBAGE_PTR &&
          types != GARBAGE_PTR && ids && names && texts && types);
    if (count != HDA_ATTRS || !ids || ids == GARBAGE_PTR || !names || names == GARBAGE_PTR || !texts ||
        texts == GARBAGE_PTR || !types || types == GARBAGE_PTR)
        return;
    for (k = 0; k < count; k++) {
        CHECK(ids[k] == HDA_ATTR_IDS[k] && types[k] == HDA_ATTR_TYPES[k]);
        CHECK(is_utf8(names[k], HDA_ATTR_NAMES[k]) && is_utf8(texts[k], HDA_ATTR_TEXTS[k]));
        CoTaskMemFree(names[k]);
        CoTaskMemFree(texts[k]);
    }
    CoTaskMemFree(ids);
    CoTaskMemFree(names);
    CoTaskMemFree(texts);
    CoTaskMemFree(types);
}

static void check_handles(IOPCHDA_Server *server) {
    LPWSTR ids[3];
    OPCHANDLE clients[3] = {HDA_CLIENT_HANDLE(0), 777, HDA_CLIENT_HANDLE(1)};
    OPCHANDLE *servers = (OPCHANDLE *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    ids[0] = (LPWSTR)W(HDA_ITEM_IDS[0]);
    ids[1] = (LPWSTR)W("Plant.Nowhere");
    ids[2] = (LPWSTR)W(HDA_ITEM_IDS[1]);
    CHECK_HR(server->lpVtbl->GetItemHandles(server, 3, ids, clients, &servers, &errors), S_FALSE);
    CHECK(servers && servers != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (!servers || servers == GARBAGE_PTR || !errors || errors == GARBAGE_PTR) return;
    CHECK(servers[0] == HDA_SERVER_HANDLE(0) && servers[1] == 0 && servers[2] == HDA_SERVER_HANDLE(1));
    CHECK_HR(errors[0], S_OK);
    CHECK_HR(errors[1], HDA_E_UNKNOWNITEMID);
    CHECK_HR(errors[2], S_OK);
    CoTaskMemFree(servers);
    CoTaskMemFree(errors);
}

static void free_items(OPCHDA_ITEM *items, DWORD count) {
    DWORD k;
    for (k = 0; k < count; k++) hda_free_item(&items[k]);
    CoTaskMemFree(items);
}

static void check_read_raw(IOPCHDA_SyncRead *sync) {
    OPCHANDLE handles[3] = {HDA_SERVER_HANDLE(0), HDA_SERVER_HANDLE(1), 0x999};
    OPCHDA_TIME start, end;
    OPCHDA_ITEM *items = (OPCHDA_ITEM *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    make_range(&start, &end);
    CHECK_HR(sync->lpVtbl->ReadRaw(sync, &start, &end, HDA_RAW_VALUES, FALSE, 3, handles, &items, &errors), S_FALSE);
    CHECK(range_resolved(&start, &end));
    CHECK(items && items != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (items && items != GARBAGE_PTR && errors && errors != GARBAGE_PTR) {
        CHECK(hda_is_item(&items[0], 0, 0));
        CHECK(hda_is_item(&items[1], 1, 0));
        CHECK(items[2].hClient == 0 && items[2].dwCount == 0 && !items[2].pftTimeStamps && !items[2].pdwQualities &&
              !items[2].pvDataValues);
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], S_OK);
        CHECK_HR(errors[2], HDA_E_INVALIDHANDLE);
        free_items(items, 3);
        CoTaskMemFree(errors);
    }
    /* Not as the server expects (a value more): refused, nothing comes back. */
    make_range(&start, &end);
    items = (OPCHDA_ITEM *)GARBAGE_PTR;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(sync->lpVtbl->ReadRaw(sync, &start, &end, HDA_RAW_VALUES + 1, FALSE, 2, handles, &items, &errors),
             E_INVALIDARG);
    CHECK(items == NULL && errors == NULL);
    range_resolved(&start, &end); /* frees */
}

static void check_read_processed(IOPCHDA_SyncRead *sync) {
    OPCHANDLE handles[2] = {HDA_SERVER_HANDLE(0), HDA_SERVER_HANDLE(0)};
    DWORD aggregates[2] = {OPCHDA_AVERAGE, OPCHDA_MAXIMUM};
    OPCHDA_TIME start, end;
    OPCHDA_ITEM *items = (OPCHDA_ITEM *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    FILETIME other;
    make_range(&start, &end);
    CHECK_HR(sync->lpVtbl->ReadProcessed(sync, &start, &end, hda_interval(), 2, handles, aggregates, &items, &errors),
             S_OK);
    CHECK(range_resolved(&start, &end));
    CHECK(items && items != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (items && items != GARBAGE_PTR && errors && errors != GARBAGE_PTR) {
        CHECK(hda_is_item(&items[0], 0, OPCHDA_AVERAGE));
        CHECK(hda_is_item(&items[1], 0, OPCHDA_MAXIMUM));
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], S_OK);
        free_items(items, 2);
        CoTaskMemFree(errors);
    }
    /* Another interval (its high half one more): the server sees it and refuses. */
    other = hda_interval();
    other.dwHighDateTime++;
    make_range(&start, &end);
    items = (OPCHDA_ITEM *)GARBAGE_PTR;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(sync->lpVtbl->ReadProcessed(sync, &start, &end, other, 2, handles, aggregates, &items, &errors),
             E_INVALIDARG);
    CHECK(items == NULL && errors == NULL);
    range_resolved(&start, &end); /* frees */
}

/* ReadAtTime: the client's times (an array of FILETIMEs, each checked by the server), both items and
 * an invalid handle's empty item; one time not as the server expects is refused. */
static void check_read_at_time(IOPCHDA_SyncRead *sync) {
    OPCHANDLE handles[3] = {HDA_SERVER_HANDLE(1), HDA_INVALID_HANDLE, HDA_SERVER_HANDLE(0)};
    FILETIME times[HDA_AT_TIMES];
    OPCHDA_ITEM *items = (OPCHDA_ITEM *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    DWORD k;
    for (k = 0; k < HDA_AT_TIMES; k++) times[k] = hda_at_time(k);
    CHECK_HR(sync->lpVtbl->ReadAtTime(sync, HDA_AT_TIMES, times, 3, handles, &items, &errors), S_FALSE);
    CHECK(items && items != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (items && items != GARBAGE_PTR && errors && errors != GARBAGE_PTR) {
        CHECK(hda_is_at_time(&items[0], 1));
        CHECK(items[1].hClient == 0 && items[1].dwCount == 0 && !items[1].pftTimeStamps && !items[1].pdwQualities &&
              !items[1].pvDataValues);
        CHECK(hda_is_at_time(&items[2], 0));
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], HDA_E_INVALIDHANDLE);
        CHECK_HR(errors[2], S_OK);
        free_items(items, 3);
        CoTaskMemFree(errors);
    }
    /* The last time's low half one more: refused, nothing comes back. */
    times[HDA_AT_TIMES - 1].dwLowDateTime++;
    items = (OPCHDA_ITEM *)GARBAGE_PTR;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(sync->lpVtbl->ReadAtTime(sync, HDA_AT_TIMES, times, 2, handles, &items, &errors), E_INVALIDARG);
    CHECK(items == NULL && errors == NULL);
}

/* ReadModified: the time range [in, out], OPCHDA_MODIFIEDITEM arrays (values, qualities, timestamps,
 * modification times, edit types, user names, an empty one among them) of both items, an invalid
 * handle's empty item; another number of values is refused. */
static void check_read_modified(IOPCHDA_SyncRead *sync) {
    OPCHANDLE handles[3] = {HDA_SERVER_HANDLE(0), HDA_SERVER_HANDLE(1), HDA_INVALID_HANDLE};
    OPCHDA_TIME start, end;
    OPCHDA_MODIFIEDITEM *items = (OPCHDA_MODIFIEDITEM *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    DWORD k;
    make_range(&start, &end);
    CHECK_HR(sync->lpVtbl->ReadModified(sync, &start, &end, HDA_MODIFIED_VALUES, 3, handles, &items, &errors),
             S_FALSE);
    CHECK(range_resolved(&start, &end));
    CHECK(items && items != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (items && items != GARBAGE_PTR && errors && errors != GARBAGE_PTR) {
        CHECK(hda_is_modified(&items[0], 0));
        CHECK(hda_is_modified(&items[1], 1));
        CHECK(items[2].hClient == 0 && items[2].dwCount == 0 && !items[2].pftTimeStamps && !items[2].pdwQualities &&
              !items[2].pvDataValues && !items[2].pftModificationTime && !items[2].pEditType && !items[2].szUser);
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], S_OK);
        CHECK_HR(errors[2], HDA_E_INVALIDHANDLE);
        for (k = 0; k < 3; k++) hda_free_modified(&items[k]);
        CoTaskMemFree(items);
        CoTaskMemFree(errors);
    }
    make_range(&start, &end);
    items = (OPCHDA_MODIFIEDITEM *)GARBAGE_PTR;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(sync->lpVtbl->ReadModified(sync, &start, &end, HDA_MODIFIED_VALUES + 1, 2, handles, &items, &errors),
             E_INVALIDARG);
    CHECK(items == NULL && errors == NULL);
    range_resolved(&start, &end); /* frees */
}

/* A count beyond its bound (65,537 attribute IDs, idl/ndr-bounds.txt) is refused by this client's
 * proxy before it is sent, with the code MIDL's [range] gives; at the bound the request leaves (the
 * server does not implement ReadAttribute). */
static void check_bound(IOPCHDA_SyncRead *sync) {
    OPCHDA_TIME start, end;
    OPCHDA_ATTRIBUTE *values = (OPCHDA_ATTRIBUTE *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    DWORD *ids = (DWORD *)calloc(65537, sizeof(DWORD));
    if (!ids) {
        CHECK(0);
        return;
    }
    make_range(&start, &end);
    CHECK_HR(sync->lpVtbl->ReadAttribute(sync, &start, &end, HDA_SERVER_HANDLE(0), 65537, ids, &values, &errors),
             HRESULT_FROM_WIN32(RPC_S_INVALID_BOUND));
    CHECK(values == NULL && errors == NULL);
    values = (OPCHDA_ATTRIBUTE *)GARBAGE_PTR;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(sync->lpVtbl->ReadAttribute(sync, &start, &end, HDA_SERVER_HANDLE(0), 65536, ids, &values, &errors),
             E_NOTIMPL);
    CHECK(values == NULL && errors == NULL);
    CoTaskMemFree(start.szTime);
    CoTaskMemFree(end.szTime);
    free(ids);
}

/* IOPCHDA_SyncUpdate: the capabilities; Insert, Replace and InsertReplace of HDA_UPDATES values
 * (VARIANTs, FILETIMEs, qualities), each element answered by the server as it arrived; DeleteRaw
 * (the time range [in, out]) and DeleteAtTime (FILETIMEs). */
static void check_update(IOPCHDA_Server *server) {
    IOPCHDA_SyncUpdate *upd = NULL;
    OPCHDA_UPDATECAPABILITIES caps = (OPCHDA_UPDATECAPABILITIES)0;
    OPCHANDLE handles[HDA_UPDATES];
    FILETIME times[HDA_UPDATES];
    VARIANT values[HDA_UPDATES];
    DWORD qualities[HDA_UPDATES], k;
    HRESULT *errors, hr;
    OPCHDA_TIME start, end;
    int method;
    CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCHDA_SyncUpdate, (void **)&upd), S_OK);
    if (!upd) return;
    CHECK_HR(upd->lpVtbl->QueryCapabilities(upd, &caps), S_OK);
    CHECK(caps == HDA_UPDATE_CAPS);
    for (method = 0; method < 4; method++) {
        for (k = 0; k < HDA_UPDATES; k++) {
            HdaUpdate u = hda_update(method, k);
            handles[k] = u.handle;
            times[k] = u.time;
            values[k] = u.value; /* cleared below */
            qualities[k] = u.quality;
        }
        errors = (HRESULT *)GARBAGE_PTR;
        if (method == 0) hr = upd->lpVtbl->Insert(upd, HDA_UPDATES, handles, times, values, qualities, &errors);
        else if (method == 1) hr = upd->lpVtbl->Replace(upd, HDA_UPDATES, handles, times, values, qualities, &errors);
        else if (method == 2)
            hr = upd->lpVtbl->InsertReplace(upd, HDA_UPDATES, handles, times, values, qualities, &errors);
        else hr = upd->lpVtbl->DeleteAtTime(upd, HDA_UPDATES, handles, times, &errors);
        CHECK_HR(hr, S_FALSE);
        if (errors && errors != GARBAGE_PTR) {
            for (k = 0; k < HDA_UPDATES; k++) CHECK_HR(errors[k], hda_update(method, k).result);
            CoTaskMemFree(errors);
        } else {
            CHECK(0);
        }
        for (k = 0; k < HDA_UPDATES; k++) VariantClear(&values[k]);
    }
    /* Replace with Insert's values: each element not as the server expects. */
    for (k = 0; k < HDA_UPDATES; k++) {
        HdaUpdate u = hda_update(0, k);
        handles[k] = u.handle;
        times[k] = u.time;
        values[k] = u.value;
        qualities[k] = u.quality;
    }
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(upd->lpVtbl->Replace(upd, HDA_UPDATES, handles, times, values, qualities, &errors), S_FALSE);
    if (errors && errors != GARBAGE_PTR) {
        for (k = 0; k < HDA_UPDATES; k++) CHECK_HR(errors[k], E_INVALIDARG);
        CoTaskMemFree(errors);
    } else {
        CHECK(0);
    }
    for (k = 0; k < HDA_UPDATES; k++) VariantClear(&values[k]);
    /* DeleteRaw over the range: both items, an invalid handle. */
    handles[0] = HDA_SERVER_HANDLE(0);
    handles[1] = HDA_SERVER_HANDLE(1);
    handles[2] = HDA_INVALID_HANDLE;
    make_range(&start, &end);
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(upd->lpVtbl->DeleteRaw(upd, &start, &end, 3, handles, &errors), S_FALSE);
    CHECK(range_resolved(&start, &end));
    CHECK_RESULTS(errors, S_OK, S_OK, HDA_E_INVALIDHANDLE);
    upd->lpVtbl->Release(upd);
}

/* IOPCHDA_Playback: ReadRawWithUpdate (two FILETIMEs by value after a DWORD), its history through
 * OnPlayback, and ReadProcessedWithUpdate (two FILETIMEs by value with a DWORD between them), each
 * checked by the server and given a cancel ID; the same with the two FILETIMEs swapped is refused;
 * Cancel of each. The callback is advised. */
static void check_playback(IOPCHDA_Server *server) {
    IOPCHDA_Playback *play = NULL;
    OPCHANDLE handles[2] = {HDA_SERVER_HANDLE(0), HDA_SERVER_HANDLE(1)};
    DWORD aggregates[2] = {OPCHDA_AVERAGE, OPCHDA_MAXIMUM}, cancel;
    OPCHDA_TIME start, end;
    HRESULT *errors;
    CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCHDA_Playback, (void **)&play), S_OK);
    if (!play) return;
    make_range(&start, &end);
    cancel = GARBAGE_U32;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(play->lpVtbl->ReadRawWithUpdate(play, 51, &start, &end, HDA_RAW_VALUES, hda_update_interval(),
                                             hda_duration(), 2, handles, &cancel, &errors),
             E_INVALIDARG);
    CHECK(cancel == 0 && errors == NULL);
    range_resolved(&start, &end); /* frees */
    cb.expected = CALL_PLAYBACK;
    cb.transaction = 51;
    cb.count = 2;
    cb.aggregate = 0;
    make_range(&start, &end);
    CHECK_HR(play->lpVtbl->ReadRawWithUpdate(play, 51, &start, &end, HDA_RAW_VALUES, hda_duration(),
                                             hda_update_interval(), 2, handles, &cancel, &errors),
             S_OK);
    CHECK(cancel == 52 && range_resolved(&start, &end));
    CHECK_RESULTS(errors, S_OK, S_OK);
    CHECK(WaitForSingleObject(cb.called, 60000) == WAIT_OBJECT_0);
    CHECK(cb.calls == 5);
    make_range(&start, &end);
    cancel = GARBAGE_U32;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(play->lpVtbl->ReadProcessedWithUpdate(play, 61, &start, &end, hda_update_interval(), HDA_INTERVALS,
                                                   hda_interval(), 2, handles, aggregates, &cancel, &errors),
             E_INVALIDARG);
    CHECK(cancel == 0 && errors == NULL);
    range_resolved(&start, &end); /* frees */
    make_range(&start, &end);
    CHECK_HR(play->lpVtbl->ReadProcessedWithUpdate(play, 61, &start, &end, hda_interval(), HDA_INTERVALS,
                                                   hda_update_interval(), 2, handles, aggregates, &cancel, &errors),
             S_OK);
    CHECK(cancel == 62 && range_resolved(&start, &end));
    CHECK_RESULTS(errors, S_OK, S_OK);
    CHECK_HR(play->lpVtbl->Cancel(play, 52), S_OK);
    CHECK_HR(play->lpVtbl->Cancel(play, 52), E_INVALIDARG);
    CHECK_HR(play->lpVtbl->Cancel(play, 62), S_OK);
    play->lpVtbl->Release(play);
}

/* IOPCHDA_SyncAnnotations::Insert: HDA_UPDATES elements of OPCHDA_ANNOTATION (hda.h: two annotations,
 * one, one of an invalid handle) with a timestamp each, each element answered by the server as it
 * arrived; then the same with one annotation's text changed, refused for that element alone. */
static void check_insert_annotations(IOPCHDA_SyncAnnotations *ann) {
    OPCHANDLE handles[HDA_UPDATES];
    FILETIME times[HDA_UPDATES];
    OPCHDA_ANNOTATION values[HDA_UPDATES];
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    DWORD k;
    for (k = 0; k < HDA_UPDATES; k++) {
        handles[k] = k < 2 ? HDA_SERVER_HANDLE(k) : HDA_INVALID_HANDLE;
        times[k] = hda_insert_time(k);
        hda_fill_insert_annotation(k, &values[k]);
    }
    CHECK_HR(ann->lpVtbl->Insert(ann, HDA_UPDATES, handles, times, values, &errors), S_FALSE);
    CHECK_RESULTS(errors, S_OK, S_OK, HDA_E_INVALIDHANDLE);
    /* The second annotation of the first element one letter different: that element is refused. */
    if (values[0].dwNumValues == 2 && values[0].szAnnotation[1]) values[0].szAnnotation[1][0]++;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(ann->lpVtbl->Insert(ann, HDA_UPDATES, handles, times, values, &errors), S_FALSE);
    CHECK_RESULTS(errors, E_INVALIDARG, S_OK, HDA_E_INVALIDHANDLE);
    for (k = 0; k < HDA_UPDATES; k++) hda_free_annotation(&values[k]);
}

static void check_annotations(IOPCHDA_Server *server) {
    IOPCHDA_SyncAnnotations *ann = NULL;
    OPCHDA_ANNOTATIONCAPABILITIES caps = (OPCHDA_ANNOTATIONCAPABILITIES)0;
    OPCHANDLE handles[2] = {HDA_SERVER_HANDLE(0), HDA_SERVER_HANDLE(1)};
    OPCHDA_TIME start, end;
    OPCHDA_ANNOTATION *values = (OPCHDA_ANNOTATION *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCHDA_SyncAnnotations, (void **)&ann), S_OK);
    if (!ann) return;
    CHECK_HR(ann->lpVtbl->QueryCapabilities(ann, &caps), S_OK);
    CHECK(caps == (OPCHDA_READANNOTATIONCAP | OPCHDA_INSERTANNOTATIONCAP));
    make_range(&start, &end);
    CHECK_HR(ann->lpVtbl->Read(ann, &start, &end, 2, handles, &values, &errors), S_OK);
    CHECK(range_resolved(&start, &end));
    CHECK(values && values != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (values && values != GARBAGE_PTR && errors && errors != GARBAGE_PTR) {
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], S_OK);
        CHECK(is_read_annotation(&values[0]));
        CHECK(is_no_annotation(&values[1]));
        hda_free_annotation(&values[0]);
        hda_free_annotation(&values[1]);
        CoTaskMemFree(values);
        CoTaskMemFree(errors);
    }
    check_insert_annotations(ann);
    ann->lpVtbl->Release(ann);
}

/* AdviseRaw: its start time [in, out] (resolved by the server), the update interval a FILETIME by
 * value; the server's OnDataChange brings the items' history; Cancel with the advise's cancel ID,
 * answered by OnCancelComplete. Another interval, or another cancel ID, is refused. */
static void check_advise(IOPCHDA_AsyncRead *async) {
    OPCHANDLE handles[2] = {HDA_SERVER_HANDLE(0), HDA_SERVER_HANDLE(1)};
    OPCHDA_TIME start, end;
    FILETIME other = hda_update_interval();
    DWORD cancel = GARBAGE_U32;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    other.dwLowDateTime ^= 1;
    make_range(&start, &end);
    CHECK_HR(async->lpVtbl->AdviseRaw(async, 71, &start, other, 2, handles, &cancel, &errors), E_INVALIDARG);
    CHECK(cancel == 0 && errors == NULL);
    cb.expected = CALL_DATA_CHANGE;
    cb.transaction = 71;
    cb.count = 2;
    cb.aggregate = 0;
    errors = (HRESULT *)GARBAGE_PTR;
    cancel = GARBAGE_U32;
    CHECK_HR(async->lpVtbl->AdviseRaw(async, 71, &start, hda_update_interval(), 2, handles, &cancel, &errors), S_OK);
    CHECK(cancel == 72);
    CHECK(start.bString && is_utf8(start.szTime, HDA_START_TEXT) &&
          same_filetime(start.ftTime, test_time(HDA_START_RESOLVED)));
    CHECK_RESULTS(errors, S_OK, S_OK);
    range_resolved(&start, &end); /* frees */
    CHECK(WaitForSingleObject(cb.called, 60000) == WAIT_OBJECT_0);
    CHECK(cb.calls == 3);
    cb.expected = CALL_CANCEL_COMPLETE;
    cb.transaction = 72;
    CHECK_HR(async->lpVtbl->Cancel(async, 71), E_INVALIDARG);
    CHECK_HR(async->lpVtbl->Cancel(async, 72), S_OK);
    CHECK(WaitForSingleObject(cb.called, 60000) == WAIT_OBJECT_0);
    CHECK(cb.calls == 4);
    CHECK_HR(async->lpVtbl->Cancel(async, 72), E_INVALIDARG); /* cancelled already */
}

/* Waits for the callback expected, the calls' count then one more than `calls` (the count before the
 * request). */
static void wait_callback(int calls) {
    CHECK(WaitForSingleObject(cb.called, 60000) == WAIT_OBJECT_0); /* 60 s only bound a broken run */
    CHECK(cb.calls == calls + 1);
}

/* What OnUpdateComplete or OnInsertAnnotations must bring next: the two items' client handles in the
 * order given and their results. */
static void expect_results(int call, DWORD transaction, OPCHANDLE first, HRESULT r0, OPCHANDLE second, HRESULT r1) {
    cb.expected = call;
    cb.transaction = transaction;
    cb.count = 2;
    cb.clients[0] = first;
    cb.results[0] = r0;
    cb.clients[1] = second;
    cb.results[1] = r1;
}

/* IOPCHDA_AsyncUpdate: Insert, Replace, InsertReplace and DeleteAtTime with the values of the
 * synchronous ones (hda.h), the invalid handle's error in the reply and the two items' results
 * (S_INSERTED, S_REPLACED among them) in OnUpdateComplete; Replace with Insert's values is refused
 * by the server; DeleteRaw (the time range [in, out]) of the items and an invalid handle between
 * them. The callback is advised. */
static void check_async_update(IOPCHDA_Server *server) {
    IOPCHDA_AsyncUpdate *upd = NULL;
    OPCHDA_UPDATECAPABILITIES caps = (OPCHDA_UPDATECAPABILITIES)0;
    OPCHANDLE handles[HDA_UPDATES];
    FILETIME times[HDA_UPDATES];
    VARIANT values[HDA_UPDATES];
    DWORD qualities[HDA_UPDATES], k, cancel, transaction;
    HRESULT *errors, hr, results[HDA_UPDATES];
    int calls;
    OPCHDA_TIME start, end;
    int method;
    CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCHDA_AsyncUpdate, (void **)&upd), S_OK);
    if (!upd) return;
    CHECK_HR(upd->lpVtbl->QueryCapabilities(upd, &caps), S_OK);
    CHECK(caps == HDA_UPDATE_CAPS);
    for (method = 0; method < 5; method++) {
        int values_of = method == 4 ? 0 : method; /* 4: Replace with Insert's values */
        for (k = 0; k < HDA_UPDATES; k++) {
            HdaUpdate u = hda_update(values_of, k);
            handles[k] = u.handle;
            times[k] = u.time;
            values[k] = u.value; /* cleared below */
            qualities[k] = u.quality;
            results[k] = u.result;
        }
        transaction = 80 + 10 * (DWORD)method;
        expect_results(CALL_UPDATE_COMPLETE, transaction, HDA_CLIENT_HANDLE(0), results[0], HDA_CLIENT_HANDLE(1),
                       results[1]);
        calls = cb.calls;
        cancel = GARBAGE_U32;
        errors = (HRESULT *)GARBAGE_PTR;
        if (method == 0)
            hr = upd->lpVtbl->Insert(upd, transaction, HDA_UPDATES, handles, times, values, qualities, &cancel,
                                     &errors);
        else if (method == 1 || method == 4)
            hr = upd->lpVtbl->Replace(upd, transaction, HDA_UPDATES, handles, times, values, qualities, &cancel,
                                      &errors);
        else if (method == 2)
            hr = upd->lpVtbl->InsertReplace(upd, transaction, HDA_UPDATES, handles, times, values, qualities, &cancel,
                                            &errors);
        else hr = upd->lpVtbl->DeleteAtTime(upd, transaction, HDA_UPDATES, handles, times, &cancel, &errors);
        for (k = 0; k < HDA_UPDATES; k++) VariantClear(&values[k]);
        if (method == 4) {
            CHECK_HR(hr, E_INVALIDARG);
            CHECK(cancel == 0 && errors == NULL);
            continue;
        }
        CHECK_HR(hr, S_FALSE);
        CHECK(cancel == transaction + 1);
        CHECK_RESULTS(errors, S_OK, S_OK, HDA_E_INVALIDHANDLE);
        wait_callback(calls);
    }
    /* DeleteRaw: item 1, an invalid handle, item 0; OnUpdateComplete brings the items in that order. */
    handles[0] = HDA_SERVER_HANDLE(1);
    handles[1] = HDA_INVALID_HANDLE;
    handles[2] = HDA_SERVER_HANDLE(0);
    expect_results(CALL_UPDATE_COMPLETE, 131, HDA_CLIENT_HANDLE(1), S_OK, HDA_CLIENT_HANDLE(0), S_OK);
    make_range(&start, &end);
    calls = cb.calls;
    cancel = GARBAGE_U32;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(upd->lpVtbl->DeleteRaw(upd, 131, &start, &end, 3, handles, &cancel, &errors), S_FALSE);
    CHECK(cancel == 132 && range_resolved(&start, &end));
    CHECK_RESULTS(errors, S_OK, HDA_E_INVALIDHANDLE, S_OK);
    wait_callback(calls);
    upd->lpVtbl->Release(upd);
}

/* IOPCHDA_AsyncAnnotations: Read (the time range [in, out]) answered by OnReadAnnotations with the
 * annotations the synchronous Read gives; Insert of hda.h's annotations (OPCHDA_ANNOTATION in), the
 * invalid handle's error in the reply and the two items' results in OnInsertAnnotations; the same
 * with one text changed is refused by the server. The callback is advised. */
static void check_async_annotations(IOPCHDA_Server *server) {
    IOPCHDA_AsyncAnnotations *ann = NULL;
    OPCHDA_ANNOTATIONCAPABILITIES caps = (OPCHDA_ANNOTATIONCAPABILITIES)0;
    OPCHANDLE handles[HDA_UPDATES];
    FILETIME times[HDA_UPDATES];
    OPCHDA_ANNOTATION values[HDA_UPDATES];
    OPCHDA_TIME start, end;
    DWORD cancel = GARBAGE_U32, k;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    int calls;
    CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCHDA_AsyncAnnotations, (void **)&ann), S_OK);
    if (!ann) return;
    CHECK_HR(ann->lpVtbl->QueryCapabilities(ann, &caps), S_OK);
    CHECK(caps == (OPCHDA_READANNOTATIONCAP | OPCHDA_INSERTANNOTATIONCAP));
    handles[0] = HDA_SERVER_HANDLE(0);
    handles[1] = HDA_SERVER_HANDLE(1);
    cb.expected = CALL_READ_ANNOTATIONS;
    cb.transaction = 141;
    make_range(&start, &end);
    calls = cb.calls;
    CHECK_HR(ann->lpVtbl->Read(ann, 141, &start, &end, 2, handles, &cancel, &errors), S_OK);
    CHECK(cancel == 142 && range_resolved(&start, &end));
    CHECK_RESULTS(errors, S_OK, S_OK);
    wait_callback(calls);
    for (k = 0; k < HDA_UPDATES; k++) {
        handles[k] = k < 2 ? HDA_SERVER_HANDLE(k) : HDA_INVALID_HANDLE;
        times[k] = hda_insert_time(k);
        hda_fill_insert_annotation(k, &values[k]);
    }
    expect_results(CALL_INSERT_ANNOTATIONS, 151, HDA_CLIENT_HANDLE(0), S_OK, HDA_CLIENT_HANDLE(1), S_OK);
    calls = cb.calls;
    cancel = GARBAGE_U32;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(ann->lpVtbl->Insert(ann, 151, HDA_UPDATES, handles, times, values, &cancel, &errors), S_FALSE);
    CHECK(cancel == 152);
    CHECK_RESULTS(errors, S_OK, S_OK, HDA_E_INVALIDHANDLE);
    wait_callback(calls);
    /* The user of the second element one letter different: refused, nothing comes back. */
    if (values[1].dwNumValues == 1 && values[1].szUser[0]) values[1].szUser[0][0]++;
    cancel = GARBAGE_U32;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(ann->lpVtbl->Insert(ann, 161, HDA_UPDATES, handles, times, values, &cancel, &errors), E_INVALIDARG);
    CHECK(cancel == 0 && errors == NULL);
    for (k = 0; k < HDA_UPDATES; k++) hda_free_annotation(&values[k]);
    ann->lpVtbl->Release(ann);
}

static void check_async(IOPCHDA_Server *server) {
    IConnectionPointContainer *cpc = NULL;
    IConnectionPoint *cp = NULL;
    IOPCHDA_AsyncRead *async = NULL;
    OPCHANDLE handles[2] = {HDA_SERVER_HANDLE(0), HDA_SERVER_HANDLE(1)};
    DWORD aggregate = OPCHDA_MAXIMUM, cookie = GARBAGE_U32, cancel = GARBAGE_U32;
    OPCHDA_TIME start, end;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    memset(&cb, 0, sizeof cb);
    cb.iface.lpVtbl = &cb_vtbl;
    cb.refs = 1;
    cb.called = CreateEventW(NULL, FALSE, FALSE, NULL);
    CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IConnectionPointContainer, (void **)&cpc), S_OK);
    CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCHDA_AsyncRead, (void **)&async), S_OK);
    if (!cpc || !async) return;
    /* Without a callback the read is refused. */
    make_range(&start, &end);
    CHECK_HR(async->lpVtbl->ReadRaw(async, 30, &start, &end, HDA_RAW_VALUES, FALSE, 2, handles, &cancel, &errors),
             CONNECT_E_NOCONNECTION);
    CHECK(cancel == 0 && errors == NULL);
    range_resolved(&start, &end); /* frees */
    CHECK_HR(cpc->lpVtbl->FindConnectionPoint(cpc, &IID_IOPCHDA_DataCallback, &cp), S_OK);
    if (cp) {
        CHECK_HR(cp->lpVtbl->Advise(cp, (IUnknown *)&cb.iface, &cookie), S_OK);
        CHECK(cookie == 1);
        /* A raw read of both items. */
        cb.expected = CALL_READ_COMPLETE;
        cb.transaction = 31;
        cb.count = 2;
        cb.aggregate = 0;
        make_range(&start, &end);
        errors = (HRESULT *)GARBAGE_PTR;
        CHECK_HR(async->lpVtbl->ReadRaw(async, 31, &start, &end, HDA_RAW_VALUES, FALSE, 2, handles, &cancel, &errors),
                 S_OK);
        CHECK(cancel == 32 && range_resolved(&start, &end));
        CHECK_RESULTS(errors, S_OK, S_OK);
        /* The server's thread calls back; 60 s only bound a broken run. */
        CHECK(WaitForSingleObject(cb.called, 60000) == WAIT_OBJECT_0);
        CHECK(cb.calls == 1);
        /* A processed read of the first item (the interval by value again). */
        cb.expected = CALL_READ_COMPLETE;
        cb.transaction = 41;
        cb.count = 1;
        cb.aggregate = OPCHDA_MAXIMUM;
        make_range(&start, &end);
        errors = (HRESULT *)GARBAGE_PTR;
        CHECK_HR(async->lpVtbl->ReadProcessed(async, 41, &start, &end, hda_interval(), 1, handles, &aggregate, &cancel,
                                              &errors),
                 S_OK);
        CHECK(cancel == 42 && range_resolved(&start, &end));
        CHECK_RESULTS(errors, S_OK);
        CHECK(WaitForSingleObject(cb.called, 60000) == WAIT_OBJECT_0);
        CHECK(cb.calls == 2);
        check_advise(async);
        check_playback(server);
        check_async_update(server);
        check_async_annotations(server);
        CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie), S_OK);
        CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie), CONNECT_E_NOCONNECTION);
        cp->lpVtbl->Release(cp);
    }
    async->lpVtbl->Release(async);
    cpc->lpVtbl->Release(cpc);
}

/* Whether `e` enumerates exactly the UTF-8 texts `want[0..count)` (count at most 2) and then ends;
 * releases it. */
static int enumerates(IEnumString *e, const char *const *want, ULONG count) {
    LPOLESTR got[3];
    ULONG fetched = GARBAGE_U32, k;
    HRESULT hr;
    int same;
    if (!e || e == GARBAGE_PTR) return 0;
    memset(got, 0, sizeof got);
    hr = e->lpVtbl->Next(e, 3, got, &fetched);
    same = hr == S_FALSE && fetched == count;
    for (k = 0; k < fetched && k < 3; k++) {
        same &= k < count && is_utf8(got[k], want[k]);
        CoTaskMemFree(got[k]);
    }
    e->lpVtbl->Release(e);
    return same;
}

/* Whether the browser's position is `want` (UTF-8). */
static int positioned(IOPCHDA_Browser *b, const char *want) {
    LPWSTR position = (LPWSTR)GARBAGE_PTR;
    int same = b->lpVtbl->GetBranchPosition(b, &position) == S_OK && position != GARBAGE_PTR &&
               is_utf8(position, want);
    if (position != GARBAGE_PTR) CoTaskMemFree(position);
    return same;
}

/* IOPCHDA_Server::CreateBrowse with filters (attribute IDs, operator codes, VARIANTs: hda.h), each
 * answered by the server as it arrived, an unknown attribute among them; IOPCHDA_Browser: GetEnum
 * (an IEnumString of branches, leaves and item IDs, as the filters let them through),
 * ChangeBrowsePosition down, up and direct, GetItemID, GetBranchPosition, and what the server
 * refuses. A filter not as the server expects is refused for that element alone. */
static void check_browser(IOPCHDA_Server *server) {
    static const char *const top[1] = {HDA_TOP_BRANCH};
    static const char *const branch[1] = {HDA_BRANCH};
    DWORD ids[HDA_FILTERS], k;
    OPCHDA_OPERATORCODES ops[HDA_FILTERS];
    VARIANT filters[HDA_FILTERS];
    IOPCHDA_Browser *b = (IOPCHDA_Browser *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    IEnumString *e;
    LPWSTR id;
    for (k = 0; k < HDA_FILTERS; k++) {
        ids[k] = HDA_FILTER_IDS[k];
        ops[k] = HDA_FILTER_OPS[k];
        filters[k] = hda_filter(k);
    }
    /* The description's operator another: that element refused, the others as before. */
    ops[1] = OPCHDA_EQUAL;
    CHECK_HR(server->lpVtbl->CreateBrowse(server, HDA_FILTERS, ids, ops, filters, &b, &errors), S_FALSE);
    CHECK(b && b != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (errors && errors != GARBAGE_PTR) {
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], E_INVALIDARG);
        CHECK_HR(errors[2], HDA_E_UNKNOWNATTRID);
        CoTaskMemFree(errors);
    }
    if (b && b != GARBAGE_PTR) b->lpVtbl->Release(b);
    ops[1] = HDA_FILTER_OPS[1];
    b = (IOPCHDA_Browser *)GARBAGE_PTR;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->CreateBrowse(server, HDA_FILTERS, ids, ops, filters, &b, &errors), S_FALSE);
    for (k = 0; k < HDA_FILTERS; k++) VariantClear(&filters[k]);
    CHECK(b && b != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (errors && errors != GARBAGE_PTR) {
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], S_OK);
        CHECK_HR(errors[2], HDA_E_UNKNOWNATTRID);
        CoTaskMemFree(errors);
    }
    if (!b || b == GARBAGE_PTR) return;
    /* The root: one branch, no leaves; the filters let item 1 alone through. */
    CHECK(positioned(b, ""));
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetEnum(b, OPCHDA_BRANCH, &e), S_OK);
    CHECK(enumerates(e, top, 1));
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetEnum(b, OPCHDA_LEAF, &e), S_FALSE);
    CHECK(enumerates(e, NULL, 0));
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetEnum(b, OPCHDA_FLAT, &e), S_OK);
    CHECK(enumerates(e, &HDA_ITEM_IDS[1], 1));
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetEnum(b, (OPCHDA_BROWSETYPE)9, &e), E_INVALIDARG);
    CHECK(e == NULL);
    /* Down twice: the leaf found and its ID; a leaf filtered out and a branch not there are refused. */
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCHDA_BROWSE_DOWN, W("Nowhere")), E_INVALIDARG);
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCHDA_BROWSE_DOWN, W(HDA_TOP_BRANCH)), S_OK);
    CHECK(positioned(b, HDA_TOP_BRANCH));
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetEnum(b, OPCHDA_BRANCH, &e), S_OK);
    CHECK(enumerates(e, branch, 1));
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCHDA_BROWSE_DOWN, W(HDA_BRANCH)), S_OK);
    CHECK(positioned(b, HDA_BRANCH_POSITION));
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetEnum(b, OPCHDA_LEAF, &e), S_OK);
    CHECK(enumerates(e, &HDA_LEAVES[1], 1));
    id = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetItemID(b, W(HDA_LEAVES[1]), &id), S_OK);
    CHECK(id != GARBAGE_PTR && is_utf8(id, HDA_ITEM_IDS[1]));
    if (id != GARBAGE_PTR) CoTaskMemFree(id);
    id = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetItemID(b, W(HDA_LEAVES[0]), &id), E_INVALIDARG);
    CHECK(id == NULL);
    /* Up, then directly to the branch, then to the root. */
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCHDA_BROWSE_UP, W("")), S_OK);
    CHECK(positioned(b, HDA_TOP_BRANCH));
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCHDA_BROWSE_DIRECT, W(HDA_BRANCH_POSITION)), S_OK);
    CHECK(positioned(b, HDA_BRANCH_POSITION));
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCHDA_BROWSE_DIRECT, W("")), S_OK);
    CHECK(positioned(b, ""));
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCHDA_BROWSE_UP, W("")), E_INVALIDARG);
    b->lpVtbl->Release(b);
}

int main(void) {
    OpcServerRegistration reg;
    IOPCHDA_Server *server = NULL;
    IOPCHDA_SyncRead *sync = NULL;
    int waited;

    beside_this_program(server_path, L"opc_hda_test_server.exe");
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    CHECK_HR(use_opccomn_proxy_stub_for(HDA_IIDS, HDA_IID_COUNT), S_OK);
    memset(&reg, 0, sizeof reg);
    reg.struct_size = sizeof reg;
    reg.server_type = OPC_SERVER_TYPE_LOCAL;
    reg.clsid = CLSID_HdaTestServer;
    reg.prog_id = L"Oop.HdaServer.1";
    reg.user_type = L"opccomn HDA tables test server";
    reg.module_path = server_path;
    CHECK_HR(OpcRegisterServer(&reg, NULL), S_OK);

    CHECK_HR(CoCreateInstance(&CLSID_HdaTestServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCHDA_Server, (void **)&server),
             S_OK);
    if (server) {
        check_status(server);
        check_attributes(server);
        check_handles(server);
        check_browser(server);
        CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCHDA_SyncRead, (void **)&sync), S_OK);
        if (sync) {
            check_read_raw(sync);
            check_read_processed(sync);
            check_read_at_time(sync);
            check_read_modified(sync);
            check_bound(sync);
            sync->lpVtbl->Release(sync);
        }
        check_annotations(server);
        check_update(server);
        check_async(server);
        server->lpVtbl->Release(server);
    }
    /* The server exits once its objects are gone (its linger is 100 ms; 10 s bound a broken run). */
    for (waited = 0; waited < 100 && process_running(L"opc_hda_test_server.exe") == 1; waited++) Sleep(100);
    CHECK(process_running(L"opc_hda_test_server.exe") == 0);
    /* The server let go of the callback before it ended. */
    CHECK(cb.refs == 1);
    if (cb.called) CloseHandle(cb.called);
    CHECK_HR(OpcUnregisterServer(&reg, NULL), S_OK);
    CoUninitialize();
    return test_summary("test_hda_tables");
}
