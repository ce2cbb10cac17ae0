//! The COM object framework every interface of the library is built on.
//!
//! A `ComObject<T>` is one heap block laid out as
//!
//! ```text
//! ComHeader { inner: Slot (the non-delegating IUnknown), refs, outer, class, module_lock } | T
//! ```
//!
//! `class` points at the [`Class`] of `T`, a constant in static memory (`ComObject::<T>::CLASS`):
//! the functions that find a slot of a `T` and free a `T`, and `T`'s type, by which
//! [`ThisSlot::object`] tells the objects of a class from the others. What belongs to the class is
//! kept with the class, not copied into every object.
//!
//! `T` holds one [`Slot`] per interface it implements. A slot is what C sees as the interface pointer:
//! its first word is the vtable pointer, its second points back at the header, so every method shim
//! finds its object without offset arithmetic. The non-delegating IUnknown (`header.inner`) is the
//! object's identity when it stands alone; when it is aggregated, the outer object's IUnknown is.
//!
//! Reference counting follows COM aggregation rules: the IUnknown methods of every interface slot
//! delegate to the controlling unknown (the outer object if there is one, else `header.inner`), and
//! only `header.inner` counts references of this object itself.
//!
//! **Pointers.** The back pointer every slot keeps is the raw pointer of the whole allocation (taken
//! from `Box::into_raw` before anything else refers to the block), so it may reach the class state
//! behind the header and free the block. Everything that goes beyond the header or frees it
//! (the class's `query` and `destroy`, the final Release, [`ComObject::from_interface`], [`ComRef`]) works from that
//! `NonNull`, never by widening a `&ComHeader` or by freeing memory a live reference points into; a
//! `&ComHeader` is only used for the header's own fields. Miri checks this under Stacked and Tree
//! Borrows (`scripts/test.sh`).
//!
//! **Reference counts** are 32 bits, as COM's `ULONG` return values are. A count never wraps: when it
//! reaches [`REFS_SATURATED_FROM`] (2^31, which only a leaking caller gets to) it saturates and the
//! object becomes immortal. From then on AddRef and Release return [`REFS_SATURATED`] and change
//! nothing, and the object is never freed: a leak, where wrapping would free a live object. (The
//! standard library's `Arc` aborts the process instead, which a DLL hosted by an OPC client must not.)

use core::any::TypeId;
use core::ffi::c_void;
use core::marker::PhantomData;
use core::ptr::{self, NonNull};
use core::sync::atomic::{AtomicU32, AtomicUsize, Ordering};
use std::mem::MaybeUninit;

use super::ffi::{self, guard, FfiResult};
use super::hresult::{CLASS_E_NOAGGREGATION, E_NOINTERFACE, E_POINTER, E_UNEXPECTED, S_OK};
use super::iids::IID_IUNKNOWN;
use super::interfaces::{IUnknownImpl, IUnknownVtbl};
use super::module_lock::ModuleLock;
use super::types::{GUID, HRESULT, REFIID, ULONG};
use super::unknown::{add_ref, Counted, IUnknown};

/// Number of library objects alive, for `DllCanUnloadNow` and leak checks.
static LIVE_OBJECTS: AtomicUsize = AtomicUsize::new(0);

/// How many COM objects created by the library are still alive.
pub fn live_objects() -> usize {
    LIVE_OBJECTS.load(Ordering::Acquire)
}

/// Counts at or above this value are saturated (the object is immortal).
pub(crate) const REFS_SATURATED_FROM: u32 = 0x8000_0000;
/// The value a saturated count is kept at, and what AddRef and Release then return. It lies in the
/// middle of the saturated range, so racing AddRef/Release calls can never move it out of that range.
pub(crate) const REFS_SATURATED: u32 = 0xC000_0000;

/// A class implemented in Rust: its state plus the interface slots it hands out.
pub trait ComClass: Sized + Send + Sync + 'static {
    /// The slot for `iid`, or `None` when the object does not implement it. Never asked for
    /// `IID_IUnknown` (the framework answers that); the result is not AddRef'd.
    fn interface(&self, iid: &GUID) -> Option<&Slot>;
}

/// One interface pointer of an object, exactly as C sees it: the vtable pointer comes first.
#[repr(C)]
pub struct Slot {
    vtbl: *const c_void,
    /// The whole object's allocation (see the module documentation), not just its header.
    header: NonNull<ComHeader>,
}

// SAFETY: a slot is immutable after construction; the vtable is static and the header outlives it.
unsafe impl Send for Slot {}
// SAFETY: as above; shared access only reads the two pointers.
unsafe impl Sync for Slot {}

impl Slot {
    /// The interface pointer to hand to C.
    pub fn as_ptr(&self) -> *mut c_void {
        self as *const Slot as *mut c_void
    }

    /// The vtable this slot was created with.
    pub fn vtbl(&self) -> *const c_void {
        self.vtbl
    }

