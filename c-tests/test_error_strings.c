/* GetErrorString as servers and clients use it: OpcGetErrorString / OpcGetErrorStringEx and
   IOPCCommon::GetErrorString through the vtable, against the published texts (published_error_texts.h),
   German texts, the Data Access / Alarms & Events collision, locale resolution, the vendor callback,
   unknown codes and NULL out-pointers. On Windows also the DLL's own message table through
   FormatMessage and its version resource through GetFileVersionInfo. */
#if !defined(_WIN32)
#define _POSIX_C_SOURCE 200809L /* setenv, unsetenv */
#endif
#include "test_util.h"
#include "published_error_texts.h"

#if defined(_WIN32)
#include <winver.h>
#endif

/* CHECK with a printf-style explanation of what was seen. */
#define CHECKF(cond, ...)                                                                                     \
    do {                                                                                                      \
        if (cond) {                                                                                           \
            test_passed++;                                                                                    \
        } else {                                                                                              \
            test_failed++;                                                                                    \
            fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond);                          \
            fprintf(stderr, __VA_ARGS__);                                                                     \
            fputc('\n', stderr);                                                                              \
        }                                                                                                     \
    } while (0)

/* Whether `w` equals the UTF-8 `expected` (NULL never does). */
static int same(const WCHAR *w, const char *expected)
{
    return w != NULL && wstr_is(w, expected);
}

/* For messages: `w` with non-ASCII shown as '?' (static buffer). */
static const char *show(const WCHAR *w)
{
    static char buf[512];
    size_t i = 0;
    if (!w)
        return "(null)";
    for (; w[i] && i < sizeof buf - 1; i++)
        buf[i] = w[i] < 0x80 ? (char)w[i] : '?';
    buf[i] = 0;
    return buf;
}

/* OpcGetErrorStringEx with a garbage-filled out-pointer; the result is owned by the caller. */
static HRESULT get(uint32_t code, LCID lcid, uint32_t kind, LPWSTR *text)
{
    *text = (LPWSTR)GARBAGE_PTR;
    return OpcGetErrorStringEx((HRESULT)code, lcid, kind, text);
}

/* Asks with OpcGetErrorStringEx and checks the text; frees it. */
static void expect(uint32_t code, LCID lcid, uint32_t kind, const char *text, const char *what)
{
    LPWSTR s;
    HRESULT hr = get(code, lcid, kind, &s);
    CHECKF(hr == S_OK && same(s, text), "%s %08X lcid %04X kind %u: hr %08X, got \"%s\", want \"%s\"", what,
          (unsigned)code, (unsigned)lcid, (unsigned)kind, (unsigned)hr, show(s), text);
    if (hr == S_OK)
        OpcTaskMemFree(s);
}

static void test_every_published_english_text(void)
{
    for (size_t i = 0; i < PUBLISHED_TEXT_COUNT; i++) {
        const struct published_text *p = &PUBLISHED_TEXTS[i];
        expect(p->code, 0x0409, p->kind, p->text, p->symbol);
        expect(p->code, LOCALE_NEUTRAL, p->kind, p->text, p->symbol);
        /* The plain function answers as a Data Access server: the same text except where codes collide. */
        if (!(p->kind == K_AE && p->code == 0xC0040203u)) {
            LPWSTR s = (LPWSTR)(uintptr_t)1;
            HRESULT hr = OpcGetErrorString((HRESULT)p->code, 0x0409, &s);
            CHECKF(hr == S_OK && same(s, p->text), "%s via OpcGetErrorString: \"%s\"", p->symbol, show(s));
            if (hr == S_OK)
                OpcTaskMemFree(s);
        }
    }
}

/* The published entry of `code` for a server of `kind`, or NULL. */
static const struct published_text *published(uint32_t code, uint32_t kind)
{
    for (size_t i = 0; i < PUBLISHED_TEXT_COUNT; i++)
        if (PUBLISHED_TEXTS[i].code == code && PUBLISHED_TEXTS[i].kind == kind)
            return &PUBLISHED_TEXTS[i];
    return NULL;
}

