/* opccomn.dll's proxy/stub of the Alarms & Events 1.10 interfaces (the NDR tables tools/gen-proxy.py
 * makes from idl/opc_ae.idl, with the checks generated from the same IDL) across processes, under the
 * real COM runtime (Wine in CI): this client and the EXE server ae_server.c, both with opccomn.dll's
 * proxy/stub as theirs for the A&E interfaces (registered per process, classic_oop.h). Every value
 * crosses the wire and is checked on the other side: the server answers a request it did not receive
 * as sent with an error. A count beyond its bound never leaves the client.
 *
 * Covered: IOPCEventServer::GetStatus (OPCEVENTSERVERSTATUS and its string), QueryAvailableFilters,
 * QueryEventCategories ([out, size_is(,*n)] DWORD ** and LPWSTR **), QueryConditionNames,
 * QuerySubConditionNames, QuerySourceConditions (names, none: NULL arrays), QueryEventAttributes per
 * category (IDs, descriptions, VARTYPE **), TranslateToItemIDs ([out, size_is(,n)] item IDs, node
 * names and CLSIDs per attribute), CreateEventSubscription (iid_is), GetConditionState
 * (OPCCONDITIONSTATE with its arrays, VARIANTs and a NULL string), DisableConditionBySource,
 * EnableConditionBySource, EnableConditionByArea, DisableConditionByArea;
 * IOPCEventServer2::DisableConditionByArea2, EnableConditionByArea2, GetEnableStateBySource,
 * GetEnableStateByArea ([in, string, size_is(n)] LPWSTR * with per-element results);
 * IOPCEventSubscriptionMgt::GetState, SetState (unique in-pointers), SetFilter, GetFilter,
 * SelectReturnedAttributes, GetReturnedAttributes (per category), Refresh, CancelRefresh;
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
    static const BOOL all[2] = {TRUE, TRUE}, none[2] = {FALSE, FALSE}, off_area[2] = {TRUE, FALSE};
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
    CHECK_RESULTS(errors, S_OK);
    areas[1] = (LPWSTR)W(AE_AREA_NAMES[0]);
    check_enable_state(server, 1, 2, areas, all, all, ok, S_OK);
    /* Version 1 by area: Tank 1's area off, its sources not effectively enabled, on again; the source
     * turned off above on by source; an unknown area refuses the call. */
    areas[0] = (LPWSTR)W(AE_AREA_NAMES[1]);
    CHECK_HR(server->lpVtbl->DisableConditionByArea(server, 1, areas), S_OK);
    check_enable_state(server, 1, 1, areas, en2, en2, ok, S_OK);
    sources[0] = (LPWSTR)W(AE_SOURCE_NAMES[0]);
    sources[1] = (LPWSTR)W(AE_SOURCE_NAMES[1]);
    check_enable_state(server, 0, 2, sources, off_area, none, ok, S_OK);
    CHECK_HR(server->lpVtbl->EnableConditionByArea(server, 1, areas), S_OK);
    CHECK_HR(server->lpVtbl->EnableConditionBySource(server, 1, sources + 1), S_OK);
    check_enable_state(server, 0, 2, sources, all, all, ok, S_OK);
    check_enable_state(server, 1, 1, areas, all, all, ok, S_OK);
    areas[1] = (LPWSTR)W("Plant.Nowhere");
    CHECK_HR(server->lpVtbl->EnableConditionByArea(server, 1, areas + 1), E_INVALIDARG);
    CHECK_HR(server->lpVtbl->DisableConditionByArea(server, 1, areas + 1), E_INVALIDARG);
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

/* A names reply (QueryConditionNames, QuerySubConditionNames, QuerySourceConditions): `hr` is
 * `expected` and the names the call left in `*pcount` and `*pnames` (read after it) are the UTF-8
 * texts `want[0..n)` (none: a NULL array); frees them. */
