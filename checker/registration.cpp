// Registration (specification chapter 6): the class's CLSID, ProgID and version-independent ProgID keys,
// its module and version resource, its categories; and the registry reading the other areas share
// (registration.h).
#include "registration.h"

#include <cwchar>

namespace checker {

std::wstring ClsidKey(const Facts &facts) { return L"CLSID\\" + GuidWide(facts.clsid); }

std::wstring RegString(const std::wstring &key, LPCWSTR name, bool *ok) {
    LPWSTR data = nullptr;
    HRESULT hr = OpcRegistryGetString(nullptr, key.c_str(), name, &data);
    *ok = SUCCEEDED(hr) && data;
    std::wstring s = *ok ? data : L"";
    OpcTaskMemFree(data);
    return s;
}

bool KeyExists(const std::wstring &key) {
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key.c_str(), 0, KEY_READ, &h) != ERROR_SUCCESS) return false;
    RegCloseKey(h);
    return true;
}

bool OtherViewHas(const std::wstring &key) {
    BOOL wow64 = FALSE;
    IsWow64Process(GetCurrentProcess(), &wow64);
    REGSAM other = sizeof(void *) == 8 ? KEY_WOW64_32KEY : (wow64 ? KEY_WOW64_64KEY : 0);
    if (!other) return false;
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key.c_str(), 0, KEY_READ | other, &h) != ERROR_SUCCESS) return false;
    RegCloseKey(h);
    return true;
}

std::string OtherViewHint(const Run &run) {
    if (!run.Local() || !OtherViewHas(L"CLSID\\" + GuidWide(run.facts.clsid))) return "";
    return sizeof(void *) == 8 ? "; the class is registered in the 32-bit registry view only: run the x86 opccomn-check"
                               : "; the class is registered in the 64-bit registry view only: run the x64 opccomn-check";
}

void ReadCategories(Facts &facts) {
    if (facts.categories_read) return;
    facts.categories_read = true;
    HKEY h;
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, (ClsidKey(facts) + L"\\Implemented Categories").c_str(), 0, KEY_READ, &h) != ERROR_SUCCESS)
        return;
    for (DWORD i = 0;; i++) {
        WCHAR name[64];
        DWORD len = 64;
        if (RegEnumKeyExW(h, i, name, &len, nullptr, nullptr, nullptr, nullptr) != ERROR_SUCCESS) break;
        CATID catid;
        if (SUCCEEDED(CLSIDFromString(name, &catid))) facts.categories.push_back(catid);
    }
    RegCloseKey(h);
}

std::wstring ModulePathOf(const std::wstring &value) {
    std::wstring v = value;
    if (!v.empty() && v[0] == L'"') {
        size_t end = v.find(L'"', 1);
        return v.substr(1, end == std::wstring::npos ? std::wstring::npos : end - 1);
    }
    if (GetFileAttributesW(v.c_str()) != INVALID_FILE_ATTRIBUTES) return v;
    // Unquoted with arguments: the longest prefix ending at a space that names a file.
    for (size_t i = v.size(); i > 0; i--)
        if (v[i - 1] == L' ') {
            std::wstring p = v.substr(0, i - 1);
            if (GetFileAttributesW(p.c_str()) != INVALID_FILE_ATTRIBUTES) return p;
        }
    size_t space = v.find(L' ');
    return space == std::wstring::npos ? v : v.substr(0, space);
}

// ---- The checks ----

