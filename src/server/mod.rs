//! The COM plumbing of an OPC server's own classes: the class object (IClassFactory) of each class, the
//! count that keeps a server loaded or running while anything it handed out is referenced, the DLL
//! entry points over a table of classes (this module) and, on Windows, the EXE host (`exe`).
//!
//! A server describes each class with an [`OpcServerClass`]: its CLSID, the function that makes an
//! instance, whether it may be aggregated, and optionally the registration `/RegServer` and
//! DllRegisterServer write for it. Everything else is the library's:
//!
//! - **Class objects** ([`OpcClassFactoryCreate`]): CreateInstance checks the arguments, refuses an
//!   outer object unless the class allows aggregation (and then wants IID_IUnknown, as COM does),
//!   calls the server's function and makes sure `*ppv` is NULL on every failure; LockServer counts.
//! - **The server count** ([`OpcServerLock`], [`OpcServerUnlock`]): what keeps the server: LockServer
//!   locks, the server's own objects (each locks when made and unlocks when freed), and every object
//!   of the library (in an EXE host through the module lock). An object that aggregates one of the
//!   library's objects (an IOPCCommon session, the shutdown connection point) is counted through it.
//! - **A DLL server** forwards its four `Dll*` exports to [`OpcModuleGetClassObject`],
//!   [`OpcModuleCanUnloadNow`], [`OpcModuleRegister`] and [`OpcModuleUnregister`].

pub mod exe;

use core::ffi::c_void;
use core::ptr;
use core::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;

use crate::com::ffi::{self, Fail, FfiResult, Hr};
use crate::com::iids::{IID_ICLASSFACTORY, IID_IUNKNOWN};
use crate::com::interfaces::{IClassFactoryImpl, IClassFactoryVtbl};
use crate::com::object::{live_objects, ComClass, ComObject, Delegating, Slot};
use crate::com::options::{read_sized, SizedStruct};
use crate::com::{
    IUnknown, BOOL, CLASS_E_CLASSNOTAVAILABLE, CLASS_E_NOAGGREGATION, CLSID, E_INVALIDARG, E_UNEXPECTED, GUID, HRESULT,
    IID, REFCLSID, REFIID, S_FALSE, S_OK,
};
use crate::registry::register::{register, unregister, OpcServerRegistration, ServerDescription};
use crate::registry::{registries, OpcRegistry, Registries};

/// Makes an instance of a server's class for IClassFactory::CreateInstance. The library has already
/// checked `riid` and `ppv` and set `*ppv` to NULL. May be called from any thread.
///
/// # Parameters
/// - `context`: OpcServerClass::context.
/// - `outer`: the controlling IUnknown to aggregate the object into, or NULL (only for a class with
///   OPC_CLASS_AGGREGATABLE; `riid` is then IID_IUnknown and the result the inner, non-delegating
///   IUnknown).
/// - `riid`: the interface the client asks for.
/// - `ppv` (out): where to store the object's interface `riid`; left NULL on failure.
///
/// # Returns
/// S_OK, or a failure with `*ppv` NULL (E_NOINTERFACE, E_OUTOFMEMORY...).
pub type OpcCreateInstanceFn = Option<
    unsafe extern "C" fn(context: *mut c_void, outer: *mut IUnknown, riid: REFIID, ppv: *mut *mut c_void) -> HRESULT,
>;

/// `OpcServerClass::flags`: instances may be aggregated (CreateInstance with an outer object).
pub const OPC_CLASS_AGGREGATABLE: u32 = 1;

