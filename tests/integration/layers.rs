//! The library's layers go one way (`docs/ARCHITECTURE.md`): a file may use what its own layer
//! and the layers below it hold, never what a layer above holds, and the only import cycles are
//! the few named here. Read from the `use crate::` and `super::` paths of `src/`, test code left
//! out (tests may build a whole world to test a part of it).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, lowest first: each a list of paths under `src/` (a file, or a folder ending in
/// `/`). Every library file is in exactly one.
const LAYERS: &[(&str, &[&str])] = &[
    (
        "base",
        &[
            "vector.rs",
            "error.rs",
            "ids.rs",
            "rng.rs",
            "tolerance.rs",
            "parallel.rs",
            "prefetch.rs",
            "color.rs",
            "border.rs",
            "pair_order.rs",
            "profile.rs",
        ],
    ),
    (
        "bodies",
        &[
            "critter.rs",
            "critter_set.rs",
            "wall.rs",
            "contact.rs",
            "default_response.rs",
            "hash/",
            "broad_phase/",
        ],
    ),
    ("step", &["kind.rs", "rules.rs", "step/"]),
    ("method", &["method/"]),
    ("world", &["world/"]),
    ("scenes", &["scenes/"]),
    ("script", &["script/"]),
    ("recording", &["recording/"]),
    ("testing", &["testing/"]),
    ("sweep", &["sweep/"]),
    ("viewer", &["viewer.rs"]),
];

/// The layers of the core (the first five): between their modules there is no import cycle
/// but the ones named in [`CYCLES`].
const CORE: usize = 5;

/// The import cycles between the core's modules, each for a reason; any other is a failure.
/// (Files of one folder below `src/` are one module's parts and may use each other.)
const CYCLES: &[(&[&str], &str)] = &[(
    &["kind.rs", "step/access.rs"],
    "hooks and the state they see: a kind's hooks take an Access, which holds the kinds",
)];

