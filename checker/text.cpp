// Text for the report (text.h).
#include "text.h"

#include <opccomn/opccomn.h>

#include <cstdarg>
#include <cstdio>

namespace checker {

std::string Utf8(const wchar_t *w) {
    if (!w) return "(null)";
    int n = WideCharToMultiByte(CP_UTF8, 0, w, -1, nullptr, 0, nullptr, nullptr);
    if (n <= 0) return "?";
    std::string s(static_cast<size_t>(n - 1), '\0');
    WideCharToMultiByte(CP_UTF8, 0, w, -1, &s[0], n, nullptr, nullptr);
    return s;
}

std::string Format(const char *fmt, ...) {
    char buf[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    return buf;
}

std::string GuidText(const GUID &g) {
    WCHAR buf[64];
    StringFromGUID2(g, buf, 64);
    return Utf8(buf);
}

std::wstring GuidWide(const GUID &g) {
    WCHAR buf[64];
    StringFromGUID2(g, buf, 64);
    return buf;
}

std::string HrText(HRESULT hr, uint32_t kind) {
    LPWSTR symbol = nullptr;
    std::string s;
    if (hr == S_OK) return "S_OK";
    if (hr == S_FALSE) return "S_FALSE";
    if (SUCCEEDED(OpcErrorSymbol(hr, kind, &symbol)) && symbol) {
        s = Utf8(symbol) + Format(" (0x%08lX)", static_cast<unsigned long>(hr));
        OpcTaskMemFree(symbol);
        return s;
    }
    // What COM's stub answers for an exception inside an out-of-process server it caught.
    if (hr == HRESULT_FROM_WIN32(ERROR_NOACCESS))
        return Format("0x%08lX (ERROR_NOACCESS: an access violation inside the server, caught by COM)", static_cast<unsigned long>(hr));
    return Format("0x%08lX", static_cast<unsigned long>(hr));
}

const char *KindName(uint32_t kind) {
    switch (kind) {
    case OPC_SERVER_KIND_ALARMS_EVENTS: return "ae";
    case OPC_SERVER_KIND_HISTORICAL_DATA: return "hda";
    default: return "da";
    }
}

}  // namespace checker
