//! opccomn.dll as the proxy/stub of the OPC Common interfaces (IOPCShutdown, IOPCCommon,
//! IOPCServerList, IOPCServerList2, IOPCEnumGUID) and of the OPC Data Access (DA 1.0, 2.05a and
//! 3.0, IOPCDataCallback included), Alarms & Events 1.10 and Historical Data Access 1.20 interfaces,
//! the way a MIDL "merged proxy/stub" DLL is one:
//! `DllGetClassObject(CLSID_OpcComnProxyStub)` hands out the system RPC runtime's PSFactoryBuffer over
//! NDR format strings generated from `idl/opccomn.idl`, `opcda.idl`, `opc_ae.idl` and `opchda.idl` (`src/proxy/opccomn_ps.c`, built by
//! `buildscript/proxy.rs` on Windows with mingw; `tools/gen-proxy.py` generates and corrects the
//! tables, CI checks they are current). The bytes on the wire are therefore the runtime's NDR for the interfaces as the OPC
//! Foundation's IDL declares them, the same as its `opccomn_ps.dll` produces.
//!
//! Registering the proxy/stub is a separate step, never a side effect of `regsvr32 opccomn.dll`:
//!
//! ```text
//! CLSID\{CLSID_OpcComnProxyStub}                  @ = PSFactoryBuffer
//! CLSID\{CLSID_OpcComnProxyStub}\InprocServer32   @ = opccomn.dll path, ThreadingModel = Both
//! Interface\{iid}                                 @ = interface name (kept when present)
//! Interface\{iid}\NumMethods                      @ = method count including IUnknown's
//! Interface\{iid}\ProxyStubClsid32                @ = {CLSID_OpcComnProxyStub}
//! ```
//!
//! An interface whose `ProxyStubClsid32` already names another installed proxy/stub (the Foundation's
//! `opccomn_ps.dll`) is left to it unless the caller asks to take over
//! ([`OPC_PROXY_STUB_TAKE_OVER`]). What registration adds or replaces goes into the same kind of ledger
//! the server registration keeps (value `OpcComnRegistration` of our `InprocServer32` key), so
//! unregistration deletes what it added, restores what it replaced (a taken-over `opccomn_ps.dll`
//! gets its `ProxyStubClsid32` back) and leaves alone every interface that another proxy/stub took
//! over after us.

use core::ffi::c_void;
use core::ptr;

use crate::com::ffi::{self, Hr};
pub use crate::com::guids::CLSID_OpcComnProxyStub;
use crate::com::{BOOL, E_INVALIDARG, GUID, HRESULT, IID, LPCWSTR, S_FALSE, S_OK};
use crate::registry::path::RegPath;
use crate::registry::register::{read_ledger, this_module_path, Entry, Recorder, LEDGER};
use crate::registry::{class_key, parse_guid, registries, OpcRegistry, RegValue, Registry};

/// `OpcRegisterProxyStub` flag: also take over interfaces another installed proxy/stub serves (the
/// previous `ProxyStubClsid32` is restored by `OpcUnregisterProxyStub`).
pub const OPC_PROXY_STUB_TAKE_OVER: u32 = 1;
/// `OpcRegisterProxyStub` flag: register the OPC Common interfaces (IOPCShutdown, IOPCCommon,
/// IOPCServerList, IOPCServerList2, IOPCEnumGUID). Without any of the specification flags, every
/// interface the proxy/stub serves is registered.
pub const OPC_PROXY_STUB_COMMON: u32 = 0x100;
/// `OpcRegisterProxyStub` flag: register the OPC Data Access 1.0, 2.05a and 3.0 interfaces (the
/// connection-point callback IOPCDataCallback included).
pub const OPC_PROXY_STUB_DA: u32 = 0x200;
/// `OpcRegisterProxyStub` flag: register the OPC Alarms & Events 1.10 interfaces (the event sink
/// IOPCEventSink included).
pub const OPC_PROXY_STUB_AE: u32 = 0x400;
/// `OpcRegisterProxyStub` flag: register the OPC Historical Data Access 1.20 interfaces (the
/// callback IOPCHDA_DataCallback included).
pub const OPC_PROXY_STUB_HDA: u32 = 0x800;

