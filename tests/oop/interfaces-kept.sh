#!/bin/sh
# The EXE host keeps the interfaces it serves registered with the RPC runtime while it serves
# (src/server/exe/keep.rs): clients that create, call once and release at once, again and again,
# never make the host's process unregister the interface they called, the moment in which Wine's
# runtime can lose the end of that call and hang every later activation of the server.
#
# Runs `test_reconnect -burst browser server` (the server browser and the test server, both on the
# host) under Wine's rpc trace, which the servers COM starts inherit, and checks in each server
# process: IOPCServerList2 (the browser) and IOPCCommon (the test server) registered, and
# unregistered at most once (when the process ends), however many clients came and went.
#
# Usage: interfaces-kept.sh [EMULATOR...] TEST_RECONNECT_EXE
out=$(mktemp) && trace=$(mktemp) || exit 1
trap 'rm -f "$out" "$trace"' EXIT
# The trace goes to standard error, the test's own output to $out; only the registration lines are kept.
{ WINEDEBUG=+pid,trace+rpc "$@" -burst browser server 2>&1 >&3 3>&- |
    grep -E 'RpcServerRegisterIf3  interface id|RpcServerUnregisterIf \(IfSpec' >"$trace"; } 3>"$out"
cat "$out"
# (The pipeline's status is grep's: the test's own is its result line.)
grep -qE '^test_reconnect: [0-9]+ passed, 0 failed' "$out" || { echo "interfaces-kept: test_reconnect failed" >&2; exit 1; }
failed=0
for iid in 9dd0b56c-ad9e-43ee-8305-487f3188bf7a f31dfde2-07b6-11d2-b2d8-0060083ba1fb; do
    # The processes that registered it (the trace's lines begin with process:thread).
    pids=$(grep -F "interface id: {$iid}" "$trace" | cut -d: -f1 | sort -u)
    [ -n "$pids" ] || { echo "interfaces-kept: no process registered {$iid} (is the rpc trace there?)" >&2; failed=1; }
    for pid in $pids; do
        n=$(grep -F "({$iid})" "$trace" | grep -c "^$pid:") || true
        echo "interfaces-kept: process $pid registered {$iid} and unregistered it $n times"
        [ "$n" -le 1 ] || failed=1
    done
done
[ "$failed" = 0 ] || { echo "interfaces-kept: an interface was unregistered while its server served" >&2; exit 1; }
echo "interfaces-kept: every served interface stayed registered while its server served"
