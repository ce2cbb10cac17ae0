#!/usr/bin/env python3
"""Writes c-tests/test_null_rule.c from the public header: for every export and every vtable method,
one case per pointer argument that must not be NULL, calling it with NULL there and valid values
everywhere else, and checking the code the NULL rule prescribes (docs/api-conventions.md) and that
every out-parameter is NULL/zero afterwards (pre-filled with garbage before the call).

The rule, as the library implements it in src/com/ffi.rs:
  - COM plumbing answers E_POINTER: QueryInterface of every interface, the methods of IUnknown, the
    enumerators and the connection points, and the functions that end in CoCreateInstance's
    `REFIID riid, void **ppv` (the creation functions and OpcDllGetClassObject);
  - OPC methods (IOPCCommon, IOPCShutdown, IOPCServerList, IOPCServerList2) and every other export
    answer E_INVALIDARG;
  - functions that return no HRESULT answer with their documented value (MatchPattern: FALSE).

A new export or method is covered as soon as it is in the header. Arguments that may be NULL by
contract are listed in OPTIONAL below; an argument type the table VALID cannot fill stops the
generator with a message, so nothing is skipped silently.

Usage: tools/gen-null-rule-test.py [--check]     (--check: fail when the committed file differs)
"""
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "c-tests", "test_null_rule.c")

# Interfaces whose methods are OPC methods (E_INVALIDARG); every other interface is COM plumbing.
OPC_INTERFACES = {"IOPCCommon", "IOPCShutdown", "IOPCServerList", "IOPCServerList2"}

# (function or Interface::Method, argument) pairs, or "*" for every function, that may be NULL.
OPTIONAL = {
    ("*", "outer"), ("*", "pUnkOuter"), ("*", "options"), ("*", "context"), ("*", "reg"),
    ("OpcShutdownNotify", "reason"), ("OpcShutdownNotifyEx", "reason"),
    ("OpcShutdownNotifyEx", "notified"), ("OpcShutdownNotifyEx", "failed"),
    ("OpcShutdownNotifyBounded", "reason"), ("OpcShutdownNotifyBounded", "notified"),
    ("OpcShutdownNotifyBounded", "failed"), ("OpcShutdownNotifyBounded", "timed_out"),
    ("OpcSetModuleLock", "lock"),
    ("OpcExeServerRun", "options"), ("OpcExeServerRun", "command_line"),
    ("IOPCShutdown::ShutdownRequest", "szReason"),
    ("OpcRegistryGetString", "name"), ("OpcRegistryExport", "key"),
    ("OpcCreateComponentCategory", "description"),
}

# The result of a function without HRESULT for a NULL argument (default: FALSE for BOOL).
NON_HRESULT = {
    ("OpcVersionCompare", "a"): "-1", ("OpcVersionCompare", "b"): "1",
    ("OpcVersionIsNewer", "installed"): "TRUE",
}

# Objects the methods are called on.
THIS = {
    "IUnknown": "nr_unknown()", "IOPCCommon": "nr_common()", "IOPCShutdown": "nr_sink()",
    "IConnectionPointContainer": "nr_container()", "IConnectionPoint": "nr_point()",
    "IEnumConnectionPoints": "nr_enum_points()", "IEnumConnections": "nr_enum_connections()",
    "IOPCServerList": "nr_list()", "IOPCServerList2": "nr_list2()", "IEnumGUID": "nr_enum_guid()",
    "IOPCEnumGUID": "nr_enum_opc_guid()", "IClassFactory": "nr_factory()",
}

