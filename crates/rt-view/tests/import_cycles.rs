//! No module imports another in a circle, inside folders included.
//!
//! Every `.rs` file under `crates/*/src` is a module (`a/mod.rs` and `a.rs`
//! are module `a`, `lib.rs` the crate root; a `main.rs` beside it is a crate
//! of its own, which reaches the library by its name only). From each
//! file's code outside `#[cfg(test)]` this check collects every path that
//! names a module of the same crate:
//!
//! - `use` declarations, grouped ones included (`use crate::{a::B, c::{d, e}}`),
//!   with `crate::`, `self::`, `super::` (at any depth) or a child module's
//!   name in front, `pub use` re-exports among them;
//! - paths written in code (`crate::sampler::SampleRng::new(…)`,
//!   `super::leaf::LANES`, `leaf::lanes_of(…)`, a name brought in by a
//!   `use`), and string literals that are such a path (serde's
//!   `default = "super::values::yes"`).
//!
//! Each path goes to the deepest module that has a file (`crate::bvh::leaf::LANES`
//! → `bvh/leaf.rs`, `crate::bvh::Bvh` → `bvh/mod.rs`); a name that file only
//! imports or re-exports (`pub use scene::Scene` in `lib.rs`) is followed to
//! the file that defines it, since that is the file the path depends on.
//! Comments, doc links included, are not code and are skipped. A file that
//! uses a name of another file is an edge between them, and the check fails
//!
//! 1. on any cycle among files (a parent `mod.rs` that imports from a child
//!    which imports `super::X` from it is one: `X` belongs in a file of its
//!    own), and
//! 2. on any cycle among folders: in every module with children, each child
//!    that is a folder counts as one node with everything below it, and the
//!    graph among the parent's own file, its child files and its child
//!    folders must be acyclic too.
//!
//! The cycles known and not yet taken apart are listed in [`ALLOWED`], each with
//! its reason; the check fails as well when a listed cycle is gone, so the
//! list only shrinks. Test-only modules (`#[cfg(test)] mod chi_square;`) are
//! not part of the graph. The parser is a small token scanner, enough for the
//! code of this workspace: no macros are expanded, and `#[path]` attributes
//! and `src/bin/` targets are refused rather than misread.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// A cycle this workspace still has, and why it is tolerated for now.
struct Allowed {
    /// The crate's folder name under `crates/`.
    krate: &'static str,
    /// `None` for a cycle among files; for a cycle among folders, the folder
    /// (relative to `src/`, `""` for `src/` itself) at whose level it is.
    level: Option<&'static str>,
    /// The members of the strongly connected component, as the failure
    /// message names them (paths relative to `src/`, folders ending in `/`).
    members: &'static [&'static str],
    /// Why it is still here.
    reason: &'static str,
}

/// Cycles tolerated for now, each with the reason it cannot be taken apart
/// yet. An entry must match one component found exactly (no more, no fewer
/// files), and an entry whose cycle is gone fails the check until it is
/// removed. Empty: there is no cycle to tolerate, and it should stay so.
const ALLOWED: &[Allowed] = &[];

// ---------------------------------------------------------------- tokens

/// A token of Rust source, as far as this check needs one.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    /// An identifier or keyword (raw identifiers without their `r#`).
    Ident(String),
    /// `::`.
    PathSep,
    /// Any other single punctuation character.
    Punct(char),
    /// The contents of a string literal (escapes left as written).
    Str(String),
    /// A number, lifetime or character literal.
    Other,
}

/// A token and the line it starts on.
#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    line: usize,
}

fn is_ident_start(c: char) -> bool {
    c == '_' || c.is_alphabetic()
}

fn is_ident_char(c: char) -> bool {
    c == '_' || c.is_alphanumeric()
}

/// Splits `src` into tokens, dropping whitespace and comments.
fn lex(src: &str) -> Vec<Token> {
    let c: Vec<char> = src.chars().collect();
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    let mut out = Vec::new();
    let mut line = 1;
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        let start_line = line;
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && at(i + 1) == '/' {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && at(i + 1) == '*' {
            // Block comments nest.
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    line += usize::from(c[i] == '\n');
                    i += 1;
                }
            }
        } else if ch == '"' {
            let (text, next) = string_literal(&c, i + 1, &mut line);
            out.push(Token { tok: Tok::Str(text), line: start_line });
            i = next;
        } else if ch == '\'' {
            i = char_or_lifetime(&c, i, &mut line);
            out.push(Token { tok: Tok::Other, line: start_line });
        } else if is_ident_start(ch) {
            let begin = i;
            while i < c.len() && is_ident_char(c[i]) {
                i += 1;
            }
            let word: String = c[begin..i].iter().collect();
            match (word.as_str(), at(i)) {
                ("r" | "br" | "cr", '#' | '"') if raw_string_follows(&c, i) => {
                    let (text, next) = raw_string_literal(&c, i, &mut line);
                    out.push(Token { tok: Tok::Str(text), line: start_line });
                    i = next;
                }
                ("r", '#') if is_ident_start(at(i + 1)) => {
                    // A raw identifier, `r#type`.
                    let begin = i + 1;
                    i += 1;
                    while i < c.len() && is_ident_char(c[i]) {
                        i += 1;
                    }
                    out.push(Token { tok: Tok::Ident(c[begin..i].iter().collect()), line: start_line });
                }
                ("b" | "c", '"') => {
                    let (text, next) = string_literal(&c, i + 1, &mut line);
                    out.push(Token { tok: Tok::Str(text), line: start_line });
                    i = next;
                }
                ("b", '\'') => {
                    i = char_or_lifetime(&c, i, &mut line);
                    out.push(Token { tok: Tok::Other, line: start_line });
                }
                _ => out.push(Token { tok: Tok::Ident(word), line: start_line }),
            }
        } else if ch.is_ascii_digit() {
            while i < c.len() && (is_ident_char(c[i]) || (c[i] == '.' && at(i + 1).is_ascii_digit())) {
                i += 1;
            }
            out.push(Token { tok: Tok::Other, line: start_line });
        } else if ch == ':' && at(i + 1) == ':' {
            out.push(Token { tok: Tok::PathSep, line: start_line });
            i += 2;
        } else {
            out.push(Token { tok: Tok::Punct(ch), line: start_line });
            i += 1;
        }
    }
    out
}

