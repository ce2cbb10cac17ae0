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

/// The tests of this module one at a time: one of them sets the host's process count, through which
/// every class object's CreateInstance and LockServer go.
fn serial() -> std::sync::MutexGuard<'static, ()> {
    static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());
    SERIAL.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
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
    let _serial = serial();
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
    let _serial = serial();
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
    let _serial = serial();
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
    let _serial = serial();
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
    let _serial = serial();
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

/// LockServer(FALSE) gives back only what LockServer(TRUE) took, and OpcServerUnlock only what
/// OpcServerLock took: an unmatched one (from any client, through the wire form too) never takes the
/// count that another lock or an object holds, so the server is neither unloaded nor ended under it.
#[test]
fn an_unmatched_unlock_takes_no_count_it_did_not_give() {
    let _serial = serial();
    let s = server(Behaviour::Make);
    let c = class(&CLSID_A, &s, 0);
    let f = factory(&c);
    let before = SERVER_LOCKS.load(Ordering::SeqCst);
    // SAFETY: a live class object.
    unsafe {
        // A DLL server: the server's own object holds the server; a LockServer(FALSE) without a TRUE
        // gives back nothing (S_FALSE), and the DLL stays loaded.
        OpcServerLock();
        assert_eq!(IClassFactory::LockServer(f, 0), S_FALSE);
        assert_eq!(IClassFactory::LockServer(f, 0), S_FALSE);
        assert_eq!(SERVER_LOCKS.load(Ordering::SeqCst), before + 1);
        assert_eq!(OpcModuleCanUnloadNow(), S_FALSE);
        // A LockServer lock: one OpcServerUnlock too many does not take it.
        assert_eq!(IClassFactory::LockServer(f, 1), S_OK);
        OpcServerUnlock();
        OpcServerUnlock();
        assert_eq!(
            SERVER_LOCKS.load(Ordering::SeqCst),
            before + 1,
            "the LockServer lock is held"
        );
        assert_eq!(IClassFactory::LockServer(f, 0), S_OK);
        assert_eq!(SERVER_LOCKS.load(Ordering::SeqCst), before);

        // An EXE host: an object of the library holds the host's count (its module lock); neither
        // an unmatched LockServer(FALSE) nor an unmatched OpcServerUnlock lets the host end.
        HOST_COUNT.reset();
        set_process_count(Some(ProcessCount {
            enter: host_enter,
            lock: host_lock,
            unlock: host_unlock,
        }));
        crate::server::server_lock(); // what the module lock does for a new object
        assert_eq!(IClassFactory::LockServer(f, 0), S_FALSE);
        OpcServerUnlock();
        assert_eq!(HOST_COUNT.held(), 1, "the object's count is held");
        assert!(!HOST_COUNT.close_if_idle(), "the host does not end under the object");
        // Matched pairs still count and give back.
        assert_eq!(IClassFactory::LockServer(f, 1), S_OK);
        OpcServerLock();
        assert_eq!(HOST_COUNT.held(), 3);
        assert_eq!(IClassFactory::LockServer(f, 0), S_OK);
        OpcServerUnlock();
        assert_eq!(IClassFactory::LockServer(f, 0), S_FALSE);
        assert_eq!(HOST_COUNT.held(), 1);
        crate::server::server_unlock(); // the object is freed
        assert_eq!(HOST_COUNT.held(), 0);
        assert!(HOST_COUNT.close_if_idle());
        set_process_count(None);
        IClassFactory::Release(f);
    }
}

fn w(s: &str) -> Vec<u16> {
    s.encode_utf16().chain(Some(0)).collect()
}

