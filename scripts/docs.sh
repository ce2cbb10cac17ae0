#!/usr/bin/env bash
# Builds the C API reference (HTML) from include/opccomn/opccomn.h with Doxygen (docs/reference/Doxyfile)
# into build/docs/html, with docs/api-conventions.md as a page of it, and fails when anything in the
# header is undocumented: any Doxygen warning (an undocumented function, struct, field, enum value,
# macro, interface or interface method, a link that leads nowhere), a function the header declares that
# the reference does not list, or a structure of the API conventions' struct_size table that the page
# does not show linked to its reference.
#
# With --check (CI) it also opens the reference in headless Chromium, as a reader would: the index and
# the header's page must render and list what they should (the main page's sections; every exported
# function, with its documentation), and a screenshot of each goes to build/docs/screenshots/.
#
# Installs doxygen (and for --check chromium) with apt-get when missing, saying so first.
# Usage: scripts/docs.sh [--check]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
. scripts/deps.sh
check=0
[ "${1:-}" = --check ] && check=1
command -v doxygen >/dev/null || install_packages "to build the C API reference" doxygen
if [ "$check" = 1 ]; then
    command -v chromium >/dev/null || install_packages "to look at the C API reference as a reader would (headless)" chromium
fi

out="$root/build/docs"
rm -rf "$out/html" "$out/warnings.txt"
mkdir -p "$out"
version=$(sed -nE 's/^version = "([^"]+)"$/\1/p' Cargo.toml | head -1)
OPCCOMN_VERSION="$version" OPCCOMN_DOCS_OUT="$out" doxygen docs/reference/Doxyfile
if [ -s "$out/warnings.txt" ]; then
    cat "$out/warnings.txt" >&2
    echo "docs.sh: $(wc -l <"$out/warnings.txt") Doxygen warnings (above): document every item of the header" >&2
    exit 1
fi
page="$out/html/opccomn_8h.html"
# Every function the header declares is listed on the header's page.
declared=$(grep -E '^[A-Za-z].* OPCCOMN_(CDECL|STDCALL) [A-Za-z0-9_]+\(' include/opccomn/opccomn.h |
    sed -E 's/.* OPCCOMN_(CDECL|STDCALL) ([A-Za-z0-9_]+)\(.*/\2/' | sort -u)
missing=0
for f in $declared; do
    grep -q ">$f</a> (" "$page" || { echo "docs.sh: $f is not in the reference" >&2; missing=$((missing + 1)); }
done
[ "$missing" = 0 ] || exit 1
# docs/api-conventions.md, rendered as Markdown: its struct_size table shows every structure, linked.
conventions="$out/html/api_conventions.html"
sized=$(sed -nE 's/^\| `(Opc[A-Za-z0-9]+)` \| .*/\1/p' docs/api-conventions.md)
[ -f "$conventions" ] && [ -n "$sized" ] || { echo "docs.sh: docs/api-conventions.md is not a page of the reference" >&2; exit 1; }
for s in $sized; do
    grep -qF "<td class=\"markdownTableBodyNone\"><code><a class=\"el\" href=\"struct$s.html\">$s</a></code>" "$conventions" ||
        { echo "docs.sh: the API conventions page does not show $s in its struct_size table" >&2; missing=$((missing + 1)); }
done
[ "$missing" = 0 ] || exit 1
echo "C API reference: $out/html/index.html, $(wc -w <<<"$declared") functions, 0 undocumented items;" \
    "the API conventions page with $(wc -w <<<"$sized") structures in its struct_size table"
[ "$check" = 1 ] || exit 0

# What a reader's browser shows.
shots="$out/screenshots"
mkdir -p "$shots"
chrome=(chromium --headless --no-sandbox --disable-gpu --disable-dev-shm-usage --hide-scrollbars)
dom() { "${chrome[@]}" --dump-dom "file://$1" 2>/dev/null; }
index_dom=$(dom "$out/html/index.html")
for want in "opccomn C and C++ API reference" "OpcCommonCreate" "MatchPatternW" "IOPCCommon" "OpcExeServerRun" "API conventions"; do
    grep -qF "$want" <<<"$index_dom" || { echo "docs.sh: the index, as Chromium renders it, does not show '$want'" >&2; exit 1; }
done
page_dom=$(dom "$page")
for f in $declared; do
    grep -qF ">$f</a>" <<<"$page_dom" || { echo "docs.sh: the header's page, as Chromium renders it, does not list $f" >&2; exit 1; }
done
for want in "one client session with its own locale" "Safety" "Functions" "Macros"; do
    grep -qF "$want" <<<"$page_dom" || { echo "docs.sh: the header's page, as Chromium renders it, does not show '$want'" >&2; exit 1; }
done
conventions_dom=$(dom "$conventions")
for want in "API conventions" "struct_size" "OpcServerRegistration" "OpcExeServerOptions"; do
    grep -qF "$want" <<<"$conventions_dom" || { echo "docs.sh: the API conventions page, as Chromium renders it, does not show '$want'" >&2; exit 1; }
done
"${chrome[@]}" --window-size=1280,1600 --screenshot="$shots/index.png" "file://$out/html/index.html" >/dev/null 2>&1
"${chrome[@]}" --window-size=1280,1600 --screenshot="$shots/api_conventions.png" "file://$conventions" >/dev/null 2>&1
"${chrome[@]}" --window-size=1280,1600 --screenshot="$shots/opccomn_h.png" "file://$page" >/dev/null 2>&1
[ -s "$shots/index.png" ] && [ -s "$shots/opccomn_h.png" ] && [ -s "$shots/api_conventions.png" ] ||
    { echo "docs.sh: Chromium made no screenshot" >&2; exit 1; }
echo "Chromium renders the index, the header's page with every function and the API conventions: screenshots in $shots"
