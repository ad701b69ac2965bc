//! Kind names a script gives as string literals (`spawn("shard", ...)`, `me.is_kind("prey")`,
//! `extends "ball";`), found by a scan of its source, with their positions.
//!
//! A world's kinds cannot be added to during a step (hooks borrow them), so when a kind is loaded
//! into a world, every kind its file names this way is loaded too ([`load_named`]), and what
//! those name in turn. Scene and test code runs between steps, where a kind loads when first
//! named, so it needs no such pass. A name computed at run time cannot be seen here; if it is
//! still unknown when a hook uses it, that use is an error naming the known kinds.
//! `check` reports the names that resolve to no kind ([`super::lint`]).

use super::host::Dim;
use super::kind_file::load_into;
use super::Runtime;
use crate::error::Error;
use crate::world::World;
use std::rc::Rc;

/// The kinds the engine has without a file.
pub(crate) const NATIVE_KINDS: &[&str] = &["ball", "wall"];

/// A kind name found in a script, with the 1-based line and column of its opening quote.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct KindRef {
    pub name: String,
    pub line: usize,
    pub column: usize,
    /// The call (or `extends`) it is an argument of.
    pub call: &'static str,
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Str(String),
    Open(char),
    Close,
    Comma,
    Semi,
    Other,
}

/// The tokens of `text` that matter here, each with its line and column; comments and the
/// insides of strings are skipped, so a name in a comment is not a reference.
fn tokens(text: &str) -> Vec<(Tok, usize, usize)> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line, mut col) = (0, 1, 1);
    let advance = |i: &mut usize, line: &mut usize, col: &mut usize, n: usize| {
        for _ in 0..n {
            if *i < chars.len() {
                if chars[*i] == '\n' {
                    *line += 1;
                    *col = 1;
                } else {
                    *col += 1;
                }
                *i += 1;
            }
        }
    };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        let (l0, c0) = (line, col);
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                advance(&mut i, &mut line, &mut col, 1);
            }
        } else if c == '/' && next == Some('*') {
            // rhai's block comments nest.
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    advance(&mut i, &mut line, &mut col, 2);
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    advance(&mut i, &mut line, &mut col, 2);
                    if depth == 0 {
                        break;
                    }
                } else {
                    advance(&mut i, &mut line, &mut col, 1);
                }
            }
        } else if c == '"' || c == '`' || c == '\'' {
            advance(&mut i, &mut line, &mut col, 1);
            let mut s = String::new();
            while i < chars.len() && chars[i] != c {
                if chars[i] == '\\' && c != '`' {
                    advance(&mut i, &mut line, &mut col, 1);
                }
                if let Some(&ch) = chars.get(i) {
                    s.push(ch);
                }
                advance(&mut i, &mut line, &mut col, 1);
            }
            advance(&mut i, &mut line, &mut col, 1);
            // Only plain "..." strings are names: a template string may hold `${...}`.
            out.push((if c == '"' { Tok::Str(s) } else { Tok::Other }, l0, c0));
        } else if c.is_alphabetic() || c == '_' {
            let mut s = String::new();
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                s.push(chars[i]);
                advance(&mut i, &mut line, &mut col, 1);
            }
            out.push((Tok::Ident(s), l0, c0));
        } else {
            let tok = match c {
                '(' | '[' | '{' => Some(Tok::Open(c)),
                ')' | ']' | '}' => Some(Tok::Close),
                ',' => Some(Tok::Comma),
                ';' => Some(Tok::Semi),
                c if c.is_whitespace() => None,
                _ => Some(Tok::Other),
            };
            if let Some(t) = tok {
                out.push((t, l0, c0));
            }
            advance(&mut i, &mut line, &mut col, 1);
        }
    }
    out
}

