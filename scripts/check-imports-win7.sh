#!/usr/bin/env bash
# Checks that a DLL's import table names nothing Windows 7 / Server 2008 R2 lacks, so that it loads
# there: every imported DLL must be one Windows 7 has (no bcryptprimitives.dll, whose ProcessPrng
# Rust's standard library takes on its default targets and which exists from Windows 10 on; no
# combase.dll, Windows 8 and later; no api-ms-win-* API sets, of which Windows 7 has only a few), and no
# imported function may be one of those that Windows 7's system DLLs lack although they exist later and
# Rust's standard library, windows-sys or this library are known to call.
# Usage: scripts/check-imports-win7.sh opccomn.dll
set -euo pipefail
dll=$1
objdump=${OPCCOMN_OBJDUMP:-x86_64-w64-mingw32-objdump}
# The DLLs Windows 7 has that a Rust library built with mingw-w64 may import (rpcrt4: the proxy/stub's NDR
# engine; every function it takes from there exists since Windows 2000).
allowed_dlls="kernel32.dll advapi32.dll ntdll.dll ole32.dll oleaut32.dll rpcrt4.dll userenv.dll ws2_32.dll msvcrt.dll user32.dll shell32.dll"
# Functions of Windows 8 and later (kernel32, advapi32, ole32).
too_new="GetSystemTimePreciseAsFileTime WaitOnAddress WakeByAddressSingle WakeByAddressAll ProcessPrng
CreateFile2 CopyFile2 GetCurrentThreadStackLimits SetThreadDescription GetThreadDescription GetTempPath2W
GetOverlappedResultEx PrefetchVirtualMemory SetThreadInformation GetProcessMitigationPolicy
SetProcessMitigationPolicy CompareObjectHandles CoIncrementMTAUsage CoDecrementMTAUsage
CreateFileMappingFromApp MapViewOfFileFromApp GetPackageFamilyName GetCurrentPackageId"

imports=$("$objdump" -p "$dll" | sed -n '/^The Import Tables/,/^The Export Tables\|^PE File Base Relocations/p' |
    awk '/DLL Name:/ { dll = tolower($3); next } NF == 3 && $1 ~ /^[0-9a-f]+$/ && dll != "" { print dll, $3 }')
[ -n "$imports" ] || { echo "$dll: no import table found" >&2; exit 1; }
failed=0
for name in $(awk '{ print $1 }' <<<"$imports" | sort -u); do
    if ! grep -qw -- "$name" <<<"$allowed_dlls"; then
        echo "$dll imports from $name, which Windows 7 does not have: $(awk -v d="$name" '$1 == d { printf "%s ", $2 }' <<<"$imports")" >&2
        failed=$((failed + 1))
    fi
done
for fn in $too_new; do
    if awk '{ print $2 }' <<<"$imports" | grep -qx -- "$fn"; then
        echo "$dll imports $fn, which Windows 7 does not have" >&2
        failed=$((failed + 1))
    fi
done
if [ "$failed" -ne 0 ]; then
    echo "imports of $(basename "$dll"): $failed problems for Windows 7"
    exit 1
fi
echo "imports of $dll: $(wc -l <<<"$imports") functions from $(awk '{ print $1 }' <<<"$imports" | sort -u | tr '\n' ' ')- all on Windows 7"
