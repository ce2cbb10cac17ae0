//! IOPCCommon through its vtable, as a client and a server use it (in process, no operating system
//! calls; so these run under Miri too).

use core::ffi::c_void;
use core::ptr;

use super::*;
use crate::com::alloc::task_free;
use crate::com::ffi::Crossed;
use crate::com::iids::IID_IUNKNOWN;
use crate::com::unknown::hostile;
use crate::com::unknown::{add_ref, query_interface, release};
use crate::com::wstr::{wstr_units, MAX_STRING_UNITS};
use crate::com::{CLASS_E_NOAGGREGATION, E_NOINTERFACE, E_POINTER, S_FALSE, ULONG};

const OPC_E_INVALIDHANDLE: HRESULT = 0xC0040001_u32 as HRESULT;

fn w(s: &str) -> Vec<WCHAR> {
    s.encode_utf16().chain(Some(0)).collect()
}

/// Reads and frees a task-allocated string.
fn take(p: LPWSTR) -> String {
    assert!(!p.is_null());
    // SAFETY: the library returned a NUL-terminated task-allocated string.
    let s = String::from_utf16(unsafe { wstr_units(p, MAX_STRING_UNITS) }.unwrap()).unwrap();
    // SAFETY: as above.
    unsafe { task_free(p.cast()) };
    s
}

/// Options with every field zero (no callbacks, the catalog's locales) and the current size.
fn no_options() -> OpcCommonOptions {
    OpcCommonOptions {
        struct_size: core::mem::size_of::<OpcCommonOptions>() as u32,
        server_kind: 0,
        locales: ptr::null(),
        locale_count: 0,
        vendor_error_string: None,
        vendor_error_context: ptr::null_mut(),
        client_name_changed: None,
        client_name_context: ptr::null_mut(),
        accept_locale: None,
        accept_locale_context: ptr::null_mut(),
        locale_changed: None,
        locale_changed_context: ptr::null_mut(),
        vendor_error_text: None,
    }
}

fn create(options: *const OpcCommonOptions) -> *mut IOPCCommon {
    let mut p: *mut c_void = ptr::null_mut();
    // SAFETY: valid arguments.
    let hr = unsafe { OpcCommonCreate(options, ptr::null_mut(), &IID_IOPCCommon, &mut p) };
    assert_eq!(hr, S_OK);
    p.cast()
}

fn vt(c: *mut IOPCCommon) -> &'static crate::com::interfaces::IOPCCommonCalls {
    // SAFETY: a live IOPCCommon pointer.
    unsafe { &*(*c).lpVtbl }
}

