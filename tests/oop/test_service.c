/* The EXE host as a Windows service under Wine's service manager (services.exe), and the server
 * browser as one (service/opccomn_browser.c, `/Service`).
 *
 * The test server (oop_server.c, which offers the service OOP_SERVICE) is registered by the library's
 * host in this process (OpcExeServerRun with its classes and `/Service`, `/RegServer`, `/UnregServer`,
 * so that every result is seen exactly): the service is created as documented (own process, demand
 * start, NT AUTHORITY\LocalService, the command line of LocalServer32 with -RunService) and the
 * AppID's LocalService names it; a client's CoCreateInstance(CLSCTX_LOCAL_SERVER) reaches the service
 * (the server's process is the service's), which serves on after its last client left; the service
 * manager's stop while a client holds an object with a shutdown sink notifies the sink and ends the
 * service within the server's bound although the client never lets go; unregistration, also of a
 * running service, leaves the registry as it was and no service. Each precondition a caller can break
 * has its error, with nothing written; another product's service of the same name is refused,
 * untouched, or (taken over) given back, never deleted, and so is one pointed at another program
 * after registration; /RegServer after /Service goes back to the EXE form; -RunService in a process
 * the service manager did not start (no service, the service stopped, the service running) is
 * refused at once.
 *
 * The browser: `opccomn_browser /Service` registers it as the service OpcComnBrowser (twice: nothing
 * changes), -RunService by hand is refused, a client browses through it, advises a shutdown sink on
 * the server list, and the service manager's stop tells the sink and ends the service;
 * `/UnregServer` leaves the registry as it was and no service.
 *
 * Services started by the service manager are never killed here (a test EXE server's class
 * registration would stay in rpcss for the session): each is stopped through the service manager. */
#include "oop.h"

#include <winsvc.h>

static WCHAR dir[MAX_PATH], server_path[MAX_PATH], server_command[MAX_PATH + 32];
static SC_HANDLE scm;
/* The AppID the test registers the test server's classes with. */
static const CLSID APPID_OopService = {0xC3000000, 0x5eed, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0xA1}};
/* The bound the test server waits for its clients after a stop, as a service (its -release:). */
#define SERVICE_RELEASE_MS 2000
#define BROWSER_SERVICE L"OpcComnBrowser"
#define ERROR_HR(e) ((HRESULT)(0x80070000u | (e)))

static HRESULT OPCCOMN_CDECL never_created(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    (void)context;
    (void)outer;
    (void)riid;
    (void)ppv;
    return E_UNEXPECTED; /* this process only registers */
}

static OpcServerRegistration registrations[2];
static OpcServerClass classes[2];

/* OpcExeServerRun in this process with the test server's classes (registrations with the AppID, or
 * without one), the service `name` and `account`, the structure's size `size` (0: this version's). */
static HRESULT host_with(const WCHAR *command_line, const WCHAR *name, const WCHAR *account, int app_id, uint32_t size) {
    static const WCHAR *const prog_ids[2] = {L"Oop.ServiceServer.1", L"Oop.ServiceList.1"};
    const CLSID *clsids[2] = {&CLSID_OopServer, &CLSID_OopServerList};
    OpcExeServerOptions options;
    int i;
    for (i = 0; i < 2; i++) {
        memset(&registrations[i], 0, sizeof registrations[i]);
        registrations[i].struct_size = sizeof registrations[i];
        registrations[i].server_type = OPC_SERVER_TYPE_LOCAL;
        registrations[i].clsid = *clsids[i];
        registrations[i].prog_id = prog_ids[i];
        registrations[i].user_type = L"opccomn service test server";
        registrations[i].module_path = server_command; /* a command line: the release bound with it */
        registrations[i].app_id = app_id ? &APPID_OopService : NULL;
        memset(&classes[i], 0, sizeof classes[i]);
        classes[i].struct_size = sizeof classes[i];
        classes[i].clsid = clsids[i];
        classes[i].create = never_created;
        classes[i].registration = &registrations[i];
    }
    memset(&options, 0, sizeof options);
    options.struct_size = size ? size : (uint32_t)sizeof options;
    options.classes = classes;
    options.class_count = 2;
    options.service_name = name;
    options.service_account = account;
    return OpcExeServerRun(&options, command_line);
}

static HRESULT host(const WCHAR *command_line) { return host_with(command_line, OOP_SERVICE, NULL, 1, 0); }

