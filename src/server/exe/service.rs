//! The EXE host as a Windows service (`-RunService`): the service control dispatcher on the thread
//! that called OpcExeServerRun, the service's main function (on the dispatcher's thread) serving as a
//! server started by hand does, the control handler, and the status reports the service manager
//! waits for.
//!
//! - Started: START_PENDING, then RUNNING once the class objects are registered, accepting STOP,
//!   SHUTDOWN and PRESHUTDOWN.
//! - STOP, SHUTDOWN, PRESHUTDOWN: a stop like the host's others (`on_stop`, then `release_timeout_ms`
//!   at most for the clients). The handler sets the stop first and reports STOP_PENDING after, with a
//!   wait hint covering `on_stop` and the release; the host reports progress (a new checkpoint) after
//!   `on_stop` and about every second while it waits for the clients, each time with the time left
//!   as the hint. Then STOPPED, with the host's result (an error as a service-specific exit code).
//! - The service serves until it is stopped, as OpcEnum and ATL's services do: COM starts a service
//!   through the service manager, and a service that ended on its own when idle would meet activations
//!   while it stops (the service manager answers "already running" and the client waits for a class
//!   object that never comes); its own count also keeps Windows from suspending its class objects.

use core::ffi::c_void;
use core::ptr;
use core::sync::atomic::{AtomicPtr, Ordering};
use std::sync::Mutex;

use windows_sys::core::PWSTR;
use windows_sys::Win32::Foundation::{ERROR_CALL_NOT_IMPLEMENTED, NO_ERROR};
use windows_sys::Win32::System::Com::{CoInitializeEx, COINIT_MULTITHREADED};
use windows_sys::Win32::System::Services::{
    RegisterServiceCtrlHandlerExW, SetServiceStatus, StartServiceCtrlDispatcherW, SERVICE_ACCEPT_PRESHUTDOWN,
    SERVICE_ACCEPT_SHUTDOWN, SERVICE_ACCEPT_STOP, SERVICE_CONTROL_INTERROGATE, SERVICE_CONTROL_PRESHUTDOWN,
    SERVICE_CONTROL_SHUTDOWN, SERVICE_CONTROL_STOP, SERVICE_RUNNING, SERVICE_START_PENDING, SERVICE_STATUS,
    SERVICE_STATUS_HANDLE, SERVICE_STOPPED, SERVICE_STOP_PENDING, SERVICE_TABLE_ENTRYW, SERVICE_WIN32_OWN_PROCESS,
};

use super::scm;
use super::windows::{last_error, release_timeout, serve, set_security, stop, Start};
use super::OpcExeServerOptions;
use crate::com::ffi::{self, Fail};
use crate::com::{E_UNEXPECTED, HRESULT};
use crate::registry::register::{ServerDescription, ServiceOptions};
use crate::server::ServerClass;

/// `ERROR_SERVICE_SPECIFIC_ERROR`: the exit code is the service's own (the host's HRESULT).
const SERVICE_SPECIFIC_ERROR: u32 = 1066;

/// The service manager waits this long for the start (class objects registered) before it takes the
/// service for hung.
const START_HINT_MS: u32 = 30_000;

/// The part of a stop's wait hint that covers the server's `on_stop` (which bounds its own calls, as
/// with `OpcShutdownNotifyBounded`), before the release.
const ON_STOP_HINT_MS: u32 = 30_000;

/// What the service's main function runs: the host's arguments, and where it leaves its result.
struct Context {
    options: OpcExeServerOptions,
    table: Vec<ServerClass>,
    descriptions: Vec<ServerDescription>,
    name: Vec<u16>,
    result: Mutex<Option<Result<HRESULT, Fail>>>,
}

/// The running service's context, while the dispatcher runs (`run`'s stack holds it).
static CONTEXT: AtomicPtr<Context> = AtomicPtr::new(ptr::null_mut());

/// What the service last reported, and its status handle (0 while none).
struct Status {
    handle: usize,
    state: u32,
    checkpoint: u32,
}

static STATUS: Mutex<Status> = Mutex::new(Status {
    handle: 0,
    state: 0,
    checkpoint: 0,
});

