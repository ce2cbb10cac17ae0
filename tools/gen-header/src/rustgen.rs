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
    /// The C type as Rust writes it: what the vtables and the call wrappers take.
    rust: String,
    /// The type's name without pointers (`GUID`, `LCID`, `IEnumGUID`, `c_void`, `LPCOLESTR`).
    base: String,
    /// Pointer levels written with `*` (and `[]`); the pointer aliases (`REFIID`, `LPCWSTR`...) are 0.
    stars: usize,
    /// Whether the type is `void` or an interface the library passes on without calling (`IStream`).
    opaque: bool,
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
    let opaque = *base == "void" || OPAQUE.contains(base);
    let name = if opaque {
        "c_void".to_string()
    } else if PLAIN_TYPES.contains(base) || catalog.contains(base) {
        base.to_string()
    } else {
        return Err(format!(
            "{iface}: parameter {} has type {base}, which tools/gen-header/src/rustgen.rs does not know",
            p.name
        ));
    };
    let mut rust = name.clone();
    for level in 0..stars {
        let kind = if level == 0 && constant { "*const" } else { "*mut" };
        rust = format!("{kind} {rust}");
    }
    Ok(Ty {
        rust,
        base: name,
        stars,
        opaque,
    })
}

/// What the generated shim makes of a parameter before it calls the trait: the reader of `ffi` that
/// checks it once (a NULL where the interface's rule forbids one gives the rule's code), and the type
/// the trait method takes, which holds what was checked for the call only.
#[derive(Debug, PartialEq)]
enum Arg {
    /// Passed as it is: an integer, a BOOL, an LCID.
    Value,
    /// `[in] void *` or an interface the library never calls (`IStream *`): `ffi::Opaque`, a pointer
    /// (perhaps NULL) the method can only pass on.
    Opaque,
    /// `[out] T *p`: `ffi::Out<T>` (the boundary reset it); `optional`: `Option<ffi::Out<T>>`.
    Out { elem: String, optional: bool },
    /// `[out, size_is(len)] T *p`: `ffi::OutArray<T>`, room for `len` elements, never reset.
    OutArray { elem: String, len: String },
    /// `[in] REFIID` / `REFCLSID`: a reference to the GUID.
    Guid { elem: String },
    /// `[in, string]` (`LPCWSTR`, `LPCOLESTR`): `ffi::WStr`, read when the method asks;
    /// `optional`: `Option<ffi::WStr>`.
    Str { optional: bool },
    /// `[in, size_is(count)] T a[]`: `ffi::InArray<T>`, read when the method asks, against its limit.
    InArray { elem: String, count: String },
    /// `[in] IFoo *p`: `ffi::Iface<IFoo>`, a valid interface pointer for the call; `optional`
    /// (`[unique]`): `Option<ffi::Iface<IFoo>>`.
    Iface { iface: String, optional: bool },
}

/// Pointer parameters the library accepts NULL for although the IDL does not say so (a pointer
/// parameter without `[unique]` is `[ref]`, never NULL, in MIDL's terms): (interface, method,
/// parameter, why). Everything else NULL gets the interface's NULL code from the shim.
const MAY_BE_NULL: &[(&str, &str, &str, &str)] = &[(
    "IOPCShutdown",
    "ShutdownRequest",
    "szReason",
    "the server gave no reason: the sink passes a NUL string on (specification 3.1.4)",
)];

/// The first argument of `size_is(...)`, if any (`size_is(,*pdwCount)` sizes what the parameter
/// points at, not the parameter: none).
fn size_is(p: &Param) -> Option<String> {
    attribute_items(&p.attributes).iter().find_map(|i| {
        i.strip_prefix("size_is(")
            .map(|rest| {
                rest.trim_end_matches(')')
                    .split(',')
                    .next()
                    .unwrap_or("")
                    .trim()
                    .to_string()
            })
            .filter(|n| !n.is_empty())
    })
}

