//! Narrow (`char`) strings for `MatchPatternA`: UTF-8 everywhere except Windows, where they are in the
//! process's ANSI code page like every `...A` Win32 function. Bytes that do not decode are characters
//! of their own (see `text.rs`).

use super::program::{Malformed, Program};

/// The bytes of the NUL-terminated string at `p`, without the NUL; `None` for NULL.
///
/// # Safety
/// `p` must be NULL or point at a NUL-terminated string.
pub(crate) unsafe fn cstr_bytes<'a>(p: *const core::ffi::c_char) -> Option<&'a [u8]> {
    if p.is_null() {
        return None;
    }
    // SAFETY: non-NULL and NUL-terminated (the caller's contract).
    Some(unsafe { core::ffi::CStr::from_ptr(p) }.to_bytes())
}

#[cfg(not(windows))]
mod imp {
    use super::super::stream::{self, Utf8Cursor};
    use super::super::text::Utf8;
    use super::*;

    pub(crate) fn compile(pattern: &[u8], case_sensitive: bool) -> Result<Program, Malformed> {
        Program::compile(&Utf8(pattern), case_sensitive)
    }

    /// Whether the NUL-terminated `string` matches the compiled `program`.
    ///
    /// # Safety
    /// `string` must point at a NUL-terminated string.
    pub(crate) unsafe fn matches(program: &Program, string: *const u8) -> bool {
        // SAFETY: NUL-terminated (the caller's contract).
        unsafe { program.matches_cursor(Utf8Cursor(string)) }
    }

    /// `MatchPatternA` without compiling: reads both strings in place (inlined into the export, as
    /// `MatchPatternW`'s loop is, so a call costs no extra frame).
    ///
    /// # Safety
    /// Both must point at NUL-terminated strings.
    #[inline(always)]
    pub(crate) unsafe fn match_once(string: *const u8, pattern: *const u8, case_sensitive: bool) -> bool {
        // SAFETY: both are NUL-terminated (the caller's contract).
        match unsafe { stream::matches(Utf8Cursor(string), Utf8Cursor(pattern), case_sensitive) } {
            Some(matched) => matched,
            // SAFETY: as above.
            None => unsafe { match_long_pattern(string, pattern, case_sensitive) },
        }
    }

    /// A pattern longer than `stream::LONG_PATTERN` with a `*`: compiled first (out of line, so the
    /// common path stays lean).
    ///
    /// # Safety
    /// Both must point at NUL-terminated strings.
    #[cold]
    #[inline(never)]
    unsafe fn match_long_pattern(string: *const u8, pattern: *const u8, case_sensitive: bool) -> bool {
        // SAFETY: NUL-terminated (the caller's contract).
        let bytes = unsafe { cstr_bytes(pattern.cast()) }.unwrap_or_default();
        match compile(bytes, case_sensitive) {
            // SAFETY: as above.
            Ok(program) => unsafe { matches(&program, string) },
            Err(_) => false,
        }
    }
}

#[cfg(windows)]
mod imp {
    use std::sync::OnceLock;

    use windows_sys::Win32::Globalization::MB_ERR_INVALID_CHARS;
    use windows_sys::Win32::Globalization::{GetACP, GetCPInfo, MultiByteToWideChar, CPINFO, CP_ACP, CP_UTF8};

    use super::super::smallvec::SmallVec;
    use super::super::stream::{self, Cursor, DecodedCursor, TableCursor, Utf8Cursor};
    use super::super::text::{invalid_byte, Chars, Text, Utf16, Utf8};
    use super::*;

    /// How the process's ANSI code page decodes each byte (it cannot change while the process runs).
    struct CodePage {
        utf8: bool,
        /// The character of each byte standing alone (`invalid_byte` where it has none).
        single: [u32; 256],
        /// Lead bytes of double-byte characters (DBCS code pages such as 932).
        lead: [bool; 256],
        /// Some byte is a lead byte.
        double: bool,
        /// No lead byte is below 0x80, so ASCII text has none.
        lead_above_ascii: bool,
        /// `single` maps no byte of 0x80 and above to an ASCII character, so a string without lead
        /// bytes can be read in place (`stream::TableCursor`). True for every code page Windows uses
        /// as its ANSI code page; checked rather than assumed.
        table_reads: bool,
        /// Every string can be read in place through `single` without looking at it first: a
        /// single-byte code page (not UTF-8) with `table_reads`. The one flag `MatchPatternA` tests
        /// before matching in the common case.
        every_string_in_place: bool,
    }

    /// Decodes up to two bytes of the ANSI code page; `None` when they are not one valid character.
    fn decode_acp(bytes: &[u8]) -> Option<u32> {
        let mut wide = [0u16; 2];
        // SAFETY: `bytes` and `wide` are valid for the lengths passed.
        let n = unsafe {
            MultiByteToWideChar(
                CP_ACP,
                MB_ERR_INVALID_CHARS,
                bytes.as_ptr(),
                bytes.len() as i32,
                wide.as_mut_ptr(),
                wide.len() as i32,
            )
        };
        match n {
            1 => Some(wide[0] as u32),
            2 => match Utf16(&wide).next(0) {
                (c, 2) => Some(c),
                _ => None,
            },
            _ => None,
        }
    }

