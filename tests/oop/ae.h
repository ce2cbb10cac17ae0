/* Shared by the cross-process test of the Alarms & Events proxy/stub (test_ae_tables.c, the client)
 * and its EXE server (ae_server.c): the class, what the server serves, and the events it sends. The
 * types and IIDs come from the header widl generates from idl/opc_ae.idl (opc_ae_idl.h; this file
 * defines the IIDs, so one translation unit per program). Windows only. */
#ifndef OPCCOMN_AE_H
#define OPCCOMN_AE_H

#include "classic_oop.h"

#include <initguid.h>
#include <ocidl.h>

#include "opc_ae_idl.h"

/* The test A&E server (ae_server.c, LocalServer32). */
static const CLSID CLSID_AeTestServer = {0xC3000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0xAE, 0x02}};

/* The A&E interfaces opccomn.dll's proxy/stub serves in these two processes. */
static const IID *const AE_IIDS[] = {&IID_IOPCEventServer,  &IID_IOPCEventSubscriptionMgt, &IID_IOPCEventAreaBrowser,
                                     &IID_IOPCEventSink,    &IID_IOPCEventServer2,         &IID_IOPCEventSubscriptionMgt2};
#define AE_IID_COUNT (sizeof AE_IIDS / sizeof AE_IIDS[0])

/* Event types (the A&E specification). */
#define AE_SIMPLE_EVENT 1u
#define AE_TRACKING_EVENT 2u
#define AE_CONDITION_EVENT 4u
#define AE_ALL_EVENTS 7u

/* The server's status: its vendor text when its proxy/stub of the A&E interfaces is opccomn.dll's. */
#define AE_VENDOR_INFO "opccomn A&E test server \xe2\x82\xac"
#define AE_VENDOR_INFO_OTHER "proxy/stub not opccomn's"

/* The event categories (QueryEventCategories of AE_ALL_EVENTS). */
#define AE_CATEGORIES 3
static const DWORD AE_CATEGORY_IDS[AE_CATEGORIES] = {1001, 2001, 0x7FFFFFFF};
static const char *const AE_CATEGORY_TEXTS[AE_CATEGORIES] = {"Level \xc3\xa4\xc3\xb6\xc3\xbc", "Operator process change",
                                                            "Vendor \xf0\x9f\x98\x80"};

/* The areas and sources (EnableConditionByArea2, GetEnableStateBySource, the area browser). */
#define AE_AREAS 3
static const char *const AE_AREA_NAMES[AE_AREAS] = {"Plant", "Plant.Tank1", "Plant.Tank2 \xe2\x82\xac"};
#define AE_SOURCES 3
static const char *const AE_SOURCE_NAMES[AE_SOURCES] = {"Plant.Tank1.Level", "Plant.Tank1.Temp",
                                                        "Plant.Tank2 \xe2\x82\xac.Level"};
static const int AE_SOURCE_AREA[AE_SOURCES] = {1, 1, 2}; /* the area of each source */
#define AE_E_UNKNOWN_NAME ((HRESULT)0xC0040007L)      /* an area or source the server does not know */

/* The subscription: what the client asks for (CreateEventSubscription), what the server revises. */
#define AE_BUFFER_TIME 1000u
#define AE_MAX_SIZE 50u
#define AE_CLIENT_SUBSCRIPTION 77u
#define AE_REVISED_BUFFER_TIME 1500u
#define AE_REVISED_MAX_SIZE 40u

/* The condition GetConditionState reads: its source, name and the attributes asked (the last
 * unknown). */
#define AE_CONDITION "Level"
#define AE_ATTRS_ASKED 3
static const DWORD AE_ATTR_IDS[AE_ATTRS_ASKED] = {1, 2, 99};
#define AE_E_INVALID_ATTR ((HRESULT)0xC0040209L)
#define AE_SUBCONDITIONS 2
static const char *const AE_SC_NAMES[AE_SUBCONDITIONS] = {"HI", "HIHI \xc3\x9f"};
static const char *const AE_SC_DEFINITIONS[AE_SUBCONDITIONS] = {"Level > 80", "Level > 95"};
static const DWORD AE_SC_SEVERITIES[AE_SUBCONDITIONS] = {500, 1000};
static const char *const AE_SC_DESCRIPTIONS[AE_SUBCONDITIONS] = {"High", "High high \xe2\x82\xac"};
#define AE_ATTR_TEXT "Tank 1 \xc3\x84\xc3\x96\xc3\x9c \xf0\x9f\x98\x80"
#define AE_ATTR_I4 (-12345)

