#!/usr/bin/env bash
# CMake's Visual Studio (MSVC) code paths, as far as a machine without Visual Studio can show them:
# the project and a project that takes it with add_subdirectory are configured with a stand-in MSVC
# toolchain (tests/msvc/msvc-stub-toolchain.cmake: CMake believes it has cl, link and lib, and has no
# binutils or LLVM), for x64 and Win32, and what they configure is checked: no error, the MSVC Rust
# target, the tests off, the static library's per-symbol rewrite off with its warning, opccomn.lib made
# by lib.exe from cargo's import library and the identifiers, and installed for find_package.
# What only Windows can show: the Visual Studio generators themselves, and a build with the real tools.
# Usage: scripts/check-cmake-msvc.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
work="$root/build/cmake-msvc"
rm -rf "$work"
fail() { echo "check-cmake-msvc: $*" >&2; exit 1; }
for variant in 8:x86_64-pc-windows-msvc 4:i686-pc-windows-msvc; do
    size=${variant%%:*} target=${variant#*:}
    dir="$work/project-$size"
    out=$(cmake -S . -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$root/tests/msvc/msvc-stub-toolchain.cmake" \
        -DOPCCOMN_STUB_POINTER_SIZE="$size" 2>&1) || { echo "$out"; fail "the project does not configure with MSVC ($target)"; }
    grep -qx "OPCCOMN_RUST_TARGET:STRING=$target" "$dir/CMakeCache.txt" || fail "the Rust target is not $target"
    grep -qx "OPCCOMN_BUILD_TESTS:BOOL=OFF" "$dir/CMakeCache.txt" || fail "the tests are not off by default with MSVC"
    grep -qx "OPCCOMN_STATIC_LIB_REWRITE:BOOL=OFF" "$dir/CMakeCache.txt" || fail "the static library's rewrite is not off without its tools"
    grep -q "OPCCOMN_STATIC_LIB_REWRITE is OFF" <<<"$out" || fail "no warning says the static library is not rewritten"
    # opccomn.lib: lib.exe with cargo's import library and one object per identifier.
    rule=$(grep -rh --include=build.make -e "/OUT:.*msvc/opccomn.lib" "$dir" | head -1)
    [ -n "$rule" ] || fail "no rule makes opccomn.lib"
    grep -q "lib.exe /NOLOGO" <<<"$rule" && grep -q "opccomn.dll.lib" <<<"$rule" && grep -q "opccomn_guid_1" <<<"$rule" ||
        fail "opccomn.lib is not made from cargo's import library and the identifiers: $rule"
    grep -q "cargo/$target/release/msvc/opccomn.lib\|/lib/opccomn.lib" "$dir/cmake_install.cmake" ||
        fail "opccomn.lib is not installed"
    grep -q 'IMPORTED_IMPLIB "${PACKAGE_PREFIX_DIR}/lib/opccomn.lib"' "$dir/opccomnConfig.cmake" ||
        fail "find_package's configuration does not name opccomn.lib"
    echo "MSVC ($target): configures; opccomn.lib from cargo's import library and the identifiers; static rewrite off, said"
done
# add_subdirectory from a Visual Studio project.
out=$(cmake -S tests/msvc/stub-consumer -B "$work/consumer" -DOPCCOMN_SOURCE_DIR="$root" \
    -DCMAKE_TOOLCHAIN_FILE="$root/tests/msvc/msvc-stub-toolchain.cmake" 2>&1) || { echo "$out"; fail "add_subdirectory does not configure with MSVC"; }
grep -q "opccomn import library for the consumer: .*/msvc/opccomn.lib" <<<"$out" || { echo "$out"; fail "the consumer does not link opccomn.lib"; }
echo "MSVC: add_subdirectory configures, and the consumer links opccomn.lib"