/// One class of a server: what its class object makes, and what registration writes for it.
/// Zero-initialise it, set `struct_size` to `sizeof(OpcServerClass)`, then set what you need; the
/// library reads only the first `struct_size` bytes. Keep it (and everything it points at) alive
/// while the class objects made from it may be used: a static table is usual.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct OpcServerClass {
    /// `sizeof(OpcServerClass)` as the caller's header declares it.
    pub struct_size: u32,
    /// The class identifier (required).
    pub clsid: *const CLSID,
    /// Makes an instance (required).
    pub create: OpcCreateInstanceFn,
    /// Passed to `create`.
    pub context: *mut c_void,
    /// OPC_CLASS_AGGREGATABLE or 0.
    pub flags: u32,
    /// What `/RegServer` (OpcExeServerRun) and OpcModuleRegister write for the class, NULL for a
    /// class that is not registered by them. Its `clsid` must be this class's.
    pub registration: *const OpcServerRegistration,
}

// SAFETY: repr(C), struct_size first; integers, raw pointers and an optional function pointer.
unsafe impl SizedStruct for OpcServerClass {
    /// The first version: one size. Fields added later make more.
    const SIZES: &'static [usize] = &[core::mem::size_of::<OpcServerClass>()];
}

/// The most classes one table may hold.
pub(crate) const MAX_CLASSES: u32 = 256;

/// A class as the library keeps it.
#[derive(Clone, Copy)]
pub(crate) struct ServerClass {
    pub(crate) clsid: GUID,
    create: unsafe extern "C" fn(*mut c_void, *mut IUnknown, REFIID, *mut *mut c_void) -> HRESULT,
    context: *mut c_void,
    aggregatable: bool,
    pub(crate) registration: *const OpcServerRegistration,
}

// SAFETY: OpcServerClass's contract: `create` may be called with `context` from any thread, and the
// registration stays valid and unchanged while the class is in use.
unsafe impl Send for ServerClass {}
// SAFETY: as above; a ServerClass is never modified.
unsafe impl Sync for ServerClass {}

impl ServerClass {
    /// Reads one class, honouring `struct_size`.
    ///
    /// # Safety
    /// `class` must be non-NULL and valid as documented on OpcServerClass.
    pub(crate) unsafe fn read(class: *const OpcServerClass) -> Result<ServerClass, HRESULT> {
        let defaults = OpcServerClass {
            struct_size: 0,
            clsid: ptr::null(),
            create: None,
            context: ptr::null_mut(),
            flags: 0,
            registration: ptr::null(),
        };
        // SAFETY: OpcServerClass is repr(C), starts with struct_size and holds integers, raw pointers
        // and an optional function pointer; the caller vouches for `class`.
        let c = unsafe { read_sized(class, defaults) }?;
        // SAFETY: the caller vouches a non-NULL `clsid` is readable.
        let clsid = unsafe { c.clsid.as_ref() }.copied().ok_or(E_INVALIDARG)?;
        let create = c.create.ok_or(E_INVALIDARG)?;
        if c.flags & !OPC_CLASS_AGGREGATABLE != 0 {
            return Err(E_INVALIDARG);
        }
        Ok(ServerClass {
            clsid,
            create,
            context: c.context,
            aggregatable: c.flags & OPC_CLASS_AGGREGATABLE != 0,
            registration: c.registration,
        })
    }

    /// Reads a table of `count` classes.
    ///
    /// # Safety
    /// `classes` must point at `count` classes valid as documented on OpcServerClass.
    pub(crate) unsafe fn read_table(classes: *const OpcServerClass, count: u32) -> Result<Vec<ServerClass>, Fail> {
        if classes.is_null() {
            return Err(Fail::Null);
        }
        if count == 0 || count > MAX_CLASSES {
            return Err(Fail::Code(E_INVALIDARG));
        }
        (0..count as usize)
            .map(|i| {
                // The entries are read one by one, each by its own `struct_size`: the table's stride is
                // the caller's `sizeof(OpcServerClass)`, which the first entry states.
                // SAFETY: the caller vouches for `count` readable entries; `stride` is read from the
                // first, which is readable.
                let stride = unsafe { (*classes).struct_size } as usize;
                // SAFETY: as above.
                unsafe { ServerClass::read(classes.cast::<u8>().add(i * stride).cast()) }.map_err(Fail::Code)
            })
            .collect()
    }
}

