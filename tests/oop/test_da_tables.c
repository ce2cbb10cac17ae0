/* opccomn.dll's proxy/stub of the Data Access interfaces (the NDR tables tools/gen-proxy.py makes from
 * idl/opcda.idl, with the checks generated from the same IDL) across processes, under the real COM
 * runtime (Wine in CI): this client and the EXE server da_server.c, both with opccomn.dll's proxy/stub
 * as theirs for the DA interfaces (registered per process, da.h). Every value crosses the wire and is
 * checked on the other side: the server answers a request it did not receive as sent with an error.
 * Both sides' proxies check: a count beyond its bound never leaves the client.
 *
 * Covered: IOPCServer::GetStatus (the structure and its vendor string), GetErrorString ([out, string]
 * LPWSTR *), AddGroup (unique in-pointers, iid_is), GetGroupByName, RemoveGroup;
 * IOPCGroupStateMgt::GetState / SetState; IOPCItemMgt::AddItems with three items (a blob each way) and
 * with an unknown item, RemoveItems; IOPCSyncIO::Read of VT_I4, VT_R8, VT_BSTR and VT_ARRAY | VT_R8
 * values with an invalid handle among them, Write and Read again; IOPCDataCallback::OnDataChange
 * through the group's connection point (IOPCAsyncIO2::Refresh2); IOPCItemProperties
 * (QueryAvailableProperties, GetItemProperties, LookupItemIDs: [out, string, size_is(,n)] LPWSTR **);
 * IOPCBrowse::GetProperties ([in, string, size_is(n)] LPWSTR *) and Browse (an [in, out, string]
 * continuation point, OPCBROWSEELEMENT with properties). The three forms in brackets are those whose
 * type offsets tools/gen-proxy.py corrects. */
#include "da.h"

#include <olectl.h>

static WCHAR server_path[MAX_PATH];

/* ---- The client's callback ---- */

typedef struct Callback {
    IOPCDataCallback iface;
    LONG refs;
    HANDLE changed; /* set by OnDataChange */
    /* What the last OnDataChange brought. */
    DWORD transaction, count;
    OPCHANDLE group;
    HRESULT quality, error;
    OPCHANDLE handles[DA_ITEMS];
    VARIANT values[DA_ITEMS];
    WORD qualities[DA_ITEMS];
    FILETIME times[DA_ITEMS];
    HRESULT errors[DA_ITEMS];
    int calls;
} Callback;

