//! `run --watch`: the script files a run loaded, watched for edits. A kind file's new text
//! replaces its kind at the next step boundary (hot reload, recorded); the scene file's runs the
//! scene again from step 0; a file that does not compile leaves the old version running. A
//! reloaded kind that fails while running stops the run, as any failing step does: the step
//! cannot be taken back, so there is no old version to go on with. The error names the reload
//! (`run::run_once`), and the next edit runs the scene again.
//!
//! The folders of the files are watched (inotify, through `notify`), not the files, so an
//! editor that saves by writing a new file and renaming it over the old one is seen too. Events
//! are let settle for [`SETTLE`] and a file counts as changed only when its text did.

use super::record;
use super::run::{self, Ended, RunArgs};
use critterbox::scenes::SourceFile;
use notify::{RecursiveMode, Watcher};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::Duration;

/// How long events must stop before the files are read (an editor's save is several events).
const SETTLE: Duration = Duration::from_millis(100);

/// How often a wait for an edit looks for a signal.
const SIGNAL_POLL: Duration = Duration::from_millis(200);

/// The watched script files of a run.
pub struct Watch {
    watcher: notify::RecommendedWatcher,
    events: Receiver<notify::Result<notify::Event>>,
    /// By its path on disk (canonical), each file's path as the run loaded it.
    files: BTreeMap<PathBuf, String>,
    /// The folders watched.
    dirs: BTreeSet<PathBuf>,
    /// Each file's text as last seen, by its path as loaded.
    texts: BTreeMap<String, String>,
    /// How many of the run's sources have been added.
    added: usize,
}

impl Watch {
    /// Watches nothing yet.
    pub fn new() -> anyhow::Result<Watch> {
        let (tx, events) = mpsc::channel();
        let watcher = notify::recommended_watcher(tx)
            .map_err(|e| anyhow::anyhow!("--watch: cannot watch files here: {e}"))?;
        Ok(Watch {
            watcher,
            events,
            files: BTreeMap::new(),
            dirs: BTreeSet::new(),
            texts: BTreeMap::new(),
            added: 0,
        })
    }

    /// How many of the run's script files (in load order) are watched so far.
    pub fn added(&self) -> usize {
        self.added
    }

    /// Also watches `sources` (the run's script files from number [`Watch::added`] on).
    pub fn add(&mut self, sources: &[SourceFile]) -> anyhow::Result<()> {
        for s in sources {
            self.added += 1;
            let Ok(real) = std::fs::canonicalize(&s.path) else {
                continue; // not a file on disk (nothing to watch)
            };
            if let Some(dir) = real.parent().filter(|d| !self.dirs.contains(*d)) {
                self.watcher
                    .watch(dir, RecursiveMode::NonRecursive)
                    .map_err(|e| anyhow::anyhow!("--watch: cannot watch {}: {e}", dir.display()))?;
                self.dirs.insert(dir.to_path_buf());
            }
            // The text on disk, which for a scene is before `--set`: edits are compared to it.
            let text = std::fs::read_to_string(&real).unwrap_or_default();
            self.texts.insert(s.path.clone(), text);
            self.files.insert(real, s.path.clone());
        }
        Ok(())
    }

    /// Files watched.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// The files whose text changed since they were last seen, as (path as loaded, new text);
    /// empty when no event came. Does not wait unless an event came, then only until events
    /// settle.
    pub fn changed(&mut self) -> Vec<(String, String)> {
        let mut touched = BTreeSet::new();
        let mut got = false;
        while let Ok(event) = self.events.try_recv() {
            got = true;
            self.note(event, &mut touched);
        }
        if !got {
            return Vec::new();
        }
        self.settle(&mut touched);
        self.read(touched)
    }

    /// Waits until some watched file's text changes, or a stop signal comes (`None`).
    pub fn wait(&mut self) -> Option<Vec<(String, String)>> {
        loop {
            if record::interrupted().is_some() {
                return None;
            }
            let mut touched = BTreeSet::new();
            match self.events.recv_timeout(SIGNAL_POLL) {
                Ok(event) => self.note(event, &mut touched),
                Err(RecvTimeoutError::Timeout) => continue,
                Err(RecvTimeoutError::Disconnected) => return None,
            }
            self.settle(&mut touched);
            let changed = self.read(touched);
            if !changed.is_empty() {
                return Some(changed);
            }
        }
    }

