#!/usr/bin/env bash
# The conformance checker against servers with known defects and against the example server, under
# Wine's COM runtime: every seeded defect (tests/conformance/defects.txt) must be reported by exactly
# the check that names it, and the defect-free test server and the C++ example server must pass every
# check. The JSON and JUnit reports are validated (tests/conformance/check_report.py).
#
# Usage: scripts/test-conformance.sh BIN_DIR EXAMPLE_DIR [OTHER_CHECKER]
#   BIN_DIR      the Windows build's program directory: opccomn-check.exe, opccomn.dll, the test servers
#   EXAMPLE_DIR  the built C++ example (opccomn_example_inproc.dll, opccomn_example_server.exe), or -
#                for the defect servers only
#   OTHER_CHECKER  the opccomn-check.exe of the other architecture: run in-process (--context inproc)
#                against a server of this one, it must fail to create it and name the registry view
#                and the checker to use (CLSCTX_ALL would reach it through the DLL surrogate)
# Needs WINEPREFIX set up (scripts/wine-env.sh). Servers are registered one at a time and
# unregistered after their run, so no test server sees another's registration.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=$(cd "$1" && pwd)
example=$2
[ "$example" = - ] || example=$(cd "$example" && pwd)
out="$bin/conformance"
rm -rf "$out" && mkdir -p "$out"
check="$bin/opccomn-check.exe"
report="python3 $root/tests/conformance/check_report.py"
passed=0

# Whatever this script registers in the shared Wine prefix is taken back when it fails (a run that
# passes has unregistered each server after its checks), so that a failure here does not become a
# failure of the stages after it (whose tests compare the registry with what it was). Each step
# ignores what is not registered.
cleanup() {
    [ -d "$bin" ] || return 0
    (cd "$bin" && wine opccomn_browser.exe /UnregServer >/dev/null 2>&1) || true
    (cd "$bin" && wine regsvr32 /u /s /n /i:ProxyStub opccomn.dll >/dev/null 2>&1) || true
    (cd "$bin" && wine regsvr32 /u /s opccomn.dll >/dev/null 2>&1) || true
    if [ "$example" != - ]; then
        (cd "$example" && wine regsvr32 /u /s opccomn_example_inproc.dll >/dev/null 2>&1) || true
        (cd "$example" && wine opccomn_example_server.exe /UnregServer >/dev/null 2>&1) || true
    fi
}
trap 'status=$?; [ "$status" -eq 0 ] || cleanup' EXIT

# run_checker NAME FORMAT ARGS...: runs the checker, report in $out/NAME.FORMAT, exit code in $rc.
#
# Wine's own marshaling of IEnumConnections (a system interface: neither the server nor opccomn
# marshals it) returns, on a loaded machine, about one call in twenty, an undefined code from Next
# although the reply carried the connection (a trace of the client shows the CONNECTDATA read with
# the right cookie, then Next returning values such as 0x00780078 or 0x5839779A). The checker reports
# that as shutdown.enum-connections failed with "0 connection(s)"; such a run, and only such a run,
# is made again, at most twice, and said so.
run_checker() {
    local name=$1 format=$2 attempt
    shift 2
    for attempt in 1 2 3; do
        rc=0
        (cd "$bin" && timeout 120 wine "$check" "$@" --format "$format" </dev/null >"$out/$name.$format" 2>"$out/$name.$format.log") || rc=$?
        tr -d '\r' <"$out/$name.$format" >"$out/$name.$format.tmp" && mv "$out/$name.$format.tmp" "$out/$name.$format"
        [ "$attempt" -lt 3 ] && grep -q '0 connection(s), not that one (Next: ' "$out/$name.$format" || break
        echo "!!!! $name ($format): IEnumConnections::Next through Wine's proxy gave an undefined code (see docs/dev/testing.md): run again" >&2
    done
    if [ "$rc" -ne 0 ] && [ "$rc" -ne 1 ]; then
        echo "opccomn-check $* exited $rc" >&2
        cat "$out/$name.$format.log" >&2
        exit 1
    fi
}

# Ends the surrogate processes (dllhost.exe) of a test server class left running in this Wine prefix.
kill_surrogates() {
    local pid
    # (The AppID's braces are no pattern: the command line is compared as a fixed string.)
    for pid in $(pgrep -fi "dllhost\.exe" || true); do
        tr '\0' ' ' <"/proc/$pid/cmdline" 2>/dev/null | grep -qiF "/PROCESSID:$1" || continue
        if tr '\0' '\n' <"/proc/$pid/environ" 2>/dev/null | grep -qxF "WINEPREFIX=$WINEPREFIX"; then
            kill "$pid" 2>/dev/null || true
        fi
    done
}

