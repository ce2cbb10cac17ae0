//! MatchPattern against the published test vectors, against a reference matcher on random input, and on
//! adversarial input.

use std::ffi::CString;

#[cfg(not(windows))]
use super::reference::decode_narrow;
use super::reference::{decode_wide, ref_match};
use super::steps;
use super::*;
use crate::com::E_INVALIDARG;
use core::ptr;

/// Whether `MatchPatternA` reads UTF-8 (everywhere but Windows).
const NARROW_IS_UTF8: bool = cfg!(not(windows));

fn wide(s: &str) -> Vec<u16> {
    s.encode_utf16().chain([0]).collect()
}

fn match_w(s: &[u16], p: &[u16], cs: bool) -> bool {
    let mut s = s.to_vec();
    s.push(0);
    let mut p = p.to_vec();
    p.push(0);
    // SAFETY: both are NUL-terminated.
    let r = unsafe { MatchPatternW(s.as_ptr(), p.as_ptr(), cs as BOOL) };
    assert!(r == TRUE || r == FALSE);
    r == TRUE
}

fn match_a(s: &[u8], p: &[u8], cs: bool) -> bool {
    let s = CString::new(s).unwrap();
    let p = CString::new(p).unwrap();
    // SAFETY: both are NUL-terminated.
    let r = unsafe { MatchPatternA(s.as_ptr(), p.as_ptr(), cs as BOOL) };
    assert!(r == TRUE || r == FALSE);
    r == TRUE
}

/// The compiled filter's answer for a wide and a narrow string, or `None` for OPC_E_INVALIDFILTER.
fn match_compiled(s: &str, p: &str, cs: bool) -> Option<(bool, bool)> {
    let pw = wide(p);
    let mut f = ptr::null_mut();
    // SAFETY: valid string and out-pointer.
    let hr = unsafe { OpcPatternCompileW(pw.as_ptr(), cs as BOOL, &mut f) };
    if hr == OPC_E_INVALIDFILTER {
        assert!(f.is_null());
        return None;
    }
    assert_eq!(hr, S_OK);
    let sw = wide(s);
    let sa = CString::new(s).unwrap();
    // SAFETY: `f` is a live filter; the strings are NUL-terminated.
    let r = unsafe { (OpcPatternMatchW(f, sw.as_ptr()), OpcPatternMatchA(f, sa.as_ptr())) };
    // SAFETY: freed once.
    unsafe { OpcPatternFree(f) };
    Some((r.0 == TRUE, r.1 == TRUE))
}

/// Every row through MatchPatternW, MatchPatternA and the compiled filter (under Miri every row through
/// MatchPatternW, one in 4 through the others).
#[test]
fn every_vector_row_passes_through_every_entry_point() {
    let mut rows = 0;
    for (i, line) in include_str!("like-vectors.tsv").lines().skip(1).enumerate() {
        let f: Vec<&str> = line.split('\t').collect();
        let (s, p, cs, expected) = (f[0], f[1], f[2] == "1", f[3] == "1");
        let what = || format!("{s:?} Like {p:?} (case sensitive: {cs}) from {}", f[4]);
        let (sw, pw): (Vec<u16>, Vec<u16>) = (s.encode_utf16().collect(), p.encode_utf16().collect());
        assert_eq!(match_w(&sw, &pw, cs), expected, "W: {}", what());
        // Narrow strings are UTF-8 except on Windows (the ANSI code page): there, ASCII rows only.
        if cfg!(miri) && i % 4 != 0 {
            rows += 1;
            continue;
        }
        let narrow = NARROW_IS_UTF8 || (s.is_ascii() && p.is_ascii());
        if narrow {
            assert_eq!(match_a(s.as_bytes(), p.as_bytes(), cs), expected, "A: {}", what());
        }
        {
            let (w, a) = match_compiled(s, p, cs).unwrap_or((false, false));
            assert_eq!(w, expected, "compiled W: {}", what());
            if narrow {
                assert_eq!(a, expected, "compiled A: {}", what());
            }
        }
        rows += 1;
    }
    assert!(rows >= 150, "only {rows} rows");
}

