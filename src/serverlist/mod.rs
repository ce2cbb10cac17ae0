//! The OPC server browser (specification chapter 7; IOPCServerList2 from OPC Common 1.10): the class
//! OPCServerList with IOPCServerList and IOPCServerList2 and its enumerator. Clients create it by CLSID
//! through opccomn's class table (`crate::module`), served by the server plumbing (`crate::server`).
//!
//! The answers are computed from the registry (through the [`Registry`] abstraction), not from the
//! system's ICatInformation, whose behaviour differs between Windows and Wine:
//!
//! - **EnumClassesOfCategories** returns the classes that implement *any* of the listed implemented
//!   categories and whose required categories are all *supported*, as ICatInformation (and so
//!   OpcEnum) defines it: `rgcatidReq` lists the categories the caller supports, and a class
//!   qualifies when every category under its own `Required Categories` key is in that list (subkey
//!   names that are not CATIDs are ignored); a class that requires nothing always qualifies. So
//!   `EnumClassesOfCategories(1, &CATID_OPCDAServer20, 1, &CATID_OPCDAServer20, ...)` finds every
//!   DA 2.0 server that requires nothing else. A count of 0 means "regardless of category" (the
//!   specification): every class registered under `CLSID`, or no condition on required categories.
//!   `(ULONG)-1` is taken as 0 for either list. (ICatInformation reads a required count of 0 or -1
//!   as "the caller supports none": there only classes requiring nothing qualify. The server list
//!   follows the specification here; with a count of at least 1 both agree.) When the Data
//!   Access 1.0 category is listed, servers registered the old way (an `OPC` key under their ProgID,
//!   whose `CLSID` is registered) are reported too. Each class is reported once, ordered by CLSID (as
//!   a 128-bit number). On 64-bit Windows both registry views are read.
//! - **GetClassDetails** reads `CLSID\{clsid}` (first view that has it): the ProgID, the user type
//!   (the key's default value, else the ProgID key's, else "") and, for IOPCServerList2, the
//!   version-independent ProgID: the registry's `VersionIndependentProgID`, an empty string for a
//!   class that registers none (not its ProgID: a client told a versioned ProgID is the
//!   version-independent one would bind to that version for good; the specification describes the
//!   value as the registry's, and opccomn-check compares it with the registry).
//! - **CLSIDFromProgID** reads `<ProgID>\CLSID`: REGDB_E_CLASSNOTREG when the ProgID (or its `CLSID`
//!   key) is not registered, CO_E_CLASSSTRING when the text cannot be a ProgID or the registered CLSID
//!   is malformed.
//!
//! As for every OPC method, NULL arguments (and counts over 4096 or arrays missing for a count) give
//! E_INVALIDARG, with every out-parameter NULL. GetClassDetails returns REGDB_E_KEYMISSING for a class
//! without a ProgID.

pub mod interfaces;

use core::ffi::c_void;
use core::ptr;
use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, Mutex, OnceLock};

use crate::com::alloc::{alloc_wstr_from_str, task_free};
use crate::com::enumerator::{EnumInterface, Enumerator};
use crate::com::ffi::{self, FfiResult, Hr};
use crate::com::iids::{IID_IOPCEnumGUID, IID_IOPCServerList, IID_IOPCServerList2, IID_IENUMGUID};
use crate::com::interfaces::{IOPCEnumGUIDImpl, IOPCServerList2Impl, IOPCServerListImpl};
use crate::com::object::{ComClass, ComObject, Delegating, Slot};
use crate::com::{
    IUnknown, CATID, CLSID, CO_E_CLASSSTRING, GUID, HRESULT, LPOLESTR, REFIID, REGDB_E_CLASSNOTREG, S_OK, ULONG,
};
use crate::registry::categories::DA10;
use crate::registry::{parse_guid, registries, OpcRegistry, Registries, Snapshot, REGDB_E_KEYMISSING};
use interfaces::{IEnumGUID, IOPCEnumGUID, IOPCEnumGUIDVtbl};

