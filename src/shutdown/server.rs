//! The server side: an aggregatable object with IConnectionPointContainer and one connection point
//! for IOPCShutdown (specification section 4.1).
//!
//! Ownership, and why there is no reference cycle: the connection point is part of the container
//! object (a second interface slot with its own COM identity). Its AddRef/Release count on the
//! container's controlling unknown, so a client holding only the connection point keeps the server
//! alive, exactly as holding any other interface of it would, and the container needs no counted
//! reference to its point. Enumerators of connection points hold counted references (and so keep
//! the server alive while they exist); nothing the server holds refers back to them. Sinks are held
//! by the connections; a sink that holds the server is the client's business (it must Unadvise).

use core::ffi::c_void;
use std::sync::{Arc, Mutex, MutexGuard};

use super::apartment::SinkRef;
use super::interfaces::{
    IConnectionPoint, IConnectionPointContainer, IConnectionPointContainerVtbl, IConnectionPointVtbl,
    IEnumConnectionPoints, IEnumConnectionPointsVtbl, IEnumConnections, IEnumConnectionsVtbl, IOPCShutdown,
    CONNECTDATA,
};
use crate::com::enumerator::{Counted, Element, EnumInterface, Enumerator};
use crate::com::ffi::{self, FfiResult};
use crate::com::iids::{
    IID_IOPCShutdown, IID_ICONNECTIONPOINT, IID_ICONNECTIONPOINTCONTAINER, IID_IENUMCONNECTIONPOINTS,
    IID_IENUMCONNECTIONS, IID_IUNKNOWN,
};
use crate::com::interfaces::{
    IConnectionPointContainerImpl, IConnectionPointImpl, IEnumConnectionPointsImpl, IEnumConnectionsImpl, IUnknownImpl,
};
use crate::com::object::{ComClass, ComObject, Delegating, Slot};
use crate::com::options::{read_sized, SizedStruct};
use crate::com::unknown::{add_ref, query};
use crate::com::{
    IUnknown, CONNECT_E_ADVISELIMIT, CONNECT_E_CANNOTCONNECT, CONNECT_E_NOCONNECTION, DWORD, E_INVALIDARG,
    E_NOINTERFACE, E_UNEXPECTED, GUID, HRESULT, IID, LPCWSTR, REFIID, S_OK,
};

/// How a server configures its shutdown connection point. Zero-initialise it, set `struct_size` to
/// `sizeof(OpcShutdownOptions)`, then set what you need; the library reads only the first
/// `struct_size` bytes, so code built against an older header keeps working.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct OpcShutdownOptions {
    /// `sizeof(OpcShutdownOptions)` as the caller's header declares it.
    pub struct_size: u32,
    /// The most sinks that may be advised at the same time; 0 means the default, 1 (the
    /// specification requires no more). Advise beyond it fails with CONNECT_E_ADVISELIMIT.
    pub advise_limit: u32,
}

// SAFETY: repr(C), struct_size first, integers only.
unsafe impl SizedStruct for OpcShutdownOptions {
    /// `struct_size` alone, and with `advise_limit`.
    const SIZES: &'static [usize] = &[
        core::mem::offset_of!(OpcShutdownOptions, advise_limit),
        core::mem::size_of::<OpcShutdownOptions>(),
    ];
}

/// The advise limit when the server sets none.
pub(crate) const DEFAULT_ADVISE_LIMIT: u32 = 1;

/// One advised sink.
struct Connection {
    cookie: DWORD,
    sink: Arc<SinkRef>,
}

/// The connections of the point and the cookie the next Advise gets.
struct Connections {
    /// Starts at 1 and only grows, so a cookie is never 0 and never reused; 0 once all 2^32 - 1
    /// cookies have been handed out (Advise then fails with CONNECT_E_ADVISELIMIT).
    next_cookie: DWORD,
    list: Vec<Connection>,
}

/// The shutdown object: IConnectionPointContainer plus the IOPCShutdown connection point.
pub struct OpcShutdown {
    container: Slot,
    point: Slot,
    advise_limit: u32,
    connections: Mutex<Connections>,
}

