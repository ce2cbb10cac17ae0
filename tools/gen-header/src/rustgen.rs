//! The Rust side of the interfaces, `src/com/interfaces.rs`, generated from the same IDL as the header.
//!
//! For each interface `IFoo` of `idl/*.idl` it writes:
//! - `IFoo`, what an interface pointer points at, whose `lpVtbl` is an `IFooCalls`: the methods as
//!   the library calls them on any object, each returning `ffi::Foreign<T>`, which no function of the
//!   library can make;
//! - `IFooVtbl`, the vtable as the library fills it for its own objects: each entry returns
//!   `ffi::Crossed<T>` (`ffi::Hr`), which only `ffi::boundary!` and `ffi::guard!` make, and
//!   `IFooVtbl::new`, which fills it with the generated shims;
//! - `IFooImpl`, the trait an object implements to present the interface, and one shim per method:
//!   an `extern "system"` function whose whole body is `ffi::boundary!` (HRESULT methods, with the
//!   IDL's `[out]` parameters reset) or `ffi::guard!` (the others), calling the trait;
//! - `IFoo::IID`, `IFoo::METHODS` and call wrappers `IFoo::Method(this, ...)` returning the plain value.
//!
//! And the proxy/stub's interface table (IIDs and method counts) from `idl/opccomn.idl`.

use std::fmt::Write as _;

use crate::emit::Catalog;
use crate::idl::{Interface, Method, Param};

/// One IDL file and what its interfaces are to the library.
pub struct File<'a> {
    pub path: &'a str,
    pub interfaces: &'a [Interface],
    /// The NULL rule of the file's interfaces (`Com` or `Opc`), before the enumerator exception.
    pub rule: &'a str,
}

/// Types of the IDL the generated code names as they are (from `crate::com::types`).
const PLAIN_TYPES: &[&str] = &[
    "HRESULT",
    "ULONG",
    "DWORD",
    "LCID",
    "BOOL",
    "GUID",
    "IID",
    "CLSID",
    "CATID",
    "REFIID",
    "REFCLSID",
    "LPCLSID",
    "LPWSTR",
    "LPCWSTR",
    "LPOLESTR",
    "LPCOLESTR",
    "CONNECTDATA",
    "CATEGORYINFO",
];

/// Type aliases that are pointers (a method taking one has a safety contract).
const POINTER_ALIASES: &[&str] = &[
    "REFIID",
    "REFCLSID",
    "LPCLSID",
    "LPWSTR",
    "LPCWSTR",
    "LPOLESTR",
    "LPCOLESTR",
];

/// Interfaces passed through without being called: an opaque pointer to the library.
const OPAQUE: &[&str] = &["IStream"];

struct Ty {
    rust: String,
    pointer: bool,
}

fn rust_type(catalog: &Catalog, iface: &str, p: &Param) -> Result<Ty, String> {
    let words: Vec<&str> =
        p.ty.split(|c: char| c.is_whitespace() || c == '*')
            .filter(|w| !w.is_empty())
            .collect();
    let constant = words.contains(&"const");
    let base = words
        .iter()
        .rfind(|w| **w != "const")
        .ok_or_else(|| format!("{iface}: parameter {} has no type", p.name))?;
    let stars = p.ty.matches('*').count() + usize::from(p.array);
    let name = if *base == "void" || OPAQUE.contains(base) {
        "c_void".to_string()
    } else if PLAIN_TYPES.contains(base) || catalog.contains(base) {
        base.to_string()
    } else {
        return Err(format!(
            "{iface}: parameter {} has type {base}, which tools/gen-header/src/rustgen.rs does not know",
            p.name
        ));
    };
    let mut rust = name;
    for level in 0..stars {
        let kind = if level == 0 && constant { "*const" } else { "*mut" };
        rust = format!("{kind} {rust}");
    }
    Ok(Ty {
        rust,
        pointer: stars > 0 || POINTER_ALIASES.contains(base),
    })
}

/// The attribute items of a parameter, split at the top level commas.
fn attribute_items(attributes: &str) -> Vec<String> {
    let mut items = Vec::new();
    let mut depth = 0;
    let mut cur = String::new();
    for c in attributes.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                items.push(cur.trim().to_string());
                cur.clear();
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    if !cur.trim().is_empty() {
        items.push(cur.trim().to_string());
    }
    items
}