/// The kind names `text` gives as string literals: `extends "name"`, and every string literal
/// that is a whole argument of one of `calls`, the functions registered as taking kind names
/// (`Runtime::kind_calls`): so `spawn("a", #{ tag: "b" })` names `a` only, and
/// `nearby(5.0, "prey")` names `prey`. In source order.
pub(crate) fn find(text: &str, calls: &[&'static str]) -> Vec<KindRef> {
    let toks = tokens(text);
    let mut out = Vec::new();
    for (i, (tok, _, _)) in toks.iter().enumerate() {
        let Tok::Ident(name) = tok else { continue };
        if name == "extends" {
            if let Some((Tok::Str(s), l, c)) = toks.get(i + 1) {
                out.push(KindRef {
                    name: s.clone(),
                    line: *l,
                    column: *c,
                    call: "extends",
                });
            }
            continue;
        }
        let Some(call) = calls.iter().find(|k| **k == name.as_str()) else {
            continue;
        };
        if !matches!(toks.get(i + 1), Some((Tok::Open('('), _, _))) {
            continue;
        }
        // The top-level arguments up to the matching `)`.
        let mut depth = 0usize;
        let mut j = i + 1;
        while let Some((t, l, c)) = toks.get(j) {
            match t {
                Tok::Open(_) => depth += 1,
                Tok::Close => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                Tok::Str(s) if depth == 1 => {
                    let before = &toks[j - 1].0;
                    let after = toks.get(j + 1).map(|t| &t.0);
                    let whole = matches!(before, Tok::Open('(') | Tok::Comma)
                        && matches!(after, Some(Tok::Close) | Some(Tok::Comma));
                    if whole {
                        out.push(KindRef {
                            name: s.clone(),
                            line: *l,
                            column: *c,
                            call,
                        });
                    }
                }
                Tok::Semi if depth <= 1 => break,
                _ => {}
            }
            j += 1;
        }
    }
    out
}

/// Loads into `world` every kind that the file `file` (already read by `rt`) names as a string
/// literal and that exists on the kind search path, with what those name in turn. Names that
/// resolve to no file are left for `check` to report and for their use to fail clearly.
pub(crate) fn load_named<V: Dim>(
    rt: &Rc<Runtime>,
    world: &mut World<V>,
    file: &str,
) -> Result<(), Error> {
    let text = rt
        .sources
        .borrow()
        .iter()
        .find(|s| s.path == file)
        .map(|s| s.text.clone());
    match text {
        Some(text) => load_named_in(rt, world, &text),
        None => Ok(()),
    }
}

/// As [`load_named`], for the names in `text`.
pub(crate) fn load_named_in<V: Dim>(
    rt: &Rc<Runtime>,
    world: &mut World<V>,
    text: &str,
) -> Result<(), Error> {
    for r in find(text, &rt.kind_calls) {
        if NATIVE_KINDS.contains(&r.name.as_str()) || world.kinds().id(&r.name).is_ok() {
            continue;
        }
        if rt.resolve_kind(&r.name).is_some() {
            load_into(rt, world, &r.name)?;
        }
    }
    Ok(())
}

/// Levenshtein distance between `a` and `b` (for "did you mean" suggestions).
pub(crate) fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

/// The candidate closest to `name` within an edit distance that a typo could explain.
pub(crate) fn closest<'a>(
    name: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    let limit = (name.chars().count() / 3).clamp(1, 3);
    candidates
        .into_iter()
        .filter(|c| *c != name)
        .map(|c| (edit_distance(name, c), c))
        .filter(|(d, _)| *d <= limit)
        .min()
        .map(|(_, c)| c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(text: &str) -> Vec<(String, usize, usize)> {
        let rt = Runtime::new(&crate::script::ScriptOptions::default(), None);
        find(text, &rt.kind_calls)
            .into_iter()
            .map(|r| (r.name, r.line, r.column))
            .collect()
    }

    #[test]
    fn finds_literal_kind_arguments_with_positions() {
        let text = "extends \"ball\";\nfn collide(me, other) {\n    if other.is_kind(\"pray\") { spawn(\"shard\", #{ tag: \"x\" }); }\n    world().nearby(me.pos, 5.0, \"hunter\");\n}\n";
        assert_eq!(
            names(text),
            vec![
                ("ball".into(), 1, 9),
                ("pray".into(), 3, 22),
                ("shard".into(), 3, 38),
                ("hunter".into(), 4, 33),
            ]
        );
    }

    #[test]
    fn ignores_comments_strings_and_computed_names() {
        let text = "// spawn(\"a\", #{})\n/* is_kind(\"b\") /* nested */ */\nlet s = \"spawn(\\\"c\\\")\";\nspawn(me.ammo, #{});\nspawn(\"d\" + x, #{});\n";
        assert!(names(text).is_empty(), "{:?}", names(text));
    }

    #[test]
    fn edit_distance_is_levenshtein() {
        assert_eq!(edit_distance("colide", "collide"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(closest("pray", ["prey", "hunter"]), Some("prey"));
        assert_eq!(closest("zzzz", ["prey", "hunter"]), None);
    }
}
