/* Shared by the cross-process test of the Historical Data Access proxy/stub (test_hda_tables.c, the
 * client) and its EXE server (hda_server.c): the class, the items the server serves and their
 * history. The types and IIDs come from the header widl generates from idl/opchda.idl (opchda_idl.h;
 * this file defines the IIDs, so one translation unit per program). Windows only. */
#ifndef OPCCOMN_HDA_H
#define OPCCOMN_HDA_H

#include "classic_oop.h"

#include <initguid.h>
#include <ocidl.h>

#include "opchda_idl.h"

/* The test HDA server (hda_server.c, LocalServer32). */
static const CLSID CLSID_HdaTestServer = {0xC3000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0x4D, 0x02}};

/* The HDA interfaces opccomn.dll's proxy/stub serves in these two processes. */
static const IID *const HDA_IIDS[] = {&IID_IOPCHDA_Browser,        &IID_IOPCHDA_Server,          &IID_IOPCHDA_SyncRead,
                                      &IID_IOPCHDA_SyncUpdate,     &IID_IOPCHDA_SyncAnnotations, &IID_IOPCHDA_AsyncRead,
                                      &IID_IOPCHDA_AsyncUpdate,    &IID_IOPCHDA_AsyncAnnotations,
                                      &IID_IOPCHDA_Playback,       &IID_IOPCHDA_DataCallback};
#define HDA_IID_COUNT (sizeof HDA_IIDS / sizeof HDA_IIDS[0])

/* The server's status: its vendor text when its proxy/stub of the HDA interfaces is opccomn.dll's. */
#define HDA_VENDOR_INFO "opccomn HDA test server \xe2\x82\xac"
#define HDA_VENDOR_INFO_OTHER "proxy/stub not opccomn's"
#define HDA_STATUS_TEXT "Running \xc3\xa4\xc3\xb6\xc3\xbc"

#define HDA_E_INVALIDHANDLE ((HRESULT)0xC0040001L) /* OPC_E_INVALIDHANDLE */
#define HDA_E_UNKNOWNITEMID ((HRESULT)0xC0040007L) /* OPC_E_UNKNOWNITEMID */
#define HDA_QUALITY_RAW 0x00040000u                /* OPCHDA_RAW */
#define HDA_QUALITY_CALCULATED 0x00080000u         /* OPCHDA_CALCULATED */

/* The item attributes (GetItemAttributes). */
#define HDA_ATTRS 3
static const DWORD HDA_ATTR_IDS[HDA_ATTRS] = {1, 2, 0x80000001u};
static const char *const HDA_ATTR_NAMES[HDA_ATTRS] = {"Data Type", "Description", "Vendor \xe2\x82\xac"};
static const char *const HDA_ATTR_TEXTS[HDA_ATTRS] = {"Data type of the item", "Description \xc3\xa4\xc3\xb6\xc3\xbc",
                                                     "A vendor's attribute \xf0\x9f\x98\x80"};
static const VARTYPE HDA_ATTR_TYPES[HDA_ATTRS] = {VT_I2, VT_BSTR, VT_R8};

/* The items: ID, the client handle the test gives each, the server's handle. */
#define HDA_ITEMS 2
static const char *const HDA_ITEM_IDS[HDA_ITEMS] = {"Plant.Tank1.Level", "Plant.Tank1.Name \xe2\x82\xac"};
#define HDA_CLIENT_HANDLE(i) ((OPCHANDLE)(500 + (i)))
#define HDA_SERVER_HANDLE(i) ((OPCHANDLE)(0x100 + (i)))

/* A raw read: HDA_RAW_VALUES values of each item (VT_R8 and VT_BSTR). */
#define HDA_RAW_VALUES 3
/* The time range the client asks for: from "NOW-1H" (a string the server resolves to test_time(10))
 * to a FILETIME (which the server revises to test_time(12)). */
#define HDA_START_TEXT "NOW-1H"
#define HDA_END_ASKED 50u
#define HDA_START_RESOLVED 10u
#define HDA_END_RESOLVED 12u
/* The interval of a processed read (a FILETIME by value: its two halves differ, so that one
 * taken apart or shifted on the stack shows), and its two intervals' values per aggregate. */
#define HDA_INTERVAL_LOW 0x65A0BC00u
#define HDA_INTERVAL_HIGH 0x00000001u
#define HDA_INTERVALS 2

