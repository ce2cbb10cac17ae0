#!/usr/bin/env bash
# The MSI packages under Wine's msiexec (stage `msi` of scripts/test.sh): installed and removed silently,
# registration checked by a client that browses through the installed browser and marshals through the
# installed proxy/stub, the browser as the Windows service COM starts (the default) and as a local
# server (OPCCOMN_SERVICE=0), a major upgrade, OpcEnum and an OPC Foundation-style proxy/stub registered
# before and after, two vendor products sharing the components, and the registry
# (HKLM\Software\Classes, both views) and the service compared before and after.
#
# Usage: scripts/test-msi.sh PACKAGE_DIR FOUNDATION_PS_X64 FOUNDATION_PS_X86 X86_MODE
#   PACKAGE_DIR: the unpacked Windows package (its msi/, x64/ and x86/ folders)
#   FOUNDATION_PS_*: the stand-in for the Foundation's opccomn_ps.dll (opccomn_widl_ps.dll, which
#     registers itself for the five interfaces as the Foundation's does), x64 and x86
#   X86_MODE: run, or the reason the x86 package cannot run (no 32-bit Wine)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
pkg=$(cd "$1" && pwd)
foundation64=$2 foundation86=$3 x86_mode=$4
version=$(cat "$pkg/VERSION")
work="$root/build/msi"
mkdir -p "$work"
rm -rf "$work/run" && mkdir -p "$work/run"
run="$work/run"

OURS='{3D738B71-0B9D-4337-A725-E8541A96D1C9}'
LIST='HKLM\Software\Classes\CLSID\{13486D51-4821-11D2-A494-3CB306C10000}'
COMMON='HKLM\Software\Classes\Interface\{F31DFDE2-07B6-11D2-B2D8-0060083BA1FB}\ProxyStubClsid32'
OPCENUM='C:\Windows\System32\OpcEnum.exe'
SERVICE='HKLM\SYSTEM\CurrentControlSet\Services\OpcComnBrowser'
svc_view=64   # the registry view of the service checks (32 in the 32-bit prefix)
BROWSER_APPID='HKLM\Software\Classes\AppID\{CCD63ADF-D02D-46DD-B170-FA6E0F086FE3}'
fail() { echo "test-msi: $*" >&2; exit 1; }

# The test client (no opccomn code of its own: tests/msi/msi_client.c) and the vendor products.
x86_64-w64-mingw32-gcc -O1 -Wall -Wextra -Werror -I"$root/include" -I"$root/c-tests" -o "$run/msi_client64.exe" \
    "$root/tests/msi/msi_client.c" -lole32 -luuid -ladvapi32 -lshell32 -static-libgcc
i686-w64-mingw32-gcc -O1 -Wall -Wextra -Werror -I"$root/include" -I"$root/c-tests" -o "$run/msi_client32.exe" \
    "$root/tests/msi/msi_client.c" -lole32 -luuid -ladvapi32 -lshell32 -static-libgcc
# A vendor builds with the package's opccomn.wxi and binaries, as docs/guide/installer.md says.
echo "a test vendor's own file" >"$run/vendor-readme.txt"
ln -sfn "$pkg/x64" "$run/x64"
ln -sfn "$pkg/x86" "$run/x86"
for vendor in A B; do
    (cd "$run" && wixl -a x64 -I "$pkg/msi" -D Vendor=$vendor -D OpcComnArch=x64 -D OpcComnBin64=x64 -D OpcComnBin86=x86 \
        -o "$run/vendor$vendor.msi" "$root/tests/msi/vendor.wxs")
done
# An earlier version of the same package, to be replaced by the package's.
scripts/build-msi.sh "$run/earlier" "$pkg/x64" "$pkg/x86" 0.0.1 >/dev/null
msi64="$pkg/msi/opccomn-$version-x64.msi"
msi86="$pkg/msi/opccomn-$version-x86.msi"
product_code() { msiinfo export "$1" Property | tr -d '\r' | sed -n 's/^ProductCode\t//p'; }

