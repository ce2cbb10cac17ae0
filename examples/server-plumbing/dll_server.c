/* A DLL server (InprocServer32) with a class factory of its own, on the library's pieces: the snippets
 * of docs/guide/server-plumbing.md ("A class factory of your own", "A module path known only at run
 * time"), built and run by ctest on Windows (example.server_plumbing: check_dll_server.c loads it as
 * COM does and checks what the guide says of it).
 *
 * The factory does work of its own, which the library's class object (OpcClassFactoryCreate) does not
 * do: it lets PLUMBING_MAX_CLIENTS server objects exist at a time (a licence, as many commercial
 * servers have) and answers CLASS_E_NOTLICENSED beyond that. From the library it takes the server
 * count (OpcServerLock / OpcServerUnlock, which DllCanUnloadNow reads through OpcModuleCanUnloadNow),
 * IOPCCommon (OpcCommonCreate, aggregated into each server object) and the registration
 * (OpcRegisterServer), which names the DLL by the path Windows loaded it from. */
#include "dll_server.h"

#include <string.h>

/* Exported under their undecorated names, also on 32-bit Windows where STDAPI is __stdcall: with
 * mingw-w64, dllexport and -Wl,--kill-at; Visual Studio projects list them in a .def file. */
#if defined(__GNUC__)
#define PLUMBING_EXPORT __declspec(dllexport)
#else
#define PLUMBING_EXPORT
#endif

/* ---- The server object: its own IUnknown, IOPCCommon aggregated ---- */
typedef struct Server {
    IUnknown unk;     /* the controlling unknown, and the object's identity */
    LONG refs;
    IUnknown *common; /* the IOPCCommon session's inner IUnknown: kept for the object's life */
} Server;

static LONG g_clients; /* server objects alive (the licence) */

static HRESULT STDMETHODCALLTYPE Server_QueryInterface(IUnknown *self, REFIID riid, void **ppv) {
    Server *s = (Server *)self;
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!riid) return E_INVALIDARG;
    if (IsEqualIID(riid, &IID_IUnknown)) {
        *ppv = &s->unk;
        self->lpVtbl->AddRef(self);
        return S_OK;
    }
    /* The session answers for IOPCCommon; its interface counts on this object. */
    if (IsEqualIID(riid, &IID_IOPCCommon)) return s->common->lpVtbl->QueryInterface(s->common, riid, ppv);
    return E_NOINTERFACE;
}

static ULONG STDMETHODCALLTYPE Server_AddRef(IUnknown *self) {
    return (ULONG)InterlockedIncrement(&((Server *)self)->refs);
}

static ULONG STDMETHODCALLTYPE Server_Release(IUnknown *self) {
    Server *s = (Server *)self;
    LONG refs = InterlockedDecrement(&s->refs);
    if (refs == 0) {
        if (s->common) s->common->lpVtbl->Release(s->common);
        HeapFree(GetProcessHeap(), 0, s);
        InterlockedDecrement(&g_clients); /* a licence free again */
        OpcServerUnlock();                /* taken when the object was made */
    }
    return (ULONG)refs;
}

static IUnknownVtbl server_vtbl = {Server_QueryInterface, Server_AddRef, Server_Release};

/* Makes a server object, which holds one of the licences (taken by the caller), and returns its
 * interface `riid`; counts it on the DLL while it lives. */
static HRESULT Server_Create(REFIID riid, void **ppv) {
    Server *s = (Server *)HeapAlloc(GetProcessHeap(), HEAP_ZERO_MEMORY, sizeof *s);
    HRESULT hr;
    if (!s) {
        InterlockedDecrement(&g_clients);
        return E_OUTOFMEMORY;
    }
    s->unk.lpVtbl = &server_vtbl;
    s->refs = 1;                 /* the creator's reference, given back below */
    OpcServerLock();             /* given back by the last Release */
    hr = OpcCommonCreate(NULL, &s->unk, &IID_IUnknown, (void **)&s->common);
    if (SUCCEEDED(hr)) hr = s->unk.lpVtbl->QueryInterface(&s->unk, riid, ppv);
    s->unk.lpVtbl->Release(&s->unk); /* frees the object when creating or QueryInterface failed */
    return hr;
}

/* ---- The class factory ---- */
static LONG g_locks; /* LockServer(TRUE) calls not given back yet */

