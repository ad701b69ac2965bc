//! Re-simulating a recorded run: the scene rebuilt from the file, stepped as the run was, and
//! any step's exact state on demand.
//!
//! To show step N, a replay starts from the nearest recorded full state before N when it can
//! (the state carries the generator and the free slots, so the world is put back exactly; the
//! restored world's hash must equal the recorded hash of that step), and from step 0 otherwise.
//! Every step's hash is checked on the way; if anything differs after a restore (a scene that
//! keeps state of its own outside the world, say), it starts again from step 0.

use super::capture;
use super::compare::first_difference;
use super::error::{with_causes, RecordingError};
use super::reader::{self, Recording};
use super::rebuild::{rebuild, Rebuilt};
use super::schema::{id_of, StateMsg};
use crate::critter::{Critter, CritterId, Shape, Traits, CLASS_UNSET};
use crate::kind::KindId;
use crate::scenes::AnyWorld;
use crate::vector::Vector;
use crate::world::World;
use std::sync::Arc;

/// A recorded run being re-simulated.
pub struct Replay {
    rebuilt: Rebuilt,
    stopped: Option<String>,
    /// The recorded reloads (step, kind file, new text), in order, and how many are made.
    reloads: Vec<(u64, String, String)>,
    reloaded: usize,
}

impl Replay {
    /// The recorded scene at step 0.
    pub fn new(rec: &Recording) -> Result<Replay, RecordingError> {
        let mut reloads = Vec::with_capacity(rec.reloads.len());
        for r in &rec.reloads {
            let Some(text) = rec.reload_texts.get(&r.attachment) else {
                return Err(RecordingError::Reload {
                    step: r.step,
                    file: r.file.clone(),
                    reason: format!("the file has no attachment '{}'", r.attachment),
                });
            };
            reloads.push((r.step, r.file.clone(), text.clone()));
        }
        Ok(Replay {
            rebuilt: rebuild(rec)?,
            stopped: None,
            reloads,
            reloaded: 0,
        })
    }

    /// Makes the recorded reloads of kind files that came after at most `step` steps, as the
    /// run made them (between two steps).
    fn reload_through(&mut self, step: u64) -> Result<(), RecordingError> {
        while let Some((at, file, text)) = self.reloads.get(self.reloaded) {
            if *at > step {
                break;
            }
            let fail = |reason: String| RecordingError::Reload {
                step: *at,
                file: file.clone(),
                reason,
            };
            let path = self
                .rebuilt
                .kind_path(file)
                .ok_or_else(|| fail("the file holds no copy of that kind file".into()))?;
            let text = self.rebuilt.repoint(text);
            self.rebuilt
                .scene
                .reload_kind(&path, &text)
                .map_err(|e| fail(e.to_string()))?;
            self.reloaded += 1;
        }
        Ok(())
    }

    /// The world now.
    pub fn world(&self) -> &AnyWorld {
        &self.rebuilt.scene.world
    }

    /// Steps taken.
    pub fn step_count(&self) -> u64 {
        self.world().step_count()
    }

    /// Steps until `step` steps have been taken, calling `each` after every step; an error of
    /// `each` stops the replay and is returned as it is.
    pub fn step_to<E: From<RecordingError>>(
        &mut self,
        step: u64,
        mut each: impl FnMut(&AnyWorld) -> Result<(), E>,
    ) -> Result<(), E> {
        while self.step_count() < step {
            if let Some(reason) = &self.stopped {
                return Err(RecordingError::SceneStopped {
                    step: self.step_count(),
                    reason: reason.clone(),
                }
                .into());
            }
            let at = self.step_count();
            self.reload_through(at)?;
            match self.rebuilt.scene.step() {
                Ok(stop) => self.stopped = stop,
                Err(error) => return Err(RecordingError::StepFailed { step: at, error }.into()),
            }
            each(self.world())?;
        }
        Ok(())
    }

