//! A Data Access EXE server made with the public crate `opc_da` 0.3.1's server module: the crate's
//! `Server<T>` and `Group<T>` are the COM objects (their IOPCServer, IOPCCommon,
//! IConnectionPointContainer, IOPCItemProperties, IOPCBrowseServerAddressSpace, IOPCItemMgt,
//! IOPCGroupStateMgt, IOPCSyncIO, IOPCAsyncIO2, ... vtables and argument handling are the crate's),
//! and the crate's `ConnectionPoint` is the group's IOPCDataCallback connection point. What the
//! crate leaves to a server, and this program supplies: the address space behind its `ServerTrait`
//! and `GroupTrait`, the IEnumString its `browse_opc_item_ids` must return, the callbacks, and the
//! EXE's COM hosting (a class factory, `CoRegisterClassObject`, /RegServer and /UnregServer of its
//! LocalServer32 key, and exiting once its last server object is released).
//!
//! It serves the address space of the project's C test server (tests/oop/da.h): four items with the
//! same IDs, types, values and times, so that a client checks every value it reads against what
//! this server serves. See docs/dev/third-party-client.md for what the crate gets wrong and how this
//! server's clients are told.
//!
//! Usage: `opc_da_crate_server.exe /RegServer | /UnregServer | -Embedding` (COM starts it with
//! -Embedding). Built for x64 its class is {C3000000-5EED-4000-8000-00000000DA03}; built for x86,
//! {C3000000-5EED-4000-8000-00000000DA04}, registered in the 32-bit view.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use opc_da::def::{EnumScope, ServerState, ServerStatus};
use opc_da::server::com::base::Variant;
use opc_da::server::com::connection_point::ConnectionPoint;
use opc_da::server::com::group::Group;
use opc_da::server::com::server::Server;
use opc_da::server::traits::{
    AvailableProperty, BrowseDirection, BrowseFilter, BrowseResult, BrowseType, GroupInfo, GroupTrait, ItemOptionalVqt,
    ItemProperties, ItemPropertyData, ItemWithMaxAge, NamespaceType, NewItem, ServerTrait, VqtWithError,
};
use opc_da_bindings::{
    IOPCDataCallback, OPC_DS_DEVICE, OPC_READABLE, OPC_WRITEABLE, tagOPCDATASOURCE, tagOPCITEMDEF, tagOPCITEMRESULT,
    tagOPCITEMSTATE, tagOPCITEMVQT,
};
use windows::Win32::Foundation::{E_FAIL, E_INVALIDARG, E_NOTIMPL, E_POINTER, FILETIME, S_FALSE, S_OK};
use windows::Win32::System::Com::{
    CLSCTX_LOCAL_SERVER, COINIT_MULTITHREADED, CONNECTDATA, CoInitializeEx, CoRegisterClassObject, CoRevokeClassObject,
    CoTaskMemAlloc, CoUninitialize, FORMATETC, IAdviseSink, IClassFactory, IClassFactory_Impl, IConnectionPoint,
    IConnectionPointContainer, IEnumConnectionPoints, IEnumFORMATETC, IEnumSTATDATA, IEnumString, IEnumString_Impl,
    REGCLS_MULTIPLEUSE, SAFEARRAY, STGMEDIUM,
};
use windows::Win32::System::Ole::{
    SafeArrayAccessData, SafeArrayCreateVector, SafeArrayGetDim, SafeArrayGetLBound, SafeArrayGetUBound,
    SafeArrayUnaccessData,
};
use windows::Win32::System::Registry::{HKEY_LOCAL_MACHINE, REG_SZ, RegDeleteTreeW, RegSetKeyValueW};
use windows::Win32::System::Variant::{VARENUM, VARIANT, VT_ARRAY, VT_BSTR, VT_I2, VT_I4, VT_R8};
use windows::core::{BOOL, GUID, HRESULT, IUnknown, Interface, PCWSTR, PWSTR};
use windows_core::{ComObject, implement};

/// This server's class: one for the x64 build, another for the x86 build (registered in the 32-bit
/// view), so that both can be registered at once.
#[cfg(target_pointer_width = "64")]
const CLSID_CRATE_SERVER: GUID = GUID::from_u128(0xc3000000_5eed_4000_8000_00000000da03);
#[cfg(target_pointer_width = "32")]
const CLSID_CRATE_SERVER: GUID = GUID::from_u128(0xc3000000_5eed_4000_8000_00000000da04);

const OPC_E_INVALIDHANDLE: HRESULT = HRESULT(0xC004_0001_u32 as i32);
const OPC_E_BADTYPE: HRESULT = HRESULT(0xC004_0004_u32 as i32);
const OPC_E_UNKNOWNITEMID: HRESULT = HRESULT(0xC004_0007_u32 as i32);
const OPC_E_INVALID_PID: HRESULT = HRESULT(0xC004_0203_u32 as i32);
const CONNECT_E_NOCONNECTION: HRESULT = HRESULT(0x8004_0200_u32 as i32);
const QUALITY_GOOD: u16 = 0xC0;

// ---- The address space (tests/oop/da.h) ---------------------------------------------------------------

const VENDOR_INFO: &str = "opccomn DA test server \u{20ac}";
const ITEM_IDS: [&str; 4] = [
    "Plant.Tank1.Level (I4)",
    "Plant.Tank1.Temp (R8)",
    "Plant.Tank1.Name (BSTR) \u{20ac}",
    "Plant.Tank1.Profile (R8[])",
];
/// VT_I4, VT_R8, VT_BSTR, VT_ARRAY | VT_R8.
const ITEM_TYPES: [u16; 4] = [3, 5, 8, 0x2005];
/// The server handle of the first group; its items are 100 + their index.
const FIRST_GROUP_HANDLE: u32 = 7;
const LOCALES: [u32; 2] = [0x0409, 0x0407];

fn item_handle(index: usize) -> u32 {
    100 + index as u32
}

/// 2026-12-04 12:00:00 UTC plus `seconds` (da_time of tests/oop/da.h).
fn da_time(seconds: u64) -> FILETIME {
    let t = 134_095_536_000_000_000 + seconds * 10_000_000;
    FILETIME {
        dwLowDateTime: t as u32,
        dwHighDateTime: (t >> 32) as u32,
    }
}

