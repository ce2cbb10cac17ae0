//! The server list's rules, checked against an in-memory registry.

use std::sync::{Arc, Mutex};

use super::*;
use crate::com::{LPWSTR, S_FALSE};
use crate::registry::categories::{CATID_OPCAEServer10, CATID_OPCDAServer10, CATID_OPCDAServer20, CATID_OPCDAServer30};
use crate::registry::memory::MemoryRegistry;
use crate::registry::regfile;
use crate::registry::Registry;

/// The classes read from the registry now, checked against what the cache answers (kept scan or
/// new one) at the same moment.
fn classes_of_categories(regs: &Registries, implemented: Option<&[CATID]>, required: Option<&[CATID]>) -> Vec<CLSID> {
    let now = super::classes_of_categories(regs, implemented, required);
    assert_eq!(
        current_scan(regs).classes_of_categories(regs, implemented, required),
        now
    );
    now
}

/// GetClassDetails's answer read from the registry now, checked against the cache's likewise.
fn class_details(regs: &Registries, clsid: &CLSID, version_independent: bool) -> Result<ClassDetails, HRESULT> {
    let now = super::class_details(regs, clsid, version_independent);
    let cached = current_scan(regs).class_details(regs, clsid).map(|mut d| {
        if !version_independent {
            d.version_independent_prog_id.clear();
        }
        d
    });
    assert_eq!(cached, now);
    now
}

fn g(n: u128) -> GUID {
    GUID::from_u128(0xC0000000_0000_0000_0000_000000000000 + n)
}

/// A registry with: class 1 (DA 2.0), class 2 (DA 2.0 + DA 3.0, requiring AE), class 3 (AE only, no
/// ProgID), class 4 (DA 1.0 the old way only), class 5 (DA 3.0, requires AE and DA 2.0), and a ProgID
/// with an OPC key whose class is not registered.
fn sample() -> Registries {
    let reg = MemoryRegistry::new();
    let class = |n: u128, impls: &[GUID], reqs: &[GUID], prog: Option<&str>| {
        let key = format!("CLSID\\{}", g(n));
        reg.set_value(&key, "", &crate::registry::RegValue::Sz(format!("Server {n}")))
            .unwrap();
        for c in impls {
            reg.create_key(&format!("{key}\\Implemented Categories\\{c}")).unwrap();
        }
        for c in reqs {
            reg.create_key(&format!("{key}\\Required Categories\\{c}")).unwrap();
        }
        if let Some(p) = prog {
            let text = format!(
                "REGEDIT4\n[HKCR\\{key}\\ProgID]\n@=\"{p}\"\n[HKCR\\{p}\\CLSID]\n@=\"{}\"\n",
                g(n)
            );
            regfile::apply(&reg, &text).unwrap();
        }
    };
    class(1, &[CATID_OPCDAServer20], &[], Some("V.One.1"));
    class(
        2,
        &[CATID_OPCDAServer20, CATID_OPCDAServer30],
        &[CATID_OPCAEServer10],
        Some("V.Two.1"),
    );
    class(3, &[CATID_OPCAEServer10], &[], None);
    class(4, &[], &[], Some("V.Old.1"));
    reg.create_key("V.Old.1\\OPC\\Vendor").unwrap();
    class(
        5,
        &[CATID_OPCDAServer30],
        &[CATID_OPCAEServer10, CATID_OPCDAServer20],
        Some("V.Five.1"),
    );
    regfile::apply(&reg, "REGEDIT4\n[HKCR\\V.Ghost.1\\OPC]\n[HKCR\\V.Ghost.1\\CLSID]\n@=\"{C0000000-0000-0000-0000-0000000000FF}\"\n[HKCR\\CLSID\\not-a-guid\\Implemented Categories\\{63D5F432-CFE4-11d1-B2C8-0060083BA1FB}]\n").unwrap();
    Registries::memory(Arc::new(reg))
}

