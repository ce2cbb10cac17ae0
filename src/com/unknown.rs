//! `IUnknown`, the root of every COM interface, in the exact COM layout.

use core::ffi::c_void;

use super::types::{HRESULT, REFIID, ULONG};

/// The three methods every COM interface starts with.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IUnknownVtbl {
    pub QueryInterface:
        unsafe extern "system" fn(This: *mut IUnknown, riid: REFIID, ppvObject: *mut *mut c_void) -> HRESULT,
    pub AddRef: unsafe extern "system" fn(This: *mut IUnknown) -> ULONG,
    pub Release: unsafe extern "system" fn(This: *mut IUnknown) -> ULONG,
}

/// A COM object seen through its `IUnknown` interface.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IUnknown {
    pub lpVtbl: *const IUnknownVtbl,
}

/// Calls `QueryInterface` on any COM interface pointer.
///
/// # Safety
/// `unknown` must be a valid COM interface pointer and `ppv` writable.
pub unsafe fn query_interface(unknown: *mut IUnknown, iid: &super::types::GUID, ppv: *mut *mut c_void) -> HRESULT {
    // SAFETY: every COM interface starts with the IUnknown methods; the caller vouches for the pointer.
    unsafe { ((*(*unknown).lpVtbl).QueryInterface)(unknown, iid, ppv) }
}

/// Calls `AddRef` on any COM interface pointer.
///
/// # Safety
/// `unknown` must be a valid COM interface pointer.
pub unsafe fn add_ref(unknown: *mut IUnknown) -> ULONG {
    // SAFETY: as for `query_interface`.
    unsafe { ((*(*unknown).lpVtbl).AddRef)(unknown) }
}

/// Calls `Release` on any COM interface pointer.
///
/// # Safety
/// `unknown` must be a valid COM interface pointer that the caller owns a reference to.
pub unsafe fn release(unknown: *mut IUnknown) -> ULONG {
    // SAFETY: as for `query_interface`.
    unsafe { ((*(*unknown).lpVtbl).Release)(unknown) }
}
