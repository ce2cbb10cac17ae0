#!/usr/bin/env bash
# The header next to the OPC Foundation's MIDL-generated headers, the library next to their *_i.c files,
# and a server DLL with its own .def next to opccomn's import libraries. The Foundation's files are
# stood in for by tests/coexistence/midl_standins.py: opccomn.h, opcda.h, opc_ae.h, opchda.h and their
# *_i.c, opcerror.h, opcae_er.h, opchda_error.h, with the traits of MIDL's (and the message compiler's)
# output that a program sees: no __CRT_UUID_DECL, `EXTERN_C const IID`, the categories as empty
# interfaces with `#define CATID_... IID_...` (opc_ae.h: IID_OPCEventServerCATID), OPCHANDLE typedef'd
# by each of opcda.h / opc_ae.h / opchda.h, an unconditional `#pragma warning`, MIDL's _i.c form.
# docs/header-coexistence.md lists them. The same headers and *_i.c as widl writes them (foundation/widl:
# what mingw users who compile the Foundation's IDL include; __CRT_UUID_DECL for every interface) are
# the second kind of Foundation headers every stage below runs against.
#
# 0. The stand-ins' traits, each shown to bite (so the stages below cannot pass for want of them), and
#    widl's: its __uuidof declarations, which a second declaration redefines.
# 1. Compile matrix (-Wall -Wextra -pedantic-errors -Werror): MIDL's / widl's headers x ours first /
#    theirs first x C, C COBJMACROS, C++, C++ CINTERFACE, C++17 (__uuidof in constant expressions) x
#    x86_64 and i686 mingw gcc/g++ (and clang/clang++ for mingw where it works), with the Foundation's
#    directory as a system directory (-isystem, C99) and as a plain one (-I, with -Wno-unknown-pragmas
#    for their #pragma warning and C11 for their repeated OPCHANDLE typedef: a macro both headers define
#    differently is then an error in either order); widl's headers with the x86_64 compilers, as a
#    system directory. Two compilations at a time (OPCCOMN_JOBS).
# 2. The i686 calling-convention checks (c-tests/abi_i686.c), with a negative control that must fail.
# 3. Link matrix, x64 and x86: static library or DLL import library x with or without the *_i.c files x
#    both include orders x C (COBJMACROS) / C++ (__uuidof of every OPC Common interface), each program
#    run under Wine (x86 under 32-bit Wine, or linked only when it is missing); with widl's headers the
#    C and C++ programs, both orders, against either library (widl's *_i.c beside the import library).
# 4. A server DLL with its own .def naming DllRegisterServer etc. undecorated, x64 and x86, linked
#    against libopccomn.dll.a and against opccomn.lib: exports its own functions (none imported from
#    opccomn.dll) and regsvr32 registers its own class under Wine; neither import library offers the
#    Dll* names (the OpcDll* ones it does).
# 5. Linux: the header alone under clang/clang++ in the same modes; the static library linked with an
#    object that defines the same identifiers.
#
# Usage: scripts/test-coexistence.sh BUILD_DIR_WINDOWS BUILD_DIR_LINUX [BUILD_DIR_WINDOWS_X86 run|link]
# (test.sh passes them; Wine must be set up as scripts/wine-env.sh does when a Windows build dir is given;
# `run` when 32-bit Wine runs programs, `link` to build the x86 programs without running them)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
win_build=${1:-}
linux_build=${2:-}
win_build_x86=${3:-}
x86_mode=${4:-link}
out="$root/build/coexistence"
rm -rf "$out"
mkdir -p "$out/foundation"
passed=0
fail() { echo "coexistence: FAILED: $*" >&2; exit 1; }
ok() { passed=$((passed + 1)); }

widl_inc=/usr/include/wine/wine/windows
[ -f "$widl_inc/unknwn.idl" ] || fail "$widl_inc/unknwn.idl missing (libwine-dev)"

