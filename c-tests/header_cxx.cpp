// opccomn/opccomn.h compiles alone as C++11 (-pedantic-errors) and declares the interfaces as MIDL does in
// C++: abstract classes deriving from IUnknown, called as p->Method(...), implementable by deriving.
#include <opccomn/opccomn.h>

#include <cstring>

namespace {

// A client's shutdown sink written the way C++ COM code writes it: derive from the interface.
class Sink : public IOPCShutdown {
public:
    ULONG refs = 1;
    int requests = 0;
    HRESULT STDMETHODCALLTYPE QueryInterface(REFIID riid, void **ppv) override {
        if (std::memcmp(&riid, &IID_IUnknown, sizeof(IID)) == 0 || std::memcmp(&riid, &IID_IOPCShutdown, sizeof(IID)) == 0) {
            *ppv = static_cast<IOPCShutdown *>(this);
            AddRef();
            return S_OK;
        }
        *ppv = nullptr;
        return E_NOINTERFACE;
    }
    ULONG STDMETHODCALLTYPE AddRef() override { return ++refs; }
    ULONG STDMETHODCALLTYPE Release() override { return --refs; }
    HRESULT STDMETHODCALLTYPE ShutdownRequest(LPCWSTR reason) override {
        requests += reason != nullptr;
        return S_OK;
    }
};

}  // namespace

int main() {
    void *p = nullptr;
    // REFIID is a reference in C++ (as in the Windows headers); OPCCOMN_RIID(...) writes the same in C and C++.
    HRESULT hr = OpcCommonCreate(nullptr, nullptr, IID_IOPCCommon, &p);
    if (hr != S_OK || !p) return 1;
    IOPCCommon *common = static_cast<IOPCCommon *>(p);
    LCID lcid = 0;
    bool ok = common->GetLocaleID(&lcid) == S_OK && lcid == LOCALE_SYSTEM_DEFAULT;
    LPWSTR text = nullptr;
    ok = common->GetErrorString(OPC_E_INVALIDFILTER, &text) == S_OK && text && text[0] != 0 && ok;
    OpcTaskMemFree(text);
    ok = common->GetErrorString(E_POINTER, nullptr) == E_INVALIDARG && ok;  // the C++ caller gets the C result
    ok = common->Release() == 0 && ok;
    void *again = nullptr;
    ok = OpcCommonCreate(nullptr, nullptr, OPCCOMN_RIID(IID_IOPCCommon), &again) == S_OK && ok;
    if (again) static_cast<IOPCCommon *>(again)->Release();

    // A C++ sink through the library's connection point.
    IUnknown *shutdown = nullptr;
    ok = OpcShutdownCreate(nullptr, IID_IUnknown, reinterpret_cast<void **>(&shutdown)) == S_OK && ok;
    Sink sink;
    DWORD cookie = 0;
    ok = shutdown && OpcShutdownAdvise(shutdown, &sink, &cookie) == S_OK && cookie != 0 && ok;
    ULONG notified = 0, failed = 0;
    ok = shutdown && OpcShutdownNotifyEx(shutdown, nullptr, &notified, &failed) == S_OK && ok;
    ok = sink.requests == 1 && notified == 1 && failed == 0 && ok;
    ok = shutdown && OpcShutdownUnadvise(shutdown, cookie) == S_OK && ok;
    if (shutdown) shutdown->Release();
    ok = sink.refs == 1 && ok;

#if defined(__CRT_UUID_DECL) || defined(_MSC_VER)
    // Where the compiler has __uuidof, it knows the interfaces' IIDs.
    ok = std::memcmp(&__uuidof(IOPCCommon), &IID_IOPCCommon, sizeof(IID)) == 0 && ok;
    ok = std::memcmp(&__uuidof(IOPCShutdown), &IID_IOPCShutdown, sizeof(IID)) == 0 && ok;
    ok = std::memcmp(&__uuidof(IOPCServerList2), &IID_IOPCServerList2, sizeof(IID)) == 0 && ok;
#endif
    return ok ? 0 : 1;
}
