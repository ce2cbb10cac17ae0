#!/usr/bin/env bash
# Runs the benchmarks (never part of scripts/test.sh; CI only builds them). Each prints its table,
# one GOAL line per goal with "met" or "NOT MET", and exits with 1 when a goal is missed; this script
# exits with 1 when any benchmark did.
#
# Usage: scripts/bench.sh [--record] [--wine | --wine32] [NAME...] [WORD...]
#   --record the run's output, with the commit, the machine and its load, also goes to
#            docs/dev/figures/bench-<linux|windows-x64|windows-x86>.txt (with NAMEs given,
#            bench-<...>-<NAME>[-<NAME>...].txt), the figures the docs show
#            (docs/dev/benchmarks.md): commit it; figures are never copied into the docs by hand
#   NAME     match-pattern, error-string, server-list, browser, da (default: match-pattern and
#            error-string on Linux; all five under Wine, as server-list and browser need the Windows
#            registry, browser also the browser service and COM, da (the Data Access round trips
#            through opccomn.dll's proxy/stub against the widl stand-in's, benches/da_bench.c) COM
#            across processes)
#   WORD     passed to the benchmarks: `scripts/bench.sh match-pattern typical Device` runs only the
#            typical set of match-pattern, and of it only the filters containing "Device"
#   --wine   the Windows DLL (x86_64, mingw-w64) under Wine instead of the Linux library
#   --wine32 the 32-bit Windows DLL (i686, mingw-w64) under 32-bit Wine; fails (exit 2) when 32-bit
#            Wine cannot run a 32-bit program (without wine32:i386 `wine prog32.exe` exits 0 silently)
# Every benchmark must print its closing line ("bench_NAME: N goals, ..."): one that printed nothing
# did not run, and fails the run. Each benchmark is stopped after BENCH_TIMEOUT_S seconds (1800 by
# default): the figures of the cases it finished are above the line that says so, and the run fails.
# Environment: BENCH_ROUNDS (default 31), BENCH_ROUND_MS (default 2) for every benchmark;
# BENCH_TIMEOUT_S. The cross-process benchmark has its own script: scripts/bench-cross-process.sh.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

wine=0
record=0
arch=x86_64
names=()
named=""
words=()
for arg in "$@"; do
    case "$arg" in
        --record) record=1 ;;
        --wine) wine=1 ;;
        --wine32) wine=1; arch=x86 ;;
        match-pattern | error-string | server-list | browser | da) names+=("$arg"); named="$named-$arg" ;;
        -*) echo "usage: scripts/bench.sh [--wine|--wine32] [match-pattern|error-string|server-list|browser|da]... [word...]" >&2; exit 2 ;;
        *) words+=("$arg") ;;
    esac
