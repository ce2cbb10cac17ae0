// IOPCCommon (specification chapter 5): locales, error texts, the client name.
#include <cwchar>
#include <cwctype>

#include "run.h"
#include "server.h"

namespace checker {

namespace {

void CheckCommonInterface(Ctx &x) {
    if (!Server(x)) return x.NotApplicable("no server object (see server.create)");
    void *p = nullptr;
    HRESULT hr;
    {
        Call c(x.watchdog, "IUnknown::QueryInterface(IID_IOPCCommon)");
        hr = x.s.server->QueryInterface(IID_IOPCCommon, &p);
    }
    if (SUCCEEDED(hr) && p) {
        if (!x.s.common) x.s.common = static_cast<IOPCCommon *>(p);
        else static_cast<IUnknown *>(p)->Release();
        x.Pass("QueryInterface(IID_IOPCCommon) succeeded");
    } else {
        x.Fail("S_OK and an interface", x.Hr(hr) + (p ? "" : ", NULL"), hr == E_NOINTERFACE ? ProxyHint(IID_IOPCCommon, "IOPCCommon") : "");
    }
}

void CheckDefaultLocale(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    LCID lcid = 0xDEADBEEF;
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCCommon::GetLocaleID");
        hr = common->GetLocaleID(&lcid);
    }
    if (hr != S_OK) return x.Fail("S_OK", x.Hr(hr));
    if (lcid == LOCALE_SYSTEM_DEFAULT) return x.Pass("a new session starts in LOCALE_SYSTEM_DEFAULT (0x0800)");
    x.Warn("LOCALE_SYSTEM_DEFAULT (0x0800)", Format("0x%04lX", static_cast<unsigned long>(lcid)),
           "the specification says the default should be LOCALE_SYSTEM_DEFAULT");
}

// QueryAvailableLocaleIDs: S_OK, a count, an array in task memory (IMalloc::DidAlloc).
void CheckLocaleArray(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    DWORD count = 0xDEADBEEF;
    LCID *array = reinterpret_cast<LCID *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCCommon::QueryAvailableLocaleIDs");
        hr = common->QueryAvailableLocaleIDs(&count, &array);
    }
    if (hr != S_OK) return x.Fail("S_OK", x.Hr(hr));
    if (count == 0 || !array)
        return x.Fail("at least one locale in a task-memory array", Format("count %lu, array %p", static_cast<unsigned long>(count), static_cast<void *>(array)));
    if (count > 4096) return x.Fail("a plausible count", Format("count %lu", static_cast<unsigned long>(count)));
    x.s.locales.assign(array, array + count);
    x.s.locales_read = true;
    std::string list;
    for (DWORD i = 0; i < count; i++) list += Format("%s0x%04lX", i ? ", " : "", static_cast<unsigned long>(array[i]));
    // In-process the array comes straight from the server: it must be the COM task allocator's, or
    // the client's CoTaskMemFree corrupts the heap. (Through a proxy the proxy allocated it.)
    IMalloc *malloc = nullptr;
    int owned = -1;
    if (SUCCEEDED(CoGetMalloc(1, &malloc)) && malloc) {
        owned = malloc->DidAlloc(array);
        malloc->Release();
    }
    if (owned == 0) {
        // Not ours to free with CoTaskMemFree: leak it rather than corrupt the heap.
        return x.Fail("an array allocated with CoTaskMemAlloc (IMalloc::DidAlloc = 1)",
                      "an array the COM task allocator did not allocate (DidAlloc = 0)", "locales " + list);
    }
    CoTaskMemFree(array);
    x.Pass(Format("%lu locale(s): ", static_cast<unsigned long>(count)) + list +
           (owned == 1 ? "; the array is task memory (IMalloc::DidAlloc)" : "; DidAlloc could not tell"));
}