/// The enumerator of EnumClassesOfCategories: the core's snapshot enumerator over class identifiers,
/// presented as IOPCEnumGUID and IEnumGUID (one layout). It follows COM's enumerator contract: a NULL
/// fetched-count for more than one element is E_POINTER.
struct ClassEnum;

static CLASS_ENUM_VTBL: IOPCEnumGUIDVtbl = IOPCEnumGUIDVtbl::new::<Delegating, Enumerator<ClassEnum>>();
crate::enum_impl!(IOPCEnumGUIDImpl, ClassEnum);

impl EnumInterface for ClassEnum {
    type Item = GUID;
    type Iface = IOPCEnumGUID;
    type Vtbl = IOPCEnumGUIDVtbl;
    const IIDS: &'static [GUID] = &[IID_IOPCEnumGUID, IID_IENUMGUID];
    fn vtbl() -> &'static IOPCEnumGUIDVtbl {
        &CLASS_ENUM_VTBL
    }
}

/// The most categories one EnumClassesOfCategories call may list.
const MAX_CATEGORIES: ULONG = 4096;
/// The count ICatInformation uses for "any category"; accepted as a synonym of 0.
const ANY_CATEGORY: ULONG = ULONG::MAX;

pub use crate::com::interfaces::{IOPCServerList, IOPCServerList2, IOPCServerList2Vtbl, IOPCServerListVtbl};

/// The OPCServerList object.
pub(crate) struct ServerList {
    list: Slot,
    list2: Slot,
    regs: Arc<Registries>,
    /// Answers from the last scan while the registry has not changed (`current_scan`); false when
    /// the process's environment has `OPCCOMN_SERVER_LIST_CACHE=0` as the object was created: each
    /// call then reads the registry (what the browser's benchmark compares with).
    cached: bool,
}

/// False when the environment turns the server list's scan cache off (`OPCCOMN_SERVER_LIST_CACHE=0`).
fn cache_enabled() -> bool {
    std::env::var_os("OPCCOMN_SERVER_LIST_CACHE").is_none_or(|v| v != "0")
}

impl ComClass for ServerList {
    fn interface(&self, iid: &GUID) -> Option<&Slot> {
        if *iid == IID_IOPCServerList {
            Some(&self.list)
        } else if *iid == IID_IOPCServerList2 {
            Some(&self.list2)
        } else {
            None
        }
    }
}

/// Orders GUIDs by their 128-bit value (the registry form read as one hexadecimal number).
fn guid_key(g: &GUID) -> u128 {
    (g.Data1 as u128) << 96 | (g.Data2 as u128) << 80 | (g.Data3 as u128) << 64 | u64::from_be_bytes(g.Data4) as u128
}

/// One class under `CLSID` in one registry view, with the categories under its `Implemented
/// Categories` and `Required Categories` keys (subkey names that are not CATIDs left out; a missing key
/// and an empty one alike).
struct ScannedClass {
    clsid: CLSID,
    implemented: Vec<CATID>,
    required: Vec<CATID>,
}

/// What a scan of the registry's views found: every class under `CLSID` with its categories; read
/// on first need, the classes ProgIDs registered the old way name (Data Access 1.0) and each
/// class's details. What a browser keeps between calls (`crate::registry::watch`): everything in it
/// was read after the change watch was armed, so it holds while the watch has seen no change.
pub(crate) struct Scan {
    /// In the order of the views (a class in both views twice).
    classes: Vec<ScannedClass>,
    /// The first entry of each class in `classes`, by [`guid_key`].
    first: HashMap<u128, usize>,
    /// Whether `classes` has the implemented and the required categories (a full scan has both).
    has_implemented: bool,
    has_required: bool,
    /// The classes named by a ProgID with an `OPC` subkey, in the views' order.
    da10: OnceLock<Vec<CLSID>>,
    /// GetClassDetails's answers, for classes in `classes` only (so as many as there are classes).
    details: Mutex<HashMap<u128, ClassDetails>>,
}

