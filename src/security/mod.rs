//! DCOM security, hardened by default: process security for servers and clients
//! (`OpcInitializeServerSecurity`, `OpcInitializeClientSecurity`, over CoInitializeSecurity) and the
//! authentication of one proxy (`OpcSetProxyBlanket`, over CoSetProxyBlanket).
//!
//! Since Microsoft's DCOM hardening (KB5004442, CVE-2021-26414, enforced since March 2023) a server
//! refuses activation below RPC_C_AUTHN_LEVEL_PKT_INTEGRITY, and code that asks COM for less (NONE,
//! CONNECT) stops working across machines whatever dcomcnfg says. These functions ask for
//! PKT_INTEGRITY unless told otherwise and refuse anything weaker unless the caller sets
//! `OPC_SECURITY_ALLOW_WEAKER_AUTHN`.
//!
//! The calls into COM go through a seam ([`CoInitializeSecurityArgs`], [`CoSetProxyBlanketArgs`]):
//! the exports pass the real functions, the tests a recorder, so the arguments the library passes can
//! be asserted where COM does not enforce them (Wine accepts CoInitializeSecurity and ignores it).

use core::ffi::c_void;
use core::ptr;
use std::sync::Mutex;

use crate::com::ffi::{self, FfiResult, Hr};
use crate::com::iids::IID_IUNKNOWN;
use crate::com::options::{read_sized, SizedStruct};
use crate::com::unknown::query;
use crate::com::{IUnknown, CLSID, E_INVALIDARG, GUID, HRESULT, LPCWSTR, S_OK};

#[cfg(windows)]
mod windows;

#[cfg(test)]
mod tests;

/// What `OpcInitializeServerSecurity`, `OpcInitializeClientSecurity` and `OpcSetProxyBlanket` ask COM
/// for. Zero-initialise it, set `struct_size` to `sizeof(OpcSecurityOptions)`, then set what you
/// need; every zero field means the hardened default. NULL options are all defaults.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct OpcSecurityOptions {
    /// `sizeof(OpcSecurityOptions)` as the caller's header declares it.
    pub struct_size: u32,
    /// An RPC_C_AUTHN_LEVEL_* value: 0 means RPC_C_AUTHN_LEVEL_PKT_INTEGRITY (5), not COM's
    /// RPC_C_AUTHN_LEVEL_DEFAULT; PKT_PRIVACY (6) is accepted. A level below PKT_INTEGRITY (NONE 1,
    /// CONNECT 2, CALL 3, PKT 4) is refused with E_INVALIDARG unless `flags` has
    /// `OPC_SECURITY_ALLOW_WEAKER_AUTHN`.
    pub authn_level: u32,
    /// An RPC_C_IMP_LEVEL_* value (1 to 4): 0 means RPC_C_IMP_LEVEL_IDENTIFY (2) for
    /// `OpcInitializeServerSecurity` (a server that never acts as its caller needs no more) and
    /// RPC_C_IMP_LEVEL_IMPERSONATE (3) for `OpcInitializeClientSecurity` and `OpcSetProxyBlanket`.
    pub imp_level: u32,
    /// `OPC_SECURITY_*` flags; 0 for none. Unknown bits are refused with E_INVALIDARG.
    pub flags: u32,
    /// The process's AppID, or NULL. When set, CoInitializeSecurity gets EOAC_APPID and COM takes the
    /// process's security from the AppID's registry key (AuthenticationLevel, AccessPermission), so
    /// an administrator's dcomcnfg settings apply; COM then ignores the levels passed. Not with
    /// `access_sddl`; NULL for `OpcSetProxyBlanket`. (Declared as a CLSID pointer: the GUID type of this
    /// header with and without the Windows headers; an AppID is often the server's CLSID.)
    pub appid: *const CLSID,
    /// Who may call into the process, as SDDL (Windows' security descriptor string), or NULL. It
    /// must name an owner (`O:`) and a group (`G:`) and have no SACL (`S:`), as CoInitializeSecurity
    /// requires, e.g. `O:BAG:BAD:(A;;0x3;;;AU)(A;;0x3;;;SY)` (authenticated users and SYSTEM;
    /// 0x3 = COM_RIGHTS_EXECUTE | COM_RIGHTS_EXECUTE_LOCAL, add 0x4 COM_RIGHTS_EXECUTE_REMOTE for
    /// remote callers). NULL with a NULL `appid`: COM checks no access list, so everyone who
    /// authenticates at the level may call. Not with `appid`; NULL for `OpcSetProxyBlanket`.
    pub access_sddl: LPCWSTR,
}

