// opccomn.h compiles alone as C++11 (-pedantic-errors): extern "C" linkage and the vtable structs.
#include "opccomn.h"

int main() {
    void *p = 0;
    // REFIID is a reference in C++ on Windows and a pointer elsewhere, as in the Windows headers.
#if defined(_WIN32)
    HRESULT hr = OpcCommonCreate(0, 0, IID_IOPCCommon, &p);
#else
    HRESULT hr = OpcCommonCreate(0, 0, &IID_IOPCCommon, &p);
#endif
    if (hr != S_OK || !p) return 1;
    IOPCCommon *common = static_cast<IOPCCommon *>(p);
    LCID lcid = 0;
    bool ok = common->lpVtbl->GetLocaleID(common, &lcid) == S_OK && lcid == LOCALE_SYSTEM_DEFAULT;
    ok = common->lpVtbl->Release(common) == 0 && ok;
    return ok ? 0 : 1;
}
