//! `critterbox run`: run a scene headless and print a summary.

use super::record::{self, RecordArgs};
use anyhow::Context;
use clap::Args;
use critterbox::scenes::{self, AnyWorld, Scene, SceneParams, SourceFile, DEFAULT_SCENE, SCENES};
use critterbox::script::{Limits, ScriptOptions};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::Write;
use std::time::{Duration, Instant};

/// Arguments of `critterbox run`.
#[derive(Args, Debug, Clone)]
#[command(
    after_help = "Exit codes: 0 when the run completed or the scene stopped it; 1 on an \
error (a scene that cannot be built is still recorded, with its scripts and the error); \
128 + the signal when SIGINT (130), SIGTERM (143) or SIGHUP (129) stopped it after the current \
step, with the recording finished (end record `interrupted`, naming the signal)."
)]
pub struct RunArgs {
    /// A scene script (scripts/scenes/NAME.rhai) or a built-in scene (see --list). Default: gas.
    pub scene: Option<String>,
    /// Override a scene script's constant, --set SPEED=20, or a kind's, --set boid.SIGHT=3
    /// (repeatable).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
    /// Most operations one script call may run before it is stopped (endless-loop guard).
    #[arg(long, default_value_t = Limits::default().max_operations, help_heading = "Script limits")]
    pub max_ops: u64,
    /// Most operations all script calls of one step may run together (0: no budget).
    #[arg(long, default_value_t = Limits::default().max_step_operations, help_heading = "Script limits")]
    pub max_step_ops: u64,
    /// Most spawns scripts may request in one step.
    #[arg(long, default_value_t = Limits::default().max_spawns_per_step, help_heading = "Script limits")]
    pub max_spawns: u64,
    /// Deepest nesting of function calls in a script.
    #[arg(long, default_value_t = Limits::default().max_call_levels, help_heading = "Script limits")]
    pub max_call_depth: usize,
    /// Longest string a script may build (bytes).
    #[arg(long, default_value_t = Limits::default().max_string_size, help_heading = "Script limits")]
    pub max_string: usize,
    /// Longest array a script may build (items of nested arrays count too).
    #[arg(long, default_value_t = Limits::default().max_array_size, help_heading = "Script limits")]
    pub max_array: usize,
    /// Largest map a script may build (entries of nested maps count too).
    #[arg(long, default_value_t = Limits::default().max_map_size, help_heading = "Script limits")]
    pub max_map: usize,
    /// List the built-in scenes and exit.
    #[arg(long)]
    pub list: bool,
    /// Number of steps (default: the scene's own).
    #[arg(long)]
    pub steps: Option<u64>,
    /// Time step in seconds (default: the scene's own).
    #[arg(long, allow_negative_numbers = true)]
    pub dt: Option<f64>,
    /// Seed of the world's random generator (default: the scene's own, 1 for built-ins): the
    /// same seed gives a bit-identical run.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Number of critters, for scenes that have a natural count (gas, cradle, pegs).
    #[arg(short = 'n', long)]
    pub n: Option<usize>,
    /// Collision method: discrete, substep:N, swept, event, solve:N or auto (default: the scene's own).
    #[arg(long, value_parser = parse_method)]
    pub method: Option<critterbox::method::Method>,
    /// Also print time per stage and pair counts per step.
    #[arg(long)]
    pub stats: bool,
    /// Also write the summary as JSON to FILE (written whole through a rename; not written
    /// when the run fails): figures, final state hash, wall time, outcome, `world().vars`.
    #[arg(long, value_name = "FILE")]
    pub summary_json: Option<std::path::PathBuf>,
    /// Watch the script files the run loaded: an edited kind file replaces its kind at the next
    /// step (recorded, so the replay makes the same swap); an edited scene file runs the scene
    /// again from step 0 (`--record run.mcap`: run.mcap, run-2.mcap, ...); a file that does not
    /// compile leaves the old version running. After the run, any edit runs it again. Ctrl-C
    /// stops (docs/scripting.md, "Edit while it runs").
    #[arg(long)]
    pub watch: bool,
    /// Watching the run.
    #[command(flatten)]
    pub view: super::view::ViewArgs,
    /// Recording options.
    #[command(flatten)]
    pub recording: RecordArgs,
}