/// Reports the state `state` to the service manager: with `hint` as the wait hint while pending (a new
/// checkpoint each time), and `exit` (a Win32 error, or a service-specific code) when stopped.
fn report(state: u32, hint: u32, exit: (u32, u32)) {
    let mut status = STATUS.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    if status.handle == 0 || status.state == SERVICE_STOPPED {
        return;
    }
    let pending = state == SERVICE_START_PENDING || state == SERVICE_STOP_PENDING;
    status.checkpoint = if !pending {
        0
    } else if status.state == state {
        status.checkpoint + 1
    } else {
        1
    };
    status.state = state;
    let report = SERVICE_STATUS {
        dwServiceType: SERVICE_WIN32_OWN_PROCESS,
        dwCurrentState: state,
        dwControlsAccepted: if state == SERVICE_RUNNING {
            SERVICE_ACCEPT_STOP | SERVICE_ACCEPT_SHUTDOWN | SERVICE_ACCEPT_PRESHUTDOWN
        } else {
            0
        },
        dwWin32ExitCode: exit.0,
        dwServiceSpecificExitCode: exit.1,
        dwCheckPoint: status.checkpoint,
        dwWaitHint: if pending { hint } else { 0 },
    };
    // SAFETY: the handle RegisterServiceCtrlHandlerExW gave (never closed); a valid status.
    unsafe { SetServiceStatus(status.handle as SERVICE_STATUS_HANDLE, &report) };
}

/// The host serves: the class objects are registered; the service manager may send its controls.
pub(super) fn serving() {
    report(SERVICE_RUNNING, 0, (NO_ERROR, 0));
}

/// The host is stopping and waits at most `release_timeout` milliseconds for its clients (a stop of
/// any kind): STOP_PENDING, with the next checkpoint.
pub(super) fn stopping(release_timeout: u32) {
    report(
        SERVICE_STOP_PENDING,
        release_timeout.saturating_add(1_000),
        (NO_ERROR, 0),
    );
}

/// What a control asks of the service.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Control {
    /// Stop: the service manager's stop, the system's (pre)shutdown.
    Stop,
    /// Only the current state (INTERROGATE).
    Report,
    /// Not a control this service takes.
    Unknown,
}

fn control_of(code: u32) -> Control {
    match code {
        SERVICE_CONTROL_STOP | SERVICE_CONTROL_SHUTDOWN | SERVICE_CONTROL_PRESHUTDOWN => Control::Stop,
        SERVICE_CONTROL_INTERROGATE => Control::Report,
        _ => Control::Unknown,
    }
}

/// The service's control handler (on the dispatcher's thread): a stop sets the host's stop event
/// first, then reports STOP_PENDING (under Wine, whose service manager may be ending itself at a
/// shutdown, the report can block: the host is on its way by then).
unsafe extern "system" fn control(
    code: u32,
    _kind: u32,
    _data: *mut c_void,
    _context: *mut c_void,
) -> ffi::Crossed<u32> {
    ffi::guard!(ERROR_CALL_NOT_IMPLEMENTED, {
        match control_of(code) {
            Control::Stop => {
                let _ = stop();
                let context = CONTEXT.load(Ordering::Acquire);
                // SAFETY: the context outlives the dispatcher, which calls this handler.
                let release = unsafe { context.as_ref() }.map_or(10_000, |c| release_timeout(&c.options));
                report(
                    SERVICE_STOP_PENDING,
                    ON_STOP_HINT_MS.saturating_add(release),
                    (NO_ERROR, 0),
                );
                NO_ERROR
            }
            Control::Report => NO_ERROR,
            Control::Unknown => ERROR_CALL_NOT_IMPLEMENTED,
        }
    })
}

/// `control` as the system's handler type, whose DWORD result is the plain `u32` that `Crossed<u32>`
/// is (`#[repr(transparent)]`: the same ABI).
fn control_handler() -> unsafe extern "system" fn(u32, u32, *mut c_void, *mut c_void) -> u32 {
    let f: unsafe extern "system" fn(u32, u32, *mut c_void, *mut c_void) -> ffi::Crossed<u32> = control;
    // SAFETY: function pointers of ABI-compatible signatures: the result types differ only by a
    // transparent wrapper.
    unsafe { core::mem::transmute(f) }
}

