#!/usr/bin/env python3
"""Writes stand-ins for the OPC Foundation's MIDL-generated headers and *_i.c files into OUT_DIR:
opccomn.h, opcda.h, opc_ae.h, opchda.h (+ their _i.c), opcerror.h, opcae_er.h, opchda_error.h.

They are not the Foundation's files (none of their text is here): widl, the only IDL compiler on
this machine, writes the declarations, from idl/opccomn.idl and from small IDL files made here that
declare the categories as the Foundation's IDL does; each header is then given the traits of MIDL's
output that a program including it beside opccomn/opccomn.h can see, and widl's own additions are
taken out. docs/header-coexistence.md lists the traits; check() asserts each one, so a stand-in that
lost a trait fails the coexistence stage instead of passing it for the wrong reason. widl's own
output, the headers and *_i.c as widl writes them, is left in OUT_DIR/widl: what mingw users who
compile the Foundation's IDL with widl include, which the stage tests as well (check() asserts its
trait: a __CRT_UUID_DECL for every interface).

Usage: midl_standins.py ROOT OUT_DIR WIDL_INCLUDE_DIR   (runs x86_64-w64-mingw32-widl)
"""
import pathlib
import re
import subprocess
import sys

# Which header declares which category, and in which form (facts about the Foundation's headers):
# (category macro, interface name). The header defines `#define <macro> IID_<interface>`.
CATEGORIES = {
    "opcda": [
        ("CATID_OPCDAServer10", "CATID_OPCDAServer10"),
        ("CATID_OPCDAServer20", "CATID_OPCDAServer20"),
        ("CATID_OPCDAServer30", "CATID_OPCDAServer30"),
        ("CATID_XMLDAServer10", "CATID_XMLDAServer10"),
    ],
    "opc_ae": [("CATID_OPCAEServer10", "OPCEventServerCATID")],
    "opchda": [("CATID_OPCHDAServer10", "CATID_OPCHDAServer10")],
}
# Each of the three also declares OPCHANDLE itself (the same typedef, repeated when two are included).

# The error headers (message-compiler output): guard, then name and HRESULT of each code of the
# specifications (the texts are not needed here).
ERRORS = {
    "opcerror.h": ("__OPCERROR_H", [
        ("OPC_E_INVALIDHANDLE", 0xC0040001), ("OPC_E_BADTYPE", 0xC0040004), ("OPC_E_PUBLIC", 0xC0040005),
        ("OPC_E_BADRIGHTS", 0xC0040006), ("OPC_E_UNKNOWNITEMID", 0xC0040007),
        ("OPC_E_INVALIDITEMID", 0xC0040008), ("OPC_E_INVALIDFILTER", 0xC0040009),
        ("OPC_E_UNKNOWNPATH", 0xC004000A), ("OPC_E_RANGE", 0xC004000B), ("OPC_E_DUPLICATENAME", 0xC004000C),
        ("OPC_S_UNSUPPORTEDRATE", 0x0004000D), ("OPC_S_CLAMP", 0x0004000E), ("OPC_S_INUSE", 0x0004000F),
        ("OPC_E_INVALIDCONFIGFILE", 0xC0040010), ("OPC_E_NOTFOUND", 0xC0040011),
        ("OPC_E_INVALID_PID", 0xC0040203), ("OPC_E_DEADBANDNOTSET", 0xC0040400),
        ("OPC_E_DEADBANDNOTSUPPORTED", 0xC0040401), ("OPC_E_NOBUFFERING", 0xC0040402),
        ("OPC_E_INVALIDCONTINUATIONPOINT", 0xC0040403), ("OPC_S_DATAQUEUEOVERFLOW", 0x00040404),
        ("OPC_E_RATENOTSET", 0xC0040405), ("OPC_E_NOTSUPPORTED", 0xC0040406),
    ]),
    "opcae_er.h": ("__OPCAE_ER_H", [
        ("OPC_S_ALREADYACKED", 0x00040200), ("OPC_S_INVALIDBUFFERTIME", 0x00040201),
        ("OPC_S_INVALIDMAXSIZE", 0x00040202), ("OPC_S_INVALIDKEEPALIVETIME", 0x00040203),
        ("OPC_E_INVALIDBRANCHNAME", 0xC0040203), ("OPC_E_INVALIDTIME", 0xC0040204),
        ("OPC_E_BUSY", 0xC0040205), ("OPC_E_NOINFO", 0xC0040206),
    ]),
    "opchda_error.h": ("__OPCHDA_ERROR_H", [
        ("OPC_E_MAXEXCEEDED", 0xC0041001), ("OPC_S_NODATA", 0x40041002), ("OPC_S_MOREDATA", 0x40041003),
        ("OPC_E_INVALIDAGGREGATE", 0xC0041004), ("OPC_S_CURRENTVALUE", 0x40041005),
        ("OPC_S_EXTRADATA", 0x40041006), ("OPC_W_NOFILTER", 0x80041007), ("OPC_E_UNKNOWNATTRID", 0xC0041008),
        ("OPC_E_NOT_AVAIL", 0xC0041009), ("OPC_E_INVALIDDATATYPE", 0xC004100A),
        ("OPC_E_DATAEXISTS", 0xC004100B), ("OPC_E_INVALIDATTRID", 0xC004100C),
        ("OPC_E_NODATAEXISTS", 0xC004100D), ("OPC_S_INSERTED", 0x4004100E), ("OPC_S_REPLACED", 0x4004100F),
    ]),
}


