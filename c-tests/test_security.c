/* DCOM security through the public header (OpcInitializeServerSecurity, OpcInitializeClientSecurity,
 * OpcSetProxyBlanket), in a fresh process, as COM sets process security once per process:
 *
 *   test_security            a server with an access list (SDDL): the real CoInitializeSecurity
 *   test_security appid      a server with its AppID (EOAC_APPID)
 *   test_security client     a client with the defaults
 *
 * Each checks that what must be refused is refused before COM is called (a level below
 * PKT_INTEGRITY without OPC_SECURITY_ALLOW_WEAKER_AUTHN, bad options), that the real call succeeds,
 * and that a second call, by either function, gives RPC_E_TOO_LATE. Under Wine, CoInitializeSecurity
 * accepts every call and enforces nothing: the S_OK shows the arguments were accepted, and the
 * RPC_E_TOO_LATE is the library's own answer (Windows gives it too). The blanket on a proxy is
 * tested across processes in tests/oop/test_oop.c; here, on an in-process object and on NULL.
 * Off Windows every call checks its arguments, then answers E_NOTIMPL. */
#include "test_util.h"

#ifndef RPC_C_AUTHN_LEVEL_CONNECT /* <windows.h> defines them */
#define RPC_C_AUTHN_LEVEL_CONNECT 2
#define RPC_C_AUTHN_LEVEL_PKT_INTEGRITY 5
#define RPC_C_AUTHN_LEVEL_PKT_PRIVACY 6
#define RPC_C_IMP_LEVEL_IDENTIFY 2
#endif

static const GUID APPID_Test = {0x5EC22000, 0x0000, 0x4000, {0x80, 0, 0, 0, 0, 0, 0, 0x22}};

static OpcSecurityOptions options(void) {
    OpcSecurityOptions o;
    memset(&o, 0, sizeof o);
    o.struct_size = sizeof o;
    return o;
}

/* What must be refused whatever the platform, and whatever was set before. */
static void check_refused(void) {
    OpcSecurityOptions o = options();
    o.authn_level = RPC_C_AUTHN_LEVEL_CONNECT; /* what broke with KB5004442 */
    CHECK_HR(OpcInitializeServerSecurity(&o), E_INVALIDARG);
    CHECK_HR(OpcInitializeClientSecurity(&o), E_INVALIDARG);
    o = options();
    o.struct_size = 4;
    CHECK_HR(OpcInitializeServerSecurity(&o), E_INVALIDARG);
    o = options();
    o.flags = 0x80;
    CHECK_HR(OpcInitializeServerSecurity(&o), E_INVALIDARG);
    o = options();
    o.authn_level = 7;
    CHECK_HR(OpcInitializeServerSecurity(&o), E_INVALIDARG);
    o = options();
    o.appid = &APPID_Test;
    o.access_sddl = W("O:BAG:BAD:(A;;0x7;;;AU)");
    CHECK_HR(OpcInitializeServerSecurity(&o), E_INVALIDARG);
    o = options();
    o.access_sddl = W("");
    CHECK_HR(OpcInitializeServerSecurity(&o), E_INVALIDARG);
    /* The blanket: NULL, a weak level, process settings. */
    CHECK_HR(OpcSetProxyBlanket(NULL, NULL), E_INVALIDARG);
}

static void check_blanket_on_an_in_process_object(void) {
    IUnknown *c = NULL;
    OpcSecurityOptions o = options();
    CHECK_HR(OpcCommonCreate(NULL, NULL, &IID_Unknown_, (void **)&c), S_OK);
    if (!c) return;
    o.authn_level = RPC_C_AUTHN_LEVEL_CONNECT;
    CHECK_HR(OpcSetProxyBlanket(c, &o), E_INVALIDARG);
    o = options();
    o.appid = &APPID_Test;
    CHECK_HR(OpcSetProxyBlanket(c, &o), E_INVALIDARG);
#if defined(_WIN32)
    /* An in-process object has no IClientSecurity: CoSetProxyBlanket's E_NOINTERFACE, passed on. */
    CHECK_HR(OpcSetProxyBlanket(c, NULL), E_NOINTERFACE);
#else
    CHECK_HR(OpcSetProxyBlanket(c, NULL), E_NOTIMPL);
#endif
    c->lpVtbl->Release(c);
}

int main(int argc, char **argv) {
    const char *mode = argc > 1 ? argv[1] : "sddl";
    OpcSecurityOptions o = options();
    HRESULT expected = S_OK;
    int client = strcmp(mode, "client") == 0;
    printf("test_security: %s\n", mode);

#if defined(_WIN32)
    CHECK_HR(CoInitializeEx(NULL, COINIT_MULTITHREADED), S_OK);
#else
    expected = E_NOTIMPL;
#endif
    check_refused();
    check_blanket_on_an_in_process_object();

    if (strcmp(mode, "appid") == 0) {
        o.appid = &APPID_Test;
    } else if (!client) {
        /* Authenticated users and SYSTEM may call, locally and remotely. */
        o.access_sddl = W("O:BAG:BAD:(A;;0x7;;;AU)(A;;0x7;;;SY)");
        o.imp_level = RPC_C_IMP_LEVEL_IDENTIFY;
    }
    /* The real call: the refused ones above did not use up the process's one chance. */
    CHECK_HR(client ? OpcInitializeClientSecurity(NULL) : OpcInitializeServerSecurity(&o), expected);

#if defined(_WIN32)
    /* Process security is set: a second call, by either function, is too late. */
    CHECK_HR(OpcInitializeServerSecurity(NULL), RPC_E_TOO_LATE);
    CHECK_HR(OpcInitializeClientSecurity(NULL), RPC_E_TOO_LATE);
    o = options();
    o.authn_level = RPC_C_AUTHN_LEVEL_PKT_PRIVACY;
    CHECK_HR(OpcInitializeServerSecurity(&o), RPC_E_TOO_LATE);
    /* For the record, what the system answers a second call itself (Windows: RPC_E_TOO_LATE; Wine 8
       accepts every call). Not checked: it is the system's behaviour, not the library's. */
    printf("test_security: the system's own second CoInitializeSecurity: 0x%08lX\n",
           (unsigned long)(unsigned int)CoInitializeSecurity(NULL, -1, NULL, NULL, RPC_C_AUTHN_LEVEL_PKT_INTEGRITY,
                                                             RPC_C_IMP_LEVEL_IDENTIFY, NULL, EOAC_NONE, NULL));
#else
    CHECK_HR(OpcInitializeServerSecurity(NULL), E_NOTIMPL); /* never set off Windows: never too late */
#endif
    check_refused(); /* bad options stay E_INVALIDARG, not RPC_E_TOO_LATE */
    check_blanket_on_an_in_process_object();

#if defined(_WIN32)
    CoUninitialize();
#endif
    CHECK(OpcObjectCount() == 0);
    return test_summary("test_security");
}
