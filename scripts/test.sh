#!/usr/bin/env bash
# Runs every test of the project, stage by stage: lint and drift of generated files, Rust tests, C tests
# on Linux under AddressSanitizer and UBSan and under valgrind, a thread stress test under
# ThreadSanitizer, Miri, the installed package (CMake config and pkg-config), the fuzz targets for a
# bounded time, the Windows DLLs (x64, x86, Windows 7) with the same C tests under Wine's COM runtime,
# the header's coexistence with the OPC Foundation's MIDL headers, the C++ example, the conformance
# checker and the Windows binary package. `--list` names the stages.
#
# Installs what is missing on a fresh Debian 12 machine, and says what before it installs it: Debian
# packages with apt-get (cmake, gcc, llvm, valgrind, mingw-w64, clang, lld, Wine, and 32-bit Wine
# after adding Debian's i386 architecture), and with rustup the nightly toolchain (rust-src, Miri) and
# the two Windows targets. Every package, 32-bit Wine included, is installed before the Wine prefix is
# made.
#
# Every stage runs, even after one failed. A stage that does not run, for whatever reason (an option,
# a missing 32-bit Wine, --only), is counted and named as skipped, never as passed. The last line is
#   test.sh: N passed, N failed, N skipped
# and the exit status is 1 when a stage failed.
#
# Usage: scripts/test.sh [--no-wine] [--no-lint] [--no-fuzz] [--no-miri] [--only STAGE]... [--list]
#   (CI runs it with no options)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh
build="$root/build"

# ---- The stages, in the order they run: name, group, description ----------------------------------
# Group: linux (needs nothing but the Linux tools), wine (the Windows tools and Wine), wine32 (32-bit
# Wine as well).
stage_table='lint|linux|format, clippy (Linux and Windows targets), drift of every generated file, the IDL against the OPC interface tables
rust-linux|linux|Rust tests (Linux)
c-asan|linux|C tests (Linux, AddressSanitizer + UBSan) and the exported symbols
c-valgrind|linux|C tests (Linux, valgrind --leak-check=full, no sanitizer)
tsan|linux|thread stress test (ThreadSanitizer, instrumented standard library)
package-linux|linux|installed package: find_package(opccomn CONFIG) and pkg-config; the static library linked with the README'"'"'s and pkg-config'"'"'s lists
no-dll-exports|linux|library without the standard Dll* exports (for COM DLLs that have their own)
docs|linux|C API reference (Doxygen): every item, parameter and result documented, a page per area with its example, search; rendered in headless Chromium
cmake-msvc|linux|CMake'"'"'s Visual Studio paths (stand-in MSVC toolchain, x64 and Win32): the project and add_subdirectory configure
msvc-build-script|linux|the build script for Visual Studio (x86_64-pc-windows-msvc): stops naming missing tools; with stand-ins, calls cl, lib, rc, mc
fuzz|linux|fuzz targets (libFuzzer + AddressSanitizer, a bounded time per target)
rust-windows|wine|Rust tests (Windows x64, under Wine)
acp932|wine|MatchPatternA and the narrow compiled filter in ANSI code page 932 (double-byte), under Wine
c-windows|wine|C tests and cross-process tests (Windows x64 DLL, under Wine) and the exported symbols
example-x64|wine|C++ example server and client (x64, under Wine, against the installed package)
third-party-client|wine|public third-party OPC client (crates opc_da 0.3.1, opc_comn_bindings 0.3.0): browse through the browser service, IOPCCommon and shutdown through the proxy/stub, a Data Access client of the C test DA server and of a DA server made with opc_da'"'"'s server module, through the proxy/stub alone (x64 and x86 clients, under Wine)
conformance-x64|wine|conformance checker: every seeded defect caught, the example server passing (x64, under Wine)
build-x86|wine|Windows x86 build: DLL, static library, opccomn.lib, C tests, undecorated exports
coexistence|wine|header and library beside the OPC Foundation'"'"'s headers (MIDL'"'"'s and widl'"'"'s) and *_i.c; a server DLL with its own .def; the static library linked with the documented and pkg-config'"'"'s lists (x64, x86, Linux)
rust-x86|wine32|Rust tests (Windows x86, under 32-bit Wine)
c-x86|wine32|C tests and cross-process tests (Windows x86 DLL, under 32-bit Wine)
conformance-x86|wine32|conformance checker (x86) against the x86 seeded-defect servers, under 32-bit Wine
wow64-browse|wine32|cross-process: a 32-bit client browses both registry views through the 64-bit browser service
win7-build|wine|Windows 7 builds (x86_64-win7-windows-gnu, i686-win7-windows-gnu): import tables and exports
c-win7-x64|wine|C tests (Windows 7 x64 DLL, under Wine)
c-win7-x86|wine32|C tests (Windows 7 x86 DLL, under 32-bit Wine)
package-windows|wine|Windows binary package: unpacked, a CMake consumer built against it (x64, x86, Windows 7) and run
msi|wine32|the MSI packages under msiexec: silent install and removal, a major upgrade, OpcEnum and a Foundation-style proxy/stub before and after, two vendor products sharing the components, the registry (both views) as before; clients browse and marshal through the installed files (x64 and x86 packages, 64- and 32-bit clients)
package-cpp-example|wine|C++ example server and client and opccomn-check, built against the unpacked package (x64, x86), under Wine
msvc-link|wine|MSVC-mode program (clang --target=*-pc-windows-msvc, lld-link) linked against the package'"'"'s opccomn.lib, under Wine
miri|linux|Miri: every test that does not call the operating system (Stacked Borrows); the tests of the COM objects (Tree Borrows); started first at low priority, reported last'

