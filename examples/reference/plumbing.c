/* The example of the C API reference's page "Server plumbing" (docs/reference/areas.dox shows the
 * lines between its snippet markers), built and run by ctest (example.reference_plumbing) on Linux
 * and under Wine, C11 with warnings as errors. The test asks the class table for its class object as
 * COM would, and makes an object with it; the EXE `main` is compiled, not run (it would serve). */
#include <string.h>

#include "example.h"

static const CLSID CLSID_MyServer = {0x8a3f54c2, 0x1b7d, 0x4e09, {0x9c, 0x61, 0x2d, 0x5e, 0x70, 0x13, 0xa4, 0xb8}};

int ExampleExeMain(void);

/* [plumbing] */
/* Makes one server object for IClassFactory::CreateInstance. A real server makes its own object and
 * aggregates the library's into it; here the IOPCCommon session stands in for it. */
static HRESULT OPCCOMN_CDECL CreateServer(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    (void)context;
    return OpcCommonCreate(NULL, outer, riid, ppv);
}

/* The server's class: its CLSID, how to make an object, how to register it. */
static OpcServerClass MyClass(const OpcServerRegistration *registration) {
    OpcServerClass c;
    memset(&c, 0, sizeof c);
    c.struct_size = sizeof c;
    c.clsid = &CLSID_MyServer;
    c.create = CreateServer;
    c.flags = OPC_CLASS_AGGREGATABLE;
    c.registration = registration; /* what /RegServer writes (see the registration page) */
    return c;
}

/* An EXE server's main: /RegServer and /UnregServer, -Embedding, its class objects, COM's lifetime
 * rule for local servers and the operator's stop, in one call. */
int ExampleExeMain(void) {
    OpcServerRegistration registration;
    memset(&registration, 0, sizeof registration);
    registration.struct_size = sizeof registration;
    registration.server_type = OPC_SERVER_TYPE_LOCAL;
    registration.clsid = CLSID_MyServer;
    registration.prog_id = u"MyVendor.MyServer.1";
    registration.user_type = u"My OPC Server";
    OpcServerClass cls = MyClass(&registration);
    OpcExeServerOptions options;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.classes = &cls;
    options.class_count = 1;
    HRESULT hr = OpcExeServerRun(&options, NULL); /* NULL: this process's command line */
    return hr == S_OK ? 0 : 1;
}

/* A DLL server's DllGetClassObject and DllCanUnloadNow are one call each over the same table. */
static OpcServerClass dll_classes[1];

static HRESULT MyDllGetClassObject(REFCLSID rclsid, REFIID riid, void **ppv) {
    return OpcModuleGetClassObject(dll_classes, 1, rclsid, riid, ppv);
}

static HRESULT MyDllCanUnloadNow(void) {
    return OpcModuleCanUnloadNow();
}
/* [plumbing] */

int main(void) {
    dll_classes[0] = MyClass(NULL);
    IClassFactory *factory = NULL;
    check(MyDllGetClassObject(&CLSID_MyServer, &IID_IClassFactory, (void **)&factory) == S_OK, "the class object");
    if (factory) {
        IOPCCommon *object = NULL;
        check(MyDllCanUnloadNow() == S_FALSE, "the class object keeps the module");
        check(factory->lpVtbl->CreateInstance(factory, NULL, &IID_IOPCCommon, (void **)&object) == S_OK,
              "CreateInstance");
        factory->lpVtbl->Release(factory);
        check(MyDllCanUnloadNow() == S_FALSE, "an object keeps the module");
        if (object) object->lpVtbl->Release(object);
    }
    check(MyDllCanUnloadNow() == S_OK, "nothing keeps the module");
    check(MyDllGetClassObject(&IID_IUnknown, &IID_IClassFactory, (void **)&factory) == CLASS_E_CLASSNOTAVAILABLE,
          "another CLSID");
    check(OpcObjectCount() == 0, "every object released");
    return report("reference plumbing");
}
