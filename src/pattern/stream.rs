//! The one-call matcher behind `MatchPatternW` and `MatchPatternA`: the same rules as the compiled
//! [`Program`](super::program::Program), but reading the pattern in place, so a call does no setup,
//! allocates nothing, and stops at the first character that rules a match out. (Patterns longer than
//! [`LONG_PATTERN`] units with a `*` are handed back to be compiled: see [`matches`].)
//!
//! It is the classic two-cursor scheme: tokens (each consumes exactly one character) are matched left
//! to right; on a mismatch the pattern restarts just after the last `*`, one character further into the
//! string (skipping straight to the next place the literal after that `*` occurs). Because every token
//! is one character, this is exact, and it costs at most O(len(string) x len(pattern)) token steps
//! without recursion. When the last `*` is reached, the tokens after it can only match the last
//! characters of the string, so they are tried there and nowhere else. A malformed pattern (an unclosed
//! `[`, a reversed range) never matches: the first `*` triggers one pass over the rest of the pattern
//! that finds the last `*` and checks every list, a match needs every token before it to have been
//! read, and reading a malformed list ends the call with FALSE.
//!
//! Strings are read through NUL-terminated pointers and never past the NUL: a lookahead only happens
//! after a unit that cannot be the terminator.

use super::fold::{fold, for_each_folded_range};
use super::text::{invalid_byte, utf8_sequence_bounds, Text, Utf16, Utf8, ANY, BANG, CLOSE, DIGIT, HYPHEN, OPEN, STAR};

/// A NUL-terminated string read character by character.
pub(crate) trait Cursor: Copy {
    /// The character starting at unit `i` and the index after it; 0 at the terminating NUL.
    ///
    /// # Safety
    /// `i` must be a character boundary reached from 0 by earlier calls, not beyond the terminator.
    unsafe fn at(self, i: usize) -> (u32, usize);

    /// The raw code unit at `i` (no decoding).
    ///
    /// # Safety
    /// `i` must be at or before the terminator.
    unsafe fn unit(self, i: usize) -> u32;

    /// The string as a slice, for walking back from its end.
    type Slice<'a>: Text;

    /// The first `len` units as a slice, where `len` is the index of the terminator.
    ///
    /// # Safety
    /// `len` must be the index of the terminating NUL.
    unsafe fn slice<'a>(self, len: usize) -> Self::Slice<'a>;

    /// The index of the terminating NUL, searching from the character boundary `i`.
    ///
    /// # Safety
    /// `i` must be at or before the terminator.
    unsafe fn end_from(self, i: usize) -> usize;
}

/// A NUL-terminated UTF-16 string; unpaired surrogates are characters of their own.
#[derive(Clone, Copy)]
pub(crate) struct WideCursor(pub *const u16);

impl Cursor for WideCursor {
    #[inline(always)]
    unsafe fn at(self, i: usize) -> (u32, usize) {
        // SAFETY: `i` is at or before the terminator (the caller's contract).
        let u = unsafe { *self.0.add(i) } as u32;
        if u & 0xFC00 == 0xD800 {
            // SAFETY: unit `i` is not the NUL, so unit `i + 1` is at or before the terminator.
            let v = unsafe { *self.0.add(i + 1) } as u32;
            if v & 0xFC00 == 0xDC00 {
                return (0x10000 + ((u - 0xD800) << 10) + (v - 0xDC00), i + 2);
            }
        }
        (u, i + 1)
    }

    #[inline(always)]
    unsafe fn unit(self, i: usize) -> u32 {
        // SAFETY: at or before the terminator (the caller's contract).
        unsafe { *self.0.add(i) as u32 }
    }

    type Slice<'a> = Utf16<'a>;

    #[inline(always)]
    unsafe fn slice<'a>(self, len: usize) -> Utf16<'a> {
        // SAFETY: the `len` units before the terminator are readable (the caller's contract).
        Utf16(unsafe { core::slice::from_raw_parts(self.0, len) })
    }

    #[inline(always)]
    unsafe fn end_from(self, mut i: usize) -> usize {
        // SAFETY: every unit up to the terminator is readable.
        while unsafe { *self.0.add(i) } != 0 {
            i += 1;
        }
        i
    }
}

