#!/usr/bin/env bash
# Runs the library's tests under Miri with isolation on, under Stacked Borrows and under Tree Borrows
# (`-Zmiri-tree-borrows`). Stacked Borrows runs every test that does not call the operating system
# (those that do are `#[cfg_attr(miri, ignore)]` with the reason, and fewer cases run under
# `cfg(miri)`; see docs/dev/testing.md). Tree Borrows, the second opinion on aliasing, runs the tests
# of the code that shares raw pointers between objects, interfaces and threads: the COM core and
# every COM object (com, common, shutdown, proxy, serverlist, module, server, security, locale,
# errors) and the thread stress test; the pattern matcher and the registry, whose unsafe code only
# reads the caller's strings and structures, run under Stacked Borrows only. Any report of undefined behaviour, a leak, a
# failed or missing test fails the run. Prints, per model, how many tests ran and how long it took.
#
# Usage: scripts/miri.sh [stacked|tree]...     (both when none is given; test.sh runs both)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh
need_miri

models=("$@")
[ "${#models[@]}" -eq 0 ] && models=(stacked tree)
declare -A flags=([stacked]="" [tree]="-Zmiri-tree-borrows")
# Test-name filters per model (libtest: a test runs when its path contains one of them).
declare -A filters=([stacked]="" [tree]="com:: common:: shutdown:: proxy:: serverlist:: module:: server:: security:: locale:: errors:: stress_tests")
# Tests left out per model among those the filters take: the NDR checks (proxy::ndr, safe code over
# byte slices, every cut of each message) run under Stacked Borrows only.
declare -A skips=([stacked]="" [tree]="--skip proxy::ndr::")
for m in "${models[@]}"; do
    [ -n "${flags[$m]+set}" ] || { echo "usage: scripts/miri.sh [stacked|tree]..." >&2; exit 2; }
done

out="$root/build/miri"
mkdir -p "$out"
started=$SECONDS
# The sysroot and the crate, built once for both runs (at most 2 jobs).
cargo +"$OPCCOMN_NIGHTLY" miri setup >/dev/null 2>&1 || cargo +"$OPCCOMN_NIGHTLY" miri setup
cargo +"$OPCCOMN_NIGHTLY" miri test -q --lib -j2 --no-run

declare -A pid
for m in "${models[@]}"; do
    rm -f "$out/$m.log" "$out/$m.rc" "$out/$m.seconds"
    (
        t=$SECONDS rc=0
        # shellcheck disable=SC2086 # the filters are words
        MIRIFLAGS="${flags[$m]} ${MIRIFLAGS:-}" cargo +"$OPCCOMN_NIGHTLY" miri test --lib -j2 -- --test-threads=1 \
            ${filters[$m]} ${skips[$m]} >"$out/$m.log" 2>&1 || rc=$?
        echo "$rc" >"$out/$m.rc"
        echo $((SECONDS - t)) >"$out/$m.seconds"
    ) &
    pid[$m]=$!
done

failed=0
for m in "${models[@]}"; do
    wait "${pid[$m]}" || true
    rc=$(cat "$out/$m.rc" 2>/dev/null || echo "none")
    secs=$(cat "$out/$m.seconds" 2>/dev/null || echo "?")
    result=$(grep -E '^test result: ' "$out/$m.log" | tail -1 || true)
    # Miri's reports (undefined behaviour, leaks, unsupported operations, deadlocks) are `error:` lines;
    # cargo's own summary lines are not counted.
    reports=$(grep -E '^error: ' "$out/$m.log" | grep -cvE '^error: (test failed, to rerun|aborting due to)' || true)
    # test result: ok. N passed; 0 failed; M ignored; 0 measured; F filtered out; ...
    passed=$(sed -nE 's/^test result: ok\. ([0-9]+) passed; 0 failed; ([0-9]+) ignored; 0 measured; ([0-9]+) filtered out.*/\1/p' <<<"$result")
    ignored=$(sed -nE 's/^test result: ok\. ([0-9]+) passed; 0 failed; ([0-9]+) ignored; 0 measured; ([0-9]+) filtered out.*/\2/p' <<<"$result")
    filtered=$(sed -nE 's/^test result: ok\. ([0-9]+) passed; 0 failed; ([0-9]+) ignored; 0 measured; ([0-9]+) filtered out.*/\3/p' <<<"$result")
    # Stacked Borrows runs everything: a test filtered out there would be a bug of this script.
    [ -n "${filters[$m]}" ] || [ "${filtered:-0}" = 0 ] || passed=
    if [ "$rc" = 0 ] && [ "$reports" = 0 ] && [ -n "$passed" ] && [ "$passed" -gt 0 ]; then
        scope="every test"
        [ -z "${filters[$m]}" ] || scope="the COM objects' tests, $filtered others left to Stacked Borrows"
        echo "miri ($m borrows, $scope): $passed tests passed, $ignored ignored (reasons in the source), 0 reports, ${secs} s"
    else
        failed=1
        echo "miri ($m borrows): FAILED (exit status $rc, $reports reports, result: ${result:-none}); from $out/$m.log:" >&2
        grep -m1 -B2 -A40 -E '^error|panicked|FAILED' "$out/$m.log" >&2 || tail -n 40 "$out/$m.log" >&2
    fi
done
echo "miri: $((SECONDS - started)) s in all (build and both models)"
exit "$failed"
