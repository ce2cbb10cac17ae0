/* The lifetime of an out-of-process COM server (an EXE started by COM as LocalServer32) whose objects
 * come from opccomn: class objects, the count of live objects, and the exit when the last one goes.
 * The count covers every object a client can hold (COM's rule for local servers): the EXE's own and,
 * through the library's module lock (OpcSetModuleLock), every object of the library, the ones the
 * library makes for other objects included (a server list's enumerators, a connection point's
 * IEnumConnections). A client that releases the server list and then walks the enumerator it got
 * keeps the process until it releases the enumerator.
 * Used by the server browser service (opccomn_browser.c) and by the cross-process tests' server
 * (tests/oop/oop_server.c). One process, one set of these: include it in one file of the EXE.
 *
 * An object of the EXE calls exe_host_object_created() when it is made and exe_host_object_destroyed()
 * when it is freed (IClassFactory::LockServer counts as one). When the count falls to zero the class
 * objects are revoked at once, so that a client activating now gets a new process instead of this
 * exiting one, and exe_host_serve() returns. */
#ifndef OPCCOMN_EXE_HOST_H
#define OPCCOMN_EXE_HOST_H

#include <string.h>

#include <opccomn/opccomn.h>

#define EXE_HOST_MAX_CLASSES 4

/* Makes an object of one class for IClassFactory::CreateInstance (no aggregation across processes). */
typedef HRESULT (*ExeHostCreate)(REFIID riid, void **ppv);

typedef struct ExeHostClass {
    IClassFactory factory;
    ExeHostCreate create;
} ExeHostClass;

static HANDLE exe_host_done;     /* set when the last object is gone */
static LONG exe_host_objects;    /* live objects and server locks */
static LONG exe_host_in_use;     /* an object was made: a client came */
static LONG exe_host_revoked;
static DWORD exe_host_cookies[EXE_HOST_MAX_CLASSES];
static LONG exe_host_classes;

static void exe_host_revoke(void) {
    LONG i;
    if (InterlockedExchange(&exe_host_revoked, 1) == 0)
        for (i = 0; i < exe_host_classes; i++) CoRevokeClassObject(exe_host_cookies[i]);
}

static void exe_host_object_created(void) {
    InterlockedIncrement(&exe_host_objects);
    InterlockedExchange(&exe_host_in_use, 1);
}

static void exe_host_object_destroyed(void) {
    if (InterlockedDecrement(&exe_host_objects) == 0) {
        exe_host_revoke();
        SetEvent(exe_host_done);
    }
}

/* ---- The class objects: static, never freed, so their reference count is not kept. ---- */
static HRESULT STDMETHODCALLTYPE exe_host_factory_qi(IClassFactory *This, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IClassFactory)) {
        *ppv = This;
        return S_OK;
    }
    return E_NOINTERFACE;
}
static ULONG STDMETHODCALLTYPE exe_host_factory_add_ref(IClassFactory *This) {
    (void)This;
    return 2;
}
static ULONG STDMETHODCALLTYPE exe_host_factory_release(IClassFactory *This) {
    (void)This;
    return 1;
}
static HRESULT STDMETHODCALLTYPE exe_host_factory_create(IClassFactory *This, IUnknown *outer, REFIID riid,
                                                        void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (outer) return CLASS_E_NOAGGREGATION;
    return ((ExeHostClass *)This)->create(riid, ppv);
}
static HRESULT STDMETHODCALLTYPE exe_host_factory_lock(IClassFactory *This, BOOL lock) {
    (void)This;
    if (lock) exe_host_object_created();
    else exe_host_object_destroyed();
    return S_OK;
}
static IClassFactoryVtbl exe_host_factory_vtbl = {exe_host_factory_qi, exe_host_factory_add_ref,
                                                  exe_host_factory_release, exe_host_factory_create,
                                                  exe_host_factory_lock};

/* A class object for `create`, to pass to exe_host_serve(). */
#define EXE_HOST_CLASS(create) {{&exe_host_factory_vtbl}, (create)}

/* ---- The module lock: every object of the library counts as one of this process's objects. ---- */
static void OPCCOMN_CDECL exe_host_lock(void *context) {
    (void)context;
    exe_host_object_created();
}
static void OPCCOMN_CDECL exe_host_unlock(void *context) {
    (void)context;
    exe_host_object_destroyed();
}

/* A server list over `registry` (NULL: the system registry, both views) for CreateInstance. It and
 * everything it hands out (its enumerators and their clones) count through the module lock. */
static HRESULT exe_host_create_server_list(OpcRegistry *registry, REFIID riid, void **ppv) {
    return registry ? OpcServerListCreateOver(registry, NULL, riid, ppv) : OpcServerListCreate(NULL, riid, ppv);
}

/* Sets the module lock (OpcSetModuleLock), so that every object of the library made from now on
 * counts, registers the class objects (COM must be initialized), then serves until the last object is gone:
 * a process no client comes to gives up after idle_ms, one in use after in_use_ms (INFINITE: never);
 * then the class objects are revoked and objects still alive get unreleased_ms (INFINITE: as long as
 * they live) to go. Returns the number of objects left (0: a clean end), or -1 when a class object
 * could not be registered (its HRESULT in *failure).
 *
 * The caller then exits without CoUninitialize: the last Release may still be on its way back to the
 * client on an RPC thread, and CoUninitialize of the apartment that call runs in waits for it (under
 * Wine it can wait for ever). Process exit tears COM down. */
static LONG exe_host_serve(const CLSID *const *clsids, ExeHostClass *classes, LONG count, DWORD idle_ms,
                           DWORD in_use_ms, DWORD unreleased_ms, HRESULT *failure) {
    DWORD waited;
    LONG i;
    OpcModuleLock lock;
    memset(&lock, 0, sizeof lock);
    lock.struct_size = sizeof lock;
    lock.lock = exe_host_lock;
    lock.unlock = exe_host_unlock;
    *failure = OpcSetModuleLock(&lock);
    exe_host_done = CreateEventW(NULL, TRUE, FALSE, NULL);
    if (SUCCEEDED(*failure) && (!exe_host_done || count > EXE_HOST_MAX_CLASSES)) *failure = E_FAIL;
    for (i = 0; SUCCEEDED(*failure) && i < count; i++) {
        *failure = CoRegisterClassObject(clsids[i], (IUnknown *)&classes[i].factory, CLSCTX_LOCAL_SERVER,
                                         REGCLS_MULTIPLEUSE, &exe_host_cookies[i]);
        if (SUCCEEDED(*failure)) exe_host_classes = i + 1;
    }
    if (FAILED(*failure)) {
        exe_host_revoke();
        return -1;
    }
    for (waited = 0; WaitForSingleObject(exe_host_done, 1000) == WAIT_TIMEOUT; waited += 1000) {
        DWORD limit = InterlockedCompareExchange(&exe_host_in_use, 0, 0) ? in_use_ms : idle_ms;
        if (limit != INFINITE && waited >= limit) break;
    }
    exe_host_revoke();
    for (waited = 0; InterlockedCompareExchange(&exe_host_objects, 0, 0) > 0; waited += 50) {
        if (unreleased_ms != INFINITE && waited >= unreleased_ms) break;
        Sleep(50);
    }
    return InterlockedCompareExchange(&exe_host_objects, 0, 0);
}

#endif
