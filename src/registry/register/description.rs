//! The C description of a server's registration, [`OpcServerRegistration`], and its validation into
//! the [`ServerDescription`] the rest of the registration code works with.

use crate::com::ffi::{self, Fail, FfiResult};
use crate::com::options::{read_sized, SizedStruct};
use crate::com::{CATID, CLSID, E_INVALIDARG, GUID, HRESULT, LPCWSTR};
use crate::registry::sddl::SecurityDescriptor;
use crate::registry::MAX_NAME_UNITS;

/// The most categories one registration may list.
const MAX_CATEGORIES: usize = 256;

/// How a server is packaged.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpcServerType {
    /// A DLL loaded into the client: `InprocServer32`.
    Inproc = 0,
    /// An EXE started by COM: `LocalServer32`.
    Local = 1,
}

/// `OpcServerRegistration::flags`: leave values that already exist as they are, instead of replacing
/// them, except the server's own module key (`InprocServer32` / `LocalServer32`). For a class that
/// another product registers too (opccomn's own server list under the CLSID of OpcEnum).
pub const OPC_REGISTRATION_KEEP_EXISTING: u32 = 1;

/// `RPC_C_AUTHN_LEVEL_PKT_INTEGRITY`: the `AuthenticationLevel` registration gives an AppID unless
/// told otherwise, the lowest level Windows accepts for activation since its DCOM hardening
/// (KB5004442, enforced since March 2023).
pub const OPC_AUTHN_LEVEL_PKT_INTEGRITY: u32 = 5;

/// `RPC_C_AUTHN_LEVEL_PKT_PRIVACY`, the highest authentication level.
const AUTHN_LEVEL_PKT_PRIVACY: u32 = 6;