/// How a run ended, when it did not fail.
pub enum Ended {
    /// It ran its steps, the scene stopped it, or a signal did.
    Finished,
    /// Its scene file changed (`--watch`): run it again.
    SceneChanged,
}

/// Runs the command.
pub fn run(args: &RunArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    if args.watch && !args.list {
        return super::watch::run_watching(args, out);
    }
    run_once(args, out, None).map(|_| ())
}

/// Runs the scene once; with `watch`, watches its script files and applies their edits.
pub fn run_once(
    args: &RunArgs,
    out: &mut dyn Write,
    mut watch: Option<&mut super::watch::Watch>,
) -> anyhow::Result<Ended> {
    if args.list {
        writeln!(out, "built-in scenes (critterbox run NAME):")?;
        for s in SCENES {
            let mark = if s.name == DEFAULT_SCENE {
                " (default)"
            } else {
                ""
            };
            writeln!(out, "  {:<10} {}{}", s.name, s.about, mark)?;
        }
        return Ok(Ended::Finished);
    }
    if let Some(dt) = args.dt {
        // Checked before the scene is built: a bad --dt is a mistyped command, not a failed set-up.
        critterbox::world::check_dt(dt).with_context(|| format!("--dt {dt}"))?;
    }
    // Signals are watched from here on, so that one arriving while the scene is built stops
    // the run before its first step, with a finished file (a second one ends the process).
    record::watch_signals();
    let mut scene = match load(args) {
        Ok(scene) => scene,
        Err(Unloaded::Usage(e)) => return Err(e),
        Err(Unloaded::Setup {
            error,
            name,
            file,
            sources,
        }) => {
            if let Some(w) = watch.as_deref_mut() {
                w.add(&sources)?;
            }
            return failed_setup(args, &name, file.as_deref(), &sources, error, out)
                .map(|()| Ended::Finished);
        }
    };
    if let Some(w) = watch.as_deref_mut() {
        w.add(&scene.sources)?;
    }
    let scene_file = scene.sources.first().map(|s| s.path.clone());
    if let Err(error) = configure(&mut scene, args) {
        let file = scene.sources.first().map(|s| s.path.clone());
        return failed_setup(
            args,
            &scene.name,
            file.as_deref(),
            &scene.sources,
            error,
            out,
        )
        .map(|()| Ended::Finished);
    }
    let name = scene.name.clone();
    let steps = args.steps.unwrap_or(scene.default_steps);

    let energy0 = scene.world.kinetic_energy();
    let momentum0 = scene.world.momentum();
    let mut viewer = super::view::Viewer::open(&args.view, &scene.world)?;
    // Recording: started before the first step, fed after each one, closed at the end.
    let mut recorder = record::start(args, &scene, steps)?;
    let mut interrupted = None;
    let bar = progress_bar(steps);
    let started = Instant::now();
    let mut stopped = None;
    let mut scene_changed = false;
    // The kind files reloaded under --watch, with the step after which each was.
    let mut reloads: Vec<(u64, String)> = Vec::new();
    // Time the simulation thread spends recording (hash, totals, events, handing them over).
    let mut recording = Duration::ZERO;
    for i in 0..steps {
        if let Some(sig) = record::interrupted() {
            interrupted = Some(sig);
            break;
        }
        let step = scene.world.step_count();
        let step_started = Instant::now();
        let outcome = scene.step();
        viewer.step(&scene.world, step_started.elapsed());
        let log = scene.world.log();
        if !log.is_empty() {
            // Step k takes the world from k - 1 steps to k: the recording keeps these lines
            // under step k too (docs/recording-format.md).
            bar.suspend(|| {
                for line in log {
                    eprintln!("[step {}] {line}", step + 1);
                }
            });
        }
        // A script error names its step already.
        let names_step =
            |e: &critterbox::Error| matches!(e, critterbox::Error::Script(s) if s.step.is_some());
        let outcome = match outcome.map_err(|e| {
            let context = if names_step(&e) {
                format!("scene '{name}'")
            } else {
                format!("scene '{name}', step {step}")
            };
            anyhow::Error::new(e).context(context)
        }) {
            Ok(outcome) => outcome,
            Err(e) => {
                // A kind reloaded under --watch that fails stops the run (watch.rs says
                // why): the error says so, naming the reload.
                let e = match reloaded_cause(&e, &reloads) {
                    Some((at, file)) => e.context(format!(
                        "watch: {file} was reloaded after step {at} and its new version failed; \
                         the run stopped (fix the file and save it: the scene runs again from step 0)"
                    )),
                    None => e,
                };
                // The error goes into the recording, which is closed before it is reported.
                bar.finish_and_clear();
                record::fail(recorder.take(), &scene, &e, out)?;
                return Err(e);
            }
        };
        if let Some(r) = &mut recorder {
            let clock = Instant::now();
            r.record(&scene)?;
            recording += clock.elapsed();
        }
        if let Some(reason) = outcome {
            stopped = Some((scene.world.step_count(), reason));
            break;
        }
        if let Some(w) = watch.as_deref_mut() {
            // Kinds the step loaded are watched too.
            let new = scene.sources_since(w.added());
            if !new.is_empty() {
                w.add(&new)?;
            }
            let changed = w.changed();
            let file = scene_file.as_deref();
            let edits = if changed.is_empty() {
                Edits::Applied(Vec::new())
            } else {
                let sets = parse_sets(args).unwrap_or_default();
                let edit = Edit {
                    scene_file: file,
                    sets: &sets,
                };
                bar.suspend(|| apply(changed, &mut scene, &mut recorder, &mut viewer, &edit))?
            };
            match edits {
                Edits::SceneChanged => {
                    let reason = "its scene file changed (--watch)".to_string();
                    stopped = Some((scene.world.step_count(), reason));
                    scene_changed = true;
                    break;
                }
                Edits::Applied(files) => {
                    let at = scene.world.step_count();
                    reloads.extend(files.into_iter().map(|f| (at, f)));
                }
            }
        }
        if i % 16 == 15 {
            bar.set_position(i + 1);
        }
    }
    let wall = started.elapsed();
    bar.finish_and_clear();
    let viewing = viewer.finish();
    let done = scene.world.step_count();
    summary(out, &name, &scene.world, done, energy0, momentum0, wall)?;
    if let Some((spent, skipped)) = viewing {
        writeln!(
            out,
            "viewer       {:.3} s of the simulation thread spent on Rerun ({:.1}% of the run){}",
            spent.as_secs_f64(),
            100.0 * spent.as_secs_f64() / wall.as_secs_f64().max(1e-9),
            if skipped > 0 {
                format!("; {skipped} steps not shown (the viewer fell behind)")
            } else {
                String::new()
            }
        )?;
    }
    let method = scene.world.method();
    writeln!(out, "method       {method}")?;
    if let Some((chose, why)) = scene.world.auto_choice() {
        writeln!(out, "auto chose   {chose} (last step): {why}")?;
    }
    if let Some(islands) = scene.world.auto_islands() {
        writeln!(out, "islands      {islands} (last step)")?;
    }
    let stepped = scene.world.auto_choice().map_or(method, |c| c.0);
    if matches!(stepped, critterbox::method::Method::Solve(_)) {
        let how = if scene.world.sleep_allowed() {
            "critters at rest under gravity sleep; `sleep: false` in world(#{ ... }) turns it off"
        } else {
            "sleep is off in this scene"
        };
        writeln!(
            out,
            "asleep       {} critters ({how})",
            scene.world.sleepers()
        )?;
    }
    let t = scene.world.totals();
    if t.events > 0 || t.budget_exceeded > 0 {
        writeln!(
            out,
            "events       {} processed, {} steps over budget",
            t.events, t.budget_exceeded
        )?;
    }
    if let Some((at, reason)) = &stopped {
        writeln!(out, "stopped      by the scene after step {at}: {reason}")?;
    }
    if let Some(sig) = interrupted {
        let name = record::signal_name(sig);
        writeln!(out, "ended        interrupted ({name}) after step {done}")?;
    }
    if args.stats {
        stats(
            out,
            &scene.world,
            done,
            recorder.is_some().then_some(recording),
        )?;
        let profile = scene.profile();
        if !profile.is_empty() {
            writeln!(out, "scripts      calls and time per kind and hook")?;
            write!(out, "{}", critterbox::profile::table(&profile))?;
        }
    }
    let (outcome, reason) = match (&stopped, interrupted) {
        (_, Some(sig)) => ("interrupted", record::signal_name(sig)),
        (Some((_, reason)), _) => ("stopped", reason.clone()),
        _ => ("completed", String::new()),
    };
    let recorded = recorder.is_some();
    record::finish(recorder, &scene, outcome, &reason, out)?;
    if let Some(path) = &args.summary_json {
        let summary = critterbox::sweep::RunSummary::of(
            &scene.world,
            &name,
            energy0,
            momentum0,
            wall,
            outcome,
            &reason,
        );
        let json = serde_json::to_string_pretty(&summary)?;
        critterbox::sweep::write_atomic(path, json.as_bytes())
            .with_context(|| format!("--summary-json {}", path.display()))?;
    }
    if let Some(signal) = interrupted {
        return Err(record::Interrupted {
            signal,
            step: done,
            recorded,
        }
        .into());
    }
    Ok(if scene_changed {
        Ended::SceneChanged
    } else {
        Ended::Finished
    })
}

