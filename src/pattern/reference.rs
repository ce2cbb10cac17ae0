//! The reference matcher the tests and the fuzz target compare every entry point with: the rules
//! table of docs/guide/matchpattern.md read as directly as possible (a token list, then dynamic
//! programming over it), with none of the library's cleverness. Strings and patterns are sequences of code points, where an
//! unpaired surrogate (or, from narrow text, the byte `x` of an invalid UTF-8 sequence, as 0xDC00 + x)
//! stands for itself.

use std::collections::HashMap;
use std::sync::OnceLock;

use super::fold::fold;

#[derive(Debug)]
pub enum RefToken {
    Star,
    Lit(u32),
    Any,
    Digit,
    Set(bool, Vec<(u32, u32)>),
}

/// The pattern rules read straight off docs/guide/matchpattern.md: a list ends at the first `]`.
pub fn ref_parse(p: &[u32]) -> Option<Vec<RefToken>> {
    let ch = |c: char| c as u32;
    let mut out = Vec::new();
    let mut i = 0;
    while i < p.len() {
        let c = p[i];
        i += 1;
        if c == ch('*') {
            out.push(RefToken::Star);
        } else if c == ch('?') {
            out.push(RefToken::Any);
        } else if c == ch('#') {
            out.push(RefToken::Digit);
        } else if c == ch('[') {
            let close = i + p[i..].iter().position(|&x| x == ch(']'))?;
            let body = &p[i..close];
            i = close + 1;
            if body.is_empty() {
                continue;
            }
            if body == [ch('!')] {
                out.push(RefToken::Lit(ch('!')));
                continue;
            }
            let (negated, body) = if body[0] == ch('!') {
                (true, &body[1..])
            } else {
                (false, body)
            };
            let mut items = Vec::new();
            let mut k = 0;
            let mut after_range = false;
            while k < body.len() {
                let c = body[k];
                if c == ch('-') && (k == 0 || after_range) {
                    items.push((c, c));
                    k += 1;
                    after_range = false;
                } else if k + 2 < body.len() && body[k + 1] == ch('-') {
                    if body[k + 2] < c {
                        return None;
                    }
                    items.push((c, body[k + 2]));
                    k += 3;
                    after_range = true;
                } else {
                    items.push((c, c));
                    k += 1;
                    after_range = false;
                }
            }
            out.push(RefToken::Set(negated, items));
        } else {
            out.push(RefToken::Lit(c));
        }
    }
    Some(out)
}

/// Every code point with the same simple case folding as `c`.
fn case_class(c: u32) -> Vec<u32> {
    static CLASSES: OnceLock<HashMap<u32, Vec<u32>>> = OnceLock::new();
    let classes = CLASSES.get_or_init(|| {
        let mut m: HashMap<u32, Vec<u32>> = HashMap::new();
        // Only code points inside a folding run fold to something else.
        for x in super::fold_table::FOLD_RUNS.iter().flat_map(|r| r.0..=r.1) {
            let f = fold(x);
            if f != x {
                m.entry(f).or_insert_with(|| vec![f]).push(x);
            }
        }
        m
    });
    classes.get(&fold(c)).cloned().unwrap_or_else(|| vec![c])
}

fn ref_one(t: &RefToken, c: u32, cs: bool) -> bool {
    match t {
        RefToken::Star => unreachable!(),
        RefToken::Lit(l) => {
            if cs {
                c == *l
            } else {
                fold(c) == fold(*l)
            }
        }
        RefToken::Any => true,
        RefToken::Digit => (b'0' as u32..=b'9' as u32).contains(&c),
        RefToken::Set(negated, items) => {
            let class = if cs { vec![c] } else { case_class(c) };
            let inside = items.iter().any(|&(lo, hi)| class.iter().any(|&x| lo <= x && x <= hi));
            inside != *negated
        }
    }
}

/// Dynamic programming over the token list: `m[j][i]` = tokens `j..` match characters `i..`.
pub fn ref_match(s: &[u32], p: &[u32], cs: bool) -> bool {
    let Some(toks) = ref_parse(p) else {
        return false;
    };
    let (n, m) = (s.len(), toks.len());
    let mut dp = vec![vec![false; n + 1]; m + 1];
    dp[m][n] = true;
    for j in (0..m).rev() {
        for i in (0..=n).rev() {
            dp[j][i] = match &toks[j] {
                RefToken::Star => dp[j + 1][i] || (i < n && dp[j][i + 1]),
                t => i < n && ref_one(t, s[i], cs) && dp[j + 1][i + 1],
            };
        }
    }
    dp[0][0]
}

/// The code points of UTF-16 text; unpaired surrogates stand for themselves.
pub fn decode_wide(s: &[u16]) -> Vec<u32> {
    char::decode_utf16(s.iter().copied())
        .map(|r| r.map(|c| c as u32).unwrap_or_else(|e| e.unpaired_surrogate() as u32))
        .collect()
}

/// The code points of narrow (UTF-8) text; each byte `x` of an invalid sequence is 0xDC00 + x.
pub fn decode_narrow(b: &[u8]) -> Vec<u32> {
    let mut out = Vec::new();
    for chunk in b.utf8_chunks() {
        out.extend(chunk.valid().chars().map(|c| c as u32));
        out.extend(chunk.invalid().iter().map(|&x| 0xDC00 + x as u32));
    }
    out
}
