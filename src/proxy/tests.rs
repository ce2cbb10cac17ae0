use super::*;
use crate::registry::memory::MemoryRegistry;

const MODULE: &str = "C:\\Program Files\\opccomn\\opccomn.dll";
/// The CLSID the stand-in for the Foundation's opccomn_ps.dll registers (MIDL's default: the first IID).
const FOUNDATION: GUID = GUID::from_u128(0x13486D50_4821_11D2_A494_3CB306C10000);

fn sz(reg: &MemoryRegistry, key: &str, name: &str) -> Option<String> {
    reg.value(key, name).and_then(|v| v.as_str().map(str::to_string))
}

/// Every key and value, for "unchanged" comparisons.
fn dump(reg: &MemoryRegistry) -> Vec<(String, String, Option<String>)> {
    let mut out = Vec::new();
    let mut stack: Vec<String> = reg.subkeys("");
    while let Some(key) = stack.pop() {
        for (name, value) in reg.values(&key) {
            out.push((
                key.to_lowercase(),
                name.to_lowercase(),
                value.as_str().map(str::to_string),
            ));
        }
        if reg.values(&key).is_empty() {
            out.push((key.to_lowercase(), String::new(), None));
        }
        stack.extend(reg.subkeys(&key).into_iter().map(|k| format!("{key}\\{k}")));
    }
    out.sort();
    out
}

