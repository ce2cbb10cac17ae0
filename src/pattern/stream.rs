//! The one-call matcher behind `MatchPatternW` and `MatchPatternA`: the same rules as the compiled
//! [`Program`](super::program::Program), but reading the pattern in place, so a call does no setup,
//! allocates nothing, and stops at the first character that rules a match out. (Patterns longer than
//! [`LONG_PATTERN`] units with a `*` are handed back to be compiled: see [`matches`].)
//!
//! The pattern is a sequence of segments separated by `*`; every token of a segment consumes exactly
//! one character (`[]` none). The first segment is anchored at the start of the string and read side by
//! side with it, so a literal prefix costs what it costs the specification's sample: one comparison per
//! character up to the first difference. Each later segment is searched for at its leftmost place after
//! the previous one (taking the leftmost place never hurts the segments after it, because each has a
//! fixed length), and the last one must end at the end of the string. That is exact, uses no recursion
//! and costs at most O(len(string) x len(pattern)) token steps. A malformed pattern (an unclosed `[`, a
//! reversed range) never matches: a match is only reported once every token of the pattern has been
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

    /// The first index in `from..end` whose code unit is `a` or `b` (ASCII; equal when only one is
    /// wanted), where `end` is the index of the terminator.
    ///
    /// # Safety
    /// `from <= end`, and `end` must be the index of the terminating NUL.
    unsafe fn find_ascii(self, from: usize, end: usize, a: u32, b: u32) -> Option<usize>;
}

/// Word-at-a-time search: the index of the first lane of `words` equal to `a` or `b`, where a lane is
/// `LANE` bits of a little-endian u64 (8 for bytes, 16 for UTF-16 units). Exact: the lowest lane the
/// zero test flags is always a real zero (borrows only run towards higher lanes).
#[inline(always)]
fn find_in_words<const LANE: u32>(words: impl Iterator<Item = u64>, a: u32, b: u32) -> Option<usize> {
    let lo = u64::MAX / ((1u64 << LANE) - 1); // 0x0101.. or 0x0001_0001..
    let hi = lo << (LANE - 1);
    let (ra, rb) = (lo * a as u64, lo * b as u64);
    for (k, w) in words.enumerate() {
        let (x, y) = (w ^ ra, w ^ rb);
        let zero = (x.wrapping_sub(lo) & !x | y.wrapping_sub(lo) & !y) & hi;
        if zero != 0 {
            return Some(k * (64 / LANE as usize) + (zero.trailing_zeros() / LANE) as usize);
        }
    }
    None
}

/// A NUL-terminated UTF-16 string; unpaired surrogates are characters of their own.
#[derive(Clone, Copy)]
pub(crate) struct WideCursor(pub *const u16);

impl Cursor for WideCursor {
    #[inline(always)]
    unsafe fn at(self, i: usize) -> (u32, usize) {
        super::steps::step(1);
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
        super::steps::step(1);
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
            super::steps::step(1);
            i += 1;
        }
        i
    }

    #[inline(always)]
    unsafe fn find_ascii(self, from: usize, end: usize, a: u32, b: u32) -> Option<usize> {
        // SAFETY: units `from..end` lie before the terminator (the caller's contract).
        let units = unsafe { core::slice::from_raw_parts(self.0.add(from), end - from) };
        let chunks = units.chunks_exact(4);
        let tail = chunks.remainder();
        let words = chunks.map(|c| c[0] as u64 | (c[1] as u64) << 16 | (c[2] as u64) << 32 | (c[3] as u64) << 48);
        if let Some(k) = find_in_words::<16>(words, a, b) {
            return Some(from + k);
        }
        let done = units.len() - tail.len();
        tail.iter()
            .position(|&u| u as u32 == a || u as u32 == b)
            .map(|k| from + done + k)
    }
}

/// A NUL-terminated UTF-8 string; bytes outside well-formed sequences are characters of their own.
#[cfg_attr(windows, allow(dead_code))]
#[derive(Clone, Copy)]
pub(crate) struct Utf8Cursor(pub *const u8);