static LPWSTR snapshot(OpcRegistry *sys) {
    static const WCHAR *const keys[] = {
        L"CLSID\\{C3000000-5EED-4000-8000-000000000001}", L"CLSID\\{C3000000-5EED-4000-8000-000000000002}",
        L"AppID\\{C3000000-5EED-4000-8000-0000000000A1}", L"AppID\\opccomn_test_server.exe",
        L"Oop.ServiceServer.1",                           L"Oop.ServiceList.1",
        L"CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}", L"AppID\\{CCD63ADF-D02D-46DD-B170-FA6E0F086FE3}",
        L"AppID\\opccomn_browser.exe",                    L"OPC.ServerList.1",
        L"OPC.ServerList"};
    return registry_snapshot(sys, keys, sizeof keys / sizeof keys[0]);
}

static int same_snapshot(LPWSTR before, LPWSTR after) {
    int same = wsame(before, after);
    if (!same) {
        fputs("  before: ", stderr);
        wprint(stderr, before);
        fputs("\n  after: ", stderr);
        wprint(stderr, after);
        fputc('\n', stderr);
    }
    free(after);
    return same;
}

/* ---- The service manager ---- */

/* Whether the service `name` exists. */
static int service_exists(const WCHAR *name) {
    SC_HANDLE s = OpenServiceW(scm, name, SERVICE_QUERY_STATUS);
    if (!s) return 0;
    CloseServiceHandle(s);
    return 1;
}

/* The service's state (SERVICE_RUNNING...), its process and exit code; 0 when it cannot be read. */
static DWORD service_state(const WCHAR *name, DWORD *pid, DWORD *exit_code) {
    SERVICE_STATUS_PROCESS st;
    DWORD needed;
    SC_HANDLE s = OpenServiceW(scm, name, SERVICE_QUERY_STATUS);
    if (!s) return 0;
    memset(&st, 0, sizeof st);
    if (!QueryServiceStatusEx(s, SC_STATUS_PROCESS_INFO, (BYTE *)&st, sizeof st, &needed)) st.dwCurrentState = 0;
    CloseServiceHandle(s);
    if (pid) *pid = st.dwProcessId;
    if (exit_code) *exit_code = st.dwWin32ExitCode;
    return st.dwCurrentState;
}

/* The service's configuration: its command line and account into the buffers (MAX_PATH + 64 units),
 * start type and service type. 0 when it cannot be read. */
static int service_config(const WCHAR *name, WCHAR *command_line, WCHAR *account, DWORD *start, DWORD *type) {
    static BYTE buffer[8192];
    QUERY_SERVICE_CONFIGW *c = (QUERY_SERVICE_CONFIGW *)buffer;
    DWORD needed;
    int ok;
    SC_HANDLE s = OpenServiceW(scm, name, SERVICE_QUERY_CONFIG);
    if (!s) return 0;
    ok = QueryServiceConfigW(s, c, sizeof buffer, &needed);
    CloseServiceHandle(s);
    if (!ok) return 0;
    swprintf(command_line, MAX_PATH + 64, L"%ls", c->lpBinaryPathName ? c->lpBinaryPathName : L"");
    swprintf(account, MAX_PATH + 64, L"%ls", c->lpServiceStartName ? c->lpServiceStartName : L"");
    *start = c->dwStartType;
    *type = c->dwServiceType;
    return 1;
}

/* Asks the service manager to stop the service; whether it took the control. */
static int stop_service(const WCHAR *name) {
    SERVICE_STATUS st;
    BOOL ok;
    SC_HANDLE s = OpenServiceW(scm, name, SERVICE_STOP);
    if (!s) return 0;
    ok = ControlService(s, SERVICE_CONTROL_STOP, &st);
    CloseServiceHandle(s);
    return ok;
}

/* Waits up to 20 s for the service to be stopped (a bound, not a measurement: the server's own bounds
 * are 3 s for the notification and SERVICE_RELEASE_MS or 10 s for the clients); its state then. */
static DWORD wait_stopped(const WCHAR *name, DWORD *exit_code) {
    DWORD state = 0;
    int i;
    for (i = 0; i < 200; i++) {
        state = service_state(name, NULL, exit_code);
        if (state == SERVICE_STOPPED || state == 0) break;
        Sleep(100);
    }
    return state;
}

