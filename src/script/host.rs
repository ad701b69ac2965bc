//! The bridge between running scripts and the world they act on.
//!
//! A script function registered with the engine cannot hold a borrow of the world: the world
//! calls the script (from a hook, inside `World::step`), and the script calls back into the world.
//! So while a script runs, the [`Host`] holds a raw pointer to what the script may touch: the
//! whole [`World`] (scene setup, `on_step`) or a hook's [`Access`] (inside a step). The pointer is
//! set by [`Host::enter`] for exactly the duration of one call into the script and restored by a
//! guard, so it never outlives the borrow it came from; script functions reach it through
//! [`with_env!`], one short-lived `&mut` at a time.

use crate::border::Topology;
use crate::context::Access;
use crate::critter::{Critter, CritterId, CritterSpec};
use crate::error::Error;
use crate::kind::{KindId, KindSet};
use crate::rng::Rng;
use crate::vector::Vector;
use crate::world::World;
use glam::{DVec2, DVec3};
use std::cell::{Cell, RefCell};

/// What a script may do to the world it runs in.
pub(crate) trait Env<V: Vector> {
    fn critter(&self, id: CritterId) -> Option<&Critter<V>>;
    fn critter_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>>;
    fn kinds(&self) -> &KindSet<V>;
    fn topology(&self) -> &Topology<V>;
    fn step_count(&self) -> u64;
    fn time(&self) -> f64;
    fn dt(&self) -> f64;
    fn rng(&mut self) -> &mut Rng;
    fn die(&mut self, id: CritterId);
    fn damage(&mut self, id: CritterId, amount: f64);
    /// Spawns now (`Some(id)`) between steps, or queues for the end of the step (`None`).
    fn spawn(&mut self, spec: CritterSpec<V>) -> Result<Option<CritterId>, Error>;
    fn log(&mut self, line: String);
    fn critters_of(&self, kind: KindId) -> Vec<CritterId>;
    fn touches(&self, a: CritterId, b: CritterId) -> bool {
        match (self.critter(a), self.critter(b)) {
            (Some(x), Some(y)) => crate::response::touches(self.topology(), x, y),
            _ => false,
        }
    }
    fn contains(&self, outer: CritterId, inner: CritterId) -> bool {
        match (self.critter(outer), self.critter(inner)) {
            (Some(o), Some(i)) => crate::response::contains(self.topology(), o, i),
            _ => false,
        }
    }
    fn distance(&self, a: CritterId, b: CritterId) -> Option<f64> {
        let (x, y) = (self.critter(a)?, self.critter(b)?);
        Some(self.topology().delta(x.pos, y.pos).length())
    }
    /// The default response; `Err` outside a step.
    fn collide_default(&mut self, caller: CritterId, arg: CritterId) -> Result<bool, String>;
    /// The world itself, between steps (scene setup and `on_step`).
    fn world(&mut self) -> Option<&mut World<V>>;
}

impl<V: Vector> Env<V> for World<V> {
    fn critter(&self, id: CritterId) -> Option<&Critter<V>> {
        self.get(id)
    }
    fn critter_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        self.get_mut(id)
    }
    fn kinds(&self) -> &KindSet<V> {
        World::kinds(self)
    }
    fn topology(&self) -> &Topology<V> {
        World::topology(self)
    }
    fn step_count(&self) -> u64 {
        World::step_count(self)
    }
    fn time(&self) -> f64 {
        World::time(self)
    }
    fn dt(&self) -> f64 {
        World::dt(self)
    }
    fn rng(&mut self) -> &mut Rng {
        World::rng(self)
    }
    fn die(&mut self, id: CritterId) {
        // Between steps a death takes effect at once.
        let _ = self.remove(id);
    }
    fn damage(&mut self, id: CritterId, amount: f64) {
        let dead = match self.get_mut(id) {
            Some(c) => {
                c.traits_mut().health -= amount;
                c.health() <= 0.0
            }
            None => false,
        };
        if dead {
            let _ = self.remove(id);
        }
    }
    fn spawn(&mut self, spec: CritterSpec<V>) -> Result<Option<CritterId>, Error> {
        World::spawn(self, spec).map(Some)
    }
    fn log(&mut self, line: String) {
        self.log_line(line);
    }
    fn critters_of(&self, kind: KindId) -> Vec<CritterId> {
        self.critters()
            .iter()
            .filter(|c| c.is_alive() && World::kinds(self).is_kind(c.kind(), kind))
            .map(|c| c.id())
            .collect()
    }
    fn collide_default(&mut self, _caller: CritterId, _arg: CritterId) -> Result<bool, String> {
        Err("collide_default can only be called inside a collide hook".into())
    }
    fn world(&mut self) -> Option<&mut World<V>> {
        Some(self)
    }
}

