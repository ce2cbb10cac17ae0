//! The Automation types of oaidl.idl on the wire: BSTR (MS-OAUT 2.2.23), VARIANT (2.2.29) and SAFEARRAY
//! (2.2.30), each a `[wire_marshal]` type whose wire type is a unique pointer.
//!
//! Where the NDR engine marshals one (a parameter, a structure's field, an array's element), the
//! pointer is a 32-bit prefix in place (Windows and Wine write "User", 0x72657355; Wine's reader
//! ignores its value, so Wine's dialect accepts any, NDR's refuses 0, which its reader could take for
//! NULL) and the body follows like a pointee: at once at the top, after the construct when embedded.
//! The body is aligned to its own alignment (NDR: 8 for a VARIANT, 4 for a BSTR or a SAFEARRAY) or
//! always to 8 (Wine's `NdrUserMarshalUnmarshall`). Inside a VARIANT, oleaut32 marshals the BSTR and
//! SAFEARRAY arms itself, at their own alignment, in both runtimes.
//!
//! What is checked, beyond every byte being there:
//!
//! - BSTR (`FLAGGED_WORD_BLOB`): the conformance equals `clSize`; a NULL BSTR (`cBytes` 0xFFFFFFFF)
//!   has `clSize` 0, any other `clSize` = `cBytes` / 2 rounded up (Wine's oleaut32 allocates
//!   `cBytes` and copies that many bytes from the message).
//! - VARIANT (`wireVARIANTStr`): the union's discriminant is `vt` (`vt` & 0xF000 for an array, as
//!   Windows and Wine write it); `vt` is one of the types an OPC value can have: VT_EMPTY, VT_NULL,
//!   VT_I1, VT_UI1, VT_I2, VT_UI2, VT_BOOL, VT_I4, VT_UI4, VT_INT, VT_UINT, VT_R4, VT_ERROR, VT_I8,
//!   VT_UI8, VT_R8, VT_CY, VT_DATE, VT_DECIMAL, VT_BSTR, or VT_ARRAY of one of the types a SAFEARRAY
//!   carries below. Refused: objects (VT_UNKNOWN, VT_DISPATCH), records, VT_BYREF, VT_VECTOR.
//!   `clSize` and the reserved words are not read by either runtime and not checked.
//! - SAFEARRAY (`wireSAFEARRAY`): the conformance equals `cDims`, 1 <= `cDims` <= [`MAX_DIMS`]; the
//!   union's type (`SF_I1`, `SF_I2`, `SF_I4`, `SF_I8`, `SF_BSTR` or `SF_VARIANT`; no interfaces or
//!   records) agrees with the VARIANT's element type and with the VARTYPE in the high word of
//!   `cLocks` (0 or one of the same size), `cbElements` with the type (1, 2, 4 or 8; 4 or 8 for BSTRs;
//!   16 or 24 for VARIANTs: Wine's oleaut32 copies `cells` x `cbElements` bytes into an array it
//!   allocated for the type); the cell count equals the product of the bounds' `cElements`, counted
//!   without overflow (Wine multiplies in 32 bits and allocates the product), each and the product at
//!   most [`MAX_CELLS`], no bound's upper end beyond 2^31; a NULL data pointer only with no cells; the
//!   data's conformance equals the cell count; the elements, as the reading runtime reads them.

use super::layout::Ty;
use super::{Check, Dialect, Walk, BAD_STUB_DATA, INVALID_BOUND, MAX_VARIANT_DEPTH};

/// The most dimensions a SAFEARRAY may have (SAFEARRAY allows 65,535; an OPC value has one or two).
pub(crate) const MAX_DIMS: u32 = 32;
/// The most cells a SAFEARRAY may have, and the most elements in any of its dimensions. Every cell is
/// on the wire (at least one byte each), so this bounds no allocation the bytes do not back; it keeps
/// the counts far from the 32-bit products the runtimes compute.
pub(crate) const MAX_CELLS: u32 = 1 << 24;

