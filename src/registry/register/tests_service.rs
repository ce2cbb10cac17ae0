//! The Windows service of the EXE host's `/Service` in the ledger: registered with its classes, taken
//! back by unregistration only while it is still what registration wrote, another product's service
//! of that name refused or (taken over) given back, never deleted. The service manager is a stand-in
//! held in memory, with the errors the real one gives.

use std::cell::RefCell;
use std::collections::BTreeMap;

use super::ledger::{read_ledger, Entry};
use super::service::{
    recorded_service, register_service, unregister_service, NewService, ServiceManager, SERVICE_EXISTS,
};
use super::tests::{dump, memory, server};
use super::*;
use crate::com::{E_INVALIDARG, GUID, HRESULT};
use crate::registry::RegValue;

/// E_ACCESSDENIED: the service manager's answer to a caller without administrator rights.
const ACCESS_DENIED: HRESULT = 0x8007_0005_u32 as HRESULT;
/// HRESULT_FROM_WIN32(ERROR_SERVICE_MARKED_FOR_DELETE).
const MARKED_FOR_DELETE: HRESULT = 0x8007_0430_u32 as HRESULT;

const PROGRAM: &str = "C:\\Program Files\\Vendor\\server.exe";
const OTHER: &str = "\"C:\\Program Files\\Other\\other.exe\" -k";

/// The service manager, in memory: services by name (compared without case, as the service manager
/// compares them), what each call did, and an error to answer with.
#[derive(Default)]
struct Scm {
    services: RefCell<BTreeMap<String, NewService>>,
    calls: RefCell<Vec<String>>,
    /// Every call fails with this (a caller without administrator rights: E_ACCESSDENIED).
    refuse: Option<HRESULT>,
    /// `create` fails with this (a service of that name is marked for deletion).
    refuse_create: Option<HRESULT>,
}

impl Scm {
    fn with(name: &str, command_line: &str) -> Scm {
        let scm = Scm::default();
        scm.services.borrow_mut().insert(
            name.to_lowercase(),
            NewService {
                name: name.into(),
                display_name: "Another product".into(),
                command_line: command_line.into(),
                account: "LocalSystem".into(),
            },
        );
        scm
    }

    fn get(&self, name: &str) -> Option<NewService> {
        self.services.borrow().get(&name.to_lowercase()).cloned()
    }
}

impl ServiceManager for Scm {
    fn command_line(&self, name: &str) -> Result<Option<String>, HRESULT> {
        self.refuse.map_or(Ok(()), Err)?;
        Ok(self.get(name).map(|s| s.command_line))
    }
    fn create(&self, service: &NewService) -> Result<(), HRESULT> {
        self.refuse.or(self.refuse_create).map_or(Ok(()), Err)?;
        self.calls.borrow_mut().push(format!("create {}", service.name));
        let previous = self
            .services
            .borrow_mut()
            .insert(service.name.to_lowercase(), service.clone());
        assert!(previous.is_none(), "created over an existing service");
        Ok(())
    }
    fn set_command_line(&self, name: &str, command_line: &str) -> Result<(), HRESULT> {
        self.refuse.map_or(Ok(()), Err)?;
        self.calls.borrow_mut().push(format!("set {name} {command_line}"));
        let mut services = self.services.borrow_mut();
        let service = services.get_mut(&name.to_lowercase()).expect("no such service");
        service.command_line = command_line.into();
        Ok(())
    }
    fn delete(&self, name: &str) -> Result<(), HRESULT> {
        self.refuse.map_or(Ok(()), Err)?;
        self.calls.borrow_mut().push(format!("delete {name}"));
        self.services
            .borrow_mut()
            .remove(&name.to_lowercase())
            .expect("no such service");
        Ok(())
    }
}

/// An EXE server's class with an AppID (the program PROGRAM).
fn exe_class(n: u128) -> ServerDescription {
    let mut d = server(n);
    d.local = true;
    d.threading_model = None;
    d.module_path = Some(PROGRAM.into());
    d.app_id = Some(GUID::from_u128(0xA0));
    d
}

