#!/usr/bin/env bash
# Builds the C API reference (HTML) from include/opccomn/opccomn.h with Doxygen (docs/reference/Doxyfile)
# into build/docs/html: a page per area (docs/reference/areas.dox), each with its example, and
# docs/api-conventions.md as a page of it. Fails when anything in the header is undocumented: any
# Doxygen warning (an undocumented function, parameter, result, struct, field, enum value, macro,
# interface or interface method, a link that leads nowhere, an example's lines not found), a function
# the header declares that is not on exactly one area's page with its parameters and result, an area
# without its example, a function the search does not know, or a structure of the API conventions'
# struct_size table that the page does not show linked to its reference.
#
# With --check (CI) it also opens the reference in headless Chromium, as a reader would: the index,
# every area's page and the API conventions must render and show what they should (every function on
# its area's page with its documentation), the search box must find a function, and a screenshot of
# the index, one area and the conventions goes to build/docs/screenshots/.
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
html="$out/html"
page="$html/opccomn_8h.html"
# Every function the header declares: on the header's page, and documented on exactly one area's page,
# with its parameters and its result when it has them.
declared=$(grep -E '^[A-Za-z].* OPCCOMN_(CDECL|STDCALL) \*?[A-Za-z0-9_]+\(' include/opccomn/opccomn.h |
    sed -E 's/.* OPCCOMN_(CDECL|STDCALL) \*?([A-Za-z0-9_]+)\(.*/\2/' | sort -u)
areas=$(sed -nE 's/^ \* @defgroup ([a-z]+) .*/\1/p' docs/reference/areas.dox)
missing=0
for f in $declared; do
    grep -q ">$f</a> (" "$page" || { echo "docs.sh: $f is not on the header's page" >&2; missing=$((missing + 1)); }
    on=$(grep -l "</span>$f()</h2>" "$html"/group__*.html || true)
    if [ "$(wc -w <<<"$on")" != 1 ]; then
        echo "docs.sh: $f is documented on $(wc -w <<<"$on") area pages, not one" >&2
        missing=$((missing + 1))
        continue
    fi
    decl=$(grep -E " OPCCOMN_(CDECL|STDCALL) \*?$f\(" include/opccomn/opccomn.h)
    doc=$(awk -v f="</span>$f()</h2>" 'index($0, f) { on = 1 } on && /<h2 class="memtitle">/ && !index($0, f) { exit } on' "$on")
    if ! grep -qE "$f\(void\)" <<<"$decl" && ! grep -q '<dl class="params">' <<<"$doc"; then
        echo "docs.sh: $f's parameters are not shown on $(basename "$on")" >&2
        missing=$((missing + 1))
    fi
    if ! grep -qE "^void OPCCOMN" <<<"$decl" && ! grep -q '<dl class="section return">' <<<"$doc"; then
        echo "docs.sh: $f's result is not shown on $(basename "$on")" >&2
        missing=$((missing + 1))
    fi
done
# Every area has its page, with its example.
for a in $areas; do
    grep -q '<div class="fragment">' "$html/group__$a.html" 2>/dev/null ||
        { echo "docs.sh: the area $a has no page with an example" >&2; missing=$((missing + 1)); }
done
# The search knows every function.
for f in $declared; do
    grep -qF "['$f',[" "$html"/search/all_*.js || { echo "docs.sh: the search does not know $f" >&2; missing=$((missing + 1)); }
done
[ "$missing" = 0 ] || exit 1
# docs/api-conventions.md, rendered as Markdown: its struct_size table shows every structure, linked.
conventions="$html/api_conventions.html"
sized=$(sed -nE 's/^\| `(Opc[A-Za-z0-9]+)` \| .*/\1/p' docs/api-conventions.md)
[ -f "$conventions" ] && [ -n "$sized" ] || { echo "docs.sh: docs/api-conventions.md is not a page of the reference" >&2; exit 1; }
for s in $sized; do
    grep -qF "<td class=\"markdownTableBodyNone\"><code><a class=\"el\" href=\"struct$s.html\">$s</a></code>" "$conventions" ||
        { echo "docs.sh: the API conventions page does not show $s in its struct_size table" >&2; missing=$((missing + 1)); }