# Out of process needs the OPC Common proxy/stub (OpcRegisterProxyStub), which opccomn.dll carries.
oop_available=1
grep -q OpcRegisterProxyStub "$bin/opccomn.dll" ||
    { echo "$bin/opccomn.dll has no proxy/stub (OpcRegisterProxyStub): the out-of-process checks cannot run" >&2; exit 1; }

# regsvr32 of a seeded server, with its exit code when it fails (3: the DLL did not load, 4: no
# DllRegisterServer, 5: DllRegisterServer failed). On a loaded machine Wine's regsvr32 has failed on
# such a DLL (twice in many runs, before its code was printed); the servers' own registration is
# tested in stage c-windows, not here, so a failure is said loudly and made once more, and a second
# failure ends the stage.
register_defect() {
    local dll=$1 attempt code
    for attempt in 1 2; do
        code=0
        (cd "$bin" && wine regsvr32 /s "$dll") || code=$?
        [ "$code" -eq 0 ] && return 0
        echo "!!!! regsvr32 $dll failed with exit code $code (attempt $attempt of 2)" >&2
    done
    exit 1
}

while read -r number name want flags; do
    case "$number" in '#'* | '') continue ;; esac
    dll="$bin/opccomn_defect_$name.dll"
    register_defect "$dll"
    args=("OpcComnTest.Defect.$name.1" --timeout 3000)
    warn=-
    oop=1
    for flag in $flags; do
        case "$flag" in
            hostile) args+=(--hostile) ;;
            dcom) args+=(--dcom) ;;
            warn=*) warn=${flag#warn=} ;;
            inproc-only) oop=0 ;;
            *) echo "defects.txt: unknown flag $flag" >&2; exit 1 ;;
        esac
    done
    start=$SECONDS
    run_checker "defect-$name" json "${args[@]}"
    $report json "$out/defect-$name.json" "$rc" "$want" "$warn"
    [ "$name" = hang-set-client-name ] && echo "  (the hung call was reported after the 3000 ms timeout; the run took $((SECONDS - start)) s)"
    # The text and JUnit reports of the first defect and of the server without one.
    # The text and JUnit reports too: the server without a defect, the first defect, the warning.
    if [ "$number" -le 1 ] || [ "$warn" != - ]; then
        run_checker "defect-$name" junit "${args[@]}"
        $report junit "$out/defect-$name.junit" "$rc" "$want" "$warn"
        run_checker "defect-$name" text "${args[@]}"
        $report text "$out/defect-$name.text" "$rc" "$want" "$warn"
    fi
    # The same server out of process: in the DLL surrogate, through the proxy/stub.
    if [ "$oop" = 1 ] && [ "$oop_available" = 1 ]; then
        (cd "$bin" && wine regsvr32 /s /n /i:ProxyStub opccomn.dll) || { echo "registering the proxy/stub failed" >&2; exit 1; }
        run_checker "defect-$name-local" json "${args[@]}" --context local
        $report json "$out/defect-$name-local.json" "$rc" "$want" "$warn"
        (cd "$bin" && wine regsvr32 /u /s /n /i:ProxyStub opccomn.dll)
        kill_surrogates "$(printf '{7E57DEF0-C0DE-4C0D-9000-0000000000%02X}' "$number")"
    fi
    code=0
    (cd "$bin" && wine regsvr32 /u /s "$dll") || code=$?
    [ "$code" -eq 0 ] || { echo "regsvr32 /u $dll failed with exit code $code" >&2; exit 1; }
    passed=$((passed + 1))
done <"$root/tests/conformance/defects.txt"
if [ -n "${3:-}" ]; then
    (cd "$bin" && wine regsvr32 /s opccomn_defect_none.dll)
    run_other() { (cd "$bin" && wine "$1" OpcComnTest.Defect.none.1 --context inproc --format json >"$out/other-view.json" 2>/dev/null) || rc=$?; }
    rc=0
    run_other "$(cd "$(dirname "$3")" && pwd)/$(basename "$3")"
    (cd "$bin" && wine regsvr32 /u /s opccomn_defect_none.dll)
    tr -d '\r' <"$out/other-view.json" >"$out/other-view.json.lf"
    python3 - "$out/other-view.json.lf" "$rc" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
create = next(c for c in r["checks"] if c["id"] == "server.create")
assert sys.argv[2] == "1" and create["status"] == "failed", (sys.argv[2], create)
assert "registry view only: run the x" in create["detail"], create
print("the other architecture's checker: server.create failed, naming the view and the checker to use")
PY
    passed=$((passed + 1))