/// The contents of the string literal whose text starts at `i` (after the
/// opening quote), and the index after its closing quote.
fn string_literal(c: &[char], mut i: usize, line: &mut usize) -> (String, usize) {
    let begin = i;
    while i < c.len() && c[i] != '"' {
        if c[i] == '\\' {
            i += 1;
        }
        if c.get(i) == Some(&'\n') {
            *line += 1;
        }
        i += 1;
    }
    (c[begin..i.min(c.len())].iter().collect(), i + 1)
}

/// Whether `c[i..]` (after an `r`, `br` or `cr`) is `#…#"`: a raw string.
fn raw_string_follows(c: &[char], mut i: usize) -> bool {
    while c.get(i) == Some(&'#') {
        i += 1;
    }
    c.get(i) == Some(&'"')
}

/// The contents of the raw string whose hashes start at `i`, and the index
/// after it.
fn raw_string_literal(c: &[char], mut i: usize, line: &mut usize) -> (String, usize) {
    let mut hashes = 0;
    while c.get(i) == Some(&'#') {
        hashes += 1;
        i += 1;
    }
    i += 1;
    let begin = i;
    while i < c.len() {
        if c[i] == '"' && (1..=hashes).all(|k| c.get(i + k) == Some(&'#')) {
            return (c[begin..i].iter().collect(), i + 1 + hashes);
        }
        *line += usize::from(c[i] == '\n');
        i += 1;
    }
    (c[begin..].iter().collect(), c.len())
}

/// Skips the character literal or lifetime whose quote is at or right after
/// `i` (`'x'`, `'\n'`, `'{'`, `b'x'`, `'a`), returning the index after it.
fn char_or_lifetime(c: &[char], mut i: usize, line: &mut usize) -> usize {
    if c[i] != '\'' {
        i += 1; // the `b` of a byte literal
    }
    let at = |k: usize| c.get(k).copied().unwrap_or('\0');
    if at(i + 1) == '\\' {
        let mut k = i + 3;
        while k < c.len() && c[k] != '\'' {
            k += 1;
        }
        k + 1
    } else if at(i + 2) == '\'' {
        *line += usize::from(at(i + 1) == '\n');
        i + 3
    } else {
        let mut k = i + 1;
        while k < c.len() && is_ident_char(c[k]) {
            k += 1;
        }
        k
    }
}

fn is(t: Option<&Token>, want: &Tok) -> bool {
    t.is_some_and(|t| &t.tok == want)
}

fn ident(t: Option<&Token>) -> Option<&str> {
    match t.map(|t| &t.tok) {
        Some(Tok::Ident(s)) => Some(s),
        _ => None,
    }
}

fn opens(t: &Tok) -> bool {
    matches!(t, Tok::Punct('(' | '[' | '{'))
}

fn closes(t: &Tok) -> bool {
    matches!(t, Tok::Punct(')' | ']' | '}'))
}

// ------------------------------------------------------- test-only code

/// A file's tokens without its `#[cfg(test)]` items.
struct NonTest {
    tokens: Vec<Token>,
    /// Child modules declared `#[cfg(test)] mod name;`.
    test_modules: Vec<String>,
    /// The file starts with `#![cfg(test)]`.
    test_only: bool,
}

/// Whether the attribute's contents are `cfg(test)` or `cfg(all(…, test, …))`.
fn is_cfg_test(attr: &[Token]) -> bool {
    let t: Vec<&Tok> = attr.iter().map(|t| &t.tok).collect();
    let word = |s: &str| Tok::Ident(s.to_string());
    if t.len() < 4 || *t[0] != word("cfg") || *t[1] != Tok::Punct('(') {
        return false;
    }
    if *t[2] == word("test") && *t[3] == Tok::Punct(')') {
        return true;
    }
    if *t[2] != word("all") || *t[3] != Tok::Punct('(') {
        return false;
    }
    // A direct argument of `all(…)`.
    let mut depth = 0;
    for k in 4..t.len() {
        match t[k] {
            Tok::Punct('(') => depth += 1,
            Tok::Punct(')') if depth == 0 => return false,
            Tok::Punct(')') => depth -= 1,
            Tok::Ident(s) if s == "test" && depth == 0 => {
                return matches!(t.get(k + 1), Some(Tok::Punct(',' | ')')));
            }
            _ => {}
        }
    }
    false
}

/// The index after the bracketed group that opens at `i`.
fn skip_group(tokens: &[Token], mut i: usize) -> usize {
    let mut depth = 0;
    while i < tokens.len() {
        if opens(&tokens[i].tok) {
            depth += 1;
        } else if closes(&tokens[i].tok) {
            depth -= 1;
            if depth == 0 {
                return i + 1;
            }
        }
        i += 1;
    }
    i
}

