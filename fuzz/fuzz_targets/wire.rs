//! The proxy/stub's checks of NDR messages (proxy::wire): any request and any reply of any method is
//! answered S_OK or with RPC_X_BAD_STUB_DATA, RPC_S_INVALID_BOUND or RPC_S_PROCNUM_OUT_OF_RANGE, never
//! a panic or a read outside the message; and what passes has the properties the proxy relies on,
//! read off the message here independently of the checks: a `Next` reply fits the caller's `celt`
//! GUIDs and carries them all; an interface pointer is NULL or an OBJREF inside the message that
//! names the method's interface, in the layout the reading runtime expects; only a NULL pointer
//! passes for both runtimes.
//!
//! The checks are generated from the IDL (src/proxy/generated/layouts.rs read by src/proxy/ndr); every
//! answer must also be the one the hand-written checks they replaced give (proxy::wire::reference).
//!
//! Input: byte 0 the interface (mod 5), byte 1 the method (mod 8), byte 2 the runtime reading
//! interface pointers (bit 0: Wine's), byte 3 `Next`'s `celt`; the message is the rest.
#![no_main]

use libfuzzer_sys::fuzz_target;
use opccomn::com::guids::{IID_IEnumGUID, IID_IOPCEnumGUID};
use opccomn::com::GUID;
use opccomn::proxy::wire::{
    check_reply, check_request, reference, reply_context, Context, Dialect as IpLayout, Interface, COMMON,
};

const LOCAL: u32 = 0x10;
/// HRESULT_FROM_WIN32 of RPC_X_BAD_STUB_DATA, RPC_S_INVALID_BOUND and RPC_S_PROCNUM_OUT_OF_RANGE.
const BAD_STUB_DATA: i32 = 0x800706F7_u32 as i32;
const INVALID_BOUND: i32 = 0x800706C6_u32 as i32;
const PROCNUM_OUT_OF_RANGE: i32 = 0x800706D1_u32 as i32;
const MEOW: u32 = 0x574F_454D;

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

fn guid_bytes(g: &GUID) -> Vec<u8> {
    let mut b = g.Data1.to_le_bytes().to_vec();
    b.extend_from_slice(&g.Data2.to_le_bytes());
    b.extend_from_slice(&g.Data3.to_le_bytes());
    b.extend_from_slice(&g.Data4);
    b
}

fn defined(r: Result<(), i32>) {
    if let Err(hr) = r {
        assert!(
            [BAD_STUB_DATA, INVALID_BOUND, PROCNUM_OUT_OF_RANGE].contains(&hr),
            "{hr:#x}"
        );
    }
}

/// An interface-pointer reply that passed: where its OBJREF is, read without the checks.
fn objref_position(msg: &[u8], reader: IpLayout) -> Option<(usize, usize)> {
    if u32_at(msg, 0) == 0 {
        return None;
    }
    Some(match reader {
        IpLayout::Wine => (4, u32_at(msg, 0) as usize),
        IpLayout::Ndr => {
            assert_eq!(u32_at(msg, 4), u32_at(msg, 8), "conformance = ulCntData");
            (12, u32_at(msg, 8) as usize)
        }
    })
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 4 {
        return;
    }
    // The OPC Common interfaces: the hand-written checks know only these (the DA layouts: `layouts`).
    let iface = COMMON[usize::from(data[0]) % COMMON.len()];
    let method = u32::from(data[1] % 8);
    let reader = if data[2] & 1 != 0 {
        IpLayout::Wine
    } else {
        IpLayout::Ndr
    };
    let celt = u32::from(data[3]);
    let msg = &data[4..];

    let request = check_request(iface, method, msg, LOCAL, reader);
    defined(request);
    assert_eq!(request, reference::check_request(iface, method, msg, LOCAL), "as the hand-written check");
    let context = reply_context(iface, method, msg, reader);
    if request.is_ok() {
        assert_eq!(context, Context::of(&[reference::reply_context(iface, method, msg)]));
    }
    let checked = check_reply(iface, method, &Context::of(&[celt]), msg, LOCAL, reader);
    defined(checked);
    assert_eq!(
        checked,
        reference::check_reply(iface, method, celt, msg, LOCAL, reader),
        "as the hand-written check"
    );
    if checked.is_err() {
        return;
    }
    let declared = match (iface, method) {
        (Interface::IOPCServerList, 3) => Some(IID_IEnumGUID),
        (Interface::IOPCServerList2, 3) | (Interface::IOPCEnumGUID, 6) => Some(IID_IOPCEnumGUID),
        _ => None,
    };
    if let Some(iid) = declared {
        let other = if reader == IpLayout::Wine {
            IpLayout::Ndr
        } else {
            IpLayout::Wine
        };
        if let Some((at, len)) = objref_position(msg, reader) {
            assert!(
                at + len + 4 <= msg.len(),
                "the OBJREF and the HRESULT are inside the message"
            );
            assert_eq!(u32_at(msg, at), MEOW);
            assert_eq!(msg[at + 8..at + 24], guid_bytes(&iid)[..], "the declared interface");
            assert!(
                check_reply(iface, method, &Context::of(&[celt]), msg, LOCAL, other).is_err(),
                "one layout only"
            );
        }
    }
    if (iface, method) == (Interface::IOPCEnumGUID, 3) {
        // Next: conformance = celt, offset 0, actual <= celt, the GUIDs, *pceltFetched, the HRESULT.
        let actual = u32_at(msg, 8);
        assert_eq!((u32_at(msg, 0), u32_at(msg, 4)), (celt, 0));
        assert!(actual <= celt);
        assert!(msg.len() >= 12 + 16 * actual as usize + 8);
        assert_eq!(u32_at(msg, 12 + 16 * actual as usize), actual);
    }
});