# ---- Stand-in Foundation headers (their traits asserted by the generator) ----
python3 "$root/tests/coexistence/midl_standins.py" "$root" "$out/foundation" "$widl_inc" ||
    fail "the MIDL-faithful stand-ins could not be made"

strict=(-Wall -Wextra -pedantic-errors -Werror)
modes=("c:" "c:-DCOBJMACROS" "c++:" "c++:-DCINTERFACE" "c++:-std=c++17")

foundation_as=system # how compile() passes the Foundation's directory: system (-isystem) or plain (-I)
foundation_kind=midl # whose headers: midl (the stand-ins) or widl (widl's own, foundation/widl first)
compile() { # "compiler [args]" lang options...
    local -a cc
    read -r -a cc <<<"$1"
    local lang=$2
    shift 2
    local std=-std=c99
    local -a dirs=("$out/foundation") how=()
    [ "$foundation_kind" = widl ] && dirs=("$out/foundation/widl" "$out/foundation")
    [ "$lang" = c++ ] && std=-std=c++11
    local dir
    for dir in "${dirs[@]}"; do
        if [ "$foundation_as" = plain ]; then how+=(-I"$dir"); else how+=(-isystem "$dir"); fi
    done
    if [ "$foundation_as" = plain ]; then
        how+=(-Wno-unknown-pragmas)
        [ "$lang" = c ] && std=-std=c11
    fi
    "${cc[@]}" -x "$lang" $std "${strict[@]}" -I"$root/include" "${how[@]}" "$@"
}

# ---- 0. the stand-ins' traits bite ----
gcc64=x86_64-w64-mingw32-gcc
# The unconditional #pragma warning: an error under -Wall -Werror unless the directory is a system one.
printf '#include <opcda.h>\nint main(void) { return 0; }\n' >"$out/trait_pragma.c"
if $gcc64 -std=c99 -Wall -Werror -fsyntax-only -I"$out/foundation" "$out/trait_pragma.c" 2>/dev/null; then
    fail "the stand-in opcda.h has no #pragma warning"
fi
$gcc64 -std=c99 -Wall -Werror -fsyntax-only -isystem "$out/foundation" "$out/trait_pragma.c" ||
    fail "the stand-in opcda.h does not compile as a system header"
ok
# OPCHANDLE, typedef'd by opcda.h, opc_ae.h and opchda.h: a C99 -pedantic-errors compiler rejects it
# (mingw gcc, and clang for mingw where it works).
printf '#include <opcda.h>\n#include <opc_ae.h>\n#include <opchda.h>\nint main(void) { OPCHANDLE h = 0; return (int)h; }\n' >"$out/trait_handle.c"
handle_compilers=("$gcc64")
if command -v clang >/dev/null && echo 'int main(void){return 0;}' | clang --target=x86_64-w64-mingw32 -x c -fsyntax-only -include windows.h - 2>/dev/null; then
    handle_compilers+=("clang --target=x86_64-w64-mingw32")
fi
for cc in "${handle_compilers[@]}"; do
    if $cc -std=c99 -pedantic-errors -Wno-unknown-pragmas -fsyntax-only -I"$out/foundation" "$out/trait_handle.c" 2>"$out/trait_handle.err"; then
        fail "the stand-ins do not repeat the OPCHANDLE typedef ($cc)"
    fi
    grep -q OPCHANDLE "$out/trait_handle.err" || fail "the stand-ins fail C99 for another reason ($cc): $(cat "$out/trait_handle.err")"
    $cc -std=c11 -pedantic-errors -Wno-unknown-pragmas -fsyntax-only -I"$out/foundation" "$out/trait_handle.c" ||
        fail "the stand-ins' repeated OPCHANDLE typedef is not the same type ($cc)"
    ok
