//! From IDL declarations to NDR layouts: resolves every type of every method of the served
//! interfaces to the layout language of `src/proxy/ndr/layout.rs` (see there), with the counts'
//! correlations, the values a reply needs of its request, and the bound of every array a peer sizes.
//!
//! The rules are MIDL's for `[object]` interfaces (C706 chapter 14, MS-RPCE 2.2.5):
//!
//! - a parameter's outermost pointer is `[ref]` unless it says `[unique]`; every other pointer is
//!   `[unique]` (`pointer_default(unique)`) unless it or its typedef says `[ref]`; full pointers
//!   (`[ptr]`) are not supported;
//! - `size_is(a, b, ...)` / `length_is(...)` give, per pointer level from the outermost, the count of
//!   the array that pointer points to; an argument names a parameter (`dwCount`), the integer a `[ref]`
//!   parameter points to (`*pdwCount`), or, inside a structure, one of its integer fields;
//! - `[string]` (on the declaration or its typedef: LPWSTR, LPOLESTR...) makes the innermost pointer a
//!   pointer to a string of `wchar_t` (2 bytes) or `char` (1 byte);
//! - an interface name with its `*` is an interface pointer; `[iid_is(riid)]` names its IID by a
//!   parameter (REFIID or GUID);
//! - an `enum` is 16 bits on the wire unless its typedef says `[v1_enum]`;
//! - BSTR, VARIANT and LPSAFEARRAY are the `[wire_marshal]` types of oaidl.idl.

use std::collections::{BTreeMap, HashMap, HashSet};

use super::parse::{self, Attrs, Field, TypeSpec, Typedef};

/// The bound of an array whose count a peer chooses, when the bounds file names none.
pub const DEFAULT_BOUND: u32 = 65_536;
/// What the interpreter allows (src/proxy/ndr/mod.rs: MAX_SLOTS, MAX_FIELDS, CONTEXT_WORDS).
const MAX_SLOTS: usize = 16;
const MAX_FIELDS: usize = 32;
const CONTEXT_WORDS: usize = 8;
/// How deeply types may nest (the interpreter recurses once per level).
const MAX_DEPTH: usize = 24;

pub type Error = String;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Corr {
    Slot(u8),
    Field(u8),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Extent {
    Fixed(u32),
    Conformant(Corr),
}

#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Node {
    Base(u8),
    Enum16,
    Guid,
    Str(u8),
    Bstr,
    Variant,
    SafeArray,
    Empty,
    /// An interface pointer: the interface's name and IID (as NDR writes it), or the slot of `iid_is`.
    Interface(String, Option<[u8; 16]>, u8),
    Pointer(bool, Box<Node>),
    Struct(String),
    Union(Box<UnionNode>),
    Array(Box<ArrayNode>),
}

#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct UnionNode {
    pub name: String,
    pub switch: Corr,
    pub size: u8,
    pub arms: Vec<(u32, Node)>,
    pub default: Option<Node>,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ArrayNode {
    pub elem: Node,
    pub size: Extent,
    pub length: Option<Corr>,
    pub bound: u32,
}

#[derive(Clone, Debug)]
pub struct StructDef {
    pub name: String,
    pub align: u8,
    pub fields: Vec<(String, Node)>,
    pub deferred: bool,
    pub plain: u32,
    /// The flat part's size when fixed; 0 otherwise.
    pub size: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Save {
    None,
    Int(u8),
    Guid(u8),
}

#[derive(Clone, Debug)]
pub struct ParamOut {
    pub name: String,
    pub node: Node,
    pub save: Save,
}

#[derive(Clone, Debug)]
pub struct MethodOut {
    pub name: String,
    pub request: Vec<ParamOut>,
    pub reply: Vec<ParamOut>,
    pub bounds: Vec<(u8, u32)>,
    pub context: Vec<Save>,
    pub request_align8: bool,
    pub reply_align8: bool,
    /// The C parameters after `This`, in order: `i` a value of at most 4 bytes, `h` one of 8, `p` a
    /// pointer, `v` a VARIANT by value, `f` a structure of 8 bytes (4-byte aligned) by value (for the tests' generic calls, `tests/oop/ps_args.h`).
    pub args: String,
}

#[derive(Clone, Debug)]
pub struct InterfaceOut {
    pub name: String,
    pub uuid: String,
    pub iid: [u8; 16],
    pub vtable: u32,
    pub methods: Vec<MethodOut>,
    /// The specification it belongs to (the name its IDL file is served under).
    pub spec: String,
}

/// Where a caller-chosen count's bound comes from, for the generated file's table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BoundUse {
    /// `Interface.Method.parameter` or `Structure.field`.
    pub key: String,
    pub bound: u32,
    /// The bounds file's reason, or None for the default.
    pub reason: Option<String>,
}

#[derive(Debug, Default)]
pub struct Model {
    pub interfaces: Vec<InterfaceOut>,
    pub structs: BTreeMap<String, StructDef>,
    pub bounds: Vec<BoundUse>,
}

/// The bounds file: `key bound reason...` per line, `#` comments.
pub fn parse_bounds(path: &str, text: &str) -> Result<BTreeMap<String, (u32, String)>, Error> {
    let mut out = BTreeMap::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or_default();
        let bound = words
            .next()
            .and_then(|b| b.replace(',', "").parse::<u32>().ok())
            .ok_or(format!("{path}:{}: expected `key bound reason`", n + 1))?;
        let reason = words.collect::<Vec<_>>().join(" ");
        if reason.is_empty() {
            return Err(format!("{path}:{}: {key}: a bound needs its reason", n + 1));
        }
        if out.insert(key.to_string(), (bound, reason)).is_some() {
            return Err(format!("{path}:{}: {key} given twice", n + 1));
        }
    }
    Ok(out)
}

/// A GUID as text (`F31DFDE2-07B6-11d2-B2D8-0060083BA1FB`) as NDR writes it.
pub fn guid_bytes(text: &str) -> Option<[u8; 16]> {
    let hex: String = text.chars().filter(|c| *c != '-').collect();
    if hex.len() != 32 || text.split('-').map(str::len).collect::<Vec<_>>() != [8, 4, 4, 4, 12] {
        return None;
    }
    let v = u128::from_str_radix(&hex, 16).ok()?;
    let mut b = [0u8; 16];
    b[..4].copy_from_slice(&((v >> 96) as u32).to_le_bytes());
    b[4..6].copy_from_slice(&((v >> 80) as u16).to_le_bytes());
    b[6..8].copy_from_slice(&((v >> 64) as u16).to_le_bytes());
    b[8..].copy_from_slice(&(v as u64).to_be_bytes());
    Some(b)
}

