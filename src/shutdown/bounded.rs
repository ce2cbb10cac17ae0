//! The bounded shutdown notification (`OpcShutdownNotifyBounded`): every advised sink is called on a
//! thread of its own, at the same time, and the server waits for the answers only until a deadline.
//!
//! A client that hangs in ShutdownRequest (or whose process hangs) cannot keep a server that is
//! shutting down waiting: its sink is counted as timed out and the server goes on. The call to it may
//! still return later, on its worker thread; that worker owns everything it touches (a counted
//! reference to the sink, its own copy of the reason, the shared slot for its outcome), never the
//! shutdown object or the caller's memory, so a late return finds all of it alive and then lets it go.
//! While a worker runs, `DllCanUnloadNow` says S_FALSE, so the DLL its code lives in stays loaded.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use super::apartment::SinkRef;
use super::server::OpcShutdown;
use crate::com::options::{read_sized, SizedStruct};
use crate::com::{HRESULT, WCHAR};

/// A timeout that never ends: the notification waits for the answer however long it takes.
pub const OPC_SHUTDOWN_NO_TIMEOUT: u32 = 0xFFFF_FFFF;

/// The whole notification's deadline when the caller sets none (`timeout_ms` 0), in milliseconds.
pub const OPC_SHUTDOWN_DEFAULT_TIMEOUT_MS: u32 = 5000;

/// How long `OpcShutdownNotifyBounded` waits for the clients. Zero-initialise it, set `struct_size` to
/// `sizeof(OpcShutdownNotifyOptions)`, then set what you need; NULL gives the defaults.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct OpcShutdownNotifyOptions {
    /// `sizeof(OpcShutdownNotifyOptions)` as the caller's header declares it.
    pub struct_size: u32,
    /// The deadline of the whole notification, in milliseconds from the call: when it passes, the
    /// call returns and every sink that has not answered counts as timed out. 0 means
    /// OPC_SHUTDOWN_DEFAULT_TIMEOUT_MS; OPC_SHUTDOWN_NO_TIMEOUT waits for every answer.
    pub timeout_ms: u32,
    /// The longest one sink is waited for, in milliseconds from the moment its call starts (all
    /// start together), within the whole deadline. 0 or OPC_SHUTDOWN_NO_TIMEOUT: only the whole.
    pub sink_timeout_ms: u32,
}

// SAFETY: repr(C), struct_size first, integers only.
unsafe impl SizedStruct for OpcShutdownNotifyOptions {
    /// One version so far.
    const SIZES: &'static [usize] = &[core::mem::size_of::<OpcShutdownNotifyOptions>()];
}

/// The deadlines of one notification; `None` waits without limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Bounds {
    pub(crate) whole: Option<Duration>,
    pub(crate) sink: Option<Duration>,
}

fn millis(ms: u32) -> Option<Duration> {
    (ms != OPC_SHUTDOWN_NO_TIMEOUT).then(|| Duration::from_millis(u64::from(ms)))
}

/// Reads the caller's options, honouring `struct_size`.
///
/// # Safety
/// `options` must be NULL or point at `struct_size` readable bytes laid out as OpcShutdownNotifyOptions.
pub(crate) unsafe fn read_notify_options(options: *const OpcShutdownNotifyOptions) -> Result<Bounds, HRESULT> {
    let defaults = OpcShutdownNotifyOptions {
        struct_size: 0,
        timeout_ms: 0,
        sink_timeout_ms: 0,
    };
    // SAFETY: OpcShutdownNotifyOptions is repr(C), starts with struct_size and holds only integers;
    // the caller vouches for `options`.
    let o = unsafe { read_sized(options, defaults) }?;
    let whole = if o.timeout_ms == 0 {
        OPC_SHUTDOWN_DEFAULT_TIMEOUT_MS
    } else {
        o.timeout_ms
    };
    Ok(Bounds {
        whole: millis(whole),
        sink: if o.sink_timeout_ms == 0 {
            None
        } else {
            millis(o.sink_timeout_ms)
        },
    })
}

