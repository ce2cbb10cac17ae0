//! Registration helpers for server authors (specification sections 6.1 and 6.3).
//!
//! A server describes itself once in an [`OpcServerRegistration`] and registers or unregisters with one
//! call. Registration writes what COM and the specification require:
//!
//! ```text
//! CLSID\{clsid}                          @ = user type          [AppID = {appid}]
//! CLSID\{clsid}\ProgID                   @ = ProgID
//! CLSID\{clsid}\VersionIndependentProgID @ = version-independent ProgID
//! CLSID\{clsid}\InprocServer32           @ = module path, ThreadingModel = ...   (in-process server)
//! CLSID\{clsid}\LocalServer32            @ = "module path" (quoted command line) (EXE server)
//! CLSID\{clsid}\Implemented Categories\{catid}   (through the Component Categories Manager on Windows)
//! CLSID\{clsid}\Required Categories\{catid}
//! Component Categories\{catid}           409 = standard description (created when missing)
//! <ProgID>                               @ = user type
//! <ProgID>\CLSID                         @ = {clsid}
//! <ProgID>\OPC\Vendor                    @ = vendor name       (Data Access 1.0 servers only)
//! <VersionIndependentProgID>             @ = user type
//! <VersionIndependentProgID>\CLSID       @ = {clsid}
//! <VersionIndependentProgID>\CurVer      @ = ProgID
//! AppID\{appid}                          @ = user type, RunAs, LocalService, DllSurrogate (as given),
//!                                        AuthenticationLevel (DWORD: as given, else 5 = PKT_INTEGRITY),
//!                                        AccessPermission, LaunchPermission (REG_BINARY
//!                                        self-relative security descriptors, from SDDL; see
//!                                        registry::sddl)
//! AppID\<exe file name>                  AppID = {appid}       (EXE servers with an AppID)
//! ```
//!
//! Unregistration removes exactly what registration added, nothing that was there before and nothing
//! another product wrote. To know what it added, registration keeps a ledger in the value
//! `OpcComnRegistration` of the server's own module key (`InprocServer32` or `LocalServer32`): the keys
//! it created, the values it added or changed with the data it wrote, and the previous data of values
//! it changed. Unregistration deletes the added values and restores the changed ones *only while they
//! still hold the data it wrote* (a value someone rewrote since is theirs: it is neither deleted nor
//! set back to stale data), and deletes the created keys that are then empty. A category description
//! is left in place while another class still implements the category. Registering twice is
//! harmless: the ledger keeps what the first registration found and follows what the last one wrote.
//! When the class serves another server since this registration (its program now in the own module
//! key, or another server registered in the other module key *after* this registration: OpcEnum
//! installed later next to opccomn's in-process server list or over the browser), the entries the
//! class shares with it (class key, ProgIDs, categories) may be its too, so unregistration adds
//! nothing back there and deletes only its own entries (its AppID keys; its module key while that
//! still names this server). Without a ledger (a registration written by other means)
//! unregistration treats the values whose data is what this registration would write as added by it,
//! under the same rules. `LocalServer32` is written as a command line with the path in quotes
//! (CWE-428), `InprocServer32` as the plain DLL path COM loads. The ledger records the AppID's DWORD
//! and binary values with their type, and they follow the same rule: a level or permission another
//! installer or an administrator changed since stays. An AppID several classes name is shared: it
//! stays whole while another registered class names it (the leaving class hands its record of it to
//! theirs) and goes with the last, back to what was there before the first (`app_id`). See
//! docs/registration-safety.md and docs/guide/dcom-appid.md.
//!
//! Files, one concern each: `description` (the C struct and its validation), `keys` (the key list),
//! `ledger` (the record format of what was written), `algorithm` (register and unregister), `app_id`
//! (the AppID several classes share), `service` (the Windows service the EXE host's `/Service`
//! registers, and its record); the category helpers of the specification are in
//! `registry::category_helpers`.

mod algorithm;
mod app_id;
mod description;
mod keys;
mod ledger;
mod service;

pub(crate) use algorithm::{register, unregister, LCID_ENGLISH};
pub(crate) use description::this_module_path;
pub use description::{
    OpcServerRegistration, OpcServerType, ServerDescription, OPC_AUTHN_LEVEL_PKT_INTEGRITY,
    OPC_REGISTRATION_KEEP_EXISTING,
};
pub(crate) use ledger::{read_ledger, Entry, Recorder, LEDGER};
#[cfg(windows)]
pub(crate) use service::{recorded_service, register_service, unregister_service, NewService, ServiceManager};
pub(crate) use service::{valid_service_name, ServiceOptions, LOCAL_SERVICE, SERVICE_ACCOUNTS};

use crate::com::alloc::alloc_wstr_from_str;
use crate::com::ffi::{self, Hr};
use crate::com::{HRESULT, LPWSTR, S_OK};
use crate::registry::{registries, OpcRegistry, Registries};