# ---- helpers running in the current prefix ----
winpath() { winepath -w "$1" 2>/dev/null; }
msi() {   # msi /i|/x PACKAGE [PROPERTY=VALUE...]: silent; the exit code of msiexec
    local op=$1 file=$2
    shift 2
    wine msiexec "$op" "$(winpath "$file")" /qn "$@" >/dev/null 2>&1
}
reg_value() {   # reg_value VIEW KEY [NAME]: the string data, or nothing
    if [ -n "${3:-}" ]; then
        wine reg query "$2" /v "$3" /reg:"$1" 2>/dev/null
    else
        wine reg query "$2" /ve /reg:"$1" 2>/dev/null
    fi | tr -d '\r' | sed -nE 's/^ +[^ ]+ +REG_[A-Z_]+ +(.*)$/\1/p' | head -1
}
# service_form EXE WHAT: the browser EXE (a Windows path) is registered as the service OpcComnBrowser:
# on demand, NT AUTHORITY\LocalService, its path in quotes, the AppID's LocalService naming it.
service_form() {
    local image
    image=$(reg_value "$svc_view" "$SERVICE" ImagePath) || true   # (none: the pipeline fails)
    [ "$image" = "\"$1\" -RunService" ] || fail "$2: the service's command line: ${image:-no service}"
    [ "$(reg_value "$svc_view" "$SERVICE" Start)" = 0x3 ] || fail "$2: the service does not start on demand"
    [ "$(reg_value "$svc_view" "$SERVICE" ObjectName)" = 'NT AUTHORITY\LocalService' ] || fail "$2: the service's account"
    [ "$(reg_value "$svc_view" "$BROWSER_APPID" LocalService)" = OpcComnBrowser ] || fail "$2: the AppID names no LocalService"
}
no_service() {   # no_service WHAT: no service OpcComnBrowser
    wine reg query "$SERVICE" /reg:"$svc_view" >/dev/null 2>&1 && fail "$1: the service OpcComnBrowser exists"
    return 0
}
installed() { wine reg query "HKLM\\Software\\Microsoft\\Windows\\CurrentVersion\\Uninstall\\$1" /reg:"$2" >/dev/null 2>&1; }
# snapshot FILE VIEW...: HKLM\Software\Classes of each view, without Windows Installer's own keys
# (Software\Classes\Installer: its bookkeeping, whose empty keys it leaves).
snapshot() {
    local file=$1 view
    shift
    : >"$file"
    for view in "$@"; do
        wine reg export 'HKLM\Software\Classes' "$(winpath "$run/export.reg")" /y /reg:"$view" >/dev/null 2>&1
        python3 - "$run/export.reg" "$view" >>"$file" <<'PY'
import sys
text = open(sys.argv[1], encoding="utf-16").read().replace("\r\n", "\n")
for block in text.split("\n\n"):
    if not block.startswith("[HKEY_LOCAL_MACHINE\\Software\\Classes\\Installer"):
        print(sys.argv[2], block)
PY
    done
}
same() {   # same A B WHAT
    if ! diff -q "$1" "$2" >/dev/null; then
        diff "$1" "$2" | head -40 >&2
        fail "$3: the registry differs"
    fi
}
browse() {   # browse CLIENT PROXY_DLL [nowait]: the client browses through the installed browser
    wine "$1" browse "$2" ${3:-} >"$run/client.out" 2>&1 || { cat "$run/client.out" >&2; fail "$(basename "$1") browse $2 failed"; }
    # (a 32-bit program that did not start prints nothing and exits 0)
    grep '^msi_client browse: [0-9]* passed, 0 failed' "$run/client.out" || fail "$(basename "$1") did not run"
}
# The 32-bit client, then the 64-bit one while the browser the first started still serves (one after
# the other: two first activations at once can start two browsers under Wine); the second waits for
# the browser to exit. As a service (clients service): the 64-bit client's activation starts the
# service, the 32-bit one's reaches the running service; each finds it running in the browser's
# process; it serves until removal stops it. (The 64-bit one first: Wine's 32-bit COM reads the AppID
# through the 32-bit view of the CLSID key, which the x64 browser registers in the 64-bit view, so a
# 32-bit client's activation starts the browser by its LocalServer32 when the service is not running.)
clients() {
    if [ "${1:-}" = service ]; then
        browse "$run/msi_client64.exe" "$dll64" service
        browse "$run/msi_client32.exe" "$dll86" service
    else
        browse "$run/msi_client32.exe" "$dll86" nowait
        browse "$run/msi_client64.exe" "$dll64"
    fi
}
opcenum_register() {
    printf 'Windows Registry Editor Version 5.00\r\n\r\n[%s]\r\n@="OpcServerList Class"\r\n"AppID"="{13486D44-4821-11D2-A494-3CB306C10000}"\r\n\r\n[%s\\LocalServer32]\r\n@="%s"\r\n\r\n[%s\\ProgID]\r\n@="OPC.ServerList.1"\r\n\r\n[HKEY_LOCAL_MACHINE\\Software\\Classes\\AppID\\{13486D44-4821-11D2-A494-3CB306C10000}]\r\n@="OpcEnum"\r\n"LocalService"="OpcEnum"\r\n\r\n[HKEY_LOCAL_MACHINE\\Software\\Classes\\OPC.ServerList.1\\CLSID]\r\n@="{13486D51-4821-11D2-A494-3CB306C10000}"\r\n\r\n' \
        "${LIST/HKLM/HKEY_LOCAL_MACHINE}" "${LIST/HKLM/HKEY_LOCAL_MACHINE}" "${OPCENUM//\\/\\\\}" "${LIST/HKLM/HKEY_LOCAL_MACHINE}" \
        | iconv -f utf-8 -t utf-16 >"$run/opcenum.reg"
    wine reg import "$(winpath "$run/opcenum.reg")" /reg:64 >/dev/null 2>&1 || fail "OpcEnum's entries not imported"
}
opcenum_remove() {
    local key
    for key in "$LIST" 'HKLM\Software\Classes\AppID\{13486D44-4821-11D2-A494-3CB306C10000}' 'HKLM\Software\Classes\OPC.ServerList.1'; do
        wine reg delete "$key" /f /reg:64 >/dev/null 2>&1 || true
    done
}
foundation() {   # foundation /u or "": the Foundation-style proxy/stub, both bitnesses
    wine regsvr32 /s $1 'C:\foundation\x64\opccomn_widl_ps.dll' || fail "regsvr32 $1 of the x64 stand-in"
    wine regsvr32 /s $1 'C:\foundation\x86\opccomn_widl_ps.dll' || fail "regsvr32 $1 of the x86 stand-in"
}