namespace {

void CheckRegClsid(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    bool ok;
    x.facts.user_type = RegString(ClsidKey(x.facts), nullptr, &ok);
    x.facts.clsid_key = KeyExists(ClsidKey(x.facts));
    if (!x.facts.clsid_key) return x.Fail("HKCR\\" + Utf8(ClsidKey(x.facts).c_str()), "no such key" + OtherViewHint(x.run));
    if (!ok || x.facts.user_type.empty())
        return x.Fail("a description (the user type) as the default value of HKCR\\" + Utf8(ClsidKey(x.facts).c_str()), "none");
    x.Pass("HKCR\\" + Utf8(ClsidKey(x.facts).c_str()) + " = \"" + Utf8(x.facts.user_type.c_str()) + "\"");
}

void CheckRegProgId(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!x.facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    bool ok;
    std::wstring prog_id = RegString(ClsidKey(x.facts) + L"\\ProgID", nullptr, &ok);
    if (!ok || prog_id.empty()) return x.Fail("CLSID\\{...}\\ProgID", "none");
    x.facts.prog_id = prog_id;
    std::wstring back = RegString(prog_id + L"\\CLSID", nullptr, &ok);
    CLSID clsid = {};
    if (!ok || FAILED(CLSIDFromString(back.c_str(), &clsid)) || !IsEqualCLSID(clsid, x.facts.clsid))
        return x.Fail("HKCR\\" + Utf8(prog_id.c_str()) + "\\CLSID = " + GuidText(x.facts.clsid), ok ? Utf8(back.c_str()) : "no such value");
    RegString(prog_id, nullptr, &ok);
    if (!ok) return x.Fail("a description as the default value of HKCR\\" + Utf8(prog_id.c_str()), "none");
    x.Pass("ProgID " + Utf8(prog_id.c_str()) + ", whose CLSID key names the class");
}

void CheckRegVersionIndependent(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!x.facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    bool ok;
    std::wstring vi = RegString(ClsidKey(x.facts) + L"\\VersionIndependentProgID", nullptr, &ok);
    if (!ok || vi.empty()) return x.NotApplicable("no VersionIndependentProgID registered");
    x.facts.vi_prog_id = vi;
    std::wstring back = RegString(vi + L"\\CLSID", nullptr, &ok);
    CLSID clsid = {};
    if (!ok || FAILED(CLSIDFromString(back.c_str(), &clsid)) || !IsEqualCLSID(clsid, x.facts.clsid))
        return x.Fail("HKCR\\" + Utf8(vi.c_str()) + "\\CLSID = " + GuidText(x.facts.clsid), ok ? Utf8(back.c_str()) : "no such value");
    std::wstring cur = RegString(vi + L"\\CurVer", nullptr, &ok);
    if (!ok) return x.Fail("HKCR\\" + Utf8(vi.c_str()) + "\\CurVer = " + Utf8(x.facts.prog_id.c_str()), "no CurVer key");
    if (!x.facts.prog_id.empty() && _wcsicmp(cur.c_str(), x.facts.prog_id.c_str()) != 0)
        return x.Fail("HKCR\\" + Utf8(vi.c_str()) + "\\CurVer = " + Utf8(x.facts.prog_id.c_str()), Utf8(cur.c_str()));
    x.Pass("VersionIndependentProgID " + Utf8(vi.c_str()) + ", CLSID and CurVer (" + Utf8(cur.c_str()) + ") consistent");
}

void CheckRegModule(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!x.facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    bool ok;
    LPCWSTR keys[] = {L"InprocServer32", L"LocalServer32"};
    for (LPCWSTR k : keys) {
        std::wstring value = RegString(ClsidKey(x.facts) + L"\\" + k, nullptr, &ok);
        if (!ok) continue;
        x.facts.module_key = k;
        x.facts.module = ModulePathOf(value);
        DWORD attr = GetFileAttributesW(x.facts.module.c_str());
        if (attr == INVALID_FILE_ATTRIBUTES || (attr & FILE_ATTRIBUTE_DIRECTORY))
            return x.Fail(Utf8(k) + " naming an existing file", "\"" + Utf8(value.c_str()) + "\": no such file");
        bool full = x.facts.module.size() > 2 && (x.facts.module[1] == L':' || (x.facts.module[0] == L'\\' && x.facts.module[1] == L'\\'));
        if (!full) return x.Fail(Utf8(k) + " with the module's full path", "\"" + Utf8(value.c_str()) + "\"");
        return x.Pass(Utf8(k) + " = " + Utf8(x.facts.module.c_str()) + " (exists)");
    }
    x.Fail("InprocServer32 or LocalServer32", "neither is registered");
}

void CheckRegCategories(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!x.facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    ReadCategories(x.facts);
    bool ok;
    if (x.facts.categories.empty()) {
        if (!x.facts.prog_id.empty() && KeyExists(x.facts.prog_id + L"\\OPC"))
            return x.NotApplicable("no Implemented Categories: a Data Access 1.0 server registered the old way (ProgID\\OPC)");
        return x.Fail("at least one category under Implemented Categories", "none");
    }
    std::string list;
    bool any_opc = false;
    for (const CATID &cat : x.facts.categories) {
        std::wstring key = L"Component Categories\\" + GuidWide(cat);
        std::wstring description = RegString(key, L"409", &ok);
        LPWSTR standard = nullptr;
        bool opc = SUCCEEDED(OpcCategoryDescription(&cat, &standard));
        any_opc = any_opc || opc;
        std::wstring want = opc ? standard : L"";
        OpcTaskMemFree(standard);
        if (!ok)
            return x.Fail("HKCR\\" + Utf8(key.c_str()) + "\\409" + (opc ? " = \"" + Utf8(want.c_str()) + "\"" : " (a description)"), "not registered");
        if (opc && description != want)
            return x.Fail("\"" + Utf8(want.c_str()) + "\" for " + GuidText(cat), "\"" + Utf8(description.c_str()) + "\"",
                          "the standard description of an OPC category");
        list += (list.empty() ? "" : "; ") + Utf8(description.c_str());
    }
    x.Pass(Format("%u categor%s registered, each with its description%s: ", static_cast<unsigned>(x.facts.categories.size()),
                  x.facts.categories.size() == 1 ? "y" : "ies", any_opc ? " (the standard one for OPC categories)" : "") + list);
}

void CheckRegDa10(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!x.facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    ReadCategories(x.facts);
    bool da10 = false;
    for (const CATID &c : x.facts.categories) da10 = da10 || IsEqualGUID(c, CATID_OPCDAServer10);
    if (!da10) return x.NotApplicable("not in the Data Access 1.0 category");
    if (x.facts.prog_id.empty()) return x.NotApplicable("no ProgID (see reg.progid)");
    if (!KeyExists(x.facts.prog_id + L"\\OPC")) return x.Fail("HKCR\\" + Utf8(x.facts.prog_id.c_str()) + "\\OPC", "no such key");
    bool ok;
    std::wstring vendor = RegString(x.facts.prog_id + L"\\OPC\\Vendor", nullptr, &ok);
    if (!ok) return x.Fail("HKCR\\" + Utf8(x.facts.prog_id.c_str()) + "\\OPC\\Vendor", "no such key");
    x.Pass("HKCR\\" + Utf8(x.facts.prog_id.c_str()) + "\\OPC\\Vendor = \"" + Utf8(vendor.c_str()) + "\"");
}

void CheckRegVersion(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its files are not read");
    if (x.facts.module.empty()) return x.NotApplicable("no module path (see reg.module)");
    DWORD handle = 0;
    DWORD size = GetFileVersionInfoSizeW(x.facts.module.c_str(), &handle);
    if (size == 0) return x.Fail("a VERSIONINFO resource in " + Utf8(x.facts.module.c_str()), "none");
    std::vector<BYTE> data(size);
    VS_FIXEDFILEINFO *fixed = nullptr;
    UINT len = 0;
    if (!GetFileVersionInfoW(x.facts.module.c_str(), 0, size, data.data()) ||
        !VerQueryValueW(data.data(), L"\\", reinterpret_cast<void **>(&fixed), &len) || !fixed || len < sizeof *fixed)
        return x.Fail("a VERSIONINFO resource with a fixed part", "unreadable");
    std::string file = Format("%u,%u,%u,%u", HIWORD(fixed->dwFileVersionMS), LOWORD(fixed->dwFileVersionMS),
                              HIWORD(fixed->dwFileVersionLS), LOWORD(fixed->dwFileVersionLS));
    std::string product = Format("%u,%u,%u,%u", HIWORD(fixed->dwProductVersionMS), LOWORD(fixed->dwProductVersionMS),
                                 HIWORD(fixed->dwProductVersionLS), LOWORD(fixed->dwProductVersionLS));
    OpcVersion version;
    if (FAILED(OpcVersionFromFileVersion(fixed->dwFileVersionMS, fixed->dwFileVersionLS, &version)))
        return x.Fail("FILEVERSION MM,mm,0,bb (the third number 0)", "FILEVERSION " + file);
    if (file != product) return x.Fail("PRODUCTVERSION the same as FILEVERSION " + file, "PRODUCTVERSION " + product);
    LPWSTR text = nullptr;
    std::string mmb = SUCCEEDED(OpcVersionFormat(&version, &text)) ? Utf8(text) : "?";
    OpcTaskMemFree(text);
    x.Pass("FILEVERSION and PRODUCTVERSION " + file + ": version " + mmb);
}

}  // namespace

std::vector<CheckDef> RegistrationChecks() {
    return {
        {"reg.clsid", "6.3", "HKCR\\CLSID\\{clsid} with a description", CheckRegClsid, kDefault},
        {"reg.progid", "6.3", "ProgID registered both ways", CheckRegProgId, kDefault},
        {"reg.version-independent", "6.3", "VersionIndependentProgID, its CLSID and CurVer consistent", CheckRegVersionIndependent, kDefault},
        {"reg.module", "6.3", "the registered module path exists", CheckRegModule, kDefault},
        {"reg.categories", "6.1.1.1", "the claimed categories are registered with their standard descriptions", CheckRegCategories, kDefault},
        {"reg.da10", "6.3", "a Data Access 1.0 server has its ProgID\\OPC\\Vendor key", CheckRegDa10, kDefault},
        {"reg.version", "6.4", "the module has a version resource in the MM.mm.bb convention", CheckRegVersion, kDefault},
    };
}

}  // namespace checker