    /// A new counted reference to this interface, as `I`: AddRef through the slot's own IUnknown, so
    /// that it counts where the slot's references count (an aggregated object's on its outer object).
    pub fn counted<I>(&self) -> Counted<I> {
        let p = self.as_ptr();
        // SAFETY: a slot of a live object (`self` is borrowed from it) is a valid interface pointer;
        // the reference added is the one the result owns, and a slot pointer is never NULL.
        unsafe {
            add_ref(p.cast());
            Counted::adopt(p.cast()).expect("slot pointers are never NULL")
        }
    }
}

/// A vtable generated from the IDL (`src/com/interfaces.rs`), whose entries all return
/// [`Crossed<T>`](super::ffi::Crossed): the only kind of vtable a slot presents. Only the generated
/// module implements it (`tools/gen-header` checks).
pub trait Vtable: 'static {}

/// Hands out slots bound to an object under construction.
pub struct Binder {
    header: NonNull<ComHeader>,
}

impl Binder {
    /// A slot presenting `vtbl` for the object being built.
    pub fn slot<V: Vtable>(&self, vtbl: &'static V) -> Slot {
        Slot {
            vtbl: vtbl as *const V as *const c_void,
            header: self.header,
        }
    }
}

/// What the objects of one class share: `ComObject::<T>::CLASS`, a constant in static memory per
/// class, which every object's header points at. (The compiler may keep more than one copy of a
/// constant; nothing compares their addresses: objects are told apart by `type_id`.)
pub struct Class {
    /// The slot of the object for an IID (`ComClass::interface`), NULL for none.
    query: unsafe fn(NonNull<ComHeader>, &GUID) -> *mut c_void,
    /// Frees the object, after its last reference.
    destroy: unsafe fn(NonNull<ComHeader>),
    /// The class's type.
    type_id: fn() -> TypeId,
}

/// Bookkeeping shared by all library objects; always at offset 0 of a `ComObject<T>`.
#[repr(C)]
pub struct ComHeader {
    inner: Slot,
    refs: AtomicU32,
    outer: *mut IUnknown,
    /// The object's class (its `ComObject::<T>::CLASS`).
    class: &'static Class,
    /// The EXE server's module lock that counted this object, unlocked once it is freed.
    module_lock: Option<ModuleLock>,
}

impl ComHeader {
    /// The non-delegating IUnknown of this object.
    pub fn inner_unknown(&self) -> *mut IUnknown {
        self.inner.as_ptr().cast()
    }

    /// The controlling unknown: the outer object when aggregated, else this object's own IUnknown.
    /// This is the object's COM identity.
    pub fn controlling_unknown(&self) -> *mut IUnknown {
        if self.outer.is_null() {
            self.inner_unknown()
        } else {
            self.outer
        }
    }

    /// QueryInterface on the controlling unknown (the object's COM identity: the outer object when
    /// aggregated), checked as a foreign object's answer requires ([`query`](super::unknown::query)).
    pub fn query<I>(&self, iid: &GUID) -> Result<Counted<I>, HRESULT> {
        // SAFETY: the controlling unknown is valid while the object lives, which `self` is part of.
        unsafe { super::unknown::query(self.controlling_unknown(), iid) }
    }

    /// True when the object was created as part of an outer (aggregating) object.
    pub fn is_aggregated(&self) -> bool {
        !self.outer.is_null()
    }

    /// The pointer to the whole object this header heads (with the provenance of its allocation).
    fn object(&self) -> NonNull<ComHeader> {
        self.inner.header
    }

    /// Non-delegating QueryInterface: the object's interface `iid`, AddRef'd, or E_NOINTERFACE.
    ///
    /// # Safety
    /// `this` must be the header of a live object.
    unsafe fn query_interface(this: NonNull<ComHeader>, iid: &GUID) -> Result<*mut c_void, HRESULT> {
        let found = if *iid == IID_IUNKNOWN {
            // SAFETY: the object is live.
            unsafe { this.as_ref() }.inner.as_ptr()
        } else {
            // SAFETY: `class` is the class of the object this header belongs to; `this` reaches it.
            unsafe { (this.as_ref().class.query)(this, iid) }
        };
        if found.is_null() {
            return Err(E_NOINTERFACE);
        }
        // SAFETY: `found` is one of this object's interface pointers. AddRef through it, so that an
        // aggregated object's interfaces count on the outer object, as COM requires.
        unsafe { add_ref(found.cast()) };
        Ok(found)
    }

    /// Counts one more reference (see the module documentation for saturation).
    fn add_ref(&self) -> ULONG {
        let old = self.refs.fetch_add(1, Ordering::Relaxed);
        if old >= REFS_SATURATED_FROM - 1 {
            // This call reached the saturated range (or found it reached): pin the count.
            self.refs.store(REFS_SATURATED, Ordering::Relaxed);
            return REFS_SATURATED;
        }
        old + 1
    }