#[test]
fn null_arguments_never_match_and_compile_reports_them() {
    let a = wide("a");
    // SAFETY: NULL is allowed for every pointer argument here.
    unsafe {
        assert_eq!(MatchPatternW(ptr::null(), a.as_ptr(), 1), FALSE);
        assert_eq!(MatchPatternW(a.as_ptr(), ptr::null(), 1), FALSE);
        assert_eq!(MatchPatternW(ptr::null(), ptr::null(), 0), FALSE);
        assert_eq!(MatchPatternA(ptr::null(), c"*".as_ptr(), 0), FALSE);
        assert_eq!(MatchPatternA(c"".as_ptr(), ptr::null(), 0), FALSE);
        let mut f = core::ptr::null_mut::<OpcPattern>().wrapping_byte_add(1);
        assert_eq!(OpcPatternCompileW(ptr::null(), 1, &mut f), E_INVALIDARG);
        assert!(f.is_null());
        f = core::ptr::null_mut::<OpcPattern>().wrapping_byte_add(1);
        assert_eq!(OpcPatternCompileA(ptr::null(), 1, &mut f), E_INVALIDARG);
        assert!(f.is_null());
        assert_eq!(OpcPatternCompileW(a.as_ptr(), 1, ptr::null_mut()), E_INVALIDARG);
        assert_eq!(OpcPatternMatchW(ptr::null(), a.as_ptr()), FALSE);
        assert_eq!(OpcPatternMatchA(ptr::null(), c"a".as_ptr()), FALSE);
        let star = wide("*");
        assert_eq!(OpcPatternCompileW(star.as_ptr(), 1, &mut f), S_OK);
        assert_eq!(OpcPatternMatchW(f, ptr::null()), FALSE);
        assert_eq!(OpcPatternMatchA(f, ptr::null()), FALSE);
        assert_eq!(OpcPatternMatchW(f, a.as_ptr()), TRUE);
        OpcPatternFree(f);
        OpcPatternFree(ptr::null_mut());
    }
}

#[test]
fn malformed_patterns_never_match_and_compile_to_invalidfilter() {
    for p in ["[", "a[b", "*[", "[!", "[a-", "[Z-A]", "a*[z-a]", "[]["] {
        assert!(
            !match_w(&wide("a")[..1], &wide(p)[..p.encode_utf16().count()], true),
            "{p}"
        );
        for s in ["", "a", "[", "[Z-A]", "ab"] {
            assert!(!match_a(s.as_bytes(), p.as_bytes(), false), "{s} {p}");
        }
        assert_eq!(match_compiled("a", p, true), None, "{p}");
    }
    // A pattern ending inside a list is never read past its NUL: the unit after the NUL is no `]`
    // that could close it.
    let buf = [b'[' as u16, b'a' as u16, 0, b']' as u16];
    // SAFETY: `buf` is NUL-terminated at index 2.
    assert_eq!(unsafe { MatchPatternW(wide("a").as_ptr(), buf.as_ptr(), 1) }, FALSE);
}

#[test]
fn unpaired_surrogates_and_invalid_bytes_are_single_characters() {
    let s = [0x61, 0xD800, 0x62];
    assert!(match_w(&s, &wide("a?b")[..3], true));
    assert!(match_w(&s, &[0x61, 0xD800, 0x62], true));
    assert!(!match_w(&s, &wide("a??b")[..4], true));
    assert!(match_w(&[0xDC00], &wide("?")[..1], true));
    assert!(match_w(&[0xD83D, 0xDE00], &wide("?")[..1], true)); // a pair is one character
    assert!(!match_w(&[0xD83D, 0xDE00], &wide("??")[..2], true));
    assert!(match_w(&[0xDE00, 0xD83D], &wide("??")[..2], true)); // low then high: two lone surrogates
    assert!(match_w(&[0xD83D], &[0x5B, 0xD800, 0x2D, 0xDBFF, 0x5D], true)); // [\uD800-\uDBFF]
    if NARROW_IS_UTF8 {
        assert!(match_a(b"a\xFFb", b"a?b", true));
        assert!(match_a(b"a\xC3b", b"a\xC3b", true));
        assert!(!match_a(b"a\xC3b", b"a\xC4b", true));
        assert!(match_a(b"\xC3\xA9", b"?", true));
        assert!(match_a(b"\xE2\x82", b"??", true)); // truncated sequence: two bytes, two characters
        assert!(match_a(b"\xC3\xA9", b"\xC3\x89", false)); // é vs É
        assert!(match_a(b"\xF0", b"[\x80-\xFF]", true));
    }
}

