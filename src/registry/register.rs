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
//! CLSID\{clsid}\LocalServer32            @ = module path                         (EXE server)
//! CLSID\{clsid}\Implemented Categories\{catid}   (through the Component Categories Manager on Windows)
//! CLSID\{clsid}\Required Categories\{catid}
//! Component Categories\{catid}           409 = standard description (created when missing)
//! <ProgID>                               @ = user type
//! <ProgID>\CLSID                         @ = {clsid}
//! <ProgID>\OPC\Vendor                    @ = vendor name       (Data Access 1.0 servers only)
//! <VersionIndependentProgID>             @ = user type
//! <VersionIndependentProgID>\CLSID       @ = {clsid}
//! <VersionIndependentProgID>\CurVer      @ = ProgID
//! AppID\{appid}                          @ = user type, RunAs, LocalService, DllSurrogate (as given)
//! AppID\<exe file name>                  AppID = {appid}       (EXE servers with an AppID)
//! ```
//!
//! Unregistration removes exactly what registration added, nothing that was there before and nothing
//! another product wrote. To know what it added, registration keeps a ledger in the value
//! `OpcComnRegistration` of the server's own module key (`InprocServer32` or `LocalServer32`): the keys
//! it created, the values it added, and the previous data of values it changed. Unregistration deletes
//! the added values, restores the changed ones, and deletes the created keys that are then empty. A
//! category description is left in place while another class still implements the category.
//! Registering twice is harmless: the ledger keeps what the first registration found. When another
//! server registered the same class in the other module key *after* this registration (an OpcEnum
//! installed later next to opccomn's in-process server list), the shared entries serve it too, so
//! unregistration then takes back only its own module key. Without a
//! ledger (a registration written by other means) unregistration removes the values whose data is what
//! this registration would write, and the server's own keys once they are empty.

use core::ptr;
use std::collections::HashSet;

use super::categories::standard_description;
use super::{
    arg_string, category_key, class_categories_key, class_key, clear_out, into_hr, opt_arg_string, regfile, registries,
    OpcRegistry, RegValue, Registries, Registry, REGDB_E_KEYMISSING,
};
use crate::com::alloc::alloc_wstr_from_str;
use crate::com::boundary::catch;
use crate::com::{CATID, CLSID, E_INVALIDARG, E_POINTER, E_UNEXPECTED, GUID, HRESULT, LPCWSTR, LPWSTR, REFCLSID};

/// The value of the module key holding the registration ledger.
pub(crate) const LEDGER: &str = "OpcComnRegistration";
/// The most categories one registration may list.
const MAX_CATEGORIES: u32 = 256;
/// Locale of the category descriptions (English, as the standard texts are).
const LCID_ENGLISH: u32 = 0x409;

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

/// A server's registration, described once and passed to `OpcRegisterServer`,
/// `OpcUnregisterServer` and `OpcRegistrationExport`. Zero-initialise it, set `struct_size` to
/// `sizeof(OpcServerRegistration)` and fill what applies; NULL strings and arrays mean "none". Fields
/// added in later versions go at the end; the library reads only `struct_size` bytes.
#[repr(C)]
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
    /// Full path of the server's DLL or EXE. NULL means: for a local server the executable of the
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
    /// The AppID (a GUID) of a local server's DCOM settings, or NULL for none.
    pub app_id: *const CLSID,
    /// `RunAs` of the AppID ("Interactive User", an account), or NULL.
    pub app_id_run_as: LPCWSTR,
    /// `LocalService` of the AppID (the Windows service that hosts the server), or NULL.
    pub app_id_local_service: LPCWSTR,
    /// `DllSurrogate` of the AppID ("" for the system surrogate), or NULL.
    pub app_id_dll_surrogate: LPCWSTR,
    /// `OPC_REGISTRATION_KEEP_EXISTING` or 0.
    pub flags: u32,
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
    pub keep_existing: bool,
}

fn valid_prog_id(p: &str) -> bool {
    !p.trim().is_empty() && !p.contains('\\') && p.encode_utf16().count() <= super::MAX_NAME_UNITS
}

/// Reads `count` entries of a caller's array.
///
/// # Safety
/// `p` must point at `count` readable entries when `count` is not 0.
unsafe fn array<'a, T>(p: *const T, count: u32) -> Result<&'a [T], HRESULT> {
    if count == 0 {
        return Ok(&[]);
    }
    if p.is_null() || count > MAX_CATEGORIES {
        return Err(E_INVALIDARG);
    }
    // SAFETY: the caller vouches for `count` readable entries.
    Ok(unsafe { core::slice::from_raw_parts(p, count as usize) })
}