    /// Gives up one reference; the last one frees the object.
    ///
    /// # Safety
    /// `this` must be the header of a live object and the caller must own a reference, which it
    /// gives up: the object may be freed before this returns.
    unsafe fn release(this: NonNull<ComHeader>) -> ULONG {
        // SAFETY: the caller's reference keeps the header alive until the decrement below; the
        // reference to the counter is not used after it.
        let refs = unsafe { &(*this.as_ptr()).refs };
        // Never go below zero: a Release too many on a still-live object is refused, not a double free.
        let mut cur = refs.load(Ordering::Relaxed);
        loop {
            if cur == 0 {
                return 0;
            }
            if cur >= REFS_SATURATED_FROM {
                return REFS_SATURATED;
            }
            match refs.compare_exchange_weak(cur, cur - 1, Ordering::Release, Ordering::Relaxed) {
                Ok(_) => break,
                Err(now) => cur = now,
            }
        }
        if cur == 1 {
            // Synchronise with every earlier Release before destroying. An acquire load (rather than
            // a standalone acquire fence) also lets ThreadSanitizer see the ordering.
            let _ = refs.load(Ordering::Acquire);
            // SAFETY: the last reference is gone; the class's `destroy` frees the object through the
            // pointer of its allocation, and no reference into the object is live here.
            unsafe {
                let destroy = (*this.as_ptr()).class.destroy;
                destroy(this);
            }
            return 0;
        }
        cur - 1
    }

    /// Sets the reference count, for tests that need a count near the top without 2^31 AddRefs.
    #[cfg(test)]
    pub(crate) fn set_refs_for_test(&self, refs: u32) {
        self.refs.store(refs, Ordering::SeqCst);
    }
}

/// A library object: the header, then the class's own state.
#[repr(C)]
pub struct ComObject<T> {
    header: ComHeader,
    state: T,
}

impl<T> core::ops::Deref for ComObject<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.state
    }
}

/// Frees a block whose construction did not complete (the class's `build` failed or panicked).
struct Unbuilt<T>(NonNull<MaybeUninit<ComObject<T>>>);

impl<T> Drop for Unbuilt<T> {
    fn drop(&mut self) {
        // SAFETY: the block came from Box::into_raw and holds no initialised value.
        drop(unsafe { Box::from_raw(self.0.as_ptr()) });
    }
}

