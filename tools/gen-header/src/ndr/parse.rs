//! Reads the declarations of an IDL file as NDR needs them: every attribute with its arguments, the
//! typedefs (aliases, structures, unions, enums) at the top and inside interfaces, and each method's
//! parameters. `import`, `cpp_quote`, `const` and `library` blocks are skipped (the types of the
//! imported system files are the generator's built-ins, `super::resolve`).

use std::fmt;

#[derive(Debug)]
pub struct Error(pub String);

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// `name(arg, arg)`: an attribute; `args` are the texts between top-level commas, trimmed (an empty
/// argument stays, as in `size_is(, *pdwCount)`).
#[derive(Debug, Clone, PartialEq)]
pub struct Attr {
    pub name: String,
    pub args: Vec<String>,
}

/// The attributes of one declaration.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Attrs(pub Vec<Attr>);

impl Attrs {
    pub fn has(&self, name: &str) -> bool {
        self.0.iter().any(|a| a.name == name)
    }
    pub fn args(&self, name: &str) -> Option<&[String]> {
        self.0.iter().find(|a| a.name == name).map(|a| a.args.as_slice())
    }
}

/// A declarator: `**name[]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Declarator {
    pub stars: usize,
    pub name: String,
    /// `[]` (None) or `[N]` per dimension.
    pub dims: Vec<Option<String>>,
}

/// A type as written: words (`unsigned long`, `const WCHAR`), or a structure, union or enum body.
#[derive(Debug, Clone, PartialEq)]
pub enum TypeSpec {
    Named(Vec<String>),
    Struct {
        tag: Option<String>,
        fields: Vec<Field>,
    },
    Union {
        tag: Option<String>,
        arms: Vec<Arm>,
    },
    Enum {
        tag: Option<String>,
        values: Vec<(String, i64)>,
    },
}

/// A field or a parameter: `[attrs] type declarator`.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub attrs: Attrs,
    pub ty: TypeSpec,
    pub decl: Declarator,
}

/// A union arm: `[case(1, 2)] type name;`, `[default] ;`.
#[derive(Debug, Clone, PartialEq)]
pub struct Arm {
    /// The case labels as written; empty for `[default]`.
    pub cases: Vec<String>,
    pub field: Option<Field>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Typedef {
    pub attrs: Attrs,
    pub ty: TypeSpec,
    pub names: Vec<Declarator>,
    pub line: usize,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Method {
    pub attrs: Attrs,
    pub ret: String,
    pub name: String,
    pub params: Vec<Field>,
    pub line: usize,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Interface {
    pub attrs: Attrs,
    pub name: String,
    pub base: Option<String>,
    pub typedefs: Vec<Typedef>,
    pub methods: Vec<Method>,
}

/// What one file declares, in order.
#[derive(Debug, Default)]
pub struct File {
    pub path: String,
    pub typedefs: Vec<Typedef>,
    pub interfaces: Vec<Interface>,
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Word(String),
    Str,
    Punct(char),
}

fn tokenize(file: &str, text: &str) -> Result<Vec<(Tok, usize)>, Error> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    while i < chars.len() {
        let c = chars[i];
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c == '/' && chars.get(i + 1) == Some(&'/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && chars.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < chars.len() && !(chars[i] == '*' && chars[i + 1] == '/') {
                if chars[i] == '\n' {
                    line += 1;
                }
                i += 1;
            }
            if i + 1 >= chars.len() {
                return Err(Error(format!("{file}:{line}: unterminated comment")));
            }
            i += 2;
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                if chars[i] == '\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push((Tok::Str, line));
        } else if c.is_ascii_alphanumeric() || c == '_' {
            let start = i;
            // GUIDs inside uuid(...) contain '-', versions '.': one word each.
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || matches!(chars[i], '_' | '.' | '-')) {
                // A '-' belongs to the word only inside a GUID (hexadecimal on both sides).
                if chars[i] == '-' && !(chars[start..i].iter().all(|c| c.is_ascii_hexdigit() || *c == '-')) {
                    break;
                }
                i += 1;
            }
            out.push((Tok::Word(chars[start..i].iter().collect()), line));
        } else {
            out.push((Tok::Punct(c), line));
            i += 1;
        }
    }
    Ok(out)
}

