/* opccomn_browser.exe: the OPC server browser out of process (the job of the Foundation's OpcEnum.exe).
 * It serves CLSID_OPCServerList (IOPCServerList, IOPCServerList2, IOPCEnumGUID over the system
 * registry, both views) as a LocalServer32, so other processes and remote clients (DCOM) can find the
 * OPC servers of this machine. It needs opccomn.dll next to it, and the proxy/stub of the OPC Common
 * interfaces registered (`regsvr32 /n /i:ProxyStub opccomn.dll`, or the Foundation's opccomn_ps.dll).
 *
 *   opccomn_browser /RegServer [/TakeOver]   register (LocalServer32, AppID); exit code 0 when this
 *                                            browser is active afterwards, 2 when another (OpcEnum)
 *                                            stays active (printed), 1 on errors
 *   opccomn_browser /Service [/TakeOver]     register as the Windows service OpcComnBrowser, as
 *                                            `OpcEnum /Service` does (the same, and the AppID's
 *                                            LocalService naming the service); exit codes as above
 *   opccomn_browser /UnregServer             remove what /RegServer or /Service wrote (the service
 *                                            too), restoring what it replaced
 *   opccomn_browser /Status                  print which browser is registered as active
 *   opccomn_browser -Embedding               (COM starts it so) serve until the last client is gone
 *   opccomn_browser -RunService              (the service manager starts it so) serve until stopped
 *
 * Switches are read from the arguments after the program name, in any case, with / or -. The
 * LocalServer32 command line registration writes holds the program's path in quotes (a path with
 * blanks unquoted could start another program, CWE-428).
 *
 * Coexistence: CLSID_OPCServerList is OpcEnum's CLSID. When its LocalServer32 names another program,
 * /RegServer leaves it (and every other value) as it is and says so; /TakeOver makes this browser the
 * active one, recording what it replaced, and /UnregServer puts it back. /UnregServer takes back only
 * what still holds what this program wrote (the registration helpers keep a ledger in the
 * LocalServer32 key): an OpcEnum installed or re-registered since keeps its registration as it is.
 *
 * DCOM security: OpcInitializeServerSecurity with the AppID {CCD63ADF-D02D-46DD-B170-FA6E0F086FE3}
 * (EOAC_APPID), so its AuthenticationLevel and access and launch permissions decide (editable with
 * dcomcnfg). Registration writes them hardened (Windows' DCOM hardening, KB5004442):
 * AuthenticationLevel 5 (PKT_INTEGRITY), and authenticated users may browse, locally and remotely,
 * while anonymous and unauthenticated callers may not (BROWSER_ACCESS, BROWSER_LAUNCH). See
 * docs/guide/dcom-appid.md and docs/guide/out-of-process.md.
 *
 * Lifetime: the library's EXE host (OpcExeServerRun) keeps the process while a client holds any
 * object it handed out, the server list's enumerators included. As a service it serves until the
 * service manager stops it (or the system shuts down).
 *
 * Stop: a stop (the service manager's, a system shutdown, Ctrl+C) tells every client that advised a
 * shutdown sink on a server list (IConnectionPointContainer, IOPCShutdown), within BROWSER_NOTIFY_MS
 * in all, and the host then waits for the clients to let go (10 s at most).
 *
 * The service (registered by the library's host, OpcExeServerRun with `service_name`): its own
 * process, demand start, NT AUTHORITY\LocalService (the least privileged account: the browser only
 * reads the registry), started by COM through the service manager for a client of
 * CLSID_OPCServerList. Registration rules as for the rest: /Service refuses a service of that name
 * another product registered unless /TakeOver, and /UnregServer deletes only the service it created
 * while it still starts this program (docs/guide/server-plumbing.md, "As a Windows service"). */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>

#include <opccomn/opccomn.h>


static const CLSID APPID_OpcComnBrowser = {0xCCD63ADF, 0xD02D, 0x46DD, {0xB1, 0x70, 0xFA, 0x6E, 0x0F, 0x08, 0x6F, 0xE3}};
/* AccessPermission: authenticated users (AU) and SYSTEM may call, locally and remotely
 * (COM_RIGHTS_EXECUTE | EXECUTE_LOCAL | EXECUTE_REMOTE = 0x7). */
