//! NDR messages built by hand, to the rules: every item aligned to its size from the message's start,
//! little-endian; the Automation types as MS-OAUT lays them out, in either runtime's dialect.

use super::{Dialect, USER};

/// A message being built.
#[derive(Clone, Debug, Default)]
pub(crate) struct Msg(pub Vec<u8>);

/// A copy of a message at an 8-byte boundary (the runtime's buffers are; a method that aligns to 8
/// needs it), or at a chosen distance past one.
pub(crate) struct Aligned {
    buf: Vec<u8>,
    at: usize,
    len: usize,
}

impl Aligned {
    pub(crate) fn bytes(&self) -> &[u8] {
        &self.buf[self.at..self.at + self.len]
    }
}

/// A SAFEARRAY's data.
#[derive(Clone, Debug)]
pub(crate) enum SaData {
    /// Elements of 1, 2, 4 or 8 bytes each, as bytes.
    Plain(Vec<u8>),
    Bstrs(Vec<Option<String>>),
    Variants(Vec<V>),
    /// A NULL data pointer.
    Null,
}

/// A SAFEARRAY (MS-OAUT 2.2.30.10): the element type, the bounds (cElements, lLbound) and the data.
#[derive(Clone, Debug)]
pub(crate) struct Sa {
    pub vt: u16,
    pub bounds: Vec<(u32, i32)>,
    pub data: SaData,
}

/// A VARIANT's value.
#[derive(Clone, Debug)]
pub(crate) enum V {
    Empty,
    Null,
    I1(i8),
    Ui1(u8),
    I2(i16),
    Bool(bool),
    I4(i32),
    Int(i32),
    R4(f32),
    Error(i32),
    I8(i64),
    R8(f64),
    Cy(i64),
    Date(f64),
    Decimal([u8; 16]),
    Bstr(Option<String>),
    Array(Option<Sa>),
    /// Any VARTYPE and discriminant, with these bytes after the header (for what is refused).
    Raw(u16, u32, Vec<u8>),
}

pub(crate) const VT_ARRAY: u16 = 0x2000;

/// The union type of a SAFEARRAY of `vt` (MS-OAUT 2.2.8).
pub(crate) fn sf_type(vt: u16) -> u32 {
    match vt {
        16 | 17 => 16,                  // VT_I1, VT_UI1: SF_I1
        2 | 18 | 11 => 2,               // VT_I2, VT_UI2, VT_BOOL: SF_I2
        3 | 19 | 22 | 23 | 4 | 10 => 3, // VT_I4, VT_UI4, VT_INT, VT_UINT, VT_R4, VT_ERROR: SF_I4
        20 | 21 | 5 | 6 | 7 => 20,      // VT_I8, VT_UI8, VT_R8, VT_CY, VT_DATE: SF_I8
        8 => 8,                         // SF_BSTR
        12 => 12,                       // SF_VARIANT
        _ => 0,
    }
}

/// The element size a SAFEARRAY of `vt` says (`cbElements`): what Windows and Wine write.
pub(crate) fn element_size(vt: u16) -> u32 {
    match sf_type(vt) {
        16 => 1,
        2 => 2,
        3 => 4,
        20 => 8,
        8 => 4,
        12 => 16,
        _ => 0,
    }
}

impl Msg {
    pub(crate) fn aligned(&self) -> Aligned {
        self.at(0)
    }

    /// A copy that starts `skew` bytes past an 8-byte boundary.
    pub(crate) fn at(&self, skew: usize) -> Aligned {
        let mut buf = vec![0u8; self.0.len() + 16];
        let at = (8 - buf.as_ptr() as usize % 8) % 8 + skew;
        buf[at..at + self.0.len()].copy_from_slice(&self.0);
        Aligned {
            buf,
            at,
            len: self.0.len(),
        }
    }

    /// Pads to a multiple of `n` with `0xEE` (NDR's padding is anything).
    pub(crate) fn align(mut self, n: usize) -> Self {
        while self.0.len() % n != 0 {
            self.0.push(0xEE);
        }
        self
    }

    pub(crate) fn raw(mut self, b: &[u8]) -> Self {
        self.0.extend_from_slice(b);
        self
    }

    pub(crate) fn u8(self, v: u8) -> Self {
        self.raw(&[v])
    }

    pub(crate) fn u16(self, v: u16) -> Self {
        self.align(2).raw(&v.to_le_bytes())
    }

    pub(crate) fn u32(self, v: u32) -> Self {
        self.align(4).raw(&v.to_le_bytes())
    }

    pub(crate) fn u64(self, v: u64) -> Self {
        self.align(8).raw(&v.to_le_bytes())
    }

    /// A GUID: `Data1`, `Data2`, `Data3` little-endian, then `Data4`; these 16 bytes as given.
    pub(crate) fn guid(self, g: [u8; 16]) -> Self {
        self.align(4).raw(&g)
    }

    /// A conformant varying string of UTF-16 units, NUL included.
    pub(crate) fn wstr(self, text: &str) -> Self {
        let units: Vec<u16> = text.encode_utf16().chain([0]).collect();
        let n = units.len() as u32;
        let mut m = self.u32(n).u32(0).u32(n);
        for u in units {
            m = m.raw(&u.to_le_bytes());
        }
        m
    }

    /// A conformant varying string of bytes, NUL included.
    pub(crate) fn cstr(self, text: &str) -> Self {
        let n = text.len() as u32 + 1;
        self.u32(n).u32(0).u32(n).raw(text.as_bytes()).u8(0)
    }

