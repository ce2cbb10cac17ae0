//! The one snapshot enumerator behind every IEnumXXX interface the library hands out: IEnumGUID and
//! IOPCEnumGUID (the server list), IEnumConnections and IEnumConnectionPoints (shutdown).
//!
//! An enumerator walks a fixed list taken when it was made. The list is shared (`Arc`) between an
//! enumerator and its clones, so Clone copies nothing and costs no AddRefs; each element owns what it
//! refers to (a counted interface pointer owns one reference) and lets it go when the last enumerator
//! sharing the list dies. The methods follow COM's IEnumXXX contract:
//!
//! - `Next(celt, rgelt, pceltFetched)` writes up to `celt` elements, every interface pointer AddRef'd
//!   for the caller, and returns S_OK when it wrote all `celt`, S_FALSE when the list ended first
//!   (`*pceltFetched` says how many). `celt` 0 is S_OK with nothing written. `pceltFetched` may be
//!   NULL only when `celt` is 1. A NULL `rgelt` is E_POINTER.
//! - `Skip(celt)`: S_OK when `celt` elements were skipped, S_FALSE (at the end) when fewer were left.
//! - `Reset()`: back to the start, S_OK.
//! - `Clone(ppenum)`: a new enumerator over the same list at the same position.
//!
//! Counts are taken as given up to `ULONG::MAX`: only the elements that exist are ever written or
//! skipped, so a huge `celt` is safe (the caller's array needs room for the elements returned).
//!
//! A user of this module names the interface ([`EnumInterface`]), implements the interface's generated
//! trait for its enumerator with [`enum_impl!`](crate::enum_impl) and builds its static vtable with the
//! generated `IEnumXXXVtbl::new`; elements implement [`Element`].

use core::ptr;
use std::sync::{Arc, Mutex, MutexGuard};

use super::ffi::{self, Fail, FfiResult};
use super::hresult::{S_FALSE, S_OK};
use super::object::{ComClass, ComObject, Slot, Vtable};
use super::types::{GUID, HRESULT, ULONG};
use super::unknown::Counted;

/// One element of a snapshot.
pub(crate) trait Element: Send + Sync + 'static {
    /// What Next writes into the caller's array.
    type Out;
    /// A copy for the caller, carrying its own reference when the element is a counted pointer.
    fn hand_out(&self) -> Self::Out;
}

impl Element for GUID {
    type Out = GUID;
    fn hand_out(&self) -> GUID {
        *self
    }
}

/// A counted interface pointer as an element of a snapshot; handed out AddRef'd, released (as the
/// [`Counted`] it holds) when the last enumerator sharing the list dies.
pub(crate) struct Listed<I>(Counted<I>);

// SAFETY: a snapshot only holds pointers that may be used from the threads its enumerator is called on:
// the library's own free-threaded objects, or (connections) sinks fetched for the apartment that made
// the enumerator, which COM confines the enumerator to. `Listed::new` makes its caller vouch for it.
unsafe impl<I> Send for Listed<I> {}
// SAFETY: as above; the pointer itself is never changed after construction.
unsafe impl<I> Sync for Listed<I> {}

impl<I> Listed<I> {
    /// The element owning `p`'s reference.
    ///
    /// # Safety
    /// `p` must be usable and releasable on every thread the enumerator may be called on (see the
    /// `Send` implementation).
    pub(crate) unsafe fn new(p: Counted<I>) -> Listed<I> {
        Listed(p)
    }
}

impl<I: 'static> Element for Listed<I> {
    type Out = *mut I;
    fn hand_out(&self) -> *mut I {
        // The caller's copy carries its own reference.
        self.0.clone().into_raw().as_ptr()
    }
}

