//! The AppID's DCOM security at registration: `AuthenticationLevel` (PKT_INTEGRITY unless given),
//! `AccessPermission` / `LaunchPermission` from SDDL, and unregistration taking back exactly those.

use super::ledger::read_ledger;
use super::tests::{memory, server};
use super::*;
use crate::com::{E_INVALIDARG, GUID};
use crate::registry::sddl::{bytes_to_sddl, sddl_to_bytes};
use crate::registry::{class_key, regfile, RegValue};
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

// ---- One AppID named by several classes (one product, several classes: the usual layout) ----------

const SHARED_APP_ID: GUID = GUID::from_u128(0x5A00);
const OTHER_ACCESS: &str = "O:BAG:BAD:(A;;0x7;;;SY)";

/// Class `n` of a product whose classes share one AppID and its security; `exe` is its program.
fn sharing(n: u128, exe: &str) -> ServerDescription {
    let mut d = local_server(n);
    d.implemented.clear();
    d.module_path = Some(format!("C:\\Vendor\\{exe}"));
    d.app_id = Some(SHARED_APP_ID);
    d.access_permission = Some(ACCESS.into());
    d.launch_permission = Some(LAUNCH.into());
    d
}

/// A registry held in memory with the root keys every Windows registry has (`CLSID`, `AppID`), which
/// no registration created and none removes.
fn machine() -> Registries {
    let regs = memory();
    for root in ["CLSID", "AppID"] {
        regs.write.create_key(root).unwrap();
    }
    regs
}

/// The AppID key's values, by name (empty when the key is missing).
fn app_values(regs: &Registries) -> Vec<(String, RegValue)> {
    let mut v = regs.write.values(&format!("AppID\\{SHARED_APP_ID}"));
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

fn binary(sddl: &str) -> RegValue {
    RegValue::Other {
        kind: 3,
        bytes: sddl_to_bytes(sddl).unwrap(),
    }
}

/// The orders to unregister two classes in: both natively, one under Miri (where each registration
/// takes seconds; the code has no `unsafe` of its own, the native run checks the other order).
fn orders() -> &'static [[usize; 2]] {
    if cfg!(miri) {
        &[[1, 0]]
    } else {
        &[[0, 1], [1, 0]]
    }
}

/// Registers every class in order, then unregisters them in `order`: while any is left the AppID is
/// what it was with all of them, and the last one's unregistration leaves the registry as it was.
fn register_all_then_unregister_in(regs: &Registries, classes: &[ServerDescription], order: &[usize]) {
    let before = super::tests::dump(regs);
    for d in classes {
        register(regs, d).unwrap();
    }
    let whole = app_values(regs);
    assert!(whole.iter().any(|(n, _)| n == "AuthenticationLevel"));
    for (i, &k) in order.iter().enumerate() {
        unregister(regs, &classes[k]).unwrap();
        if i + 1 < order.len() {
            assert_eq!(
                app_values(regs),
                whole,
                "unregistered {:?}: the others still name the AppID",
                &order[..=i]
            );
        }
    }
    assert_eq!(super::tests::dump(regs), before, "order {order:?}");
}

#[test]
fn a_shared_app_id_stays_whole_while_a_class_names_it_and_goes_with_the_last() {
    let classes = [sharing(0x10, "a.exe"), sharing(0x11, "b.exe"), sharing(0x12, "c.exe")];
    // Two classes, either order; then three, in every order (under Miri one order of three: the
    // other tests have two).
    if !cfg!(miri) {
        for order in orders() {
            register_all_then_unregister_in(&machine(), &classes[..2], order);
        }
    }
    let three: &[[usize; 3]] = if cfg!(miri) {
        &[[1, 0, 2]]
    } else {
        &[[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]]
    };
    for order in three {
        register_all_then_unregister_in(&machine(), &classes, order);
    }
    if cfg!(miri) {
        return;
    }
    // The AppID's values stay as a class that still names it registered them.
    let regs = machine();
    register(&regs, &classes[0]).unwrap();
    register(&regs, &classes[1]).unwrap();
    unregister(&regs, &classes[0]).unwrap();
    let app = format!("AppID\\{SHARED_APP_ID}");
    assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(5)));
    assert_eq!(regs.write.value(&app, "AccessPermission"), Some(binary(ACCESS)));
    assert_eq!(regs.write.value(&app, "LaunchPermission"), Some(binary(LAUNCH)));
    // The class that went takes its own program's key with it; the other's stays.
    assert!(!regs.write.key_exists("AppID\\a.exe"));
    assert!(regs.write.key_exists("AppID\\b.exe"));
    // Registered again beside the one that stayed, it leaves nothing once both are gone, in either
    // order.
    for order in orders() {
        let regs = machine();
        let before = super::tests::dump(&regs);
        register(&regs, &classes[0]).unwrap();
        register(&regs, &classes[1]).unwrap();
        unregister(&regs, &classes[0]).unwrap();
        register(&regs, &classes[0]).unwrap();
        unregister(&regs, &classes[order[0]]).unwrap();
        unregister(&regs, &classes[order[1]]).unwrap();
        assert_eq!(super::tests::dump(&regs), before, "order {order:?}");
    }
}

