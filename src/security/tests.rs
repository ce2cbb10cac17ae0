//! The arguments the library passes to CoInitializeSecurity and CoSetProxyBlanket, recorded through
//! the seam (COM under Wine accepts and ignores them, so here is where they are shown), and what is
//! refused before COM is called.

use core::ffi::c_void;
use core::ptr;

use super::*;
use crate::com::ffi::Fail;
use crate::com::iids::IID_IOPCCommon;
use crate::com::unknown::hostile::{Answer, Hostile};
use crate::com::unknown::{add_ref, release};
use crate::com::{E_NOINTERFACE, E_POINTER, S_FALSE};
use crate::common::OpcCommonCreate;

const APPID: GUID = GUID::from_u128(0x5ec22000_0000_4000_8000_000000000022);

fn utf16(s: &str) -> Vec<u16> {
    s.encode_utf16().chain([0]).collect()
}

fn options() -> OpcSecurityOptions {
    OpcSecurityOptions {
        struct_size: core::mem::size_of::<OpcSecurityOptions>() as u32,
        authn_level: 0,
        imp_level: 0,
        flags: 0,
        appid: ptr::null(),
        access_sddl: ptr::null(),
    }
}

/// What one CoInitializeSecurity call through the seam received; the AppID is copied out during the
/// call (the pointer is only valid then).
#[derive(Debug, Clone, Copy)]
struct Seen {
    args: CoInitializeSecurityArgs,
    appid: Option<GUID>,
}

/// Runs `initialize` on a fresh process state with a recorder that answers `answer`.
fn initialize_with(role: Role, options: Option<&OpcSecurityOptions>, answer: HRESULT) -> (FfiResult, Vec<Seen>) {
    initialize_on(&ProcessSecurity::new(), role, options, answer)
}

fn initialize_on(
    state: &ProcessSecurity,
    role: Role,
    options: Option<&OpcSecurityOptions>,
    answer: HRESULT,
) -> (FfiResult, Vec<Seen>) {
    let mut seen = Vec::new();
    let p = options.map_or(ptr::null(), |o| o as *const OpcSecurityOptions);
    let record = |a: &CoInitializeSecurityArgs| {
        let appid = (a.capabilities & EOAC_APPID != 0)
            // SAFETY: with EOAC_APPID the library passes a pointer to a GUID, valid during the call.
            .then(|| unsafe { *a.sec_desc.cast::<GUID>() });
        seen.push(Seen { args: *a, appid });
        answer
    };
    // SAFETY: `p` is NULL or a whole options struct with NULL or valid pointers.
    let r = unsafe { state.initialize(role, p, record) };
    (r, seen)
}

/// The arguments every call has whatever the options: COM chooses the services, nothing reserved.
fn assert_fixed(a: &CoInitializeSecurityArgs) {
    assert_eq!(a.auth_svc_count, -1);
    assert!(a.auth_svc.is_null() && a.reserved1.is_null() && a.auth_list.is_null() && a.reserved3.is_null());
}

#[test]
fn a_server_asks_for_packet_integrity_and_identify_with_no_access_list_by_default() {
    for o in [None, Some(&options())] {
        let (r, seen) = initialize_with(Role::Server, o, S_OK);
        assert_eq!(r, Ok(S_OK));
        assert_eq!(seen.len(), 1);
        let a = seen[0].args;
        assert_fixed(&a);
        assert!(a.sec_desc.is_null());
        assert_eq!((a.authn_level, a.imp_level, a.capabilities), (5, 2, EOAC_NONE));
    }
}

#[test]
fn a_client_impersonates_by_default() {
    let (r, seen) = initialize_with(Role::Client, None, S_OK);
    assert_eq!(r, Ok(S_OK));
    assert_eq!((seen[0].args.authn_level, seen[0].args.imp_level), (5, 3));
    assert_eq!(seen[0].args.capabilities, EOAC_NONE);
}

#[test]
fn an_appid_goes_to_com_with_eoac_appid() {
    let mut o = options();
    o.appid = &APPID;
    for role in [Role::Server, Role::Client] {
        let (r, seen) = initialize_with(role, Some(&o), S_OK);
        assert_eq!(r, Ok(S_OK));
        assert_eq!(seen[0].args.capabilities, EOAC_APPID);
        assert_eq!(seen[0].appid, Some(APPID));
        assert_fixed(&seen[0].args);
        assert_eq!(seen[0].args.authn_level, 5);
    }
}