static FILETIME hda_interval(void) {
    FILETIME f;
    f.dwLowDateTime = HDA_INTERVAL_LOW;
    f.dwHighDateTime = HDA_INTERVAL_HIGH;
    return f;
}

/* Fills `it` with the raw history of item `i` (aggregate 0) or its processed history by `aggregate`
 * (task memory). */
static void hda_fill_item(int i, DWORD aggregate, OPCHDA_ITEM *it) {
    DWORD k, n = aggregate ? HDA_INTERVALS : HDA_RAW_VALUES;
    memset(it, 0, sizeof *it);
    it->hClient = HDA_CLIENT_HANDLE(i);
    it->haAggregate = aggregate;
    it->pftTimeStamps = (FILETIME *)task_zero(n * sizeof(FILETIME));
    it->pdwQualities = (DWORD *)task_zero(n * sizeof(DWORD));
    it->pvDataValues = (VARIANT *)task_zero(n * sizeof(VARIANT));
    if (!it->pftTimeStamps || !it->pdwQualities || !it->pvDataValues) return; /* dwCount 0 */
    it->dwCount = n;
    for (k = 0; k < n; k++) {
        VARIANT *v = &it->pvDataValues[k];
        char text[64];
        VariantInit(v);
        if (aggregate) {
            it->pftTimeStamps[k] = test_time(HDA_START_RESOLVED + 600 * k);
            it->pdwQualities[k] = HDA_QUALITY_CALCULATED | 0xC0;
            V_VT(v) = VT_R8;
            V_R8(v) = aggregate * 10.0 + k + 0.25;
        } else if (i == 0) {
            it->pftTimeStamps[k] = test_time(HDA_START_RESOLVED + k);
            it->pdwQualities[k] = HDA_QUALITY_RAW | (k == 1 ? 0x40 : 0xC0);
            V_VT(v) = VT_R8;
            V_R8(v) = 1.5 + k * 1e100;
        } else {
            it->pftTimeStamps[k] = test_time(HDA_START_RESOLVED + k);
            it->pdwQualities[k] = HDA_QUALITY_RAW | 0xC0;
            snprintf(text, sizeof text, "Wert %lu \xc3\xa4\xc3\xb6\xc3\xbc \xe2\x82\xac", (unsigned long)k);
            V_VT(v) = VT_BSTR;
            V_BSTR(v) = bstr_utf8(text);
        }
    }
}

static void hda_free_item(OPCHDA_ITEM *it) {
    DWORD k;
    for (k = 0; it->pvDataValues && k < it->dwCount; k++) VariantClear(&it->pvDataValues[k]);
    CoTaskMemFree(it->pftTimeStamps);
    CoTaskMemFree(it->pdwQualities);
    CoTaskMemFree(it->pvDataValues);
    memset(it, 0, sizeof *it);
}

static int hda_same_variant(const VARIANT *a, const VARIANT *b) {
    if (V_VT(a) != V_VT(b)) return 0;
    switch (V_VT(a)) {
    case VT_I2: return V_I2(a) == V_I2(b);
    case VT_I4: return V_I4(a) == V_I4(b);
    case VT_R8: return V_R8(a) == V_R8(b);
    case VT_BSTR:
        return V_BSTR(a) && V_BSTR(b) && SysStringLen(V_BSTR(a)) == SysStringLen(V_BSTR(b)) &&
               memcmp(V_BSTR(a), V_BSTR(b), SysStringLen(V_BSTR(a)) * sizeof(WCHAR)) == 0;
    default: return 0;
    }
}

/* Whether `got` is the history hda_fill_item(i, aggregate) gives, value for value. */
static int hda_is_item(const OPCHDA_ITEM *got, int i, DWORD aggregate) {
    OPCHDA_ITEM want;
    DWORD k;
    int same;
    hda_fill_item(i, aggregate, &want);
    same = got->hClient == want.hClient && got->haAggregate == want.haAggregate && got->dwCount == want.dwCount &&
           got->pftTimeStamps && got->pdwQualities && got->pvDataValues;
    for (k = 0; same && k < want.dwCount; k++)
        same = same_filetime(got->pftTimeStamps[k], want.pftTimeStamps[k]) &&
               got->pdwQualities[k] == want.pdwQualities[k] &&
               hda_same_variant(&got->pvDataValues[k], &want.pvDataValues[k]);
    hda_free_item(&want);
    return same;
}

