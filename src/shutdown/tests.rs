//! Tests of both sides of the shutdown capability, with sinks that count their references.

use core::ffi::c_void;
use core::ptr;

use crate::com::ffi::{Crossed, Hr};
use crate::com::HRESULT;
use core::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;

use super::client::{OpcShutdownAdvise, OpcShutdownSinkCreate, OpcShutdownUnadvise};
use super::interfaces::*;
use super::server::{from_container, OpcShutdownOptions};
use super::*;
use crate::com::iids::{
    IID_IOPCCommon, IID_IOPCShutdown, IID_ICONNECTIONPOINT, IID_ICONNECTIONPOINTCONTAINER, IID_IENUMCONNECTIONPOINTS,
    IID_IENUMCONNECTIONS, IID_IUNKNOWN,
};
use crate::com::unknown::{add_ref, query_interface, release};
use crate::com::{
    CLASS_E_NOAGGREGATION, CONNECT_E_ADVISELIMIT, CONNECT_E_CANNOTCONNECT, CONNECT_E_NOCONNECTION, DWORD, E_FAIL,
    E_INVALIDARG, E_NOINTERFACE, E_POINTER, GUID, IID, WCHAR,
};

// ---------------------------------------------------------------------------------------------
// A client sink written by hand, counting its references and recording its calls.

type Hook = Box<dyn FnMut() + Send>;

#[repr(C)]
struct MockSink {
    vtbl: &'static IOPCShutdownVtbl,
    refs: AtomicU32,
    has_shutdown: bool,
    result: HRESULT,
    calls: AtomicU32,
    reasons: Mutex<Vec<Vec<WCHAR>>>,
    hook: Mutex<Option<Hook>>,
}

static MOCK_VTBL: IOPCShutdownVtbl = IOPCShutdownVtbl {
    QueryInterface: mock_qi,
    AddRef: mock_add_ref,
    Release: mock_release,
    ShutdownRequest: mock_shutdown_request,
};

unsafe extern "system" fn mock_qi(this: *mut IOPCShutdown, riid: REFIID, ppv: *mut *mut c_void) -> Hr {
    Crossed::from_c(|| {
        // SAFETY: only MockSink objects present MOCK_VTBL; the caller passes valid pointers.
        unsafe {
            let m = &*(this as *const MockSink);
            *ppv = ptr::null_mut();
            if *riid == IID_IUNKNOWN || (m.has_shutdown && *riid == IID_IOPCShutdown) {
                m.refs.fetch_add(1, Ordering::SeqCst);
                *ppv = this.cast();
                return S_OK;
            }
        }
        E_NOINTERFACE
    })
}

unsafe extern "system" fn mock_add_ref(this: *mut IOPCShutdown) -> Crossed<ULONG> {
    Crossed::from_c(|| {
        // SAFETY: as above.
        unsafe { &*(this as *const MockSink) }
            .refs
            .fetch_add(1, Ordering::SeqCst)
            + 1
    })
}

unsafe extern "system" fn mock_release(this: *mut IOPCShutdown) -> Crossed<ULONG> {
    Crossed::from_c(|| {
        // SAFETY: as above. The test owns the memory; the count only has to stay observable.
        let m = unsafe { &*(this as *const MockSink) };
        let before = m.refs.fetch_sub(1, Ordering::SeqCst);
        assert!(before > 0, "Release without a reference");
        before - 1
    })
}

unsafe extern "system" fn mock_shutdown_request(this: *mut IOPCShutdown, reason: LPCWSTR) -> Hr {
    Crossed::from_c(|| {
        // SAFETY: as above; the server passes a NUL-terminated string.
        let m = unsafe { &*(this as *const MockSink) };
        m.calls.fetch_add(1, Ordering::SeqCst);
        assert!(!reason.is_null(), "the server must never pass a NULL reason");
        // SAFETY: NUL-terminated per the interface contract.
        let units = unsafe { crate::com::wstr::wstr_units(reason, 1000) }.unwrap().to_vec();
        m.reasons.lock().unwrap().push(units);
        // Taken out of the mutex while it runs, so the hook may re-enter the server freely.
        let hook = m.hook.lock().unwrap().take();
        if let Some(mut hook) = hook {
            hook();
            *m.hook.lock().unwrap() = Some(hook);
        }
        m.result
    })
}

impl MockSink {
    fn new(has_shutdown: bool, result: HRESULT) -> Box<MockSink> {
        Box::new(MockSink {
            vtbl: &MOCK_VTBL,
            refs: AtomicU32::new(1),
            has_shutdown,
            result,
            calls: AtomicU32::new(0),
            reasons: Mutex::new(Vec::new()),
            hook: Mutex::new(None),
        })
    }
    fn unk(&self) -> *mut IUnknown {
        self as *const MockSink as *mut IUnknown
    }
    fn refs(&self) -> u32 {
        self.refs.load(Ordering::SeqCst)
    }
    fn calls(&self) -> u32 {
        self.calls.load(Ordering::SeqCst)
    }
    fn set_hook(&self, hook: impl FnMut() + Send + 'static) {
        *self.hook.lock().unwrap() = Some(Box::new(hook));
    }
}

// ---------------------------------------------------------------------------------------------
// Small wrappers over the vtables, as a C++ client would write them.

fn w(s: &str) -> Vec<WCHAR> {
    s.encode_utf16().chain(Some(0)).collect()
}

struct Server(*mut IConnectionPointContainer);

// SAFETY: the library's shutdown objects are free-threaded.
unsafe impl Sync for Server {}

// SAFETY: the library's shutdown objects are free-threaded.
unsafe impl Send for Server {}

impl Server {
    fn new() -> Server {
        Self::with_limit(None)
    }
    fn with_limit(limit: Option<u32>) -> Server {
        let options = limit.map(|advise_limit| OpcShutdownOptions {
            struct_size: core::mem::size_of::<OpcShutdownOptions>() as u32,
            advise_limit,
            container: ptr::null_mut(),
        });
        let mut p: *mut c_void = ptr::null_mut();
        let opts = options.as_ref().map_or(ptr::null(), |o| o as *const OpcShutdownOptions);
        // SAFETY: valid arguments.
        let hr = unsafe { OpcShutdownCreateEx(opts, ptr::null_mut(), &IID_ICONNECTIONPOINTCONTAINER, &mut p) };
        assert_eq!(hr, S_OK);
        Server(p.cast())
    }
    fn unk(&self) -> *mut IUnknown {
        self.0.cast()
    }
    fn find(&self, iid: &IID) -> (HRESULT, *mut IConnectionPoint) {
        let mut cp = core::ptr::null_mut::<IConnectionPoint>().wrapping_byte_add(1); // garbage, to prove it is written
                                                                                     // SAFETY: a live container.
        let hr = unsafe { ((*(*self.0).lpVtbl).FindConnectionPoint)(self.0, iid, &mut cp) }.get();
        (hr, cp)
    }
    fn point(&self) -> Point {
        let (hr, cp) = self.find(&IID_IOPCShutdown);
        assert_eq!(hr, S_OK);
        Point(cp)
    }
    fn notify(&self, reason: LPCWSTR) -> (HRESULT, u32, u32) {
        let (mut n, mut f) = (99, 99);
        // SAFETY: a live object.
        let hr = unsafe { OpcShutdownNotifyEx(self.unk(), reason, &mut n, &mut f) };
        (hr.get(), n, f)
    }
    fn connections(&self) -> usize {
        // SAFETY: a live container of ours.
        unsafe { from_container(self.0) }.unwrap().connection_count()
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        // SAFETY: the reference this wrapper owns.
        unsafe { release(self.0.cast()) };
    }
}

struct Point(*mut IConnectionPoint);

impl Point {
    fn advise(&self, sink: *mut IUnknown) -> (HRESULT, DWORD) {
        let mut cookie: DWORD = 0xDEAD;
        // SAFETY: a live point.
        let hr = unsafe { ((*(*self.0).lpVtbl).Advise)(self.0, sink, &mut cookie) };
        (hr.get(), cookie)
    }
    fn unadvise(&self, cookie: DWORD) -> HRESULT {
        // SAFETY: a live point.
        unsafe { ((*(*self.0).lpVtbl).Unadvise)(self.0, cookie) }.get()
    }
}

impl Drop for Point {
    fn drop(&mut self) {
        // SAFETY: the reference this wrapper owns.
        unsafe { release(self.0.cast()) };
    }
}

// ---------------------------------------------------------------------------------------------

