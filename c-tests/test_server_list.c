/* The OPC server browser (OPCServerList) through the public header: the enumeration rules over a
 * registry held in memory (any of the implemented categories, every required one supported by the
 * caller, 0 = any,
 * DA 1.0 servers registered the old way, no duplicates, sorted), GetClassDetails of both interfaces,
 * CLSIDFromProgID, the enumerator, bad input, the class factory and DllCanUnloadNow.
 *
 * On Windows (under Wine) the program also registers opccomn.dll with regsvr32 over a pre-existing
 * OpcEnum-style registration, creates the server list with CoCreateInstance by CLSID and by ProgID,
 * registers fake servers with the helpers (in both registry views), finds them through both
 * interfaces, unregisters everything and checks the registry is as it was. */
#include <stddef.h>
#include <stdint.h>

#include "test_util.h"

#ifdef _WIN32
#define STDMETHODCALLTYPE_ STDMETHODCALLTYPE
#else
#define STDMETHODCALLTYPE_
#endif

static const IID IID_EnumGUID_ = {0x0002E000, 0x0000, 0x0000, {0xC0, 0, 0, 0, 0, 0, 0, 0x46}};
static const IID IID_ClassFactory_ = {0x00000001, 0x0000, 0x0000, {0xC0, 0, 0, 0, 0, 0, 0, 0x46}};
static const IID IID_Bogus_ = {0x01234567, 0x89AB, 0xCDEF, {1, 2, 3, 4, 5, 6, 7, 8}};

/* Test classes {C0000000-0000-0000-0000-0000000000NN}. */
static CLSID test_clsid(unsigned n) {
    CLSID c = {0xC0000000, 0, 0, {0, 0, 0, 0, 0, 0, 0, (unsigned char)n}};
    return c;
}

static int same_guid(const GUID *a, const GUID *b) { return memcmp(a, b, sizeof(GUID)) == 0; }

/* Classes 1 (DA 2.0), 2 (DA 2.0 + 3.0, requires A&E), 3 (A&E, no ProgID), 4 (DA 1.0 the old way
 * only), 5 (DA 3.0, requires A&E and DA 2.0), and a DA 1.0 ProgID whose class is not registered. */
static const char SAMPLE[] =
    "Windows Registry Editor Version 5.00\r\n\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000001}]\r\n@=\"Server One\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000001}\\ProgID]\r\n@=\"V.One.1\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000001}\\Implemented Categories\\{63D5F432-CFE4-11d1-B2C8-0060083BA1FB}]\r\n"
    "[HKEY_CLASSES_ROOT\\V.One.1\\CLSID]\r\n@=\"{C0000000-0000-0000-0000-000000000001}\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000002}]\r\n@=\"Server Two\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000002}\\ProgID]\r\n@=\"V.Two.1\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000002}\\VersionIndependentProgID]\r\n@=\"V.Two\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000002}\\Implemented Categories\\{63D5F432-CFE4-11d1-B2C8-0060083BA1FB}]\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000002}\\Implemented Categories\\{CC603642-66D7-48f1-B69A-B625E73652D7}]\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000002}\\Required Categories\\{58E13251-AC87-11d1-84D5-00608CB8A7E9}]\r\n"
    "[HKEY_CLASSES_ROOT\\V.Two.1\\CLSID]\r\n@=\"{C0000000-0000-0000-0000-000000000002}\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000003}]\r\n@=\"Server Three\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000003}\\Implemented Categories\\{58E13251-AC87-11d1-84D5-00608CB8A7E9}]\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000004}]\r\n@=\"Old Server\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000004}\\ProgID]\r\n@=\"V.Old.1\"\r\n"
    "[HKEY_CLASSES_ROOT\\V.Old.1\\CLSID]\r\n@=\"{C0000000-0000-0000-0000-000000000004}\"\r\n"
    "[HKEY_CLASSES_ROOT\\V.Old.1\\OPC\\Vendor]\r\n@=\"Old Vendor\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000005}]\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000005}\\ProgID]\r\n@=\"V.Five.1\"\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000005}\\Implemented Categories\\{CC603642-66D7-48f1-B69A-B625E73652D7}]\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000005}\\Required Categories\\{58E13251-AC87-11d1-84D5-00608CB8A7E9}]\r\n"
    "[HKEY_CLASSES_ROOT\\CLSID\\{C0000000-0000-0000-0000-000000000005}\\Required Categories\\{63D5F432-CFE4-11d1-B2C8-0060083BA1FB}]\r\n"
    "[HKEY_CLASSES_ROOT\\V.Five.1]\r\n@=\"Five by its ProgID\"\r\n"
    "[HKEY_CLASSES_ROOT\\V.Five.1\\CLSID]\r\n@=\"{C0000000-0000-0000-0000-000000000005}\"\r\n"
    "[HKEY_CLASSES_ROOT\\V.Ghost.1\\OPC]\r\n"
    "[HKEY_CLASSES_ROOT\\V.Ghost.1\\CLSID]\r\n@=\"{C0000000-0000-0000-0000-0000000000FF}\"\r\n"
    "[HKEY_CLASSES_ROOT\\V.Bad.1\\CLSID]\r\n@=\"not a guid\"\r\n";