/// System interfaces the served IDL may name without declaring them (their IIDs, from the SDK's IDL).
const SYSTEM_INTERFACES: &[(&str, &str)] = &[
    ("IUnknown", "00000000-0000-0000-C000-000000000046"),
    ("IDispatch", "00020400-0000-0000-C000-000000000046"),
    ("IEnumString", "00000101-0000-0000-C000-000000000046"),
    ("IEnumUnknown", "00000100-0000-0000-C000-000000000046"),
    ("IEnumGUID", "0002E000-0000-0000-C000-000000000046"),
];

/// What a named type is, before pointers.
#[derive(Clone, Debug)]
enum Leaf {
    Base(u8),
    /// A character: a string's element behind `[string]`, a base type otherwise.
    Char(u8),
    Enum16,
    Guid,
    Bstr,
    Variant,
    SafeArray,
    Void,
    Interface(String),
    Struct(String),
    Union(String),
}

/// One pointer level (or, for a parameter, an array declarator `[]` / `[N]`).
#[derive(Clone, Debug, Default)]
struct Level {
    /// `Some(true)` unique, `Some(false)` ref, None: the default.
    unique: Option<bool>,
    string: bool,
    /// An array declarator: `Some(None)` for `[]`, `Some(Some(n))` for `[n]`.
    dim: Option<Option<u32>>,
}

#[derive(Clone, Debug)]
struct Shape {
    leaf: Leaf,
    /// Outermost first.
    levels: Vec<Level>,
}

/// The types every file may use: typedefs and tags by name, enum constants, interfaces.
struct Env<'a> {
    typedefs: HashMap<String, (&'a Typedef, usize)>,
    tags: HashMap<String, (&'a TypeSpec, Attrs, String)>,
    enum_values: HashMap<String, i64>,
    interfaces: HashMap<String, &'a parse::Interface>,
}

fn base_type(name: &str) -> Option<Leaf> {
    Some(match name {
        "byte" | "BYTE" | "UCHAR" | "unsigned char" | "small" | "boolean" | "BOOLEAN" | "unsigned small" => {
            Leaf::Base(1)
        }
        "char" | "CHAR" | "signed char" => Leaf::Char(1),
        "short" | "SHORT" | "USHORT" | "WORD" | "unsigned short" | "signed short" | "VARIANT_BOOL" | "VARTYPE" => {
            Leaf::Base(2)
        }
        "wchar_t" | "WCHAR" | "OLECHAR" => Leaf::Char(2),
        "long" | "LONG" | "ULONG" | "DWORD" | "unsigned long" | "signed long" | "int" | "INT" | "UINT"
        | "unsigned int" | "signed int" | "long int" | "unsigned long int" | "BOOL" | "HRESULT" | "SCODE" | "LCID"
        | "float" | "FLOAT" | "error_status_t" => Leaf::Base(4),
        "hyper" | "LONGLONG" | "ULONGLONG" | "__int64" | "unsigned hyper" | "unsigned __int64" | "long long"
        | "unsigned long long" | "double" | "DOUBLE" | "DATE" | "CY" | "CURRENCY" => Leaf::Base(8),
        "GUID" | "IID" | "CLSID" | "CATID" | "UUID" => Leaf::Guid,
        "BSTR" => Leaf::Bstr,
        "VARIANT" | "VARIANTARG" => Leaf::Variant,
        "LPSAFEARRAY" => Leaf::SafeArray,
        "FILETIME" => Leaf::Struct("FILETIME".into()),
        "void" => Leaf::Void,
        _ => return None,
    })
}

/// The pointer typedefs of the system IDL files: (name, leaf, string).
fn system_pointer(name: &str) -> Option<Shape> {
    let one = |leaf, string, unique: Option<bool>| Shape {
        leaf,
        levels: vec![Level {
            unique,
            string,
            dim: None,
        }],
    };
    Some(match name {
        "LPWSTR" | "LPCWSTR" | "LPOLESTR" | "LPCOLESTR" => one(Leaf::Char(2), true, None),
        "LPSTR" | "LPCSTR" => one(Leaf::Char(1), true, None),
        "REFIID" | "REFCLSID" | "REFGUID" => one(Leaf::Guid, false, Some(false)),
        "LPCLSID" | "LPGUID" | "LPIID" => one(Leaf::Guid, false, None),
        "LPUNKNOWN" => one(Leaf::Interface("IUnknown".into()), false, None),
        "LPENUMSTRING" => one(Leaf::Interface("IEnumString".into()), false, None),
        "LPENUMUNKNOWN" => one(Leaf::Interface("IEnumUnknown".into()), false, None),
        "LPDISPATCH" => one(Leaf::Interface("IDispatch".into()), false, None),
        _ => return None,
    })
}

fn pointer_attr(attrs: &Attrs) -> Result<Option<bool>, Error> {
    if attrs.has("ptr") {
        return Err("full pointers ([ptr]) are not supported".into());
    }
    Ok(if attrs.has("unique") {
        Some(true)
    } else if attrs.has("ref") {
        Some(false)
    } else {
        None
    })
}

impl<'a> Env<'a> {
    fn new(files: &'a [parse::File]) -> Result<Self, Error> {
        let mut env = Env {
            typedefs: HashMap::new(),
            tags: HashMap::new(),
            enum_values: HashMap::new(),
            interfaces: HashMap::new(),
        };
        for f in files {
            let all = f
                .typedefs
                .iter()
                .chain(f.interfaces.iter().flat_map(|i| i.typedefs.iter()));
            for td in all {
                for (k, d) in td.names.iter().enumerate() {
                    env.typedefs.insert(d.name.clone(), (td, k));
                }
                let first = td.names.iter().find(|d| d.stars == 0).map(|d| d.name.clone());
                let (tag, values) = match &td.ty {
                    TypeSpec::Struct { tag, .. } | TypeSpec::Union { tag, .. } => (tag.clone(), None),
                    TypeSpec::Enum { tag, values } => (tag.clone(), Some(values)),
                    TypeSpec::Named(_) => (None, None),
                };
                if let Some(tag) = tag {
                    env.tags
                        .insert(tag.clone(), (&td.ty, td.attrs.clone(), first.unwrap_or(tag)));
                }
                for (name, v) in values.into_iter().flatten() {
                    env.enum_values.insert(name.clone(), *v);
                }
            }
            for i in &f.interfaces {
                env.interfaces.insert(i.name.clone(), i);
            }
        }
        Ok(env)
    }

    fn iid(&self, name: &str) -> Result<[u8; 16], Error> {
        let text = match self.interfaces.get(name) {
            Some(i) => i
                .attrs
                .args("uuid")
                .and_then(|a| a.first().cloned())
                .ok_or(format!("{name} has no uuid"))?,
            None => SYSTEM_INTERFACES
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, u)| u.to_string())
                .ok_or(format!("unknown interface {name}"))?,
        };
        guid_bytes(&text).ok_or(format!("{name}: bad uuid {text}"))
    }

    /// A type written as words.
    fn named(&self, words: &[String], depth: usize) -> Result<Shape, Error> {
        if depth > MAX_DEPTH {
            return Err(format!("typedefs of {} nest too deeply", words.join(" ")));
        }
        let name = words.join(" ");
        if let Some(td) = self.typedefs.get(&name) {
            return self.typedef(td.0, td.1, depth);
        }
        if let Some(leaf) = base_type(&name) {
            return Ok(Shape { leaf, levels: vec![] });
        }
        if let Some(shape) = system_pointer(&name) {
            return Ok(shape);
        }
        if let Some((spec, attrs, typedef_name)) = self.tags.get(&name) {
            return Ok(Shape {
                leaf: self.leaf_of_body(spec, attrs, typedef_name)?,
                levels: vec![],
            });
        }
        if self.interfaces.contains_key(&name) || SYSTEM_INTERFACES.iter().any(|(n, _)| *n == name) {
            return Ok(Shape {
                leaf: Leaf::Interface(name),
                levels: vec![],
            });
        }
        Err(format!("unknown type {name}"))
    }

    fn leaf_of_body(&self, spec: &TypeSpec, attrs: &Attrs, name: &str) -> Result<Leaf, Error> {
        Ok(match spec {
            TypeSpec::Struct { .. } => Leaf::Struct(name.to_string()),
            TypeSpec::Union { .. } => Leaf::Union(name.to_string()),
            TypeSpec::Enum { .. } if attrs.has("v1_enum") => Leaf::Base(4),
            TypeSpec::Enum { .. } => Leaf::Enum16,
            TypeSpec::Named(w) => return Err(format!("{} is not a type body", w.join(" "))),
        })
    }

    fn typedef(&self, td: &Typedef, k: usize, depth: usize) -> Result<Shape, Error> {
        let decl = &td.names[k];
        if !decl.dims.is_empty() {
            return Err(format!("typedef {}: array typedefs are not supported", decl.name));
        }
        let mut shape = match &td.ty {
            TypeSpec::Named(words) => self.named(words, depth + 1)?,
            body => {
                let first = td
                    .names
                    .iter()
                    .find(|d| d.stars == 0)
                    .map_or(decl.name.clone(), |d| d.name.clone());
                Shape {
                    leaf: self.leaf_of_body(body, &td.attrs, &first)?,
                    levels: vec![],
                }
            }
        };
        if td.attrs.has("wire_marshal") || td.attrs.has("user_marshal") || td.attrs.has("transmit_as") {
            return Err(format!(
                "typedef {}: [wire_marshal] types other than oaidl's are not supported",
                decl.name
            ));
        }
        let mut own: Vec<Level> = (0..decl.stars).map(|_| Level::default()).collect();
        if let Some(first) = own.first_mut() {
            first.unique = pointer_attr(&td.attrs)?;
        }
        if td.attrs.has("string") {
            match own.last_mut() {
                Some(l) => l.string = true,
                None => return Err(format!("typedef {}: [string] without a pointer", decl.name)),
            }
        }
        own.append(&mut shape.levels);
        shape.levels = own;
        Ok(shape)
    }
}