/* OpcErrorCodesOfKind lists exactly the codes of each kind's own header, each once, with the symbol and
   text the published list has; the AE and HDA lists are every published entry of their kind. */
static void test_codes_of_each_kind(void)
{
    static const struct { uint32_t kind; DWORD count; } kinds[] = {{K_DA, 28}, {K_AE, 8}, {K_HDA, 15}, {K_BATCH, 1}};
    for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
        DWORD count = GARBAGE_U32;
        HRESULT *codes = (HRESULT *)GARBAGE_PTR;
        CHECK_HR(OpcErrorCodesOfKind(kinds[k].kind, &count, &codes), S_OK);
        CHECKF(count == kinds[k].count, "kind %u: %u codes", (unsigned)kinds[k].kind, (unsigned)count);
        for (DWORD i = 0; i < count; i++) {
            uint32_t code = (uint32_t)codes[i];
            const struct published_text *p = published(code, kinds[k].kind);
            CHECKF(p != NULL, "kind %u: %08X is not a published code of the kind", (unsigned)kinds[k].kind, (unsigned)code);
            CHECKF(i == 0 || (uint32_t)codes[i - 1] < code, "kind %u: not ascending at %08X", (unsigned)kinds[k].kind, (unsigned)code);
            LPWSTR symbol = (LPWSTR)GARBAGE_PTR;
            HRESULT hr = OpcErrorSymbol((HRESULT)code, kinds[k].kind, &symbol);
            CHECKF(hr == S_OK && p && same(symbol, p->symbol), "%08X: symbol \"%s\"", (unsigned)code, show(symbol));
            if (hr == S_OK)
                OpcTaskMemFree(symbol);
            if (p)
                expect(code, 0x0409, kinds[k].kind, p->text, p->symbol);
        }
        if (kinds[k].kind == K_AE || kinds[k].kind == K_HDA) {
            size_t listed = 0;
            for (size_t i = 0; i < PUBLISHED_TEXT_COUNT; i++)
                listed += PUBLISHED_TEXTS[i].kind == kinds[k].kind;
            CHECKF(listed == count, "kind %u: %u published, %u listed", (unsigned)kinds[k].kind, (unsigned)listed, (unsigned)count);
        }
        if (count)
            OpcTaskMemFree(codes);
    }
    DWORD count = GARBAGE_U32;
    HRESULT *codes = (HRESULT *)GARBAGE_PTR;
    CHECK_HR(OpcErrorCodesOfKind(77, &count, &codes), E_INVALIDARG);
    CHECK(count == 0 && codes == NULL);
    LPWSTR symbol = (LPWSTR)GARBAGE_PTR;
    CHECK_HR(OpcErrorSymbol((HRESULT)0x12345678, K_DA, &symbol), E_INVALIDARG);
    CHECK(symbol == NULL);
}

static void test_german_texts(void)
{
    expect(0xC0040007u, 0x0407, K_DA,
           "Die Element-ID ist im Adressraum des Servers nicht definiert oder existiert dort nicht mehr.", "de");
    expect(0xC004000Au, 0x0407, K_DA, "Der Zugriffspfad des Elements ist dem Server nicht bekannt.", "de");
    expect(0xC0040401u, 0x0407, K_DA, "Das Element unterstützt kein Totband.", "de");
    expect(0xC0040005u, 0x0407, K_DA,
           "Die angeforderte Operation kann nicht auf eine öffentliche Gruppe angewendet werden.", "de");
    expect(0x00040200u, 0x0407, K_AE, "Die Bedingung wurde bereits quittiert.", "de");
    expect(0x40041002u, 0x0407, K_HDA, "Innerhalb der angegebenen Parameter liegen keine Daten vor.", "de");
    expect(0xC0040711u, 0x0407, K_DX,
           "Der Überschreibwert liegt außerhalb des Wertebereichs des Zielelements, und das Überschreiben-Flag ist "
           "gesetzt.",
           "de");
    expect(0xC0040903u, 0x0407, K_CMD, "Der Server kann diesen Befehl derzeit nicht verarbeiten.", "de");
    expect(0x80040202u, 0x0407, K_DA, "Die Verbindung kann nicht hergestellt werden.", "de");
    /* Any German locale gets German; a sublanguage is not needed. */
    expect(0xC0040401u, 0x0C07, K_DA, "Das Element unterstützt kein Totband.", "de-AT");
    expect(0xC0040401u, 0x0807, K_DA, "Das Element unterstützt kein Totband.", "de-CH");
}

