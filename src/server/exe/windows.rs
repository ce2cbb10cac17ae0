//! The EXE host on Windows: COM's class table, COM's server process count, events and the console;
//! the command line's registrations (the Windows service's through `super::scm`), and serving, by
//! COM's start, by hand or as the Windows service (`super::service`).

use core::ffi::c_void;
use core::ptr;
use core::sync::atomic::{AtomicBool, AtomicPtr, Ordering};

use windows_sys::Win32::Foundation::{
    CloseHandle, GetLastError, LocalFree, ERROR_ACCESS_DENIED, ERROR_ALREADY_EXISTS, ERROR_INVALID_HANDLE,
    ERROR_SUCCESS, HANDLE, WAIT_OBJECT_0, WAIT_TIMEOUT,
};
use windows_sys::Win32::Security::Authorization::{
    ConvertSidToStringSidW, ConvertStringSecurityDescriptorToSecurityDescriptorW, GetSecurityInfo, SDDL_REVISION_1,
    SE_KERNEL_OBJECT,
};
use windows_sys::Win32::Security::{
    EqualSid, GetAce, GetSecurityDescriptorDacl, GetTokenInformation, TokenOwner, TokenUser, ACCESS_ALLOWED_ACE, ACL,
    DACL_SECURITY_INFORMATION, OWNER_SECURITY_INFORMATION, PSECURITY_DESCRIPTOR, PSID, SECURITY_ATTRIBUTES,
    TOKEN_INFORMATION_CLASS, TOKEN_QUERY,
};
use windows_sys::Win32::System::Com::{
    CoAddRefServerProcess, CoInitializeEx, CoRegisterClassObject, CoReleaseServerProcess, CoResumeClassObjects,
    CoRevokeClassObject, CLSCTX_LOCAL_SERVER, COINIT_MULTITHREADED, REGCLS_MULTIPLEUSE, REGCLS_SUSPENDED,
};
use windows_sys::Win32::System::Console::SetConsoleCtrlHandler;
use windows_sys::Win32::System::Threading::{
    CreateEventW, GetCurrentProcess, OpenProcessToken, ResetEvent, SetEvent, WaitForMultipleObjects,
};

use super::keep::KEEPER;
use super::{scm::Scm, service, HostCommand, OpcExeServerOptions};
use crate::com::ffi::{self, Fail};
use crate::com::iids::IID_IUNKNOWN;
use crate::com::kept::Kept;
use crate::com::module_lock::{set_module_lock, ModuleLock};
use crate::com::unknown::Counted;
use crate::com::wstr::wstr_units;
use crate::com::{IUnknown, E_UNEXPECTED, HRESULT, LPCWSTR, S_FALSE, S_OK};
use crate::registry::register::{
    recorded_service, register_service, unregister_service, ServerDescription, ServiceOptions,
};
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
/// (`idle_linger_ms`): a client that released its last object and connects again within it is served
/// by this process, which then serves on, and the time starts again at the next last release. Five
/// seconds, as ATL's EXE module waits. Under Wine, whose CoReleaseServerProcess does not suspend the
/// class objects, COM hands a new client the class object of this process until the host revokes it;
/// a client on its way while the host ends can fail (see `END_PAUSE_MS`). The longer the linger, the
/// rarer a client meets that moment: a client that reconnects within it never does.
const LINGER_MS: u32 = 5_000;

