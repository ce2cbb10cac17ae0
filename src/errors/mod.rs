//! Error texts: `IOPCCommon::GetErrorString`, `OpcGetErrorString` and `OpcGetErrorStringEx`.
//!
//! Lookup order (specification 5.1.4 and what OPC clients expect of it):
//! 1. the server's own callback for its vendor-specific codes, asked with the resolved locale;
//! 2. the OPC catalog (Data Access, Alarms & Events, HDA, Security, Batch, DX, Command Execution and
//!    the connection point codes), in the session's language, falling back to English text by text.
//!    Where one HRESULT means different things to different kinds of server (C0040203 is
//!    OPC_E_INVALID_PID to Data Access and OPC_E_INVALIDBRANCHNAME to Alarms & Events), the kind the
//!    server declared decides;
//! 3. system codes: on Windows the system's own text (FormatMessage, trailing line break removed) in
//!    the resolved language; if Windows lacks that language, the catalog's text in it; then the
//!    system's text in its own choice of language. On other platforms, and where Windows has no text,
//!    the catalog's Windows texts of the COM and RPC codes an OPC client meets.
//!
//! Codes without a text fail with E_INVALIDARG and a NULL string, as the specification requires.

use core::ffi::c_void;
use core::ptr;

use crate::com::alloc::{alloc_array, alloc_wstr, alloc_wstr_from_str, alloc_wstr_terminated};
use crate::com::ffi::{self, FfiResult, Hr};
use crate::com::wstr::{wstr_units, MAX_STRING_UNITS};
use crate::com::{DWORD, E_INVALIDARG, HRESULT, LCID, LPCWSTR, LPWSTR, S_OK};
use crate::locale::resolve_locale;
#[cfg(test)]
use crate::locale::Language;

mod catalog;
#[cfg(windows)]
mod system;

pub use catalog::OpcServerKind;
#[cfg(windows)]
use catalog::Spec;
pub(crate) use catalog::CATALOG_LOCALES;

/// A server's own texts for its vendor-specific codes, asked before the catalog. May be called from
/// any thread, concurrently.
///
/// # Parameters
/// - `context`: OpcCommonOptions::vendor_error_context.
/// - `code`: the error code the client asks about.
/// - `locale`: the resolved locale (never LOCALE_SYSTEM_DEFAULT or the like: the concrete locale, e.g.
///   0x0407).
/// - `text` (out): where to store the answer, a NUL-terminated string; the library copies it into task
///   memory before the callback is called again, so a static string or one the server keeps is fine.
///
/// # Returns
/// S_OK with `*text` set to answer; any other code (S_FALSE to decline) lets the library look the
/// code up itself.
pub type OpcVendorErrorStringFn =
    Option<unsafe extern "C" fn(context: *mut c_void, code: HRESULT, locale: LCID, text: *mut LPCWSTR) -> HRESULT>;

/// A server's own texts for its vendor-specific codes, handed over as task memory: the form for a
/// server that formats its texts into a new buffer (no thread-local storage, no lifetime to keep).
/// Called as `OpcVendorErrorStringFn`; may be called from any thread, concurrently.
///
/// # Parameters
/// - `context`: OpcCommonOptions::vendor_error_context.
/// - `code`: the error code the client asks about.
/// - `locale`: the resolved locale (the concrete locale, e.g. 0x0407).
/// - `text` (out): NULL on entry; where to store the answer, a NUL-terminated string allocated with
///   `OpcTaskMemAlloc` (CoTaskMemAlloc on Windows). A string stored here is the library's whatever the
///   return: it hands that very string to the client, or frees it when it does not use it (also when
///   it is longer than the library's string bound, 2^19 code units, which is then treated as
///   declined).
///
/// # Returns
/// S_OK with `*text` set to answer; any other code (S_FALSE to decline) lets the library look the
/// code up itself.
pub type OpcVendorErrorTextFn =
    Option<unsafe extern "C" fn(context: *mut c_void, code: HRESULT, locale: LCID, text: *mut LPWSTR) -> HRESULT>;

/// How a vendor callback answers: with a string the server keeps, or with task memory it hands over.
#[derive(Clone, Copy)]
pub(crate) enum VendorCallback {
    Borrowed(unsafe extern "C" fn(context: *mut c_void, code: HRESULT, locale: LCID, text: *mut LPCWSTR) -> HRESULT),
    Owned(unsafe extern "C" fn(context: *mut c_void, code: HRESULT, locale: LCID, text: *mut LPWSTR) -> HRESULT),
}

/// A vendor callback with its context pointer.
#[derive(Clone, Copy)]
pub(crate) struct VendorTexts {
    pub callback: VendorCallback,
    pub context: *mut c_void,
}

