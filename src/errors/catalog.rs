//! The error text catalog as static tables, one per language.
//!
//! The texts live in `catalog/<language>.txt` (one line per code, reviewed and extended as text); the
//! build script turns each file into a table of this module, sorted by code, with the UTF-16 form of
//! every text ready to copy. The same files feed the message table of the Windows DLL.

use crate::common::locale::Language;

/// The specification that defines a code (the SPEC column of the catalog files).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug)]
pub(crate) enum Spec {
    DataAccess,
    AlarmsEvents,
    HistoricalData,
    Security,
    Batch,
    DataExchange,
    CommandExecution,
    /// COM codes of the OPC Common interfaces that the system has no (or a misleading) text for.
    Connection,
    /// COM, RPC and Win32 codes; on Windows the system's own text is preferred.
    System,
}

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
    #[cfg_attr(not(test), allow(dead_code))]
    pub symbol: &'static str,
    pub text: Text,
}

include!(concat!(env!("OUT_DIR"), "/catalog.rs"));

/// The translations the library ships, each parallel to ENGLISH; English is complete and every other
/// language falls back to it text by text.
static TRANSLATIONS: &[(Language, &[Option<Text>])] = &[(Language::GERMAN, GERMAN)];

/// A code's catalog entry as one kind of server means it (an index into ENGLISH).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) struct Found(usize);

impl Found {
    /// The specification whose text this is (the system's texts are preferred on Windows).
    #[cfg_attr(not(any(windows, test)), allow(dead_code))]
    pub fn spec(self) -> Spec {
        ENGLISH[self.0].spec
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
        TRANSLATIONS
            .iter()
            .find(|(l, _)| *l == language)
            .and_then(|(_, table)| table[self.0].as_ref())
    }
}

/// The entry `code` gets for a server of specification `preferred`: its own where it defines the code,
/// otherwise the first in specification order (Data Access first). One hash probe, usually.
pub(crate) fn lookup(code: u32, preferred: Spec) -> Option<Found> {
    let mask = (1usize << INDEX_BITS) - 1;
    let mut slot = (code.wrapping_mul(0x9E37_79B1) >> (32 - INDEX_BITS)) as usize;
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
            .chain(TRANSLATIONS.iter().flat_map(|(_, t)| t.iter().flatten()));
        for t in texts {
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

    #[test]
    fn german_translates_every_english_text() {
        for (i, e) in ENGLISH.iter().enumerate() {
            let de = GERMAN[i]
                .as_ref()
                .unwrap_or_else(|| panic!("{} untranslated", e.symbol));
            assert_ne!(de.text, e.text.text, "{} is not German", e.symbol);
            assert_eq!(Found(i).text(Language::GERMAN).text, de.text);
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
    fn missing_languages_fall_back_to_english() {
        let found = lookup(0xC0040001, Spec::DataAccess).unwrap();
        assert_eq!(found.text(Language(0x0C)).text, "The value of the handle is invalid.");
        assert_eq!(found.text(Language::GERMAN).text, "Der Wert des Handles ist ungültig.");
        assert!(found.text_in(Language(0x0C)).is_none());
        assert_eq!(
            found.text_in(Language::ENGLISH).map(|t| t.text),
            Some("The value of the handle is invalid.")
        );
    }
}