/// After the linger, the host revokes its class objects (COM hands new clients to a new process from
/// then on) and serves this long more before it decides to end: a client that got a class object just
/// before the revocation (its activation was on its way) still makes its instance here, and the host
/// then serves it. ATL's EXE module pauses one second the same way.
const END_PAUSE_MS: u32 = 1_000;

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
    /// An unnamed manual-reset event, not set.
    fn new() -> Result<Event, HRESULT> {
        // SAFETY: default security, manual reset, not set, no name.
        let h = unsafe { CreateEventW(ptr::null(), 1, 0, ptr::null()) };
        if h.is_null() {
            return Err(last_error());
        }
        Ok(Event(h))
    }

    /// The operator's named stop event: a manual-reset event, not set, that this host creates, with
    /// an access list that lets only SYSTEM, the administrators and the server's own account use it.
    /// A name that already exists is shared only when it is what a host of this account made (an
    /// event with this process's owner and exactly this access list: another instance of the same
    /// server, which COM starts when a client comes while this one ends); anything else (an event
    /// made otherwise, even by this account, a mutex...) is refused with
    /// HRESULT_FROM_WIN32(ERROR_ALREADY_EXISTS): an object the host did not create could be set, or
    /// held, by others, and stop the server or keep it from starting.
    fn named(name: LPCWSTR) -> Result<Event, HRESULT> {
        let descriptor = stop_event_descriptor()?;
        let attributes = SECURITY_ATTRIBUTES {
            nLength: core::mem::size_of::<SECURITY_ATTRIBUTES>() as u32,
            lpSecurityDescriptor: descriptor.0,
            bInheritHandle: 0,
        };
        // SAFETY: a valid descriptor and attributes; `name` a NUL-terminated string (the caller's).
        let h = unsafe { CreateEventW(&attributes, 1, 0, name) };
        // SAFETY: no arguments; read at once after the call.
        let error = unsafe { GetLastError() };
        if h.is_null() {
            // ERROR_INVALID_HANDLE: another kind of object has the name; ERROR_ACCESS_DENIED: an
            // event of that name that this account may not open. Both: the name is taken.
            return Err(match error {
                ERROR_INVALID_HANDLE | ERROR_ACCESS_DENIED => NAME_TAKEN,
                _ => last_error(),
            });
        }
        let event = Event(h);
        if error == ERROR_ALREADY_EXISTS && !made_by_a_host_of_this_account(event.0, &descriptor)? {
            return Err(NAME_TAKEN);
        }
        Ok(event)
    }
}

/// HRESULT_FROM_WIN32(ERROR_ALREADY_EXISTS): the stop event's name is taken.
const NAME_TAKEN: HRESULT = 0x8007_00B7_u32 as HRESULT;

/// A self-relative security descriptor from LocalAlloc, freed when dropped.
struct LocalDescriptor(*mut c_void);

impl Drop for LocalDescriptor {
    fn drop(&mut self) {
        // SAFETY: allocated with LocalAlloc by the conversion that made it.
        unsafe { LocalFree(self.0) };
    }
}

/// The stop event's security: full access for SYSTEM, the administrators and the account the server
/// runs as (its token's user), nothing for anyone else, nothing inherited.
fn stop_event_descriptor() -> Result<LocalDescriptor, HRESULT> {
    let user = TokenSid::of(TokenUser)?.text()?;
    // EVENT_ALL_ACCESS (0x1F0003) rather than GA, so that the entries stored are the entries written
    // and a second instance can recognise them.
    let sddl: Vec<u16> = format!("D:P(A;;0x1f0003;;;SY)(A;;0x1f0003;;;BA)(A;;0x1f0003;;;{user})")
        .encode_utf16()
        .chain([0])
        .collect();
    let mut descriptor: *mut c_void = ptr::null_mut();
    // SAFETY: NUL-terminated text; `descriptor` writable.
    let ok = unsafe {
        ConvertStringSecurityDescriptorToSecurityDescriptorW(
            sddl.as_ptr(),
            SDDL_REVISION_1,
            &mut descriptor,
            ptr::null_mut(),
        )
    };
    if ok == 0 || descriptor.is_null() {
        return Err(last_error());
    }
    Ok(LocalDescriptor(descriptor))
}

