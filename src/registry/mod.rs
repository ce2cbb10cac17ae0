//! The registry as the server browser and the registration helpers see it (specification chapter 6).
//!
//! All registry logic of the library runs against the [`Registry`] trait, which has two
//! implementations: [`memory::MemoryRegistry`], a registry held in memory (used by the tests on every
//! platform, and as the process-wide registry off Windows), and, on Windows, the real registry under
//! `HKEY_CLASSES_ROOT` (`windows.rs`). Paths are relative to `HKEY_CLASSES_ROOT`, with `\` between
//! key names, compared without regard to case as Windows does.
//!
//! C programs see a registry as an opaque [`OpcRegistry`] handle: `OpcRegistryCreateMemory` makes an
//! empty one, `OpcRegistryOpenSystem` the system one, and every registration and server-list function
//! takes one (NULL meaning the system registry).

pub mod categories;
pub mod category_helpers;
pub mod cmdline;
pub mod memory;
pub mod path;
pub mod regfile;
pub mod register;
pub mod sddl;
pub mod version;
pub(crate) mod watch;
#[cfg(windows)]
pub mod windows;

use std::any::Any;
use std::sync::{Arc, OnceLock};

use crate::com::alloc::alloc_wstr_from_str;
use crate::com::ffi::{self, Hr};
use crate::com::{GUID, HRESULT, LPCWSTR, LPWSTR, S_OK};

/// `REGDB_E_KEYMISSING`: a registry key the operation needs is missing.
#[cfg(not(system_com_headers))]
pub const REGDB_E_KEYMISSING: HRESULT = 0x80040152_u32 as HRESULT;
/// `REGDB_E_INVALIDVALUE`: a registry value is not of the expected type or form.
#[cfg(not(system_com_headers))]
pub const REGDB_E_INVALIDVALUE: HRESULT = 0x80040153_u32 as HRESULT;

/// The longest key or value name the Windows registry accepts, in UTF-16 units.
pub(crate) const MAX_NAME_UNITS: usize = 255;

/// The most levels of keys below `HKEY_CLASSES_ROOT` a path may have: the Windows registry's limit
/// (512 levels). Deeper paths are refused with E_INVALIDARG by the in-memory registry and by
/// `.reg` import before anything is written, so no walk meets a deeper tree.
pub(crate) const MAX_KEY_DEPTH: usize = 512;

/// One registry value. Registration writes strings, and for an AppID a `REG_DWORD`
/// (`AuthenticationLevel`) and `REG_BINARY` security descriptors (`AccessPermission`,
/// `LaunchPermission`); the other kinds exist so an export of the real registry is faithful.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RegValue {
    /// `REG_SZ`.
    Sz(String),
    /// `REG_EXPAND_SZ`.
    ExpandSz(String),
    /// `REG_DWORD`.
    Dword(u32),
    /// Any other type, as its raw bytes (`REG_BINARY` is 3, `REG_MULTI_SZ` 7, ...).
    Other { kind: u32, bytes: Vec<u8> },
}

impl From<&str> for RegValue {
    fn from(text: &str) -> RegValue {
        RegValue::Sz(text.to_string())
    }
}

impl From<String> for RegValue {
    fn from(text: String) -> RegValue {
        RegValue::Sz(text)
    }
}

impl RegValue {
    /// The text of a string value (`REG_SZ` or `REG_EXPAND_SZ`, unexpanded).
    pub fn as_str(&self) -> Option<&str> {
        match self {
            RegValue::Sz(s) | RegValue::ExpandSz(s) => Some(s),
            _ => None,
        }
    }
}

/// A registry rooted at `HKEY_CLASSES_ROOT`, as the server list and the registration helpers use it.
///
/// Reads are best effort: a key that is missing or cannot be read has no subkeys and no values.
/// Writes report failures as HRESULTs. Names are compared without regard to case. The empty value
/// name is the key's default value.
pub trait Registry: Send + Sync {
    /// True when `path` exists.
    fn key_exists(&self, path: &str) -> bool;
    /// The names of the subkeys of `path`, in no particular order (empty when `path` is missing).
    fn subkeys(&self, path: &str) -> Vec<String>;
    /// The values of `path` as (name, value) pairs (empty when `path` is missing).
    fn values(&self, path: &str) -> Vec<(String, RegValue)>;
    /// The value `name` of `path`, if both exist.
    fn value(&self, path: &str, name: &str) -> Option<RegValue>;
    /// Creates `path` and any missing parents; succeeds when it exists already.
    fn create_key(&self, path: &str) -> Result<(), HRESULT>;
    /// Writes the value `name` of `path`, creating the key if needed.
    fn set_value(&self, path: &str, name: &str, value: &RegValue) -> Result<(), HRESULT>;
    /// Deletes the value `name` of `path`; succeeds when it does not exist.
    fn delete_value(&self, path: &str, name: &str) -> Result<(), HRESULT>;
    /// Deletes `path` if it has no subkeys (its values go with it); succeeds when it does not exist.
    fn delete_key(&self, path: &str) -> Result<(), HRESULT>;