/// The index after the item (or field, statement, block) that starts at `i`:
/// after its `;` or `,`, or after its closing brace; at the `}` of the
/// enclosing block if that comes first.
fn skip_item(tokens: &[Token], mut i: usize) -> usize {
    let mut depth = 0;
    while i < tokens.len() {
        let t = &tokens[i].tok;
        if depth == 0 && matches!(t, Tok::Punct(';' | ',')) {
            return i + 1;
        }
        if closes(t) {
            if depth == 0 {
                return i;
            }
            depth -= 1;
            if depth == 0 && *t == Tok::Punct('}') {
                return i + 1;
            }
        } else if opens(t) {
            depth += 1;
        }
        i += 1;
    }
    i
}

/// The name of `mod name;` if `item` declares a module in a file of its own.
fn declared_module(item: &[Token]) -> Option<String> {
    let mut k = 0;
    if ident(item.get(k)) == Some("pub") {
        k += 1;
        if is(item.get(k), &Tok::Punct('(')) {
            k = skip_group(item, k);
        }
    }
    if ident(item.get(k)) == Some("mod") && is(item.get(k + 2), &Tok::Punct(';')) {
        ident(item.get(k + 1)).map(str::to_string)
    } else {
        None
    }
}

/// Drops every item gated by `#[cfg(test)]` from `tokens`.
fn strip_test_code(tokens: &[Token]) -> NonTest {
    let mut out = NonTest { tokens: Vec::new(), test_modules: Vec::new(), test_only: false };
    let mut i = 0;
    while i < tokens.len() {
        let inner = is(tokens.get(i + 1), &Tok::Punct('!'));
        let bracket = if inner { i + 2 } else { i + 1 };
        if !(is(tokens.get(i), &Tok::Punct('#')) && is(tokens.get(bracket), &Tok::Punct('['))) {
            out.tokens.push(tokens[i].clone());
            i += 1;
            continue;
        }
        let end = skip_group(tokens, bracket);
        let attr = &tokens[bracket + 1..end.saturating_sub(1).max(bracket + 1)];
        if !is_cfg_test(attr) {
            out.tokens.extend_from_slice(&tokens[i..end]);
            i = end;
        } else if inner {
            out.test_only = true;
            i = end;
        } else {
            // Further attributes of the same item, then the item.
            let mut item = end;
            while is(tokens.get(item), &Tok::Punct('#')) && is(tokens.get(item + 1), &Tok::Punct('[')) {
                item = skip_group(tokens, item + 1);
            }
            let next = skip_item(tokens, item);
            out.test_modules.extend(declared_module(&tokens[item..next]));
            i = next;
        }
    }
    out
}

// ------------------------------------------------------------ references

/// A path written in a file, from a `use` or from code.
#[derive(Clone, Debug)]
struct Reference {
    /// Its segments as written (`super`, `crate`, `self` included).
    segments: Vec<String>,
    /// The inline modules (`mod name { … }`) it is written in.
    scope: Vec<String>,
    line: usize,
    /// From a `use`: the name it binds (`None` for globs and `as _`).
    binds: Option<String>,
}

impl Reference {
    fn text(&self) -> String {
        self.segments.join("::")
    }
}

/// What one file says: the paths it uses and the modules it declares.
#[derive(Default, Debug)]
struct Scanned {
    uses: Vec<Reference>,
    paths: Vec<Reference>,
    /// `mod name;` outside test code.
    modules: Vec<String>,
}

/// Reads the use tree at `tokens[*i]` under `prefix` into `out`.
fn use_tree(
    tokens: &[Token],
    i: &mut usize,
    prefix: Vec<String>,
    scope: &[String],
    line: usize,
    out: &mut Vec<Reference>,
) {
    let mut segments = prefix;
    if is(tokens.get(*i), &Tok::PathSep) {
        // `::name`: an outside crate.
        segments.push(String::new());
        *i += 1;
    }
    let leaf = |segments: Vec<String>, binds: Option<String>| Reference {
        segments,
        scope: scope.to_vec(),
        line,
        binds,
    };
    loop {
        match tokens.get(*i).map(|t| &t.tok) {
            Some(Tok::Ident(s)) => {
                segments.push(s.clone());
                *i += 1;
                if is(tokens.get(*i), &Tok::PathSep) {
                    *i += 1;
                } else {
                    break;
                }
            }
            Some(Tok::Punct('*')) => {
                *i += 1;
                out.push(leaf(segments, None));
                return;
            }
            Some(Tok::Punct('{')) => {
                *i += 1;
                while *i < tokens.len() && !is(tokens.get(*i), &Tok::Punct('}')) {
                    let before = *i;
                    use_tree(tokens, i, segments.clone(), scope, line, out);
                    if is(tokens.get(*i), &Tok::Punct(',')) {
                        *i += 1;
                    }
                    if *i == before {
                        *i += 1; // not a use tree: skip it rather than loop
                    }
                }
                *i += 1;
                return;
            }
            _ => return,
        }
    }
    if segments.last().is_some_and(|s| s == "self") {
        segments.pop();
    }
    let mut binds = segments.last().cloned();
    if ident(tokens.get(*i)) == Some("as") {
        binds = ident(tokens.get(*i + 1)).filter(|a| *a != "_").map(str::to_string);
        *i += 2;
    }
    out.push(leaf(segments, binds));
}

