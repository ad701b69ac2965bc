//! The `--rerun*` options shared by `run` (and `replay`): a viewer when the `rerun` feature is
//! built in, a clear error otherwise.

use clap::Args;
use critterbox::scenes::AnyWorld;
use std::path::PathBuf;
use std::time::Duration;

/// Where to watch a run.
#[derive(Args, Debug, Default, Clone)]
pub struct ViewArgs {
    /// Stream to a new Rerun viewer (the `rerun` program must be on PATH).
    #[arg(long, help_heading = "Viewer (Rerun)")]
    pub rerun: bool,
    /// Stream to a running Rerun viewer at this URL (e.g. rerun+http://127.0.0.1:9876/proxy).
    #[arg(long, value_name = "URL", help_heading = "Viewer (Rerun)")]
    pub rerun_connect: Option<String>,
    /// Write what the viewer would show to a Rerun file (.rrd) instead.
    #[arg(long, value_name = "FILE.rrd", help_heading = "Viewer (Rerun)")]
    pub rerun_save: Option<PathBuf>,
    /// Draw velocity arrows (default: on up to 2,000 critters).
    #[arg(long, value_name = "on|off", help_heading = "Viewer (Rerun)")]
    pub arrows: Option<String>,
}

impl ViewArgs {
    /// True when any viewer output was asked for.
    pub fn wanted(&self) -> bool {
        self.rerun || self.rerun_connect.is_some() || self.rerun_save.is_some()
    }
}

/// A viewer, or nothing.
pub struct Viewer {
    #[cfg(feature = "rerun")]
    sink: Option<critterbox::viewer::RerunSink>,
}

impl Viewer {
    /// Opens what `args` ask for. A live viewer that cannot be reached is a warning (printed
    /// here) and the run goes on without it; a file that cannot be written is an error.
    pub fn open(args: &ViewArgs, world: &AnyWorld) -> anyhow::Result<Viewer> {
        if !args.wanted() {
            return Ok(Viewer {
                #[cfg(feature = "rerun")]
                sink: None,
            });
        }
        #[cfg(not(feature = "rerun"))]
        {
            let _ = world;
            anyhow::bail!(
                "this critterbox was built without the Rerun viewer; build it with `cargo build --release --features rerun`"
            );
        }
        #[cfg(feature = "rerun")]
        {
            use critterbox::viewer::{RerunSink, RerunTarget};
            let target = match (&args.rerun_save, &args.rerun_connect) {
                (Some(path), _) => RerunTarget::Save(path.clone()),
                (None, Some(url)) => RerunTarget::Connect(url.clone()),
                (None, None) => RerunTarget::Spawn,
            };
            let saving = matches!(target, RerunTarget::Save(_));
            let mut sink = match RerunSink::new(target, world.len()) {
                Ok(sink) => sink,
                Err(e) if saving => anyhow::bail!("cannot write the Rerun file: {e}"),
                Err(e) => {
                    eprintln!("warning: no Rerun viewer: {e}; running without it");
                    return Ok(Viewer { sink: None });
                }
            };
            match args.arrows.as_deref() {
                None => {}
                Some("on") => sink.set_arrows(true),
                Some("off") => sink.set_arrows(false),
                Some(other) => anyhow::bail!("--arrows {other}: write on or off"),
            }
            sink.log_static(world);
            sink.log_step(world, Duration::ZERO);
            Ok(Viewer { sink: Some(sink) })
        }
    }

    /// Logs the state after a step.
    pub fn step(&mut self, world: &AnyWorld, step_time: Duration) {
        #[cfg(feature = "rerun")]
        if let Some(sink) = &mut self.sink {
            sink.log_step(world, step_time);
        }
        #[cfg(not(feature = "rerun"))]
        let _ = (world, step_time);
    }

    /// Shows `line` in the viewer's log with the next step (a kind reloaded, `run --watch`).
    pub fn note(&mut self, line: String) {
        #[cfg(feature = "rerun")]
        if let Some(sink) = &mut self.sink {
            sink.note(line);
        }
        #[cfg(not(feature = "rerun"))]
        let _ = line;
    }

    /// Finishes; returns the time taken from the simulation thread and the steps a live
    /// viewer skipped, and prints a warning if a live viewer never took the data.
    pub fn finish(self) -> Option<(Duration, u64)> {
        #[cfg(feature = "rerun")]
        if let Some(sink) = self.sink {
            let spent = (sink.logging_time(), sink.skipped());
            if let Some(warning) = sink.finish() {
                eprintln!("warning: {warning}");
            }
            return Some(spent);
        }
        None
    }
}
