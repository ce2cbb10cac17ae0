//! A reader for the subset of MIDL that `idl/*.idl` use: `import`, `cpp_quote`, `library` blocks
//! (skipped), and `[attributes] interface Name : Base { typedefs and methods }`.

use std::collections::HashMap;
use std::fmt;

/// One parameter of a method.
#[derive(Debug, Clone)]
pub struct Param {
    /// The attribute list as written, without brackets (`in, size_is(cImplemented)`).
    pub attributes: String,
    /// The C type (`CATID`, `LCID *`, `const GUID *`), without the name.
    pub ty: String,
    pub name: String,
    /// `true` for `CATID rgcatidImpl[]`.
    pub array: bool,
}

impl Param {
    /// The declaration as C writes it: `LCID *pdwLcid`, `CATID rgcatidImpl[]`.
    pub fn declaration(&self) -> String {
        let mut s = self.ty.clone();
        if !s.ends_with('*') {
            s.push(' ');
        }
        s.push_str(&self.name);
        if self.array {
            s.push_str("[]");
        }
        s
    }
}

#[derive(Debug, Clone)]
pub struct Method {
    pub ret: String,
    pub name: String,
    pub params: Vec<Param>,
    /// The `///` comment lines in front of the method, without the slashes: its documentation.
    pub doc: Vec<String>,
}

#[derive(Debug, Clone)]
pub struct Interface {
    pub name: String,
    pub base: Option<String>,
    pub uuid: String,
    /// Typedefs inside the interface, as C: `IOPCEnumGUID *LPOPCENUMGUID`.
    pub typedefs: Vec<String>,
    pub methods: Vec<Method>,
    /// The `///` comment lines in front of the interface's attributes: its documentation.
    pub doc: Vec<String>,
}

#[derive(Debug)]
pub struct Error(pub String);

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    Str(String),
    Punct(char),
}

/// The tokens with their lines, and the documentation (`///` lines) in front of each token that has
/// some, by token index.
type Tokens = (Vec<(Tok, usize)>, HashMap<usize, Vec<String>>);

fn tokenize(text: &str) -> Result<Tokens, Error> {
    let bytes: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut docs: HashMap<usize, Vec<String>> = HashMap::new();
    let mut i = 0;
    let mut line = 1;
    while i < bytes.len() {
        let c = bytes[i];
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c == '/' && bytes.get(i + 1) == Some(&'/') {
            let start = i;
            while i < bytes.len() && bytes[i] != '\n' {
                i += 1;
            }
            let comment: String = bytes[start..i].iter().collect();
            if let Some(doc) = comment.strip_prefix("///") {
                let doc = doc.strip_prefix(' ').unwrap_or(doc).trim_end();
                docs.entry(out.len()).or_default().push(doc.to_string());
            }
        } else if c == '/' && bytes.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < bytes.len() && !(bytes[i] == '*' && bytes[i + 1] == '/') {
                if bytes[i] == '\n' {
                    line += 1;
                }
                i += 1;
            }
            i += 2;
        } else if c == '"' {
            let mut s = String::new();
            i += 1;
            while i < bytes.len() && bytes[i] != '"' {
                if bytes[i] == '\\' && i + 1 < bytes.len() {
                    s.push(bytes[i]);
                    i += 1;
                }
                s.push(bytes[i]);
                i += 1;
            }
            i += 1;
            out.push((Tok::Str(s), line));
        } else if c.is_ascii_alphanumeric() || c == '_' {
            let mut s = String::new();
            // GUIDs inside uuid(...) contain '-': read them as one word.
            while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == '_' || bytes[i] == '.') {
                s.push(bytes[i]);
                i += 1;
            }
            out.push((Tok::Ident(s), line));
        } else {
            out.push((Tok::Punct(c), line));
            i += 1;
        }
    }
    Ok((out, docs))
}

struct Parser {
    toks: Vec<(Tok, usize)>,
    docs: HashMap<usize, Vec<String>>,
    pos: usize,
    file: String,
}

