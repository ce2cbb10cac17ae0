// The example as an EXE server (LocalServer32): `/RegServer` and `/UnregServer` register and
// unregister it; started by COM (`-Embedding`) it serves until its last client is gone; started by
// hand it serves until Ctrl+C. Stopped by its operator (EXAMPLE_STOP_EVENT, Ctrl+C) while clients are
// connected, it asks them to disconnect (IOPCShutdown).
#include "example_server.h"

#include <cstdio>

namespace {
HANDLE g_idle;           // set when no server object and no LockServer remain
HANDLE g_operator_stop;  // EXAMPLE_STOP_EVENT: set by the operator's tools, Ctrl+C or the console closing

BOOL WINAPI OnConsoleControl(DWORD) {
    SetEvent(g_operator_stop);  // the main thread notifies the clients (it has COM initialised)
    return TRUE;
}
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
        CoUninitialize();
        return FAILED(hr) ? 1 : 0;
    }

    g_idle = CreateEventW(nullptr, TRUE, FALSE, nullptr);
    g_operator_stop = CreateEventW(nullptr, TRUE, FALSE, EXAMPLE_STOP_EVENT);
    bool by_hand = command != OPC_SERVER_COMMAND_EMBEDDING;
    if (by_hand) ExampleModuleLock();  // keep serving until the operator stops the server
    SetConsoleCtrlHandler(OnConsoleControl, TRUE);
    DWORD cookie = 0;
    hr = CoRegisterClassObject(CLSID_ExampleServer, ExampleClassFactory(), CLSCTX_LOCAL_SERVER, REGCLS_MULTIPLEUSE, &cookie);
    if (SUCCEEDED(hr)) {
        HANDLE events[] = {g_idle, g_operator_stop};
        if (WaitForMultipleObjects(2, events, FALSE, INFINITE) == WAIT_OBJECT_0 + 1) {
            // Taken down while clients may be connected: tell them (IOPCShutdown), then give them a
            // moment to release their references.
            ExampleNotifyAllServers(L"The operator stopped the server.", nullptr);
            if (by_hand) ExampleModuleUnlock();
            WaitForSingleObject(g_idle, 10000);
        }
        CoRevokeClassObject(cookie);
    } else {
        fprintf(stderr, "example_server: CoRegisterClassObject failed (0x%08lX)\n", static_cast<unsigned long>(hr));
    }
    CoUninitialize();
    return FAILED(hr) ? 1 : 0;
}