bool ReadLocales(Ctx &x) {
    if (x.s.locales_read) return true;
    IOPCCommon *common = Common(x);
    if (!common) return false;
    DWORD count = 0;
    LCID *array = nullptr;
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCCommon::QueryAvailableLocaleIDs");
        hr = common->QueryAvailableLocaleIDs(&count, &array);
    }
    if (hr != S_OK || !array || count == 0 || count > 4096) {
        x.NotApplicable("QueryAvailableLocaleIDs gave no list (see common.locales.array)");
        return false;
    }
    x.s.locales.assign(array, array + count);
    x.s.locales_read = true;
    return true;  // the array is leaked on purpose: it may not be task memory (common.locales.array)
}

void CheckSetEveryLocale(Ctx &x) {
    if (!ReadLocales(x)) return;
    IOPCCommon *common = x.s.common;
    std::string done;
    for (LCID lcid : x.s.locales) {
        HRESULT hr;
        LCID back = 0xDEADBEEF;
        {
            Call c(x.watchdog, "IOPCCommon::SetLocaleID");
            hr = common->SetLocaleID(lcid);
        }
        if (hr != S_OK)
            return x.Fail(Format("SetLocaleID(0x%04lX) = S_OK (it is in the list)", static_cast<unsigned long>(lcid)), x.Hr(hr));
        {
            Call c(x.watchdog, "IOPCCommon::GetLocaleID");
            hr = common->GetLocaleID(&back);
        }
        if (hr != S_OK || back != lcid)
            return x.Fail(Format("GetLocaleID = S_OK, 0x%04lX", static_cast<unsigned long>(lcid)),
                          x.Hr(hr) + Format(", 0x%04lX", static_cast<unsigned long>(back)));
        done += Format("%s0x%04lX", done.empty() ? "" : ", ", static_cast<unsigned long>(lcid));
    }
    x.Pass("set and read back: " + done);
}

bool Listed(const std::vector<LCID> &locales, LCID lcid) {
    for (LCID l : locales)
        if (l == lcid) return true;
    return false;
}

void CheckUnsupportedLocale(Ctx &x) {
    if (!ReadLocales(x)) return;
    IOPCCommon *common = x.s.common;
    // A real locale that is not in the list: the first of a few that few servers offer.
    static const LCID candidates[] = {0x0419, 0x0411, 0x041F, 0x0408, 0x042A, 0x0439};
    LCID bad = 0;
    for (LCID c : candidates)
        if (!Listed(x.s.locales, c)) {
            bad = c;
            break;
        }
    if (!bad) return x.NotApplicable("the server lists every candidate locale");
    LCID before = 0, after = 0;
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCCommon::GetLocaleID");
        hr = common->GetLocaleID(&before);
    }
    if (hr != S_OK) return x.Fail("GetLocaleID = S_OK", x.Hr(hr));
    {
        Call c(x.watchdog, "IOPCCommon::SetLocaleID");
        hr = common->SetLocaleID(bad);
    }
    {
        Call c(x.watchdog, "IOPCCommon::GetLocaleID");
        common->GetLocaleID(&after);
    }
    std::string what = Format("SetLocaleID(0x%04lX), a locale QueryAvailableLocaleIDs does not list", static_cast<unsigned long>(bad));
    if (hr != E_INVALIDARG)
        return x.Fail("E_INVALIDARG, locale unchanged", x.Hr(hr) + Format(", locale now 0x%04lX", static_cast<unsigned long>(after)), what);
    if (after != before)
        return x.Fail(Format("E_INVALIDARG, locale still 0x%04lX", static_cast<unsigned long>(before)),
                      Format("E_INVALIDARG, locale now 0x%04lX", static_cast<unsigned long>(after)), what);
    x.Pass(what + ": E_INVALIDARG, locale unchanged");
}

// ---- What an error text must say (5.1.4: "the server's textual representation" of the code) ----

bool AsciiAlnum(wchar_t c) { return (c >= L'0' && c <= L'9') || (c >= L'a' && c <= L'z') || (c >= L'A' && c <= L'Z'); }

