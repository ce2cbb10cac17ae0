//! The register / unregister algorithm: write the key list while recording it, and take back exactly
//! what the record says (see the module documentation).

use super::app_id;
use super::description::ServerDescription;
use super::ledger::{read_ledger, write_ledger, Entry, Recorder, LEDGER};
use crate::com::{GUID, HRESULT};
use crate::registry::categories::standard_description;
use crate::registry::path::RegPath;
use crate::registry::{
    category_key, class_categories_key, class_key, parse_guid, RegValue, Registries, Registry, REGDB_E_KEYMISSING,
};

/// Locale of the category descriptions (English, as the standard texts are).
pub(crate) const LCID_ENGLISH: u32 = 0x409;

/// Registers the server `d` in `regs` (see the module documentation for what is written).
/// A description that is not valid is refused before anything is written.
pub(crate) fn register(regs: &Registries, d: &ServerDescription) -> Result<(), HRESULT> {
    d.check()?;
    let reg = &*regs.write;
    let module_key = d.module_key();
    let ledger = read_ledger(reg, &module_key).unwrap_or_default();
    let first = ledger.is_empty();
    let mut rec = Recorder::new(reg, ledger);
    // Values of an AppID other classes name: recorded back to before the first of them.
    rec.origins = app_id::inherited_origins(reg, d)?;
    if first && reg.key_exists(&d.other_module_key()) {
        rec.ledger.push(Entry::OtherServer);
    }
    for (key, name, data, ours) in d.values()? {
        rec.set(&key, &name, &data, ours || !d.keep_existing)?;
    }
    if let Some(vendor_key) = d.da10_vendor.as_ref().map(|_| format!("{}\\OPC", d.prog_id)) {
        rec.key(&vendor_key)?;
    }
    for (catid, given) in &d.implemented {
        let key = category_key(catid);
        let name = format!("{LCID_ENGLISH:x}");
        let description = given.as_deref().or(standard_description(catid));
        if let (None, Some(text)) = (reg.value(&key, &name), description) {
            rec.note_missing_keys(&key);
            rec.values.insert((RegPath::new(&key), RegPath::new(&name)));
            rec.ledger.push(Entry::Added(key, name, Some(text.into())));
            reg.register_category(catid, LCID_ENGLISH, text)?;
        }
        rec.note_missing_keys(&format!("{}\\{catid}", class_categories_key(&d.clsid, false)));
        reg.register_class_category(&d.clsid, catid, false)?;
    }
    for catid in &d.required {
        rec.note_missing_keys(&format!("{}\\{catid}", class_categories_key(&d.clsid, true)));
        reg.register_class_category(&d.clsid, catid, true)?;
    }
    write_ledger(reg, &module_key, &rec.ledger)
}

/// True when a class other than `except` implements `catid` in `reg`.
fn category_in_use(reg: &dyn Registry, catid: &GUID, except: &GUID) -> bool {
    let wanted = RegPath::new(catid.to_string());
    let except = RegPath::new(except.to_string());
    reg.scan("CLSID", &["Implemented Categories"])
        .into_iter()
        .any(|(clsid, found)| {
            RegPath::new(clsid) != except
                && found[0]
                    .as_ref()
                    .is_some_and(|cats| cats.iter().any(|c| RegPath::new(c) == wanted))
        })
}

fn key_is_empty(reg: &dyn Registry, path: &str) -> bool {
    reg.subkeys(path).is_empty() && reg.values(path).is_empty()
}

/// The category and kind (required or not) a key `CLSID\{clsid}\Implemented|Required
/// Categories\{catid}` names; `prefixes` are the two category keys of the class, each with a `\`.
fn class_category_of(path: &str, prefixes: &[(String, bool); 2]) -> Option<(GUID, bool)> {
    let path = RegPath::new(path);
    for (prefix, required) in prefixes {
        if let Some(rest) = path.strip_prefix(prefix) {
            return parse_guid(rest).map(|catid| (catid, *required));
        }
    }
    None
}

