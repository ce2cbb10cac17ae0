#!/usr/bin/env python3
"""Fails when a hand-written mention of the version no longer matches Cargo.toml.

The build derives the version everywhere it is compiled in (the header, the DLL's VERSIONINFO, the
checker, CMake, pkg-config, the package's name) from `version` in Cargo.toml. What people read is
written by hand and checked here, in every tracked file but the changelog (which is history):

- `find_package(opccomn X.Y` asks for the current MAJOR.MINOR (the package accepts only its own);
- `opccomn-<version>-windows` names the current whole version ("0.3.0-dev");
- `libopccomn.so.X.Y.Z` names the current numbers (the installed file);
- a line starting `opccomn-check <version>: ` (sample output) names the current whole version;
- the lock files of the workspaces that build the library as a path dependency (`fuzz/Cargo.lock`)
  name the current version (the fuzz stage builds with `--locked`, which refuses a stale one);
- the README's status: for a version in development ("0.3.0-dev") that main is the development of
  **0.3.0**, that it builds `0.3.0-dev`, and that the latest release is the newest version of
  CHANGELOG.md; for a release, "Version **0.3.0**".

Usage: tools/check-versions.py [ROOT]   (scripts/check-generated.sh runs it; exit 1 on a mismatch)
"""
import pathlib
import re
import subprocess
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parents[1])


def package_version():
    manifest = (root / "Cargo.toml").read_text()
    package = manifest.split("[package]", 1)[1].split("\n[", 1)[0]
    return re.search(r'^version = "([^"]+)"', package, re.M).group(1)


version = package_version()
m = re.fullmatch(r"(\d+)\.(\d+)\.(\d+)(?:-([0-9A-Za-z.-]+))?(?:\+.*)?", version)
if not m:
    sys.exit(f"check-versions: Cargo.toml's version {version!r} is not MAJOR.MINOR.PATCH[-PRERELEASE]")
numbers = ".".join(m.group(1, 2, 3))
minor = ".".join(m.group(1, 2))
prerelease = m.group(4)
full = numbers + (f"-{prerelease}" if prerelease else "")
changelog = (root / "CHANGELOG.md").read_text()
released = re.findall(r"^## (\d+\.\d+\.\d+) \(", changelog, re.M)
latest = released[0] if released else None

problems = []
# (pattern, expected value of its group, what it is)
rules = [
    (re.compile(r"find_package\(opccomn (\d+\.\d+)\b"), minor, "a find_package request"),
    (re.compile(r"opccomn-(\d+\.\d+\.\d+(?:-[0-9A-Za-z.]+)?)-windows"), full, "the Windows package's name"),
    (re.compile(r"libopccomn\.so\.(\d+\.\d+\.\d+)"), numbers, "the installed library's file name"),
    (re.compile(r"^opccomn-check (\S+): ", re.M), full, "opccomn-check's first line"),
]
files = subprocess.run(["git", "ls-files"], cwd=root, capture_output=True, text=True, check=True).stdout.split()
checked = 0
for name in files:
    if name == "CHANGELOG.md" or name.startswith(("docs/dev/figures/", "fuzz/seeds/", "tests/third-party/")):
        continue
    path = root / name
    try:
        text = path.read_text(encoding="utf-8")
    except (UnicodeDecodeError, IsADirectoryError, FileNotFoundError):
        continue
    for pattern, want, what in rules:
        for hit in pattern.finditer(text):
            checked += 1
            if hit.group(1) != want:
                line = text.count("\n", 0, hit.start()) + 1
                problems.append(f"{name}:{line}: {what} says {hit.group(1)}, Cargo.toml {want} ({version})")

for lock in ("fuzz/Cargo.lock",):
    text = (root / lock).read_text()
    hit = re.search(r'^name = "opccomn"\nversion = "([^"]+)"', text, re.M)
    checked += 1
    if not hit or hit.group(1) != version:
        problems.append(f"{lock}: opccomn is {hit.group(1) if hit else 'missing'}, Cargo.toml {version} "
                        f"(run `cargo update -w --offline` in {lock.rsplit('/', 1)[0]})")

readme = (root / "README.md").read_text()
if prerelease:
    wants = [f"the development of the next version, **{numbers}**", f"`{full}`"]
    if latest:
        wants.append(f"The latest release is **{latest}**")
    for want in wants:
        if want not in readme:
            problems.append(f"README.md: the status does not say '{want}' (Cargo.toml {version}, "
                            f"CHANGELOG.md's latest release {latest})")
    if latest == numbers:
        problems.append(f"Cargo.toml says {version}, a version in development, but CHANGELOG.md has released {numbers}")
elif f"Version **{numbers}**" not in readme:
    problems.append(f"README.md: the status does not say 'Version **{numbers}**' (Cargo.toml {version})")

if problems:
    print("\n".join(problems), file=sys.stderr)
    sys.exit(f"check-versions: {len(problems)} mention(s) of the version differ from Cargo.toml ({version})")
print(f"version mentions match Cargo.toml ({version}): {checked} in the tracked files, the README's status")