fn ids(list: &[u128]) -> Vec<GUID> {
    list.iter().map(|&n| g(n)).collect()
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn zero_means_any_category() {
    let regs = sample();
    assert_eq!(classes_of_categories(&regs, None, None), ids(&[1, 2, 3, 4, 5]));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn a_class_qualifies_by_any_implemented_category() {
    let regs = sample();
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer20]), None),
        ids(&[1, 2])
    );
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer30, CATID_OPCAEServer10]), None),
        ids(&[2, 3, 5])
    );
    // Listing a category twice, or a class matching twice, reports it once.
    assert_eq!(
        classes_of_categories(
            &regs,
            Some(&[CATID_OPCDAServer20, CATID_OPCDAServer30, CATID_OPCDAServer20]),
            None
        ),
        ids(&[1, 2, 5])
    );
    assert_eq!(classes_of_categories(&regs, Some(&[g(0x99)]), None), ids(&[]));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn required_categories_are_the_ones_the_caller_supports() {
    let regs = sample();
    // Supporting A&E: every class that requires nothing (1, 3, 4) and class 2 (requires A&E); not 5,
    // which also requires DA 2.0.
    assert_eq!(
        classes_of_categories(&regs, None, Some(&[CATID_OPCAEServer10])),
        ids(&[1, 2, 3, 4])
    );
    // Supporting both of class 5's requirements admits it too.
    assert_eq!(
        classes_of_categories(&regs, None, Some(&[CATID_OPCAEServer10, CATID_OPCDAServer20])),
        ids(&[1, 2, 3, 4, 5])
    );
    // A list that matches no requirement leaves exactly the classes requiring nothing.
    assert_eq!(classes_of_categories(&regs, None, Some(&[g(0x99)])), ids(&[1, 3, 4]));
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer20]), Some(&[CATID_OPCAEServer10])),
        ids(&[1, 2])
    );
    // What OPC clients call: DA 2.0 servers, supporting DA 2.0. Class 2 requires A&E, which the
    // caller does not support.
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer20]), Some(&[CATID_OPCDAServer20])),
        ids(&[1])
    );
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer30]), Some(&[CATID_OPCDAServer20])),
        ids(&[])
    );
    // Names under Required Categories that are not CATIDs are no requirement.
    regs.write
        .create_key(&format!("CLSID\\{}\\Required Categories\\not-a-catid", g(1)))
        .unwrap();
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer20]), Some(&[CATID_OPCDAServer20])),
        ids(&[1])
    );
    // An empty Required Categories key requires nothing.
    regs.write
        .create_key(&format!("CLSID\\{}\\Required Categories", g(3)))
        .unwrap();
    assert_eq!(classes_of_categories(&regs, None, Some(&[g(0x99)])), ids(&[1, 3, 4]));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn data_access_1_servers_registered_the_old_way_meet_required_categories_too() {
    let regs = sample();
    regs.write
        .create_key(&format!("CLSID\\{}\\Required Categories\\{CATID_OPCAEServer10}", g(4)))
        .unwrap();
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer10]), Some(&[CATID_OPCDAServer20])),
        ids(&[])
    );
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer10]), Some(&[CATID_OPCAEServer10])),
        ids(&[4])
    );
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer10]), None),
        ids(&[4])
    );
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn data_access_1_servers_registered_the_old_way_are_found() {
    let regs = sample();
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer10]), None),
        ids(&[4])
    );
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer10, CATID_OPCDAServer20]), None),
        ids(&[1, 2, 4])
    );
    // A class implementing the DA 1.0 category and registered the old way is reported once.
    regs.write
        .create_key(&format!(
            "CLSID\\{}\\Implemented Categories\\{CATID_OPCDAServer10}",
            g(4)
        ))
        .unwrap();
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer10]), None),
        ids(&[4])
    );
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn every_view_is_read_and_each_class_reported_once() {
    let regs = sample();
    let other = MemoryRegistry::new();
    other
        .create_key(&format!(
            "CLSID\\{}\\Implemented Categories\\{CATID_OPCDAServer20}",
            g(7)
        ))
        .unwrap();
    other
        .create_key(&format!(
            "CLSID\\{}\\Implemented Categories\\{CATID_OPCDAServer20}",
            g(1)
        ))
        .unwrap();
    other
        .set_value(
            &format!("CLSID\\{}\\ProgID", g(7)),
            "",
            &crate::registry::RegValue::Sz("W.Seven.1".into()),
        )
        .unwrap();
    let regs = Registries::new(
        regs.write.clone(),
        vec![regs.write.clone(), Arc::new(other)],
        Box::new(crate::registry::watch::tests::TestWatch::default()),
    );
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCDAServer20]), None),
        ids(&[1, 2, 7])
    );
    assert_eq!(class_details(&regs, &g(7), true).unwrap().prog_id, "W.Seven.1");
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn details_come_from_the_class_key() {
    let regs = sample();
    assert_eq!(
        class_details(&regs, &g(1), true),
        Ok(ClassDetails {
            prog_id: "V.One.1".into(),
            user_type: "Server 1".into(),
            version_independent_prog_id: String::new(),
        })
    );
    regfile::apply(
        &*regs.write,
        &format!(
            "REGEDIT4\n[HKCR\\CLSID\\{}\\VersionIndependentProgID]\n@=\"V.One\"\n",
            g(1)
        ),
    )
    .unwrap();
    assert_eq!(
        class_details(&regs, &g(1), true).unwrap().version_independent_prog_id,
        "V.One"
    );
    assert_eq!(class_details(&regs, &g(0x99), true), Err(REGDB_E_CLASSNOTREG));
    assert_eq!(class_details(&regs, &g(3), true), Err(REGDB_E_KEYMISSING));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn prog_ids_map_to_their_clsid() {
    let regs = sample();
    assert_eq!(clsid_from_prog_id(&regs, "V.Two.1"), Ok(g(2)));
    assert_eq!(clsid_from_prog_id(&regs, "v.two.1"), Ok(g(2)));
    assert_eq!(clsid_from_prog_id(&regs, "V.Nope.1"), Err(REGDB_E_CLASSNOTREG));
    assert_eq!(clsid_from_prog_id(&regs, ""), Err(CO_E_CLASSSTRING));
    assert_eq!(clsid_from_prog_id(&regs, "CLSID\\x"), Err(CO_E_CLASSSTRING));
    regfile::apply(&*regs.write, "REGEDIT4\n[HKCR\\V.Bad.1\\CLSID]\n@=\"garbage\"\n").unwrap();
    assert_eq!(clsid_from_prog_id(&regs, "V.Bad.1"), Err(CO_E_CLASSSTRING));
}

#[test]
#[cfg_attr(
    miri,
    ignore = "safe code only (no unsafe on its path), long under Miri: the native run checks it"
)]
fn enumeration_and_registration_may_run_on_several_threads() {
    let regs = Arc::new(sample());
    let workers: Vec<_> = (0..4u128)
        .map(|t| {
            let regs = regs.clone();
            std::thread::spawn(move || {
                for i in 0..20u128 {
                    let mut d = crate::registry::register::tests::server(0x1000 + t * 100 + i);
                    d.implemented = vec![(CATID_OPCAEServer10, None)];
                    crate::registry::register::register(&regs, &d).unwrap();
                    // (Other threads register meanwhile: the kept scan and a read of the registry
                    // may differ by their classes, never by this thread's, registered before.)
                    let ae = Some(&[CATID_OPCAEServer10][..]);
                    let found = super::classes_of_categories(&regs, ae, None);
                    assert!(found.contains(&d.clsid) && found.contains(&g(3)));
                    let found = current_scan(&regs).classes_of_categories(&regs, ae, None);
                    assert!(found.contains(&d.clsid) && found.contains(&g(3)));
                    assert_eq!(super::class_details(&regs, &d.clsid, true).unwrap().prog_id, d.prog_id);
                    let cached = current_scan(&regs).class_details(&regs, &d.clsid);
                    assert_eq!(cached.unwrap().prog_id, d.prog_id);
                    crate::registry::register::unregister(&regs, &d).unwrap();
                }
            })
        })
        .collect();
    for w in workers {
        w.join().unwrap();
    }
    assert_eq!(
        classes_of_categories(&regs, Some(&[CATID_OPCAEServer10]), None),
        ids(&[3])
    );
}

