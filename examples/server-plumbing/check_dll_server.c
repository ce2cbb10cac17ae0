/* Checks the plumbing example's DLL server (dll_server.c) as COM uses it, and so what
 * docs/guide/server-plumbing.md says of it: its class factory hands out server objects (IOPCCommon
 * aggregated) up to its licence and refuses more with CLASS_E_NOTLICENSED; the server objects and
 * LockServer keep the DLL (DllCanUnloadNow), and an unmatched LockServer(FALSE) takes nothing; the
 * registration names the DLL by the path it was loaded from, and unregistration removes it. */
#include "dll_server.h"

#include "test_check.h"

typedef HRESULT(STDAPICALLTYPE *GetClassObjectFn)(REFCLSID, REFIID, void **);
typedef HRESULT(STDAPICALLTYPE *PlainFn)(void);

static IOPCCommon *create(IClassFactory *factory, HRESULT want) {
    IOPCCommon *c = (IOPCCommon *)GARBAGE_PTR;
    CHECK_HR(factory->lpVtbl->CreateInstance(factory, NULL, &IID_IOPCCommon, (void **)&c), want);
    if (FAILED(want)) CHECK(c == NULL);
    return SUCCEEDED(want) ? c : NULL;
}

int main(void) {
    HMODULE dll;
    GetClassObjectFn get_class_object;
    PlainFn can_unload, register_server, unregister_server;
    IClassFactory *factory = (IClassFactory *)GARBAGE_PTR;
    IOPCCommon *a, *b, *c;
    IUnknown *identity = NULL, *outer = (IUnknown *)GARBAGE_PTR;
    LCID lcid = 0;
    WCHAR dll_path[MAX_PATH], registered[MAX_PATH], key[128];
    DWORD size;
    HKEY h;
    CLSID other = CLSID_PlumbingServer;

    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    dll = LoadLibraryW(L"plumbing_server.dll");
    CHECK(dll != NULL);
    if (!dll) return test_summary("example_server_plumbing");
    get_class_object = (GetClassObjectFn)(void (*)(void))GetProcAddress(dll, "DllGetClassObject");
    can_unload = (PlainFn)(void (*)(void))GetProcAddress(dll, "DllCanUnloadNow");
    register_server = (PlainFn)(void (*)(void))GetProcAddress(dll, "DllRegisterServer");
    unregister_server = (PlainFn)(void (*)(void))GetProcAddress(dll, "DllUnregisterServer");
    CHECK(get_class_object && can_unload && register_server && unregister_server);
    if (!get_class_object || !can_unload || !register_server || !unregister_server) return test_summary("example_server_plumbing");

    /* The class object of its one class, which does not count on the DLL. */
    other.Data1++;
    CHECK_HR(get_class_object(&other, &IID_IClassFactory, (void **)&factory), CLASS_E_CLASSNOTAVAILABLE);
    CHECK(factory == NULL);
    CHECK_HR(get_class_object(&CLSID_PlumbingServer, &IID_IClassFactory, (void **)&factory), S_OK);
    if (!factory) return test_summary("example_server_plumbing");
    CHECK_HR(can_unload(), S_OK);

    /* Server objects up to the licence; each with its own IOPCCommon session and one identity. */
    CHECK_HR(factory->lpVtbl->CreateInstance(factory, (IUnknown *)GARBAGE_PTR, &IID_IUnknown, (void **)&outer),
             CLASS_E_NOAGGREGATION);
    CHECK(outer == NULL);
    a = create(factory, S_OK);
    b = create(factory, S_OK);
    c = create(factory, CLASS_E_NOTLICENSED); /* PLUMBING_MAX_CLIENTS is 2 */
    CHECK(a && b && c == NULL);
    if (!a || !b) return test_summary("example_server_plumbing");
    CHECK_HR(a->lpVtbl->SetLocaleID(a, 0x0407), S_OK);
    CHECK_HR(a->lpVtbl->GetLocaleID(a, &lcid), S_OK);
    CHECK(lcid == 0x0407);
    CHECK_HR(b->lpVtbl->GetLocaleID(b, &lcid), S_OK);
    CHECK(lcid == LOCALE_SYSTEM_DEFAULT); /* a session per server object */
    CHECK_HR(a->lpVtbl->QueryInterface(a, &IID_IUnknown, (void **)&identity), S_OK);
    CHECK(identity != NULL && identity != (IUnknown *)a); /* the server object, not the session */
    if (identity) identity->lpVtbl->Release(identity);
    CHECK_HR(can_unload(), S_FALSE);

    /* A licence comes back with its object. */
    a->lpVtbl->Release(a);
    c = create(factory, S_OK);
    if (c) c->lpVtbl->Release(c);

    /* An unmatched LockServer(FALSE) takes nothing: the object still held keeps the DLL. */
    CHECK_HR(factory->lpVtbl->LockServer(factory, FALSE), E_UNEXPECTED);
    CHECK_HR(can_unload(), S_FALSE);
    b->lpVtbl->Release(b);
    CHECK_HR(can_unload(), S_OK);
    CHECK_HR(factory->lpVtbl->LockServer(factory, TRUE), S_OK);
    CHECK_HR(can_unload(), S_FALSE);
    CHECK_HR(factory->lpVtbl->LockServer(factory, FALSE), S_OK);
    CHECK_HR(can_unload(), S_OK);
    factory->lpVtbl->Release(factory);

    /* DllRegisterServer names this DLL by the path it was loaded from. */
    CHECK(GetModuleFileNameW(dll, dll_path, MAX_PATH) > 0);
    lstrcpyW(key, L"CLSID\\{5EC0A7B1-6C1D-4E51-9B0C-2D4F61A3C7E8}\\InprocServer32");
    CHECK_HR(register_server(), S_OK);
    size = sizeof registered;
    CHECK(RegGetValueW(HKEY_CLASSES_ROOT, key, NULL, RRF_RT_REG_SZ, NULL, registered, &size) == ERROR_SUCCESS);
    CHECK(lstrcmpiW(registered, dll_path) == 0);
    size = sizeof registered;
    CHECK(RegGetValueW(HKEY_CLASSES_ROOT, key, L"ThreadingModel", RRF_RT_REG_SZ, NULL, registered, &size) == ERROR_SUCCESS);
    CHECK(lstrcmpW(registered, L"Both") == 0);
    CHECK_HR(unregister_server(), S_OK);
    CHECK(RegOpenKeyExW(HKEY_CLASSES_ROOT, L"CLSID\\{5EC0A7B1-6C1D-4E51-9B0C-2D4F61A3C7E8}", 0, KEY_READ, &h) ==
          ERROR_FILE_NOT_FOUND);
    CHECK(RegOpenKeyExW(HKEY_CLASSES_ROOT, PLUMBING_PROGID, 0, KEY_READ, &h) == ERROR_FILE_NOT_FOUND);

    FreeLibrary(dll);
    CoUninitialize();
    return test_summary("example_server_plumbing");
}
