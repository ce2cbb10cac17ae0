//! The bounded shutdown notification (`OpcShutdownNotifyBounded`): the advised sinks are called at
//! the same time on worker threads, and the server waits for the answers only until a deadline.
//!
//! A client that hangs in ShutdownRequest (or whose process hangs) cannot keep a server that is
//! shutting down waiting: its sink is counted as timed out and the server goes on. The call to it may
//! still return later, on its worker thread; that thread owns everything the call touches (a counted
//! reference to the sink, its own copy of the reason, the call's progress), never the shutdown object
//! or the caller's memory, so a late return finds all of it alive and then lets it go. While a worker
//! runs, `DllCanUnloadNow` says S_FALSE, so the DLL its code lives in stays loaded.
//!
//! **Threads.** The workers are one pool for the whole process, at most
//! [`OPC_SHUTDOWN_MAX_NOTIFY_THREADS`] threads, whatever the clients do: a worker takes the calls
//! waiting in the pool's queue, oldest first, and ends when none is left. A connection has at most one
//! call at a time: a sink whose earlier call is still waiting or under way is not called again (it
//! counts as timed out), so a hung client holds one thread however often the server notifies.
//!
//! **Healthy sinks are always called.** A notification returns only once each of its calls has been
//! made (and answered or passed its deadline). A call waiting while every worker is inside a call is
//! made by the notifying thread itself, one after the other, when all those calls are past their
//! deadlines (as many clients hung at once as there may be workers) or its own deadline has passed;
//! so is every call when no worker thread can be created. Hung clients can therefore hold every
//! worker but never keep another sink from being called; what they can then cost is the deadline, as
//! the notifying thread waits for the calls it makes itself.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use super::server::{Advised, OpcShutdown};
use crate::com::options::{read_sized, SizedStruct};
use crate::com::{HRESULT, WCHAR};

/// The most threads the library runs at the same time, in the whole process, to call sinks for
/// `OpcShutdownNotifyBounded` (every notification of every shutdown object together).
pub const OPC_SHUTDOWN_MAX_NOTIFY_THREADS: u32 = 64;

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
    /// The longest one sink is waited for, in milliseconds from the moment its call starts (usually
    /// all start together), within the whole deadline. 0 or OPC_SHUTDOWN_NO_TIMEOUT: only the whole.
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

/// What a bounded notification achieved: every sink advised when it started, and not unadvised
/// before its call, is in exactly one count.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct BoundedCounts {
    /// Sinks whose ShutdownRequest succeeded before their deadline.
    pub(crate) notified: u32,
    /// Sinks that could not be reached or whose ShutdownRequest failed before their deadline.
    pub(crate) failed: u32,
    /// Sinks that had not answered at their deadline (their call may still be under way), and sinks
    /// not called because an earlier call to them had not returned yet.
    pub(crate) timed_out: u32,
}

/// Worker threads alive, each calling a sink or about to take or leave the queue.
static WORKERS: AtomicUsize = AtomicUsize::new(0);

/// Whether a worker of a bounded notification is still running code of this library.
pub(crate) fn workers_running() -> usize {
    WORKERS.load(Ordering::Acquire)
}

/// The process's pool of workers, shared by every bounded notification.
static POOL: Pool = Pool::new(OPC_SHUTDOWN_MAX_NOTIFY_THREADS as usize);

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

/// Where one call stands.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Stage {
    /// Waiting for a thread.
    Queued,
    /// ShutdownRequest is under way.
    Running,
    /// Returned; true when the request was accepted (false: refused, or the sink could not be
    /// reached from the calling thread).
    Answered(bool),
    /// Not made: the sink was unadvised before the call could start.
    NotMade,
}

struct Progress {
    stage: Stage,
    /// When the notification stops waiting for this call: the whole deadline, and once the call has
    /// started the earlier of that and the sink's own.
    deadline: Option<Instant>,
    /// When the answer came.
    answered: Option<Instant>,
}

/// One call of ShutdownRequest and everything it needs, owned by whichever threads make or wait for
/// it: the sink (claimed for this call, see [`Advised::claim_call`]), a copy of the reason, the
/// progress. Never the shutdown object or the caller's memory.
struct Call {
    advised: Arc<Advised>,
    reason: Arc<[WCHAR]>,
    sink_timeout: Option<Duration>,
    /// Locked with the pool's lock held, or alone by the notification counting its calls.
    progress: Mutex<Progress>,
}

impl Call {
    fn progress(&self) -> MutexGuard<'_, Progress> {
        // Every update is a few plain stores: a panic cannot leave it half-written.
        self.progress.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn deadline(&self) -> Option<Instant> {
        self.progress().deadline
    }

    /// The call starts now: its own deadline begins.
    fn start(&self, now: Instant) {
        let mut p = self.progress();
        p.stage = Stage::Running;
        if let Some(own) = self.sink_timeout.and_then(|d| now.checked_add(d)) {
            p.deadline = Some(p.deadline.map_or(own, |whole| whole.min(own)));
        }
    }