/// What a bounded notification achieved: every sink called is in exactly one count.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct BoundedCounts {
    /// Sinks whose ShutdownRequest succeeded before their deadline.
    pub(crate) notified: u32,
    /// Sinks that could not be reached or whose ShutdownRequest failed before their deadline.
    pub(crate) failed: u32,
    /// Sinks that had not answered at their deadline (their call may still be under way).
    pub(crate) timed_out: u32,
}

/// Worker threads alive, each still calling (or about to release) a sink.
static WORKERS: AtomicUsize = AtomicUsize::new(0);

/// Whether a worker of a bounded notification is still running code of this library.
pub(crate) fn workers_running() -> usize {
    WORKERS.load(Ordering::Acquire)
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Outcome {
    Pending,
    Notified,
    Failed,
}

/// The outcomes of one notification, one per sink, shared by the caller and the workers.
struct Outcomes {
    list: Mutex<Vec<Outcome>>,
    changed: Condvar,
}

impl Outcomes {
    fn lock(&self) -> MutexGuard<'_, Vec<Outcome>> {
        // Every update is a single store: a panic cannot leave the list half-written.
        self.list.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn set(&self, i: usize, outcome: Outcome) {
        self.lock()[i] = outcome;
        self.changed.notify_all();
    }
}

/// Counts a worker from before its thread starts until it has let go of everything.
struct WorkerCount;

impl WorkerCount {
    fn new() -> WorkerCount {
        WORKERS.fetch_add(1, Ordering::AcqRel);
        WorkerCount
    }
}

impl Drop for WorkerCount {
    fn drop(&mut self) {
        WORKERS.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Calls ShutdownRequest on `sink` on the current (worker) thread: true when it succeeded.
fn call(sink: &SinkRef, reason: &[WCHAR]) -> bool {
    match sink.get() {
        Ok(call) => {
            let p = call.as_ptr();
            // SAFETY: `p` is a counted IOPCShutdown pointer valid on this thread; `reason` is
            // NUL-terminated and owned by the worker; no lock is held.
            let hr = unsafe { ((*(*p).lpVtbl).ShutdownRequest)(p, reason.as_ptr()) }.get();
            hr >= 0
        }
        Err(_) => false,
    }
}

/// The body of one worker: calls the sink in the multithreaded apartment (on Windows, so the sink can
/// be fetched from the Global Interface Table), records the outcome and lets go of the sink before
/// leaving the apartment.
fn work(sink: Arc<SinkRef>, reason: Arc<[WCHAR]>, outcomes: Arc<Outcomes>, i: usize, _count: WorkerCount) {
    #[cfg(windows)]
    // SAFETY: no preconditions; balanced by CoUninitialize below when it succeeds.
    let com = unsafe {
        windows_sys::Win32::System::Com::CoInitializeEx(
            core::ptr::null(),
            windows_sys::Win32::System::Com::COINIT_MULTITHREADED as u32,
        )
    } >= 0;
    let ok = call(&sink, &reason);
    outcomes.set(i, if ok { Outcome::Notified } else { Outcome::Failed });
    // The last reference to a sink unadvised meanwhile revokes its GIT entry: inside the apartment.
    drop(sink);
    #[cfg(windows)]
    if com {
        // SAFETY: balances the successful CoInitializeEx above on this thread.
        unsafe { windows_sys::Win32::System::Com::CoUninitialize() };
    }
}

impl OpcShutdown {
    /// Calls ShutdownRequest on every sink advised now, each on its own worker thread, and waits
    /// until each has answered or passed its deadline. A sink unadvised before its worker starts is
    /// not called.
    ///
    /// # Safety
    /// `reason` must point at a NUL-terminated UTF-16 string.
    pub(crate) unsafe fn notify_bounded(&self, reason: *const WCHAR, bounds: Bounds) -> BoundedCounts {
        // SAFETY: NUL-terminated per the caller; the workers get their own copy.
        let reason: Arc<[WCHAR]> = unsafe { nul_terminated_copy(reason) };
        let start = Instant::now();
        let whole_deadline = bounds.whole.and_then(|d| start.checked_add(d));
        let sinks = self.snapshot();
        let outcomes = Arc::new(Outcomes {
            list: Mutex::new(vec![Outcome::Pending; sinks.len()]),
            changed: Condvar::new(),
        });
        // Per sink: its deadline (None: none), or no entry when it was not called.
        let mut deadlines: Vec<Option<Option<Instant>>> = Vec::with_capacity(sinks.len());
        for (i, (cookie, sink)) in sinks.into_iter().enumerate() {
            if !self.is_connected(cookie) {
                deadlines.push(None);
                continue;
            }
            let started = Instant::now();
            let own = bounds.sink.and_then(|d| started.checked_add(d));
            let deadline = match (own, whole_deadline) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            };
            deadlines.push(Some(deadline));
            let (reason, shared, count) = (reason.clone(), outcomes.clone(), WorkerCount::new());
            let spawned = std::thread::Builder::new()
                .name("opccomn shutdown notification".into())
                .spawn(move || work(sink, reason, shared, i, count));
            if spawned.is_err() {
                // No thread for this sink (the closure, with its references, is gone already).
                outcomes.set(i, Outcome::Failed);
            }
        }
        self.wait(&outcomes, &deadlines)
    }

    /// Waits for the outcomes until each is known or past its deadline, then counts them. A sink
    /// still pending at its deadline counts as timed out even when its answer comes in later.
    fn wait(&self, outcomes: &Outcomes, deadlines: &[Option<Option<Instant>>]) -> BoundedCounts {
        let mut late = vec![false; deadlines.len()];
        let mut list = outcomes.lock();
        loop {
            let now = Instant::now();
            // How long to wait for the next change: None when nothing is waited for any more,
            // Some(None) when a sink without deadline is pending.
            let mut next: Option<Option<Instant>> = None;
            for (i, deadline) in deadlines.iter().enumerate() {
                if list[i] != Outcome::Pending || late[i] {
                    continue;
                }
                match deadline {
                    None => {}
                    Some(None) => next = Some(None),
                    Some(Some(d)) if *d <= now => late[i] = true,
                    Some(Some(d)) => {
                        next = match next {
                            Some(None) => Some(None),
                            Some(Some(e)) => Some(Some(e.min(*d))),
                            None => Some(Some(*d)),
                        }
                    }
                }
            }
            list = match next {
                None => break,
                Some(None) => outcomes.changed.wait(list).unwrap_or_else(|p| p.into_inner()),
                Some(Some(d)) => match outcomes.changed.wait_timeout(list, d - now) {
                    Ok((guard, _)) => guard,
                    Err(poisoned) => poisoned.into_inner().0,
                },
            };
        }
        let mut counts = BoundedCounts::default();
        for (i, deadline) in deadlines.iter().enumerate() {
            match (deadline, list[i]) {
                (None, _) => {}
                _ if late[i] => counts.timed_out += 1,
                (_, Outcome::Notified) => counts.notified += 1,
                (_, Outcome::Failed) => counts.failed += 1,
                (_, Outcome::Pending) => counts.timed_out += 1,
            }
        }
        counts
    }
}

/// A copy of a NUL-terminated UTF-16 string, NUL included.
///
/// # Safety
/// `s` must point at a NUL-terminated UTF-16 string.
unsafe fn nul_terminated_copy(s: *const WCHAR) -> Arc<[WCHAR]> {
    let mut n = 0;
    // SAFETY: the string is NUL-terminated per the caller, so every unit up to the NUL is readable.
    while unsafe { *s.add(n) } != 0 {
        n += 1;
    }
    // SAFETY: `n + 1` units are readable (the string and its NUL).
    Arc::from(unsafe { core::slice::from_raw_parts(s, n + 1) })
}