/// Whether the existing event `h` (opened with READ_CONTROL) is one a host of this account made: owned
/// by the owner this process's token gives new objects, with exactly the access list of `ours`.
fn made_by_a_host_of_this_account(h: HANDLE, ours: &LocalDescriptor) -> Result<bool, HRESULT> {
    let owner_wanted = TokenSid::of(TokenOwner)?;
    let (mut owner, mut dacl): (PSID, *mut ACL) = (ptr::null_mut(), ptr::null_mut());
    let mut descriptor: PSECURITY_DESCRIPTOR = ptr::null_mut();
    // SAFETY: a valid handle; the out-pointers are writable; the others NULL (not asked for).
    let e = unsafe {
        GetSecurityInfo(
            h,
            SE_KERNEL_OBJECT,
            OWNER_SECURITY_INFORMATION | DACL_SECURITY_INFORMATION,
            &mut owner,
            ptr::null_mut(),
            &mut dacl,
            ptr::null_mut(),
            &mut descriptor,
        )
    };
    if e != ERROR_SUCCESS || descriptor.is_null() {
        return Ok(false); // a descriptor that cannot be read is not known to be ours
    }
    let _descriptor = LocalDescriptor(descriptor);
    let (mut wanted, mut present, mut defaulted): (*mut ACL, i32, i32) = (ptr::null_mut(), 0, 0);
    // SAFETY: `ours` is a valid descriptor; the out-pointers are writable.
    if unsafe { GetSecurityDescriptorDacl(ours.0, &mut present, &mut wanted, &mut defaulted) } == 0 || wanted.is_null()
    {
        return Err(last_error());
    }
    // SAFETY: `owner` and `dacl` point into `_descriptor` (alive) or are NULL; `owner_wanted` holds a
    // valid SID and `wanted` is the DACL of `ours`.
    Ok(!owner.is_null() && unsafe { EqualSid(owner, owner_wanted.sid()) } != 0 && unsafe { same_aces(dacl, wanted) })
}

/// Whether two access lists hold the same entries in the same order (type, flags, rights, SID).
///
/// # Safety
/// `a` NULL or a valid ACL; `b` a valid ACL.
unsafe fn same_aces(a: *mut ACL, b: *mut ACL) -> bool {
    if a.is_null() {
        return false; // a NULL DACL lets everyone in
    }
    // SAFETY: both valid ACLs (the caller's contract).
    let (na, nb) = unsafe { ((*a).AceCount, (*b).AceCount) };
    if na != nb {
        return false;
    }
    (0..u32::from(na)).all(|i| {
        let (mut x, mut y): (*mut c_void, *mut c_void) = (ptr::null_mut(), ptr::null_mut());
        // SAFETY: valid ACLs and an index below their count; the out-pointers are writable.
        if unsafe { GetAce(a, i, &mut x) == 0 || GetAce(b, i, &mut y) == 0 } {
            return false;
        }
        let (x, y) = (x.cast::<ACCESS_ALLOWED_ACE>(), y.cast::<ACCESS_ALLOWED_ACE>());
        // SAFETY: entries of valid ACLs; every entry starts with an ACE_HEADER, and the mask and the
        // SID follow as in ACCESS_ALLOWED_ACE for the allow and deny types compared here.
        unsafe {
            let (hx, hy) = ((*x).Header, (*y).Header);
            hx.AceType == hy.AceType
                && hx.AceFlags == hy.AceFlags
                && u32::from(hx.AceType) <= 1 // ACCESS_ALLOWED_ACE_TYPE, ACCESS_DENIED_ACE_TYPE
                && (*x).Mask == (*y).Mask
                && EqualSid(ptr::addr_of_mut!((*x).SidStart).cast(), ptr::addr_of_mut!((*y).SidStart).cast()) != 0
        }
    })
}

/// A SID of this process's token (its user, or the owner it gives new objects).
struct TokenSid {
    /// TOKEN_USER or TOKEN_OWNER, then the SID it points at: 8-byte aligned, larger than any needs.
    buffer: [u64; 64],
    /// Where in `buffer` the SID starts, in bytes (the structure's pointer is into the buffer where
    /// it was written, which moves with `self`).
    offset: usize,
}

impl TokenSid {
    /// `class`: TokenUser or TokenOwner (both begin with the SID's pointer).
    fn of(class: TOKEN_INFORMATION_CLASS) -> Result<TokenSid, HRESULT> {
        let mut token: HANDLE = ptr::null_mut();
        // SAFETY: the process's own pseudo-handle; `token` writable.
        if unsafe { OpenProcessToken(GetCurrentProcess(), TOKEN_QUERY, &mut token) } == 0 {
            return Err(last_error());
        }
        let token = Handle(token);
        let mut buffer = [0u64; 64];
        let size = core::mem::size_of_val(&buffer);
        let mut written = 0u32;
        // SAFETY: a token opened for query; the buffer and its size in bytes; `written` writable.
        let ok = unsafe { GetTokenInformation(token.0, class, buffer.as_mut_ptr().cast(), size as u32, &mut written) };
        if ok == 0 {
            return Err(last_error());
        }
        // SAFETY: TOKEN_USER and TOKEN_OWNER both begin with the SID's pointer, which
        // GetTokenInformation wrote at the start of the (aligned) buffer.
        let sid = unsafe { *buffer.as_ptr().cast::<PSID>() } as usize;
        let offset = sid.wrapping_sub(buffer.as_ptr() as usize);
        // The SID lies within the buffer, after the pointer to it.
        if sid == 0 || offset < core::mem::size_of::<PSID>() || offset >= size {
            return Err(E_UNEXPECTED);
        }
        Ok(TokenSid { buffer, offset })
    }

