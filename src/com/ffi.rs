//! The one way across the C boundary. Every `#[no_mangle]` export and every vtable method is written
//! as a plain `unsafe extern` function whose whole body is one of two macros:
//!
//! - [`boundary!`](crate::ffi_boundary) for functions returning an HRESULT: it names the function's
//!   NULL rule ([`Rule::Opc`] or [`Rule::Com`]) and its out-parameters, resets those on entry, runs the
//!   body under the panic guard, turns the body's `Result` into the HRESULT and resets the
//!   out-parameters again when the result is a failure;
//! - [`guard!`](crate::ffi_guard) for the few functions returning something else (a BOOL, a count,
//!   a pointer, nothing) or an HRESULT without arguments to check (ShutdownRequest, the `Dll...`
//!   entry points): the panic guard with the function's documented failure value.
//!
//! Inside a body the typed readers below take the raw arguments apart: [`out`] for an out-pointer,
//! [`in_ref`] for an in-reference, [`in_units`] / [`in_string`] for an in-string, [`in_array`] for an
//! in-array. A NULL argument gives [`Fail::Null`], which the boundary turns into the function's NULL
//! code, so the rule is written once per function and cannot drift between functions of one kind.
//!
//! The generated shim of every interface method reads its arguments once with them and hands the
//! object's (safe) trait method what they checked, typed and bound to the call: [`Out`], [`OutArray`],
//! [`WStr`], [`InArray`], [`Iface`], [`Opaque`] (`src/com/interfaces.rs` says which IDL shape gets
//! which).
//!
//! Both macros return a [`Crossed<T>`] ([`Hr`] for an HRESULT), which code outside this module cannot
//! make from a value of its own, and every entry of a vtable the library fills returns one (the
//! vtables, their shims and the trait an object implements per interface are generated from the IDL:
//! `src/com/interfaces.rs`). A call into an object (any object, through the `...Calls` view of its
//! vtable that an interface pointer has) returns a [`Foreign<T>`] instead, which no Rust function of the
//! library can make either, so a method that only forwards another object's result cannot fill a
//! vtable, and a vtable whose entries skipped the boundary cannot be built: the compiler proves both
//! (see the `compile_fail` examples on [`Crossed`]). C sees the plain `T` (`#[repr(transparent)]`).
//!
//! What the compiler cannot see is checked by `tools/gen-header` (`rustcheck.rs`, with syn), which
//! fails the build's drift check: that every export and every callback handed to C (a named
//! `extern "C"` / `extern "system"` function outside the generated module) has one `boundary!` or
//! `guard!` as its whole body and declares `Hr` / `Crossed<T>` (or nothing), so no code of it runs
//! outside the panic guard; and that nothing but the generated module implements
//! [`Vtable`](super::object::Vtable) or casts a pointer to a `...Vtbl` type.
//!
//! The rule (docs/api-conventions.md): COM plumbing (IUnknown, IClassFactory, the enumerators,
//! connection points, and the creation functions that follow CoCreateInstance's `riid, ppv`
//! protocol) answers NULL with E_POINTER, as COM does; OPC methods and the library's helper functions
//! answer it with E_INVALIDARG, as the OPC specifications do. Invalid content (over-long or invalid
//! UTF-16 strings, huge counts) is E_INVALIDARG under both rules.

use core::marker::PhantomData;
use core::ptr::NonNull;
use std::panic::{catch_unwind, AssertUnwindSafe};

use super::hresult::{E_INVALIDARG, E_POINTER, E_UNEXPECTED};
use super::types::{HRESULT, WCHAR};
use super::wstr::{wstr_units, MAX_STRING_UNITS};

/// Which code a NULL pointer argument gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// OPC methods and the library's helpers: E_INVALIDARG.
    Opc,
    /// COM plumbing (QueryInterface, class factory, enumerators, connection points, creation
    /// functions with `riid, ppv`): E_POINTER.
    Com,
}

impl Rule {
    /// The code a NULL pointer argument gets under this rule.
    pub const fn null_code(self) -> HRESULT {
        match self {
            Rule::Opc => E_INVALIDARG,
            Rule::Com => E_POINTER,
        }
    }
}

