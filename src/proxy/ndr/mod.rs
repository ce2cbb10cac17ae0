//! The interpreter of NDR layouts: checks one message (a request or a reply) against the layout of
//! its method ([`layout`], generated from the IDL by `tools/gen-header`) before the runtime's NDR
//! engine reads it.
//!
//! What it enforces, in both directions (docs/proxy-stub-robustness.md says it for users):
//!
//! - every byte the layout needs is in the message (a message may carry more after it);
//! - every count on the wire that sizes an array equals the value `size_is` / `length_is` names
//!   (a parameter, `*parameter`, or a field of the structure that declares it), a varying array has
//!   offset 0 and an actual count within its size, and a union's discriminant equals its
//!   `switch_is`; a value that comes later in the message is compared when it arrives;
//! - counts a peer chooses are at most the array's bound ([`layout::Array::bound`], what MIDL's
//!   `[range]` would say): `RPC_S_INVALID_BOUND`; values a request gives to size an `[out]` array are
//!   bounded as soon as they are read ([`layout::Method::bounds`]);
//! - a NULL pointer to an array sized by a value of the same message comes with a count of 0 (the
//!   receiver would walk NULL);
//! - strings are whole: maximum count = actual count >= 1, offset 0, the last character NUL;
//! - enum16 values are at most 0x7FFF (MIDL's rule);
//! - BSTRs, VARIANTs and SAFEARRAYs as MS-OAUT defines them, with what each runtime reads
//!   ([`automation`]), nested at most [`MAX_VARIANT_DEPTH`] deep;
//! - interface pointers: an OBJREF of the declared or `iid_is` interface, in the layout the reading
//!   runtime reads ([`objref`]);
//! - the data representation is the local one (little-endian, ASCII, IEEE); nothing is converted;
//! - a message with something aligned to 8 starts at an 8-byte address (the NDR engine aligns to the
//!   address, the checks from the message's start: only then are they the same).
//!
//! It reads with a cursor that never passes the end of the message, allocates nothing, and recurses
//! only as deep as the layout's types nest (the generator refuses recursive types) and, for VARIANTs
//! inside SAFEARRAYs, [`MAX_VARIANT_DEPTH`].
//!
//! Pointees follow NDR's order (C706 14.3.12): the pointee of a top-level pointer follows it at once;
//! the pointees of pointers embedded in a structure or an array follow the whole construct, in the
//! order of their pointers, each with its own deferred pointees right after it. The interpreter reads a
//! construct's flat part once to check it, then walks it again to read the pointees in that order,
//! which needs no list of them.

pub mod layout;

mod automation;
pub(crate) mod objref;

use crate::com::HRESULT;
use layout::{Array, Corr, Extent, Method, Param, Pointer, Save, Struct, Ty, Union};

/// `HRESULT_FROM_WIN32(RPC_X_BAD_STUB_DATA)`: the bytes do not match the method's layout.
pub(crate) const BAD_STUB_DATA: HRESULT = 0x800706F7_u32 as HRESULT;
/// `HRESULT_FROM_WIN32(RPC_S_INVALID_BOUND)`: a count beyond its bound.
pub(crate) const INVALID_BOUND: HRESULT = 0x800706C6_u32 as HRESULT;
/// `HRESULT_FROM_WIN32(RPC_S_PROCNUM_OUT_OF_RANGE)`: the interface has no such method.
pub(crate) const PROCNUM_OUT_OF_RANGE: HRESULT = 0x800706D1_u32 as HRESULT;

/// The bound of every array whose count a peer chooses, unless the IDL's bounds say otherwise:
/// 65,536 elements (tools/gen-header writes each array's bound into its layout).
#[cfg(any(test, feature = "fuzzing"))]
pub(crate) const DEFAULT_BOUND: u32 = 65_536;

/// How deep VARIANTs may nest: a VARIANT holding a SAFEARRAY of VARIANTs is two levels.
pub(crate) const MAX_VARIANT_DEPTH: u32 = 4;

/// `NDR_LOCAL_DATA_REPRESENTATION`: little-endian integers, ASCII, IEEE floating point.
const LOCAL_DATA_REPRESENTATION: u32 = 0x10;

