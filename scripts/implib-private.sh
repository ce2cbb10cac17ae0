#!/usr/bin/env bash
# Makes the standard COM entry points of opccomn.dll private in the mingw import library
# (libopccomn.dll.a, written by the linker when cargo links the DLL), as `PRIVATE` in a .def does: the
# DLL still exports DllGetClassObject, DllCanUnloadNow, DllRegisterServer, DllUnregisterServer and
# DllInstall (regsvr32 and COM find them by name), but a program linked against the import library can
# no longer bind to them. A server DLL with its own .def naming `DllRegisterServer` undecorated would
# otherwise, on x86 where its own function is `_DllRegisterServer@0`, bind the name to opccomn's
# import thunk and export a jump into opccomn.dll: regsvr32 would then register opccomn's class, not
# the server. The OpcDll* functions (the same entry points under opccomn's own names) stay linkable.
#
# The members defining those names (the thunk and its __imp_ pointer, one member per export) are
# removed; everything else in the archive is left as the linker wrote it. Idempotent.
#
# Usage: scripts/implib-private.sh IMPLIB   (tools: OPCCOMN_NM, OPCCOMN_AR; default x86_64-w64-mingw32-*)
set -euo pipefail
[ "$#" -eq 1 ] || { echo "usage: $0 IMPLIB" >&2; exit 2; }
implib=$1
nm=${OPCCOMN_NM:-x86_64-w64-mingw32-nm}
ar=${OPCCOMN_AR:-x86_64-w64-mingw32-ar}
private_names='DllGetClassObject DllCanUnloadNow DllRegisterServer DllUnregisterServer DllInstall'

# `member symbol` for every symbol whose undecorated name (without __imp_, the x86 leading underscore
# and the @N of __stdcall) is one of the private names.
members_of_private() {
    "$nm" -A --defined-only "$implib" 2>/dev/null | awk -v names="$private_names" '
        BEGIN { n = split(names, list, " "); for (i = 1; i <= n; i++) private[list[i]] = 1 }
        {
            sym = $NF
            split($1, where, ":")
            base = sym
            sub(/^__imp_/, "", base)
            sub(/^_/, "", base)
            sub(/@[0-9]+$/, "", base)
            if (base in private) print where[2], sym
        }'
}

found=$(members_of_private)
if [ -n "$found" ]; then
    mapfile -t members < <(awk '{ print $1 }' <<<"$found" | sort -u)
    "$ar" d "$implib" "${members[@]}"
    "$ar" s "$implib"
fi
left=$(members_of_private)
[ -z "$left" ] || { echo "$0: $implib still defines: $left" >&2; exit 1; }
kept=$("$nm" --defined-only "$implib" 2>/dev/null | grep -cE ' T _?OpcDll(GetClassObject|CanUnloadNow|RegisterServer|UnregisterServer|Install)(@[0-9]+)?$' || true)
[ "$kept" -eq 5 ] || { echo "$0: $implib offers $kept of the 5 OpcDll* functions (expected all)" >&2; exit 1; }
echo "$(basename "$implib"): DllGetClassObject, DllCanUnloadNow, DllRegisterServer, DllUnregisterServer, DllInstall private"