/* The values of attributes 1 (VT_BSTR) and 2 (VT_I4); another is unknown (VT_EMPTY). */
static HRESULT ae_attribute(DWORD id, VARIANT *v) {
    VariantInit(v);
    if (id == 1) {
        V_VT(v) = VT_BSTR;
        V_BSTR(v) = bstr_utf8(AE_ATTR_TEXT);
        return V_BSTR(v) ? S_OK : E_OUTOFMEMORY;
    }
    if (id == 2) {
        V_VT(v) = VT_I4;
        V_I4(v) = AE_ATTR_I4;
        return S_OK;
    }
    return AE_E_INVALID_ATTR;
}

/* The filters the server supports (QueryAvailableFilters): by event, category, severity, area and
 * source, and a vendor bit. */
#define AE_FILTER_MASK 0x8000001Fu

/* The event attributes of each category (QueryEventAttributes) and the items behind them
 * (TranslateToItemIDs); the third category has none. An empty node name is the server's own. */
#define AE_EVENT_ATTRS 4
typedef struct AeEventAttr {
    DWORD category, id;
    const char *desc;
    VARTYPE type;
    const char *item_id, *node;
    CLSID clsid;
} AeEventAttr;
static const AeEventAttr AE_EVENT_ATTR_TABLE[AE_EVENT_ATTRS] = {
    {1001, 1, "Tank text \xc3\xa4\xc3\xb6\xc3\xbc", VT_BSTR, "Plant.Tank1.Level.Text \xe2\x82\xac", "",
     {0xC3000001, 0x5EED, 0x4001, {0x80, 1, 2, 3, 4, 5, 6, 7}}},
    {1001, 2, "Count", VT_I4, "Plant.Tank1.Level.Count", "host-\xc3\xa4",
     {0x01020304, 0x0506, 0x0708, {0x09, 0x0A, 0x0B, 0x0C, 0x0D, 0x0E, 0x0F, 0x10}}},
    {1001, 0x80000003u, "Rates \xf0\x9f\x98\x80", VT_ARRAY | VT_R8, "Plant.Tank1.Level.Rates", "\\\\plant-server",
     {0xFFFFFFFF, 0xFFFF, 0x0000, {0xFF, 0, 0xFF, 0, 0xFF, 0, 0xFF, 0}}},
    {2001, 2, "Setpoint", VT_UI2, "Plant.Tank2.Setpoint", "", {0}}};

/* The rows of AE_EVENT_ATTR_TABLE of category `category` in `rows` (AE_EVENT_ATTRS at most); their
 * count, or -1 for a category the server does not have. */
static int ae_category_attrs(DWORD category, int *rows) {
    int i, n = 0, known = 0;
    for (i = 0; i < AE_CATEGORIES; i++) known |= AE_CATEGORY_IDS[i] == category;
    if (!known) return -1;
    for (i = 0; i < AE_EVENT_ATTRS; i++)
        if (AE_EVENT_ATTR_TABLE[i].category == category) rows[n++] = i;
    return n;
}

/* The row of attribute `id` of category `category`, or -1. */
static int ae_event_attr(DWORD category, DWORD id) {
    int i;
    for (i = 0; i < AE_EVENT_ATTRS; i++)
        if (AE_EVENT_ATTR_TABLE[i].category == category && AE_EVENT_ATTR_TABLE[i].id == id) return i;
    return -1;
}

/* TranslateToItemIDs: the attributes asked (of AE_SOURCE_NAMES[0]'s AE_CONDITION, sub-condition
 * AE_SC_NAMES[1], category 1001), in another order than the server's. */
#define AE_TRANSLATED 3
static const DWORD AE_TRANSLATE_IDS[AE_TRANSLATED] = {0x80000003u, 1, 2};