impl ComClass for OpcShutdown {
    fn interface(&self, iid: &GUID) -> Option<&Slot> {
        // The connection point is not reachable by QueryInterface on the container: it is a
        // different COM object (it answers QueryInterface itself, see `point_query_interface`).
        (*iid == IID_ICONNECTIONPOINTCONTAINER).then_some(&self.container)
    }
}

/// What one notification achieved.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Notified {
    /// Sinks whose ShutdownRequest succeeded.
    pub(crate) notified: u32,
    /// Sinks that could not be reached or whose ShutdownRequest failed.
    pub(crate) failed: u32,
}

impl OpcShutdown {
    pub(crate) fn build(binder: &crate::com::object::Binder, advise_limit: u32) -> OpcShutdown {
        OpcShutdown {
            container: binder.slot(&CONTAINER_VTBL),
            point: binder.slot(&POINT_VTBL),
            advise_limit: if advise_limit == 0 {
                DEFAULT_ADVISE_LIMIT
            } else {
                advise_limit
            },
            connections: Mutex::new(Connections {
                next_cookie: 1,
                list: Vec::new(),
            }),
        }
    }

    fn connections(&self) -> MutexGuard<'_, Connections> {
        // Every update of Connections is a single push/remove: a panic cannot leave it half-written.
        self.connections.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The container interface (not AddRef'd).
    pub(crate) fn container_ptr(&self) -> *mut IConnectionPointContainer {
        self.container.as_ptr().cast()
    }

    /// The connection point interface (not AddRef'd).
    pub(crate) fn point_ptr(&self) -> *mut IConnectionPoint {
        self.point.as_ptr().cast()
    }

    /// Number of sinks advised now.
    #[cfg(test)]
    pub(crate) fn connection_count(&self) -> usize {
        self.connections().list.len()
    }

    /// For each connection, whether its sink went through the Global Interface Table.
    #[cfg(all(test, windows))]
    pub(crate) fn held_globally(&self) -> Vec<bool> {
        self.connections().list.iter().map(|c| c.sink.is_global()).collect()
    }

    /// IConnectionPoint::Advise after the argument checks.
    ///
    /// # Safety
    /// `sink` must be a valid COM interface pointer.
    unsafe fn advise(&self, sink: *mut IUnknown) -> Result<DWORD, HRESULT> {
        // SAFETY: `sink` is valid per the caller.
        let shutdown = unsafe { query::<IOPCShutdown>(sink, &IID_IOPCShutdown) }
            .map_err(|_| CONNECT_E_CANNOTCONNECT)?
            .into_raw();
        // Registering in the GIT may call into the sink, so it happens before the lock is taken.
        // SAFETY: a counted IOPCShutdown pointer of the calling apartment.
        let sink = Arc::new(unsafe { SinkRef::adopt(shutdown) });
        let mut connections = self.connections();
        if connections.list.len() >= self.advise_limit as usize || connections.next_cookie == 0 {
            drop(connections);
            // Released outside the lock: the sink's Release may call back into this object.
            drop(sink);
            return Err(CONNECT_E_ADVISELIMIT);
        }
        let cookie = connections.next_cookie;
        connections.next_cookie = cookie.wrapping_add(1);
        connections.list.push(Connection { cookie, sink });
        Ok(cookie)
    }

    /// IConnectionPoint::Unadvise.
    fn unadvise(&self, cookie: DWORD) -> HRESULT {
        let removed = {
            let mut connections = self.connections();
            match connections.list.iter().position(|c| c.cookie == cookie) {
                Some(i) => connections.list.remove(i),
                None => return CONNECT_E_NOCONNECTION,
            }
        };
        // Released outside the lock: the sink's Release may call back into this object.
        drop(removed);
        S_OK
    }

    /// The advised sinks, as counted references taken under the lock.
    pub(super) fn snapshot(&self) -> Vec<(DWORD, Arc<SinkRef>)> {
        self.connections()
            .list
            .iter()
            .map(|c| (c.cookie, c.sink.clone()))
            .collect()
    }

    pub(super) fn is_connected(&self, cookie: DWORD) -> bool {
        self.connections().list.iter().any(|c| c.cookie == cookie)
    }

    /// Calls ShutdownRequest on every advised sink, never holding the lock during a call. Just before
    /// each call the sink is checked to be still advised, so a sink unadvised from inside the
    /// notification (by itself or by an earlier sink) is not called any more. An Unadvise racing on
    /// another thread may still see one call that was already under way.
    ///
    /// # Safety
    /// `reason` must point at a NUL-terminated UTF-16 string.
    pub(crate) unsafe fn notify(&self, reason: LPCWSTR) -> Notified {
        let mut result = Notified::default();
        for (cookie, sink) in self.snapshot() {
            if !self.is_connected(cookie) {
                continue;
            }
            let ok = match sink.get() {
                Ok(call) => {
                    let p = call.as_ptr();
                    // SAFETY: `p` is a counted IOPCShutdown pointer valid on this thread; no lock is held.
                    let hr = unsafe { ((*(*p).lpVtbl).ShutdownRequest)(p, reason) }.get();
                    hr >= 0
                }
                Err(_) => false,
            };
            if ok {
                result.notified += 1;
            } else {
                result.failed += 1;
            }
            // `sink` (and `call`) drop here, outside any lock.
        }
        result
    }

    /// IConnectionPoint::EnumConnections: the connections now, with sinks valid on this thread. Fails
    /// with the sink's error when one cannot be had on this thread (on Windows: an apartment-bound
    /// sink held directly, asked for from another thread, gives RPC_E_WRONG_THREAD).
    fn enum_connections(&self) -> Result<*mut IEnumConnections, HRESULT> {
        let mut data = Vec::new();
        for (cookie, sink) in self.snapshot() {
            // On failure `data` drops, releasing the sinks fetched so far.
            let call = sink.get()?;
            // SAFETY: `into_raw` gives up a counted, non-NULL pointer that the element now owns.
            let sink = unsafe { Counted::adopt(call.into_raw().cast::<IUnknown>()) }.ok_or(E_UNEXPECTED)?;
            data.push(EnumeratedConnection { sink, cookie });
        }
        Ok(Enumerator::<ConnectionsEnum>::create(data.into(), 0))
    }
}

/// One connection of an IEnumConnections snapshot: the sink (one counted reference) and its cookie.
pub(crate) struct EnumeratedConnection {
    sink: Counted<IUnknown>,
    cookie: DWORD,
}

impl Element for EnumeratedConnection {
    type Out = CONNECTDATA;
    fn hand_out(&self) -> CONNECTDATA {
        CONNECTDATA {
            pUnk: self.sink.hand_out(),
            dwCookie: self.cookie,
        }
    }
}

/// IEnumConnections over the connections of the point, as the core's snapshot enumerator.
struct ConnectionsEnum;

static ENUM_CONNECTIONS_VTBL: IEnumConnectionsVtbl =
    IEnumConnectionsVtbl::new::<Delegating, Enumerator<ConnectionsEnum>>();
crate::enum_impl!(IEnumConnectionsImpl, ConnectionsEnum);

impl EnumInterface for ConnectionsEnum {
    type Item = EnumeratedConnection;
    type Iface = IEnumConnections;
    type Vtbl = IEnumConnectionsVtbl;
    const IIDS: &'static [GUID] = &[IID_IENUMCONNECTIONS];
    fn vtbl() -> &'static IEnumConnectionsVtbl {
        &ENUM_CONNECTIONS_VTBL
    }
}