/// Why a body failed: a NULL argument (the boundary picks the code) or a definite HRESULT.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fail {
    /// A required pointer argument was NULL.
    Null,
    /// Any other failure, with its code.
    Code(HRESULT),
}

impl From<HRESULT> for Fail {
    fn from(hr: HRESULT) -> Fail {
        Fail::Code(hr)
    }
}

/// What a body returns: the success code (S_OK, S_FALSE, ...) or why it failed.
pub type FfiResult<T = HRESULT> = Result<T, Fail>;

/// Types whose all-zero bit pattern is the defined failure value of an out-parameter: NULL pointers,
/// zero counts and cookies, GUID_NULL, zeroed plain C structs (specification section 3.1.3).
///
/// # Safety
/// All-zero bytes must be a valid value of the type.
pub unsafe trait ZeroIsEmpty {}

// SAFETY: zero is a valid integer.
unsafe impl ZeroIsEmpty for u16 {}
// SAFETY: as above.
unsafe impl ZeroIsEmpty for u32 {}
// SAFETY: as above.
unsafe impl ZeroIsEmpty for i32 {}
// SAFETY: zero is the NULL pointer, a valid raw pointer.
unsafe impl<T> ZeroIsEmpty for *mut T {}
// SAFETY: as above.
unsafe impl<T> ZeroIsEmpty for *const T {}
// SAFETY: GUID is four integer fields; zero is GUID_NULL.
unsafe impl ZeroIsEmpty for super::types::GUID {}

/// The out-parameters a boundary resets: a tuple of raw pointers, each NULL or writable.
pub trait OutParams: Copy {
    /// Writes the failure value through every non-NULL pointer.
    ///
    /// # Safety
    /// Every pointer must be NULL or valid for writing one value.
    unsafe fn reset(self);
}

impl<T: ZeroIsEmpty> OutParams for *mut T {
    unsafe fn reset(self) {
        if !self.is_null() {
            // SAFETY: the caller vouches the pointer is writable; all-zero is a valid T.
            unsafe { self.write_bytes(0, 1) };
        }
    }
}

impl OutParams for () {
    unsafe fn reset(self) {}
}

macro_rules! out_tuple {
    ($($name:ident),+) => {
        impl<$($name: OutParams),+> OutParams for ($($name,)+) {
            #[allow(non_snake_case)]
            unsafe fn reset(self) {
                let ($($name,)+) = self;
                // SAFETY: forwarded from the caller's contract, pointer by pointer.
                unsafe { $($name.reset();)+ }
            }
        }
    };
}
out_tuple!(A);
out_tuple!(A, B);
out_tuple!(A, B, C);
out_tuple!(A, B, C, D);

/// What every export and vtable method returns (an HRESULT, a BOOL, a count, a pointer), as proof
/// that it came out of [`run`] or [`guarded`], the functions behind
/// [`boundary!`](crate::ffi_boundary) and [`guard!`](crate::ffi_guard). The field is private to this
/// module and nothing else makes one, so a vtable entry or an export whose body skipped the boundary
/// does not type-check. `#[repr(transparent)]`: the ABI is exactly `T`'s under every calling
/// convention (an HRESULT is returned as the `int32_t` it is); `cbindgen.toml` has the header say `T`.
///
/// A vtable is filled by the generated `IFooVtbl::new` from an object's implementation of `IFooImpl`;
/// a vtable written out by hand needs functions that return this type, which only the two macros make:
///
/// ```
/// use core::ffi::c_void;
/// use opccomn::com::ffi::{self, Crossed, Hr};
/// use opccomn::com::{IUnknown, IUnknownVtbl, E_NOINTERFACE, REFIID, ULONG};
///
/// unsafe extern "system" fn qi(_: *mut IUnknown, _: REFIID, ppv: *mut *mut c_void) -> Hr {
///     ffi::boundary!(Com, [ppv], { Err(E_NOINTERFACE.into()) })
/// }
/// unsafe extern "system" fn count(_: *mut IUnknown) -> Crossed<ULONG> {
///     ffi::guard!(1, { 1 })
/// }
/// static VTBL: IUnknownVtbl = IUnknownVtbl { QueryInterface: qi, AddRef: count, Release: count };
/// ```
///
/// one that skips the boundary does not compile:
///
/// ```compile_fail,E0308
/// use core::ffi::c_void;
/// use opccomn::com::ffi::{self, Crossed};
/// use opccomn::com::{IUnknown, IUnknownVtbl, E_NOINTERFACE, HRESULT, REFIID, ULONG};
///
/// unsafe extern "system" fn qi(_: *mut IUnknown, _: REFIID, _: *mut *mut c_void) -> HRESULT {
///     E_NOINTERFACE
/// }
/// unsafe extern "system" fn count(_: *mut IUnknown) -> Crossed<ULONG> {
///     ffi::guard!(1, { 1 })
/// }
/// static VTBL: IUnknownVtbl = IUnknownVtbl { QueryInterface: qi, AddRef: count, Release: count };
/// ```
///
/// nor does one that only forwards a call into another object (its result is a [`Foreign<T>`]):
///
/// ```compile_fail,E0308
/// use opccomn::com::ffi::Crossed;
/// use opccomn::com::{IUnknown, ULONG};
///
/// unsafe extern "system" fn f(this: *mut IUnknown) -> Crossed<ULONG> {
///     let o = this;
///     ((*(*o).lpVtbl).AddRef)(o)
/// }
/// ```
///
/// and a view of a foreign vtable cannot be filled, since nothing makes a [`Foreign<T>`]:
///
/// ```compile_fail,E0423
/// use opccomn::com::ffi::Foreign;
/// use opccomn::com::{IUnknown, ULONG};
///
/// unsafe extern "system" fn f(_: *mut IUnknown) -> Foreign<ULONG> {
///     Foreign(1)
/// }
/// ```
#[repr(transparent)]
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Crossed<T>(T);