    /// Calls ShutdownRequest on the current thread, unless the sink was unadvised meanwhile. No lock
    /// is held.
    fn make(&self) -> Stage {
        if !self.advised.is_connected() {
            return Stage::NotMade;
        }
        Stage::Answered(match self.advised.sink().get() {
            Ok(call) => {
                let p = call.as_ptr();
                // SAFETY: `p` is a counted IOPCShutdown pointer valid on this thread; `reason` is
                // NUL-terminated and owned by the call; no lock is held.
                let hr = unsafe { ((*(*p).lpVtbl).ShutdownRequest)(p, self.reason.as_ptr()) }.get();
                hr >= 0
            }
            Err(_) => false,
        })
    }

    /// Records the end of the call and gives the sink back to later notifications.
    fn finish(&self, stage: Stage, at: Instant) {
        let mut p = self.progress();
        p.stage = stage;
        p.answered = Some(at);
        drop(p);
        self.advised.end_call();
    }
}

/// A pool of worker threads making calls of bounded notifications, at most `max` at a time.
pub(crate) struct Pool {
    max: usize,
    state: Mutex<PoolState>,
    /// Signalled whenever a call changes stage or a worker ends.
    changed: Condvar,
}

struct PoolState {
    /// Calls waiting for a thread, oldest first.
    queue: VecDeque<Arc<Call>>,
    /// Calls the workers are making now.
    running: Vec<Arc<Call>>,
    /// Worker threads started (or being started) and not yet ended.
    workers: usize,
    /// The most workers there have been at once.
    #[cfg(test)]
    peak: usize,
}

impl Pool {
    pub(crate) const fn new(max: usize) -> Pool {
        Pool {
            max,
            state: Mutex::new(PoolState {
                queue: VecDeque::new(),
                running: Vec::new(),
                workers: 0,
                #[cfg(test)]
                peak: 0,
            }),
            changed: Condvar::new(),
        }
    }

    fn lock(&self) -> MutexGuard<'_, PoolState> {
        // No update of the state can panic half-way (they are pushes, removals and counts).
        self.state.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The most workers there have been at once, and how many there are now.
    #[cfg(test)]
    pub(crate) fn workers(&self) -> (usize, usize) {
        let state = self.lock();
        (state.peak, state.workers)
    }

    /// Starts a worker for each call waiting, as far as the bound allows. Returns with the lock held
    /// again; a worker that could not be created is not counted.
    fn grow(&'static self, mut state: MutexGuard<'static, PoolState>) -> MutexGuard<'static, PoolState> {
        let n = state.queue.len().min(self.max.saturating_sub(state.workers));
        if n == 0 {
            return state;
        }
        state.workers += n;
        #[cfg(test)]
        {
            state.peak = state.peak.max(state.workers);
        }
        drop(state);
        let mut failed = 0;
        for _ in 0..n {
            let count = WorkerCount::new();
            let spawned = std::thread::Builder::new()
                .name("opccomn shutdown notification".into())
                .spawn(move || self.work(count));
            // On failure the closure, and with it `count`, is gone already.
            failed += usize::from(spawned.is_err());
        }
        let mut state = self.lock();
        if failed > 0 {
            state.workers -= failed;
            self.changed.notify_all();
        }
        state
    }

    /// The body of a worker: takes the calls waiting, oldest first, until none is left. On Windows
    /// it calls from the multithreaded apartment (the sinks are fetched from the Global Interface
    /// Table for it) and lets go of each call, whose sink reference may be the last, inside it.
    fn work(&'static self, _count: WorkerCount) {
        #[cfg(windows)]
        // SAFETY: no preconditions; balanced by CoUninitialize below when it succeeds.
        let com = unsafe {
            windows_sys::Win32::System::Com::CoInitializeEx(
                core::ptr::null(),
                windows_sys::Win32::System::Com::COINIT_MULTITHREADED as u32,
            )
        } >= 0;
        loop {
            let call = {
                let mut state = self.lock();
                let Some(call) = state.queue.pop_front() else {
                    break;
                };
                call.start(Instant::now());
                state.running.push(call.clone());
                self.changed.notify_all();
                call
            };
            let stage = call.make();
            let at = Instant::now();
            {
                let mut state = self.lock();
                state.running.retain(|c| !Arc::ptr_eq(c, &call));
                call.finish(stage, at);
                self.changed.notify_all();
            }
            drop(call);
        }
        #[cfg(windows)]
        if com {
            // SAFETY: balances the successful CoInitializeEx above on this thread.
            unsafe { windows_sys::Win32::System::Com::CoUninitialize() };
        }
        // Last: until here a notification counts this thread against the bound.
        let mut state = self.lock();
        state.workers -= 1;
        self.changed.notify_all();
    }

    /// Whether a waiting call must be made by the notifying thread: no worker is there to take it
    /// (none could be created), or every worker is making a call (none is about to take one) and
    /// either the waiting call's deadline has passed or each of those calls has passed its own, all
    /// the bound allows being there: then no worker takes a call before one of them returns.
    fn caller_must_make(&self, state: &PoolState, waiting: &Call, now: Instant) -> bool {
        let late = |c: &Call| c.deadline().is_some_and(|d| d <= now);
        state.workers == 0
            || (state.running.len() >= state.workers
                && (late(waiting) || (state.workers >= self.max && state.running.iter().all(|c| late(c)))))
    }

    /// Makes `calls` (all `Queued`): queues them for the workers and waits until each has been made
    /// and has answered or passed its deadline. A call still waiting when no worker will take it in
    /// time (`caller_must_make`) is taken back and made on this thread.
    fn make_all(&'static self, calls: &[Arc<Call>]) {
        if calls.is_empty() {
            return;
        }
        let mut state = self.lock();
        state.queue.extend(calls.iter().cloned());
        loop {
            state = self.grow(state);
            let now = Instant::now();
            // What this notification still waits for, and until when at the latest before looking again.
            let (mut waiting, mut wake, mut first_queued) = (false, None::<Instant>, None);
            let mut wake_at = |d: Option<Instant>| {
                if let Some(d) = d.filter(|d| *d > now) {
                    wake = Some(wake.map_or(d, |w: Instant| w.min(d)));
                }
            };
            for call in calls {
                let p = call.progress();
                match p.stage {
                    Stage::Answered(_) | Stage::NotMade => {}
                    Stage::Running => {
                        if p.deadline.is_none_or(|d| d > now) {
                            waiting = true;
                            wake_at(p.deadline);
                        }
                    }
                    Stage::Queued => {
                        waiting = true;
                        wake_at(p.deadline);
                        first_queued = first_queued.or(Some(call));
                    }
                }
            }
            if !waiting {
                return;
            }
            if let Some(call) = first_queued {
                if self.caller_must_make(&state, call, now) {
                    state.queue.retain(|c| !Arc::ptr_eq(c, call));
                    call.start(now);
                    drop(state);
                    let stage = call.make();
                    let at = Instant::now();
                    state = self.lock();
                    call.finish(stage, at);
                    self.changed.notify_all();
                    continue;
                }
                if state.workers >= self.max {
                    // Look again when the workers' calls pass their deadlines.
                    for c in &state.running {
                        wake_at(c.deadline());
                    }
                }
            }
            state = match wake {
                None => self.changed.wait(state).unwrap_or_else(|p| p.into_inner()),
                Some(d) => match self.changed.wait_timeout(state, d - now) {
                    Ok((guard, _)) => guard,
                    Err(poisoned) => poisoned.into_inner().0,
                },
            };
        }
    }
}