    /// Puts the world in a recorded full state (see [`restore_any`]), with the kinds as they
    /// were then: the reloads before that step are made first.
    pub fn restore(&mut self, state: &StateMsg) -> Result<(), String> {
        self.stopped = None;
        if self.reloads[..self.reloaded]
            .iter()
            .any(|(at, _, _)| *at >= state.step)
        {
            return Err(format!(
                "kinds were reloaded at or after step {}, so its state cannot be put back",
                state.step
            ));
        }
        self.reload_through(state.step.saturating_sub(1))
            .map_err(|e| e.to_string())?;
        restore_any(&mut self.rebuilt.scene.world, state)
    }

    /// Takes one more step, expecting it to fail (the recording ended with an error); returns the
    /// error, or `None` if the step succeeded.
    pub fn step_expecting_error(&mut self) -> Option<String> {
        if let Err(e) = self.reload_through(self.step_count()) {
            return Some(e.to_string());
        }
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
    /// Re-simulated from the recorded full state at step `keyframe` (restored exactly: its hash
    /// matched), every step's hash matching the recording on the way.
    Restored {
        /// The recorded full state the replay started from.
        keyframe: u64,
    },
    /// Re-simulated from step 0; every step's hash matched the recording, and the full state
    /// at the keyframe `keyframe` (if any) matched too.
    Resimulated {
        /// The nearest recorded full state before the step.
        keyframe: Option<u64>,
        /// Why the replay could not start from that state, if it tried.
        why_not_restored: Option<String>,
    },
}

/// Puts `world` in the recorded full state `s`: step count, generator, free slots and every
/// critter (walls are matched by id with the world's own). Fails, changing nothing that
/// matters, when the state lacks what a restore needs (recordings by older versions have no
/// generator state) or does not fit this world.
pub fn restore_any(world: &mut AnyWorld, s: &StateMsg) -> Result<(), String> {
    match world {
        AnyWorld::D2(w) => restore_world(w, s),
        AnyWorld::D3(w) => restore_world(w, s),
    }
}

fn restore_world<V: Vector>(w: &mut World<V>, s: &StateMsg) -> Result<(), String> {
    s.check()?;
    let rng: [u64; 4] = s
        .rng
        .as_deref()
        .and_then(|r| r.try_into().ok())
        .ok_or("the recorded state has no generator state (recorded by an older critterbox)")?;
    let free: Vec<CritterId> = s
        .free
        .as_ref()
        .ok_or("the recorded state has no free-slot list (recorded by an older critterbox)")?
        .iter()
        .map(|&k| id_of(k))
        .collect();
    if s.dim() != V::DIM {
        return Err(format!("a {}D state for a {}D world", s.dim(), V::DIM));
    }
    let kinds: Vec<Option<KindId>> = s.kinds.iter().map(|n| w.kinds().id(n).ok()).collect();
    let mut critters = Vec::with_capacity(s.len());
    let column = |c: &Option<super::schema::Floats>, i: usize| c.as_ref().map_or(0.0, |c| c.0[i]);
    for i in 0..s.len() {
        let kind = kinds
            .get(s.kind[i] as usize)
            .copied()
            .flatten()
            .ok_or_else(|| format!("kind '{}' is not known yet at step 0", s.kind_name(i)))?;
        let mut pos = V::zero();
        let mut vel = V::zero();
        for (axis, (p, v)) in [
            (s.x.0[i], s.vx.0[i]),
            (s.y.0[i], s.vy.0[i]),
            (column(&s.z, i), column(&s.vz, i)),
        ]
        .into_iter()
        .enumerate()
        .take(V::DIM)
        {
            pos.set(axis, p);
            vel.set(axis, v);
        }
        let id = id_of(s.id[i]);
        let (mass, fixed) = (s.mass.0[i], s.fixed[i]);
        critters.push(Critter {
            id,
            class: CLASS_UNSET,
            pos,
            vel,
            radius: s.radius.0[i],
            _align: [],
            fixed,
            alive: s.alive[i],
            wall: false,
            aside: false,
            traits: Arc::new(Traits {
                kind,
                mass,
                priority: s.priority.0[i],
                restitution: s.restitution.0[i],
                health: s.health.0[i],
                shape: Shape::Disk,
                props: s
                    .props
                    .get(&s.id[i].to_string())
                    .cloned()
                    .unwrap_or_default(),
                color: s.colors.get(&s.id[i].to_string()).cloned(),
            }),
        });
    }
    w.restore(s.step, rng, critters, &free)?;
    *w.vars_mut() = s.vars.clone();
    let impulses = s
        .contact_impulses
        .iter()
        .map(|&(a, b, j)| (id_of(a), id_of(b), j.0));
    w.set_contact_impulses(impulses)?;
    w.set_quiet_steps(
        s.quiet_steps
            .iter()
            .map(|&(id, q, island)| (id_of(id), q, island.map(id_of))),
    )
}

/// The exact state after `step` steps: from the file if it holds that state, else re-simulated
/// from the nearest recorded full state before it (or from step 0), checked against the
/// recorded hashes on the way.
pub fn state_at_step(
    rec: &Recording,
    step: u64,
) -> Result<(StateMsg, StateSource), RecordingError> {
    let last = rec.last_step();
    if step > last {
        return Err(RecordingError::NoStep { step, last });
    }
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
    // From the keyframe, if the world can be put back in it exactly.
    let mut why_not = None;
    if let Some(k) = key_state.as_ref().filter(|k| k.step > 0) {
        match from_keyframe(rec, k, step) {
            Ok(state) => {
                return Ok((state, StateSource::Restored { keyframe: k.step }));
            }
            Err(e) => why_not = Some(with_causes(&e)),
        }
    }
    let mut replay = Replay::new(rec)?;
    let check = |world: &AnyWorld| -> Result<(), RecordingError> {
        let s = world.step_count();
        check_hash(rec, world, step)?;
        if let Some(k) = &key_state {
            if k.step == s {
                let mine = capture::any_state(world);
                if let Some(difference) = first_difference(k, &mine, "recorded", "replayed") {
                    return Err(RecordingError::DiffersFromKeyframe {
                        step: s,
                        difference,
                    });
                }
            }
        }
        Ok(())
    };
    check(replay.world())?;
    replay.step_to(step, check)?;
    Ok((
        capture::any_state(replay.world()),
        StateSource::Resimulated {
            keyframe,
            why_not_restored: why_not,
        },
    ))
}

/// The recorded hash of the world's step, if there is one, equals the world's.
fn check_hash(rec: &Recording, world: &AnyWorld, target: u64) -> Result<(), RecordingError> {
    rec.check_state_hash()?;
    let s = world.step_count();
    if let Some(&recorded) = rec.hashes.get(&s) {
        let got = world.state_hash();
        if got != recorded {
            return Err(RecordingError::Diverged {
                step: s,
                got,
                recorded,
                shown: target,
            });
        }
    }
    Ok(())
}

/// Step `step`'s state, re-simulated from the recorded full state `key`.
fn from_keyframe(rec: &Recording, key: &StateMsg, step: u64) -> Result<StateMsg, RecordingError> {
    let mut replay = Replay::new(rec)?;
    replay
        .restore(key)
        .map_err(|reason| RecordingError::CannotRestore {
            step: key.step,
            reason,
        })?;
    let at = replay.world().step_count();
    if !rec.hashes.contains_key(&at) {
        return Err(RecordingError::NoHashToCheck { step: at });
    }
    check_hash(rec, replay.world(), step)
        .map_err(|e| RecordingError::RestoredDiffers(Box::new(e)))?;
    replay.step_to(step, |w| check_hash(rec, w, step))?;
    Ok(capture::any_state(replay.world()))
}
