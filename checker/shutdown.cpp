// The IOPCShutdown connection point (specification chapter 4): finding it, Advise and Unadvise, the
// enumerators, and the container it names.
#include <windows.h>
#include <olectl.h>

#include "run.h"
#include "server.h"

namespace checker {

namespace {

void CheckContainer(Ctx &x) {
    if (!Server(x)) return x.NotApplicable("no server object (see server.create)");
    void *p = nullptr;
    HRESULT hr;
    {
        Call c(x.watchdog, "IUnknown::QueryInterface(IID_IConnectionPointContainer)");
        hr = x.s.server->QueryInterface(IID_IConnectionPointContainer, &p);
    }
    if (FAILED(hr) || !p) return x.Fail("S_OK and an interface", x.Hr(hr));
    if (!x.s.container) x.s.container = static_cast<IConnectionPointContainer *>(p);
    else static_cast<IUnknown *>(p)->Release();
    x.Pass("QueryInterface(IID_IConnectionPointContainer) succeeded");
}

void CheckFind(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    IConnectionPoint *point = reinterpret_cast<IConnectionPoint *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPointContainer::FindConnectionPoint(IID_IOPCShutdown)");
        hr = container->FindConnectionPoint(IID_IOPCShutdown, &point);
    }
    if (hr != S_OK || !point || point == reinterpret_cast<IConnectionPoint *>(static_cast<uintptr_t>(0xDEADBEEF)))
        return x.Fail("S_OK and the connection point", x.Hr(hr));
    IID iid = {};
    {
        Call c(x.watchdog, "IConnectionPoint::GetConnectionInterface");
        hr = point->GetConnectionInterface(&iid);
    }
    if (!x.s.point) x.s.point = point;
    else point->Release();
    if (hr != S_OK || !IsEqualIID(iid, IID_IOPCShutdown))
        return x.Fail("GetConnectionInterface = S_OK, IID_IOPCShutdown", x.Hr(hr) + ", " + GuidText(iid));
    x.Pass("FindConnectionPoint(IID_IOPCShutdown) gave the point; GetConnectionInterface says IID_IOPCShutdown");
}

// IConnectionPoint::GetConnectionPointContainer gives back the container the point belongs to, which
// for IOPCShutdown is the server object: a client holding only the point (from EnumConnectionPoints,
// or kept after the server object was released) finds its server this way. COM identity decides:
// the container's IUnknown must be the server object's. A server that forwards to a connection point
// object it does not aggregate gets that object's own container back, another object.
void CheckPointContainer(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    IConnectionPointContainer *const garbage = reinterpret_cast<IConnectionPointContainer *>(static_cast<uintptr_t>(0xDEADBEEF));
    IConnectionPointContainer *back = garbage;
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPoint::GetConnectionPointContainer");
        hr = point->GetConnectionPointContainer(&back);
    }
    const std::string want = "S_OK and the server object's IConnectionPointContainer";
    if (back == garbage) return x.Fail(want, x.Hr(hr) + ", the out-pointer not written");
    if (hr != S_OK || !back) {
        // On failure a non-NULL pointer may be anything: it is left alone, not released.
        return x.Fail(want, x.Hr(hr) + (back ? ", the out-pointer not set to NULL" : ", NULL"),
                      "the connection point cannot name its container");
    }
    void *server = nullptr, *container = nullptr;
    {
        Call c(x.watchdog, "IUnknown::QueryInterface(IID_IUnknown)");
        x.s.server->QueryInterface(IID_IUnknown, &server);
        back->QueryInterface(IID_IUnknown, &container);
    }
    bool same = server && server == container;
    if (server) static_cast<IUnknown *>(server)->Release();
    if (container) static_cast<IUnknown *>(container)->Release();
    back->Release();
    if (!container) return x.Fail(want, "an object whose QueryInterface(IID_IUnknown) fails");
    if (!same)
        return x.Fail(want + " (the same IUnknown as the server object)", "another object (another IUnknown)",
                      "the container is not the server object: a connection point object forwarded to without "
                      "aggregating it names its own container");
    x.Pass("GetConnectionPointContainer gave the server object back (the same IUnknown)");
}

