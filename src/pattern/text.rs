//! Strings as sequences of characters, for the matcher: UTF-16 (the `W` functions), UTF-8 (the `A`
//! functions off Windows) and already decoded code points (the `A` functions on Windows).
//!
//! A character is one Unicode scalar value. Input that does not decode is never rejected: an unpaired
//! surrogate is one character whose value is the surrogate itself, and a byte that does not start a
//! valid UTF-8 sequence is one character with the value `0xDC00 + byte` (U+DC80..U+DCFF, the values
//! Python's `surrogateescape` uses), which no valid narrow text can produce. Decoding never reads
//! outside the slice.

/// The value an undecodable narrow byte (always 0x80 or above) is matched as.
pub(crate) const fn invalid_byte(b: u8) -> u32 {
    0xDC00 + b as u32
}

/// A string the matcher walks character by character, forwards and backwards. Positions are code unit
/// indices; both directions split the string into the same characters.
pub(crate) trait Text {
    /// Length in code units.
    fn units(&self) -> usize;
    /// The character starting at unit `i` (`i < units()`) and the index after it.
    fn next(&self, i: usize) -> (u32, usize);
    /// The character ending at unit `i` (`0 < i <= units()`) and the index where it starts.
    fn prev(&self, i: usize) -> (u32, usize);
    /// The code unit at `i` (`i < units()`), undecoded.
    fn unit(&self, i: usize) -> u32;
}

/// UTF-16 text; unpaired surrogates are characters of their own.
#[derive(Clone, Copy)]
pub(crate) struct Utf16<'a>(pub &'a [u16]);

impl Text for Utf16<'_> {
    #[inline(always)]
    fn units(&self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    fn next(&self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        let u = self.0[i] as u32;
        if u & 0xFC00 == 0xD800 {
            if let Some(&v) = self.0.get(i + 1) {
                if v & 0xFC00 == 0xDC00 {
                    return (0x10000 + ((u - 0xD800) << 10) + (v as u32 - 0xDC00), i + 2);
                }
            }
        }
        (u, i + 1)
    }

    #[inline(always)]
    fn prev(&self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        let v = self.0[i - 1] as u32;
        if v & 0xFC00 == 0xDC00 && i >= 2 {
            let u = self.0[i - 2] as u32;
            if u & 0xFC00 == 0xD800 {
                return (0x10000 + ((u - 0xD800) << 10) + (v - 0xDC00), i - 2);
            }
        }
        (v, i - 1)
    }

    #[inline(always)]
    fn unit(&self, i: usize) -> u32 {
        super::steps::step(1);
        self.0[i] as u32
    }
}

// The pattern syntax of the specification's Appendix B.
pub(crate) const STAR: u32 = '*' as u32;
pub(crate) const ANY: u32 = '?' as u32;
pub(crate) const DIGIT: u32 = '#' as u32;
pub(crate) const OPEN: u32 = '[' as u32;
pub(crate) const CLOSE: u32 = ']' as u32;
pub(crate) const BANG: u32 = '!' as u32;
pub(crate) const HYPHEN: u32 = '-' as u32;

/// For a UTF-8 lead byte: the sequence length and the range the second byte must lie in (Unicode
/// Table 3-7, well-formed UTF-8 byte sequences; later bytes are plain continuation bytes). `None` for
/// bytes that start no well-formed sequence (ASCII included: callers handle it first).
#[inline(always)]
pub(crate) fn utf8_sequence_bounds(b0: u8) -> Option<(usize, u8, u8)> {
    Some(match b0 {
        0xC2..=0xDF => (2, 0x80, 0xBF),
        0xE0 => (3, 0xA0, 0xBF),
        0xE1..=0xEC | 0xEE..=0xEF => (3, 0x80, 0xBF),
        0xED => (3, 0x80, 0x9F),
        0xF0 => (4, 0x90, 0xBF),
        0xF1..=0xF3 => (4, 0x80, 0xBF),
        0xF4 => (4, 0x80, 0x8F),
        _ => return None,
    })
}

/// UTF-8 text; every byte that is not part of a well-formed sequence (overlong forms, encoded
/// surrogates, values above U+10FFFF and truncated sequences included) is a character of its own.
#[derive(Clone, Copy)]
pub(crate) struct Utf8<'a>(pub &'a [u8]);

impl Utf8<'_> {
    /// The well-formed sequence starting at `i`: (code point, length); `None` if there is none.
    #[inline(always)]
    fn sequence(&self, i: usize) -> Option<(u32, usize)> {
        let s = self.0;
        let b0 = s[i];
        let (len, lo, hi) = utf8_sequence_bounds(b0)?;
        let tail = s.get(i + 1..i + len)?;
        if !(lo..=hi).contains(&tail[0]) || tail[1..].iter().any(|&b| b & 0xC0 != 0x80) {
            return None;
        }
        let mut c = (b0 as u32) & (0x7F >> len);
        for &b in tail {
            c = (c << 6) | (b as u32 & 0x3F);
        }
        Some((c, len))
    }
}

impl Text for Utf8<'_> {
    #[inline(always)]
    fn units(&self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    fn next(&self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        let b = self.0[i];
        if b < 0x80 {
            return (b as u32, i + 1);
        }
        match self.sequence(i) {
            Some((c, len)) => (c, i + len),
            None => (invalid_byte(b), i + 1),
        }
    }

    #[inline(always)]
    fn prev(&self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        let b = self.0[i - 1];
        if b < 0x80 {
            return (b as u32, i - 1);
        }
        // Well-formed sequences never overlap, so at most one of them ends at `i`; every other byte is
        // a character of its own, exactly as `next` splits the string.
        if b & 0xC0 == 0x80 {
            for len in 2..=4.min(i) {
                if let Some((c, l)) = self.sequence(i - len) {
                    if l == len {
                        return (c, i - len);
                    }
                }
            }
        }
        (invalid_byte(b), i - 1)
    }

    #[inline(always)]
    fn unit(&self, i: usize) -> u32 {
        super::steps::step(1);
        self.0[i] as u32
    }
}

