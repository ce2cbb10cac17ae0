/* opccomn.dll's proxy/stub of the Alarms & Events 1.10 interfaces (the NDR tables tools/gen-proxy.py
 * makes from idl/opc_ae.idl, with the checks generated from the same IDL) across processes, under the
 * real COM runtime (Wine in CI): this client and the EXE server ae_server.c, both with opccomn.dll's
 * proxy/stub as theirs for the A&E interfaces (registered per process, classic_oop.h). Every value
 * crosses the wire and is checked on the other side: the server answers a request it did not receive
 * as sent with an error. A count beyond its bound never leaves the client.
 *
 * Covered: IOPCEventServer::GetStatus (OPCEVENTSERVERSTATUS and its string), QueryEventCategories
 * ([out, size_is(,*n)] DWORD ** and LPWSTR **), CreateEventSubscription (iid_is), GetConditionState
 * (OPCCONDITIONSTATE with its arrays, VARIANTs and a NULL string), DisableConditionBySource;
 * IOPCEventServer2::DisableConditionByArea2, EnableConditionByArea2, GetEnableStateBySource,
 * GetEnableStateByArea ([in, string, size_is(n)] LPWSTR * with per-element results);
 * IOPCEventSubscriptionMgt::GetState, SetState (unique in-pointers), SetFilter, GetFilter, Refresh;
 * IOPCEventSink::OnEvent with two ONEVENTSTRUCTs (strings, NULL strings, FILETIMEs, VT_BSTR and VT_I4
 * attributes) through the subscription's connection point; IOPCEventServer::CreateAreaBrowser and
 * IOPCEventAreaBrowser (ChangeBrowsePosition, BrowseOPCAreas: an IEnumString out,
 * GetQualifiedAreaName, GetQualifiedSourceName); IOPCEventServer::AckCondition (two strings, arrays of
 * strings, FILETIMEs and cookies, per-element results, a success code among them);
 * IOPCEventSubscriptionMgt2::SetKeepAlive (a revised time with OPC_S_INVALIDKEEPALIVETIME) and
 * GetKeepAlive. */
#include "ae.h"

#include <olectl.h> /* CONNECT_E_* */

static WCHAR server_path[MAX_PATH];

/* ---- The client's sink: checks what OnEvent brings (the main thread waits meanwhile) ---- */

typedef struct Sink {
    IOPCEventSink iface;
    LONG refs;
    HANDLE called; /* set by OnEvent */
    int calls;
} Sink;

static HRESULT STDMETHODCALLTYPE sink_qi(IOPCEventSink *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCEventSink)) {
        *ppv = This;
        This->lpVtbl->AddRef(This);
        return S_OK;
    }
    *ppv = NULL;
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE sink_add_ref(IOPCEventSink *This) {
    return (ULONG)InterlockedIncrement(&((Sink *)This)->refs);
}
static ULONG STDMETHODCALLTYPE sink_release(IOPCEventSink *This) {
    return (ULONG)InterlockedDecrement(&((Sink *)This)->refs); /* static: nothing to free */
}
static HRESULT STDMETHODCALLTYPE sink_on_event(IOPCEventSink *This, OPCHANDLE client, BOOL refresh, BOOL last,
                                               DWORD count, ONEVENTSTRUCT *events) {
    Sink *s = (Sink *)This;
    DWORD i;
    s->calls++;
    CHECK(client == AE_CLIENT_SUBSCRIPTION && refresh == TRUE && last == TRUE);
    CHECK(count == AE_EVENTS && events);
    for (i = 0; events && i < count && i < AE_EVENTS; i++) CHECK(ae_is_event(&events[i], (int)i));
    SetEvent(s->called);
    return S_OK;
}
static IOPCEventSinkVtbl sink_vtbl = {sink_qi, sink_add_ref, sink_release, sink_on_event};

/* Static, as the server's proxy may release it after the test's function returned. */
static Sink sink;

/* ---- Checks ---- */

/* Both processes use opccomn.dll's proxy/stub (the server says so in its status), and this client's
 * proxies check what they send: a count beyond its bound (65,537 attribute IDs,
 * idl/ndr-bounds.txt) is refused before it is sent, with the code MIDL's [range] gives. */
