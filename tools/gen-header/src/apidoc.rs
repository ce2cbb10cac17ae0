//! The header's documentation as the C API reference reads it (Doxygen, docs/reference/Doxyfile): one
//! pass over the generated header that
//!
//! - turns the doc comments' Markdown sections into Doxygen's commands: `# Parameters`, a list of
//!   `` - `name`: text `` (`` - `name` (out): text ``, `(in, out)`; continuation lines indented), into
//!   `@param` lines; `# Returns` into `@return`; any other heading (`# Safety`) into a titled paragraph
//!   (`@par Safety`; a Markdown heading would be a section of the whole page). The Rust sources and
//!   the IDL keep the Markdown form, which rustdoc renders as it is;
//! - checks that every function, callback type and interface method documents each of its parameters,
//!   in the order of its declaration, and its result unless it returns `void`; an interface method's
//!   direction comes from the IDL's `[in]`/`[out]` (a `(out)` in its documentation must agree), and
//!   the C form's `This` is documented here;
//! - links names: a function named in backticks or bare (`` `OpcTaskMemFree` ``, OpcTaskMemFree)
//!   becomes `OpcTaskMemFree()`, a macro, typedef, callback type, enum value or identifier in backticks
//!   `::NAME`, a structure or interface in backticks its bare name, `` `Struct::field` `` the bare
//!   `Struct::field`: the forms Doxygen links, where backticks would make plain code;
//! - puts every declaration at the top level into its area (`@ingroup`, from [`crate::groups`]).

use std::collections::BTreeSet;

/// What a documentation block documents.
#[derive(Debug, Clone, PartialEq)]
enum Decl {
    /// The file's own block (`@file`), or one the pass cannot attribute (a comment before nothing).
    Other,
    Function {
        name: String,
        params: Vec<Param>,
        returns: bool,
    },
    Callback {
        name: String,
        params: Vec<Param>,
        returns: bool,
    },
    /// An interface method: a C vtable entry (its first parameter `This`) or a C++ virtual function.
    Method {
        name: String,
        params: Vec<Param>,
        returns: bool,
    },
    /// A macro, typedef, enum value or data declaration: Doxygen links it as `::NAME`.
    Member(String),
    /// A structure, enum or interface: Doxygen links its bare name.
    Compound(String),
    /// A structure's field.
    Field,
}

#[derive(Debug, Clone, PartialEq)]
struct Param {
    name: String,
    /// From the IDL's attribute comment (`/* [out] */`), for interface methods.
    out: Option<bool>,
    in_: bool,
}

/// One documentation block and what follows it.
struct Block {
    /// The block's lines in the header, `first..=last`.
    first: usize,
    last: usize,
    indent: String,
    /// The text, without comment markers.
    text: Vec<String>,
    decl: Decl,
    /// The interface whose `__X_INTERFACE_DEFINED__` section the block is in.
    interface: Option<String>,
}

/// The names the documentation links, by the form Doxygen links them in.
#[derive(Default)]
struct Names {
    functions: BTreeSet<String>,
    compounds: BTreeSet<String>,
    members: BTreeSet<String>,
}