    /// The SID, inside `self.buffer`: valid while `self` is borrowed.
    fn sid(&self) -> PSID {
        // SAFETY: `offset` is within the buffer (checked when it was read).
        unsafe { self.buffer.as_ptr().cast::<u8>().add(self.offset) as PSID }
    }

    /// The SID as text (S-1-5-...).
    fn text(&self) -> Result<String, HRESULT> {
        let mut text: *mut u16 = ptr::null_mut();
        // SAFETY: a valid SID inside `self.buffer`; `text` writable.
        if unsafe { ConvertSidToStringSidW(self.sid(), &mut text) } == 0 || text.is_null() {
            return Err(last_error());
        }
        let text = LocalDescriptor(text.cast());
        // SAFETY: a NUL-terminated string from ConvertSidToStringSidW, alive until `text` drops; a
        // SID's text is far shorter than the bound.
        let units = unsafe { wstr_units(text.0.cast(), 256) }.ok_or(E_UNEXPECTED)?;
        Ok(String::from_utf16_lossy(units))
    }
}

/// A handle closed when dropped.
struct Handle(HANDLE);

impl Drop for Handle {
    fn drop(&mut self) {
        // SAFETY: a handle this owns.
        unsafe { CloseHandle(self.0) };
    }
}

impl Drop for Event {
    fn drop(&mut self) {
        // SAFETY: a handle this Event owns.
        unsafe { CloseHandle(self.0) };
    }
}

pub(super) fn last_error() -> HRESULT {
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
    command: HostCommand,
    service: Option<&ServiceOptions>,
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
    let scm = Scm::new(release_timeout(o));
    match command {
        HostCommand::Register => {
            // The EXE form: a service form registered before goes first, as /UnregServer takes it.
            if recorded_service(&*regs.write, descriptions).is_some() {
                unregister_service(&regs, &scm, descriptions)?;
                unregister_all(&regs, descriptions)?;
            }
            return Ok(register_all(&regs, descriptions).map(|()| S_OK)?);
        }
        HostCommand::Unregister => {
            // The service first: refused (without administrator rights) before anything is removed.
            unregister_service(&regs, &scm, descriptions)?;
            return Ok(unregister_all(&regs, descriptions).map(|()| S_OK)?);
        }
        HostCommand::Service { take_over } => {
            let service = service.ok_or(E_UNEXPECTED)?; // checked by the caller
            return Ok(register_service(&regs, &scm, descriptions, service, take_over).map(|()| S_OK)?);
        }
        HostCommand::RunService => {
            let service = service.ok_or(E_UNEXPECTED)?; // checked by the caller
            let result = service::run(o, table, descriptions, service);
            drop(running);
            return result;
        }
        HostCommand::ByHand | HostCommand::Embedding => {}
    }
    set_security(descriptions)?;
    let start = if command == HostCommand::Embedding {
        Start::Com
    } else {
        Start::Hand
    };
    let result = serve(o, table, start);
    drop(running);
    result
}

/// Process security from the server's AppID (EOAC_APPID: its AuthenticationLevel and permissions,
/// which registration writes at PKT_INTEGRITY), unless the server set its own before.
pub(super) fn set_security(descriptions: &[ServerDescription]) -> Result<(), Fail> {
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
    Ok(())
}

/// After a stop, how long the host waits for the clients to release what they hold.
pub(super) fn release_timeout(o: &OpcExeServerOptions) -> u32 {
    if o.release_timeout_ms == 0 {
        10_000
    } else {
        o.release_timeout_ms
    }
}

