#!/usr/bin/env python3
"""Generates the proxy/stub code of the OPC interfaces from idl/*.idl with widl, and corrects the
known widl 7/8 defects in it.

    python3 tools/gen-proxy.py            # rewrites src/proxy/generated/
    python3 tools/gen-proxy.py --check    # CI: fails when the committed files differ from a fresh run
    python3 tools/gen-proxy.py --out DIR  # writes the files into DIR (the tests' independent copy)

The IDL files (IDLS below): idl/opccomn.idl (OPC Common: the tables opccomn.dll's proxy/stub
serves), idl/opcda.idl, idl/opc_ae.idl and idl/opchda.idl (Data Access, Alarms & Events, Historical
Data Access: generated and tested, not yet served by opccomn.dll). For each NAME, per architecture
(the NDR stack offsets differ): `NAME_p_win64.c` and `NAME_p_win32.c` (`widl -Oif`: format strings
interpreted by the system's RPC runtime, NdrClientCall2 / NdrStubCall2 / CStdStubBuffer, as MIDL's
/Oicf proxies are; the tables are named after NAME: NAME_ProxyFileInfo), and `NAME_idl.h`, the header
they include. widl is `x86_64-w64-mingw32-widl` from Debian 12's mingw-w64-tools (widl 7.0; 8.0 gives
the same output) or the program named by $WIDL; system IDL files come from libwine-dev
(/usr/include/wine/wine/windows, or $WIDL_INCLUDE).

The corrections. widl before 9.x writes a wrong type offset for pointers to strings and arrays of
strings that carry the [string] attribute (MIDL's output for the same declarations, compared
parameter by parameter with tools/compare-ndr.py, shows where each must point: docs/dev/proxy-tables.md):

1. `[out, string] LPWSTR *` and `[in, out, string] LPWSTR *` (GetErrorString's ppString,
   GetClassDetails' strings: LPOLESTR is `[string] OLECHAR *`; IOPCBrowse::Browse's
   pszContinuationPoint): widl names the inner unique string pointer (`FC_OP` -> `FC_C_WSTRING`)
   instead of the reference pointer in front of it (`FC_RP [allocated_on_stack] [pointer_deref]`,
   4 bytes earlier). The runtime then marshals the pointer slot as if it were the string, and the
   client receives NULL.
2. `[out, string, size_is(,n)] LPWSTR **` (IOPCItemProperties::LookupItemIDs, IOPCHDA_Server's
   names): widl names the array of strings instead of the `FC_RP` -> `FC_OP` in front of it
   (8 bytes earlier): the reply's pointer levels are read as array data.
3. `[in, string, size_is(n)] LPWSTR *` parameters (IOPCBrowse::GetProperties, IOPCEventServer2) and
   `[string, size_is(n)] LPWSTR *` structure members (OPCHDA_ANNOTATION): widl points 4 bytes into
   the array that describes them (`FC_BOGUS_ARRAY`; on x86 `FC_CARRAY` with a pointer layout), at
   its conformance descriptor, which the runtime then reads as a type (the call fails or misreads
   the request).

The script moves exactly those references (rules 1 and 2: an out or in-out parameter whose
server-allocated slot names the pointer under an adjacent FC_RP that leads to it; rule 3: a
reference that lands 4 bytes into an array), and checks afterwards that every parameter and
every reference inside the type format string names the start of a type, and that every out-parameter with a server-allocated slot
that is not a simple reference ("srv size=N" without "simple ref") names an `FC_RP`. With a widl
that is already right nothing is moved and the output is the same.

The first line of each file (widl's version banner) is normalised so that widl 7.0 and 8.0 produce the
same committed text.
"""
import argparse
import difflib
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
OUT = os.path.join(ROOT, "src", "proxy", "generated")
IDLS = ("opccomn", "opcda", "opc_ae", "opchda")
ARCHES = ("win64", "win32")


def outputs(name):
    """The files generated from idl/NAME.idl: the header first."""
    return ["%s_idl.h" % name] + ["%s_p_%s.c" % (name, arch) for arch in ARCHES]


def widl(args, cwd):
    program = os.environ.get("WIDL", "x86_64-w64-mingw32-widl")
    include = os.environ.get("WIDL_INCLUDE", "/usr/include/wine/wine/windows")
    command = [program, "-I" + include] + args
    try:
        subprocess.run(command, cwd=cwd, check=True)
    except FileNotFoundError:
        sys.exit("gen-proxy: %s not found (apt-get install mingw-w64-tools libwine-dev)" % program)


