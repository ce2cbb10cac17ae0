//! Windows only: makes the client sink agile by aggregating the COM free-threaded marshaler (FTM).
//!
//! The sink's only state is a C callback that the library documents as callable from any thread, so
//! there is no reason to confine it to the apartment that created it. With the FTM, marshaling the
//! sink to another apartment of the same process yields the sink itself: a server notifying from
//! another apartment calls the callback directly on its own thread, and no proxy/stub for
//! IOPCShutdown is needed in-process. (Across processes the FTM defers to standard marshaling, which
//! needs the IOPCShutdown proxy/stub as always.)
//!
//! The sink's IMarshal slot forwards every call to the FTM's IMarshal. The FTM is created on first use,
//! aggregated with the sink as its outer object; the sink keeps the FTM's non-delegating IUnknown and
//! asks it for IMarshal per call (releasing right after), so the sink never holds a reference to itself.

use core::ffi::c_void;
use core::ptr::{self, NonNull};
use std::sync::OnceLock;

use crate::com::ffi::{self, Crossed, Hr};
use crate::com::object::{delegating_add_ref, delegating_query_interface, delegating_release, ComClass, ComObject};
use crate::com::ole32::CoCreateFreeThreadedMarshaler;
use crate::com::unknown::{query, release};
use crate::com::{IUnknown, DWORD, E_POINTER, GUID, HRESULT, REFIID, S_OK, ULONG};

/// `IID_IMarshal` {00000003-0000-0000-C000-000000000046}.
pub(crate) const IID_IMARSHAL: GUID = GUID::from_u128(0x00000003_0000_0000_C000_000000000046);

/// IMarshal in its COM layout (streams are passed through untouched, so they stay `c_void`).
#[repr(C)]
#[allow(non_snake_case)]
pub(crate) struct IMarshalVtbl {
    QueryInterface: unsafe extern "system" fn(*mut IMarshal, REFIID, *mut *mut c_void) -> Hr,
    AddRef: unsafe extern "system" fn(*mut IMarshal) -> Crossed<ULONG>,
    Release: unsafe extern "system" fn(*mut IMarshal) -> Crossed<ULONG>,
    GetUnmarshalClass:
        unsafe extern "system" fn(*mut IMarshal, REFIID, *mut c_void, DWORD, *mut c_void, DWORD, *mut GUID) -> Hr,
    GetMarshalSizeMax:
        unsafe extern "system" fn(*mut IMarshal, REFIID, *mut c_void, DWORD, *mut c_void, DWORD, *mut DWORD) -> Hr,
    MarshalInterface:
        unsafe extern "system" fn(*mut IMarshal, *mut c_void, REFIID, *mut c_void, DWORD, *mut c_void, DWORD) -> Hr,
    UnmarshalInterface: unsafe extern "system" fn(*mut IMarshal, *mut c_void, REFIID, *mut *mut c_void) -> Hr,
    ReleaseMarshalData: unsafe extern "system" fn(*mut IMarshal, *mut c_void) -> Hr,
    DisconnectObject: unsafe extern "system" fn(*mut IMarshal, DWORD) -> Hr,
}

#[repr(C)]
pub(crate) struct IMarshal {
    vtbl: *const IMarshalVtbl,
}

/// The aggregated FTM of one object: its non-delegating IUnknown, created on first use.
#[derive(Default)]
pub(crate) struct Ftm(OnceLock<Result<FtmInner, HRESULT>>);

struct FtmInner(NonNull<IUnknown>);

// SAFETY: the free-threaded marshaler is, by definition, callable from any thread.
unsafe impl Send for FtmInner {}
// SAFETY: as above.
unsafe impl Sync for FtmInner {}

impl Drop for FtmInner {
    fn drop(&mut self) {
        // SAFETY: the reference CoCreateFreeThreadedMarshaler gave us; the outer releases its inner.
        unsafe { release(self.0.as_ptr()) };
    }
}

/// Objects whose IMarshal slot is backed by an aggregated FTM.
pub(crate) trait HasFtm: ComClass {
    fn ftm(&self) -> &Ftm;
}

/// The IMarshal vtable for objects of type `T`.
pub(crate) struct MarshalVtbl<T>(core::marker::PhantomData<T>);

impl<T: HasFtm> MarshalVtbl<T> {
    pub(crate) const VTBL: IMarshalVtbl = IMarshalVtbl {
        QueryInterface: delegating_query_interface::<IMarshal>,
        AddRef: delegating_add_ref::<IMarshal>,
        Release: delegating_release::<IMarshal>,
        GetUnmarshalClass: get_unmarshal_class::<T>,
        GetMarshalSizeMax: get_marshal_size_max::<T>,
        MarshalInterface: marshal_interface::<T>,
        UnmarshalInterface: unmarshal_interface::<T>,
        ReleaseMarshalData: release_marshal_data::<T>,
        DisconnectObject: disconnect_object::<T>,
    };
}