done
# No __uuidof declaration: alone, the stand-in opccomn.h compiles __uuidof(IOPCCommon) and fails to link.
printf '#include <opccomn.h>\nint main() { return __uuidof(IOPCCommon).Data1 == 0; }\n' >"$out/trait_uuidof.cpp"
if x86_64-w64-mingw32-g++ -isystem "$out/foundation" -o "$out/trait_uuidof.exe" "$out/trait_uuidof.cpp" \
        -x c "$out/foundation/opccomn_i.c" 2>"$out/trait_uuidof.err"; then
    fail "the stand-in opccomn.h declares __uuidof(IOPCCommon), as MIDL's output does not"
fi
grep -q '__mingw_uuidof' "$out/trait_uuidof.err" || fail "__uuidof without opccomn.h failed otherwise: $(cat "$out/trait_uuidof.err")"
ok
# The category redirect: opc_ae.h's CATID_OPCAEServer10 is the symbol IID_OPCEventServerCATID.
printf '#include <opc_ae.h>\nint main(void) { return (int)CATID_OPCAEServer10.Data1; }\n' >"$out/trait_ae.c"
if $gcc64 -isystem "$out/foundation" -o "$out/trait_ae.exe" "$out/trait_ae.c" 2>"$out/trait_ae.err"; then
    fail "the stand-in opc_ae.h defines CATID_OPCAEServer10 itself"
fi
grep -q 'IID_OPCEventServerCATID' "$out/trait_ae.err" || fail "opc_ae.h's category failed otherwise: $(cat "$out/trait_ae.err")"
ok
# widl's opccomn.h declares __uuidof(IOPCShutdown) itself: a second declaration is a redefinition, in
# C++11 and C++17 (mingw's two forms of __CRT_UUID_DECL).
printf '#include <opccomn.h>\n__CRT_UUID_DECL(IOPCShutdown, 0xf31dfde1, 0x07b6, 0x11d2, 0xb2,0xd8,0x00,0x60,0x08,0x3b,0xa1,0xfb)\nint main() { return 0; }\n' >"$out/trait_widl.cpp"
for std in c++11 c++17; do
    if x86_64-w64-mingw32-g++ -std=$std -isystem "$out/foundation/widl" -fsyntax-only "$out/trait_widl.cpp" 2>"$out/trait_widl.err"; then
        fail "widl's opccomn.h declares no __uuidof(IOPCShutdown) ($std)"
    fi
    grep -q 'redefinition' "$out/trait_widl.err" || fail "a second __uuidof after widl's failed otherwise ($std): $(cat "$out/trait_widl.err")"
done
ok
echo "coexistence: the stand-ins' traits (#pragma warning, repeated OPCHANDLE, no __uuidof, category redirect) and widl's (its own __uuidof) each shown"

# ---- 1. compile matrix ----
compilers=(x86_64-w64-mingw32-gcc:c x86_64-w64-mingw32-g++:c++ i686-w64-mingw32-gcc:c i686-w64-mingw32-g++:c++)
if command -v clang >/dev/null && echo 'int main(void){return 0;}' | clang --target=x86_64-w64-mingw32 -x c -fsyntax-only -include windows.h - 2>/dev/null; then
    compilers+=(clang-x86_64-mingw:c clang++-x86_64-mingw:c++)
else
    echo "coexistence: clang for x86_64-w64-mingw32 not usable here; the mingw matrix runs with gcc/g++ only"