static void check_status(IOPCEventServer2 *server) {
    OPCEVENTSERVERSTATUS *st = (OPCEVENTSERVERSTATUS *)GARBAGE_PTR;
    CHECK(proxy_stub_is_opccomn_for(AE_IIDS, AE_IID_COUNT));
    CHECK_HR(server->lpVtbl->GetStatus(server, &st), S_OK);
    CHECK(st && st != GARBAGE_PTR);
    if (!st || st == GARBAGE_PTR) return;
    CHECK(same_filetime(st->ftStartTime, test_time(0)));
    CHECK(same_filetime(st->ftCurrentTime, test_time(1)));
    CHECK(same_filetime(st->ftLastUpdateTime, test_time(2)));
    CHECK(st->dwServerState == OPCAE_STATUS_RUNNING);
    CHECK(st->wMajorVersion == 1 && st->wMinorVersion == 10 && st->wBuildNumber == 42 && st->wReserved == 0);
    CHECK(is_utf8(st->szVendorInfo, AE_VENDOR_INFO));
    CoTaskMemFree(st->szVendorInfo);
    CoTaskMemFree(st);
}

static void check_bound(IOPCEventServer2 *server) {
    OPCCONDITIONSTATE *state = (OPCCONDITIONSTATE *)GARBAGE_PTR;
    DWORD *ids = (DWORD *)calloc(65537, sizeof(DWORD));
    if (!ids) {
        CHECK(0);
        return;
    }
    memcpy(ids, AE_ATTR_IDS, sizeof AE_ATTR_IDS);
    CHECK_HR(server->lpVtbl->GetConditionState(server, (LPWSTR)W(AE_SOURCE_NAMES[0]), (LPWSTR)W(AE_CONDITION), 65537,
                                               ids, &state),
             HRESULT_FROM_WIN32(RPC_S_INVALID_BOUND));
    CHECK(state == NULL);
    /* At the bound the request leaves, and the server refuses what it did not expect. */
    state = (OPCCONDITIONSTATE *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->GetConditionState(server, (LPWSTR)W(AE_SOURCE_NAMES[0]), (LPWSTR)W(AE_CONDITION), 65536,
                                               ids, &state),
             E_INVALIDARG);
    CHECK(state == NULL);
    free(ids);
}

static void check_categories(IOPCEventServer2 *server) {
    DWORD count = GARBAGE_U32, *ids = (DWORD *)GARBAGE_PTR, k;
    LPWSTR *texts = (LPWSTR *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->QueryEventCategories(server, AE_ALL_EVENTS, &count, &ids, &texts), S_OK);
    CHECK(count == AE_CATEGORIES && ids && ids != GARBAGE_PTR && texts && texts != GARBAGE_PTR);
    if (count == AE_CATEGORIES && ids && ids != GARBAGE_PTR && texts && texts != GARBAGE_PTR) {
        for (k = 0; k < count; k++) {
            CHECK(ids[k] == AE_CATEGORY_IDS[k]);
            CHECK(is_utf8(texts[k], AE_CATEGORY_TEXTS[k]));
            CoTaskMemFree(texts[k]);
        }
        CoTaskMemFree(ids);
        CoTaskMemFree(texts);
    }
    /* Refused: nothing comes back. */
    count = GARBAGE_U32;
    ids = (DWORD *)GARBAGE_PTR;
    texts = (LPWSTR *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->QueryEventCategories(server, AE_SIMPLE_EVENT, &count, &ids, &texts), E_INVALIDARG);
    CHECK(count == 0 && ids == NULL && texts == NULL);
}

