#!/usr/bin/env bash
# Checks that a built library exports every function and data item include/opccomn.h declares.
# Usage: scripts/check-exports.sh path/to/libopccomn.so|opccomn.dll
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
lib=$1
header="$root/include/opccomn.h"
# Items under `#if !defined(_WIN32)` (the standard COM identifiers off Windows) are not part of the DLL.
case "$lib" in
    *.dll) header_text=$(sed '/^#if !defined(_WIN32)$/,/^#endif$/d' "$header") ;;
    *) header_text=$(cat "$header") ;;
esac
# cbindgen writes each declaration on one line, starting in column 0.
declared=$( { grep -E '^[A-Za-z_][A-Za-z0-9_ *]*[ *][A-Za-z_][A-Za-z0-9_]*\(.*\);$' <<<"$header_text" | grep -v '^typedef' |
                sed -E 's/^.*[ *]([A-Za-z_][A-Za-z0-9_]*)\(.*$/\1/';
              grep -E '^extern const ' <<<"$header_text" | sed -E 's/^.*[ *]([A-Za-z_][A-Za-z0-9_]*);$/\1/'; } | sort -u)
case "$lib" in
    *.dll) exported=$(x86_64-w64-mingw32-objdump -p "$lib" | sed -nE 's/^\s*\[ *[0-9]+\] ([A-Za-z_][A-Za-z0-9_]*)$/\1/p') ;;
    *) exported=$(nm -D --defined-only "$lib" | awk '{print $3}') ;;
esac
missing=0
for name in $declared OpcCommonCreate OpcGetErrorString OpcTaskMemAlloc OpcTaskMemFree; do
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
echo "exports of $(basename "$lib"): all $count declarations of opccomn.h exported"
