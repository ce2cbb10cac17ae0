//! `IUnknown`, the root of every COM interface, in the exact COM layout.

use core::ffi::c_void;
use core::ptr::NonNull;

use super::hresult::E_POINTER;
use super::types::{GUID, HRESULT, ULONG};

pub use super::interfaces::{IUnknown, IUnknownVtbl};

/// Calls `QueryInterface` on any COM interface pointer.
///
/// # Safety
/// `unknown` must be a valid COM interface pointer and `ppv` writable.
pub unsafe fn query_interface(unknown: *mut IUnknown, iid: &GUID, ppv: *mut *mut c_void) -> HRESULT {
    // SAFETY: every COM interface starts with the IUnknown methods; the caller vouches for the pointer.
    unsafe { IUnknown::QueryInterface(unknown, iid, ppv) }
}

/// Calls `AddRef` on any COM interface pointer.
///
/// # Safety
/// `unknown` must be a valid COM interface pointer.
pub unsafe fn add_ref(unknown: *mut IUnknown) -> ULONG {
    // SAFETY: as for `query_interface`.
    unsafe { IUnknown::AddRef(unknown) }
}

/// Calls `Release` on any COM interface pointer.
///
/// # Safety
/// `unknown` must be a valid COM interface pointer that the caller owns a reference to.
pub unsafe fn release(unknown: *mut IUnknown) -> ULONG {
    // SAFETY: as for `query_interface`.
    unsafe { IUnknown::Release(unknown) }
}

/// One counted reference to an interface of an object, released when dropped: the one owner of a COM
/// reference in the library (the system objects it creates, the sinks and objects callers hand it,
/// its own objects it keeps). It never holds NULL: a raw pointer becomes a `Counted` only through
/// [`Counted::adopt`], which answers `None` for NULL, so no owner can release through NULL (as one
/// built from a failed CoCreateInstance would).
///
/// Neither `Send` nor `Sync`: a COM interface pointer belongs to its apartment. An owner that may be
/// used from other threads says why in its own `unsafe impl`.
pub struct Counted<I>(NonNull<I>);

impl<I> Counted<I> {
    /// Takes over a counted reference; `None` for NULL.
    ///
    /// # Safety
    /// `p` must be NULL or a valid COM interface pointer carrying one reference the caller gives up.
    pub unsafe fn adopt(p: *mut I) -> Option<Self> {
        NonNull::new(p).map(Counted)
    }

    /// The interface pointer (still owned by `self`).
    pub fn as_ptr(&self) -> *mut I {
        self.0.as_ptr()
    }

    /// Gives up ownership: the caller now owns the reference.
    pub fn into_raw(self) -> NonNull<I> {
        let p = self.0;
        core::mem::forget(self);
        p
    }

    /// The same reference, as the IUnknown every interface begins with.
    pub fn into_unknown(self) -> Counted<IUnknown> {
        Counted(self.into_raw().cast())
    }
}

/// Another counted reference to the same interface (AddRef).
impl<I> Clone for Counted<I> {
    fn clone(&self) -> Self {
        // SAFETY: `self` keeps the interface alive; the reference added belongs to the result.
        unsafe { add_ref(self.0.as_ptr().cast()) };
        Counted(self.0)
    }
}

impl<I> Drop for Counted<I> {
    fn drop(&mut self) {
        // SAFETY: `self` owns one reference to a valid COM interface pointer.
        unsafe { release(self.0.as_ptr().cast()) };
    }
}

/// QueryInterface on an object the library does not control (a caller's object, a sink, an outer
/// object, a system object), checked as a hostile or broken answer requires. Every helper that asks
/// such an object for an interface goes through this.
///
/// - A failure HRESULT is returned as it is. A pointer left in the out-parameter with it is neither
///   used nor released: COM requires NULL on failure, so anything else may be garbage.
/// - A success code with a NULL pointer (a broken object) is `Err(E_POINTER)`.
/// - Otherwise the pointer and its reference are the caller's, as [`Counted`].
///
/// # Safety
/// `unknown` must be a valid COM interface pointer.
pub unsafe fn query<I>(unknown: *mut IUnknown, iid: &GUID) -> Result<Counted<I>, HRESULT> {
    let mut p: *mut c_void = core::ptr::null_mut();
    // SAFETY: the caller vouches for `unknown`; `p` is writable.
    let hr = unsafe { query_interface(unknown, iid, &mut p) };
    if hr < 0 {
        return Err(hr);
    }
    // SAFETY: a successful QueryInterface hands over one reference (NULL gives None).
    unsafe { Counted::adopt(p.cast::<I>()) }.ok_or(E_POINTER)
}

/// Objects that answer QueryInterface as a broken or hostile caller's might, for tests.
#[cfg(test)]
pub(crate) mod hostile {
    use core::ffi::c_void;
    use core::sync::atomic::{AtomicU32, Ordering};