static void check_condition_state(IOPCEventServer2 *server) {
    OPCCONDITIONSTATE *c = (OPCCONDITIONSTATE *)GARBAGE_PTR;
    DWORD k;
    VARIANT v;
    CHECK_HR(server->lpVtbl->GetConditionState(server, (LPWSTR)W(AE_SOURCE_NAMES[0]), (LPWSTR)W(AE_CONDITION),
                                               AE_ATTRS_ASKED, (DWORD *)AE_ATTR_IDS, &c),
             S_OK);
    CHECK(c && c != GARBAGE_PTR);
    if (!c || c == GARBAGE_PTR) return;
    CHECK(c->wState == 0x0003 && c->dwASCSeverity == AE_SC_SEVERITIES[0] && c->wQuality == 0xC0);
    CHECK(is_utf8(c->szActiveSubCondition, AE_SC_NAMES[0]));
    CHECK(is_utf8(c->szASCDefinition, AE_SC_DEFINITIONS[0]));
    CHECK(is_utf8(c->szASCDescription, AE_SC_DESCRIPTIONS[0]));
    CHECK(same_filetime(c->ftLastAckTime, test_time(1)) && same_filetime(c->ftSubCondLastActive, test_time(2)));
    CHECK(same_filetime(c->ftCondLastActive, test_time(3)));
    CHECK(c->ftCondLastInactive.dwLowDateTime == 0 && c->ftCondLastInactive.dwHighDateTime == 0);
    CHECK(is_utf8(c->szAcknowledgerID, "operator \xc3\xa4"));
    CHECK(c->szComment == NULL);
    CHECK(c->dwNumSCs == AE_SUBCONDITIONS && c->pszSCNames && c->pszSCDefinitions && c->pdwSCSeverities &&
          c->pszSCDescriptions);
    if (c->dwNumSCs == AE_SUBCONDITIONS && c->pszSCNames && c->pszSCDefinitions && c->pdwSCSeverities &&
        c->pszSCDescriptions)
        for (k = 0; k < AE_SUBCONDITIONS; k++) {
            CHECK(is_utf8(c->pszSCNames[k], AE_SC_NAMES[k]));
            CHECK(is_utf8(c->pszSCDefinitions[k], AE_SC_DEFINITIONS[k]));
            CHECK(c->pdwSCSeverities[k] == AE_SC_SEVERITIES[k]);
            CHECK(is_utf8(c->pszSCDescriptions[k], AE_SC_DESCRIPTIONS[k]));
            CoTaskMemFree(c->pszSCNames[k]);
            CoTaskMemFree(c->pszSCDefinitions[k]);
            CoTaskMemFree(c->pszSCDescriptions[k]);
        }
    CHECK(c->dwNumEventAttrs == AE_ATTRS_ASKED && c->pEventAttributes && c->pErrors);
    if (c->dwNumEventAttrs == AE_ATTRS_ASKED && c->pEventAttributes && c->pErrors)
        for (k = 0; k < AE_ATTRS_ASKED; k++) {
            CHECK_HR(c->pErrors[k], ae_attribute(AE_ATTR_IDS[k], &v));
            CHECK(ae_same_variant(&c->pEventAttributes[k], &v));
            VariantClear(&v);
            VariantClear(&c->pEventAttributes[k]);
        }
    CoTaskMemFree(c->szActiveSubCondition);
    CoTaskMemFree(c->szASCDefinition);
    CoTaskMemFree(c->szASCDescription);
    CoTaskMemFree(c->szAcknowledgerID);
    CoTaskMemFree(c->pszSCNames);
    CoTaskMemFree(c->pszSCDefinitions);
    CoTaskMemFree(c->pdwSCSeverities);
    CoTaskMemFree(c->pszSCDescriptions);
    CoTaskMemFree(c->pEventAttributes);
    CoTaskMemFree(c->pErrors);
    CoTaskMemFree(c);
    /* Another condition: refused, nothing comes back. */
    c = (OPCCONDITIONSTATE *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->GetConditionState(server, (LPWSTR)W(AE_SOURCE_NAMES[0]), (LPWSTR)W("Temp"),
                                               AE_ATTRS_ASKED, (DWORD *)AE_ATTR_IDS, &c),
             E_INVALIDARG);
    CHECK(c == NULL);
}