/// Values kept while a message is read (the generator assigns at most this many per method).
pub(crate) const MAX_SLOTS: usize = 16;
/// Fields a structure may have (the generator refuses more).
pub(crate) const MAX_FIELDS: usize = 32;
/// Comparisons with a value that comes later in the message, waiting at once (distinct ones).
const MAX_PENDING: usize = 8;

/// Words of [`Context`] (the generator refuses a method whose reply needs more).
pub(crate) const CONTEXT_WORDS: usize = 8;

type Check = Result<(), HRESULT>;

/// The runtime that will read the message, where runtimes read NDR differently.
///
/// Windows' rpcrt4 and oleaut32 read NDR as C706, MS-RPCE, MS-DCOM and MS-OAUT specify it. Wine's
/// depart from it in places a message cannot show, so a message is checked as its reader will read
/// it, and what that reader would misread is refused:
///
/// - an interface pointer: NDR's `MInterfacePointer` (a referent ID, the conformance, `ulCntData`,
///   the OBJREF) or Wine's (a byte count, the OBJREF): [`objref`];
/// - the body of a BSTR or SAFEARRAY pointer marshalled by the NDR engine: at its own alignment (4) or
///   at 8 (Wine's `NdrUserMarshalUnmarshall`);
/// - a SAFEARRAY of BSTRs or VARIANTs: referent IDs, then the elements (NDR), or the elements only
///   (Wine's oleaut32); a SAFEARRAY without data: no conformance (NDR) or a conformance still
///   (Wine).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dialect {
    /// Windows' rpcrt4 and oleaut32.
    Ndr,
    /// Wine's rpcrt4 and oleaut32.
    Wine,
}

/// What a reply check needs to know of its request: the values of the `[in]` parameters the reply's
/// counts and `iid_is` name ([`layout::Method::context`]), in order; a GUID takes four words.
///
/// cbindgen:ignore
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Context(pub [u32; CONTEXT_WORDS]);

impl Context {
    /// A context of these words (the rest 0).
    #[cfg(any(test, feature = "fuzzing"))]
    pub fn of(words: &[u32]) -> Context {
        let mut c = Context::default();
        for (to, from) in c.0.iter_mut().zip(words) {
            *to = *from;
        }
        c
    }
}

/// The method at vtable index `method` of `iface`.
fn method_of(iface: &'static layout::Interface, method: u32) -> Result<&'static Method, HRESULT> {
    if !(3..iface.vtable).contains(&method) {
        return Err(PROCNUM_OUT_OF_RANGE);
    }
    iface.methods.get(method as usize - 3).ok_or(PROCNUM_OUT_OF_RANGE)
}

/// What every message must be before its bytes are read: in the local data representation, and at an
/// 8-byte boundary when it has something aligned to 8.
fn readable(align8: bool, buf: &[u8], drep: u32) -> Check {
    if drep & 0xFFFF != LOCAL_DATA_REPRESENTATION {
        return Err(BAD_STUB_DATA);
    }
    if align8 && buf.as_ptr() as usize % 8 != 0 {
        return Err(BAD_STUB_DATA);
    }
    Ok(())
}

/// Checks a request for `method` (its vtable index) of `iface` before the stub unmarshals it, and
/// returns what the reply check will need of it.
pub fn check_request(
    iface: &'static layout::Interface,
    method: u32,
    buf: &[u8],
    drep: u32,
    dialect: Dialect,
) -> Result<Context, HRESULT> {
    let m = method_of(iface, method)?;
    readable(m.request_align8, buf, drep)?;
    let mut w = Walk::new(buf, dialect);
    for p in m.request {
        w.param(p)?;
        if let Save::Int(slot) = p.save {
            for &(s, bound) in m.bounds {
                if s == slot && w.slots.get(usize::from(slot)).is_some_and(|&v| v > bound) {
                    return Err(INVALID_BOUND);
                }
            }
        }
    }
    w.finish()?;
    Ok(w.context(m))
}

/// Checks a reply to `method` of `iface` before the proxy unmarshals it into the caller's memory.
/// `context` is what [`check_request`] returned for the request.
pub fn check_reply(
    iface: &'static layout::Interface,
    method: u32,
    context: &Context,
    buf: &[u8],
    drep: u32,
    dialect: Dialect,
) -> Check {
    let m = method_of(iface, method)?;
    readable(m.reply_align8, buf, drep)?;
    let mut w = Walk::new(buf, dialect);
    w.preload(m, context);
    for p in m.reply {
        w.param(p)?;
    }
    w.finish()
}

/// A value a count names, as far as the message has told it.
#[derive(Clone, Copy)]
enum Value {
    /// Known: the value, and whether it came from this message (not from the request's context).
    Known(u32, bool),
    /// A slot the message sets later.
    Later(u8),
}

/// The first or the second walk over a construct's flat part.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Pass {
    /// Checks the flat part (referent IDs, counts, values).
    Flat,
    /// Walks it again to read the pointees, at the message's cursor, in the order of their pointers.
    Deferred,
}