#[test]
fn no_file_uses_a_layer_above_its_own() {
    let graph = Graph::read();
    let mut wrong = Vec::new();
    for (file, uses) in &graph.edges {
        let from = layer_of(file);
        for used in uses {
            let to = layer_of(used);
            if to > from {
                wrong.push(format!(
                    "{file} ({}) uses {used} ({})",
                    LAYERS[from].0, LAYERS[to].0
                ));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "upward imports (layers: {}):\n{}",
        LAYERS.iter().map(|l| l.0).collect::<Vec<_>>().join(" -> "),
        wrong.join("\n")
    );
}

#[test]
fn the_core_has_no_import_cycle_but_the_named_ones() {
    let graph = Graph::read();
    let allowed: Vec<BTreeSet<String>> = CYCLES
        .iter()
        .map(|(files, _)| files.iter().map(|f| f.to_string()).collect())
        .collect();
    let found: Vec<_> = graph
        .across_folders()
        .cycles()
        .into_iter()
        .filter(|c| c.iter().any(|f| layer_of(f) < CORE))
        .collect();
    let unexpected: Vec<String> = found
        .iter()
        .filter(|c| !allowed.contains(c))
        .map(|c| c.iter().cloned().collect::<Vec<_>>().join(", "))
        .collect();
    assert!(
        unexpected.is_empty(),
        "import cycles not in tests/integration/layers.rs's CYCLES (break them, or name one there with its \
         reason):\n{}",
        unexpected.join("\n")
    );
    // A named cycle that went away is good news: the list must say so.
    for (c, (files, _)) in allowed.iter().zip(CYCLES) {
        assert!(
            found.contains(c),
            "the cycle {files:?} is gone: take it out of CYCLES"
        );
    }
    assert!(
        CYCLES[0].0.len() <= 8,
        "the hooks' coupling to the state must stay within 8 files"
    );
}

#[test]
fn the_checker_sees_imports() {
    // Guards the tests above against passing vacuously (a parser that finds nothing).
    let graph = Graph::read();
    let uses = |a: &str, b: &str| graph.edges.get(a).is_some_and(|u| u.contains(b));
    assert!(uses("world/mod.rs", "method/method_state.rs"));
    assert!(uses("step/motion.rs", "step/state.rs"));
    assert!(uses("kind.rs", "step/access.rs"));
    assert!(graph.edges.len() > 100, "{} files", graph.edges.len());
    let mut g = Graph::default();
    g.edges.insert("a.rs".into(), ["b.rs".to_string()].into());
    g.edges.insert("b.rs".into(), ["a.rs".to_string()].into());
    assert_eq!(g.cycles().len(), 1);
    assert_eq!(
        code_only("#[cfg(test)]\nmod tests { use crate::x; }\nuse crate::y; // crate::z\n"),
        "\nuse crate::y; \n"
    );
}

/// The layer a file under `src/` is in.
fn layer_of(file: &str) -> usize {
    LAYERS
        .iter()
        .position(|(_, paths)| {
            paths.iter().any(|p| {
                if p.ends_with('/') {
                    file.starts_with(p)
                } else {
                    file == *p
                }
            })
        })
        .unwrap_or_else(|| {
            panic!("src/{file} is in no layer of tests/integration/layers.rs: add it to one")
        })
}

/// Which library file uses which, by path under `src/`.
#[derive(Default)]
struct Graph {
    edges: BTreeMap<String, BTreeSet<String>>,
}

impl Graph {
    fn read() -> Graph {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut files = Vec::new();
        walk(&src, &mut files);
        let sources: BTreeMap<String, String> = files
            .iter()
            .map(|p| {
                let rel = p.strip_prefix(&src).expect("under src").to_string_lossy();
                let text = std::fs::read_to_string(p).expect("a readable source file");
                (rel.replace('\\', "/"), text)
            })
            .collect();
        let tests = test_files(&sources);
        let modules: BTreeMap<Vec<String>, String> =
            sources.keys().map(|f| (module_of(f), f.clone())).collect();
        // What each module brings into its namespace with `use` (children may name it through
        // `super::`), so that a path is followed to the file that defines what it names.
        let imports: BTreeMap<Vec<String>, BTreeMap<String, Vec<String>>> = sources
            .iter()
            .map(|(f, text)| {
                let here = module_of(f);
                let named = imported(text)
                    .into_iter()
                    .filter_map(|(name, path)| {
                        absolute(&here, &path, &modules).map(|full| (name, full))
                    })
                    .collect();
                (here, named)
            })
            .collect();
        let mut graph = Graph::default();
        for (file, text) in &sources {
            if file == "lib.rs" || tests.contains(file) {
                continue;
            }
            let here = module_of(file);
            let code = code_only(text);
            let mut uses = BTreeSet::new();
            for path in paths_in(&code) {
                let Some(full) = absolute(&here, &path, &modules) else {
                    continue;
                };
                if let Some(target) = defining_file(full, &modules, &imports) {
                    if &target != file && target != "lib.rs" && !tests.contains(&target) {
                        uses.insert(target);
                    }
                }
            }
            graph.edges.insert(file.clone(), uses);
        }
        graph
    }

    /// The graph without the uses between files of one folder below `src/`: they are the parts
    /// of one module (a `mod.rs` and its children), which may use each other.
    fn across_folders(&self) -> Graph {
        let folder = |f: &str| f.rsplit_once('/').map(|(d, _)| d.to_string());
        let edges = self
            .edges
            .iter()
            .map(|(a, uses)| {
                let kept = uses
                    .iter()
                    .filter(|b| folder(a).is_none() || folder(a) != folder(b))
                    .cloned()
                    .collect();
                (a.clone(), kept)
            })
            .collect();
        Graph { edges }
    }

    /// The strongly connected sets of more than one file (Tarjan's algorithm).
    fn cycles(&self) -> Vec<BTreeSet<String>> {
        struct Walk<'a> {
            g: &'a Graph,
            index: BTreeMap<&'a str, usize>,
            low: BTreeMap<&'a str, usize>,
            stack: Vec<&'a str>,
            on: BTreeSet<&'a str>,
            out: Vec<BTreeSet<String>>,
        }
        fn visit<'a>(w: &mut Walk<'a>, v: &'a str) {
            let n = w.index.len();
            w.index.insert(v, n);
            w.low.insert(v, n);
            w.stack.push(v);
            w.on.insert(v);
            let g = w.g;
            for u in g.edges.get(v).into_iter().flatten() {
                let u = u.as_str();
                if !w.index.contains_key(u) {
                    visit(w, u);
                    let lu = w.low[u];
                    let lv = w.low.get_mut(v).expect("visited");
                    *lv = (*lv).min(lu);
                } else if w.on.contains(u) {
                    let iu = w.index[u];
                    let lv = w.low.get_mut(v).expect("visited");
                    *lv = (*lv).min(iu);
                }
            }
            if w.low[v] == w.index[v] {
                let mut set = BTreeSet::new();
                while let Some(u) = w.stack.pop() {
                    w.on.remove(u);
                    set.insert(u.to_string());
                    if u == v {
                        break;
                    }
                }
                if set.len() > 1 {
                    w.out.push(set);
                }
            }
        }
        let mut w = Walk {
            g: self,
            index: BTreeMap::new(),
            low: BTreeMap::new(),
            stack: Vec::new(),
            on: BTreeSet::new(),
            out: Vec::new(),
        };
        for v in self.edges.keys() {
            if !w.index.contains_key(v.as_str()) {
                visit(&mut w, v);
            }
        }
        w.out
    }
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("a readable folder") {
        let path = entry.expect("a folder entry").path();
        if path.is_dir() {
            walk(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// `step/pairs/tests.rs` -> [step, pairs, tests]; `method/mod.rs` -> [method].
fn module_of(file: &str) -> Vec<String> {
    let mut parts: Vec<String> = file
        .trim_end_matches(".rs")
        .split('/')
        .map(String::from)
        .collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
        parts.pop();
    }
    parts
}

/// Files that are test modules: declared under `#[cfg(test)]` (with or without `#[path]`), and
/// every file below such a module's folder.
fn test_files(sources: &BTreeMap<String, String>) -> BTreeSet<String> {
    let mut tests = BTreeSet::new();
    for (file, text) in sources {
        let dir = match file.rsplit_once('/') {
            Some((d, "mod.rs")) => format!("{d}/"),
            Some((d, name)) => format!("{d}/{}/", name.trim_end_matches(".rs")),
            None if file == "lib.rs" => String::new(),
            None => format!("{}/", file.trim_end_matches(".rs")),
        };
        let path_dir = match file.rsplit_once('/') {
            Some((d, _)) => format!("{d}/"),
            None => String::new(),
        };
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        for (i, line) in lines.iter().enumerate() {
            let declared = ["mod ", "pub mod ", "pub(crate) mod ", "pub(super) mod "]
                .iter()
                .find_map(|v| line.strip_prefix(v));
            let Some(name) = declared.and_then(|r| r.strip_suffix(';')) else {
                continue;
            };
            let attrs: Vec<&str> = lines[..i]
                .iter()
                .rev()
                .take_while(|l| l.starts_with("#["))
                .copied()
                .collect();
            if !attrs.iter().any(|a| a.starts_with("#[cfg(test)]")) {
                continue;
            }
            let path = attrs.iter().find_map(|a| {
                a.strip_prefix("#[path = \"")
                    .and_then(|r| r.strip_suffix("\"]"))
            });
            match path {
                Some(p) => tests.insert(format!("{path_dir}{p}")),
                None => {
                    tests.insert(format!("{dir}{name}.rs"));
                    tests.insert(format!("{dir}{name}/mod.rs"))
                }
            };
            let folder = format!("{dir}{name}/");
            tests.extend(sources.keys().filter(|f| f.starts_with(&folder)).cloned());
        }
    }
    tests
}

/// The names a file's `use` declarations bring in, each with the path it names.
fn imported(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for stmt in use_statements(&code_only(text)) {
        for (path, alias) in expand_named(&stmt) {
            out.push((alias, path));
        }
    }
    out
}

/// The file that defines what the absolute path `full` names: the deepest module file it
/// reaches, followed through the `use` declarations of that module when the next name is one
/// it imports.
fn defining_file(
    mut full: Vec<String>,
    modules: &BTreeMap<Vec<String>, String>,
    imports: &BTreeMap<Vec<String>, BTreeMap<String, Vec<String>>>,
) -> Option<String> {
    for _ in 0..8 {
        let n = (0..=full.len())
            .rev()
            .find(|&n| modules.contains_key(&full[..n]))?;
        let through = full
            .get(n)
            .and_then(|name| imports.get(&full[..n]).and_then(|m| m.get(name)));
        match through {
            Some(path) if path != &full[..=n] => {
                let mut next = path.clone();
                next.extend(full[n + 1..].iter().cloned());
                full = next;
            }
            _ => return modules.get(&full[..n]).cloned(),
        }
    }
    None
}

/// The source without comments, string and character literals, and items under
/// `#[cfg(test)]`.
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        let rest = &text[i..];
        if rest.starts_with("//") {
            i += rest.find('\n').unwrap_or(rest.len());
        } else if rest.starts_with("/*") {
            i += rest.find("*/").map_or(rest.len(), |e| e + 2);
        } else if rest.starts_with("r#\"") || rest.starts_with("r\"") {
            let hashes = rest[1..].bytes().take_while(|&c| c == b'#').count();
            let close = format!("\"{}", "#".repeat(hashes));
            let open = 2 + hashes;
            i += open
                + rest[open..]
                    .find(&close)
                    .map_or(rest.len(), |e| e + close.len());
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
        } else if b[i] == b'\'' {
            // A character literal ('x', '\n', '{'), not a lifetime ('a).
            if let Some(escaped) = rest.strip_prefix("'\\") {
                i += 2 + escaped.find('\'').map_or(0, |e| e + 1);
            } else if let Some(c) = rest[1..].chars().next() {
                let after = 1 + c.len_utf8();
                if rest[after..].starts_with('\'') {
                    i += after + 1;
                } else {
                    i += 1;
                }
            } else {
                i += 1;
            }
        } else if rest.starts_with("#[cfg(test)]") {
            i += "#[cfg(test)]".len();
            i += skip_item(&text[i..]);
        } else {
            let c = rest.chars().next().expect("not at the end");
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// The length of the item at the start of `text` (after its attributes): up to its `;`, or
/// through its braced body.
fn skip_item(text: &str) -> usize {
    let mut depth = 0usize;
    for (k, c) in text.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth = depth.saturating_sub(1);
                if depth == 0 {
                    return k + 1;
                }
            }
            ';' if depth == 0 => return k + 1,
            _ => {}
        }
    }
    text.len()
}

fn use_statements(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(k) = find_word(rest, "use") {
        let after = &rest[k + 3..];
        let end = after.find(';').unwrap_or(after.len());
        out.push(
            after[..end]
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" "),
        );
        rest = &after[end..];
    }
    out
}