/* The enable state of `count` areas or sources, against what is expected of each. */
static void check_enable_state(IOPCEventServer2 *server, int by_area, DWORD count, LPWSTR *names, const BOOL *enabled,
                               const BOOL *effective, const HRESULT *errors, HRESULT expected) {
    BOOL *en = (BOOL *)GARBAGE_PTR, *eff = (BOOL *)GARBAGE_PTR;
    HRESULT *err = (HRESULT *)GARBAGE_PTR;
    DWORD k;
    if (by_area) CHECK_HR(server->lpVtbl->GetEnableStateByArea(server, count, names, &en, &eff, &err), expected);
    else CHECK_HR(server->lpVtbl->GetEnableStateBySource(server, count, names, &en, &eff, &err), expected);
    CHECK(en && en != GARBAGE_PTR && eff && eff != GARBAGE_PTR && err && err != GARBAGE_PTR);
    if (!en || en == GARBAGE_PTR || !eff || eff == GARBAGE_PTR || !err || err == GARBAGE_PTR) return;
    for (k = 0; k < count; k++) {
        CHECK(en[k] == enabled[k] && eff[k] == effective[k]);
        CHECK_HR(err[k], errors[k]);
    }
    CoTaskMemFree(en);
    CoTaskMemFree(eff);
    CoTaskMemFree(err);
}

static void check_enable(IOPCEventServer2 *server) {
    LPWSTR areas[2], sources[3];
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    static const BOOL en1[3] = {TRUE, TRUE, FALSE}, eff1[3] = {TRUE, FALSE, FALSE};
    static const HRESULT err1[3] = {S_OK, S_OK, E_INVALIDARG};
    static const BOOL en2[2] = {FALSE, TRUE};
    static const BOOL all[2] = {TRUE, TRUE};
    static const HRESULT ok[3] = {S_OK, S_OK, S_OK};
    /* Tank 2's area off (and an area the server does not know). */
    areas[0] = (LPWSTR)W(AE_AREA_NAMES[2]);
    areas[1] = (LPWSTR)W("Plant.Nowhere");
    CHECK_HR(server->lpVtbl->DisableConditionByArea2(server, 2, areas, &errors), S_FALSE);
    CHECK(errors && errors != GARBAGE_PTR);
    if (errors && errors != GARBAGE_PTR) {
        CHECK_HR(errors[0], S_OK);
        CHECK_HR(errors[1], E_INVALIDARG);
        CoTaskMemFree(errors);
    }
    /* Tank 2's level: enabled itself, not effectively; an unknown source. */
    sources[0] = (LPWSTR)W(AE_SOURCE_NAMES[0]);
    sources[1] = (LPWSTR)W(AE_SOURCE_NAMES[2]);
    sources[2] = (LPWSTR)W("Plant.Nowhere.Level");
    check_enable_state(server, 0, 3, sources, en1, eff1, err1, S_FALSE);
    /* Version 1: one source off, one result for the call. */
    sources[0] = (LPWSTR)W(AE_SOURCE_NAMES[1]);
    CHECK_HR(server->lpVtbl->DisableConditionBySource(server, 1, sources), S_OK);
    sources[1] = (LPWSTR)W(AE_SOURCE_NAMES[0]);
    check_enable_state(server, 0, 2, sources, en2, en2, ok, S_OK);
    sources[2] = (LPWSTR)W("Plant.Nowhere.Level");
    CHECK_HR(server->lpVtbl->DisableConditionBySource(server, 1, sources + 2), E_INVALIDARG);
    /* Tank 2's area on again. */
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->EnableConditionByArea2(server, 1, areas, &errors), S_OK);
    if (errors && errors != GARBAGE_PTR) {
        CHECK_HR(errors[0], S_OK);
        CoTaskMemFree(errors);
    } else {
        CHECK(0);
    }
    areas[1] = (LPWSTR)W(AE_AREA_NAMES[0]);
    check_enable_state(server, 1, 2, areas, all, all, ok, S_OK);
}