/* Stops (as an interrupted earlier run may have left it) and deletes a service of this test's. */
static void remove_service(const WCHAR *name) {
    SERVICE_STATUS st;
    SC_HANDLE s = OpenServiceW(scm, name, SERVICE_STOP | SERVICE_QUERY_STATUS | DELETE);
    if (!s) return;
    ControlService(s, SERVICE_CONTROL_STOP, &st);
    wait_stopped(name, NULL);
    DeleteService(s);
    CloseServiceHandle(s);
}

/* The other product: a service of the test server's name that starts its own program. */
#define OTHER_COMMAND L"\"C:\\Program Files\\Other Vendor\\other.exe\" -service"
static void create_other_service(void) {
    SC_HANDLE s = CreateServiceW(scm, OOP_SERVICE, L"Another product", SERVICE_QUERY_STATUS, SERVICE_WIN32_OWN_PROCESS,
                                 SERVICE_DEMAND_START, SERVICE_ERROR_NORMAL, OTHER_COMMAND, NULL, NULL, NULL, NULL, NULL);
    CHECK(s != NULL);
    if (s) CloseServiceHandle(s);
}

/* Whether the process `pid` ends within 10 s (a bound: a service reports STOPPED a moment before its
 * process exits). */
static int process_ends(DWORD pid) {
    DWORD r;
    HANDLE h = OpenProcess(SYNCHRONIZE, FALSE, pid);
    if (!h) return GetLastError() == ERROR_INVALID_PARAMETER; /* no such process: gone already */
    r = WaitForSingleObject(h, 10000);
    CloseHandle(h);
    return r == WAIT_OBJECT_0;
}

/* Whether the process `pid` is still there after `ms` milliseconds (one that must not end). */
static int process_stays_alive(DWORD pid, DWORD ms) {
    DWORD r;
    HANDLE h = OpenProcess(SYNCHRONIZE, FALSE, pid);
    if (!h) return 0;
    r = WaitForSingleObject(h, ms);
    CloseHandle(h);
    return r == WAIT_TIMEOUT;
}

/* Points the service at another command line, as another product's installer would. */
static int set_service_command(const WCHAR *name, const WCHAR *command_line) {
    BOOL ok;
    SC_HANDLE s = OpenServiceW(scm, name, SERVICE_CHANGE_CONFIG);
    if (!s) return 0;
    ok = ChangeServiceConfigW(s, SERVICE_NO_CHANGE, SERVICE_NO_CHANGE, SERVICE_NO_CHANGE, command_line, NULL, NULL,
                              NULL, NULL, NULL, NULL);
    CloseServiceHandle(s);
    return ok;
}

/* ---- The client's side ---- */

/* GetErrorString of a vendor code of the test server, as a malloc'd copy (NULL on failure). */
static WCHAR *ask(IOPCCommon *c, HRESULT code) {
    LPWSTR text = NULL;
    WCHAR *copy = NULL;
    if (SUCCEEDED(c->lpVtbl->GetErrorString(c, code, &text)) && text) {
        size_t n = wlen(text);
        copy = (WCHAR *)malloc((n + 1) * sizeof(WCHAR));
        if (copy) memcpy(copy, text, (n + 1) * sizeof(WCHAR));
        CoTaskMemFree(text);
    }
    return copy;
}

/* The process that serves `c`. */
static DWORD server_process(IOPCCommon *c) {
    WCHAR *answer = ask(c, OOP_CODE_PROCESS_ID);
    DWORD pid = answer ? (DWORD)wcstoul(answer, NULL, 10) : 0;
    free(answer);
    return pid;
}

typedef struct Told {
    LONG calls;
    WCHAR reason[128];
} Told;

static void on_shutdown(void *context, LPCWSTR reason) {
    Told *told = (Told *)context;
    if (reason) swprintf(told->reason, 128, L"%ls", reason);
    InterlockedIncrement(&told->calls);
}

/* Waits up to 10 s for the sink to be told. */
static int told_within(Told *told) {
    int i;
    for (i = 0; i < 100 && InterlockedCompareExchange(&told->calls, 0, 0) == 0; i++) Sleep(100);
    return InterlockedCompareExchange(&told->calls, 0, 0) == 1;
}

/* ---- The test server as a service ---- */