/// IEnumConnectionPoints over the container's one connection point (counted: it keeps the server alive).
struct ConnectionPointsEnum;

static ENUM_POINTS_VTBL: IEnumConnectionPointsVtbl =
    IEnumConnectionPointsVtbl::new::<Delegating, Enumerator<ConnectionPointsEnum>>();
crate::enum_impl!(IEnumConnectionPointsImpl, ConnectionPointsEnum);

impl EnumInterface for ConnectionPointsEnum {
    type Item = Counted<IConnectionPoint>;
    type Iface = IEnumConnectionPoints;
    type Vtbl = IEnumConnectionPointsVtbl;
    const IIDS: &'static [GUID] = &[IID_IENUMCONNECTIONPOINTS];
    fn vtbl() -> &'static IEnumConnectionPointsVtbl {
        &ENUM_POINTS_VTBL
    }
}

static CONTAINER_VTBL: IConnectionPointContainerVtbl = IConnectionPointContainerVtbl::new::<Delegating, OpcShutdown>();

static POINT_VTBL: IConnectionPointVtbl = IConnectionPointVtbl::new::<PointUnknown, OpcShutdown>();

/// The object behind any of its interfaces, if it is one of ours.
///
/// # Safety
/// `this` must be NULL or a valid COM interface pointer.
pub(crate) unsafe fn from_container<'a>(this: *mut IConnectionPointContainer) -> Option<&'a ComObject<OpcShutdown>> {
    // SAFETY: forwarded from the caller.
    unsafe { ComObject::<OpcShutdown>::from_foreign(this, &CONTAINER_VTBL) }
}