static OpcRegistry *sample_registry(void) {
    OpcRegistry *reg = (OpcRegistry *)GARBAGE_PTR;
    WCHAR *text = wdup(SAMPLE);
    CHECK_HR(OpcRegistryCreateMemory(&reg), S_OK);
    CHECK_HR(OpcRegistryApply(reg, text), S_OK);
    free(text);
    return reg;
}

/* Enumerates through IOPCServerList and checks the classes are exactly `want` (numbers), in order. */
static void expect_classes(IOPCServerList *list, ULONG ci, CATID *impl, ULONG cr, CATID *req, const unsigned *want,
                           unsigned nwant) {
    IEnumGUID *e = (IEnumGUID *)GARBAGE_PTR;
    CLSID got[16];
    ULONG fetched = GARBAGE_U32;
    unsigned i;
    HRESULT hr = list->lpVtbl->EnumClassesOfCategories(list, ci, impl, cr, req, &e);
    CHECK_HR(hr, S_OK);
    if (hr != S_OK) return;
    hr = e->lpVtbl->Next(e, 16, got, &fetched);
    CHECK_HR(hr, nwant == 16 ? S_OK : S_FALSE);
    CHECK(fetched == nwant);
    for (i = 0; i < nwant && i < fetched; i++) {
        CLSID c = test_clsid(want[i]);
        CHECK(same_guid(&got[i], &c));
    }
    e->lpVtbl->Release(e);
}

static void test_enumeration_rules(IOPCServerList *list) {
    CATID da10 = CATID_OPCDAServer10, da20 = CATID_OPCDAServer20, da30 = CATID_OPCDAServer30,
          ae = CATID_OPCAEServer10;
    CATID two[2], three[3];
    {
        static const unsigned all[] = {1, 2, 3, 4, 5};
        expect_classes(list, 0, NULL, 0, NULL, all, 5); /* 0 = regardless of category */
        expect_classes(list, (ULONG)-1, NULL, (ULONG)-1, NULL, all, 5); /* ICatInformation's -1 too */
    }
    {
        static const unsigned w[] = {1, 2};
        expect_classes(list, 1, &da20, 0, NULL, w, 2);
    }
    {
        static const unsigned w[] = {2, 3, 5}; /* any of DA 3.0, A&E */
        two[0] = da30;
        two[1] = ae;
        expect_classes(list, 2, two, 0, NULL, w, 3);
    }
    {
        static const unsigned w[] = {1, 2, 5}; /* a category listed twice, a class matching twice: once */
        three[0] = da20;
        three[1] = da30;
        three[2] = da20;
        expect_classes(list, 3, three, 0, NULL, w, 3);
    }
    /* Required categories as ICatInformation defines them: rgcatidReq lists what the caller
       supports; a class qualifies when all it requires is listed, and a class requiring nothing always
       does. */
    {
        static const unsigned w[] = {1, 2, 3, 4}; /* supports A&E: not 5, which also requires DA 2.0 */
        expect_classes(list, 0, NULL, 1, &ae, w, 4);
    }
    {
        static const unsigned w[] = {1, 2, 3, 4, 5}; /* supports both of 5's requirements */
        two[0] = ae;
        two[1] = da20;
        expect_classes(list, 0, NULL, 2, two, w, 5);
    }
    {
        static const unsigned w[] = {1, 3, 4}; /* supports nothing any class requires */
        CATID unknown = IID_Bogus_;
        expect_classes(list, 0, NULL, 1, &unknown, w, 3);
    }
    {
        static const unsigned w[] = {1, 2}; /* implements DA 2.0, supports A&E */
        expect_classes(list, 1, &da20, 1, &ae, w, 2);
    }
    {
        static const unsigned w[] = {1}; /* what OPC clients call: DA 2.0, supporting DA 2.0 */
        expect_classes(list, 1, &da20, 1, &da20, w, 1);
    }
    {
        static const unsigned w[] = {1, 2}; /* (ULONG)-1 is taken as 0: regardless */
        expect_classes(list, 1, &da20, (ULONG)-1, NULL, w, 2);
    }
    expect_classes(list, 1, &da30, 1, &da20, NULL, 0); /* 2 and 5 both require A&E */
    {
        static const unsigned w[] = {4}; /* DA 1.0 the old way; the unregistered ghost is not reported */
        expect_classes(list, 1, &da10, 0, NULL, w, 1);
    }
    {
        static const unsigned w[] = {1, 2, 4};
        two[0] = da10;
        two[1] = da20;
        expect_classes(list, 2, two, 0, NULL, w, 3);
    }
    {
        CATID unknown = IID_Bogus_;
        expect_classes(list, 1, &unknown, 0, NULL, NULL, 0);
    }
}

