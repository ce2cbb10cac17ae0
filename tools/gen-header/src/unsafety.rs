//! Counts the `unsafe` of the library outside the COM core (`src/com/`, where the boundary and the
//! object framework live), per file: `unsafe { }` blocks, `unsafe fn`s (the `unsafe extern` exports
//! and callbacks among them), `unsafe impl`s and `unsafe trait`s, in the code the library is built
//! from (the module tree from `src/lib.rs`, without `#[cfg(test)]` modules and items). Function
//! pointer types (`unsafe extern "C" fn(...)` in a type) are not counted: they declare, not do.
//!
//! docs/dev/architecture.md has a table of these counts by area with the reason for each; `--check`
//! fails when the table and the sources disagree, so that new unsafe code comes with its reason.

use std::collections::BTreeMap;
use std::path::Path;

use proc_macro2::{Delimiter, TokenStream, TokenTree};

/// The counts of one file or area.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Count {
    pub blocks: usize,
    pub fns: usize,
    pub impls: usize,
}

impl std::ops::AddAssign for Count {
    fn add_assign(&mut self, o: Count) {
        self.blocks += o.blocks;
        self.fns += o.fns;
        self.impls += o.impls;
    }
}

/// Whether an attribute's tokens (`cfg(test)`, `cfg(all(test, windows))`) make the item test-only.
fn is_test_cfg(attr: &TokenStream) -> bool {
    let tokens: Vec<TokenTree> = attr.clone().into_iter().collect();
    let [TokenTree::Ident(cfg), TokenTree::Group(args)] = tokens.as_slice() else {
        return false;
    };
    fn mentions(stream: &TokenStream, word: &str) -> bool {
        stream.clone().into_iter().any(|t| match t {
            TokenTree::Ident(i) => i == word,
            TokenTree::Group(g) => mentions(&g.stream(), word),
            _ => false,
        })
    }
    cfg == "cfg" && mentions(&args.stream(), "test") && !mentions(&args.stream(), "not")
}

/// The tokens of `stream` without the items under a test-only `cfg` attribute.
fn without_tests(stream: TokenStream) -> Vec<TokenTree> {
    let tokens: Vec<TokenTree> = stream.into_iter().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        if let (TokenTree::Punct(p), Some(TokenTree::Group(g))) = (&tokens[i], tokens.get(i + 1)) {
            if p.as_char() == '#' && g.delimiter() == Delimiter::Bracket && is_test_cfg(&g.stream()) {
                // Skip the item: up to its first brace group (a body) or its `;`.
                i += 2;
                while i < tokens.len() {
                    match &tokens[i] {
                        TokenTree::Group(g) if g.delimiter() == Delimiter::Brace => break,
                        TokenTree::Punct(p) if p.as_char() == ';' => break,
                        _ => i += 1,
                    }
                }
                i += 1;
                continue;
            }
        }
        out.push(tokens[i].clone());
        i += 1;
    }
    out
}

/// Counts the `unsafe` in `tokens` (and in every group within).
fn count_tokens(tokens: &[TokenTree], count: &mut Count) {
    for (i, t) in tokens.iter().enumerate() {
        match t {
            TokenTree::Group(g) => count_tokens(&without_tests(g.stream()), count),
            TokenTree::Ident(id) if id == "unsafe" => match tokens.get(i + 1) {
                Some(TokenTree::Group(g)) if g.delimiter() == Delimiter::Brace => count.blocks += 1,
                Some(TokenTree::Ident(next)) if next == "impl" || next == "trait" => count.impls += 1,
                Some(TokenTree::Ident(next)) if next == "fn" || next == "extern" => {
                    // `unsafe fn name` / `unsafe extern "C" fn name`, not the type `unsafe fn(...)`.
                    let fn_at = if next == "fn" { i + 1 } else { i + 3 };
                    if matches!(tokens.get(fn_at + 1), Some(TokenTree::Ident(_))) {
                        count.fns += 1;
                    }
                }
                _ => {}
            },
            _ => {}
        }
    }
}