static void check_names(HRESULT hr, HRESULT expected, const DWORD *pcount, LPWSTR *const *pnames,
                        const char *const *want, DWORD n) {
    DWORD k, count = *pcount;
    LPWSTR *names = *pnames;
    CHECK_HR(hr, expected);
    CHECK(count == n && names != GARBAGE_PTR && (n ? names != NULL : names == NULL));
    if (count != n || !names || names == GARBAGE_PTR) return;
    for (k = 0; k < n; k++) {
        CHECK(is_utf8(names[k], want[k]));
        CoTaskMemFree(names[k]);
    }
    CoTaskMemFree(names);
}

/* QueryAvailableFilters and the condition queries: per category, per condition, per source; a name
 * or category the server does not have is refused and nothing comes back. */
static void check_condition_queries(IOPCEventServer2 *server) {
    DWORD mask = GARBAGE_U32, count;
    LPWSTR *names;
    int i;
    CHECK_HR(server->lpVtbl->QueryAvailableFilters(server, &mask), S_OK);
    CHECK(mask == AE_FILTER_MASK);
    for (i = 0; i < AE_CATEGORIES; i++) {
        count = GARBAGE_U32;
        names = (LPWSTR *)GARBAGE_PTR;
        check_names(server->lpVtbl->QueryConditionNames(server, AE_CATEGORY_IDS[i], &count, &names),
                    S_OK, &count, &names, AE_CONDITION_NAMES, i == 0 ? AE_CONDITIONS : 0);
    }
    count = GARBAGE_U32;
    names = (LPWSTR *)GARBAGE_PTR;
    check_names(server->lpVtbl->QueryConditionNames(server, 1002, &count, &names), E_INVALIDARG, &count, &names, NULL,
                0);
    count = GARBAGE_U32;
    names = (LPWSTR *)GARBAGE_PTR;
    check_names(server->lpVtbl->QuerySubConditionNames(server, (LPWSTR)W(AE_CONDITION_NAMES[0]), &count, &names),
                S_OK, &count, &names, AE_SC_NAMES, AE_SUBCONDITIONS);
    count = GARBAGE_U32;
    names = (LPWSTR *)GARBAGE_PTR;
    check_names(server->lpVtbl->QuerySubConditionNames(server, (LPWSTR)W(AE_CONDITION_NAMES[1]), &count, &names),
                S_OK, &count, &names, NULL, 0);
    count = GARBAGE_U32;
    names = (LPWSTR *)GARBAGE_PTR;
    check_names(server->lpVtbl->QuerySubConditionNames(server, (LPWSTR)W("Temperature"), &count, &names),
                E_INVALIDARG, &count, &names, NULL, 0);
    for (i = 0; i < AE_SOURCES; i++) {
        count = GARBAGE_U32;
        names = (LPWSTR *)GARBAGE_PTR;
        check_names(server->lpVtbl->QuerySourceConditions(server, (LPWSTR)W(AE_SOURCE_NAMES[i]), &count, &names),
                    S_OK, &count, &names, AE_CONDITION_NAMES + AE_SOURCE_CONDITION[i], 1);
    }
    count = GARBAGE_U32;
    names = (LPWSTR *)GARBAGE_PTR;
    check_names(server->lpVtbl->QuerySourceConditions(server, (LPWSTR)W("Plant.Tank1"), &count, &names),
                E_INVALIDARG, &count, &names, NULL, 0);
}

/* QueryEventAttributes of each category (the IDs, descriptions and VARTYPEs of AE_EVENT_ATTR_TABLE,
 * none for the third) and of a category the server does not have (refused, nothing comes back). */
