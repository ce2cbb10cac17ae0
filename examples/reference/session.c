/* The examples of the C API reference's pages "IOPCCommon" and "Error texts" (docs/reference/areas.dox
 * shows the lines between their snippet markers), built and run by ctest
 * (example.reference_session) on Linux and under Wine, C11 with warnings as errors. */
#include <string.h>

#include "example.h"

/* [iopccommon] */
/* The server's own text for its vendor-specific code, asked before the library's catalog. */
static HRESULT OPCCOMN_CDECL VendorText(void *context, HRESULT code, LCID locale, LPCWSTR *text) {
    (void)context;
    (void)locale; /* the client's locale, resolved: 0x0407 for German */
    if (code != (HRESULT)0xE0000001L) return S_FALSE; /* not ours: the catalog's text */
    *text = u"The valve is in manual mode.";
    return S_OK;
}

/* One client session: English and German, the server's own texts first. (A server object aggregates
 * it: pass its controlling IUnknown as `outer` and IID_IUnknown.) */
static IOPCCommon *NewSession(void) {
    static const LCID locales[] = {0x0409, 0x0407};
    OpcCommonOptions options;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.locales = locales;
    options.locale_count = 2;
    options.vendor_error_string = VendorText;
    IOPCCommon *session = NULL;
    HRESULT hr = OpcCommonCreate(&options, NULL, OPCCOMN_RIID(IID_IOPCCommon), (void **)&session);
    return hr == S_OK ? session : NULL;
}

/* What a client does through the interface, and what the server reads back. */
static void UseSession(IOPCCommon *session) {
    session->lpVtbl->SetLocaleID(session, 0x0407);
    session->lpVtbl->SetClientName(session, u"Operator station 3");
    LPWSTR text = NULL;
    if (session->lpVtbl->GetErrorString(session, (HRESULT)0xE0000001L, &text) == S_OK)
        OpcTaskMemFree(text); /* "The valve is in manual mode." */

    LCID locale = 0;
    LPWSTR name = NULL;
    OpcCommonGetLocale((IUnknown *)session, &locale);   /* 0x0407 */
    OpcCommonGetClientName((IUnknown *)session, &name); /* "Operator station 3" */
    OpcTaskMemFree(name);
}
/* [iopccommon] */

/* [errors] */
/* IOPCEventServer::GetErrorString of an Alarms & Events server: the text in the client's locale, as
 * that specification words it. */
static HRESULT EventServerErrorString(HRESULT code, LCID locale, LPWSTR *text) {
    return OpcGetErrorStringEx(code, locale, OPC_SERVER_KIND_ALARMS_EVENTS, text);
}

/* The codes the Data Access specification publishes, each with its name and its English text. */
static DWORD ListDataAccessCodes(void) {
    DWORD count = 0;
    HRESULT *codes = NULL;
    if (OpcErrorCodesOfKind(OPC_SERVER_KIND_DATA_ACCESS, &count, &codes) != S_OK) return 0;
    for (DWORD i = 0; i < count; i++) {
        LPWSTR symbol = NULL, text = NULL;
        OpcErrorSymbol(codes[i], OPC_SERVER_KIND_DATA_ACCESS, &symbol);            /* OPC_E_INVALIDHANDLE, ... */
        OpcGetErrorStringEx(codes[i], 0x0409, OPC_SERVER_KIND_DATA_ACCESS, &text); /* its English text */
        OpcTaskMemFree(symbol);
        OpcTaskMemFree(text);
    }
    OpcTaskMemFree(codes);
    return count;
}
/* [errors] */

int main(void) {
    IOPCCommon *session = NewSession();
    check(session != NULL, "OpcCommonCreate");
    if (session) {
        UseSession(session);
        LCID locale = 0;
        LPWSTR text = NULL, name = NULL;
        check(OpcCommonGetLocale((IUnknown *)session, &locale) == S_OK && locale == 0x0407, "the client's locale");
        check(OpcCommonGetClientName((IUnknown *)session, &name) == S_OK && same(name, "Operator station 3"),
              "the client's name");
        OpcTaskMemFree(name);
        check(session->lpVtbl->GetErrorString(session, (HRESULT)0xE0000001L, &text) == S_OK &&
                  same(text, "The valve is in manual mode."),
              "the vendor's text");
        OpcTaskMemFree(text);
        check(session->lpVtbl->SetLocaleID(session, 0x040C) == E_INVALIDARG, "a locale not offered");
        session->lpVtbl->Release(session);
    }

    LPWSTR text = NULL;
    check(EventServerErrorString((HRESULT)0xC0040203L, 0x0409, &text) == S_OK &&
              same(text, "The string was not recognized as an area name."),
          "the Alarms & Events text of C0040203");
    OpcTaskMemFree(text);
    check(ListDataAccessCodes() == 28, "28 Data Access codes");
    check(OpcObjectCount() == 0, "every object released");
    return report("reference session (IOPCCommon, error texts)");
}