// The words of a text: runs of characters between blanks and punctuation ('_' joins them, as in
// OPC_E_INVALIDHANDLE), ASCII letters in lower case. A character beyond ASCII is part of a word
// unless the runtime calls it a blank or punctuation, so a text in any script has words.
std::vector<std::wstring> Words(const std::wstring &text) {
    std::vector<std::wstring> words(1);
    for (wchar_t c : text) {
        bool part = c == L'_' || (c < 0x80 ? AsciiAlnum(c) : !iswspace(c) && !iswpunct(c));
        if (part) words.back() += c < 0x80 ? static_cast<wchar_t>(towlower(c)) : c;
        else if (!words.back().empty()) words.emplace_back();
    }
    if (words.back().empty()) words.pop_back();
    return words;
}

bool AllIn(const std::wstring &s, const wchar_t *set) { return !s.empty() && s.find_first_not_of(set) == std::wstring::npos; }

// Whether a word is a number: decimal, hexadecimal with 0x, or the code itself in hexadecimal (bare,
// after VB's &H, whose '&' is punctuation, or with the assembler's h after it).
bool NumberWord(const std::wstring &w, HRESULT code) {
    static const wchar_t hex_digits[] = L"0123456789abcdef";
    if (AllIn(w, L"0123456789")) return true;
    if (w.size() > 2 && w.compare(0, 2, L"0x") == 0 && AllIn(w.substr(2), hex_digits)) return true;
    std::wstring hex = w;
    if (hex.size() > 1 && hex.front() == L'h') hex.erase(0, 1);
    else if (hex.size() > 1 && hex.back() == L'h') hex.pop_back();
    return AllIn(hex, hex_digits) && hex.size() <= 16 &&
           wcstoull(hex.c_str(), nullptr, 16) == static_cast<unsigned long long>(static_cast<uint32_t>(code));
}

// Whether `text` says nothing beyond the code: it has no word, or each word is a number (the code
// in hexadecimal or decimal, signed or not, or any other), the code's symbol, or a word that only
// announces a code ("error", "code", "HRESULT", "unknown", ...; English and a few other languages).
bool SaysNothing(const std::wstring &text, HRESULT code, const std::wstring &symbol) {
    static const wchar_t *const announce[] = {
        L"error", L"errors", L"err", L"hresult", L"hr", L"scode", L"code", L"codes", L"errorcode", L"result",
        L"status", L"unknown", L"undefined", L"unspecified", L"opc", L"no", L"nr", L"num", L"number", L"value",
        L"id", L"message", L"text", L"string", L"description", L"the", L"a", L"an", L"of", L"for", L"is",
        L"with", L"returned", L"fehler", L"fehlercode", L"unbekannter", L"unbekannt", L"erreur", L"inconnue",
        L"errore", L"erro", L"codigo"};
    std::wstring lower_symbol;
    for (wchar_t c : symbol) lower_symbol += c < 0x80 ? static_cast<wchar_t>(towlower(c)) : c;
    for (const std::wstring &w : Words(text)) {
        bool filler = NumberWord(w, code) || (!lower_symbol.empty() && w == lower_symbol);
        for (const wchar_t *a : announce) filler = filler || w == a;
        if (!filler) return false;
    }
    return true;
}

// The locale GetErrorString is asked in: an English one when the server lists one (its texts can then
// be compared with the published ones), otherwise the first it lists. *english tells which.
void SetTextLocale(Ctx &x, bool *english) {
    *english = false;
    if (!ReadLocales(x)) return;
    LCID chosen = x.s.locales.front();
    for (LCID l : x.s.locales)
        if (PRIMARYLANGID(LANGIDFROMLCID(l)) == LANG_ENGLISH) {
            chosen = l;
            *english = true;
            break;
        }
    Call c(x.watchdog, "IOPCCommon::SetLocaleID");
    if (x.s.common->SetLocaleID(chosen) != S_OK) *english = false;
}