/// The specifications whose interfaces the proxy/stub serves: the name registration's command line
/// gives each (as `tools/gen-header` names them in the layouts) and its flag.
///
/// cbindgen:ignore
const SPECIFICATIONS: [(&str, u32); 4] = [
    ("Common", OPC_PROXY_STUB_COMMON),
    ("DA", OPC_PROXY_STUB_DA),
    ("AE", OPC_PROXY_STUB_AE),
    ("HDA", OPC_PROXY_STUB_HDA),
];
/// Every specification flag.
///
/// cbindgen:ignore
const ALL_SPECIFICATIONS: u32 = OPC_PROXY_STUB_COMMON | OPC_PROXY_STUB_DA | OPC_PROXY_STUB_AE | OPC_PROXY_STUB_HDA;

/// The flag of a specification, by its name in the layouts.
fn spec_flag(name: &str) -> u32 {
    SPECIFICATIONS
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name))
        .map_or(0, |(_, flag)| *flag)
}

/// The interfaces the proxy/stub serves, generated from the IDL with its layouts.
static INTERFACES: [(IID, &str, u32, &str); layouts::COUNT] = layouts::PROXY_STUB_INTERFACES;

/// The interfaces the proxy/stub serves: IID, name, `NumMethods` (IUnknown's three included).
fn interfaces() -> [(&'static IID, &'static str, u32); layouts::COUNT] {
    INTERFACES
        .each_ref()
        .map(|(iid, name, methods, _)| (iid, *name, *methods))
}

/// Those of the specifications in `specs` (`OPC_PROXY_STUB_COMMON`, ...).
fn interfaces_of(specs: u32) -> Vec<(&'static IID, &'static str, u32)> {
    INTERFACES
        .iter()
        .filter(|(.., spec)| spec_flag(spec) & specs != 0)
        .map(|(iid, name, methods, _)| (iid, *name, *methods))
        .collect()
}

// The checks: used by the proxy/stub (Windows, mingw); everywhere else only their tests and the fuzz
// targets run them. `ndr` is the interpreter, `layouts` what tools/gen-header generates from the IDL,
// `wire` the checks of the served interfaces.
#[cfg(feature = "fuzzing")]
pub mod ndr;
#[cfg(not(feature = "fuzzing"))]
#[cfg_attr(not(opccomn_proxy_stub), allow(dead_code))]
pub(crate) mod ndr;

#[path = "generated/layouts.rs"]
#[cfg_attr(not(opccomn_proxy_stub), allow(dead_code))]
pub mod layouts;

/// Layouts of idl/testdata/ndr-constructs.idl, which uses every construct of the layout language
/// (nothing registers its interfaces: their table goes unused).
#[cfg(any(test, feature = "fuzzing"))]
#[path = "generated/test_layouts.rs"]
#[allow(dead_code)]
pub mod test_layouts;

/// The checks of the served interfaces by their names, for the tests and the fuzz targets (the C
/// boundary below calls `ndr` with the number the C side passes).
#[cfg(feature = "fuzzing")]
pub mod wire;
#[cfg(all(test, not(feature = "fuzzing")))]
mod wire;

#[cfg(opccomn_proxy_stub)]
extern "C" {
    // src/proxy/opccomn_ps.c: NdrDllGetClassObject / NdrDllCanUnloadNow over the generated tables, with
    // the checks of `ndr` in front of the runtime's NDR engine.
    fn OpcProxyStubGetClassObject(
        rclsid: *const GUID,
        riid: *const GUID,
        ppv: *mut *mut c_void,
        checks: *const Checks,
    ) -> HRESULT;
    fn OpcProxyStubCanUnloadNow() -> HRESULT;
}

/// The checks `src/proxy/opccomn_ps.c` calls (its `OpcProxyStubChecks`).
#[cfg(opccomn_proxy_stub)]
#[repr(C)]
struct Checks {
    request: unsafe extern "C" fn(u32, u32, *const u8, u32, u32, u32, *mut u32) -> Hr,
    reply: unsafe extern "C" fn(u32, u32, *const u32, *const u8, u32, u32, u32) -> Hr,
}

