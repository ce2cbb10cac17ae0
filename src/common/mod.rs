//! IOPCCommon (specification chapter 5) as a reusable, aggregatable object.
//!
//! Each object is one client session: it keeps its own locale and client name, and two objects never
//! share them. A server creates one per client connection with `OpcCommonCreate`, usually aggregated
//! into its server object.

use core::ffi::c_void;
use core::ptr;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Mutex, MutexGuard};

use crate::com::alloc::{alloc_array, alloc_wstr};
use crate::com::ffi::{self, FfiResult, Hr};
use crate::com::iids::IID_IOPCCommon;
use crate::com::interfaces::IOPCCommonImpl;
use crate::com::object::{ComClass, ComObject, Delegating, Slot};
use crate::com::options::{read_sized, SizedStruct};
use crate::com::{IUnknown, DWORD, E_INVALIDARG, GUID, HRESULT, LCID, LPCWSTR, LPWSTR, REFIID, S_OK, WCHAR};
use crate::errors::{
    error_string, OpcServerKind, OpcVendorErrorStringFn, OpcVendorErrorTextFn, VendorCallback, VendorTexts,
    CATALOG_LOCALES,
};
use crate::locale::{LOCALE_SYSTEM_DEFAULT, SPECIAL_LOCALES};

pub use crate::com::interfaces::{IOPCCommon, IOPCCommonVtbl};

/// Called after a client set its name (IOPCCommon::SetClientName). May be called from any thread;
/// never called while the library holds a lock.
///
/// # Parameters
/// - `context`: OpcCommonOptions::client_name_context.
/// - `name`: the client's new name, valid only during the call.
pub type OpcClientNameFn = Option<unsafe extern "C" fn(context: *mut c_void, name: LPCWSTR)>;

/// Decides whether a session may use a locale: called by SetLocaleID. May be called from any thread,
/// concurrently; never while the library holds a lock.
///
/// # Parameters
/// - `context`: OpcCommonOptions::accept_locale_context.
/// - `locale`: the locale the client asks for, as it gave it.
/// - `listed`: nonzero when the session declared it (in OpcCommonOptions::locales, or one of the four
///   special locales).
///
/// # Returns
/// Nonzero to accept the locale, 0 to refuse it (the client then gets E_INVALIDARG and keeps its
/// locale).
pub type OpcAcceptLocaleFn = Option<unsafe extern "C" fn(context: *mut c_void, locale: LCID, listed: i32) -> i32>;

/// Called after a client changed the session's locale with SetLocaleID. May be called from any
/// thread; never called while the library holds a lock. When two clients' calls race, the calls may
/// arrive in either order: read the current value with `OpcCommonGetLocale` if the order matters.
///
/// # Parameters
/// - `context`: OpcCommonOptions::locale_changed_context.
/// - `locale`: the new locale, as the client gave it (e.g. LOCALE_SYSTEM_DEFAULT).
pub type OpcLocaleChangedFn = Option<unsafe extern "C" fn(context: *mut c_void, locale: LCID)>;

/// How a server configures an IOPCCommon object. Zero-initialise it, set `struct_size` to
/// `sizeof(OpcCommonOptions)`, then set what you need: fields added in later versions go at the end,
/// and the library reads only the first `struct_size` bytes, so code built against an older header
/// keeps working.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct OpcCommonOptions {
    /// `sizeof(OpcCommonOptions)` as the caller's header declares it.
    pub struct_size: u32,
    /// Which kind of server this session belongs to (`OpcServerKind`); 0 is Data Access.
    pub server_kind: u32,
    /// The concrete locales the server supports (e.g. 0x0409, 0x0407); NULL with a count of 0 means
    /// the languages the library's catalog ships. LOCALE_SYSTEM_DEFAULT, LOCALE_USER_DEFAULT,
    /// LOCALE_NEUTRAL and LOCALE_INVARIANT are always available in addition.
    pub locales: *const LCID,
    /// Number of entries in `locales` (at most 4096).
    pub locale_count: u32,
    /// Texts for the server's own error codes, asked before the catalog (optional).
    pub vendor_error_string: OpcVendorErrorStringFn,
    /// Passed to `vendor_error_string`.
    pub vendor_error_context: *mut c_void,
    /// Told of every client name set through SetClientName (optional).
    pub client_name_changed: OpcClientNameFn,
    /// Passed to `client_name_changed`.
    pub client_name_context: *mut c_void,
    /// Decides each SetLocaleID (optional, since 0.2): with it, a locale is accepted when the callback
    /// says so, listed or not (QueryAvailableLocaleIDs still returns the declared list); without it,
    /// exactly the declared locales are.
    pub accept_locale: OpcAcceptLocaleFn,
    /// Passed to `accept_locale`.
    pub accept_locale_context: *mut c_void,
    /// Told of every locale set through SetLocaleID (optional, since 0.2).
    pub locale_changed: OpcLocaleChangedFn,
    /// Passed to `locale_changed`.
    pub locale_changed_context: *mut c_void,
    /// Texts for the server's own error codes, handed over as task memory (optional, since 0.2;
    /// called with `vendor_error_context`). Set this or `vendor_error_string`, not both.
    pub vendor_error_text: OpcVendorErrorTextFn,
}

