//! `check` as a linter: every file given is checked, and every problem found is reported, not
//! only the first. Errors are what stops a file from loading (it does not compile, a scene fails
//! to set up, a kind is invalid); warnings are mistakes that would pass silently: a function
//! whose name is close to a hook's (`colide`), a kind name in a string literal of a kind file
//! that names no kind.
//!
//! A problem's verdict is its own, never another's: loading stops at its first error, so what
//! the linter can see in the text it reports itself, whatever else is wrong. A hook with the
//! wrong number of parameters is an error (a kind or scene with one does not load), each one,
//! not only the first the loader meets; a kind name that names no kind is an error in a scene
//! (its set-up or `on_step` fails there) and a warning in a kind or test file. A scene's spawn
//! with a bad field is reported and left out, and the set-up goes on.
//!
//! A file is a test file when it defines `fn test_...` functions, a scene when it makes a world,
//! and a kind otherwise (as `critterbox test` and `run` take them).

use super::kind_refs::{self, closest, edit_distance};
use super::{kind_file, scene, Runtime, ScriptOptions};
use crate::error::{Error, ScriptError};
use std::fmt;
use std::path::{Path, PathBuf};

/// The hooks a kind may define, with the numbers of parameters each may take.
const KIND_HOOKS: &[(&str, &[usize])] = &kind_file::HOOKS;

/// The hook a scene may define.
const SCENE_HOOKS: &[(&str, &[usize])] = &[("on_step", &[1])];

/// How bad a problem is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    /// The file does not load.
    Error,
    /// The file loads, but probably does not do what was meant.
    Warning,
}

/// One problem in a checked file, located where possible.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// Error or warning.
    pub severity: Severity,
    /// File, line, column, message and hint.
    pub error: ScriptError,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = &self.error;
        let word = match self.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        write!(f, "{word}: {e}")
    }
}

/// What `check` found in one file.
#[derive(Clone, Debug, PartialEq)]
pub struct FileCheck {
    /// The file.
    pub path: PathBuf,
    /// One line saying what the file is, when it loaded (`path: kind 'bullet' ok (...)`).
    pub summary: Option<String>,
    /// Errors first, then warnings, each in source order.
    pub problems: Vec<Problem>,
}

impl FileCheck {
    /// Problems of `severity`.
    pub fn count(&self, severity: Severity) -> usize {
        self.problems
            .iter()
            .filter(|p| p.severity == severity)
            .count()
    }
}

/// What kind of script a file is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FileType {
    Kind,
    Scene,
    Test,
}

/// True when `text` is a kind file: neither a scene nor a test file.
pub(crate) fn is_kind_text(text: &str) -> bool {
    file_type(text) == FileType::Kind
}

fn file_type(text: &str) -> FileType {
    if fn_defs(text).iter().any(|f| f.name.starts_with("test_")) {
        FileType::Test
    } else if scene::looks_like_scene(text) {
        FileType::Scene
    } else {
        FileType::Kind
    }
}

/// A `fn name(params)` definition found at the start of a line.
struct FnDef {
    name: String,
    params: usize,
    line: usize,
    column: usize,
}

/// The functions `text` defines (`fn` or `private fn` at the start of a line).
fn fn_defs(text: &str) -> Vec<FnDef> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        let rest = trimmed.strip_prefix("private ").unwrap_or(trimmed);
        let Some(rest) = rest.strip_prefix("fn ") else {
            continue;
        };
        let Some(open) = rest.find('(') else { continue };
        let name = rest[..open].trim();
        if name.is_empty() || !name.chars().all(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let after = &rest[open + 1..];
        let inside = after.split(')').next().unwrap_or("");
        let params = if inside.trim().is_empty() {
            0
        } else {
            inside.split(',').filter(|p| !p.trim().is_empty()).count()
        };
        let name_at = line.len() - rest.len() + rest.find(name).unwrap_or(0);
        out.push(FnDef {
            name: name.to_string(),
            params,
            line: i + 1,
            column: line[..name_at].chars().count() + 1,
        });
    }
    out
}