stage_names=()
declare -A stage_group stage_text
while IFS='|' read -r name group text; do
    stage_names+=("$name")
    stage_group[$name]=$group
    stage_text[$name]=$text
done <<<"$stage_table"

usage() {
    echo "usage: scripts/test.sh [--no-wine] [--no-lint] [--no-fuzz] [--no-miri] [--only STAGE]... [--list]" >&2
    exit 2
}
declare -A only=() disabled=()
list=0
while [ "$#" -gt 0 ]; do
    case "$1" in
        --no-wine) disabled[wine]="--no-wine" ;;
        --no-lint) disabled[lint]="--no-lint" ;;
        --no-fuzz) disabled[fuzz]="--no-fuzz" ;;
        --no-miri) disabled[miri]="--no-miri" ;;
        --only)
            [ "$#" -ge 2 ] && [ -n "${stage_group[$2]+set}" ] || { echo "scripts/test.sh: --only needs a stage name (see --list)" >&2; usage; }
            only[$2]=1
            shift
            ;;
        --list) list=1 ;;
        *) usage ;;
    esac
    shift
done
if [ "$list" = 1 ]; then
    for name in "${stage_names[@]}"; do
        printf '%-20s %s\n' "$name" "${stage_text[$name]}"
    done
    exit 0
fi

# Why a stage will not run, or nothing when it will.
reason_not_to_run() {
    local name=$1 group=${stage_group[$1]}
    if [ "${#only[@]}" -gt 0 ] && [ -z "${only[$name]+set}" ]; then
        echo "not selected (--only)"
    elif [ -n "${disabled[$name]+set}" ]; then
        echo "${disabled[$name]}"
    elif [ "$group" != linux ] && [ -n "${disabled[wine]+set}" ]; then
        echo "--no-wine"
    elif [ "$group" = wine32 ] && [ "$wine32_ok" != 1 ]; then
        echo "32-bit Wine is not available: $wine32_missing"
    fi
}
selected() {
    local name
    for name in "${stage_names[@]}"; do
        [ "${stage_group[$name]}" = "$1" ] || { [ "$1" = wine ] && [ "${stage_group[$name]}" = wine32 ]; } || continue
        [ "${#only[@]}" -gt 0 ] && [ -z "${only[$name]+set}" ] && continue
        [ -n "${disabled[$name]+set}" ] && continue
        [ "${stage_group[$name]}" != linux ] && [ -n "${disabled[wine]+set}" ] && continue
        return 0
    done
    return 1
}

# ---- Builds shared by several stages (incremental: each stage builds what it needs) ---------------
build_linux() {
    export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
    cmake -S . -B "$build/linux" -DOPCCOMN_SANITIZE=ON >/dev/null
    cmake --build "$build/linux" -j2
}
build_windows() {
    cmake -S . -B "$build/windows" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-x86_64.cmake" >/dev/null
    cmake --build "$build/windows" -j2
}
build_windows_x86() {
    cmake -S . -B "$build/windows-x86" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-i686.cmake" >/dev/null
    cmake --build "$build/windows-x86" -j2
}
win7_args=(-DOPCCOMN_RUST_TOOLCHAIN="$OPCCOMN_NIGHTLY" "-DOPCCOMN_CARGO_ARGS=-Zbuild-std=std,panic_unwind"
    -DOPCCOMN_BUILD_CHECKER=OFF)   # the checker and its test servers run from the x64 and x86 builds
build_win7() {   # build_win7 x64|x86
    need_nightly_rust_src
    local toolchain=x86_64 target=x86_64-win7-windows-gnu
    [ "$1" = x86 ] && toolchain=i686 target=i686-win7-windows-gnu
    cmake -S . -B "$build/windows7-$1" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-$toolchain.cmake" \
        -DOPCCOMN_RUST_TARGET="$target" "${win7_args[@]}" >/dev/null
    cmake --build "$build/windows7-$1" -j2
}
version=$(sed -nE 's/^version = "([^"]+)"$/\1/p' Cargo.toml | head -1)
pkg="$build/package-test/opccomn-$version-windows"
run_id="$$.$(date +%s)"
# The Windows package, built and unpacked once per run (the stages run in subshells: a file marks it).
unpack_package() {
    [ -f "$build/package-test/unpacked.$run_id" ] && return 0
    scripts/package-windows.sh "$build/package" >/dev/null
    rm -rf "$build/package-test" && mkdir -p "$build/package-test"
    (cd "$build/package-test" && cmake -E tar xf "$build/package/opccomn-$version-windows.zip")
    touch "$build/package-test/unpacked.$run_id"
}
# A part of a stage that could not run (the stage itself ran): counted as skipped and named.
skipped_parts="$build/test-skipped-parts.$run_id"
skip_part() {
    echo "$1: NOT run ($2)"
    echo "$1 ($2)" >>"$skipped_parts"
}

