//! What the fuzz suites share: their proptest configuration, the committed corpus, and a
//! per-case time limit. A case that runs past the limit is a hang: its input is written to a
//! file and the process aborts naming it. The limit only turns a hang into a failure report;
//! no result depends on how fast a case runs.

use proptest::test_runner::{Config, RngSeed};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::thread::ThreadId;
use std::time::{Duration, Instant};

/// Longer than any case takes on a slow, busy machine, far shorter than CI's patience.
const LIMIT: Duration = Duration::from_secs(60);

/// The seed of the CI run: the same inputs every run (`PROPTEST_RNG_SEED` picks others).
const CI_SEED: u64 = 42;

/// The configuration of a suite: `ci_cases` cases and a fixed seed, unless `PROPTEST_CASES` or
/// `PROPTEST_RNG_SEED` say otherwise (the long run by hand, `docs/testing.md`). Failures are
/// reported, not persisted: an input worth keeping goes into the corpus.
pub fn config(ci_cases: u32) -> Config {
    let mut c = Config::default();
    if std::env::var_os("PROPTEST_CASES").is_none() {
        c.cases = ci_cases;
    }
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        c.rng_seed = RngSeed::Fixed(CI_SEED);
    }
    c.failure_persistence = None;
    c
}

/// The files of the corpus folder `tests/fuzz/corpus/NAME`, in name order.
pub fn corpus(name: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz/corpus")
        .join(name);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

/// The cases running now, by thread: when each started, what it is, and its input.
type Running = Vec<(ThreadId, Instant, String, Vec<u8>)>;
static RUNNING: Mutex<Running> = Mutex::new(Vec::new());

fn running() -> std::sync::MutexGuard<'static, Running> {
    RUNNING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Clears the thread's case when it ends, panicking or not.
struct Done;

impl Drop for Done {
    fn drop(&mut self) {
        let me = std::thread::current().id();
        running().retain(|(thread, ..)| *thread != me);
    }
}

/// Runs `f` as the case `what` with `input`, aborting the process (after saving the input to
/// `fuzz-hang-input` in cargo's test temp folder) if it is still running after [`LIMIT`].
pub fn case<R>(what: &str, input: &[u8], f: impl FnOnce() -> R) -> R {
    static WATCH: std::sync::Once = std::sync::Once::new();
    WATCH.call_once(|| {
        std::thread::spawn(|| loop {
            std::thread::sleep(Duration::from_millis(250));
            let hung = running()
                .iter()
                .find(|(_, started, ..)| started.elapsed() > LIMIT)
                .map(|(_, _, what, input)| (what.clone(), input.clone()));
            if let Some((what, input)) = hung {
                let file = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz-hang-input");
                let _ = std::fs::write(&file, input);
                eprintln!(
                    "fuzz: the case '{what}' ran for over {LIMIT:?} (a hang); its input is in {}",
                    file.display()
                );
                std::process::abort();
            }
        });
    });
    running().push((
        std::thread::current().id(),
        Instant::now(),
        what.to_string(),
        input.to_vec(),
    ));
    let _done = Done;
    f()
}