/// A server's registration, described once and passed to `OpcRegisterServer`,
/// `OpcUnregisterServer` and `OpcRegistrationExport`. Zero-initialise it, set `struct_size` to
/// `sizeof(OpcServerRegistration)` and fill what applies; NULL strings and arrays mean "none". Fields
/// added in later versions go at the end; the library reads only `struct_size` bytes, and takes the
/// fields of a shorter (older) structure as zero.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct OpcServerRegistration {
    /// `sizeof(OpcServerRegistration)` as the caller's header declares it.
    pub struct_size: u32,
    /// `OpcServerType`: in-process (0, `InprocServer32`) or local (1, `LocalServer32`).
    pub server_type: u32,
    /// The server's class identifier.
    pub clsid: CLSID,
    /// The ProgID, `Vendor.Server.1` (required; no backslash, at most 255 characters).
    pub prog_id: LPCWSTR,
    /// The version-independent ProgID, `Vendor.Server` (optional).
    pub version_independent_prog_id: LPCWSTR,
    /// The description users see (required), for example "My OPC Server".
    pub user_type: LPCWSTR,
    /// Full path of the server's DLL or EXE, without quotes: `LocalServer32` gets it in quotes (a
    /// path with blanks unquoted could start another program), `InprocServer32` as it is. A value
    /// holding a quote is taken as a complete command line and written as given. NULL means: for a local server the executable of the
    /// calling process (what an EXE server handling `/RegServer` wants); for an in-process server the
    /// module that contains the opccomn code (the server DLL when it links opccomn statically; opccomn
    /// itself when it is loaded as opccomn.dll, so a server DLL using opccomn.dll must pass its path).
    pub module_path: LPCWSTR,
    /// `ThreadingModel` of an in-process server: "Apartment", "Free", "Both" or "Neutral"; NULL writes
    /// none (COM then uses the main apartment). Ignored for local servers.
    pub threading_model: LPCWSTR,
    /// The categories the server implements (for example `CATID_OPCDAServer20`).
    pub implemented_categories: *const CATID,
    /// Number of entries in `implemented_categories` (at most 256).
    pub implemented_category_count: u32,
    /// Descriptions of the implemented categories, parallel to `implemented_categories`: used to
    /// create a category that does not exist yet. NULL (the array or an entry) uses the standard text
    /// for OPC categories; a category with no description is registered without being created.
    pub implemented_category_descriptions: *const LPCWSTR,
    /// The categories a client must support to use the server (`Required Categories`).
    pub required_categories: *const CATID,
    /// Number of entries in `required_categories` (at most 256).
    pub required_category_count: u32,
    /// For Data Access 1.0 servers only: the vendor name written to `<ProgID>\OPC\Vendor`, by which
    /// OpcEnum and DA 1.0 clients find servers registered the old way.
    pub da10_vendor: LPCWSTR,
    /// The AppID (a GUID) of a local server's DCOM settings, or NULL for none. Classes that name one
    /// AppID share it (COM applies it to their process): it holds what the latest registration wrote,
    /// and stays until the last of them is unregistered; give them the same settings.
    pub app_id: *const CLSID,
    /// `RunAs` of the AppID ("Interactive User", an account), or NULL.
    pub app_id_run_as: LPCWSTR,
    /// `LocalService` of the AppID (the Windows service that hosts the server), or NULL.
    pub app_id_local_service: LPCWSTR,
    /// `DllSurrogate` of the AppID ("" for the system surrogate), or NULL.
    pub app_id_dll_surrogate: LPCWSTR,
    /// `OPC_REGISTRATION_KEEP_EXISTING` or 0.
    pub flags: u32,
    /// `AccessPermission` of the AppID, as SDDL text (who may call the server; for example
    /// `O:BAG:BAD:(A;;0x7;;;AU)(A;;0x7;;;SY)`), written as the binary self-relative security
    /// descriptor dcomcnfg writes; NULL writes none (the machine's default access permission then
    /// applies). Owner, group and a DACL of allow and deny ACEs: docs/guide/dcom-appid.md says which
    /// SDDL is accepted. Needs `app_id`. (Version 2 of the structure.)
    pub app_id_access_permission: LPCWSTR,
    /// `LaunchPermission` of the AppID, as SDDL text (who may start and activate the server, for
    /// example `O:BAG:BAD:(A;;0x1F;;;BA)(A;;0x1F;;;SY)(A;;0xB;;;IU)`), as for
    /// `app_id_access_permission`; NULL writes none (the machine's default launch permission applies).
    /// Needs `app_id`. (Version 2 of the structure.)
    pub app_id_launch_permission: LPCWSTR,
    /// `AuthenticationLevel` of the AppID, an `RPC_C_AUTHN_LEVEL_*` value: 0 gives
    /// `OPC_AUTHN_LEVEL_PKT_INTEGRITY` (5), the level every AppID gets unless told otherwise (also when
    /// an older, shorter structure is passed); 1 to 6 is written as given. Below 5 (NONE 1, CONNECT 2,
    /// CALL 3, PKT 4), clients on other machines cannot activate the server since Windows' DCOM
    /// hardening (KB5004442, CVE-2021-26414), and `opccomn-check --dcom` fails the AppID: set a lower
    /// level only for a reason. A value above 6, or a level without `app_id`, is E_INVALIDARG.
    /// (Version 2 of the structure.)
    pub app_id_authentication_level: u32,
}

// SAFETY: repr(C), struct_size first; integers, a GUID and raw pointers.
unsafe impl SizedStruct for OpcServerRegistration {
    /// Every size at which a version of OpcServerRegistration ends, after its last field, with or
    /// without C's trailing padding.
    const SIZES: &'static [usize] = {
        use core::mem::{offset_of, size_of};
        type R = OpcServerRegistration;
        &[
            // Version 1: up to `flags`.
            offset_of!(R, flags) + size_of::<u32>(),
            offset_of!(R, app_id_access_permission),
            // Version 2: the AppID's security.
            offset_of!(R, app_id_authentication_level) + size_of::<u32>(),
            size_of::<R>(),
        ]
    };
}