fn options(name: &str) -> ServiceOptions {
    ServiceOptions {
        name: name.into(),
        account: LOCAL_SERVICE.into(),
    }
}

fn app_key(d: &ServerDescription) -> String {
    format!("AppID\\{}", d.app_id.unwrap())
}

/// What `/Service`'s command line is for PROGRAM.
fn ours() -> String {
    format!("\"{PROGRAM}\" -RunService")
}

/// `/UnregServer` as the host does it: the service, then the classes in reverse order.
fn unregister_all(regs: &Registries, scm: &Scm, classes: &[ServerDescription]) -> Result<(), HRESULT> {
    unregister_service(regs, scm, classes)?;
    for d in classes.iter().rev() {
        unregister(regs, d)?;
    }
    Ok(())
}

#[test]
fn a_service_is_registered_with_its_classes_and_taken_back_whole() {
    let regs = memory();
    let before = dump(&regs);
    let scm = Scm::default();
    let classes = [exe_class(1), exe_class(2)];
    register_service(&regs, &scm, &classes, &options("VendorOpc"), false).unwrap();
    // The service: own program, its command line that of LocalServer32 with -RunService, the least
    // privileged account, the first class's description as its display name.
    let service = scm.get("vendoropc").expect("the service");
    assert_eq!(service.command_line, ours());
    assert_eq!(service.account, "NT AUTHORITY\\LocalService");
    assert_eq!(service.display_name, "Vendor Server 1");
    // The classes as /RegServer writes them, with LocalService naming the service.
    for d in &classes {
        assert_eq!(
            regs.write.value(&d.module_key(), ""),
            Some(RegValue::Sz(format!("\"{PROGRAM}\"")))
        );
        let recorded = read_ledger(&*regs.write, &d.module_key()).unwrap();
        assert!(recorded.contains(&Entry::Service {
            name: "VendorOpc".into(),
            written: ours(),
            previous: None
        }));
    }
    assert_eq!(
        regs.write.value(&app_key(&classes[0]), "LocalService"),
        Some(RegValue::Sz("VendorOpc".into()))
    );
    // Registering again changes nothing.
    let registered = dump(&regs);
    register_service(&regs, &scm, &classes, &options("VendorOpc"), false).unwrap();
    assert_eq!(dump(&regs), registered);
    assert_eq!(*scm.calls.borrow(), ["create VendorOpc"]);
    // Unregistration: the service is deleted and the registry is as it was.
    unregister_all(&regs, &scm, &classes).unwrap();
    assert!(scm.get("VendorOpc").is_none());
    assert_eq!(dump(&regs), before);
}

#[test]
fn another_products_service_of_that_name_is_refused_and_never_deleted() {
    let regs = memory();
    let before = dump(&regs);
    let scm = Scm::with("VendorOpc", OTHER);
    let classes = [exe_class(1)];
    assert_eq!(
        register_service(&regs, &scm, &classes, &options("vendoropc"), false),
        Err(SERVICE_EXISTS)
    );
    assert_eq!(dump(&regs), before, "nothing written");
    assert_eq!(scm.get("VendorOpc").unwrap().command_line, OTHER);
    assert!(scm.calls.borrow().is_empty());

    // Taken over: only its command line changes, and unregistration gives it back.
    register_service(&regs, &scm, &classes, &options("VendorOpc"), true).unwrap();
    let service = scm.get("VendorOpc").unwrap();
    assert_eq!(
        (service.command_line.as_str(), service.account.as_str()),
        (ours().as_str(), "LocalSystem")
    );
    let recorded = read_ledger(&*regs.write, &classes[0].module_key()).unwrap();
    assert!(recorded.contains(&Entry::Service {
        name: "VendorOpc".into(),
        written: ours(),
        previous: Some(OTHER.into())
    }));
    // Registering again (without taking over) keeps the record of what it replaced.
    register_service(&regs, &scm, &classes, &options("VendorOpc"), false).unwrap();
    unregister_all(&regs, &scm, &classes).unwrap();
    assert_eq!(scm.get("VendorOpc").unwrap().command_line, OTHER, "given back");
    assert!(!scm.calls.borrow().iter().any(|c| c.starts_with("delete")));
    assert_eq!(dump(&regs), before);
}