#[test]
fn creation_follows_the_standard_protocol() {
    let mut p: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
    // SAFETY: deliberately bad arguments, all of which the function must reject cleanly.
    unsafe {
        assert_eq!(OpcShutdownCreate(ptr::null_mut(), ptr::null(), &mut p), E_POINTER);
        assert!(p.is_null());
        assert_eq!(
            OpcShutdownCreate(ptr::null_mut(), &IID_IUNKNOWN, ptr::null_mut()),
            E_POINTER
        );
        p = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
        assert_eq!(
            OpcShutdownCreate(ptr::null_mut(), &IID_IOPCCommon, &mut p),
            E_NOINTERFACE
        );
        assert!(p.is_null());
        let outer = MockSink::new(false, S_OK);
        assert_eq!(
            OpcShutdownCreate(outer.unk(), &IID_ICONNECTIONPOINTCONTAINER, &mut p),
            CLASS_E_NOAGGREGATION
        );
        assert!(p.is_null());
        let bad = OpcShutdownOptions {
            struct_size: 2,
            advise_limit: 1,
            container: ptr::null_mut(),
        };
        assert_eq!(
            OpcShutdownCreateEx(&bad, ptr::null_mut(), &IID_IUNKNOWN, &mut p),
            E_INVALIDARG
        );
        let bad = OpcShutdownOptions {
            struct_size: 64,
            advise_limit: 1,
            container: ptr::null_mut(),
        };
        assert_eq!(
            OpcShutdownCreateEx(&bad, ptr::null_mut(), &IID_IUNKNOWN, &mut p),
            E_INVALIDARG
        );
        assert!(p.is_null());
        assert_eq!(outer.refs(), 1);
    }
}

#[test]
fn find_connection_point_answers_only_iopcshutdown() {
    let server = Server::new();
    let (hr, cp) = server.find(&IID_IOPCCommon);
    assert_eq!(hr, CONNECT_E_NOCONNECTION);
    assert!(cp.is_null());
    // SAFETY: NULL arguments must be refused without touching anything.
    unsafe {
        let mut cp = core::ptr::null_mut::<IConnectionPoint>().wrapping_byte_add(1);
        assert_eq!(
            ((*(*server.0).lpVtbl).FindConnectionPoint)(server.0, ptr::null(), &mut cp),
            E_POINTER
        );
        assert!(cp.is_null());
        assert_eq!(
            ((*(*server.0).lpVtbl).FindConnectionPoint)(server.0, &IID_IOPCShutdown, ptr::null_mut()),
            E_POINTER
        );
        assert_eq!(
            ((*(*server.0).lpVtbl).EnumConnectionPoints)(server.0, ptr::null_mut()),
            E_POINTER
        );
    }
    let point = server.point();
    let mut iid = GUID::default();
    // SAFETY: a live point.
    unsafe {
        assert_eq!(((*(*point.0).lpVtbl).GetConnectionInterface)(point.0, &mut iid), S_OK);
        assert_eq!(
            ((*(*point.0).lpVtbl).GetConnectionInterface)(point.0, ptr::null_mut()),
            E_POINTER
        );
    }
    assert_eq!(iid, IID_IOPCShutdown);
}

#[test]
fn the_connection_point_is_its_own_object_and_knows_its_container() {
    let server = Server::new();
    let point = server.point();
    // SAFETY: live objects; every reference obtained is released.
    unsafe {
        // Its identity is its own, not the container's.
        let mut a: *mut c_void = ptr::null_mut();
        let mut b: *mut c_void = ptr::null_mut();
        assert_eq!(query_interface(point.0.cast(), &IID_IUNKNOWN, &mut a), S_OK);
        assert_eq!(query_interface(server.unk(), &IID_IUNKNOWN, &mut b), S_OK);
        assert_ne!(a, b);
        release(a.cast());
        release(b.cast());
        assert_eq!(query_interface(point.0.cast(), &IID_ICONNECTIONPOINT, &mut a), S_OK);
        assert_eq!(a, point.0.cast());
        release(a.cast());
        a = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
        assert_eq!(
            query_interface(point.0.cast(), &IID_ICONNECTIONPOINTCONTAINER, &mut a),
            E_NOINTERFACE
        );
        assert!(a.is_null());
        // The container does not hand out the point through QueryInterface either.
        a = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
        assert_eq!(
            query_interface(server.unk(), &IID_ICONNECTIONPOINT, &mut a),
            E_NOINTERFACE
        );
        assert!(a.is_null());

        let mut cpc: *mut IConnectionPointContainer = ptr::null_mut();
        assert_eq!(
            ((*(*point.0).lpVtbl).GetConnectionPointContainer)(point.0, &mut cpc),
            S_OK
        );
        assert_eq!(cpc, server.0);
        release(cpc.cast());
        assert_eq!(
            ((*(*point.0).lpVtbl).GetConnectionPointContainer)(point.0, ptr::null_mut()),
            E_POINTER
        );
    }
}

#[test]
fn advise_checks_its_arguments_and_the_sink() {
    let server = Server::new();
    let point = server.point();
    let (hr, cookie) = point.advise(ptr::null_mut());
    assert_eq!((hr, cookie), (E_POINTER, 0));
    // SAFETY: NULL cookie pointer must be refused.
    let hr = unsafe { ((*(*point.0).lpVtbl).Advise)(point.0, ptr::null_mut(), ptr::null_mut()) };
    assert_eq!(hr, E_POINTER);

    let plain = MockSink::new(false, S_OK);
    let (hr, cookie) = point.advise(plain.unk());
    assert_eq!((hr, cookie), (CONNECT_E_CANNOTCONNECT, 0));
    assert_eq!(plain.refs(), 1, "a refused sink keeps no reference");

    let sink = MockSink::new(true, S_OK);
    let (hr, cookie) = point.advise(sink.unk());
    assert_eq!(hr, S_OK);
    assert_ne!(cookie, 0);
    assert_eq!(sink.refs(), 2, "the connection holds exactly one reference");

    // The default limit is one sink.
    let other = MockSink::new(true, S_OK);
    let (hr, c2) = point.advise(other.unk());
    assert_eq!((hr, c2), (CONNECT_E_ADVISELIMIT, 0));
    assert_eq!(other.refs(), 1);

    assert_eq!(point.unadvise(0), CONNECT_E_NOCONNECTION);
    assert_eq!(point.unadvise(cookie + 1), CONNECT_E_NOCONNECTION);
    assert_eq!(point.unadvise(cookie), S_OK);
    assert_eq!(sink.refs(), 1);
    assert_eq!(point.unadvise(cookie), CONNECT_E_NOCONNECTION);
}

#[test]
fn cookies_are_never_zero_and_never_reused() {
    let server = Server::new();
    let point = server.point();
    let sink = MockSink::new(true, S_OK);
    let mut seen = Vec::new();
    for _ in 0..50 {
        let (hr, cookie) = point.advise(sink.unk());
        assert_eq!(hr, S_OK);
        assert_ne!(cookie, 0);
        assert!(!seen.contains(&cookie));
        seen.push(cookie);
        assert_eq!(point.unadvise(cookie), S_OK);
    }
    assert_eq!(sink.refs(), 1);
}

#[test]
fn the_advise_limit_can_be_raised() {
    let server = Server::with_limit(Some(3));
    let point = server.point();
    let sinks: Vec<_> = (0..4).map(|_| MockSink::new(true, S_OK)).collect();
    let mut cookies = Vec::new();
    for s in &sinks[..3] {
        let (hr, cookie) = point.advise(s.unk());
        assert_eq!(hr, S_OK);
        cookies.push(cookie);
    }
    assert_eq!(point.advise(sinks[3].unk()), (CONNECT_E_ADVISELIMIT, 0));
    assert_eq!(point.unadvise(cookies[1]), S_OK);
    let (hr, cookie) = point.advise(sinks[3].unk());
    assert_eq!(hr, S_OK);
    assert!(!cookies.contains(&cookie));
    assert_eq!(server.connections(), 3);

    // A limit of 0 in the options means the default, one.
    let default = Server::with_limit(Some(0));
    let p = default.point();
    assert_eq!(p.advise(sinks[0].unk()).0, S_OK);
    assert_eq!(p.advise(sinks[1].unk()).0, CONNECT_E_ADVISELIMIT);
    drop(p);
    drop(default);
    drop(point);
    drop(server);
    for s in &sinks {
        assert_eq!(s.refs(), 1, "the server released every sink when it died");
    }
}

#[test]
fn notify_passes_the_reason_and_a_nul_string_for_null() {
    let server = Server::new();
    assert_eq!(server.notify(ptr::null()), (S_OK, 0, 0), "no sink advised");
    let point = server.point();
    let sink = MockSink::new(true, S_OK);
    let (_, cookie) = point.advise(sink.unk());
    let reason = w("Server going down");
    assert_eq!(server.notify(reason.as_ptr()), (S_OK, 1, 0));
    assert_eq!(server.notify(ptr::null()), (S_OK, 1, 0));
    // SAFETY: the plain variant, through the connection point (any interface of the object works).
    assert_eq!(unsafe { OpcShutdownNotify(point.0.cast(), ptr::null()) }, E_INVALIDARG);
    // SAFETY: through the container.
    assert_eq!(unsafe { OpcShutdownNotify(server.unk(), ptr::null()) }, S_OK);
    let reasons = sink.reasons.lock().unwrap().clone();
    assert_eq!(reasons, vec![w("Server going down")[..17].to_vec(), vec![], vec![]]);
    assert_eq!(point.unadvise(cookie), S_OK);
    assert_eq!(sink.refs(), 1);
}