/// A NUL-terminated UTF-8 string; bytes outside well-formed sequences are characters of their own.
#[cfg_attr(windows, allow(dead_code))]
#[derive(Clone, Copy)]
pub(crate) struct Utf8Cursor(pub *const u8);

impl Cursor for Utf8Cursor {
    #[inline(always)]
    unsafe fn at(self, i: usize) -> (u32, usize) {
        // SAFETY: `i` is at or before the terminator (the caller's contract).
        let b0 = unsafe { *self.0.add(i) };
        if b0 < 0x80 {
            return (b0 as u32, i + 1);
        }
        let Some((len, lo, hi)) = utf8_sequence_bounds(b0) else {
            return (invalid_byte(b0), i + 1);
        };
        let mut c = (b0 as u32) & (0x7F >> len);
        for k in 1..len {
            // SAFETY: bytes `i..i + k` were not NUL (b0 >= 0x80, later ones continuation bytes), so byte
            // `i + k` is at or before the terminator.
            let b = unsafe { *self.0.add(i + k) };
            let ok = if k == 1 {
                (lo..=hi).contains(&b)
            } else {
                b & 0xC0 == 0x80
            };
            if !ok {
                return (invalid_byte(b0), i + 1);
            }
            c = (c << 6) | (b as u32 & 0x3F);
        }
        (c, i + len)
    }

    #[inline(always)]
    unsafe fn unit(self, i: usize) -> u32 {
        // SAFETY: at or before the terminator (the caller's contract).
        unsafe { *self.0.add(i) as u32 }
    }

    type Slice<'a> = Utf8<'a>;

    #[inline(always)]
    unsafe fn slice<'a>(self, len: usize) -> Utf8<'a> {
        // SAFETY: the `len` bytes before the terminator are readable (the caller's contract).
        Utf8(unsafe { core::slice::from_raw_parts(self.0, len) })
    }

    #[inline(always)]
    unsafe fn end_from(self, i: usize) -> usize {
        // SAFETY: NUL-terminated from `i` on (the caller's contract).
        i + unsafe { core::ffi::CStr::from_ptr(self.0.add(i).cast()) }.count_bytes()
    }
}

/// Code points already decoded, ending with a 0.
#[cfg_attr(not(windows), allow(dead_code))]
#[derive(Clone, Copy)]
pub(crate) struct DecodedCursor(pub *const u32);

impl Cursor for DecodedCursor {
    #[inline(always)]
    unsafe fn at(self, i: usize) -> (u32, usize) {
        // SAFETY: `i` is at or before the terminating 0 (the caller's contract).
        (unsafe { *self.0.add(i) }, i + 1)
    }

    #[inline(always)]
    unsafe fn unit(self, i: usize) -> u32 {
        // SAFETY: at or before the terminator (the caller's contract).
        unsafe { *self.0.add(i) }
    }

    type Slice<'a> = super::text::Chars<'a>;

    #[inline(always)]
    unsafe fn slice<'a>(self, len: usize) -> Self::Slice<'a> {
        // SAFETY: the `len` values before the terminator are readable (the caller's contract).
        super::text::Chars(unsafe { core::slice::from_raw_parts(self.0, len) })
    }

    #[inline(always)]
    unsafe fn end_from(self, mut i: usize) -> usize {
        // SAFETY: every value up to the terminating 0 is readable.
        while unsafe { *self.0.add(i) } != 0 {
            i += 1;
        }
        i
    }
}

/// Whether some code point of `lo..=hi` compares equal to a character whose folding is `f`.
#[inline]
fn range_has_folding(lo: u32, hi: u32, f: u32) -> bool {
    if lo <= f && f <= hi {
        return true;
    }
    if hi < 0x80 {
        // Within ASCII only the capitals fold to something else.
        return f.wrapping_sub('a' as u32) < 26 && lo <= f - 32 && f - 32 <= hi;
    }
    let mut found = false;
    for_each_folded_range(lo, hi, |a, b| found |= a <= f && f <= b);
    found
}

/// What the `[...]` starting after the `[` at `i` does with character `c`.
enum List {
    /// `[]`: matches the empty string; the pattern continues at the index.
    Empty(usize),
    /// Whether `c` is accepted, and the index after the `]`.
    Match(bool, usize),
    /// No `]`, or a reversed range.
    Malformed,
}

