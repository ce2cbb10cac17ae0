//! The proxy/stub's NDR layouts, generated from the IDL: `src/proxy/generated/layouts.rs` (every
//! method's request and reply of the served interfaces, in the layout language of
//! `src/proxy/ndr/layout.rs`, with the interfaces' numbering and registration table),
//! `src/proxy/generated/interfaces.h` (the same numbering for `src/proxy/opccomn_ps.c`), and
//! `src/proxy/generated/test_layouts.rs` (the layouts of `idl/testdata/ndr-constructs.idl`, which
//! uses every construct, for the interpreter's tests).
//!
//! The bounds of arrays whose counts a peer chooses come from `idl/ndr-bounds.txt` (and
//! `idl/testdata/ndr-constructs-bounds.txt`): `Interface.Method.parameter` or `Structure.field`, the
//! bound, and why. Every such array of the served IDL must be named there; the test IDL's may take
//! [`resolve::DEFAULT_BOUND`].

mod emit;
mod parse;
mod resolve;

#[cfg(test)]
mod tests;

/// The IDL files whose interfaces the proxy/stub serves, in the order they are numbered, each with
/// the name of its specification (what registration's command line chooses by).
pub const SERVED: &[(&str, &str)] = &[
    ("idl/opccomn.idl", "Common"),
    ("idl/opcda.idl", "DA"),
    ("idl/opc_ae.idl", "AE"),
    ("idl/opchda.idl", "HDA"),
];
/// Files whose interfaces the served ones may name (for their IIDs).
const SYSTEM: &[&str] = &["idl/combase.idl", "idl/internal.idl"];
const BOUNDS: &str = "idl/ndr-bounds.txt";
pub const TEST_IDL: &str = "idl/testdata/ndr-constructs.idl";
pub const TEST_BOUNDS: &str = "idl/testdata/ndr-constructs-bounds.txt";
/// The interpreter's `CONTEXT_WORDS` (src/proxy/ndr/mod.rs).
const CONTEXT_WORDS: usize = 8;

const PURPOSE: &str =
    "//! The NDR layout of every method's request and reply of the interfaces opccomn's proxy/stub serves\n\
//! (the language: src/proxy/ndr/layout.rs; what the interpreter checks: src/proxy/ndr/mod.rs), their\n\
//! numbering, which src/proxy/generated/interfaces.h gives src/proxy/opccomn_ps.c, and their\n\
//! registration table.\n";

const TEST_PURPOSE: &str =
    "//! Layouts of a test IDL that uses every construct of the layout language; the interpreter's tests\n\
//! (src/proxy/ndr/tests.rs) and the `ndr` fuzz target read messages against them.\n";

/// The layouts of the interfaces of `served`, with `system` for the interfaces they name.
fn model(
    read: &dyn Fn(&str) -> String,
    served: &[(&str, &str)],
    system: &[&str],
    bounds: &str,
    require_bounds: bool,
) -> Result<resolve::Model, String> {
    let mut files = Vec::new();
    for path in served.iter().map(|(path, _)| path).chain(system) {
        files.push(parse::parse(path, &read(path)).map_err(|e| e.to_string())?);
    }
    let bounds = resolve::parse_bounds(bounds, &read(bounds))?;
    resolve::model(&files, served, &bounds, require_bounds)
}

/// The generated files: (path, text); `format` is rustfmt.
pub fn outputs(
    read: &dyn Fn(&str) -> String,
    format: &dyn Fn(&str) -> String,
) -> Result<Vec<(&'static str, String)>, String> {
    // Every bound of the served interfaces is a decision with its reason; the test IDL's arrays may
    // take the default.
    let served = model(read, SERVED, SYSTEM, BOUNDS, true)?;
    let files: Vec<&str> = SERVED.iter().map(|(path, _)| *path).collect();
    let sources = format!("{} and {BOUNDS}", files.join(", "));
    let test = model(read, &[(TEST_IDL, "Test")], &["idl/combase.idl"], TEST_BOUNDS, false)?;
    Ok(vec![
        (
            "src/proxy/generated/layouts.rs",
            format(&emit::rust(&served, &sources, PURPOSE)),
        ),
        (
            "src/proxy/generated/interfaces.h",
            emit::c_include(&served, &sources, CONTEXT_WORDS),
        ),
        ("tests/oop/ps_args.h", emit::c_args(&served, &sources)),
        (
            "src/proxy/generated/test_layouts.rs",
            format(&emit::rust(
                &test,
                &format!("{TEST_IDL} and {TEST_BOUNDS}"),
                TEST_PURPOSE,
            )),
        ),
    ])
}
