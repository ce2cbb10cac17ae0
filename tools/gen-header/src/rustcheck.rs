//! Reads the library's Rust sources (with syn) for what the header must agree with (the exported
//! functions and callback types with their calling conventions) and for the rules of the FFI boundary
//! that the compiler cannot check by itself.
//!
//! The compiler checks the rest: every vtable entry returns `ffi::Crossed<T>`, which only
//! `ffi::boundary!` and `ffi::guard!` make, and the vtables and their shims are generated
//! (`src/com/interfaces.rs`). What is left, outside `#[cfg(test)]` modules and the generated module:
//! - every named `extern "C"` / `extern "system"` function with a body (the exports and the callbacks
//!   handed to C) has one `ffi::boundary!(...)` or `ffi::guard!(...)` as its whole body, and returns
//!   `ffi::Hr` / `ffi::Crossed<T>` or nothing, so no code of it runs outside the panic guard;
//! - nothing implements `Vtable` (what `Binder::slot` accepts) or casts a pointer to a `...Vtbl`
//!   type, either of which could put a function that skipped the boundary into a vtable;
//! - outside `src/com/`, no method of a generated interface trait (`IFooImpl`) is an `unsafe fn`: the
//!   generated shim checks every argument and hands the method typed, checked values, so an object's
//!   methods are safe code (the compiler refuses an `unsafe fn` for a safe trait method; this keeps a
//!   generator that went back to raw pointers from passing unnoticed).
//!
//! It also checks the names of the C API's parameters (docs/api-conventions.md, "Names"): the
//! functions the OPC specification defines (MatchPattern) have the specification's parameter names
//! exactly; every other export, every callback type and every field of an `Opc...` structure is in
//! snake_case. (Windows' own entry points, `Dll...`, are declared by Windows' headers, not this
//! library's, and keep the names Rust gives them.) And it records where each item is defined, for the
//! reference's areas (`groups`).

use std::collections::BTreeMap;
use std::path::Path;

use syn::visit::Visit;

/// The generated module: it is where the vtables are made.
const GENERATED: &str = "src/com/interfaces.rs";

/// The COM core, whose framework may implement the IUnknown methods of its slots itself.
const CORE: &str = "src/com/";

pub struct Sources {
    /// `#[no_mangle]` / `#[export_name]` functions: symbol → ABI ("C" or "system").
    pub functions: BTreeMap<String, String>,
    /// Function pointer types (`pub type F = Option<unsafe extern "C" fn(...)>`): name → ABI.
    pub callbacks: BTreeMap<String, String>,
    /// Items the header may declare (exports, `pub` types, structures, enums and constants): name →
    /// the file that defines it, relative to the repository's root (the first, when several do).
    pub origins: BTreeMap<String, String>,
    /// Breaches of the boundary's rules and of the naming rule, one line each (`file: what`).
    pub problems: Vec<String>,
    /// How many extern functions were checked.
    pub checked: usize,
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

fn is_cfg_test(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        a.path().is_ident("cfg")
            && a.parse_args::<syn::Meta>()
                .is_ok_and(|m| m.path().is_ident("test") || m.path().is_ident("miri"))
    })
}

fn is_exported(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        let p = a.path();
        p.is_ident("no_mangle")
            || p.is_ident("export_name")
            || (p.is_ident("unsafe")
                && a.parse_args::<syn::Path>()
                    .is_ok_and(|inner| inner.is_ident("no_mangle") || inner.is_ident("export_name")))
    })
}

/// `ffi::boundary!` / `ffi::guard!` (also through `crate::com::ffi::` or `super::ffi::`).
fn is_boundary_macro(path: &syn::Path) -> bool {
    let segments: Vec<String> = path.segments.iter().map(|s| s.ident.to_string()).collect();
    let n = segments.len();
    n >= 2 && segments[n - 2] == "ffi" && matches!(segments[n - 1].as_str(), "boundary" | "guard")
}