static void test_enumerator(IOPCServerList2 *list2) {
    IOPCEnumGUID *e = (IOPCEnumGUID *)GARBAGE_PTR, *copy = (IOPCEnumGUID *)GARBAGE_PTR;
    IEnumGUID *as_enum = (IEnumGUID *)GARBAGE_PTR;
    void *p = GARBAGE_PTR;
    CLSID got[8];
    ULONG n = GARBAGE_U32;
    CATID da20 = CATID_OPCDAServer20;
    CLSID one = test_clsid(1), two = test_clsid(2);

    CHECK_HR(list2->lpVtbl->EnumClassesOfCategories(list2, 1, &da20, 0, NULL, &e), S_OK);
    CHECK_HR(e->lpVtbl->Next(e, 1, got, NULL), S_OK); /* the count may be omitted for one element */
    CHECK(same_guid(&got[0], &one));
    CHECK_HR(e->lpVtbl->Clone(e, &copy), S_OK);
    CHECK_HR(e->lpVtbl->Next(e, 5, got, &n), S_FALSE);
    CHECK(n == 1 && same_guid(&got[0], &two));
    CHECK_HR(e->lpVtbl->Next(e, 1, got, &n), S_FALSE);
    CHECK(n == 0);
    CHECK_HR(e->lpVtbl->Next(e, 2, got, NULL), E_POINTER);
    CHECK_HR(e->lpVtbl->Next(e, 1, NULL, &n), E_POINTER);
    CHECK_HR(e->lpVtbl->Next(e, 0, NULL, &n), S_OK);
    CHECK_HR(e->lpVtbl->Reset(e), S_OK);
    CHECK_HR(e->lpVtbl->Skip(e, 1), S_OK);
    CHECK_HR(e->lpVtbl->Skip(e, 0xFFFFFFFFu), S_FALSE);
    CHECK_HR(e->lpVtbl->Clone(e, NULL), E_POINTER);
    /* The clone kept its own position (after the first class). */
    n = GARBAGE_U32;
    CHECK_HR(copy->lpVtbl->Next(copy, 8, got, &n), S_FALSE);
    CHECK(n == 1 && same_guid(&got[0], &two));
    /* The same object answers for IEnumGUID, IOPCEnumGUID and IUnknown; nothing else. */
    CHECK_HR(e->lpVtbl->QueryInterface(e, &IID_EnumGUID_, (void **)&as_enum), S_OK);
    CHECK((void *)as_enum == (void *)e);
    CHECK_HR(e->lpVtbl->QueryInterface(e, &IID_Bogus_, &p), E_NOINTERFACE);
    CHECK(p == NULL);
    as_enum->lpVtbl->Release(as_enum);
    copy->lpVtbl->Release(copy);
    CHECK(e->lpVtbl->Release(e) == 0);
}

