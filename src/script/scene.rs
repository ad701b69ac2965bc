//! Scene files: loading a scene script (with `--set` overrides of its constants), running its
//! top level to build the world, and its `on_step(world)`. The functions a scene calls to build
//! its world are in [`super::api`].

use super::api::WorldRef;
use super::env::Env;
use super::errors::{eval_error, fn_location};
use super::{read_script, Runtime, ScriptOptions, SourceFile};
use crate::error::{Error, ScriptError};
use crate::scenes::{AnyWorld, Scene};
use glam::{DVec2, DVec3};
use rhai::{CallFnOptions, Dynamic, Scope};
use std::path::Path;
use std::rc::Rc;

/// True when the text is a scene script (it makes a world) rather than a kind file.
pub(crate) fn looks_like_scene(text: &str) -> bool {
    text.lines().any(|l| {
        let l = l.trim_start();
        !l.starts_with("//") && l.contains("world(#{")
    })
}

/// The names of the `const NAME = ...;` lines of `text`.
pub(crate) fn constants_of(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.trim_start().strip_prefix("const "))
        .filter_map(|r| {
            r.trim_start()
                .split(|c: char| c == '=' || c == ':' || c.is_whitespace())
                .next()
        })
        .filter(|n| !n.is_empty())
        .map(str::to_string)
        .collect()
}

/// A `--set` value as rhai source: numbers, `true`, `false` and quoted strings as they are,
/// anything else as a string.
fn literal(value: &str) -> String {
    if value.parse::<f64>().is_ok() || value == "true" || value == "false" || value.starts_with('"')
    {
        value.to_string()
    } else {
        format!("{value:?}")
    }
}

/// `text` with the value of its `const NAME = ...;` replaced for each (NAME, VALUE) of `sets`;
/// `missing(name)` is the error of a name it declares no constant of.
pub(crate) fn set_constants(
    text: &str,
    sets: &[(String, String)],
    missing: impl Fn(&str) -> Error,
) -> Result<String, Error> {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for (name, value) in sets {
        let literal = literal(value);
        let mut found = false;
        for line in &mut lines {
            let t = line.trim_start();
            if let Some(rest) = t.strip_prefix("const ") {
                let rest = rest.trim_start();
                if let Some(after) = rest.strip_prefix(name.as_str()) {
                    let after = after.trim_start();
                    if let Some(expr) = after.strip_prefix('=') {
                        let indent = &line[..line.len() - t.len()];
                        let comment = expr.find("//").map(|i| &expr[i..]).unwrap_or("");
                        *line = format!("{indent}const {name} = {literal}; {comment}");
                        found = true;
                        break;
                    }
                }
            }
        }
        if !found {
            return Err(missing(name));
        }
    }
    Ok(lines.join("\n"))
}

/// "its constants are A, B", or that it has none: the hint of a `--set` of no constant.
pub(crate) fn constants_hint(what: &str, text: &str) -> String {
    let consts = constants_of(text);
    if consts.is_empty() {
        format!("{what} declares no constants to set")
    } else {
        format!("its constants are {}", consts.join(", "))
    }
}

/// Replaces the value of `const NAME = ...;` at the top level for each override.
fn apply_sets(path: &str, text: &str, sets: &[(String, String)]) -> Result<String, Error> {
    set_constants(text, sets, |name| {
        let mut e = ScriptError::new(
            path,
            format!("--set {name}: the scene has no constant {name}"),
        );
        e.hint = Some(constants_hint("this scene", text));
        Error::from(e)
    })
}

/// `--set NAME=VALUE` pairs, as (NAME, VALUE).
type Sets = Vec<(String, String)>;

/// A `--set KIND.NAME=VALUE`: the kind's constant `NAME`.
struct KindSet {
    kind: String,
    name: String,
    value: String,
}

/// The sets of the scene's constants (`NAME`) and those of its kinds' (`KIND.NAME`).
fn split_sets(file: &str, sets: &[(String, String)]) -> Result<(Sets, Vec<KindSet>), Error> {
    let mut scene = Vec::new();
    let mut kinds = Vec::new();
    for (key, value) in sets {
        match key.split_once('.') {
            None => scene.push((key.clone(), value.clone())),
            Some((kind, name)) if !kind.is_empty() && !name.is_empty() && !name.contains('.') => {
                kinds.push(KindSet {
                    kind: kind.to_string(),
                    name: name.to_string(),
                    value: value.clone(),
                })
            }
            Some(_) => {
                let mut e = ScriptError::new(file, format!("--set {key}: not a constant's name"));
                e.hint = Some(
                    "write NAME=VALUE for the scene's constant, KIND.NAME=VALUE for a kind's \
                     (--set SPEED=2, --set boid.SIGHT=3)"
                        .into(),
                );
                return Err(Error::from(e));
            }
        }
    }
    Ok((scene, kinds))
}

