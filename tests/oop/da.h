/* Shared by the cross-process test of the Data Access proxy/stub (test_da_tables.c, the client) and
 * its EXE server (da_server.c): the classes, the items the server serves with their values, and the
 * registration of opccomn.dll's proxy/stub (or of the stand-in for the Foundation's) as this process's
 * for the Data Access interfaces. Windows only; the types and IIDs come from the header widl generates from
 * idl/opcda.idl (opcda_idl.h; this file defines the IIDs, so one translation unit per program). */
#ifndef OPCCOMN_DA_H
#define OPCCOMN_DA_H

#include "classic_oop.h"

#include <initguid.h>
#include <ocidl.h>

#include "opcda_idl.h"

/* The test DA server (da_server.c, LocalServer32). */
static const CLSID CLSID_DaTestServer = {0xC3000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0xDA, 0x02}};

/* The Data Access interfaces opccomn.dll's proxy/stub serves in these two processes. */
static const IID *const DA_IIDS[] = {
    &IID_IOPCServer, &IID_IOPCServerPublicGroups, &IID_IOPCBrowseServerAddressSpace, &IID_IOPCGroupStateMgt,
    &IID_IOPCPublicGroupStateMgt, &IID_IOPCSyncIO, &IID_IOPCAsyncIO, &IID_IOPCItemMgt, &IID_IEnumOPCItemAttributes,
    &IID_IOPCDataCallback, &IID_IOPCAsyncIO2, &IID_IOPCItemProperties, &IID_IOPCItemDeadbandMgt,
    &IID_IOPCItemSamplingMgt, &IID_IOPCBrowse, &IID_IOPCItemIO, &IID_IOPCSyncIO2, &IID_IOPCAsyncIO3,
    &IID_IOPCGroupStateMgt2};
#define DA_IID_COUNT (sizeof DA_IIDS / sizeof DA_IIDS[0])

/* The CLSID of opc_classic_widl_ps.dll (classic_widl_ps.c), the stand-in for the OPC Foundation's
 * proxy/stub of the same interfaces. */
static const CLSID CLSID_ClassicWidlProxyStub = {0xC3000000, 0x5EED, 0x4000, {0x80, 0, 0, 0, 0, 0, 0xDA, 0x01}};

typedef HRESULT(STDAPICALLTYPE *DaGetClassObjectFn)(REFCLSID, REFIID, void **);

/* Makes COM use opc_classic_widl_ps.dll for the Data Access interfaces in this process (the
 * multithreaded apartment). */
static HRESULT use_classic_proxy_stub(void) {
    HMODULE dll = LoadLibraryW(L"opc_classic_widl_ps.dll");
    DaGetClassObjectFn get;
    IUnknown *factory = NULL;
    DWORD cookie;
    HRESULT hr;
    size_t i;
    if (!dll) return HRESULT_FROM_WIN32(GetLastError());
    get = (DaGetClassObjectFn)(void (*)(void))GetProcAddress(dll, "DllGetClassObject");
    if (!get) return E_NOINTERFACE;
    hr = get(&CLSID_ClassicWidlProxyStub, &IID_IUnknown, (void **)&factory);
    if (FAILED(hr)) return hr;
    hr = CoRegisterClassObject(&CLSID_ClassicWidlProxyStub, factory, CLSCTX_INPROC_SERVER, REGCLS_MULTIPLEUSE,
                               &cookie);
    factory->lpVtbl->Release(factory);
    for (i = 0; SUCCEEDED(hr) && i < DA_IID_COUNT; i++) hr = CoRegisterPSClsid(DA_IIDS[i], &CLSID_ClassicWidlProxyStub);
    return hr;
}

/* Makes COM use opccomn.dll's proxy/stub (CLSID_OpcComnProxyStub) for the Data Access interfaces in
 * this process (the multithreaded apartment), without the registry. */
static HRESULT use_opccomn_proxy_stub(void) { return use_opccomn_proxy_stub_for(DA_IIDS, DA_IID_COUNT); }

/* Whether COM takes this process's proxies and stubs of every Data Access interface from opccomn.dll. */
static int da_proxy_stub_is_opccomn(void) { return proxy_stub_is_opccomn_for(DA_IIDS, DA_IID_COUNT); }

/* A code the server's IOPCServer::GetErrorString answers with "opccomn" when its proxy/stub for the
 * DA interfaces is opccomn.dll's, "widl" when it is opc_classic_widl_ps.dll's, "other" otherwise. */
#define DA_CODE_PROXY_STUB ((HRESULT)0xE0040301L)
/* Codes answered with the server's da_process_cpu_ns() and its process identifier, as text (for the
 * DA benchmark, benches/da_bench.c). */
#define DA_CODE_CPU_TIME ((HRESULT)0xE0040302L)
#define DA_CODE_PROCESS_ID ((HRESULT)0xE0040303L)

/* The CPU time in nanoseconds that this process's threads have used so far. Under Wine a Windows
 * process is a Linux process, whose CPU time Linux keeps to the nanosecond (Wine's GetProcessTimes has
 * the scheduler tick's 10 ms resolution): it is asked directly, clock_gettime(CLOCK_PROCESS_CPUTIME_ID);
 * elsewhere GetProcessTimes. */