// VARTYPEs (wtypes.h).
const VT_EMPTY: u16 = 0;
const VT_NULL: u16 = 1;
const VT_I2: u16 = 2;
const VT_I4: u16 = 3;
const VT_R4: u16 = 4;
const VT_R8: u16 = 5;
const VT_CY: u16 = 6;
const VT_DATE: u16 = 7;
const VT_BSTR: u16 = 8;
const VT_ERROR: u16 = 10;
const VT_BOOL: u16 = 11;
const VT_VARIANT: u16 = 12;
const VT_DECIMAL: u16 = 14;
const VT_I1: u16 = 16;
const VT_UI1: u16 = 17;
const VT_UI2: u16 = 18;
const VT_UI4: u16 = 19;
const VT_I8: u16 = 20;
const VT_UI8: u16 = 21;
const VT_INT: u16 = 22;
const VT_UINT: u16 = 23;
const VT_ARRAY: u16 = 0x2000;
const VT_TYPEMASK: u16 = 0x0FFF;

// SAFEARRAY union types (MS-OAUT 2.2.8 SF_TYPE).
const SF_I1: u32 = 16;
const SF_I2: u32 = 2;
const SF_I4: u32 = 3;
const SF_I8: u32 = 20;
const SF_BSTR: u32 = 8;
const SF_VARIANT: u32 = 12;

/// The union type a SAFEARRAY of `vt` has, if it is one the checks read.
fn sf_type(vt: u16) -> Option<u32> {
    Some(match vt {
        VT_I1 | VT_UI1 => SF_I1,
        VT_I2 | VT_UI2 | VT_BOOL => SF_I2,
        VT_I4 | VT_UI4 | VT_INT | VT_UINT | VT_R4 | VT_ERROR => SF_I4,
        VT_I8 | VT_UI8 | VT_R8 | VT_CY | VT_DATE => SF_I8,
        VT_BSTR => SF_BSTR,
        VT_VARIANT => SF_VARIANT,
        _ => return None,
    })
}

/// The `cbElements` a SAFEARRAY of this union type may say.
fn element_sizes(sf: u32) -> &'static [u32] {
    match sf {
        SF_I1 => &[1],
        SF_I2 => &[2],
        SF_I4 => &[4],
        SF_I8 => &[8],
        // sizeof(BSTR) on 32- and 64-bit Windows (Wine writes 4 on both).
        SF_BSTR => &[4, 8],
        // The wire size Windows and Wine write (16); sizeof(VARIANT) on 64-bit Windows.
        SF_VARIANT => &[16, 24],
        _ => &[],
    }
}

