//! Interfaces kept registered with the RPC runtime: table-strong marshals of an object of the
//! library's own, held until dropped (the EXE host's use, and why, in `server/exe/keep.rs`).
//!
//! The object answers QueryInterface for IUnknown and a fixed list of interfaces only, with one table
//! of `KEEPER_METHODS` entries; the methods past IUnknown's refuse (E_UNEXPECTED). Its marshal data
//! never leave the process, so no client can call it: the stubs COM makes for it only hold it.

use core::ffi::c_void;
use core::ptr;

use super::ffi::{self, Crossed, Hr};
use super::iids::IID_IUNKNOWN;
use super::ole32::{
    CoMarshalInterface, CoReleaseMarshalData, CreateStreamOnHGlobal, GlobalAlloc, GlobalFree, GMEM_MOVEABLE,
};
use super::unknown::Counted;
use super::{IUnknown, E_NOINTERFACE, E_UNEXPECTED, GUID, S_OK};

/// `MSHCTX_LOCAL`: marshaled for another process of this machine (what COM's activation does).
const MSHCTX_LOCAL: u32 = 0;
/// `MSHLFLAGS_TABLESTRONG`: the marshal data stay valid, and hold the stub, until released.
const MSHLFLAGS_TABLESTRONG: u32 = 1;

/// Entries in a keeper's table, IUnknown's three included: a kept interface has no more methods.
///
/// cbindgen:ignore
pub const KEEPER_METHODS: usize = 64;

/// The object the marshals are of: a static, answering for IUnknown and `iids`.
#[repr(C)]
pub struct Keeper {
    vtbl: &'static KeeperVtbl,
    iids: &'static [GUID],
}

impl Keeper {
    /// A keeper answering for IUnknown and `iids`.
    pub const fn new(iids: &'static [GUID]) -> Keeper {
        Keeper { vtbl: &VTBL, iids }
    }

    /// The interfaces it answers for besides IUnknown.
    #[cfg(test)]
    pub fn iids(&self) -> &'static [GUID] {
        self.iids
    }

    fn as_ptr(&'static self) -> *mut c_void {
        (self as *const Keeper).cast_mut().cast()
    }
}

#[repr(C)]
struct KeeperVtbl {
    query_interface: unsafe extern "system" fn(*mut c_void, *const GUID, *mut *mut c_void) -> Hr,
    add_ref: unsafe extern "system" fn(*mut c_void) -> Crossed<u32>,
    release: unsafe extern "system" fn(*mut c_void) -> Crossed<u32>,
    rest: [unsafe extern "system" fn(*mut c_void) -> Hr; KEEPER_METHODS - 3],
}

static VTBL: KeeperVtbl = KeeperVtbl {
    query_interface,
    add_ref,
    release,
    rest: [refuse; KEEPER_METHODS - 3],
};

/// # Safety
/// `this` a `Keeper`; `iid` NULL or readable; `out` NULL or writable (the NULLs are refused).
unsafe extern "system" fn query_interface(this: *mut c_void, iid: *const GUID, out: *mut *mut c_void) -> Hr {
    ffi::boundary!(Com, [out], {
        // SAFETY: NULL or writable for the rest of the call, by the caller's contract.
        let out = unsafe { ffi::out(out) }?;
        // SAFETY: NULL or readable, by the caller's contract.
        let iid = unsafe { ffi::in_ref(iid) }?;
        // SAFETY: NULL or a Keeper, by the caller's contract.
        let keeper = unsafe { ffi::in_ref(this.cast_const().cast::<Keeper>()) }?;
        if *iid != IID_IUNKNOWN && !keeper.iids.contains(iid) {
            return Err(E_NOINTERFACE.into());
        }
        out.write(this);
        Ok(S_OK)
    })
}

/// A keeper is static: no count to keep.
unsafe extern "system" fn add_ref(_this: *mut c_void) -> Crossed<u32> {
    ffi::guard!(1, { 1 })
}

/// A keeper is static: no count to keep.
unsafe extern "system" fn release(_this: *mut c_void) -> Crossed<u32> {
    ffi::guard!(1, { 1 })
}

/// Every method past IUnknown's (no client has the marshal data to call one).
unsafe extern "system" fn refuse(_this: *mut c_void) -> Hr {
    ffi::boundary!(Com, [], { Err(E_UNEXPECTED.into()) })
}

/// The marshals of a keeper's interfaces, released when dropped: the memory each was written to.
pub struct Kept(Vec<*mut c_void>);

impl Kept {
    /// Marshals each of `keeper`'s interfaces that can be marshaled here (one without a proxy/stub
    /// cannot be, by anyone: it is skipped). Call with COM initialised.
    pub fn new(keeper: &'static Keeper) -> Kept {
        Kept(keeper.iids.iter().filter_map(|iid| marshal(keeper, iid)).collect())
    }

    /// How many interfaces are kept.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.0.len()
    }
}

/// Marshals `keeper`'s `iid` table-strong into new memory: that memory, or `None` when the interface
/// cannot be marshaled here (the memory then freed).
fn marshal(keeper: &'static Keeper, iid: &GUID) -> Option<*mut c_void> {
    // The memory is ours from the start, so that each failure below can free it. (Movable, as
    // CreateStreamOnHGlobal requires; the stream grows it as it writes.)
    // SAFETY: no pointer arguments.
    let memory = unsafe { GlobalAlloc(GMEM_MOVEABLE, 64) };
    if memory.is_null() {
        return None;
    }
    let mut stream: *mut c_void = ptr::null_mut();
    // SAFETY: movable memory of ours, which the stream does not free when it goes (FALSE).
    let created = unsafe { CreateStreamOnHGlobal(memory, 0, &mut stream) } >= 0;
    let stream = if created {
        // SAFETY: the reference CreateStreamOnHGlobal gave us, released when `stream` drops.
        unsafe { Counted::adopt(stream.cast::<IUnknown>()) }
    } else {
        None
    };
    let Some(stream) = stream else {
        free(memory, false);
        return None;
    };
    // SAFETY: a valid stream and IID; a static object answering for `iid`, whose table COM only calls
    // through IUnknown's methods here.
    let hr = unsafe {
        CoMarshalInterface(
            stream.as_ptr().cast(),
            iid,
            keeper.as_ptr(),
            MSHCTX_LOCAL,
            ptr::null_mut(),
            MSHLFLAGS_TABLESTRONG,
        )
    };
    drop(stream);
    if hr < 0 {
        free(memory, false);
        return None;
    }
    Some(memory)
}

