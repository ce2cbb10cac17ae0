//! The enumerator of class identifiers EnumClassesOfCategories returns: IOPCEnumGUID (OPC Common 1.10),
//! which has the layout of the system's IEnumGUID and answers QueryInterface for both.

use core::ffi::c_void;
use core::ptr;
use std::sync::{Arc, Mutex};

use crate::com::boundary::catch;
use crate::com::iids::{IID_IOPCEnumGUID, IID_IENUMGUID};
use crate::com::object::{
    delegating_add_ref, delegating_query_interface, delegating_release, ComClass, ComObject, Slot,
};
use crate::com::{CLSID, E_INVALIDARG, E_POINTER, E_UNEXPECTED, GUID, HRESULT, REFIID, S_FALSE, S_OK, ULONG};

/// The methods of IOPCEnumGUID (the same as IEnumGUID's).
#[repr(C)]
#[allow(non_snake_case)]
pub struct IOPCEnumGUIDVtbl {
    pub QueryInterface:
        unsafe extern "system" fn(This: *mut IOPCEnumGUID, riid: REFIID, ppvObject: *mut *mut c_void) -> HRESULT,
    pub AddRef: unsafe extern "system" fn(This: *mut IOPCEnumGUID) -> ULONG,
    pub Release: unsafe extern "system" fn(This: *mut IOPCEnumGUID) -> ULONG,
    pub Next: unsafe extern "system" fn(
        This: *mut IOPCEnumGUID,
        celt: ULONG,
        rgelt: *mut CLSID,
        pceltFetched: *mut ULONG,
    ) -> HRESULT,
    pub Skip: unsafe extern "system" fn(This: *mut IOPCEnumGUID, celt: ULONG) -> HRESULT,
    pub Reset: unsafe extern "system" fn(This: *mut IOPCEnumGUID) -> HRESULT,
    pub Clone: unsafe extern "system" fn(This: *mut IOPCEnumGUID, ppenum: *mut *mut IOPCEnumGUID) -> HRESULT,
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
        unsafe extern "system" fn(This: *mut IEnumGUID, riid: REFIID, ppvObject: *mut *mut c_void) -> HRESULT,
    pub AddRef: unsafe extern "system" fn(This: *mut IEnumGUID) -> ULONG,
    pub Release: unsafe extern "system" fn(This: *mut IEnumGUID) -> ULONG,
    pub Next: unsafe extern "system" fn(
        This: *mut IEnumGUID,
        celt: ULONG,
        rgelt: *mut CLSID,
        pceltFetched: *mut ULONG,
    ) -> HRESULT,
    pub Skip: unsafe extern "system" fn(This: *mut IEnumGUID, celt: ULONG) -> HRESULT,
    pub Reset: unsafe extern "system" fn(This: *mut IEnumGUID) -> HRESULT,
    pub Clone: unsafe extern "system" fn(This: *mut IEnumGUID, ppenum: *mut *mut IEnumGUID) -> HRESULT,
}

/// The system's IEnumGUID (comcat.h), which IOPCServerList::EnumClassesOfCategories returns.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
pub struct IEnumGUID {
    pub lpVtbl: *const IEnumGUIDVtbl,
}

/// The enumerator object: a shared, immutable list and this enumerator's position in it.
pub(crate) struct GuidEnum {
    slot: Slot,
    items: Arc<[GUID]>,
    position: Mutex<usize>,
}

impl ComClass for GuidEnum {
    fn interface(&self, iid: &GUID) -> Option<&Slot> {
        (*iid == IID_IOPCEnumGUID || *iid == IID_IENUMGUID).then_some(&self.slot)
    }
}

static VTBL: IOPCEnumGUIDVtbl = IOPCEnumGUIDVtbl {
    QueryInterface: delegating_query_interface::<IOPCEnumGUID>,
    AddRef: delegating_add_ref::<IOPCEnumGUID>,
    Release: delegating_release::<IOPCEnumGUID>,
    Next: next,
    Skip: skip,
    Reset: reset,
    Clone: clone,
};

