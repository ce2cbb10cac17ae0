//! The host of an EXE server (LocalServer32), [`OpcExeServerRun`]: the command line,
//! registration, the class objects, the process's lifetime and the operator's stop.
//!
//! **Lifetime.** While it serves, the server count ([`super::OpcServerLock`], LockServer, and through
//! the module lock every object of the library) is COM's server process count: CoAddRefServerProcess
//! and CoReleaseServerProcess: COM's rule for local servers, kept while **any** object handed out is
//! referenced. When it falls to zero (Windows then suspends the class objects) the host serves
//! `idle_linger_ms` (five seconds) more after the last release: a client that released its last
//! object and connects again meanwhile is served, and the host serves on. Then it revokes its class
//! objects (COM starts a new process for a new client) and pauses a second, in which a client that
//! got a class object just before is still served. Then it ends: from that moment, decided
//! atomically with the count, any new instance or LockServer is refused with CO_E_SERVER_STOPPING, so
//! no client is handed an object of a process about to exit. Started by COM (`-Embedding`), a server
//! no client comes to gives up after `first_client_timeout_ms`. Started by hand, it holds one count of
//! its own until it is stopped.
//!
//! **Unlocks too many.** LockServer(FALSE) gives back only what LockServer(TRUE) took, and
//! OpcServerUnlock only what OpcServerLock took: an unmatched one, from any client, never ends the
//! server under an object another client holds.
//!
//! **Stop.** Console control (Ctrl+C, the console closing, log-off, shutdown), the named event
//! `stop_event_name`, or [`OpcExeServerStop`] from any thread: the host calls `on_stop` (where the
//! server notifies its clients, within a bound: `OpcShutdownNotifyBounded`), lets go of its own count,
//! waits `release_timeout_ms` at most for the clients to release what they hold, and returns. From the
//! stop on, the class objects are revoked and new instances and LockServer refused.
//!
//! **As a Windows service** (`service_name`): `/Service` registers the server as that service, whose
//! command line the service manager starts it with carries `-RunService`; the host then runs as the
//! service (`service`: the dispatcher, the control handler, the status reports; `scm`: the service
//! manager's side of registration, whose rules are `registry::register::service`'s). A service serves
//! until it is stopped, as OpcEnum and ATL's services do: it holds a count of its own, as a server
//! started by hand does, so COM's count never suspends its class objects and no activation meets its
//! end; the service manager's stop and a system shutdown are stops like the others.
//!
//! Off Windows the functions exist (a server's `main` builds everywhere) and OpcExeServerRun returns
//! E_NOTIMPL after checking its arguments.

use core::ffi::c_void;
use core::ptr;
use core::sync::atomic::{AtomicU32, Ordering};

use super::{registrations, OpcServerClass, ServerClass, MAX_CLASSES};
use crate::com::ffi::{self, Fail, Hr};
use crate::com::options::{read_sized, SizedStruct};
#[cfg(not(windows))]
use crate::com::E_NOTIMPL;
#[cfg(not(windows))]
use crate::com::S_FALSE;
use crate::com::{E_INVALIDARG, E_UNEXPECTED, HRESULT, LPCWSTR};
use crate::registry::cmdline::{arguments, parse_command_line, OpcServerCommand};
use crate::registry::register::{valid_service_name, ServiceOptions, LOCAL_SERVICE, SERVICE_ACCOUNTS};

#[cfg(windows)]
mod keep;
#[cfg(windows)]
mod scm;
#[cfg(windows)]
mod service;
#[cfg(windows)]
mod windows;

/// HRESULT_FROM_WIN32(ERROR_NOT_SUPPORTED): `/Service` or `-RunService` for a server that names no
/// service.
const NOT_SUPPORTED: HRESULT = 0x8007_0032_u32 as HRESULT;

/// What the host's command line asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum HostCommand {
    /// `/RegServer`: register (the EXE form).
    Register,
    /// `/UnregServer`: unregister, whichever form was registered.
    Unregister,
    /// `-Embedding`: COM started the server for a client.
    Embedding,
    /// Nothing the host knows: started by hand.
    ByHand,
    /// `/Service`: register as the Windows service `service_name` (`/TakeOver`: another product's
    /// service of that name too).
    Service { take_over: bool },
    /// `-RunService`: the service manager started the server as its service.
    RunService,
}