/* The annotations of item 0 (item 1 has none). */
#define HDA_ANNOTATIONS 2
static const char *const HDA_ANNOTATION_TEXTS[HDA_ANNOTATIONS] = {"Calibrated \xc3\xa4\xc3\xb6\xc3\xbc",
                                                                  "Checked \xe2\x82\xac"};
static const char *const HDA_ANNOTATION_USERS[HDA_ANNOTATIONS] = {"operator", "maintenance \xf0\x9f\x98\x80"};

/* IOPCHDA_SyncUpdate: the capabilities, and the values of Insert (method 0), Replace (1) and
 * InsertReplace (2) and the times of DeleteAtTime (3): HDA_UPDATES elements, item 0's VT_R8, item
 * 1's VT_BSTR and a VT_I4 of an invalid handle, each method's values its own (a request delivered
 * to another method shows), each element's answer the server's for it. */
#define HDA_UPDATE_CAPS \
    (OPCHDA_INSERTCAP | OPCHDA_REPLACECAP | OPCHDA_INSERTREPLACECAP | OPCHDA_DELETERAWCAP | OPCHDA_DELETEATTIMECAP)
#define HDA_UPDATES 3
#define HDA_INVALID_HANDLE ((OPCHANDLE)0x999)
#define HDA_S_INSERTED ((HRESULT)0x4004100EL)
#define HDA_S_REPLACED ((HRESULT)0x4004100FL)
typedef struct HdaUpdate {
    OPCHANDLE handle;
    FILETIME time;
    VARIANT value; /* a BSTR in it the caller's to clear */
    DWORD quality;
    HRESULT result;
} HdaUpdate;

static HdaUpdate hda_update(int method, DWORD k) {
    HdaUpdate u;
    char text[64];
    memset(&u, 0, sizeof u);
    VariantInit(&u.value);
    u.handle = k < 2 ? HDA_SERVER_HANDLE(k) : HDA_INVALID_HANDLE;
    u.time = test_time(20 + 10 * (unsigned)method + k);
    u.quality = (k == 1 ? 0x40u : 0xC0u) | (DWORD)method << 24;
    u.result = k == 2 ? HDA_E_INVALIDHANDLE : method == 2 ? (k == 0 ? HDA_S_INSERTED : HDA_S_REPLACED) : S_OK;
    if (k == 0) {
        V_VT(&u.value) = VT_R8;
        V_R8(&u.value) = -2.5e-300 * (method + 1);
    } else if (k == 1) {
        snprintf(text, sizeof text, "Neu %d \xc3\xa4\xc3\xb6\xc3\xbc \xe2\x82\xac", method);
        V_VT(&u.value) = VT_BSTR;
        V_BSTR(&u.value) = bstr_utf8(text);
    } else {
        V_VT(&u.value) = VT_I4;
        V_I4(&u.value) = -7 - method;
    }
    return u;
}

/* The FILETIMEs by value of IOPCHDA_Playback and IOPCHDA_AsyncRead::AdviseRaw: the update duration
 * and the update interval, each with halves of their own. */
static FILETIME hda_duration(void) {
    FILETIME f;
    f.dwLowDateTime = 0x89ABCDEFu;
    f.dwHighDateTime = 0x00000002u;
    return f;
}
static FILETIME hda_update_interval(void) {
    FILETIME f;
    f.dwLowDateTime = 0x01234567u;
    f.dwHighDateTime = 0x00000003u;
    return f;
}

/* IOPCHDA_SyncRead::ReadAtTime: the client asks for the values at HDA_AT_TIMES times of its own;
 * the server answers each item with a value at each (item 0 VT_R8, item 1 VT_BSTR), interpolated. */
#define HDA_AT_TIMES 3
#define HDA_QUALITY_INTERPOLATED 0x00020000u /* OPCHDA_INTERPOLATED */

static FILETIME hda_at_time(DWORD n) {
    return test_time(200 + 7 * n);
}

