//! A server registered as a Windows service: what the EXE host's `/Service` writes besides the classes'
//! registrations, and how `/UnregServer` (and `/RegServer`, which goes back to the EXE form) takes it
//! back.
//!
//! `/Service` writes every class's registration as `/RegServer` does, with the AppID's `LocalService`
//! naming the service (COM then starts the server through the service manager rather than by its
//! `LocalServer32`, which stays), and creates the service: its own process, started on demand, under
//! the account given (`NT AUTHORITY\LocalService` unless the server says otherwise), with the command
//! line of the classes' `LocalServer32` and [`RUN_SERVICE`] added. Every class's ledger records it
//! ([`Entry::Service`]), and the rules of values hold for it:
//!
//! - The service manager is asked first, before anything is written: without the rights to create
//!   services (an administrator's) registration fails with the service manager's error as an HRESULT
//!   (E_ACCESSDENIED) and writes nothing.
//! - A service of that name that starts another program is another product's: `/Service` refuses it
//!   (HRESULT_FROM_WIN32(ERROR_SERVICE_EXISTS)) and writes nothing, unless told to take it over; a
//!   take-over changes only its command line and records the one it had, which unregistration gives
//!   back. Such a service is never deleted.
//! - A service of that name that starts this program but is recorded by no class (written by other
//!   means) is taken as this registration's, as a value holding what registration would write is.
//! - Unregistration takes the service back only while it still starts the program registration wrote:
//!   deletes the service it created (stopping it first), gives a service it took over its command line
//!   back. A service someone pointed at another program since is theirs and stays.
//! - Registering again changes only the command line of the service (a program moved); its account,
//!   start type and display name stay as they are, an administrator's choice included.

#![cfg_attr(not(windows), allow(dead_code))] // the EXE host (Windows) registers services; the tests everywhere

use super::algorithm::{register, unregister};
use super::description::ServerDescription;
use super::ledger::{read_ledger, write_ledger, Entry};
use crate::com::{E_INVALIDARG, HRESULT};
use crate::registry::cmdline::{command_line_of, program_path};
use crate::registry::{Registries, Registry};

/// The switch the service's command line carries: the program was started by the service manager and
/// runs as the service (`StartServiceCtrlDispatcherW`).
pub(crate) const RUN_SERVICE: &str = "-RunService";

/// The account a service runs as unless the server names another: the least-privileged built-in
/// account (no administrator rights, the network as an anonymous user).
pub(crate) const LOCAL_SERVICE: &str = "NT AUTHORITY\\LocalService";

/// The accounts a server may name for its service: the built-in ones, which need no password.
pub(crate) const SERVICE_ACCOUNTS: [&str; 3] = [LOCAL_SERVICE, "NT AUTHORITY\\NetworkService", "LocalSystem"];

/// The longest service name the service manager takes, in UTF-16 code units.
pub(crate) const MAX_SERVICE_NAME: usize = 256;

/// HRESULT_FROM_WIN32(ERROR_SERVICE_EXISTS): a service of that name is another product's.
pub(crate) const SERVICE_EXISTS: HRESULT = 0x8007_0431_u32 as HRESULT;

/// A service the server asks for (the EXE host's options).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct ServiceOptions {
    /// The service's name (checked: [`valid_service_name`]).
    pub(crate) name: String,
    /// The account it runs as: one of [`SERVICE_ACCOUNTS`].
    pub(crate) account: String,
}

/// Whether the service manager takes `name`: 1 to 256 characters, no `/` or `\`.
pub(crate) fn valid_service_name(name: &str) -> bool {
    let units = name.encode_utf16().count();
    (1..=MAX_SERVICE_NAME).contains(&units) && !name.contains(['/', '\\']) && !name.trim().is_empty()
}

/// A service to create.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct NewService {
    pub(crate) name: String,
    pub(crate) display_name: String,
    pub(crate) command_line: String,
    pub(crate) account: String,
}

/// What registration asks of the service manager. Each call is a failure with the service manager's
/// error as an HRESULT (HRESULT_FROM_WIN32) when it fails.
pub(crate) trait ServiceManager {
    /// The command line of the service `name` (its `ImagePath`), `None` when there is no such service.
    fn command_line(&self, name: &str) -> Result<Option<String>, HRESULT>;
    /// Creates a service: its own process, started on demand.
    fn create(&self, service: &NewService) -> Result<(), HRESULT>;
    /// Sets the command line of the service `name`, nothing else.
    fn set_command_line(&self, name: &str, command_line: &str) -> Result<(), HRESULT>;
    /// Stops the service `name` when it runs (waiting a bounded time for it), then deletes it.
    fn delete(&self, name: &str) -> Result<(), HRESULT>;
}

/// What the ledgers record of the service: its name, the command line registration set, and the one a
/// taken-over service had before (`None`: registration created the service).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct ServiceRecord {
    pub(crate) name: String,
    pub(crate) written: String,
    pub(crate) previous: Option<String>,
}

impl ServiceRecord {
    fn entry(&self) -> Entry {
        Entry::Service {
            name: self.name.clone(),
            written: self.written.clone(),
            previous: self.previous.clone(),
        }
    }
}

/// Whether the command line `current` starts the program of `ours` (a command line registration
/// writes: the path in quotes). `current` may be unquoted (written by other means): its text up to a
/// blank after the path then counts.
fn same_program(current: &str, ours: &str) -> bool {
    let program = program_path(ours);
    let current = current.trim();
    if current.starts_with('"') {
        return program_path(current).eq_ignore_ascii_case(program);
    }
    current.len() >= program.len()
        && current.is_char_boundary(program.len())
        && current[..program.len()].eq_ignore_ascii_case(program)
        && current[program.len()..]
            .chars()
            .next()
            .is_none_or(|c| c == ' ' || c == '\t')
}

