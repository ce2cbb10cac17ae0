/* MatchPattern through the public header: every row of the published test vectors through
 * MatchPatternW, MatchPatternA and the compiled filter, NULL and malformed input, surrogates, invalid
 * narrow bytes, the MatchPattern macro, and patterns that end exactly where their memory ends. */
#include <stdint.h>

#include "test_util.h"

#if defined(_WIN32)
#include <windows.h>
#endif

struct like_vector {
    const char *string;
    const char *pattern;
    int case_sensitive;
    int expected;
    int ascii_only;
    const char *source;
};

static const struct like_vector vectors[] = {
#include "like_vectors.inc"
};

static int vector_failed(const struct like_vector *v, const char *how, int got) {
    fprintf(stderr, "%s: \"%s\" Like \"%s\" (case sensitive %d) gave %d, expected %d [%s]\n", how, v->string,
            v->pattern, v->case_sensitive, got, v->expected, v->source);
    return 0;
}

#define CHECK_VECTOR(v, how, got)                                  \
    do {                                                           \
        BOOL got_ = (got);                                         \
        CHECK(got_ == (v)->expected || vector_failed(v, how, got_)); \
    } while (0)

/* The narrow form of a vector's text: UTF-8 off Windows; on Windows the ANSI code page when every
 * character has an exact equivalent there (returns 0 when not). */
static int narrow(const char *utf8, char *out, size_t size) {
#if defined(_WIN32)
    BOOL lossy = FALSE;
    int n = WideCharToMultiByte(CP_ACP, WC_NO_BEST_FIT_CHARS, (LPCWCH)W(utf8), -1, out, (int)size, NULL, &lossy);
    return n > 0 && !lossy;
#else
    if (strlen(utf8) + 1 > size) return 0;
    memcpy(out, utf8, strlen(utf8) + 1);
    return 1;
#endif
}

static void test_vectors(void) {
    size_t i, narrow_rows = 0;
    for (i = 0; i < sizeof vectors / sizeof vectors[0]; i++) {
        const struct like_vector *v = &vectors[i];
        const WCHAR *ws = W(v->string);
        const WCHAR *wp = W(v->pattern);
        char ns[256], np[256];
        int have_narrow = narrow(v->string, ns, sizeof ns) && narrow(v->pattern, np, sizeof np);
        OpcPattern *f = (OpcPattern *)GARBAGE_PTR;
        HRESULT hr;

        CHECK_VECTOR(v, "MatchPatternW", MatchPatternW(ws, wp, v->case_sensitive));

        if (v->ascii_only) CHECK(have_narrow);
        if (have_narrow) {
            narrow_rows++;
            CHECK_VECTOR(v, "MatchPatternA", MatchPatternA(ns, np, v->case_sensitive));
        }

        hr = OpcPatternCompileW(wp, v->case_sensitive, &f);
        CHECK(hr == S_OK || hr == OPC_E_INVALIDFILTER);
        if (hr == S_OK) {
            CHECK(f != NULL);
            CHECK_VECTOR(v, "OpcPatternMatchW", OpcPatternMatchW(f, ws));
            if (have_narrow) CHECK_VECTOR(v, "OpcPatternMatchA", OpcPatternMatchA(f, ns));
            OpcPatternFree(f);
        } else {
            CHECK(f == NULL);
            CHECK(v->expected == 0);
        }

        if (have_narrow) {
            f = (OpcPattern *)GARBAGE_PTR;
            hr = OpcPatternCompileA(np, v->case_sensitive, &f);
            CHECK(hr == S_OK || hr == OPC_E_INVALIDFILTER);
            if (hr == S_OK) {
                CHECK_VECTOR(v, "OpcPatternCompileA+MatchA", OpcPatternMatchA(f, ns));
                CHECK_VECTOR(v, "OpcPatternCompileA+MatchW", OpcPatternMatchW(f, ws));
                OpcPatternFree(f);
            } else {
                CHECK(f == NULL);
            }
        }
    }
    CHECK(i >= 150);
    printf("%u vectors, %u of them also as narrow strings\n", (unsigned)i, (unsigned)narrow_rows);
}

