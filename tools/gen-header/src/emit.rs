//! The interface section of include/opccomn/opccomn.h, written from the IDL in the shape MIDL (and
//! widl) give their headers, so that this header and a MIDL-generated one skip each other's
//! declarations: `__IOPCCommon_FWD_DEFINED__` and `__IOPCCommon_INTERFACE_DEFINED__` guards, IIDs
//! declared `EXTERN_C const IID`, C++ abstract classes unless `CINTERFACE`, C `lpVtbl` structs with
//! `STDMETHODCALLTYPE` on every entry, and `COBJMACROS` call macros.

use std::collections::HashMap;
use std::fmt::Write as _;

use crate::guids::{crt_uuid_args, Entry, Form};
use crate::idl::{Interface, Method, Param};

/// A documentation comment (`/** ... */`, which Doxygen reads) with `indent` in front of each line;
/// nothing for no lines.
pub fn doc_block(lines: &[String], indent: &str) -> String {
    if lines.is_empty() {
        return String::new();
    }
    let mut s = format!("{indent}/**\n");
    for l in lines {
        if l.is_empty() {
            let _ = writeln!(s, "{indent} *");
        } else {
            let _ = writeln!(s, "{indent} * {l}");
        }
    }
    let _ = writeln!(s, "{indent} */");
    s
}

/// All interfaces by name, to walk base interfaces.
pub struct Catalog<'a> {
    by_name: HashMap<&'a str, &'a Interface>,
}

impl<'a> Catalog<'a> {
    pub fn new(all: impl IntoIterator<Item = &'a Interface>) -> Self {
        Catalog {
            by_name: all.into_iter().map(|i| (i.name.as_str(), i)).collect(),
        }
    }

    /// Whether an interface of this name is declared.
    pub fn contains(&self, name: &str) -> bool {
        self.by_name.contains_key(name)
    }

    /// The interface of this name.
    pub fn get(&self, name: &str) -> Option<&'a Interface> {
        self.by_name.get(name).copied()
    }

    /// The methods of `i` with those of its bases first, each with the interface that declares it.
    pub fn vtable(&self, i: &'a Interface) -> Vec<(&'a str, &'a Method)> {
        let mut chain = vec![i];
        let mut cur = i;
        while let Some(base) = &cur.base {
            cur = self
                .by_name
                .get(base.as_str())
                .unwrap_or_else(|| panic!("{}: unknown base {base}", i.name));
            chain.push(cur);
        }
        chain
            .iter()
            .rev()
            .flat_map(|c| c.methods.iter().map(move |m| (c.name.as_str(), m)))
            .collect()
    }
}

/// The forward declarations, before anything else in the header.
pub fn forwards(interfaces: &[&Interface]) -> String {
    let mut s = String::new();
    for i in interfaces {
        let n = &i.name;
        let _ = write!(
            s,
            "#ifndef __{n}_FWD_DEFINED__\n#define __{n}_FWD_DEFINED__\ntypedef struct {n} {n};\n#endif\n\n"
        );
    }
    s
}

fn comment_attributes(p: &Param) -> String {
    if p.attributes.is_empty() {
        String::new()
    } else {
        format!("/* [{}] */ ", p.attributes)
    }
}

fn param_list(this: Option<&str>, params: &[Param], indent: &str) -> String {
    let mut parts = Vec::new();
    if let Some(t) = this {
        parts.push(format!("{t} *This"));
    }
    for p in params {
        parts.push(format!("{}{}", comment_attributes(p), p.declaration()));
    }
    if parts.is_empty() {
        return "void".to_string();
    }
    format!("\n{indent}{}", parts.join(&format!(",\n{indent}")))
}