/// Frees memory `marshal` allocated, releasing the marshal data at its start first when `marshaled`.
fn free(memory: *mut c_void, marshaled: bool) {
    if marshaled {
        let mut stream: *mut c_void = ptr::null_mut();
        // SAFETY: memory from `marshal`, handed to a new stream that reads it from the start and frees
        // it when it goes (TRUE).
        if unsafe { CreateStreamOnHGlobal(memory, 1, &mut stream) } >= 0 {
            // SAFETY: the reference CreateStreamOnHGlobal gave us, released (and the memory with it)
            // at the end.
            if let Some(stream) = unsafe { Counted::adopt(stream.cast::<IUnknown>()) } {
                // SAFETY: a stream positioned at the marshal data `marshal` wrote.
                unsafe { CoReleaseMarshalData(stream.as_ptr().cast()) };
                return;
            }
        }
        // (Without a stream the marshal data cannot be released: the memory at least is freed.)
    }
    // SAFETY: global memory from `marshal`, which nothing else owns.
    unsafe { GlobalFree(memory) };
}

impl Drop for Kept {
    fn drop(&mut self) {
        for memory in self.0.drain(..) {
            free(memory, true);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::com::guids::{IID_IConnectionPoint, IID_IEnumGUID};
    use crate::com::E_POINTER;
    use windows_sys::Win32::System::Com::{CoInitializeEx, CoUninitialize, COINIT_MULTITHREADED};

    /// Two system interfaces (the system's proxy/stubs) and one nobody has a proxy/stub for.
    static IIDS: [GUID; 3] = [
        IID_IConnectionPoint,
        IID_IEnumGUID,
        GUID::from_u128(0x0BADF00D_0000_4000_8000_000000000001),
    ];
    static KEEPER: Keeper = Keeper::new(&IIDS);

    #[test]
    fn a_keeper_answers_for_its_interfaces_only() {
        let this = KEEPER.as_ptr();
        let mut out: *mut c_void;
        for iid in IIDS.iter().chain([&IID_IUNKNOWN]) {
            out = ptr::null_mut();
            // SAFETY: a keeper and valid pointers.
            assert_eq!(unsafe { query_interface(this, iid, &mut out) }, S_OK);
            assert_eq!(out, this);
        }
        // Not IMarshal, IExternalConnection nor IClassFactory: COM marshals it with its standard
        // marshaler and calls nothing else on it.
        for iid in [
            GUID::from_u128(0x00000003_0000_0000_C000_000000000046),
            GUID::from_u128(0x00000019_0000_0000_C000_000000000046),
            crate::com::iids::IID_ICLASSFACTORY,
        ] {
            out = this;
            // SAFETY: a keeper and valid pointers.
            assert_eq!(unsafe { query_interface(this, &iid, &mut out) }, E_NOINTERFACE);
            assert!(out.is_null());
        }
        out = this;
        // SAFETY: a NULL IID is refused.
        assert_eq!(unsafe { query_interface(this, ptr::null(), &mut out) }, E_POINTER);
        assert!(out.is_null());
        assert_eq!(
            // SAFETY: a NULL out-pointer is refused.
            unsafe { query_interface(this, &IID_IUNKNOWN, ptr::null_mut()) },
            E_POINTER
        );
        // SAFETY: a keeper.
        assert_eq!(unsafe { (add_ref(this).get(), release(this).get()) }, (1, 1));
        // SAFETY: as above.
        assert_eq!(unsafe { refuse(this) }, E_UNEXPECTED);
    }

    #[test]
    fn the_interfaces_with_a_proxy_stub_are_kept_until_dropped() {
        // SAFETY: this test thread joins the multithreaded apartment, left at the end.
        assert!(unsafe { CoInitializeEx(ptr::null(), COINIT_MULTITHREADED as u32) } >= 0);
        let kept = Kept::new(&KEEPER);
        // The two system interfaces, not the one without a proxy/stub.
        assert_eq!(kept.len(), 2);
        drop(kept);
        // Released: kept again (a second host run in the same process).
        let again = Kept::new(&KEEPER);
        assert_eq!(again.len(), 2);
        drop(again);
        // SAFETY: balances CoInitializeEx above.
        unsafe { CoUninitialize() };
    }

    #[test]
    fn a_thread_without_com_keeps_what_its_process_lets_it() {
        // Kept::new's precondition broken: a thread that never initialised COM. Its marshals fail
        // (CO_E_NOTINITIALIZED: nothing kept) unless another thread of the process holds the
        // multithreaded apartment, which this thread then implicitly belongs to (other tests of this
        // process may); either way it returns, and what it kept is released when dropped.
        let kept = std::thread::spawn(|| {
            let kept = Kept::new(&KEEPER);
            let n = kept.len();
            drop(kept);
            n
        })
        .join()
        .expect("Kept::new without COM returns");
        assert!(kept == 0 || kept == 2, "{kept} kept");
    }
}
