#!/usr/bin/env bash
# Benchmark of round trips across processes under Wine: GetErrorString, and EnumClassesOfCategories +
# Next of 100 classes, through opccomn.dll's proxy/stub and through the widl-generated stand-in for
# the Foundation's opccomn_ps.dll, in the same run (benches/cross_process_bench.c; goal <= 1.1x, a GOAL
# line per goal; exit code 1 when one is missed).
#
# Usage: scripts/bench-cross-process.sh [N]   (N GetErrorString and N/5 Enum+Next per contender in all, in 51
# interleaved rounds; default 10200)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh
need_windows_tools
build="$root/build/windows"
cmake -S . -B "$build" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-x86_64.cmake" >/dev/null
cmake --build "$build" -j2 --target cross_process_bench >/dev/null
. scripts/wine-env.sh "$build"
cd "$build/bin"
wine cross_process_bench.exe "$@"