impl ServerDescription {
    /// Reads and checks a caller's registration.
    ///
    /// # Safety
    /// `r` must be NULL or valid as documented on OpcServerRegistration.
    pub unsafe fn read(r: *const OpcServerRegistration) -> Result<ServerDescription, HRESULT> {
        if r.is_null() {
            return Err(E_POINTER);
        }
        // SAFETY: the first field is always present.
        let size = unsafe { ptr::addr_of!((*r).struct_size).read_unaligned() } as usize;
        if size != core::mem::size_of::<OpcServerRegistration>() {
            // One version of the structure so far: anything else is a caller error.
            return Err(E_INVALIDARG);
        }
        // SAFETY: the size matches, so the whole structure is readable.
        let r = unsafe { &*r };
        let local = match r.server_type {
            0 => false,
            1 => true,
            _ => return Err(E_INVALIDARG),
        };
        if r.flags & !OPC_REGISTRATION_KEEP_EXISTING != 0 {
            return Err(E_INVALIDARG);
        }
        // SAFETY: the structure's contract covers every pointer read below.
        unsafe {
            let implemented = array(r.implemented_categories, r.implemented_category_count)?;
            let descriptions: &[LPCWSTR] = if r.implemented_category_descriptions.is_null() {
                &[]
            } else {
                array(r.implemented_category_descriptions, r.implemented_category_count)?
            };
            let mut cats = Vec::with_capacity(implemented.len());
            for (i, catid) in implemented.iter().enumerate() {
                let given = match descriptions.get(i) {
                    Some(&p) => opt_arg_string(p)?,
                    None => None,
                };
                cats.push((*catid, given));
            }
            let d = ServerDescription {
                clsid: r.clsid,
                local,
                prog_id: arg_string(r.prog_id)?,
                version_independent_prog_id: opt_arg_string(r.version_independent_prog_id)?,
                user_type: arg_string(r.user_type)?,
                module_path: opt_arg_string(r.module_path)?,
                threading_model: opt_arg_string(r.threading_model)?,
                implemented: cats,
                required: array(r.required_categories, r.required_category_count)?.to_vec(),
                da10_vendor: opt_arg_string(r.da10_vendor)?,
                app_id: r.app_id.as_ref().copied(),
                run_as: opt_arg_string(r.app_id_run_as)?,
                local_service: opt_arg_string(r.app_id_local_service)?,
                dll_surrogate: opt_arg_string(r.app_id_dll_surrogate)?,
                keep_existing: r.flags & OPC_REGISTRATION_KEEP_EXISTING != 0,
            };
            d.check()?;
            Ok(d)
        }
    }

    fn check(&self) -> Result<(), HRESULT> {
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
        Ok(())
    }

    fn module_key(&self) -> String {
        let kind = if self.local { "LocalServer32" } else { "InprocServer32" };
        format!("{}\\{kind}", class_key(&self.clsid))
    }

    /// The module key a server of the other packaging would use.
    fn other_module_key(&self) -> String {
        let kind = if self.local { "InprocServer32" } else { "LocalServer32" };
        format!("{}\\{kind}", class_key(&self.clsid))
    }

    fn module_path(&self) -> Result<String, HRESULT> {
        match &self.module_path {
            Some(p) => Ok(p.clone()),
            None => this_module_path(self.local),
        }
    }

    /// The values registration writes: (key, value name, data, always replaced).
    fn values(&self) -> Result<Vec<(String, String, String, bool)>, HRESULT> {
        let class = class_key(&self.clsid);
        let clsid = self.clsid.to_string();
        let mut v = vec![(class.clone(), String::new(), self.user_type.clone(), false)];
        v.push((format!("{class}\\ProgID"), String::new(), self.prog_id.clone(), false));
        if let Some(vi) = &self.version_independent_prog_id {
            v.push((
                format!("{class}\\VersionIndependentProgID"),
                String::new(),
                vi.clone(),
                false,
            ));
        }
        let module = self.module_key();
        v.push((module.clone(), String::new(), self.module_path()?, true));
        if let (false, Some(tm)) = (self.local, &self.threading_model) {
            v.push((module, "ThreadingModel".into(), tm.clone(), true));
        }
        v.push((self.prog_id.clone(), String::new(), self.user_type.clone(), false));
        v.push((format!("{}\\CLSID", self.prog_id), String::new(), clsid.clone(), false));
        if let Some(vendor) = &self.da10_vendor {
            v.push((
                format!("{}\\OPC\\Vendor", self.prog_id),
                String::new(),
                vendor.clone(),
                false,
            ));
        }
        if let Some(vi) = &self.version_independent_prog_id {
            v.push((vi.clone(), String::new(), self.user_type.clone(), false));
            v.push((format!("{vi}\\CLSID"), String::new(), clsid.clone(), false));
            v.push((format!("{vi}\\CurVer"), String::new(), self.prog_id.clone(), false));
        }
        if let Some(app_id) = &self.app_id {
            let app = format!("AppID\\{app_id}");
            v.push((class.clone(), "AppID".into(), app_id.to_string(), false));
            v.push((app.clone(), String::new(), self.user_type.clone(), false));
            for (name, data) in [
                ("RunAs", &self.run_as),
                ("LocalService", &self.local_service),
                ("DllSurrogate", &self.dll_surrogate),
            ] {
                if let Some(data) = data {
                    v.push((app.clone(), name.into(), data.clone(), false));
                }
            }
            if self.local {
                let path = self.module_path()?;
                let exe = path.rsplit(['\\', '/']).next().unwrap_or(&path).to_string();
                if !exe.is_empty() && exe.encode_utf16().count() <= super::MAX_NAME_UNITS {
                    v.push((format!("AppID\\{exe}"), "AppID".into(), app_id.to_string(), false));
                }
            }
        }
        Ok(v)
    }

