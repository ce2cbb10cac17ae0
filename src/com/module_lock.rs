//! The module lock of an EXE server: every object the library makes counts on the server process, so
//! that the process lives as long as any of them does (COM's rule for local servers; ATL's
//! `CAtlModule::Lock`/`Unlock`, or `CoAddRefServerProcess`/`CoReleaseServerProcess`).
//!
//! An EXE server hands out more than the objects its class factories make: the enumerator a server
//! list returns, a connection point's IEnumConnections, and so on. Those are the library's objects,
//! and the EXE cannot see them being made or freed. With a module lock set, each of them calls the
//! EXE's `lock` when it is made and its `unlock` when it is freed.

use core::ffi::c_void;
use std::sync::Mutex;

use super::ffi::{self, Hr};
use super::options::{read_sized, SizedStruct};
use super::S_OK;

/// One function of a module lock. May be called from any thread, concurrently; must not call into the
/// library.
///
/// # Parameters
/// - `context`: the lock's `context` (OpcModuleLock::context).
pub type OpcModuleLockFn = Option<unsafe extern "C" fn(context: *mut c_void)>;

/// The functions an EXE server's module lock consists of. Zero-initialise it, set `struct_size` to
/// `sizeof(OpcModuleLock)`, then set `lock`, `unlock` and `context`.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct OpcModuleLock {
    /// `sizeof(OpcModuleLock)` as the caller's header declares it.
    pub struct_size: u32,
    /// Called with `context` when an object of the library has been made, on the thread making it.
    pub lock: OpcModuleLockFn,
    /// Called with `context` when an object that called `lock` has been freed, on the thread of its
    /// last Release (an RPC thread for a remote client's release), after the object is gone.
    pub unlock: OpcModuleLockFn,
    /// Passed to `lock` and `unlock`.
    pub context: *mut c_void,
}

// SAFETY: repr(C), struct_size first; optional function pointers and a raw pointer.
unsafe impl SizedStruct for OpcModuleLock {
    /// One version so far.
    const SIZES: &'static [usize] = &[core::mem::size_of::<OpcModuleLock>()];
}

/// A module lock in force: both functions and their context.
#[derive(Clone, Copy)]
pub(crate) struct ModuleLock {
    lock: unsafe extern "C" fn(*mut c_void),
    unlock: unsafe extern "C" fn(*mut c_void),
    context: *mut c_void,
}

// SAFETY: `OpcSetModuleLock`'s contract: the functions may be called with the context from any thread.
unsafe impl Send for ModuleLock {}
// SAFETY: as above; a ModuleLock is never modified.
unsafe impl Sync for ModuleLock {}

static CURRENT: Mutex<Option<ModuleLock>> = Mutex::new(None);

impl ModuleLock {
    /// Calls `lock` when a module lock is set, returning it for the matching `unlock`.
    pub(crate) fn lock() -> Option<ModuleLock> {
        let current = *CURRENT.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(m) = current {
            // SAFETY: `OpcSetModuleLock`'s contract.
            unsafe { (m.lock)(m.context) };
        }
        current
    }

    /// A module lock of the library's own (the EXE host's).
    #[cfg_attr(not(windows), allow(dead_code))]
    pub(crate) fn new(
        lock: unsafe extern "C" fn(*mut c_void),
        unlock: unsafe extern "C" fn(*mut c_void),
        context: *mut c_void,
    ) -> ModuleLock {
        ModuleLock { lock, unlock, context }
    }

    /// Calls `unlock` (of the module lock that counted the object, even if another was set since).
    pub(crate) fn unlock(self) {
        // SAFETY: `OpcSetModuleLock`'s contract.
        unsafe { (self.unlock)(self.context) };
    }
}

/// Sets (or, with `None`, clears) the module lock in force.
pub(crate) fn set_module_lock(next: Option<ModuleLock>) {
    *CURRENT.lock().unwrap_or_else(|poisoned| poisoned.into_inner()) = next;
}

/// Sets the module lock of an EXE server (see `OpcModuleLock`): from now on, every object the library
/// makes (server lists, enumerators, IOPCCommon sessions, shutdown objects, sinks, ...) calls `lock`
/// when it is made and `unlock` once it has been freed, so an EXE server that counts them exits only
/// when the last of the objects it handed out, directly or not, is released (COM's rule for local
/// servers). Objects made before the call are not counted; each object calls the `unlock` of the
/// module lock that counted it, even when another was set since. Set it once, before registering the
/// class objects; an in-process (DLL) server has no need of it. The library's EXE host
/// (`OpcExeServerRun`) sets its own.
///
/// # Parameters
/// - `lock`: the module lock, copied; NULL stops the counting for objects made from then on.
///
/// # Returns
/// S_OK; E_INVALIDARG when `lock` is not NULL and its `struct_size` is not the size of some version
/// of `OpcModuleLock`, or its `lock` or `unlock` is NULL.
///
/// # Safety
/// `lock` must be NULL or point at `struct_size` readable bytes laid out as `OpcModuleLock`; its
/// functions must be callable with its context from any thread, at any time until the process ends,
/// and must not call into the library.
#[no_mangle]
pub unsafe extern "C" fn OpcSetModuleLock(lock: *const OpcModuleLock) -> Hr {
    ffi::boundary!(Opc, [], {
        let next = if lock.is_null() {
            None
        } else {
            let defaults = OpcModuleLock {
                struct_size: 0,
                lock: None,
                unlock: None,
                context: core::ptr::null_mut(),
            };
            // SAFETY: OpcModuleLock is repr(C), starts with struct_size and holds only optional
            // function pointers and a raw pointer; the caller vouches for `lock`.
            let given = unsafe { read_sized(lock, defaults) }?;
            match (given.lock, given.unlock) {
                (Some(lock), Some(unlock)) => Some(ModuleLock {
                    lock,
                    unlock,
                    context: given.context,
                }),
                _ => return Err(super::E_INVALIDARG.into()),
            }
        };
        set_module_lock(next);
        Ok(S_OK)
    })
}