/// Registers a server. Writes the CLSID, ProgID, version-independent ProgID and CurVer keys, `InprocServer32`
/// (the DLL path, with `ThreadingModel`) or `LocalServer32` (the EXE path in quotes), the AppID, the
/// categories (created with their standard descriptions when missing; on Windows through the Component
/// Categories Manager when COM can create it on the calling thread, else, COM not being initialised
/// there, as EXE servers registering before CoInitializeEx do, by writing the same keys) and, for Data
/// Access 1.0 servers, `<ProgID>\OPC\Vendor`. Records what it added so `OpcUnregisterServer` removes exactly
/// that. Registering again is harmless. Call it from DllRegisterServer, or when `OpcParseCommandLine`
/// reports OPC_SERVER_COMMAND_REGISTER (`OpcModuleRegister` and `OpcExeServerRun` call it for a
/// server on the library's plumbing).
///
/// # Parameters
/// - `server`: what to register (OpcServerRegistration).
/// - `reg`: the registry, or NULL for the system registry.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `server` or a required string that is NULL; E_INVALIDARG for a wrong
/// `struct_size`, unknown `server_type` or `flags`, a malformed ProgID, more than 256 categories or a
/// count without an array, strings that are not valid UTF-16; a registry error (for example
/// E_ACCESSDENIED without administrator rights) when a write fails.
///
/// # Safety
/// `server` NULL or valid as documented on OpcServerRegistration; `reg` NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn OpcRegisterServer(server: *const OpcServerRegistration, reg: *const OpcRegistry) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller's contract: `server` NULL or valid, `reg` NULL or a live handle.
        let (d, regs) = unsafe { (ServerDescription::read(server)?, registries(reg)) };
        register(&regs, &d)?;
        Ok(S_OK)
    })
}

/// Unregisters a server registered with `OpcRegisterServer`: removes the values and keys that registration added and restores values it replaced, leaving everything that
/// was there before and everything other products wrote. Only what still holds the data registration
/// wrote is taken back: a value rewritten since (another server registered over this one, OpcEnum
/// re-registered after a take-over) is left as it is, never set back to older data, and while the
/// class serves another server what it shares with it stays. A category's description stays while
/// another class implements the category. An AppID another registered class names stays whole (the
/// AppID key with every value, and `AppID\<exe>` while that class runs in the same program) until
/// the last of them is unregistered, which removes what the registrations wrote and restores what was
/// there before the first. Like registration it works with or without COM initialised on the calling
/// thread.
///
/// # Parameters
/// - `server`: the description it was registered with.
/// - `reg`: the registry, or NULL for the system registry.
///
/// # Returns
/// S_OK; REGDB_E_KEYMISSING when the server is not registered; the errors of `OpcRegisterServer` for a
/// bad description or a failing registry write.
///
/// # Safety
/// As for `OpcRegisterServer`.
#[no_mangle]
pub unsafe extern "C" fn OpcUnregisterServer(server: *const OpcServerRegistration, reg: *const OpcRegistry) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller's contract: `server` NULL or valid, `reg` NULL or a live handle.
        let (d, regs) = unsafe { (ServerDescription::read(server)?, registries(reg)) };
        unregister(&regs, &d)?;
        Ok(S_OK)
    })
}

/// The registration `d` would write into an empty registry, as `.reg` text.
pub(crate) fn export_registration(d: &ServerDescription) -> Result<String, HRESULT> {
    let regs = Registries::memory(std::sync::Arc::new(crate::registry::memory::MemoryRegistry::new()));
    register(&regs, d)?;
    crate::registry::regfile::export(&*regs.write, "")
}

/// A server's registration as the text of a `.reg` file ("Windows Registry Editor Version 5.00"), for
/// installers that register servers by importing a file. It holds what `OpcRegisterServer` writes into
/// an empty registry, including the record `OpcUnregisterServer` uses.
///
/// # Parameters
/// - `server`: what to register; give an explicit OpcServerRegistration::module_path (the default is
///   this process's module).
/// - `text` (out): receives the text (free it with `OpcTaskMemFree`), or NULL on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `text`; the errors of `OpcRegisterServer` for a bad description.
///
/// # Safety
/// `server` as for `OpcRegisterServer`; `text` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcRegistrationExport(server: *const OpcServerRegistration, text: *mut LPWSTR) -> Hr {
    ffi::boundary!(Opc, [text], {
        // SAFETY: the caller's contract: `text` NULL or writable, `server` NULL or valid.
        let (text, d) = unsafe { (ffi::out(text)?, ServerDescription::read(server)?) };
        text.write(alloc_wstr_from_str(&export_registration(&d)?)?);
        Ok(S_OK)
    })
}

#[cfg(test)]
pub(crate) mod tests;
#[cfg(test)]
mod tests_app_id;
#[cfg(test)]
mod tests_service;