static void test_languages_without_texts_fall_back_to_english(void)
{
    expect(0xC0040401u, 0x040C, K_DA, "The item does not support deadband.", "fr-FR");
    expect(0xC0040401u, 0x0411, K_DA, "The item does not support deadband.", "ja-JP");
    expect(0xC0040401u, 0x0809, K_DA, "The item does not support deadband.", "en-GB");
    expect(0xC0040401u, LOCALE_INVARIANT, K_DA, "The item does not support deadband.", "invariant");
}

static void test_collision_both_ways(void)
{
    expect(0xC0040203u, 0x0409, K_DA, "The specified property ID is not valid for the item.", "DA");
    expect(0xC0040203u, 0x0409, K_AE, "The string was not recognized as an area name.", "AE");
    expect(0xC0040203u, 0x0407, K_DA, "Die angegebene Eigenschafts-ID ist für das Element nicht gültig.", "DA de");
    expect(0xC0040203u, 0x0407, K_AE, "Die Zeichenfolge wurde nicht als Bereichsname erkannt.", "AE de");
    /* Kinds without a text of their own get the Data Access one. */
    expect(0xC0040203u, 0x0409, K_HDA, "The specified property ID is not valid for the item.", "HDA");
    /* AE codes that collide with nothing are answered for every kind. */
    expect(0x00040203u, 0x0409, K_DA, "The KeepAliveTime parameter was invalid.", "DA asks AE code");
}

/* The language LOCALE_SYSTEM_DEFAULT / LOCALE_USER_DEFAULT must resolve to. On Linux main() sets
   LC_MESSAGES to German before the first call; on Windows it is the system's. */
static LCID expected_default(LCID special)
{
#if defined(_WIN32)
    return special == LOCALE_SYSTEM_DEFAULT ? GetSystemDefaultLCID() : GetUserDefaultLCID();
#else
    (void)special;
    return 0x0407;
#endif
}

static void test_default_locales_resolve(void)
{
    LCID specials[2] = {LOCALE_SYSTEM_DEFAULT, LOCALE_USER_DEFAULT};
    for (int i = 0; i < 2; i++) {
        LPWSTR a, b;
        HRESULT ha = get(0xC0040006u, specials[i], K_DA, &a);
        HRESULT hb = get(0xC0040006u, expected_default(specials[i]), K_DA, &b);
        CHECKF(ha == S_OK && hb == S_OK && wlen(a) == wlen(b) && memcmp(a, b, wlen(a) * sizeof(WCHAR)) == 0,
              "%04X: \"%s\"", (unsigned)specials[i], show(a));
        if (ha == S_OK)
            OpcTaskMemFree(a);
        if (hb == S_OK)
            OpcTaskMemFree(b);
    }
#if !defined(_WIN32)
    expect(0xC0040006u, LOCALE_SYSTEM_DEFAULT, K_DA, "Die Zugriffsrechte des Elements erlauben die Operation nicht.",
           "LC_MESSAGES=de_DE.UTF-8");
#endif
    expect(0xC0040006u, LOCALE_NEUTRAL, K_DA, "The item's access rights do not allow the operation.", "neutral");
}

