//! A pattern compiled into single-character tokens, and the matcher.
//!
//! Compiling turns the pattern into segments of tokens separated by `*`: every token (a literal, `?`,
//! `#` or a character list) consumes exactly one character, `[]` disappears and runs of `*` become one.
//! Matching then needs no backtracking beyond a search: the first segment must match at the start,
//! the last at the end, and each segment in between at its leftmost place after the previous one
//! (taking the leftmost place never hurts the segments that follow, because every segment has a fixed
//! length). That is O(len(string) x len(pattern)) at worst, linear for typical filters, and uses no
//! recursion. Two refinements keep inputs built to force the worst case cheap where that is easy:
//! a `?` right after a `*` is moved in front of it (`*?` matches what `?*` does), and a segment that
//! starts with a long literal run is searched with Knuth-Morris-Pratt.

use super::fold::{fold, for_each_folded_range};
use super::smallvec::SmallVec;
use super::stream::Cursor;
use super::text::{Text, ANY, BANG, CLOSE, DIGIT, HYPHEN, OPEN, STAR};

/// One pattern element that consumes exactly one character.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Token {
    /// The character itself (case-folded when matching case-insensitively).
    Literal(u32),
    /// `?`: any character.
    Any,
    /// `#`: an ASCII digit `0`-`9`.
    Digit,
    /// `[list]` / `[!list]`: index into `Program::sets`.
    Set(u32),
}

/// A character list. `ascii` answers for characters below U+0080 directly (negation applied);
/// other characters are looked up in `ranges[start..start + len]` (sorted, disjoint, merged).
#[derive(Clone, Copy, Debug)]
pub(crate) struct CharSet {
    ascii: [u64; 2],
    negated: bool,
    start: u32,
    len: u32,
}

/// Why a pattern cannot be compiled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Malformed {
    /// A `[` without its `]`.
    UnclosedList,
    /// A range whose end comes before its start, as in `[Z-A]`.
    ReversedRange,
}

/// A compiled pattern. The inline capacities fit ordinary filters without touching the heap; longer
/// patterns spill over transparently.
pub(crate) struct Program {
    case_sensitive: bool,
    /// The pattern's leading ASCII literals, `?`, `#` and lists as (unit, mask): a string unit `u`
    /// matches a literal when `u | mask == unit` (mask 0x20 for letters when case-insensitive);
    /// `LEAD_ANY`, `LEAD_DIGIT` and `LEAD_SET + k` stand for `?`, `#` and the list `k`. The common prefix of a filter is compared a code unit at a
    /// time, without decoding. At most `LEAD_MAX` (the tokens after them are matched one by one).
    /// `lead[lead_len]` is `(LEAD_END, 0)`, which no unit matches: the loop over `lead` needs no
    /// other end test.
    lead: [(u32, u32); LEAD_MAX + 1],
    lead_len: usize,
    /// The ASCII bitmaps of the lists `0..LEAD_SETS` (those that can be in `lead`, the pattern's first
    /// lists), at a fixed place: the inlined loop over `lead` tests an ASCII character against them
    /// with one load, where `sets` would need its inline-or-heap storage looked up.
    lead_sets: [[u64; 2]; LEAD_SETS],
    /// What the string must do after the characters `lead` matched.
    tail: Tail,
    /// No segment starts with a literal run long enough for the Knuth-Morris-Pratt search.
    kmp_free: bool,
    tokens: SmallVec<Token, 40>,
    /// End (exclusive token index) of each segment; segments are separated by one `*`.
    segments: SmallVec<u32, 8>,
    sets: SmallVec<CharSet, 4>,
    ranges: SmallVec<(u32, u32), 12>,
}

/// What is left of a pattern after its `lead` tokens.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Tail {
    /// Only a final `*` (or nothing but `*`s): every rest of the string matches.
    Any,
    /// Nothing: the string must end there.
    End,
    /// More tokens: `matches_after_lead` decides.
    General,
}

/// How many leading tokens `lead` holds at most.
const LEAD_MAX: usize = 32;

