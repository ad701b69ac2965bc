//! Rebuilding a recorded run's scene from the recording alone: a built-in scene from its name
//! and parameters, a script scene from its attached scripts.
//!
//! Scripts are written into a fresh temporary folder in the layout the scene's kind search
//! expects (the scene at `scenes/NAME.rhai`, kinds at `kinds/KIND.rhai`, which the scene finds as
//! `../kinds/`), and that `kinds/` folder is also put first on the kind path, so no file outside
//! the recording is ever read. A kind a script loaded by path (`load_kind("dir/k.rhai")`) is
//! pointed at its attached copy.

use super::error::RecordingError;
use super::meta::SceneSource;
use super::reader::Recording;
use crate::scenes::{self, Scene, SceneParams};
use crate::script::{self, ScriptOptions};
use std::path::{Path, PathBuf};

/// A scene rebuilt from a recording, with the temporary folder its scripts live in (removed when
/// this is dropped).
pub struct Rebuilt {
    /// The scene, at step 0.
    pub scene: Scene,
    /// Each attached kind file's recorded path and where its copy is.
    kinds: Vec<(String, PathBuf)>,
    _dir: Option<TempDir>,
}

impl Rebuilt {
    /// Where the rebuilt scene loaded the recorded kind file `file` from.
    pub fn kind_path(&self, file: &str) -> Option<String> {
        let at = self.kinds.iter().find(|(name, _)| name == file)?;
        Some(at.1.display().to_string())
    }

    /// `text` with every recorded kind path in quotes pointed at its copy.
    pub fn repoint(&self, text: &str) -> String {
        repoint(&self.kinds, text)
    }
}

fn repoint(kinds: &[(String, PathBuf)], text: &str) -> String {
    let mut text = text.to_string();
    for (name, at) in kinds {
        let quoted = format!("\"{name}\"");
        if text.contains(&quoted) {
            text = text.replace(&quoted, &format!("{:?}", at.display().to_string()));
        }
    }
    text
}

/// A temporary folder, removed on drop.
pub struct TempDir(PathBuf);

impl TempDir {
    /// A new empty folder under the system's temporary folder.
    pub fn new(prefix: &str) -> std::io::Result<TempDir> {
        use std::sync::atomic::{AtomicU64, Ordering};
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let dir = std::env::temp_dir().join(format!(
            "{prefix}-{}-{}-{nanos}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir)?;
        Ok(TempDir(dir))
    }
    /// Its path.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn file_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.replace(['/', '\\'], "_"))
}

/// Rebuilds the recorded scene at step 0, with the recorded dt override applied.
pub fn rebuild(rec: &Recording) -> Result<Rebuilt, RecordingError> {
    let meta = rec.meta();
    let (mut scene, kinds, dir) = match &meta.source {
        SceneSource::Builtin => {
            let params = SceneParams {
                n: meta.n,
                seed: meta.seed_override.unwrap_or(meta.seed),
                dt: meta.dt_override,
            };
            let scene =
                scenes::builtin(&meta.scene, &params).map_err(|error| RecordingError::Builtin {
                    scene: meta.scene.clone(),
                    version: meta.version.clone(),
                    error: Box::new(error),
                })?;
            (scene, Vec::new(), None)
        }
        SceneSource::Test { case } => {
            return Err(RecordingError::BuiltByTest { case: case.clone() })
        }
        SceneSource::Script { file } => {
            let dir = TempDir::new("critterbox-replay").map_err(RecordingError::TempFolder)?;
            let (scene, kinds) = load_script_scene(rec, file, dir.path())?;
            (scene, kinds, Some(dir))
        }
    };
    let method = meta
        .method
        .parse::<crate::method::Method>()
        .map_err(|reason| RecordingError::Method {
            method: meta.method.clone(),
            reason,
        })?;
    scene.world.set_method(method)?;
    if let Some(dt) = meta.dt_override {
        scene.world.set_dt(dt)?;
    }
    Ok(Rebuilt {
        scene,
        kinds,
        _dir: dir,
    })
}

fn load_script_scene(
    rec: &Recording,
    scene_file: &str,
    dir: &Path,
) -> Result<(Scene, Vec<(String, PathBuf)>), RecordingError> {
    let meta = rec.meta();
    let scene_text = rec
        .scripts
        .iter()
        .find(|(name, _)| name == scene_file)
        .map(|(_, text)| text.clone())
        .ok_or_else(|| RecordingError::NoSceneScript {
            file: scene_file.to_string(),
        })?;
    let kinds_dir = dir.join("kinds");
    let scenes_dir = dir.join("scenes");
    std::fs::create_dir_all(&kinds_dir)?;
    std::fs::create_dir_all(&scenes_dir)?;
    // Kinds: each at kinds/<file name>; a kind named by path in a script is pointed there.
    let kinds: Vec<(String, PathBuf)> = rec
        .scripts
        .iter()
        .filter(|(name, _)| name != scene_file)
        .map(|(name, _)| (name.clone(), kinds_dir.join(file_name(name))))
        .collect();
    let repoint = |text: &str| repoint(&kinds, text);
    for (name, text) in &rec.scripts {
        if name == scene_file {
            continue;
        }
        std::fs::write(kinds_dir.join(file_name(name)), repoint(text))?;
    }
    let scene_path = scenes_dir.join(file_name(scene_file));
    std::fs::write(&scene_path, repoint(&scene_text))?;
    let options = ScriptOptions {
        limits: meta.limits.clone(),
        kind_dirs: vec![kinds_dir],
        seed: meta.seed_override,
        ..ScriptOptions::default()
    };
    // The attached scene text already has the --set values in it.
    let scene = script::load_scene(&scene_path, &[], &options).map_err(|error| {
        RecordingError::ScriptScene {
            scene: meta.scene.clone(),
            error: Box::new(error),
        }
    })?;
    Ok((scene, kinds))
}
