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
//!
//! A server object that forwards to this object instead of aggregating it names itself as the
//! container (`OpcShutdownOptions::container`): the point's AddRef/Release then count on that server
//! object, which holds this object, so holding the point keeps both alive; this object holds no
//! reference to the server (the pointer is not counted), so again there is no cycle.

use core::ffi::c_void;
use core::ptr::NonNull;
use core::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use super::apartment::SinkRef;
use super::interfaces::{
    IConnectionPoint, IConnectionPointContainer, IConnectionPointContainerVtbl, IConnectionPointVtbl,
    IEnumConnectionPoints, IEnumConnectionPointsVtbl, IEnumConnections, IEnumConnectionsVtbl, IOPCShutdown,
    CONNECTDATA,
};
use crate::com::enumerator::{Element, EnumInterface, Enumerator, Listed};
use crate::com::ffi::{self, FfiResult};
use crate::com::iids::{
    IID_IOPCShutdown, IID_ICONNECTIONPOINT, IID_ICONNECTIONPOINTCONTAINER, IID_IENUMCONNECTIONPOINTS,
    IID_IENUMCONNECTIONS, IID_IUNKNOWN,
};
use crate::com::interfaces::{
    IConnectionPointContainerImpl, IConnectionPointImpl, IEnumConnectionPointsImpl, IEnumConnectionsImpl, IUnknownImpl,
};
use crate::com::object::{ComClass, ComObject, Delegating, Slot, ThisSlot};
use crate::com::options::{read_sized, SizedStruct};
use crate::com::unknown::{add_ref, query, release, Counted};
use crate::com::{
    IUnknown, CONNECT_E_ADVISELIMIT, CONNECT_E_CANNOTCONNECT, CONNECT_E_NOCONNECTION, DWORD, E_INVALIDARG,
    E_NOINTERFACE, GUID, HRESULT, IID, LPCWSTR, S_OK,
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
    /// For a server object that forwards to the shutdown object instead of aggregating it (it
    /// implements IConnectionPointContainer itself and passes FindConnectionPoint and
    /// EnumConnectionPoints on): the server object (any of its interfaces), so that the connection
    /// point names it as its container. NULL: the container is the shutdown object itself, or the
    /// outer object when it is aggregated (then this must be NULL).
    ///
    /// The connection point then counts its references on this object, as an interface of an
    /// aggregated object counts on its outer object: whoever holds the connection point (or an
    /// enumerator of it) keeps the server object alive, and through it the shutdown object;
    /// IConnectionPoint::GetConnectionPointContainer returns the server object's
    /// IConnectionPointContainer (QueryInterface on it), so the container has the server's COM
    /// identity. The shutdown object holds no reference to the server object (no cycle). So the
    /// server object keeps its own reference to the shutdown object (which may be any of its
    /// interfaces) until it is destroyed, and hands none of the shutdown object's own interfaces to
    /// its clients: they count only on the shutdown object, which could outlive the server.
    pub container: *mut IUnknown,
}

/// What a server set in its `OpcShutdownOptions`.
pub(crate) struct ShutdownSettings {
    pub(crate) advise_limit: u32,
    pub(crate) container: *mut IUnknown,
}

// SAFETY: repr(C), struct_size first, integers and a raw pointer.
unsafe impl SizedStruct for OpcShutdownOptions {
    /// `struct_size` alone, with `advise_limit`, and with `container`.
    const SIZES: &'static [usize] = &[
        core::mem::offset_of!(OpcShutdownOptions, advise_limit),
        core::mem::offset_of!(OpcShutdownOptions, container),
        core::mem::size_of::<OpcShutdownOptions>(),
    ];
}

/// The advise limit when the server sets none.
pub(crate) const DEFAULT_ADVISE_LIMIT: u32 = 1;

/// One advised sink, as the connection and the notifications under way share it.
pub(crate) struct Advised {
    sink: SinkRef,
    /// Cleared when the connection ends (Unadvise, or the object's end): a call that has not
    /// started by then is not made.
    connected: AtomicBool,
    /// Set while a bounded notification's call to the sink is waiting for a thread or under way, so
    /// that no other bounded notification calls it again meanwhile (see `bounded`).
    calling: AtomicBool,
}

