//! Benchmark of the server browser against the system's own machinery, in the same run.
//!
//! Registers 2,000 classes in a test category, then times, alternately and several rounds each:
//! - opccomn: IOPCServerList2::EnumClassesOfCategories, then GetClassDetails (ProgID, user type and
//!   version-independent ProgID) for every class found;
//! - baseline: ICatInformation::EnumClassesOfCategories from the Component Categories Manager, then
//!   ProgIDFromCLSID for every class found (what a client without a server list does, and less work:
//!   one string per class instead of three).
//!
//! It prints the median of each and their ratio (goal: at most 1.2), then removes the classes. Windows
//! only; under Wine:
//!
//! ```sh
//! . scripts/wine-env.sh build/windows
//! CARGO_TARGET_X86_64_PC_WINDOWS_GNU_RUNNER=wine cargo run --release --example bench_server_list --target x86_64-pc-windows-gnu
//! ```

#[cfg(not(windows))]
fn main() {
    eprintln!("bench_server_list measures against the Windows Component Categories Manager: run it for a Windows target (see the file's documentation)");
}

#[cfg(windows)]
fn main() {
    bench::run();
}

#[cfg(windows)]
mod bench {
    use core::ffi::c_void;
    use core::ptr;
    use std::time::{Duration, Instant};

    use opccomn::com::iids::IID_IOPCServerList2;
    use opccomn::com::{GUID, HRESULT, ULONG};
    use opccomn::registry::windows::WindowsRegistry;
    use opccomn::registry::{RegValue, Registry};
    use opccomn::serverlist::interfaces::IOPCEnumGUID;
    use opccomn::serverlist::{IOPCServerList2, OpcServerListCreate};
    use windows_sys::Win32::System::Com::{
        CoCreateInstance, CoInitializeEx, CoTaskMemFree, ProgIDFromCLSID, CLSCTX_INPROC_SERVER,
        COINIT_APARTMENTTHREADED,
    };

    const CLASSES: u32 = 2000;
    const ROUNDS: usize = 7;
    /// A category of this benchmark only.
    const CATID_BENCH: GUID = GUID::from_u128(0xBE0C0000_0000_4000_8000_00000000CA70);
    const CLSID_STD_COMPONENT_CATEGORIES_MGR: GUID = GUID::from_u128(0x0002E005_0000_0000_C000_000000000046);
    const IID_ICAT_INFORMATION: GUID = GUID::from_u128(0x0002E013_0000_0000_C000_000000000046);

    fn clsid(i: u32) -> GUID {
        GUID::from_u128(0xBE0C0000_0000_4000_8000_000000000000 | i as u128)
    }

    #[repr(C)]
    #[allow(non_snake_case)]
    struct ICatInformationVtbl {
        QueryInterface: unsafe extern "system" fn(*mut ICatInformation, *const GUID, *mut *mut c_void) -> HRESULT,
        AddRef: unsafe extern "system" fn(*mut ICatInformation) -> ULONG,
        Release: unsafe extern "system" fn(*mut ICatInformation) -> ULONG,
        EnumCategories: usize,
        GetCategoryDesc: usize,
        EnumClassesOfCategories: unsafe extern "system" fn(
            *mut ICatInformation,
            ULONG,
            *const GUID,
            ULONG,
            *const GUID,
            *mut *mut IOPCEnumGUID,
        ) -> HRESULT,
    }

    #[repr(C)]
    struct ICatInformation {
        vtbl: *const ICatInformationVtbl,
    }

    fn register(reg: &WindowsRegistry) {
        for i in 0..CLASSES {
            let key = format!("CLSID\\{}", clsid(i));
            let sz = |s: String| RegValue::Sz(s);
            reg.set_value(&key, "", &sz(format!("Bench Server {i}"))).unwrap();
            reg.set_value(&format!("{key}\\ProgID"), "", &sz(format!("Bench.Server{i}.1")))
                .unwrap();
            reg.set_value(
                &format!("{key}\\VersionIndependentProgID"),
                "",
                &sz(format!("Bench.Server{i}")),
            )
            .unwrap();
            reg.create_key(&format!("{key}\\Implemented Categories\\{CATID_BENCH}"))
                .unwrap();
        }
    }

    fn unregister(reg: &WindowsRegistry) {
        for i in 0..CLASSES {
            let key = format!("CLSID\\{}", clsid(i));
            for sub in [
                format!("{key}\\Implemented Categories\\{CATID_BENCH}"),
                format!("{key}\\Implemented Categories"),
                format!("{key}\\ProgID"),
                format!("{key}\\VersionIndependentProgID"),
                key.clone(),
            ] {
                reg.delete_key(&sub).unwrap();
            }
        }
    }

