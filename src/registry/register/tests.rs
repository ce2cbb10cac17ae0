use super::ledger::{read_ledger, Entry, LEDGER};
use super::*;
use crate::com::ffi::Fail;
use crate::com::{E_INVALIDARG, GUID};
use crate::registry::categories::{CATID_OPCDAServer10, CATID_OPCDAServer20};
use crate::registry::memory::MemoryRegistry;
use crate::registry::{class_key, regfile, RegValue, REGDB_E_KEYMISSING};
use core::ptr;
use std::sync::Arc;

pub(crate) fn memory() -> Registries {
    Registries::memory(Arc::new(MemoryRegistry::new()))
}

pub(crate) fn server(n: u128) -> ServerDescription {
    ServerDescription {
        clsid: GUID::from_u128(0x11111111_2222_3333_4444_000000000000 + n),
        prog_id: format!("Vendor.Server{n}.1"),
        version_independent_prog_id: Some(format!("Vendor.Server{n}")),
        user_type: format!("Vendor Server {n}"),
        module_path: Some("C:\\Program Files\\Vendor\\server.dll".into()),
        threading_model: Some("Both".into()),
        implemented: vec![(CATID_OPCDAServer20, None)],
        ..Default::default()
    }
}

/// Every key (as written) with its values, in the registry's order: what two states are compared by.
/// (The same as comparing `.reg` exports, without formatting the text, which Miri takes long for.)
pub(crate) fn dump(regs: &Registries) -> Vec<(String, Vec<(String, RegValue)>)> {
    fn walk(reg: &dyn crate::registry::Registry, path: String, out: &mut Vec<(String, Vec<(String, RegValue)>)>) {
        let subkeys = reg.subkeys(&path);
        out.push((path.clone(), reg.values(&path)));
        for child in subkeys {
            walk(
                reg,
                if path.is_empty() {
                    child
                } else {
                    format!("{path}\\{child}")
                },
                out,
            );
        }
    }
    let mut out = Vec::new();
    walk(&*regs.write, String::new(), &mut out);
    out
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn registration_writes_what_com_and_the_specification_require() {
    let regs = memory();
    let mut d = server(1);
    d.da10_vendor = Some("Vendor Inc.".into());
    d.implemented.push((CATID_OPCDAServer10, None));
    register(&regs, &d).unwrap();
    let r = &*regs.write;
    let s = |k: &str, n: &str| r.value(k, n).and_then(|v| v.as_str().map(str::to_string));
    let class = format!("CLSID\\{}", d.clsid);
    assert_eq!(s(&class, "").as_deref(), Some("Vendor Server 1"));
    assert_eq!(s(&format!("{class}\\ProgID"), "").as_deref(), Some("Vendor.Server1.1"));
    assert_eq!(
        s(&format!("{class}\\VersionIndependentProgID"), "").as_deref(),
        Some("Vendor.Server1")
    );
    assert_eq!(
        s(&format!("{class}\\InprocServer32"), "").as_deref(),
        Some("C:\\Program Files\\Vendor\\server.dll")
    );
    assert_eq!(
        s(&format!("{class}\\InprocServer32"), "ThreadingModel").as_deref(),
        Some("Both")
    );
    assert!(!r.key_exists(&format!("{class}\\LocalServer32")));
    assert_eq!(
        s("Vendor.Server1.1\\CLSID", "").as_deref(),
        Some(d.clsid.to_string().as_str())
    );
    assert_eq!(s("Vendor.Server1\\CurVer", "").as_deref(), Some("Vendor.Server1.1"));
    assert_eq!(
        s("Vendor.Server1\\CLSID", "").as_deref(),
        Some(d.clsid.to_string().as_str())
    );
    assert_eq!(s("Vendor.Server1.1\\OPC\\Vendor", "").as_deref(), Some("Vendor Inc."));
    assert!(r.key_exists(&format!("{class}\\Implemented Categories\\{CATID_OPCDAServer20}")));
    assert!(r.key_exists(&format!("{class}\\Implemented Categories\\{CATID_OPCDAServer10}")));
    assert_eq!(
        s(&format!("Component Categories\\{CATID_OPCDAServer20}"), "409").as_deref(),
        Some("OPC Data Access Servers Version 2.0")
    );
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn unregistration_leaves_the_registry_as_it_was() {
    let regs = memory();
    regfile::apply(
        &*regs.write,
        "REGEDIT4\n[HKCR\\CLSID\\{00000000-0000-0000-0000-000000000001}]\n@=\"someone else\"\n[HKCR\\Other]\n",
    )
    .unwrap();
    let before = dump(&regs);
    let mut d = server(2);
    d.da10_vendor = Some("V".into());
    d.required = vec![CATID_OPCDAServer10];
    d.app_id = Some(GUID::from_u128(7));
    d.run_as = Some("Interactive User".into());
    d.local = true;
    register(&regs, &d).unwrap();
    assert_ne!(dump(&regs), before);
    register(&regs, &d).unwrap();
    unregister(&regs, &d).unwrap();
    assert_eq!(dump(&regs), before);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn coexisting_registrations_keep_what_they_found() {
    let regs = memory();
    let d = server(3);
    let class = format!("CLSID\\{}", d.clsid);
    // Another product registered the class as an EXE server, with its own description.
    let other = format!(
        "REGEDIT4\n[HKCR\\{class}]\n@=\"Other Class\"\n\"AppID\"=\"{{x}}\"\n[HKCR\\{class}\\LocalServer32]\n@=\"C:\\\\other.exe\"\n[HKCR\\{class}\\ProgID]\n@=\"Vendor.Server3.1\"\n[HKCR\\Vendor.Server3.1\\CLSID]\n@=\"{}\"\n",
        d.clsid
    );
    regfile::apply(&*regs.write, &other).unwrap();
    let before = dump(&regs);
    let mut keep = d.clone();
    keep.keep_existing = true;
    register(&regs, &keep).unwrap();
    assert_eq!(regs.write.value(&class, ""), Some(RegValue::Sz("Other Class".into())));
    assert!(regs.write.key_exists(&format!("{class}\\InprocServer32")));
    unregister(&regs, &keep).unwrap();
    assert_eq!(dump(&regs), before);
    // Without the flag the description is replaced, and restored on unregistration.
    register(&regs, &d).unwrap();
    assert_eq!(
        regs.write.value(&class, ""),
        Some(RegValue::Sz("Vendor Server 3".into()))
    );
    unregister(&regs, &d).unwrap();
    assert_eq!(dump(&regs), before);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn a_server_registered_later_under_the_same_class_keeps_its_entries() {
    let regs = memory();
    let mut d = server(9);
    d.keep_existing = true;
    register(&regs, &d).unwrap();
    // Another product registers the class as an EXE server afterwards, writing the same values.
    let class = class_key(&d.clsid);
    regs.write
        .set_value(
            &format!("{class}\\LocalServer32"),
            "",
            &RegValue::Sz("C:\\other.exe".into()),
        )
        .unwrap();
    let with_other = dump(&regs);
    unregister(&regs, &d).unwrap();
    assert!(!regs.write.key_exists(&d.module_key()));
    let s = |k: &str| regs.write.value(k, "").and_then(|v| v.as_str().map(str::to_string));
    assert_eq!(s(&class).as_deref(), Some("Vendor Server 9"));
    assert_eq!(s("Vendor.Server9.1\\CLSID"), Some(d.clsid.to_string()));
    assert!(regs
        .write
        .key_exists(&format!("{class}\\Implemented Categories\\{CATID_OPCDAServer20}")));
    assert_ne!(dump(&regs), with_other);
    // Registering again and unregistering keeps it so.
    register(&regs, &d).unwrap();
    unregister(&regs, &d).unwrap();
    assert_eq!(s("Vendor.Server9.1\\CLSID"), Some(d.clsid.to_string()));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn a_shared_category_keeps_its_description() {
    let regs = memory();
    let empty = dump(&regs);
    let (a, b) = (server(4), server(5));
    register(&regs, &a).unwrap();
    let only_a = dump(&regs);
    register(&regs, &b).unwrap();
    unregister(&regs, &a).unwrap();
    let key = format!("Component Categories\\{CATID_OPCDAServer20}");
    assert!(
        regs.write.value(&key, "409").is_some(),
        "b still implements the category"
    );
    unregister(&regs, &b).unwrap();
    // a created the category; with b gone nobody uses it, but a's record was consumed already, so the
    // description stays: created by a, kept for b.
    assert!(regs.write.value(&key, "409").is_some());
    assert_ne!(dump(&regs), empty);
    // In the order of registration's reverse, everything goes.
    let regs = memory();
    register(&regs, &a).unwrap();
    register(&regs, &b).unwrap();
    unregister(&regs, &b).unwrap();
    assert_eq!(dump(&regs), only_a);
    unregister(&regs, &a).unwrap();
    assert_eq!(dump(&regs), empty);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn unregistration_without_a_ledger_removes_only_matching_values() {
    let regs = memory();
    let d = server(6);
    register(&regs, &d).unwrap();
    regs.write.delete_value(&d.module_key(), LEDGER).unwrap();
    regs.write
        .set_value("Vendor.Server6.1", "Extra", &RegValue::Sz("kept".into()))
        .unwrap();
    unregister(&regs, &d).unwrap();
    assert!(!regs.write.key_exists(&class_key(&d.clsid)));
    assert_eq!(
        regs.write.values("Vendor.Server6.1"),
        vec![("Extra".into(), RegValue::Sz("kept".into()))]
    );
    assert_eq!(unregister(&memory(), &d), Err(REGDB_E_KEYMISSING));
}

/// The browser's registration (service/opccomn_browser.c): OpcEnum's class as an EXE server with its
/// own AppID.
fn browser() -> ServerDescription {
    ServerDescription {
        clsid: GUID::from_u128(0x13486D51_4821_11D2_A494_3CB306C10000),
        local: true,
        prog_id: "OPC.ServerList.1".into(),
        version_independent_prog_id: Some("OPC.ServerList".into()),
        user_type: "Opc ServerList Class".into(),
        module_path: Some("C:\\Program Files\\OPC Tools\\opccomn_browser.exe".into()),
        app_id: Some(GUID::from_u128(0xCCD63ADF_D02D_46DD_B170_FA6E0F086FE3)),
        access_permission: Some("O:BAG:BAD:(A;;0x7;;;AU)(A;;0x7;;;SY)".into()),
        launch_permission: Some("O:BAG:BAD:(A;;0x1F;;;AU)(A;;0x1F;;;SY)".into()),
        authentication_level: Some(5),
        ..Default::default()
    }
}

/// What the OPC Foundation's OpcEnum.exe registers for itself, with its program at `path`.
fn opcenum(path: &str) -> String {
    let path = path.replace('\\', "\\\\").replace('"', "\\\"");
    format!(
        "REGEDIT4\n\
         [HKCR\\CLSID\\{{13486D51-4821-11D2-A494-3CB306C10000}}]\n@=\"OpcServerList Class\"\n\
         \"AppID\"=\"{{13486D44-4821-11D2-A494-3CB306C10000}}\"\n\
         [HKCR\\CLSID\\{{13486D51-4821-11D2-A494-3CB306C10000}}\\LocalServer32]\n@=\"{path}\"\n\
         [HKCR\\CLSID\\{{13486D51-4821-11D2-A494-3CB306C10000}}\\ProgID]\n@=\"OPC.ServerList.1\"\n\
         [HKCR\\AppID\\{{13486D44-4821-11D2-A494-3CB306C10000}}]\n@=\"OpcEnum\"\n\
         [HKCR\\AppID\\OpcEnum.exe]\n\"AppID\"=\"{{13486D44-4821-11D2-A494-3CB306C10000}}\"\n\
         [HKCR\\OPC.ServerList.1]\n@=\"OpcServerList Class\"\n\
         [HKCR\\OPC.ServerList.1\\CLSID]\n@=\"{{13486D51-4821-11D2-A494-3CB306C10000}}\"\n\
         [HKCR\\OPC.ServerList]\n@=\"OpcServerList Class\"\n\
         [HKCR\\OPC.ServerList\\CLSID]\n@=\"{{13486D51-4821-11D2-A494-3CB306C10000}}\"\n\
         [HKCR\\OPC.ServerList\\CurVer]\n@=\"OPC.ServerList.1\"\n"
    )
}

/// Every value of `part` (keys and values as (key, name, value), case as written) is in `whole`.
fn holds_all(whole: &Registries, part: &Registries) {
    for (key, values) in dump(part) {
        for (name, value) in values {
            assert_eq!(whole.write.value(&key, &name), Some(value), "{key} {name:?}");
        }
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn unregistration_leaves_a_server_installed_later_under_the_same_class() {
    // Browser registered, then OpcEnum installed over it, then the browser unregistered.
    let regs = memory();
    let d = browser();
    register(&regs, &d).unwrap();
    regfile::apply(&*regs.write, &opcenum("C:\\Windows\\System32\\OpcEnum.exe")).unwrap();
    unregister(&regs, &d).unwrap();
    let only_opcenum = memory();
    regfile::apply(&*only_opcenum.write, &opcenum("C:\\Windows\\System32\\OpcEnum.exe")).unwrap();
    holds_all(&regs, &only_opcenum);
    // This registration's own keys are gone, its record too.
    assert!(!regs.write.key_exists("AppID\\{CCD63ADF-D02D-46DD-B170-FA6E0F086FE3}"));
    assert!(!regs.write.key_exists("AppID\\opccomn_browser.exe"));
    assert_eq!(regs.write.value(&d.module_key(), LEDGER), None);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn unregistration_never_writes_a_stale_value_over_a_newer_registration() {
    // OpcEnum installed; the browser takes over (replacing its values); OpcEnum re-registers at a
    // new path; the browser unregisters.
    for rewrite_all in [true, false] {
        let regs = memory();
        regfile::apply(&*regs.write, &opcenum("C:\\Windows\\System32\\OpcEnum.exe")).unwrap();
        let d = browser();
        register(&regs, &d).unwrap();
        let new_path = "\"D:\\OPC Core\\OpcEnum.exe\"";
        if rewrite_all {
            regfile::apply(&*regs.write, &opcenum(new_path)).unwrap();
        } else {
            regs.write
                .set_value(&d.module_key(), "", &RegValue::Sz(new_path.into()))
                .unwrap();
        }
        unregister(&regs, &d).unwrap();
        let expected = memory();
        regfile::apply(&*expected.write, &opcenum(new_path)).unwrap();
        // Every value OpcEnum wrote holds what it wrote last (the values the browser replaced and that
        // still held its data got OpcEnum's back).
        holds_all(&regs, &expected);
        assert!(!regs.write.key_exists("AppID\\{CCD63ADF-D02D-46DD-B170-FA6E0F086FE3}"));
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn values_rewritten_since_registration_stay() {
    let regs = memory();
    let mut d = server(10);
    d.local = true;
    d.app_id = Some(GUID::from_u128(10));
    d.run_as = Some("Interactive User".into());
    register(&regs, &d).unwrap();
    let app = format!("AppID\\{}", GUID::from_u128(10));
    let category = format!("Component Categories\\{CATID_OPCDAServer20}");
    // An administrator changes the account; another product rewrites the category's description and
    // the version-independent ProgID's current version.
    regs.write
        .set_value(&app, "RunAs", &RegValue::Sz("OPC Account".into()))
        .unwrap();
    regs.write
        .set_value(&category, "409", &RegValue::Sz("Data Access 2".into()))
        .unwrap();
    regs.write
        .set_value("Vendor.Server10\\CurVer", "", &RegValue::Sz("Vendor.Server10.2".into()))
        .unwrap();
    unregister(&regs, &d).unwrap();
    let s = |k: &str, n: &str| regs.write.value(k, n).and_then(|v| v.as_str().map(str::to_string));
    assert_eq!(s(&app, "RunAs").as_deref(), Some("OPC Account"));
    assert_eq!(s(&app, ""), None, "the description it wrote goes");
    assert_eq!(s(&category, "409").as_deref(), Some("Data Access 2"));
    assert_eq!(s("Vendor.Server10\\CurVer", "").as_deref(), Some("Vendor.Server10.2"));
    assert!(!regs.write.key_exists(&class_key(&d.clsid)));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn a_registration_moved_to_a_new_path_unregisters_completely() {
    let regs = memory();
    let empty = dump(&regs);
    let mut d = browser();
    register(&regs, &d).unwrap();
    d.module_path = Some("D:\\Tools\\opccomn_browser.exe".into());
    register(&regs, &d).unwrap();
    assert_eq!(
        regs.write.value(&d.module_key(), ""),
        Some(RegValue::Sz("\"D:\\Tools\\opccomn_browser.exe\"".into()))
    );
    unregister(&regs, &d).unwrap();
    assert_eq!(dump(&regs), empty);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn registrations_of_earlier_versions_still_unregister() {
    // Before, the ledger did not record the data written, and LocalServer32 was written unquoted.
    let regs = memory();
    let empty = dump(&regs);
    let d = browser();
    register(&regs, &d).unwrap();
    let old: Vec<String> = read_ledger(&*regs.write, &d.module_key())
        .unwrap()
        .into_iter()
        .map(|e| match e {
            Entry::Added(k, n, _) => Entry::Added(k, n, None),
            Entry::Replaced(k, n, o, _) => Entry::Replaced(k, n, o, None),
            e => e,
        })
        .map(|e| e.encode())
        .collect();
    let module = d.module_key();
    regs.write
        .set_value(&module, LEDGER, &RegValue::Sz(old.join(";")))
        .unwrap();
    regs.write
        .set_value(&module, "", &RegValue::Sz(d.module_path.clone().unwrap()))
        .unwrap();
    unregister(&regs, &d).unwrap();
    assert_eq!(dump(&regs), empty);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn command_lines_are_quoted_and_dll_paths_are_not() {
    let regs = memory();
    let mut exe = browser();
    register(&regs, &exe).unwrap();
    // (CWE-428: unquoted, `C:\Program Files\OPC Tools\opccomn_browser.exe` starts C:\Program.exe.)
    assert_eq!(
        regs.write.value(&exe.module_key(), ""),
        Some(RegValue::Sz(
            "\"C:\\Program Files\\OPC Tools\\opccomn_browser.exe\"".into()
        ))
    );
    assert!(regs.write.key_exists("AppID\\opccomn_browser.exe"));
    unregister(&regs, &exe).unwrap();
    // A command line given already quoted (with arguments) is kept as given.
    exe.module_path = Some("\"C:\\Program Files\\OPC Tools\\svc.exe\" -service".into());
    register(&regs, &exe).unwrap();
    assert_eq!(
        regs.write.value(&exe.module_key(), ""),
        Some(RegValue::Sz(exe.module_path.clone().unwrap()))
    );
    assert!(regs.write.key_exists("AppID\\svc.exe"));
    unregister(&regs, &exe).unwrap();
    // An in-process server's InprocServer32 is a file path that COM loads as it is.
    let dll = server(11);
    register(&regs, &dll).unwrap();
    assert_eq!(
        regs.write.value(&dll.module_key(), ""),
        Some(RegValue::Sz("C:\\Program Files\\Vendor\\server.dll".into()))
    );
}

#[test]
fn ledger_entries_survive_awkward_names() {
    for e in [
        Entry::Key("A;B|C%3B".into()),
        Entry::Added("K".into(), "".into(), None),
        Entry::Added("K".into(), "".into(), Some("C:\\a|b;c%".into())),
        Entry::Replaced("K".into(), "n|;".into(), "old;data%".into(), None),
        Entry::Replaced("K".into(), "n".into(), "old".into(), Some("".into())),
        Entry::Added("K".into(), "AuthenticationLevel".into(), Some(RegValue::Dword(5))),
        Entry::Added(
            "K".into(),
            "AccessPermission".into(),
            Some(RegValue::Other {
                kind: 3,
                bytes: vec![1, 0, 0x7C, 0x3B, 0x25, 0xFF],
            }),
        ),
        Entry::Added(
            "K".into(),
            "Odd".into(),
            Some(RegValue::Other {
                kind: 11,
                bytes: vec![],
            }),
        ),
        Entry::Replaced("K".into(), "n".into(), "old|;".into(), Some(RegValue::Dword(u32::MAX))),
        Entry::Replaced("K".into(), "n".into(), RegValue::Dword(2), Some(RegValue::Dword(5))),
        Entry::Replaced(
            "K".into(),
            "n".into(),
            RegValue::ExpandSz("%x%".into()),
            Some("y".into()),
        ),
        Entry::OtherServer,
    ] {
        assert_eq!(Entry::decode(&e.encode()), Some(e.clone()));
    }
    // Ledgers written before the data was recorded read as such.
    assert_eq!(Entry::decode("VK|n"), Some(Entry::Added("K".into(), "n".into(), None)));
    assert_eq!(
        Entry::decode("RK|n|old"),
        Some(Entry::Replaced("K".into(), "n".into(), "old".into(), None))
    );
    // String entries keep the form they always had (older libraries read them); typed ones have
    // fields older libraries do not know, so they skip them and leave those values alone.
    assert_eq!(
        Entry::Added("K".into(), "n".into(), Some("x".into())).encode(),
        "VK|n|x"
    );
    assert_eq!(
        Entry::Added("K".into(), "n".into(), Some(RegValue::Dword(5))).encode(),
        "VK|n|5|4"
    );
    for bad in [
        "VK|n|5|x",
        "VK|n|x|4",
        "VK|n|abc|3",
        "VK|n|zz|3",
        "RK|n|1|2|4",
        "RK|n|a|b|4|4",
    ] {
        assert_eq!(Entry::decode(bad), None, "{bad}");
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn exported_registration_applies_to_the_same_registry() {
    let d = server(7);
    let text = export_registration(&d).unwrap();
    assert!(text.starts_with("Windows Registry Editor Version 5.00\r\n"));
    let regs = memory();
    regfile::apply(&*regs.write, &text).unwrap();
    let direct = memory();
    register(&direct, &d).unwrap();
    assert_eq!(dump(&regs), dump(&direct));
    unregister(&regs, &d).unwrap();
    assert_eq!(dump(&regs), dump(&memory()));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn bad_descriptions_are_refused() {
    let regs = memory();
    let empty = dump(&regs);
    for bad in ["", "A\\B", " "] {
        let mut d = server(8);
        d.prog_id = bad.into();
        assert_eq!(d.check(), Err(E_INVALIDARG));
        assert_eq!(register(&regs, &d), Err(E_INVALIDARG), "ProgID {bad:?}");
    }
    let mut d = server(8);
    d.module_path = Some(String::new());
    assert_eq!(d.check(), Err(E_INVALIDARG));
    assert_eq!(register(&regs, &d), Err(E_INVALIDARG), "empty module path");
    // The refused registrations wrote nothing (the same registry takes a good one).
    assert_eq!(dump(&regs), empty);
    register(&regs, &server(8)).unwrap();
    assert_ne!(dump(&regs), empty);
}

/// A NULL description is refused before anything is read (unsafe code: runs under Miri).
#[test]
fn a_null_description_is_refused() {
    // SAFETY: NULL is allowed.
    assert_eq!(unsafe { ServerDescription::read(ptr::null()) }.err(), Some(Fail::Null));
}

/// Reads the whole registry behind a handle through `OpcRegistryExport`, as C callers do.
///
/// # Safety
/// `reg` is a live handle.
unsafe fn export_through_the_handle(reg: *const crate::registry::OpcRegistry) -> String {
    let mut text = ptr::null_mut();
    // SAFETY: a live handle, a NULL key (the whole registry) and a writable out-pointer.
    let hr = unsafe { crate::registry::regfile::OpcRegistryExport(reg, ptr::null(), &mut text) };
    assert_eq!(hr, crate::com::S_OK);
    // SAFETY: the library returned a NUL-terminated string, freed once here.
    unsafe {
        let s = String::from_utf16(crate::com::wstr::wstr_units(text, usize::MAX).unwrap()).unwrap();
        crate::com::alloc::OpcTaskMemFree(text.cast());
        s
    }
}

/// The C entry points read every field of the caller's structure and its arrays, write through a
/// registry handle, and refuse a structure of another size after reading only its size (under Miri a
/// read past the 4-byte allocation given would be reported).
#[test]
fn the_c_entry_points_read_the_structure_and_write_through_a_handle() {
    use crate::registry::{OpcRegistryCreateMemory, OpcRegistryRelease};
    let w = |s: &str| -> Vec<u16> { s.encode_utf16().chain([0]).collect() };
    let (prog, vi, user, path) = (
        w("Vendor.CServer.1"),
        w("Vendor.CServer"),
        w("Vendor C Server"),
        w("C:\\Vendor\\c.exe"),
    );
    let (vendor, text, run_as) = (w("Vendor Inc."), w("Vendor Special Servers"), w("Interactive User"));
    let clsid = GUID::from_u128(0xC1000000_1111_2222_3333_444455556601);
    let app_id = GUID::from_u128(0xC1000000_1111_2222_3333_444455556602);
    let cats = [
        CATID_OPCDAServer20,
        GUID::from_u128(0xC1000000_1111_2222_3333_444455556603),
    ];
    let texts = [ptr::null(), text.as_ptr()];
    let make = || OpcServerRegistration {
        struct_size: core::mem::size_of::<OpcServerRegistration>() as u32,
        server_type: OpcServerType::Local as u32,
        clsid,
        prog_id: prog.as_ptr(),
        version_independent_prog_id: vi.as_ptr(),
        user_type: user.as_ptr(),
        module_path: path.as_ptr(),
        threading_model: ptr::null(),
        implemented_categories: cats.as_ptr(),
        implemented_category_count: 2,
        implemented_category_descriptions: texts.as_ptr(),
        required_categories: cats[1..].as_ptr(),
        required_category_count: 1,
        da10_vendor: vendor.as_ptr(),
        app_id: &app_id,
        app_id_run_as: run_as.as_ptr(),
        app_id_local_service: ptr::null(),
        app_id_dll_surrogate: ptr::null(),
        flags: 0,
        app_id_access_permission: ptr::null(),
        app_id_launch_permission: ptr::null(),
        app_id_authentication_level: 0,
    };
    let r = make();
    let mut reg = ptr::null_mut();
    // SAFETY: every pointer in `r` is NULL or points at live, NUL-terminated or counted data; `reg`
    // is a live handle until released at the end.
    unsafe {
        assert_eq!(OpcRegistryCreateMemory(&mut reg), crate::com::S_OK);
        let empty = export_through_the_handle(reg);
        assert_eq!(OpcRegisterServer(&r, reg), crate::com::S_OK);
        let value = |key: &str, name: Option<&str>| {
            let key = w(key);
            let name = name.map(w);
            let mut data = ptr::null_mut();
            let name_ptr = name.as_ref().map_or(ptr::null(), |n| n.as_ptr());
            match crate::registry::OpcRegistryGetString(reg, key.as_ptr(), name_ptr, &mut data).get() {
                crate::com::S_OK => {
                    let s = String::from_utf16(crate::com::wstr::wstr_units(data, usize::MAX).unwrap()).unwrap();
                    crate::com::alloc::OpcTaskMemFree(data.cast());
                    Some(s)
                }
                hr => {
                    assert!(data.is_null(), "{hr:#x}");
                    None
                }
            }
        };
        let class = format!("CLSID\\{clsid}");
        assert_eq!(
            value(&format!("{class}\\LocalServer32"), None).as_deref(),
            Some("\"C:\\Vendor\\c.exe\"")
        );
        assert_eq!(value(&format!("{class}\\InprocServer32"), None), None);
        assert_eq!(
            value(&format!("AppID\\{app_id}"), Some("RunAs")).as_deref(),
            Some("Interactive User")
        );
        assert_eq!(
            value(&format!("Component Categories\\{}", cats[1]), Some("409")).as_deref(),
            Some("Vendor Special Servers")
        );
        assert_eq!(
            value("Vendor.CServer.1\\OPC\\Vendor", None).as_deref(),
            Some("Vendor Inc.")
        );
        assert_eq!(
            value("Vendor.CServer\\CurVer", Some("")).as_deref(),
            Some("Vendor.CServer.1")
        );
        assert_eq!(OpcUnregisterServer(&r, reg), crate::com::S_OK);
        assert_eq!(export_through_the_handle(reg), empty);
        // Only the size field of a structure of another size is read, and nothing is written.
        let size_only: Box<u32> = Box::new(4);
        let short = (&*size_only as *const u32).cast::<OpcServerRegistration>();
        assert_eq!(OpcRegisterServer(short, reg), E_INVALIDARG);
        assert_eq!(OpcRegisterServer(ptr::null(), reg), E_INVALIDARG);
        // More categories than allowed: refused before the array is read (it holds two).
        let mut bad = make();
        bad.implemented_category_count = 257;
        assert_eq!(OpcRegisterServer(&bad, reg), E_INVALIDARG);
        assert_eq!(export_through_the_handle(reg), empty);
        OpcRegistryRelease(reg);
    }
}