fn problem(
    severity: Severity,
    file: &str,
    (line, column): (usize, usize),
    message: String,
    hint: String,
) -> Problem {
    let mut e = ScriptError::new(file, message);
    e.line = Some(line);
    e.column = Some(column);
    e.hint = Some(hint);
    Problem { severity, error: e }
}

fn warning(file: &str, line: usize, column: usize, message: String, hint: String) -> Problem {
    problem(Severity::Warning, file, (line, column), message, hint)
}

/// The parameters of hook `hook`, as the messages name them.
fn params_of(hook: &str) -> &'static str {
    if hook == "on_step" {
        "world"
    } else {
        kind_file::hook_params(hook)
    }
}

/// Errors for hooks with the wrong number of parameters (every one: the loader stops at the
/// first), and warnings for functions named like a hook.
fn hook_problems(file: &str, text: &str, hooks: &[(&str, &[usize])]) -> Vec<Problem> {
    let mut out = Vec::new();
    for f in fn_defs(text) {
        if let Some((_, arities)) = hooks.iter().find(|(h, _)| *h == f.name) {
            if !arities.contains(&f.params) {
                let want = arities
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(" or ");
                out.push(problem(
                    Severity::Error,
                    file,
                    (f.line, f.column),
                    format!(
                        "hook {} takes {want} parameter{} ({}), not {}",
                        f.name,
                        if arities == &[1] { "" } else { "s" },
                        params_of(&f.name),
                        f.params
                    ),
                    format!(
                        "the engine loads no file whose hook takes other parameters: give {} \
                         the parameters ({}) (see the hooks in docs/scripting.md)",
                        f.name,
                        params_of(&f.name)
                    ),
                ));
            }
            continue;
        }
        let near = hooks
            .iter()
            .map(|(h, _)| (edit_distance(&f.name, h), *h))
            .filter(|(d, h)| *d <= (h.len() / 4).clamp(1, 2))
            .min();
        if let Some((_, hook)) = near {
            out.push(warning(
                file,
                f.line,
                f.column,
                format!("function '{}' is not a hook: did you mean '{hook}'?", f.name),
                format!("the engine calls only functions named exactly as its hooks; rename it to {hook}"),
            ));
        }
    }
    out
}

/// Kind names in string literals that name no kind, as problems of `severity`.
fn kind_name_problems(rt: &Runtime, file: &str, text: &str, severity: Severity) -> Vec<Problem> {
    let known = rt.known_kind_names();
    kind_refs::find(text, &rt.kind_calls)
        .into_iter()
        .filter(|r| !known.contains(&r.name))
        .map(|r| {
            let hint = match closest(&r.name, known.iter().map(String::as_str)) {
                Some(k) => format!("did you mean '{k}'?"),
                None => format!("the known kinds are {}", known.join(", ")),
            };
            problem(
                severity,
                file,
                (r.line, r.column),
                format!("unknown kind '{}' in {}", r.name, r.call),
                hint,
            )
        })
        .collect()
}

fn as_problem(e: Error, file: &str) -> Problem {
    let error = match e {
        Error::Script(s) => *s,
        other => ScriptError::new(file, other.to_string()),
    };
    Problem {
        severity: Severity::Error,
        error,
    }
}