impl IConnectionPointContainerImpl for OpcShutdown {
    unsafe fn EnumConnectionPoints(this: &ComObject<Self>, ppEnum: *mut *mut IEnumConnectionPoints) -> FfiResult {
        // SAFETY: the caller vouches a non-NULL `ppEnum` is writable.
        let out = unsafe { ffi::out(ppEnum) }?;
        let point = this.point_ptr();
        // The snapshot's reference to the point counts on the server, which it keeps alive.
        // SAFETY: `point` is a slot of the live object; the element takes over the reference added.
        let item = unsafe {
            add_ref(point.cast());
            Counted::adopt(point)
        }
        .expect("slot pointers are never NULL");
        out.write(Enumerator::<ConnectionPointsEnum>::create(vec![item].into(), 0));
        Ok(S_OK)
    }

    unsafe fn FindConnectionPoint(this: &ComObject<Self>, riid: REFIID, ppCP: *mut *mut IConnectionPoint) -> FfiResult {
        // SAFETY: the caller's contract: `ppCP` NULL or writable, `riid` NULL or readable.
        let (out, riid) = unsafe { (ffi::out(ppCP)?, ffi::in_ref(riid)?) };
        if *riid != IID_IOPCShutdown {
            return Err(CONNECT_E_NOCONNECTION.into());
        }
        let point = this.point_ptr();
        // SAFETY: a slot of the live object; the AddRef counts on the controlling unknown.
        unsafe { add_ref(point.cast()) };
        out.write(point);
        Ok(S_OK)
    }
}

/// The IUnknown of the connection point: its own identity, answering IUnknown and IConnectionPoint
/// only (a connection point is not its container); AddRef and Release count on the controlling
/// unknown, as for every other slot.
struct PointUnknown;

impl IUnknownImpl for PointUnknown {
    unsafe fn QueryInterface(this: *mut IUnknown, riid: REFIID, ppv: *mut *mut c_void) -> FfiResult {
        // SAFETY: the caller's contract: `ppv` NULL or writable, `riid` NULL or readable.
        let (out, iid) = unsafe { (ffi::out(ppv)?, ffi::in_ref(riid)?) };
        if *iid != IID_IUNKNOWN && *iid != IID_ICONNECTIONPOINT {
            return Err(E_NOINTERFACE.into());
        }
        // SAFETY: `this` is the point slot of a live object.
        unsafe { add_ref(this) };
        out.write(this.cast());
        Ok(S_OK)
    }

    unsafe fn AddRef(this: *mut IUnknown) -> u32 {
        // SAFETY: forwarded: `this` is a slot of a live object.
        unsafe { Delegating::AddRef(this) }
    }

    unsafe fn Release(this: *mut IUnknown) -> u32 {
        // SAFETY: forwarded; the caller gives up its reference.
        unsafe { Delegating::Release(this) }
    }
}

impl IConnectionPointImpl for OpcShutdown {
    unsafe fn GetConnectionInterface(_this: &ComObject<Self>, pIID: *mut IID) -> FfiResult {
        // SAFETY: the caller vouches a non-NULL `pIID` is writable.
        unsafe { ffi::out(pIID) }?.write(IID_IOPCShutdown);
        Ok(S_OK)
    }

