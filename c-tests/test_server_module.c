/* A server's own classes through the public header, as a DLL server uses them: the class object
 * (OpcClassFactoryCreate, OpcModuleGetClassObject) makes the server's objects and refuses what COM
 * refuses, LockServer and OpcServerLock keep the module (OpcModuleCanUnloadNow) as the server's
 * objects and the library's do, and OpcModuleRegister/OpcModuleUnregister write and remove exactly
 * the classes' registrations. Off Windows OpcExeServerRun checks its arguments and answers E_NOTIMPL. */
#include "test_util.h"

static const CLSID CLSID_One = {0x5EC00011, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0x66}};
static const CLSID CLSID_Two = {0x5EC00012, 0x1111, 0x2222, {0x33, 0x33, 0x44, 0x44, 0x55, 0x55, 0x66, 0x66}};

/* The server's "objects": IOPCCommon sessions, made by the server's create function, which counts
 * each call and can be told to fail. */
static int made, fail_next;

static HRESULT OPCCOMN_CDECL create(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    CHECK(context == &made);
    CHECK(ppv != NULL && *ppv == NULL); /* checked and reset by the library first */
    made++;
    if (fail_next) {
        fail_next = 0;
        *ppv = (void *)(size_t)0x10; /* garbage left with a failure: the library must drop it */
        return E_OUTOFMEMORY;
    }
    return OpcCommonCreate(NULL, outer, riid, ppv);
}

static OpcServerClass make_class(const CLSID *clsid, uint32_t flags) {
    OpcServerClass c;
    memset(&c, 0, sizeof c);
    c.struct_size = sizeof c;
    c.clsid = clsid;
    c.create = create;
    c.context = &made;
    c.flags = flags;
    return c;
}

static int has_key(OpcRegistry *reg, const char *key) {
    LPWSTR text = NULL;
    HRESULT hr = OpcRegistryGetString(reg, W(key), NULL, &text);
    OpcTaskMemFree(text);
    return hr == S_OK;
}