/// The reload (step, file) a failed step's error comes from: the last reload of the file the
/// script error names.
fn reloaded_cause<'a>(
    e: &anyhow::Error,
    reloads: &'a [(u64, String)],
) -> Option<&'a (u64, String)> {
    let file = e
        .chain()
        .find_map(|c| match c.downcast_ref::<critterbox::Error>() {
            Some(critterbox::Error::Script(s)) => Some(s.file.clone()),
            _ => None,
        })?;
    reloads.iter().rev().find(|(_, f)| *f == file)
}

/// What the watched files' edits did between two steps.
enum Edits {
    /// Nothing, or the kind files it names reloaded (edits that did not compile are reported
    /// and change nothing).
    Applied(Vec<String>),
    /// The scene file changed: the run starts again.
    SceneChanged,
}

/// What [`apply`] needs of the run: its scene file, and its `--set`s (a kind's are in its
/// reloaded text too).
struct Edit<'a> {
    scene_file: Option<&'a str>,
    sets: &'a [(String, String)],
}

/// Applies edits of the watched files (path as loaded, new text) between two steps: a kind
/// file's new text replaces its kinds (and is recorded); a text that does not compile is
/// reported and the old one runs on; a change of the scene file ends the run.
fn apply(
    changed: Vec<(String, String)>,
    scene: &mut Scene,
    recorder: &mut Option<record::RunRecording>,
    viewer: &mut super::view::Viewer,
    edit: &Edit,
) -> anyhow::Result<Edits> {
    let step = scene.world.step_count();
    let mut reloaded = Vec::new();
    for (file, text) in changed {
        if Some(file.as_str()) == edit.scene_file {
            return Ok(Edits::SceneChanged);
        }
        match scene.reload_kind(&file, &text) {
            Ok(kinds) => {
                let line = format!(
                    "watch: after step {step}: {file} reloaded (kind {})",
                    kinds.join(", ")
                );
                eprintln!("{line}");
                viewer.note(line);
                if let Some(r) = recorder {
                    // The text the kind was built from: with its --set constants in it.
                    let built = match kinds.first() {
                        Some(kind) => {
                            critterbox::script::kind_text_with_sets(&file, kind, &text, edit.sets)?
                        }
                        None => text.clone(),
                    };
                    r.reload(scene, &file, &built, kinds)?;
                }
                reloaded.push(file);
            }
            Err(e) => eprintln!(
                "watch: after step {step}: {file} not reloaded, the old version runs on: {e}"
            ),
        }
    }
    Ok(Edits::Applied(reloaded))
}

