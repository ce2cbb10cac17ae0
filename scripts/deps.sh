# Sourced by the scripts: installs what a fresh Debian 12 machine with only Rust lacks, and nothing when
# it is all there already. Needs root (or sudo) only when something is missing.
need_linux_tools() {
    local missing=()
    command -v cmake >/dev/null || missing+=(cmake)
    command -v cc >/dev/null || missing+=(gcc)
    command -v c++ >/dev/null || missing+=(g++)
    command -v pkg-config >/dev/null || missing+=(pkg-config)
    command -v llvm-ar >/dev/null || missing+=(llvm)   # rewrites libopccomn.a (CMakeLists.txt)
    command -v python3 >/dev/null || missing+=(python3)
    # CaseFolding.txt, for the drift check of the case-folding table (scripts/check-generated.sh).
    [ -f /usr/share/unicode/CaseFolding.txt ] || missing+=(unicode-data)
    install_packages "${missing[@]}"
}

# valgrind, and the nightly toolchain with the standard library's sources (ThreadSanitizer needs an
# instrumented standard library, built with -Zbuild-std).
need_soundness_tools() {
    command -v valgrind >/dev/null || install_packages valgrind
    local installed
    installed=$(rustup +nightly component list --installed 2>/dev/null || true)
    if ! grep -q '^rust-src' <<<"$installed"; then
        rustup toolchain install nightly --profile minimal --component rust-src
    fi
}

need_windows_tools() {
    local missing=()
    command -v x86_64-w64-mingw32-gcc >/dev/null || missing+=(gcc-mingw-w64-x86-64)
    command -v x86_64-w64-mingw32-g++ >/dev/null || missing+=(g++-mingw-w64-x86-64)
    command -v x86_64-w64-mingw32-windres >/dev/null || missing+=(binutils-mingw-w64-x86-64)
    command -v x86_64-w64-mingw32-widl >/dev/null || missing+=(mingw-w64-tools)
    # The header's coexistence and calling-convention checks: i686 compilers (compile only), the system
    # IDL files widl needs for the stand-in OPC Foundation headers, clang.
    command -v i686-w64-mingw32-gcc >/dev/null || missing+=(gcc-mingw-w64-i686)
    command -v i686-w64-mingw32-g++ >/dev/null || missing+=(g++-mingw-w64-i686)
    [ -f /usr/include/wine/wine/windows/unknwn.idl ] || missing+=(libwine-dev)
    command -v clang >/dev/null || missing+=(clang)
    command -v wine >/dev/null || missing+=(wine wine64)
    install_packages "${missing[@]}"
    if ! rustup target list --installed | grep -qx x86_64-pc-windows-gnu; then
        rustup target add x86_64-pc-windows-gnu
    fi
}

install_packages() {
    [ "$#" -eq 0 ] && return 0
    local sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    echo "== installing: $*"
    $sudo apt-get -o DPkg::Lock::Timeout=900 update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=900 install -y -qq --no-install-recommends "$@" >/dev/null
}

# Nightly Rust for the fuzz targets (libFuzzer instrumentation with AddressSanitizer).
need_fuzz_tools() {
    if ! rustup toolchain list | grep -q '^nightly'; then
        rustup toolchain install nightly --profile minimal
    fi
}
