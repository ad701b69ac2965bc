//! What the hooks queue for the end of the step (deaths, spawns, the damage whose `on_damage`
//! is still to run), how a spawn is placed when it overlaps something, and where a script
//! asked for it.

use super::events::{DeathCause, HookAt};
use crate::critter::{CritterId, CritterSpec};
use crate::error::{Error, ScriptError};
use crate::vector::Vector;

/// Spawns and deaths waiting for the end of the step, and damage waiting for its `on_damage`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Pending<V: Vector> {
    pub spawns: Vec<PendingSpawn<V>>,
    pub deaths: Vec<CritterId>,
    /// Why each of `deaths` died, one per entry.
    pub death_causes: Vec<DeathCause>,
    /// Damage dealt whose `on_damage` has not run yet (only while some kind has the hook).
    pub damages: Vec<PendingDamage>,
}

/// A damage whose `on_damage` hook is still to run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PendingDamage {
    /// The critter damaged.
    pub id: CritterId,
    pub amount: f64,
    /// The critter whose hook did it (`None`: the scene or a test).
    pub source: Option<CritterId>,
}

/// A spawn queued by a hook: what to add, how to place it, and where it was asked for.
#[derive(Clone, Debug)]
pub(crate) struct PendingSpawn<V: Vector> {
    pub spec: CritterSpec<V>,
    pub on_overlap: OnOverlap,
    /// `None` for a spawn from Rust (`Access::spawn`).
    pub origin: Option<Box<SpawnOrigin>>,
    /// The hook that asked for it (`None`: none was running).
    pub by: Option<HookAt>,
}

/// Where a queued spawn was asked for, so that its failure at the end of the step names the
/// script's file:line:col, the hook's kind, the hook, the critter and the step.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct SpawnOrigin {
    pub file: String,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub kind: Option<String>,
    pub hook: Option<String>,
    pub critter: Option<CritterId>,
    pub step: u64,
}

impl SpawnOrigin {
    /// `file:line:col` of the `spawn` call.
    pub fn place(&self) -> String {
        match (self.line, self.column) {
            (Some(l), Some(c)) => format!("{}:{l}:{c}", self.file),
            (Some(l), None) => format!("{}:{l}", self.file),
            _ => self.file.clone(),
        }
    }

    /// `e`, the failure of the spawn asked for here, located at the `spawn` call.
    pub fn locate(&self, e: Error) -> Error {
        let inside_wall = matches!(e, Error::SpawnInsideWall { .. });
        let message = match e {
            Error::Script(s) => s.message,
            other => other.to_string(),
        };
        let mut err = ScriptError::new(&self.file, format!("spawn failed: {message}"));
        err.line = self.line;
        err.column = self.column;
        err.kind = self.kind.clone();
        err.hook = self.hook.clone();
        err.critter = self.critter;
        err.step = Some(self.step);
        if inside_wall {
            err.hint = Some(
                "add on_overlap: \"push\" (moved out) or \"skip\" (not added) to the spawn map"
                    .into(),
            );
        }
        Error::from(err)
    }
}

/// What a spawn does when the new critter would overlap a wall or another critter.
///
/// A critter *reaches into* a wall when the wall's contact with it is deeper than the rounding
/// margin, and *overlaps* a live critter when their disks overlap by more than that margin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum OnOverlap {
    /// Reaching into a wall is an error (the spawn checks as it always did); overlapping
    /// critters is allowed, as the response separates them.
    Error,
    /// Not added if it reaches into a wall or overlaps a critter.
    Skip,
    /// Moved out of what it reaches into, deepest first, along each contact normal (at most
    /// [`MAX_PUSHES`](super::spawn::MAX_PUSHES) moves, kept inside the world box); not added if it still overlaps then.
    Push,
}

impl OnOverlap {
    /// The policy named `name` (`"error"`, `"skip"`, `"push"`).
    pub fn parse(name: &str) -> Option<OnOverlap> {
        match name {
            "error" => Some(OnOverlap::Error),
            "skip" => Some(OnOverlap::Skip),
            "push" => Some(OnOverlap::Push),
            _ => None,
        }
    }
}