impl<V: Vector> Env<V> for Access<'_, V> {
    fn critter(&self, id: CritterId) -> Option<&Critter<V>> {
        self.get(id)
    }
    fn critter_mut(&mut self, id: CritterId) -> Option<&mut Critter<V>> {
        self.get_mut(id)
    }
    fn kinds(&self) -> &KindSet<V> {
        Access::kinds(self)
    }
    fn topology(&self) -> &Topology<V> {
        Access::topology(self)
    }
    fn step_count(&self) -> u64 {
        self.step()
    }
    fn time(&self) -> f64 {
        Access::time(self)
    }
    fn dt(&self) -> f64 {
        Access::dt(self)
    }
    fn rng(&mut self) -> &mut Rng {
        Access::rng(self)
    }
    fn die(&mut self, id: CritterId) {
        Access::die(self, id)
    }
    fn damage(&mut self, id: CritterId, amount: f64) {
        Access::damage(self, id, amount)
    }
    fn spawn(&mut self, spec: CritterSpec<V>) -> Result<Option<CritterId>, Error> {
        Access::spawn(self, spec);
        Ok(None)
    }
    fn log(&mut self, line: String) {
        Access::log(self, line)
    }
    fn critters_of(&self, kind: KindId) -> Vec<CritterId> {
        Access::critters_of(self, kind)
    }
    fn collide_default(&mut self, caller: CritterId, arg: CritterId) -> Result<bool, String> {
        Ok(self.collide_default_pair(caller, arg).is_some())
    }
    fn world(&mut self) -> Option<&mut World<V>> {
        None
    }
}

