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
//! fixed length); the last one must end at the end of the string, so it is only tried there. That is
//! exact, uses no recursion and costs at most O(len(string) x len(pattern)) token steps. A malformed
//! pattern (an unclosed `[`, a reversed range) never matches: a match is only reported once every
//! token of the pattern has been read, and reading a malformed list ends the call with FALSE.
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
/// `LANE` bits of a little-endian machine word (8 for bytes, 16 for UTF-16 units; a word is 64 bits on
/// 64-bit targets, 32 on 32-bit ones, so the search never emulates wider arithmetic). Exact: the
/// lowest lane the zero test flags is always a real zero (borrows only run towards higher lanes).
#[inline(always)]
fn find_in_words<const LANE: u32>(words: impl Iterator<Item = usize>, a: u32, b: u32) -> Option<usize> {
    let lo = usize::MAX / ((1usize << LANE) - 1); // 0x0101.. or 0x0001_0001..
    let hi = lo << (LANE - 1);
    let (ra, rb) = (lo * a as usize, lo * b as usize);
    for (k, w) in words.enumerate() {
        let (x, y) = (w ^ ra, w ^ rb);
        let zero = (x.wrapping_sub(lo) & !x | y.wrapping_sub(lo) & !y) & hi;
        if zero != 0 {
            return Some(k * (usize::BITS / LANE) as usize + (zero.trailing_zeros() / LANE) as usize);
        }
    }
    None
}

/// Bytes in a machine word.
const WORD: usize = core::mem::size_of::<usize>();

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
        let chunks = units.chunks_exact(WORD / 2);
        let tail = chunks.remainder();
        let words = chunks.map(|c| c.iter().rev().fold(0usize, |w, &u| w << 16 | u as usize));
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
        unsafe { byte_end_from(self.0, i) }
    }

    #[inline(always)]
    unsafe fn find_ascii(self, from: usize, end: usize, a: u32, b: u32) -> Option<usize> {
        // SAFETY: bytes `from..end` lie before the terminator (the caller's contract).
        unsafe { byte_find_ascii(self.0, from, end, a, b) }
    }
}

/// The index of the NUL of the byte string at `p`, searching from `i`.
///
/// # Safety
/// `p` must be NUL-terminated from `i` on.
#[inline(always)]
unsafe fn byte_end_from(p: *const u8, i: usize) -> usize {
    // SAFETY: NUL-terminated from `i` on (the caller's contract).
    let len = unsafe { core::ffi::CStr::from_ptr(p.add(i).cast()) }.count_bytes();
    super::steps::step(len);
    i + len
}

/// The first index in `from..end` of the byte string at `p` whose byte is `a` or `b`, a word at a time.
///
/// # Safety
/// Bytes `from..end` of `p` must be readable.
#[inline(always)]
unsafe fn byte_find_ascii(p: *const u8, from: usize, end: usize, a: u32, b: u32) -> Option<usize> {
    // SAFETY: bytes `from..end` are readable (the caller's contract).
    let bytes = unsafe { core::slice::from_raw_parts(p.add(from), end - from) };
    let chunks = bytes.chunks_exact(WORD);
    let tail = chunks.remainder();
    let words = chunks.map(|c| c.iter().rev().fold(0usize, |w, &b| w << 8 | b as usize));
    if let Some(k) = find_in_words::<8>(words, a, b) {
        return Some(from + k);
    }
    let done = bytes.len() - tail.len();
    tail.iter()
        .position(|&u| u as u32 == a || u as u32 == b)
        .map(|k| from + done + k)
}

/// A NUL-terminated string in a single-byte code page: every byte is one character, `table[byte]`.
/// The table must map every ASCII byte to itself and every other byte to a value of 0x80 or above,
/// so that code units compare with ASCII exactly as the characters do (the matcher reads ASCII a code
/// unit at a time and searches for ASCII literals a word at a time).
#[cfg_attr(not(windows), allow(dead_code))]
#[derive(Clone, Copy)]
pub(crate) struct TableCursor<'t>(pub *const u8, pub &'t [u32; 256]);

impl<'t> Cursor for TableCursor<'t> {
    #[inline(always)]
    unsafe fn at(self, i: usize) -> (u32, usize) {
        super::steps::step(1);
        // SAFETY: `i` is at or before the terminator (the caller's contract).
        let b = unsafe { *self.0.add(i) };
        (self.1[b as usize], i + 1)
    }

    #[inline(always)]
    unsafe fn unit(self, i: usize) -> u32 {
        super::steps::step(1);
        // SAFETY: at or before the terminator (the caller's contract).
        unsafe { *self.0.add(i) as u32 }
    }

    type Slice<'a> = super::text::TableText<'a, 't>;

    #[inline(always)]
    unsafe fn slice<'a>(self, len: usize) -> Self::Slice<'a> {
        // SAFETY: the `len` bytes before the terminator are readable (the caller's contract).
        super::text::TableText(unsafe { core::slice::from_raw_parts(self.0, len) }, self.1)
    }

