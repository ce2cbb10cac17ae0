// The server under test: created once per session as a client creates it, and its interfaces, each
// asked for once per session (server.cpp).
#ifndef OPCCOMN_CHECK_SERVER_H
#define OPCCOMN_CHECK_SERVER_H

#include "run.h"

namespace checker {

// The context of a creation on --host, as remote OPC clients ask: the host's local server, which COM
// reaches by DCOM, or this machine's when the host names this machine ("localhost", its own name).
constexpr DWORD kHostContext = CLSCTX_REMOTE_SERVER | CLSCTX_LOCAL_SERVER;

// The machine --host names, in `info`; NULL for this machine.
COSERVERINFO *ServerInfo(const Options &opt, COSERVERINFO *info);

// The server object of the check's session, or NULL when it cannot be created (server.create).
IUnknown *Server(Ctx &x);

// The server's IOPCCommon, or NULL (the check is then "not applicable": the QI check failed).
IOPCCommon *Common(Ctx &x);

// The server's IConnectionPointContainer and its IOPCShutdown point, or NULL (likewise).
IConnectionPointContainer *Container(Ctx &x);
IConnectionPoint *Point(Ctx &x);

// A new client shutdown sink (the library's), or NULL.
IUnknown *NewSink();

// Why an interface may not cross to an out-of-process server: no proxy/stub registered for it; "" if
// one is.
std::string ProxyHint(const IID &iid, const char *name);

}  // namespace checker

#endif