#[test]
fn a_session_keeps_its_locale_and_client_name() {
    let locales = [0x0409, 0x0407];
    let options = OpcCommonOptions {
        struct_size: core::mem::size_of::<OpcCommonOptions>() as u32,
        server_kind: 0,
        locales: locales.as_ptr(),
        locale_count: 2,
        vendor_error_string: None,
        vendor_error_context: ptr::null_mut(),
        client_name_changed: None,
        client_name_context: ptr::null_mut(),
        ..no_options()
    };
    let c = create(&options);
    let other = create(ptr::null());
    let v = vt(c);
    // SAFETY: `c` and `other` are live until their final Release; out-parameters are valid.
    unsafe {
        let mut lcid = 0xFFFF;
        assert_eq!((v.GetLocaleID)(c, &mut lcid), S_OK);
        assert_eq!(lcid, crate::locale::LOCALE_SYSTEM_DEFAULT);
        assert_eq!((v.SetLocaleID)(c, 0x0407), S_OK);
        assert_eq!((v.SetLocaleID)(c, 0x0411), E_INVALIDARG);
        assert_eq!((v.GetLocaleID)(c, &mut lcid), S_OK);
        assert_eq!(lcid, 0x0407);
        assert_eq!((v.GetLocaleID)(c, ptr::null_mut()), E_INVALIDARG);
        assert_eq!((v.GetLocaleID)(other, &mut lcid), S_OK);
        assert_eq!(lcid, crate::locale::LOCALE_SYSTEM_DEFAULT, "sessions share nothing");

        let (mut count, mut list) = (99, ptr::null_mut());
        assert_eq!((v.QueryAvailableLocaleIDs)(c, &mut count, &mut list), S_OK);
        let got = core::slice::from_raw_parts(list, count as usize).to_vec();
        task_free(list.cast());
        assert_eq!(&got[..2], &locales);
        assert!(got.contains(&crate::locale::LOCALE_SYSTEM_DEFAULT));
        assert_eq!(
            (v.QueryAvailableLocaleIDs)(c, &mut count, ptr::null_mut()),
            E_INVALIDARG
        );
        assert_eq!(count, 0);

        let mut text = ptr::null_mut();
        assert_eq!((v.GetErrorString)(c, OPC_E_INVALIDHANDLE, &mut text), S_OK);
        assert_eq!(take(text), "Der Wert des Handles ist ungültig.");
        assert_eq!((v.SetLocaleID)(c, 0x0409), S_OK);
        assert_eq!((v.GetErrorString)(c, OPC_E_INVALIDHANDLE, &mut text), S_OK);
        assert_eq!(take(text), "The value of the handle is invalid.");
        text = core::ptr::null_mut::<u16>().wrapping_byte_add(1);
        assert_eq!((v.GetErrorString)(c, 0x1234_5678, &mut text), E_INVALIDARG);
        assert!(text.is_null());

        let mut name = ptr::null_mut();
        assert_eq!(OpcCommonGetClientName(c.cast(), &mut name), S_OK);
        assert_eq!(take(name), "");
        assert_eq!((v.SetClientName)(c, w("Client A").as_ptr()), S_OK);
        assert_eq!((v.SetClientName)(c, ptr::null()), E_INVALIDARG);
        assert_eq!(OpcCommonGetClientName(c.cast(), &mut name), S_OK);
        assert_eq!(take(name), "Client A");
        assert_eq!(OpcCommonGetClientName(c.cast(), ptr::null_mut()), E_INVALIDARG);
        name = core::ptr::null_mut::<u16>().wrapping_byte_add(1);
        assert_eq!(OpcCommonGetClientName(ptr::null_mut(), &mut name), E_INVALIDARG);
        assert!(name.is_null());

        assert_eq!((v.Release)(other), 0);
        assert_eq!((v.Release)(c), 0);
    }
}

/// A server object aggregating an IOPCCommon session, written as a C++ server would.
#[repr(C)]
struct Outer {
    vtbl: &'static crate::com::IUnknownVtbl,
    refs: core::sync::atomic::AtomicU32,
    inner: core::cell::Cell<*mut IUnknown>,
}

static OUTER_VTBL: crate::com::IUnknownVtbl = crate::com::IUnknownVtbl {
    QueryInterface: outer_qi,
    AddRef: outer_add_ref,
    Release: outer_release,
};

unsafe extern "system" fn outer_qi(this: *mut IUnknown, riid: REFIID, ppv: *mut *mut c_void) -> Hr {
    Crossed::from_c(|| {
        // SAFETY: only Outer objects present OUTER_VTBL; the callers pass valid pointers.
        unsafe {
            let o = &*(this as *const Outer);
            if *riid == IID_IUNKNOWN {
                *ppv = this.cast();
                outer_add_ref(this);
                return S_OK;
            }
            if *riid == IID_IOPCCommon {
                return query_interface(o.inner.get(), &*riid, ppv);
            }
            *ppv = ptr::null_mut();
            E_NOINTERFACE
        }
    })
}

unsafe extern "system" fn outer_add_ref(this: *mut IUnknown) -> Crossed<ULONG> {
    Crossed::from_c(|| {
        // SAFETY: as above.
        unsafe { &*(this as *const Outer) }
            .refs
            .fetch_add(1, core::sync::atomic::Ordering::SeqCst)
            + 1
    })
}

unsafe extern "system" fn outer_release(this: *mut IUnknown) -> Crossed<ULONG> {
    Crossed::from_c(|| {
        // SAFETY: as above; the test owns the memory and releases the inner object itself.
        unsafe { &*(this as *const Outer) }
            .refs
            .fetch_sub(1, core::sync::atomic::Ordering::SeqCst)
            - 1
    })
}