/// The current environment of a running script, if any.
#[derive(Clone, Copy)]
pub(crate) enum EnvPtr {
    None,
    D2(*mut (dyn Env<DVec2> + 'static)),
    D3(*mut (dyn Env<DVec3> + 'static)),
}

/// A dimension scripts can run in.
pub(crate) trait Dim: Vector {
    fn env_ptr(env: *mut (dyn Env<Self> + 'static)) -> EnvPtr;
}

impl Dim for DVec2 {
    fn env_ptr(env: *mut (dyn Env<Self> + 'static)) -> EnvPtr {
        EnvPtr::D2(env)
    }
}

impl Dim for DVec3 {
    fn env_ptr(env: *mut (dyn Env<Self> + 'static)) -> EnvPtr {
        EnvPtr::D3(env)
    }
}

/// Shared state of one script runtime: where running scripts act, and per-step counters.
pub(crate) struct Host {
    env: Cell<EnvPtr>,
    /// Spawns requested by scripts in the current step.
    pub spawns: Cell<u64>,
    /// The step `spawns` counts for.
    pub spawns_step: Cell<u64>,
    /// Most spawns scripts may request in one step.
    pub max_spawns_per_step: u64,
    /// The runtime this host belongs to (for loading kinds from scripts).
    pub runtime: super::RuntimeLink,
    /// While a kind file's top level runs: what it declares.
    pub kind_decl: RefCell<Option<super::kind::KindDecl>>,
    /// The scene a script is building or a test is running (owned here while it runs; taken
    /// back with `Box::from_raw` by whoever finishes the run).
    pub scene_world: Cell<*mut crate::scenes::Scene>,
    /// True while test scripts run: they may load scenes and step worlds.
    pub testing: Cell<bool>,
    /// A test's wall-clock deadline.
    pub deadline: Cell<Option<std::time::Instant>>,
    /// The recording of a test's run (kept only if the test fails).
    pub test_recorder: RefCell<Option<crate::recording::Recorder>>,
    /// Where a test's run would be recorded, and the test's name; `None` records nothing.
    pub test_record_path: RefCell<Option<(std::path::PathBuf, String)>>,
    /// `critterbox test --bless`: golden recordings are rewritten, not compared.
    pub bless: Cell<bool>,
    /// Set by `world.stop(reason)`.
    pub stop: RefCell<Option<String>>,
    /// Steps the scene asked for (`world(#{ steps: ... })`).
    pub scene_steps: Cell<Option<u64>>,
    /// `--seed`, which wins over the scene's own seed.
    pub seed_override: Cell<Option<u64>>,
    /// A located error from deeper down (a kind file a scene loaded, a hook run by a spawn),
    /// kept whole while rhai carries its text up through the calling script.
    pub stashed: RefCell<Option<Box<crate::error::ScriptError>>>,
}

impl Host {
    pub fn new(max_spawns_per_step: u64) -> Self {
        Host {
            env: Cell::new(EnvPtr::None),
            spawns: Cell::new(0),
            spawns_step: Cell::new(u64::MAX),
            max_spawns_per_step,
            runtime: RefCell::new(std::rc::Weak::new()),
            kind_decl: RefCell::new(None),
            scene_world: Cell::new(std::ptr::null_mut()),
            testing: Cell::new(false),
            deadline: Cell::new(None),
            test_recorder: RefCell::new(None),
            test_record_path: RefCell::new(None),
            bless: Cell::new(false),
            stop: RefCell::new(None),
            scene_steps: Cell::new(None),
            seed_override: Cell::new(None),
            stashed: RefCell::new(None),
        }
    }

    /// Runs `f` with no world reachable from scripts (kind files' top level).
    pub fn without_env<R>(&self, f: impl FnOnce() -> R) -> R {
        struct Restore<'h>(&'h Cell<EnvPtr>, EnvPtr);
        impl Drop for Restore<'_> {
            fn drop(&mut self) {
                self.0.set(self.1);
            }
        }
        let _restore = Restore(&self.env, self.env.replace(EnvPtr::None));
        f()
    }

    /// Points scripts at `ptr` until [`Host::clear_env`] (a scene's top level, which spans many
    /// calls). The caller keeps the pointee alive and otherwise untouched until then.
    pub fn set_env(&self, ptr: EnvPtr) {
        self.env.set(ptr);
    }

    /// Takes back the scene a script made or loaded, and points scripts at nothing.
    pub fn take_scene(&self) -> Option<crate::scenes::Scene> {
        self.clear_env();
        let raw = self.scene_world.replace(std::ptr::null_mut());
        // SAFETY: `raw` came from `Box::into_raw` when the scene was stored, and the environment
        // pointing into it has just been cleared.
        (!raw.is_null()).then(|| *unsafe { Box::from_raw(raw) })
    }

    /// Stores `scene` as the one scripts act on, and points them at its world.
    pub fn put_scene(&self, scene: crate::scenes::Scene) {
        let raw = Box::into_raw(Box::new(scene));
        self.scene_world.set(raw);
        // SAFETY: `raw` stays alive until `take_scene`.
        let ptr = match unsafe { &mut (*raw).world } {
            crate::scenes::AnyWorld::D2(w) => env_of::<DVec2>(w),
            crate::scenes::AnyWorld::D3(w) => env_of::<DVec3>(w),
        };
        self.set_env(ptr);
    }

    /// The error as rhai should carry it; a located script error is also kept whole, so
    /// [`Host::locate`] can report it with its own file and line.
    pub fn carry(&self, e: crate::error::Error) -> Box<rhai::EvalAltResult> {
        let text = match e {
            crate::error::Error::Script(s) => {
                let text = s.to_string();
                *self.stashed.borrow_mut() = Some(s);
                text
            }
            other => other.to_string(),
        };
        Box::new(rhai::EvalAltResult::ErrorRuntime(
            rhai::Dynamic::from(text),
            rhai::Position::NONE,
        ))
    }

    /// The kept error if `e` is the one it carried up, else `fallback()`.
    pub fn locate(
        &self,
        e: &rhai::EvalAltResult,
        fallback: impl FnOnce() -> crate::error::ScriptError,
    ) -> crate::error::ScriptError {
        let kept = self.stashed.borrow_mut().take();
        match (kept, e.unwrap_inner()) {
            (Some(s), rhai::EvalAltResult::ErrorRuntime(v, _))
                if v.to_string() == s.to_string() =>
            {
                *s
            }
            _ => fallback(),
        }
    }

    /// Ends [`Host::set_env`].
    pub fn clear_env(&self) {
        self.env.set(EnvPtr::None);
    }

    /// Runs `f` with scripts acting on `env`; the previous environment is restored afterwards,
    /// also when `f` unwinds.
    pub fn enter<V: Dim, R>(&self, env: &mut dyn Env<V>, f: impl FnOnce() -> R) -> R {
        struct Restore<'h>(&'h Cell<EnvPtr>, EnvPtr);
        impl Drop for Restore<'_> {
            fn drop(&mut self) {
                self.0.set(self.1);
            }
        }
        let short: *mut (dyn Env<V> + '_) = env;
        // SAFETY: only the lifetime bound is erased. The pointer is stored for the duration of
        // `f` and removed by `Restore` before `env`'s borrow ends; it is dereferenced only inside
        // `f` (by script functions called from it), never concurrently with another use of `env`.
        let erased: *mut (dyn Env<V> + 'static) = unsafe { std::mem::transmute(short) };
        let _restore = Restore(&self.env, self.env.replace(V::env_ptr(erased)));
        f()
    }

    /// The current environment.
    pub fn current(&self) -> EnvPtr {
        self.env.get()
    }
}

/// Runs `$body` with `$env` bound to the current environment as `&mut dyn Env<V>`, for whichever
/// dimension the running world has. Evaluates to an error when no world is active.
macro_rules! with_env {
    ($host:expr, $env:ident => $body:expr) => {
        match $host.current() {
            $crate::script::host::EnvPtr::None => Err($crate::script::api::no_world()),
            $crate::script::host::EnvPtr::D2(p) => {
                // SAFETY: see `Host::enter`: the pointer is live while a script runs.
                #[allow(unused_unsafe)]
                let $env = unsafe { &mut *p };
                $body
            }
            $crate::script::host::EnvPtr::D3(p) => {
                // SAFETY: as above.
                #[allow(unused_unsafe)]
                let $env = unsafe { &mut *p };
                $body
            }
        }
    };
}
pub(crate) use with_env;

/// The environment pointer of a world (lifetime erased; see [`Host::enter`]).
pub(crate) fn env_of<V: Dim>(w: &mut World<V>) -> EnvPtr {
    let short: *mut (dyn Env<V> + '_) = w;
    // SAFETY: lifetime erasure only; callers keep `w` alive while the pointer is in use.
    let erased: *mut (dyn Env<V> + 'static) = unsafe { std::mem::transmute(short) };
    V::env_ptr(erased)
}
