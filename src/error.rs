//! The library's errors. Each names what is wrong, where, and what to do.

use crate::ids::CritterId;

/// Everything that can go wrong in the library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A critter's field is out of range.
    #[error("{critter}: {field} = {value}: {reason}")]
    InvalidCritter {
        /// Which critter ("critter #3", or "the ball spawned at (1, 2)").
        critter: String,
        /// The field.
        field: &'static str,
        /// The bad value.
        value: String,
        /// What is wrong and what would be right.
        reason: String,
    },
    /// A wall's geometry is out of range.
    #[error("wall {field} = {value}: {reason}")]
    InvalidWall {
        /// The field.
        field: &'static str,
        /// The bad value.
        value: String,
        /// What is wrong.
        reason: String,
    },
    /// A critter would start inside a wall.
    #[error("{critter} overlaps wall {wall} by {depth:.3}: move it out of the wall (its centre must be at least its radius from every wall)")]
    SpawnInsideWall {
        /// Which critter.
        critter: String,
        /// The wall.
        wall: CritterId,
        /// How deep it overlaps.
        depth: f64,
    },
    /// A critter's radius is out of range, or the critter cannot fit in the world box or
    /// between its walls.
    #[error("{critter}: radius {radius} {reason}")]
    InvalidRadius {
        /// Which critter.
        critter: String,
        /// The radius, as the user wrote it.
        radius: String,
        /// What is wrong and what to do.
        reason: String,
    },
    /// A wall would be added through a live critter.
    #[error("{wall} overlaps {critter} by {depth:.3}: move the wall or the critter (every critter's centre must be at least its radius from every wall)")]
    WallThroughCritter {
        /// The wall ("the wall from (0, 0) to (1, 10)").
        wall: String,
        /// Which critter ("critter #3 (ball at (1, 2), radius 0.5)").
        critter: String,
        /// How deep they overlap.
        depth: f64,
    },
    /// An exact method (`event`, `swept`, `auto`) could not finish a step: its events did not
    /// run out (an endless sequence of collisions), and moving the critters on without them
    /// would leave the run silently wrong.
    #[error("step {step}: the {method} step gave up after {events} events, {at:.3e} into a step of {dt:e}, on {pair}: the collisions do not run out in this step (an endless sequence, or a step far longer than the time between them); take a shorter --dt, or a method that is not exact (--method solve:8 for critters at rest, substep:N)")]
    EndlessEvents {
        /// The step (counted from 0, as errors count steps).
        step: u64,
        /// The method that gave up.
        method: &'static str,
        /// The events processed in the step before it gave up.
        events: u64,
        /// The time into the step where it gave up.
        at: f64,
        /// The step's length.
        dt: f64,
        /// The event it gave up on ("ball 3v0 and wall 17v0").
        pair: String,
    },
    /// The world's settings are out of range.
    #[error("world {field} = {value}: {reason}")]
    InvalidWorld {
        /// The field.
        field: &'static str,
        /// The bad value.
        value: String,
        /// What is wrong.
        reason: String,
    },
    /// A kind definition is out of range.
    #[error("kind '{kind}': {reason}")]
    InvalidKind {
        /// The kind.
        kind: String,
        /// What is wrong.
        reason: String,
    },
    /// No kind of that name.
    #[error("unknown kind '{kind}' (known kinds: {known})")]
    UnknownKind {
        /// The name asked for.
        kind: String,
        /// The names that exist.
        known: String,
    },
    /// No critter with that id (it died, or never was).
    #[error("no live critter {0}")]
    NoSuchCritter(CritterId),
    /// No built-in scene of that name.
    #[error(
        "unknown scene '{name}' (built-in scenes: {known}; `critterbox run --list` describes them)"
    )]
    UnknownScene {
        /// The name asked for.
        name: String,
        /// The names that exist.
        known: String,
    },
    /// A script failed to compile, load or run.
    #[error("{0}")]
    Script(Box<ScriptError>),
    /// A kind's hook failed.
    #[error("step {step}: kind '{kind}', critter {critter}: {message}")]
    Hook {
        /// The kind whose hook failed.
        kind: String,
        /// The critter it ran for.
        critter: CritterId,
        /// The step.
        step: u64,
        /// What went wrong.
        message: String,
    },
}

/// A script error, located: file, line and column, and which kind, critter and step it ran for.
#[derive(Debug, Clone, PartialEq)]
pub struct ScriptError {
    /// The script file.
    pub file: String,
    /// Line (1-based), when known.
    pub line: Option<usize>,
    /// Column (1-based), when known.
    pub column: Option<usize>,
    /// The kind whose hook ran.
    pub kind: Option<String>,
    /// The hook or function that was running (`collide`, `update`, `on_step`, ...).
    pub hook: Option<String>,
    /// The critter the hook ran for.
    pub critter: Option<CritterId>,
    /// The step.
    pub step: Option<u64>,
    /// What went wrong.
    pub message: String,
    /// What to do about it.
    pub hint: Option<String>,
}

impl ScriptError {
    /// An error in `file` with `message`, location unknown.
    pub fn new(file: impl Into<String>, message: impl Into<String>) -> Self {
        ScriptError {
            file: file.into(),
            line: None,
            column: None,
            kind: None,
            hook: None,
            critter: None,
            step: None,
            message: message.into(),
            hint: None,
        }
    }
}

impl std::fmt::Display for ScriptError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        write!(f, ": {}", self.message)?;
        let mut context = Vec::new();
        if let Some(kind) = &self.kind {
            context.push(format!("kind '{kind}'"));
        }
        if let Some(hook) = &self.hook {
            context.push(format!("in {hook}"));
        }
        if let Some(c) = self.critter {
            context.push(format!("critter {c}"));
        }
        if let Some(step) = self.step {
            context.push(format!("step {step}"));
        }
        if !context.is_empty() {
            write!(f, " ({})", context.join(", "))?;
        }
        if let Some(hint) = &self.hint {
            write!(f, "\n  hint: {hint}")?;
        }
        Ok(())
    }
}

impl From<ScriptError> for Error {
    fn from(e: ScriptError) -> Self {
        Error::Script(Box::new(e))
    }
}
