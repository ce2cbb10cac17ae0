#!/usr/bin/env python3
"""Compares the NDR tables of two proxy files, procedure by procedure and parameter by parameter.

    python3 tools/compare-ndr.py REFERENCE_p.c src/proxy/generated/opcda_p_win64.c
    python3 tools/compare-ndr.py --ignore-offsets src/proxy/generated/opcda_p_win64.c \
        src/proxy/generated/opcda_p_win32.c      # the two architectures: the same wire (stage lint)

REFERENCE is a proxy file MIDL generated for the same interfaces (/Oicf), for the same
architecture: the OPC Foundation's proxy/stub sources and many projects that built them carry one
(docs/dev/proxy-tables.md names those the tables here were compared with); the second file is
widl's, as tools/gen-proxy.py corrects it. No MIDL output is kept in this repository.

Each parameter of each method (found through the interfaces' FormatStringOffsetTable) is decoded
into a description of what goes on the wire: direction, stack offset, and the type tree (pointer
kinds, strings, structures as their members, arrays with their conformance and variance, interface
pointers with their IID or iid_is, user-marshalled types by their routines). The descriptions must
be equal. The differences that do not change the wire are normalised before comparing, and
--strict shows them:

- FC_OP and FC_UP (MIDL writes object pointers for the embedded pointers of object interfaces,
  widl unique pointers: both are a referent identifier and the deferred pointee);
- FC_CARRAY / FC_CVARRAY and FC_BOGUS_ARRAY with the same conformance and variance (the same
  counts before the same elements);
- FC_LONG, FC_ULONG, FC_ENUM32 and FC_ERROR_STATUS_T (four bytes), FC_SHORT / FC_USHORT / FC_WCHAR,
  FC_BYTE / FC_CHAR / FC_SMALL / FC_USMALL; flags that guide allocation and freeing (must size,
  must free, the server's allocation size) and the buffer size hints; MIDL's robust correlation
  flags.

With --ignore-offsets the stack offsets and the offsets of correlations (which differ between
architectures) are left out: the Win64 and Win32 tables generated from one IDL file must then
describe the same wire, and a pointer layout that counts a nested structure's array by a field
outside that structure (a widl defect on Win32, tools/gen-proxy.py rule 4) shows as a difference.

Interfaces present in one file only (MIDL's output of the Foundation's IDL includes its category
identifiers as empty interfaces) are listed and do not count as differences. Exit status 1 when a
parameter differs.
"""
import argparse
import re
import sys

SIMPLE = {
    0x01: "1", 0x02: "1", 0x03: "1", 0x04: "1", 0x05: "2", 0x06: "2", 0x07: "2", 0x08: "4",
    0x09: "4", 0x0A: "float", 0x0B: "8", 0x0C: "double", 0x0D: "enum16", 0x0E: "4", 0x10: "4",
    0xB8: "int3264", 0xB9: "int3264",
}
POINTERS = {0x11: "RP", 0x12: "UP", 0x13: "OP", 0x14: "FP"}
FLAGS = ((0x8, "in"), (0x10, "out"), (0x20, "return"), (0x40, "base"), (0x80, "by value"), (0x100, "simple ref"))


def strip_comments(text):
    return re.sub(r"//[^\n]*", " ", re.sub(r"/\*.*?\*/", " ", text, flags=re.S))


def to_bytes(body):
    out = bytearray()
    for m in re.finditer(r"NdrFcShort\(\s*(0x[0-9a-fA-F]+|\d+)\s*\)|NdrFcLong\(\s*(0x[0-9a-fA-F]+|\d+)\s*\)"
                         r"|(0x[0-9a-fA-F]+|\b\d+\b)", body):
        if m.group(1):
            out += (int(m.group(1), 0) & 0xFFFF).to_bytes(2, "little")
        elif m.group(2):
            out += (int(m.group(2), 0) & 0xFFFFFFFF).to_bytes(4, "little")
        else:
            out.append(int(m.group(3), 0) & 0xFF)
    return bytes(out)


def format_string(text, kind):
    m = re.search(r"_MIDL_%sFormatString\s*=\s*\{\s*0\s*,\s*\{(.*?)\}\s*\}\s*;" % kind, text, re.S)
    if not m:
        sys.exit("compare-ndr: no %s format string" % kind)
    return to_bytes(strip_comments(m.group(1)))


def offset_tables(text):
    tables = {}
    for m in re.finditer(r"(\w+)_FormatStringOffsetTable\[\]\s*=\s*\{(.*?)\}", text, re.S):
        values = [v.replace("(unsigned short)", "").strip() for v in strip_comments(m.group(2)).split(",")]
        tables[m.group(1)] = [int(v, 0) & 0xFFFF for v in values if v]
    return tables