# Runs the C tests of a 32-bit Windows build directory under 32-bit Wine and proves they ran: a 32-bit
# program that did not start prints nothing, so every test must have printed its closing line.
# Usage: run_x86_c_tests DIR [CTEST_EXCLUDE_REGEX]
run_x86_c_tests() {
    local dir=$1 exclude=${2:-^$} tests t oop_tests ps_tests lines
    # (ctest -N rewrites Testing/Temporary/LastTest.log: list the tests before running them.)
    tests=$(ctest --test-dir "$dir" -N -E "$exclude" | sed -nE 's/^ *Test +#[0-9]+: c\.(test_[A-Za-z0-9_]+)$/\1/p')
    oop_tests=$(ctest --test-dir "$dir" -N -E "$exclude" | grep -cE '^ *Test +#[0-9]+: oop\.') || true
    ps_tests=$(ctest --test-dir "$dir" -N -E "$exclude" | grep -cE '^ *Test +#[0-9]+: ps\.test_[a-z_]+$') || true
    [ -n "$tests" ] || { echo "no C tests found in $dir" >&2; return 1; }
    ctest --test-dir "$dir" --output-on-failure --timeout 300 -E "$exclude"
    for t in $tests; do
        grep -qE "^$t: [0-9]+ passed, 0 failed" "$dir/Testing/Temporary/LastTest.log" ||
            { echo "$t (x86, $dir) printed no result line" >&2; return 1; }
    done
    # The cross-process tests (tests/oop) of the same build: one result line per ctest entry.
    lines=$(grep -cE '^test_(oop|browser|ps_registration|bench_registration|reconnect|da_tables|ae_tables|hda_tables|service): [0-9]+ passed, 0 failed' \
        "$dir/Testing/Temporary/LastTest.log") || true
    [ "$oop_tests" -gt 0 ] && [ "$oop_tests" = "$lines" ] ||
        { echo "x86 cross-process tests in $dir: $oop_tests tests, $lines result lines" >&2; return 1; }
    # The proxy/stub robustness tests (ps.*; the runs against the unchecked stand-in must fail).
    lines=$(grep -cE '^test_(stub_requests|proxy_replies|served_messages): [0-9]+ passed, 0 failed' \
        "$dir/Testing/Temporary/LastTest.log") || true
    [ "$ps_tests" -gt 0 ] && [ "$ps_tests" = "$lines" ] ||
        { echo "x86 proxy/stub tests in $dir: $ps_tests tests, $lines result lines" >&2; return 1; }
    echo "every x86 C test, cross-process test and proxy/stub test in $dir printed its result line"
}

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

# ---- The stages --------------------------------------------------------------------------------------
stage_lint() {
    cargo fmt --all -- --check
    # The third-party client and server (tests/third-party/opc-da-client, opc-da-server) are Cargo
    # projects of their own (rustfmt directly: cargo fmt would resolve their crates.io dependencies).
    rustfmt --check --edition 2024 tests/third-party/opc-da-client/src/main.rs \
        tests/third-party/opc-da-server/src/main.rs
    cargo clippy --all-targets -- -D warnings
    if [ -z "${disabled[wine]+set}" ]; then
        cargo clippy --lib --target x86_64-pc-windows-gnu -- -D warnings
        cargo clippy --lib --target i686-pc-windows-gnu -- -D warnings
    fi
    cargo run -q -p gen-header -- --check
    scripts/check-generated.sh
    python3 tools/gen-null-rule-test.py --check
    # The generator's own checks (IDL reader, the Rust interfaces it generates, the boundary rules it
    # checks catching each kind of breach).
    cargo clippy -q -p gen-header --all-targets -- -D warnings
    cargo test -q -p gen-header
    # The proxy/stub's NDR tables are generated from idl/opccomn.idl, opcda.idl, opc_ae.idl and
    # opchda.idl (widl and the system IDLs come with the Windows tools).
    if [ -z "${disabled[wine]+set}" ]; then
        python3 tools/gen-proxy.py --check
    else
        echo "lint: the proxy/stub tables' drift check needs the Windows tools (widl) and was NOT run (--no-wine)"
    fi
    # The IDL's interfaces (IIDs, methods, parameters) and the generated vtables against the
    # Foundation's published tables; the Win64 and Win32 tables of each IDL file describe the same wire.
    python3 tools/check-idl-tables.py
    local idl
    for idl in opccomn opcda opc_ae opchda; do
        python3 tools/compare-ndr.py --ignore-offsets "src/proxy/generated/${idl}_p_win64.c" \
            "src/proxy/generated/${idl}_p_win32.c"
    done
}