// SAFETY: repr(C), struct_size first; integers and raw pointers.
unsafe impl SizedStruct for OpcSecurityOptions {
    /// One version so far.
    const SIZES: &'static [usize] = &[core::mem::size_of::<OpcSecurityOptions>()];
}

/// `OpcSecurityOptions::flags`: accept an authentication level below RPC_C_AUTHN_LEVEL_PKT_INTEGRITY.
/// Warning: Windows hardened DCOM against it (KB5004442, CVE-2021-26414; enforced since March
/// 2023): servers refuse activation requests below PKT_INTEGRITY, so a process using a weaker level
/// stops talking to other machines. Only for tests or for peers on systems without the hardening.
pub const OPC_SECURITY_ALLOW_WEAKER_AUTHN: u32 = 1;

/// Every flag this version knows.
const KNOWN_FLAGS: u32 = OPC_SECURITY_ALLOW_WEAKER_AUTHN;

/// RPC_C_AUTHN_LEVEL_* values.
pub(crate) const RPC_C_AUTHN_LEVEL_PKT_INTEGRITY: u32 = 5;
pub(crate) const RPC_C_AUTHN_LEVEL_PKT_PRIVACY: u32 = 6;
/// RPC_C_IMP_LEVEL_* values.
pub(crate) const RPC_C_IMP_LEVEL_IDENTIFY: u32 = 2;
pub(crate) const RPC_C_IMP_LEVEL_IMPERSONATE: u32 = 3;
pub(crate) const RPC_C_IMP_LEVEL_DELEGATE: u32 = 4;
/// EOLE_AUTHENTICATION_CAPABILITIES values.
pub(crate) const EOAC_NONE: u32 = 0;
pub(crate) const EOAC_APPID: u32 = 0x8;
pub(crate) const EOAC_DEFAULT: u32 = 0x800;
/// CoSetProxyBlanket's "keep what the proxy has" values.
pub(crate) const RPC_C_AUTHN_DEFAULT: u32 = 0xFFFF_FFFF;
pub(crate) const RPC_C_AUTHZ_DEFAULT: u32 = 0xFFFF_FFFF;
pub(crate) const COLE_DEFAULT_PRINCIPAL: LPCWSTR = usize::MAX as LPCWSTR;
pub(crate) const COLE_DEFAULT_AUTHINFO: *const c_void = usize::MAX as *const c_void;
/// CoInitializeSecurity has already been called in this process (winerror.h's value).
pub(crate) const RPC_E_TOO_LATE: HRESULT = 0x80010119_u32 as HRESULT;

/// Who asks: the defaults and what may be set differ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Role {
    /// A server's process security: identify by default.
    Server,
    /// A client's process security: impersonate by default.
    Client,
    /// One proxy's blanket: impersonate by default, no AppID or access list.
    Proxy,
}

/// Whose access list the process gets.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Access {
    /// NULL: no access check beyond authentication.
    Anyone,
    /// EOAC_APPID: the AppID's registry key decides.
    AppId(GUID),
    /// A security descriptor, as SDDL (UTF-16 without the NUL).
    Sddl(Vec<u16>),
}

/// The checked request.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Plan {
    pub authn_level: u32,
    pub imp_level: u32,
    pub access: Access,
}

