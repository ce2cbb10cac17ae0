// MatchPattern from C++, on Linux and on Windows alike: the snippet of docs/guide/matchpattern.md,
// built and run by ctest (example.match_pattern_cxx) so that it keeps compiling.
//
// In C++ a `u"..."` literal is `const char16_t *`, a type of its own, and LPCWSTR is `const WCHAR *`
// (`uint16_t` on Linux, `wchar_t` on Windows): both hold UTF-16 code units, so a reinterpret_cast
// passes one as the other. `L"..."` needs no cast on Windows, but is UTF-32 on Linux.
#include <cstdio>

#include <opccomn/opccomn.h>

static LPCWSTR W16(const char16_t *s) { return reinterpret_cast<LPCWSTR>(s); }

int main() {
    int failures = 0;
    if (!MatchPatternW(W16(u"Channel1.Device2.Tag7"), W16(u"Channel?.Device[1-3].Tag*"), FALSE)) {
        std::printf("FAIL MatchPatternW\n");
        failures++;
    }
    if (MatchPatternA("Channel1.Device4.Tag7", "Channel?.Device[1-3].Tag*", FALSE)) {
        std::printf("FAIL MatchPatternA\n");
        failures++;
    }
    OpcPattern *filter = nullptr;
    HRESULT hr = OpcPatternCompileW(W16(u"Channel?.Device[1-3].Tag*"), FALSE, &filter);
    if (hr != S_OK || !OpcPatternMatchW(filter, W16(u"CHANNEL3.DEVICE1.TAG")) ||
        OpcPatternMatchW(filter, W16(u"Channel3.Device0.Tag"))) {
        std::printf("FAIL compiled filter (0x%08lX)\n", static_cast<unsigned long>(hr));
        failures++;
    }
    OpcPatternFree(filter);
    std::printf("match_pattern (C++): %s\n", failures ? "FAILED" : "ok");
    return failures ? 1 : 0;
}