static HRESULT STDMETHODCALLTYPE cb_qi(IOPCDataCallback *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCDataCallback)) {
        *ppv = This;
        This->lpVtbl->AddRef(This);
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE cb_add_ref(IOPCDataCallback *This) {
    return (ULONG)InterlockedIncrement(&((Callback *)This)->refs);
}
static ULONG STDMETHODCALLTYPE cb_release(IOPCDataCallback *This) {
    return (ULONG)InterlockedDecrement(&((Callback *)This)->refs); /* static: nothing to free */
}
static HRESULT STDMETHODCALLTYPE cb_data_change(IOPCDataCallback *This, DWORD transaction, OPCHANDLE group,
                                                HRESULT quality, HRESULT error, DWORD count, OPCHANDLE *handles,
                                                VARIANT *values, WORD *qualities, FILETIME *times,
                                                HRESULT *errors) {
    Callback *c = (Callback *)This;
    DWORD i;
    c->calls++;
    c->transaction = transaction;
    c->group = group;
    c->quality = quality;
    c->error = error;
    c->count = count;
    for (i = 0; i < count && i < DA_ITEMS; i++) {
        c->handles[i] = handles[i];
        VariantInit(&c->values[i]);
        VariantCopy(&c->values[i], &values[i]);
        c->qualities[i] = qualities[i];
        c->times[i] = times[i];
        c->errors[i] = errors[i];
    }
    SetEvent(c->changed);
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cb_read_complete(IOPCDataCallback *This, DWORD transaction, OPCHANDLE group,
                                                  HRESULT quality, HRESULT error, DWORD count, OPCHANDLE *handles,
                                                  VARIANT *values, WORD *qualities, FILETIME *times,
                                                  HRESULT *errors) {
    (void)This, (void)transaction, (void)group, (void)quality, (void)error, (void)count, (void)handles;
    (void)values, (void)qualities, (void)times, (void)errors;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cb_write_complete(IOPCDataCallback *This, DWORD transaction, OPCHANDLE group,
                                                   HRESULT error, DWORD count, OPCHANDLE *handles, HRESULT *errors) {
    (void)This, (void)transaction, (void)group, (void)error, (void)count, (void)handles, (void)errors;
    return S_OK;
}
static HRESULT STDMETHODCALLTYPE cb_cancel_complete(IOPCDataCallback *This, DWORD transaction, OPCHANDLE group) {
    (void)This, (void)transaction, (void)group;
    return S_OK;
}
static IOPCDataCallbackVtbl cb_vtbl = {cb_qi,           cb_add_ref,       cb_release,        cb_data_change,
                                       cb_read_complete, cb_write_complete, cb_cancel_complete};

/* ---- Checks ---- */

/* The value item `i` holds at first (da_server.c: initial_value). */
static int is_initial(int i, const VARIANT *v) {
    switch (i) {
    case 0: return V_VT(v) == VT_I4 && V_I4(v) == DA_I4;
    case 1: return V_VT(v) == VT_R8 && V_R8(v) == DA_R8;
    case 2: return V_VT(v) == VT_BSTR && wsame(V_BSTR(v), W(DA_TEXT)) && SysStringLen(V_BSTR(v)) == wlen(W(DA_TEXT));
    default: return is_doubles(v, DA_PROFILE, DA_PROFILE_COUNT);
    }
}

static void check_status(IOPCServer *server) {
    OPCSERVERSTATUS *st = (OPCSERVERSTATUS *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->GetStatus(server, &st), S_OK);
    CHECK(st && st != GARBAGE_PTR);
    if (!st || st == GARBAGE_PTR) return;
    CHECK(same_filetime(st->ftStartTime, test_time(0)));
    CHECK(same_filetime(st->ftCurrentTime, test_time(1)));
    CHECK(same_filetime(st->ftLastUpdateTime, test_time(2)));
    CHECK(st->dwServerState == OPC_STATUS_RUNNING);
    CHECK(st->dwGroupCount == 0);
    CHECK(st->dwBandWidth == 0xFFFFFFFF);
    CHECK(st->wMajorVersion == 3 && st->wMinorVersion == 0 && st->wBuildNumber == 42);
    CHECK(wsame(st->szVendorInfo, W(DA_VENDOR_INFO)));
    CoTaskMemFree(st->szVendorInfo);
    CoTaskMemFree(st);
}

/* Both processes use opccomn.dll's proxy/stub, and this client's proxies check what they send: a
 * count beyond its bound (65,536 property IDs, idl/ndr-bounds.txt) is refused before it is sent, with
 * the code MIDL's [range] gives (a proxy without the checks would send it and the server answer). */
static void check_opccomn_serves(IOPCServer *server, IOPCItemProperties *props, int classic) {
    LPWSTR text = (LPWSTR)GARBAGE_PTR;
    DWORD *ids;
    VARIANT *data = (VARIANT *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    CHECK(da_proxy_stub_is_opccomn() == !classic);
    CHECK_HR(server->lpVtbl->GetErrorString(server, DA_CODE_PROXY_STUB, 0x0409, &text), S_OK);
    CHECK(wsame(text, W("opccomn")));
    if (text != GARBAGE_PTR) CoTaskMemFree(text);
    if (classic) return; /* the stand-in's proxy sends what it is given */
    ids = (DWORD *)calloc(65537, sizeof(DWORD));
    if (!ids || !props) {
        CHECK(0);
        free(ids);
        return;
    }
    ids[0] = DA_PROPERTY_IDS[0];
    CHECK_HR(props->lpVtbl->GetItemProperties(props, (LPWSTR)W(DA_ITEM_IDS[0]), 65537, ids, &data, &errors),
             HRESULT_FROM_WIN32(RPC_S_INVALID_BOUND));
    CHECK(data == NULL && errors == NULL);
    free(ids);
}

static void check_error_string(IOPCServer *server) {
    LPWSTR text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->GetErrorString(server, DA_ERROR_CODE, 0x0409, &text), S_OK);
    CHECK(wsame(text, W(DA_ERROR_TEXT)));
    if (text != GARBAGE_PTR) CoTaskMemFree(text);
    text = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->GetErrorString(server, DA_ERROR_CODE, 0x0407, &text), E_INVALIDARG);
    CHECK(text == NULL);
}

static void check_group_state(IOPCGroupStateMgt *state) {
    DWORD rate = GARBAGE_U32, lcid = GARBAGE_U32, revised = GARBAGE_U32, new_rate = 2500;
    BOOL active = (BOOL)GARBAGE_U32, inactive = FALSE;
    LPWSTR name = (LPWSTR)GARBAGE_PTR;
    LONG bias = (LONG)GARBAGE_U32, new_bias = 120;
    FLOAT deadband = -1.0f;
    OPCHANDLE client = GARBAGE_U32, server = GARBAGE_U32;
    CHECK_HR(state->lpVtbl->GetState(state, &rate, &active, &name, &bias, &deadband, &lcid, &client, &server), S_OK);
    CHECK(rate == 1000 && active == TRUE && bias == -60 && deadband == 0.0f && lcid == 0x0407);
    CHECK(client == 42 && server == 7);
    CHECK(wsame(name, W(DA_GROUP_NAME)));
    if (name != GARBAGE_PTR) CoTaskMemFree(name);
    /* SetState: NULL for what stays (unique in-pointers), two changes. */
    CHECK_HR(state->lpVtbl->SetState(state, &new_rate, &revised, &inactive, &new_bias, NULL, NULL, NULL), S_OK);
    CHECK(revised == 2500);
    name = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(state->lpVtbl->GetState(state, &rate, &active, &name, &bias, &deadband, &lcid, &client, &server), S_OK);
    CHECK(rate == 2500 && active == FALSE && bias == 120 && deadband == 0.0f && lcid == 0x0407 && client == 42);
    if (name != GARBAGE_PTR) CoTaskMemFree(name);
}

/* AddItems of the first three items (the first with a blob), then of the fourth with an unknown one;
 * fills `servers` with the items' server handles. */
static void check_add_items(IOPCItemMgt *items, OPCHANDLE *servers) {
    OPCITEMDEF defs[3];
    OPCITEMRESULT *results = (OPCITEMRESULT *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    int i;
    memset(defs, 0, sizeof defs);
    for (i = 0; i < 3; i++) {
        defs[i].szAccessPath = (LPWSTR)W("");
        defs[i].szItemID = (LPWSTR)W(DA_ITEM_IDS[i]);
        defs[i].bActive = TRUE;
        defs[i].hClient = DA_CLIENT_HANDLE(i);
        defs[i].vtRequestedDataType = VT_EMPTY;
    }
    defs[0].dwBlobSize = DA_BLOB_SIZE;
    defs[0].pBlob = (BYTE *)DA_BLOB;
    CHECK_HR(items->lpVtbl->AddItems(items, 3, defs, &results, &errors), S_OK);
    CHECK(results && results != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (results && results != GARBAGE_PTR && errors && errors != GARBAGE_PTR) {
        for (i = 0; i < 3; i++) {
            CHECK_HR(errors[i], S_OK);
            CHECK(results[i].hServer == (OPCHANDLE)(100 + i));
            CHECK(results[i].vtCanonicalDataType == DA_ITEM_TYPES[i]);
            CHECK(results[i].dwAccessRights == (OPC_READABLE_ | OPC_WRITEABLE_));
            servers[i] = results[i].hServer;
        }
        /* The server's blob: the client's, reversed. */
        CHECK(results[0].dwBlobSize == DA_BLOB_SIZE && results[0].pBlob);
        if (results[0].pBlob)
            for (i = 0; i < DA_BLOB_SIZE; i++) CHECK(results[0].pBlob[i] == DA_BLOB[DA_BLOB_SIZE - 1 - i]);
        CHECK(results[1].dwBlobSize == 0 && !results[1].pBlob && results[2].dwBlobSize == 0 && !results[2].pBlob);
        CoTaskMemFree(results[0].pBlob);
        CoTaskMemFree(results);
        CoTaskMemFree(errors);
    }

    /* The array item, and one the server does not know. */
    memset(defs, 0, sizeof defs);
    defs[0].szAccessPath = defs[1].szAccessPath = (LPWSTR)W("");
    defs[0].szItemID = (LPWSTR)W(DA_ITEM_IDS[3]);
    defs[1].szItemID = (LPWSTR)W("Plant.Tank9.Nothing");
    defs[0].bActive = defs[1].bActive = TRUE;
    defs[0].hClient = DA_CLIENT_HANDLE(3);
    defs[1].hClient = DA_CLIENT_HANDLE(9);
    results = (OPCITEMRESULT *)GARBAGE_PTR;
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(items->lpVtbl->AddItems(items, 2, defs, &results, &errors), S_FALSE);
    if (results && results != GARBAGE_PTR && errors && errors != GARBAGE_PTR) {
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], OPC_E_UNKNOWNITEMID_);
        CHECK(results[0].hServer == 103 && results[0].vtCanonicalDataType == (VT_ARRAY | VT_R8));
        CHECK(results[1].hServer == 0 && !results[1].pBlob);
        servers[3] = results[0].hServer;
        CoTaskMemFree(results);
        CoTaskMemFree(errors);
    } else {
        CHECK(0);
    }
}

/* Reads the four items (their first values, from the device) and an invalid handle. */
static void check_read(IOPCSyncIO *sync, const OPCHANDLE *servers) {
    OPCHANDLE handles[DA_ITEMS + 1];
    OPCITEMSTATE *states = (OPCITEMSTATE *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    int i;
    for (i = 0; i < DA_ITEMS; i++) handles[i] = servers[i];
    handles[DA_ITEMS] = 999;
    CHECK_HR(sync->lpVtbl->Read(sync, OPC_DS_DEVICE, DA_ITEMS + 1, handles, &states, &errors), S_FALSE);
    if (!states || states == GARBAGE_PTR || !errors || errors == GARBAGE_PTR) {
        CHECK(0);
        return;
    }
    for (i = 0; i < DA_ITEMS; i++) {
        CHECK_HR(errors[i], S_OK);
        CHECK(states[i].hClient == DA_CLIENT_HANDLE(i));
        CHECK(same_filetime(states[i].ftTimeStamp, test_time((unsigned)i + 10)));
        CHECK(states[i].wQuality == OPC_QUALITY_GOOD_);
        CHECK(is_initial(i, &states[i].vDataValue));
        VariantClear(&states[i].vDataValue);
    }
    CHECK_HR(errors[DA_ITEMS], OPC_E_INVALIDHANDLE_);
    CHECK(V_VT(&states[DA_ITEMS].vDataValue) == VT_EMPTY);
    CoTaskMemFree(states);
    CoTaskMemFree(errors);
}

/* Writes new values of the four items and reads them back. */
static void check_write(IOPCSyncIO *sync, const OPCHANDLE *servers) {
    static const double profile[2] = {-0.5, 42.0};
    VARIANT values[DA_ITEMS];
    OPCITEMSTATE *states = (OPCITEMSTATE *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    int i;
    for (i = 0; i < DA_ITEMS; i++) VariantInit(&values[i]);
    V_VT(&values[0]) = VT_I4;
    V_I4(&values[0]) = -7;
    V_VT(&values[1]) = VT_R8;
    V_R8(&values[1]) = 1e-300;
    V_VT(&values[2]) = VT_BSTR;
    V_BSTR(&values[2]) = bstr_utf8("written \xc3\x9f");
    V_VT(&values[3]) = VT_ARRAY | VT_R8;
    V_ARRAY(&values[3]) = da_doubles(profile, 2);
    CHECK_HR(sync->lpVtbl->Write(sync, DA_ITEMS, (OPCHANDLE *)servers, values, &errors), S_OK);
    if (errors && errors != GARBAGE_PTR) {
        for (i = 0; i < DA_ITEMS; i++) CHECK_HR(errors[i], S_OK);
        CoTaskMemFree(errors);
    }
    /* A wrong type for the first item: refused per item. */
    errors = (HRESULT *)GARBAGE_PTR;
    VariantClear(&values[0]);
    V_VT(&values[0]) = VT_R8;
    V_R8(&values[0]) = 1.0;
    CHECK_HR(sync->lpVtbl->Write(sync, 1, (OPCHANDLE *)servers, values, &errors), S_FALSE);
    if (errors && errors != GARBAGE_PTR) {
        CHECK_HR(errors[0], (HRESULT)0xC0040004L); /* OPC_E_BADTYPE */
        CoTaskMemFree(errors);
    }
    CHECK_HR(sync->lpVtbl->Read(sync, OPC_DS_CACHE, DA_ITEMS, (OPCHANDLE *)servers, &states, &errors), S_OK);
    if (states && states != GARBAGE_PTR && errors && errors != GARBAGE_PTR) {
        CHECK(V_VT(&states[0].vDataValue) == VT_I4 && V_I4(&states[0].vDataValue) == -7);
        CHECK(V_VT(&states[1].vDataValue) == VT_R8 && V_R8(&states[1].vDataValue) == 1e-300);
        CHECK(V_VT(&states[2].vDataValue) == VT_BSTR && wsame(V_BSTR(&states[2].vDataValue), W("written \xc3\x9f")));
        CHECK(is_doubles(&states[3].vDataValue, profile, 2));
        for (i = 0; i < DA_ITEMS; i++) {
            CHECK(same_filetime(states[i].ftTimeStamp, test_time((unsigned)i)));
            VariantClear(&states[i].vDataValue);
        }
        CoTaskMemFree(states);
        CoTaskMemFree(errors);
    } else {
        CHECK(0);
    }
    for (i = 0; i < DA_ITEMS; i++) VariantClear(&values[i]);
}

/* The callback object: static, as the server's proxy may release it after the test's function
 * returned. */
static Callback cb;

static void check_data_change(IUnknown *group) {
    IConnectionPointContainer *cpc = NULL;
    IConnectionPoint *cp = NULL;
    IOPCAsyncIO2 *async = NULL;
    DWORD cookie = GARBAGE_U32, cancel = GARBAGE_U32;
    DWORD i;
    memset(&cb, 0, sizeof cb);
    cb.iface.lpVtbl = &cb_vtbl;
    cb.refs = 1;
    cb.changed = CreateEventW(NULL, FALSE, FALSE, NULL);
    CHECK_HR(group->lpVtbl->QueryInterface(group, &IID_IConnectionPointContainer, (void **)&cpc), S_OK);
    CHECK_HR(group->lpVtbl->QueryInterface(group, &IID_IOPCAsyncIO2, (void **)&async), S_OK);
    if (!cpc || !async) return;
    /* Without a callback the refresh is refused. */
    CHECK_HR(async->lpVtbl->Refresh2(async, OPC_DS_CACHE, 76, &cancel), CONNECT_E_NOCONNECTION);
    CHECK_HR(cpc->lpVtbl->FindConnectionPoint(cpc, &IID_IOPCDataCallback, &cp), S_OK);
    if (cp) {
        CHECK_HR(cp->lpVtbl->Advise(cp, (IUnknown *)&cb.iface, &cookie), S_OK);
        CHECK(cookie == 1);
        CHECK_HR(async->lpVtbl->Refresh2(async, OPC_DS_CACHE, 77, &cancel), S_OK);
        CHECK(cancel == 78);
        /* The server's thread calls back; 60 s only bound a broken run. */
        CHECK(WaitForSingleObject(cb.changed, 60000) == WAIT_OBJECT_0);
        CHECK(cb.calls == 1 && cb.transaction == 77 && cb.group == 42);
        CHECK(cb.quality == S_OK && cb.error == S_OK && cb.count == DA_ITEMS);
        for (i = 0; i < cb.count && i < DA_ITEMS; i++) {
            CHECK(cb.handles[i] == DA_CLIENT_HANDLE(i));
            CHECK(is_initial((int)i, &cb.values[i]));
            CHECK(cb.qualities[i] == OPC_QUALITY_GOOD_);
            CHECK(same_filetime(cb.times[i], test_time(i + 20)));
            CHECK_HR(cb.errors[i], S_OK);
            VariantClear(&cb.values[i]);
        }
        CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie), S_OK);
        CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie), CONNECT_E_NOCONNECTION);
        cp->lpVtbl->Release(cp);
    }
    async->lpVtbl->Release(async);
    cpc->lpVtbl->Release(cpc);
    CloseHandle(cb.changed);
    cb.changed = NULL;
}