/// The result of a function returning an HRESULT across the boundary.
pub type Hr = Crossed<HRESULT>;

impl<T> Crossed<T> {
    /// The plain value.
    pub fn get(self) -> T {
        self.0
    }
}

/// What a call into an object returns: read through the `...Calls` view of its vtable, which every
/// interface pointer has (`src/com/interfaces.rs`). The object may be anybody's (the library's own, a
/// caller's, the system's), so its result proves nothing about the library's boundary: no Rust
/// function of the library can make one, and a vtable entry, which must return a [`Crossed<T>`],
/// cannot return one. [`Foreign::get`] gives the plain value. `#[repr(transparent)]`, as `Crossed`.
#[repr(transparent)]
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Foreign<T>(T);

impl<T> Foreign<T> {
    /// The plain value.
    pub fn get(self) -> T {
        self.0
    }
}

impl<T: core::fmt::Debug> core::fmt::Debug for Foreign<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.0.fmt(f)
    }
}

impl<T: PartialEq> PartialEq<T> for Foreign<T> {
    fn eq(&self, other: &T) -> bool {
        self.0 == *other
    }
}

#[cfg(test)]
impl<T> Crossed<T> {
    /// What a method of an object written in C returns: for the tests' stand-ins for the objects
    /// callers give the library (sinks, outer objects, servers), which do not cross its boundary.
    pub(crate) fn from_c(method: impl FnOnce() -> T) -> Self {
        Crossed(method())
    }
}

impl<T: core::fmt::Debug> core::fmt::Debug for Crossed<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.0.fmt(f)
    }
}

impl<T: PartialEq> PartialEq<T> for Crossed<T> {
    fn eq(&self, other: &T) -> bool {
        self.0 == *other
    }
}

/// The boundary behind [`boundary!`](crate::ffi_boundary): resets `outs`, runs `body` under the panic
/// guard, maps [`Fail::Null`] to the rule's code and a panic to E_UNEXPECTED, and resets `outs` again
/// on any failure code, so out-parameters are NULL/zero whenever the result is a failure.
///
/// # Safety
/// Every pointer in `outs` must be NULL or valid for writing one value for the whole call.
#[inline(always)]
pub unsafe fn run<O: OutParams>(rule: Rule, outs: O, body: impl FnOnce() -> FfiResult) -> Hr {
    // SAFETY: the caller's contract.
    unsafe { outs.reset() };
    let hr = match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(hr)) => hr,
        Ok(Err(Fail::Null)) => rule.null_code(),
        Ok(Err(Fail::Code(hr))) => hr,
        Err(_) => E_UNEXPECTED,
    };
    if hr < 0 {
        // SAFETY: as above.
        unsafe { outs.reset() };
    }
    Crossed(hr)
}

