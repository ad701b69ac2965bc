//! The step's layer: the state a step works on and the stages that change it, below both
//! [`crate::world`] (which builds and owns a world) and [`crate::method`] (which plans a step
//! and runs these stages in its own order).
//!
//! - [`state`]: what every stage and method reads and writes; [`span`]: the step's length,
//!   made once per step and passed down;
//! - the stages, each in a file named after it: `update`, `motion`, `pairs`, `response`,
//!   `touch`, `damage`, `lifecycle`;
//! - what the stages keep or queue: the neighbour grid (`neighbours`), the touching spells
//!   (`spells`), spawn steps (`births`), the step's events (`events`), the hooks' queued
//!   changes (`pending`) and how spawns are placed (`spawn`);
//! - [`access`]: what hooks and script functions may read and change;
//! - [`stats`]: the stages' timers and counts.

pub(crate) mod access;
pub(crate) mod births;
pub(crate) mod damage;
pub(crate) mod events;
pub(crate) mod lifecycle;
pub(crate) mod motion;
pub(crate) mod neighbours;
pub(crate) mod pairs;
pub(crate) mod pending;
pub(crate) mod response;
pub(crate) mod span;
pub(crate) mod spawn;
pub(crate) mod spells;
pub(crate) mod state;
pub(crate) mod stats;
pub(crate) mod touch;
pub(crate) mod update;