/// The header with its documentation rewritten for Doxygen, or what is wrong with the documentation.
/// `area` gives a top-level declaration's area: its name and the interface section it is in.
pub fn rewrite(header: &str, area: &dyn Fn(&str, Option<&str>) -> Option<&'static str>) -> Result<String, Vec<String>> {
    let lines: Vec<&str> = header.lines().collect();
    let blocks = blocks(&lines);
    let mut names = Names::default();
    for b in &blocks {
        match &b.decl {
            Decl::Function { name, .. } => {
                names.functions.insert(name.clone());
            }
            Decl::Callback { name, .. } | Decl::Member(name) => {
                names.members.insert(name.clone());
            }
            Decl::Compound(name) => {
                names.compounds.insert(name.clone());
            }
            _ => {}
        }
    }
    let mut problems = Vec::new();
    let mut out = String::new();
    let mut next = 0;
    for b in &blocks {
        for l in &lines[next..b.first] {
            out += l;
            out.push('\n');
        }
        next = b.last + 1;
        let shown = match (&b.decl, &b.interface) {
            (Decl::Method { name, .. }, Some(i)) => format!("{i}::{name}"),
            (d, _) => decl_name(d).unwrap_or_default(),
        };
        let mut text = sections(&b.text, &b.decl, &shown, &mut problems);
        link(&mut text, &names);
        let top = b.indent.is_empty();
        let grouped = b.text.iter().any(|l| {
            ["@file", "@ingroup", "@defgroup", "@addtogroup"]
                .iter()
                .any(|c| l.contains(c))
        });
        if top && !grouped && b.decl != Decl::Other {
            let name = decl_name(&b.decl).unwrap_or_default();
            match area(&name, b.interface.as_deref()) {
                Some(g) => {
                    text.push(String::new());
                    text.push(format!("@ingroup {g}"));
                }
                None => problems.push(format!(
                    "{name}: in no area of the reference (tools/gen-header/src/groups.rs)"
                )),
            }
        }
        if text == b.text {
            for l in &lines[b.first..=b.last] {
                out += l;
                out.push('\n');
            }
        } else {
            out += &format!("{}/**\n", b.indent);
            for l in &text {
                if l.is_empty() {
                    out += &format!("{} *\n", b.indent);
                } else {
                    out += &format!("{} * {l}\n", b.indent);
                }
            }
            out += &format!("{} */\n", b.indent);
        }
    }
    for l in &lines[next..] {
        out += l;
        out.push('\n');
    }
    if problems.is_empty() {
        Ok(out)
    } else {
        // An inherited method is in every vtable that derives from its interface: say it once.
        let mut seen = BTreeSet::new();
        problems.retain(|p| seen.insert(p.clone()));
        Err(problems)
    }
}

fn decl_name(d: &Decl) -> Option<String> {
    match d {
        Decl::Function { name, .. }
        | Decl::Callback { name, .. }
        | Decl::Method { name, .. }
        | Decl::Member(name)
        | Decl::Compound(name) => Some(name.clone()),
        _ => None,
    }
}

fn blocks(lines: &[&str]) -> Vec<Block> {
    let mut out = Vec::new();
    let mut interface: Option<String> = None;
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let trimmed = line.trim_start();
        if let Some(name) = trimmed
            .strip_prefix("#ifndef __")
            .and_then(|r| r.strip_suffix("_INTERFACE_DEFINED__"))
        {
            interface = Some(name.to_string());
        } else if trimmed.starts_with("#endif /* __") && trimmed.ends_with("_INTERFACE_DEFINED__ */") {
            interface = None;
        }
        if !trimmed.starts_with("/**") {
            i += 1;
            continue;
        }
        let indent = line[..line.len() - trimmed.len()].to_string();
        let first = i;
        while !lines[i].contains("*/") {
            i += 1;
        }
        let last = i;
        let text = block_text(&lines[first..=last]);
        let decl = declaration(&lines[last + 1..], !indent.is_empty());
        out.push(Block {
            first,
            last,
            indent,
            text,
            decl,
            interface: interface.clone(),
        });
        i += 1;
    }
    out
}

/// The text of a comment block: `/**`, `*/` and each line's leading ` * ` removed.
fn block_text(lines: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    for (n, l) in lines.iter().enumerate() {
        let mut t = l.trim();
        if n == 0 {
            t = t.strip_prefix("/**").unwrap_or(t);
        }
        if let Some(before) = t.strip_suffix("*/") {
            t = before;
        }
        let t = t.trim_end();
        let t = if n == 0 {
            t.trim_start()
        } else if let Some(rest) = t.strip_prefix("* ") {
            rest
        } else if t == "*" {
            ""
        } else {
            t
        };
        if n == 0 && t.is_empty() {
            continue;
        }
        out.push(t.to_string());
    }
    while out.last().is_some_and(|l| l.is_empty()) {
        out.pop();
    }
    // Continuation lines keep their indentation relative to the block's text (`  more` in a list).
    out
}

