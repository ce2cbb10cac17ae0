#!/usr/bin/env bash
# Runs every test of the project: lint and drift of generated files, Rust tests, C tests on Linux under
# AddressSanitizer and UBSan and under valgrind, a thread stress test under ThreadSanitizer, the
# installed package (CMake config and pkg-config), the fuzz targets for a bounded time, the Windows
# DLL with the same C tests under Wine, and the header's coexistence with the OPC Foundation's MIDL
# headers (scripts/test-coexistence.sh). Installs what is missing on a fresh
# Debian 12 machine.
#
# Also runs the tests that do not call the operating system under Miri (Stacked and Tree Borrows).
#
# Usage: scripts/test.sh [--no-wine] [--no-lint] [--no-fuzz] [--no-miri]     (CI runs it with no options)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh

wine_stage=1
lint_stage=1
fuzz_stage=1
miri_stage=1
for arg in "$@"; do
    case "$arg" in
        --no-wine) wine_stage=0 ;;
        --no-lint) lint_stage=0 ;;
        --no-fuzz) fuzz_stage=0 ;;
        --no-miri) miri_stage=0 ;;
        *) echo "usage: scripts/test.sh [--no-wine] [--no-lint] [--no-fuzz] [--no-miri]" >&2; exit 2 ;;
    esac
done

build="$root/build"
stages=0
skipped=0
stage_started=$SECONDS
stage() {
    stages=$((stages + 1))
    printf '\n==== %s   (previous stage: %ds)\n' "$*" $((SECONDS - stage_started))
    stage_started=$SECONDS
}
# A stage that could not run: said loudly, counted as skipped, never as passed.
skip_stage() {
    skipped=$((skipped + 1))
    printf '\n==== SKIPPED: %s\n' "$1"
    printf '!!!! %s\n' "${@:2}"
}

# Runs the C tests of a 32-bit Windows build directory under 32-bit Wine and proves they ran: a 32-bit
# program that did not start prints nothing, so every test must have printed its closing line.
run_x86_c_tests() {
    local dir=$1 tests t oop_tests ps_tests lines
    # (ctest -N rewrites Testing/Temporary/LastTest.log: list the tests before running them.)
    tests=$(ctest --test-dir "$dir" -N | sed -nE 's/^ *Test +#[0-9]+: c\.(test_[A-Za-z0-9_]+)$/\1/p')
    oop_tests=$(ctest --test-dir "$dir" -N | grep -cE '^ *Test +#[0-9]+: oop\.') || true
    ps_tests=$(ctest --test-dir "$dir" -N | grep -cE '^ *Test +#[0-9]+: ps\.test_[a-z_]+$') || true
    [ -n "$tests" ] || { echo "no C tests found in $dir" >&2; exit 1; }
    ctest --test-dir "$dir" --output-on-failure --timeout 300
    for t in $tests; do
        grep -qE "^$t: [0-9]+ passed, 0 failed" "$dir/Testing/Temporary/LastTest.log" ||
            { echo "$t (x86, $dir) printed no result line" >&2; exit 1; }
    done
    # The cross-process tests (tests/oop) of the same build: one result line per ctest entry.
    lines=$(grep -cE '^test_(oop|browser|ps_registration): [0-9]+ passed, 0 failed' \
        "$dir/Testing/Temporary/LastTest.log") || true
    [ "$oop_tests" -gt 0 ] && [ "$oop_tests" = "$lines" ] ||
        { echo "x86 cross-process tests in $dir: $oop_tests tests, $lines result lines" >&2; exit 1; }
    # The proxy/stub robustness tests (ps.*; the runs against the unchecked stand-in must fail).
    lines=$(grep -cE '^test_(stub_requests|proxy_replies): [0-9]+ passed, 0 failed' \
        "$dir/Testing/Temporary/LastTest.log") || true
    [ "$ps_tests" -gt 0 ] && [ "$ps_tests" = "$lines" ] ||
        { echo "x86 proxy/stub tests in $dir: $ps_tests tests, $lines result lines" >&2; return 1; }
    echo "every x86 C test, cross-process test and proxy/stub test in $dir printed its result line"
}

need_linux_tools
need_soundness_tools
# Every Wine package, 32-bit Wine included, is installed before the Wine prefix is made: a prefix made
# by 64-bit Wine alone is unusable once wine32:i386 arrives (scripts/wine-env.sh also makes such a
# prefix anew).
wine32_installed=0
if [ "$wine_stage" = 1 ]; then
    need_windows_tools
    need_wine32 && wine32_installed=1
fi