#[test]
fn notify_rejects_what_is_not_a_shutdown_object() {
    let foreign = MockSink::new(true, S_OK);
    let (mut n, mut f) = (7, 7);
    // SAFETY: a NULL and a foreign object (no IConnectionPointContainer).
    unsafe {
        assert_eq!(
            OpcShutdownNotifyEx(ptr::null_mut(), ptr::null(), &mut n, &mut f),
            E_INVALIDARG
        );
        assert_eq!((n, f), (0, 0));
        assert_eq!(OpcShutdownNotify(foreign.unk(), ptr::null()), E_INVALIDARG);
    }
    assert_eq!(foreign.refs(), 1);
}

#[test]
fn a_failing_sink_does_not_stop_the_others() {
    let server = Server::with_limit(Some(3));
    let point = server.point();
    let good1 = MockSink::new(true, S_OK);
    let bad = MockSink::new(true, E_FAIL);
    let good2 = MockSink::new(true, S_OK);
    for s in [&good1, &bad, &good2] {
        assert_eq!(point.advise(s.unk()).0, S_OK);
    }
    assert_eq!(server.notify(ptr::null()), (S_FALSE, 2, 1));
    assert_eq!((good1.calls(), bad.calls(), good2.calls()), (1, 1, 1));
    drop(point);
    drop(server);
    for s in [&good1, &bad, &good2] {
        assert_eq!(s.refs(), 1);
    }
}

#[test]
fn a_sink_may_unadvise_itself_inside_shutdown_request() {
    let server = Server::new();
    let sink = MockSink::new(true, S_OK);
    let mut cookie: DWORD = 0;
    // SAFETY: live objects.
    let hr = unsafe { OpcShutdownAdvise(server.unk(), sink.unk(), &mut cookie) };
    assert_eq!(hr, S_OK);
    let server_unk = server.unk() as usize;
    let results = std::sync::Arc::new(Mutex::new(Vec::new()));
    let seen = results.clone();
    sink.set_hook(move || {
        // Would deadlock if the server held its lock while calling us.
        // SAFETY: the server is alive during the notification.
        let hr = unsafe { OpcShutdownUnadvise(server_unk as *mut IUnknown, cookie) };
        seen.lock().unwrap().push(hr);
    });
    assert_eq!(server.notify(ptr::null()), (S_OK, 1, 0));
    assert_eq!(*results.lock().unwrap(), vec![S_OK]);
    assert_eq!(server.connections(), 0);
    assert_eq!(sink.refs(), 1, "unadvised: the server dropped its reference");
    assert_eq!(server.notify(ptr::null()), (S_OK, 0, 0));
    assert_eq!(sink.calls(), 1);
}

#[test]
fn a_sink_unadvised_by_another_during_notification_is_not_called() {
    let server = Server::with_limit(Some(2));
    let point = server.point();
    let first = MockSink::new(true, S_OK);
    let second = MockSink::new(true, S_OK);
    let (_, c1) = point.advise(first.unk());
    let (_, c2) = point.advise(second.unk());
    let cp = point.0 as usize;
    first.set_hook(move || {
        // SAFETY: the point is alive during the notification.
        let hr = unsafe { ((*(*(cp as *mut IConnectionPoint)).lpVtbl).Unadvise)(cp as *mut IConnectionPoint, c2) };
        assert_eq!(hr, S_OK);
    });
    assert_eq!(server.notify(ptr::null()), (S_OK, 1, 0));
    assert_eq!((first.calls(), second.calls()), (1, 0));
    assert_eq!(second.refs(), 1);
    assert_eq!(point.unadvise(c1), S_OK);
    assert_eq!(first.refs(), 1);
}

#[test]
fn a_sink_may_release_the_last_reference_to_the_server_inside_shutdown_request() {
    let server = Server::new();
    let point = server.point();
    let sink = MockSink::new(true, S_OK);
    assert_eq!(point.advise(sink.unk()).0, S_OK);
    drop(point);
    let raw = server.unk() as usize;
    core::mem::forget(server); // the sink now owns the last reference
    sink.set_hook(move || {
        // SAFETY: the reference given to the sink; OpcShutdownNotify holds its own meanwhile.
        unsafe { release(raw as *mut IUnknown) };
    });
    let (mut n, mut f) = (0, 0);
    // SAFETY: the object is alive when the call starts.
    let hr = unsafe { OpcShutdownNotifyEx(raw as *mut IUnknown, ptr::null(), &mut n, &mut f) };
    assert_eq!((hr.get(), n, f), (S_OK, 1, 0));
    assert_eq!(
        sink.refs(),
        1,
        "the server died after the notification and released the sink"
    );
}

#[test]
fn connection_points_enumerate_with_next_skip_reset_clone() {
    let server = Server::new();
    let sink = MockSink::new(true, S_OK);
    let point = server.point();
    assert_eq!(point.advise(sink.unk()).0, S_OK);
    drop(point);
    let mut e: *mut IEnumConnectionPoints = ptr::null_mut();
    // SAFETY: live objects; every reference obtained is released.
    unsafe {
        assert_eq!(((*(*server.0).lpVtbl).EnumConnectionPoints)(server.0, &mut e), S_OK);
        let v = &*(*e).lpVtbl;
        let mut got: [*mut IConnectionPoint; 3] = [ptr::null_mut(); 3];
        let mut fetched: ULONG = 99;
        assert_eq!((v.Next)(e, 3, got.as_mut_ptr(), &mut fetched), S_FALSE);
        assert_eq!(fetched, 1);
        let mut iid = GUID::default();
        assert_eq!(((*(*got[0]).lpVtbl).GetConnectionInterface)(got[0], &mut iid), S_OK);
        assert_eq!(iid, IID_IOPCShutdown);
        release(got[0].cast());
        assert_eq!((v.Next)(e, 1, got.as_mut_ptr(), &mut fetched), S_FALSE);
        assert_eq!(fetched, 0);
        assert_eq!((v.Next)(e, 2, got.as_mut_ptr(), ptr::null_mut()), E_POINTER);
        assert_eq!((v.Next)(e, 1, ptr::null_mut(), &mut fetched), E_POINTER);
        assert_eq!((v.Reset)(e), S_OK);
        assert_eq!((v.Skip)(e, 1), S_OK);
        assert_eq!((v.Skip)(e, 1), S_FALSE);
        assert_eq!((v.Reset)(e), S_OK);
        let mut c: *mut IEnumConnectionPoints = ptr::null_mut();
        assert_eq!((v.Clone)(e, &mut c), S_OK);
        assert_eq!((v.Clone)(e, ptr::null_mut()), E_POINTER);
        // pcFetched may be NULL when asking for one.
        assert_eq!((v.Next)(c, 1, got.as_mut_ptr(), ptr::null_mut()), S_OK);
        release(got[0].cast());
        let mut other: *mut c_void = ptr::null_mut();
        assert_eq!(query_interface(e.cast(), &IID_IENUMCONNECTIONPOINTS, &mut other), S_OK);
        release(other.cast());
        // The enumerators keep the server alive after the client released it.
        let e2 = c as usize;
        drop(server);
        assert_eq!(sink.refs(), 2);
        release(e.cast());
        assert_eq!(sink.refs(), 2);
        release(e2 as *mut IUnknown);
        assert_eq!(sink.refs(), 1, "the last enumerator released the server");
    }
}

#[test]
fn connections_enumerate_with_counted_sinks() {
    let server = Server::with_limit(Some(2));
    let point = server.point();
    let a = MockSink::new(true, S_OK);
    let b = MockSink::new(true, S_OK);
    let (_, ca) = point.advise(a.unk());
    let (_, cb) = point.advise(b.unk());
    let mut e: *mut IEnumConnections = ptr::null_mut();
    // SAFETY: live objects; every reference obtained is released.
    unsafe {
        assert_eq!(
            ((*(*point.0).lpVtbl).EnumConnections)(point.0, ptr::null_mut()),
            E_POINTER
        );
        assert_eq!(((*(*point.0).lpVtbl).EnumConnections)(point.0, &mut e), S_OK);
        let v = &*(*e).lpVtbl;
        assert_eq!(
            (a.refs(), b.refs()),
            (3, 3),
            "the snapshot holds a reference to each sink"
        );
        // Unadvising now does not change the snapshot.
        assert_eq!(point.unadvise(cb), S_OK);
        let mut data = [CONNECTDATA {
            pUnk: ptr::null_mut(),
            dwCookie: 0,
        }; 4];
        let mut fetched: ULONG = 0;
        assert_eq!((v.Skip)(e, 1), S_OK);
        assert_eq!((v.Next)(e, 4, data.as_mut_ptr(), &mut fetched), S_FALSE);
        assert_eq!(fetched, 1);
        assert_eq!(data[0].dwCookie, cb);
        assert_eq!(data[0].pUnk, b.unk());
        assert_eq!(b.refs(), 3, "snapshot + the caller's copy");
        release(data[0].pUnk);
        assert_eq!((v.Reset)(e), S_OK);
        assert_eq!((v.Next)(e, 2, data.as_mut_ptr(), &mut fetched), S_OK);
        assert_eq!(fetched, 2);
        assert_eq!((data[0].dwCookie, data[1].dwCookie), (ca, cb));
        release(data[0].pUnk);
        release(data[1].pUnk);
        let mut c: *mut IEnumConnections = ptr::null_mut();
        assert_eq!((v.Clone)(e, &mut c), S_OK);
        assert_eq!(
            (v.Next)(c, 1, data.as_mut_ptr(), ptr::null_mut()),
            S_FALSE,
            "a clone keeps the position"
        );
        let mut other: *mut c_void = ptr::null_mut();
        assert_eq!(query_interface(c.cast(), &IID_IENUMCONNECTIONS, &mut other), S_OK);
        release(other.cast());
        release(e.cast());
        assert_eq!(b.refs(), 2, "the clone still shares the snapshot");
        release(c.cast());
        assert_eq!((a.refs(), b.refs()), (2, 1));
    }
    assert_eq!(point.unadvise(ca), S_OK);
    assert_eq!(a.refs(), 1);
}