/// Why no scene came out of [`load`].
enum Unloaded {
    /// The command line asks for something impossible: nothing ran, nothing is recorded.
    Usage(anyhow::Error),
    /// Building the scene failed: the run is recorded with the error.
    Setup {
        error: anyhow::Error,
        /// The scene's name (a built-in's, or the script's file stem).
        name: String,
        /// The scene script, for a script scene.
        file: Option<String>,
        /// The scripts read up to the error.
        sources: Vec<SourceFile>,
    },
}

/// The command line's `--dt` and `--method`, applied to the built scene.
fn configure(scene: &mut Scene, args: &RunArgs) -> anyhow::Result<()> {
    if let Some(dt) = args.dt {
        scene.world.set_dt(dt)?;
    }
    if let Some(m) = args.method {
        scene.world.set_method(m)?;
    }
    Ok(())
}

/// Records a run whose scene could not be built, then gives its error back to be reported (a
/// recording that cannot be written is a warning: the set-up error is the one to report).
fn failed_setup(
    args: &RunArgs,
    name: &str,
    file: Option<&str>,
    sources: &[SourceFile],
    error: anyhow::Error,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    if let Err(e) = record::failed_setup(args, name, file, sources, &error, out) {
        eprintln!("warning: the failed set-up could not be recorded: {e:#}");
    }
    Err(error)
}