impl<T: ComClass> ComObject<T> {
    /// The class of `T`'s objects, which their headers point at.
    pub const CLASS: &'static Class = &Class {
        query: query_thunk::<T>,
        destroy: destroy_thunk::<T>,
        type_id: TypeId::of::<T>,
    };

    /// Allocates an object with one reference (owned by the caller through its inner IUnknown).
    /// `build` receives a [`Binder`] for making the object's interface slots.
    #[allow(clippy::new_ret_no_self)] // the caller gets a counted reference, never the object by value
    pub fn new(outer: *mut IUnknown, build: impl FnOnce(&Binder) -> T) -> ComRef<T> {
        match Self::try_new(outer, |b| Ok::<T, core::convert::Infallible>(build(b))) {
            Ok(obj) => obj,
            Err(never) => match never {},
        }
    }

    /// As [`ComObject::new`], for construction that can fail; nothing is allocated on failure.
    pub fn try_new<E>(outer: *mut IUnknown, build: impl FnOnce(&Binder) -> Result<T, E>) -> Result<ComRef<T>, E> {
        Self::make(outer, true, build)
    }

    /// As [`ComObject::try_new`]; `counted`: whether the object counts on an EXE server's module lock
    /// (every object does but class objects, which COM holds while they are registered).
    fn make<E>(
        outer: *mut IUnknown,
        counted: bool,
        build: impl FnOnce(&Binder) -> Result<T, E>,
    ) -> Result<ComRef<T>, E> {
        // The raw pointer of the allocation, taken first: every slot keeps a copy of it, and nothing
        // reborrows the block through a Box or a reference later (that would invalidate the copies).
        let raw: NonNull<MaybeUninit<ComObject<T>>> = NonNull::from(Box::leak(Box::new_uninit()));
        let unbuilt = Unbuilt(raw);
        // The header sits at offset 0, so slots can point at it before the object is written.
        let binder = Binder { header: raw.cast() };
        let value = build(&binder)?;
        core::mem::forget(unbuilt);
        let obj: NonNull<ComObject<T>> = raw.cast();
        // SAFETY: `obj` is the allocation, valid for writes and not yet initialised.
        unsafe {
            obj.as_ptr().write(ComObject {
                header: ComHeader {
                    inner: binder.slot(&INNER_VTBL),
                    refs: AtomicU32::new(1),
                    outer,
                    class: Self::CLASS,
                    module_lock: if counted { ModuleLock::lock() } else { None },
                },
                state: value,
            })
        };
        LIVE_OBJECTS.fetch_add(1, Ordering::AcqRel);
        Ok(ComRef { obj })
    }

    /// The standard creation protocol of the library's `...Create` functions (and of
    /// `IClassFactory::CreateInstance`): checks the arguments, refuses aggregation unless `riid` is
    /// IID_IUnknown (CLASS_E_NOAGGREGATION), builds the object and returns the requested interface.
    /// `*ppv` is NULL on every failure.
    ///
    /// # Safety
    /// `outer` must be NULL or a valid IUnknown; `riid` NULL or readable; `ppv` NULL or writable.
    pub unsafe fn create(
        outer: *mut IUnknown,
        riid: REFIID,
        ppv: *mut *mut c_void,
        build: impl FnOnce(&Binder) -> Result<T, HRESULT>,
    ) -> HRESULT {
        // SAFETY: forwarded from the caller's contract.
        unsafe { Self::create_as(outer, true, riid, ppv, build) }
    }

    /// The creation protocol of a class object (IClassFactory): as [`ComObject::create`] without an
    /// outer object, and the object does not count on an EXE server's module lock.
    ///
    /// # Safety
    /// `riid` NULL or readable; `ppv` NULL or writable.
    pub unsafe fn create_class_object(
        riid: REFIID,
        ppv: *mut *mut c_void,
        build: impl FnOnce(&Binder) -> Result<T, HRESULT>,
    ) -> HRESULT {
        // SAFETY: forwarded from the caller's contract; no outer object.
        unsafe { Self::create_as(ptr::null_mut(), false, riid, ppv, build) }
    }

    /// The creation protocol, for an object that counts on the module lock or not (`counted`).
    ///
    /// # Safety
    /// As for [`ComObject::create`].
    unsafe fn create_as(
        outer: *mut IUnknown,
        counted: bool,
        riid: REFIID,
        ppv: *mut *mut c_void,
        build: impl FnOnce(&Binder) -> Result<T, HRESULT>,
    ) -> HRESULT {
        if ppv.is_null() {
            return E_POINTER;
        }
        // SAFETY: checked non-NULL; the caller vouches it is writable.
        unsafe { *ppv = ptr::null_mut() };
        if riid.is_null() {
            return E_POINTER;
        }
        // SAFETY: checked non-NULL; the caller vouches it is readable.
        if !outer.is_null() && unsafe { *riid } != IID_IUNKNOWN {
            return CLASS_E_NOAGGREGATION;
        }
        let obj = match guard(Err(E_UNEXPECTED), || Self::make(outer, counted, build)) {
            Ok(obj) => obj,
            Err(hr) => return hr,
        };
        // SAFETY: `obj` keeps the object alive meanwhile; `riid` was checked above.
        match unsafe { ComHeader::query_interface(obj.obj.cast(), &*riid) } {
            Ok(found) => {
                // SAFETY: checked non-NULL above; the caller vouches it is writable.
                unsafe { *ppv = found };
                S_OK
            }
            Err(hr) => hr,
        }
        // `obj` drops here, releasing the construction reference.
    }

    /// The object behind one of its interface pointers.
    ///
    /// # Safety
    /// `this` must be an interface pointer handed out by a live `ComObject<T>` (one of its slots),
    /// and the object must outlive `'a`.
    pub unsafe fn from_interface<'a, I>(this: *mut I) -> &'a ComObject<T> {
        // SAFETY: the caller vouches `this` is a slot of a live ComObject<T>; the slot's back pointer
        // is the pointer of the whole allocation, and the header is at offset 0.
        unsafe { header_of(this).cast::<ComObject<T>>().as_ref() }
    }

    /// The object behind `this` if it is one of ours presenting `vtbl`, else `None`. Reading the first
    /// word of any COM interface pointer is valid, so foreign objects are told apart safely.
    ///
    /// # Safety
    /// `this` must be NULL or a valid COM interface pointer.
    pub unsafe fn from_foreign<'a, I, V>(this: *mut I, vtbl: &'static V) -> Option<&'a ComObject<T>> {
        if this.is_null() {
            return None;
        }
        // SAFETY: every COM interface pointer points at its vtable pointer.
        let found = unsafe { *(this as *const *const c_void) };
        if found != vtbl as *const V as *const c_void {
            return None;
        }
        // SAFETY: the vtable is one that only ComObject<T> slots present.
        Some(unsafe { Self::from_interface(this) })
    }

    /// The bookkeeping header (identity, aggregation).
    pub fn header(&self) -> &ComHeader {
        &self.header
    }

    /// A new counted reference to this object (non-delegating; keeps this object itself alive).
    pub fn to_ref(&self) -> ComRef<T> {
        self.header.add_ref();
        ComRef {
            // The allocation's pointer, not one derived from `&self`: the last ComRef frees through it.
            obj: self.header.object().cast(),
        }
    }
}

/// An owned reference to a library object (counted on its non-delegating IUnknown).
pub struct ComRef<T: ComClass> {
    /// The pointer of the allocation (see the module documentation).
    obj: NonNull<ComObject<T>>,
}

// SAFETY: library objects are free-threaded: their state is Send + Sync and the count is atomic.
unsafe impl<T: ComClass> Send for ComRef<T> {}
// SAFETY: as above.
unsafe impl<T: ComClass> Sync for ComRef<T> {}

