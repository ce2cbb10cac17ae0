//! Locale identifiers: the special values every OPC client uses and how the library resolves them.
//! Shared infrastructure: IOPCCommon (`common`) keeps a session's locale with it, the error texts
//! (`errors`) resolve it to the language they answer in; neither depends on the other for it.
//!
//! | LCID | name | meaning in this library |
//! |---|---|---|
//! | 0x0800 | LOCALE_SYSTEM_DEFAULT | the default of every session; texts in the system's language |
//! | 0x0400 | LOCALE_USER_DEFAULT | texts in the user's language |
//! | 0x0000 | LOCALE_NEUTRAL | English texts (en-US, 0x0409) |
//! | 0x007F | LOCALE_INVARIANT | English texts (en-US, 0x0409) |
//!
//! These four are always available. On Windows the system and user defaults are the system's
//! (GetSystemDefaultLCID / GetUserDefaultLCID). Elsewhere a process has no separate system locale, so
//! both are the locale of the process's messages as POSIX defines it: the first non-empty of the
//! environment variables `LC_ALL`, `LC_MESSAGES` and `LANG` (for example `de_DE.UTF-8` -> de-DE, 0x0407),
//! read once, at the first resolution; unset, `C`, `POSIX` or a language without a Windows locale ID in
//! the table below resolve to en-US. Any other LCID is taken as it is: its primary language picks the
//! texts, and languages without texts get English; other locales with a neutral primary language
//! (such as LOCALE_CUSTOM_DEFAULT, 0x0C00) are en-US.

use crate::com::LCID;

/// The system's default locale (a session starts with it).
#[cfg(not(system_com_headers))]
pub const LOCALE_SYSTEM_DEFAULT: LCID = 0x0800;
/// The user's default locale.
#[cfg(not(system_com_headers))]
pub const LOCALE_USER_DEFAULT: LCID = 0x0400;
/// The neutral locale.
#[cfg(not(system_com_headers))]
pub const LOCALE_NEUTRAL: LCID = 0x0000;
/// The invariant locale (English texts).
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

/// A language, by Windows primary language ID.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) struct Language(pub u16);

