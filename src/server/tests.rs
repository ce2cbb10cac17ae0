//! The class objects and the DLL-module functions, through the C API (no operating system calls).

use core::ffi::c_void;
use core::ptr;
use core::sync::atomic::{AtomicU32, Ordering};

use super::*;
use crate::com::interfaces::IClassFactory;
use crate::com::unknown::release;
use crate::com::{E_NOINTERFACE, E_OUTOFMEMORY, E_POINTER, LPCWSTR};
use crate::registry::register::OpcServerType;
use crate::registry::{OpcRegistryCreateMemory, OpcRegistryGetString, OpcRegistryRelease};

const CLSID_A: GUID = GUID::from_u128(0x5EC00001_1111_2222_3333_444455556666);
const CLSID_B: GUID = GUID::from_u128(0x5EC00002_1111_2222_3333_444455556666);

/// What the server's create function does, chosen by its context.
#[derive(Clone, Copy)]
enum Behaviour {
    /// Makes a library object (an IOPCCommon session, aggregated when asked).
    Make,
    /// E_OUTOFMEMORY, with garbage left in `*ppv`.
    FailWithGarbage,
    /// S_OK without an object.
    OkWithNull,
}

struct Server {
    behaviour: Behaviour,
    calls: AtomicU32,
}

unsafe extern "C" fn create(
    context: *mut c_void,
    outer: *mut IUnknown,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> HRESULT {
    // SAFETY: the tests pass a live Server as the context; the library passes checked pointers.
    unsafe {
        let server = &*(context as *const Server);
        server.calls.fetch_add(1, Ordering::SeqCst);
        assert!((*ppv).is_null(), "the library sets *ppv to NULL first");
        match server.behaviour {
            Behaviour::Make => crate::common::OpcCommonCreate(ptr::null(), outer, riid, ppv).get(),
            Behaviour::FailWithGarbage => {
                *ppv = ptr::NonNull::<u64>::dangling().as_ptr().cast();
                E_OUTOFMEMORY
            }
            Behaviour::OkWithNull => S_OK,
        }
    }
}

fn class(clsid: &GUID, server: &Server, flags: u32) -> OpcServerClass {
    OpcServerClass {
        struct_size: core::mem::size_of::<OpcServerClass>() as u32,
        clsid,
        create: Some(create),
        context: server as *const Server as *mut c_void,
        flags,
        registration: ptr::null(),
    }
}

fn server(behaviour: Behaviour) -> Server {
    Server {
        behaviour,
        calls: AtomicU32::new(0),
    }
}

/// The class object of `c`, as IClassFactory.
fn factory(c: &OpcServerClass) -> *mut IClassFactory {
    let mut p: *mut c_void = ptr::null_mut();
    // SAFETY: valid arguments.
    assert_eq!(unsafe { OpcClassFactoryCreate(c, &IID_ICLASSFACTORY, &mut p) }, S_OK);
    p.cast()
}

#[test]
fn create_instance_makes_objects_and_refuses_aggregation_the_class_does_not_allow() {
    let s = server(Behaviour::Make);
    let plain = class(&CLSID_A, &s, 0);
    let f = factory(&plain);
    let iid_common = crate::com::iids::IID_IOPCCommon;
    // SAFETY: `f` is a live class object; every pointer passed is valid or deliberately NULL.
    unsafe {
        let mut p: *mut c_void = ptr::null_mut();
        assert_eq!(
            IClassFactory::CreateInstance(f, ptr::null_mut(), &iid_common, &mut p),
            S_OK
        );
        assert!(!p.is_null());
        assert_eq!(release(p.cast()), 0);
        // An outer object for a class that does not allow aggregation: refused before the server is asked.
        let outer = f.cast::<IUnknown>();
        p = ptr::NonNull::<u64>::dangling().as_ptr().cast();
        assert_eq!(
            IClassFactory::CreateInstance(f, outer, &IID_IUNKNOWN, &mut p),
            CLASS_E_NOAGGREGATION
        );
        assert!(p.is_null());
        assert_eq!(s.calls.load(Ordering::SeqCst), 1);
        // NULL arguments: COM's rule.
        assert_eq!(
            IClassFactory::CreateInstance(f, ptr::null_mut(), &iid_common, ptr::null_mut()),
            E_POINTER
        );
        assert_eq!(
            IClassFactory::CreateInstance(f, ptr::null_mut(), ptr::null(), &mut p),
            E_POINTER
        );
        // The class object answers IUnknown and IClassFactory only.
        let mut q: *mut c_void = ptr::null_mut();
        assert_eq!(IClassFactory::QueryInterface(f, &iid_common, &mut q), E_NOINTERFACE);
        assert!(q.is_null());
        assert_eq!(IClassFactory::Release(f), 0);
    }

    let aggregatable = class(&CLSID_A, &s, OPC_CLASS_AGGREGATABLE);
    let f = factory(&aggregatable);
    // A stand-in outer object: a class object of its own (a valid controlling unknown that outlives
    // the inner object).
    let outer = factory(&plain).cast::<IUnknown>();
    // SAFETY: as above.
    unsafe {
        let mut p: *mut c_void = ptr::null_mut();
        assert_eq!(
            IClassFactory::CreateInstance(f, outer, &iid_common, &mut p),
            CLASS_E_NOAGGREGATION
        );
        assert_eq!(IClassFactory::CreateInstance(f, outer, &IID_IUNKNOWN, &mut p), S_OK);
        assert!(!p.is_null());
        assert_eq!(release(p.cast()), 0, "the inner IUnknown counts the inner object only");
        release(outer);
        IClassFactory::Release(f);
    }
}

#[test]
fn a_failing_or_broken_create_function_leaves_no_object_behind() {
    for (behaviour, expected) in [
        (Behaviour::FailWithGarbage, E_OUTOFMEMORY),
        (Behaviour::OkWithNull, E_UNEXPECTED),
    ] {
        let s = server(behaviour);
        let c = class(&CLSID_A, &s, 0);
        let f = factory(&c);
        let mut p: *mut c_void = ptr::null_mut();
        // SAFETY: a live class object, valid arguments. The garbage pointer must not be released.
        unsafe {
            assert_eq!(
                IClassFactory::CreateInstance(f, ptr::null_mut(), &IID_IUNKNOWN, &mut p),
                expected
            );
            assert!(p.is_null());
            IClassFactory::Release(f);
        }
        assert_eq!(s.calls.load(Ordering::SeqCst), 1);
    }
}

#[test]
fn bad_classes_are_refused() {
    let s = server(Behaviour::Make);
    let good = class(&CLSID_A, &s, 0);
    let mut bad = [good; 5];
    bad[0].struct_size -= 8;
    bad[1].clsid = ptr::null();
    bad[2].create = None;
    bad[3].flags = 2;
    bad[4].struct_size = 0;
    for c in &bad {
        let mut p: *mut c_void = ptr::NonNull::<u64>::dangling().as_ptr().cast();
        // SAFETY: valid pointers; the class's content is what is wrong.
        let hr = unsafe { OpcClassFactoryCreate(c, &IID_ICLASSFACTORY, &mut p) };
        assert_eq!(hr, E_INVALIDARG);
        assert!(p.is_null());
    }
    let mut p: *mut c_void = ptr::null_mut();
    // SAFETY: NULL where the function must refuse it.
    unsafe {
        assert_eq!(
            OpcClassFactoryCreate(ptr::null(), &IID_ICLASSFACTORY, &mut p),
            E_POINTER
        );
        assert_eq!(OpcClassFactoryCreate(&good, ptr::null(), &mut p), E_POINTER);
        assert_eq!(
            OpcClassFactoryCreate(&good, &IID_ICLASSFACTORY, ptr::null_mut()),
            E_POINTER
        );
        assert_eq!(
            OpcClassFactoryCreate(&good, &crate::com::iids::IID_IOPCCommon, &mut p),
            E_NOINTERFACE
        );
        assert!(p.is_null());
    }
}

#[test]
fn the_module_finds_each_class_by_its_clsid() {
    let (sa, sb) = (server(Behaviour::Make), server(Behaviour::Make));
    let table = [class(&CLSID_A, &sa, 0), class(&CLSID_B, &sb, 0)];
    // SAFETY: a live table of two classes; valid or deliberately wrong arguments.
    unsafe {
        for (clsid, s) in [(CLSID_A, &sa), (CLSID_B, &sb)] {
            let mut p: *mut c_void = ptr::null_mut();
            assert_eq!(
                OpcModuleGetClassObject(table.as_ptr(), 2, &clsid, &IID_ICLASSFACTORY, &mut p),
                S_OK
            );
            let f = p.cast::<IClassFactory>();
            let mut o: *mut c_void = ptr::null_mut();
            assert_eq!(
                IClassFactory::CreateInstance(f, ptr::null_mut(), &IID_IUNKNOWN, &mut o),
                S_OK
            );
            release(o.cast());
            IClassFactory::Release(f);
            assert_eq!(s.calls.load(Ordering::SeqCst), 1, "the class of that CLSID made it");
        }
        let other = GUID::from_u128(7);
        let mut p: *mut c_void = ptr::NonNull::<u64>::dangling().as_ptr().cast();
        assert_eq!(
            OpcModuleGetClassObject(table.as_ptr(), 2, &other, &IID_ICLASSFACTORY, &mut p),
            CLASS_E_CLASSNOTAVAILABLE
        );
        assert!(p.is_null());
        assert_eq!(
            OpcModuleGetClassObject(table.as_ptr(), 0, &CLSID_A, &IID_ICLASSFACTORY, &mut p),
            E_INVALIDARG
        );
        assert_eq!(
            OpcModuleGetClassObject(ptr::null(), 2, &CLSID_A, &IID_ICLASSFACTORY, &mut p),
            E_POINTER
        );
        assert_eq!(
            OpcModuleGetClassObject(table.as_ptr(), 2, ptr::null(), &IID_ICLASSFACTORY, &mut p),
            E_POINTER
        );
        assert_eq!(
            OpcModuleGetClassObject(table.as_ptr(), 2, &CLSID_A, &IID_ICLASSFACTORY, ptr::null_mut()),
            E_POINTER
        );
    }
}

#[test]
fn lock_server_and_server_locks_count() {
    let s = server(Behaviour::Make);
    let c = class(&CLSID_A, &s, 0);
    let f = factory(&c);
    let before = SERVER_LOCKS.load(Ordering::SeqCst);
    // SAFETY: a live class object.
    unsafe {
        assert_eq!(IClassFactory::LockServer(f, 1), S_OK);
        OpcServerLock();
        assert_eq!(SERVER_LOCKS.load(Ordering::SeqCst), before + 2);
        assert_eq!(OpcModuleCanUnloadNow(), S_FALSE);
        assert_eq!(IClassFactory::LockServer(f, 0), S_OK);
        OpcServerUnlock();
        assert_eq!(SERVER_LOCKS.load(Ordering::SeqCst), before);
        IClassFactory::Release(f);
    }
}

fn w(s: &str) -> Vec<u16> {
    s.encode_utf16().chain(Some(0)).collect()
}

#[test]
fn the_module_registers_and_unregisters_every_class_with_a_registration() {
    let (sa, sb) = (server(Behaviour::Make), server(Behaviour::Make));
    let (prog_a, prog_b, user, path) = (
        w("Vendor.A.1"),
        w("Vendor.B.1"),
        w("Vendor Server"),
        w("C:\\Vendor\\s.dll"),
    );
    let registration = |clsid: GUID, prog: &[u16]| {
        // SAFETY: all-zero is a valid OpcServerRegistration (NULL pointers, zero counts); the fields
        // it needs are set below.
        let mut r: OpcServerRegistration = unsafe { core::mem::zeroed() };
        r.struct_size = core::mem::size_of::<OpcServerRegistration>() as u32;
        r.server_type = OpcServerType::Inproc as u32;
        r.clsid = clsid;
        r.prog_id = prog.as_ptr();
        r.user_type = user.as_ptr();
        r.module_path = path.as_ptr();
        r
    };
    let (ra, rb) = (registration(CLSID_A, &prog_a), registration(CLSID_B, &prog_b));
    let mut table = [
        class(&CLSID_A, &sa, 0),
        class(&CLSID_B, &sb, 0),
        class(&CLSID_B, &sb, 0),
    ];
    table[0].registration = &ra;
    table[1].registration = &rb;
    // The third class has no registration: it is not written.
    let mut reg = ptr::null_mut();
    // SAFETY: a live table and registrations; `reg` live until released.
    unsafe {
        assert_eq!(OpcRegistryCreateMemory(&mut reg), S_OK);
        let has = |key: &str| {
            let key = w(key);
            let mut text: crate::com::LPWSTR = ptr::null_mut();
            let hr = OpcRegistryGetString(reg, key.as_ptr(), ptr::null() as LPCWSTR, &mut text).get();
            crate::com::alloc::task_free(text.cast());
            hr == S_OK
        };
        assert_eq!(OpcModuleRegister(table.as_ptr(), 3, reg), S_OK);
        assert!(has(&format!("CLSID\\{CLSID_A}\\InprocServer32")));
        assert!(has(&format!("CLSID\\{CLSID_B}\\InprocServer32")));
        assert!(has("Vendor.B.1\\CLSID"));
        assert_eq!(OpcModuleUnregister(table.as_ptr(), 3, reg), S_OK);
        assert!(!has(&format!("CLSID\\{CLSID_A}\\InprocServer32")));
        assert!(!has("Vendor.B.1\\CLSID"));
        // Not registered: no failure.
        assert_eq!(OpcModuleUnregister(table.as_ptr(), 3, reg), S_OK);

        // A registration that describes another class: refused, nothing written.
        table[1].registration = &ra;
        assert_eq!(OpcModuleRegister(table.as_ptr(), 3, reg), E_INVALIDARG);
        assert!(!has(&format!("CLSID\\{CLSID_A}\\InprocServer32")));
        assert_eq!(OpcModuleRegister(ptr::null(), 3, reg), E_INVALIDARG);
        assert_eq!(OpcModuleRegister(table.as_ptr(), MAX_CLASSES + 1, reg), E_INVALIDARG);
        OpcRegistryRelease(reg);
    }
}