stage_rust_linux() {
    cargo test
}

stage_c_asan() {
    build_linux
    ctest --test-dir "$build/linux" --output-on-failure --timeout 300
    scripts/check-exports.sh "$build/linux/cargo/release/libopccomn.so"
}

stage_c_valgrind() {
    cmake -S . -B "$build/valgrind" -DOPCCOMN_VALGRIND=ON >/dev/null
    cmake --build "$build/valgrind" -j2
    ctest --test-dir "$build/valgrind" --output-on-failure --timeout 900 -R '^c\.'
}

stage_tsan() {
    # 8 threads on one IOPCCommon, one shutdown object whose sinks unadvise themselves during a notify,
    # one compiled pattern (src/stress_tests.rs). Any report fails the run (halt_on_error).
    RUSTFLAGS="-Zsanitizer=thread" TSAN_OPTIONS="halt_on_error=1" CARGO_TARGET_DIR="$root/target/tsan" \
        cargo +"$OPCCOMN_NIGHTLY" test -Zbuild-std --target x86_64-unknown-linux-gnu --lib stress_tests
}

stage_miri() {
    # Stacked Borrows and Tree Borrows, one process each, at once (scripts/miri.sh): the COM core,
    # IOPCCommon, errors, locale, pattern, shutdown with the in-process sink, the server list and the
    # registry over the in-memory registry, the stress test. Any report fails the stage.
    if [ -z "$miri_background" ]; then
        scripts/miri.sh
        return
    fi
    # Started before the first stage (see below): wait for it, then show what it printed.
    while [ ! -f "$miri_background.rc" ]; do sleep 2; done
    cat "$miri_background.log"
    return "$(cat "$miri_background.rc")"
}

stage_package_linux() {
    build_linux
    rm -rf "$build/install" "$build/consumer"
    cmake --install "$build/linux" --prefix "$build/install" >/dev/null
    cmake -S examples/consumer -B "$build/consumer" -DCMAKE_PREFIX_PATH="$build/install" >/dev/null
    cmake --build "$build/consumer" -j2 >/dev/null
    "$build/consumer/consumer"
    PKG_CONFIG_PATH="$build/install/lib/pkgconfig" cc -o "$build/consumer/pkgconfig_demo" examples/demo.c \
        $(PKG_CONFIG_PATH="$build/install/lib/pkgconfig" pkg-config --cflags --libs opccomn) \
        -Wl,-rpath,"$build/install/lib"
    "$build/consumer/pkgconfig_demo" >/dev/null
    # The version as the installed package states it (Cargo.toml's, "0.3.0-dev" while in development).
    [ "$(PKG_CONFIG_PATH="$build/install/lib/pkgconfig" pkg-config --modversion opccomn)" = "$version" ]
    grep -qx "set(opccomn_VERSION_FULL \"$version\")" "$build/install/lib/cmake/opccomn/opccomnConfig.cmake"
    # The static library linked with the README's list and with pkg-config's, and run.
    scripts/test-static-link.sh linux "$build/linux" "$build/install"
}

stage_no_dll_exports() {
    cmake -S . -B "$build/no-dll-exports" -DOPCCOMN_DLL_EXPORTS=OFF -DOPCCOMN_BUILD_TESTS=OFF >/dev/null
    cmake --build "$build/no-dll-exports" -j2 >/dev/null
    local no_exports
    no_exports=$(nm -D --defined-only "$build/no-dll-exports/cargo/release/libopccomn.so" | awk '{print $3}')
    if grep -qx DllGetClassObject <<<"$no_exports" || ! grep -qx OpcDllGetClassObject <<<"$no_exports"; then
        echo "OPCCOMN_DLL_EXPORTS=OFF: expected OpcDllGetClassObject without DllGetClassObject" >&2
        return 1
    fi
    echo "OPCCOMN_DLL_EXPORTS=OFF: Dll* absent, OpcDll* present"
}

stage_docs() {
    scripts/docs.sh --check
}

stage_cmake_msvc() {
    scripts/check-cmake-msvc.sh
}

stage_msvc_build_script() {
    scripts/check-msvc-build-script.sh
}

stage_fuzz() {
    echo "${OPCCOMN_FUZZ_SECONDS:-30} s per target"
    scripts/fuzz.sh "${OPCCOMN_FUZZ_SECONDS:-30}"
}

stage_rust_windows() {
    CARGO_TARGET_X86_64_PC_WINDOWS_GNU_RUNNER=wine cargo test --target x86_64-pc-windows-gnu --lib
}