struct Parser<'a> {
    toks: Vec<(Tok, usize)>,
    pos: usize,
    file: &'a str,
}

impl Parser<'_> {
    fn line(&self) -> usize {
        self.toks.get(self.pos).or(self.toks.last()).map_or(0, |t| t.1)
    }
    fn err<T>(&self, what: &str) -> Result<T, Error> {
        Err(Error(format!("{}:{}: {what}", self.file, self.line())))
    }
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos).map(|t| &t.0)
    }
    fn peek_word(&self) -> Option<&str> {
        match self.peek() {
            Some(Tok::Word(w)) => Some(w),
            _ => None,
        }
    }
    fn next(&mut self) -> Option<Tok> {
        let t = self.toks.get(self.pos).map(|t| t.0.clone());
        self.pos += 1;
        t
    }
    fn eat(&mut self, c: char) -> bool {
        if self.peek() == Some(&Tok::Punct(c)) {
            self.pos += 1;
            true
        } else {
            false
        }
    }
    fn eat_word(&mut self, w: &str) -> bool {
        if self.peek_word() == Some(w) {
            self.pos += 1;
            true
        } else {
            false
        }
    }
    fn expect(&mut self, c: char) -> Result<(), Error> {
        if self.eat(c) {
            Ok(())
        } else {
            self.err(&format!("expected '{c}'"))
        }
    }
    fn word(&mut self) -> Result<String, Error> {
        match self.peek() {
            Some(Tok::Word(w)) => {
                let w = w.clone();
                self.pos += 1;
                Ok(w)
            }
            _ => self.err("expected a name"),
        }
    }

    /// Skips to after the balanced `close` matching an `open` already consumed.
    fn skip_group(&mut self, open: char, close: char) -> Result<(), Error> {
        let mut depth = 1;
        while depth > 0 {
            match self.next() {
                Some(Tok::Punct(c)) if c == open => depth += 1,
                Some(Tok::Punct(c)) if c == close => depth -= 1,
                Some(_) => {}
                None => return self.err(&format!("unclosed '{open}'")),
            }
        }
        Ok(())
    }

    /// The text of tokens up to (not including) a top-level `,` or `)`, words separated by spaces.
    fn argument(&mut self) -> Result<String, Error> {
        let mut text = String::new();
        let mut depth = 0;
        loop {
            match self.peek() {
                Some(Tok::Punct(',')) | Some(Tok::Punct(')')) if depth == 0 => return Ok(text.trim().to_string()),
                Some(Tok::Punct(c)) => {
                    let c = *c;
                    if c == '(' {
                        depth += 1;
                    } else if c == ')' {
                        depth -= 1;
                    }
                    text.push(c);
                }
                Some(Tok::Word(w)) => {
                    if text.ends_with(|c: char| c.is_ascii_alphanumeric() || c == '_') {
                        text.push(' ');
                    }
                    text.push_str(w);
                }
                Some(Tok::Str) => text.push_str("\"\""),
                None => return self.err("unclosed attribute"),
            }
            self.pos += 1;
        }
    }

    /// `[a, b(x, y)]`, the `[` already consumed.
    fn attrs(&mut self) -> Result<Attrs, Error> {
        let mut out = Vec::new();
        if self.eat(']') {
            return Ok(Attrs(out));
        }
        loop {
            let name = self.word()?;
            let mut args = Vec::new();
            if self.eat('(') && !self.eat(')') {
                loop {
                    args.push(self.argument()?);
                    if self.eat(')') {
                        break;
                    }
                    self.expect(',')?;
                }
            }
            out.push(Attr { name, args });
            if self.eat(']') {
                return Ok(Attrs(out));
            }
            self.expect(',')?;
        }
    }

    fn opt_attrs(&mut self) -> Result<Attrs, Error> {
        if self.eat('[') {
            self.attrs()
        } else {
            Ok(Attrs::default())
        }
    }

    /// A type: words, or `struct`/`union`/`enum` with an optional body.
    fn type_spec(&mut self) -> Result<TypeSpec, Error> {
        let mut words = Vec::new();
        loop {
            match self.peek_word() {
                Some("struct") if words.is_empty() || words == ["const"] => {
                    self.pos += 1;
                    return self.struct_body();
                }
                Some("union") if words.is_empty() => {
                    self.pos += 1;
                    return self.union_body();
                }
                Some("enum") if words.is_empty() => {
                    self.pos += 1;
                    return self.enum_body();
                }
                Some("const") => {
                    self.pos += 1;
                }
                Some("unsigned" | "signed" | "long" | "short" | "int" | "char" | "hyper" | "small" | "__int64")
                    if words
                        .last()
                        .is_none_or(|w: &String| matches!(w.as_str(), "unsigned" | "signed" | "long" | "short")) =>
                {
                    words.push(self.word()?);
                }
                Some(_) if words.is_empty() => words.push(self.word()?),
                _ => break,
            }
        }
        if words.is_empty() {
            return self.err("expected a type");
        }
        Ok(TypeSpec::Named(words))
    }

    fn tag(&mut self) -> Option<String> {
        match self.peek() {
            Some(Tok::Word(w)) if w != "switch" => {
                let w = w.clone();
                self.pos += 1;
                Some(w)
            }
            _ => None,
        }
    }

    fn struct_body(&mut self) -> Result<TypeSpec, Error> {
        let tag = self.tag();
        if !self.eat('{') {
            return Ok(TypeSpec::Named(vec![
                tag.ok_or_else(|| Error("struct without a name".into()))?
            ]));
        }
        let mut fields = Vec::new();
        while !self.eat('}') {
            let attrs = self.opt_attrs()?;
            let ty = self.type_spec()?;
            loop {
                let decl = self.declarator()?;
                fields.push(Field {
                    attrs: attrs.clone(),
                    ty: ty.clone(),
                    decl,
                });
                if !self.eat(',') {
                    break;
                }
            }
            self.expect(';')?;
        }
        Ok(TypeSpec::Struct { tag, fields })
    }

    fn union_body(&mut self) -> Result<TypeSpec, Error> {
        let tag = self.tag();
        if self.peek_word() == Some("switch") {
            return self.err("encapsulated unions (union switch) are not supported; use [switch_is] on a union");
        }
        if !self.eat('{') {
            return Ok(TypeSpec::Named(vec![
                tag.ok_or_else(|| Error("union without a name".into()))?
            ]));
        }
        let mut arms = Vec::new();
        while !self.eat('}') {
            let attrs = self.opt_attrs()?;
            let cases = if let Some(c) = attrs.args("case") {
                c.to_vec()
            } else if attrs.has("default") {
                Vec::new()
            } else {
                return self.err("a union arm needs [case(...)] or [default]");
            };
            let field = if self.eat(';') {
                None
            } else {
                let ty = self.type_spec()?;
                let decl = self.declarator()?;
                self.expect(';')?;
                Some(Field {
                    attrs: Attrs(
                        attrs
                            .0
                            .into_iter()
                            .filter(|a| a.name != "case" && a.name != "default")
                            .collect(),
                    ),
                    ty,
                    decl,
                })
            };
            arms.push(Arm { cases, field });
        }
        Ok(TypeSpec::Union { tag, arms })
    }

    fn enum_body(&mut self) -> Result<TypeSpec, Error> {
        let tag = self.tag();
        if !self.eat('{') {
            return Ok(TypeSpec::Named(vec![
                tag.ok_or_else(|| Error("enum without a name".into()))?
            ]));
        }
        let mut values = Vec::new();
        let mut next = 0i64;
        while !self.eat('}') {
            let name = self.word()?;
            if self.eat('=') {
                let text = self.argument_until_comma_or_brace()?;
                next = parse_int(&text).ok_or_else(|| Error(format!("{}: enum value {text}", self.file)))?;
            }
            values.push((name, next));
            next += 1;
            if !self.eat(',') {
                self.expect('}')?;
                break;
            }
        }
        Ok(TypeSpec::Enum { tag, values })
    }

    fn argument_until_comma_or_brace(&mut self) -> Result<String, Error> {
        let mut text = String::new();
        loop {
            match self.peek() {
                Some(Tok::Punct(',')) | Some(Tok::Punct('}')) => return Ok(text),
                Some(Tok::Punct(c)) => text.push(*c),
                Some(Tok::Word(w)) => text.push_str(w),
                _ => return self.err("bad enum value"),
            }
            self.pos += 1;
        }
    }

    /// `* * name [N] []`.
    fn declarator(&mut self) -> Result<Declarator, Error> {
        let mut stars = 0;
        loop {
            if self.eat('*') {
                stars += 1;
            } else if self.eat_word("const") {
            } else {
                break;
            }
        }
        let name = self.word()?;
        let mut dims = Vec::new();
        while self.eat('[') {
            if self.eat(']') {
                dims.push(None);
            } else {
                let n = self.argument_until(']')?;
                dims.push(Some(n));
            }
        }
        Ok(Declarator { stars, name, dims })
    }

    fn argument_until(&mut self, close: char) -> Result<String, Error> {
        let mut text = String::new();
        loop {
            match self.next() {
                Some(Tok::Punct(c)) if c == close => return Ok(text),
                Some(Tok::Punct(c)) => text.push(c),
                Some(Tok::Word(w)) => text.push_str(&w),
                _ => return self.err("unclosed dimension"),
            }
        }
    }

    /// `typedef` already consumed.
    fn typedef(&mut self) -> Result<Typedef, Error> {
        let line = self.line();
        let attrs = self.opt_attrs()?;
        let ty = self.type_spec()?;
        let mut names = Vec::new();
        loop {
            names.push(self.declarator()?);
            if !self.eat(',') {
                break;
            }
        }
        self.expect(';')?;
        Ok(Typedef { attrs, ty, names, line })
    }

    fn interface_body(&mut self) -> Result<(Vec<Typedef>, Vec<Method>), Error> {
        let mut typedefs = Vec::new();
        let mut methods = Vec::new();
        loop {
            if self.eat('}') {
                self.eat(';');
                return Ok((typedefs, methods));
            }
            if self.eat_word("typedef") {
                typedefs.push(self.typedef()?);
                continue;
            }
            if self.eat_word("const") {
                while !self.eat(';') {
                    if self.next().is_none() {
                        return self.err("unterminated const");
                    }
                }
                continue;
            }
            if self.eat_word("cpp_quote") {
                self.expect('(')?;
                self.skip_group('(', ')')?;
                continue;
            }
            let attrs = self.opt_attrs()?;
            let line = self.line();
            let ret = self.word()?;
            let name = self.word()?;
            self.expect('(')?;
            let mut params = Vec::new();
            if !self.eat(')') {
                loop {
                    let pattrs = self.opt_attrs()?;
                    if pattrs.0.is_empty() && self.peek_word() == Some("void") {
                        let save = self.pos;
                        self.pos += 1;
                        if self.eat(')') {
                            break;
                        }
                        self.pos = save;
                    }
                    let ty = self.type_spec()?;
                    let decl = self.declarator()?;
                    params.push(Field {
                        attrs: pattrs,
                        ty,
                        decl,
                    });
                    if self.eat(')') {
                        break;
                    }
                    self.expect(',')?;
                }
            }
            self.expect(';')?;
            methods.push(Method {
                attrs,
                ret,
                name,
                params,
                line,
            });
        }
    }
}