# ================= x64: a 64-bit prefix with 32-bit support =================
# A prefix of its own, made anew when a run was interrupted (the MSIs are rebuilt with new product
# codes each run, so what an earlier run left installed cannot be removed by them).
[ -f "$work/wineprefix/clean" ] || rm -rf "$work/wineprefix"
. "$root/scripts/wine-env.sh" "$work"
rm -f "$WINEPREFIX/clean"
mkdir -p "$WINEPREFIX/drive_c/foundation/x64" "$WINEPREFIX/drive_c/foundation/x86"
cp "$foundation64" "$WINEPREFIX/drive_c/foundation/x64/opccomn_widl_ps.dll"
cp "$foundation86" "$WINEPREFIX/drive_c/foundation/x86/opccomn_widl_ps.dll"
dll64='C:\Program Files\Common Files\opccomn\opccomn.dll'
dll86='C:\Program Files (x86)\Common Files\opccomn\opccomn.dll'
browser64='C:\Program Files\Common Files\opccomn\opccomn_browser.exe'
wine "$run/msi_client64.exe" absent >/dev/null || fail "the prefix $WINEPREFIX already has a server browser registered"
snapshot "$run/base" 64 32

# 1. OpcEnum and the Foundation's proxy/stub installed before: the package leaves both as they are
#    (unless OPCCOMN_TAKEOVER=1 for the browser), and its removal gives back exactly what was there.
opcenum_register
foundation ""
foundation_ps=$(reg_value 64 "$COMMON")
[ -n "$foundation_ps" ] && [ "$foundation_ps" != "$OURS" ] || fail "the Foundation stand-in did not register ($foundation_ps)"
snapshot "$run/others" 64 32
msi /i "$msi64" || fail "install next to OpcEnum"
[ "$(reg_value 64 "$LIST\\LocalServer32")" = "$OPCENUM" ] || fail "OpcEnum's CLSID taken over without OPCCOMN_TAKEOVER"
no_service "installed next to OpcEnum without OPCCOMN_TAKEOVER"
[ "$(reg_value 64 "$COMMON")" = "$foundation_ps" ] && [ "$(reg_value 32 "$COMMON")" = "$foundation_ps" ] ||
    fail "the Foundation's proxy/stub was replaced"
[ "$(reg_value 64 'HKLM\Software\Classes\CLSID\{3D738B71-0B9D-4337-A725-E8541A96D1C9}\InprocServer32')" = "$dll64" ] ||
    fail "the x64 proxy/stub class is not registered"
