# Sourced by the test scripts: a Wine prefix for running the Windows build, created on first use.
# Sets WINEPREFIX (under the build directory), keeps wineserver running for the caller's lifetime and
# installs the bcryptprimitives.dll test fixture (see tests/wine/bcryptprimitives.c), 64-bit and 32-bit.
# Usage: . scripts/wine-env.sh BUILD_DIR
# Wine wants an absolute prefix path; accept a relative build directory.
wine_build_dir=$(mkdir -p "$1" && cd "$1" && pwd)
export WINEPREFIX="$wine_build_dir/wineprefix" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml=;winemenubuilder.exe=d"
unset DISPLAY
# A prefix belongs to the Wine installation that made it: one made while only 64-bit Wine was installed
# has no 32-bit system, and after wine32:i386 arrives every program in it fails ("could not load
# kernel32.dll, status c0000135"). The prefix records which installation made it and is made anew when
# that changes. Callers install every Wine package before sourcing this file (scripts/deps.sh).
wine_installation() {
    local pkg
    printf '%s\n' "$(wine --version 2>/dev/null)"
    for pkg in wine64 wine32:i386 libwine libwine:i386; do
        printf '%s=%s\n' "$pkg" "$(dpkg-query -W -f='${Status} ${Version}' "$pkg" 2>/dev/null || true)"
    done
}
wine_stamp="$WINEPREFIX/opccomn-wine-installation.txt"
if [ -f "$WINEPREFIX/system.reg" ] && [ "$(cat "$wine_stamp" 2>/dev/null)" != "$(wine_installation)" ]; then
    echo "== Wine prefix $WINEPREFIX was made by another Wine installation: making it anew"
    wineserver -k 2>/dev/null || true
    rm -rf "$WINEPREFIX"
fi
if [ ! -f "$WINEPREFIX/system.reg" ]; then
    echo "== creating Wine prefix $WINEPREFIX"
    wine wineboot -i >/dev/null 2>&1 || true
    wineserver -w
    wine_installation >"$wine_stamp"
fi
wineserver -p 2>/dev/null || true
trap 'wineserver -k 2>/dev/null || true' EXIT
# Start Wine's services now, with their output going nowhere: a service first started by a test would
# inherit the test runner's output pipe and keep it open, and ctest would wait for it forever.
wine cmd.exe /c exit 0 </dev/null >/dev/null 2>&1 || true
src_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# The fixture for 64-bit processes goes into system32, the 32-bit one (when the i686 compiler is there)
# into syswow64, where WOW64 looks for the DLLs of 32-bit processes.
for wine_fixture_arch in x86_64:system32 i686:syswow64; do
    wine_fixture_cc="${wine_fixture_arch%%:*}-w64-mingw32-gcc"
    fixture="$WINEPREFIX/drive_c/windows/${wine_fixture_arch#*:}/bcryptprimitives.dll"
    command -v "$wine_fixture_cc" >/dev/null && [ -d "$(dirname "$fixture")" ] || continue
    if [ ! -f "$fixture" ] || [ "$src_dir/tests/wine/bcryptprimitives.c" -nt "$fixture" ]; then
        "$wine_fixture_cc" -O2 -shared -o "$fixture" "$src_dir/tests/wine/bcryptprimitives.c" \
            "$src_dir/tests/wine/bcryptprimitives.def" -ladvapi32 -Wl,--enable-stdcall-fixup
    fi
done
