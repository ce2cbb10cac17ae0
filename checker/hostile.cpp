// Hostile input (--hostile): NULL out-parameters and absurd counts, which a server must refuse cleanly.
#include <windows.h>
#include <olectl.h>

#include "run.h"
#include "server.h"

namespace checker {

namespace {

void HostileNullLocale(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCCommon::GetLocaleID(NULL)");
        hr = common->GetLocaleID(nullptr);
    }
    if (hr != E_INVALIDARG && hr != E_POINTER && hr != HRESULT_FROM_WIN32(RPC_X_NULL_REF_POINTER))
        return x.Fail("E_INVALIDARG (E_POINTER accepted; through a proxy RPC_X_NULL_REF_POINTER)", x.Hr(hr));
    x.Pass("GetLocaleID(NULL) = " + x.Hr(hr));
}

void HostileNullLocaleArray(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    DWORD count = 0xDEADBEEF;
    LCID *array = reinterpret_cast<LCID *>(static_cast<uintptr_t>(0xDEADBEEF));
    HRESULT a, b;
    {
        Call c(x.watchdog, "IOPCCommon::QueryAvailableLocaleIDs(&count, NULL)");
        a = common->QueryAvailableLocaleIDs(&count, nullptr);
    }
    {
        Call c(x.watchdog, "IOPCCommon::QueryAvailableLocaleIDs(NULL, &array)");
        b = common->QueryAvailableLocaleIDs(nullptr, &array);
    }
    if (SUCCEEDED(a) || SUCCEEDED(b))
        return x.Fail("a failure code for each NULL out-parameter", x.Hr(a) + ", " + x.Hr(b));
    // Through a proxy the NULL never reaches the server: the proxy refuses the call and leaves the
    // other out-parameter alone, which says nothing about the server.
    if (!x.s.proxy) {
        if (count != 0) return x.Fail("the count set to 0 on failure (3.1.3)", Format("%lu", static_cast<unsigned long>(count)));
        if (array != nullptr) return x.Fail("the array set to NULL on failure (3.1.3)", "left as it was");
    }
    x.Pass("NULL count: " + x.Hr(b) + "; NULL array: " + x.Hr(a) + (x.s.proxy ? " (refused by the proxy)" : "; the other out-parameter cleared"));
}

// A call with a NULL where the method needs a pointer, which must fail: `call` is what the progress line
// names, `shown` what the report says was called.
template <typename F>
void MustFail(Ctx &x, const char *call, const char *shown, const char *expected, F f) {
    HRESULT hr;
    {
        Call c(x.watchdog, call);
        hr = f();
    }
    if (SUCCEEDED(hr)) return x.Fail(expected, x.Hr(hr));
    x.Pass(std::string(shown) + " = " + x.Hr(hr));
}

void HostileNullErrorString(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    MustFail(x, "IOPCCommon::GetErrorString(code, NULL)", "GetErrorString(E_FAIL, NULL)", "E_INVALIDARG",
             [&] { return common->GetErrorString(E_FAIL, nullptr); });
}

void HostileNullClientName(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    MustFail(x, "IOPCCommon::SetClientName(NULL)", "SetClientName(NULL)", "E_INVALIDARG",
             [&] { return common->SetClientName(nullptr); });
}

void HostileLongClientName(Ctx &x) {
    IOPCCommon *common = Common(x);
    if (!common) return;
    std::wstring name(1u << 20, L'x');  // a million characters
    HRESULT hr;
    {
        Call c(x.watchdog, "IOPCCommon::SetClientName(1,048,576 characters)");
        hr = common->SetClientName(name.c_str());
    }
    if (hr != S_OK && hr != E_INVALIDARG && hr != E_OUTOFMEMORY)
        return x.Fail("S_OK, E_INVALIDARG or E_OUTOFMEMORY", x.Hr(hr));
    x.Pass("SetClientName of 1,048,576 characters = " + x.Hr(hr));
}

void HostileFindNull(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    MustFail(x, "IConnectionPointContainer::FindConnectionPoint(IID_IOPCShutdown, NULL)",
             "FindConnectionPoint(IID_IOPCShutdown, NULL)", "E_POINTER",
             [&] { return container->FindConnectionPoint(IID_IOPCShutdown, nullptr); });
}

void HostileAdviseNull(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    DWORD cookie = 0xDEADBEEF;
    HRESULT a, b;
    {
        Call c(x.watchdog, "IConnectionPoint::Advise(NULL, &cookie)");
        a = point->Advise(nullptr, &cookie);
    }
    IUnknown *sink = NewSink();
    {
        Call c(x.watchdog, "IConnectionPoint::Advise(sink, NULL)");
        b = point->Advise(sink, nullptr);
    }
    if (sink) sink->Release();
    if (SUCCEEDED(a) || SUCCEEDED(b)) return x.Fail("a failure code for each", x.Hr(a) + ", " + x.Hr(b));
    if (cookie != 0 && !x.s.proxy) return x.Fail("the cookie set to 0 on failure (3.1.3)", Format("%lu", static_cast<unsigned long>(cookie)));
    x.Pass("Advise(NULL, &cookie) = " + x.Hr(a) + " with cookie 0; Advise(sink, NULL) = " + x.Hr(b));
}

void HostileUnadviseZero(Ctx &x) {
    IConnectionPoint *point = Point(x);
    if (!point) return;
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPoint::Unadvise(0)");
        hr = point->Unadvise(0);
    }
    if (hr != CONNECT_E_NOCONNECTION) return x.Fail("CONNECT_E_NOCONNECTION", x.Hr(hr));
    x.Pass("Unadvise(0) = CONNECT_E_NOCONNECTION");
}