/// Collects the `use` declarations, code paths and module declarations of
/// a file's non-test tokens.
fn scan(tokens: &[Token]) -> Scanned {
    let mut out = Scanned::default();
    let mut scope: Vec<(String, usize)> = Vec::new(); // inline module, brace depth inside it
    let mut depth = 0;
    let mut i = 0;
    let names = |s: &[(String, usize)]| s.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
    while i < tokens.len() {
        let t = &tokens[i];
        match &t.tok {
            Tok::Punct('{') => depth += 1,
            Tok::Punct('}') => {
                depth -= 1;
                if scope.last().is_some_and(|&(_, d)| depth < d) {
                    scope.pop();
                }
            }
            Tok::Ident(w) if w == "mod" => {
                if let Some(name) = ident(tokens.get(i + 1)) {
                    if is(tokens.get(i + 2), &Tok::Punct('{')) {
                        scope.push((name.to_string(), depth + 1));
                    } else if is(tokens.get(i + 2), &Tok::Punct(';')) && scope.is_empty() {
                        out.modules.push(name.to_string());
                    }
                }
            }
            // `use<'a>` is a precise-capturing bound, not an import.
            Tok::Ident(w) if w == "use" && !is(tokens.get(i + 1), &Tok::Punct('<')) => {
                i += 1;
                let here = names(&scope);
                while i < tokens.len() && !is(tokens.get(i), &Tok::Punct(';')) {
                    let before = i;
                    use_tree(tokens, &mut i, Vec::new(), &here, t.line, &mut out.uses);
                    if i == before {
                        i += 1;
                    }
                }
                i += 1;
                continue;
            }
            // The start of a path (not its middle), but not the module of a
            // `pub(in crate::a)`, which names where an item is visible.
            Tok::Ident(first)
                if is(tokens.get(i + 1), &Tok::PathSep)
                    && !matches!(i.checked_sub(1).map(|k| &tokens[k].tok), Some(Tok::PathSep))
                    && !(i >= 2
                        && ident(tokens.get(i - 1)) == Some("in")
                        && is(tokens.get(i - 2), &Tok::Punct('('))) =>
            {
                let mut segments = vec![first.clone()];
                let mut k = i + 1;
                while is(tokens.get(k), &Tok::PathSep) {
                    match ident(tokens.get(k + 1)) {
                        Some(s) => segments.push(s.to_string()),
                        None => break,
                    }
                    k += 2;
                }
                if segments.len() > 1 {
                    out.paths.push(Reference { segments, scope: names(&scope), line: t.line, binds: None });
                }
                i = k;
                continue;
            }
            Tok::Str(s) => {
                let segments: Vec<String> = s.split("::").map(str::to_string).collect();
                let word =
                    |w: &String| w.chars().next().is_some_and(is_ident_start) && w.chars().all(is_ident_char);
                if segments.len() > 1
                    && matches!(segments[0].as_str(), "crate" | "super" | "self")
                    && segments.iter().all(word)
                {
                    out.paths.push(Reference { segments, scope: names(&scope), line: t.line, binds: None });
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

// ----------------------------------------------------------- resolution

/// One file of a crate.
struct File {
    /// Path relative to the crate's `src/`.
    path: String,
    /// Module path from the crate root (`[]` for `lib.rs`).
    module: Vec<String>,
    scanned: Scanned,
    /// Not part of the graph: compiled for tests only.
    test_only: bool,
    /// A binary's `main.rs` beside a `lib.rs`: a crate of its own, which
    /// reaches the library by its name only.
    separate_root: bool,
}

/// The module path of the file at `path` (relative to `src/`).
fn module_of(path: &str) -> Vec<String> {
    let mut parts: Vec<String> = path.trim_end_matches(".rs").split('/').map(str::to_string).collect();
    let last = parts.pop().unwrap_or_default();
    let top = parts.is_empty();
    if !(last == "mod" || (top && (last == "lib" || last == "main"))) {
        parts.push(last);
    }
    parts
}

/// The module graph of one crate.
struct Crate {
    files: Vec<File>,
    by_module: BTreeMap<Vec<String>, usize>,
}

/// How deep a chain of `use` bindings is followed (a guard against loops).
const MAX_HOPS: usize = 16;

impl Crate {
    /// Reads the crate's files (`(path relative to src/, text)`).
    fn new(sources: &[(String, String)]) -> Crate {
        let has_lib = sources.iter().any(|(p, _)| p == "lib.rs");
        let mut files = Vec::new();
        for (path, text) in sources {
            assert!(!path.starts_with("bin/"), "{path}: src/bin targets are not modelled by this check");
            let tokens = lex(text);
            let path_attribute = tokens.windows(3).any(|w| {
                w[0].tok == Tok::Punct('#')
                    && w[1].tok == Tok::Punct('[')
                    && ident(Some(&w[2])) == Some("path")
            });
            assert!(!path_attribute, "{path}: #[path] attributes are not modelled by this check");
            let stripped = strip_test_code(&tokens);
            let scanned = scan(&stripped.tokens);
            let separate_root = has_lib && path == "main.rs";
            assert!(
                !separate_root || scanned.modules.is_empty(),
                "main.rs declares modules beside lib.rs: this check does not model a binary with modules of its own"
            );
            files.push((path.clone(), stripped, scanned, separate_root));
        }
        // Modules declared `#[cfg(test)] mod name;`, and everything below them.
        let test_roots: BTreeSet<Vec<String>> = files
            .iter()
            .flat_map(|(path, stripped, _, _)| {
                let parent = module_of(path);
                stripped.test_modules.iter().map(move |m| [parent.clone(), vec![m.clone()]].concat())
            })
            .collect();
        let files: Vec<File> = files
            .into_iter()
            .map(|(path, stripped, scanned, separate_root)| {
                let module = module_of(&path);
                let test_only =
                    stripped.test_only || (1..=module.len()).any(|k| test_roots.contains(&module[..k]));
                File { path, module, scanned, test_only, separate_root }
            })
            .collect();
        let by_module = files
            .iter()
            .enumerate()
            .filter(|(_, f)| !f.separate_root)
            .map(|(k, f)| (f.module.clone(), k))
            .collect();
        Crate { files, by_module }
    }

    /// The full module path (from the crate root) that `segments`, written
    /// in `file` inside the inline modules `scope`, names; `None` for paths
    /// into other crates, local types and variables.
    fn absolute(
        &self,
        file: usize,
        scope: &[String],
        segments: &[String],
        hops: usize,
    ) -> Option<Vec<String>> {
        let f = &self.files[file];
        if f.separate_root || hops > MAX_HOPS || segments.is_empty() {
            return None;
        }
        let here = [f.module.clone(), scope.to_vec()].concat();
        let (mut base, mut rest) = match segments[0].as_str() {
            "crate" => (Vec::new(), &segments[1..]),
            "self" => (here, &segments[1..]),
            "super" => {
                let mut base = here;
                let mut k = 0;
                while segments.get(k).is_some_and(|s| s == "super") {
                    base.pop()?;
                    k += 1;
                }
                (base, &segments[k..])
            }
            name => {
                let bound =
                    f.scanned.uses.iter().find(|u| u.binds.as_deref() == Some(name) && u.scope == scope);
                if let Some(u) = bound {
                    (self.absolute(file, &u.scope, &u.segments, hops + 1)?, &segments[1..])
                } else if self.by_module.contains_key(&[here.clone(), vec![name.to_string()]].concat()) {
                    (here, segments)
                } else {
                    return None;
                }
            }
        };
        if rest.first().is_some_and(|s| s == "self") {
            rest = &rest[1..];
        }
        base.extend_from_slice(rest);
        Some(base)
    }

    /// The file that defines what the full path `path` names: the deepest
    /// module with a file, or, where that file only imports the name, the
    /// file it imports it from.
    fn defining_file(&self, path: &[String], hops: usize) -> Option<usize> {
        let (k, &file) =
            (0..=path.len()).rev().find_map(|k| self.by_module.get(&path[..k]).map(|f| (k, f)))?;
        let Some(name) = path.get(k) else { return Some(file) };
        let import = self.files[file]
            .scanned
            .uses
            .iter()
            .find(|u| u.binds.as_ref() == Some(name) && u.scope.is_empty());
        let imported = import
            .filter(|_| hops < MAX_HOPS)
            .and_then(|u| self.absolute(file, &[], &u.segments, hops + 1))
            .and_then(|target| self.defining_file(&[target, path[k + 1..].to_vec()].concat(), hops + 1));
        Some(imported.unwrap_or(file))
    }

    /// Every edge between files outside test code, with the paths (and
    /// their lines) that make it.
    fn edges(&self) -> BTreeMap<(usize, usize), Vec<String>> {
        let mut edges: BTreeMap<(usize, usize), Vec<String>> = BTreeMap::new();
        for (from, f) in self.files.iter().enumerate() {
            if f.test_only {
                continue;
            }
            for r in f.scanned.uses.iter().chain(&f.scanned.paths) {
                let Some(to) =
                    self.absolute(from, &r.scope, &r.segments, 0).and_then(|p| self.defining_file(&p, 0))
                else {
                    continue;
                };
                if to != from && !self.files[to].test_only {
                    let why = format!("{} (line {})", r.text(), r.line);
                    let list = edges.entry((from, to)).or_default();
                    if !list.contains(&why) {
                        list.push(why);
                    }
                }
            }
        }
        edges
    }
}

// --------------------------------------------------------------- cycles

/// The strongly connected components with more than one node (Tarjan).
fn components(n: usize, edges: &BTreeSet<(usize, usize)>) -> Vec<Vec<usize>> {
    struct State<'a> {
        next: Vec<Vec<usize>>,
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        counter: usize,
        out: &'a mut Vec<Vec<usize>>,
    }
    fn visit(s: &mut State, v: usize) {
        s.index[v] = Some(s.counter);
        s.low[v] = s.counter;
        s.counter += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for w in s.next[v].clone() {
            match s.index[w] {
                None => {
                    visit(s, w);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                _ => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack[w] = false;
                component.push(w);
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.out.push(component);
            }
        }
    }
    let mut next = vec![Vec::new(); n];
    for &(a, b) in edges {
        if a != b {
            next[a].push(b);
        }
    }
    let mut out = Vec::new();
    let mut s = State {
        next,
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        counter: 0,
        out: &mut out,
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(&mut s, v);
        }
    }
    out.sort();
    out
}

/// The elementary cycles through `component` (at most `limit`), each from
/// its smallest node back to it.
fn cycles_in(component: &[usize], edges: &BTreeSet<(usize, usize)>, limit: usize) -> Vec<Vec<usize>> {
    fn walk(
        path: &mut Vec<usize>,
        start: usize,
        allowed: &BTreeSet<usize>,
        edges: &BTreeSet<(usize, usize)>,
        out: &mut Vec<Vec<usize>>,
        limit: usize,
    ) {
        let v = *path.last().unwrap();
        for &(_, w) in edges.range((v, 0)..(v + 1, 0)) {
            if out.len() >= limit {
                return;
            }
            if w == start {
                out.push([path.clone(), vec![start]].concat());
            } else if w > start && allowed.contains(&w) && !path.contains(&w) {
                path.push(w);
                walk(path, start, allowed, edges, out, limit);
                path.pop();
            }
        }
    }
    let allowed: BTreeSet<usize> = component.iter().copied().collect();
    let mut out = Vec::new();
    for &start in component {
        walk(&mut vec![start], start, &allowed, edges, &mut out, limit);
    }
    out
}

/// One strongly connected component found, described for a reader.
#[derive(Debug)]
struct Cycle {
    krate: String,
    /// `None` among files; the folder whose level it is at otherwise.
    level: Option<String>,
    /// Its members, sorted (paths relative to `src/`, folders ending in `/`).
    members: Vec<String>,
    /// Its cycles and the paths that make each edge.
    description: String,
}

/// Describes the component `component` of a graph whose nodes are named
/// `names`, with the paths behind each edge in `why`.
fn describe(
    component: &[usize],
    names: &[String],
    edges: &BTreeSet<(usize, usize)>,
    why: &BTreeMap<(usize, usize), Vec<String>>,
) -> String {
    const LIMIT: usize = 20;
    let cycles = cycles_in(component, edges, LIMIT + 1);
    let mut text = String::new();
    for cycle in cycles.iter().take(LIMIT) {
        let line: Vec<&str> = cycle.iter().map(|&v| names[v].as_str()).collect();
        text += &format!("    {}\n", line.join(" → "));
    }
    if cycles.len() > LIMIT {
        text += "    … and more\n";
    }
    text += "  made by:\n";
    for &(a, b) in edges {
        if component.contains(&a) && component.contains(&b) {
            text += &format!("    {} → {}: {}\n", names[a], names[b], why[&(a, b)].join(", "));
        }
    }
    text
}

/// The cycles of the crate `krate` (sources as `(path relative to src/, text)`),
/// among files and among folders.
fn find_cycles(krate: &str, sources: &[(String, String)]) -> Vec<Cycle> {
    let c = Crate::new(sources);
    let why = c.edges();
    let names: Vec<String> = c.files.iter().map(|f| f.path.clone()).collect();
    let edges: BTreeSet<(usize, usize)> = why.keys().copied().collect();
    let mut out: Vec<Cycle> = components(c.files.len(), &edges)
        .into_iter()
        .map(|component| Cycle {
            krate: krate.to_string(),
            level: None,
            members: component.iter().map(|&v| names[v].clone()).collect(),
            description: describe(&component, &names, &edges, &why),
        })
        .collect();

    // Folder levels: every module whose children include a folder.
    let mut parents: BTreeSet<Vec<String>> = BTreeSet::new();
    for f in c.files.iter().filter(|f| !f.test_only && !f.separate_root) {
        for k in 0..f.module.len().saturating_sub(1) {
            parents.insert(f.module[..k].to_vec());
        }
    }
    for parent in parents {
        // Units: the parent's own file, and each child with everything below it.
        let mut unit_names: Vec<String> = Vec::new();
        let mut unit_of: BTreeMap<usize, usize> = BTreeMap::new();
        for (v, f) in c.files.iter().enumerate() {
            if f.test_only || f.separate_root || !f.module.starts_with(&parent) {
                continue;
            }
            let name = if f.module.len() == parent.len() {
                f.path.clone()
            } else {
                let child = [parent.clone(), vec![f.module[parent.len()].clone()]].concat();
                let has_children =
                    c.files.iter().any(|g| g.module.len() > child.len() && g.module.starts_with(&child));
                if has_children {
                    format!("{}/", child.join("/"))
                } else {
                    c.files[c.by_module[&child]].path.clone()
                }
            };
            let unit = unit_names.iter().position(|n| *n == name).unwrap_or_else(|| {
                unit_names.push(name);
                unit_names.len() - 1
            });
            unit_of.insert(v, unit);
        }
        let mut unit_why: BTreeMap<(usize, usize), Vec<String>> = BTreeMap::new();
        for (&(a, b), paths) in &why {
            if let (Some(&ua), Some(&ub)) = (unit_of.get(&a), unit_of.get(&b))
                && ua != ub
            {
                let list = unit_why.entry((ua, ub)).or_default();
                list.extend(paths.iter().map(|p| format!("{p} in {}", names[a])));
            }
        }
        let unit_edges: BTreeSet<(usize, usize)> = unit_why.keys().copied().collect();
        for component in components(unit_names.len(), &unit_edges) {
            // A component of single files only is already a file cycle above.
            if component.iter().any(|&u| unit_names[u].ends_with('/')) {
                out.push(Cycle {
                    krate: krate.to_string(),
                    level: Some(parent.join("/")),
                    members: component.iter().map(|&u| unit_names[u].clone()).collect(),
                    description: describe(&component, &unit_names, &unit_edges, &unit_why),
                });
            }
        }
    }
    for cycle in &mut out {
        cycle.members.sort();
    }
    out
}

// ---------------------------------------------------------------- the check

/// The `.rs` files under `dir`, as `(path relative to root, text)`.
fn read_sources(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            read_sources(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let rel = path.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/");
            out.push((rel, std::fs::read_to_string(&path).unwrap()));
        }
    }
}

fn is_allowed(cycle: &Cycle, allowed: &Allowed) -> bool {
    allowed.krate == cycle.krate
        && allowed.level == cycle.level.as_deref()
        && allowed.members.iter().copied().eq(cycle.members.iter().map(String::as_str))
}

fn place(krate: &str, level: Option<&str>) -> String {
    match level {
        None => format!("{krate}, a cycle among files"),
        Some(level) => {
            let folder = if level.is_empty() { String::new() } else { format!("{level}/") };
            format!("{krate}, a cycle among the files and folders of src/{folder} (a folder counts as one)")
        }
    }
}

#[test]
fn no_module_imports_another_in_a_circle() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut names: Vec<String> = std::fs::read_dir(&crates)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("src").is_dir())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(
        names.iter().any(|n| n == "rt-core") && names.iter().any(|n| n == "rt-view"),
        "crates found: {names:?}"
    );

    let mut found = Vec::new();
    for name in &names {
        let src = crates.join(name).join("src");
        let mut sources = Vec::new();
        read_sources(&src, &src, &mut sources);
        found.extend(find_cycles(name, &sources));
    }

    let mut failures = String::new();
    for cycle in found.iter().filter(|c| !ALLOWED.iter().any(|a| is_allowed(c, a))) {
        failures += &format!("{}:\n{}\n", place(&cycle.krate, cycle.level.as_deref()), cycle.description);
    }
    if !failures.is_empty() {
        failures = format!(
            "modules import each other in a circle; move the names both need into a file of \
             their own (or the file of the concept they belong to):\n\n{failures}"
        );
    }
    for allowed in ALLOWED.iter().filter(|a| !found.iter().any(|c| is_allowed(c, a))) {
        failures += &format!(
            "{} {{{}}} is listed in ALLOWED ({}) but no longer a cycle as listed: remove or update its entry\n",
            place(allowed.krate, allowed.level),
            allowed.members.join(", "),
            allowed.reason
        );
    }
    assert!(failures.is_empty(), "{failures}");
}

/// Prints every edge of the graph with the paths that make it:
/// `cargo test -p rt-view --test import_cycles -- --ignored --nocapture`.
#[test]
#[ignore = "prints the import graph"]
fn print_the_import_graph() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for name in ["rt-core", "rt-view"] {
        let src = crates.join(name).join("src");
        let mut sources = Vec::new();
        read_sources(&src, &src, &mut sources);
        let c = Crate::new(&sources);
        for f in c.files.iter().filter(|f| f.test_only) {
            println!("{name} {} (tests only, left out)", f.path);
        }
        for ((a, b), why) in c.edges() {
            println!("{name} {} → {}: {}", c.files[a].path, c.files[b].path, why.join(", "));
        }
    }
}

