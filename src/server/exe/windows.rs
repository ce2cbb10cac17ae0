//! The EXE host on Windows: COM's class table, COM's server process count, events and the console.

use core::ffi::c_void;
use core::ptr;
use core::sync::atomic::{AtomicBool, AtomicPtr, Ordering};

use windows_sys::Win32::Foundation::{CloseHandle, HANDLE, WAIT_OBJECT_0, WAIT_TIMEOUT};
use windows_sys::Win32::System::Com::{
    CoAddRefServerProcess, CoInitializeEx, CoRegisterClassObject, CoReleaseServerProcess, CoResumeClassObjects,
    CoRevokeClassObject, CLSCTX_LOCAL_SERVER, COINIT_MULTITHREADED, REGCLS_MULTIPLEUSE, REGCLS_SUSPENDED,
};
use windows_sys::Win32::System::Console::SetConsoleCtrlHandler;
use windows_sys::Win32::System::Threading::{CreateEventW, ResetEvent, SetEvent, WaitForMultipleObjects};

use super::OpcExeServerOptions;
use crate::com::ffi::{self, Fail};
use crate::com::iids::IID_IUNKNOWN;
use crate::com::module_lock::{set_module_lock, ModuleLock};
use crate::com::unknown::Counted;
use crate::com::{IUnknown, E_UNEXPECTED, HRESULT, LPCWSTR, S_FALSE, S_OK};
use crate::registry::cmdline::OpcServerCommand;
use crate::registry::register::ServerDescription;
use crate::registry::registries;
use crate::security::{OpcInitializeServerSecurity, OpcSecurityOptions, RPC_E_TOO_LATE};
use crate::server::exe::HostCount;
use crate::server::{
    class_object, register_all, server_lock, server_unlock, set_process_count, unregister_all, ProcessCount,
    ServerClass,
};

/// The running host: its stop event, and the event set when the server count reaches zero.
static STOP: AtomicPtr<c_void> = AtomicPtr::new(ptr::null_mut());
static IDLE: AtomicPtr<c_void> = AtomicPtr::new(ptr::null_mut());
static RUNNING: AtomicBool = AtomicBool::new(false);
/// Set once anything counted on the server: a client came.
static USED: AtomicBool = AtomicBool::new(false);
/// The host's count (beside COM's server process count) and whether it is ending.
static COUNT: HostCount = HostCount::new();

/// After the last client left, how long the host keeps serving before it ends, unless the server says
/// (`idle_linger_ms`): a client that released its last object and connects again at once is served by
/// this process, which then serves on. Under Wine, whose CoReleaseServerProcess does not suspend the
/// class objects, an activation already on its way to a process whose class objects are revoked fails
/// (E_FAIL) and one to a process that exits fails too (RPC_S_CALL_FAILED): this quarter of a second
/// is what spares such a client (reconnecting takes milliseconds), and what every exit costs.
const LINGER_MS: u32 = 250;

fn process_enter() -> bool {
    if !COUNT.enter() {
        return false;
    }
    // SAFETY: no arguments; COM keeps the count.
    unsafe { CoAddRefServerProcess() };
    USED.store(true, Ordering::Release);
    true
}

fn process_lock() {
    COUNT.lock();
    // SAFETY: no arguments; COM keeps the count.
    unsafe { CoAddRefServerProcess() };
    USED.store(true, Ordering::Release);
}

fn process_unlock() {
    let Some(left) = COUNT.unlock() else {
        return; // an unlock too many: COM's count is left alone too
    };
    // SAFETY: no arguments; at zero Windows suspends the class objects itself.
    unsafe { CoReleaseServerProcess() };
    if left == 0 {
        let idle = IDLE.load(Ordering::Acquire);
        if !idle.is_null() {
            // SAFETY: the host's event, alive while it runs (the count is only kept then).
            unsafe { SetEvent(idle) };
        }
    }
}

/// The module lock of the host: every object of the library counts on the server.
unsafe extern "C" fn module_lock(_context: *mut c_void) {
    ffi::guard!((), { server_lock() })
}

/// As `module_lock`, for a freed object.
unsafe extern "C" fn module_unlock(_context: *mut c_void) {
    ffi::guard!((), { server_unlock() })
}

/// Console control (Ctrl+C, Ctrl+Break, the console closing, log-off, shutdown): a stop.
unsafe extern "system" fn console_control(_kind: u32) -> ffi::Crossed<i32> {
    ffi::guard!(0, {
        let stop = STOP.load(Ordering::Acquire);
        if stop.is_null() {
            0
        } else {
            // SAFETY: the host's event, alive while the handler is installed.
            unsafe { SetEvent(stop) };
            1
        }
    })
}

/// An event handle, closed when dropped.
struct Event(HANDLE);

impl Event {
    fn new(name: LPCWSTR) -> Result<Event, HRESULT> {
        // SAFETY: default security, manual reset, not set; `name` NULL or a NUL-terminated string.
        let h = unsafe { CreateEventW(ptr::null(), 1, 0, name) };
        if h.is_null() {
            return Err(last_error());
        }
        Ok(Event(h))
    }
}