/// `lead` entries for `?`, `#` and lists (`LEAD_SET + k` for `Token::Set(k)`). No code unit or
/// character reaches these values, so `u | mask` never equals them.
const LEAD_ANY: u32 = u32::MAX;
const LEAD_DIGIT: u32 = u32::MAX - 1;
const LEAD_SET: u32 = 0x8000_0000;
const LEAD_END: u32 = u32::MAX - 2;

/// How many of a pattern's first lists have their ASCII bitmap in `Program::lead_sets`; a `lead`
/// list after them is tested out of line.
const LEAD_SETS: usize = 4;

/// Segments starting with at least this many literals are searched with Knuth-Morris-Pratt (shorter
/// runs cost at most this many steps per place tried, and skip to their first character quickly).
const KMP_MIN_RUN: usize = 16;

impl Program {
    /// Compiles `pattern`. Matching later is case-insensitive (Unicode simple case folding) unless
    /// `case_sensitive`.
    pub(crate) fn compile(pattern: &impl Text, case_sensitive: bool) -> Result<Program, Malformed> {
        let mut p = Program {
            case_sensitive,
            lead: [(LEAD_END, 0); LEAD_MAX + 1],
            lead_len: 0,
            lead_sets: [[0; 2]; LEAD_SETS],
            tail: Tail::General,
            kmp_free: true,
            tokens: SmallVec::new(),
            segments: SmallVec::new(),
            sets: SmallVec::new(),
            ranges: SmallVec::new(),
        };
        let n = pattern.units();
        let mut i = 0;
        while i < n {
            let (c, next) = pattern.next(i);
            i = next;
            match c {
                STAR => {
                    let len = p.tokens.len() as u32;
                    // A `*` right after another `*` (with at most `[]` between) adds nothing.
                    if p.segments.as_slice().last() != Some(&len) {
                        p.segments.push(len);
                    }
                }
                ANY => {
                    p.tokens.push(Token::Any);
                    // `*?` matches what `?*` does; moving the `?` in front of the `*` means the search
                    // after the `*` never has to try a run of `?`s at every place.
                    let len = p.tokens.len() as u32;
                    if let Some(end) = p.segments.as_mut_slice().last_mut() {
                        if *end == len - 1 {
                            *end = len;
                        }
                    }
                }
                DIGIT => p.tokens.push(Token::Digit),
                OPEN => i = p.list(pattern, i)?,
                _ => p.push_literal(c),
            }
        }
        let len = p.tokens.len() as u32;
        p.segments.push(len);
        let mut start = 0;
        for &end in p.segments.as_slice() {
            let seg = &p.tokens.as_slice()[start..end as usize];
            if seg.iter().take_while(|t| matches!(t, Token::Literal(_))).count() >= KMP_MIN_RUN {
                p.kmp_free = false;
            }
            start = end as usize;
        }
        for &t in &p.tokens.as_slice()[..p.segments.as_slice()[0] as usize] {
            if p.lead_len == LEAD_MAX {
                break;
            }
            p.lead[p.lead_len] = match t {
                Token::Any => (LEAD_ANY, 0),
                Token::Digit => (LEAD_DIGIT, 0),
                Token::Set(k) => (LEAD_SET + k, 0),
                Token::Literal(c) if c < 0x80 => {
                    let mask = if !case_sensitive && c.wrapping_sub('a' as u32) < 26 {
                        0x20
                    } else {
                        0
                    };
                    (c, mask)
                }
                _ => break,
            };
            p.lead_len += 1;
        }
        p.lead[p.lead_len] = (LEAD_END, 0);
        for (bits, set) in p.lead_sets.iter_mut().zip(p.sets.as_slice()) {
            *bits = set.ascii;
        }
        let segments = p.segments.as_slice();
        if segments[0] as usize == p.lead_len {
            if segments.len() == 1 {
                p.tail = Tail::End;
            } else if segments.len() == 2 && segments[1] == segments[0] {
                p.tail = Tail::Any;
            }
        }
        Ok(p)
    }

    fn push_literal(&mut self, c: u32) {
        self.tokens
            .push(Token::Literal(if self.case_sensitive { c } else { fold(c) }));
    }

