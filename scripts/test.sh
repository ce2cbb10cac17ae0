#!/usr/bin/env bash
# Runs every test of the project: lint and drift of generated files, Rust tests, C tests on Linux under
# AddressSanitizer and UBSan and under valgrind, a thread stress test under ThreadSanitizer, the
# installed package (CMake config and pkg-config), the fuzz targets for a bounded time, the Windows
# DLL with the same C tests under Wine, and the header's coexistence with the OPC Foundation's MIDL
# headers (scripts/test-coexistence.sh). Installs what is missing on a fresh
# Debian 12 machine.
#
# Usage: scripts/test.sh [--no-wine] [--no-lint] [--no-fuzz]     (CI runs it with no options)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh

wine_stage=1
lint_stage=1
fuzz_stage=1
for arg in "$@"; do
    case "$arg" in
        --no-wine) wine_stage=0 ;;
        --no-lint) lint_stage=0 ;;
        --no-fuzz) fuzz_stage=0 ;;
        *) echo "usage: scripts/test.sh [--no-wine] [--no-lint] [--no-fuzz]" >&2; exit 2 ;;
    esac
done

build="$root/build"
stages=0
stage() {
    stages=$((stages + 1))
    printf '\n==== %s\n' "$*"
}

need_linux_tools
need_soundness_tools
[ "$wine_stage" = 1 ] && need_windows_tools

if [ "$lint_stage" = 1 ]; then
    stage "format, clippy, drift of generated files (header, C test vectors, case folding)"
    cargo fmt --all -- --check
    cargo clippy --all-targets -- -D warnings
    [ "$wine_stage" = 1 ] && cargo clippy --lib --target x86_64-pc-windows-gnu -- -D warnings
    cargo run -q -p gen-header -- --check
    scripts/check-generated.sh
fi

stage "Rust tests (Linux)"
cargo test

stage "C tests (Linux, AddressSanitizer + UBSan)"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
cmake -S . -B "$build/linux" -DOPCCOMN_SANITIZE=ON >/dev/null
cmake --build "$build/linux" -j2
ctest --test-dir "$build/linux" --output-on-failure --timeout 300
scripts/check-exports.sh "$build/linux/cargo/release/libopccomn.so"

stage "C tests (Linux, valgrind --leak-check=full, no sanitizer)"
cmake -S . -B "$build/valgrind" -DOPCCOMN_VALGRIND=ON >/dev/null
cmake --build "$build/valgrind" -j2
ctest --test-dir "$build/valgrind" --output-on-failure --timeout 900 -R '^c\.'

stage "thread stress test (ThreadSanitizer, instrumented standard library)"
# 8 threads on one IOPCCommon, one shutdown object whose sinks unadvise themselves during a notify,
# one compiled pattern (src/stress_tests.rs). Any report fails the run (halt_on_error).
RUSTFLAGS="-Zsanitizer=thread" TSAN_OPTIONS="halt_on_error=1" CARGO_TARGET_DIR="$root/target/tsan" \
    cargo +nightly test -Zbuild-std --target x86_64-unknown-linux-gnu --lib stress_tests

stage "installed package: find_package(opccomn CONFIG) and pkg-config"
rm -rf "$build/install" "$build/consumer"
cmake --install "$build/linux" --prefix "$build/install" >/dev/null
cmake -S examples/consumer -B "$build/consumer" -DCMAKE_PREFIX_PATH="$build/install" >/dev/null
cmake --build "$build/consumer" -j2 >/dev/null
"$build/consumer/consumer"
PKG_CONFIG_PATH="$build/install/lib/pkgconfig" cc -o "$build/consumer/pkgconfig_demo" examples/demo.c \
    $(PKG_CONFIG_PATH="$build/install/lib/pkgconfig" pkg-config --cflags --libs opccomn) \
    -Wl,-rpath,"$build/install/lib"
"$build/consumer/pkgconfig_demo" >/dev/null

stage "library without the standard Dll* exports (for COM DLLs that have their own)"
cmake -S . -B "$build/no-dll-exports" -DOPCCOMN_DLL_EXPORTS=OFF -DOPCCOMN_BUILD_TESTS=OFF >/dev/null
cmake --build "$build/no-dll-exports" -j2 >/dev/null
no_exports=$(nm -D --defined-only "$build/no-dll-exports/cargo/release/libopccomn.so" | awk '{print $3}')
if grep -qx DllGetClassObject <<<"$no_exports" || ! grep -qx OpcDllGetClassObject <<<"$no_exports"; then
    echo "OPCCOMN_DLL_EXPORTS=OFF: expected OpcDllGetClassObject without DllGetClassObject" >&2
    exit 1
fi
echo "OPCCOMN_DLL_EXPORTS=OFF: Dll* absent, OpcDll* present"

if [ "$fuzz_stage" = 1 ]; then
    stage "fuzz targets (libFuzzer + AddressSanitizer, ${OPCCOMN_FUZZ_SECONDS:-30} s per target)"
    scripts/fuzz.sh "${OPCCOMN_FUZZ_SECONDS:-30}"
else
    printf '\n==== SKIPPED: fuzz targets (--no-fuzz); not counted as passed\n'
fi

# The C++ example (examples/cpp-server) built as a user builds it: against a Windows build installed as
# a package (find_package). Its client registers the example servers, uses them through COM under Wine,
# unregisters them and checks the registry; ctest passes it only on its own "N passed, 0 failed" line.
# Usage: example_stage ARCH LIBRARY_BUILD_DIR TOOLCHAIN_FILE
example_stage() {
    local arch=$1 lib_build=$2 toolchain=$3
    rm -rf "$build/example-$arch" "$build/example-$arch-install"
    cmake --install "$lib_build" --prefix "$build/example-$arch-install" >/dev/null
    cmake -S examples/cpp-server -B "$build/example-$arch" -DCMAKE_TOOLCHAIN_FILE="$toolchain" \
        -DCMAKE_PREFIX_PATH="$build/example-$arch-install" >/dev/null
    cmake --build "$build/example-$arch" -j2
    ctest --test-dir "$build/example-$arch" --output-on-failure --timeout 300
}

if [ "$wine_stage" = 1 ]; then
    . scripts/wine-env.sh "$build/windows"

    stage "Rust tests (Windows, under Wine)"
    CARGO_TARGET_X86_64_PC_WINDOWS_GNU_RUNNER=wine cargo test --target x86_64-pc-windows-gnu --lib

    stage "C tests (Windows DLL, under Wine)"
    cmake -S . -B "$build/windows" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-x86_64.cmake" >/dev/null
    cmake --build "$build/windows" -j2
    ctest --test-dir "$build/windows" --output-on-failure --timeout 300
    scripts/check-exports.sh "$build/windows/cargo/x86_64-pc-windows-gnu/release/opccomn.dll"

    stage "header and library beside the OPC Foundation's headers and *_i.c (x64, x86 compile-only, Linux)"
    scripts/test-coexistence.sh "$build/windows" "$build/linux"

    stage "C++ example server and client (x64, under Wine, against the installed package)"
    example_stage x64 "$build/windows" "$root/cmake/mingw-w64-x86_64.cmake"
else
    echo "test.sh: --no-wine: the Windows stages, the header coexistence stage and the C++ example were NOT run" >&2
fi

# Every stage ran to its end (set -e stops at the first failure).
printf '\n==== all stages passed\ntest.sh: %d passed, 0 failed\n' "$stages"
