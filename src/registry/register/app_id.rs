//! An AppID that several classes name (one product, several classes, one AppID: the usual layout).
//!
//! The AppID key `AppID\{appid}` with its values (the user type, `RunAs`, `AuthenticationLevel`, the
//! permissions...) is one thing the classes naming it share: COM applies it to the process that
//! serves them. So is an EXE's `AppID\<exe>` key, for the classes that program serves. The rule:
//! the AppID stays whole while any registered class names it, and goes with the last.
//!
//! - **Registration** writes the values its description gives, as for any registration, so the AppID
//!   holds what the latest registration wrote. Where it replaces a value another class's registration
//!   wrote (and still holds), it records as the previous data what was there *before that one*: every
//!   class's record of a shared value goes back to the state before the first registration.
//! - **Unregistration**, while another class still names the AppID, leaves these keys exactly as
//!   they are and hands its record of them over to the ledgers of the classes that stay: the keys it
//!   created, and each value that still holds what it wrote (for such a value the others' records now
//!   say they wrote it). The last class's unregistration then takes back what the registrations wrote
//!   there, as for any value: deleted while it holds what was written (else left: someone rewrote it),
//!   given back what was there before the first registration, a created key deleted when empty.
//! - A class that names the AppID without a ledger (registered by other means) keeps the keys as they
//!   are; nothing is handed over, they are left to it.
//!
//! Ledgers written before this rule (whose records of a shared value go back only to the previous
//! registration) are joined by the data: a record whose previous data is what the leaving class
//! wrote takes the leaving class's previous data.

use std::collections::HashMap;

use super::description::ServerDescription;
use super::keys::program_file_name;
use super::ledger::{read_ledger, write_ledger, Entry, LEDGER};
use crate::com::{GUID, HRESULT};
use crate::registry::path::RegPath;
use crate::registry::{class_key, parse_guid, RegValue, Registry};

/// Another class that names the AppID.
struct Sharer {
    /// The module key holding its ledger, when it has one.
    ledger_key: Option<String>,
    /// The file name of its program (`LocalServer32`), if any.
    program: Option<String>,
}

/// The classes other than `except` whose `AppID` value names `app_id`.
fn sharers(reg: &dyn Registry, app_id: &GUID, except: &GUID) -> Vec<Sharer> {
    reg.subkey_values("CLSID", "AppID")
        .into_iter()
        .filter_map(|(name, value)| {
            let clsid = parse_guid(&name)?;
            (clsid != *except && parse_guid(value.as_str()?) == Some(*app_id)).then_some(clsid)
        })
        .map(|clsid| {
            let class = class_key(&clsid);
            let local = format!("{class}\\LocalServer32");
            let ledger_key = [local.clone(), format!("{class}\\InprocServer32")]
                .into_iter()
                .find(|k| reg.value(k, LEDGER).is_some());
            let program = reg
                .value(&local, "")
                .and_then(|v| v.as_str().map(|s| program_file_name(s).to_string()));
            Sharer { ledger_key, program }
        })
        .collect()
}

/// The shared keys of a class's AppID: its `AppID\{appid}` key and its program's `AppID\<exe>` key.
struct Shared {
    app_id: GUID,
    app_key: RegPath,
    program: Option<String>,
    program_key: Option<RegPath>,
}

impl Shared {
    fn of(d: &ServerDescription) -> Result<Option<Shared>, HRESULT> {
        let Some(app_id) = d.app_id else {
            return Ok(None);
        };
        let program = d.app_id_program()?;
        Ok(Some(Shared {
            app_id,
            app_key: RegPath::new(format!("AppID\\{app_id}")),
            program_key: program.as_ref().map(|exe| RegPath::new(format!("AppID\\{exe}"))),
            program,
        }))
    }

    /// Whether `entry` is about the AppID's key (`Some(false)`) or the program's (`Some(true)`).
    fn kind(&self, entry: &Entry) -> Option<bool> {
        let key = RegPath::new(entry.key()?);
        if key == self.app_key {
            Some(false)
        } else if self.program_key.as_ref() == Some(&key) {
            Some(true)
        } else {
            None
        }
    }

    /// Whether the sharer shares the program's key too (the same program serves it).
    fn same_program(&self, sharer: &Sharer) -> bool {
        matches!((&sharer.program, &self.program), (Some(theirs), Some(ours)) if theirs.eq_ignore_ascii_case(ours))
    }
}

/// For registering `d`: the shared values that another class's registration wrote and still holds,
/// each with what was there before that registration (`None`: nothing). Empty for the first class of
/// an AppID (its key does not exist yet: no scan of the classes then).
pub(super) fn inherited_origins(
    reg: &dyn Registry,
    d: &ServerDescription,
) -> Result<HashMap<(RegPath, RegPath), Option<RegValue>>, HRESULT> {
    let mut origins = HashMap::new();
    let Some(shared) = Shared::of(d)? else {
        return Ok(origins);
    };
    if !reg.key_exists(&format!("AppID\\{}", shared.app_id)) {
        return Ok(origins);
    }
    for sharer in sharers(reg, &shared.app_id, &d.clsid) {
        let Some(ledger) = sharer.ledger_key.as_ref().and_then(|k| read_ledger(reg, k)) else {
            continue;
        };
        for entry in ledger {
            let origin = match &entry {
                Entry::Added(_, _, Some(_)) => None,
                Entry::Replaced(_, _, old, Some(_)) => Some(old.clone()),
                _ => continue,
            };
            let ours = match shared.kind(&entry) {
                Some(false) => true,
                Some(true) => shared.same_program(&sharer),
                None => false,
            };
            if ours && entry.still_written(reg, |_, _| None) {
                if let Some(id) = entry.value() {
                    origins.entry(id).or_insert(origin);
                }
            }
        }
    }
    Ok(origins)
}