// ---- differential testing against a reference matcher ----

struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// UTF-16 units drawn from an alphabet rich in pattern syntax, case pairs and surrogates.
const UNITS: &[&[u16]] = &[
    &[0x61],
    &[0x62],
    &[0x41],
    &[0x42],
    &[0x6B],
    &[0x4B],
    &[0x212A],
    &[0x73],
    &[0x17F],
    &[0xE9],
    &[0xC9],
    &[0x5B],
    &[0x5D],
    &[0x21],
    &[0x2D],
    &[0x23],
    &[0x2A],
    &[0x3F],
    &[0x30],
    &[0x35],
    &[0x39],
    &[0x7A],
    &[0xD83D, 0xDE00],
    &[0xD801, 0xDC00],
    &[0xD801, 0xDC28],
    &[0xD800],
    &[0xDC00],
    &[0xDBFF],
    &[0x3A3],
    &[0x3C2],
];

fn random_wide(rng: &mut XorShift, max: usize) -> Vec<u16> {
    let len = rng.below(max + 1);
    let mut v = Vec::new();
    for _ in 0..len {
        v.extend_from_slice(UNITS[rng.below(UNITS.len())]);
    }
    v
}

/// Runs `cases` random (string, pattern) pairs through the library and the reference.
fn differential_wide(seed: u64, cases: usize) {
    let mut rng = XorShift(seed);
    for case in 0..cases {
        let p = random_wide(&mut rng, 9);
        let s = random_wide(&mut rng, 9);
        let cs = rng.next() & 1 == 0;
        let expected = ref_match(&decode_wide(&s), &decode_wide(&p), cs);
        let got = match Program::compile(&Utf16(&p), cs) {
            Ok(prog) => {
                let mut nul_terminated = s.clone();
                nul_terminated.push(0);
                // SAFETY: NUL-terminated.
                let by_cursor = unsafe { prog.matches_cursor(stream::WideCursor(nul_terminated.as_ptr())) };
                assert_eq!(by_cursor, prog.matches(&Utf16(&s)), "case {case}");
                by_cursor
            }
            Err(_) => false,
        };
        assert_eq!(
            got,
            expected,
            "case {case}: {:?} Like {:?} (case sensitive: {cs})",
            String::from_utf16_lossy(&s),
            String::from_utf16_lossy(&p)
        );
        // The one-call matcher (reading in place) agrees too.
        assert_eq!(match_w(&s, &p, cs), expected, "MatchPatternW, case {case}");
    }
}