static void check_keep_alive(IOPCEventSubscriptionMgt *sub) {
    IOPCEventSubscriptionMgt2 *sub2 = NULL;
    DWORD revised = GARBAGE_U32, time = GARBAGE_U32;
    CHECK_HR(sub->lpVtbl->QueryInterface(sub, &IID_IOPCEventSubscriptionMgt2, (void **)&sub2), S_OK);
    if (!sub2) return;
    CHECK_HR(sub2->lpVtbl->GetKeepAlive(sub2, &time), S_OK);
    CHECK(time == 0);
    CHECK_HR(sub2->lpVtbl->SetKeepAlive(sub2, AE_KEEP_ALIVE, &revised), OPC_S_INVALIDKEEPALIVETIME_AE);
    CHECK(revised == AE_REVISED_KEEP_ALIVE);
    time = GARBAGE_U32;
    CHECK_HR(sub2->lpVtbl->GetKeepAlive(sub2, &time), S_OK);
    CHECK(time == AE_REVISED_KEEP_ALIVE);
    revised = GARBAGE_U32;
    CHECK_HR(sub2->lpVtbl->SetKeepAlive(sub2, AE_KEEP_ALIVE + 1, &revised), E_INVALIDARG);
    CHECK(revised == 0);
    time = GARBAGE_U32;
    CHECK_HR(sub2->lpVtbl->GetKeepAlive(sub2, &time), S_OK);
    CHECK(time == AE_REVISED_KEEP_ALIVE);
    revised = GARBAGE_U32;
    CHECK_HR(sub2->lpVtbl->SetKeepAlive(sub2, 0, &revised), S_OK);
    CHECK(revised == 0);
    sub2->lpVtbl->Release(sub2);
}

/* AckCondition: strings, arrays of strings, FILETIMEs and cookies, each element answered by the
 * server as it arrived (ae.h); an acknowledger or comment not as expected refuses the call. */
static void check_ack(IOPCEventServer2 *server) {
    LPWSTR sources[AE_ACKS], conditions[AE_ACKS];
    FILETIME times[AE_ACKS];
    DWORD cookies[AE_ACKS], k;
    HRESULT *errors = (HRESULT *)GARBAGE_PTR;
    LPWSTR acknowledger = task_utf8(AE_ACKNOWLEDGER), comment = task_utf8(AE_ACK_COMMENT);
    for (k = 0; k < AE_ACKS; k++) {
        AeAck a = ae_ack(k);
        sources[k] = task_utf8(a.source);
        conditions[k] = task_utf8(a.condition);
        times[k] = a.active_time;
        cookies[k] = a.cookie;
    }
    CHECK_HR(server->lpVtbl->AckCondition(server, AE_ACKS, acknowledger, comment, sources, conditions, times, cookies,
                                          &errors),
             S_FALSE);
    CHECK(errors && errors != GARBAGE_PTR);
    if (errors && errors != GARBAGE_PTR) {
        for (k = 0; k < AE_ACKS; k++) CHECK_HR(errors[k], ae_ack(k).result);
        CoTaskMemFree(errors);
    }
    /* The first element alone: not the count the server expects, refused, nothing comes back. */
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->AckCondition(server, 1, acknowledger, comment, sources, conditions, times, cookies, &errors),
             E_INVALIDARG);
    CHECK(errors == NULL);
    /* Another comment (an empty string): refused, nothing comes back. */
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->AckCondition(server, AE_ACKS, acknowledger, (LPWSTR)W(""), sources, conditions, times,
                                          cookies, &errors),
             E_INVALIDARG);
    CHECK(errors == NULL);
    /* One element's active time a second later: the server sees it. */
    times[0] = test_time(5);
    errors = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->AckCondition(server, AE_ACKS, acknowledger, comment, sources, conditions, times, cookies,
                                          &errors),
             S_FALSE);
    if (errors && errors != GARBAGE_PTR) {
        CHECK_HR(errors[0], E_INVALIDARG);
        for (k = 1; k < AE_ACKS; k++) CHECK_HR(errors[k], ae_ack(k).result);
        CoTaskMemFree(errors);
    } else {
        CHECK(0);
    }
    for (k = 0; k < AE_ACKS; k++) {
        CoTaskMemFree(sources[k]);
        CoTaskMemFree(conditions[k]);
    }
    CoTaskMemFree(acknowledger);
    CoTaskMemFree(comment);
}