/// Whether an interface pointer sits in an array or union (where it would be embedded): only a
/// parameter, or the pointee of a parameter's pointers, can be one.
fn interface_in_construct(n: &Node, inside: bool) -> bool {
    match n {
        Node::Interface(..) => inside,
        Node::Pointer(_, t) => interface_in_construct(t, inside),
        Node::Array(a) => interface_in_construct(&a.elem, true),
        Node::Union(u) => u
            .arms
            .iter()
            .map(|(_, a)| a)
            .chain(&u.default)
            .any(|a| interface_in_construct(a, true)),
        _ => false,
    }
}

/// A correlation argument: `name` or `*name`.
fn corr_name(arg: &str) -> Result<(bool, String), Error> {
    let arg = arg.trim();
    let (deref, name) = match arg.strip_prefix('*') {
        Some(rest) => (true, rest.trim()),
        None => (false, arg),
    };
    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(format!(
            "the count `{arg}` is not supported: name a parameter, *parameter or field"
        ));
    }
    Ok((deref, name.to_string()))
}

/// The attributes whose arguments name counts or IIDs.
const CORRELATION_ATTRS: [&str; 4] = ["size_is", "length_is", "switch_is", "iid_is"];

/// Where a declaration's counts are looked up.
enum Scope<'s> {
    /// A method's parameters: name → (slot, whether it is read by dereferencing).
    Params(&'s HashMap<String, u8>),
    /// A structure's fields: name → index.
    Fields(&'s HashMap<String, u8>),
}

/// Builds layouts; remembers the structures and the bounds it used.
struct Builder<'a> {
    env: Env<'a>,
    bounds_file: &'a BTreeMap<String, (u32, String)>,
    bounds_used: HashSet<String>,
    structs: BTreeMap<String, StructDef>,
    in_progress: HashSet<String>,
    bound_uses: Vec<BoundUse>,
    /// Whether every array a peer sizes must be named in the bounds file (the served IDL: each
    /// bound is a decision with its reason); the arrays it does not name.
    require_bounds: bool,
    unnamed: Vec<String>,
}