/// Unregisters the server `d` from `regs`, undoing what [`register`] recorded.
///
/// Only what still holds what this registration wrote is taken back: a value someone else wrote or
/// rewrote since is left as it is (and a value it replaced is not written back over a newer
/// registration). When the class now serves another server (its program in the own module key, or
/// its other module key added after this registration: OpcEnum installed or re-registered later), the
/// keys and values this registration added where the class shares them with that server (the class
/// key, ProgIDs, categories) stay too, as they may be the other server's as well; its own entries (its
/// AppID keys, its module key while it still names this server) go, and values it replaced that still
/// hold its data get their previous data back.
pub(crate) fn unregister(regs: &Registries, d: &ServerDescription) -> Result<(), HRESULT> {
    let reg = &*regs.write;
    let module_key = d.module_key();
    let mut ledger = match read_ledger(reg, &module_key) {
        Some(ledger) => ledger,
        None => fallback_ledger(reg, d)?,
    };
    let written = Written::new(d)?;
    let expected = |key: &str, name: &str| written.data(key, name);
    let module_entry = ledger
        .iter()
        .find(|e| e.is_value(&module_key, ""))
        .cloned()
        .unwrap_or_else(|| Entry::Added(module_key.clone(), String::new(), None));
    let module_still_ours = module_entry.still_written(reg, expected);
    let other_came = !ledger.contains(&Entry::OtherServer) && reg.key_exists(&d.other_module_key());
    if !module_still_ours || other_came {
        // What it added where the class is shared may be the other server's too (the same data): it
        // stays. A value it replaced that still holds this registration's data gets its previous data
        // back.
        let own_module = RegPath::new(&module_key);
        let shared = |key: &str| {
            let path = RegPath::new(key);
            if path == own_module || path.strip_prefix(&format!("{module_key}\\")).is_some() {
                return !module_still_ours;
            }
            shared_by_the_class(d, &path)
        };
        ledger.retain(|e| matches!(e, Entry::Replaced(..)) || e.key().is_some_and(|k| !shared(k)));
    }
    // An AppID another class still names stays whole; its record goes to that class.
    let ledger = app_id::hand_over_shared(reg, d, ledger, expected)?;
    for entry in ledger.iter().rev() {
        if !entry.still_written(reg, expected) {
            continue;
        }
        match entry {
            Entry::Added(key, name, _) => {
                let category = RegPath::new(key)
                    .strip_prefix("Component Categories\\")
                    .and_then(parse_guid);
                if category.is_some_and(|catid| category_in_use(reg, &catid, &d.clsid)) {
                    continue;
                }
                reg.delete_value(key, name)?
            }
            Entry::Replaced(key, name, old, _) => reg.set_value(key, name, old)?,
            // A service is taken back by the EXE host, which knows the service manager (`service`).
            Entry::Key(_) | Entry::OtherServer | Entry::Service { .. } => {}
        }
    }
    if reg.value(&module_key, LEDGER).is_some() {
        reg.delete_value(&module_key, LEDGER)?;
    }
    let mut keys: Vec<&String> = ledger
        .iter()
        .filter_map(|e| match e {
            Entry::Key(k) => Some(k),
            _ => None,
        })
        .collect();
    // Deepest first, so children go before their parents.
    keys.sort_by_cached_key(|k| core::cmp::Reverse(k.matches('\\').count()));
    let prefixes = [false, true].map(|required| (format!("{}\\", class_categories_key(&d.clsid, required)), required));
    for key in keys {
        if let Some((catid, required)) = class_category_of(key, &prefixes) {
            if reg.key_exists(key) && reg.subkeys(key).is_empty() {
                reg.unregister_class_category(&d.clsid, &catid, required)?;
            }
        } else if reg.key_exists(key) && key_is_empty(reg, key) {
            reg.delete_key(key)?;
        }
    }
    Ok(())
}

/// What registration writes to each value, for the entries of ledgers that did not record it.
struct Written {
    /// (key, value name, data)
    values: Vec<(RegPath, RegPath, RegValue)>,
}

impl Written {
    fn new(d: &ServerDescription) -> Result<Written, HRESULT> {
        let mut values: Vec<(RegPath, RegPath, RegValue)> = d
            .values()?
            .into_iter()
            .map(|(key, name, data, _)| (RegPath::new(key), RegPath::new(name), data))
            .collect();
        for (catid, given) in &d.implemented {
            if let Some(text) = given.as_deref().or(standard_description(catid)) {
                let name = format!("{LCID_ENGLISH:x}");
                values.push((RegPath::new(category_key(catid)), RegPath::new(name), text.into()));
            }
        }
        Ok(Written { values })
    }

    fn data(&self, key: &str, name: &str) -> Option<RegValue> {
        let (key, name) = (RegPath::new(key), RegPath::new(name));
        self.values
            .iter()
            .find(|(k, n, _)| *k == key && *n == name)
            .map(|(_, _, data)| data.clone())
    }
}

/// True when `key` is one a class shares with every server registered for it: the class key and
/// its subkeys, the ProgIDs, the category descriptions.
fn shared_by_the_class(d: &ServerDescription, key: &RegPath) -> bool {
    let under = |root: &str| *key == RegPath::new(root) || key.strip_prefix(&format!("{root}\\")).is_some();
    under(&class_key(&d.clsid))
        || key.strip_prefix("Component Categories\\").is_some()
        || under(&d.prog_id)
        || d.version_independent_prog_id.as_deref().is_some_and(under)
}

/// What to undo when no ledger exists: the values that hold what registration would write, and the
/// server's own keys.
fn fallback_ledger(reg: &dyn Registry, d: &ServerDescription) -> Result<Vec<Entry>, HRESULT> {
    if !reg.key_exists(&class_key(&d.clsid)) && !reg.key_exists(&d.prog_id) {
        return Err(REGDB_E_KEYMISSING);
    }
    let mut ledger: Vec<Entry> = d.own_keys().into_iter().map(Entry::Key).collect();
    for (key, name, data, _) in d.values()? {
        let holds = reg
            .value(&key, &name)
            .is_some_and(|current| match (current.as_str(), data.as_str()) {
                (Some(current), Some(data)) => current == data,
                _ => current == data,
            });
        if holds {
            ledger.push(Entry::Added(key, name, Some(data)));
        }
    }
    Ok(ledger)
}