#[cfg(opccomn_proxy_stub)]
static CHECKS: Checks = Checks {
    request: check_request,
    reply: check_reply,
};

/// The bytes of a message: `len` bytes at `buf`; None for NULL with a length, and for a buffer that is
/// not 4-byte aligned (the NDR engine aligns to the address, the checks to the message's start; a
/// channel's buffers are always aligned; a method that aligns to 8 needs 8, which the checks see).
///
/// # Safety
/// `buf` NULL or readable for `len` bytes for `'a`.
#[cfg(opccomn_proxy_stub)]
unsafe fn message<'a>(buf: *const u8, len: u32) -> Option<&'a [u8]> {
    if buf.is_null() {
        return (len == 0).then_some(&[]);
    }
    if buf as usize % 4 != 0 {
        return None;
    }
    // SAFETY: readable for `len` bytes, as the caller vouches.
    Some(unsafe { core::slice::from_raw_parts(buf, len as usize) })
}

/// The runtime that reads this process's messages: Wine's (`wine_reader` nonzero) or Windows'.
#[cfg(opccomn_proxy_stub)]
fn dialect(wine_reader: u32) -> ndr::Dialect {
    if wine_reader != 0 {
        ndr::Dialect::Wine
    } else {
        ndr::Dialect::Ndr
    }
}

/// [`ndr::check_request`] for the stubs' `Invoke` and the checked channel: the request for `method`
/// of interface number `iface`; when `context` is not NULL, what the reply check will need of it goes
/// to its [`ndr::CONTEXT_WORDS`] words (zeros when the request is refused). `wine_reader`: nonzero when
/// this process's rpcrt4 is Wine's ([`ndr::Dialect`]).
///
/// # Safety
/// `buf` NULL or readable for `len` bytes; `context` NULL or writable for `ndr::CONTEXT_WORDS` words.
#[cfg(opccomn_proxy_stub)]
unsafe extern "C" fn check_request(
    iface: u32,
    method: u32,
    buf: *const u8,
    len: u32,
    drep: u32,
    wine_reader: u32,
    context: *mut u32,
) -> Hr {
    ffi::guard!(ndr::BAD_STUB_DATA, {
        // SAFETY: forwarded from the caller.
        let result = match (layouts::Interface::from_index(iface), unsafe { message(buf, len) }) {
            (Some(iface), Some(bytes)) => ndr::check_request(iface.layout(), method, bytes, drep, dialect(wine_reader)),
            _ => Err(ndr::BAD_STUB_DATA),
        };
        if !context.is_null() {
            let words = result.unwrap_or_default().0;
            // SAFETY: writable for CONTEXT_WORDS words, as the caller vouches.
            unsafe { core::ptr::copy_nonoverlapping(words.as_ptr(), context, words.len()) };
        }
        match result {
            Ok(_) => S_OK,
            Err(hr) => hr,
        }
    })
}

/// [`ndr::check_reply`] for the checked channel: the reply to `method` of interface number `iface`,
/// with the context [`check_request`] wrote for its request.
///
/// # Safety
/// `context` readable for `ndr::CONTEXT_WORDS` words; `buf` NULL or readable for `len` bytes.
#[cfg(opccomn_proxy_stub)]
unsafe extern "C" fn check_reply(
    iface: u32,
    method: u32,
    context: *const u32,
    buf: *const u8,
    len: u32,
    drep: u32,
    wine_reader: u32,
) -> Hr {
    ffi::guard!(ndr::BAD_STUB_DATA, {
        if context.is_null() {
            return ndr::BAD_STUB_DATA;
        }
        let mut words = [0u32; ndr::CONTEXT_WORDS];
        // SAFETY: readable for CONTEXT_WORDS words, as the caller vouches.
        unsafe { core::ptr::copy_nonoverlapping(context, words.as_mut_ptr(), words.len()) };
        // SAFETY: forwarded from the caller.
        match (layouts::Interface::from_index(iface), unsafe { message(buf, len) }) {
            (Some(iface), Some(bytes)) => {
                match ndr::check_reply(
                    iface.layout(),
                    method,
                    &ndr::Context(words),
                    bytes,
                    drep,
                    dialect(wine_reader),
                ) {
                    Ok(()) => S_OK,
                    Err(hr) => hr,
                }
            }
            _ => ndr::BAD_STUB_DATA,
        }
    })
}

