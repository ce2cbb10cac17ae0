//! Build script.
//!
//! 1. Sets platform details of the shared library (the SONAME on Linux).
//! 2. Turns the error catalog (`src/errors/catalog/<language>.txt`, one file per language, reviewed as
//!    text) into static tables (`$OUT_DIR/catalog.rs`, included by `src/errors/catalog.rs`). Malformed
//!    or inconsistent catalog lines fail the build with the file and line.
//! 3. For Windows targets built with mingw, compiles the DLL's resources from the same data: a message
//!    table (so `FormatMessage(FORMAT_MESSAGE_FROM_HMODULE, opccomn.dll, code)` returns the catalog
//!    texts) and a VERSIONINFO following the specification's version convention (section 6.4: version
//!    MM.mm.bb is written FILEVERSION MM,mm,0,bb, the same for PRODUCTVERSION), taken from Cargo.toml.
//!    The tools are `<triple>-windmc` and `<triple>-windres` from binutils-mingw-w64, or the programs
//!    named by OPCCOMN_WINDMC / OPCCOMN_WINDRES.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::{env, fs};

/// The specifications a catalog entry may belong to: short name in the catalog files and the variant of
/// `Spec` in src/errors/catalog.rs. The order is the order in which colliding codes are preferred when
/// the kind of server asking has no text of its own.
const SPECS: &[(&str, &str)] = &[
    ("DA", "DataAccess"),
    ("AE", "AlarmsEvents"),
    ("HDA", "HistoricalData"),
    ("SEC", "Security"),
    ("BAT", "Batch"),
    ("DX", "DataExchange"),
    ("CMD", "CommandExecution"),
    ("COM", "Connection"),
    ("SYS", "System"),
];
const SYSTEM: usize = 8;

/// The catalog languages: file stem, constant name, the LCID the message table uses, the windmc name.
const LANGUAGES: &[(&str, &str, u32, &str)] =
    &[("en", "ENGLISH", 0x0409, "English"), ("de", "GERMAN", 0x0407, "German")];

struct Entry {
    code: u32,
    spec: usize,
    symbol: String,
    text: String,
}

fn main() {
    let manifest_dir = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap());
    let out_dir = PathBuf::from(env::var("OUT_DIR").unwrap());
    let catalog_dir = manifest_dir.join("src/errors/catalog");
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        // Programs linked against libopccomn.so record this name, not the build path.
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libopccomn.so");
    }
    println!("cargo:rerun-if-env-changed=OPCCOMN_WINDMC");
    println!("cargo:rerun-if-env-changed=OPCCOMN_WINDRES");

    let mut catalogs: Vec<Vec<Entry>> = Vec::new();
    for (stem, ..) in LANGUAGES {
        let path = catalog_dir.join(format!("{stem}.txt"));
        println!("cargo:rerun-if-changed={}", path.display());
        catalogs.push(parse(&path));
    }
    check_translations(&catalogs);
    fs::write(out_dir.join("catalog.rs"), generate_tables(&catalogs)).expect("write catalog.rs");

    if env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("windows") {
        if env::var("CARGO_CFG_TARGET_ENV").as_deref() == Ok("gnu") {
            let object = compile_resources(&out_dir, &catalogs);
            println!("cargo:rustc-link-arg-cdylib={}", object.display());
        } else {
            println!("cargo:warning=opccomn: resources (message table, VERSIONINFO) are built only with mingw");
        }
    }
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
            .position(|(s, _)| *s == spec)
            .unwrap_or_else(|| fail("unknown specification"));
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

/// Every translation must name an English entry exactly (code, specification and symbol).
fn check_translations(catalogs: &[Vec<Entry>]) {
    let english = &catalogs[0];
    for (catalog, (stem, ..)) in catalogs.iter().zip(LANGUAGES).skip(1) {
        for e in catalog {
            match english.iter().find(|en| en.code == e.code && en.spec == e.spec) {
                Some(en) if en.symbol == e.symbol => {}
                Some(en) => panic!(
                    "{stem}.txt: {:08X} is {} in en.txt, not {}",
                    e.code, en.symbol, e.symbol
                ),
                None => panic!("{stem}.txt: {:08X} {} has no English entry", e.code, SPECS[e.spec].0),
            }
        }
    }
}

/// Slots of the generated hash index (a power of two, well above the number of codes).
const INDEX_BITS: u32 = 10;

