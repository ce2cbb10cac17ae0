#!/usr/bin/env bash
# Builds tests/msvc/link_test.c as a Visual Studio project would be built: MSVC mode
# (clang --target=<arch>-pc-windows-msvc, lld-link), no C runtime, linked against opccomn.lib; then runs
# it under Wine next to opccomn.dll (the caller sets WINEPREFIX; see scripts/wine-env.sh) and requires
# its closing line. x86 needs 32-bit Wine.
# Usage: scripts/test-msvc-link.sh [--no-run] x64|x86 DIR_WITH_opccomn.lib_AND_opccomn.dll OUT_DIR
#        (--no-run: build only, for x86 without 32-bit Wine)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
run=1
[ "${1:-}" = --no-run ] && { run=0; shift; }
[ "$#" -eq 3 ] || { echo "usage: $0 [--no-run] x64|x86 LIB_DIR OUT_DIR" >&2; exit 2; }
arch=$1 lib_dir=$2 out=$3
case "$arch" in
    x64) target=x86_64-pc-windows-msvc machine=i386:x86-64 extra=() ;;
    x86) target=i686-pc-windows-msvc machine=i386 extra=(-Wl,-safeseh:no) ;;
    *) echo "$0: unknown architecture $arch" >&2; exit 2 ;;
esac
mkdir -p "$out"
if [ "$arch" = x64 ]; then
    sed -E 's/@[0-9]+$//' "$root/tests/msvc/kernel32.def" >"$out/kernel32.def"
else
    cp "$root/tests/msvc/kernel32.def" "$out/kernel32.def"
fi
llvm-dlltool -m "$machine" -k -d "$out/kernel32.def" -l "$out/kernel32.lib"
clang --target="$target" -O2 -Wall -Wextra -Werror -nostdlib -fuse-ld=lld -Wl,-entry:entry \
    -Wl,-subsystem:console "${extra[@]}" -o "$out/link_test.exe" "$root/tests/msvc/link_test.c" \
    "$lib_dir/opccomn.lib" "$out/kernel32.lib"
cp "$lib_dir/opccomn.dll" "$out/"
[ "$run" = 1 ] || exit 0
result=$(cd "$out" && wine link_test.exe) || { echo "$result"; echo "link_test.exe ($arch) failed" >&2; exit 1; }
echo "$result"
grep -qE "^msvc link test \($([ "$arch" = x64 ] && echo 64 || echo 32)-bit\): [0-9]+ passed, 0 failed" <<<"$result" || {
    echo "link_test.exe ($arch) did not report its results" >&2
    exit 1
}