/// The server count outside an EXE host: LockServer locks and the server's own objects
/// (OpcServerLock). In an EXE host it is kept by COM instead (see `exe`), and this counts nothing.
static SERVER_LOCKS: AtomicU32 = AtomicU32::new(0);

/// The locks one kind of caller took on the server count, so that it gives back only what it took.
/// The server count is shared by every kind (objects of the library, LockServer, OpcServerLock); an
/// unlock without its lock (a LockServer(FALSE) from any client, through the wire form too) must not
/// take a count that an object holds, or the server would end or unload under that object.
/// Replaces the value of `atomic` with `f(value)` unless `f` says `None`: the value before on
/// success, the value seen on refusal. What `AtomicU32::fetch_update` does; written out because
/// newer toolchains deprecate that name for one older toolchains lack, and the library builds with
/// both (the Windows 7 targets use a pinned nightly).
pub(crate) fn update_u32(
    atomic: &AtomicU32,
    set_order: Ordering,
    fetch_order: Ordering,
    mut f: impl FnMut(u32) -> Option<u32>,
) -> Result<u32, u32> {
    let mut seen = atomic.load(fetch_order);
    while let Some(next) = f(seen) {
        match atomic.compare_exchange_weak(seen, next, set_order, fetch_order) {
            Ok(before) => return Ok(before),
            Err(now) => seen = now,
        }
    }
    Err(seen)
}

pub(crate) struct Taken(AtomicU32);

impl Taken {
    pub(crate) const fn new() -> Taken {
        Taken(AtomicU32::new(0))
    }

    /// Records one lock taken; false (nothing recorded) when the count is saturated.
    fn take(&self) -> bool {
        update_u32(&self.0, Ordering::AcqRel, Ordering::Acquire, |n| n.checked_add(1)).is_ok()
    }

    /// Gives back one recorded lock: false when none is left to give back (an unlock too many).
    fn give_back(&self) -> bool {
        update_u32(&self.0, Ordering::AcqRel, Ordering::Acquire, |n| n.checked_sub(1)).is_ok()
    }

    /// Forgets every lock (the count they were taken on is gone: a host starts or ends).
    pub(crate) fn forget(&self) {
        self.0.store(0, Ordering::Release);
    }
}

/// The locks LockServer(TRUE) took and LockServer(FALSE) has not given back.
pub(crate) static LOCK_SERVER_LOCKS: Taken = Taken::new();
/// The locks OpcServerLock took and OpcServerUnlock has not given back.
pub(crate) static OWN_LOCKS: Taken = Taken::new();

/// What the server count calls in an EXE host: COM's server process count (CoAddRefServerProcess),
/// so that COM stops handing out the class objects at once when it falls to zero.
#[derive(Clone, Copy)]
#[cfg_attr(not(windows), allow(dead_code))]
pub(crate) struct ProcessCount {
    /// A count for something new a client asked for (an instance, LockServer): false when the host
    /// is ending and takes no more.
    pub(crate) enter: fn() -> bool,
    /// A count that cannot be refused (an object made by an object still alive).
    pub(crate) lock: fn(),
    pub(crate) unlock: fn(),
}

static PROCESS_COUNT: Mutex<Option<ProcessCount>> = Mutex::new(None);

/// Sets (an EXE host starts) or clears (it ends) the count the server count calls. The LockServer
/// and OpcServerLock locks recorded so far were taken on the other count and are forgotten.
#[cfg_attr(not(windows), allow(dead_code))]
pub(crate) fn set_process_count(count: Option<ProcessCount>) {
    let mut current = PROCESS_COUNT.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    *current = count;
    LOCK_SERVER_LOCKS.forget();
    OWN_LOCKS.forget();
}

