/* What the examples of the C API reference (examples/reference/) share to check themselves: a failure
 * count and a comparison of a wide string with ASCII text. Not part of what the reference shows. */
#ifndef OPCCOMN_REFERENCE_EXAMPLE_H
#define OPCCOMN_REFERENCE_EXAMPLE_H

#include <stdio.h>

#include <opccomn/opccomn.h>

static int failures;

static inline void check(int ok, const char *what) {
    if (!ok) {
        printf("FAIL %s\n", what);
        failures++;
    }
}

/* Whether the UTF-16 string `wide` is the ASCII text `ascii`. */
static inline int same(LPCWSTR wide, const char *ascii) {
    if (wide == NULL) return 0;
    while (*ascii && *wide == (WCHAR)(unsigned char)*ascii) {
        wide++;
        ascii++;
    }
    return *wide == 0 && *ascii == 0;
}

static inline int report(const char *name) {
    printf("%s: %s\n", name, failures ? "FAILED" : "ok");
    return failures ? 1 : 0;
}

#endif
