//! A thread stress test over the shared objects, meant for ThreadSanitizer (`scripts/test.sh` builds
//! it with `-Zsanitizer=thread` and an instrumented standard library) and run by every `cargo test`
//! and under Miri with fewer rounds.
//!
//! Eight threads at once use one IOPCCommon session, one shutdown object whose sinks unadvise
//! themselves from inside the notification, and one compiled pattern, all through the C entry points
//! and vtables as C callers use them.

use core::ffi::c_void;
use core::ptr;
use core::sync::atomic::{AtomicU32, AtomicUsize, Ordering};
use std::sync::Arc;

use crate::com::iids::{IID_IOPCCommon, IID_ICONNECTIONPOINTCONTAINER, IID_IUNKNOWN};
use crate::com::unknown::{add_ref, query_interface, release};
use crate::com::{IUnknown, DWORD, HRESULT, LPCWSTR, S_OK, ULONG, WCHAR};
use crate::common::{IOPCCommon, OpcCommonCreate, OpcCommonGetClientName};
use crate::pattern::{OpcPattern, OpcPatternCompileW, OpcPatternFree, OpcPatternMatchW};
use crate::shutdown::client::{OpcShutdownAdvise, OpcShutdownSinkCreate, OpcShutdownUnadvise};
use crate::shutdown::server::OpcShutdownOptions;
use crate::shutdown::{OpcShutdownCreateEx, OpcShutdownNotifyEx};

const THREADS: usize = 8;
/// Rounds per thread: enough for ThreadSanitizer to see every interleaving the design allows, few
/// enough under Miri (which runs threads one step at a time).
const ROUNDS: usize = if cfg!(miri) { 3 } else { 200 };

fn w(s: &str) -> Vec<WCHAR> {
    s.encode_utf16().chain(Some(0)).collect()
}

/// A pointer to a free-threaded object, shared by the threads.
struct Shared<T>(*mut T);
impl<T> Clone for Shared<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Shared<T> {}
// SAFETY: every object shared this way is free-threaded (or, for the pattern, immutable).
unsafe impl<T> Send for Shared<T> {}
// SAFETY: as above.
unsafe impl<T> Sync for Shared<T> {}
impl<T> Shared<T> {
    fn get(self) -> *mut T {
        self.0
    }
}

/// What one client sink knows; lives until the end of the test (after every sink is destroyed).
struct SinkState {
    server: Shared<IUnknown>,
    cookie: AtomicU32,
    calls: AtomicU32,
    unadvised: AtomicU32,
}

/// The sink callback: unadvises its own connection from inside the notification.
unsafe extern "C" fn unadvise_self(context: *mut c_void, reason: LPCWSTR) {
    // SAFETY: the context is a SinkState that outlives the sink; the reason is NUL-terminated.
    let state = unsafe { &*(context as *const SinkState) };
    assert!(!reason.is_null());
    state.calls.fetch_add(1, Ordering::SeqCst);
    let cookie = state.cookie.load(Ordering::SeqCst);
    // SAFETY: the server outlives every notification.
    if cookie != 0 && unsafe { OpcShutdownUnadvise(state.server.get(), cookie) } == S_OK {
        state.unadvised.fetch_add(1, Ordering::SeqCst);
    }
}

fn notify(server: *mut IUnknown) -> (HRESULT, ULONG) {
    let (mut notified, mut failed) = (0, 0);
    let reason = w("stress");
    // SAFETY: a live shutdown object; valid out-parameters.
    let hr = unsafe { OpcShutdownNotifyEx(server, reason.as_ptr(), &mut notified, &mut failed) };
    assert_eq!(failed, 0);
    (hr.get(), notified)
}