/// The panic guard: `fallback` when `body` panics. Inlined, so that a hot export (MatchPattern) pays
/// nothing for it.
#[inline(always)]
pub fn guard<R>(fallback: R, body: impl FnOnce() -> R) -> R {
    catch_unwind(AssertUnwindSafe(body)).unwrap_or(fallback)
}

/// The boundary behind [`guard!`](crate::ffi_guard): [`guard`], with the result as a [`Crossed`].
#[inline(always)]
pub fn guarded<R>(fallback: R, body: impl FnOnce() -> R) -> Crossed<R> {
    Crossed(guard(fallback, body))
}

/// The body of an HRESULT-returning export or vtable method:
/// `boundary!(Opc | Com, [out, params], { ...; Ok(S_OK) })`. The body is a closure returning
/// [`FfiResult`]; `?` works on `Result<_, HRESULT>` and on the readers of this module.
#[macro_export]
macro_rules! ffi_boundary {
    ($rule:ident, [$($out:expr),* $(,)?], $body:block) => {{
        let body = || -> $crate::com::ffi::FfiResult { $body };
        let outs = ($($out,)*);
        // SAFETY: every listed out-parameter is NULL or writable: the `# Safety` contract of the
        // function this body belongs to.
        unsafe { $crate::com::ffi::run($crate::com::ffi::Rule::$rule, outs, body) }
    }};
}

/// The body of an export or vtable method that returns no HRESULT: `guard!(fallback, { ... })`.
#[macro_export]
macro_rules! ffi_guard {
    // A function returning nothing has no result to carry the proof; tools/gen-header checks that such
    // an export's whole body is this macro.
    ((), $body:block) => {
        $crate::com::ffi::guard((), move || $body)
    };
    ($fallback:expr, $body:block) => {
        $crate::com::ffi::guarded($fallback, move || $body)
    };
}

pub use crate::ffi_boundary as boundary;
pub use crate::ffi_guard as guard;

/// A checked, writable out-parameter, for the call it was passed to (`'a`). The boundary has already
/// written its failure value; the body writes the result once it has succeeded.
pub struct Out<'a, T>(NonNull<T>, PhantomData<&'a mut T>);

impl<T> Out<'_, T> {
    /// Stores the result.
    pub fn write(self, value: T) {
        // SAFETY: `out` checked the pointer and its caller vouched it is writable for the call.
        unsafe { self.0.as_ptr().write(value) }
    }

    /// The raw pointer, for handing on to a function that writes it itself.
    pub fn as_ptr(&self) -> *mut T {
        self.0.as_ptr()
    }
}

impl<'a, T> Out<'a, *mut T> {
    /// The same out-parameter, for a pointer to another type (a thin pointer either way): for a method
    /// that hands out an object under an interface with another's layout (IOPCEnumGUID as IEnumGUID).
    pub fn cast_pointee<U>(self) -> Out<'a, *mut U> {
        Out(self.0.cast(), PhantomData)
    }
}

/// An out-parameter: NULL gives [`Fail::Null`].
///
/// # Safety
/// `p` must be NULL or valid for writing one `T` for `'a` (the rest of the call).
pub unsafe fn out<'a, T>(p: *mut T) -> FfiResult<Out<'a, T>> {
    NonNull::new(p).map(|p| Out(p, PhantomData)).ok_or(Fail::Null)
}

/// An optional out-parameter: `None` for NULL.
///
/// # Safety
/// As for [`out`].
pub unsafe fn out_opt<'a, T>(p: *mut T) -> Option<Out<'a, T>> {
    NonNull::new(p).map(|p| Out(p, PhantomData))
}

/// An out-array (`[out, size_is(len)]`: an enumerator's `rgelt`), for the call it was passed to: room
/// for `len` elements, written one by one (the method says how many it wrote). Never reset: its size
/// may be zero.
pub struct OutArray<'a, T> {
    first: NonNull<T>,
    len: usize,
    call: PhantomData<&'a mut [T]>,
}