#[test]
fn the_levels_asked_for_are_passed_and_privacy_is_accepted() {
    let mut o = options();
    o.authn_level = 6;
    o.imp_level = 4;
    let (r, seen) = initialize_with(Role::Server, Some(&o), S_OK);
    assert_eq!(r, Ok(S_OK));
    assert_eq!((seen[0].args.authn_level, seen[0].args.imp_level), (6, 4));
    o.imp_level = 1;
    let (_, seen) = initialize_with(Role::Client, Some(&o), S_OK);
    assert_eq!(seen[0].args.imp_level, 1);
}

#[test]
fn a_level_below_packet_integrity_is_refused_without_the_flag_and_com_is_not_called() {
    for level in 1..=4 {
        let mut o = options();
        o.authn_level = level;
        for role in [Role::Server, Role::Client] {
            let (r, seen) = initialize_with(role, Some(&o), S_OK);
            assert_eq!(r, Err(Fail::Code(E_INVALIDARG)), "level {level}");
            assert!(seen.is_empty());
        }
        o.flags = OPC_SECURITY_ALLOW_WEAKER_AUTHN;
        let (r, seen) = initialize_with(Role::Server, Some(&o), S_OK);
        assert_eq!(r, Ok(S_OK));
        assert_eq!(seen[0].args.authn_level, level);
    }
}

#[test]
fn bad_options_are_refused_before_com_is_called() {
    let sddl = utf16("O:BAG:BAD:(A;;0x7;;;AU)");
    let empty = utf16("");
    let mut cases = Vec::new();
    for size in [0, 4, 16, core::mem::size_of::<OpcSecurityOptions>() as u32 + 8] {
        cases.push(OpcSecurityOptions {
            struct_size: size,
            ..options()
        });
    }
    cases.push(OpcSecurityOptions { flags: 2, ..options() });
    cases.push(OpcSecurityOptions {
        authn_level: 7,
        flags: OPC_SECURITY_ALLOW_WEAKER_AUTHN,
        ..options()
    });
    cases.push(OpcSecurityOptions {
        imp_level: 5,
        ..options()
    });
    cases.push(OpcSecurityOptions {
        appid: &APPID,
        access_sddl: sddl.as_ptr(),
        ..options()
    });
    cases.push(OpcSecurityOptions {
        access_sddl: empty.as_ptr(),
        ..options()
    });
    for (i, o) in cases.iter().enumerate() {
        let (r, seen) = initialize_with(Role::Server, Some(o), S_OK);
        assert_eq!(r, Err(Fail::Code(E_INVALIDARG)), "case {i}");
        assert!(seen.is_empty(), "case {i}");
    }
}

#[test]
fn process_security_is_set_once_and_a_second_call_is_too_late() {
    let state = ProcessSecurity::new();
    // A refused call and a failing one leave the process free to try again.
    let weak = OpcSecurityOptions {
        authn_level: 2,
        ..options()
    };
    assert_eq!(
        initialize_on(&state, Role::Server, Some(&weak), S_OK).0,
        Err(Fail::Code(E_INVALIDARG))
    );
    let (r, seen) = initialize_on(&state, Role::Server, None, E_OUTOFMEMORY_);
    assert_eq!((r, seen.len()), (Err(Fail::Code(E_OUTOFMEMORY_)), 1));
    // COM's own RPC_E_TOO_LATE (the process called CoInitializeSecurity itself) passes through.
    let (r, seen) = initialize_on(&state, Role::Server, None, RPC_E_TOO_LATE);
    assert_eq!((r, seen.len()), (Err(Fail::Code(RPC_E_TOO_LATE)), 1));
    let (r, seen) = initialize_on(&state, Role::Server, None, S_OK);
    assert_eq!((r, seen.len()), (Ok(S_OK), 1));
    // Then the library answers RPC_E_TOO_LATE itself, for either role, without calling COM.
    for role in [Role::Server, Role::Client] {
        let (r, seen) = initialize_on(&state, role, None, S_OK);
        assert_eq!((r, seen.len()), (Err(Fail::Code(RPC_E_TOO_LATE)), 0));
    }
    // Bad options are still E_INVALIDARG, not RPC_E_TOO_LATE.
    assert_eq!(
        initialize_on(&state, Role::Client, Some(&weak), S_OK).0,
        Err(Fail::Code(E_INVALIDARG))
    );
}