#define BROWSER_ACCESS L"O:BAG:BAD:(A;;0x7;;;AU)(A;;0x7;;;SY)"
/* LaunchPermission: authenticated users and SYSTEM may start and activate it, locally and remotely
 * (EXECUTE | EXECUTE_LOCAL | EXECUTE_REMOTE | ACTIVATE_LOCAL | ACTIVATE_REMOTE = 0x1F). The machine's
 * MachineLaunchRestriction still applies on top (by default remote launch only for Administrators and
 * Distributed COM Users). */
#define BROWSER_LAUNCH L"O:BAG:BAD:(A;;0x1F;;;AU)(A;;0x1F;;;SY)"
#define SERVER_LIST_KEY L"CLSID\\{13486D51-4821-11D2-A494-3CB306C10000}\\LocalServer32"
#define BROWSER_APPID_KEY L"AppID\\{CCD63ADF-D02D-46DD-B170-FA6E0F086FE3}"
/* A browser nobody connects to gives up after this long (COM starts it for a client, so one comes). */
#define IDLE_MS 60000
/* The Windows service of /Service (at most 38 characters: Wine's COM reads no longer LocalService). */
#define BROWSER_SERVICE L"OpcComnBrowser"
/* A stop tells the clients within this long, all server lists together. */
#define BROWSER_NOTIFY_MS 3000
#define BROWSER_STOP_REASON L"The OPC server browser is stopping."

/* ---- The server list objects: the library's server list, with a shutdown connection point ----
 * The library's object (IOPCServerList, IOPCServerList2) is contained and called through; the
 * shutdown object (IConnectionPointContainer with the IOPCShutdown connection point) is aggregated. */
typedef struct Browser {
    IOPCServerList2 list2; /* the identity */
    IOPCServerList list1;
    LONG refs;
    IOPCServerList2 *inner2; /* the library's server list */
    IOPCServerList *inner1;
    IUnknown *shutdown; /* the shutdown object's inner IUnknown */
    struct Browser *next, *prev;
} Browser;

/* The live server lists, for a stop. */
static CRITICAL_SECTION browsers_lock;
static Browser all_browsers; /* the list's head (main links it to itself) */

static Browser *of2(IOPCServerList2 *p) { return (Browser *)p; }
static Browser *of1(IOPCServerList *p) { return (Browser *)((char *)p - offsetof(Browser, list1)); }

static HRESULT STDMETHODCALLTYPE browser_qi(Browser *b, REFIID riid, void **ppv) {
    if (!ppv) return E_POINTER;
    *ppv = NULL;
    if (!riid) return E_INVALIDARG;
    if (IsEqualIID(riid, &IID_IUnknown) || IsEqualIID(riid, &IID_IOPCServerList2)) *ppv = &b->list2;
    else if (IsEqualIID(riid, &IID_IOPCServerList)) *ppv = &b->list1;
    else if (IsEqualIID(riid, &IID_IConnectionPointContainer))
        return b->shutdown->lpVtbl->QueryInterface(b->shutdown, riid, ppv);
    else return E_NOINTERFACE;
    InterlockedIncrement(&b->refs);
    return S_OK;
}

static ULONG browser_release(Browser *b) {
    LONG n = InterlockedDecrement(&b->refs);
    if (n == 0) {
        EnterCriticalSection(&browsers_lock);
        b->prev->next = b->next;
        b->next->prev = b->prev;
        LeaveCriticalSection(&browsers_lock);
        b->refs = 1; /* guard against the aggregated object's releases coming back */
        if (b->inner1) b->inner1->lpVtbl->Release(b->inner1);
        if (b->inner2) b->inner2->lpVtbl->Release(b->inner2);
        if (b->shutdown) b->shutdown->lpVtbl->Release(b->shutdown);
        free(b);
        OpcServerUnlock();
    }
    return (ULONG)n;
}