/// An enumerator interface: its element, C types, IIDs and static vtable.
pub(crate) trait EnumInterface: Send + Sync + Sized + 'static {
    /// The element of the snapshot.
    type Item: Element;
    /// The interface (`IEnumXXX`).
    type Iface;
    /// Its vtable type (generated).
    type Vtbl: Vtable;
    /// The interfaces the enumerator answers QueryInterface for (with the one vtable: they share a
    /// layout, as IOPCEnumGUID and IEnumGUID do).
    const IIDS: &'static [GUID];
    /// The vtable: `IEnumXXXVtbl::new::<Delegating, Enumerator<Self>>()`.
    fn vtbl() -> &'static Self::Vtbl;
}

/// Implements the generated trait `$trait` of an IEnumXXX interface for `Enumerator<$kind>` (an
/// [`EnumInterface`]) with this module's methods.
#[macro_export]
#[doc(hidden)]
macro_rules! enum_impl {
    ($trait:path, $kind:ty) => {
        impl $trait for $crate::com::enumerator::Enumerator<$kind> {
            fn Next(
                this: &$crate::com::object::ComObject<Self>,
                celt: $crate::com::ULONG,
                rgelt: $crate::com::ffi::OutArray<
                    '_,
                    <<$kind as $crate::com::enumerator::EnumInterface>::Item as $crate::com::enumerator::Element>::Out,
                >,
                pceltFetched: Option<$crate::com::ffi::Out<'_, $crate::com::ULONG>>,
            ) -> $crate::com::ffi::FfiResult {
                $crate::com::enumerator::next(this, celt, rgelt, pceltFetched)
            }
            fn Skip(
                this: &$crate::com::object::ComObject<Self>,
                celt: $crate::com::ULONG,
            ) -> $crate::com::ffi::FfiResult {
                $crate::com::enumerator::skip(this, celt)
            }
            fn Reset(this: &$crate::com::object::ComObject<Self>) -> $crate::com::ffi::FfiResult {
                $crate::com::enumerator::reset(this)
            }
            fn Clone(
                this: &$crate::com::object::ComObject<Self>,
                ppenum: $crate::com::ffi::Out<'_, *mut <$kind as $crate::com::enumerator::EnumInterface>::Iface>,
            ) -> $crate::com::ffi::FfiResult {
                $crate::com::enumerator::clone(this, ppenum)
            }
        }
    };
}

/// The enumerator object: a shared, immutable list and this enumerator's position in it.
pub(crate) struct Enumerator<K: EnumInterface> {
    slot: Slot,
    items: Arc<[K::Item]>,
    position: Mutex<usize>,
}

impl<K: EnumInterface> ComClass for Enumerator<K> {
    fn interface(&self, iid: &GUID) -> Option<&Slot> {
        K::IIDS.contains(iid).then_some(&self.slot)
    }
}

impl<K: EnumInterface> Enumerator<K> {
    /// A new enumerator over `items` at `position`, as an interface pointer carrying one reference.
    pub(crate) fn create(items: Arc<[K::Item]>, position: usize) -> *mut K::Iface {
        let obj = ComObject::<Enumerator<K>>::new(ptr::null_mut(), |binder| Enumerator {
            slot: binder.slot(K::vtbl()),
            items,
            position: Mutex::new(position),
        });
        // Not aggregated: the slot's reference count is the object's own, so the construction
        // reference becomes the reference of the returned interface pointer.
        let p = obj.slot.as_ptr().cast::<K::Iface>();
        core::mem::forget(obj);
        p
    }

    fn position(&self) -> MutexGuard<'_, usize> {
        self.position.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Advances by up to `celt` elements; returns the first index and how many were passed.
    fn advance(&self, celt: ULONG) -> (usize, usize) {
        let mut position = self.position();
        let start = (*position).min(self.items.len());
        let count = (self.items.len() - start).min(celt as usize);
        *position = start + count;
        (start, count)
    }
}

fn all_or_false(count: usize, celt: ULONG) -> HRESULT {
    if count == celt as usize {
        S_OK
    } else {
        S_FALSE
    }
}