/* Fills `it` with item `i`'s values at the times hda_at_time() gives (task memory). */
static void hda_fill_at_time(int i, OPCHDA_ITEM *it) {
    DWORD k;
    memset(it, 0, sizeof *it);
    it->hClient = HDA_CLIENT_HANDLE(i);
    it->pftTimeStamps = (FILETIME *)task_zero(HDA_AT_TIMES * sizeof(FILETIME));
    it->pdwQualities = (DWORD *)task_zero(HDA_AT_TIMES * sizeof(DWORD));
    it->pvDataValues = (VARIANT *)task_zero(HDA_AT_TIMES * sizeof(VARIANT));
    if (!it->pftTimeStamps || !it->pdwQualities || !it->pvDataValues) return; /* dwCount 0 */
    it->dwCount = HDA_AT_TIMES;
    for (k = 0; k < HDA_AT_TIMES; k++) {
        VARIANT *v = &it->pvDataValues[k];
        char text[64];
        VariantInit(v);
        it->pftTimeStamps[k] = hda_at_time(k);
        it->pdwQualities[k] = HDA_QUALITY_INTERPOLATED | (k == 2 ? 0x50u : 0xC0u);
        if (i == 0) {
            V_VT(v) = VT_R8;
            V_R8(v) = -3.75 - k * 1e-200;
        } else {
            snprintf(text, sizeof text, "Zeit %lu \xf0\x9f\x98\x80", (unsigned long)k);
            V_VT(v) = VT_BSTR;
            V_BSTR(v) = bstr_utf8(text);
        }
    }
}

/* Whether `got` has `want`'s values (hClient, haAggregate, each timestamp, quality and value). */
static int hda_same_item(const OPCHDA_ITEM *got, const OPCHDA_ITEM *want) {
    DWORD k;
    int same = got->hClient == want->hClient && got->haAggregate == want->haAggregate &&
               got->dwCount == want->dwCount && got->pftTimeStamps && got->pdwQualities && got->pvDataValues;
    for (k = 0; same && k < want->dwCount; k++)
        same = same_filetime(got->pftTimeStamps[k], want->pftTimeStamps[k]) &&
               got->pdwQualities[k] == want->pdwQualities[k] &&
               hda_same_variant(&got->pvDataValues[k], &want->pvDataValues[k]);
    return same;
}

static int hda_is_at_time(const OPCHDA_ITEM *got, int i) {
    OPCHDA_ITEM want;
    int same;
    hda_fill_at_time(i, &want);
    same = hda_same_item(got, &want);
    hda_free_item(&want);
    return same;
}

/* IOPCHDA_SyncRead::ReadModified: HDA_MODIFIED_VALUES modified values of each item, with the time,
 * the kind of each edit (OPCHDA_EDITTYPE) and who made it. */
#define HDA_MODIFIED_VALUES 2
static const char *const HDA_MODIFIED_USERS[HDA_ITEMS][HDA_MODIFIED_VALUES] = {
    {"engineer \xc3\xa4\xc3\xb6\xc3\xbc", "operator"}, {"", "maintenance \xf0\x9f\x98\x80 \xe2\x82\xac"}};

/* Fills `m` with item `i`'s modified values (task memory). */
static void hda_fill_modified(int i, OPCHDA_MODIFIEDITEM *m) {
    DWORD k;
    memset(m, 0, sizeof *m);
    m->hClient = HDA_CLIENT_HANDLE(i);
    m->pftTimeStamps = (FILETIME *)task_zero(HDA_MODIFIED_VALUES * sizeof(FILETIME));
    m->pdwQualities = (DWORD *)task_zero(HDA_MODIFIED_VALUES * sizeof(DWORD));
    m->pvDataValues = (VARIANT *)task_zero(HDA_MODIFIED_VALUES * sizeof(VARIANT));
    m->pftModificationTime = (FILETIME *)task_zero(HDA_MODIFIED_VALUES * sizeof(FILETIME));
    m->pEditType = (OPCHDA_EDITTYPE *)task_zero(HDA_MODIFIED_VALUES * sizeof(OPCHDA_EDITTYPE));
    m->szUser = (LPWSTR *)task_zero(HDA_MODIFIED_VALUES * sizeof(LPWSTR));
    if (!m->pftTimeStamps || !m->pdwQualities || !m->pvDataValues || !m->pftModificationTime || !m->pEditType ||
        !m->szUser)
        return; /* dwCount 0 */
    m->dwCount = HDA_MODIFIED_VALUES;
    for (k = 0; k < HDA_MODIFIED_VALUES; k++) {
        VARIANT *v = &m->pvDataValues[k];
        char text[64];
        VariantInit(v);
        m->pftTimeStamps[k] = test_time(HDA_START_RESOLVED + k);
        m->pdwQualities[k] = HDA_QUALITY_RAW | (k == 0 ? 0xC0u : 0x18u);
        m->pftModificationTime[k] = test_time(300 + 10 * (unsigned)i + k);
        m->pEditType[k] = (OPCHDA_EDITTYPE)(OPCHDA_INSERT + 2 * i + (int)k); /* all four among the items */
        m->szUser[k] = task_utf8(HDA_MODIFIED_USERS[i][k]);
        if (i == 0) {
            V_VT(v) = VT_R8;
            V_R8(v) = 7.125e10 + k;
        } else {
            snprintf(text, sizeof text, "Alt %lu \xc3\xa4\xc3\xb6\xc3\xbc", (unsigned long)k);
            V_VT(v) = VT_BSTR;
            V_BSTR(v) = bstr_utf8(text);
        }
    }
}