static void test_details(IOPCServerList *list, IOPCServerList2 *list2) {
    LPOLESTR prog = (LPOLESTR)GARBAGE_PTR, user = (LPOLESTR)GARBAGE_PTR, vi = (LPOLESTR)GARBAGE_PTR;
    CLSID c = test_clsid(2);

    CHECK_HR(list->lpVtbl->GetClassDetails(list, &c, &prog, &user), S_OK);
    CHECK(wstr_is(prog, "V.Two.1"));
    CHECK(wstr_is(user, "Server Two"));
    OpcTaskMemFree(prog);
    OpcTaskMemFree(user);

    CHECK_HR(list2->lpVtbl->GetClassDetails(list2, &c, &prog, &user, &vi), S_OK);
    CHECK(wstr_is(prog, "V.Two.1") && wstr_is(user, "Server Two") && wstr_is(vi, "V.Two"));
    OpcTaskMemFree(prog);
    OpcTaskMemFree(user);
    OpcTaskMemFree(vi);

    /* No VersionIndependentProgID: an empty string, as the registry has none. No description: the
     * ProgID key's. */
    c = test_clsid(5);
    CHECK_HR(list2->lpVtbl->GetClassDetails(list2, &c, &prog, &user, &vi), S_OK);
    CHECK(wstr_is(prog, "V.Five.1") && wstr_is(user, "Five by its ProgID") && wstr_is(vi, ""));
    OpcTaskMemFree(prog);
    OpcTaskMemFree(user);
    OpcTaskMemFree(vi);

    /* Unknown class: REGDB_E_CLASSNOTREG and every out-parameter NULL. */
    c = test_clsid(0x77);
    prog = user = vi = (LPOLESTR)GARBAGE_PTR;
    CHECK_HR(list2->lpVtbl->GetClassDetails(list2, &c, &prog, &user, &vi), REGDB_E_CLASSNOTREG);
    CHECK(prog == NULL && user == NULL && vi == NULL);
    /* A class without a ProgID: REGDB_E_KEYMISSING, nothing returned. */
    c = test_clsid(3);
    prog = user = (LPOLESTR)GARBAGE_PTR;
    CHECK_HR(list->lpVtbl->GetClassDetails(list, &c, &prog, &user), REGDB_E_KEYMISSING);
    CHECK(prog == NULL && user == NULL);
    /* Bad arguments. */
    prog = user = vi = (LPOLESTR)GARBAGE_PTR;
    CHECK_HR(list2->lpVtbl->GetClassDetails(list2, NULL, &prog, &user, &vi), E_INVALIDARG);
    CHECK(prog == NULL && user == NULL && vi == NULL);
    prog = (LPOLESTR)GARBAGE_PTR;
    CHECK_HR(list->lpVtbl->GetClassDetails(list, &c, &prog, NULL), E_INVALIDARG);
    CHECK(prog == NULL);
    user = (LPOLESTR)GARBAGE_PTR;
    CHECK_HR(list2->lpVtbl->GetClassDetails(list2, &c, NULL, &user, NULL), E_INVALIDARG);
    CHECK(user == NULL);
}

static void test_prog_ids(IOPCServerList *list) {
    CLSID got, want = test_clsid(2), null_guid;
    memset(&null_guid, 0, sizeof null_guid);

    memset(&got, 0xAB, sizeof got);
    CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, W("V.Two.1"), &got), S_OK);
    CHECK(same_guid(&got, &want));
    CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, W("v.two.1"), &got), S_OK); /* case-insensitive */
    memset(&got, 0xAB, sizeof got);
    CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, W("V.Unknown.1"), &got), REGDB_E_CLASSNOTREG);
    CHECK(same_guid(&got, &null_guid));
    CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, W("V.Bad.1"), &got), CO_E_CLASSSTRING);
    CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, W(""), &got), CO_E_CLASSSTRING);
    CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, W("CLSID\\{x}"), &got), CO_E_CLASSSTRING);
    {
        static const WCHAR lone_surrogate[] = {'V', 0xD800, '.', '1', 0};
        CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, lone_surrogate, &got), CO_E_CLASSSTRING);
    }
    memset(&got, 0xAB, sizeof got);
    CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, NULL, &got), E_INVALIDARG);
    CHECK(same_guid(&got, &null_guid));
    CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, W("V.Two.1"), NULL), E_INVALIDARG);
}