/// Reads the list after a `[` (the whole list, so a malformed one is always noticed) and tests `c`.
///
/// # Safety
/// `i` must be the index right after a `[` of `p`.
#[inline]
unsafe fn list(p: impl Cursor, i: usize, c: u32, case_sensitive: bool) -> List {
    let f = if case_sensitive { c } else { fold(c) };
    let contains =
        |lo: u32, hi: u32| (lo <= c && c <= hi) || (!case_sensitive && c >= 0x41 && range_has_folding(lo, hi, f));
    // SAFETY: an index from an earlier character; walks stop at the terminator.
    let (c1, mut j) = unsafe { p.at(i) };
    match c1 {
        0 => return List::Malformed,
        CLOSE => return List::Empty(j),
        _ => {}
    }
    let mut negated = false;
    if c1 == BANG {
        // SAFETY: an index from an earlier character; walks stop at the terminator.
        let (c2, after) = unsafe { p.at(j) };
        match c2 {
            0 => return List::Malformed,
            CLOSE => return List::Match(c == BANG, after), // `[!]` is a literal `!`
            _ => {}
        }
        negated = true;
    } else {
        j = i;
    }
    let mut found = false;
    let mut first = true;
    let mut after_range = false;
    loop {
        // SAFETY: an index from an earlier character; walks stop at the terminator.
        let (lo, next) = unsafe { p.at(j) };
        j = next;
        match lo {
            0 => return List::Malformed,
            CLOSE => break,
            _ => {}
        }
        if lo == HYPHEN && (first || after_range) {
            found = found || c == HYPHEN;
            first = false;
            after_range = false;
            continue;
        }
        first = false;
        after_range = false;
        // SAFETY: an index from an earlier character; walks stop at the terminator.
        let (h, after_h) = unsafe { p.at(j) };
        if h == HYPHEN {
            // SAFETY: an index from an earlier character; walks stop at the terminator.
            let (hi, after_hi) = unsafe { p.at(after_h) };
            if hi == 0 {
                return List::Malformed;
            }
            if hi != CLOSE {
                if hi < lo {
                    return List::Malformed;
                }
                found = found || contains(lo, hi);
                j = after_hi;
                after_range = true;
                continue;
            }
        }
        found = found || contains(lo, lo);
    }
    List::Match(found != negated, j)
}

/// Patterns longer than this (in code units) that contain a `*` are compiled instead: on long
/// patterns the compiled form's precomputed lists pay for the compilation (see `matches`).
pub(crate) const LONG_PATTERN: usize = 128;

/// Where the last `*` of a pattern is, how many characters the tokens after it consume, and where the
/// pattern ends; `None` when the pattern (from `i` on) is malformed.
///
/// # Safety
/// `i` must be a character boundary of `pattern`.
unsafe fn last_star(pattern: impl Cursor, mut i: usize) -> Option<(usize, usize, usize)> {
    let mut last = (usize::MAX, 0);
    loop {
        // SAFETY: units before `i` were not NUL, so unit `i` is at or before the terminator.
        let u = unsafe { pattern.unit(i) };
        if (u < 0x80 && PLAIN_ASCII & (1 << u) != 0) || u == ANY || u == DIGIT {
            last.1 += 1; // a one-unit token
            i += 1;
            continue;
        }
        // SAFETY: an index from an earlier character; walks stop at the terminator.
        let (c, next) = unsafe { pattern.at(i) };
        match c {
            0 => return Some((last.0, last.1, i)),
            _ => i = next,
        }
        match c {
            STAR => last = (next, 0),
            // SAFETY: an index from an earlier character; walks stop at the terminator.
            OPEN => match unsafe { list(pattern, next, 0, true) } {
                List::Empty(after) => i = after,
                List::Match(_, after) => {
                    i = after;
                    last.1 += 1;
                }
                List::Malformed => return None,
            },
            _ => last.1 += 1,
        }
    }
}

