//! The version convention of specification section 6.4: `MM.mm.bb` (major, minor, build), stored in a
//! version resource as `FILEVERSION MM,mm,0,bb`, and used by installers to never replace a newer file
//! with an older one.

use core::cmp::Ordering;

use super::arg_string;
use crate::com::alloc::alloc_wstr_from_str;
use crate::com::boundary::catch;
use crate::com::{BOOL, DWORD, E_INVALIDARG, E_POINTER, E_UNEXPECTED, FALSE, HRESULT, LPCWSTR, LPWSTR, S_OK, TRUE};

/// A version `MM.mm.bb` (each part 0 to 65535, the range of a version resource field).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct OpcVersion {
    pub major: u16,
    pub minor: u16,
    pub build: u16,
}

impl OpcVersion {
    /// Parses `MM.mm.bb`: exactly three dot-separated decimal numbers, digits only, each at most 65535.
    pub fn parse(text: &str) -> Option<OpcVersion> {
        let mut parts = text.split('.');
        let mut next = || -> Option<u16> {
            let p = parts.next()?;
            if p.is_empty() || p.len() > 5 || !p.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            p.parse().ok()
        };
        let v = OpcVersion {
            major: next()?,
            minor: next()?,
            build: next()?,
        };
        parts.next().is_none().then_some(v)
    }

    /// The `FILEVERSION` words as `VS_FIXEDFILEINFO` holds them: `(MM << 16 | mm, 0 << 16 | bb)`.
    pub fn file_version(&self) -> (DWORD, DWORD) {
        ((self.major as u32) << 16 | self.minor as u32, self.build as u32)
    }

    /// The version a `FILEVERSION MM,mm,x,bb` denotes; `None` when the third field is not 0, as the
    /// convention requires.
    pub fn from_file_version(ms: DWORD, ls: DWORD) -> Option<OpcVersion> {
        (ls >> 16 == 0).then_some(OpcVersion {
            major: (ms >> 16) as u16,
            minor: ms as u16,
            build: ls as u16,
        })
    }
}

impl core::fmt::Display for OpcVersion {
    /// `MM.mm.bb` in plain decimal numbers, as the specification writes it (`5.2.41`).
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}.{}.{}", self.major, self.minor, self.build)
    }
}

/// Parses a version `MM.mm.bb` (three decimal numbers of at most 65535, nothing else) into `*version`.
///
/// Returns S_OK; E_POINTER for a NULL argument; E_INVALIDARG for any other text. `*version` is 0.0.0 on
/// failure.
///
/// # Safety
/// `text` NULL or NUL-terminated; `version` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionParse(text: LPCWSTR, version: *mut OpcVersion) -> HRESULT {
    if version.is_null() {
        return E_POINTER;
    }
    // SAFETY: checked non-NULL; the caller vouches it is writable.
    unsafe { *version = OpcVersion::default() };
    catch(E_UNEXPECTED, || {
        // SAFETY: forwarded from the caller's contract.
        let text = match unsafe { arg_string(text) } {
            Ok(t) => t,
            Err(hr) => return hr,
        };
        match OpcVersion::parse(&text) {
            Some(v) => {
                // SAFETY: as above.
                unsafe { *version = v };
                S_OK
            }
            None => E_INVALIDARG,
        }
    })
}

/// Formats `*version` as `MM.mm.bb` (for example `5.2.41`) into `*text`, freed with `OpcTaskMemFree`.
///
/// Returns S_OK; E_POINTER for a NULL argument; E_OUTOFMEMORY. `*text` is NULL on failure.
///
/// # Safety
/// `version` NULL or readable; `text` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionFormat(version: *const OpcVersion, text: *mut LPWSTR) -> HRESULT {
    // SAFETY: forwarded from the caller's contract.
    if let Err(hr) = unsafe { super::clear_out(text) } {
        return hr;
    }
    if version.is_null() {
        return E_POINTER;
    }
    catch(E_UNEXPECTED, || {
        // SAFETY: checked non-NULL; the caller vouches it is readable.
        match alloc_wstr_from_str(&unsafe { *version }.to_string()) {
            Ok(p) => {
                // SAFETY: checked writable above.
                unsafe { *text = p };
                S_OK
            }
            Err(hr) => hr,
        }
    })
}

/// The `FILEVERSION` / `PRODUCTVERSION` of `*version` as the two words of `VS_FIXEDFILEINFO`:
/// `*ms = MM << 16 | mm`, `*ls = 0 << 16 | bb` (the resource line `FILEVERSION MM,mm,0,bb`).
///
/// Returns S_OK, or E_POINTER for a NULL argument (the outputs that are not NULL are 0 then).
///
/// # Safety
/// `version` NULL or readable; `ms` and `ls` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionToFileVersion(
    version: *const OpcVersion,
    ms: *mut DWORD,
    ls: *mut DWORD,
) -> HRESULT {
    // SAFETY: each output is written only when non-NULL.
    unsafe {
        if !ms.is_null() {
            *ms = 0;
        }
        if !ls.is_null() {
            *ls = 0;
        }
    }
    if version.is_null() || ms.is_null() || ls.is_null() {
        return E_POINTER;
    }
    catch(E_UNEXPECTED, || {
        // SAFETY: all three checked non-NULL above.
        unsafe {
            let (m, l) = (*version).file_version();
            *ms = m;
            *ls = l;
        }
        S_OK
    })
}