static void test_bad_enumeration_arguments(IOPCServerList *list) {
    IEnumGUID *e = (IEnumGUID *)GARBAGE_PTR;
    CATID da20 = CATID_OPCDAServer20;
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, NULL, 0, NULL, &e), E_INVALIDARG);
    CHECK(e == NULL);
    e = (IEnumGUID *)GARBAGE_PTR;
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 0, NULL, 2, NULL, &e), E_INVALIDARG);
    CHECK(e == NULL);
    e = (IEnumGUID *)GARBAGE_PTR;
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 100000, &da20, 0, NULL, &e), E_INVALIDARG);
    CHECK(e == NULL);
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, &da20, 0, NULL, NULL), E_INVALIDARG);
}

static void test_objects(void) {
    uint32_t before = OpcObjectCount();
    OpcRegistry *reg = sample_registry();
    void *p = GARBAGE_PTR;
    IOPCServerList *list = NULL;
    IOPCServerList2 *list2 = NULL;
    IUnknown *u1 = NULL, *u2 = NULL;

    CHECK_HR(OpcServerListCreateOver(reg, NULL, &IID_IOPCServerList, &p), S_OK);
    list = (IOPCServerList *)p;
    /* The object keeps the registry alive: release the handle now. */
    OpcRegistryRelease(reg);
    CHECK_HR(list->lpVtbl->QueryInterface(list, &IID_IOPCServerList2, &p), S_OK);
    list2 = (IOPCServerList2 *)p;
    /* COM identity: both interfaces give the same IUnknown. */
    CHECK_HR(list->lpVtbl->QueryInterface(list, &IID_Unknown_, (void **)&u1), S_OK);
    CHECK_HR(list2->lpVtbl->QueryInterface(list2, &IID_Unknown_, (void **)&u2), S_OK);
    CHECK(u1 == u2);
    u1->lpVtbl->Release(u1);
    u2->lpVtbl->Release(u2);

    test_enumeration_rules(list);
    test_enumerator(list2);
    test_details(list, list2);
    test_prog_ids(list);
    test_bad_enumeration_arguments(list);

    list2->lpVtbl->Release(list2);
    CHECK(list->lpVtbl->Release(list) == 0);
    CHECK(OpcObjectCount() == before);

    /* Creation errors. */
    p = GARBAGE_PTR;
    CHECK_HR(OpcServerListCreate(NULL, &IID_Bogus_, &p), E_NOINTERFACE);
    CHECK(p == NULL);
    p = GARBAGE_PTR;
    CHECK_HR(OpcServerListCreate((IUnknown *)GARBAGE_PTR, &IID_IOPCServerList, &p), CLASS_E_NOAGGREGATION);
    CHECK(p == NULL);
    CHECK_HR(OpcServerListCreate(NULL, NULL, &p), E_POINTER);
    CHECK_HR(OpcServerListCreate(NULL, &IID_IOPCServerList, NULL), E_POINTER);
    CHECK(OpcObjectCount() == before);
}

typedef struct IClassFactoryLike IClassFactoryLike;
typedef struct {
    HRESULT(STDMETHODCALLTYPE_ *QueryInterface)(IClassFactoryLike *, REFIID, void **);
    ULONG(STDMETHODCALLTYPE_ *AddRef)(IClassFactoryLike *);
    ULONG(STDMETHODCALLTYPE_ *Release)(IClassFactoryLike *);
    HRESULT(STDMETHODCALLTYPE_ *CreateInstance)(IClassFactoryLike *, IUnknown *, REFIID, void **);
    HRESULT(STDMETHODCALLTYPE_ *LockServer)(IClassFactoryLike *, BOOL);
} IClassFactoryLikeVtbl;
struct IClassFactoryLike {
    const IClassFactoryLikeVtbl *lpVtbl;
};