/* The conditions (QueryConditionNames of category 1001; the others have none) and the condition of
 * each source (QuerySourceConditions); AE_CONDITION's sub-conditions are AE_SC_NAMES. */
#define AE_CONDITIONS 2
static const char *const AE_CONDITION_NAMES[AE_CONDITIONS] = {AE_CONDITION, "Temperature \xc2\xb0" "C"};
static const int AE_SOURCE_CONDITION[AE_SOURCES] = {0, 1, 0};

/* The attributes a subscription returns for category 1001 (SelectReturnedAttributes), in the
 * client's order. */
#define AE_SELECTED 2
static const DWORD AE_SELECTED_IDS[AE_SELECTED] = {0x80000003u, 2};

/* The events the server sends on a Refresh: a condition event with both attributes and no actor, a
 * tracking event with one attribute, no condition and an actor. */
#define AE_EVENTS 2
#define AE_EVENT_COOKIE 4711u

/* Fills event `i` (its strings in task memory, its attributes in `attrs`, which it points to). */
static void ae_fill_event(int i, ONEVENTSTRUCT *e, VARIANT *attrs) {
    memset(e, 0, sizeof *e);
    if (i == 0) {
        e->wChangeMask = 0x0003;
        e->wNewState = 0x0003;
        e->szSource = task_utf8(AE_SOURCE_NAMES[0]);
        e->ftTime = test_time(5);
        e->szMessage = task_utf8("Level high \xc3\xa4\xc3\xb6\xc3\xbc \xe2\x82\xac");
        e->dwEventType = AE_CONDITION_EVENT;
        e->dwEventCategory = AE_CATEGORY_IDS[0];
        e->dwSeverity = 700;
        e->szConditionName = task_utf8(AE_CONDITION);
        e->szSubconditionName = task_utf8(AE_SC_NAMES[0]);
        e->wQuality = 0xC0;
        e->wReserved = 0;
        e->bAckRequired = TRUE;
        e->ftActiveTime = test_time(4);
        e->dwCookie = AE_EVENT_COOKIE;
        e->dwNumEventAttrs = 2;
        ae_attribute(1, &attrs[0]);
        ae_attribute(2, &attrs[1]);
        e->pEventAttributes = attrs;
        e->szActorID = NULL;
    } else {
        e->szSource = task_utf8(AE_SOURCE_NAMES[2]);
        e->ftTime = test_time(6);
        e->szMessage = task_utf8("Setpoint changed to 42");
        e->dwEventType = AE_TRACKING_EVENT;
        e->dwEventCategory = AE_CATEGORY_IDS[1];
        e->dwSeverity = 200;
        e->wQuality = 0x40;
        e->ftActiveTime.dwLowDateTime = 0xFFFFFFFFu; /* both halves of a FILETIME cross apart */
        e->ftActiveTime.dwHighDateTime = 1;
        e->dwCookie = 0;
        e->dwNumEventAttrs = 1;
        ae_attribute(2, &attrs[0]);
        e->pEventAttributes = attrs;
        e->szActorID = task_utf8("operator \xe2\x82\xac");
    }
}

static void ae_free_event(ONEVENTSTRUCT *e) {
    DWORD k;
    CoTaskMemFree(e->szSource);
    CoTaskMemFree(e->szMessage);
    CoTaskMemFree(e->szConditionName);
    CoTaskMemFree(e->szSubconditionName);
    CoTaskMemFree(e->szActorID);
    for (k = 0; k < e->dwNumEventAttrs; k++) VariantClear(&e->pEventAttributes[k]);
}

/* Whether two variants of the events' attributes are the same (VT_BSTR, VT_I4, VT_EMPTY). */
static int ae_same_variant(const VARIANT *a, const VARIANT *b) {
    if (V_VT(a) != V_VT(b)) return 0;
    switch (V_VT(a)) {
    case VT_EMPTY: return 1;
    case VT_I4: return V_I4(a) == V_I4(b);
    case VT_BSTR:
        return V_BSTR(a) && V_BSTR(b) && SysStringLen(V_BSTR(a)) == SysStringLen(V_BSTR(b)) &&
               memcmp(V_BSTR(a), V_BSTR(b), SysStringLen(V_BSTR(a)) * sizeof(WCHAR)) == 0;
    default: return 0;
    }
}