#[test]
fn holding_only_the_connection_point_keeps_the_server_and_nothing_leaks() {
    let server = Server::new();
    let point = server.point();
    let sink = MockSink::new(true, S_OK);
    assert_eq!(point.advise(sink.unk()).0, S_OK);
    drop(server);
    assert_eq!(sink.refs(), 2, "the point keeps the server alive");
    let mut cpc: *mut IConnectionPointContainer = ptr::null_mut();
    // SAFETY: a live point.
    unsafe {
        assert_eq!(
            ((*(*point.0).lpVtbl).GetConnectionPointContainer)(point.0, &mut cpc),
            S_OK
        );
        assert_eq!(OpcShutdownNotify(cpc.cast(), ptr::null()), S_OK);
        release(cpc.cast());
    }
    assert_eq!(sink.calls(), 1);
    drop(point);
    assert_eq!(
        sink.refs(),
        1,
        "the server died with the last reference and released the sink"
    );
}

// ---------------------------------------------------------------------------------------------
// Client side.

struct Received(Mutex<Vec<Vec<WCHAR>>>);

unsafe extern "C" fn record(context: *mut c_void, reason: LPCWSTR) {
    // SAFETY: the tests pass a `Received` as context; the library passes a valid string.
    let received = unsafe { &*(context as *const Received) };
    // SAFETY: as above.
    let units = unsafe { crate::com::wstr::wstr_units(reason, 1000) }.unwrap().to_vec();
    received.0.lock().unwrap().push(units);
}

#[test]
fn the_client_sink_calls_back_and_always_returns_s_ok() {
    let received = Received(Mutex::new(Vec::new()));
    let ctx = &received as *const Received as *mut c_void;
    let mut p: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
    // SAFETY: valid and deliberately invalid arguments.
    unsafe {
        assert_eq!(OpcShutdownSinkCreate(None, ctx, &IID_IOPCShutdown, &mut p), E_POINTER);
        assert!(p.is_null());
        assert_eq!(
            OpcShutdownSinkCreate(Some(record), ctx, &IID_IOPCCommon, &mut p),
            E_NOINTERFACE
        );
        assert_eq!(OpcShutdownSinkCreate(Some(record), ctx, ptr::null(), &mut p), E_POINTER);
        assert_eq!(
            OpcShutdownSinkCreate(Some(record), ctx, &IID_IOPCShutdown, ptr::null_mut()),
            E_POINTER
        );
        assert_eq!(
            OpcShutdownSinkCreate(Some(record), ctx, &IID_IOPCShutdown, &mut p),
            S_OK
        );
        let sink = p.cast::<IOPCShutdown>();
        let reason = w("maintenance");
        assert_eq!(((*(*sink).lpVtbl).ShutdownRequest)(sink, reason.as_ptr()), S_OK);
        assert_eq!(((*(*sink).lpVtbl).ShutdownRequest)(sink, ptr::null()), S_OK);
        let mut unk: *mut c_void = ptr::null_mut();
        assert_eq!(query_interface(sink.cast(), &IID_IUNKNOWN, &mut unk), S_OK);
        assert_eq!(add_ref(unk.cast()), 3);
        release(unk.cast());
        release(unk.cast());
        assert_eq!(release(sink.cast()), 0);
    }
    let got = received.0.lock().unwrap().clone();
    assert_eq!(got, vec![w("maintenance")[..11].to_vec(), vec![]]);
}

#[test]
fn client_and_server_of_this_library_work_together() {
    let received = Received(Mutex::new(Vec::new()));
    let ctx = &received as *const Received as *mut c_void;
    let server = Server::new();
    let mut sink: *mut c_void = ptr::null_mut();
    let mut cookie: DWORD = 0xDEAD;
    // SAFETY: live objects; references released below.
    unsafe {
        assert_eq!(OpcShutdownSinkCreate(Some(record), ctx, &IID_IUNKNOWN, &mut sink), S_OK);
        assert_eq!(OpcShutdownAdvise(server.unk(), sink.cast(), &mut cookie), S_OK);
        assert_ne!(cookie, 0);
        // The client may let go of its own reference: the connection keeps the sink.
        release(sink.cast());
        let reason = w("bye");
        assert_eq!(OpcShutdownNotify(server.unk(), reason.as_ptr()), S_OK);
        assert_eq!(OpcShutdownUnadvise(server.unk(), cookie), S_OK);
        assert_eq!(OpcShutdownUnadvise(server.unk(), cookie), CONNECT_E_NOCONNECTION);
        assert_eq!(OpcShutdownNotify(server.unk(), reason.as_ptr()), S_OK);
    }
    assert_eq!(received.0.lock().unwrap().len(), 1);
}

#[test]
fn the_helpers_report_servers_without_shutdown_support() {
    let not_a_server = MockSink::new(true, S_OK);
    let sink = MockSink::new(true, S_OK);
    let mut cookie: DWORD = 0xDEAD;
    // SAFETY: valid COM objects; NULL arguments refused.
    unsafe {
        assert_eq!(
            OpcShutdownAdvise(not_a_server.unk(), sink.unk(), &mut cookie),
            E_NOINTERFACE
        );
        assert_eq!(cookie, 0);
        assert_eq!(OpcShutdownUnadvise(not_a_server.unk(), 1), E_NOINTERFACE);
        cookie = 0xDEAD;
        assert_eq!(
            OpcShutdownAdvise(ptr::null_mut(), sink.unk(), &mut cookie),
            E_INVALIDARG
        );
        assert_eq!(cookie, 0);
        let server = Server::new();
        assert_eq!(
            OpcShutdownAdvise(server.unk(), ptr::null_mut(), &mut cookie),
            E_INVALIDARG
        );
        assert_eq!(
            OpcShutdownAdvise(server.unk(), sink.unk(), ptr::null_mut()),
            E_INVALIDARG
        );
        assert_eq!(OpcShutdownUnadvise(ptr::null_mut(), 1), E_INVALIDARG);
        let plain = MockSink::new(false, S_OK);
        assert_eq!(
            OpcShutdownAdvise(server.unk(), plain.unk(), &mut cookie),
            CONNECT_E_CANNOTCONNECT
        );
        assert_eq!(OpcShutdownUnadvise(server.unk(), 12345), CONNECT_E_NOCONNECTION);
    }
    assert_eq!((not_a_server.refs(), sink.refs()), (1, 1));
}

#[test]
fn hostile_query_interface_answers_are_refused_without_a_crash() {
    use crate::com::unknown::hostile;
    let server = Server::new();
    let point = server.point();
    let sink = MockSink::new(true, S_OK);
    // S_OK with NULL is E_POINTER; a failure passes through (its garbage pointer untouched).
    for (h, expected) in hostile::all().into_iter().zip([E_POINTER, E_NOINTERFACE]) {
        let mut cookie: DWORD = 0xDEAD;
        // SAFETY: valid (if broken) COM objects and writable out-parameters.
        unsafe {
            // As a server object: QueryInterface(IID_IConnectionPointContainer) answers badly.
            assert_eq!(OpcShutdownAdvise(h.unk(), sink.unk(), &mut cookie), expected);
            assert_eq!(cookie, 0);
            assert_eq!(OpcShutdownUnadvise(h.unk(), 1), expected);
            assert_eq!(OpcShutdownNotify(h.unk(), ptr::null()), E_INVALIDARG);
            let (mut n, mut f) = (7, 7);
            assert_eq!(OpcShutdownNotifyEx(h.unk(), ptr::null(), &mut n, &mut f), E_INVALIDARG);
            assert_eq!((n, f), (0, 0));
            // As a sink: QueryInterface(IID_IOPCShutdown) answers badly.
            assert_eq!(point.advise(h.unk()), (CONNECT_E_CANNOTCONNECT, 0));
            assert_eq!(
                OpcShutdownAdvise(server.unk(), h.unk(), &mut cookie),
                CONNECT_E_CANNOTCONNECT
            );
        }
        assert_eq!(h.refs(), 1, "nothing released or kept");
    }
    assert_eq!(server.connections(), 0);
    assert_eq!(sink.refs(), 1);
}