def guid_table(root):
    """Name -> GUID text, from idl/opcguids.txt."""
    table = {}
    for line in (root / "idl/opcguids.txt").read_text().splitlines():
        parts = line.split()
        if len(parts) >= 4 and not line.startswith("#"):
            table[parts[2]] = parts[3]
    return table


def guid_args(guid):
    """`0xF31DFDE2,0x07B6,0x11d2,0xB2,0xD8,...` as MIDL_DEFINE_GUID takes them."""
    g = guid.replace("-", "")
    return ",".join(["0x" + g[0:8], "0x" + g[8:12], "0x" + g[12:16]] +
                    ["0x" + g[16 + 2 * i:18 + 2 * i] for i in range(8)])


def midl_prologue(stem):
    """What MIDL 6.00 writes before the declarations: the warning pragma (unconditional, for every
    compiler), the rpcndr.h version check, the system headers, the include guard."""
    return (
        f"/* Stand-in for the OPC Foundation's MIDL-generated {stem}.h (see docs/header-coexistence.md). */\n\n"
        "#pragma warning( disable: 4049 )  /* more than 64k source lines */\n\n"
        "#ifndef __REQUIRED_RPCNDR_H_VERSION__\n#define __REQUIRED_RPCNDR_H_VERSION__ 440\n#endif\n\n"
        "#include \"rpc.h\"\n#include \"rpcndr.h\"\n\n"
        "#ifndef __RPCNDR_H_VERSION__\n#error this stub requires an updated version of <rpcndr.h>\n#endif\n\n"
        "#ifndef COM_NO_WINDOWS_H\n#include \"windows.h\"\n#include \"ole2.h\"\n#endif\n\n"
        f"#ifndef __{stem}_h__\n#define __{stem}_h__\n\n"
        "#if defined(_MSC_VER) && (_MSC_VER >= 1020)\n#pragma once\n#endif\n"
    )


def midl_form(widl_text, stem):
    """widl's header, turned into what MIDL's declares: no __CRT_UUID_DECL (MIDL has no __uuidof
    declaration for mingw), `EXTERN_C const IID IID_X;` instead of DEFINE_GUID, the COBJMACROS as
    plain macros (no widl inline wrappers), MIDL's prologue."""
    lines = widl_text.splitlines()
    # Drop widl's prologue (everything up to and including its include guard).
    start = lines.index(f"#define __{stem}_h__") + 1
    out = []
    skip_depth = 0
    in_wrappers = False
    i = start
    while i < len(lines):
        line = lines[i]
        if line == "#ifdef __CRT_UUID_DECL":
            # The three-line block: #ifdef, __CRT_UUID_DECL(...), #endif.
            assert lines[i + 1].startswith("__CRT_UUID_DECL(") and lines[i + 2] == "#endif", lines[i:i + 3]
            i += 3
            continue
        if line == "#ifndef WIDL_C_INLINE_WRAPPERS":
            in_wrappers = True
            i += 1
            continue
        if in_wrappers:
            if skip_depth == 0 and line == "#else":
                skip_depth = 1
            elif skip_depth:
                if line.startswith("#if"):
                    skip_depth += 1
                elif line == "#endif":
                    skip_depth -= 1
                    if skip_depth == 0:
                        in_wrappers = False
            else:
                m = re.match(r"#define (\w+)\(([^)]*)\) \(This\)->lpVtbl->(\w+)\((.*)\)$", line)
                out.append(f"#define {m.group(1)}({m.group(2)})\t\\\n    (This)->lpVtbl -> {m.group(3)}({m.group(4)})"
                           if m else line)
            i += 1
            continue
        m = re.match(r"DEFINE_GUID\((\w+), .*\);$", line)
        if m:
            kind = "CLSID" if m.group(1).startswith("CLSID_") else "IID"
            out.append(f"EXTERN_C const {kind} {m.group(1)};")
        else:
            out.append(line)
        i += 1
    return midl_prologue(stem) + "\n".join(out) + "\n"