static HRESULT STDMETHODCALLTYPE list2_qi(IOPCServerList2 *This, REFIID riid, void **ppv) { return browser_qi(of2(This), riid, ppv); }
static ULONG STDMETHODCALLTYPE list2_add_ref(IOPCServerList2 *This) { return (ULONG)InterlockedIncrement(&of2(This)->refs); }
static ULONG STDMETHODCALLTYPE list2_release(IOPCServerList2 *This) { return browser_release(of2(This)); }
static HRESULT STDMETHODCALLTYPE list2_enum(IOPCServerList2 *This, ULONG implemented_count, CATID implemented[],
                                            ULONG required_count, CATID required[], IOPCEnumGUID **classes) {
    IOPCServerList2 *inner = of2(This)->inner2;
    return inner->lpVtbl->EnumClassesOfCategories(inner, implemented_count, implemented, required_count, required, classes);
}
static HRESULT STDMETHODCALLTYPE list2_details(IOPCServerList2 *This, REFCLSID clsid, LPOLESTR *prog_id,
                                               LPOLESTR *user_type, LPOLESTR *version_independent_prog_id) {
    IOPCServerList2 *inner = of2(This)->inner2;
    return inner->lpVtbl->GetClassDetails(inner, clsid, prog_id, user_type, version_independent_prog_id);
}
static HRESULT STDMETHODCALLTYPE list2_clsid(IOPCServerList2 *This, LPCOLESTR prog_id, LPCLSID clsid) {
    IOPCServerList2 *inner = of2(This)->inner2;
    return inner->lpVtbl->CLSIDFromProgID(inner, prog_id, clsid);
}
static IOPCServerList2Vtbl list2_vtbl = {list2_qi, list2_add_ref, list2_release, list2_enum, list2_details, list2_clsid};

static HRESULT STDMETHODCALLTYPE list1_qi(IOPCServerList *This, REFIID riid, void **ppv) { return browser_qi(of1(This), riid, ppv); }
static ULONG STDMETHODCALLTYPE list1_add_ref(IOPCServerList *This) { return (ULONG)InterlockedIncrement(&of1(This)->refs); }
static ULONG STDMETHODCALLTYPE list1_release(IOPCServerList *This) { return browser_release(of1(This)); }
static HRESULT STDMETHODCALLTYPE list1_enum(IOPCServerList *This, ULONG implemented_count, CATID implemented[],
                                            ULONG required_count, CATID required[], IEnumGUID **classes) {
    IOPCServerList *inner = of1(This)->inner1;
    return inner->lpVtbl->EnumClassesOfCategories(inner, implemented_count, implemented, required_count, required, classes);
}
static HRESULT STDMETHODCALLTYPE list1_details(IOPCServerList *This, REFCLSID clsid, LPOLESTR *prog_id, LPOLESTR *user_type) {
    IOPCServerList *inner = of1(This)->inner1;
    return inner->lpVtbl->GetClassDetails(inner, clsid, prog_id, user_type);
}
static HRESULT STDMETHODCALLTYPE list1_clsid(IOPCServerList *This, LPCOLESTR prog_id, LPCLSID clsid) {
    IOPCServerList *inner = of1(This)->inner1;
    return inner->lpVtbl->CLSIDFromProgID(inner, prog_id, clsid);
}
static IOPCServerListVtbl list1_vtbl = {list1_qi, list1_add_ref, list1_release, list1_enum, list1_details, list1_clsid};

static HRESULT OPCCOMN_CDECL create_server_list(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    Browser *b = (Browser *)calloc(1, sizeof *b);
    HRESULT hr;
    (void)context;
    (void)outer; /* not aggregatable: the library refuses an outer object */
    if (!b) return E_OUTOFMEMORY;
    b->list2.lpVtbl = &list2_vtbl;
    b->list1.lpVtbl = &list1_vtbl;
    b->refs = 1;
    OpcServerLock(); /* the object counts on the server while it lives */
    EnterCriticalSection(&browsers_lock);
    b->next = all_browsers.next;
    b->prev = &all_browsers;
    all_browsers.next->prev = b;
    all_browsers.next = b;
    LeaveCriticalSection(&browsers_lock);
    hr = OpcServerListCreate(NULL, &IID_IOPCServerList2, (void **)&b->inner2);
    if (SUCCEEDED(hr)) hr = b->inner2->lpVtbl->QueryInterface(b->inner2, &IID_IOPCServerList, (void **)&b->inner1);
    if (SUCCEEDED(hr)) hr = OpcShutdownCreate((IUnknown *)&b->list2, &IID_IUnknown, (void **)&b->shutdown);
    if (SUCCEEDED(hr)) hr = browser_qi(b, riid, ppv);
    browser_release(b);
    return hr;
}

/* A stop: every client that advised a shutdown sink on a server list is told, within
 * BROWSER_NOTIFY_MS for all of them together. (On the host's thread; then the host waits for the
 * clients to let go.) */