    #[inline(always)]
    unsafe fn end_from(self, i: usize) -> usize {
        // SAFETY: NUL-terminated from `i` on (the caller's contract).
        unsafe { byte_end_from(self.0, i) }
    }

    #[inline(always)]
    unsafe fn find_ascii(self, from: usize, end: usize, a: u32, b: u32) -> Option<usize> {
        // SAFETY: bytes `from..end` lie before the terminator (the caller's contract).
        unsafe { byte_find_ascii(self.0, from, end, a, b) }
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
/// segment must match at the end of the string, so it is tried there only.
///
/// The pattern's leading ASCII literals, `?`, `#` and simple lists (`[a-z]`, `[x]`) against ASCII
/// characters are compared here, inlined into the caller, in a loop that needs nothing but the two
/// strings: a filter with a literal prefix rejects most strings in it, and one that ends with `*`
/// accepts them there. Everything from the first other pattern character (or non-ASCII string
/// character) on is out of line ([`matches_from`]).
///
/// # Safety
/// Both cursors must point at NUL-terminated strings.
#[inline(always)]
pub(crate) unsafe fn matches(string: impl Cursor, pattern: impl Cursor, case_sensitive: bool) -> Option<bool> {
    let (mut pi, mut si) = (0, 0);
    loop {
        // SAFETY: the units before `pi` and `si` were ASCII (not NUL) and matched, so unit `pi` of the
        // pattern and unit `si` of the string are at or before their terminators.
        let p = unsafe { pattern.unit(pi) };
        // SAFETY: as above.
        let u = unsafe { string.unit(si) };
        if PLAIN_OR_NOT[p.min(0x80) as usize] {
            if u != p && (case_sensitive || ascii_fold(u) != ascii_fold(p)) {
                // A non-ASCII character may still fold to an ASCII letter (KELVIN SIGN is a `k`, LONG S
                // an `s`): the general path decides. Otherwise the characters differ.
                if !case_sensitive && u >= 0x80 && matches!(ascii_fold(p), 0x6B | 0x73) {
                    break;
                }
                return Some(false);
            }
            pi += 1;
        } else {
            let ascii = u != 0 && u < 0x80;
            match p {
                ANY if ascii => pi += 1,
                DIGIT if ascii => {
                    if u.wrapping_sub('0' as u32) >= 10 {
                        return Some(false);
                    }
                    pi += 1;
                }
                // SAFETY: `pi + 1` follows the `[`.
                OPEN if ascii => match unsafe { simple_list(pattern, pi + 1, u, case_sensitive) } {
                    Some((true, next)) => pi = next,
                    Some((false, _)) => return Some(false),
                    None => break, // any other list: the general path reads it
                },
                // SAFETY: unit `pi` is not the NUL.
                STAR if unsafe { pattern.unit(pi + 1) } == 0 => {
                    return Some(true); // a final `*`: everything before it matched
                }
                _ => break, // the pattern's end, other syntax or characters, or a non-ASCII string character
            }
        }
        si += 1;
    }
    // SAFETY: `pi` and `si` are character boundaries (every unit before them was ASCII).
    unsafe { matches_from(string, pattern, pi, si, case_sensitive) }
}

/// A list of the form `[x]` or `[x-y]` (`x` and `y` ASCII, not `!`, `-` or `]`, `x <= y`) after the `[`
/// at `i - 1`, tested against the ASCII character `c`: whether it matches and the index after the `]`.
/// `None` for every other list, which `list` reads.
///
/// # Safety
/// `i` must be the index right after a `[` of `p`.
#[inline(always)]
unsafe fn simple_list(p: impl Cursor, i: usize, c: u32, case_sensitive: bool) -> Option<(bool, usize)> {
    let simple = |x: u32| x != 0 && x < 0x80 && x != BANG && x != HYPHEN && x != CLOSE;
    // SAFETY: unit `i - 1` is the `[`, not the NUL.
    let lo = unsafe { p.unit(i) };
    if !simple(lo) {
        return None;
    }
    // SAFETY: unit `i` is not the NUL.
    let (hi, close) = match unsafe { p.unit(i + 1) } {
        CLOSE => (lo, i + 1),
        HYPHEN => {
            // SAFETY: unit `i + 1` is not the NUL.
            let hi = unsafe { p.unit(i + 2) };
            // SAFETY: unit `i + 2` is not the NUL when it is simple.
            if !(simple(hi) && hi >= lo && unsafe { p.unit(i + 3) } == CLOSE) {
                return None;
            }
            (hi, i + 3)
        }
        _ => return None,
    };
    let found = (lo <= c && c <= hi) || (!case_sensitive && c >= 0x41 && range_has_folding(lo, hi, ascii_fold(c)));
    Some((found, close + 1))
}

/// [`matches`] from unit `pi` of the pattern and `si` of the string on, where everything before matched.
///
/// # Safety
/// Both cursors must point at NUL-terminated strings; `pi` and `si` must be character boundaries at or
/// before their terminators, with every character of both before them ASCII.
#[inline(never)]
unsafe fn matches_from(
    string: impl Cursor,
    pattern: impl Cursor,
    pi: usize,
    si: usize,
    case_sensitive: bool,
) -> Option<bool> {
    // SAFETY: `pi` and `si` are character boundaries (the caller's contract).
    let (pi, si) = match unsafe { match_here(string, pattern, pi, si, case_sensitive) } {
        Step::Star(pi, si) => (pi, si),
        // SAFETY: `si` is at or before the terminator.
        Step::End(si, _) => return Some(unsafe { string.unit(si) } == 0),
        Step::Fail | Step::Malformed => return Some(false),
    };
    // SAFETY: `pi` is at a `*`, so `pi + 1` is at or before the terminator.
    if unsafe { pattern.unit(pi + 1) } == 0 {
        return Some(true); // a final `*`: everything before it matched, and nothing is left to check
    }
    // The pattern's length, where its last `*` unit is (no segment after it has a `*`), and whether
    // the units after that are all ASCII outside lists: then each is one character.
    let mut tail = Tail {
        end: pi + 1,
        last_star: pi,
        plain: true,
    };
    loop {
        // SAFETY: `tail.end` only moves past units that are not the terminator.
        match unsafe { pattern.unit(tail.end) } {
            0 => break,
            STAR => (tail.last_star, tail.plain) = (tail.end, true),
            OPEN | 0x80.. => tail.plain = false,
            _ => {}
        }
        tail.end += 1;
    }
    if tail.end > LONG_PATTERN {
        return None;
    }
    // SAFETY: `pi` is at a `*`; `si` is a character boundary.
    unsafe { match_segments(string, pattern, pi, si, tail, case_sensitive) }
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

/// What [`matches_from`] learned of the pattern after its first `*`.
#[derive(Clone, Copy)]
struct Tail {
    /// The index of the terminator.
    end: usize,
    /// The index of the last `*` unit.
    last_star: usize,
    /// No unit after `last_star` is a `[` or not ASCII.
    plain: bool,
}

/// The segments after the `*` at `pi`, against the string from `si` (`tail`: see [`Tail`]).
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
    tail: Tail,
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
        // The last segment can only match the characters at the end of the string: no search. (A
        // segment after the last `*` unit is the last; one before it may still be, when that `*` is in
        // a list, and the search below then finds its place as for any other.)
        let last = if pi <= tail.last_star {
            Last::No
        } else if tail.plain {
            Last::Chars(tail.end - pi) // one character per unit, none of them a list
        } else {
            // SAFETY: `pi` is a character boundary of the pattern.
            unsafe { last_segment(pattern, pi) }
        };
        match last {
            Last::No => {}
            Last::Malformed => return Some(false),
            Last::Chars(count) => {
                // SAFETY: `end` is the index of the terminator.
                let text = unsafe { string.slice(end) };
                let mut q = end;
                for _ in 0..count {
                    if q <= si {
                        return Some(false); // fewer characters left than the segment consumes
                    }
                    q = text.prev(q).1;
                }
                // SAFETY: `q` is a character boundary at or after `si` (walked back from the end).
                return Some(matches!(
                    unsafe { match_here(string, pattern, pi, q, case_sensitive) },
                    Step::End(e, _) if e == end
                ));
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

/// Whether the segment at `pi` is the pattern's last, and then how many characters it consumes.
enum Last {
    /// A `*` follows it.
    No,
    /// It is the last and consumes this many characters (every token one, `[]` none).
    Chars(usize),
    /// It holds a malformed list: the pattern never matches.
    Malformed,
}

/// Reads the segment at `pi` up to the next `*` or the pattern's end (see [`Last`]).
///
/// # Safety
/// `pi` must be a character boundary of the NUL-terminated `pattern`.
#[inline]
unsafe fn last_segment(pattern: impl Cursor, mut pi: usize) -> Last {
    let mut count = 0;
    loop {
        // SAFETY: `pi` only moves past characters that are not the terminator.
        match unsafe { pattern.unit(pi) } {
            0 => return Last::Chars(count),
            STAR => return Last::No,
            // Where a list ends and whether it is malformed do not depend on the character tested.
            // SAFETY: `pi + 1` follows the `[`.
            OPEN => match unsafe { list(pattern, pi + 1, 0, true) } {
                List::Empty(next) => pi = next,
                List::Match(_, next) => {
                    pi = next;
                    count += 1;
                }
                List::Malformed => return Last::Malformed,
            },
            u if u < 0x80 => {
                pi += 1;
                count += 1;
            }
            _ => {
                // SAFETY: as above.
                pi = unsafe { pattern.at(pi) }.1;
                count += 1;
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

/// `PLAIN_ASCII` with one more entry, false, for everything from 0x80 on (index `unit.min(0x80)`).
const PLAIN_OR_NOT: [bool; 129] = {
    let mut t = [false; 129];
    let mut k = 0;
    while k < 128 {
        t[k] = PLAIN_ASCII[k];
        k += 1;
    }
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