/// `ty` with one pointer level fewer: the type a pointer parameter points at.
fn pointee(iface: &str, p: &Param, ty: &Ty) -> Result<String, String> {
    if let Some(rest) = ty
        .rust
        .strip_prefix("*mut ")
        .or_else(|| ty.rust.strip_prefix("*const "))
    {
        return Ok(rest.to_string());
    }
    match ty.base.as_str() {
        "LPCLSID" => Ok("CLSID".to_string()),
        other => Err(format!(
            "{iface}: parameter {} of type {other} points at nothing the generator knows",
            p.name
        )),
    }
}

fn classify(catalog: &Catalog, iface: &str, enumerator: bool, m: &Method, p: &Param, ty: &Ty) -> Result<Arg, String> {
    let items = attribute_items(&p.attributes);
    let has = |a: &str| items.iter().any(|i| i == a);
    let optional = has("unique")
        || MAY_BE_NULL
            .iter()
            .any(|(i, mm, pp, _)| *i == iface && *mm == m.name && *pp == p.name);
    let alias_pointer = POINTER_ALIASES.contains(&ty.base.as_str());
    if ty.stars == 0 && !alias_pointer {
        return Ok(Arg::Value);
    }
    if has("out") {
        if let Some(len) = size_is(p) {
            return Ok(Arg::OutArray {
                elem: pointee(iface, p, ty)?,
                len,
            });
        }
        // COM's enumerator contract: Next's count of fetched elements may be NULL (when one is asked for).
        let fetched = enumerator && m.name == "Next" && m.params.last().is_some_and(|last| last.name == p.name);
        return Ok(Arg::Out {
            elem: pointee(iface, p, ty)?,
            optional: optional || fetched,
        });
    }
    if !has("in") {
        return Err(format!(
            "{iface}::{}: parameter {} is neither [in] nor [out]",
            m.name, p.name
        ));
    }
    match ty.base.as_str() {
        "REFIID" | "REFCLSID" if !optional => {
            return Ok(Arg::Guid {
                elem: if ty.base == "REFIID" { "IID" } else { "CLSID" }.to_string(),
            })
        }
        "LPCWSTR" | "LPCOLESTR" if ty.stars == 0 => return Ok(Arg::Str { optional }),
        _ => {}
    }
    if let Some(count) = size_is(p) {
        return Ok(Arg::InArray {
            elem: pointee(iface, p, ty)?,
            count,
        });
    }
    if ty.opaque && ty.stars == 1 {
        return Ok(Arg::Opaque);
    }
    if ty.stars == 1 && catalog.contains(&ty.base) {
        return Ok(Arg::Iface {
            iface: ty.base.clone(),
            optional,
        });
    }
    Err(format!(
        "{iface}::{}: parameter {} ({}) is a pointer the generator has no reader for",
        m.name, p.name, p.ty
    ))
}

impl Arg {
    /// The type the trait method takes.
    fn trait_type(&self, raw: &str) -> String {
        let opt = |optional: bool, t: String| if optional { format!("Option<{t}>") } else { t };
        match self {
            Arg::Value => raw.to_string(),
            Arg::Opaque => "ffi::Opaque<'_>".to_string(),
            Arg::Out { elem, optional } => opt(*optional, format!("ffi::Out<'_, {elem}>")),
            Arg::OutArray { elem, .. } => format!("ffi::OutArray<'_, {elem}>"),
            Arg::Guid { elem } => format!("&{elem}"),
            Arg::Str { optional } => opt(*optional, "ffi::WStr<'_>".to_string()),
            Arg::InArray { elem, .. } => format!("ffi::InArray<'_, {elem}>"),
            Arg::Iface { iface, optional } => opt(*optional, format!("ffi::Iface<'_, {iface}>")),
        }
    }