static unsigned long long da_process_cpu_ns(void) {
    HMODULE ntdll = GetModuleHandleA("ntdll.dll");
    if (ntdll && GetProcAddress(ntdll, "wine_get_version")) {
        long ret;
#if defined(__x86_64__)
        struct {
            long long sec, nsec;
        } t;
        /* clock_gettime(CLOCK_PROCESS_CPUTIME_ID = 2, &t): x86_64 system call 228 */
        __asm__ volatile("syscall" : "=a"(ret) : "a"(228L), "D"(2L), "S"(&t) : "rcx", "r11", "memory");
#elif defined(__i386__)
        struct {
            long sec, nsec;
        } t;
        /* clock_gettime(CLOCK_PROCESS_CPUTIME_ID = 2, &t): i386 system call 265 */
        __asm__ volatile("int $0x80" : "=a"(ret) : "a"(265L), "b"(2L), "c"(&t) : "memory");
#else
        struct {
            long sec, nsec;
        } t = {0, 0};
        ret = -1;
#endif
        if (ret == 0) return (unsigned long long)t.sec * 1000000000ULL + (unsigned long long)t.nsec;
    }
    return process_cpu_time() * 100ULL;
}

/* The server's class under other CLSIDs, served by a server started with "-set:N" (N from 1 to 9):
 * the benchmark keeps several servers running at once. Set 0 is CLSID_DaTestServer. */
static CLSID da_server_class(unsigned set) {
    CLSID c = CLSID_DaTestServer;
    c.Data4[5] = (unsigned char)set;
    return c;
}

/* Whether COM takes this process's proxies and stubs of every Data Access interface from
 * opc_classic_widl_ps.dll. */
static int da_proxy_stub_is_classic(void) {
    CLSID clsid;
    size_t i;
    for (i = 0; i < DA_IID_COUNT; i++)
        if (FAILED(CoGetPSClsid(DA_IIDS[i], &clsid)) || !IsEqualCLSID(&clsid, &CLSID_ClassicWidlProxyStub)) return 0;
    return 1;
}

/* ---- What the server serves ---- */

#define DA_GROUP_NAME "Gruppe \xc3\xa4\xc3\xb6\xc3\xbc 1"
#define DA_VENDOR_INFO "opccomn DA test server \xe2\x82\xac"
#define DA_ERROR_CODE ((HRESULT)0xC0040007L) /* OPC_E_UNKNOWNITEMID */
#define DA_ERROR_TEXT "The item ID is not defined in the server address space."
#define OPC_E_INVALIDHANDLE_ ((HRESULT)0xC0040001L)
#define OPC_E_UNKNOWNITEMID_ ((HRESULT)0xC0040007L)
#define OPC_QUALITY_GOOD_ 0xC0
#define OPC_READABLE_ 1
#define OPC_WRITEABLE_ 2
#define DA_ITEMS 4
/* Items for the benchmark besides the four above: "Bench.0" to "Bench.199", VT_I4 (even numbers,
 * the value N) and VT_R8 (odd numbers, the value N + 0.5), never in a refresh unless added. */
#define DA_BENCH_ITEMS 200
#define DA_ALL_ITEMS (DA_ITEMS + DA_BENCH_ITEMS)

/* The items: ID, canonical type, and the client handle the test gives each. */
static const char *const DA_ITEM_IDS[DA_ITEMS] = {"Plant.Tank1.Level (I4)", "Plant.Tank1.Temp (R8)",
                                                  "Plant.Tank1.Name (BSTR) \xe2\x82\xac", "Plant.Tank1.Profile (R8[])"};
static const VARTYPE DA_ITEM_TYPES[DA_ITEMS] = {VT_I4, VT_R8, VT_BSTR, VT_ARRAY | VT_R8};
#define DA_CLIENT_HANDLE(i) ((OPCHANDLE)(1000 + (i)))
#define DA_BLOB_SIZE 5
static const BYTE DA_BLOB[DA_BLOB_SIZE] = {1, 2, 3, 0xFE, 0xFF};
#define DA_PROFILE_COUNT 3
static const double DA_PROFILE[DA_PROFILE_COUNT] = {1.5, -2.0, 1e300};
#define DA_TEXT "Tank \xc3\xa4\xc3\xb6\xc3\xbc \xe2\x82\xac \xf0\x9f\x98\x80"
#define DA_I4 12345
#define DA_R8 3.25

/* The item properties the browse calls return (IOPCBrowse, IOPCItemProperties). */
#define DA_PROPERTY_COUNT 2
static const DWORD DA_PROPERTY_IDS[DA_PROPERTY_COUNT] = {1, 101}; /* data type, description */

/* A SAFEARRAY of doubles, or NULL. */
static SAFEARRAY *da_doubles(const double *values, ULONG count) {
    SAFEARRAY *a = SafeArrayCreateVector(VT_R8, 0, count);
    double *data = NULL;
    ULONG i;
    if (!a) return NULL;
    if (FAILED(SafeArrayAccessData(a, (void **)&data))) {
        SafeArrayDestroy(a);
        return NULL;
    }
    for (i = 0; i < count; i++) data[i] = values[i];
    SafeArrayUnaccessData(a);
    return a;
}

/* Whether `v` is a one-dimensional VT_ARRAY | VT_R8 holding `values`. */
static int is_doubles(const VARIANT *v, const double *values, ULONG count) {
    double *data = NULL;
    LONG lower = -1, upper = -1;
    int same;
    ULONG i;
    if (V_VT(v) != (VT_ARRAY | VT_R8) || !V_ARRAY(v) || SafeArrayGetDim(V_ARRAY(v)) != 1) return 0;
    if (FAILED(SafeArrayGetLBound(V_ARRAY(v), 1, &lower)) || FAILED(SafeArrayGetUBound(V_ARRAY(v), 1, &upper)))
        return 0;
    if (lower != 0 || upper != (LONG)count - 1) return 0;
    if (FAILED(SafeArrayAccessData(V_ARRAY(v), (void **)&data))) return 0;
    same = 1;
    for (i = 0; i < count; i++) same &= data[i] == values[i];
    SafeArrayUnaccessData(V_ARRAY(v));
    return same;
}

#endif