done
if [ ${#names[@]} = 0 ]; then
    # Linux: MatchPattern and GetErrorString. Under Wine all five: the server list's and the
    # browser's goals are stated for the Windows registry, the DA round trips' for COM.
    if [ "$wine" = 1 ]; then
        names=(match-pattern error-string server-list browser da)
    else
        names=(match-pattern error-string)
    fi
fi

if [ "$wine" = 1 ]; then
    if [ "$arch" = x86 ]; then
        build="$root/build/bench-windows-x86"
        toolchain="$root/cmake/mingw-w64-i686.cmake"
    else
        build="$root/build/bench-windows"
        toolchain="$root/cmake/mingw-w64-x86_64.cmake"
    fi
    if [ ! -f "$toolchain" ]; then
        echo "scripts/bench.sh: no $toolchain: this tree cannot build that Windows DLL" >&2
        exit 2
    fi
    cmake -S . -B "$build" -DCMAKE_TOOLCHAIN_FILE="$toolchain" >/dev/null
    # 32-bit Wine is installed before the prefix is made (scripts/wine-env.sh).
    if [ "$arch" = x86 ]; then
        . scripts/deps.sh
        if ! need_wine32; then
            echo "scripts/bench.sh: NOT RUN: 32-bit Wine is not available: $wine32_missing" >&2
            exit 2
        fi
    fi
    . scripts/wine-env.sh "$build"
    if [ "$arch" = x86 ]; then
        i686-w64-mingw32-gcc -O2 -o "$build/wow64_canary.exe" tests/wine/wow64_canary.c
        canary=$(wine "$build/wow64_canary.exe" 2>&1 | tr -d '\r') || true
        if [ "$canary" != "wow64 canary: 32-bit process, WOW64 yes" ]; then
            echo "scripts/bench.sh: NOT RUN: wine32:i386 is installed, but a 32-bit program did not run (it printed: '$canary')" >&2
            exit 2
        fi
    fi
    run() {
        if [ "$1" = da_bench ]; then
            # Its output goes to a file, not a pipe: the DA servers COM starts inherit its standard
            # output (it waits for them to end, but one that hangs would keep a pipe's reader
            # waiting). It takes no words; BENCH_ROUNDS sets its rounds.
            local out rc=0
            out=$(mktemp)
            (cd "$build/bin" && timeout -k 30 "$limit" wine da_bench.exe ${BENCH_ROUNDS:+--rounds "$BENCH_ROUNDS"}) \
                >"$out" 2>&1 </dev/null || rc=$?
            tr -d '\r' <"$out"
            rm -f "$out"
            if [ "$rc" = 124 ] || [ "$rc" = 137 ]; then
                (cd "$build/bin" && wine da_bench.exe --unregister) </dev/null 2>&1 | tr -d '\r'
            fi
            return "$rc"
        fi
        timeout -k 30 "$limit" wine "$build/bin/$1.exe" "${words[@]}"
    }
else
    build="$root/build/bench"
    cmake -S . -B "$build" -DOPCCOMN_SANITIZE=OFF >/dev/null
    run() { timeout -k 30 "$limit" "$build/bin/$1" "${words[@]}"; }
fi
limit=${BENCH_TIMEOUT_S:-1800}
targets=()
for name in "${names[@]}"; do
    if [ "$name" = da ]; then
        if [ "$wine" != 1 ]; then
            echo "scripts/bench.sh: da runs under Wine only (--wine or --wine32)" >&2
            exit 2
        fi
        targets+=(da_bench)
    else
        targets+=("bench_${name//-/_}")
    fi
done
cmake --build "$build" -j2 --target "${targets[@]}" >/dev/null

measure() {
    echo "machine: $(nproc) cores, $(uptime | sed 's/.*load average/load average/'), $(date -u '+%Y-%m-%d %H:%M UTC')"
    local status=0 log target rc
    log=$(mktemp)
    for target in "${targets[@]}"; do
        printf '\n==== %s%s\n' "$target" "$([ "$wine" = 1 ] && echo " (Windows $arch DLL under Wine)")"
        { rc=0; run "$target" || rc=$?; echo "$rc" >"$log.rc"; } | tee "$log"
        rc=$(cat "$log.rc")
        [ "$rc" = 0 ] || status=1
        if [ "$rc" = 124 ] || [ "$rc" = 137 ]; then
            echo "scripts/bench.sh: $target did not end within $limit s (BENCH_TIMEOUT_S) and was stopped: the figures above are those of the cases it finished" >&2
        fi
        if ! tr -d '\r' <"$log" | grep -qE "^$target: [0-9]+ goals"; then
            echo "scripts/bench.sh: $target printed no closing line: it did not run to its end" >&2
            status=1
        fi
    done
    rm -f "$log" "$log.rc"
    echo "end: $(uptime | sed 's/.*load average/load average/'), $(date -u '+%Y-%m-%d %H:%M UTC')"
    return "$status"
}

if [ "$record" = 1 ]; then
    variant=linux
    [ "$wine" = 1 ] && variant="windows-$([ "$arch" = x86 ] && echo x86 || echo x64)"
    mkdir -p docs/dev/figures
    figures="docs/dev/figures/bench-$variant$named.txt"
    {
        echo "# Printed by: scripts/bench.sh $*"
        echo "# commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)$(git diff --quiet HEAD -- src benches 2>/dev/null || echo ', with uncommitted changes in src/ or benches/')"
        measure 2>&1
    } | tee "$figures"
else
    measure
fi
