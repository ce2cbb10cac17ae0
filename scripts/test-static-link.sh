#!/usr/bin/env bash
# The static library linked as the documentation says, and as pkg-config says: tests/static-link/
# static_link.c, which calls into every area of the library, linked against libopccomn.a
#   1. with exactly the libraries the documentation lists (docs/windows.md for mingw-w64, the README
#      for Linux), which must be the list rustc reported when the library was built
#      (<build>/opccomn-static-libs.txt, `--print native-static-libs`);
#   2. with what `pkg-config --static --libs opccomn` of the installed build gives (mingw: `gcc -static`,
#      as mingw programs link statically; Linux: the same flags, `-l:libopccomn.a` for `-lopccomn`, as
#      `-static` would make the C library static too);
# then checks that neither program depends on opccomn.dll / libopccomn.so and runs both: Linux
# natively, Windows under Wine (`link` mode: linked, not run, when 32-bit Wine is missing). On Windows
# a negative control links without the list's last library (-luuid): that must fail, so a library
# missing from a list fails this test.
#
# Usage: scripts/test-static-link.sh linux BUILD_DIR INSTALL_PREFIX
#        scripts/test-static-link.sh windows x64|x86 BUILD_DIR run|link
# (scripts/test.sh: stages package-linux and coexistence; Wine set up as scripts/wine-env.sh does)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
fail() { echo "static link: FAILED: $*" >&2; exit 1; }

platform=${1:-}
case "$platform" in
    linux)
        [ "$#" = 3 ] || fail "usage: $0 linux BUILD_DIR INSTALL_PREFIX"
        arch=linux build=$2 prefix=$3 mode=run
        cc=(cc) objdump=objdump
        # The README's Linux line: cc -std=c11 -Iinclude app.c target/release/libopccomn.a LIBS -o app
        documented=$(sed -nE 's|^cc -std=c11 -Iinclude app\.c target/release/libopccomn\.a (.*) -o app( .*)?$|\1|p' "$root/README.md")
        where="README.md"
        ;;
    windows)
        [ "$#" = 4 ] || fail "usage: $0 windows x64|x86 BUILD_DIR run|link"
        arch=$2 build=$3 mode=$4
        case "$arch" in
            x64) triple=x86_64-w64-mingw32 ;;
            x86) triple=i686-w64-mingw32 ;;
            *) fail "unknown architecture $arch" ;;
        esac
        cc=("$triple-gcc") objdump=$triple-objdump
        prefix="$root/build/static-link/install-$arch"
        # docs/windows.md: Static: link `libopccomn.a` and `LIBS`
        documented=$(sed -nE 's|.*Static: link `libopccomn\.a` and `([^`]*)`.*|\1|p' "$root/docs/windows.md")
        where="docs/windows.md"
        ;;
    *) fail "usage: $0 linux|windows ..." ;;
esac

out="$root/build/static-link/$arch"
rm -rf "$out"
mkdir -p "$out"

# ---- The documented list is rustc's ----
derived=$(tr -s ' \n' ' ' <"$build/opccomn-static-libs.txt" | sed 's/ *$//')
[ -n "$derived" ] || fail "$build/opccomn-static-libs.txt is empty"
[ "$(wc -l <<<"$documented")" = 1 ] && [ -n "$documented" ] || fail "$where does not state the static library's list once"
[ "$documented" = "$derived" ] ||
    fail "$where lists '$documented' for the static library; rustc reported '$derived' ($build/opccomn-static-libs.txt)"
echo "static link ($arch): $where lists what rustc reported: $derived"

# ---- The installed build and its pkg-config file ----
if [ "$platform" = windows ]; then
    rm -rf "$prefix"
    cmake --install "$build" --prefix "$prefix" >/dev/null
fi
lib="$prefix/lib/libopccomn.a"
[ -f "$lib" ] || fail "$lib not installed"
pc=$(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" PKG_CONFIG_LIBDIR="$prefix/lib/pkgconfig" pkg-config --static --libs opccomn)
cflags=$(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" PKG_CONFIG_LIBDIR="$prefix/lib/pkgconfig" pkg-config --cflags opccomn)
grep -qE -- "-lopccomn( |$)" <<<"$pc" || fail "pkg-config --static --libs opccomn gave no -lopccomn: $pc"

# ---- Compile once, link three ways ----
# shellcheck disable=SC2086 # pkg-config's output is a list of flags
"${cc[@]}" -std=c11 -Wall -Wextra -Werror -pedantic $cflags -c -o "$out/static_link.o" "$root/tests/static-link/static_link.c"
exe=""
[ "$platform" = windows ] && exe=.exe
# shellcheck disable=SC2086
"${cc[@]}" -o "$out/documented$exe" "$out/static_link.o" "$lib" $documented ||
    fail "the link with the documented list ($where: $documented) failed"
if [ "$platform" = windows ]; then
    # shellcheck disable=SC2086
    "${cc[@]}" -static -o "$out/pkgconfig$exe" "$out/static_link.o" $pc ||
        fail "the link with pkg-config's list (gcc -static ... $pc) failed"
    # Negative control: the list without its last library (-luuid) does not link.
    short=${derived% *}
    # shellcheck disable=SC2086
    if "${cc[@]}" -o "$out/short$exe" "$out/static_link.o" "$lib" $short 2>"$out/short.err"; then
        fail "the program links without '${derived##* }' (with '$short'): the test cannot catch a missing library"
    fi
    grep -q "undefined reference" "$out/short.err" || fail "the negative control failed otherwise: $(head -3 "$out/short.err")"
    echo "static link ($arch): without ${derived##* } the link fails ($(grep -c 'undefined reference' "$out/short.err") undefined references), as it must"
else
    # shellcheck disable=SC2086
    "${cc[@]}" -o "$out/pkgconfig$exe" "$out/static_link.o" ${pc//-lopccomn/-l:libopccomn.a} ||
        fail "the link with pkg-config's list ($pc, the archive for -lopccomn) failed"
fi
echo "static link ($arch): linked with the documented list and with pkg-config's ($pc)"

# ---- Static: no opccomn.dll / libopccomn.so among the dependencies ----
for program in documented pkgconfig; do
    if [ "$platform" = windows ]; then
        ! "$objdump" -p "$out/$program$exe" | grep -qi 'DLL Name: opccomn.dll' || fail "$program$exe imports opccomn.dll"
    else
        ! readelf -d "$out/$program" | grep -q 'NEEDED.*libopccomn' || fail "$program needs libopccomn.so"
    fi
done

# ---- Run ----
if [ "$mode" != run ]; then
    echo "static link ($arch): linked; NOT RUN (no 32-bit Wine)" >&2
    exit 0
fi
for program in documented pkgconfig; do
    if [ "$platform" = windows ]; then
        result=$(cd "$out" && wine "./$program$exe" 2>&1 | tr -d '\r') || true
    else
        result=$("$out/$program" 2>&1) || true
    fi
    last=$(tail -1 <<<"$result")
    [ "$last" = "static link: 10 areas, 0 failed" ] || { echo "$result" >&2; fail "$program$exe ($arch) ended with '$last'"; }
done
echo "static link ($arch): both programs ran, every area answered"
