/* The examples of the C API reference's pages "The header", "COM base types" and "Memory" (docs/reference/
 * areas.dox shows the lines between their snippet markers), built and run by ctest
 * (example.reference_basics) on Linux and under Wine, C11 with warnings as errors. */
/* [header] */
#include <opccomn/opccomn.h>

#if OPCCOMN_VERSION_MAJOR == 0 && OPCCOMN_VERSION_MINOR < 3
#error "this program needs opccomn 0.3 or later"
#endif
/* [header] */

#include <string.h>

#include "example.h"

/* [com] */
/* Interfaces from C: each method through lpVtbl, the object first; an identifier by its address, which
 * OPCCOMN_RIID() writes for C and C++ alike. */
static LCID SessionLocale(void) {
    IUnknown *unknown = NULL;
    IOPCCommon *common = NULL;
    LCID locale = 0;
    if (OpcCommonCreate(NULL, NULL, OPCCOMN_RIID(IID_IUnknown), (void **)&unknown) != S_OK) return 0;
    if (unknown->lpVtbl->QueryInterface(unknown, OPCCOMN_RIID(IID_IOPCCommon), (void **)&common) == S_OK) {
        common->lpVtbl->GetLocaleID(common, &locale); /* LOCALE_SYSTEM_DEFAULT */
        common->lpVtbl->Release(common);
    }
    unknown->lpVtbl->Release(unknown);
    return locale;
}
/* [com] */

/* [memory] */
/* Memory crosses the boundary as task memory (CoTaskMemAlloc on Windows): what the library returns is
 * freed with OpcTaskMemFree(), and what a server hands to it is allocated with OpcTaskMemAlloc(), as a
 * text formatted into a new buffer. */
static HRESULT OPCCOMN_CDECL FormattedText(void *context, HRESULT code, LCID locale, LPWSTR *text) {
    static const WCHAR message[] = u"Valve 7 is in manual mode.";
    (void)context;
    (void)locale;
    if (code != (HRESULT)0xE0000007L) return S_FALSE;
    *text = (LPWSTR)OpcTaskMemAlloc(sizeof message);
    if (*text == NULL) return E_OUTOFMEMORY;
    memcpy(*text, message, sizeof message); /* the library hands this very string to the client */
    return S_OK;
}
/* [memory] */

int main(void) {
    check(SessionLocale() == LOCALE_SYSTEM_DEFAULT, "a new session's locale");

    OpcCommonOptions options;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.vendor_error_text = FormattedText;
    IOPCCommon *session = NULL;
    check(OpcCommonCreate(&options, NULL, &IID_IOPCCommon, (void **)&session) == S_OK, "OpcCommonCreate");
    if (session) {
        LPWSTR text = NULL;
        check(session->lpVtbl->GetErrorString(session, (HRESULT)0xE0000007L, &text) == S_OK &&
                  same(text, "Valve 7 is in manual mode."),
              "the formatted text");
        OpcTaskMemFree(text);
        session->lpVtbl->Release(session);
    }
    check(OpcObjectCount() == 0, "every object released");
    return report("reference basics (header, COM base types, memory)");
}