impl<T> OutArray<'_, T> {
    /// The room the caller gave, in elements.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the caller gave no room.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Stores element `index`, which must be below [`len`](Self::len) (else it panics, which the
    /// boundary turns into E_UNEXPECTED).
    pub fn write(&mut self, index: usize, value: T) {
        assert!(index < self.len, "an out-array has room for {} elements", self.len);
        // SAFETY: `out_array`'s caller vouched for `len` writable elements; `index` is below it.
        unsafe { self.first.as_ptr().add(index).write(value) }
    }
}

/// An out-array of `len` elements: NULL gives [`Fail::Null`] unless `len` is 0 (then it may be NULL,
/// and nothing is ever written).
///
/// # Safety
/// A non-NULL `p` must be valid for writing `len` elements for `'a` (the rest of the call); a caller
/// that gives less room must not be asked for more elements than it has room for (COM's enumerators
/// write only the elements that exist).
pub unsafe fn out_array<'a, T>(p: *mut T, len: u32) -> FfiResult<OutArray<'a, T>> {
    let first = match NonNull::new(p) {
        Some(first) => first,
        None if len == 0 => NonNull::dangling(),
        None => return Err(Fail::Null),
    };
    Ok(OutArray {
        first,
        len: len as usize,
        call: PhantomData,
    })
}

/// A string argument (`[in, string]`: `LPCWSTR`, `LPCOLESTR`), for the call it was passed to: not
/// NULL, and NUL-terminated (or at least 2^19 + 1 units long). Its length is read only when asked
/// ([`units`](Self::units)), so a method that only passes it on reads nothing.
#[derive(Clone, Copy)]
pub struct WStr<'a>(NonNull<WCHAR>, PhantomData<&'a [WCHAR]>);

impl<'a> WStr<'a> {
    /// The string as it was passed, NUL-terminated, for handing on.
    pub fn as_ptr(self) -> *const WCHAR {
        self.0.as_ptr()
    }

    /// Its code units without the NUL (invalid UTF-16 kept); E_INVALIDARG when it is longer than
    /// 2^19 units (only that many are read).
    pub fn units(self) -> FfiResult<&'a [WCHAR]> {
        // SAFETY: `in_wstr`'s caller vouched for a NUL-terminated string valid for `'a`.
        unsafe { wstr_units(self.0.as_ptr(), MAX_STRING_UNITS) }.ok_or(Fail::Code(E_INVALIDARG))
    }
}

/// A string argument: NULL gives [`Fail::Null`].
///
/// # Safety
/// `p` must be NULL or point at a NUL-terminated UTF-16 string (or at least 2^19 + 1 readable units)
/// that stays readable for `'a` (the rest of the call).
pub unsafe fn in_wstr<'a>(p: *const WCHAR) -> FfiResult<WStr<'a>> {
    NonNull::new(p.cast_mut())
        .map(|p| WStr(p, PhantomData))
        .ok_or(Fail::Null)
}

/// A string argument that may be NULL: `None` for NULL.
///
/// # Safety
/// As for [`in_wstr`].
pub unsafe fn in_wstr_opt<'a>(p: *const WCHAR) -> Option<WStr<'a>> {
    NonNull::new(p.cast_mut()).map(|p| WStr(p, PhantomData))
}

/// An in-array argument (`[in, size_is(count)]`), for the call it was passed to. It is read only when
/// asked, against the method's own limit ([`read`](Self::read)): a method may give a count a meaning
/// of its own (the server list takes `(ULONG)-1` as "any category") before it reads anything.
#[derive(Clone, Copy)]
pub struct InArray<'a, T> {
    first: *const T,
    count: u32,
    call: PhantomData<&'a [T]>,
}

impl<'a, T> InArray<'a, T> {
    /// The count the caller gave.
    pub fn count(self) -> u32 {
        self.count
    }

    /// The items, as [`in_array`] reads them: an empty slice for a count of 0, [`Fail::Null`] for a
    /// NULL array with another count, E_INVALIDARG for more than `max` items.
    pub fn read(self, max: usize) -> FfiResult<&'a [T]> {
        // SAFETY: `in_array_arg`'s caller vouched for `count` readable items (or NULL) for `'a`.
        unsafe { in_array(self.first, self.count, max) }
    }
}