/// The PSFactoryBuffer for `rclsid` (CLSID_OpcComnProxyStub, or, as with MIDL's proxies, the IID of one
/// of the interfaces it serves); CLASS_E_CLASSNOTAVAILABLE otherwise and where the proxy/stub is not built.
///
/// # Safety
/// `rclsid` and `riid` readable; `ppv` writable.
pub(crate) unsafe fn get_class_object(rclsid: &GUID, riid: &GUID, ppv: *mut *mut c_void) -> HRESULT {
    #[cfg(opccomn_proxy_stub)]
    {
        // SAFETY: valid pointers; the runtime checks `riid` and writes `*ppv` (NULL on failure).
        let hr = unsafe { OpcProxyStubGetClassObject(rclsid, riid, ppv, &CHECKS) };
        if hr < 0 {
            // SAFETY: writable, as the caller vouches.
            unsafe { *ppv = ptr::null_mut() };
        }
        hr
    }
    #[cfg(not(opccomn_proxy_stub))]
    {
        let _ = (rclsid, riid);
        // SAFETY: writable, as the caller vouches.
        unsafe { *ppv = ptr::null_mut() };
        crate::com::CLASS_E_CLASSNOTAVAILABLE
    }
}

/// True when no proxy, stub or factory reference of the proxy/stub is alive.
pub(crate) fn can_unload() -> bool {
    #[cfg(opccomn_proxy_stub)]
    {
        // SAFETY: no arguments; the runtime reads the factory's reference count.
        unsafe { OpcProxyStubCanUnloadNow() == S_OK }
    }
    #[cfg(not(opccomn_proxy_stub))]
    {
        true
    }
}

fn module_key() -> String {
    format!("{}\\InprocServer32", class_key(&CLSID_OpcComnProxyStub))
}

fn interface_key(iid: &GUID) -> String {
    format!("Interface\\{iid}")
}

/// The CLSID an interface's `ProxyStubClsid32` names, if any.
fn proxy_stub_of(reg: &dyn Registry, iid: &GUID) -> Option<GUID> {
    let value = reg.value(&format!("{}\\ProxyStubClsid32", interface_key(iid)), "")?;
    parse_guid(value.as_str()?)
}

/// Registers the proxy/stub (module `module`) in `reg` for the interfaces of the specifications in
/// `specs`. Ok(true) when all of them now use it, Ok(false) when some stay with another installed
/// proxy/stub.
pub(crate) fn register(reg: &dyn Registry, module: &str, take_over: bool, specs: u32) -> Result<bool, HRESULT> {
    let module_key = module_key();
    let ours = CLSID_OpcComnProxyStub.to_string();
    let mut rec = Recorder::new(reg, read_ledger(reg, &module_key).unwrap_or_default());
    rec.value(&class_key(&CLSID_OpcComnProxyStub), "", "PSFactoryBuffer", false)?;
    rec.value(&module_key, "", module, true)?;
    rec.value(&module_key, "ThreadingModel", "Both", true)?;
    let mut all = true;
    for (iid, name, methods) in interfaces_of(specs) {
        match proxy_stub_of(reg, iid) {
            Some(other)
                if other != CLSID_OpcComnProxyStub
                    && !take_over
                    && reg.key_exists(&format!("{}\\InprocServer32", class_key(&other))) =>
            {
                all = false;
                continue;
            }
            _ => {}
        }
        let key = interface_key(iid);
        rec.value(&key, "", name, false)?;
        rec.value(&format!("{key}\\NumMethods"), "", &methods.to_string(), true)?;
        rec.value(&format!("{key}\\ProxyStubClsid32"), "", &ours, true)?;
    }
    let text: Vec<String> = rec.ledger.iter().map(Entry::encode).collect();
    reg.set_value(&module_key, LEDGER, &RegValue::Sz(text.join(";")))?;
    Ok(all)
}