/// Reads and checks the caller's options for `role`.
///
/// # Safety
/// `options` must be NULL or point at `options->struct_size` readable bytes whose `appid` and
/// `access_sddl` are NULL or valid (a GUID; a NUL-terminated UTF-16 string).
pub(crate) unsafe fn plan(role: Role, options: *const OpcSecurityOptions) -> FfiResult<Plan> {
    let defaults = OpcSecurityOptions {
        struct_size: 0,
        authn_level: 0,
        imp_level: 0,
        flags: 0,
        appid: ptr::null(),
        access_sddl: ptr::null(),
    };
    // SAFETY: repr(C), starts with struct_size, only integers and raw pointers; the caller vouches
    // for `options`.
    let o = unsafe { read_sized(options, defaults) }?;
    if o.flags & !KNOWN_FLAGS != 0 {
        return Err(E_INVALIDARG.into());
    }
    let authn_level = match o.authn_level {
        0 => RPC_C_AUTHN_LEVEL_PKT_INTEGRITY,
        level if level > RPC_C_AUTHN_LEVEL_PKT_PRIVACY => return Err(E_INVALIDARG.into()),
        level if level < RPC_C_AUTHN_LEVEL_PKT_INTEGRITY && o.flags & OPC_SECURITY_ALLOW_WEAKER_AUTHN == 0 => {
            return Err(E_INVALIDARG.into())
        }
        level => level,
    };
    let imp_level = match o.imp_level {
        0 if role == Role::Server => RPC_C_IMP_LEVEL_IDENTIFY,
        0 => RPC_C_IMP_LEVEL_IMPERSONATE,
        level if level > RPC_C_IMP_LEVEL_DELEGATE => return Err(E_INVALIDARG.into()),
        level => level,
    };
    // SAFETY: the caller vouches a non-NULL `appid` is readable.
    let appid = unsafe { o.appid.as_ref() }.copied();
    // SAFETY: the caller vouches a non-NULL `access_sddl` is a NUL-terminated string.
    let sddl = unsafe { ffi::in_units_opt(o.access_sddl) }?;
    let access = match (appid, sddl) {
        (Some(_), Some(_)) => return Err(E_INVALIDARG.into()),
        (Some(_), None) | (None, Some(_)) if role == Role::Proxy => return Err(E_INVALIDARG.into()),
        (Some(appid), None) => Access::AppId(appid),
        (None, Some([])) => return Err(E_INVALIDARG.into()),
        (None, Some(units)) => {
            check_access_list(units)?;
            Access::Sddl(units.to_vec())
        }
        (None, None) => Access::Anyone,
    };
    Ok(Plan {
        authn_level,
        imp_level,
        access,
    })
}

/// Off Windows, where no system reads SDDL, the access list is checked with the library's own codec
/// (`registry::sddl`, the subset registration writes): valid SDDL with an owner and a group, as
/// CoInitializeSecurity requires (the subset has no SACL). On Windows the system's conversion checks it,
/// with SDDL beyond the subset accepted.
fn check_access_list(units: &[u16]) -> Result<(), HRESULT> {
    #[cfg(not(windows))]
    {
        let text = String::from_utf16(units).map_err(|_| E_INVALIDARG)?;
        let sd = crate::registry::sddl::SecurityDescriptor::parse(&text)?;
        if sd.owner.is_none() || sd.group.is_none() {
            return Err(E_INVALIDARG);
        }
    }
    #[cfg(windows)]
    let _ = units;
    Ok(())
}

/// The nine arguments of one CoInitializeSecurity call, exactly as the library passes them.
// Off Windows only the tests read them: there is no COM to pass them to.
#[cfg_attr(not(windows), allow(dead_code))]
#[derive(Clone, Copy, Debug)]
pub(crate) struct CoInitializeSecurityArgs {
    /// NULL, the AppID (with EOAC_APPID) or an absolute SECURITY_DESCRIPTOR.
    pub sec_desc: *const c_void,
    /// -1: COM chooses the authentication services.
    pub auth_svc_count: i32,
    pub auth_svc: *const c_void,
    pub reserved1: *const c_void,
    pub authn_level: u32,
    pub imp_level: u32,
    pub auth_list: *const c_void,
    pub capabilities: u32,
    pub reserved3: *const c_void,
}

/// The eight arguments of one CoSetProxyBlanket call, exactly as the library passes them.
#[cfg_attr(not(windows), allow(dead_code))]
#[derive(Clone, Copy, Debug)]
pub(crate) struct CoSetProxyBlanketArgs {
    pub proxy: *mut IUnknown,
    pub authn_svc: u32,
    pub authz_svc: u32,
    pub server_principal: LPCWSTR,
    pub authn_level: u32,
    pub imp_level: u32,
    pub auth_info: *const c_void,
    pub capabilities: u32,
}