/// What `line` asks the host for: the switches of `OpcParseCommandLine`, and `/Service` (with
/// `/TakeOver`) and `-RunService`, in any case, with `/` or `-`. Asking for two of register,
/// unregister, `/Service` and `-RunService` at once is E_INVALIDARG.
pub(crate) fn host_command(line: &str) -> Result<HostCommand, HRESULT> {
    let (mut service, mut take_over, mut run) = (false, false, false);
    for arg in arguments(line) {
        let Some(switch) = arg.strip_prefix(['/', '-']) else {
            continue;
        };
        match switch.to_ascii_lowercase().as_str() {
            "service" => service = true,
            "takeover" => take_over = true,
            "runservice" => run = true,
            _ => {}
        }
    }
    let command = parse_command_line(line)?;
    let registering = matches!(command, OpcServerCommand::Register | OpcServerCommand::Unregister);
    if (service || run) && (registering || service == run) {
        return Err(E_INVALIDARG);
    }
    Ok(match command {
        _ if service => HostCommand::Service { take_over },
        _ if run => HostCommand::RunService,
        OpcServerCommand::Register => HostCommand::Register,
        OpcServerCommand::Unregister => HostCommand::Unregister,
        OpcServerCommand::Embedding => HostCommand::Embedding,
        OpcServerCommand::None => HostCommand::ByHand,
    })
}

/// The host's count of what is held on the server (its mirror of COM's server process count), and
/// whether it is ending. Ending is decided once, atomically with the count: [`HostCount::close_if_idle`]
/// only when nothing is held, and from then on [`HostCount::enter`] (a new instance, LockServer)
/// refuses, so that no client is handed an object of a process about to exit.
pub(crate) struct HostCount(AtomicU32);

/// The bit of `HostCount` that says the host is ending; the rest is the count.
const CLOSING: u32 = 1 << 31;

#[cfg_attr(not(windows), allow(dead_code))]
impl HostCount {
    pub(crate) const fn new() -> HostCount {
        HostCount(AtomicU32::new(0))
    }

    /// Serving again from nothing held (the host starts).
    pub(crate) fn reset(&self) {
        self.0.store(0, Ordering::SeqCst);
    }

    /// A count for something new a client asked for; false (nothing counted) when ending.
    pub(crate) fn enter(&self) -> bool {
        super::update_u32(&self.0, Ordering::SeqCst, Ordering::SeqCst, |n| {
            if n & CLOSING != 0 {
                None
            } else {
                (n + 1 < CLOSING).then_some(n + 1)
            }
        })
        .is_ok()
    }

    /// A count that is not refused, even when ending (an object made by an object still alive).
    /// Saturates rather than reaching the closing bit.
    pub(crate) fn lock(&self) {
        let _ = super::update_u32(&self.0, Ordering::SeqCst, Ordering::SeqCst, |n| {
            (n & !CLOSING < CLOSING - 1).then_some(n + 1)
        });
    }

    /// Gives back one count: the count left, or `None` when none was held (an unlock too many,
    /// ignored).
    pub(crate) fn unlock(&self) -> Option<u32> {
        super::update_u32(&self.0, Ordering::SeqCst, Ordering::SeqCst, |n| {
            (n & !CLOSING != 0).then(|| n - 1)
        })
        .ok()
        .map(|n| (n & !CLOSING) - 1)
    }

    /// How much is held.
    pub(crate) fn held(&self) -> u32 {
        self.0.load(Ordering::SeqCst) & !CLOSING
    }

    /// Ends serving if nothing is held, atomically: true when it did.
    pub(crate) fn close_if_idle(&self) -> bool {
        self.0
            .compare_exchange(0, CLOSING, Ordering::SeqCst, Ordering::SeqCst)
            .is_ok()
    }

    /// Ends serving now, whatever is held (a stop).
    pub(crate) fn close(&self) {
        self.0.fetch_or(CLOSING, Ordering::SeqCst);
    }
}

/// Called when an EXE server is stopped by its operator, on the host's thread (COM initialised, in the
/// multithreaded apartment) while clients may still be connected: ask them to disconnect here
/// (IOPCShutdown, `OpcShutdownNotifyBounded` with a timeout, so that a hung client cannot hold the
/// stop). Not called when the server ends because its last client left.
///
/// # Parameters
/// - `context`: OpcExeServerOptions::context.
pub type OpcExeServerStopFn = Option<unsafe extern "C" fn(context: *mut c_void)>;