/// IEnumXXX::Next (the generated shim has reset `pceltFetched` and refused a NULL `rgelt` for a
/// `celt` above 0).
pub(crate) fn next<K: EnumInterface>(
    e: &ComObject<Enumerator<K>>,
    celt: ULONG,
    mut rgelt: ffi::OutArray<'_, <K::Item as Element>::Out>,
    pceltFetched: Option<ffi::Out<'_, ULONG>>,
) -> FfiResult {
    if celt == 0 {
        return Ok(S_OK);
    }
    // COM: the count may be omitted only when asking for one element.
    if pceltFetched.is_none() && celt > 1 {
        return Err(Fail::Null);
    }
    let (start, count) = e.advance(celt);
    for (i, item) in e.items[start..start + count].iter().enumerate() {
        // `i < count <= celt`, the room the caller gave.
        rgelt.write(i, item.hand_out());
    }
    if let Some(fetched) = pceltFetched {
        // `count <= celt` fits a ULONG.
        fetched.write(count as ULONG);
    }
    Ok(all_or_false(count, celt))
}

/// IEnumXXX::Skip.
pub(crate) fn skip<K: EnumInterface>(e: &ComObject<Enumerator<K>>, celt: ULONG) -> FfiResult {
    let (_, count) = e.advance(celt);
    Ok(all_or_false(count, celt))
}

/// IEnumXXX::Reset.
pub(crate) fn reset<K: EnumInterface>(e: &ComObject<Enumerator<K>>) -> FfiResult {
    *e.position() = 0;
    Ok(S_OK)
}

