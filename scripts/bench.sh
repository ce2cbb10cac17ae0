#!/usr/bin/env bash
# Runs the benchmarks (never part of scripts/test.sh; CI only builds them). Each prints its table,
# one GOAL line per goal with "met" or "NOT MET", and exits with 1 when a goal is missed; this script
# exits with 1 when any benchmark did.
#
# Usage: scripts/bench.sh [--wine] [NAME...] [WORD...]
#   NAME     match-pattern, error-string, server-list (default: every one the platform runs;
#            server-list needs the Windows registry, so it runs with --wine only)
#   WORD     passed to the benchmarks: `scripts/bench.sh match-pattern typical Device` runs only the
#            typical set of match-pattern, and of it only the filters containing "Device"
#   --wine   the Windows DLL (x86_64, mingw-w64) under Wine instead of the Linux library
# Environment: BENCH_ROUNDS (default 31), BENCH_ROUND_MS (default 2) for every benchmark.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

wine=0
names=()
words=()
for arg in "$@"; do
    case "$arg" in
        --wine) wine=1 ;;
        match-pattern | error-string | server-list) names+=("$arg") ;;
        -*) echo "usage: scripts/bench.sh [--wine] [match-pattern|error-string|server-list]... [word...]" >&2; exit 2 ;;
        *) words+=("$arg") ;;
    esac
done
if [ ${#names[@]} = 0 ]; then
    names=(match-pattern error-string)
    [ "$wine" = 1 ] && names+=(server-list)
fi

if [ "$wine" = 1 ]; then
    build="$root/build/bench-windows"
    cmake -S . -B "$build" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-x86_64.cmake" >/dev/null
    . scripts/wine-env.sh "$build"
    run() { wine "$build/bin/$1.exe" "${words[@]}"; }
else
    build="$root/build/bench"
    cmake -S . -B "$build" -DOPCCOMN_SANITIZE=OFF >/dev/null
    run() { "$build/bin/$1" "${words[@]}"; }
fi
targets=()
for name in "${names[@]}"; do
    targets+=("bench_${name//-/_}")
done
cmake --build "$build" -j2 --target "${targets[@]}" >/dev/null

echo "machine: $(nproc) cores, $(uptime | sed 's/.*load average/load average/'), $(date -u '+%Y-%m-%d %H:%M UTC')"
status=0
for target in "${targets[@]}"; do
    printf '\n==== %s%s\n' "$target" "$([ "$wine" = 1 ] && echo ' (Windows DLL under Wine)')"
    run "$target" || status=1
done
exit "$status"