void CheckEnumPoints(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    IEnumConnectionPoints *points = nullptr;
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPointContainer::EnumConnectionPoints");
        hr = container->EnumConnectionPoints(&points);
    }
    if (hr != S_OK || !points) return x.Fail("S_OK and an enumerator", x.Hr(hr));
    bool found = false;
    ULONG seen = 0;
    for (int guard = 0; guard < 64; guard++) {
        IConnectionPoint *p = nullptr;
        ULONG fetched = 0;
        {
            Call c(x.watchdog, "IEnumConnectionPoints::Next");
            hr = points->Next(1, &p, &fetched);
        }
        if (hr != S_OK || fetched != 1 || !p) break;
        seen++;
        IID iid = {};
        {
            Call c(x.watchdog, "IConnectionPoint::GetConnectionInterface");
            if (p->GetConnectionInterface(&iid) == S_OK && IsEqualIID(iid, IID_IOPCShutdown)) found = true;
        }
        p->Release();
    }
    points->Release();
    if (!found) return x.Fail("an enumerator that includes IOPCShutdown", Format("%lu point(s), none for IOPCShutdown", static_cast<unsigned long>(seen)));
    x.Pass(Format("%lu connection point(s), IOPCShutdown among them", static_cast<unsigned long>(seen)));
}

void CheckAdvise(Ctx &x) {
    if (!Container(x)) return;
    IUnknown *sink = NewSink();
    if (!sink) return x.Fail("a client sink", "OpcShutdownSinkCreate failed");
    DWORD cookie = 0xDEADBEEF;
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPoint::Advise (OpcShutdownAdvise)");
        hr = OpcShutdownAdvise(x.s.server, sink, &cookie);
    }
    if (hr != S_OK) {
        sink->Release();
        return x.Fail("S_OK and a non-zero cookie", x.Hr(hr), hr == CONNECT_E_CANNOTCONNECT ? ProxyHint(IID_IOPCShutdown, "IOPCShutdown") : "");
    }
    x.s.sink = sink;  // kept until the connection is gone
    x.s.cookie = cookie;
    x.s.advised = true;
    if (cookie == 0) return x.Fail("S_OK and a non-zero cookie", "S_OK and cookie 0", "0 is the cookie COM reserves for \"no connection\"");
    x.Pass(Format("Advise of the library's shutdown sink: S_OK, cookie %lu", static_cast<unsigned long>(cookie)));
}

void CheckSecondAdvise(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    if (!x.s.advised) return x.NotApplicable("the first Advise did not succeed (see shutdown.advise)");
    IUnknown *sink = NewSink();
    if (!sink) return x.Fail("a client sink", "OpcShutdownSinkCreate failed");
    DWORD cookie = 0xDEADBEEF;
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPoint::Advise");
        hr = point->Advise(sink, &cookie);
    }
    if (hr == CONNECT_E_ADVISELIMIT) {
        sink->Release();
        if (cookie != 0) return x.Fail("CONNECT_E_ADVISELIMIT with cookie 0", Format("CONNECT_E_ADVISELIMIT with cookie %lu", static_cast<unsigned long>(cookie)));
        return x.Pass("a second Advise: CONNECT_E_ADVISELIMIT (one connection per client, as the specification allows)");
    }
    if (hr != S_OK) {
        sink->Release();
        return x.Fail("S_OK or CONNECT_E_ADVISELIMIT", x.Hr(hr));
    }
    x.s.sink2 = sink;
    std::string got = Format("S_OK, cookie %lu", static_cast<unsigned long>(cookie));
    HRESULT un;
    {
        Call c(x.watchdog, "IConnectionPoint::Unadvise");
        un = point->Unadvise(cookie);
    }
    if (cookie == 0 || cookie == x.s.cookie)
        return x.Fail("S_OK with a non-zero cookie of its own", got + Format(" (the first was %lu)", static_cast<unsigned long>(x.s.cookie)));
    if (un != S_OK) return x.Fail("Unadvise of the second connection = S_OK", x.Hr(un));
    x.Pass("a second Advise: " + got + ", unadvised again");
}