#[test]
fn a_service_pointed_at_another_program_since_stays() {
    let regs = memory();
    let before = dump(&regs);
    let scm = Scm::default();
    let classes = [exe_class(1)];
    register_service(&regs, &scm, &classes, &options("VendorOpc"), false).unwrap();
    // Another product (or an administrator) makes the service start its program.
    scm.set_command_line("VendorOpc", OTHER).unwrap();
    unregister_all(&regs, &scm, &classes).unwrap();
    assert_eq!(
        scm.get("VendorOpc").unwrap().command_line,
        OTHER,
        "theirs now: it stays"
    );
    assert_eq!(dump(&regs), before, "the classes' registration goes");
    // Registering again meets it as another product's.
    assert_eq!(
        register_service(&regs, &scm, &classes, &options("VendorOpc"), false),
        Err(SERVICE_EXISTS)
    );

    // A taken-over service pointed elsewhere again is not set back to stale data either.
    let regs = memory();
    let scm = Scm::with("VendorOpc", OTHER);
    register_service(&regs, &scm, &classes, &options("VendorOpc"), true).unwrap();
    scm.set_command_line("VendorOpc", "\"C:\\Other\\v2.exe\"").unwrap();
    unregister_all(&regs, &scm, &classes).unwrap();
    assert_eq!(scm.get("VendorOpc").unwrap().command_line, "\"C:\\Other\\v2.exe\"");
}

#[test]
fn without_the_service_managers_rights_nothing_is_written_or_removed() {
    let regs = memory();
    let before = dump(&regs);
    let scm = Scm {
        refuse: Some(ACCESS_DENIED),
        ..Scm::default()
    };
    let classes = [exe_class(1)];
    assert_eq!(
        register_service(&regs, &scm, &classes, &options("VendorOpc"), false),
        Err(ACCESS_DENIED)
    );
    assert_eq!(dump(&regs), before);
    // Registered by an administrator, unregistered without the rights: refused before anything goes.
    let scm = Scm::default();
    register_service(&regs, &scm, &classes, &options("VendorOpc"), false).unwrap();
    let registered = dump(&regs);
    let denied = Scm {
        refuse: Some(ACCESS_DENIED),
        services: RefCell::new(scm.services.borrow().clone()),
        ..Scm::default()
    };
    assert_eq!(unregister_all(&regs, &denied, &classes), Err(ACCESS_DENIED));
    assert_eq!(dump(&regs), registered);
    assert!(denied.get("VendorOpc").is_some());
    // The service manager's other errors come through as they are, and nothing stays written.
    let regs = memory();
    let scm = Scm {
        refuse_create: Some(MARKED_FOR_DELETE),
        ..Scm::default()
    };
    assert_eq!(
        register_service(&regs, &scm, &classes, &options("VendorOpc"), false),
        Err(MARKED_FOR_DELETE)
    );
    assert_eq!(dump(&regs), before);
}

#[test]
fn a_service_starting_this_program_without_a_record_is_taken_as_this_registrations() {
    let regs = memory();
    let before = dump(&regs);
    let scm = Scm::with("VendorOpc", &format!("{PROGRAM} -RunService")); // unquoted, by other means
    let classes = [exe_class(1)];
    register_service(&regs, &scm, &classes, &options("VendorOpc"), false).unwrap();
    assert_eq!(scm.get("VendorOpc").unwrap().command_line, ours());
    unregister_all(&regs, &scm, &classes).unwrap();
    assert!(scm.get("VendorOpc").is_none());
    assert_eq!(dump(&regs), before);
}