    fn code_page() -> &'static CodePage {
        static CODE_PAGE: OnceLock<CodePage> = OnceLock::new();
        CODE_PAGE.get_or_init(|| {
            // SAFETY: no arguments.
            let acp = unsafe { GetACP() };
            let mut cp = CodePage {
                utf8: acp == CP_UTF8,
                single: [0; 256],
                lead: [false; 256],
                double: false,
                lead_above_ascii: true,
                table_reads: true,
                every_string_in_place: false,
            };
            let mut info = CPINFO {
                MaxCharSize: 1,
                DefaultChar: [0; 2],
                LeadByte: [0; 12],
            };
            // SAFETY: `info` is a writable CPINFO.
            if unsafe { GetCPInfo(CP_ACP, &mut info) } != 0 && info.MaxCharSize == 2 {
                for pair in info.LeadByte.chunks(2) {
                    if pair[0] == 0 && pair[1] == 0 {
                        break;
                    }
                    for b in pair[0]..=pair[1] {
                        cp.lead[b as usize] = true;
                    }
                }
            }
            for b in 0..=255u8 {
                cp.single[b as usize] = match b {
                    0..=0x7F => b as u32,
                    _ if cp.lead[b as usize] => invalid_byte(b),
                    _ => decode_acp(&[b]).unwrap_or(invalid_byte(b)),
                };
                cp.double |= cp.lead[b as usize];
                cp.lead_above_ascii &= b >= 0x80 || !cp.lead[b as usize];
                cp.table_reads &= b < 0x80 || cp.single[b as usize] >= 0x80;
            }
            cp.every_string_in_place = !cp.utf8 && !cp.double && cp.table_reads;
            cp
        })
    }

    impl CodePage {
        /// Whether `bytes` decode one character per byte, `single[byte]`: no lead byte among them.
        #[inline(always)]
        fn bytes_are_single(&self, bytes: &[u8]) -> bool {
            !self.double || (self.lead_above_ascii && bytes.is_ascii()) || !bytes.iter().any(|&b| self.lead[b as usize])
        }
    }

    /// Decodes `bytes` into `out`, one code point per character.
    fn decode(bytes: &[u8], out: &mut SmallVec<u32, 256>) {
        let cp = code_page();
        if cp.utf8 {
            let t = Utf8(bytes);
            let mut i = 0;
            while i < bytes.len() {
                let (c, next) = t.next(i);
                out.push(c);
                i = next;
            }
            return;
        }
        let mut i = 0;
        while i < bytes.len() {
            let b = bytes[i];
            if cp.lead[b as usize] && i + 1 < bytes.len() {
                if let Some(c) = decode_acp(&bytes[i..i + 2]) {
                    out.push(c);
                    i += 2;
                    continue;
                }
            }
            out.push(cp.single[b as usize]);
            i += 1;
        }
    }

    /// Every character of `bytes` as `decode` splits them (for the tests' reference).
    #[cfg(test)]
    pub(crate) fn decode_all(bytes: &[u8]) -> Vec<u32> {
        let mut chars = SmallVec::<u32, 256>::new();
        decode(bytes, &mut chars);
        chars.as_slice().to_vec()
    }

    pub(crate) fn compile(pattern: &[u8], case_sensitive: bool) -> Result<Program, Malformed> {
        let mut chars = SmallVec::new();
        decode(pattern, &mut chars);
        Program::compile(&Chars(chars.as_slice()), case_sensitive)
    }

    /// Whether the NUL-terminated `string` matches the compiled `program`: read in place in UTF-8 and
    /// in single-byte code pages (and in a double-byte one when the string has no lead byte), decoded
    /// first otherwise.
    ///
    /// # Safety
    /// `string` must point at a NUL-terminated string.
    pub(crate) unsafe fn matches(program: &Program, string: *const u8) -> bool {
        let cp = code_page();
        if cp.utf8 {
            // SAFETY: NUL-terminated (the caller's contract).
            return unsafe { program.matches_cursor(Utf8Cursor(string)) };
        }
        if cp.every_string_in_place {
            // SAFETY: as above.
            return unsafe { program.matches_cursor(TableCursor(string, &cp.single)) };
        }
        // SAFETY: as above.
        let Some(bytes) = (unsafe { cstr_bytes(string.cast()) }) else {
            return false;
        };
        if cp.table_reads && cp.bytes_are_single(bytes) {
            // SAFETY: as above.
            return unsafe { program.matches_cursor(TableCursor(string, &cp.single)) };
        }
        matches_decoded(program, bytes)
    }

    /// `matches` for a string decoded first (out of line: its buffer would make every caller's stack
    /// frame large).
    #[inline(never)]
    fn matches_decoded(program: &Program, bytes: &[u8]) -> bool {
        let mut chars = SmallVec::new();
        decode(bytes, &mut chars);
        program.matches(&Chars(chars.as_slice()))
    }

    /// `MatchPatternA` without compiling: both strings read in place where `matches` reads the string
    /// in place, decoded first (on the stack for ordinary lengths) otherwise. Inlined into the export:
    /// in a single-byte code page (the common case) a call costs `MatchPatternW`'s plus one test of
    /// the code page, with no frame of its own; every other code page goes out of line.
    ///
    /// # Safety
    /// Both must point at NUL-terminated strings.
    #[inline(always)]
    pub(crate) unsafe fn match_once(string: *const u8, pattern: *const u8, case_sensitive: bool) -> bool {
        let cp = code_page();
        if cp.every_string_in_place {
            let (s, p) = (TableCursor(string, &cp.single), TableCursor(pattern, &cp.single));
            // SAFETY: both are NUL-terminated (the caller's contract).
            return unsafe { match_in_place(s, p, pattern, case_sensitive) };
        }
        // SAFETY: as above.
        unsafe { match_once_other(cp, string, pattern, case_sensitive) }
    }

    /// `match_once` in UTF-8 and in double-byte code pages (and in any code page whose table cannot
    /// read strings in place).
    ///
    /// # Safety
    /// Both must point at NUL-terminated strings.
    #[inline(never)]
    unsafe fn match_once_other(cp: &CodePage, string: *const u8, pattern: *const u8, case_sensitive: bool) -> bool {
        if cp.utf8 {
            // SAFETY: both are NUL-terminated (the caller's contract).
            return unsafe { match_in_place(Utf8Cursor(string), Utf8Cursor(pattern), pattern, case_sensitive) };
        }
        let in_place = (TableCursor(string, &cp.single), TableCursor(pattern, &cp.single));
        // SAFETY: as above.
        let (string, pattern_bytes) = unsafe { (cstr_bytes(string.cast()), cstr_bytes(pattern.cast())) };
        let (Some(string), Some(pattern_bytes)) = (string, pattern_bytes) else {
            return false;
        };
        if cp.table_reads && cp.bytes_are_single(string) && cp.bytes_are_single(pattern_bytes) {
            // SAFETY: as above.
            return unsafe { match_in_place(in_place.0, in_place.1, pattern, case_sensitive) };
        }
        match_decoded(string, pattern_bytes, case_sensitive)
    }

    /// `match_once` for strings decoded first (out of line: its buffers would make every caller's
    /// stack frame large).
    #[inline(never)]
    fn match_decoded(string: &[u8], pattern: &[u8], case_sensitive: bool) -> bool {
        let mut s = SmallVec::new();
        decode(string, &mut s);
        s.push(0);
        let mut p = SmallVec::new();
        decode(pattern, &mut p);
        p.push(0);
        // SAFETY: both buffers end with a 0 and hold no other 0 (the strings had no NUL before their end).
        let once = unsafe {
            stream::matches(
                DecodedCursor(s.as_slice().as_ptr()),
                DecodedCursor(p.as_slice().as_ptr()),
                case_sensitive,
            )
        };
        once.unwrap_or_else(|| {
            // A long pattern: compile it (see `stream::matches`).
            let pattern = &p.as_slice()[..p.len() - 1];
            let string = &s.as_slice()[..s.len() - 1];
            match Program::compile(&Chars(pattern), case_sensitive) {
                Ok(program) => program.matches(&Chars(string)),
                Err(_) => false,
            }
        })
    }

    /// `stream::matches` over cursors that read the strings in place; a long pattern is compiled
    /// first (out of line, so the common path stays lean).
    ///
    /// # Safety
    /// Both cursors must point at NUL-terminated strings; `pattern` is the pattern's cursor's string.
    #[inline(always)]
    unsafe fn match_in_place(string: impl Cursor, cursor: impl Cursor, pattern: *const u8, cs: bool) -> bool {
        // SAFETY: both are NUL-terminated (the caller's contract).
        match unsafe { stream::matches(string, cursor, cs) } {
            Some(matched) => matched,
            // SAFETY: as above.
            None => unsafe { match_long_pattern(string, pattern, cs) },
        }
    }

    /// A pattern longer than `stream::LONG_PATTERN` with a `*`: compiled, then matched as by
    /// `matches`.
    ///
    /// # Safety
    /// `pattern` must point at a NUL-terminated string; `string` must be a cursor over one.
    #[cold]
    #[inline(never)]
    unsafe fn match_long_pattern(string: impl Cursor, pattern: *const u8, case_sensitive: bool) -> bool {
        // SAFETY: NUL-terminated (the caller's contract).
        let bytes = unsafe { cstr_bytes(pattern.cast()) }.unwrap_or_default();
        match compile(bytes, case_sensitive) {
            // SAFETY: as above.
            Ok(program) => unsafe { program.matches_cursor(string) },
            Err(_) => false,
        }
    }
}

#[cfg(all(test, windows))]
pub(crate) use imp::decode_all;
pub(crate) use imp::{compile, match_once, matches};
