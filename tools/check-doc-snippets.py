#!/usr/bin/env python3
"""Fails when a code snippet of the docs is no longer in the file it was taken from.

A snippet is a fenced code block directly after a line `<!-- snippet: PATH -->` (PATH relative to the
repository's root): its lines must appear, contiguous and unchanged, in PATH, a file ctest builds and
runs. Scans README.md and every Markdown file under docs/.

Usage: tools/check-doc-snippets.py
"""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
MARKER = re.compile(r"^<!-- snippet: (\S+) -->$")


def snippets(md):
    lines = md.read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        m = MARKER.match(line.strip())
        if not m:
            continue
        if i + 1 >= len(lines) or not lines[i + 1].startswith("```"):
            yield i + 1, m.group(1), None
            continue
        end = i + 2
        while end < len(lines) and not lines[end].startswith("```"):
            end += 1
        yield i + 1, m.group(1), lines[i + 2 : end]


def contains(haystack, block):
    n = len(block)
    return n > 0 and any(haystack[k : k + n] == block for k in range(len(haystack) - n + 1))


def main():
    failed = 0
    count = 0
    for md in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        for line, path, block in snippets(md):
            where = f"{md.relative_to(ROOT)}:{line}"
            source = ROOT / path
            if block is None:
                print(f"{where}: the snippet marker is not followed by a code block", file=sys.stderr)
                failed += 1
            elif not source.is_file():
                print(f"{where}: {path} does not exist", file=sys.stderr)
                failed += 1
            elif not contains(source.read_text(encoding="utf-8").splitlines(), block):
                print(f"{where}: the snippet is not in {path} as it is written there: copy it again", file=sys.stderr)
                failed += 1
            count += 1
    if failed:
        return 1
    print(f"{count} snippets of the docs are in the files ctest builds")
    return 0


if __name__ == "__main__":
    sys.exit(main())