    /// Takes events until none comes for [`SETTLE`].
    fn settle(&mut self, touched: &mut BTreeSet<String>) {
        while let Ok(event) = self.events.recv_timeout(SETTLE) {
            self.note(event, touched);
        }
    }

    fn note(&self, event: notify::Result<notify::Event>, touched: &mut BTreeSet<String>) {
        // Opening and reading a file (as this watch does) is not an edit.
        let Ok(event) = event.map_err(drop).and_then(|e| match e.kind {
            notify::EventKind::Access(_) => Err(()),
            _ => Ok(e),
        }) else {
            return;
        };
        for path in &event.paths {
            if let Some(loaded) = self.loaded_as(path) {
                touched.insert(loaded.to_string());
            }
        }
    }

    /// The watched file at `path`, as the run loaded it.
    fn loaded_as(&self, path: &Path) -> Option<&str> {
        if let Some(l) = self.files.get(path) {
            return Some(l);
        }
        // A path under a folder given another way (a symbolic link): by folder and name.
        let real = std::fs::canonicalize(path).ok()?;
        self.files.get(&real).map(String::as_str)
    }

    /// The touched files whose text is not the one last seen, with their new text.
    fn read(&mut self, touched: BTreeSet<String>) -> Vec<(String, String)> {
        let mut changed = Vec::new();
        for file in touched {
            // A file being replaced may be missing for a moment: then it is read next time.
            let Ok(text) = std::fs::read_to_string(&file) else {
                continue;
            };
            if self.texts.get(&file) != Some(&text) {
                self.texts.insert(file.clone(), text.clone());
                changed.push((file, text));
            }
        }
        changed
    }
}

/// `critterbox run --watch`: runs the scene, and again from step 0 whenever its scene file
/// changes, or any script file once the run has ended; kind files edited during a run are
/// reloaded into it. Ends at Ctrl-C (or SIGTERM, SIGHUP).
pub fn run_watching(args: &RunArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    for n in 1.. {
        let mut watch = Watch::new()?;
        // Each run its own file: `--record run.mcap` gives run.mcap, run-2.mcap, ...
        let mut this = args.clone();
        if let (Some(path), true) = (&args.recording.record, n > 1) {
            this.recording.record = Some(numbered(path, n));
        }
        let ended = run::run_once(&this, out, Some(&mut watch));
        out.flush()?;
        match ended {
            Ok(Ended::SceneChanged) => {
                eprintln!("watch: the scene file changed; running it again from step 0");
                continue;
            }
            Ok(Ended::Finished) => {}
            Err(e) if e.downcast_ref::<record::Interrupted>().is_some() => return Err(e),
            Err(e) if watch.len() == 0 => return Err(e),
            Err(e) => eprintln!("error: {e:#}"),
        }
        if watch.len() == 0 {
            eprintln!("watch: this scene loads no script files, so there is nothing to watch");
            return Ok(());
        }
        eprintln!(
            "watch: watching {} script file{} for edits; an edit runs the scene again (Ctrl-C to stop)",
            watch.len(),
            if watch.len() == 1 { "" } else { "s" }
        );
        match watch.wait() {
            Some(changed) => {
                let names: Vec<&str> = changed.iter().map(|(f, _)| f.as_str()).collect();
                eprintln!(
                    "watch: {} changed; running the scene again",
                    names.join(", ")
                );
            }
            None => {
                eprintln!("watch: stopped");
                return Ok(());
            }
        }
    }
    Ok(())
}

/// `path` with `-n` before its extension: `run.mcap` -> `run-2.mcap`.
fn numbered(path: &Path, n: u64) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let name = match path.extension() {
        Some(ext) => format!("{stem}-{n}.{}", ext.to_string_lossy()),
        None => format!("{stem}-{n}"),
    };
    path.with_file_name(name)
}
