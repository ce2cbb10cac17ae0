//! opccomn's own module: the one class it serves as an in-process COM server (OPCServerList), as an
//! [`OpcServerClass`] table, and its `Dll*` entry points, which are the server plumbing's module
//! functions (`src/server/`: [`OpcModuleGetClassObject`], [`OpcModuleCanUnloadNow`],
//! [`OpcModuleRegister`], [`OpcModuleUnregister`]) over that table, as any DLL server built on the
//! library has them. The server list itself (IOPCServerList, IOPCServerList2) is `src/serverlist/`.
//!
//! Beside the table's class, `DllGetClassObject` hands out the proxy/stub's class objects
//! (`src/proxy`, on Windows), and `DllInstall` (`src/proxy`) registers the proxy/stub
//! (`regsvr32 /i:ProxyStub`).
//!
//! The four `Dll*` entry points are exported under their standard names only with the cargo feature
//! `dll-exports` (on by default), because a server that links opccomn statically into its own COM DLL
//! has its own. Such a server builds opccomn with `--no-default-features` and, to serve the server
//! list as well, calls `OpcDllGetClassObject` (and the other `OpcDll*` functions, always exported) from
//! its own entry points.
//!
//! Registration coexists with the OPC Foundation's OpcEnum, which registers the same CLSID as an EXE
//! server: the class's registration keeps existing values (`OPC_REGISTRATION_KEEP_EXISTING`), so
//! opccomn adds `InprocServer32` (ThreadingModel Both) and whatever values are missing, keeps every
//! value it finds (`LocalServer32`, `AppID`, OpcEnum's description...), and unregistration removes only
//! what it added. It never registers proxies or stubs for the OPC interfaces (specification 6.3): that
//! is a separate step (src/proxy, `OpcRegisterProxyStub` or `regsvr32 /i:ProxyStub`).

use core::ffi::c_void;
use core::ptr;

use crate::com::ffi::{self, Hr};
use crate::com::iids::CLSID_OPCServerList;
use crate::com::{IUnknown, CLASS_E_CLASSNOTAVAILABLE, HRESULT, REFCLSID, REFIID, S_FALSE, S_OK, WCHAR};
use crate::registry::register::{OpcServerRegistration, OpcServerType, OPC_REGISTRATION_KEEP_EXISTING};
use crate::registry::registries;
use crate::server::{
    OpcCreateInstanceFn, OpcModuleCanUnloadNow, OpcModuleGetClassObject, OpcModuleRegister, OpcModuleUnregister,
    OpcServerClass, OPC_CLASS_AGGREGATABLE,
};

/// `SELFREG_E_CLASS` (olectl.h): DllRegisterServer / DllUnregisterServer could not write the class.
#[cfg(not(system_com_headers))]
pub const SELFREG_E_CLASS: HRESULT = 0x80040201_u32 as HRESULT;

/// A NUL-terminated UTF-16 copy of an ASCII text, made by the compiler. `N` is its length plus one.
const fn wide<const N: usize>(text: &str) -> [WCHAR; N] {
    let bytes = text.as_bytes();
    assert!(bytes.len() + 1 == N, "N must be the text's length plus one");
    let mut units = [0; N];
    let mut i = 0;
    while i < bytes.len() {
        assert!(bytes[i].is_ascii(), "ASCII only");
        units[i] = bytes[i] as WCHAR;
        i += 1;
    }
    units
}

static PROG_ID: [WCHAR; 17] = wide("OPC.ServerList.1");
static VERSION_INDEPENDENT_PROG_ID: [WCHAR; 15] = wide("OPC.ServerList");
static USER_TYPE: [WCHAR; 21] = wide("Opc ServerList Class");
static THREADING_MODEL: [WCHAR; 5] = wide("Both");

/// What a static holds that has raw pointers: only to other statics, never written.
struct Shared<T>(T);

// SAFETY: every pointer in a `Shared` value points at a static that is never written (the strings and
// the registration below, CLSID_OPCServerList); the class's `create` may be called from any thread.
unsafe impl<T> Sync for Shared<T> {}

