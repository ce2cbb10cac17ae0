//! The record of what a registration wrote (the ledger), kept in the value `OpcComnRegistration` of the
//! server's module key: its entry format and the [`Recorder`] that writes keys and values while
//! noting what it added.

use std::collections::HashSet;

use crate::com::HRESULT;
use crate::registry::path::RegPath;
use crate::registry::{RegValue, Registry};

/// The value of the module key holding the registration ledger.
pub(crate) const LEDGER: &str = "OpcComnRegistration";

/// One thing a registration did, as the ledger records it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Entry {
    /// Created this key.
    Key(String),
    /// Added this value (key, name).
    Added(String, String),
    /// Replaced this value (key, name, previous data).
    Replaced(String, String, String),
    /// At the first registration another server already registered the class in the other module key
    /// (`LocalServer32` for an in-process server, and the reverse).
    OtherServer,
}

fn escape(s: &str) -> String {
    s.replace('%', "%25").replace('|', "%7C").replace(';', "%3B")
}

fn unescape(s: &str) -> String {
    s.replace("%3B", ";").replace("%7C", "|").replace("%25", "%")
}

impl Entry {
    pub(crate) fn encode(&self) -> String {
        match self {
            Entry::Key(k) => format!("K{}", escape(k)),
            Entry::OtherServer => "O".to_string(),
            Entry::Added(k, n) => format!("V{}|{}", escape(k), escape(n)),
            Entry::Replaced(k, n, old) => format!("R{}|{}|{}", escape(k), escape(n), escape(old)),
        }
    }

    pub(super) fn decode(s: &str) -> Option<Entry> {
        let mut chars = s.chars();
        let tag = chars.next()?;
        let fields: Vec<String> = chars.as_str().split('|').map(unescape).collect();
        match (tag, fields.as_slice()) {
            ('K', [k]) => Some(Entry::Key(k.clone())),
            ('V', [k, n]) => Some(Entry::Added(k.clone(), n.clone())),
            ('R', [k, n, old]) => Some(Entry::Replaced(k.clone(), n.clone(), old.clone())),
            ('O', [empty]) if empty.is_empty() => Some(Entry::OtherServer),
            _ => None,
        }
    }

    /// The value this entry is about, for "already recorded" checks.
    fn value(&self) -> Option<(RegPath, RegPath)> {
        match self {
            Entry::Key(_) | Entry::OtherServer => None,
            Entry::Added(k, n) | Entry::Replaced(k, n, _) => Some((RegPath::new(k), RegPath::new(n))),
        }
    }

    /// The key this entry is about (none for `OtherServer`).
    pub(super) fn key(&self) -> Option<&str> {
        match self {
            Entry::Key(k) | Entry::Added(k, _) | Entry::Replaced(k, _, _) => Some(k),
            Entry::OtherServer => None,
        }
    }
}

pub(crate) fn read_ledger(reg: &dyn Registry, module_key: &str) -> Option<Vec<Entry>> {
    let text = reg.value(module_key, LEDGER)?;
    let text = text.as_str()?;
    Some(
        text.split(';')
            .filter(|s| !s.is_empty())
            .filter_map(Entry::decode)
            .collect(),
    )
}

/// Writes keys and values while recording what it adds.
pub(crate) struct Recorder<'a> {
    reg: &'a dyn Registry,
    pub(crate) ledger: Vec<Entry>,
    keys: HashSet<RegPath>,
    pub(super) values: HashSet<(RegPath, RegPath)>,
}

impl<'a> Recorder<'a> {
    pub(crate) fn new(reg: &'a dyn Registry, ledger: Vec<Entry>) -> Recorder<'a> {
        let keys = ledger
            .iter()
            .filter_map(|e| match e {
                Entry::Key(k) => Some(RegPath::new(k)),
                _ => None,
            })
            .collect();
        let values = ledger.iter().filter_map(Entry::value).collect();
        Recorder {
            reg,
            ledger,
            keys,
            values,
        }
    }

    /// Records every missing key on the way to `path` (parents first); does not create them.
    pub(super) fn note_missing_keys(&mut self, path: &str) {
        // A key exists only with all its parents: nothing is missing (the common case, one lookup).
        if self.reg.key_exists(path) {
            return;
        }
        let mut prefix = String::new();
        for part in path.split('\\') {
            if !prefix.is_empty() {
                prefix.push('\\');
            }
            prefix.push_str(part);
            if !self.reg.key_exists(&prefix) && self.keys.insert(RegPath::new(&prefix)) {
                self.ledger.push(Entry::Key(prefix.clone()));
            }
        }
    }

    pub(crate) fn key(&mut self, path: &str) -> Result<(), HRESULT> {
        self.note_missing_keys(path);
        self.reg.create_key(path)
    }

    pub(crate) fn value(&mut self, path: &str, name: &str, data: &str, replace: bool) -> Result<(), HRESULT> {
        let id = (RegPath::new(path), RegPath::new(name));
        match self.reg.value(path, name) {
            Some(RegValue::Sz(old)) if old == data => return Ok(()),
            Some(_) if !replace => return Ok(()),
            Some(old) => {
                if let (Some(old), true) = (old.as_str(), !self.values.contains(&id)) {
                    self.ledger
                        .push(Entry::Replaced(path.to_string(), name.to_string(), old.to_string()));
                    self.values.insert(id);
                }
            }
            None => {
                self.note_missing_keys(path);
                if self.values.insert(id) {
                    self.ledger.push(Entry::Added(path.to_string(), name.to_string()));
                }
            }
        }
        self.reg.set_value(path, name, &RegValue::Sz(data.to_string()))
    }
}
