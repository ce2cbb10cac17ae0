//! Writes a [`Model`] as Rust statics in the layout language (`src/proxy/ndr/layout.rs`) and the C
//! include that gives `src/proxy/opccomn_ps.c` the same interface numbering.

use std::collections::HashMap;
use std::fmt::Write as _;

use super::resolve::{Corr, Extent, Model, Node, Save, DEFAULT_BOUND};

/// Writes statics once each, named in order of first use.
struct Statics {
    text: String,
    names: HashMap<String, String>,
    counters: HashMap<&'static str, usize>,
    used: std::collections::BTreeSet<&'static str>,
}

impl Statics {
    /// The name of a static of type `ty` with this initializer (the same initializer, the same name).
    fn named(&mut self, prefix: &'static str, ty: &'static str, body: String, doc: &str) -> String {
        let key = format!("{ty}{body}");
        if let Some(n) = self.names.get(&key) {
            return n.clone();
        }
        let counter = self.counters.entry(prefix).or_insert(0);
        let name = format!("{prefix}_{counter}");
        *counter += 1;
        self.used.insert(ty);
        if !doc.is_empty() {
            let _ = writeln!(self.text, "/// {doc}");
        }
        let _ = writeln!(self.text, "static {name}: {ty} = {body};\n");
        self.names.insert(key, name.clone());
        name
    }
}

fn corr(c: &Corr) -> String {
    match c {
        Corr::Slot(s) => format!("Corr::Slot({s})"),
        Corr::Field(f) => format!("Corr::Field({f})"),
    }
}

fn bytes(b: &[u8; 16]) -> String {
    let items: Vec<String> = b.iter().map(|x| format!("0x{x:02X}")).collect();
    format!("[{}]", items.join(", "))
}

struct Writer<'m> {
    model: &'m Model,
    statics: Statics,
}

impl Writer<'_> {
    fn align(&self, n: &Node) -> u8 {
        match n {
            Node::Base(s) => *s,
            Node::Enum16 => 2,
            Node::Empty => 1,
            Node::Struct(name) => self.model.structs.get(name).map_or(4, |s| s.align),
            _ => 4,
        }
    }

    fn plain(&self, n: &Node) -> u32 {
        match n {
            Node::Base(s) => u32::from(*s),
            Node::Guid => 16,
            Node::Struct(name) => self.model.structs.get(name).map_or(0, |s| s.plain),
            _ => 0,
        }
    }

    fn deferred(&self, n: &Node) -> bool {
        match n {
            Node::Pointer(..) | Node::Bstr | Node::Variant | Node::SafeArray => true,
            Node::Struct(name) => self.model.structs.get(name).is_some_and(|s| s.deferred),
            Node::Array(a) => self.deferred(&a.elem),
            Node::Union(u) => u
                .arms
                .iter()
                .map(|(_, a)| a)
                .chain(&u.default)
                .any(|a| self.deferred(a)),
            _ => false,
        }
    }

    fn ty(&mut self, n: &Node) -> String {
        match n {
            Node::Base(s) => format!("Ty::Base({s})"),
            Node::Enum16 => "Ty::Enum16".into(),
            Node::Guid => "Ty::Guid".into(),
            Node::Str(u) => format!("Ty::Str({u})"),
            Node::Bstr => "Ty::Bstr".into(),
            Node::Variant => "Ty::Variant".into(),
            Node::SafeArray => "Ty::SafeArray".into(),
            Node::Empty => "Ty::Empty".into(),
            Node::Interface(name, Some(iid), _) => {
                let c = format!("IID_{}", name.to_uppercase());
                if self.statics.names.insert(c.clone(), c.clone()).is_none() {
                    let _ = writeln!(
                        self.statics.text,
                        "/// {name}'s IID as NDR writes it.\nconst {c}: [u8; 16] = {};\n",
                        bytes(iid)
                    );
                }
                self.statics.used.insert("Iid");
                format!("Ty::Interface(Iid::Fixed({c}))")
            }
            Node::Interface(_, None, slot) => {
                self.statics.used.insert("Iid");
                format!("Ty::Interface(Iid::Slot({slot}))")
            }
            Node::Pointer(unique, target) => {
                let t = self.ty(target);
                let body = format!("Pointer {{ unique: {unique}, target: {t} }}");
                format!("Ty::Pointer(&{})", self.statics.named("POINTER", "Pointer", body, ""))
            }
            Node::Struct(name) => format!("Ty::Struct(&STRUCT_{})", name.to_uppercase()),
            Node::Union(u) => {
                let mut arms = String::new();
                for (case, arm) in &u.arms {
                    let t = self.ty(arm);
                    let _ = write!(arms, "({case}, {t}), ");
                }
                let default = match &u.default {
                    Some(d) => format!("Some({})", self.ty(d)),
                    None => "None".into(),
                };
                let deferred = self.deferred(n);
                let body = format!(
                    "Union {{ name: {:?}, switch: {}, switch_size: {}, arms: &[{arms}], default: {default}, deferred: {deferred} }}",
                    u.name,
                    corr(&u.switch),
                    u.size
                );
                self.statics.used.insert("Corr");
                format!("Ty::Union(&{})", self.statics.named("UNION", "Union", body, ""))
            }
            Node::Array(a) => {
                let elem = self.ty(&a.elem);
                let size = match a.size {
                    Extent::Fixed(n) => format!("Extent::Fixed({n})"),
                    Extent::Conformant(c) => format!("Extent::Conformant({})", corr(&c)),
                };
                let length = match &a.length {
                    Some(c) => format!("Some({})", corr(c)),
                    None => "None".into(),
                };
                self.statics.used.insert("Extent");
                self.statics.used.insert("Corr");
                let plain = self.plain(&a.elem);
                let plain = if plain.is_multiple_of(u32::from(self.align(&a.elem))) {
                    plain
                } else {
                    0
                };
                // The engine aligns the elements' start to the array's alignment, which for VARIANTs
                // is VARIANT's memory alignment (the FC_BOGUS_ARRAY of widl's and MIDL's format
                // strings), not their 4-byte places in the flat part.
                let align = match a.elem {
                    Node::Variant => 8,
                    ref e => self.align(e),
                };
                let body = format!(
                    "Array {{ elem: {elem}, size: {size}, length: {length}, bound: {}, plain: {plain}, align: {align}, deferred: {} }}",
                    a.bound,
                    self.deferred(&a.elem)
                );
                format!("Ty::Array(&{})", self.statics.named("ARRAY", "Array", body, ""))
            }
        }
    }

    fn save(s: &Save) -> String {
        match s {
            Save::None => "Save::None".into(),
            Save::Int(x) => format!("Save::Int({x})"),
            Save::Guid(x) => format!("Save::Guid({x})"),
        }
    }
}