impl<T: ComClass> ComRef<T> {
    /// Gives up this reference as the object's non-delegating IUnknown pointer.
    pub fn into_inner_unknown(self) -> *mut IUnknown {
        let p = self.header().inner_unknown();
        core::mem::forget(self);
        p
    }
}

impl<T: ComClass> core::ops::Deref for ComRef<T> {
    type Target = ComObject<T>;
    fn deref(&self) -> &ComObject<T> {
        // SAFETY: the reference keeps the object alive.
        unsafe { self.obj.as_ref() }
    }
}

impl<T: ComClass> Clone for ComRef<T> {
    fn clone(&self) -> Self {
        self.to_ref()
    }
}

impl<T: ComClass> Drop for ComRef<T> {
    fn drop(&mut self) {
        // SAFETY: this reference was counted; after the call it is not used again. No reference into
        // the object is live across the call.
        unsafe { ComHeader::release(self.obj.cast()) };
    }
}

/// # Safety
/// Installed only in headers of ComObject<T>; `header` is the pointer of the live allocation.
unsafe fn query_thunk<T: ComClass>(header: NonNull<ComHeader>, iid: &GUID) -> *mut c_void {
    // SAFETY: `header` reaches the whole ComObject<T>, which starts with the header.
    let obj = unsafe { header.cast::<ComObject<T>>().as_ref() };
    obj.state.interface(iid).map_or(ptr::null_mut(), Slot::as_ptr)
}

/// # Safety
/// Installed only in headers of ComObject<T>; `header` is the pointer of its allocation (made by
/// `ComObject::try_new` from a Box), called once, when the last reference is gone.
unsafe fn destroy_thunk<T: ComClass>(header: NonNull<ComHeader>) {
    // SAFETY: per the contract above.
    let object = unsafe { Box::from_raw(header.cast::<ComObject<T>>().as_ptr()) };
    let module_lock = object.header.module_lock;
    drop(object);
    LIVE_OBJECTS.fetch_sub(1, Ordering::AcqRel);
    // Last: an EXE server may exit as soon as its count reaches zero.
    if let Some(m) = module_lock {
        m.unlock();
    }
}

/// The pointer of the object behind any slot pointer (its whole allocation).
///
/// # Safety
/// `this` must be a slot of a live library object.
unsafe fn header_of<I>(this: *mut I) -> NonNull<ComHeader> {
    // SAFETY: the caller vouches for the slot; slots point back at their object.
    unsafe { (*(this as *const Slot)).header }
}

/// The slot an IUnknown method was called through (the `This` of [`IUnknownImpl`]), for that call: one
/// of a live object's slots, made by the generated shim. Neither `Copy` nor `Clone`, and Release takes
/// it by value: Release gives up the caller's reference, after which the object may be gone, so nothing
/// borrowed from it can be used after the call that may free it.
pub struct ThisSlot<'call> {
    slot: NonNull<Slot>,
    call: PhantomData<&'call Slot>,
}

impl ThisSlot<'_> {
    /// The slot `this` points at.
    ///
    /// # Safety
    /// `this` must be a slot of a live library object (one a [`Binder`] made, or an object's own
    /// IUnknown) whose vtable was made with the IUnknown methods being called, and the caller's
    /// reference must keep the object alive for `'call` (until it is given to Release).
    pub unsafe fn new(this: *mut IUnknown) -> Self {
        ThisSlot {
            // SAFETY: a slot of a live object is never NULL.
            slot: unsafe { NonNull::new_unchecked(this.cast()) },
            call: PhantomData,
        }
    }

    /// The slot as the interface pointer the caller called (not AddRef'd).
    pub fn as_unknown(&self) -> *mut IUnknown {
        self.slot.as_ptr().cast()
    }

    /// The object whose slot this is, if it is a `T`: its class's type is checked, so the answer is
    /// right whatever vtable the slot presents.
    pub fn object<T: ComClass>(&self) -> Option<&ComObject<T>> {
        let header = self.header();
        // SAFETY: the object is live for the call (`new`'s contract).
        if (unsafe { header.as_ref() }.class.type_id)() != TypeId::of::<T>() {
            return None;
        }
        // SAFETY: the object is a live ComObject<T> (its class says so), whose header is at offset 0;
        // the reference is bound to `self`, which Release takes by value, so it ends before the
        // object can go.
        Some(unsafe { header.cast::<ComObject<T>>().as_ref() })
    }

    /// AddRef through the slot's own IUnknown (which counts where the slot's references count: on the
    /// outer object of an aggregated object, for instance), for a reference the method hands out.
    pub fn add_ref(&self) -> ULONG {
        // SAFETY: the slot is live for the call (`new`'s contract).
        unsafe { add_ref(self.as_unknown()) }
    }

    /// The object's allocation, from the slot's back pointer.
    fn header(&self) -> NonNull<ComHeader> {
        // SAFETY: the slot is live for the call (`new`'s contract).
        unsafe { self.slot.as_ref() }.header
    }
}