/// What the Foundation's opccomn_ps.dll (or rpcrt4's NdrDllRegisterProxy for it) writes.
fn install_foundation(reg: &MemoryRegistry, interfaces: &[(&GUID, &str, u32)]) {
    let class = class_key(&FOUNDATION);
    reg.set_value(&class, "", &RegValue::Sz("PSFactoryBuffer".into()))
        .unwrap();
    reg.set_value(
        &format!("{class}\\InprocServer32"),
        "",
        &RegValue::Sz("C:\\Windows\\System32\\opccomn_ps.dll".into()),
    )
    .unwrap();
    for (iid, name, n) in interfaces {
        let key = interface_key(iid);
        reg.set_value(&key, "", &RegValue::Sz((*name).into())).unwrap();
        reg.set_value(&format!("{key}\\NumMethods"), "", &RegValue::Sz(n.to_string()))
            .unwrap();
        reg.set_value(
            &format!("{key}\\ProxyStubClsid32"),
            "",
            &RegValue::Sz(FOUNDATION.to_string()),
        )
        .unwrap();
    }
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn registration_writes_the_interfaces_and_unregistration_removes_everything() {
    let reg = MemoryRegistry::new();
    assert_eq!(register(&reg, MODULE, false, ALL_SPECIFICATIONS), Ok(true));
    let ours = CLSID_OpcComnProxyStub.to_string();
    assert_eq!(
        sz(&reg, &class_key(&CLSID_OpcComnProxyStub), "").as_deref(),
        Some("PSFactoryBuffer")
    );
    assert_eq!(sz(&reg, &module_key(), "").as_deref(), Some(MODULE));
    assert_eq!(sz(&reg, &module_key(), "ThreadingModel").as_deref(), Some("Both"));
    for (iid, name, n) in interfaces() {
        let key = interface_key(iid);
        assert_eq!(sz(&reg, &key, "").as_deref(), Some(name));
        assert_eq!(sz(&reg, &format!("{key}\\NumMethods"), ""), Some(n.to_string()));
        assert_eq!(sz(&reg, &format!("{key}\\ProxyStubClsid32"), ""), Some(ours.clone()));
    }
    // Twice is harmless and the ledger still undoes everything.
    assert_eq!(register(&reg, MODULE, false, ALL_SPECIFICATIONS), Ok(true));
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
    assert_eq!(dump(&reg), Vec::new(), "everything opccomn wrote is gone");
    // Unregistering again (nothing registered) succeeds.
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn an_installed_foundation_proxy_stub_keeps_its_interfaces() {
    let reg = MemoryRegistry::new();
    // An opccomn_ps.dll of OPC Common 1.0 knows three of the five interfaces.
    let old = interfaces();
    install_foundation(&reg, &old[..3]);
    let before = dump(&reg);
    assert_eq!(
        register(&reg, MODULE, false, ALL_SPECIFICATIONS),
        Ok(false),
        "S_FALSE: some interfaces stay with opccomn_ps"
    );
    for (iid, ..) in &old[..3] {
        assert_eq!(proxy_stub_of(&reg, iid), Some(FOUNDATION));
    }
    for (iid, ..) in &old[3..] {
        assert_eq!(proxy_stub_of(&reg, iid), Some(CLSID_OpcComnProxyStub));
    }
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
    assert_eq!(dump(&reg), before, "the Foundation's registration is exactly as it was");
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn taking_over_is_undone_by_unregistration() {
    let reg = MemoryRegistry::new();
    install_foundation(&reg, &interfaces());
    let before = dump(&reg);
    assert_eq!(register(&reg, MODULE, true, ALL_SPECIFICATIONS), Ok(true));
    for (iid, ..) in interfaces() {
        assert_eq!(proxy_stub_of(&reg, iid), Some(CLSID_OpcComnProxyStub));
        // The Foundation's name stays.
        assert!(sz(&reg, &interface_key(iid), "").is_some());
    }
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
    assert_eq!(dump(&reg), before, "ProxyStubClsid32 points to opccomn_ps.dll again");
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn a_proxy_stub_installed_after_us_keeps_what_it_wrote() {
    let reg = MemoryRegistry::new();
    assert_eq!(register(&reg, MODULE, false, ALL_SPECIFICATIONS), Ok(true));
    // opccomn_ps.dll installed later overwrites two interfaces.
    install_foundation(&reg, &interfaces()[..2]);
    let theirs: Vec<_> = interfaces()[..2]
        .iter()
        .map(|(iid, ..)| {
            let key = interface_key(iid);
            (sz(&reg, &key, ""), sz(&reg, &format!("{key}\\NumMethods"), ""))
        })
        .collect();
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
    for ((iid, ..), (name, methods)) in interfaces()[..2].iter().zip(theirs) {
        let key = interface_key(iid);
        assert_eq!(proxy_stub_of(&reg, iid), Some(FOUNDATION));
        assert_eq!(
            (sz(&reg, &key, ""), sz(&reg, &format!("{key}\\NumMethods"), "")),
            (name, methods)
        );
    }
    for (iid, ..) in &interfaces()[2..] {
        assert!(!reg.key_exists(&interface_key(iid)), "ours are gone");
    }
    assert!(!reg.key_exists(&class_key(&CLSID_OpcComnProxyStub)));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn a_dangling_proxy_stub_class_is_replaced_and_restored() {
    let reg = MemoryRegistry::new();
    install_foundation(&reg, &interfaces()[..1]);
    reg.delete_value(&format!("{}\\InprocServer32", class_key(&FOUNDATION)), "")
        .unwrap();
    reg.delete_key(&format!("{}\\InprocServer32", class_key(&FOUNDATION)))
        .unwrap();
    let before = dump(&reg);
    // The Foundation's DLL is gone (its class has no InprocServer32): nothing serves the interface.
    assert_eq!(register(&reg, MODULE, false, ALL_SPECIFICATIONS), Ok(true));
    assert_eq!(proxy_stub_of(&reg, interfaces()[0].0), Some(CLSID_OpcComnProxyStub));
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
    assert_eq!(dump(&reg), before);
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn values_rewritten_since_registration_stay() {
    // Taken over from the Foundation's proxy/stub; then another product rewrites an interface's name
    // and its method count while the proxy/stub is still ours.
    let reg = MemoryRegistry::new();
    install_foundation(&reg, &interfaces()[..1]);
    assert_eq!(register(&reg, MODULE, true, ALL_SPECIFICATIONS), Ok(true));
    let key = interface_key(interfaces()[0].0);
    reg.set_value(&key, "", &RegValue::Sz("IOPCShutdown (v2)".into()))
        .unwrap();
    reg.set_value(&format!("{key}\\NumMethods"), "", &RegValue::Sz("5".into()))
        .unwrap();
    let other = interface_key(interfaces()[1].0);
    reg.set_value(&other, "", &RegValue::Sz("Their name".into())).unwrap();
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
    // The taken-over interface gets the Foundation's proxy/stub back; what others rewrote stays.
    assert_eq!(proxy_stub_of(&reg, interfaces()[0].0), Some(FOUNDATION));
    assert_eq!(sz(&reg, &key, "").as_deref(), Some("IOPCShutdown (v2)"));
    assert_eq!(sz(&reg, &format!("{key}\\NumMethods"), "").as_deref(), Some("5"));
    assert_eq!(sz(&reg, &other, "").as_deref(), Some("Their name"));
    assert_eq!(proxy_stub_of(&reg, interfaces()[1].0), None);
    // A ProxyStubClsid32 written over ours since is not set back to what it was before us.
    let reg = MemoryRegistry::new();
    install_foundation(&reg, &interfaces()[..1]);
    assert_eq!(register(&reg, MODULE, true, ALL_SPECIFICATIONS), Ok(true));
    let newer = GUID::from_u128(0x5EED);
    reg.set_value(
        &format!("{key}\\ProxyStubClsid32"),
        "",
        &RegValue::Sz(newer.to_string()),
    )
    .unwrap();
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
    assert_eq!(proxy_stub_of(&reg, interfaces()[0].0), Some(newer));
    assert!(!reg.key_exists(&class_key(&CLSID_OpcComnProxyStub)));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn unregistration_without_a_ledger_removes_only_our_values() {
    let reg = MemoryRegistry::new();
    install_foundation(&reg, &interfaces()[..1]);
    register(&reg, MODULE, false, ALL_SPECIFICATIONS).unwrap();
    reg.delete_value(&module_key(), LEDGER).unwrap();
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
    assert_eq!(proxy_stub_of(&reg, interfaces()[0].0), Some(FOUNDATION));
    for (iid, ..) in &interfaces()[1..] {
        assert_eq!(proxy_stub_of(&reg, iid), None);
    }
    assert!(!reg.key_exists(&class_key(&CLSID_OpcComnProxyStub)));
}

#[test]
fn the_c_entry_points_check_their_arguments() {
    let mut mem = ptr::null_mut();
    // SAFETY: valid pointers, deliberate bad values; the registry handle is released at the end.
    unsafe {
        assert_eq!(crate::registry::OpcRegistryCreateMemory(&mut mem), S_OK);
        assert_eq!(OpcRegisterProxyStub(mem, 2), E_INVALIDARG);
        assert_eq!(OpcRegisterProxyStub(mem, 0x8000), E_INVALIDARG);
        // Registering finds this module's path with dladdr, which Miri cannot call.
        #[cfg(not(miri))]
        {
            assert_eq!(OpcRegisterProxyStub(mem, OPC_PROXY_STUB_TAKE_OVER), S_OK);
            assert_eq!(OpcUnregisterProxyStub(mem), S_OK);
        }
        assert_eq!(OpcDllInstall(1, ptr::null()), E_INVALIDARG);
        let empty = [0u16];
        assert_eq!(OpcDllInstall(1, empty.as_ptr()), E_INVALIDARG);
        let unknown: Vec<u16> = "ProxyStub,Everything\0".encode_utf16().collect();
        assert_eq!(OpcDllInstall(1, unknown.as_ptr()), E_INVALIDARG);
        crate::registry::OpcRegistryRelease(mem);
    }
    assert_eq!(parse_install_command("proxystub"), Some(0));
    assert_eq!(
        parse_install_command("ProxyStub, TakeOver"),
        Some(OPC_PROXY_STUB_TAKE_OVER)
    );
    assert_eq!(parse_install_command("ProxyStub da"), Some(OPC_PROXY_STUB_DA));
    assert_eq!(
        parse_install_command("ProxyStub Common DA TakeOver"),
        Some(OPC_PROXY_STUB_TAKE_OVER | OPC_PROXY_STUB_COMMON | OPC_PROXY_STUB_DA)
    );
    assert_eq!(parse_install_command("TakeOver"), None);
    assert_eq!(parse_install_command("DA"), None);
    assert_eq!(parse_install_command("ProxyStub HDA2"), None);
    assert_eq!(
        parse_install_command("ProxyStub,AE,HDA"),
        Some(OPC_PROXY_STUB_AE | OPC_PROXY_STUB_HDA)
    );
    assert_eq!(specifications(0), ALL_SPECIFICATIONS);
    assert_eq!(
        specifications(OPC_PROXY_STUB_TAKE_OVER | OPC_PROXY_STUB_DA),
        OPC_PROXY_STUB_DA
    );
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn the_specifications_register_and_unregister_on_their_own() {
    let common: Vec<_> = interfaces_of(OPC_PROXY_STUB_COMMON);
    let da: Vec<_> = interfaces_of(OPC_PROXY_STUB_DA);
    assert_eq!(common.len(), 5);
    assert_eq!(da.len(), 19, "every interface of opcda.idl");
    let ae = interfaces_of(OPC_PROXY_STUB_AE);
    let hda = interfaces_of(OPC_PROXY_STUB_HDA);
    assert_eq!(
        (ae.len(), hda.len()),
        (6, 10),
        "every interface of opc_ae.idl and opchda.idl"
    );
    assert_eq!(common.len() + da.len() + ae.len() + hda.len(), interfaces().len());
    assert!(ae.iter().any(|(_, name, _)| *name == "IOPCEventSink"));
    assert!(hda.iter().any(|(_, name, _)| *name == "IOPCHDA_DataCallback"));
    assert!(da.iter().any(|(_, name, _)| *name == "IOPCDataCallback"));
    assert!(
        da.iter().any(|(_, name, n)| *name == "IOPCSyncIO2" && *n == 7),
        "inherited methods counted"
    );

    // DA only: the Common interfaces are not touched.
    let reg = MemoryRegistry::new();
    assert_eq!(register(&reg, MODULE, false, OPC_PROXY_STUB_DA), Ok(true));
    for (iid, ..) in &da {
        assert_eq!(proxy_stub_of(&reg, iid), Some(CLSID_OpcComnProxyStub));
    }
    for (iid, ..) in &common {
        assert!(!reg.key_exists(&interface_key(iid)));
    }
    // Then Common too; unregistering DA leaves Common and the class registered, with a ledger that
    // still undoes them.
    assert_eq!(register(&reg, MODULE, false, OPC_PROXY_STUB_COMMON), Ok(true));
    unregister(&reg, OPC_PROXY_STUB_DA).unwrap();
    for (iid, ..) in &da {
        assert!(!reg.key_exists(&interface_key(iid)), "DA's are gone");
    }
    for (iid, ..) in &common {
        assert_eq!(proxy_stub_of(&reg, iid), Some(CLSID_OpcComnProxyStub));
    }
    assert_eq!(sz(&reg, &module_key(), "").as_deref(), Some(MODULE));
    unregister(&reg, OPC_PROXY_STUB_COMMON).unwrap();
    assert_eq!(dump(&reg), Vec::new(), "the last specification takes the class with it");

    // A Foundation-style DA proxy/stub (opcproxy.dll) keeps its interfaces unless taken over, and gets
    // them back on unregistration; Common's are registered beside it.
    let reg = MemoryRegistry::new();
    install_foundation(&reg, &da);
    let before = dump(&reg);
    assert_eq!(register(&reg, MODULE, false, ALL_SPECIFICATIONS), Ok(false));
    for (iid, ..) in &da {
        assert_eq!(proxy_stub_of(&reg, iid), Some(FOUNDATION));
    }
    assert_eq!(register(&reg, MODULE, true, OPC_PROXY_STUB_DA), Ok(true));
    for (iid, ..) in &da {
        assert_eq!(proxy_stub_of(&reg, iid), Some(CLSID_OpcComnProxyStub));
    }
    unregister(&reg, OPC_PROXY_STUB_DA).unwrap();
    for (iid, ..) in &da {
        assert_eq!(proxy_stub_of(&reg, iid), Some(FOUNDATION), "restored");
    }
    for (iid, ..) in &common {
        assert_eq!(proxy_stub_of(&reg, iid), Some(CLSID_OpcComnProxyStub));
    }
    unregister(&reg, ALL_SPECIFICATIONS).unwrap();
    assert_eq!(dump(&reg), before);
}