/// The body is one boundary macro and nothing else.
fn body_is_boundary(block: &syn::Block) -> bool {
    match block.stmts.as_slice() {
        [syn::Stmt::Macro(m)] => m.semi_token.is_none() && is_boundary_macro(&m.mac.path),
        [syn::Stmt::Expr(syn::Expr::Macro(m), None)] => is_boundary_macro(&m.mac.path),
        _ => false,
    }
}

/// `Hr`, `Crossed<T>` (any path ending so), or no return type.
fn returns_proof(output: &syn::ReturnType) -> bool {
    match output {
        syn::ReturnType::Default => true,
        syn::ReturnType::Type(_, ty) => match &**ty {
            syn::Type::Path(p) => p
                .path
                .segments
                .last()
                .is_some_and(|s| s.ident == "Hr" || s.ident == "Crossed"),
            _ => false,
        },
    }
}

fn extern_abi(abi: &Option<syn::Abi>) -> Option<String> {
    abi.as_ref()
        .map(|a| a.name.as_ref().map_or("C".into(), |n| n.value()))
        .filter(|abi| abi == "C" || abi == "system")
}

/// Looks inside function bodies for casts to a `...Vtbl` pointer.
struct Casts<'a> {
    file: &'a str,
    problems: &'a mut Vec<String>,
}

impl<'ast> Visit<'ast> for Casts<'_> {
    fn visit_expr_cast(&mut self, cast: &'ast syn::ExprCast) {
        if let syn::Type::Ptr(p) = &*cast.ty {
            if let syn::Type::Path(target) = &*p.elem {
                if let Some(last) = target.path.segments.last() {
                    if last.ident.to_string().ends_with("Vtbl") {
                        self.problems.push(format!(
                            "{}: a cast to a pointer to {}: call an object through its interface (its `...Calls` view)",
                            self.file, last.ident
                        ));
                    }
                }
            }
        }
        syn::visit::visit_expr_cast(self, cast);
    }

    fn visit_item_mod(&mut self, m: &'ast syn::ItemMod) {
        if !is_cfg_test(&m.attrs) {
            syn::visit::visit_item_mod(self, m);
        }
    }
}

/// The methods of an implementation of a generated interface trait that are `unsafe fn`.
fn unsafe_methods(i: &syn::ItemImpl, traits: &[String], file: &str, out: &mut Vec<String>) {
    let Some(name) = i
        .trait_
        .as_ref()
        .and_then(|(_, path, _)| path.segments.last())
        .map(|s| s.ident.to_string())
        .filter(|n| traits.contains(n))
    else {
        return;
    };
    for item in &i.items {
        if let syn::ImplItem::Fn(f) = item {
            if f.sig.unsafety.is_some() {
                out.push(format!(
                    "{file}: {name}::{} is an unsafe fn: the generated shim checks the arguments, the method is safe code",
                    f.sig.ident
                ));
            }
        }
    }
}

/// The functions the OPC specification defines, with its parameter names (OPC Common 1.10, Appendix B:
/// `BOOL MatchPattern(LPCTSTR string, LPCTSTR pattern, BOOL bCaseSensitive)`).
pub const SPECIFICATION: &[(&str, &[&str])] = &[
    ("MatchPatternW", &["string", "pattern", "bCaseSensitive"]),
    ("MatchPatternA", &["string", "pattern", "bCaseSensitive"]),
];