void CheckUnadviseUnknown(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    // A cookie no Advise handed out: far from the first one (cookies usually count up).
    DWORD unknown = x.s.cookie ^ 0x5A5A0000u;
    if (unknown == 0) unknown = 0x5A5A0001u;
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPoint::Unadvise");
        hr = point->Unadvise(unknown);
    }
    std::string what = Format("Unadvise(%lu), a cookie no Advise returned", static_cast<unsigned long>(unknown));
    if (hr != CONNECT_E_NOCONNECTION) return x.Fail("CONNECT_E_NOCONNECTION", x.Hr(hr), what);
    x.Pass(what + ": CONNECT_E_NOCONNECTION");
}

void CheckFindOther(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    IConnectionPoint *point = reinterpret_cast<IConnectionPoint *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPointContainer::FindConnectionPoint(IID_IOPCCommon)");
        hr = container->FindConnectionPoint(IID_IOPCCommon, &point);
    }
    std::string what = "FindConnectionPoint(IID_IOPCCommon), an interface with no connection point";
    if (hr == S_OK) {
        if (point) point->Release();
        return x.Fail("CONNECT_E_NOCONNECTION and NULL", "S_OK", what);
    }
    if (hr != CONNECT_E_NOCONNECTION) return x.Fail("CONNECT_E_NOCONNECTION and NULL", x.Hr(hr), what);
    if (point != nullptr) return x.Fail("CONNECT_E_NOCONNECTION and NULL", "CONNECT_E_NOCONNECTION, the out-pointer not set to NULL", what);
    x.Pass(what + ": CONNECT_E_NOCONNECTION with NULL");
}

// A sink without IOPCShutdown: the library's IOPCCommon object, which has IUnknown only besides it.
void CheckWrongSink(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    IUnknown *not_a_sink = nullptr;
    if (FAILED(OpcCommonCreate(nullptr, nullptr, IID_IUnknown, reinterpret_cast<void **>(&not_a_sink))))
        return x.Fail("an object without IOPCShutdown", "OpcCommonCreate failed");
    DWORD cookie = 0xDEADBEEF;
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPoint::Advise");
        hr = point->Advise(not_a_sink, &cookie);
    }
    if (hr == S_OK) {
        Call c(x.watchdog, "IConnectionPoint::Unadvise");
        point->Unadvise(cookie);
    }
    not_a_sink->Release();
    std::string what = "Advise of an object without IOPCShutdown";
    if (hr != CONNECT_E_CANNOTCONNECT) return x.Fail("CONNECT_E_CANNOTCONNECT, cookie 0", x.Hr(hr), what);
    if (cookie != 0) return x.Fail("CONNECT_E_CANNOTCONNECT, cookie 0", Format("CONNECT_E_CANNOTCONNECT, cookie %lu", static_cast<unsigned long>(cookie)), what);
    x.Pass(what + ": CONNECT_E_CANNOTCONNECT, cookie 0");
}