/// Process security is set once per process; this remembers that the library set it.
pub(crate) struct ProcessSecurity {
    done: Mutex<bool>,
}

/// This process's.
static PROCESS: ProcessSecurity = ProcessSecurity::new();

impl ProcessSecurity {
    pub(crate) const fn new() -> ProcessSecurity {
        ProcessSecurity {
            done: Mutex::new(false),
        }
    }

    /// Checks `options`, then, unless an earlier call succeeded (RPC_E_TOO_LATE), builds the access
    /// list and makes the call through `call`, under a lock so that one of two racing calls wins.
    ///
    /// # Safety
    /// As for [`plan`].
    pub(crate) unsafe fn initialize(
        &self,
        role: Role,
        options: *const OpcSecurityOptions,
        call: impl FnOnce(&CoInitializeSecurityArgs) -> HRESULT,
    ) -> FfiResult {
        // SAFETY: forwarded from the caller's contract.
        let plan = unsafe { plan(role, options) }?;
        let mut done = self.done.lock().unwrap_or_else(|e| e.into_inner());
        if *done {
            return Err(RPC_E_TOO_LATE.into());
        }
        let hr = call_with_access(&plan, call)?;
        if hr < 0 {
            return Err(hr.into());
        }
        *done = true;
        Ok(hr)
    }
}

/// Makes the call with `plan`'s access list as COM wants it.
fn call_with_access(plan: &Plan, call: impl FnOnce(&CoInitializeSecurityArgs) -> HRESULT) -> FfiResult {
    let args = |sec_desc: *const c_void, capabilities: u32| CoInitializeSecurityArgs {
        sec_desc,
        auth_svc_count: -1,
        auth_svc: ptr::null(),
        reserved1: ptr::null(),
        authn_level: plan.authn_level,
        imp_level: plan.imp_level,
        auth_list: ptr::null(),
        capabilities,
        reserved3: ptr::null(),
    };
    match &plan.access {
        Access::Anyone => Ok(call(&args(ptr::null(), EOAC_NONE))),
        Access::AppId(appid) => Ok(call(&args((appid as *const GUID).cast(), EOAC_APPID))),
        #[cfg(windows)]
        Access::Sddl(sddl) => {
            let descriptor = windows::AbsoluteDescriptor::from_sddl(sddl)?;
            let hr = call(&args(descriptor.as_ptr(), EOAC_NONE));
            if hr >= 0 {
                // COM's documentation does not say that CoInitializeSecurity copies the descriptor:
                // it stays for the life of the process (once per process, a few hundred bytes).
                core::mem::forget(descriptor);
            }
            Ok(hr)
        }
        #[cfg(not(windows))]
        Access::Sddl(_) => Err(crate::com::E_NOTIMPL.into()),
    }
}

/// Checks `options` for a proxy, then calls `set` for `proxy` and, when that succeeds, for its
/// IUnknown (queried and released here).
///
/// # Safety
/// `proxy` must be NULL or a valid COM interface pointer; `options` as for [`plan`].
pub(crate) unsafe fn set_blanket(
    proxy: *mut IUnknown,
    options: *const OpcSecurityOptions,
    mut set: impl FnMut(&CoSetProxyBlanketArgs) -> HRESULT,
) -> FfiResult {
    let proxy = ffi::in_ptr(proxy)?.as_ptr();
    // SAFETY: forwarded from the caller's contract.
    let plan = unsafe { plan(Role::Proxy, options) }?;
    let args = |proxy: *mut IUnknown| CoSetProxyBlanketArgs {
        proxy,
        authn_svc: RPC_C_AUTHN_DEFAULT,
        authz_svc: RPC_C_AUTHZ_DEFAULT,
        server_principal: COLE_DEFAULT_PRINCIPAL,
        authn_level: plan.authn_level,
        imp_level: plan.imp_level,
        auth_info: COLE_DEFAULT_AUTHINFO,
        capabilities: EOAC_DEFAULT,
    };
    let hr = set(&args(proxy));
    if hr < 0 {
        return Err(hr.into());
    }
    // QueryInterface, AddRef and Release go through the proxy manager's IUnknown (IRemUnknown), which
    // has its own blanket.
    // SAFETY: the caller vouches for `proxy`.
    let unknown = unsafe { query::<IUnknown>(proxy, &IID_IUNKNOWN) }?;
    let hr = set(&args(unknown.as_ptr()));
    drop(unknown);
    if hr < 0 {
        return Err(hr.into());
    }
    Ok(S_OK)
}