static void check_remove_items(IOPCItemMgt *items, const OPCHANDLE *servers) {
    OPCHANDLE handles[2];
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    handles[0] = servers[1];
    handles[1] = 555;
    CHECK_HR(items->lpVtbl->RemoveItems(items, 2, handles, &errors), S_FALSE);
    if (errors && errors != GARBAGE_PTR) {
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], OPC_E_INVALIDHANDLE_);
        CoTaskMemFree(errors);
    }
}

static void check_item_properties(IOPCServer *server) {
    IOPCItemProperties *p = NULL;
    DWORD count = GARBAGE_U32, *ids = (DWORD *)GARBAGE_PTR, k;
    LPWSTR *descriptions = (LPWSTR *)GARBAGE_PTR, *new_ids = (LPWSTR *)GARBAGE_PTR;
    VARTYPE *types = (VARTYPE *)GARBAGE_PTR;
    VARIANT *values = (VARIANT *)GARBAGE_PTR;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    DWORD asked[3] = {101, 1, 77};
    LPWSTR item = (LPWSTR)W(DA_ITEM_IDS[1]);
    CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCItemProperties, (void **)&p), S_OK);
    if (!p) return;
    CHECK_HR(p->lpVtbl->QueryAvailableProperties(p, item, &count, &ids, &descriptions, &types), S_OK);
    CHECK(count == DA_PROPERTY_COUNT);
    if (count == DA_PROPERTY_COUNT && ids != GARBAGE_PTR && descriptions != GARBAGE_PTR && types != GARBAGE_PTR) {
        CHECK(ids[0] == 1 && ids[1] == 101 && types[0] == VT_I2 && types[1] == VT_BSTR);
        CHECK(wsame(descriptions[0], W("Item Canonical Data Type")) && wsame(descriptions[1], W("Item Description")));
        for (k = 0; k < count; k++) CoTaskMemFree(descriptions[k]);
        CoTaskMemFree(ids);
        CoTaskMemFree(descriptions);
        CoTaskMemFree(types);
    }
    CHECK_HR(p->lpVtbl->GetItemProperties(p, item, 3, asked, &values, &errors), S_FALSE);
    if (values != GARBAGE_PTR && errors != GARBAGE_PTR && values && errors) {
        CHECK(V_VT(&values[0]) == VT_BSTR && wsame(V_BSTR(&values[0]), W("Description of Plant.Tank1.Temp (R8)")));
        CHECK(V_VT(&values[1]) == VT_I2 && V_I2(&values[1]) == VT_R8);
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], S_OK);
        CHECK_HR(errors[2], (HRESULT)0xC0040203L);
        for (k = 0; k < 3; k++) VariantClear(&values[k]);
        CoTaskMemFree(values);
        CoTaskMemFree(errors);
    }
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(p->lpVtbl->LookupItemIDs(p, item, 3, asked, &new_ids, &errors), S_FALSE);
    CHECK(new_ids && new_ids != GARBAGE_PTR && errors && errors != GARBAGE_PTR);
    if (new_ids && new_ids != GARBAGE_PTR && errors && errors != GARBAGE_PTR) {
        CHECK(wsame(new_ids[0], W("Plant.Tank1.Temp (R8).Description")));
        CHECK(new_ids[1] == NULL && new_ids[2] == NULL);
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], (HRESULT)0xC0040203L);
        CoTaskMemFree(new_ids[0]);
        CoTaskMemFree(new_ids);
        CoTaskMemFree(errors);
    }
    p->lpVtbl->Release(p);
}

