//! The bridge between running scripts and the world they act on.
//!
//! A script function registered with the engine cannot hold a borrow of the world: the world
//! calls the script (from a hook, inside `World::step`), and the script calls back into the
//! world. So the [`Host`] knows what running scripts may touch, its *target*:
//!
//! - its own scene (a scene's setup, a test's world), which it owns in a `RefCell` and lends
//!   anew to each script function that touches it, and to each [`Host::with_scene`];
//! - or what [`Host::enter`] lends for one call into a script: a hook's `Access` inside a step,
//!   or a scene's world during `on_step`, as a pointer whose lifetime is erased and which a
//!   guard takes back before the borrow it came from ends.
//!
//! Script functions reach the target through [`with_env!`], one short-lived [`Env`] at a
//! time: while one lives, the target is marked busy, so a second is never derived beside it.
//! Every pointer into the world is derived from one place (the host's scene, or the `&mut` lent
//! to `enter`) at the moment of use and dropped after it; none is kept across another `&mut`.

use super::api::{error, no_world, Res};
use super::env::Env;
use super::{Extension, Runtime};
use crate::error::ScriptError;
use crate::scenes::{AnyWorld, Scene};
use crate::step::access::Access;
use crate::vector::Vector;
use crate::world::World;
use glam::{DVec2, DVec3};
use std::cell::{Cell, RefCell, RefMut};
use std::rc::{Rc, Weak};

/// What scripts act on, its lifetime erased: an environment lent by [`Host::enter`], or the
/// host's own scene's world.
#[derive(Clone, Copy)]
pub(crate) enum EnvPtr {
    D2(*mut Env<'static, DVec2>),
    D3(*mut Env<'static, DVec3>),
    World2(*mut World<DVec2>),
    World3(*mut World<DVec3>),
}

/// A dimension scripts can run in.
pub(crate) trait Dim: Vector {
    fn env_ptr(env: *mut Env<'static, Self>) -> EnvPtr;
}

impl Dim for DVec2 {
    fn env_ptr(env: *mut Env<'static, Self>) -> EnvPtr {
        EnvPtr::D2(env)
    }
}

impl Dim for DVec3 {
    fn env_ptr(env: *mut Env<'static, Self>) -> EnvPtr {
        EnvPtr::D3(env)
    }
}

/// The pointer of `env`, its lifetime erased; see [`Host::enter`] and [`Host::access`] for how
/// long it is used.
fn erase<V: Dim>(env: &mut Env<'_, V>) -> EnvPtr {
    // Only the lifetime parameter changes, not the pointer. The callers dereference the result
    // only while the borrow it came from is live.
    let short: *mut Env<'_, V> = env;
    V::env_ptr(short.cast::<Env<'static, V>>())
}

/// What running scripts act on.
#[derive(Clone, Copy)]
enum Target {
    /// The host's scene (scripts fail with "no world yet" while it has none).
    Scene,
    /// What [`Host::enter`] lent for the current call.
    Entered(EnvPtr),
    /// No world: a kind file's top level.
    Nothing,
    /// In use by a script function (see [`Host::access`]).
    Busy,
}

/// Why [`Host::with_scene`] could not lend the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum NoScene {
    /// No script has made or loaded one.
    Missing,
    /// It is lent already: the caller runs inside its step (a kind's hook).
    Busy,
}

/// Shared state of one script runtime: where running scripts act, and per-step counters.
pub(crate) struct Host {
    target: Cell<Target>,
    /// The scene a script made or loaded, owned here until [`Host::take_scene`].
    scene: RefCell<Option<Scene>>,
    /// What the layer that made the runtime added to it (the test runner's API).
    pub extension: Option<Rc<dyn Extension>>,
    /// Spawns requested by scripts in the current step.
    pub spawns: Cell<u64>,
    /// The step `spawns` counts for.
    pub spawns_step: Cell<u64>,
    /// Most spawns scripts may request in one step.
    pub max_spawns_per_step: u64,
    /// The runtime this host belongs to (for loading kinds from scripts).
    runtime: Weak<Runtime>,
    /// While a kind file's top level runs: what it declares.
    pub kind_decl: RefCell<Option<super::kind_file::KindDecl>>,
    /// Set by `world.stop(reason)`.
    pub stop: RefCell<Option<String>>,
    /// Steps the scene asked for (`world(#{ steps: ... })`).
    pub scene_steps: Cell<Option<u64>>,
    /// `--seed`, which wins over the scene's own seed.
    pub seed_override: Cell<Option<u64>>,
    /// A located error from deeper down (a kind file a scene loaded, a hook run by a spawn),
    /// kept whole while rhai carries its text up through the calling script.
    pub stashed: RefCell<Option<Box<ScriptError>>>,
    /// The script hooks running, innermost last (for `parent_*` and `contact.impulse`).
    pub frames: RefCell<Vec<super::kind_file::HookFrame>>,
    /// Under `critterbox check`: the problems a scene's set-up noted and went on from (a
    /// spawn's bad field is left out), so one does not hide the rest of the scene.
    pub check_notes: RefCell<Option<Vec<ScriptError>>>,
}

/// Puts a host's previous target back when dropped, also when a script call unwinds.
struct Restore<'h> {
    target: &'h Cell<Target>,
    previous: Target,
}

impl Drop for Restore<'_> {
    fn drop(&mut self) {
        self.target.set(self.previous);
    }
}

impl Host {
    pub fn new(
        max_spawns_per_step: u64,
        extension: Option<Rc<dyn Extension>>,
        runtime: Weak<Runtime>,
    ) -> Self {
        Host {
            target: Cell::new(Target::Scene),
            scene: RefCell::new(None),
            extension,
            spawns: Cell::new(0),
            spawns_step: Cell::new(u64::MAX),
            max_spawns_per_step,
            runtime,
            kind_decl: RefCell::new(None),
            stop: RefCell::new(None),
            scene_steps: Cell::new(None),
            seed_override: Cell::new(None),
            stashed: RefCell::new(None),
            frames: RefCell::new(Vec::new()),
            check_notes: RefCell::new(None),
        }
    }