/// Checks one file: loads it as what it is (scenes are set up, not stepped; kinds are loaded;
/// test files are compiled), then lints it.
pub fn check_file(path: &Path, options: &ScriptOptions) -> FileCheck {
    let file = path.display().to_string();
    let mut report = FileCheck {
        path: path.to_path_buf(),
        summary: None,
        problems: Vec::new(),
    };
    let text = match super::read_script(path) {
        Ok(t) => t,
        Err(e) => {
            report.problems.push(as_problem(e, &file));
            return report;
        }
    };
    let rt = Runtime::new(options, path.parent());
    let ty = file_type(&text);
    let mut noted = Vec::new();
    let loaded = match ty {
        FileType::Scene => {
            let (scene, notes) = scene::load_checking(path, options);
            noted = notes;
            scene.map(|scene| super::scene_ok(&file, &scene))
        }
        FileType::Kind => kind_file::load_def(&rt, &file).map(|def| {
            let hooks: Vec<&str> = def.hook_names().collect();
            format!(
                "{file}: kind '{}' ok (hooks: {})",
                def.name,
                if hooks.is_empty() {
                    "none".to_string()
                } else {
                    hooks.join(", ")
                }
            )
        }),
        FileType::Test => rt.compile(&file, &text).map(|_| {
            let n = fn_defs(&text)
                .iter()
                .filter(|f| f.name.starts_with("test_"))
                .count();
            format!("{file}: tests ok ({n} tests)")
        }),
    };
    let mut loading: Vec<Problem> = noted
        .into_iter()
        .map(|error| Problem {
            severity: Severity::Error,
            error,
        })
        .collect();
    match loaded {
        // A scene that set up only without its bad spawn fields did not load as written.
        Ok(summary) if loading.is_empty() => report.summary = Some(summary),
        Ok(_) => {}
        Err(e) => loading.push(as_problem(e, &file)),
    }
    let mut linted = match ty {
        FileType::Kind => hook_problems(&file, &text, KIND_HOOKS),
        FileType::Scene => hook_problems(&file, &text, SCENE_HOOKS),
        FileType::Test => Vec::new(),
    };
    let unknown_kind = match ty {
        FileType::Scene => Severity::Error,
        FileType::Kind | FileType::Test => Severity::Warning,
    };
    linted.extend(kind_name_problems(&rt, &file, &text, unknown_kind));
    let (mut errors, mut warnings): (Vec<Problem>, Vec<Problem>) = linted
        .into_iter()
        .partition(|p| p.severity == Severity::Error);
    // The loader's error on a line the linter names is the same problem (the first wrong hook,
    // the unknown kind it stopped at): the linter's says it as for the others.
    let place = |p: &Problem| (p.error.file.clone(), p.error.line);
    let linted_lines: Vec<_> = errors.iter().map(place).collect();
    loading.retain(|p| !linted_lines.contains(&place(p)));
    errors.extend(loading);
    errors.sort_by_key(|p| (p.error.file != file, p.error.line, p.error.column));
    // A warning on a line an error already names says nothing new.
    let error_lines: Vec<_> = errors.iter().map(place).collect();
    warnings.retain(|w| !error_lines.contains(&place(w)));
    warnings.sort_by_key(|w| (w.error.line, w.error.column));
    report.problems = errors;
    report.problems.extend(warnings);
    report
}

/// Checks every file in `paths` (see [`check_file`]).
pub fn check_files(paths: &[PathBuf], options: &ScriptOptions) -> Vec<FileCheck> {
    paths.iter().map(|p| check_file(p, options)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fn_defs_find_names_params_and_places() {
        let defs = fn_defs("fn a() {}\n  private fn colide(me, other) {\n}\nlet fn_x = 1;\n");
        let got: Vec<_> = defs
            .iter()
            .map(|f| (f.name.as_str(), f.params, f.line, f.column))
            .collect();
        assert_eq!(got, vec![("a", 0, 1, 4), ("colide", 2, 2, 14)]);
    }

    #[test]
    fn near_hook_names_warn_and_exact_ones_do_not() {
        let text = "fn colide(me, other) {}\nfn colides_with(me, other) {}\nfn updat(me, dt) {}\nfn touch_begn(me, other, c) {}\nfn on_deth(me) {}\nfn collide(me, other) {}\nfn is_target(me, other) {}\nfn init(me, extra) {}\n";
        let w = hook_problems("k.rhai", text, KIND_HOOKS);
        let lines: Vec<usize> = w.iter().filter_map(|p| p.error.line).collect();
        assert_eq!(lines, vec![1, 2, 3, 4, 5, 8], "{w:#?}");
        assert!(w[0].error.message.contains("'collide'"));
        assert!(w[5].error.message.contains("takes 1"));
        let errors: Vec<usize> = w
            .iter()
            .filter(|p| p.severity == Severity::Error)
            .filter_map(|p| p.error.line)
            .collect();
        assert_eq!(
            errors,
            vec![8],
            "a wrong arity is an error, a near name a warning"
        );
    }
}
