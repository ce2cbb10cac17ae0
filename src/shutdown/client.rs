//! The client side: a shutdown sink that forwards ShutdownRequest to a C callback (specification
//! section 4.2), and helpers to advise it on a server and unadvise it again.

use core::ffi::c_void;
use core::ptr;

use super::interfaces::{IConnectionPoint, IConnectionPointContainer, IOPCShutdownVtbl};
use crate::com::ffi::{self, Fail, FfiResult, Hr};
use crate::com::iids::{IID_IOPCShutdown, IID_ICONNECTIONPOINTCONTAINER};
use crate::com::interfaces::IOPCShutdownImpl;
use crate::com::object::{ComClass, ComObject, Delegating, Slot};
use crate::com::unknown::{query, Counted};
use crate::com::{IUnknown, DWORD, E_POINTER, GUID, HRESULT, LPCWSTR, REFIID, S_OK, WCHAR};

/// Called when the server asks the client to disconnect. Runs on the thread that called
/// ShutdownRequest (the sink is agile: on Windows it aggregates the free-threaded marshaler, so an
/// in-process server in another apartment calls it directly); the library holds no lock, so the
/// callback may unadvise the sink and release the server.
///
/// # Parameters
/// - `context`: the `context` given to `OpcShutdownSinkCreate`.
/// - `reason`: the server's reason, never NULL (a NUL string when the server gave none), valid only
///   during the call.
pub type OpcShutdownCallback = Option<unsafe extern "C" fn(context: *mut c_void, reason: LPCWSTR)>;

/// The NUL string passed for a NULL reason (specification section 3.1.4).
pub(crate) static NUL_STRING: [WCHAR; 1] = [0];

/// The sink object. On Windows it is agile: it aggregates the free-threaded marshaler (see `agile`).
pub struct ShutdownSink {
    shutdown: Slot,
    #[cfg(windows)]
    marshal: Slot,
    #[cfg(windows)]
    ftm: super::agile::Ftm,
    callback: unsafe extern "C" fn(context: *mut c_void, reason: LPCWSTR),
    context: *mut c_void,
}

// SAFETY: the sink's contract says the callback is called with its context from any thread.
unsafe impl Send for ShutdownSink {}
// SAFETY: as above; the fields are never modified after construction.
unsafe impl Sync for ShutdownSink {}

impl ComClass for ShutdownSink {
    fn interface(&self, iid: &GUID) -> Option<&Slot> {
        #[cfg(windows)]
        if *iid == super::agile::IID_IMARSHAL {
            return Some(&self.marshal);
        }
        (*iid == IID_IOPCShutdown).then_some(&self.shutdown)
    }
}

#[cfg(windows)]
impl super::agile::HasFtm for ShutdownSink {
    fn ftm(&self) -> &super::agile::Ftm {
        &self.ftm
    }
}

#[cfg(windows)]
static SINK_MARSHAL_VTBL: crate::com::interfaces::IMarshalVtbl =
    crate::com::interfaces::IMarshalVtbl::new::<Delegating, ShutdownSink>();

static SINK_VTBL: IOPCShutdownVtbl = IOPCShutdownVtbl::new::<Delegating, ShutdownSink>();

impl IOPCShutdownImpl for ShutdownSink {
    fn ShutdownRequest(this: &ComObject<Self>, reason: Option<ffi::WStr<'_>>) -> FfiResult {
        // The specification requires S_OK whatever happens, a panic included.
        Ok(ffi::guard(S_OK, || {
            let reason = reason.map_or(NUL_STRING.as_ptr(), ffi::WStr::as_ptr);
            // SAFETY: the client registered the callback for this; `reason` is a valid string.
            unsafe { (this.callback)(this.context, reason) };
            S_OK
        }))
    }
}

/// Creates a shutdown sink for a client: an object with IUnknown and IOPCShutdown whose
/// ShutdownRequest calls `callback(context, reason)` and returns S_OK.
///
/// Pass the sink to `OpcShutdownAdvise` (or to IConnectionPoint::Advise yourself); the server keeps its
/// own reference until Unadvise, so the client may release its reference at any time.
///
/// # Parameters
/// - `callback`: what ShutdownRequest calls (OpcShutdownCallback).
/// - `context`: passed to `callback`; must stay valid until the sink is destroyed (after the last
///   Release: watch `OpcObjectCount` or unadvise first).
/// - `riid`: the interface wanted: IID_IUnknown or IID_IOPCShutdown.
/// - `ppv` (out): receives the interface, or NULL on failure.
///
/// # Returns
/// S_OK; E_POINTER for a NULL `ppv`, `riid` or `callback`; E_NOINTERFACE for another `riid`.
///
/// # Safety
/// `callback` must be NULL or callable with `context` from any thread; `riid` NULL or readable;
/// `ppv` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcShutdownSinkCreate(
    callback: OpcShutdownCallback,
    context: *mut c_void,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> Hr {
    ffi::boundary!(Com, [ppv], {
        let callback = callback.ok_or(Fail::Null)?;
        // SAFETY: forwarded from the caller's contract; not aggregated.
        Ok(unsafe {
            ComObject::<ShutdownSink>::create(ptr::null_mut(), riid, ppv, |binder| {
                Ok(ShutdownSink {
                    shutdown: binder.slot(&SINK_VTBL),
                    #[cfg(windows)]
                    marshal: binder.slot(&SINK_MARSHAL_VTBL),
                    #[cfg(windows)]
                    ftm: Default::default(),
                    callback,
                    context,
                })
            })
        })
    })
}