/// The same time as a SystemTime (the crate's ServerStatus takes those).
fn da_system_time(seconds: u64) -> SystemTime {
    // 1601-01-01 to 1970-01-01 in 100 ns units.
    let since_unix = 134_095_536_000_000_000 - 116_444_736_000_000_000 + seconds * 10_000_000;
    UNIX_EPOCH + Duration::from_nanos(since_unix * 100)
}

/// A value of the address space.
#[derive(Clone, Debug, PartialEq)]
enum Value {
    I4(i32),
    R8(f64),
    Text(String),
    R8s(Vec<f64>),
}

fn initial_values() -> Vec<Value> {
    vec![
        Value::I4(12345),
        Value::R8(3.25),
        Value::Text("Tank \u{e4}\u{f6}\u{fc} \u{20ac} \u{1F600}".to_owned()),
        Value::R8s(vec![1.5, -2.0, 1e300]),
    ]
}

impl Value {
    fn to_variant(&self) -> VARIANT {
        match self {
            Value::I4(v) => VARIANT::from(*v),
            Value::R8(v) => VARIANT::from(*v),
            Value::Text(v) => VARIANT::from(v.as_str()),
            Value::R8s(values) => {
                let mut v = VARIANT::default();
                // SAFETY: a new SAFEARRAY of `values.len()` doubles, filled while accessed, then owned
                // by the VARIANT.
                unsafe {
                    let array = SafeArrayCreateVector(VT_R8, 0, values.len() as u32);
                    if array.is_null() {
                        return v;
                    }
                    let mut data = std::ptr::null_mut();
                    if SafeArrayAccessData(array, &mut data).is_ok() {
                        std::ptr::copy_nonoverlapping(values.as_ptr(), data.cast::<f64>(), values.len());
                        let _ = SafeArrayUnaccessData(array);
                    }
                    let inner = std::ops::DerefMut::deref_mut(&mut v.Anonymous.Anonymous);
                    inner.vt = VARENUM(VT_ARRAY.0 | VT_R8.0);
                    inner.Anonymous.parray = array;
                }
                v
            }
        }
    }

    /// The value a client wrote, when it has the item's canonical type.
    fn from_variant(v: &VARIANT, canonical: u16) -> Option<Value> {
        // SAFETY: the union member read is the one `vt` names.
        unsafe {
            let inner = &v.Anonymous.Anonymous;
            if inner.vt.0 != canonical {
                return None;
            }
            match inner.vt {
                VT_I4 => Some(Value::I4(inner.Anonymous.lVal)),
                VT_R8 => Some(Value::R8(inner.Anonymous.dblVal)),
                VT_BSTR => Some(Value::Text(inner.Anonymous.bstrVal.to_string())),
                _ if inner.vt.0 == VT_ARRAY.0 | VT_R8.0 => doubles_of(inner.Anonymous.parray).map(Value::R8s),
                _ => None,
            }
        }
    }
}

/// A one-dimensional zero-based SAFEARRAY's doubles.
///
/// # Safety
/// `array` is NULL or a live SAFEARRAY of VT_R8.
unsafe fn doubles_of(array: *mut SAFEARRAY) -> Option<Vec<f64>> {
    if array.is_null() {
        return None;
    }
    // SAFETY: a live SAFEARRAY (the caller's promise), read while accessed.
    unsafe {
        if SafeArrayGetDim(array) != 1 {
            return None;
        }
        let lower = SafeArrayGetLBound(array, 1).ok()?;
        let upper = SafeArrayGetUBound(array, 1).ok()?;
        if lower != 0 || upper < -1 {
            return None;
        }
        let mut data = std::ptr::null_mut();
        SafeArrayAccessData(array, &mut data).ok()?;
        let values = std::slice::from_raw_parts(data.cast::<f64>(), (upper + 1) as usize).to_vec();
        let _ = SafeArrayUnaccessData(array);
        Some(values)
    }
}

/// The items' values, shared by the server and its groups.
struct Space {
    values: Mutex<Vec<Value>>,
}

impl Space {
    fn value(&self, index: usize) -> Option<Value> {
        self.values.lock().ok()?.get(index).cloned()
    }
}

fn item_of(id: &str) -> Option<usize> {
    ITEM_IDS.iter().position(|known| *known == id)
}

/// A string in task memory, for an out-parameter.
fn task_string(s: &str) -> PWSTR {
    let wide: Vec<u16> = s.encode_utf16().chain([0]).collect();
    // SAFETY: a new allocation of the string's size, filled before it is handed out.
    unsafe {
        let p = CoTaskMemAlloc(wide.len() * 2).cast::<u16>();
        if !p.is_null() {
            std::ptr::copy_nonoverlapping(wide.as_ptr(), p, wide.len());
        }
        PWSTR(p)
    }
}

fn error_text(code: i32) -> windows::core::Result<String> {
    match HRESULT(code) {
        OPC_E_INVALIDHANDLE => Ok("The value of the handle is invalid.".to_owned()),
        OPC_E_BADTYPE => Ok(
            "The server cannot convert the data between the requested data type and the canonical data type."
                .to_owned(),
        ),
        OPC_E_UNKNOWNITEMID => Ok("The item ID is not defined in the server address space.".to_owned()),
        _ => Err(E_INVALIDARG.into()),
    }
}

// ---- The process's objects: it exits once the last server object (or lock) is released ---------------

static LIVE_SERVERS: AtomicUsize = AtomicUsize::new(0);
static EVER_SERVED: AtomicBool = AtomicBool::new(false);
static DONE: (Mutex<bool>, Condvar) = (Mutex::new(false), Condvar::new());

fn server_released() {
    // An unlock without a lock changes nothing.
    let before = LIVE_SERVERS.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| n.checked_sub(1));
    if before == Ok(1) {
        let (lock, signal) = &DONE;
        if let Ok(mut done) = lock.lock() {
            *done = true;
            signal.notify_all();
        }
    }
}

// ---- The server object: the crate's Server<ServerState> ---------------------------------------------

struct DaServer {
    space: Arc<Space>,
    locale: AtomicU32,
    groups: Mutex<BTreeMap<u32, ComObject<Group<DaGroup>>>>,
    next_group: AtomicU32,
}

