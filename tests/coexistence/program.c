/* Includes opccomn/opccomn.h and the stand-ins for the OPC Foundation's MIDL-generated headers (opccomn.h,
   opcda.h, opc_ae.h, opchda.h, opcerror.h, opcae_er.h, opchda_error.h; see docs/header-coexistence.md),
   in the order OURS_FIRST says, and uses what both declare: the interfaces (C++ classes or C vtables),
   the IIDs, every category, error codes and, in C++, __uuidof of the OPC Common interfaces. Built as C
   and C++, with and without CINTERFACE / COBJMACROS, with -Wall -Wextra -pedantic-errors -Werror;
   linked against the static library or the DLL's import library, with and without the Foundation's
   *_i.c files; run under Wine it checks the values the linker bound. The same with the headers as
   widl writes them (scripts/test-coexistence.sh passes their directory first). */
#if OURS_FIRST
#include <opccomn/opccomn.h>
#include <opccomn.h>
#include <opcda.h>
#include <opc_ae.h>
#include <opchda.h>
#include <opcerror.h>
#include <opcae_er.h>
#include <opchda_error.h>
#else
#include <opccomn.h>
#include <opcda.h>
#include <opc_ae.h>
#include <opchda.h>
#include <opcerror.h>
#include <opcae_er.h>
#include <opchda_error.h>
#include <opccomn/opccomn.h>
#endif

#include <stdio.h>
#include <string.h>

#if defined(__cplusplus) && !defined(CINTERFACE)
#define CALL0(p, iface, m) (p)->m()
#define CALL(p, iface, m, ...) (p)->m(__VA_ARGS__)
#define RIID(x) (x)
#elif defined(COBJMACROS)
#define CALL0(p, iface, m) iface##_##m(p)
#define CALL(p, iface, m, ...) iface##_##m(p, __VA_ARGS__)
#define RIID(x) OPCCOMN_RIID(x)
#else
#define CALL0(p, iface, m) (p)->lpVtbl->m(p)
#define CALL(p, iface, m, ...) (p)->lpVtbl->m(p, __VA_ARGS__)
#define RIID(x) OPCCOMN_RIID(x)
#endif

#if defined(__cplusplus) && !defined(CINTERFACE) && __cplusplus >= 201703L && defined(__MINGW32__)
/* C++17: mingw's __uuidof is a constant expression, whichever header declared the interface (MIDL's,
   widl's or this library's), and for every other type (IUnknown) after opccomn's header too. */
static_assert(__uuidof(IOPCCommon).Data1 == 0xF31DFDE2u && __uuidof(IOPCCommon).Data4[7] == 0xFB, "IOPCCommon");
static_assert(__uuidof(IOPCShutdown).Data1 == 0xF31DFDE1u, "IOPCShutdown");
static_assert(__uuidof(IOPCServerList).Data1 == 0x13486D50u, "IOPCServerList");
static_assert(__uuidof(IOPCEnumGUID).Data1 == 0x55C382C8u, "IOPCEnumGUID");
static_assert(__uuidof(IOPCServerList2).Data1 == 0x9DD0B56Cu, "IOPCServerList2");
static_assert(__uuidof(IOPCCommon *).Data1 == 0xF31DFDE2u, "IOPCCommon *");
static_assert(__uuidof(IUnknown).Data4[0] == 0xC0 && __uuidof(IUnknown).Data4[7] == 0x46, "IUnknown");
#endif

static int same(const GUID *a, unsigned int d1, unsigned short d2, unsigned short d3) {
    return a->Data1 == d1 && a->Data2 == d2 && a->Data3 == d3;
}

int main(void) {
    int failures = 0;
    void *p = NULL;
    IOPCCommon *common = NULL;
    LPWSTR text = NULL;
    LCID lcid = 0;
    const CATID *category = &CATID_OPCDAServer20;
    HRESULT hr = OpcCommonCreate(NULL, NULL, RIID(IID_IOPCCommon), &p);
    if (hr != S_OK || p == NULL) {
        printf("OpcCommonCreate: 0x%08lX\n", (unsigned long)hr);
        return 1;
    }
    common = (IOPCCommon *)p;
    failures += CALL(common, IOPCCommon, GetLocaleID, &lcid) != S_OK;
    failures += CALL(common, IOPCCommon, GetErrorString, OPC_E_INVALIDFILTER, &text) != S_OK || text == NULL;
    OpcTaskMemFree(text);
    failures += CALL0(common, IOPCCommon, Release) != 0;
    failures += !same(&IID_IOPCCommon, 0xF31DFDE2, 0x07B6, 0x11D2);
    failures += !same(&IID_IOPCShutdown, 0xF31DFDE1, 0x07B6, 0x11D2);
    failures += !same(&IID_IOPCServerList2, 0x9DD0B56C, 0xAD9E, 0x43EE);
    failures += !same(category, 0x63D5F432, 0xCFE4, 0x11D1);
    failures += !same(&CATID_OPCDAServer10, 0x63D5F430, 0xCFE4, 0x11D1);
    failures += !same(&CLSID_OPCServerList, 0x13486D51, 0x4821, 0x11D2);
    /* Every category, under the names the Foundation's headers give them (opc_ae.h: CATID_OPCAEServer10
       is IID_OPCEventServerCATID), with or without the *_i.c files. */
    failures += !same(&CATID_OPCDAServer30, 0xCC603642, 0x66D7, 0x48F1);
    failures += !same(&CATID_XMLDAServer10, 0x3098EDA4, 0xA006, 0x48B2);
    failures += !same(&CATID_OPCAEServer10, 0x58E13251, 0xAC87, 0x11D1);
    failures += !same(&IID_OPCEventServerCATID, 0x58E13251, 0xAC87, 0x11D1);
    failures += !same(&CATID_OPCHDAServer10, 0x7DE5B060, 0xE089, 0x11D2);
    failures += !same(&CATID_OPCBatchServer20, 0x843DE67B, 0xB0C9, 0x11D4);
    failures += OPC_E_INVALIDFILTER != (HRESULT)0xC0040009L;
    failures += OPC_E_INVALIDBRANCHNAME != (HRESULT)0xC0040203L;
    failures += OPC_S_NODATA != (HRESULT)0x40041002L;
#if defined(__cplusplus) && !defined(CINTERFACE)
    /* mingw g++ and clang know the interfaces' IIDs through __uuidof, whichever header declared them
       first (MIDL's output declares none; widl's and opccomn/opccomn.h do). */
    failures += !same(&__uuidof(IOPCCommon), 0xF31DFDE2, 0x07B6, 0x11D2);
    failures += !same(&__uuidof(IOPCShutdown), 0xF31DFDE1, 0x07B6, 0x11D2);
    failures += !same(&__uuidof(IOPCServerList), 0x13486D50, 0x4821, 0x11D2);
    failures += !same(&__uuidof(IOPCEnumGUID), 0x55C382C8, 0x21C7, 0x4E88);
    failures += !same(&__uuidof(IOPCServerList2), 0x9DD0B56C, 0xAD9E, 0x43EE);
    failures += !same(&__uuidof(common), 0xF31DFDE2, 0x07B6, 0x11D2);
#endif
    printf("coexistence program: %d failure(s)\n", failures);
    return failures != 0;
}
