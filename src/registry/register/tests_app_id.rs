//! The AppID's DCOM security at registration: `AuthenticationLevel` (PKT_INTEGRITY unless given),
//! `AccessPermission` / `LaunchPermission` from SDDL, and unregistration taking back exactly those.

use super::ledger::read_ledger;
use super::tests::{memory, server};
use super::*;
use crate::com::{E_INVALIDARG, GUID};
use crate::registry::sddl::{bytes_to_sddl, sddl_to_bytes};
use crate::registry::{regfile, RegValue};
use core::ptr;

const ACCESS: &str = "O:BAG:BAD:(A;;0x7;;;AU)(A;;0x7;;;SY)";
const LAUNCH: &str = "O:BAG:BAD:(A;;0x1F;;;BA)(A;;0x1F;;;SY)(A;;0xB;;;IU)";

fn local_server(n: u128) -> ServerDescription {
    let mut d = server(n);
    d.local = true;
    d.threading_model = None;
    d.module_path = Some("C:\\Vendor\\server.exe".into());
    d.app_id = Some(GUID::from_u128(0xA0 + n));
    d
}

fn app_key(d: &ServerDescription) -> String {
    format!("AppID\\{}", d.app_id.unwrap())
}

/// The SDDL of a REG_BINARY value, or None.
fn sddl_of(value: Option<RegValue>) -> Option<String> {
    match value? {
        RegValue::Other { kind: 3, bytes } => bytes_to_sddl(&bytes).ok(),
        _ => None,
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn an_app_id_gets_pkt_integrity_unless_told_otherwise() {
    let regs = memory();
    let d = local_server(1);
    register(&regs, &d).unwrap();
    let app = app_key(&d);
    assert_eq!(
        regs.write.value(&app, "AuthenticationLevel"),
        Some(RegValue::Dword(OPC_AUTHN_LEVEL_PKT_INTEGRITY))
    );
    assert_eq!(
        regs.write.value(&app, "AccessPermission"),
        None,
        "no SDDL, no descriptor"
    );
    assert_eq!(regs.write.value(&app, "LaunchPermission"), None);
    // Without an AppID nothing of it is written.
    let regs = memory();
    register(&regs, &server(2)).unwrap();
    assert!(regs.write.subkeys("AppID").is_empty());
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn levels_and_permissions_are_written_as_given_and_taken_back_exactly() {
    let regs = memory();
    let before = regfile::export(&*regs.write, "").unwrap();
    let mut d = local_server(3);
    d.authentication_level = Some(6);
    d.access_permission = Some(ACCESS.into());
    d.launch_permission = Some(LAUNCH.into());
    register(&regs, &d).unwrap();
    let app = app_key(&d);
    assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(6)));
    let access = regs.write.value(&app, "AccessPermission");
    assert_eq!(
        access,
        Some(RegValue::Other {
            kind: 3,
            bytes: sddl_to_bytes(ACCESS).unwrap()
        })
    );
    assert_eq!(
        sddl_of(access).as_deref(),
        Some("O:BAG:BAD:(A;;CCDCLC;;;AU)(A;;CCDCLC;;;SY)")
    );
    assert_eq!(
        sddl_of(regs.write.value(&app, "LaunchPermission")).as_deref(),
        Some("O:BAG:BAD:(A;;CCDCLCSWRP;;;BA)(A;;CCDCLCSWRP;;;SY)(A;;CCDCSW;;;IU)")
    );
    // The .reg export holds them as dcomcnfg's values are exported.
    let text = regfile::export(&*regs.write, "").unwrap();
    assert!(text.contains("\"AuthenticationLevel\"=dword:00000006\r\n"), "{text}");
    assert!(text.contains("\"AccessPermission\"=hex:01,00,04,80,"), "{text}");
    // Registering again changes nothing; unregistering leaves the registry as it was.
    register(&regs, &d).unwrap();
    assert_eq!(regfile::export(&*regs.write, "").unwrap(), text);
    unregister(&regs, &d).unwrap();
    assert_eq!(regfile::export(&*regs.write, "").unwrap(), before);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn values_another_installer_changed_stay() {
    let regs = memory();
    let mut d = local_server(4);
    d.access_permission = Some(ACCESS.into());
    d.launch_permission = Some(LAUNCH.into());
    register(&regs, &d).unwrap();
    let app = app_key(&d);
    // An administrator (or another installer) raises the level and rewrites the access permission;
    // the launch permission is left as registration wrote it.
    let theirs = RegValue::Other {
        kind: 3,
        bytes: sddl_to_bytes("O:BAG:BAD:(A;;0x7;;;BA)").unwrap(),
    };
    regs.write
        .set_value(&app, "AuthenticationLevel", &RegValue::Dword(6))
        .unwrap();
    regs.write.set_value(&app, "AccessPermission", &theirs).unwrap();
    unregister(&regs, &d).unwrap();
    assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(6)));
    assert_eq!(regs.write.value(&app, "AccessPermission"), Some(theirs));
    assert_eq!(regs.write.value(&app, "LaunchPermission"), None, "still ours: removed");
    assert_eq!(regs.write.value(&app, ""), None, "the description it wrote goes");
    assert!(regs.write.key_exists(&app), "the key stays while it holds their values");
    // A value of another type under the same name is theirs too.
    let regs = memory();
    register(&regs, &d).unwrap();
    regs.write
        .set_value(&app, "AuthenticationLevel", &RegValue::Sz("5".into()))
        .unwrap();
    unregister(&regs, &d).unwrap();
    assert_eq!(
        regs.write.value(&app, "AuthenticationLevel"),
        Some(RegValue::Sz("5".into()))
    );
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn values_found_at_registration_come_back() {
    let regs = memory();
    let d = local_server(5);
    let app = app_key(&d);
    // An older installation left the AppID at CONNECT with a permission of its own.
    let old = RegValue::Other {
        kind: 3,
        bytes: sddl_to_bytes("D:(A;;0x1F;;;WD)").unwrap(),
    };
    regs.write
        .set_value(&app, "AuthenticationLevel", &RegValue::Dword(2))
        .unwrap();
    regs.write.set_value(&app, "AccessPermission", &old).unwrap();
    let mut hardened = d.clone();
    hardened.access_permission = Some(ACCESS.into());
    register(&regs, &hardened).unwrap();
    assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(5)));
    unregister(&regs, &hardened).unwrap();
    assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(2)));
    assert_eq!(regs.write.value(&app, "AccessPermission"), Some(old.clone()));
    // With OPC_REGISTRATION_KEEP_EXISTING what is there stays, and is never recorded as ours.
    let mut keep = hardened.clone();
    keep.keep_existing = true;
    register(&regs, &keep).unwrap();
    assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(2)));
    assert_eq!(regs.write.value(&app, "AccessPermission"), Some(old.clone()));
    let ledger = read_ledger(&*regs.write, &keep.module_key()).unwrap();
    assert!(!ledger.iter().any(|e| e.is_value(&app, "AuthenticationLevel")));
    unregister(&regs, &keep).unwrap();
    assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(2)));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn without_a_ledger_only_matching_values_go() {
    let regs = memory();
    let mut d = local_server(6);
    d.access_permission = Some(ACCESS.into());
    register(&regs, &d).unwrap();
    let app = app_key(&d);
    regs.write.delete_value(&d.module_key(), super::LEDGER).unwrap();
    regs.write
        .set_value(&app, "AuthenticationLevel", &RegValue::Dword(6))
        .unwrap();
    unregister(&regs, &d).unwrap();
    assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(6)));
    assert_eq!(regs.write.value(&app, "AccessPermission"), None);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn bad_security_settings_are_refused_before_anything_is_written() {
    for change in [
        (|d: &mut ServerDescription| d.authentication_level = Some(7)) as fn(&mut ServerDescription),
        |d| d.authentication_level = Some(u32::MAX),
        |d| d.access_permission = Some("D:(A;;0xB;;;AU".into()),
        |d| d.launch_permission = Some("O:BAS:(AU;SA;CC;;;WD)".into()),
        |d| d.launch_permission = Some(String::new()),
        |d| {
            d.app_id = None;
            d.authentication_level = Some(5);
        },
        |d| {
            d.app_id = None;
            d.access_permission = Some(ACCESS.into());
        },
    ] {
        let regs = memory();
        let mut d = local_server(7);
        change(&mut d);
        assert_eq!(register(&regs, &d), Err(E_INVALIDARG));
        assert!(regs.write.subkeys("").is_empty());
    }
    // Levels below PKT_INTEGRITY are written when asked for explicitly.
    for level in 1..=6 {
        let regs = memory();
        let mut d = local_server(8);
        d.authentication_level = Some(level);
        register(&regs, &d).unwrap();
        assert_eq!(
            regs.write.value(&app_key(&d), "AuthenticationLevel"),
            Some(RegValue::Dword(level))
        );
    }
}

