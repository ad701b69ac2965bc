//! Scenes: a world ready to run and what a scene adds around it ([`Scene`], [`AnyWorld`]), the
//! built-in scenes (`critterbox run NAME`, and the standard gas the benchmarks measure), and,
//! for the tests and `critterbox stability`/`chart`, the stress scenes (`stress`), the mixed
//! scenes (`mixed`), the readings of where `solve:n` fails (`solve_limits`) and the chart's
//! sweeps (`chart`). Each scene is written once.

mod builtin;
#[doc(hidden)]
pub mod chart;
#[doc(hidden)]
pub mod mixed;
#[doc(hidden)]
pub mod solve_limits;
#[doc(hidden)]
pub mod stress;

pub use builtin::{
    build, builtin, find, gas, gas_with, GasParams, SceneInfo, SceneParams, DEFAULT_SCENE, SCENES,
};

use crate::border::Border;
use crate::error::Error;
use crate::vector::Vector;
use crate::world::{StepStats, World};
use glam::{DVec2, DVec3};
use std::collections::BTreeMap;

/// A world of either dimension, for code that runs any scene.
pub enum AnyWorld {
    /// A 2D world.
    D2(World<DVec2>),
    /// A 3D world.
    D3(World<DVec3>),
}

macro_rules! both {
    ($self:expr, $w:ident => $body:expr) => {
        match $self {
            AnyWorld::D2($w) => $body,
            AnyWorld::D3($w) => $body,
        }
    };
}

impl AnyWorld {
    /// 2 or 3.
    pub fn dim(&self) -> usize {
        match self {
            AnyWorld::D2(_) => 2,
            AnyWorld::D3(_) => 3,
        }
    }
    /// One step.
    pub fn step(&mut self) -> Result<(), Error> {
        both!(self, w => w.step())
    }
    /// Steps taken.
    pub fn step_count(&self) -> u64 {
        both!(self, w => w.step_count())
    }

    /// The seed of the world's random generator.
    pub fn seed(&self) -> u64 {
        both!(self, w => w.seed())
    }
    /// The collision method.
    pub fn method(&self) -> crate::method::Method {
        both!(self, w => w.method())
    }
    /// Changes the collision method.
    pub fn set_method(&mut self, m: crate::method::Method) -> Result<(), Error> {
        both!(self, w => w.set_method(m))
    }
    /// Sets when the critters are laid out in memory (see [`crate::world::Locality`]).
    pub fn set_locality(&mut self, locality: crate::world::Locality) {
        both!(self, w => w.set_locality(locality))
    }
    /// True while the critters are stored elsewhere than their ids' slots.
    pub fn is_laid_out(&self) -> bool {
        both!(self, w => w.critters().is_arranged())
    }
    /// What `auto` chose for the last step, and why.
    pub fn auto_choice(&self) -> Option<(crate::method::Method, crate::method::auto::Why)> {
        both!(self, w => w.auto_choice())
    }
    /// See [`crate::World::auto_islands`].
    pub fn auto_islands(&self) -> Option<crate::method::mixed::IslandSummary> {
        both!(self, w => w.auto_islands().cloned())
    }
    /// How many critters sleep (under `solve:n`, [`crate::method::sleep`]).
    pub fn sleepers(&self) -> usize {
        both!(self, w => w.sleepers())
    }
    /// True when critters may sleep under `solve:n`.
    pub fn sleep_allowed(&self) -> bool {
        both!(self, w => w.sleep_allowed())
    }
    /// Simulated time.
    pub fn time(&self) -> f64 {
        both!(self, w => w.time())
    }
    /// Time step.
    pub fn dt(&self) -> f64 {
        both!(self, w => w.dt())
    }
    /// Number of critters (walls included).
    pub fn len(&self) -> usize {
        both!(self, w => w.critters().len())
    }
    /// True when the world has no critters.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Kinetic energy of the free critters.
    pub fn kinetic_energy(&self) -> f64 {
        both!(self, w => w.kinetic_energy())
    }
    /// Momentum as `[x, y, z]` (z = 0 in 2D).
    pub fn momentum(&self) -> [f64; 3] {
        both!(self, w => w.momentum().to_array3())
    }
    /// Live critters by kind name.
    pub fn count_by_kind(&self) -> BTreeMap<String, usize> {
        both!(self, w => w.count_by_kind())
    }
    /// State hash (see [`World::state_hash`]).
    pub fn state_hash(&self) -> u64 {
        both!(self, w => w.state_hash())
    }
    /// Stats of the last step.
    pub fn stats(&self) -> &StepStats {
        both!(self, w => w.stats())
    }
    /// Stats summed over all steps.
    pub fn totals(&self) -> &StepStats {
        both!(self, w => w.totals())
    }
    /// The border rule.
    pub fn border(&self) -> Border {
        both!(self, w => w.topology().border)
    }
    /// How the engine's caches and layouts have behaved (see [`crate::World::diagnostics`]).
    pub fn diagnostics(&self) -> crate::world::Diagnostics<'_> {
        both!(self, w => w.diagnostics())
    }
    /// Changes the time step.
    pub fn set_dt(&mut self, dt: f64) -> Result<(), Error> {
        both!(self, w => w.set_dt(dt))
    }
    /// The scripts' shared state (`world().vars`).
    pub fn vars(&self) -> &crate::critter::Props {
        both!(self, w => w.vars())
    }
    /// Log lines of the last step.
    pub fn log(&self) -> &[String] {
        both!(self, w => &w.events().log)
    }
}