/// The generated Rust module. `sources` names the files it comes from (for its header).
pub fn rust(model: &Model, sources: &str, purpose: &str) -> String {
    let mut w = Writer {
        model,
        statics: Statics {
            text: String::new(),
            names: HashMap::new(),
            counters: HashMap::new(),
            used: Default::default(),
        },
    };
    // Structures first, by name.
    let mut structs = String::new();
    for s in model.structs.values() {
        let mut fields = String::new();
        for (name, node) in &s.fields {
            let t = w.ty(node);
            let _ = writeln!(fields, "        {t}, // {name}");
        }
        let _ = writeln!(
            structs,
            "static STRUCT_{}: Struct = Struct {{\n    name: {:?},\n    align: {},\n    fields: &[\n{fields}    ],\n    deferred: {},\n    plain: {},\n    size: {},\n}};\n",
            s.name.to_uppercase(),
            s.name,
            s.align,
            s.deferred,
            s.plain,
            s.size
        );
    }
    if !model.structs.is_empty() {
        w.statics.used.insert("Struct");
    }
    let mut methods = String::new();
    for i in &model.interfaces {
        let _ = writeln!(methods, "/// {}'s methods from vtable index 3.", i.name);
        let _ = writeln!(
            methods,
            "static METHODS_{}: [Method; {}] = [",
            i.name.to_uppercase(),
            i.methods.len()
        );
        for m in &i.methods {
            let mut params = |ps: &[super::resolve::ParamOut]| {
                let mut out = String::new();
                for p in ps {
                    let t = w.ty(&p.node);
                    let _ = write!(
                        out,
                        "Param {{ name: {:?}, ty: {t}, save: {} }}, ",
                        p.name,
                        Writer::save(&p.save)
                    );
                }
                out
            };
            let request = params(&m.request);
            let reply = params(&m.reply);
            let bounds: Vec<String> = m.bounds.iter().map(|(s, b)| format!("({s}, {b})")).collect();
            let context: Vec<String> = m.context.iter().map(Writer::save).collect();
            let _ = writeln!(
                methods,
                "    Method {{ name: {:?}, request: &[{request}], reply: &[{reply}], bounds: &[{}], context: &[{}], request_align8: {}, reply_align8: {} }},",
                m.name,
                bounds.join(", "),
                context.join(", "),
                m.request_align8,
                m.reply_align8
            );
        }
        methods += "];\n\n";
    }

    let mut out = String::new();
    let _ = writeln!(
        out,
        "//! Generated by tools/gen-header from {sources}: do not edit\n\
         //! (`cargo run -p gen-header`; `--check` fails when this file is not what they generate).\n//!\n{purpose}//!\n\
         //! The bound of every array whose count a peer chooses (what MIDL's `[range]` would say), by\n\
         //! `Interface.Method.parameter` or `Structure.field`; the default is {DEFAULT_BOUND}:\n//!"
    );
    let mut bounds = model.bounds.clone();
    bounds.sort_by(|a, b| a.key.cmp(&b.key));
    for b in &bounds {
        let why = b.reason.as_deref().unwrap_or("(the default)");
        let _ = writeln!(out, "//! - `{}`: {} {why}", b.key, b.bound);
    }
    if bounds.is_empty() {
        out += "//! (none)\n";
    }
    let mut used: Vec<&str> = ["Interface as Layout", "Method", "Param", "Save", "Ty"]
        .into_iter()
        .chain(w.statics.used.iter().copied().filter(|t| *t != "[u8; 16]"))
        .collect();
    used.sort_by_key(|t| t.to_lowercase());
    used.dedup();
    let _ = writeln!(
        out,
        "\nuse crate::com::GUID;\nuse crate::proxy::ndr::layout::{{{}}};\n",
        used.join(", ")
    );

    // The interfaces and their numbering.
    let _ = writeln!(
        out,
        "/// The interfaces, numbered from 0 in the order of the IDL (the number the C side passes).\n\
         ///\n/// cbindgen:ignore\n\
         #[allow(non_camel_case_types)]\n#[derive(Clone, Copy, Debug, PartialEq, Eq)]\npub enum Interface {{"
    );
    for (n, i) in model.interfaces.iter().enumerate() {
        let _ = writeln!(out, "    {} = {n},", i.name);
    }
    let _ = writeln!(out, "}}\n");
    let count = model.interfaces.len();
    let all: Vec<String> = model
        .interfaces
        .iter()
        .map(|i| format!("Interface::{}", i.name))
        .collect();
    let _ = writeln!(
        out,
        "/// How many there are.\npub(crate) const COUNT: usize = {count};\n\n\
         const ALL: [Interface; COUNT] = [{}];\n\n\
         impl Interface {{\n    /// Every interface, by number.\n    pub fn all() -> &'static [Interface] {{\n        &ALL\n    }}\n\n\
         \x20   /// The interface numbered `n`.\n    pub fn from_index(n: u32) -> Option<Interface> {{\n        ALL.get(n as usize).copied()\n    }}\n\n\
         \x20   /// Its layout.\n    pub fn layout(self) -> &'static Layout {{\n        &INTERFACES[self as usize]\n    }}\n}}\n",
        all.join(", ")
    );
    let _ = writeln!(
        out,
        "/// The interfaces' layouts, by number.\npub(crate) static INTERFACES: [Layout; COUNT] = ["
    );
    for i in &model.interfaces {
        let _ = writeln!(
            out,
            "    Layout {{ name: {:?}, iid: {}, vtable: {}, methods: &METHODS_{} }},",
            i.name,
            bytes(&i.iid),
            i.vtable,
            i.name.to_uppercase()
        );
    }
    let _ = writeln!(
        out,
        "];\n\n/// The interfaces as registered under `Interface\\{{iid}}`: IID, name, `NumMethods` (IUnknown's three\n/// included), and the specification each belongs to.\npub(crate) const PROXY_STUB_INTERFACES: [(GUID, &str, u32, &str); COUNT] = ["
    );
    for i in &model.interfaces {
        let hex: String = i.uuid.chars().filter(|c| *c != '-').collect();
        let _ = writeln!(
            out,
            "    (GUID::from_u128(0x{}), {:?}, {}, {:?}),",
            hex.to_uppercase(),
            i.name,
            i.vtable,
            i.spec
        );
    }
    out += "];\n\n";
    out += &methods;
    out += &structs;
    out += &w.statics.text;
    out
}

