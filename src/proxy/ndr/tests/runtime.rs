//! The Automation types as the runtime's oleaut32 marshals them (`VARIANT_UserMarshal`,
//! `BSTR_UserMarshal`, `LPSAFEARRAY_UserMarshal`, framed as the NDR engine frames them: the "User"
//! prefix, the body at 8), under Wine in the stages that run these tests (x64 and x86): every VARIANT an
//! OPC value can be, and SAFEARRAYs of every element type. The checks pass what the runtime writes
//! (Wine's dialect) and refuse every proper prefix of it; the messages the construct tests build have
//! the runtime's layout (the same length), and the runtime's unmarshaller reads them back as the
//! value they were built from (checked under Wine, whose unmarshaller needs no stub message).

use core::ffi::c_void;

use super::build::{Msg, Sa, SaData, V};
use super::*;

type Bstr = *mut u16;

/// A VARIANT: `vt`, three reserved words, then 8 (x86) or 16 (x64) bytes; aligned to 8.
#[repr(C, align(8))]
#[derive(Clone, Copy)]
struct Variant {
    bytes: [u8; 8 + 2 * core::mem::size_of::<usize>()],
}

#[repr(C)]
struct SafeArrayBound {
    elements: u32,
    lower: i32,
}

#[link(name = "oleaut32")]
extern "system" {
    fn VARIANT_UserSize(flags: *mut u32, start: u32, v: *mut Variant) -> u32;
    fn VARIANT_UserMarshal(flags: *mut u32, buf: *mut u8, v: *mut Variant) -> *mut u8;
    fn VARIANT_UserUnmarshal(flags: *mut u32, buf: *mut u8, v: *mut Variant) -> *mut u8;
    fn BSTR_UserSize(flags: *mut u32, start: u32, b: *mut Bstr) -> u32;
    fn BSTR_UserMarshal(flags: *mut u32, buf: *mut u8, b: *mut Bstr) -> *mut u8;
    fn LPSAFEARRAY_UserSize(flags: *mut u32, start: u32, sa: *mut *mut c_void) -> u32;
    fn LPSAFEARRAY_UserMarshal(flags: *mut u32, buf: *mut u8, sa: *mut *mut c_void) -> *mut u8;
    fn SysAllocStringLen(s: *const u16, n: u32) -> Bstr;
    fn SysFreeString(b: Bstr);
    fn SafeArrayCreate(vt: u16, dims: u32, bounds: *const SafeArrayBound) -> *mut c_void;
    fn SafeArrayAccessData(sa: *mut c_void, data: *mut *mut c_void) -> i32;
    fn SafeArrayUnaccessData(sa: *mut c_void) -> i32;
    fn SafeArrayPutElement(sa: *mut c_void, indices: *const i32, v: *const c_void) -> i32;
    fn SafeArrayDestroy(sa: *mut c_void) -> i32;
    fn VariantClear(v: *mut Variant) -> i32;
}

/// `MAKELONG(MSHCTX_DIFFERENTMACHINE, NDR_LOCAL_DATA_REPRESENTATION)`.
const FLAGS: u32 = 0x0010_0002;

fn bstr(text: &str) -> Bstr {
    let units: Vec<u16> = text.encode_utf16().collect();
    // SAFETY: `units` is readable for its length.
    let b = unsafe { SysAllocStringLen(units.as_ptr(), units.len() as u32) };
    assert!(!b.is_null());
    b
}

