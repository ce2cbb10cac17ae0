//! For Windows targets built with mingw, the proxy/stub of the OPC Common interfaces: compiles
//! `src/proxy/opccomn_ps.c` (with the NDR tables `tools/gen-proxy.py` generated from
//! `idl/opccomn.idl` into `src/proxy/generated/`) with `<triple>-gcc` (or OPCCOMN_CC) into a static
//! library (`<triple>-ar` or OPCCOMN_AR), links it and rpcrt4 (the NDR engine that interprets the
//! tables) and uuid, and sets `cfg(opccomn_proxy_stub)` for src/proxy. MSVC builds get no proxy/stub (a build
//! warning says so).

use std::path::Path;
use std::process::Command;
use std::{env, fs};

use crate::resources::{run, tool};

pub fn build(manifest_dir: &Path, out_dir: &Path) {
    println!("cargo:rerun-if-env-changed=OPCCOMN_CC");
    println!("cargo:rerun-if-env-changed=OPCCOMN_AR");
    if env::var("CARGO_CFG_TARGET_ENV").as_deref() != Ok("gnu") {
        println!("cargo:warning=opccomn: the proxy/stub (src/proxy) is built only with mingw");
        return;
    }
    let src = manifest_dir.join("src/proxy");
    for file in [
        "opccomn_ps.c",
        "generated/opccomn_idl.h",
        "generated/opccomn_p_win64.c",
        "generated/opccomn_p_win32.c",
    ] {
        println!("cargo:rerun-if-changed={}", src.join(file).display());
    }
    let dir = out_dir.join("proxy");
    fs::create_dir_all(&dir).expect("create proxy dir");
    let object = dir.join("opccomn_ps.o");
    let mut cc = Command::new(tool("OPCCOMN_CC", "gcc"));
    cc.args(["-c", "-O2", "-Wall", "-Werror", "-o"])
        .arg(&object)
        .arg(src.join("opccomn_ps.c"));
    run(cc);
    let library = dir.join("libopccomn_ps.a");
    let _ = fs::remove_file(&library);
    let mut ar = Command::new(tool("OPCCOMN_AR", "ar"));
    ar.arg("crs").arg(&library).arg(&object);
    run(ar);
    println!("cargo:rustc-link-search=native={}", dir.display());
    println!("cargo:rustc-link-lib=static=opccomn_ps");
    println!("cargo:rustc-link-lib=dylib=rpcrt4");
    // The IIDs of IUnknown, IPSFactoryBuffer, IRpcProxyBuffer and IRpcChannelBuffer (mingw's libuuid.a).
    println!("cargo:rustc-link-lib=uuid");
    println!("cargo:rustc-cfg=opccomn_proxy_stub");
}
