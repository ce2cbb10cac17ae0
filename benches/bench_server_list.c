/* Benchmark (not a test) of the server list's Data Access 1.0 scan: servers registered the old way (a
   ProgID with an `OPC` subkey and a `CLSID` subkey, no category), found by walking every key of
   HKEY_CLASSES_ROOT. Registers 2,000 such servers among 20,000 unrelated ProgIDs, then times, in the
   same process and in interleaved rounds:
   - IOPCServerList::EnumClassesOfCategories(CATID_OPCDAServer10), the enumerator drained;
   - the same walk written plainly in C with the registry API: in both registry views, the classes
     whose `Implemented Categories` has the DA 1.0 category, then every key of HKCR (except file
     extensions and CLSID) with an `OPC` subkey whose `CLSID` names a registered class, sorted and
     without duplicates.
   Goal: the server list at most 1.2x the plain walk.

   Second case, the ordinary browse: 2,000 classes implementing a category, found with
   IOPCServerList2::EnumClassesOfCategories and described with GetClassDetails (ProgID, user type,
   version-independent ProgID), against the Component Categories Manager (ICatInformation) with
   ProgIDFromCLSID for each class (less work: one string per class). For information: no goal.

   Everything registered is removed at the end. Windows only (run: scripts/bench.sh --wine server-list). */
#define BENCH_WALL_CLOCK /* the registry lives in wineserver, another process: its time counts */
#include "bench.h"

#include <opccomn/opccomn.h>

#if !defined(_WIN32)
int main(void)
{
    printf("bench_server_list walks the Windows registry: run it with scripts/bench.sh --wine server-list\n");
    return 0;
}
#else

#define SERVERS 2000
#define UNRELATED 20000
#define MAX_FOUND 8192

static GUID bench_clsid(unsigned i)
{
    GUID g = {0xBE0C0010u, 0x0000, 0x4000, {0x80, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}};
    g.Data4[4] = (BYTE)(i >> 24);
    g.Data4[5] = (BYTE)(i >> 16);
    g.Data4[6] = (BYTE)(i >> 8);
    g.Data4[7] = (BYTE)i;
    return g;
}

static void guid_text(const GUID *g, WCHAR *out)
{
    swprintf(out, 40, L"{%08lX-%04X-%04X-%02X%02X-%02X%02X%02X%02X%02X%02X}", (unsigned long)g->Data1, g->Data2,
             g->Data3, g->Data4[0], g->Data4[1], g->Data4[2], g->Data4[3], g->Data4[4], g->Data4[5], g->Data4[6],
             g->Data4[7]);
}

static void set_default(const WCHAR *path, const WCHAR *text)
{
    HKEY k;
    if (RegCreateKeyExW(HKEY_CLASSES_ROOT, path, 0, NULL, 0, KEY_WRITE, NULL, &k, NULL) != ERROR_SUCCESS) {
        fwprintf(stderr, L"cannot create %ls\n", path);
        exit(2);
    }
    RegSetValueExW(k, L"", 0, REG_SZ, (const BYTE *)text, (DWORD)((wcslen(text) + 1) * sizeof(WCHAR)));
    RegCloseKey(k);
}

static void registration(int add)
{
    WCHAR path[128], clsid[40];
    for (unsigned i = 0; i < SERVERS; i++) {
        GUID g = bench_clsid(i);
        guid_text(&g, clsid);
        swprintf(path, 128, L"OpcBench.Da10Server%u.1", i);
        if (add) {
            WCHAR sub[160];
            swprintf(sub, 160, L"%ls\\OPC\\Vendor", path);
            set_default(sub, L"Benchmark vendor");
            swprintf(sub, 160, L"%ls\\CLSID", path);
            set_default(sub, clsid);
            swprintf(sub, 160, L"CLSID\\%ls", clsid);
            set_default(sub, L"Benchmark DA 1.0 server");
        } else {
            RegDeleteTreeW(HKEY_CLASSES_ROOT, path);
            WCHAR sub[160];
            swprintf(sub, 160, L"CLSID\\%ls", clsid);
            RegDeleteTreeW(HKEY_CLASSES_ROOT, sub);
        }
    }
    for (unsigned i = 0; i < UNRELATED; i++) {
        swprintf(path, 128, L"OpcBench.Unrelated%u", i);
        if (add) {
            GUID g = bench_clsid(0x100000u + i);
            WCHAR sub[160];
            guid_text(&g, clsid);
            set_default(path, L"Unrelated component");
            swprintf(sub, 160, L"%ls\\CLSID", path);
            set_default(sub, clsid);
        } else {
            RegDeleteTreeW(HKEY_CLASSES_ROOT, path);
        }
    }
}