# ---- The type format string, line by line ----

BYTES = re.compile(r"NdrFcShort\((0x[0-9a-f]+)\)|NdrFcLong\((0x[0-9a-f]+)\)|\b(0x[0-9a-f]+)\b")
POINTERS = (0x11, 0x12, 0x13, 0x14)  # FC_RP, FC_UP, FC_OP, FC_FP
ARRAYS = (0x1B, 0x21)  # FC_CARRAY (x86: an array of pointers with a pointer layout), FC_BOGUS_ARRAY


class TypeString:
    """widl's __MIDL_TypeFormatString: its bytes, the offset of each line, and the offsets where a
    type starts (widl comments each one: `/* 36 (LPWSTR) */` or `/* 38 */`)."""

    def __init__(self, lines):
        self.lines = lines
        start = next(i for i, line in enumerate(lines) if "__MIDL_TypeFormatString =" in line)
        self.offset_of = {}  # line index -> offset of its first byte
        self.data = bytearray()
        self.starts = set()
        for i in range(start + 3, len(lines)):
            text = lines[i].strip()
            if text.startswith("}"):
                break
            m = re.match(r"/\*\s*(\d+)(?: \(.*\))? \*/$", text)
            if m:
                if int(m.group(1)) != len(self.data):
                    sys.exit("gen-proxy: type offset comment %s at byte %d" % (m.group(1), len(self.data)))
                self.starts.add(len(self.data))
                continue
            code = re.sub(r"/\*.*?\*/", "", text)
            self.offset_of[i] = len(self.data)
            for short, long_, byte in BYTES.findall(code):
                if short:
                    self.data += int(short, 16).to_bytes(2, "little")
                elif long_:
                    self.data += int(long_, 16).to_bytes(4, "little")
                else:
                    self.data.append(int(byte, 16))

    def s16(self, offset):
        return int.from_bytes(self.data[offset:offset + 2], "little", signed=True)

    def references(self):
        """(line index, offset of the field, target) of every relative offset to a type: each line
        `NdrFcShort(..), /* Offset= N (T) */` (pointers, pointer layouts, embedded types, a structure's
        array and pointer layout), and the pointers at the start of a type that widl leaves uncommented."""
        seen = set()
        for i, offset in self.offset_of.items():
            if re.search(r"/\* Offset= -?\d+ \(\d+\) \*/", self.lines[i]):
                seen.add(offset)
                if self.s16(offset):  # 0: none (a structure without a pointer layout)
                    yield i, offset, offset + self.s16(offset)
        for start in sorted(self.starts):
            if start + 4 <= len(self.data) and self.data[start] in POINTERS and not self.data[start + 1] & 0x08:
                if start + 2 not in seen:
                    i = next(i for i, o in self.offset_of.items() if o == start + 2)
                    yield i, start + 2, start + 2 + self.s16(start + 2)

    def pointee(self, offset):
        """The target of the pointer that starts at `offset`, or None."""
        if offset in self.starts and self.data[offset] in POINTERS and not self.data[offset + 1] & 0x08:
            return offset + 2 + self.s16(offset + 2)
        return None


def inside_array(types, target):
    """The start of the array `target` points 4 bytes into (rule 3), or None."""
    if target not in types.starts and target - 4 in types.starts and types.data[target - 4] in ARRAYS:
        return target - 4
    return None


PARAM = re.compile(
    r"(/\* \d+ \(parameter (\w+)\) \*/\n"
    r"\s*NdrFcShort\(0x[0-9a-f]+\),\t/\* flags: ([^*]*?) \*/\n"
    r"\s*NdrFcShort\(0x[0-9a-f]+\),\t/\* stack offset = \d+ \*/\n"
    r"\s*)NdrFcShort\(0x([0-9a-f]+)\),\t/\* type offset = (\d+) \*/"
)


def server_allocated(flags):
    """An out or in-out parameter whose slot the stub allocates and which is not a simple reference."""
    return "out" in flags.split(", ") and "srv size=" in flags and "simple ref" not in flags