static void test_unknown_codes_and_null_pointers(void)
{
    uint32_t unknown[] = {0xC004FFFFu, 0x0004FFF0u, 0xC0040002u, 0xE0001234u};
    for (size_t i = 0; i < sizeof unknown / sizeof unknown[0]; i++) {
        LPWSTR s;
        HRESULT hr = get(unknown[i], 0x0409, K_DA, &s);
        CHECKF(hr == E_INVALIDARG && s == NULL, "%08X: hr %08X", (unsigned)unknown[i], (unsigned)hr);
    }
    LPWSTR s;
    HRESULT hr = get(0xC0040001u, 0x0409, 6, &s);
    CHECKF(hr == E_INVALIDARG && s == NULL, "unknown kind: hr %08X", (unsigned)hr);
    CHECKF(OpcGetErrorString((HRESULT)0xC0040001u, 0x0409, NULL) == E_INVALIDARG, "NULL out-pointer");
    CHECKF(OpcGetErrorStringEx((HRESULT)0xC0040001u, 0x0409, K_AE, NULL) == E_INVALIDARG, "NULL out-pointer (Ex)");
}

static void test_com_codes(void)
{
    /* Connection point codes come from the catalog everywhere (the system's texts for these values are
       unrelated ones). */
    expect(0x80040200u, 0x0409, K_DA, "No connection for this connection ID", "CONNECT_E_NOCONNECTION");
    expect(0x80040201u, 0x0409, K_DA, "Limit on the number of connections has been reached", "CONNECT_E_ADVISELIMIT");
    expect(0x80040202u, 0x0409, K_AE, "Cannot connect", "CONNECT_E_CANNOTCONNECT");
#if defined(_WIN32)
    /* The system's text, without the trailing line break. */
    uint32_t codes[] = {0x80070057u, 0x80004002u, 0x80070005u, 0x800706BAu};
    for (size_t i = 0; i < 2 * sizeof codes / sizeof codes[0]; i++) {
        LPWSTR s;
        HRESULT hr = get(codes[i / 2], i % 2 ? 0x0407 : 0x0409, K_DA, &s);
        size_t n = hr == S_OK ? wlen(s) : 0;
        CHECKF(hr == S_OK && n > 0 && s[n - 1] != '\n' && s[n - 1] != '\r', "%08X: \"%s\"", (unsigned)codes[i / 2],
              show(hr == S_OK ? s : NULL));
        if (hr == S_OK)
            OpcTaskMemFree(s);
    }
#else
    /* No system to ask: the library carries Windows' English texts, and German ones. */
    for (size_t i = 0; i < WINDOWS_TEXT_COUNT; i++)
        expect(WINDOWS_TEXTS[i].code, 0x0409, K_DA, WINDOWS_TEXTS[i].text, WINDOWS_TEXTS[i].symbol);
    expect(0x80070057u, 0x0407, K_DA, "Falscher Parameter.", "E_INVALIDARG de");
    expect(0x800706BAu, 0x0407, K_DA, "Der RPC-Server ist nicht verfügbar.", "RPC_S_SERVER_UNAVAILABLE de");
#endif
}

/* The vendor callback: answers 0xE0040001, declines everything else; records the locale it was given. */
static LCID vendor_seen_locale;
static int vendor_calls;

static HRESULT vendor_text(void *context, HRESULT code, LCID locale, LPCWSTR *text)
{
    static WCHAR answer[] = {'P', 'u', 'm', 'p', 'e', ' ', 0x00FC, 'b', 'e', 'r', 'h', 'i', 't', 'z', 't', 0};
    CHECKF(context == (void *)&vendor_calls, "context passed through");
    vendor_calls++;
    vendor_seen_locale = locale;
    if ((uint32_t)code == 0xE0040001u) {
        *text = answer;
        return S_OK;
    }
    return S_FALSE;
}

