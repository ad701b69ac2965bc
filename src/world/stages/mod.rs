//! The stages of a step, each in a file named after it: `update`, then (as the collision
//! method runs them) `motion`, `pairs` and `response`, then `lifecycle`.

pub(crate) mod lifecycle;
pub(crate) mod motion;
pub(crate) mod pairs;
pub(crate) mod response;
pub(crate) mod update;
