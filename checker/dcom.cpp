// DCOM security (--dcom): the AppID and the machine's settings, as Windows' DCOM hardening
// (KB5004442, CVE-2021-26414, enforced since March 2023) needs them.
#include <windows.h>
#include <sddl.h>

#include <cstring>

#include "registration.h"
#include "run.h"

namespace checker {

namespace {

const wchar_t kOleKey[] = L"SOFTWARE\\Microsoft\\Ole";
const wchar_t kAppCompatKey[] = L"SOFTWARE\\Microsoft\\Ole\\AppCompat";
const DWORD kPktIntegrity = 5;  // RPC_C_AUTHN_LEVEL_PKT_INTEGRITY

// A registry value of any type: false when it does not exist.
bool RegRaw(HKEY root, const std::wstring &key, LPCWSTR name, DWORD *type, std::vector<BYTE> *data) {
    DWORD size = 0;
    if (RegGetValueW(root, key.c_str(), name, RRF_RT_ANY | RRF_NOEXPAND, type, nullptr, &size) != ERROR_SUCCESS) return false;
    data->assign(size, 0);
    if (size && RegGetValueW(root, key.c_str(), name, RRF_RT_ANY | RRF_NOEXPAND, type, data->data(), &size) != ERROR_SUCCESS)
        return false;
    data->resize(size);
    return true;
}

// A value read for the report: "not set", a number, text, or what it is when it is neither.
struct RegFact {
    bool exists = false;
    DWORD type = REG_NONE;
    std::vector<BYTE> data;
    bool Dword(DWORD *v) const {
        if (!exists || type != REG_DWORD || data.size() != 4) return false;
        memcpy(v, data.data(), 4);
        return true;
    }
};

RegFact ReadFact(HKEY root, const std::wstring &key, LPCWSTR name) {
    RegFact f;
    f.exists = RegRaw(root, key, name, &f.type, &f.data);
    return f;
}

const char *LevelName(DWORD level) {
    static const char *const names[] = {"DEFAULT", "NONE", "CONNECT", "CALL", "PKT", "PKT_INTEGRITY", "PKT_PRIVACY"};
    return level < 7 ? names[level] : "not a level";
}

std::string LevelText(DWORD level) { return Format("%lu (RPC_C_AUTHN_LEVEL_%s)", static_cast<unsigned long>(level), LevelName(level)); }

// The SDDL of a binary self-relative security descriptor, as Windows writes it; false when it is
// not a valid descriptor.
bool SddlOf(const std::vector<BYTE> &sd, std::string *sddl) {
    if (sd.size() < 20 || !IsValidSecurityDescriptor(const_cast<BYTE *>(sd.data()))) return false;
    LPWSTR text = nullptr;
    if (!ConvertSecurityDescriptorToStringSecurityDescriptorW(const_cast<BYTE *>(sd.data()), SDDL_REVISION_1,
                                                              OWNER_SECURITY_INFORMATION | GROUP_SECURITY_INFORMATION |
                                                                  DACL_SECURITY_INFORMATION,
                                                              &text, nullptr))
        return false;
    *sddl = Utf8(text);
    LocalFree(text);
    return true;
}

// What the machine's value `name` under HKLM\SOFTWARE\Microsoft\Ole says, for reports.
std::string MachineLevelText() {
    RegFact f = ReadFact(HKEY_LOCAL_MACHINE, kOleKey, L"LegacyAuthenticationLevel");
    DWORD v;
    if (f.Dword(&v)) return "HKLM\\SOFTWARE\\Microsoft\\Ole LegacyAuthenticationLevel = " + LevelText(v);
    return "HKLM\\SOFTWARE\\Microsoft\\Ole LegacyAuthenticationLevel not set (Windows then uses CONNECT)";
}

std::string MachinePermissionText(LPCWSTR name) {
    RegFact f = ReadFact(HKEY_LOCAL_MACHINE, kOleKey, name);
    std::string sddl;
    if (!f.exists) return "HKLM\\SOFTWARE\\Microsoft\\Ole " + Utf8(name) + " not set (Windows' built-in default)";
    if (f.type != REG_BINARY || !SddlOf(f.data, &sddl)) return "HKLM\\SOFTWARE\\Microsoft\\Ole " + Utf8(name) + " is not a valid security descriptor";
    return "HKLM\\SOFTWARE\\Microsoft\\Ole " + Utf8(name) + " = " + sddl;
}

// The class's AppID (CLSID\{clsid} AppID) and the one its EXE's file name names, read once.
void ReadAppId(Facts &facts) {
    AppIdFacts &app = facts.app;
    if (app.read) return;
    app.read = true;
    bool ok;
    app.app_id = RegString(ClsidKey(facts), L"AppID", &ok);
    app.named = ok && !app.app_id.empty();
    if (app.named) app.key = KeyExists(L"AppID\\" + app.app_id);
    std::wstring command = RegString(ClsidKey(facts) + L"\\LocalServer32", nullptr, &ok);
    app.local = ok;
    if (ok) {
        std::wstring path = ModulePathOf(command);
        size_t slash = path.find_last_of(L"\\/");
        app.exe = slash == std::wstring::npos ? path : path.substr(slash + 1);
        if (!app.exe.empty()) {
            app.exe_app_id = RegString(L"AppID\\" + app.exe, L"AppID", &ok);
            if (!ok) app.exe_app_id.clear();
        }
    }
}

std::wstring AppKey(const Facts &facts) { return L"AppID\\" + facts.app.app_id; }

// Why a DCOM check does not apply, or "" when it does.
std::string DcomNotApplicable(Ctx &x) {
    if (!x.Local()) return "a server on another machine: its registry is not read";
    if (!x.facts.clsid_key) return "no CLSID key (see reg.clsid)";
    ReadAppId(x.facts);
    if (!x.facts.app.named || !x.facts.app.key) return "no AppID (see dcom.appid)";
    return "";
}

void CheckDcomAppId(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    if (!x.facts.clsid_key) return x.NotApplicable("no CLSID key (see reg.clsid)");
    ReadAppId(x.facts);
    std::string app = Utf8(x.facts.app.app_id.c_str());
    if (!x.facts.app.named) {
        if (!x.facts.app.local)
            return x.NotApplicable("an in-process server without an AppID: the client's process security applies");
        return x.Warn("an AppID for the EXE server's DCOM settings (CLSID\\{clsid} AppID)", "none",
                      "the machine's defaults apply: " + MachineLevelText() + "; " + MachinePermissionText(L"DefaultAccessPermission") +
                          "; " + MachinePermissionText(L"DefaultLaunchPermission"));
    }
    if (!x.facts.app.key) return x.Fail("HKCR\\AppID\\" + app, "no such key (CLSID\\{clsid} names AppID " + app + ")");
    bool ok;
    std::wstring name = RegString(AppKey(x.facts), nullptr, &ok);
    std::string detail = "AppID " + app + (ok ? " \"" + Utf8(name.c_str()) + "\"" : "");
    if (x.facts.app.local) {
        if (x.facts.app.exe_app_id.empty())
            return x.Warn("HKCR\\AppID\\" + Utf8(x.facts.app.exe.c_str()) + " AppID = " + app, "no such value",
                          "COM finds the AppID of an EXE server started by hand (not by COM) through its file name");
        if (_wcsicmp(x.facts.app.exe_app_id.c_str(), x.facts.app.app_id.c_str()) != 0)
            return x.Fail("HKCR\\AppID\\" + Utf8(x.facts.app.exe.c_str()) + " AppID = " + app, Utf8(x.facts.app.exe_app_id.c_str()));
        detail += "; AppID\\" + Utf8(x.facts.app.exe.c_str()) + " names it";
    }
    x.Pass(detail);
}

void CheckDcomLevel(Ctx &x) {
    std::string why = DcomNotApplicable(x);
    if (!why.empty()) return x.NotApplicable(why);
    RegFact f = ReadFact(HKEY_CLASSES_ROOT, AppKey(x.facts), L"AuthenticationLevel");
    DWORD level = 0;
    if (!f.exists || (f.Dword(&level) && level == 0))
        return x.Warn("AuthenticationLevel 5 (PKT_INTEGRITY) or 6 (PKT_PRIVACY)", f.exists ? "0 (DEFAULT)" : "not set",
                      "the machine default applies: " + MachineLevelText());
    if (!f.Dword(&level)) return x.Fail("AuthenticationLevel as a REG_DWORD", Format("a value of type %lu", static_cast<unsigned long>(f.type)));
    if (level > 6) return x.Fail("AuthenticationLevel 5 (PKT_INTEGRITY) or 6 (PKT_PRIVACY)", Format("%lu, not an authentication level", static_cast<unsigned long>(level)));
    if (level < kPktIntegrity)
        return x.Fail("AuthenticationLevel 5 (PKT_INTEGRITY) or 6 (PKT_PRIVACY)", LevelText(level),
                      "below PKT_INTEGRITY: since Windows' DCOM hardening (KB5004442, CVE-2021-26414; enforced since "
                      "March 2023) clients on other machines are refused or lose their calls; register the AppID "
                      "with level 5 or more");
    x.Pass("AuthenticationLevel = " + LevelText(level));
}

// A permission of the AppID: set (printed as SDDL) or the machine default.
void CheckDcomPermission(Ctx &x, LPCWSTR name, LPCWSTR machine_default) {
    std::string why = DcomNotApplicable(x);
    if (!why.empty()) return x.NotApplicable(why);
    RegFact f = ReadFact(HKEY_CLASSES_ROOT, AppKey(x.facts), name);
    std::string sddl;
    if (!f.exists)
        return x.Warn(Utf8(name) + " of the AppID", "not set", "the machine default applies: " + MachinePermissionText(machine_default));
    if (f.type != REG_BINARY || !SddlOf(f.data, &sddl))
        return x.Fail(Utf8(name) + " as a REG_BINARY self-relative security descriptor", "a value that is not one");
    // Everyone and ANONYMOUS LOGON allowed in: what the hardening is meant to end.
    for (const char *who : {";WD)", ";AN)"}) {
        for (size_t at = sddl.find("(A;"); at != std::string::npos; at = sddl.find("(A;", at + 1)) {
            size_t end = sddl.find(')', at);
            if (end != std::string::npos && sddl.compare(end - 3, 4, who) == 0)
                return x.Warn(Utf8(name) + " without Everyone (WD) or ANONYMOUS LOGON (AN) allowed", sddl,
                              "anyone on the network may use the server as far as the machine limits allow");
        }
    }
    x.Pass(Utf8(name) + " = " + sddl);
}

void CheckDcomAccess(Ctx &x) { CheckDcomPermission(x, L"AccessPermission", L"DefaultAccessPermission"); }
void CheckDcomLaunch(Ctx &x) { CheckDcomPermission(x, L"LaunchPermission", L"DefaultLaunchPermission"); }

void CheckDcomRunAs(Ctx &x) {
    std::string why = DcomNotApplicable(x);
    if (!why.empty()) return x.NotApplicable(why);
    bool ok, service;
    std::wstring run_as = RegString(AppKey(x.facts), L"RunAs", &ok);
    std::wstring local_service = RegString(AppKey(x.facts), L"LocalService", &service);
    if (service) return x.Pass("LocalService = " + Utf8(local_service.c_str()) + " (runs as that Windows service's account)");
    if (!ok) return x.Pass("no RunAs: the server runs as the user who launched it");
    if (_wcsicmp(run_as.c_str(), L"Interactive User") == 0)
        return x.Pass("RunAs = Interactive User (runs in the logged-on user's session; not without one)");
    x.Pass("RunAs = " + Utf8(run_as.c_str()));
}

void CheckDcomMachine(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its registry is not read");
    std::string detail;
    auto dword = [&](const wchar_t *key, LPCWSTR name, const char *missing) {
        DWORD v;
        RegFact f = ReadFact(HKEY_LOCAL_MACHINE, key, name);
        detail += (detail.empty() ? "" : "; ") + Utf8(name) + " = " +
                  (f.Dword(&v) ? Format("%lu", static_cast<unsigned long>(v)) : f.exists ? std::string("(not a DWORD)") : std::string(missing));
        return f.Dword(&v) ? static_cast<long>(v) : -1L;
    };
    bool ok;
    std::wstring enable = L"";
    {
        RegFact f = ReadFact(HKEY_LOCAL_MACHINE, kOleKey, L"EnableDCOM");
        if (f.exists && (f.type == REG_SZ || f.type == REG_EXPAND_SZ) && f.data.size() >= 2) enable = reinterpret_cast<const wchar_t *>(f.data.data());
        ok = f.exists;
    }
    detail = "EnableDCOM = " + (ok ? "\"" + Utf8(enable.c_str()) + "\"" : std::string("not set (Y)"));
    dword(kOleKey, L"LegacyAuthenticationLevel", "not set (CONNECT)");
    dword(kOleKey, L"LegacyImpersonationLevel", "not set (IDENTIFY)");
    for (LPCWSTR name : {L"DefaultAccessPermission", L"DefaultLaunchPermission", L"MachineAccessRestriction", L"MachineLaunchRestriction"})
        detail += std::string("; ") + Utf8(name) + (ReadFact(HKEY_LOCAL_MACHINE, kOleKey, name).exists ? " set" : " not set");
    long require = dword(kAppCompatKey, L"RequireIntegrityActivationAuthenticationLevel", "not set (on)");
    dword(kAppCompatKey, L"RaiseActivationAuthenticationLevel", "not set (2 since November 2022)");
    detail += Format("; this checker's calls: CoInitializeSecurity(RPC_C_AUTHN_LEVEL_PKT_INTEGRITY) = %s", x.Hr(x.run.security_hr).c_str());
    if (ok && (enable == L"N" || enable == L"n")) return x.Warn("EnableDCOM = \"Y\"", "\"N\"", "no remote client reaches any server here; " + detail);
    if (require == 0)
        return x.Warn("RequireIntegrityActivationAuthenticationLevel on", "0 (off)",
                      "the KB5004442 hardening is turned off on this machine (Windows updates since March 2023 ignore that); " + detail);
    x.Pass(detail);
}

void CheckDcomBrowser(Ctx &x) {
    if (!x.Local()) return x.NotApplicable("a server on another machine: its registry is not read (its browser answered if the ProgID resolved)");
    std::wstring key = L"CLSID\\" + GuidWide(CLSID_OPCServerList);
    bool ok;
    std::wstring command = RegString(key + L"\\LocalServer32", nullptr, &ok);
    if (!ok) {
        bool inproc = KeyExists(key + L"\\InprocServer32");
        return x.Warn("CLSID_OPCServerList registered as an EXE server (OpcEnum or opccomn_browser)",
                      inproc ? "an in-process server list only" : "none",
                      "clients on other machines cannot browse this machine's servers (specification 7.1)");
    }
    std::string detail = "CLSID_OPCServerList: " + Utf8(command.c_str());
    std::wstring app = RegString(key, L"AppID", &ok);
    if (ok) {
        RegFact f = ReadFact(HKEY_CLASSES_ROOT, L"AppID\\" + app, L"AuthenticationLevel");
        DWORD level;
        if (f.Dword(&level) && level != 0 && level < kPktIntegrity)
            return x.Warn("the browser's AppID at PKT_INTEGRITY or above", LevelText(level),
                          "remote browsing fails since KB5004442; " + detail);
        detail += ", AppID " + Utf8(app.c_str()) + " AuthenticationLevel " + (f.Dword(&level) ? LevelText(level) : std::string("not set"));
    }
    x.Pass(detail);
}

}  // namespace

std::vector<CheckDef> DcomChecks() {
    return {
        {"dcom.appid", "6.3", "the class's AppID (its DCOM settings) is registered", CheckDcomAppId, kDcom},
        {"dcom.authentication-level", "6.3", "the AppID's AuthenticationLevel is PKT_INTEGRITY or above (KB5004442)", CheckDcomLevel, kDcom},
        {"dcom.access-permission", "6.3", "the AppID's AccessPermission is set (SDDL) or the machine default applies", CheckDcomAccess, kDcom},
        {"dcom.launch-permission", "6.3", "the AppID's LaunchPermission is set (SDDL) or the machine default applies", CheckDcomLaunch, kDcom},
        {"dcom.runas", "6.3", "whom the server runs as (RunAs, LocalService)", CheckDcomRunAs, kDcom},
        {"dcom.machine", "6.3", "the machine's DCOM and hardening settings", CheckDcomMachine, kDcom},
        {"dcom.browser", "7.1, 7.2", "a server browser (CLSID_OPCServerList) serves remote clients", CheckDcomBrowser, kDcom},
    };
}

}  // namespace checker