fn find_word(text: &str, word: &str) -> Option<usize> {
    let b = text.as_bytes();
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut from = 0;
    while let Some(k) = text[from..].find(word) {
        let at = from + k;
        let before_ok = at == 0 || !ident(b[at - 1]);
        let after_ok = b.get(at + word.len()).is_none_or(|&c| !ident(c));
        if before_ok && after_ok {
            return Some(at);
        }
        from = at + word.len();
    }
    None
}

/// `a::{b, c::{d, e as f}}` -> [a::b, a::c::d, a::c::e].
fn expand(tree: &str) -> Vec<String> {
    expand_named(tree).into_iter().map(|(p, _)| p).collect()
}

/// As [`expand`], each path with the name it is brought in as (`f` for `e as f`).
fn expand_named(tree: &str) -> Vec<(String, String)> {
    let tree = tree
        .trim()
        .trim_start_matches("pub(crate) ")
        .trim_start_matches("pub(super) ")
        .trim_start_matches("pub ");
    let Some(open) = tree.find('{') else {
        let mut parts = tree.split(" as ");
        let path = parts.next().unwrap_or("").trim().replace(' ', "");
        if path.is_empty() || path.ends_with('*') {
            return vec![];
        }
        let last = path.rsplit("::").next().unwrap_or("").to_string();
        let alias = parts.next().map_or(last, |a| a.trim().to_string());
        return vec![(path, alias)];
    };
    let prefix = tree[..open].replace(' ', "");
    let body = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (k, c) in body.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&body[start..k]);
                start = k + 1;
            }
            _ => {}
        }
    }
    parts.push(&body[start..]);
    let base = prefix.trim_end_matches("::").to_string();
    let last = base.rsplit("::").next().unwrap_or("").to_string();
    parts
        .into_iter()
        .flat_map(expand_named)
        .map(|(p, alias)| {
            if p == "self" {
                (base.clone(), last.clone())
            } else if let Some(rest) = p.strip_prefix("self as ") {
                (base.clone(), rest.trim().to_string())
            } else {
                (format!("{prefix}{p}"), alias)
            }
        })
        .collect()
}

