//! What `critterbox run` adds for recording: the `--record` flags, the run's metadata, the
//! recorder's start and end, and Ctrl-C, which ends the run early with the file finished.

use super::run::RunArgs;
use clap::Args;
use critterbox::recording::{path, EndMeta, Recorder, RunMeta, RunOverrides, Written};
use critterbox::scenes::Scene;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

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

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// From now on, Ctrl-C asks the run to stop after the current step (and a second Ctrl-C quits at
/// once).
pub fn watch_ctrl_c() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            if INTERRUPTED.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        });
    });
}

/// True once Ctrl-C was pressed.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// The run's metadata.
pub fn run_meta(args: &RunArgs, scene: &Scene, steps: u64) -> RunMeta {
    let overrides = RunOverrides {
        seed: args.seed,
        dt: args.dt,
        n: args.n,
        sets: args.sets.clone(),
        steps: Some(steps),
        limits: super::run::limits(args),
        record_every: args.recording.record_every,
    };
    RunMeta::for_scene(scene, &overrides)
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
    print_written(out, &w, outcome)
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

fn print_written(out: &mut dyn Write, w: &Written, outcome: &str) -> anyhow::Result<()> {
    let note = match outcome {
        "completed" | "stopped" => String::new(),
        other => format!(", ended by {other}"),
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
