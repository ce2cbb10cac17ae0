//! Registry key paths and value names as the registry compares them: without regard to case, as
//! Windows does. Code that asks "is this the same key" holds a [`RegPath`] instead of lower-casing
//! strings itself.

use std::hash::{Hash, Hasher};

/// A key path (`CLSID\{...}\InprocServer32`) or value name, kept as written and compared, hashed and
/// ordered case-insensitively (each character by its lower-case mapping).
#[derive(Clone, Debug)]
pub struct RegPath(String);

/// The case-insensitive form of one character: its lower-case mapping. ASCII (every key the library
/// writes) maps to one character without the general case-mapping tables.
fn fold(c: char) -> Folded {
    if c.is_ascii() {
        Folded::Ascii(Some(c.to_ascii_lowercase()))
    } else {
        Folded::Other(c.to_lowercase())
    }
}

enum Folded {
    Ascii(Option<char>),
    Other(core::char::ToLowercase),
}

impl Iterator for Folded {
    type Item = char;
    fn next(&mut self) -> Option<char> {
        match self {
            Folded::Ascii(c) => c.take(),
            Folded::Other(it) => it.next(),
        }
    }
}

/// Both texts are ASCII: their folded forms are their ASCII lower case, byte by byte (the same
/// characters in the same order as the general path gives).
fn both_ascii(a: &str, b: &str) -> bool {
    a.is_ascii() && b.is_ascii()
}

impl RegPath {
    /// A path as written.
    pub fn new(text: impl Into<String>) -> RegPath {
        RegPath(text.into())
    }

    /// The path as written.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// The rest of the path after `prefix`, if the path starts with it (ignoring case).
    pub fn strip_prefix(&self, prefix: &str) -> Option<&str> {
        let mut rest = self.0.char_indices();
        for p in prefix.chars() {
            let (_, c) = rest.next()?;
            if !fold(c).eq(fold(p)) {
                return None;
            }
        }
        Some(rest.next().map_or("", |(i, _)| &self.0[i..]))
    }

    fn folded(&self) -> impl Iterator<Item = char> + '_ {
        self.0.chars().flat_map(fold)
    }
}

/// The case-insensitive form of a name, for maps keyed by it (the in-memory registry).
pub fn folded(name: &str) -> String {
    if name.is_ascii() {
        return name.to_ascii_lowercase();
    }
    name.chars().flat_map(fold).collect()
}

impl PartialEq for RegPath {
    fn eq(&self, other: &RegPath) -> bool {
        if both_ascii(&self.0, &other.0) {
            return self.0.eq_ignore_ascii_case(&other.0);
        }
        self.folded().eq(other.folded())
    }
}

impl Eq for RegPath {}

impl Hash for RegPath {
    fn hash<H: Hasher>(&self, state: &mut H) {
        // The folded text, as `str` hashes (equal paths fold to the same text, "K" and KELVIN SIGN
        // included), in one write rather than one per character.
        folded(&self.0).hash(state);
    }
}

impl PartialOrd for RegPath {
    fn partial_cmp(&self, other: &RegPath) -> Option<core::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for RegPath {
    fn cmp(&self, other: &RegPath) -> core::cmp::Ordering {
        if both_ascii(&self.0, &other.0) {
            let (a, b) = (self.0.bytes(), other.0.bytes());
            return a.map(|c| c.to_ascii_lowercase()).cmp(b.map(|c| c.to_ascii_lowercase()));
        }
        self.folded().cmp(other.folded())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn paths_compare_hash_and_strip_without_regard_to_case() {
        let a = RegPath::new("CLSID\\{ABC}\\InprocServer32");
        let b = RegPath::new("clsid\\{abc}\\INPROCSERVER32");
        assert_eq!(a, b);
        assert_ne!(a, RegPath::new("CLSID\\{ABC}\\LocalServer32"));
        assert!(HashSet::from([a.clone()]).contains(&b));
        assert_eq!(a.strip_prefix("clsid\\"), Some("{ABC}\\InprocServer32"));
        assert_eq!(a.strip_prefix("CLSID\\{ABC}\\InprocServer32"), Some(""));
        assert_eq!(a.strip_prefix("CLSIDX"), None);
        assert_eq!(RegPath::new("Ä").strip_prefix("ä"), Some(""));
        assert_eq!(a.as_str(), "CLSID\\{ABC}\\InprocServer32");
        assert!(RegPath::new("a") < RegPath::new("B"));
        assert_eq!(folded("Grüße ÄB"), "grüße äb");
        // The ASCII shortcuts give what the general mapping gives, and mixed texts compare alike.
        for c in (0..128u8).map(char::from) {
            assert!(fold(c).eq(c.to_lowercase()), "{c:?}");
        }
        assert!(RegPath::new("Z") < RegPath::new("ä") && RegPath::new("äa") < RegPath::new("äB"));
        assert_eq!(RegPath::new("Äb"), RegPath::new("äB"));
        // An ASCII path and a non-ASCII one that folds to it are equal and hash alike.
        assert_eq!(RegPath::new("\u{212A}ey"), RegPath::new("KEY"));
        assert!(HashSet::from([RegPath::new("\u{212A}ey")]).contains(&RegPath::new("KEY")));
    }
}
