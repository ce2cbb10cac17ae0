// The example as an EXE server (LocalServer32): `/RegServer` and `/UnregServer` register and
// unregister it; started by COM (`-Embedding`) it serves until its last client is gone; started by
// hand it serves until Ctrl+C. Stopped by its operator (EXAMPLE_STOP_EVENT, Ctrl+C) while clients are
// connected, it asks them to disconnect (IOPCShutdown), waiting for them only so long.
//
// Its lifetime follows COM's rule for local servers: every object a client can hold keeps the
// process, its own server objects and the library's objects alike (the IOPCCommon session and the
// connection point it aggregates, and the enumerators they hand out, such as a connection point's
// IEnumConnections), through the library's module lock (OpcSetModuleLock).
#include "example_server.h"

#include <cstdio>

namespace {
HANDLE g_idle;           // set when no object and no LockServer remain
HANDLE g_operator_stop;  // EXAMPLE_STOP_EVENT: set by the operator's tools, Ctrl+C or the console closing

BOOL WINAPI OnConsoleControl(DWORD) {
    SetEvent(g_operator_stop);  // the main thread notifies the clients (it has COM initialised)
    return TRUE;
}

// The library's objects count on the process as the example's own do.
void OPCCOMN_CDECL LibraryObjectMade(void *) { ExampleModuleLock(); }
void OPCCOMN_CDECL LibraryObjectFreed(void *) { ExampleModuleUnlock(); }
}  // namespace

// COM's server process reference count: at zero, COM stops handing out this server's class objects.
void ExampleModuleLock() { CoAddRefServerProcess(); }
void ExampleModuleUnlock() {
    if (CoReleaseServerProcess() == 0) SetEvent(g_idle);
}

int main() {
    uint32_t command = OPC_SERVER_COMMAND_NONE;
    HRESULT hr = OpcParseCommandLine(GetCommandLineW(), &command);
    if (FAILED(hr)) {
        fprintf(stderr, "example_server: bad command line (0x%08lX)\n", static_cast<unsigned long>(hr));
        return 2;
    }
    // The Component Categories Manager is a COM object: registration wants COM too.
    hr = CoInitializeEx(nullptr, COINIT_MULTITHREADED);
    if (FAILED(hr)) return 1;

    if (command == OPC_SERVER_COMMAND_REGISTER || command == OPC_SERVER_COMMAND_UNREGISTER) {
        OpcServerRegistration registration = ExampleRegistration(false, nullptr);  // NULL: this EXE
        hr = command == OPC_SERVER_COMMAND_REGISTER ? OpcRegisterServer(&registration, nullptr)
                                                    : OpcUnregisterServer(&registration, nullptr);
        if (FAILED(hr)) fprintf(stderr, "example_server: (un)registration failed (0x%08lX)\n", static_cast<unsigned long>(hr));
        CoUninitialize();  // no client has been here: nothing can be on its way back
        return FAILED(hr) ? 1 : 0;
    }

    g_idle = CreateEventW(nullptr, TRUE, FALSE, nullptr);
    g_operator_stop = CreateEventW(nullptr, TRUE, FALSE, EXAMPLE_STOP_EVENT);
    OpcModuleLock lock = {};
    lock.struct_size = sizeof lock;
    lock.lock = LibraryObjectMade;
    lock.unlock = LibraryObjectFreed;
    hr = OpcSetModuleLock(&lock);  // before any object exists
    bool by_hand = command != OPC_SERVER_COMMAND_EMBEDDING;
    if (by_hand) ExampleModuleLock();  // keep serving until the operator stops the server
    SetConsoleCtrlHandler(OnConsoleControl, TRUE);
    DWORD cookie = 0;
    if (SUCCEEDED(hr))
        hr = CoRegisterClassObject(CLSID_ExampleServer, ExampleClassFactory(), CLSCTX_LOCAL_SERVER, REGCLS_MULTIPLEUSE, &cookie);
    if (SUCCEEDED(hr)) {
        HANDLE events[] = {g_idle, g_operator_stop};
        if (WaitForMultipleObjects(2, events, FALSE, INFINITE) == WAIT_OBJECT_0 + 1) {
            // Taken down while clients may be connected: tell them (IOPCShutdown), all at once and
            // waiting 5 s at most for their answers (a hung client cannot hold the stop), then give
            // them a moment to release their references.
            OpcShutdownNotifyOptions bounded = {};
            bounded.struct_size = sizeof bounded;
            bounded.timeout_ms = 5000;
            ExampleNotifyAllServers(L"The operator stopped the server.", nullptr, &bounded);
            if (by_hand) ExampleModuleUnlock();
            WaitForSingleObject(g_idle, 10000);
        }
        CoRevokeClassObject(cookie);
    } else {
        fprintf(stderr, "example_server: cannot serve (0x%08lX)\n", static_cast<unsigned long>(hr));
    }
    // No CoUninitialize: the last Release may still be on its way back to the client on an RPC
    // thread, and CoUninitialize of the apartment that call runs in waits for it (under Wine it can
    // wait for ever: the server never exits). Process exit tears COM down.
    return FAILED(hr) ? 1 : 0;
}