/// The error of a `--set KIND.NAME` whose kind is no script kind of this run.
fn unknown_kind_set(rt: &Runtime, file: &str, set: &KindSet) -> Error {
    let KindSet { kind, name, .. } = set;
    if super::kind_refs::NATIVE_KINDS.contains(&kind.as_str()) {
        let mut e = ScriptError::new(
            file,
            format!("--set {kind}.{name}: '{kind}' is a native kind, it has no constants"),
        );
        e.hint = Some("only script kinds (scripts/kinds/NAME.rhai) have constants to set".into());
        return Error::from(e);
    }
    let known: Vec<String> = rt
        .known_kind_names()
        .into_iter()
        .filter(|k| !super::kind_refs::NATIVE_KINDS.contains(&k.as_str()))
        .collect();
    let mut e = ScriptError::new(
        file,
        format!("--set {kind}.{name}: no kind '{kind}' in this run"),
    );
    let near = super::kind_refs::closest(kind, known.iter().map(String::as_str));
    e.hint = Some(match near {
        Some(k) => format!(
            "did you mean '{k}'? The script kinds found are {}",
            known.join(", ")
        ),
        None if known.is_empty() => "no script kinds were found on the kind search path".into(),
        None => format!("the script kinds found are {}", known.join(", ")),
    });
    Error::from(e)
}

/// Checks the kinds' sets whose kind files are on the search path (their constants exist), and
/// gives them to the runtime, which applies them to each kind's text as it is built.
fn give_kind_sets(rt: &Runtime, file: &str, sets: &[KindSet]) -> Result<(), Error> {
    for set in sets {
        if super::kind_refs::NATIVE_KINDS.contains(&set.kind.as_str()) {
            return Err(unknown_kind_set(rt, file, set));
        }
        if let Some(path) = rt.resolve_kind(&set.kind) {
            let text = read_script(&path)?;
            let kind_file = path.display().to_string();
            kind_constant_set(
                &kind_file,
                &set.kind,
                &text,
                &[(set.name.clone(), set.value.clone())],
            )?;
        }
        rt.kind_sets
            .borrow_mut()
            .entry(set.kind.clone())
            .or_default()
            .push((set.name.clone(), set.value.clone()));
    }
    Ok(())
}

/// The text of kind `kind` (its file `file`) with its constants set as `sets` say.
pub(crate) fn kind_constant_set(
    file: &str,
    kind: &str,
    text: &str,
    sets: &[(String, String)],
) -> Result<String, Error> {
    set_constants(text, sets, |name| {
        let mut e = ScriptError::new(
            file,
            format!("--set {kind}.{name}: the kind '{kind}' has no constant {name}"),
        );
        e.kind = Some(kind.to_string());
        e.hint = Some(constants_hint("this kind", text));
        Error::from(e)
    })
}

/// Loads and sets up a scene script.
pub(crate) fn load(
    path: &Path,
    sets: &[(String, String)],
    options: &ScriptOptions,
) -> Result<Scene, Error> {
    load_keeping_sources(path, sets, options).map_err(|(e, _)| e)
}

/// As [`load`], but a failure also gives the script files read before it (the scene first, as
/// far as it was read), so a failed set-up can still be recorded with them.
pub(crate) fn load_keeping_sources(
    path: &Path,
    sets: &[(String, String)],
    options: &ScriptOptions,
) -> Result<Scene, (Error, Vec<SourceFile>)> {
    let file = path.display().to_string();
    let raw = read_script(path).map_err(|e| (e, Vec::new()))?;
    let scene_only = |e: Error| {
        let scene = SourceFile {
            path: file.clone(),
            text: raw.clone(),
        };
        (e, vec![scene])
    };
    let (scene_sets, kind_sets) = split_sets(&file, sets).map_err(scene_only)?;
    let text = apply_sets(&file, &raw, &scene_sets).map_err(scene_only)?;
    let rt = Runtime::new(options, path.parent());
    give_kind_sets(&rt, &file, &kind_sets).map_err(scene_only)?;
    load_on(&rt, path, &file, text, &kind_sets)
}