    /// The shim's expression that checks the raw argument `name` and makes the trait's argument.
    fn reader(&self, name: &str) -> String {
        match self {
            Arg::Value => name.to_string(),
            Arg::Opaque => format!("ffi::opaque({name})"),
            Arg::Out { optional: false, .. } => format!("ffi::out({name})?"),
            Arg::Out { optional: true, .. } => format!("ffi::out_opt({name})"),
            Arg::OutArray { len, .. } => format!("ffi::out_array({name}, {len})?"),
            Arg::Guid { .. } => format!("ffi::in_ref({name})?"),
            Arg::Str { optional: false } => format!("ffi::in_wstr({name})?"),
            Arg::Str { optional: true } => format!("ffi::in_wstr_opt({name})"),
            Arg::InArray { count, .. } => format!("ffi::in_array_arg({name}, {count})"),
            Arg::Iface { optional: false, .. } => format!("ffi::in_iface({name})?"),
            Arg::Iface { optional: true, .. } => format!("ffi::in_iface_opt({name})"),
        }
    }
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

/// `text` as `//` comment lines of at most 100 columns after `indent`.
fn comment(text: &str, indent: &str) -> String {
    let mut s = String::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        if !line.is_empty() && line.len() + 1 + word.len() > 100 - indent.len() - 3 {
            let _ = writeln!(s, "{indent}// {line}");
            line.clear();
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    let _ = writeln!(s, "{indent}// {line}");
    s
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
    /// What the shim makes of each parameter for the trait.
    args: Vec<Arg>,
    ret: &'static str,
    /// The parameters the boundary resets.
    outs: Vec<String>,
}

fn signature(catalog: &Catalog, iface: &str, enumerator: bool, m: &Method) -> Result<Sig, String> {
    let mut params = Vec::new();
    let mut args = Vec::new();
    let mut outs = Vec::new();
    for p in &m.params {
        if resets(p) {
            outs.push(p.name.clone());
        }
        let ty = rust_type(catalog, iface, p)?;
        args.push(classify(catalog, iface, enumerator, m, p, &ty)?);
        params.push((p.name.clone(), ty));
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
    Ok(Sig {
        params,
        args,
        ret,
        outs,
    })
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

/// The trait method's parameters after `this`: the typed arguments.
fn trait_param_list(sig: &Sig) -> String {
    sig.params
        .iter()
        .zip(&sig.args)
        .map(|((n, t), a)| format!(", {n}: {}", a.trait_type(&t.rust)))
        .collect()
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
         //! - The trait's methods are safe: the shim checks every pointer argument once, under the\n\
         //!   interface's NULL rule, and hands the method what it checked, typed from the IDL and valid\n\
         //!   for the call only: `[out]` as [`ffi::Out`] (`Option` where COM allows NULL), `[out,\n\
         //!   size_is]` as [`ffi::OutArray`], `REFIID`/`REFCLSID` as a reference, `[in, string]` as\n\
         //!   [`ffi::WStr`], `[in, size_is]` as [`ffi::InArray`], an interface pointer as\n\
         //!   [`ffi::Iface`] (`Option` for `[unique]`), `void *` as [`ffi::Opaque`], and an IUnknown\n\
         //!   method's `This` as a [`ThisSlot`].\n\
         //! - `IFoo::IID` and `IFoo::METHODS` (IUnknown's three included).\n\n\
         #![allow(non_snake_case, clippy::too_many_arguments)]\n\n\
         use core::ffi::c_void;\n\n\
         use super::ffi::{self, Crossed, FfiResult, Foreign, Hr};\n\
         use super::object::{ComClass, ComObject, ThisSlot, Vtable};\n",
    );
    // The types the module names.
    let mut used: Vec<&str> = vec!["CLSID", "GUID", "HRESULT", "IID", "ULONG", "REFIID"];
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
        let enumerator = catalog.get(owner).is_some_and(is_enumerator);
        sigs.push((*owner, *m, signature(catalog, owner, enumerator, m)?));
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
        s += &doc(&m.doc, "    ");
        let this = if is_root {
            "This: ThisSlot<'_>".to_string()
        } else {
            "this: &ComObject<Self>".to_string()
        };
        let ret = if sig.ret == "HRESULT" { "FfiResult" } else { sig.ret };
        let _ = writeln!(s, "    fn {}({this}{}) -> {ret};", m.name, trait_param_list(sig));
    }
    s += "}\n\n";

    // The shims of the interface's own methods.
    for (owner, m, sig) in &sigs {
        if *owner != *name {
            continue;
        }
        let (head, this_ty, this_arg, call) = if is_root {
            (
                format!("<U: {name}Impl, I>"),
                "*mut I".to_string(),
                "ThisSlot::new(This.cast())".to_string(),
                format!("<U as {name}Impl>::{}", m.name),
            )
        } else {
            (
                format!("<T: {name}Impl>"),
                format!("*mut {name}"),
                "ComObject::<T>::from_interface(This)".to_string(),
                format!("<T as {name}Impl>::{}", m.name),
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
        let slot = if is_root {
            "`new::<U>` installs this shim only in vtables of slots that `U` answers for, so `This` is a slot \
             of a live object of the library"
                .to_string()
        } else {
            format!(
                "`{name}Vtbl::new::<_, T>` installs this shim only in the slots of `T`'s objects, so `This` is a \
                 slot of a live ComObject<T>"
            )
        };
        let checked: Vec<(&str, String)> = sig
            .params
            .iter()
            .zip(&sig.args)
            .filter(|(_, a)| **a != Arg::Value)
            .map(|((n, _), a)| (n.as_str(), a.reader(n)))
            .collect();
        let safety = if checked.is_empty() {
            comment(&format!("SAFETY: {slot}."), "        ")
        } else {
            comment(
                &format!(
                    "SAFETY: {slot}; every pointer argument is the COM caller's, NULL or valid for the call as \
                     the IDL declares it, which is what its reader requires."
                ),
                "        ",
            )
        };
        let mut names = vec!["this".to_string()];
        let mut readers = vec![this_arg];
        for (n, r) in &checked {
            names.push((*n).to_string());
            readers.push(r.clone());
        }
        let args: String = sig.params.iter().map(|(n, _)| format!(", {n}")).collect();
        let bind = if names.len() == 1 {
            format!("        let this = unsafe {{ {} }};\n", readers[0])
        } else {
            format!(
                "        let ({}) = unsafe {{ ({}) }};\n",
                names.join(", "),
                readers.join(", ")
            )
        };
        if sig.ret == "HRESULT" {
            let _ = writeln!(s, "    ffi::boundary!({rule}, [{}], {{", sig.outs.join(", "));
        } else {
            let _ = writeln!(s, "    ffi::guard!(0, {{");
        }
        s += &safety;
        s += &bind;
        let _ = writeln!(s, "        {call}(this{args})\n    }})\n}}\n");
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
        // Typed, checked arguments: no method is an unsafe fn.
        assert!(m.contains(
            "    fn QueryAvailableLocaleIDs(this: &ComObject<Self>, pdwCount: ffi::Out<'_, DWORD>, pdwLcid: ffi::Out<'_, *mut LCID>) -> FfiResult;"
        ), "{m}");
        for block in m.split("pub trait ").skip(1) {
            let body = &block[..block.find("}\n\n").unwrap()];
            assert!(!body.contains("unsafe fn"), "a trait method is unsafe: {body}");
        }
        // The shim checks them once, in the IDL's order, and calls the safe method.
        assert!(m.contains(
            "let (this, pdwCount, pdwLcid) = unsafe { (ComObject::<T>::from_interface(This), ffi::out(pdwCount)?, ffi::out(pdwLcid)?) };\n        <T as IOPCCommonImpl>::QueryAvailableLocaleIDs(this, pdwCount, pdwLcid)\n"
        ), "{m}");
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
        // `rgelt` is room for `celt` elements; the fetched count may be NULL (COM's enumerator rule).
        assert!(m.contains(
            "    fn Next(this: &ComObject<Self>, celt: ULONG, rgelt: ffi::OutArray<'_, GUID>, pceltFetched: Option<ffi::Out<'_, ULONG>>) -> FfiResult;"
        ), "{m}");
        assert!(m.contains("ffi::out_array(rgelt, celt)?, ffi::out_opt(pceltFetched)"));
        assert!(m.contains("fn Clone(this: &ComObject<Self>, ppenum: ffi::Out<'_, *mut IEnumGUID>) -> FfiResult;"));
        // IUnknown's methods take the slot they were called through.
        assert!(m.contains(
            "    fn QueryInterface(This: ThisSlot<'_>, riid: &IID, ppvObject: ffi::Out<'_, *mut c_void>) -> FfiResult;"
        ), "{m}");
        assert!(m.contains("    fn Release(This: ThisSlot<'_>) -> ULONG;"));
        assert!(
            m.contains("let this = unsafe { ThisSlot::new(This.cast()) };\n        <U as IUnknownImpl>::Release(this)")
        );
    }

    #[test]
    fn strings_arrays_guids_and_interface_pointers_are_typed() {
        let methods = OPC.replace(
            "HRESULT SetLocaleID([in] LCID dwLcid);",
            "HRESULT SetLocaleID([in] LCID dwLcid);\n\
             HRESULT SetClientName([in, string] LPCWSTR szName);\n\
             HRESULT CLSIDFromProgID([in] LPCOLESTR szProgId, [out] LPCLSID clsid);\n\
             HRESULT Enum([in] ULONG c, [in, size_is(c)] CATID rg[], [in] REFCLSID clsid, [out] IEnumGUID **pp);\n\
             HRESULT Make([in, unique] IUnknown *pOuter, [in] IUnknown *pSink, [in] REFIID riid, [out, iid_is(riid)] void **ppv);\n\
             HRESULT Pass([in, unique] void *pv);",
        );
        let m = generate(&methods).unwrap();
        assert!(
            m.contains("fn SetClientName(this: &ComObject<Self>, szName: ffi::WStr<'_>) -> FfiResult;"),
            "{m}"
        );
        assert!(m.contains("ffi::in_wstr(szName)?"));
        assert!(m.contains("fn CLSIDFromProgID(this: &ComObject<Self>, szProgId: ffi::WStr<'_>, clsid: ffi::Out<'_, CLSID>) -> FfiResult;"));
        assert!(m.contains(
            "fn Enum(this: &ComObject<Self>, c: ULONG, rg: ffi::InArray<'_, CATID>, clsid: &CLSID, pp: ffi::Out<'_, *mut IEnumGUID>) -> FfiResult;"
        ), "{m}");
        // An in-array is read by the method, against its own limit: the shim does not check it.
        assert!(m.contains("ffi::in_array_arg(rg, c), ffi::in_ref(clsid)?, ffi::out(pp)?"));
        assert!(m.contains(
            "fn Make(this: &ComObject<Self>, pOuter: Option<ffi::Iface<'_, IUnknown>>, pSink: ffi::Iface<'_, IUnknown>, riid: &IID, ppv: ffi::Out<'_, *mut c_void>) -> FfiResult;"
        ), "{m}");
        assert!(m.contains("ffi::in_iface_opt(pOuter), ffi::in_iface(pSink)?, ffi::in_ref(riid)?, ffi::out(ppv)?"));
        // A pointer the library only passes on.
        assert!(m.contains("fn Pass(this: &ComObject<Self>, pv: ffi::Opaque<'_>) -> FfiResult;"));
        assert!(m.contains("(ComObject::<T>::from_interface(This), ffi::opaque(pv))"));
        assert!(m.contains("fn SetLocaleID(this: &ComObject<Self>, dwLcid: LCID) -> FfiResult;"));
    }

    #[test]
    fn the_shutdown_reason_may_be_null_and_unknown_pointers_are_errors() {
        let shutdown = r#"
            [object, uuid(F31DFDE1-07B6-11d2-B2D8-0060083BA1FB)]
            interface IOPCShutdown : IUnknown {
                HRESULT ShutdownRequest([in, string] LPCWSTR szReason);
            }
        "#;
        let m = generate(shutdown).unwrap();
        assert!(
            m.contains("fn ShutdownRequest(this: &ComObject<Self>, szReason: Option<ffi::WStr<'_>>) -> FfiResult;"),
            "{m}"
        );
        assert!(m.contains("ffi::in_wstr_opt(szReason)"));
        let bad = OPC.replace("[in] LCID dwLcid", "[in] LCID *pdwLcid");
        let e = generate(&bad).unwrap_err();
        assert!(e.contains("no reader"), "{e}");
    }

    #[test]
    fn a_method_added_to_the_idl_is_in_the_trait_every_object_must_implement() {
        let added = OPC.replace(
            "HRESULT SetLocaleID([in] LCID dwLcid);",
            "HRESULT SetLocaleID([in] LCID dwLcid);\n HRESULT GetLocaleID([out] LCID *pdwLcid);",
        );
        let m = generate(&added).unwrap();
        assert!(m.contains("    fn GetLocaleID(this: &ComObject<Self>, pdwLcid: ffi::Out<'_, LCID>) -> FfiResult;"));
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