/// A SAFEARRAY of one dimension (or equal ones) holding `sa`'s data.
fn safearray(sa: &Sa) -> *mut c_void {
    let bounds: Vec<SafeArrayBound> = sa
        .bounds
        .iter()
        .map(|&(elements, lower)| SafeArrayBound { elements, lower })
        .collect();
    // SAFETY: `bounds` holds the dimensions.
    let psa = unsafe { SafeArrayCreate(sa.vt, bounds.len() as u32, bounds.as_ptr()) };
    assert!(!psa.is_null());
    match &sa.data {
        SaData::Plain(bytes) => {
            let mut data = core::ptr::null_mut();
            // SAFETY: the array holds `bytes.len()` bytes of data (its cells times their size).
            unsafe {
                assert_eq!(SafeArrayAccessData(psa, &mut data), 0);
                core::ptr::copy_nonoverlapping(bytes.as_ptr(), data.cast::<u8>(), bytes.len());
                SafeArrayUnaccessData(psa);
            }
        }
        SaData::Bstrs(items) => {
            for (i, t) in items.iter().enumerate() {
                let b = t.as_deref().map_or(core::ptr::null_mut(), bstr);
                let index = sa.bounds[0].1 + i as i32;
                // SAFETY: a one-dimensional array of BSTRs; PutElement copies the string.
                unsafe {
                    assert_eq!(SafeArrayPutElement(psa, &index, b.cast()), 0);
                    SysFreeString(b);
                }
            }
        }
        SaData::Variants(items) => {
            for (i, v) in items.iter().enumerate() {
                let mut var = variant(v);
                let index = sa.bounds[0].1 + i as i32;
                // SAFETY: a one-dimensional array of VARIANTs; PutElement copies the VARIANT.
                unsafe {
                    assert_eq!(SafeArrayPutElement(psa, &index, (&var as *const Variant).cast()), 0);
                    VariantClear(&mut var);
                }
            }
        }
        SaData::Null => panic!("a SAFEARRAY without data is not made here"),
    }
    psa
}

/// The VARIANT `v` describes (its strings and arrays allocated; `VariantClear` frees them).
fn variant(v: &V) -> Variant {
    let mut var = Variant {
        bytes: [0; 8 + 2 * core::mem::size_of::<usize>()],
    };
    let (vt, _) = super::build::vt_of(v);
    let value: Vec<u8> = match v {
        V::Empty | V::Null => vec![],
        V::I1(x) => vec![*x as u8],
        V::Ui1(x) => vec![*x],
        V::I2(x) => x.to_le_bytes().to_vec(),
        V::Bool(x) => (if *x { -1i16 } else { 0 }).to_le_bytes().to_vec(),
        V::I4(x) | V::Int(x) | V::Error(x) => x.to_le_bytes().to_vec(),
        V::R4(x) => x.to_le_bytes().to_vec(),
        V::I8(x) | V::Cy(x) => x.to_le_bytes().to_vec(),
        V::R8(x) | V::Date(x) => x.to_le_bytes().to_vec(),
        V::Decimal(d) => {
            var.bytes[..16].copy_from_slice(d);
            vec![]
        }
        V::Bstr(t) => (t.as_deref().map_or(core::ptr::null_mut(), bstr) as usize)
            .to_le_bytes()
            .to_vec(),
        V::Array(sa) => (sa.as_ref().map_or(core::ptr::null_mut(), safearray) as usize)
            .to_le_bytes()
            .to_vec(),
        V::Raw(..) => panic!("not a value"),
    };
    var.bytes[8..8 + value.len()].copy_from_slice(&value);
    var.bytes[..2].copy_from_slice(&vt.to_le_bytes());
    var
}

/// An 8-aligned buffer of `len` bytes.
fn buffer(len: usize) -> Vec<u64> {
    vec![0u64; len.div_ceil(8) + 1]
}

fn bytes_of(words: &[u64], len: usize) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).take(len).collect()
}

/// A `[wire_marshal]` value as Wine's NDR engine writes it at the top of a message: "User", padding
/// to 8, then what the user marshaller writes there.
fn framed(size: u32, marshal: impl FnOnce(*mut u8) -> *mut u8) -> Vec<u8> {
    let mut words = buffer(8 + size as usize);
    let base = words.as_mut_ptr().cast::<u8>();
    words[0] = u64::from(USER);
    // SAFETY: `size` from the marshaller's own sizing, from offset 8 on; the buffer has room for it.
    let end = marshal(unsafe { base.add(8) });
    let len = end as usize - base as usize;
    assert!(
        len <= 8 + size as usize,
        "the marshaller wrote {len} bytes, sized {size}"
    );
    bytes_of(&words, len)
}

