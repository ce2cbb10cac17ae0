//! The layout language: what a method's request and reply look like in NDR 2.0, as data.
//!
//! `tools/gen-header` writes these tables from the IDL (`src/proxy/generated/layouts.rs`); the
//! interpreter in [`super`] reads a message against them. Nothing here is code: every item is a
//! `static` the generator writes, and the names carry no meaning to the interpreter (they are for
//! the reader of the generated file and for error messages in tests).
//!
//! The vocabulary is NDR's (C706 chapter 14, MS-RPCE 2.2.5) with the Automation types of MS-OAUT:
//!
//! - [`Ty::Base`]: an integer or floating-point type of 1, 2, 4 or 8 bytes, aligned to its size
//!   (`byte`, `short`, `long`, `hyper`, `float`, `double`; HRESULT, BOOL, DWORD, DATE...).
//! - [`Ty::Enum16`]: an IDL `enum` without `[v1_enum]`: 2 bytes on the wire, at most 0x7FFF.
//! - [`Ty::Guid`]: 16 bytes aligned to 4.
//! - [`Ty::Str`]: what a `[string]` pointer points at, a conformant varying array of 1- or 2-byte
//!   characters.
//! - [`Ty::Bstr`], [`Ty::Variant`], [`Ty::SafeArray`]: the `[wire_marshal]` types of oaidl.idl (BSTR
//!   as MS-OAUT 2.2.23, VARIANT as 2.2.29, SAFEARRAY as 2.2.30).
//! - [`Ty::Interface`]: an interface pointer, `MInterfacePointer` (MS-DCOM 2.2.14), with a fixed
//!   IID or one named by `iid_is`.
//! - [`Ty::Pointer`], [`Ty::Struct`], [`Ty::Union`], [`Ty::Array`]: the constructed types.
//!
//! Counts (`size_is`, `length_is`, `switch_is`, `iid_is`) name a [`Corr`]: a value the interpreter
//! keeps while it reads a message (a parameter, or `*parameter` of a pointer to one: [`Corr::Slot`])
//! or a field of the structure that declares the array ([`Corr::Field`]).