static void OPCCOMN_CDECL on_stop(void *context) {
    Browser *b, **each = NULL;
    size_t n = 0, cap = 0, i;
    ULONGLONG deadline = GetTickCount64() + BROWSER_NOTIFY_MS;
    (void)context;
    EnterCriticalSection(&browsers_lock);
    for (b = all_browsers.next; b != &all_browsers; b = b->next) {
        if (InterlockedCompareExchange(&b->refs, 0, 0) <= 0) continue; /* on its way out */
        if (n == cap) {
            Browser **more = (Browser **)realloc(each, (cap = cap ? 2 * cap : 16) * sizeof *each);
            if (!more) break;
            each = more;
        }
        InterlockedIncrement(&b->refs);
        each[n++] = b;
    }
    LeaveCriticalSection(&browsers_lock);
    for (i = 0; i < n; i++) {
        ULONGLONG now = GetTickCount64();
        if (now < deadline) {
            OpcShutdownNotifyOptions bounds;
            memset(&bounds, 0, sizeof bounds);
            bounds.struct_size = sizeof bounds;
            bounds.timeout_ms = (uint32_t)(deadline - now);
            OpcShutdownNotifyBounded((IUnknown *)&each[i]->list2, BROWSER_STOP_REASON, &bounds, NULL, NULL, NULL);
        }
        browser_release(each[i]);
    }
    free(each);
}

static OpcServerRegistration registration(const WCHAR *self) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = CLSID_OPCServerList;
    r.prog_id = L"OPC.ServerList.1";
    r.version_independent_prog_id = L"OPC.ServerList";
    r.user_type = L"Opc ServerList Class";
    r.module_path = self;
    r.app_id = &APPID_OpcComnBrowser;
    r.app_id_access_permission = BROWSER_ACCESS;
    r.app_id_launch_permission = BROWSER_LAUNCH;
    r.app_id_authentication_level = OPC_AUTHN_LEVEL_PKT_INTEGRITY;
    return r;
}

/* The program LocalServer32 of CLSID_OPCServerList names, or "" (static buffer). */
static const WCHAR *active_browser(void) {
    static WCHAR data[MAX_PATH + 64];
    DWORD size = sizeof data;
    data[0] = 0;
    if (RegGetValueW(HKEY_CLASSES_ROOT, SERVER_LIST_KEY, NULL, RRF_RT_REG_SZ | RRF_RT_REG_EXPAND_SZ | RRF_NOEXPAND,
                     NULL, data, &size) != ERROR_SUCCESS)
        data[0] = 0;
    return data;
}

/* The library's EXE host with the browser's class: `command_line` "-Embedding" or "-RunService"
 * serves (the server list over the system registry: until the last object a client holds is released,
 * its enumerators included, or nobody came within IDLE_MS; as the service, until stopped); the
 * registration switches register or unregister (with the service). */
static HRESULT host(const WCHAR *self, const WCHAR *command_line) {
    OpcServerClass cls;
    OpcExeServerOptions options;
    OpcServerRegistration r = registration(self);
    memset(&cls, 0, sizeof cls);
    cls.struct_size = sizeof cls;
    cls.clsid = &CLSID_OPCServerList;
    cls.create = create_server_list;
    cls.registration = &r;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.classes = &cls;
    options.class_count = 1;
    options.first_client_timeout_ms = IDLE_MS;
    options.on_stop = on_stop;
    options.service_name = BROWSER_SERVICE; /* the least privileged account: NT AUTHORITY\LocalService */
    return OpcExeServerRun(&options, command_line);
}

static int serve(const WCHAR *self, const WCHAR *command_line) {
    OpcSecurityOptions security;
    HRESULT hr = CoInitializeEx(NULL, COINIT_MULTITHREADED);
    /* The process's security is the AppID's (EOAC_APPID): its AuthenticationLevel and AccessPermission
     * decide who may call (machine defaults where it has none). (The host would set it so too, from
     * the registration's AppID.) */
    memset(&security, 0, sizeof security);
    security.struct_size = sizeof security;
    security.appid = &APPID_OpcComnBrowser;
    if (SUCCEEDED(hr)) hr = OpcInitializeServerSecurity(&security);
    if (SUCCEEDED(hr)) hr = host(self, command_line);
    if (SUCCEEDED(hr)) return 0; /* without CoUninitialize (OpcExeServerRun) */
    fprintf(stderr, "opccomn_browser: cannot serve CLSID_OPCServerList: 0x%08lX\n", (unsigned long)hr);
    return 1;
}

static int is_self(const WCHAR *command, const WCHAR *self) {
    size_t n = wcslen(self);
    if (command[0] == L'"') command++;
    return _wcsnicmp(command, self, n) == 0 && (command[n] == 0 || command[n] == L'"' || command[n] == L' ');
}