    /// Parses the list after a `[` at `i`; returns the index after its `]`.
    fn list(&mut self, pattern: &impl Text, mut i: usize) -> Result<usize, Malformed> {
        let n = pattern.units();
        let next = |i: usize| {
            if i < n {
                Ok(pattern.next(i))
            } else {
                Err(Malformed::UnclosedList)
            }
        };
        let (c, after) = next(i)?;
        if c == CLOSE {
            return Ok(after); // `[]` is the empty string
        }
        let mut negated = false;
        if c == BANG {
            let (c2, after2) = next(after)?;
            if c2 == CLOSE {
                self.push_literal(BANG); // `[!]` is a literal `!`
                return Ok(after2);
            }
            negated = true;
            i = after;
        }
        let start = self.ranges.len();
        let mut first = true;
        let mut after_range = false;
        loop {
            let (lo, after) = next(i)?;
            i = after;
            if lo == CLOSE {
                break;
            }
            // A `-` first in the list or right after a range stands for itself.
            if lo == HYPHEN && (first || after_range) {
                self.ranges.push((HYPHEN, HYPHEN));
                first = false;
                after_range = false;
                continue;
            }
            first = false;
            after_range = false;
            let (h, after_h) = next(i)?;
            if h == HYPHEN {
                let (hi, after_hi) = next(after_h)?;
                if hi != CLOSE {
                    if hi < lo {
                        return Err(Malformed::ReversedRange);
                    }
                    self.ranges.push((lo, hi));
                    i = after_hi;
                    after_range = true;
                    continue;
                }
                // `-` before the `]` stands for itself: the next round reads it.
            }
            self.ranges.push((lo, lo));
        }
        self.finish_set(start, negated);
        Ok(i)
    }

    /// Turns `ranges[start..]` into a set: adds the case foldings when case-insensitive, sorts,
    /// merges, and builds the ASCII bitmap.
    fn finish_set(&mut self, start: usize, negated: bool) {
        if !self.case_sensitive {
            let end = self.ranges.len();
            for k in start..end {
                let (lo, hi) = self.ranges.as_slice()[k];
                let ranges = &mut self.ranges;
                for_each_folded_range(lo, hi, |a, b| ranges.push((a, b)));
            }
        }
        let list = &mut self.ranges.as_mut_slice()[start..];
        list.sort_unstable();
        let mut merged = 0;
        for k in 0..list.len() {
            let (lo, hi) = list[k];
            if merged > 0 && lo <= list[merged - 1].1.saturating_add(1) {
                list[merged - 1].1 = list[merged - 1].1.max(hi);
            } else {
                list[merged] = (lo, hi);
                merged += 1;
            }
        }
        self.ranges.truncate(start + merged);

        let mut ascii = [0u64; 2];
        for &(lo, hi) in &self.ranges.as_slice()[start..] {
            for c in lo..=hi.min(0x7F) {
                ascii[(c >> 6) as usize] |= 1 << (c & 63);
            }
        }
        if !self.case_sensitive {
            // An ASCII capital is in the list when its folding (the small letter) is.
            for c in b'A' as u32..=b'Z' as u32 {
                let f = c + 32;
                if ascii[(f >> 6) as usize] & (1 << (f & 63)) != 0 {
                    ascii[(c >> 6) as usize] |= 1 << (c & 63);
                }
            }
        }
        if negated {
            ascii = [!ascii[0], !ascii[1]];
        }
        let set = CharSet {
            ascii,
            negated,
            start: start as u32,
            len: merged as u32,
        };
        self.tokens.push(Token::Set(self.sets.len() as u32));
        self.sets.push(set);
    }

    #[inline(always)]
    fn set_contains(&self, set: &CharSet, c: u32) -> bool {
        if c < 0x80 {
            return set.ascii[(c >> 6) as usize] & (1 << (c & 63)) != 0;
        }
        let c = if self.case_sensitive { c } else { fold(c) };
        let ranges = &self.ranges.as_slice()[set.start as usize..(set.start + set.len) as usize];
        let found = if ranges.len() <= 4 {
            ranges.iter().any(|&(lo, hi)| lo <= c && c <= hi)
        } else {
            let k = ranges.partition_point(|r| r.1 < c);
            k < ranges.len() && ranges[k].0 <= c
        };
        found != set.negated
    }