impl Drop for Event {
    fn drop(&mut self) {
        // SAFETY: a handle this Event owns.
        unsafe { CloseHandle(self.0) };
    }
}

fn last_error() -> HRESULT {
    // SAFETY: no arguments.
    let e = unsafe { windows_sys::Win32::Foundation::GetLastError() };
    if e == 0 {
        E_UNEXPECTED
    } else {
        ((e & 0xFFFF) | 0x8007_0000) as HRESULT
    }
}

/// The class objects registered with COM, revoked and released when dropped.
struct Registered(Vec<(u32, Counted<IUnknown>)>);

impl Registered {
    /// Registers the class object of each class with COM, suspended; `CoResumeClassObjects` hands
    /// them out.
    fn new(table: &[ServerClass]) -> Result<Registered, Fail> {
        let mut registered = Registered(Vec::new());
        for class in table {
            let mut unknown: *mut c_void = ptr::null_mut();
            // SAFETY: a valid IID and out-pointer.
            let hr = unsafe { class_object(*class, &IID_IUNKNOWN, &mut unknown) };
            if hr < 0 {
                return Err(hr.into());
            }
            // SAFETY: the reference class_object gave us (released when `unknown` drops).
            let unknown = unsafe { Counted::adopt(unknown.cast::<IUnknown>()) }.ok_or(E_UNEXPECTED)?;
            let mut cookie = 0;
            // SAFETY: a valid CLSID and class object; COM keeps its own reference while registered.
            let hr = unsafe {
                CoRegisterClassObject(
                    (&class.clsid as *const crate::com::GUID).cast(),
                    unknown.as_ptr().cast(),
                    CLSCTX_LOCAL_SERVER,
                    (REGCLS_MULTIPLEUSE | REGCLS_SUSPENDED) as u32,
                    &mut cookie,
                )
            };
            if hr < 0 {
                return Err(hr.into());
            }
            registered.0.push((cookie, unknown));
        }
        // SAFETY: no arguments: every class object is registered, hand them out from now on.
        let hr = unsafe { CoResumeClassObjects() };
        if hr < 0 {
            return Err(hr.into());
        }
        Ok(registered)
    }

    /// Revokes every registration: COM hands out none of them from now on.
    fn revoke(&mut self) {
        for (cookie, unknown) in self.0.drain(..) {
            // SAFETY: a registration of ours; the reference we kept for it goes after.
            unsafe { CoRevokeClassObject(cookie) };
            drop(unknown);
        }
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        self.revoke();
    }
}

/// What the host leaves as it found when it returns: no process count, no module lock, no handler,
/// not running.
struct Running;

impl Drop for Running {
    fn drop(&mut self) {
        // SAFETY: removing the handler this host installed (a no-op when it was not).
        unsafe { SetConsoleCtrlHandler(Some(console_handler()), 0) };
        set_module_lock(None);
        set_process_count(None);
        STOP.store(ptr::null_mut(), Ordering::Release);
        IDLE.store(ptr::null_mut(), Ordering::Release);
        RUNNING.store(false, Ordering::Release);
    }
}

/// `console_control` as the system's handler type, whose BOOL result is the plain `i32` that
/// `Crossed<i32>` is (`#[repr(transparent)]`: the same ABI).
fn console_handler() -> unsafe extern "system" fn(u32) -> i32 {
    let f: unsafe extern "system" fn(u32) -> ffi::Crossed<i32> = console_control;
    // SAFETY: function pointers of ABI-compatible signatures: the result types differ only by a
    // transparent wrapper.
    unsafe { core::mem::transmute(f) }
}

/// Waits for any of `events`, `ms` at most; the index of the one set, or `None` on timeout.
fn wait(events: &[HANDLE], ms: u32) -> Option<usize> {
    // SAFETY: valid handles, a count that matches.
    let r = unsafe { WaitForMultipleObjects(events.len() as u32, events.as_ptr(), 0, ms) };
    if r == WAIT_TIMEOUT {
        return None;
    }
    let i = r.wrapping_sub(WAIT_OBJECT_0) as usize;
    (i < events.len()).then_some(i)
}

