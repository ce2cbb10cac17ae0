//! Portable definitions of the COM base types.
//!
//! COM strings are UTF-16 on every platform, so `WCHAR` is 16 bits here even where C's `wchar_t` is 32.
//! Every item that Windows' own headers also define carries `#[cfg(not(system_com_headers))]`: Rust
//! never sets that cfg, so the items always exist in Rust, and cbindgen turns it into
//! `#if !defined(_WIN32)` so a C program on Windows gets these types from `<windows.h>` instead.

/// A COM result code. Negative values are failures (`FAILED(hr)`).
#[cfg(not(system_com_headers))]
pub type HRESULT = i32;
/// A locale identifier.
#[cfg(not(system_com_headers))]
pub type LCID = u32;
/// A 32-bit unsigned integer.
#[cfg(not(system_com_headers))]
pub type DWORD = u32;
/// A 32-bit unsigned integer (reference counts, element counts).
#[cfg(not(system_com_headers))]
pub type ULONG = u32;
/// A Win32 boolean: 0 is FALSE, 1 is TRUE.
#[cfg(not(system_com_headers))]
pub type BOOL = i32;
/// A UTF-16 code unit.
#[cfg(not(system_com_headers))]
pub type WCHAR = u16;
/// A NUL-terminated UTF-16 string the callee may write or the caller must free.
#[cfg(not(system_com_headers))]
pub type LPWSTR = *mut WCHAR;
/// A NUL-terminated UTF-16 string that is only read.
#[cfg(not(system_com_headers))]
pub type LPCWSTR = *const WCHAR;
/// A NUL-terminated narrow string (UTF-8, or the ANSI code page on Windows).
#[cfg(not(system_com_headers))]
pub type LPCSTR = *const core::ffi::c_char;
/// A COM string allocated with the task allocator (same as `LPWSTR`).
#[cfg(not(system_com_headers))]
pub type LPOLESTR = *mut WCHAR;
/// A read-only COM string (same as `LPCWSTR`).
#[cfg(not(system_com_headers))]
pub type LPCOLESTR = *const WCHAR;

/// A globally unique identifier, laid out exactly as Windows' `GUID`.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
#[allow(non_snake_case)]
pub struct GUID {
    /// The first 8 hexadecimal digits.
    pub Data1: u32,
    /// The next 4 digits.
    pub Data2: u16,
    /// The next 4 digits.
    pub Data3: u16,
    /// The last 16 digits, as bytes in the order written.
    pub Data4: [u8; 8],
}

/// An interface identifier.
#[cfg(not(system_com_headers))]
pub type IID = GUID;
/// A class identifier.
#[cfg(not(system_com_headers))]
pub type CLSID = GUID;
/// A component category identifier.
#[cfg(not(system_com_headers))]
pub type CATID = GUID;
/// A pointer to an interface identifier (a reference in C++ on Windows; the same ABI).
#[cfg(not(system_com_headers))]
pub type REFIID = *const IID;
/// A pointer to a class identifier.
#[cfg(not(system_com_headers))]
pub type REFCLSID = *const CLSID;
/// A pointer to a class identifier the callee writes.
#[cfg(not(system_com_headers))]
pub type LPCLSID = *mut CLSID;

/// One connection of a connection point: the sink and the cookie Advise returned for it.
#[cfg(not(system_com_headers))]
#[repr(C)]
#[allow(non_snake_case)]
#[derive(Clone, Copy)]
pub struct CONNECTDATA {
    /// The connected sink (AddRef'ed for whoever received it from IEnumConnections::Next).
    pub pUnk: *mut super::interfaces::IUnknown,
    /// The cookie IConnectionPoint::Advise returned for the sink.
    pub dwCookie: DWORD,
}

/// `CATEGORYINFO` of comcat.h: a component category and its description in one locale (what
/// ICatRegister::RegisterCategories takes; the library's header does not use it).
#[repr(C)]
#[allow(non_snake_case)]
#[derive(Clone, Copy)]
pub struct CATEGORYINFO {
    /// The category.
    pub catid: CATID,
    /// The locale of the description.
    pub lcid: LCID,
    /// The description, NUL-terminated.
    pub szDescription: [WCHAR; 128],
}

impl GUID {
    /// Builds a GUID from its canonical 128-bit big-endian value,
    /// `0x01234567_89ab_cdef_0123_456789abcdef` for `{01234567-89AB-CDEF-0123-456789ABCDEF}`.
    pub const fn from_u128(v: u128) -> GUID {
        GUID {
            Data1: (v >> 96) as u32,
            Data2: (v >> 80) as u16,
            Data3: (v >> 64) as u16,
            Data4: (v as u64).to_be_bytes(),
        }
    }
}

impl core::fmt::Display for GUID {
    /// Registry form: `{F31DFDE2-07B6-11D2-B2D8-0060083BA1FB}`.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let d = &self.Data4;
        write!(
            f,
            "{{{:08X}-{:04X}-{:04X}-{:02X}{:02X}-{:02X}{:02X}{:02X}{:02X}{:02X}{:02X}}}",
            self.Data1, self.Data2, self.Data3, d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7]
        )
    }
}

/// `FALSE`.
#[cfg(not(system_com_headers))]
pub const FALSE: BOOL = 0;
/// `TRUE`.
#[cfg(not(system_com_headers))]
pub const TRUE: BOOL = 1;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn guid_from_u128_matches_registry_form() {
        let g = GUID::from_u128(0xF31DFDE2_07B6_11D2_B2D8_0060083BA1FB);
        assert_eq!(g.Data1, 0xF31DFDE2);
        assert_eq!(g.Data2, 0x07B6);
        assert_eq!(g.Data3, 0x11d2);
        assert_eq!(g.Data4, [0xB2, 0xD8, 0x00, 0x60, 0x08, 0x3B, 0xA1, 0xFB]);
        assert_eq!(g.to_string(), "{F31DFDE2-07B6-11D2-B2D8-0060083BA1FB}");
        assert_eq!(core::mem::size_of::<GUID>(), 16);
    }
}
