//! A public third-party OPC client, the crates.io crates `opc_da` 0.3.1 and `opc_comn_bindings`
//! 0.3.0, run against opccomn under Wine (scripts/test-third-party-client.sh, docs/dev/third-party-client.md).
//!
//! - Browsing: `opc_da`'s own `ClientTrait::get_servers` (the v2 client's, and the same code for the
//!   example's category) through CLSID_OPCServerList, served by the library's browser service
//!   (`opccomn_browser.exe`) alone: nothing in-process answers, the proxy/stub is registered with `/n`.
//! - The example EXE server (`examples/cpp-server`, LocalServer32) through opccomn.dll's proxy/stub:
//!   IOPCCommon through `opc_da`'s `CommonTrait`, the IOPCShutdown connection point through its
//!   `ConnectionPointContainerTrait`, and a shutdown sink made with windows-core's `#[implement]` that
//!   the server calls back when its operator stops it.
//! - A Data Access server in another process (`da.rs`): the C test server `opc_da_test_server.exe`
//!   through opccomn.dll's proxy/stub alone, with `opc_da`'s v2 client code: connect, status, a group
//!   and its items, sync and async reads (every value the one the server serves), write and read
//!   back, data-change callbacks to an `#[implement]` IOPCDataCallback, browsing and item
//!   properties, removal.
//!
//! The script registers the browser, the example server, the DA test server and the proxy/stub
//! before and removes them after. Prints `third-party-client: N passed, M failed`; exits non-zero when a check failed.
//!
//! What belongs to the crate is not asserted: its GUID iterator yields the 16 zero GUIDs of its cache
//! before the first `IEnumGUID::Next` and pads every batch to 16 with whatever the cache held, so only
//! the non-zero GUIDs it yields are judged (each a registered class of the category, the example's
//! among them), and its `create_server` wants IOPCServer, which the example does not have.

use std::process::ExitCode;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use opc_comn_bindings::{IOPCCommon, IOPCShutdown, IOPCShutdown_Impl};
use opc_da::client::{ClientTrait, CommonTrait, ConnectionPointContainerTrait, v2};
use windows::Win32::Foundation::{CloseHandle, E_INVALIDARG, E_NOINTERFACE, ERROR_SUCCESS};
use windows::Win32::System::Com::{
    CLSCTX_LOCAL_SERVER, CLSIDFromProgID, COINIT_MULTITHREADED, CoCreateInstance, CoDisconnectObject, CoInitializeEx,
    CoUninitialize, IConnectionPoint, IConnectionPointContainer,
};
use windows::Win32::System::Diagnostics::ToolHelp::{
    CreateToolhelp32Snapshot, PROCESSENTRY32W, Process32FirstW, Process32NextW, TH32CS_SNAPPROCESS,
};
use windows::Win32::System::Registry::{
    HKEY, HKEY_LOCAL_MACHINE, KEY_READ, KEY_WOW64_32KEY, KEY_WOW64_64KEY, RRF_NOEXPAND, RRF_RT_REG_EXPAND_SZ,
    RRF_RT_REG_SZ, RegCloseKey, RegGetValueW, RegOpenKeyExW,
};
use windows::Win32::System::Threading::{EVENT_MODIFY_STATE, OpenEventW, SetEvent};
use windows::core::{GUID, HRESULT, HSTRING, IUnknown, Interface, PCWSTR};
use windows_core::implement;

mod da;

/// CLSID_OPCServerList (the browser's class; OpcEnum's CLSID).
const CLSID_OPC_SERVER_LIST: GUID = GUID::from_u128(0x13486d51_4821_11d2_a494_3cb306c10000);
/// The example EXE server's class (examples/cpp-server/example_guids.cpp) and its category.
const CLSID_EXAMPLE_SERVER: GUID = GUID::from_u128(0xbf0ae666_d841_4412_b587_a70f6a67ba2e);
const CATID_EXAMPLE_SERVERS: GUID = GUID::from_u128(0x21c3fe99_2c81_4f6f_b062_36e7b5a89e2d);
/// The example's own interface: it has no proxy/stub, so it cannot cross processes.
const IID_EXAMPLE_ADDRESS_SPACE: GUID = GUID::from_u128(0x9834816c_39e4_4bb0_81f9_e2b53c38be33);
/// The example server's stop command (EXAMPLE_STOP_EVENT): its operator's tools set it.
const EXAMPLE_STOP_EVENT: &str = "Local\\OpcComnExampleServerStop";
const EXAMPLE_SHUTDOWN_REASON: &str = "The operator stopped the server.";