impl GuidEnum {
    fn position(&self) -> std::sync::MutexGuard<'_, usize> {
        self.position.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// A new enumerator over `items` at `position`, as an IOPCEnumGUID pointer carrying one reference.
pub(crate) fn new_enum(items: Arc<[GUID]>, position: usize) -> *mut IOPCEnumGUID {
    let obj = ComObject::<GuidEnum>::new(ptr::null_mut(), |b| GuidEnum {
        slot: b.slot(&VTBL),
        items,
        position: Mutex::new(position),
    });
    let p = obj.slot.as_ptr().cast();
    // The construction reference now belongs to the caller, through the interface pointer (the
    // object is not aggregated, so the slot's Release reaches the same count).
    core::mem::forget(obj);
    p
}

/// # Safety
/// `this` is an IOPCEnumGUID pointer of a live GuidEnum (COM calls only reach us that way).
unsafe fn object<'a>(this: *mut IOPCEnumGUID) -> &'a GuidEnum {
    // SAFETY: VTBL is only installed in GuidEnum objects.
    unsafe { ComObject::<GuidEnum>::from_interface(this) }
}

unsafe extern "system" fn next(
    this: *mut IOPCEnumGUID,
    celt: ULONG,
    rgelt: *mut CLSID,
    fetched: *mut ULONG,
) -> HRESULT {
    if !fetched.is_null() {
        // SAFETY: non-NULL out-parameter the caller vouches is writable.
        unsafe { *fetched = 0 };
    }
    // COM: the count of fetched elements may only be omitted when asking for one.
    if fetched.is_null() && celt > 1 {
        return E_INVALIDARG;
    }
    if celt == 0 {
        return S_OK;
    }
    if rgelt.is_null() {
        return E_POINTER;
    }
    catch(E_UNEXPECTED, || {
        // SAFETY: COM calls this only through our vtable.
        let e = unsafe { object(this) };
        let mut pos = e.position();
        let n = (celt as usize).min(e.items.len() - *pos);
        // SAFETY: the caller provides room for `celt` >= `n` elements.
        unsafe { ptr::copy_nonoverlapping(e.items[*pos..].as_ptr(), rgelt, n) };
        *pos += n;
        if !fetched.is_null() {
            // SAFETY: as above.
            unsafe { *fetched = n as ULONG };
        }
        if n == celt as usize {
            S_OK
        } else {
            S_FALSE
        }
    })
}

unsafe extern "system" fn skip(this: *mut IOPCEnumGUID, celt: ULONG) -> HRESULT {
    catch(E_UNEXPECTED, || {
        // SAFETY: COM calls this only through our vtable.
        let e = unsafe { object(this) };
        let mut pos = e.position();
        let n = (celt as usize).min(e.items.len() - *pos);
        *pos += n;
        if n == celt as usize {
            S_OK
        } else {
            S_FALSE
        }
    })
}

unsafe extern "system" fn reset(this: *mut IOPCEnumGUID) -> HRESULT {
    catch(E_UNEXPECTED, || {
        // SAFETY: COM calls this only through our vtable.
        *unsafe { object(this) }.position() = 0;
        S_OK
    })
}

unsafe extern "system" fn clone(this: *mut IOPCEnumGUID, ppenum: *mut *mut IOPCEnumGUID) -> HRESULT {
    if ppenum.is_null() {
        return E_POINTER;
    }
    // SAFETY: non-NULL out-parameter.
    unsafe { *ppenum = ptr::null_mut() };
    catch(E_UNEXPECTED, || {
        // SAFETY: COM calls this only through our vtable.
        let e = unsafe { object(this) };
        let position = *e.position();
        // SAFETY: as above.
        unsafe { *ppenum = new_enum(e.items.clone(), position) };
        S_OK
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::com::unknown::{query_interface, release, IUnknown};

    fn g(n: u128) -> GUID {
        GUID::from_u128(n)
    }

    #[test]
    fn next_skip_reset_clone_follow_the_enumerator_rules() {
        let p = new_enum(vec![g(1), g(2), g(3)].into(), 0);
        // SAFETY: `p` is a live enumerator; every pointer passed is valid or deliberately NULL.
        unsafe {
            let v = &*(*p).lpVtbl;
            let mut out = [GUID::default(); 4];
            let mut n = 99;
            assert_eq!((v.Next)(p, 2, out.as_mut_ptr(), &mut n), S_OK);
            assert_eq!((n, out[0], out[1]), (2, g(1), g(2)));
            let mut copy = ptr::null_mut();
            assert_eq!((v.Clone)(p, &mut copy), S_OK);
            assert_eq!((v.Next)(p, 4, out.as_mut_ptr(), &mut n), S_FALSE);
            assert_eq!((n, out[0]), (1, g(3)));
            assert_eq!((v.Next)(p, 1, out.as_mut_ptr(), ptr::null_mut()), S_FALSE);
            assert_eq!((v.Next)(p, 2, out.as_mut_ptr(), ptr::null_mut()), E_INVALIDARG);
            assert_eq!((v.Next)(p, 1, ptr::null_mut(), &mut n), E_POINTER);
            assert_eq!((v.Reset)(p), S_OK);
            assert_eq!((v.Skip)(p, 2), S_OK);
            assert_eq!((v.Skip)(p, 5), S_FALSE);
            assert_eq!((v.Skip)(p, u32::MAX), S_FALSE);
            // The clone kept its own position.
            assert_eq!((v.Next)(copy, 1, out.as_mut_ptr(), ptr::null_mut()), S_OK);
            assert_eq!(out[0], g(3));
            assert_eq!((v.Clone)(p, ptr::null_mut()), E_POINTER);
            let mut as_enum_guid = ptr::null_mut();
            assert_eq!(
                query_interface(p.cast::<IUnknown>(), &IID_IENUMGUID, &mut as_enum_guid),
                S_OK
            );
            assert_eq!(as_enum_guid, p.cast());
            release(as_enum_guid.cast());
            assert_eq!(release(copy.cast()), 0);
            assert_eq!(release(p.cast()), 0);
        }
    }
}