/// A scene script when SCENE names a file, a built-in scene otherwise.
fn load(args: &RunArgs) -> Result<Scene, Unloaded> {
    let name = args.scene.as_deref().unwrap_or(DEFAULT_SCENE);
    let path = std::path::Path::new(name);
    let is_script = name.ends_with(".rhai") || path.is_file();
    let usage = |e: anyhow::Error| Unloaded::Usage(e);
    if !is_script {
        if !args.sets.is_empty() {
            return Err(usage(anyhow::anyhow!(
                "--set works on scene scripts; '{name}' is a built-in scene (try -n, --dt, --seed)"
            )));
        }
        let params = SceneParams {
            n: args.n,
            seed: args.seed.unwrap_or(1),
            dt: args.dt,
        };
        return scenes::builtin(name, &params).map_err(|e| match e {
            // A name that is no scene is a mistyped command, not a failed set-up.
            critterbox::Error::UnknownScene { .. } => usage(e.into()),
            e => Unloaded::Setup {
                error: e.into(),
                name: name.to_string(),
                file: None,
                sources: Vec::new(),
            },
        });
    }
    if args.n.is_some() {
        return Err(usage(anyhow::anyhow!(
            "-n works on built-in scenes; a scene script sets its own counts (use --set NAME=VALUE)"
        )));
    }
    let sets = parse_sets(args).map_err(usage)?;
    let options = ScriptOptions {
        limits: limits(args),
        seed: args.seed,
        profile: profiled(args),
        ..ScriptOptions::default()
    };
    critterbox::script::load_scene_keeping_sources(path, &sets, &options).map_err(
        |(error, sources)| {
            // A script that could not be read at all is a mistyped path: nothing to record.
            if sources.is_empty() {
                return usage(error.into());
            }
            Unloaded::Setup {
                error: error.into(),
                name: path
                    .file_stem()
                    .map_or(name.to_string(), |s| s.to_string_lossy().into_owned()),
                file: Some(name.to_string()),
                sources,
            }
        },
    )
}