// ------------------------------------------------- tests of the checker

/// In-memory sources for the checker.
fn sources(files: &[(&str, &str)]) -> Vec<(String, String)> {
    files.iter().map(|(p, t)| (p.to_string(), t.to_string())).collect()
}

/// The edges of the crate `files`, as `from → to` path pairs.
fn edge_names(files: &[(&str, &str)]) -> BTreeSet<(String, String)> {
    let c = Crate::new(&sources(files));
    c.edges().keys().map(|&(a, b)| (c.files[a].path.clone(), c.files[b].path.clone())).collect()
}

fn pair(a: &str, b: &str) -> (String, String) {
    (a.to_string(), b.to_string())
}

#[test]
fn two_files_that_import_each_other_are_a_cycle() {
    let found = find_cycles(
        "fake",
        &sources(&[
            ("lib.rs", "mod a;\nmod b;\n"),
            ("a.rs", "use crate::b::B;\npub struct A;\n"),
            ("b.rs", "pub struct B;\nfn f() -> crate::a::A { crate::a::A }\n"),
        ]),
    );
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].members, ["a.rs", "b.rs"]);
    assert!(found[0].description.contains("a.rs → b.rs → a.rs"), "{}", found[0].description);
    assert!(found[0].description.contains("crate::a::A (line 2)"), "{}", found[0].description);
}