/// The non-test modules a file declares with `mod name;`, each with the file a `#[path = "..."]`
/// attribute before it names (relative to the directory of the file's child modules).
fn child_modules(tokens: &[TokenTree]) -> Vec<(String, Option<String>)> {
    let mut out: Vec<(String, Option<String>)> = Vec::new();
    let mut path = None;
    for (i, t) in tokens.iter().enumerate() {
        match t {
            TokenTree::Group(g) if g.delimiter() == Delimiter::Bracket => {
                let inner: Vec<TokenTree> = g.stream().into_iter().collect();
                if let [TokenTree::Ident(name), TokenTree::Punct(eq), TokenTree::Literal(lit)] = inner.as_slice() {
                    if name == "path" && eq.as_char() == '=' {
                        path = Some(lit.to_string().trim_matches('"').to_string());
                    }
                }
            }
            TokenTree::Group(_) => path = None,
            TokenTree::Punct(p) if p.as_char() == ';' => path = None,
            TokenTree::Ident(m) if m == "mod" => {
                if let (Some(TokenTree::Ident(name)), Some(TokenTree::Punct(semi))) =
                    (tokens.get(i + 1), tokens.get(i + 2))
                {
                    let name = name.to_string();
                    if semi.as_char() == ';' && !out.iter().any(|(n, _)| *n == name) {
                        out.push((name, path.take()));
                    }
                }
                path = None;
            }
            _ => {}
        }
    }
    out
}