/// Through the C API: the structure's versions (the sizes a version-1 caller passes get the
/// PKT_INTEGRITY default), the new fields, and refusals.
#[test]
fn the_c_structure_versions() {
    use crate::registry::{OpcRegistry, OpcRegistryCreateMemory, OpcRegistryGetString, OpcRegistryRelease};
    let w = |s: &str| -> Vec<u16> { s.encode_utf16().chain([0]).collect() };
    let (prog, user, path) = (w("Vendor.Sec.1"), w("Vendor Sec"), w("C:\\Vendor\\sec.exe"));
    let (access, bad) = (w(ACCESS), w("D:(A;;0xB;;;XX)"));
    let app_id = GUID::from_u128(0x5EC0);
    let make = |size: usize| OpcServerRegistration {
        struct_size: size as u32,
        server_type: OpcServerType::Local as u32,
        clsid: GUID::from_u128(0x5EC1),
        prog_id: prog.as_ptr(),
        version_independent_prog_id: ptr::null(),
        user_type: user.as_ptr(),
        module_path: path.as_ptr(),
        threading_model: ptr::null(),
        implemented_categories: ptr::null(),
        implemented_category_count: 0,
        implemented_category_descriptions: ptr::null(),
        required_categories: ptr::null(),
        required_category_count: 0,
        da10_vendor: ptr::null(),
        app_id: &app_id,
        app_id_run_as: ptr::null(),
        app_id_local_service: ptr::null(),
        app_id_dll_surrogate: ptr::null(),
        flags: 0,
        app_id_access_permission: access.as_ptr(),
        app_id_launch_permission: ptr::null(),
        app_id_authentication_level: 2,
    };
    type R = OpcServerRegistration;
    let v1_end = core::mem::offset_of!(R, flags) + 4;
    let v1_sizeof = core::mem::offset_of!(R, app_id_access_permission);
    let v2_end = core::mem::offset_of!(R, app_id_authentication_level) + 4;
    let full = core::mem::size_of::<R>();
    // SAFETY: `reg` is a live handle until released; every pointer in the structures is NULL or
    // points at live data; a shorter `struct_size` only makes the library read less of them.
    unsafe {
        let mut reg: *mut OpcRegistry = ptr::null_mut();
        assert_eq!(OpcRegistryCreateMemory(&mut reg), crate::com::S_OK);
        let regs = crate::registry::registries(reg);
        let level = || regs.write.value(&format!("AppID\\{app_id}"), "AuthenticationLevel");
        let permission = || regs.write.value(&format!("AppID\\{app_id}"), "AccessPermission");
        // Under Miri one size per version: the structure is allocated whole for every size, so the
        // second size of a version shows Miri no other memory access (the native run checks both).
        let sizes = |a: usize, b: usize| if cfg!(miri) { vec![a] } else { vec![a, b] };
        for size in sizes(v1_end, v1_sizeof) {
            // A version-1 caller knows nothing of the new fields: they are taken as zero.
            let r = make(size);
            assert_eq!(OpcRegisterServer(&r, reg), crate::com::S_OK, "size {size}");
            assert_eq!(level(), Some(RegValue::Dword(5)), "size {size}");
            assert_eq!(permission(), None);
            assert_eq!(OpcUnregisterServer(&r, reg), crate::com::S_OK);
            assert!(regs.write.subkeys("").is_empty());
        }
        for size in sizes(v2_end, full) {
            let r = make(size);
            assert_eq!(OpcRegisterServer(&r, reg), crate::com::S_OK, "size {size}");
            assert_eq!(level(), Some(RegValue::Dword(2)), "explicitly asked for");
            assert_eq!(
                sddl_of(permission()).as_deref(),
                Some("O:BAG:BAD:(A;;CCDCLC;;;AU)(A;;CCDCLC;;;SY)")
            );
            let mut text = ptr::null_mut();
            let (key, name) = (w(&format!("AppID\\{app_id}")), w("AuthenticationLevel"));
            // Not a string: the string reader refuses it (and resets its out-parameter).
            assert_ne!(
                OpcRegistryGetString(reg, key.as_ptr(), name.as_ptr(), &mut text),
                crate::com::S_OK
            );
            assert!(text.is_null());
            assert_eq!(OpcUnregisterServer(&r, reg), crate::com::S_OK);
            assert!(regs.write.subkeys("").is_empty());
        }
        for size in [0, 4, v1_end - 4, v1_end + 1, v2_end - 4, full + 8] {
            if [v1_end, v1_sizeof, v2_end, full].contains(&size) {
                continue;
            }
            assert_eq!(OpcRegisterServer(&make(size), reg), E_INVALIDARG, "size {size}");
        }
        let mut r = make(full);
        r.app_id_access_permission = bad.as_ptr();
        assert_eq!(OpcRegisterServer(&r, reg), E_INVALIDARG);
        let mut r = make(full);
        r.app_id_authentication_level = 7;
        assert_eq!(OpcRegisterServer(&r, reg), E_INVALIDARG);
        let mut r = make(full);
        r.app_id = ptr::null();
        assert_eq!(OpcRegisterServer(&r, reg), E_INVALIDARG, "security without an AppID");
        assert!(regs.write.subkeys("").is_empty());
        drop(regs);
        OpcRegistryRelease(reg);
    }
}