/// `snake_case`: lower-case words and digits joined by single underscores.
pub fn is_snake_case(name: &str) -> bool {
    !name.is_empty()
        && name.split('_').all(|w| !w.is_empty())
        && name.starts_with(|c: char| c.is_ascii_lowercase())
        && name
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

fn pat_name(p: &syn::Pat) -> Option<String> {
    match p {
        syn::Pat::Ident(i) => Some(i.ident.to_string()),
        _ => None,
    }
}

/// The naming rule for one export's parameters.
fn check_parameter_names(function: &str, names: &[String], file: &str, problems: &mut Vec<String>) {
    if function.starts_with("Dll") {
        return;
    }
    if let Some((_, spec)) = SPECIFICATION.iter().find(|(f, _)| *f == function) {
        if names.iter().map(String::as_str).ne(spec.iter().copied()) {
            problems.push(format!(
                "{file}: {function}({}) must have the specification's parameter names ({})",
                names.join(", "),
                spec.join(", ")
            ));
        }
        return;
    }
    for n in names {
        if !is_snake_case(n) {
            problems.push(format!(
                "{file}: {function}: the parameter `{n}` must be snake_case (docs/api-conventions.md, Names)"
            ));
        }
    }
}

fn is_pub(v: &syn::Visibility) -> bool {
    matches!(v, syn::Visibility::Public(_))
}

fn has_repr_c(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        a.path().is_ident("repr")
            && a.parse_args_with(syn::punctuated::Punctuated::<syn::Path, syn::Token![,]>::parse_terminated)
                .is_ok_and(|list| list.iter().any(|p| p.is_ident("C")))
    })
}

fn visit_items(items: &[syn::Item], file: &str, traits: &[String], out: &mut Sources) {
    let generated = file == GENERATED;
    for item in items {
        match item {
            syn::Item::Fn(f) => {
                let exported = is_exported(&f.attrs);
                let abi = extern_abi(&f.sig.abi);
                if let (true, Some(abi)) = (exported, &abi) {
                    out.functions.insert(f.sig.ident.to_string(), abi.clone());
                    out.origins
                        .entry(f.sig.ident.to_string())
                        .or_insert_with(|| file.to_string());
                    let names: Vec<String> = f
                        .sig
                        .inputs
                        .iter()
                        .filter_map(|a| match a {
                            syn::FnArg::Typed(t) => pat_name(&t.pat),
                            syn::FnArg::Receiver(_) => None,
                        })
                        .collect();
                    check_parameter_names(&f.sig.ident.to_string(), &names, file, &mut out.problems);
                }
                if exported && abi.is_none() {
                    out.problems.push(format!(
                        "{file}: {} is exported but not extern \"C\" or \"system\"",
                        f.sig.ident
                    ));
                }
                if abi.is_some() && !generated {
                    out.checked += 1;
                    if !body_is_boundary(&f.block) {
                        out.problems.push(format!(
                            "{file}: {}: the whole body must be one ffi::boundary!(...) or ffi::guard!(...)",
                            f.sig.ident
                        ));
                    }
                    if !returns_proof(&f.sig.output) {
                        out.problems.push(format!(
                            "{file}: {} must return ffi::Hr or ffi::Crossed<T> (or nothing)",
                            f.sig.ident
                        ));
                    }
                }
            }
            syn::Item::Impl(i) if !generated => {
                let names_vtable = i
                    .trait_
                    .as_ref()
                    .and_then(|(_, path, _)| path.segments.last())
                    .is_some_and(|s| s.ident == "Vtable");
                if names_vtable {
                    out.problems.push(format!(
                        "{file}: implements Vtable; only the generated vtables of src/com/interfaces.rs may"
                    ));
                }
                if !file.starts_with(CORE) {
                    unsafe_methods(i, traits, file, &mut out.problems);
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
                    if abi == "C" || abi == "system" {
                        let names: Vec<String> = f
                            .inputs
                            .iter()
                            .filter_map(|a| a.name.as_ref().map(|(n, _)| n.to_string()))
                            .collect();
                        if names.len() != f.inputs.len() && !generated {
                            out.problems.push(format!(
                                "{file}: the callback type {} must name its parameters (the header shows them)",
                                t.ident
                            ));
                        }
                        if !generated {
                            check_parameter_names(&t.ident.to_string(), &names, file, &mut out.problems);
                        }
                    }
                    out.callbacks.insert(t.ident.to_string(), abi);
                }
                if is_pub(&t.vis) && !generated {
                    out.origins
                        .entry(t.ident.to_string())
                        .or_insert_with(|| file.to_string());
                }
            }
            syn::Item::Struct(s) if is_pub(&s.vis) && !generated => {
                out.origins
                    .entry(s.ident.to_string())
                    .or_insert_with(|| file.to_string());
                let name = s.ident.to_string();
                if has_repr_c(&s.attrs) && name.starts_with("Opc") {
                    for field in &s.fields {
                        if let Some(f) = &field.ident {
                            if !is_snake_case(&f.to_string()) {
                                out.problems.push(format!(
                                    "{file}: the field {name}::{f} must be snake_case (docs/api-conventions.md, Names)"
                                ));
                            }
                        }
                    }
                }
            }
            syn::Item::Enum(e) if is_pub(&e.vis) && !generated => {
                out.origins
                    .entry(e.ident.to_string())
                    .or_insert_with(|| file.to_string());
            }
            syn::Item::Const(c) if is_pub(&c.vis) && !generated => {
                out.origins
                    .entry(c.ident.to_string())
                    .or_insert_with(|| file.to_string());
            }
            syn::Item::Mod(m) if !is_cfg_test(&m.attrs) => {
                if let Some((_, items)) = &m.content {
                    visit_items(items, file, traits, out);
                }
            }
            _ => {}
        }
        if !generated {
            let mut casts = Casts {
                file,
                problems: &mut out.problems,
            };
            match item {
                syn::Item::Mod(_) => {}
                other => casts.visit_item(other),
            }
        }
    }
}

