#!/usr/bin/env bash
# Builds the Windows Installer packages with wixl (Debian's msitools) from packaging/msi/opccomn.wxs
# and opccomn.wxi: opccomn-<version>-x64.msi (the x64 and x86 proxy/stubs, the x64 browser) and
# opccomn-<version>-x86.msi (for 32-bit Windows: the x86 proxy/stub and browser).
# The browser is registered as the Windows service OpcComnBrowser by default (the packages' property
# OPCCOMN_SERVICE=1, opccomn.wxi); OPCCOMN_SERVICE=0 on msiexec's command line installs it as a local
# server instead. One package for both: the form is chosen at install time, the components are the same.
#
# Usage: scripts/build-msi.sh OUT_DIR X64_DIR X86_DIR [VERSION]
#   X64_DIR, X86_DIR: folders holding opccomn.dll and opccomn_browser.exe (the package's x64/ and x86/)
#   VERSION: the package's version (Cargo.toml's); the MSI's ProductVersion is its numeric part
#   (0.3.0-dev: 0.3.0). Windows Installer compares three fields: a package replaces every installed
#   version below the next patch version (so a rebuild of the same version too).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
. "$root/scripts/deps.sh"
need_msi_tools
[ "$#" -ge 3 ] || { echo "usage: scripts/build-msi.sh OUT_DIR X64_DIR X86_DIR [VERSION]" >&2; exit 2; }
out=$1 x64=$(cd "$2" && pwd) x86=$(cd "$3" && pwd)
version=${4:-$(sed -nE 's/^version = "([^"]+)"$/\1/p' "$root/Cargo.toml" | head -1)}
msi_version=${version%%-*}
[[ "$msi_version" =~ ^([0-9]+)\.([0-9]+)\.([0-9]+)$ ]] || { echo "build-msi.sh: version $version is not A.B.C[-suffix]" >&2; exit 2; }
next_version="${BASH_REMATCH[1]}.${BASH_REMATCH[2]}.$((BASH_REMATCH[3] + 1))"
mkdir -p "$out"
out=$(cd "$out" && pwd)
# wixl finds a File's Source relative to the current folder (an absolute path is not found): build in
# a folder where x64/ and x86/ lead to the binaries.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ln -s "$x64" "$work/x64"
ln -s "$x86" "$work/x86"
for arch in x64 x86; do
    (cd "$work" && wixl -a "$arch" -I "$root/packaging/msi" -D OpcComnArch="$arch" -D OpcComnVersion="$msi_version" \
        -D OpcComnNextVersion="$next_version" -D OpcComnBin64=x64 -D OpcComnBin86=x86 \
        -o "$out/opccomn-$version-$arch.msi" "$root/packaging/msi/opccomn.wxs")
    # wixl leaves the File table's Version empty, and Windows Installer then treats a file as
    # unversioned (replaced by any copy another product brings). The DLLs' version is their
    # VERSIONINFO's FILEVERSION (MM.mm.0.bb, buildscript/resources.rs), so that an older copy never
    # replaces a newer one; the browser has no version resource.
    msibuild "$out/opccomn-$version-$arch.msi" -q "UPDATE \`File\` SET \`Version\` = '${BASH_REMATCH[1]}.${BASH_REMATCH[2]}.0.${BASH_REMATCH[3]}' WHERE \`File\` = 'OpcComnDll64' OR \`File\` = 'OpcComnDll86'"
done
echo "MSI: $out/opccomn-$version-x64.msi, $out/opccomn-$version-x86.msi (ProductVersion $msi_version)"