static void test_null_and_malformed(void) {
    static const char *const malformed[] = {"[", "a[b", "*[", "[!", "[a-", "[Z-A]", "x*[z-a]*", "[]["};
    OpcPattern *f = (OpcPattern *)GARBAGE_PTR;
    size_t i;

    CHECK(MatchPatternW(NULL, W("*"), TRUE) == FALSE);
    CHECK(MatchPatternW(W(""), NULL, TRUE) == FALSE);
    CHECK(MatchPatternW(NULL, NULL, FALSE) == FALSE);
    CHECK(MatchPatternA(NULL, "*", TRUE) == FALSE);
    CHECK(MatchPatternA("", NULL, FALSE) == FALSE);
    CHECK(MatchPatternW(W(""), W(""), TRUE) == TRUE);
    CHECK(MatchPatternA("", "[]", TRUE) == TRUE);

    CHECK_HR(OpcPatternCompileW(NULL, TRUE, &f), E_INVALIDARG);
    CHECK(f == NULL);
    f = (OpcPattern *)GARBAGE_PTR;
    CHECK_HR(OpcPatternCompileA(NULL, TRUE, &f), E_INVALIDARG);
    CHECK(f == NULL);
    CHECK_HR(OpcPatternCompileW(W("a"), TRUE, NULL), E_INVALIDARG);
    CHECK_HR(OpcPatternCompileA("a", TRUE, NULL), E_INVALIDARG);
    CHECK(OpcPatternMatchW(NULL, W("a")) == FALSE);
    CHECK(OpcPatternMatchA(NULL, "a") == FALSE);
    OpcPatternFree(NULL);

    for (i = 0; i < sizeof malformed / sizeof malformed[0]; i++) {
        CHECK(MatchPatternW(W(malformed[i]), W(malformed[i]), TRUE) == FALSE);
        CHECK(MatchPatternA("a", malformed[i], FALSE) == FALSE);
        f = (OpcPattern *)GARBAGE_PTR;
        CHECK_HR(OpcPatternCompileW(W(malformed[i]), TRUE, &f), OPC_E_INVALIDFILTER);
        CHECK(f == NULL);
        f = (OpcPattern *)GARBAGE_PTR;
        CHECK_HR(OpcPatternCompileA(malformed[i], FALSE, &f), OPC_E_INVALIDFILTER);
        CHECK(f == NULL);
    }

    CHECK_HR(OpcPatternCompileW(W("*"), TRUE, &f), S_OK);
    CHECK(OpcPatternMatchW(f, NULL) == FALSE);
    CHECK(OpcPatternMatchA(f, NULL) == FALSE);
    CHECK(OpcPatternMatchW(f, W("anything")) == TRUE);
    OpcPatternFree(f);
}

/* Patterns in heap blocks of exactly their size: reading past the NUL would be caught by AddressSanitizer
 * (the specification's sample reads past an unclosed '['). */
static void test_no_over_read(void) {
    static const char *const patterns[] = {"[", "a[", "[!", "[a-", "a*[", "[]", "*"};
    size_t i, k;
    for (i = 0; i < sizeof patterns / sizeof patterns[0]; i++) {
        size_t n = strlen(patterns[i]);
        char *a = (char *)malloc(n + 1);
        WCHAR *w = (WCHAR *)malloc((n + 1) * sizeof(WCHAR));
        OpcPattern *f = NULL;
        memcpy(a, patterns[i], n + 1);
        for (k = 0; k <= n; k++) w[k] = (WCHAR)(unsigned char)patterns[i][k];
        CHECK(MatchPatternA("a", a, TRUE) == (strcmp(patterns[i], "*") == 0));
        CHECK(MatchPatternW(W("a"), w, FALSE) == (strcmp(patterns[i], "*") == 0));
        if (OpcPatternCompileW(w, TRUE, &f) == S_OK) OpcPatternFree(f);
        free(a);
        free(w);
    }
}