#[test]
fn the_exe_form_and_the_service_form_follow_each_other() {
    let regs = memory();
    let before = dump(&regs);
    let scm = Scm::default();
    let classes = [exe_class(1)];
    // /RegServer, then /Service: the service and LocalService are added to the EXE form's record.
    register(&regs, &classes[0]).unwrap();
    let exe_form = dump(&regs);
    register_service(&regs, &scm, &classes, &options("VendorOpc"), false).unwrap();
    assert!(scm.get("VendorOpc").is_some());
    // /RegServer again, as the host does it: the service form is taken back, the EXE form written.
    assert!(unregister_service(&regs, &scm, &classes).unwrap());
    unregister(&regs, &classes[0]).unwrap();
    register(&regs, &classes[0]).unwrap();
    assert!(scm.get("VendorOpc").is_none());
    assert_eq!(dump(&regs), exe_form);
    assert_eq!(recorded_service(&*regs.write, &classes), None);
    // /UnregServer of the EXE form asks nothing of the service manager.
    let refusing = Scm {
        refuse: Some(ACCESS_DENIED),
        ..Scm::default()
    };
    assert!(!unregister_service(&regs, &refusing, &classes).unwrap());
    unregister(&regs, &classes[0]).unwrap();
    assert_eq!(dump(&regs), before);
}

#[test]
fn a_renamed_service_replaces_the_one_recorded() {
    let regs = memory();
    let before = dump(&regs);
    let scm = Scm::default();
    let classes = [exe_class(1)];
    register_service(&regs, &scm, &classes, &options("VendorOpc"), false).unwrap();
    register_service(&regs, &scm, &classes, &options("VendorOpc2"), false).unwrap();
    assert!(scm.get("VendorOpc").is_none());
    assert_eq!(
        regs.write.value(&app_key(&classes[0]), "LocalService"),
        Some(RegValue::Sz("VendorOpc2".into()))
    );
    unregister_all(&regs, &scm, &classes).unwrap();
    assert!(scm.services.borrow().is_empty());
    assert_eq!(dump(&regs), before);
}

#[test]
fn what_cannot_be_one_service_is_refused_before_anything_is_written() {
    let regs = memory();
    let before = dump(&regs);
    let scm = Scm::default();
    let no_app_id = ServerDescription {
        app_id: None,
        ..exe_class(1)
    };
    let in_process = ServerDescription {
        local: false,
        ..exe_class(2)
    };
    let other_program = ServerDescription {
        module_path: Some("C:\\Vendor\\other.exe".into()),
        ..exe_class(3)
    };
    let named_otherwise = ServerDescription {
        local_service: Some("Else".into()),
        ..exe_class(4)
    };
    let cases: [(&[ServerDescription], ServiceOptions); 8] = [
        (&[], options("VendorOpc")),
        (&[no_app_id], options("VendorOpc")),
        (&[in_process], options("VendorOpc")),
        (&[exe_class(1), other_program], options("VendorOpc")),
        (&[named_otherwise], options("VendorOpc")),
        (&[exe_class(1)], options("Vendor\\Opc")),
        (&[exe_class(1)], options(&"x".repeat(257))),
        (
            &[exe_class(1)],
            ServiceOptions {
                name: "VendorOpc".into(),
                account: ".\\operator".into(),
            },
        ),
    ];
    for (classes, service) in cases {
        assert_eq!(
            register_service(&regs, &scm, classes, &service, false),
            Err(E_INVALIDARG),
            "{service:?}"
        );
    }
    assert_eq!(dump(&regs), before);
    assert!(scm.calls.borrow().is_empty());
    // The longest name and the other built-in accounts are taken.
    for account in ["NT AUTHORITY\\NetworkService", "localsystem"] {
        let service = ServiceOptions {
            name: "v".repeat(256),
            account: account.into(),
        };
        register_service(&regs, &scm, &[exe_class(1)], &service, false).unwrap();
        unregister_all(&regs, &scm, &[exe_class(1)]).unwrap();
    }
    assert_eq!(dump(&regs), before);
}

#[test]
fn service_records_survive_awkward_names_and_paths() {
    for entry in [
        Entry::Service {
            name: "Vendor|Opc;100%".into(),
            written: "\"C:\\a;b|c\\s.exe\" -RunService".into(),
            previous: None,
        },
        Entry::Service {
            name: "x".into(),
            written: "\"C:\\s.exe\" -RunService".into(),
            previous: Some("C:\\Old Path\\%25.exe -k".into()),
        },
    ] {
        assert_eq!(Entry::decode(&entry.encode()), Some(entry.clone()));
    }
}