/// The declaration after a block, read from its first lines.
fn declaration(after: &[&str], nested: bool) -> Decl {
    let mut lines = after.iter().map(|l| l.trim()).skip_while(|l| l.is_empty());
    let Some(first) = lines.next() else {
        return Decl::Other;
    };
    // Up to the `;` that ends the declaration, on one line.
    let statement = || {
        let mut text = String::new();
        for l in std::iter::once(first).chain(after.iter().map(|l| l.trim()).skip_while(|l| l.is_empty()).skip(1)) {
            text += l;
            text.push(' ');
            if l.ends_with(';') {
                break;
            }
        }
        text.trim().to_string()
    };
    if let Some(rest) = first.strip_prefix("#define ") {
        return Decl::Member(ident_at_start(rest));
    }
    if let Some(rest) = first.strip_prefix("MIDL_INTERFACE(") {
        let _ = rest;
        return Decl::Compound(ident_at_start(lines.next().unwrap_or("")));
    }
    for kw in ["struct ", "enum ", "typedef struct ", "typedef enum "] {
        if let Some(rest) = first.strip_prefix(kw) {
            let name = ident_at_start(rest);
            let alias = rest.trim_end_matches(';').rsplit(' ').next().unwrap_or("");
            // `typedef struct GUID IID;` names another type; `typedef struct X X;` and `struct X {` the structure.
            return if kw.starts_with("typedef") && rest.ends_with(';') && alias != name {
                Decl::Member(alias.to_string())
            } else {
                Decl::Compound(name)
            };
        }
    }
    if first.starts_with("typedef ") {
        let text = statement();
        if let (Some(star), Some(params_at)) = (text.find(" *").filter(|_| text.contains(")(")), text.find(")(")) {
            // typedef R (OPCCOMN_CDECL *Name)(params);
            let open = text[..star].rfind('(').unwrap_or(star);
            return Decl::Callback {
                name: ident_at_start(&text[star + 2..]),
                params: params(&text[params_at + 1..]),
                returns: text["typedef ".len()..open].trim() != "void",
            };
        }
        let name = text
            .trim_end_matches([';', ' '])
            .rsplit(|c: char| !(c.is_alphanumeric() || c == '_'))
            .next()
            .unwrap_or_default();
        return Decl::Member(name.to_string());
    }
    if let Some(rest) = first.strip_prefix("EXTERN_C const ") {
        return Decl::Member(
            rest.trim_end_matches(';')
                .rsplit(' ')
                .next()
                .unwrap_or_default()
                .to_string(),
        );
    }
    if first.starts_with("virtual ") {
        // virtual R STDMETHODCALLTYPE Name(params) = 0;
        let text = statement();
        let open = text.find('(').unwrap_or(text.len());
        let head = &text["virtual ".len()..open];
        return Decl::Method {
            name: head.rsplit(' ').next().unwrap_or_default().to_string(),
            params: params(&text[open..]),
            returns: head.split(" STDMETHODCALLTYPE").next().unwrap_or("").trim() != "void",
        };
    }
    if first.starts_with('#') || first.starts_with("/*") {
        return Decl::Other;
    }
    let marker = "(STDMETHODCALLTYPE *";
    if nested {
        if let Some(at) = first.find(marker) {
            // R (STDMETHODCALLTYPE *Name)(params);
            let text = statement();
            let at = text.find(marker).unwrap_or(at);
            let params_at = text.find(")(").map_or(text.len(), |p| p + 1);
            return Decl::Method {
                name: ident_at_start(&text[at + marker.len()..]),
                params: params(&text[params_at..]),
                returns: text[..at].trim() != "void",
            };
        }
        return match enum_value(first) {
            Some(name) => Decl::Member(name),
            None => Decl::Field,
        };
    }
    let text = statement();
    if let Some(open) = text.find('(').filter(|_| text.ends_with(");")) {
        let head = &text[..open];
        let name = head.rsplit([' ', '*']).next().unwrap_or_default();
        let ret = head[..head.len() - name.len()]
            .replace("OPCCOMN_CDECL", "")
            .replace("OPCCOMN_STDCALL", "");
        return Decl::Function {
            name: name.to_string(),
            params: params(&text[open..]),
            returns: ret.trim() != "void",
        };
    }
    Decl::Other
}

