//! Registry key paths and value names as the registry compares them: without regard to case, as
//! Windows does. Code that asks "is this the same key" holds a [`RegPath`] instead of lower-casing
//! strings itself.

use std::hash::{Hash, Hasher};

/// A key path (`CLSID\{...}\InprocServer32`) or value name, kept as written and compared, hashed and
/// ordered case-insensitively (each character by its lower-case mapping).
#[derive(Clone, Debug)]
pub struct RegPath(String);

/// The case-insensitive form of one character.
fn fold(c: char) -> impl Iterator<Item = char> {
    c.to_lowercase()
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
    name.chars().flat_map(fold).collect()
}

impl PartialEq for RegPath {
    fn eq(&self, other: &RegPath) -> bool {
        self.folded().eq(other.folded())
    }
}

impl Eq for RegPath {}

impl Hash for RegPath {
    fn hash<H: Hasher>(&self, state: &mut H) {
        for c in self.folded() {
            c.hash(state);
        }
    }
}

impl PartialOrd for RegPath {
    fn partial_cmp(&self, other: &RegPath) -> Option<core::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for RegPath {
    fn cmp(&self, other: &RegPath) -> core::cmp::Ordering {
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
    }
}
