//! Calling a script kind's hooks: [`ScriptKind`], the [`KindHooks`] implementation the engine
//! calls, the frames of the hooks running, and the `parent_*` calls that reach a parent kind's
//! hook (see [`parent_hook`]).

use super::api::{fail, rule_code, rule_of_code, CritterRef, Res, ScriptContact};
use super::env::{Env, PairView};
use super::errors::eval_error;
use super::host::{with_env, Dim, Host};
use super::kind_file::{HookFn, ScriptKindDef};
use super::Runtime;
use crate::critter::CritterId;
use crate::error::{Error, ScriptError};
use crate::kind::{CollideRule, KindHooks, RuleCtx};
use crate::rng::Rng;
use crate::step::access::{CollideCtx, HookContact, UpdateCtx};
use rhai::grain::Vm;
use rhai::{CallFnOptions, Dynamic, Scope, INT};
use std::cell::Cell;
use std::rc::Rc;
/// A script kind as the engine sees it.
pub(crate) struct ScriptKind {
    def: Rc<ScriptKindDef>,
    rt: Rc<Runtime>,
}

/// A hook running: the level of the kind chain whose function runs (so a `parent_*` call in it
/// goes one level up), for which critters, and what `contact.impulse` reads.
pub(crate) struct HookFrame {
    pub level: Rc<ScriptKindDef>,
    pub hook: &'static str,
    pub me: CritterId,
    pub other: Option<CritterId>,
    /// The contact `collide` was given, if it took one (boxed: every hook call pushes a frame).
    pub contact: Option<Box<ScriptContact>>,
    /// True on the first step of the pair's touching spell (`collide` only).
    pub first: bool,
    /// The impulse of the last `me.collide_default(other)` in this call (`collide` only).
    pub impulse: Option<Rc<Cell<f64>>>,
}

/// Takes a frame off the host's stack when dropped, also when the call unwinds.
struct Popped<'h>(&'h Host);

impl Drop for Popped<'_> {
    fn drop(&mut self) {
        // Dropped in place: `pop` would move the frame out first.
        let mut frames = self.0.frames.borrow_mut();
        let top = frames.len().saturating_sub(1);
        frames.truncate(top);
    }
}

impl ScriptKind {
    pub(super) fn new(def: Rc<ScriptKindDef>, rt: Rc<Runtime>) -> Self {
        ScriptKind { def, rt }
    }

    /// Calls hook `hook` (its function `f`) with `args`: the one place script hooks are
    /// invoked. `frame` says which critters and which level of the kind chain the call is for.
    #[must_use = "a hook's result says what it did"]
    fn call(
        &self,
        hook: &str,
        f: &HookFn,
        frame: HookFrame,
        args: impl rhai::FuncArgs,
    ) -> Result<Dynamic, Error> {
        self.rt.host.frames.borrow_mut().push(frame);
        let _pop = Popped(&self.rt.host);
        let options = CallFnOptions::new().eval_ast(false).rewind_scope(true);
        // Timed per kind and hook when the profiler is on (`run --stats`, profile.rs).
        let profiler = &self.rt.profiler;
        let engine = &self.rt.engine;
        let (scope, calls) = (f.scope.try_borrow_mut(), self.def.calls.try_borrow_mut());
        let result = profiler.time(&self.def.name, hook, || match (scope, calls) {
            // The kind's bytecode, unless it makes function pointers: a native function calling
            // one back (`map`, `filter`) finds only the AST's functions.
            (Ok(mut scope), Ok(mut calls)) => match self.def.vm.try_borrow_mut() {
                Ok(mut keep) if !self.def.program.makes_fn_pointers() => Vm::call_fn_kept(
                    engine,
                    &mut keep,
                    options,
                    &mut scope,
                    &self.def.program,
                    hook,
                    args,
                ),
                _ => engine.call_fn_cached(
                    &mut calls,
                    options,
                    &mut scope,
                    &self.def.ast,
                    hook,
                    args,
                ),
            },
            // A hook re-entered (a spawn's init inside another hook): a fresh scope and cache.
            _ => engine.call_fn_with_options(options, &mut Scope::new(), &self.def.ast, hook, args),
        });
        result.map_err(|e| {
            let mut err = eval_error(&f.file, Some(hook), f.line, &e, self.max_ops());
            err.kind = Some(self.def.name.clone());
            Error::from(err)
        })
    }

