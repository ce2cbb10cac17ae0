// Reading the server's registration (HKEY_CLASSES_ROOT), shared by the registration, browsing and DCOM
// checks and by the choice of the class and kind to check (registration.cpp).
#ifndef OPCCOMN_CHECK_REGISTRATION_H
#define OPCCOMN_CHECK_REGISTRATION_H

#include "run.h"

namespace checker {

// "CLSID\{clsid}" of the class under test.
std::wstring ClsidKey(const Facts &facts);

// A string value under HKEY_CLASSES_ROOT through the library's registry reader; `ok` tells whether it exists.
std::wstring RegString(const std::wstring &key, LPCWSTR name, bool *ok);

bool KeyExists(const std::wstring &key);

// Whether the other registry view (32-bit for a 64-bit checker and the other way round) has `key`
// under HKEY_CLASSES_ROOT: the most common reason a client does not find a server.
bool OtherViewHas(const std::wstring &key);

// For a report: the class is registered in the other view only, and which checker to run; or "".
std::string OtherViewHint(const Run &run);

// The class's Implemented Categories into facts.categories, once.
void ReadCategories(Facts &facts);

// The program path of an InprocServer32 / LocalServer32 value: quotes removed, arguments dropped.
std::wstring ModulePathOf(const std::wstring &value);

}  // namespace checker

#endif
