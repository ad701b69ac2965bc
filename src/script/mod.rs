//! rhai scripts: scenes (`scripts/scenes/*.rhai`) that set up a world, and kinds
//! (`scripts/kinds/*.rhai`) that give critters their own `collide`, `collides_with`, `update` and
//! `init`. The user's guide is `docs/scripting.md`.
//!
//! One `Runtime` per run holds the engine (built once by `api::build_engine`), each kind's
//! compiled AST and its bytecode, and the `Host` (`host.rs`) through which running scripts reach
//! the world. Each hook runs on a bytecode virtual machine kept per kind (`Vm::call_fn_kept`, a
//! patch of the vendored rhai), with the top level not re-run, no per-call scope allocation, and
//! the functions it calls resolved once per kind; a kind that hands closures to natives runs on
//! its AST (`call_fn_cached`). A kind's hooks run only for pairs that really touch, and only for
//! kinds that define them. A layer above (the script test runner, [`crate::testing`]) adds its
//! functions through an `Extension`; nothing here depends on it or on recordings.

pub(crate) mod api;
pub(crate) mod env;
pub(crate) mod errors;
pub(crate) mod host;
pub(crate) mod kind_calls;
pub(crate) mod kind_file;
pub(crate) mod kind_refs;
pub mod lint;
pub(crate) mod reload;

pub(crate) mod scene;

pub use lint::{check_file, check_files, FileCheck, Problem, Severity};

use crate::error::{Error, ScriptError};
use crate::scenes::{Scene, SourceFile};
use api::Res;
use host::Host;
use rhai::{Engine, AST};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Limits on what script calls may do: all are counts, never times, so a run stops at the same
/// place on every machine. The defaults are far above what real scripts need, and low enough
/// that a hostile script stops within a bounded amount of work (see "Sandbox and limits" in
/// `docs/scripting.md`).
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    /// Operations per hook call (an endless loop stops here).
    pub max_operations: u64,
    /// Operations of all script calls of one step together; 0 for no such budget.
    pub max_step_operations: u64,
    /// Depth of nested function calls.
    pub max_call_levels: usize,
    /// Longest string.
    pub max_string_size: usize,
    /// Longest array (items of nested arrays count too). rhai measures an array after each
    /// operation that may change it; that walk is charged as operations
    /// ([`DATA_WALK_ITEMS_PER_OP`]).
    pub max_array_size: usize,
    /// Largest map (entries of nested maps count too).
    pub max_map_size: usize,
    /// Spawns scripts may request in one step.
    pub max_spawns_per_step: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_operations: 1_000_000,
            max_step_operations: 10_000_000,
            max_call_levels: 64,
            max_string_size: 1 << 20,
            max_array_size: 10_000,
            max_map_size: 10_000,
            max_spawns_per_step: 100_000,
        }
    }
}

/// Items of arrays and maps rhai walks, when it measures them against `--max-array` and
/// `--max-map`, per operation charged toward `--max-ops` and `--max-step-ops`: about what one
/// cheap operation costs in time, so the operation limits bound a call's time even when every
/// operation measures a full array (`vendor/rhai/PATCH.md`).
pub const DATA_WALK_ITEMS_PER_OP: u64 = 32;

/// Where scripts live and how they are limited.
#[derive(Clone, Debug, Default)]
pub struct ScriptOptions {
    /// Limits per call and per step.
    pub limits: Limits,
    /// Extra folders to look for kinds in (before the defaults).
    pub kind_dirs: Vec<PathBuf>,
    /// A seed that overrides the scene's own.
    pub seed: Option<u64>,
    /// Time every hook call per kind and hook from the start ([`crate::profile`]; `run --stats`).
    pub profile: bool,
}

/// The engine, the kinds loaded so far, and the bridge to the world.
pub(crate) struct Runtime {
    pub engine: Engine,
    pub host: Rc<Host>,
    /// Folders searched for `name.rhai` when a kind is asked for by name.
    pub kind_dirs: Vec<PathBuf>,
    /// The script functions whose string arguments name kinds (see [`api::Api::kind_func`]).
    pub(crate) kind_calls: Vec<&'static str>,
    /// Script kinds by name.
    pub kinds: RefCell<BTreeMap<String, Rc<kind_file::ScriptKindDef>>>,
    /// Every file loaded, in load order.
    pub sources: RefCell<Vec<SourceFile>>,
    /// The constants `--set KIND.NAME=VALUE` gives, by kind: applied to the kind's text each
    /// time it is built (loaded or reloaded), so its sources and recordings hold the values.
    pub kind_sets: RefCell<BTreeMap<String, Vec<(String, String)>>>,
    /// The limits the engine was built with.
    pub limits: Limits,
    /// Whether a kind name has a file on the kind search path, once asked (see
    /// [`Runtime::kind_exists`]).
    kind_files: RefCell<BTreeMap<String, bool>>,
    /// Names of no kind that a hook asked for, warned of once each.
    unknown_warned: RefCell<std::collections::BTreeSet<String>>,
    /// Calls and time per kind and hook, when turned on.
    pub profiler: Rc<crate::profile::Profiler>,
}

