//! The error text catalog as static tables, one per language.
//!
//! The texts live in `catalog/<language>.txt` (one line per code, reviewed and extended as text); the
//! build script turns each file into a table of this module, sorted by code, with the UTF-16 form of
//! every text ready to copy. The same files feed the message table of the Windows DLL.
//!
//! Which specifications and languages there are, and the hash of the code index, is said once, in
//! `catalog/tables.rs`, which the build script compiles too.

use crate::com::LCID;
use crate::locale::Language;

mod tables;

pub use tables::OpcServerKind;
pub(crate) use tables::Spec;
use tables::{primary_language, slot_of, INDEX_BITS, LANGUAGES};

/// A text in UTF-8 (for tests and debuggers) and in UTF-16 with its terminating NUL (to copy).
#[derive(Debug)]
pub(crate) struct Text {
    #[cfg_attr(not(test), allow(dead_code))]
    pub text: &'static str,
    pub wide: &'static [u16],
}

/// One English catalog entry.
#[derive(Debug)]
pub(crate) struct Entry {
    pub code: u32,
    pub spec: Spec,
    /// The name in the specification's header.
    pub symbol: &'static str,
    pub text: Text,
}

include!(concat!(env!("OUT_DIR"), "/catalog.rs"));

/// The locales a server supports when it declares none: one per language of the catalog.
pub(crate) const CATALOG_LOCALES: [LCID; LANGUAGES.len()] = {
    let mut locales = [0; LANGUAGES.len()];
    let mut i = 0;
    while i < LANGUAGES.len() {
        locales[i] = LANGUAGES[i].lcid;
        i += 1;
    }
    locales
};

/// The translation table of `language` (parallel to ENGLISH), if the catalog has that language.
fn translation(language: Language) -> Option<&'static [Option<Text>]> {
    let position = LANGUAGES[1..]
        .iter()
        .position(|l| primary_language(l.lcid) == language.0)?;
    Some(TRANSLATIONS[position])
}

/// A code's catalog entry as one kind of server means it (an index into ENGLISH).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) struct Found(usize);

impl Found {
    /// The specification whose text this is (the system's texts are preferred on Windows).
    #[cfg_attr(not(any(windows, test)), allow(dead_code))]
    pub fn spec(self) -> Spec {
        ENGLISH[self.0].spec
    }

    /// The name of the code in its specification's header (`OPC_E_INVALIDHANDLE`).
    pub fn symbol(self) -> &'static str {
        ENGLISH[self.0].symbol
    }

    /// The text in `language`, or in English where the language has none.
    pub fn text(self, language: Language) -> &'static Text {
        self.text_in(language).unwrap_or(&ENGLISH[self.0].text)
    }

    /// The text in `language` if the catalog has it in that language.
    pub fn text_in(self, language: Language) -> Option<&'static Text> {
        if language == Language::ENGLISH {
            return Some(&ENGLISH[self.0].text);
        }
        translation(language).and_then(|table| table[self.0].as_ref())
    }
}

/// The entry `code` gets for a server of specification `preferred`: its own where it defines the code,
/// otherwise the first in specification order (Data Access first). One hash probe, usually.
#[inline]
pub(crate) fn lookup(code: u32, preferred: Spec) -> Option<Found> {
    let mask = (1usize << INDEX_BITS) - 1;
    let mut slot = slot_of(code);
    let first = loop {
        match INDEX[slot] {
            0 => return None,
            i if ENGLISH[usize::from(i) - 1].code == code => break usize::from(i) - 1,
            _ => slot = (slot + 1) & mask,
        }
    };
    let same_code = ENGLISH[first..].iter().take_while(|e| e.code == code);
    let own = same_code.clone().position(|e| e.spec == preferred).unwrap_or(0);
    Some(Found(first + own))
}