static void hda_free_modified(OPCHDA_MODIFIEDITEM *m) {
    DWORD k;
    for (k = 0; k < m->dwCount; k++) {
        if (m->pvDataValues) VariantClear(&m->pvDataValues[k]);
        if (m->szUser) CoTaskMemFree(m->szUser[k]);
    }
    CoTaskMemFree(m->pftTimeStamps);
    CoTaskMemFree(m->pdwQualities);
    CoTaskMemFree(m->pvDataValues);
    CoTaskMemFree(m->pftModificationTime);
    CoTaskMemFree(m->pEditType);
    CoTaskMemFree(m->szUser);
    memset(m, 0, sizeof *m);
}

/* Whether `got` is what hda_fill_modified(i) gives, value for value. */
static int hda_is_modified(const OPCHDA_MODIFIEDITEM *got, int i) {
    OPCHDA_MODIFIEDITEM want;
    DWORD k;
    int same;
    hda_fill_modified(i, &want);
    same = got->hClient == want.hClient && got->dwCount == want.dwCount && got->pftTimeStamps && got->pdwQualities &&
           got->pvDataValues && got->pftModificationTime && got->pEditType && got->szUser;
    for (k = 0; same && k < want.dwCount; k++)
        same = same_filetime(got->pftTimeStamps[k], want.pftTimeStamps[k]) &&
               got->pdwQualities[k] == want.pdwQualities[k] &&
               hda_same_variant(&got->pvDataValues[k], &want.pvDataValues[k]) &&
               same_filetime(got->pftModificationTime[k], want.pftModificationTime[k]) &&
               got->pEditType[k] == want.pEditType[k] && is_utf8(got->szUser[k], HDA_MODIFIED_USERS[i][k]);
    hda_free_modified(&want);
    return same;
}

/* IOPCHDA_SyncAnnotations::Insert: HDA_UPDATES elements (item 0 with two annotations, item 1 with
 * one, an invalid handle with one), each with a timestamp; each element answered as it arrived. */
static FILETIME hda_insert_time(DWORD k) { return test_time(400 + 3 * k); }

/* Fills `a` with element `k` of the annotations inserted (task memory). */
static void hda_fill_insert_annotation(DWORD k, OPCHDA_ANNOTATION *a) {
    DWORD n, count = k == 0 ? 2 : 1;
    memset(a, 0, sizeof *a);
    a->hClient = k < 2 ? HDA_CLIENT_HANDLE(k) : 0;
    a->ftTimeStamps = (FILETIME *)task_zero(count * sizeof(FILETIME));
    a->ftAnnotationTime = (FILETIME *)task_zero(count * sizeof(FILETIME));
    a->szAnnotation = (LPWSTR *)task_zero(count * sizeof(LPWSTR));
    a->szUser = (LPWSTR *)task_zero(count * sizeof(LPWSTR));
    if (!a->ftTimeStamps || !a->ftAnnotationTime || !a->szAnnotation || !a->szUser) return; /* dwNumValues 0 */
    a->dwNumValues = count;
    for (n = 0; n < count; n++) {
        char text[64];
        a->ftTimeStamps[n] = hda_insert_time(k);
        a->ftAnnotationTime[n] = test_time(500 + 10 * k + n);
        snprintf(text, sizeof text, "Note %lu.%lu \xe2\x82\xac \xf0\x9f\x98\x80", (unsigned long)k, (unsigned long)n);
        a->szAnnotation[n] = task_utf8(text);
        snprintf(text, sizeof text, "user%lu \xc3\xa4", (unsigned long)(k + n));
        a->szUser[n] = task_utf8(text);
    }
}

