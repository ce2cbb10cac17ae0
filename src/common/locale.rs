//! Locale identifiers: the special values every OPC client uses and how the library resolves them.
//!
//! | LCID | name | meaning in this library |
//! |---|---|---|
//! | 0x0800 | LOCALE_SYSTEM_DEFAULT | the default of every session; texts in the system's language |
//! | 0x0400 | LOCALE_USER_DEFAULT | texts in the user's language |
//! | 0x0000 | LOCALE_NEUTRAL | English texts |
//! | 0x007F | LOCALE_INVARIANT | English texts |
//!
//! These four are always available. On Windows the system and user defaults are asked of the system;
//! elsewhere both resolve to English (en-US, 0x0409).

use crate::com::LCID;

#[cfg(not(system_com_headers))]
pub const LOCALE_SYSTEM_DEFAULT: LCID = 0x0800;
#[cfg(not(system_com_headers))]
pub const LOCALE_USER_DEFAULT: LCID = 0x0400;
#[cfg(not(system_com_headers))]
pub const LOCALE_NEUTRAL: LCID = 0x0000;
#[cfg(not(system_com_headers))]
pub const LOCALE_INVARIANT: LCID = 0x007F;
/// English (United States).
pub(crate) const LOCALE_EN_US: LCID = 0x0409;

/// The special locale IDs every session accepts, in the order QueryAvailableLocaleIDs reports them.
pub(crate) const SPECIAL_LOCALES: [LCID; 4] = [
    LOCALE_SYSTEM_DEFAULT,
    LOCALE_USER_DEFAULT,
    LOCALE_NEUTRAL,
    LOCALE_INVARIANT,
];

/// The locales a server supports when it declares none: the languages the catalog ships.
pub(crate) const DEFAULT_LOCALES: [LCID; 1] = [LOCALE_EN_US];

/// A language of the error catalog, by Windows primary language ID.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) struct Language(pub u16);

impl Language {
    pub(crate) const ENGLISH: Language = Language(0x09);

    /// The primary language of a concrete locale (`PRIMARYLANGID(LANGIDFROMLCID(lcid))`).
    pub fn of(lcid: LCID) -> Language {
        Language((lcid & 0x3FF) as u16)
    }
}

/// A session locale turned into the concrete locale and language texts are given in.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) struct Resolved {
    pub lcid: LCID,
    pub language: Language,
}

/// Resolves the special locale IDs to concrete ones (see the module table).
pub(crate) fn resolve_locale(lcid: LCID) -> Resolved {
    let concrete = match lcid {
        LOCALE_SYSTEM_DEFAULT => system_default_locale(),
        LOCALE_USER_DEFAULT => user_default_locale(),
        LOCALE_NEUTRAL | LOCALE_INVARIANT => LOCALE_EN_US,
        other => other,
    };
    let language = Language::of(concrete);
    // Neutral primary languages (0) resolve to English too.
    let language = if language.0 == 0 { Language::ENGLISH } else { language };
    Resolved {
        lcid: concrete,
        language,
    }
}

#[cfg(windows)]
fn system_default_locale() -> LCID {
    // SAFETY: no arguments; always succeeds.
    unsafe { windows_sys::Win32::Globalization::GetSystemDefaultLCID() }
}

#[cfg(windows)]
fn user_default_locale() -> LCID {
    // SAFETY: no arguments; always succeeds.
    unsafe { windows_sys::Win32::Globalization::GetUserDefaultLCID() }
}

#[cfg(not(windows))]
fn system_default_locale() -> LCID {
    LOCALE_EN_US
}

#[cfg(not(windows))]
fn user_default_locale() -> LCID {
    LOCALE_EN_US
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neutral_and_invariant_are_english() {
        assert_eq!(resolve_locale(LOCALE_NEUTRAL).language, Language::ENGLISH);
        assert_eq!(resolve_locale(LOCALE_INVARIANT).language, Language::ENGLISH);
        assert_eq!(resolve_locale(0x0407).language, Language(0x07));
        assert_eq!(resolve_locale(0x0407).lcid, 0x0407);
    }
}
