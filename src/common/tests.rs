//! IOPCCommon through its vtable, as a client and a server use it (in process, no operating system
//! calls; so these run under Miri too).

use core::ffi::c_void;
use core::ptr;

use super::*;
use crate::com::alloc::task_free;
use crate::com::iids::IID_IUNKNOWN;
use crate::com::unknown::hostile;
use crate::com::unknown::{add_ref, query_interface, release};
use crate::com::wstr::{wstr_units, MAX_STRING_UNITS};
use crate::com::{CLASS_E_NOAGGREGATION, E_NOINTERFACE, E_POINTER};

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

fn create(options: *const OpcCommonOptions) -> *mut IOPCCommon {
    let mut p: *mut c_void = ptr::null_mut();
    // SAFETY: valid arguments.
    let hr = unsafe { OpcCommonCreate(options, ptr::null_mut(), &IID_IOPCCommon, &mut p) };
    assert_eq!(hr, S_OK);
    p.cast()
}

fn vt(c: *mut IOPCCommon) -> &'static IOPCCommonVtbl {
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
