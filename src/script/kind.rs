//! Kinds written as scripts: loading a kind file, and the [`KindHooks`] implementation that
//! calls its hooks.
//!
//! A kind file is named for its kind (`bullet.rhai` defines `bullet`). Its top level may say
//! `extends "parent";` and `defaults(#{ radius: 0.1, ... });`, and define `const`s; it defines
//! any of `init(me)`, `update(me, dt)`, `collides_with(me, other)`, `collide(me, other)`. Hooks it
//! does not define are inherited from its parent kind, and from the engine beyond that.

use super::api::{error, fail, num_or, props_from_map, rule_code, rule_of_code, CritterRef, Res};
use super::env::Env;
use super::errors::{eval_error, fn_location};
use super::host::Dim;
use super::{read_script, Runtime, SourceFile};
use crate::border::Topology;
use crate::context::{CollideCtx, UpdateCtx};
use crate::critter::{Critter, CritterId, CritterSpec};
use crate::error::{Error, ScriptError};
use crate::kind::{CollideRule, KindDefaults, KindHooks, KindId, KindSet, RuleCtx};
use crate::rng::Rng;
use crate::vector::Vector;
use crate::world::World;
use rhai::{CallFnOptions, Dynamic, Map, Position, Scope, AST};
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// The hooks a kind may define, with their number of parameters.
pub(crate) const HOOKS: [(&str, usize); 4] = [
    ("init", 1),
    ("update", 2),
    ("collides_with", 2),
    ("collide", 2),
];

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
    scope: RefCell<Scope<'static>>,
}

/// A loaded kind: its name, defaults, and hooks (own or inherited).
pub(crate) struct ScriptKindDef {
    pub name: String,
    pub file: String,
    pub parent: Option<String>,
    pub defaults: KindDefaults,
    pub rule_depends_on_state: bool,
    /// The kind's functions merged over its parent's: a function redefined here replaces the
    /// parent's everywhere, also when the parent's hooks call it (as C++ virtuals did in Pop).
    ast: Rc<AST>,
    hooks: [Option<Rc<HookFn>>; 4],
}

impl ScriptKindDef {
    fn hook(&self, name: &str) -> Option<&Rc<HookFn>> {
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
    let ast = rt
        .compile(&file, &text)
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

    let mut hooks: [Option<Rc<HookFn>>; 4] = Default::default();
    for (i, (hook, arity)) in HOOKS.iter().enumerate() {
        let mine = own.iter_functions().find(|f| f.name == *hook);
        hooks[i] = match mine {
            Some(f) if f.params.len() != *arity => {
                let mut e = ScriptError::new(
                    &file,
                    format!(
                        "hook {hook} takes {arity} parameter{} ({}), not {}",
                        if *arity == 1 { "" } else { "s" },
                        match *hook {
                            "init" => "me",
                            "update" => "me, dt",
                            _ => "me, other",
                        },
                        f.params.len()
                    ),
                );
                if let Some((l, c)) = fn_location(&text, hook) {
                    e.line = Some(l);
                    e.column = Some(c);
                }
                e.kind = Some(name.clone());
                return Err(Error::from(e));
            }
            Some(_) => Some(Rc::new(HookFn {
                file: file.clone(),
                line: fn_location(&text, hook),
                scope: RefCell::new(Scope::new()),
            })),
            None => parent.as_ref().and_then(|p| p.hooks[i].clone()),
        };
    }

    let ast = Rc::new(match &parent {
        Some(p) => p.ast.merge(&own),
        None => own,
    });
    let def = Rc::new(ScriptKindDef {
        ast,
        name: name.clone(),
        file: file.clone(),
        parent: decl.parent.clone(),
        defaults,
        rule_depends_on_state,
        hooks,
    });
    rt.sources
        .borrow_mut()
        .push(SourceFile { path: file, text });
    rt.kinds.borrow_mut().insert(name, def.clone());
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
    let hooks = Rc::new(ScriptKind {
        def: def.clone(),
        rt: rt.clone(),
    });
    let id = world
        .register_kind(&def.name, parent.as_deref(), def.defaults.clone(), hooks)
        .map_err(|e| in_kind(e, &def.file, &def.name))?;
    super::kind_refs::load_named(rt, world, &def.file)?;
    Ok(id)
}

/// A script kind as the engine sees it.
pub(crate) struct ScriptKind {
    def: Rc<ScriptKindDef>,
    rt: Rc<Runtime>,
}

impl ScriptKind {
    #[must_use = "a hook's result says what it did"]
    fn call(&self, hook: &str, f: &HookFn, args: impl rhai::FuncArgs) -> Result<Dynamic, Error> {
        let options = CallFnOptions::new().eval_ast(false).rewind_scope(true);
        // Timed per kind and hook when the profiler is on (`run --stats`, script/profile.rs).
        let profiler = &self.rt.profiler;
        let result = profiler.time(&self.def.name, hook, || match f.scope.try_borrow_mut() {
            Ok(mut scope) => self.rt.engine.call_fn_with_options::<Dynamic>(
                options,
                &mut scope,
                &self.def.ast,
                hook,
                args,
            ),
            // A hook re-entered (a spawn's init inside another hook): use a fresh scope.
            Err(_) => self.rt.engine.call_fn_with_options::<Dynamic>(
                options,
                &mut Scope::new(),
                &self.def.ast,
                hook,
                args,
            ),
        });
        result.map_err(|e| {
            let mut err = eval_error(&f.file, Some(hook), f.line, &e, self.max_ops());
            err.kind = Some(self.def.name.clone());
            Error::from(err)
        })
    }