fn process_count() -> Option<ProcessCount> {
    *PROCESS_COUNT.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// One count on the server (the module lock of an EXE host: an object of the library was made).
pub(crate) fn server_lock() {
    match process_count() {
        Some(count) => (count.lock)(),
        None => {
            // Saturates rather than wraps: a server that never unlocks stays loaded.
            let _ = update_u32(&SERVER_LOCKS, Ordering::AcqRel, Ordering::Acquire, |n| n.checked_add(1));
        }
    }
}

/// A count for something new a client asked for: an instance (held while the server's function makes
/// it) or a LockServer. False, with nothing counted, when an EXE host is ending (its last client left,
/// or it was stopped) and takes no more: the caller answers CO_E_SERVER_STOPPING, and COM activates a
/// new server process.
pub(crate) fn server_enter() -> bool {
    match process_count() {
        Some(count) => (count.enter)(),
        None => {
            server_lock();
            true
        }
    }
}

/// Gives back one count of `server_lock` or `server_enter`.
pub(crate) fn server_unlock() {
    match process_count() {
        Some(count) => (count.unlock)(),
        None => {
            // An unlock without a lock is ignored rather than wrapping around.
            let _ = update_u32(&SERVER_LOCKS, Ordering::AcqRel, Ordering::Acquire, |n| n.checked_sub(1));
        }
    }
}

/// Whether nothing of the library's code is in use: no server count (OpcServerLock, LockServer), no
/// object of the library alive, no proxy or stub in use, no worker of `OpcShutdownNotifyBounded`
/// calling a sink. What opccomn.dll's DllCanUnloadNow and a server DLL's OpcModuleCanUnloadNow answer
/// (a DLL linking the library statically runs that code too).
pub(crate) fn can_unload() -> bool {
    SERVER_LOCKS.load(Ordering::Acquire) == 0
        && live_objects() == 0
        && crate::proxy::can_unload()
        && crate::shutdown::bounded::workers_running() == 0
}

/// The object server is ending: an EXE host whose last client left, or that was stopped, takes no
/// more (COM then starts a new server process for the client).
const CO_E_SERVER_STOPPING: HRESULT = 0x80080008_u32 as HRESULT;

/// IClassFactory::LockServer of every class object of the library: TRUE takes a server count (refused
/// with CO_E_SERVER_STOPPING by an EXE host that is ending), FALSE gives back one that a TRUE took. A
/// FALSE without a TRUE still held (from any client) gives back nothing and answers S_FALSE: it never
/// takes the count of an object a client holds.
pub(crate) fn lock_server(lock: BOOL) -> FfiResult {
    if lock == 0 {
        if !LOCK_SERVER_LOCKS.give_back() {
            return Ok(S_FALSE);
        }
        server_unlock();
    } else {
        if !server_enter() {
            return Err(CO_E_SERVER_STOPPING.into());
        }
        if !LOCK_SERVER_LOCKS.take() {
            // Saturated: the lock could never be given back; keep the count balanced instead.
            server_unlock();
        }
    }
    Ok(S_OK)
}

/// A count taken by `server_enter`, given back when dropped.
struct Entered;

impl Drop for Entered {
    fn drop(&mut self) {
        server_unlock();
    }
}

/// The class object of one class.
struct ClassObject {
    slot: Slot,
    class: ServerClass,
}

impl ComClass for ClassObject {
    fn interface(&self, iid: &GUID) -> Option<&Slot> {
        (*iid == IID_ICLASSFACTORY).then_some(&self.slot)
    }
}

static CLASS_OBJECT_VTBL: IClassFactoryVtbl = IClassFactoryVtbl::new::<Delegating, ClassObject>();

impl IClassFactoryImpl for ClassObject {
    fn CreateInstance(
        this: &ComObject<Self>,
        outer: Option<ffi::Iface<'_, IUnknown>>,
        riid: &IID,
        ppv: ffi::Out<'_, *mut c_void>,
    ) -> FfiResult {
        if outer.is_some() && (!this.class.aggregatable || *riid != IID_IUNKNOWN) {
            return Err(CLASS_E_NOAGGREGATION.into());
        }
        if !server_enter() {
            return Err(CO_E_SERVER_STOPPING.into());
        }
        // The count is held while the object is made (the object takes its own), so that an EXE host
        // cannot end meanwhile.
        let _entered = Entered;
        let class = this.class;
        let outer = outer.map_or(ptr::null_mut(), ffi::Iface::as_ptr);
        // SAFETY: the server's function, with its context, the caller's outer object and checked
        // `riid` and `ppv` (already NULL), as OpcCreateInstanceFn documents.
        let hr = unsafe { (class.create)(class.context, outer, riid, ppv.as_ptr()) };
        if hr < 0 {
            // A pointer left behind with a failure is neither used nor released (it may be garbage);
            // the boundary resets the out-parameter.
            return Err(hr.into());
        }
        // SAFETY: `ppv` is the caller's writable out-parameter, which the boundary set to NULL before
        // the call; read back what the server's function left there.
        if unsafe { *ppv.as_ptr() }.is_null() {
            // Success without an object: the server's function is broken.
            return Err(E_UNEXPECTED.into());
        }
        Ok(hr)
    }

    fn LockServer(_this: &ComObject<Self>, lock: BOOL) -> FfiResult {
        lock_server(lock)
    }
}

/// A new class object for `class`, as `riid` (IID_IClassFactory or IID_IUnknown).
///
/// # Safety
/// `riid` NULL or readable, `ppv` NULL or writable.
pub(crate) unsafe fn class_object(class: ServerClass, riid: REFIID, ppv: *mut *mut c_void) -> HRESULT {
    // A class object does not count on the server: COM holds the EXE's for as long as they are
    // registered, and a client that keeps one uses LockServer (COM's rule).
    // SAFETY: forwarded from the caller.
    unsafe {
        ComObject::<ClassObject>::create_class_object(riid, ppv, |binder| {
            Ok(ClassObject {
                slot: binder.slot(&CLASS_OBJECT_VTBL),
                class,
            })
        })
    }
}

/// Creates the class object (IClassFactory) of one of the server's classes: CreateInstance calls
/// `class->create` (checking the arguments first, refusing an outer object with CLASS_E_NOAGGREGATION
/// unless the class is OPC_CLASS_AGGREGATABLE and `riid` is IID_IUnknown, and making sure `*ppv` is
/// NULL on every failure: a function that reports success without an object gets E_UNEXPECTED);
/// LockServer(TRUE/FALSE) is OpcServerLock/OpcServerUnlock. The class object itself does not count
/// on the server. For CoRegisterClassObject in an EXE that does not use OpcExeServerRun, or a
/// DllGetClassObject of its own.
///
/// # Parameters
/// - `cls`: the class (OpcServerClass).
/// - `riid`: the interface wanted: IID_IClassFactory or IID_IUnknown.
/// - `ppv` (out): receives the class object, or NULL on failure.
///
/// # Returns
/// S_OK; E_POINTER for a NULL `cls`, `riid` or `ppv`; E_INVALIDARG for a wrong `struct_size`, a NULL
/// `clsid` or `create`, or unknown `flags`; E_NOINTERFACE unless `riid` is IID_IClassFactory or
/// IID_IUnknown.
///
/// # Safety
/// `cls` NULL or valid as documented on OpcServerClass (and kept so while the class object lives);
/// `riid` NULL or readable; `ppv` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcClassFactoryCreate(cls: *const OpcServerClass, riid: REFIID, ppv: *mut *mut c_void) -> Hr {
    ffi::boundary!(Com, [ppv], {
        // SAFETY: the caller's contract.
        let (out, riid, cls) = unsafe { (ffi::out(ppv)?, ffi::in_ref(riid)?, ffi::in_ref(cls)?) };
        // SAFETY: as above.
        let class = unsafe { ServerClass::read(cls) }?;
        // SAFETY: `riid` readable, `out` writable.
        Ok(unsafe { class_object(class, riid, out.as_ptr()) })
    })
}