if [ "$lint_stage" = 1 ]; then
    stage "format, clippy, drift of generated files (header, C test vectors, case folding)"
    cargo fmt --all -- --check
    cargo clippy --all-targets -- -D warnings
    if [ "$wine_stage" = 1 ]; then
        cargo clippy --lib --target x86_64-pc-windows-gnu -- -D warnings
        cargo clippy --lib --target i686-pc-windows-gnu -- -D warnings
    fi
    cargo run -q -p gen-header -- --check
    scripts/check-generated.sh
    python3 tools/gen-null-rule-test.py --check
    # The generator's own checks (IDL reader, the Rust-vtable comparison catching each kind of mismatch).
    cargo clippy -q -p gen-header --all-targets -- -D warnings
    cargo test -q -p gen-header
    # The proxy/stub's NDR tables are generated from idl/opccomn.idl (widl and the system IDLs come
    # with the Windows tools).
    [ "$wine_stage" = 1 ] && python3 tools/gen-proxy.py --check
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

if [ "$miri_stage" = 1 ]; then
    # Stacked Borrows and Tree Borrows, one process each, at once (scripts/miri.sh): the COM core,
    # IOPCCommon, errors, locale, pattern, shutdown with the in-process sink, the server list and the
    # registry over the in-memory registry, the stress test. Any report fails the stage.
    stage "Miri (Stacked Borrows and Tree Borrows): every test that does not call the operating system"
    scripts/miri.sh
else
    skip_stage "Miri (--no-miri)" "The Miri stage was NOT run: this run does not prove the absence of undefined behaviour."