impl Advised {
    /// The sink, to be fetched for the calling thread.
    pub(crate) fn sink(&self) -> &SinkRef {
        &self.sink
    }

    /// Whether the sink is still advised.
    pub(crate) fn is_connected(&self) -> bool {
        self.connected.load(Ordering::Acquire)
    }

    /// Claims the sink for one call; false when a call to it is already waiting or under way.
    pub(crate) fn claim_call(&self) -> bool {
        self.calling
            .compare_exchange(false, true, Ordering::AcqRel, Ordering::Acquire)
            .is_ok()
    }

    /// Gives back the claim of `claim_call` once the call has returned (or was not made).
    pub(crate) fn end_call(&self) {
        self.calling.store(false, Ordering::Release);
    }

    /// Whether a call claimed by `claim_call` has not ended yet.
    #[cfg(test)]
    pub(crate) fn is_calling(&self) -> bool {
        self.calling.load(Ordering::Acquire)
    }
}

/// One advised sink.
struct Connection {
    cookie: DWORD,
    sink: Arc<Advised>,
}

impl Drop for Connection {
    fn drop(&mut self) {
        // A notification may still hold the sink: from now on it does not start a call to it.
        self.sink.connected.store(false, Ordering::Release);
    }
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
    /// The server object a forwarding server named as the point's container (not counted: see
    /// `OpcShutdownOptions::container`).
    named_container: Option<NamedContainer>,
    advise_limit: u32,
    connections: Mutex<Connections>,
}

/// The server object named as the container, which the connection point's references count on.
struct NamedContainer(NonNull<IUnknown>);