/// An `[out]` parameter the boundary resets (to NULL or zero) on entry and on failure: one that
/// points at a single value. An array (`size_is(n)`) is not touched: its size may be zero.
fn resets(p: &Param) -> bool {
    let items = attribute_items(&p.attributes);
    let out = items.iter().any(|i| i == "out");
    let array = items.iter().any(|i| {
        i.strip_prefix("size_is(")
            .is_some_and(|rest| !rest.split(',').next().unwrap_or("").trim().is_empty())
    });
    out && !array && !p.array
}

/// COM's enumerator contract (Next, Skip, Reset, Clone) is COM plumbing: NULL is E_POINTER.
fn is_enumerator(i: &Interface) -> bool {
    let names: Vec<&str> = i.methods.iter().map(|m| m.name.as_str()).collect();
    names == ["Next", "Skip", "Reset", "Clone"]
}

fn doc(lines: &[String], indent: &str) -> String {
    let mut s = String::new();
    for l in lines {
        if l.is_empty() {
            let _ = writeln!(s, "{indent}///");
        } else {
            let _ = writeln!(s, "{indent}/// {l}");
        }
    }
    s
}

struct Sig {
    /// `name: type` of each parameter after `This`.
    params: Vec<(String, Ty)>,
    ret: &'static str,
    /// The parameters the boundary resets.
    outs: Vec<String>,
}

fn signature(catalog: &Catalog, iface: &str, m: &Method) -> Result<Sig, String> {
    let mut params = Vec::new();
    let mut outs = Vec::new();
    for p in &m.params {
        if resets(p) {
            outs.push(p.name.clone());
        }
        params.push((p.name.clone(), rust_type(catalog, iface, p)?));
    }
    let ret = match m.ret.as_str() {
        "HRESULT" => "HRESULT",
        "ULONG" => "ULONG",
        other => {
            return Err(format!(
                "{iface}::{}: return type {other} is not HRESULT or ULONG",
                m.name
            ))
        }
    };
    Ok(Sig { params, ret, outs })
}

fn guid_literal(uuid: &str) -> String {
    let hex: String = uuid.chars().filter(|c| *c != '-').collect::<String>().to_uppercase();
    format!(
        "GUID::from_u128(0x{}_{}_{}_{}_{})",
        &hex[0..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..32]
    )
}

fn arg_list(sig: &Sig) -> String {
    sig.params.iter().map(|(n, _)| format!(", {n}")).collect()
}

fn param_list(sig: &Sig) -> String {
    sig.params.iter().map(|(n, t)| format!(", {n}: {}", t.rust)).collect()
}