/// What `OpcDllRegisterServer` writes for OPCServerList: an in-process server of this module
/// (`module_path` NULL), keeping what another product (OpcEnum) registered under the same CLSID.
static REGISTRATION: Shared<OpcServerRegistration> = Shared(OpcServerRegistration {
    struct_size: core::mem::size_of::<OpcServerRegistration>() as u32,
    server_type: OpcServerType::Inproc as u32,
    clsid: CLSID_OPCServerList,
    prog_id: PROG_ID.as_ptr(),
    version_independent_prog_id: VERSION_INDEPENDENT_PROG_ID.as_ptr(),
    user_type: USER_TYPE.as_ptr(),
    module_path: ptr::null(),
    threading_model: THREADING_MODEL.as_ptr(),
    implemented_categories: ptr::null(),
    implemented_category_count: 0,
    implemented_category_descriptions: ptr::null(),
    required_categories: ptr::null(),
    required_category_count: 0,
    da10_vendor: ptr::null(),
    app_id: ptr::null(),
    app_id_run_as: ptr::null(),
    app_id_local_service: ptr::null(),
    app_id_dll_surrogate: ptr::null(),
    flags: OPC_REGISTRATION_KEEP_EXISTING,
    app_id_access_permission: ptr::null(),
    app_id_launch_permission: ptr::null(),
    app_id_authentication_level: 0,
});

/// Makes a server list over the system registry for the class object's CreateInstance (which has
/// checked `riid` and `ppv`, set `*ppv` to NULL, and refused an outer object unless `riid` is
/// IID_IUnknown).
///
/// # Safety
/// As for `OpcCreateInstanceFn`.
unsafe extern "C" fn create_server_list(
    _context: *mut c_void,
    outer: *mut IUnknown,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> Hr {
    ffi::boundary!(Com, [ppv], {
        // SAFETY: the caller's contract; the creation protocol checks every argument again.
        Ok(unsafe { crate::serverlist::create(registries(ptr::null()), outer, riid, ppv) })
    })
}

/// `create_server_list` as `OpcServerClass::create`, whose result is the plain HRESULT that `Hr` is.
const CREATE_SERVER_LIST: OpcCreateInstanceFn = {
    let f: unsafe extern "C" fn(*mut c_void, *mut IUnknown, REFIID, *mut *mut c_void) -> Hr = create_server_list;
    // SAFETY: function pointers of ABI-compatible signatures: the result types differ only by a
    // transparent wrapper (`Crossed<HRESULT>` is `#[repr(transparent)]`).
    Some(unsafe {
        core::mem::transmute::<
            unsafe extern "C" fn(_, _, _, _) -> Hr,
            unsafe extern "C" fn(*mut c_void, *mut IUnknown, REFIID, *mut *mut c_void) -> HRESULT,
        >(f)
    })
};

/// opccomn's class table: OPCServerList, aggregatable (with IID_IUnknown, as COM requires), made over
/// the system registry, registered by `OpcDllRegisterServer`.
static CLASSES: Shared<[OpcServerClass; 1]> = Shared([OpcServerClass {
    struct_size: core::mem::size_of::<OpcServerClass>() as u32,
    clsid: &CLSID_OPCServerList,
    create: CREATE_SERVER_LIST,
    context: ptr::null_mut(),
    flags: OPC_CLASS_AGGREGATABLE,
    registration: &REGISTRATION.0,
}]);

/// The table as the module functions take it.
fn classes() -> (*const OpcServerClass, u32) {
    (CLASSES.0.as_ptr(), CLASSES.0.len() as u32)
}

/// The class object of CLSID_OPCServerList (an IClassFactory whose CreateInstance makes server lists
/// over the system registry, and which honours LockServer), as DllGetClassObject returns it; on
/// Windows also the proxy/stub factory of CLSID_OpcComnProxyStub (see `OpcRegisterProxyStub`). For
/// servers that link opccomn statically and have their own DllGetClassObject: forward these classes here.
///
/// # Parameters
/// - `rclsid`: the class: CLSID_OPCServerList, or on Windows CLSID_OpcComnProxyStub.
/// - `riid`: the interface wanted: IID_IClassFactory or IID_IUnknown for CLSID_OPCServerList.
/// - `ppv` (out): receives the class object, or NULL on failure.
///
/// # Returns
/// S_OK; E_POINTER for a NULL `ppv`, `rclsid` or `riid`; CLASS_E_CLASSNOTAVAILABLE for any other
/// class; E_NOINTERFACE unless `riid` is IID_IClassFactory or IID_IUnknown.
///
/// # Safety
/// `rclsid` and `riid` NULL or readable; `ppv` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcDllGetClassObject(rclsid: REFCLSID, riid: REFIID, ppv: *mut *mut c_void) -> Hr {
    ffi::boundary!(Com, [ppv], {
        let (table, count) = classes();
        // SAFETY: the static table is valid as OpcServerClass documents; the caller's pointers are
        // checked by the module function.
        let hr = unsafe { OpcModuleGetClassObject(table, count, rclsid, riid, ppv) }.get();
        if hr != CLASS_E_CLASSNOTAVAILABLE {
            return Ok(hr);
        }
        // Not the table's class (so every argument was there): the proxy/stub's classes on Windows,
        // CLASS_E_CLASSNOTAVAILABLE for any other.
        // SAFETY: the caller's contract: `ppv` NULL or writable, `rclsid` and `riid` NULL or readable.
        let (out, rclsid, riid) = unsafe { (ffi::out(ppv)?, ffi::in_ref(rclsid)?, ffi::in_ref(riid)?) };
        // SAFETY: `rclsid` and `riid` are readable; `out` is the caller's writable out-parameter.
        Ok(unsafe { crate::proxy::get_class_object(rclsid, riid, out.as_ptr()) })
    })
}