/// The character a `*` at `star_end` is followed by, when it is a plain literal (folded when
/// case-insensitive): the string can skip straight to the next place that character occurs.
///
/// # Safety
/// `star_end` must be the index right after a `*` of `pattern`.
#[inline(always)]
unsafe fn literal_after(pattern: impl Cursor, star_end: usize, case_sensitive: bool) -> Option<u32> {
    // SAFETY: the index after a `*` is a character boundary at or before the terminator.
    match unsafe { pattern.at(star_end) }.0 {
        0 | STAR | ANY | DIGIT | OPEN => None,
        c if case_sensitive => Some(c),
        c => Some(fold(c)),
    }
}

/// The first position at or after `i` where `lit` (if any) can match; `None` at the end of the string.
///
/// # Safety
/// `i` must be a character boundary of `string`.
#[inline(always)]
unsafe fn skip_to(string: impl Cursor, mut i: usize, lit: Option<u32>, case_sensitive: bool) -> Option<usize> {
    let Some(lit) = lit else {
        return Some(i);
    };
    // An ASCII literal is found a code unit at a time: an ASCII unit always starts a character, and
    // no other character equals it, or folds to it unless it is `k` or `s` (KELVIN SIGN, LONG S).
    if lit < 0x80 && (case_sensitive || (lit != 'k' as u32 && lit != 's' as u32)) {
        loop {
            // SAFETY: units before `i` were not NUL, so unit `i` is at or before the terminator.
            let u = unsafe { string.unit(i) };
            if u == lit || (!case_sensitive && u.wrapping_sub('A' as u32) < 26 && u + 32 == lit) {
                return Some(i);
            }
            if u == 0 {
                return None;
            }
            i += 1;
        }
    }
    loop {
        // SAFETY: `i` is a boundary; the walk stops at the terminator.
        let (c, next) = unsafe { string.at(i) };
        if c == 0 {
            return None;
        }
        if c == lit || (!case_sensitive && fold(c) == lit) {
            return Some(i);
        }
        i = next;
    }
}