/// How `OpcExeServerRun` runs an EXE server. Zero-initialise it, set `struct_size` to
/// `sizeof(OpcExeServerOptions)`, then set what you need.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct OpcExeServerOptions {
    /// `sizeof(OpcExeServerOptions)` as the caller's header declares it.
    pub struct_size: u32,
    /// The server's classes (at least one, at most 256): their class objects are registered while it
    /// serves, their `registration`s written by `/RegServer` (NULL `module_path`: this EXE).
    pub classes: *const OpcServerClass,
    /// Number of entries in `classes`.
    pub class_count: u32,
    /// The name of an event the operator's tools set to stop the server (for example
    /// `L"Local\\VendorServerStop"`), NULL for none. The host creates it (manual reset, not set) with
    /// access for SYSTEM, the administrators and the account the server runs as, and nobody else:
    /// they may set it (OpenEventW with EVENT_MODIFY_STATE, then SetEvent). If an object of that name
    /// already exists, OpcExeServerRun refuses to serve (0x800700B7): it never adopts an event someone
    /// else created.
    pub stop_event_name: LPCWSTR,
    /// Called when the server is stopped (see OpcExeServerStopFn); NULL for nothing.
    pub on_stop: OpcExeServerStopFn,
    /// Passed to `on_stop`.
    pub context: *mut c_void,
    /// How long a server started by COM (`-Embedding`) waits for its first client, in milliseconds;
    /// 0 means 60000.
    pub first_client_timeout_ms: u32,
    /// After a stop, how long the host waits for clients to release what they hold, in milliseconds;
    /// 0 means 10000.
    pub release_timeout_ms: u32,
    /// After the last client left, how long the host keeps serving before it ends, in milliseconds,
    /// counted from the last release; 0 means 5000 (as ATL's EXE module). A client that connects again
    /// within it is served by this process. After it the host revokes its class objects, serves one
    /// second more for a client already on its way, then ends. Shorter values end the process sooner
    /// after its last client, at a price under Wine, whose COM does not suspend the class objects: a
    /// client whose activation meets the end can fail there (docs/guide/server-plumbing.md). Every
    /// exit of the server that is not a stop waits for it. Not used by a service, which serves until
    /// it is stopped.
    pub idle_linger_ms: u32,
    /// The name of the Windows service the server runs as (for example `L"VendorOpcServer"`), or NULL
    /// for a server that does not offer to: with a name, `/Service` registers the server as that
    /// service and the service manager starts it with `-RunService` (docs/guide/server-plumbing.md, "As
    /// a Windows service"); without, both are HRESULT_FROM_WIN32(ERROR_NOT_SUPPORTED) (0x80070032).
    /// 1 to 256 characters without `/` or `\`, else E_INVALIDARG whatever the command line. Under Wine
    /// COM starts a service only when its name has at most 38 characters. (Version 2 of the
    /// structure: a library older than it refuses this `struct_size` with E_INVALIDARG.)
    pub service_name: LPCWSTR,
    /// The account `/Service` creates the service with: NULL for `NT AUTHORITY\LocalService`, the
    /// least privileged (no administrator rights, the network as an anonymous user), or
    /// `NT AUTHORITY\NetworkService` or `LocalSystem` for a server that needs more; anything else is
    /// E_INVALIDARG, as is an account without a `service_name` (an account with a password is an
    /// administrator's choice, in the service's properties, which registering again keeps). (Version
    /// 2.)
    pub service_account: LPCWSTR,
}

// SAFETY: repr(C), struct_size first; integers, raw pointers and an optional function pointer.
unsafe impl SizedStruct for OpcExeServerOptions {
    /// Every size at which a version ends: C's `sizeof` of each.
    const SIZES: &'static [usize] = &[
        // Version 1: up to `idle_linger_ms`, with C's trailing padding (the offset of the next field).
        core::mem::offset_of!(OpcExeServerOptions, service_name),
        // Version 2: the Windows service.
        core::mem::size_of::<OpcExeServerOptions>(),
    ];
}

