//! Re-simulating a recorded run: the scene rebuilt from the file, stepped as the run was, and
//! any step's exact state on demand.
//!
//! A world cannot be restored from a keyframe without an engine API to set its step count, its
//! generator and its slot allocation, so a replay runs from step 0; the keyframes it passes are
//! checked on the way, and the hashes of every step.

use super::capture;
use super::compare::first_difference;
use super::reader::{self, Recording};
use super::rebuild::{rebuild, Rebuilt};
use super::schema::StateMsg;
use crate::scenes::AnyWorld;

/// Why a replay could not reach a step.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The re-simulated step failed.
    #[error("the replay failed at step {step}: {message}")]
    Failed {
        /// Steps completed before the failure.
        step: u64,
        /// The error.
        message: String,
    },
    /// The scene asked to stop before the step.
    #[error("the scene stopped after step {step} ({reason})")]
    Stopped {
        /// Steps taken.
        step: u64,
        /// The scene's reason.
        reason: String,
    },
}

/// A recorded run being re-simulated.
pub struct Replay {
    rebuilt: Rebuilt,
    stopped: Option<String>,
}

impl Replay {
    /// The recorded scene at step 0.
    pub fn new(rec: &Recording) -> anyhow::Result<Replay> {
        Ok(Replay {
            rebuilt: rebuild(rec)?,
            stopped: None,
        })
    }

    /// The world now.
    pub fn world(&self) -> &AnyWorld {
        &self.rebuilt.scene.world
    }

    /// Steps taken.
    pub fn step_count(&self) -> u64 {
        self.world().step_count()
    }

    /// Steps until `step` steps have been taken, calling `each` after every step.
    pub fn step_to(
        &mut self,
        step: u64,
        mut each: impl FnMut(&AnyWorld) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        while self.step_count() < step {
            if let Some(reason) = &self.stopped {
                return Err(ReplayError::Stopped {
                    step: self.step_count(),
                    reason: reason.clone(),
                }
                .into());
            }
            let at = self.step_count();
            match self.rebuilt.scene.step() {
                Ok(stop) => self.stopped = stop,
                Err(e) => {
                    return Err(ReplayError::Failed {
                        step: at,
                        message: e.to_string(),
                    }
                    .into())
                }
            }
            each(self.world())?;
        }
        Ok(())
    }

    /// Takes one more step, expecting it to fail (the recording ended with an error); returns the
    /// error, or `None` if the step succeeded.
    pub fn step_expecting_error(&mut self) -> Option<String> {
        match self.rebuilt.scene.step() {
            Ok(stop) => {
                self.stopped = stop;
                None
            }
            Err(e) => Some(e.to_string()),
        }
    }
}

/// Where a state shown by [`state_at_step`] came from.
#[derive(Clone, Debug, PartialEq)]
pub enum StateSource {
    /// Read from the recording.
    Recorded,
    /// Re-simulated from step 0; every step's hash matched the recording, and the full state
    /// at the keyframe `keyframe` (if any) matched too.
    Resimulated {
        /// The nearest recorded full state before the step.
        keyframe: Option<u64>,
    },
}

/// The exact state after `step` steps: from the file if it holds that state, else re-simulated
/// and checked against the recorded hashes and the nearest keyframe on the way.
pub fn state_at_step(rec: &Recording, step: u64) -> anyhow::Result<(StateMsg, StateSource)> {
    let last = rec.last_step();
    anyhow::ensure!(
        step <= last,
        "the recording ends at step {last}; there is no step {step}"
    );
    if rec.keyframes.contains(&step) {
        if let Some(s) = reader::state_at(&rec.path, step)? {
            return Ok((s, StateSource::Recorded));
        }
    }
    let keyframe = rec.keyframe_at_or_before(step);
    let key_state = match keyframe {
        Some(k) => reader::state_at(&rec.path, k)?,
        None => None,
    };
    let mut replay = Replay::new(rec)?;
    let check = |world: &AnyWorld| -> anyhow::Result<()> {
        let s = world.step_count();
        if let Some(&h) = rec.hashes.get(&s) {
            let got = world.state_hash();
            anyhow::ensure!(
                got == h,
                "the replay diverged from the recording at step {s} (hash {got:016x}, recorded \
                 {h:016x}); step {step} cannot be shown exactly: run `critterbox replay --verify`"
            );
        }
        if let Some(k) = &key_state {
            if k.step == s {
                let mine = capture::any_state(world);
                if let Some(d) = first_difference(k, &mine, "recorded", "replayed") {
                    anyhow::bail!("the replay differs from the keyframe at step {s}: {d}");
                }
            }
        }
        Ok(())
    };
    check(replay.world())?;
    replay.step_to(step, check)?;
    Ok((
        capture::any_state(replay.world()),
        StateSource::Resimulated { keyframe },
    ))
}