/// The locales the example server declares, one it does not, and the session's default.
const LOCALE_ENGLISH_US: u32 = 0x0409;
const LOCALE_GERMAN: u32 = 0x0407;
const LOCALE_JAPANESE: u32 = 0x0411;
const LOCALE_SYSTEM_DEFAULT: u32 = 0x0800;

/// An OPC Data Access code (the library's catalog text) and the example's own (its vendor text).
const OPC_E_UNKNOWNITEMID: HRESULT = HRESULT(0xC004_0007_u32 as i32);
const EXAMPLE_E_DEVICEOFFLINE: HRESULT = HRESULT(0xC004_8001_u32 as i32);
const CONNECT_E_NOCONNECTION: HRESULT = HRESULT(0x8004_0200_u32 as i32);
const CONNECT_E_ADVISELIMIT: HRESULT = HRESULT(0x8004_0201_u32 as i32);

/// How long the operator's stop may take to reach the sink, and the EXE server to exit after it.
const CALLBACK_DEADLINE: Duration = Duration::from_secs(30);
const EXIT_DEADLINE: Duration = Duration::from_secs(30);

#[derive(Default)]
struct Tally {
    passed: u32,
    failed: u32,
}

impl Tally {
    fn check(&mut self, ok: bool, what: &str) {
        if ok {
            self.passed += 1;
            println!("ok     {what}");
        } else {
            self.failed += 1;
            println!("FAILED {what}");
        }
    }

    /// Checks that `result` failed with `want` (Ok counts as a failure, and so does another code).
    fn check_code<T>(&mut self, result: &windows::core::Result<T>, want: HRESULT, what: &str) {
        let got = match result {
            Ok(_) => HRESULT(0),
            Err(e) => e.code(),
        };
        self.check(got == want, &format!("{what}: {} (expected {})", hex(got), hex(want)));
    }

    /// Checks that `result` is Ok and returns its value.
    fn ok<T>(&mut self, result: windows::core::Result<T>, what: &str) -> Option<T> {
        match result {
            Ok(value) => {
                self.check(true, what);
                Some(value)
            }
            Err(e) => {
                self.check(false, &format!("{what}: {} {}", hex(e.code()), e.message()));
                None
            }
        }
    }
}

fn hex(hr: HRESULT) -> String {
    format!("0x{:08X}", hr.0 as u32)
}

/// `{XXXXXXXX-XXXX-XXXX-XXXX-XXXXXXXXXXXX}`, as the registry names classes.
fn braced(g: &GUID) -> String {
    let d = g.data4;
    format!(
        "{{{:08X}-{:04X}-{:04X}-{:02X}{:02X}-{:02X}{:02X}{:02X}{:02X}{:02X}{:02X}}}",
        g.data1, g.data2, g.data3, d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7]
    )
}

/// A registry view: a 32-bit client reads the 32-bit view of the classes unless told otherwise, and the
/// x64 browser, example server and proxy/stub register in the 64-bit one.
#[derive(Clone, Copy)]
enum View {
    /// This process's own view (what its COM uses).
    Own,
    Bits64,
    Bits32,
}