static void check_subscription(IOPCEventServer2 *server) {
    IOPCEventSubscriptionMgt *sub = NULL;
    IConnectionPointContainer *cpc = NULL;
    IConnectionPoint *cp = NULL;
    DWORD revised_buffer = GARBAGE_U32, revised_max = GARBAGE_U32, buffer = GARBAGE_U32, max = GARBAGE_U32;
    DWORD cookie = GARBAGE_U32, type = GARBAGE_U32, ncat = GARBAGE_U32, low = GARBAGE_U32, high = GARBAGE_U32;
    DWORD nareas = GARBAGE_U32, nsources = GARBAGE_U32, *cats = (DWORD *)GARBAGE_PTR, k, new_max = 20;
    LPWSTR *areas = (LPWSTR *)GARBAGE_PTR, *sources = (LPWSTR *)GARBAGE_PTR;
    LPWSTR filter_areas[AE_FILTER_AREAS], filter_sources[AE_FILTER_SOURCES];
    BOOL active = (BOOL)GARBAGE_U32, inactive = FALSE;
    OPCHANDLE client = GARBAGE_U32;
    IUnknown *unk = (IUnknown *)GARBAGE_PTR;

    /* Not as the server expects: refused, nothing comes back. */
    CHECK_HR(server->lpVtbl->CreateEventSubscription(server, TRUE, AE_BUFFER_TIME, AE_MAX_SIZE + 1,
                                                     AE_CLIENT_SUBSCRIPTION, &IID_IOPCEventSubscriptionMgt, &unk,
                                                     &revised_buffer, &revised_max),
             E_INVALIDARG);
    CHECK(unk == NULL && revised_buffer == 0 && revised_max == 0);
    CHECK_HR(server->lpVtbl->CreateEventSubscription(server, TRUE, AE_BUFFER_TIME, AE_MAX_SIZE, AE_CLIENT_SUBSCRIPTION,
                                                     &IID_IOPCEventSubscriptionMgt, (IUnknown **)&sub,
                                                     &revised_buffer, &revised_max),
             S_OK);
    CHECK(revised_buffer == AE_REVISED_BUFFER_TIME && revised_max == AE_REVISED_MAX_SIZE);
    if (!sub) return;
    CHECK_HR(sub->lpVtbl->GetState(sub, &active, &buffer, &max, &client), S_OK);
    CHECK(active == TRUE && buffer == AE_REVISED_BUFFER_TIME && max == AE_REVISED_MAX_SIZE &&
          client == AE_CLIENT_SUBSCRIPTION);

    /* The filter: set, then read back. */
    for (k = 0; k < AE_FILTER_AREAS; k++) filter_areas[k] = (LPWSTR)W(AE_AREA_NAMES[1 + k]);
    filter_sources[0] = (LPWSTR)W(AE_SOURCE_NAMES[0]);
    CHECK_HR(sub->lpVtbl->SetFilter(sub, AE_CONDITION_EVENT | AE_TRACKING_EVENT, AE_FILTER_CATEGORIES,
                                    (DWORD *)AE_FILTER_CATEGORY_IDS, AE_FILTER_LOW, AE_FILTER_HIGH, AE_FILTER_AREAS,
                                    filter_areas, AE_FILTER_SOURCES, filter_sources),
             S_OK);
    CHECK_HR(sub->lpVtbl->SetFilter(sub, AE_CONDITION_EVENT | AE_TRACKING_EVENT, AE_FILTER_CATEGORIES,
                                    (DWORD *)AE_FILTER_CATEGORY_IDS, AE_FILTER_LOW, AE_FILTER_HIGH, 1,
                                    filter_areas + 1, AE_FILTER_SOURCES, filter_sources),
             E_INVALIDARG);
    CHECK_HR(sub->lpVtbl->GetFilter(sub, &type, &ncat, &cats, &low, &high, &nareas, &areas, &nsources, &sources), S_OK);
    CHECK(type == (AE_CONDITION_EVENT | AE_TRACKING_EVENT) && low == AE_FILTER_LOW && high == AE_FILTER_HIGH);
    CHECK(ncat == AE_FILTER_CATEGORIES && nareas == AE_FILTER_AREAS && nsources == AE_FILTER_SOURCES);
    if (ncat == AE_FILTER_CATEGORIES && cats && cats != GARBAGE_PTR) {
        CHECK(memcmp(cats, AE_FILTER_CATEGORY_IDS, sizeof AE_FILTER_CATEGORY_IDS) == 0);
        CoTaskMemFree(cats);
    } else {
        CHECK(0);
    }
    if (nareas == AE_FILTER_AREAS && areas && areas != GARBAGE_PTR) {
        for (k = 0; k < nareas; k++) {
            CHECK(is_utf8(areas[k], AE_AREA_NAMES[1 + k]));
            CoTaskMemFree(areas[k]);
        }
        CoTaskMemFree(areas);
    } else {
        CHECK(0);
    }
    if (nsources == AE_FILTER_SOURCES && sources && sources != GARBAGE_PTR) {
        CHECK(is_utf8(sources[0], AE_SOURCE_NAMES[0]));
        CoTaskMemFree(sources[0]);
        CoTaskMemFree(sources);
    } else {
        CHECK(0);
    }

    /* The sink through the subscription's connection point, and the events of a refresh. */
    memset(&sink, 0, sizeof sink);
    sink.iface.lpVtbl = &sink_vtbl;
    sink.refs = 1;
    sink.called = CreateEventW(NULL, FALSE, FALSE, NULL);
    CHECK_HR(sub->lpVtbl->Refresh(sub, 1), CONNECT_E_NOCONNECTION);
    CHECK_HR(sub->lpVtbl->QueryInterface(sub, &IID_IConnectionPointContainer, (void **)&cpc), S_OK);
    if (cpc) CHECK_HR(cpc->lpVtbl->FindConnectionPoint(cpc, &IID_IOPCEventSink, &cp), S_OK);
    if (cp) {
        CHECK_HR(cp->lpVtbl->Advise(cp, (IUnknown *)&sink.iface, &cookie), S_OK);
        CHECK(cookie == 1);
        CHECK_HR(sub->lpVtbl->Refresh(sub, 2), E_INVALIDARG);
        CHECK_HR(sub->lpVtbl->Refresh(sub, cookie), S_OK);
        /* The server's thread calls back; 60 s only bound a broken run. */
        CHECK(WaitForSingleObject(sink.called, 60000) == WAIT_OBJECT_0);
        CHECK(sink.calls == 1);
        CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie), S_OK);
        CHECK_HR(cp->lpVtbl->Unadvise(cp, cookie), CONNECT_E_NOCONNECTION);
        cp->lpVtbl->Release(cp);
    }
    if (cpc) cpc->lpVtbl->Release(cpc);

    /* IOPCEventSubscriptionMgt2: the keep-alive time asked, revised (a success code other than S_OK),
     * read back; another time is not what the server expects. */
    check_keep_alive(sub);

    /* SetState: NULL for what stays (unique in-pointers), two changes and a new client handle. */
    revised_buffer = revised_max = GARBAGE_U32;
    CHECK_HR(sub->lpVtbl->SetState(sub, &inactive, NULL, &new_max, AE_CLIENT_SUBSCRIPTION + 1, &revised_buffer,
                                   &revised_max),
             S_OK);
    CHECK(revised_buffer == AE_REVISED_BUFFER_TIME && revised_max == new_max);
    CHECK_HR(sub->lpVtbl->GetState(sub, &active, &buffer, &max, &client), S_OK);
    CHECK(active == FALSE && buffer == AE_REVISED_BUFFER_TIME && max == new_max &&
          client == AE_CLIENT_SUBSCRIPTION + 1);
    sub->lpVtbl->Release(sub);
    CloseHandle(sink.called);
    sink.called = NULL;
}

