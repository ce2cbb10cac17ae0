//! The panic boundary. A panic unwinding into C is undefined behaviour and aborting would kill the OPC
//! client or server hosting the library, so every export and every vtable method runs its body
//! through [`catch`] and returns its documented failure value instead.

use std::panic::{catch_unwind, AssertUnwindSafe};

/// Runs `f`; if it panics, returns `fallback` (E_UNEXPECTED for HRESULT-returning functions).
///
/// Out-parameters must already hold their failure values before `f` runs, so a panic leaves them
/// well defined (specification section 3.1.3).
#[inline(always)]
pub fn catch<R>(fallback: R, f: impl FnOnce() -> R) -> R {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or(fallback)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::com::hresult::{E_UNEXPECTED, S_OK};

    #[test]
    fn a_panic_becomes_the_fallback() {
        assert_eq!(catch(E_UNEXPECTED, || panic!("boom")), E_UNEXPECTED);
        assert_eq!(catch(E_UNEXPECTED, || S_OK), S_OK);
    }
}