/// Reads every Rust source of the library; `traits` are the generated interface traits (`IFooImpl`).
pub fn read(root: &Path, traits: &[String]) -> Sources {
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    let mut out = Sources {
        functions: BTreeMap::new(),
        callbacks: BTreeMap::new(),
        origins: BTreeMap::new(),
        problems: Vec::new(),
        checked: 0,
    };
    for path in files {
        let rel = path.strip_prefix(root).unwrap_or(&path).display().to_string();
        // Files of tests only (`tests.rs`, `stress_tests.rs`) are not the library's boundary.
        if rel.ends_with("tests.rs") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("read a Rust source");
        let file = syn::parse_file(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        visit_items(&file.items, &rel, traits, &mut out);
    }
    if out.checked < 40 {
        out.problems.push(format!(
            "only {} extern functions found in src/: is the check still reading the sources?",
            out.checked
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problems_in(file: &str, rust: &str) -> Vec<String> {
        let mut sources = Sources {
            functions: BTreeMap::new(),
            callbacks: BTreeMap::new(),
            origins: BTreeMap::new(),
            problems: Vec::new(),
            checked: 0,
        };
        let traits = ["IUnknownImpl".to_string(), "IOPCCommonImpl".to_string()];
        visit_items(&syn::parse_file(rust).unwrap().items, file, &traits, &mut sources);
        sources.problems
    }

    fn problems(rust: &str) -> Vec<String> {
        problems_in("src/t.rs", rust)
    }

    #[test]
    fn exports_written_with_the_boundary_pass() {
        let good = r#"
            #[no_mangle]
            pub unsafe extern "C" fn OpcA(p: *mut u32) -> Hr {
                ffi::boundary!(Opc, [p], { Ok(S_OK) })
            }
            #[no_mangle]
            pub extern "system" fn OpcB() -> ffi::Crossed<BOOL> {
                crate::com::ffi::guard!(0, { 1 })
            }
            #[no_mangle]
            pub extern "C" fn OpcC() {
                ffi::guard!((), { work() })
            }
            fn plain() -> u32 { let x = 1; x }
            #[cfg(test)]
            mod tests {
                extern "system" fn stand_in() -> HRESULT { 0 }
                fn f() { let _ = p as *const IFooVtbl; }
                impl Vtable for TestVtbl {}
            }
        "#;
        assert_eq!(problems(good), Vec::<String>::new());
    }

    #[test]
    fn code_outside_the_boundary_is_reported() {
        let p = problems(
            r#"#[no_mangle] pub extern "C" fn OpcA() -> Hr { let x = risky(); ffi::boundary!(Opc, [], { Ok(x) }) }"#,
        );
        assert!(p.len() == 1 && p[0].contains("whole body"), "{p:?}");

        let p = problems(r#"#[no_mangle] pub extern "C" fn OpcA() -> HRESULT { ffi::guard!(0, { 0 }) }"#);
        assert!(p.len() == 1 && p[0].contains("must return"), "{p:?}");

        let p = problems(r#"unsafe extern "system" fn shim(this: *mut IFoo) -> Hr { other(this) }"#);
        assert!(p.len() == 1 && p[0].contains("whole body"), "{p:?}");

        let p = problems(r#"#[no_mangle] pub extern "C" fn OpcA() { ffi::guard!((), { 1 }); log() }"#);
        assert!(p.len() == 1 && p[0].contains("whole body"), "{p:?}");

        let p = problems(r#"#[no_mangle] pub fn OpcA() -> Hr { ffi::guard!(0, { 0 }) }"#);
        assert!(p.len() == 1 && p[0].contains("not extern"), "{p:?}");
    }

    #[test]
    fn vtables_made_by_hand_are_reported() {
        let p = problems("struct MyVtbl; impl Vtable for MyVtbl {}");
        assert!(p.len() == 1 && p[0].contains("implements Vtable"), "{p:?}");

        let p = problems(
            "fn f(o: *mut IUnknown) -> u32 { unsafe { ((*((*o).lpVtbl as *const IUnknownVtbl)).AddRef)(o) }.get() }",
        );
        assert!(p.len() == 1 && p[0].contains("IUnknownVtbl"), "{p:?}");

        let p = problems("mod inner { fn f(v: *const u8) { let _ = v as *mut crate::x::IFooVtbl; } }");
        assert!(p.len() == 1 && p[0].contains("IFooVtbl"), "{p:?}");
    }

    #[test]
    fn interface_methods_outside_the_core_are_safe_code() {
        let safe = r#"
            impl IOPCCommonImpl for Session {
                fn GetLocaleID(this: &ComObject<Self>, out: ffi::Out<'_, LCID>) -> FfiResult { Ok(S_OK) }
            }
            impl Cursor for Utf16 { unsafe fn at(self, i: usize) -> u32 { 0 } }
        "#;
        assert_eq!(problems(safe), Vec::<String>::new());

        let raw = r#"
            impl IOPCCommonImpl for Session {
                unsafe fn GetLocaleID(this: &ComObject<Self>, out: *mut LCID) -> FfiResult { Ok(S_OK) }
            }
        "#;
        let p = problems(raw);
        assert!(
            p.len() == 1 && p[0].contains("IOPCCommonImpl::GetLocaleID is an unsafe fn"),
            "{p:?}"
        );
        let p = problems_in("src/shutdown/server.rs", &format!("mod inner {{ {raw} }}"));
        assert!(p.len() == 1 && p[0].starts_with("src/shutdown/server.rs:"), "{p:?}");

        // The core's framework may (its IUnknown implementations work on raw slots).
        let core = "impl IUnknownImpl for Inner { unsafe fn AddRef(this: *mut IUnknown) -> ULONG { 1 } }";
        assert_eq!(problems_in("src/com/object.rs", core), Vec::<String>::new());
        assert_eq!(problems_in("src/t.rs", core).len(), 1);
    }

    #[test]
    fn exports_and_callbacks_are_listed_with_their_conventions() {
        let mut sources = Sources {
            functions: BTreeMap::new(),
            callbacks: BTreeMap::new(),
            origins: BTreeMap::new(),
            problems: Vec::new(),
            checked: 0,
        };
        let text = r#"
            #[no_mangle] pub extern "system" fn DllCanUnloadNow() -> Hr { ffi::guard!(0, { 0 }) }
            #[unsafe(no_mangle)] pub unsafe extern "C" fn OpcX() -> Hr { ffi::guard!(0, { 0 }) }
            pub type Cb = Option<unsafe extern "C" fn(context: *mut c_void)>;
        "#;
        visit_items(&syn::parse_file(text).unwrap().items, "src/t.rs", &[], &mut sources);
        assert_eq!(sources.functions["DllCanUnloadNow"], "system");
        assert_eq!(sources.functions["OpcX"], "C");
        assert_eq!(sources.callbacks["Cb"], "C");
        assert_eq!(sources.checked, 2);
    }

    #[test]
    fn parameter_names_follow_the_naming_rule() {
        let good = r#"
            #[no_mangle] pub unsafe extern "C" fn OpcA(out_count: *mut u32, riid: REFIID, ppv: *mut *mut c_void) -> Hr { ffi::guard!(0, { 0 }) }
            #[no_mangle] pub unsafe extern "C" fn MatchPatternW(string: LPCWSTR, pattern: LPCWSTR, bCaseSensitive: BOOL) -> Crossed<BOOL> { ffi::guard!(0, { 0 }) }
            #[no_mangle] pub unsafe extern "system" fn DllInstall(bInstall: BOOL, pszCmdLine: LPCWSTR) -> Hr { ffi::guard!(0, { 0 }) }
            pub type OpcCb = Option<unsafe extern "C" fn(context: *mut c_void, locale: LCID)>;
            #[repr(C)] pub struct OpcOptions { pub struct_size: u32, pub locale_count: u32 }
            #[repr(C)] pub struct CONNECTDATA { pub pUnk: *mut IUnknown, pub dwCookie: DWORD }
        "#;
        assert_eq!(problems(good), Vec::<String>::new());

        let p = problems(
            r#"#[no_mangle] pub unsafe extern "C" fn OpcA(ppName: *mut LPWSTR) -> Hr { ffi::guard!(0, { 0 }) }"#,
        );
        assert!(
            p.len() == 1 && p[0].contains("OpcA: the parameter `ppName` must be snake_case"),
            "{p:?}"
        );

        let p = problems(
            r#"#[no_mangle] pub unsafe extern "C" fn MatchPatternA(string: LPCSTR, pattern: LPCSTR, case_sensitive: BOOL) -> Crossed<BOOL> { ffi::guard!(0, { 0 }) }"#,
        );
        assert!(
            p.len() == 1 && p[0].contains("the specification's parameter names (string, pattern, bCaseSensitive)"),
            "{p:?}"
        );

        let p = problems(r#"pub type OpcCb = Option<unsafe extern "C" fn(pContext: *mut c_void)>;"#);
        assert!(
            p.len() == 1 && p[0].contains("OpcCb: the parameter `pContext`"),
            "{p:?}"
        );

        let p = problems(r#"pub type OpcCb = Option<unsafe extern "C" fn(*mut c_void)>;"#);
        assert!(p.len() == 1 && p[0].contains("must name its parameters"), "{p:?}");

        let p = problems("#[repr(C)] pub struct OpcOptions { pub struct_size: u32, pub dwFlags: u32 }");
        assert!(
            p.len() == 1 && p[0].contains("OpcOptions::dwFlags must be snake_case"),
            "{p:?}"
        );
    }

    #[test]
    fn snake_case_is_lower_case_words_joined_by_one_underscore() {
        for good in ["reg", "command_line", "timed_out", "da10_vendor", "ppv", "riid"] {
            assert!(is_snake_case(good), "{good}");
        }
        for bad in ["ppName", "bCaseSensitive", "_x", "x_", "a__b", "", "Reg", "9lives"] {
            assert!(!is_snake_case(bad), "{bad}");
        }
    }
}