    /// The runtime this host belongs to.
    pub fn runtime(&self) -> Res<Rc<Runtime>> {
        self.runtime
            .upgrade()
            .ok_or_else(|| error("the script runtime is gone"))
    }

    /// Points scripts at `target` until the guard drops.
    fn aim(&self, target: Target) -> Restore<'_> {
        Restore {
            target: &self.target,
            previous: self.target.replace(target),
        }
    }

    /// Runs `f` with no world reachable from scripts (kind files' top level).
    pub fn without_env<R>(&self, f: impl FnOnce() -> R) -> R {
        let _restore = self.aim(Target::Nothing);
        f()
    }

    /// Runs `f` with scripts acting on `env`; the previous target is restored afterwards, also
    /// when `f` unwinds.
    pub fn enter<V: Dim, R>(&self, env: &mut Env<'_, V>, f: impl FnOnce() -> R) -> R {
        // The pointer lives in the target only while `f` runs: `_restore` removes it before
        // `env`'s borrow ends, and nothing else uses `env` meanwhile (it is lent to this call).
        let _restore = self.aim(Target::Entered(erase(env)));
        f()
    }

    /// Runs `f` with scripts acting through a hook's `access` (inside a step).
    pub fn enter_hook<V: Dim, R>(&self, access: &mut Access<'_, V>, f: impl FnOnce() -> R) -> R {
        self.enter(&mut Env::Hook(access.reborrow()), f)
    }

    /// True when the host holds a scene (lent out or not).
    pub fn has_scene(&self) -> bool {
        self.scene.try_borrow().map_or(true, |s| s.is_some())
    }

    /// Stores `scene` as the one scripts act on, and tells the extension, if any.
    pub fn put_scene(&self, scene: Scene) -> Res<()> {
        *self.scene.try_borrow_mut().map_err(|_| busy())? = Some(scene);
        match &self.extension {
            Some(extension) => extension.scene_made(self),
            None => Ok(()),
        }
    }

    /// Takes back the scene a script made or loaded.
    pub fn take_scene(&self) -> Option<Scene> {
        // Called once the scripts are done, so nothing holds the scene.
        self.scene.try_borrow_mut().ok().and_then(|mut s| s.take())
    }

    /// Runs `f` on the host's scene (a test stepping its world).
    pub fn with_scene<R>(&self, f: impl FnOnce(&mut Scene) -> R) -> Result<R, NoScene> {
        let mut slot = self.scene.try_borrow_mut().map_err(|_| NoScene::Busy)?;
        let scene = slot.as_mut().ok_or(NoScene::Missing)?;
        Ok(f(scene))
    }