impl Drop for DaServer {
    fn drop(&mut self) {
        if let Ok(mut groups) = self.groups.lock() {
            for group in groups.values() {
                group.0.disconnect();
            }
            groups.clear();
        }
        server_released();
    }
}

impl DaServer {
    fn new() -> Self {
        LIVE_SERVERS.fetch_add(1, Ordering::SeqCst);
        EVER_SERVED.store(true, Ordering::SeqCst);
        DaServer {
            space: Arc::new(Space {
                values: Mutex::new(initial_values()),
            }),
            locale: AtomicU32::new(0x0800),
            groups: Mutex::new(BTreeMap::new()),
            next_group: AtomicU32::new(FIRST_GROUP_HANDLE),
        }
    }
}

/// `object`'s interface `riid`, as the IUnknown the crate's trait returns (what the caller asked for,
/// so that an in-process caller gets the interface it named).
fn interface_for(object: &IUnknown, riid: Option<u128>) -> windows::core::Result<IUnknown> {
    let iid = GUID::from_u128(riid.unwrap_or(IUnknown::IID.to_u128()));
    let mut raw = std::ptr::null_mut();
    // SAFETY: a QueryInterface with a valid IID and out-pointer; the reference it adds is owned by
    // the IUnknown made from it.
    unsafe {
        object.query(&iid, &mut raw).ok()?;
        Ok(IUnknown::from_raw(raw))
    }
}

impl ServerTrait for DaServer {
    fn set_locale_id(&self, locale_id: u32) -> windows::core::Result<()> {
        if !LOCALES.contains(&locale_id) {
            return Err(E_INVALIDARG.into());
        }
        self.locale.store(locale_id, Ordering::SeqCst);
        Ok(())
    }

    fn get_locale_id(&self) -> windows::core::Result<u32> {
        Ok(self.locale.load(Ordering::SeqCst))
    }

    fn query_available_locale_ids(&self) -> windows::core::Result<Vec<u32>> {
        Ok(LOCALES.to_vec())
    }

    fn get_error_string(&self, error: i32) -> windows::core::Result<String> {
        error_text(error)
    }

    fn set_client_name(&self, _name: String) -> windows::core::Result<()> {
        Ok(())
    }

    fn enum_connection_points(&self) -> windows::core::Result<Vec<IConnectionPoint>> {
        Ok(Vec::new())
    }

    fn find_connection_point(&self, _riid: *const GUID) -> windows::core::Result<IConnectionPoint> {
        Err(CONNECT_E_NOCONNECTION.into())
    }

    fn query_available_properties(&self, item_id: String) -> windows::core::Result<Vec<AvailableProperty>> {
        item_of(&item_id).ok_or(OPC_E_UNKNOWNITEMID)?;
        Ok(vec![
            AvailableProperty {
                property_id: 1,
                description: "Item Canonical Data Type".to_owned(),
                data_type: VT_I2.0,
            },
            AvailableProperty {
                property_id: 101,
                description: "Item Description".to_owned(),
                data_type: VT_BSTR.0,
            },
        ])
    }

    fn get_item_properties(
        &self,
        item_id: String,
        property_ids: Vec<u32>,
    ) -> windows::core::Result<Vec<ItemPropertyData>> {
        let index = item_of(&item_id).ok_or(OPC_E_UNKNOWNITEMID)?;
        Ok(property_ids
            .into_iter()
            .map(|property_id| {
                let (data, error) = match property_id {
                    1 => (Variant::I16(ITEM_TYPES[index] as i16), S_OK),
                    101 => (Variant::String(format!("Description of {item_id}")), S_OK),
                    _ => (Variant::Empty, OPC_E_INVALID_PID),
                };
                ItemPropertyData {
                    property_id,
                    data,
                    error,
                }
            })
            .collect())
    }

    fn lookup_item_ids(&self, item_id: String, property_ids: Vec<u32>) -> windows::core::Result<Vec<NewItem>> {
        item_of(&item_id).ok_or(OPC_E_UNKNOWNITEMID)?;
        Ok(property_ids
            .into_iter()
            .map(|property_id| match property_id {
                101 => NewItem {
                    new_item_id: format!("{item_id}.Description"),
                    error: S_OK,
                },
                _ => NewItem {
                    new_item_id: String::new(),
                    error: OPC_E_INVALID_PID,
                },
            })
            .collect())
    }

    // IOPCBrowse: the crate's Browse and GetProperties write every element's and property's strings
    // through a NULL pointer (PointerWriter::try_write_to), so this server does not serve them.
    fn get_properties(
        &self,
        _item_ids: Vec<String>,
        _return_property_values: bool,
        _property_ids: Vec<u32>,
    ) -> windows::core::Result<Vec<ItemProperties>> {
        Err(E_NOTIMPL.into())
    }

    fn browse(
        &self,
        _item_id: String,
        _continuation_point: Option<String>,
        _max_elements_returned: u32,
        _browse_filter: BrowseFilter,
        _element_name_filter: String,
        _vendor_filter: String,
        _return_all_properties: bool,
        _return_property_values: bool,
        _property_ids: Vec<u32>,
    ) -> windows::core::Result<BrowseResult> {
        Err(E_NOTIMPL.into())
    }

    fn get_public_group_by_name(&self, _name: String, _riid: u128) -> windows::core::Result<IUnknown> {
        Err(E_NOTIMPL.into())
    }

    fn remove_public_group(&self, _server_group: u32, _force: bool) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn query_organization(&self) -> windows::core::Result<NamespaceType> {
        Ok(NamespaceType::Flat)
    }

    fn change_browse_position(&self, _direction: BrowseDirection) -> windows::core::Result<()> {
        // A flat address space has no branches to move to.
        Err(E_FAIL.into())
    }

