#!/bin/sh
# Benchmark of GetErrorString (issue 3): builds the release library and benches/error_string_bench.c,
# then prints ns per call for IOPCCommon::GetErrorString (through the vtable, allocation and free
# included) and for a plain C baseline measured in the same run, and their ratio (goal <= 1.5x).
# Usage: scripts/bench-error-strings.sh [calls per round]
set -eu
cd "$(dirname "$0")/.."
cargo build --release --lib --quiet
out=target/release/bench
mkdir -p "$out"
${CC:-cc} -std=c11 -D_POSIX_C_SOURCE=200809L -O2 -Iinclude benches/error_string_bench.c \
    -Ltarget/release -lopccomn -Wl,-rpath,"$PWD/target/release" -o "$out/error_string_bench"
"$out/error_string_bench" "$@"
