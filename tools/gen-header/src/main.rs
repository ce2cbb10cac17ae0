//! Generates `include/opccomn.h` with cbindgen, using `cbindgen.toml` at the crate root.
//!
//! `gen-header` writes the header; `gen-header --check` exits 1 when the committed header differs from
//! what the sources generate now (CI runs this, so the header cannot drift).

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let check = std::env::args().skip(1).any(|a| a == "--check");
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let root = root.canonicalize().expect("crate root");
    let mut config = cbindgen::Config::from_file(root.join("cbindgen.toml")).expect("cbindgen.toml");
    // The version macros come from Cargo.toml, never from a hand-kept copy.
    let version = package_version(&root);
    let mut parts = version.split(['.', '-', '+']);
    let mut next = || parts.next().unwrap_or("0").to_string();
    let (major, minor, patch) = (next(), next(), next());
    config.after_includes = config.after_includes.map(|text| {
        text.replace("@MAJOR@", &major)
            .replace("@MINOR@", &minor)
            .replace("@PATCH@", &patch)
            .replace("@VERSION@", &version)
    });
    let bindings = cbindgen::Builder::new()
        .with_crate(&root)
        .with_config(config)
        .generate()
        .expect("cbindgen could not generate the header");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let header = root.join("include/opccomn.h");
    let current = std::fs::read(&header).unwrap_or_default();
    if current == generated {
        println!("include/opccomn.h is up to date");
        return ExitCode::SUCCESS;
    }
    if check {
        eprintln!(
            "include/opccomn.h differs from what the sources generate: run `cargo run -p gen-header` and commit it"
        );
        return ExitCode::FAILURE;
    }
    std::fs::write(&header, generated).expect("write include/opccomn.h");
    println!("wrote include/opccomn.h");
    ExitCode::SUCCESS
}

/// The `version` of the `[package]` table in the crate's Cargo.toml.
fn package_version(root: &std::path::Path) -> String {
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