const E_OUTOFMEMORY_: HRESULT = crate::com::E_OUTOFMEMORY;

#[cfg(not(windows))]
#[test]
fn off_windows_an_access_list_is_checked_then_not_implemented_and_com_is_not_called() {
    let sddl = utf16("O:BAG:BAD:(A;;0x7;;;AU)");
    let o = OpcSecurityOptions {
        access_sddl: sddl.as_ptr(),
        ..options()
    };
    let (r, seen) = initialize_with(Role::Server, Some(&o), S_OK);
    assert_eq!(r, Err(Fail::Code(crate::com::E_NOTIMPL)));
    assert!(seen.is_empty());
    // Not SDDL, no owner or group, a SACL: refused before anything else.
    for bad in [
        "not sddl",
        "D:(A;;0x7;;;AU)",
        "O:BAD:(A;;0x7;;;AU)",
        "O:BAG:BAS:(AU;SA;0x7;;;WD)",
    ] {
        let text = utf16(bad);
        let o = OpcSecurityOptions {
            access_sddl: text.as_ptr(),
            ..options()
        };
        let (r, seen) = initialize_with(Role::Server, Some(&o), S_OK);
        assert_eq!(r, Err(Fail::Code(E_INVALIDARG)), "{bad}");
        assert!(seen.is_empty());
    }
}

#[cfg(not(windows))]
#[test]
fn off_windows_the_exports_check_their_arguments_then_answer_e_notimpl() {
    use crate::com::E_NOTIMPL;
    let weak = OpcSecurityOptions {
        authn_level: 1,
        ..options()
    };
    // SAFETY: NULL or whole options structs.
    unsafe {
        assert_eq!(OpcInitializeServerSecurity(ptr::null()), E_NOTIMPL);
        assert_eq!(OpcInitializeClientSecurity(&options()), E_NOTIMPL);
        assert_eq!(OpcInitializeServerSecurity(&weak), E_INVALIDARG);
        assert_eq!(OpcSetProxyBlanket(ptr::null_mut(), ptr::null()), E_INVALIDARG);
        let o = common();
        assert_eq!(OpcSetProxyBlanket(o, ptr::null()), E_NOTIMPL);
        assert_eq!(OpcSetProxyBlanket(o, &weak), E_INVALIDARG);
        release(o);
    }
}