int main(void) {
    OpcServerClass table[2];
    IClassFactory *factory = NULL;
    IUnknown *object = NULL, *inner = NULL;
    void *p = NULL;
    OpcRegistry *reg = NULL;
    OpcServerRegistration r1, r2;
    OpcExeServerOptions exe;

    table[0] = make_class(&CLSID_One, 0);
    table[1] = make_class(&CLSID_Two, OPC_CLASS_AGGREGATABLE);
    CHECK_HR(OpcModuleCanUnloadNow(), S_OK);

    /* The class object of each CLSID makes that class's objects. */
    CHECK_HR(OpcModuleGetClassObject(table, 2, OPCCOMN_RIID(CLSID_One), OPCCOMN_RIID(IID_IClassFactory), &p), S_OK);
    factory = (IClassFactory *)p;
    CHECK_HR(OpcModuleCanUnloadNow(), S_FALSE); /* a client holds the class object */
    CHECK_HR(factory->lpVtbl->CreateInstance(factory, NULL, OPCCOMN_RIID(IID_IOPCCommon), &p), S_OK);
    object = (IUnknown *)p;
    CHECK(made == 1);
    /* An outer object for a class that does not allow aggregation is refused before the server is asked. */
    p = (void *)(size_t)0x10;
    CHECK_HR(factory->lpVtbl->CreateInstance(factory, object, OPCCOMN_RIID(IID_IUnknown), &p), CLASS_E_NOAGGREGATION);
    CHECK(p == NULL && made == 1);
    /* A failing create function: its failure, and never the garbage it left. */
    fail_next = 1;
    CHECK_HR(factory->lpVtbl->CreateInstance(factory, NULL, OPCCOMN_RIID(IID_IUnknown), &p), E_OUTOFMEMORY);
    CHECK(p == NULL && made == 2);
    /* LockServer keeps the module while the client holds nothing else. */
    CHECK_HR(factory->lpVtbl->LockServer(factory, TRUE), S_OK);
    factory->lpVtbl->Release(factory);
    object->lpVtbl->Release(object);
    CHECK_HR(OpcModuleCanUnloadNow(), S_FALSE);
    CHECK_HR(OpcModuleGetClassObject(table, 2, OPCCOMN_RIID(CLSID_One), OPCCOMN_RIID(IID_IClassFactory), &p), S_OK);
    factory = (IClassFactory *)p;
    CHECK_HR(factory->lpVtbl->LockServer(factory, FALSE), S_OK);
    factory->lpVtbl->Release(factory);
    CHECK_HR(OpcModuleCanUnloadNow(), S_OK);
    /* The server's own objects count with OpcServerLock. */
    OpcServerLock();
    CHECK_HR(OpcModuleCanUnloadNow(), S_FALSE);
    OpcServerUnlock();
    OpcServerUnlock(); /* one too many: ignored */
    CHECK_HR(OpcModuleCanUnloadNow(), S_OK);
    /* Each gives back only what it took: a LockServer(FALSE) without a TRUE (any client may send one)
     * does not take the server's own object's count, nor an OpcServerUnlock too many a LockServer's. */
    CHECK_HR(OpcModuleGetClassObject(table, 2, OPCCOMN_RIID(CLSID_One), OPCCOMN_RIID(IID_IClassFactory), &p), S_OK);
    factory = (IClassFactory *)p;
    OpcServerLock();
    CHECK_HR(factory->lpVtbl->LockServer(factory, FALSE), S_FALSE);
    CHECK_HR(factory->lpVtbl->LockServer(factory, TRUE), S_OK);
    OpcServerUnlock();
    OpcServerUnlock(); /* one too many: the LockServer lock stays */
    factory->lpVtbl->Release(factory);
    CHECK_HR(OpcModuleCanUnloadNow(), S_FALSE);
    CHECK_HR(OpcModuleGetClassObject(table, 2, OPCCOMN_RIID(CLSID_One), OPCCOMN_RIID(IID_IClassFactory), &p), S_OK);
    factory = (IClassFactory *)p;
    CHECK_HR(factory->lpVtbl->LockServer(factory, FALSE), S_OK);
    CHECK_HR(factory->lpVtbl->LockServer(factory, FALSE), S_FALSE);
    factory->lpVtbl->Release(factory);
    CHECK_HR(OpcModuleCanUnloadNow(), S_OK);

    /* An aggregatable class: the inner IUnknown for an outer object that asks for IUnknown only. */
    CHECK_HR(OpcClassFactoryCreate(&table[1], OPCCOMN_RIID(IID_IClassFactory), &p), S_OK);
    factory = (IClassFactory *)p;
    CHECK_HR(OpcCommonCreate(NULL, NULL, OPCCOMN_RIID(IID_IUnknown), &p), S_OK);
    object = (IUnknown *)p; /* the stand-in outer object: any live COM object */
    CHECK_HR(factory->lpVtbl->CreateInstance(factory, object, OPCCOMN_RIID(IID_IOPCCommon), &p), CLASS_E_NOAGGREGATION);
    CHECK_HR(factory->lpVtbl->CreateInstance(factory, object, OPCCOMN_RIID(IID_IUnknown), &p), S_OK);
    inner = (IUnknown *)p;
    CHECK(inner != NULL && inner != object);
    CHECK(inner->lpVtbl->Release(inner) == 0);
    object->lpVtbl->Release(object);
    factory->lpVtbl->Release(factory);

    /* What is not in the table, and bad tables. */
    p = (void *)(size_t)0x10;
    CHECK_HR(OpcModuleGetClassObject(table, 1, OPCCOMN_RIID(CLSID_Two), OPCCOMN_RIID(IID_IClassFactory), &p),
             CLASS_E_CLASSNOTAVAILABLE);
    CHECK(p == NULL);
    CHECK_HR(OpcModuleGetClassObject(table, 0, OPCCOMN_RIID(CLSID_One), OPCCOMN_RIID(IID_IClassFactory), &p), E_INVALIDARG);
    CHECK_HR(OpcModuleGetClassObject(table, 2, OPCCOMN_RIID(CLSID_One), OPCCOMN_RIID(IID_IOPCCommon), &p), E_NOINTERFACE);
    table[0].create = NULL;
    CHECK_HR(OpcModuleGetClassObject(table, 2, OPCCOMN_RIID(CLSID_Two), OPCCOMN_RIID(IID_IClassFactory), &p), E_INVALIDARG);
    table[0].create = create;
    CHECK_HR(OpcModuleCanUnloadNow(), S_OK);

    /* Registration of every class that has one, and its exact removal. */
    CHECK_HR(OpcRegistryCreateMemory(&reg), S_OK);
    memset(&r1, 0, sizeof r1);
    r1.struct_size = sizeof r1;
    r1.server_type = OPC_SERVER_TYPE_INPROC;
    r1.clsid = CLSID_One;
    r1.prog_id = W("Module.One.1");
    r1.user_type = W("Module test server one");
    r1.module_path = W("C:\\Vendor\\module.dll");
    r2 = r1;
    r2.clsid = CLSID_Two;
    r2.prog_id = W("Module.Two.1");
    table[0].registration = &r1;
    table[1].registration = &r2;
    CHECK_HR(OpcModuleRegister(table, 2, reg), S_OK);
    CHECK(has_key(reg, "Module.One.1\\CLSID"));
    CHECK(has_key(reg, "Module.Two.1\\CLSID"));
    CHECK_HR(OpcModuleUnregister(table, 2, reg), S_OK);
    CHECK(!has_key(reg, "Module.One.1\\CLSID"));
    CHECK(!has_key(reg, "Module.Two.1\\CLSID"));
    table[1].registration = &r1; /* describes another class */
    CHECK_HR(OpcModuleRegister(table, 2, reg), E_INVALIDARG);
    CHECK(!has_key(reg, "Module.One.1\\CLSID"));
    OpcRegistryRelease(reg);

    /* The EXE host checks its arguments everywhere; off Windows it serves nothing. */
    memset(&exe, 0, sizeof exe);
    exe.struct_size = sizeof exe;
    exe.classes = table;
    exe.class_count = 0;
    CHECK_HR(OpcExeServerRun(&exe, W("-Embedding")), E_INVALIDARG);
    exe.class_count = 1;
    CHECK_HR(OpcExeServerRun(&exe, W("/RegServer /UnregServer")), E_INVALIDARG);
#if !defined(_WIN32)
    CHECK_HR(OpcExeServerRun(&exe, W("-Embedding")), E_NOTIMPL);
#endif
    CHECK_HR(OpcExeServerStop(), S_FALSE); /* no host runs */

    CHECK(OpcObjectCount() == 0);
    return test_summary("test_server_module");
}
