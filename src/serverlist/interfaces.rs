//! The enumerator interface EnumClassesOfCategories returns: IOPCEnumGUID (OPC Common 1.10), which has
//! the layout of the system's IEnumGUID; the library's enumerator (`com::enumerator`) answers
//! QueryInterface for both.

use crate::com::ffi::{Crossed, Hr};
use core::ffi::c_void;

use crate::com::{CLSID, REFIID, ULONG};

/// The methods of IOPCEnumGUID (the same as IEnumGUID's).
#[repr(C)]
#[allow(non_snake_case)]
pub struct IOPCEnumGUIDVtbl {
    pub QueryInterface:
        unsafe extern "system" fn(This: *mut IOPCEnumGUID, riid: REFIID, ppvObject: *mut *mut c_void) -> Hr,
    pub AddRef: unsafe extern "system" fn(This: *mut IOPCEnumGUID) -> Crossed<ULONG>,
    pub Release: unsafe extern "system" fn(This: *mut IOPCEnumGUID) -> Crossed<ULONG>,
    pub Next: unsafe extern "system" fn(
        This: *mut IOPCEnumGUID,
        celt: ULONG,
        rgelt: *mut CLSID,
        pceltFetched: *mut ULONG,
    ) -> Hr,
    pub Skip: unsafe extern "system" fn(This: *mut IOPCEnumGUID, celt: ULONG) -> Hr,
    pub Reset: unsafe extern "system" fn(This: *mut IOPCEnumGUID) -> Hr,
    pub Clone: unsafe extern "system" fn(This: *mut IOPCEnumGUID, ppenum: *mut *mut IOPCEnumGUID) -> Hr,
}

/// IOPCEnumGUID: an enumeration of GUIDs (the class identifiers of servers).
#[repr(C)]
#[allow(non_snake_case)]
pub struct IOPCEnumGUID {
    pub lpVtbl: *const IOPCEnumGUIDVtbl,
}

/// The methods of the system's IEnumGUID.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IEnumGUIDVtbl {
    pub QueryInterface:
        unsafe extern "system" fn(This: *mut IEnumGUID, riid: REFIID, ppvObject: *mut *mut c_void) -> Hr,
    pub AddRef: unsafe extern "system" fn(This: *mut IEnumGUID) -> Crossed<ULONG>,
    pub Release: unsafe extern "system" fn(This: *mut IEnumGUID) -> Crossed<ULONG>,
    pub Next:
        unsafe extern "system" fn(This: *mut IEnumGUID, celt: ULONG, rgelt: *mut CLSID, pceltFetched: *mut ULONG) -> Hr,
    pub Skip: unsafe extern "system" fn(This: *mut IEnumGUID, celt: ULONG) -> Hr,
    pub Reset: unsafe extern "system" fn(This: *mut IEnumGUID) -> Hr,
    pub Clone: unsafe extern "system" fn(This: *mut IEnumGUID, ppenum: *mut *mut IEnumGUID) -> Hr,
}

/// The system's IEnumGUID (comcat.h), which IOPCServerList::EnumClassesOfCategories returns.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IEnumGUID {
    pub lpVtbl: *const IEnumGUIDVtbl,
}