    /// The keys that belong to this server alone (deleted when empty even without a ledger).
    fn own_keys(&self) -> Vec<String> {
        let class = class_key(&self.clsid);
        let mut keys = vec![
            class.clone(),
            format!("{class}\\ProgID"),
            format!("{class}\\VersionIndependentProgID"),
            self.module_key(),
            class_categories_key(&self.clsid, false),
            class_categories_key(&self.clsid, true),
            self.prog_id.clone(),
            format!("{}\\CLSID", self.prog_id),
            format!("{}\\OPC", self.prog_id),
            format!("{}\\OPC\\Vendor", self.prog_id),
        ];
        for (catid, _) in &self.implemented {
            keys.push(format!("{}\\{catid}", class_categories_key(&self.clsid, false)));
        }
        for catid in &self.required {
            keys.push(format!("{}\\{catid}", class_categories_key(&self.clsid, true)));
        }
        if let Some(vi) = &self.version_independent_prog_id {
            keys.extend([vi.clone(), format!("{vi}\\CLSID"), format!("{vi}\\CurVer")]);
        }
        if let Some(app_id) = &self.app_id {
            keys.push(format!("AppID\\{app_id}"));
        }
        keys
    }
}

/// The path of the module registration writes when none is given.
#[cfg(windows)]
fn this_module_path(local: bool) -> Result<String, HRESULT> {
    if local {
        super::windows::module_file_name(core::ptr::null_mut())
    } else {
        super::windows::module_file_name(super::windows::this_module())
    }
}

/// The path of the module registration writes when none is given.
#[cfg(not(windows))]
fn this_module_path(local: bool) -> Result<String, HRESULT> {
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

/// One thing a registration did, as the ledger records it.
#[derive(Clone, Debug, PartialEq)]
enum Entry {
    /// Created this key.
    Key(String),
    /// Added this value (key, name).
    Added(String, String),
    /// Replaced this value (key, name, previous data).
    Replaced(String, String, String),
    /// At the first registration another server already registered the class in the other module key
    /// (`LocalServer32` for an in-process server, and the reverse).
    OtherServer,
}

fn escape(s: &str) -> String {
    s.replace('%', "%25").replace('|', "%7C").replace(';', "%3B")
}

fn unescape(s: &str) -> String {
    s.replace("%3B", ";").replace("%7C", "|").replace("%25", "%")
}

impl Entry {
    fn encode(&self) -> String {
        match self {
            Entry::Key(k) => format!("K{}", escape(k)),
            Entry::OtherServer => "O".to_string(),
            Entry::Added(k, n) => format!("V{}|{}", escape(k), escape(n)),
            Entry::Replaced(k, n, old) => format!("R{}|{}|{}", escape(k), escape(n), escape(old)),
        }
    }

    fn decode(s: &str) -> Option<Entry> {
        let mut chars = s.chars();
        let tag = chars.next()?;
        let fields: Vec<String> = chars.as_str().split('|').map(unescape).collect();
        match (tag, fields.as_slice()) {
            ('K', [k]) => Some(Entry::Key(k.clone())),
            ('V', [k, n]) => Some(Entry::Added(k.clone(), n.clone())),
            ('R', [k, n, old]) => Some(Entry::Replaced(k.clone(), n.clone(), old.clone())),
            ('O', [empty]) if empty.is_empty() => Some(Entry::OtherServer),
            _ => None,
        }
    }

    /// The value this entry is about, for "already recorded" checks.
    fn value(&self) -> Option<(String, String)> {
        match self {
            Entry::Key(_) | Entry::OtherServer => None,
            Entry::Added(k, n) | Entry::Replaced(k, n, _) => Some((k.to_lowercase(), n.to_lowercase())),
        }
    }
}

fn read_ledger(reg: &dyn Registry, module_key: &str) -> Option<Vec<Entry>> {
    let text = reg.value(module_key, LEDGER)?;
    let text = text.as_str()?;
    Some(
        text.split(';')
            .filter(|s| !s.is_empty())
            .filter_map(Entry::decode)
            .collect(),
    )
}

/// Writes keys and values while recording what it adds.
struct Recorder<'a> {
    reg: &'a dyn Registry,
    ledger: Vec<Entry>,
    keys: HashSet<String>,
    values: HashSet<(String, String)>,
}

