//! Kinds written as scripts: loading a kind file (the calls of its hooks are in
//! [`super::kind_calls`]).
//!
//! A kind file is named for its kind (`bullet.rhai` defines `bullet`). Its top level may say
//! `extends "parent";` and `defaults(#{ radius: 0.1, ... });`, and define `const`s; it defines
//! any of `init(me)`, `update(me, dt)`, `collides_with(me, other)`, `collide(me, other)` or
//! `collide(me, other, contact)`, `touch_begin(me, other, contact)`, `touch_end(me, other)`,
//! `on_death(me)`, `on_damage(me, amount, source)`. Hooks it does not define are inherited
//! from its parent kind, and from the engine beyond that; `me.parent_collide(other)` and its
//! kin call the parent's (see [`super::kind_calls`]).

use super::api::{error, fail, num_or, props_from_map, Res};
use super::errors::{eval_error, fn_location};
use super::host::Dim;
use super::{read_script, Runtime, SourceFile};
use crate::error::{Error, ScriptError};
use crate::kind::{KindDefaults, KindId};
use crate::world::World;
use rhai::grain::{Compiler, Program, VmKeep};
use rhai::{FnCallCache, Map, Position, Scope, AST};
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::rc::{Rc, Weak};

/// The hooks a kind may define, with the numbers of parameters each may take.
pub(crate) const HOOKS: [(&str, &[usize]); 8] = [
    ("init", &[1]),
    ("update", &[2]),
    ("collides_with", &[2]),
    ("collide", &[2, 3]),
    ("touch_begin", &[3]),
    ("touch_end", &[2]),
    ("on_death", &[1]),
    ("on_damage", &[3]),
];

/// The parameters of hook `name`, as error messages name them.
pub(crate) fn hook_params(name: &str) -> &'static str {
    match name {
        "init" | "on_death" => "me",
        "update" => "me, dt",
        "collide" => "me, other or me, other, contact",
        "touch_begin" => "me, other, contact",
        "on_damage" => "me, amount, source",
        _ => "me, other",
    }
}

/// The keys `defaults(#{ ... })` accepts.
const DEFAULT_KEYS: &[&str] = &[
    "radius",
    "density",
    "mass",
    "priority",
    "restitution",
    "fixed",
    "health",
    "color",
    "props",
    "rule_depends_on_state",
];

/// What a kind file's top level declares.
#[derive(Default)]
pub(crate) struct KindDecl {
    pub parent: Option<String>,
    pub defaults: Option<(Map, Position)>,
}

/// One hook: where it is defined (in this kind's file or an ancestor's).
pub(crate) struct HookFn {
    pub file: String,
    pub line: Option<(usize, usize)>,
    /// Its number of parameters (`collide` may take 2 or 3).
    pub params: usize,
    /// The kind whose file defines it: a `parent_*` call inside it goes to that kind's parent.
    pub(super) owner: Weak<ScriptKindDef>,
    pub(super) scope: RefCell<Scope<'static>>,
}

/// A loaded kind: its name, defaults, and hooks (own or inherited).
pub(crate) struct ScriptKindDef {
    pub name: String,
    pub file: String,
    /// The file's text it was built from (a kind extending this one is rebuilt from its own
    /// text when this one is reloaded).
    pub text: Rc<str>,
    pub parent: Option<String>,
    pub defaults: KindDefaults,
    pub rule_depends_on_state: bool,
    /// The kind's functions merged over its parent's: a function redefined here replaces the
    /// parent's everywhere, also when the parent's hooks call it (as C++ virtuals did in Pop).
    pub(super) ast: Rc<AST>,
    hooks: [Option<Rc<HookFn>>; HOOKS.len()],
    /// The parent kind, when it is a script kind.
    pub(super) parent_def: Option<Rc<ScriptKindDef>>,
    /// What the calls of its hooks resolved function names to, kept for the next calls: they
    /// all run in `ast` with the one engine, so the answers stay right.
    pub(super) calls: RefCell<FnCallCache>,
    /// `ast` compiled to rhai's bytecode (Grain), which runs the hooks; its virtual machine's
    /// state is kept from one call to the next in `vm`.
    pub(super) program: Program<'static>,
    pub(super) vm: RefCell<VmKeep>,
}

impl ScriptKindDef {
    pub(super) fn hook(&self, name: &str) -> Option<&Rc<HookFn>> {
        HOOKS
            .iter()
            .position(|(n, _)| *n == name)
            .and_then(|i| self.hooks[i].as_ref())
    }

    /// Names of the hooks this kind has (own or inherited).
    pub fn hook_names(&self) -> impl Iterator<Item = &'static str> + '_ {
        HOOKS
            .iter()
            .zip(&self.hooks)
            .filter(|(_, h)| h.is_some())
            .map(|((n, _), _)| *n)
    }
}