static void check_event_attributes(IOPCEventServer2 *server) {
    DWORD count, *ids;
    LPWSTR *texts;
    VARTYPE *types;
    int rows[AE_EVENT_ATTRS], n, i, k;
    for (i = 0; i <= AE_CATEGORIES; i++) {
        DWORD category = i < AE_CATEGORIES ? AE_CATEGORY_IDS[i] : 1002;
        n = ae_category_attrs(category, rows);
        count = GARBAGE_U32;
        ids = (DWORD *)GARBAGE_PTR;
        texts = (LPWSTR *)GARBAGE_PTR;
        types = (VARTYPE *)GARBAGE_PTR;
        CHECK_HR(server->lpVtbl->QueryEventAttributes(server, category, &count, &ids, &texts, &types),
                 n < 0 ? E_INVALIDARG : S_OK);
        if (n <= 0) {
            CHECK(count == 0 && ids == NULL && texts == NULL && types == NULL);
            continue;
        }
        CHECK(count == (DWORD)n && ids && ids != GARBAGE_PTR && texts && texts != GARBAGE_PTR && types &&
              types != GARBAGE_PTR);
        if (count != (DWORD)n || !ids || ids == GARBAGE_PTR || !texts || texts == GARBAGE_PTR || !types ||
            types == GARBAGE_PTR)
            continue;
        for (k = 0; k < n; k++) {
            CHECK(ids[k] == AE_EVENT_ATTR_TABLE[rows[k]].id);
            CHECK(is_utf8(texts[k], AE_EVENT_ATTR_TABLE[rows[k]].desc));
            CHECK(types[k] == AE_EVENT_ATTR_TABLE[rows[k]].type);
            CoTaskMemFree(texts[k]);
        }
        CoTaskMemFree(ids);
        CoTaskMemFree(texts);
        CoTaskMemFree(types);
    }
}

/* TranslateToItemIDs: per attribute asked, its item ID, node name (an empty one among them) and
 * CLSID; another sub-condition is refused and nothing comes back. */
static void check_translate(IOPCEventServer2 *server) {
    LPWSTR *items = (LPWSTR *)GARBAGE_PTR, *nodes = (LPWSTR *)GARBAGE_PTR;
    CLSID *clsids = (CLSID *)GARBAGE_PTR;
    LPWSTR source = task_utf8(AE_SOURCE_NAMES[0]), condition = task_utf8(AE_CONDITION);
    LPWSTR sub = task_utf8(AE_SC_NAMES[1]), other = task_utf8(AE_SC_NAMES[0]);
    DWORD k;
    CHECK_HR(server->lpVtbl->TranslateToItemIDs(server, source, AE_CATEGORY_IDS[0], condition, sub, AE_TRANSLATED,
                                                (DWORD *)AE_TRANSLATE_IDS, &items, &nodes, &clsids),
             S_OK);
    CHECK(items && items != GARBAGE_PTR && nodes && nodes != GARBAGE_PTR && clsids && clsids != GARBAGE_PTR);
    if (items && items != GARBAGE_PTR && nodes && nodes != GARBAGE_PTR && clsids && clsids != GARBAGE_PTR) {
        for (k = 0; k < AE_TRANSLATED; k++) {
            const AeEventAttr *a = &AE_EVENT_ATTR_TABLE[ae_event_attr(AE_CATEGORY_IDS[0], AE_TRANSLATE_IDS[k])];
            CHECK(is_utf8(items[k], a->item_id));
            CHECK(is_utf8(nodes[k], a->node));
            CHECK(IsEqualCLSID(&clsids[k], &a->clsid));
            CoTaskMemFree(items[k]);
            CoTaskMemFree(nodes[k]);
        }
        CoTaskMemFree(items);
        CoTaskMemFree(nodes);
        CoTaskMemFree(clsids);
    }
    items = nodes = (LPWSTR *)GARBAGE_PTR;
    clsids = (CLSID *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->TranslateToItemIDs(server, source, AE_CATEGORY_IDS[0], condition, other, AE_TRANSLATED,
                                                (DWORD *)AE_TRANSLATE_IDS, &items, &nodes, &clsids),
             E_INVALIDARG);
    CHECK(items == NULL && nodes == NULL && clsids == NULL);
    /* Attribute 1 is not one of the tracking category's: refused. */
    items = nodes = (LPWSTR *)GARBAGE_PTR;
    clsids = (CLSID *)GARBAGE_PTR;
    CHECK_HR(server->lpVtbl->TranslateToItemIDs(server, source, AE_CATEGORY_IDS[1], condition, sub, AE_TRANSLATED,
                                                (DWORD *)AE_TRANSLATE_IDS, &items, &nodes, &clsids),
             E_INVALIDARG);
    CHECK(items == NULL && nodes == NULL && clsids == NULL);
    CoTaskMemFree(source);
    CoTaskMemFree(condition);
    CoTaskMemFree(sub);
    CoTaskMemFree(other);
}

