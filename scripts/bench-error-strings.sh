#!/usr/bin/env bash
# Benchmark of GetErrorString: builds the release library and benches/error_string_bench.c, then
# prints ns per call for IOPCCommon::GetErrorString (through the vtable, allocation and free included)
# and for a plain C baseline measured in the same run, and their ratio (goal <= 1.5x).
#
# Usage: scripts/bench-error-strings.sh [--wine] [calls per round]
#   --wine   the Windows DLL (CoTaskMemAlloc on both sides) under Wine instead of the Linux library
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
if [ "${1:-}" = "--wine" ]; then
    shift
    cargo build --release --lib --quiet --target x86_64-pc-windows-gnu
    out="$root/target/x86_64-pc-windows-gnu/release"
    x86_64-w64-mingw32-gcc -std=c11 -O2 -Iinclude benches/error_string_bench.c "$out/opccomn.dll" \
        -static-libgcc -o "$out/error_string_bench.exe"
    . scripts/wine-env.sh "$root/build/windows"
    wine "$out/error_string_bench.exe" "$@"
else
    cargo build --release --lib --quiet
    out="$root/target/release"
    ${CC:-cc} -std=c11 -O2 -Iinclude benches/error_string_bench.c -L"$out" -lopccomn -Wl,-rpath,"$out" \
        -o "$out/error_string_bench"
    "$out/error_string_bench" "$@"
fi
