//! What the last scan of the registry found, kept until the registry changes: the server list's
//! answers come from it.
//!
//! A scan of `CLSID` in both registry views costs hundreds of registry calls (under Wine each a round
//! trip to wineserver), and a browser answers many clients: [`Snapshots`] keeps the last scan as an
//! immutable value behind an `Arc`, which any number of callers read at once, and a [`ChangeWatch`]
//! says when the registry may have changed since. It is never stale:
//!
//! - every call asks the watch first, synchronously: a change made before the call began has
//!   signalled it (on Windows the registry signals a notification's event in the same operation as
//!   the change), so the call scans again;
//! - the watch is armed *before* the scan it guards, so a change while the scan runs signals the
//!   watch and the next call scans again, even if this scan missed it;
//! - a scan is kept only when its arm succeeded and no other arm happened meanwhile; when arming
//!   fails, every call scans (and tries to arm again), none fails for it.
//!
//! Arming and keeping a scan happen under the write side of one lock, the check of a kept scan under
//! its read side: a caller never sees a scan together with a watch armed after it. Callers that find
//! the registry changed scan one at a time (the others then take what the first found), but never
//! while holding the lock that readers of a current scan take.

use std::sync::{Arc, Mutex, RwLock};

use crate::com::HRESULT;

/// What tells the cache that the registry may have changed.
pub(crate) trait ChangeWatch: Send + Sync {
    /// Starts (or keeps) watching: from its return until the next call, [`ChangeWatch::changed`] is
    /// true after any change of what the server list reads. Parts of the watch that have not seen a
    /// change since they were armed may stay as they are. An error means the watch cannot be relied
    /// on until a later arm succeeds.
    fn arm(&self) -> Result<(), HRESULT>;
    /// True when the registry may have changed since the last successful arm (also when that cannot
    /// be known). Must not block.
    fn changed(&self) -> bool;
}

impl<W: ChangeWatch> ChangeWatch for Arc<W> {
    fn arm(&self) -> Result<(), HRESULT> {
        (**self).arm()
    }

    fn changed(&self) -> bool {
        (**self).changed()
    }
}

struct State<T: ?Sized> {
    /// The scan made after the last arm, when that arm succeeded and no change has been seen since.
    current: Option<Arc<T>>,
    /// Counts the arms: a scan is kept only if no other arm came between its own and its end.
    arms: u64,
}

/// The last scan and the watch that says whether it still holds.
pub(crate) struct Snapshots<T: ?Sized> {
    watch: Box<dyn ChangeWatch>,
    state: RwLock<State<T>>,
    /// Held by the caller that scans after a change, so that callers arriving meanwhile wait for its
    /// scan rather than make their own. Not held while scanning when the arm failed.
    rescan: Mutex<()>,
}

impl<T: ?Sized> Snapshots<T> {
    pub(crate) fn new(watch: Box<dyn ChangeWatch>) -> Snapshots<T> {
        Snapshots {
            watch,
            state: RwLock::new(State { current: None, arms: 0 }),
            rescan: Mutex::new(()),
        }
    }

    /// The kept scan, if there is one and the registry has not changed since its arm.
    fn current(&self) -> Option<Arc<T>> {
        let state = self.state.read().unwrap_or_else(|p| p.into_inner());
        // Asked under the read lock: no arm (which takes the write lock) can come between the check
        // and the scan it vouches for.
        state.current.clone().filter(|_| !self.watch.changed())
    }

    /// A scan that holds the registry as it was when this call began (or later): the kept one when
    /// nothing changed since, else a new one from `scan`.
    pub(crate) fn get(&self, scan: impl FnOnce() -> Arc<T>) -> Arc<T> {
        if let Some(current) = self.current() {
            return current;
        }
        let guard = self.rescan.lock().unwrap_or_else(|p| p.into_inner());
        // Another caller may have scanned while this one waited: its scan began after its arm, and
        // no change since that arm means none since this call began either.
        if let Some(current) = self.current() {
            return current;
        }
        let (armed, arm) = {
            let mut state = self.state.write().unwrap_or_else(|p| p.into_inner());
            state.current = None;
            state.arms += 1;
            (self.watch.arm().is_ok(), state.arms)
        };
        if !armed {
            // Nothing to keep: every call scans, at the same time as the others.
            drop(guard);
            return scan();
        }
        let fresh = scan();
        let mut state = self.state.write().unwrap_or_else(|p| p.into_inner());
        if state.arms == arm {
            state.current = Some(fresh.clone());
        }
        fresh
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering::SeqCst};

    /// A watch the test drives: `signal` is a change, `fail` makes arming fail.
    #[derive(Default)]
    pub(crate) struct TestWatch {
        pub(crate) signalled: AtomicBool,
        pub(crate) fail: AtomicBool,
        pub(crate) arms: AtomicUsize,
        /// Callers inside `changed` now, and the most there were at once.
        pub(crate) checking: AtomicUsize,
        pub(crate) most_checking: AtomicUsize,
        /// How many callers `changed` waits for (a second at most) before it answers.
        pub(crate) gather: AtomicUsize,
    }

    impl TestWatch {
        pub(crate) fn signal(&self) {
            self.signalled.store(true, SeqCst);
        }
    }

    impl ChangeWatch for TestWatch {
        fn arm(&self) -> Result<(), HRESULT> {
            self.arms.fetch_add(1, SeqCst);
            if self.fail.load(SeqCst) {
                return Err(crate::com::E_FAIL);
            }
            self.signalled.store(false, SeqCst);
            Ok(())
        }