/// Runs an EXE server (LocalServer32) as its `main`: everything but the server's own objects.
///
/// - `/RegServer` (or `-RegServer`): registers every class with a `registration` (NULL `module_path`:
///   this EXE), unregistering again what it wrote when one fails; returns.
/// - `/UnregServer`: unregisters them, in reverse order (a class not registered is no failure), and
///   the Windows service `/Service` registered, if any; returns.
/// - `/Service` (with a `service_name`): registers every class as `/RegServer` does, with its AppID's
///   `LocalService` naming the service, and creates the service (own process, demand start,
///   `service_account`), after asking the service manager first; `/TakeOver` takes over another
///   product's service of that name (its command line, given back by `/UnregServer`) instead of
///   refusing it. `/RegServer` goes back to the EXE form, removing the service. Returns.
/// - `-RunService` (the service manager starts the service so): runs as the service (on a thread of
///   the service manager's dispatcher, which `on_stop` is called on too): serves as a server started
///   by hand until the service manager stops it, the system shuts down or another stop, reporting its
///   state; returns when the service has stopped.
/// - Otherwise it serves: initialises COM (multithreaded apartment); when a class's registration has an
///   AppID, sets the process's security from it (OpcInitializeServerSecurity with `appid`: EOAC_APPID,
///   so the AppID's AuthenticationLevel and permissions apply) unless the server set process security
///   itself before the call; registers the class objects
///   (REGCLS_MULTIPLEUSE), and keeps the process while anything counts on the server: every object the
///   library makes (through the module lock, which the host sets), LockServer, and the server's own
///   objects that call OpcServerLock/OpcServerUnlock or aggregate an object of the library. When the
///   last goes it serves `idle_linger_ms` more after the last release (a client that connects again
///   meanwhile keeps it serving), then revokes the class objects, serves one second more for a client
///   already on its way, and returns, answering any later CreateInstance or LockServer with
///   CO_E_SERVER_STOPPING (COM then starts a new server process). LockServer(FALSE) and
///   OpcServerUnlock give back only what LockServer(TRUE) and OpcServerLock took. Started by COM
///   (`-Embedding`) it gives up after `first_client_timeout_ms` without a client; started by hand it
///   serves until stopped. A stop (console control, the named event `stop_event_name`,
///   OpcExeServerStop) calls `on_stop`, then waits `release_timeout_ms` at most for the clients to let
///   go. The host creates the named event itself, not set, with access for SYSTEM, the administrators
///   and the server's own account only; a name that already exists is refused.
///
/// The host returns without CoUninitialize: a client's last Release may still be on its way back on an
/// RPC thread, and CoUninitialize would wait for it (under Wine possibly for ever); return from `main`
/// (or call ExitProcess) with `SUCCEEDED(hr) ? 0 : 1`. One host per process at a time. Off Windows it
/// returns E_NOTIMPL after checking its arguments.
///
/// # Parameters
/// - `options`: the server's classes and how it is stopped (OpcExeServerOptions).
/// - `command_line`: the command line, or NULL for the process's (GetCommandLineW; off Windows, none).
///
/// # Returns
/// S_OK (registered, unregistered, or served until the last client left or a stop); S_FALSE after a
/// stop when objects were still referenced at the end of `release_timeout_ms`; E_INVALIDARG for a NULL
/// `options`, a wrong `struct_size`, no classes or over 256, a bad class or registration, a bad
/// `service_name` or `service_account`, a command line that asks for two of `/RegServer`,
/// `/UnregServer`, `/Service` and `-RunService`, or for `/Service` classes that cannot be one service
/// (every registration an EXE server's, of one program, with an AppID whose `LocalService` is unset
/// or the service's); HRESULT_FROM_WIN32(ERROR_NOT_SUPPORTED) (0x80070032) for `/Service` or
/// `-RunService` without a `service_name`; for `/Service` and `/UnregServer` the service manager's
/// errors, before anything is written or removed: E_ACCESSDENIED without administrator rights,
/// HRESULT_FROM_WIN32(ERROR_SERVICE_EXISTS) (0x80070431) for a service of that name that starts
/// another program (another product's) unless `/TakeOver`, HRESULT_FROM_WIN32(ERROR_SERVICE_MARKED_FOR_DELETE)
/// (0x80070430) while a service of that name is being deleted;
/// HRESULT_FROM_WIN32(ERROR_FAILED_SERVICE_CONTROLLER_CONNECT) (0x80070427) for `-RunService` in a
/// process the service manager did not start; E_UNEXPECTED when a host already runs in the process;
/// HRESULT_FROM_WIN32(ERROR_ALREADY_EXISTS) (0x800700B7) when an object named `stop_event_name`
/// already exists (an event or any other kind: another instance of the server, or a name someone took
/// first), before anything is served; the errors of CoInitializeEx, CoRegisterClassObject and of
/// registration.
///
/// # Safety
/// `options` NULL or valid as documented on OpcExeServerOptions (with its classes, kept so until the
/// call returns); `command_line` NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn OpcExeServerRun(options: *const OpcExeServerOptions, command_line: LPCWSTR) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller's contract.
        let (o, service) = unsafe { read_options(options) }?;
        // SAFETY: as above: `classes` holds `class_count` valid classes.
        let table = unsafe { ServerClass::read_table(o.classes, o.class_count) }?;
        // SAFETY: as above; the registrations are checked before anything is written.
        let descriptions = unsafe { registrations(o.classes, o.class_count) }?;
        let line = match command_line.is_null() {
            #[cfg(windows)]
            // SAFETY: no arguments; the process's command line lives as long as the process.
            true => unsafe { ffi::in_string(windows_sys::Win32::System::Environment::GetCommandLineW()) }?,
            #[cfg(not(windows))]
            true => String::new(),
            // SAFETY: the caller's NUL-terminated string.
            false => unsafe { ffi::in_string(command_line) }?,
        };
        let command = host_command(&line)?;
        if matches!(command, HostCommand::Service { .. } | HostCommand::RunService) && service.is_none() {
            return Err(NOT_SUPPORTED.into());
        }
        #[cfg(not(windows))]
        {
            let _ = (table, descriptions, command, service);
            Err(E_NOTIMPL.into())
        }
        #[cfg(windows)]
        windows::run(&o, &table, &descriptions, command, service.as_ref())
    })
}