msi /x "$msi64" || fail "uninstall next to OpcEnum"
snapshot "$run/after" 64 32
same "$run/others" "$run/after" "installed and removed next to OpcEnum and the Foundation's proxy/stub"
msi /i "$msi64" OPCCOMN_TAKEOVER=1 || fail "install with OPCCOMN_TAKEOVER=1"
[ "$(reg_value 64 "$LIST\\LocalServer32")" = '"C:\Program Files\Common Files\opccomn\opccomn_browser.exe"' ] ||
    fail "OPCCOMN_TAKEOVER=1 did not make the browser the active one"
service_form "$browser64" "OPCCOMN_TAKEOVER=1"
msi /x "$msi64" || fail "uninstall after OPCCOMN_TAKEOVER=1"
no_service "removed after OPCCOMN_TAKEOVER=1"
snapshot "$run/after" 64 32
same "$run/others" "$run/after" "taken over from OpcEnum and removed"
opcenum_remove
foundation /u
snapshot "$run/after" 64 32
same "$run/base" "$run/after" "OpcEnum and the Foundation stand-in removed"
echo "msi x64: next to OpcEnum and the Foundation's proxy/stub: both left alone, no service (OPCCOMN_TAKEOVER=1 takes the CLSID, registers the service, gives both back), the registry as before"

# 2. Alone: an earlier version, replaced by the package's (major upgrade); a repair; clients browse
#    through the installed browser and marshal through the installed proxy/stubs (64-bit and 32-bit);
#    OpcEnum and the Foundation's proxy/stub installed after; removal leaves theirs.
earlier="$run/earlier/opccomn-0.0.1-x64.msi"
msi /i "$earlier" || fail "install of the earlier version"
installed "$(product_code "$earlier")" 64 || fail "the earlier version is not installed"
msi /i "$msi64" || fail "upgrade"
installed "$(product_code "$earlier")" 64 && fail "the upgrade left the earlier version installed"
installed "$(product_code "$msi64")" 64 || fail "the upgrade did not install the package"
service_form "$browser64" "upgraded"
msi /i "$earlier" && fail "the earlier version installed over the later one"
# A repair puts back a registration someone damaged (Wine's msiexec /fa fails: the same by properties).
wine reg delete "$COMMON" /f /reg:64 >/dev/null 2>&1 || fail "no ProxyStubClsid32 to damage"
msi /i "$msi64" REINSTALL=ALL REINSTALLMODE=omus || fail "repair"
[ "$(reg_value 64 "$COMMON")" = "$OURS" ] || fail "the repair did not register the proxy/stub again"
service_form "$browser64" "repaired"
clients service
opcenum_register
foundation ""
msi /x "$msi64" || fail "uninstall with OpcEnum and the Foundation's proxy/stub installed after"
[ "$(reg_value 64 "$LIST\\LocalServer32")" = "$OPCENUM" ] || fail "OpcEnum registered after the package lost its LocalServer32"
[ "$(reg_value 64 "$LIST" AppID)" = '{13486D44-4821-11D2-A494-3CB306C10000}' ] || fail "OpcEnum registered after the package lost its AppID"
[ "$(reg_value 64 "$COMMON")" = "$foundation_ps" ] && [ "$(reg_value 32 "$COMMON")" = "$foundation_ps" ] ||
    fail "the Foundation's proxy/stub registered after the package lost its ProxyStubClsid32"
no_service "removed while the service ran"
opcenum_remove
foundation /u
# What the browser added next to OpcEnum's entries (the version-independent ProgID) stays with the class
# (docs/registration-safety.md); it goes with the class.
wine reg delete 'HKLM\Software\Classes\OPC.ServerList' /f /reg:64 >/dev/null 2>&1 || true
snapshot "$run/after" 64 32
same "$run/base" "$run/after" "upgraded, OpcEnum and the Foundation's proxy/stub registered after, removed"
echo "msi x64: an earlier version replaced; a repair registers again; the browser a service (on demand, LocalService, its path quoted), started by a client's activation through the service manager; 64-bit and 32-bit clients browse and marshal through the installed files; removal stops and deletes the service; OpcEnum and the Foundation's proxy/stub installed after keep their entries; the registry as before"

# 2b. The EXE form (OPCCOMN_SERVICE=0): a local server, no service; COM starts it per client.
msi /i "$msi64" OPCCOMN_SERVICE=0 || fail "install with OPCCOMN_SERVICE=0"
no_service "OPCCOMN_SERVICE=0"
[ -z "$(reg_value "$svc_view" "$BROWSER_APPID" LocalService)" ] || fail "OPCCOMN_SERVICE=0: the AppID names a LocalService"
clients
msi /x "$msi64" || fail "uninstall of the EXE form"
snapshot "$run/after" 64 32
same "$run/base" "$run/after" "the EXE form installed and removed"
echo "msi x64: OPCCOMN_SERVICE=0: the browser a local server (no service), clients browse; the registry as before"