/// The most locales a server may declare.
const MAX_LOCALES: u32 = 4096;

// SAFETY: repr(C), struct_size first; integers, raw pointers and optional function pointers.
unsafe impl SizedStruct for OpcCommonOptions {
    /// Every size the struct ends at in some version: after a whole field (with or without the
    /// padding C adds).
    const SIZES: &'static [usize] = {
        use core::mem::{offset_of, size_of};
        type O = OpcCommonOptions;
        const PTR: usize = size_of::<*const c_void>();
        &[
            offset_of!(O, server_kind),
            offset_of!(O, locales),
            offset_of!(O, locales) + PTR,
            offset_of!(O, locale_count) + size_of::<u32>(),
            offset_of!(O, vendor_error_string),
            offset_of!(O, vendor_error_context),
            offset_of!(O, client_name_changed),
            offset_of!(O, client_name_context),
            offset_of!(O, accept_locale),
            offset_of!(O, accept_locale_context),
            offset_of!(O, locale_changed),
            offset_of!(O, locale_changed_context),
            offset_of!(O, vendor_error_text),
            size_of::<O>(),
        ]
    };
}

/// The options as the object keeps them.
struct Settings {
    kind: OpcServerKind,
    available: Vec<LCID>,
    vendor: Option<VendorTexts>,
    observer: Option<NameObserver>,
    accept_locale: Option<LocaleJudge>,
    locale_observer: Option<LocaleObserver>,
}

#[derive(Clone, Copy)]
struct LocaleJudge {
    callback: unsafe extern "C" fn(context: *mut c_void, locale: LCID, listed: i32) -> i32,
    context: *mut c_void,
}

#[derive(Clone, Copy)]
struct LocaleObserver {
    callback: unsafe extern "C" fn(context: *mut c_void, locale: LCID),
    context: *mut c_void,
}

// SAFETY: the options contract says these callbacks may be called from any thread with their context.
unsafe impl Send for LocaleJudge {}
// SAFETY: as above.
unsafe impl Sync for LocaleJudge {}
// SAFETY: as above.
unsafe impl Send for LocaleObserver {}
// SAFETY: as above.
unsafe impl Sync for LocaleObserver {}

#[derive(Clone, Copy)]
struct NameObserver {
    callback: unsafe extern "C" fn(context: *mut c_void, name: LPCWSTR),
    context: *mut c_void,
}

// SAFETY: the options contract says the observer may be called from any thread with its context.
unsafe impl Send for NameObserver {}
// SAFETY: as above.
unsafe impl Sync for NameObserver {}