def midl_i_c(stem, guids):
    """An _i.c file as MIDL 6.00 writes it: MIDL_DEFINE_GUID definitions, its own IID typedef when
    __IID_DEFINED__ is not defined, and the stray token after `#endif` MIDL puts there."""
    body = "".join(f"MIDL_DEFINE_GUID({kind}, {name},{guid_args(g)});\n\n" for kind, name, g in guids)
    return (
        f"/* Stand-in for the OPC Foundation's MIDL-generated {stem}_i.c (see docs/header-coexistence.md). */\n\n"
        "#pragma warning( disable: 4049 )  /* more than 64k source lines */\n\n"
        "#ifdef __cplusplus\nextern \"C\"{\n#endif\n\n"
        "#include <rpc.h>\n#include <rpcndr.h>\n\n"
        "#ifdef _MIDL_USE_GUIDDEF_\n\n"
        "#ifndef INITGUID\n#define INITGUID\n#include <guiddef.h>\n#undef INITGUID\n#else\n#include <guiddef.h>\n#endif\n\n"
        "#define MIDL_DEFINE_GUID(type,name,l,w1,w2,b1,b2,b3,b4,b5,b6,b7,b8) \\\n"
        "        DEFINE_GUID(name,l,w1,w2,b1,b2,b3,b4,b5,b6,b7,b8)\n\n"
        "#else // !_MIDL_USE_GUIDDEF_\n\n"
        "#ifndef __IID_DEFINED__\n#define __IID_DEFINED__\n\n"
        "typedef struct _IID\n{\n    unsigned long x;\n    unsigned short s1;\n    unsigned short s2;\n"
        "    unsigned char  c[8];\n} IID;\n\n#endif // __IID_DEFINED__\n\n"
        "#ifndef CLSID_DEFINED\n#define CLSID_DEFINED\ntypedef IID CLSID;\n#endif // CLSID_DEFINED\n\n"
        "#define MIDL_DEFINE_GUID(type,name,l,w1,w2,b1,b2,b3,b4,b5,b6,b7,b8) \\\n"
        "        const type name = {l,w1,w2,{b1,b2,b3,b4,b5,b6,b7,b8}}\n\n"
        "#endif !_MIDL_USE_GUIDDEF_\n\n"
        f"{body}"
        "#undef MIDL_DEFINE_GUID\n\n#ifdef __cplusplus\n}\n#endif\n"
    )


def category_idl(stem, categories, table):
    """The categories as the Foundation's IDL declares them: an empty interface each, a cpp_quote'd
    #define after it, and OPCHANDLE."""
    s = f"// Categories of {stem}.idl, in its form (an empty interface, then the name #defined to its IID).\n"
    s += 'import "unknwn.idl";\n\n'
    for macro, iface in categories:
        s += f"[\n    object,\n    uuid({table[macro]})\n]\ninterface {iface} : IUnknown\n{{\n    // no methods\n}}\n\n"
        s += f'cpp_quote("#define {macro} IID_{iface}")\n\n'
    s += "typedef DWORD OPCHANDLE;\n"
    return s


def error_header(name, guard, codes):
    """Message-compiler output: `//` comments, `#define NAME ((HRESULT)0x...L)`."""
    s = f"// Stand-in for the OPC Foundation's {name} (message-compiler output; see docs/header-coexistence.md).\n"
    s += f"#ifndef {guard}\n#define {guard}\n\n"
    for code_name, value in codes:
        s += f"//\n// MessageId: {code_name}\n//\n#define {code_name} ((HRESULT)0x{value:08X}L)\n\n"
    return s + "#endif\n"


def idl_uuids(idl_text):
    """(interface or library name, uuid) from an IDL file."""
    return re.findall(r"uuid\(([0-9A-Fa-f-]{36})\)[^\]]*\]\s*(?:interface|library)\s+(\w+)", idl_text)