/// Where the kind `name_or_path` is: a path (ends in `.rhai` or has a `/`), or a name looked up
/// in the runtime's kind folders.
fn resolve(rt: &Runtime, name_or_path: &str) -> Result<PathBuf, Error> {
    if name_or_path.ends_with(".rhai") || name_or_path.contains('/') {
        return Ok(PathBuf::from(name_or_path));
    }
    for dir in &rt.kind_dirs {
        let candidate = dir.join(format!("{name_or_path}.rhai"));
        if candidate.is_file() {
            return Ok(candidate);
        }
    }
    let looked: Vec<String> = rt
        .kind_dirs
        .iter()
        .map(|d| d.display().to_string())
        .collect();
    Err(Error::UnknownKind {
        kind: name_or_path.to_string(),
        known: format!(
            "the native kinds ball and wall; no file {name_or_path}.rhai in {}",
            looked.join(", ")
        ),
    })
}

fn kind_name(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Loads (or finds already loaded) the script kind `name_or_path`, and its parents.
pub(crate) fn load_def(rt: &Runtime, name_or_path: &str) -> Result<Rc<ScriptKindDef>, Error> {
    if let Some(def) = rt.kinds.borrow().get(name_or_path) {
        return Ok(def.clone());
    }
    let path = resolve(rt, name_or_path)?;
    let name = kind_name(&path);
    if let Some(def) = rt.kinds.borrow().get(&name) {
        return Ok(def.clone());
    }
    let text = read_script(&path)?;
    define(rt, path.display().to_string(), name, text)
}

/// Defines the kind `name` from `text`, the text of its file `file`, and loads its parents.
pub(crate) fn define(
    rt: &Runtime,
    file: String,
    name: String,
    text: String,
) -> Result<Rc<ScriptKindDef>, Error> {
    let def = build(rt, file.clone(), name.clone(), &text)?;
    // The text built from, with any `--set KIND.NAME` in it, is what a replay needs.
    rt.sources.borrow_mut().push(SourceFile {
        path: file,
        text: def.text.to_string(),
    });
    rt.kinds.borrow_mut().insert(name, def.clone());
    Ok(def)
}

/// The kind `name` built from `text`, the text of its file `file` (with the constants
/// `--set KIND.NAME` gives it set), its parents loaded; not yet among the runtime's kinds.
pub(crate) fn build(
    rt: &Runtime,
    file: String,
    name: String,
    text: &str,
) -> Result<Rc<ScriptKindDef>, Error> {
    let sets = rt.kind_sets.borrow().get(&name).cloned();
    let set_text;
    let text = match sets {
        Some(sets) => {
            set_text = super::scene::kind_constant_set(&file, &name, text, &sets)?;
            set_text.as_str()
        }
        None => text,
    };
    let ast = rt
        .compile(&file, text)
        .map_err(|e| in_kind(e, &file, &name))?;

    // Run the top level once, with no world reachable: it declares, it does not act.
    *rt.host.kind_decl.borrow_mut() = Some(KindDecl::default());
    let mut scope = Scope::new();
    let ran = rt
        .host
        .without_env(|| rt.engine.run_ast_with_scope(&mut scope, &ast));
    let decl = rt.host.kind_decl.borrow_mut().take().unwrap_or_default();
    ran.map_err(|e| Error::from(eval_error(&file, None, None, &e, u64::MAX)))?;

    // Top-level constants become visible inside the hooks.
    let mut constants = Scope::new();
    for (n, is_const, value) in scope.iter() {
        if is_const {
            constants.push_constant(n.to_string(), value);
        }
    }
    let own = rt.engine.optimize_ast(
        &constants,
        ast.clone_functions_only(),
        rhai::OptimizationLevel::Simple,
    );

    let parent = match &decl.parent {
        Some(p) if p == &name => {
            let mut e = ScriptError::new(&file, format!("kind '{name}' cannot extend itself"));
            e.kind = Some(name);
            return Err(Error::from(e));
        }
        Some(p) if p == "ball" || p == "wall" => None,
        Some(p) => Some(load_def(rt, p).map_err(|e| in_kind(e, &file, &name))?),
        None => None,
    };
    let mut defaults = parent
        .as_ref()
        .map(|p| p.defaults.clone())
        .unwrap_or_default();
    let mut rule_depends_on_state = parent.as_ref().is_some_and(|p| p.rule_depends_on_state);
    if let Some((map, pos)) = &decl.defaults {
        apply_defaults(&mut defaults, &mut rule_depends_on_state, map).map_err(|e| {
            let mut err = eval_error(&file, None, None, &e, u64::MAX);
            if err.line.is_none() {
                err.line = pos.line();
                err.column = pos.position();
            }
            err.kind = Some(name.clone());
            Error::from(err)
        })?;
    }

    // A kind file may define a hook at one arity only (`collide` with 2 or 3 parameters).
    let mut found: [Option<usize>; HOOKS.len()] = Default::default();
    for (i, (hook, arities)) in HOOKS.iter().enumerate() {
        let mine: Vec<usize> = own
            .iter_functions()
            .filter(|f| f.name == *hook)
            .map(|f| f.params.len())
            .collect();
        let wrong = mine.iter().find(|n| !arities.contains(n));
        if wrong.is_some() || mine.len() > 1 {
            let message = match wrong {
                Some(n) => {
                    let counts: Vec<String> = arities.iter().map(|a| a.to_string()).collect();
                    let plural = if arities == &[1] { "" } else { "s" };
                    format!(
                        "hook {hook} takes {} parameter{plural} ({}), not {n}",
                        counts.join(" or "),
                        hook_params(hook)
                    )
                }
                None => format!(
                    "hook {hook} is defined twice; define it once, with ({})",
                    hook_params(hook)
                ),
            };
            let mut e = ScriptError::new(&file, message);
            if let Some((l, c)) = fn_location(text, hook) {
                e.line = Some(l);
                e.column = Some(c);
            }
            e.kind = Some(name.clone());
            return Err(Error::from(e));
        }
        found[i] = mine.first().copied();
    }

    let ast = Rc::new(match &parent {
        Some(p) => p.ast.merge(&own),
        None => own,
    });
    let program = Compiler::new().compile(&ast);
    let def = Rc::new_cyclic(|me: &Weak<ScriptKindDef>| {
        let mut hooks: [Option<Rc<HookFn>>; HOOKS.len()] = Default::default();
        for (i, (hook, _)) in HOOKS.iter().enumerate() {
            hooks[i] = match found[i] {
                Some(params) => Some(Rc::new(HookFn {
                    file: file.clone(),
                    line: fn_location(text, hook),
                    params,
                    owner: me.clone(),
                    scope: RefCell::new(Scope::new()),
                })),
                None => parent.as_ref().and_then(|p| p.hooks[i].clone()),
            };
        }
        ScriptKindDef {
            ast,
            name: name.clone(),
            file: file.clone(),
            text: Rc::from(text),
            parent: decl.parent.clone(),
            defaults,
            rule_depends_on_state,
            hooks,
            parent_def: parent.clone(),
            calls: RefCell::new(FnCallCache::default()),
            program,
            vm: RefCell::new(VmKeep::default()),
        }
    });
    Ok(def)
}

fn in_kind(e: Error, file: &str, name: &str) -> Error {
    match e {
        Error::Script(mut s) => {
            if s.file == file {
                s.kind.get_or_insert_with(|| name.to_string());
            }
            Error::Script(s)
        }
        other => {
            let mut err = ScriptError::new(file, other.to_string());
            err.kind = Some(name.to_string());
            Error::from(err)
        }
    }
}

fn apply_defaults(d: &mut KindDefaults, depends: &mut bool, map: &Map) -> Res<()> {
    for (key, value) in map {
        let n = |what: &str| num_or(value, what);
        match key.as_str() {
            "radius" => d.radius = n("radius")?,
            "density" => {
                d.density = n("density")?;
                d.mass = None;
            }
            "mass" => d.mass = Some(n("mass")?),
            "priority" => d.priority = n("priority")?,
            "restitution" => d.restitution = n("restitution")?,
            "health" => d.health = n("health")?,
            "fixed" => {
                d.fixed = value
                    .as_bool()
                    .map_err(|_| error("fixed must be true or false"))?
            }
            "rule_depends_on_state" => {
                *depends = value
                    .as_bool()
                    .map_err(|_| error("rule_depends_on_state must be true or false"))?
            }
            "color" => d.color = Some(value.to_string()),
            "props" => match value.clone().try_cast::<Map>() {
                Some(props) => d.props.extend(props_from_map(&props)?),
                None => return fail("props must be a map, e.g. props: #{ damage: 1 }"),
            },
            other => {
                return fail(format!(
                    "unknown default '{other}'; a kind's defaults are {}",
                    DEFAULT_KEYS.join(", ")
                ))
            }
        }
    }
    Ok(())
}

/// Loads the kind `name_or_path` (and its parents) into `world`, if it is not there yet.
pub(crate) fn load_into<V: Dim>(
    rt: &Rc<Runtime>,
    world: &mut World<V>,
    name_or_path: &str,
) -> Result<KindId, Error> {
    if let Ok(id) = world.kinds().id(name_or_path) {
        return Ok(id);
    }
    let def = load_def(rt, name_or_path)?;
    if let Ok(id) = world.kinds().id(&def.name) {
        return Ok(id);
    }
    let parent = match &def.parent {
        Some(p) if p == "ball" || p == "wall" => Some(p.clone()),
        Some(p) => {
            load_into(rt, world, p)?;
            Some(p.clone())
        }
        None => None,
    };
    let hooks = Rc::new(ScriptKind::new(def.clone(), rt.clone()));
    let id = world
        .register_kind(&def.name, parent.as_deref(), def.defaults.clone(), hooks)
        .map_err(|e| in_kind(e, &def.file, &def.name))?;
    super::kind_refs::load_named(rt, world, &def.file)?;
    Ok(id)
}

pub(crate) use super::kind_calls::{
    note_default, parent_collide, parent_collides_with, parent_plain, HookFrame, ScriptKind,
};