    fn max_ops(&self) -> u64 {
        self.rt.engine.max_operations()
    }

    fn wrong_type(&self, hook: &str, f: &HookFn, got: &Dynamic, want: &str, hint: &str) -> Error {
        let mut err = ScriptError::new(
            &f.file,
            format!(
                "{hook} must return {want}, but returned {got} ({})",
                got.type_name()
            ),
        );
        if let Some((l, c)) = f.line {
            err.line = Some(l);
            err.column = Some(c);
        }
        err.kind = Some(self.def.name.clone());
        err.hook = Some(hook.to_string());
        err.hint = Some(hint.to_string());
        Error::from(err)
    }
}

impl<V: Dim> KindHooks<V> for ScriptKind {
    fn collides_with(&self, ctx: &RuleCtx<'_, V>) -> Result<CollideRule, Error> {
        let Some(f) = self.def.hook("collides_with") else {
            return Ok(crate::kind::default_collides_with(ctx.me, ctx.other));
        };
        let mut view = PairView {
            a: ctx.me,
            b: ctx.other,
            kinds: ctx.kinds,
            topo: ctx.topo,
            rng: Rng::new(0),
        };
        let args = (CritterRef(ctx.me.id()), CritterRef(ctx.other.id()));
        let got = self
            .rt
            .host
            .enter::<V, _>(&mut view, || self.call("collides_with", f, args))?;
        match got.as_int().ok().and_then(rule_of_code) {
            Some(rule) => Ok(rule),
            None => Err(self.wrong_type(
                "collides_with",
                f,
                &got,
                "DONT_COLLIDE, COLLIDE_AS_CALLER, COLLIDE_AS_ARG or COLLIDE_EITHER_WAY",
                &format!(
                    "end collides_with with one of the rule constants (they are the numbers {}..{})",
                    rule_code(CollideRule::DontCollide),
                    rule_code(CollideRule::EitherWay)
                ),
            )),
        }
    }

    fn rule_depends_on_state(&self) -> bool {
        self.def.rule_depends_on_state
    }

    fn collide(&self, ctx: &mut CollideCtx<'_, V>) -> Result<bool, Error> {
        let Some(f) = self.def.hook("collide") else {
            return Ok(ctx.collide_default());
        };
        let args = (CritterRef(ctx.me().id()), CritterRef(ctx.other().id()));
        let got = self
            .rt
            .host
            .enter::<V, _>(&mut **ctx, || self.call("collide", f, args))?;
        got.as_bool().map_err(|_| {
            self.wrong_type(
                "collide",
                f,
                &got,
                "true or false (touched and handled)",
                "end collide with `true`, `false`, or `me.collide_default(other)`",
            )
        })
    }

    fn has_collide(&self) -> bool {
        self.def.hook("collide").is_some()
    }

    fn has_update(&self) -> bool {
        self.def.hook("update").is_some()
    }

    fn update(&self, ctx: &mut UpdateCtx<'_, V>, dt: f64) -> Result<(), Error> {
        if let Some(f) = self.def.hook("update") {
            let args = (CritterRef(ctx.me().id()), dt);
            self.rt
                .host
                .enter::<V, _>(&mut **ctx, || self.call("update", f, args))
                .map(drop)?;
        }
        Ok(())
    }

    fn has_init(&self) -> bool {
        self.def.hook("init").is_some()
    }

    fn init(&self, ctx: &mut UpdateCtx<'_, V>) -> Result<(), Error> {
        if let Some(f) = self.def.hook("init") {
            let args = (CritterRef(ctx.me().id()),);
            self.rt
                .host
                .enter::<V, _>(&mut **ctx, || self.call("init", f, args))
                .map(drop)?;
        }
        Ok(())
    }
}

/// What `collides_with` may see: the two critters, read-only.
struct PairView<'a, V: Vector> {
    a: &'a Critter<V>,
    b: &'a Critter<V>,
    kinds: &'a KindSet<V>,
    topo: &'a Topology<V>,
    rng: Rng,
}

impl<V: Vector> Env<V> for PairView<'_, V> {
    fn critter(&self, id: CritterId) -> Option<&Critter<V>> {
        [self.a, self.b].into_iter().find(|c| c.id() == id)
    }
    fn critter_mut(&mut self, _id: CritterId) -> Option<&mut Critter<V>> {
        None
    }
    fn kinds(&self) -> &KindSet<V> {
        self.kinds
    }
    fn topology(&self) -> &Topology<V> {
        self.topo
    }
    fn step_count(&self) -> u64 {
        0
    }
    fn time(&self) -> f64 {
        0.0
    }
    fn dt(&self) -> f64 {
        0.0
    }
    fn rng(&mut self) -> &mut Rng {
        // collides_with must not draw numbers: its answer may be cached.
        &mut self.rng
    }
    fn die(&mut self, _id: CritterId) {}
    fn damage(&mut self, _id: CritterId, _amount: f64) {}
    fn spawn(&mut self, _spec: CritterSpec<V>) -> Result<Option<CritterId>, Error> {
        Err(Error::InvalidKind {
            kind: "collides_with".into(),
            reason: "collides_with only answers how two critters meet; spawn in collide or update"
                .into(),
        })
    }
    fn log(&mut self, _line: String) {}
    fn critters_of(&self, _kind: KindId) -> Vec<CritterId> {
        Vec::new()
    }
    fn collide_default(&mut self, _caller: CritterId, _arg: CritterId) -> Result<bool, String> {
        Err("collide_default belongs in collide, not collides_with".into())
    }
    fn world(&mut self) -> Option<&mut World<V>> {
        None
    }
}