    #[inline(always)]
    fn token_matches(&self, t: Token, c: u32) -> bool {
        match t {
            Token::Literal(l) => c == l || (!self.case_sensitive && fold(c) == l),
            Token::Any => true,
            Token::Digit => c.wrapping_sub('0' as u32) < 10,
            Token::Set(k) => self.set_contains(&self.sets.as_slice()[k as usize], c),
        }
    }

    /// Matches `seg` at unit `i`, using no characters at or after `end`; returns the index after it.
    #[inline(always)]
    fn match_at(&self, seg: &[Token], s: &impl Text, mut i: usize, end: usize) -> Option<usize> {
        for &t in seg {
            if i >= end {
                return None;
            }
            let (c, next) = s.next(i);
            if !self.token_matches(t, c) {
                return None;
            }
            i = next;
        }
        Some(i)
    }

    /// Whether the whole of `s` matches the pattern.
    pub(crate) fn matches(&self, s: &impl Text) -> bool {
        let first = &self.tokens.as_slice()[..self.segments.as_slice()[0] as usize];
        match self.match_at(first, s, 0, s.units()) {
            Some(from) => self.match_rest(s, from),
            None => false,
        }
    }

    /// Whether the NUL-terminated string behind `cursor` matches. The first segment is matched while
    /// reading, so most strings that do not match are rejected before their end is even looked for:
    /// the leading ASCII literals, `?`, `#` and lists here, inlined into the caller (a filter with a literal
    /// prefix rejects most strings in this loop), everything after them out of line.
    ///
    /// # Safety
    /// `cursor` must point at a NUL-terminated string.
    #[inline(always)]
    pub(crate) unsafe fn matches_cursor(&self, cursor: impl Cursor) -> bool {
        let mut i = 0;
        loop {
            // `i <= lead_len`: the loop ends at the `LEAD_END` entry at the latest (no code unit matches
            // it, and `lead_len <= LEAD_MAX`). Unchecked: a bounds test per character would be a third
            // of the loop.
            debug_assert!(i <= self.lead_len);
            // SAFETY: `i <= lead_len <= LEAD_MAX`, an index of `lead`, as above.
            let (unit, mask) = unsafe { *self.lead.get_unchecked(i) };
            // SAFETY: units before `i` were not NUL (they matched ASCII literals, `?`, `#` or lists),
            // so unit `i` is at or before the terminator.
            let u = unsafe { cursor.unit(i) };
            if u | mask != unit {
                let ascii = u != 0 && u < 0x80;
                let matched = match unit {
                    LEAD_END => break,
                    LEAD_ANY => ascii,
                    LEAD_DIGIT => u.wrapping_sub('0' as u32) < 10,
                    LEAD_SET.. => {
                        ascii
                            && match self.lead_sets.get((unit - LEAD_SET) as usize) {
                                Some(bits) => bits[(u >> 6) as usize & 1] & (1 << (u & 63)) != 0,
                                None => self.lead_set_contains(unit - LEAD_SET, u),
                            }
                    }
                    _ => false,
                };
                if !matched {
                    // A non-ASCII character for `?` or a list, or one that may fold to an ASCII letter
                    // (KELVIN SIGN is a `k`): the general path decides.
                    if u >= 0x80 && (unit >= LEAD_SET || !self.case_sensitive) {
                        // SAFETY: NUL-terminated.
                        return unsafe { self.matches_decoded(cursor) };
                    }
                    return false;
                }
            }
            i += 1;
        }
        match self.tail {
            Tail::Any => true,
            // SAFETY: `i` is at or before the terminator (units before it were not NUL).
            Tail::End => (unsafe { cursor.unit(i) }) == 0,
            // SAFETY: `i` is a character boundary (after ASCII units only) at or before the terminator.
            Tail::General => unsafe { self.matches_after_lead(cursor, i) },
        }
    }