/// Reads the caller's options, honouring `struct_size`, with the service they name (checked).
///
/// # Safety
/// `options` NULL or valid as documented on OpcExeServerOptions.
unsafe fn read_options(
    options: *const OpcExeServerOptions,
) -> Result<(OpcExeServerOptions, Option<ServiceOptions>), Fail> {
    if options.is_null() {
        return Err(Fail::Null);
    }
    let defaults = OpcExeServerOptions {
        struct_size: 0,
        classes: ptr::null(),
        class_count: 0,
        stop_event_name: ptr::null(),
        on_stop: None,
        context: ptr::null_mut(),
        first_client_timeout_ms: 0,
        release_timeout_ms: 0,
        idle_linger_ms: 0,
        service_name: ptr::null(),
        service_account: ptr::null(),
    };
    // SAFETY: repr(C), starting with struct_size, integers, raw pointers and an optional function
    // pointer; the caller vouches for `options`.
    let o = unsafe { read_sized(options, defaults) }?;
    if o.class_count == 0 || o.class_count > MAX_CLASSES {
        return Err(Fail::Code(E_INVALIDARG));
    }
    // SAFETY: the caller vouches for the strings it set (NULL or NUL-terminated).
    let (name, account) = unsafe {
        (
            ffi::in_string_opt(o.service_name)?,
            ffi::in_string_opt(o.service_account)?,
        )
    };
    let service = match name {
        None if account.is_some() => return Err(Fail::Code(E_INVALIDARG)),
        None => None,
        Some(name) => {
            let account = match account {
                None => LOCAL_SERVICE.to_string(),
                Some(a) => SERVICE_ACCOUNTS
                    .iter()
                    .find(|known| known.eq_ignore_ascii_case(&a))
                    .ok_or(Fail::Code(E_INVALIDARG))?
                    .to_string(),
            };
            if !valid_service_name(&name) {
                return Err(Fail::Code(E_INVALIDARG));
            }
            Some(ServiceOptions { name, account })
        }
    };
    Ok((o, service))
}

/// Stops the EXE server that OpcExeServerRun runs in this process, as its operator would: the host
/// calls `on_stop` and ends once the clients let go (or `release_timeout_ms` passed). From any thread,
/// for example the server's own user interface (a server running as a Windows service on the host is
/// stopped by the service manager through the host itself).
///
/// # Returns
/// S_OK; S_FALSE when no host runs.
#[no_mangle]
pub extern "C" fn OpcExeServerStop() -> Hr {
    ffi::guard!(E_UNEXPECTED, {
        #[cfg(windows)]
        {
            windows::stop()
        }
        #[cfg(not(windows))]
        {
            S_FALSE
        }
    })
}
