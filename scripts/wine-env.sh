# Sourced by the test scripts: a Wine prefix for running the Windows build, created on first use.
# Sets WINEPREFIX (under the build directory), keeps wineserver running for the caller's lifetime and
# installs the bcryptprimitives.dll test fixture (see tests/wine/bcryptprimitives.c).
# Usage: . scripts/wine-env.sh BUILD_DIR
# Wine wants an absolute prefix path; accept a relative build directory.
wine_build_dir=$(mkdir -p "$1" && cd "$1" && pwd)
export WINEPREFIX="$wine_build_dir/wineprefix" WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml=;winemenubuilder.exe=d"
unset DISPLAY
if [ ! -f "$WINEPREFIX/system.reg" ]; then
    echo "== creating Wine prefix $WINEPREFIX"
    wine wineboot -i >/dev/null 2>&1 || true
    wineserver -w
fi
wineserver -p 2>/dev/null || true
trap 'wineserver -k 2>/dev/null || true' EXIT
# Start Wine's services now, with their output going nowhere: a service first started by a test would
# inherit the test runner's output pipe and keep it open, and ctest would wait for it forever.
wine cmd.exe /c exit 0 </dev/null >/dev/null 2>&1 || true
fixture="$WINEPREFIX/drive_c/windows/system32/bcryptprimitives.dll"
src_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if [ ! -f "$fixture" ] || [ "$src_dir/tests/wine/bcryptprimitives.c" -nt "$fixture" ]; then
    x86_64-w64-mingw32-gcc -O2 -shared -o "$fixture" "$src_dir/tests/wine/bcryptprimitives.c" \
        "$src_dir/tests/wine/bcryptprimitives.def" -ladvapi32
fi