/// Sets the process security of an OPC server (CoInitializeSecurity), hardened: authentication at
/// RPC_C_AUTHN_LEVEL_PKT_INTEGRITY (or what `options->authn_level` asks, never below PKT_INTEGRITY
/// without `OPC_SECURITY_ALLOW_WEAKER_AUTHN`), impersonation RPC_C_IMP_LEVEL_IDENTIFY (the server
/// learns who calls but cannot act as the caller), and for access: EOAC_APPID with
/// `options->appid` (COM then takes the settings from the AppID's registry key), else the access list
/// `options->access_sddl`, else none (everyone who authenticates at the level may call). The other
/// arguments: COM chooses the authentication services (-1), no authentication list.
///
/// Call it once, early: after CoInitializeEx and before the process marshals anything (registering
/// class objects, creating or receiving proxies), because COM sets process security once, implicitly
/// at the first marshalling if nobody called CoInitializeSecurity.
///
/// # Parameters
/// - `options`: the settings (OpcSecurityOptions), or NULL for the defaults above.
///
/// # Returns
/// S_OK; E_INVALIDARG for a `struct_size` other than `sizeof(OpcSecurityOptions)`, an unknown flag, a
/// level out of range or below PKT_INTEGRITY without the flag, both `appid` and `access_sddl`, or an
/// access list that is empty, is no valid SDDL, names no owner or group, or has a SACL (Windows'
/// conversion error, as an HRESULT, where it gives one); RPC_E_TOO_LATE when process security is
/// already set: by an earlier successful call of this function or `OpcInitializeClientSecurity` (the
/// library answers that itself, without calling COM), or, on Windows, by the process itself or
/// implicitly by COM (CoInitializeSecurity's answer); otherwise CoInitializeSecurity's result as it is
/// (on Windows CO_E_NOTINITIALIZED before CoInitializeEx). Off Windows the options are checked as
/// above (the access list with the library's SDDL subset, that of registration:
/// `docs/guide/dcom-appid.md`), then the result is E_NOTIMPL.
///
/// # Safety
/// `options` must be NULL or point at `options->struct_size` readable bytes; its `appid` NULL or
/// readable, its `access_sddl` NULL or a NUL-terminated UTF-16 string.
#[no_mangle]
pub unsafe extern "C" fn OpcInitializeServerSecurity(options: *const OpcSecurityOptions) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: forwarded from the caller's contract.
        unsafe { PROCESS.initialize(Role::Server, options, system::co_initialize_security) }
    })
}

/// Sets the process security of an OPC client (CoInitializeSecurity), hardened: as
/// `OpcInitializeServerSecurity`, with impersonation RPC_C_IMP_LEVEL_IMPERSONATE by default (the
/// level servers expect of clients). A client is a DCOM server for the callbacks it receives
/// (IOPCShutdown::ShutdownRequest, data callbacks): a client that receives them from another machine
/// needs PKT_INTEGRITY here too, and `access_sddl` (or `appid`) decides who may call it back.
///
/// # Parameters
/// - `options`: the settings (OpcSecurityOptions), or NULL for the defaults.
///
/// # Returns
/// What `OpcInitializeServerSecurity` returns; off Windows E_NOTIMPL after checking the options.
///
/// # Safety
/// As for `OpcInitializeServerSecurity`.
#[no_mangle]
pub unsafe extern "C" fn OpcInitializeClientSecurity(options: *const OpcSecurityOptions) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: forwarded from the caller's contract.
        unsafe { PROCESS.initialize(Role::Client, options, system::co_initialize_security) }
    })
}