/// The generated module.
pub fn module(catalog: &Catalog, files: &[File]) -> Result<String, String> {
    let mut out = String::from(
        "// Generated by tools/gen-header from idl/combase.idl, idl/opccomn.idl and idl/internal.idl. Do not\n\
         // edit; run `cargo run -p gen-header` (CI runs it with --check).\n\n\
         //! The library's COM interfaces, generated from the IDL, as `include/opccomn/opccomn.h` is.\n\
         //!\n\
         //! For each interface `IFoo`:\n\
         //! - `IFoo` is what an interface pointer points at. Its `lpVtbl` is an `IFooCalls`: the methods as\n\
         //!   the library calls them on any object (its own, a caller's, the system's). Each returns a\n\
         //!   [`Foreign<T>`](super::ffi::Foreign), which no Rust function of the library can make, so a\n\
         //!   method that only forwards a call to another object cannot be put in a vtable.\n\
         //!   `IFoo::Method(this, ...)` calls one and returns the plain value.\n\
         //! - `IFooVtbl` is the vtable as the library fills it for its own objects: every entry returns a\n\
         //!   [`Crossed<T>`](super::ffi::Crossed), which only `ffi::boundary!` and `ffi::guard!` make.\n\
         //!   `IFooVtbl::new::<U, T>()` fills it with the generated shims: the IUnknown methods of\n\
         //!   `U` (an [`IUnknownImpl`], usually [`Delegating`](super::object::Delegating)) and the\n\
         //!   methods of `T`, an object that implements `IFooImpl`.\n\
         //! - `IFooImpl` is the trait an object implements to present the interface. Each generated shim\n\
         //!   is one `ffi::boundary!` (HRESULT methods: the interface's NULL rule, the IDL's `[out]`\n\
         //!   parameters reset on entry and on failure, panics caught) or `ffi::guard!` (the others)\n\
         //!   around a call of the trait's method.\n\
         //! - `IFoo::IID` and `IFoo::METHODS` (IUnknown's three included).\n\n\
         #![allow(non_snake_case, clippy::too_many_arguments)]\n\n\
         use core::ffi::c_void;\n\n\
         use super::ffi::{self, Crossed, FfiResult, Foreign, Hr};\n\
         use super::object::{ComClass, ComObject, Vtable};\n",
    );
    // The types the module names.
    let mut used: Vec<&str> = vec!["GUID", "HRESULT", "ULONG", "REFIID"];
    for f in files {
        for i in f.interfaces {
            for m in &i.methods {
                for p in &m.params {
                    for w in p.ty.split(|c: char| c.is_whitespace() || c == '*') {
                        if let Some(t) = PLAIN_TYPES.iter().find(|t| **t == w) {
                            used.push(t);
                        }
                    }
                }
            }
        }
    }
    used.sort();
    used.dedup();
    let _ = writeln!(out, "use super::types::{{{}}};", used.join(", "));

    let root = files
        .iter()
        .flat_map(|f| f.interfaces.iter())
        .find(|i| i.base.is_none())
        .ok_or("no root interface (IUnknown) in the IDL")?;
    for f in files {
        for i in f.interfaces {
            let rule = if is_enumerator(i) { "Com" } else { f.rule };
            out += &interface(catalog, f.path, i, root, rule)?;
        }
    }

    // The proxy/stub's table.
    let opc = files
        .iter()
        .find(|f| f.path.ends_with("opccomn.idl"))
        .ok_or("idl/opccomn.idl is missing")?;
    let _ = writeln!(
        out,
        "\n/// The interfaces of idl/opccomn.idl, which opccomn's proxy/stub serves: IID, name and number of\n\
         /// methods (IUnknown's three included), as registered under `Interface\\{{iid}}`.\n\
         pub const OPC_COMMON_INTERFACES: [(GUID, &str, u32); {}] = [",
        opc.interfaces.len()
    );
    for i in opc.interfaces {
        let _ = writeln!(out, "    ({0}::IID, \"{0}\", {0}::METHODS),", i.name);
    }
    out += "];\n";
    Ok(out)
}