stage_acp932() {
    # Narrow strings are in the ANSI code page on Windows; the prefix's default is 1252. Wine takes
    # the code page from the locale's name (installed or not), so LC_ALL=ja_JP.SJIS gives 932, a
    # double-byte one; the test asserts it (OPCCOMN_TEST_ACP) and says which it ran under.
    local acp_test=pattern::tests::narrow_entry_points_agree_with_the_decoded_ansi_code_page acp_out
    acp_out=$(OPCCOMN_TEST_ACP=932 LC_ALL=ja_JP.SJIS CARGO_TARGET_X86_64_PC_WINDOWS_GNU_RUNNER=wine \
        cargo test --target x86_64-pc-windows-gnu --lib -- --exact "$acp_test" --nocapture 2>&1) ||
        { echo "$acp_out"; return 1; }
    grep -q "narrow differential in ANSI code page 932" <<<"$acp_out" && grep -q "test result: ok. 1 passed" <<<"$acp_out" ||
        { echo "$acp_out"; echo "the code page 932 test did not run" >&2; return 1; }
    echo "$acp_test: passed in ANSI code page 932"
}

stage_c_windows() {
    build_windows
    ctest --test-dir "$build/windows" --output-on-failure --timeout 300
    scripts/check-exports.sh "$build/windows/cargo/x86_64-pc-windows-gnu/release/opccomn.dll"
}

stage_coexistence() {
    build_windows
    build_linux
    build_windows_x86
    # The x86 link matrix and the x86 server with its own .def are linked, and run under 32-bit Wine
    # when it is there.
    local x86_mode=link
    [ "$wine32_ok" = 1 ] && x86_mode=run
    [ "$x86_mode" = run ] || skip_part "coexistence: the x86 programs (linked)" "32-bit Wine is not available: $wine32_missing"
    scripts/test-coexistence.sh "$build/windows" "$build/linux" "$build/windows-x86" "$x86_mode"
    # The static library linked with docs/windows.md's list and with pkg-config's (x64, x86), and run.
    scripts/test-static-link.sh windows x64 "$build/windows" run
    scripts/test-static-link.sh windows x86 "$build/windows-x86" "$x86_mode"
}

# Reconnects to the example's EXE server at the host's defaults (tests/oop/test_reconnect.c): 8
# processes x 25 reconnects at gaps spread over 0 to 3 s, each to succeed. Usage: example_reconnects
# EXAMPLE_DIR TEST_RECONNECT_EXE
example_reconnects() {
    local server="$1/opccomn_example_server.exe" rc=0
    wine "$server" /RegServer
    sh tests/oop/run-isolated.sh wine "$2" example || rc=$?
    wine "$server" /UnregServer
    return "$rc"
}

stage_example_x64() {
    build_windows
    example_stage x64 "$build/windows" "$root/cmake/mingw-w64-x86_64.cmake"
    example_reconnects "$build/example-x64" "$build/windows/bin/test_reconnect.exe"
}

stage_third_party_client() {
    build_windows
    [ -f "$build/example-x64/CMakeCache.txt" ] || example_stage x64 "$build/windows" "$root/cmake/mingw-w64-x86_64.cmake"
    # The x86 client (32-bit Wine) against the same x64 browser, example server and DA test server,
    # through the x86 proxy/stub.
    if [ "$wine32_ok" = 1 ]; then
        build_windows_x86
        scripts/test-third-party-client.sh "$build/windows/bin" "$build/example-x64" "$build/windows-x86/bin"
    else
        scripts/test-third-party-client.sh "$build/windows/bin" "$build/example-x64"
        skip_part "third-party-client: the x86 client" "32-bit Wine is not available: $wine32_missing"
    fi
}

stage_conformance_x64() {
    build_windows
    [ -f "$build/example-x64/CMakeCache.txt" ] || example_stage x64 "$build/windows" "$root/cmake/mingw-w64-x86_64.cmake"
    scripts/test-conformance.sh "$build/windows/bin" "$build/example-x64"
}

stage_build_x86() {
    build_windows_x86
    local x86_out="$build/windows-x86/cargo/i686-pc-windows-gnu/release"
    scripts/check-exports.sh "$x86_out/opccomn.dll"
    ls "$x86_out/libopccomn.a" "$x86_out/libopccomn.dll.a" "$x86_out/msvc/opccomn.lib" >/dev/null
}

stage_rust_x86() {
    # RUST_BACKTRACE=0: with backtraces on (RUST_BACKTRACE=1 in the environment), taking the
    # backtrace of a panic under Debian 12's 32-bit Wine 8 reads through NULL inside its ucrtbase
    # and kills the process at the first test that panics on purpose (the boundary's panic tests);
    # a plain program that catches a panic survives it. What those tests check is the library's
    # handling of the panic; the x64 stage runs them with backtraces as the environment sets.
    RUST_BACKTRACE=0 CARGO_TARGET_I686_PC_WINDOWS_GNU_RUNNER=wine cargo test --target i686-pc-windows-gnu --lib
}

stage_c_x86() {
    build_windows_x86
    run_x86_c_tests "$build/windows-x86"
}

stage_conformance_x86() {
    build_windows_x86
    build_windows
    scripts/test-conformance.sh "$build/windows-x86/bin" - "$build/windows/bin/opccomn-check.exe"
}

stage_wow64_browse() {
    build_windows
    build_windows_x86
    wine "$build/windows/bin/test_browser.exe" wow64-serve
    local rc=0
    wine "$build/windows-x86/bin/test_browser.exe" wow64-client || rc=$?
    wine "$build/windows/bin/test_browser.exe" wow64-cleanup
    [ "$rc" = 0 ]
}