    /// For each subkey of `parent`: its name, and for each of `children` (paths relative to that
    /// subkey) the subkey names below it, or `None` when it is missing. The server list's scan of
    /// `CLSID`; implementations may do it faster than one lookup at a time.
    fn scan(&self, parent: &str, children: &[&str]) -> Vec<(String, Vec<Option<Vec<String>>>)> {
        self.subkeys(parent)
            .into_iter()
            .map(|name| {
                let found = children
                    .iter()
                    .map(|child| {
                        let path = format!("{parent}\\{name}\\{child}");
                        self.key_exists(&path).then(|| self.subkeys(&path))
                    })
                    .collect();
                (name, found)
            })
            .collect()
    }

    /// For each subkey of `parent` that has the value `name`: the subkey's name and the value. What
    /// unregistration reads to find the classes that name an AppID (`CLSID`, `AppID`);
    /// implementations may do it faster than one lookup at a time.
    fn subkey_values(&self, parent: &str, name: &str) -> Vec<(String, RegValue)> {
        self.subkeys(parent)
            .into_iter()
            .filter_map(|sub| {
                let value = self.value(&format!("{parent}\\{sub}"), name)?;
                Some((sub, value))
            })
            .collect()
    }

    /// The default values of `CLSID\{clsid}` and of its `ProgID` and (when `version_independent`)
    /// `VersionIndependentProgID` subkeys; `None` when the class key does not exist. What
    /// GetClassDetails reads; implementations may read it with fewer lookups.
    fn class_strings(&self, clsid: &GUID, version_independent: bool) -> Option<ClassStrings> {
        let class = class_key(clsid);
        if !self.key_exists(&class) {
            return None;
        }
        let text = |key: &str| self.value(key, "").and_then(|v| v.as_str().map(str::to_string));
        Some(ClassStrings {
            user_type: text(&class),
            prog_id: text(&format!("{class}\\ProgID")),
            version_independent_prog_id: if version_independent {
                text(&format!("{class}\\VersionIndependentProgID"))
            } else {
                None
            },
        })
    }

    /// Creates the component category `catid` with `description` for `lcid` (the specification's
    /// CreateComponentCategory): `Component Categories\{catid}`, value `<lcid in hex>`.
    fn register_category(&self, catid: &GUID, lcid: u32, description: &str) -> Result<(), HRESULT> {
        write_category(self, catid, lcid, description)
    }

    /// Registers `clsid` as implementing (or, with `required`, requiring) `catid`:
    /// `CLSID\{clsid}\Implemented Categories\{catid}` (the specification's RegisterCLSIDInCategory).
    fn register_class_category(&self, clsid: &GUID, catid: &GUID, required: bool) -> Result<(), HRESULT> {
        self.create_key(&class_category_key(clsid, catid, required))
    }

    /// Removes what `register_class_category` wrote (the specification's UnRegisterCLSIDInCategory);
    /// the `Implemented Categories` key itself stays.
    fn unregister_class_category(&self, clsid: &GUID, catid: &GUID, required: bool) -> Result<(), HRESULT> {
        self.delete_key(&class_category_key(clsid, catid, required))
    }
}

/// What `Registry::register_category` writes, with plain registry calls.
pub(crate) fn write_category<R: Registry + ?Sized>(
    reg: &R,
    catid: &GUID,
    lcid: u32,
    text: &str,
) -> Result<(), HRESULT> {
    reg.set_value(
        &category_key(catid),
        &format!("{lcid:x}"),
        &RegValue::Sz(text.to_string()),
    )
}

/// `CLSID\{clsid}\Implemented Categories\{catid}` (or `Required Categories`).
pub(crate) fn class_category_key(clsid: &GUID, catid: &GUID, required: bool) -> String {
    format!("{}\\{catid}", class_categories_key(clsid, required))
}

/// The strings of a class that GetClassDetails reports, as registered (`None` when missing).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ClassStrings {
    /// The default value of `CLSID\{clsid}`.
    pub user_type: Option<String>,
    /// The default value of `CLSID\{clsid}\ProgID`.
    pub prog_id: Option<String>,
    /// The default value of `CLSID\{clsid}\VersionIndependentProgID`.
    pub version_independent_prog_id: Option<String>,
}

/// `CLSID\{clsid}`.
pub(crate) fn class_key(clsid: &GUID) -> String {
    format!("CLSID\\{clsid}")
}