    /// Whether list `k` contains `c`, out of line: finding the list would otherwise take registers
    /// (and their saving) from every call of the inlined `matches_cursor`.
    #[inline(never)]
    fn lead_set_contains(&self, k: u32, c: u32) -> bool {
        self.set_contains(&self.sets.as_slice()[k as usize], c)
    }

    /// `matches` over the whole string behind `cursor`.
    ///
    /// # Safety
    /// `cursor` must point at a NUL-terminated string.
    #[inline(never)]
    unsafe fn matches_decoded(&self, cursor: impl Cursor) -> bool {
        // SAFETY: NUL-terminated.
        let end = unsafe { cursor.end_from(0) };
        // SAFETY: `end` is the terminator's index.
        self.matches(&unsafe { cursor.slice(end) })
    }

    /// `matches_cursor` from unit `i`, where the leading tokens in `lead` have matched.
    ///
    /// # Safety
    /// `cursor` must point at a NUL-terminated string; `i` must be the character boundary after the
    /// characters the `lead` tokens matched.
    #[inline(never)]
    unsafe fn matches_after_lead(&self, cursor: impl Cursor, mut i: usize) -> bool {
        let tokens = self.tokens.as_slice();
        let segments = self.segments.as_slice();
        for &t in &tokens[self.lead_len..segments[0] as usize] {
            // SAFETY: `i` is a character boundary at or before the terminator; an ASCII unit is a whole
            // character.
            let (c, next) = match unsafe { cursor.unit(i) } {
                u @ 0..=0x7F => (u, i + 1),
                // SAFETY: as above.
                _ => unsafe { cursor.at(i) },
            };
            if c == 0 || !self.token_matches(t, c) {
                return false;
            }
            i = next;
        }
        if segments.len() == 1 {
            // SAFETY: as above.
            return unsafe { cursor.at(i) }.0 == 0;
        }
        let n = segments.len();
        if segments[n - 1] == segments[n - 2] && self.kmp_free {
            // The pattern ends with `*`: the end of the string does not matter, so the segments in
            // between are searched for without looking for it.
            for w in segments[..n - 1].windows(2) {
                let seg = &tokens[w[0] as usize..w[1] as usize];
                // SAFETY: `i` is a character boundary at or before the terminator.
                match unsafe { self.find_in_cursor(seg, cursor, i) } {
                    Some(end) => i = end,
                    None => return false,
                }
            }
            return true;
        }
        // SAFETY: as above; `end` is the terminator's index.
        let end = unsafe { cursor.end_from(i) };
        // SAFETY: `end` is the index of the terminator.
        self.match_rest(&unsafe { cursor.slice(end) }, i)
    }

    /// The end of the leftmost match of `seg` at or after `from` in a NUL-terminated string.
    ///
    /// # Safety
    /// `from` must be a character boundary of `cursor`'s string, at or before its terminator.
    unsafe fn find_in_cursor(&self, seg: &[Token], cursor: impl Cursor, mut from: usize) -> Option<usize> {
        let first = match seg.first() {
            Some(&Token::Literal(l)) => Some(l),
            _ => None,
        };
        loop {
            if let Some(l) = first {
                // Skip to the next place the first character occurs (see `stream::skip_to`).
                if l < 0x80 && (self.case_sensitive || (l != 'k' as u32 && l != 's' as u32)) {
                    loop {
                        // SAFETY: units before `from` were not NUL, so it is at or before the terminator.
                        let u = unsafe { cursor.unit(from) };
                        if u == l || u == 0 || (!self.case_sensitive && u.wrapping_sub('A' as u32) < 26 && u + 32 == l)
                        {
                            break;
                        }
                        from += 1;
                    }
                }
                loop {
                    // SAFETY: `from` is a boundary at or before the terminator.
                    let (c, next) = unsafe { cursor.at(from) };
                    if c == 0 {
                        return None;
                    }
                    if c == l || (!self.case_sensitive && fold(c) == l) {
                        break;
                    }
                    from = next;
                }
            }
            let mut i = from;
            let mut matched = true;
            for &t in seg {
                // SAFETY: `i` is a boundary at or before the terminator (it only moves past non-NULs);
                // an ASCII unit is a whole character.
                let (c, next) = match unsafe { cursor.unit(i) } {
                    u @ 0..=0x7F => (u, i + 1),
                    // SAFETY: as above.
                    _ => unsafe { cursor.at(i) },
                };
                if c == 0 {
                    return None; // not enough characters left here, nor anywhere further on
                }
                if !self.token_matches(t, c) {
                    matched = false;
                    break;
                }
                i = next;
            }
            if matched {
                return Some(i);
            }
            // SAFETY: `from` is a boundary before the terminator (a character matched or was tried there).
            from = unsafe { cursor.at(from) }.1;
        }
    }