static INNER_VTBL: IUnknownVtbl = IUnknownVtbl::new::<Inner>();

/// The IUnknown of an object itself (`header.inner`): its identity when it stands alone, and what an
/// aggregating outer object holds. It counts this object's own references.
pub struct Inner;

impl IUnknownImpl for Inner {
    fn QueryInterface(this: ThisSlot<'_>, riid: &GUID, ppvObject: ffi::Out<'_, *mut c_void>) -> FfiResult {
        // SAFETY: the object is live for the call (the shim's `ThisSlot`).
        ppvObject.write(unsafe { ComHeader::query_interface(this.header(), riid) }?);
        Ok(S_OK)
    }

    fn AddRef(this: ThisSlot<'_>) -> ULONG {
        // SAFETY: as above.
        unsafe { this.header().as_ref() }.add_ref()
    }

    fn Release(this: ThisSlot<'_>) -> ULONG {
        // SAFETY: as above; the caller gives up its reference, and `this` is not used after.
        unsafe { ComHeader::release(this.header()) }
    }
}

/// The IUnknown methods of every other slot of an object: they delegate to the controlling unknown
/// (the outer object when aggregated, else the object's own inner IUnknown), as COM requires.
pub struct Delegating;

impl IUnknownImpl for Delegating {
    fn QueryInterface(this: ThisSlot<'_>, riid: &GUID, ppvObject: ffi::Out<'_, *mut c_void>) -> FfiResult {
        let header = this.header();
        // SAFETY: the object is live for the call.
        let outer = unsafe { header.as_ref() }.outer;
        if outer.is_null() {
            // SAFETY: as above.
            ppvObject.write(unsafe { ComHeader::query_interface(header, riid) }?);
            return Ok(S_OK);
        }
        // SAFETY: the outer unknown is valid while this object lives; `ppvObject` is writable.
        Ok(unsafe { super::unknown::query_interface(outer, riid, ppvObject.as_ptr()) })
    }

    fn AddRef(this: ThisSlot<'_>) -> ULONG {
        // SAFETY: the object is live for the call, and the outer object while it lives.
        unsafe {
            let header = this.header().as_ref();
            if header.outer.is_null() {
                header.add_ref()
            } else {
                add_ref(header.outer)
            }
        }
    }