impl Settings {
    /// Reads the caller's options, honouring `struct_size`.
    ///
    /// # Safety
    /// `options` must be NULL or point at `struct_size` readable bytes laid out as OpcCommonOptions,
    /// with `locales` pointing at `locale_count` readable LCIDs.
    unsafe fn read(options: *const OpcCommonOptions) -> Result<Settings, HRESULT> {
        let defaults = OpcCommonOptions {
            struct_size: 0,
            server_kind: 0,
            locales: ptr::null(),
            locale_count: 0,
            accept_locale: None,
            accept_locale_context: ptr::null_mut(),
            locale_changed: None,
            locale_changed_context: ptr::null_mut(),
            vendor_error_text: None,
            vendor_error_string: None,
            vendor_error_context: ptr::null_mut(),
            client_name_changed: None,
            client_name_context: ptr::null_mut(),
        };
        // SAFETY: OpcCommonOptions is repr(C), starts with struct_size and holds integers, raw
        // pointers and optional function pointers; the caller vouches for `options`.
        let o = unsafe { read_sized(options, defaults) }?;
        let kind = OpcServerKind::from_raw(o.server_kind).ok_or(E_INVALIDARG)?;
        if o.locale_count > MAX_LOCALES || (o.locale_count > 0 && o.locales.is_null()) {
            return Err(E_INVALIDARG);
        }
        let declared: &[LCID] = if o.locale_count == 0 {
            &CATALOG_LOCALES
        } else {
            // SAFETY: checked non-NULL; the caller vouches for `locale_count` readable entries.
            unsafe { core::slice::from_raw_parts(o.locales, o.locale_count as usize) }
        };
        let mut available: Vec<LCID> = Vec::with_capacity(declared.len() + SPECIAL_LOCALES.len());
        for &lcid in declared.iter().chain(SPECIAL_LOCALES.iter()) {
            if !available.contains(&lcid) {
                available.push(lcid);
            }
        }
        let vendor = match (o.vendor_error_string, o.vendor_error_text) {
            (Some(_), Some(_)) => return Err(E_INVALIDARG),
            (Some(borrowed), None) => Some(VendorCallback::Borrowed(borrowed)),
            (None, Some(owned)) => Some(VendorCallback::Owned(owned)),
            (None, None) => None,
        };
        Ok(Settings {
            kind,
            available,
            vendor: vendor.map(|callback| VendorTexts {
                callback,
                context: o.vendor_error_context,
            }),
            accept_locale: o.accept_locale.map(|callback| LocaleJudge {
                callback,
                context: o.accept_locale_context,
            }),
            locale_observer: o.locale_changed.map(|callback| LocaleObserver {
                callback,
                context: o.locale_changed_context,
            }),
            observer: o.client_name_changed.map(|callback| NameObserver {
                callback,
                context: o.client_name_context,
            }),
        })
    }
}

/// The client name one session has set.
struct Session {
    /// The client name as given (invalid UTF-16 kept), without a NUL; `None` until set.
    client_name: Option<Vec<WCHAR>>,
}

/// The IOPCCommon object.
pub struct OpcCommon {
    common: Slot,
    settings: Settings,
    /// The session's locale (SetLocaleID). Apart from the lock: GetErrorString reads it on every call,
    /// and a lone LCID needs no more than an atomic to be read whole.
    locale: AtomicU32,
    session: Mutex<Session>,
}

impl ComClass for OpcCommon {
    fn interface(&self, iid: &GUID) -> Option<&Slot> {
        (*iid == IID_IOPCCommon).then_some(&self.common)
    }
}

impl OpcCommon {
    fn session(&self) -> MutexGuard<'_, Session> {
        // A panic while holding the lock cannot leave a Session half-written; keep going.
        self.session.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn set_locale(&self, lcid: LCID) -> Result<HRESULT, HRESULT> {
        let listed = self.settings.available.contains(&lcid);
        let accepted = match self.settings.accept_locale {
            Some(judge) => {
                // SAFETY: the server registered the callback for this; no lock is held.
                let verdict = unsafe { (judge.callback)(judge.context, lcid, i32::from(listed)) };
                verdict != 0
            }
            None => listed,
        };
        if !accepted {
            return Err(E_INVALIDARG);
        }
        self.locale.store(lcid, Ordering::Relaxed);
        if let Some(observer) = self.settings.locale_observer {
            // SAFETY: the server registered the observer for this; no lock is held.
            unsafe { (observer.callback)(observer.context, lcid) };
        }
        Ok(S_OK)
    }

    fn error_string(&self, code: HRESULT) -> Result<LPWSTR, HRESULT> {
        let locale = self.locale.load(Ordering::Relaxed);
        error_string(code, locale, self.settings.kind, self.settings.vendor.as_ref())
    }