/// `CLSID\{clsid}\Implemented Categories` (or `Required Categories`).
pub(crate) fn class_categories_key(clsid: &GUID, required: bool) -> String {
    let kind = if required { "Required" } else { "Implemented" };
    format!("CLSID\\{clsid}\\{kind} Categories")
}

/// `Component Categories\{catid}`.
pub(crate) fn category_key(catid: &GUID) -> String {
    format!("Component Categories\\{catid}")
}

/// Parses the registry form of a GUID, `{F31DFDE2-07B6-11D2-B2D8-0060083BA1FB}` (any case, braces
/// required, nothing around it).
pub fn parse_guid(text: &str) -> Option<GUID> {
    let b = text.as_bytes();
    if b.len() != 38 || b[0] != b'{' || b[37] != b'}' {
        return None;
    }
    let mut value = 0u128;
    for (i, &c) in b[1..37].iter().enumerate() {
        if matches!(i, 8 | 13 | 18 | 23) {
            if c != b'-' {
                return None;
            }
        } else {
            // (A byte of a multi-byte character is no hex digit either.)
            value = value << 4 | u128::from(char::from(c).to_digit(16)?);
        }
    }
    Some(GUID::from_u128(value))
}

/// What a scan of the registry found, kept until the registry changes (the server list's; the
/// registry does not know its type).
pub(crate) type Snapshot = dyn Any + Send + Sync;

/// A registry with the views the server list merges.
///
/// `write` is where registration writes; `views` are read in order by the server list (on 64-bit
/// Windows the 64-bit and the 32-bit registry view, so a server registered in only one of them is still
/// found; elsewhere just `write`). `snapshots` keeps the server list's last scan of `views` while their
/// change watch says nothing changed.
pub(crate) struct Registries {
    pub(crate) write: Arc<dyn Registry>,
    pub(crate) views: Vec<Arc<dyn Registry>>,
    pub(crate) snapshots: watch::Snapshots<Snapshot>,
}

impl Registries {
    /// `write` and `views` with the change watch of `views`.
    pub(crate) fn new(
        write: Arc<dyn Registry>,
        views: Vec<Arc<dyn Registry>>,
        watch: Box<dyn watch::ChangeWatch>,
    ) -> Registries {
        Registries {
            write,
            views,
            snapshots: watch::Snapshots::new(watch),
        }
    }

    /// One registry held in memory, read and written.
    pub(crate) fn memory(reg: Arc<memory::MemoryRegistry>) -> Registries {
        let watch = Box::new(memory::MemoryWatch::new(reg.clone()));
        Registries::new(reg.clone(), vec![reg], watch)
    }

    /// The system registry: on Windows `HKEY_CLASSES_ROOT` in both views (native first); elsewhere the
    /// process-wide in-memory registry, which `DllRegisterServer` writes to as well.
    pub(crate) fn system() -> Arc<Registries> {
        static SYSTEM: OnceLock<Arc<Registries>> = OnceLock::new();
        SYSTEM
            .get_or_init(|| {
                #[cfg(windows)]
                {
                    Arc::new(windows::system_registries())
                }
                #[cfg(not(windows))]
                {
                    Arc::new(Registries::memory(Arc::new(memory::MemoryRegistry::new())))
                }
            })
            .clone()
    }
}

/// A registry the C API works on: the system registry, or one held in memory (for tests and for
/// preparing `.reg` files). Create with `OpcRegistryCreateMemory` or `OpcRegistryOpenSystem`, free
/// with `OpcRegistryRelease`. Objects made over a registry (server lists) keep it alive themselves,
/// so the handle may be released while they live. A handle may be used from several threads.
pub struct OpcRegistry {
    pub(crate) inner: Arc<Registries>,
}

/// The registries behind a C handle; NULL means the system registry.
///
/// # Safety
/// `reg` must be NULL or a live handle from `OpcRegistryCreateMemory` / `OpcRegistryOpenSystem`.
pub(crate) unsafe fn registries(reg: *const OpcRegistry) -> Arc<Registries> {
    if reg.is_null() {
        Registries::system()
    } else {
        // SAFETY: the caller vouches for the handle.
        unsafe { (*reg).inner.clone() }
    }
}

/// Creates an empty registry held in memory, for tests and for preparing `.reg` files. Fill it with
/// the registration functions or `OpcRegistryApply`; read it with `OpcRegistryExport`.
///
/// # Parameters
/// - `reg` (out): receives the new registry's handle (free it with `OpcRegistryRelease`), or NULL on
///   failure.
///
/// # Returns
/// S_OK, or E_INVALIDARG for a NULL `reg`.
///
/// # Safety
/// `reg` must be NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcRegistryCreateMemory(reg: *mut *mut OpcRegistry) -> Hr {
    ffi::boundary!(Opc, [reg], {
        // SAFETY: the caller vouches a non-NULL `reg` is writable.
        let out = unsafe { ffi::out(reg) }?;
        out.write(Box::into_raw(Box::new(OpcRegistry {
            inner: Arc::new(Registries::memory(Arc::new(memory::MemoryRegistry::new()))),
        })));
        Ok(S_OK)
    })
}

