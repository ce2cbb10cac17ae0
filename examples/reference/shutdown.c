/* The example of the C API reference's page "Shutdown" (docs/reference/areas.dox shows the lines
 * between its snippet markers), built and run by ctest (example.reference_shutdown) on Linux and
 * under Wine, C11 with warnings as errors. Server and client are one process here; across processes
 * the calls are the same. */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L /* nanosleep */
#include <time.h>
#endif
#include <string.h>

#include "example.h"

/* The bounded notification's workers give their references to the sink back once each call has
 * returned, possibly just after OpcShutdownNotifyBounded itself: wait for that, 10 s at most. */
static int all_released(void) {
    for (int i = 0; i < 1000 && OpcObjectCount() != 0; i++) {
#if defined(_WIN32)
        Sleep(10);
#else
        struct timespec pause = {0, 10 * 1000 * 1000};
        nanosleep(&pause, NULL);
#endif
    }
    return OpcObjectCount() == 0;
}

/* [shutdown] */
/* The client's side: what its sink does when the server goes (release the server's objects soon
 * after, not from inside the call). */
static void OPCCOMN_CDECL OnShutdown(void *context, LPCWSTR reason) {
    (void)reason; /* "The server is shutting down." */
    *(int *)context = 1;
}

static HRESULT ShutdownExample(int *asked, ULONG *notified) {
    /* The server: one shutdown object per server object (a server aggregates it: its controlling
     * IUnknown as `outer`, and QueryInterface(IID_IConnectionPointContainer) forwarded to it). */
    IUnknown *shutdown = NULL;
    HRESULT hr = OpcShutdownCreate(NULL, OPCCOMN_RIID(IID_IUnknown), (void **)&shutdown);
    if (hr != S_OK) return hr;

    /* The client: a sink, advised on the server object. */
    IUnknown *sink = NULL;
    DWORD cookie = 0;
    hr = OpcShutdownSinkCreate(OnShutdown, asked, OPCCOMN_RIID(IID_IUnknown), (void **)&sink);
    if (hr == S_OK) hr = OpcShutdownAdvise(shutdown, sink, &cookie);

    /* The server goes: every advised client is asked to disconnect, none waited for beyond 5 s. */
    OpcShutdownNotifyOptions bounded;
    memset(&bounded, 0, sizeof bounded);
    bounded.struct_size = sizeof bounded;
    bounded.timeout_ms = 5000;
    ULONG failed = 0, timed_out = 0;
    if (hr == S_OK)
        hr = OpcShutdownNotifyBounded(shutdown, u"The server is shutting down.", &bounded, notified, &failed, &timed_out);

    if (cookie != 0) OpcShutdownUnadvise(shutdown, cookie);
    if (sink) sink->lpVtbl->Release(sink);
    shutdown->lpVtbl->Release(shutdown);
    return hr;
}
/* [shutdown] */

int main(void) {
#if defined(_WIN32)
    CoInitializeEx(NULL, COINIT_MULTITHREADED); /* notification needs COM on the calling thread */
#endif
    int asked = 0;
    ULONG notified = 0;
    check(ShutdownExample(&asked, &notified) == S_OK, "the notification");
    check(asked == 1 && notified == 1, "the client was asked once");
    check(all_released(), "every object released");
#if defined(_WIN32)
    CoUninitialize();
#endif
    return report("reference shutdown");
}