impl<'a> Recorder<'a> {
    fn new(reg: &'a dyn Registry, ledger: Vec<Entry>) -> Recorder<'a> {
        let keys = ledger
            .iter()
            .filter_map(|e| match e {
                Entry::Key(k) => Some(k.to_lowercase()),
                _ => None,
            })
            .collect();
        let values = ledger.iter().filter_map(Entry::value).collect();
        Recorder {
            reg,
            ledger,
            keys,
            values,
        }
    }

    /// Records every missing key on the way to `path` (parents first); does not create them.
    fn note_missing_keys(&mut self, path: &str) {
        let mut prefix = String::new();
        for part in path.split('\\') {
            if !prefix.is_empty() {
                prefix.push('\\');
            }
            prefix.push_str(part);
            if !self.reg.key_exists(&prefix) && self.keys.insert(prefix.to_lowercase()) {
                self.ledger.push(Entry::Key(prefix.clone()));
            }
        }
    }

    fn key(&mut self, path: &str) -> Result<(), HRESULT> {
        self.note_missing_keys(path);
        self.reg.create_key(path)
    }

    fn value(&mut self, path: &str, name: &str, data: &str, replace: bool) -> Result<(), HRESULT> {
        let id = (path.to_lowercase(), name.to_lowercase());
        match self.reg.value(path, name) {
            Some(RegValue::Sz(old)) if old == data => return Ok(()),
            Some(_) if !replace => return Ok(()),
            Some(old) => {
                if let (Some(old), true) = (old.as_str(), !self.values.contains(&id)) {
                    self.ledger
                        .push(Entry::Replaced(path.to_string(), name.to_string(), old.to_string()));
                    self.values.insert(id);
                }
            }
            None => {
                self.note_missing_keys(path);
                if self.values.insert(id) {
                    self.ledger.push(Entry::Added(path.to_string(), name.to_string()));
                }
            }
        }
        self.reg.set_value(path, name, &RegValue::Sz(data.to_string()))
    }
}

/// Registers the server `d` in `regs` (see the module documentation for what is written).
/// A description that is not valid is refused before anything is written.
pub(crate) fn register(regs: &Registries, d: &ServerDescription) -> Result<(), HRESULT> {
    d.check()?;
    let reg = &*regs.write;
    let module_key = d.module_key();
    let ledger = read_ledger(reg, &module_key).unwrap_or_default();
    let first = ledger.is_empty();
    let mut rec = Recorder::new(reg, ledger);
    if first && reg.key_exists(&d.other_module_key()) {
        rec.ledger.push(Entry::OtherServer);
    }
    for (key, name, data, ours) in d.values()? {
        rec.value(&key, &name, &data, ours || !d.keep_existing)?;
    }
    if let Some(vendor_key) = d.da10_vendor.as_ref().map(|_| format!("{}\\OPC", d.prog_id)) {
        rec.key(&vendor_key)?;
    }
    for (catid, given) in &d.implemented {
        let key = category_key(catid);
        let name = format!("{LCID_ENGLISH:x}");
        let description = given.as_deref().or(standard_description(catid));
        if let (None, Some(text)) = (reg.value(&key, &name), description) {
            rec.note_missing_keys(&key);
            rec.values.insert((key.to_lowercase(), name.clone()));
            rec.ledger.push(Entry::Added(key, name));
            reg.register_category(catid, LCID_ENGLISH, text)?;
        }
        rec.note_missing_keys(&format!("{}\\{catid}", class_categories_key(&d.clsid, false)));
        reg.register_class_category(&d.clsid, catid, false)?;
    }
    for catid in &d.required {
        rec.note_missing_keys(&format!("{}\\{catid}", class_categories_key(&d.clsid, true)));
        reg.register_class_category(&d.clsid, catid, true)?;
    }
    let text: Vec<String> = rec.ledger.iter().map(Entry::encode).collect();
    reg.set_value(&module_key, LEDGER, &RegValue::Sz(text.join(";")))
}

/// True when a class other than `except` implements `catid` in `reg`.
fn category_in_use(reg: &dyn Registry, catid: &GUID, except: &GUID) -> bool {
    let wanted = catid.to_string().to_lowercase();
    let except = except.to_string().to_lowercase();
    reg.scan("CLSID", &["Implemented Categories"])
        .into_iter()
        .any(|(clsid, found)| {
            clsid.to_lowercase() != except
                && found[0]
                    .as_ref()
                    .is_some_and(|cats| cats.iter().any(|c| c.to_lowercase() == wanted))
        })
}

fn key_is_empty(reg: &dyn Registry, path: &str) -> bool {
    reg.subkeys(path).is_empty() && reg.values(path).is_empty()
}

/// The class and category a key `CLSID\{clsid}\Implemented|Required Categories\{catid}` names.
fn class_category_of(path: &str, d: &ServerDescription) -> Option<(GUID, bool)> {
    for required in [false, true] {
        let prefix = format!("{}\\", class_categories_key(&d.clsid, required)).to_lowercase();
        if let Some(rest) = path.to_lowercase().strip_prefix(&prefix) {
            return super::parse_guid(rest).map(|catid| (catid, required));
        }
    }
    None
}

/// Unregisters the server `d` from `regs`, undoing what [`register`] recorded.
pub(crate) fn unregister(regs: &Registries, d: &ServerDescription) -> Result<(), HRESULT> {
    let reg = &*regs.write;
    let module_key = d.module_key();
    let mut ledger = match read_ledger(reg, &module_key) {
        Some(ledger) => ledger,
        None => fallback_ledger(reg, d)?,
    };
    // Another server registered the class after this one (OpcEnum installed later, say): the class
    // key, ProgIDs and categories now serve it too. Take back only the own module key.
    if !ledger.contains(&Entry::OtherServer) && reg.key_exists(&d.other_module_key()) {
        let own = module_key.to_lowercase();
        let is_own = |key: &str| key.to_lowercase() == own;
        ledger.retain(|e| match e {
            Entry::Key(k) | Entry::Added(k, _) | Entry::Replaced(k, _, _) => is_own(k),
            Entry::OtherServer => false,
        });
    }
    for entry in ledger.iter().rev() {
        match entry {
            Entry::Added(key, name) => {
                let category = key
                    .to_lowercase()
                    .strip_prefix("component categories\\")
                    .and_then(super::parse_guid);
                if category.is_some_and(|catid| category_in_use(reg, &catid, &d.clsid)) {
                    continue;
                }
                reg.delete_value(key, name)?
            }
            Entry::Replaced(key, name, old) => reg.set_value(key, name, &RegValue::Sz(old.clone()))?,
            Entry::Key(_) | Entry::OtherServer => {}
        }
    }
    reg.delete_value(&module_key, LEDGER)?;
    let mut keys: Vec<&String> = ledger
        .iter()
        .filter_map(|e| match e {
            Entry::Key(k) => Some(k),
            _ => None,
        })
        .collect();
    // Deepest first, so children go before their parents.
    keys.sort_by_key(|k| core::cmp::Reverse(k.matches('\\').count()));
    for key in keys {
        if let Some((catid, required)) = class_category_of(key, d) {
            if reg.key_exists(key) && reg.subkeys(key).is_empty() {
                reg.unregister_class_category(&d.clsid, &catid, required)?;
            }
        } else if reg.key_exists(key) && key_is_empty(reg, key) {
            reg.delete_key(key)?;
        }
    }
    Ok(())
}

/// What to undo when no ledger exists: the values that hold what registration would write, and the
/// server's own keys.
fn fallback_ledger(reg: &dyn Registry, d: &ServerDescription) -> Result<Vec<Entry>, HRESULT> {
    if !reg.key_exists(&class_key(&d.clsid)) && !reg.key_exists(&d.prog_id) {
        return Err(REGDB_E_KEYMISSING);
    }
    let mut ledger: Vec<Entry> = d.own_keys().into_iter().map(Entry::Key).collect();
    for (key, name, data, _) in d.values()? {
        if reg.value(&key, &name).as_ref().and_then(RegValue::as_str) == Some(data.as_str()) {
            ledger.push(Entry::Added(key, name));
        }
    }
    Ok(ledger)
}

/// Registers a server as `server` describes it (see OpcServerRegistration), in `reg` (NULL: the system
/// registry). Writes the CLSID, ProgID, version-independent ProgID and CurVer keys, `InprocServer32`
/// (with `ThreadingModel`) or `LocalServer32`, the AppID, the categories (created with their standard
/// descriptions when missing; on Windows through the Component Categories Manager when COM is initialised
/// on the calling thread, else by writing the same keys) and, for Data Access
/// 1.0 servers, `<ProgID>\OPC\Vendor`. Records what it added so `OpcUnregisterServer` removes exactly
/// that. Registering again is harmless. Call it from DllRegisterServer, or when `OpcParseCommandLine`
/// reports OPC_SERVER_COMMAND_REGISTER.
///
/// Returns S_OK; E_POINTER for a NULL `server` or a required string that is NULL; E_INVALIDARG for a
/// wrong `struct_size`, unknown `server_type` or `flags`, a malformed ProgID, more than 256
/// categories or a count without an array, strings that are not valid UTF-16; a registry error (for
/// example E_ACCESSDENIED without administrator rights) when a write fails.
///
/// # Safety
/// `server` NULL or valid as documented on OpcServerRegistration; `reg` NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn OpcRegisterServer(server: *const OpcServerRegistration, reg: *const OpcRegistry) -> HRESULT {
    catch(E_UNEXPECTED, || {
        // SAFETY: forwarded from the caller's contract.
        let run = || unsafe { register(&registries(reg), &ServerDescription::read(server)?) };
        into_hr(run())
    })
}

