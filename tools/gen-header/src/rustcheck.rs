//! Reads the library's Rust sources (with syn) for what the header must agree with: the `#[repr(C)]`
//! vtable structs, which must have the IDL's methods in the IDL's order with the IDL's parameters, and
//! the exported functions with their calling conventions.

use std::collections::BTreeMap;
use std::path::Path;

use crate::emit::Catalog;
use crate::idl::Interface;

/// One `fn` pointer field of a vtable struct.
pub struct Field {
    pub name: String,
    pub abi: Option<String>,
    /// (parameter name, normalised base type, pointer depth)
    pub params: Vec<(String, String, usize)>,
}

pub struct Sources {
    /// Vtable structs by name (a name may occur more than once, e.g. in tests).
    pub vtables: BTreeMap<String, Vec<(String, Vec<Field>)>>,
    /// `#[no_mangle]` / `#[export_name]` functions: symbol → ABI ("C" or "system").
    pub functions: BTreeMap<String, String>,
    /// Function pointer types (`pub type F = Option<unsafe extern "C" fn(...)>`): name → ABI.
    pub callbacks: BTreeMap<String, String>,
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .expect("read src")
        .flatten()
        .map(|e| e.path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// `GUID`, `CLSID`, `IID` and `CATID` are one type; so are the string aliases.
fn normalise(name: &str) -> String {
    match name {
        "CLSID" | "IID" | "CATID" => "GUID",
        "LPOLESTR" => "LPWSTR",
        "LPCOLESTR" => "LPCWSTR",
        "c_void" => "void",
        other => other,
    }
    .to_string()
}

fn rust_type(ty: &syn::Type) -> (String, usize) {
    match ty {
        syn::Type::Ptr(p) => {
            let (base, depth) = rust_type(&p.elem);
            (base, depth + 1)
        }
        syn::Type::Path(p) => (
            normalise(&p.path.segments.last().map(|s| s.ident.to_string()).unwrap_or_default()),
            0,
        ),
        _ => ("?".into(), 0),
    }
}

/// The base type and pointer depth of an IDL parameter type (`const GUID *` → ("GUID", 1)).
pub fn idl_type(ty: &str, array: bool) -> (String, usize) {
    let base = ty
        .split_whitespace()
        .rfind(|w| *w != "const" && !w.chars().all(|c| c == '*'))
        .unwrap_or("");
    (normalise(base), ty.matches('*').count() + usize::from(array))
}

fn visit_items(items: &[syn::Item], file: &str, out: &mut Sources) {
    for item in items {
        match item {
            syn::Item::Struct(s) if s.ident.to_string().ends_with("Vtbl") => {
                let mut fields = Vec::new();
                if let syn::Fields::Named(named) = &s.fields {
                    for f in &named.named {
                        let syn::Type::BareFn(fun) = &f.ty else { continue };
                        let abi = fun
                            .abi
                            .as_ref()
                            .map(|a| a.name.as_ref().map_or("C".into(), |n| n.value()));
                        let params = fun
                            .inputs
                            .iter()
                            .map(|a| {
                                let name = a.name.as_ref().map(|(n, _)| n.to_string()).unwrap_or_default();
                                let (base, depth) = rust_type(&a.ty);
                                (name, base, depth)
                            })
                            .collect();
                        fields.push(Field {
                            name: f.ident.as_ref().map(|i| i.to_string()).unwrap_or_default(),
                            abi,
                            params,
                        });
                    }
                }
                out.vtables
                    .entry(s.ident.to_string())
                    .or_default()
                    .push((file.to_string(), fields));
            }
            syn::Item::Fn(f) => {
                let exported = f.attrs.iter().any(|a| {
                    let p = a.path();
                    p.is_ident("no_mangle")
                        || p.is_ident("export_name")
                        || (p.is_ident("unsafe")
                            && a.parse_args::<syn::Path>()
                                .is_ok_and(|inner| inner.is_ident("no_mangle")))
                });
                if let (true, Some(abi)) = (exported, &f.sig.abi) {
                    let abi = abi.name.as_ref().map_or("C".into(), |n| n.value());
                    out.functions.insert(f.sig.ident.to_string(), abi);
                }
            }
            syn::Item::Type(t) => {
                let mut ty = &*t.ty;
                // Option<fn(...)>
                if let syn::Type::Path(p) = ty {
                    if let Some(seg) = p.path.segments.last().filter(|s| s.ident == "Option") {
                        if let syn::PathArguments::AngleBracketed(a) = &seg.arguments {
                            if let Some(syn::GenericArgument::Type(inner)) = a.args.first() {
                                ty = inner;
                            }
                        }
                    }
                }
                if let syn::Type::BareFn(f) = ty {
                    let abi = f
                        .abi
                        .as_ref()
                        .map_or("Rust".into(), |a| a.name.as_ref().map_or("C".into(), |n| n.value()));
                    out.callbacks.insert(t.ident.to_string(), abi);
                }
            }
            syn::Item::Mod(m) => {
                if let Some((_, items)) = &m.content {
                    visit_items(items, file, out);
                }
            }
            _ => {}
        }
    }
}

pub fn read(root: &Path) -> Sources {
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    let mut out = Sources {
        vtables: BTreeMap::new(),
        functions: BTreeMap::new(),
        callbacks: BTreeMap::new(),
    };
    for path in files {
        let text = std::fs::read_to_string(&path).expect("read a Rust source");
        let file = syn::parse_file(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let rel = path.strip_prefix(root).unwrap_or(&path).display().to_string();
        visit_items(&file.items, &rel, &mut out);
    }
    out
}

/// Compares every IDL interface with the Rust vtable struct of the same name; returns the differences.
pub fn check_vtables(catalog: &Catalog, interfaces: &[&Interface], sources: &Sources) -> Vec<String> {
    let mut problems = Vec::new();
    for i in interfaces {
        let vname = format!("{}Vtbl", i.name);
        let Some(found) = sources.vtables.get(&vname) else {
            problems.push(format!("no Rust struct {vname} for the IDL interface {}", i.name));
            continue;
        };
        let expected = catalog.vtable(i);
        for (file, fields) in found {
            let names: Vec<&str> = fields.iter().map(|f| f.name.as_str()).collect();
            let idl_names: Vec<&str> = expected.iter().map(|(_, m)| m.name.as_str()).collect();
            if names != idl_names {
                problems.push(format!(
                    "{file}: {vname} has the methods {names:?}, the IDL has {idl_names:?} (names and order must match)"
                ));
                continue;
            }
            for (field, (_, m)) in fields.iter().zip(&expected) {
                let at = format!("{file}: {vname}::{}", field.name);
                if field.abi.as_deref() != Some("system") {
                    problems.push(format!("{at} is not `extern \"system\"` (STDMETHODCALLTYPE)"));
                }
                let mut want: Vec<(String, String, usize)> = vec![("This".into(), i.name.clone(), 1)];
                for p in &m.params {
                    let (base, depth) = idl_type(&p.ty, p.array);
                    want.push((p.name.clone(), base, depth));
                }
                if field.params != want {
                    problems.push(format!("{at}: parameters {:?}, the IDL says {:?}", field.params, want));
                }
            }
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::idl;

    const IDL: &str = r#"
        [object, uuid(00000000-0000-0000-C000-000000000046)]
        interface IUnknown {
            HRESULT QueryInterface([in] REFIID riid, [out] void **ppvObject);
            ULONG AddRef();
            ULONG Release();
        }
        [object, uuid(F31DFDE1-07B6-11d2-B2D8-0060083BA1FB)]
        interface IOPCShutdown : IUnknown { HRESULT ShutdownRequest([in, string] LPCWSTR szReason); }
    "#;

    fn problems(rust: &str) -> Vec<String> {
        let ifs = idl::parse("t.idl", IDL).unwrap();
        let catalog = Catalog::new(ifs.iter());
        let mut sources = Sources {
            vtables: BTreeMap::new(),
            functions: BTreeMap::new(),
            callbacks: BTreeMap::new(),
        };
        visit_items(&syn::parse_file(rust).unwrap().items, "t.rs", &mut sources);
        let all: Vec<&Interface> = ifs.iter().collect();
        check_vtables(&catalog, &all, &sources)
    }

    const GOOD: &str = r#"
        pub struct IUnknownVtbl {
            pub QueryInterface: unsafe extern "system" fn(This: *mut IUnknown, riid: REFIID, ppvObject: *mut *mut c_void) -> HRESULT,
            pub AddRef: unsafe extern "system" fn(This: *mut IUnknown) -> ULONG,
            pub Release: unsafe extern "system" fn(This: *mut IUnknown) -> ULONG,
        }
        pub struct IOPCShutdownVtbl {
            pub QueryInterface: unsafe extern "system" fn(This: *mut IOPCShutdown, riid: REFIID, ppvObject: *mut *mut c_void) -> HRESULT,
            pub AddRef: unsafe extern "system" fn(This: *mut IOPCShutdown) -> ULONG,
            pub Release: unsafe extern "system" fn(This: *mut IOPCShutdown) -> ULONG,
            pub ShutdownRequest: unsafe extern "system" fn(This: *mut IOPCShutdown, szReason: LPCWSTR) -> HRESULT,
        }
    "#;

    #[test]
    fn matching_vtables_pass() {
        assert_eq!(problems(GOOD), Vec::<String>::new());
    }

    #[test]
    fn order_abi_parameters_and_missing_structs_are_reported() {
        let swapped = GOOD.replace(
            "pub AddRef: unsafe extern \"system\" fn(This: *mut IOPCShutdown) -> ULONG,\n            pub Release: unsafe extern \"system\" fn(This: *mut IOPCShutdown) -> ULONG,",
            "pub Release: unsafe extern \"system\" fn(This: *mut IOPCShutdown) -> ULONG,\n            pub AddRef: unsafe extern \"system\" fn(This: *mut IOPCShutdown) -> ULONG,",
        );
        assert_ne!(swapped, GOOD);
        let p = problems(&swapped);
        assert!(p.len() == 1 && p[0].contains("order must match"), "{p:?}");

        let cdecl = GOOD.replace(
            "ShutdownRequest: unsafe extern \"system\"",
            "ShutdownRequest: unsafe extern \"C\"",
        );
        let p = problems(&cdecl);
        assert!(p.len() == 1 && p[0].contains("not `extern \"system\"`"), "{p:?}");

        let wrong_type = GOOD.replace("szReason: LPCWSTR", "szReason: *mut LPCWSTR");
        let p = problems(&wrong_type);
        assert!(p.len() == 1 && p[0].contains("the IDL says"), "{p:?}");

        let renamed = GOOD.replace("szReason: LPCWSTR", "reason: LPCWSTR");
        assert_eq!(problems(&renamed).len(), 1);

        let missing = GOOD.replace("IOPCShutdownVtbl", "SomethingElseVtbl");
        let p = problems(&missing);
        assert!(
            p.len() == 1 && p[0].contains("no Rust struct IOPCShutdownVtbl"),
            "{p:?}"
        );
    }
}