/// The version of a `VS_FIXEDFILEINFO` (`dwFileVersionMS`, `dwFileVersionLS`) in the `MM,mm,0,bb`
/// convention.
///
/// Returns S_OK; E_POINTER for a NULL `version`; E_INVALIDARG when the third field is not 0 (the file
/// does not follow the convention). `*version` is 0.0.0 on failure.
///
/// # Safety
/// `version` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionFromFileVersion(ms: DWORD, ls: DWORD, version: *mut OpcVersion) -> HRESULT {
    if version.is_null() {
        return E_POINTER;
    }
    // SAFETY: checked non-NULL; the caller vouches it is writable.
    unsafe { *version = OpcVersion::default() };
    match OpcVersion::from_file_version(ms, ls) {
        Some(v) => {
            // SAFETY: as above.
            unsafe { *version = v };
            S_OK
        }
        None => E_INVALIDARG,
    }
}

/// Compares two versions: negative when `a` is older than `b`, 0 when equal, positive when newer
/// (major first, then minor, then build). A NULL argument counts as older than any version.
///
/// # Safety
/// `a` and `b` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionCompare(a: *const OpcVersion, b: *const OpcVersion) -> i32 {
    // SAFETY: each is read only when non-NULL.
    let (a, b) = unsafe { (a.as_ref(), b.as_ref()) };
    match a.cmp(&b) {
        Ordering::Less => -1,
        Ordering::Equal => 0,
        Ordering::Greater => 1,
    }
}

/// TRUE when `candidate` is strictly newer than `installed`, so an installer may replace the installed
/// file with it (specification section 6.5); FALSE otherwise, and when `candidate` is NULL. A NULL
/// `installed` (nothing installed) makes any candidate newer.
///
/// # Safety
/// `candidate` and `installed` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionIsNewer(candidate: *const OpcVersion, installed: *const OpcVersion) -> BOOL {
    // SAFETY: forwarded from the caller's contract.
    if !candidate.is_null() && unsafe { OpcVersionCompare(candidate, installed) } > 0 {
        TRUE
    } else {
        FALSE
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(major: u16, minor: u16, build: u16) -> OpcVersion {
        OpcVersion { major, minor, build }
    }

    #[test]
    fn parses_exactly_three_decimal_parts() {
        assert_eq!(OpcVersion::parse("5.2.41"), Some(v(5, 2, 41)));
        assert_eq!(OpcVersion::parse("05.02.041"), Some(v(5, 2, 41)));
        assert_eq!(OpcVersion::parse("65535.0.65535"), Some(v(65535, 0, 65535)));
        for bad in [
            "",
            "5.2",
            "5.2.41.0",
            "5..41",
            "5.2.x",
            " 5.2.41",
            "5.2.41 ",
            "-5.2.41",
            "+5.2.41",
            "65536.0.0",
            "5,2,0,41",
            "000001.0.0",
        ] {
            assert_eq!(OpcVersion::parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn file_version_is_mm_mm_0_bb() {
        assert_eq!(v(5, 2, 41).file_version(), (0x0005_0002, 41));
        assert_eq!(OpcVersion::from_file_version(0x0005_0002, 41), Some(v(5, 2, 41)));
        assert_eq!(OpcVersion::from_file_version(0x0005_0002, 0x0001_0029), None);
        assert_eq!(v(5, 2, 41).to_string(), "5.2.41");
    }

    #[test]
    fn newer_compares_major_then_minor_then_build() {
        // SAFETY: references to locals.
        unsafe {
            assert_eq!(OpcVersionIsNewer(&v(5, 2, 42), &v(5, 2, 41)), TRUE);
            assert_eq!(OpcVersionIsNewer(&v(5, 3, 0), &v(5, 2, 41)), TRUE);
            assert_eq!(OpcVersionIsNewer(&v(6, 0, 0), &v(5, 99, 99)), TRUE);
            assert_eq!(OpcVersionIsNewer(&v(5, 2, 41), &v(5, 2, 41)), FALSE);
            assert_eq!(OpcVersionIsNewer(&v(5, 1, 99), &v(5, 2, 0)), FALSE);
            assert_eq!(OpcVersionIsNewer(&v(1, 0, 0), core::ptr::null()), TRUE);
            assert_eq!(OpcVersionIsNewer(core::ptr::null(), &v(1, 0, 0)), FALSE);
            assert_eq!(OpcVersionCompare(&v(1, 0, 0), &v(1, 0, 1)), -1);
        }
    }
}