/// A registration as the library works with it.
#[derive(Clone, Debug, Default)]
pub struct ServerDescription {
    pub clsid: GUID,
    pub local: bool,
    pub prog_id: String,
    pub version_independent_prog_id: Option<String>,
    pub user_type: String,
    /// `None`: this module (see `OpcServerRegistration::module_path`).
    pub module_path: Option<String>,
    pub threading_model: Option<String>,
    /// Implemented categories, each with the description to create it with (if any).
    pub implemented: Vec<(GUID, Option<String>)>,
    pub required: Vec<GUID>,
    pub da10_vendor: Option<String>,
    pub app_id: Option<GUID>,
    pub run_as: Option<String>,
    pub local_service: Option<String>,
    pub dll_surrogate: Option<String>,
    /// `AuthenticationLevel` given explicitly (1 to 6); `None` writes PKT_INTEGRITY with an AppID.
    pub authentication_level: Option<u32>,
    /// `AccessPermission` as SDDL text.
    pub access_permission: Option<String>,
    /// `LaunchPermission` as SDDL text.
    pub launch_permission: Option<String>,
    pub keep_existing: bool,
}

fn valid_prog_id(p: &str) -> bool {
    !p.trim().is_empty() && !p.contains('\\') && p.encode_utf16().count() <= MAX_NAME_UNITS
}

/// Reads `count` entries of a caller's category array (at most 256; a count without an array, or a
/// NULL array with a count, is E_INVALIDARG: these are fields of a struct, not pointer arguments).
///
/// # Safety
/// `p` must point at `count` readable entries when `count` is not 0.
unsafe fn categories<'a, T>(p: *const T, count: u32) -> FfiResult<&'a [T]> {
    // SAFETY: forwarded from the caller.
    unsafe { ffi::in_array(p, count, MAX_CATEGORIES) }.map_err(|_| Fail::Code(E_INVALIDARG))
}

impl ServerDescription {
    /// Reads and checks a caller's registration.
    ///
    /// # Safety
    /// `r` must be NULL or valid as documented on OpcServerRegistration.
    pub unsafe fn read(r: *const OpcServerRegistration) -> FfiResult<ServerDescription> {
        if r.is_null() {
            return Err(Fail::Null);
        }
        // SAFETY: all zero is a valid OpcServerRegistration (integers, a GUID and raw pointers).
        let defaults: OpcServerRegistration = unsafe { core::mem::zeroed() };
        // SAFETY: the caller vouches for `struct_size` readable bytes; read_sized copies no more, and
        // only sizes at which a version of the structure ends.
        let r = unsafe { read_sized(r, defaults) }?;
        let r = &r;
        let local = match r.server_type {
            0 => false,
            1 => true,
            _ => return Err(E_INVALIDARG.into()),
        };
        if r.flags & !OPC_REGISTRATION_KEEP_EXISTING != 0 {
            return Err(E_INVALIDARG.into());
        }
        // SAFETY: the structure's contract covers every pointer read below.
        unsafe {
            let implemented = categories(r.implemented_categories, r.implemented_category_count)?;
            let descriptions: &[LPCWSTR] = if r.implemented_category_descriptions.is_null() {
                &[]
            } else {
                categories(r.implemented_category_descriptions, r.implemented_category_count)?
            };
            let mut cats = Vec::with_capacity(implemented.len());
            for (i, catid) in implemented.iter().enumerate() {
                let given = match descriptions.get(i) {
                    Some(&p) => ffi::in_string_opt(p)?,
                    None => None,
                };
                cats.push((*catid, given));
            }
            let d = ServerDescription {
                clsid: r.clsid,
                local,
                prog_id: ffi::in_string(r.prog_id)?,
                version_independent_prog_id: ffi::in_string_opt(r.version_independent_prog_id)?,
                user_type: ffi::in_string(r.user_type)?,
                module_path: ffi::in_string_opt(r.module_path)?,
                threading_model: ffi::in_string_opt(r.threading_model)?,
                implemented: cats,
                required: categories(r.required_categories, r.required_category_count)?.to_vec(),
                da10_vendor: ffi::in_string_opt(r.da10_vendor)?,
                app_id: r.app_id.as_ref().copied(),
                run_as: ffi::in_string_opt(r.app_id_run_as)?,
                local_service: ffi::in_string_opt(r.app_id_local_service)?,
                dll_surrogate: ffi::in_string_opt(r.app_id_dll_surrogate)?,
                authentication_level: match r.app_id_authentication_level {
                    0 => None,
                    level => Some(level),
                },
                access_permission: ffi::in_string_opt(r.app_id_access_permission)?,
                launch_permission: ffi::in_string_opt(r.app_id_launch_permission)?,
                keep_existing: r.flags & OPC_REGISTRATION_KEEP_EXISTING != 0,
            };
            d.check()?;
            Ok(d)
        }
    }

