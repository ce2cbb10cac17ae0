//! The COM core every interface of the library reuses: base types, IUnknown, the object framework
//! (reference counting, identity, aggregation), the one FFI boundary (`ffi`) and the task allocator.

pub mod alloc;
pub mod enumerator;
pub mod ffi;
pub mod guids;
pub mod hresult;
pub mod iids;
pub mod interfaces;
#[cfg(windows)]
pub(crate) mod kept;
pub mod module_lock;
pub mod object;
#[cfg(windows)]
pub mod ole32;
pub mod options;
pub mod types;
pub mod unknown;
pub mod wstr;

pub use hresult::*;
pub use interfaces::{IUnknown, IUnknownVtbl};
pub use types::*;