std::string LocaleList(const std::vector<LCID> &locales) {
    std::string list;
    for (LCID l : locales) list += Format("%s0x%04lX", list.empty() ? "" : ", ", static_cast<unsigned long>(l));
    return list.empty() ? "none" : list;
}

// Every published code of the kind needs S_OK and a text of its own: not empty, not the code restated
// (SaysNothing), not the text of another code whose published text differs. Texts read in an English
// locale are compared with the published ones (a warning where they differ, as vendors may word them
// otherwise); without one, texts that are exactly the published English ones pass, and others are a
// warning saying they could not be compared, never a pass.
void CheckPublishedCodes(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    bool english = false;
    SetTextLocale(x, &english);
    LCID locale = 0xFFFFFFFF;
    {
        Call c(x.watchdog, "IOPCCommon::GetLocaleID");
        if (common->GetLocaleID(&locale) != S_OK) locale = 0xFFFFFFFF;
    }
    DWORD count = 0;
    HRESULT *codes = nullptr;
    if (FAILED(OpcErrorCodesOfKind(x.run.kind, &count, &codes))) return x.NotApplicable("no published codes for this kind");
    struct Answer {
        HRESULT code;
        std::wstring text, published;
    };
    std::vector<Answer> answers;
    std::string failed, restated, shared, differs;
    DWORD n_failed = 0, n_restated = 0, n_shared = 0, different = 0;
    auto add = [](std::string &list, const std::string &item) {
        if (list.size() < 600) list += (list.empty() ? "" : "; ") + item;
    };
    for (DWORD i = 0; i < count; i++) {
        LPWSTR text = reinterpret_cast<LPWSTR>(static_cast<uintptr_t>(0xDEADBEEF));
        HRESULT hr;
        {
            Call c(x.watchdog, "IOPCCommon::GetErrorString");
            hr = common->GetErrorString(codes[i], &text);
        }
        if (hr != S_OK || !text) {
            n_failed++;
            add(failed, x.Hr(codes[i]) + ": " + x.Hr(hr) + (hr == S_OK ? " with NULL" : ""));
            continue;
        }
        Answer a = {codes[i], text, L""};
        CoTaskMemFree(text);
        LPWSTR published = nullptr, symbol = nullptr;
        if (SUCCEEDED(OpcGetErrorStringEx(codes[i], 0x0409, x.run.kind, &published)) && published) a.published = published;
        OpcTaskMemFree(published);
        std::wstring symbol_text;
        if (SUCCEEDED(OpcErrorSymbol(codes[i], x.run.kind, &symbol)) && symbol) symbol_text = symbol;
        OpcTaskMemFree(symbol);
        if (SaysNothing(a.text, a.code, symbol_text)) {
            n_restated++;
            add(restated, x.Hr(a.code) + ": \"" + Utf8(a.text.c_str()) + "\"");
        } else {
            for (const Answer &before : answers)
                if (before.text == a.text && before.published != a.published) {
                    n_shared++;
                    add(shared, x.Hr(before.code) + " and " + x.Hr(a.code) + ": \"" + Utf8(a.text.c_str()) + "\"");
                    break;
                }
        }
        if (a.text != a.published) {
            different++;
            add(differs, x.Hr(a.code) + ": \"" + Utf8(a.text.c_str()) + "\" (published: \"" + Utf8(a.published.c_str()) + "\")");
        }
        answers.push_back(a);
    }
    OpcTaskMemFree(codes);
    std::string summary = Format("%lu of %lu published %s codes answered", static_cast<unsigned long>(answers.size()),
                                 static_cast<unsigned long>(count), KindName(x.run.kind));
    std::string read_in = locale == 0xFFFFFFFF ? "the session's locale" : Format("locale 0x%04lX", static_cast<unsigned long>(locale));
    if (n_failed || n_restated || n_shared) {
        std::string got;
        if (n_failed) got += Format("%lu without S_OK and a text: ", static_cast<unsigned long>(n_failed)) + failed;
        if (n_restated)
            got += (got.empty() ? "" : "; ") + Format("%lu are empty or only restate the code: ", static_cast<unsigned long>(n_restated)) + restated;
        if (n_shared)
            got += (got.empty() ? "" : "; ") + Format("%lu give the text of another code: ", static_cast<unsigned long>(n_shared)) + shared;
        return x.Fail("S_OK and, for every published code, a text of its own that says more than the code", got,
                      summary + ", read in " + read_in);
    }
    if (!different)
        return x.Pass(summary + ", every text as published" +
                      (english ? "" : " (read in " + read_in + "; the server lists no English locale)"));
    if (english)
        return x.Warn("the texts the OPC Foundation publishes", Format("%lu differ: ", static_cast<unsigned long>(different)) + differs, summary);
    x.Warn("an English locale, to compare the texts with those the OPC Foundation publishes",
           "no English locale among those listed (" + LocaleList(x.s.locales) + ")",
           summary + ", read in " + read_in + Format(": %lu differ from the published English texts, ", static_cast<unsigned long>(different)) +
               "so they were not compared");
}