    /// A BSTR's FLAGGED_WORD_BLOB (MS-OAUT 2.2.23.1): the conformance, cBytes, clSize, the units.
    pub(crate) fn blob(self, text: Option<&str>) -> Self {
        match text {
            None => self.u32(0).u32(u32::MAX).u32(0),
            Some(t) => {
                let units: Vec<u16> = t.encode_utf16().collect();
                let n = units.len() as u32;
                let mut m = self.u32(n).u32(n * 2).u32(n);
                for u in units {
                    m = m.raw(&u.to_le_bytes());
                }
                m
            }
        }
    }

    /// A `[wire_marshal]` type as the NDR engine writes it at the top of a message: the "User"
    /// prefix, then the body at 8 (Wine) or at its own alignment (NDR: 4 for a BSTR or SAFEARRAY).
    pub(crate) fn user(self, dialect: Dialect, natural: usize, body: impl FnOnce(Msg) -> Msg) -> Self {
        let m = self.u32(USER);
        body(m.align(if dialect == Dialect::Wine { 8 } else { natural }))
    }

    /// A wireVARIANTStr (MS-OAUT 2.2.29.1) and what its arm points to.
    pub(crate) fn variant(self, v: &V, dialect: Dialect) -> Self {
        let (vt, switch) = vt_of(v);
        // A DECIMAL overlays the whole VARIANT: its scale, sign and high word are the reserved words.
        let reserved = match v {
            V::Decimal(d) => [d[2], d[3], d[4], d[5], d[6], d[7]],
            _ => [0; 6],
        };
        let m = self.align(8).u32(0xC1).u32(0).u16(vt).raw(&reserved).u32(switch);
        match v {
            V::Empty | V::Null => m,
            V::I1(x) => m.u8(*x as u8),
            V::Ui1(x) => m.u8(*x),
            V::I2(x) => m.u16(*x as u16),
            V::Bool(x) => m.u16(if *x { 0xFFFF } else { 0 }),
            V::I4(x) | V::Int(x) | V::Error(x) => m.u32(*x as u32),
            V::R4(x) => m.u32(x.to_bits()),
            V::I8(x) | V::Cy(x) => m.u64(*x as u64),
            V::R8(x) | V::Date(x) => m.u64(x.to_bits()),
            V::Decimal(d) => m.align(8).raw(d),
            V::Bstr(t) => m.u32(USER).blob(t.as_deref()),
            V::Array(sa) => m.u32(USER).safearray(sa.as_ref(), dialect),
            V::Raw(_, _, bytes) => m.raw(bytes),
        }
    }

    /// A wirePSAFEARRAY's pointee: the inner pointer, then the wireSAFEARRAY and its data.
    pub(crate) fn safearray(self, sa: Option<&Sa>, dialect: Dialect) -> Self {
        let Some(sa) = sa else { return self.u32(0) };
        let cells: u32 = if sa.bounds.iter().any(|b| b.0 == 0) {
            0
        } else {
            // Multiplied in 32 bits, as Windows and Wine do.
            sa.bounds.iter().fold(1u32, |a, b| a.wrapping_mul(b.0))
        };
        let dims = sa.bounds.len() as u32;
        let mut m = self
            .u32(1)
            .u32(dims)
            .u16(dims as u16)
            .u16(0x0080)
            .u32(element_size(sa.vt))
            .u32(u32::from(sa.vt) << 16)
            .u32(sf_type(sa.vt))
            .u32(cells)
            .u32(if matches!(sa.data, SaData::Null) { 0 } else { 2 });
        for (n, lower) in &sa.bounds {
            m = m.u32(*n).u32(*lower as u32);
        }
        match &sa.data {
            SaData::Null => {
                if dialect == Dialect::Wine {
                    m = m.u32(cells);
                }
                m
            }
            SaData::Plain(bytes) => {
                let size = element_size(sa.vt) as usize;
                m.u32(cells).align(size).raw(bytes)
            }
            SaData::Bstrs(items) => {
                m = m.u32(cells);
                if dialect == Dialect::Ndr {
                    for _ in items {
                        m = m.u32(USER);
                    }
                }
                for t in items {
                    m = m.blob(t.as_deref());
                }
                m
            }
            SaData::Variants(items) => {
                m = m.u32(cells);
                if dialect == Dialect::Ndr {
                    for _ in items {
                        m = m.u32(USER);
                    }
                }
                for v in items {
                    m = m.variant(v, dialect);
                }
                m
            }
        }
    }
}

/// A VARIANT's `vt` and union discriminant.
pub(crate) fn vt_of(v: &V) -> (u16, u32) {
    let vt = match v {
        V::Empty => 0,
        V::Null => 1,
        V::I1(_) => 16,
        V::Ui1(_) => 17,
        V::I2(_) => 2,
        V::Bool(_) => 11,
        V::I4(_) => 3,
        V::Int(_) => 22,
        V::R4(_) => 4,
        V::Error(_) => 10,
        V::I8(_) => 20,
        V::R8(_) => 5,
        V::Cy(_) => 6,
        V::Date(_) => 7,
        V::Decimal(_) => 14,
        V::Bstr(_) => 8,
        V::Array(sa) => VT_ARRAY | sa.as_ref().map_or(3, |s| s.vt),
        V::Raw(vt, switch, _) => return (*vt, *switch),
    };
    (
        vt,
        if vt & VT_ARRAY != 0 {
            u32::from(vt & 0xF000)
        } else {
            u32::from(vt)
        },
    )
}