/// How many random cases the differential test runs: `OPCCOMN_DIFFERENTIAL_CASES`, else 1,000,000
/// (16 under Miri, which is some ten thousand times slower than a debug build).
fn differential_cases() -> usize {
    std::env::var("OPCCOMN_DIFFERENTIAL_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(if cfg!(miri) { 16 } else { 1_000_000 })
}

/// `n` cases, or `under_miri` under Miri.
fn scaled(n: usize, under_miri: usize) -> usize {
    if cfg!(miri) {
        under_miri
    } else {
        n
    }
}

#[test]
fn differential_against_reference_wide() {
    differential_wide(0x9E37_79B9_7F4A_7C15, differential_cases());
}

#[test]
fn differential_long_patterns() {
    // Patterns beyond stream::LONG_PATTERN take the compiled path inside MatchPatternW/A.
    let mut rng = XorShift(0xD1B5_4A32_D192_ED03);
    for case in 0..scaled(2_000, 2) {
        let mut p = random_wide(&mut rng, 100);
        while p.len() <= stream::LONG_PATTERN {
            p.push(b'*' as u16);
            p.extend(random_wide(&mut rng, 20));
        }
        let s = random_wide(&mut rng, 200);
        let cs = rng.next() & 1 == 0;
        let expected = ref_match(&decode_wide(&s), &decode_wide(&p), cs);
        assert_eq!(match_w(&s, &p, cs), expected, "case {case}");
        if let (true, Ok(sn), Ok(pn)) = (NARROW_IS_UTF8, String::from_utf16(&s), String::from_utf16(&p)) {
            assert_eq!(
                match_a(sn.as_bytes(), pn.as_bytes(), cs),
                expected,
                "case {case} narrow"
            );
        }
    }
}

#[test]
fn differential_long_literal_runs() {
    // Runs of 16 or more literals in a middle segment take the Knuth-Morris-Pratt search; a two-letter
    // alphabet makes partial matches and borders common.
    let mut rng = XorShift(0x6A09_E667_F3BC_C909);
    let ab = |rng: &mut XorShift, n: usize| -> Vec<u16> {
        (0..n)
            .map(|_| if rng.next() & 1 == 0 { b'a' as u16 } else { b'B' as u16 })
            .collect()
    };
    for case in 0..scaled(20_000, 2) {
        let mut p = vec![b'*' as u16];
        let run = 16 + rng.below(9);
        p.extend(ab(&mut rng, run));
        p.extend_from_slice(UNITS[rng.below(UNITS.len())]);
        p.push(b'*' as u16);
        if rng.next() & 1 == 0 {
            p.extend(ab(&mut rng, 2));
        }
        let len = rng.below(70);
        let s = ab(&mut rng, len);
        let cs = rng.next() & 1 == 0;
        let expected = ref_match(&decode_wide(&s), &decode_wide(&p), cs);
        let prog = Program::compile(&Utf16(&p), cs);
        let got = prog.map(|prog| prog.matches(&Utf16(&s))).unwrap_or(false);
        assert_eq!(
            got,
            expected,
            "case {case}: {:?} Like {:?}",
            String::from_utf16_lossy(&s),
            String::from_utf16_lossy(&p)
        );
        assert_eq!(match_w(&s, &p, cs), expected, "MatchPatternW, case {case}");
    }
}

/// Bytes for the narrow differential tests: pattern syntax, case pairs, and bytes of 0x80 and above
/// (in a double-byte code page such as 932 some are lead bytes, and `\x83A` is one character).
const NARROW_BYTES: &[u8] = &[
    b'a', b'b', b'A', b'K', b'k', b's', b'S', b'[', b']', b'!', b'-', b'#', b'*', b'?', b'0', b'9', 0x80, 0x81, 0x82,
    0x83, 0x8A, 0x9A, 0x9F, 0xA0, 0xC9, 0xD7, 0xE0, 0xE9, 0xFF,
];

fn random_narrow(rng: &mut XorShift, max: usize) -> Vec<u8> {
    let len = rng.below(max + 1);
    (0..len).map(|_| NARROW_BYTES[rng.below(NARROW_BYTES.len())]).collect()
}

/// A pattern long enough (over `stream::LONG_PATTERN`) to be compiled by the one-call matchers.
fn long_narrow(rng: &mut XorShift) -> Vec<u8> {
    let mut p = random_narrow(rng, 4);
    p.push(b'*');
    p.extend((0..140).map(|_| [b'?', b'*', b'a', 0xE9][rng.below(4)]));
    p.extend(random_narrow(rng, 4));
    p
}

#[test]
fn single_byte_code_pages_read_in_place_like_the_decoded_text() {
    // Windows-1252 in part: undefined bytes, letters whose case pair is elsewhere in the table (0x9F is
    // Ÿ, whose folding ÿ is 0xFF), the rest Latin-1.
    let mut table = [0u32; 256];
    for (b, entry) in table.iter_mut().enumerate() {
        *entry = match b {
            0x80 => 0x20AC,
            0x8A => 0x160,
            0x9A => 0x161,
            0x9F => 0x178,
            0x81 | 0x8D | 0x8F | 0x90 | 0x9D => text::invalid_byte(b as u8),
            _ => b as u32,
        };
    }
    let decode = |b: &[u8]| b.iter().map(|&x| table[x as usize]).collect::<Vec<u32>>();
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    for case in 0..differential_cases() / 10 {
        let p = if case % 16 == 0 {
            long_narrow(&mut rng)
        } else {
            random_narrow(&mut rng, 9)
        };
        let s = random_narrow(&mut rng, 9);
        let cs = rng.next() & 1 == 0;
        let expected = ref_match(&decode(&s), &decode(&p), cs);
        let what = format!("case {case}: {s:x?} Like {p:x?} (case sensitive: {cs})");
        let (sz, pz) = (CString::new(s.clone()).unwrap(), CString::new(p.clone()).unwrap());
        let (sc, pc) = (
            stream::TableCursor(sz.as_ptr().cast(), &table),
            stream::TableCursor(pz.as_ptr().cast(), &table),
        );
        // SAFETY: both are NUL-terminated.
        match unsafe { stream::matches(sc, pc, cs) } {
            Some(got) => assert_eq!(got, expected, "one call, {what}"),
            None => assert!(
                p.len() > stream::LONG_PATTERN,
                "only long patterns are handed back: {what}"
            ),
        }
        let compiled = Program::compile(&text::TableText(&p, &table), cs);
        let got = match compiled {
            Ok(prog) => {
                // SAFETY: NUL-terminated.
                let by_cursor = unsafe { prog.matches_cursor(sc) };
                assert_eq!(by_cursor, prog.matches(&text::TableText(&s, &table)), "{what}");
                by_cursor
            }
            Err(_) => false,
        };
        assert_eq!(got, expected, "compiled, {what}");
    }
}

/// MatchPatternA and the compiled filter in the process's ANSI code page against the reference over
/// the characters the code page decodes: in place or decoded first, the answers are the same. When
/// `OPCCOMN_TEST_ACP` is set, the code page must be that one (test.sh runs this under 932, a
/// double-byte code page, as well as under the default).
#[cfg(windows)]
#[test]
fn narrow_entry_points_agree_with_the_decoded_ansi_code_page() {
    // SAFETY: no arguments.
    let acp = unsafe { windows_sys::Win32::Globalization::GetACP() };
    if let Ok(want) = std::env::var("OPCCOMN_TEST_ACP") {
        assert_eq!(acp.to_string(), want, "the ANSI code page");
    }
    eprintln!("narrow differential in ANSI code page {acp}");
    let mut rng = XorShift(0xD1B5_4A32_D192_ED03);
    for case in 0..differential_cases() / 10 {
        let p = if case % 16 == 0 {
            long_narrow(&mut rng)
        } else {
            random_narrow(&mut rng, 9)
        };
        let s = random_narrow(&mut rng, 9);
        let cs = rng.next() & 1 == 0;
        let expected = ref_match(&narrow::decode_all(&s), &narrow::decode_all(&p), cs);
        let what = format!("case {case}: {s:x?} Like {p:x?} (case sensitive: {cs})");
        assert_eq!(match_a(&s, &p, cs), expected, "MatchPatternA, {what}");
        let (sz, pz) = (CString::new(s.clone()).unwrap(), CString::new(p.clone()).unwrap());
        let mut f = ptr::null_mut();
        // SAFETY: a NUL-terminated pattern and a writable out-pointer.
        let hr = unsafe { OpcPatternCompileA(pz.as_ptr(), cs as BOOL, &mut f) };
        if hr == OPC_E_INVALIDFILTER {
            assert!(!expected, "{what}");
            continue;
        }
        assert_eq!(hr, S_OK, "{what}");
        // SAFETY: a live filter and a NUL-terminated string; freed once.
        let got = unsafe { OpcPatternMatchA(f, sz.as_ptr()) } == TRUE;
        // SAFETY: freed once.
        unsafe { OpcPatternFree(f) };
        assert_eq!(got, expected, "OpcPatternMatchA, {what}");
    }
}

#[cfg(windows)]
#[test]
fn narrow_strings_use_the_ansi_code_page() {
    // SAFETY: no arguments.
    let acp = unsafe { windows_sys::Win32::Globalization::GetACP() };
    if acp != 1252 {
        eprintln!("ANSI code page {acp}: the Windows-1252 checks do not apply");
        return;
    }
    assert!(match_a(b"\xC9t\xC9", b"\xE9t\xE9", false)); // ÉtÉ vs étÉ
    assert!(!match_a(b"\xC9", b"\xE9", true));
    assert!(match_a(b"\x80", b"?", true)); // the euro sign
    assert!(match_a(b"\xE9", b"[\xE0-\xFF]", true));
}

#[cfg(not(windows))]
#[test]
fn differential_against_reference_narrow() {
    let bytes: &[&[u8]] = &[
        b"a",
        b"b",
        b"A",
        b"K",
        b"k",
        b"[",
        b"]",
        b"!",
        b"-",
        b"#",
        b"*",
        b"?",
        b"0",
        b"9",
        "é".as_bytes(),
        "É".as_bytes(),
        "\u{212A}".as_bytes(),
        "😀".as_bytes(),
        b"\xC3",
        b"\xFF",
        b"\x80",
        b"\xE2\x82",
    ];
    let mut rng = XorShift(0x2545_F491_4F6C_DD1D);
    let gen = |rng: &mut XorShift| {
        let len = rng.below(10);
        (0..len)
            .flat_map(|_| bytes[rng.below(bytes.len())].iter().copied())
            .collect::<Vec<u8>>()
    };
    let decode = decode_narrow;
    for case in 0..differential_cases() / 4 {
        let p = gen(&mut rng);
        let s = gen(&mut rng);
        let cs = rng.next() & 1 == 0;
        let expected = ref_match(&decode(&s), &decode(&p), cs);
        let got = match narrow::compile(&p, cs) {
            Ok(prog) => {
                let nul_terminated = CString::new(s.clone()).unwrap();
                // SAFETY: NUL-terminated.
                let by_cursor = unsafe { narrow::matches(&prog, nul_terminated.as_ptr().cast()) };
                assert_eq!(by_cursor, prog.matches(&text::Utf8(&s)), "case {case}");
                by_cursor
            }
            Err(_) => false,
        };
        assert_eq!(got, expected, "case {case}: {s:x?} Like {p:x?} (case sensitive: {cs})");
        assert_eq!(
            match_a(&s, &p, cs),
            expected,
            "MatchPatternA, case {case}: {s:x?} Like {p:x?}"
        );
    }
}

/// Under Miri every kind of case at a sixteenth of its length (the `*?` run at an eighth: shorter, it
/// reads each character more often than the bound allows), and k = 4, 8, 12 only.
#[test]
fn adversarial_patterns_take_bounded_steps() {
    let n = |len: usize| if cfg!(miri) { len / 16 } else { len };
    let a100 = "a".repeat(if cfg!(miri) { 25 } else { 100 });
    let mut cases: Vec<(String, String, bool)> = Vec::new();
    for k in (4..=12).step_by(if cfg!(miri) { 4 } else { 1 }) {
        cases.push((a100.clone(), "a*".repeat(k) + "b", false));
        cases.push((a100.clone(), "a*".repeat(k) + "a", true));
    }
    cases.push(("a".repeat(24), "*".repeat(12) + "b", false));
    cases.push((
        "a".repeat(n(4096)),
        "*".to_string() + &"a".repeat(n(2048) - 1) + "#*",
        false,
    ));
    cases.push(("a".repeat(2 * n(4096)), "*?".repeat(2 * n(1000)) + "b", false));
    cases.push(("ab".repeat(n(2048)), "*a?".repeat(n(1000)) + "c*", false));
    cases.push((
        "a".repeat(n(4096) - 1) + "b",
        "*".to_string() + &"[a-z]".repeat(n(800)) + "*b",
        true,
    ));

    for (s, p, expected) in &cases {
        let (sw, pw) = (wide(s), wide(p));
        // SAFETY: both are NUL-terminated.
        let (got, steps) = steps::counted(|| unsafe { MatchPatternW(sw.as_ptr(), pw.as_ptr(), 1) } == TRUE);
        let what = format!(
            "{} chars Like {}... ({} chars)",
            s.len(),
            &p[..p.len().min(20)],
            p.len()
        );
        assert_eq!(got, *expected, "{what}");
        // Steps are character reads (src/pattern/steps.rs); n and m count the terminators too.
        let (n, m) = (s.chars().count() as u64 + 1, p.chars().count() as u64 + 1);
        // The documented bound holds with room to spare: at most len(string) x len(pattern) steps (the
        // specification's recursive sample needs exponentially many for these, seconds for one call)...
        assert!(steps <= n * m, "{what}: {steps} steps, more than {}", n * m);
        // ...and these inputs, built to defeat backtracking, are linear: each character is read a few
        // times at most.
        assert!(
            steps <= READS_PER_CHAR * (n + m),
            "{what}: {steps} steps for {} characters",
            n + m
        );
        // The count is real: every case reads at least the shorter of its inputs.
        assert!(steps >= n.min(m) - 1, "{what}: {steps} steps");
    }
}

/// How many times the matcher may read each character of an adversarial case (a development run: at
/// most 2.5).
const READS_PER_CHAR: u64 = 4;

/// Memory whose last bytes sit right before an inaccessible page: a string copied to the end, NUL
/// included, makes any read past its terminator a crash instead of a silent over-read.
#[cfg(all(unix, not(miri)))]
struct GuardedTail {
    base: *mut u8,
    page: usize,
}

#[cfg(all(unix, not(miri)))]
impl GuardedTail {
    fn new() -> GuardedTail {
        // SAFETY: sysconf has no preconditions.
        let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) } as usize;
        // SAFETY: an anonymous private mapping of two pages; the second is made inaccessible.
        let base = unsafe {
            let p = libc::mmap(
                ptr::null_mut(),
                2 * page,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            );
            assert_ne!(p, libc::MAP_FAILED);
            assert_eq!(
                libc::mprotect(p.cast::<u8>().add(page).cast(), page, libc::PROT_NONE),
                0
            );
            p.cast::<u8>()
        };
        GuardedTail { base, page }
    }

    /// Copies `units` (without a NUL) plus a NUL so that the NUL is the last element before the guard.
    fn place<T: Copy + Default>(&mut self, units: &[T]) -> *const T {
        let size = core::mem::size_of::<T>();
        let len = units.len() + 1;
        assert!(len * size <= self.page, "too long for one page");
        // SAFETY: the destination lies inside the accessible first page, aligned for T (the page end
        // is aligned for any T of size 1 or 2).
        unsafe {
            let dst = self.base.add(self.page - len * size).cast::<T>();
            ptr::copy_nonoverlapping(units.as_ptr(), dst, units.len());
            *dst.add(units.len()) = T::default();
            dst
        }
    }
}

