//! Reading NUL-terminated UTF-16 strings from callers, with a bound so a missing terminator cannot
//! make the library read without end.

use super::types::WCHAR;

/// The longest string, in UTF-16 code units, the library reads from a caller (1 MiB of text). Under
/// Miri 4,096, so that the tests reach the refusal of a longer string in seconds (Miri interprets
/// every unit read); the code that applies the bound is the same.
pub(crate) const MAX_STRING_UNITS: usize = if cfg!(miri) { 1 << 12 } else { 1 << 19 };

/// The code units of the NUL-terminated string at `p`, without the NUL; `None` for NULL or for a
/// string longer than `max` units (only `max + 1` units are ever read).
///
/// # Safety
/// `p` must be NULL or point at a NUL-terminated UTF-16 string (or at least `max + 1` readable units).
pub unsafe fn wstr_units<'a>(p: *const WCHAR, max: usize) -> Option<&'a [WCHAR]> {
    if p.is_null() {
        return None;
    }
    let mut len = 0;
    // SAFETY: the caller vouches every unit up to the NUL (or `max + 1` units) is readable.
    while unsafe { *p.add(len) } != 0 {
        if len == max {
            return None;
        }
        len += 1;
    }
    // SAFETY: the `len` units before the NUL were just read.
    Some(unsafe { core::slice::from_raw_parts(p, len) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_up_to_the_nul_and_respects_the_bound() {
        let s = [0x61u16, 0xD800, 0x62, 0];
        // SAFETY: `s` is NUL-terminated.
        unsafe {
            assert_eq!(wstr_units(s.as_ptr(), 10), Some(&s[..3]));
            assert_eq!(wstr_units(s.as_ptr(), 3), Some(&s[..3]));
            assert_eq!(wstr_units(s.as_ptr(), 2), None);
            assert_eq!(wstr_units(core::ptr::null(), 2), None);
        }
    }
}