/// The fields of the structure being read, for the counts that name them.
struct Frame {
    fields: [u32; MAX_FIELDS],
}

/// One message being read.
struct Walk<'a> {
    buf: &'a [u8],
    /// Where the next top-level item, or the next deferred pointee, starts.
    pos: usize,
    dialect: Dialect,
    slots: [u32; MAX_SLOTS],
    /// Bit per slot: its value is known.
    known: u32,
    /// Bit per slot: its value came from the request's context.
    from_context: u32,
    /// (slot, value): the slot must have this value when the message sets it.
    pending: [(u8, u32); MAX_PENDING],
    pending_len: usize,
}

impl<'a> Walk<'a> {
    fn new(buf: &'a [u8], dialect: Dialect) -> Self {
        Walk {
            buf,
            pos: 0,
            dialect,
            slots: [0; MAX_SLOTS],
            known: 0,
            from_context: 0,
            pending: [(0, 0); MAX_PENDING],
            pending_len: 0,
        }
    }

    // ---- Reading, never past the end ----

    fn skip(&self, at: &mut usize, n: usize) -> Check {
        let end = at.checked_add(n).ok_or(BAD_STUB_DATA)?;
        if end > self.buf.len() {
            return Err(BAD_STUB_DATA);
        }
        *at = end;
        Ok(())
    }

    /// Pads `at` to a multiple of `n` (1, 2, 4 or 8: a power of two), relative to the message's start.
    fn align(&self, at: &mut usize, n: usize) -> Check {
        let pad = at.wrapping_neg() & n.wrapping_sub(1);
        self.skip(at, pad)
    }