impl Cursor for Utf8Cursor {
    #[inline(always)]
    unsafe fn at(self, i: usize) -> (u32, usize) {
        super::steps::step(1);
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
        super::steps::step(1);
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
        let len = unsafe { core::ffi::CStr::from_ptr(self.0.add(i).cast()) }.count_bytes();
        super::steps::step(len);
        i + len
    }

    #[inline(always)]
    unsafe fn find_ascii(self, from: usize, end: usize, a: u32, b: u32) -> Option<usize> {
        // SAFETY: bytes `from..end` lie before the terminator (the caller's contract).
        let bytes = unsafe { core::slice::from_raw_parts(self.0.add(from), end - from) };
        let chunks = bytes.chunks_exact(8);
        let tail = chunks.remainder();
        let words = chunks.map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]));
        if let Some(k) = find_in_words::<8>(words, a, b) {
            return Some(from + k);
        }
        let done = bytes.len() - tail.len();
        tail.iter()
            .position(|&u| u as u32 == a || u as u32 == b)
            .map(|k| from + done + k)
    }
}

/// Code points already decoded, ending with a 0.
#[cfg_attr(not(windows), allow(dead_code))]
#[derive(Clone, Copy)]
pub(crate) struct DecodedCursor(pub *const u32);

impl Cursor for DecodedCursor {
    #[inline(always)]
    unsafe fn at(self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        // SAFETY: `i` is at or before the terminating 0 (the caller's contract).
        (unsafe { *self.0.add(i) }, i + 1)
    }

