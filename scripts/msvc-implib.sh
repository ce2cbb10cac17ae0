#!/usr/bin/env bash
# Makes opccomn.lib, the import library in the format Microsoft's linker (link.exe, lld-link) reads, for
# Visual Studio projects, and the opccomn.def it comes from. Nothing is kept by hand:
# - the names are the export table of the built DLL (the standard COM entry points PRIVATE);
# - whether a name is a function or data (DATA in the .def), and on x86 the __stdcall decoration the
#   callers' object files would use (`_DllGetClassObject@12`, though that one is PRIVATE; the import
#   name stays undecorated), come from the symbols the same build's static library defines, i.e. from
#   the implementation;
# - the identifiers (IID_..., CATID_..., CLSID_...) are also put into opccomn.lib as ordinary members,
#   one object file per symbol, compiled from src/c/opccomn_guids.c (generated with the header). A
#   program whose headers declare them as MIDL does (`EXTERN_C const IID IID_IOPCCommon;`, no
#   dllimport) links them from there; one that declares them __declspec(dllimport) gets them from the
#   DLL; one that links the OPC Foundation's opccomn_i.c keeps its own definition, and the library's
#   member is never pulled.
#
# Usage: scripts/msvc-implib.sh x64|x86 DLL STATIC_LIBRARY OUT_DIR
# Tools (override through the environment): OPCCOMN_DLLTOOL (llvm-dlltool), OPCCOMN_LLVM_LIB (llvm-lib),
# OPCCOMN_NM (<triple>-nm), OPCCOMN_OBJDUMP (x86_64-w64-mingw32-objdump), CC (the mingw C compiler of ARCH).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[ "$#" -eq 4 ] || { echo "usage: $0 x64|x86 DLL STATIC_LIBRARY OUT_DIR" >&2; exit 2; }
arch=$1 dll=$2 staticlib=$3 out=$4
case "$arch" in
    x64) machine=i386:x86-64 prefix="" triple=x86_64-w64-mingw32 ;;
    x86) machine=i386 prefix=_ triple=i686-w64-mingw32 ;;
    *) echo "$0: unknown architecture $arch (x64 or x86)" >&2; exit 2 ;;
esac
dlltool=${OPCCOMN_DLLTOOL:-llvm-dlltool}
llvm_lib=${OPCCOMN_LLVM_LIB:-llvm-lib}
cc=${CC:-$triple-gcc}
# GNU nm: LLVM's reads the bitcode rustc leaves in the standard library's objects and may not know its
# version.
nm=${OPCCOMN_NM:-$triple-nm}
objdump=${OPCCOMN_OBJDUMP:-x86_64-w64-mingw32-objdump}
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The export table, in its order.
"$objdump" -p "$dll" | sed -n '/^\[Ordinal\/Name Pointer\] Table/,/^$/p' |
    sed -nE 's/^\s*\[ *[0-9]+\] ([A-Za-z_][A-Za-z0-9_]*)$/\1/p' >"$work/exports"
[ -s "$work/exports" ] || { echo "$0: $dll has no exports" >&2; exit 1; }
"$nm" --defined-only "$staticlib" 2>/dev/null | awk 'NF == 3 { print $2, $3 }' >"$work/symbols"

# One .def line per export: `Name`, `Name@N` (x86 __stdcall) or `Name DATA`; the standard COM entry
# points PRIVATE (exported by the DLL, not offered for linking: a server with its own .def naming
# DllRegisterServer must bind its own function, never opccomn's; the OpcDll* names stay linkable).
awk -v prefix="$prefix" -v lib="$staticlib" '
    NR == FNR { order[++n] = $0; want[$0] = 1; next }
    {
        type = $1; sym = $2
        if (prefix != "") { if (substr(sym, 1, 1) != prefix) next; sym = substr(sym, 2) }
        decoration = ""
        if (match(sym, /@[0-9]+$/)) { decoration = substr(sym, RSTART); sym = substr(sym, 1, RSTART - 1) }
        if (!(sym in want)) next
        if (type == "T") function_of[sym] = decoration
        else if (type ~ /^[RDB]$/) data[sym] = 1
    }
    END {
        print "LIBRARY opccomn.dll"
        print "EXPORTS"
        for (i = 1; i <= n; i++) {
            name = order[i]
            if (name ~ /^Dll(GetClassObject|CanUnloadNow|RegisterServer|UnregisterServer|Install)$/ && name in function_of)
                print "    " name function_of[name] " PRIVATE"
            else if (name in function_of) print "    " name function_of[name]
            else if (name in data) print "    " name " DATA"
            else { print "msvc-implib: " name " is exported but not defined in " lib > "/dev/stderr"; failed = 1 }
        }
        exit failed
    }' "$work/exports" "$work/symbols" >"$out/opccomn.def"

"$dlltool" -m "$machine" -k -d "$out/opccomn.def" -l "$work/imports.lib"

# One member per identifier the DLL exports as data.
members=()
guids="$root/src/c/opccomn_guids.c"
if [ -f "$guids" ]; then
    count=$(sed -nE 's/^#define OPCCOMN_GUID_COUNT ([0-9]+)$/\1/p' "$guids")
    for ((i = 1; i <= count; i++)); do
        obj="$work/guid_$i.obj"
        "$cc" -c -O2 -fno-ident -I"$root/include" -DOPCCOMN_GUID_ONLY="$i" -o "$obj" "$guids"
        sym=$("$nm" --defined-only "$obj" | awk -v prefix="$prefix" '$2 ~ /^[RDB]$/ && substr($3, 1, length(prefix)) == prefix { print substr($3, length(prefix) + 1) }')
        # Entries for other platforms compile to nothing; keep only what the DLL exports.
        [ -n "$sym" ] && grep -qx "$sym DATA" <(sed 's/^ *//' "$out/opccomn.def") && members+=("$obj")
    done
fi
"$llvm_lib" /machine:"$arch" /out:"$out/opccomn.lib" "$work/imports.lib" "${members[@]}"
echo "opccomn.lib ($arch): $(grep -c '^    ' "$out/opccomn.def") exports, $(grep -c ' DATA$' "$out/opccomn.def") of them data, ${#members[@]} identifier objects"