    fn bytes(&self, at: &mut usize, n: usize) -> Result<&'a [u8], HRESULT> {
        let from = *at;
        self.skip(at, n)?;
        Ok(&self.buf[from..from + n])
    }

    /// An unsigned value of `size` bytes (1, 2 or 4) at its alignment.
    fn uint(&self, at: &mut usize, size: usize) -> Result<u32, HRESULT> {
        self.align(at, size)?;
        let b = self.bytes(at, size)?;
        Ok(match *b {
            [a] => u32::from(a),
            [a, b] => u32::from(u16::from_le_bytes([a, b])),
            [a, b, c, d] => u32::from_le_bytes([a, b, c, d]),
            _ => return Err(BAD_STUB_DATA),
        })
    }

    fn u32(&self, at: &mut usize) -> Result<u32, HRESULT> {
        self.uint(at, 4)
    }

    fn u16(&self, at: &mut usize) -> Result<u16, HRESULT> {
        self.uint(at, 2).map(|v| v as u16)
    }

    /// An NDR enum16: MIDL's stubs refuse values above 0x7FFF.
    fn enum16(&self, at: &mut usize) -> Result<u32, HRESULT> {
        let v = self.uint(at, 2)?;
        if v > 0x7FFF {
            return Err(BAD_STUB_DATA);
        }
        Ok(v)
    }

    // ---- The values counts name ----

    fn value(&self, c: Corr, frame: Option<&Frame>) -> Value {
        match c {
            Corr::Slot(s) => {
                let bit = 1u32 << (s & 31);
                match self.slots.get(usize::from(s)) {
                    Some(&v) if self.known & bit != 0 => Value::Known(v, self.from_context & bit == 0),
                    _ => Value::Later(s),
                }
            }
            Corr::Field(i) => {
                let v = frame.and_then(|f| f.fields.get(usize::from(i))).copied().unwrap_or(0);
                Value::Known(v, true)
            }
        }
    }

    /// Remembers that `slot` must be `value` when the message sets it (once per distinct pair; in the
    /// second walk over a construct nothing new is learnt).
    fn pend(&mut self, slot: u8, value: u32, pass: Pass) -> Check {
        if pass == Pass::Deferred || self.pending[..self.pending_len].contains(&(slot, value)) {
            return Ok(());
        }
        let free = self.pending.get_mut(self.pending_len).ok_or(BAD_STUB_DATA)?;
        *free = (slot, value);
        self.pending_len += 1;
        Ok(())
    }

    fn set(&mut self, slot: u8, value: u32) -> Check {
        let s = usize::from(slot);
        if s >= MAX_SLOTS {
            return Err(BAD_STUB_DATA);
        }
        if self.pending[..self.pending_len]
            .iter()
            .any(|&(ps, pv)| ps == slot && pv != value)
        {
            return Err(BAD_STUB_DATA);
        }
        self.slots[s] = value;
        self.known |= 1 << s;
        self.from_context &= !(1 << s);
        Ok(())
    }

    /// The message is over: every value a count was compared with in advance has arrived.
    fn finish(&self) -> Check {
        let all_known = self.pending[..self.pending_len]
            .iter()
            .all(|&(s, _)| self.known & (1 << (s & 31)) != 0);
        if all_known {
            Ok(())
        } else {
            Err(BAD_STUB_DATA)
        }
    }

    fn context(&self, m: &Method) -> Context {
        let mut c = Context::default();
        let mut words = c.0.iter_mut();
        for save in m.context {
            let (from, n) = match *save {
                Save::Int(s) => (usize::from(s), 1),
                Save::Guid(s) => (usize::from(s), 4),
                Save::None => continue,
            };
            for v in self.slots.iter().skip(from).take(n) {
                if let Some(w) = words.next() {
                    *w = *v;
                }
            }
        }
        c
    }

    fn preload(&mut self, m: &Method, context: &Context) {
        let mut words = context.0.iter();
        for save in m.context {
            let (from, n) = match *save {
                Save::Int(s) => (usize::from(s), 1),
                Save::Guid(s) => (usize::from(s), 4),
                Save::None => continue,
            };
            for s in from..(from + n).min(MAX_SLOTS) {
                if let Some(&w) = words.next() {
                    self.slots[s] = w;
                    self.known |= 1 << s;
                    self.from_context |= 1 << s;
                }
            }
        }
    }

    // ---- Parameters and pointees ----

    /// One top-level parameter; its value kept when a count names it.
    fn param(&mut self, p: &Param) -> Check {
        let mut ty = p.ty;
        if p.save != Save::None {
            // A value, or [ref] pointers to one (no wire representation at the top).
            while let Ty::Pointer(ptr) = ty {
                if ptr.unique {
                    return Err(BAD_STUB_DATA);
                }
                ty = ptr.target;
            }
        }
        let mut at = self.pos;
        match (p.save, ty) {
            (Save::Int(s), Ty::Base(n)) if n <= 4 => {
                let v = self.uint(&mut at, usize::from(n))?;
                self.pos = at;
                self.set(s, v)
            }
            (Save::Int(s), Ty::Enum16) => {
                let v = self.enum16(&mut at)?;
                self.pos = at;
                self.set(s, v)
            }
            (Save::Guid(s), Ty::Guid) => {
                self.align(&mut at, 4)?;
                let b = self.bytes(&mut at, 16)?;
                self.pos = at;
                for (i, w) in b.chunks_exact(4).enumerate() {
                    self.set(s + i as u8, u32::from_le_bytes([w[0], w[1], w[2], w[3]]))?;
                }
                Ok(())
            }
            (Save::None, _) => self.top(ty, None),
            _ => Err(BAD_STUB_DATA),
        }
    }

    /// A value that is not embedded in a construct: a top-level parameter, or a pointee.
    fn top(&mut self, ty: Ty, frame: Option<&Frame>) -> Check {
        let mut at = self.pos;
        match ty {
            Ty::Pointer(p) => {
                if p.unique {
                    let id = self.u32(&mut at)?;
                    self.pos = at;
                    if id == 0 {
                        return self.null(p.target, frame, Pass::Flat);
                    }
                }
                self.top(p.target, frame)
            }
            Ty::Str(unit) => {
                self.string(&mut at, usize::from(unit))?;
                self.pos = at;
                Ok(())
            }
            Ty::Interface(iid) => {
                self.interface_pointer(&mut at, iid)?;
                self.pos = at;
                Ok(())
            }
            Ty::Bstr | Ty::Variant | Ty::SafeArray => {
                self.prefix(&mut at)?;
                self.pos = at;
                self.user_body(ty)
            }
            _ => {
                // A construct: its flat part, then its deferred pointees in order.
                let start = self.pos;
                let mut at = start;
                self.flat(ty, &mut at, frame, Pass::Flat)?;
                self.pos = at;
                if deferred(ty) {
                    let mut again = start;
                    self.flat(ty, &mut again, frame, Pass::Deferred)?;
                }
                Ok(())
            }
        }
    }

    /// A NULL pointer to an array sized by a value of this message: the value must be 0.
    fn null(&mut self, target: Ty, frame: Option<&Frame>, pass: Pass) -> Check {
        if let Ty::Array(Array {
            size: Extent::Conformant(c),
            ..
        }) = target
        {
            match self.value(*c, frame) {
                Value::Known(v, true) if v != 0 => return Err(BAD_STUB_DATA),
                Value::Known(..) => {}
                Value::Later(s) => self.pend(s, 0, pass)?,
            }
        }
        Ok(())
    }

    /// A value inside a construct, at `at`. In [`Pass::Deferred`] the pointees of its pointers are read
    /// at the message's cursor.
    fn flat(&mut self, ty: Ty, at: &mut usize, frame: Option<&Frame>, pass: Pass) -> Check {
        match ty {
            Ty::Base(n) => {
                let n = usize::from(n);
                self.align(at, n)?;
                self.skip(at, n)
            }
            Ty::Enum16 => self.enum16(at).map(|_| ()),
            Ty::Guid => {
                self.align(at, 4)?;
                self.skip(at, 16)
            }
            Ty::Empty => Ok(()),
            // The generator puts these at the top or behind a pointer only.
            Ty::Str(_) | Ty::Interface(_) => Err(BAD_STUB_DATA),
            Ty::Bstr | Ty::Variant | Ty::SafeArray => {
                self.prefix(at)?;
                if pass == Pass::Deferred {
                    self.user_body(ty)?;
                }
                Ok(())
            }
            Ty::Pointer(p) => self.pointer(p, at, frame, pass),
            Ty::Struct(s) => self.structure(s, at, pass),
            Ty::Array(a) => self.array(a, at, frame, pass),
            Ty::Union(u) => self.union(u, at, frame, pass),
        }
    }

    /// An embedded pointer: its referent ID at `at`; its pointee, in [`Pass::Deferred`], at the
    /// message's cursor.
    fn pointer(&mut self, p: &Pointer, at: &mut usize, frame: Option<&Frame>, pass: Pass) -> Check {
        let id = self.u32(at)?;
        if p.unique && id == 0 {
            if let (Ty::Array(_), Pass::Flat) = (p.target, pass) {
                return self.null(p.target, frame, pass);
            }
            return Ok(());
        }
        if pass == Pass::Deferred {
            self.top(p.target, frame)?;
        }
        Ok(())
    }

    fn structure(&mut self, s: &Struct, at: &mut usize, pass: Pass) -> Check {
        self.align(at, usize::from(s.align))?;
        if s.plain != 0 {
            return self.skip(at, s.plain as usize);
        }
        // Walked again for pointees it does not have: its size, checked the first time.
        if pass == Pass::Deferred && !s.deferred && s.size != 0 {
            return self.skip(at, s.size as usize);
        }
        let mut frame = Frame {
            fields: [0; MAX_FIELDS],
        };
        for (i, &f) in s.fields.iter().enumerate() {
            // The common fields here, the rest through `flat`.
            let v = match f {
                Ty::Base(n) if n <= 4 => self.uint(at, usize::from(n))?,
                Ty::Enum16 => self.enum16(at)?,
                Ty::Pointer(p) => {
                    self.pointer(p, at, Some(&frame), pass)?;
                    continue;
                }
                other => {
                    self.flat(other, at, Some(&frame), pass)?;
                    continue;
                }
            };
            if let Some(field) = frame.fields.get_mut(i) {
                *field = v;
            }
        }
        Ok(())
    }

    fn array(&mut self, a: &Array, at: &mut usize, frame: Option<&Frame>, pass: Pass) -> Check {
        let max = match a.size {
            Extent::Fixed(n) => n,
            Extent::Conformant(c) => {
                let value = self.value(c, frame);
                if let Value::Known(v, true) = value {
                    if v > a.bound {
                        return Err(INVALID_BOUND);
                    }
                }
                let max = self.u32(at)?;
                match value {
                    Value::Known(v, _) if v != max => return Err(BAD_STUB_DATA),
                    Value::Known(..) => {}
                    Value::Later(s) => {
                        if max > a.bound {
                            return Err(INVALID_BOUND);
                        }
                        self.pend(s, max, pass)?;
                    }
                }
                max
            }
        };
        let count = match a.length {
            None => max,
            Some(c) => {
                let offset = self.u32(at)?;
                let actual = self.u32(at)?;
                if offset != 0 || actual > max {
                    return Err(BAD_STUB_DATA);
                }
                match self.value(c, frame) {
                    Value::Known(v, _) if v != actual => return Err(BAD_STUB_DATA),
                    Value::Known(..) => {}
                    Value::Later(s) => self.pend(s, actual, pass)?,
                }
                actual
            }
        };
        self.align(at, usize::from(a.align))?;
        if a.plain != 0 {
            let bytes = (count as usize).checked_mul(a.plain as usize).ok_or(BAD_STUB_DATA)?;
            return self.skip(at, bytes);
        }
        for _ in 0..count {
            self.flat(a.elem, at, frame, pass)?;
        }
        Ok(())
    }

    fn union(&mut self, u: &Union, at: &mut usize, frame: Option<&Frame>, pass: Pass) -> Check {
        let d = self.uint(at, usize::from(u.switch_size))?;
        match self.value(u.switch, frame) {
            Value::Known(v, _) if v != d => return Err(BAD_STUB_DATA),
            Value::Known(..) => {}
            Value::Later(s) => self.pend(s, d, pass)?,
        }
        let arm = u
            .arms
            .iter()
            .find(|(case, _)| *case == d)
            .map(|(_, ty)| *ty)
            .or(u.default)
            .ok_or(BAD_STUB_DATA)?;
        self.flat(arm, at, frame, pass)
    }

    /// A `[string]` pointee (conformant and varying): maximum count = actual count >= 1, offset 0,
    /// every character present, the last one NUL. MIDL and widl marshal a string so; anything else
    /// would let the maximum size an allocation the bytes do not back.
    fn string(&self, at: &mut usize, unit: usize) -> Check {
        let max = self.u32(at)?;
        let offset = self.u32(at)?;
        let actual = self.u32(at)?;
        if max != actual || offset != 0 || actual == 0 || !(unit == 1 || unit == 2) {
            return Err(BAD_STUB_DATA);
        }
        let n = (actual as usize).checked_mul(unit).ok_or(BAD_STUB_DATA)?;
        let text = self.bytes(at, n)?;
        if text[n - unit..].iter().any(|&b| b != 0) {
            return Err(BAD_STUB_DATA);
        }
        Ok(())
    }
}

/// Whether a construct has pointees deferred until after it.
fn deferred(ty: Ty) -> bool {
    match ty {
        Ty::Struct(s) => s.deferred,
        Ty::Array(a) => a.deferred,
        Ty::Union(u) => u.deferred,
        Ty::Pointer(_) | Ty::Bstr | Ty::Variant | Ty::SafeArray => true,
        _ => false,
    }
}

#[cfg(test)]
mod tests;