/// On Windows (under Wine in CI) the access list reaches COM as an absolute descriptor holding exactly
/// what the SDDL says: converted back to SDDL during the call, it reads as the input does.
#[cfg(windows)]
#[test]
fn an_access_list_reaches_com_as_the_absolute_descriptor_of_the_sddl() {
    use windows_sys::Win32::Foundation::LocalFree;
    use windows_sys::Win32::Security::Authorization::{
        ConvertSecurityDescriptorToStringSecurityDescriptorW, ConvertStringSecurityDescriptorToSecurityDescriptorW,
        SDDL_REVISION_1,
    };
    use windows_sys::Win32::Security::{
        DACL_SECURITY_INFORMATION, GROUP_SECURITY_INFORMATION, OWNER_SECURITY_INFORMATION, SE_SELF_RELATIVE,
    };

    /// The SDDL of a descriptor (absolute or self-relative).
    fn to_sddl(sd: *mut c_void) -> String {
        let mut text: *mut u16 = ptr::null_mut();
        let mut len = 0u32;
        // SAFETY: `sd` is a valid descriptor; the out-pointers are writable; the text is freed below.
        unsafe {
            let ok = ConvertSecurityDescriptorToStringSecurityDescriptorW(
                sd,
                SDDL_REVISION_1,
                OWNER_SECURITY_INFORMATION | GROUP_SECURITY_INFORMATION | DACL_SECURITY_INFORMATION,
                &mut text,
                &mut len,
            );
            assert!(ok != 0 && !text.is_null());
            let s = String::from_utf16_lossy(core::slice::from_raw_parts(text, len as usize));
            LocalFree(text.cast());
            s.trim_end_matches('\0').to_owned()
        }
    }

    let input = "O:BAG:SYD:(A;;0x7;;;AU)(A;;0x3;;;SY)";
    let wide = utf16(input);
    // The system's own reading of the input, for comparing (it writes rights its own way).
    let mut reference: *mut c_void = ptr::null_mut();
    // SAFETY: NUL-terminated input, writable out-pointer; freed below.
    let ok = unsafe {
        ConvertStringSecurityDescriptorToSecurityDescriptorW(
            wide.as_ptr(),
            SDDL_REVISION_1,
            &mut reference,
            ptr::null_mut(),
        )
    };
    assert!(ok != 0);
    let want = to_sddl(reference);
    // SAFETY: allocated by the conversion.
    unsafe { LocalFree(reference) };
    assert!(want.starts_with("O:BAG:SYD:"), "{want}");

    let o = OpcSecurityOptions {
        access_sddl: wide.as_ptr(),
        ..options()
    };
    let mut got = None;
    let record = |a: &CoInitializeSecurityArgs| {
        // SAFETY: an absolute SECURITY_DESCRIPTOR the library made; its control word (bytes 2-3)
        // must not say self-relative.
        let control = unsafe { a.sec_desc.cast::<u16>().add(1).read() };
        assert_eq!(control & SE_SELF_RELATIVE, 0);
        assert_eq!((a.authn_level, a.imp_level, a.capabilities), (5, 2, EOAC_NONE));
        got = Some(to_sddl(a.sec_desc.cast_mut()));
        S_OK
    };
    // SAFETY: a whole options struct.
    let r = unsafe { ProcessSecurity::new().initialize(Role::Server, &o, record) };
    assert_eq!(r, Ok(S_OK));
    assert_eq!(got.as_deref(), Some(want.as_str()));

    // What CoInitializeSecurity refuses is refused here, before it is called.
    for bad in [
        "D:(A;;0x7;;;AU)",                           // no owner, no group
        "O:BAD:(A;;0x7;;;AU)",                       // no group
        "O:BAG:BAD:(A;;0x7;;;AU)S:(AU;SA;0x7;;;WD)", // a SACL
    ] {
        let wide = utf16(bad);
        let o = OpcSecurityOptions {
            access_sddl: wide.as_ptr(),
            ..options()
        };
        let (r, seen) = initialize_with(Role::Server, Some(&o), S_OK);
        assert_eq!(r, Err(Fail::Code(E_INVALIDARG)), "{bad}");
        assert!(seen.is_empty(), "{bad}");
    }
    // Text the system cannot read: its error, as an HRESULT (Wine 8 gives 0x800706A9 for this one).
    let wide = utf16("O:BAG:BAD:(not SDDL");
    let o = OpcSecurityOptions {
        access_sddl: wide.as_ptr(),
        ..options()
    };
    let (r, seen) = initialize_with(Role::Server, Some(&o), S_OK);
    assert!(matches!(r, Err(Fail::Code(hr)) if hr < 0), "{r:?}");
    assert!(seen.is_empty());
}

/// A library object to set blankets on (it is no proxy).
fn common() -> *mut IUnknown {
    let mut p: *mut c_void = ptr::null_mut();
    // SAFETY: valid arguments.
    let hr = unsafe { OpcCommonCreate(ptr::null(), ptr::null_mut(), &IID_IOPCCommon, &mut p) };
    assert_eq!(hr, S_OK);
    p.cast()
}

/// The object's identity (its IUnknown), without keeping a reference.
fn identity(p: *mut IUnknown) -> *mut IUnknown {
    // SAFETY: a live object.
    let u = unsafe { query::<IUnknown>(p, &IID_IUNKNOWN) }.unwrap();
    u.as_ptr()
}

/// References held on `p` now (by AddRef/Release's answers).
fn refs(p: *mut IUnknown) -> u32 {
    // SAFETY: a live object; the reference is given back at once.
    unsafe {
        add_ref(p);
        release(p)
    }
}

fn blanket_with(
    proxy: *mut IUnknown,
    options: Option<&OpcSecurityOptions>,
    answers: [HRESULT; 2],
) -> (FfiResult, Vec<CoSetProxyBlanketArgs>) {
    let mut seen = Vec::new();
    let p = options.map_or(ptr::null(), |o| o as *const OpcSecurityOptions);
    // SAFETY: `proxy` is NULL or live; `p` NULL or a whole options struct.
    let r = unsafe {
        set_blanket(proxy, p, |a| {
            seen.push(*a);
            answers[seen.len() - 1]
        })
    };
    (r, seen)
}