fi
# The class is gone with its registration: the checker then says so and exits 2.
rc=0
(cd "$bin" && wine "$check" OpcComnTest.Defect.none.1 >/dev/null 2>&1) || rc=$?
[ "$rc" -eq 2 ] || { echo "opccomn-check of an unregistered ProgID exited $rc, expected 2" >&2; exit 1; }

if [ "$example" = - ]; then
    echo "test-conformance: $passed passed, 0 failed (defect servers only)$([ "$oop_available" = 1 ] || echo ', out of process NOT RUN')"
    exit 0
fi
# The C++ example server, in-process, every check including the hostile ones: nothing may fail. Its
# browsing checks go through CLSID_OPCServerList as registered (opccomn.dll here, as regsvr32 installs
# it); the defect servers' went through the library's own server list (none was registered).
(cd "$bin" && wine regsvr32 /s opccomn.dll)
(cd "$example" && wine regsvr32 /s opccomn_example_inproc.dll)
run_checker example-inproc text OpcComn.ExampleServerInProc.1 --hostile
$report text "$out/example-inproc.text" "$rc"
run_checker example-inproc json OpcComn.ExampleServerInProc.1 --hostile
$report json "$out/example-inproc.json" "$rc"
run_checker example-inproc junit OpcComn.ExampleServerInProc.1 --hostile
$report junit "$out/example-inproc.junit" "$rc"
# The sample output of docs/opccomn-check.md: the same command (without --hostile), compared below,
# once the prefix is as it was.
run_checker example-sample text OpcComn.ExampleServerInProc.1
sample_rc=$rc
(cd "$example" && wine regsvr32 /u /s opccomn_example_inproc.dll)
(cd "$bin" && wine regsvr32 /u /s opccomn.dll)
$report text "$out/example-sample.text" "$sample_rc"
# What the checker printed for the example is the sample, but for the version on the first line and
# the module's path.
sample_lines() { sed -E -e '1s/^opccomn-check [^:]*:/opccomn-check VERSION:/' -e 's/(InprocServer32 = ).*(opccomn_example_inproc\.dll)/\1...\2/'; }
documented=$(awk '/^<!-- opccomn-check output: compared by scripts\/test-conformance.sh -->$/ { after = 1; next }
    after && /^```$/ { if (inside) exit; inside = 1; next }
    inside { print }' "$root/docs/opccomn-check.md")
if [ -z "$documented" ] || [ "$(sample_lines <<<"$documented")" != "$(sample_lines <"$out/example-sample.text")" ]; then
    diff <(sample_lines <<<"$documented") <(sample_lines <"$out/example-sample.text") >&2 || true
    echo "docs/opccomn-check.md: its sample output is not what opccomn-check prints for the example (above): copy it again" >&2
    exit 1
fi
echo "docs/opccomn-check.md: the sample output is what opccomn-check prints for the example"
passed=$((passed + 1))
grep -q '"listed by the registered OPCServerList' "$out/example-inproc.json" ||
    { echo "the example's browse.listed did not use the registered OPCServerList" >&2; exit 1; }
passed=$((passed + 1))
cat "$out/example-inproc.text"

# The example's EXE server (LocalServer32), out of process through the proxy/stub: nothing may fail.
if [ "$oop_available" = 0 ]; then
    echo "!!!! NOT RUN: the example's EXE server and the defect servers out of process (no proxy/stub)"
    echo "test-conformance: $passed passed, 0 failed, out of process NOT RUN"
    exit 0
fi
(cd "$example" && wine opccomn_example_server.exe /RegServer)
(cd "$bin" && wine regsvr32 /s /n /i:ProxyStub opccomn.dll)
run_checker example-local text OpcComn.ExampleServer.1 --context local --hostile
$report text "$out/example-local.text" "$rc"
run_checker example-local json OpcComn.ExampleServer.1 --context local --hostile
$report json "$out/example-local.json" "$rc"
passed=$((passed + 1))
cat "$out/example-local.text"

# --host, as for a server on another machine: creation with CLSCTX_REMOTE_SERVER | CLSCTX_LOCAL_SERVER
# and the host in COSERVERINFO, the ProgID resolved through the host's OPCServerList (the browser
# service, opccomn_browser.exe), no registry or file of the host read. "localhost" names this machine,
# where COM (Windows' DCOM as Wine's) starts the local server: every check of the server and the
# browsing checks must pass, the registration checks are not applicable.
(cd "$bin" && wine opccomn_browser.exe /RegServer >/dev/null)
run_checker example-host json OpcComn.ExampleServer.1 --host localhost
$report json "$out/example-host.json" "$rc"
(cd "$bin" && wine opccomn_browser.exe /UnregServer >/dev/null)
python3 - "$out/example-host.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert r["server"]["host"] == "localhost", r["server"]
status = {c["id"]: c["status"] for c in r["checks"]}
for check, s in status.items():
    if check.startswith("reg."):
        assert s == "not applicable", (check, s)
    else:
        assert s == "passed", (check, s, [c for c in r["checks"] if c["id"] == check])
assert status["server.create"] == "passed" and status["browse.progid"] == "passed", status
print("--host localhost: the server checked through the host's server list; registration checks not applicable")
PY

# DCOM security (--dcom). The example's EXE server as registered (AppID at PKT_INTEGRITY, both
# permissions) with the browser registered (its AppID hardened too): every check passes, with no
# warning. Then the same AppID at AuthenticationLevel 1 and 2, as installers of old wrote it:
# dcom.authentication-level fails, naming KB5004442, and nothing else; without a level it is a
# warning naming the machine default. Wine enforces none of this: what is checked is the registry
# the checker reads and its verdicts (docs/guide/dcom-appid.md).
(cd "$bin" && wine opccomn_browser.exe /RegServer >/dev/null)
app_key='HKCR\AppID\{C906C0A4-7001-4E1E-8827-B369541ED7F7}'
for format in json junit text; do
    run_checker example-dcom "$format" OpcComn.ExampleServer.1 --context local --dcom
    $report "$format" "$out/example-dcom.$format" "$rc"
done
python3 - "$out/example-dcom.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
status = {c["id"]: (c["status"], c["detail"]) for c in r["checks"]}
dcom = [k for k in status if k.startswith("dcom.")]
assert len(dcom) == 7 and all(status[k][0] == "passed" for k in dcom), {k: status[k] for k in dcom}
assert "5 (RPC_C_AUTHN_LEVEL_PKT_INTEGRITY)" in status["dcom.authentication-level"][1], status
assert status["dcom.access-permission"][1] == "AccessPermission = O:BAG:BAD:(A;;CCDCLC;;;AU)(A;;CCDCLC;;;SY)", status
assert status["dcom.launch-permission"][1] == "LaunchPermission = O:BAG:BAD:(A;;CCDCLCSWRP;;;AU)(A;;CCDCLCSWRP;;;SY)", status
assert "opccomn_browser.exe" in status["dcom.browser"][1] and "PKT_INTEGRITY" in status["dcom.browser"][1], status
print("--dcom: the example's AppID passes (PKT_INTEGRITY, its permissions as SDDL), the browser is reported")
PY
for level in 1 2; do
    wine reg add "$app_key" /v AuthenticationLevel /t REG_DWORD /d "$level" /f >/dev/null
    for format in json junit; do
        run_checker "example-dcom-level$level" "$format" OpcComn.ExampleServer.1 --context local --dcom
        $report "$format" "$out/example-dcom-level$level.$format" "$rc" dcom.authentication-level
    done
    grep -q 'KB5004442' "$out/example-dcom-level$level.json" ||
        { echo "dcom.authentication-level at level $level does not name KB5004442" >&2; exit 1; }
done
wine reg delete "$app_key" /v AuthenticationLevel /f >/dev/null
run_checker example-dcom-nolevel json OpcComn.ExampleServer.1 --context local --dcom
$report json "$out/example-dcom-nolevel.json" "$rc" - dcom.authentication-level
grep -q 'LegacyAuthenticationLevel' "$out/example-dcom-nolevel.json" ||
    { echo "dcom.authentication-level without a level does not name the machine default" >&2; exit 1; }
# Back to what registration wrote, so that unregistration removes the AppID entirely (a level changed
# by someone else would stay, by design).
wine reg add "$app_key" /v AuthenticationLevel /t REG_DWORD /d 5 /f >/dev/null
(cd "$bin" && wine opccomn_browser.exe /UnregServer >/dev/null)
passed=$((passed + 1))
(cd "$bin" && wine regsvr32 /u /s /n /i:ProxyStub opccomn.dll)
(cd "$example" && wine opccomn_example_server.exe /UnregServer)
if wine reg query "$app_key" >/dev/null 2>&1; then
    echo "the example's AppID is still registered after /UnregServer" >&2
    exit 1
fi
passed=$((passed + 1))

echo "test-conformance: $passed passed, 0 failed"