/* What a caller can get wrong: each refused with its error, nothing written, no service made. */
static void preconditions(OpcRegistry *sys) {
    LPWSTR before = snapshot(sys);
    WCHAR long_name[300];
    int i;
    for (i = 0; i < 257; i++) long_name[i] = L'S';
    long_name[257] = 0;
    CHECK_HR(host_with(L"/Service", NULL, NULL, 1, 0), ERROR_HR(ERROR_NOT_SUPPORTED));  /* no service offered */
    CHECK_HR(host_with(L"-RunService", NULL, NULL, 1, 0), ERROR_HR(ERROR_NOT_SUPPORTED));
    /* The structure of the version before (no service fields): still taken, and no service offered. */
    CHECK_HR(host_with(L"/Service", OOP_SERVICE, NULL, 1, (uint32_t)offsetof(OpcExeServerOptions, service_name)),
             ERROR_HR(ERROR_NOT_SUPPORTED));
    CHECK_HR(host_with(L"/Service", long_name, NULL, 1, 0), E_INVALIDARG);            /* 257 characters */
    CHECK_HR(host_with(L"/RegServer", long_name, NULL, 1, 0), E_INVALIDARG);          /* whatever the command */
    CHECK_HR(host_with(L"/Service", L"Opc\\Test", NULL, 1, 0), E_INVALIDARG);          /* a backslash */
    CHECK_HR(host_with(L"/Service", L"", NULL, 1, 0), E_INVALIDARG);
    CHECK_HR(host_with(L"/Service", OOP_SERVICE, L".\\operator", 1, 0), E_INVALIDARG); /* an account with a password */
    CHECK_HR(host_with(L"/RegServer", NULL, L"LocalSystem", 1, 0), E_INVALIDARG);      /* an account, no service */
    CHECK_HR(host_with(L"/Service", OOP_SERVICE, NULL, 0, 0), E_INVALIDARG);           /* no AppID to name it */
    CHECK_HR(host(L"/Service /RegServer"), E_INVALIDARG);
    CHECK_HR(host(L"/Service /UnregServer"), E_INVALIDARG);
    CHECK_HR(host(L"/Service -RunService"), E_INVALIDARG);
    /* -RunService in a process the service manager did not start (here: no such service): its error,
     * at once (not after the dispatcher's wait for a service manager that never comes). */
    CHECK_HR(host(L"-RunService"), ERROR_HR(ERROR_FAILED_SERVICE_CONTROLLER_CONNECT));
    CHECK(same_snapshot(before, snapshot(sys)));
    CHECK(!service_exists(OOP_SERVICE));
    free(before);
}

/* Another product's service of the same name: refused and untouched; taken over on request, and given
 * back by unregistration, never deleted. */
static void another_products_service(OpcRegistry *sys) {
    WCHAR command_line[MAX_PATH + 64], account[MAX_PATH + 64];
    DWORD start = 0, type = 0;
    LPWSTR before = snapshot(sys);
    create_other_service();
    /* Nothing of ours registered: unregistration leaves the other product's service alone. */
    CHECK_HR(host(L"/UnregServer"), S_OK);
    CHECK(service_config(OOP_SERVICE, command_line, account, &start, &type) && wcscmp(command_line, OTHER_COMMAND) == 0);
    CHECK_HR(host(L"/Service"), ERROR_HR(ERROR_SERVICE_EXISTS));
    CHECK(same_snapshot(before, snapshot(sys)));
    CHECK(service_config(OOP_SERVICE, command_line, account, &start, &type) && wcscmp(command_line, OTHER_COMMAND) == 0);
    CHECK_HR(host(L"/Service /TakeOver"), S_OK);
    CHECK(service_config(OOP_SERVICE, command_line, account, &start, &type));
    CHECK(wcsncmp(command_line, server_command, wcslen(server_command)) == 0);
    CHECK(wcscmp(account, L"LocalSystem") == 0); /* only the command line changes */
    CHECK_HR(host(L"/UnregServer"), S_OK);
    CHECK(service_config(OOP_SERVICE, command_line, account, &start, &type) && wcscmp(command_line, OTHER_COMMAND) == 0);
    CHECK(same_snapshot(before, snapshot(sys)));
    remove_service(OOP_SERVICE); /* the other product leaves */

    /* Ours, then pointed at the other product's program since (by its installer): unregistration
     * removes our registrations and leaves that service, which is no longer ours. */
    CHECK_HR(host(L"/Service"), S_OK);
    CHECK(set_service_command(OOP_SERVICE, OTHER_COMMAND));
    CHECK_HR(host(L"/UnregServer"), S_OK);
    CHECK(service_config(OOP_SERVICE, command_line, account, &start, &type) && wcscmp(command_line, OTHER_COMMAND) == 0);
    CHECK(same_snapshot(before, snapshot(sys)));
    free(before);
    remove_service(OOP_SERVICE);
}