    fn browse_opc_item_ids(
        &self,
        browse_type: BrowseType,
        filter: String,
        data_type: u16,
        access_rights: u32,
    ) -> windows::core::Result<IEnumString> {
        let names: Vec<String> = match browse_type {
            BrowseType::Branch => Vec::new(),
            BrowseType::Leaf | BrowseType::Flat => ITEM_IDS
                .iter()
                .zip(ITEM_TYPES)
                .filter(|(id, vt)| {
                    (filter.is_empty() || filter == "*" || id.contains(filter.as_str()))
                        && (data_type == 0 || data_type == *vt)
                        && access_rights & !(OPC_READABLE | OPC_WRITEABLE) == 0
                })
                .map(|(id, _)| (*id).to_owned())
                .collect(),
        };
        Ok(Names {
            names,
            next: AtomicUsize::new(0),
        }
        .into())
    }

    fn get_item_id(&self, item_data_id: String) -> windows::core::Result<String> {
        item_of(&item_data_id).ok_or(OPC_E_UNKNOWNITEMID)?;
        Ok(item_data_id)
    }

    fn browse_access_paths(&self, _item_id: String) -> windows::core::Result<Vec<String>> {
        Err(E_NOTIMPL.into())
    }

    fn read(&self, _items: Vec<ItemWithMaxAge>) -> windows::core::Result<Vec<VqtWithError>> {
        Err(E_NOTIMPL.into())
    }

    fn write_vqt(&self, _items: Vec<ItemOptionalVqt>) -> windows::core::Result<Vec<HRESULT>> {
        Err(E_NOTIMPL.into())
    }

    fn add_group(
        &self,
        name: String,
        active: bool,
        requested_update_rate: u32,
        client_group: u32,
        time_bias: Option<i32>,
        percent_deadband: Option<f32>,
        locale_id: u32,
        reference_interface_id: Option<u128>,
    ) -> windows::core::Result<GroupInfo> {
        if !(0.0..=100.0).contains(&percent_deadband.unwrap_or(0.0)) {
            return Err(E_INVALIDARG.into());
        }
        let handle = self.next_group.fetch_add(1, Ordering::SeqCst);
        let group = ComObject::new(Group(DaGroup {
            space: Arc::clone(&self.space),
            name,
            update_rate: requested_update_rate,
            active: AtomicBool::new(active),
            time_bias: time_bias.unwrap_or(0),
            percent_deadband: percent_deadband.unwrap_or(0.0),
            locale: locale_id,
            client_handle: client_group,
            server_handle: handle,
            items: Mutex::new(BTreeMap::new()),
            point: Mutex::new(None),
            next_cancel: AtomicU32::new(1),
            enabled: AtomicBool::new(true),
        }));
        // The crate's connection point for IOPCDataCallback, in the group's container. It holds the
        // group; the server breaks that cycle when the group is removed or the server released.
        let container: IConnectionPointContainer = group.to_interface();
        let point: IConnectionPoint = ConnectionPoint::new(container, IOPCDataCallback::IID).into();
        if let Ok(mut slot) = group.0.point.lock() {
            *slot = Some(point);
        }
        let unknown = interface_for(&group.to_interface::<IUnknown>(), reference_interface_id);
        let unknown = match unknown {
            Ok(unknown) => unknown,
            Err(error) => {
                group.0.disconnect();
                return Err(error);
            }
        };
        self.groups.lock().map_err(|_| E_FAIL)?.insert(handle, group);
        Ok(GroupInfo {
            server_group: handle,
            revised_update_rate: requested_update_rate,
            unknown,
        })
    }

    fn get_error_string_locale(&self, error: i32, _locale: u32) -> windows::core::Result<String> {
        error_text(error)
    }

    fn get_group_by_name(&self, name: String, riid: Option<u128>) -> windows::core::Result<IUnknown> {
        let groups = self.groups.lock().map_err(|_| E_FAIL)?;
        let group = groups.values().find(|g| g.0.name == name).ok_or(E_INVALIDARG)?;
        interface_for(&group.to_interface::<IUnknown>(), riid)
    }

    fn get_status(&self) -> windows::core::Result<ServerStatus> {
        Ok(ServerStatus {
            start_time: da_system_time(0),
            current_time: da_system_time(1),
            last_update_time: da_system_time(2),
            server_state: ServerState::Running,
            group_count: self.groups.lock().map_err(|_| E_FAIL)?.len() as u32,
            band_width: 0xFFFF_FFFF,
            major_version: 3,
            minor_version: 0,
            build_number: 42,
            vendor_info: VENDOR_INFO.to_owned(),
        })
    }

    fn remove_group(&self, server_group: u32, _force: bool) -> windows::core::Result<()> {
        let group = self
            .groups
            .lock()
            .map_err(|_| E_FAIL)?
            .remove(&server_group)
            .ok_or(E_INVALIDARG)?;
        group.0.disconnect();
        Ok(())
    }

    fn create_group_enumerator(&self, _scope: EnumScope, _riid: Option<u128>) -> windows::core::Result<IUnknown> {
        Err(E_NOTIMPL.into())
    }
}

// ---- The IEnumString of browse_opc_item_ids ---------------------------------------------------------

/// The item IDs a browse found. (The crate's own StringEnumerator cannot be used: its Next indexes an
/// empty vector, a panic, and hands out pointers into its own memory instead of task memory.)
#[implement(IEnumString)]
struct Names {
    names: Vec<String>,
    next: AtomicUsize,
}

impl IEnumString_Impl for Names_Impl {
    fn Next(&self, count: u32, elements: *mut PWSTR, fetched: *mut u32) -> HRESULT {
        if elements.is_null() || (count != 1 && fetched.is_null()) {
            return E_POINTER;
        }
        let start = self.next.load(Ordering::SeqCst).min(self.names.len());
        let end = (start + count as usize).min(self.names.len());
        for (k, name) in self.names[start..end].iter().enumerate() {
            // SAFETY: `elements` holds `count` slots (the caller's), and k < count.
            unsafe { *elements.add(k) = task_string(name) };
        }
        self.next.store(end, Ordering::SeqCst);
        if !fetched.is_null() {
            // SAFETY: checked non-NULL above.
            unsafe { *fetched = (end - start) as u32 };
        }
        if end - start == count as usize { S_OK } else { S_FALSE }
    }

    fn Skip(&self, count: u32) -> HRESULT {
        let start = self.next.load(Ordering::SeqCst);
        let end = (start + count as usize).min(self.names.len());
        self.next.store(end, Ordering::SeqCst);
        if end - start == count as usize { S_OK } else { S_FALSE }
    }