/// Whether COM may unload opccomn.dll (its DllCanUnloadNow).
///
/// # Returns
/// S_OK when no object of the library is alive, no server lock is held, no proxy or stub is in use
/// and no worker of `OpcShutdownNotifyBounded` is still calling a sink, so COM may unload the DLL;
/// S_FALSE otherwise.
#[no_mangle]
pub extern "C" fn OpcDllCanUnloadNow() -> Hr {
    ffi::guard!(S_FALSE, { OpcModuleCanUnloadNow().get() })
}

/// Registers CLSID_OPCServerList as an in-process server of this module (InprocServer32 with
/// ThreadingModel Both, ProgID OPC.ServerList.1, version-independent OPC.ServerList, user type "Opc
/// ServerList Class") in the system registry, adding to an existing OpcEnum registration without
/// changing it.
///
/// # Returns
/// S_OK or SELFREG_E_CLASS.
#[no_mangle]
pub extern "C" fn OpcDllRegisterServer() -> Hr {
    ffi::guard!(SELFREG_E_CLASS, {
        let (table, count) = classes();
        // SAFETY: the static table; NULL is the system registry.
        match unsafe { OpcModuleRegister(table, count, ptr::null()) }.get() {
            S_OK => S_OK,
            _ => SELFREG_E_CLASS,
        }
    })
}

/// Removes what `OpcDllRegisterServer` added, leaving everything else (an OpcEnum registration under
/// the same CLSID in particular). Unregistering what is not registered succeeds.
///
/// # Returns
/// S_OK or SELFREG_E_CLASS.
#[no_mangle]
pub extern "C" fn OpcDllUnregisterServer() -> Hr {
    ffi::guard!(SELFREG_E_CLASS, {
        let (table, count) = classes();
        // SAFETY: the static table; NULL is the system registry.
        match unsafe { OpcModuleUnregister(table, count, ptr::null()) }.get() {
            S_OK => S_OK,
            _ => SELFREG_E_CLASS,
        }
    })
}

/// The standard COM entry point: `OpcDllGetClassObject`. (Declared by the system headers, so not in
/// opccomn.h.)
///
/// cbindgen:ignore
///
/// # Safety
/// As for `OpcDllGetClassObject`.
#[cfg(feature = "dll-exports")]
#[no_mangle]
pub unsafe extern "system" fn DllGetClassObject(rclsid: REFCLSID, riid: REFIID, ppv: *mut *mut c_void) -> Hr {
    ffi::boundary!(Com, [ppv], {
        // SAFETY: forwarded.
        Ok(unsafe { OpcDllGetClassObject(rclsid, riid, ppv) }.get())
    })
}

/// The standard COM entry point: `OpcDllCanUnloadNow`.
///
/// cbindgen:ignore
#[cfg(feature = "dll-exports")]
#[no_mangle]
pub extern "system" fn DllCanUnloadNow() -> Hr {
    ffi::guard!(S_FALSE, { OpcDllCanUnloadNow().get() })
}

/// The standard self-registration entry point (`regsvr32 opccomn.dll`): `OpcDllRegisterServer`.
///
/// cbindgen:ignore
#[cfg(feature = "dll-exports")]
#[no_mangle]
pub extern "system" fn DllRegisterServer() -> Hr {
    ffi::guard!(SELFREG_E_CLASS, { OpcDllRegisterServer().get() })
}

/// The standard unregistration entry point (`regsvr32 /u opccomn.dll`): `OpcDllUnregisterServer`.
///
/// cbindgen:ignore
#[cfg(feature = "dll-exports")]
#[no_mangle]
pub extern "system" fn DllUnregisterServer() -> Hr {
    ffi::guard!(SELFREG_E_CLASS, { OpcDllUnregisterServer().get() })
}

#[cfg(test)]
mod tests;