fn read_and_free(p: LPWSTR) -> String {
    // SAFETY: `p` is a NUL-terminated string the library allocated; freed once here.
    unsafe {
        let s = String::from_utf16(crate::com::wstr::wstr_units(p, usize::MAX).unwrap()).unwrap();
        task_free(p.cast());
        s
    }
}

/// The server list object over an in-memory registry, through its vtables as a C client uses it:
/// EnumClassesOfCategories and the IOPCEnumGUID it returns (Next, Skip, Reset, Clone), GetClassDetails,
/// CLSIDFromProgID, and failures that leave every out-parameter NULL.
#[test]
fn the_com_object_answers_through_its_vtables() {
    let handle = OpcRegistry {
        inner: Arc::new(sample()),
    };
    let mut p: *mut c_void = ptr::null_mut();
    // SAFETY: the object and the enumerators are used while alive and released once; every pointer
    // passed is valid for what the method writes.
    unsafe {
        assert_eq!(
            OpcServerListCreateOver(&handle, ptr::null_mut(), &IID_IOPCServerList2, &mut p),
            S_OK
        );
        let list = p.cast::<IOPCServerList2>();
        let vt = &*(*list).lpVtbl;
        let mut cats = [CATID_OPCDAServer20];
        let mut e: *mut IOPCEnumGUID = ptr::null_mut();
        assert_eq!(
            (vt.EnumClassesOfCategories)(list, 1, cats.as_mut_ptr(), 0, ptr::null_mut(), &mut e),
            S_OK
        );
        let ev = &*(*e).lpVtbl;
        let mut got = [GUID::default(); 3];
        let mut n = 7;
        assert_eq!((ev.Next)(e, 3, got.as_mut_ptr(), &mut n), S_FALSE);
        assert_eq!((n, &got[..2]), (2, &ids(&[1, 2])[..]));
        assert_eq!((ev.Reset)(e), S_OK);
        assert_eq!((ev.Skip)(e, 1), S_OK);
        let mut c: *mut IOPCEnumGUID = ptr::null_mut();
        assert_eq!((ev.Clone)(e, &mut c), S_OK);
        assert_eq!((ev.Release)(e), 0);
        assert_eq!(((*(*c).lpVtbl).Next)(c, 1, got.as_mut_ptr(), ptr::null_mut()), S_OK);
        assert_eq!(got[0], g(2));
        assert_eq!(((*(*c).lpVtbl).Next)(c, 1, got.as_mut_ptr(), &mut n), S_FALSE);
        assert_eq!(n, 0);
        assert_eq!(((*(*c).lpVtbl).Release)(c), 0);

        let (mut prog, mut user, mut vi) = (ptr::null_mut(), ptr::null_mut(), ptr::null_mut());
        assert_eq!((vt.GetClassDetails)(list, &g(1), &mut prog, &mut user, &mut vi), S_OK);
        assert_eq!(
            (read_and_free(prog), read_and_free(user), read_and_free(vi)),
            ("V.One.1".into(), "Server 1".into(), String::new())
        );
        let garbage = ptr::null_mut::<u16>().wrapping_byte_add(8);
        let (mut prog, mut user, mut vi) = (garbage, garbage, garbage);
        assert_eq!(
            (vt.GetClassDetails)(list, &g(0x99), &mut prog, &mut user, &mut vi),
            REGDB_E_CLASSNOTREG
        );
        assert!(prog.is_null() && user.is_null() && vi.is_null());

        let name: Vec<u16> = "v.two.1".encode_utf16().chain([0]).collect();
        let mut clsid = GUID::default();
        assert_eq!((vt.CLSIDFromProgID)(list, name.as_ptr(), &mut clsid), S_OK);
        assert_eq!(clsid, g(2));
        assert_eq!((vt.Release)(list), 0);
    }
}

