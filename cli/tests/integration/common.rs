//! What the CLI's test files share: running the binary and a fresh folder per test.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository, where the scripts and recordings are.
pub const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// A fresh folder for test `name` of the group `group`.
pub fn tmp_in(group: &str, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(group)
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Runs the binary in `dir`, its default recordings going under `dir/recordings`.
pub fn critterbox_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_critterbox"))
        .args(args)
        .current_dir(dir)
        .env("CRITTERBOX_RECORDINGS", dir.join("recordings"))
        .output()
        .expect("the critterbox binary runs")
}

/// Runs the binary in the repository.
pub fn critterbox(args: &[&str]) -> Output {
    critterbox_in(Path::new(ROOT), args)
}

/// What a run printed, stdout then stderr.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Waits (up to a minute) until a run started in the background has written to its recording
/// `file`, then a little longer, so that it is stepping.
pub fn wait_until_stepping(file: &Path) {
    let start = std::time::Instant::now();
    while std::fs::metadata(file).map_or(0, |m| m.len()) == 0 {
        assert!(
            start.elapsed() < std::time::Duration::from_secs(60),
            "the run never wrote"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
}