/* Whether event `got` is event `i` field by field. */
static int ae_is_event(const ONEVENTSTRUCT *got, int i) {
    ONEVENTSTRUCT want;
    VARIANT attrs[2];
    DWORD k;
    int same;
    ae_fill_event(i, &want, attrs);
    same = got->wChangeMask == want.wChangeMask && got->wNewState == want.wNewState &&
           wsame(got->szSource, want.szSource) && same_filetime(got->ftTime, want.ftTime) &&
           wsame(got->szMessage, want.szMessage) && got->dwEventType == want.dwEventType &&
           got->dwEventCategory == want.dwEventCategory && got->dwSeverity == want.dwSeverity &&
           wsame(got->szConditionName, want.szConditionName) && wsame(got->szSubconditionName, want.szSubconditionName) &&
           got->wQuality == want.wQuality && got->wReserved == want.wReserved &&
           got->bAckRequired == want.bAckRequired && same_filetime(got->ftActiveTime, want.ftActiveTime) &&
           got->dwCookie == want.dwCookie && got->dwNumEventAttrs == want.dwNumEventAttrs &&
           got->pEventAttributes && wsame(got->szActorID, want.szActorID);
    for (k = 0; same && k < want.dwNumEventAttrs; k++)
        same = ae_same_variant(&got->pEventAttributes[k], &want.pEventAttributes[k]);
    ae_free_event(&want);
    return same;
}

/* The filter the client sets (SetFilter) and reads back (GetFilter). */
#define AE_FILTER_CATEGORIES 2
static const DWORD AE_FILTER_CATEGORY_IDS[AE_FILTER_CATEGORIES] = {1001, 0x7FFFFFFF};
#define AE_FILTER_LOW 100u
#define AE_FILTER_HIGH 900u
#define AE_FILTER_AREAS 2 /* AE_AREA_NAMES[1] and [2] */
#define AE_FILTER_SOURCES 1 /* AE_SOURCE_NAMES[0] */

/* The keep-alive time of a subscription (IOPCEventSubscriptionMgt2): asked, revised by the server,
 * which answers OPC_S_INVALIDKEEPALIVETIME then. */
#define AE_KEEP_ALIVE 2345u
#define AE_REVISED_KEEP_ALIVE 2500u
#define OPC_S_INVALIDKEEPALIVETIME_AE ((HRESULT)0x00040203L)

/* AckCondition: who acknowledges, the comment, and the conditions acknowledged: the condition of
 * event 0 (acknowledged), the same again with its time's halves apart (already acknowledged), a
 * wrong active time, a source the server does not know. */
#define AE_ACKNOWLEDGER "operator \xc3\xa4\xc3\xb6\xc3\xbc"
#define AE_ACK_COMMENT "Checked on site \xe2\x82\xac \xf0\x9f\x98\x80"
#define AE_ACKS 4
#define AE_S_ALREADYACKED ((HRESULT)0x00040200L)
#define AE_E_INVALIDTIME ((HRESULT)0xC0040204L)
typedef struct AeAck {
    const char *source, *condition;
    FILETIME active_time;
    DWORD cookie;
    HRESULT result; /* the server's answer for it */
} AeAck;

static AeAck ae_ack(DWORD k) {
    AeAck a;
    a.source = k == 3 ? "Plant.Nowhere.Level" : AE_SOURCE_NAMES[k == 1 ? 2 : 0];
    a.condition = AE_CONDITION;
    a.active_time = test_time(4);
    a.cookie = AE_EVENT_COOKIE + k;
    a.result = S_OK;
    if (k == 1) {
        a.active_time.dwLowDateTime = 0xFFFFFFFFu;
        a.active_time.dwHighDateTime = 0x01020304u;
        a.cookie = 0x80000001u;
        a.result = AE_S_ALREADYACKED;
    } else if (k == 2) {
        a.active_time = test_time(3);
        a.result = AE_E_INVALIDTIME;
    } else if (k == 3) {
        a.result = AE_E_UNKNOWN_NAME;
    }
    return a;
}

#endif