#[test]
fn classes_asking_for_different_security_share_what_the_latest_registration_wrote() {
    let a = sharing(0x20, "a.exe");
    let mut b = sharing(0x21, "b.exe");
    b.access_permission = Some(OTHER_ACCESS.into());
    b.authentication_level = Some(6);
    let app = format!("AppID\\{SHARED_APP_ID}");
    for order in orders() {
        let regs = machine();
        register(&regs, &a).unwrap();
        register(&regs, &b).unwrap();
        // One AppID, one security: the latest registration's.
        assert_eq!(regs.write.value(&app, "AccessPermission"), Some(binary(OTHER_ACCESS)));
        assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(6)));
        unregister(&regs, [&a, &b][order[0]]).unwrap();
        // It stays so while either class is registered.
        assert_eq!(regs.write.value(&app, "AccessPermission"), Some(binary(OTHER_ACCESS)));
        assert_eq!(regs.write.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(6)));
        unregister(&regs, [&a, &b][order[1]]).unwrap();
        assert!(regs.write.subkeys("AppID").is_empty(), "order {order:?}");
    }
    if cfg!(miri) {
        return;
    }
    // Registering again with other settings follows the latest, and the last unregistration still
    // leaves nothing.
    let regs = machine();
    register(&regs, &a).unwrap();
    register(&regs, &b).unwrap();
    register(&regs, &a).unwrap();
    assert_eq!(regs.write.value(&app, "AccessPermission"), Some(binary(ACCESS)));
    unregister(&regs, &b).unwrap();
    assert_eq!(regs.write.value(&app, "AccessPermission"), Some(binary(ACCESS)));
    unregister(&regs, &a).unwrap();
    assert_eq!(super::tests::dump(&regs), super::tests::dump(&machine()));
}

#[test]
fn values_found_before_the_first_registration_come_back_after_the_last() {
    let classes = [sharing(0x30, "server.exe"), sharing(0x31, "server.exe")];
    let app = format!("AppID\\{SHARED_APP_ID}");
    for order in orders() {
        let regs = machine();
        // An older installation left level 2 and its own description; an administrator set RunAs;
        // another product keeps a value of its own there.
        let w = &regs.write;
        w.set_value(&app, "", &"Old Vendor Server".into()).unwrap();
        w.set_value(&app, "AuthenticationLevel", &RegValue::Dword(2)).unwrap();
        w.set_value(&app, "RunAs", &"Interactive User".into()).unwrap();
        w.set_value(&app, "TheirValue", &RegValue::Dword(7)).unwrap();
        register_all_then_unregister_in(&regs, &classes, order);
        assert_eq!(w.value(&app, "AuthenticationLevel"), Some(RegValue::Dword(2)));
        assert_eq!(w.value(&app, "TheirValue"), Some(RegValue::Dword(7)));
    }
    if cfg!(miri) {
        return;
    }
    // A value rewritten by someone else while the classes were registered stays theirs.
    let regs = machine();
    register(&regs, &classes[0]).unwrap();
    register(&regs, &classes[1]).unwrap();
    regs.write
        .set_value(&app, "AuthenticationLevel", &RegValue::Dword(6))
        .unwrap();
    unregister(&regs, &classes[0]).unwrap();
    unregister(&regs, &classes[1]).unwrap();
    assert_eq!(
        app_values(&regs),
        vec![("AuthenticationLevel".to_string(), RegValue::Dword(6))]
    );
}

#[test]
fn classes_of_one_program_keep_its_key_until_the_last() {
    let classes = [sharing(0x40, "server.exe"), sharing(0x41, "server.exe")];
    for order in orders() {
        let regs = machine();
        register(&regs, &classes[0]).unwrap();
        register(&regs, &classes[1]).unwrap();
        unregister(&regs, &classes[order[0]]).unwrap();
        assert_eq!(
            regs.write.value("AppID\\server.exe", "AppID"),
            Some(RegValue::Sz(SHARED_APP_ID.to_string())),
            "the other class's program still maps to the AppID"
        );
        unregister(&regs, &classes[order[1]]).unwrap();
        assert_eq!(super::tests::dump(&regs), super::tests::dump(&machine()));
    }
}

#[test]
fn an_app_id_another_product_also_names_is_left_to_it() {
    let regs = machine();
    let ours = sharing(0x50, "server.exe");
    register(&regs, &ours).unwrap();
    // A class registered by other means (no record of ours) names the same AppID.
    let theirs = format!("CLSID\\{}", GUID::from_u128(0x5EED_5EED));
    regs.write
        .set_value(&theirs, "AppID", &SHARED_APP_ID.to_string().as_str().into())
        .unwrap();
    let whole = app_values(&regs);
    unregister(&regs, &ours).unwrap();
    assert_eq!(app_values(&regs), whole);
    assert!(!regs.write.key_exists(&class_key(&ours.clsid)));
}

#[test]
fn records_of_earlier_versions_join_by_their_data() {
    // Registered by a version that recorded a shared value back only to the previous registration:
    // the second class's record of the user type says it replaced the first one's.
    let classes = [sharing(0x60, "server.exe"), sharing(0x61, "server.exe")];
    let first = class_key(&classes[0].clsid);
    for order in orders() {
        let regs = machine();
        let before = super::tests::dump(&regs);
        register(&regs, &classes[0]).unwrap();
        // (The second registration does not see the first class name the AppID.)
        let named = regs.write.value(&first, "AppID").unwrap();
        regs.write.delete_value(&first, "AppID").unwrap();
        register(&regs, &classes[1]).unwrap();
        regs.write.set_value(&first, "AppID", &named).unwrap();
        let ledger = read_ledger(&*regs.write, &classes[1].module_key()).unwrap();
        let app = format!("AppID\\{SHARED_APP_ID}");
        assert!(ledger.contains(&super::Entry::Replaced(
            app.clone(),
            String::new(),
            "Vendor Server 96".into(),
            Some("Vendor Server 97".into())
        )));
        let whole = app_values(&regs);
        unregister(&regs, &classes[order[0]]).unwrap();
        assert_eq!(app_values(&regs), whole);
        unregister(&regs, &classes[order[1]]).unwrap();
        assert_eq!(super::tests::dump(&regs), before, "order {order:?}");
    }
}