def user_marshal_routines(text):
    m = re.search(r"UserMarshalRoutines\[[^\]]*\]\s*=\s*\{(.*?)\n\s*\};", text, re.S)
    return re.findall(r"(\w+)_UserSize", m.group(1)) if m else []


class Types:
    """Decodes the type format string into wire descriptions."""

    def __init__(self, data, routines, correlation_size, strict, pointer_size):
        self.t = data
        self.pointer_size = pointer_size
        self.routines = routines
        self.corr_size = correlation_size  # 4, or 6 with MIDL's robust correlation flags
        self.strict = strict

    def s16(self, o):
        return int.from_bytes(self.t[o:o + 2], "little", signed=True)

    def u16(self, o):
        return int.from_bytes(self.t[o:o + 2], "little")

    def simple(self, code):
        return ("FC%02x" % code) if self.strict else SIMPLE.get(code, "?%02x" % code)

    def pointer_kind(self, code):
        kind = POINTERS[code]
        return "UP" if kind == "OP" and not self.strict else kind

    def correlation(self, o):
        kind, op, offset = self.t[o], self.t[o + 1], self.s16(o + 2)
        if kind == 0xFF and op == 0xFF:
            return "none", o + self.corr_size
        where = {0x00: "field", 0x10: "pointer field", 0x20: "param", 0x30: "constant"}.get(kind & 0xF0, "?")
        operator = {0x00: "", 0x54: "*", 0x59: "callback "}.get(op, "op%02x " % op)
        return "%s%s@%d" % (operator, where, offset), o + self.corr_size

    def variance(self, o):
        if self.u16(o) == 0xFFFF and self.u16(o + 2) == 0xFFFF:
            return "none", o + self.corr_size
        return self.correlation(o)

    def describe(self, o, depth=0):
        if depth > 16:
            return "..."
        c = self.t[o]
        if c in POINTERS:
            attributes = self.t[o + 1]
            name = self.pointer_kind(c)
            if c == 0x11:
                name += "".join(f for bit, f in ((0x04, "s"), (0x10, "d")) if attributes & bit)
            if attributes & 0x08:
                inner = self.t[o + 2]
                return "%s->%s" % (name, "WSTR" if inner == 0x25 else "CSTR" if inner == 0x22 else self.simple(inner))
            return "%s->%s" % (name, self.describe(o + 2 + self.s16(o + 2), depth + 1))
        if c in SIMPLE:
            return self.simple(c)
        if c == 0x25:
            return "WSTR"
        if c == 0x22:
            return "CSTR"
        if c == 0x2F:
            if self.t[o + 1] == 0x5A:
                return "IP{%s}" % self.t[o + 2:o + 18].hex()
            return "IP(iid_is %s)" % self.correlation(o + 2)[0]
        if c == 0xB4:
            index = self.u16(o + 2)
            return "USER(%s)" % (self.routines[index] if index < len(self.routines) else index)
        if c in (0x15, 0x16, 0x17, 0x18, 0x1A):
            return self.structure(o, depth)
        if c in (0x1B, 0x1C, 0x21):
            return self.array(o, depth)
        if c in (0x1D, 0x1E):
            size = self.u16(o + 2) if c == 0x1D else int.from_bytes(self.t[o + 2:o + 6], "little")
            return "FIXED[%d bytes]" % size
        return "?%02x" % c

    SIZES = {0x01: 1, 0x02: 1, 0x03: 1, 0x04: 1, 0x05: 2, 0x06: 2, 0x07: 2, 0x08: 4, 0x09: 4, 0x0A: 4, 0x0B: 8,
             0x0C: 8, 0x0D: 4, 0x0E: 4, 0x10: 4}

    def memory_size(self, o):
        """The memory size of the type at `o` (structures, user-marshalled types); 0 if unknown."""
        c = self.t[o]
        if c in (0x15, 0x16, 0x17, 0x18, 0x1A):
            return self.u16(o + 2)
        if c == 0xB4:
            return self.u16(o + 4)
        return self.SIZES.get(c, 0)

    def members(self, o, depth, pointers):
        """A member layout up to FC_END: [(memory offset, description)], and where it ends. FC_POINTER
        members take `pointers` in order; widl writes some pointers' descriptions in place."""
        out = []
        taken = offset = 0
        while True:
            c = self.t[o]
            if c == 0x5B:
                return out, o + 1
            if c == 0x5C:
                o += 1
            elif 0x37 <= c <= 0x39:  # FC_ALIGNM2, 4, 8
                align = {0x37: 2, 0x38: 4, 0x39: 8}[c]
                offset = (offset + align - 1) // align * align
                o += 1
            elif 0x3D <= c <= 0x43:  # FC_STRUCTPAD1 to 7
                offset += c - 0x3C
                o += 1
            elif c == 0x4C:
                target = o + 2 + self.s16(o + 2)
                out.append((offset, self.describe(target, depth + 1), self.memory_size(target)))
                offset += self.memory_size(target)
                o += 4
            elif c == 0x36:
                out.append((offset, pointers[taken] if taken < len(pointers) else "POINTER?", 0))
                taken += 1
                offset += 8 if self.pointer_size == 8 else 4
                o += 1
            elif c in POINTERS:
                out.append((offset, self.describe(o, depth + 1), 0))
                offset += self.pointer_size
                o += 4
            elif c == 0x4B:
                return out, o
            else:
                out.append((offset, self.simple(c), 0))
                offset += self.SIZES.get(c, 4)
                o += 1

    def pointer_layout(self, o, depth):
        """FC_PP ... FC_END: {memory offset: (description, the field offset its array's count is read
        at, or None)}, and where it ends."""
        o += 2
        found = {}
        while self.t[o] != 0x5B:
            kind = self.t[o]
            if kind == 0x46:  # FC_NO_REPEAT
                found[self.s16(o + 2)] = self.layout_pointer(o + 6, depth)
                o += 10
            elif kind in (0x47, 0x48):  # FC_FIXED_REPEAT, FC_VARIABLE_REPEAT
                o += 4 if kind == 0x47 else 2
                count = self.u16(o + 4)
                o += 6
                for _ in range(count):
                    found[self.s16(o)] = self.layout_pointer(o + 4, depth)
                    o += 8
            else:
                break
        return found, o + 1

    def layout_pointer(self, o, depth):
        field = None
        if self.t[o] in POINTERS and not self.t[o + 1] & 0x08:
            array = o + 2 + self.s16(o + 2)
            kind = self.t[array + 4]
            if self.t[array] in (0x1B, 0x1C, 0x21) and kind != 0xFF and kind & 0xF0 in (0x00, 0x10):
                field = self.s16(array + 6)
        return self.describe(o, depth + 1), field

    def structure(self, o, depth):
        c = self.t[o]
        if c == 0x15:
            return "S{%s}" % ",".join(m[1] for m in self.members(o + 4, depth, [])[0])
        if c in (0x16, 0x18):  # FC_PSTRUCT, FC_CPSTRUCT: members as plain longs, pointers in FC_PP
            start = o + 4 if c == 0x16 else o + 6
            pointers, end = self.pointer_layout(start, depth) if self.t[start] == 0x4B else ({}, start)
            members = self.members(end, depth, [])[0]
            text = self.flat_with_pointers(members, pointers)
            if c == 0x18:
                text += ",conformant=" + self.describe(o + 4 + self.s16(o + 4), depth + 1)
            return "S{%s}" % text
        if c == 0x17:
            members = ",".join(m[1] for m in self.members(o + 6, depth, [])[0])
            return "S{%s,conformant=%s}" % (members, self.describe(o + 4 + self.s16(o + 4), depth + 1))
        # FC_BOGUS_STRUCT: FC_POINTER members, their descriptions in the pointer layout.
        array, layout = self.s16(o + 4), self.s16(o + 6)
        count, p = 0, o + 8
        while self.t[p] != 0x5B:
            count += self.t[p] == 0x36
            p += 4 if self.t[p] == 0x4C else 1
        pointers = [self.describe(o + 6 + layout + 4 * i, depth + 1) for i in range(count)] if layout else []
        text = ",".join(m[1] for m in self.members(o + 8, depth, pointers)[0])
        if array:
            text += ",conformant=" + self.describe(o + 4 + array, depth + 1)
        return "S{%s}" % text

    @staticmethod
    def flat_with_pointers(members, pointers):
        """Members whose pointers a pointer layout describes by memory offset (x86 structures and
        arrays of pointers): each pointer in its member's place. A pointer inside a nested structure
        is that structure's (its own description shows it); the field its array is counted by must
        lie in that structure too, as the runtime reads it from the start of the outer one (else
        "COUNT OUTSIDE ITS STRUCTURE" marks it)."""
        out = []
        for offset, text, size in members:
            if offset in pointers:
                out.append(pointers[offset][0])
                continue
            for memory, (_, field) in pointers.items():
                if size and offset < memory < offset + size and field is not None and not offset <= field < offset + size:
                    text += "[COUNT OUTSIDE ITS STRUCTURE]"
            out.append(text)
        return ",".join(out)

    def array(self, o, depth):
        c = self.t[o]
        if c == 0x21:
            conformance, e = self.correlation(o + 4)
            variance, e = self.variance(e)
            element = self.t[e]
            if element == 0x4C:
                described = self.describe(e + 2 + self.s16(e + 2), depth + 1)
            elif element in POINTERS:
                described = self.describe(e, depth + 1)
            else:
                described = self.simple(element)
            kind = "BOGUS[n=%d]" % self.u16(o + 2)
        else:
            conformance, e = self.correlation(o + 4)
            variance = "none"
            if c == 0x1C:
                variance, e = self.correlation(e)
            pointers = {}
            if self.t[e] == 0x4B:
                pointers, e = self.pointer_layout(e, depth)
            if self.t[e] == 0x4C:
                # An array of structures: the pointer layout is the structure's, by element.
                element = e + 2 + self.s16(e + 2)
                described = self.describe(element, depth + 1)
                if self.t[element] in (0x15, 0x16):
                    start = element + 4
                    if self.t[element] == 0x16 and self.t[start] == 0x4B:
                        start = self.pointer_layout(start, depth)[1]
                    check = self.flat_with_pointers(self.members(start, depth, [])[0], pointers)
                    if "COUNT OUTSIDE" in check:
                        described += "[COUNT OUTSIDE ITS STRUCTURE]"
            else:
                described = self.flat_with_pointers(self.members(e, depth, [])[0], pointers)
            kind = "CARRAY" if c == 0x1B else "CVARRAY"
        if not self.strict:
            kind = "ARRAY"
        return "%s[size=%s,length=%s](%s)" % (kind, conformance, variance, described)