impl Walk<'_> {
    /// The 32-bit prefix of a `[wire_marshal]` pointer, or the referent ID of a VARIANT's BSTR or
    /// SAFEARRAY arm: never NULL (MS-OAUT marshals even a NULL BSTR as a blob); Wine's reader ignores
    /// the value, Windows' might take 0 for NULL.
    pub(super) fn prefix(&self, at: &mut usize) -> Check {
        let v = self.u32(at)?;
        if v == 0 && self.dialect == Dialect::Ndr {
            return Err(BAD_STUB_DATA);
        }
        Ok(())
    }

    /// The body of a `[wire_marshal]` type the NDR engine marshals, at the message's cursor.
    pub(super) fn user_body(&mut self, ty: Ty) -> Check {
        let mut at = self.pos;
        let align = match (self.dialect, ty) {
            (Dialect::Wine, _) | (Dialect::Ndr, Ty::Variant) => 8,
            (Dialect::Ndr, _) => 4,
        };
        self.align(&mut at, align)?;
        match ty {
            Ty::Bstr => self.blob(&mut at)?,
            Ty::Variant => self.variant(&mut at, 0)?,
            Ty::SafeArray => self.safearray(&mut at, None, 0)?,
            _ => return Err(BAD_STUB_DATA),
        }
        self.pos = at;
        Ok(())
    }

    /// A BSTR's `FLAGGED_WORD_BLOB` (a conformant structure: the conformance first).
    fn blob(&self, at: &mut usize) -> Check {
        let max = self.u32(at)?;
        let bytes = self.u32(at)?;
        let units = self.u32(at)?;
        let expected = if bytes == u32::MAX { 0 } else { bytes / 2 + bytes % 2 };
        if max != units || units != expected {
            return Err(BAD_STUB_DATA);
        }
        self.skip(at, units as usize * 2)
    }

    /// A `wireVARIANTStr` and what its arm points to; `depth` VARIANTs hold this one.
    fn variant(&self, at: &mut usize, depth: u32) -> Check {
        if depth >= MAX_VARIANT_DEPTH {
            return Err(BAD_STUB_DATA);
        }
        self.align(at, 8)?;
        // clSize, rpcReserved.
        self.skip(at, 8)?;
        let vt = self.u16(at)?;
        // wReserved1 to 3.
        self.skip(at, 6)?;
        let switch = self.u32(at)?;
        let expected = if vt & VT_ARRAY != 0 { vt & !VT_TYPEMASK } else { vt };
        if switch != u32::from(expected) {
            return Err(BAD_STUB_DATA);
        }
        if vt & !VT_TYPEMASK == VT_ARRAY {
            let elem = vt & VT_TYPEMASK;
            if sf_type(elem).is_none() {
                return Err(BAD_STUB_DATA);
            }
            self.prefix(at)?;
            return self.safearray(at, Some(elem), depth);
        }
        let (align, size) = match vt {
            VT_EMPTY | VT_NULL => return Ok(()),
            VT_I1 | VT_UI1 => (1, 1),
            VT_I2 | VT_UI2 | VT_BOOL => (2, 2),
            VT_I4 | VT_UI4 | VT_INT | VT_UINT | VT_R4 | VT_ERROR => (4, 4),
            VT_I8 | VT_UI8 | VT_R8 | VT_CY | VT_DATE => (8, 8),
            VT_DECIMAL => (8, 16),
            VT_BSTR => {
                self.prefix(at)?;
                return self.blob(at);
            }
            _ => return Err(BAD_STUB_DATA),
        };
        self.align(at, align)?;
        self.skip(at, size)
    }

    /// A `wirePSAFEARRAY`'s inner pointer and, when not NULL, the `wireSAFEARRAY` with its data;
    /// `elem` the VARIANT's element type, if a VARIANT holds it.
    fn safearray(&self, at: &mut usize, elem: Option<u16>, depth: u32) -> Check {
        if self.u32(at)? == 0 {
            return Ok(());
        }
        let conformance = self.u32(at)?;
        let dims = self.u16(at)?;
        let _features = self.u16(at)?;
        let element_size = self.u32(at)?;
        let locks = self.u32(at)?;
        let sf = self.u32(at)?;
        if u32::from(dims) != conformance || dims == 0 {
            return Err(BAD_STUB_DATA);
        }
        if u32::from(dims) > MAX_DIMS {
            return Err(INVALID_BOUND);
        }
        let array_vt = (locks >> 16) as u16;
        let agrees = |vt: u16| sf_type(vt) == Some(sf);
        if !element_sizes(sf).contains(&element_size)
            || elem.is_some_and(|vt| !agrees(vt))
            || (array_vt != 0 && !agrees(array_vt))
        {
            return Err(BAD_STUB_DATA);
        }
        // The union's arm: Size (the cell count) and the data pointer.
        let cells = self.u32(at)?;
        let data = self.u32(at)?;
        let mut product: u64 = 1;
        for _ in 0..dims {
            let elements = self.u32(at)?;
            let lower = self.u32(at)? as i32;
            if elements > MAX_CELLS {
                return Err(INVALID_BOUND);
            }
            if i64::from(lower) + i64::from(elements) > i64::from(i32::MAX) + 1 {
                return Err(BAD_STUB_DATA);
            }
            product *= u64::from(elements);
            if product > u64::from(MAX_CELLS) {
                return Err(INVALID_BOUND);
            }
        }
        if product != u64::from(cells) {
            return Err(BAD_STUB_DATA);
        }
        if data == 0 {
            if cells != 0 {
                return Err(BAD_STUB_DATA);
            }
            // Wine's oleaut32 writes and reads the data's conformance even without data.
            if self.dialect == Dialect::Wine && self.u32(at)? != 0 {
                return Err(BAD_STUB_DATA);
            }
            return Ok(());
        }
        if self.u32(at)? != cells {
            return Err(BAD_STUB_DATA);
        }
        let cells = cells as usize;
        match sf {
            SF_I1 => self.skip(at, cells),
            SF_I2 | SF_I4 | SF_I8 => {
                let size = element_size as usize;
                self.align(at, size)?;
                self.skip(at, cells * size)
            }
            SF_BSTR | SF_VARIANT => {
                // NDR: an array of unique pointers, then their pointees; Wine's oleaut32: the pointees.
                if self.dialect == Dialect::Ndr {
                    for _ in 0..cells {
                        self.prefix(at)?;
                    }
                }
                for _ in 0..cells {
                    if sf == SF_BSTR {
                        self.blob(at)?;
                    } else {
                        self.variant(at, depth + 1)?;
                    }
                }
                Ok(())
            }
            _ => Err(BAD_STUB_DATA),
        }
    }
}
