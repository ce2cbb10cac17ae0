#!/usr/bin/env bash
# The build script on the Visual Studio target (x86_64-pc-windows-msvc), as far as this machine can show
# it without Visual Studio: `cargo check` runs the build script but links nothing.
#  1. Without cl, lib, rc and mc on PATH the build stops, naming each missing tool and the mingw-w64
#     alternative: never a DLL without its message table, VERSIONINFO and proxy/stub.
#  2. With stand-ins for the four tools (tests/msvc/tool-stand-in.sh, which record their arguments and
#     write the files they are asked for), each is called as Visual Studio's would be, and the build
#     script links the resources (.res) and the proxy/stub library and turns the proxy/stub on.
# What only Windows can show: that the real cl, lib, rc and mc accept these files.
# Usage: scripts/check-msvc-build-script.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
target=x86_64-pc-windows-msvc
if ! rustup target list --installed | grep -qx "$target"; then
    echo "== installing: Rust target $target (rustup), to check the build script for Visual Studio"
    rustup target add "$target"
fi
work="$root/build/msvc-build-script"
rm -rf "$work/bin" "$work/log"
mkdir -p "$work/bin"
export CARGO_TARGET_DIR="$work/target"
cargo_dir=$(dirname "$(command -v cargo)")
base_path="$cargo_dir:/usr/bin:/bin"
for tool in cl lib rc mc; do
    if PATH="$base_path" command -v "$tool" >/dev/null; then
        echo "check-msvc-build-script: '$tool' is on $base_path; the check needs a PATH without it" >&2
        exit 1
    fi
done

# 1. The tools missing: the build stops and says what to do.
out=$(PATH="$base_path" cargo check -q --lib --target "$target" 2>&1) && {
    echo "$out"
    echo "check-msvc-build-script: the MSVC build went on without cl, lib, rc and mc" >&2
    exit 1
}
for want in "not found: mc (" ", rc (" ", cl (" ", lib (" "Developer Command Prompt" "x86_64-pc-windows-gnu"; do
    grep -qF "$want" <<<"$out" || { echo "$out"; echo "check-msvc-build-script: the error does not say '$want'" >&2; exit 1; }
done
echo "without the Visual Studio tools: the build stops and names mc, rc, cl and lib"

# 2. With stand-ins: each tool called as expected, and the outputs linked.
for tool in cl lib rc mc; do
    ln -sf "$root/tests/msvc/tool-stand-in.sh" "$work/bin/$tool"
done
PATH="$work/bin:$base_path" OPCCOMN_TOOL_LOG="$work/log" cargo check -q --lib --target "$target"
expect() {   # expect REGEX: a line of the log matches
    grep -qE "$1" "$work/log" || { cat "$work/log"; echo "check-msvc-build-script: no call matching '$1'" >&2; exit 1; }
}
expect '^mc -u -U -r \. -h \. opccomn_messages\.mc$'
expect '^rc /nologo /fo opccomn\.res opccomn\.rc$'
expect '^cl /nologo /c /O2 /W3 /WX /Fo[^ ]*/opccomn_ps\.obj [^ ]*/src/proxy/opccomn_ps\.c$'
expect '^cl /nologo /c /O2 /W3 /WX /Fo[^ ]*/opcda_ps\.obj [^ ]*/src/proxy/opcda_ps\.c$'
expect '^cl /nologo /c /O2 /W3 /WX /Fo[^ ]*/opc_ae_ps\.obj [^ ]*/src/proxy/opc_ae_ps\.c$'
expect '^cl /nologo /c /O2 /W3 /WX /Fo[^ ]*/opchda_ps\.obj [^ ]*/src/proxy/opchda_ps\.c$'
expect '^lib /nologo /OUT:[^ ]*/opccomn_ps\.lib [^ ]*/opccomn_ps\.obj [^ ]*/opcda_ps\.obj [^ ]*/opc_ae_ps\.obj [^ ]*/opchda_ps\.obj$'
output=$(ls -t "$CARGO_TARGET_DIR/$target"/debug/build/opccomn-*/output | head -1)
for want in 'cargo:rustc-link-arg-cdylib=.*/opccomn\.res$' 'cargo:rustc-link-lib=static=opccomn_ps$' \
    'cargo:rustc-link-lib=dylib=rpcrt4$' 'cargo:rustc-cfg=opccomn_proxy_stub$'; do
    grep -qE "$want" "$output" || { cat "$output"; echo "check-msvc-build-script: the build script did not print '$want'" >&2; exit 1; }
done
echo "with cl, lib, rc and mc: message table, VERSIONINFO (.res) and proxy/stub built and linked"