def procedures(text, strict):
    procs = format_string(text, "Proc")
    win64 = "defined(__RPC_WIN64__)" in text or "env=Win64" in text[:3000]  # widl's check, MIDL's banner
    types = Types(format_string(text, "Type"), user_marshal_routines(text),
                  6 if re.search(r"protocol\s*:.*robust", text[:3000]) else 4, strict, 8 if win64 else 4)
    found = {}
    for interface, offsets in offset_tables(text).items():
        for index, offset in enumerate(offsets):
            if offset == 0xFFFF:
                continue  # IUnknown's methods (MIDL writes -1)
            p = offset + 2 + (4 if procs[offset + 1] & 0x08 else 0)
            method = int.from_bytes(procs[p:p + 2], "little")
            stack = int.from_bytes(procs[p + 2:p + 4], "little")
            p += 8
            flags2, count = procs[p], procs[p + 1]
            p += 2
            if flags2 & 0x40:
                p += procs[p]  # the extension's size
            params = []
            for _ in range(count):
                flags = int.from_bytes(procs[p:p + 2], "little")
                where = int.from_bytes(procs[p + 2:p + 4], "little")
                names = [name for bit, name in FLAGS if flags & bit]
                if flags & 0x40:
                    described = types.simple(procs[p + 4])
                else:
                    described = types.describe(int.from_bytes(procs[p + 4:p + 6], "little"))
                    if flags & 0x100:
                        described = "RP(simple)->" + described
                params.append("%s, stack %d: %s" % (" ".join(names), where, described))
                p += 6
            found[(interface, index)] = (method, stack, params)
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("reference")
    parser.add_argument("other")
    parser.add_argument("--strict", action="store_true", help="do not normalise what does not change the wire")
    parser.add_argument("--ignore-offsets", action="store_true",
                        help="leave out stack and correlation offsets (to compare two architectures)")
    args = parser.parse_args()
    a = procedures(open(args.reference, errors="replace").read(), args.strict)
    b = procedures(open(args.other, errors="replace").read(), args.strict)
    differences = 0
    for interface in sorted({k[0] for k in a} ^ {k[0] for k in b}):
        print("only in %s: %s" % (args.reference if any(k[0] == interface for k in a) else args.other, interface))
    for key in sorted(set(a) & set(b)):
        (ma, sa, pa), (mb, sb, pb) = a[key], b[key]
        if (ma, len(pa)) != (mb, len(pb)) or (sa != sb and not args.ignore_offsets):
            differences += 1
            print("%s method %d: vtable slot %d/%d, stack %d/%d, %d/%d parameters"
                  % (key[0], key[1], ma, mb, sa, sb, len(pa), len(pb)))
        for i, (x, y) in enumerate(zip(pa, pb)):
            if args.ignore_offsets:
                x, y = (re.sub(r"@-?\d+", "@", re.sub(r"stack \d+", "stack", t)) for t in (x, y))
            if x != y:
                differences += 1
                print("%s method %d parameter %d:\n  %s\n  %s" % (key[0], key[1], i, x, y))
    print("compare-ndr: %d procedures in both, %d differences" % (len(set(a) & set(b)), differences))
    sys.exit(1 if differences else 0)


if __name__ == "__main__":
    main()