/// An in-array argument of `count` items.
///
/// # Safety
/// `p` must be NULL or point at `count` readable, initialised items for `'a` (the rest of the call).
pub unsafe fn in_array_arg<'a, T>(p: *const T, count: u32) -> InArray<'a, T> {
    InArray {
        first: p,
        count,
        call: PhantomData,
    }
}

/// A pointer argument the library passes on without reading it (`[in] void *`, or an interface it
/// never calls, as IMarshal's `IStream *`), for the call it was passed to; perhaps NULL.
#[derive(Clone, Copy)]
pub struct Opaque<'a>(*mut core::ffi::c_void, PhantomData<&'a ()>);

impl Opaque<'_> {
    /// The pointer as the caller passed it, for handing on.
    pub fn as_ptr(self) -> *mut core::ffi::c_void {
        self.0
    }
}

/// A pointer argument passed on without being read: no check.
pub fn opaque<'a, T>(p: *mut T) -> Opaque<'a> {
    Opaque(p.cast(), PhantomData)
}

/// An interface pointer argument (`[in] IFoo *`), for the call it was passed to: not NULL, and a valid
/// COM interface pointer of the caller's for `'a` (the caller holds its reference meanwhile).
#[derive(Clone, Copy)]
pub struct Iface<'a, I>(NonNull<I>, PhantomData<&'a I>);

impl<I> Iface<'_, I> {
    /// The interface pointer, for handing on (not AddRef'd).
    pub fn as_ptr(self) -> *mut I {
        self.0.as_ptr()
    }

    /// QueryInterface on the object, checked as a foreign object's answer requires
    /// ([`query`](super::unknown::query)).
    pub fn query<J>(self, iid: &super::types::GUID) -> Result<super::unknown::Counted<J>, HRESULT> {
        // SAFETY: `in_iface`'s caller vouched for a valid interface pointer for the call.
        unsafe { super::unknown::query(self.0.as_ptr().cast(), iid) }
    }
}

/// An interface pointer argument: NULL gives [`Fail::Null`].
///
/// # Safety
/// `p` must be NULL or a valid COM interface pointer for `'a` (the rest of the call).
pub unsafe fn in_iface<'a, I>(p: *mut I) -> FfiResult<Iface<'a, I>> {
    NonNull::new(p).map(|p| Iface(p, PhantomData)).ok_or(Fail::Null)
}

/// An interface pointer argument that may be NULL (`[in, unique]`): `None` for NULL.
///
/// # Safety
/// As for [`in_iface`].
pub unsafe fn in_iface_opt<'a, I>(p: *mut I) -> Option<Iface<'a, I>> {
    NonNull::new(p).map(|p| Iface(p, PhantomData))
}

/// An in-reference (a GUID, an options struct, an object the function reads): NULL gives
/// [`Fail::Null`].
///
/// # Safety
/// `p` must be NULL or valid for reading a `T` for the rest of the call.
pub unsafe fn in_ref<'a, T>(p: *const T) -> FfiResult<&'a T> {
    // SAFETY: the caller vouches a non-NULL `p` is readable.
    unsafe { p.as_ref() }.ok_or(Fail::Null)
}

/// A required pointer the function passes on without reading (an interface pointer): NULL gives
/// [`Fail::Null`].
pub fn in_ptr<T>(p: *mut T) -> FfiResult<NonNull<T>> {
    NonNull::new(p).ok_or(Fail::Null)
}

/// An in-string, as UTF-16 code units without the NUL (invalid UTF-16 kept): NULL gives
/// [`Fail::Null`], a string longer than 2^19 units E_INVALIDARG.
///
/// # Safety
/// `p` must be NULL or point at a NUL-terminated UTF-16 string (or at least 2^19 + 1 readable units).
pub unsafe fn in_units<'a>(p: *const WCHAR) -> FfiResult<&'a [WCHAR]> {
    if p.is_null() {
        return Err(Fail::Null);
    }
    // SAFETY: forwarded from the caller's contract.
    unsafe { wstr_units(p, MAX_STRING_UNITS) }.ok_or(Fail::Code(E_INVALIDARG))
}