/// The service's main function, on a thread of the dispatcher: registers the control handler, serves,
/// leaves the result in the context and reports STOPPED (after which the process may end at any
/// moment: nothing of the context is touched then).
unsafe extern "system" fn service_main(_argc: u32, _argv: *mut PWSTR) {
    ffi::guard!((), {
        let context = CONTEXT.load(Ordering::Acquire);
        // SAFETY: `run` keeps the context alive until the dispatcher returns, which it does only once
        // this service has reported STOPPED.
        let Some(context) = (unsafe { context.as_ref() }) else {
            return;
        };
        // SAFETY: a NUL-terminated name; a handler that may be called on any thread.
        let handle =
            unsafe { RegisterServiceCtrlHandlerExW(context.name.as_ptr(), Some(control_handler()), ptr::null()) };
        if handle.is_null() {
            *context.result.lock().unwrap_or_else(|p| p.into_inner()) = Some(Err(last_error().into()));
            return;
        }
        {
            let mut status = STATUS.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            *status = Status {
                handle: handle as usize,
                state: 0,
                checkpoint: 0,
            };
        }
        report(SERVICE_START_PENDING, START_HINT_MS, (NO_ERROR, 0));
        let result = main(context);
        let exit = match &result {
            Ok(_) => (NO_ERROR, 0),
            Err(Fail::Code(hr)) => (SERVICE_SPECIFIC_ERROR, *hr as u32),
            Err(Fail::Null) => (SERVICE_SPECIFIC_ERROR, E_UNEXPECTED as u32),
        };
        *context.result.lock().unwrap_or_else(|p| p.into_inner()) = Some(result);
        report(SERVICE_STOPPED, 0, exit);
    })
}

/// The service's work: COM on this thread (the multithreaded apartment), process security from the
/// AppID, then serving until stopped.
fn main(context: &Context) -> Result<HRESULT, Fail> {
    // SAFETY: this thread joins the multithreaded apartment.
    let hr = unsafe { CoInitializeEx(ptr::null(), COINIT_MULTITHREADED as u32) };
    if hr < 0 {
        return Err(hr.into());
    }
    set_security(&context.descriptions)?;
    serve(&context.options, &context.table, Start::Service)
}

/// HRESULT_FROM_WIN32(ERROR_FAILED_SERVICE_CONTROLLER_CONNECT): the service manager did not start
/// this process.
const NOT_STARTED_BY_SCM: HRESULT = 0x8007_0427_u32 as HRESULT;

/// Runs the host as the service `service` until the service manager stopped it: the dispatcher, on
/// this thread. HRESULT_FROM_WIN32(ERROR_FAILED_SERVICE_CONTROLLER_CONNECT) when the service manager
/// did not start this process: at once when it says so (no such service, or not starting this
/// process), else when the dispatcher finds no service manager to connect to (at once on Windows,
/// under Wine after about ten seconds).
pub(super) fn run(
    o: &OpcExeServerOptions,
    table: &[ServerClass],
    descriptions: &[ServerDescription],
    service: &ServiceOptions,
) -> Result<HRESULT, Fail> {
    if !scm::may_be_starting(&service.name) {
        return Err(NOT_STARTED_BY_SCM.into());
    }
    let context = Context {
        options: *o,
        table: table.to_vec(),
        descriptions: descriptions.to_vec(),
        name: service.name.encode_utf16().chain([0]).collect(),
        result: Mutex::new(None),
    };
    CONTEXT.store(ptr::addr_of!(context).cast_mut(), Ordering::Release);
    let entries = [
        SERVICE_TABLE_ENTRYW {
            lpServiceName: context.name.as_ptr().cast_mut(),
            lpServiceProc: Some(service_main),
        },
        SERVICE_TABLE_ENTRYW {
            lpServiceName: ptr::null_mut(),
            lpServiceProc: None,
        },
    ];
    // SAFETY: a table ended by an empty entry, whose name outlives the call (the context's); the
    // service manager calls `service_main` on a thread of its own and returns once it stopped.
    let dispatched = unsafe { StartServiceCtrlDispatcherW(entries.as_ptr()) } != 0;
    let error = last_error();
    CONTEXT.store(ptr::null_mut(), Ordering::Release);
    STATUS.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).handle = 0;
    if !dispatched {
        return Err(error.into());
    }
    let result = context
        .result
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
        .take();
    result.unwrap_or(Err(E_UNEXPECTED.into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_service_managers_stop_and_the_systems_shutdown_are_stops() {
        for code in [
            SERVICE_CONTROL_STOP,
            SERVICE_CONTROL_SHUTDOWN,
            SERVICE_CONTROL_PRESHUTDOWN,
        ] {
            assert_eq!(control_of(code), Control::Stop, "{code}");
        }
        assert_eq!(control_of(SERVICE_CONTROL_INTERROGATE), Control::Report);
        // Pause, continue, parameter changes, session changes...: not taken.
        for code in [2, 3, 6, 14, 128] {
            assert_eq!(control_of(code), Control::Unknown, "{code}");
        }
    }

    #[test]
    fn reports_without_a_service_do_nothing() {
        // Outside a service (no status handle) the host's reports are no-ops.
        serving();
        stopping(1_000);
        assert_eq!(STATUS.lock().unwrap().handle, 0);
    }
}