/// One value's layout.
#[derive(Clone, Copy, Debug)]
pub enum Ty {
    /// A base type of this many bytes (1, 2, 4 or 8), aligned to its size.
    Base(u8),
    /// An NDR `enum` (16 bits on the wire; MIDL refuses values above 0x7FFF).
    Enum16,
    /// A GUID: 16 bytes aligned to 4.
    Guid,
    /// The pointee of a `[string]` pointer: maximum count, offset, actual count, then the characters
    /// of this many bytes each (2: `wchar_t`, 1: `char`).
    Str(u8),
    /// A BSTR: its wire type `[unique] FLAGGED_WORD_BLOB *`.
    Bstr,
    /// A VARIANT: its wire type `[unique] wireVARIANTStr *`.
    Variant,
    /// A SAFEARRAY pointer (`LPSAFEARRAY`): its wire type `[unique] wireSAFEARRAY *`.
    SafeArray,
    /// An interface pointer.
    Interface(Iid),
    /// A pointer.
    Pointer(&'static Pointer),
    /// A structure.
    Struct(&'static Struct),
    /// A non-encapsulated union (`[switch_is]`).
    Union(&'static Union),
    /// An array.
    Array(&'static Array),
    /// Nothing: an empty union arm.
    Empty,
}

/// The IID an interface pointer's OBJREF must carry.
#[derive(Clone, Copy, Debug)]
pub enum Iid {
    /// The declared interface's, as NDR writes a GUID (Data1 to Data3 little-endian, then Data4).
    Fixed([u8; 16]),
    /// The GUID kept in this slot (`iid_is(riid)`): four slots, from this one on.
    Slot(u8),
}

/// A pointer. At the top of a parameter, a `[ref]` pointer has no wire representation and a
/// `[unique]` one is a referent ID (0: NULL) followed by its pointee. Embedded in a structure or an
/// array, either is a 32-bit referent ID and its pointee is deferred until after the construct.
#[derive(Debug)]
pub struct Pointer {
    /// `[unique]` (may be NULL); otherwise `[ref]`.
    pub unique: bool,
    pub target: Ty,
}

/// A structure: its fields in order, aligned to `align`.
#[derive(Debug)]
pub struct Struct {
    pub name: &'static str,
    /// The alignment of the structure: its largest field's.
    pub align: u8,
    pub fields: &'static [Ty],
    /// Whether a field (or a field's field) is a pointer or a `[wire_marshal]` type whose pointee
    /// is deferred until after the construct.
    pub deferred: bool,
    /// The structure's size on the wire when it is a block of base types and GUIDs with no padding
    /// at its end and no value to check (an array of them is skipped in one step); 0 otherwise.
    pub plain: u32,
    /// Its flat part's size when that is fixed (no union, no varying array), from its aligned start;
    /// 0 otherwise. The second walk over a construct skips it when it has no pointees.
    pub size: u32,
}

/// A non-encapsulated union: the discriminant (`switch_size` bytes, which must equal the value
/// `switch_is` names) then the arm it selects, at the arm's own alignment.
#[derive(Debug)]
pub struct Union {
    pub name: &'static str,
    pub switch: Corr,
    /// 1, 2 or 4: the size of `switch_type`.
    pub switch_size: u8,
    /// The `[case]` arms: (discriminant, layout).
    pub arms: &'static [(u32, Ty)],
    /// The `[default]` arm, if any; a discriminant of no arm is refused without one.
    pub default: Option<Ty>,
    pub deferred: bool,
}

/// An array of `elem`.
#[derive(Debug)]
pub struct Array {
    pub elem: Ty,
    /// How many elements it has room for: a fixed number, or a conformance on the wire that must
    /// equal a value (`size_is`).
    pub size: Extent,
    /// `length_is`: a varying array (offset 0, then the actual count, which must equal this value and
    /// be at most the size); `None` for all of them.
    pub length: Option<Corr>,
    /// The most elements the array may carry when a peer chooses its count (what MIDL's `[range]`
    /// would say; `tools/gen-header` documents each in the generated file).
    pub bound: u32,
    /// The element's size when it is plain (see [`Struct::plain`]): the elements are skipped in one
    /// step; 0 otherwise.
    pub plain: u32,
    /// Where the elements start is aligned to this, after the conformance and variance, whatever
    /// their number: the element's alignment, or 8 for VARIANTs (the format strings' array of
    /// VARIANTs has VARIANT's memory alignment, though each element's place is 4 bytes).
    pub align: u8,
    /// Whether the elements have deferred pointees.
    pub deferred: bool,
}

/// The number of elements of an array.
#[derive(Clone, Copy, Debug)]
pub enum Extent {
    Fixed(u32),
    /// Conformant: the conformance on the wire equals this value.
    Conformant(Corr),
}

/// A value a count refers to.
#[derive(Clone, Copy, Debug)]
pub enum Corr {
    /// The value kept in this slot: a parameter of the method (`size_is(dwCount)`), or the integer a
    /// parameter points to (`size_is(, *pdwCount)`). In a reply the slots of `[in]` parameters come
    /// from the request ([`Method::context`]).
    Slot(u8),
    /// A field of the structure that declares the pointer or array (by its index).
    Field(u8),
}

/// Where a parameter's value is kept for the counts that refer to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Save {
    None,
    /// An integer (the parameter, or what its `[ref]` pointers point to), in this slot.
    Int(u8),
    /// A GUID (`REFIID riid` for `iid_is`), in four slots from this one.
    Guid(u8),
}

/// A parameter as one message carries it.
#[derive(Debug)]
pub struct Param {
    pub name: &'static str,
    pub ty: Ty,
    pub save: Save,
}

/// A method: its request (`[in]` parameters) and its reply (`[out]` parameters, then the HRESULT).
#[derive(Debug)]
pub struct Method {
    pub name: &'static str,
    pub request: &'static [Param],
    pub reply: &'static [Param],
    /// Checked in the request as soon as the slot is read: values that size an `[out]` array which
    /// the stub or the caller allocates before the reply is there (slot, bound).
    pub bounds: &'static [(u8, u32)],
    /// The request's values the reply check needs, in order (a GUID takes four words of the
    /// [`super::Context`]).
    pub context: &'static [Save],
    /// Whether something in the request is aligned to 8 bytes (hyper, double, VARIANT...): the NDR
    /// engine aligns to the address, so the message must start at an 8-byte boundary for the check's
    /// offsets (from the message's start) to be the engine's.
    pub request_align8: bool,
    /// The same for the reply.
    pub reply_align8: bool,
}

/// An interface as the proxy/stub serves it.
///
/// cbindgen:ignore
#[derive(Debug)]
pub struct Interface {
    pub name: &'static str,
    /// The IID as NDR writes a GUID.
    pub iid: [u8; 16],
    /// Methods in the vtable, IUnknown's three included.
    pub vtable: u32,
    /// The methods from vtable index 3 on.
    pub methods: &'static [Method],
}
