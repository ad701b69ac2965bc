//! What `critterbox run` adds for recording: the `--record` flags, the run's metadata, the
//! recorder's start and end, the file of a run whose scene could not be built, and the signals
//! (SIGINT, SIGTERM, SIGHUP) that end a run early with the file finished.

use super::run::RunArgs;
use clap::Args;
use critterbox::recording::{
    path, write_failed_setup, EndMeta, Recorder, RunMeta, RunOverrides, Written,
};
use critterbox::scenes::{Scene, SourceFile};
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicI32, Ordering};

/// Recording options of `critterbox run`.
#[derive(Args, Debug, Default, Clone)]
pub struct RecordArgs {
    /// Write the recording to PATH (default: recordings/<scene>-<YYYYMMDD-HHMMSS>.mcap, or under
    /// $CRITTERBOX_RECORDINGS).
    #[arg(long, value_name = "PATH", help_heading = "Recording")]
    pub record: Option<PathBuf>,
    /// Do not record this run.
    #[arg(long, conflicts_with = "record", help_heading = "Recording")]
    pub no_record: bool,
    /// Record the full state every K steps (1 = every step). Hash, totals and events are recorded
    /// every step anyway. Default: every step for scenes of up to 100 critters, else a K chosen to
    /// keep recording under 10% of the step time (see docs/recording-format.md).
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u64).range(1..), help_heading = "Recording")]
    pub record_every: Option<u64>,
}

/// The signal that asked the run to stop (0: none yet).
static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// The signals that stop a run with its file finished: Ctrl-C, and what `kill`, `timeout` and
/// schedulers send, and a closed terminal.
const STOP_SIGNALS: [i32; 3] = [
    signal_hook::consts::SIGINT,
    signal_hook::consts::SIGTERM,
    signal_hook::consts::SIGHUP,
];

/// From now on, SIGINT, SIGTERM and SIGHUP ask the run to stop after the current step; a second
/// one while the run finishes quits at once (exit code 128 + its number).
pub fn watch_signals() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let Ok(mut signals) = signal_hook::iterator::Signals::new(STOP_SIGNALS) else {
            return;
        };
        // signal-hook's own handler only wakes this thread, which may then do anything.
        let _ = std::thread::Builder::new()
            .name("critterbox-signals".into())
            .spawn(move || {
                for sig in signals.forever() {
                    if SIGNAL
                        .compare_exchange(0, sig, Ordering::SeqCst, Ordering::SeqCst)
                        .is_err()
                    {
                        std::process::exit(128 + sig);
                    }
                }
            });
    });
}

/// The signal that asked the run to stop, if one did.
pub fn interrupted() -> Option<i32> {
    match SIGNAL.load(Ordering::SeqCst) {
        0 => None,
        sig => Some(sig),
    }
}

/// A signal's name as `kill -l` gives it (`SIGTERM`).
pub fn signal_name(sig: i32) -> String {
    match sig {
        signal_hook::consts::SIGINT => "SIGINT".into(),
        signal_hook::consts::SIGTERM => "SIGTERM".into(),
        signal_hook::consts::SIGHUP => "SIGHUP".into(),
        other => format!("signal {other}"),
    }
}

/// A run stopped by a signal, with its file finished: the error `main` turns into the exit code
/// 128 + the signal's number (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP), as shells do.
#[derive(Debug)]
pub struct Interrupted {
    /// The signal's number.
    pub signal: i32,
    /// Steps taken.
    pub step: u64,
    /// Whether the run was recorded.
    pub recorded: bool,
}

impl Interrupted {
    /// The exit code.
    pub fn exit_code(&self) -> u8 {
        u8::try_from(128 + self.signal).unwrap_or(1)
    }
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let by = match self.signal {
            signal_hook::consts::SIGINT => "Ctrl-C (SIGINT)".to_string(),
            other => signal_name(other),
        };
        write!(f, "interrupted by {by} after step {}", self.step)?;
        if self.recorded {
            write!(f, " (the recording is complete up to there)")?;
        }
        Ok(())
    }
}

impl std::error::Error for Interrupted {}

/// The run's metadata.
pub fn run_meta(args: &RunArgs, scene: &Scene, steps: u64) -> RunMeta {
    RunMeta::for_scene(scene, &overrides(args, Some(steps)))
}

fn overrides(args: &RunArgs, steps: Option<u64>) -> RunOverrides {
    RunOverrides {
        seed: args.seed,
        dt: args.dt,
        n: args.n,
        sets: args.sets.clone(),
        steps,
        limits: super::run::limits(args),
        record_every: args.recording.record_every,
    }
}