done
[ "$missing" = 0 ] || exit 1
echo "C API reference: $html/index.html, $(wc -w <<<"$declared") functions with their parameters and results on" \
    "$(wc -w <<<"$areas") area pages, each with its example, 0 undocumented items; the API conventions page with" \
    "$(wc -w <<<"$sized") structures in its struct_size table"
[ "$check" = 1 ] || exit 0

# What a reader's browser shows.
shots="$out/screenshots"
mkdir -p "$shots"
chrome=(chromium --headless --no-sandbox --disable-gpu --disable-dev-shm-usage --hide-scrollbars)
# The page once its scripts ran (the search box is placed when the page is ready).
dom() { "${chrome[@]}" --window-size=1280,1024 --virtual-time-budget=2000 --dump-dom "file://$1" 2>/dev/null; }
index_dom=$(dom "$html/index.html")
for want in "opccomn C and C++ API reference" "OpcCommonCreate" "MatchPatternW" "IOPCCommon" "OpcExeServerRun" \
    "Server plumbing" "DCOM security" "API conventions" "MSearchField"; do
    grep -qF "$want" <<<"$index_dom" || { echo "docs.sh: the index, as Chromium renders it, does not show '$want'" >&2; exit 1; }
done
for a in $areas; do
    area_dom=$(dom "$html/group__$a.html")
    for want in "Detailed Description" 'class="fragment"'; do
        grep -qF "$want" <<<"$area_dom" || { echo "docs.sh: the page of $a, as Chromium renders it, does not show '$want'" >&2; exit 1; }
    done
    for f in $declared; do
        grep -q "</span>$f()</h2>" "$html/group__$a.html" || continue
        grep -qF "$f()</h2>" <<<"$area_dom" || { echo "docs.sh: the page of $a, as Chromium renders it, does not show $f" >&2; exit 1; }
    done
done
# The search box's results page finds a function and links its area's page.
letters=$(sed -nE 's/^ *0: "([a-z0-9_]+)",?$/\1/p' "$html/search/searchdata.js")
for f in OpcShutdownNotifyBounded MatchPatternW; do
    first=$(tr 'A-Z' 'a-z' <<<"${f:0:1}")
    n=$(awk -v s="$letters" -v c="$first" 'BEGIN { printf "%x", index(s, c) - 1 }')
    lower=$(tr 'A-Z' 'a-z' <<<"$f")
    found=$(dom "$html/search/all_$n.html?$lower" | grep -o 'style="display: block;"[^>]*><div class="SREntry"[^>]*><a [^>]*href="[^"]*"[^>]*>'"$f"'</a>' || true)
    grep -q 'href="../group__' <<<"$found" ||
        { echo "docs.sh: the search, as Chromium runs it, does not find $f on an area's page" >&2; exit 1; }
done
conventions_dom=$(dom "$conventions")
for want in "API conventions" "struct_size" "OpcServerRegistration" "OpcExeServerOptions" "Names"; do
    grep -qF "$want" <<<"$conventions_dom" || { echo "docs.sh: the API conventions page, as Chromium renders it, does not show '$want'" >&2; exit 1; }
done
"${chrome[@]}" --window-size=1280,1600 --screenshot="$shots/index.png" "file://$html/index.html" >/dev/null 2>&1
"${chrome[@]}" --window-size=1280,1600 --screenshot="$shots/api_conventions.png" "file://$conventions" >/dev/null 2>&1
"${chrome[@]}" --window-size=1280,2400 --screenshot="$shots/shutdown.png" "file://$html/group__shutdown.html" >/dev/null 2>&1
[ -s "$shots/index.png" ] && [ -s "$shots/shutdown.png" ] && [ -s "$shots/api_conventions.png" ] ||
    { echo "docs.sh: Chromium made no screenshot" >&2; exit 1; }
echo "Chromium renders the index, the $(wc -w <<<"$areas") area pages with every function, the search and the API" \
    "conventions: screenshots in $shots"
