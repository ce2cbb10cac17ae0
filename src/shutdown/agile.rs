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
use core::ptr;
use std::sync::OnceLock;

use crate::com::ffi::{self, FfiResult};
use crate::com::interfaces::IMarshalImpl;
use crate::com::object::{ComClass, ComObject};
use crate::com::ole32::CoCreateFreeThreadedMarshaler;
use crate::com::unknown::{query, Counted};
use crate::com::{IUnknown, CLSID, DWORD, E_POINTER, GUID, HRESULT, IID, S_OK};

pub(crate) use crate::com::interfaces::IMarshal;

/// `IID_IMarshal`.
pub(crate) const IID_IMARSHAL: GUID = IMarshal::IID;

/// The aggregated FTM of one object: its non-delegating IUnknown, created on first use.
#[derive(Default)]
pub(crate) struct Ftm(OnceLock<Result<FtmInner, HRESULT>>);

struct FtmInner(Counted<IUnknown>);

// SAFETY: the free-threaded marshaler is, by definition, callable (and released) from any thread.
unsafe impl Send for FtmInner {}
// SAFETY: as above.
unsafe impl Sync for FtmInner {}

/// Objects whose IMarshal slot is backed by an aggregated FTM.
pub(crate) trait HasFtm: ComClass {
    fn ftm(&self) -> &Ftm;
}

/// Runs `f` with the FTM's IMarshal for the object behind `this`.
///
fn with_ftm<T: HasFtm>(obj: &ComObject<T>, f: impl FnOnce(*mut IMarshal) -> HRESULT) -> HRESULT {
    {
        let inner = obj.ftm().0.get_or_init(|| {
            let mut unk: *mut c_void = ptr::null_mut();
            // The object is its own controlling unknown (the sink is never aggregated).
            let outer = obj.header().controlling_unknown();
            // SAFETY: a valid outer unknown and out-pointer.
            let hr = unsafe { CoCreateFreeThreadedMarshaler(outer.cast(), &mut unk) };
            if hr != S_OK {
                // A pointer left behind with a failure is not trusted, not released.
                return Err(hr);
            }
            // SAFETY: the reference CoCreateFreeThreadedMarshaler gave us (the outer releases its
            // inner as the owner drops).
            unsafe { Counted::adopt(unk.cast::<IUnknown>()) }
                .map(FtmInner)
                .ok_or(E_POINTER)
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

// The free-threaded marshaler writes the out-parameters itself; the arguments go to it as the shim
// checked them.
impl<T: HasFtm> IMarshalImpl for T {
    fn GetUnmarshalClass(
        this: &ComObject<Self>,
        riid: &IID,
        pv: ffi::Opaque<'_>,
        ctx: DWORD,
        pvctx: ffi::Opaque<'_>,
        flags: DWORD,
        clsid: ffi::Out<'_, CLSID>,
    ) -> FfiResult {
        // SAFETY: `m` is the FTM's IMarshal; the arguments are the caller's, checked by the shim.
        Ok(with_ftm(this, |m| unsafe {
            IMarshal::GetUnmarshalClass(m, riid, pv.as_ptr(), ctx, pvctx.as_ptr(), flags, clsid.as_ptr())
        }))
    }

    fn GetMarshalSizeMax(
        this: &ComObject<Self>,
        riid: &IID,
        pv: ffi::Opaque<'_>,
        ctx: DWORD,
        pvctx: ffi::Opaque<'_>,
        flags: DWORD,
        size: ffi::Out<'_, DWORD>,
    ) -> FfiResult {
        // SAFETY: as above.
        Ok(with_ftm(this, |m| unsafe {
            IMarshal::GetMarshalSizeMax(m, riid, pv.as_ptr(), ctx, pvctx.as_ptr(), flags, size.as_ptr())
        }))
    }

    fn MarshalInterface(
        this: &ComObject<Self>,
        stream: ffi::Opaque<'_>,
        riid: &IID,
        pv: ffi::Opaque<'_>,
        ctx: DWORD,
        pvctx: ffi::Opaque<'_>,
        flags: DWORD,
    ) -> FfiResult {
        // SAFETY: as above.
        Ok(with_ftm(this, |m| unsafe {
            IMarshal::MarshalInterface(m, stream.as_ptr(), riid, pv.as_ptr(), ctx, pvctx.as_ptr(), flags)
        }))
    }

    fn UnmarshalInterface(
        this: &ComObject<Self>,
        stream: ffi::Opaque<'_>,
        riid: &IID,
        ppv: ffi::Out<'_, *mut c_void>,
    ) -> FfiResult {
        // SAFETY: as above.
        Ok(with_ftm(this, |m| unsafe {
            IMarshal::UnmarshalInterface(m, stream.as_ptr(), riid, ppv.as_ptr())
        }))
    }

    fn ReleaseMarshalData(this: &ComObject<Self>, stream: ffi::Opaque<'_>) -> FfiResult {
        // SAFETY: as above.
        Ok(with_ftm(this, |m| unsafe {
            IMarshal::ReleaseMarshalData(m, stream.as_ptr())
        }))
    }

    fn DisconnectObject(this: &ComObject<Self>, reserved: DWORD) -> FfiResult {
        // SAFETY: as above.
        Ok(with_ftm(this, |m| unsafe { IMarshal::DisconnectObject(m, reserved) }))
    }
}
