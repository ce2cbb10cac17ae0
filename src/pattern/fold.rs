//! Unicode simple case folding (one code point to one code point), used for case-insensitive matching.
//! The table is generated from the Unicode Character Database by `tools/gen-case-folding.py`.

use super::fold_table::FOLD_RUNS;

/// The simple case folding of `c` (CaseFolding.txt statuses C and S); `c` itself when it has none.
/// Surrogates and the values used for undecodable bytes have none.
#[inline(always)]
pub(crate) fn fold(c: u32) -> u32 {
    if c < 0x80 {
        if c.wrapping_sub(b'A' as u32) < 26 {
            c + 32
        } else {
            c
        }
    } else {
        fold_non_ascii(c)
    }
}

fn fold_non_ascii(c: u32) -> u32 {
    let i = FOLD_RUNS.partition_point(|r| r.0 <= c);
    if i == 0 {
        return c;
    }
    let (first, last, delta, stride) = FOLD_RUNS[i - 1];
    if c <= last && (stride <= 1 || (c - first) % stride as u32 == 0) {
        c.wrapping_add_signed(delta)
    } else {
        c
    }
}

/// Calls `add(lo, hi)` with ranges that together contain the case foldings of every code point in
/// `lo..=hi` that does not fold to itself (some ranges may also contain code points of `lo..=hi`).
/// With `lo..=hi` itself this covers `{ fold(x) : lo <= x <= hi }`, the set a case-insensitive range
/// stands for.
pub(crate) fn for_each_folded_range(lo: u32, hi: u32, mut add: impl FnMut(u32, u32)) {
    let start = FOLD_RUNS.partition_point(|r| r.1 < lo);
    for &(first, last, delta, stride) in &FOLD_RUNS[start..] {
        if first > hi {
            break;
        }
        let a = first.max(lo);
        let b = last.min(hi);
        if stride <= 1 {
            add(a.wrapping_add_signed(delta), b.wrapping_add_signed(delta));
        } else {
            let stride = stride as u32;
            let mut x = first + (a - first).div_ceil(stride) * stride;
            while x <= b {
                let t = x.wrapping_add_signed(delta);
                if t < lo || t > hi {
                    add(t, t);
                }
                x += stride;
            }
        }
    }
}

/// The code points a test walks for "every code point", in order: all of them, or under Miri (which
/// is some ten thousand times slower) all of ASCII, the first and last code point of every folding
/// run, and one in 16,411 of the rest.
#[cfg(test)]
pub(crate) fn test_code_points() -> &'static [u32] {
    static POINTS: std::sync::OnceLock<Vec<u32>> = std::sync::OnceLock::new();
    POINTS.get_or_init(|| {
        if !cfg!(miri) {
            return (0..0x11_0000).collect();
        }
        let mut v = Vec::new();
        let mut next = 0u32;
        let gap = |v: &mut Vec<u32>, from: u32, to: u32| {
            let mut c = from;
            while c < to {
                v.push(c);
                c = if c < 0x80 { c + 1 } else { (c / 16411 + 1) * 16411 };
            }
        };
        for &(first, last, _, _) in &FOLD_RUNS {
            gap(&mut v, next, first);
            let from = first.max(next);
            if from <= last {
                v.push(from);
            }
            if last > from {
                v.push(last);
            }
            next = next.max(last + 1);
        }
        gap(&mut v, next, 0x11_0000);
        v
    })
}

#[cfg(test)]
mod tests {
    use super::super::fold_table::{FOLDING_COUNT, UNICODE_VERSION};
    use super::*;

    #[test]
    fn known_simple_foldings() {
        let cases = [
            ('A', 'a'),
            ('z', 'z'),
            ('É', 'é'),
            ('é', 'é'),
            ('\u{212A}', 'k'), // KELVIN SIGN
            ('\u{017F}', 's'), // LATIN SMALL LETTER LONG S
            ('Σ', 'σ'),
            ('ς', 'σ'),
            ('\u{1E9E}', 'ß'),        // status S: simple folding of CAPITAL SHARP S
            ('\u{0130}', '\u{0130}'), // only F and T foldings: simple folding keeps it
            ('\u{13F8}', '\u{13F0}'), // Cherokee small letters fold to capitals
            ('\u{AB70}', '\u{13A0}'),
            ('\u{10400}', '\u{10428}'), // Deseret, beyond the BMP
            ('\u{1E921}', '\u{1E943}'),
            ('Ā', 'ā'),
            ('ā', 'ā'),
            ('0', '0'),
            ('\u{FF21}', '\u{FF41}'), // FULLWIDTH A
        ];
        for (from, to) in cases {
            assert_eq!(fold(from as u32), to as u32, "{from:?}");
        }
        assert_eq!(fold(0xD800), 0xD800);
        assert_eq!(fold(0xDCC3), 0xDCC3);
    }

    #[test]
    fn folding_is_idempotent_and_counts_match_the_table() {
        let mut changed = 0;
        for &c in test_code_points() {
            let f = fold(c);
            assert_eq!(fold(f), f, "{c:X}");
            changed += (f != c) as usize;
        }
        // Every code point that folds was walked (not so under Miri, which samples).
        if cfg!(miri) {
            assert!(changed > 0 && changed < FOLDING_COUNT);
        } else {
            assert_eq!(changed, FOLDING_COUNT);
        }
    }

    /// Checks every entry against the Unicode data file when the `unicode-data` package provides the
    /// same version the table was generated from.
    #[test]
    #[cfg_attr(miri, ignore)] // reads a file of the system
    fn agrees_with_casefolding_txt_when_installed() {
        let Ok(text) = std::fs::read_to_string("/usr/share/unicode/CaseFolding.txt") else {
            eprintln!("CaseFolding.txt not installed: checked against the known foldings only");
            return;
        };
        if !text.contains(&format!("CaseFolding-{UNICODE_VERSION}.txt")) {
            eprintln!("CaseFolding.txt is another Unicode version: not compared");
            return;
        }
        let mut seen = 0;
        for line in text.lines() {
            let line = line.split('#').next().unwrap().trim();
            let f: Vec<&str> = line.split(';').map(str::trim).collect();
            if f.len() < 3 || !(f[1] == "C" || f[1] == "S") {
                continue;
            }
            let from = u32::from_str_radix(f[0], 16).unwrap();
            let to = u32::from_str_radix(f[2], 16).unwrap();
            assert_eq!(fold(from), to, "{from:X}");
            seen += 1;
        }
        assert_eq!(seen, FOLDING_COUNT);
    }

    #[test]
    #[cfg_attr(miri, ignore)] // code points x ranges: far too long under Miri; the matcher tests run the same code
    fn folded_ranges_cover_exactly_the_image_of_a_range() {
        for (lo, hi) in [
            (0x41, 0x5A),
            (0x100, 0x17F),
            (0x0, 0x2FF),
            (0x10400, 0x10427),
            (0x212A, 0x212A),
        ] {
            let mut ranges = vec![(lo, hi)];
            for_each_folded_range(lo, hi, |a, b| ranges.push((a, b)));
            let covered = |c: u32| ranges.iter().any(|&(a, b)| a <= c && c <= b);
            for x in lo..=hi {
                assert!(covered(fold(x)), "{x:X} in {lo:X}-{hi:X}");
            }
            // Anything covered that is a folding target must be the folding of something in range.
            let image: std::collections::HashSet<u32> = (lo..=hi).map(fold).collect();
            for &c in test_code_points() {
                if covered(c) && fold(c) == c {
                    assert!(image.contains(&c), "{c:X} is not in the image of {lo:X}-{hi:X}");
                }
            }
        }
    }
}
