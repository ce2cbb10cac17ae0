#!/usr/bin/env bash
# A public third-party OPC client against the library under Wine: the crates.io crates opc_da 0.3.1
# and opc_comn_bindings 0.3.0, in a program of their own (tests/third-party/opc-da-client, its own
# Cargo project and Cargo.lock), built for x86_64-pc-windows-gnu (and i686-pc-windows-gnu, run under
# 32-bit Wine, when the x86 build is given). It browses with the crate's own
# client code through the library's browser service (opccomn_browser.exe) alone, calls IOPCCommon
# and the IOPCShutdown connection point of the C++ example's EXE server through opccomn.dll's
# proxy/stub, and is a Data Access client, with the crate's client code, of the C test DA server
# (opc_da_test_server.exe, tests/oop/da_server.c) through the same proxy/stub; then the same client of
# a Data Access server written with the crate's server module (tests/third-party/opc-da-server, its
# own Cargo project and Cargo.lock, opc_da_crate_server.exe, built for the same targets: the x64
# build, and the x86 one in a 32-bit process), serving the same items, through the same proxy/stub. See docs/dev/third-party-client.md for what is asserted and what belongs to the
# crate.
#
# The browser, the example server, the two DA servers and the proxy/stub (`regsvr32 /n /i:ProxyStub`,
# which registers the OPC Common, Data Access, A&E and HDA interfaces: nothing in-process answers
# CLSID_OPCServerList) are registered for the run and unregistered after it, whatever happened; the
# registry's classes (both views) must then be exactly as they were before.
#
# Usage: scripts/test-third-party-client.sh BIN_DIR EXAMPLE_DIR [X86_BIN_DIR]
#   BIN_DIR      the x64 Windows build's program directory (opccomn.dll, opccomn_browser.exe,
#                opc_da_test_server.exe), e.g. build/windows/bin
#   EXAMPLE_DIR  the built C++ example (opccomn_example_server.exe, with its opccomn.dll), e.g.
#                build/example-x64 (scripts/test.sh's example stage builds it)
#   X86_BIN_DIR  the x86 Windows build's program directory (its opccomn.dll), e.g. build/windows-x86/bin:
#                the program also runs as a 32-bit client, with the x86 proxy/stub registered in the
#                32-bit view, against the same x64 browser service, example EXE server and DA
#                test server, and the opc_da server is built for x86 too (its own class, registered
#                in the 32-bit view) and served to both clients
# Needs WINEPREFIX set up (scripts/wine-env.sh). The program is built in build/third-party-client
# (cargo --locked: the crates' versions are those of the committed Cargo.lock).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[ "$#" = 2 ] || [ "$#" = 3 ] || { echo "usage: scripts/test-third-party-client.sh BIN_DIR EXAMPLE_DIR [X86_BIN_DIR]" >&2; exit 2; }
bin=$(cd "$1" && pwd)
example=$(cd "$2" && pwd)
x86_bin=
targets=(x86_64-pc-windows-gnu)
if [ "$#" = 3 ]; then
    x86_bin=$(cd "$3" && pwd)
    [ -f "$x86_bin/opccomn.dll" ] || { echo "test-third-party-client: no $x86_bin/opccomn.dll (build it first)" >&2; exit 1; }
    targets+=(i686-pc-windows-gnu)
fi
: "${WINEPREFIX:?set up a Wine prefix first (. scripts/wine-env.sh build/windows)}"
for file in "$bin/opccomn.dll" "$bin/opccomn_browser.exe" "$bin/opc_da_test_server.exe" \
    "$example/opccomn_example_server.exe"; do
    [ -f "$file" ] || { echo "test-third-party-client: no $file (build it first)" >&2; exit 1; }
done

# A release build: in a debug build windows-core's `#[implement]` QueryInterface checks the alignment
# of the IID pointer it is given and aborts, and COM hands it one from the NDR format string of the
# system's IConnectionPoint proxy (see the documentation).
target_dir="$root/build/third-party-client"
manifest="$root/tests/third-party/opc-da-client/Cargo.toml"
server_manifest="$root/tests/third-party/opc-da-server/Cargo.toml"
# Without optimisation (the release profile's checks, at opt-level 0): a test program, built in half
# the time. Linted once: the code is the same for both targets.
export CARGO_PROFILE_RELEASE_OPT_LEVEL=0
# The server declares the client's dependencies, so both share one build of the crates.
for m in "$manifest" "$server_manifest"; do
    CARGO_TARGET_DIR="$target_dir" cargo clippy -q --release --locked -j2 --manifest-path "$m" \
        --target "${targets[0]}" -- -D warnings
done
for target in "${targets[@]}"; do
    CARGO_TARGET_DIR="$target_dir" cargo build --release --locked -j2 --manifest-path "$manifest" --target "$target"
