//! Every construct of the layout language, on the layouts tools/gen-header generated from
//! idl/testdata/ndr-constructs.idl (src/proxy/generated/test_layouts.rs), with messages built here
//! field by field to the NDR rules (C706 chapter 14, MS-RPCE 2.2.5; MS-OAUT 2.2.23, 2.2.29 and 2.2.30
//! for BSTR, VARIANT and SAFEARRAY; MS-DCOM 2.2.14 and 2.2.18 for interface pointers): each well-formed
//! one passes, every proper prefix of it is refused, and each kind of malformed one is refused with
//! its code.

use super::*;
use crate::proxy::test_layouts::Interface as T;

pub(crate) mod build;
mod constructs;
mod da;
#[cfg(windows)]
mod runtime;
mod served;

use build::{Msg, Sa, SaData, V};

const LOCAL: u32 = 0x10;
const USER: u32 = 0x7265_7355;

/// A vtable index of a test interface by its method name.
fn index(iface: T, name: &str) -> u32 {
    let i = iface.layout().methods.iter().position(|m| m.name == name);
    3 + i.unwrap_or_else(|| panic!("{iface:?} has no {name}")) as u32
}

fn request(iface: T, name: &str, m: &Msg, dialect: Dialect) -> Result<Context, HRESULT> {
    check_request(iface.layout(), index(iface, name), m.aligned().bytes(), LOCAL, dialect)
}

fn reply(iface: T, name: &str, ctx: &Context, m: &Msg, dialect: Dialect) -> Check {
    check_reply(
        iface.layout(),
        index(iface, name),
        ctx,
        m.aligned().bytes(),
        LOCAL,
        dialect,
    )
}

/// The message passes, and every proper prefix of it is refused.
fn whole(check: impl Fn(&[u8]) -> Check, m: &Msg) {
    let buf = m.aligned();
    assert_eq!(check(buf.bytes()), Ok(()), "{:02x?}", buf.bytes());
    for len in 0..buf.bytes().len() {
        assert!(
            check(&buf.bytes()[..len]).is_err(),
            "a prefix of {len} bytes passed: {:02x?}",
            buf.bytes()
        );
    }
}

fn whole_request(iface: T, name: &str, m: &Msg, dialect: Dialect) {
    let i = index(iface, name);
    whole(|b| check_request(iface.layout(), i, b, LOCAL, dialect).map(|_| ()), m);
}

fn whole_reply(iface: T, name: &str, ctx: &Context, m: &Msg, dialect: Dialect) {
    let i = index(iface, name);
    whole(|b| check_reply(iface.layout(), i, ctx, b, LOCAL, dialect), m);
}

const BOTH: [Dialect; 2] = [Dialect::Ndr, Dialect::Wine];
