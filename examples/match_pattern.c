/* MatchPattern from C, on Linux and on Windows alike: the snippet of docs/guide/matchpattern.md, of
 * the README and of the C API reference's page "MatchPattern" (the lines between its snippet
 * markers), built and run by ctest (example.match_pattern_c, C11 with incompatible pointer types an
 * error) so that it keeps compiling.
 *
 * Wide strings are UTF-16 on every platform (WCHAR is 16 bits). `u"..."` (C11) is a UTF-16 literal
 * everywhere and has WCHAR's type in C; `L"..."` is UTF-16 only on Windows (wchar_t is 32 bits on
 * Linux, so it does not convert to LPCWSTR there). Narrow strings are UTF-8 (on Windows: the ANSI
 * code page). */
#include <stdio.h>

#include <opccomn/opccomn.h>

static int failures;

static void expect(const char *what, BOOL got, BOOL want) {
    if (got != want) {
        printf("FAIL %s: %d, expected %d\n", what, (int)got, (int)want);
        failures++;
    }
}

int main(void) {
    /* [pattern] */
    /* One name, one pattern. */
    expect("MatchPatternA", MatchPatternA("Channel1.Device2.Tag7", "Channel?.Device[1-3].Tag*", FALSE), TRUE);
    expect("MatchPatternW", MatchPatternW(u"Channel1.Device4.Tag7", u"Channel?.Device[1-3].Tag*", FALSE), FALSE);

    /* One filter, many names (a browse): compile once. */
    static const WCHAR *const items[] = {u"Channel1.Device2.Tag7", u"channel2.device3.tag", u"Channel1.Device4.Tag7"};
    OpcPattern *filter = NULL;
    HRESULT hr = OpcPatternCompileW(u"Channel?.Device[1-3].Tag*", FALSE, &filter);
    /* S_OK; OPC_E_INVALIDFILTER for a malformed pattern (what a browse must return); E_INVALIDARG for NULL */
    if (hr == S_OK) { /* SUCCEEDED() is <windows.h>'s: off Windows the header does not define it */
        expect("compiled filter, items[0]", OpcPatternMatchW(filter, items[0]), TRUE);
        expect("compiled filter, items[1] (case-insensitive)", OpcPatternMatchW(filter, items[1]), TRUE);
        expect("compiled filter, items[2]", OpcPatternMatchW(filter, items[2]), FALSE);
        OpcPatternFree(filter); /* NULL is fine */
    } else {
        printf("FAIL OpcPatternCompileW: 0x%08lX\n", (unsigned long)hr);
        failures++;
    }
    /* [pattern] */

    /* A malformed pattern (an unclosed list) is refused with the code a browse returns. */
    filter = NULL;
    hr = OpcPatternCompileA("Tag[1-3", FALSE, &filter);
    if (hr != OPC_E_INVALIDFILTER || filter != NULL) {
        printf("FAIL OpcPatternCompileA(\"Tag[1-3\"): 0x%08lX\n", (unsigned long)hr);
        failures++;
    }

    printf("match_pattern (C): %s\n", failures ? "FAILED" : "ok");
    return failures ? 1 : 0;
}