/// The IOPCShutdown connection point of `server`, as a counted pointer.
///
/// # Safety
/// `server` must be a valid COM interface pointer.
unsafe fn shutdown_point(server: *mut IUnknown) -> Result<Counted<IConnectionPoint>, HRESULT> {
    // SAFETY: valid per the caller.
    let container = unsafe { query::<IConnectionPointContainer>(server, &IID_ICONNECTIONPOINTCONTAINER) }?;
    let mut point: *mut IConnectionPoint = ptr::null_mut();
    // SAFETY: a counted IConnectionPointContainer pointer, released right after.
    let hr = unsafe {
        let c = container.as_ptr();
        ((*(*c).lpVtbl).FindConnectionPoint)(c, &IID_IOPCShutdown, &mut point).get()
    };
    drop(container);
    if hr < 0 {
        // As with QueryInterface: a pointer left behind with a failure is not trusted, not released.
        return Err(hr);
    }
    // SAFETY: a successful FindConnectionPoint hands over one reference (NULL gives None).
    unsafe { Counted::adopt(point) }.ok_or(E_POINTER)
}

/// Advises a client's shutdown sink on the IOPCShutdown connection point of a server: QueryInterface
/// for IConnectionPointContainer, FindConnectionPoint(IID_IOPCShutdown), then Advise.
///
/// Across machines the sink receives ShutdownRequest as a DCOM call from the server's machine: the
/// client is then a DCOM server, and since Windows' DCOM hardening (KB5004442) the call arrives only
/// when the client's process security is at RPC_C_AUTHN_LEVEL_PKT_INTEGRITY or above. Call
/// `OpcInitializeClientSecurity` after CoInitializeEx and before creating the server.
///
/// # Parameters
/// - `server`: any interface of the server object.
/// - `sink`: the client's sink, an object with IOPCShutdown (`OpcShutdownSinkCreate` makes one).
/// - `cookie` (out): receives the cookie for `OpcShutdownUnadvise`, or 0 on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL argument; otherwise the errors of the three steps as they are, so a
/// server without shutdown support gives E_NOINTERFACE (no IConnectionPointContainer) or
/// CONNECT_E_NOCONNECTION (no IOPCShutdown connection point); Advise gives CONNECT_E_CANNOTCONNECT
/// (the sink has no IOPCShutdown) or CONNECT_E_ADVISELIMIT.
///
/// # Safety
/// `server` and `sink` must be NULL or valid COM interface pointers; `cookie` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcShutdownAdvise(server: *mut IUnknown, sink: *mut IUnknown, cookie: *mut DWORD) -> Hr {
    ffi::boundary!(Opc, [cookie], {
        // SAFETY: the caller vouches a non-NULL `cookie` is writable.
        let (out, server, sink) = (unsafe { ffi::out(cookie) }?, ffi::in_ptr(server)?, ffi::in_ptr(sink)?);
        // SAFETY: valid per the caller.
        let point = unsafe { shutdown_point(server.as_ptr()) }?;
        let mut given: DWORD = 0;
        // SAFETY: a counted IConnectionPoint pointer, released as `point` drops.
        let hr = unsafe {
            let p = point.as_ptr();
            ((*(*p).lpVtbl).Advise)(p, sink.as_ptr(), &mut given).get()
        };
        if hr >= 0 {
            out.write(given);
        }
        Ok(hr)
    })
}

/// Unadvises a client's shutdown sink from a server.
///
/// # Parameters
/// - `server`: any interface of the server object.
/// - `cookie`: the cookie `OpcShutdownAdvise` returned.
///
/// # Returns
/// S_OK, or the error of the step that failed, as for `OpcShutdownAdvise`; an unknown cookie gives
/// CONNECT_E_NOCONNECTION. E_INVALIDARG for a NULL `server`.
///
/// # Safety
/// `server` must be NULL or a valid COM interface pointer.
#[no_mangle]
pub unsafe extern "C" fn OpcShutdownUnadvise(server: *mut IUnknown, cookie: DWORD) -> Hr {
    ffi::boundary!(Opc, [], {
        let server = ffi::in_ptr(server)?;
        // SAFETY: valid per the caller.
        let point = unsafe { shutdown_point(server.as_ptr()) }?;
        // SAFETY: a counted IConnectionPoint pointer, released as `point` drops.
        Ok(unsafe {
            let p = point.as_ptr();
            ((*(*p).lpVtbl).Unadvise)(p, cookie).get()
        })
    })
}
