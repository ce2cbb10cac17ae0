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

#[cfg(not(system_com_headers))]
pub const S_OK: HRESULT = 0;
#[cfg(not(system_com_headers))]
pub const S_FALSE: HRESULT = 1;
#[cfg(not(system_com_headers))]
pub const E_NOTIMPL: HRESULT = 0x80004001_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const E_NOINTERFACE: HRESULT = 0x80004002_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const E_POINTER: HRESULT = 0x80004003_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const E_FAIL: HRESULT = 0x80004005_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const E_UNEXPECTED: HRESULT = 0x8000FFFF_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const E_OUTOFMEMORY: HRESULT = 0x8007000E_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const E_INVALIDARG: HRESULT = 0x80070057_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const CLASS_E_NOAGGREGATION: HRESULT = 0x80040110_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const CLASS_E_CLASSNOTAVAILABLE: HRESULT = 0x80040111_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const CONNECT_E_NOCONNECTION: HRESULT = 0x80040200_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const CONNECT_E_ADVISELIMIT: HRESULT = 0x80040201_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const CONNECT_E_CANNOTCONNECT: HRESULT = 0x80040202_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const REGDB_E_CLASSNOTREG: HRESULT = 0x80040154_u32 as HRESULT;
#[cfg(not(system_com_headers))]
pub const CO_E_CLASSSTRING: HRESULT = 0x800401F3_u32 as HRESULT;
pub const OPC_E_INVALIDFILTER: HRESULT = 0xC0040009_u32 as HRESULT;