static IOPCCommon *create_common(uint32_t kind, int with_vendor)
{
    struct OpcCommonOptions options;
    memset(&options, 0, sizeof options);
    options.struct_size = sizeof options;
    options.server_kind = kind;
    if (with_vendor) {
        options.vendor_error_string = vendor_text;
        options.vendor_error_context = &vendor_calls;
    }
    void *p = NULL;
    HRESULT hr = OpcCommonCreate(&options, NULL, &IID_IOPCCommon, &p);
    CHECKF(hr == S_OK && p != NULL, "OpcCommonCreate: %08X", (unsigned)hr);
    return (IOPCCommon *)p;
}

/* IOPCCommon::GetErrorString with a garbage-filled out-pointer; checks the text (NULL: expects failure). */
static void expect_common(IOPCCommon *common, uint32_t code, const char *text, const char *what)
{
    LPWSTR s = (LPWSTR)GARBAGE_PTR;
    HRESULT hr = common->lpVtbl->GetErrorString(common, (HRESULT)code, &s);
    if (text) {
        CHECKF(hr == S_OK && same(s, text), "%s %08X: hr %08X \"%s\"", what, (unsigned)code, (unsigned)hr,
              show(hr == S_OK ? s : NULL));
        if (hr == S_OK)
            OpcTaskMemFree(s);
    } else {
        CHECKF(hr == E_INVALIDARG && s == NULL, "%s %08X: hr %08X", what, (unsigned)code, (unsigned)hr);
    }
}

static void test_iopccommon(void)
{
    IOPCCommon *da = create_common(K_DA, 0);
    IOPCCommon *ae = create_common(K_AE, 0);
    if (!da || !ae)
        return;
    CHECKF(da->lpVtbl->SetLocaleID(da, 0x0409) == S_OK, "SetLocaleID en-US");
    CHECKF(ae->lpVtbl->SetLocaleID(ae, 0x0409) == S_OK, "SetLocaleID en-US");
    expect_common(da, 0xC0040203u, "The specified property ID is not valid for the item.", "DA session");
    expect_common(ae, 0xC0040203u, "The string was not recognized as an area name.", "AE session");
    CHECKF(ae->lpVtbl->SetLocaleID(ae, 0x0407) == S_OK, "SetLocaleID de-DE is available by default");
    expect_common(ae, 0xC0040203u, "Die Zeichenfolge wurde nicht als Bereichsname erkannt.", "AE session de");
    CHECKF(ae->lpVtbl->SetLocaleID(ae, LOCALE_INVARIANT) == S_OK, "SetLocaleID invariant");
    expect_common(ae, 0xC0040205u, "A refresh is currently in progress.", "AE session invariant");
    expect_common(da, 0xC004FFFFu, NULL, "unknown code");
    CHECKF(da->lpVtbl->GetErrorString(da, (HRESULT)0xC0040001u, NULL) == E_INVALIDARG, "NULL out-pointer");

    DWORD count = 0;
    LCID *lcids = NULL;
    CHECKF(da->lpVtbl->QueryAvailableLocaleIDs(da, &count, &lcids) == S_OK, "QueryAvailableLocaleIDs");
    int en = 0, de = 0;
    for (DWORD i = 0; i < count; i++) {
        en |= lcids[i] == 0x0409;
        de |= lcids[i] == 0x0407;
    }
    CHECKF(en && de, "en-US and de-DE available by default");
    OpcTaskMemFree(lcids);
    da->lpVtbl->Release(da);
    ae->lpVtbl->Release(ae);
}