/// Unregisters a server registered with `OpcRegisterServer` (pass the same description): removes the
/// values and keys that registration added and restores values it replaced, leaving everything that
/// was there before and everything other products wrote. A category's description stays while another
/// class implements the category.
///
/// Returns S_OK; REGDB_E_KEYMISSING when the server is not registered; the errors of
/// `OpcRegisterServer` for a bad description or a failing registry write.
///
/// # Safety
/// As for `OpcRegisterServer`.
#[no_mangle]
pub unsafe extern "C" fn OpcUnregisterServer(server: *const OpcServerRegistration, reg: *const OpcRegistry) -> HRESULT {
    catch(E_UNEXPECTED, || {
        // SAFETY: forwarded from the caller's contract.
        let run = || unsafe { unregister(&registries(reg), &ServerDescription::read(server)?) };
        into_hr(run())
    })
}

/// The registration `d` would write into an empty registry, as `.reg` text.
pub(crate) fn export_registration(d: &ServerDescription) -> Result<String, HRESULT> {
    let regs = Registries::single(std::sync::Arc::new(super::memory::MemoryRegistry::new()));
    register(&regs, d)?;
    regfile::export(&*regs.write, "")
}

/// Writes the registration `server` describes as the text of a `.reg` file ("Windows Registry Editor
/// Version 5.00") into `*text` (free with `OpcTaskMemFree`), for installers that register servers by
/// importing a file. It holds what `OpcRegisterServer` writes into an empty registry, including the
/// record `OpcUnregisterServer` uses. Pass an explicit `module_path`: the default is this process's
/// module.
///
/// Returns S_OK; E_POINTER for a NULL `text`; the errors of `OpcRegisterServer` for a bad description.
/// `*text` is NULL on failure.
///
/// # Safety
/// `server` as for `OpcRegisterServer`; `text` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcRegistrationExport(server: *const OpcServerRegistration, text: *mut LPWSTR) -> HRESULT {
    // SAFETY: forwarded from the caller's contract.
    if let Err(hr) = unsafe { clear_out(text) } {
        return hr;
    }
    catch(E_UNEXPECTED, || {
        let run = || -> Result<(), HRESULT> {
            // SAFETY: forwarded from the caller's contract.
            let d = unsafe { ServerDescription::read(server)? };
            let p = alloc_wstr_from_str(&export_registration(&d)?)?;
            // SAFETY: checked writable above.
            unsafe { *text = p };
            Ok(())
        };
        into_hr(run())
    })
}

