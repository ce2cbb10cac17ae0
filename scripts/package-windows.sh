#!/usr/bin/env bash
# Builds the binary package for Windows users: build/package/opccomn-<version>-windows.zip, laid out as
# the README's "Windows binary package" lists (headers; x64/ and x86/ with opccomn.dll, opccomn.lib,
# libopccomn.dll.a and libopccomn.a; the same for Windows 7 in win7/; the CMake package; README and
# licences). Reuses the build directories of scripts/test.sh when they exist.
#
# Usage: scripts/package-windows.sh [OUT_DIR]      (OUT_DIR: build/package)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh
need_linux_tools
need_windows_tools
need_nightly_rust_src
build="$root/build"
out=${1:-$build/package}
version=$(sed -nE 's/^version = "([^"]+)"$/\1/p' Cargo.toml | head -1)
name="opccomn-$version-windows"
win7_args=(-DOPCCOMN_RUST_TOOLCHAIN="$OPCCOMN_NIGHTLY" "-DOPCCOMN_CARGO_ARGS=-Zbuild-std=std,panic_unwind")

# build DIR TOOLCHAIN_FILE [CMAKE_ARGS...]: the library, opccomn.lib and opccomn-check.exe, in DIR.
build_variant() {
    local dir=$1 toolchain=$2
    shift 2
    if [ ! -f "$dir/CMakeCache.txt" ]; then
        cmake -S . -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/$toolchain" -DOPCCOMN_BUILD_TESTS=OFF "$@" >/dev/null
    fi
    cmake --build "$dir" -j2 --target opccomn_msvc_implib opccomn_static_lib
    if [[ "$dir" != */windows7-* ]]; then
        cmake --build "$dir" -j2 --target opccomn_check
    fi
}

# copy_variant DIR RUST_TARGET DEST (the static library is the one CMake makes, with one member per
# exported identifier, as `cmake --install` installs it)
copy_variant() {
    local rust_out="$1/cargo/$2/release" dest=$3
    mkdir -p "$dest"
    cp "$rust_out/opccomn.dll" "$rust_out/libopccomn.dll.a" "$1/opccomn/libopccomn.a" \
        "$rust_out/msvc/opccomn.lib" "$rust_out/msvc/opccomn.def" "$dest/"
}

build_variant "$build/windows" mingw-w64-x86_64.cmake
build_variant "$build/windows-x86" mingw-w64-i686.cmake
build_variant "$build/windows7-x64" mingw-w64-x86_64.cmake -DOPCCOMN_RUST_TARGET=x86_64-win7-windows-gnu "${win7_args[@]}"
build_variant "$build/windows7-x86" mingw-w64-i686.cmake -DOPCCOMN_RUST_TARGET=i686-win7-windows-gnu "${win7_args[@]}"

stage="$out/$name"
rm -rf "$stage" "$out/$name.zip"
mkdir -p "$stage/cmake"
cp -r include "$stage/"
copy_variant "$build/windows" x86_64-pc-windows-gnu "$stage/x64"
copy_variant "$build/windows-x86" i686-pc-windows-gnu "$stage/x86"
# The conformance checker, beside the DLL it uses (x64 and x86; it runs on Windows 10 and later).
cp "$build/windows/bin/opccomn-check.exe" "$stage/x64/"
cp "$build/windows-x86/bin/opccomn-check.exe" "$stage/x86/"
copy_variant "$build/windows7-x64" x86_64-win7-windows-gnu "$stage/win7/x64"
copy_variant "$build/windows7-x86" i686-win7-windows-gnu "$stage/win7/x86"
cp "$build/windows/package/opccomnConfig.cmake" "$build/windows/package/opccomnConfigVersion.cmake" "$stage/cmake/"
cp README.md LICENSE-MIT LICENSE-APACHE "$stage/"
(cd "$out" && cmake -E tar cf "$name.zip" --format=zip "$name")
echo "package: $out/$name.zip"
(cd "$stage" && find . -type f | sort | sed 's|^\./|    |')