/// The codes `spec` publishes, in ascending order (each once).
pub(crate) fn codes_of(spec: Spec) -> impl Iterator<Item = u32> {
    ENGLISH.iter().filter(move |e| e.spec == spec).map(|e| e.code)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_sorted_and_texts_terminated() {
        assert!(ENGLISH
            .windows(2)
            .all(|w| (w[0].code, w[0].spec) < (w[1].code, w[1].spec)));
        let texts = ENGLISH
            .iter()
            .map(|e| &e.text)
            .chain(TRANSLATIONS.iter().flat_map(|t| t.iter().flatten()));
        // Under Miri one text in 61 (encoding them all takes minutes there).
        for t in texts.step_by(if cfg!(miri) { 61 } else { 1 }) {
            let units: Vec<u16> = t.text.encode_utf16().chain([0]).collect();
            assert_eq!(t.wide, &units[..], "{}", t.text);
        }
    }

    #[test]
    fn every_code_is_found_through_the_index() {
        for (i, e) in ENGLISH.iter().enumerate() {
            let found = lookup(e.code, e.spec).unwrap();
            assert_eq!(found, Found(i), "{}", e.symbol);
        }
        assert_eq!(lookup(0x12345678, Spec::DataAccess), None);
        assert_eq!(lookup(0xC0040002, Spec::DataAccess), None);
    }

    const GERMAN: Language = Language(0x07);

    #[test]
    fn german_translates_every_english_text() {
        let german = translation(GERMAN).expect("German is a catalog language");
        for (i, e) in ENGLISH.iter().enumerate() {
            let de = german[i]
                .as_ref()
                .unwrap_or_else(|| panic!("{} untranslated", e.symbol));
            assert_ne!(de.text, e.text.text, "{} is not German", e.symbol);
            assert_eq!(Found(i).text(GERMAN).text, de.text);
        }
    }

    #[test]
    fn the_tables_derive_from_one_list() {
        // Every catalog language has a translation table (English is ENGLISH) and a default locale.
        assert_eq!(TRANSLATIONS.len() + 1, LANGUAGES.len());
        assert_eq!(CATALOG_LOCALES, [0x0409, 0x0407]);
        assert_eq!(primary_language(LANGUAGES[0].lcid), Language::ENGLISH.0);
        assert!(translation(Language::ENGLISH).is_none() && translation(Language(0x0C)).is_none());
        // Every server kind, and no other value, selects the specification of the same name.
        let kinds: Vec<(u32, Spec)> = (0..64)
            .filter_map(|v| OpcServerKind::from_raw(v).map(|k| (k as u32, k.spec())))
            .collect();
        assert_eq!(
            kinds,
            [
                (0, Spec::DataAccess),
                (1, Spec::AlarmsEvents),
                (2, Spec::HistoricalData),
                (3, Spec::Batch),
                (4, Spec::DataExchange),
                (5, Spec::CommandExecution),
            ]
        );
        for (v, spec) in kinds {
            assert_eq!(
                format!("{:?}", OpcServerKind::from_raw(v).unwrap()),
                format!("{spec:?}")
            );
        }
    }

    #[test]
    fn colliding_codes_follow_the_server_kind() {
        let spec = |code, preferred| lookup(code, preferred).map(Found::spec);
        assert_eq!(spec(0xC0040203, Spec::DataAccess), Some(Spec::DataAccess));
        assert_eq!(spec(0xC0040203, Spec::AlarmsEvents), Some(Spec::AlarmsEvents));
        assert_eq!(spec(0xC0040203, Spec::HistoricalData), Some(Spec::DataAccess));
        assert_eq!(spec(0x00040200, Spec::DataAccess), Some(Spec::AlarmsEvents));
        assert_eq!(spec(0x12345678, Spec::DataAccess), None);
    }

    #[test]
    fn codes_of_a_specification_are_its_own_sorted() {
        let da: Vec<u32> = codes_of(Spec::DataAccess).collect();
        assert!(da.windows(2).all(|w| w[0] < w[1]));
        assert!(da.contains(&0xC0040001) && da.contains(&0xC0040203) && da.contains(&0x0004040B));
        // The Alarms & Events meaning of C0040203 is not a Data Access code, and vice versa.
        assert!(!da.contains(&0x00040200));
        let ae: Vec<u32> = codes_of(Spec::AlarmsEvents).collect();
        assert!(ae.contains(&0xC0040203) && ae.contains(&0x00040200) && !ae.contains(&0xC0040001));
        assert_eq!(
            lookup(0xC0040203, Spec::AlarmsEvents).map(Found::symbol),
            Some("OPC_E_INVALIDBRANCHNAME")
        );
        assert_eq!(
            lookup(0xC0040203, Spec::DataAccess).map(Found::symbol),
            Some("OPC_E_INVALID_PID")
        );
    }

    #[test]
    fn missing_languages_fall_back_to_english() {
        let found = lookup(0xC0040001, Spec::DataAccess).unwrap();
        assert_eq!(found.text(Language(0x0C)).text, "The value of the handle is invalid.");
        assert_eq!(found.text(GERMAN).text, "Der Wert des Handles ist ungültig.");
        assert!(found.text_in(Language(0x0C)).is_none());
        assert_eq!(
            found.text_in(Language::ENGLISH).map(|t| t.text),
            Some("The value of the handle is invalid.")
        );
    }
}