# 3. Two vendors' products sharing the components: install A, install B, remove A: B's clients still
#    browse and marshal; remove B: the registry as before.
msi /i "$run/vendorA.msi" || fail "install of vendor A"
msi /i "$run/vendorB.msi" || fail "install of vendor B"
msi /x "$run/vendorA.msi" || fail "removal of vendor A"
[ -f "$WINEPREFIX/drive_c/Program Files (x86)/Test OPC server A/readme.txt" ] && fail "vendor A's own file stayed"
service_form "$browser64" "vendor A removed, B installed"
clients service
msi /x "$run/vendorB.msi" || fail "removal of vendor B"
no_service "both vendors removed"
wine "$run/msi_client64.exe" absent >/dev/null || fail "the browser is still registered after the last product went"
[ -e "$WINEPREFIX/drive_c/Program Files/Common Files/opccomn" ] && fail "the shared files stayed after the last product went"
snapshot "$run/after" 64 32
same "$run/base" "$run/after" "two vendors' products installed and removed"
echo "msi x64: two products sharing the components: after the first's removal the second's clients browse and marshal; after both, the registry as before"

# 4. The x86 package refuses 64-bit Windows (the x64 package has both proxy/stubs).
msi /i "$msi86" && fail "the x86 package installed on 64-bit Windows"
touch "$WINEPREFIX/clean"
wineserver -k 2>/dev/null || true
trap - EXIT

# ================= x86: a 32-bit prefix (32-bit Windows) =================
if [ "$x86_mode" != run ]; then
    echo "test-msi: the x86 package was NOT tested ($x86_mode)"
    exit 0
fi
export WINEARCH=win32 WINEPREFIX="$work/wineprefix-x86"
svc_view=32
[ -f "$WINEPREFIX/clean" ] || rm -rf "$WINEPREFIX"
if [ ! -f "$WINEPREFIX/system.reg" ]; then
    echo "== creating 32-bit Wine prefix $WINEPREFIX"
    wine wineboot -i >/dev/null 2>&1 || true
    wineserver -w
fi
wineserver -p 2>/dev/null || true
trap 'wineserver -k 2>/dev/null || true' EXIT
wine cmd.exe /c exit 0 </dev/null >/dev/null 2>&1 || true
[ -d "$WINEPREFIX/drive_c/windows/syswow64" ] && fail "$WINEPREFIX is not a 32-bit prefix"
# The test fixture every program that loads opccomn.dll needs under Wine 8 (tests/wine/bcryptprimitives.c).
i686-w64-mingw32-gcc -O2 -shared -o "$WINEPREFIX/drive_c/windows/system32/bcryptprimitives.dll" \
    "$root/tests/wine/bcryptprimitives.c" "$root/tests/wine/bcryptprimitives.def" -ladvapi32 -Wl,--enable-stdcall-fixup
rm -f "$WINEPREFIX/clean"
wine "$run/msi_client32.exe" absent >/dev/null || fail "the prefix $WINEPREFIX already has a server browser registered"
snapshot "$run/base86" 32
msi /i "$run/earlier/opccomn-0.0.1-x86.msi" || fail "x86: install of the earlier version"
msi /i "$msi86" || fail "x86: upgrade"
installed "$(product_code "$run/earlier/opccomn-0.0.1-x86.msi")" 32 && fail "x86: the upgrade left the earlier version installed"
service_form 'C:\Program Files\Common Files\opccomn\opccomn_browser.exe' "x86: upgraded"
browse "$run/msi_client32.exe" 'C:\Program Files\Common Files\opccomn\opccomn.dll' service
msi /x "$msi86" || fail "x86: uninstall"
no_service "x86: removed"
wine "$run/msi_client32.exe" absent >/dev/null || fail "x86: the browser is still registered after removal"
snapshot "$run/after86" 32
same "$run/base86" "$run/after86" "x86: upgraded and removed"
echo "msi x86 (32-bit Windows): an earlier version replaced; the browser a service started by a client's activation; a client browses and marshals through the installed files; removal stops and deletes the service; the registry as before"
touch "$WINEPREFIX/clean"