/// A script file that a run used, kept so a recording can hold everything needed to rerun it.
#[derive(Clone, Debug, PartialEq)]
pub struct SourceFile {
    /// The path it was loaded from.
    pub path: String,
    /// Its text as loaded (after `--set` overrides).
    pub text: String,
}

/// A scene's own step-by-step logic: runs after each step; `Some(reason)` asks the run to stop.
pub type OnStep = Box<dyn FnMut(&mut AnyWorld) -> Result<Option<String>, Error>>;

/// A world ready to run, with what the scene adds around it.
pub struct Scene {
    /// Name (a built-in scene's name, or a script's file stem).
    pub name: String,
    /// The world.
    pub world: AnyWorld,
    /// Steps to run when none are asked for.
    pub default_steps: u64,
    /// The scene's `on_step`, if it has one.
    pub on_step: Option<OnStep>,
    /// Script files used (empty for built-in scenes).
    pub sources: Vec<SourceFile>,
    /// Every script file loaded so far from the `n`-th on, kinds loaded during the run included
    /// (set for script scenes).
    pub(crate) loaded_since: Option<Box<dyn Fn(usize) -> Vec<SourceFile>>>,
    /// The script profiler of a script scene's hooks (`run --stats`), off until turned on.
    pub profiler: Option<std::rc::Rc<crate::profile::Profiler>>,
    /// Replaces a kind from a new text of its file (set for script scenes; see
    /// [`Scene::reload_kind`]).
    pub(crate) reloader: Option<Reloader>,
}

/// How a script scene replaces a kind: the world, the kind's file as loaded, its new text.
pub(crate) type Reloader = Box<dyn Fn(&mut AnyWorld, &str, &str) -> Result<Vec<String>, Error>>;

impl Scene {
    /// A scene of `world` with no script around it.
    pub fn new(name: impl Into<String>, world: AnyWorld, default_steps: u64) -> Self {
        Scene {
            name: name.into(),
            world,
            default_steps,
            on_step: None,
            sources: Vec::new(),
            loaded_since: None,
            profiler: None,
            reloader: None,
        }
    }

    /// Replaces the kind that the script file `file` (its path as loaded, as in
    /// [`Scene::sources`]) defines with the one `text` defines, between two steps: hot reload.
    /// Kinds that extend it are rebuilt on it. Critters keep their state; critters spawned
    /// from now on get the new defaults. Returns the names of the kinds replaced. A text that
    /// does not compile, or a file of no loaded kind, is an error and changes nothing.
    pub fn reload_kind(&mut self, file: &str, text: &str) -> Result<Vec<String>, Error> {
        match &self.reloader {
            Some(reload) => reload(&mut self.world, file, text),
            None => Err(Error::from(crate::error::ScriptError::new(
                file,
                "this scene loads no kind files: only a script scene's kinds can be reloaded",
            ))),
        }
    }

    /// The script files loaded so far, from the `n`-th on: `sources` and then any kind the
    /// scene loaded while running (from `on_step`). Empty for built-in scenes.
    pub fn sources_since(&self, n: usize) -> Vec<SourceFile> {
        match &self.loaded_since {
            Some(f) => f(n),
            None => self.sources.get(n..).map(<[_]>::to_vec).unwrap_or_default(),
        }
    }

    /// The script profile so far: calls and time per kind and hook (empty unless
    /// `profiler` was turned on).
    pub fn profile(&self) -> Vec<crate::profile::ProfileRow> {
        self.profiler.as_ref().map(|p| p.rows()).unwrap_or_default()
    }

    /// One step of the world, then the scene's `on_step`. Returns the reason when the scene asks
    /// to stop.
    pub fn step(&mut self) -> Result<Option<String>, Error> {
        self.world.step()?;
        match &mut self.on_step {
            Some(f) => f(&mut self.world),
            None => Ok(None),
        }
    }
}

impl From<World<DVec2>> for AnyWorld {
    fn from(w: World<DVec2>) -> Self {
        AnyWorld::D2(w)
    }
}

impl From<World<DVec3>> for AnyWorld {
    fn from(w: World<DVec3>) -> Self {
        AnyWorld::D3(w)
    }
}