impl OpcShutdown {
    /// Calls ShutdownRequest on every sink advised now through the process's pool of workers, and
    /// waits until each call has answered or passed its deadline. A sink whose earlier call has not
    /// returned is not called (it counts as timed out); a sink unadvised before its call starts is not
    /// called (and not counted).
    ///
    /// # Safety
    /// `reason` must point at a NUL-terminated UTF-16 string.
    pub(crate) unsafe fn notify_bounded(&self, reason: *const WCHAR, bounds: Bounds) -> BoundedCounts {
        // SAFETY: forwarded from the caller.
        unsafe { self.notify_bounded_in(&POOL, reason, bounds) }
    }

    /// As `notify_bounded`, through `pool`.
    ///
    /// # Safety
    /// As for `notify_bounded`.
    pub(crate) unsafe fn notify_bounded_in(
        &self,
        pool: &'static Pool,
        reason: *const WCHAR,
        bounds: Bounds,
    ) -> BoundedCounts {
        // SAFETY: NUL-terminated per the caller; the calls get their own copy.
        let reason: Arc<[WCHAR]> = unsafe { nul_terminated_copy(reason) };
        let whole = bounds.whole.and_then(|d| Instant::now().checked_add(d));
        let mut counts = BoundedCounts::default();
        let mut calls = Vec::new();
        for (_, advised) in self.snapshot() {
            if !advised.is_connected() {
                continue;
            }
            if !advised.claim_call() {
                // Its earlier call has not returned: that client is not called twice.
                counts.timed_out += 1;
                continue;
            }
            calls.push(Arc::new(Call {
                advised,
                reason: reason.clone(),
                sink_timeout: bounds.sink,
                progress: Mutex::new(Progress {
                    stage: Stage::Queued,
                    deadline: whole,
                    answered: None,
                }),
            }));
        }
        pool.make_all(&calls);
        for call in &calls {
            let p = call.progress();
            let in_time = match (p.answered, p.deadline) {
                (Some(at), Some(deadline)) => at <= deadline,
                (answered, None) => answered.is_some(),
                (None, Some(_)) => false,
            };
            match p.stage {
                Stage::NotMade => {}
                Stage::Answered(true) if in_time => counts.notified += 1,
                Stage::Answered(false) if in_time => counts.failed += 1,
                _ => counts.timed_out += 1,
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