/// The service recorded in the ledgers of `descriptions`' classes (the first found), if any.
pub(crate) fn recorded_service(reg: &dyn Registry, descriptions: &[ServerDescription]) -> Option<ServiceRecord> {
    descriptions.iter().find_map(|d| {
        read_ledger(reg, &d.module_key())?.into_iter().find_map(|e| match e {
            Entry::Service {
                name,
                written,
                previous,
            } => Some(ServiceRecord {
                name,
                written,
                previous,
            }),
            _ => None,
        })
    })
}

/// The command line of the service that serves `descriptions`, after checking that they can be one
/// service: at least one class, every class an EXE server with an AppID (whose `LocalService` will
/// name the service: one the description gives must be this one), all of one program.
fn service_command_line(descriptions: &[ServerDescription], name: &str) -> Result<String, HRESULT> {
    let first = descriptions.first().ok_or(E_INVALIDARG)?;
    let program = command_line_of(&first.module_path()?);
    for d in descriptions {
        let named_otherwise = d
            .local_service
            .as_deref()
            .is_some_and(|s| !s.eq_ignore_ascii_case(name));
        if !d.local || d.app_id.is_none() || named_otherwise {
            return Err(E_INVALIDARG);
        }
        if !same_program(&command_line_of(&d.module_path()?), &program) {
            return Err(E_INVALIDARG);
        }
    }
    Ok(format!("{program} {RUN_SERVICE}"))
}

/// Registers the classes `descriptions` as served by the Windows service `service` (the EXE host's
/// `/Service`; see the module documentation). `take_over`: a service of that name that starts another
/// program is taken over rather than refused.
pub(crate) fn register_service(
    regs: &Registries,
    scm: &dyn ServiceManager,
    descriptions: &[ServerDescription],
    service: &ServiceOptions,
    take_over: bool,
) -> Result<(), HRESULT> {
    if !valid_service_name(&service.name)
        || !SERVICE_ACCOUNTS
            .iter()
            .any(|a| a.eq_ignore_ascii_case(&service.account))
    {
        return Err(E_INVALIDARG);
    }
    for d in descriptions {
        d.check()?;
    }
    let command_line = service_command_line(descriptions, &service.name)?;
    let reg = &*regs.write;
    let recorded = recorded_service(reg, descriptions);
    let name = &service.name;
    // The service manager first: without its rights, or with a service of that name that is another
    // product's, nothing is written.
    let current = scm.command_line(name)?;
    let previous = match &current {
        None => None,
        Some(theirs) if same_program(theirs, &command_line) => recorded
            .as_ref()
            .filter(|r| r.name.eq_ignore_ascii_case(name))
            .and_then(|r| r.previous.clone()),
        Some(theirs) if take_over => Some(theirs.clone()),
        Some(_) => return Err(SERVICE_EXISTS),
    };
    match &current {
        None => scm.create(&NewService {
            name: name.clone(),
            display_name: descriptions[0].user_type.clone(),
            command_line: command_line.clone(),
            account: service.account.clone(),
        })?,
        Some(theirs) if *theirs != command_line => scm.set_command_line(name, &command_line)?,
        Some(_) => {}
    }
    // Undoes the service manager's part when the classes cannot be registered.
    let undo = || {
        let _ = match &current {
            None => scm.delete(name),
            Some(theirs) if *theirs != command_line => scm.set_command_line(name, theirs),
            Some(_) => Ok(()),
        };
    };
    let as_service: Vec<ServerDescription> = descriptions
        .iter()
        .map(|d| ServerDescription {
            local_service: Some(name.clone()),
            ..d.clone()
        })
        .collect();
    for (i, d) in as_service.iter().enumerate() {
        if let Err(hr) = register(regs, d) {
            for done in as_service[..i].iter().rev() {
                let _ = unregister(regs, done);
            }
            undo();
            return Err(hr);
        }
    }
    // A service recorded under another name (the server renamed its service) goes as unregistration
    // would take it.
    if let Some(old) = recorded.filter(|r| !r.name.eq_ignore_ascii_case(name)) {
        take_back(scm, &old)?;
    }
    let record = ServiceRecord {
        name: name.clone(),
        written: command_line,
        previous,
    };
    for d in &as_service {
        let key = d.module_key();
        let mut ledger = read_ledger(reg, &key).unwrap_or_default();
        ledger.retain(|e| !matches!(e, Entry::Service { .. }));
        ledger.push(record.entry());
        write_ledger(reg, &key, &ledger)?;
    }
    Ok(())
}

/// Takes back the service a registration recorded: deleted (stopped first) when registration created
/// it, given its previous command line when registration took it over; left alone when it no longer
/// starts the program registration wrote, or is gone.
fn take_back(scm: &dyn ServiceManager, record: &ServiceRecord) -> Result<(), HRESULT> {
    match scm.command_line(&record.name)? {
        Some(current) if same_program(&current, &record.written) => match &record.previous {
            None => scm.delete(&record.name),
            Some(previous) => scm.set_command_line(&record.name, previous),
        },
        _ => Ok(()),
    }
}

/// For unregistering `descriptions`: takes back the service their ledgers record, if any (the classes'
/// own registrations are unregistered after, by the caller). Fails, before the classes are touched,
/// when the service manager refuses (without administrator rights: E_ACCESSDENIED). Returns whether a
/// service was recorded.
pub(crate) fn unregister_service(
    regs: &Registries,
    scm: &dyn ServiceManager,
    descriptions: &[ServerDescription],
) -> Result<bool, HRESULT> {
    match recorded_service(&*regs.write, descriptions) {
        Some(record) => take_back(scm, &record).map(|()| true),
        None => Ok(false),
    }
}