/// An optional in-string: `None` for NULL, otherwise as [`in_units`].
///
/// # Safety
/// As for [`in_units`].
pub unsafe fn in_units_opt<'a>(p: *const WCHAR) -> FfiResult<Option<&'a [WCHAR]>> {
    if p.is_null() {
        return Ok(None);
    }
    // SAFETY: forwarded from the caller's contract.
    unsafe { in_units(p) }.map(Some)
}

/// An in-string that must be valid UTF-16 (registry keys, values, `.reg` text): NULL gives
/// [`Fail::Null`], over-long or invalid UTF-16 (an unpaired surrogate) E_INVALIDARG.
///
/// # Safety
/// As for [`in_units`].
pub unsafe fn in_string(p: *const WCHAR) -> FfiResult<String> {
    // SAFETY: forwarded from the caller's contract.
    let units = unsafe { in_units(p) }?;
    String::from_utf16(units).map_err(|_| Fail::Code(E_INVALIDARG))
}

/// An optional in-string that must be valid UTF-16: `None` for NULL, otherwise as [`in_string`].
///
/// # Safety
/// As for [`in_units`].
pub unsafe fn in_string_opt(p: *const WCHAR) -> FfiResult<Option<String>> {
    if p.is_null() {
        return Ok(None);
    }
    // SAFETY: forwarded from the caller's contract.
    unsafe { in_string(p) }.map(Some)
}

