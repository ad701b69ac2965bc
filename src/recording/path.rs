//! Where recordings go by default: `recordings/<scene>-<YYYYMMDD-HHMMSS>.mcap` under the current
//! folder, or under `$CRITTERBOX_RECORDINGS` when that is set.

use std::path::{Path, PathBuf};

/// The environment variable that moves the default recordings folder.
pub const DIR_VARIABLE: &str = "CRITTERBOX_RECORDINGS";

/// The default recordings folder.
pub fn default_dir() -> PathBuf {
    std::env::var_os(DIR_VARIABLE)
        .filter(|v| !v.is_empty())
        .map_or_else(|| PathBuf::from("recordings"), PathBuf::from)
}

/// A new file name for a recording of `scene` in `dir`: the scene and the UTC time, with `-2`,
/// `-3`... if that name is taken.
pub fn new_path(dir: &Path, scene: &str) -> PathBuf {
    let (stamp, _) = super::meta::utc_now();
    let safe: String = scene
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let mut path = dir.join(format!("{safe}-{stamp}.mcap"));
    let mut k = 2;
    while path.exists() {
        path = dir.join(format!("{safe}-{stamp}-{k}.mcap"));
        k += 1;
    }
    path
}
