//! The version convention of specification section 6.4: `MM.mm.bb` (major, minor, build), stored in a
//! version resource as `FILEVERSION MM,mm,0,bb`, and used by installers to never replace a newer file
//! with an older one.

use core::cmp::Ordering;

use crate::com::alloc::alloc_wstr_from_str;
use crate::com::ffi::{self, Crossed, Hr};
use crate::com::{BOOL, DWORD, E_INVALIDARG, FALSE, LPCWSTR, LPWSTR, S_OK, TRUE};

/// A version `MM.mm.bb` (each part 0 to 65535, the range of a version resource field).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct OpcVersion {
    /// MM: the major version.
    pub major: u16,
    /// mm: the minor version.
    pub minor: u16,
    /// bb: the build number.
    pub build: u16,
}

// SAFETY: three u16 fields; all zero is version 0.0.0, the failure value.
unsafe impl ffi::ZeroIsEmpty for OpcVersion {}

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

/// Parses a version `MM.mm.bb`: three decimal numbers of at most 65535, nothing else.
///
/// # Parameters
/// - `text`: the text.
/// - `version` (out): receives the version; 0.0.0 on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL argument; E_INVALIDARG for any other text.
///
/// # Safety
/// `text` NULL or NUL-terminated; `version` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionParse(text: LPCWSTR, version: *mut OpcVersion) -> Hr {
    ffi::boundary!(Opc, [version], {
        // SAFETY: the caller's contract: `version` NULL or writable, `text` NULL or NUL-terminated.
        let (version, text) = unsafe { (ffi::out(version)?, ffi::in_string(text)?) };
        version.write(OpcVersion::parse(&text).ok_or(E_INVALIDARG)?);
        Ok(S_OK)
    })
}

/// Formats a version as `MM.mm.bb` (for example `5.2.41`).
///
/// # Parameters
/// - `version`: the version.
/// - `text` (out): receives a new string (free it with `OpcTaskMemFree`), or NULL on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL argument; E_OUTOFMEMORY.
///
/// # Safety
/// `version` NULL or readable; `text` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionFormat(version: *const OpcVersion, text: *mut LPWSTR) -> Hr {
    ffi::boundary!(Opc, [text], {
        // SAFETY: the caller's contract: `version` NULL or readable, `text` NULL or writable.
        let (version, text) = unsafe { (ffi::in_ref(version)?, ffi::out(text)?) };
        text.write(alloc_wstr_from_str(&version.to_string())?);
        Ok(S_OK)
    })
}

/// The `FILEVERSION` / `PRODUCTVERSION` of a version as the two words of `VS_FIXEDFILEINFO` (the
/// resource line `FILEVERSION MM,mm,0,bb`).
///
/// # Parameters
/// - `version`: the version.
/// - `ms` (out): receives `MM << 16 | mm` (`dwFileVersionMS`); 0 on failure.
/// - `ls` (out): receives `0 << 16 | bb` (`dwFileVersionLS`); 0 on failure.
///
/// # Returns
/// S_OK, or E_INVALIDARG for a NULL argument.
///
/// # Safety
/// `version` NULL or readable; `ms` and `ls` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionToFileVersion(version: *const OpcVersion, ms: *mut DWORD, ls: *mut DWORD) -> Hr {
    ffi::boundary!(Opc, [ms, ls], {
        // SAFETY: the caller's contract: `version` NULL or readable, `ms` and `ls` NULL or writable.
        let (version, ms, ls) = unsafe { (ffi::in_ref(version)?, ffi::out(ms)?, ffi::out(ls)?) };
        let (m, l) = version.file_version();
        ms.write(m);
        ls.write(l);
        Ok(S_OK)
    })
}

/// The version of a `VS_FIXEDFILEINFO` in the `MM,mm,0,bb` convention.
///
/// # Parameters
/// - `ms`: `dwFileVersionMS`.
/// - `ls`: `dwFileVersionLS`.
/// - `version` (out): receives the version; 0.0.0 on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `version`; E_INVALIDARG when the third field is not 0 (the file does
/// not follow the convention).
///
/// # Safety
/// `version` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionFromFileVersion(ms: DWORD, ls: DWORD, version: *mut OpcVersion) -> Hr {
    ffi::boundary!(Opc, [version], {
        // SAFETY: the caller vouches a non-NULL `version` is writable.
        let version = unsafe { ffi::out(version) }?;
        version.write(OpcVersion::from_file_version(ms, ls).ok_or(E_INVALIDARG)?);
        Ok(S_OK)
    })
}

/// Compares two versions: major first, then minor, then build. A NULL argument counts as older than
/// any version.
///
/// # Parameters
/// - `a`: one version.
/// - `b`: the other.
///
/// # Returns
/// Negative when `a` is older than `b`, 0 when they are equal, positive when `a` is newer.
///
/// # Safety
/// `a` and `b` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionCompare(a: *const OpcVersion, b: *const OpcVersion) -> Crossed<i32> {
    ffi::guard!(0, {
        // SAFETY: each is read only when non-NULL.
        let (a, b) = unsafe { (a.as_ref(), b.as_ref()) };
        match a.cmp(&b) {
            Ordering::Less => -1,
            Ordering::Equal => 0,
            Ordering::Greater => 1,
        }
    })
}

/// Whether a file may replace the installed one (specification section 6.5): whether it is strictly
/// newer.
///
/// # Parameters
/// - `candidate`: the version of the file that would replace it.
/// - `installed`: the version installed; NULL when nothing is installed.
///
/// # Returns
/// TRUE when `candidate` is strictly newer than `installed` or `installed` is NULL (and `candidate`
/// is not); FALSE otherwise, and when `candidate` is NULL.
///
/// # Safety
/// `candidate` and `installed` NULL or readable.
#[no_mangle]
pub unsafe extern "C" fn OpcVersionIsNewer(
    candidate: *const OpcVersion,
    installed: *const OpcVersion,
) -> Crossed<BOOL> {
    ffi::guard!(FALSE, {
        // SAFETY: forwarded from the caller's contract.
        if !candidate.is_null() && unsafe { OpcVersionCompare(candidate, installed) }.get() > 0 {
            TRUE
        } else {
            FALSE
        }
    })
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
