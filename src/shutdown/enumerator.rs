//! IEnumConnectionPoints and IEnumConnections: enumerators over a snapshot taken when they were made.
//!
//! The snapshot holds a counted reference to every element and is shared (`Arc`) between an
//! enumerator and its clones, so Clone costs no AddRefs and the elements are released once, when the
//! last enumerator sharing them dies. Every element Next hands out is AddRef'd for the caller.

use core::ptr::{self, NonNull};
use std::sync::{Arc, Mutex};

use super::interfaces::{
    IConnectionPoint, IEnumConnectionPoints, IEnumConnectionPointsVtbl, IEnumConnections, IEnumConnectionsVtbl,
    CONNECTDATA,
};
use crate::com::boundary::catch;
use crate::com::iids::{IID_IENUMCONNECTIONPOINTS, IID_IENUMCONNECTIONS};
use crate::com::object::{
    delegating_add_ref, delegating_query_interface, delegating_release, ComClass, ComObject, Slot,
};
use crate::com::unknown::{add_ref, release};
use crate::com::{E_POINTER, E_UNEXPECTED, GUID, HRESULT, S_FALSE, S_OK, ULONG};

/// What an enumerator enumerates: a fixed list of counted elements.
pub(crate) trait Snapshot: Send + Sync + Sized + 'static {
    /// The element type of Next's array.
    type Elem;
    /// The enumerator interface.
    type Iface;
    /// Its vtable type.
    type Vtbl: 'static;
    /// Its IID.
    const IID: GUID;
    /// The vtable enumerators of this snapshot present.
    fn vtbl() -> &'static Self::Vtbl;
    fn len(&self) -> usize;
    /// Writes element `i` to `out`, AddRef'd for the caller.
    ///
    /// # Safety
    /// `i < self.len()`; `out` writable.
    unsafe fn hand_out(&self, i: usize, out: *mut Self::Elem);
}

/// An enumerator object over a shared snapshot.
pub(crate) struct Enumerator<S: Snapshot> {
    slot: Slot,
    items: Arc<S>,
    position: Mutex<usize>,
}

impl<S: Snapshot> ComClass for Enumerator<S> {
    fn interface(&self, iid: &GUID) -> Option<&Slot> {
        (*iid == S::IID).then_some(&self.slot)
    }
}

impl<S: Snapshot> Enumerator<S> {
    /// A new enumerator at `position`, returned as a counted interface pointer.
    pub(crate) fn create(items: Arc<S>, position: usize) -> *mut S::Iface {
        let obj = ComObject::<Enumerator<S>>::new(ptr::null_mut(), |binder| Enumerator {
            slot: binder.slot(S::vtbl()),
            items,
            position: Mutex::new(position),
        });
        // Not aggregated: the slot's reference count is the object's own, so the construction
        // reference becomes the reference of the returned interface pointer.
        let p = obj.slot.as_ptr().cast::<S::Iface>();
        core::mem::forget(obj);
        p
    }