    fn Release(this: ThisSlot<'_>) -> ULONG {
        // SAFETY: as for AddRef; the caller gives up a reference, and `this` is not used after.
        unsafe {
            let header = this.header();
            let outer = header.as_ref().outer;
            if outer.is_null() {
                ComHeader::release(header)
            } else {
                super::unknown::release(outer)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::com::hresult::{E_INVALIDARG, E_NOTIMPL};
    use crate::com::interfaces::{IOPCCommon, IOPCCommonImpl, IOPCCommonVtbl};
    use crate::com::unknown::release;
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;

    /// The test interface: IOPCCommon, whose GetLocaleID returns the object's value and whose
    /// SetLocaleID panics (the other methods are not used).
    type ITest = IOPCCommon;
    const IID_ITEST: GUID = IOPCCommon::IID;

    struct TestObject {
        test: Slot,
        value: u32,
        died: Arc<AtomicBool>,
    }
    impl Drop for TestObject {
        fn drop(&mut self) {
            assert!(!self.died.swap(true, Ordering::SeqCst), "dropped twice");
        }
    }
    impl ComClass for TestObject {
        fn interface(&self, iid: &GUID) -> Option<&Slot> {
            (*iid == IID_ITEST).then_some(&self.test)
        }
    }

    impl IOPCCommonImpl for TestObject {
        fn SetLocaleID(_: &ComObject<Self>, _: u32) -> FfiResult {
            panic!("a bug inside a method")
        }
        fn GetLocaleID(this: &ComObject<Self>, out: ffi::Out<'_, u32>) -> FfiResult {
            out.write(this.value);
            Ok(S_OK)
        }
        fn QueryAvailableLocaleIDs(_: &ComObject<Self>, _: ffi::Out<'_, u32>, _: ffi::Out<'_, *mut u32>) -> FfiResult {
            Err(E_NOTIMPL.into())
        }
        fn GetErrorString(_: &ComObject<Self>, _: HRESULT, _: ffi::Out<'_, *mut u16>) -> FfiResult {
            Err(E_NOTIMPL.into())
        }
        fn SetClientName(_: &ComObject<Self>, _: ffi::WStr<'_>) -> FfiResult {
            Err(E_NOTIMPL.into())
        }
    }
    static TEST_VTBL: IOPCCommonVtbl = IOPCCommonVtbl::new::<Delegating, TestObject>();

    fn create(died: &Arc<AtomicBool>) -> *mut ITest {
        let mut p: *mut c_void = ptr::null_mut();
        let died = died.clone();
        // SAFETY: valid arguments.
        let hr = unsafe {
            ComObject::<TestObject>::create(ptr::null_mut(), &IID_ITEST, &mut p, |b| {
                Ok(TestObject {
                    test: b.slot(&TEST_VTBL),
                    value: 42,
                    died,
                })
            })
        };
        assert_eq!(hr, S_OK);
        p.cast()
    }

    #[test]
    fn objects_die_exactly_at_the_last_release() {
        let died = Arc::new(AtomicBool::new(false));
        let t = create(&died);
        // SAFETY: `t` is a live interface pointer until its last Release.
        unsafe {
            let vt = &*(*t).lpVtbl;
            assert_eq!((vt.AddRef)(t), 2);
            assert_eq!((vt.Release)(t), 1);
            let mut unk: *mut c_void = ptr::null_mut();
            assert_eq!((vt.QueryInterface)(t, &IID_IUNKNOWN, &mut unk), S_OK);
            assert!(!died.load(Ordering::SeqCst));
            assert_eq!((vt.Release)(t), 1);
            assert!(!died.load(Ordering::SeqCst));
            assert_eq!(release(unk.cast()), 0);
        }
        assert!(died.load(Ordering::SeqCst));
    }

    #[test]
    fn identity_and_query_interface_rules() {
        let died = Arc::new(AtomicBool::new(false));
        let t = create(&died);
        // SAFETY: `t` is live throughout; every reference taken is released.
        unsafe {
            let vt = &*(*t).lpVtbl;
            let (mut u1, mut u2, mut again) = (ptr::null_mut(), ptr::null_mut(), ptr::null_mut());
            assert_eq!((vt.QueryInterface)(t, &IID_IUNKNOWN, &mut u1), S_OK);
            assert_eq!(
                crate::com::unknown::query_interface(u1.cast(), &IID_IUNKNOWN, &mut u2),
                S_OK
            );
            assert_eq!(u1, u2);
            assert_eq!(
                crate::com::unknown::query_interface(u1.cast(), &IID_ITEST, &mut again),
                S_OK
            );
            assert_eq!(again, t.cast());
            let mut missing: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
            let other = GUID::from_u128(0x99);
            assert_eq!((vt.QueryInterface)(t, &other, &mut missing), E_NOINTERFACE);
            assert!(missing.is_null());
            assert_eq!((vt.QueryInterface)(t, &IID_ITEST, ptr::null_mut()), E_POINTER);
            let mut p: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
            assert_eq!((vt.QueryInterface)(t, ptr::null(), &mut p), E_POINTER);
            assert!(p.is_null());
            release(u1.cast());
            release(u2.cast());
            release(again.cast());
            assert_eq!((vt.Release)(t), 0);
        }
        assert!(died.load(Ordering::SeqCst));
    }

    #[test]
    fn a_panic_in_a_method_becomes_e_unexpected_and_the_object_lives_on() {
        let died = Arc::new(AtomicBool::new(false));
        let t = create(&died);
        // SAFETY: `t` is live until the final Release.
        unsafe {
            let vt = &*(*t).lpVtbl;
            assert_eq!((vt.SetLocaleID)(t, 0), E_UNEXPECTED);
            let mut v = 0;
            assert_eq!((vt.GetLocaleID)(t, &mut v), S_OK);
            assert_eq!(v, 42);
            assert_eq!((vt.Release)(t), 0);
        }
        assert!(died.load(Ordering::SeqCst));
    }

    #[test]
    fn reference_counts_are_exact_under_concurrency() {
        /// An interface pointer that may cross threads (the object is free-threaded).
        #[derive(Clone, Copy)]
        struct Shared(*mut ITest);
        // SAFETY: library objects are free-threaded.
        unsafe impl Send for Shared {}
        impl Shared {
            fn get(self) -> *mut ITest {
                self.0
            }
        }
        let died = Arc::new(AtomicBool::new(false));
        let t = Shared(create(&died));
        let rounds = if cfg!(miri) { 40 } else { 20_000 };
        let threads: Vec<_> = (0..4)
            .map(|_| {
                std::thread::spawn(move || {
                    let t = t.get();
                    for _ in 0..rounds {
                        // SAFETY: the creating reference keeps the object alive meanwhile.
                        unsafe {
                            ((*(*t).lpVtbl).AddRef)(t);
                            ((*(*t).lpVtbl).Release)(t);
                        }
                    }
                })
            })
            .collect();
        for th in threads {
            th.join().unwrap();
        }
        assert!(!died.load(Ordering::SeqCst));
        let t = t.get();
        // SAFETY: the last reference.
        assert_eq!(unsafe { ((*(*t).lpVtbl).Release)(t) }, 0);
        assert!(died.load(Ordering::SeqCst));
    }

    #[test]
    fn reference_counts_saturate_instead_of_wrapping() {
        let died = Arc::new(AtomicBool::new(false));
        let t = create(&died);
        // SAFETY: `t` is live throughout (a saturated object is never freed); the test finally puts
        // the count back to 1 and releases the object.
        unsafe {
            let vt = &*(*t).lpVtbl;
            let obj = ComObject::<TestObject>::from_interface(t);
            // The top of the exact range: AddRef and Release still count.
            obj.header().set_refs_for_test(REFS_SATURATED_FROM - 2);
            assert_eq!((vt.AddRef)(t), REFS_SATURATED_FROM - 1);
            assert_eq!((vt.Release)(t), REFS_SATURATED_FROM - 2);
            assert_eq!((vt.AddRef)(t), REFS_SATURATED_FROM - 1);
            // One more saturates: from here the count is pinned and the object immortal.
            assert_eq!((vt.AddRef)(t), REFS_SATURATED);
            assert_eq!((vt.AddRef)(t), REFS_SATURATED);
            for _ in 0..if cfg!(miri) { 50 } else { 1000 } {
                assert_eq!((vt.Release)(t), REFS_SATURATED);
            }
            let mut unk: *mut c_void = ptr::null_mut();
            assert_eq!((vt.QueryInterface)(t, &IID_IUNKNOWN, &mut unk), S_OK);
            assert_eq!(release(unk.cast()), REFS_SATURATED);
            // A count set anywhere in the saturated range (as racing AddRefs past the top would leave
            // it) is pinned too, also through the non-delegating IUnknown and ComRef.
            obj.header().set_refs_for_test(u32::MAX);
            assert_eq!(add_ref(unk.cast()), REFS_SATURATED);
            obj.header().set_refs_for_test(u32::MAX);
            drop(obj.to_ref());
            assert_eq!((vt.Release)(t), REFS_SATURATED);
            let mut v = 0;
            assert_eq!((vt.GetLocaleID)(t, &mut v), S_OK);
            assert_eq!(v, 42);
            assert!(!died.load(Ordering::SeqCst));
            obj.header().set_refs_for_test(1);
            assert_eq!((vt.Release)(t), 0);
        }
        assert!(died.load(Ordering::SeqCst));
    }

    #[test]
    fn the_objects_of_a_class_point_at_its_class_which_tells_them_from_others() {
        let died = Arc::new(AtomicBool::new(false));
        let (a, b) = (create(&died), create(&Arc::new(AtomicBool::new(false))));
        // SAFETY: `a` and `b` are live interface pointers until their last Release.
        unsafe {
            let (oa, ob) = (
                ComObject::<TestObject>::from_interface(a),
                ComObject::<TestObject>::from_interface(b),
            );
            // Each header points at the class's constant: its functions and its type.
            assert_eq!((oa.header().class.type_id)(), TypeId::of::<TestObject>());
            assert_eq!(
                (ob.header().class.type_id)(),
                (ComObject::<TestObject>::CLASS.type_id)()
            );
            // A slot of `a`, as an IUnknown method sees it: a TestObject, and nothing else.
            {
                let this = ThisSlot::new(a.cast());
                assert!(this.object::<TestObject>().is_some_and(|o| o.value == 42));
                assert!(this.object::<Other>().is_none());
            }
            assert_eq!(((*(*a).lpVtbl).Release)(a), 0);
            assert_eq!(((*(*b).lpVtbl).Release)(b), 0);
        }
        assert!(died.load(Ordering::SeqCst));
    }

    /// Another class, for the type check.
    struct Other;
    impl ComClass for Other {
        fn interface(&self, _: &GUID) -> Option<&Slot> {
            None
        }
    }

    #[test]
    fn a_build_that_panics_frees_its_block_and_counts_no_object() {
        let mut p: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
        // SAFETY: valid arguments.
        let hr = unsafe {
            ComObject::<TestObject>::create(
                ptr::null_mut(),
                &IID_ITEST,
                &mut p,
                |_| -> Result<TestObject, HRESULT> { panic!("a bug in a constructor") },
            )
        };
        assert_eq!(hr, E_UNEXPECTED);
        assert!(p.is_null());
        // The block itself: Miri's leak check fails the run if it was not freed.
    }

    #[test]
    fn aggregation_is_refused_for_other_interfaces_and_failed_builds_allocate_nothing() {
        let mut p: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
        let fake_outer = core::ptr::null_mut::<IUnknown>().wrapping_byte_add(8); // never dereferenced: refused before use
                                                                                 // SAFETY: the outer pointer is not touched on this path.
        let hr = unsafe {
            ComObject::<TestObject>::create(fake_outer, &IID_ITEST, &mut p, |_| -> Result<TestObject, HRESULT> {
                unreachable!("must not build")
            })
        };
        assert_eq!(hr, CLASS_E_NOAGGREGATION);
        assert!(p.is_null());
        let mut p: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
        // SAFETY: valid arguments.
        let hr = unsafe { ComObject::<TestObject>::create(ptr::null_mut(), &IID_ITEST, &mut p, |_| Err(E_INVALIDARG)) };
        assert_eq!(hr, E_INVALIDARG);
        assert!(p.is_null());
    }
}
