#!/usr/bin/env python3
"""Validates one opccomn-check report and checks which checks failed.

Usage: check_report.py FORMAT REPORT EXIT_CODE [EXPECTED_FAILED_CHECK [EXPECTED_WARNING]]

FORMAT is json, junit or text. The report must parse (JSON: json.load; JUnit: an XML parser, with
the structure JUnit consumers read), list every check once with a section of the specification, and
name the checker's version as Cargo.toml has it (JSON and text: "0.3.0-dev" for a version in
development, never only its numbers), its failed checks must be exactly EXPECTED_FAILED_CHECK (none when it is absent or "-"), and its
warnings exactly EXPECTED_WARNING (likewise). EXIT_CODE is the checker's: 1 when a check failed, 0
otherwise (warnings do not fail). Prints one line saying what was seen.
"""
import json
import pathlib
import re
import sys
import xml.etree.ElementTree as ET

fmt, path, code = sys.argv[1], sys.argv[2], int(sys.argv[3])
want = [] if len(sys.argv) < 5 or sys.argv[4] == "-" else [sys.argv[4]]
want_warn = [] if len(sys.argv) < 6 or sys.argv[5] == "-" else [sys.argv[5]]
text = open(path, encoding="utf-8").read()


def fail(msg):
    print(f"check_report: {path}: {msg}", file=sys.stderr)
    sys.exit(1)


def package_version():
    """The version of Cargo.toml's [package] table."""
    manifest = (pathlib.Path(__file__).resolve().parents[2] / "Cargo.toml").read_text()
    package = manifest.split("[package]", 1)[1].split("\n[", 1)[0]
    return re.search(r'^version = "([^"]+)"', package, re.M).group(1)


version = package_version()


if fmt == "json":
    report = json.loads(text)
    if report.get("version") != version:
        fail(f"version {report.get('version')!r}, expected {version!r} (Cargo.toml)")
    checks = report["checks"]
    ids = [c["id"] for c in checks]
    failed = [c["id"] for c in checks if c["status"] == "failed"]
    warned = [c["id"] for c in checks if c["status"] == "warning"]
    for c in checks:
        if c["status"] not in ("passed", "failed", "warning", "not applicable", "not run"):
            fail(f"{c['id']}: status {c['status']!r}")
        if not re.match(r"^[0-9]", c["section"]):
            fail(f"{c['id']}: no section of the specification: {c['section']!r}")
        if c["status"] == "failed" and not (c.get("expected") and c.get("got")):
            fail(f"{c['id']}: failed without expected/got")
    summary = report["summary"]
    if summary["failed"] != len(failed) or sum(summary.values()) != len(checks):
        fail(f"summary {summary} does not match the {len(checks)} checks")
elif fmt == "junit":
    root = ET.fromstring(text)
    if root.tag != "testsuites":
        fail(f"root element {root.tag}")
    suites = root.findall("testsuite")
    if len(suites) != 1:
        fail(f"{len(suites)} testsuite elements")
    cases = suites[0].findall("testcase")
    ids = [c.get("name").split(" ")[0] for c in cases]
    failed = [c.get("name").split(" ")[0] for c in cases if c.find("failure") is not None]
    warned = [c.get("name").split(" ")[0] for c in cases
              if c.find("system-out") is not None and (c.find("system-out").text or "").startswith("warning:")]
    if int(suites[0].get("tests")) != len(cases) or int(suites[0].get("failures")) != len(failed):
        fail("testsuite counts do not match its testcases")
    for c in cases:
        if not re.search(r"\([0-9][0-9., ]*\)$", c.get("name")):
            fail(f"testcase {c.get('name')!r} names no section")
else:
    lines = text.splitlines()
    if not lines or not lines[0].startswith(f"opccomn-check {version}: "):
        fail(f"first line {lines[0] if lines else ''!r}, expected 'opccomn-check {version}: ...' (Cargo.toml)")
    rows = [re.match(r"^(PASS|FAIL|WARN|N/A |SKIP)  ([0-9][0-9., ]*?) +([a-z][a-z0-9.-]*) ", l) for l in lines[1:-1]]
    if not all(rows):
        fail("a check line without a status, a section and a check name")
    ids = [m.group(3) for m in rows]
    failed = [m.group(3) for m in rows if m.group(1) == "FAIL"]
    warned = [m.group(3) for m in rows if m.group(1) == "WARN"]
    if not lines or not re.match(r"^summary: \d+ passed, \d+ failed", lines[-1]):
        fail("no summary line")

if len(ids) != len(set(ids)) or not ids:
    fail(f"checks listed {len(ids)} times, {len(set(ids))} distinct")
if sorted(failed) != sorted(want):
    fail(f"failed checks {failed}, expected {want or 'none'}")
if sorted(warned) != sorted(want_warn):
    fail(f"warnings {warned}, expected {want_warn or 'none'}")
if code != (1 if want else 0):
    fail(f"exit code {code}, expected {1 if want else 0}")
print(f"{path}: {fmt} valid, {len(ids)} checks, failed: {', '.join(failed) or 'none'}, "
      f"warnings: {', '.join(warned) or 'none'} (exit {code})")