#[test]
fn files_that_import_in_one_direction_are_no_cycle() {
    let found = find_cycles(
        "fake",
        &sources(&[
            ("lib.rs", "pub mod a;\npub mod b;\npub use a::A;\n"),
            ("a.rs", "use crate::b::B;\n"),
            ("b.rs", ""),
        ]),
    );
    assert!(found.is_empty(), "{found:?}");
}

#[test]
fn grouped_imports_resolve_each_path_to_its_deepest_file() {
    let edges = edge_names(&[
        ("lib.rs", "mod a;\nmod c;\nmod x;\n"),
        ("a.rs", "pub struct B;\n"),
        ("c/mod.rs", "mod d;\npub mod e;\n"),
        ("c/d.rs", ""),
        ("c/e.rs", "pub fn f() {}\n"),
        ("x.rs", "use crate::{a::B, c::{d, e::f, self}};\n"),
    ]);
    let from_x: BTreeSet<_> = edges.iter().filter(|(a, _)| a == "x.rs").cloned().collect();
    assert_eq!(
        from_x,
        [pair("x.rs", "a.rs"), pair("x.rs", "c/d.rs"), pair("x.rs", "c/e.rs"), pair("x.rs", "c/mod.rs")]
            .into()
    );
}

#[test]
fn super_paths_climb_one_module_per_super() {
    let edges = edge_names(&[
        ("lib.rs", "mod x;\n"),
        ("x/mod.rs", "mod w;\nmod y;\n"),
        ("x/w.rs", "pub const V: u8 = 1;\n"),
        ("x/y/mod.rs", "mod z;\n"),
        ("x/y/z.rs", "fn f() -> u8 { super::super::w::V }\nuse super::Q;\n"),
    ]);
    assert!(edges.contains(&pair("x/y/z.rs", "x/w.rs")), "{edges:?}");
    assert!(edges.contains(&pair("x/y/z.rs", "x/y/mod.rs")), "{edges:?}");
}

