/* Benchmark: round trips across processes through opccomn.dll's proxy/stub against the widl-generated
 * one (opccomn_widl_ps.dll, the stand-in for the Foundation's opccomn_ps.dll), in the same run, under
 * the same COM runtime. Both sides of a phase use the same proxy/stub: the client through
 * CoRegisterPSClsid, the test server (tests/oop/oop_server.c, a fresh process per phase) through its
 * command line.
 *
 *   GetErrorString     IOPCCommon::GetErrorString(OPC_E_UNKNOWNITEMID) + CoTaskMemFree
 *   Enum+Next(100)     IOPCServerList2::EnumClassesOfCategories + IOPCEnumGUID::Next of 100 + Release
 *
 * Phases alternate (5 of each) and each contender keeps its best, as the machine is shared. Prints
 * the time per round trip, the ratio ours/widl and a GOAL line per goal (<= 1.1x) with met or NOT MET,
 * as the other benchmarks do; exit code 1 when a goal is missed or a round trip failed. Run with
 * scripts/bench-cross-process.sh [N]: N GetErrorString and N/5 Enum+Next per phase (default 500). */
#include "oop.h"

#include <tlhelp32.h>

static WCHAR server_path[MAX_PATH];
static const CATID CATID_DA2 = {0x63D5F432, 0xCFE4, 0x11D1, {0xB2, 0xC8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
/* Round trips per phase (the first argument scales both: GetErrorString N, Enum+Next N/5). */
static int CALLS_STRING = 500;
static int CALLS_ENUM = 100;
#define ROUNDS 5

static double now(void) {
    LARGE_INTEGER f, c;
    QueryPerformanceFrequency(&f);
    QueryPerformanceCounter(&c);
    return (double)c.QuadPart / (double)f.QuadPart;
}

static int server_running(void) {
    PROCESSENTRY32W e;
    int found = 0;
    HANDLE snap = CreateToolhelp32Snapshot(TH32CS_SNAPPROCESS, 0);
    if (snap == INVALID_HANDLE_VALUE) return 0;
    e.dwSize = sizeof e;
    if (Process32FirstW(snap, &e)) {
        do found |= _wcsicmp(e.szExeFile, L"opccomn_test_server.exe") == 0;
        while (Process32NextW(snap, &e));
    }
    CloseHandle(snap);
    return found;
}

static void set_command(const CLSID *clsid, int widl) {
    WCHAR key[80], command[MAX_PATH + 32], guid[40];
    HKEY h;
    StringFromGUID2(clsid, guid, 40);
    swprintf(key, 80, L"CLSID\\%ls\\LocalServer32", guid);
    swprintf(command, MAX_PATH + 32, widl ? L"\"%ls\" -ps:widl" : L"\"%ls\" -ps:opccomn-direct", server_path);
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key, 0, KEY_WRITE, &h) == ERROR_SUCCESS) {
        RegSetValueExW(h, NULL, 0, REG_SZ, (const BYTE *)command, (DWORD)((wcslen(command) + 1) * sizeof(WCHAR)));
        RegCloseKey(h);
    }
}

static OpcServerRegistration server_registration(const CLSID *clsid, const WCHAR *prog_id) {
    OpcServerRegistration r;
    memset(&r, 0, sizeof r);
    r.struct_size = sizeof r;
    r.server_type = OPC_SERVER_TYPE_LOCAL;
    r.clsid = *clsid;
    r.prog_id = prog_id;
    r.user_type = L"opccomn cross-process benchmark server";
    r.module_path = server_path;
    return r;
}

