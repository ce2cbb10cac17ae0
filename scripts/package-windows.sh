#!/usr/bin/env bash
# Builds the binary package for Windows users: build/package/opccomn-<version>-windows.zip, laid out as
# the README's "Windows binary package" lists (headers; x64/ and x86/ with opccomn.dll, opccomn.lib,
# libopccomn.dll.a and libopccomn.a; the same for Windows 7 in win7/; msi/ with the MSI packages and
# their WiX sources; the CMake package; README and licences). Reuses the build directories of scripts/test.sh when they exist.
#
# Usage: scripts/package-windows.sh [OUT_DIR]      (OUT_DIR: build/package)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh
need_linux_tools
need_windows_tools
need_msi_tools
need_nightly_rust_src
build="$root/build"
out=${1:-$build/package}
version=$(sed -nE 's/^version = "([^"]+)"$/\1/p' Cargo.toml | head -1)
name="opccomn-$version-windows"
win7_args=(-DOPCCOMN_RUST_TOOLCHAIN="$OPCCOMN_NIGHTLY" "-DOPCCOMN_CARGO_ARGS=-Zbuild-std=std,panic_unwind")

# build DIR TOOLCHAIN_FILE [CMAKE_ARGS...]: the library, opccomn.lib, the browser service and (not for
# Windows 7) opccomn-check.exe, in DIR. A build directory of scripts/test.sh is reused, but configured
# again with every option that changes what is shipped, so a directory left with other settings (the
# standard Dll* exports turned off, another toolchain) cannot be packaged as it is.
build_variant() {
    local dir=$1 toolchain=$2
    shift 2
    local fresh=()
    [ -f "$dir/CMakeCache.txt" ] || fresh=(-DOPCCOMN_BUILD_TESTS=OFF)
    cmake -S . -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/$toolchain" -DOPCCOMN_DLL_EXPORTS=ON \
        -DOPCCOMN_CARGO_ARGS= -DOPCCOMN_RUST_TOOLCHAIN= "${fresh[@]}" "$@" >/dev/null
    cmake --build "$dir" -j2 --target opccomn_msvc_implib opccomn_static_lib opccomn_browser
    if [[ "$dir" != */windows7-* ]]; then
        cmake --build "$dir" -j2 --target opccomn_check
    fi
}

# copy_variant DIR RUST_TARGET DEST TRIPLET (the static library is the one CMake makes, with one member
# per exported identifier, as `cmake --install` installs it). The DLL is shipped stripped; its debug
# information (DWARF) goes into opccomn.dll.debug beside it, which the DLL names (.gnu_debuglink), for
# gdb and other DWARF debuggers. (Visual Studio reads PDB files, which a mingw-w64 build does not make.)
copy_variant() {
    local rust_out="$1/cargo/$2/release" dest=$3 objcopy=$4-objcopy
    mkdir -p "$dest"
    # opccomn-static-libs.txt: what rustc reported the static library needs besides itself.
    cp "$rust_out/libopccomn.dll.a" "$1/opccomn/libopccomn.a" "$1/opccomn-static-libs.txt" \
        "$rust_out/msvc/opccomn.lib" "$rust_out/msvc/opccomn.def" "$dest/"
    "$objcopy" --only-keep-debug "$rust_out/opccomn.dll" "$dest/opccomn.dll.debug"
    "$objcopy" --strip-debug --add-gnu-debuglink="$dest/opccomn.dll.debug" "$rust_out/opccomn.dll" "$dest/opccomn.dll"
    # The server browser service (chapter 7 of the specification; docs/guide/out-of-process.md).
    local browser
    browser=$(find "$1" -name opccomn_browser.exe -not -path '*/CMakeFiles/*' | head -1)
    [ -n "$browser" ] || { echo "no opccomn_browser.exe in $1" >&2; exit 1; }
    "$objcopy" --strip-debug "$browser" "$dest/opccomn_browser.exe"
}

build_variant "$build/windows" mingw-w64-x86_64.cmake
build_variant "$build/windows-x86" mingw-w64-i686.cmake
build_variant "$build/windows7-x64" mingw-w64-x86_64.cmake -DOPCCOMN_RUST_TARGET=x86_64-win7-windows-gnu "${win7_args[@]}"
build_variant "$build/windows7-x86" mingw-w64-i686.cmake -DOPCCOMN_RUST_TARGET=i686-win7-windows-gnu "${win7_args[@]}"

stage="$out/$name"
rm -rf "$stage" "$out/$name.zip"
mkdir -p "$stage/cmake"
cp -r include "$stage/"
copy_variant "$build/windows" x86_64-pc-windows-gnu "$stage/x64" x86_64-w64-mingw32
copy_variant "$build/windows-x86" i686-pc-windows-gnu "$stage/x86" i686-w64-mingw32
# The conformance checker, beside the DLL it uses (x64 and x86). It runs on Windows 10 and later, as
# that DLL does; it checks a server on an older machine with --host.
find_checker() { find "$1" -name opccomn-check.exe -not -path '*/CMakeFiles/*' | head -1; }
cp "$(find_checker "$build/windows")" "$stage/x64/"
cp "$(find_checker "$build/windows-x86")" "$stage/x86/"
copy_variant "$build/windows7-x64" x86_64-win7-windows-gnu "$stage/win7/x64" x86_64-w64-mingw32
copy_variant "$build/windows7-x86" i686-win7-windows-gnu "$stage/win7/x86" i686-w64-mingw32
# The Windows Installer packages, built from the files just staged, and the WiX sources a vendor's
# installer includes (docs/guide/installer.md).
mkdir -p "$stage/msi"
cp packaging/msi/opccomn.wxi packaging/msi/opccomn.wxs "$stage/msi/"
scripts/build-msi.sh "$stage/msi" "$stage/x64" "$stage/x86" "$version" >/dev/null
cp "$build/windows/package/opccomnConfig.cmake" "$build/windows/package/opccomnConfigVersion.cmake" "$stage/cmake/"
# The documentation (the developers' README stays in the repository: the package has its own), the
# C++ example server and the licences.
cp packaging/windows/README.md LICENSE-MIT LICENSE-APACHE "$stage/"
[ -f CHANGELOG.md ] && cp CHANGELOG.md "$stage/"
mkdir -p "$stage/docs" "$stage/examples"
cp -r docs/. "$stage/docs/"
rm -rf "$stage/docs/dev"
# The C API reference, built from the header (scripts/docs.sh fails on any undocumented item).
scripts/docs.sh >/dev/null
cp -r "$build/docs/html" "$stage/docs/reference/"
cp -r examples/cpp-server examples/server-plumbing "$stage/examples/"
printf '%s\n' "$version" >"$stage/VERSION"
(cd "$stage" && find . -type f ! -name SHA256SUMS | sort | sed 's|^\./||' | xargs sha256sum >SHA256SUMS)
(cd "$out" && cmake -E tar cf "$name.zip" --format=zip "$name")
echo "package: $out/$name.zip"
(cd "$stage" && find . -type f | sort | sed 's|^\./|    |')