    use super::{IUnknown, IUnknownVtbl};
    use crate::com::ffi::{Crossed, Hr};
    use crate::com::hresult::{E_NOINTERFACE, S_OK};
    use crate::com::types::{REFIID, ULONG};

    /// How the object answers every QueryInterface.
    #[derive(Clone, Copy)]
    pub(crate) enum Answer {
        /// S_OK with a NULL pointer.
        OkWithNull,
        /// E_NOINTERFACE with a garbage pointer left in the out-parameter.
        FailWithGarbage,
    }

    /// A COM object that counts AddRef/Release and answers QueryInterface with `answer`.
    #[repr(C)]
    pub(crate) struct Hostile {
        vtbl: &'static IUnknownVtbl,
        answer: Answer,
        refs: AtomicU32,
    }

    static VTBL: IUnknownVtbl = IUnknownVtbl {
        QueryInterface: qi,
        AddRef: add_ref,
        Release: release,
    };

    unsafe extern "system" fn qi(this: *mut IUnknown, _riid: REFIID, ppv: *mut *mut c_void) -> Hr {
        Crossed::from_c(|| {
            // SAFETY: only Hostile objects present VTBL; the library passes a writable `ppv`.
            unsafe {
                match (*(this as *const Hostile)).answer {
                    Answer::OkWithNull => {
                        *ppv = core::ptr::null_mut();
                        S_OK
                    }
                    Answer::FailWithGarbage => {
                        *ppv = core::ptr::NonNull::<u64>::dangling().as_ptr().cast();
                        E_NOINTERFACE
                    }
                }
            }
        })
    }

    unsafe extern "system" fn add_ref(this: *mut IUnknown) -> Crossed<ULONG> {
        Crossed::from_c(|| {
            // SAFETY: as above.
            unsafe { &*(this as *const Hostile) }
                .refs
                .fetch_add(1, Ordering::SeqCst)
                + 1
        })
    }

    unsafe extern "system" fn release(this: *mut IUnknown) -> Crossed<ULONG> {
        Crossed::from_c(|| {
            // SAFETY: as above.
            let before = unsafe { &*(this as *const Hostile) }
                .refs
                .fetch_sub(1, Ordering::SeqCst);
            assert!(before > 1, "released the reference the test holds");
            before - 1
        })
    }

    impl Hostile {
        pub(crate) fn new(answer: Answer) -> Box<Hostile> {
            Box::new(Hostile {
                vtbl: &VTBL,
                answer,
                refs: AtomicU32::new(1),
            })
        }

        pub(crate) fn unk(&self) -> *mut IUnknown {
            self as *const Hostile as *mut IUnknown
        }

        /// References held now (the test's own is 1).
        pub(crate) fn refs(&self) -> u32 {
            self.refs.load(Ordering::SeqCst)
        }
    }

    /// Both kinds.
    pub(crate) fn all() -> [Box<Hostile>; 2] {
        [Hostile::new(Answer::OkWithNull), Hostile::new(Answer::FailWithGarbage)]
    }
}

#[cfg(test)]
mod tests {
    use super::hostile::{Answer, Hostile};
    use super::*;
    use crate::com::hresult::E_NOINTERFACE;
    use crate::com::iids::IID_IUNKNOWN;

    #[test]
    fn query_refuses_a_null_success_and_ignores_what_a_failure_left_behind() {
        let h = Hostile::new(Answer::OkWithNull);
        // SAFETY: a valid COM object.
        let got = unsafe { query::<IUnknown>(h.unk(), &IID_IUNKNOWN) };
        assert_eq!(got.err(), Some(E_POINTER));
        let h2 = Hostile::new(Answer::FailWithGarbage);
        // SAFETY: as above. The garbage pointer must not be released (that would crash).
        let got = unsafe { query::<IUnknown>(h2.unk(), &IID_IUNKNOWN) };
        assert_eq!(got.err(), Some(E_NOINTERFACE));
        assert_eq!((h.refs(), h2.refs()), (1, 1));
    }

    #[test]
    fn an_owner_is_never_null_and_releases_exactly_what_it_owns() {
        // SAFETY: NULL is what a failed CoCreateInstance leaves behind: no owner comes of it.
        assert!(unsafe { Counted::<IUnknown>::adopt(core::ptr::null_mut()) }.is_none());
        let h = Hostile::new(Answer::OkWithNull);
        // SAFETY: a valid COM object; the reference added is the one the owner takes over.
        let owner = unsafe {
            add_ref(h.unk());
            Counted::adopt(h.unk())
        }
        .unwrap();
        assert_eq!(h.refs(), 2);
        let second = owner.clone();
        assert_eq!((h.refs(), second.as_ptr()), (3, h.unk()));
        drop(owner);
        let unknown = second.into_unknown();
        assert_eq!(h.refs(), 2);
        drop(unknown);
        assert_eq!(h.refs(), 1, "the test's own reference is left");
    }
}