# Valid values of in-arguments: by (function, argument), then by argument, then by type.
VALID_BY_FUNCTION = {
    ("IConnectionPointContainer::FindConnectionPoint", "riid"): "&IID_IOPCShutdown",
    ("OpcVersionParse", "text"): 'W("1.2.3")',
    ("OpcRegistryApply", "text"): 'W("Windows Registry Editor Version 5.00\\r\\n")',
    ("OpcShutdownAdvise", "server"): "nr_container_unknown()",
    ("OpcShutdownUnadvise", "server"): "nr_container_unknown()",
    ("IOPCServerList::CLSIDFromProgID", "szProgId"): 'W("OPC.ServerList.1")',
    ("IOPCServerList2::CLSIDFromProgID", "szProgId"): 'W("OPC.ServerList.1")',
    ("OpcModuleGetClassObject", "rclsid"): "&nr_class_id",
    ("OpcModuleGetClassObject", "riid"): "&IID_IClassFactory", ("OpcClassFactoryCreate", "riid"): "&IID_IClassFactory",
}
VALID_BY_NAME = {
    "riid": "&IID_Unknown_", "rclsid": "&CLSID_OPCServerList", "clsid": "&CLSID_OPCServerList",
    "catid": "&CATID_OPCDAServer20", "common": "nr_common_unknown()", "shutdown": "nr_container_unknown()",
    "sink": "nr_sink_unknown()", "pUnkSink": "nr_sink_unknown()", "callback": "nr_on_shutdown",
    "rgcatidImpl": "nr_categories()", "rgcatidReq": "nr_categories()", "server": "nr_registration()",
    "command_line": 'W("/RegServer")', "key": 'W("CLSID")', "pattern": None, "string": None,
    "celt": None, "cConnections": None, "count": "1", "cImplemented": "1", "cRequired": "1", "dwLcid": "0x409",
    "locale": "0x409", "dwError": "(HRESULT)0x80004005L", "code": "(HRESULT)0x80004005L", "kind": "0",
    "bCaseSensitive": "TRUE", "case_sensitive": "TRUE", "dwCookie": "1", "cookie": "1",
    "ms": "0x00010002", "ls": "3", "size": "8", "szName": 'W("client")', "text": 'W("x")',
    "a": "&nr_version", "b": "&nr_version", "candidate": "&nr_version", "installed": "&nr_version",
    "version": "&nr_version",
}
VALID_BY_TYPE = {
    "LPCWSTR": 'W("abc")', "LPCOLESTR": 'W("abc")', "LPCSTR": '"abc"',
    "const OpcPattern *": "nr_pattern()", "const OpcRegistry *": "nr_reg",
    "const struct OpcServerClass *": "nr_server_class()", "const OpcServerClass *": "nr_server_class()",
    "OpcRegistry *": "nr_reg", "const OpcVersion *": "&nr_version",
}
# Pointer types that are inputs (everything else that is a pointer is an out-parameter).
IN_POINTER_TYPES = {"REFIID", "REFCLSID", "LPCWSTR", "LPCOLESTR", "LPCSTR", "OpcShutdownCallback",
                    "IUnknown *", "CATID *", "void *", "OpcPattern *", "OpcRegistry *"}
POINTER_TYPEDEFS = {"REFIID": "IID", "REFCLSID": "CLSID", "LPCWSTR": "WCHAR", "LPCOLESTR": "WCHAR",
                    "LPCSTR": "char", "LPCLSID": "CLSID", "LPWSTR": "WCHAR", "LPOLESTR": "WCHAR",
                    "OpcShutdownCallback": None}


# Calling-convention macros between a return type and a name (`void OPCCOMN_CDECL OpcTaskMemFree`).
CALLING_CONVENTION = re.compile(r"^(STDMETHODCALLTYPE|WINAPI|__stdcall|__cdecl|OPCCOMN_[A-Z]+)$")


