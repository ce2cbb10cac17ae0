//! A registry held in memory, with the semantics of the Windows registry that the library relies on:
//! case-insensitive names that keep the case they were created with, a default value per key, and
//! keys that can only be deleted once they have no subkeys.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering::SeqCst};
use std::sync::{Arc, Mutex, MutexGuard};

use super::watch::ChangeWatch;
use super::{RegValue, Registry, MAX_KEY_DEPTH, MAX_NAME_UNITS};
use crate::com::{E_INVALIDARG, HRESULT};

#[derive(Default)]
struct Node {
    /// Lower-cased name -> (name as created, value).
    values: BTreeMap<String, (String, RegValue)>,
    /// Lower-cased name -> (name as created, key).
    children: BTreeMap<String, (String, Node)>,
}

/// A registry held in memory. Safe to share between threads.
#[derive(Default)]
pub struct MemoryRegistry {
    root: Mutex<Node>,
    /// Counts the writes (every call that may have changed the tree), for [`MemoryWatch`].
    writes: AtomicU64,
}

/// The key names of `path`; `None` when a name is empty or too long, or the path deeper than the
/// registry allows (MAX_KEY_DEPTH). The empty path is the root.
fn split(path: &str) -> Option<Vec<&str>> {
    if path.is_empty() {
        return Some(Vec::new());
    }
    let parts: Vec<&str> = path.split('\\').collect();
    if parts.len() > MAX_KEY_DEPTH {
        return None;
    }
    parts
        .iter()
        // (A name has at most as many UTF-16 units as UTF-8 bytes: most need no count.)
        .all(|p| !p.is_empty() && (p.len() <= MAX_NAME_UNITS || p.encode_utf16().count() <= MAX_NAME_UNITS))
        .then_some(parts)
}

/// The map key of a name: its case-insensitive form, borrowed when the name is that already (lower
/// case ASCII, the common case: a lookup then allocates nothing).
fn fold(name: &str) -> Cow<'_, str> {
    if name.bytes().all(|b| b.is_ascii() && !b.is_ascii_uppercase()) {
        Cow::Borrowed(name)
    } else {
        Cow::Owned(super::path::folded(name))
    }
}

impl Drop for Node {
    /// Frees the subtree level by level, not by recursion: the depth of a tree costs no stack.
    fn drop(&mut self) {
        let mut pending: Vec<Node> = core::mem::take(&mut self.children)
            .into_values()
            .map(|(_, n)| n)
            .collect();
        while let Some(mut node) = pending.pop() {
            pending.extend(core::mem::take(&mut node.children).into_values().map(|(_, n)| n));
        }
    }
}

impl Node {
    fn find(&self, parts: &[&str]) -> Option<&Node> {
        parts.iter().try_fold(self, |node, part| {
            node.children.get(fold(part).as_ref()).map(|(_, n)| n)
        })
    }

    fn find_mut(&mut self, parts: &[&str]) -> Option<&mut Node> {
        parts.iter().try_fold(self, |node, part| {
            node.children.get_mut(fold(part).as_ref()).map(|(_, n)| n)
        })
    }

    fn create(&mut self, parts: &[&str]) -> &mut Node {
        parts.iter().fold(self, |node, part| {
            let key = fold(part);
            // (Looked up first, so that the keys on the way, which exist, cost no allocation.)
            if !node.children.contains_key(key.as_ref()) {
                node.children
                    .insert(key.clone().into_owned(), (part.to_string(), Node::default()));
            }
            &mut node.children.get_mut(key.as_ref()).expect("present").1
        })
    }
}

impl MemoryRegistry {
    /// An empty registry.
    pub fn new() -> MemoryRegistry {
        MemoryRegistry::default()
    }

    fn root(&self) -> MutexGuard<'_, Node> {
        // Every operation leaves the tree consistent, so a panic elsewhere cannot corrupt it.
        self.root.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The tree, to change: the change is counted (before the write returns) for [`MemoryWatch`].
    fn root_to_write(&self) -> MutexGuard<'_, Node> {
        let root = self.root();
        self.writes.fetch_add(1, SeqCst);
        root
    }
}

/// The change watch of a registry held in memory: a change is any write since the arm.
pub(crate) struct MemoryWatch {
    reg: Arc<MemoryRegistry>,
    armed_at: AtomicU64,
}

impl MemoryWatch {
    pub(crate) fn new(reg: Arc<MemoryRegistry>) -> MemoryWatch {
        // Not armed yet: a count no registry reaches.
        MemoryWatch {
            reg,
            armed_at: AtomicU64::new(u64::MAX),
        }
    }
}

impl ChangeWatch for MemoryWatch {
    fn arm(&self) -> Result<(), HRESULT> {
        self.armed_at.store(self.reg.writes.load(SeqCst), SeqCst);
        Ok(())
    }

    fn changed(&self) -> bool {
        self.reg.writes.load(SeqCst) != self.armed_at.load(SeqCst)
    }
}

impl Registry for MemoryRegistry {
    fn key_exists(&self, path: &str) -> bool {
        split(path).is_some_and(|parts| self.root().find(&parts).is_some())
    }

    fn subkeys(&self, path: &str) -> Vec<String> {
        let Some(parts) = split(path) else { return Vec::new() };
        let root = self.root();
        root.find(&parts)
            .map(|n| n.children.values().map(|(name, _)| name.clone()).collect())
            .unwrap_or_default()
    }

