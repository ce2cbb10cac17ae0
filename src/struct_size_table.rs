//! The table of accepted `struct_size` values in docs/api-conventions.md, generated from the code: each
//! structure's `SizedStruct::SIZES` as this target compiles them. The table has a column per
//! architecture; a test run checks the column of its own target (x86_64: the Linux and Windows x64
//! tests, and the `lint` stage through `scripts/check-generated.sh`; i686: the Windows x86 tests under
//! 32-bit Wine), and with `OPCCOMN_BLESS=1` in the environment writes it instead
//! (`scripts/gen-struct-size-table.sh` does both architectures).

use crate::com::options::SizedStruct;

const DOC: &str = include_str!("../docs/api-conventions.md");
const DOC_PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/api-conventions.md");
const BEGIN: &str = "<!-- begin struct_size table: generated from the code by scripts/gen-struct-size-table.sh -->";
const END: &str = "<!-- end struct_size table -->";
const HEADER: &str = "| structure | x86_64 (Windows x64, Linux) | i686 (Windows x86) |\n|---|---|---|";

/// The column of this target: 0 for x86_64, 1 for i686.
const COLUMN: usize = if cfg!(target_pointer_width = "64") { 0 } else { 1 };

/// The structure's C name and its accepted sizes on this target, ascending, each once.
fn row<T: SizedStruct>() -> (&'static str, String) {
    let full = core::any::type_name::<T>();
    let name = full.rsplit("::").next().unwrap_or(full);
    let mut sizes = T::SIZES.to_vec();
    sizes.sort_unstable();
    sizes.dedup();
    let sizes: Vec<String> = sizes.iter().map(|s| s.to_string()).collect();
    (name, sizes.join(", "))
}

/// Every structure the library reads by `struct_size`, in the order the table lists them.
fn rows() -> Vec<(&'static str, String)> {
    vec![
        row::<crate::common::OpcCommonOptions>(),
        row::<crate::shutdown::server::OpcShutdownOptions>(),
        row::<crate::shutdown::bounded::OpcShutdownNotifyOptions>(),
        row::<crate::registry::register::OpcServerRegistration>(),
        row::<crate::security::OpcSecurityOptions>(),
        row::<crate::server::OpcServerClass>(),
        row::<crate::server::exe::OpcExeServerOptions>(),
        row::<crate::com::module_lock::OpcModuleLock>(),
    ]
}

/// The table's rows as the document has them: name (without the backticks) and the two columns.
fn documented(doc: &str) -> (usize, usize, Vec<(String, [String; 2])>) {
    let begin = doc
        .find(BEGIN)
        .expect("docs/api-conventions.md lost the table's begin marker");
    let end = doc
        .find(END)
        .expect("docs/api-conventions.md lost the table's end marker");
    let body = &doc[begin + BEGIN.len()..end];
    let rows = body
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("| `"))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
            assert_eq!(cells.len(), 3, "a row of the struct_size table has three cells: {l}");
            (
                cells[0].trim_matches('`').to_string(),
                [cells[1].to_string(), cells[2].to_string()],
            )
        })
        .collect();
    (begin, end, rows)
}

/// The table with this target's column from the code and the other column as documented ("?" for a
/// structure the document does not list yet).
fn table(doc: &str) -> String {
    let (_, _, old) = documented(doc);
    let mut out = format!("{BEGIN}\n{HEADER}\n");
    for (name, sizes) in rows() {
        let mut cells = old
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, c)| c.clone())
            .unwrap_or_else(|| ["?".to_string(), "?".to_string()]);
        cells[COLUMN] = sizes;
        out += &format!("| `{name}` | {} | {} |\n", cells[0], cells[1]);
    }
    out
}

#[test]
#[cfg_attr(miri, ignore)] // writes a file when blessing; reading the table is cheap elsewhere
fn the_documented_struct_sizes_are_the_ones_the_code_accepts() {
    let (begin, end, _) = documented(DOC);
    let expected = table(DOC);
    if std::env::var_os("OPCCOMN_BLESS").is_some() {
        let current = std::fs::read_to_string(DOC_PATH).expect("reading docs/api-conventions.md");
        let (begin, end, _) = documented(&current);
        let updated = format!("{}{}{}", &current[..begin], table(&current), &current[end..]);
        std::fs::write(DOC_PATH, updated).expect("writing docs/api-conventions.md");
        return;
    }
    let arch = ["x86_64", "i686"][COLUMN];
    let (_, _, cells) = documented(DOC);
    let missing: Vec<&str> = cells
        .iter()
        .filter(|(_, c)| c.iter().any(|c| c.is_empty() || c == "?"))
        .map(|(n, _)| n.as_str())
        .collect();
    assert!(
        missing.is_empty(),
        "docs/api-conventions.md's struct_size table lacks sizes of {missing:?}: run scripts/gen-struct-size-table.sh"
    );
    assert_eq!(
        &DOC[begin..end],
        expected,
        "docs/api-conventions.md's struct_size table is not what the code accepts on {arch}: \
         run scripts/gen-struct-size-table.sh (or OPCCOMN_BLESS=1 cargo test --lib struct_size) and commit it"
    );
}

/// The test above lists every structure the library reads by `struct_size`: every `SizedStruct`
/// implementation in the sources (read_sized takes no other).
#[test]
#[cfg(not(windows))]
#[cfg_attr(miri, ignore)] // reads the sources
fn the_table_lists_every_sized_structure() {
    fn walk(dir: &std::path::Path, found: &mut Vec<String>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, found);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).unwrap();
                for line in text.lines() {
                    if let Some(rest) = line.trim().strip_prefix("unsafe impl SizedStruct for ") {
                        found.push(rest.trim_end_matches(" {").trim().to_string());
                    }
                }
            }
        }
    }
    let mut found = Vec::new();
    walk(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        &mut found,
    );
    found.retain(|n| n != "V2"); // the options module's own test structure
    found.sort();
    let mut listed: Vec<String> = rows().into_iter().map(|(n, _)| n.to_string()).collect();
    listed.sort();
    assert_eq!(found, listed, "add the structure to rows() in src/struct_size_table.rs");
}