def check(out):
    """Every modelled trait is there, and nothing of widl's that MIDL lacks."""
    problems = []
    for stem in ["opccomn", "opcda", "opc_ae", "opchda"]:
        h = (out / f"{stem}.h").read_text()
        for absent in ["__CRT_UUID_DECL", "DEFINE_GUID", "WIDL_C_INLINE_WRAPPERS", "FORCEINLINE"]:
            if absent in h:
                problems.append(f"{stem}.h contains {absent}")
        if not h.startswith("/* Stand-in") or "#pragma warning( disable: 4049 )" not in h.split("#ifndef")[0]:
            problems.append(f"{stem}.h lacks the unconditional #pragma warning")
        if stem != "opccomn" and h.count("typedef DWORD OPCHANDLE;") != 1:
            problems.append(f"{stem}.h does not typedef OPCHANDLE")
        for macro, iface in CATEGORIES.get(stem, []):
            if f"#define {macro} IID_{iface}" not in h or f"EXTERN_C const IID IID_{iface};" not in h:
                problems.append(f"{stem}.h lacks {macro} as IID_{iface}")
        c = (out / f"{stem}_i.c").read_text()
        if "#endif !_MIDL_USE_GUIDDEF_" not in c or "MIDL_DEFINE_GUID(IID," not in c:
            problems.append(f"{stem}_i.c is not in MIDL's form")
    h = (out / "opccomn.h").read_text()
    for iface in ["IOPCShutdown", "IOPCCommon", "IOPCServerList", "IOPCEnumGUID", "IOPCServerList2"]:
        if f"EXTERN_C const IID IID_{iface};" not in h or f"#ifndef __{iface}_INTERFACE_DEFINED__" not in h:
            problems.append(f"opccomn.h lacks {iface}")
    # widl's own output declares __uuidof for every interface (what makes it differ from MIDL's).
    for stem, names in [("opccomn", ["IOPCShutdown", "IOPCCommon", "IOPCServerList", "IOPCEnumGUID", "IOPCServerList2"]),
                        ("opcda", ["CATID_OPCDAServer20"]), ("opc_ae", ["OPCEventServerCATID"])]:
        h = (out / "widl" / f"{stem}.h").read_text()
        for name in names:
            if f"__CRT_UUID_DECL({name}," not in h:
                problems.append(f"widl/{stem}.h lacks __CRT_UUID_DECL({name})")
        if "MIDL_DEFINE_GUID(IID," not in (out / "widl" / f"{stem}_i.c").read_text():
            problems.append(f"widl/{stem}_i.c defines no IID")
    if problems:
        sys.exit("midl_standins: " + "; ".join(problems))


def main():
    root, out, widl_inc = (pathlib.Path(a) for a in sys.argv[1:4])
    out.mkdir(parents=True, exist_ok=True)
    table = guid_table(root)

    def widl(stem):
        (out / "widl").mkdir(exist_ok=True)
        subprocess.run(["x86_64-w64-mingw32-widl", f"-I{widl_inc}", f"-I{out}", "-h", "-o",
                        str(out / "widl" / f"{stem}.h"), str(out / f"{stem}.idl")], check=True)
        subprocess.run(["x86_64-w64-mingw32-widl", f"-I{widl_inc}", f"-I{out}", "-u", "-o",
                        str(out / "widl" / f"{stem}_i.c"), str(out / f"{stem}.idl")], check=True)
        return (out / "widl" / f"{stem}.h").read_text()

    opccomn_idl = (root / "idl/opccomn.idl").read_text()
    (out / "opccomn.idl").write_text(opccomn_idl)
    (out / "opccomn.h").write_text(midl_form(widl("opccomn"), "opccomn"))
    guids = [("IID", ("LIBID_" if name == "OPCCOMN" else "IID_") + name, g) for g, name in idl_uuids(opccomn_idl)]
    (out / "opccomn_i.c").write_text(midl_i_c("opccomn", guids))
    for stem, categories in CATEGORIES.items():
        (out / f"{stem}.idl").write_text(category_idl(stem, categories, table))
        (out / f"{stem}.h").write_text(midl_form(widl(stem), stem))
        (out / f"{stem}_i.c").write_text(midl_i_c(stem, [("IID", f"IID_{i}", table[m]) for m, i in categories]))
    for name, (guard, codes) in ERRORS.items():
        (out / name).write_text(error_header(name, guard, codes))
    check(out)


if __name__ == "__main__":
    main()