/* ---- The ordinary browse: classes of a category ---- */

#define CLASSES 2000
static const GUID CATID_BENCH = {0xBE0C0000u, 0x0000, 0x4000, {0x80, 0x00, 0x00, 0x00, 0x00, 0x00, 0xCA, 0x70}};

static void class_registration(int add)
{
    WCHAR key[128], sub[200], clsid[40], catid[40], text[64];
    guid_text(&CATID_BENCH, catid);
    for (unsigned i = 0; i < CLASSES; i++) {
        GUID g = bench_clsid(0x200000u + i);
        guid_text(&g, clsid);
        swprintf(key, 128, L"CLSID\\%ls", clsid);
        if (!add) {
            RegDeleteTreeW(HKEY_CLASSES_ROOT, key);
            continue;
        }
        swprintf(text, 64, L"Bench Server %u", i);
        set_default(key, text);
        swprintf(sub, 200, L"%ls\\ProgID", key);
        swprintf(text, 64, L"Bench.Server%u.1", i);
        set_default(sub, text);
        swprintf(sub, 200, L"%ls\\VersionIndependentProgID", key);
        swprintf(text, 64, L"Bench.Server%u", i);
        set_default(sub, text);
        swprintf(sub, 200, L"%ls\\Implemented Categories\\%ls", key, catid);
        set_default(sub, L"");
    }
}

static IOPCServerList2 *list2;
static ICatInformation *cats;
static int browsed;

static void run_server_list_browse(void *context, long reps)
{
    (void)context;
    for (long r = 0; r < reps; r++) {
        CATID cat = CATID_BENCH;
        IOPCEnumGUID *e = NULL;
        browsed = 0;
        if (list2->lpVtbl->EnumClassesOfCategories(list2, 1, &cat, 0, NULL, &e) != S_OK)
            exit(2);
        for (;;) {
            ULONG n = 0;
            GUID buf[256];
            HRESULT hr = e->lpVtbl->Next(e, 256, buf, &n);
            for (ULONG i = 0; i < n; i++) {
                LPOLESTR prog = NULL, user = NULL, vi = NULL;
                if (list2->lpVtbl->GetClassDetails(list2, &buf[i], &prog, &user, &vi) == S_OK)
                    browsed++;
                CoTaskMemFree(prog);
                CoTaskMemFree(user);
                CoTaskMemFree(vi);
            }
            if (hr != S_OK)
                break;
        }
        e->lpVtbl->Release(e);
    }
}

static void run_categories_manager(void *context, long reps)
{
    (void)context;
    for (long r = 0; r < reps; r++) {
        IEnumGUID *e = NULL;
        browsed = 0;
        if (cats->lpVtbl->EnumClassesOfCategories(cats, 1, &CATID_BENCH, (ULONG)-1, NULL, &e) != S_OK)
            exit(2);
        for (;;) {
            ULONG n = 0;
            GUID buf[256];
            HRESULT hr = e->lpVtbl->Next(e, 256, buf, &n);
            for (ULONG i = 0; i < n; i++) {
                LPOLESTR prog = NULL;
                if (ProgIDFromCLSID(&buf[i], &prog) == S_OK)
                    browsed++;
                CoTaskMemFree(prog);
            }
            if (hr != S_OK)
                break;
        }
        e->lpVtbl->Release(e);
    }
}

static void browse_case(void)
{
    class_registration(0);
    class_registration(1);
    void *p = NULL;
    if (OpcServerListCreate(NULL, &IID_IOPCServerList2, &p) != S_OK ||
        CoCreateInstance(&CLSID_StdComponentCategoriesMgr, NULL, CLSCTX_INPROC_SERVER, &IID_ICatInformation,
                         (void **)&cats) != S_OK) {
        fprintf(stderr, "cannot create the server list or the Component Categories Manager\n");
        exit(2);
    }
    list2 = p;
    run_server_list_browse(NULL, 1);
    int ours = browsed;
    run_categories_manager(NULL, 1);
    if (ours != CLASSES || browsed != CLASSES) {
        fprintf(stderr, "browse: server list found %d classes, the Component Categories Manager %d\n", ours,
                browsed);
        exit(2);
    }
    printf("\nBrowse: %d classes of one category, with their details\n", CLASSES);
    BenchContender c[2] = {
        {"ICatInformation + ProgIDFromCLSID", run_categories_manager, NULL, 1},
        {"EnumClassesOfCategories + GetClassDetails", run_server_list_browse, NULL, 1},
    };
    BenchResult r = bench_case(c, 2);
    char a[96], b[96];
    bench_format_time(a, sizeof a, &r, 0);
    bench_format_time(b, sizeof b, &r, 1);
    printf("time per browse, median of %d rounds (lowest-highest round): Component Categories Manager %s, server "
           "list %s\n",
           r.rounds, a, b);
    double lo, hi, ratio = bench_ratio(&r, 1, 0, &lo, &hi);
    /* For information, not a goal: the server list reads three strings per class where ProgIDFromCLSID
       reads one, in more registry calls. */
    printf("server list browse / ICatInformation + ProgIDFromCLSID: %.2fx (rounds %.2f-%.2f), for information\n",
           ratio, lo, hi);
    list2->lpVtbl->Release(list2);
    cats->lpVtbl->Release(cats);
    class_registration(0);
}

