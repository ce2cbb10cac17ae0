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

/// One catalog text.
#[derive(Debug)]
pub(crate) struct Entry {
    pub code: u32,
    pub spec: Spec,
    /// The name in the specification's header and the text as UTF-8: for tests and debuggers.
    #[cfg_attr(not(test), allow(dead_code))]
    pub symbol: &'static str,
    #[cfg_attr(not(test), allow(dead_code))]
    pub text: &'static str,
    /// `text` as UTF-16 including the terminating NUL.
    pub wide: &'static [u16],
}

include!(concat!(env!("OUT_DIR"), "/catalog.rs"));

/// The catalog of every language the library ships. English is complete; the others fall back to it
/// text by text.
pub(crate) static LANGUAGES: &[(Language, &[Entry])] = &[(Language::ENGLISH, ENGLISH), (Language::GERMAN, GERMAN)];

/// The entries for `code` in `table` (several where specifications collide).
fn entries(table: &'static [Entry], code: u32) -> &'static [Entry] {
    let start = table.partition_point(|e| e.code < code);
    let end = start + table[start..].partition_point(|e| e.code == code);
    &table[start..end]
}

/// Which specification's text `code` gets for a server of specification `preferred`: its own where it
/// defines the code, otherwise the first in specification order (Data Access first).
pub(crate) fn spec_of(code: u32, preferred: Spec) -> Option<Spec> {
    let candidates = entries(ENGLISH, code);
    candidates
        .iter()
        .find(|e| e.spec == preferred)
        .or_else(|| candidates.first())
        .map(|e| e.spec)
}

/// The text of (`code`, `spec`) in `language`, falling back to English.
pub(crate) fn text(code: u32, spec: Spec, language: Language) -> Option<&'static Entry> {
    let in_table = |table: &'static [Entry]| entries(table, code).iter().find(|e| e.spec == spec);
    LANGUAGES
        .iter()
        .find(|(l, _)| *l == language)
        .and_then(|(_, table)| in_table(table))
        .or_else(|| in_table(ENGLISH))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_sorted_and_texts_terminated() {
        for (_, table) in LANGUAGES {
            assert!(table
                .windows(2)
                .all(|w| (w[0].code, w[0].spec) < (w[1].code, w[1].spec)));
            for e in table.iter() {
                let units: Vec<u16> = e.text.encode_utf16().chain([0]).collect();
                assert_eq!(e.wide, &units[..], "{}", e.symbol);
            }
        }
    }

    #[test]
    fn german_translates_every_english_text() {
        for e in ENGLISH {
            let de = text(e.code, e.spec, Language::GERMAN).unwrap();
            assert!(
                GERMAN.iter().any(|g| g.code == e.code && g.spec == e.spec),
                "{} untranslated",
                e.symbol
            );
            assert_ne!(de.text, e.text, "{} is not German", e.symbol);
        }
    }

    #[test]
    fn colliding_codes_follow_the_server_kind() {
        assert_eq!(spec_of(0xC0040203, Spec::DataAccess), Some(Spec::DataAccess));
        assert_eq!(spec_of(0xC0040203, Spec::AlarmsEvents), Some(Spec::AlarmsEvents));
        assert_eq!(spec_of(0xC0040203, Spec::HistoricalData), Some(Spec::DataAccess));
        assert_eq!(spec_of(0x00040200, Spec::DataAccess), Some(Spec::AlarmsEvents));
        assert_eq!(spec_of(0x12345678, Spec::DataAccess), None);
    }

    #[test]
    fn missing_languages_fall_back_to_english() {
        let fr = text(0xC0040001, Spec::DataAccess, Language(0x0C)).unwrap();
        assert_eq!(fr.text, "The value of the handle is invalid.");
        let de = text(0xC0040001, Spec::DataAccess, Language::GERMAN).unwrap();
        assert_eq!(de.text, "Der Wert des Handles ist ungültig.");
    }
}