/// An in-array of `count` items: an empty slice for a count of 0 (the pointer may then be NULL),
/// [`Fail::Null`] for NULL with a non-zero count, E_INVALIDARG for more than `max` items.
///
/// # Safety
/// A non-NULL `p` must point at `count` readable, initialised items for the rest of the call.
pub unsafe fn in_array<'a, T>(p: *const T, count: u32, max: usize) -> FfiResult<&'a [T]> {
    if count == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(Fail::Null);
    }
    let count = count as usize;
    if count > max
        || count
            .checked_mul(core::mem::size_of::<T>())
            .is_none_or(|bytes| bytes > isize::MAX as usize)
    {
        return Err(Fail::Code(E_INVALIDARG));
    }
    // SAFETY: non-NULL, bounded, and the caller vouches for `count` readable items.
    Ok(unsafe { core::slice::from_raw_parts(p, count) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::com::hresult::{E_OUTOFMEMORY, S_FALSE};
    use core::ptr;

    #[test]
    fn the_rule_picks_the_null_code_and_failures_reset_the_out_parameters() {
        let (mut a, mut b): (*mut u16, u32) = (core::ptr::null_mut::<u16>().wrapping_byte_add(8), 7);
        let f = |rule, fail: bool, a: &mut *mut u16, b: &mut u32| {
            let (pa, pb) = (a as *mut *mut u16, b as *mut u32);
            // SAFETY: both out-parameters are writable locals.
            unsafe {
                run(rule, (pa, pb), || {
                    assert!((*pa).is_null() && *pb == 0, "reset on entry");
                    out(pb)?.write(5);
                    if fail {
                        out(ptr::null_mut::<u32>())?.write(1);
                    }
                    Ok(S_FALSE)
                })
            }
        };
        assert_eq!(f(Rule::Opc, false, &mut a, &mut b), S_FALSE);
        assert_eq!(b, 5);
        assert_eq!(f(Rule::Opc, true, &mut a, &mut b), E_INVALIDARG);
        assert_eq!(b, 0, "reset on failure");
        b = 9;
        assert_eq!(f(Rule::Com, true, &mut a, &mut b), E_POINTER);
        assert_eq!(b, 0);
    }

    #[test]
    fn a_panic_becomes_e_unexpected_with_the_out_parameters_reset() {
        let mut v: u32 = 3;
        let p = &mut v as *mut u32;
        // SAFETY: `p` is a writable local.
        let hr = unsafe {
            run(Rule::Opc, p, || {
                out(p)?.write(4);
                panic!("a bug inside a method")
            })
        };
        assert_eq!((hr.get(), v), (E_UNEXPECTED, 0));
        // SAFETY: `p` is a writable local.
        let hr = unsafe { run(Rule::Com, (), || Err(E_OUTOFMEMORY.into())) };
        assert_eq!(hr, E_OUTOFMEMORY);
        assert_eq!(guard(7, || -> i32 { panic!("boom") }), 7);
        assert_eq!(guard(7, || 1), 1);
    }

    #[test]
    fn the_typed_arguments_hold_what_the_shim_checked() {
        let text = [0x61u16, 0xD800, 0];
        let long = vec![0x61u16; MAX_STRING_UNITS + 2];
        let items = [1u32, 2, 3];
        let mut room = [0u32; 2];
        // SAFETY: every pointer is NULL or a local valid for the test, as each reader requires.
        unsafe {
            // A string is checked for NULL at once and read when asked, bounded.
            assert!(in_wstr(ptr::null()).is_err_and(|f| f == Fail::Null));
            assert!(in_wstr_opt(ptr::null()).is_none());
            let s = in_wstr(text.as_ptr()).unwrap();
            assert_eq!((s.units().unwrap(), s.as_ptr()), (&text[..2], text.as_ptr()));
            let s = in_wstr(long.as_ptr()).unwrap();
            assert_eq!(s.units().err(), Some(Fail::Code(E_INVALIDARG)));
            // An in-array is read against the method's limit, NULL refused only with a count.
            assert_eq!(in_array_arg::<u32>(ptr::null(), 0).read(1).unwrap(), &[] as &[u32]);
            assert_eq!(in_array_arg::<u32>(ptr::null(), 7).count(), 7);
            assert_eq!(in_array_arg::<u32>(ptr::null(), 7).read(8).err(), Some(Fail::Null));
            assert_eq!(
                in_array_arg(items.as_ptr(), 3).read(2).err(),
                Some(Fail::Code(E_INVALIDARG))
            );
            assert_eq!(in_array_arg(items.as_ptr(), 3).read(3).unwrap(), &items);
            // An out-array: NULL only for no room; written within its room.
            assert!(out_array::<u32>(ptr::null_mut(), 1).is_err_and(|f| f == Fail::Null));
            assert!(out_array::<u32>(ptr::null_mut(), 0).unwrap().is_empty());
            let mut a = out_array(room.as_mut_ptr(), 2).unwrap();
            a.write(1, 9);
            assert_eq!(a.len(), 2);
            let beyond = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| a.write(2, 1)));
            assert!(beyond.is_err(), "no write past the room");
            assert_eq!(room, [0, 9]);
            // Interface pointers and pointers passed on.
            assert!(in_iface::<u32>(ptr::null_mut()).is_err_and(|f| f == Fail::Null));
            assert!(in_iface_opt::<u32>(ptr::null_mut()).is_none());
            assert!(opaque::<u32>(ptr::null_mut()).as_ptr().is_null());
        }
    }

    #[test]
    fn readers_refuse_null_over_long_and_invalid_input() {
        let s = [0x61u16, 0xD800, 0];
        let ok = [0x61u16, 0x62, 0];
        // SAFETY: every pointer is NULL or a NUL-terminated local array.
        unsafe {
            assert_eq!(in_units(ptr::null()).err(), Some(Fail::Null));
            assert_eq!(in_units(s.as_ptr()).unwrap(), &s[..2]);
            assert_eq!(in_string(s.as_ptr()).err(), Some(Fail::Code(E_INVALIDARG)));
            assert_eq!(in_string(ok.as_ptr()).unwrap(), "ab");
            assert_eq!(in_string_opt(ptr::null()).unwrap(), None);
            let long = vec![0x61u16; MAX_STRING_UNITS + 2];
            assert_eq!(in_units(long.as_ptr()).err(), Some(Fail::Code(E_INVALIDARG)));
            assert_eq!(in_array::<u32>(ptr::null(), 0, 4).unwrap(), &[] as &[u32]);
            assert_eq!(in_array::<u32>(ptr::null(), 1, 4).err(), Some(Fail::Null));
            let items = [1u32, 2];
            assert_eq!(in_array(items.as_ptr(), 2, 4).unwrap(), &items);
            assert_eq!(
                in_array(items.as_ptr(), u32::MAX, 1 << 20).err(),
                Some(Fail::Code(E_INVALIDARG))
            );
            assert_eq!(in_array(items.as_ptr(), 5, 4).err(), Some(Fail::Code(E_INVALIDARG)));
            assert_eq!(in_ref::<u32>(ptr::null()).err(), Some(Fail::Null));
            assert_eq!(*in_ref(&items[1]).unwrap(), 2);
        }
    }
}