done
# The crate-made server, built for each target too: every client talks to the x64 one and, with an
# x86 build, to the x86 one (a 32-bit process, its class registered in the 32-bit view).
for target in "${targets[@]}"; do
    CARGO_TARGET_DIR="$target_dir" cargo build --release --locked -j2 --manifest-path "$server_manifest" \
        --target "$target"
done
crate_server_dirs=()
for target in "${targets[@]}"; do crate_server_dirs+=("$target_dir/$target/release"); done
out="$target_dir/run"
rm -rf "$out" && mkdir -p "$out"

# The registry's classes, both views, as text.
registry_state() {
    local view
    for view in 'HKLM\Software\Classes' 'HKLM\Software\Wow6432Node\Classes'; do
        rm -f "$out/view.reg"
        wine reg export "$view" 'Z:'"${out//\//\\}"'\view.reg' /y >/dev/null 2>&1 || true
        echo "==== $view"
        [ -f "$out/view.reg" ] && iconv -f UTF-16LE -t UTF-8 "$out/view.reg" | tr -d '\r'
    done
    rm -f "$out/view.reg"
}
registry_state >"$out/registry-before.txt"

unregister() {
    (cd "$bin" && wine opccomn_browser.exe /UnregServer >/dev/null) || echo "opccomn_browser.exe /UnregServer failed" >&2
    (cd "$bin" && wine regsvr32 /u /s /n /i:ProxyStub opccomn.dll) || echo "unregistering the proxy/stub failed" >&2
    [ -z "$x86_bin" ] || (cd "$x86_bin" && wine regsvr32 /u /s /n /i:ProxyStub opccomn.dll) ||
        echo "unregistering the x86 proxy/stub failed" >&2
    (cd "$example" && wine opccomn_example_server.exe /UnregServer) || echo "opccomn_example_server.exe /UnregServer failed" >&2
    (cd "$bin" && wine opc_da_test_server.exe /UnregServer) || echo "opc_da_test_server.exe /UnregServer failed" >&2
    local dir
    for dir in "${crate_server_dirs[@]}"; do
        (cd "$dir" && wine opc_da_crate_server.exe /UnregServer) ||
            echo "$dir/opc_da_crate_server.exe /UnregServer failed" >&2
    done
}
trap unregister EXIT

(cd "$example" && wine opccomn_example_server.exe /RegServer)
(cd "$bin" && wine opc_da_test_server.exe /RegServer)
for dir in "${crate_server_dirs[@]}"; do (cd "$dir" && wine opc_da_crate_server.exe /RegServer); done
# The client runs the x86 server's checks only when it is registered.
if [ -n "$x86_bin" ]; then export OPC_DA_CRATE_SERVER_X86=1; else export OPC_DA_CRATE_SERVER_X86=0; fi
(cd "$bin" && wine regsvr32 /s /n /i:ProxyStub opccomn.dll)
# A 32-bit client's COM loads the proxy/stub from the 32-bit view.
[ -z "$x86_bin" ] || (cd "$x86_bin" && wine regsvr32 /s /n /i:ProxyStub opccomn.dll)
# Exit code 2: another browser (OpcEnum) stays active, and the client would browse through it.
(cd "$bin" && wine opccomn_browser.exe /RegServer)

declare -A rc
for target in "${targets[@]}"; do
    rc[$target]=0
    (cd "$target_dir/$target/release" && timeout 300 wine opc-da-client-test.exe </dev/null) \
        >"$out/client-$target.log" 2>&1 || rc[$target]=$?
    tr -d '\r' <"$out/client-$target.log"
done

trap - EXIT
unregister
registry_state >"$out/registry-after.txt"
if ! diff -u "$out/registry-before.txt" "$out/registry-after.txt" >"$out/registry.diff"; then
    cat "$out/registry.diff"
    echo "test-third-party-client: the registry's classes differ from what they were before the run" >&2
    exit 1
fi
echo "test-third-party-client: the registry's classes are as they were before the run"

# Passed only on the program's own closing line with no failure, and its exit code 0 (a 32-bit program
# that did not start prints nothing).
failed=0
for target in "${targets[@]}"; do
    log="$out/client-$target.log"
    if [ "${rc[$target]}" = 0 ] && tr -d '\r' <"$log" | grep -qE '^third-party-client: [1-9][0-9]* passed, 0 failed$'; then
        echo "test-third-party-client: $target client: $(tr -d '\r' <"$log" | tail -n 1)"
        continue
    fi
    failed=1
    # The crate reports its own errors with windows-core's Error::new, which calls RoOriginateErrorW, a
    # stub in Wine 8's combase: a failure in its browsing code aborts the program there.
    grep -q 'unimplemented function combase.dll.RoOriginateErrorW' "$log" &&
        echo "test-third-party-client: $target: the crate met an error after the last check printed above (it" \
            "reports errors with RoOriginateErrorW, which this Wine does not implement, and the program stopped there)" >&2
    echo "test-third-party-client: the $target client failed (exit code ${rc[$target]})" >&2
done
exit "$failed"