#[test]
fn an_aggregated_session_counts_on_its_outer_object() {
    let outer = Box::new(Outer {
        vtbl: &OUTER_VTBL,
        refs: core::sync::atomic::AtomicU32::new(1),
        inner: core::cell::Cell::new(ptr::null_mut()),
    });
    let outer_unk = &*outer as *const Outer as *mut IUnknown;
    let mut inner: *mut c_void = ptr::null_mut();
    let mut p: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
    // SAFETY: valid arguments; the outer object outlives the inner one.
    unsafe {
        assert_eq!(
            OpcCommonCreate(ptr::null(), outer_unk, &IID_IOPCCommon, &mut p),
            CLASS_E_NOAGGREGATION
        );
        assert!(p.is_null());
        assert_eq!(OpcCommonCreate(ptr::null(), outer_unk, &IID_IUNKNOWN, &mut inner), S_OK);
        outer.inner.set(inner.cast());
        // Through the outer object, as a client sees the server.
        assert_eq!(query_interface(outer_unk, &IID_IOPCCommon, &mut p), S_OK);
        let c: *mut IOPCCommon = p.cast();
        assert_eq!(
            outer.refs.load(core::sync::atomic::Ordering::SeqCst),
            2,
            "counted on the outer"
        );
        // IUnknown from the session is the server's identity.
        let mut identity = ptr::null_mut();
        assert_eq!((vt(c).QueryInterface)(c, &IID_IUNKNOWN, &mut identity), S_OK);
        assert_eq!(identity, outer_unk.cast());
        release(identity.cast());
        assert_eq!((vt(c).SetClientName)(c, w("Aggregated").as_ptr()), S_OK);
        let mut name = ptr::null_mut();
        assert_eq!(OpcCommonGetClientName(outer_unk, &mut name), S_OK);
        assert_eq!(take(name), "Aggregated");
        assert_eq!(OpcCommonGetClientName(inner.cast(), &mut name), S_OK);
        assert_eq!(take(name), "Aggregated");
        assert_eq!((vt(c).Release)(c), 1);
        // The non-delegating IUnknown counts the session itself; its last Release destroys it.
        assert_eq!(add_ref(inner.cast()), 2);
        assert_eq!(release(inner.cast()), 1);
        assert_eq!(release(inner.cast()), 0);
    }
    assert_eq!(outer.refs.load(core::sync::atomic::Ordering::SeqCst), 1);
}

#[test]
fn a_hostile_query_interface_answer_is_refused_without_a_crash() {
    for h in hostile::all() {
        let mut name: LPWSTR = core::ptr::null_mut::<u16>().wrapping_byte_add(1);
        // SAFETY: a valid (if broken) COM object and a writable out-parameter.
        assert_eq!(unsafe { OpcCommonGetClientName(h.unk(), &mut name) }, E_INVALIDARG);
        assert!(name.is_null());
        assert_eq!(h.refs(), 1, "nothing released or kept");
    }
    let mut p: *mut c_void = core::ptr::null_mut::<c_void>().wrapping_byte_add(1);
    // SAFETY: NULL arguments are refused before anything is read or written.
    let hr = unsafe { OpcCommonCreate(ptr::null(), ptr::null_mut(), &IID_IOPCCommon, ptr::null_mut()) };
    assert_eq!(hr, E_POINTER);
    // SAFETY: as above.
    let hr = unsafe { OpcCommonCreate(ptr::null(), ptr::null_mut(), ptr::null(), &mut p) };
    assert_eq!(hr, E_POINTER);
    assert!(p.is_null());
}

/// What the locale callbacks saw: (locale, listed) for each question, and each change.
#[derive(Default)]
struct LocaleLog {
    asked: std::sync::Mutex<Vec<(LCID, i32)>>,
    changed: std::sync::Mutex<Vec<LCID>>,
}

/// Accepts 0x0411 (unlisted) and refuses 0x0407 (listed); decides the rest by the list.
unsafe extern "C" fn judge(context: *mut c_void, locale: LCID, listed: i32) -> i32 {
    // SAFETY: the test passes a LocaleLog that outlives the session.
    let log = unsafe { &*context.cast::<LocaleLog>() };
    log.asked.lock().unwrap().push((locale, listed));
    match locale {
        0x0411 => 1,
        0x0407 => 0,
        _ => listed,
    }
}

unsafe extern "C" fn locale_changed(context: *mut c_void, locale: LCID) {
    // SAFETY: as above.
    let log = unsafe { &*context.cast::<LocaleLog>() };
    log.changed.lock().unwrap().push(locale);
}

