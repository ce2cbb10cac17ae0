#!/usr/bin/env python3
"""Checks the interfaces of idl/*.idl against the OPC Foundation's published tables.

    python3 tools/check-idl-tables.py

The lists below were compiled from the Foundation's IDL files (opccomn.idl, opcda.idl, opc_ae.idl,
opchda.idl as published with its Core Components and as older editions carry them) and checked
against MIDL's builds of them (the IIDs of opcda_i.c; each interface's method count from the proxy
vtables of opcda_p.c, opc_ae_p.c and opchda_p.c: CINTERFACE_PROXY_VTABLE(n)); the IDL comments and
docs/dev/proxy-tables.md name the copies. They are written here a second time, on purpose, apart
from the IDL: a typo in either fails this check.

It fails when, for any interface:
- the IID, the base interface, the methods (names, order) or a method's number of parameters in
  idl/NAME.idl differ from the list, or the IDL has an interface the list does not, or lacks one;
- the header widl generated (src/proxy/generated/NAME_idl.h) defines another IID for it;
- a generated proxy file (src/proxy/generated/NAME_p_win64.c, _win32.c) has a vtable of another
  size for it (3 for IUnknown's methods, then the base interface's, then its own).
Also, that idl/opcguids.txt gives the component categories the Foundation's IDL declares, and that
each IDL's type library has the Foundation's identifier and version.
"""
import os
import re
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))

