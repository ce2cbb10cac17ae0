//! Generates include/opccomn/opccomn.h and the identifier tables derived from the IDL.
//!
//! - The C API (functions, option structs, constants, the portable COM base types) comes from the Rust
//!   sources through cbindgen (`cbindgen.toml`).
//! - The interfaces come from `idl/opccomn.idl` (the five OPC Common interfaces) and `idl/combase.idl`
//!   (the standard COM interfaces, declared only off Windows), written in MIDL's shape (see `emit`).
//!   `idl/opcda.idl`, `idl/opc_ae.idl` and `idl/opchda.idl` are not read: they are the source of the
//!   proxy/stub tables only (`IDL_FILES` says which file is for what, and every file of `idl/` must be
//!   listed there).
//! - `src/com/interfaces.rs`: the Rust side of the same interfaces and of `idl/internal.idl` (vtables,
//!   shims, the trait per interface, the proxy/stub's table; see `rustgen`), formatted by rustfmt.
//! - The identifiers: `src/com/guids.rs` (Rust constants and the DLL's data exports) and
//!   `src/c/opccomn_guids.c` (the same data for per-symbol objects) from the IDL and idl/opcguids.txt.
//! - `src/proxy/generated/layouts.rs` and `interfaces.h`: the proxy/stub's checks, each method's NDR
//!   layout with the interfaces' numbering, from `idl/opccomn.idl` and `idl/ndr-bounds.txt`, and
//!   `test_layouts.rs` from the test IDL of the layout language (see `ndr`).
//! - `c-tests/abi_i686.c`: compile-time checks (for i686-w64-mingw32-gcc) that every vtable entry is
//!   `__stdcall` and every exported function and callback has the convention of its Rust definition.
//!
//! It also checks the rules of the FFI boundary that the compiler cannot and the names of the C API's
//! parameters (see `rustcheck`), the header's documentation as the C API reference needs it: every
//! parameter and result documented, names linked, every declaration in an area (see `apidoc`,
//! `groups`), and that docs/dev/architecture.md accounts for every `unsafe` outside `src/com/` (see
//! `unsafety`; `gen-header --unsafe` prints the counts per file).
//!
//! `gen-header` writes the files; `gen-header --check` exits 1 when a committed file differs from what
//! the sources generate now (CI runs this). Both exit 1 when the sources break the boundary's rules,
//! the naming rule or the documentation's.

mod apidoc;
mod emit;
mod groups;
mod guids;
mod idl;
mod ndr;
mod rustcheck;
mod rustgen;
mod unsafety;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

const HEADER: &str = "include/opccomn/opccomn.h";

/// The document with the table of the `unsafe` outside `src/com/`, and the line before the table.
const UNSAFE_DOC: &str = "docs/dev/architecture.md";
const UNSAFE_TABLE: &str = "<!-- the unsafe outside src/com/, checked by gen-header -->";

/// What an IDL file of `idl/` is for.
#[derive(Debug, Clone, Copy, PartialEq)]
enum IdlUse {
    /// Read here: the header, the Rust interfaces and the identifier tables.
    Header,
    /// Read here for the Rust side only (`src/com/interfaces.rs`), not part of the header.
    RustOnly,
    /// Not read here: the source of the NDR tables (`tools/gen-proxy.py`) and nothing else. The
    /// Data Access, A&E and HDA interfaces stay out of the header: programs declare them by the
    /// Foundation's `opcda.h`, `opc_ae.h` and `opchda.h`, beside which this header must compile
    /// (docs/header.md), and a second declaration of them here could only disagree with those.
    ProxyTablesOnly,
}

/// Every IDL file of `idl/` and what it is for; a file missing here fails the run, so that a new one
/// is put in the header, or kept out of it, on purpose.
const IDL_FILES: &[(&str, IdlUse)] = &[
    ("idl/combase.idl", IdlUse::Header),
    ("idl/opccomn.idl", IdlUse::Header),
    ("idl/internal.idl", IdlUse::RustOnly),
    ("idl/opcda.idl", IdlUse::ProxyTablesOnly),
    ("idl/opc_ae.idl", IdlUse::ProxyTablesOnly),
    ("idl/opchda.idl", IdlUse::ProxyTablesOnly),
];

/// The `.idl` files of `dir` (the repository's `idl/`) that `IDL_FILES` does not list.
fn unlisted_idl_files(dir: &Path) -> Vec<String> {
    let mut unlisted: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|entry| entry.ok()?.file_name().into_string().ok())
        .filter(|name| name.ends_with(".idl"))
        .map(|name| format!("idl/{name}"))
        .filter(|path| !IDL_FILES.iter().any(|(listed, _)| listed == path))
        .collect();
    unlisted.sort();
    unlisted
}