/* Whether `e` enumerates exactly the UTF-8 texts `want[0..count)`; releases it. */
static int enumerates(IEnumString *e, const char *const *want, ULONG count) {
    LPOLESTR got[4];
    ULONG fetched = GARBAGE_U32, k;
    HRESULT hr;
    int same;
    if (!e || e == GARBAGE_PTR) return 0;
    memset(got, 0, sizeof got);
    hr = e->lpVtbl->Next(e, 4, got, &fetched);
    same = hr == (count == 4 ? S_OK : S_FALSE) && fetched == count;
    for (k = 0; k < fetched && k < 4; k++) {
        same &= k < count && is_utf8(got[k], want[k]);
        CoTaskMemFree(got[k]);
    }
    e->lpVtbl->Release(e);
    return same;
}

/* IOPCEventAreaBrowser: down the tree and up, areas and sources by filters, qualified names. */
static void check_area_browser(IOPCEventServer2 *server) {
    static const char *const root[1] = {"Plant"};
    static const char *const tanks[2] = {"Tank1", "Tank2 \xe2\x82\xac"};
    static const char *const tank2[1] = {"Tank2 \xe2\x82\xac"};
    static const char *const tank1_sources[2] = {"Level", "Temp"};
    IOPCEventAreaBrowser *b = NULL;
    IEnumString *e = (IEnumString *)GARBAGE_PTR;
    LPWSTR name = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->CreateAreaBrowser(server, &IID_IOPCEventAreaBrowser, (IUnknown **)&b), S_OK);
    if (!b) return;
    CHECK_HR(b->lpVtbl->BrowseOPCAreas(b, OPC_AREA, W(""), &e), S_OK);
    CHECK(enumerates(e, root, 1));
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->BrowseOPCAreas(b, OPC_SOURCE, W("*"), &e), S_FALSE); /* the root has no sources */
    CHECK(enumerates(e, NULL, 0));
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCAE_BROWSE_DOWN, W("Nowhere")), E_INVALIDARG);
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCAE_BROWSE_DOWN, W("Plant")), S_OK);
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->BrowseOPCAreas(b, OPC_AREA, W("Tank*"), &e), S_OK);
    CHECK(enumerates(e, tanks, 2));
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->BrowseOPCAreas(b, OPC_AREA, W("*\xe2\x82\xac"), &e), S_OK);
    CHECK(enumerates(e, tank2, 1));
    CHECK_HR(b->lpVtbl->GetQualifiedAreaName(b, W(tanks[1]), &name), S_OK);
    CHECK(name != GARBAGE_PTR && is_utf8(name, AE_AREA_NAMES[2]));
    if (name != GARBAGE_PTR) CoTaskMemFree(name);
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCAE_BROWSE_DOWN, W("Tank1")), S_OK);
    e = (IEnumString *)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->BrowseOPCAreas(b, OPC_SOURCE, W("*"), &e), S_OK);
    CHECK(enumerates(e, tank1_sources, 2));
    name = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetQualifiedSourceName(b, W("Temp"), &name), S_OK);
    CHECK(name != GARBAGE_PTR && is_utf8(name, AE_SOURCE_NAMES[1]));
    if (name != GARBAGE_PTR) CoTaskMemFree(name);
    name = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(b->lpVtbl->GetQualifiedSourceName(b, W("Pressure"), &name), E_INVALIDARG);
    CHECK(name == NULL);
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCAE_BROWSE_UP, W("")), S_OK);
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCAE_BROWSE_UP, W("")), S_OK);
    CHECK_HR(b->lpVtbl->ChangeBrowsePosition(b, OPCAE_BROWSE_UP, W("")), E_FAIL);
    b->lpVtbl->Release(b);
}