/// Reads a GUID argument.
///
/// # Safety
/// `p` NULL or readable.
unsafe fn guid_arg(p: *const GUID) -> Result<GUID, HRESULT> {
    // SAFETY: forwarded.
    unsafe { p.as_ref() }.copied().ok_or(E_POINTER)
}

/// Creates the component category `catid` with `description` in English (0x409), as the
/// specification's CreateComponentCategory helper: `Component Categories\{catid}`, value `409`. A NULL
/// `description` uses the standard text of an OPC category. On Windows this goes through the Component
/// Categories Manager (ICatRegister::RegisterCategories) when COM is initialised.
///
/// Returns S_OK; E_POINTER for a NULL `catid`; E_INVALIDARG for a NULL description of a category that
/// is not an OPC one, or a description over 127 characters (the limit of CATEGORYINFO); registry errors.
///
/// # Safety
/// `reg` NULL or a live handle; `catid` NULL or readable; `description` NULL or NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn OpcCreateComponentCategory(
    reg: *const OpcRegistry,
    catid: *const CATID,
    description: LPCWSTR,
) -> HRESULT {
    catch(E_UNEXPECTED, || {
        let run = || -> Result<(), HRESULT> {
            // SAFETY: forwarded from the caller's contract.
            let (catid, given) = unsafe { (guid_arg(catid)?, opt_arg_string(description)?) };
            let text = match given {
                Some(t) => t,
                None => standard_description(&catid).ok_or(E_INVALIDARG)?.to_string(),
            };
            if text.encode_utf16().count() > 127 {
                return Err(E_INVALIDARG);
            }
            // SAFETY: as above.
            unsafe { registries(reg) }
                .write
                .register_category(&catid, LCID_ENGLISH, &text)
        };
        into_hr(run())
    })
}

/// Registers `clsid` as implementing the category `catid` (the specification's
/// RegisterCLSIDInCategory): `CLSID\{clsid}\Implemented Categories\{catid}`; through the Component
/// Categories Manager on Windows.
///
/// Returns S_OK; E_POINTER for a NULL argument; registry errors.
///
/// # Safety
/// `reg` NULL or a live handle; `clsid` and `catid` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn OpcRegisterClassInCategory(
    reg: *const OpcRegistry,
    clsid: REFCLSID,
    catid: *const CATID,
) -> HRESULT {
    catch(E_UNEXPECTED, || {
        let run = || -> Result<(), HRESULT> {
            // SAFETY: forwarded from the caller's contract.
            let (clsid, catid) = unsafe { (guid_arg(clsid)?, guid_arg(catid)?) };
            // SAFETY: as above.
            unsafe { registries(reg) }
                .write
                .register_class_category(&clsid, &catid, false)
        };
        into_hr(run())
    })
}

/// Removes `clsid` from the category `catid` (the specification's UnRegisterCLSIDInCategory): deletes
/// `CLSID\{clsid}\Implemented Categories\{catid}`. Succeeds when it was not registered.
///
/// Returns S_OK; E_POINTER for a NULL argument; registry errors.
///
/// # Safety
/// As for `OpcRegisterClassInCategory`.
#[no_mangle]
pub unsafe extern "C" fn OpcUnregisterClassInCategory(
    reg: *const OpcRegistry,
    clsid: REFCLSID,
    catid: *const CATID,
) -> HRESULT {
    catch(E_UNEXPECTED, || {
        let run = || -> Result<(), HRESULT> {
            // SAFETY: forwarded from the caller's contract.
            let (clsid, catid) = unsafe { (guid_arg(clsid)?, guid_arg(catid)?) };
            // SAFETY: as above.
            unsafe { registries(reg) }
                .write
                .unregister_class_category(&clsid, &catid, false)
        };
        into_hr(run())
    })
}