        fn changed(&self) -> bool {
            let now = self.checking.fetch_add(1, SeqCst) + 1;
            self.most_checking.fetch_max(now, SeqCst);
            // (Bounded: a cache that let one caller at a time in makes this wait end unmet, and
            // the test then fails on `most_checking`, without hanging.)
            for _ in 0..1000 {
                if self.checking.load(SeqCst) >= self.gather.load(SeqCst) {
                    break;
                }
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
            self.most_checking.fetch_max(self.checking.load(SeqCst), SeqCst);
            self.checking.fetch_sub(1, SeqCst);
            self.signalled.load(SeqCst)
        }
    }

    /// A scan that found `n`.
    fn scan_of(n: u32) -> Arc<u32> {
        Arc::new(n)
    }

    fn first(s: &u32) -> u32 {
        *s
    }

    #[test]
    fn a_scan_is_kept_until_the_watch_sees_a_change() {
        let watch = Arc::new(TestWatch::default());
        let cache = Snapshots::new(Box::new(watch.clone()));
        let scans = AtomicUsize::new(0);
        let scan = |n| {
            scans.fetch_add(1, SeqCst);
            scan_of(n)
        };
        assert_eq!(first(&cache.get(|| scan(1))), 1);
        assert_eq!(first(&cache.get(|| scan(2))), 1, "served from the kept scan");
        assert_eq!(scans.load(SeqCst), 1);
        watch.signal();
        assert_eq!(first(&cache.get(|| scan(3))), 3, "a change makes the next call scan");
        assert_eq!(first(&cache.get(|| scan(4))), 3);
        assert_eq!((scans.load(SeqCst), watch.arms.load(SeqCst)), (2, 2));
    }

    #[test]
    fn a_change_during_the_scan_is_not_lost() {
        let watch = Arc::new(TestWatch::default());
        let cache = Snapshots::new(Box::new(watch.clone()));
        // The registry changes while the scan runs, after it read the part that changed: the watch,
        // armed before the scan, has seen it.
        let s = cache.get(|| {
            let s = scan_of(1);
            watch.signal();
            s
        });
        assert_eq!(first(&s), 1);
        assert_eq!(first(&cache.get(|| scan_of(2))), 2, "scanned again");
        assert_eq!(first(&cache.get(|| scan_of(3))), 2);
    }

    #[test]
    fn when_arming_fails_every_call_scans() {
        let watch = Arc::new(TestWatch::default());
        watch.fail.store(true, SeqCst);
        let cache = Snapshots::new(Box::new(watch.clone()));
        for n in 1..=3 {
            assert_eq!(first(&cache.get(|| scan_of(n))), n);
        }
        assert_eq!(watch.arms.load(SeqCst), 3, "each call tries to arm again");
        // A kept scan, then an arm that fails: the kept scan is not served again.
        watch.fail.store(false, SeqCst);
        assert_eq!(first(&cache.get(|| scan_of(4))), 4);
        assert_eq!(first(&cache.get(|| scan_of(5))), 4);
        watch.fail.store(true, SeqCst);
        watch.signal();
        assert_eq!(first(&cache.get(|| scan_of(6))), 6);
        assert_eq!(first(&cache.get(|| scan_of(7))), 7);
        watch.fail.store(false, SeqCst);
        assert_eq!(first(&cache.get(|| scan_of(8))), 8);
        assert_eq!(first(&cache.get(|| scan_of(9))), 8);
    }

    #[test]
    fn readers_share_one_scan_at_the_same_time() {
        let watch = Arc::new(TestWatch::default());
        let cache = Arc::new(Snapshots::new(Box::new(watch.clone())));
        let kept = cache.get(|| scan_of(1));
        // Readers check the watch and hold the kept scan together (no one waits for another), and
        // a change while they hold theirs does not disturb them.
        let threads = if cfg!(miri) { 3 } else { 8 };
        watch.gather.store(threads, SeqCst);
        let barrier = Arc::new(std::sync::Barrier::new(threads));
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                let (cache, barrier) = (cache.clone(), barrier.clone());
                std::thread::spawn(move || {
                    let held = cache.get(|| panic!("no scan: nothing changed"));
                    // Every reader holds its scan here at once.
                    barrier.wait();
                    first(&held)
                })
            })
            .collect();
        for w in workers {
            assert_eq!(w.join().unwrap(), 1);
        }
        assert_eq!(
            watch.most_checking.load(SeqCst),
            threads,
            "every reader was in the check at once"
        );
        watch.gather.store(0, SeqCst);
        assert_eq!(
            Arc::strong_count(&kept),
            2,
            "the cache's and this one: the readers let go"
        );
        watch.signal();
        let after = cache.get(|| scan_of(2));
        assert_eq!(first(&after), 2);
        drop(kept);
        assert_eq!(
            Arc::strong_count(&after),
            2,
            "the old scan is gone, the new one kept once"
        );
    }

    #[test]
    fn callers_after_a_change_wait_for_one_scan() {
        let watch = Arc::new(TestWatch::default());
        let cache = Arc::new(Snapshots::new(Box::new(watch.clone())));
        cache.get(|| scan_of(1));
        watch.signal();
        let scans = Arc::new(AtomicUsize::new(0));
        let threads = if cfg!(miri) { 3 } else { 8 };
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                let (cache, scans) = (cache.clone(), scans.clone());
                std::thread::spawn(move || {
                    first(&cache.get(|| {
                        scans.fetch_add(1, SeqCst);
                        scan_of(2)
                    }))
                })
            })
            .collect();
        for w in workers {
            assert_eq!(w.join().unwrap(), 2);
        }
        assert_eq!(scans.load(SeqCst), 1);
    }
}