#[test]
fn eight_threads_share_a_session_a_shutdown_object_and_a_pattern() {
    // SAFETY: (the whole test) every pointer is created here and released at the end, after the
    // threads are joined; out-parameters are locals.
    unsafe {
        let mut p: *mut c_void = ptr::null_mut();
        assert_eq!(
            OpcCommonCreate(ptr::null(), ptr::null_mut(), &IID_IOPCCommon, &mut p),
            S_OK
        );
        let common = Shared(p.cast::<IOPCCommon>());

        let options = OpcShutdownOptions {
            struct_size: core::mem::size_of::<OpcShutdownOptions>() as u32,
            advise_limit: 1000,
            container: ptr::null_mut(),
        };
        let mut p: *mut c_void = ptr::null_mut();
        assert_eq!(
            OpcShutdownCreateEx(&options, ptr::null_mut(), &IID_ICONNECTIONPOINTCONTAINER, &mut p),
            S_OK
        );
        let server = Shared(p.cast::<IUnknown>());

        let mut pattern: *mut OpcPattern = ptr::null_mut();
        assert_eq!(
            OpcPatternCompileW(w("Channel?.Device[1-3].*").as_ptr(), 1, &mut pattern),
            S_OK
        );
        let pattern = Shared(pattern);
        let names: Vec<(Vec<WCHAR>, bool)> = (0..40)
            .map(|i| {
                let name = format!("Channel{}.Device{}.Tag{i}", i % 3, i % 5);
                let hit = (1..=3).contains(&(i % 5));
                (w(&name), hit)
            })
            .collect();
        let names = Arc::new(names);

        let sinks: Arc<std::sync::Mutex<Vec<Arc<SinkState>>>> = Arc::default();
        let advised = Arc::new(AtomicUsize::new(0));
        let threads: Vec<_> = (0..THREADS)
            .map(|t| {
                let (names, sinks, advised) = (names.clone(), sinks.clone(), advised.clone());
                std::thread::spawn(move || {
                    let (common, server, pattern) = (common.get(), server.get(), pattern.get());
                    let v = &*(*common).lpVtbl;
                    let my_name = w(&format!("client {t}"));
                    for round in 0..ROUNDS {
                        // IOPCCommon: locale, client name, error texts, identity, counting.
                        let lcid = if (round + t) % 2 == 0 { 0x0409 } else { 0x0407 };
                        assert_eq!((v.SetLocaleID)(common, lcid), S_OK);
                        let mut got = 0;
                        assert_eq!((v.GetLocaleID)(common, &mut got), S_OK);
                        assert!(got == 0x0409 || got == 0x0407);
                        let mut text = ptr::null_mut();
                        assert_eq!((v.GetErrorString)(common, 0xC0040001_u32 as HRESULT, &mut text), S_OK);
                        crate::com::alloc::task_free(text.cast());
                        assert_eq!((v.SetClientName)(common, my_name.as_ptr()), S_OK);
                        let mut name = ptr::null_mut();
                        assert_eq!(OpcCommonGetClientName(common.cast(), &mut name), S_OK);
                        crate::com::alloc::task_free(name.cast());
                        let mut unk = ptr::null_mut();
                        assert_eq!((v.QueryInterface)(common, &IID_IUNKNOWN, &mut unk), S_OK);
                        add_ref(unk.cast());
                        release(unk.cast());
                        release(unk.cast());

                        // Shutdown: a new sink that unadvises itself when notified.
                        let state = Arc::new(SinkState {
                            server: Shared(server),
                            cookie: AtomicU32::new(0),
                            calls: AtomicU32::new(0),
                            unadvised: AtomicU32::new(0),
                        });
                        sinks.lock().unwrap().push(state.clone());
                        let mut sink: *mut c_void = ptr::null_mut();
                        let context = Arc::as_ptr(&state) as *mut c_void;
                        assert_eq!(
                            OpcShutdownSinkCreate(Some(unadvise_self), context, &IID_IUNKNOWN, &mut sink),
                            S_OK
                        );
                        let mut cookie: DWORD = 0;
                        assert_eq!(OpcShutdownAdvise(server, sink.cast(), &mut cookie), S_OK);
                        advised.fetch_add(1, Ordering::SeqCst);
                        state.cookie.store(cookie, Ordering::SeqCst);
                        release(sink.cast());
                        let (hr, _) = notify(server);
                        assert_eq!(hr, S_OK);

                        // The compiled pattern, shared read-only.
                        for (name, hit) in names.iter() {
                            assert_eq!(OpcPatternMatchW(pattern, name.as_ptr()) != 0, *hit);
                        }
                    }
                })
            })
            .collect();
        for th in threads {
            th.join().unwrap();
        }

        // A sink notified before its cookie was stored is still advised: notify until none is left.
        let mut rounds = 0;
        while notify(server.get()).1 != 0 {
            rounds += 1;
            assert!(rounds < 10, "sinks keep their connections");
        }
        let sinks = sinks.lock().unwrap();
        assert_eq!(sinks.len(), THREADS * ROUNDS);
        assert_eq!(advised.load(Ordering::SeqCst), THREADS * ROUNDS);
        for s in sinks.iter() {
            assert!(s.calls.load(Ordering::SeqCst) >= 1, "every sink was notified");
            assert_eq!(
                s.unadvised.load(Ordering::SeqCst),
                1,
                "and unadvised itself exactly once"
            );
        }
        let mut found = ptr::null_mut();
        assert_eq!(query_interface(server.get(), &IID_IUNKNOWN, &mut found), S_OK);
        release(found.cast());

        OpcPatternFree(pattern.get());
        assert_eq!(release(server.get()), 0);
        assert_eq!(((*(*common.get()).lpVtbl).Release)(common.get()), 0);
    }
}
