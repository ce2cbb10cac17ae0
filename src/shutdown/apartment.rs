//! How an advised sink is held so that it can be called correctly from whichever thread notifies.
//!
//! A COM interface pointer belongs to the apartment it was obtained in. On Windows, Advise registers
//! the sink in the process's Global Interface Table, and every later use fetches it back with
//! `GetInterfaceFromGlobal`, which gives the notifying thread a pointer valid in its own apartment
//! (a proxy when the sink lives in another apartment and is not agile). When the GIT is unavailable
//! (the advising thread has not initialised COM) or refuses the sink (an apartment-bound sink whose
//! interface has no registered proxy/stub, such as IOPCShutdown on a machine without the OPC proxy
//! DLL), the pointer is held directly. If it was advised from a single-threaded apartment it is then
//! only called on that apartment's thread: from any other thread it counts as unreachable
//! (RPC_E_WRONG_THREAD) rather than being called where COM forbids it.
//!
//! A directly held sink is released by whichever thread ends its connection (Unadvise, or the last
//! Release of the server object); a GIT registration is revoked there, which COM allows from any
//! apartment of the process, but only on a thread that has initialised COM (otherwise the
//! registration stays until the process ends).
//!
//! Off Windows there are no apartments: the pointer is always held directly.

use super::interfaces::IOPCShutdown;
use crate::com::unknown::Counted;
use crate::com::HRESULT;

/// A counted reference to an advised sink's IOPCShutdown, released (or revoked from the GIT) on drop.
pub(crate) struct SinkRef {
    held: Held,
}

enum Held {
    /// A counted IOPCShutdown pointer used as is, on the threads `home` allows.
    Direct(Counted<IOPCShutdown>, Home),
    /// A Global Interface Table cookie; the GIT holds the reference.
    #[cfg(windows)]
    Global(u32),
}

// SAFETY: a `Direct` sink is called from other threads only where that is correct (no apartments off
// Windows; on Windows only when the GIT refused it, see the module documentation); a `Global` cookie
// is a plain number usable from any thread.
unsafe impl Send for SinkRef {}
// SAFETY: as above; `SinkRef` has no interior mutability.
unsafe impl Sync for SinkRef {}

/// Where a directly held sink may be called.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Home {
    /// From any thread (no apartments, or advised from the multithreaded apartment).
    Anywhere,
    /// Only on the thread of the single-threaded apartment it was advised from.
    #[cfg(windows)]
    Thread(u32),
}

impl Home {
    /// The calling thread's apartment.
    fn here() -> Home {
        #[cfg(windows)]
        {
            use windows_sys::Win32::System::Com::{CoGetApartmentType, APTTYPEQUALIFIER, APTTYPE_MAINSTA, APTTYPE_STA};
            let (mut kind, mut qualifier) = (0, 0 as APTTYPEQUALIFIER);
            // SAFETY: two valid out-pointers; fails cleanly when COM is not initialised here.
            let hr = unsafe { CoGetApartmentType(&mut kind, &mut qualifier) };
            if hr == 0 && (kind == APTTYPE_STA || kind == APTTYPE_MAINSTA) {
                // SAFETY: no preconditions.
                return Home::Thread(unsafe { windows_sys::Win32::System::Threading::GetCurrentThreadId() });
            }
        }
        Home::Anywhere
    }

    /// Whether a sink with this home may be called on the calling thread.
    fn allows_here(self) -> bool {
        match self {
            Home::Anywhere => true,
            #[cfg(windows)]
            // SAFETY: no preconditions.
            Home::Thread(id) => id == unsafe { windows_sys::Win32::System::Threading::GetCurrentThreadId() },
        }
    }
}

/// `RPC_E_WRONG_THREAD`: the sink belongs to another thread's apartment.
pub(crate) const RPC_E_WRONG_THREAD: HRESULT = 0x8001010E_u32 as HRESULT;

/// A counted IOPCShutdown pointer usable on the current thread, released on drop.
pub(crate) type SinkCall = Counted<IOPCShutdown>;

impl SinkRef {
    /// Takes over `sink`'s reference (the result of the sink's QueryInterface for IOPCShutdown).
    ///
    /// # Safety
    /// `sink` must be a counted IOPCShutdown pointer valid in the calling thread's apartment.
    pub(crate) unsafe fn adopt(sink: Counted<IOPCShutdown>) -> SinkRef {
        #[cfg(windows)]
        {
            // SAFETY: forwarded from the caller.
            if let Some(cookie) = unsafe { git::register(sink.as_ptr()) } {
                // The GIT holds its own reference now; ours goes.
                drop(sink);
                return SinkRef {
                    held: Held::Global(cookie),
                };
            }
        }
        SinkRef {
            held: Held::Direct(sink, Home::here()),
        }
    }

