//! The areas of the C API reference, one page each: every declaration at the top level of the header
//! is in one (`@ingroup`, written by `apidoc`), found here by the Rust source that defines it, the
//! interface it belongs to, or its row of idl/opcguids.txt. The areas themselves (title, introduction,
//! example) are defined in docs/reference/areas.dox. A declaration in no area stops the generator.

use crate::guids::Entry;

/// Rust sources (a file, or a folder ending in `/`) and their area; the first match wins.
pub const SOURCES: &[(&str, &str)] = &[
    ("src/com/module_lock.rs", "plumbing"),
    ("src/com/alloc.rs", "memory"),
    ("src/lib.rs", "memory"),
    ("src/com/", "com"),
    ("src/locale.rs", "com"),
    ("src/common/", "iopccommon"),
    ("src/errors/", "errors"),
    ("src/pattern/", "pattern"),
    ("src/proxy/", "proxystub"),
    ("src/registry/mod.rs", "registry"),
    ("src/registry/regfile.rs", "registry"),
    ("src/registry/", "registration"),
    ("src/security/", "security"),
    ("src/server/", "plumbing"),
    ("src/serverlist/", "browser"),
    // opccomn's own class table and entry points: the browser's class object and registration.
    ("src/module.rs", "browser"),
    ("src/shutdown/", "shutdown"),
];

/// The OPC Common interfaces (idl/opccomn.idl) and their areas; the interfaces of idl/combase.idl are
/// in `com`.
pub const INTERFACES: &[(&str, &str)] = &[
    ("IOPCShutdown", "shutdown"),
    ("IOPCCommon", "iopccommon"),
    ("IOPCServerList", "browser"),
    ("IOPCServerList2", "browser"),
    ("IOPCEnumGUID", "browser"),
];

/// The classes of idl/opcguids.txt and their areas; its categories are in `registration`.
pub const CLASSES: &[(&str, &str)] = &[
    ("CLSID_OPCServerList", "browser"),
    ("CLSID_OpcComnProxyStub", "proxystub"),
];

/// Declarations by name: those written by hand in cbindgen.toml (and the generator), and the few whose
/// area is not their source's (an OPC code defined among COM's).
pub const NAMED: &[(&str, &str)] = &[
    ("OPC_E_INVALIDFILTER", "pattern"),
    ("OPCCOMN_VERSION_MAJOR", "header"),
    ("OPCCOMN_VERSION_MINOR", "header"),
    ("OPCCOMN_VERSION_PATCH", "header"),
    ("OPCCOMN_VERSION", "header"),
    ("OPCCOMN_VERSION_PRERELEASE", "header"),
    ("OPCCOMN_CDECL", "header"),
    ("OPCCOMN_STDCALL", "header"),
    ("OPCCOMN_RIID", "header"),
    ("MIDL_INTERFACE", "com"),
    ("OPCCOMN_TCHAR_MACROS", "pattern"),
    ("MatchPattern", "pattern"),
    ("OpcPatternCompile", "pattern"),
    ("OpcPatternMatch", "pattern"),
];

/// The area of the Rust source `file` (relative to the repository's root).
pub fn of_source(file: &str) -> Option<&'static str> {
    SOURCES
        .iter()
        .find(|(prefix, _)| {
            if prefix.ends_with('/') {
                file.starts_with(prefix)
            } else {
                file == *prefix
            }
        })
        .map(|(_, g)| *g)
}

/// The area of a declaration named `name` in the section of interface `interface` (if any).
pub fn of(
    name: &str,
    interface: Option<&str>,
    origins: &std::collections::BTreeMap<String, String>,
    base_interfaces: &[String],
    table: &[Entry],
) -> Option<&'static str> {
    let by_table = |n: &str| {
        table
            .iter()
            .find(|e| e.name == n || e.interface_name() == n)
            .and_then(|e| {
                if e.kind == "category" {
                    Some("registration")
                } else {
                    CLASSES.iter().find(|(c, _)| *c == e.name).map(|(_, g)| *g)
                }
            })
    };
    if let Some(i) = interface {
        if let Some((_, g)) = INTERFACES.iter().find(|(n, _)| *n == i) {
            return Some(g);
        }
        if base_interfaces.iter().any(|b| b == i) {
            return Some("com");
        }
        return by_table(i);
    }
    if let Some((_, g)) = NAMED.iter().find(|(n, _)| *n == name) {
        return Some(g);
    }
    if let Some(file) = origins.get(name) {
        return of_source(file);
    }
    by_table(name)
}

#[cfg(test)]
mod tests {
    use super::of_source;

    #[test]
    fn a_file_takes_the_first_matching_area() {
        assert_eq!(of_source("src/com/alloc.rs"), Some("memory"));
        assert_eq!(of_source("src/com/types.rs"), Some("com"));
        assert_eq!(of_source("src/registry/mod.rs"), Some("registry"));
        assert_eq!(of_source("src/registry/register/description.rs"), Some("registration"));
        assert_eq!(of_source("src/elsewhere.rs"), None);
    }
}