static HRESULT STDMETHODCALLTYPE Factory_QueryInterface(IClassFactory *self, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!riid) return E_INVALIDARG;
    if (!IsEqualIID(riid, &IID_IUnknown) && !IsEqualIID(riid, &IID_IClassFactory)) return E_NOINTERFACE;
    *ppv = self;
    return S_OK;
}

/* A class object does not count on the DLL (COM's rule: a client that keeps one calls LockServer). */
static ULONG STDMETHODCALLTYPE Factory_AddRef(IClassFactory *self) {
    (void)self;
    return 2;
}
static ULONG STDMETHODCALLTYPE Factory_Release(IClassFactory *self) {
    (void)self;
    return 1;
}

static HRESULT STDMETHODCALLTYPE Factory_CreateInstance(IClassFactory *self, IUnknown *outer, REFIID riid, void **ppv) {
    (void)self;
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!riid) return E_INVALIDARG;
    if (outer) return CLASS_E_NOAGGREGATION;
    /* The factory's own work: no more server objects at a time than the licence allows. A licence is
     * taken before the object is made, so that two clients at once cannot both take the last one. */
    if (InterlockedIncrement(&g_clients) > PLUMBING_MAX_CLIENTS) {
        InterlockedDecrement(&g_clients);
        return CLASS_E_NOTLICENSED;
    }
    return Server_Create(riid, ppv); /* the object gives its licence back when it is freed */
}

static HRESULT STDMETHODCALLTYPE Factory_LockServer(IClassFactory *self, BOOL lock) {
    LONG n;
    (void)self;
    if (lock) {
        InterlockedIncrement(&g_locks);
        OpcServerLock();
        return S_OK;
    }
    /* Gives back only what LockServer(TRUE) took: an unmatched LockServer(FALSE) must not take the
     * count a server object holds (the DLL would be unloaded under it). */
    for (n = g_locks; n > 0; n = g_locks) {
        if (InterlockedCompareExchange(&g_locks, n - 1, n) == n) {
            OpcServerUnlock();
            return S_OK;
        }
    }
    return E_UNEXPECTED;
}

static IClassFactoryVtbl factory_vtbl = {Factory_QueryInterface, Factory_AddRef, Factory_Release,
                                          Factory_CreateInstance, Factory_LockServer};
static IClassFactory g_factory = {&factory_vtbl};

/* ---- The four Dll* exports ---- */
static HMODULE g_module; /* this DLL: where it was loaded from is known only at run time */

BOOL WINAPI DllMain(HINSTANCE instance, DWORD reason, LPVOID reserved) {
    (void)reserved;
    if (reason == DLL_PROCESS_ATTACH) {
        g_module = instance;
        DisableThreadLibraryCalls(instance);
    }
    return TRUE;
}

PLUMBING_EXPORT HRESULT STDAPICALLTYPE DllGetClassObject(REFCLSID rclsid, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!rclsid || !riid) return E_INVALIDARG;
    if (!IsEqualCLSID(rclsid, &CLSID_PlumbingServer)) return CLASS_E_CLASSNOTAVAILABLE;
    return g_factory.lpVtbl->QueryInterface(&g_factory, riid, ppv);
}

/* S_OK when no server object and no LockServer lock is left, and no object of the library either. */
PLUMBING_EXPORT HRESULT STDAPICALLTYPE DllCanUnloadNow(void) { return OpcModuleCanUnloadNow(); }

/* The registration names this DLL by its own path: NULL would name the module the library's code
 * is in, opccomn.dll. */
static HRESULT Register(BOOL add) {
    WCHAR path[MAX_PATH];
    OpcServerRegistration r;
    DWORD length = GetModuleFileNameW(g_module, path, MAX_PATH);
    if (length == 0 || length >= MAX_PATH) return E_FAIL; /* no path, or one cut short */
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_INPROC;
    r.clsid = CLSID_PlumbingServer;
    r.prog_id = PLUMBING_PROGID;
    r.user_type = L"opccomn plumbing example server";
    r.module_path = path;
    r.threading_model = L"Both";
    return add ? OpcRegisterServer(&r, NULL) : OpcUnregisterServer(&r, NULL);
}

PLUMBING_EXPORT HRESULT STDAPICALLTYPE DllRegisterServer(void) { return Register(TRUE); }
PLUMBING_EXPORT HRESULT STDAPICALLTYPE DllUnregisterServer(void) { return Register(FALSE); }
