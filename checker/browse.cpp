// Server browsing (specification chapter 7): the server list clients use finds the class under its
// categories, with the registry's names.
#include "registration.h"
#include "run.h"
#include "server.h"

namespace checker {

namespace {

// The server list, created by the first browsing check (any worker) and kept in the run.
IOPCServerList2 *ServerList(Ctx &x) {
    if (x.run.server_list) return x.run.server_list;
    void *p = nullptr;
    HRESULT hr;
    if (x.Local()) {
        // What clients use: CLSID_OPCServerList as registered (OpcEnum, or opccomn.dll registered
        // with regsvr32); where none is registered or it cannot be created, the library's own.
        {
            Call c(x.watchdog, "CoCreateInstance(CLSID_OPCServerList)");
            hr = CoCreateInstance(CLSID_OPCServerList, nullptr, CLSCTX_ALL, IID_IOPCServerList2, &p);
        }
        if (SUCCEEDED(hr) && p) {
            x.run.server_list_source = "the registered OPCServerList (CLSID_OPCServerList)";
        } else {
            std::string why = x.Hr(hr);
            hr = OpcServerListCreate(nullptr, IID_IOPCServerList2, &p);
            x.run.server_list_source = "the library's server browser (OpcServerListCreate; CLSID_OPCServerList: " + why + ")";
        }
    } else {
        COSERVERINFO info;
        MULTI_QI mqi = {&IID_IOPCServerList2, nullptr, S_OK};
        Call c(x.watchdog, "CoCreateInstanceEx(CLSID_OPCServerList)");
        hr = CoCreateInstanceEx(CLSID_OPCServerList, nullptr, kHostContext, ServerInfo(x.opt, &info), 1, &mqi);
        if (SUCCEEDED(hr)) hr = mqi.hr;
        p = mqi.pItf;
        x.run.server_list_source = "OPCServerList on " + Utf8(x.opt.host.c_str());
    }
    if (FAILED(hr) || !p) {
        x.NotApplicable("no server list: " + x.Hr(hr));
        return nullptr;
    }
    x.run.server_list = static_cast<IOPCServerList2 *>(p);
    return x.run.server_list;
}

void CheckBrowseListed(Ctx &x) {
    IOPCServerList2 *list = ServerList(x);
    if (!list) return;
    ReadCategories(x.facts);
    std::vector<CATID> cats = x.facts.categories;
    if (cats.empty()) {
        if (!x.Local()) return x.NotApplicable("the categories of a server on another machine are not known");
        if (!x.facts.prog_id.empty() && KeyExists(x.facts.prog_id + L"\\OPC")) cats.push_back(CATID_OPCDAServer10);
        else return x.NotApplicable("the server claims no category (see reg.categories)");
    }
    std::string found;
    for (CATID cat : cats) {
        IOPCEnumGUID *classes = nullptr;
        HRESULT hr;
        {
            Call c(x.watchdog, "IOPCServerList2::EnumClassesOfCategories");
            hr = list->EnumClassesOfCategories(1, &cat, 0, nullptr, &classes);
        }
        if (FAILED(hr) || !classes) return x.Fail("EnumClassesOfCategories = S_OK", x.Hr(hr), "category " + GuidText(cat));
        bool listed = false;
        for (;;) {
            GUID g[16];
            ULONG fetched = 0;
            {
                Call c(x.watchdog, "IOPCEnumGUID::Next");
                hr = classes->Next(16, g, &fetched);
            }
            for (ULONG i = 0; i < fetched && i < 16; i++) listed = listed || IsEqualCLSID(g[i], x.facts.clsid);
            if (hr != S_OK || fetched == 0) break;
        }
        classes->Release();
        if (!listed) return x.Fail("the class listed under category " + GuidText(cat), "not listed", x.run.server_list_source);
        found += (found.empty() ? "" : ", ") + GuidText(cat);
    }
    x.Pass("listed by " + x.run.server_list_source + " under " + found);
}

void CheckBrowseDetails(Ctx &x) {
    IOPCServerList2 *list = ServerList(x);
    if (!list) return;
    LPOLESTR prog_id = nullptr, user_type = nullptr, vi = nullptr;
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCServerList2::GetClassDetails");
        hr = list->GetClassDetails(x.facts.clsid, &prog_id, &user_type, &vi);
    }
    std::string got = x.Hr(hr) + ": \"" + Utf8(prog_id) + "\", \"" + Utf8(user_type) + "\", \"" + Utf8(vi) + "\"";
    std::wstring p = prog_id ? prog_id : L"", u = user_type ? user_type : L"", v = vi ? vi : L"";
    CoTaskMemFree(prog_id);
    CoTaskMemFree(user_type);
    CoTaskMemFree(vi);
    if (FAILED(hr)) return x.Fail("S_OK and the class's details", got);
    if (x.Local() && x.facts.clsid_key && !x.facts.prog_id.empty()) {
        std::string want = "\"" + Utf8(x.facts.prog_id.c_str()) + "\", \"" + Utf8(x.facts.user_type.c_str()) + "\", \"" + Utf8(x.facts.vi_prog_id.c_str()) + "\"";
        if (p != x.facts.prog_id || u != x.facts.user_type || v != x.facts.vi_prog_id)
            return x.Fail("the registry's " + want, got, x.run.server_list_source);
        return x.Pass("GetClassDetails: " + want + ", as in the registry");
    }
    if (p.empty()) return x.Fail("a ProgID", got);
    x.facts.prog_id = p, x.facts.user_type = u, x.facts.vi_prog_id = v;
    x.Pass("GetClassDetails: " + got + (x.Local() ? " (nothing to compare: the registry checks found no registration)" : ""));
}

void CheckBrowseProgId(Ctx &x) {
    IOPCServerList2 *list = ServerList(x);
    if (!list) return;
    if (x.facts.prog_id.empty()) return x.NotApplicable("no ProgID known (see reg.progid)");
    CLSID clsid = {};
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCServerList2::CLSIDFromProgID");
        hr = list->CLSIDFromProgID(x.facts.prog_id.c_str(), &clsid);
    }
    if (hr != S_OK || !IsEqualCLSID(clsid, x.facts.clsid))
        return x.Fail("S_OK, " + GuidText(x.facts.clsid), x.Hr(hr) + ", " + GuidText(clsid));
    x.Pass("CLSIDFromProgID(" + Utf8(x.facts.prog_id.c_str()) + ") = " + GuidText(clsid));
}

}  // namespace

std::vector<CheckDef> BrowseChecks() {
    return {
        {"browse.listed", "7.5.1", "IOPCServerList lists the server under each category it claims", CheckBrowseListed, kDefault},
        {"browse.details", "7.5.2", "GetClassDetails gives the registry's ProgID, user type and version-independent ProgID", CheckBrowseDetails, kDefault},
        {"browse.progid", "7.5.3", "CLSIDFromProgID gives the class", CheckBrowseProgId, kDefault},
    };
}

}  // namespace checker
