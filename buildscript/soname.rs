//! Platform details of the shared library.

/// Programs linked against libopccomn.so record the name `libopccomn.so`, not the build path.
pub fn emit(target_os: &str) {
    if target_os == "linux" {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libopccomn.so");
    }
}
