//! Build script, one module per job:
//!
//! - [`soname`]: platform details of the shared library (the SONAME on Linux);
//! - [`catalog`]: the error catalog (`src/errors/catalog/<language>.txt`) turned into static tables
//!   (`$OUT_DIR/catalog.rs`, included by `src/errors/catalog.rs`), from the specifications and
//!   languages of `src/errors/catalog/tables.rs`, which the library compiles too;
//! - [`resources`]: for Windows targets built with mingw, the DLL's message table (from the same
//!   catalog) and VERSIONINFO;
//! - [`proxy`]: for the same targets, the proxy/stub of the OPC Common interfaces (src/proxy).

mod catalog;
mod proxy;
mod resources;
mod soname;

use std::env;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=buildscript");
    println!("cargo:rustc-check-cfg=cfg(opccomn_proxy_stub)");
    let manifest_dir = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap());
    let out_dir = PathBuf::from(env::var("OUT_DIR").unwrap());
    let target_os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();

    soname::emit(&target_os);
    let catalogs = catalog::build(&manifest_dir, &out_dir);
    if target_os == "windows" {
        resources::build(&out_dir, &catalogs);
        proxy::build(&manifest_dir, &out_dir);
    }
}