/* The attributes category `category` returns (GetReturnedAttributes) are `want[0..n)`. */
static void check_returned(IOPCEventSubscriptionMgt *sub, DWORD category, HRESULT expected, const DWORD *want,
                           DWORD n) {
    DWORD count = GARBAGE_U32, *ids = (DWORD *)GARBAGE_PTR, k;
    CHECK_HR(sub->lpVtbl->GetReturnedAttributes(sub, category, &count, &ids), expected);
    CHECK(count == n && ids != GARBAGE_PTR && (n ? ids != NULL : ids == NULL));
    if (count != n || !ids || ids == GARBAGE_PTR) return;
    for (k = 0; k < n; k++) CHECK(ids[k] == want[k]);
    CoTaskMemFree(ids);
}

/* SelectReturnedAttributes and GetReturnedAttributes: none selected at first, a selection in the
 * client's order read back, a selection the server refuses leaves it as it was. */
static void check_returned_attributes(IOPCEventSubscriptionMgt *sub) {
    static const DWORD bad[2] = {2, 1}; /* 1 is not an attribute of the tracking category */
    static const DWORD one[1] = {2};
    check_returned(sub, AE_CATEGORY_IDS[0], S_OK, NULL, 0);
    CHECK_HR(sub->lpVtbl->SelectReturnedAttributes(sub, AE_CATEGORY_IDS[0], AE_SELECTED, (DWORD *)AE_SELECTED_IDS),
             S_OK);
    check_returned(sub, AE_CATEGORY_IDS[0], S_OK, AE_SELECTED_IDS, AE_SELECTED);
    check_returned(sub, AE_CATEGORY_IDS[1], S_OK, NULL, 0);
    CHECK_HR(sub->lpVtbl->SelectReturnedAttributes(sub, AE_CATEGORY_IDS[1], 2, (DWORD *)bad), E_INVALIDARG);
    CHECK_HR(sub->lpVtbl->SelectReturnedAttributes(sub, AE_CATEGORY_IDS[1], 1, (DWORD *)one), S_OK);
    check_returned(sub, AE_CATEGORY_IDS[1], S_OK, one, 1);
    check_returned(sub, AE_CATEGORY_IDS[0], S_OK, AE_SELECTED_IDS, AE_SELECTED);
    CHECK_HR(sub->lpVtbl->SelectReturnedAttributes(sub, 1002, 1, (DWORD *)one), E_INVALIDARG);
    check_returned(sub, 1002, E_INVALIDARG, NULL, 0);
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

    check_returned_attributes(sub);

    /* The sink through the subscription's connection point, and the events of a refresh. */
    memset(&sink, 0, sizeof sink);
    sink.iface.lpVtbl = &sink_vtbl;
    sink.refs = 1;
    sink.called = CreateEventW(NULL, FALSE, FALSE, NULL);
    CHECK_HR(sub->lpVtbl->Refresh(sub, 1), CONNECT_E_NOCONNECTION);
    CHECK_HR(sub->lpVtbl->CancelRefresh(sub, 1), CONNECT_E_NOCONNECTION);
    CHECK_HR(sub->lpVtbl->QueryInterface(sub, &IID_IConnectionPointContainer, (void **)&cpc), S_OK);
    if (cpc) CHECK_HR(cpc->lpVtbl->FindConnectionPoint(cpc, &IID_IOPCEventSink, &cp), S_OK);
    if (cp) {
        CHECK_HR(cp->lpVtbl->Advise(cp, (IUnknown *)&sink.iface, &cookie), S_OK);
        CHECK(cookie == 1);
        /* No refresh under way: nothing to cancel on this connection, and no other connection. */
        CHECK_HR(sub->lpVtbl->CancelRefresh(sub, cookie), E_FAIL);
        CHECK_HR(sub->lpVtbl->CancelRefresh(sub, cookie + 1), E_INVALIDARG);
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
        check_condition_queries(server);
        check_event_attributes(server);
        check_translate(server);
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