/// The standard English description of an OPC component category (for example "OPC Data Access
/// Servers Version 2.0" for CATID_OPCDAServer20) into `*description`, freed with `OpcTaskMemFree`.
///
/// Returns S_OK; E_POINTER for a NULL argument; E_INVALIDARG for a category that is not an OPC one.
/// `*description` is NULL on failure.
///
/// # Safety
/// `catid` NULL or readable; `description` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcCategoryDescription(catid: *const CATID, description: *mut LPWSTR) -> HRESULT {
    // SAFETY: forwarded from the caller's contract.
    if let Err(hr) = unsafe { clear_out(description) } {
        return hr;
    }
    catch(E_UNEXPECTED, || {
        let run = || -> Result<(), HRESULT> {
            // SAFETY: forwarded from the caller's contract.
            let catid = unsafe { guid_arg(catid)? };
            let p = alloc_wstr_from_str(standard_description(&catid).ok_or(E_INVALIDARG)?)?;
            // SAFETY: checked writable above.
            unsafe { *description = p };
            Ok(())
        };
        into_hr(run())
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::registry::categories::{CATID_OPCDAServer10, CATID_OPCDAServer20};
    use crate::registry::memory::MemoryRegistry;
    use std::sync::Arc;

    pub(crate) fn memory() -> Registries {
        Registries::single(Arc::new(MemoryRegistry::new()))
    }

    pub(crate) fn server(n: u128) -> ServerDescription {
        ServerDescription {
            clsid: GUID::from_u128(0x11111111_2222_3333_4444_000000000000 + n),
            prog_id: format!("Vendor.Server{n}.1"),
            version_independent_prog_id: Some(format!("Vendor.Server{n}")),
            user_type: format!("Vendor Server {n}"),
            module_path: Some("C:\\Program Files\\Vendor\\server.dll".into()),
            threading_model: Some("Both".into()),
            implemented: vec![(CATID_OPCDAServer20, None)],
            ..Default::default()
        }
    }

    fn dump(regs: &Registries) -> String {
        regfile::export(&*regs.write, "").unwrap()
    }

    #[test]
    fn registration_writes_what_com_and_the_specification_require() {
        let regs = memory();
        let mut d = server(1);
        d.da10_vendor = Some("Vendor Inc.".into());
        d.implemented.push((CATID_OPCDAServer10, None));
        register(&regs, &d).unwrap();
        let r = &*regs.write;
        let s = |k: &str, n: &str| r.value(k, n).and_then(|v| v.as_str().map(str::to_string));
        let class = format!("CLSID\\{}", d.clsid);
        assert_eq!(s(&class, "").as_deref(), Some("Vendor Server 1"));
        assert_eq!(s(&format!("{class}\\ProgID"), "").as_deref(), Some("Vendor.Server1.1"));
        assert_eq!(
            s(&format!("{class}\\VersionIndependentProgID"), "").as_deref(),
            Some("Vendor.Server1")
        );
        assert_eq!(
            s(&format!("{class}\\InprocServer32"), "").as_deref(),
            Some("C:\\Program Files\\Vendor\\server.dll")
        );
        assert_eq!(
            s(&format!("{class}\\InprocServer32"), "ThreadingModel").as_deref(),
            Some("Both")
        );
        assert!(!r.key_exists(&format!("{class}\\LocalServer32")));
        assert_eq!(
            s("Vendor.Server1.1\\CLSID", "").as_deref(),
            Some(d.clsid.to_string().as_str())
        );
        assert_eq!(s("Vendor.Server1\\CurVer", "").as_deref(), Some("Vendor.Server1.1"));
        assert_eq!(
            s("Vendor.Server1\\CLSID", "").as_deref(),
            Some(d.clsid.to_string().as_str())
        );
        assert_eq!(s("Vendor.Server1.1\\OPC\\Vendor", "").as_deref(), Some("Vendor Inc."));
        assert!(r.key_exists(&format!("{class}\\Implemented Categories\\{CATID_OPCDAServer20}")));
        assert!(r.key_exists(&format!("{class}\\Implemented Categories\\{CATID_OPCDAServer10}")));
        assert_eq!(
            s(&format!("Component Categories\\{CATID_OPCDAServer20}"), "409").as_deref(),
            Some("OPC Data Access Servers Version 2.0")
        );
    }

    #[test]
    fn unregistration_leaves_the_registry_as_it_was() {
        let regs = memory();
        regfile::apply(
            &*regs.write,
            "REGEDIT4\n[HKCR\\CLSID\\{00000000-0000-0000-0000-000000000001}]\n@=\"someone else\"\n[HKCR\\Other]\n",
        )
        .unwrap();
        let before = dump(&regs);
        let mut d = server(2);
        d.da10_vendor = Some("V".into());
        d.required = vec![CATID_OPCDAServer10];
        d.app_id = Some(GUID::from_u128(7));
        d.run_as = Some("Interactive User".into());
        d.local = true;
        register(&regs, &d).unwrap();
        assert_ne!(dump(&regs), before);
        register(&regs, &d).unwrap();
        unregister(&regs, &d).unwrap();
        assert_eq!(dump(&regs), before);
    }

    #[test]
    fn coexisting_registrations_keep_what_they_found() {
        let regs = memory();
        let d = server(3);
        let class = format!("CLSID\\{}", d.clsid);
        // Another product registered the class as an EXE server, with its own description.
        let other = format!(
            "REGEDIT4\n[HKCR\\{class}]\n@=\"Other Class\"\n\"AppID\"=\"{{x}}\"\n[HKCR\\{class}\\LocalServer32]\n@=\"C:\\\\other.exe\"\n[HKCR\\{class}\\ProgID]\n@=\"Vendor.Server3.1\"\n[HKCR\\Vendor.Server3.1\\CLSID]\n@=\"{}\"\n",
            d.clsid
        );
        regfile::apply(&*regs.write, &other).unwrap();
        let before = dump(&regs);
        let mut keep = d.clone();
        keep.keep_existing = true;
        register(&regs, &keep).unwrap();
        assert_eq!(regs.write.value(&class, ""), Some(RegValue::Sz("Other Class".into())));
        assert!(regs.write.key_exists(&format!("{class}\\InprocServer32")));
        unregister(&regs, &keep).unwrap();
        assert_eq!(dump(&regs), before);
        // Without the flag the description is replaced, and restored on unregistration.
        register(&regs, &d).unwrap();
        assert_eq!(
            regs.write.value(&class, ""),
            Some(RegValue::Sz("Vendor Server 3".into()))
        );
        unregister(&regs, &d).unwrap();
        assert_eq!(dump(&regs), before);
    }

    #[test]
    fn a_server_registered_later_under_the_same_class_keeps_its_entries() {
        let regs = memory();
        let mut d = server(9);
        d.keep_existing = true;
        register(&regs, &d).unwrap();
        // Another product registers the class as an EXE server afterwards, writing the same values.
        let class = class_key(&d.clsid);
        regs.write
            .set_value(
                &format!("{class}\\LocalServer32"),
                "",
                &RegValue::Sz("C:\\other.exe".into()),
            )
            .unwrap();
        let with_other = dump(&regs);
        unregister(&regs, &d).unwrap();
        assert!(!regs.write.key_exists(&d.module_key()));
        let s = |k: &str| regs.write.value(k, "").and_then(|v| v.as_str().map(str::to_string));
        assert_eq!(s(&class).as_deref(), Some("Vendor Server 9"));
        assert_eq!(s("Vendor.Server9.1\\CLSID"), Some(d.clsid.to_string()));
        assert!(regs
            .write
            .key_exists(&format!("{class}\\Implemented Categories\\{CATID_OPCDAServer20}")));
        assert_ne!(dump(&regs), with_other);
        // Registering again and unregistering keeps it so.
        register(&regs, &d).unwrap();
        unregister(&regs, &d).unwrap();
        assert_eq!(s("Vendor.Server9.1\\CLSID"), Some(d.clsid.to_string()));
    }

    #[test]
    fn a_shared_category_keeps_its_description() {
        let regs = memory();
        let empty = dump(&regs);
        let (a, b) = (server(4), server(5));
        register(&regs, &a).unwrap();
        let only_a = dump(&regs);
        register(&regs, &b).unwrap();
        unregister(&regs, &a).unwrap();
        let key = format!("Component Categories\\{CATID_OPCDAServer20}");
        assert!(
            regs.write.value(&key, "409").is_some(),
            "b still implements the category"
        );
        unregister(&regs, &b).unwrap();
        // a created the category; with b gone nobody uses it, but a's record was consumed already, so the
        // description stays: created by a, kept for b.
        assert!(regs.write.value(&key, "409").is_some());
        assert_ne!(dump(&regs), empty);
        // In the order of registration's reverse, everything goes.
        let regs = memory();
        register(&regs, &a).unwrap();
        register(&regs, &b).unwrap();
        unregister(&regs, &b).unwrap();
        assert_eq!(dump(&regs), only_a);
        unregister(&regs, &a).unwrap();
        assert_eq!(dump(&regs), empty);
    }

    #[test]
    fn unregistration_without_a_ledger_removes_only_matching_values() {
        let regs = memory();
        let d = server(6);
        register(&regs, &d).unwrap();
        regs.write.delete_value(&d.module_key(), LEDGER).unwrap();
        regs.write
            .set_value("Vendor.Server6.1", "Extra", &RegValue::Sz("kept".into()))
            .unwrap();
        unregister(&regs, &d).unwrap();
        assert!(!regs.write.key_exists(&class_key(&d.clsid)));
        assert_eq!(
            regs.write.values("Vendor.Server6.1"),
            vec![("Extra".into(), RegValue::Sz("kept".into()))]
        );
        assert_eq!(unregister(&memory(), &d), Err(REGDB_E_KEYMISSING));
    }

    #[test]
    fn ledger_entries_survive_awkward_names() {
        for e in [
            Entry::Key("A;B|C%3B".into()),
            Entry::Added("K".into(), "".into()),
            Entry::Replaced("K".into(), "n|;".into(), "old;data%".into()),
            Entry::OtherServer,
        ] {
            assert_eq!(Entry::decode(&e.encode()), Some(e.clone()));
        }
    }

    #[test]
    fn exported_registration_applies_to_the_same_registry() {
        let d = server(7);
        let text = export_registration(&d).unwrap();
        assert!(text.starts_with("Windows Registry Editor Version 5.00\r\n"));
        let regs = memory();
        regfile::apply(&*regs.write, &text).unwrap();
        let direct = memory();
        register(&direct, &d).unwrap();
        assert_eq!(dump(&regs), dump(&direct));
        unregister(&regs, &d).unwrap();
        assert_eq!(dump(&regs), dump(&memory()));
    }

    #[test]
    fn bad_descriptions_are_refused() {
        let regs = memory();
        let empty = dump(&regs);
        for bad in ["", "A\\B", " "] {
            let mut d = server(8);
            d.prog_id = bad.into();
            assert_eq!(d.check(), Err(E_INVALIDARG));
            assert_eq!(register(&regs, &d), Err(E_INVALIDARG), "ProgID {bad:?}");
        }
        let mut d = server(8);
        d.module_path = Some(String::new());
        assert_eq!(d.check(), Err(E_INVALIDARG));
        assert_eq!(register(&regs, &d), Err(E_INVALIDARG), "empty module path");
        // SAFETY: NULL is allowed.
        assert_eq!(unsafe { ServerDescription::read(ptr::null()) }.err(), Some(E_POINTER));
        // The refused registrations wrote nothing (the same registry takes a good one).
        assert_eq!(dump(&regs), empty);
        register(&regs, &server(8)).unwrap();
        assert_ne!(dump(&regs), empty);
    }
}