impl Parser {
    /// The documentation in front of the token at `pos`, taken (each comment documents one thing).
    fn take_doc(&mut self, pos: usize) -> Vec<String> {
        self.docs.remove(&pos).unwrap_or_default()
    }
    fn err<T>(&self, what: &str) -> Result<T, Error> {
        let line = self.toks.get(self.pos).or(self.toks.last()).map_or(0, |t| t.1);
        Err(Error(format!("{}:{line}: {what}", self.file)))
    }
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos).map(|t| &t.0)
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
    fn expect(&mut self, c: char) -> Result<(), Error> {
        if self.eat(c) {
            Ok(())
        } else {
            self.err(&format!("expected '{c}'"))
        }
    }
    fn ident(&mut self) -> Result<String, Error> {
        match self.next() {
            Some(Tok::Ident(s)) => Ok(s),
            _ => {
                self.pos -= 1;
                self.err("expected a name")
            }
        }
    }
    /// Reads a balanced group opened by `open` (already consumed) and returns its text.
    fn group_text(&mut self, open: char, close: char) -> Result<String, Error> {
        let mut depth = 1;
        let mut text = String::new();
        let mut last_word = false;
        loop {
            let Some(t) = self.next() else {
                return self.err(&format!("unclosed '{open}'"));
            };
            match t {
                Tok::Punct(c) if c == open => {
                    depth += 1;
                    text.push(c);
                    last_word = false;
                }
                Tok::Punct(c) if c == close => {
                    depth -= 1;
                    if depth == 0 {
                        return Ok(text);
                    }
                    text.push(c);
                    last_word = false;
                }
                Tok::Punct(c) => {
                    if c == ',' {
                        text.push_str(", ");
                    } else {
                        text.push(c);
                    }
                    last_word = false;
                }
                Tok::Ident(s) => {
                    if last_word {
                        text.push(' ');
                    }
                    text.push_str(&s);
                    last_word = true;
                }
                Tok::Str(s) => {
                    text.push('"');
                    text.push_str(&s);
                    text.push('"');
                    last_word = false;
                }
            }
        }
    }
}

/// The value of `uuid(...)` in an attribute list.
fn uuid_of(attributes: &str) -> Option<String> {
    let start = attributes.find("uuid(")? + 5;
    let end = attributes[start..].find(')')? + start;
    Some(attributes[start..end].replace(' ', ""))
}

/// Parses an IDL file's interfaces.
pub fn parse(file: &str, text: &str) -> Result<Vec<Interface>, Error> {
    let (toks, docs) = tokenize(text)?;
    let mut p = Parser {
        toks,
        docs,
        pos: 0,
        file: file.to_string(),
    };
    let mut out = Vec::new();
    let mut attributes = String::new();
    let mut doc = Vec::new();
    while let Some(t) = p.next() {
        match t {
            Tok::Punct('[') => {
                doc = p.take_doc(p.pos - 1);
                attributes = p.group_text('[', ']')?;
            }
            Tok::Punct(';') => {}
            Tok::Ident(word) if word == "import" => {
                while !p.eat(';') {
                    if p.next().is_none() {
                        return p.err("unterminated import");
                    }
                }
            }
            Tok::Ident(word) if word == "cpp_quote" => {
                p.expect('(')?;
                p.group_text('(', ')')?;
            }
            Tok::Ident(word) if word == "library" => {
                p.ident()?;
                p.expect('{')?;
                p.group_text('{', '}')?;
                attributes.clear();
            }
            Tok::Ident(word) if word == "interface" => {
                let name = p.ident()?;
                if p.eat(';') {
                    attributes.clear();
                    continue;
                }
                let base = if p.eat(':') { Some(p.ident()?) } else { None };
                let Some(uuid) = uuid_of(&attributes) else {
                    return p.err(&format!("{name} has no uuid"));
                };
                attributes.clear();
                p.expect('{')?;
                let (typedefs, methods) = parse_body(&mut p)?;
                out.push(Interface {
                    name,
                    base,
                    uuid,
                    typedefs,
                    methods,
                    doc: std::mem::take(&mut doc),
                });
            }
            _ => {
                p.pos -= 1;
                return p.err("unexpected text");
            }
        }
    }
    Ok(out)
}

