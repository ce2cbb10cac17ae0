#!/usr/bin/env bash
# Benchmark of round trips across processes under Wine: GetErrorString, and EnumClassesOfCategories +
# Next of 100 classes, through opccomn.dll's proxy/stub and through the widl-generated stand-in for
# the Foundation's opccomn_ps.dll, in the same run (benches/cross_process_bench.c; goal <= 1.1x, a GOAL
# line per goal; exit code 1 when one is missed).
#
# Usage: scripts/bench-cross-process.sh [--record] [N] [OPTION...]   (N GetErrorString and N/5
# Enum+Next per contender in all, in 51 interleaved rounds; default 10200). --record also writes the
# output, with the commit and the machine's load, to docs/dev/figures/bench-cross-process.txt, the
# figures docs/dev/benchmarks.md shows. OPTIONs go to the benchmark: --rounds R, --budget-s S (the
# rounds stop after S seconds, 1200 by default), --stall-s S (a batch of round trips that takes
# longer is a stall, 60 by default).
#
# Bounded in time: the benchmark ends itself after a stall (exit code 3, the figures of the rounds
# complete so far marked partial); should it not, this script kills it after BENCH_TIMEOUT_S seconds
# (2400 by default), removes the classes it registered (cross_process_bench --unregister) and says
# so. The benchmark registers its proxy/stubs in its own processes only: the machine's proxy/stub
# registration is left as it is.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh
need_windows_tools
build="$root/build/windows"
cmake -S . -B "$build" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-x86_64.cmake" >/dev/null
cmake --build "$build" -j2 --target cross_process_bench >/dev/null
. scripts/wine-env.sh "$build"
record=0
if [ "${1:-}" = --record ]; then
    record=1
    shift
fi
measure() {
    echo "machine: $(nproc) cores, $(uptime | sed 's/.*load average/load average/'), $(date -u '+%Y-%m-%d %H:%M UTC')"
    # The output goes to a file, not a pipe: the test servers COM starts inherit the benchmark's
    # standard output and live on after it, and a pipe's reader would wait for them.
    local rc=0 out limit=${BENCH_TIMEOUT_S:-2400}
    out=$(mktemp)
    (cd "$build/bin" && timeout -k 30 "$limit" wine cross_process_bench.exe "$@") >"$out" 2>&1 </dev/null || rc=$?
    tr -d '\r' <"$out"
    rm -f "$out"
    case "$rc" in
        3) echo "bench-cross-process: the benchmark stalled and ended itself: its figures above are partial" ;;
        124 | 137)
            echo "bench-cross-process: the benchmark did not end within $limit s (BENCH_TIMEOUT_S) and was killed: what it printed is above"
            (cd "$build/bin" && wine cross_process_bench.exe --unregister) </dev/null 2>&1 | tr -d '\r'
            ;;
    esac
    echo "end: $(uptime | sed 's/.*load average/load average/'), $(date -u '+%Y-%m-%d %H:%M UTC')"
    return "$rc"
}
if [ "$record" = 1 ]; then
    mkdir -p docs/dev/figures
    {
        echo "# Printed by: scripts/bench-cross-process.sh --record $*"
        echo "# commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- src benches tests/oop || echo ', with uncommitted changes in src/, benches/ or tests/oop/')"
        measure "$@" 2>&1
    } | tee docs/dev/figures/bench-cross-process.txt
else
    measure "$@"
fi
