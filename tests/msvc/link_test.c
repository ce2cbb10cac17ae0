/* A Visual Studio-style program: compiled in MSVC mode (clang --target=<arch>-pc-windows-msvc), linked
 * by lld-link against opccomn.lib (the MSVC-format import library) and a kernel32 import library, with
 * no C runtime at all (its own entry point). It declares what it uses itself, the way MIDL-generated
 * headers and the Windows SDK declare them, because mingw's headers do not compile in MSVC mode:
 * - functions with the calling convention opccomn.h states (cdecl for the library's own functions,
 *   OpcDllGetClassObject included: opccomn.lib keeps the standard Dll* exports PRIVATE, so a server
 *   with its own .def binds its own DllGetClassObject, never opccomn's);
 * - IID_IOPCCommon as MIDL's opccomn_i.c users declare it (`EXTERN_C const IID`, no dllimport): it
 *   links from an ordinary member of opccomn.lib;
 * - IID_IOPCShutdown declared __declspec(dllimport): it links through the import, from the DLL.
 * Run under Wine; prints "msvc link test: N passed, M failed" and exits with the number of failures. */

typedef long HRESULT;
typedef unsigned long ULONG;
typedef unsigned long DWORD;
typedef DWORD LCID;
typedef int BOOL;
typedef unsigned short WCHAR;
typedef void *HANDLE;
typedef struct GUID {
    unsigned long Data1;
    unsigned short Data2, Data3;
    unsigned char Data4[8];
} GUID;
typedef GUID IID;
typedef GUID CLSID;

#define WINAPI __stdcall
#define STDMETHODCALLTYPE __stdcall
#define S_OK ((HRESULT)0)
#define E_INVALIDARG ((HRESULT)0x80070057L)
#define CLASS_E_CLASSNOTAVAILABLE ((HRESULT)0x80040111L)

__declspec(dllimport) HANDLE WINAPI GetStdHandle(DWORD which);
__declspec(dllimport) BOOL WINAPI WriteFile(HANDLE file, const void *data, DWORD size, DWORD *written, void *overlapped);
__declspec(dllimport) void WINAPI ExitProcess(unsigned int code);

/* opccomn.h, as a Visual Studio user gets it. */
typedef struct IOPCCommon IOPCCommon;
typedef struct IOPCCommonVtbl {
    HRESULT(STDMETHODCALLTYPE *QueryInterface)(IOPCCommon *This, const IID *riid, void **ppv);
    ULONG(STDMETHODCALLTYPE *AddRef)(IOPCCommon *This);
    ULONG(STDMETHODCALLTYPE *Release)(IOPCCommon *This);
    HRESULT(STDMETHODCALLTYPE *SetLocaleID)(IOPCCommon *This, LCID lcid);
    HRESULT(STDMETHODCALLTYPE *GetLocaleID)(IOPCCommon *This, LCID *lcid);
    HRESULT(STDMETHODCALLTYPE *QueryAvailableLocaleIDs)(IOPCCommon *This, DWORD *count, LCID **lcids);
    HRESULT(STDMETHODCALLTYPE *GetErrorString)(IOPCCommon *This, HRESULT code, WCHAR **text);
    HRESULT(STDMETHODCALLTYPE *SetClientName)(IOPCCommon *This, const WCHAR *name);
} IOPCCommonVtbl;
struct IOPCCommon {
    const IOPCCommonVtbl *lpVtbl;
};

extern const IID IID_IOPCCommon;                       /* MIDL style: an archive member of opccomn.lib */
__declspec(dllimport) extern const IID IID_IOPCShutdown; /* through the import */
BOOL __cdecl MatchPatternW(const WCHAR *string, const WCHAR *pattern, BOOL case_sensitive);
HRESULT __cdecl OpcGetErrorString(HRESULT code, LCID locale, WCHAR **text);
HRESULT __cdecl OpcCommonCreate(const void *options, void *outer, const IID *riid, void **ppv);
void __cdecl OpcTaskMemFree(void *p);
HRESULT __cdecl OpcDllGetClassObject(const CLSID *clsid, const IID *riid, void **ppv);
HRESULT __cdecl OpcDllCanUnloadNow(void);

static int passed, failed;
static HANDLE out;

static void print(const char *s) {
    DWORD n = 0, written;
    while (s[n]) n++;
    WriteFile(out, s, n, &written, 0);
}