#[test]
fn a_parent_that_re_exports_a_child_using_its_names_is_a_cycle() {
    let found = find_cycles(
        "fake",
        &sources(&[
            ("lib.rs", "mod bvh;\n"),
            ("bvh/mod.rs", "mod leaf;\npub use leaf::Leaf;\nconst WIDTH: usize = 8;\n"),
            ("bvh/leaf.rs", "pub struct Leaf([u8; super::WIDTH]);\n"),
        ]),
    );
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].members, ["bvh/leaf.rs", "bvh/mod.rs"]);
}

#[test]
fn a_name_imported_through_a_re_export_depends_on_the_file_defining_it() {
    let edges = edge_names(&[
        ("lib.rs", "mod scene;\nmod color;\npub use color::Color;\n"),
        ("color.rs", "pub struct Color;\n"),
        ("scene.rs", "use crate::Color;\n"),
    ]);
    assert_eq!(edges, [pair("lib.rs", "color.rs"), pair("scene.rs", "color.rs")].into());
}

#[test]
fn child_modules_and_use_bindings_in_code_paths_count() {
    let edges = edge_names(&[
        ("lib.rs", "mod bvh;\nmod sampler;\n"),
        ("sampler.rs", "pub struct SampleRng;\n"),
        (
            "bvh/mod.rs",
            "mod leaf;\nuse crate::sampler;\nfn f() { leaf::lanes(); let r = sampler::SampleRng; }\n",
        ),
        ("bvh/leaf.rs", "pub fn lanes() {}\n"),
    ]);
    assert_eq!(edges, [pair("bvh/mod.rs", "bvh/leaf.rs"), pair("bvh/mod.rs", "sampler.rs")].into());
}