def parse(text):
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"^\s*#[^\n]*(\\\n[^\n]*)*", "", text, flags=re.M)
    text = re.sub(r'extern\s+"C"\s*\{', "", text)
    text = re.sub(r"^\s*\}\s*$", "", text, flags=re.M)
    text = re.sub(r"\b(BEGIN_INTERFACE|END_INTERFACE)\b", "", text)
    vtbls = {}
    for m in re.finditer(r"typedef\s+struct\s+(\w+?)Vtbl\s*\{(.*?)\}\s*\w+\s*;", text, re.S):
        meths = []
        for mm in re.finditer(r"([\w\s\*]+?)\(\s*(?:STDMETHODCALLTYPE|__stdcall|WINAPI|OPCCOMN_[A-Z]+)?\s*\*\s*(\w+)\s*\)\s*\((.*?)\)\s*;",
                              m.group(2), re.S):
            meths.append((mm.group(2), " ".join(mm.group(1).split()), params(mm.group(3))))
        vtbls[m.group(1)] = meths
    flat = text
    for _ in range(3):
        flat = re.sub(r"\{[^{}]*\}", "{}", flat)
    funcs = []
    for stmt in flat.split(";"):
        s = " ".join(stmt.split()).split("}")[-1].strip()
        if not s or s.startswith("typedef"):
            continue
        m = re.match(r"^(?:extern\s+)?([\w\s\*]+?)\s*\b(\w+)\s*\(([^()]*)\)$", s)
        if not m or m.group(1).startswith("static") or "__RPC" in m.group(1):
            continue
        # MIDL-style headers also declare the proxy/stub and marshalling helpers; they are not exports.
        if re.search(r"_(Proxy|Stub|UserSize|UserMarshal|UserUnmarshal|UserFree)$", m.group(2)):
            continue
        ret = " ".join(w for w in m.group(1).split() if not CALLING_CONVENTION.match(w))
        funcs.append((m.group(2), ret, params(m.group(3))))
    return vtbls, funcs


def params(s):
    s = " ".join(s.split())
    if s in ("", "void"):
        return []
    out = []
    for p in s.split(","):
        p = p.strip()
        if re.search(r"\[\s*\w*\s*\]$", p):  # `CATID rgcatidImpl[]` is a pointer
            p = re.sub(r"\s*(\w+)\s*\[\s*\w*\s*\]$", r" *\1", p)
        m = re.match(r"^(.*?)(\w+)$", p)
        # Types without `struct`: the tags are also typedef names, in cbindgen and MIDL headers alike.
        typ = " ".join(w for w in m.group(1).replace("*", " * ").split() if w != "struct").replace("* *", "**")
        out.append((m.group(2), typ))
    return out


def is_pointer(typ):
    return typ.endswith("*") or typ in POINTER_TYPEDEFS


def is_in(typ):
    return typ in IN_POINTER_TYPES or typ.startswith("const ")


def pointee(typ):
    """The C type an out-parameter points at, without `struct` (typedef names are the tags)."""
    if typ in POINTER_TYPEDEFS:
        base = POINTER_TYPEDEFS[typ]
    else:
        base = typ[:-1].strip()
    return base


def optional(name, arg, typ=None):
    """Whether `arg` of `name` may be NULL by contract. A name listed for every function ("*") is an
    input there: an out-parameter of the same name (OpcRegistryCreateMemory's `reg`) is not optional."""
    if (name, arg) in OPTIONAL:
        return True
    return ("*", arg) in OPTIONAL and (typ is None or not is_pointer(typ) or is_in(typ))


def valid(name, arg, typ, method):
    if (name, arg) in VALID_BY_FUNCTION:
        return VALID_BY_FUNCTION[(name, arg)]
    if method in ("Next",) and arg in ("celt", "cConnections"):
        return "2"  # more than one, so that the fetched count may not be NULL
    if method == "Skip" and arg in ("celt", "cConnections"):
        return "1"
    if arg == "pattern":
        return 'W("a*")' if typ == "LPCWSTR" else ('"a*"' if typ == "LPCSTR" else VALID_BY_TYPE.get(typ))
    if arg == "string":
        return 'W("abc")' if typ == "LPCWSTR" else '"abc"'
    if VALID_BY_NAME.get(arg) is not None:
        return VALID_BY_NAME[arg]
    if typ in VALID_BY_TYPE:
        return VALID_BY_TYPE[typ]
    if not is_pointer(typ):
        return "0"
    if optional(name, arg):
        return "NULL"
    sys.exit(f"gen-null-rule-test: no valid value for argument `{arg}` ({typ}) of {name}: add one to VALID")