static void test_class_factory(void) {
    void *p = GARBAGE_PTR;
    IClassFactoryLike *f;
    IOPCServerList *list;
    CLSID other = test_clsid(9);

    CHECK_HR(OpcDllGetClassObject(&other, &IID_ClassFactory_, &p), CLASS_E_CLASSNOTAVAILABLE);
    CHECK(p == NULL);
    CHECK_HR(OpcDllGetClassObject(&CLSID_OPCServerList, &IID_ClassFactory_, NULL), E_POINTER);
    CHECK_HR(OpcDllGetClassObject(NULL, &IID_ClassFactory_, &p), E_POINTER);
    CHECK_HR(OpcDllGetClassObject(&CLSID_OPCServerList, &IID_IOPCServerList, &p), E_NOINTERFACE);
    CHECK(p == NULL);
    CHECK_HR(OpcDllCanUnloadNow(), S_OK);

    CHECK_HR(OpcDllGetClassObject(&CLSID_OPCServerList, &IID_ClassFactory_, &p), S_OK);
    f = (IClassFactoryLike *)p;
    CHECK_HR(OpcDllCanUnloadNow(), S_FALSE); /* the factory itself is alive */
    CHECK_HR(f->lpVtbl->LockServer(f, TRUE), S_OK);
    CHECK_HR(f->lpVtbl->CreateInstance(f, (IUnknown *)GARBAGE_PTR, &IID_IOPCServerList, &p), CLASS_E_NOAGGREGATION);
    CHECK(p == NULL);
    CHECK_HR(f->lpVtbl->CreateInstance(f, NULL, &IID_IOPCServerList, &p), S_OK);
    list = (IOPCServerList *)p;
    f->lpVtbl->Release(f);
    CHECK_HR(OpcDllCanUnloadNow(), S_FALSE); /* a server list and a lock */
    list->lpVtbl->Release(list);
    CHECK_HR(OpcDllCanUnloadNow(), S_FALSE); /* still locked */
    CHECK_HR(OpcDllGetClassObject(&CLSID_OPCServerList, &IID_ClassFactory_, &p), S_OK);
    f = (IClassFactoryLike *)p;
    CHECK_HR(f->lpVtbl->LockServer(f, FALSE), S_OK);
    CHECK_HR(f->lpVtbl->LockServer(f, FALSE), S_FALSE); /* an unlock too many gives back nothing */
    f->lpVtbl->Release(f);
    CHECK_HR(OpcDllCanUnloadNow(), S_OK);
}

#ifndef _WIN32
/* Off Windows the "system" registry is the process's in-memory one: self-registration and the class
 * factory work against it exactly as on Windows. */
static void test_self_registration_in_process_registry(void) {
    OpcRegistry *sys = NULL;
    LPWSTR before = NULL, after = NULL, s = NULL;
    void *p = NULL;
    IOPCServerList *list;
    CLSID got;

    CHECK_HR(OpcRegistryOpenSystem(&sys), S_OK);
    CHECK_HR(OpcRegistryExport(sys, NULL, &before), S_OK);
    CHECK_HR(OpcDllRegisterServer(), S_OK);
    CHECK_HR(OpcRegistryGetString(sys, W("CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}"), NULL, &s), S_OK);
    CHECK(wstr_is(s, "Opc ServerList Class"));
    OpcTaskMemFree(s);
    CHECK_HR(OpcRegistryGetString(sys, W("CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}\\InprocServer32"),
                                  W("ThreadingModel"), &s),
             S_OK);
    CHECK(wstr_is(s, "Both"));
    OpcTaskMemFree(s);
    CHECK_HR(OpcRegistryGetString(sys, W("OPC.ServerList\\CurVer"), NULL, &s), S_OK);
    CHECK(wstr_is(s, "OPC.ServerList.1"));
    OpcTaskMemFree(s);

    CHECK_HR(OpcServerListCreate(NULL, &IID_IOPCServerList, &p), S_OK);
    list = (IOPCServerList *)p;
    CHECK_HR(list->lpVtbl->CLSIDFromProgID(list, W("OPC.ServerList.1"), &got), S_OK);
    CHECK(same_guid(&got, &CLSID_OPCServerList));
    list->lpVtbl->Release(list);

    CHECK_HR(OpcDllUnregisterServer(), S_OK);
    CHECK_HR(OpcRegistryExport(sys, NULL, &after), S_OK);
    CHECK(wsame(before, after));
    CHECK_HR(OpcDllUnregisterServer(), S_OK); /* unregistering twice is harmless */
    OpcTaskMemFree(before);
    OpcTaskMemFree(after);
    OpcRegistryRelease(sys);
}
#endif

#ifdef _WIN32
#include "test_server_list_win.h"
#endif

int main(void) {
    uint32_t before = OpcObjectCount();
    test_objects();
    test_class_factory();
#ifndef _WIN32
    test_self_registration_in_process_registry();
#else
    test_com_activation();
#endif
    CHECK(OpcObjectCount() == before);
    return test_summary("test_server_list");
}