/* The properties of one item as IOPCBrowse returns them (all: 1 and 101), with values or without. */
static void check_properties(const OPCITEMPROPERTIES *p, int i, int with_values) {
    char id[96];
    CHECK_HR(p->hrErrorID, S_OK);
    CHECK(p->dwNumProperties == 2 && p->pItemProperties);
    if (p->dwNumProperties != 2 || !p->pItemProperties) return;
    snprintf(id, sizeof id, "%s.Description", DA_ITEM_IDS[i]);
    CHECK(p->pItemProperties[0].dwPropertyID == 1 && p->pItemProperties[0].vtDataType == VT_I2);
    CHECK(p->pItemProperties[0].szItemID == NULL);
    CHECK(wsame(p->pItemProperties[0].szDescription, W("Item Canonical Data Type")));
    CHECK(p->pItemProperties[1].dwPropertyID == 101 && p->pItemProperties[1].vtDataType == VT_BSTR);
    CHECK(wsame(p->pItemProperties[1].szItemID, W(id)));
    CHECK(wsame(p->pItemProperties[1].szDescription, W("Item Description")));
    if (with_values) {
        CHECK(V_VT(&p->pItemProperties[0].vValue) == VT_I2 && V_I2(&p->pItemProperties[0].vValue) == (SHORT)DA_ITEM_TYPES[i]);
        CHECK(V_VT(&p->pItemProperties[1].vValue) == VT_BSTR);
    } else {
        CHECK(V_VT(&p->pItemProperties[0].vValue) == VT_EMPTY && V_VT(&p->pItemProperties[1].vValue) == VT_EMPTY);
    }
}