static void test_surrogates_and_invalid_bytes(void) {
    static const WCHAR lone_high[] = {'a', 0xD800, 'b', 0};
    static const WCHAR lone_low_first[] = {0xDE00, 0xD83D, 0};
    static const WCHAR pair[] = {0xD83D, 0xDE00, 0};
    static const WCHAR high_range[] = {'[', 0xD800, '-', 0xDBFF, ']', 0};
    CHECK(MatchPatternW(lone_high, W("a?b"), TRUE) == TRUE);
    CHECK(MatchPatternW(lone_high, lone_high, TRUE) == TRUE);
    CHECK(MatchPatternW(lone_high, W("a??b"), TRUE) == FALSE);
    CHECK(MatchPatternW(pair, W("?"), TRUE) == TRUE);
    CHECK(MatchPatternW(pair, W("??"), TRUE) == FALSE);
    CHECK(MatchPatternW(lone_low_first, W("??"), TRUE) == TRUE);
    CHECK(MatchPatternW(W("\xED\x9F\xBF"), high_range, TRUE) == FALSE); /* U+D7FF */
    CHECK(MatchPatternW(lone_high + 1, W("?b"), TRUE) == TRUE);
#if !defined(_WIN32)
    /* Narrow strings are UTF-8 here: bytes that do not decode are single characters. */
    CHECK(MatchPatternA("a\xFF" "b", "a?b", TRUE) == TRUE);
    CHECK(MatchPatternA("a\xC3" "b", "a\xC3" "b", TRUE) == TRUE);
    CHECK(MatchPatternA("a\xC3" "b", "a\xC4" "b", TRUE) == FALSE);
    CHECK(MatchPatternA("\xE2\x82", "??", TRUE) == TRUE);
    CHECK(MatchPatternA("\xE2\x82\xAC", "?", TRUE) == TRUE);
    CHECK(MatchPatternA("\xC3\xA9", "\xC3\x89", FALSE) == TRUE);
    CHECK(MatchPatternA("\xC3\xA9", "\xC3\x89", TRUE) == FALSE);
#endif
}

static void test_case_folding(void) {
    CHECK(MatchPatternW(W("\xC3\x89T\xC3\x89"), W("\xC3\xA9t\xC3\xA9"), FALSE) == TRUE); /* ÉTÉ */
    CHECK(MatchPatternW(W("\xC3\x89T\xC3\x89"), W("\xC3\xA9t\xC3\xA9"), TRUE) == FALSE);
    CHECK(MatchPatternW(W("\xE2\x84\xAA"), W("k"), FALSE) == TRUE);  /* KELVIN SIGN */
    CHECK(MatchPatternW(W("\xE2\x84\xAA"), W("[a-z]"), FALSE) == TRUE);
    CHECK(MatchPatternW(W("Q"), W("[a-z]"), FALSE) == TRUE);
    CHECK(MatchPatternW(W("Q"), W("[!a-z]"), FALSE) == FALSE);
    CHECK(MatchPatternW(W("\xF0\x90\x90\x80"), W("\xF0\x90\x90\xA8"), FALSE) == TRUE); /* Deseret */
    CHECK(MatchPatternW(W("\xEF\xBC\x95"), W("#"), FALSE) == FALSE); /* FULLWIDTH 5 is no 0-9 */
}

static void test_macro_and_adversarial(void) {
    char pattern[64];
    char a100[101];
    int k;
    /* UNICODE is not defined here, so MatchPattern is the narrow function. */
    CHECK(MatchPattern("Channel1.Device1.Tag12", "Channel#.*.Tag1?", TRUE) == TRUE);
    memset(a100, 'a', 100);
    a100[100] = 0;
    for (k = 4; k <= 12; k++) {
        int j;
        pattern[0] = 0;
        for (j = 0; j < k; j++) strcat(pattern, "a*");
        strcat(pattern, "b");
        CHECK(MatchPatternA(a100, pattern, TRUE) == FALSE);
        pattern[strlen(pattern) - 1] = 'a';
        CHECK(MatchPatternA(a100, pattern, TRUE) == TRUE);
    }
    CHECK(MatchPatternA("aaaaaaaaaaaaaaaaaaaaaaaa", "************b", TRUE) == FALSE);
}

int main(void) {
    test_vectors();
    test_null_and_malformed();
    test_no_over_read();
    test_surrogates_and_invalid_bytes();
    test_case_folding();
    test_macro_and_adversarial();
    return test_summary("test_match_pattern");
}