fn main() -> ExitCode {
    let check = std::env::args().skip(1).any(|a| a == "--check");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let root = root.canonicalize().expect("crate root");

    let unlisted = unlisted_idl_files(&root.join("idl"));
    if !unlisted.is_empty() {
        eprintln!(
            "{}: not in IDL_FILES (tools/gen-header/src/main.rs): say whether the header declares its \
             interfaces or only the proxy/stub tables are made from it",
            unlisted.join(", ")
        );
        return ExitCode::FAILURE;
    }
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
    let opc = idl::parse("idl/opccomn.idl", &read("idl/opccomn.idl")).unwrap_or_else(|e| panic!("{e}"));
    let base = idl::parse("idl/combase.idl", &read("idl/combase.idl")).unwrap_or_else(|e| panic!("{e}"));
    let internal = idl::parse("idl/internal.idl", &read("idl/internal.idl")).unwrap_or_else(|e| panic!("{e}"));
    let table = guids::parse_table(&read("idl/opcguids.txt")).unwrap_or_else(|e| panic!("{e}"));
    let catalog = emit::Catalog::new(opc.iter().chain(&base).chain(&internal));

    // The Rust side of the interfaces.
    let interfaces = rustgen::module(
        &catalog,
        &[
            rustgen::File {
                path: "idl/combase.idl",
                interfaces: &base,
                rule: "Com",
            },
            rustgen::File {
                path: "idl/opccomn.idl",
                interfaces: &opc,
                rule: "Opc",
            },
            rustgen::File {
                path: "idl/internal.idl",
                interfaces: &internal,
                rule: "Com",
            },
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));

    let traits: Vec<String> = opc
        .iter()
        .chain(&base)
        .chain(&internal)
        .map(|i| format!("{}Impl", i.name))
        .collect();
    let sources = rustcheck::read(&root, &traits);

    let header = match generate_header(&root, &opc, &base, &table, &catalog, &sources) {
        Ok(h) => h,
        Err(e) => {
            eprintln!("{e}");
            for p in &sources.problems {
                eprintln!("rules: {p}");
            }
            return ExitCode::FAILURE;
        }
    };
    let abi_check = abi_checks(&header, &opc, &catalog, &sources);
    let outputs = [
        (HEADER, header),
        ("src/com/guids.rs", guids::rust_module(&opc, &base, &table)),
        ("src/com/interfaces.rs", rustfmt(&root, &interfaces)),
        ("src/c/opccomn_guids.c", guids::c_data(&opc, &base, &table)),
        ("c-tests/abi_i686.c", abi_check),
    ];
    // The proxy/stub's NDR layouts and interface table (src/ndr/).
    let layouts = ndr::outputs(&read, &|text| rustfmt(&root, text)).unwrap_or_else(|e| panic!("{e}"));
    let outputs: Vec<(&str, String)> = outputs.into_iter().chain(layouts).collect();
    let mut stale = 0;
    for (path, text) in &outputs {
        let full = root.join(path);
        if std::fs::read(&full).unwrap_or_default() == text.as_bytes() {
            println!("{path} is up to date");
            continue;
        }
        if check {
            eprintln!("{path} differs from what the sources generate: run `cargo run -p gen-header` and commit it");
            stale += 1;
        } else {
            std::fs::create_dir_all(full.parent().unwrap()).expect("create the directory");
            std::fs::write(&full, text).unwrap_or_else(|e| panic!("write {path}: {e}"));
            println!("wrote {path}");
        }
    }
    // What the compiler cannot check about the boundary, and the names.
    for p in &sources.problems {
        eprintln!("rules: {p}");
    }
    // The unsafe code outside the COM core, against the documented table.
    let counts = unsafety::count(&root);
    if std::env::args().any(|a| a == "--unsafe") {
        for (file, c) in &counts {
            println!("{file:45} blocks {:3}  fns {:3}  impls {:3}", c.blocks, c.fns, c.impls);
        }
    }
    let unsafe_problems = unsafety::check(&read(UNSAFE_DOC), UNSAFE_TABLE, &counts);
    for p in &unsafe_problems {
        eprintln!("unsafe: {p}");
    }
    if !unsafe_problems.is_empty() {
        eprintln!("{UNSAFE_DOC}: the table of the unsafe outside src/com/ differs from the sources (`cargo run -p gen-header -- --unsafe` counts them): update it, with the reason for what is new");
        return ExitCode::FAILURE;
    }
    if !sources.problems.is_empty() {
        eprintln!(
            "{} breach(es) of the boundary's rules or the naming rule (tools/gen-header/src/rustcheck.rs)",
            sources.problems.len()
        );
        return ExitCode::FAILURE;
    }
    if stale > 0 {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

fn generate_header(
    root: &Path,
    opc: &[idl::Interface],
    base: &[idl::Interface],
    table: &[guids::Entry],
    catalog: &emit::Catalog,
    sources: &rustcheck::Sources,
) -> Result<String, String> {
    let mut config = cbindgen::Config::from_file(root.join("cbindgen.toml")).expect("cbindgen.toml");
    // The version macros come from Cargo.toml, never from a hand-kept copy.
    let version = package_version(root);
    let (numbers, prerelease) = split_version(&version);
    let mut parts = numbers.split('.');
    let mut next = || parts.next().unwrap_or("0").to_string();
    let (major, minor, patch) = (next(), next(), next());
    // A version in development (Cargo.toml's `0.3.0-dev`) says so; a released header has no such macro.
    let prerelease = match prerelease {
        Some(pre) => format!(
            "/** Defined only in the header of a version in development (a build of the main branch, not a\n    \
             release): the pre-release part of OPCCOMN_VERSION, which then names the version to come. */\n\
             #define OPCCOMN_VERSION_PRERELEASE \"{pre}\"\n"
        ),
        None => String::new(),
    };
    let opc_refs: Vec<&idl::Interface> = opc.iter().collect();
    let base_refs: Vec<&idl::Interface> = base.iter().collect();
    let forwards = format!(
        "#if !defined(_WIN32)\n{}#endif\n\n{}",
        emit::forwards(&base_refs),
        emit::forwards(&opc_refs)
    );
    config.after_includes = config.after_includes.map(|text| {
        text.replace("@MAJOR@", &major)
            .replace("@MINOR@", &minor)
            .replace("@PATCH@", &patch)
            .replace("@VERSION@", &version)
            .replace("@PRERELEASE@", &prerelease)
            .replace("@FORWARDS@\n", &forwards)
    });
    // The interfaces (and their vtables) are declared from the IDL, not from the Rust structs.
    for i in opc.iter().chain(base) {
        config.export.exclude.push(i.name.clone());
        config.export.exclude.push(format!("{}Vtbl", i.name));
        config.export.exclude.push(format!("{}Calls", i.name));
    }
    let bindings = cbindgen::Builder::new()
        .with_crate(root)
        .with_config(config)
        .generate()
        .map_err(|e| format!("cbindgen could not generate the header: {e}"))?;
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let text = String::from_utf8(generated).expect("UTF-8 header");
    // The Rust doc comments' `# Safety` heading, as a titled paragraph of the function's documentation
    // (as a Markdown heading Doxygen would make it a section of the whole page).
    let text = text.replace("\n * # Safety\n", "\n * @par Safety\n");
    // cbindgen declares a C enum's type as `uint32_t` before C23 (its values are the enum's): say so.
    let text = text
        .lines()
        .map(|line| {
            let typedef = line
                .strip_prefix("typedef uint32_t ")
                .or_else(|| line.strip_prefix("typedef enum ").and_then(|r| r.split(' ').nth(1)))
                .and_then(|r| r.strip_suffix(';'));
            match typedef {
                Some(name) if text.contains(&format!("\nenum {name}\n")) => {
                    format!("/** The type of enum {name}'s values. */\n{line}\n")
                }
                _ => format!("{line}\n"),
            }
        })
        .collect::<String>();

    // The interface section goes after the types cbindgen declares and before the functions.
    let mut section = String::from(
        "/* ---- The interfaces, from idl/combase.idl (off Windows) and idl/opccomn.idl, in MIDL's shape: a\n\
         \x20  MIDL-generated header (the OPC Foundation's opccomn.h) and this one skip each other's\n\
         \x20  declarations whichever comes first. ---- */\n\n",
    );
    section += emit::UUIDOF_PROLOGUE;
    section += "#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n#if !defined(_WIN32)\n\n";
    for i in base {
        section += &emit::interface(
            catalog,
            i,
            " (the standard COM interface; <windows.h> declares it on Windows)",
        );
    }
    section += "#endif /* !defined(_WIN32) */\n\n";
    for i in opc {
        section += &emit::interface(catalog, i, " (OPC Common, idl/opccomn.idl)");
    }
    section += "/* ---- The component categories and classes (idl/opcguids.txt). ---- */\n\n";
    section += &emit::table_declarations(table);
    section += "#ifdef __cplusplus\n}  /* extern \"C\" */\n#endif\n\n";
    section += emit::UUIDOF_EPILOGUE;

    let marker = "#ifdef __cplusplus\nextern \"C\" {\n#endif // __cplusplus\n";
    let at = text.find(marker).ok_or("no extern \"C\" block in cbindgen's output")?;
    let (head, tail) = text.split_at(at);
    let mut out = String::new();
    for line in head.lines() {
        out += &rewrite_type_line(line, sources)?;
        out.push('\n');
    }
    out += &section;
    for line in tail.lines() {
        out += &rewrite_function_line(line, sources)?;
        out.push('\n');
    }
    // The documentation as the reference reads it: sections to commands, names linked, areas.
    let base_names: Vec<String> = base.iter().map(|i| i.name.clone()).collect();
    let area = |name: &str, interface: Option<&str>| groups::of(name, interface, &sources.origins, &base_names, table);
    apidoc::rewrite(&out, &area).map_err(|problems| {
        let n = problems.len();
        let mut text: String = problems.into_iter().map(|p| format!("docs: {p}\n")).collect();
        text += &format!(
            "{n} problem(s) with the header's documentation (tools/gen-header/src/apidoc.rs; docs/api-conventions.md)"
        );
        text
    })
}

/// Before the functions: HRESULT macros in the Windows SDK's spelling, so a redefinition by opcerror.h
/// or winerror.h is token for token the same; REFIID and REFCLSID references in C++ (as Windows'
/// guiddef.h has them); callback typedefs with their calling convention.
fn rewrite_type_line(line: &str, sources: &rustcheck::Sources) -> Result<String, String> {
    if let Some(rest) = line.strip_prefix("#define ") {
        if let Some((name, value)) = rest.split_once(" (HRESULT)") {
            let v: u32 = value
                .trim_end_matches('u')
                .parse()
                .map_err(|_| format!("bad HRESULT {line}"))?;
            return Ok(format!("#define {name} ((HRESULT)0x{v:08X}L)"));
        }
    }
    for (alias, target) in [("REFIID", "IID"), ("REFCLSID", "CLSID")] {
        if line == format!("typedef const {target} *{alias};") {
            return Ok(format!(
                "#if defined(__cplusplus)\ntypedef const {target} &{alias};\n#else\ntypedef const {target} *{alias};\n#endif"
            ));
        }
    }
    if let Some(rest) = line.strip_prefix("typedef ") {
        if let Some(open) = rest.find("(*") {
            let name: String = rest[open + 2..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            let abi = sources
                .callbacks
                .get(&name)
                .ok_or(format!("no Rust type for the callback {name}"))?;
            return Ok(format!(
                "typedef {}({} *{}",
                &rest[..open],
                convention(abi)?,
                &rest[open + 2..]
            ));
        }
    }
    Ok(line.to_string())
}

fn convention(abi: &str) -> Result<&'static str, String> {
    match abi {
        "C" => Ok("OPCCOMN_CDECL"),
        "system" => Ok("OPCCOMN_STDCALL"),
        other => Err(format!("an exported function or callback has the ABI \"{other}\"")),
    }
}

/// A function declaration (`HRESULT OpcCommonCreate(...);`) gets the calling convention of the Rust
/// function it declares.
fn rewrite_function_line(line: &str, sources: &rustcheck::Sources) -> Result<String, String> {
    if line.starts_with(|c: char| c.is_ascii_alphabetic()) && line.ends_with(");") && !line.starts_with("typedef") {
        if let Some(open) = line.find('(') {
            let before = &line[..open];
            let split = before.rfind([' ', '*']).ok_or(format!("cannot read {line}"))? + 1;
            let name = &before[split..];
            let abi = sources
                .functions
                .get(name)
                .ok_or(format!("{name} is declared but not a Rust export"))?;
            return Ok(format!("{}{} {}", &before[..split], convention(abi)?, &line[split..]));
        }
    }
    Ok(line.to_string())
}

/// `c-tests/abi_i686.c`: on i686, `__stdcall` and `__cdecl` function pointer types are different types,
/// so `__builtin_types_compatible_p` proves each declaration's convention at compile time.
fn abi_checks(header: &str, opc: &[idl::Interface], catalog: &emit::Catalog, sources: &rustcheck::Sources) -> String {
    let mut s = String::from(
        "/* Generated by tools/gen-header: do not edit. Run `cargo run -p gen-header`.\n\
         \n\
         Compile-time proof that include/opccomn/opccomn.h states the calling conventions of the library:\n\
         every vtable entry is __stdcall (STDMETHODCALLTYPE, Rust's extern \"system\"), every exported\n\
         function and callback type has the convention of its Rust definition (extern \"C\": __cdecl).\n\
         Meaningful on 32-bit x86, where the conventions differ:\n\
         \x20   i686-w64-mingw32-gcc -std=c11 -fsyntax-only -Iinclude c-tests/abi_i686.c            (must pass)\n\
         \x20   i686-w64-mingw32-gcc -std=c11 -fsyntax-only -Iinclude -DOPCCOMN_ABI_EXPECT_FAILURE ... (must fail)\n\
         */\n\
         #include <opccomn/opccomn.h>\n\n\
         #if !defined(__i386__)\n#error \"the calling convention checks are only meaningful on 32-bit x86\"\n#endif\n\n\
         #define OPCCOMN_STDCALL_ENTRY(iface, method, type) \\\n\
         \x20   _Static_assert(__builtin_types_compatible_p(__typeof__(((iface##Vtbl *)0)->method), type), \\\n\
         \x20                  #iface \"::\" #method \" must be __stdcall\")\n\
         #define OPCCOMN_CONVENTION(expr, type, what) \\\n\
         \x20   _Static_assert(__builtin_types_compatible_p(__typeof__(expr), type), what)\n\n\
         /* Vtable entries, from the IDL. */\n",
    );
    // (The category interfaces are not checked: their names are macros for their IIDs once declared,
    // as in opcda.h, so they cannot be used as types.)
    for i in opc {
        let vt = catalog.vtable(i);
        for (_, m) in vt {
            let params: Vec<String> = std::iter::once(format!("{} *", i.name))
                .chain(m.params.iter().map(|p| p.declaration()))
                .collect();
            s += &format!(
                "OPCCOMN_STDCALL_ENTRY({}, {}, {} (__attribute__((stdcall)) *)({}));\n",
                i.name,
                m.name,
                m.ret,
                params.join(", ")
            );
        }
    }
    s += "\n/* Exported functions, with the convention of their Rust definition. */\n";
    for line in header.lines() {
        for (mac, attr) in [("OPCCOMN_CDECL ", "cdecl"), ("OPCCOMN_STDCALL ", "stdcall")] {
            if line.starts_with("typedef") || !line.ends_with(");") {
                continue;
            }
            if let Some((ret, rest)) = line.split_once(mac) {
                let (name, params) = rest.split_once('(').expect("a declaration");
                let abi = &sources.functions[name];
                let want = if abi == "system" { "stdcall" } else { "cdecl" };
                assert_eq!(want, attr, "{name}");
                s += &format!(
                    "OPCCOMN_CONVENTION(&{name}, {}(__attribute__(({want})) *)({}, \"{name} must be {want}\");\n",
                    ret,
                    params.trim_end_matches(';').trim_end_matches(')').to_string() + ")"
                );
            }
        }
    }
    s += "\n/* Callback types. */\n";
    for line in header.lines() {
        if let Some(rest) = line.strip_prefix("typedef ") {
            if let Some((ret, after)) = rest.split_once("(OPCCOMN_CDECL *") {
                let (name, params) = after.split_once(")(").expect("a callback typedef");
                s += &format!(
                    "OPCCOMN_CONVENTION(({name})0, {ret}(__attribute__((cdecl)) *)({}, \"{name} must be cdecl\");\n",
                    params.trim_end_matches(';')
                );
            }
        }
    }
    s += "\n/* The check can fail: a vtable entry is not __cdecl. */\n\
          #ifdef OPCCOMN_ABI_EXPECT_FAILURE\n\
          OPCCOMN_CONVENTION(((IOPCCommonVtbl *)0)->GetErrorString, HRESULT (__attribute__((cdecl)) *)(IOPCCommon *, HRESULT, LPWSTR *), \"expected to fail\");\n\
          #endif\n\n\
          int opccomn_abi_i686_checked;\n";
    s
}

/// The `version` of the `[package]` table in the crate's Cargo.toml.
fn package_version(root: &Path) -> String {
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).expect("Cargo.toml");
    let mut in_package = false;
    for line in manifest.lines() {
        let line = line.trim();
        if line.starts_with('[') {
            in_package = line == "[package]";
        } else if in_package {
            if let Some(value) = line.strip_prefix("version") {
                let value = value.trim_start().trim_start_matches('=').trim();
                return value.trim_matches('"').to_string();
            }
        }
    }
    panic!("no [package] version in Cargo.toml");
}

/// A SemVer version split into its numbers and its pre-release part: `0.3.0-dev` is ("0.3.0",
/// Some("dev")), `0.2.0` ("0.2.0", None). Build metadata (`+...`) is not part of either.
fn split_version(version: &str) -> (&str, Option<&str>) {
    let version = version.split('+').next().unwrap_or(version);
    match version.split_once('-') {
        Some((numbers, pre)) => (numbers, Some(pre)),
        None => (version, None),
    }
}

/// `text` as `cargo fmt` formats it (the repository's rustfmt.toml), so the generated module passes
/// `cargo fmt --check` as it is written.
fn rustfmt(root: &Path, text: &str) -> String {
    use std::io::Write as _;
    let mut child = std::process::Command::new("rustfmt")
        .args(["--edition", "2021", "--emit", "stdout", "--config-path"])
        .arg(root.join("rustfmt.toml"))
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("run rustfmt (rustup component add rustfmt)");
    child
        .stdin
        .take()
        .expect("rustfmt's input")
        .write_all(text.as_bytes())
        .expect("write to rustfmt");
    let output = child.wait_with_output().expect("rustfmt");
    assert!(output.status.success(), "rustfmt could not format the generated module");
    String::from_utf8(output.stdout).expect("UTF-8 from rustfmt")
}

#[cfg(test)]
mod tests {
    use super::{split_version, unlisted_idl_files, IdlUse, HEADER, IDL_FILES};
    use std::path::PathBuf;

    fn root() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
    }

    #[test]
    fn every_idl_file_says_what_it_is_for() {
        assert_eq!(unlisted_idl_files(&root().join("idl")), Vec::<String>::new());
        for (path, _) in IDL_FILES {
            assert!(root().join(path).is_file(), "{path} is listed but missing");
        }
    }

    #[test]
    fn an_idl_file_nobody_listed_is_found() {
        let dir = std::env::temp_dir().join(format!("gen-header-idl-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("opccomn.idl"), "").unwrap();
        std::fs::write(dir.join("opcbatch.idl"), "").unwrap();
        std::fs::write(dir.join("notes.txt"), "").unwrap();
        let unlisted = unlisted_idl_files(&dir);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(unlisted, vec!["idl/opcbatch.idl".to_string()]);
    }

    /// The interfaces of the files kept out of the header are not declared by it (the header made
    /// from the other files, as committed).
    #[test]
    fn the_header_declares_no_interface_of_the_proxy_only_files() {
        let header = std::fs::read_to_string(root().join(HEADER)).unwrap();
        let mut seen = 0;
        for (path, what) in IDL_FILES {
            if *what != IdlUse::ProxyTablesOnly {
                continue;
            }
            let text = std::fs::read_to_string(root().join(path)).unwrap();
            // Declarations only: without the `//` comments (these files have no other kind).
            let text: String = text
                .lines()
                .map(|l| l.split("//").next().unwrap_or(""))
                .collect::<Vec<_>>()
                .join("\n");
            let mut words = text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'));
            while let Some(word) = words.next() {
                if word != "interface" {
                    continue;
                }
                let Some(name) = words.find(|w| !w.is_empty()) else {
                    break;
                };
                seen += 1;
                for declared in [format!("__{name}_FWD_DEFINED__"), format!("IID_{name}")] {
                    let whole_word = header.match_indices(&declared).any(|(at, _)| {
                        !header[at + declared.len()..].starts_with(|c: char| c.is_ascii_alphanumeric() || c == '_')
                    });
                    assert!(!whole_word, "{HEADER} declares {name} of {path}");
                }
            }
        }
        assert!(seen >= 35, "only {seen} interfaces found in the proxy-only IDL files");
    }

    #[test]
    fn a_version_splits_into_its_numbers_and_its_prerelease() {
        assert_eq!(split_version("0.2.0"), ("0.2.0", None));
        assert_eq!(split_version("0.3.0-dev"), ("0.3.0", Some("dev")));
        assert_eq!(split_version("1.0.0-rc.1+build.5"), ("1.0.0", Some("rc.1")));
        assert_eq!(split_version("1.0.0+build.5"), ("1.0.0", None));
    }
}