static void free_properties(OPCITEMPROPERTIES *p) {
    DWORD k;
    for (k = 0; k < p->dwNumProperties; k++) {
        CoTaskMemFree(p->pItemProperties[k].szItemID);
        CoTaskMemFree(p->pItemProperties[k].szDescription);
        VariantClear(&p->pItemProperties[k].vValue);
    }
    CoTaskMemFree(p->pItemProperties);
}

static void check_browse(IOPCServer *server) {
    IOPCBrowse *b = NULL;
    LPWSTR ids[3];
    OPCITEMPROPERTIES *props = (OPCITEMPROPERTIES *)GARBAGE_PTR;
    OPCBROWSEELEMENT *elements = (OPCBROWSEELEMENT *)GARBAGE_PTR;
    LPWSTR continuation = NULL;
    BOOL more = (BOOL)GARBAGE_U32;
    DWORD count = GARBAGE_U32, k, seen = 0, no_ids = 0;
    int i, round;
    CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCBrowse, (void **)&b), S_OK);
    if (!b) return;
    ids[0] = (LPWSTR)W(DA_ITEM_IDS[2]);
    ids[1] = (LPWSTR)W("Plant.Nothing");
    ids[2] = (LPWSTR)W(DA_ITEM_IDS[0]);
    /* No property IDs: every property. The array is a reference pointer (the Foundation's IDL), so
     * not NULL even when empty. */
    CHECK_HR(b->lpVtbl->GetProperties(b, 3, ids, TRUE, 0, &no_ids, &props), S_FALSE);
    if (props && props != GARBAGE_PTR) {
        check_properties(&props[0], 2, 1);
        CHECK_HR(props[1].hrErrorID, OPC_E_UNKNOWNITEMID_);
        CHECK(props[1].dwNumProperties == 0 && !props[1].pItemProperties);
        check_properties(&props[2], 0, 1);
        for (k = 0; k < 3; k++) free_properties(&props[k]);
        CoTaskMemFree(props);
    } else {
        CHECK(0);
    }
    /* Browse the root three items at a time: two pages, the continuation point in between. */
    for (round = 0; round < 2; round++) {
        elements = (OPCBROWSEELEMENT *)GARBAGE_PTR;
        CHECK_HR(b->lpVtbl->Browse(b, (LPWSTR)W(""), &continuation, 3, OPC_BROWSE_FILTER_ALL, (LPWSTR)W(""),
                                   (LPWSTR)W(""), TRUE, round == 0, 0, &no_ids, &more, &count, &elements),
                 S_OK);
        CHECK(count == (round == 0 ? 3u : 1u) && more == (round == 0));
        CHECK(round == 0 ? wsame(continuation, W("cp:3")) : continuation == NULL);
        if (elements == GARBAGE_PTR || !elements) {
            CHECK(0);
            break;
        }
        for (k = 0; k < count; k++) {
            i = (int)(seen + k);
            CHECK(wsame(elements[k].szName, W(DA_ITEM_IDS[i])) && wsame(elements[k].szItemID, W(DA_ITEM_IDS[i])));
            CHECK(elements[k].dwFlagValue == 2);
            check_properties(&elements[k].ItemProperties, i, round == 0);
            CoTaskMemFree(elements[k].szName);
            CoTaskMemFree(elements[k].szItemID);
            free_properties(&elements[k].ItemProperties);
        }
        seen += count;
        CoTaskMemFree(elements);
    }
    CHECK(seen == DA_ITEMS);
    /* A continuation point the server did not give is refused, and the client's stays. */
    continuation = (LPWSTR)CoTaskMemAlloc(8 * sizeof(WCHAR));
    memcpy(continuation, W("bogus"), 6 * sizeof(WCHAR));
    elements = (OPCBROWSEELEMENT *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->Browse(b, (LPWSTR)W(""), &continuation, 3, OPC_BROWSE_FILTER_ALL, (LPWSTR)W(""),
                               (LPWSTR)W(""), FALSE, FALSE, 0, &no_ids, &more, &count, &elements),
             (HRESULT)0xC0040403L);
    CHECK(count == 0 && elements == NULL);
    CHECK(wsame(continuation, W("bogus")));
    CoTaskMemFree(continuation);
    b->lpVtbl->Release(b);
}