/// One interface's definition block.
pub fn interface(catalog: &Catalog, i: &Interface, note: &str) -> String {
    let n = &i.name;
    let mut s = String::new();
    let _ = writeln!(s, "/* {n}{note} */");
    let _ = writeln!(
        s,
        "#ifndef __{n}_INTERFACE_DEFINED__\n#define __{n}_INTERFACE_DEFINED__\n"
    );
    for t in &i.typedefs {
        let _ = writeln!(s, "/** MIDL's pointer type for {n}. */\ntypedef {t};");
    }
    let _ = writeln!(s, "/** The interface identifier of {n}, {{{}}}. */", i.uuid);
    let _ = writeln!(s, "EXTERN_C const IID IID_{n};\n");
    // C++
    let _ = writeln!(s, "#if defined(__cplusplus) && !defined(CINTERFACE)\n");
    s += &doc_block(&i.doc, "");
    match &i.base {
        Some(b) => {
            let _ = writeln!(
                s,
                "MIDL_INTERFACE(\"{}\")\n{n} : public {b}\n{{\npublic:",
                i.uuid.to_lowercase()
            );
        }
        None => {
            let _ = writeln!(
                s,
                "MIDL_INTERFACE(\"{}\")\n{n}\n{{\npublic:\n    BEGIN_INTERFACE",
                i.uuid.to_lowercase()
            );
        }
    }
    for m in &i.methods {
        s += &doc_block(&m.doc, "    ");
        let _ = writeln!(
            s,
            "    virtual {} STDMETHODCALLTYPE {}({}) = 0;\n",
            m.ret,
            m.name,
            param_list(None, &m.params, "        ")
        );
    }
    if i.base.is_none() {
        let _ = writeln!(s, "    END_INTERFACE");
    }
    let _ = writeln!(s, "}};\n");
    let _ = writeln!(
        s,
        "#ifdef __CRT_UUID_DECL\n__CRT_UUID_DECL({n}, {})\n#endif\n",
        crt_uuid_args(&i.uuid)
    );
    // C
    let _ = writeln!(s, "#else /* C style interface */\n");
    let _ = writeln!(
        s,
        "/** The methods of {n} in vtable order, {} first (the C form of the interface). */",
        i.base.as_deref().unwrap_or("its own")
    );
    let _ = writeln!(s, "typedef struct {n}Vtbl\n{{\n    BEGIN_INTERFACE\n");
    let vtable = catalog.vtable(i);
    let mut last_owner = "";
    for (owner, m) in &vtable {
        if *owner != last_owner {
            let _ = writeln!(s, "    /* {owner} methods */");
            last_owner = owner;
        }
        s += &doc_block(&m.doc, "    ");
        let _ = writeln!(
            s,
            "    {} (STDMETHODCALLTYPE *{})({});\n",
            m.ret,
            m.name,
            param_list(Some(n), &m.params, "        ")
        );
    }
    let _ = writeln!(s, "    END_INTERFACE\n}} {n}Vtbl;\n");
    s += &doc_block(&i.doc, "");
    let _ = writeln!(
        s,
        "struct {n}\n{{\n    /** The interface's methods ({n}Vtbl). */\n    CONST_VTBL struct {n}Vtbl *lpVtbl;\n}};\n"
    );
    let _ = writeln!(s, "#ifdef COBJMACROS");
    for (_, m) in &vtable {
        let args: Vec<&str> = std::iter::once("This")
            .chain(m.params.iter().map(|p| p.name.as_str()))
            .collect();
        let _ = writeln!(
            s,
            "#define {n}_{}({}) \\\n    ( (This)->lpVtbl->{}({}) )",
            m.name,
            args.join(","),
            m.name,
            args.join(",")
        );
    }
    let _ = writeln!(s, "#endif /* COBJMACROS */\n");
    let _ = writeln!(s, "#endif /* C style interface */\n");
    s += &foreign_uuidof(n, &i.uuid);
    let _ = writeln!(s, "#endif /* __{n}_INTERFACE_DEFINED__ */\n");
    s
}

