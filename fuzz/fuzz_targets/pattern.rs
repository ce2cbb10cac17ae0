//! MatchPattern: every entry point (MatchPatternW/A, the compiled filter in both widths) against the
//! reference matcher of the tests (dynamic programming over the rules of docs/guide/matchpattern.md).
//!
//! Input: one flags byte (bit 0: case sensitive; bit 1: the rest is UTF-16LE units, else bytes), then
//! the pattern, a NUL, the string (a missing NUL: empty string). Bytes go to the narrow functions as
//! they are (UTF-8 on Linux, invalid sequences included) and to the wide ones as the same characters in
//! UTF-16, each byte of an invalid sequence as the unpaired surrogate 0xDC00 + byte, which is also how
//! the reference sees it; raw units reach the wide functions only.
#![no_main]

use libfuzzer_sys::fuzz_target;
use opccomn::com::{FALSE, S_OK, TRUE};
use opccomn::pattern::reference::{decode_narrow, decode_wide, ref_match};
use opccomn::pattern::{
    MatchPatternA, MatchPatternW, OpcPatternCompileA, OpcPatternCompileW, OpcPatternFree, OpcPatternMatchA,
    OpcPatternMatchW,
};

fn wide_of(chars: &[u32]) -> Vec<u16> {
    let mut out = Vec::new();
    for &c in chars {
        match char::from_u32(c) {
            Some(ch) => out.extend_from_slice(ch.encode_utf16(&mut [0; 2])),
            None => out.push(c as u16), // an unpaired surrogate
        }
    }
    out
}

fn boolean(r: i32) -> bool {
    assert!(r == TRUE || r == FALSE, "BOOL result {r}");
    r == TRUE
}

/// Every wide entry point for `s` Like `p`; NUL-free inputs.
fn wide_results(s: &[u16], p: &[u16], cs: bool) -> bool {
    let s: Vec<u16> = s.iter().copied().chain([0]).collect();
    let p: Vec<u16> = p.iter().copied().chain([0]).collect();
    // SAFETY: NUL-terminated.
    let direct = boolean(unsafe { MatchPatternW(s.as_ptr(), p.as_ptr(), cs as i32) }.get());
    let mut filter = core::ptr::null_mut();
    // SAFETY: NUL-terminated pattern, writable out-pointer.
    let hr = unsafe { OpcPatternCompileW(p.as_ptr(), cs as i32, &mut filter) }.get();
    if hr == S_OK {
        // SAFETY: a live filter, freed once.
        let compiled = boolean(unsafe { OpcPatternMatchW(filter, s.as_ptr()) }.get());
        // SAFETY: as above.
        unsafe { OpcPatternFree(filter) };
        assert_eq!(compiled, direct, "compiled filter vs MatchPatternW");
    } else {
        assert!(filter.is_null());
        assert!(
            !direct,
            "MatchPatternW matched a pattern OpcPatternCompileW refused ({hr:#x})"
        );
    }
    direct
}

/// Every narrow entry point; NUL-free inputs.
fn narrow_results(s: &[u8], p: &[u8], cs: bool) -> bool {
    let s: Vec<u8> = s.iter().copied().chain([0]).collect();
    let p: Vec<u8> = p.iter().copied().chain([0]).collect();
    // SAFETY: NUL-terminated.
    let direct = boolean(unsafe { MatchPatternA(s.as_ptr().cast(), p.as_ptr().cast(), cs as i32) }.get());
    let mut filter = core::ptr::null_mut();
    // SAFETY: as in `wide_results`.
    let hr = unsafe { OpcPatternCompileA(p.as_ptr().cast(), cs as i32, &mut filter) }.get();
    if hr == S_OK {
        // SAFETY: a live filter, freed once.
        let compiled = boolean(unsafe { OpcPatternMatchA(filter, s.as_ptr().cast()) }.get());
        // SAFETY: as above.
        unsafe { OpcPatternFree(filter) };
        assert_eq!(compiled, direct, "compiled filter vs MatchPatternA");
    } else {
        assert!(filter.is_null());
        assert!(
            !direct,
            "MatchPatternA matched a pattern OpcPatternCompileA refused ({hr:#x})"
        );
    }
    direct
}

fuzz_target!(|data: &[u8]| {
    let Some((&flags, rest)) = data.split_first() else {
        return;
    };
    let cs = flags & 1 != 0;
    if flags & 2 != 0 {
        let units: Vec<u16> = rest.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect();
        let mut parts = units.splitn(3, |&u| u == 0);
        let p = parts.next().unwrap_or_default();
        let s = parts.next().unwrap_or_default();
        let expected = ref_match(&decode_wide(s), &decode_wide(p), cs);
        assert_eq!(
            wide_results(s, p, cs),
            expected,
            "wide {s:x?} Like {p:x?} (case sensitive: {cs})"
        );
    } else {
        let mut parts = rest.splitn(3, |&b| b == 0);
        let p = parts.next().unwrap_or_default();
        let s = parts.next().unwrap_or_default();
        let (sc, pc) = (decode_narrow(s), decode_narrow(p));
        let expected = ref_match(&sc, &pc, cs);
        assert_eq!(
            narrow_results(s, p, cs),
            expected,
            "narrow {s:x?} Like {p:x?} (case sensitive: {cs})"
        );
        assert_eq!(
            wide_results(&wide_of(&sc), &wide_of(&pc), cs),
            expected,
            "wide form of {s:x?} Like {p:x?} (case sensitive: {cs})"
        );
    }
});