#[test]
fn a_server_decides_each_locale_and_is_told_of_every_change() {
    let log = LocaleLog::default();
    let locales = [0x0409, 0x0407];
    let context = ptr::from_ref(&log).cast_mut().cast();
    let options = OpcCommonOptions {
        locales: locales.as_ptr(),
        locale_count: 2,
        accept_locale: Some(judge),
        accept_locale_context: context,
        locale_changed: Some(locale_changed),
        locale_changed_context: context,
        ..no_options()
    };
    let c = create(&options);
    let v = vt(c);
    // SAFETY: `c` is live until its final Release; out-parameters are valid.
    unsafe {
        let mut lcid = 0;
        assert_eq!(
            (v.SetLocaleID)(c, 0x0411),
            S_OK,
            "the server accepts an unlisted locale"
        );
        assert_eq!((v.SetLocaleID)(c, 0x0407), E_INVALIDARG, "and refuses a listed one");
        assert_eq!((v.GetLocaleID)(c, &mut lcid), S_OK);
        assert_eq!(lcid, 0x0411, "a refused locale leaves the session's locale as it was");
        assert_eq!((v.SetLocaleID)(c, 0x0409), S_OK);
        assert_eq!((v.SetLocaleID)(c, 0x0C0A), E_INVALIDARG);
        // The fast read through the IOPCCommon pointer and the read through the object's IUnknown.
        let mut fast = 0;
        assert_eq!(OpcCommonGetLocale(c.cast(), &mut fast), S_OK);
        assert_eq!(fast, 0x0409);
        let mut unknown: *mut c_void = ptr::null_mut();
        assert_eq!((v.QueryInterface)(c, &IID_IUNKNOWN, &mut unknown), S_OK);
        let mut slow = 0;
        assert_eq!(OpcCommonGetLocale(unknown.cast(), &mut slow), S_OK);
        assert_eq!(slow, 0x0409);
        release(unknown.cast());
        // QueryAvailableLocaleIDs keeps the declared list.
        let (mut count, mut list) = (0, ptr::null_mut());
        assert_eq!((v.QueryAvailableLocaleIDs)(c, &mut count, &mut list), S_OK);
        let got = core::slice::from_raw_parts(list, count as usize).to_vec();
        task_free(list.cast());
        assert_eq!(&got[..2], &locales);
        assert!(!got.contains(&0x0411));
        release(c.cast());
    }
    assert_eq!(
        *log.asked.lock().unwrap(),
        [(0x0411, 0), (0x0407, 1), (0x0409, 1), (0x0C0A, 0)],
        "every SetLocaleID is asked, with whether the locale is listed"
    );
    assert_eq!(
        *log.changed.lock().unwrap(),
        [0x0411, 0x0409],
        "only accepted changes are told"
    );
}

#[test]
fn without_a_judge_exactly_the_declared_locales_are_accepted_and_older_options_still_work() {
    let log = LocaleLog::default();
    let locales = [0x0409];
    let mut options = OpcCommonOptions {
        locales: locales.as_ptr(),
        locale_count: 1,
        locale_changed: Some(locale_changed),
        locale_changed_context: ptr::from_ref(&log).cast_mut().cast(),
        ..no_options()
    };
    let c = create(&options);
    // SAFETY: `c` is live until its final Release.
    unsafe {
        assert_eq!((vt(c).SetLocaleID)(c, 0x0407), E_INVALIDARG);
        assert_eq!((vt(c).SetLocaleID)(c, 0x0409), S_OK);
        release(c.cast());
    }
    assert_eq!(*log.changed.lock().unwrap(), [0x0409]);
    // A caller built against the 0.1 header passes the size that ends after client_name_context: the
    // new fields are not read (the judge here would accept anything, and is never asked).
    options.accept_locale = Some(judge);
    options.accept_locale_context = ptr::from_ref(&log).cast_mut().cast();
    options.struct_size =
        (core::mem::offset_of!(OpcCommonOptions, client_name_context) + core::mem::size_of::<*mut c_void>()) as u32;
    let c = create(&options);
    // SAFETY: as above.
    unsafe {
        assert_eq!((vt(c).SetLocaleID)(c, 0x0411), E_INVALIDARG);
        release(c.cast());
    }
    assert!(log.asked.lock().unwrap().is_empty());
    assert_eq!(
        *log.changed.lock().unwrap(),
        [0x0409],
        "the observer of an older caller is not read either"
    );
}

