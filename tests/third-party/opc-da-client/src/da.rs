//! A Data Access server in another process through opccomn.dll's proxy/stub, with `opc_da`'s own v2
//! client code: the C test server `opc_da_test_server.exe` (tests/oop/da_server.c), whose items and
//! values are those of tests/oop/da.h, repeated below; then `opc_da_crate_server.exe`
//! (tests/third-party/opc-da-server), a server made with `opc_da`'s server module that serves the
//! same items, its x64 build and, when registered, its x86 build.
//!
//! The crate's client API is used wherever it has a call: `v2::Client::create_server`, `ServerTrait`
//! (AddGroup, GetStatus, RemoveGroup), `CommonTrait`, `ItemPropertiesTrait`, `ItemMgtTrait`,
//! `SyncIoTrait`, `AsyncIo2Trait` (Read, Refresh2), `GroupStateMgtTrait`,
//! `ConnectionPointContainerTrait` and `BrowseTrait` (on a wrapper holding the server's IOPCBrowse:
//! the crate's v2 server has no IOPCBrowse and its v3 server wants IOPCItemIO, which the test server
//! does not have). Raw calls through `opc_da_bindings` / windows-rs only where the crate has no
//! wrapper: `IConnectionPoint::Advise` / `Unadvise`, and the data callback, an `#[implement]` sink of
//! this program's (the crate's own `DataCallback` frees the `[in]` arrays it is called with, which
//! belong to the caller, so it cannot be used across processes).

use std::sync::{Arc, Mutex};

use opc_da::client::{
    AsyncIo2Trait, BrowseServerAddressSpaceTrait, BrowseTrait, ClientTrait, CommonTrait, ConnectionPointContainerTrait,
    GroupStateMgtTrait, ItemMgtTrait, ItemPropertiesTrait, ServerTrait, SyncIoTrait, v2,
};
use opc_da::def::ClassContext;
use opc_da::utils::RemoteArray;
use opc_da_bindings::{
    IOPCAsyncIO2, IOPCBrowse, IOPCBrowseServerAddressSpace, IOPCDataCallback, IOPCDataCallback_Impl, IOPCGroupStateMgt,
    IOPCItemMgt, IOPCItemProperties, IOPCServer, IOPCSyncIO, OPC_BRANCH, OPC_BROWSE_DOWN, OPC_BROWSE_FILTER_ALL,
    OPC_BROWSE_ISITEM, OPC_DS_CACHE, OPC_DS_DEVICE, OPC_FLAT, OPC_NS_FLAT, OPC_READABLE, OPC_STATUS_RUNNING,
    OPC_WRITEABLE, tagOPCBROWSETYPE, tagOPCITEMDEF, tagOPCITEMPROPERTY, tagOPCITEMSTATE,
};
use windows::Win32::Foundation::{E_FAIL, E_INVALIDARG, FILETIME, S_FALSE, S_OK};
use windows::Win32::System::Com::{CoDisconnectObject, CoGetPSClsid, CoTaskMemFree, IEnumString, SAFEARRAY};
use windows::Win32::System::Ole::{
    SafeArrayAccessData, SafeArrayCreateVector, SafeArrayGetDim, SafeArrayGetLBound, SafeArrayGetUBound,
    SafeArrayUnaccessData,
};
use windows::Win32::System::Variant::{VARENUM, VARIANT, VT_ARRAY, VT_BSTR, VT_I2, VT_I4, VT_R8};
use windows::core::{GUID, HRESULT, Interface, PWSTR};
use windows_core::implement;

use crate::{
    CALLBACK_DEADLINE, CONNECT_E_NOCONNECTION, EXIT_DEADLINE, OPC_E_UNKNOWNITEMID, Tally, View, braced, default_value,
    hex, process_running, wait_until,
};

/// opccomn.dll's proxy/stub class.
const CLSID_OPCCOMN_PROXY_STUB: GUID = GUID::from_u128(0x3d738b71_0b9d_4337_a725_e8541a96d1c9);

/// A Data Access server this program is a client of: both serve the address space below.
pub(crate) struct Target {
    /// Its class, a LocalServer32.
    clsid: GUID,
    /// Its program, as the process list names it.
    exe: &'static str,
    /// The registry view of its LocalServer32 (an x86 server registers in the 32-bit one).
    view: View,
    /// What the program calls it.
    name: &'static str,
    /// Made with `opc_da` 0.3.1's server module (tests/third-party/opc-da-server): where the crate
    /// answers differently from the C test server, the program checks what the crate does (each
    /// case is named where it is checked, and in docs/dev/third-party-client.md).
    made_with_crate: bool,
}

/// The project's C test server (CLSID_DaTestServer, tests/oop/da.h, da_server.c).
pub(crate) const C_TEST_SERVER: Target = Target {
    clsid: GUID::from_u128(0xc3000000_5eed_4000_8000_00000000da02),
    exe: "opc_da_test_server.exe",
    view: View::Bits64,
    name: "the C test server (x64)",
    made_with_crate: false,
};

/// A server written with the crate `opc_da` 0.3.1's server module (its `Server` and `Group` COM
/// objects and its `ConnectionPoint`), serving the same items: the x64 build.
pub(crate) const CRATE_SERVER: Target = Target {
    clsid: GUID::from_u128(0xc3000000_5eed_4000_8000_00000000da03),
    exe: "opc_da_crate_server.exe",
    view: View::Bits64,
    name: "the opc_da server (x64)",
    made_with_crate: true,
};

/// The same server built for x86 (a 32-bit process under 32-bit Wine, registered in the 32-bit view).
pub(crate) const CRATE_SERVER_X86: Target = Target {
    clsid: GUID::from_u128(0xc3000000_5eed_4000_8000_00000000da04),
    exe: "opc_da_crate_server.exe",
    view: View::Bits32,
    name: "the opc_da server (x86)",
    made_with_crate: true,
};

const OPC_E_INVALIDHANDLE: HRESULT = HRESULT(0xC004_0001_u32 as i32);
const OPC_E_BADTYPE: HRESULT = HRESULT(0xC004_0004_u32 as i32);
const OPC_E_INVALID_PID: HRESULT = HRESULT(0xC004_0203_u32 as i32);
const OPC_E_INVALIDCONTINUATIONPOINT: HRESULT = HRESULT(0xC004_0403_u32 as i32);