/// Undoes [`register`] in `reg` for the interfaces of the specifications in `specs`, leaving
/// interfaces that another proxy/stub serves by now. What was registered for the other
/// specifications stays, with the proxy/stub's class, in the ledger; the class goes with the last
/// interface.
pub(crate) fn unregister(reg: &dyn Registry, specs: u32) -> Result<(), HRESULT> {
    let module_key = module_key();
    let class = class_key(&CLSID_OpcComnProxyStub);
    let ledger = match read_ledger(reg, &module_key) {
        Some(ledger) => ledger,
        // No ledger (written by other means): our own class keys, and ProxyStubClsid32 where it is ours.
        None => {
            let mut ledger = vec![
                Entry::Key(class.clone()),
                Entry::Key(module_key.clone()),
                Entry::Added(class.clone(), String::new(), None),
                Entry::Added(module_key.clone(), String::new(), None),
                Entry::Added(module_key.clone(), "ThreadingModel".into(), None),
            ];
            for (iid, ..) in interfaces() {
                ledger.push(Entry::Added(
                    format!("{}\\ProxyStubClsid32", interface_key(iid)),
                    String::new(),
                    None,
                ));
            }
            ledger
        }
    };
    // Interfaces another proxy/stub took over after us are its business now.
    let foreign: Vec<String> = interfaces()
        .iter()
        .filter(|(iid, ..)| proxy_stub_of(reg, iid).is_some_and(|c| c != CLSID_OpcComnProxyStub))
        .map(|(iid, ..)| interface_key(iid).to_lowercase())
        .collect();
    let under = |keys: &[String], key: &str| {
        let key = key.to_lowercase();
        keys.iter()
            .any(|f| key == *f || key.strip_prefix(f.as_str()).is_some_and(|rest| rest.starts_with('\\')))
    };
    // The interfaces of the specifications that stay registered, and whether the ledger holds any of
    // theirs (then the class and its module stay too).
    let staying: Vec<String> = interfaces_of(ALL_SPECIFICATIONS & !specs)
        .iter()
        .map(|(iid, ..)| interface_key(iid).to_lowercase())
        .collect();
    let others_remain = ledger.iter().any(|e| e.key().is_some_and(|k| under(&staying, k)));
    let stays = |key: &str| under(&staying, key) || (others_remain && !key.to_lowercase().starts_with("interface\\"));
    let keep = |key: &str| under(&foreign, key) || stays(key);
    // What registration writes, for entries of ledgers that did not record it (the module path of
    // our own class: whatever it is).
    let ours = CLSID_OpcComnProxyStub.to_string();
    let expected = |key: &str, name: &str| -> Option<RegValue> {
        let (key, name) = (RegPath::new(key), RegPath::new(name));
        if key == RegPath::new(class.as_str()) && name == RegPath::new("") {
            return Some("PSFactoryBuffer".into());
        }
        if key == RegPath::new(module_key.as_str()) {
            return (name == RegPath::new("ThreadingModel")).then(|| "Both".into());
        }
        interfaces().into_iter().find_map(|(iid, iname, methods)| {
            let k = interface_key(iid);
            if name != RegPath::new("") {
                None
            } else if key == RegPath::new(k.as_str()) {
                Some(iname.into())
            } else if key == RegPath::new(format!("{k}\\NumMethods")) {
                Some(methods.to_string().into())
            } else if key == RegPath::new(format!("{k}\\ProxyStubClsid32")) {
                Some(ours.clone().into())
            } else {
                None
            }
        })
    };
    // Only what still holds what registration wrote is taken back (see `Entry::still_written`).
    for entry in ledger.iter().rev() {
        if entry.key().is_some_and(keep) || !entry.still_written(reg, expected) {
            continue;
        }
        match entry {
            Entry::Added(key, name, _) => reg.delete_value(key, name)?,
            Entry::Replaced(key, name, old, _) => reg.set_value(key, name, old)?,
            _ => {}
        }
    }
    let remaining: Vec<String> = ledger
        .iter()
        .filter(|e| e.key().is_some_and(stays))
        .map(Entry::encode)
        .collect();
    if others_remain {
        reg.set_value(&module_key, LEDGER, &RegValue::Sz(remaining.join(";")))?;
    } else if reg.value(&module_key, LEDGER).is_some() {
        reg.delete_value(&module_key, LEDGER)?;
    }
    let mut keys: Vec<&String> = ledger
        .iter()
        .filter_map(|e| match e {
            Entry::Key(k) if !keep(k) => Some(k),
            _ => None,
        })
        .collect();
    // Deepest first, so children go before their parents.
    keys.sort_by_key(|k| core::cmp::Reverse(k.matches('\\').count()));
    for key in keys {
        if reg.key_exists(key) && reg.subkeys(key).is_empty() && reg.values(key).is_empty() {
            reg.delete_key(key)?;
        }
    }
    Ok(())
}