static void hda_free_annotation(OPCHDA_ANNOTATION *a) {
    DWORD n;
    for (n = 0; n < a->dwNumValues; n++) {
        if (a->szAnnotation) CoTaskMemFree(a->szAnnotation[n]);
        if (a->szUser) CoTaskMemFree(a->szUser[n]);
    }
    CoTaskMemFree(a->ftTimeStamps);
    CoTaskMemFree(a->ftAnnotationTime);
    CoTaskMemFree(a->szAnnotation);
    CoTaskMemFree(a->szUser);
    memset(a, 0, sizeof *a);
}

static int hda_same_wstr(const WCHAR *a, const WCHAR *b) { return a && b && lstrcmpW(a, b) == 0; }

/* Whether `got` is element `k` of the annotations inserted, value for value. */
static int hda_is_insert_annotation(const OPCHDA_ANNOTATION *got, DWORD k) {
    OPCHDA_ANNOTATION want;
    DWORD n;
    int same;
    hda_fill_insert_annotation(k, &want);
    same = got->hClient == want.hClient && got->dwNumValues == want.dwNumValues && got->ftTimeStamps &&
           got->ftAnnotationTime && got->szAnnotation && got->szUser;
    for (n = 0; same && n < want.dwNumValues; n++)
        same = same_filetime(got->ftTimeStamps[n], want.ftTimeStamps[n]) &&
               same_filetime(got->ftAnnotationTime[n], want.ftAnnotationTime[n]) &&
               hda_same_wstr(got->szAnnotation[n], want.szAnnotation[n]) &&
               hda_same_wstr(got->szUser[n], want.szUser[n]);
    hda_free_annotation(&want);
    return same;
}

/* IOPCHDA_Server::CreateBrowse and IOPCHDA_Browser: the items of hda.h as a tree, "Plant" and
 * "Plant.Tank1" its branches, the items its leaves there. The client's filters: the data type equal
 * to VT_BSTR (so only item 1 is found), the description not equal to a text, and an attribute the
 * server does not know. */
#define HDA_E_UNKNOWNATTRID ((HRESULT)0xC0041008L) /* OPC_E_UNKNOWNATTRID */
#define HDA_FILTERS 3
#define HDA_UNKNOWN_ATTR 0x7777u
#define HDA_FILTER_TEXT "No description \xe2\x82\xac \xf0\x9f\x98\x80"
static const DWORD HDA_FILTER_IDS[HDA_FILTERS] = {1, 2, HDA_UNKNOWN_ATTR};
static const OPCHDA_OPERATORCODES HDA_FILTER_OPS[HDA_FILTERS] = {OPCHDA_EQUAL, OPCHDA_NOTEQUAL, OPCHDA_GREATER};
static const char *const HDA_LEAVES[HDA_ITEMS] = {"Level", "Name \xe2\x82\xac"};
#define HDA_TOP_BRANCH "Plant"
#define HDA_BRANCH "Tank1"
#define HDA_BRANCH_POSITION "Plant.Tank1"

/* The filter value `k` (its BSTR the caller's to clear). */
static VARIANT hda_filter(DWORD k) {
    VARIANT v;
    VariantInit(&v);
    if (k == 0) {
        V_VT(&v) = VT_I2;
        V_I2(&v) = VT_BSTR;
    } else if (k == 1) {
        V_VT(&v) = VT_BSTR;
        V_BSTR(&v) = bstr_utf8(HDA_FILTER_TEXT);
    } else {
        V_VT(&v) = VT_R8;
        V_R8(&v) = 2.5;
    }
    return v;
}

/* The IOPCHDA_DataCallback methods a thread of the server calls back (the server says which it
 * calls, the client which it waited for). */
enum {
    CALL_READ_COMPLETE,
    CALL_DATA_CHANGE,
    CALL_CANCEL_COMPLETE,
    CALL_PLAYBACK,
    CALL_UPDATE_COMPLETE,
    CALL_READ_ANNOTATIONS,
    CALL_INSERT_ANNOTATIONS
};

#endif
