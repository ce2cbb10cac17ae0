//! Build script: platform details of the shared library.

fn main() {
    let target_os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if target_os == "linux" {
        // Programs linked against libopccomn.so record this name, not the build path.
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libopccomn.so");
    }
    println!("cargo:rerun-if-changed=build.rs");
}
