//! The record of what a registration wrote (the ledger), kept in the value `OpcComnRegistration` of the
//! server's module key: its entry format, the [`Recorder`] that writes keys and values while noting
//! what it added, and the rule every unregistration follows: a value is taken back (deleted, or its
//! previous data restored) only while it still holds the data this registration wrote
//! ([`Entry::still_written`]); a value someone else wrote or rewrote since is theirs.

use std::collections::{HashMap, HashSet};

use crate::com::HRESULT;
use crate::registry::cmdline::program_path;
use crate::registry::path::RegPath;
use crate::registry::{RegValue, Registry};

/// The value of the module key holding the registration ledger.
pub(crate) const LEDGER: &str = "OpcComnRegistration";

/// One thing a registration did, as the ledger records it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Entry {
    /// Created this key.
    Key(String),
    /// Added this value (key, name, data written). The data is `None` in ledgers written before the
    /// data was recorded.
    Added(String, String, Option<RegValue>),
    /// Replaced this value (key, name, previous data, data written; `None` as for `Added`).
    Replaced(String, String, RegValue, Option<RegValue>),
    /// At the first registration another server already registered the class in the other module key
    /// (`LocalServer32` for an in-process server, and the reverse).
    OtherServer,
    /// The EXE host registered the server as the Windows service `name`, whose command line it set to
    /// `written`: it created the service (`previous` `None`), or took over another product's service
    /// of that name, whose command line was `previous` (see `service`).
    Service {
        name: String,
        written: String,
        previous: Option<String>,
    },
}

fn escape(s: &str) -> String {
    s.replace('%', "%25").replace('|', "%7C").replace(';', "%3B")
}

fn unescape(s: &str) -> String {
    s.replace("%3B", ";").replace("%7C", "|").replace("%25", "%")
}

/// A value's data as ledger text with its registry type (`REG_SZ` 1, `REG_EXPAND_SZ` 2, `REG_DWORD`
/// 4 in decimal, anything else, `REG_BINARY` 3 for the AppID's permissions, in hex).
fn data_text(value: &RegValue) -> (String, u32) {
    match value {
        RegValue::Sz(s) => (s.clone(), 1),
        RegValue::ExpandSz(s) => (s.clone(), 2),
        RegValue::Dword(d) => (d.to_string(), 4),
        RegValue::Other { kind, bytes } => (bytes.iter().map(|b| format!("{b:02x}")).collect(), *kind),
    }
}

/// The value [`data_text`] wrote (None for text that is not of its form).
fn data_of(text: &str, kind: &str) -> Option<RegValue> {
    let kind: u32 = kind.parse().ok()?;
    Some(match kind {
        1 => RegValue::Sz(text.to_string()),
        2 => RegValue::ExpandSz(text.to_string()),
        4 => RegValue::Dword(text.parse().ok()?),
        _ if text.len() % 2 == 0 && text.is_ascii() => RegValue::Other {
            kind,
            bytes: (0..text.len())
                .step_by(2)
                .map(|i| u8::from_str_radix(&text[i..i + 2], 16).ok())
                .collect::<Option<Vec<u8>>>()?,
        },
        _ => return None,
    })
}

/// True when the entry's data must be recorded with its type: not all of it is `REG_SZ`. (Ledgers
/// of only strings keep the form they always had.)
fn typed(values: &[&RegValue]) -> bool {
    values.iter().any(|v| !matches!(v, RegValue::Sz(_)))
}