#[cfg(all(unix, not(miri)))]
impl Drop for GuardedTail {
    fn drop(&mut self) {
        // SAFETY: unmaps exactly the mapping made in `new`.
        unsafe { libc::munmap(self.base.cast(), 2 * self.page) };
    }
}

/// Under Miri (no mmap/mprotect): each text in an allocation of exactly its size, NUL included, so a
/// read past the terminator leaves the allocation, which Miri reports.
#[cfg(miri)]
struct GuardedTail {
    block: Option<(*mut u8, std::alloc::Layout)>,
}

#[cfg(miri)]
impl GuardedTail {
    fn new() -> GuardedTail {
        GuardedTail { block: None }
    }

    /// Copies `units` plus a NUL into a new allocation of that size; the previous one is freed.
    fn place<T: Copy + Default>(&mut self, units: &[T]) -> *const T {
        self.free();
        let layout = std::alloc::Layout::array::<T>(units.len() + 1).unwrap();
        // SAFETY: the layout is at least one element (the NUL) of a sized, non-zero-sized T.
        let dst = unsafe { std::alloc::alloc(layout) }.cast::<T>();
        assert!(!dst.is_null());
        // SAFETY: `dst` has room for `units.len() + 1` elements of T and is aligned for T.
        unsafe {
            ptr::copy_nonoverlapping(units.as_ptr(), dst, units.len());
            dst.add(units.len()).write(T::default());
        }
        self.block = Some((dst.cast(), layout));
        dst
    }

