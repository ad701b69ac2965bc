//! Helpers for the script tests: scratch folders for inline scripts, loading and stepping scenes,
//! finding critters by a `tag` property, reading properties, and the laws the checks compare
//! against (Pop's 1-D elastic formula and `assert_close`, shared with the engine's tests in
//! `common`; a 2D `assert_close_vec`).

use critterbox::glam::DVec2;
use critterbox::scenes::{AnyWorld, Scene};
use critterbox::script::{load_scene, ScriptOptions};
use critterbox::{CritterId, Error, PropValue, ScriptError, World};
use std::path::{Path, PathBuf};

pub use crate::common::{assert_close, pop_elastic};

/// The crate root (tests also run with it as the working directory).
pub fn crate_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A shipped scene, by name (`scripts/scenes/NAME.rhai`).
pub fn shipped_scene(name: &str) -> PathBuf {
    crate_root()
        .join("scripts/scenes")
        .join(format!("{name}.rhai"))
}

/// Every `.rhai` file in `scripts/<sub>/`, sorted.
pub fn shipped(sub: &str) -> Vec<PathBuf> {
    let dir = crate_root().join("scripts").join(sub);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|entry| entry.expect("a directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "rhai"))
        .collect();
    files.sort();
    files
}

/// A fresh scratch folder laid out as `DIR/scenes/` and `DIR/kinds/`, removed when dropped.
pub struct Sandbox {
    pub dir: PathBuf,
}

impl Sandbox {
    /// An empty sandbox named for the test.
    pub fn new(name: &str) -> Self {
        let dir =
            std::env::temp_dir().join(format!("critterbox-test-{}-{}", std::process::id(), name));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("scenes")).expect("create the scenes folder");
        std::fs::create_dir_all(dir.join("kinds")).expect("create the kinds folder");
        Sandbox { dir }
    }

    /// A sandbox whose `kinds/` holds copies of the shipped kinds.
    pub fn with_shipped_kinds(name: &str) -> Self {
        let sandbox = Sandbox::new(name);
        for kind in shipped("kinds") {
            let to = sandbox.dir.join("kinds").join(kind.file_name().unwrap());
            std::fs::copy(&kind, &to).expect("copy a shipped kind");
        }
        sandbox
    }

    /// Writes `kinds/NAME.rhai`.
    pub fn kind(&self, name: &str, text: &str) -> PathBuf {
        let path = self.dir.join("kinds").join(format!("{name}.rhai"));
        std::fs::write(&path, text).expect("write a kind file");
        path
    }

    /// Writes `scenes/NAME.rhai`.
    pub fn scene(&self, name: &str, text: &str) -> PathBuf {
        let path = self.dir.join("scenes").join(format!("{name}.rhai"));
        std::fs::write(&path, text).expect("write a scene file");
        path
    }

    /// Writes `scenes/x.rhai` and loads it with the default options.
    pub fn try_load(&self, scene_text: &str) -> Result<Scene, Error> {
        let path = self.scene("x", scene_text);
        load_scene(&path, &[], &ScriptOptions::default())
    }

    /// As [`Sandbox::try_load`], failing the test on an error (shown in full).
    pub fn load(&self, scene_text: &str) -> Scene {
        self.try_load(scene_text)
            .unwrap_or_else(|e| panic!("the scene should load:\n{e}"))
    }
}

impl Drop for Sandbox {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Loads the scene at `path` with `sets`, failing the test on an error.
pub fn load(path: &Path, sets: &[(&str, &str)]) -> Scene {
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    load_scene(path, &sets, &ScriptOptions::default())
        .unwrap_or_else(|e| panic!("{} should load:\n{e}", path.display()))
}

/// One step of a scene (world and `on_step`), failing the test on an error.
#[track_caller]
pub fn step(scene: &mut Scene) -> Option<String> {
    let n = scene.world.step_count();
    scene
        .step()
        .unwrap_or_else(|e| panic!("step {n} of '{}' failed:\n{e}", scene.name))
}

/// The 2D world of a scene.
#[track_caller]
pub fn w2(scene: &Scene) -> &World<DVec2> {
    match &scene.world {
        AnyWorld::D2(w) => w,
        AnyWorld::D3(_) => panic!("scene '{}' should be 2D", scene.name),
    }
}

/// The live critter whose `tag` property is `tag` (scenes in these tests tag what they check).
#[track_caller]
pub fn tagged(w: &World<DVec2>, tag: &str) -> CritterId {
    let found: Vec<CritterId> = w
        .critters()
        .iter()
        .filter(|c| c.props().get("tag") == Some(&PropValue::Text(tag.to_string())))
        .map(|c| c.id())
        .collect();
    assert_eq!(
        found.len(),
        1,
        "exactly one critter should be tagged '{tag}'"
    );
    found[0]
}

/// Live critters of kind `kind` (or kinds extending it).
pub fn of_kind(w: &World<DVec2>, kind: &str) -> Vec<CritterId> {
    w.critters_of(kind).unwrap_or_default()
}

/// A property of a live critter.
#[track_caller]
pub fn prop(w: &World<DVec2>, id: CritterId, name: &str) -> PropValue {
    let c = w
        .get(id)
        .unwrap_or_else(|| panic!("critter {id} should be alive"));
    c.props()
        .get(name)
        .cloned()
        .unwrap_or_else(|| panic!("critter {id} should have a property '{name}'"))
}

/// An integer property of a live critter.
#[track_caller]
pub fn prop_int(w: &World<DVec2>, id: CritterId, name: &str) -> i64 {
    match prop(w, id, name) {
        PropValue::Int(i) => i,
        other => panic!("property '{name}' of {id} should be an integer, is {other:?}"),
    }
}

/// A boolean property of a live critter.
#[track_caller]
pub fn prop_bool(w: &World<DVec2>, id: CritterId, name: &str) -> bool {
    match prop(w, id, name) {
        PropValue::Bool(b) => b,
        other => panic!("property '{name}' of {id} should be a bool, is {other:?}"),
    }
}

/// The script error inside `e`, failing the test if it is another kind of error.
#[track_caller]
pub fn script_error(e: Error) -> ScriptError {
    match e {
        Error::Script(s) => *s,
        other => panic!("expected a script error, got: {other} ({other:?})"),
    }
}

/// Asserts two 2D vectors agree to `tol` (norm of the difference).
#[track_caller]
pub fn assert_close_vec(actual: DVec2, expected: DVec2, tol: f64, what: &str) {
    let diff = (actual - expected).length();
    assert!(
        diff <= tol,
        "{what}: got {actual:?}, want {expected:?} (difference {diff:e} > tolerance {tol:e})"
    );
}
