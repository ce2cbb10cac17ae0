/* Test fixture for Wine 8 only: Rust's standard library imports ProcessPrng from bcryptprimitives.dll,
 * which Windows 10 and later have and Wine 8 lacks. This stand-in implements it with RtlGenRandom. It
 * is copied into the test prefix's system32 and never shipped. */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length); /* RtlGenRandom, advapi32 */

BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T len) {
    while (len > 0) {
        ULONG chunk = len > 0x40000000 ? 0x40000000 : (ULONG)len;
        if (!SystemFunction036(data, chunk)) return FALSE;
        data += chunk;
        len -= chunk;
    }
    return TRUE;
}