fi

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

    # Narrow strings are in the ANSI code page on Windows; the prefix's default is 1252. Wine takes
    # the code page from the locale's name (installed or not), so LC_ALL=ja_JP.SJIS gives 932, a
    # double-byte one; the test asserts it (OPCCOMN_TEST_ACP) and says which it ran under.
    stage "MatchPatternA and the narrow compiled filter in ANSI code page 932 (double-byte), under Wine"
    acp_test=pattern::tests::narrow_entry_points_agree_with_the_decoded_ansi_code_page
    acp_out=$(OPCCOMN_TEST_ACP=932 LC_ALL=ja_JP.SJIS CARGO_TARGET_X86_64_PC_WINDOWS_GNU_RUNNER=wine \
        cargo test --target x86_64-pc-windows-gnu --lib -- --exact "$acp_test" --nocapture 2>&1) ||
        { echo "$acp_out"; exit 1; }
    grep -q "narrow differential in ANSI code page 932" <<<"$acp_out" && grep -q "test result: ok. 1 passed" <<<"$acp_out" ||
        { echo "$acp_out"; echo "the code page 932 test did not run" >&2; exit 1; }
    echo "$acp_test: passed in ANSI code page 932"

    stage "C tests (Windows DLL, under Wine)"
    cmake -S . -B "$build/windows" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-x86_64.cmake" >/dev/null
    cmake --build "$build/windows" -j2
    ctest --test-dir "$build/windows" --output-on-failure --timeout 300
    scripts/check-exports.sh "$build/windows/cargo/x86_64-pc-windows-gnu/release/opccomn.dll"

    stage "header and library beside the OPC Foundation's headers and *_i.c (x64, x86 compile-only, Linux)"
    scripts/test-coexistence.sh "$build/windows" "$build/linux"

    stage "C++ example server and client (x64, under Wine, against the installed package)"
    example_stage x64 "$build/windows" "$root/cmake/mingw-w64-x86_64.cmake"

    stage "conformance checker (opccomn-check): every seeded defect caught by its check, the example server passing (x64, in-process, under Wine)"
    scripts/test-conformance.sh "$build/windows/bin" "$build/example-x64"

    stage "Windows x86 (i686-pc-windows-gnu): DLL, static library, opccomn.lib, C tests built, undecorated exports"
    cmake -S . -B "$build/windows-x86" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-i686.cmake" >/dev/null
    cmake --build "$build/windows-x86" -j2
    x86_out="$build/windows-x86/cargo/i686-pc-windows-gnu/release"
    scripts/check-exports.sh "$x86_out/opccomn.dll"
    ls "$x86_out/libopccomn.a" "$x86_out/libopccomn.dll.a" "$x86_out/msvc/opccomn.lib" >/dev/null

    # 32-bit Wine: without wine32:i386 `wine prog32.exe` exits 0 without running anything, so the
    # stages below run only after a 32-bit program has been seen to run and print.
    wine32_ok=0
    if [ "$wine32_installed" = 1 ]; then
        i686-w64-mingw32-gcc -O2 -o "$build/windows-x86/wow64_canary.exe" tests/wine/wow64_canary.c
        canary=$(wine "$build/windows-x86/wow64_canary.exe" 2>&1 | tr -d '\r') || true
        if [ "$canary" = "wow64 canary: 32-bit process, WOW64 yes" ]; then
            wine32_ok=1
        else
            wine32_missing="wine32:i386 is installed, but a 32-bit program did not run (it printed: '$canary')"
        fi
    fi
    if [ "$wine32_ok" = 1 ]; then
        stage "Rust tests (Windows x86, under 32-bit Wine)"
        # RUST_BACKTRACE=0: with backtraces on (RUST_BACKTRACE=1 in the environment), taking the
        # backtrace of a panic under Debian 12's 32-bit Wine 8 reads through NULL inside its ucrtbase
        # and kills the process at the first test that panics on purpose (the boundary's panic tests);
        # a plain program that catches a panic survives it. What those tests check is the library's
        # handling of the panic; the x64 stage above runs them with backtraces as the environment sets.
        RUST_BACKTRACE=0 CARGO_TARGET_I686_PC_WINDOWS_GNU_RUNNER=wine cargo test --target i686-pc-windows-gnu --lib

        stage "C tests and cross-process tests (Windows x86 DLL, under 32-bit Wine)"
        run_x86_c_tests "$build/windows-x86"

        stage "conformance checker (opccomn-check, x86) against the x86 seeded-defect servers, under 32-bit Wine"
        scripts/test-conformance.sh "$build/windows-x86/bin" - "$build/windows/bin/opccomn-check.exe"

        stage "cross-process: a 32-bit client browses both registry views through the 64-bit browser service"
        wine "$build/windows/bin/test_browser.exe" wow64-serve
        wow64_rc=0
        wine "$build/windows-x86/bin/test_browser.exe" wow64-client || wow64_rc=$?
        wine "$build/windows/bin/test_browser.exe" wow64-cleanup
        [ "$wow64_rc" = 0 ]
    else
        skip_stage "Rust tests, C tests, cross-process tests and the conformance checker of the x86 DLL under 32-bit Wine" \
            "32-bit Wine is not available: $wine32_missing" \
            "The x86 DLL was built and its exports checked, but it was NOT run. This run does not prove x86."
    fi

    # Windows 7 / Server 2008 R2: Rust's tier-3 *-win7-windows-gnu targets (nightly, -Zbuild-std).
    need_nightly_rust_src
    win7_args=(-DOPCCOMN_RUST_TOOLCHAIN=nightly "-DOPCCOMN_CARGO_ARGS=-Zbuild-std=std,panic_unwind"
        -DOPCCOMN_BUILD_CHECKER=OFF)   # the checker and its test servers run from the x64 and x86 builds
    stage "Windows 7 builds (x86_64-win7-windows-gnu, i686-win7-windows-gnu): import tables"
    cmake -S . -B "$build/windows7-x64" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-x86_64.cmake" \
        -DOPCCOMN_RUST_TARGET=x86_64-win7-windows-gnu "${win7_args[@]}" >/dev/null
    cmake --build "$build/windows7-x64" -j2
    cmake -S . -B "$build/windows7-x86" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-i686.cmake" \
        -DOPCCOMN_RUST_TARGET=i686-win7-windows-gnu "${win7_args[@]}" >/dev/null
    cmake --build "$build/windows7-x86" -j2
    for dll in "$build/windows7-x64/cargo/x86_64-win7-windows-gnu/release/opccomn.dll" \
        "$build/windows7-x86/cargo/i686-win7-windows-gnu/release/opccomn.dll"; do
        scripts/check-imports-win7.sh "$dll"
        scripts/check-exports.sh "$dll"
    done
    # The check can fail: the default build needs Windows 10 (ProcessPrng) and must be refused.
    if scripts/check-imports-win7.sh "$build/windows/cargo/x86_64-pc-windows-gnu/release/opccomn.dll" >/dev/null 2>&1; then
        echo "check-imports-win7.sh accepted the default build, which imports ProcessPrng" >&2
        exit 1
    fi

    stage "C tests (Windows 7 x64 DLL, under Wine)"
    ctest --test-dir "$build/windows7-x64" --output-on-failure --timeout 300

    if [ "$wine32_ok" = 1 ]; then
        stage "C tests (Windows 7 x86 DLL, under 32-bit Wine)"
        run_x86_c_tests "$build/windows7-x86"
    else
        skip_stage "C tests of the Windows 7 x86 DLL under 32-bit Wine" \
            "32-bit Wine is not available: $wine32_missing" \
            "The Windows 7 x86 DLL was built and its import table checked, but it was NOT run."
    fi

    stage "Windows binary package: unpacked, a CMake consumer built against it (x64, x86, Windows 7) and run"
    scripts/package-windows.sh "$build/package" >/dev/null
    version=$(sed -nE 's/^version = "([^"]+)"$/\1/p' Cargo.toml | head -1)
    rm -rf "$build/package-test" && mkdir -p "$build/package-test"
    (cd "$build/package-test" && cmake -E tar xf "$build/package/opccomn-$version-windows.zip")
    pkg="$build/package-test/opccomn-$version-windows"
    for variant in x64:x86_64:OFF x86:i686:OFF x64:x86_64:ON; do
        IFS=: read -r arch toolchain win7 <<<"$variant"
        dir="$build/package-test/consumer-$arch-win7-$win7"
        cmake -S examples/consumer -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-$toolchain.cmake" \
            -DCMAKE_PREFIX_PATH="$pkg" -DOPCCOMN_WINDOWS7="$win7" >/dev/null
        cmake --build "$dir" -j2 >/dev/null
        # The program got the package's DLL of its own architecture and variant.
        want="$pkg/$arch/opccomn.dll"
        [ "$win7" = ON ] && want="$pkg/win7/$arch/opccomn.dll"
        cmp -s "$want" "$dir/opccomn.dll" || { echo "$dir/opccomn.dll is not $want" >&2; exit 1; }
        if [ "$arch" = x86 ] && [ "$wine32_ok" != 1 ]; then
            echo "package consumer ($arch): built, NOT run (no 32-bit Wine; see the SKIPPED stage)"
            continue
        fi
        (cd "$dir" && wine consumer.exe >consumer.out)
        echo "package consumer ($arch, Windows 7 variant $win7): ran, $(wc -l <"$dir/consumer.out") lines of output"
    done

    stage "C++ example server and client built with CMake against the unpacked package (x64, x86), under Wine"
    for variant in x64:x86_64 x86:i686; do
        IFS=: read -r arch toolchain <<<"$variant"
        dir="$build/package-test/cpp-server-$arch"
        cmake -S examples/cpp-server -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-$toolchain.cmake" \
            -DCMAKE_PREFIX_PATH="$pkg" >/dev/null
        cmake --build "$dir" -j2 >/dev/null
        if [ "$arch" = x86 ] && [ "$wine32_ok" != 1 ]; then
            echo "C++ example ($arch): built, NOT run (no 32-bit Wine; see the SKIPPED stage)"
            continue
        fi
        ctest --test-dir "$dir" --output-on-failure --timeout 300
        # The package's opccomn-check of the same architecture against this example DLL: all passed.
        cp "$pkg/$arch/opccomn-check.exe" "$dir/"
        (cd "$dir" && wine regsvr32 /s opccomn_example_inproc.dll)
        rc=0
        (cd "$dir" && wine opccomn-check.exe OpcComn.ExampleServerInProc.1 --format json >check.json 2>check.log) || rc=$?
        (cd "$dir" && wine regsvr32 /u /s opccomn_example_inproc.dll)
        tr -d '\r' <"$dir/check.json" >"$dir/check.json.lf"
        python3 tests/conformance/check_report.py json "$dir/check.json.lf" "$rc"
    done

    stage "MSVC-mode program (clang --target=*-pc-windows-msvc, lld-link, no CRT) linked against the package's opccomn.lib, under Wine"
    scripts/test-msvc-link.sh x64 "$pkg/x64" "$build/package-test/msvc-x64"
    if [ "$wine32_ok" = 1 ]; then
        scripts/test-msvc-link.sh x86 "$pkg/x86" "$build/package-test/msvc-x86"
    else
        scripts/test-msvc-link.sh --no-run x86 "$pkg/x86" "$build/package-test/msvc-x86"
        echo "msvc link test (x86): linked, NOT run (no 32-bit Wine; see the SKIPPED stage)"
    fi
else
    echo "test.sh: --no-wine: the Windows stages, the header coexistence stage and the C++ example were NOT run" >&2
fi

# Every stage ran to its end (set -e stops at the first failure).
printf '\n(last stage: %ds; all: %ds)\n' $((SECONDS - stage_started)) "$SECONDS"
if [ "$skipped" -eq 0 ]; then
    printf '\n==== all stages passed\ntest.sh: %d passed, 0 failed\n' "$stages"
else
    printf '\n==== %d stages passed, %d SKIPPED (see the SKIPPED lines above)\ntest.sh: %d passed, 0 failed, %d skipped\n' \
        "$stages" "$skipped" "$stages" "$skipped"
fi