// SAFETY: the server object is a COM object of the server's, which the connection point only AddRefs,
// Releases and asks for IConnectionPointContainer, as any client thread may (a server object shared
// with the library's free-threaded objects is called from any thread).
unsafe impl Send for NamedContainer {}
// SAFETY: as above; the pointer is never changed.
unsafe impl Sync for NamedContainer {}

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
    pub(crate) fn build(binder: &crate::com::object::Binder, settings: ShutdownSettings) -> OpcShutdown {
        OpcShutdown {
            container: binder.slot(&CONTAINER_VTBL),
            point: binder.slot(&POINT_VTBL),
            named_container: NonNull::new(settings.container).map(NamedContainer),
            advise_limit: if settings.advise_limit == 0 {
                DEFAULT_ADVISE_LIMIT
            } else {
                settings.advise_limit
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

    /// Number of sinks advised now.
    #[cfg(test)]
    pub(crate) fn connection_count(&self) -> usize {
        self.connections().list.len()
    }

    /// For each connection, whether its sink went through the Global Interface Table.
    #[cfg(all(test, windows))]
    pub(crate) fn held_globally(&self) -> Vec<bool> {
        self.connections()
            .list
            .iter()
            .map(|c| c.sink.sink.is_global())
            .collect()
    }

    /// IConnectionPoint::Advise after the argument checks.
    fn advise(&self, sink: ffi::Iface<'_, IUnknown>) -> Result<DWORD, HRESULT> {
        let shutdown = sink
            .query::<IOPCShutdown>(&IID_IOPCShutdown)
            .map_err(|_| CONNECT_E_CANNOTCONNECT)?;
        // Registering in the GIT may call into the sink, so it happens before the lock is taken.
        // SAFETY: a counted IOPCShutdown pointer of the calling apartment.
        let held = unsafe { SinkRef::adopt(shutdown) };
        let sink = Arc::new(Advised {
            sink: held,
            connected: AtomicBool::new(true),
            calling: AtomicBool::new(false),
        });
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
    pub(super) fn snapshot(&self) -> Vec<(DWORD, Arc<Advised>)> {
        self.connections()
            .list
            .iter()
            .map(|c| (c.cookie, c.sink.clone()))
            .collect()
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
        for (_, advised) in self.snapshot() {
            if !advised.is_connected() {
                continue;
            }
            let ok = match advised.sink().get() {
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
            // `advised` (and `call`) drop here, outside any lock.
        }
        result
    }

    /// IConnectionPoint::EnumConnections: the connections now, with sinks valid on this thread. Fails
    /// with the sink's error when one cannot be had on this thread (on Windows: an apartment-bound
    /// sink held directly, asked for from another thread, gives RPC_E_WRONG_THREAD).
    fn enum_connections(&self) -> Result<*mut IEnumConnections, HRESULT> {
        let mut data = Vec::new();
        for (cookie, advised) in self.snapshot() {
            // On failure `data` drops, releasing the sinks fetched so far.
            let call = advised.sink().get()?;
            // SAFETY: fetched for this thread's apartment, to which COM confines the enumerator.
            let sink = unsafe { Listed::new(call.into_unknown()) };
            data.push(EnumeratedConnection { sink, cookie });
        }
        Ok(Enumerator::<ConnectionsEnum>::create(data.into(), 0))
    }
}

/// One connection of an IEnumConnections snapshot: the sink (one counted reference) and its cookie.
pub(crate) struct EnumeratedConnection {
    sink: Listed<IUnknown>,
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
    type Item = Listed<IConnectionPoint>;
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
    fn EnumConnectionPoints(this: &ComObject<Self>, ppEnum: ffi::Out<'_, *mut IEnumConnectionPoints>) -> FfiResult {
        // The snapshot's reference to the point counts on the server, which it keeps alive.
        // SAFETY: the point of the free-threaded object, usable on any thread.
        let item = unsafe { Listed::new(this.point.counted::<IConnectionPoint>()) };
        ppEnum.write(Enumerator::<ConnectionPointsEnum>::create(vec![item].into(), 0));
        Ok(S_OK)
    }

    fn FindConnectionPoint(this: &ComObject<Self>, riid: &IID, ppCP: ffi::Out<'_, *mut IConnectionPoint>) -> FfiResult {
        if *riid != IID_IOPCShutdown {
            return Err(CONNECT_E_NOCONNECTION.into());
        }
        // The caller's reference counts on the controlling unknown.
        ppCP.write(this.point.counted::<IConnectionPoint>().into_raw().as_ptr());
        Ok(S_OK)
    }
}

/// The IUnknown of the connection point: its own identity, answering IUnknown and IConnectionPoint
/// only (a connection point is not its container); AddRef and Release count on the server object a
/// forwarding server named as the container, otherwise on the controlling unknown, as for every other
/// slot.
struct PointUnknown;

impl PointUnknown {
    /// The named container of the object whose point `this` is, if any.
    fn named_container(this: &ThisSlot<'_>) -> Option<*mut IUnknown> {
        let obj = this.object::<OpcShutdown>()?;
        obj.named_container.as_ref().map(|c| c.0.as_ptr())
    }
}

impl IUnknownImpl for PointUnknown {
    fn QueryInterface(this: ThisSlot<'_>, riid: &IID, ppv: ffi::Out<'_, *mut c_void>) -> FfiResult {
        if *riid != IID_IUNKNOWN && *riid != IID_ICONNECTIONPOINT {
            return Err(E_NOINTERFACE.into());
        }
        // The caller's new reference, counted where every reference to the point counts.
        this.add_ref();
        ppv.write(this.as_unknown().cast());
        Ok(S_OK)
    }

    fn AddRef(this: ThisSlot<'_>) -> u32 {
        match Self::named_container(&this) {
            // SAFETY: a named container outlives every reference to the point (they count on it).
            Some(container) => unsafe { add_ref(container) },
            None => Delegating::AddRef(this),
        }
    }

    fn Release(this: ThisSlot<'_>) -> u32 {
        // The container is read before the Release, which may end the server object and with it this
        // one.
        match Self::named_container(&this) {
            // SAFETY: as for AddRef; the caller gives up its reference.
            Some(container) => unsafe { release(container) },
            None => Delegating::Release(this),
        }
    }
}

impl IConnectionPointImpl for OpcShutdown {
    fn GetConnectionInterface(_this: &ComObject<Self>, pIID: ffi::Out<'_, IID>) -> FfiResult {
        pIID.write(IID_IOPCShutdown);
        Ok(S_OK)
    }

    fn GetConnectionPointContainer(
        this: &ComObject<Self>,
        ppCPC: ffi::Out<'_, *mut IConnectionPointContainer>,
    ) -> FfiResult {
        if let Some(server) = &this.named_container {
            // The server object that forwards to this one: its own IConnectionPointContainer. Never
            // this object's container, which counts on this object only (see OpcShutdownOptions).
            // SAFETY: the named container is alive while the point is referenced (the reference
            // this call is made through counts on it).
            let found =
                unsafe { query::<IConnectionPointContainer>(server.0.as_ptr(), &IID_ICONNECTIONPOINTCONTAINER) }?;
            ppCPC.write(found.into_raw().as_ptr());
            return Ok(S_OK);
        }
        let header = this.header();
        if header.is_aggregated() {
            // The container is whatever the server object (the controlling unknown) answers for
            // IConnectionPointContainer: usually this object's container slot, forwarded.
            if let Ok(found) = header.query::<IConnectionPointContainer>(&IID_ICONNECTIONPOINTCONTAINER) {
                // The reference QueryInterface gave us goes to the caller.
                ppCPC.write(found.into_raw().as_ptr());
                return Ok(S_OK);
            }
        }
        // Our own container slot; its AddRef counts on the controlling unknown.
        ppCPC.write(
            this.container
                .counted::<IConnectionPointContainer>()
                .into_raw()
                .as_ptr(),
        );
        Ok(S_OK)
    }

    fn Advise(this: &ComObject<Self>, pUnkSink: ffi::Iface<'_, IUnknown>, pdwCookie: ffi::Out<'_, DWORD>) -> FfiResult {
        pdwCookie.write(this.advise(pUnkSink)?);
        Ok(S_OK)
    }

    fn Unadvise(this: &ComObject<Self>, dwCookie: DWORD) -> FfiResult {
        Ok(this.unadvise(dwCookie))
    }

    fn EnumConnections(this: &ComObject<Self>, ppEnum: ffi::Out<'_, *mut IEnumConnections>) -> FfiResult {
        ppEnum.write(this.enum_connections()?);
        Ok(S_OK)
    }
}

/// Reads the caller's options, honouring `struct_size`.
///
/// # Safety
/// `options` must be NULL or point at `struct_size` readable bytes laid out as OpcShutdownOptions.
pub(crate) unsafe fn read_options(options: *const OpcShutdownOptions) -> Result<ShutdownSettings, HRESULT> {
    let defaults = OpcShutdownOptions {
        struct_size: 0,
        advise_limit: 0,
        container: core::ptr::null_mut(),
    };
    // SAFETY: OpcShutdownOptions is repr(C), starts with struct_size and holds integers and a raw
    // pointer; the caller vouches for `options`.
    let o = unsafe { read_sized(options, defaults) }?;
    Ok(ShutdownSettings {
        advise_limit: o.advise_limit,
        container: o.container,
    })
}

/// Finds the shutdown object behind any interface of it, of a server aggregating it, or of a server
/// forwarding to it (whose own IConnectionPointContainer hands out its connection point), and runs
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
    if let Some(obj) = unsafe { from_container(container.as_ptr()) } {
        let result = f(obj);
        drop(container);
        return Ok(result);
    }
    // A server's own container: is its IOPCShutdown connection point ours?
    let mut point: *mut IConnectionPoint = core::ptr::null_mut();
    // SAFETY: a valid container; the out-pointer is writable.
    let hr =
        unsafe { IConnectionPointContainer::FindConnectionPoint(container.as_ptr(), &IID_IOPCShutdown, &mut point) };
    drop(container);
    if hr < 0 {
        // A pointer left behind with a failure is neither used nor released.
        return Err(E_INVALIDARG);
    }
    // SAFETY: a successful FindConnectionPoint hands over one reference (none when NULL).
    let point = unsafe { Counted::adopt(point) }.ok_or(E_INVALIDARG)?;
    // SAFETY: a valid IConnectionPoint pointer, ours or not; the reference keeps the object alive
    // while `f` runs (it counts on the server, which holds the shutdown object, or on the object).
    let result = match unsafe { ComObject::<OpcShutdown>::from_foreign(point.as_ptr(), &POINT_VTBL) } {
        Some(obj) => Ok(f(obj)),
        None => Err(E_INVALIDARG),
    };
    drop(point);
    result
}