#[test]
fn the_module_registers_and_unregisters_every_class_with_a_registration() {
    let _serial = serial();
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

#[test]
fn the_host_count_ends_only_when_nothing_is_held_and_then_refuses_new_work() {
    let count = exe::HostCount::new();
    assert!(count.enter());
    count.lock();
    assert_eq!(count.held(), 2);
    assert!(!count.close_if_idle(), "objects are held");
    assert!(count.enter(), "not ending: still serving");
    assert_eq!(count.unlock(), Some(2));
    assert_eq!(count.unlock(), Some(1));
    assert_eq!(count.unlock(), Some(0));
    assert_eq!(count.unlock(), None, "an unlock too many is ignored");
    assert_eq!(count.held(), 0);
    assert!(count.close_if_idle());
    assert!(!count.enter(), "ending: no new instance, no LockServer");
    assert_eq!(count.held(), 0);
    count.lock(); // an object of a live object still counts
    assert_eq!(count.unlock(), Some(0));

    // A stop ends at once, with objects held; they still give back their counts.
    count.reset();
    assert!(count.enter());
    count.close();
    assert!(!count.enter());
    assert_eq!(count.held(), 1);
    assert!(!count.close_if_idle());
    assert_eq!(count.unlock(), Some(0));
    assert_eq!(count.held(), 0);
}

/// While clients come and go on other threads, the host's decision to end is atomic with the count:
/// once it ended, no client gets a count; a client that got one kept the host from ending.
#[test]
fn ending_races_no_client() {
    let rounds = if cfg!(miri) { 20 } else { 2000 };
    for _ in 0..rounds / 20 {
        let count = std::sync::Arc::new(exe::HostCount::new());
        let entered_after_end = std::sync::Arc::new(AtomicU32::new(0));
        let ended = std::sync::Arc::new(core::sync::atomic::AtomicBool::new(false));
        let client = {
            let (count, entered_after_end, ended) = (count.clone(), entered_after_end.clone(), ended.clone());
            std::thread::spawn(move || {
                for _ in 0..20 {
                    if count.enter() {
                        if ended.load(Ordering::SeqCst) {
                            entered_after_end.fetch_add(1, Ordering::SeqCst);
                        }
                        assert!(count.unlock().is_some());
                    }
                }
            })
        };
        loop {
            if count.close_if_idle() {
                ended.store(true, Ordering::SeqCst);
                break;
            }
            std::thread::yield_now();
        }
        client.join().unwrap();
        assert_eq!(entered_after_end.load(Ordering::SeqCst), 0);
        assert_eq!(count.held(), 0);
        assert!(!count.enter());
    }
}

static HOST_COUNT: exe::HostCount = exe::HostCount::new();
/// What HOST_COUNT held while the server's function ran.
static HELD_WHILE_MAKING: AtomicU32 = AtomicU32::new(u32::MAX);

fn host_enter() -> bool {
    HOST_COUNT.enter()
}
fn host_lock() {
    HOST_COUNT.lock()
}
fn host_unlock() {
    let _ = HOST_COUNT.unlock();
}

unsafe extern "C" fn create_seeing_count(
    context: *mut c_void,
    outer: *mut IUnknown,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> HRESULT {
    HELD_WHILE_MAKING.store(HOST_COUNT.held(), Ordering::SeqCst);
    // SAFETY: forwarded as the library passed them.
    unsafe { create(context, outer, riid, ppv) }
}

/// In an EXE host that is ending, a class object makes nothing and takes no LockServer: the client
/// gets CO_E_SERVER_STOPPING (and COM a new server process), never an object of a process about to
/// exit. While serving, the count is held while the server's function makes the object.
#[test]
fn an_ending_host_refuses_instances_and_lock_server() {
    let _serial = serial();
    let s = server(Behaviour::Make);
    let mut c = class(&CLSID_A, &s, 0);
    c.create = Some(create_seeing_count);
    let f = factory(&c);
    let iid_common = crate::com::iids::IID_IOPCCommon;
    HOST_COUNT.reset();
    set_process_count(Some(ProcessCount {
        enter: host_enter,
        lock: host_lock,
        unlock: host_unlock,
    }));
    // SAFETY: `f` is a live class object; every pointer passed is valid.
    unsafe {
        let mut p: *mut c_void = ptr::null_mut();
        assert_eq!(
            IClassFactory::CreateInstance(f, ptr::null_mut(), &iid_common, &mut p),
            S_OK
        );
        assert_eq!(HELD_WHILE_MAKING.load(Ordering::SeqCst), 1, "counted while made");
        assert_eq!(
            HOST_COUNT.held(),
            0,
            "and given back after (the object counts for itself)"
        );
        assert_eq!(release(p.cast()), 0);
        assert_eq!(IClassFactory::LockServer(f, 1), S_OK);
        assert_eq!(HOST_COUNT.held(), 1);
        assert_eq!(IClassFactory::LockServer(f, 0), S_OK);

        assert!(HOST_COUNT.close_if_idle());
        p = ptr::NonNull::<u64>::dangling().as_ptr().cast();
        assert_eq!(
            IClassFactory::CreateInstance(f, ptr::null_mut(), &iid_common, &mut p),
            CO_E_SERVER_STOPPING
        );
        assert!(p.is_null());
        assert_eq!(s.calls.load(Ordering::SeqCst), 1, "the server's function is not called");
        assert_eq!(IClassFactory::LockServer(f, 1), CO_E_SERVER_STOPPING);
        assert_eq!(HOST_COUNT.held(), 0);
        // The server list's class object answers the same.
        let mut list: *mut c_void = ptr::null_mut();
        assert_eq!(
            crate::module::OpcDllGetClassObject(&crate::com::iids::CLSID_OPCServerList, &IID_ICLASSFACTORY, &mut list)
                .get(),
            S_OK
        );
        assert_eq!(IClassFactory::LockServer(list.cast(), 1), CO_E_SERVER_STOPPING);
        IClassFactory::Release(list.cast());
        set_process_count(None);
        IClassFactory::Release(f);
    }
}

#[test]
fn update_u32_changes_the_value_only_when_the_function_allows_it() {
    use std::sync::atomic::{AtomicU32, Ordering::SeqCst};
    let n = AtomicU32::new(u32::MAX - 1);
    assert_eq!(
        super::update_u32(&n, SeqCst, SeqCst, |v| v.checked_add(1)),
        Ok(u32::MAX - 1)
    );
    assert_eq!(
        super::update_u32(&n, SeqCst, SeqCst, |v| v.checked_add(1)),
        Err(u32::MAX)
    );
    assert_eq!(n.load(SeqCst), u32::MAX);
    // Under contention every change is counted once.
    let rounds = if cfg!(miri) { 50 } else { 10_000 };
    let counter = AtomicU32::new(0);
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                for _ in 0..rounds {
                    super::update_u32(&counter, SeqCst, SeqCst, |v| v.checked_add(1)).unwrap();
                }
            });
        }
    });
    assert_eq!(counter.load(SeqCst), 4 * rounds);
}