# (interface, IID, base, [method:number of parameters, ...]) per IDL file, in the Foundation's order.
TABLES = {
    "opccomn": [
        ("IOPCShutdown", "F31DFDE1-07B6-11D2-B2D8-0060083BA1FB", "IUnknown", ["ShutdownRequest:1"]),
        ("IOPCCommon", "F31DFDE2-07B6-11D2-B2D8-0060083BA1FB", "IUnknown",
         ["SetLocaleID:1", "GetLocaleID:1", "QueryAvailableLocaleIDs:2", "GetErrorString:2", "SetClientName:1"]),
        ("IOPCServerList", "13486D50-4821-11D2-A494-3CB306C10000", "IUnknown",
         ["EnumClassesOfCategories:5", "GetClassDetails:3", "CLSIDFromProgID:2"]),
        ("IOPCEnumGUID", "55C382C8-21C7-4E88-96C1-BECFB1E3F483", "IUnknown", ["Next:3", "Skip:1", "Reset:0", "Clone:1"]),
        ("IOPCServerList2", "9DD0B56C-AD9E-43EE-8305-487F3188BF7A", "IUnknown",
         ["EnumClassesOfCategories:5", "GetClassDetails:4", "CLSIDFromProgID:2"]),
    ],
    "opcda": [
        ("IOPCServer", "39C13A4D-011E-11D0-9675-0020AFD8ADB3", "IUnknown",
         ["AddGroup:11", "GetErrorString:3", "GetGroupByName:3", "GetStatus:1", "RemoveGroup:2",
          "CreateGroupEnumerator:3"]),
        ("IOPCServerPublicGroups", "39C13A4E-011E-11D0-9675-0020AFD8ADB3", "IUnknown",
         ["GetPublicGroupByName:3", "RemovePublicGroup:2"]),
        ("IOPCBrowseServerAddressSpace", "39C13A4F-011E-11D0-9675-0020AFD8ADB3", "IUnknown",
         ["QueryOrganization:1", "ChangeBrowsePosition:2", "BrowseOPCItemIDs:5", "GetItemID:2", "BrowseAccessPaths:2"]),
        ("IOPCGroupStateMgt", "39C13A50-011E-11D0-9675-0020AFD8ADB3", "IUnknown",
         ["GetState:8", "SetState:7", "SetName:1", "CloneGroup:3"]),
        ("IOPCPublicGroupStateMgt", "39C13A51-011E-11D0-9675-0020AFD8ADB3", "IUnknown", ["GetState:1", "MoveToPublic:0"]),
        ("IOPCSyncIO", "39C13A52-011E-11D0-9675-0020AFD8ADB3", "IUnknown", ["Read:5", "Write:4"]),
        ("IOPCAsyncIO", "39C13A53-011E-11D0-9675-0020AFD8ADB3", "IUnknown", ["Read:6", "Write:6", "Refresh:3", "Cancel:1"]),
        ("IOPCItemMgt", "39C13A54-011E-11D0-9675-0020AFD8ADB3", "IUnknown",
         ["AddItems:4", "ValidateItems:5", "RemoveItems:3", "SetActiveState:4", "SetClientHandles:4",
          "SetDatatypes:4", "CreateEnumerator:2"]),
        ("IEnumOPCItemAttributes", "39C13A55-011E-11D0-9675-0020AFD8ADB3", "IUnknown",
         ["Next:3", "Skip:1", "Reset:0", "Clone:1"]),
        ("IOPCDataCallback", "39C13A70-011E-11D0-9675-0020AFD8ADB3", "IUnknown",
         ["OnDataChange:10", "OnReadComplete:10", "OnWriteComplete:6", "OnCancelComplete:2"]),
        ("IOPCAsyncIO2", "39C13A71-011E-11D0-9675-0020AFD8ADB3", "IUnknown",
         ["Read:5", "Write:6", "Refresh2:3", "Cancel2:1", "SetEnable:1", "GetEnable:1"]),
        ("IOPCItemProperties", "39C13A72-011E-11D0-9675-0020AFD8ADB3", "IUnknown",
         ["QueryAvailableProperties:5", "GetItemProperties:5", "LookupItemIDs:5"]),
        ("IOPCItemDeadbandMgt", "5946DA93-8B39-4EC8-AB3D-AA73DF5BC86F", "IUnknown",
         ["SetItemDeadband:4", "GetItemDeadband:4", "ClearItemDeadband:3"]),
        ("IOPCItemSamplingMgt", "3E22D313-F08B-41A5-86C8-95E95CB49FFC", "IUnknown",
         ["SetItemSamplingRate:5", "GetItemSamplingRate:4", "ClearItemSamplingRate:3", "SetItemBufferEnable:4",
          "GetItemBufferEnable:4"]),
        ("IOPCBrowse", "39227004-A18F-4B57-8B0A-5235670F4468", "IUnknown", ["GetProperties:6", "Browse:13"]),
        ("IOPCItemIO", "85C0B427-2893-4CBC-BD78-E5FC5146F08F", "IUnknown", ["Read:7", "WriteVQT:4"]),
        ("IOPCSyncIO2", "730F5F0F-55B1-4C81-9E18-FF8A0904E1FA", "IOPCSyncIO", ["ReadMaxAge:7", "WriteVQT:4"]),
        ("IOPCAsyncIO3", "0967B97B-36EF-423E-B6F8-6BFF1E40D39D", "IOPCAsyncIO2",
         ["ReadMaxAge:6", "WriteVQT:6", "RefreshMaxAge:3"]),
        ("IOPCGroupStateMgt2", "8E368666-D72E-4F78-87ED-647611C61C9F", "IOPCGroupStateMgt",
         ["SetKeepAlive:2", "GetKeepAlive:1"]),
    ],
    "opc_ae": [
        ("IOPCEventServer", "65168851-5783-11D1-84A0-00608CB8A7E9", "IUnknown",
         ["GetStatus:1", "CreateEventSubscription:8", "QueryAvailableFilters:1", "QueryEventCategories:4",
          "QueryConditionNames:3", "QuerySubConditionNames:3", "QuerySourceConditions:3", "QueryEventAttributes:5",
          "TranslateToItemIDs:9", "GetConditionState:5", "EnableConditionByArea:2", "EnableConditionBySource:2",
          "DisableConditionByArea:2", "DisableConditionBySource:2", "AckCondition:8", "CreateAreaBrowser:2"]),
        ("IOPCEventSubscriptionMgt", "65168855-5783-11D1-84A0-00608CB8A7E9", "IUnknown",
         ["SetFilter:9", "GetFilter:9", "SelectReturnedAttributes:3", "GetReturnedAttributes:3", "Refresh:1",
          "CancelRefresh:1", "GetState:4", "SetState:6"]),
        ("IOPCEventAreaBrowser", "65168857-5783-11D1-84A0-00608CB8A7E9", "IUnknown",
         ["ChangeBrowsePosition:2", "BrowseOPCAreas:3", "GetQualifiedAreaName:2", "GetQualifiedSourceName:2"]),
        ("IOPCEventSink", "6516885F-5783-11D1-84A0-00608CB8A7E9", "IUnknown", ["OnEvent:5"]),
        ("IOPCEventServer2", "71BBE88E-9564-4BCD-BCFC-71C558D94F2D", "IOPCEventServer",
         ["EnableConditionByArea2:3", "EnableConditionBySource2:3", "DisableConditionByArea2:3",
          "DisableConditionBySource2:3", "GetEnableStateByArea:5", "GetEnableStateBySource:5"]),
        ("IOPCEventSubscriptionMgt2", "94C955DC-3684-4CCB-AFAB-F898CE19AAC3", "IOPCEventSubscriptionMgt",
         ["SetKeepAlive:2", "GetKeepAlive:1"]),
    ],
    "opchda": [
        ("IOPCHDA_Browser", "1F1217B1-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["GetEnum:2", "ChangeBrowsePosition:2", "GetItemID:2", "GetBranchPosition:1"]),
        ("IOPCHDA_Server", "1F1217B0-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["GetItemAttributes:5", "GetAggregates:4", "GetHistorianStatus:9", "GetItemHandles:5",
          "ReleaseItemHandles:3", "ValidateItemIDs:3", "CreateBrowse:6"]),
        ("IOPCHDA_SyncRead", "1F1217B2-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["ReadRaw:8", "ReadProcessed:8", "ReadAtTime:6", "ReadModified:7", "ReadAttribute:7"]),
        ("IOPCHDA_SyncUpdate", "1F1217B3-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["QueryCapabilities:1", "Insert:6", "Replace:6", "InsertReplace:6", "DeleteRaw:5", "DeleteAtTime:4"]),
        ("IOPCHDA_SyncAnnotations", "1F1217B4-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["QueryCapabilities:1", "Read:6", "Insert:5"]),
        ("IOPCHDA_AsyncRead", "1F1217B5-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["ReadRaw:9", "AdviseRaw:7", "ReadProcessed:9", "AdviseProcessed:9", "ReadAtTime:7", "ReadModified:8",
          "ReadAttribute:8", "Cancel:1"]),
        ("IOPCHDA_AsyncUpdate", "1F1217B6-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["QueryCapabilities:1", "Insert:8", "Replace:8", "InsertReplace:8", "DeleteRaw:7", "DeleteAtTime:6",
          "Cancel:1"]),
        ("IOPCHDA_AsyncAnnotations", "1F1217B7-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["QueryCapabilities:1", "Read:7", "Insert:7", "Cancel:1"]),
        ("IOPCHDA_Playback", "1F1217B8-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["ReadRawWithUpdate:10", "ReadProcessedWithUpdate:11", "Cancel:1"]),
        ("IOPCHDA_DataCallback", "1F1217B9-DEE0-11D2-A5E5-000086339399", "IUnknown",
         ["OnDataChange:5", "OnReadComplete:5", "OnReadModifiedComplete:5", "OnReadAttributeComplete:6",
          "OnReadAnnotations:5", "OnInsertAnnotations:5", "OnPlayback:5", "OnUpdateComplete:5", "OnCancelComplete:1"]),
    ],
}

# The type libraries: (LIBID, version) per IDL file.
LIBRARIES = {
    "opccomn": ("B28EEDB1-AC6F-11D1-84D5-00608CB8A7E9", "1.10"),
    "opcda": ("3B540B51-0378-4551-ADCC-EA9B104302BF", "3.00"),
    "opc_ae": ("65168844-5783-11D1-84A0-00608CB8A7E9", "1.10"),
    "opchda": ("1F1217BA-DEE0-11D2-A5E5-000086339399", "1.10"),
}

# The component categories the Foundation's IDL declares (opcda.idl, opc_ae.idl, opchda.idl), which
# idl/opcguids.txt keeps.
CATEGORIES = {
    "CATID_OPCDAServer10": "63D5F430-CFE4-11D1-B2C8-0060083BA1FB",
    "CATID_OPCDAServer20": "63D5F432-CFE4-11D1-B2C8-0060083BA1FB",
    "CATID_OPCDAServer30": "CC603642-66D7-48F1-B69A-B625E73652D7",
    "CATID_XMLDAServer10": "3098EDA4-A006-48B2-A27F-247453959408",
    "CATID_OPCAEServer10": "58E13251-AC87-11D1-84D5-00608CB8A7E9",
    "CATID_OPCHDAServer10": "7DE5B060-E089-11D2-A5E6-000086339399",
}


def read(path):
    with open(os.path.join(ROOT, path)) as f:
        return f.read()


def parameters(text):
    """The number of parameters in a parameter list (`void` and nothing are none)."""
    text = text.strip()
    if text in ("", "void"):
        return 0
    depth, count = 0, 1
    for c in text:
        if c in "[(":
            depth += 1
        elif c in "])":
            depth -= 1
        elif c == "," and depth == 0:
            count += 1
    return count


def interfaces(text):
    """[(name, IID, base, [method:parameters, ...])] of an IDL file, in order."""
    text = re.sub(r"/\*.*?\*/", "", re.sub(r"//[^\n]*", "", text), flags=re.S)
    found = []
    pattern = r"\[([^\[\]]*)\]\s*interface\s+(\w+)\s*:\s*(\w+)\s*\{(.*?)\n\}"
    for m in re.finditer(pattern, text, re.S):
        attributes, name, base, body = m.groups()
        uuid = re.search(r"uuid\(\s*([0-9A-Fa-f-]+)\s*\)", attributes)
        if not uuid or "object" not in re.split(r"[\s,]+", attributes):
            sys.exit("check-idl-tables: interface %s has no uuid or no object attribute" % name)
        methods = ["%s:%d" % (n, parameters(p)) for n, p in re.findall(r"HRESULT\s+(\w+)\s*\((.*?)\)\s*;", body, re.S)]
        found.append((name, uuid.group(1).upper(), base, methods))
    return found


def main():
    errors = []
    for idl, table in TABLES.items():
        got = interfaces(read("idl/%s.idl" % idl))
        names = [t[0] for t in table]
        if [g[0] for g in got] != names:
            errors.append("idl/%s.idl declares %s; the Foundation's: %s" % (idl, [g[0] for g in got], names))
        by_name = {g[0]: g for g in got}
        expected_by_name = {t[0]: t for t in table}
        for name, iid, base, methods in table:
            g = by_name.get(name)
            if g is None:
                continue
            if g[1] != iid:
                errors.append("idl/%s.idl: %s has IID %s, the Foundation's %s" % (idl, name, g[1], iid))
            if g[2] != base:
                errors.append("idl/%s.idl: %s derives from %s, the Foundation's from %s" % (idl, name, g[2], base))
            if g[3] != methods:
                errors.append("idl/%s.idl: %s has the methods %s, the Foundation's %s" % (idl, name, g[3], methods))
        # What widl generated: the IIDs in the header, the vtable sizes in the proxy files.
        header = read("src/proxy/generated/%s_idl.h" % idl)
        for name, iid, base, methods in table:
            m = re.search(r"DEFINE_GUID\(IID_%s, 0x([0-9a-f]{8}), 0x([0-9a-f]{4}), 0x([0-9a-f]{4}), "
                          r"0x([0-9a-f]{2}),0x([0-9a-f]{2}), 0x([0-9a-f]{2}),0x([0-9a-f]{2}),0x([0-9a-f]{2}),"
                          r"0x([0-9a-f]{2}),0x([0-9a-f]{2}),0x([0-9a-f]{2})\)" % name, header)
            generated = "-".join([m.group(1), m.group(2), m.group(3), m.group(4) + m.group(5),
                                  "".join(m.group(i) for i in range(6, 12))]).upper() if m else None
            if generated != iid:
                errors.append("src/proxy/generated/%s_idl.h: IID_%s is %s, the Foundation's %s" % (idl, name, generated, iid))
        for arch in ("win64", "win32"):
            proxy = read("src/proxy/generated/%s_p_%s.c" % (idl, arch))
            for name, iid, base, methods in table:
                size = 3 + len(methods)
                parent = base
                while parent != "IUnknown":
                    parent_entry = expected_by_name[parent]
                    size += len(parent_entry[3])
                    parent = parent_entry[2]
                m = re.search(r"CINTERFACE_PROXY_VTABLE\((\d+)\) _%sProxyVtbl" % name, proxy)
                if not m or int(m.group(1)) != size:
                    errors.append("src/proxy/generated/%s_p_%s.c: the proxy vtable of %s has %s entries, not %d"
                                  % (idl, arch, name, m.group(1) if m else "no", size))
        library = re.search(r"\[\s*uuid\(([0-9A-Fa-f-]+)\),\s*version\(([\d.]+)\)[^\]]*\]\s*library", read("idl/%s.idl" % idl))
        if not library or (library.group(1).upper(), library.group(2)) != LIBRARIES[idl]:
            errors.append("idl/%s.idl: the type library is %s, the Foundation's %s"
                          % (idl, library.groups() if library else None, LIBRARIES[idl]))
    categories = {}
    for line in read("idl/opcguids.txt").splitlines():
        parts = line.split()
        if len(parts) >= 4 and parts[0] == "category":
            categories[parts[2]] = parts[3].upper()
    for name, guid in CATEGORIES.items():
        if categories.get(name) != guid:
            errors.append("idl/opcguids.txt: %s is %s, the Foundation's %s" % (name, categories.get(name), guid))
    for e in errors:
        print("check-idl-tables: " + e, file=sys.stderr)
    if errors:
        sys.exit(1)
    count = sum(len(t) for t in TABLES.values())
    print("check-idl-tables: %d interfaces of %d IDL files, their IIDs, methods and generated vtables, the type"
          " libraries and %d categories match the Foundation's" % (count, len(TABLES), len(CATEGORIES)),
          file=sys.stderr)


if __name__ == "__main__":
    main()