def correct(text, name):
    """Applies the three corrections; returns (text, number of references moved)."""
    moved = 0
    # Rule 3 in the type format string: pointers that land inside an array.
    lines = text.split("\n")
    types = TypeString(lines)
    for i, field, target in list(types.references()):
        array = inside_array(types, target)
        if array is None:
            continue
        relative = array - field
        lines[i], n = re.subn(
            r"NdrFcShort\(0x[0-9a-f]+\),(\s*)/\* Offset= -?\d+ \(\d+\) \*/",
            lambda m: "NdrFcShort(0x%x),%s/* Offset= %d (%d) */" % (relative & 0xFFFF, m.group(1), relative, array),
            lines[i],
        )
        if n != 1:
            sys.exit("gen-proxy: %s: cannot correct the reference at type offset %d" % (name, field))
        moved += 1
    text = "\n".join(lines)
    types = TypeString(text.split("\n"))

    # Rules 1, 2 and 3 in the parameters.
    def fix(m):
        nonlocal moved
        flags = m.group(3)
        offset = int(m.group(5))
        new = offset
        if server_allocated(flags) and types.data[offset] != 0x11:
            for up in (4, 8):
                ref = offset - up
                if ref in types.starts and types.data[ref] == 0x11:
                    chain = [types.pointee(ref)]
                    if up == 8 and chain[0] is not None:
                        chain.append(types.pointee(chain[0]))
                    if chain[-1] == offset:
                        new = ref
                        break
        array = inside_array(types, offset)
        if array is not None:
            new = array
        if new != offset:
            moved += 1
        return "%sNdrFcShort(0x%x),\t/* type offset = %d */" % (m.group(1), new, new)

    text = PARAM.sub(fix, text)
    verify(text, name)
    return text, moved


def verify(text, name):
    """Every parameter and pointer names the start of a type; server-allocated out slots an FC_RP."""
    types = TypeString(text.split("\n"))
    for _, field, target in types.references():
        if target not in types.starts:
            sys.exit("gen-proxy: %s: the reference at type offset %d names %d, not a type" % (name, field, target))
    for m in PARAM.finditer(text):
        param, flags, offset = m.group(2), m.group(3), int(m.group(5))
        if offset not in types.starts:
            sys.exit("gen-proxy: %s: parameter %s names type offset %d, not a type" % (name, param, offset))
        if server_allocated(flags) and types.data[offset] != 0x11:
            sys.exit("gen-proxy: %s: parameter %s (type offset %d) is not an FC_RP after correction"
                     % (name, param, offset))


def normalise(text, name):
    lines = text.split("\n")
    if lines and lines[0].startswith("/*** Autogenerated by WIDL"):
        lines[0] = "/*** Autogenerated by WIDL from idl/%s.idl by tools/gen-proxy.py - Do not edit ***/" % name
    return "\n".join(lines)


def generate():
    work = tempfile.mkdtemp(prefix="gen-proxy-")
    results = {}
    try:
        for name in IDLS:
            idl = "idl/%s.idl" % name
            header = outputs(name)[0]
            widl(["-h", "-o", os.path.join(work, header), idl], ROOT)
            results[header] = normalise(open(os.path.join(work, header)).read(), name)
            for arch in ARCHES:
                # widl names the tables after the output file: NAME_ProxyFileInfo for both.
                path = os.path.join(work, arch, "%s_p.c" % name)
                os.makedirs(os.path.dirname(path), exist_ok=True)
                widl(["-Oif", "--" + arch, "-p", "-H", header, "-o", path, idl], ROOT)
                out = "%s_p_%s.c" % (name, arch)
                text, moved = correct(normalise(open(path).read(), name), out)
                results[out] = text
                print("gen-proxy: %s: %d type references corrected" % (out, moved), file=sys.stderr)
        return results
    finally:
        shutil.rmtree(work)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="compare with the committed files")
    parser.add_argument("--out", help="write into this directory instead of src/proxy/generated")
    args = parser.parse_args()
    results = generate()
    if args.check:
        stale = []
        for name, text in results.items():
            path = os.path.join(OUT, name)
            old = open(path).read() if os.path.exists(path) else ""
            if old != text:
                stale.append(name)
                sys.stderr.writelines(difflib.unified_diff(
                    old.splitlines(True), text.splitlines(True), path, "widl " + name, n=1))
        if stale:
            sys.exit("gen-proxy: %s out of date: run python3 tools/gen-proxy.py" % ", ".join(stale))
        print("gen-proxy: src/proxy/generated matches idl/%s" % ", idl/".join(n + ".idl" for n in IDLS),
              file=sys.stderr)
        return
    out_dir = args.out or OUT
    os.makedirs(out_dir, exist_ok=True)
    for name, text in results.items():
        with open(os.path.join(out_dir, name), "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