    fn Reset(&self) -> windows::core::Result<()> {
        self.next.store(0, Ordering::SeqCst);
        Ok(())
    }

    fn Clone(&self) -> windows::core::Result<IEnumString> {
        Ok(Names {
            names: self.names.clone(),
            next: AtomicUsize::new(self.next.load(Ordering::SeqCst)),
        }
        .into())
    }
}

// ---- A group: the crate's Group<DaGroup> ----------------------------------------------------------------

struct DaGroup {
    space: Arc<Space>,
    name: String,
    update_rate: u32,
    active: AtomicBool,
    time_bias: i32,
    percent_deadband: f32,
    locale: u32,
    client_handle: u32,
    server_handle: u32,
    /// Server handle -> (item index, client handle).
    items: Mutex<BTreeMap<u32, (usize, u32)>>,
    point: Mutex<Option<IConnectionPoint>>,
    next_cancel: AtomicU32,
    enabled: AtomicBool,
}

/// One item of a callback.
struct Reported {
    client: u32,
    value: VARIANT,
    time: FILETIME,
}

impl DaGroup {
    /// Drops the connection point (which holds the group).
    fn disconnect(&self) {
        if let Ok(mut point) = self.point.lock() {
            *point = None;
        }
    }

    /// The advised sinks, through the crate's connection point's IEnumConnections.
    fn sinks(&self) -> Vec<IOPCDataCallback> {
        let Some(point) = self.point.lock().ok().and_then(|p| p.clone()) else {
            return Vec::new();
        };
        // SAFETY: plain calls on a live connection point; each CONNECTDATA's reference is taken over.
        unsafe {
            let Ok(connections) = point.EnumConnections() else {
                return Vec::new();
            };
            let mut sinks = Vec::new();
            loop {
                let mut data = [CONNECTDATA::default()];
                let mut fetched = 0;
                let hr = connections.Next(&mut data, &mut fetched);
                if hr != S_OK || fetched != 1 {
                    break;
                }
                let unknown = std::mem::ManuallyDrop::into_inner(std::mem::take(&mut data[0].pUnk));
                if let Some(sink) = unknown.and_then(|u| u.cast::<IOPCDataCallback>().ok()) {
                    sinks.push(sink);
                }
            }
            sinks
        }
    }

    fn item(&self, server: u32) -> Option<(usize, u32)> {
        self.items.lock().ok()?.get(&server).copied()
    }

    /// Calls every sink from a thread of the server: a data change (`read` false) or a read
    /// completion.
    fn report(&self, read: bool, transaction: u32, items: Vec<Reported>) {
        let job = Callback {
            sinks: self.sinks(),
            items,
        };
        let group = self.client_handle;
        std::thread::spawn(move || {
            // The whole job (Send), not its fields (which are not).
            let job = job;
            let Callback { sinks, items } = job;
            // SAFETY: the thread joins the process's multithreaded apartment for its calls.
            let _ = unsafe { CoInitializeEx(None, COINIT_MULTITHREADED) };
            let handles: Vec<u32> = items.iter().map(|i| i.client).collect();
            let values: Vec<VARIANT> = items.iter().map(|i| i.value.clone()).collect();
            let qualities = vec![QUALITY_GOOD; items.len()];
            let times: Vec<FILETIME> = items.iter().map(|i| i.time).collect();
            let errors = vec![S_OK; items.len()];
            for sink in &sinks {
                // SAFETY: arrays of `items.len()` elements each, live for the call.
                let _ = unsafe {
                    if read {
                        sink.OnReadComplete(
                            transaction,
                            group,
                            S_OK,
                            S_OK,
                            items.len() as u32,
                            handles.as_ptr(),
                            values.as_ptr(),
                            qualities.as_ptr(),
                            times.as_ptr(),
                            errors.as_ptr(),
                        )
                    } else {
                        sink.OnDataChange(
                            transaction,
                            group,
                            S_OK,
                            S_OK,
                            items.len() as u32,
                            handles.as_ptr(),
                            values.as_ptr(),
                            qualities.as_ptr(),
                            times.as_ptr(),
                            errors.as_ptr(),
                        )
                    }
                };
            }
            drop(sinks);
            // SAFETY: pairs the CoInitializeEx above.
            unsafe { CoUninitialize() };
        });
    }
}

/// What a callback thread calls, and with what.
struct Callback {
    sinks: Vec<IOPCDataCallback>,
    items: Vec<Reported>,
}

// SAFETY: the sinks are proxies (or objects) of the multithreaded apartment, which any of its
// threads may call; the VARIANTs are owned values moved to the thread.
unsafe impl Send for Callback {}

/// Writes `value` into a slot of an array the crate allocated with CoTaskMemAlloc and did not
/// initialise (an assignment would drop the garbage there first).
fn put<T>(slot: &mut T, value: T) {
    // SAFETY: `slot` is valid for writes; its old contents are not read or dropped.
    unsafe { std::ptr::write(slot, value) };
}

fn item_result(index: usize) -> tagOPCITEMRESULT {
    tagOPCITEMRESULT {
        hServer: item_handle(index),
        vtCanonicalDataType: ITEM_TYPES[index],
        wReserved: 0,
        dwAccessRights: OPC_READABLE | OPC_WRITEABLE,
        dwBlobSize: 0,
        pBlob: std::ptr::null_mut(),
    }
}

fn no_item_result() -> tagOPCITEMRESULT {
    tagOPCITEMRESULT {
        hServer: 0,
        vtCanonicalDataType: 0,
        wReserved: 0,
        dwAccessRights: 0,
        dwBlobSize: 0,
        pBlob: std::ptr::null_mut(),
    }
}

/// The item a definition names, or why not.
fn validate(def: &tagOPCITEMDEF) -> Result<usize, HRESULT> {
    if def.szItemID.is_null() {
        return Err(OPC_E_UNKNOWNITEMID);
    }
    // SAFETY: a NUL-terminated string of the request.
    let id = unsafe { def.szItemID.to_string() }.map_err(|_| OPC_E_UNKNOWNITEMID)?;
    let index = item_of(&id).ok_or(OPC_E_UNKNOWNITEMID)?;
    if def.vtRequestedDataType != 0 && def.vtRequestedDataType != ITEM_TYPES[index] {
        return Err(OPC_E_BADTYPE);
    }
    Ok(index)
}

