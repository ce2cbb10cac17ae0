/* opccomn_browser.exe: the OPC server browser out of process (the job of the Foundation's OpcEnum.exe).
 * It serves CLSID_OPCServerList (IOPCServerList, IOPCServerList2, IOPCEnumGUID over the system
 * registry, both views) as a LocalServer32, so other processes and remote clients (DCOM) can find the
 * OPC servers of this machine. It needs opccomn.dll next to it, and the proxy/stub of the OPC Common
 * interfaces registered (`regsvr32 /n /i:ProxyStub opccomn.dll`, or the Foundation's opccomn_ps.dll).
 *
 *   opccomn_browser /RegServer [/TakeOver]   register (LocalServer32, AppID); exit code 0 when this
 *                                            browser is active afterwards, 2 when another (OpcEnum)
 *                                            stays active (printed), 1 on errors
 *   opccomn_browser /UnregServer             remove what /RegServer wrote, restoring what it replaced
 *   opccomn_browser /Status                  print which browser is registered as active
 *   opccomn_browser -Embedding               (COM starts it so) serve until the last client is gone
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
 * object it handed out, the server list's enumerators included. */
#include <stdio.h>
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
/* A browser nobody connects to gives up after this long (COM starts it for a client, so one comes). */
#define IDLE_MS 60000

static HRESULT OPCCOMN_CDECL create_server_list(void *context, IUnknown *outer, REFIID riid, void **ppv) {
    (void)context;
    (void)outer; /* not aggregatable: the library refuses an outer object */
    return OpcServerListCreate(NULL, riid, ppv);
}

/* On the library's EXE host: the server list over the system registry, until the last object a
 * client holds is released (its enumerators included), or nobody came within IDLE_MS. */
static int serve(void) {
    OpcServerClass cls;
    OpcExeServerOptions options;
    OpcSecurityOptions security;
    HRESULT hr;
    memset(&cls, 0, sizeof cls);
    cls.struct_size = sizeof cls;
    cls.clsid = &CLSID_OPCServerList;
    cls.create = create_server_list;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.classes = &cls;
    options.class_count = 1;
    options.first_client_timeout_ms = IDLE_MS;
    hr = CoInitializeEx(NULL, COINIT_MULTITHREADED);
    /* The process's security is the AppID's (EOAC_APPID): its AuthenticationLevel and AccessPermission
     * decide who may call (machine defaults where it has none). */
    memset(&security, 0, sizeof security);
    security.struct_size = sizeof security;
    security.appid = &APPID_OpcComnBrowser;
    if (SUCCEEDED(hr)) hr = OpcInitializeServerSecurity(&security);
    if (SUCCEEDED(hr)) hr = OpcExeServerRun(&options, L"-Embedding");
    if (SUCCEEDED(hr)) return 0; /* without CoUninitialize (OpcExeServerRun) */
    fprintf(stderr, "opccomn_browser: cannot serve CLSID_OPCServerList: 0x%08lX\n", (unsigned long)hr);
    return 1;
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

static int status(const WCHAR *self) {
    const WCHAR *active = active_browser();
    if (!active[0]) printf("no out-of-process server browser is registered\n");
    else if (is_self(active, self)) printf("active: opccomn_browser (%ls)\n", active);
    else printf("active: another server browser (OpcEnum?): %ls\n", active);
    return active[0] && is_self(active, self) ? 0 : 2;
}

int main(void) {
    WCHAR self[MAX_PATH];
    const WCHAR *args = arguments_of(GetCommandLineW());
    uint32_t command = OPC_SERVER_COMMAND_NONE;
    OpcServerRegistration r;
    HRESULT hr;
    GetModuleFileNameW(NULL, self, MAX_PATH);
    r = registration(self);
    if (has_switch(args, L"Status")) return status(self);
    if (FAILED(OpcParseCommandLine(args, &command))) command = OPC_SERVER_COMMAND_NONE;
    if (command == OPC_SERVER_COMMAND_REGISTER) {
        const WCHAR *active = active_browser();
        int take_over = has_switch(args, L"TakeOver");
        if (active[0] && !is_self(active, self) && !take_over) {
            printf("not registered: another server browser is active (%ls); /TakeOver replaces it until "
                   "/UnregServer\n", active);
            return 2;
        }
        hr = OpcRegisterServer(&r, NULL);
        if (FAILED(hr)) {
            fprintf(stderr, "opccomn_browser: registration failed: 0x%08lX\n", (unsigned long)hr);
            return 1;
        }
        return status(self);
    }
    if (command == OPC_SERVER_COMMAND_UNREGISTER) {
        hr = OpcUnregisterServer(&r, NULL);
        if (FAILED(hr)) {
            fprintf(stderr, "opccomn_browser: unregistration failed: 0x%08lX\n", (unsigned long)hr);
            return 1;
        }
        status(self);
        return 0;
    }
    if (command == OPC_SERVER_COMMAND_EMBEDDING) return serve();
    fprintf(stderr, "usage: opccomn_browser /RegServer [/TakeOver] | /UnregServer | /Status | -Embedding\n");
    return 1;
}
