//! The proxy/stub's checks of the NDR bytes of the interfaces it serves, made before the runtime's NDR
//! engine reads them, by the interfaces' names (the tests and the fuzz targets call these; the C
//! boundary in `super` calls [`super::ndr`] with the interface's number).
//!
//! The tables `widl` generates carry no correlation checks (no `/robust` correlation descriptors),
//! and Wine's NDR engine would not enforce them if they did (`NdrCorrelationInitialize` and
//! `NdrCorrelationPass` are stubs in Wine 8): a count on the wire that sizes an array was believed
//! as sent. So opccomn checks every request before the stub unmarshals it and every reply before the
//! proxy unmarshals it (`src/proxy/opccomn_ps.c` calls these functions from its `Invoke` and channel
//! wrappers). The checks are not written per method: `tools/gen-header` generates each method's
//! layout from the IDL (`src/proxy/generated/layouts.rs`, in the language of
//! [`super::ndr::layout`]) and [`super::ndr`] reads a message against it; that module says what is
//! enforced. What is refused never reaches the NDR engine or the server: the call fails with
//! `RPC_X_BAD_STUB_DATA`, `RPC_S_INVALID_BOUND` (a count beyond its bound, as MIDL's `[range]`
//! reports it) or `RPC_S_PROCNUM_OUT_OF_RANGE` (no such method), as HRESULTs.
//!
//! A message may carry bytes after what is read (the runtime sizes buffers generously).

pub use super::layouts::Interface;
use super::ndr;
pub use super::ndr::{Context, Dialect};
pub(crate) use super::ndr::{BAD_STUB_DATA, INVALID_BOUND, PROCNUM_OUT_OF_RANGE};
use crate::com::HRESULT;

/// The bound of every array of the OPC Common interfaces whose count a peer chooses (GUIDs asked of
/// `IOPCEnumGUID::Next`, categories given to `EnumClassesOfCategories`, locales returned by
/// `QueryAvailableLocaleIDs`; `idl/ndr-bounds.txt`).
pub(crate) const MAX_ELEMENTS: u32 = ndr::DEFAULT_BOUND;

/// The OPC Common interfaces (the first five of [`Interface`]; the hand-written checks of
/// `reference`, which the generated ones are compared with, know only these).
///
/// cbindgen:ignore
pub const COMMON: [Interface; 5] = [
    Interface::IOPCShutdown,
    Interface::IOPCCommon,
    Interface::IOPCServerList,
    Interface::IOPCEnumGUID,
    Interface::IOPCServerList2,
];

/// `NDR_LOCAL_DATA_REPRESENTATION`, as the proxy's own requests are.
const LOCAL: u32 = 0x10;

type Check = Result<(), HRESULT>;

/// Checks a request for `method` (its vtable index) of `interface` before the stub unmarshals it.
/// `dialect`: the runtime that reads it (this process's).
pub fn check_request(interface: Interface, method: u32, buf: &[u8], drep: u32, dialect: Dialect) -> Check {
    ndr::check_request(interface.layout(), method, buf, drep, dialect).map(|_| ())
}

/// What a reply check needs to know of the request the proxy sent (`request`, the proxy's own):
/// `IOPCEnumGUID::Next`'s `celt` (the size of the caller's buffer); nothing for the other methods
/// (and for a request the checks refuse).
pub fn reply_context(interface: Interface, method: u32, request: &[u8], dialect: Dialect) -> Context {
    ndr::check_request(interface.layout(), method, request, LOCAL, dialect).unwrap_or_default()
}

/// Checks a reply to `method` of `interface` before the proxy unmarshals it into the caller's memory.
/// `context` is [`reply_context`] of the request; `dialect` the runtime that reads it (this
/// process's: it decides, among other things, the layout of interface pointers, the one thing a
/// message cannot say).
pub fn check_reply(
    interface: Interface,
    method: u32,
    context: &Context,
    buf: &[u8],
    drep: u32,
    dialect: Dialect,
) -> Check {
    ndr::check_reply(interface.layout(), method, context, buf, drep, dialect)
}

#[cfg(feature = "fuzzing")]
pub mod reference;
#[cfg(all(test, not(feature = "fuzzing")))]
mod reference;

#[cfg(test)]
mod tests;