fn interface(catalog: &Catalog, path: &str, i: &Interface, root: &Interface, rule: &str) -> Result<String, String> {
    let name = &i.name;
    let is_root = i.base.is_none();
    if let Some(base) = &i.base {
        if *base != root.name {
            return Err(format!(
                "{name}: derives from {base}; the generator handles interfaces derived from {} only",
                root.name
            ));
        }
    }
    let vtable = catalog.vtable(i);
    let mut sigs = Vec::new();
    for (owner, m) in &vtable {
        sigs.push((*owner, *m, signature(catalog, owner, m)?));
    }
    let mut s = String::new();
    let _ = writeln!(s, "\n// ---- {name} ({path}) ----\n");

    // The interface pointer's target.
    s += &doc(&i.doc, "");
    let _ = write!(
        s,
        "#[repr(C)]\npub struct {name} {{\n    /// The methods, as the library calls them.\n    pub lpVtbl: *const {name}Calls,\n}}\n\n"
    );

    // IID, METHODS and the call wrappers.
    let _ = writeln!(s, "impl {name} {{");
    let _ = writeln!(s, "    /// `IID_{name}` {{{}}}.", i.uuid.to_uppercase());
    let _ = writeln!(s, "    pub const IID: GUID = {};", guid_literal(&i.uuid));
    let _ = writeln!(s, "    /// The number of methods, IUnknown's three included.");
    let _ = writeln!(s, "    pub const METHODS: u32 = {};", vtable.len());
    for (_, m, sig) in &sigs {
        let _ = writeln!(s);
        s += &doc(&m.doc, "    ");
        let _ = writeln!(s, "    ///\n    /// # Safety");
        let _ = writeln!(
            s,
            "    /// `this` must be a valid {name} pointer, and the arguments valid as the IDL declares them."
        );
        let _ = writeln!(
            s,
            "    pub unsafe fn {}(this: *mut Self{}) -> {} {{",
            m.name,
            param_list(sig),
            sig.ret
        );
        let _ = writeln!(
            s,
            "        // SAFETY: the caller's contract; every interface pointer points at its vtable."
        );
        let _ = writeln!(
            s,
            "        unsafe {{ ((*(*this).lpVtbl).{})(this{}) }}.get()\n    }}",
            m.name,
            arg_list(sig)
        );
    }
    s += "}\n\n";

    // The two views of the vtable.
    for (kind, wrap) in [("Calls", "Foreign"), ("Vtbl", "Crossed")] {
        if kind == "Calls" {
            let _ = writeln!(
                s,
                "/// {name}'s methods as the library calls them on any object: each returns a `Foreign<T>`."
            );
        } else {
            let _ = writeln!(
                s,
                "/// {name}'s vtable as the library fills it for its own objects: each entry returns a\n\
                 /// `Crossed<T>`, which only `ffi::boundary!` and `ffi::guard!` make. See [`{name}Vtbl::new`]."
            );
        }
        let _ = writeln!(s, "#[repr(C)]\npub struct {name}{kind} {{");
        for (_, m, sig) in &sigs {
            let ret = match (wrap, sig.ret) {
                ("Crossed", "HRESULT") => "Hr".to_string(),
                (w, r) => format!("{w}<{r}>"),
            };
            let _ = writeln!(
                s,
                "    /// {}.\n    pub {}: unsafe extern \"system\" fn(This: *mut {name}{}) -> {ret},",
                m.name,
                m.name,
                param_list(sig)
            );
        }
        s += "}\n\n";
    }

    // Filling the vtable.
    let bounds = if is_root {
        format!("<U: {name}Impl>")
    } else {
        format!("<U: {}Impl, T: {name}Impl>", root.name)
    };
    let _ = writeln!(s, "impl {name}Vtbl {{");
    if is_root {
        let _ = writeln!(s, "    /// The vtable whose methods are `U`'s.");
    } else {
        let _ = writeln!(
            s,
            "    /// The vtable of the {name} slots of `T`'s objects, with the IUnknown methods of `U`\n    /// ([`Delegating`](super::object::Delegating) for the controlling unknown, as COM requires)."
        );
    }
    let _ = writeln!(s, "    pub const fn new{bounds}() -> Self {{\n        {name}Vtbl {{");
    for (owner, m, _) in &sigs {
        let shim = if *owner == root.name {
            format!("{owner}_{}::<U, {name}>", m.name)
        } else {
            format!("{owner}_{}::<T>", m.name)
        };
        let _ = writeln!(s, "            {}: {shim},", m.name);
    }
    s += "        }\n    }\n}\n\n";
    let _ = writeln!(s, "impl Vtable for {name}Vtbl {{}}\n");

    // The trait.
    if is_root {
        let _ = writeln!(
            s,
            "/// The IUnknown methods of a slot: how an object (or one of its slots) answers QueryInterface,\n\
             /// AddRef and Release. The framework's implementations are in `super::object`."
        );
        let _ = writeln!(s, "pub trait {name}Impl {{");
    } else {
        let _ = writeln!(s, "/// What an object implements to present {name}: one method per IDL method (after\n/// IUnknown's), called by the generated shim with the object and the caller's arguments.");
        let _ = writeln!(s, "pub trait {name}Impl: ComClass {{");
    }
    for (owner, m, sig) in &sigs {
        if *owner != *name {
            continue;
        }
        let unsafe_ = is_root || sig.params.iter().any(|(_, t)| t.pointer);
        s += &doc(&m.doc, "    ");
        if unsafe_ {
            let _ = writeln!(s, "    ///\n    /// # Safety");
            if is_root {
                let _ = writeln!(
                    s,
                    "    /// Called by the generated shim with `This`, a slot whose vtable was made with this\n    /// implementation, and the COM caller's arguments."
                );
            } else {
                let _ = writeln!(
                    s,
                    "    /// Called by the generated shim with the COM caller's arguments, each as the IDL declares it\n    /// (a pointer NULL or valid; the shim has already reset the `[out]` parameters)."
                );
            }
        }
        let this = if is_root {
            format!("This: *mut {name}")
        } else {
            "this: &ComObject<Self>".to_string()
        };
        let ret = if sig.ret == "HRESULT" { "FfiResult" } else { sig.ret };
        let _ = writeln!(
            s,
            "    {}fn {}({this}{}) -> {ret};",
            if unsafe_ { "unsafe " } else { "" },
            m.name,
            param_list(sig)
        );
    }
    s += "}\n\n";

    // The shims of the interface's own methods.
    for (owner, m, sig) in &sigs {
        if *owner != *name {
            continue;
        }
        let (head, this_ty, call) = if is_root {
            (
                format!("<U: {name}Impl, I>"),
                "*mut I".to_string(),
                format!("<U as {name}Impl>::{}(This.cast(){})", m.name, arg_list(sig)),
            )
        } else {
            (
                format!("<T: {name}Impl>"),
                format!("*mut {name}"),
                format!(
                    "<T as {name}Impl>::{}(ComObject::<T>::from_interface(This){})",
                    m.name,
                    arg_list(sig)
                ),
            )
        };
        let ret = if sig.ret == "HRESULT" {
            "Hr".to_string()
        } else {
            format!("Crossed<{}>", sig.ret)
        };
        let _ = writeln!(
            s,
            "unsafe extern \"system\" fn {name}_{}{head}(This: {this_ty}{}) -> {ret} {{",
            m.name,
            param_list(sig)
        );
        let safety = if is_root {
            "        // SAFETY: `new::<U>` installs this shim only in vtables of slots that `U` answers for; the\n        // arguments are the COM caller's.\n"
                .to_string()
        } else {
            format!(
                "        // SAFETY: `{name}Vtbl::new::<_, T>` installs this shim only in the slots of `T`'s objects,\n        // so `This` is a slot of a live ComObject<T>; the arguments are the COM caller's.\n"
            )
        };
        if sig.ret == "HRESULT" {
            let _ = writeln!(s, "    ffi::boundary!({rule}, [{}], {{", sig.outs.join(", "));
            s += &safety;
            let _ = writeln!(s, "        unsafe {{ {call} }}\n    }})\n}}\n");
        } else {
            let _ = writeln!(s, "    ffi::guard!(0, {{");
            s += &safety;
            let _ = writeln!(s, "        unsafe {{ {call} }}\n    }})\n}}\n");
        }
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::idl;

    const BASE: &str = r#"
        [local, object, uuid(00000000-0000-0000-C000-000000000046)]
        interface IUnknown {
            HRESULT QueryInterface([in] REFIID riid, [out, iid_is(riid)] void **ppvObject);
            ULONG AddRef();
            ULONG Release();
        }
        [object, uuid(0002E000-0000-0000-C000-000000000046)]
        interface IEnumGUID : IUnknown {
            HRESULT Next([in] ULONG celt, [out, size_is(celt), length_is(*pceltFetched)] GUID *rgelt, [out] ULONG *pceltFetched);
            HRESULT Skip([in] ULONG celt);
            HRESULT Reset();
            HRESULT Clone([out] IEnumGUID **ppenum);
        }
    "#;

    const OPC: &str = r#"
        [object, uuid(F31DFDE2-07B6-11d2-B2D8-0060083BA1FB)]
        interface IOPCCommon : IUnknown {
            /// Sets the locale.
            HRESULT SetLocaleID([in] LCID dwLcid);
            HRESULT QueryAvailableLocaleIDs([out] DWORD *pdwCount, [out, size_is(,*pdwCount)] LCID **pdwLcid);
        }
    "#;

    fn generate(opc: &str) -> Result<String, String> {
        let base = idl::parse("idl/combase.idl", BASE).unwrap();
        let opc = idl::parse("idl/opccomn.idl", opc).unwrap();
        let catalog = Catalog::new(base.iter().chain(&opc));
        module(
            &catalog,
            &[
                File {
                    path: "idl/combase.idl",
                    interfaces: &base,
                    rule: "Com",
                },
                File {
                    path: "idl/opccomn.idl",
                    interfaces: &opc,
                    rule: "Opc",
                },
            ],
        )
    }

    #[test]
    fn each_method_gets_a_trait_method_a_guarded_shim_and_both_vtable_views() {
        let m = generate(OPC).unwrap();
        assert!(m.contains("pub trait IOPCCommonImpl: ComClass {"), "{m}");
        assert!(m.contains(
            "    /// Sets the locale.\n    fn SetLocaleID(this: &ComObject<Self>, dwLcid: LCID) -> FfiResult;"
        ));
        assert!(m.contains(
            "unsafe fn QueryAvailableLocaleIDs(this: &ComObject<Self>, pdwCount: *mut DWORD, pdwLcid: *mut *mut LCID) -> FfiResult;"
        ));
        // The OPC rule; the `[out]` parameters reset, the pointer to an array (`size_is(,...)`) included.
        assert!(m.contains("ffi::boundary!(Opc, [pdwCount, pdwLcid], {"), "{m}");
        assert!(m.contains("pub SetLocaleID: unsafe extern \"system\" fn(This: *mut IOPCCommon, dwLcid: LCID) -> Hr,"));
        assert!(m.contains(
            "pub SetLocaleID: unsafe extern \"system\" fn(This: *mut IOPCCommon, dwLcid: LCID) -> Foreign<HRESULT>,"
        ));
        assert!(m.contains("pub lpVtbl: *const IOPCCommonCalls,"));
        assert!(m.contains("pub const METHODS: u32 = 5;"));
        assert!(m.contains("pub const IID: GUID = GUID::from_u128(0xF31DFDE2_07B6_11D2_B2D8_0060083BA1FB);"));
        assert!(m.contains("QueryInterface: IUnknown_QueryInterface::<U, IOPCCommon>,"));
        assert!(m.contains("SetLocaleID: IOPCCommon_SetLocaleID::<T>,"));
        assert!(m.contains("impl Vtable for IOPCCommonVtbl {}"));
        assert!(m.contains("pub const OPC_COMMON_INTERFACES: [(GUID, &str, u32); 1] = [\n    (IOPCCommon::IID, \"IOPCCommon\", IOPCCommon::METHODS),"));
        // AddRef and Release are guarded with 0, as COM's reference counts.
        assert!(m.contains("unsafe extern \"system\" fn IUnknown_AddRef<U: IUnknownImpl, I>(This: *mut I) -> Crossed<ULONG> {\n    ffi::guard!(0, {"));
    }

    #[test]
    fn enumerators_follow_com_and_arrays_are_never_reset() {
        let m = generate(OPC).unwrap();
        assert!(m.contains("fn IEnumGUID_Next<T: IEnumGUIDImpl>(This: *mut IEnumGUID, celt: ULONG, rgelt: *mut GUID, pceltFetched: *mut ULONG) -> Hr {\n    ffi::boundary!(Com, [pceltFetched], {"), "{m}");
        assert!(m.contains("ffi::boundary!(Com, [ppenum], {"));
        assert!(m.contains("fn Skip(this: &ComObject<Self>, celt: ULONG) -> FfiResult;"));
    }

    #[test]
    fn a_method_added_to_the_idl_is_in_the_trait_every_object_must_implement() {
        let added = OPC.replace(
            "HRESULT SetLocaleID([in] LCID dwLcid);",
            "HRESULT SetLocaleID([in] LCID dwLcid);\n HRESULT GetLocaleID([out] LCID *pdwLcid);",
        );
        let m = generate(&added).unwrap();
        assert!(m.contains("unsafe fn GetLocaleID(this: &ComObject<Self>, pdwLcid: *mut LCID) -> FfiResult;"));
        assert!(m.contains("GetLocaleID: IOPCCommon_GetLocaleID::<T>,"));
        assert!(m.contains("pub const METHODS: u32 = 6;"));
    }

    #[test]
    fn unknown_types_and_unsupported_shapes_are_errors() {
        let bad = OPC.replace("[in] LCID dwLcid", "[in] VARIANT v");
        let e = generate(&bad).unwrap_err();
        assert!(e.contains("VARIANT"), "{e}");
        let bad = OPC.replace("HRESULT SetLocaleID", "BOOL SetLocaleID");
        assert!(generate(&bad).unwrap_err().contains("not HRESULT or ULONG"));
        let bad = OPC.replace("interface IOPCCommon : IUnknown", "interface IOPCCommon : IEnumGUID");
        assert!(generate(&bad).unwrap_err().contains("derives from IEnumGUID"));
    }
}