impl Scan {
    /// Reads the classes of every view, with the implemented and the required categories when asked.
    pub(crate) fn read(regs: &Registries, implemented: bool, required: bool) -> Scan {
        let mut children = Vec::new();
        if implemented {
            children.push("Implemented Categories");
        }
        if required {
            children.push("Required Categories");
        }
        let catids = |names: Option<Vec<String>>| -> Vec<CATID> {
            names.unwrap_or_default().iter().filter_map(|n| parse_guid(n)).collect()
        };
        let mut classes = Vec::new();
        for view in &regs.views {
            for (name, keys) in view.scan("CLSID", &children) {
                let Some(clsid) = parse_guid(&name) else { continue };
                let mut keys = keys.into_iter();
                let implemented = if implemented {
                    catids(keys.next().flatten())
                } else {
                    Vec::new()
                };
                let required = if required {
                    catids(keys.next().flatten())
                } else {
                    Vec::new()
                };
                classes.push(ScannedClass {
                    clsid,
                    implemented,
                    required,
                });
            }
        }
        let mut first = HashMap::with_capacity(classes.len());
        for (i, c) in classes.iter().enumerate() {
            first.entry(guid_key(&c.clsid)).or_insert(i);
        }
        Scan {
            classes,
            first,
            has_implemented: implemented,
            has_required: required,
            da10: OnceLock::new(),
            details: Mutex::new(HashMap::new()),
        }
    }

    /// The classes ProgIDs registered the old way name (an `OPC` subkey and a `CLSID` value), read
    /// once.
    fn da10(&self, regs: &Registries) -> &[CLSID] {
        self.da10.get_or_init(|| {
            let mut found = Vec::new();
            for view in &regs.views {
                for name in view.subkeys("") {
                    // File extensions and the well-known trees are never ProgIDs.
                    if name.starts_with('.') || name.eq_ignore_ascii_case("CLSID") {
                        continue;
                    }
                    if !view.key_exists(&format!("{name}\\OPC")) {
                        continue;
                    }
                    if let Some(clsid) = view
                        .value(&format!("{name}\\CLSID"), "")
                        .and_then(|v| v.as_str().and_then(parse_guid))
                    {
                        found.push(clsid);
                    }
                }
            }
            found
        })
    }

    /// The classes that implement any of `implemented` (`None`: regardless) and require nothing
    /// beyond `required`, the categories the caller supports (`None`: no condition), sorted by
    /// CLSID, each once. The scan must have read the categories the arguments ask about.
    fn classes_of_categories(
        &self,
        regs: &Registries,
        implemented: Option<&[CATID]>,
        required: Option<&[CATID]>,
    ) -> Vec<CLSID> {
        debug_assert!(implemented.is_none() || self.has_implemented);
        debug_assert!(required.is_none() || self.has_required);
        // `required` lists the categories the caller supports (ICatInformation's rgcatidReq): a class
        // qualifies when each category it requires is among them; a class requiring nothing always does.
        let requirements_met = |class: &ScannedClass| match required {
            None => true,
            Some(supported) => class.required.iter().all(|c| supported.contains(c)),
        };
        let mut found: BTreeMap<u128, CLSID> = BTreeMap::new();
        for class in &self.classes {
            let implements = match implemented {
                None => true,
                Some(wanted) => class.implemented.iter().any(|c| wanted.contains(c)),
            };
            if implements && requirements_met(class) {
                found.insert(guid_key(&class.clsid), class.clsid);
            }
        }
        if implemented.is_some_and(|wanted| wanted.contains(&DA10)) {
            for clsid in self.da10(regs) {
                // The class must be registered, in any view; its required categories are those of
                // the first view that registers it.
                let Some(&i) = self.first.get(&guid_key(clsid)) else {
                    continue;
                };
                if requirements_met(&self.classes[i]) {
                    found.insert(guid_key(clsid), *clsid);
                }
            }
        }
        found.into_values().collect()
    }

    /// GetClassDetails's answer for `clsid` (with the version-independent ProgID), read once per
    /// class: a class not in the scan is not registered.
    fn class_details(&self, regs: &Registries, clsid: &CLSID) -> Result<ClassDetails, HRESULT> {
        let key = guid_key(clsid);
        if !self.first.contains_key(&key) {
            return Err(REGDB_E_CLASSNOTREG);
        }
        if let Some(d) = self.details.lock().unwrap_or_else(|p| p.into_inner()).get(&key) {
            return Ok(d.clone());
        }
        // Read without the lock (callers asking about other classes do not wait); a class without a
        // ProgID is asked about rarely and read each time.
        let d = class_details(regs, clsid, true)?;
        self.details
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .insert(key, d.clone());
        Ok(d)
    }
}