/// The `--set NAME=VALUE` and `--set KIND.NAME=VALUE` pairs.
fn parse_sets(args: &RunArgs) -> anyhow::Result<Vec<(String, String)>> {
    let mut sets = Vec::new();
    for s in &args.sets {
        let (k, v) = s.split_once('=').with_context(|| {
            format!(
                "--set {s}: write NAME=VALUE for a scene constant or KIND.NAME=VALUE for a \
                 kind's, e.g. --set SPEED=20 or --set boid.SIGHT=3"
            )
        })?;
        sets.push((k.trim().to_string(), v.trim().to_string()));
    }
    Ok(sets)
}

/// Whether the run times its hooks (critterbox::profile): with `--stats`, whose table it feeds,
/// and the recording's end metadata then keeps the table too.
fn profiled(args: &RunArgs) -> bool {
    args.stats
}

fn parse_method(s: &str) -> Result<critterbox::method::Method, String> {
    s.parse()
}

/// The script limits the command line asks for.
impl Default for RunArgs {
    /// What `critterbox run` with no arguments gets (also `critterbox` alone, and the runs
    /// `critterbox test` records): the command line's defaults. A derived `Default` gave zeros
    /// for the script limits, which recordings then carried, and a replay of them refused the
    /// scene's first spawn.
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Bare {
            #[command(flatten)]
            args: RunArgs,
        }
        <Bare as clap::Parser>::parse_from(["critterbox"]).args
    }
}

pub(crate) fn limits(args: &RunArgs) -> Limits {
    Limits {
        max_operations: args.max_ops,
        max_step_operations: args.max_step_ops,
        max_spawns_per_step: args.max_spawns,
        max_call_levels: args.max_call_depth,
        max_string_size: args.max_string,
        max_array_size: args.max_array,
        max_map_size: args.max_map,
    }
}

