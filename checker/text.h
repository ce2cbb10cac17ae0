// Text for the report: UTF-8 from the wide strings of COM, printf-style formatting, GUIDs, and the
// names of the codes and server kinds the report mentions.
#ifndef OPCCOMN_CHECK_TEXT_H
#define OPCCOMN_CHECK_TEXT_H

#include <windows.h>

#include <cstdint>
#include <string>

namespace checker {

std::string Utf8(const wchar_t *w);
std::string Format(const char *fmt, ...);
std::string GuidText(const GUID &g);
std::wstring GuidWide(const GUID &g);

// The name of a code the report mentions: the catalog's symbol (OPC, connection point and COM codes)
// for the server's kind with its value, e.g. "CONNECT_E_NOCONNECTION (0x80040200)".
std::string HrText(HRESULT hr, uint32_t kind);

// The kind of server (OPC_SERVER_KIND_*) as --kind names it: "da", "ae" or "hda".
const char *KindName(uint32_t kind);

}  // namespace checker

#endif