/// The hash the index uses; src/errors/catalog.rs computes the same.
fn slot_of(code: u32) -> usize {
    (code.wrapping_mul(0x9E37_79B1) >> (32 - INDEX_BITS)) as usize
}

/// The tables of src/errors/catalog.rs: the English entries sorted by code and specification, one
/// translation table per other language parallel to it, and an open-addressing hash index from a code
/// to its first entry.
fn generate_tables(catalogs: &[Vec<Entry>]) -> String {
    let english = &catalogs[0];
    let mut out = String::from("// Generated by build.rs from src/errors/catalog/*.txt: do not edit.\n\n");
    let wide = |text: &str| -> String {
        let units: Vec<String> = text.encode_utf16().chain([0]).map(|u| u.to_string()).collect();
        format!("&[{}]", units.join(","))
    };
    out.push_str("/// `src/errors/catalog/en.txt`, sorted by code and specification.\n");
    out.push_str("pub(super) static ENGLISH: &[Entry] = &[\n");
    for e in english {
        writeln!(
            out,
            "    Entry {{ code: 0x{:08X}, spec: Spec::{}, symbol: {:?}, text: Text {{ text: {:?}, wide: {} }} }},",
            e.code,
            SPECS[e.spec].1,
            e.symbol,
            e.text,
            wide(&e.text)
        )
        .unwrap();
    }
    out.push_str("];\n\n");
    for (catalog, (stem, name, ..)) in catalogs.iter().zip(LANGUAGES).skip(1) {
        writeln!(
            out,
            "/// `src/errors/catalog/{stem}.txt`, entry by entry of ENGLISH (None: not translated)."
        )
        .unwrap();
        writeln!(out, "pub(super) static {name}: &[Option<Text>] = &[").unwrap();
        for e in english {
            match catalog.iter().find(|t| t.code == e.code && t.spec == e.spec) {
                Some(t) => writeln!(out, "    Some(Text {{ text: {:?}, wide: {} }}),", t.text, wide(&t.text)).unwrap(),
                None => out.push_str("    None,\n"),
            }
        }
        out.push_str("];\n\n");
    }
    let mut index = vec![0u16; 1 << INDEX_BITS];
    for (i, e) in english.iter().enumerate() {
        if i > 0 && english[i - 1].code == e.code {
            continue;
        }
        let mut slot = slot_of(e.code);
        while index[slot] != 0 {
            slot = (slot + 1) % index.len();
        }
        index[slot] = u16::try_from(i + 1).expect("too many catalog entries");
    }
    writeln!(out, "pub(super) const INDEX_BITS: u32 = {INDEX_BITS};").unwrap();
    out.push_str("/// Hash index: slot -> 1 + index in ENGLISH of the first entry of a code; 0 is empty.\n");
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

/// The mingw tool `name` for the target (e.g. x86_64-w64-mingw32-windres), or the override from `var`.
fn tool(var: &str, name: &str) -> String {
    if let Ok(program) = env::var(var) {
        return program;
    }
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap();
    let prefix = match arch.as_str() {
        "x86" => "i686",
        other => other,
    };
    format!("{prefix}-w64-mingw32-{name}")
}

fn run(mut command: Command) {
    let shown = format!("{command:?}");
    match command.status() {
        Ok(status) if status.success() => {}
        Ok(status) => panic!("{shown} failed: {status}"),
        Err(e) => panic!("cannot run {shown}: {e} (install binutils-mingw-w64, or set OPCCOMN_WINDMC/OPCCOMN_WINDRES)"),
    }
}

/// Builds the message table and version resources into one COFF object and returns its path.
fn compile_resources(out_dir: &Path, catalogs: &[Vec<Entry>]) -> PathBuf {
    let dir = out_dir.join("resources");
    fs::create_dir_all(&dir).expect("create resources dir");

    // One message per code: where codes collide the specification order decides (Data Access first),
    // as for a server that does not say what kind it is. System codes are the system's business.
    let mut messages: BTreeMap<u32, usize> = BTreeMap::new();
    for (i, e) in catalogs[0].iter().enumerate() {
        if e.spec != SYSTEM {
            messages.entry(e.code).or_insert(i);
        }
    }
    let mut mc = String::from(
        "; Generated by build.rs from src/errors/catalog/*.txt: do not edit.\n\
         MessageIdTypedef=HRESULT\n\
         SeverityNames=(Success=0x0 Informational=0x1 Warning=0x2 Error=0x3)\n\
         FacilityNames=(Interface=0x4)\n",
    );
    let names: Vec<String> = LANGUAGES
        .iter()
        .map(|(_, _, lcid, name)| format!("{name}=0x{lcid:X}:MSG{lcid:05X}"))
        .collect();
    writeln!(mc, "LanguageNames=({})\n", names.join(" ")).unwrap();
    for (&code, &index) in &messages {
        let english = &catalogs[0][index];
        assert!(
            code & 0x2FFF_0000 == 0x0004_0000,
            "{:08X}: only FACILITY_ITF codes go into the message table",
            code
        );
        let severity = ["Success", "Informational", "Warning", "Error"][(code >> 30) as usize];
        writeln!(
            mc,
            "MessageId=0x{:04X}\nSeverity={severity}\nFacility=Interface\nSymbolicName={}",
            code & 0xFFFF,
            english.symbol
        )
        .unwrap();
        for (catalog, (_, _, _, name)) in catalogs.iter().zip(LANGUAGES) {
            let text = catalog
                .iter()
                .find(|e| e.code == code && e.spec == english.spec)
                .map_or(&english.text, |e| &e.text);
            // "%0" ends the message without the line break the compiler would add.
            writeln!(mc, "Language={name}\n{text}%0\n.").unwrap();
        }
    }
    // windmc reads UTF-16LE (-u) so the texts keep their non-ASCII characters.
    let utf16: Vec<u8> = mc.encode_utf16().flat_map(u16::to_le_bytes).collect();
    fs::write(dir.join("opccomn_messages.mc"), utf16).expect("write .mc");
    let mut windmc = Command::new(tool("OPCCOMN_WINDMC", "windmc"));
    windmc
        .current_dir(&dir)
        .args(["-u", "-U", "-r", ".", "-h", ".", "opccomn_messages.mc"]);
    run(windmc);
    let messages_rc = fs::read_to_string(dir.join("opccomn_messages.rc")).expect("windmc wrote no .rc");

    let major: u32 = env::var("CARGO_PKG_VERSION_MAJOR").unwrap().parse().unwrap();
    let minor: u32 = env::var("CARGO_PKG_VERSION_MINOR").unwrap().parse().unwrap();
    let build: u32 = env::var("CARGO_PKG_VERSION_PATCH").unwrap().parse().unwrap();
    let version = format!("{major}.{minor}.{build}");
    let description = env::var("CARGO_PKG_DESCRIPTION")
        .unwrap_or_default()
        .replace('"', "\"\"");
    let license = env::var("CARGO_PKG_LICENSE").unwrap_or_default();
    let debug = u32::from(env::var("PROFILE").as_deref() == Ok("debug"));
    let mut rc = messages_rc;
    write!(
        rc,
        r#"
LANGUAGE 0x9, 0x1
1 VERSIONINFO
 FILEVERSION {major},{minor},0,{build}
 PRODUCTVERSION {major},{minor},0,{build}
 FILEFLAGSMASK 0x3fL
 FILEFLAGS 0x{debug}L
 FILEOS 0x40004L
 FILETYPE 0x2L
 FILESUBTYPE 0x0L
BEGIN
    BLOCK "StringFileInfo"
    BEGIN
        BLOCK "040904b0"
        BEGIN
            VALUE "FileDescription", "{description}\0"
            VALUE "FileVersion", "{version}\0"
            VALUE "InternalName", "opccomn\0"
            VALUE "LegalCopyright", "License: {license}\0"
            VALUE "OriginalFilename", "opccomn.dll\0"
            VALUE "ProductName", "opccomn\0"
            VALUE "ProductVersion", "{version}\0"
        END
    END
    BLOCK "VarFileInfo"
    BEGIN
        VALUE "Translation", 0x409, 1200
    END
END
"#
    )
    .unwrap();
    fs::write(dir.join("opccomn.rc"), rc).expect("write .rc");
    let mut windres = Command::new(tool("OPCCOMN_WINDRES", "windres"));
    windres
        .current_dir(&dir)
        .args(["-O", "coff", "-i", "opccomn.rc", "-o", "opccomn_res.o"]);
    run(windres);
    dir.join("opccomn_res.o")
}