/// Counts one more reference to the server: call it when an object of the server's own is made (and
/// OpcServerUnlock when it is freed), so that a DLL server is not unloaded and an EXE server does not
/// exit while a client holds it. LockServer and the library's objects are counted without it, and so
/// is an object that aggregates one of the library's objects (IOPCCommon, the shutdown connection
/// point) for as long as it holds it. Under OpcExeServerRun this is COM's server process count
/// (CoAddRefServerProcess); elsewhere a count OpcModuleCanUnloadNow reads. Any thread.
#[no_mangle]
pub extern "C" fn OpcServerLock() {
    ffi::guard!((), {
        if OWN_LOCKS.take() {
            server_lock();
        }
    })
}

/// Takes back one OpcServerLock. Under OpcExeServerRun the last count on the server ends it once it
/// has had a client (COM stops handing out its class objects at once). An unlock without an
/// OpcServerLock still held is ignored: it never takes the count of a LockServer lock or of an object
/// of the library. Any thread.
#[no_mangle]
pub extern "C" fn OpcServerUnlock() {
    ffi::guard!((), {
        if OWN_LOCKS.give_back() {
            server_unlock();
        }
    })
}

/// DllGetClassObject for a DLL server: the class object of one class of a table, as
/// OpcClassFactoryCreate makes it.
///
/// # Parameters
/// - `classes`: the server's classes (OpcServerClass).
/// - `count`: how many `classes` holds (1 to 256).
/// - `rclsid`: the class COM asks for.
/// - `riid`: the interface wanted: IID_IClassFactory or IID_IUnknown.
/// - `ppv` (out): receives the class object, or NULL on failure.
///
/// # Returns
/// S_OK; E_POINTER for a NULL `classes`, `rclsid`, `riid` or `ppv`; E_INVALIDARG for a count of 0 or
/// over 256, or a class OpcClassFactoryCreate refuses; CLASS_E_CLASSNOTAVAILABLE for a CLSID not in
/// the table; E_NOINTERFACE unless `riid` is IID_IClassFactory or IID_IUnknown.
///
/// # Safety
/// `classes` NULL or `count` classes valid as documented on OpcServerClass (kept so while the DLL is
/// loaded); `rclsid` and `riid` NULL or readable; `ppv` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcModuleGetClassObject(
    classes: *const OpcServerClass,
    count: u32,
    rclsid: REFCLSID,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> Hr {
    ffi::boundary!(Com, [ppv], {
        // SAFETY: the caller's contract.
        let (out, rclsid, riid) = unsafe { (ffi::out(ppv)?, ffi::in_ref(rclsid)?, ffi::in_ref(riid)?) };
        // SAFETY: as above.
        let table = unsafe { ServerClass::read_table(classes, count) }?;
        let class = table
            .into_iter()
            .find(|c| c.clsid == *rclsid)
            .ok_or(CLASS_E_CLASSNOTAVAILABLE)?;
        // SAFETY: `riid` readable, `out` writable.
        Ok(unsafe { class_object(class, riid, out.as_ptr()) })
    })
}