/// What a layer above scripts adds to a runtime (the script test runner's API): functions on
/// its engine, and a word each time a script puts a scene into the runtime's host.
pub(crate) trait Extension {
    /// Registers the functions (each reaches the world through the host [`api::Api`] hands it).
    fn register(self: Rc<Self>, api: &mut api::Api);
    /// A script has just made the host's scene (`world(#{ ... })`) or loaded one.
    fn scene_made(&self, host: &Host) -> Res<()>;
}

impl Runtime {
    /// A runtime for scripts in `scene_dir` (kinds are looked up beside it).
    pub fn new(options: &ScriptOptions, scene_dir: Option<&Path>) -> Rc<Runtime> {
        Runtime::extended(options, scene_dir, None)
    }

    /// A runtime whose engine also has `extension`'s functions.
    pub fn extended(
        options: &ScriptOptions,
        scene_dir: Option<&Path>,
        extension: Option<Rc<dyn Extension>>,
    ) -> Rc<Runtime> {
        let mut kind_dirs = options.kind_dirs.clone();
        if let Some(dir) = scene_dir {
            kind_dirs.push(dir.join("../kinds"));
            kind_dirs.push(dir.join("kinds"));
            kind_dirs.push(dir.to_path_buf());
        }
        kind_dirs.push(PathBuf::from("scripts/kinds"));
        Rc::new_cyclic(|runtime| {
            let host = Rc::new(Host::new(
                options.limits.max_spawns_per_step,
                extension,
                runtime.clone(),
            ));
            host.seed_override.set(options.seed);
            let profiler = Rc::new(crate::profile::Profiler::default());
            profiler.set_on(options.profile);
            let (engine, kind_calls) = api::build_engine(&host, &options.limits);
            Runtime {
                engine,
                kind_calls,
                host,
                kind_dirs,
                kinds: RefCell::new(BTreeMap::new()),
                sources: RefCell::new(Vec::new()),
                kind_sets: RefCell::new(BTreeMap::new()),
                limits: options.limits.clone(),
                kind_files: RefCell::new(BTreeMap::new()),
                unknown_warned: RefCell::new(Default::default()),
                profiler,
            }
        })
    }

    /// The file of the kind `name` on the kind search path, if there is one.
    pub fn resolve_kind(&self, name: &str) -> Option<PathBuf> {
        self.kind_dirs
            .iter()
            .map(|dir| dir.join(format!("{name}.rhai")))
            .find(|p| p.is_file())
    }

    /// True when `name` is a kind: native, loaded, or a file on the kind search path (looked
    /// up once per name, as hooks may ask every step).
    pub fn kind_exists(&self, name: &str) -> bool {
        if kind_refs::NATIVE_KINDS.contains(&name) || self.kinds.borrow().contains_key(name) {
            return true;
        }
        if let Some(&known) = self.kind_files.borrow().get(name) {
            return known;
        }
        let found = self.resolve_kind(name).is_some();
        self.kind_files.borrow_mut().insert(name.to_string(), found);
        found
    }

    /// True the first time `name` is passed: a hook asked for a kind that does not exist.
    pub fn warn_unknown_kind(&self, name: &str) -> bool {
        self.unknown_warned.borrow_mut().insert(name.to_string())
    }

    /// The names of every kind on the kind search path (its files that are neither scenes nor
    /// test files), and the native ones.
    pub fn known_kind_names(&self) -> Vec<String> {
        let mut names: Vec<String> = kind_refs::NATIVE_KINDS
            .iter()
            .map(|s| s.to_string())
            .collect();
        for dir in &self.kind_dirs {
            let Ok(entries) = std::fs::read_dir(dir) else {
                continue;
            };
            for entry in entries.flatten() {
                let path = entry.path();
                // A scene's own folder is on the path, and scenes and tests are no kinds.
                let is_kind =
                    || std::fs::read_to_string(&path).is_ok_and(|t| lint::is_kind_text(&t));
                if path.extension().is_some_and(|e| e == "rhai") && is_kind() {
                    if let Some(stem) = path.file_stem() {
                        names.push(stem.to_string_lossy().into_owned());
                    }
                }
            }
        }
        names.extend(self.kinds.borrow().keys().cloned());
        names.sort();
        names.dedup();
        names
    }