/// The classes that implement any of `implemented` (`None`: regardless) and require nothing beyond
/// `required`, the categories the caller supports (`None`: no condition), sorted by CLSID, each once:
/// read from the registry now, only the categories the arguments ask about.
pub(crate) fn classes_of_categories(
    regs: &Registries,
    implemented: Option<&[CATID]>,
    required: Option<&[CATID]>,
) -> Vec<CLSID> {
    Scan::read(regs, implemented.is_some(), required.is_some()).classes_of_categories(regs, implemented, required)
}

/// The last full scan of `regs` while their change watch has seen no change, else a new one.
pub(crate) fn current_scan(regs: &Registries) -> Arc<Scan> {
    let read = || -> Arc<Snapshot> { Arc::new(Scan::read(regs, true, true)) };
    // (Only the server list keeps snapshots: always a Scan.)
    regs.snapshots
        .get(read)
        .downcast::<Scan>()
        .unwrap_or_else(|_| Arc::new(Scan::read(regs, true, true)))
}

/// What GetClassDetails reports.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ClassDetails {
    pub prog_id: String,
    pub user_type: String,
    pub version_independent_prog_id: String,
}

/// The details of `clsid` from the first view that registers it (`version_independent`: also read the
/// version-independent ProgID, for IOPCServerList2), read from the registry now.
pub(crate) fn class_details(
    regs: &Registries,
    clsid: &CLSID,
    version_independent: bool,
) -> Result<ClassDetails, HRESULT> {
    let found = regs
        .views
        .iter()
        .find_map(|v| v.class_strings(clsid, version_independent))
        .ok_or(REGDB_E_CLASSNOTREG)?;
    let nonempty = |s: Option<String>| s.filter(|s| !s.is_empty());
    let prog_id = nonempty(found.prog_id).ok_or(REGDB_E_KEYMISSING)?;
    let user_type = match nonempty(found.user_type) {
        Some(u) => u,
        None => regs
            .views
            .iter()
            .find_map(|v| nonempty(v.value(&prog_id, "").and_then(|v| v.as_str().map(str::to_string))))
            .unwrap_or_default(),
    };
    let version_independent_prog_id = found.version_independent_prog_id.unwrap_or_default();
    Ok(ClassDetails {
        prog_id,
        user_type,
        version_independent_prog_id,
    })
}

/// The CLSID registered for `prog_id`.
pub(crate) fn clsid_from_prog_id(regs: &Registries, prog_id: &str) -> Result<CLSID, HRESULT> {
    if prog_id.trim().is_empty() || prog_id.contains('\\') || prog_id.encode_utf16().count() > 255 {
        return Err(CO_E_CLASSSTRING);
    }
    let key = format!("{prog_id}\\CLSID");
    let value = regs
        .views
        .iter()
        .find_map(|v| v.value(&key, ""))
        .ok_or(REGDB_E_CLASSNOTREG)?;
    value.as_str().and_then(parse_guid).ok_or(CO_E_CLASSSTRING)
}

/// Reads a category list argument: `None` for "any" (a count of 0 or `(ULONG)-1`, which OPC clients
/// pass for "no restriction"). NULL with another count gives the NULL rule's code; more than 4096
/// categories E_INVALIDARG.
fn category_list(list: ffi::InArray<'_, CATID>) -> FfiResult<Option<&[CATID]>> {
    if list.count() == 0 || list.count() == ANY_CATEGORY {
        return Ok(None);
    }
    list.read(MAX_CATEGORIES as usize).map(Some)
}