pub(crate) fn progress_bar(steps: u64) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(steps), ProgressDrawTarget::stderr_with_hz(10));
    bar.set_style(
        ProgressStyle::with_template("{spinner} step {pos}/{len} [{bar:30}] {per_sec} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar
}

fn fmt3(v: [f64; 3], dim: usize) -> String {
    let parts: Vec<String> = v[..dim].iter().map(|x| format!("{x:.6e}")).collect();
    format!("({})", parts.join(", "))
}

fn summary(
    out: &mut dyn Write,
    name: &str,
    world: &AnyWorld,
    steps: u64,
    energy0: f64,
    momentum0: [f64; 3],
    wall: Duration,
) -> anyhow::Result<()> {
    let dim = world.dim();
    let totals = world.totals();
    let energy = world.kinetic_energy();
    let drift = if energy0 > 0.0 {
        (energy - energy0) / energy0
    } else {
        0.0
    };
    let counts: Vec<String> = world
        .count_by_kind()
        .iter()
        .map(|(k, n)| format!("{k} {n}"))
        .collect();
    writeln!(
        out,
        "scene        {name} ({dim}D, {:?} border)",
        world.border()
    )?;
    writeln!(
        out,
        "steps        {steps} (t = {:.4} s, dt = {:.6} s)",
        world.time(),
        world.dt()
    )?;
    writeln!(out, "critters     {}", counts.join(", "))?;
    // The scripts' shared state, as `--summary-json` writes it (values as JSON).
    let vars = world.vars();
    if !vars.is_empty() {
        let shown: Vec<String> = vars
            .iter()
            .map(|(k, v)| format!("{k} = {}", critterbox::sweep::prop_to_json(v)))
            .collect();
        writeln!(out, "vars         {}", shown.join(", "))?;
    }
    writeln!(
        out,
        "collisions   {} impacts ({:.2} per step), {} contacts handled",
        totals.impacts,
        totals.impacts as f64 / steps.max(1) as f64,
        totals.collisions
    )?;
    writeln!(
        out,
        "energy       {energy:.9e} (start {energy0:.9e}, relative change {drift:+.3e})"
    )?;
    writeln!(
        out,
        "momentum     {} (start {})",
        fmt3(world.momentum(), dim),
        fmt3(momentum0, dim)
    )?;
    writeln!(out, "state hash   {:016x}", world.state_hash())?;
    writeln!(
        out,
        "wall time    {:.3} s ({:.4} ms/step)",
        wall.as_secs_f64(),
        wall.as_secs_f64() * 1e3 / steps.max(1) as f64
    )?;
    Ok(())
}

/// Time per stage and pair counts per step; `recording` is the simulation thread's time spent
/// recording, if the run was recorded.
fn stats(
    out: &mut dyn Write,
    world: &AnyWorld,
    steps: u64,
    recording: Option<Duration>,
) -> anyhow::Result<()> {
    let t = world.totals();
    let per = |d: Duration| d.as_secs_f64() * 1e3 / steps.max(1) as f64;
    let n = steps.max(1) as f64;
    writeln!(out, "per step     ms")?;
    for (stage, d) in [
        ("update", t.update),
        ("move", t.moving),
        ("pairs", t.pairs),
        ("response", t.response),
        ("lifecycle", t.lifecycle),
        ("total", t.total()),
    ] {
        writeln!(out, "  {stage:<12} {:.4}", per(d))?;
    }
    if let Some(r) = recording {
        writeln!(
            out,
            "  record       {:.4} (not in the total: {:.1}% on top of it, on the simulation thread)",
            per(r),
            100.0 * r.as_secs_f64() / t.total().as_secs_f64().max(1e-12)
        )?;
    }
    let diagnostics = world.diagnostics();
    let rebuilds = diagnostics.list_rebuilds;
    let grid_steps = diagnostics.grid_steps;
    if rebuilds > 0 {
        writeln!(
            out,
            "pair list    rebuilt {rebuilds} times (every {:.1} steps), mended {} times",
            steps.saturating_sub(grid_steps) as f64 / rebuilds as f64,
            diagnostics.list_repairs
        )?;
    }
    if diagnostics.layouts > 0 {
        writeln!(
            out,
            "layout       the critters laid out along the grid {} (docs/ARCHITECTURE.md, \"Ids and slots\")",
            match diagnostics.layouts {
                1 => "once".to_string(),
                n => format!("{n} times"),
            }
        )?;
    }
    if grid_steps > 0 {
        writeln!(
            out,
            "plain grid   {grid_steps} steps (the pair lists lived a single step each)"
        )?;
    }
    if let Some(peak) = peak_rss_bytes() {
        writeln!(
            out,
            "memory       peak {:.1} MiB ({:.0} bytes per critter, whole process)",
            peak as f64 / (1 << 20) as f64,
            peak as f64 / world.len().max(1) as f64
        )?;
    }
    writeln!(
        out,
        "pairs/step   {:.1} box tests, {:.1} candidates, {:.1} may collide, {:.1} touching",
        t.pair_tests as f64 / n,
        t.candidates as f64 / n,
        t.ruled as f64 / n,
        t.contacts as f64 / n
    )?;
    if t.sweeps > 0 {
        writeln!(
            out,
            "solve        {:.1} velocity sweeps per step (summed over substeps)",
            t.sweeps as f64 / n
        )?;
    }
    Ok(())
}

/// The process's peak resident memory, where the system says it (Linux).
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `RunArgs::default()` is what the command line gives with no arguments: the script limits'
    /// defaults, not zeros (a recording made from it carries them into its replays).
    #[test]
    fn default_run_args_are_the_command_line_s_defaults() {
        let args = RunArgs::default();
        assert_eq!(limits(&args), Limits::default());
        assert!(args.scene.is_none() && args.sets.is_empty() && args.steps.is_none());
    }
}