    /// Compiles `text` as `path`; errors carry file, line and column.
    pub fn compile(&self, path: &str, text: &str) -> Result<AST, Error> {
        let mut ast = self
            .engine
            .compile(text)
            .map_err(|e| Error::from(errors::parse_error(path, text, &e)))?;
        ast.set_source(path);
        Ok(ast)
    }
}

/// Reads a script file; a missing or unreadable file is a clear error.
pub(crate) fn read_script(path: &Path) -> Result<String, Error> {
    std::fs::read_to_string(path).map_err(|e| {
        let mut err = ScriptError::new(
            path.display().to_string(),
            format!("cannot read the script: {e}"),
        );
        err.hint = Some(
            "check the path; scene scripts live in scripts/scenes/, kinds in scripts/kinds/".into(),
        );
        Error::from(err)
    })
}

/// Loads a scene script, applying `--set NAME=VALUE` overrides to its top-level constants.
pub fn load_scene(
    path: &Path,
    sets: &[(String, String)],
    options: &ScriptOptions,
) -> Result<Scene, Error> {
    scene::load(path, sets, options)
}

/// As [`load_scene`], but a failure also gives the script files read up to it (the scene first,
/// then its kinds, the failing one included), so `critterbox run` can record a failed set-up.
pub fn load_scene_keeping_sources(
    path: &Path,
    sets: &[(String, String)],
    options: &ScriptOptions,
) -> Result<Scene, (Error, Vec<SourceFile>)> {
    scene::load_keeping_sources(path, sets, options)
}

/// The text of kind `kind` (file `file`) as a run given `sets` builds it: with the constants
/// its `KIND.NAME=VALUE` sets name replaced, as they are when it is loaded or reloaded. A
/// recording of a reload keeps this text, so that the replay makes the same kind.
pub fn kind_text_with_sets(
    file: &str,
    kind: &str,
    text: &str,
    sets: &[(String, String)],
) -> Result<String, Error> {
    let prefix = format!("{kind}.");
    let own: Vec<(String, String)> = sets
        .iter()
        .filter_map(|(k, v)| Some((k.strip_prefix(&prefix)?.to_string(), v.clone())))
        .collect();
    if own.is_empty() {
        return Ok(text.to_string());
    }
    scene::kind_constant_set(file, kind, text, &own)
}

/// A world that script kinds can be loaded into: `World<DVec2>` and `World<DVec3>`.
pub trait ScriptWorld {
    /// Loads the kind file at `path` (and the kinds it extends, from the same folder) into the
    /// world, for a Rust program that builds its own world.
    fn load_kind(
        &mut self,
        path: &Path,
        options: &ScriptOptions,
    ) -> Result<crate::kind::KindId, Error>;
}

impl<V: host::Dim> ScriptWorld for crate::world::World<V> {
    fn load_kind(
        &mut self,
        path: &Path,
        options: &ScriptOptions,
    ) -> Result<crate::kind::KindId, Error> {
        let rt = Runtime::new(options, path.parent());
        kind_file::load_into(&rt, self, &path.display().to_string())
    }
}

/// Compiles and checks script files without running a world: scenes are set up (not stepped),
/// kinds are loaded and their hooks checked. Returns one line per file checked.
pub fn check(paths: &[PathBuf], options: &ScriptOptions) -> Result<Vec<String>, Error> {
    let mut report = Vec::new();
    for path in paths {
        let text = read_script(path)?;
        if scene::looks_like_scene(&text) {
            let scene = load_scene(path, &[], options)?;
            report.push(scene_ok(&path.display().to_string(), &scene));
        } else {
            let dir = path.parent().map(Path::to_path_buf);
            let rt = Runtime::new(options, dir.as_deref());
            let def = kind_file::load_def(&rt, &path.display().to_string())?;
            let hooks: Vec<&str> = def.hook_names().collect();
            report.push(format!(
                "{}: kind '{}' ok (hooks: {})",
                path.display(),
                def.name,
                if hooks.is_empty() {
                    "none".to_string()
                } else {
                    hooks.join(", ")
                }
            ));
        }
    }
    Ok(report)
}

/// `check`'s line for a scene that loads: its file, dimension, critters and kinds.
pub(crate) fn scene_ok(file: &str, scene: &Scene) -> String {
    let kinds: Vec<String> = scene.world.count_by_kind().keys().cloned().collect();
    format!(
        "{file}: scene ok ({}D, {} critters, kinds: {})",
        scene.world.dim(),
        scene.world.len(),
        kinds.join(", ")
    )
}
