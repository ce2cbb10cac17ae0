/* The module lock of an EXE server (OpcSetModuleLock) through the public header: every object the
 * library makes, the ones it makes for other objects included (the enumerator a server list returns,
 * its clones), counts on the lock from its creation until it is freed, so an EXE server counting them
 * lives while a client holds any of them; objects made before the lock was set, or after it was
 * cleared, are not counted; the arguments are checked. */
#include "test_util.h"

static long locks, unlocks;
static unsigned objects_at_unlock = 99;

static void OPCCOMN_CDECL on_lock(void *context) {
    CHECK(context == &locks);
    locks++;
}

static void OPCCOMN_CDECL on_unlock(void *context) {
    CHECK(context == &locks);
    unlocks++;
    objects_at_unlock = OpcObjectCount(); /* the object is gone when its unlock comes */
}

static const CATID CATID_DA2_ = {0x63D5F432, 0xCFE4, 0x11D1, {0xB2, 0xC8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};

int main(void) {
    OpcModuleLock lock;
    OpcRegistry *registry = NULL;
    OpcServerRegistration r;
    IOPCServerList2 *list = NULL;
    IOPCEnumGUID *e = NULL, *clone = NULL;
    GUID got[4];
    ULONG fetched = 0;
    const CLSID server = {0xC0000000, 0, 0, {0, 0, 0, 0, 0, 0, 0, 0x42}};

    memset(&lock, 0, sizeof lock);
    lock.struct_size = sizeof lock;
    lock.lock = on_lock;
    lock.unlock = on_unlock;
    lock.context = &locks;

    /* Bad arguments change nothing. */
    lock.struct_size = 4;
    CHECK_HR(OpcSetModuleLock(&lock), E_INVALIDARG);
    lock.struct_size = sizeof lock;
    lock.unlock = NULL;
    CHECK_HR(OpcSetModuleLock(&lock), E_INVALIDARG);
    lock.unlock = on_unlock;

    CHECK_HR(OpcRegistryCreateMemory(&registry), S_OK);
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = server;
    r.prog_id = W("Lock.Test.1");
    r.user_type = W("Module lock test server");
    r.module_path = W("C:\\lock\\test.exe");
    r.implemented_categories = &CATID_DA2_;
    r.implemented_category_count = 1;
    CHECK_HR(OpcRegisterServer(&r, registry), S_OK);

    /* Made before the lock is set: not counted. */
    CHECK_HR(OpcServerListCreateOver(registry, NULL, &IID_IOPCServerList2, (void **)&list), S_OK);
    CHECK_HR(OpcSetModuleLock(&lock), S_OK);
    CHECK(locks == 0);
    if (list) {
        list->lpVtbl->Release(list);
        CHECK(unlocks == 0);
    }

    /* The client's way: it gets the list, an enumerator from it, releases the list and walks the
     * enumerator. The enumerator holds the lock until it is released. */
    list = NULL;
    CHECK_HR(OpcServerListCreateOver(registry, NULL, &IID_IOPCServerList2, (void **)&list), S_OK);
    CHECK(locks == 1 && unlocks == 0);
    if (list) {
        CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, (CATID *)&CATID_DA2_, 0, NULL, &e), S_OK);
        list->lpVtbl->Release(list);
    }
    CHECK(locks - unlocks == 1); /* the list is gone, its enumerator is not */
    if (e) {
        CHECK_HR(e->lpVtbl->Clone(e, &clone), S_OK);
        CHECK(locks - unlocks == 2);
        CHECK_HR(e->lpVtbl->Next(e, 4, got, &fetched), S_FALSE);
        CHECK(fetched == 1 && memcmp(&got[0], &server, sizeof server) == 0);
        e->lpVtbl->Release(e);
        CHECK(locks - unlocks == 1);
    }
    if (clone) {
        CHECK_HR(clone->lpVtbl->Next(clone, 4, got, &fetched), S_FALSE);
        CHECK(fetched == 1);
        clone->lpVtbl->Release(clone);
    }
    CHECK(locks >= 3 && locks == unlocks);
    CHECK(objects_at_unlock == 0);

    /* Cleared: objects made from now on are not counted. */
    CHECK_HR(OpcSetModuleLock(NULL), S_OK);
    list = NULL;
    CHECK_HR(OpcServerListCreateOver(registry, NULL, &IID_IOPCServerList2, (void **)&list), S_OK);
    if (list) list->lpVtbl->Release(list);
    CHECK(locks == unlocks && locks >= 3);

    OpcRegistryRelease(registry);
    CHECK(OpcObjectCount() == 0);
    return test_summary("test_module_lock");
}