// ---- What the server serves (tests/oop/da.h) ----------------------------------------------------------

const GROUP_NAME: &str = "Gruppe \u{e4}\u{f6}\u{fc} 1";
const GROUP_CLIENT_HANDLE: u32 = 42;
/// The server handle the server gives its one group.
const GROUP_SERVER_HANDLE: u32 = 7;
const VENDOR_INFO: &str = "opccomn DA test server \u{20ac}";
const ITEM_IDS: [&str; 4] = [
    "Plant.Tank1.Level (I4)",
    "Plant.Tank1.Temp (R8)",
    "Plant.Tank1.Name (BSTR) \u{20ac}",
    "Plant.Tank1.Profile (R8[])",
];
const UNKNOWN_ITEM: &str = "Plant.Tank1.Nothing";
/// The canonical types: VT_I4, VT_R8, VT_BSTR, VT_ARRAY | VT_R8.
const ITEM_TYPES: [u16; 4] = [3, 5, 8, 0x2005];
const QUALITY_GOOD: u16 = 0xC0;
/// A handle the server never gives.
const BAD_HANDLE: u32 = 999;

fn client_handle(i: usize) -> u32 {
    1000 + i as u32
}

fn server_handle(i: usize) -> u32 {
    100 + i as u32
}

/// The time the server stamps item `i`'s value with, `offset` seconds later (da_time(i + offset)).
fn da_time(i: usize, offset: u64) -> u64 {
    134_095_536_000_000_000 + (i as u64 + offset) * 10_000_000
}

/// A value as it arrives, by its VARIANT type.
#[derive(Debug, Clone, PartialEq)]
enum Value {
    I2(i16),
    I4(i32),
    R8(f64),
    Text(String),
    R8s(Vec<f64>),
    /// Another type, or an array that is not a one-dimensional zero-based one.
    Other(u16),
}

/// The values the server serves at first.
fn initial_values() -> Vec<Value> {
    vec![
        Value::I4(12345),
        Value::R8(3.25),
        Value::Text("Tank \u{e4}\u{f6}\u{fc} \u{20ac} \u{1F600}".to_owned()),
        Value::R8s(vec![1.5, -2.0, 1e300]),
    ]
}

/// The values the program writes.
fn written_values() -> Vec<Value> {
    vec![
        Value::I4(-98765),
        Value::R8(-0.125),
        Value::Text("Geschrieben: Gr\u{fc}\u{df}e \u{2713} \u{1D11E}".to_owned()),
        Value::R8s(vec![0.5, -1e-300, 42.0, 7.0]),
    ]
}

/// One item of a read or a callback.
#[derive(Debug, Clone, PartialEq)]
struct ItemValue {
    client: u32,
    value: Value,
    quality: u16,
    time: u64,
    error: HRESULT,
}

/// What the server should send for items `indices` holding `values`, stamped `offset` seconds on.
fn expected(indices: &[usize], values: &[Value], offset: u64) -> Vec<ItemValue> {
    indices
        .iter()
        .map(|&i| ItemValue {
            client: client_handle(i),
            value: values[i].clone(),
            quality: QUALITY_GOOD,
            time: da_time(i, offset),
            error: S_OK,
        })
        .collect()
}

fn filetime(t: &FILETIME) -> u64 {
    (u64::from(t.dwHighDateTime) << 32) | u64::from(t.dwLowDateTime)
}