    fn values(&self, path: &str) -> Vec<(String, RegValue)> {
        let Some(parts) = split(path) else { return Vec::new() };
        let root = self.root();
        root.find(&parts)
            .map(|n| n.values.values().cloned().collect())
            .unwrap_or_default()
    }

    fn value(&self, path: &str, name: &str) -> Option<RegValue> {
        let parts = split(path)?;
        let root = self.root();
        root.find(&parts)?
            .values
            .get(fold(name).as_ref())
            .map(|(_, v)| v.clone())
    }

    fn create_key(&self, path: &str) -> Result<(), HRESULT> {
        let parts = split(path).filter(|p| !p.is_empty()).ok_or(E_INVALIDARG)?;
        self.root_to_write().create(&parts);
        Ok(())
    }

    fn set_value(&self, path: &str, name: &str, value: &RegValue) -> Result<(), HRESULT> {
        let parts = split(path).ok_or(E_INVALIDARG)?;
        if name.encode_utf16().count() > MAX_NAME_UNITS {
            return Err(E_INVALIDARG);
        }
        let mut root = self.root_to_write();
        let node = root.create(&parts);
        node.values
            .insert(fold(name).into_owned(), (name.to_string(), value.clone()));
        Ok(())
    }

    fn delete_value(&self, path: &str, name: &str) -> Result<(), HRESULT> {
        let parts = split(path).ok_or(E_INVALIDARG)?;
        if let Some(node) = self.root_to_write().find_mut(&parts) {
            node.values.remove(fold(name).as_ref());
        }
        Ok(())
    }

    fn delete_key(&self, path: &str) -> Result<(), HRESULT> {
        let parts = split(path).filter(|p| !p.is_empty()).ok_or(E_INVALIDARG)?;
        let (last, parents) = parts.split_last().expect("checked non-empty");
        let mut root = self.root_to_write();
        let Some(parent) = root.find_mut(parents) else {
            return Ok(());
        };
        match parent.children.get(fold(last).as_ref()) {
            None => Ok(()),
            // Windows refuses to delete a key with subkeys (ERROR_ACCESS_DENIED).
            Some((_, node)) if !node.children.is_empty() => Err(crate::com::hr(0x80070005)),
            Some(_) => {
                parent.children.remove(fold(last).as_ref());
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sz(s: &str) -> RegValue {
        RegValue::Sz(s.to_string())
    }

    #[test]
    fn names_are_case_insensitive_and_keep_their_case() {
        let reg = MemoryRegistry::new();
        reg.set_value("CLSID\\{A}\\ProgID", "", &sz("Vendor.Server.1")).unwrap();
        assert!(reg.key_exists("clsid\\{a}"));
        assert_eq!(reg.subkeys("CLSID"), vec!["{A}".to_string()]);
        assert_eq!(reg.value("clsid\\{A}\\progid", ""), Some(sz("Vendor.Server.1")));
        reg.set_value("CLSID\\{A}", "AppID", &sz("x")).unwrap();
        assert_eq!(reg.value("CLSID\\{A}", "appid"), Some(sz("x")));
        reg.set_value("CLSID\\{A}", "APPID", &sz("y")).unwrap();
        assert_eq!(reg.values("CLSID\\{A}"), vec![("APPID".to_string(), sz("y"))]);
    }

    #[test]
    fn keys_with_subkeys_cannot_be_deleted() {
        let reg = MemoryRegistry::new();
        reg.create_key("A\\B").unwrap();
        assert!(reg.delete_key("A").is_err());
        reg.delete_key("a\\b").unwrap();
        reg.delete_key("A").unwrap();
        assert!(!reg.key_exists("A"));
        // Deleting what is not there succeeds.
        reg.delete_key("A\\B\\C").unwrap();
        reg.delete_value("A", "x").unwrap();
    }

    #[test]
    #[cfg_attr(miri, ignore = "safe code only (no unsafe on its path), long under Miri")]
    fn malformed_paths_are_refused() {
        let reg = MemoryRegistry::new();
        assert_eq!(reg.create_key(""), Err(E_INVALIDARG));
        assert_eq!(reg.create_key("A\\\\B"), Err(E_INVALIDARG));
        assert_eq!(reg.create_key(&"x".repeat(256)), Err(E_INVALIDARG));
        assert!(reg.create_key(&"x".repeat(255)).is_ok());
        // Malformed spellings of keys that exist find nothing.
        reg.create_key("A\\B").unwrap();
        assert!(reg.key_exists("A") && reg.key_exists("A\\B"));
        assert!(!reg.key_exists("A\\"));
        assert!(!reg.key_exists("A\\\\B"));
        assert!(reg.subkeys("\\").is_empty());
        assert!(reg.subkeys("A\\").is_empty());
        assert_eq!(reg.subkeys("A"), vec!["B".to_string()]);
        // As deep as the Windows registry goes (512 levels), and no deeper.
        let deepest = vec!["k"; MAX_KEY_DEPTH].join("\\");
        assert!(reg.create_key(&deepest).is_ok());
        assert_eq!(reg.create_key(&format!("{deepest}\\k")), Err(E_INVALIDARG));
        assert_eq!(
            reg.set_value(&format!("{deepest}\\k"), "v", &RegValue::Dword(1)),
            Err(E_INVALIDARG)
        );
        assert!(!reg.key_exists(&format!("{deepest}\\k")));
    }
}
