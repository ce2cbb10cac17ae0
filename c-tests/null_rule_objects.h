/* Valid objects and arguments for the generated NULL-rule test (test_null_rule.c, written by
 * tools/gen-null-rule-test.py from the public header). Every case makes its objects afresh with
 * nr_setup() and lets go of all of them in nr_teardown(), which also checks that no library object
 * is left alive. */
#ifndef OPCCOMN_NULL_RULE_OBJECTS_H
#define OPCCOMN_NULL_RULE_OBJECTS_H

#include "test_util.h"

static IUnknown *nr_held[16];
static int nr_count;
static OpcRegistry *nr_reg;
static OpcPattern *nr_pattern_made;

static void *nr_hold(void *p) {
    if (!p) {
        fprintf(stderr, "null_rule: could not make a fixture object\n");
        exit(1);
    }
    nr_held[nr_count++] = (IUnknown *)p;
    return p;
}

static void nr_setup(void) {
    nr_count = 0;
    nr_reg = NULL;
    if (OpcRegistryCreateMemory(&nr_reg) != S_OK) {
        fprintf(stderr, "null_rule: no memory registry\n");
        exit(1);
    }
}

static void nr_teardown(void) {
    while (nr_count > 0) {
        IUnknown *p = nr_held[--nr_count];
        p->lpVtbl->Release(p);
    }
    OpcRegistryRelease(nr_reg);
    nr_reg = NULL;
    OpcPatternFree(nr_pattern_made);
    nr_pattern_made = NULL;
    CHECK(OpcObjectCount() == 0);
}

static void nr_on_shutdown(void *context, LPCWSTR reason) {
    (void)context;
    (void)reason;
}

static IUnknown *nr_unknown(void) {
    void *p = NULL;
    OpcCommonCreate(NULL, NULL, &IID_Unknown_, &p);
    return (IUnknown *)nr_hold(p);
}

static IOPCCommon *nr_common(void) {
    void *p = NULL;
    OpcCommonCreate(NULL, NULL, &IID_IOPCCommon, &p);
    return (IOPCCommon *)nr_hold(p);
}

static IOPCShutdown *nr_sink(void) {
    void *p = NULL;
    OpcShutdownSinkCreate(nr_on_shutdown, NULL, &IID_IOPCShutdown, &p);
    return (IOPCShutdown *)nr_hold(p);
}

static IConnectionPointContainer *nr_container(void) {
    void *p = NULL;
    OpcShutdownCreate(NULL, &IID_IConnectionPointContainer, &p);
    return (IConnectionPointContainer *)nr_hold(p);
}

static IConnectionPoint *nr_point(void) {
    IConnectionPointContainer *c = nr_container();
    IConnectionPoint *p = NULL;
    c->lpVtbl->FindConnectionPoint(c, &IID_IOPCShutdown, &p);
    return (IConnectionPoint *)nr_hold(p);
}

static IEnumConnectionPoints *nr_enum_points(void) {
    IConnectionPointContainer *c = nr_container();
    IEnumConnectionPoints *e = NULL;
    c->lpVtbl->EnumConnectionPoints(c, &e);
    return (IEnumConnectionPoints *)nr_hold(e);
}

static IEnumConnections *nr_enum_connections(void) {
    IConnectionPoint *p = nr_point();
    IEnumConnections *e = NULL;
    p->lpVtbl->EnumConnections(p, &e);
    return (IEnumConnections *)nr_hold(e);
}

static IOPCServerList *nr_list(void) {
    void *p = NULL;
    OpcServerListCreateOver(nr_reg, NULL, &IID_IOPCServerList, &p);
    return (IOPCServerList *)nr_hold(p);
}

static IOPCServerList2 *nr_list2(void) {
    void *p = NULL;
    OpcServerListCreateOver(nr_reg, NULL, &IID_IOPCServerList2, &p);
    return (IOPCServerList2 *)nr_hold(p);
}

static IEnumGUID *nr_enum_guid(void) {
    IOPCServerList *l = nr_list();
    IEnumGUID *e = NULL;
    l->lpVtbl->EnumClassesOfCategories(l, 0, NULL, 0, NULL, &e);
    return (IEnumGUID *)nr_hold(e);
}

static IOPCEnumGUID *nr_enum_opc_guid(void) {
    IOPCServerList2 *l = nr_list2();
    IOPCEnumGUID *e = NULL;
    l->lpVtbl->EnumClassesOfCategories(l, 0, NULL, 0, NULL, &e);
    return (IOPCEnumGUID *)nr_hold(e);
}

static IClassFactory *nr_factory(void) {
    void *p = NULL;
    OpcDllGetClassObject(&CLSID_OPCServerList, &IID_IClassFactory, &p);
    return (IClassFactory *)nr_hold(p);
}

/* A server class whose instances are IOPCCommon sessions, for the class-object and module functions. */
static const GUID nr_class_id = {0x5ec00001, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0x66}};

static HRESULT OPCCOMN_CDECL nr_create_instance(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    (void)context;
    return OpcCommonCreate(NULL, outer, riid, ppv);
}

static const OpcServerClass *nr_server_class(void) {
    static OpcServerClass c;
    memset(&c, 0, sizeof c);
    c.struct_size = sizeof c;
    c.clsid = &nr_class_id;
    c.create = nr_create_instance;
    return &c;
}

/* Interface pointers, each of its own object, for arguments of type IUnknown *. */
static IUnknown *nr_common_unknown(void) { return (IUnknown *)nr_common(); }
static IUnknown *nr_container_unknown(void) { return (IUnknown *)nr_container(); }
static IUnknown *nr_sink_unknown(void) { return (IUnknown *)nr_sink(); }

static const OpcPattern *nr_pattern(void) {
    OpcPatternFree(nr_pattern_made);
    nr_pattern_made = NULL;
    OpcPatternCompileW(W("a*"), TRUE, &nr_pattern_made);
    return nr_pattern_made;
}

static const OpcVersion nr_version = {1, 2, 3};

static CATID nr_catids[1];
static CATID *nr_categories(void) {
    nr_catids[0] = CATID_OPCDAServer20;
    return nr_catids;
}

static const OpcServerRegistration *nr_registration(void) {
    static OpcServerRegistration r;
    static const CLSID clsid = {0x6A1F2E40, 0x1B7C, 0x4D5E, {0x9A, 0x3B, 0x2C, 0x4D, 0x5E, 0x6F, 0x70, 0x81}};
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = clsid;
    r.prog_id = W("NullRule.Server.1");
    r.user_type = W("Null rule server");
    r.module_path = W("C:\\null-rule\\server.exe");
    return &r;
}

static int nr_is_zero(const void *p, size_t n) {
    const unsigned char *b = (const unsigned char *)p;
    size_t i;
    for (i = 0; i < n; i++) {
        if (b[i]) return 0;
    }
    return 1;
}

#endif
