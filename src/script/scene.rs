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

/// Replaces the value of `const NAME = ...;` at the top level for each override.
fn apply_sets(path: &str, text: &str, sets: &[(String, String)]) -> Result<String, Error> {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for (name, value) in sets {
        let literal = if value.parse::<f64>().is_ok()
            || value == "true"
            || value == "false"
            || value.starts_with('"')
        {
            value.clone()
        } else {
            format!("{value:?}")
        };
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
            let consts: Vec<String> = text
                .lines()
                .filter_map(|l| l.trim_start().strip_prefix("const "))
                .filter_map(|r| r.split(|c: char| c == '=' || c.is_whitespace()).next())
                .map(str::to_string)
                .collect();
            let mut e = ScriptError::new(
                path,
                format!("--set {name}: the scene has no constant {name}"),
            );
            e.hint = Some(if consts.is_empty() {
                "this scene declares no constants to set".into()
            } else {
                format!("its constants are {}", consts.join(", "))
            });
            return Err(Error::from(e));
        }
    }
    Ok(lines.join("\n"))
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
    let text = apply_sets(&file, &raw, sets).map_err(|e| {
        let scene = SourceFile {
            path: file.clone(),
            text: raw.clone(),
        };
        (e, vec![scene])
    })?;
    let rt = Runtime::new(options, path.parent());
    load_on(&rt, path, &file, text)
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
    let scene = load_on(&rt, path, &file, text).map_err(|(e, _)| e);
    let mut notes = rt.host.check_notes.borrow_mut().take().unwrap_or_default();
    for n in &mut notes {
        if n.file.is_empty() {
            n.file.clone_from(&file);
        }
    }
    (scene, notes)
}

/// Sets up the scene `file`, whose text (any `--set` applied) is `text`, in `rt`.
fn load_on(
    rt: &Rc<Runtime>,
    path: &Path,
    file: &str,
    text: String,
) -> Result<Scene, (Error, Vec<SourceFile>)> {
    let file = file.to_string();
    rt.sources.borrow_mut().push(SourceFile {
        path: file.clone(),
        text: text.clone(),
    });
    set_up(rt, path, &file, &text).map_err(|e| {
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