impl Language {
    /// The language texts fall back to.
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
#[inline]
pub(crate) fn resolve_locale(lcid: LCID) -> Resolved {
    let concrete = match lcid {
        LOCALE_SYSTEM_DEFAULT => system_default_locale(),
        LOCALE_USER_DEFAULT => user_default_locale(),
        LOCALE_NEUTRAL | LOCALE_INVARIANT => LOCALE_EN_US,
        other => other,
    };
    // Other locales with a neutral primary language (LOCALE_CUSTOM_DEFAULT 0x0C00 and the like) are
    // English too, so callers always see a concrete locale.
    let concrete = if Language::of(concrete).0 == 0 {
        LOCALE_EN_US
    } else {
        concrete
    };
    Resolved {
        lcid: concrete,
        language: Language::of(concrete),
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
    environment_locale()
}

#[cfg(not(windows))]
fn user_default_locale() -> LCID {
    environment_locale()
}

/// The locale of the process's messages (LC_ALL, LC_MESSAGES, LANG), read once.
#[cfg(not(windows))]
fn environment_locale() -> LCID {
    static LOCALE: std::sync::OnceLock<LCID> = std::sync::OnceLock::new();
    *LOCALE.get_or_init(|| {
        let name = ["LC_ALL", "LC_MESSAGES", "LANG"]
            .iter()
            .filter_map(|var| std::env::var(var).ok())
            .find(|value| !value.is_empty());
        name.and_then(|n| lcid_from_posix(&n)).unwrap_or(LOCALE_EN_US)
    })
}

/// Windows locale IDs of POSIX locale names: `language_TERRITORY` first, then the language alone.
#[cfg(any(not(windows), test))]
static POSIX_LOCALES: &[(&str, LCID)] = &[
    ("en_US", 0x0409),
    ("en_GB", 0x0809),
    ("en_AU", 0x0C09),
    ("en_CA", 0x1009),
    ("en_IE", 0x1809),
    ("en", 0x0409),
    ("de_DE", 0x0407),
    ("de_CH", 0x0807),
    ("de_AT", 0x0C07),
    ("de_LU", 0x1007),
    ("de_LI", 0x1407),
    ("de", 0x0407),
    ("fr_FR", 0x040C),
    ("fr_BE", 0x080C),
    ("fr_CA", 0x0C0C),
    ("fr_CH", 0x100C),
    ("fr", 0x040C),
    ("it_IT", 0x0410),
    ("it_CH", 0x0810),
    ("it", 0x0410),
    ("es", 0x0C0A),
    ("nl_BE", 0x0813),
    ("nl", 0x0413),
    ("pt_BR", 0x0416),
    ("pt", 0x0816),
    ("da", 0x0406),
    ("sv", 0x041D),
    ("nb", 0x0414),
    ("fi", 0x040B),
    ("pl", 0x0415),
    ("cs", 0x0405),
    ("hu", 0x040E),
    ("ru", 0x0419),
    ("tr", 0x041F),
    ("ja", 0x0411),
    ("ko", 0x0412),
    ("zh_TW", 0x0404),
    ("zh", 0x0804),
];

/// The Windows locale ID of a POSIX locale name such as `de_AT.UTF-8@euro`; `None` for `C`, `POSIX`
/// and languages the table does not know.
#[cfg(any(not(windows), test))]
fn lcid_from_posix(name: &str) -> Option<LCID> {
    let base = name.split(['.', '@']).next().unwrap_or("");
    let language = base.split('_').next().unwrap_or("");
    POSIX_LOCALES
        .iter()
        .find(|(n, _)| *n == base)
        .or_else(|| POSIX_LOCALES.iter().find(|(n, _)| *n == language))
        .map(|(_, lcid)| *lcid)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neutral_and_invariant_are_english() {
        assert_eq!(resolve_locale(LOCALE_NEUTRAL).language, Language::ENGLISH);
        assert_eq!(resolve_locale(LOCALE_NEUTRAL).lcid, LOCALE_EN_US);
        assert_eq!(resolve_locale(LOCALE_INVARIANT).language, Language::ENGLISH);
        assert_eq!(resolve_locale(0x0407).language, Language(0x07));
        assert_eq!(resolve_locale(0x0C07).language, Language(0x07));
        assert_eq!(resolve_locale(0x0407).lcid, 0x0407);
        assert_eq!(resolve_locale(0x10407).language, Language(0x07)); // German, phone book sort
        assert_eq!(resolve_locale(0x0C00).lcid, LOCALE_EN_US);
    }

    #[test]
    fn defaults_resolve_to_a_concrete_locale() {
        for special in [LOCALE_SYSTEM_DEFAULT, LOCALE_USER_DEFAULT] {
            let r = resolve_locale(special);
            assert!(!SPECIAL_LOCALES.contains(&r.lcid));
            assert_ne!(r.language.0, 0);
        }
    }

    #[test]
    fn posix_names_map_to_windows_locales() {
        assert_eq!(lcid_from_posix("de_DE.UTF-8"), Some(0x0407));
        assert_eq!(lcid_from_posix("de_AT.UTF-8@euro"), Some(0x0C07));
        assert_eq!(lcid_from_posix("de_BE"), Some(0x0407));
        assert_eq!(lcid_from_posix("en_GB.utf8"), Some(0x0809));
        assert_eq!(lcid_from_posix("fr"), Some(0x040C));
        assert_eq!(lcid_from_posix("C"), None);
        assert_eq!(lcid_from_posix("C.UTF-8"), None);
        assert_eq!(lcid_from_posix("POSIX"), None);
        assert_eq!(lcid_from_posix(""), None);
    }
}
