//! The service manager's side of registering the EXE host's Windows service (`/Service`,
//! `/UnregServer`): the [`ServiceManager`] of `registry::register::service` (whose rules these calls
//! follow) over the Win32 service API. Every failure is the service manager's error as an HRESULT
//! (HRESULT_FROM_WIN32: E_ACCESSDENIED without administrator rights).

use core::ptr;

use windows_sys::Win32::Foundation::{GetLastError, ERROR_INSUFFICIENT_BUFFER, ERROR_SERVICE_DOES_NOT_EXIST};
use windows_sys::Win32::System::Services::{
    ChangeServiceConfigW, CloseServiceHandle, ControlService, CreateServiceW, DeleteService, OpenSCManagerW,
    OpenServiceW, QueryServiceConfigW, QueryServiceStatus, QueryServiceStatusEx, QUERY_SERVICE_CONFIGW, SC_HANDLE,
    SC_MANAGER_CONNECT, SC_MANAGER_CREATE_SERVICE, SC_STATUS_PROCESS_INFO, SERVICE_CHANGE_CONFIG, SERVICE_CONTROL_STOP,
    SERVICE_DEMAND_START, SERVICE_ERROR_NORMAL, SERVICE_NO_CHANGE, SERVICE_QUERY_CONFIG, SERVICE_QUERY_STATUS,
    SERVICE_START_PENDING, SERVICE_STATUS, SERVICE_STATUS_PROCESS, SERVICE_STOP, SERVICE_STOPPED,
    SERVICE_WIN32_OWN_PROCESS,
};
use windows_sys::Win32::System::Threading::{GetCurrentProcessId, Sleep};

use super::windows::last_error;
use crate::com::wstr::wstr_units;
use crate::com::{E_UNEXPECTED, HRESULT};
use crate::registry::register::{NewService, ServiceManager};

/// The standard access right to delete an object.
const DELETE: u32 = 0x0001_0000;

/// A handle of the service manager or of a service, closed when dropped.
struct ScHandle(SC_HANDLE);

impl Drop for ScHandle {
    fn drop(&mut self) {
        // SAFETY: a handle this owns.
        unsafe { CloseServiceHandle(self.0) };
    }
}

/// A NUL-terminated copy of `s`.
fn wide(s: &str) -> Vec<u16> {
    s.encode_utf16().chain([0]).collect()
}

/// The service manager of this machine.
pub(super) struct Scm {
    /// How long `delete` waits for a running service to stop, in milliseconds.
    stop_wait_ms: u32,
}

impl Scm {
    /// `release_timeout_ms`: the server's bound for its clients after a stop; `delete` waits that long
    /// and half a minute more (for its `on_stop`) for the service to stop.
    pub(super) fn new(release_timeout_ms: u32) -> Scm {
        Scm {
            stop_wait_ms: release_timeout_ms.saturating_add(30_000),
        }
    }

    /// The service manager, with the right to create services (an administrator's): asked for
    /// whatever registration does, so that a caller without it is refused before anything changes.
    fn manager(&self) -> Result<ScHandle, HRESULT> {
        // SAFETY: this machine's active database; no pointers but NULLs.
        let h = unsafe { OpenSCManagerW(ptr::null(), ptr::null(), SC_MANAGER_CONNECT | SC_MANAGER_CREATE_SERVICE) };
        if h.is_null() {
            return Err(last_error());
        }
        Ok(ScHandle(h))
    }

    /// The service `name`, opened for `access`; `None` when there is no such service.
    fn open(&self, name: &str, access: u32) -> Result<Option<ScHandle>, HRESULT> {
        let manager = self.manager()?;
        let name = wide(name);
        // SAFETY: an open service manager; a NUL-terminated name.
        let h = unsafe { OpenServiceW(manager.0, name.as_ptr(), access) };
        if h.is_null() {
            // SAFETY: no arguments; read at once after the call.
            if unsafe { GetLastError() } == ERROR_SERVICE_DOES_NOT_EXIST {
                return Ok(None);
            }
            return Err(last_error());
        }
        Ok(Some(ScHandle(h)))
    }

    /// Opens the service `name` for `access`, which must exist.
    fn existing(&self, name: &str, access: u32) -> Result<ScHandle, HRESULT> {
        self.open(name, access)?.ok_or(0x8007_0424_u32 as HRESULT) // HRESULT_FROM_WIN32(ERROR_SERVICE_DOES_NOT_EXIST)
    }
}

/// Whether the service manager may be starting this process as the service `name`: `false` only when
/// it says otherwise (no such service, or the service is not starting, or is starting in another
/// process), so that a `-RunService` it did not start fails at once instead of after the dispatcher's
/// wait for a connection (about ten seconds under Wine). When the service manager cannot be asked (no
/// right to), `true`: the dispatcher decides.
pub(super) fn may_be_starting(name: &str) -> bool {
    // SAFETY: this machine's active database; no pointers but NULLs.
    let manager = unsafe { OpenSCManagerW(ptr::null(), ptr::null(), SC_MANAGER_CONNECT) };
    if manager.is_null() {
        return true;
    }
    let manager = ScHandle(manager);
    let name = wide(name);
    // SAFETY: an open service manager; a NUL-terminated name.
    let service = unsafe { OpenServiceW(manager.0, name.as_ptr(), SERVICE_QUERY_STATUS) };
    if service.is_null() {
        // SAFETY: no arguments; read at once after the call.
        return unsafe { GetLastError() } != ERROR_SERVICE_DOES_NOT_EXIST;
    }
    let service = ScHandle(service);
    // SAFETY: plain integers; all zero is a valid value.
    let mut status: SERVICE_STATUS_PROCESS = unsafe { core::mem::zeroed() };
    let mut needed = 0u32;
    // SAFETY: an open service; a buffer of the structure's size.
    let ok = unsafe {
        QueryServiceStatusEx(
            service.0,
            SC_STATUS_PROCESS_INFO,
            ptr::addr_of_mut!(status).cast(),
            core::mem::size_of::<SERVICE_STATUS_PROCESS>() as u32,
            &mut needed,
        )
    } != 0;
    if !ok {
        return true;
    }
    // The service manager sets START_PENDING before it creates the process, and records the process
    // after: 0 is this process on its way.
    // SAFETY: no arguments.
    let this = unsafe { GetCurrentProcessId() };
    status.dwCurrentState == SERVICE_START_PENDING && (status.dwProcessId == 0 || status.dwProcessId == this)
}