    /// Whether the rest of `s`, from `from` (just after the first segment), matches the rest.
    fn match_rest(&self, s: &impl Text, mut from: usize) -> bool {
        let tokens = self.tokens.as_slice();
        let segments = self.segments.as_slice();
        let n = s.units();
        if segments.len() == 1 {
            return from == n;
        }

        // The last segment is anchored at the end: walk back over it.
        let last_start = segments[segments.len() - 2] as usize;
        let mut to = n;
        for &t in tokens[last_start..].iter().rev() {
            if to <= from {
                return false;
            }
            let (c, prev) = s.prev(to);
            if !self.token_matches(t, c) {
                return false;
            }
            to = prev;
        }

        // Each segment in between at its leftmost place in what remains.
        for w in segments[..segments.len() - 1].windows(2) {
            let seg = &tokens[w[0] as usize..w[1] as usize];
            from = match self.find(seg, s, from, to) {
                Some(e) => e,
                None => return false,
            };
        }
        true
    }

    /// The end of the leftmost match of `seg` within `from..to`.
    fn find(&self, seg: &[Token], s: &impl Text, from: usize, to: usize) -> Option<usize> {
        let run = seg.iter().take_while(|t| matches!(t, Token::Literal(_))).count();
        if run >= KMP_MIN_RUN {
            self.find_by_literal_run(seg, run, s, from, to)
        } else {
            self.find_naive(seg, s, from, to)
        }
    }

    /// `find` for a segment that starts with `run` literals: Knuth-Morris-Pratt over the string finds
    /// each place the literals occur in one pass, and only there is the rest of the segment tried.
    /// Linear where the naive search is quadratic (a long run of `a` against a long run of `a`).
    fn find_by_literal_run(&self, seg: &[Token], run: usize, s: &impl Text, from: usize, to: usize) -> Option<usize> {
        let lit = |k: usize| match seg[k] {
            Token::Literal(l) => l,
            _ => unreachable!("the first `run` tokens are literals"),
        };
        // fail[k]: length of the longest proper border of the first k + 1 literals.
        let mut fail = SmallVec::<u32, 32>::new();
        fail.push(0);
        let mut b = 0usize;
        for k in 1..run {
            while b > 0 && lit(k) != lit(b) {
                b = fail.as_slice()[b - 1] as usize;
            }
            if lit(k) == lit(b) {
                b += 1;
            }
            fail.push(b as u32);
        }
        let fail = fail.as_slice();
        let rest = &seg[run..];
        let mut q = 0usize;
        let mut i = from;
        while i < to {
            let (c, next) = s.next(i);
            let c = if self.case_sensitive { c } else { fold(c) };
            while q > 0 && lit(q) != c {
                q = fail[q - 1] as usize;
            }
            if lit(q) == c {
                q += 1;
            }
            i = next;
            if q == run {
                if let Some(end) = self.match_at(rest, s, i, to) {
                    return Some(end);
                }
                q = fail[q - 1] as usize;
            }
        }
        None
    }