static void test_vendor_callback(void)
{
    IOPCCommon *common = create_common(K_DA, 1);
    if (!common)
        return;
    /* Answered, with the session's default locale resolved to a concrete one. */
    vendor_calls = 0;
    expect_common(common, 0xE0040001u, "Pumpe überhitzt", "vendor code");
    CHECKF(vendor_calls == 1, "asked once: %d", vendor_calls);
    CHECKF(vendor_seen_locale == expected_default(LOCALE_SYSTEM_DEFAULT), "resolved locale %04X",
          (unsigned)vendor_seen_locale);
    CHECKF(common->lpVtbl->SetLocaleID(common, 0x0407) == S_OK, "SetLocaleID de-DE");
    expect_common(common, 0xE0040001u, "Pumpe überhitzt", "vendor code");
    CHECKF(vendor_seen_locale == 0x0407, "locale %04X", (unsigned)vendor_seen_locale);
    CHECKF(common->lpVtbl->SetLocaleID(common, LOCALE_NEUTRAL) == S_OK, "SetLocaleID neutral");
    expect_common(common, 0xE0040001u, "Pumpe überhitzt", "vendor code");
    CHECKF(vendor_seen_locale == 0x0409, "neutral resolves to en-US: %04X", (unsigned)vendor_seen_locale);
    /* Declined: the catalog answers, or nobody does. */
    vendor_calls = 0;
    expect_common(common, 0xC0040001u, "The value of the handle is invalid.", "declined OPC code");
    CHECKF(vendor_calls == 1, "vendor asked first: %d", vendor_calls);
    expect_common(common, 0xE0040002u, NULL, "declined unknown code");
    common->lpVtbl->Release(common);
}

#if defined(_WIN32)
static void test_dll_message_table(void)
{
    HMODULE dll = GetModuleHandleW(L"opccomn.dll");
    CHECKF(dll != NULL, "opccomn.dll loaded");
    if (!dll)
        return;
    WCHAR buf[1024];
    for (size_t i = 0; i < PUBLISHED_TEXT_COUNT; i++) {
        const struct published_text *p = &PUBLISHED_TEXTS[i];
        if (p->kind == K_AE && p->code == 0xC0040203u)
            continue; /* one message per code: the DLL carries the Data Access text */
        DWORD n = FormatMessageW(FORMAT_MESSAGE_FROM_HMODULE | FORMAT_MESSAGE_IGNORE_INSERTS, dll, p->code, 0x0409,
                                 buf, 1024, NULL);
        buf[n < 1024 ? n : 1023] = 0;
        CHECKF(n > 0 && same(buf, p->text), "FormatMessage %s: \"%s\" (error %lu)", p->symbol, show(buf),
              (unsigned long)GetLastError());
    }
    DWORD n = FormatMessageW(FORMAT_MESSAGE_FROM_HMODULE | FORMAT_MESSAGE_IGNORE_INSERTS, dll, 0xC0040401u, 0x0407,
                             buf, 1024, NULL);
    buf[n < 1024 ? n : 1023] = 0;
    CHECKF(n > 0 && same(buf, "Das Element unterstützt kein Totband."), "German message: \"%s\"", show(buf));
    n = FormatMessageW(FORMAT_MESSAGE_FROM_HMODULE | FORMAT_MESSAGE_IGNORE_INSERTS, dll, 0x80070057u, 0x0409, buf,
                       1024, NULL);
    CHECKF(n == 0, "system codes are not in the DLL's table");
}