/// For unregistering `d`: takes the entries about the shared keys out of `ledger` when another class
/// still names the AppID, handing them over to the ledgers of those classes (or leaving them, when
/// none has a ledger). What remains is taken back now. `expected` gives the data of entries of older
/// ledgers, which did not record it.
pub(super) fn hand_over_shared(
    reg: &dyn Registry,
    d: &ServerDescription,
    ledger: Vec<Entry>,
    expected: impl Fn(&str, &str) -> Option<RegValue>,
) -> Result<Vec<Entry>, HRESULT> {
    let Some(shared) = Shared::of(d)? else {
        return Ok(ledger);
    };
    if !ledger.iter().any(|e| shared.kind(e).is_some()) {
        return Ok(ledger);
    }
    let sharers = sharers(reg, &shared.app_id, &d.clsid);
    // Who takes each kind: every class naming the AppID takes the AppID's key; only those the same
    // program serves take the program's key, which goes now when there is none.
    let takers =
        |program: bool| -> Vec<&Sharer> { sharers.iter().filter(|s| !program || shared.same_program(s)).collect() };
    let (for_app, for_program) = (takers(false), takers(true));
    let mut now = Vec::new();
    let mut handed: Vec<(Entry, bool)> = Vec::new();
    for entry in ledger {
        match shared.kind(&entry) {
            Some(false) if !for_app.is_empty() => handed.push((entry, false)),
            Some(true) if !for_program.is_empty() => handed.push((entry, true)),
            _ => now.push(entry),
        }
    }
    for sharer in &sharers {
        let Some(key) = &sharer.ledger_key else {
            continue;
        };
        let mine: Vec<&Entry> = handed
            .iter()
            .filter(|(_, program)| !program || shared.same_program(sharer))
            .map(|(e, _)| e)
            .collect();
        if mine.is_empty() {
            continue;
        }
        let mut theirs = read_ledger(reg, key).unwrap_or_default();
        for entry in mine {
            take_over(reg, &mut theirs, entry.clone(), &expected);
        }
        write_ledger(reg, key, &theirs)?;
    }
    Ok(now)
}

/// The entry recording that the value `name` of `key` had `previous` (`None`: did not exist) before a
/// registration wrote `written`.
fn record(key: &str, name: &str, previous: Option<RegValue>, written: RegValue) -> Entry {
    match previous {
        None => Entry::Added(key.to_string(), name.to_string(), Some(written)),
        Some(old) => Entry::Replaced(key.to_string(), name.to_string(), old, Some(written)),
    }
}

/// Adds the leaving class's `entry` to `theirs`, the ledger of a class that stays (see the module
/// documentation).
fn take_over(
    reg: &dyn Registry,
    theirs: &mut Vec<Entry>,
    entry: Entry,
    expected: &impl Fn(&str, &str) -> Option<RegValue>,
) {
    let (key, name, previous, written) = match entry {
        Entry::Key(k) => {
            let path = RegPath::new(&k);
            if !theirs
                .iter()
                .any(|e| matches!(e, Entry::Key(t) if RegPath::new(t) == path))
            {
                theirs.push(Entry::Key(k));
            }
            return;
        }
        Entry::OtherServer | Entry::Service { .. } => return,
        Entry::Added(k, n, w) => (k, n, None, w),
        Entry::Replaced(k, n, old, w) => (k, n, Some(old), w),
    };
    let Some(written) = written.or_else(|| expected(&key, &name)) else {
        return;
    };
    // Whether the value holds what the leaving class wrote.
    let holds = record(&key, &name, None, written.clone()).still_written(reg, |_, _| None);
    let Some(i) = theirs.iter().position(|e| e.is_value(&key, &name)) else {
        if holds {
            theirs.push(record(&key, &name, previous, written));
        }
        return;
    };
    let (their_previous, their_written) = match &theirs[i] {
        Entry::Added(_, _, w) => (None, w.clone()),
        Entry::Replaced(_, _, old, w) => (Some(old.clone()), w.clone()),
        Entry::Key(_) | Entry::OtherServer | Entry::Service { .. } => return,
    };
    let Some(their_written) = their_written else {
        return;
    };
    // A record of an earlier version that goes back only to what the leaving class wrote goes back
    // as far as the leaving class's.
    let before = if their_previous.as_ref() == Some(&written) {
        previous
    } else {
        their_previous
    };
    // The value holds what the leaving class wrote: the staying class counts it as its own.
    let now = if holds && !theirs[i].still_written(reg, |_, _| None) {
        written
    } else {
        their_written
    };
    theirs[i] = record(&key, &name, before, now);
}
