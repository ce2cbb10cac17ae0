//! Platform details of the shared library.

/// Programs linked against libopccomn.so record the versioned name `libopccomn.so.N`, N being the
/// major version of Cargo.toml (0 until 1.0), not the build path and not the unversioned name: a
/// release whose exports are not compatible with the previous ones raises N (docs/abi-policy.md),
/// so a program keeps loading the library it was linked against. The CMake build puts the
/// `libopccomn.so.N` link next to the library it builds and installs the usual chain
/// (`libopccomn.so` -> `libopccomn.so.N` -> `libopccomn.so.MAJOR.MINOR.PATCH`).
pub fn emit(target_os: &str) {
    if target_os == "linux" {
        let major = std::env::var("CARGO_PKG_VERSION_MAJOR").expect("cargo sets CARGO_PKG_VERSION_MAJOR");
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libopccomn.so.{major}");
    }
}