// SAFETY: the options contract says the callback may be called from any thread with its context.
unsafe impl Send for VendorTexts {}
// SAFETY: as above.
unsafe impl Sync for VendorTexts {}

impl VendorTexts {
    /// The vendor's text for `code`, copied into task memory, or `None` when the vendor declines.
    fn lookup(&self, code: HRESULT, locale: LCID) -> Option<Result<LPWSTR, HRESULT>> {
        match self.callback {
            VendorCallback::Borrowed(callback) => {
                let mut text: LPCWSTR = ptr::null();
                // SAFETY: the server registered this callback and context for exactly this call.
                let hr = unsafe { callback(self.context, code, locale, &mut text) };
                if hr != S_OK || text.is_null() {
                    return None;
                }
                // SAFETY: the callback contract: a NUL-terminated string valid until it is called again.
                let units = unsafe { wstr_units(text, MAX_STRING_UNITS) }?;
                Some(alloc_wstr(units))
            }
            VendorCallback::Owned(callback) => {
                let mut text: LPWSTR = ptr::null_mut();
                // SAFETY: the server registered this callback and context for exactly this call.
                let hr = unsafe { callback(self.context, code, locale, &mut text) };
                if text.is_null() {
                    return None;
                }
                // SAFETY: the callback contract: a NUL-terminated string in task memory, now ours.
                let fits = unsafe { wstr_units(text, MAX_STRING_UNITS) }.is_some();
                if hr == S_OK && fits {
                    return Some(Ok(text));
                }
                // SAFETY: the string is ours (see above) and not handed on.
                unsafe { crate::com::alloc::task_free(text.cast()) };
                None
            }
        }
    }
}

/// The text for `code` as a new task-allocated string, for a session in `locale`.
///
/// Inlined into GetErrorString: a catalog answer is a hash probe, one allocation and one copy, and the
/// calls between them would cost as much as the lookup.
#[inline(always)]
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
    let code = code as u32;
    let found = catalog::lookup(code, kind.spec());
    // On Windows system codes get the system's text in the session's language; where Windows lacks
    // that language, the catalog's text in it; then the system's text in its own choice of language.
    #[cfg(windows)]
    if found.is_none_or(|f| f.spec() == Spec::System) {
        let language = (resolved.lcid & 0xFFFF) as u16;
        if let Some(answer) = system::message(code, language) {
            return answer;
        }
        if let Some(text) = found.and_then(|f| f.text_in(resolved.language)) {
            return copy(text);
        }
        if let Some(answer) = system::message(code, 0) {
            return answer;
        }
    }
    match found {
        Some(found) => copy(found.text(resolved.language)),
        None => Err(E_INVALIDARG),
    }
}

/// A catalog text as a new task-allocated string: the table holds it with its NUL, copied in one go.
#[inline(always)]
fn copy(text: &catalog::Text) -> Result<LPWSTR, HRESULT> {
    alloc_wstr_terminated(text.wide)
}

/// The catalog text for `code` as a server of `kind` means it, in `language` (English where the
/// language has none); system texts are not consulted.
#[cfg(test)]
fn catalog_text(code: HRESULT, kind: OpcServerKind, language: Language) -> Option<&'static str> {
    catalog::lookup(code as u32, kind.spec()).map(|found| found.text(language).text)
}

/// Shared body of the exports: the text for `code` as a server of the raw `kind` means it.
fn export_text(code: HRESULT, locale: LCID, kind: u32) -> FfiResult<LPWSTR> {
    let kind = OpcServerKind::from_raw(kind).ok_or(E_INVALIDARG)?;
    Ok(error_string(code, locale, kind, None)?)
}

/// The text of an OPC, COM or system error code in a locale, for servers that implement the
/// locale-taking `GetErrorString` of their own interfaces (IOPCServer and others). Texts are those of
/// a Data Access server where codes collide; `OpcGetErrorStringEx` chooses.
///
/// # Parameters
/// - `code`: the error code.
/// - `locale`: a concrete LCID, or LOCALE_SYSTEM_DEFAULT, LOCALE_USER_DEFAULT, LOCALE_NEUTRAL or
///   LOCALE_INVARIANT.
/// - `text` (out): receives a new string (free it with `OpcTaskMemFree`, or CoTaskMemFree on
///   Windows), or NULL on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for a NULL `text` or a code without a text.
///
/// # Safety
/// `text` must be NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcGetErrorString(code: HRESULT, locale: LCID, text: *mut LPWSTR) -> Hr {
    ffi::boundary!(Opc, [text], {
        // SAFETY: the caller vouches a non-NULL `text` is writable.
        let out = unsafe { ffi::out(text) }?;
        out.write(export_text(code, locale, OpcServerKind::DataAccess as u32)?);
        Ok(S_OK)
    })
}