fn parse_body(p: &mut Parser) -> Result<(Vec<String>, Vec<Method>), Error> {
    let mut typedefs = Vec::new();
    let mut methods = Vec::new();
    let mut doc = Vec::new();
    loop {
        if p.eat('}') {
            return Ok((typedefs, methods));
        }
        let here = p.take_doc(p.pos);
        if !here.is_empty() {
            doc = here;
        }
        if p.eat('[') {
            p.group_text('[', ']')?; // method attributes: nothing in the C declaration
            continue;
        }
        let first = p.ident()?;
        if first == "typedef" {
            doc.clear();
            let mut words = Vec::new();
            loop {
                match p.next() {
                    Some(Tok::Punct(';')) => break,
                    Some(Tok::Punct('[')) => {
                        p.group_text('[', ']')?;
                    }
                    Some(Tok::Ident(s)) => words.push(s),
                    Some(Tok::Punct('*')) => words.push("*".into()),
                    _ => return p.err("unsupported typedef"),
                }
            }
            let Some(tname) = words.pop() else {
                return p.err("empty typedef");
            };
            let decl = Param {
                attributes: String::new(),
                ty: join_type(&words),
                name: tname,
                array: false,
            };
            typedefs.push(decl.declaration());
            continue;
        }
        let ret = first;
        let name = p.ident()?;
        p.expect('(')?;
        let mut params = Vec::new();
        if !p.eat(')') {
            loop {
                let attributes = if p.eat('[') {
                    p.group_text('[', ']')?
                } else {
                    String::new()
                };
                let mut words = Vec::new();
                let mut array = false;
                loop {
                    match p.peek() {
                        Some(Tok::Punct(',')) | Some(Tok::Punct(')')) => break,
                        Some(Tok::Punct('[')) => {
                            p.next();
                            p.expect(']')?;
                            array = true;
                        }
                        Some(Tok::Punct('*')) => {
                            p.next();
                            words.push("*".to_string());
                        }
                        Some(Tok::Ident(_)) => words.push(p.ident()?),
                        _ => return p.err("unsupported parameter"),
                    }
                }
                if words.len() == 1 && words[0] == "void" && attributes.is_empty() {
                    // `()` written as `(void)`
                } else {
                    let Some(pname) = words.pop().filter(|w| w != "*" && !words.is_empty()) else {
                        return p.err("parameter without a type or a name");
                    };
                    params.push(Param {
                        attributes,
                        ty: join_type(&words),
                        name: pname,
                        array,
                    });
                }
                if p.eat(')') {
                    break;
                }
                p.expect(',')?;
            }
        }
        p.expect(';')?;
        methods.push(Method {
            ret,
            name,
            params,
            doc: std::mem::take(&mut doc),
        });
    }
}

/// `["LCID", "*", "*"]` → `LCID **`; `["const", "GUID", "*"]` → `const GUID *`.
fn join_type(words: &[String]) -> String {
    let mut s = String::new();
    for w in words {
        if w == "*" {
            if !s.ends_with('*') {
                s.push(' ');
            }
            s.push('*');
        } else {
            if !s.is_empty() {
                s.push(' ');
            }
            s.push_str(w);
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_an_interface() {
        let text = r#"import "unknwn.idl";
            [object, uuid(F31DFDE2-07B6-11d2-B2D8-0060083BA1FB), pointer_default(unique)]
            interface IOPCCommon : IUnknown {
                typedef [unique] IOPCCommon *LPX;
                HRESULT QueryAvailableLocaleIDs([out] DWORD *pdwCount, [out, size_is(,*pdwCount)] LCID **pdwLcid);
                HRESULT Enum([in] ULONG c, [in, size_is(c)] CATID rg[]);
                HRESULT Reset();
            }
            library L { interface IOPCCommon; };"#;
        let ifs = parse("t.idl", text).unwrap();
        assert_eq!(ifs.len(), 1);
        let i = &ifs[0];
        assert_eq!(i.uuid, "F31DFDE2-07B6-11d2-B2D8-0060083BA1FB");
        assert_eq!(i.base.as_deref(), Some("IUnknown"));
        assert_eq!(i.typedefs, vec!["IOPCCommon *LPX".to_string()]);
        assert_eq!(i.methods[0].params[1].declaration(), "LCID **pdwLcid");
        assert_eq!(i.methods[0].params[1].attributes, "out, size_is(, *pdwCount)");
        assert_eq!(i.methods[1].params[1].declaration(), "CATID rg[]");
        assert!(i.methods[2].params.is_empty());
    }

    #[test]
    fn keeps_the_documentation_of_interfaces_and_methods() {
        let text = r#"// A plain comment documents nothing.
            /// The session.
            ///
            /// Second paragraph.
            [object, uuid(F31DFDE2-07B6-11d2-B2D8-0060083BA1FB)]
            interface IOPCCommon : IUnknown {
                /// Sets the locale.
                HRESULT SetLocaleID([in] LCID dwLcid);
                typedef [unique] IOPCCommon *LPX;
                HRESULT Undocumented();
                /// With attributes.
                [local] HRESULT Local();
            }"#;
        let i = &parse("t.idl", text).unwrap()[0];
        assert_eq!(i.doc, ["The session.", "", "Second paragraph."]);
        assert_eq!(i.methods[0].doc, ["Sets the locale."]);
        assert!(
            i.methods[1].doc.is_empty(),
            "a method takes no documentation from the one before"
        );
        assert_eq!(i.methods[2].doc, ["With attributes."]);
    }

    #[test]
    fn reports_the_line_of_an_error() {
        let e = parse("t.idl", "\n\n[uuid(1)] interface X : IUnknown { HRESULT F(int); }").unwrap_err();
        assert!(e.0.starts_with("t.idl:3:"), "{e}");
    }
}