/// A change of the registry, made once.
type Change = Box<dyn FnOnce(&MemoryRegistry) + Send>;

/// A registry that runs `during` once, right after the server list's scan of `CLSID` has read it: a
/// change while a scan runs.
struct ChangingDuringScan {
    inner: Arc<MemoryRegistry>,
    during: Mutex<Option<Change>>,
}

impl Registry for ChangingDuringScan {
    fn key_exists(&self, path: &str) -> bool {
        self.inner.key_exists(path)
    }
    fn subkeys(&self, path: &str) -> Vec<String> {
        self.inner.subkeys(path)
    }
    fn values(&self, path: &str) -> Vec<(String, crate::registry::RegValue)> {
        self.inner.values(path)
    }
    fn value(&self, path: &str, name: &str) -> Option<crate::registry::RegValue> {
        self.inner.value(path, name)
    }
    fn create_key(&self, path: &str) -> Result<(), HRESULT> {
        self.inner.create_key(path)
    }
    fn set_value(&self, path: &str, name: &str, value: &crate::registry::RegValue) -> Result<(), HRESULT> {
        self.inner.set_value(path, name, value)
    }
    fn delete_value(&self, path: &str, name: &str) -> Result<(), HRESULT> {
        self.inner.delete_value(path, name)
    }
    fn delete_key(&self, path: &str) -> Result<(), HRESULT> {
        self.inner.delete_key(path)
    }
    fn scan(&self, parent: &str, children: &[&str]) -> Vec<(String, Vec<Option<Vec<String>>>)> {
        let found = self.inner.scan(parent, children);
        if let Some(change) = self.during.lock().unwrap().take() {
            change(&self.inner);
        }
        found
    }
}

fn da2_class(n: u128) -> String {
    format!("CLSID\\{}\\Implemented Categories\\{CATID_OPCDAServer20}", g(n))
}

