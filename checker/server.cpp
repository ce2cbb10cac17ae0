// The server under test (server.h): its creation as a client creates it, in process or out of process
// through its proxy, locally or on --host, and the interfaces the other areas' checks call.
#include "server.h"

#include <cstdio>
#include <cstring>

#include "registration.h"

namespace checker {

COSERVERINFO *ServerInfo(const Options &opt, COSERVERINFO *info) {
    if (opt.Local()) return nullptr;
    memset(info, 0, sizeof *info);
    info->pwszName = const_cast<LPWSTR>(opt.host.c_str());
    return info;
}

// Created once per session.
IUnknown *Server(Ctx &x) {
    Session &s = x.s;
    if (!s.create_tried) {
        s.create_tried = true;
        COSERVERINFO info;
        MULTI_QI mqi = {&IID_IUnknown, nullptr, S_OK};
        DWORD context = x.Local() ? x.opt.context : kHostContext;
        Call c(x.watchdog, "CoCreateInstanceEx");
        s.create_hr = CoCreateInstanceEx(x.facts.clsid, nullptr, context, ServerInfo(x.opt, &info), 1, &mqi);
        if (SUCCEEDED(s.create_hr)) s.create_hr = mqi.hr;
        if (SUCCEEDED(s.create_hr) && mqi.pItf) {
            s.server = mqi.pItf;
            // Proxies have IClientSecurity; in-process objects (practically) never.
            void *security = nullptr;
            if (SUCCEEDED(s.server->QueryInterface(IID_IClientSecurity, &security)) && security) {
                s.proxy = true;
                static_cast<IUnknown *>(security)->Release();
            }
        } else if (SUCCEEDED(s.create_hr)) {
            s.create_hr = E_POINTER;
        }
    }
    return s.server;
}

IOPCCommon *Common(Ctx &x) {
    if (!x.s.common && Server(x)) {
        void *p = nullptr;
        Call c(x.watchdog, "IUnknown::QueryInterface(IID_IOPCCommon)");
        if (SUCCEEDED(x.s.server->QueryInterface(IID_IOPCCommon, &p))) x.s.common = static_cast<IOPCCommon *>(p);
    }
    if (!x.s.common) x.NotApplicable("the server object has no IOPCCommon (see common.interface)");
    return x.s.common;
}

IConnectionPointContainer *Container(Ctx &x) {
    if (!x.s.container && Server(x)) {
        void *p = nullptr;
        Call c(x.watchdog, "IUnknown::QueryInterface(IID_IConnectionPointContainer)");
        if (SUCCEEDED(x.s.server->QueryInterface(IID_IConnectionPointContainer, &p)))
            x.s.container = static_cast<IConnectionPointContainer *>(p);
    }
    if (!x.s.container) x.NotApplicable("the server object has no IConnectionPointContainer (see shutdown.container)");
    return x.s.container;
}

IConnectionPoint *Point(Ctx &x) {
    if (!x.s.point && Container(x)) {
        IConnectionPoint *p = nullptr;
        Call c(x.watchdog, "IConnectionPointContainer::FindConnectionPoint(IID_IOPCShutdown)");
        if (SUCCEEDED(x.s.container->FindConnectionPoint(IID_IOPCShutdown, &p))) x.s.point = p;
    }
    if (!x.s.point && x.r.status == kNotRun)
        x.NotApplicable("the server has no IOPCShutdown connection point (see shutdown.find)");
    return x.s.point;
}

namespace {

void OnShutdown(void *, LPCWSTR reason) {
    fprintf(stderr, "opccomn-check: the server sent ShutdownRequest(\"%s\")\n", Utf8(reason).c_str());
}

}  // namespace

IUnknown *NewSink() {
    void *sink = nullptr;
    return SUCCEEDED(OpcShutdownSinkCreate(OnShutdown, nullptr, IID_IUnknown, &sink)) ? static_cast<IUnknown *>(sink)
                                                                                     : nullptr;
}

// Out of process an interface crosses through its proxy/stub, registered on both machines
// (Interface\{iid}\ProxyStubClsid32). Without one, QueryInterface gives E_NOINTERFACE and the server
// cannot call the client's sink: say so.
std::string ProxyHint(const IID &iid, const char *name) {
    HKEY h;
    std::wstring key = L"Interface\\" + GuidWide(iid) + L"\\ProxyStubClsid32";
    if (RegOpenKeyExW(HKEY_CLASSES_ROOT, key.c_str(), 0, KEY_READ, &h) == ERROR_SUCCESS) {
        RegCloseKey(h);
        return "";
    }
    return std::string("no proxy/stub is registered for ") + name +
           " on this machine (regsvr32 /n /i:ProxyStub opccomn.dll registers the OPC Common, Data"
           " Access, Alarms & Events and HDA interfaces; or the OPC Foundation's Core Components)";
}

// ---- The checks: creation ----

namespace {

void CheckCreate(Ctx &x) {
    if (Server(x)) {
        x.Pass(Format("CoCreateInstanceEx(%s, %s) gave the server object", GuidText(x.facts.clsid).c_str(),
                      x.Local() ? "local" : Utf8(x.opt.host.c_str()).c_str()));
    } else {
        x.Fail("S_OK and an object", x.Hr(x.s.create_hr), "the server could not be created; its other checks cannot run" + OtherViewHint(x.run));
    }
}

}  // namespace

std::vector<CheckDef> ServerChecks() {
    return {
        {"server.create", "6.3", "the server object is created as a client creates it", CheckCreate, kDefault},
    };
}

}  // namespace checker