/// The C include of `src/proxy/opccomn_ps.c` and `src/proxy/opcda_ps.c`: the interfaces by number,
/// the reply context's size, and the IIDs of the interfaces that are not OPC Common's (whose tables
/// are compiled on their own) under names of the proxy/stub's own, in three parts the includer
/// chooses (no include guard).
pub fn c_include(model: &Model, sources: &str, context_words: usize) -> String {
    let own: Vec<_> = model.interfaces.iter().filter(|i| i.spec != "Common").collect();
    let mut s = format!(
        "/* Generated by tools/gen-header from {sources}: do not edit\n\
         \x20* (`cargo run -p gen-header`).\n\
         \x20*\n\
         \x20* The interfaces opccomn's proxy/stub serves, numbered as src/proxy/generated/layouts.rs numbers\n\
         \x20* them: the checks (src/proxy/ndr) take this number. Three parts, by what the includer defines:\n\
         \x20* - OPC_PS_PART_NAMES, before the widl-generated headers: the IIDs of the interfaces that are not\n\
         \x20*   OPC Common's get names of the proxy/stub's own (opccomn_ps_IID_...), so that a program linking\n\
         \x20*   opccomn statically may define IID_IOPCServer and the others itself (OPC Common's IIDs are\n\
         \x20*   opccomn's exported GUIDs);\n\
         \x20* - OPC_PS_PART_IIDS: their definitions (src/proxy/opcda_ps.c);\n\
         \x20* - neither: the numbering (src/proxy/opccomn_ps.c, after the headers that declare the IIDs). */\n\n\
         #if defined(OPC_PS_PART_NAMES)\n"
    );
    for i in &own {
        let _ = writeln!(s, "#define IID_{0} opccomn_ps_IID_{0}", i.name);
    }
    s += "#elif defined(OPC_PS_PART_IIDS)\n";
    for i in &own {
        let _ = writeln!(s, "const IID IID_{} = {};", i.name, c_guid(&i.uuid));
    }
    let _ = write!(
        s,
        "#else\n\
         #define OPC_PS_INTERFACE_COUNT {}\n\
         /* The words of what a reply check needs of its request (src/proxy/ndr: Context). */\n\
         #define OPC_PS_CONTEXT_WORDS {context_words}\n\n\
         static const IID *const opc_ps_interfaces[OPC_PS_INTERFACE_COUNT] = {{\n",
        model.interfaces.len()
    );
    for i in &model.interfaces {
        let _ = writeln!(s, "    &IID_{},", i.name);
    }
    s += "};\n#endif\n";
    s
}