    /// Drains an enumerator (IEnumGUID or IOPCEnumGUID: same layout) and releases it.
    unsafe fn drain(e: *mut IOPCEnumGUID) -> Vec<GUID> {
        let mut out = Vec::new();
        let mut buf = [GUID::default(); 64];
        loop {
            let mut n = 0;
            // SAFETY: live enumerator, room for 64.
            let hr = unsafe { ((*(*e).lpVtbl).Next)(e, 64, buf.as_mut_ptr(), &mut n) };
            out.extend_from_slice(&buf[..n as usize]);
            if hr != 0 {
                break;
            }
        }
        // SAFETY: we own the reference.
        unsafe { ((*(*e).lpVtbl).Release)(e) };
        out
    }

    /// Our server list: enumerate the bench category, then (with `details`) every class's details.
    fn ours(list: *mut IOPCServerList2, details: bool) -> usize {
        // SAFETY: `list` is a live IOPCServerList2; every out-parameter is a local; the strings
        // returned are freed once.
        unsafe {
            let v = &*(*list).lpVtbl;
            let mut e = ptr::null_mut();
            let mut cat = CATID_BENCH;
            assert_eq!(
                (v.EnumClassesOfCategories)(list, 1, &mut cat, 0, ptr::null_mut(), &mut e),
                0
            );
            let classes = drain(e);
            for c in classes.iter().filter(|_| details) {
                let (mut p, mut u, mut vi) = (ptr::null_mut(), ptr::null_mut(), ptr::null_mut());
                assert_eq!((v.GetClassDetails)(list, c, &mut p, &mut u, &mut vi), 0);
                CoTaskMemFree(p as _);
                CoTaskMemFree(u as _);
                CoTaskMemFree(vi as _);
            }
            classes.len()
        }
    }

    /// The system: ICatInformation, then (with `details`) ProgIDFromCLSID for every class.
    fn baseline(cats: *mut ICatInformation, details: bool) -> usize {
        // SAFETY: `cats` is a live ICatInformation; out-parameters are locals; strings freed once.
        unsafe {
            let v = &*(*cats).vtbl;
            let mut e = ptr::null_mut();
            let hr = (v.EnumClassesOfCategories)(cats, 1, &CATID_BENCH, u32::MAX, ptr::null(), &mut e);
            assert_eq!(hr, 0);
            let classes = drain(e);
            for c in classes.iter().filter(|_| details) {
                let mut p = ptr::null_mut();
                assert_eq!(ProgIDFromCLSID((c as *const GUID).cast(), &mut p), 0);
                CoTaskMemFree(p as _);
            }
            classes.len()
        }
    }

    fn median(mut v: Vec<Duration>) -> Duration {
        v.sort();
        v[v.len() / 2]
    }

    pub fn run() {
        // SAFETY: plain COM calls with valid arguments; every object is released.
        unsafe {
            CoInitializeEx(ptr::null(), COINIT_APARTMENTTHREADED as u32);
            let reg = WindowsRegistry::native();
            unregister(&reg);
            register(&reg);

            let mut list: *mut c_void = ptr::null_mut();
            assert_eq!(OpcServerListCreate(ptr::null_mut(), &IID_IOPCServerList2, &mut list), 0);
            let list = list as *mut IOPCServerList2;
            let mut cats: *mut c_void = ptr::null_mut();
            let hr = CoCreateInstance(
                (&CLSID_STD_COMPONENT_CATEGORIES_MGR as *const GUID).cast(),
                ptr::null_mut(),
                CLSCTX_INPROC_SERVER,
                (&IID_ICAT_INFORMATION as *const GUID).cast(),
                &mut cats,
            );
            assert_eq!(hr, 0);
            let cats = cats as *mut ICatInformation;

            // Warm up (registry caches), and check both see the same classes.
            assert_eq!(ours(list, true), CLASSES as usize);
            assert_eq!(baseline(cats, true), CLASSES as usize);
            let (mut a, mut b, mut ea, mut eb) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for _ in 0..ROUNDS {
                let t = Instant::now();
                ours(list, true);
                a.push(t.elapsed());
                let t = Instant::now();
                baseline(cats, true);
                b.push(t.elapsed());
                let t = Instant::now();
                ours(list, false);
                ea.push(t.elapsed());
                let t = Instant::now();
                baseline(cats, false);
                eb.push(t.elapsed());
            }
            let (a, b, ea, eb) = (median(a), median(b), median(ea), median(eb));
            println!("classes: {CLASSES}, rounds: {ROUNDS} (medians)");
            println!("opccomn  EnumClassesOfCategories + GetClassDetails: {a:?}");
            println!("baseline ICatInformation + ProgIDFromCLSID:         {b:?}");
            println!("ratio: {:.2} (goal <= 1.20)", a.as_secs_f64() / b.as_secs_f64());
            println!("enumeration alone: opccomn {ea:?}, baseline {eb:?}");

            ((*(*list).lpVtbl).Release)(list);
            ((*(*cats).vtbl).Release)(cats);
            unregister(&reg);
        }
    }
}