static void test_dll_version_resource(void)
{
    HMODULE dll = GetModuleHandleW(L"opccomn.dll");
    WCHAR path[MAX_PATH];
    DWORD handle = 0;
    CHECKF(dll && GetModuleFileNameW(dll, path, MAX_PATH) > 0, "module path");
    DWORD size = GetFileVersionInfoSizeW(path, &handle);
    CHECKF(size > 0, "version resource present (error %lu)", (unsigned long)GetLastError());
    if (!size)
        return;
    void *info = malloc(size);
    CHECKF(GetFileVersionInfoW(path, 0, size, info), "GetFileVersionInfoW");
    VS_FIXEDFILEINFO *fixed = NULL;
    UINT len = 0;
    CHECKF(VerQueryValueW(info, L"\\", (void **)&fixed, &len) && fixed && len >= sizeof *fixed, "fixed info");
    if (fixed) {
        /* Specification 6.4: MM.mm.bb is written MM,mm,0,bb, for the file and the product. */
        DWORD ms = ((DWORD)OPCCOMN_VERSION_MAJOR << 16) | OPCCOMN_VERSION_MINOR;
        DWORD ls = (DWORD)OPCCOMN_VERSION_PATCH;
        CHECKF(fixed->dwSignature == 0xFEEF04BDu, "signature");
        CHECKF(fixed->dwFileVersionMS == ms && fixed->dwFileVersionLS == ls, "file version %08lX %08lX",
              (unsigned long)fixed->dwFileVersionMS, (unsigned long)fixed->dwFileVersionLS);
        CHECKF(fixed->dwProductVersionMS == ms && fixed->dwProductVersionLS == ls, "product version");
        CHECKF(fixed->dwFileType == VFT_DLL, "file type");
        /* A build of a version in development says so (VS_FF_PRERELEASE); a release does not. */
#ifdef OPCCOMN_VERSION_PRERELEASE
        CHECKF((fixed->dwFileFlags & fixed->dwFileFlagsMask & VS_FF_PRERELEASE) != 0, "pre-release flag missing (flags %08lX)",
              (unsigned long)fixed->dwFileFlags);
#else
        CHECKF((fixed->dwFileFlags & VS_FF_PRERELEASE) == 0, "pre-release flag on a release (flags %08lX)",
              (unsigned long)fixed->dwFileFlags);
#endif
    }
    /* The strings carry the whole version, "0.3.0-dev" for a version in development. */
    WCHAR *value = NULL;
    CHECKF(VerQueryValueW(info, L"\\StringFileInfo\\040904b0\\FileVersion", (void **)&value, &len) &&
              same(value, OPCCOMN_VERSION),
          "FileVersion string \"%s\"", show(value));
    CHECKF(VerQueryValueW(info, L"\\StringFileInfo\\040904b0\\ProductVersion", (void **)&value, &len) &&
              same(value, OPCCOMN_VERSION),
          "ProductVersion string \"%s\"", show(value));
    CHECKF(VerQueryValueW(info, L"\\StringFileInfo\\040904b0\\OriginalFilename", (void **)&value, &len) &&
              same(value, "opccomn.dll"),
          "OriginalFilename");
    free(info);
}
#endif

/* OPCCOMN_VERSION is MAJOR.MINOR.PATCH, then "-" and OPCCOMN_VERSION_PRERELEASE for a version in
   development. */
static void test_version_macros(void)
{
    char expected[64];
#ifdef OPCCOMN_VERSION_PRERELEASE
    snprintf(expected, sizeof expected, "%d.%d.%d-%s", OPCCOMN_VERSION_MAJOR, OPCCOMN_VERSION_MINOR,
             OPCCOMN_VERSION_PATCH, OPCCOMN_VERSION_PRERELEASE);
    CHECKF(OPCCOMN_VERSION_PRERELEASE[0] != '\0', "an empty pre-release");
#else
    snprintf(expected, sizeof expected, "%d.%d.%d", OPCCOMN_VERSION_MAJOR, OPCCOMN_VERSION_MINOR,
             OPCCOMN_VERSION_PATCH);
#endif
    CHECKF(strcmp(OPCCOMN_VERSION, expected) == 0, "OPCCOMN_VERSION \"%s\", expected \"%s\"", OPCCOMN_VERSION, expected);
}

int main(void)
{
#if !defined(_WIN32)
    /* Before the first call: the library reads the locale environment once. */
    unsetenv("LC_ALL");
    setenv("LC_MESSAGES", "de_DE.UTF-8", 1);
    setenv("LANG", "en_US.UTF-8", 1);
#endif
    test_version_macros();
    test_default_locales_resolve();
    test_every_published_english_text();
    test_codes_of_each_kind();
    test_german_texts();
    test_languages_without_texts_fall_back_to_english();
    test_collision_both_ways();
    test_unknown_codes_and_null_pointers();
    test_com_codes();
    test_iopccommon();
    test_vendor_callback();
#if defined(_WIN32)
    test_dll_message_table();
    test_dll_version_resource();
#endif
    CHECKF(OpcObjectCount() == 0, "objects leaked: %u", (unsigned)OpcObjectCount());
    return test_summary("test_error_strings");
}