/* Registered as a service: reached by activation, serving on after its last client, stopped by the
 * service manager while a client holds an object with a shutdown sink, started again, unregistered
 * while it runs. */
static void test_server_as_a_service(OpcRegistry *sys) {
    WCHAR command_line[MAX_PATH + 64], account[MAX_PATH + 64], expected[MAX_PATH + 64];
    DWORD start = 0, type = 0, pid = 0, exit_code = 99, first;
    IOPCCommon *c = NULL;
    IUnknown *sink = NULL;
    DWORD cookie = 0;
    Told told;
    LPWSTR before = snapshot(sys), registered;
    LPWSTR value = NULL;

    CHECK_HR(host(L"/Service"), S_OK);
    CHECK(service_config(OOP_SERVICE, command_line, account, &start, &type));
    swprintf(expected, MAX_PATH + 64, L"%ls -RunService", server_command);
    CHECK(wcscmp(command_line, expected) == 0);
    CHECK(wcscmp(account, L"NT AUTHORITY\\LocalService") == 0);
    CHECK(start == SERVICE_DEMAND_START && type == SERVICE_WIN32_OWN_PROCESS);
    CHECK_HR(OpcRegistryGetString(sys, L"AppID\\{C3000000-5EED-4000-8000-0000000000A1}", L"LocalService", &value), S_OK);
    CHECK(wsame(value, OOP_SERVICE));
    CoTaskMemFree(value);
    value = NULL;
    CHECK_HR(OpcRegistryGetString(sys, L"CLSID\\{C3000000-5EED-4000-8000-000000000001}\\LocalServer32", NULL, &value), S_OK);
    CHECK(wsame(value, server_command)); /* the EXE form's key stays (COM prefers the service) */
    CoTaskMemFree(value);
    registered = snapshot(sys);
    CHECK_HR(host(L"/Service"), S_OK); /* registering again changes nothing */
    CHECK(same_snapshot(registered, snapshot(sys)));
    /* Registered but not started by the service manager: -RunService by hand is refused at once. */
    CHECK_HR(host(L"-RunService"), ERROR_HR(ERROR_FAILED_SERVICE_CONTROLLER_CONNECT));
    CHECK(service_state(OOP_SERVICE, NULL, NULL) == SERVICE_STOPPED);

    /* Activation goes through the service manager: the server's process is the service's. */
    CHECK_HR(CoCreateInstance(&CLSID_OopServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&c), S_OK);
    if (!c) return;
    first = server_process(c);
    CHECK(service_state(OOP_SERVICE, &pid, NULL) == SERVICE_RUNNING);
    CHECK(first != 0 && pid == first);
    c->lpVtbl->Release(c);
    c = NULL;
    /* It serves on after its last client left (started by COM it would end 2 s after: its linger and
     * the host's pause). */
    CHECK(process_stays_alive(first, 3000));
    CHECK(service_state(OOP_SERVICE, &pid, NULL) == SERVICE_RUNNING && pid == first);
    /* While the service runs, a second -RunService by hand is refused too, and the service runs on. */
    CHECK_HR(host(L"-RunService"), ERROR_HR(ERROR_FAILED_SERVICE_CONTROLLER_CONNECT));
    CHECK(service_state(OOP_SERVICE, &pid, NULL) == SERVICE_RUNNING && pid == first);

    /* The service manager's stop while a client holds an object with a shutdown sink: the sink is
     * told, and the service ends within its bound although the client never lets go. */
    CHECK_HR(CoCreateInstance(&CLSID_OopServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&c), S_OK);
    if (!c) return;
    CHECK(server_process(c) == first); /* the running service, not a new process */
    memset(&told, 0, sizeof told);
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown, &told, &IID_IUnknown, (void **)&sink), S_OK);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)c, sink, &cookie), S_OK);
    CHECK(stop_service(OOP_SERVICE));
    CHECK(told_within(&told));
    CHECK(wstr_is(told.reason, OOP_REASON));
    CHECK(wait_stopped(OOP_SERVICE, &exit_code) == SERVICE_STOPPED);
    CHECK(exit_code == NO_ERROR);
    CHECK(process_ends(first));
    c->lpVtbl->Release(c); /* a proxy of a process that is gone */
    c = NULL;
    if (sink) sink->lpVtbl->Release(sink);

    /* The next client starts it again; without clients a stop ends it at once. */
    CHECK_HR(CoCreateInstance(&CLSID_OopServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&c), S_OK);
    if (!c) return;
    CHECK(service_state(OOP_SERVICE, &pid, NULL) == SERVICE_RUNNING && pid == server_process(c) && pid != first);
    c->lpVtbl->Release(c);
    c = NULL;
    CHECK(stop_service(OOP_SERVICE));
    CHECK(wait_stopped(OOP_SERVICE, &exit_code) == SERVICE_STOPPED && exit_code == NO_ERROR);
    CHECK(process_ends(pid)); /* (the service manager starts no new one while it is there) */

    /* Unregistered while it runs: stopped, deleted, and the registry as it was. */
    CHECK_HR(CoCreateInstance(&CLSID_OopServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&c), S_OK);
    if (c) c->lpVtbl->Release(c);
    CHECK(service_state(OOP_SERVICE, &pid, NULL) == SERVICE_RUNNING);
    CHECK_HR(host(L"/UnregServer"), S_OK);
    CHECK(!service_exists(OOP_SERVICE));
    CHECK(process_ends(pid));
    CHECK(same_snapshot(before, snapshot(sys)));
    free(registered);
    free(before);
}

