//! Error texts: `IOPCCommon::GetErrorString` and `OpcGetErrorString`.
//!
//! Lookup order: the server's own (vendor) callback, then the OPC catalog for the kind of server asking
//! (the same HRESULT means different things to a Data Access and an Alarms & Events server), then the
//! COM and system codes. Unknown codes fail with E_INVALIDARG, as the specification requires.

use core::ffi::c_void;
use core::ptr;

use crate::com::alloc::{alloc_wstr, alloc_wstr_from_str};
use crate::com::boundary::catch;
use crate::com::wstr::{wstr_units, MAX_STRING_UNITS};
use crate::com::{E_INVALIDARG, E_UNEXPECTED, HRESULT, LCID, LPCWSTR, LPWSTR, S_OK};
use crate::common::locale::{resolve_locale, Language};

mod en;

/// The kind of OPC server asking for a text; it decides which specification's text a colliding code
/// gets.
#[repr(u32)]
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub enum OpcServerKind {
    /// Data Access (and Complex Data): the default.
    #[default]
    DataAccess = 0,
    /// Alarms & Events.
    AlarmsEvents = 1,
    /// Historical Data Access.
    HistoricalData = 2,
}

impl OpcServerKind {
    /// The kind for a raw value from C; `None` for values this version does not know.
    pub fn from_raw(v: u32) -> Option<OpcServerKind> {
        match v {
            0 => Some(OpcServerKind::DataAccess),
            1 => Some(OpcServerKind::AlarmsEvents),
            2 => Some(OpcServerKind::HistoricalData),
            _ => None,
        }
    }
}

/// A server's own texts for its vendor-specific codes, asked before the catalog.
///
/// Called with the code and the resolved locale (never LOCALE_SYSTEM_DEFAULT or the like: the concrete
/// language). To answer, store a NUL-terminated string in `*text` and return S_OK; the library copies
/// it before the callback is called again, so a static string or one the server keeps is fine. Any
/// other return (S_FALSE to decline) lets the library look the code up itself. May be called from any
/// thread, concurrently.
pub type OpcVendorErrorStringFn =
    Option<unsafe extern "C" fn(context: *mut c_void, code: HRESULT, locale: LCID, text: *mut LPCWSTR) -> HRESULT>;

/// A vendor callback with its context pointer.
#[derive(Clone, Copy)]
pub(crate) struct VendorTexts {
    pub callback:
        unsafe extern "C" fn(context: *mut c_void, code: HRESULT, locale: LCID, text: *mut LPCWSTR) -> HRESULT,
    pub context: *mut c_void,
}

// SAFETY: the options contract says the callback may be called from any thread with its context.
unsafe impl Send for VendorTexts {}
// SAFETY: as above.
unsafe impl Sync for VendorTexts {}

impl VendorTexts {
    /// The vendor's text for `code`, copied into task memory, or `None` when the vendor declines.
    fn lookup(&self, code: HRESULT, locale: LCID) -> Option<Result<LPWSTR, HRESULT>> {
        let mut text: LPCWSTR = ptr::null();
        // SAFETY: the server registered this callback and context for exactly this call.
        let hr = unsafe { (self.callback)(self.context, code, locale, &mut text) };
        if hr != S_OK || text.is_null() {
            return None;
        }
        // SAFETY: the callback contract: a NUL-terminated string valid until it is called again.
        let units = unsafe { wstr_units(text, MAX_STRING_UNITS) }?;
        Some(alloc_wstr(units))
    }
}

/// The text for `code` as a new task-allocated string, for a session in `locale`.
pub(crate) fn error_string(
    code: HRESULT,
    locale: LCID,
    kind: OpcServerKind,
    vendor: Option<&VendorTexts>,
) -> Result<LPWSTR, HRESULT> {
    let resolved = resolve_locale(locale);
    if let Some(answer) = vendor.and_then(|v| v.lookup(code, resolved.lcid)) {
        return answer;
    }
    match catalog_text(code, kind, resolved.language) {
        Some(text) => alloc_wstr_from_str(text),
        None => Err(E_INVALIDARG),
    }
}

/// The catalog text for `code` in `language`, falling back to English.
pub(crate) fn catalog_text(code: HRESULT, kind: OpcServerKind, language: Language) -> Option<&'static str> {
    let _ = language; // only English ships so far; every language falls back to it
    en::text(code as u32, kind)
}

/// Returns the text for an OPC, COM or system error code in the given locale, for servers that
/// implement the locale-taking `GetErrorString` of their own interfaces (IOPCServer and others).
/// Texts are those of a Data Access server where codes collide.
///
/// `*ppString` receives a new string (free it with `OpcTaskMemFree`, or CoTaskMemFree on Windows), or
/// NULL on failure. Returns E_INVALIDARG for a NULL `ppString` or a code without a text.
///
/// # Safety
/// `ppString` must be NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcGetErrorString(code: HRESULT, locale: LCID, ppString: *mut LPWSTR) -> HRESULT {
    if ppString.is_null() {
        return E_INVALIDARG;
    }
    // SAFETY: checked non-NULL; the caller vouches it is writable.
    unsafe { *ppString = ptr::null_mut() };
    catch(E_UNEXPECTED, || {
        match error_string(code, locale, OpcServerKind::DataAccess, None) {
            Ok(p) => {
                // SAFETY: as above.
                unsafe { *ppString = p };
                S_OK
            }
            Err(hr) => hr,
        }
    })
}
