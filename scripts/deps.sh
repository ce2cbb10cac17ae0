# Sourced by the scripts: installs what a fresh Debian 12 machine with only Rust lacks, and nothing when
# it is all there already. Needs root (or sudo) only when something is missing. Each script asks only
# for what it uses, and every install is announced (with its reason) before it starts.

# What building the library and its C programs with CMake needs (scripts/demo.sh).
need_build_tools() {
    local missing=()
    command -v cmake >/dev/null || missing+=(cmake)
    command -v cc >/dev/null || missing+=(gcc)
    command -v c++ >/dev/null || missing+=(g++)
    command -v llvm-ar >/dev/null || missing+=(llvm)   # rewrites libopccomn.a (CMakeLists.txt)
    install_packages "to build the library with CMake" "${missing[@]}"
}

# Everything the Linux test stages use besides the build tools.
need_linux_tools() {
    need_build_tools
    local missing=()
    command -v pkg-config >/dev/null || missing+=(pkg-config)
    command -v python3 >/dev/null || missing+=(python3)
    # CaseFolding.txt, for the drift check of the case-folding table (scripts/check-generated.sh).
    [ -f /usr/share/unicode/CaseFolding.txt ] || missing+=(unicode-data)
    install_packages "for the Linux tests (pkg-config check, generators, case-folding drift check)" "${missing[@]}"
}

# The one nightly Rust toolchain every nightly build uses (the Windows 7 builds, ThreadSanitizer, Miri,
# the fuzz targets), named so that a build can be repeated: a new nightly is taken on purpose, by
# changing this line, never by whatever is current on the day. OPCCOMN_NIGHTLY overrides it.
OPCCOMN_NIGHTLY=${OPCCOMN_NIGHTLY:-nightly-2026-10-30}

# need_nightly [COMPONENT...]: the pinned nightly toolchain with these components.
need_nightly() {
    if ! rustup toolchain list | grep -q "^$OPCCOMN_NIGHTLY-"; then
        echo "== installing: Rust $OPCCOMN_NIGHTLY (rustup, minimal profile${1:+, with $*})"
        rustup toolchain install "$OPCCOMN_NIGHTLY" --profile minimal
    fi
    local installed component
    installed=$(rustup +"$OPCCOMN_NIGHTLY" component list --installed 2>/dev/null || true)
    for component in "$@"; do
        if ! grep -q "^$component" <<<"$installed"; then
            echo "== installing: $component for Rust $OPCCOMN_NIGHTLY (rustup)"
            rustup component add "$component" --toolchain "$OPCCOMN_NIGHTLY"
        fi
    done
}

# valgrind, and the nightly toolchain with the standard library's sources (ThreadSanitizer needs an
# instrumented standard library, built with -Zbuild-std).
need_soundness_tools() {
    command -v valgrind >/dev/null || install_packages "for the leak checks" valgrind
    need_nightly rust-src
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
    command -v python3 >/dev/null || missing+=(python3)
    command -v wine >/dev/null || missing+=(wine wine64)
    # 32-bit (x86) builds.
    command -v i686-w64-mingw32-gcc >/dev/null || missing+=(gcc-mingw-w64-i686)
    command -v i686-w64-mingw32-g++ >/dev/null || missing+=(g++-mingw-w64-i686)
    command -v i686-w64-mingw32-windres >/dev/null || missing+=(binutils-mingw-w64-i686)
    # The MSVC-format import library (llvm-dlltool, llvm-lib) and the MSVC-mode link test (clang, lld-link).
    command -v clang >/dev/null || missing+=(clang)
    command -v lld-link >/dev/null || missing+=(lld)
    { command -v llvm-dlltool && command -v llvm-lib; } >/dev/null || missing+=(llvm)
    install_packages "to cross-build the Windows DLLs (mingw-w64, clang, lld) and run them (64-bit Wine)" "${missing[@]}"
    local target
    for target in x86_64-pc-windows-gnu i686-pc-windows-gnu; do
        if ! rustup target list --installed | grep -qx "$target"; then
            echo "== installing: Rust target $target (rustup)"
            rustup target add "$target"
        fi
    done
}