fi
# The compilations run two at a time (OPCCOMN_JOBS): each parses <windows.h>, most of the stage's time.
jobs_max=${OPCCOMN_JOBS:-2}
matrix_failures="$out/compile-matrix-failures.txt"
: >"$matrix_failures"
matrix_count=0
compile_job() { # what, then compile()'s arguments; a failure is recorded with the compiler's messages
    local what=$1 err="$out/compile-matrix-$BASHPID.err"
    shift
    compile "$@" 2>"$err" || { echo "$what"; cat "$err"; } >>"$matrix_failures"
    rm -f "$err"
}
for entry in "${compilers[@]}"; do
    cc=${entry%%:*}
    kind=${entry##*:}
    case "$cc" in
        clang-x86_64-mingw) cc_cmd=(clang --target=x86_64-w64-mingw32) ;;
        clang++-x86_64-mingw) cc_cmd=(clang++ --target=x86_64-w64-mingw32) ;;
        *) cc_cmd=("$cc") ;;
    esac
    command -v "${cc_cmd[0]}" >/dev/null || fail "${cc_cmd[0]} not installed"
    for mode in "${modes[@]}"; do
        lang=${mode%%:*}
        define=${mode#*:}
        [ "$lang" = "$kind" ] || continue
        for foundation_kind in midl widl; do
            for foundation_as in system plain; do
                # widl's headers: x86_64 compilers, as a system directory (what differs from MIDL's, the
                # __uuidof declarations and DEFINE_GUID, does not depend on the architecture or on
                # whether their own warnings are shown).
                if [ "$foundation_kind" = widl ] && { [ "$foundation_as" = plain ] || [[ "$cc" = i686-* ]]; }; then
                    continue
                fi
                for first in 1 0; do
                    compile_job "$cc $lang $define ours-first=$first, the Foundation's headers by $foundation_kind, $foundation_as" \
                        "${cc_cmd[*]}" "$lang" ${define:+"$define"} -DOURS_FIRST=$first -fsyntax-only \
                        "$root/tests/coexistence/program.c" &
                    matrix_count=$((matrix_count + 1))
                    while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n || true; done
                done
            done
        done
    done
done
wait
if [ -s "$matrix_failures" ]; then
    cat "$matrix_failures" >&2
    fail "compile matrix: $(grep -c 'ours-first=' "$matrix_failures") of $matrix_count combinations failed (above)"
fi
passed=$((passed + matrix_count))
foundation_as=system
foundation_kind=midl
echo "coexistence: compile matrix (MIDL's and widl's headers), $matrix_count combinations"
# OPCCOMN_FOREIGN_UUIDOF (no longer needed) still leaves __uuidof to the header that came first.
printf '#include <opccomn.h>\n#include <opccomn/opccomn.h>\nint main() { return __uuidof(IOPCCommon).Data1 == 0; }\n' >"$out/widl_first.cpp"
x86_64-w64-mingw32-g++ -std=c++11 "${strict[@]}" -DOPCCOMN_FOREIGN_UUIDOF -I"$root/include" -isystem "$out/foundation/widl" \
    -fsyntax-only "$out/widl_first.cpp" || fail "a widl-generated opccomn.h first, with OPCCOMN_FOREIGN_UUIDOF"
ok

# ---- 2. i686 calling conventions ----
i686-w64-mingw32-gcc -std=c11 "${strict[@]}" -fsyntax-only -I"$root/include" "$root/c-tests/abi_i686.c" ||
    fail "c-tests/abi_i686.c: a declaration has the wrong calling convention"
if i686-w64-mingw32-gcc -std=c11 -fsyntax-only -I"$root/include" -DOPCCOMN_ABI_EXPECT_FAILURE \
        "$root/c-tests/abi_i686.c" 2>/dev/null; then
    fail "the calling-convention check accepts a __cdecl vtable entry (it cannot fail)"
fi
ok
echo "coexistence: i686 calling conventions proven ($(grep -c '^OPCCOMN_' "$root/c-tests/abi_i686.c") checks; the negative control fails as it must)"

# ---- 3. link matrix (x64 and x86, run under Wine) ----
link_matrix() { # arch build_dir run(1/0)
    local arch=$1 build=$2 run=$3 triple rust lib with_i first lang name cc libarg result
    case "$arch" in
        x64) triple=x86_64-w64-mingw32 rust=x86_64-pc-windows-gnu ;;
        x86) triple=i686-w64-mingw32 rust=i686-pc-windows-gnu ;;
    esac
    local static="$build/opccomn/libopccomn.a"
    local implib="$build/cargo/$rust/release/libopccomn.dll.a"
    local dll="$build/cargo/$rust/release/opccomn.dll"
    [ -f "$static" ] && [ -f "$implib" ] && [ -f "$dll" ] || fail "build $build first (static library, import library, DLL)"
    local deps=(-lole32 -loleaut32 -lrpcrt4 -luuid -ladvapi32 -lversion -luserenv -lws2_32 -lntdll -lsynchronization -static-libgcc)
    local dir="$out/run-$arch"
    mkdir -p "$dir"
    cp "$dll" "$dir/"
    # The *_i.c files are C (MIDL's form, with its stray #endif token); compiled as such, once, and
    # linked into the C and the C++ programs alike.
    local foundation_objs=()
    for stem in opccomn opcda opc_ae opchda; do
        $triple-gcc -w -c -o "$dir/${stem}_i.o" "$out/foundation/${stem}_i.c" -I"$out/foundation"
        foundation_objs+=("$dir/${stem}_i.o")
    done
    for lib in static dll; do
        for with_i in 1 0; do
            for first in 1 0; do
                for lang in c c++; do
                    name="$dir/link-$lib-i$with_i-first$first-$lang.exe"
                    libarg=$([ "$lib" = static ] && echo "$static" || echo "$implib")
                    cc=$triple-gcc
                    local extra=() iobjs=() macros=()
                    if [ "$lang" = c++ ]; then cc=$triple-g++; extra=(-static-libstdc++); fi
                    [ "$with_i" = 1 ] && iobjs=("${foundation_objs[@]}")
                    # C through the COBJMACROS call macros, C++ through the classes.
                    [ "$lang" = c ] && macros=(-DCOBJMACROS)
                    compile "$cc" "$lang" "${macros[@]}" -DOURS_FIRST=$first -c -o "$name.o" "$root/tests/coexistence/program.c"
                    "$cc" -o "$name" "$name.o" "${iobjs[@]}" "$libarg" "${deps[@]}" "${extra[@]}" ||
                        fail "link ($arch): $lib library, *_i.c=$with_i, ours-first=$first, $lang"
                    if [ "$run" = 1 ]; then
                        result=$(cd "$dir" && wine "$name" 2>/dev/null | tr -d '\r')
                        [ "$result" = "coexistence program: 0 failure(s)" ] ||
                            fail "run ($arch): $lib library, *_i.c=$with_i, ours-first=$first, $lang: '$result'"
                    fi
                    ok
                done
            done
        done
    done
    # widl's headers (what mingw users who compile the Foundation's IDL include): C (COBJMACROS) and
    # C++ (__uuidof of every interface), whichever header came first, against either library (widl's
    # *_i.c beside the import library, as a project that compiles the IDL links them).
    local widl_objs=()
    for stem in opccomn opcda opc_ae opchda; do
        $triple-gcc -w -c -o "$dir/widl_${stem}_i.o" "$out/foundation/widl/${stem}_i.c"
        widl_objs+=("$dir/widl_${stem}_i.o")
    done
    foundation_kind=widl
    for lib in static dll; do
        for first in 1 0; do
            for lang in c c++; do
                name="$dir/link-widl-$lib-first$first-$lang.exe"
                libarg=$([ "$lib" = static ] && echo "$static" || echo "$implib")
                local iobjs=() extra=() macros=()
                [ "$lib" = dll ] && iobjs=("${widl_objs[@]}")
                cc=$triple-gcc
                if [ "$lang" = c++ ]; then cc=$triple-g++; extra=(-static-libstdc++); else macros=(-DCOBJMACROS); fi
                compile "$cc" "$lang" "${macros[@]}" -DOURS_FIRST=$first -c -o "$name.o" "$root/tests/coexistence/program.c"
                "$cc" -o "$name" "$name.o" "${iobjs[@]}" "$libarg" "${deps[@]}" "${extra[@]}" ||
                    fail "link ($arch): widl's headers, $lib library, ours-first=$first, $lang"
                if [ "$run" = 1 ]; then
                    result=$(cd "$dir" && wine "$name" 2>/dev/null | tr -d '\r')
                    [ "$result" = "coexistence program: 0 failure(s)" ] ||
                        fail "run ($arch): widl's headers, $lib library, ours-first=$first, $lang: '$result'"
                fi
                ok
            done
        done
    done
    foundation_kind=midl
    if [ "$run" = 1 ]; then
        echo "coexistence: link matrix ($arch: static and import library x with/without the *_i.c files x both orders x C with COBJMACROS/C++ with __uuidof; widl's headers in C and C++, both orders, either library) ran under Wine"
    else
        echo "coexistence: link matrix ($arch) linked; NOT RUN (no 32-bit Wine)" >&2
    fi
}

