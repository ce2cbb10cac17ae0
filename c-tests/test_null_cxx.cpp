/* The bad-input contract through the C++ interface classes (MIDL's form, `p->Method(...)`): a C++
 * caller that passes NULL gets the same HRESULT as the C tests check through lpVtbl (test_common.c,
 * test_server_list.c, test_shutdown.c), and out-parameters are written the same way. Built and run on
 * Linux and for both Windows DLLs (x64 and x86). */
#include "test_check.h"

static void test_common_nulls() {
    IOPCCommon *c = nullptr;
    void *p = GARBAGE_PTR;
    CHECK_HR(OpcCommonCreate(nullptr, nullptr, IID_IOPCCommon, nullptr), E_POINTER);
    CHECK_HR(OpcCommonCreate(nullptr, nullptr, IID_IOPCCommon, &p), S_OK);
    c = static_cast<IOPCCommon *>(p);
    if (!c) return;
    CHECK_HR(c->GetLocaleID(nullptr), E_INVALIDARG);
    DWORD count = GARBAGE_U32;
    CHECK_HR(c->QueryAvailableLocaleIDs(&count, nullptr), E_INVALIDARG);
    CHECK(count == 0);
    LCID *lcids = static_cast<LCID *>(GARBAGE_PTR);
    CHECK_HR(c->QueryAvailableLocaleIDs(nullptr, &lcids), E_INVALIDARG);
    CHECK(lcids == nullptr);
    CHECK_HR(c->GetErrorString(static_cast<HRESULT>(0xC0040001u), nullptr), E_INVALIDARG);
    LPWSTR text = static_cast<LPWSTR>(GARBAGE_PTR);
    CHECK_HR(c->GetErrorString(static_cast<HRESULT>(0x12345678u), &text), E_INVALIDARG);
    CHECK(text == nullptr);
    CHECK_HR(c->SetClientName(nullptr), E_INVALIDARG);
    CHECK_HR(c->QueryInterface(IID_IOPCCommon, nullptr), E_POINTER);
    CHECK_HR(OpcCommonGetClientName(c, nullptr), E_INVALIDARG);
    CHECK(c->Release() == 0);
}

static void test_server_list_nulls() {
    void *p = GARBAGE_PTR;
    CHECK_HR(OpcServerListCreate(nullptr, IID_IOPCServerList, nullptr), E_POINTER);
    CHECK_HR(OpcServerListCreate(nullptr, IID_IOPCServerList2, &p), S_OK);
    IOPCServerList2 *list2 = static_cast<IOPCServerList2 *>(p);
    if (!list2) return;
    CATID da20 = CATID_OPCDAServer20;
    IOPCEnumGUID *e = static_cast<IOPCEnumGUID *>(GARBAGE_PTR);
    CHECK_HR(list2->EnumClassesOfCategories(1, &da20, 0, nullptr, nullptr), E_INVALIDARG);
    CHECK_HR(list2->EnumClassesOfCategories(1, nullptr, 0, nullptr, &e), E_INVALIDARG);
    CHECK(e == nullptr);
    CHECK_HR(list2->CLSIDFromProgID(W("Some.Server.1"), nullptr), E_INVALIDARG);
    CLSID clsid;
    memset(&clsid, 0xAB, sizeof clsid);
    CHECK_HR(list2->CLSIDFromProgID(nullptr, &clsid), E_INVALIDARG);
    LPOLESTR prog = static_cast<LPOLESTR>(GARBAGE_PTR), user = static_cast<LPOLESTR>(GARBAGE_PTR);
    CHECK_HR(list2->GetClassDetails(CLSID_OPCServerList, &prog, &user, nullptr), E_INVALIDARG);
    CHECK(prog == nullptr && user == nullptr);
    CHECK(list2->Release() == 0);
}

static void test_shutdown_nulls() {
    void *p = GARBAGE_PTR;
    CHECK_HR(OpcShutdownCreate(nullptr, IID_IConnectionPointContainer, nullptr), E_POINTER);
    CHECK_HR(OpcShutdownCreate(nullptr, IID_IConnectionPointContainer, &p), S_OK);
    IConnectionPointContainer *cpc = static_cast<IConnectionPointContainer *>(p);
    if (!cpc) return;
    CHECK_HR(cpc->FindConnectionPoint(IID_IOPCShutdown, nullptr), E_POINTER);
    CHECK_HR(cpc->EnumConnectionPoints(nullptr), E_POINTER);
    IConnectionPoint *cp = nullptr;
    CHECK_HR(cpc->FindConnectionPoint(IID_IOPCShutdown, &cp), S_OK);
    if (cp) {
        DWORD cookie = GARBAGE_U32;
        CHECK_HR(cp->Advise(nullptr, &cookie), E_POINTER);
        CHECK(cookie == 0);
        CHECK_HR(cp->GetConnectionInterface(nullptr), E_POINTER);
        CHECK_HR(cp->EnumConnections(nullptr), E_POINTER);
        cp->Release();
    }
    CHECK(cpc->Release() == 0);
}

int main() {
    uint32_t objects = OpcObjectCount();
    test_common_nulls();
    test_server_list_nulls();
    test_shutdown_nulls();
    CHECK(OpcObjectCount() == objects);
    return test_summary("test_null_cxx");
}