/// The host's part of `OpcExeServerRun`, after the arguments were checked.
pub(super) fn run(
    o: &OpcExeServerOptions,
    table: &[ServerClass],
    descriptions: &[ServerDescription],
    command: OpcServerCommand,
) -> Result<HRESULT, Fail> {
    if RUNNING.swap(true, Ordering::AcqRel) {
        return Err(E_UNEXPECTED.into());
    }

    let running = Running;
    // SAFETY: the calling thread joins the multithreaded apartment; S_FALSE (already) is fine.
    let hr = unsafe { CoInitializeEx(ptr::null(), COINIT_MULTITHREADED as u32) };
    if hr < 0 {
        return Err(hr.into());
    }
    // SAFETY: NULL: the system registry.
    let regs = unsafe { registries(ptr::null()) };
    match command {
        OpcServerCommand::Register => return Ok(register_all(&regs, descriptions).map(|()| S_OK)?),
        OpcServerCommand::Unregister => return Ok(unregister_all(&regs, descriptions).map(|()| S_OK)?),
        OpcServerCommand::None | OpcServerCommand::Embedding => {}
    }
    // Process security from the server's AppID (EOAC_APPID: its AuthenticationLevel and permissions,
    // which registration writes at PKT_INTEGRITY), unless the server set its own before.
    if let Some(app_id) = descriptions.iter().find_map(|d| d.app_id) {
        let security = OpcSecurityOptions {
            struct_size: core::mem::size_of::<OpcSecurityOptions>() as u32,
            authn_level: 0,
            imp_level: 0,
            flags: 0,
            appid: &app_id,
            access_sddl: ptr::null(),
        };
        // SAFETY: valid options with a readable AppID.
        let hr = unsafe { OpcInitializeServerSecurity(&security) }.get();
        if hr < 0 && hr != RPC_E_TOO_LATE {
            return Err(hr.into());
        }
    }
    let result = serve(o, table, command == OpcServerCommand::Embedding);
    drop(running);
    result
}

/// Serving, until the last client left or a stop.
fn serve(o: &OpcExeServerOptions, table: &[ServerClass], by_com: bool) -> Result<HRESULT, Fail> {
    let stop = Event::new(ptr::null())?;
    let idle = Event::new(ptr::null())?;
    let named = if o.stop_event_name.is_null() {
        None
    } else {
        Some(Event::new(o.stop_event_name)?)
    };
    STOP.store(stop.0, Ordering::Release);
    IDLE.store(idle.0, Ordering::Release);
    USED.store(false, Ordering::Release);
    COUNT.reset();
    set_process_count(Some(ProcessCount {
        enter: process_enter,
        lock: process_lock,
        unlock: process_unlock,
    }));
    set_module_lock(Some(ModuleLock::new(module_lock, module_unlock, ptr::null_mut())));
    // SAFETY: a handler that only sets the host's event.
    unsafe { SetConsoleCtrlHandler(Some(console_handler()), 1) };
    if !by_com {
        // Started by hand: serve until stopped, not until the first client leaves.
        process_lock();
        USED.store(false, Ordering::Release);
    }
    let mut registered = Registered::new(table)?;

    let first_client = if o.first_client_timeout_ms == 0 {
        60_000
    } else {
        o.first_client_timeout_ms
    };
    let release_timeout = if o.release_timeout_ms == 0 {
        10_000
    } else {
        o.release_timeout_ms
    };
    let linger = if o.idle_linger_ms == 0 {
        LINGER_MS
    } else {
        o.idle_linger_ms
    };
    let mut stops = vec![stop.0];
    if let Some(named) = &named {
        stops.push(named.0);
    }
    let mut events = vec![idle.0];
    events.extend_from_slice(&stops);
    let mut waited = 0u32;
    let stopped = loop {
        match wait(&events, 500) {
            Some(0) => {
                // SAFETY: the host's event; the count is read again below, so a wake-up is not lost.
                unsafe { ResetEvent(idle.0) };
            }
            Some(_) => break true,
            None => waited = waited.saturating_add(500),
        }
        let ending = if USED.load(Ordering::Acquire) {
            COUNT.held() == 0
        } else {
            by_com && waited >= first_client
        };
        if !ending {
            continue;
        }
        // The last client left (or none came): a while for a client already on its way here, then
        // the end, decided atomically with the count.
        if wait(&stops, linger).is_some() {
            break true;
        }
        if COUNT.close_if_idle() {
            break false;
        }
        // A client came meanwhile: serve on, with the class objects handed out again (Windows
        // suspended them when the count fell to zero).
        // SAFETY: no arguments.
        unsafe { CoResumeClassObjects() };
    };
    let mut result = S_OK;
    if stopped {
        // No new client from now on; those connected are asked to go.
        COUNT.close();
        registered.revoke();
        if let Some(on_stop) = o.on_stop {
            // SAFETY: the server's function, with its context, on this thread (COM initialised).
            unsafe { on_stop(o.context) };
        }
        if !by_com {
            process_unlock();
        }
        if !released_within(idle.0, release_timeout) {
            result = S_FALSE;
        }
    } else if !by_com {
        process_unlock();
    }
    drop(registered);
    Ok(result)
}

/// Whether nothing is held on the server within `ms` milliseconds.
fn released_within(idle: HANDLE, ms: u32) -> bool {
    let mut left = ms;
    while COUNT.held() > 0 {
        if left == 0 {
            return false;
        }
        let step = left.min(100);
        // SAFETY: the host's event; the count is read again, so a wake-up is not lost.
        unsafe { ResetEvent(idle) };
        if COUNT.held() == 0 {
            break;
        }
        let _ = wait(&[idle], step);
        left -= step;
    }
    true
}

/// Sets the running host's stop event: S_OK, or S_FALSE when no host runs.
pub(super) fn stop() -> HRESULT {
    let stop = STOP.load(Ordering::Acquire);
    if stop.is_null() {
        S_FALSE
    } else {
        // SAFETY: the host's event, alive while it runs.
        unsafe { SetEvent(stop) };
        S_OK
    }
}