#[test]
fn the_locale_of_something_that_is_not_a_session_is_refused() {
    let mut lcid = 0x1234;
    // SAFETY: NULL arguments and a live object of another class.
    unsafe {
        assert_eq!(OpcCommonGetLocale(ptr::null_mut(), &mut lcid), E_INVALIDARG);
        assert_eq!(lcid, 0, "the out-parameter is reset on failure");
        let c = create(ptr::null());
        assert_eq!(OpcCommonGetLocale(c.cast(), ptr::null_mut()), E_INVALIDARG);
        release(c.cast());
        let mut shutdown: *mut c_void = ptr::null_mut();
        assert_eq!(
            crate::shutdown::OpcShutdownCreate(ptr::null_mut(), &IID_IUNKNOWN, &mut shutdown).get(),
            S_OK
        );
        lcid = 0x1234;
        assert_eq!(OpcCommonGetLocale(shutdown.cast(), &mut lcid), E_INVALIDARG);
        assert_eq!(lcid, 0);
        release(shutdown.cast());
    }
}

/// Hands over a new task string for OPC_E_INVALIDHANDLE, declines everything else: with S_FALSE and a
/// string (the library must free it) for 0xE0000002, with a string longer than the library's bound
/// for 0xE0000003.
unsafe extern "C" fn owned_text(context: *mut c_void, code: HRESULT, _locale: LCID, text: *mut LPWSTR) -> HRESULT {
    // SAFETY: the test passes a Mutex<Vec<usize>> that outlives the session.
    let handed = unsafe { &*context.cast::<std::sync::Mutex<Vec<usize>>>() };
    let units: Vec<WCHAR> = match code as u32 {
        0xC0040001 => w("vendor: bad handle"),
        0xE0000002 => w("declined"),
        0xE0000003 => vec![0x61; MAX_STRING_UNITS + 2].into_iter().chain(Some(0)).collect(),
        _ => return S_FALSE,
    };
    let p = crate::com::alloc::task_alloc(units.len() * 2).cast::<WCHAR>();
    // SAFETY: `p` holds `units.len()` units; `text` is the library's out-parameter.
    unsafe {
        ptr::copy_nonoverlapping(units.as_ptr(), p, units.len());
        *text = p;
    }
    handed.lock().unwrap().push(p as usize);
    if code as u32 == 0xE0000002 {
        S_FALSE
    } else {
        S_OK
    }
}

#[test]
fn vendor_texts_handed_over_as_task_memory_reach_the_client_as_they_are() {
    let handed = std::sync::Mutex::new(Vec::<usize>::new());
    let options = OpcCommonOptions {
        vendor_error_text: Some(owned_text),
        vendor_error_context: ptr::from_ref(&handed).cast_mut().cast(),
        ..no_options()
    };
    let c = create(&options);
    let v = vt(c);
    // SAFETY: `c` is live until its final Release; out-parameters are valid.
    unsafe {
        let mut text = ptr::null_mut();
        assert_eq!((v.GetErrorString)(c, OPC_E_INVALIDHANDLE, &mut text), S_OK);
        assert_eq!(
            text as usize,
            handed.lock().unwrap()[0],
            "the server's string itself, not a copy"
        );
        assert_eq!(take(text), "vendor: bad handle");
        // Declined with a string: the library frees it (the leak checks of Miri, ASan and valgrind
        // would see it otherwise) and answers from the catalog, which has no such code.
        assert_eq!(
            (v.GetErrorString)(c, 0xE0000002_u32 as HRESULT, &mut text),
            E_INVALIDARG
        );
        assert!(text.is_null());
        // Too long: freed, and the code is looked up as if declined.
        assert_eq!(
            (v.GetErrorString)(c, 0xE0000003_u32 as HRESULT, &mut text),
            E_INVALIDARG
        );
        assert!(text.is_null());
        // Declined without a string: the catalog's text.
        assert_eq!((v.GetErrorString)(c, 0xC0040004_u32 as HRESULT, &mut text), S_OK);
        assert!(!take(text).is_empty());
        release(c.cast());
    }
    assert_eq!(handed.lock().unwrap().len(), 3);
}

unsafe extern "C" fn borrowed_text(
    _context: *mut c_void,
    _code: HRESULT,
    _locale: LCID,
    _text: *mut LPCWSTR,
) -> HRESULT {
    S_FALSE
}

#[test]
fn both_forms_of_vendor_texts_at_once_are_refused() {
    let options = OpcCommonOptions {
        vendor_error_string: Some(borrowed_text),
        vendor_error_text: Some(owned_text),
        ..no_options()
    };
    let mut p: *mut c_void = 1 as *mut c_void;
    // SAFETY: valid arguments.
    let hr = unsafe { OpcCommonCreate(&options, ptr::null_mut(), &IID_IOPCCommon, &mut p) };
    assert_eq!(hr, E_INVALIDARG);
    assert!(p.is_null());
}