    fn position(&self) -> std::sync::MutexGuard<'_, usize> {
        self.position.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

/// # Safety
/// `this` is an interface pointer of a live `Enumerator<S>`.
unsafe fn object<'a, S: Snapshot>(this: *mut S::Iface) -> &'a Enumerator<S> {
    // SAFETY: only `Enumerator<S>` slots present this vtable.
    unsafe { ComObject::<Enumerator<S>>::from_interface(this) }
}

/// IEnumXXX::Next: up to `celt` elements; S_OK when all `celt` were fetched, else S_FALSE.
/// `pcFetched` may be NULL only when `celt` is 1.
unsafe extern "system" fn next<S: Snapshot>(
    this: *mut S::Iface,
    celt: ULONG,
    rgelt: *mut S::Elem,
    pcFetched: *mut ULONG,
) -> HRESULT {
    if !pcFetched.is_null() {
        // SAFETY: non-NULL out-parameter.
        unsafe { *pcFetched = 0 };
    }
    if celt == 0 {
        return S_OK;
    }
    if rgelt.is_null() || (pcFetched.is_null() && celt != 1) {
        return E_POINTER;
    }
    catch(E_UNEXPECTED, || {
        // SAFETY: COM calls this only through our vtable.
        let e = unsafe { object::<S>(this) };
        let mut position = e.position();
        let start = (*position).min(e.items.len());
        let count = (e.items.len() - start).min(celt as usize);
        for i in 0..count {
            // SAFETY: `start + i < len`; the caller provides room for `celt >= count` elements.
            unsafe { e.items.hand_out(start + i, rgelt.add(i)) };
        }
        *position = start + count;
        if !pcFetched.is_null() {
            // SAFETY: non-NULL out-parameter.
            unsafe { *pcFetched = count as ULONG };
        }
        if count == celt as usize {
            S_OK
        } else {
            S_FALSE
        }
    })
}

/// IEnumXXX::Skip: S_OK when `celt` elements were skipped, S_FALSE when the end came first.
unsafe extern "system" fn skip<S: Snapshot>(this: *mut S::Iface, celt: ULONG) -> HRESULT {
    catch(E_UNEXPECTED, || {
        // SAFETY: COM calls this only through our vtable.
        let e = unsafe { object::<S>(this) };
        let mut position = e.position();
        let left = e.items.len() - (*position).min(e.items.len());
        if celt as usize > left {
            *position = e.items.len();
            S_FALSE
        } else {
            *position += celt as usize;
            S_OK
        }
    })
}

unsafe extern "system" fn reset<S: Snapshot>(this: *mut S::Iface) -> HRESULT {
    catch(E_UNEXPECTED, || {
        // SAFETY: COM calls this only through our vtable.
        *unsafe { object::<S>(this) }.position() = 0;
        S_OK
    })
}

/// IEnumXXX::Clone: a new enumerator over the same snapshot, at the same position.
unsafe extern "system" fn clone<S: Snapshot>(this: *mut S::Iface, ppEnum: *mut *mut S::Iface) -> HRESULT {
    if ppEnum.is_null() {
        return E_POINTER;
    }
    // SAFETY: non-NULL out-parameter.
    unsafe { *ppEnum = ptr::null_mut() };
    catch(E_UNEXPECTED, || {
        // SAFETY: COM calls this only through our vtable.
        let e = unsafe { object::<S>(this) };
        let position = *e.position();
        // SAFETY: non-NULL out-parameter.
        unsafe { *ppEnum = Enumerator::<S>::create(e.items.clone(), position) };
        S_OK
    })
}

/// The connection points of a container (counted IConnectionPoint pointers).
pub(crate) struct PointSnapshot(Vec<NonNull<IConnectionPoint>>);

// SAFETY: the connection points of this library are free-threaded objects.
unsafe impl Send for PointSnapshot {}
// SAFETY: as above; the list is never modified after construction.
unsafe impl Sync for PointSnapshot {}

impl PointSnapshot {
    /// Takes over one counted reference per point.
    pub(crate) fn adopt(points: Vec<NonNull<IConnectionPoint>>) -> PointSnapshot {
        PointSnapshot(points)
    }
}

impl Drop for PointSnapshot {
    fn drop(&mut self) {
        for p in &self.0 {
            // SAFETY: each point's reference was adopted by this snapshot.
            unsafe { release(p.as_ptr().cast()) };
        }
    }
}

static ENUM_POINTS_VTBL: IEnumConnectionPointsVtbl = IEnumConnectionPointsVtbl {
    QueryInterface: delegating_query_interface::<IEnumConnectionPoints>,
    AddRef: delegating_add_ref::<IEnumConnectionPoints>,
    Release: delegating_release::<IEnumConnectionPoints>,
    Next: next::<PointSnapshot>,
    Skip: skip::<PointSnapshot>,
    Reset: reset::<PointSnapshot>,
    Clone: clone::<PointSnapshot>,
};

impl Snapshot for PointSnapshot {
    type Elem = *mut IConnectionPoint;
    type Iface = IEnumConnectionPoints;
    type Vtbl = IEnumConnectionPointsVtbl;
    const IID: GUID = IID_IENUMCONNECTIONPOINTS;
    fn vtbl() -> &'static IEnumConnectionPointsVtbl {
        &ENUM_POINTS_VTBL
    }
    fn len(&self) -> usize {
        self.0.len()
    }
    unsafe fn hand_out(&self, i: usize, out: *mut *mut IConnectionPoint) {
        let p = self.0[i].as_ptr();
        // SAFETY: `p` is alive (counted by the snapshot); `out` is writable per the caller.
        unsafe {
            add_ref(p.cast());
            *out = p;
        }
    }
}

/// The connections of a connection point (CONNECTDATA with counted `pUnk`).
pub(crate) struct ConnectionSnapshot(Vec<CONNECTDATA>);

// SAFETY: the sinks were fetched for the apartment that created the enumerator, which COM rules
// confine the enumerator to; the list is never modified after construction.
unsafe impl Send for ConnectionSnapshot {}
// SAFETY: as above.
unsafe impl Sync for ConnectionSnapshot {}

impl ConnectionSnapshot {
    /// Takes over one counted `pUnk` reference per connection.
    pub(crate) fn adopt(connections: Vec<CONNECTDATA>) -> ConnectionSnapshot {
        ConnectionSnapshot(connections)
    }
}

impl Drop for ConnectionSnapshot {
    fn drop(&mut self) {
        for c in &self.0 {
            // SAFETY: each reference was adopted by this snapshot.
            unsafe { release(c.pUnk) };
        }
    }
}

static ENUM_CONNECTIONS_VTBL: IEnumConnectionsVtbl = IEnumConnectionsVtbl {
    QueryInterface: delegating_query_interface::<IEnumConnections>,
    AddRef: delegating_add_ref::<IEnumConnections>,
    Release: delegating_release::<IEnumConnections>,
    Next: next::<ConnectionSnapshot>,
    Skip: skip::<ConnectionSnapshot>,
    Reset: reset::<ConnectionSnapshot>,
    Clone: clone::<ConnectionSnapshot>,
};

impl Snapshot for ConnectionSnapshot {
    type Elem = CONNECTDATA;
    type Iface = IEnumConnections;
    type Vtbl = IEnumConnectionsVtbl;
    const IID: GUID = IID_IENUMCONNECTIONS;
    fn vtbl() -> &'static IEnumConnectionsVtbl {
        &ENUM_CONNECTIONS_VTBL
    }
    fn len(&self) -> usize {
        self.0.len()
    }
    unsafe fn hand_out(&self, i: usize, out: *mut CONNECTDATA) {
        let c = self.0[i];
        // SAFETY: `c.pUnk` is alive (counted by the snapshot); `out` is writable per the caller.
        unsafe {
            add_ref(c.pUnk);
            *out = c;
        }
    }
}