/* The arguments after the program name, by the rule Windows reads the program name with: up to the
 * closing quote when it starts with one, else up to the first blank. (The program's path is no
 * argument: a browser under C:\Plant-Status\ or "C:\OPC -TakeOver\" is no /Status or /TakeOver.) */
static const WCHAR *arguments_of(const WCHAR *line) {
    if (*line == L'"') {
        line++;
        while (*line && *line != L'"') line++;
        if (*line) line++;
    } else {
        while (*line && *line != L' ' && *line != L'\t') line++;
    }
    return line;
}

/* True when `args` holds the switch `name` as a whole argument: /name or -name, in any case, as
 * OpcParseCommandLine matches its switches. */
static int has_switch(const WCHAR *args, const WCHAR *name) {
    size_t n = wcslen(name);
    while (*args) {
        const WCHAR *start;
        int quoted = 0;
        while (*args == L' ' || *args == L'\t') args++;
        start = args;
        while (*args && (quoted || (*args != L' ' && *args != L'\t'))) {
            if (*args == L'"') quoted = !quoted;
            args++;
        }
        if ((size_t)(args - start) == n + 1 && (start[0] == L'/' || start[0] == L'-') &&
            _wcsnicmp(start + 1, name, n) == 0)
            return 1;
    }
    return 0;
}

/* The service the browser's AppID names (LocalService), or "" (static buffer). */
static const WCHAR *browser_service(void) {
    static WCHAR data[300];
    DWORD size = sizeof data;
    data[0] = 0;
    if (RegGetValueW(HKEY_CLASSES_ROOT, BROWSER_APPID_KEY, L"LocalService", RRF_RT_REG_SZ, NULL, data, &size) !=
        ERROR_SUCCESS)
        data[0] = 0;
    return data;
}

static int status(const WCHAR *self) {
    const WCHAR *active = active_browser();
    if (!active[0]) printf("no out-of-process server browser is registered\n");
    else if (is_self(active, self) && browser_service()[0])
        printf("active: opccomn_browser (%ls), as the Windows service %ls\n", active, browser_service());
    else if (is_self(active, self)) printf("active: opccomn_browser (%ls)\n", active);
    else printf("active: another server browser (OpcEnum?): %ls\n", active);
    return active[0] && is_self(active, self) ? 0 : 2;
}

int main(void) {
    WCHAR self[MAX_PATH];
    const WCHAR *args = arguments_of(GetCommandLineW());
    uint32_t command = OPC_SERVER_COMMAND_NONE;
    int service;
    HRESULT hr;
    GetModuleFileNameW(NULL, self, MAX_PATH);
    InitializeCriticalSection(&browsers_lock);
    all_browsers.next = all_browsers.prev = &all_browsers;
    if (has_switch(args, L"Status")) return status(self);
    if (has_switch(args, L"RunService")) return serve(self, L"-RunService");
    service = has_switch(args, L"Service");
    if (FAILED(OpcParseCommandLine(args, &command))) command = OPC_SERVER_COMMAND_NONE;
    if (command == OPC_SERVER_COMMAND_REGISTER || service) {
        const WCHAR *active = active_browser();
        int take_over = has_switch(args, L"TakeOver");
        if (active[0] && !is_self(active, self) && !take_over) {
            printf("not registered: another server browser is active (%ls); /TakeOver replaces it until "
                   "/UnregServer\n", active);
            return 2;
        }
        /* The host registers the EXE form (/RegServer, removing a service registered before) or the
         * service (/Service, /TakeOver also taking over another product's service of that name). */
        hr = host(self, args);
        if (FAILED(hr)) {
            fprintf(stderr, "opccomn_browser: registration failed: 0x%08lX\n", (unsigned long)hr);
            return 1;
        }
        return status(self);
    }
    if (command == OPC_SERVER_COMMAND_UNREGISTER) {
        hr = host(self, L"/UnregServer");
        if (FAILED(hr)) {
            fprintf(stderr, "opccomn_browser: unregistration failed: 0x%08lX\n", (unsigned long)hr);
            return 1;
        }
        status(self);
        return 0;
    }
    if (command == OPC_SERVER_COMMAND_EMBEDDING) return serve(self, L"-Embedding");
    fprintf(stderr, "usage: opccomn_browser /RegServer [/TakeOver] | /Service [/TakeOver] | /UnregServer | /Status | "
                    "-Embedding | -RunService\n");
    return 1;
}