/// A GUID as C's initializer: `{0x39c13a4d, 0x011e, 0x11d0, {0x96, 0x75, ...}}`.
fn c_guid(uuid: &str) -> String {
    let parts: Vec<&str> = uuid.split('-').collect();
    let tail: String = parts[3..].concat();
    let bytes: Vec<String> = (0..8).map(|i| format!("0x{}", &tail[2 * i..2 * i + 2])).collect();
    format!(
        "{{0x{}, 0x{}, 0x{}, {{{}}}}}",
        parts[0],
        parts[1],
        parts[2],
        bytes.join(", ")
    )
}

/// The tests' table of every served method's C parameters (`tests/oop/ps_args.h`): what a generic
/// call passes for each (`tests/oop/test_served_messages.c`).
pub fn c_args(model: &Model, sources: &str) -> String {
    let mut s = format!(
        "/* Generated by tools/gen-header from {sources}: do not edit (`cargo run -p gen-header`).\n\
         \x20*\n\
         \x20* Every method of every interface opccomn's proxy/stub serves, by interface and method name, with\n\
         \x20* its C parameters after `This` in order: i a value of at most 4 bytes, h one of 8, p a pointer,\n\
         \x20* v a VARIANT by value, f a structure of 8 bytes by value (a FILETIME). For the tests'\n\
         \x20* generic calls through the proxies (tests/oop/test_served_messages.c). */\n\n\
         static const char *const PS_ARGS[][3] = {{\n"
    );
    for i in &model.interfaces {
        for m in &i.methods {
            let _ = writeln!(s, "    {{\"{}\", \"{}\", \"{}\"}},", i.name, m.name, m.args);
        }
    }
    s += "};\n#define PS_ARGS_COUNT (sizeof PS_ARGS / sizeof PS_ARGS[0])\n";
    s
}