/// How the host was started, which decides how long it serves.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Start {
    /// By COM (`-Embedding`): until the last client left.
    Com,
    /// By hand: until stopped.
    Hand,
    /// By the service manager, as its service: until stopped, reporting its state to the service
    /// manager and without the console's controls (a service gets every user's log-off there).
    Service,
}

/// Serving, until the last client left or a stop.
pub(super) fn serve(o: &OpcExeServerOptions, table: &[ServerClass], start: Start) -> Result<HRESULT, Fail> {
    let by_com = start == Start::Com;
    let stop = Event::new()?;
    let idle = Event::new()?;
    let named = if o.stop_event_name.is_null() {
        None
    } else {
        Some(Event::named(o.stop_event_name)?)
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
    if start != Start::Service {
        // SAFETY: a handler that only sets the host's event.
        unsafe { SetConsoleCtrlHandler(Some(console_handler()), 1) };
    }
    if !by_com {
        // Started by hand or as a service: serve until stopped, not until the first client leaves.
        process_lock();
        USED.store(false, Ordering::Release);
    }
    // Before the first client: the interfaces clients will be handed stay registered with the RPC
    // runtime until the end (keep.rs says why).
    let kept = Kept::new(&KEEPER);
    let mut registered = Registered::new(table)?;
    if start == Start::Service {
        service::serving();
    }

    let first_client = if o.first_client_timeout_ms == 0 {
        60_000
    } else {
        o.first_client_timeout_ms
    };
    let release_timeout = release_timeout(o);
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
        // The last client left (or none came): serve `linger` more after the last release.
        match linger_after_last_release(&events, linger) {
            Idle::Stopped => break true,
            Idle::Busy => {
                // A client came and holds the server: serve on, with the class objects handed out
                // again (Windows suspended them when the count fell to zero).
                if !registered.0.is_empty() {
                    // SAFETY: no arguments.
                    unsafe { CoResumeClassObjects() };
                }
                continue;
            }
            Idle::Quiet => {}
        }
        // New clients go to a new process from now on; one already on its way here is still served
        // during the pause. Then the end, decided atomically with the count.
        registered.revoke();
        if wait(&stops, END_PAUSE_MS).is_some() {
            break true;
        }
        if COUNT.close_if_idle() {
            break false;
        }
        // A client came during the pause: serve it (without class objects) until it leaves.
    };
    let mut result = S_OK;
    if stopped {
        if start == Start::Service {
            // (Also when the stop came from the stop event or OpcExeServerStop.)
            service::stopping(release_timeout);
        }
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
        let progress = || {
            if start == Start::Service {
                service::stopping(release_timeout);
            }
        };
        if !released_within(idle.0, release_timeout, progress) {
            result = S_FALSE;
        }
    } else if !by_com {
        process_unlock();
    }
    drop(registered);
    drop(kept);
    Ok(result)
}

/// How the linger after the last release ended.
enum Idle {
    /// `linger` milliseconds passed with nothing held.
    Quiet,
    /// Something is held (a client came and stays).
    Busy,
    /// A stop.
    Stopped,
}

/// Waits until nothing has been held for `linger` milliseconds since the last release: a client that
/// comes and goes meanwhile (the count falls to zero again, `events[0]`) starts the time again. The
/// other events are stops.
fn linger_after_last_release(events: &[HANDLE], linger: u32) -> Idle {
    loop {
        if COUNT.held() > 0 {
            return Idle::Busy;
        }
        match wait(events, linger) {
            Some(0) => {
                // SAFETY: the host's event; the count is read again at the top.
                unsafe { ResetEvent(events[0]) };
            }
            Some(_) => return Idle::Stopped,
            None => {
                return if COUNT.held() > 0 { Idle::Busy } else { Idle::Quiet };
            }
        }
    }
}

/// Whether nothing is held on the server within `ms` milliseconds; `progress` is called about once a
/// second meanwhile (a service reports that it is still stopping).
fn released_within(idle: HANDLE, ms: u32, progress: impl Fn()) -> bool {
    let mut left = ms;
    let mut since_progress = 0;
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
        since_progress += step;
        if since_progress >= 1_000 {
            since_progress = 0;
            progress();
        }
    }
    true
}

/// Sets the running host's stop event: S_OK, or S_FALSE when no host runs (or it does not serve yet).
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