    fn find_naive(&self, seg: &[Token], s: &impl Text, mut from: usize, to: usize) -> Option<usize> {
        let first = match seg.first() {
            Some(&Token::Literal(l)) => Some(l),
            _ => None,
        };
        while to - from >= seg.len() {
            if let Some(l) = first {
                // Skip straight to the next place the segment's first character occurs; an ASCII
                // literal a code unit at a time (see `stream::skip_to`).
                if l < 0x80 && (self.case_sensitive || (l != 'k' as u32 && l != 's' as u32)) {
                    while from < to {
                        let u = s.unit(from);
                        if u == l || (!self.case_sensitive && u.wrapping_sub('A' as u32) < 26 && u + 32 == l) {
                            break;
                        }
                        from += 1;
                    }
                }
                loop {
                    if from >= to {
                        return None;
                    }
                    let (c, next) = s.next(from);
                    if c == l || (!self.case_sensitive && fold(c) == l) {
                        break;
                    }
                    from = next;
                }
                if to - from < seg.len() {
                    return None;
                }
            }
            if let Some(end) = self.match_at(seg, s, from, to) {
                return Some(end);
            }
            from = s.next(from).1;
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::super::text::Utf16;
    use super::*;

    fn compile(p: &str, cs: bool) -> Result<Program, Malformed> {
        let w: Vec<u16> = p.encode_utf16().collect();
        Program::compile(&Utf16(&w), cs)
    }

    fn is_match(s: &str, p: &str, cs: bool) -> bool {
        let w: Vec<u16> = s.encode_utf16().collect();
        compile(p, cs).map(|p| p.matches(&Utf16(&w))).unwrap_or(false)
    }

    #[test]
    fn compiles_into_single_character_tokens() {
        let p = compile("a**[]*?#[!b-d]", true).unwrap();
        assert_eq!(
            p.tokens.as_slice()[..3],
            [Token::Literal('a' as u32), Token::Any, Token::Digit]
        );
        assert_eq!(p.segments.as_slice(), &[2, 4]); // `*?` is compiled as `?*`
        assert_eq!(p.ranges.as_slice(), &[('b' as u32, 'd' as u32)]);
        let p = compile("a*??b*?", true).unwrap(); // `*?` is compiled as `?*`
        assert_eq!(p.segments.as_slice(), &[3, 5, 5]);
        let p = compile("***", true).unwrap();
        assert_eq!(p.tail, Tail::Any); // every string matches
        assert_eq!(compile("", true).unwrap().tail, Tail::End);
        assert_eq!(compile("ab?", true).unwrap().tail, Tail::End);
        assert_eq!(compile("a[b-c]#*", true).unwrap().tail, Tail::Any);
        assert_eq!(compile("a*b", true).unwrap().tail, Tail::General);
        assert_eq!(compile("\u{e9}*", true).unwrap().tail, Tail::General); // not ASCII: not in `lead`
    }

    #[test]
    fn hyphen_and_bang_rules() {
        let set = |p: &str| compile(p, true).unwrap().ranges.as_slice().to_vec();
        let c = |x: char| x as u32;
        assert_eq!(set("[-a]"), vec![(c('-'), c('-')), (c('a'), c('a'))]);
        assert_eq!(set("[a-]"), vec![(c('-'), c('-')), (c('a'), c('a'))]);
        assert_eq!(
            set("[a-c-e]"),
            vec![(c('-'), c('-')), (c('a'), c('c')), (c('e'), c('e'))]
        );
        assert_eq!(set("[a-cd]"), vec![(c('a'), c('d'))]); // merged
        assert!(!is_match("d", "[a-c-e]", true));
        assert_eq!(
            compile("[!]", true).unwrap().tokens.as_slice(),
            &[Token::Literal(c('!'))]
        );
        assert!(!is_match("x", "[a!]", true) && is_match("!", "[a!]", true));
    }

    #[test]
    fn malformed_patterns_are_reported() {
        for p in ["[", "a[b", "[!", "[a-", "[a-b", "[Z-A]", "x[b-a]y", "[]]["] {
            assert!(compile(p, true).is_err(), "{p}");
        }
        assert_eq!(compile("[Z-A]", true).err(), Some(Malformed::ReversedRange));
        assert_eq!(compile("a[b", true).err(), Some(Malformed::UnclosedList));
    }

    #[test]
    fn middle_segments_found_by_literal_runs_overlap_correctly() {
        // Segments with at least KMP_MIN_RUN leading literals take the Knuth-Morris-Pratt search.
        let ab8 = "ab".repeat(8);
        let a16 = "a".repeat(16);
        assert!(is_match(&("ab".repeat(9) + "c"), &format!("*{ab8}c*"), true));
        assert!(!is_match(&"ab".repeat(9), &format!("*{ab8}c*"), true));
        assert!(is_match(&("a".repeat(20) + "1"), &format!("*{a16}#"), true));
        assert!(is_match(&format!("{a16}_{a16}1"), &format!("*{a16}#*"), true));
        assert!(!is_match(&("a".repeat(15) + "1"), &format!("*{a16}#*"), true));
        assert!(is_match(
            &format!("x{}z!", "aB".repeat(9)),
            &format!("*{}?!", "Ab".repeat(8)),
            false
        ));
        assert!(!is_match(
            &format!("x{}z!", "aB".repeat(9)),
            &format!("*{}?!", "Ab".repeat(8)),
            true
        ));
        let border = "aabaabaabaabaabaab"; // borders of every length that is a multiple of 3
        assert!(is_match(&format!("aabaab{border}x"), &format!("*{border}?"), true));
        assert!(is_match(&format!("aabaa{border}x1"), &format!("*{border}x#"), true));
        // Short runs take the naive search.
        assert!(is_match("aaaaab1", "*aaab#*", true));
        assert!(!is_match("aaaaab", "*aaab#*", true));
    }

    /// The loop over `lead` tests the first `LEAD_SETS` lists from `lead_sets` and later ones out of
    /// line: both agree with the general matcher (negated lists, both modes, characters that are not
    /// ASCII), and each rejects what it should.
    #[test]
    fn lead_lists_in_place_and_out_of_line_agree_with_the_general_matcher() {
        let pattern = "[a-c][!0-9][A-Z][#-%][x][b-d][!q]*";
        const { assert!(LEAD_SETS < 7, "the pattern must have lists beyond lead_sets") };
        let cases: &[(&str, bool, bool)] = &[
            ("aXB#xby", true, true),
            ("aXB#xbyzz", true, true),
            ("a5B#xby", false, false),       // second list (in place)
            ("aXb#xby", false, true),        // third list, case folding (in place)
            ("aXB&xby", false, false),       // fourth list (in place)
            ("aXB#xay", false, false),       // sixth list (out of line)
            ("aXB#xBy", false, true),        // sixth list, case folding (out of line)
            ("aXB#xbq", false, false),       // seventh list, negated (out of line)
            ("aÉB#xby", true, true),         // not ASCII: the general path
            ("aX\u{212A}#xby", false, true), // KELVIN SIGN folds to k, in [A-Z] when insensitive
            ("aXB#x", false, false),
        ];
        for &(s, sensitive, insensitive) in cases {
            for (cs, expected) in [(true, sensitive), (false, insensitive)] {
                let p = compile(pattern, cs).unwrap();
                let units: Vec<u16> = s.encode_utf16().collect();
                let terminated: Vec<u16> = units.iter().copied().chain([0]).collect();
                // SAFETY: NUL-terminated.
                let by_cursor = unsafe { p.matches_cursor(super::super::stream::WideCursor(terminated.as_ptr())) };
                assert_eq!(by_cursor, expected, "{s:?}, case sensitive: {cs}");
                assert_eq!(p.matches(&Utf16(&units)), expected, "{s:?}, case sensitive: {cs}");
            }
        }
    }

    #[test]
    fn case_insensitive_lists_use_simple_folding() {
        assert!(is_match("Q", "[a-z]", false));
        assert!(is_match("q", "[A-Z]", false));
        assert!(is_match("\u{212A}", "[A-Z]", false)); // KELVIN SIGN folds to k
        assert!(is_match("K", "[\u{212A}]", false));
        assert!(!is_match("K", "[!\u{212A}]", false));
        assert!(is_match("É", "[à-ÿ]", false));
        assert!(!is_match("É", "[à-ÿ]", true));
        assert!(is_match("ſ", "S", false));
        assert!(is_match("Ā", "[ā]", false));
    }
}