# 32-bit Wine (Debian's wine32:i386, after `dpkg --add-architecture i386`; about 2 minutes). Returns 1
# and sets `wine32_missing` to the reason when it cannot be installed (on 2026-12-01 Debian's i386
# security index failed to download for a while, which made wine32:i386 uninstallable); the caller
# must then report the 32-bit run as skipped.
wine32_missing=""
need_wine32() {
    dpkg -s wine32:i386 >/dev/null 2>&1 && return 0
    local sudo="" added=0 log
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    log=$(mktemp)
    if ! dpkg --print-foreign-architectures | grep -qx i386; then
        echo "== installing: wine32:i386 (32-bit Wine, to run the x86 DLL), after adding Debian's i386 architecture (dpkg --add-architecture i386)"
    else
        echo "== installing: wine32:i386 (32-bit Wine, to run the x86 DLL)"
    fi
    if ! dpkg --print-foreign-architectures | grep -qx i386; then
        $sudo dpkg --add-architecture i386
        added=1
    fi
    if ! $sudo apt-get -o DPkg::Lock::Timeout=900 update -qq >"$log" 2>&1 || grep -q '^[EW]: ' "$log"; then
        wine32_missing="apt-get update with i386 failed: $(grep -m2 '^[EW]: ' "$log" | tr '\n' ' ')"
    fi
    if ! DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=900 install -y -qq \
            --no-install-recommends wine32:i386 >>"$log" 2>&1; then
        wine32_missing="apt-get install wine32:i386 failed: $(grep -m3 '^E: \|Depends:\|Breaks:' "$log" | tr '\n' ' ')${wine32_missing:+ (after: $wine32_missing)}"
        # Leave no half-usable foreign architecture behind: its broken index would fail every later
        # `apt-get update` on this machine.
        [ "$added" = 1 ] && $sudo dpkg --remove-architecture i386 2>/dev/null || true
        rm -f "$log"
        return 1
    fi
    rm -f "$log"
    wine32_missing=""
    dpkg -s wine32:i386 >/dev/null 2>&1 || { wine32_missing="wine32:i386 is not installed after apt-get install"; return 1; }
}

# The nightly toolchain with the standard library's sources, for the tier-3 Windows 7 targets
# (x86_64-win7-windows-gnu, i686-win7-windows-gnu are built with -Zbuild-std).
need_nightly_rust_src() {
    need_nightly rust-src
}

# Miri: the nightly toolchain with its miri component and the standard library's sources (Miri builds
# its own sysroot from them). A component that cannot be installed fails the caller (set -e): the Miri
# stage never passes without Miri.
need_miri() {
    need_nightly rust-src miri
    cargo +"$OPCCOMN_NIGHTLY" miri --version >/dev/null
}

# wixl (Debian's msitools: wixl, msibuild, msiinfo) builds the Windows Installer packages from WiX
# sources (scripts/build-msi.sh); Wine's msiexec installs them in the tests.
need_msi_tools() {
    local missing=()
    command -v wixl >/dev/null || missing+=(wixl)
    { command -v msiinfo && command -v msibuild; } >/dev/null || missing+=(msitools)
    install_packages "to build the MSI packages (wixl, msibuild, msiinfo)" "${missing[@]}"
}

# install_packages WHY PACKAGE...: installs the Debian packages, saying which and why first.
install_packages() {
    local why=$1
    shift
    [ "$#" -eq 0 ] && return 0
    local sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    echo "== installing (apt-get${sudo:+ with sudo}) $why: $*"
    # An index that fails to download (it happens, e.g. Debian's i386 security index) must not stop
    # installs that the other indexes serve.
    $sudo apt-get -o DPkg::Lock::Timeout=900 update -qq || echo "== warning: apt-get update failed; installing from the lists there are" >&2
    DEBIAN_FRONTEND=noninteractive $sudo apt-get -o DPkg::Lock::Timeout=900 install -y -qq --no-install-recommends "$@" >/dev/null
}

# Nightly Rust for the fuzz targets (libFuzzer instrumentation with AddressSanitizer).
need_fuzz_tools() {
    need_nightly
}