/// `OPC_SERVER_KIND_DATA_ACCESS = 0,` → the value's name.
fn enum_value(text: &str) -> Option<String> {
    let name = ident_at_start(text);
    let rest = text[name.len()..].trim_start();
    (!name.is_empty() && (rest.starts_with('=') || rest.starts_with(','))).then_some(name)
}

fn ident_at_start(s: &str) -> String {
    s.trim_start()
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// The parameters of `(params)...`: each one's name (its last identifier), with the IDL's direction
/// when an attribute comment (`/* [in, string] */`) says it.
fn params(s: &str) -> Vec<Param> {
    let Some(open) = s.find('(') else { return Vec::new() };
    let mut depth = 0;
    let mut end = s.len();
    for (i, c) in s[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    end = open + i;
                    break;
                }
            }
            _ => {}
        }
    }
    let inner = s[open + 1..end].trim();
    if inner.is_empty() || inner == "void" {
        return Vec::new();
    }
    // Split at the commas outside attribute comments (`/* [out, iid_is(riid)] */`) and parentheses.
    let mut parts = Vec::new();
    let (mut depth, mut comment, mut start) = (0, false, 0);
    let bytes = inner.as_bytes();
    for (i, &c) in bytes.iter().enumerate() {
        match c {
            b'*' if i > 0 && bytes[i - 1] == b'/' => comment = true,
            b'/' if i > 0 && bytes[i - 1] == b'*' && comment => comment = false,
            b'(' if !comment => depth += 1,
            b')' if !comment => depth -= 1,
            b',' if !comment && depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .map(|p| {
            let p = p.trim();
            let (attrs, decl) = match p.strip_prefix("/* [").and_then(|r| r.split_once("] */")) {
                Some((a, d)) => (Some(a.to_string()), d.trim()),
                None => (None, p),
            };
            let decl = decl.trim_end_matches("[]");
            let name = decl
                .rsplit(|c: char| !(c.is_alphanumeric() || c == '_'))
                .next()
                .unwrap_or_default()
                .to_string();
            let words: Vec<String> = attrs
                .as_deref()
                .unwrap_or("")
                .split(',')
                .map(|w| w.trim().split('(').next().unwrap_or("").to_string())
                .collect();
            Param {
                name,
                out: attrs.as_ref().map(|_| words.iter().any(|w| w == "out")),
                in_: words.iter().any(|w| w == "in"),
            }
        })
        .collect()
}

/// One `# Parameters` item: the name, the direction the documentation states (`(out)`,
/// `(in, out)`), and the text.
fn param_item(line: &str) -> Option<(String, Option<&'static str>, String)> {
    let rest = line.strip_prefix("- `")?;
    let (name, rest) = rest.split_once('`')?;
    let (dir, rest) = if let Some(r) = rest.strip_prefix(" (out)") {
        (Some("out"), r)
    } else if let Some(r) = rest.strip_prefix(" (in, out)") {
        (Some("in,out"), r)
    } else {
        (None, rest)
    };
    let text = rest.strip_prefix(':')?.trim_start();
    Some((name.to_string(), dir, text.to_string()))
}

/// Turns the Markdown sections into Doxygen's commands and checks them against the declaration.
fn sections(text: &[String], decl: &Decl, name: &str, problems: &mut Vec<String>) -> Vec<String> {
    #[derive(PartialEq)]
    enum In {
        Text,
        Params,
        Returns,
        Code,
    }
    let mut out = Vec::new();
    let mut state = In::Text;
    let mut documented: Vec<(String, Option<&'static str>)> = Vec::new();
    let mut has_returns = false;
    let mut returns_started = false;
    let (params, returns, method) = match decl {
        Decl::Function { params, returns, .. } | Decl::Callback { params, returns, .. } => {
            (Some(params), *returns, false)
        }
        Decl::Method { params, returns, .. } => (Some(params), *returns, true),
        _ => (None, false, false),
    };
    for line in text {
        if state == In::Code {
            if line.trim_start().starts_with("```") {
                state = In::Text;
            }
            out.push(line.clone());
            continue;
        }
        if line.trim_start().starts_with("```") {
            state = In::Code;
            out.push(line.clone());
            continue;
        }
        if let Some(heading) = line.strip_prefix("# ") {
            match heading {
                "Parameters" => state = In::Params,
                "Returns" => {
                    state = In::Returns;
                    has_returns = true;
                    returns_started = false;
                }
                other => {
                    out.push(format!("@par {other}"));
                    state = In::Text;
                }
            }
            continue;
        }
        match state {
            In::Params if line.starts_with("- ") => match param_item(line) {
                Some((p, dir, rest)) => {
                    // An interface method's direction is the IDL's.
                    let idl = params.and_then(|ps| ps.iter().find(|q| q.name == p)).and_then(|q| {
                        q.out.map(|out| match (q.in_, out) {
                            (true, true) => "in,out",
                            (_, true) => "out",
                            _ => "in",
                        })
                    });
                    let dir = match (dir, idl) {
                        (Some(d), Some(i)) if d != i => {
                            problems.push(format!("{name}: `{p}` is documented ({d}) but the IDL says [{i}]"));
                            Some(d)
                        }
                        (None, Some("in")) => None,
                        (None, Some(i)) => Some(i),
                        (d, _) => d,
                    };
                    documented.push((p.clone(), dir));
                    out.push(match dir {
                        Some(d) => format!("@param[{d}] {p} {rest}"),
                        None => format!("@param {p} {rest}"),
                    });
                }
                None => {
                    problems.push(format!("{name}: `{line}` is not a parameter item (- `name`: text)"));
                    out.push(line.clone());
                }
            },
            In::Params if line.starts_with("  ") => out.push(line.clone()),
            In::Params if line.is_empty() => {
                state = In::Text;
                out.push(String::new());
            }
            In::Params => {
                problems.push(format!(
                    "{name}: `{line}` in # Parameters is neither an item nor its continuation"
                ));
                out.push(line.clone());
            }
            In::Returns if line.is_empty() => {
                state = In::Text;
                out.push(String::new());
            }
            In::Returns if returns_started => out.push(line.clone()),
            In::Returns => {
                returns_started = true;
                out.push(format!("@return {line}"));
            }
            _ => out.push(line.clone()),
        }
    }
    while out.last().is_some_and(|l| l.is_empty()) {
        out.pop();
    }
    if let Some(params) = params {
        // The C form of an interface method has `This` first; its documentation says what it is.
        let this = method && params.first().is_some_and(|p| p.name == "This");
        let want: Vec<&str> = params
            .iter()
            .map(|p| p.name.as_str())
            .filter(|p| !(this && *p == "This"))
            .collect();
        let got: Vec<&str> = documented.iter().map(|(p, _)| p.as_str()).collect();
        if want != got {
            problems.push(format!(
                "{name}: # Parameters documents ({}) where the declaration has ({})",
                got.join(", "),
                want.join(", ")
            ));
        }
        if returns && !has_returns {
            problems.push(format!("{name}: no # Returns section"));
        }
        if !returns && has_returns {
            problems.push(format!("{name}: a # Returns section, but it returns void"));
        }
        if this {
            let at = out
                .iter()
                .position(|l| l.starts_with("@param") || l.starts_with("@return"))
                .unwrap_or(out.len());
            let mut insert = vec!["@param This the object the method is called on (the interface pointer)".to_string()];
            if at == out.len() {
                insert.insert(0, String::new());
            }
            for (k, l) in insert.into_iter().enumerate() {
                out.insert(at + k, l);
            }
        }
    } else if has_returns || !documented.is_empty() {
        problems.push(format!(
            "{name}: # Parameters or # Returns on something that is not a function"
        ));
    }
    out
}

/// Rewrites names into the forms Doxygen links (see the module's documentation), outside code blocks.
fn link(text: &mut [String], names: &Names) {
    let mut code = false;
    // A code span that goes on to the next line is kept as it is.
    let mut in_span = false;
    for line in text.iter_mut() {
        if line.trim_start().starts_with("```") || line.contains("@code") || line.contains("@endcode") {
            code = !code;
            continue;
        }
        if code {
            continue;
        }
        *line = link_line(line, names, &mut in_span);
    }
}

fn link_line(line: &str, names: &Names, in_span: &mut bool) -> String {
    let mut out = String::new();
    let mut rest = line;
    if *in_span {
        match rest.find('`') {
            Some(end) => {
                out += &rest[..=end];
                rest = &rest[end + 1..];
                *in_span = false;
            }
            None => return line.to_string(),
        }
    }
    loop {
        // Text up to the next code span, then the span.
        let Some(a) = rest.find('`') else {
            out += &link_bare(rest, names);
            break;
        };
        out += &link_bare(&rest[..a], names);
        match rest[a + 1..].find('`') {
            Some(b) => {
                out += &link_span(&rest[a + 1..a + 1 + b], names);
                rest = &rest[a + 2 + b..];
            }
            None => {
                out += &rest[a..];
                *in_span = true;
                break;
            }
        }
    }
    out
}

/// A code span: a name Doxygen can link loses its backticks.
fn link_span(inner: &str, names: &Names) -> String {
    let bare = inner.strip_suffix("()").unwrap_or(inner);
    let ident = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_alphanumeric() || c == '_');
    if ident(bare) && names.functions.contains(bare) {
        return format!("{bare}()");
    }
    if ident(inner) && names.compounds.contains(inner) {
        return inner.to_string();
    }
    if ident(inner) && names.members.contains(inner) {
        return format!("::{inner}");
    }
    if let Some((outer, field)) = inner.split_once("::") {
        if ident(outer) && ident(field) && names.compounds.contains(outer) {
            return inner.to_string();
        }
    }
    format!("`{inner}`")
}

/// Plain text: a function's bare name gets its `()`.
fn link_bare(text: &str, names: &Names) -> String {
    let mut out = String::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let word: String = chars[start..i].iter().collect();
            out += &word;
            let before = if start > 0 { Some(chars[start - 1]) } else { None };
            let after = chars.get(i).copied();
            if names.functions.contains(&word)
                && after != Some('(')
                && !matches!(before, Some(':') | Some('#') | Some('.') | Some('\\') | Some('@'))
            {
                out += "()";
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(_: &str, _: Option<&str>) -> Option<&'static str> {
        Some("things")
    }

    #[test]
    fn sections_become_commands_and_names_links() {
        let header = "\
/**
 * Makes a thing; free it with `FreeThing`, or FreeThing, flags `THING_FLAG`, see `Thing` and
 * `Thing::size`, not `other`.
 *
 * # Parameters
 * - `size`: how big.
 *   Still how big.
 * - `out` (out): the thing.
 *
 * # Returns
 * S_OK; E_INVALIDARG for a `size` of 0.
 *
 * # Safety
 * `out` must be writable.
 */
HRESULT OPCCOMN_CDECL MakeThing(size_t size, struct Thing **out);

/**
 * Frees a thing.
 *
 * # Parameters
 * - `thing`: the thing, or NULL.
 */
void OPCCOMN_CDECL FreeThing(struct Thing *thing);

/** A flag. */
#define THING_FLAG 1

/**
 * A thing.
 */
typedef struct Thing {
  /**
   * Its size.
   */
  size_t size;
} Thing;
";
        let out = rewrite(header, &area).unwrap();
        assert!(out.contains(" * Makes a thing; free it with FreeThing(), or FreeThing(), flags ::THING_FLAG, see Thing and\n * Thing::size, not `other`.\n"), "{out}");
        assert!(
            out.contains(" * @param size how big.\n *   Still how big.\n * @param[out] out the thing.\n"),
            "{out}"
        );
        assert!(
            out.contains(" * @return S_OK; E_INVALIDARG for a `size` of 0.\n"),
            "{out}"
        );
        assert!(
            out.contains(" * @par Safety\n * `out` must be writable.\n *\n * @ingroup things\n */\nHRESULT"),
            "{out}"
        );
        assert!(
            out.contains("/**\n * A flag.\n *\n * @ingroup things\n */\n#define THING_FLAG 1"),
            "{out}"
        );
        // A field is in its structure's area, not one of its own.
        assert!(out.contains("  /**\n   * Its size.\n   */\n  size_t size;"), "{out}");
    }

    #[test]
    fn a_code_span_over_two_lines_is_kept_and_names_after_a_slash_are_linked() {
        let header = "\
/**
 * Its text is `MakeThing(size,
 * out)`, its pair FreeThing/FreeThing.
 */
#define THING_FLAG 1

/**
 * Frees a thing.
 */
void OPCCOMN_CDECL FreeThing(void);
";
        let out = rewrite(header, &area).unwrap();
        assert!(
            out.contains(" * Its text is `MakeThing(size,\n * out)`, its pair FreeThing()/FreeThing().\n"),
            "{out}"
        );
    }

    #[test]
    fn missing_wrong_and_extra_documentation_is_reported() {
        let header = "\
/**
 * No parameters documented.
 */
HRESULT OPCCOMN_CDECL A(int x, int y);

/**
 * # Parameters
 * - `y`: second.
 * - `x`: first.
 *
 * # Returns
 * Nothing really.
 */
void OPCCOMN_CDECL B(int x, int y);

/**
 * A callback.
 *
 * # Parameters
 * - `context`: the context.
 */
typedef HRESULT (OPCCOMN_CDECL *Cb)(void *context, LCID locale);
";
        let p = rewrite(header, &area).unwrap_err();
        assert!(
            p.iter()
                .any(|p| p.contains("A: # Parameters documents () where the declaration has (x, y)")),
            "{p:?}"
        );
        assert!(p.iter().any(|p| p.contains("A: no # Returns")), "{p:?}");
        assert!(
            p.iter().any(|p| p.contains("B: # Parameters documents (y, x)")),
            "{p:?}"
        );
        assert!(
            p.iter()
                .any(|p| p.contains("B: a # Returns section, but it returns void")),
            "{p:?}"
        );
        assert!(p.iter().any(|p| p.contains("Cb: # Parameters documents (context) where the declaration has (context, locale)")), "{p:?}");
        assert!(p.iter().any(|p| p.contains("Cb: no # Returns")), "{p:?}");
    }

    #[test]
    fn interface_methods_take_their_direction_from_the_idl_and_document_this() {
        let header = "\
#ifndef __IThing_INTERFACE_DEFINED__
/** The methods. */
typedef struct IThingVtbl
{
    /**
     * Gets it.
     *
     * # Parameters
     * - `pValue`: where it goes.
     *
     * # Returns
     * S_OK.
     */
    HRESULT (STDMETHODCALLTYPE *Get)(
        IThing *This,
        /* [out] */ LONG *pValue);

    /**
     * Resets it.
     *
     * # Returns
     * S_OK.
     */
    HRESULT (STDMETHODCALLTYPE *Reset)(
        IThing *This);

    /**
     * Sets it.
     *
     * # Parameters
     * - `value` (out): wrong.
     *
     * # Returns
     * S_OK.
     */
    HRESULT (STDMETHODCALLTYPE *Set)(
        IThing *This,
        /* [in] */ LONG value);
} IThingVtbl;
#endif /* __IThing_INTERFACE_DEFINED__ */
";
        let p = rewrite(header, &|_, i| (i == Some("IThing")).then_some("things")).unwrap_err();
        assert_eq!(
            p,
            vec!["IThing::Set: `value` is documented (out) but the IDL says [in]".to_string()]
        );
        let fixed = header.replace("`value` (out): wrong", "`value`: right");
        let out = rewrite(&fixed, &|_, i| (i == Some("IThing")).then_some("things")).unwrap();
        assert!(out.contains("     * @param This the object the method is called on (the interface pointer)\n     * @param[out] pValue where it goes.\n"), "{out}");
        assert!(out.contains("     * Resets it.\n     *\n     * @param This the object the method is called on (the interface pointer)\n     * @return S_OK.\n"), "{out}");
        assert!(
            out.contains("/**\n * The methods.\n *\n * @ingroup things\n */\ntypedef struct IThingVtbl"),
            "{out}"
        );
    }

    #[test]
    fn a_declaration_in_no_area_is_reported() {
        let p = rewrite("/** A flag. */\n#define LOST 1\n", &|_, _| None).unwrap_err();
        assert_eq!(
            p,
            vec!["LOST: in no area of the reference (tools/gen-header/src/groups.rs)".to_string()]
        );
    }
}