/* ---- The plain C walk ---- */

typedef struct {
    GUID found[MAX_FOUND];
    int count;
} Found;

static int guid_cmp(const void *a, const void *b)
{
    return memcmp(a, b, sizeof(GUID));
}

static void add(Found *f, const GUID *g)
{
    if (f->count < MAX_FOUND)
        f->found[f->count++] = *g;
}

/* Sorts and removes duplicates. */
static void finish(Found *f)
{
    qsort(f->found, (size_t)f->count, sizeof(GUID), guid_cmp);
    int n = 0;
    for (int i = 0; i < f->count; i++)
        if (n == 0 || memcmp(&f->found[n - 1], &f->found[i], sizeof(GUID)))
            f->found[n++] = f->found[i];
    f->count = n;
}

static void plain_walk(Found *f)
{
    /* The views the server list reads, in its order: the process's own (flag 0), then the other one
       (a 32-bit process's other view is the 64-bit one). */
    static const REGSAM views[2] = {0, sizeof(void *) == 8 ? KEY_WOW64_32KEY : KEY_WOW64_64KEY};
    WCHAR name[256], path[300], catid[40];
    guid_text(&CATID_OPCDAServer10, catid);
    f->count = 0;
    for (int v = 0; v < 2; v++) {
        /* Classes with the DA 1.0 category. */
        HKEY classes;
        if (RegOpenKeyExW(HKEY_CLASSES_ROOT, L"CLSID", 0, KEY_READ | views[v], &classes) == ERROR_SUCCESS) {
            for (DWORD i = 0;; i++) {
                DWORD len = 256;
                if (RegEnumKeyExW(classes, i, name, &len, NULL, NULL, NULL, NULL) != ERROR_SUCCESS)
                    break;
                HKEY k;
                swprintf(path, 300, L"%ls\\Implemented Categories\\%ls", name, catid);
                if (RegOpenKeyExW(classes, path, 0, KEY_READ | views[v], &k) == ERROR_SUCCESS) {
                    GUID g;
                    RegCloseKey(k);
                    if (CLSIDFromString(name, &g) == S_OK)
                        add(f, &g);
                }
            }
            RegCloseKey(classes);
        }
        /* ProgIDs with an OPC subkey. */
        HKEY root;
        if (RegOpenKeyExW(HKEY_CLASSES_ROOT, L"", 0, KEY_READ | views[v], &root) != ERROR_SUCCESS)
            continue;
        for (DWORD i = 0;; i++) {
            DWORD len = 256;
            if (RegEnumKeyExW(root, i, name, &len, NULL, NULL, NULL, NULL) != ERROR_SUCCESS)
                break;
            if (name[0] == L'.' || !_wcsicmp(name, L"CLSID"))
                continue;
            HKEY k;
            swprintf(path, 300, L"%ls\\OPC", name);
            if (RegOpenKeyExW(HKEY_CLASSES_ROOT, path, 0, KEY_READ | views[v], &k) != ERROR_SUCCESS)
                continue;
            RegCloseKey(k);
            WCHAR clsid[64];
            swprintf(path, 300, L"%ls\\CLSID", name);
            if (RegOpenKeyExW(HKEY_CLASSES_ROOT, path, 0, KEY_READ | views[v], &k) != ERROR_SUCCESS)
                continue;
            DWORD type, bytes = sizeof clsid;
            LONG e = RegQueryValueExW(k, L"", NULL, &type, (BYTE *)clsid, &bytes);
            RegCloseKey(k);
            GUID g;
            if (e != ERROR_SUCCESS || type != REG_SZ || CLSIDFromString(clsid, &g) != S_OK)
                continue;
            /* The class must be registered (in either view). */
            swprintf(path, 300, L"CLSID\\%ls", clsid);
            for (int w = 0; w < 2; w++) {
                if (RegOpenKeyExW(HKEY_CLASSES_ROOT, path, 0, KEY_READ | views[w], &k) == ERROR_SUCCESS) {
                    RegCloseKey(k);
                    add(f, &g);
                    break;
                }
            }
        }
        RegCloseKey(root);
    }
    finish(f);
}

