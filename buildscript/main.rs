//! Build script, one module per job:
//!
//! - [`soname`]: platform details of the shared library (the SONAME on Linux);
//! - [`catalog`]: the error catalog (`src/errors/catalog/<language>.txt`) turned into static tables
//!   (`$OUT_DIR/catalog.rs`, included by `src/errors/catalog.rs`), from the specifications and
//!   languages of `src/errors/catalog/tables.rs`, which the library compiles too;
//! - [`toolchain`]: for Windows targets, the C tools of the target's toolchain (mingw-w64 or MSVC),
//!   or a stop that names what is missing: a DLL without its resources or proxy/stub is never built;
//! - [`resources`]: for Windows targets, the DLL's message table (from the same catalog) and
//!   VERSIONINFO;
//! - [`proxy`]: for the same targets, the proxy/stub of the OPC Common interfaces (src/proxy).

mod catalog;
mod proxy;
mod resources;
mod soname;
mod toolchain;

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
        let toolchain = toolchain::Toolchain::for_target();
        resources::build(&out_dir, &catalogs, &toolchain);
        proxy::build(&manifest_dir, &out_dir, &toolchain);
    }
}