/* One phase: best-of times per call (seconds) for both operations; 0 on success. */
static int phase(int widl, double *t_string, double *t_enum) {
    IOPCCommon *c = NULL;
    IOPCServerList2 *l = NULL;
    const CLSID *ps = widl ? &CLSID_WidlProxyStub : &CLSID_OpcComnProxyStub;
    double t0;
    int i, k;
    for (k = 0; k < 100 && server_running(); k++) Sleep(50); /* the previous phase's server is gone */
    for (i = 0; i < 5; i++)
        if (FAILED(CoRegisterPSClsid(OOP_IIDS[i], ps))) return 1;
    set_command(&CLSID_OopServer, widl);
    set_command(&CLSID_OopServerList, widl);
    if (FAILED(CoCreateInstance(&CLSID_OopServer, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCCommon, (void **)&c))) return 1;
    if (FAILED(CoCreateInstance(&CLSID_OopServerList, NULL, CLSCTX_LOCAL_SERVER, &IID_IOPCServerList2, (void **)&l))) {
        c->lpVtbl->Release(c);
        return 1;
    }
    /* The proxies in this process must be the phase's. */
    if ((widl_proxy_stub_in_use() == S_FALSE) != widl) {
        fprintf(stderr, "cross_process_bench: phase %s runs with the other proxy/stub\n", widl ? "widl" : "opccomn");
        return 1;
    }
    t0 = now();
    for (i = 0; i < CALLS_STRING; i++) {
        LPWSTR text = NULL;
        if (FAILED(c->lpVtbl->GetErrorString(c, (HRESULT)0xC0040007L, &text)) || !text) return 1;
        CoTaskMemFree(text);
    }
    *t_string = (now() - t0) / CALLS_STRING;
    t0 = now();
    for (i = 0; i < CALLS_ENUM; i++) {
        IOPCEnumGUID *e = NULL;
        GUID buf[OOP_FAKE_SERVERS];
        ULONG fetched = 0;
        if (FAILED(l->lpVtbl->EnumClassesOfCategories(l, 1, (CATID *)&CATID_DA2, 0, NULL, &e))) return 1;
        if (e->lpVtbl->Next(e, OOP_FAKE_SERVERS, buf, &fetched) != S_OK || fetched != OOP_FAKE_SERVERS) return 1;
        e->lpVtbl->Release(e);
    }
    *t_enum = (now() - t0) / CALLS_ENUM;
    l->lpVtbl->Release(l);
    c->lpVtbl->Release(c);
    return 0;
}

int main(int argc, char **argv) {
    OpcServerRegistration server, list;
    double best[2][2] = {{1e9, 1e9}, {1e9, 1e9}};
    WCHAR *slash;
    int round, widl, failed = 0, missed = 0;
    if (argc > 1 && atoi(argv[1]) >= 5) {
        CALLS_STRING = atoi(argv[1]);
        CALLS_ENUM = CALLS_STRING / 5;
    }
    printf("%d x GetErrorString and %d x Enum+Next(100) per phase, %d phases each\n", CALLS_STRING, CALLS_ENUM,
           ROUNDS);
    GetModuleFileNameW(NULL, server_path, MAX_PATH);
    slash = wcsrchr(server_path, L'\\');
    wcscpy(slash ? slash + 1 : server_path, L"opccomn_test_server.exe");
    /* Both proxy/stub class objects registered in this process (and in each phase's server), so that
     * neither pays a registry lookup per new proxy or stub that the other does not. */
    if (FAILED(CoInitializeEx(NULL, COINIT_MULTITHREADED)) || FAILED(use_widl_proxy_stub()) ||
        FAILED(use_opccomn_proxy_stub_directly()))
        return 1;
    server = server_registration(&CLSID_OopServer, L"Oop.Server.1");
    list = server_registration(&CLSID_OopServerList, L"Oop.ServerList.1");
    OpcUnregisterProxyStub(NULL); /* whatever an interrupted earlier run left */
    if (FAILED(OpcRegisterProxyStub(NULL, 0)) || FAILED(OpcRegisterServer(&server, NULL)) ||
        FAILED(OpcRegisterServer(&list, NULL)))
        return 1;
    for (round = 0; round < ROUNDS && !failed; round++) {
        for (widl = 0; widl < 2 && !failed; widl++) {
            /* Alternate which contender goes first. */
            int who = (round & 1) ? 1 - widl : widl;
            double ts, te;
            if (phase(who, &ts, &te)) {
                failed = 1;
                break;
            }
            if (ts < best[who][0]) best[who][0] = ts;
            if (te < best[who][1]) best[who][1] = te;
        }
    }
    OpcUnregisterServer(&server, NULL);
    OpcUnregisterServer(&list, NULL);
    OpcUnregisterProxyStub(NULL);
    CoUninitialize();
    if (failed) {
        fprintf(stderr, "cross_process_bench: a round trip failed\n");
        return 1;
    }
    printf("%-16s %14s %14s %8s\n", "round trip", "opccomn (us)", "widl (us)", "ratio");
    {
        static const char *const names[2] = {"GetErrorString", "Enum+Next(100)"};
        int k;
        for (k = 0; k < 2; k++)
            printf("%-16s %14.1f %14.1f %8.2f\n", names[k], best[0][k] * 1e6, best[1][k] * 1e6, best[0][k] / best[1][k]);
        for (k = 0; k < 2; k++) {
            double ratio = best[0][k] / best[1][k];
            int met = ratio <= 1.1;
            printf("GOAL %-40s %7.2fx  goal <= 1.10x  %s\n", names[k], ratio, met ? "met" : "NOT MET");
            missed |= !met;
        }
    }
    return missed;
}