/// A run's recorder, and how many of the scene's script files are in the file so far.
pub struct RunRecording {
    rec: Recorder,
    attached: usize,
}

impl RunRecording {
    /// Records the step just taken, and attaches any script file the scene loaded during it (a
    /// kind loaded from `on_step`), so even a run killed later can be re-simulated.
    pub fn record(&mut self, scene: &Scene) -> anyhow::Result<()> {
        self.rec.record(&scene.world)?;
        self.attach_new(scene)
    }

    /// Records that `text`, the new text of the kind file `file`, replaced the kinds `kinds`
    /// after the last step recorded.
    pub fn reload(
        &mut self,
        scene: &Scene,
        file: &str,
        text: &str,
        kinds: Vec<String>,
    ) -> anyhow::Result<()> {
        self.attach_new(scene)?;
        Ok(self.rec.reload(&scene.world, file, text, kinds)?)
    }

    fn attach_new(&mut self, scene: &Scene) -> anyhow::Result<()> {
        let new = scene.sources_since(self.attached);
        if !new.is_empty() {
            self.attached += new.len();
            self.rec.attach(new)?;
        }
        Ok(())
    }
}

/// Starts recording, unless `--no-record`.
pub fn start(args: &RunArgs, scene: &Scene, steps: u64) -> anyhow::Result<Option<RunRecording>> {
    if args.recording.no_record {
        return Ok(None);
    }
    let file = match &args.recording.record {
        Some(p) => p.clone(),
        None => path::new_path(&path::default_dir(), &scene.name),
    };
    let meta = run_meta(args, scene, steps);
    let rec = Recorder::create(&file, &meta, &scene.sources, &scene.world)?;
    Ok(Some(RunRecording {
        rec,
        attached: scene.sources.len(),
    }))
}

/// Closes the recording after the run and says where it is.
pub fn finish(
    recorder: Option<RunRecording>,
    scene: &Scene,
    outcome: &str,
    reason: &str,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let Some(mut run) = recorder else {
        return Ok(());
    };
    run.attach_new(scene)?;
    let rec = run.rec;
    let end = EndMeta {
        steps: scene.world.step_count(),
        outcome: outcome.into(),
        reason: reason.into(),
        hash: scene.world.state_hash(),
        profile: scene.profile(),
    };
    let w = rec.finish(&scene.world, end)?;
    let ended = match outcome {
        "interrupted" => format!("{outcome} ({reason})"),
        _ => outcome.to_string(),
    };
    print_written(out, &w, &ended)
}

/// Records the error that stopped the run and closes the file, before the error is reported.
pub fn fail(
    recorder: Option<RunRecording>,
    scene: &Scene,
    error: &anyhow::Error,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let Some(mut run) = recorder else {
        return Ok(());
    };
    let message = format!("{error:#}");
    run.attach_new(scene)?;
    let mut rec = run.rec;
    rec.record_error(&scene.world, &message)?;
    let end = EndMeta {
        steps: scene.world.step_count(),
        outcome: "error".into(),
        reason: message,
        hash: scene.world.state_hash(),
        profile: scene.profile(),
    };
    let w = rec.finish(&scene.world, end)?;
    print_written(out, &w, "error")
}

/// A run whose scene could not be built: `scene` is the name asked for, `file` its script if
/// it is one, `sources` the scripts read up to the error. Writes a recording of the failure
/// (unless `--no-record`) before the error is reported.
pub fn failed_setup(
    args: &RunArgs,
    scene: &str,
    file: Option<&str>,
    sources: &[SourceFile],
    error: &anyhow::Error,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    if args.recording.no_record {
        return Ok(());
    }
    let path = match &args.recording.record {
        Some(p) => p.clone(),
        None => path::new_path(&path::default_dir(), scene),
    };
    let meta = RunMeta::for_failed_setup(
        scene,
        file,
        args.method.map(|m| m.to_string()),
        &overrides(args, args.steps),
    );
    let w = write_failed_setup(&path, &meta, sources, &format!("{error:#}"))?;
    print_written(out, &w, "failed during set-up")
}

fn print_written(out: &mut dyn Write, w: &Written, outcome: &str) -> anyhow::Result<()> {
    let note = match outcome {
        "completed" | "stopped" => String::new(),
        other => format!(", ended: {other}"),
    };
    writeln!(
        out,
        "recording    {} ({} steps, {} full states, {:.1} KiB{note})",
        w.path.display(),
        w.steps,
        w.states,
        w.bytes as f64 / 1024.0
    )?;
    Ok(())
}