/* argv[1] "classic": this client uses opc_classic_widl_ps.dll (the widl-generated tables in a
 * MIDL-style proxy/stub DLL: the stand-in for the OPC Foundation's DA proxy/stub) while the server
 * keeps opccomn.dll's, so that each side's proxy talks to the other's stub (the callback too). */
int main(int argc, char **argv) {
    int classic = argc > 1 && strcmp(argv[1], "classic") == 0;
    OpcServerRegistration reg;
    IOPCServer *server = NULL;
    IUnknown *group = NULL;
    IOPCItemMgt *items = NULL;
    IOPCSyncIO *sync = NULL;
    IOPCGroupStateMgt *state = NULL;
    OPCHANDLE servers[DA_ITEMS] = {0, 0, 0, 0};
    OPCHANDLE server_group = GARBAGE_U32;
    DWORD revised = GARBAGE_U32;
    LONG bias = -60;
    WCHAR *slash;
    int waited;

    GetModuleFileNameW(NULL, server_path, MAX_PATH);
    slash = wcsrchr(server_path, L'\\');
    wcscpy(slash ? slash + 1 : server_path, L"opc_da_test_server.exe");
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    CHECK_HR(classic ? use_classic_proxy_stub() : use_opccomn_proxy_stub(), S_OK);
    memset(&reg, 0, sizeof reg);
    reg.struct_size = sizeof reg;
    reg.server_type = OPC_SERVER_TYPE_LOCAL;
    reg.clsid = CLSID_DaTestServer;
    reg.prog_id = L"Oop.DaServer.1";
    reg.user_type = L"opccomn DA tables test server";
    reg.module_path = server_path;
    CHECK_HR(OpcRegisterServer(&reg, NULL), S_OK);

    CHECK_HR(CoCreateInstance(&CLSID_DaTestServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServer, (void **)&server), S_OK);
    if (server) {
        IOPCItemProperties *props = NULL;
        CHECK_HR(server->lpVtbl->QueryInterface(server, &IID_IOPCItemProperties, (void **)&props), S_OK);
        check_opccomn_serves(server, props, classic);
        if (props) props->lpVtbl->Release(props);
        check_status(server);
        check_error_string(server);
        CHECK_HR(server->lpVtbl->AddGroup(server, W(DA_GROUP_NAME), TRUE, 1000, 42, &bias, NULL, 0x0407,
                                          &server_group, &revised, &IID_IOPCItemMgt, &group),
                 S_OK);
        CHECK(server_group == 7 && revised == 1000);
    }
    if (group) {
        IUnknown *again = NULL;
        CHECK_HR(server->lpVtbl->GetGroupByName(server, W(DA_GROUP_NAME), &IID_IOPCSyncIO, &again), S_OK);
        if (again) again->lpVtbl->Release(again);
        CHECK_HR(server->lpVtbl->GetGroupByName(server, W("other"), &IID_IOPCSyncIO, &again), E_INVALIDARG);
        items = (IOPCItemMgt *)group;
        CHECK_HR(group->lpVtbl->QueryInterface(group, &IID_IOPCSyncIO, (void **)&sync), S_OK);
        CHECK_HR(group->lpVtbl->QueryInterface(group, &IID_IOPCGroupStateMgt, (void **)&state), S_OK);
        if (state) check_group_state(state);
        check_add_items(items, servers);
        if (sync) {
            check_read(sync, servers);
            check_data_change(group);
            check_write(sync, servers);
        }
        check_remove_items(items, servers);
        if (sync) sync->lpVtbl->Release(sync);
        if (state) state->lpVtbl->Release(state);
        group->lpVtbl->Release(group);
        CHECK_HR(server->lpVtbl->RemoveGroup(server, 7, FALSE), S_OK);
    }
    if (server) {
        check_item_properties(server);
        check_browse(server);
        server->lpVtbl->Release(server);
    }
    /* The server exits once its objects are gone (its linger is 100 ms; 10 s bound a broken run). */
    for (waited = 0; waited < 100 && process_running(L"opc_da_test_server.exe") == 1; waited++) Sleep(100);
    CHECK(process_running(L"opc_da_test_server.exe") == 0);
    /* The server let go of the callback before it ended (its thread of the refresh may hold it a
     * moment after OnDataChange returned, so this is checked once the server is gone). */
    CHECK(cb.refs == 1);
    CHECK_HR(OpcUnregisterServer(&reg, NULL), S_OK);
    CoUninitialize();
    return test_summary("test_da_tables");
}