/// As [`load`], for `critterbox check`: a spawn's bad field is noted and left out and the
/// set-up goes on, so that one bad field does not hide the rest of the scene. Gives the notes
/// with the outcome.
pub(crate) fn load_checking(
    path: &Path,
    options: &ScriptOptions,
) -> (Result<Scene, Error>, Vec<ScriptError>) {
    let file = path.display().to_string();
    let text = match read_script(path) {
        Ok(text) => text,
        Err(e) => return (Err(e), Vec::new()),
    };
    let rt = Runtime::new(options, path.parent());
    *rt.host.check_notes.borrow_mut() = Some(Vec::new());
    let scene = load_on(&rt, path, &file, text, &[]).map_err(|(e, _)| e);
    let mut notes = rt.host.check_notes.borrow_mut().take().unwrap_or_default();
    for n in &mut notes {
        if n.file.is_empty() {
            n.file.clone_from(&file);
        }
    }
    (scene, notes)
}

/// Sets up the scene `file`, whose text (any `--set` applied) is `text`, in `rt`; every kind
/// `kind_sets` names must then be known.
fn load_on(
    rt: &Rc<Runtime>,
    path: &Path,
    file: &str,
    text: String,
    kind_sets: &[KindSet],
) -> Result<Scene, (Error, Vec<SourceFile>)> {
    let file = file.to_string();
    rt.sources.borrow_mut().push(SourceFile {
        path: file.clone(),
        text: text.clone(),
    });
    let built = set_up(rt, path, &file, &text).and_then(|scene| {
        // A kind not found by name on the search path may have been loaded by its path.
        let unknown = |s: &&KindSet| {
            !rt.kinds.borrow().contains_key(&s.kind) && rt.resolve_kind(&s.kind).is_none()
        };
        match kind_sets.iter().find(unknown) {
            Some(set) => Err(unknown_kind_set(rt, &file, set)),
            None => Ok(scene),
        }
    });
    built.map_err(|e| {
        let mut read = rt.sources.borrow().clone();
        // A kind file that failed to compile or load is kept only once it loads: add its text.
        if let Error::Script(s) = &e {
            if !read.iter().any(|f| f.path == s.file) {
                if let Ok(text) = std::fs::read_to_string(&s.file) {
                    read.push(SourceFile {
                        path: s.file.clone(),
                        text,
                    });
                }
            }
        }
        (e, read)
    })
}

/// Compiles the scene's text and runs its top level, which builds the world.
fn set_up(rt: &Rc<Runtime>, path: &Path, file: &str, text: &str) -> Result<Scene, Error> {
    let (file, text) = (file.to_string(), text.to_string());
    let ast = rt.compile(&file, &text)?;

    let mut scope = Scope::new();
    let ran = rt.engine.run_ast_with_scope(&mut scope, &ast);
    let world = rt.host.take_scene().map(|scene| scene.world);
    ran.map_err(|e| {
        Error::from(rt.host.locate(&e, || {
            eval_error(&file, None, None, &e, rt.engine.max_operations())
        }))
    })?;
    let Some(world) = world else {
        let mut e = ScriptError::new(&file, "the scene never made a world");
        e.hint =
            Some("start the scene with `let w = world(#{ dim: 2, size: vec(20, 10) });`".into());
        return Err(Error::from(e));
    };

    let on_step = ast
        .iter_functions()
        .find(|f| f.name == "on_step")
        .map(|f| f.params.len());
    let on_step = match on_step {
        None => None,
        Some(1) => {
            let mut constants = Scope::new();
            for (n, is_const, value) in scope.iter() {
                if is_const {
                    constants.push_constant(n.to_string(), value);
                }
            }
            let fns = rt.engine.optimize_ast(
                &constants,
                ast.clone_functions_only(),
                rhai::OptimizationLevel::Simple,
            );
            Some(OnStep {
                rt: rt.clone(),
                ast: fns,
                file: file.clone(),
                line: fn_location(&text, "on_step"),
            })
        }
        Some(n) => {
            let mut e = ScriptError::new(
                &file,
                format!("on_step takes one parameter (world), not {n}"),
            );
            if let Some((l, c)) = fn_location(&text, "on_step") {
                e.line = Some(l);
                e.column = Some(c);
            }
            return Err(Error::from(e));
        }
    };
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or(file.clone());
    let sources = rt.sources.borrow().clone();
    let mut scene = Scene::new(name, world, rt.host.scene_steps.get().unwrap_or(600));
    scene.sources = sources;
    scene.profiler = Some(rt.profiler.clone());
    let loaded = rt.clone();
    scene.loaded_since = Some(Box::new(move |n| {
        loaded
            .sources
            .borrow()
            .get(n..)
            .map(<[_]>::to_vec)
            .unwrap_or_default()
    }));
    let reloading = rt.clone();
    scene.reloader = Some(Box::new(
        move |world: &mut AnyWorld, file: &str, text: &str| match world {
            AnyWorld::D2(w) => super::reload::reload(&reloading, w, file, text),
            AnyWorld::D3(w) => super::reload::reload(&reloading, w, file, text),
        },
    ));
    if let Some(on_step) = on_step {
        scene.on_step = Some(Box::new(move |world: &mut AnyWorld| on_step.call(world)));
    }
    Ok(scene)
}