/// The `#elif` branch of an interface's `__{n}_INTERFACE_DEFINED__` guard, taken when another header
/// declared the interface first: its C++ `__uuidof` (mingw's emulation) in this header's own table,
/// `opccomn_uuidof_s` (see [`UUIDOF_PROLOGUE`]), never as a second `__CRT_UUID_DECL`. MIDL's output (the
/// OPC Foundation's headers) declares no `__uuidof`, widl's does, and nothing the preprocessor sees
/// tells them apart: a `__CRT_UUID_DECL` here was a redefinition after widl's, and its absence left
/// `__uuidof(IOPCCommon)` unlinkable after MIDL's. Skipped when the name is a macro: opcda.h
/// `#define`s CATID_OPCDAServer20, its category interface, to the IID.
fn foreign_uuidof(n: &str, uuid: &str) -> String {
    format!(
        "#elif defined(__cplusplus) && !defined(CINTERFACE) && defined(OPCCOMN_UUIDOF_TABLE_) && !defined({n})\n\
         /* {n} was declared by another header: __uuidof({n}) from this header's table */\n\
         OPCCOMN_UUIDOF_DECL_({n}, {})\n\
         #define OPCCOMN_UUIDOF_REDIRECT_ 1\n",
        crt_uuid_args(uuid)
    )
}

/// Before the interfaces: the table `opccomn_uuidof_s<T>` that [`foreign_uuidof`] fills for the
/// interfaces another header declared first. Its primary template answers with mingw's
/// `__mingw_uuidof<T>()`, so that [`UUIDOF_EPILOGUE`] can point `__uuidof` at it for every type.
/// Constant expressions where mingw's are (C++17), as its `__CRT_UUID_DECL` has them.
pub const UUIDOF_PROLOGUE: &str = r#"/* C++ with mingw-w64 (g++, clang++): __uuidof of the interfaces another header declared first.
   MIDL's output (the OPC Foundation's headers) declares no __uuidof for them, and __uuidof(IOPCCommon)
   would compile and fail to link; widl's output declares it with __CRT_UUID_DECL, and a second
   declaration would be a redefinition. No preprocessor test tells the two apart, so for such an
   interface this header declares the identifier in a table of its own, opccomn_uuidof_s<T>, and at its
   end __uuidof reads that table, which hands every other type to mingw's __mingw_uuidof<T>(). An
   interface this header declares itself gets mingw's declaration (__CRT_UUID_DECL) with it, and
   __uuidof stays mingw's. Defining OPCCOMN_FOREIGN_UUIDOF leaves __uuidof to the other header. */
#if defined(__cplusplus) && !defined(CINTERFACE) && defined(__uuidof) && defined(__CRT_UUID_DECL) && !defined(OPCCOMN_FOREIGN_UUIDOF)
#define OPCCOMN_UUIDOF_TABLE_ 1
extern "C++" {
#if __cpp_constexpr >= 200704L && __cpp_inline_variables >= 201606L
template<typename T> struct opccomn_uuidof_s {
    static constexpr const GUID &get() { return __mingw_uuidof<T>(); }
};
#define OPCCOMN_UUIDOF_DECL_(type, l, w1, w2, b1, b2, b3, b4, b5, b6, b7, b8) \
    extern "C++" { \
    template<> struct opccomn_uuidof_s<type> { \
        static constexpr IID value = {l, w1, w2, {b1, b2, b3, b4, b5, b6, b7, b8}}; \
        static constexpr const GUID &get() { return value; } \
    }; \
    template<> struct opccomn_uuidof_s<type *> : opccomn_uuidof_s<type> {}; \
    }
#else
template<typename T> struct opccomn_uuidof_s {
    static const GUID &get() { return __mingw_uuidof<T>(); }
};
#define OPCCOMN_UUIDOF_DECL_(type, l, w1, w2, b1, b2, b3, b4, b5, b6, b7, b8) \
    extern "C++" { \
    template<> struct opccomn_uuidof_s<type> { \
        static const GUID &get() { \
            static const IID value = {l, w1, w2, {b1, b2, b3, b4, b5, b6, b7, b8}}; \
            return value; \
        } \
    }; \
    template<> struct opccomn_uuidof_s<type *> : opccomn_uuidof_s<type> {}; \
    }
#endif
}
#endif

"#;

/// After the interfaces: when one of them was declared by another header, `__uuidof` reads
/// [`UUIDOF_PROLOGUE`]'s table (which answers for every other type as mingw's `__uuidof` did).
pub const UUIDOF_EPILOGUE: &str = r#"/* An interface above was declared by another header first: __uuidof reads this header's table,
   which answers for every other type as mingw-w64's __uuidof does. */
#if defined(OPCCOMN_UUIDOF_REDIRECT_)
#undef __uuidof
#define __uuidof(type) opccomn_uuidof_s<__typeof(type)>::get()
#endif