/// EnumClassesOfCategories of both interfaces.
fn enum_classes(
    list: &ServerList,
    implemented: ffi::InArray<'_, CATID>,
    required: ffi::InArray<'_, CATID>,
    ppenum: ffi::Out<'_, *mut IOPCEnumGUID>,
) -> FfiResult {
    let (implemented, required) = (category_list(implemented)?, category_list(required)?);
    let classes = if list.cached {
        current_scan(&list.regs).classes_of_categories(&list.regs, implemented, required)
    } else {
        classes_of_categories(&list.regs, implemented, required)
    };
    ppenum.write(Enumerator::<ClassEnum>::create(classes.into(), 0));
    Ok(S_OK)
}

/// Strings a call has allocated for its out-parameters; freed unless handed over.
struct Allocated(Vec<LPOLESTR>);

impl Allocated {
    fn string(&mut self, text: &str) -> Result<LPOLESTR, HRESULT> {
        let p = alloc_wstr_from_str(text)?;
        self.0.push(p);
        Ok(p)
    }

    fn hand_over(mut self) {
        self.0.clear();
    }
}

impl Drop for Allocated {
    fn drop(&mut self) {
        for p in self.0.drain(..) {
            // SAFETY: allocated by `string` and not handed over.
            unsafe { task_free(p.cast()) };
        }
    }
}

/// GetClassDetails of both interfaces (`vi` `None` for IOPCServerList).
fn get_class_details(
    list: &ServerList,
    clsid: &CLSID,
    prog_id: ffi::Out<'_, LPOLESTR>,
    user_type: ffi::Out<'_, LPOLESTR>,
    vi: Option<ffi::Out<'_, LPOLESTR>>,
) -> FfiResult {
    let details = if list.cached {
        current_scan(&list.regs).class_details(&list.regs, clsid)?
    } else {
        class_details(&list.regs, clsid, vi.is_some())?
    };
    let mut strings = Allocated(Vec::new());
    let p = strings.string(&details.prog_id)?;
    let u = strings.string(&details.user_type)?;
    let v = match vi {
        Some(_) => strings.string(&details.version_independent_prog_id)?,
        None => ptr::null_mut(),
    };
    strings.hand_over();
    prog_id.write(p);
    user_type.write(u);
    if let Some(vi) = vi {
        vi.write(v);
    }
    Ok(S_OK)
}

/// CLSIDFromProgID of both interfaces.
fn clsid_from_prog_id_method(list: &ServerList, prog_id: ffi::WStr<'_>, clsid: ffi::Out<'_, CLSID>) -> FfiResult {
    // An over-long string is not a ProgID: CO_E_CLASSSTRING, as for one that is not valid UTF-16.
    let units = prog_id.units().map_err(|_| CO_E_CLASSSTRING)?;
    let prog_id = String::from_utf16(units).map_err(|_| CO_E_CLASSSTRING)?;
    clsid.write(clsid_from_prog_id(&list.regs, &prog_id)?);
    Ok(S_OK)
}

impl IOPCServerListImpl for ServerList {
    fn EnumClassesOfCategories(
        this: &ComObject<Self>,
        _c_impl: ULONG,
        rg_impl: ffi::InArray<'_, CATID>,
        _c_req: ULONG,
        rg_req: ffi::InArray<'_, CATID>,
        ppenum: ffi::Out<'_, *mut IEnumGUID>,
    ) -> FfiResult {
        // The enumerator answers for IEnumGUID with the same layout.
        let ppenum = ppenum.cast_pointee::<IOPCEnumGUID>();
        enum_classes(this, rg_impl, rg_req, ppenum)
    }

    fn GetClassDetails(
        this: &ComObject<Self>,
        clsid: &CLSID,
        prog_id: ffi::Out<'_, LPOLESTR>,
        user_type: ffi::Out<'_, LPOLESTR>,
    ) -> FfiResult {
        get_class_details(this, clsid, prog_id, user_type, None)
    }

    fn CLSIDFromProgID(this: &ComObject<Self>, prog_id: ffi::WStr<'_>, clsid: ffi::Out<'_, CLSID>) -> FfiResult {
        clsid_from_prog_id_method(this, prog_id, clsid)
    }
}