#[test]
fn concurrent_advise_unadvise_and_notify_stay_consistent() {
    let server = std::sync::Arc::new(Server::with_limit(Some(64)));
    let sinks: Vec<_> = (0..4).map(|_| MockSink::new(true, S_OK)).collect();
    /// A sink's pointer, handed to a thread (the mock sinks are thread-safe).
    #[derive(Clone, Copy)]
    struct SinkPtr(*mut IUnknown);
    // SAFETY: the mock sinks count with atomics and outlive the scope.
    unsafe impl Send for SinkPtr {}
    let sink_ptrs: Vec<SinkPtr> = sinks.iter().map(|s| SinkPtr(s.unk())).collect();
    // (20 rounds under Miri, which runs the threads one step at a time.)
    let rounds = if cfg!(miri) { 20 } else { 200 };
    std::thread::scope(|scope| {
        for &sink in &sink_ptrs {
            let server = server.clone();
            scope.spawn(move || {
                let sink = sink; // the whole wrapper, not its field (which is not Send)
                let point = server.point();
                for _ in 0..rounds {
                    let (hr, cookie) = point.advise(sink.0);
                    assert_eq!(hr, S_OK);
                    let (hr, _, failed) = server.notify(ptr::null());
                    assert_eq!((hr, failed), (S_OK, 0));
                    assert_eq!(point.unadvise(cookie), S_OK);
                }
            });
        }
    });
    assert_eq!(server.connections(), 0);
    drop(server);
    for s in &sinks {
        assert_eq!(s.refs(), 1, "every reference taken was given back");
        assert!(
            s.calls() >= rounds,
            "each sink was advised during its own notifications"
        );
    }
}

/// Windows: with COM initialised, Advise puts an agile sink (the library's own, which aggregates the
/// free-threaded marshaler) into the Global Interface Table; an apartment-bound sink goes there too
/// when IOPCShutdown has a registered proxy/stub (the GIT marshals it), and stays held directly when
/// it has none. Both are notified.
#[cfg(windows)]
#[test]
fn sinks_go_through_the_global_interface_table_when_com_is_initialised() {
    use windows_sys::Win32::System::Com::{CoInitializeEx, CoUninitialize, COINIT_MULTITHREADED};
    std::thread::spawn(|| {
        // SAFETY: a fresh thread of our own; balanced by CoUninitialize below.
        assert!(unsafe { CoInitializeEx(ptr::null(), COINIT_MULTITHREADED as u32) } >= 0);
        {
            let received = Received(Mutex::new(Vec::new()));
            let server = Server::with_limit(Some(2));
            let mut sink: *mut c_void = ptr::null_mut();
            let mock = MockSink::new(true, S_OK);
            let (mut agile_cookie, mut bound_cookie): (DWORD, DWORD) = (0, 0);
            let ctx = &received as *const Received as *mut c_void;
            // SAFETY: live objects; references released below.
            unsafe {
                assert_eq!(OpcShutdownSinkCreate(Some(record), ctx, &IID_IUNKNOWN, &mut sink), S_OK);
                assert_eq!(OpcShutdownAdvise(server.unk(), sink.cast(), &mut agile_cookie), S_OK);
                assert_eq!(OpcShutdownAdvise(server.unk(), mock.unk(), &mut bound_cookie), S_OK);
                release(sink.cast());
            }
            // SAFETY: a live container of ours.
            let held = unsafe { from_container(server.0) }.unwrap().held_globally();
            // What this machine has registered (the Wine prefix of the tests may hold opccomn's
            // proxy/stub or the Foundation's); each case is a defined outcome of the same rule.
            let proxy_stub = crate::registry::Registries::system()
                .write
                .key_exists(&format!("Interface\\{IID_IOPCShutdown}\\ProxyStubClsid32"));
            assert_eq!(
                held,
                vec![true, proxy_stub],
                "IOPCShutdown proxy/stub registered: {proxy_stub}"
            );
            assert_eq!(server.notify(ptr::null()), (S_OK, 2, 0));
            assert_eq!((received.0.lock().unwrap().len(), mock.calls()), (1, 1));
            // SAFETY: live objects.
            unsafe {
                assert_eq!(OpcShutdownUnadvise(server.unk(), agile_cookie), S_OK);
                assert_eq!(OpcShutdownUnadvise(server.unk(), bound_cookie), S_OK);
            }
            assert_eq!(mock.refs(), 1);
        }
        // SAFETY: balances CoInitializeEx above.
        unsafe { CoUninitialize() };
    })
    .join()
    .unwrap();
}

// ---------------------------------------------------------------------------------------------
// The bounded notification (OpcShutdownNotifyBounded).

use super::bounded::{OpcShutdownNotifyOptions, OPC_SHUTDOWN_NO_TIMEOUT};

/// Options for `OpcShutdownNotifyBounded`.
fn bounds(timeout_ms: u32, sink_timeout_ms: u32) -> OpcShutdownNotifyOptions {
    OpcShutdownNotifyOptions {
        struct_size: core::mem::size_of::<OpcShutdownNotifyOptions>() as u32,
        timeout_ms,
        sink_timeout_ms,
    }
}

impl Server {
    /// `OpcShutdownNotifyBounded`: the result and the counts notified, failed, timed out.
    fn notify_bounded(&self, reason: LPCWSTR, options: *const OpcShutdownNotifyOptions) -> (HRESULT, u32, u32, u32) {
        let (mut n, mut f, mut t) = (99, 99, 99);
        // SAFETY: a live object; valid pointers.
        let hr = unsafe { OpcShutdownNotifyBounded(self.unk(), reason, options, &mut n, &mut f, &mut t) };
        (hr.get(), n, f, t)
    }
}