/// Opens the system registry: on Windows `HKEY_CLASSES_ROOT`, where registration writes to the
/// registry view of the calling process and the server list reads both the 64-bit and the 32-bit view;
/// elsewhere the process-wide in-memory registry that `DllRegisterServer` and the server list created by
/// `DllGetClassObject` or `OpcServerListCreate` use. Passing NULL to a function taking a registry means
/// the same registry.
///
/// # Parameters
/// - `reg` (out): receives the handle (free it with `OpcRegistryRelease`), or NULL on failure.
///
/// # Returns
/// S_OK, or E_INVALIDARG for a NULL `reg`.
///
/// # Safety
/// `reg` must be NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcRegistryOpenSystem(reg: *mut *mut OpcRegistry) -> Hr {
    ffi::boundary!(Opc, [reg], {
        // SAFETY: the caller vouches a non-NULL `reg` is writable.
        let out = unsafe { ffi::out(reg) }?;
        out.write(Box::into_raw(Box::new(OpcRegistry {
            inner: Registries::system(),
        })));
        Ok(S_OK)
    })
}

/// Frees a registry handle. Objects created over the registry stay usable.
///
/// # Parameters
/// - `reg`: the handle, or NULL (ignored).
///
/// # Safety
/// `reg` must be NULL or a live handle that is not used again.
#[no_mangle]
pub unsafe extern "C" fn OpcRegistryRelease(reg: *mut OpcRegistry) {
    ffi::guard!((), {
        if !reg.is_null() {
            // SAFETY: the caller gives up a handle made by Box::into_raw.
            drop(unsafe { Box::from_raw(reg) })
        }
    })
}

/// Reads a string value.
///
/// # Parameters
/// - `reg`: the registry, or NULL for the system registry.
/// - `key`: the key, relative to HKEY_CLASSES_ROOT (`CLSID\{...}`).
/// - `name`: the value's name; NULL or "" for the key's default value.
/// - `data` (out): receives a new string (free it with `OpcTaskMemFree`), or NULL on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `key` or `data`; E_INVALIDARG for strings that are not valid UTF-16;
/// REGDB_E_KEYMISSING when the key or value does not exist; REGDB_E_INVALIDVALUE when the value is not
/// a string.
///
/// # Safety
/// `reg` NULL or a live handle; `key` and `name` NULL or NUL-terminated; `data` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcRegistryGetString(
    reg: *const OpcRegistry,
    key: LPCWSTR,
    name: LPCWSTR,
    data: *mut LPWSTR,
) -> Hr {
    ffi::boundary!(Opc, [data], {
        // SAFETY: the caller's contract: `data` NULL or writable, the strings NULL or NUL-terminated.
        let (data, key, name) = unsafe { (ffi::out(data)?, ffi::in_string(key)?, ffi::in_string_opt(name)?) };
        // SAFETY: as above.
        let regs = unsafe { registries(reg) };
        let value = regs
            .write
            .value(&key, &name.unwrap_or_default())
            .ok_or(REGDB_E_KEYMISSING)?;
        let text = value.as_str().ok_or(REGDB_E_INVALIDVALUE)?;
        data.write(alloc_wstr_from_str(text)?);
        Ok(S_OK)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn guids_parse_in_registry_form_only() {
        let g = GUID::from_u128(0x63D5F432_CFE4_11D1_B2C8_0060083BA1FB);
        assert_eq!(parse_guid("{63D5F432-CFE4-11d1-B2C8-0060083BA1FB}"), Some(g));
        assert_eq!(parse_guid(&g.to_string()), Some(g));
        assert_eq!(parse_guid("63D5F432-CFE4-11d1-B2C8-0060083BA1FB"), None);
        assert_eq!(parse_guid("{63D5F432-CFE4-11d1-B2C8-0060083BA1FG}"), None);
        assert_eq!(parse_guid("{63D5F432+CFE4-11d1-B2C8-0060083BA1FB}"), None);
        assert_eq!(parse_guid("{63D5F432-CFE4-11d1-B2C8-0060083BA1FB} "), None);
        assert_eq!(parse_guid("{+3D5F432-CFE4-11d1-B2C8-0060083BA1FB}"), None);
        assert_eq!(parse_guid(""), None);
        assert_eq!(parse_guid("{éD5F432-CFE4-11d1-B2C8-0060083BA1F}"), None);
    }
}