def cases(vtbls, funcs):
    """(label, call target, rule, return type, args) for every callable in the header."""
    items = []
    for iface, meths in vtbls.items():
        if iface not in THIS:
            if [m[0] for m in meths] == ["QueryInterface", "AddRef", "Release"]:
                # A declaration carrying only a GUID (MIDL headers declare CATIDs this way): the
                # library has no object of it.
                continue
            sys.exit(f"gen-null-rule-test: no fixture object for interface {iface}: add one to THIS")
        for meth, ret, args in meths:
            rule = "E_INVALIDARG" if iface in OPC_INTERFACES and meth != "QueryInterface" else "E_POINTER"
            items.append((f"{iface}::{meth}", (iface, meth), rule, ret, args[1:]))
    for name, ret, args in funcs:
        com = len(args) >= 2 and args[-2][1] == "REFIID" and args[-1][1] == "void **"
        items.append((name, None, "E_POINTER" if com else "E_INVALIDARG", ret, args))
    return items


def emit(items):
    out = []
    w = out.append
    w("/* Generated by tools/gen-null-rule-test.py from the public header: do not edit. Every export and")
    w(" * every vtable method, with NULL in each pointer argument that must not be NULL (one at a time, the")
    w(" * others valid), gives the code of the NULL rule and leaves every out-parameter NULL/zero. */")
    w('#include "null_rule_objects.h"')
    w("")
    w("static int cases;")
    w("")
    names = []
    for label, target, rule, ret, args in items:
        method = target[1] if target else None
        for i, (arg, typ) in enumerate(args):
            if not is_pointer(typ) or optional(label, arg, typ):
                continue
            fn = "case_" + re.sub(r"\W", "_", label) + "__" + arg
            names.append(fn)
            w(f"static void {fn}(void) {{")
            w("    nr_setup();")
            call_args = []
            outs = []
            if target:
                w(f"    {target[0]} *self = {THIS[target[0]]};")
            for j, (a, t) in enumerate(args):
                if j == i:
                    call_args.append("NULL")
                elif is_pointer(t) and not is_in(t):
                    local = f"out_{a}"
                    if method == "Next" and j == 1:
                        w(f"    {pointee(t)} {local}[2];")
                        w(f"    memset({local}, 0xA5, sizeof {local});")
                        call_args.append(local)
                    else:
                        w(f"    {pointee(t)} {local};")
                        w(f"    memset(&{local}, 0xA5, sizeof {local});")
                        call_args.append(f"&{local}")
                        outs.append(local)
                else:
                    call_args.append(valid(label, a, t, method))
            if target:
                call = f"self->lpVtbl->{target[1]}(" + ", ".join(["self"] + call_args) + ")"
            else:
                call = f"{label}(" + ", ".join(call_args) + ")"
            if ret == "HRESULT":
                w(f"    CHECK_HR({call}, {rule});")
            elif ret == "void":
                w(f"    {call};")
                w("    CHECK(1); /* returned without a crash */")
            else:
                want = NON_HRESULT.get((label, arg), "FALSE")
                w(f"    CHECK({call} == {want});")
            for local in outs:
                w(f'    if (!nr_is_zero(&{local}, sizeof {local})) fprintf(stderr, "{label}({arg} = NULL): `{local[4:]}` not reset\\n");')
                w(f"    CHECK(nr_is_zero(&{local}, sizeof {local}));")
            w("    nr_teardown();")
            w("    cases++;")
            w("}")
            w("")
    w("int main(void) {")
    for fn in names:
        w(f"    {fn}();")
    w('    printf("test_null_rule: %d cases\\n", cases);')
    w('    return test_summary("test_null_rule");')
    w("}")
    return "\n".join(out) + "\n", len(names)


def header():
    for rel in ("include/opccomn/opccomn.h", "include/opccomn.h"):
        path = os.path.join(ROOT, rel)
        if os.path.exists(path):
            return path
    sys.exit("gen-null-rule-test: no public header found")


def main():
    vtbls, funcs = parse(open(header(), encoding="utf-8").read())
    text, n = emit(cases(vtbls, funcs))
    if "--check" in sys.argv[1:]:
        old = open(OUT, encoding="utf-8").read() if os.path.exists(OUT) else ""
        if old != text:
            sys.exit("c-tests/test_null_rule.c is out of date: run tools/gen-null-rule-test.py")
        print(f"c-tests/test_null_rule.c is up to date ({n} cases)")
        return
    with open(OUT, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)
    print(f"wrote c-tests/test_null_rule.c ({n} cases)")


main()
