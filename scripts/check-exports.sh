#!/usr/bin/env bash
# Checks that a built library exports every function and data item include/opccomn/opccomn.h declares.
# Usage: scripts/check-exports.sh path/to/libopccomn.so|opccomn.dll
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
lib=$1
header="$root/include/opccomn/opccomn.h"
# Items under `#if !defined(_WIN32)` (the standard COM identifiers off Windows) are not part of the DLL;
# such blocks nest (#if/#ifdef/#ifndef ... #endif), so they are skipped by depth.
case "$lib" in
    *.dll) header_text=$(awk '
        skip == 0 && /^#if !defined\(_WIN32\)/ { skip = 1; next }
        skip > 0 && /^#if/ { skip++; next }
        skip > 0 && /^#endif/ { skip--; next }
        skip == 0 { print }' "$header") ;;
    *) header_text=$(cat "$header") ;;
esac
# Functions: one declaration per line, starting in column 0, with the calling convention macro before the
# name. Data: `EXTERN_C const IID IID_IOPCCommon;`, as MIDL declares it.
declared=$( { grep -E '^[A-Za-z_][A-Za-z0-9_ *]*[ *][A-Za-z_][A-Za-z0-9_]*\(.*\);$' <<<"$header_text" | grep -v '^typedef' |
                sed -E 's/^.*[ *]([A-Za-z_][A-Za-z0-9_]*)\(.*$/\1/';
              grep -E '^EXTERN_C const [A-Za-z_]+ [A-Za-z_][A-Za-z0-9_]*;$' <<<"$header_text" |
                sed -E 's/^.* ([A-Za-z_][A-Za-z0-9_]*);$/\1/'; } | sort -u)
case "$lib" in
    *.dll) exported=$(x86_64-w64-mingw32-objdump -p "$lib" | sed -nE 's/^\s*\[ *[0-9]+\] ([A-Za-z_][A-Za-z0-9_]*)$/\1/p') ;;
    *) exported=$(nm -D --defined-only "$lib" | awk '{print $3}') ;;
esac
missing=0
for name in $declared OpcCommonCreate OpcGetErrorString OpcTaskMemAlloc OpcTaskMemFree IID_IOPCCommon; do
    if ! grep -qx "$name" <<<"$exported"; then
        echo "$lib does not export $name" >&2
        missing=$((missing + 1))
    fi
done
count=$(wc -w <<<"$declared")
if [ "$missing" -ne 0 ]; then
    echo "exports: $((count - missing)) passed, $missing failed"
    exit 1
fi
echo "exports of $(basename "$lib"): all $count declarations of opccomn/opccomn.h exported"