/// Opens HKEY_LOCAL_MACHINE\Software\Classes\`key` (what HKEY_CLASSES_ROOT shows) in `view`.
fn open_class_key(key: &str, view: View) -> Option<HKEY> {
    let access = match view {
        View::Own => KEY_READ,
        View::Bits64 => KEY_READ | KEY_WOW64_64KEY,
        View::Bits32 => KEY_READ | KEY_WOW64_32KEY,
    };
    let mut hkey = HKEY::default();
    let path = HSTRING::from(format!("Software\\Classes\\{key}"));
    // SAFETY: `path` lives for the call (HSTRING is NUL-terminated), `hkey` is a valid out-parameter.
    let opened = unsafe { RegOpenKeyExW(HKEY_LOCAL_MACHINE, &path, None, access, &mut hkey) };
    (opened == ERROR_SUCCESS).then_some(hkey)
}

/// Whether the class key `key` exists in `view`.
fn key_exists(key: &str, view: View) -> bool {
    let Some(hkey) = open_class_key(key, view) else {
        return false;
    };
    // SAFETY: `hkey` was opened by open_class_key and is closed once.
    unsafe {
        let _ = RegCloseKey(hkey);
    }
    true
}

/// The default value of the class key `key` in `view`, when it is a string.
fn default_value(key: &str, view: View) -> Option<String> {
    let hkey = open_class_key(key, view)?;
    let mut buffer = [0u16; 1024];
    let mut bytes = (buffer.len() * 2) as u32;
    // SAFETY: `hkey` is open; `buffer` holds `bytes` bytes and outlives the call.
    let read = unsafe {
        RegGetValueW(
            hkey,
            PCWSTR::null(),
            PCWSTR::null(),
            RRF_RT_REG_SZ | RRF_RT_REG_EXPAND_SZ | RRF_NOEXPAND,
            None,
            Some(buffer.as_mut_ptr().cast()),
            Some(&mut bytes),
        )
    };
    // SAFETY: `hkey` was opened by open_class_key and is closed once.
    unsafe {
        let _ = RegCloseKey(hkey);
    }
    if read != ERROR_SUCCESS {
        return None;
    }
    let len = buffer.iter().position(|&c| c == 0).unwrap_or(buffer.len());
    Some(String::from_utf16_lossy(&buffer[..len]))
}

/// Whether a process runs the program `exe_name` (compared case-insensitively).
fn process_running(exe_name: &str) -> bool {
    // SAFETY: a snapshot of the processes; closed below.
    let Ok(snapshot) = (unsafe { CreateToolhelp32Snapshot(TH32CS_SNAPPROCESS, 0) }) else {
        return false;
    };
    let mut entry = PROCESSENTRY32W {
        dwSize: size_of::<PROCESSENTRY32W>() as u32,
        ..Default::default()
    };
    let mut found = false;
    // SAFETY: `entry` is a valid PROCESSENTRY32W with dwSize set, for a snapshot that is still open.
    let mut more = unsafe { Process32FirstW(snapshot, &mut entry) }.is_ok();
    while more && !found {
        let len = entry
            .szExeFile
            .iter()
            .position(|&c| c == 0)
            .unwrap_or(entry.szExeFile.len());
        found = String::from_utf16_lossy(&entry.szExeFile[..len]).eq_ignore_ascii_case(exe_name);
        // SAFETY: as above.
        more = unsafe { Process32NextW(snapshot, &mut entry) }.is_ok();
    }
    // SAFETY: the snapshot handle is closed once.
    unsafe {
        let _ = CloseHandle(snapshot);
    }
    found
}

