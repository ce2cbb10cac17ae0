/* opccomn demo: what an OPC server does with the library's IOPCCommon session object, seen from
 * both sides: the server creates one session per client, the client sets its locale and name and asks
 * for error texts. Then shutdown (chapter 4), again with the library on both sides: the server object
 * offers the IOPCShutdown connection point, the client advises a sink, and the server tells it to go. */
#include <stdio.h>
#include <string.h>

#include <opccomn/opccomn.h>

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

/* The client's shutdown callback: release everything from this server, starting with the connection. */
typedef struct DemoClient {
    IUnknown *server;
    DWORD cookie;
} DemoClient;

static void on_shutdown(void *context, LPCWSTR reason) {
    DemoClient *client = (DemoClient *)context;
    HRESULT hr;
    printf("  [client] server asks us to disconnect: \"");
    print_utf16(reason);
    printf("\"\n");
    hr = OpcShutdownUnadvise(client->server, client->cookie); /* allowed from inside the callback */
    printf("  [client] unadvised from inside the callback: 0x%08lX\n", (unsigned long)(unsigned int)hr);
}

/* Shutdown, both sides. Returns the number of failures. */
static int shutdown_demo(void) {
    IConnectionPointContainer *server = NULL;
    IOPCShutdown *sink = NULL;
    DemoClient client = {NULL, 0};
    ULONG notified = 0, failed = 0;
    WCHAR buf[64];
    int failures = 0;
    static const char *reason = "Server is shutting down for maintenance";
    size_t i;

    /* Server side: a real server aggregates this into its server object (see docs/guide/shutdown.md). */
    if (OpcShutdownCreate(NULL, &IID_IConnectionPointContainer, (void **)&server) != S_OK) return 1;

    /* Client side: a sink that calls back, advised on the server's IOPCShutdown connection point. */
    client.server = (IUnknown *)server;
    failures += OpcShutdownSinkCreate(on_shutdown, &client, &IID_IOPCShutdown, (void **)&sink) != S_OK;
    failures += OpcShutdownAdvise(client.server, (IUnknown *)sink, &client.cookie) != S_OK;
    printf("  [client] advised a shutdown sink, cookie %lu\n", (unsigned long)client.cookie);
    if (sink) sink->lpVtbl->Release(sink); /* the connection keeps the sink alive */

    /* Server side: going down. */
    for (i = 0; reason[i] && i + 1 < 64; i++) buf[i] = (WCHAR)reason[i];
    buf[i] = 0;
    failures += OpcShutdownNotifyEx((IUnknown *)server, buf, &notified, &failed) != S_OK;
    printf("  [server] notified %lu client(s), %lu failed\n", (unsigned long)notified, (unsigned long)failed);
    failures += notified != 1;
    server->lpVtbl->Release(server);
    return failures;
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
    /* The same session in German: the catalog ships English and German. */
    failures += session->lpVtbl->SetLocaleID(session, 0x0407) != S_OK;
    failures += session->lpVtbl->GetErrorString(session, codes[0], &text) != S_OK;
    printf("  [client] locale 0x0407, 0x%08lX: ", (unsigned long)(unsigned int)codes[0]);
    print_utf16(text);
    printf("\n");
    OpcTaskMemFree(text);
    text = NULL;
    printf("  [client] unknown code 0x12345678 -> 0x%08lX (E_INVALIDARG, as the specification says)\n",
           (unsigned long)(unsigned int)session->lpVtbl->GetErrorString(session, 0x12345678, &text));

    session->lpVtbl->Release(session);

    failures += shutdown_demo();
    printf("%s\n", failures == 0 && OpcObjectCount() == 0 ? "demo finished" : "demo FAILED");
    return failures == 0 && OpcObjectCount() == 0 ? 0 : 1;
}