/// DllCanUnloadNow for a DLL server: whether COM may unload it.
///
/// # Returns
/// S_OK when nothing counts on the server (no OpcServerLock or LockServer lock is held), no object of
/// the library is alive (the server's sessions, connection points and enumerators among them; with
/// opccomn.dll shared between modules, every module's), and no proxy, stub or bounded shutdown
/// notification of the library is at work; else S_FALSE.
#[no_mangle]
pub extern "C" fn OpcModuleCanUnloadNow() -> Hr {
    ffi::guard!(S_FALSE, {
        if can_unload() {
            S_OK
        } else {
            S_FALSE
        }
    })
}

/// Registers every class of a table that has a `registration` (OpcRegisterServer for each, in order):
/// for DllRegisterServer, or `/RegServer`. A DLL that uses opccomn.dll must set `module_path` in its
/// registrations (NULL would be opccomn.dll's path). When one fails, the classes registered before it
/// are unregistered again.
///
/// # Parameters
/// - `classes`: the server's classes (OpcServerClass).
/// - `count`: how many `classes` holds (1 to 256).
/// - `reg`: the registry, or NULL for the system registry.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `classes`, a count of 0 or over 256, a bad class, or a registration
/// whose CLSID is not its class's; the errors of OpcRegisterServer.
///
/// # Safety
/// `classes` NULL or `count` classes valid as documented on OpcServerClass; `reg` NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn OpcModuleRegister(classes: *const OpcServerClass, count: u32, reg: *const OpcRegistry) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller's contract.
        let (descriptions, regs) = unsafe { (registrations(classes, count)?, registries(reg)) };
        register_all(&regs, &descriptions)?;
        Ok(S_OK)
    })
}