/// Runs `f` with the FTM's IMarshal for the object behind `this`.
///
/// # Safety
/// `this` must be the IMarshal slot of a live `ComObject<T>`.
unsafe fn with_ftm<T: HasFtm>(this: *mut IMarshal, f: impl FnOnce(*mut IMarshal) -> HRESULT) -> HRESULT {
    {
        // SAFETY: per the caller.
        let obj = unsafe { ComObject::<T>::from_interface(this) };
        let inner = obj.ftm().0.get_or_init(|| {
            let mut unk: *mut c_void = ptr::null_mut();
            // The object is its own controlling unknown (the sink is never aggregated).
            let outer = obj.header().controlling_unknown();
            // SAFETY: a valid outer unknown and out-pointer.
            let hr = unsafe { CoCreateFreeThreadedMarshaler(outer.cast(), &mut unk) };
            match NonNull::new(unk.cast::<IUnknown>()) {
                Some(p) if hr == S_OK => Ok(FtmInner(p)),
                _ => Err(if hr == S_OK { E_POINTER } else { hr }),
            }
        });
        let inner = match inner {
            Ok(inner) => inner,
            Err(hr) => return *hr,
        };
        // SAFETY: the FTM's inner unknown is alive while the object is.
        let marshal = match unsafe { query::<IMarshal>(inner.0.as_ptr(), &IID_IMARSHAL) } {
            Ok(m) => m,
            Err(hr) => return hr,
        };
        // The reference QueryInterface gave us (counted on this object, the outer) is released when
        // `marshal` drops.
        f(marshal.as_ptr())
    }
}

unsafe extern "system" fn get_unmarshal_class<T: HasFtm>(
    this: *mut IMarshal,
    riid: REFIID,
    pv: *mut c_void,
    ctx: DWORD,
    pvctx: *mut c_void,
    flags: DWORD,
    clsid: *mut GUID,
) -> Hr {
    // The free-threaded marshaler checks and writes the arguments itself.
    ffi::boundary!(Com, [], {
        // SAFETY: COM calls this only through our vtable; the arguments go to the FTM unchanged.
        Ok(unsafe {
            with_ftm::<T>(this, |m| {
                ((*(*m).vtbl).GetUnmarshalClass)(m, riid, pv, ctx, pvctx, flags, clsid).get()
            })
        })
    })
}

unsafe extern "system" fn get_marshal_size_max<T: HasFtm>(
    this: *mut IMarshal,
    riid: REFIID,
    pv: *mut c_void,
    ctx: DWORD,
    pvctx: *mut c_void,
    flags: DWORD,
    size: *mut DWORD,
) -> Hr {
    // The free-threaded marshaler checks and writes the arguments itself.
    ffi::boundary!(Com, [], {
        // SAFETY: as above.
        Ok(unsafe {
            with_ftm::<T>(this, |m| {
                ((*(*m).vtbl).GetMarshalSizeMax)(m, riid, pv, ctx, pvctx, flags, size).get()
            })
        })
    })
}

unsafe extern "system" fn marshal_interface<T: HasFtm>(
    this: *mut IMarshal,
    stream: *mut c_void,
    riid: REFIID,
    pv: *mut c_void,
    ctx: DWORD,
    pvctx: *mut c_void,
    flags: DWORD,
) -> Hr {
    // The free-threaded marshaler checks and writes the arguments itself.
    ffi::boundary!(Com, [], {
        // SAFETY: as above.
        Ok(unsafe {
            with_ftm::<T>(this, |m| {
                ((*(*m).vtbl).MarshalInterface)(m, stream, riid, pv, ctx, pvctx, flags).get()
            })
        })
    })
}

unsafe extern "system" fn unmarshal_interface<T: HasFtm>(
    this: *mut IMarshal,
    stream: *mut c_void,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> Hr {
    // The free-threaded marshaler checks and writes the arguments itself.
    ffi::boundary!(Com, [], {
        // SAFETY: as above.
        Ok(unsafe { with_ftm::<T>(this, |m| ((*(*m).vtbl).UnmarshalInterface)(m, stream, riid, ppv).get()) })
    })
}

unsafe extern "system" fn release_marshal_data<T: HasFtm>(this: *mut IMarshal, stream: *mut c_void) -> Hr {
    // The free-threaded marshaler checks and writes the arguments itself.
    ffi::boundary!(Com, [], {
        // SAFETY: as above.
        Ok(unsafe { with_ftm::<T>(this, |m| ((*(*m).vtbl).ReleaseMarshalData)(m, stream).get()) })
    })
}

unsafe extern "system" fn disconnect_object<T: HasFtm>(this: *mut IMarshal, reserved: DWORD) -> Hr {
    // The free-threaded marshaler checks and writes the arguments itself.
    ffi::boundary!(Com, [], {
        // SAFETY: as above.
        Ok(unsafe { with_ftm::<T>(this, |m| ((*(*m).vtbl).DisconnectObject)(m, reserved).get()) })
    })
}