impl Entry {
    pub(crate) fn encode(&self) -> String {
        match self {
            Entry::Key(k) => format!("K{}", escape(k)),
            Entry::OtherServer => "O".to_string(),
            // A library that predates service registration finds no entry it knows there and leaves
            // the service alone.
            Entry::Service {
                name,
                written,
                previous,
            } => match previous {
                None => format!("S{}|{}", escape(name), escape(written)),
                Some(previous) => format!("S{}|{}|{}", escape(name), escape(written), escape(previous)),
            },
            // Typed entries have one more field (V) or two (R): the registry types. A library that
            // predates them finds no entry it knows there and leaves the value alone.
            Entry::Added(k, n, data) => match data {
                Some(data) if typed(&[data]) => {
                    let (text, kind) = data_text(data);
                    format!("V{}|{}|{}|{kind}", escape(k), escape(n), escape(&text))
                }
                Some(data) => format!("V{}|{}|{}", escape(k), escape(n), escape(&data_text(data).0)),
                None => format!("V{}|{}", escape(k), escape(n)),
            },
            Entry::Replaced(k, n, old, data) => {
                let (old_text, old_kind) = data_text(old);
                match data {
                    Some(data) if typed(&[old, data]) => {
                        let (text, kind) = data_text(data);
                        format!(
                            "R{}|{}|{}|{}|{old_kind}|{kind}",
                            escape(k),
                            escape(n),
                            escape(&old_text),
                            escape(&text)
                        )
                    }
                    Some(data) => format!(
                        "R{}|{}|{}|{}",
                        escape(k),
                        escape(n),
                        escape(&old_text),
                        escape(&data_text(data).0)
                    ),
                    // (Only ledgers of strings have entries without the data written.)
                    None => format!("R{}|{}|{}", escape(k), escape(n), escape(&old_text)),
                }
            }
        }
    }

    pub(super) fn decode(s: &str) -> Option<Entry> {
        let mut chars = s.chars();
        let tag = chars.next()?;
        let fields: Vec<String> = chars.as_str().split('|').map(unescape).collect();
        match (tag, fields.as_slice()) {
            ('K', [k]) => Some(Entry::Key(k.clone())),
            ('V', [k, n]) => Some(Entry::Added(k.clone(), n.clone(), None)),
            ('V', [k, n, data]) => Some(Entry::Added(k.clone(), n.clone(), Some(RegValue::Sz(data.clone())))),
            ('V', [k, n, data, kind]) => Some(Entry::Added(k.clone(), n.clone(), Some(data_of(data, kind)?))),
            ('R', [k, n, old]) => Some(Entry::Replaced(k.clone(), n.clone(), RegValue::Sz(old.clone()), None)),
            ('R', [k, n, old, data]) => Some(Entry::Replaced(
                k.clone(),
                n.clone(),
                RegValue::Sz(old.clone()),
                Some(RegValue::Sz(data.clone())),
            )),
            ('R', [k, n, old, data, old_kind, kind]) => Some(Entry::Replaced(
                k.clone(),
                n.clone(),
                data_of(old, old_kind)?,
                Some(data_of(data, kind)?),
            )),
            ('O', [empty]) if empty.is_empty() => Some(Entry::OtherServer),
            ('S', [name, written]) => Some(Entry::Service {
                name: name.clone(),
                written: written.clone(),
                previous: None,
            }),
            ('S', [name, written, previous]) => Some(Entry::Service {
                name: name.clone(),
                written: written.clone(),
                previous: Some(previous.clone()),
            }),
            _ => None,
        }
    }

    /// The value this entry is about, for "already recorded" checks.
    pub(super) fn value(&self) -> Option<(RegPath, RegPath)> {
        match self {
            Entry::Key(_) | Entry::OtherServer | Entry::Service { .. } => None,
            Entry::Added(k, n, _) | Entry::Replaced(k, n, _, _) => Some((RegPath::new(k), RegPath::new(n))),
        }
    }

    /// True when the value this entry recorded still holds the data the registration wrote, so that
    /// taking it back harms nobody. `expected` gives the data for entries of older ledgers, which did
    /// not record it (`None` from it too: the value is taken as still written, the rule of those
    /// ledgers). A missing value, or one of another type, no longer holds it. Always true for keys
    /// (and for a service, which is not in the registry: `service` checks it).
    pub(crate) fn still_written(&self, reg: &dyn Registry, expected: impl Fn(&str, &str) -> Option<RegValue>) -> bool {
        let (key, name, written) = match self {
            Entry::Key(_) | Entry::OtherServer | Entry::Service { .. } => return true,
            Entry::Added(k, n, w) | Entry::Replaced(k, n, _, w) => (k, n, w),
        };
        let Some(current) = reg.value(key, name) else {
            return false;
        };
        match written.clone().or_else(|| expected(key, name)) {
            Some(written) => same_data(key, name, &current, &written),
            // Ledgers that did not record the data only ever wrote strings.
            None => current.as_str().is_some(),
        }
    }

    /// True when this entry records the value `name` of `key`.
    pub(crate) fn is_value(&self, key: &str, name: &str) -> bool {
        self.value() == Some((RegPath::new(key), RegPath::new(name)))
    }

