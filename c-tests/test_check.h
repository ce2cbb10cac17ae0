/* The checks and the closing line of every C and C++ test: CHECK, CHECK_HR, garbage to pre-fill
 * out-parameters with, W() for UTF-16 text, test_summary(). C and C++ alike; only the public header. */
#ifndef OPCCOMN_TEST_CHECK_H
#define OPCCOMN_TEST_CHECK_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <opccomn/opccomn.h>

static int test_passed;
static int test_failed;

#define CHECK(cond)                                                                   \
    do {                                                                              \
        if (cond) {                                                                   \
            test_passed++;                                                            \
        } else {                                                                      \
            test_failed++;                                                            \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
        }                                                                             \
    } while (0)

#define CHECK_HR(expr, expected)                                                                      \
    do {                                                                                              \
        HRESULT check_hr_got_ = (expr);                                                               \
        HRESULT check_hr_want_ = (expected);                                                          \
        if (check_hr_got_ == check_hr_want_) {                                                        \
            test_passed++;                                                                            \
        } else {                                                                                      \
            test_failed++;                                                                            \
            fprintf(stderr, "%s:%d: %s returned 0x%08lX, expected 0x%08lX\n", __FILE__, __LINE__, #expr, \
                    (unsigned long)(unsigned int)check_hr_got_, (unsigned long)(unsigned int)check_hr_want_); \
        }                                                                                             \
    } while (0)

/* Garbage to pre-fill out-parameters with, proving the callee writes them. */
#define GARBAGE_PTR ((void *)(size_t)0xDEADBEEFu)
#define GARBAGE_U32 0xDEADBEEFu

/* Prints the closing line ctest logs show ("N passed, M failed") and returns the exit code. */
static int test_summary(const char *name) {
    printf("%s: %d passed, %d failed\n", name, test_passed, test_failed);
    return test_failed == 0 ? 0 : 1;
}

/* UTF-8 to NUL-terminated UTF-16 in one of a ring of static buffers (tests only; up to 1023 units). */
static const WCHAR *W(const char *utf8) {
    static WCHAR ring[16][1024];
    static unsigned next;
    WCHAR *out = ring[next++ % 16];
    const unsigned char *s = (const unsigned char *)utf8;
    size_t n = 0;
    while (*s && n < 1020) {
        unsigned long cp;
        if (*s < 0x80) {
            cp = *s++;
        } else if ((*s & 0xE0) == 0xC0) {
            cp = (unsigned long)(*s++ & 0x1F) << 6;
            cp |= *s++ & 0x3F;
        } else if ((*s & 0xF0) == 0xE0) {
            cp = (unsigned long)(*s++ & 0x0F) << 12;
            cp |= (unsigned long)(*s++ & 0x3F) << 6;
            cp |= *s++ & 0x3F;
        } else {
            cp = (unsigned long)(*s++ & 0x07) << 18;
            cp |= (unsigned long)(*s++ & 0x3F) << 12;
            cp |= (unsigned long)(*s++ & 0x3F) << 6;
            cp |= *s++ & 0x3F;
        }
        if (cp >= 0x10000) {
            cp -= 0x10000;
            out[n++] = (WCHAR)(0xD800 + (cp >> 10));
            out[n++] = (WCHAR)(0xDC00 + (cp & 0x3FF));
        } else {
            out[n++] = (WCHAR)cp;
        }
    }
    out[n] = 0;
    return out;
}

#endif