    unsafe fn GetConnectionPointContainer(
        this: &ComObject<Self>,
        ppCPC: *mut *mut IConnectionPointContainer,
    ) -> FfiResult {
        // SAFETY: the caller vouches a non-NULL `ppCPC` is writable.
        let out = unsafe { ffi::out(ppCPC) }?;
        let header = this.header();
        if header.is_aggregated() {
            // The container is whatever the server object (the controlling unknown) answers for
            // IConnectionPointContainer: usually this object's container slot, forwarded.
            // SAFETY: the outer unknown is valid while this object lives.
            let found = unsafe {
                query::<IConnectionPointContainer>(header.controlling_unknown(), &IID_ICONNECTIONPOINTCONTAINER)
            };
            if let Ok(found) = found {
                // The reference QueryInterface gave us goes to the caller.
                out.write(found.into_raw().as_ptr());
                return Ok(S_OK);
            }
        }
        // Our own container slot; its AddRef counts on the controlling unknown.
        let container = this.container_ptr();
        // SAFETY: a slot of the live object.
        unsafe { add_ref(container.cast()) };
        out.write(container);
        Ok(S_OK)
    }

    unsafe fn Advise(this: &ComObject<Self>, pUnkSink: *mut IUnknown, pdwCookie: *mut DWORD) -> FfiResult {
        // SAFETY: the caller vouches a non-NULL `pdwCookie` is writable.
        let (out, sink) = (unsafe { ffi::out(pdwCookie) }?, ffi::in_ptr(pUnkSink)?);
        // SAFETY: the sink is a valid COM pointer.
        out.write(unsafe { this.advise(sink.as_ptr()) }?);
        Ok(S_OK)
    }

    fn Unadvise(this: &ComObject<Self>, dwCookie: DWORD) -> FfiResult {
        Ok(this.unadvise(dwCookie))
    }

    unsafe fn EnumConnections(this: &ComObject<Self>, ppEnum: *mut *mut IEnumConnections) -> FfiResult {
        // SAFETY: the caller vouches a non-NULL `ppEnum` is writable.
        let out = unsafe { ffi::out(ppEnum) }?;
        out.write(this.enum_connections()?);
        Ok(S_OK)
    }
}

/// Reads the caller's options, honouring `struct_size`; returns the advise limit.
///
/// # Safety
/// `options` must be NULL or point at `struct_size` readable bytes laid out as OpcShutdownOptions.
pub(crate) unsafe fn read_options(options: *const OpcShutdownOptions) -> Result<u32, HRESULT> {
    let defaults = OpcShutdownOptions {
        struct_size: 0,
        advise_limit: 0,
    };
    // SAFETY: OpcShutdownOptions is repr(C), starts with struct_size and holds only integers; the
    // caller vouches for `options`.
    Ok(unsafe { read_sized(options, defaults) }?.advise_limit)
}

/// Finds the shutdown object behind any interface of it (or of a server aggregating it) and runs
/// `f` on it while holding a reference, so a sink releasing the server cannot pull it away.
///
/// # Safety
/// `shutdown` must be NULL or a valid COM interface pointer.
pub(crate) unsafe fn with_object<R>(
    shutdown: *mut IUnknown,
    f: impl FnOnce(&ComObject<OpcShutdown>) -> R,
) -> Result<R, HRESULT> {
    if shutdown.is_null() {
        return Err(E_INVALIDARG);
    }
    // SAFETY: valid per the caller.
    let container = unsafe { query::<IConnectionPointContainer>(shutdown, &IID_ICONNECTIONPOINTCONTAINER) }
        .map_err(|_| E_INVALIDARG)?;
    // SAFETY: a valid IConnectionPointContainer pointer, ours or not, counted while `f` runs.
    let result = match unsafe { from_container(container.as_ptr()) } {
        Some(obj) => Ok(f(obj)),
        None => Err(E_INVALIDARG),
    };
    drop(container);
    result
}