fn marshalled_variant(var: &mut Variant) -> Vec<u8> {
    let mut flags = FLAGS;
    // SAFETY: a valid VARIANT; the buffer is what VARIANT_UserSize asks for.
    let size = unsafe { VARIANT_UserSize(&mut flags, 8, var) };
    framed(size, |at| {
        // SAFETY: `at` has room for the size VARIANT_UserSize gave.
        unsafe { VARIANT_UserMarshal(&mut flags, at, var) }
    })
}

fn under_wine() -> bool {
    use windows_sys::Win32::System::LibraryLoader::{GetModuleHandleA, GetProcAddress};
    // SAFETY: NUL-terminated names; a NULL module is checked.
    unsafe {
        let ntdll = GetModuleHandleA(c"ntdll.dll".as_ptr().cast());
        !ntdll.is_null() && GetProcAddress(ntdll, c"wine_get_version".as_ptr().cast()).is_some()
    }
}

fn values() -> Vec<V> {
    let mut out = vec![
        V::Empty,
        V::Null,
        V::I1(-1),
        V::Ui1(200),
        V::I2(-2),
        V::Bool(true),
        V::I4(-4),
        V::Int(4),
        V::R4(1.5),
        V::Error(0x80004005_u32 as i32),
        V::I8(-8),
        V::R8(2.5),
        V::Cy(12345),
        V::Date(45000.5),
        V::Decimal([14, 0, 2, 0, 0, 0, 0, 0, 0x39, 0x30, 0, 0, 0, 0, 0, 0]),
        V::Bstr(None),
        V::Bstr(Some(String::new())),
        V::Bstr(Some("value".into())),
        V::Array(None),
    ];
    let one = |vt: u16, n: u32, data: SaData| {
        V::Array(Some(Sa {
            vt,
            bounds: vec![(n, 1)],
            data,
        }))
    };
    out.push(one(17, 3, SaData::Plain(vec![1, 2, 3])));
    out.push(one(2, 2, SaData::Plain(vec![1, 0, 2, 0])));
    out.push(one(11, 2, SaData::Plain(vec![0xFF, 0xFF, 0, 0])));
    out.push(one(3, 2, SaData::Plain(vec![1, 0, 0, 0, 2, 0, 0, 0])));
    out.push(one(4, 1, SaData::Plain(1.5f32.to_le_bytes().to_vec())));
    out.push(one(
        5,
        2,
        SaData::Plain([1.5f64.to_le_bytes(), 2.5f64.to_le_bytes()].concat()),
    ));
    out.push(one(20, 1, SaData::Plain(7i64.to_le_bytes().to_vec())));
    out.push(one(
        8,
        3,
        // (SafeArrayPutElement stores a NULL BSTR as an empty one.)
        SaData::Bstrs(vec![Some("a".into()), Some(String::new()), Some("ccc".into())]),
    ));
    out.push(one(12, 2, SaData::Variants(vec![V::I4(1), V::R8(2.0)])));
    out.push(V::Array(Some(Sa {
        vt: 3,
        bounds: vec![(2, 0), (2, 0)],
        data: SaData::Plain(vec![0; 16]),
    })));
    out
}