/// Waits (polling) until `done` holds or `deadline` has passed; returns whether it held.
fn wait_until(deadline: Duration, mut done: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    while !done() {
        if start.elapsed() > deadline {
            return false;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    true
}

// ---- Browsing through the browser service, with opc_da's client code ----------------------------------

/// `opc_da`'s ClientTrait with the example's category: `get_servers` is the crate's own code
/// (CLSIDFromProgID("OPC.ServerList.1"), CoCreateInstance(CLSCTX_ALL),
/// IOPCServerList::EnumClassesOfCategories, its GuidIterator), asked for CATID_ExampleServers.
struct ExampleCategoryClient;

impl ClientTrait<v2::Server> for ExampleCategoryClient {
    const CATALOG_ID: GUID = CATID_EXAMPLE_SERVERS;
}

/// Browses one category with the crate's `get_servers` and checks what the library controls: the call
/// and every step of the enumeration succeed, each non-zero GUID is a registered class of the
/// category. Returns the non-zero GUIDs.
fn browse_category<C: ClientTrait<v2::Server>>(t: &mut Tally, client: &C, name: &str) -> Vec<GUID> {
    let Some(mut iterator) = t.ok(client.get_servers(), &format!("opc_da get_servers ({name})")) else {
        return Vec::new();
    };
    let mut servers = Vec::new();
    let (mut zeros, mut errors) = (0, 0);
    for item in iterator.by_ref() {
        match item {
            Ok(guid) if guid == GUID::zeroed() => zeros += 1,
            Ok(guid) => servers.push(guid),
            Err(e) => {
                errors += 1;
                println!("       the enumeration failed: {} {}", hex(e.code()), e.message());
            }
        }
    }
    t.check(
        errors == 0,
        &format!("{name}: every IEnumGUID::Next through the browser succeeded"),
    );
    // The crate released the server list inside get_servers and kept only the enumerator: the
    // browser service serves that for as long as it is held.
    t.check(
        process_running("opccomn_browser.exe"),
        &format!("{name}: the browser service (opccomn_browser.exe) answered and still serves the enumerator"),
    );
    drop(iterator);
    println!(
        "       {name}: {} classes, and {zeros} zero GUIDs from the crate's iterator (its own; not judged)",
        servers.len()
    );
    let category = braced(&C::CATALOG_ID);
    for guid in &servers {
        let key = format!("CLSID\\{}\\Implemented Categories\\{category}", braced(guid));
        t.check(
            key_exists(&key, View::Bits64) || key_exists(&key, View::Bits32),
            &format!("{name}: {} is a registered class of the category", braced(guid)),
        );
    }
    servers
}

fn browse(t: &mut Tally) {
    // Only the browser service can answer: CLSID_OPCServerList is a LocalServer32 naming
    // opccomn_browser.exe, with no InprocServer32 (the proxy/stub was registered with /n).
    let class_key = format!("CLSID\\{}", braced(&CLSID_OPC_SERVER_LIST));
    let local_server = default_value(&format!("{class_key}\\LocalServer32"), View::Bits64).unwrap_or_default();
    t.check(
        local_server.to_ascii_lowercase().contains("opccomn_browser.exe"),
        &format!("CLSID_OPCServerList is served by opccomn_browser.exe (LocalServer32: {local_server:?})"),
    );
    t.check(
        !key_exists(&format!("{class_key}\\InprocServer32"), View::Bits64)
            && !key_exists(&format!("{class_key}\\InprocServer32"), View::Bits32),
        "CLSID_OPCServerList has no InprocServer32",
    );
    // SAFETY: a NUL-terminated literal.
    let from_prog_id = unsafe { CLSIDFromProgID(windows::core::w!("OPC.ServerList.1")) };
    t.check(
        from_prog_id.as_ref().is_ok_and(|clsid| *clsid == CLSID_OPC_SERVER_LIST),
        "OPC.ServerList.1 (the ProgID opc_da looks up) names CLSID_OPCServerList",
    );

    // The example's category: the example EXE server is there.
    let servers = browse_category(t, &ExampleCategoryClient, "CATID_ExampleServers");
    t.check(
        servers.contains(&CLSID_EXAMPLE_SERVER),
        &format!("the example EXE server {} is among them", braced(&CLSID_EXAMPLE_SERVER)),
    );
    // The crate's own v2 client (CATID_OPCDAServer20): whatever is registered there is listed right.
    browse_category(t, &v2::Client, "CATID_OPCDAServer20 (opc_da's v2::Client)");
}

// ---- The example EXE server through the proxy/stub --------------------------------------------------

/// The example server seen through `opc_da`'s traits. The crate's own server types (v1/v2/v3::Server)
/// are made from an IOPCServer, which the example does not implement; this holds what it has.
struct ExampleServer {
    common: IOPCCommon,
    container: IConnectionPointContainer,
}

impl CommonTrait for ExampleServer {
    fn interface(&self) -> windows::core::Result<&IOPCCommon> {
        Ok(&self.common)
    }
}

impl ConnectionPointContainerTrait for ExampleServer {
    fn interface(&self) -> windows::core::Result<&IConnectionPointContainer> {
        Ok(&self.container)
    }
}

/// What a sink was told.
#[derive(Default)]
struct SinkRecord {
    calls: AtomicU32,
    reason: Mutex<String>,
}

/// A shutdown sink, as a Rust client writes one with the crate's bindings.
#[implement(IOPCShutdown)]
struct ShutdownSink {
    record: Arc<SinkRecord>,
}

impl IOPCShutdown_Impl for ShutdownSink_Impl {
    fn ShutdownRequest(&self, szreason: &PCWSTR) -> windows::core::Result<()> {
        let reason = if szreason.is_null() {
            "(null)".to_owned()
        } else {
            // SAFETY: a non-NULL [in, string] argument: a NUL-terminated string for the call.
            unsafe { szreason.to_string() }.unwrap_or_else(|_| "(not UTF-16)".to_owned())
        };
        if let Ok(mut slot) = self.record.reason.lock() {
            *slot = reason;
        }
        self.record.calls.fetch_add(1, Ordering::SeqCst);
        Ok(())
    }
}

fn common_calls(t: &mut Tally, server: &ExampleServer) {
    t.check(
        server.get_locale_id().ok() == Some(LOCALE_SYSTEM_DEFAULT),
        "GetLocaleID: a new session starts at LOCALE_SYSTEM_DEFAULT",
    );
    t.ok(
        server.set_locale_id(LOCALE_GERMAN),
        "SetLocaleID(de-DE), a declared locale",
    );
    t.check_code(
        &server.set_locale_id(LOCALE_JAPANESE),
        E_INVALIDARG,
        "SetLocaleID(ja-JP), a locale the server does not declare",
    );
    t.check(
        server.get_locale_id().ok() == Some(LOCALE_GERMAN),
        "GetLocaleID: de-DE, unchanged by the refusal",
    );
    if let Some(locales) = t.ok(server.query_available_locale_ids(), "QueryAvailableLocaleIDs") {
        let locales = locales.as_slice();
        t.check(
            locales.contains(&LOCALE_ENGLISH_US)
                && locales.contains(&LOCALE_GERMAN)
                && !locales.contains(&LOCALE_JAPANESE),
            &format!("QueryAvailableLocaleIDs: en-US and de-DE, not ja-JP ({locales:04X?})"),
        );
    }
    let texts = [
        (
            OPC_E_UNKNOWNITEMID,
            "Die Element-ID ist im Adressraum des Servers nicht definiert oder existiert dort nicht mehr.",
            "the library's German catalog text",
        ),
        (
            EXAMPLE_E_DEVICEOFFLINE,
            "Das Ger\u{e4}t antwortet nicht.",
            "the server's German vendor text",
        ),
    ];
    for (code, want, what) in texts {
        let got = server.get_error_string(code);
        t.check(
            got.as_deref().ok() == Some(want),
            &format!("GetErrorString({}): {what} ({got:?})", hex(code)),
        );
    }
    t.ok(server.set_locale_id(LOCALE_ENGLISH_US), "SetLocaleID(en-US)");
    let texts = [
        (
            OPC_E_UNKNOWNITEMID,
            "The item ID is not defined in the server address space or no longer exists in the server address space.",
            "the library's English catalog text",
        ),
        (
            EXAMPLE_E_DEVICEOFFLINE,
            "The device does not answer.",
            "the server's English vendor text",
        ),
    ];
    for (code, want, what) in texts {
        let got = server.get_error_string(code);
        t.check(
            got.as_deref().ok() == Some(want),
            &format!("GetErrorString({}): {what} ({got:?})", hex(code)),
        );
    }
    t.ok(
        server.set_client_name("opc_da third-party client (opccomn CI)"),
        "SetClientName",
    );
}

/// Advises `sink` on `point`; returns the cookie (0 when it failed).
fn advise(t: &mut Tally, point: &IConnectionPoint, sink: &IOPCShutdown, what: &str) -> u32 {
    // SAFETY: both interfaces are live for the call.
    let cookie = t.ok(unsafe { point.Advise(sink) }, what).unwrap_or(0);
    t.check(cookie != 0, &format!("{what}: a non-zero cookie ({cookie})"));
    cookie
}

fn shutdown_calls(t: &mut Tally, server: &ExampleServer) {
    // The example offers the IOPCShutdown connection point (OpcShutdownCreate) and no other.
    t.check_code(
        &server.data_callback_connection_point(),
        CONNECT_E_NOCONNECTION,
        "FindConnectionPoint(IOPCDataCallback), a point the server does not have",
    );
    let Some(point) = t.ok(
        server.find_connection_point(&IOPCShutdown::IID),
        "FindConnectionPoint(IOPCShutdown)",
    ) else {
        return;
    };
    // SAFETY: `point` is live.
    let iid = unsafe { point.GetConnectionInterface() };
    t.check(
        iid.as_ref().is_ok_and(|iid| *iid == IOPCShutdown::IID),
        "GetConnectionInterface: IID_IOPCShutdown",
    );

    let record = Arc::new(SinkRecord::default());
    let sink: IOPCShutdown = ShutdownSink {
        record: Arc::clone(&record),
    }
    .into();
    let other_record = Arc::new(SinkRecord::default());
    let other: IOPCShutdown = ShutdownSink {
        record: Arc::clone(&other_record),
    }
    .into();

    // One sink per server object (the library's default advise limit): a second Advise is refused
    // until the first sink is unadvised; cookies are not reused.
    let other_cookie = advise(t, &point, &other, "Advise(an #[implement] IOPCShutdown sink)");
    // SAFETY: both interfaces are live for the call.
    t.check_code(
        &unsafe { point.Advise(&sink) },
        CONNECT_E_ADVISELIMIT,
        "Advise(a second sink) while one is advised",
    );
    // SAFETY: `point` is live.
    t.ok(unsafe { point.Unadvise(other_cookie) }, "Unadvise(the first sink)");
    // SAFETY: as above.
    t.check_code(
        &unsafe { point.Unadvise(other_cookie) },
        CONNECT_E_NOCONNECTION,
        "Unadvise(the same cookie again)",
    );
    let cookie = advise(
        t,
        &point,
        &sink,
        "Advise(the second sink) after the first was unadvised",
    );
    t.check(
        cookie != other_cookie,
        &format!("the second connection has a new cookie ({other_cookie}, then {cookie})"),
    );

    // The operator stops the server (its named event): the server asks the advised sink, and only
    // it, to disconnect, calling back into this process through the proxy/stub.
    // SAFETY: a NUL-terminated name; the handle is closed below.
    let stop = unsafe { OpenEventW(EVENT_MODIFY_STATE, false, &HSTRING::from(EXAMPLE_STOP_EVENT)) };
    if let Some(stop) = t.ok(stop, "OpenEvent(the example server's stop event)") {
        // SAFETY: `stop` is an open event handle.
        t.ok(
            unsafe { SetEvent(stop) },
            "SetEvent(stop): the operator stops the server",
        );
        // SAFETY: as above; closed once and not used after this.
        unsafe {
            let _ = CloseHandle(stop);
        }
        wait_until(CALLBACK_DEADLINE, || record.calls.load(Ordering::SeqCst) > 0);
        let reason = record.reason.lock().map(|r| r.clone()).unwrap_or_default();
        t.check(
            record.calls.load(Ordering::SeqCst) == 1 && reason == EXAMPLE_SHUTDOWN_REASON,
            &format!(
                "ShutdownRequest arrived once, with the server's reason ({} calls, {reason:?})",
                record.calls.load(Ordering::SeqCst)
            ),
        );
        t.check(
            other_record.calls.load(Ordering::SeqCst) == 0,
            "the unadvised sink was not called",
        );
    }
    if cookie != 0 {
        // SAFETY: `point` is live.
        t.ok(
            unsafe { point.Unadvise(cookie) },
            "Unadvise(the second sink) after the shutdown request",
        );
    }
    drop(point);
    // No stub may outlive the sinks.
    // SAFETY: the sinks are live objects of this process.
    unsafe {
        let _ = CoDisconnectObject(&sink, None);
        let _ = CoDisconnectObject(&other, None);
    }
}

fn example_server(t: &mut Tally) {
    let class_key = format!("CLSID\\{}", braced(&CLSID_EXAMPLE_SERVER));
    t.check(
        key_exists(&format!("{class_key}\\LocalServer32"), View::Bits64),
        "the example server is a LocalServer32",
    );
    t.check(
        key_exists(
            &format!("Interface\\{}\\ProxyStubClsid32", braced(&IOPCCommon::IID)),
            View::Own,
        ),
        "IOPCCommon has a proxy/stub registered",
    );
    // SAFETY: plain activation; the result owns its reference.
    let created: windows::core::Result<IUnknown> =
        unsafe { CoCreateInstance(&CLSID_EXAMPLE_SERVER, None, CLSCTX_LOCAL_SERVER) };
    let Some(unknown) = t.ok(created, "CoCreateInstance(the example server, CLSCTX_LOCAL_SERVER)") else {
        return;
    };
    t.check(
        process_running("opccomn_example_server.exe"),
        "COM started opccomn_example_server.exe",
    );
    let common = t.ok(
        unknown.cast::<IOPCCommon>(),
        "QueryInterface(IOPCCommon) across processes",
    );
    let container = t.ok(
        unknown.cast::<IConnectionPointContainer>(),
        "QueryInterface(IConnectionPointContainer) across processes",
    );
    // SAFETY: a QueryInterface with a valid IID and out-parameter.
    let space = unsafe {
        let mut out = std::ptr::null_mut();
        let hr = unknown.query(&IID_EXAMPLE_ADDRESS_SPACE, &mut out);
        if !out.is_null() {
            drop(IUnknown::from_raw(out));
        }
        hr
    };
    t.check(
        space == E_NOINTERFACE,
        &format!(
            "QueryInterface(IExampleAddressSpace): E_NOINTERFACE, it has no proxy/stub ({})",
            hex(space)
        ),
    );
    if let (Some(common), Some(container)) = (common, container) {
        let server = ExampleServer { common, container };
        common_calls(t, &server);
        shutdown_calls(t, &server);
    }
    drop(unknown);
    // The server, stopped by its operator and with no object left, exits.
    t.check(
        wait_until(EXIT_DEADLINE, || !process_running("opccomn_example_server.exe")),
        "opccomn_example_server.exe exited once its clients let go",
    );
}

fn main() -> ExitCode {
    // SAFETY: the first COM call of this thread, undone by CoUninitialize below.
    let hr = unsafe { CoInitializeEx(None, COINIT_MULTITHREADED) };
    if hr.is_err() {
        eprintln!("third-party-client: CoInitializeEx failed: {}", hex(hr));
        return ExitCode::from(2);
    }
    println!(
        "third-party-client: opc_da 0.3.1 / opc_comn_bindings 0.3.0, client built for {}",
        std::env::consts::ARCH
    );
    let mut t = Tally::default();
    browse(&mut t);
    example_server(&mut t);
    da::da_server(&mut t, &da::C_TEST_SERVER);
    da::da_server(&mut t, &da::CRATE_SERVER);
    // The x86 build of the same server, registered by the test script when 32-bit Wine runs.
    if std::env::var_os("OPC_DA_CRATE_SERVER_X86").is_some_and(|v| v == "1") {
        da::da_server(&mut t, &da::CRATE_SERVER_X86);
    } else {
        println!("-- the x86 opc_da server is not registered (OPC_DA_CRATE_SERVER_X86 is not 1): not run");
    }
    // SAFETY: balances the CoInitializeEx above; every interface of this thread is released.
    unsafe { CoUninitialize() };
    println!("third-party-client: {} passed, {} failed", t.passed, t.failed);
    if t.failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
