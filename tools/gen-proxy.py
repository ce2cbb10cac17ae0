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
strings that carry the [string] attribute (rules 1 to 3; MIDL's output for the same declarations,
compared parameter by parameter with tools/compare-ndr.py, shows where each must point), and a wrong
correlation for a nested structure's array on Win32 (rule 4): docs/dev/proxy-tables.md.

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
4. On Win32 only, a structure nested in another (OPCBROWSEELEMENT's OPCITEMPROPERTIES): widl
   flattens the nested structure's pointers into the outer structure's pointer layout, and with them
   the array the nested structure counts by one of its fields (dwNumProperties), whose offset then
   still counts from the nested structure while the runtime reads it from the start of the outer
   one (a pointer's value is read as the count, and the stub faults; MIDL makes such structures
   FC_BOGUS_STRUCTs instead). The script points each such flattened pointer at a copy of the array
   that reads its count at the field's offset in the outer structure.

The script moves exactly those references (rules 1 and 2: an out or in-out parameter whose
server-allocated slot names the pointer under an adjacent FC_RP that leads to it; rule 3: a
reference that lands 4 bytes into an array; rule 4: copies appended to the type format string),
and checks afterwards that every parameter and every reference inside the type format string names
the start of a type, that every flattened pointer's array is counted by a field of the structure
that holds it, and that every out-parameter with a server-allocated slot that is not a simple
reference ("srv size=N" without "simple ref") names an `FC_RP`. With a widl that is already right
nothing is moved and the output is the same.

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


# ---- Rule 4: pointer layouts that flatten a nested structure's pointers ----

SIZES = {0x01: 1, 0x02: 1, 0x03: 1, 0x04: 1, 0x05: 2, 0x06: 2, 0x07: 2, 0x08: 4, 0x09: 4, 0x0A: 4, 0x0B: 8,
         0x0C: 8, 0x0D: 4, 0x0E: 4, 0x10: 4}


def pointer_layout(types, o):
    """The FC_PP pointer layout at `o`: [(memory offset, offset of the pointer's description)] and
    where it ends."""
    entries = []
    d = types.data
    o += 2
    while d[o] != 0x5B:
        if d[o] == 0x46:  # FC_NO_REPEAT, FC_PAD, memory offset, buffer offset, pointer
            entries.append((types.s16(o + 2), o + 6))
            o += 10
        elif d[o] in (0x47, 0x48):  # FC_FIXED_REPEAT (+ iterations) / FC_VARIABLE_REPEAT
            o += 4 if d[o] == 0x47 else 2
            count = int.from_bytes(d[o + 4:o + 6], "little")
            o += 6
            for _ in range(count):
                entries.append((types.s16(o), o + 4))
                o += 8
        else:
            sys.exit("gen-proxy: unknown pointer layout entry 0x%02x at type offset %d" % (d[o], o))
    return entries, o + 1


def struct_members(types, start):
    """The members of the FC_STRUCT / FC_PSTRUCT at `start`: [(memory offset, size, start of the
    embedded structure or None)]."""
    d = types.data
    o = start + 4
    if d[start] == 0x16 and d[o] == 0x4B:
        o = pointer_layout(types, o)[1]
    members, offset = [], 0
    while d[o] != 0x5B:
        c = d[o]
        if c == 0x5C:
            o += 1
        elif c in (0x37, 0x38, 0x39):  # FC_ALIGNM2, 4, 8
            align = {0x37: 2, 0x38: 4, 0x39: 8}[c]
            offset = (offset + align - 1) // align * align
            o += 1
        elif 0x3D <= c <= 0x43:  # FC_STRUCTPAD1 to 7
            offset += c - 0x3C
            o += 1
        elif c == 0x4C:
            target = o + 2 + types.s16(o + 2)
            if d[target] not in (0x15, 0x16):
                return None  # not a layout this rule reads
            size = int.from_bytes(d[target + 2:target + 4], "little")
            members.append((offset, size, target))
            offset += size
            o += 4
        else:
            size = SIZES.get(c, 4)
            members.append((offset, size, None))
            offset += size
            o += 1
    return members


def flattened_pointers(types):
    """Every pointer of a pointer layout that lands inside a nested structure, with an array as
    pointee whose count is a field: (offset of the pointer's description, the array, the field's
    offset, the nested structure's offset B and size)."""
    d = types.data
    for start in sorted(types.starts):
        if d[start] == 0x16 and d[start + 4] == 0x4B:  # FC_PSTRUCT with a pointer layout
            entries = pointer_layout(types, start + 4)[0]
            struct = start
        elif d[start] == 0x1B and d[start + 8] == 0x4B:  # FC_CARRAY with a pointer layout
            entries, end = pointer_layout(types, start + 8)
            if d[end] != 0x4C:
                continue  # an array of pointers: no structure
            struct = end + 2 + types.s16(end + 2)
            if d[struct] not in (0x15, 0x16):
                continue
        else:
            continue
        members = struct_members(types, struct)
        if members is None:
            continue
        for memory, pointer in entries:
            if d[pointer] not in POINTERS or d[pointer + 1] & 0x08:
                continue
            array = pointer + 2 + types.s16(pointer + 2)
            if d[array] not in ARRAYS or d[array + 4] == 0xFF or d[array + 4] & 0xF0 not in (0x00, 0x10):
                continue
            field = types.s16(array + 6)
            for offset, size, nested in members:
                if nested is not None and offset <= memory < offset + size:
                    yield pointer, array, field, offset, size


def copy_array(types, array, field):
    """A copy of the FC_BOGUS_ARRAY at `array` with its count read at field offset `field`, as the
    lines of a type format string placed at offset `at` (a function of `at`), and its size."""
    d = types.data
    if d[array] != 0x21:
        sys.exit("gen-proxy: rule 4 copies FC_BOGUS_ARRAY only, not 0x%02x at %d" % (d[array], array))
    element = array + 12
    if d[element] == 0x4C or (d[element] in POINTERS and not d[element + 1] & 0x08):
        target = element + 2 + types.s16(element + 2)
    else:
        sys.exit("gen-proxy: rule 4 cannot copy the element of the array at %d" % array)
    end = element + 4
    while d[end] != 0x5B:
        end += 1

    def lines(at):
        out = [
            "/* %d (the array at %d, its count read at field offset %d) */" % (at, array, field),
            "        0x21,	/* FC_BOGUS_ARRAY */",
            "        0x%x,	/* %d */" % (d[array + 1], d[array + 1]),
            "        NdrFcShort(0x%x),	/* %d */" % (int.from_bytes(d[array + 2:array + 4], "little"),
                                                   int.from_bytes(d[array + 2:array + 4], "little")),
            "        0x%x,	/* Corr desc: field%s */" % (d[array + 4], " pointer" if d[array + 4] & 0x10 else ""),
            "        0x%x,	/* operator */" % d[array + 5],
            "        NdrFcShort(0x%x),	/* offset = %d */" % (field & 0xFFFF, field),
            "        NdrFcLong(0x%08x),	/* variance */" % int.from_bytes(d[array + 8:array + 12], "little"),
            "        0x%x, 0x%x," % (d[element], d[element + 1]),
            "        NdrFcShort(0x%x),	/* Offset= %d (%d) */" % ((target - (at + 14)) & 0xFFFF, target - (at + 14), target),
        ]
        out += ["        0x%x," % b for b in d[element + 4:end + 1]]
        return out

    return lines, end + 1 - array


def nest_conformance(text, name):
    """Rule 4; returns (text, number of pointers retargeted)."""
    lines = text.split("\n")
    types = TypeString(lines)
    copies = {}  # (array, field) -> offset of the copy
    appended = []
    size = len(types.data) - 1  # without the closing 0x0
    moved = 0
    for pointer, array, field, nested, nested_size in list(flattened_pointers(types)):
        if nested <= field < nested + nested_size:
            continue  # the count lies in the nested structure: right
        if not 0 <= field < nested_size:
            sys.exit("gen-proxy: %s: the array at %d counts a field outside its structure" % (name, array))
        key = (array, field + nested)
        if key not in copies:
            make, length = copy_array(types, array, field + nested)
            copies[key] = size
            appended += make(size)
            size += length
        i = next(i for i, o in types.offset_of.items() if o == pointer + 2)
        relative = copies[key] - (pointer + 2)
        lines[i], n = re.subn(
            r"NdrFcShort\(0x[0-9a-f]+\),(\s*)/\* Offset= -?\d+ \(\d+\) \*/",
            lambda m: "NdrFcShort(0x%x),%s/* Offset= %d (%d) */" % (relative & 0xFFFF, m.group(1), relative, copies[key]),
            lines[i],
        )
        if n != 1:
            sys.exit("gen-proxy: %s: cannot retarget the pointer at type offset %d" % (name, pointer))
        moved += 1
    if appended:
        end = max(types.offset_of) + 1  # the line after the closing 0x0's
        closing = end - 1
        if lines[closing].strip() != "0x0":
            sys.exit("gen-proxy: %s: the type format string does not end as expected" % name)
        lines[closing:closing] = appended
        text = "\n".join(lines)
        text, n = re.subn(r"#define TYPE_FORMAT_STRING_SIZE \d+", "#define TYPE_FORMAT_STRING_SIZE %d" % (size + 1), text)
        if n != 1:
            sys.exit("gen-proxy: %s: no TYPE_FORMAT_STRING_SIZE" % name)
        return text, moved
    return "\n".join(lines), moved


def correct(text, name):
    """Applies the four corrections; returns (text, number of references moved)."""
    text, moved = nest_conformance(text, name)
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
    """Every parameter and pointer names the start of a type; server-allocated out slots an FC_RP;
    every flattened pointer's count lies in its own nested structure."""
    types = TypeString(text.split("\n"))
    for pointer, array, field, nested, nested_size in flattened_pointers(types):
        if not nested <= field < nested + nested_size:
            sys.exit("gen-proxy: %s: the pointer at type offset %d counts its array at field offset %d, outside "
                     "the structure at %d that holds it" % (name, pointer, field, nested))
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