stage_win7_build() {
    build_win7 x64
    build_win7 x86
    local dll
    for dll in "$build/windows7-x64/cargo/x86_64-win7-windows-gnu/release/opccomn.dll" \
        "$build/windows7-x86/cargo/i686-win7-windows-gnu/release/opccomn.dll"; do
        scripts/check-imports-win7.sh "$dll"
        scripts/check-exports.sh "$dll"
    done
    # The check can fail: the default build needs Windows 10 (ProcessPrng) and must be refused.
    build_windows >/dev/null
    if scripts/check-imports-win7.sh "$build/windows/cargo/x86_64-pc-windows-gnu/release/opccomn.dll" >/dev/null 2>&1; then
        echo "check-imports-win7.sh accepted the default build, which imports ProcessPrng" >&2
        return 1
    fi
}

# The Windows 7 builds differ from the others in the system functions they import, not in the host's
# lifetime or the benchmarks: the reconnect tests (a minute of gaps; its burst under the rpc trace),
# the benchmark's registration test and the DA and browser benchmarks' short runs run in c-windows and
# c-x86 only.
# (The registration test ends the servers of a stalled run, and Wine keeps an ended server's class
# registration for the rest of the session: a second run of it in the same session, here with the
# same CLSIDs, would meet those.)
win7_excluded='^(oop\.(reconnect|interfaces_kept|bench_registration)|bench\.(da|browser)_figures)$'
stage_c_win7_x64() {
    build_win7 x64
    ctest --test-dir "$build/windows7-x64" --output-on-failure --timeout 300 -E "$win7_excluded"
}

stage_c_win7_x86() {
    build_win7 x86
    run_x86_c_tests "$build/windows7-x86" "$win7_excluded"
}

