//! The interpreter of NDR layouts (proxy::ndr) over the layouts of the interfaces opccomn.dll's
//! proxy/stub serves (src/proxy/generated/layouts.rs: OPC Common, Data Access, A&E and HDA,
//! generated from idl/opccomn.idl, opcda.idl, opc_ae.idl and opchda.idl): any message for any
//! method, as a request or a reply, read by
//! either runtime's dialect, is answered S_OK or with RPC_X_BAD_STUB_DATA,
//! RPC_S_INVALID_BOUND or RPC_S_PROCNUM_OUT_OF_RANGE, never a panic or a read outside the message.
//! What passes keeps passing with bytes after it (a message may be longer than what is read) and at
//! another 8-byte-aligned address; a request that passes gives a context its reply check can use.
//!
//! Seeds: a request and a reply of every method, made from its layout (src/proxy/ndr/tests/served.rs).
//!
//! Input: byte 0 the interface (mod their number), byte 1 the method (3 + mod 24: past the longest
//! interface's), byte 2 bit 0 the dialect (Wine's), bit 1 a reply (not a request), bytes 3 to 18 the
//! reply's context (four words: the request's counts, or the IID of `iid_is`); the message is the
//! rest, copied to an 8-byte boundary.
#![no_main]

use libfuzzer_sys::fuzz_target;
use opccomn::proxy::ndr::{check_reply, check_request, Context, Dialect};
use opccomn::proxy::layouts::Interface;

const LOCAL: u32 = 0x10;
/// HRESULT_FROM_WIN32 of RPC_X_BAD_STUB_DATA, RPC_S_INVALID_BOUND and RPC_S_PROCNUM_OUT_OF_RANGE.
const BAD_STUB_DATA: i32 = 0x800706F7_u32 as i32;
const INVALID_BOUND: i32 = 0x800706C6_u32 as i32;
const PROCNUM_OUT_OF_RANGE: i32 = 0x800706D1_u32 as i32;

fn defined(r: Result<(), i32>) {
    if let Err(hr) = r {
        assert!([BAD_STUB_DATA, INVALID_BOUND, PROCNUM_OUT_OF_RANGE].contains(&hr), "{hr:#x}");
    }
}

/// `bytes` with `extra` bytes of 0xAB after them, in a buffer where they start at an 8-byte
/// boundary: (buffer, start, length).
fn aligned(bytes: &[u8], extra: usize) -> (Vec<u8>, usize, usize) {
    let mut buf = vec![0xABu8; bytes.len() + extra + 8];
    let at = (8 - buf.as_ptr() as usize % 8) % 8;
    buf[at..at + bytes.len()].copy_from_slice(bytes);
    (buf, at, bytes.len() + extra)
}

fuzz_target!(|data: &[u8]| {
    if data.len() < 19 {
        return;
    }
    let iface = Interface::all()[usize::from(data[0]) % Interface::all().len()].layout();
    let method = 3 + u32::from(data[1] % 24);
    let dialect = if data[2] & 1 != 0 { Dialect::Wine } else { Dialect::Ndr };
    let is_reply = data[2] & 2 != 0;
    let words: Vec<u32> = data[3..19]
        .chunks_exact(4)
        .map(|w| u32::from_le_bytes(w.try_into().unwrap()))
        .collect();
    let context = Context::of(&words);
    let msg = &data[19..];

    let run = |extra: usize| -> Result<Option<Context>, i32> {
        let (buf, at, len) = aligned(msg, extra);
        let bytes = &buf[at..at + len];
        if is_reply {
            check_reply(iface, method, &context, bytes, LOCAL, dialect).map(|()| None)
        } else {
            check_request(iface, method, bytes, LOCAL, dialect).map(Some)
        }
    };
    let first = run(0);
    defined(first.map(|_| ()));
    if let Ok(ctx) = first {
        // Bytes after what is read change nothing.
        assert_eq!(run(5).map(|_| ()), Ok(()), "bytes after a message that passed");
        if let Some(ctx) = ctx {
            let (buf, at, len) = aligned(msg, 0);
            defined(check_reply(iface, method, &ctx, &buf[at..at + len], LOCAL, dialect));
        }
    }
});