impl Builder<'_> {
    fn bound(&mut self, key: &str) -> u32 {
        let (bound, reason) = match self.bounds_file.get(key) {
            Some((b, r)) => {
                self.bounds_used.insert(key.to_string());
                (*b, Some(r.clone()))
            }
            None => {
                if self.require_bounds && !self.unnamed.iter().any(|k| k == key) {
                    self.unnamed.push(key.to_string());
                }
                (DEFAULT_BOUND, None)
            }
        };
        let use_ = BoundUse {
            key: key.to_string(),
            bound,
            reason,
        };
        if !self.bound_uses.contains(&use_) {
            self.bound_uses.push(use_);
        }
        bound
    }

    fn corr(&self, arg: &str, scope: &Scope) -> Result<Corr, Error> {
        let (_, name) = corr_name(arg)?;
        match scope {
            Scope::Params(slots) => slots
                .get(&name)
                .map(|s| Corr::Slot(*s))
                .ok_or(format!("`{arg}` names no parameter")),
            Scope::Fields(fields) => fields
                .get(&name)
                .map(|i| Corr::Field(*i))
                .ok_or(format!("`{arg}` names no field of the structure")),
        }
    }

    /// The layout of a declaration. `top`: a parameter (its outermost pointer is `[ref]` by default
    /// and its array declarators are pointers); `key` names it for the bounds file.
    fn declaration(&mut self, f: &Field, top: bool, scope: &Scope, key: &str) -> Result<Node, Error> {
        for a in &f.attrs.0 {
            if matches!(
                a.name.as_str(),
                "max_is" | "min_is" | "first_is" | "last_is" | "range" | "ptr" | "ignore" | "call_as"
            ) {
                return Err(format!("{key}: [{}] is not supported", a.name));
            }
        }
        let TypeSpec::Named(words) = &f.ty else {
            return Err(format!("{key}: declare the structure, union or enum with a typedef"));
        };
        let base = self.env.named(words, 0).map_err(|e| format!("{key}: {e}"))?;
        let mut levels: Vec<Level> = Vec::new();
        let mut inline_dims = Vec::new();
        for d in &f.decl.dims {
            let n = match d {
                Some(text) => Some(
                    parse::parse_int(text)
                        .filter(|n| *n > 0 && *n <= i64::from(u32::MAX))
                        .ok_or(format!("{key}: array dimension {text}"))? as u32,
                ),
                None => None,
            };
            if top {
                levels.push(Level {
                    unique: Some(false),
                    string: false,
                    dim: Some(n),
                });
            } else {
                inline_dims.push(n.ok_or(format!(
                    "{key}: conformant arrays inside structures are not supported; use a [size_is] pointer"
                ))?);
            }
        }
        levels.extend((0..f.decl.stars).map(|_| Level::default()));
        levels.extend(base.levels);
        let mut leaf = base.leaf;
        if let Some(first) = levels.first_mut() {
            if let Some(u) = pointer_attr(&f.attrs)? {
                first.unique = Some(u);
            }
        } else if pointer_attr(&f.attrs)?.is_some() {
            return Err(format!("{key}: [unique]/[ref] on something that is not a pointer"));
        }
        if f.attrs.has("string") {
            match levels.last_mut() {
                Some(l) => l.string = true,
                None => return Err(format!("{key}: [string] without a pointer")),
            }
        }
        // An interface pointer's own `*`, or `void *` with iid_is.
        let iid_is = f.attrs.args("iid_is").map(|a| a.to_vec());
        if matches!(leaf, Leaf::Interface(_)) || (matches!(leaf, Leaf::Void) && iid_is.is_some()) {
            if levels.pop().is_none() {
                return Err(format!("{key}: an interface is passed by pointer"));
            }
            if matches!(leaf, Leaf::Void) {
                leaf = Leaf::Interface("IUnknown".into());
            }
        } else if iid_is.is_some() {
            return Err(format!("{key}: [iid_is] on something that is not an interface pointer"));
        }
        let per_level = |name: &str| -> Vec<String> { f.attrs.args(name).map(|a| a.to_vec()).unwrap_or_default() };
        let sizes = per_level("size_is");
        let lengths = per_level("length_is");
        if sizes.len() > levels.len() || lengths.len() > levels.len() {
            return Err(format!("{key}: more counts than pointer levels"));
        }
        let mut node = self.leaf_node(&leaf, f, scope, key, iid_is.as_deref())?;
        for i in (0..levels.len()).rev() {
            let l = &levels[i];
            let size = sizes.get(i).filter(|s| !s.is_empty());
            let length = lengths.get(i).filter(|s| !s.is_empty());
            if l.string {
                if i != levels.len() - 1 {
                    return Err(format!("{key}: [string] on a pointer to a pointer"));
                }
                let Leaf::Char(unit) = leaf else {
                    return Err(format!(
                        "{key}: [string] on a pointer to something other than characters"
                    ));
                };
                if size.is_some() || length.is_some() {
                    return Err(format!("{key}: sized strings are not supported"));
                }
                node = Node::Str(unit);
            } else if size.is_some() || length.is_some() || l.dim.is_some() {
                let extent = match (l.dim, size) {
                    (Some(Some(_)), Some(_)) => return Err(format!("{key}: [size_is] on a fixed array")),
                    (Some(Some(n)), None) => Extent::Fixed(n),
                    (_, Some(s)) => Extent::Conformant(self.corr(s, scope).map_err(|e| format!("{key}: {e}"))?),
                    (_, None) => return Err(format!("{key}: an array without [size_is]")),
                };
                let length = length
                    .map(|s| self.corr(s, scope))
                    .transpose()
                    .map_err(|e| format!("{key}: {e}"))?;
                let bound = match extent {
                    Extent::Fixed(n) => n,
                    Extent::Conformant(_) => self.bound(key),
                };
                node = Node::Array(Box::new(ArrayNode {
                    elem: node,
                    size: extent,
                    length,
                    bound,
                }));
            }
            let unique = match l.unique {
                Some(u) => u,
                None => !(top && i == 0),
            };
            if l.dim.is_some() && unique {
                return Err(format!("{key}: an array parameter cannot be [unique]"));
            }
            node = Node::Pointer(unique, Box::new(node));
        }
        for n in inline_dims.into_iter().rev() {
            node = Node::Array(Box::new(ArrayNode {
                elem: node,
                size: Extent::Fixed(n),
                length: None,
                bound: n,
            }));
        }
        if !top && matches!(node, Node::Interface(..)) {
            return Err(format!("{key}: interface pointers inside structures are not supported"));
        }
        if interface_in_construct(&node, false) {
            return Err(format!("{key}: arrays of interface pointers are not supported"));
        }
        Ok(node)
    }

    fn leaf_node(
        &mut self,
        leaf: &Leaf,
        f: &Field,
        scope: &Scope,
        key: &str,
        iid_is: Option<&[String]>,
    ) -> Result<Node, Error> {
        if f.attrs.has("switch_is") && !matches!(leaf, Leaf::Union(_)) {
            return Err(format!("{key}: [switch_is] on something that is not a union"));
        }
        Ok(match leaf {
            Leaf::Base(n) | Leaf::Char(n) => Node::Base(*n),
            Leaf::Enum16 => Node::Enum16,
            Leaf::Guid => Node::Guid,
            Leaf::Bstr => Node::Bstr,
            Leaf::Variant => Node::Variant,
            Leaf::SafeArray => Node::SafeArray,
            Leaf::Void => return Err(format!("{key}: void without [iid_is]")),
            Leaf::Interface(name) => match iid_is {
                Some([arg]) => {
                    let Corr::Slot(s) = self.corr(arg, scope).map_err(|e| format!("{key}: {e}"))? else {
                        return Err(format!("{key}: [iid_is] names a field"));
                    };
                    Node::Interface(name.clone(), None, s)
                }
                Some(_) => return Err(format!("{key}: [iid_is] takes one argument")),
                None => Node::Interface(name.clone(), Some(self.env.iid(name)?), 0),
            },
            Leaf::Struct(name) => {
                self.structure(name)?;
                Node::Struct(name.clone())
            }
            Leaf::Union(name) => {
                let arg = f
                    .attrs
                    .args("switch_is")
                    .and_then(|a| a.first())
                    .ok_or(format!("{key}: a union needs [switch_is]"))?;
                let switch = self.corr(arg, scope).map_err(|e| format!("{key}: {e}"))?;
                Node::Union(Box::new(self.union(name, switch, &f.attrs, key)?))
            }
        })
    }

    fn union(&mut self, name: &str, switch: Corr, use_attrs: &Attrs, key: &str) -> Result<UnionNode, Error> {
        let (spec, attrs, _) = self
            .env
            .tags
            .values()
            .find(|(_, _, n)| n == name)
            .cloned()
            .or_else(|| {
                self.env
                    .typedefs
                    .get(name)
                    .map(|(td, _)| (&td.ty, td.attrs.clone(), name.to_string()))
            })
            .ok_or(format!("{key}: unknown union {name}"))?;
        let TypeSpec::Union { arms, .. } = spec else {
            return Err(format!("{key}: {name} is not a union"));
        };
        let switch_type = attrs
            .args("switch_type")
            .or(use_attrs.args("switch_type"))
            .and_then(|a| a.first().cloned())
            .ok_or(format!("{key}: union {name} needs [switch_type]"))?;
        let words: Vec<String> = switch_type.split_whitespace().map(str::to_string).collect();
        let size = match self.env.named(&words, 0)?.leaf {
            Leaf::Base(n) | Leaf::Char(n) if n <= 4 => n,
            Leaf::Enum16 => 2,
            _ => return Err(format!("{key}: union {name}: switch_type {switch_type}")),
        };
        let mask = if size == 4 { u32::MAX } else { (1u32 << (8 * size)) - 1 };
        let empty = HashMap::new();
        let mut out = UnionNode {
            name: name.to_string(),
            switch,
            size,
            arms: Vec::new(),
            default: None,
        };
        for arm in arms {
            let node = match &arm.field {
                Some(field) => {
                    if CORRELATION_ATTRS.iter().any(|a| field.attrs.has(a)) {
                        return Err(format!(
                            "{key}: union {name}: counts inside union arms are not supported"
                        ));
                    }
                    self.declaration(
                        field,
                        false,
                        &Scope::Fields(&empty),
                        &format!("{name}.{}", field.decl.name),
                    )?
                }
                None => Node::Empty,
            };
            if arm.cases.is_empty() {
                if out.default.replace(node).is_some() {
                    return Err(format!("{key}: union {name}: two [default] arms"));
                }
                continue;
            }
            for case in &arm.cases {
                let v = parse::parse_int(case)
                    .or_else(|| self.env.enum_values.get(case.trim()).copied())
                    .ok_or(format!("{key}: union {name}: case {case}"))?;
                let v = (v as u32) & mask;
                if out.arms.iter().any(|(c, _)| *c == v) {
                    return Err(format!("{key}: union {name}: case {case} twice"));
                }
                out.arms.push((v, node.clone()));
            }
        }
        Ok(out)
    }

    /// The structure `name`, resolved once.
    fn structure(&mut self, name: &str) -> Result<(), Error> {
        if self.structs.contains_key(name) {
            return Ok(());
        }
        if name == "FILETIME" {
            self.structs.insert(
                name.into(),
                StructDef {
                    name: name.into(),
                    align: 4,
                    fields: vec![
                        ("dwLowDateTime".into(), Node::Base(4)),
                        ("dwHighDateTime".into(), Node::Base(4)),
                    ],
                    deferred: false,
                    plain: 8,
                    size: 8,
                },
            );
            return Ok(());
        }
        if !self.in_progress.insert(name.to_string()) {
            return Err(format!(
                "structure {name} contains itself: recursive types are not supported"
            ));
        }
        let spec = self
            .env
            .typedefs
            .get(name)
            .map(|(td, _)| &td.ty)
            .or_else(|| self.env.tags.get(name).map(|t| t.0))
            .ok_or(format!("unknown structure {name}"))?;
        let TypeSpec::Struct { fields, .. } = spec else {
            return Err(format!("{name} is not a structure"));
        };
        if fields.len() > MAX_FIELDS {
            return Err(format!("structure {name}: more than {MAX_FIELDS} fields"));
        }
        if fields.is_empty() {
            return Err(format!("structure {name} has no field"));
        }
        let index: HashMap<String, u8> = fields
            .iter()
            .enumerate()
            .map(|(i, f)| (f.decl.name.clone(), i as u8))
            .collect();
        let mut out = Vec::new();
        for (i, f) in fields.iter().enumerate() {
            let key = format!("{name}.{}", f.decl.name);
            let node = self.declaration(f, false, &Scope::Fields(&index), &key)?;
            out.push((f.decl.name.clone(), node));
            // Inline unions and arrays read their counts as they go: those must come first.
            for arg in ["switch_is", "length_is"]
                .iter()
                .filter_map(|a| f.attrs.args(a))
                .flatten()
            {
                if let Ok((_, n)) = corr_name(arg) {
                    if index.get(&n).is_some_and(|&j| usize::from(j) >= i) && !matches!(out[i].1, Node::Pointer(..)) {
                        return Err(format!("{key}: its count {n} must come before it"));
                    }
                }
            }
        }
        // Fields that counts name must be integers.
        for f in fields {
            for arg in CORRELATION_ATTRS.iter().filter_map(|a| f.attrs.args(a)).flatten() {
                if arg.is_empty() {
                    continue;
                }
                let (deref, n) = corr_name(arg)?;
                let j = usize::from(index[&n]);
                if deref || !matches!(out[j].1, Node::Base(1 | 2 | 4) | Node::Enum16) {
                    return Err(format!(
                        "{name}.{}: its count {arg} must be an integer field",
                        f.decl.name
                    ));
                }
            }
        }
        self.in_progress.remove(name);
        // A VARIANT field makes the structure 8-aligned on the wire, though its own place in the flat
        // part is a 4-byte pointer: the format strings' FC_BOGUS_STRUCT of such a structure (widl's and
        // MIDL's, Win32 and Win64) carry VARIANT's memory alignment, and the engine aligns each
        // structure to it (an array of OPCITEMSTATE has 24-byte elements).
        let align = out
            .iter()
            .map(|(_, n)| match n {
                Node::Variant => 8,
                n => self.align(n),
            })
            .max()
            .unwrap_or(1);
        let deferred = out.iter().any(|(_, n)| self.deferred(n));
        let plain = self.plain_struct(&out, align);
        let size = self.flat_size(&out).unwrap_or(0);
        self.structs.insert(
            name.to_string(),
            StructDef {
                name: name.to_string(),
                align,
                fields: out,
                deferred,
                plain,
                size,
            },
        );
        Ok(())
    }

    /// The size of a flat part of these fields from an aligned start, when it is fixed.
    fn flat_size(&self, fields: &[(String, Node)]) -> Option<u32> {
        let mut size = 0u32;
        for (_, n) in fields {
            let s = self.fixed(n)?;
            let a = u32::from(self.align(n));
            size = size.div_ceil(a) * a + s;
        }
        Some(size)
    }

    /// The size of a value in a flat part, when it is fixed.
    fn fixed(&self, n: &Node) -> Option<u32> {
        match n {
            Node::Base(s) => Some(u32::from(*s)),
            Node::Enum16 => Some(2),
            Node::Guid => Some(16),
            Node::Pointer(..) | Node::Bstr | Node::Variant | Node::SafeArray => Some(4),
            Node::Empty => Some(0),
            Node::Struct(name) => self.structs.get(name).map(|s| s.size).filter(|s| *s != 0),
            Node::Array(a) => match (a.size, &a.length) {
                (Extent::Fixed(count), None) => {
                    let s = self.fixed(&a.elem)?;
                    let a = u32::from(self.align(&a.elem));
                    let stride = s.div_ceil(a) * a;
                    count
                        .checked_sub(1)
                        .map_or(Some(0), |n| n.checked_mul(stride)?.checked_add(s))
                }
                _ => None,
            },
            _ => None,
        }
    }

    /// The NDR size of a structure of plain fields with no padding at its end; 0 otherwise.
    fn plain_struct(&self, fields: &[(String, Node)], align: u8) -> u32 {
        let mut size = 0u32;
        for (_, n) in fields {
            let Some(s) = self.plain(n) else { return 0 };
            let a = u32::from(self.align(n));
            size = size.div_ceil(a) * a + s;
        }
        if size.is_multiple_of(u32::from(align)) {
            size
        } else {
            0
        }
    }

    /// The size of a value skipped without a look: base types, GUIDs, plain structures and fixed
    /// arrays of them (whose size is a multiple of their alignment).
    pub fn plain(&self, n: &Node) -> Option<u32> {
        match n {
            Node::Base(s) => Some(u32::from(*s)),
            Node::Guid => Some(16),
            Node::Struct(name) => self.structs.get(name).map(|s| s.plain).filter(|p| *p != 0),
            Node::Array(a) => match (a.size, &a.length) {
                (Extent::Fixed(count), None) => {
                    let s = self.plain(&a.elem)?;
                    s.is_multiple_of(u32::from(self.align(&a.elem)))
                        .then_some(s.checked_mul(count)?)
                }
                _ => None,
            },
            _ => None,
        }
    }

    pub fn align(&self, n: &Node) -> u8 {
        match n {
            Node::Base(s) => *s,
            Node::Enum16 => 2,
            Node::Empty => 1,
            Node::Struct(name) => self.structs.get(name).map_or(4, |s| s.align),
            Node::Union(u) => u
                .arms
                .iter()
                .map(|(_, a)| a)
                .chain(&u.default)
                .map(|a| self.align(a))
                .max()
                .unwrap_or(1)
                .max(u.size),
            Node::Array(a) => {
                let e = self.align(&a.elem);
                if matches!(a.size, Extent::Conformant(_)) || a.length.is_some() {
                    e.max(4)
                } else {
                    e
                }
            }
            _ => 4,
        }
    }

    pub fn deferred(&self, n: &Node) -> bool {
        match n {
            Node::Pointer(..) | Node::Bstr | Node::Variant | Node::SafeArray => true,
            Node::Struct(name) => self.structs.get(name).is_some_and(|s| s.deferred),
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

    /// Whether the NDR engine aligns something in this value to 8 bytes.
    fn align8(&self, n: &Node) -> bool {
        match n {
            Node::Base(8) | Node::Bstr | Node::Variant | Node::SafeArray => true,
            Node::Pointer(_, t) => self.align8(t),
            Node::Struct(name) => self
                .structs
                .get(name)
                .is_some_and(|s| s.fields.iter().any(|(_, f)| self.align8(f))),
            Node::Array(a) => self.align8(&a.elem),
            Node::Union(u) => u.arms.iter().map(|(_, a)| a).chain(&u.default).any(|a| self.align8(a)),
            _ => false,
        }
    }

    fn depth(&self, n: &Node) -> usize {
        1 + match n {
            Node::Pointer(_, t) => self.depth(t),
            Node::Struct(name) => self
                .structs
                .get(name)
                .map_or(0, |s| s.fields.iter().map(|(_, f)| self.depth(f)).max().unwrap_or(0)),
            Node::Array(a) => self.depth(&a.elem),
            Node::Union(u) => u
                .arms
                .iter()
                .map(|(_, a)| a)
                .chain(&u.default)
                .map(|a| self.depth(a))
                .max()
                .unwrap_or(0),
            _ => 0,
        }
    }

    /// Every `Corr::Slot` a layout uses, with whether it sizes an array (and the array's bound).
    fn slots_used(&self, n: &Node, out: &mut Vec<(u8, Option<u32>)>) {
        match n {
            Node::Interface(_, None, s) => out.push((*s, None)),
            Node::Pointer(_, t) => self.slots_used(t, out),
            Node::Array(a) => {
                if let Extent::Conformant(Corr::Slot(s)) = a.size {
                    out.push((s, Some(a.bound)));
                }
                if let Some(Corr::Slot(s)) = a.length {
                    out.push((s, None));
                }
                self.slots_used(&a.elem, out);
            }
            Node::Union(u) => {
                if let Corr::Slot(s) = u.switch {
                    out.push((s, None));
                }
                for a in u.arms.iter().map(|(_, a)| a).chain(&u.default) {
                    self.slots_used(a, out);
                }
            }
            _ => {}
        }
    }

    /// A value a count or `iid_is` names: an integer (a GUID for `iid_is`) behind `[ref]` pointers
    /// only, named `*p` when it is behind one and `p` when not.
    fn check_saved(&self, m: &parse::Method, p: &Field, node: &Node, save: Save, pkey: &str) -> Result<(), Error> {
        let mut n = node;
        let mut pointers = 0;
        while let Node::Pointer(false, t) = n {
            n = t;
            pointers += 1;
        }
        let ok = match save {
            Save::Int(_) => matches!(n, Node::Base(1 | 2 | 4) | Node::Enum16) && pointers <= 1,
            Save::Guid(_) => matches!(n, Node::Guid),
            Save::None => true,
        };
        if !ok {
            return Err(format!(
                "{pkey}: a count must be an integer or *pointer to one, an IID a GUID (REFIID), behind [ref] pointers"
            ));
        }
        for a in ["size_is", "length_is", "switch_is"] {
            for arg in m.params.iter().filter_map(|q| q.attrs.args(a)).flatten() {
                if let Ok((deref, name)) = corr_name(arg) {
                    if name == p.decl.name && deref != (pointers == 1) {
                        return Err(format!(
                            "{pkey}: `{arg}` must be `{}{name}`",
                            if pointers == 1 { "*" } else { "" }
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    fn method(&mut self, iface: &str, m: &parse::Method) -> Result<MethodOut, Error> {
        let key = format!("{iface}.{}", m.name);
        if m.ret != "HRESULT" {
            return Err(format!("{key}: returns {}; remoted methods return HRESULT", m.ret));
        }
        for a in ["local", "call_as", "async", "callback"] {
            if m.attrs.has(a) {
                return Err(format!("{key}: [{a}] methods are not supported"));
            }
        }
        // The parameters counts and IIDs name get slots, in order.
        let mut named: HashMap<String, bool> = HashMap::new();
        for p in &m.params {
            for a in CORRELATION_ATTRS {
                for arg in p.attrs.args(a).unwrap_or_default() {
                    if !arg.is_empty() {
                        let (_, name) = corr_name(arg).map_err(|e| format!("{key}.{}: {e}", p.decl.name))?;
                        named.insert(name, a == "iid_is");
                    }
                }
            }
        }
        let mut slots: HashMap<String, u8> = HashMap::new();
        let mut saves: Vec<Save> = Vec::new();
        let mut next = 0usize;
        for p in &m.params {
            let save = match named.get(&p.decl.name) {
                None => Save::None,
                Some(&guid) => {
                    let s = next as u8;
                    next += if guid { 4 } else { 1 };
                    slots.insert(p.decl.name.clone(), s);
                    if guid {
                        Save::Guid(s)
                    } else {
                        Save::Int(s)
                    }
                }
            };
            saves.push(save);
        }
        if next > MAX_SLOTS {
            return Err(format!("{key}: more than {MAX_SLOTS} slots of counts and IIDs"));
        }
        for name in named.keys() {
            if !slots.contains_key(name) {
                return Err(format!("{key}: `{name}` names no parameter"));
            }
        }
        // The IID an interface pointer names is read before it.
        for (i, p) in m.params.iter().enumerate() {
            for arg in p.attrs.args("iid_is").unwrap_or_default() {
                let (_, name) = corr_name(arg)?;
                if m.params
                    .iter()
                    .position(|q| q.decl.name == name)
                    .is_some_and(|j| j >= i)
                {
                    return Err(format!(
                        "{key}.{}: [iid_is({name})] names a later parameter",
                        p.decl.name
                    ));
                }
            }
        }
        let scope = Scope::Params(&slots);
        let slot_of = |s: &Save| match s {
            Save::Int(x) | Save::Guid(x) => Some(*x),
            Save::None => None,
        };
        let direction = |p: &Field| (p.attrs.has("in") || !p.attrs.has("out"), p.attrs.has("out"));
        // Per slot: its parameter's direction and what it keeps.
        let mut slot_dir: HashMap<u8, ((bool, bool), Save)> = HashMap::new();
        for (p, save) in m.params.iter().zip(&saves) {
            if let Some(s) = slot_of(save) {
                slot_dir.insert(s, (direction(p), *save));
            }
        }
        let mut request = Vec::new();
        let mut reply = Vec::new();
        let mut args = String::new();
        // (slot, bound of the array it sizes) per use in the reply's parameters.
        let mut reply_uses: Vec<(u8, Option<u32>, bool)> = Vec::new();
        for (p, save) in m.params.iter().zip(&saves) {
            let pkey = format!("{key}.{}", p.decl.name);
            let node = self.declaration(p, true, &scope, &pkey)?;
            if self.depth(&node) > MAX_DEPTH {
                return Err(format!("{pkey}: types nest too deeply"));
            }
            if *save != Save::None {
                self.check_saved(m, p, &node, *save, &pkey)?;
            }
            args.push(match &node {
                Node::Pointer(..) | Node::Interface(..) | Node::Bstr | Node::SafeArray | Node::Str(_) => 'p',
                Node::Variant => 'v',
                Node::Base(8) => 'h',
                // A structure of 8 bytes by value (HDA's FILETIME intervals): one slot on x64, two
                // on x86.
                Node::Struct(name) if self.structs.get(name).is_some_and(|s| s.size == 8 && s.align <= 4) => 'f',
                Node::Struct(name) => return Err(format!("{pkey}: a structure {name} by value is not supported")),
                _ => 'i',
            });
            let (dir_in, dir_out) = direction(p);
            if dir_out && !matches!(node, Node::Pointer(..)) {
                return Err(format!("{pkey}: an [out] parameter must be a pointer"));
            }
            let mut used = Vec::new();
            self.slots_used(&node, &mut used);
            if dir_in {
                for (s, _) in &used {
                    if !slot_dir.get(s).is_some_and(|((i, _), _)| *i) {
                        return Err(format!("{pkey}: a count of the request names an [out]-only parameter"));
                    }
                }
                request.push(ParamOut {
                    name: p.decl.name.clone(),
                    node: node.clone(),
                    save: *save,
                });
            }
            if dir_out {
                reply_uses.extend(used.iter().map(|(s, b)| (*s, *b, dir_in)));
                reply.push(ParamOut {
                    name: p.decl.name.clone(),
                    node,
                    save: *save,
                });
            }
        }
        reply.push(ParamOut {
            name: "HRESULT".into(),
            node: Node::Base(4),
            save: Save::None,
        });
        // What the reply needs of the request ([in]-only values its counts and IIDs name, in order),
        // and the request's values that size an [out]-only array (bounded as soon as they are read).
        let mut context = Vec::new();
        let mut bounds: BTreeMap<u8, u32> = BTreeMap::new();
        let mut in_only: Vec<(u8, Save)> = slot_dir
            .iter()
            .filter(|(_, ((i, o), _))| *i && !*o)
            .map(|(s, (_, save))| (*s, *save))
            .collect();
        in_only.sort_by_key(|(s, _)| *s);
        for (s, save) in &in_only {
            if reply_uses.iter().any(|(u, _, _)| u == s) {
                context.push(*save);
            }
            for (u, bound, also_in) in &reply_uses {
                if let (true, Some(b), false) = (u == s, bound, also_in) {
                    let e = bounds.entry(*s).or_insert(*b);
                    *e = (*e).min(*b);
                }
            }
        }
        let words: usize = context
            .iter()
            .map(|s| if matches!(s, Save::Guid(_)) { 4 } else { 1 })
            .sum();
        if words > CONTEXT_WORDS {
            return Err(format!(
                "{key}: the reply needs more than {CONTEXT_WORDS} words of its request"
            ));
        }
        let request_align8 = request.iter().any(|p| self.align8(&p.node));
        let reply_align8 = reply.iter().any(|p| self.align8(&p.node));
        Ok(MethodOut {
            name: m.name.clone(),
            request,
            reply,
            bounds: bounds.into_iter().collect(),
            context,
            request_align8,
            reply_align8,
            args,
        })
    }
}

/// The layouts of every interface of `served` (in order: each IDL file with the name of its
/// specification), with `env` the files whose types and interfaces they may name (`served`
/// included). With `require_bounds`, an array a peer sizes that the bounds file does not name is an
/// error (all of them listed), not the default.
pub fn model(
    env_files: &[parse::File],
    served: &[(&str, &str)],
    bounds_file: &BTreeMap<String, (u32, String)>,
    require_bounds: bool,
) -> Result<Model, Error> {
    let mut b = Builder {
        env: Env::new(env_files)?,
        bounds_file,
        bounds_used: HashSet::new(),
        structs: BTreeMap::new(),
        in_progress: HashSet::new(),
        bound_uses: Vec::new(),
        require_bounds,
        unnamed: Vec::new(),
    };
    let mut interfaces = Vec::new();
    for (path, spec) in served {
        let file = env_files
            .iter()
            .find(|f| f.path == *path)
            .ok_or(format!("{path} was not read"))?;
        for i in &file.interfaces {
            if i.attrs.has("local") {
                continue;
            }
            if !i.attrs.has("object") {
                return Err(format!("{}: only [object] interfaces are served", i.name));
            }
            // The vtable: IUnknown's three methods, then each base's, then its own.
            let mut chain = vec![i];
            let mut base = i.base.clone();
            while let Some(name) = base {
                if name == "IUnknown" {
                    break;
                }
                let parent = b
                    .env
                    .interfaces
                    .get(&name)
                    .copied()
                    .ok_or(format!("{}: base interface {name} is not declared", i.name))?;
                chain.push(parent);
                base = parent.base.clone();
            }
            if i.base.is_none() {
                return Err(format!("{}: an [object] interface derives from IUnknown", i.name));
            }
            let mut methods = Vec::new();
            for owner in chain.iter().rev() {
                for m in &owner.methods {
                    methods.push(b.method(&owner.name, m).map_err(|e| format!("{path}: {e}"))?);
                }
            }
            let uuid = i
                .attrs
                .args("uuid")
                .and_then(|a| a.first().cloned())
                .ok_or(format!("{} has no uuid", i.name))?;
            interfaces.push(InterfaceOut {
                name: i.name.clone(),
                iid: guid_bytes(&uuid).ok_or(format!("{}: bad uuid", i.name))?,
                uuid,
                vtable: 3 + methods.len() as u32,
                methods,
                spec: spec.to_string(),
            });
        }
    }
    if !b.unnamed.is_empty() {
        b.unnamed.sort();
        return Err(format!(
            "the bounds file names no bound (with its reason) for these arrays a peer sizes: {}",
            b.unnamed.join(", ")
        ));
    }
    for key in bounds_file.keys() {
        if !b.bounds_used.contains(key) {
            return Err(format!(
                "the bounds file names {key}, which sizes no array a peer chooses"
            ));
        }
    }
    Ok(Model {
        interfaces,
        structs: b.structs,
        bounds: b.bound_uses,
    })
}