void HostileEnumHuge(Ctx &x) {
    IConnectionPointContainer *container = Container(x);
    if (!container) return;
    IEnumConnectionPoints *points = nullptr;
    HRESULT hr;
    {
        Call c(x.watchdog, "IConnectionPointContainer::EnumConnectionPoints");
        hr = container->EnumConnectionPoints(&points);
    }
    if (hr != S_OK || !points) return x.NotApplicable("no connection point enumerator (see shutdown.enum-points)");
    // Room for 8; a count of 0xFFFFFFFF must give at most what the server has.
    IConnectionPoint *buf[8] = {};
    ULONG fetched = 0xDEADBEEF;
    {
        Call c(x.watchdog, "IEnumConnectionPoints::Next(0xFFFFFFFF, ...)");
        // In-process the absurd count reaches the server; a proxy would make the stub allocate for it.
        hr = points->Next(x.s.proxy ? 8u : 0xFFFFFFFFu, buf, &fetched);
    }
    ULONG got = fetched;
    for (ULONG i = 0; i < 8; i++)
        if (buf[i] && i < got) buf[i]->Release();
    HRESULT skip;
    {
        Call c(x.watchdog, "IEnumConnectionPoints::Skip(0xFFFFFFFF)");
        skip = points->Skip(0xFFFFFFFFu);
    }
    points->Release();
    if (SUCCEEDED(hr) && got > 8) return x.Fail("at most the enumerator's elements", Format("%lu fetched", static_cast<unsigned long>(got)));
    if (FAILED(skip) && skip != E_INVALIDARG) return x.Fail("Skip(0xFFFFFFFF) = S_FALSE", x.Hr(skip));
    x.Pass("Next(0xFFFFFFFF) = " + x.Hr(hr) + Format(", %lu fetched; Skip(0xFFFFFFFF) = ", static_cast<unsigned long>(got)) + x.Hr(skip));
}

}  // namespace

std::vector<CheckDef> HostileChecks() {
    return {
        {"hostile.getlocale-null", "5.1.2, 3.1.3", "GetLocaleID(NULL) fails cleanly", HostileNullLocale, kHostile},
        {"hostile.locales-null", "5.1.3, 3.1.3", "QueryAvailableLocaleIDs with a NULL out-parameter fails and clears the other", HostileNullLocaleArray, kHostile},
        {"hostile.errorstring-null", "5.1.4", "GetErrorString(code, NULL) fails cleanly", HostileNullErrorString, kHostile},
        {"hostile.clientname-null", "5.1.5", "SetClientName(NULL) fails cleanly", HostileNullClientName, kHostile},
        {"hostile.clientname-long", "5.1.5", "SetClientName of a million characters is handled", HostileLongClientName, kHostile},
        {"hostile.find-null", "4.1.2", "FindConnectionPoint with a NULL out-pointer fails cleanly", HostileFindNull, kHostile},
        {"hostile.advise-null", "4.2, 3.1.3", "Advise with a NULL sink or cookie pointer fails cleanly", HostileAdviseNull, kHostile},
        {"hostile.unadvise-zero", "4.1", "Unadvise(0) gives CONNECT_E_NOCONNECTION", HostileUnadviseZero, kHostile},
        {"hostile.enum-huge", "4.1.1", "IEnumConnectionPoints::Next and Skip with a count of 0xFFFFFFFF", HostileEnumHuge, kHostile},
    };
}

}  // namespace checker