/// Every path the code names through `crate::`, `super::` or `self::`, or in a `use` (whose
/// first segment may also be a child module).
fn paths_in(code: &str) -> Vec<String> {
    let mut out: Vec<String> = use_statements(code)
        .iter()
        .flat_map(|s| expand(s))
        .collect();
    let b = code.as_bytes();
    for start in ["crate::", "super::"] {
        let mut from = 0;
        while let Some(k) = code[from..].find(start) {
            let at = from + k;
            let mut end = at;
            while end < b.len()
                && (b[end].is_ascii_alphanumeric() || b[end] == b'_' || b[end] == b':')
            {
                end += 1;
            }
            let prefix_ok = at == 0 || !(b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_');
            if prefix_ok {
                out.push(code[at..end].trim_end_matches(':').to_string());
            }
            from = end.max(at + 1);
        }
    }
    out
}

/// The absolute path of `path` as written in module `here`, or None for a path outside the
/// crate (a path whose first name is neither `crate`, `super`, `self` nor a child module).
fn absolute(
    here: &[String],
    path: &str,
    modules: &BTreeMap<Vec<String>, String>,
) -> Option<Vec<String>> {
    let segs: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
    let mut base: Vec<String> = here.to_vec();
    let mut rest = &segs[..];
    match *segs.first()? {
        "crate" => {
            base.clear();
            rest = &segs[1..];
        }
        "super" | "self" => {
            while let Some(s) = rest.first() {
                match *s {
                    "super" => {
                        base.pop();
                    }
                    "self" => {}
                    _ => break,
                }
                rest = &rest[1..];
            }
        }
        child => {
            let mut m = here.to_vec();
            m.push(child.to_string());
            if !modules.contains_key(&m) {
                return None;
            }
        }
    }
    base.extend(rest.iter().map(|s| s.to_string()));
    Some(base)
}