impl ServiceManager for Scm {
    fn command_line(&self, name: &str) -> Result<Option<String>, HRESULT> {
        let Some(service) = self.open(name, SERVICE_QUERY_CONFIG)? else {
            return Ok(None);
        };
        let mut needed = 0u32;
        // SAFETY: an open service; no buffer: asks for the size needed.
        let ok = unsafe { QueryServiceConfigW(service.0, ptr::null_mut(), 0, &mut needed) };
        // SAFETY: no arguments; read at once after the call.
        if ok != 0 || unsafe { GetLastError() } != ERROR_INSUFFICIENT_BUFFER {
            return Err(if ok != 0 { E_UNEXPECTED } else { last_error() });
        }
        // 8-byte aligned, for the structure at its start; the strings follow it.
        let mut buffer = vec![0u64; (needed as usize).div_ceil(8)];
        let config = buffer.as_mut_ptr().cast::<QUERY_SERVICE_CONFIGW>();
        // SAFETY: an open service; a buffer of at least `needed` bytes, aligned for the structure.
        if unsafe { QueryServiceConfigW(service.0, config, needed, &mut needed) } == 0 {
            return Err(last_error());
        }
        // SAFETY: the structure was written; its path is NULL or a NUL-terminated string in `buffer`,
        // shorter than the buffer.
        let path = unsafe { (*config).lpBinaryPathName };
        if path.is_null() {
            return Ok(Some(String::new()));
        }
        // SAFETY: as above.
        let units = unsafe { wstr_units(path, buffer.len() * 4) }.ok_or(E_UNEXPECTED)?;
        Ok(Some(String::from_utf16_lossy(units)))
    }

    fn create(&self, service: &NewService) -> Result<(), HRESULT> {
        let manager = self.manager()?;
        let (name, display, command_line, account) = (
            wide(&service.name),
            wide(&service.display_name),
            wide(&service.command_line),
            wide(&service.account),
        );
        // SAFETY: an open service manager; NUL-terminated strings; the built-in accounts need no
        // password (NULL).
        let h = unsafe {
            CreateServiceW(
                manager.0,
                name.as_ptr(),
                display.as_ptr(),
                SERVICE_QUERY_STATUS,
                SERVICE_WIN32_OWN_PROCESS,
                SERVICE_DEMAND_START,
                SERVICE_ERROR_NORMAL,
                command_line.as_ptr(),
                ptr::null(),
                ptr::null_mut(),
                ptr::null(),
                account.as_ptr(),
                ptr::null(),
            )
        };
        if h.is_null() {
            return Err(last_error());
        }
        drop(ScHandle(h));
        Ok(())
    }

    fn set_command_line(&self, name: &str, command_line: &str) -> Result<(), HRESULT> {
        let service = self.existing(name, SERVICE_CHANGE_CONFIG)?;
        let command_line = wide(command_line);
        // SAFETY: an open service; a NUL-terminated command line; everything else unchanged.
        let ok = unsafe {
            ChangeServiceConfigW(
                service.0,
                SERVICE_NO_CHANGE,
                SERVICE_NO_CHANGE,
                SERVICE_NO_CHANGE,
                command_line.as_ptr(),
                ptr::null(),
                ptr::null_mut(),
                ptr::null(),
                ptr::null(),
                ptr::null(),
                ptr::null(),
            )
        };
        if ok == 0 {
            return Err(last_error());
        }
        Ok(())
    }

    fn delete(&self, name: &str) -> Result<(), HRESULT> {
        let service = self.existing(name, DELETE | SERVICE_STOP | SERVICE_QUERY_STATUS)?;
        // A running service is stopped first (its clients told, through `on_stop`), a bounded time:
        // one that does not stop within it is deleted as it is, and goes when it stops.
        let mut status: SERVICE_STATUS = SERVICE_STATUS {
            dwServiceType: 0,
            dwCurrentState: 0,
            dwControlsAccepted: 0,
            dwWin32ExitCode: 0,
            dwServiceSpecificExitCode: 0,
            dwCheckPoint: 0,
            dwWaitHint: 0,
        };
        // SAFETY: an open service; `status` writable.
        let running =
            unsafe { QueryServiceStatus(service.0, &mut status) } != 0 && status.dwCurrentState != SERVICE_STOPPED;
        if running {
            // SAFETY: as above (a stop the service does not accept fails, and is waited for anyway).
            unsafe { ControlService(service.0, SERVICE_CONTROL_STOP, &mut status) };
            let mut waited = 0;
            while waited < self.stop_wait_ms {
                // SAFETY: as above.
                if unsafe { QueryServiceStatus(service.0, &mut status) } == 0
                    || status.dwCurrentState == SERVICE_STOPPED
                {
                    break;
                }
                // SAFETY: no pointers.
                unsafe { Sleep(100) };
                waited += 100;
            }
        }
        // SAFETY: an open service, with DELETE access.
        if unsafe { DeleteService(service.0) } == 0 {
            return Err(last_error());
        }
        Ok(())
    }
}