/// Sets the authentication of one proxy (CoSetProxyBlanket), for clients that cannot set their
/// process security: on the proxy and on its IUnknown (queried, set, released), because QueryInterface,
/// AddRef and Release travel through the IUnknown's own blanket. Authentication at
/// RPC_C_AUTHN_LEVEL_PKT_INTEGRITY or `options->authn_level` (never below PKT_INTEGRITY without
/// `OPC_SECURITY_ALLOW_WEAKER_AUTHN`), impersonation RPC_C_IMP_LEVEL_IMPERSONATE or
/// `options->imp_level`; the authentication and authorization services, the server principal name,
/// the identity and the capabilities stay the proxy's (RPC_C_AUTHN_DEFAULT, RPC_C_AUTHZ_DEFAULT,
/// COLE_DEFAULT_PRINCIPAL, COLE_DEFAULT_AUTHINFO, EOAC_DEFAULT). Each further interface the client
/// queries from the object gets a new proxy with the process's blanket: set it on each.
///
/// # Parameters
/// - `proxy`: the interface pointer (a proxy) to secure.
/// - `options`: the settings (OpcSecurityOptions; its `appid` and `access_sddl` must be NULL), or NULL
///   for the defaults.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `proxy`, bad options (as `OpcInitializeServerSecurity`), or an
/// `appid` or `access_sddl`; E_NOINTERFACE when `proxy` is not a proxy (an in-process object has no
/// IClientSecurity; nothing to secure, and nothing is changed); otherwise CoSetProxyBlanket's result
/// for the interface or, when that succeeded, for its IUnknown (the interface's blanket then stays
/// set), or QueryInterface's failure. Off Windows E_NOTIMPL after checking the arguments.
///
/// # Safety
/// `proxy` must be NULL or a valid COM interface pointer; `options` as for
/// `OpcInitializeServerSecurity`.
#[no_mangle]
pub unsafe extern "C" fn OpcSetProxyBlanket(proxy: *mut IUnknown, options: *const OpcSecurityOptions) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: forwarded from the caller's contract.
        unsafe { set_blanket(proxy, options, system::co_set_proxy_blanket) }
    })
}

/// The system's functions behind the seam.
mod system {
    use super::{CoInitializeSecurityArgs, CoSetProxyBlanketArgs};
    use crate::com::HRESULT;

    /// CoInitializeSecurity with `a`.
    #[cfg(windows)]
    pub(super) fn co_initialize_security(a: &CoInitializeSecurityArgs) -> HRESULT {
        // SAFETY: the arguments are what CoInitializeSecurity documents: NULL, an AppID with
        // EOAC_APPID, or an absolute security descriptor that outlives the call.
        unsafe {
            windows_sys::Win32::System::Com::CoInitializeSecurity(
                a.sec_desc.cast_mut(),
                a.auth_svc_count,
                a.auth_svc.cast(),
                a.reserved1,
                a.authn_level,
                a.imp_level,
                a.auth_list,
                a.capabilities as _,
                a.reserved3,
            )
        }
    }

    /// CoSetProxyBlanket with `a`.
    #[cfg(windows)]
    pub(super) fn co_set_proxy_blanket(a: &CoSetProxyBlanketArgs) -> HRESULT {
        // SAFETY: `a.proxy` is a valid interface pointer (the export's contract, or one this library
        // queried); the other arguments are CoSetProxyBlanket's documented "keep the default" values.
        unsafe {
            windows_sys::Win32::System::Com::CoSetProxyBlanket(
                a.proxy.cast(),
                a.authn_svc,
                a.authz_svc,
                a.server_principal,
                a.authn_level,
                a.imp_level,
                a.auth_info,
                a.capabilities as _,
            )
        }
    }

    /// Off Windows there is no COM security to set.
    #[cfg(not(windows))]
    pub(super) fn co_initialize_security(_: &CoInitializeSecurityArgs) -> HRESULT {
        crate::com::E_NOTIMPL
    }

    /// Off Windows there are no proxies.
    #[cfg(not(windows))]
    pub(super) fn co_set_proxy_blanket(_: &CoSetProxyBlanketArgs) -> HRESULT {
        crate::com::E_NOTIMPL
    }
}