/// Unregisters every class of a table that has a `registration` (OpcUnregisterServer for each, in
/// reverse order): for DllUnregisterServer, or `/UnregServer`. Goes on after a class that fails and
/// returns the first failure; a class that is not registered (REGDB_E_KEYMISSING) is no failure.
///
/// # Parameters
/// - `classes`: the server's classes, as given to OpcModuleRegister.
/// - `count`: how many `classes` holds (1 to 256).
/// - `reg`: the registry, or NULL for the system registry.
///
/// # Returns
/// S_OK; the errors of OpcModuleRegister for a bad table; the errors of OpcUnregisterServer.
///
/// # Safety
/// As for OpcModuleRegister.
#[no_mangle]
pub unsafe extern "C" fn OpcModuleUnregister(
    classes: *const OpcServerClass,
    count: u32,
    reg: *const OpcRegistry,
) -> Hr {
    ffi::boundary!(Opc, [], {
        // SAFETY: the caller's contract.
        let (descriptions, regs) = unsafe { (registrations(classes, count)?, registries(reg)) };
        unregister_all(&regs, &descriptions)?;
        Ok(S_OK)
    })
}

/// Registers every description in order; when one fails, unregisters those before it again.
pub(crate) fn register_all(regs: &Registries, descriptions: &[ServerDescription]) -> Result<(), HRESULT> {
    for (i, d) in descriptions.iter().enumerate() {
        if let Err(hr) = register(regs, d) {
            for done in descriptions[..i].iter().rev() {
                let _ = unregister(regs, done);
            }
            return Err(hr);
        }
    }
    Ok(())
}

/// Unregisters every description in reverse order, going on after a failure; the first failure (a
/// description that is not registered is none).
pub(crate) fn unregister_all(regs: &Registries, descriptions: &[ServerDescription]) -> Result<(), HRESULT> {
    let mut first = Ok(());
    for d in descriptions.iter().rev() {
        match unregister(regs, d) {
            Err(hr) if hr != crate::registry::REGDB_E_KEYMISSING && first.is_ok() => first = Err(hr),
            _ => {}
        }
    }
    first
}

/// The registrations of a table's classes, checked.
///
/// # Safety
/// As for OpcModuleRegister.
pub(crate) unsafe fn registrations(classes: *const OpcServerClass, count: u32) -> Result<Vec<ServerDescription>, Fail> {
    // SAFETY: the caller's contract.
    let table = unsafe { ServerClass::read_table(classes, count) }?;
    let mut out = Vec::new();
    for class in table {
        if class.registration.is_null() {
            continue;
        }
        // SAFETY: a non-NULL registration is valid, per OpcServerClass's contract.
        let d = unsafe { ServerDescription::read(class.registration) }?;
        if d.clsid != class.clsid {
            return Err(Fail::Code(E_INVALIDARG));
        }
        out.push(d);
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