/// Registers opccomn's proxy/stub for the interfaces it serves: the OPC Common interfaces
/// (IOPCShutdown, IOPCCommon, IOPCServerList, IOPCServerList2, IOPCEnumGUID), those of OPC Data
/// Access 1.0, 2.05a and 3.0 (IOPCServer, IOPCItemMgt, IOPCSyncIO, IOPCDataCallback, ...), of OPC
/// Alarms & Events 1.10 (IOPCEventServer, IOPCEventSink, ...) and of Historical Data Access 1.20
/// (IOPCHDA_Server, IOPCHDA_DataCallback, ...), or those of the specifications `flags` names.
/// Writes `CLSID_OpcComnProxyStub` with this module as its
/// `InprocServer32` (ThreadingModel Both) and, per interface, `Interface\{iid}` with `NumMethods`
/// and `ProxyStubClsid32`. An interface whose `ProxyStubClsid32` names another installed proxy/stub
/// (the OPC Foundation's `opccomn_ps.dll` or `opcproxy.dll`) keeps it unless `flags` has
/// `OPC_PROXY_STUB_TAKE_OVER`. Records what it adds or replaces, so `OpcUnregisterProxyStub` undoes
/// exactly that. Registering twice is harmless; registering one specification after another adds to
/// what is registered.
///
/// # Parameters
/// - `reg`: the registry to write, or NULL for the system registry (on 64-bit Windows the view of the
///   calling process, so a 32-bit opccomn.dll registers the 32-bit view).
/// - `flags`: `OPC_PROXY_STUB_TAKE_OVER` or not, with the specifications to register
///   (`OPC_PROXY_STUB_COMMON`, `OPC_PROXY_STUB_DA`, `OPC_PROXY_STUB_AE`, `OPC_PROXY_STUB_HDA`); none
///   of those: all of them.
///
/// # Returns
/// S_OK when every interface registered now uses opccomn's proxy/stub; S_FALSE when some stay with
/// another; E_INVALIDARG for unknown flags; registry errors as HRESULTs.
///
/// # Safety
/// `reg` must be NULL or a live registry handle.
#[no_mangle]
pub unsafe extern "C" fn OpcRegisterProxyStub(reg: *const OpcRegistry, flags: u32) -> Hr {
    ffi::boundary!(Opc, [], {
        if flags & !(OPC_PROXY_STUB_TAKE_OVER | ALL_SPECIFICATIONS) != 0 {
            return Err(E_INVALIDARG.into());
        }
        // SAFETY: the caller vouches for the handle.
        let regs = unsafe { registries(reg) };
        let module = this_module_path(false)?;
        let take_over = flags & OPC_PROXY_STUB_TAKE_OVER != 0;
        Ok(if register(&*regs.write, &module, take_over, specifications(flags))? {
            S_OK
        } else {
            S_FALSE
        })
    })
}

/// The specifications `flags` names; none: all of them.
fn specifications(flags: u32) -> u32 {
    match flags & ALL_SPECIFICATIONS {
        0 => ALL_SPECIFICATIONS,
        specs => specs,
    }
}