    /// The frame of a call of `f` (hook `hook`) for `me` and `other`.
    fn frame(
        &self,
        hook: &'static str,
        f: &HookFn,
        me: CritterId,
        other: Option<CritterId>,
    ) -> HookFrame {
        HookFrame {
            level: f.owner.upgrade().unwrap_or_else(|| self.def.clone()),
            hook,
            me,
            other,
            contact: None,
            first: false,
            impulse: None,
        }
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

    /// The answer of `collides_with`, checked.
    fn rule_of(&self, f: &HookFn, got: &Dynamic) -> Result<CollideRule, Error> {
        match got.as_int().ok().and_then(rule_of_code) {
            Some(rule) => Ok(rule),
            None => Err(self.wrong_type(
                "collides_with",
                f,
                got,
                "DONT_COLLIDE, COLLIDE_AS_CALLER, COLLIDE_AS_ARG or COLLIDE_EITHER_WAY",
                &format!(
                    "end collides_with with one of the rule constants (they are the numbers {}..{})",
                    rule_code(CollideRule::DontCollide),
                    rule_code(CollideRule::EitherWay)
                ),
            )),
        }
    }

    /// The answer of `collide`, checked.
    fn handled(&self, f: &HookFn, got: &Dynamic) -> Result<bool, Error> {
        got.as_bool().map_err(|_| {
            self.wrong_type(
                "collide",
                f,
                got,
                "true or false (touched and handled)",
                "end collide with `true`, `false`, or `me.collide_default(other)`",
            )
        })
    }

    /// Runs `collide` (`f`) for `me` and `other` in the environment already entered; `contact`
    /// is what a three-parameter `collide` gets.
    fn run_collide(
        &self,
        f: &HookFn,
        me: CritterId,
        other: CritterId,
        contact: ScriptContact,
        first: bool,
    ) -> Result<bool, Error> {
        let mut frame = self.frame("collide", f, me, Some(other));
        frame.first = first;
        let got = if f.params == 3 {
            let cell = Rc::new(Cell::new(0.0));
            frame.impulse = Some(cell.clone());
            let contact = contact.with_impulse(cell);
            frame.contact = Some(Box::new(contact.clone()));
            self.call(
                "collide",
                f,
                frame,
                (CritterRef(me), CritterRef(other), contact),
            )?
        } else {
            self.call("collide", f, frame, (CritterRef(me), CritterRef(other)))?
        };
        self.handled(f, &got)
    }
}

impl<V: Dim> KindHooks<V> for ScriptKind {
    fn collides_with(&self, ctx: &RuleCtx<'_, V>) -> Result<CollideRule, Error> {
        let Some(f) = self.def.hook("collides_with") else {
            return Ok(crate::kind::default_collides_with(ctx.me, ctx.other));
        };
        let mut rng = Rng::new(0);
        let mut view = Env::Pair(PairView {
            a: ctx.me,
            b: ctx.other,
            kinds: ctx.kinds,
            topo: ctx.topo,
            rng: &mut rng,
        });
        let (me, other) = (ctx.me.id(), ctx.other.id());
        let frame = self.frame("collides_with", f, me, Some(other));
        let args = (CritterRef(me), CritterRef(other));
        let got = self
            .rt
            .host
            .enter::<V, _>(&mut view, || self.call("collides_with", f, frame, args))?;
        self.rule_of(f, &got)
    }

    fn rule_depends_on_state(&self) -> bool {
        self.def.rule_depends_on_state
    }

