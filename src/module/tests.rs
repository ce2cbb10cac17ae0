//! opccomn's own class through the module functions: the class object, its CreateInstance and the
//! classes the table does not hold.

use super::*;
use crate::com::iids::{IID_IOPCServerList, IID_ICLASSFACTORY, IID_IUNKNOWN};
use crate::com::interfaces::IClassFactory;
use crate::com::unknown::{query_interface, release};
use crate::com::{CLASS_E_NOAGGREGATION, E_NOINTERFACE, E_POINTER, GUID};

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
            OpcDllGetClassObject(&CLSID_OPCServerList, ptr::null(), &mut p),
            E_POINTER
        );
        assert_eq!(
            OpcDllGetClassObject(&CLSID_OPCServerList, &IID_IOPCServerList, &mut p),
            E_NOINTERFACE
        );
        assert_eq!(
            OpcDllGetClassObject(&CLSID_OPCServerList, &IID_ICLASSFACTORY, ptr::null_mut()),
            E_POINTER
        );
        assert_eq!(OpcDllGetClassObject(&CLSID_OPCServerList, &IID_IUNKNOWN, &mut p), S_OK);
        release(p.cast());
        assert_eq!(
            OpcDllGetClassObject(&CLSID_OPCServerList, &IID_ICLASSFACTORY, &mut p),
            S_OK
        );
        let f: *mut IClassFactory = p.cast();
        let mut list = ptr::null_mut();
        assert_eq!(
            IClassFactory::CreateInstance(f, ptr::null_mut(), &IID_IOPCServerList, &mut list),
            S_OK
        );
        assert!(!list.is_null());
        release(list.cast());
        IClassFactory::Release(f);
    }
}

#[test]
fn the_server_list_is_made_aggregated_only_as_iunknown() {
    let mut p: *mut c_void = ptr::null_mut();
    // A stand-in outer object: another server list, whose identity the inner one delegates to.
    // SAFETY: valid arguments; every reference taken is released.
    unsafe {
        assert_eq!(
            OpcDllGetClassObject(&CLSID_OPCServerList, &IID_ICLASSFACTORY, &mut p),
            S_OK
        );
        let f: *mut IClassFactory = p.cast();
        let mut outer: *mut c_void = ptr::null_mut();
        assert_eq!(
            IClassFactory::CreateInstance(f, ptr::null_mut(), &IID_IUNKNOWN, &mut outer),
            S_OK
        );
        let mut inner: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
        assert_eq!(
            IClassFactory::CreateInstance(f, outer.cast(), &IID_IOPCServerList, &mut inner),
            CLASS_E_NOAGGREGATION
        );
        assert!(inner.is_null());
        assert_eq!(
            IClassFactory::CreateInstance(f, outer.cast(), &IID_IUNKNOWN, &mut inner),
            S_OK
        );
        // The inner object's interfaces delegate their identity to the outer object.
        let mut list: *mut c_void = ptr::null_mut();
        assert_eq!(query_interface(inner.cast(), &IID_IOPCServerList, &mut list), S_OK);
        let mut identity: *mut c_void = ptr::null_mut();
        assert_eq!(query_interface(list.cast(), &IID_IUNKNOWN, &mut identity), S_OK);
        let mut outer_identity: *mut c_void = ptr::null_mut();
        assert_eq!(query_interface(outer.cast(), &IID_IUNKNOWN, &mut outer_identity), S_OK);
        assert_eq!(identity, outer_identity);
        release(identity.cast());
        release(outer_identity.cast());
        release(list.cast());
        release(inner.cast());
        release(outer.cast());
        IClassFactory::Release(f);
    }
}