    fn free(&mut self) {
        if let Some((p, layout)) = self.block.take() {
            // SAFETY: allocated in `place` with this layout, freed once.
            unsafe { std::alloc::dealloc(p, layout) };
        }
    }
}

#[cfg(miri)]
impl Drop for GuardedTail {
    fn drop(&mut self) {
        self.free();
    }
}

/// Every entry point reads its string and pattern only up to their NUL: each is placed right before an
/// inaccessible page, for the published vectors, malformed patterns and random input.
#[cfg(unix)]
///
/// Under Miri each text sits in an allocation of exactly its size instead (a read past it is
/// reported), with every malformed pattern (against two strings), one vector row in 16, 6 random
/// cases and the long patterns just past the compiled-path threshold.
#[test]
fn no_entry_point_reads_past_a_terminator() {
    let mut s_tail = GuardedTail::new();
    let mut p_tail = GuardedTail::new();
    let mut cases: Vec<(Vec<u16>, Vec<u16>)> = Vec::new();
    let rows = include_str!("like-vectors.tsv").lines().skip(1);
    for line in rows.step_by(if cfg!(miri) { 16 } else { 1 }) {
        let f: Vec<&str> = line.split('\t').collect();
        cases.push((f[0].encode_utf16().collect(), f[1].encode_utf16().collect()));
    }
    for p in [
        "[", "a[b", "[!", "[a-", "[a-]", "*[", "[]*[", "[Z-A]", "*#[!", "[[", "-", "[-",
    ] {
        let strings: &[&str] = if cfg!(miri) {
            &["", "a-"]
        } else {
            &["", "a", "abc", "[", "a-"]
        };
        for s in strings {
            cases.push((s.encode_utf16().collect(), p.encode_utf16().collect()));
        }
    }
    let mut rng = XorShift(0x2545_F491_4F6C_DD1D);
    for _ in 0..scaled(20_000, 6) {
        cases.push((random_wide(&mut rng, 12), random_wide(&mut rng, 8)));
    }
    // Long patterns take the compiled path inside MatchPatternW/A.
    let long = if cfg!(miri) { stream::LONG_PATTERN / 2 + 1 } else { 150 };
    cases.push((vec![b'a' as u16; 2 * long], [b'*' as u16, b'a' as u16].repeat(long)));
    cases.push((vec![b'a' as u16; 2 * long], [b'*' as u16, b'[' as u16].repeat(long)));
    for (s, p) in &cases {
        for cs in [FALSE, TRUE] {
            let sp = s_tail.place(s);
            let pp = p_tail.place(p);
            // SAFETY: both are NUL-terminated; reading past the NUL faults.
            unsafe {
                MatchPatternW(sp, pp, cs);
                let mut f = ptr::null_mut();
                if OpcPatternCompileW(pp, cs, &mut f) == S_OK {
                    OpcPatternMatchW(f, sp);
                    OpcPatternFree(f);
                }
            }
            // The same text as UTF-8 (unpaired surrogates become U+FFFD) through the narrow functions.
            let sa: Vec<u8> = String::from_utf16_lossy(s).into_bytes();
            let pa: Vec<u8> = String::from_utf16_lossy(p).into_bytes();
            if sa.contains(&0) || pa.contains(&0) {
                continue;
            }
            let sp = s_tail.place(&sa).cast::<core::ffi::c_char>();
            let pp = p_tail.place(&pa).cast::<core::ffi::c_char>();
            // SAFETY: as above.
            unsafe {
                MatchPatternA(sp, pp, cs);
                let mut f = ptr::null_mut();
                if OpcPatternCompileA(pp, cs, &mut f) == S_OK {
                    OpcPatternMatchA(f, sp);
                    OpcPatternFree(f);
                }
            }
        }
    }
}
