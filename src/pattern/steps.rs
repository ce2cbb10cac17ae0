//! The matchers' step count, for tests: every read of a pattern or string character (and every unit
//! passed while looking for a terminator) is one step. Tests bound the work a call does by it instead
//! of timing the call; outside tests `step` compiles to nothing.

#[cfg(test)]
std::thread_local! {
    static STEPS: core::cell::Cell<u64> = const { core::cell::Cell::new(0) };
}

/// Counts `n` steps (in tests only).
#[inline(always)]
pub(crate) fn step(n: usize) {
    #[cfg(test)]
    STEPS.with(|s| s.set(s.get() + n as u64));
    #[cfg(not(test))]
    let _ = n;
}

/// Runs `f` and returns its result with the steps it took on this thread.
#[cfg(test)]
pub(crate) fn counted<R>(f: impl FnOnce() -> R) -> (R, u64) {
    let before = STEPS.with(|s| s.get());
    let r = f();
    (r, STEPS.with(|s| s.get()) - before)
}