    /// The key this entry is about (none for `OtherServer` and `Service`).
    pub(crate) fn key(&self) -> Option<&str> {
        match self {
            Entry::Key(k) | Entry::Added(k, _, _) | Entry::Replaced(k, _, _, _) => Some(k),
            Entry::OtherServer | Entry::Service { .. } => None,
        }
    }
}

/// True when `current`, the data of value `name` of `key`, is `written`: the same type (`REG_SZ` and
/// `REG_EXPAND_SZ` count as text) and data. A `LocalServer32` command line compares by its program
/// path as well, so a registration from before command lines were quoted (the same path unquoted)
/// still counts as this registration's.
fn same_data(key: &str, name: &str, current: &RegValue, written: &RegValue) -> bool {
    let (Some(current), Some(written)) = (current.as_str(), written.as_str()) else {
        return current == written;
    };
    if current == written {
        return true;
    }
    let is_command_line = name.is_empty()
        && key
            .rsplit('\\')
            .next()
            .is_some_and(|k| k.eq_ignore_ascii_case("LocalServer32"));
    is_command_line && program_path(current).eq_ignore_ascii_case(program_path(written))
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

/// Writes `ledger` as the record of the registration whose module key is `module_key`.
pub(crate) fn write_ledger(reg: &dyn Registry, module_key: &str, ledger: &[Entry]) -> Result<(), HRESULT> {
    let text: Vec<String> = ledger.iter().map(Entry::encode).collect();
    reg.set_value(module_key, LEDGER, &RegValue::Sz(text.join(";")))
}

/// Writes keys and values while recording what it adds.
pub(crate) struct Recorder<'a> {
    reg: &'a dyn Registry,
    pub(crate) ledger: Vec<Entry>,
    keys: HashSet<RegPath>,
    pub(super) values: HashSet<(RegPath, RegPath)>,
    /// For values another registration wrote and still holds (an AppID several classes name): what
    /// was there before that one, recorded in its place as the previous data (`None`: the value did
    /// not exist).
    pub(super) origins: HashMap<(RegPath, RegPath), Option<RegValue>>,
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
            origins: HashMap::new(),
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

    /// Writes the string `data` to the value `name` of `path` (see [`Recorder::set`]).
    pub(crate) fn value(&mut self, path: &str, name: &str, data: &str, replace: bool) -> Result<(), HRESULT> {
        self.set(path, name, &RegValue::Sz(data.to_string()), replace)
    }

    /// Writes `data` to the value `name` of `path`, recording it as added, or as replaced with the
    /// previous data; a value that exists is left as it is unless `replace`.
    pub(crate) fn set(&mut self, path: &str, name: &str, data: &RegValue, replace: bool) -> Result<(), HRESULT> {
        let id = (RegPath::new(path), RegPath::new(name));
        match self.reg.value(path, name) {
            Some(old) if old == *data => {
                // Already so; if this registration wrote it, the record says so too.
                self.note_written(&id, data);
                return Ok(());
            }
            Some(_) if !replace => return Ok(()),
            Some(old) => {
                if self.values.contains(&id) {
                    // Ours already (registering again, say at a new path): the record follows.
                    self.note_written(&id, data);
                } else {
                    let (path, name, written) = (path.to_string(), name.to_string(), Some(data.clone()));
                    self.ledger.push(match self.origins.get(&id) {
                        // What it replaces another registration wrote: what was there before that.
                        Some(None) => Entry::Added(path, name, written),
                        Some(Some(before)) => Entry::Replaced(path, name, before.clone(), written),
                        None => Entry::Replaced(path, name, old, written),
                    });
                    self.values.insert(id);
                }
            }
            None => {
                self.note_missing_keys(path);
                if self.values.insert(id.clone()) {
                    self.ledger
                        .push(Entry::Added(path.to_string(), name.to_string(), Some(data.clone())));
                } else {
                    self.note_written(&id, data);
                }
            }
        }
        self.reg.set_value(path, name, data)
    }

    /// Records `data` as what this registration wrote to the value `id`, if the ledger has it.
    fn note_written(&mut self, id: &(RegPath, RegPath), data: &RegValue) {
        for entry in &mut self.ledger {
            if entry.value().as_ref() == Some(id) {
                if let Entry::Added(_, _, written) | Entry::Replaced(_, _, _, written) = entry {
                    *written = Some(data.clone());
                }
            }
        }
    }
}