/// Whether the NUL-terminated `string` matches the NUL-terminated `pattern`; `None` when the pattern
/// is longer than [`LONG_PATTERN`] and has a `*`: the caller then compiles it, because matching a long
/// pattern can take up to len(string) x len(pattern) steps, and a compiled step is cheaper (lists are
/// precomputed bitmaps instead of being read again at every step).
///
/// # Safety
/// Both cursors must point at NUL-terminated strings.
pub(crate) unsafe fn matches(string: impl Cursor, pattern: impl Cursor, case_sensitive: bool) -> Option<bool> {
    let (mut pi, mut si) = (0usize, 0usize);
    // After the last `*` the rest of the pattern is anchored at the end of the string; found (and the
    // whole pattern checked) when the first `*` is reached.
    let mut last_star_at: Option<(usize, usize)> = None;
    // Where the pattern resumes after the current `*`, where the string resumes on the next retry, and
    // the literal that must come next.
    let mut star: Option<(usize, usize, Option<u32>)> = None;
    loop {
        // Fast path: an ASCII literal, `?` or `#` of the pattern against an ASCII unit of the string
        // (every ASCII unit is a whole character); anything else takes the general path below.
        // SAFETY: units before `pi` and `si` were not NUL, so both are at or before their terminators.
        let (p, u) = unsafe { (pattern.unit(pi), string.unit(si)) };
        if p < 0x80 && u < 0x80 && (PLAIN_ASCII & (1 << p) != 0 || p == ANY || p == DIGIT) {
            let hit = match p {
                ANY => u != 0,
                DIGIT => u.wrapping_sub('0' as u32) < 10,
                _ => u == p || (!case_sensitive && ascii_fold(u) == ascii_fold(p)),
            };
            if hit {
                pi += 1;
                si += 1;
                continue;
            }
            // SAFETY: `star` only holds indices from earlier characters.
            if let Some(next) = unsafe { retry(string, &mut star, case_sensitive) } {
                (pi, si) = next;
                continue;
            }
            return Some(false);
        }
        // SAFETY: an index from an earlier character; walks stop at the terminator.
        let (pc, pn) = unsafe { pattern.at(pi) };
        match pc {
            STAR => {
                // SAFETY: `pn` follows a character that was not the terminator.
                if last_star_at.is_none() && unsafe { pattern.unit(pn) } == 0 {
                    return Some(true); // a final `*`, and the only one: everything before it matched
                }
                let (last, tail) = match last_star_at {
                    Some(l) => l,
                    // SAFETY: an index from an earlier character; walks stop at the terminator.
                    None => match unsafe { last_star(pattern, pi) } {
                        Some((_, _, end)) if end > LONG_PATTERN => return None,
                        Some((last, tail, _)) => {
                            last_star_at = Some((last, tail));
                            (last, tail)
                        }
                        None => return Some(false),
                    },
                };
                if pn == last {
                    // The tail must match the last `tail` characters.
                    if tail == 0 {
                        return Some(true);
                    }
                    // SAFETY: an index from an earlier character; walks stop at the terminator.
                    let end = unsafe { string.end_from(si) };
                    // SAFETY: `end` is the index of the terminator.
                    let text = unsafe { string.slice(end) };
                    let mut q = end;
                    for _ in 0..tail {
                        if q <= si {
                            return Some(false);
                        }
                        q = text.prev(q).1;
                    }
                    star = None;
                    pi = pn;
                    si = q;
                    continue;
                }
                // SAFETY: an index from an earlier character; walks stop at the terminator.
                let lit = unsafe { literal_after(pattern, pn, case_sensitive) };
                // SAFETY: an index from an earlier character; walks stop at the terminator.
                let Some(from) = (unsafe { skip_to(string, si, lit, case_sensitive) }) else {
                    return Some(false);
                };
                star = Some((pn, from, lit));
                pi = pn;
                si = from;
                continue;
            }
            0 => {
                // SAFETY: an index from an earlier character; walks stop at the terminator.
                if unsafe { string.at(si) }.0 == 0 {
                    return Some(true);
                }
            }
            _ => {
                // SAFETY: an index from an earlier character; walks stop at the terminator.
                let (sc, sn) = unsafe { string.at(si) };
                let hit = match pc {
                    ANY => sc != 0,
                    DIGIT => sc.wrapping_sub('0' as u32) < 10,
                    // SAFETY: an index from an earlier character; walks stop at the terminator.
                    OPEN => match unsafe { list(pattern, pn, sc, case_sensitive) } {
                        List::Empty(next) => {
                            pi = next;
                            continue;
                        }
                        List::Match(hit, next) => {
                            if hit && sc != 0 {
                                pi = next;
                                si = sn;
                                continue;
                            }
                            false
                        }
                        List::Malformed => return Some(false),
                    },
                    _ => sc == pc || (!case_sensitive && sc != 0 && fold(sc) == fold(pc)),
                };
                if hit {
                    pi = pn;
                    si = sn;
                    continue;
                }
            }
        }
        // SAFETY: `star` only holds indices from earlier characters.
        match unsafe { retry(string, &mut star, case_sensitive) } {
            Some(next) => (pi, si) = next,
            None => return Some(false),
        }
    }
}

/// After a mismatch: the pattern and string positions to retry from, just after the last `*` and at
/// the next place in the string its literal occurs; `None` when there is no `*` or no place left.
///
/// # Safety
/// `star` must hold indices of `string` reached by earlier characters.
#[inline(always)]
unsafe fn retry(
    string: impl Cursor,
    star: &mut Option<(usize, usize, Option<u32>)>,
    case_sensitive: bool,
) -> Option<(usize, usize)> {
    let (resume, from, lit) = (*star)?;
    // SAFETY: `from` is a character boundary at or before the terminator.
    let (c, next) = unsafe { string.at(from) };
    if c == 0 {
        return None;
    }
    // SAFETY: `next` follows a character that was not the terminator.
    let next = unsafe { skip_to(string, next, lit, case_sensitive) }?;
    *star = Some((resume, next, lit));
    Some((resume, next))
}

/// ASCII characters that stand for themselves in a pattern: all but NUL, `*`, `?`, `#` and `[`.
const PLAIN_ASCII: u128 = !(1 | 1 << STAR | 1 << ANY | 1 << DIGIT | 1 << OPEN);

#[inline(always)]
fn ascii_fold(c: u32) -> u32 {
    if c.wrapping_sub('A' as u32) < 26 {
        c + 32
    } else {
        c
    }
}