    fn collide(&self, ctx: &mut CollideCtx<'_, V>) -> Result<bool, Error> {
        let Some(f) = self.def.hook("collide") else {
            return Ok(ctx.collide_default());
        };
        let (me, other) = (ctx.me().id(), ctx.other().id());
        // Only a three-parameter collide pays for its contact.
        let contact = match f.params {
            3 => ScriptContact::from(&ctx.contact()),
            _ => ScriptContact::default(),
        };
        let first = ctx.first;
        self.rt.host.enter_hook::<V, _>(&mut **ctx, || {
            self.run_collide(f, me, other, contact, first)
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
            let me = ctx.me().id();
            let frame = self.frame("update", f, me, None);
            self.rt
                .host
                .enter_hook::<V, _>(&mut **ctx, || {
                    self.call("update", f, frame, (CritterRef(me), dt))
                })
                .map(drop)?;
        }
        Ok(())
    }

    fn has_init(&self) -> bool {
        self.def.hook("init").is_some()
    }

    fn init(&self, ctx: &mut UpdateCtx<'_, V>) -> Result<(), Error> {
        if let Some(f) = self.def.hook("init") {
            let me = ctx.me().id();
            let frame = self.frame("init", f, me, None);
            self.rt
                .host
                .enter_hook::<V, _>(&mut **ctx, || {
                    self.call("init", f, frame, (CritterRef(me),))
                })
                .map(drop)?;
        }
        Ok(())
    }

    fn tracks_touch(&self) -> bool {
        KindHooks::<V>::has_touch_hooks(self)
            || self.def.hook("collide").is_some_and(|f| f.params == 3)
    }

    fn has_touch_hooks(&self) -> bool {
        self.def.hook("touch_begin").is_some() || self.def.hook("touch_end").is_some()
    }

    fn touch_begin(
        &self,
        ctx: &mut CollideCtx<'_, V>,
        contact: &HookContact<V>,
    ) -> Result<(), Error> {
        if let Some(f) = self.def.hook("touch_begin") {
            let (me, other) = (ctx.me().id(), ctx.other().id());
            let frame = self.frame("touch_begin", f, me, Some(other));
            let args = (
                CritterRef(me),
                CritterRef(other),
                ScriptContact::from(contact),
            );
            self.rt
                .host
                .enter_hook::<V, _>(&mut **ctx, || self.call("touch_begin", f, frame, args))
                .map(drop)?;
        }
        Ok(())
    }

    fn touch_end(&self, ctx: &mut CollideCtx<'_, V>) -> Result<(), Error> {
        if let Some(f) = self.def.hook("touch_end") {
            let (me, other) = (ctx.me().id(), ctx.other().id());
            let frame = self.frame("touch_end", f, me, Some(other));
            let args = (CritterRef(me), CritterRef(other));
            self.rt
                .host
                .enter_hook::<V, _>(&mut **ctx, || self.call("touch_end", f, frame, args))
                .map(drop)?;
        }
        Ok(())
    }

    fn has_on_death(&self) -> bool {
        self.def.hook("on_death").is_some()
    }

    fn on_death(&self, ctx: &mut UpdateCtx<'_, V>) -> Result<(), Error> {
        if let Some(f) = self.def.hook("on_death") {
            let me = ctx.me().id();
            let frame = self.frame("on_death", f, me, None);
            self.rt
                .host
                .enter_hook::<V, _>(&mut **ctx, || {
                    self.call("on_death", f, frame, (CritterRef(me),))
                })
                .map(drop)?;
        }
        Ok(())
    }

    fn has_on_damage(&self) -> bool {
        self.def.hook("on_damage").is_some()
    }

    fn on_damage(
        &self,
        ctx: &mut UpdateCtx<'_, V>,
        amount: f64,
        source: Option<CritterId>,
    ) -> Result<(), Error> {
        if let Some(f) = self.def.hook("on_damage") {
            let me = ctx.me().id();
            let frame = self.frame("on_damage", f, me, source);
            // The scene (or a test) is no critter: its damage comes from `()`.
            let source = source.map_or(Dynamic::UNIT, |id| Dynamic::from(CritterRef(id)));
            self.rt
                .host
                .enter_hook::<V, _>(&mut **ctx, || {
                    self.call("on_damage", f, frame, (CritterRef(me), amount, source))
                })
                .map(drop)?;
        }
        Ok(())
    }
}

/// What a `parent_*` call reaches: the hook of the nearest ancestor of the running level that
/// has one (with that ancestor, to run it in its own functions), or `None` for the engine's
/// default. Errors unless called inside hook `hook` on its own `me`.
fn parent_hook(
    host: &Host,
    hook: &'static str,
    me: CritterId,
) -> Res<(Option<ScriptKind>, Option<Rc<HookFn>>, HookFrame)> {
    let frames = host.frames.borrow();
    let call = format!("me.parent_{hook}");
    let Some(top) = frames.last() else {
        return fail(format!(
            "{call}(...) can only be called inside the kind's {hook} hook"
        ));
    };
    if top.hook != hook || top.me != me {
        return fail(format!(
            "{call}(...) can only be called inside the kind's {hook} hook, on its own `me` (it is called in {})",
            top.hook
        ));
    }
    let parent = top.level.parent_def.clone();
    let f = parent.as_ref().and_then(|p| p.hook(hook).cloned());
    let frame = HookFrame {
        level: top.level.clone(),
        hook,
        me,
        other: top.other,
        contact: top.contact.clone(),
        first: top.first,
        impulse: top.impulse.clone(),
    };
    drop(frames);
    let kind = match (&f, host.runtime()) {
        (Some(f), Ok(rt)) => {
            let def = f.owner.upgrade();
            def.map(|def| ScriptKind { def, rt })
        }
        (Some(_), Err(e)) => return Err(e),
        (None, _) => None,
    };
    Ok((kind, f, frame))
}

/// `me.parent_collide(other)` or with `contact`: the parent's `collide`, or the engine's
/// default response where no ancestor has one.
pub(crate) fn parent_collide(
    host: &Host,
    me: CritterId,
    other: CritterId,
    contact: Option<ScriptContact>,
) -> Res<bool> {
    let (kind, f, frame) = parent_hook(host, "collide", me)?;
    let (Some(kind), Some(f)) = (kind, f) else {
        let impulse = with_env!(host, env => env.collide_default(me, other).or_else(fail))?;
        if let (Some(j), Some(cell)) = (impulse, &frame.impulse) {
            cell.set(j);
        }
        return Ok(impulse.is_some());
    };
    let contact = match contact.or(frame.contact.map(|c| *c)) {
        Some(c) => c,
        None if f.params == 3 => {
            with_env!(host, env => ScriptContact::between(env, me, other, frame.first))?
        }
        None => ScriptContact::default(),
    };
    let mut inner = kind.frame("collide", &f, me, Some(other));
    inner.first = frame.first;
    // The parent's default response counts for the child's contact too.
    inner.impulse = frame.impulse;
    let got = if f.params == 3 {
        let cell = inner.impulse.get_or_insert_with(|| Rc::new(Cell::new(0.0)));
        let contact = contact.with_impulse(cell.clone());
        inner.contact = Some(Box::new(contact.clone()));
        kind.call(
            "collide",
            &f,
            inner,
            (CritterRef(me), CritterRef(other), contact),
        )
    } else {
        kind.call("collide", &f, inner, (CritterRef(me), CritterRef(other)))
    };
    let got = got.map_err(|e| host.carry(e))?;
    kind.handled(&f, &got).map_err(|e| host.carry(e))
}

/// Notes the impulse of `me.collide_default(other)` for the running `collide` of that pair.
pub(crate) fn note_default(host: &Host, me: CritterId, other: CritterId, impulse: Option<f64>) {
    if let (Some(j), Ok(frames)) = (impulse, host.frames.try_borrow()) {
        if let Some(top) = frames.last() {
            if let (true, Some(cell)) = (top.me == me && top.other == Some(other), &top.impulse) {
                cell.set(j);
            }
        }
    }
}

/// `me.parent_collides_with(other)`: the parent's answer, or Pop's default rule.
pub(crate) fn parent_collides_with(host: &Host, me: CritterId, other: CritterId) -> Res<INT> {
    let (kind, f, frame) = parent_hook(host, "collides_with", me)?;
    let (Some(kind), Some(f)) = (kind, f) else {
        return with_env!(host, env => match (env.critter(me), env.critter(other)) {
            (Some(a), Some(b)) => Ok(rule_code(crate::kind::default_collides_with(a, b))),
            _ => fail("parent_collides_with: a critter is gone"),
        });
    };
    let inner = kind.frame("collides_with", &f, me, frame.other);
    let got = kind
        .call(
            "collides_with",
            &f,
            inner,
            (CritterRef(me), CritterRef(other)),
        )
        .map_err(|e| host.carry(e))?;
    kind.rule_of(&f, &got)
        .map(rule_code)
        .map_err(|e| host.carry(e))
}

/// `me.parent_update(dt)` and `me.parent_init()`: the parent's hook, or nothing.
pub(crate) fn parent_plain(
    host: &Host,
    hook: &'static str,
    me: CritterId,
    dt: Option<f64>,
) -> Res<()> {
    let (kind, f, _) = parent_hook(host, hook, me)?;
    let (Some(kind), Some(f)) = (kind, f) else {
        return Ok(());
    };
    let inner = kind.frame(hook, &f, me, None);
    let got = match dt {
        Some(dt) => kind.call(hook, &f, inner, (CritterRef(me), dt)),
        None => kind.call(hook, &f, inner, (CritterRef(me),)),
    };
    got.map(drop).map_err(|e| host.carry(e))
}
