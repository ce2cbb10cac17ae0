//! The C tools a Windows build needs besides rustc: a message compiler and a resource compiler (the
//! DLL's message table and VERSIONINFO), a C compiler and an archiver (the proxy/stub). Every one of
//! them is found before anything is built; when one is missing the build stops and says which and how
//! to get it, so a DLL without its message table, VERSIONINFO or proxy/stub is never made.
//!
//! | toolchain (target env) | message / resource compiler | C compiler / archiver | override with |
//! |---|---|---|---|
//! | mingw-w64 (`gnu`) | `<triple>-windmc`, `<triple>-windres` | `<triple>-gcc`, `<triple>-ar` | OPCCOMN_WINDMC, OPCCOMN_WINDRES, OPCCOMN_CC, OPCCOMN_AR |
//! | Visual Studio (`msvc`) | `mc`, `rc` (Windows SDK) | `cl`, `lib` | OPCCOMN_MC, OPCCOMN_RC, OPCCOMN_CL, OPCCOMN_LIB |

use std::env;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The C toolchain of a Windows target, with the program of each tool.
pub enum Toolchain {
    Mingw,
    Msvc,
}

/// One tool: the environment variable that overrides it, and its default program name.
struct Tool {
    var: &'static str,
    program: String,
    what: &'static str,
}

impl Toolchain {
    /// The toolchain of the target being built, after checking that each of its tools can be found.
    /// Panics (stops the build) with what is missing and how to get it.
    pub fn for_target() -> Toolchain {
        for var in [
            "OPCCOMN_WINDMC",
            "OPCCOMN_WINDRES",
            "OPCCOMN_CC",
            "OPCCOMN_AR",
            "OPCCOMN_MC",
            "OPCCOMN_RC",
            "OPCCOMN_CL",
            "OPCCOMN_LIB",
        ] {
            println!("cargo:rerun-if-env-changed={var}");
        }
        println!("cargo:rerun-if-env-changed=PATH");
        let env = env::var("CARGO_CFG_TARGET_ENV").unwrap_or_default();
        let toolchain = match env.as_str() {
            "gnu" => Toolchain::Mingw,
            "msvc" => Toolchain::Msvc,
            other => panic!(
                "opccomn: Windows target environment '{other}' is not supported: build for \
                 x86_64-pc-windows-gnu / i686-pc-windows-gnu (mingw-w64) or x86_64-pc-windows-msvc / \
                 i686-pc-windows-msvc (Visual Studio)"
            ),
        };
        let missing: Vec<String> = toolchain
            .tools()
            .iter()
            .filter(|tool| find_program(&tool.program()).is_none())
            .map(|tool| {
                format!(
                    "{} ({}, or set {})",
                    tool.program().to_string_lossy(),
                    tool.what,
                    tool.var
                )
            })
            .collect();
        if !missing.is_empty() {
            panic!("{}", toolchain.missing_message(&missing));
        }
        toolchain
    }

    fn tools(&self) -> [Tool; 4] {
        match self {
            Toolchain::Mingw => [
                mingw("OPCCOMN_WINDMC", "windmc", "the message compiler"),
                mingw("OPCCOMN_WINDRES", "windres", "the resource compiler"),
                mingw("OPCCOMN_CC", "gcc", "the C compiler"),
                mingw("OPCCOMN_AR", "ar", "the archiver"),
            ],
            Toolchain::Msvc => [
                msvc("OPCCOMN_MC", "mc", "the Windows SDK's message compiler"),
                msvc("OPCCOMN_RC", "rc", "the Windows SDK's resource compiler"),
                msvc("OPCCOMN_CL", "cl", "the MSVC C compiler"),
                msvc("OPCCOMN_LIB", "lib", "the MSVC library manager"),
            ],
        }
    }

    fn missing_message(&self, missing: &[String]) -> String {
        let list = missing.join(", ");
        match self {
            Toolchain::Mingw => format!(
                "opccomn: the Windows DLL needs these mingw-w64 tools, not found: {list}. On Debian: apt \
                 install gcc-mingw-w64-x86-64 binutils-mingw-w64-x86-64 (-i686 for x86). Without them \
                 the DLL would lack its message table, VERSIONINFO and proxy/stub, so it is not built."
            ),
            Toolchain::Msvc => format!(
                "opccomn: a Visual Studio (MSVC) build of the DLL needs these tools, not found: {list}. \
                 They come with Visual Studio's \"Desktop development with C++\" workload (cl, lib) and \
                 the Windows SDK (mc, rc): run cargo or CMake from a \"Developer Command Prompt\" or \
                 \"x64 Native Tools Command Prompt\" (vcvarsall.bat), which puts them on PATH. Without \
                 them the DLL would lack its message table, VERSIONINFO and proxy/stub, so it is not \
                 built. Or build with mingw-w64 instead (rustup target add x86_64-pc-windows-gnu; see \
                 docs/windows.md): that DLL and its opccomn.lib work with Visual Studio programs too."
            ),
        }
    }

    pub fn message_compiler(&self) -> OsString {
        self.tools()[0].program()
    }

    pub fn resource_compiler(&self) -> OsString {
        self.tools()[1].program()
    }

    pub fn c_compiler(&self) -> OsString {
        self.tools()[2].program()
    }

    pub fn archiver(&self) -> OsString {
        self.tools()[3].program()
    }
}

impl Tool {
    /// The program: the override when set, else the default name.
    fn program(&self) -> OsString {
        env::var_os(self.var).unwrap_or_else(|| OsString::from(&self.program))
    }
}

fn mingw(var: &'static str, name: &str, what: &'static str) -> Tool {
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let prefix = match arch.as_str() {
        "x86" => "i686",
        other => other,
    };
    Tool {
        var,
        program: format!("{prefix}-w64-mingw32-{name}"),
        what,
    }
}

fn msvc(var: &'static str, name: &str, what: &'static str) -> Tool {
    Tool {
        var,
        program: name.to_owned(),
        what,
    }
}

/// Where `program` is: itself when it names a path, else the first match on PATH (with the
/// extensions of PATHEXT on a Windows host).
fn find_program(program: &OsString) -> Option<PathBuf> {
    let path = Path::new(program);
    if path.components().count() > 1 {
        return path.is_file().then(|| path.to_path_buf());
    }
    let extensions: Vec<OsString> = if cfg!(windows) {
        let pathext = env::var("PATHEXT").unwrap_or_else(|_| ".COM;.EXE;.BAT;.CMD".into());
        std::iter::once(OsString::new())
            .chain(pathext.split(';').filter(|e| !e.is_empty()).map(OsString::from))
            .collect()
    } else {
        vec![OsString::new()]
    };
    let dirs = env::var_os("PATH")?;
    env::split_paths(&dirs).find_map(|dir| {
        extensions.iter().find_map(|ext| {
            let mut name = program.clone();
            name.push(ext);
            let candidate = dir.join(name);
            candidate.is_file().then_some(candidate)
        })
    })
}

/// Runs a tool; a failure stops the build with the command line.
pub(crate) fn run(mut command: Command) {
    let shown = format!("{command:?}");
    match command.status() {
        Ok(status) if status.success() => {}
        Ok(status) => panic!("{shown} failed: {status}"),
        Err(e) => panic!("cannot run {shown}: {e}"),
    }
}