impl GroupTrait for DaGroup {
    fn add_items(
        &self,
        items: &[tagOPCITEMDEF],
        results: &mut [tagOPCITEMRESULT],
        errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        let mut added = self.items.lock().map_err(|_| E_FAIL)?;
        for ((def, result), error) in items.iter().zip(results.iter_mut()).zip(errors.iter_mut()) {
            match validate(def) {
                Ok(index) => {
                    added.insert(item_handle(index), (index, def.hClient));
                    put(result, item_result(index));
                    put(error, S_OK);
                }
                Err(code) => {
                    put(result, no_item_result());
                    put(error, code);
                }
            }
        }
        Ok(())
    }

    fn validate_items(
        &self,
        items: &[tagOPCITEMDEF],
        _blob_update: BOOL,
        results: &mut [tagOPCITEMRESULT],
        errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        for ((def, result), error) in items.iter().zip(results.iter_mut()).zip(errors.iter_mut()) {
            match validate(def) {
                Ok(index) => {
                    put(result, item_result(index));
                    put(error, S_OK);
                }
                Err(code) => {
                    put(result, no_item_result());
                    put(error, code);
                }
            }
        }
        Ok(())
    }

    fn remove_items(&self, handles: &[u32], errors: &mut [HRESULT]) -> windows::core::Result<()> {
        let mut added = self.items.lock().map_err(|_| E_FAIL)?;
        for (handle, error) in handles.iter().zip(errors.iter_mut()) {
            put(
                error,
                if added.remove(handle).is_some() {
                    S_OK
                } else {
                    OPC_E_INVALIDHANDLE
                },
            );
        }
        Ok(())
    }

    fn set_active_state(&self, handles: &[u32], _active: BOOL, errors: &mut [HRESULT]) -> windows::core::Result<()> {
        for (handle, error) in handles.iter().zip(errors.iter_mut()) {
            put(
                error,
                if self.item(*handle).is_some() {
                    S_OK
                } else {
                    OPC_E_INVALIDHANDLE
                },
            );
        }
        Ok(())
    }

    fn set_client_handles(
        &self,
        handles: &[u32],
        clients: &[u32],
        errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        let mut added = self.items.lock().map_err(|_| E_FAIL)?;
        for ((handle, client), error) in handles.iter().zip(clients).zip(errors.iter_mut()) {
            put(
                error,
                match added.get_mut(handle) {
                    Some(item) => {
                        item.1 = *client;
                        S_OK
                    }
                    None => OPC_E_INVALIDHANDLE,
                },
            );
        }
        Ok(())
    }

    fn set_data_types(&self, handles: &[u32], types: &[u16], errors: &mut [HRESULT]) -> windows::core::Result<()> {
        for ((handle, vt), error) in handles.iter().zip(types).zip(errors.iter_mut()) {
            put(
                error,
                match self.item(*handle) {
                    Some((index, _)) if *vt == 0 || *vt == ITEM_TYPES[index] => S_OK,
                    Some(_) => OPC_E_BADTYPE,
                    None => OPC_E_INVALIDHANDLE,
                },
            );
        }
        Ok(())
    }

    fn create_enumerator(&self, _riid: &GUID) -> windows::core::Result<IUnknown> {
        Err(E_NOTIMPL.into())
    }

    fn get_state(
        &self,
        update_rate: &mut u32,
        active: &mut BOOL,
        name: &mut PWSTR,
        time_bias: &mut i32,
        percent_deadband: &mut f32,
        locale_id: &mut u32,
        group_client_handle: &mut u32,
        group_server_handle: &mut u32,
    ) -> windows::core::Result<()> {
        let text = task_string(&self.name);
        if text.is_null() {
            return Err(windows::Win32::Foundation::E_OUTOFMEMORY.into());
        }
        *update_rate = self.update_rate;
        *active = self.active.load(Ordering::SeqCst).into();
        *name = text;
        *time_bias = self.time_bias;
        *percent_deadband = self.percent_deadband;
        *locale_id = self.locale;
        *group_client_handle = self.client_handle;
        *group_server_handle = self.server_handle;
        Ok(())
    }