/// A SAFEARRAY's doubles, when it is one-dimensional and zero-based.
///
/// # Safety
/// `array` is NULL or a live SAFEARRAY of VT_R8.
unsafe fn doubles_of(array: *mut SAFEARRAY) -> Option<Vec<f64>> {
    if array.is_null() {
        return None;
    }
    // SAFETY: a live SAFEARRAY (the caller's promise); the data is read only while it is accessed.
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

/// The value a VARIANT holds.
fn value_of(v: &VARIANT) -> Value {
    // SAFETY: the union member read is the one `vt` names; a SAFEARRAY is read by doubles_of.
    unsafe {
        let inner = &v.Anonymous.Anonymous;
        let vt = inner.vt;
        if vt == VT_I2 {
            Value::I2(inner.Anonymous.iVal)
        } else if vt == VT_I4 {
            Value::I4(inner.Anonymous.lVal)
        } else if vt == VT_R8 {
            Value::R8(inner.Anonymous.dblVal)
        } else if vt == VT_BSTR {
            Value::Text(inner.Anonymous.bstrVal.to_string())
        } else if vt.0 == VT_ARRAY.0 | VT_R8.0 {
            doubles_of(inner.Anonymous.parray).map_or(Value::Other(vt.0), Value::R8s)
        } else {
            Value::Other(vt.0)
        }
    }
}

/// A VARIANT holding `value` (what the program writes).
fn variant_of(value: &Value) -> VARIANT {
    match value {
        Value::I2(v) => VARIANT::from(*v),
        Value::I4(v) => VARIANT::from(*v),
        Value::R8(v) => VARIANT::from(*v),
        Value::Text(v) => VARIANT::from(v.as_str()),
        Value::R8s(values) => {
            let mut v = VARIANT::default();
            // SAFETY: a new SAFEARRAY of `values.len()` doubles, filled while accessed, then owned by
            // the VARIANT (VariantClear destroys it when the VARIANT is dropped).
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
        Value::Other(_) => VARIANT::default(),
    }
}

/// Reads a string COM allocated for this process and frees it.
fn take_string(p: PWSTR) -> Option<String> {
    if p.is_null() {
        return None;
    }
    // SAFETY: a NUL-terminated string in task memory, owned by this process and freed once here.
    unsafe {
        let text = p.to_string().ok();
        CoTaskMemFree(Some(p.0 as *const _));
        text
    }
}

/// The states of a sync read, their values taken out of the crate's array (which frees only the
/// array itself) and cleared; paired with the per-item errors.
fn take_states(states: &mut RemoteArray<tagOPCITEMSTATE>, errors: &RemoteArray<HRESULT>) -> Vec<ItemValue> {
    let errors = errors.as_slice();
    states
        .as_mut_slice()
        .iter_mut()
        .zip(errors)
        .map(|(state, &error)| {
            let variant = std::mem::take(&mut state.vDataValue);
            ItemValue {
                client: state.hClient,
                value: value_of(&variant),
                quality: state.wQuality,
                time: filetime(&state.ftTimeStamp),
                error,
            }
        })
        .collect()
}

/// Checks that `got` is `want`, showing what came when it is not.
fn check_items(t: &mut Tally, got: &[ItemValue], want: &[ItemValue], what: &str) {
    let same = got == want;
    if same {
        t.check(true, what);
    } else {
        t.check(
            false,
            &format!("{what}\n         got:  {got:?}\n         want: {want:?}"),
        );
    }
}

// ---- The data callback ------------------------------------------------------------------------------

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    DataChange,
    ReadComplete,
    WriteComplete,
    CancelComplete,
}

/// One callback as it arrived.
#[derive(Debug, Clone)]
struct Delivered {
    kind: Kind,
    transaction: u32,
    group: u32,
    quality: HRESULT,
    error: HRESULT,
    items: Vec<ItemValue>,
}

/// What the sink was told, in order.
#[derive(Default)]
struct CallbackLog {
    calls: Mutex<Vec<Delivered>>,
}

impl CallbackLog {
    fn count(&self) -> usize {
        self.calls.lock().map(|c| c.len()).unwrap_or(0)
    }

    fn get(&self, index: usize) -> Option<Delivered> {
        self.calls.lock().ok()?.get(index).cloned()
    }

    fn push(&self, call: Delivered) {
        if let Ok(mut calls) = self.calls.lock() {
            calls.push(call);
        }
    }
}

/// The client's IOPCDataCallback, made with windows-core's `#[implement]`.
#[implement(IOPCDataCallback)]
struct DataSink {
    log: Arc<CallbackLog>,
}

/// The items of a data change or read completion (the `[in, size_is(count)]` arrays).
///
/// # Safety
/// Each pointer is NULL or points at `count` elements for the call.
unsafe fn items_of(
    count: u32,
    handles: *const u32,
    values: *const VARIANT,
    qualities: *const u16,
    times: *const FILETIME,
    errors: *const HRESULT,
) -> Vec<ItemValue> {
    if count == 0 || handles.is_null() || values.is_null() || qualities.is_null() || times.is_null() || errors.is_null()
    {
        return Vec::new();
    }
    let n = count as usize;
    // SAFETY: non-NULL arrays of `count` elements (the caller's promise), only read.
    let (handles, values, qualities, times, errors) = unsafe {
        (
            std::slice::from_raw_parts(handles, n),
            std::slice::from_raw_parts(values, n),
            std::slice::from_raw_parts(qualities, n),
            std::slice::from_raw_parts(times, n),
            std::slice::from_raw_parts(errors, n),
        )
    };
    (0..n)
        .map(|k| ItemValue {
            client: handles[k],
            value: value_of(&values[k]),
            quality: qualities[k],
            time: filetime(&times[k]),
            error: errors[k],
        })
        .collect()
}

impl IOPCDataCallback_Impl for DataSink_Impl {
    fn OnDataChange(
        &self,
        transaction: u32,
        group: u32,
        quality: HRESULT,
        error: HRESULT,
        count: u32,
        handles: *const u32,
        values: *const VARIANT,
        qualities: *const u16,
        times: *const FILETIME,
        errors: *const HRESULT,
    ) -> windows_core::Result<()> {
        // SAFETY: the stub's [in, size_is(dwCount)] arrays, live for the call.
        let items = unsafe { items_of(count, handles, values, qualities, times, errors) };
        self.log.push(Delivered {
            kind: Kind::DataChange,
            transaction,
            group,
            quality,
            error,
            items,
        });
        Ok(())
    }

    fn OnReadComplete(
        &self,
        transaction: u32,
        group: u32,
        quality: HRESULT,
        error: HRESULT,
        count: u32,
        handles: *const u32,
        values: *const VARIANT,
        qualities: *const u16,
        times: *const FILETIME,
        errors: *const HRESULT,
    ) -> windows_core::Result<()> {
        // SAFETY: as in OnDataChange.
        let items = unsafe { items_of(count, handles, values, qualities, times, errors) };
        self.log.push(Delivered {
            kind: Kind::ReadComplete,
            transaction,
            group,
            quality,
            error,
            items,
        });
        Ok(())
    }

    fn OnWriteComplete(
        &self,
        transaction: u32,
        group: u32,
        error: HRESULT,
        _count: u32,
        _handles: *const u32,
        _errors: *const HRESULT,
    ) -> windows_core::Result<()> {
        self.log.push(Delivered {
            kind: Kind::WriteComplete,
            transaction,
            group,
            quality: S_OK,
            error,
            items: Vec::new(),
        });
        Ok(())
    }

    fn OnCancelComplete(&self, transaction: u32, group: u32) -> windows_core::Result<()> {
        self.log.push(Delivered {
            kind: Kind::CancelComplete,
            transaction,
            group,
            quality: S_OK,
            error: S_OK,
            items: Vec::new(),
        });
        Ok(())
    }
}

/// Waits for callback number `index` (0-based) and checks it: its kind, transaction, group handle,
/// master codes, and items.
fn check_callback(t: &mut Tally, log: &CallbackLog, index: usize, kind: Kind, transaction: u32, want: &[ItemValue]) {
    let what = format!("{kind:?} (transaction {transaction})");
    let arrived = wait_until(CALLBACK_DEADLINE, || log.count() > index);
    let Some(call) = log.get(index).filter(|_| arrived) else {
        t.check(
            false,
            &format!("{what} arrived across processes ({} callbacks)", log.count()),
        );
        return;
    };
    t.check(
        call.kind == kind
            && call.transaction == transaction
            && call.group == GROUP_CLIENT_HANDLE
            && call.quality == S_OK
            && call.error == S_OK,
        &format!(
            "{what} arrived across processes, for the group's client handle, master quality and error \
             S_OK (got {:?}, transaction {}, group {}, {}, {})",
            call.kind,
            call.transaction,
            call.group,
            hex(call.quality),
            hex(call.error)
        ),
    );
    check_items(
        t,
        &call.items,
        want,
        &format!("{what}: every item's handle, value, quality and time"),
    );
}

// ---- Browsing -----------------------------------------------------------------------------------------

/// A property as it arrives: ID, type, description, item ID, value, error.
type Property = (u32, u16, Option<String>, Option<String>, Value, HRESULT);

/// The server's IOPCBrowse, for the crate's BrowseTrait.
struct Browser(IOPCBrowse);

impl BrowseTrait for Browser {
    fn interface(&self) -> windows::core::Result<&IOPCBrowse> {
        Ok(&self.0)
    }
}

fn browse(t: &mut Tally, browser: &Browser) {
    let none: Option<&str> = None;
    let all = browser.browse(
        Some(""),
        none,
        0,
        OPC_BROWSE_FILTER_ALL,
        Some(""),
        Some(""),
        false,
        false,
        &[],
    );
    if let Some((more, continuation, elements)) = t.ok(all, "IOPCBrowse::Browse(the root) (opc_da BrowseTrait)") {
        let got: Vec<(Option<String>, Option<String>, u32)> = elements
            .as_slice()
            .iter()
            .map(|e| (take_string(e.szName), take_string(e.szItemID), e.dwFlagValue))
            .collect();
        let want: Vec<(Option<String>, Option<String>, u32)> = ITEM_IDS
            .iter()
            .map(|id| (Some((*id).to_owned()), Some((*id).to_owned()), OPC_BROWSE_ISITEM))
            .collect();
        t.check(
            !more && continuation.is_none() && got == want,
            &format!("Browse: the four items, each an item (more {more}, continuation {continuation:?}, {got:?})"),
        );
    }
    // At most three a call: a continuation point, then the rest.
    let first = browser.browse(
        Some(""),
        none,
        3,
        OPC_BROWSE_FILTER_ALL,
        Some(""),
        Some(""),
        false,
        false,
        &[],
    );
    let mut next = None;
    if let Some((more, continuation, elements)) = t.ok(first, "Browse(the root, at most 3 elements)") {
        let names: Vec<Option<String>> = elements
            .as_slice()
            .iter()
            .map(|e| {
                take_string(e.szItemID);
                take_string(e.szName)
            })
            .collect();
        let want: Vec<Option<String>> = ITEM_IDS[..3].iter().map(|id| Some((*id).to_owned())).collect();
        t.check(
            more && continuation.is_some() && names == want,
            &format!("Browse: the first three items and a continuation point (more {more}, {continuation:?})"),
        );
        next = continuation;
    }
    if let Some(point) = next {
        let rest = browser.browse(
            Some(""),
            Some(point),
            3,
            OPC_BROWSE_FILTER_ALL,
            Some(""),
            Some(""),
            false,
            false,
            &[],
        );
        if let Some((more, continuation, elements)) = t.ok(rest, "Browse(the continuation point)") {
            let names: Vec<Option<String>> = elements
                .as_slice()
                .iter()
                .map(|e| {
                    take_string(e.szItemID);
                    take_string(e.szName)
                })
                .collect();
            t.check(
                !more && continuation.is_none() && names == [Some(ITEM_IDS[3].to_owned())],
                &format!("Browse: the fourth item, and no more ({names:?}, more {more}, {continuation:?})"),
            );
        }
    }
    let bogus = browser.browse(
        Some(""),
        Some("bogus"),
        0,
        OPC_BROWSE_FILTER_ALL,
        Some(""),
        Some(""),
        false,
        false,
        &[],
    );
    t.check_code(
        &bogus,
        OPC_E_INVALIDCONTINUATIONPOINT,
        "Browse(a continuation point the server never gave)",
    );

    // IOPCBrowse::GetProperties of every item and an unknown one, with values.
    let mut ids: Vec<String> = ITEM_IDS.iter().map(|id| (*id).to_owned()).collect();
    ids.push(UNKNOWN_ITEM.to_owned());
    let Some(mut all) = t.ok(
        browser.get_properties(&ids, true, &[]),
        "IOPCBrowse::GetProperties (with values)",
    ) else {
        return;
    };
    let mut good = 0;
    for (i, item) in all.as_mut_slice().iter_mut().enumerate() {
        let properties: &mut [tagOPCITEMPROPERTY] = if item.pItemProperties.is_null() {
            &mut []
        } else {
            // SAFETY: the array of dwNumProperties properties the proxy unnot_opccomn for this process.
            unsafe { std::slice::from_raw_parts_mut(item.pItemProperties, item.dwNumProperties as usize) }
        };
        let got: Vec<Property> = properties
            .iter_mut()
            .map(|p| {
                let value = std::mem::take(&mut p.vValue);
                (
                    p.dwPropertyID,
                    p.vtDataType,
                    take_string(p.szDescription),
                    take_string(p.szItemID),
                    value_of(&value),
                    p.hrErrorID,
                )
            })
            .collect();
        if !item.pItemProperties.is_null() {
            // SAFETY: the properties array, its strings and values already taken; freed once.
            unsafe { CoTaskMemFree(Some(item.pItemProperties as *const _)) };
            item.pItemProperties = std::ptr::null_mut();
        }
        let want: Vec<Property> = if i < ITEM_IDS.len() {
            vec![
                (
                    1,
                    VT_I2.0,
                    Some("Item Canonical Data Type".to_owned()),
                    None,
                    Value::I2(ITEM_TYPES[i] as i16),
                    S_OK,
                ),
                (
                    101,
                    VT_BSTR.0,
                    Some("Item Description".to_owned()),
                    Some(format!("{}.Description", ITEM_IDS[i])),
                    Value::Text(format!("Description of {}", ITEM_IDS[i])),
                    S_OK,
                ),
            ]
        } else {
            Vec::new()
        };
        let want_error = if i < ITEM_IDS.len() { S_OK } else { OPC_E_UNKNOWNITEMID };
        if item.hrErrorID == want_error && got == want {
            good += 1;
        } else {
            println!("       GetProperties({}): {} {got:?}", ids[i], hex(item.hrErrorID));
        }
    }
    t.check(
        good == ids.len(),
        &format!(
            "GetProperties: each item's canonical type and description, with item IDs and values, and \
             OPC_E_UNKNOWNITEMID for the unknown item ({good} of {} right)",
            ids.len()
        ),
    );
}

/// Every string an IEnumString gives, asking for `ask` at a time, and the last call's code.
fn strings_of(names: &IEnumString, ask: usize) -> (Vec<Option<String>>, HRESULT) {
    let mut got = Vec::new();
    loop {
        let mut batch = vec![PWSTR::null(); ask];
        let mut fetched = 0;
        // SAFETY: `batch` holds `ask` slots; the strings returned are task memory of this process.
        let hr = unsafe { names.Next(&mut batch, Some(&mut fetched)) };
        let fetched = (fetched as usize).min(ask);
        got.extend(batch[..fetched].iter().map(|p| take_string(*p)));
        if hr != S_OK || fetched == 0 || got.len() > 64 {
            return (got, hr);
        }
    }
}

/// IOPCBrowseServerAddressSpace through the crate's BrowseServerAddressSpaceTrait.
fn browse_address_space(t: &mut Tally, server: &v2::Server) {
    let organization = t.ok(
        server.query_organization(),
        "IOPCBrowseServerAddressSpace::QueryOrganization (opc_da BrowseServerAddressSpaceTrait)",
    );
    t.check(
        organization == Some(OPC_NS_FLAT),
        &format!("QueryOrganization: a flat address space ({organization:?})"),
    );
    t.check_code(
        &server.change_browse_position(OPC_BROWSE_DOWN, "Plant"),
        E_FAIL,
        "ChangeBrowsePosition(down) in a flat address space",
    );
    let all: Vec<Option<String>> = ITEM_IDS.iter().map(|id| Some((*id).to_owned())).collect();
    let cases: [(&str, tagOPCBROWSETYPE, u16, Vec<Option<String>>); 3] = [
        ("OPC_FLAT, every type", OPC_FLAT, 0, all),
        (
            "OPC_FLAT, VT_R8 only",
            OPC_FLAT,
            VT_R8.0,
            vec![Some(ITEM_IDS[1].to_owned())],
        ),
        ("OPC_BRANCH", OPC_BRANCH, 0, Vec::new()),
    ];
    for (what, kind, vt, want) in cases {
        // The filter is a [string] (reference) pointer: "" for none (the crate's None would send
        // NULL, which every proxy refuses with RPC_X_NULL_REF_POINTER).
        let Some(names) = t.ok(
            server.browse_opc_item_ids(kind, Some(""), vt, 0),
            &format!("BrowseOPCItemIDs({what})"),
        ) else {
            continue;
        };
        // Three at a time: the last call gives fewer and S_FALSE.
        let (got, last) = strings_of(&names, 3);
        t.check(
            got == want && last == S_FALSE,
            &format!(
                "BrowseOPCItemIDs({what}): the server's item IDs, then S_FALSE ({got:?}, {})",
                hex(last)
            ),
        );
    }
}

/// IOPCItemProperties through the crate's ItemPropertiesTrait.
fn item_properties(t: &mut Tally, server: &v2::Server) {
    let id = ITEM_IDS[1];
    if let Some((ids, descriptions, types)) = t.ok(
        server.query_available_properties(id),
        "IOPCItemProperties::QueryAvailableProperties (opc_da ItemPropertiesTrait)",
    ) {
        let descriptions: Vec<Option<String>> = descriptions.as_slice().iter().map(|d| take_string(*d)).collect();
        t.check(
            ids.as_slice() == [1, 101]
                && types.as_slice() == [VT_I2.0, VT_BSTR.0]
                && descriptions
                    == [
                        Some("Item Canonical Data Type".to_owned()),
                        Some("Item Description".to_owned()),
                    ],
            &format!(
                "QueryAvailableProperties: properties 1 and 101 ({:?}, {:?}, {descriptions:?})",
                ids.as_slice(),
                types.as_slice()
            ),
        );
    }
    if let Some((mut values, errors)) = t.ok(
        server.get_item_properties(id, &[1, 101, 5555]),
        "GetItemProperties(1, 101, and an unknown property)",
    ) {
        let got: Vec<Value> = values
            .as_mut_slice()
            .iter_mut()
            .map(|v| value_of(&std::mem::take(v)))
            .collect();
        t.check(
            got.len() == 3
                && got[..2]
                    == [
                        Value::I2(ITEM_TYPES[1] as i16),
                        Value::Text(format!("Description of {id}")),
                    ]
                && errors.as_slice() == [S_OK, S_OK, OPC_E_INVALID_PID],
            &format!(
                "GetItemProperties: the canonical type and description, OPC_E_INVALID_PID for 5555 ({got:?}, {:?})",
                errors.as_slice()
            ),
        );
    }
    if let Some((item_ids, errors)) = t.ok(server.lookup_item_ids(id, &[101]), "LookupItemIDs(101)") {
        let got: Vec<Option<String>> = item_ids.as_slice().iter().map(|p| take_string(*p)).collect();
        t.check(
            got == [Some(format!("{id}.Description"))] && errors.as_slice() == [S_OK],
            &format!("LookupItemIDs: the description's item ID ({got:?})"),
        );
    }
}

// ---- The group ----------------------------------------------------------------------------------------

/// Adds the items (and an unknown one); returns the server handles of the four.
fn add_items(t: &mut Tally, group: &v2::Group) -> Vec<u32> {
    let empty: Vec<u16> = vec![0];
    let ids: Vec<Vec<u16>> = ITEM_IDS
        .iter()
        .chain([UNKNOWN_ITEM].iter())
        .map(|id| id.encode_utf16().chain([0]).collect())
        .collect();
    let defs: Vec<tagOPCITEMDEF> = ids
        .iter()
        .enumerate()
        .map(|(i, id)| tagOPCITEMDEF {
            szAccessPath: PWSTR(empty.as_ptr().cast_mut()),
            szItemID: PWSTR(id.as_ptr().cast_mut()),
            bActive: true.into(),
            hClient: client_handle(i),
            dwBlobSize: 0,
            pBlob: std::ptr::null_mut(),
            vtRequestedDataType: 0,
            wReserved: 0,
        })
        .collect();
    let Some((results, errors)) = t.ok(
        group.add_items(&defs),
        "IOPCItemMgt::AddItems(the four items and an unknown one) (opc_da ItemMgtTrait)",
    ) else {
        return Vec::new();
    };
    let (results, errors) = (results.as_slice(), errors.as_slice());
    let mut handles = Vec::new();
    for (i, (id, canonical)) in ITEM_IDS.iter().zip(ITEM_TYPES).enumerate() {
        let ok = errors.get(i) == Some(&S_OK)
            && results.get(i).is_some_and(|r| {
                r.hServer == server_handle(i)
                    && r.vtCanonicalDataType == canonical
                    && r.dwAccessRights == OPC_READABLE | OPC_WRITEABLE
                    && r.dwBlobSize == 0
            });
        t.check(
            ok,
            &format!(
                "AddItems: {:?} added, its server handle, canonical type {:#06X}, readable and writeable",
                id, canonical
            ),
        );
        handles.push(results.get(i).map_or(0, |r| r.hServer));
    }
    t.check(
        errors.get(4) == Some(&OPC_E_UNKNOWNITEMID),
        &format!(
            "AddItems: the unknown item is OPC_E_UNKNOWNITEMID ({})",
            errors.get(4).map_or_else(|| "none".to_owned(), |e| hex(*e))
        ),
    );
    handles
}

/// A sync read of `handles` from `source`.
fn sync_read(
    t: &mut Tally,
    group: &v2::Group,
    source: opc_da_bindings::tagOPCDATASOURCE,
    handles: &[u32],
    what: &str,
) -> Vec<ItemValue> {
    match t.ok(SyncIoTrait::read(group, source, handles), what) {
        Some((mut states, errors)) => take_states(&mut states, &errors),
        None => Vec::new(),
    }
}

fn group_calls(t: &mut Tally, group: &v2::Group, target: &Target) {
    if let Some(state) = t.ok(
        group.get_state(),
        "IOPCGroupStateMgt::GetState (opc_da GroupStateMgtTrait)",
    ) {
        t.check(
            state.name == GROUP_NAME
                && state.update_rate == 1000
                && state.active
                && state.time_bias == -60
                && state.percent_deadband == 0.0
                && state.locale_id == 0x0407
                && state.client_handle == GROUP_CLIENT_HANDLE
                && state.server_handle == GROUP_SERVER_HANDLE,
            &format!("GetState: the group as added ({state:?})"),
        );
    }
    let handles = add_items(t, group);
    if handles.len() != ITEM_IDS.len() {
        return;
    }
    let all = [0, 1, 2, 3];
    let initial = initial_values();

    // Sync reads: from the device (its time, 10 s later) with an invalid handle among them, and
    // from the cache.
    let mut asked = handles.clone();
    asked.insert(2, BAD_HANDLE);
    let mut got = sync_read(
        t,
        group,
        OPC_DS_DEVICE,
        &asked,
        "IOPCSyncIO::Read(OPC_DS_DEVICE) (opc_da SyncIoTrait)",
    );
    let bad = (got.len() == 5).then(|| got.remove(2));
    check_items(
        t,
        &got,
        &expected(&all, &initial, 10),
        "Read(device): every value is the one the server serves (VT_I4, VT_R8, VT_BSTR, VT_ARRAY | VT_R8)",
    );
    t.check(
        bad.as_ref().is_some_and(|b| b.error == OPC_E_INVALIDHANDLE),
        &format!(
            "Read(device): the invalid handle among them is OPC_E_INVALIDHANDLE ({:?})",
            bad.map(|b| hex(b.error))
        ),
    );
    let got = sync_read(t, group, OPC_DS_CACHE, &handles, "Read(OPC_DS_CACHE)");
    check_items(
        t,
        &got,
        &expected(&all, &initial, 0),
        "Read(cache): every value, with the cache's time",
    );

    // Before a callback is advised, asynchronous calls have nowhere to report.
    t.check_code(
        &group.refresh2(OPC_DS_CACHE, 1),
        CONNECT_E_NOCONNECTION,
        "IOPCAsyncIO2::Refresh2 with no callback advised",
    );
    if target.made_with_crate {
        // Not called: when a method fails, opc_da's server frees the arrays it allocated for the
        // out-parameters but leaves their pointers in place (its safe_call!), so the stub would
        // marshal and free freed memory (any stub: NDR marshals [out] parameters whatever the
        // HRESULT).
        println!(
            "       note: IOPCAsyncIO2::Read with no callback advised not called: opc_da's server would fail it with dangling out-arrays"
        );
    } else {
        t.check_code(
            &AsyncIo2Trait::read(group, &handles, 1),
            CONNECT_E_NOCONNECTION,
            "IOPCAsyncIO2::Read with no callback advised",
        );
    }

    // The callback on the group's connection point.
    let Some(point) = t.ok(
        group.data_callback_connection_point(),
        "FindConnectionPoint(IOPCDataCallback) on the group (opc_da ConnectionPointContainerTrait)",
    ) else {
        return;
    };
    let log = Arc::new(CallbackLog::default());
    let sink: IOPCDataCallback = DataSink { log: Arc::clone(&log) }.into();
    // SAFETY: both interfaces are live for the call.
    let cookie = t.ok(
        unsafe { point.Advise(&sink) },
        "Advise(an #[implement] IOPCDataCallback sink)",
    );
    if let Some(cookie) = cookie {
        if target.made_with_crate {
            // The crate's ConnectionPoint numbers its cookies from 0 (a server's choice: COM's
            // marshalling does not care).
            println!("       note: Advise gave cookie {cookie} (opc_da's ConnectionPoint counts from 0)");
        } else {
            t.check(cookie != 0, &format!("Advise: a non-zero cookie ({cookie})"));
        }

        // Refresh2: an OnDataChange of every item, from a thread of the server.
        let refreshed = t.ok(
            group.refresh2(OPC_DS_CACHE, 77),
            "Refresh2(OPC_DS_CACHE, transaction 77)",
        );
        t.check(
            refreshed.is_some_and(|c| c != 0),
            &format!("Refresh2: a cancel ID ({refreshed:?})"),
        );
        check_callback(t, &log, 0, Kind::DataChange, 77, &expected(&all, &initial, 20));

        // IOPCAsyncIO2::Read of three handles, one invalid: OnReadComplete of the other two, in order.
        let read = AsyncIo2Trait::read(group, &[handles[3], BAD_HANDLE, handles[0]], 88);
        if let Some((cancel, errors)) = t.ok(read, "IOPCAsyncIO2::Read(3 handles, one invalid, transaction 88)") {
            t.check(
                cancel != 0 && errors.as_slice() == [S_OK, OPC_E_INVALIDHANDLE, S_OK],
                &format!(
                    "IOPCAsyncIO2::Read: a cancel ID, OPC_E_INVALIDHANDLE for the invalid handle only ({cancel}, {:?})",
                    errors.as_slice()
                ),
            );
        }
        check_callback(t, &log, 1, Kind::ReadComplete, 88, &expected(&[3, 0], &initial, 10));

        // Write, then read back; a value of the wrong type and an invalid handle fail per item.
        let written = written_values();
        let mut write_handles = handles.clone();
        let mut values: Vec<VARIANT> = written.iter().map(variant_of).collect();
        write_handles.push(handles[0]);
        values.push(VARIANT::from(1.5f64));
        write_handles.push(BAD_HANDLE);
        values.push(VARIANT::from(1i32));
        if let Some(errors) = t.ok(
            SyncIoTrait::write(group, &write_handles, &values),
            "IOPCSyncIO::Write(the four items, a VT_R8 to the VT_I4 item, an invalid handle)",
        ) {
            t.check(
                errors.as_slice() == [S_OK, S_OK, S_OK, S_OK, OPC_E_BADTYPE, OPC_E_INVALIDHANDLE],
                &format!(
                    "Write: the four written, OPC_E_BADTYPE for the wrong type, OPC_E_INVALIDHANDLE ({:?})",
                    errors.as_slice()
                ),
            );
        }
        drop(values);
        let got = sync_read(t, group, OPC_DS_CACHE, &handles, "Read(cache) after the write");
        check_items(
            t,
            &got,
            &expected(&all, &written, 0),
            "Read after Write: every value as written",
        );
        let refreshed = t.ok(
            group.refresh2(OPC_DS_DEVICE, 99),
            "Refresh2(OPC_DS_DEVICE, transaction 99)",
        );
        t.check(refreshed.is_some_and(|c| c != 0), "Refresh2: a cancel ID");
        check_callback(t, &log, 2, Kind::DataChange, 99, &expected(&all, &written, 20));

        // SAFETY: `point` is live.
        t.ok(unsafe { point.Unadvise(cookie) }, "Unadvise(the sink)");
        // SAFETY: as above.
        let again = unsafe { point.Unadvise(cookie) };
        if target.made_with_crate {
            // The crate's ConnectionPoint::Unadvise removes the cookie if it is there and succeeds
            // either way.
            t.check(
                again.is_ok(),
                &format!(
                    "Unadvise(the same cookie again): S_OK, as opc_da's ConnectionPoint answers any cookie ({})",
                    hex(again.as_ref().err().map_or(S_OK, |e| e.code()))
                ),
            );
        } else {
            t.check_code(&again, CONNECT_E_NOCONNECTION, "Unadvise(the same cookie again)");
        }
        t.check_code(
            &group.refresh2(OPC_DS_CACHE, 100),
            CONNECT_E_NOCONNECTION,
            "Refresh2 after Unadvise",
        );
        t.check(
            log.count() == 3,
            &format!("the sink was called three times, no more ({})", log.count()),
        );
    }
    drop(point);
    // SAFETY: the sink is a live object of this process: no stub may outlive it.
    unsafe {
        let _ = CoDisconnectObject(&sink, None);
    }

    // Remove the items: then their handles are unknown.
    if let Some(errors) = t.ok(group.remove_items(&handles), "IOPCItemMgt::RemoveItems(the four items)") {
        t.check(
            errors.as_slice() == [S_OK; 4],
            &format!("RemoveItems: each removed ({:?})", errors.as_slice()),
        );
    }
    if let Some(errors) = t.ok(group.remove_items(&handles[..1]), "RemoveItems(a removed item)") {
        t.check(
            errors.as_slice() == [OPC_E_INVALIDHANDLE],
            &format!(
                "RemoveItems: a removed item is OPC_E_INVALIDHANDLE ({:?})",
                errors.as_slice()
            ),
        );
    }
}

// ---- The server ---------------------------------------------------------------------------------------

/// IOPCCommon of the opc_da server (the crate's IOPCCommon on the server's locales en-US and de-DE
/// and its error texts) through the crate's CommonTrait.
fn crate_common(t: &mut Tally, server: &v2::Server) {
    let locale = t.ok(server.get_locale_id(), "IOPCCommon::GetLocaleID (opc_da CommonTrait)");
    t.check(
        locale == Some(0x0800),
        &format!("GetLocaleID: LOCALE_SYSTEM_DEFAULT at first ({locale:?})"),
    );
    t.ok(server.set_locale_id(0x0407), "SetLocaleID(de-DE)");
    t.check_code(&server.set_locale_id(0x0411), E_INVALIDARG, "SetLocaleID(ja-JP)");
    let locale = t.ok(server.get_locale_id(), "GetLocaleID after SetLocaleID");
    t.check(
        locale == Some(0x0407),
        &format!("GetLocaleID: de-DE, the locale set ({locale:?})"),
    );
    if let Some(locales) = t.ok(server.query_available_locale_ids(), "QueryAvailableLocaleIDs") {
        t.check(
            locales.as_slice() == [0x0409, 0x0407],
            &format!("QueryAvailableLocaleIDs: en-US and de-DE ({:?})", locales.as_slice()),
        );
    }
    let text = t.ok(
        server.get_error_string(OPC_E_UNKNOWNITEMID),
        "IOPCCommon::GetErrorString(OPC_E_UNKNOWNITEMID)",
    );
    t.check(
        text.as_deref() == Some("The item ID is not defined in the server address space."),
        &format!("GetErrorString: the server's text ({text:?})"),
    );
    // Not asked for a code without a text: the crate's IOPCCommon::GetErrorString makes every
    // failure E_FAIL with windows-core's Error::new, which calls RoOriginateErrorW, a stub in Wine 8
    // (the server faults there and the client gets 0xC0000005).
}

fn status(t: &mut Tally, server: &v2::Server, groups: u32, target: &Target) {
    if target.made_with_crate {
        // Not called: opc_da 0.3.1's IOPCServer::GetStatus converts the status with its
        // PointerWriter::try_write_to, which writes the vendor string through a NULL pointer (an
        // access violation in the server, which COM reports to the client as 0x800703E6) and would
        // then refuse the structure itself with E_POINTER: no status reaches a client.
        println!("       note: IOPCServer::GetStatus not called ({groups} group(s)): opc_da's server cannot answer it");
        return;
    }
    let Some(status) = t.ok(server.get_status(), "IOPCServer::GetStatus (opc_da ServerTrait)") else {
        return;
    };
    let Some(s) = status.as_ref() else {
        t.check(false, "GetStatus: a status");
        return;
    };
    // The crate frees the structure only: the vendor string is freed here.
    let vendor = take_string(s.szVendorInfo);
    t.check(
        s.dwServerState == OPC_STATUS_RUNNING
            && filetime(&s.ftStartTime) == da_time(0, 0)
            && filetime(&s.ftCurrentTime) == da_time(1, 0)
            && filetime(&s.ftLastUpdateTime) == da_time(2, 0)
            && s.dwGroupCount == groups
            && s.dwBandWidth == 0xFFFF_FFFF
            && (s.wMajorVersion, s.wMinorVersion, s.wBuildNumber) == (3, 0, 42)
            && vendor.as_deref() == Some(VENDOR_INFO),
        &format!(
            "GetStatus: running, its times, {groups} group(s), version 3.0.42, vendor {vendor:?} (state {}, {} groups)",
            s.dwServerState.0, s.dwGroupCount
        ),
    );
}

pub(crate) fn da_server(t: &mut Tally, target: &Target) {
    println!(
        "-- Data Access server: {}, {} ({})",
        target.name,
        target.exe,
        braced(&target.clsid)
    );
    let class_key = format!("CLSID\\{}", braced(&target.clsid));
    let local_server = default_value(&format!("{class_key}\\LocalServer32"), target.view).unwrap_or_default();
    t.check(
        local_server.to_ascii_lowercase().contains(target.exe),
        &format!("{} is a LocalServer32 ({local_server:?})", target.name),
    );
    // Only opccomn.dll marshals the DA interfaces: registered for this process's view, and what its
    // COM uses.
    let interfaces = [
        ("IOPCServer", IOPCServer::IID),
        ("IOPCItemProperties", IOPCItemProperties::IID),
        ("IOPCBrowse", IOPCBrowse::IID),
        ("IOPCBrowseServerAddressSpace", IOPCBrowseServerAddressSpace::IID),
        ("IOPCItemMgt", IOPCItemMgt::IID),
        ("IOPCGroupStateMgt", IOPCGroupStateMgt::IID),
        ("IOPCSyncIO", IOPCSyncIO::IID),
        ("IOPCAsyncIO2", IOPCAsyncIO2::IID),
        ("IOPCDataCallback", IOPCDataCallback::IID),
    ];
    let opccomn = braced(&CLSID_OPCCOMN_PROXY_STUB);
    let mut not_opccomn = Vec::new();
    for (name, iid) in interfaces {
        let registered = default_value(&format!("Interface\\{}\\ProxyStubClsid32", braced(&iid)), View::Own)
            .is_some_and(|clsid| clsid.eq_ignore_ascii_case(&opccomn));
        // SAFETY: a plain query with a valid IID.
        let used = unsafe { CoGetPSClsid(&iid) }.is_ok_and(|clsid| clsid == CLSID_OPCCOMN_PROXY_STUB);
        if !(registered && used) {
            not_opccomn.push(name);
        }
    }
    t.check(
        not_opccomn.is_empty(),
        &format!("the DA interfaces' proxy/stub is opccomn.dll's, registered and used by COM (not: {not_opccomn:?})"),
    );

    // The crate's own connection: CoCreateInstance(IOPCServer, CLSCTX_LOCAL_SERVER), then its v2
    // server's interfaces (IOPCCommon, IConnectionPointContainer, IOPCItemProperties) queried across.
    let created = v2::Client.create_server(target.clsid, ClassContext::LocalServer);
    let Some(server) = t.ok(
        created,
        &format!("opc_da v2::Client::create_server({}, LocalServer)", target.exe),
    ) else {
        return;
    };
    t.check(process_running(target.exe), &format!("COM started {}", target.exe));
    status(t, &server, 0, target);
    t.ok(
        server.set_client_name("opc_da third-party client (opccomn CI)"),
        "IOPCCommon::SetClientName on the DA server (opc_da CommonTrait)",
    );
    t.check_code(
        &server.data_callback_connection_point(),
        CONNECT_E_NOCONNECTION,
        "the server object has no IOPCDataCallback connection point (its groups do)",
    );
    if target.made_with_crate {
        crate_common(t, &server);
    }

    let mut revised = 0;
    let mut group_handle = 0;
    let added = server.add_group(
        GROUP_NAME,
        true,
        GROUP_CLIENT_HANDLE,
        1000,
        0x0407,
        -60,
        0.0,
        &mut revised,
        &mut group_handle,
    );
    if let Some(group) = t.ok(added, "IOPCServer::AddGroup (opc_da ServerTrait, a v2::Group)") {
        t.check(
            group_handle == GROUP_SERVER_HANDLE && revised == 1000,
            &format!("AddGroup: the server's handle and the rate asked for ({group_handle}, {revised} ms)"),
        );
        status(t, &server, 1, target);
        group_calls(t, &group, target);
        drop(group);
        t.ok(
            server.remove_group(GROUP_SERVER_HANDLE, false),
            "IOPCServer::RemoveGroup, once the group is released",
        );
        t.check_code(
            &server.remove_group(GROUP_SERVER_HANDLE, false),
            E_INVALIDARG,
            "RemoveGroup of the removed group",
        );
        status(t, &server, 0, target);
    }

    item_properties(t, &server);
    if target.made_with_crate {
        // The crate's IOPCBrowse::Browse and GetProperties write each element's and property's
        // strings through a NULL pointer (PointerWriter::try_write_to): an access violation in the
        // server for any element. Its DA 2.0 browse (IOPCBrowseServerAddressSpace) is used instead.
        browse_address_space(t, &server);
        drop(server);
        t.check(
            wait_until(EXIT_DEADLINE, || !process_running(target.exe)),
            &format!("{} exited once its client let go", target.exe),
        );
        return;
    }
    let browser = <v2::Server as ServerTrait<v2::Group>>::interface(&server).and_then(|s| s.cast::<IOPCBrowse>());
    if let Some(browser) = t.ok(browser, "QueryInterface(IOPCBrowse) across processes") {
        browse(t, &Browser(browser));
    }
    drop(server);
    t.check(
        wait_until(EXIT_DEADLINE, || !process_running(target.exe)),
        &format!("{} exited once its client let go", target.exe),
    );
}