    fn set_client_name(&self, name: &[WCHAR]) {
        self.session().client_name = Some(name.to_vec());
        if let Some(observer) = self.settings.observer {
            let mut terminated = Vec::with_capacity(name.len() + 1);
            terminated.extend_from_slice(name);
            terminated.push(0);
            // SAFETY: the server registered the observer for this; the lock is not held.
            unsafe { (observer.callback)(observer.context, terminated.as_ptr()) };
        }
    }

    fn client_name(&self) -> Vec<WCHAR> {
        self.session().client_name.clone().unwrap_or_default()
    }
}

static IOPCCOMMON_VTBL: IOPCCommonVtbl = IOPCCommonVtbl::new::<Delegating, OpcCommon>();

impl IOPCCommonImpl for OpcCommon {
    fn SetLocaleID(this: &ComObject<Self>, lcid: LCID) -> FfiResult {
        Ok(this.set_locale(lcid)?)
    }

    fn GetLocaleID(this: &ComObject<Self>, pdwLcid: ffi::Out<'_, LCID>) -> FfiResult {
        pdwLcid.write(this.locale.load(Ordering::Relaxed));
        Ok(S_OK)
    }

    fn QueryAvailableLocaleIDs(
        this: &ComObject<Self>,
        pdwCount: ffi::Out<'_, DWORD>,
        pdwLcid: ffi::Out<'_, *mut LCID>,
    ) -> FfiResult {
        let available = &this.settings.available;
        pdwLcid.write(alloc_array(available)?);
        pdwCount.write(available.len() as DWORD);
        Ok(S_OK)
    }

    fn GetErrorString(this: &ComObject<Self>, dwError: HRESULT, ppString: ffi::Out<'_, LPWSTR>) -> FfiResult {
        ppString.write(this.error_string(dwError)?);
        Ok(S_OK)
    }

    fn SetClientName(this: &ComObject<Self>, szName: ffi::WStr<'_>) -> FfiResult {
        this.set_client_name(szName.units()?);
        Ok(S_OK)
    }
}

/// Creates an IOPCCommon object: one client session with its own locale (LOCALE_SYSTEM_DEFAULT at
/// first) and client name.
///
/// To aggregate the object into a server object, pass the server's controlling IUnknown as `outer`
/// and IID_IUnknown as `riid`: the result is the inner, non-delegating IUnknown, which the server
/// keeps, releases when it is destroyed, and forwards QueryInterface(IID_IOPCCommon) to.
///
/// # Parameters
/// - `options`: the session's settings (OpcCommonOptions), or NULL for the defaults (a Data Access
///   server supporting the catalog's languages).
/// - `outer`: the controlling IUnknown of the server object that aggregates the session, or NULL.
/// - `riid`: the interface wanted: IID_IOPCCommon or IID_IUnknown, only IID_IUnknown with an `outer`.
/// - `ppv` (out): receives the interface, or NULL on failure.
///
/// # Returns
/// S_OK; E_POINTER for a NULL `ppv` or `riid`; CLASS_E_NOAGGREGATION for an `outer` with a `riid`
/// other than IID_IUnknown; E_INVALIDARG for bad options (wrong `struct_size`, unknown `server_kind`,
/// more than 4096 locales, or a count without an array); E_NOINTERFACE.
///
/// # Safety
/// `options` must be NULL or valid as documented on OpcCommonOptions; `outer` NULL or a valid
/// IUnknown that outlives the object; `riid` NULL or readable; `ppv` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcCommonCreate(
    options: *const OpcCommonOptions,
    outer: *mut IUnknown,
    riid: REFIID,
    ppv: *mut *mut c_void,
) -> Hr {
    ffi::boundary!(Com, [ppv], {
        // SAFETY: forwarded from the caller's contract.
        Ok(unsafe {
            ComObject::<OpcCommon>::create(outer, riid, ppv, |binder| {
                let settings = Settings::read(options)?;
                Ok(OpcCommon {
                    common: binder.slot(&IOPCCOMMON_VTBL),
                    settings,
                    locale: AtomicU32::new(LOCALE_SYSTEM_DEFAULT),
                    session: Mutex::new(Session { client_name: None }),
                })
            })
        })
    })
}

