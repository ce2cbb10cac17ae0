//! The error catalog: `src/errors/catalog/<language>.txt` (one file per language, reviewed as text)
//! becomes the static tables of `$OUT_DIR/catalog.rs`, included by `src/errors/catalog.rs`. Malformed or
//! inconsistent catalog lines fail the build with the file and line.
//!
//! The specifications, the languages and the index hash come from `src/errors/catalog/tables.rs`, the
//! file the library compiles as well.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

#[allow(dead_code)] // the library uses the rest of the tables
#[path = "../src/errors/catalog/tables.rs"]
mod tables;

pub(crate) use tables::{Spec, LANGUAGES, SPECS};

/// One catalog line.
pub struct Entry {
    pub code: u32,
    pub spec: Spec,
    pub symbol: String,
    pub text: String,
}

/// The catalogs of every language of [`LANGUAGES`], in its order (English first), after checking each
/// line and every translation against English; writes `$OUT_DIR/catalog.rs`.
pub fn build(manifest_dir: &Path, out_dir: &Path) -> Vec<Vec<Entry>> {
    let catalog_dir = manifest_dir.join("src/errors/catalog");
    println!("cargo:rerun-if-changed={}", catalog_dir.display());
    let catalogs: Vec<Vec<Entry>> = LANGUAGES
        .iter()
        .map(|language| parse(&catalog_dir.join(format!("{}.txt", language.file))))
        .collect();
    check_translations(&catalogs);
    fs::write(out_dir.join("catalog.rs"), generate_tables(&catalogs)).expect("write catalog.rs");
    catalogs
}

/// Reads one catalog file: `CODE SPEC SYMBOL TEXT` per line, `#` comments and blank lines ignored.
fn parse(path: &Path) -> Vec<Entry> {
    let content = fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut entries: Vec<Entry> = Vec::new();
    for (n, line) in content.lines().enumerate() {
        let fail = |why: &str| -> ! { panic!("{}:{}: {why}", path.display(), n + 1) };
        if line.trim().is_empty() || line.starts_with('#') {
            continue;
        }
        let mut rest = line;
        let mut field = || {
            let trimmed = rest.trim_start_matches(' ');
            let end = trimmed.find(' ').unwrap_or(trimmed.len());
            let (f, r) = trimmed.split_at(end);
            rest = r;
            f
        };
        let (code, spec, symbol) = (field(), field(), field());
        let text = rest.trim_start_matches(' ');
        if code.len() != 8 {
            fail("the code must be 8 hex digits");
        }
        let code = u32::from_str_radix(code, 16).unwrap_or_else(|_| fail("the code must be 8 hex digits"));
        let spec = SPECS
            .iter()
            .find(|s| s.name == spec)
            .unwrap_or_else(|| fail("unknown specification"))
            .spec;
        if symbol.is_empty()
            || !symbol
                .bytes()
                .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_')
        {
            fail("the symbol must be an upper-case C identifier");
        }
        if text.is_empty() || text.ends_with(char::is_whitespace) || text.chars().any(char::is_control) {
            fail("the text must be non-empty, without control characters or trailing blanks");
        }
        // '%' starts an insert in message tables; no published text has one.
        if text.contains('%') {
            fail("texts must not contain '%'");
        }
        if entries.iter().any(|e| e.code == code && e.spec == spec) {
            fail("duplicate code for this specification");
        }
        entries.push(Entry {
            code,
            spec,
            symbol: symbol.to_string(),
            text: text.to_string(),
        });
    }
    entries.sort_by_key(|e| (e.code, e.spec));
    entries
}

/// The catalog name of a specification.
pub fn spec_name(spec: Spec) -> &'static str {
    SPECS.iter().find(|s| s.spec == spec).map_or("?", |s| s.name)
}

/// Every translation must name an English entry exactly (code, specification and symbol).
fn check_translations(catalogs: &[Vec<Entry>]) {
    let english = &catalogs[0];
    for (catalog, language) in catalogs.iter().zip(LANGUAGES).skip(1) {
        let file = language.file;
        for e in catalog {
            match english.iter().find(|en| en.code == e.code && en.spec == e.spec) {
                Some(en) if en.symbol == e.symbol => {}
                Some(en) => panic!(
                    "{file}.txt: {:08X} is {} in en.txt, not {}",
                    e.code, en.symbol, e.symbol
                ),
                None => panic!("{file}.txt: {:08X} {} has no English entry", e.code, spec_name(e.spec)),
            }
        }
    }
}

/// The tables of src/errors/catalog.rs: the English entries sorted by code and specification, one
/// translation table per other language parallel to it (in the order of LANGUAGES), and an
/// open-addressing hash index from a code to its first entry.
fn generate_tables(catalogs: &[Vec<Entry>]) -> String {
    let english = &catalogs[0];
    let mut out =
        String::from("// Generated by buildscript/catalog.rs from src/errors/catalog/*.txt: do not edit.\n\n");
    let wide = |text: &str| -> String {
        let units: Vec<String> = text.encode_utf16().chain([0]).map(|u| u.to_string()).collect();
        format!("&[{}]", units.join(","))
    };
    out.push_str("/// `src/errors/catalog/en.txt`, sorted by code and specification.\n");
    out.push_str("pub(super) static ENGLISH: &[Entry] = &[\n");
    for e in english {
        writeln!(
            out,
            "    Entry {{ code: 0x{:08X}, spec: Spec::{:?}, symbol: {:?}, text: Text {{ text: {:?}, wide: {} }} }},",
            e.code,
            e.spec,
            e.symbol,
            e.text,
            wide(&e.text)
        )
        .unwrap();
    }
    out.push_str("];\n\n");
    out.push_str(
        "/// The other languages of LANGUAGES in its order, each entry by entry of ENGLISH (None: not translated).\n",
    );
    writeln!(
        out,
        "pub(super) static TRANSLATIONS: [&[Option<Text>]; {}] = [",
        LANGUAGES.len() - 1
    )
    .unwrap();
    for (catalog, language) in catalogs.iter().zip(LANGUAGES).skip(1) {
        writeln!(out, "    // src/errors/catalog/{}.txt", language.file).unwrap();
        out.push_str("    &[\n");
        for e in english {
            match catalog.iter().find(|t| t.code == e.code && t.spec == e.spec) {
                Some(t) => writeln!(
                    out,
                    "        Some(Text {{ text: {:?}, wide: {} }}),",
                    t.text,
                    wide(&t.text)
                )
                .unwrap(),
                None => out.push_str("        None,\n"),
            }
        }
        out.push_str("    ],\n");
    }
    out.push_str("];\n\n");
    let mut index = vec![0u16; 1 << tables::INDEX_BITS];
    for (i, e) in english.iter().enumerate() {
        if i > 0 && english[i - 1].code == e.code {
            continue;
        }
        let mut slot = tables::slot_of(e.code);
        while index[slot] != 0 {
            slot = (slot + 1) % index.len();
        }
        index[slot] = u16::try_from(i + 1).expect("too many catalog entries");
    }
    out.push_str(
        "/// Hash index (`slot_of`): slot -> 1 + index in ENGLISH of the first entry of a code; 0 is empty.\n",
    );
    let slots: Vec<String> = index.iter().map(u16::to_string).collect();
    writeln!(
        out,
        "pub(super) static INDEX: [u16; {}] = [{}];",
        index.len(),
        slots.join(",")
    )
    .unwrap();
    out
}