/// `12`, `0x1F`, `-1`, `0x10L`.
pub fn parse_int(text: &str) -> Option<i64> {
    let t = text.trim().trim_end_matches(['L', 'l', 'U', 'u']);
    let (neg, t) = match t.strip_prefix('-') {
        Some(rest) => (true, rest.trim()),
        None => (false, t),
    };
    let v = if let Some(hex) = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        i64::from_str_radix(hex, 16).ok()?
    } else {
        t.parse().ok()?
    };
    Some(if neg { -v } else { v })
}

/// Parses one IDL file.
pub fn parse(path: &str, text: &str) -> Result<File, Error> {
    let toks = tokenize(path, text)?;
    let mut p = Parser {
        toks,
        pos: 0,
        file: path,
    };
    let mut file = File {
        path: path.to_string(),
        ..File::default()
    };
    let mut attrs = Attrs::default();
    while p.peek().is_some() {
        if p.eat('[') {
            attrs = p.attrs()?;
            continue;
        }
        if p.eat(';') {
            continue;
        }
        match p.word()?.as_str() {
            "import" | "importlib" => {
                while !p.eat(';') {
                    if p.next().is_none() {
                        return p.err("unterminated import");
                    }
                }
            }
            "cpp_quote" => {
                p.expect('(')?;
                p.skip_group('(', ')')?;
            }
            "const" => {
                while !p.eat(';') {
                    if p.next().is_none() {
                        return p.err("unterminated const");
                    }
                }
            }
            "typedef" => file.typedefs.push(p.typedef()?),
            "library" | "coclass" | "module" | "dispinterface" => {
                p.word()?;
                if p.eat('{') {
                    p.skip_group('{', '}')?;
                }
                p.eat(';');
                attrs = Attrs::default();
            }
            "interface" => {
                let name = p.word()?;
                if p.eat(';') {
                    attrs = Attrs::default();
                    continue;
                }
                let base = if p.eat(':') { Some(p.word()?) } else { None };
                p.expect('{')?;
                let (typedefs, methods) = p.interface_body()?;
                file.interfaces.push(Interface {
                    attrs: std::mem::take(&mut attrs),
                    name,
                    base,
                    typedefs,
                    methods,
                });
            }
            other => {
                p.pos -= 1;
                return p.err(&format!("unexpected '{other}'"));
            }
        }
    }
    Ok(file)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_typedefs_attributes_and_methods() {
        let text = r#"
            import "oaidl.idl";
            typedef DWORD OPCHANDLE;
            typedef enum tagX { A = 1, B, C = 0x10 } X;
            typedef struct tagS {
                [string] LPWSTR szName;
                DWORD dwCount;
                [size_is(dwCount)] BYTE *pBlob;
                DWORD fixed[4];
            } S, *PS;
            typedef [switch_type(DWORD)] union tagU { [case(1)] DWORD a; [case(2, 3)] double b; [default] ; } U;
            [object, uuid(F31DFDE2-07B6-11d2-B2D8-0060083BA1FB), pointer_default(unique)]
            interface ITest : IUnknown {
                HRESULT M([in] DWORD c, [out, size_is(, *pc)] LCID **pp, [in] REFIID riid, [out, iid_is(riid)] IUnknown **ppUnk);
                HRESULT N(void);
            }
        "#;
        let f = parse("t.idl", text).unwrap();
        assert_eq!(f.typedefs.len(), 4);
        let TypeSpec::Enum { values, .. } = &f.typedefs[1].ty else {
            panic!()
        };
        assert_eq!(values, &[("A".into(), 1), ("B".into(), 2), ("C".into(), 16)]);
        let TypeSpec::Struct { fields, .. } = &f.typedefs[2].ty else {
            panic!()
        };
        assert_eq!(fields[2].attrs.args("size_is").unwrap(), ["dwCount"]);
        assert_eq!(fields[3].decl.dims, [Some("4".to_string())]);
        assert_eq!(f.typedefs[2].names[1].stars, 1);
        let TypeSpec::Union { arms, .. } = &f.typedefs[3].ty else {
            panic!()
        };
        assert_eq!(arms[1].cases, ["2", "3"]);
        assert!(arms[2].field.is_none());
        let i = &f.interfaces[0];
        assert_eq!(i.attrs.args("uuid").unwrap(), ["F31DFDE2-07B6-11d2-B2D8-0060083BA1FB"]);
        assert_eq!(i.methods[0].params[1].attrs.args("size_is").unwrap(), ["", "*pc"]);
        assert_eq!(i.methods[0].params[1].decl.stars, 2);
        assert_eq!(i.methods[0].params[3].attrs.args("iid_is").unwrap(), ["riid"]);
        assert!(i.methods[1].params.is_empty());
    }

    #[test]
    fn multiword_types_and_errors() {
        let f = parse("t.idl", "typedef unsigned long UL; typedef const unsigned short *P;").unwrap();
        assert_eq!(
            f.typedefs[0].ty,
            TypeSpec::Named(vec!["unsigned".into(), "long".into()])
        );
        assert_eq!(
            f.typedefs[1].ty,
            TypeSpec::Named(vec!["unsigned".into(), "short".into()])
        );
        let e = parse("t.idl", "\n\ntypedef union switch (long k) u { } U;").unwrap_err();
        assert!(e.0.starts_with("t.idl:3:"), "{e}");
    }
}
