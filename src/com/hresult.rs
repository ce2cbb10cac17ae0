//! HRESULT values used by the library, with their Windows names.
//!
//! Values are written in their unsigned 32-bit form, as every SDK header lists them. The COM codes are
//! emitted into the C header only where <windows.h> does not define them (see `types.rs`).

use super::types::HRESULT;

/// Converts the unsigned form in which HRESULTs are published (`0x80070057`) to an `HRESULT`.
#[cfg(not(system_com_headers))]
pub const fn hr(v: u32) -> HRESULT {
    v as HRESULT
}

/// True for failure codes (`FAILED(hr)`).
#[cfg(not(system_com_headers))]
pub const fn failed(code: HRESULT) -> bool {
    code < 0
}

/// Success.
#[cfg(not(system_com_headers))]
pub const S_OK: HRESULT = 0;
/// Success, with a negative answer (fewer elements than asked, a declined request).
#[cfg(not(system_com_headers))]
pub const S_FALSE: HRESULT = 1;
/// Not implemented.
#[cfg(not(system_com_headers))]
pub const E_NOTIMPL: HRESULT = 0x80004001_u32 as HRESULT;
/// The object has no such interface.
#[cfg(not(system_com_headers))]
pub const E_NOINTERFACE: HRESULT = 0x80004002_u32 as HRESULT;
/// A NULL pointer where COM requires one (the COM methods' rule; OPC methods use E_INVALIDARG).
#[cfg(not(system_com_headers))]
pub const E_POINTER: HRESULT = 0x80004003_u32 as HRESULT;
/// Unspecified failure.
#[cfg(not(system_com_headers))]
pub const E_FAIL: HRESULT = 0x80004005_u32 as HRESULT;
/// Unexpected failure (opccomn: a panic caught at the boundary).
#[cfg(not(system_com_headers))]
pub const E_UNEXPECTED: HRESULT = 0x8000FFFF_u32 as HRESULT;
/// Out of memory.
#[cfg(not(system_com_headers))]
pub const E_OUTOFMEMORY: HRESULT = 0x8007000E_u32 as HRESULT;
/// An argument is invalid (OPC methods: also a NULL pointer).
#[cfg(not(system_com_headers))]
pub const E_INVALIDARG: HRESULT = 0x80070057_u32 as HRESULT;
/// The class cannot be aggregated this way (an outer object with an IID other than IUnknown).
#[cfg(not(system_com_headers))]
pub const CLASS_E_NOAGGREGATION: HRESULT = 0x80040110_u32 as HRESULT;
/// The class object does not serve this CLSID.
#[cfg(not(system_com_headers))]
pub const CLASS_E_CLASSNOTAVAILABLE: HRESULT = 0x80040111_u32 as HRESULT;
/// No such connection (an unknown cookie, or no such connection point).
#[cfg(not(system_com_headers))]
pub const CONNECT_E_NOCONNECTION: HRESULT = 0x80040200_u32 as HRESULT;
/// The connection point takes no more sinks.
#[cfg(not(system_com_headers))]
pub const CONNECT_E_ADVISELIMIT: HRESULT = 0x80040201_u32 as HRESULT;
/// The sink does not implement the connection point's interface.
#[cfg(not(system_com_headers))]
pub const CONNECT_E_CANNOTCONNECT: HRESULT = 0x80040202_u32 as HRESULT;
/// The class is not registered.
#[cfg(not(system_com_headers))]
pub const REGDB_E_CLASSNOTREG: HRESULT = 0x80040154_u32 as HRESULT;
/// Not a valid ProgID or CLSID string.
#[cfg(not(system_com_headers))]
pub const CO_E_CLASSSTRING: HRESULT = 0x800401F3_u32 as HRESULT;
/// The filter string was not valid (MatchPattern's compiled filter).
pub const OPC_E_INVALIDFILTER: HRESULT = 0xC0040009_u32 as HRESULT;