    /// What one script function acts on, until the returned access drops; meanwhile the target
    /// is busy. Used through [`with_env!`].
    ///
    /// # Safety
    /// The access must be dropped before the script function that asked for it returns: a
    /// target lent by [`Host::enter`] is valid only until `enter` returns.
    #[inline]
    pub unsafe fn access(&self) -> Res<EnvAccess<'_>> {
        let (ptr, scene) = match self.target.get() {
            Target::Entered(ptr) => (ptr, None),
            Target::Scene => {
                let mut slot = self.scene.try_borrow_mut().map_err(|_| busy())?;
                let Some(scene) = slot.as_mut() else {
                    return Err(no_world());
                };
                let ptr = match &mut scene.world {
                    AnyWorld::D2(w) => EnvPtr::World2(w),
                    AnyWorld::D3(w) => EnvPtr::World3(w),
                };
                (ptr, Some(slot))
            }
            Target::Nothing => return Err(no_world()),
            Target::Busy => return Err(busy()),
        };
        Ok(EnvAccess {
            ptr,
            _scene: scene,
            _restore: self.aim(Target::Busy),
        })
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
        error(text)
    }

    /// The kept error if `e` is the one it carried up, else `fallback()`.
    pub fn locate(
        &self,
        e: &rhai::EvalAltResult,
        fallback: impl FnOnce() -> ScriptError,
    ) -> ScriptError {
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
}

/// The error of a script function that reaches for the world while another holds it.
fn busy() -> Box<rhai::EvalAltResult> {
    error("the world is busy: a script reached for it from inside a call that is using it")
}

/// One script function's hold on its target, from [`Host::access`].
pub(crate) struct EnvAccess<'h> {
    ptr: EnvPtr,
    /// The host's scene, held while `ptr` points into it.
    _scene: Option<RefMut<'h, Option<Scene>>>,
    /// Marks the target busy until this access drops.
    _restore: Restore<'h>,
}

/// The environment of one script function, in the running world's dimension.
pub(crate) enum EnvRef<'a> {
    D2(Env<'a, DVec2>),
    D3(Env<'a, DVec3>),
}

impl EnvAccess<'_> {
    #[inline]
    pub fn env(&mut self) -> EnvRef<'_> {
        // SAFETY: `ptr` is valid and not otherwise used while this access lives. Either it was
        // derived in `Host::access` from the scene held in `_scene`, or it was lent by
        // `Host::enter`, whose caller does not touch the pointee until `enter` returns, and this
        // access lives inside one script function, inside that call (`Host::access`'s contract).
        // The target is busy meanwhile, so no second reference is derived from `ptr`; a script
        // run from here (a spawn's `init`) is lent a pointer derived from the reference returned
        // here, through its own `enter`, so the two nest as reborrows do.
        match self.ptr {
            EnvPtr::D2(p) => EnvRef::D2(unsafe { (*p).reborrow() }),
            EnvPtr::D3(p) => EnvRef::D3(unsafe { (*p).reborrow() }),
            EnvPtr::World2(p) => EnvRef::D2(Env::World(unsafe { &mut *p })),
            EnvPtr::World3(p) => EnvRef::D3(Env::World(unsafe { &mut *p })),
        }
    }
}

/// Runs `$body` with `$env` bound to the running script's environment as `&mut Env<'_, V>`,
/// for whichever dimension the world has (the body is compiled once for each). Evaluates to an
/// error when no world is reachable.
macro_rules! with_env {
    ($host:expr, $env:ident => $body:expr) => {{
        let host: &$crate::script::host::Host = &$host;
        // SAFETY: the access is dropped at the end of this match, inside the script function.
        match unsafe { host.access() } {
            Err(e) => Err(e),
            Ok(mut access) => match access.env() {
                $crate::script::host::EnvRef::D2(mut env) => {
                    let $env = &mut env;
                    $body
                }
                $crate::script::host::EnvRef::D3(mut env) => {
                    let $env = &mut env;
                    $body
                }
            },
        }
    }};
}
pub(crate) use with_env;

#[cfg(test)]
mod tests;