void CheckUnknownCode(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    // Facility 0xFFF is used by nobody: no catalog, no system and no vendor text exists for it.
    const HRESULT unknown = static_cast<HRESULT>(0x8FFF7A3Eu);
    LPWSTR text = reinterpret_cast<LPWSTR>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCCommon::GetErrorString");
        hr = common->GetErrorString(unknown, &text);
    }
    std::string got = x.Hr(hr);
    if (hr == S_OK) {
        got += text ? ", \"" + Utf8(text) + "\"" : ", NULL";
        if (text) CoTaskMemFree(text);
        return x.Fail("E_INVALIDARG and NULL", got, "GetErrorString(0x8FFF7A3E), a code without a text");
    }
    if (hr != E_INVALIDARG || text != nullptr)
        return x.Fail("E_INVALIDARG and NULL", got + (text ? ", the out-pointer not set to NULL" : ", NULL"),
                      "GetErrorString(0x8FFF7A3E), a code without a text");
    x.Pass("GetErrorString(0x8FFF7A3E) = E_INVALIDARG with NULL");
}

void CheckClientName(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCCommon::SetClientName");
        hr = common->SetClientName(L"opccomn-check");
    }
    if (hr != S_OK) return x.Fail("S_OK", x.Hr(hr), "SetClientName(L\"opccomn-check\")");
    x.Pass("SetClientName(L\"opccomn-check\") = S_OK");
}

}  // namespace

std::vector<CheckDef> CommonChecks() {
    return {
        {"common.interface", "5", "the server object has IOPCCommon", CheckCommonInterface, kDefault},
        {"common.locale.default", "5.1.1", "a new session's locale is LOCALE_SYSTEM_DEFAULT", CheckDefaultLocale, kDefault},
        {"common.locales.array", "5.1.3, 3.1.3", "QueryAvailableLocaleIDs returns a task-memory array", CheckLocaleArray, kDefault},
        {"common.locales.set", "5.1.1, 5.1.2", "every available locale can be set and read back", CheckSetEveryLocale, kDefault},
        {"common.locales.unsupported", "5.1.1", "an unlisted LCID gives E_INVALIDARG and leaves the locale", CheckUnsupportedLocale, kDefault},
        {"common.errorstring.published", "5.1.4", "GetErrorString answers every published code of the kind with a text of its own", CheckPublishedCodes, kDefault},
        {"common.errorstring.unknown", "5.1.4", "GetErrorString of an unknown code gives E_INVALIDARG and NULL", CheckUnknownCode, kDefault},
        {"common.clientname", "5.1.5", "SetClientName accepts a name", CheckClientName, kDefault},
    };
}

}  // namespace checker