/* /RegServer after /Service: back to the EXE form (no service, no LocalService); /Service after
 * /RegServer adds the service; /UnregServer removes either. */
static void the_forms_follow_each_other(OpcRegistry *sys) {
    LPWSTR before = snapshot(sys), exe_form;
    LPWSTR value = NULL;
    CHECK_HR(host(L"/RegServer"), S_OK);
    exe_form = snapshot(sys);
    CHECK_HR(host(L"/Service"), S_OK);
    CHECK(service_exists(OOP_SERVICE));
    CHECK_HR(host(L"/RegServer"), S_OK);
    CHECK(!service_exists(OOP_SERVICE));
    CHECK(FAILED(OpcRegistryGetString(sys, L"AppID\\{C3000000-5EED-4000-8000-0000000000A1}", L"LocalService", &value)));
    CHECK(same_snapshot(exe_form, snapshot(sys)));
    CHECK_HR(host(L"/Service"), S_OK);
    CHECK_HR(host(L"/UnregServer"), S_OK);
    CHECK(!service_exists(OOP_SERVICE));
    CHECK(same_snapshot(before, snapshot(sys)));
    free(exe_form);
    free(before);
}

/* ---- The browser as a service ---- */

/* Runs the browser with `args`; its exit code. */
static DWORD browser(const WCHAR *args) {
    WCHAR cmd[MAX_PATH + 64];
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    DWORD code = 999;
    swprintf(cmd, MAX_PATH + 64, L"\"%ls\\opccomn_browser.exe\" %ls", dir, args);
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    if (!CreateProcessW(NULL, cmd, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi)) return 998;
    WaitForSingleObject(pi.hProcess, 60000);
    GetExitCodeProcess(pi.hProcess, &code);
    CloseHandle(pi.hProcess);
    CloseHandle(pi.hThread);
    return code;
}

/* Whether the process `pid` runs opccomn_browser.exe. (By its identifier: other tests' browsers may
 * still be about in this Wine session.) */
static int is_browser(DWORD pid) {
    PROCESSENTRY32W e;
    int found = 0;
    HANDLE snap = CreateToolhelp32Snapshot(TH32CS_SNAPPROCESS, 0);
    if (snap == INVALID_HANDLE_VALUE) return 0;
    e.dwSize = sizeof e;
    if (Process32FirstW(snap, &e)) {
        do found |= e.th32ProcessID == pid && _wcsicmp(e.szExeFile, L"opccomn_browser.exe") == 0;
        while (Process32NextW(snap, &e));
    }
    CloseHandle(snap);
    return found;
}