static void print_number(unsigned long v) {
    char buf[12];
    int i = 11;
    buf[i] = 0;
    do {
        buf[--i] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    print(buf + i);
}

static void check(int ok, const char *what) {
    if (ok) {
        passed++;
    } else {
        failed++;
        print("CHECK failed: ");
        print(what);
        print("\n");
    }
}

static int same_guid(const GUID *a, const GUID *b) {
    const unsigned char *x = (const unsigned char *)a, *y = (const unsigned char *)b;
    int i;
    for (i = 0; i < 16; i++)
        if (x[i] != y[i]) return 0;
    return 1;
}

static int starts_with(const WCHAR *s, const char *prefix) {
    if (!s) return 0;
    for (; *prefix; prefix++, s++)
        if (*s != (WCHAR)*prefix) return 0;
    return 1;
}

void __cdecl entry(void) {
    static const WCHAR tag[] = {'T', 'a', 'g', '7', 0}, pattern[] = {'T', 'a', 'g', '#', 0};
    static const WCHAR tagx[] = {'T', 'a', 'g', 'X', 0}, client[] = {'M', 'S', 'V', 'C', 0};
    static const IID opccommon = {0xF31DFDE2, 0x07B6, 0x11D2, {0xB2, 0xD8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
    static const IID shutdown = {0xF31DFDE1, 0x07B6, 0x11D2, {0xB2, 0xD8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB}};
    static const CLSID bogus = {0x01234567, 0x89AB, 0xCDEF, {1, 2, 3, 4, 5, 6, 7, 8}};
    IOPCCommon *common = 0, *again = 0;
    WCHAR *text = 0;
    void *factory = (void *)1;
    LCID lcid = 0;
    int i;

    out = GetStdHandle((DWORD)-11); /* STD_OUTPUT_HANDLE */
    check(same_guid(&IID_IOPCCommon, &opccommon), "IID_IOPCCommon (archive member) has its value");
    check(same_guid(&IID_IOPCShutdown, &shutdown), "IID_IOPCShutdown (dllimport) has its value");
    check(MatchPatternW(tag, pattern, 1) == 1 && MatchPatternW(tagx, pattern, 1) == 0, "MatchPatternW");
    check(OpcGetErrorString((HRESULT)0xC0040007L, 0x0409, &text) == S_OK && starts_with(text, "The item ID"),
          "OpcGetErrorString");
    OpcTaskMemFree(text);
    check(OpcCommonCreate(0, 0, &IID_IOPCCommon, (void **)&common) == S_OK && common, "OpcCommonCreate");
    if (common) {
        /* Many __stdcall vtable calls: a wrong convention would move the stack and crash. */
        for (i = 0; i < 10000; i++) common->lpVtbl->SetLocaleID(common, (i & 1) ? 0x0407 : 0x0409);
        check(common->lpVtbl->GetLocaleID(common, &lcid) == S_OK && lcid == 0x0407, "GetLocaleID");
        check(common->lpVtbl->SetClientName(common, client) == S_OK, "SetClientName");
        check(common->lpVtbl->SetClientName(common, 0) == E_INVALIDARG, "SetClientName(NULL)");
        text = 0;
        check(common->lpVtbl->GetErrorString(common, (HRESULT)0xC0040007L, &text) == S_OK &&
                  starts_with(text, "Die Element-ID"),
              "GetErrorString (German session)");
        OpcTaskMemFree(text);
        check(common->lpVtbl->QueryInterface(common, &IID_IOPCCommon, (void **)&again) == S_OK && again == common,
              "QueryInterface(IID_IOPCCommon)");
        if (again) again->lpVtbl->Release(again);
        check(common->lpVtbl->Release(common) == 0, "Release");
    }
    check(OpcDllGetClassObject(&bogus, &IID_IOPCCommon, &factory) == CLASS_E_CLASSNOTAVAILABLE && factory == 0,
          "OpcDllGetClassObject of an unknown class");
    check(OpcDllCanUnloadNow() == S_OK, "OpcDllCanUnloadNow");

    print("msvc link test (");
    print_number((unsigned long)(sizeof(void *) * 8));
    print("-bit): ");
    print_number((unsigned long)passed);
    print(" passed, ");
    print_number((unsigned long)failed);
    print(" failed\n");
    ExitProcess((unsigned int)failed);
}
