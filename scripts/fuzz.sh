#!/usr/bin/env bash
# Fuzzes every parser of the library for a bounded time: MatchPattern (all entry points against the
# reference matcher), `.reg` import (OpcRegistryApply), EXE command lines (OpcParseCommandLine) and
# version strings (OpcVersionParse/Format), the SDDL of AppID permissions (registry::sddl), the
# proxy/stub's checks of NDR requests and replies (proxy::wire, against the hand-written checks they
# replaced), the interpreter of NDR layouts over a test IDL that uses every construct (proxy::ndr) and
# over the layouts of every interface the proxy/stub serves, DA's, A&E's and HDA's included (layouts).
# The targets are in fuzz/fuzz_targets/, their committed seed corpus in fuzz/seeds/<target>/. Built
# with nightly Rust, libFuzzer (crate libfuzzer-sys) and AddressSanitizer; a crash, a failed assertion, a leak or a
# timeout is a finding and fails the run (the input is kept in build/fuzz/artifacts/).
#
# Usage: scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]    (default 30 s each, every target)
# Reproduce a finding: build/fuzz/target/x86_64-unknown-linux-gnu/release/<target> <artifact>
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh
need_linux_tools
need_fuzz_tools

seconds=${1:-${OPCCOMN_FUZZ_SECONDS:-30}}
shift || true
targets=("$@")
[ "${#targets[@]}" -eq 0 ] && targets=(pattern regfile cmdline version sddl wire ndr layouts)

out="$root/build/fuzz"
triple=x86_64-unknown-linux-gnu
# What cargo-fuzz passes: libFuzzer's coverage instrumentation, ASan, debug assertions and overflow
# checks. With an explicit --target these flags reach the fuzzed code only, not build scripts.
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares -Zsanitizer=address -Cdebug-assertions -Coverflow-checks"
cargo +"$OPCCOMN_NIGHTLY" build --release --locked -j2 --manifest-path fuzz/Cargo.toml --target "$triple" \
    --target-dir "$out/target" --bins
unset RUSTFLAGS

# Per target: the longest input (the pattern reference is quadratic) and the time one input may take.
max_len() {
    case "$1" in
        pattern) echo 512 ;;
        # Room for keys deeper than the registry allows (a `[-key]` of 20,000 levels is a seed).
        regfile) echo 45000 ;;
        *) echo 4096 ;;
    esac
}

export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:symbolize=1
# One target: its libFuzzer run, its exit status in $out/$t.status.
run_target() {
    local t=$1 corpus="$out/corpus/$1" status=0   # corpus: what this run found, beside the committed seeds
    mkdir -p "$corpus" "$out/artifacts"
    "$out/target/$triple/release/$t" "$corpus" "fuzz/seeds/$t" -max_total_time="$seconds" \
        -max_len="$(max_len "$t")" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
        -artifact_prefix="$out/artifacts/$t-" >"$out/$t.log" 2>&1 || status=$?
    echo "$status" >"$out/$t.status"
}
# Two targets at a time (one per core); each still gets its full time.
for ((i = 0; i < ${#targets[@]}; i += 2)); do
    pids=()
    for t in "${targets[@]:i:2}"; do
        rm -f "$out/$t.status"
        run_target "$t" &
        pids+=($!)
    done
    wait "${pids[@]}" || true
done
total=0
for t in "${targets[@]}"; do
    log="$out/$t.log"
    status=$(cat "$out/$t.status" 2>/dev/null || echo "none")
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    if [ "$status" != 0 ]; then
        tail -40 "$log" >&2
        echo "fuzz $t: FINDING after ${runs:-?} cases (exit $status); input in $out/artifacts/" >&2
        exit 1
    fi
    if [ -z "$runs" ]; then
        tail -20 "$log" >&2
        echo "fuzz $t: no statistics in $log" >&2
        exit 1
    fi
    total=$((total + runs))
    echo "fuzz $t: $runs cases in ${seconds} s, 0 findings ($(ls "fuzz/seeds/$t" | wc -l) seeds)"
done
echo "fuzz: $total cases over ${#targets[@]} targets, 0 findings"