/// A scene's `on_step(world)`, called after every step.
struct OnStep {
    rt: Rc<Runtime>,
    ast: rhai::AST,
    file: String,
    line: Option<(usize, usize)>,
}

impl OnStep {
    fn call(&self, world: &mut AnyWorld) -> Result<Option<String>, Error> {
        let options = CallFnOptions::new().eval_ast(false).rewind_scope(true);
        let mut scope = Scope::new();
        let run = || {
            self.rt.engine.call_fn_with_options::<Dynamic>(
                options,
                &mut scope,
                &self.ast,
                "on_step",
                (WorldRef,),
            )
        };
        let step = match world {
            AnyWorld::D2(w) => w.step_count(),
            AnyWorld::D3(w) => w.step_count(),
        };
        let result = self.rt.profiler.time("scene", "on_step", || match world {
            AnyWorld::D2(w) => self.rt.host.enter::<DVec2, _>(&mut Env::World(w), run),
            AnyWorld::D3(w) => self.rt.host.enter::<DVec3, _>(&mut Env::World(w), run),
        });
        result.map(drop).map_err(|e| {
            let mut err = eval_error(
                &self.file,
                Some("on_step"),
                self.line,
                &e,
                self.rt.engine.max_operations(),
            );
            err.step = Some(step);
            Error::from(err)
        })?;
        Ok(self.rt.host.stop.borrow_mut().take())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KIND: &str = "const SIGHT = 5.0; // how far\nconst SIGHT2 = 1;\nfn update(me, dt) {}\n";

    #[test]
    fn a_kinds_sets_replace_its_constants_and_leave_the_rest() {
        let sets = [
            ("boid.SIGHT".to_string(), "3".to_string()),
            ("N".to_string(), "7".to_string()),
            ("other.SIGHT".to_string(), "9".to_string()),
        ];
        let text = crate::script::kind_text_with_sets("boid.rhai", "boid", KIND, &sets)
            .expect("boid has SIGHT");
        assert!(text.starts_with("const SIGHT = 3; // how far\n"), "{text}");
        assert!(text.contains("const SIGHT2 = 1;"), "{text}");
        let plain =
            crate::script::kind_text_with_sets("x.rhai", "x", KIND, &sets).expect("no sets");
        assert_eq!(plain, KIND, "a kind no set names keeps its text");
    }

    #[test]
    fn a_kinds_set_of_no_constant_names_the_kind_and_its_constants() {
        let sets = [("boid.SPEED".to_string(), "3".to_string())];
        let err = crate::script::kind_text_with_sets("boid.rhai", "boid", KIND, &sets)
            .expect_err("boid has no SPEED");
        let shown = err.to_string();
        assert!(shown.contains("boid.rhai"), "{shown}");
        assert!(
            shown.contains("the kind 'boid' has no constant SPEED"),
            "{shown}"
        );
        assert!(shown.contains("its constants are SIGHT, SIGHT2"), "{shown}");
    }

    #[test]
    fn a_set_value_that_is_no_number_or_bool_is_a_string() {
        assert_eq!(literal("2.5"), "2.5");
        assert_eq!(literal("true"), "true");
        assert_eq!(literal("\"x\""), "\"x\"");
        assert_eq!(literal("wide"), "\"wide\"");
    }
}