    /// A counted pointer to the sink that is valid on the calling thread.
    pub(crate) fn get(&self) -> Result<SinkCall, HRESULT> {
        match &self.held {
            Held::Direct(_, home) if !home.allows_here() => Err(RPC_E_WRONG_THREAD),
            Held::Direct(p, _) => Ok(p.clone()),
            #[cfg(windows)]
            Held::Global(cookie) => git::fetch(*cookie),
        }
    }
}

#[cfg(all(test, windows))]
impl SinkRef {
    /// Whether the sink is held through the Global Interface Table.
    pub(crate) fn is_global(&self) -> bool {
        matches!(self.held, Held::Global(_))
    }
}

/// A GIT registration is revoked; a directly held sink is released as its `Counted` drops.
#[cfg(windows)]
impl Drop for SinkRef {
    fn drop(&mut self) {
        if let Held::Global(cookie) = self.held {
            git::revoke(cookie);
        }
    }
}

#[cfg(windows)]
mod git {
    //! The Global Interface Table (`CLSID_StdGlobalInterfaceTable`), called through its vtable.

    use core::ffi::c_void;
    use core::ptr;

    use windows_sys::Win32::System::Com::{CoCreateInstance, CLSCTX_INPROC_SERVER};

    use super::{IOPCShutdown, SinkCall};
    use crate::com::iids::IID_IOPCShutdown;
    use crate::com::interfaces::IGlobalInterfaceTable as Git;
    use crate::com::unknown::Counted;
    use crate::com::{DWORD, GUID, HRESULT, S_OK};

    /// `CLSID_StdGlobalInterfaceTable` {00000323-0000-0000-C000-000000000046}.
    const CLSID_STD_GLOBAL_INTERFACE_TABLE: GUID = GUID::from_u128(0x00000323_0000_0000_C000_000000000046);

    /// Runs `f` with the process's GIT (a singleton; asking for it is cheap).
    fn with_git<R>(f: impl FnOnce(*mut Git) -> Result<R, HRESULT>) -> Result<R, HRESULT> {
        let mut git: *mut c_void = ptr::null_mut();
        // SAFETY: valid CLSID/IID and out-pointer; fails cleanly when COM is not initialised here.
        let hr = unsafe {
            CoCreateInstance(
                (&CLSID_STD_GLOBAL_INTERFACE_TABLE as *const GUID).cast(),
                ptr::null_mut(),
                CLSCTX_INPROC_SERVER,
                (&Git::IID as *const GUID).cast(),
                &mut git,
            )
        };
        if hr != S_OK {
            return Err(hr);
        }
        // SAFETY: CoCreateInstance gave us this reference (released when `git` drops).
        let git = unsafe { Counted::adopt(git.cast::<Git>()) }.ok_or(crate::com::E_POINTER)?;
        f(git.as_ptr())
    }

    /// Registers `sink` and returns its cookie, or `None` when the GIT cannot take it.
    ///
    /// # Safety
    /// `sink` must be a valid IOPCShutdown pointer of the calling thread's apartment.
    pub(super) unsafe fn register(sink: *mut IOPCShutdown) -> Option<u32> {
        with_git(|git| {
            let mut cookie: DWORD = 0;
            // SAFETY: `git` is a live GIT; `sink` is valid per the caller.
            let hr = unsafe { Git::RegisterInterfaceInGlobal(git, sink.cast(), &IID_IOPCShutdown, &mut cookie) };
            if hr == S_OK {
                Ok(cookie)
            } else {
                Err(hr)
            }
        })
        .ok()
    }

    /// The sink registered under `cookie`, as a counted pointer valid in the calling apartment.
    pub(super) fn fetch(cookie: u32) -> Result<SinkCall, HRESULT> {
        with_git(|git| {
            let mut p: *mut c_void = ptr::null_mut();
            // SAFETY: `git` is a live GIT; the out-pointer is valid.
            let hr = unsafe { Git::GetInterfaceFromGlobal(git, cookie, &IID_IOPCShutdown, &mut p) };
            if hr != S_OK {
                // A pointer left behind with a failure is not trusted, not released.
                return Err(hr);
            }
            // SAFETY: a successful GetInterfaceFromGlobal hands over one reference.
            unsafe { Counted::adopt(p.cast::<IOPCShutdown>()) }.ok_or(crate::com::E_POINTER)
        })
    }

    /// Revokes `cookie`, releasing the GIT's reference to the sink. When COM is not initialised on the
    /// calling thread this cannot be done and the registration stays until the process ends.
    pub(super) fn revoke(cookie: u32) {
        let _ = with_git(|git| {
            // SAFETY: `git` is a live GIT.
            Ok(unsafe { Git::RevokeInterfaceFromGlobal(git, cookie) })
        });
    }
}
