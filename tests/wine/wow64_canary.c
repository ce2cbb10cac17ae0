/* Proves that Wine really runs 32-bit programs. Without wine32, `wine prog32.exe` prints a warning
 * (hidden by WINEDEBUG=-all) and exits 0, so a 32-bit test would "pass" without running. The x86 test
 * stage runs this first and requires its exact output. Built with i686-w64-mingw32-gcc. */
#include <windows.h>
#include <stdio.h>

int main(void) {
    BOOL wow64 = FALSE;
    if (sizeof(void *) != 4) return 2;
    if (!IsWow64Process(GetCurrentProcess(), &wow64)) return 3;
    printf("wow64 canary: 32-bit process, WOW64 %s\n", wow64 ? "yes" : "no");
    return 0;
}