/// Gives a server the client name of one of its IOPCCommon sessions.
///
/// # Parameters
/// - `common`: any interface of the session: the IOPCCommon pointer, the inner IUnknown from
///   `OpcCommonCreate`, or the server object that aggregates it.
/// - `name` (out): receives a new string, the name the client set (empty while it has set none;
///   free it with `OpcTaskMemFree`), or NULL on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for NULL arguments or an object that is not an IOPCCommon of this library.
///
/// # Safety
/// `common` must be NULL or a valid COM interface pointer; `name` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcCommonGetClientName(common: *mut IUnknown, name: *mut LPWSTR) -> Hr {
    ffi::boundary!(Opc, [name], {
        // SAFETY: the caller vouches a non-NULL out-parameter is writable.
        let out = unsafe { ffi::out(name) }?;
        let common = ffi::in_ptr(common)?;
        // SAFETY: `common` is a valid COM pointer per the contract.
        let iface = unsafe { crate::com::unknown::query::<IOPCCommon>(common.as_ptr(), &IID_IOPCCommon) }
            .map_err(|_| E_INVALIDARG)?;
        // SAFETY: `iface` is a valid IOPCCommon pointer, ours or not; it stays counted meanwhile.
        let result = match unsafe { ComObject::<OpcCommon>::from_foreign(iface.as_ptr(), &IOPCCOMMON_VTBL) } {
            Some(obj) => alloc_wstr(&obj.client_name()),
            None => Err(E_INVALIDARG),
        };
        drop(iface);
        out.write(result?);
        Ok(S_OK)
    })
}

/// Gives a server the current locale of one of its IOPCCommon sessions (what GetLocaleID returns).
///
/// Passing the IOPCCommon pointer itself is the cheap form: the library recognises its own object and
/// reads the locale without a QueryInterface. For any other interface the library asks for IOPCCommon
/// first (one QueryInterface and Release). A server that aggregates the session keeps the inner
/// IUnknown from `OpcCommonCreate` and passes that, not an IOPCCommon pointer: every interface of an
/// aggregated object but its inner IUnknown counts its references on the outer object, so a kept
/// IOPCCommon pointer would keep the server object alive for ever. OpcCommonOptions::locale_changed
/// tells a server of every change without a call.
///
/// # Parameters
/// - `common`: any interface of the session, as for `OpcCommonGetClientName`.
/// - `locale` (out): receives the locale, or 0 on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for NULL arguments or an object that is not an IOPCCommon of this library.
///
/// # Safety
/// `common` must be NULL or a valid COM interface pointer; `locale` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcCommonGetLocale(common: *mut IUnknown, locale: *mut LCID) -> Hr {
    ffi::boundary!(Opc, [locale], {
        // SAFETY: the caller vouches a non-NULL out-parameter is writable.
        let out = unsafe { ffi::out(locale) }?;
        let common = ffi::in_ptr(common)?;
        // The cheap form: the session's own IOPCCommon pointer.
        let own = common.as_ptr().cast::<IOPCCommon>();
        // SAFETY: `common` is a valid COM pointer per the contract.
        let own = unsafe { ComObject::<OpcCommon>::from_foreign(own, &IOPCCOMMON_VTBL) };
        if let Some(obj) = own {
            out.write(obj.locale.load(Ordering::Relaxed));
            return Ok(S_OK);
        }
        // SAFETY: `common` is a valid COM pointer per the contract.
        let iface = unsafe { crate::com::unknown::query::<IOPCCommon>(common.as_ptr(), &IID_IOPCCommon) }
            .map_err(|_| E_INVALIDARG)?;
        // SAFETY: `iface` is a valid IOPCCommon pointer, ours or not; it stays counted meanwhile.
        let result = match unsafe { ComObject::<OpcCommon>::from_foreign(iface.as_ptr(), &IOPCCOMMON_VTBL) } {
            Some(obj) => Ok(obj.locale.load(Ordering::Relaxed)),
            None => Err(E_INVALIDARG),
        };
        drop(iface);
        out.write(result?);
        Ok(S_OK)
    })
}

#[cfg(test)]
mod tests;
