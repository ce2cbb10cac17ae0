//! For Windows targets, the proxy/stub of the OPC Common, Data Access, Alarms & Events and HDA
//! interfaces: compiles `src/proxy/opccomn_ps.c`, `opcda_ps.c`, `opc_ae_ps.c` and `opchda_ps.c` (with
//! the NDR tables `tools/gen-proxy.py` generated from the IDL files of `idl/` into `src/proxy/generated/`, and the interface
//! table `tools/gen-header` generated beside them) into a static library, links it, rpcrt4 (the NDR
//! engine that interprets the tables) and uuid, and sets `cfg(opccomn_proxy_stub)` for src/proxy. With
//! mingw the tools are `<triple>-gcc` and `<triple>-ar` (or OPCCOMN_CC / OPCCOMN_AR), with MSVC `cl`
//! and `lib` (or OPCCOMN_CL / OPCCOMN_LIB), see [`crate::toolchain`].

use std::fs;
use std::path::Path;
use std::process::Command;

use crate::toolchain::{run, Toolchain};

pub fn build(manifest_dir: &Path, out_dir: &Path, toolchain: &Toolchain) {
    let src = manifest_dir.join("src/proxy");
    // Each table file on its own (they define the same static names), with its checking wrapper.
    let units = ["opccomn_ps", "opcda_ps", "opc_ae_ps", "opchda_ps"];
    for file in [
        "opccomn_ps.c",
        "opcda_ps.c",
        "generated/interfaces.h",
        "generated/opccomn_idl.h",
        "generated/opccomn_p_win64.c",
        "generated/opccomn_p_win32.c",
        "generated/opcda_idl.h",
        "generated/opcda_p_win64.c",
        "generated/opcda_p_win32.c",
        "opc_ae_ps.c",
        "opchda_ps.c",
        "generated/opc_ae_idl.h",
        "generated/opc_ae_p_win64.c",
        "generated/opc_ae_p_win32.c",
        "generated/opchda_idl.h",
        "generated/opchda_p_win64.c",
        "generated/opchda_p_win32.c",
    ] {
        println!("cargo:rerun-if-changed={}", src.join(file).display());
    }
    let dir = out_dir.join("proxy");
    fs::create_dir_all(&dir).expect("create proxy dir");
    let library = match toolchain {
        Toolchain::Mingw => dir.join("libopccomn_ps.a"),
        Toolchain::Msvc => dir.join("opccomn_ps.lib"),
    };
    let mut objects = Vec::new();
    for unit in units {
        let object = match toolchain {
            Toolchain::Mingw => dir.join(format!("{unit}.o")),
            Toolchain::Msvc => dir.join(format!("{unit}.obj")),
        };
        let mut cc = Command::new(toolchain.c_compiler());
        match toolchain {
            Toolchain::Mingw => {
                cc.args(["-c", "-O2", "-Wall", "-Werror", "-o"]).arg(&object);
            }
            Toolchain::Msvc => {
                let mut fo = std::ffi::OsString::from("/Fo");
                fo.push(&object);
                cc.args(["/nologo", "/c", "/O2", "/W3", "/WX"]).arg(fo);
            }
        }
        cc.arg(src.join(format!("{unit}.c")));
        run(cc);
        objects.push(object);
    }
    let _ = fs::remove_file(&library);
    let mut ar = Command::new(toolchain.archiver());
    match toolchain {
        Toolchain::Mingw => {
            ar.arg("crs").arg(&library);
        }
        Toolchain::Msvc => {
            let mut out = std::ffi::OsString::from("/OUT:");
            out.push(&library);
            ar.arg("/nologo").arg(out);
        }
    }
    ar.args(&objects);
    run(ar);
    println!("cargo:rustc-link-search=native={}", dir.display());
    println!("cargo:rustc-link-lib=static=opccomn_ps");
    println!("cargo:rustc-link-lib=dylib=rpcrt4");
    // The Automation types' marshalling (VARIANT, BSTR, SAFEARRAY user-marshal routines) of the DA tables.
    println!("cargo:rustc-link-lib=dylib=oleaut32");
    // The IIDs of IUnknown, IPSFactoryBuffer, IRpcProxyBuffer and IRpcChannelBuffer (mingw's libuuid.a).
    println!("cargo:rustc-link-lib=uuid");
    println!("cargo:rustc-cfg=opccomn_proxy_stub");
}