/// Text already decoded into code points (one per character).
#[cfg_attr(not(windows), allow(dead_code))]
#[derive(Clone, Copy)]
pub(crate) struct Chars<'a>(pub &'a [u32]);

impl Text for Chars<'_> {
    #[inline(always)]
    fn units(&self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    fn next(&self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        (self.0[i], i + 1)
    }

    #[inline(always)]
    fn prev(&self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        (self.0[i - 1], i - 1)
    }

    #[inline(always)]
    fn unit(&self, i: usize) -> u32 {
        super::steps::step(1);
        self.0[i]
    }
}

/// Text in a single-byte code page: every byte is one character, `table[byte]` (see
/// `stream::TableCursor`); code units are the bytes.
#[cfg_attr(not(windows), allow(dead_code))]
#[derive(Clone, Copy)]
pub(crate) struct TableText<'a, 't>(pub &'a [u8], pub &'t [u32; 256]);

impl Text for TableText<'_, '_> {
    #[inline(always)]
    fn units(&self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    fn next(&self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        (self.1[self.0[i] as usize], i + 1)
    }

    #[inline(always)]
    fn prev(&self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        (self.1[self.0[i - 1] as usize], i - 1)
    }

    #[inline(always)]
    fn unit(&self, i: usize) -> u32 {
        super::steps::step(1);
        self.0[i] as u32
    }
}

/// All characters of `t`, front to back.
#[cfg(test)]
pub(crate) fn chars_of(t: &impl Text) -> Vec<u32> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < t.units() {
        let (c, n) = t.next(i);
        out.push(c);
        i = n;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn backwards(t: &impl Text) -> Vec<u32> {
        let mut out = Vec::new();
        let mut i = t.units();
        while i > 0 {
            let (c, p) = t.prev(i);
            out.push(c);
            i = p;
        }
        out.reverse();
        out
    }

    #[test]
    fn utf16_pairs_decode_and_lone_surrogates_stand_alone() {
        let s = [0x41, 0xD83D, 0xDE00, 0xDC00, 0xD800, 0xD800, 0xDC01, 0xD800];
        let t = Utf16(&s);
        assert_eq!(chars_of(&t), vec![0x41, 0x1F600, 0xDC00, 0xD800, 0x10001, 0xD800]);
        assert_eq!(backwards(&t), chars_of(&t));
    }

    #[test]
    fn utf8_invalid_bytes_are_single_characters() {
        let cases: &[(&[u8], &[u32])] = &[
            (b"a\xC3\xA9", &[0x61, 0xE9]),
            (b"\xE2\x82\xAC", &[0x20AC]),
            (b"\xF0\x9F\x98\x80", &[0x1F600]),
            (b"\xC3", &[0xDCC3]),
            (b"\xC0\x80", &[0xDCC0, 0xDC80]),                         // overlong NUL
            (b"\xED\xA0\x80", &[0xDCED, 0xDCA0, 0xDC80]),             // encoded surrogate
            (b"\xF4\x90\x80\x80", &[0xDCF4, 0xDC90, 0xDC80, 0xDC80]), // above U+10FFFF
            (b"\xE2\x82\xE2\x82\xAC", &[0xDCE2, 0xDC82, 0x20AC]),
            (b"\x80\xBF", &[0xDC80, 0xDCBF]),
            (b"\xF0\x9F\x98", &[0xDCF0, 0xDC9F, 0xDC98]),
        ];
        for (bytes, want) in cases {
            let t = Utf8(bytes);
            assert_eq!(chars_of(&t), *want, "{bytes:x?}");
            assert_eq!(backwards(&t), *want, "{bytes:x?} backwards");
        }
    }

    #[test]
    fn utf8_both_directions_agree_on_every_short_byte_string() {
        // Every string of up to 3 bytes drawn from bytes that exercise each decoding rule.
        let alphabet = [
            0x41, 0x80, 0x9F, 0xA0, 0xBF, 0xC2, 0xE0, 0xED, 0xF0, 0xF4, 0x90, 0x8F, 0xC0, 0xFF,
        ];
        let mut s = Vec::new();
        for len in 0..=4u32 {
            // Under Miri (safe code here; the pointer readers have their own tests) one string in 3
            // of two bytes, 1 in 97 of three and 1 in 1,999 of four.
            let stride = match len {
                _ if !cfg!(miri) => 1,
                0 | 1 => 1,
                2 => 3,
                3 => 97,
                _ => 1999,
            };
            for mut k in (0..alphabet.len().pow(len)).step_by(stride) {
                s.clear();
                for _ in 0..len {
                    s.push(alphabet[k % alphabet.len()]);
                    k /= alphabet.len();
                }
                let t = Utf8(&s);
                let fwd = chars_of(&t);
                assert_eq!(backwards(&t), fwd, "{s:x?}");
                let valid = core::str::from_utf8(&s).map(|x| x.chars().map(|c| c as u32).collect::<Vec<_>>());
                if let Ok(v) = valid {
                    assert_eq!(fwd, v);
                }
            }
        }
    }
}