# ---- 4. a server DLL with its own .def, against both import libraries ----
own_def_server() { # arch build_dir run(1/0)
    local arch=$1 build=$2 run=$3 triple rust regsvr32 lib name imports exports value
    case "$arch" in
        x64) triple=x86_64-w64-mingw32 rust=x86_64-pc-windows-gnu regsvr32=regsvr32 ;;
        x86) triple=i686-w64-mingw32 rust=i686-pc-windows-gnu regsvr32='C:\windows\syswow64\regsvr32.exe' ;;
    esac
    local rust_out="$build/cargo/$rust/release"
    # Neither import library offers the standard names; both offer opccomn's own.
    for lib in "$rust_out/libopccomn.dll.a" "$rust_out/msvc/opccomn.lib"; do
        [ -f "$lib" ] || fail "$lib not built"
        if llvm-nm "$lib" 2>/dev/null | grep -E ' T (__imp_)?_?Dll(GetClassObject|CanUnloadNow|RegisterServer|UnregisterServer|Install)(@[0-9]+)?$'; then
            fail "$lib ($arch) offers the standard Dll* entry points for linking"
        fi
        [ "$(llvm-nm "$lib" 2>/dev/null | grep -cE ' T _?OpcDll(GetClassObject|CanUnloadNow|RegisterServer|UnregisterServer|Install)(@[0-9]+)?$')" = 5 ] ||
            fail "$lib ($arch) does not offer the five OpcDll* functions"
        ok
    done
    local dir="$out/own-def-$arch"
    mkdir -p "$dir"
    cp "$rust_out/opccomn.dll" "$dir/"
    # The class's InprocServer32, read through the registry API in the server's registry view (Wine's
    # reg.exe did not find keys the library created, though the API does).
    "$triple-gcc" -std=c99 -Wall -Wextra -Werror -O2 -o "$dir/own_def_query.exe" "$root/tests/coexistence/own_def_query.c"
    for lib in libopccomn.dll.a msvc/opccomn.lib; do
        name="$dir/own_def_server.dll"
        "$triple-gcc" -std=c99 -Wall -Wextra -Werror -O2 -shared -o "$name" -I"$root/include" \
            "$root/tests/coexistence/own_def_server.c" "$root/tests/coexistence/own_def_server.def" \
            "$rust_out/$lib" -Wl,--enable-stdcall-fixup || fail "own .def server ($arch, $lib) does not link"
        imports=$(x86_64-w64-mingw32-objdump -p "$name" | sed -n '/DLL Name: opccomn.dll/,/^$/p')
        exports=$(x86_64-w64-mingw32-objdump -p "$name" | sed -n '/^\[Ordinal\/Name Pointer\] Table/,/^$/p')
        if grep -E 'Dll(GetClassObject|CanUnloadNow|RegisterServer|UnregisterServer|Install)$' <<<"$imports"; then
            fail "own .def server ($arch, $lib) exports opccomn.dll's entry points as its own: $imports"
        fi
        for f in DllGetClassObject DllCanUnloadNow DllRegisterServer DllUnregisterServer; do
            grep -qE "\] $f\$" <<<"$exports" || fail "own .def server ($arch, $lib) does not export $f"
        done
        grep -q OpcRegisterServer <<<"$imports" || fail "own .def server ($arch, $lib) does not use opccomn.dll"
        if [ "$run" = 1 ]; then
            (cd "$dir" && wine "$regsvr32" /s own_def_server.dll) || fail "regsvr32 own_def_server.dll ($arch, $lib)"
            value=$(wine "$dir/own_def_query.exe" 2>/dev/null | tr -d '\r')
            grep -qi '\\own-def-'"$arch"'\\own_def_server.dll$' <<<"$value" ||
                fail "regsvr32 ($arch, $lib) did not register the server's own class (InprocServer32: '$value')"
            (cd "$dir" && wine "$regsvr32" /s /u own_def_server.dll) || fail "regsvr32 /u own_def_server.dll ($arch, $lib)"
            value=$(wine "$dir/own_def_query.exe" 2>/dev/null | tr -d '\r')
            [ "$value" = absent ] || fail "regsvr32 /u ($arch, $lib) left the server's class: '$value'"
        fi
        ok
    done
    if [ "$run" = 1 ]; then
        echo "coexistence: a server DLL with its own .def ($arch) exports its own entry points and registers its own class (regsvr32 under Wine), against libopccomn.dll.a and opccomn.lib"
    else
        echo "coexistence: a server DLL with its own .def ($arch) exports its own entry points; regsvr32 NOT RUN (no 32-bit Wine)" >&2
    fi
}