/// The cache over an in-memory registry and its own change watch: a class registered a moment
/// before a call is in its answer, one removed is gone, and between changes the kept scan answers.
#[test]
fn the_kept_scan_is_never_stale() {
    let regs = sample();
    let da2 = Some(&[CATID_OPCDAServer20][..]);
    let first = current_scan(&regs);
    assert_eq!(first.classes_of_categories(&regs, da2, None), ids(&[1, 2]));
    assert!(
        Arc::ptr_eq(&first, &current_scan(&regs)),
        "nothing changed: the kept scan"
    );
    regs.write.create_key(&da2_class(9)).unwrap();
    assert_eq!(
        current_scan(&regs).classes_of_categories(&regs, da2, None),
        ids(&[1, 2, 9])
    );
    assert_eq!(
        current_scan(&regs).class_details(&regs, &g(9)),
        Err(REGDB_E_KEYMISSING),
        "registered, without a ProgID"
    );
    regs.write
        .set_value(&format!("CLSID\\{}\\ProgID", g(9)), "", &"V.Nine.1".into())
        .unwrap();
    assert_eq!(
        current_scan(&regs).class_details(&regs, &g(9)).unwrap().prog_id,
        "V.Nine.1"
    );
    // A change of a detail alone (the ProgID) is seen too.
    regs.write
        .set_value(&format!("CLSID\\{}\\ProgID", g(9)), "", &"V.Nine.2".into())
        .unwrap();
    assert_eq!(
        current_scan(&regs).class_details(&regs, &g(9)).unwrap().prog_id,
        "V.Nine.2"
    );
    regs.write.delete_key(&da2_class(9)).unwrap();
    assert_eq!(
        current_scan(&regs).classes_of_categories(&regs, da2, None),
        ids(&[1, 2])
    );
    // Data Access 1.0 servers registered the old way, read on first need, are seen coming too.
    let da1 = Some(&[CATID_OPCDAServer10][..]);
    assert_eq!(current_scan(&regs).classes_of_categories(&regs, da1, None), ids(&[4]));
    regfile::apply(
        &*regs.write,
        &format!(
            "REGEDIT4\n[HKCR\\V.Old2.1\\OPC]\n[HKCR\\V.Old2.1\\CLSID]\n@=\"{}\"\n",
            g(1)
        ),
    )
    .unwrap();
    assert_eq!(
        current_scan(&regs).classes_of_categories(&regs, da1, None),
        ids(&[1, 4])
    );
}

/// A class registered while a scan runs, after the scan read `CLSID`: that scan misses it, the next
/// call does not (the watch was armed before the scan).
#[test]
fn a_class_registered_during_a_scan_is_in_the_next_answer() {
    let inner = Arc::new(MemoryRegistry::new());
    inner.create_key(&da2_class(1)).unwrap();
    let reg = Arc::new(ChangingDuringScan {
        inner: inner.clone(),
        during: Mutex::new(Some(Box::new(|r: &MemoryRegistry| {
            r.create_key(&da2_class(2)).unwrap()
        }))),
    });
    let regs = Registries::new(
        reg.clone(),
        vec![reg],
        Box::new(crate::registry::memory::MemoryWatch::new(inner)),
    );
    let da2 = Some(&[CATID_OPCDAServer20][..]);
    assert_eq!(current_scan(&regs).classes_of_categories(&regs, da2, None), ids(&[1]));
    assert_eq!(
        current_scan(&regs).classes_of_categories(&regs, da2, None),
        ids(&[1, 2])
    );
}

/// A watch that cannot be armed: every call reads the registry, and answers.
#[test]
fn without_a_watch_every_call_reads_the_registry() {
    let reg = Arc::new(MemoryRegistry::new());
    let watch = Arc::new(crate::registry::watch::tests::TestWatch::default());
    watch.fail.store(true, std::sync::atomic::Ordering::SeqCst);
    let regs = Registries::new(reg.clone(), vec![reg.clone()], Box::new(watch.clone()));
    let da2 = Some(&[CATID_OPCDAServer20][..]);
    assert_eq!(current_scan(&regs).classes_of_categories(&regs, da2, None), ids(&[]));
    // A change the watch does not report (it is not armed): seen all the same.
    reg.create_key(&da2_class(3)).unwrap();
    assert_eq!(current_scan(&regs).classes_of_categories(&regs, da2, None), ids(&[3]));
    assert_eq!(watch.arms.load(std::sync::atomic::Ordering::SeqCst), 2);
}
