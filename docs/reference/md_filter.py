#!/usr/bin/env python3
"""Doxygen's input filter for the Markdown pages of the C API reference (docs/reference/Doxyfile,
FILTER_PATTERNS): docs/api-conventions.md becomes the page `api_conventions`, its sections get labels
(a link `(#name)` within it, as GitHub resolves it, becomes a link to the section), its links to
other pages of docs/, which the reference does not contain, become their paths in the sources, and a
function of the header named in backticks (`OpcTaskMemFree`) gets the `()` with which Doxygen links
it. Other files pass unchanged.

Usage (by Doxygen): md_filter.py FILE
"""
import pathlib
import re
import sys

PAGE = "api_conventions"
HEADER = pathlib.Path(__file__).resolve().parent.parent.parent / "include" / "opccomn" / "opccomn.h"


def functions():
    """The functions the header declares."""
    text = HEADER.read_text(encoding="utf-8")
    return set(re.findall(r"^[A-Za-z].* OPCCOMN_(?:CDECL|STDCALL) \*?([A-Za-z0-9_]+)\(", text, re.M))


def slug(heading):
    """The anchor GitHub gives a heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def label(anchor):
    return PAGE + "_" + re.sub(r"\W", "_", anchor)


def main():
    path = pathlib.Path(sys.argv[1])
    text = path.read_text(encoding="utf-8")
    if path.name != "api-conventions.md":
        sys.stdout.write(text)
        return
    declared = functions()
    out = []
    for line in text.splitlines():
        m = re.match(r"^(#+) (.*)$", line)
        if m and len(m.group(1)) == 1:
            line = f"{line} {{#{PAGE}}}"
        elif m:
            line = f"{line} {{#{label(slug(m.group(2)))}}}"
        # A link to a section of this page.
        line = re.sub(r"\]\(#([^)]+)\)", lambda l: f"](#{label(l.group(1))})", line)
        # A link to another page of docs/: its path in the sources.
        def outside(l):
            target = (path.parent / l.group(2).split("#")[0]).resolve()
            try:
                shown = target.relative_to(path.parent.parent.resolve()).as_posix()
            except ValueError:
                shown = l.group(2)
            name = l.group(1)
            return f"`{shown}`" if name.strip("`") in (l.group(2), shown) else f"{name} (`{shown}`)"
        line = re.sub(r"\[([^\]]+)\]\(([^)#:]+\.md(?:#[^)]*)?)\)", outside, line)
        # A function in backticks, linked as Doxygen links functions.
        line = re.sub(r"`([A-Za-z0-9_]+)`", lambda f: f"`{f.group(1)}()`" if f.group(1) in declared else f.group(0), line)
        out.append(line)
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