    fn set_state(
        &self,
        _requested_update_rate: &u32,
        _revised_update_rate: &mut u32,
        _active: &BOOL,
        _time_bias: &i32,
        _percent_deadband: &f32,
        _locale_id: &u32,
        _group_client_handle: &u32,
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn set_name(&self, _name: &PCWSTR) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn clone_group(&self, _name: &PCWSTR, _riid: &GUID) -> windows::core::Result<IUnknown> {
        Err(E_NOTIMPL.into())
    }

    fn set_keep_alive(&self, _keep_alive_time: u32) -> windows::core::Result<u32> {
        Err(E_NOTIMPL.into())
    }

    fn get_keep_alive(&self) -> windows::core::Result<u32> {
        Err(E_NOTIMPL.into())
    }

    fn get_public_group_state(&self) -> windows::core::Result<BOOL> {
        Ok(false.into())
    }

    fn move_to_public(&self) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn read(
        &self,
        source: tagOPCDATASOURCE,
        handles: &[u32],
        states: &mut [tagOPCITEMSTATE],
        errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        // The device's time is 10 s after the cache's (tests/oop/da.h).
        let offset = if source == OPC_DS_DEVICE { 10 } else { 0 };
        for ((handle, state), error) in handles.iter().zip(states.iter_mut()).zip(errors.iter_mut()) {
            match self
                .item(*handle)
                .and_then(|(index, client)| Some((index, client, self.space.value(index)?)))
            {
                Some((index, client, value)) => {
                    put(
                        state,
                        tagOPCITEMSTATE {
                            hClient: client,
                            ftTimeStamp: da_time(index as u64 + offset),
                            wQuality: QUALITY_GOOD,
                            wReserved: 0,
                            vDataValue: value.to_variant(),
                        },
                    );
                    put(error, S_OK);
                }
                None => {
                    put(
                        state,
                        tagOPCITEMSTATE {
                            hClient: 0,
                            ftTimeStamp: FILETIME::default(),
                            wQuality: 0,
                            wReserved: 0,
                            vDataValue: VARIANT::default(),
                        },
                    );
                    put(error, OPC_E_INVALIDHANDLE);
                }
            }
        }
        Ok(())
    }

    fn write(&self, handles: &[u32], values: &[VARIANT], errors: &mut [HRESULT]) -> windows::core::Result<()> {
        let mut stored = self.space.values.lock().map_err(|_| E_FAIL)?;
        for ((handle, value), error) in handles.iter().zip(values).zip(errors.iter_mut()) {
            put(
                error,
                match self.item(*handle) {
                    Some((index, _)) => match Value::from_variant(value, ITEM_TYPES[index]) {
                        Some(value) => {
                            stored[index] = value;
                            S_OK
                        }
                        None => OPC_E_BADTYPE,
                    },
                    None => OPC_E_INVALIDHANDLE,
                },
            );
        }
        Ok(())
    }

    fn read_max_age(
        &self,
        _handles: &[u32],
        _max_age: &[u32],
        _values: &mut [VARIANT],
        _qualities: &mut [u16],
        _timestamps: &mut [FILETIME],
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn write_vqt(
        &self,
        _count: u32,
        _handles: &[u32],
        _item_vqt: &[tagOPCITEMVQT],
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn read2(
        &self,
        handles: &[u32],
        transaction_id: u32,
        cancel_id: &mut u32,
        errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        if self.sinks().is_empty() {
            return Err(CONNECT_E_NOCONNECTION.into());
        }
        let mut reported = Vec::new();
        for (handle, error) in handles.iter().zip(errors.iter_mut()) {
            match self
                .item(*handle)
                .and_then(|(index, client)| Some((index, client, self.space.value(index)?)))
            {
                Some((index, client, value)) => {
                    reported.push(Reported {
                        client,
                        value: value.to_variant(),
                        time: da_time(index as u64 + 10),
                    });
                    put(error, S_OK);
                }
                None => put(error, OPC_E_INVALIDHANDLE),
            }
        }
        *cancel_id = self.next_cancel.fetch_add(1, Ordering::SeqCst);
        if !reported.is_empty() {
            self.report(true, transaction_id, reported);
        }
        Ok(())
    }

    fn write2(
        &self,
        _count: u32,
        _handles: &[u32],
        _values: &[VARIANT],
        _transaction_id: u32,
        _cancel_id: &mut u32,
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn refresh2(&self, _source: tagOPCDATASOURCE, transaction_id: u32) -> windows::core::Result<u32> {
        if self.sinks().is_empty() {
            return Err(CONNECT_E_NOCONNECTION.into());
        }
        let items: Vec<(usize, u32)> = self.items.lock().map_err(|_| E_FAIL)?.values().copied().collect();
        if items.is_empty() || !self.active.load(Ordering::SeqCst) {
            return Err(E_FAIL.into());
        }
        // A refresh is stamped 20 s after the cache's time (tests/oop/da.h).
        let reported = items
            .into_iter()
            .filter_map(|(index, client)| {
                Some(Reported {
                    client,
                    value: self.space.value(index)?.to_variant(),
                    time: da_time(index as u64 + 20),
                })
            })
            .collect();
        let cancel = self.next_cancel.fetch_add(1, Ordering::SeqCst);
        self.report(false, transaction_id, reported);
        Ok(cancel)
    }

    fn cancel2(&self, _cancel_id: u32) -> windows::core::Result<()> {
        Err(E_FAIL.into())
    }

    fn set_enable(&self, enable: BOOL) -> windows::core::Result<()> {
        self.enabled.store(enable.as_bool(), Ordering::SeqCst);
        Ok(())
    }

    fn get_enable(&self) -> windows::core::Result<BOOL> {
        Ok(self.enabled.load(Ordering::SeqCst).into())
    }

    fn read_max_age2(
        &self,
        _handles: &[u32],
        _max_age: &[u32],
        _transaction_id: u32,
        _cancel_id: &mut u32,
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn write_vqt2(
        &self,
        _handles: &[u32],
        _item_vqt: &[tagOPCITEMVQT],
        _transaction_id: u32,
        _cancel_id: &mut u32,
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn refresh_max_age(&self, _max_age: u32, _transaction_id: u32) -> windows::core::Result<u32> {
        Err(E_NOTIMPL.into())
    }

    fn set_item_deadband(
        &self,
        _handles: &[u32],
        _deadband: &[f32],
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn get_item_deadband(
        &self,
        _handles: &[u32],
        _deadband: &mut [f32],
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn clear_item_deadband(&self, _handles: &[u32], _errors: &mut [HRESULT]) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn set_item_sampling_rate(
        &self,
        _count: u32,
        _handles: &[u32],
        _requested: &[u32],
        _revised: &mut [u32],
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn get_item_sampling_rate(
        &self,
        _handles: &[u32],
        _rates: &mut [u32],
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn clear_item_sampling_rate(&self, _handles: &[u32], _errors: &mut [HRESULT]) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn set_item_buffer_enable(
        &self,
        _handles: &[u32],
        _enable: &BOOL,
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn get_item_buffer_enable(
        &self,
        _handles: &[u32],
        _enable: &mut [BOOL],
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn enum_connection_points(&self) -> windows::core::Result<IEnumConnectionPoints> {
        Err(E_NOTIMPL.into())
    }

    fn find_connection_point(&self, riid: &GUID) -> windows::core::Result<IConnectionPoint> {
        if *riid != IOPCDataCallback::IID {
            return Err(CONNECT_E_NOCONNECTION.into());
        }
        self.point
            .lock()
            .ok()
            .and_then(|p| p.clone())
            .ok_or_else(|| CONNECT_E_NOCONNECTION.into())
    }

    fn read3(
        &self,
        _connection: u32,
        _source: tagOPCDATASOURCE,
        _handles: &[u32],
        _transaction_id: &mut u32,
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn write3(
        &self,
        _connection: u32,
        _handles: &[u32],
        _values: &[VARIANT],
        _transaction_id: &mut u32,
        _errors: &mut [HRESULT],
    ) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn refresh(&self, _connection: u32, _source: tagOPCDATASOURCE) -> windows::core::Result<u32> {
        Err(E_NOTIMPL.into())
    }

    fn cancel(&self, _transaction_id: u32) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn get_data(&self, _format: &FORMATETC) -> windows::core::Result<STGMEDIUM> {
        Err(E_NOTIMPL.into())
    }

    fn get_data_here(&self, _format: &FORMATETC, _medium: &mut STGMEDIUM) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn query_get_data(&self, _format: &FORMATETC) -> HRESULT {
        E_NOTIMPL
    }

    fn get_canonical_format_etc(&self, _format: &FORMATETC, _out: &mut FORMATETC) -> HRESULT {
        E_NOTIMPL
    }

    fn set_data(&self, _format: &FORMATETC, _medium: &STGMEDIUM, _release: BOOL) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn enum_format_etc(&self, _direction: u32) -> windows::core::Result<IEnumFORMATETC> {
        Err(E_NOTIMPL.into())
    }

    fn data_advise(
        &self,
        _format: &FORMATETC,
        _adv: u32,
        _sink: windows::core::Ref<'_, IAdviseSink>,
    ) -> windows::core::Result<u32> {
        Err(E_NOTIMPL.into())
    }

    fn data_unadvise(&self, _connection: u32) -> windows::core::Result<()> {
        Err(E_NOTIMPL.into())
    }

    fn enum_data_advise(&self) -> windows::core::Result<IEnumSTATDATA> {
        Err(E_NOTIMPL.into())
    }
}

// ---- COM hosting -----------------------------------------------------------------------------------------

#[implement(IClassFactory)]
struct Factory;

impl IClassFactory_Impl for Factory_Impl {
    fn CreateInstance(
        &self,
        outer: windows::core::Ref<'_, IUnknown>,
        riid: *const GUID,
        object: *mut *mut core::ffi::c_void,
    ) -> windows::core::Result<()> {
        if object.is_null() || riid.is_null() {
            return Err(E_POINTER.into());
        }
        // SAFETY: checked non-NULL; the out-pointer is cleared before anything can fail.
        unsafe { *object = std::ptr::null_mut() };
        if outer.is_some() {
            return Err(windows::Win32::Foundation::CLASS_E_NOAGGREGATION.into());
        }
        let server: IUnknown = ComObject::new(Server(DaServer::new())).into_interface();
        // SAFETY: a QueryInterface with the caller's IID and out-pointer.
        unsafe { server.query(riid, object).ok() }
    }

    fn LockServer(&self, lock: BOOL) -> windows::core::Result<()> {
        // A lock keeps the process as a server object does.
        if lock.as_bool() {
            LIVE_SERVERS.fetch_add(1, Ordering::SeqCst);
            EVER_SERVED.store(true, Ordering::SeqCst);
        } else {
            server_released();
        }
        Ok(())
    }
}

fn class_key() -> String {
    format!("Software\\Classes\\CLSID\\{{{:?}}}", CLSID_CRATE_SERVER)
}

fn wide(s: &str) -> Vec<u16> {
    s.encode_utf16().chain([0]).collect()
}

fn set_value(key: &str, value: &str) -> Result<(), String> {
    let (key_w, value_w) = (wide(key), wide(value));
    // SAFETY: NUL-terminated strings, and the data's size in bytes including its NUL.
    let rc = unsafe {
        RegSetKeyValueW(
            HKEY_LOCAL_MACHINE,
            PCWSTR(key_w.as_ptr()),
            PCWSTR::null(),
            REG_SZ.0,
            Some(value_w.as_ptr().cast()),
            (value_w.len() * 2) as u32,
        )
    };
    if rc.is_ok() {
        Ok(())
    } else {
        Err(format!("RegSetKeyValueW({key}): {}", rc.0))
    }
}

fn register() -> Result<(), String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let key = class_key();
    set_value(&key, "opc_da 0.3.1 server module (opccomn third-party test server)")?;
    set_value(&format!("{key}\\LocalServer32"), &format!("\"{}\"", exe.display()))
}

fn unregister() -> Result<(), String> {
    let key = wide(&class_key());
    // SAFETY: a NUL-terminated key name.
    let rc = unsafe { RegDeleteTreeW(HKEY_LOCAL_MACHINE, PCWSTR(key.as_ptr())) };
    if rc.is_ok() || rc.0 == 2 {
        Ok(())
    } else {
        Err(format!("RegDeleteTreeW: {}", rc.0))
    }
}

fn serve() -> Result<(), String> {
    // SAFETY: this thread joins the multithreaded apartment for the life of the process.
    unsafe { CoInitializeEx(None, COINIT_MULTITHREADED) }
        .ok()
        .map_err(|e| format!("CoInitializeEx: {e}"))?;
    let factory: IClassFactory = Factory.into();
    // SAFETY: the factory lives until it is revoked below.
    let cookie =
        unsafe { CoRegisterClassObject(&CLSID_CRATE_SERVER, &factory, CLSCTX_LOCAL_SERVER, REGCLS_MULTIPLEUSE) }
            .map_err(|e| format!("CoRegisterClassObject: {e}"))?;
    // Until the last server object is released (or, when no client ever creates one, a minute).
    let (lock, signal) = &DONE;
    let mut done = lock.lock().map_err(|_| "lock".to_owned())?;
    let started = std::time::Instant::now();
    while !*done {
        let (next, _) = signal
            .wait_timeout(done, Duration::from_secs(1))
            .map_err(|_| "lock".to_owned())?;
        done = next;
        if !EVER_SERVED.load(Ordering::SeqCst) && started.elapsed() > Duration::from_secs(60) {
            break;
        }
    }
    drop(done);
    // SAFETY: the cookie CoRegisterClassObject returned; then this thread leaves the apartment.
    unsafe {
        let _ = CoRevokeClassObject(cookie);
        CoUninitialize();
    }
    Ok(())
}

fn main() -> std::process::ExitCode {
    let arg = std::env::args().nth(1).unwrap_or_default().to_ascii_lowercase();
    let result = match arg.trim_start_matches(['/', '-']) {
        "regserver" => register(),
        "unregserver" => unregister(),
        _ => serve(),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("opc_da_crate_server: {message}");
            std::process::ExitCode::FAILURE
        }
    }
}