/// `OpcGetErrorString` for a given kind of server: an Alarms & Events server passes
/// OPC_SERVER_KIND_ALARMS_EVENTS so that C0040203 reads "The string was not recognized as an area
/// name." rather than the Data Access text.
///
/// # Parameters
/// - `code`: the error code.
/// - `locale`: as for `OpcGetErrorString`.
/// - `kind`: the kind of server (an `OpcServerKind` value).
/// - `text` (out): receives a new string (free it with `OpcTaskMemFree`), or NULL on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for an unknown `kind`, a NULL `text` or a code without a text.
///
/// # Safety
/// `text` must be NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcGetErrorStringEx(code: HRESULT, locale: LCID, kind: u32, text: *mut LPWSTR) -> Hr {
    ffi::boundary!(Opc, [text], {
        // SAFETY: the caller vouches a non-NULL `text` is writable.
        let out = unsafe { ffi::out(text) }?;
        out.write(export_text(code, locale, kind)?);
        Ok(S_OK)
    })
}

/// The error codes the specification of a kind of server publishes: the codes whose text that kind
/// of server answers with its own specification's text, in ascending order (as unsigned numbers:
/// success codes first). For a client or a test tool that checks a server's GetErrorString against
/// the published list: each code's standard English text is `OpcGetErrorStringEx(code, 0x0409, kind,
/// ...)`, its name `OpcErrorSymbol`. Data Access has 28 codes, Alarms & Events 8, Historical Data
/// Access 15.
///
/// # Parameters
/// - `kind`: the kind of server (an `OpcServerKind` value).
/// - `count` (out): receives the number of codes, or 0 on failure.
/// - `codes` (out): receives a new array of `*count` codes (free it with `OpcTaskMemFree`), or NULL
///   on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for an unknown `kind` or a NULL argument.
///
/// # Safety
/// `count` and `codes` must be NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcErrorCodesOfKind(kind: u32, count: *mut DWORD, codes: *mut *mut HRESULT) -> Hr {
    ffi::boundary!(Opc, [count, codes], {
        // SAFETY: the caller vouches non-NULL out-parameters are writable.
        let (count, array) = unsafe { (ffi::out(count)?, ffi::out(codes)?) };
        let kind = OpcServerKind::from_raw(kind).ok_or(E_INVALIDARG)?;
        let published: Vec<HRESULT> = catalog::codes_of(kind.spec()).map(|c| c as HRESULT).collect();
        array.write(alloc_array(&published)?);
        count.write(published.len() as DWORD);
        Ok(S_OK)
    })
}