int main(void) {
    OpcServerRegistration reg;
    IOPCEventServer2 *server = NULL;
    int waited;

    beside_this_program(server_path, L"opc_ae_test_server.exe");
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    CHECK_HR(use_opccomn_proxy_stub_for(AE_IIDS, AE_IID_COUNT), S_OK);
    memset(&reg, 0, sizeof reg);
    reg.struct_size = sizeof reg;
    reg.server_type = OPC_SERVER_TYPE_LOCAL;
    reg.clsid = CLSID_AeTestServer;
    reg.prog_id = L"Oop.AeServer.1";
    reg.user_type = L"opccomn A&E tables test server";
    reg.module_path = server_path;
    CHECK_HR(OpcRegisterServer(&reg, NULL), S_OK);

    CHECK_HR(CoCreateInstance(&CLSID_AeTestServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCEventServer2, (void **)&server),
             S_OK);
    if (server) {
        check_status(server);
        check_bound(server);
        check_categories(server);
        check_condition_state(server);
        check_enable(server);
        check_ack(server);
        check_subscription(server);
        check_area_browser(server);
        server->lpVtbl->Release(server);
    }
    /* The server exits once its objects are gone (its linger is 100 ms; 10 s bound a broken run). */
    for (waited = 0; waited < 100 && process_running(L"opc_ae_test_server.exe") == 1; waited++) Sleep(100);
    CHECK(process_running(L"opc_ae_test_server.exe") == 0);
    /* The server let go of the sink before it ended. */
    CHECK(sink.refs == 1);
    CHECK_HR(OpcUnregisterServer(&reg, NULL), S_OK);
    CoUninitialize();
    return test_summary("test_ae_tables");
}
