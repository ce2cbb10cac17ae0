// The example as an EXE server (LocalServer32), on the library's host (OpcExeServerRun): `/RegServer`
// and `/UnregServer` register and unregister it; started by COM (`-Embedding`) it serves until its
// last client is gone; started by hand it serves until stopped. Stopped by its operator
// (EXAMPLE_STOP_EVENT, Ctrl+C) while clients are connected, it asks them to disconnect
// (IOPCShutdown), waiting for them only so long.
//
// Its lifetime follows COM's rule for local servers: every object a client can hold keeps the
// process, its own server objects (OpcServerLock) and the library's objects alike (the IOPCCommon
// session and the connection point each server object aggregates, and the enumerators they hand
// out). The host keeps that count; this file is the server's part only.
#include "example_server.h"

#include <cstdio>

namespace {
// Taken down while clients may be connected: tell them (IOPCShutdown), all at once and waiting 5 s at
// most for their answers, so that a hung client cannot hold the stop.
void OPCCOMN_CDECL OnOperatorStop(void *) {
    OpcShutdownNotifyOptions bounded = {};
    bounded.struct_size = sizeof bounded;
    bounded.timeout_ms = 5000;
    ExampleNotifyAllServers(L"The operator stopped the server.", nullptr, &bounded);
}
}  // namespace

int main() {
    OpcServerRegistration registration = ExampleRegistration(false, nullptr);  // NULL: this EXE
    OpcServerClass cls = ExampleClass(false, &registration);
    OpcExeServerOptions options = {};
    options.struct_size = sizeof options;
    options.classes = &cls;
    options.class_count = 1;
    options.stop_event_name = EXAMPLE_STOP_EVENT;
    options.on_stop = OnOperatorStop;
    options.release_timeout_ms = 10000;
    HRESULT hr = OpcExeServerRun(&options, nullptr);  // NULL: this process's command line
    if (FAILED(hr)) fprintf(stderr, "example_server: 0x%08lX\n", static_cast<unsigned long>(hr));
    return FAILED(hr) ? 1 : 0;
}
