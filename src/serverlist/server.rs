//! opccomn as an in-process COM server of CLSID_OPCServerList: the class factory, DllGetClassObject,
//! DllCanUnloadNow, DllRegisterServer and DllUnregisterServer.
//!
//! The four `Dll*` entry points are exported under their standard names only with the cargo feature
//! `dll-exports` (on by default), because a server that links opccomn statically into its own COM DLL
//! has its own. Such a server builds opccomn with `--no-default-features` and, to serve the server
//! list as well, calls `OpcDllGetClassObject` (and the other `OpcDll*` functions, always exported) from
//! its own entry points.
//!
//! Registration coexists with the OPC Foundation's OpcEnum, which registers the same CLSID as an EXE
//! server: opccomn adds `InprocServer32` (ThreadingModel Both) and whatever values are missing, keeps
//! every value it finds (`LocalServer32`, `AppID`, OpcEnum's description...), and unregistration removes
//! only what it added. It never registers proxies or stubs for the OPC interfaces (specification 6.3):
//! that is a separate step (src/proxy, `OpcRegisterProxyStub` or `regsvr32 /i:ProxyStub`).

use core::ffi::c_void;
use core::ptr;

use crate::com::ffi::{self, FfiResult, Hr};
use crate::com::iids::{CLSID_OPCServerList, IID_ICLASSFACTORY};
use crate::com::interfaces::{IClassFactoryImpl, IClassFactoryVtbl};
use crate::com::object::{ComClass, ComObject, Delegating, Slot};
use crate::com::{IUnknown, BOOL, GUID, HRESULT, REFCLSID, REFIID, S_FALSE, S_OK};
use crate::registry::register::{register, unregister, ServerDescription};
use crate::registry::{registries, REGDB_E_KEYMISSING};

/// `SELFREG_E_CLASS` (olectl.h): DllRegisterServer / DllUnregisterServer could not write the class.
#[cfg(not(system_com_headers))]
pub const SELFREG_E_CLASS: HRESULT = 0x80040201_u32 as HRESULT;

/// The class factory of OPCServerList.
struct Factory {
    slot: Slot,
}

impl ComClass for Factory {
    fn interface(&self, iid: &GUID) -> Option<&Slot> {
        (*iid == IID_ICLASSFACTORY).then_some(&self.slot)
    }
}

static FACTORY_VTBL: IClassFactoryVtbl = IClassFactoryVtbl::new::<Delegating, Factory>();

impl IClassFactoryImpl for Factory {
    unsafe fn CreateInstance(
        _this: &ComObject<Self>,
        outer: *mut IUnknown,
        riid: REFIID,
        ppv: *mut *mut c_void,
    ) -> FfiResult {
        // SAFETY: forwarded: the standard creation protocol checks every argument.
        Ok(unsafe { super::create(registries(ptr::null()), outer, riid, ppv) })
    }

    fn LockServer(_this: &ComObject<Self>, lock: BOOL) -> FfiResult {
        // The server count every class object of the library keeps (OpcServerLock).
        crate::server::lock_server(lock)
    }
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
        // SAFETY: the caller's contract: `ppv` NULL or writable, `rclsid` and `riid` NULL or readable.
        let (out, rclsid, riid) = unsafe { (ffi::out(ppv)?, ffi::in_ref(rclsid)?, ffi::in_ref(riid)?) };
        if *rclsid != CLSID_OPCServerList {
            // The proxy/stub class on Windows; CLASS_E_CLASSNOTAVAILABLE for any other class.
            // SAFETY: `rclsid` and `riid` are readable; `out` is the caller's writable out-parameter.
            return Ok(unsafe { crate::proxy::get_class_object(rclsid, riid, out.as_ptr()) });
        }
        let factory = ComObject::<Factory>::new(ptr::null_mut(), |b| Factory {
            slot: b.slot(&FACTORY_VTBL),
        });
        // SAFETY: `factory` keeps the object alive; its IUnknown QueryInterface checks `riid`.
        Ok(unsafe { crate::com::unknown::query_interface(factory.header().inner_unknown(), riid, out.as_ptr()) })
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
    ffi::guard!(S_FALSE, {
        if crate::server::can_unload() {
            S_OK
        } else {
            S_FALSE
        }
    })
}

/// What opccomn registers for itself.
fn server_list_registration() -> ServerDescription {
    ServerDescription {
        clsid: CLSID_OPCServerList,
        local: false,
        prog_id: "OPC.ServerList.1".into(),
        version_independent_prog_id: Some("OPC.ServerList".into()),
        user_type: "Opc ServerList Class".into(),
        module_path: None,
        threading_model: Some("Both".into()),
        keep_existing: true,
        ..Default::default()
    }
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
        // SAFETY: NULL is the system registry.
        match register(&*unsafe { registries(ptr::null()) }, &server_list_registration()) {
            Ok(()) => S_OK,
            Err(_) => SELFREG_E_CLASS,
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
        // SAFETY: NULL is the system registry.
        match unregister(&*unsafe { registries(ptr::null()) }, &server_list_registration()) {
            Ok(()) | Err(REGDB_E_KEYMISSING) => S_OK,
            Err(_) => SELFREG_E_CLASS,
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
mod tests {
    use super::*;
    use crate::com::iids::{IID_IOPCServerList, IID_IUNKNOWN};
    use crate::com::{CLASS_E_CLASSNOTAVAILABLE, E_POINTER};

    #[test]
    fn the_class_object_serves_only_the_server_list() {
        let mut p = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
        let other = GUID::from_u128(1);
        // SAFETY: valid pointers or deliberate NULLs.
        unsafe {
            assert_eq!(
                OpcDllGetClassObject(&other, &IID_ICLASSFACTORY, &mut p),
                CLASS_E_CLASSNOTAVAILABLE
            );
            assert!(p.is_null());
            assert_eq!(OpcDllGetClassObject(ptr::null(), &IID_ICLASSFACTORY, &mut p), E_POINTER);
            assert_eq!(
                OpcDllGetClassObject(&CLSID_OPCServerList, &IID_IOPCServerList, &mut p),
                crate::com::E_NOINTERFACE
            );
            assert_eq!(
                OpcDllGetClassObject(&CLSID_OPCServerList, &IID_ICLASSFACTORY, ptr::null_mut()),
                E_POINTER
            );
            assert_eq!(OpcDllGetClassObject(&CLSID_OPCServerList, &IID_IUNKNOWN, &mut p), S_OK);
            crate::com::unknown::release(p.cast());
            assert_eq!(
                OpcDllGetClassObject(&CLSID_OPCServerList, &IID_ICLASSFACTORY, &mut p),
                S_OK
            );
            let f = p as *mut crate::com::interfaces::IClassFactory;
            let v = &*(*f).lpVtbl;
            let mut list = ptr::null_mut();
            assert_eq!(
                (v.CreateInstance)(f, ptr::null_mut(), &IID_IOPCServerList, &mut list),
                S_OK
            );
            assert!(!list.is_null());
            crate::com::unknown::release(list.cast());
            (v.Release)(f);
        }
    }
}