void CheckEnumConnections(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    IEnumConnections *connections = reinterpret_cast<IEnumConnections *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPoint::EnumConnections");
        hr = point->EnumConnections(&connections);
    }
    if (hr == E_NOTIMPL) {
        if (connections != nullptr) return x.Fail("E_NOTIMPL with NULL", "E_NOTIMPL, the out-pointer not set to NULL");
        return x.Pass("E_NOTIMPL (allowed for IOPCShutdown, specification 4.1)");
    }
    if (hr != S_OK || !connections || connections == reinterpret_cast<IEnumConnections *>(static_cast<uintptr_t>(0xDEADBEEF)))
        return x.Fail("S_OK and an enumerator, or E_NOTIMPL", x.Hr(hr));
    ULONG seen = 0;
    bool found = false;
    HRESULT last = S_OK;
    for (int guard = 0; guard < 64; guard++) {
        CONNECTDATA data = {nullptr, 0};
        ULONG fetched = 0;
        {
            Call c(x.watchdog, "IEnumConnections::Next");
            hr = connections->Next(1, &data, &fetched);
        }
        last = hr;
        // S_OK means all `celt` were fetched (Wine's cross-process IEnumConnections proxy leaves
        // *pcFetched unwritten, so the count is taken from the code).
        if (hr != S_OK) break;
        seen++;
        if (data.dwCookie == x.s.cookie && data.pUnk) found = true;
        if (data.pUnk) data.pUnk->Release();
    }
    connections->Release();
    if (x.s.advised && !found)
        return x.Fail(Format("an enumerator listing cookie %lu", static_cast<unsigned long>(x.s.cookie)),
                      Format("%lu connection(s), not that one (Next: ", static_cast<unsigned long>(seen)) + x.Hr(last) + ")");
    x.Pass(Format("S_OK; %lu connection(s)", static_cast<unsigned long>(seen)) + (x.s.advised ? ", the checker's among them" : ""));
}

void CheckUnadvise(Ctx &x) {
    if (!Container(x)) return;
    if (!x.s.advised) return x.NotApplicable("no connection to remove (see shutdown.advise)");
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPoint::Unadvise (OpcShutdownUnadvise)");
        hr = OpcShutdownUnadvise(x.s.server, x.s.cookie);
    }
    if (hr != S_OK) return x.Fail("S_OK", x.Hr(hr), Format("Unadvise(%lu), the cookie Advise returned", static_cast<unsigned long>(x.s.cookie)));
    x.s.advised = false;
    HRESULT again;
    {
        Call c(x.watchdog, "IConnectionPoint::Unadvise (OpcShutdownUnadvise)");
        again = OpcShutdownUnadvise(x.s.server, x.s.cookie);
    }
    if (again != CONNECT_E_NOCONNECTION)
        return x.Fail("a second Unadvise of the same cookie = CONNECT_E_NOCONNECTION", x.Hr(again));
    x.Pass(Format("Unadvise(%lu) = S_OK; once more = CONNECT_E_NOCONNECTION", static_cast<unsigned long>(x.s.cookie)));
}

}  // namespace

std::vector<CheckDef> ShutdownChecks() {
    return {
        {"shutdown.container", "4.1", "the server object has IConnectionPointContainer", CheckContainer, kDefault},
        {"shutdown.find", "4.1.2", "FindConnectionPoint(IID_IOPCShutdown) gives the connection point", CheckFind, kDefault},
        {"shutdown.point-container", "4.1", "the connection point's GetConnectionPointContainer gives the server object", CheckPointContainer, kDefault},
        {"shutdown.enum-points", "4.1.1", "EnumConnectionPoints includes IOPCShutdown", CheckEnumPoints, kDefault},
        {"shutdown.advise-wrong-sink", "4.2", "Advise of an object without IOPCShutdown gives CONNECT_E_CANNOTCONNECT", CheckWrongSink, kDefault},
        {"shutdown.advise", "4.2", "Advise of a shutdown sink gives S_OK and a non-zero cookie", CheckAdvise, kDefault},
        {"shutdown.advise-second", "4.1", "a second Advise gives S_OK or CONNECT_E_ADVISELIMIT", CheckSecondAdvise, kDefault},
        {"shutdown.unadvise-unknown", "4.1", "Unadvise of an unknown cookie gives CONNECT_E_NOCONNECTION", CheckUnadviseUnknown, kDefault},
        {"shutdown.find-other", "4.1.2", "FindConnectionPoint of another IID gives CONNECT_E_NOCONNECTION and NULL", CheckFindOther, kDefault},
        {"shutdown.enum-connections", "4.1", "EnumConnections works or is E_NOTIMPL", CheckEnumConnections, kDefault},
        {"shutdown.unadvise", "4.2", "Unadvise of the connection succeeds, once", CheckUnadvise, kDefault},
    };
}

}  // namespace checker