/// Removes what `OpcRegisterProxyStub` added, for every specification, and restores the
/// `ProxyStubClsid32` values it replaced; interfaces another proxy/stub registered itself for since
/// are left as they are. Unregistering what is not registered succeeds. (`regsvr32 /u` with
/// `/i:"ProxyStub DA"` unregisters one specification.)
///
/// # Parameters
/// - `reg`: the registry, or NULL for the system registry.
///
/// # Returns
/// S_OK, or a registry error as an HRESULT.
///
/// # Safety
/// `reg` must be NULL or a live registry handle.
#[no_mangle]
pub unsafe extern "C" fn OpcUnregisterProxyStub(reg: *const OpcRegistry) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller vouches for the handle.
        let regs = unsafe { registries(reg) };
        unregister(&*regs.write, ALL_SPECIFICATIONS)?;
        Ok(S_OK)
    })
}

/// What a `DllInstall` command line asks for: Some(flags) for `ProxyStub` (`OpcRegisterProxyStub`'s
/// flags: `TakeOver`, and the specifications named, `Common`, `DA`, `AE` and `HDA`).
fn parse_install_command(text: &str) -> Option<u32> {
    let mut proxy_stub = false;
    let mut flags = 0;
    for word in text.split([',', ' ', ';']).filter(|w| !w.is_empty()) {
        if word.eq_ignore_ascii_case("ProxyStub") {
            proxy_stub = true;
        } else if word.eq_ignore_ascii_case("TakeOver") {
            flags |= OPC_PROXY_STUB_TAKE_OVER;
        } else {
            match spec_flag(word) {
                0 => return None,
                flag => flags |= flag,
            }
        }
    }
    proxy_stub.then_some(flags)
}

/// `DllInstall` of opccomn.dll, for `regsvr32 /i:<command line>`: the command line `ProxyStub`
/// registers the proxy/stub in the system registry for every interface it serves
/// (`OpcRegisterProxyStub`), `ProxyStub,TakeOver` also takes over from another installed proxy/stub;
/// the words `Common`, `DA`, `AE` and `HDA` choose the specifications (`ProxyStub DA`: only Data Access's), for
/// registering and for unregistering. Words are case-insensitive and separated by commas or blanks.
/// regsvr32 also calls DllRegisterServer / DllUnregisterServer unless given `/n`.
///
/// # Parameters
/// - `install`: TRUE to register; FALSE to unregister (`regsvr32 /u /i:ProxyStub`).
/// - `command_line`: what follows `/i:`.
///
/// # Returns
/// What `OpcRegisterProxyStub` or `OpcUnregisterProxyStub` returns; E_INVALIDARG for a NULL, empty or
/// unknown command line.
///
/// # Safety
/// `command_line` must be NULL or a NUL-terminated UTF-16 string.
#[no_mangle]
pub unsafe extern "C" fn OpcDllInstall(install: BOOL, command_line: LPCWSTR) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller vouches for NULL or a NUL-terminated string; the reader bounds the read.
        let text = unsafe { ffi::in_string(command_line)? };
        let flags = parse_install_command(&text).ok_or(E_INVALIDARG)?;
        if install != 0 {
            // SAFETY: NULL is the system registry.
            return Ok(unsafe { OpcRegisterProxyStub(ptr::null(), flags) }.get());
        }
        // SAFETY: NULL is the system registry.
        let regs = unsafe { registries(ptr::null()) };
        unregister(&*regs.write, specifications(flags))?;
        Ok(S_OK)
    })
}

/// The standard entry point `regsvr32 /i` calls: `OpcDllInstall`.
///
/// cbindgen:ignore
///
/// # Safety
/// As for `OpcDllInstall`.
#[cfg(feature = "dll-exports")]
#[no_mangle]
pub unsafe extern "system" fn DllInstall(install: BOOL, command_line: LPCWSTR) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: forwarded under the same contract.
        Ok(unsafe { OpcDllInstall(install, command_line) }.get())
    })
}

#[cfg(test)]
mod tests;