impl IOPCServerList2Impl for ServerList {
    fn EnumClassesOfCategories(
        this: &ComObject<Self>,
        _c_impl: ULONG,
        rg_impl: ffi::InArray<'_, CATID>,
        _c_req: ULONG,
        rg_req: ffi::InArray<'_, CATID>,
        ppenum: ffi::Out<'_, *mut IOPCEnumGUID>,
    ) -> FfiResult {
        enum_classes(this, rg_impl, rg_req, ppenum)
    }

    fn GetClassDetails(
        this: &ComObject<Self>,
        clsid: &CLSID,
        prog_id: ffi::Out<'_, LPOLESTR>,
        user_type: ffi::Out<'_, LPOLESTR>,
        vi: ffi::Out<'_, LPOLESTR>,
    ) -> FfiResult {
        get_class_details(this, clsid, prog_id, user_type, Some(vi))
    }

    fn CLSIDFromProgID(this: &ComObject<Self>, prog_id: ffi::WStr<'_>, clsid: ffi::Out<'_, CLSID>) -> FfiResult {
        clsid_from_prog_id_method(this, prog_id, clsid)
    }
}

static LIST_VTBL: IOPCServerListVtbl = IOPCServerListVtbl::new::<Delegating, ServerList>();
static LIST2_VTBL: IOPCServerList2Vtbl = IOPCServerList2Vtbl::new::<Delegating, ServerList>();

/// Creates a server list over `regs` with the standard creation protocol.
///
/// # Safety
/// As for [`ComObject::create`].
pub(crate) unsafe fn create(
    regs: Arc<Registries>,
    outer: *mut IUnknown,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> HRESULT {
    // SAFETY: forwarded.
    unsafe {
        ComObject::<ServerList>::create(outer, riid, ppv, |b| {
            Ok(ServerList {
                list: b.slot(&LIST_VTBL),
                list2: b.slot(&LIST2_VTBL),
                regs,
                cached: cache_enabled(),
            })
        })
    }
}

/// Creates the OPC server browser object (CLSID_OPCServerList) in-process, over the system registry
/// (see `OpcRegistryOpenSystem`), without going through COM activation.
///
/// # Parameters
/// - `outer`: the controlling IUnknown of an object that aggregates the browser, or NULL.
/// - `riid`: the interface wanted: IID_IOPCServerList, IID_IOPCServerList2 or IID_IUnknown; only
///   IID_IUnknown with an `outer`.
/// - `ppv` (out): receives the interface, or NULL on failure.
///
/// # Returns
/// S_OK; E_POINTER for a NULL `ppv` or `riid`; CLASS_E_NOAGGREGATION for an `outer` with a `riid`
/// other than IID_IUnknown; E_NOINTERFACE.
///
/// # Safety
/// `outer` NULL or a valid IUnknown that outlives the object; `riid` NULL or readable; `ppv` NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn OpcServerListCreate(outer: *mut IUnknown, riid: REFIID, ppv: *mut *mut c_void) -> Hr {
    ffi::boundary!(Com, [ppv], {
        // SAFETY: forwarded from the caller's contract.
        Ok(unsafe { create(registries(ptr::null()), outer, riid, ppv) })
    })
}

/// As `OpcServerListCreate`, over a registry of the caller's (for example one from
/// `OpcRegistryCreateMemory`, to test a client's browsing against known contents). The object keeps
/// the registry alive.
///
/// # Parameters
/// - `reg`: the registry to browse, or NULL for the system registry.
/// - `outer`: as for `OpcServerListCreate`.
/// - `riid`: as for `OpcServerListCreate`.
/// - `ppv` (out): receives the interface, or NULL on failure.
///
/// # Returns
/// As `OpcServerListCreate`.
///
/// # Safety
/// `reg` NULL (the system registry) or a live handle; the rest as for `OpcServerListCreate`.
#[no_mangle]
pub unsafe extern "C" fn OpcServerListCreateOver(
    reg: *const OpcRegistry,
    outer: *mut IUnknown,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> Hr {
    ffi::boundary!(Com, [ppv], {
        // SAFETY: forwarded from the caller's contract.
        Ok(unsafe { create(registries(reg), outer, riid, ppv) })
    })
}

#[cfg(test)]
mod tests;