#[test]
fn the_blanket_is_set_on_the_interface_then_on_its_iunknown_with_the_proxy_defaults_kept() {
    let c = common();
    let unknown = identity(c);
    assert_ne!(c, unknown, "the test needs an interface other than the identity");
    let before = refs(c);
    let (r, seen) = blanket_with(c, None, [S_OK, S_OK]);
    assert_eq!(r, Ok(S_OK));
    assert_eq!(seen.len(), 2);
    assert_eq!((seen[0].proxy, seen[1].proxy), (c, unknown));
    for a in &seen {
        assert_eq!((a.authn_level, a.imp_level), (5, 3));
        assert_eq!(
            (a.authn_svc, a.authz_svc, a.capabilities),
            (RPC_C_AUTHN_DEFAULT, RPC_C_AUTHZ_DEFAULT, EOAC_DEFAULT)
        );
        assert_eq!(
            (a.server_principal as usize, a.auth_info as usize),
            (usize::MAX, usize::MAX)
        );
    }
    assert_eq!(refs(c), before, "the IUnknown queried for the second call is released");

    let o = OpcSecurityOptions {
        authn_level: 6,
        imp_level: 2,
        ..options()
    };
    let (r, seen) = blanket_with(c, Some(&o), [S_OK, S_FALSE]);
    assert_eq!(r, Ok(S_OK));
    assert_eq!((seen[1].authn_level, seen[1].imp_level), (6, 2));
    // SAFETY: the test's reference.
    unsafe { release(c) };
}

#[test]
fn a_blanket_failure_is_passed_through_and_an_in_process_object_gets_e_nointerface() {
    let c = common();
    let before = refs(c);
    // The first call fails (an in-process object has no IClientSecurity): nothing else is tried.
    let (r, seen) = blanket_with(c, None, [E_NOINTERFACE, S_OK]);
    assert_eq!((r, seen.len()), (Err(Fail::Code(E_NOINTERFACE)), 1));
    // The second fails: its code, and the IUnknown is still released.
    let (r, seen) = blanket_with(c, None, [S_OK, E_OUTOFMEMORY_]);
    assert_eq!((r, seen.len()), (Err(Fail::Code(E_OUTOFMEMORY_)), 2));
    assert_eq!(refs(c), before);
    // The real function on Windows (Wine in CI): a library object is no proxy.
    #[cfg(windows)]
    // SAFETY: a live object.
    unsafe {
        assert_eq!(OpcSetProxyBlanket(c, ptr::null()), E_NOINTERFACE);
    }
    // SAFETY: the test's reference.
    unsafe { release(c) };
}

#[test]
fn a_blanket_below_packet_integrity_or_with_process_settings_is_refused_before_com_is_called() {
    let c = common();
    let sddl = utf16("O:BAG:BAD:(A;;0x7;;;AU)");
    let cases = [
        OpcSecurityOptions {
            authn_level: 2,
            ..options()
        },
        OpcSecurityOptions {
            appid: &APPID,
            ..options()
        },
        OpcSecurityOptions {
            access_sddl: sddl.as_ptr(),
            ..options()
        },
        OpcSecurityOptions {
            struct_size: 4,
            ..options()
        },
    ];
    for (i, o) in cases.iter().enumerate() {
        let (r, seen) = blanket_with(c, Some(o), [S_OK, S_OK]);
        assert_eq!(r, Err(Fail::Code(E_INVALIDARG)), "case {i}");
        assert!(seen.is_empty(), "case {i}");
    }
    let weak_allowed = OpcSecurityOptions {
        authn_level: 1,
        flags: OPC_SECURITY_ALLOW_WEAKER_AUTHN,
        ..options()
    };
    let (r, seen) = blanket_with(c, Some(&weak_allowed), [S_OK, S_OK]);
    assert_eq!(r, Ok(S_OK));
    assert_eq!((seen[0].authn_level, seen[1].authn_level), (1, 1));
    // NULL: the Opc rule.
    let (r, seen) = blanket_with(ptr::null_mut(), None, [S_OK, S_OK]);
    assert_eq!((r, seen.len()), (Err(Fail::Null), 0));
    // SAFETY: the test's reference.
    unsafe { release(c) };
}

#[test]
fn an_object_answering_iunknown_with_null_gets_e_pointer_after_the_first_call() {
    let h = Hostile::new(Answer::OkWithNull);
    let (r, seen) = blanket_with(h.unk(), None, [S_OK, S_OK]);
    assert_eq!((r, seen.len()), (Err(Fail::Code(E_POINTER)), 1));
    assert_eq!(h.refs(), 1);
}