"#;

/// A category of the interface form: an interface without methods (opcda.h's declaration).
fn category_interface(e: &Entry) -> String {
    let n = e.interface_name();
    let name = &e.name;
    format!(
        "/* {name} {{{g}}}: {d} */\n\
         #ifndef __{n}_FWD_DEFINED__\n#define __{n}_FWD_DEFINED__\ntypedef struct {n} {n};\n#endif\n\
         #ifndef __{n}_INTERFACE_DEFINED__\n#define __{n}_INTERFACE_DEFINED__\n\
         /** The category {d}, {{{g}}} (`{name}` names it; declared as an interface, as opcda.h does). */\n\
         EXTERN_C const IID IID_{n};\n\
         #if defined(__cplusplus) && !defined(CINTERFACE)\n\
         /** The category {d} in the interface form of the Foundation's headers: no methods. */\n\
         MIDL_INTERFACE(\"{gl}\")\n{n} : public IUnknown\n{{\npublic:\n}};\n\
         #ifdef __CRT_UUID_DECL\n__CRT_UUID_DECL({n}, {crt})\n#endif\n\
         #else\n\
         /** The vtable of the category's interface form: IUnknown's methods only. */\n\
         typedef struct {n}Vtbl\n{{\n    BEGIN_INTERFACE\n\
         \x20   /**\n\
         \x20    * IUnknown::QueryInterface.\n\
         \x20    *\n\
         \x20    * # Parameters\n\
         \x20    * - `riid`: the interface wanted.\n\
         \x20    * - `ppvObject`: receives the interface, or NULL on failure.\n\
         \x20    *\n\
         \x20    * # Returns\n\
         \x20    * S_OK; E_NOINTERFACE.\n\
         \x20    */\n\
         \x20   HRESULT (STDMETHODCALLTYPE *QueryInterface)({n} *This, /* [in] */ REFIID riid, /* [out] */ void **ppvObject);\n\
         \x20   /**\n\
         \x20    * IUnknown::AddRef.\n\
         \x20    *\n\
         \x20    * # Returns\n\
         \x20    * The new count, for diagnostics only.\n\
         \x20    */\n\
         \x20   ULONG (STDMETHODCALLTYPE *AddRef)({n} *This);\n\
         \x20   /**\n\
         \x20    * IUnknown::Release.\n\
         \x20    *\n\
         \x20    * # Returns\n\
         \x20    * The new count, for diagnostics only.\n\
         \x20    */\n\
         \x20   ULONG (STDMETHODCALLTYPE *Release)({n} *This);\n\
         \x20   END_INTERFACE\n}} {n}Vtbl;\n\
         /** The category {d} in the interface form of the Foundation's headers: no methods. */\n\
         struct {n}\n{{\n    /** IUnknown's methods. */\n    CONST_VTBL struct {n}Vtbl *lpVtbl;\n}};\n\
         #endif\n{foreign}#endif /* __{n}_INTERFACE_DEFINED__ */\n\
         #ifndef {name}\n/** The category {d}: `IID_{n}` under the name code uses. */\n#define {name} IID_{n}\n#endif\n\n",
        g = e.guid,
        gl = e.guid.to_lowercase(),
        d = e.note,
        crt = crt_uuid_args(&e.guid),
        foreign = foreign_uuidof(n, &e.guid),
    )
}

/// The declarations of the table's categories and classes.
pub fn table_declarations(table: &[Entry]) -> String {
    let mut s = String::new();
    for e in table {
        match e.form {
            Form::Interface => s += &category_interface(e),
            Form::Constant => {
                let ty = if e.kind == "category" { "CATID" } else { "CLSID" };
                let what = if e.kind == "category" {
                    e.note.clone()
                } else {
                    format!("the class {}", e.note)
                };
                let _ = write!(
                    s,
                    "/* {n} {{{g}}}: {what} */\n#ifndef {n}\n/** {{{g}}}: {what}. */\nEXTERN_C const {ty} {n};\n#endif\n\n",
                    n = e.name,
                    g = e.guid
                );
            }
            Form::Internal => {}
        }
    }
    s
}