static void browser_as_a_service(OpcRegistry *sys) {
    static const CATID CATID_DA2 = {0x63D5F432, 0xCFE4, 0x11D1, {0xB2, 0xC8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
    WCHAR command_line[MAX_PATH + 64], account[MAX_PATH + 64], expected[MAX_PATH + 64];
    DWORD start = 0, type = 0, pid = 0, exit_code = 99;
    IOPCServerList2 *list = NULL;
    IOPCEnumGUID *e = NULL;
    IUnknown *sink = NULL;
    DWORD cookie = 0;
    Told told;
    LPWSTR before = snapshot(sys), registered;

    CHECK(browser(L"-RunService") == 1); /* no such service: refused (the error printed) */
    CHECK(browser(L"/Service") == 0);    /* 0: this browser is the active one */
    CHECK(browser(L"/Status") == 0);
    registered = snapshot(sys);
    CHECK(browser(L"/Service") == 0); /* again: nothing changes */
    CHECK(same_snapshot(registered, snapshot(sys)));
    free(registered);
    CHECK(browser(L"-RunService") == 1); /* registered, not started by the service manager */
    CHECK(service_state(BROWSER_SERVICE, NULL, NULL) == SERVICE_STOPPED);
    CHECK(service_config(BROWSER_SERVICE, command_line, account, &start, &type));
    swprintf(expected, MAX_PATH + 64, L"\"%ls\\opccomn_browser.exe\" -RunService", dir);
    CHECK(wcscmp(command_line, expected) == 0);
    CHECK(wcscmp(account, L"NT AUTHORITY\\LocalService") == 0);
    CHECK(start == SERVICE_DEMAND_START && type == SERVICE_WIN32_OWN_PROCESS);

    CHECK_HR(CoCreateInstance(&CLSID_OPCServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&list), S_OK);
    if (!list) return;
    CHECK(service_state(BROWSER_SERVICE, &pid, NULL) == SERVICE_RUNNING);
    CHECK(pid != 0 && is_browser(pid));
    CHECK_HR(list->lpVtbl->EnumClassesOfCategories(list, 1, (CATID *)&CATID_DA2, 0, NULL, &e), S_OK);
    if (e) e->lpVtbl->Release(e);
    memset(&told, 0, sizeof told);
    CHECK_HR(OpcShutdownSinkCreate(on_shutdown, &told, &IID_IUnknown, (void **)&sink), S_OK);
    CHECK_HR(OpcShutdownAdvise((IUnknown *)list, sink, &cookie), S_OK);
    CHECK(stop_service(BROWSER_SERVICE));
    CHECK(told_within(&told));
    CHECK(wstr_is(told.reason, "The OPC server browser is stopping."));
    /* The client does what it is asked: it lets go, and the service ends. */
    CHECK_HR(OpcShutdownUnadvise((IUnknown *)list, cookie), S_OK);
    list->lpVtbl->Release(list);
    if (sink) sink->lpVtbl->Release(sink);
    CHECK(wait_stopped(BROWSER_SERVICE, &exit_code) == SERVICE_STOPPED && exit_code == NO_ERROR);
    CHECK(process_ends(pid));

    CHECK(browser(L"/UnregServer") == 0);
    CHECK(!service_exists(BROWSER_SERVICE));
    CHECK(browser(L"/Status") == 2);
    CHECK(same_snapshot(before, snapshot(sys)));
    free(before);
}

int main(void) {
    OpcRegistry *sys = NULL;
    WCHAR *slash;
    GetModuleFileNameW(NULL, dir, MAX_PATH);
    slash = wcsrchr(dir, L'\\');
    if (slash) *slash = 0;
    swprintf(server_path, MAX_PATH, L"%ls\\opccomn_test_server.exe", dir);
    swprintf(server_command, MAX_PATH + 32, L"\"%ls\" -release:%d", server_path, SERVICE_RELEASE_MS);

    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
    CHECK_HR(OpcRegistryOpenSystem(&sys), S_OK);
    scm = OpenSCManagerW(NULL, NULL, SC_MANAGER_ALL_ACCESS);
    CHECK(scm != NULL);
    if (!scm) return test_summary("test_service");
    /* Whatever an interrupted earlier run left. */
    host(L"/UnregServer");
    browser(L"/UnregServer");
    remove_service(OOP_SERVICE);
    remove_service(BROWSER_SERVICE);
    OpcUnregisterProxyStub(NULL);
    CHECK_HR(OpcRegisterProxyStub(NULL, 0), S_OK);

    preconditions(sys);
    another_products_service(sys);
    test_server_as_a_service(sys);
    the_forms_follow_each_other(sys);
    browser_as_a_service(sys);

    CHECK_HR(OpcUnregisterProxyStub(NULL), S_OK);
    CloseServiceHandle(scm);
    OpcRegistryRelease(sys);
    CoUninitialize();
    return test_summary("test_service");
}