    #[inline(always)]
    unsafe fn unit(self, i: usize) -> u32 {
        super::steps::step(1);
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
            super::steps::step(1);
            i += 1;
        }
        i
    }

    #[inline(always)]
    unsafe fn find_ascii(self, from: usize, end: usize, a: u32, b: u32) -> Option<usize> {
        // SAFETY: values `from..end` lie before the terminator (the caller's contract).
        let chars = unsafe { core::slice::from_raw_parts(self.0.add(from), end - from) };
        chars.iter().position(|&c| c == a || c == b).map(|k| from + k)
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

/// Whether the NUL-terminated `string` matches the NUL-terminated `pattern`; `None` when the pattern
/// is longer than [`LONG_PATTERN`] and has a `*`: the caller then compiles it, because matching a long
/// pattern can take up to len(string) x len(pattern) steps, and a compiled step is cheaper (lists are
/// precomputed bitmaps instead of being read again at every step).
///
/// Up to the first `*` the pattern is anchored at the start of the string: both are read side by side,
/// ASCII a code unit at a time, and the first character that differs ends the call, with no setup
/// before it (as in the specification's sample). From there on the pattern is taken a segment (the
/// tokens up to the next `*`) at a time, each searched for at its leftmost place: by its first two
/// literals a code unit at a time when it starts with ASCII literals, then token by token. The last
/// segment must match at the end of the string: once a place matches it entirely, only the end is tried.
///
/// # Safety
/// Both cursors must point at NUL-terminated strings.
#[inline(always)]
pub(crate) unsafe fn matches(string: impl Cursor, pattern: impl Cursor, case_sensitive: bool) -> Option<bool> {
    // SAFETY: both start at their first character.
    let (pi, si) = match unsafe { match_here(string, pattern, 0, 0, case_sensitive) } {
        Step::Star(pi, si) => (pi, si),
        // SAFETY: `si` is at or before the terminator.
        Step::End(si, _) => return Some(unsafe { string.unit(si) } == 0),
        Step::Fail | Step::Malformed => return Some(false),
    };
    // SAFETY: `pi` is at a `*`, so `pi + 1` is at or before the terminator.
    if unsafe { pattern.unit(pi + 1) } == 0 {
        return Some(true); // a final `*`: everything before it matched, and nothing is left to check
    }
    // SAFETY: as above.
    if unsafe { pattern.end_from(pi) } > LONG_PATTERN {
        return None;
    }
    // SAFETY: `pi` is at a `*`; `si` is a character boundary.
    unsafe { match_segments(string, pattern, pi, si, case_sensitive) }
}

/// How far [`match_here`] got.
enum Step {
    /// Every token up to a `*` matched: the `*`'s index and the string's index after the tokens.
    Star(usize, usize),
    /// Every token up to the end of the pattern matched: the string's index after them and how many
    /// characters they consumed.
    End(usize, usize),
    /// A token did not match (or the string ended first).
    Fail,
    /// A malformed list: the pattern never matches.
    Malformed,
}

/// Matches the tokens of `pattern` from `pi` against `string` from `si`, up to the next `*` or the end
/// of the pattern. ASCII literals are compared a code unit at a time.
///
/// # Safety
/// `pi` and `si` must be character boundaries of the NUL-terminated `pattern` and `string`.
#[inline(always)]
unsafe fn match_here(
    string: impl Cursor,
    pattern: impl Cursor,
    mut pi: usize,
    mut si: usize,
    case_sensitive: bool,
) -> Step {
    let mut count = 0;
    loop {
        // SAFETY: units before `pi` and `si` were not NUL, so both are at or before their terminators.
        let (p, u) = unsafe { (pattern.unit(pi), string.unit(si)) };
        if p < 0x80 && PLAIN_ASCII[p as usize] {
            if u == p || (!case_sensitive && u != 0 && ascii_fold(u) == ascii_fold(p)) {
                pi += 1;
                si += 1;
                count += 1;
                continue;
            }
            // A non-ASCII character may still fold to an ASCII letter (KELVIN SIGN is a `k`, LONG S
            // an `s`); otherwise the characters differ.
            if !case_sensitive && u >= 0x80 && matches!(ascii_fold(p), 0x6B | 0x73) {
                // SAFETY: unit `si` is not the NUL.
                let (sc, sn) = unsafe { string.at(si) };
                if fold(sc) == ascii_fold(p) {
                    pi += 1;
                    si = sn;
                    count += 1;
                    continue;
                }
            }
            return Step::Fail;
        }
        match p {
            0 => return Step::End(si, count),
            STAR => return Step::Star(pi, si),
            ANY => {
                if u == 0 {
                    return Step::Fail;
                }
                pi += 1;
                // SAFETY: unit `si` is not the NUL.
                si = if u < 0x80 { si + 1 } else { unsafe { string.at(si) }.1 };
            }
            DIGIT => {
                if u.wrapping_sub('0' as u32) >= 10 {
                    return Step::Fail;
                }
                pi += 1;
                si += 1;
            }
            OPEN => {
                // SAFETY: an index from an earlier character; walks stop at the terminator.
                let (sc, sn) = unsafe { string.at(si) };
                // SAFETY: `pi + 1` follows the `[`.
                match unsafe { list(pattern, pi + 1, sc, case_sensitive) } {
                    List::Empty(next) => {
                        pi = next;
                        continue; // `[]` consumes nothing
                    }
                    List::Match(true, next) if sc != 0 => {
                        pi = next;
                        si = sn;
                    }
                    List::Malformed => return Step::Malformed,
                    List::Match(..) => return Step::Fail,
                }
            }
            _ => {
                // A non-ASCII pattern character.
                // SAFETY: indices from earlier characters; walks stop at the terminators.
                let ((pc, pn), (sc, sn)) = unsafe { (pattern.at(pi), string.at(si)) };
                if sc == 0 || !(sc == pc || (!case_sensitive && fold(sc) == fold(pc))) {
                    return Step::Fail;
                }
                pi = pn;
                si = sn;
            }
        }
        count += 1;
    }
}

/// The segments after the `*` at `pi`, against the string from `si`.
///
/// # Safety
/// `pi` must be the index of a `*` of the NUL-terminated `pattern`; `si` a character boundary of the
/// NUL-terminated `string`.
#[inline(never)]
unsafe fn match_segments(
    string: impl Cursor,
    pattern: impl Cursor,
    mut pi: usize,
    mut si: usize,
    case_sensitive: bool,
) -> Option<bool> {
    // The string's end, found once: the searches below go a word at a time up to it.
    // SAFETY: `si` is a character boundary at or before the terminator.
    let end = unsafe { string.end_from(si) };
    loop {
        // Skip the `*` and any `*` or `[]` right after it.
        loop {
            // SAFETY: `pi` is at or before the terminator (it only moves past non-NUL units).
            match unsafe { pattern.unit(pi) } {
                STAR => pi += 1,
                // SAFETY: as above; `[` is not the terminator.
                OPEN if unsafe { pattern.unit(pi + 1) } == CLOSE => pi += 2,
                0 => return Some(true), // the pattern ends with `*`
                _ => break,
            }
        }
        // The segment's first two tokens when they are ASCII literals found a code unit at a time (an
        // ASCII unit always starts a character; only `k` and `s` have non-ASCII characters folding to
        // them).
        let literal = |u: u32| {
            (u < 0x80 && PLAIN_ASCII[u as usize] && (case_sensitive || !matches!(ascii_fold(u), 0x6B | 0x73)))
                .then(|| if case_sensitive { u } else { ascii_fold(u) })
        };
        // SAFETY: `pi` is at or before the terminator.
        let first = literal(unsafe { pattern.unit(pi) });
        // SAFETY: unit `pi` is a literal when `first` is set, so `pi + 1` is at or before the terminator.
        let second = first.and_then(|_| literal(unsafe { pattern.unit(pi + 1) }));
        let mut from = si;
        loop {
            if let Some(l) = first {
                let upper = if !case_sensitive && l.wrapping_sub('a' as u32) < 26 {
                    l - 32
                } else {
                    l
                };
                loop {
                    // SAFETY: `from` is at or before `end`, the terminator's index.
                    let found = unsafe { string.find_ascii(from, end, l, upper) };
                    // The units the search passed (read a word at a time) count as steps.
                    super::steps::step(found.map_or(end, |at| at + 1) - from);
                    match found {
                        Some(at) => from = at,
                        None => return Some(false),
                    }
                    // SAFETY: unit `from` is not the NUL, so `from + 1` is at or before the terminator.
                    let v = unsafe { string.unit(from + 1) };
                    match second {
                        Some(m) if !(v == m || (!case_sensitive && ascii_fold(v) == m)) => from += 1,
                        _ => break,
                    }
                }
            }
            // SAFETY: `pi` and `from` are character boundaries.
            match unsafe { match_here(string, pattern, pi, from, case_sensitive) } {
                Step::Star(next_pi, after) => {
                    (pi, si) = (next_pi, after);
                    break;
                }
                Step::End(after, count) => {
                    // SAFETY: `after` is at or before the terminator.
                    if unsafe { string.unit(after) } == 0 {
                        return Some(true);
                    }
                    // The last segment: only its place at the end of the string can match.
                    // SAFETY: `end` is the index of the terminator.
                    let text = unsafe { string.slice(end) };
                    let mut q = end;
                    for _ in 0..count {
                        q = text.prev(q).1;
                    }
                    // `q` is at or after `from`: the segment matched `count` characters there.
                    // SAFETY: `q` is a character boundary (walked back from the end).
                    return Some(matches!(
                        unsafe { match_here(string, pattern, pi, q, case_sensitive) },
                        Step::End(e, _) if e == end
                    ));
                }
                Step::Malformed => return Some(false),
                Step::Fail => {
                    // SAFETY: `from` is a boundary at or before the terminator.
                    let (c, next) = unsafe { string.at(from) };
                    if c == 0 {
                        return Some(false);
                    }
                    from = next;
                }
            }
        }
    }
}

/// ASCII characters that stand for themselves in a pattern: all but NUL, `*`, `?`, `#` and `[`.
const PLAIN_ASCII: [bool; 128] = {
    let mut t = [true; 128];
    t[0] = false;
    t[STAR as usize] = false;
    t[ANY as usize] = false;
    t[DIGIT as usize] = false;
    t[OPEN as usize] = false;
    t
};

#[inline(always)]
fn ascii_fold(c: u32) -> u32 {
    if c.wrapping_sub('A' as u32) < 26 {
        c + 32
    } else {
        c
    }
}
