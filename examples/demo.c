/* opccomn demo: what an OPC server does with the library's IOPCCommon session object, seen from
 * both sides: the server creates one session per client, the client sets its locale and name and asks
 * for error texts. */
#include <stdio.h>
#include <string.h>

#include "opccomn.h"

/* Prints a UTF-16 string as UTF-8. */
static void print_utf16(const WCHAR *s) {
    for (; s && *s; s++) {
        unsigned long c = *s;
        if (c >= 0xD800 && c < 0xDC00 && s[1] >= 0xDC00 && s[1] < 0xE000) c = 0x10000 + ((c - 0xD800) << 10) + (*++s - 0xDC00);
        if (c < 0x80) putchar((int)c);
        else if (c < 0x800) printf("%c%c", (int)(0xC0 | c >> 6), (int)(0x80 | (c & 0x3F)));
        else if (c < 0x10000) printf("%c%c%c", (int)(0xE0 | c >> 12), (int)(0x80 | ((c >> 6) & 0x3F)), (int)(0x80 | (c & 0x3F)));
        else printf("%c%c%c%c", (int)(0xF0 | c >> 18), (int)(0x80 | ((c >> 12) & 0x3F)), (int)(0x80 | ((c >> 6) & 0x3F)), (int)(0x80 | (c & 0x3F)));
    }
}

static void client_name_changed(void *context, LPCWSTR name) {
    printf("  [server] %s: client is now \"", (const char *)context);
    print_utf16(name);
    printf("\"\n");
}

static const WCHAR *ascii(const char *s, WCHAR *buf, size_t n) {
    size_t i;
    for (i = 0; s[i] && i + 1 < n; i++) buf[i] = (WCHAR)(unsigned char)s[i];
    buf[i] = 0;
    return buf;
}

int main(void) {
    static const LCID locales[] = {0x0409, 0x0407};
    static const HRESULT codes[] = {(HRESULT)0xC0040007u, (HRESULT)0xC0040009u, (HRESULT)0x0004000Eu};
    OpcCommonOptions options;
    IOPCCommon *session = NULL;
    DWORD count = 0, i;
    LCID *available = NULL, lcid = 0;
    WCHAR buf[64];
    LPWSTR text = NULL;
    int failures = 0;

    printf("opccomn %s demo\n", OPCCOMN_VERSION);

    /* Server side: one IOPCCommon session per client connection. */
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.locales = locales;
    options.locale_count = 2;
    options.client_name_changed = client_name_changed;
    options.client_name_context = (void *)"session 1";
    if (OpcCommonCreate(&options, NULL, &IID_IOPCCommon, (void **)&session) != S_OK) {
        fprintf(stderr, "OpcCommonCreate failed\n");
        return 1;
    }

    /* Client side: what any OPC client does with IOPCCommon. */
    failures += session->lpVtbl->SetClientName(session, ascii("DEMO-NODE\\demo.exe", buf, 64)) != S_OK;
    failures += session->lpVtbl->QueryAvailableLocaleIDs(session, &count, &available) != S_OK;
    printf("  [client] available locales:");
    for (i = 0; i < count; i++) printf(" 0x%04lX", (unsigned long)available[i]);
    printf("\n");
    OpcTaskMemFree(available);
    failures += session->lpVtbl->SetLocaleID(session, 0x0409) != S_OK;
    failures += session->lpVtbl->GetLocaleID(session, &lcid) != S_OK;
    printf("  [client] locale set to 0x%04lX\n", (unsigned long)lcid);
    for (i = 0; i < sizeof codes / sizeof codes[0]; i++) {
        failures += session->lpVtbl->GetErrorString(session, codes[i], &text) != S_OK;
        printf("  [client] 0x%08lX: ", (unsigned long)(unsigned int)codes[i]);
        print_utf16(text);
        printf("\n");
        OpcTaskMemFree(text);
        text = NULL;
    }
    printf("  [client] unknown code 0x12345678 -> 0x%08lX (E_INVALIDARG, as the specification says)\n",
           (unsigned long)(unsigned int)session->lpVtbl->GetErrorString(session, 0x12345678, &text));

    session->lpVtbl->Release(session);
    printf("%s\n", failures == 0 && OpcObjectCount() == 0 ? "demo finished" : "demo FAILED");
    return failures == 0 && OpcObjectCount() == 0 ? 0 : 1;
}