#[test]
fn test_code_comments_and_strings_are_not_imports() {
    // Braces in character and string literals must not end a test item early.
    let edges = edge_names(&[
        ("lib.rs", "mod a;\nmod b;\n#[cfg(test)]\nmod helpers;\n"),
        ("a.rs", "use crate::b::B;\npub struct A;\n"),
        (
            "b.rs",
            "pub struct B;\n// crate::a::A\n/* crate::a::A /* nested */ crate::a::A */\n\
             /// [`crate::a::A`]\nconst S: &str = \"see crate::a::A\";\nconst C: char = '{';\n\
             #[cfg(test)]\nfn helper() { let c = '}'; let s = \"}\"; crate::a::f(); }\n\
             #[cfg(test)]\nmod tests {\n    use crate::a::*;\n}\n",
        ),
        ("helpers.rs", "use crate::a::A;\n"),
        ("helpers/deep.rs", "use crate::a::A;\n"),
    ]);
    assert_eq!(edges, [pair("a.rs", "b.rs")].into());
}

#[test]
fn serde_function_paths_in_strings_count() {
    let edges = edge_names(&[
        ("lib.rs", "mod f;\n"),
        ("f/mod.rs", "mod values;\nmod light;\n"),
        ("f/values.rs", "pub fn yes() -> bool { true }\n"),
        (
            "f/light.rs",
            "#[derive(Deserialize)]\nstruct L {\n    #[serde(default = \"super::values::yes\")]\n    on: bool,\n}\n",
        ),
    ]);
    assert!(edges.contains(&pair("f/light.rs", "f/values.rs")), "{edges:?}");
}

#[test]
fn a_cycle_between_a_folder_and_a_file_is_found_at_the_folders_level() {
    // No two files import each other, but scene.rs needs bvh/ and bvh/ needs scene.rs.
    let found = find_cycles(
        "fake",
        &sources(&[
            ("lib.rs", "mod bvh;\nmod scene;\n"),
            ("scene.rs", "use crate::bvh::Bvh;\npub struct Scene;\n"),
            ("bvh/mod.rs", "mod query;\npub struct Bvh;\n"),
            ("bvh/query.rs", "use crate::scene::Scene;\n"),
        ]),
    );
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].level.as_deref(), Some(""));
    assert_eq!(found[0].members, ["bvh/", "scene.rs"]);
}

#[test]
fn the_allow_list_matches_a_component_exactly() {
    let cycle = Cycle {
        krate: "fake".into(),
        level: None,
        members: vec!["a.rs".into(), "b.rs".into()],
        description: String::new(),
    };
    let entry =
        |members: &'static [&'static str]| Allowed { krate: "fake", level: None, members, reason: "" };
    assert!(is_allowed(&cycle, &entry(&["a.rs", "b.rs"])));
    assert!(!is_allowed(&cycle, &entry(&["a.rs"])));
    assert!(!is_allowed(&cycle, &entry(&["a.rs", "b.rs", "c.rs"])));
}