fn visit(root: &Path, rel: &str, children_dir: &str, out: &mut BTreeMap<String, Count>) {
    let text = std::fs::read_to_string(root.join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"));
    let stream: TokenStream = text.parse().unwrap_or_else(|e| panic!("{rel}: {e:?}"));
    let tokens = without_tests(stream);
    let mut count = Count::default();
    count_tokens(&tokens, &mut count);
    if count != Count::default() {
        out.insert(rel.to_string(), count);
    }
    for (name, path) in child_modules(&tokens) {
        if let Some(path) = path {
            let file = format!("{children_dir}{path}");
            if !root.join(&file).exists() {
                panic!("{rel}: module {name} not found at {file}");
            }
            // A file named by `#[path]` declares no modules of its own here (generated code).
            visit(root, &file, "", out);
            continue;
        }
        let flat = format!("{children_dir}{name}.rs");
        let nested = format!("{children_dir}{name}/mod.rs");
        let (file, dir) = if root.join(&flat).exists() {
            (flat, format!("{children_dir}{name}/"))
        } else if root.join(&nested).exists() {
            (nested, format!("{children_dir}{name}/"))
        } else {
            panic!("{rel}: module {name} not found");
        };
        if file.starts_with("src/com/") {
            continue;
        }
        visit(root, &file, &dir, out);
    }
}

/// The counts per file of the library outside `src/com/`.
pub fn count(root: &Path) -> BTreeMap<String, Count> {
    let mut out = BTreeMap::new();
    visit(root, "src/lib.rs", "src/", &mut out);
    out
}

/// A row of the documented table: the paths it covers (files, or directories ending in `/`) and its
/// counts.
struct Row {
    paths: Vec<String>,
    count: Count,
    line: String,
}

/// The rows of the table after `marker` in `doc`: `| paths | blocks | fns | impls | why |`.
fn rows(doc: &str, marker: &str) -> Result<Vec<Row>, String> {
    let start = doc.find(marker).ok_or(format!("no `{marker}` in the document"))?;
    let mut rows = Vec::new();
    for line in doc[start..].lines().skip(1).skip_while(|l| !l.starts_with('|')) {
        if !line.starts_with('|') {
            break;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let Some(blocks) = cells.get(2).and_then(|c| c.parse().ok()) else {
            continue; // the head and its rule
        };
        let num = |i: usize| -> Result<usize, String> {
            cells
                .get(i)
                .and_then(|c| c.parse().ok())
                .ok_or(format!("not a count in: {line}"))
        };
        let paths: Vec<String> = cells[1].split('`').skip(1).step_by(2).map(str::to_string).collect();
        rows.push(Row {
            paths,
            count: Count {
                blocks,
                fns: num(3)?,
                impls: num(4)?,
            },
            line: line.to_string(),
        });
    }
    Ok(rows)
}

/// Compares the table after `marker` in `doc` with `counts`: each file belongs to the row with the
/// longest path that covers it, and every row's sums must be its numbers.
pub fn check(doc: &str, marker: &str, counts: &BTreeMap<String, Count>) -> Vec<String> {
    let rows = match rows(doc, marker) {
        Ok(r) => r,
        Err(e) => return vec![e],
    };
    let mut problems = Vec::new();
    let mut sums = vec![Count::default(); rows.len()];
    for (file, c) in counts {
        let best = rows
            .iter()
            .enumerate()
            .flat_map(|(i, r)| r.paths.iter().map(move |p| (i, p)))
            .filter(|(_, p)| *p == file || (p.ends_with('/') && file.starts_with(p.as_str())))
            .max_by_key(|(_, p)| p.len());
        match best {
            Some((i, _)) => sums[i] += *c,
            None => problems.push(format!(
                "{file}: {} unsafe block(s), {} unsafe fn(s), {} unsafe impl(s) in no row of the table",
                c.blocks, c.fns, c.impls
            )),
        }
    }
    for (row, sum) in rows.iter().zip(&sums) {
        if row.count != *sum {
            problems.push(format!(
                "the sources have {} unsafe block(s), {} unsafe fn(s), {} unsafe impl(s) for: {}",
                sum.blocks, sum.fns, sum.impls, row.line
            ));
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count_of(text: &str) -> Count {
        let mut c = Count::default();
        count_tokens(&without_tests(text.parse().unwrap()), &mut c);
        c
    }

    #[test]
    fn blocks_functions_and_impls_are_counted_and_types_and_tests_are_not() {
        let text = r#"
            pub type Cb = Option<unsafe extern "C" fn(context: *mut c_void)>;
            struct S { f: unsafe fn(u32) }
            unsafe impl Send for S {}
            unsafe trait Zero {}
            pub unsafe fn read(p: *const u8) -> u8 { unsafe { *p } }
            #[no_mangle]
            pub unsafe extern "C" fn OpcX(p: *mut u32) -> Hr {
                ffi::boundary!(Opc, [p], { let v = unsafe { ffi::out(p) }?; Ok(S_OK) })
            }
            #[cfg(test)]
            fn helper() { unsafe { risky() } }
            #[cfg(all(test, windows))]
            mod windows_tests { unsafe fn f() {} }
            #[cfg(not(test))]
            fn real() { unsafe { work() } }
            #[cfg(test)]
            mod tests;
        "#;
        assert_eq!(
            count_of(text),
            Count {
                blocks: 3,
                fns: 2,
                impls: 2
            }
        );
    }

    #[test]
    fn the_table_must_account_for_every_file() {
        let doc = "<!-- unsafe -->\n\n| where | blocks | fns | impls | why |\n|---|---|---|---|---|\n\
                   | `src/a/` | 3 | 1 | 0 | reasons |\n| `src/a/win.rs`, `src/b.rs` | 2 | 0 | 1 | more |\n\nafter\n";
        let mut counts = BTreeMap::new();
        counts.insert(
            "src/a/x.rs".to_string(),
            Count {
                blocks: 3,
                fns: 1,
                impls: 0,
            },
        );
        counts.insert(
            "src/a/win.rs".to_string(),
            Count {
                blocks: 1,
                fns: 0,
                impls: 1,
            },
        );
        counts.insert(
            "src/b.rs".to_string(),
            Count {
                blocks: 1,
                fns: 0,
                impls: 0,
            },
        );
        assert_eq!(check(doc, "<!-- unsafe -->", &counts), Vec::<String>::new());
        counts.insert(
            "src/c.rs".to_string(),
            Count {
                blocks: 1,
                fns: 0,
                impls: 0,
            },
        );
        counts.insert(
            "src/b.rs".to_string(),
            Count {
                blocks: 2,
                fns: 0,
                impls: 0,
            },
        );
        let p = check(doc, "<!-- unsafe -->", &counts);
        assert_eq!(p.len(), 2, "{p:?}");
        assert!(p[0].starts_with("src/c.rs: 1 unsafe block(s)"), "{p:?}");
        assert!(
            p[1].contains("3 unsafe block(s), 0 unsafe fn(s), 1 unsafe impl(s) for: | `src/a/win.rs`"),
            "{p:?}"
        );
    }
}