#[test]
fn variants_as_the_runtime_marshals_them() {
    let wine = under_wine();
    let i = index(T::INdrAutomation, "Variants");
    for v in values() {
        let mut var = variant(&v);
        let real = Msg(marshalled_variant(&mut var)).u32(0).u32(0).align(8);
        // The checks pass the runtime's bytes, and refuse every prefix of them.
        whole(
            |b| check_request(T::INdrAutomation.layout(), i, b, LOCAL, Dialect::Wine).map(|_| ()),
            &real,
        );
        // The construct tests' messages are laid out as the runtime lays them out.
        let built = Msg::default()
            .u32(USER)
            .variant(&v, Dialect::Wine)
            .u32(0)
            .u32(0)
            .align(8);
        assert_eq!(
            built.0.len(),
            real.0.len(),
            "{v:?}: {:02x?} vs {:02x?}",
            built.0,
            real.0
        );
        // And the runtime's unmarshaller reads them back as that value: marshalled again, the same
        // bytes (the arm's referent ID aside: Wine writes a pointer's low bits there).
        if wine {
            let copy = built.aligned();
            let at = copy.bytes().as_ptr() as usize;
            let mut back = Variant {
                bytes: [0; 8 + 2 * core::mem::size_of::<usize>()],
            };
            let mut flags = FLAGS;
            let body = copy.bytes()[8..].as_ptr() as *mut u8;
            // SAFETY: the buffer holds a whole VARIANT (the checks passed it), which the unmarshaller
            // only reads; `back` is empty.
            let end = unsafe { VARIANT_UserUnmarshal(&mut flags, body, &mut back) };
            let variant_end = Msg::default().u32(USER).variant(&v, Dialect::Wine).0.len();
            assert_eq!(end as usize - at, variant_end, "{v:?}");
            let mut again = marshalled_variant(&mut back);
            let mut original = real.0[..again.len()].to_vec();
            if let V::Bstr(_) | V::Array(_) = v {
                again[28..32].fill(0);
                original[28..32].fill(0);
            }
            assert_eq!(again, original, "{v:?}");
            // SAFETY: what the unmarshaller allocated.
            unsafe { VariantClear(&mut back) };
        }
        // SAFETY: what `variant` allocated.
        unsafe { VariantClear(&mut var) };
    }
}

#[test]
fn bstrs_and_safearrays_as_the_runtime_marshals_them() {
    for text in [None, Some(""), Some("odd"), Some("a longer string")] {
        let mut b = text.map_or(core::ptr::null_mut(), bstr);
        let mut flags = FLAGS;
        // SAFETY: a BSTR or NULL; the buffer is what BSTR_UserSize asks for.
        let size = unsafe { BSTR_UserSize(&mut flags, 8, &mut b) };
        let real = framed(size, |at| {
            // SAFETY: `at` has room for the size BSTR_UserSize gave.
            unsafe { BSTR_UserMarshal(&mut flags, at, &mut b) }
        });
        whole_request(T::INdrAutomation, "Bstrs", &Msg(real.clone()), Dialect::Wine);
        let built = Msg::default().user(Dialect::Wine, 4, |m| m.blob(text));
        assert_eq!(built.0.len(), real.len());
        // SAFETY: ours.
        unsafe { SysFreeString(b) };
    }
    for v in values() {
        let V::Array(Some(sa)) = v else { continue };
        let mut psa = safearray(&sa);
        let mut flags = FLAGS;
        // SAFETY: a SAFEARRAY; the buffer is what LPSAFEARRAY_UserSize asks for.
        let size = unsafe { LPSAFEARRAY_UserSize(&mut flags, 8, &mut psa) };
        let real = framed(size, |at| {
            // SAFETY: `at` has room for the size LPSAFEARRAY_UserSize gave.
            unsafe { LPSAFEARRAY_UserMarshal(&mut flags, at, &mut psa) }
        });
        whole_request(T::INdrAutomation, "Arrays", &Msg(real.clone()), Dialect::Wine);
        let built = Msg::default().user(Dialect::Wine, 4, |m| m.safearray(Some(&sa), Dialect::Wine));
        assert_eq!(built.0.len(), real.len(), "{sa:?}");
        // SAFETY: ours.
        unsafe { SafeArrayDestroy(psa) };
    }
}