stage_package_windows() {
    unpack_package
    local variant arch toolchain win7 dir want folder file
    # It holds what its README names: checksums that match, every file in every folder, stripped DLLs
    # that name their debug files, and a browser service that runs.
    (cd "$pkg" && sha256sum --quiet -c SHA256SUMS)
    [ "$(cat "$pkg/VERSION")" = "$version" ]
    for file in README.md LICENSE-MIT LICENSE-APACHE include/opccomn/opccomn.h cmake/opccomnConfig.cmake \
        docs/migration.md docs/reference/html/index.html examples/cpp-server/CMakeLists.txt; do
        [ -f "$pkg/$file" ] || { echo "package: no $file" >&2; return 1; }
    done
    for folder in x64 x86 win7/x64 win7/x86; do
        for file in opccomn.dll opccomn.dll.debug opccomn.lib opccomn.def libopccomn.dll.a libopccomn.a opccomn-static-libs.txt opccomn_browser.exe; do
            [ -f "$pkg/$folder/$file" ] || { echo "package: no $folder/$file" >&2; return 1; }
        done
        if objdump -h "$pkg/$folder/opccomn.dll" | grep -q '\.debug_info'; then
            echo "package: $folder/opccomn.dll is not stripped" >&2
            return 1
        fi
        objdump -h "$pkg/$folder/opccomn.dll" | grep -q '\.gnu_debuglink' ||
            { echo "package: $folder/opccomn.dll does not name its debug file" >&2; return 1; }
        objdump -h "$pkg/$folder/opccomn.dll.debug" | grep -q '\.debug_info' ||
            { echo "package: $folder/opccomn.dll.debug holds no debug information" >&2; return 1; }
    done
    for file in "opccomn-$version-x64.msi" "opccomn-$version-x86.msi" opccomn.wxi opccomn.wxs; do
        [ -f "$pkg/msi/$file" ] || { echo "package: no msi/$file" >&2; return 1; }
    done
    for folder in x64 x86; do
        [ -f "$pkg/$folder/opccomn-check.exe" ] || { echo "package: no $folder/opccomn-check.exe" >&2; return 1; }
    done
    # The browser from the package runs beside the package's DLL: /Status exits 0 (it is the active
    # browser) or 2 (another one, or none), 1 only on an error.
    local status_rc=0
    (cd "$pkg/x64" && wine opccomn_browser.exe /Status >/dev/null) || status_rc=$?
    [ "$status_rc" = 0 ] || [ "$status_rc" = 2 ] || { echo "package: x64/opccomn_browser.exe /Status exited $status_rc" >&2; return 1; }
    echo "package: every file its README names is there, the DLLs are stripped with their debug files beside them, the browser runs"
    # The static library's libraries as docs/windows.md lists them, per folder (scripts/test-static-link.sh
    # links with the x64 and x86 lists in the coexistence stage).
    local listed listed_win7
    listed=$(sed -nE 's|.*Static: link `libopccomn\.a` and `([^`]*)`.*|\1|p' docs/windows.md)
    listed_win7=$(sed -nE 's|.*the `win7/` builds: `([^`]*)`.*|\1|p' docs/windows.md)
    for folder in x64 x86 win7/x64 win7/x86; do
        want=$listed
        [[ "$folder" = win7/* ]] && want=$listed_win7
        [ -n "$want" ] && [ "$(cat "$pkg/$folder/opccomn-static-libs.txt")" = "$want" ] ||
            { echo "package: $folder/opccomn-static-libs.txt says '$(cat "$pkg/$folder/opccomn-static-libs.txt")', docs/windows.md '$want'" >&2; return 1; }
    done
    echo "package: each folder's opccomn-static-libs.txt is the list docs/windows.md gives"
    for variant in x64:x86_64:OFF x86:i686:OFF x64:x86_64:ON; do
        IFS=: read -r arch toolchain win7 <<<"$variant"
        dir="$build/package-test/consumer-$arch-win7-$win7"
        cmake -S examples/consumer -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-$toolchain.cmake" \
            -DCMAKE_PREFIX_PATH="$pkg" -DOPCCOMN_WINDOWS7="$win7" >/dev/null
        cmake --build "$dir" -j2 >/dev/null
        # The program got the package's DLL of its own architecture and variant.
        want="$pkg/$arch/opccomn.dll"
        [ "$win7" = ON ] && want="$pkg/win7/$arch/opccomn.dll"
        cmp -s "$want" "$dir/opccomn.dll" || { echo "$dir/opccomn.dll is not $want" >&2; return 1; }
        if [ "$arch" = x86 ] && [ "$wine32_ok" != 1 ]; then
            skip_part "package-windows: the x86 consumer (built)" "32-bit Wine is not available: $wine32_missing"
            continue
        fi
        (cd "$dir" && wine consumer.exe >consumer.out)
        echo "package consumer ($arch, Windows 7 variant $win7): ran, $(wc -l <"$dir/consumer.out") lines of output"
    done
}

# The MSI packages of the Windows package (scripts/test-msi.sh), with the stand-in for the Foundation's
# proxy/stub of both builds. The x64 package holds the x86 proxy/stub too, whose registration runs
# 32-bit: the stage needs 32-bit Wine.
stage_msi() {
    unpack_package
    local variant
    for variant in windows:x86_64 windows-x86:i686; do
        # (the stand-in is a test target: a build folder package-windows.sh made first has the tests off)
        cmake -S . -B "$build/${variant%%:*}" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-${variant#*:}.cmake" \
            -DOPCCOMN_BUILD_TESTS=ON >/dev/null
        cmake --build "$build/${variant%%:*}" -j2 --target opccomn_widl_ps >/dev/null
    done
    scripts/test-msi.sh "$pkg" "$build/windows/bin/opccomn_widl_ps.dll" "$build/windows-x86/bin/opccomn_widl_ps.dll" run
}

stage_package_cpp_example() {
    unpack_package
    local variant arch toolchain dir rc
    for variant in x64:x86_64 x86:i686; do
        IFS=: read -r arch toolchain <<<"$variant"
        dir="$build/package-test/cpp-server-$arch"
        cmake -S examples/cpp-server -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$root/cmake/mingw-w64-$toolchain.cmake" \
            -DCMAKE_PREFIX_PATH="$pkg" >/dev/null
        cmake --build "$dir" -j2 >/dev/null
        if [ "$arch" = x86 ] && [ "$wine32_ok" != 1 ]; then
            skip_part "package-cpp-example: the x86 example and checker (built)" "32-bit Wine is not available: $wine32_missing"
            continue
        fi
        ctest --test-dir "$dir" --output-on-failure --timeout 300
        if [ "$arch" = x86 ]; then
            # The x86 example at the host's defaults, reconnected to by x86 clients (the x64 example
            # in stage example-x64).
            build_windows_x86
            example_reconnects "$dir" "$build/windows-x86/bin/test_reconnect.exe"
        fi
        # The package's opccomn-check of the same architecture against this example DLL: all passed.
        cp "$pkg/$arch/opccomn-check.exe" "$dir/"
        (cd "$dir" && wine regsvr32 /s opccomn_example_inproc.dll)
        rc=0
        (cd "$dir" && wine opccomn-check.exe OpcComn.ExampleServerInProc.1 --format json >check.json 2>check.log) || rc=$?
        (cd "$dir" && wine regsvr32 /u /s opccomn_example_inproc.dll)
        tr -d '\r' <"$dir/check.json" >"$dir/check.json.lf"
        python3 tests/conformance/check_report.py json "$dir/check.json.lf" "$rc"
    done
}

stage_msvc_link() {
    unpack_package
    scripts/test-msvc-link.sh x64 "$pkg/x64" "$build/package-test/msvc-x64"
    if [ "$wine32_ok" = 1 ]; then
        scripts/test-msvc-link.sh x86 "$pkg/x86" "$build/package-test/msvc-x86"
    else
        scripts/test-msvc-link.sh --no-run x86 "$pkg/x86" "$build/package-test/msvc-x86"
        skip_part "msvc-link: the x86 program (linked)" "32-bit Wine is not available: $wine32_missing"
    fi
}

# ---- Tools: everything is installed before the Wine prefix is made --------------------------------
need_linux_tools
need_soundness_tools
wine32_ok=0
wine32_missing="not checked"
if selected wine; then
    need_windows_tools
    need_msi_tools
    # 32-bit Wine before the prefix: a prefix made by 64-bit Wine alone is unusable once wine32:i386
    # arrives (scripts/wine-env.sh also makes such a prefix anew).
    wine32_installed=0
    need_wine32 && wine32_installed=1
    . scripts/wine-env.sh "$build/windows"
    # Without wine32:i386 `wine prog32.exe` exits 0 without running anything, so the 32-bit stages
    # run only after a 32-bit program has been seen to run and print.
    if [ "$wine32_installed" = 1 ]; then
        mkdir -p "$build/windows"
        i686-w64-mingw32-gcc -O2 -o "$build/windows/wow64_canary.exe" tests/wine/wow64_canary.c
        canary=$(wine "$build/windows/wow64_canary.exe" 2>&1 | tr -d '\r') || true
        if [ "$canary" = "wow64 canary: 32-bit process, WOW64 yes" ]; then
            wine32_ok=1
        else
            wine32_missing="wine32:i386 is installed, but a 32-bit program did not run (it printed: '$canary')"
        fi
    fi
fi

# ---- Run ----------------------------------------------------------------------------------------------
passed=()
failed=()
skipped=()
mkdir -p "$build"
# Free space where the builds go: a full run writes about 8 GB there (the builds of every stage, Wine
# prefixes, Miri's and the fuzzers' targets). Said at the start and after a failed stage, so that a
# stage stopped by a full disk ("No space left on device") is told apart from a defect.
free_space() {
    df -Pk "$build" | awk 'NR == 2 { printf "%.1f GB free in %s\n", $4 / 1048576, $6 }'
}
echo "disk: $(free_space)"
if [ "$(df -Pk "$build" | awk 'NR == 2 { print int($4 / 1048576) }')" -lt 10 ]; then
    echo "!!!! disk: less than 10 GB free; a full run writes about 8 GB: stages may fail for want of space"
fi
rm -f "$build"/test-skipped-parts.*
# Miri interprets the tests on one core per model, for minutes, while the other stages (Wine's in
# particular, which wait on processes and timeouts) leave the machine idle for long stretches: when it
# runs among others, it starts now at the lowest priority (nice 19), so that it takes only the time
# they leave, and its stage, last, waits for it and prints its result. Its time does not depend on
# load: Miri's clock is its own (isolation).
miri_background=
if [ -z "$(reason_not_to_run miri)" ] && [ "${#only[@]}" != 1 ]; then
    need_miri
    miri_background="$build/miri-background"
    rm -f "$miri_background.rc" "$miri_background.log"
    (
        rc=0
        nice -n 19 scripts/miri.sh >"$miri_background.log" 2>&1 || rc=$?
        echo "$rc" >"$miri_background.rc"
    ) &
fi
for name in "${stage_names[@]}"; do
    why=$(reason_not_to_run "$name")
    if [ -n "$why" ]; then
        skipped+=("$name ($why)")
        # An option or a missing 32-bit Wine is said loudly; a stage left out by --only quietly.
        [ "${#only[@]}" -gt 0 ] && [ -z "${only[$name]+set}" ] ||
            printf '\n==== SKIPPED: %s: %s\n!!!! not run: %s\n' "$name" "${stage_text[$name]}" "$why"
        continue
    fi
    printf '\n==== %s: %s\n' "$name" "${stage_text[$name]}"
    started=$SECONDS
    # The stage runs in a subshell with errexit on (set -e is not in force inside a function called
    # from a condition, so the status is read after the subshell, not in an `if`).
    set +e
    (set -e; "stage_${name//-/_}")
    rc=$?
    set -e
    if [ "$rc" = 0 ]; then
        passed+=("$name")
        printf '==== passed: %s (%ds)\n' "$name" $((SECONDS - started))
    else
        failed+=("$name")
        printf '==== FAILED: %s (exit %d, %ds; disk: %s)\n' "$name" "$rc" $((SECONDS - started)) "$(free_space)"
    fi
done

if [ -f "$skipped_parts" ]; then
    while IFS= read -r line; do skipped+=("$line"); done <"$skipped_parts"
    rm -f "$skipped_parts"
fi
printf '\n==== summary (%ds)\n' "$SECONDS"
for name in "${failed[@]}"; do printf 'FAILED   %s\n' "$name"; done
not_selected=0
for name in "${skipped[@]}"; do
    case "$name" in
        *"(not selected (--only))") not_selected=$((not_selected + 1)) ;;
        *) printf 'SKIPPED  %s\n' "$name" ;;
    esac
done
[ "$not_selected" = 0 ] || printf 'SKIPPED  %d stages not selected (--only)\n' "$not_selected"
printf 'test.sh: %d passed, %d failed, %d skipped\n' "${#passed[@]}" "${#failed[@]}" "${#skipped[@]}"
[ "${#failed[@]}" -eq 0 ]