/// IEnumXXX::Clone: a new enumerator over the same snapshot, at the same position.
pub(crate) fn clone<K: EnumInterface>(e: &ComObject<Enumerator<K>>, ppenum: ffi::Out<'_, *mut K::Iface>) -> FfiResult {
    let position = *e.position();
    ppenum.write(Enumerator::<K>::create(e.items.clone(), position));
    Ok(S_OK)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::com::hresult::E_POINTER;
    use crate::com::iids::IID_IUNKNOWN;
    use crate::com::interfaces::{
        IConnectionPoint, IEnumConnectionPoints, IEnumConnectionPointsImpl, IEnumConnectionPointsVtbl, IEnumGUID,
        IEnumGUIDImpl, IEnumGUIDVtbl,
    };
    use crate::com::object::Delegating;
    use crate::com::unknown::{add_ref, query_interface, release, IUnknown};

    const IID_TEST: GUID = GUID::from_u128(0x1234);
    const IID_TEST_ALIAS: GUID = GUID::from_u128(0x5678);

    /// GUIDs, presented as IEnumGUID under two test IIDs.
    struct Guids;
    static GUIDS_VTBL: IEnumGUIDVtbl = IEnumGUIDVtbl::new::<Delegating, Enumerator<Guids>>();
    crate::enum_impl!(IEnumGUIDImpl, Guids);
    impl EnumInterface for Guids {
        type Item = GUID;
        type Iface = IEnumGUID;
        type Vtbl = IEnumGUIDVtbl;
        const IIDS: &'static [GUID] = &[IID_TEST, IID_TEST_ALIAS];
        fn vtbl() -> &'static IEnumGUIDVtbl {
            &GUIDS_VTBL
        }
    }

    /// Counted pointers (plain library objects, presented as connection points: only their
    /// reference counts are used).
    struct Pointers;
    static POINTERS_VTBL: IEnumConnectionPointsVtbl =
        IEnumConnectionPointsVtbl::new::<Delegating, Enumerator<Pointers>>();
    crate::enum_impl!(IEnumConnectionPointsImpl, Pointers);
    impl EnumInterface for Pointers {
        type Item = Listed<IConnectionPoint>;
        type Iface = IEnumConnectionPoints;
        type Vtbl = IEnumConnectionPointsVtbl;
        const IIDS: &'static [GUID] = &[IID_TEST];
        fn vtbl() -> &'static IEnumConnectionPointsVtbl {
            &POINTERS_VTBL
        }
    }

    fn g(n: u128) -> GUID {
        GUID::from_u128(n)
    }

    /// A plain library object (IUnknown only) whose reference count the tests read.
    struct Thing;
    impl ComClass for Thing {
        fn interface(&self, _: &GUID) -> Option<&Slot> {
            None
        }
    }
    fn thing() -> *mut IUnknown {
        ComObject::<Thing>::new(ptr::null_mut(), |_| Thing).into_inner_unknown()
    }
    /// The reference count of `p` now.
    fn refs(p: *mut IUnknown) -> ULONG {
        // SAFETY: `p` is alive; the AddRef is undone at once.
        unsafe {
            add_ref(p);
            release(p)
        }
    }

    #[test]
    fn next_skip_reset_clone_follow_the_enumerator_rules() {
        let p = Enumerator::<Guids>::create(vec![g(1), g(2), g(3)].into(), 0);
        // SAFETY: `p` is a live enumerator; every pointer passed is valid or deliberately NULL.
        unsafe {
            let v = &*(*p).lpVtbl;
            let mut out = [GUID::default(); 4];
            let mut n = 99;
            assert_eq!((v.Next)(p, 0, ptr::null_mut(), &mut n), S_OK);
            assert_eq!(n, 0);
            assert_eq!((v.Next)(p, 2, out.as_mut_ptr(), &mut n), S_OK);
            assert_eq!((n, out[0], out[1]), (2, g(1), g(2)));
            let mut copy = ptr::null_mut();
            assert_eq!((v.Clone)(p, &mut copy), S_OK);
            n = 99;
            assert_eq!((v.Next)(p, 4, out.as_mut_ptr(), &mut n), S_FALSE);
            assert_eq!((n, out[0]), (1, g(3)));
            n = 99;
            assert_eq!((v.Next)(p, 1, out.as_mut_ptr(), &mut n), S_FALSE, "at the end");
            assert_eq!(n, 0);
            assert_eq!((v.Next)(p, 1, out.as_mut_ptr(), ptr::null_mut()), S_FALSE);
            assert_eq!((v.Next)(p, 2, out.as_mut_ptr(), ptr::null_mut()), E_POINTER);
            assert_eq!((v.Next)(p, 1, ptr::null_mut(), &mut n), E_POINTER);
            assert_eq!((v.Reset)(p), S_OK);
            assert_eq!((v.Skip)(p, 0), S_OK);
            assert_eq!((v.Skip)(p, 2), S_OK);
            assert_eq!((v.Skip)(p, 5), S_FALSE);
            assert_eq!((v.Skip)(p, u32::MAX), S_FALSE);
            assert_eq!((v.Next)(p, 1, out.as_mut_ptr(), ptr::null_mut()), S_FALSE);
            // The clone kept its own position (after the first two).
            out = [GUID::default(); 4];
            assert_eq!((v.Next)(copy, 1, out.as_mut_ptr(), ptr::null_mut()), S_OK);
            assert_eq!(out[0], g(3));
            assert_eq!((v.Clone)(p, ptr::null_mut()), E_POINTER);
            // One vtable answers for every IID of the interface, and for IUnknown.
            for iid in [IID_TEST_ALIAS, IID_TEST, IID_IUNKNOWN] {
                let mut other = ptr::null_mut();
                assert_eq!(query_interface(p.cast::<IUnknown>(), &iid, &mut other), S_OK);
                assert!(!other.is_null());
                release(other.cast());
            }
            assert_eq!(release(copy.cast()), 0);
            assert_eq!(release(p.cast()), 0);
        }
    }

    #[test]
    fn huge_counts_write_only_what_exists() {
        let p = Enumerator::<Guids>::create(vec![g(7), g(8)].into(), 0);
        // SAFETY: `p` is a live enumerator; `out` has room for every element the list holds, which is
        // all Next may write whatever `celt` says.
        unsafe {
            let v = &*(*p).lpVtbl;
            let mut out = [GUID::default(); 3];
            let mut n = 0;
            assert_eq!((v.Next)(p, u32::MAX, out.as_mut_ptr(), &mut n), S_FALSE);
            assert_eq!((n, out[0], out[1], out[2]), (2, g(7), g(8), GUID::default()));
            assert_eq!((v.Skip)(p, u32::MAX), S_FALSE);
            assert_eq!((v.Reset)(p), S_OK);
            assert_eq!((v.Skip)(p, u32::MAX), S_FALSE);
            assert_eq!((v.Next)(p, u32::MAX, out.as_mut_ptr(), &mut n), S_FALSE);
            assert_eq!(n, 0);
            release(p.cast());
        }
        // An empty list, and a clone made past the end.
        let e = Enumerator::<Guids>::create(Vec::new().into(), 5);
        // SAFETY: as above.
        unsafe {
            let v = &*(*e).lpVtbl;
            let mut out = GUID::default();
            let mut n = 9;
            assert_eq!((v.Next)(e, 1, &mut out, &mut n), S_FALSE);
            assert_eq!(n, 0);
            let mut copy = ptr::null_mut();
            assert_eq!((v.Clone)(e, &mut copy), S_OK);
            assert_eq!((v.Next)(copy, 1, &mut out, ptr::null_mut()), S_FALSE);
            assert_eq!((v.Reset)(copy), S_OK);
            assert_eq!((v.Skip)(copy, 0), S_OK);
            assert_eq!(release(copy.cast()), 0);
            assert_eq!(release(e.cast()), 0);
        }
    }

    #[test]
    fn counted_elements_are_handed_out_addrefd_and_released_with_the_last_enumerator() {
        let (a, b) = (thing(), thing());
        // SAFETY: the snapshot takes over one reference to each (AddRef'd for it here).
        // Library objects are free-threaded: fit for a snapshot.
        let items: Arc<[Listed<IConnectionPoint>]> = unsafe {
            add_ref(a);
            add_ref(b);
            [a, b].map(|p| Listed::new(Counted::adopt(p.cast()).unwrap())).into()
        };
        assert_eq!((refs(a), refs(b)), (2, 2));
        let p = Enumerator::<Pointers>::create(items, 0);
        // SAFETY: `p` is a live enumerator; the pointers Next hands out are released once each.
        unsafe {
            let v = &*(*p).lpVtbl;
            let mut copy = ptr::null_mut();
            assert_eq!((v.Clone)(p, &mut copy), S_OK);
            assert_eq!((refs(a), refs(b)), (2, 2), "Clone shares the snapshot");
            let mut out = [ptr::null_mut(); 3];
            let mut n = 0;
            assert_eq!((v.Next)(p, 3, out.as_mut_ptr(), &mut n), S_FALSE);
            assert_eq!((n, out[0].cast(), out[1].cast()), (2, a, b));
            assert!(out[2].is_null());
            assert_eq!((refs(a), refs(b)), (3, 3), "every pointer handed out is AddRef'd");
            release(out[0].cast());
            release(out[1].cast());
            assert_eq!((v.Next)(copy, 1, out.as_mut_ptr(), ptr::null_mut()), S_OK);
            assert_eq!(out[0].cast(), a);
            release(out[0].cast());
            assert_eq!(release(p.cast()), 0);
            assert_eq!((refs(a), refs(b)), (2, 2), "the clone still holds the snapshot");
            assert_eq!(release(copy.cast()), 0);
            assert_eq!((refs(a), refs(b)), (1, 1), "the last enumerator released the snapshot");
            assert_eq!(release(a), 0);
            assert_eq!(release(b), 0);
        }
    }
}
