//! The specification's component category helpers (section 6.3: CreateComponentCategory,
//! RegisterCLSIDInCategory, UnRegisterCLSIDInCategory) and the standard category descriptions.

use super::categories::standard_description;
use super::register::LCID_ENGLISH;
use super::{registries, OpcRegistry};
use crate::com::alloc::alloc_wstr_from_str;
use crate::com::ffi::{self, FfiResult, Hr};
use crate::com::{CATID, E_INVALIDARG, GUID, LPCWSTR, LPWSTR, REFCLSID, S_OK};

/// Reads a GUID argument: NULL gives the rule's code.
///
/// # Safety
/// `p` NULL or readable.
unsafe fn guid_arg(p: *const GUID) -> FfiResult<GUID> {
    // SAFETY: forwarded.
    unsafe { ffi::in_ref(p) }.copied()
}

/// Creates a component category with its English (0x409) description, as the specification's
/// CreateComponentCategory helper: `Component Categories\{catid}`, value `409`. On Windows this goes
/// through the Component Categories Manager (ICatRegister::RegisterCategories) when COM can create it
/// on the calling thread; where COM is not initialised (a server registering before CoInitializeEx)
/// the library writes the same value itself.
///
/// # Parameters
/// - `reg`: the registry, or NULL for the system registry.
/// - `catid`: the category.
/// - `description`: its description, at most 127 characters (the limit of CATEGORYINFO); NULL for the
///   standard text of an OPC category.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `catid`; E_INVALIDARG for a NULL description of a category that is
/// not an OPC one, or a description over 127 characters; registry errors.
///
/// # Safety
/// `reg` NULL or a live handle; `catid` NULL or readable; `description` NULL or NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn OpcCreateComponentCategory(
    reg: *const OpcRegistry,
    catid: *const CATID,
    description: LPCWSTR,
) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller's contract: `catid` NULL or readable, `description` NULL or
        // NUL-terminated.
        let (catid, given) = unsafe { (guid_arg(catid)?, ffi::in_string_opt(description)?) };
        let text = match given {
            Some(t) => t,
            None => standard_description(&catid).ok_or(E_INVALIDARG)?.to_string(),
        };
        if text.encode_utf16().count() > 127 {
            return Err(E_INVALIDARG.into());
        }
        // SAFETY: `reg` NULL or a live handle.
        unsafe { registries(reg) }
            .write
            .register_category(&catid, LCID_ENGLISH, &text)?;
        Ok(S_OK)
    })
}

/// Registers a class as implementing a category (the specification's RegisterCLSIDInCategory):
/// `CLSID\{clsid}\Implemented Categories\{catid}`. On Windows through the Component Categories
/// Manager when COM can create it on the calling thread, else (COM not initialised there) by creating
/// the key itself.
///
/// # Parameters
/// - `reg`: the registry, or NULL for the system registry.
/// - `clsid`: the class.
/// - `catid`: the category it implements.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `clsid` or `catid`; registry errors.
///
/// # Safety
/// `reg` NULL or a live handle; `clsid` and `catid` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn OpcRegisterClassInCategory(
    reg: *const OpcRegistry,
    clsid: REFCLSID,
    catid: *const CATID,
) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller's contract: `clsid` and `catid` NULL or readable.
        let (clsid, catid) = unsafe { (guid_arg(clsid)?, guid_arg(catid)?) };
        // SAFETY: `reg` NULL or a live handle.
        unsafe { registries(reg) }
            .write
            .register_class_category(&clsid, &catid, false)?;
        Ok(S_OK)
    })
}

/// Removes a class from a category (the specification's UnRegisterCLSIDInCategory): deletes
/// `CLSID\{clsid}\Implemented Categories\{catid}`, through the Component Categories Manager or
/// directly as `OpcRegisterClassInCategory` does. Succeeds when it was not registered.
///
/// # Parameters
/// - `reg`: the registry, or NULL for the system registry.
/// - `clsid`: the class.
/// - `catid`: the category.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `clsid` or `catid`; registry errors.
///
/// # Safety
/// As for `OpcRegisterClassInCategory`.
#[no_mangle]
pub unsafe extern "C" fn OpcUnregisterClassInCategory(
    reg: *const OpcRegistry,
    clsid: REFCLSID,
    catid: *const CATID,
) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller's contract: `clsid` and `catid` NULL or readable.
        let (clsid, catid) = unsafe { (guid_arg(clsid)?, guid_arg(catid)?) };
        // SAFETY: `reg` NULL or a live handle.
        unsafe { registries(reg) }
            .write
            .unregister_class_category(&clsid, &catid, false)?;
        Ok(S_OK)
    })
}

/// The standard English description of an OPC component category (for example "OPC Data Access
/// Servers Version 2.0" for CATID_OPCDAServer20).
///
/// # Parameters
/// - `catid`: the category.
/// - `description` (out): receives a new string (free it with `OpcTaskMemFree`), or NULL on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL argument; E_INVALIDARG for a category that is not an OPC one.
///
/// # Safety
/// `catid` NULL or readable; `description` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcCategoryDescription(catid: *const CATID, description: *mut LPWSTR) -> Hr {
    ffi::boundary!(Opc, [description], {
        // SAFETY: the caller's contract: `catid` NULL or readable, `description` NULL or writable.
        let (catid, description) = unsafe { (guid_arg(catid)?, ffi::out(description)?) };
        description.write(alloc_wstr_from_str(standard_description(&catid).ok_or(E_INVALIDARG)?)?);
        Ok(S_OK)
    })
}