/// Waits (without a time limit of its own: the test harness has one) until `done` holds.
fn wait_until(done: impl Fn() -> bool) {
    while !done() {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

#[test]
fn bounded_notification_checks_its_arguments() {
    let (mut n, mut f, mut t) = (99, 99, 99);
    let options = bounds(0, 0);
    // SAFETY: NULL is allowed for the object; the counts are writable.
    let hr = unsafe { OpcShutdownNotifyBounded(ptr::null_mut(), ptr::null(), &options, &mut n, &mut f, &mut t) };
    assert_eq!((hr.get(), n, f, t), (E_INVALIDARG, 0, 0, 0));
    let server = Server::new();
    for size in [0u32, 4, 8, 16] {
        let bad = OpcShutdownNotifyOptions {
            struct_size: size,
            ..options
        };
        assert_eq!(server.notify_bounded(ptr::null(), &bad), (E_INVALIDARG, 0, 0, 0));
    }
    // No sink advised: nothing to wait for.
    assert_eq!(server.notify_bounded(ptr::null(), ptr::null()), (S_OK, 0, 0, 0));
    // Every count may be NULL.
    // SAFETY: a live object.
    let hr = unsafe {
        OpcShutdownNotifyBounded(
            server.unk(),
            ptr::null(),
            ptr::null(),
            ptr::null_mut(),
            ptr::null_mut(),
            ptr::null_mut(),
        )
    };
    assert_eq!(hr.get(), S_OK);
}

#[test]
fn bounded_notification_calls_every_sink_and_counts_failures() {
    let server = Server::with_limit(Some(3));
    let point = server.point();
    let good = MockSink::new(true, S_OK);
    let bad = MockSink::new(true, E_FAIL);
    for s in [&good, &bad] {
        assert_eq!(point.advise(s.unk()).0, S_OK);
    }
    let options = bounds(OPC_SHUTDOWN_NO_TIMEOUT, 0);
    assert_eq!(server.notify_bounded(w("Stop").as_ptr(), &options), (S_FALSE, 1, 1, 0));
    assert_eq!(server.notify_bounded(ptr::null(), ptr::null()), (S_FALSE, 1, 1, 0));
    assert_eq!((good.calls(), bad.calls()), (2, 2));
    assert_eq!(*good.reasons.lock().unwrap(), vec![w("Stop")[..4].to_vec(), vec![]]);
    drop(point);
    drop(server);
    wait_until(|| good.refs() == 1 && bad.refs() == 1); // the workers let go of their references
}

/// The sinks are called at once: the first sink sees the second called while it is still inside its
/// own call, which a notification calling them one after the other never shows (the first sink
/// gives up waiting after a generous while, so that such a notification fails instead of hanging).
#[test]
fn bounded_notification_calls_the_sinks_at_once() {
    let server = Server::with_limit(Some(2));
    let point = server.point();
    let waiting = MockSink::new(true, S_OK);
    let other = std::sync::Arc::new(MockSink::new(true, S_OK));
    let saw_other = std::sync::Arc::new(core::sync::atomic::AtomicBool::new(false));
    let (seen, saw) = (other.clone(), saw_other.clone());
    waiting.set_hook(move || {
        for _ in 0..2000 {
            if seen.calls() >= 1 {
                saw.store(true, Ordering::SeqCst);
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    });
    for s in [waiting.unk(), other.unk()] {
        assert_eq!(point.advise(s).0, S_OK);
    }
    let options = bounds(OPC_SHUTDOWN_NO_TIMEOUT, 0);
    assert_eq!(server.notify_bounded(ptr::null(), &options), (S_OK, 2, 0, 0));
    drop(point);
    drop(server);
    wait_until(|| waiting.refs() == 1 && other.refs() == 1);
    assert!(
        saw_other.load(Ordering::SeqCst),
        "the second sink was called while the first was inside its call"
    );
}

/// A sink that blocks in ShutdownRequest does not hold the call: it times out, the others are counted
/// as they answered, and when its call returns late, after the server and the caller's reason are
/// gone, the worker finds what it holds alive and releases the sink.
#[test]
fn a_blocked_sink_times_out_and_its_late_return_is_harmless() {
    let server = Server::with_limit(Some(3));
    let point = server.point();
    let good = MockSink::new(true, S_OK);
    let bad = MockSink::new(true, E_FAIL);
    let blocked = MockSink::new(true, S_OK);
    let (release_sink, released) = std::sync::mpsc::channel::<()>();
    let released = Mutex::new(released);
    blocked.set_hook(move || {
        let _ = released.lock().unwrap().recv(); // until the test lets it go
    });
    for s in [&blocked, &good, &bad] {
        assert_eq!(point.advise(s.unk()).0, S_OK);
    }
    let reason = w("Maintenance");
    let options = bounds(100, 0);
    // Returns while the blocked sink is still inside ShutdownRequest: the test lets it go only after.
    let (hr, notified, failed, timed_out) = server.notify_bounded(reason.as_ptr(), &options);
    let worker_running = super::bounded::workers_running() >= 1;
    let unload = crate::module::OpcDllCanUnloadNow().get();
    // Everything the caller had goes away before the late call returns.
    drop(reason);
    drop(point);
    drop(server);
    release_sink.send(()).unwrap();
    wait_until(|| blocked.refs() == 1 && good.refs() == 1 && bad.refs() == 1);
    // (Checked once every worker is done, so that a failure cannot free a sink under a worker.)
    assert_eq!(hr, S_FALSE);
    assert!(timed_out >= 1, "the blocked sink timed out");
    // The others answered at once; on a loaded machine they might still miss the deadline, never
    // be miscounted.
    assert!(notified <= 1 && failed <= 1 && notified + failed + timed_out == 3);
    assert!(
        worker_running && unload == S_FALSE,
        "the late worker keeps the DLL loaded"
    );
    assert_eq!((blocked.calls(), good.calls(), bad.calls()), (1, 1, 1));
    assert_eq!(*blocked.reasons.lock().unwrap(), vec![w("Maintenance")[..11].to_vec()]);
}

/// A sink that never returns: the deadline per sink ends the wait for it even without a deadline for
/// the whole notification.
#[test]
#[cfg_attr(miri, ignore)] // leaves a thread blocked for good
fn a_sink_that_never_returns_does_not_hold_the_notification() {
    let server = Server::with_limit(Some(2));
    let point = server.point();
    let good = MockSink::new(true, S_OK);
    // Leaked: its calls never end, so its memory must stay valid for the rest of the process.
    let stuck: &'static MockSink = Box::leak(MockSink::new(true, S_OK));
    stuck.set_hook(|| loop {
        std::thread::park();
    });
    for s in [stuck.unk(), good.unk()] {
        assert_eq!(point.advise(s).0, S_OK);
    }
    let options = bounds(OPC_SHUTDOWN_NO_TIMEOUT, 100);
    let (hr, notified, failed, timed_out) = server.notify_bounded(ptr::null(), &options);
    drop(point);
    drop(server);
    wait_until(|| good.refs() == 1);
    assert_eq!((hr, failed), (S_FALSE, 0));
    // The stuck sink timed out; the other answered at once (on a loaded machine it might miss its
    // deadline too, never be miscounted).
    assert!(timed_out >= 1 && notified + timed_out == 2);
    assert_eq!((good.calls(), stuck.calls()), (1, 1));
}

// ---------------------------------------------------------------------------------------------
// The bounded notification's threads: one call per sink at a time, a pool of bounded size, and every
// healthy sink called however many sinks hang.

use super::bounded::Pool;
use std::sync::{Arc, Condvar};

/// Holds the sinks that call `wait` inside ShutdownRequest until the test opens it.
#[derive(Clone, Default)]
struct Gate(Arc<(Mutex<bool>, Condvar)>);

impl Gate {
    fn wait(&self) {
        let (open, changed) = &*self.0;
        let mut open = open.lock().unwrap();
        while !*open {
            open = changed.wait(open).unwrap();
        }
    }
    fn open(&self) {
        *self.0 .0.lock().unwrap() = true;
        self.0 .1.notify_all();
    }
}

/// A sink that hangs in ShutdownRequest until `gate` opens.
fn hung_sink(gate: &Gate) -> Box<MockSink> {
    let sink = MockSink::new(true, S_OK);
    let gate = gate.clone();
    sink.set_hook(move || gate.wait());
    sink
}

/// A sink that answers at once and records the thread each call came on.
fn healthy_sink() -> (Box<MockSink>, Arc<Mutex<Vec<std::thread::ThreadId>>>) {
    let sink = MockSink::new(true, S_OK);
    let threads = Arc::new(Mutex::new(Vec::new()));
    let record = threads.clone();
    sink.set_hook(move || record.lock().unwrap().push(std::thread::current().id()));
    (sink, threads)
}

impl Server {
    /// `OpcShutdownNotifyBounded` through `pool`: the result and the counts notified, failed, timed out.
    fn notify_in(&self, pool: &'static Pool, options: &OpcShutdownNotifyOptions) -> (HRESULT, u32, u32, u32) {
        // SAFETY: a live container of ours.
        let obj = unsafe { from_container(self.0) }.unwrap();
        // SAFETY: the options are valid; the reason is a NUL string.
        let bounds = unsafe { super::bounded::read_notify_options(options) }.unwrap();
        // SAFETY: a NUL-terminated reason.
        let c = unsafe { obj.notify_bounded_in(pool, w("").as_ptr(), bounds) };
        let hr = if c.failed == 0 && c.timed_out == 0 {
            S_OK
        } else {
            S_FALSE
        };
        (hr, c.notified, c.failed, c.timed_out)
    }
    /// For each advised sink, whether a bounded notification's call to it has not ended yet.
    fn calling(&self) -> Vec<bool> {
        // SAFETY: a live container of ours.
        let obj = unsafe { from_container(self.0) }.unwrap();
        obj.snapshot().iter().map(|(_, advised)| advised.is_calling()).collect()
    }
}

/// A client hung in ShutdownRequest is called once, however often the server notifies: while that
/// call has not returned, each notification counts it as timed out without calling it (and so
/// without another thread), and still calls the healthy sink. Once the call returns, the next
/// notification calls it again.
#[test]
fn a_sink_whose_call_has_not_returned_is_not_called_again() {
    let server = Server::with_limit(Some(2));
    let point = server.point();
    let gate = Gate::default();
    let hung = hung_sink(&gate);
    let (healthy, _) = healthy_sink();
    for s in [&hung, &healthy] {
        assert_eq!(point.advise(s.unk()).0, S_OK);
    }
    let options = bounds(20, 0);
    let rounds = if cfg!(miri) { 3 } else { 10 };
    for round in 0..rounds {
        // The healthy sink's last call has ended (answered in time it has; on a loaded machine, or
        // under Miri's clock, it may have missed the deadline and still be ending).
        wait_until(|| !server.calling()[1]);
        let (hr, notified, failed, timed_out) = server.notify_bounded(ptr::null(), &options);
        // The healthy sink answers at once; on a loaded machine it may still miss the 20 ms.
        assert_eq!((hr, failed), (S_FALSE, 0), "round {round}");
        assert!(timed_out >= 1 && notified + timed_out == 2, "round {round}");
        assert_eq!((hung.calls(), healthy.calls()), (1, round + 1), "round {round}");
    }
    gate.open();
    wait_until(|| server.calling() == [false, false]);
    assert_eq!(
        server.notify_bounded(ptr::null(), &bounds(OPC_SHUTDOWN_NO_TIMEOUT, 0)),
        (S_OK, 2, 0, 0)
    );
    assert_eq!((hung.calls(), healthy.calls()), (2, rounds + 1));
    drop(point);
    drop(server);
    wait_until(|| hung.refs() == 1 && healthy.refs() == 1);
}

/// With every worker of a pool held by a hung client, a pool of two threads still calls every other
/// sink: the notifying thread makes the call itself. The pool never has more than its two workers.
#[test]
fn hung_sinks_that_hold_every_worker_do_not_keep_a_healthy_sink_from_its_call() {
    static TWO: Pool = Pool::new(2);
    let gate = Gate::default();
    let (hung1, hung2) = (hung_sink(&gate), hung_sink(&gate));
    let (healthy, threads) = healthy_sink();
    let (first, second) = (Server::with_limit(Some(3)), Server::new());
    let (p1, p2) = (first.point(), second.point());
    for s in [&hung1, &hung2, &healthy] {
        assert_eq!(p1.advise(s.unk()).0, S_OK);
    }
    let (other, other_threads) = healthy_sink();
    assert_eq!(p2.advise(other.unk()).0, S_OK);
    let options = bounds(20, 0);
    // The two workers take the hung sinks; the healthy one is made by this thread once they are
    // past their deadline (so after it, and it may count as timed out).
    let (_, notified, failed, timed_out) = first.notify_in(&TWO, &options);
    assert!(failed == 0 && notified <= 1 && notified + timed_out == 3);
    assert_eq!((hung1.calls(), hung2.calls(), healthy.calls()), (1, 1, 1));
    // Again, and on another object: the hung sinks are not called again, the workers are still held
    // by them, the healthy sinks are made here at once.
    for _ in 0..3 {
        let (_, _, failed, timed_out) = first.notify_in(&TWO, &options);
        assert!(failed == 0 && timed_out >= 2);
        let (_, _, failed, _) = second.notify_in(&TWO, &options);
        assert_eq!(failed, 0);
    }
    assert_eq!(
        (hung1.calls(), hung2.calls(), healthy.calls(), other.calls()),
        (1, 1, 4, 3)
    );
    let me = std::thread::current().id();
    assert!(threads
        .lock()
        .unwrap()
        .iter()
        .chain(other_threads.lock().unwrap().iter())
        .all(|t| *t == me));
    assert_eq!(TWO.workers(), (2, 2));
    gate.open();
    wait_until(|| TWO.workers().1 == 0);
    drop((p1, p2, first, second));
    for s in [&hung1, &hung2, &healthy, &other] {
        assert_eq!(s.refs(), 1);
    }
}

/// When no worker thread can be had at all (here a pool of none, as when the system refuses to
/// create threads), every sink is still called, on the notifying thread, one after the other.
#[test]
fn without_worker_threads_the_notifying_thread_calls_every_sink() {
    static NONE: Pool = Pool::new(0);
    let server = Server::with_limit(Some(3));
    let point = server.point();
    let (good, threads) = healthy_sink();
    let bad = MockSink::new(true, E_FAIL);
    let (good2, threads2) = healthy_sink();
    for s in [&good, &bad, &good2] {
        assert_eq!(point.advise(s.unk()).0, S_OK);
    }
    let options = bounds(OPC_SHUTDOWN_NO_TIMEOUT, 0);
    assert_eq!(server.notify_in(&NONE, &options), (S_FALSE, 2, 1, 0));
    assert_eq!((good.calls(), bad.calls(), good2.calls()), (1, 1, 1));
    let me = std::thread::current().id();
    assert_eq!((threads.lock().unwrap()[0], threads2.lock().unwrap()[0]), (me, me));
    assert_eq!(NONE.workers(), (0, 0));
    drop(point);
    drop(server);
    for s in [&good, &bad, &good2] {
        assert_eq!(s.refs(), 1);
    }
}

/// A call waiting for a worker is not made when its sink is unadvised meanwhile (here by the sink
/// whose call holds the only worker), and is then in no count.
#[test]
fn a_sink_unadvised_while_its_call_waits_for_a_worker_is_not_called() {
    static ONE: Pool = Pool::new(1);
    let server = Arc::new(Server::with_limit(Some(2)));
    let point = server.point();
    let first = MockSink::new(true, S_OK);
    let second = MockSink::new(true, S_OK);
    assert_eq!(point.advise(first.unk()).0, S_OK);
    let (hr, cookie) = point.advise(second.unk());
    assert_eq!(hr, S_OK);
    let target = Arc::clone(&server);
    first.set_hook(move || {
        let p = target.point();
        assert_eq!(p.unadvise(cookie), S_OK);
    });
    let options = bounds(OPC_SHUTDOWN_NO_TIMEOUT, 0);
    assert_eq!(server.notify_in(&ONE, &options), (S_OK, 1, 0, 0));
    assert_eq!((first.calls(), second.calls()), (1, 0));
    first.set_hook(|| {});
    wait_until(|| ONE.workers().1 == 0);
    drop(point);
    drop(server);
    assert_eq!((first.refs(), second.refs()), (1, 1));
}

// ---------------------------------------------------------------------------------------------
// A server object that forwards to the shutdown object instead of aggregating it, naming itself as
// the connection point's container (`OpcShutdownOptions::container`).

use crate::com::interfaces::{IConnectionPointContainerVtbl, IUnknownVtbl};
use core::sync::atomic::{AtomicBool, AtomicPtr};

/// A server object written by hand, as a windows-rs or C++ server is: its own IUnknown (the identity)
/// and IConnectionPointContainer, whose FindConnectionPoint and EnumConnectionPoints pass the call on
/// to the shutdown object it keeps. Counts its references; releases the shutdown object when the last
/// one goes (its memory stays, owned by the test, so the test can look at it afterwards).
#[repr(C)]
struct Forwarding {
    unk: &'static IUnknownVtbl,
    cpc: &'static IConnectionPointContainerVtbl,
    refs: AtomicU32,
    destroyed: AtomicBool,
    /// The shutdown object's own IConnectionPointContainer (counted on the shutdown object).
    shutdown: AtomicPtr<IConnectionPointContainer>,
}

static FORWARDING_UNK: IUnknownVtbl = IUnknownVtbl {
    QueryInterface: fwd_qi,
    AddRef: fwd_add_ref,
    Release: fwd_release,
};

static FORWARDING_CPC: IConnectionPointContainerVtbl = IConnectionPointContainerVtbl {
    QueryInterface: fwd_cpc_qi,
    AddRef: fwd_cpc_add_ref,
    Release: fwd_cpc_release,
    EnumConnectionPoints: fwd_enum_points,
    FindConnectionPoint: fwd_find_point,
};

/// The server behind its IUnknown (the first field).
unsafe fn fwd(this: *mut IUnknown) -> &'static Forwarding {
    // SAFETY: only Forwarding objects present these vtables; the test keeps them alive.
    unsafe { &*(this as *const Forwarding) }
}

/// The server behind its IConnectionPointContainer (the second field).
unsafe fn fwd_of_cpc(this: *mut IConnectionPointContainer) -> &'static Forwarding {
    // SAFETY: as above; `cpc` sits one pointer after the start.
    unsafe { &*(this.cast::<u8>().sub(core::mem::offset_of!(Forwarding, cpc)) as *const Forwarding) }
}

unsafe extern "system" fn fwd_qi(this: *mut IUnknown, riid: REFIID, ppv: *mut *mut c_void) -> Hr {
    Crossed::from_c(|| {
        // SAFETY: the caller passes valid pointers.
        unsafe {
            let s = fwd(this);
            *ppv = ptr::null_mut();
            let found: *mut c_void = if *riid == IID_IUNKNOWN {
                this.cast()
            } else if *riid == IID_ICONNECTIONPOINTCONTAINER {
                // From `this`, whose provenance is the whole object's.
                this.cast::<u8>().add(core::mem::offset_of!(Forwarding, cpc)).cast()
            } else {
                return E_NOINTERFACE;
            };
            s.refs.fetch_add(1, Ordering::SeqCst);
            *ppv = found;
            S_OK
        }
    })
}

unsafe extern "system" fn fwd_add_ref(this: *mut IUnknown) -> Crossed<ULONG> {
    // SAFETY: as above.
    Crossed::from_c(|| unsafe { fwd(this) }.refs.fetch_add(1, Ordering::SeqCst) + 1)
}

unsafe extern "system" fn fwd_release(this: *mut IUnknown) -> Crossed<ULONG> {
    Crossed::from_c(|| {
        // SAFETY: as above.
        let s = unsafe { fwd(this) };
        let before = s.refs.fetch_sub(1, Ordering::SeqCst);
        assert!(before > 0, "Release without a reference");
        if before == 1 {
            // The server object's end: it lets go of the shutdown object.
            s.destroyed.store(true, Ordering::SeqCst);
            let shutdown = s.shutdown.swap(ptr::null_mut(), Ordering::SeqCst);
            if !shutdown.is_null() {
                // SAFETY: the reference the server kept.
                unsafe { release(shutdown.cast()) };
            }
        }
        before - 1
    })
}

unsafe extern "system" fn fwd_cpc_qi(this: *mut IConnectionPointContainer, riid: REFIID, ppv: *mut *mut c_void) -> Hr {
    // SAFETY: the IUnknown methods of every interface are the object's.
    unsafe { fwd_qi((fwd_of_cpc(this) as *const Forwarding).cast_mut().cast(), riid, ppv) }
}

unsafe extern "system" fn fwd_cpc_add_ref(this: *mut IConnectionPointContainer) -> Crossed<ULONG> {
    // SAFETY: as above.
    unsafe { fwd_add_ref((fwd_of_cpc(this) as *const Forwarding).cast_mut().cast()) }
}

unsafe extern "system" fn fwd_cpc_release(this: *mut IConnectionPointContainer) -> Crossed<ULONG> {
    // SAFETY: as above.
    unsafe { fwd_release((fwd_of_cpc(this) as *const Forwarding).cast_mut().cast()) }
}

unsafe extern "system" fn fwd_enum_points(
    this: *mut IConnectionPointContainer,
    pp: *mut *mut IEnumConnectionPoints,
) -> Hr {
    Crossed::from_c(|| {
        // SAFETY: the shutdown object is alive while the server is; the caller's pointer is passed on.
        unsafe {
            let shutdown = fwd_of_cpc(this).shutdown.load(Ordering::SeqCst);
            IConnectionPointContainer::EnumConnectionPoints(shutdown, pp)
        }
    })
}

unsafe extern "system" fn fwd_find_point(
    this: *mut IConnectionPointContainer,
    riid: REFIID,
    pp: *mut *mut IConnectionPoint,
) -> Hr {
    Crossed::from_c(|| {
        // SAFETY: as above.
        unsafe {
            let shutdown = fwd_of_cpc(this).shutdown.load(Ordering::SeqCst);
            IConnectionPointContainer::FindConnectionPoint(shutdown, riid, pp)
        }
    })
}

impl Forwarding {
    /// A server object with one reference (the test's); `create_shutdown` gives it its shutdown
    /// object (once the box has its place: the pointers handed out come from it).
    fn new() -> Box<Forwarding> {
        Box::new(Forwarding {
            unk: &FORWARDING_UNK,
            cpc: &FORWARDING_CPC,
            refs: AtomicU32::new(1),
            destroyed: AtomicBool::new(false),
            shutdown: AtomicPtr::new(ptr::null_mut()),
        })
    }
    /// Creates the shutdown object, which names this server as its container.
    fn create_shutdown(&self) {
        let options = OpcShutdownOptions {
            struct_size: core::mem::size_of::<OpcShutdownOptions>() as u32,
            advise_limit: 0,
            container: self.unk(),
        };
        let mut p: *mut c_void = ptr::null_mut();
        // SAFETY: valid arguments; the server outlives every reference to the connection point.
        let hr = unsafe { OpcShutdownCreateEx(&options, ptr::null_mut(), &IID_ICONNECTIONPOINTCONTAINER, &mut p) };
        assert_eq!(hr, S_OK);
        self.shutdown.store(p.cast(), Ordering::SeqCst);
    }
    fn unk(&self) -> *mut IUnknown {
        self as *const Forwarding as *mut IUnknown
    }
    fn refs(&self) -> u32 {
        self.refs.load(Ordering::SeqCst)
    }
}

/// QueryInterface(IID_IUnknown) on `p`, released at once: the object's identity.
fn identity(p: *mut IUnknown) -> *mut c_void {
    let mut id: *mut c_void = ptr::null_mut();
    // SAFETY: a live object.
    unsafe {
        assert_eq!(query_interface(p, &IID_IUNKNOWN, &mut id), S_OK);
        release(id.cast());
    }
    id
}

/// The connection point of a forwarding server names the server as its container (COM identity),
/// counts on it, and keeps it alive: a client holding only the point still gets the server back, and
/// the server (with the shutdown object) goes when the point is released.
#[test]
fn a_forwarding_server_is_the_container_of_its_connection_point() {
    let objects = crate::com::object::live_objects();
    let server = Forwarding::new();
    server.create_shutdown();
    assert_eq!(server.refs(), 1, "the shutdown object holds no reference to the server");
    // SAFETY: live objects; every reference obtained is released.
    unsafe {
        let mut p: *mut c_void = ptr::null_mut();
        assert_eq!(
            query_interface(server.unk(), &IID_ICONNECTIONPOINTCONTAINER, &mut p),
            S_OK
        );
        let cpc = p.cast::<IConnectionPointContainer>();
        let mut cp: *mut IConnectionPoint = ptr::null_mut();
        assert_eq!(
            IConnectionPointContainer::FindConnectionPoint(cpc, &IID_IOPCShutdown, &mut cp),
            S_OK
        );
        assert_eq!(server.refs(), 3, "the connection point counts on the server");

        let mut back: *mut IConnectionPointContainer = ptr::null_mut();
        assert_eq!(((*(*cp).lpVtbl).GetConnectionPointContainer)(cp, &mut back), S_OK);
        assert_eq!(back, cpc, "the server's own container");
        assert_eq!(identity(back.cast()), server.unk().cast());
        release(back.cast());

        // Enumerated connection points count on the server too.
        let mut points: *mut IEnumConnectionPoints = ptr::null_mut();
        assert_eq!(IConnectionPointContainer::EnumConnectionPoints(cpc, &mut points), S_OK);
        let (mut got, mut fetched): (*mut IConnectionPoint, ULONG) = (ptr::null_mut(), 0);
        assert_eq!(IEnumConnectionPoints::Next(points, 1, &mut got, &mut fetched), S_OK);
        assert_eq!((got, fetched), (cp, 1));
        release(got.cast());
        release(points.cast());
        assert_eq!(server.refs(), 3);

        // The helpers and the notifications take the server object.
        let sink = MockSink::new(true, S_OK);
        let mut cookie = 0;
        assert_eq!(OpcShutdownAdvise(server.unk(), sink.unk(), &mut cookie).get(), S_OK);
        let (mut n, mut f) = (99, 99);
        assert_eq!(
            OpcShutdownNotifyEx(server.unk(), w("Bye").as_ptr(), &mut n, &mut f).get(),
            S_OK
        );
        assert_eq!((n, f, sink.calls()), (1, 0, 1));

        // The client lets go of everything but the connection point: the server stays.
        release(cpc.cast());
        release(server.unk());
        assert_eq!(server.refs(), 1);
        assert!(!server.destroyed.load(Ordering::SeqCst));
        assert_eq!(((*(*cp).lpVtbl).GetConnectionPointContainer)(cp, &mut back), S_OK);
        assert_eq!(identity(back.cast()), server.unk().cast());
        release(back.cast());
        assert_eq!(sink.refs(), 2, "still advised");

        // The last reference to the point is the server's last: it goes, and the shutdown object
        // with it.
        release(cp.cast());
        assert!(server.destroyed.load(Ordering::SeqCst));
        assert_eq!(sink.refs(), 1);
        assert_eq!(crate::com::object::live_objects(), objects);
    }
}

/// The container's options: only without an outer object, every size of the struct, and a named
/// container that is no IConnectionPointContainer gets its failure passed on.
#[test]
fn a_named_container_is_checked() {
    let sink = MockSink::new(true, S_OK);
    let mut options = OpcShutdownOptions {
        struct_size: core::mem::size_of::<OpcShutdownOptions>() as u32,
        advise_limit: 0,
        container: sink.unk(),
    };
    let mut p: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
    // SAFETY: valid arguments throughout; every object made is released.
    unsafe {
        // With an outer object the container is the outer object: naming another is refused.
        let outer = MockSink::new(false, S_OK);
        assert_eq!(
            OpcShutdownCreateEx(&options, outer.unk(), &IID_IUNKNOWN, &mut p),
            E_INVALIDARG
        );
        assert!(p.is_null());
        assert_eq!(outer.refs(), 1);

        // Each version's size; nothing between.
        let ptr_size = core::mem::size_of::<*mut c_void>();
        assert_eq!(
            <super::server::OpcShutdownOptions as crate::com::options::SizedStruct>::SIZES,
            [4, 8, 8 + ptr_size]
        );
        for (size, want) in [
            (4, S_OK),
            (8, S_OK),
            (8 + ptr_size as u32, S_OK),
            (12 + ptr_size as u32, E_INVALIDARG),
        ] {
            options.struct_size = size;
            assert_eq!(
                OpcShutdownCreateEx(&options, ptr::null_mut(), &IID_IUNKNOWN, &mut p),
                want,
                "{size}"
            );
            if want == S_OK {
                release(p.cast());
            }
        }
        // 64-bit: 12 cuts the pointer in half.
        if ptr_size == 8 {
            options.struct_size = 12;
            assert_eq!(
                OpcShutdownCreateEx(&options, ptr::null_mut(), &IID_IUNKNOWN, &mut p),
                E_INVALIDARG
            );
        }

        // The sink as "container": it has no IConnectionPointContainer.
        options.struct_size = core::mem::size_of::<OpcShutdownOptions>() as u32;
        assert_eq!(
            OpcShutdownCreateEx(&options, ptr::null_mut(), &IID_ICONNECTIONPOINTCONTAINER, &mut p),
            S_OK
        );
        let server = Server(p.cast());
        let point = server.point();
        assert_eq!(sink.refs(), 2, "the point counts on the named container");
        let mut back = core::ptr::null_mut::<IConnectionPointContainer>().wrapping_byte_add(1);
        assert_eq!(
            ((*(*point.0).lpVtbl).GetConnectionPointContainer)(point.0, &mut back).get(),
            E_NOINTERFACE
        );
        assert!(back.is_null());
        drop(point);
        drop(server);
    }
    assert_eq!(sink.refs(), 1);
}