    pub(super) fn check(&self) -> Result<(), HRESULT> {
        if !valid_prog_id(&self.prog_id)
            || self
                .version_independent_prog_id
                .as_deref()
                .is_some_and(|p| !valid_prog_id(p))
        {
            return Err(E_INVALIDARG);
        }
        if self.module_path.as_deref().is_some_and(str::is_empty) {
            return Err(E_INVALIDARG);
        }
        // The AppID's security: a level from 1 to 6, permissions in the SDDL the library converts,
        // and neither without an AppID to hold them.
        if self
            .authentication_level
            .is_some_and(|l| !(1..=AUTHN_LEVEL_PKT_PRIVACY).contains(&l))
        {
            return Err(E_INVALIDARG);
        }
        for sddl in [&self.access_permission, &self.launch_permission].into_iter().flatten() {
            SecurityDescriptor::parse(sddl)?;
        }
        let security =
            self.authentication_level.is_some() || self.access_permission.is_some() || self.launch_permission.is_some();
        if security && self.app_id.is_none() {
            return Err(E_INVALIDARG);
        }
        Ok(())
    }

    /// The AppID's `AuthenticationLevel`: as given, else PKT_INTEGRITY.
    pub(super) fn authentication_level(&self) -> u32 {
        self.authentication_level.unwrap_or(OPC_AUTHN_LEVEL_PKT_INTEGRITY)
    }

    pub(super) fn module_path(&self) -> Result<String, HRESULT> {
        match &self.module_path {
            Some(p) => Ok(p.clone()),
            None => this_module_path(self.local),
        }
    }
}

/// The path of the module registration writes when none is given.
#[cfg(windows)]
pub(crate) fn this_module_path(local: bool) -> Result<String, HRESULT> {
    if local {
        crate::registry::windows::module_file_name(core::ptr::null_mut())
    } else {
        crate::registry::windows::module_file_name(crate::registry::windows::this_module())
    }
}

/// The path of the module registration writes when none is given.
#[cfg(not(windows))]
pub(crate) fn this_module_path(local: bool) -> Result<String, HRESULT> {
    use crate::com::E_FAIL;
    if local {
        return std::env::current_exe()
            .ok()
            .and_then(|p| p.to_str().map(str::to_string))
            .ok_or(E_FAIL);
    }
    // SAFETY: dladdr only reads the address and fills `info`; `dli_fname` is NUL-terminated when set.
    unsafe {
        let mut info: libc::Dl_info = core::mem::zeroed();
        if libc::dladdr(this_module_path as *const libc::c_void, &mut info) == 0 || info.dli_fname.is_null() {
            return Err(E_FAIL);
        }
        let name = core::ffi::CStr::from_ptr(info.dli_fname).to_str().map_err(|_| E_FAIL)?;
        Ok(std::fs::canonicalize(name)
            .ok()
            .and_then(|p| p.to_str().map(str::to_string))
            .unwrap_or(name.to_string()))
    }
}