/// The name of an error code as the header of its specification spells it (`OPC_E_INVALIDHANDLE`,
/// `CONNECT_E_NOCONNECTION`, `E_INVALIDARG`), for a server of a kind: C0040203 is
/// `OPC_E_INVALID_PID` to Data Access and `OPC_E_INVALIDBRANCHNAME` to Alarms & Events.
///
/// # Parameters
/// - `code`: the error code.
/// - `kind`: the kind of server (an `OpcServerKind` value).
/// - `symbol` (out): receives a new string (free it with `OpcTaskMemFree`), or NULL on failure.
///
/// # Returns
/// S_OK; E_INVALIDARG for an unknown `kind`, a code the catalog does not have or a NULL `symbol`.
///
/// # Safety
/// `symbol` must be NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn OpcErrorSymbol(code: HRESULT, kind: u32, symbol: *mut LPWSTR) -> Hr {
    ffi::boundary!(Opc, [symbol], {
        // SAFETY: the caller vouches a non-NULL `symbol` is writable.
        let out = unsafe { ffi::out(symbol) }?;
        let kind = OpcServerKind::from_raw(kind).ok_or(E_INVALIDARG)?;
        let found = catalog::lookup(code as u32, kind.spec()).ok_or(E_INVALIDARG)?;
        out.write(alloc_wstr_from_str(found.symbol())?);
        Ok(S_OK)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::com::alloc::task_free;

    /// The codes of `kind` through the export, or its failure (with the out-parameters checked).
    fn codes(kind: u32) -> Result<Vec<u32>, HRESULT> {
        let (mut count, mut array): (DWORD, *mut HRESULT) = (7, 1 as *mut HRESULT);
        // SAFETY: both out-parameters are writable.
        let hr = unsafe { OpcErrorCodesOfKind(kind, &mut count, &mut array) };
        if hr != S_OK {
            assert!(count == 0 && array.is_null());
            return Err(hr.get());
        }
        // SAFETY: S_OK gives a task array of `count` codes, freed once here.
        unsafe {
            let v = core::slice::from_raw_parts(array, count as usize)
                .iter()
                .map(|&c| c as u32)
                .collect();
            task_free(array.cast());
            Ok(v)
        }
    }

    fn symbol(code: u32, kind: u32) -> Result<String, HRESULT> {
        let mut p: LPWSTR = 1 as LPWSTR;
        // SAFETY: `p` is writable.
        let hr = unsafe { OpcErrorSymbol(code as HRESULT, kind, &mut p) };
        if hr != S_OK {
            assert!(p.is_null());
            return Err(hr.get());
        }
        // SAFETY: S_OK gives a NUL-terminated task string, freed once here.
        unsafe {
            let s = String::from_utf16(wstr_units(p, MAX_STRING_UNITS).unwrap()).unwrap();
            task_free(p.cast());
            Ok(s)
        }
    }

    #[test]
    fn published_codes_of_each_kind() {
        let da = codes(OpcServerKind::DataAccess as u32).unwrap();
        let ae = codes(OpcServerKind::AlarmsEvents as u32).unwrap();
        let hda = codes(OpcServerKind::HistoricalData as u32).unwrap();
        assert_eq!((da.len(), ae.len(), hda.len()), (28, 8, 15));
        // Ascending as unsigned numbers: the success codes (OPC_S_UNSUPPORTEDRATE) come first.
        assert_eq!((da[0], *da.last().unwrap()), (0x0004000D, 0xC004040A));
        assert!(da.windows(2).all(|w| w[0] < w[1]));
        assert!(ae.contains(&0xC0040203) && ae.contains(&0x00040200));
        assert!(hda.contains(&0x40041002) && hda.contains(&0x80041007));
        // Every published code has the kind's own text and a symbol; other kinds' codes are absent.
        for &c in &da {
            assert!(get(c, 0x0409, 0).is_ok(), "{c:08X}");
            assert!(symbol(c, 0).unwrap().starts_with("OPC"), "{c:08X}");
        }
        assert_eq!(
            get(0xC0040203, 0x0409, 1).unwrap(),
            "The string was not recognized as an area name."
        );
        assert_eq!(symbol(0xC0040203, 1).unwrap(), "OPC_E_INVALIDBRANCHNAME");
        assert_eq!(symbol(0xC0040203, 0).unwrap(), "OPC_E_INVALID_PID");
        assert_eq!(symbol(0x80040200, 0).unwrap(), "CONNECT_E_NOCONNECTION");
        assert_eq!(codes(99), Err(E_INVALIDARG));
        assert_eq!(symbol(0xC0040001, 99), Err(E_INVALIDARG));
        assert_eq!(symbol(0x12345678, 0), Err(E_INVALIDARG));
        // NULL out-parameters: E_INVALIDARG, the other one still reset.
        let mut count: DWORD = 5;
        // SAFETY: `count` is writable; NULL is allowed.
        let hr = unsafe { OpcErrorCodesOfKind(0, &mut count, ptr::null_mut()) };
        assert_eq!((hr.get(), count), (E_INVALIDARG, 0));
        // SAFETY: NULL is allowed.
        let hr = unsafe { OpcErrorSymbol(0xC0040001u32 as HRESULT, 0, ptr::null_mut()) };
        assert_eq!(hr, E_INVALIDARG);
    }

    fn get(code: u32, locale: LCID, kind: u32) -> Result<String, HRESULT> {
        let mut p: LPWSTR = core::ptr::null_mut::<u16>().wrapping_byte_add(1); // garbage: the function must overwrite it
                                                                               // SAFETY: `p` is writable.
        let hr = unsafe { OpcGetErrorStringEx(code as HRESULT, locale, kind, &mut p) };
        if hr != S_OK {
            assert!(p.is_null());
            return Err(hr.get());
        }
        // SAFETY: S_OK gives a NUL-terminated task string, freed once here.
        unsafe {
            let units = wstr_units(p, MAX_STRING_UNITS).unwrap();
            let s = String::from_utf16(units).unwrap();
            task_free(p.cast());
            Ok(s)
        }
    }

    #[test]
    fn collisions_answer_as_the_kind_of_server_asks() {
        assert_eq!(
            get(0xC0040203, 0x0409, 0).unwrap(),
            "The specified property ID is not valid for the item."
        );
        assert_eq!(
            get(0xC0040203, 0x0409, 1).unwrap(),
            "The string was not recognized as an area name."
        );
        assert_eq!(
            get(0xC0040203, 0x0407, 1).unwrap(),
            "Die Zeichenfolge wurde nicht als Bereichsname erkannt."
        );
        assert_eq!(
            get(0x00040200, 0x0409, 0).unwrap(),
            "The condition has already been acknowleged."
        );
    }

    #[test]
    fn unknown_codes_kinds_and_null_out_pointers_are_invalid_arguments() {
        assert_eq!(get(0xC004FFFF, 0x0409, 0), Err(E_INVALIDARG));
        assert_eq!(get(0xC0040001, 0x0409, 6), Err(E_INVALIDARG));
        // SAFETY: NULL is the point of the test.
        let hr = unsafe { OpcGetErrorString(0xC0040001_u32 as HRESULT, 0x0409, ptr::null_mut()) };
        assert_eq!(hr, E_INVALIDARG);
    }

    #[test]
    fn languages_without_texts_get_english() {
        assert_eq!(
            get(0xC0040001, 0x040C, 0).unwrap(),
            "The value of the handle is invalid."
        );
        assert_eq!(
            get(0xC0040001, 0x0C07, 0).unwrap(),
            "Der Wert des Handles ist ungültig."
        );
        assert_eq!(
            get(0xC0040001, 0x0000, 0).unwrap(),
            "The value of the handle is invalid."
        );
        assert_eq!(
            get(0xC0040001, 0x007F, 0).unwrap(),
            "The value of the handle is invalid."
        );
    }

    #[test]
    fn catalog_texts_skip_the_system() {
        assert_eq!(
            catalog_text(0xC0040011_u32 as HRESULT, OpcServerKind::DataAccess, Language::ENGLISH),
            Some("The requested object (e.g. a public group) was not found.")
        );
        assert_eq!(
            catalog_text(0x80040200_u32 as HRESULT, OpcServerKind::DataAccess, Language(0x07)),
            Some("Für diese Verbindungs-ID besteht keine Verbindung.")
        );
    }

    #[cfg(not(windows))]
    #[test]
    fn com_codes_have_windows_texts_elsewhere() {
        assert_eq!(get(0x80070057, 0x0409, 0).unwrap(), "The parameter is incorrect.");
        assert_eq!(get(0x800706BA, 0x0409, 0).unwrap(), "The RPC server is unavailable.");
        assert_eq!(get(0x80070057, 0x0407, 0).unwrap(), "Falscher Parameter.");
    }

    unsafe extern "C" fn vendor(context: *mut c_void, code: HRESULT, locale: LCID, text: *mut LPCWSTR) -> HRESULT {
        static ANSWER: [u16; 4] = [0x56, 0x31, 0x21, 0]; // "V1!"
                                                         // SAFETY: the test passes a pointer to a live `Cell<LCID>` as context (a shared reference with
                                                         // interior mutability: the test reads the cell between calls while the library holds the
                                                         // pointer, which a pointer derived from `&mut` would not allow under Tree Borrows).
        unsafe { (*context.cast::<core::cell::Cell<LCID>>()).set(locale) };
        if code as u32 == 0xE0000001 {
            // SAFETY: `text` is the library's out-parameter.
            unsafe { *text = ANSWER.as_ptr() };
            return S_OK;
        }
        1 // S_FALSE: decline
    }

    #[test]
    fn vendor_callback_is_asked_first_with_the_resolved_locale() {
        let seen = core::cell::Cell::new(0 as LCID);
        let texts = VendorTexts {
            callback: VendorCallback::Borrowed(vendor),
            context: ptr::from_ref(&seen).cast_mut().cast(),
        };
        let p = error_string(
            0xE0000001_u32 as HRESULT,
            0x007F,
            OpcServerKind::DataAccess,
            Some(&texts),
        )
        .unwrap();
        // SAFETY: a NUL-terminated task string, freed once.
        unsafe {
            assert_eq!(wstr_units(p, 10).unwrap(), &[0x56, 0x31, 0x21]);
            task_free(p.cast());
        }
        assert_eq!(seen.get(), 0x0409);
        let p = error_string(
            0xC0040001_u32 as HRESULT,
            0x0407,
            OpcServerKind::DataAccess,
            Some(&texts),
        )
        .unwrap();
        assert_eq!(seen.get(), 0x0407);
        // SAFETY: as above.
        unsafe { task_free(p.cast()) };
        assert_eq!(
            error_string(
                0xE0000002_u32 as HRESULT,
                0x0409,
                OpcServerKind::DataAccess,
                Some(&texts)
            ),
            Err(E_INVALIDARG)
        );
    }
}