/* ---- The server list ---- */

static void library_walk(IOPCServerList *list, Found *f)
{
    CATID cat = CATID_OPCDAServer10;
    IEnumGUID *e = NULL;
    f->count = 0;
    if (list->lpVtbl->EnumClassesOfCategories(list, 1, &cat, 0, NULL, &e) != S_OK) {
        fprintf(stderr, "EnumClassesOfCategories failed\n");
        exit(2);
    }
    for (;;) {
        ULONG n = 0;
        GUID buf[256];
        HRESULT hr = e->lpVtbl->Next(e, 256, buf, &n);
        for (ULONG i = 0; i < n; i++)
            add(f, &buf[i]);
        if (hr != S_OK)
            break;
    }
    e->lpVtbl->Release(e);
}

static Found plain_found, library_found;
static IOPCServerList *list;

static void run_plain(void *context, long reps)
{
    (void)context;
    for (long r = 0; r < reps; r++)
        plain_walk(&plain_found);
}

static void run_library(void *context, long reps)
{
    (void)context;
    for (long r = 0; r < reps; r++)
        library_walk(list, &library_found);
}

/* The DA 1.0 scan case. */
static void da10_case(void)
{
    registration(0);
    registration(1);
    void *p = NULL;
    if (OpcServerListCreate(NULL, &IID_IOPCServerList, &p) != S_OK) {
        fprintf(stderr, "OpcServerListCreate failed\n");
        exit(2);
    }
    list = p;
    plain_walk(&plain_found);
    library_walk(list, &library_found);
    finish(&library_found);
    int same = plain_found.count == library_found.count &&
               !memcmp(plain_found.found, library_found.found, (size_t)plain_found.count * sizeof(GUID));
    if (!same || plain_found.count < SERVERS) {
        fprintf(stderr, "the walks disagree: plain %d classes, server list %d\n", plain_found.count,
                library_found.count);
        exit(2);
    }
    printf("Data Access 1.0 scan: %d servers registered the old way among %d unrelated ProgIDs (%d classes found)\n",
           SERVERS, UNRELATED, plain_found.count);
    BenchContender c[2] = {
        {"plain C walk", run_plain, NULL, 1},
        {"EnumClassesOfCategories", run_library, NULL, 1},
    };
    BenchResult r = bench_case(c, 2);
    char a[96], b[96];
    bench_format_time(a, sizeof a, &r, 0);
    bench_format_time(b, sizeof b, &r, 1);
    printf("time per scan, median of %d rounds (lowest-highest round): plain C walk %s, server list %s\n", r.rounds,
           a, b);
    double lo, hi, ratio = bench_ratio(&r, 1, 0, &lo, &hi);
    bench_goal("server list DA 1.0 scan / plain C registry walk", ratio, lo, hi, 0, 1.2, "x");
    list->lpVtbl->Release(list);
    registration(0);
}

/* `bench_server_list da10` or `bench_server_list browse` runs one case. */
int main(int argc, char **argv)
{
    /* A round is one whole scan (seconds under Wine, all of it registry calls into wineserver, timed by
       the wall clock): 15 rounds keep one slow round from moving the median. A scan is some 100,000
       round trips to wineserver (in a 64-bit process more: Wine opens a path in the 32-bit view a key at
       a time, asking for each key's Wow6432Node), and on a loaded machine every round trip waits for the
       scheduler, so a scan can take a minute there: after 4 minutes a case ends its rounds (at 5 at the
       least; BENCH_BUDGET_S) and says so, rather than run for an hour. */
    bench_rounds = 15;
    bench_budget_s = 240;
    bench_init();
    CoInitializeEx(NULL, COINIT_APARTMENTTHREADED);
    const char *only = argc > 1 ? argv[1] : NULL;
    if (!only || !strcmp(only, "da10"))
        da10_case();
    if (!only || !strcmp(only, "browse"))
        browse_case();
    CoUninitialize();
    return bench_finish("bench_server_list");
}
#endif