if [ -n "$win_build" ]; then
    link_matrix x64 "$win_build" 1
    own_def_server x64 "$win_build" 1
else
    echo "coexistence: LINK MATRIX SKIPPED (no Windows build directory given)" >&2
fi
if [ -n "$win_build_x86" ]; then
    x86_run=0
    [ "$x86_mode" = run ] && x86_run=1
    link_matrix x86 "$win_build_x86" "$x86_run"
    own_def_server x86 "$win_build_x86" "$x86_run"
else
    echo "coexistence: x86 LINK MATRIX SKIPPED (no x86 Windows build directory given)" >&2
fi

# ---- 5. Linux: clang and the static library ----
if [ -n "$linux_build" ]; then
    for cc in gcc g++ clang clang++; do
        if ! command -v "$cc" >/dev/null; then
            echo "coexistence: $cc not installed, Linux header check without it"
            continue
        fi
        kind=c
        case "$cc" in *++) kind=c++ ;; esac
        for mode in "${modes[@]}"; do
            lang=${mode%%:*}
            define=${mode#*:}
            [ "$lang" = "$kind" ] || continue
            printf '#include <opccomn/opccomn.h>\nint main(void) { return OPC_E_INVALIDFILTER == 0; }\n' |
                compile "$cc" "$lang" ${define:+"$define"} -fsyntax-only - || fail "Linux $cc $lang $define"
            ok
        done
    done
    # An object file that defines the library's identifiers itself (as opccomn_i.c does on Windows) links
    # with the static library: the object's definitions win, the archive's are never pulled.
    gcc -c -o "$out/own_guids.o" "$root/src/c/opccomn_guids.c"
    printf '#include <opccomn/opccomn.h>\n#include <stdio.h>\nint main(void) { void *p = 0; HRESULT hr = OpcCommonCreate(0, 0, &IID_IOPCCommon, &p);\n if (hr == S_OK) ((IOPCCommon *)p)->lpVtbl->Release((IOPCCommon *)p);\n printf("%%d\\n", hr == S_OK && CATID_OPCDAServer20.Data1 == 0x63D5F432u); return hr != S_OK; }\n' > "$out/linux_link.c"
    gcc -std=c99 -o "$out/linux_link" -I"$root/include" "$out/linux_link.c" "$out/own_guids.o" \
        "$linux_build/opccomn/libopccomn.a" -lpthread -ldl -lm || fail "Linux static link beside an object defining the IIDs"
    [ "$("$out/linux_link")" = 1 ] || fail "Linux static link: wrong values"
    ok
    echo "coexistence: Linux header under the installed compilers; static library beside own IID definitions"
fi
echo "coexistence: $passed passed, 0 failed"
