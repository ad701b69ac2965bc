//! Collision methods: how a step finds and resolves collisions, from cheapest to exact.
//!
//! * [`Method::Discrete`]: Pop's move, find overlaps, respond, separate (`World::step`'s stages).
//! * [`Method::Substep`]: the same with `n` substeps of `dt / n` (update hooks once per step).
//! * [`Method::Swept`]: continuous collision detection within the step (`swept`): times of
//!   impact resolved in time order, then a discrete pass for resting contacts. No tunnelling.
//! * [`Method::Event`]: exact event-driven dynamics (`event`): parabolic flights under gravity,
//!   collisions, wall hits, border and cell crossings processed in time order.
//! * [`Method::Solve`]: the discrete step with its contacts solved together ([`solve`]): `n`
//!   sweeps of sequential impulses over every contact, then a partial position correction, so
//!   piles and stacks come to rest; under gravity, islands at rest then sleep ([`sleep`]).
//! * [`Method::Auto`]: per step, `solve:8` (with more sweeps for deep piles) under gravity,
//!   `event` without it, `discrete` for a slow step whose flight something outside it keeps
//!   changing, and `swept` for a step under gravity too fast for solved substeps ([`auto`]).
//!   Under gravity it chooses per island ([`islands`]): islands of impacts in flight (a cradle
//!   struck in mid-air) take `event` while the islands at rest are solved, both in one step
//!   ([`mixed`]).
//!
//! Every method keeps Pop's roles: a touching pair is handed to the caller's `collide` hook.
//! `flight` is the event engine `swept` and `event` share; [`toi`] holds the time-of-impact
//! formulas.

pub(crate) mod aside;
pub mod auto;
pub mod bullets;
pub(crate) mod discrete;
pub(crate) mod event;
pub(crate) mod flight;
pub mod islands;
pub(crate) mod method_state;
pub mod mixed;
mod queue;
pub mod sleep;
pub mod solve;
pub(crate) mod swept;
pub mod toi;

pub use flight::FLIGHT_STEPS;

use std::fmt;
use std::str::FromStr;

/// How a world's step finds and resolves collisions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// Pop's step: move, detect overlaps, respond, separate.
    #[default]
    Discrete,
    /// Discrete with `n` substeps per step (n >= 1).
    Substep(u32),
    /// Continuous collision detection within each step.
    Swept,
    /// Exact event-driven dynamics.
    Event,
    /// Discrete with the contacts solved together by `n` sweeps of sequential impulses (n >= 1).
    Solve(u32),
    /// The cheapest method that keeps the tolerances, chosen each step and per critter.
    Auto,
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Method::Discrete => write!(f, "discrete"),
            Method::Substep(n) => write!(f, "substep:{n}"),
            Method::Swept => write!(f, "swept"),
            Method::Event => write!(f, "event"),
            Method::Solve(n) => write!(f, "solve:{n}"),
            Method::Auto => write!(f, "auto"),
        }
    }
}

/// Largest sweep count of `solve` accepted.
pub const MAX_SWEEPS: u32 = 10_000;

/// Largest substep count accepted (a guard against typos like `substep:1000000000`).
pub const MAX_SUBSTEPS: u32 = 100_000;

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        let usage = "use discrete, substep:N, swept, event, solve:N or auto";
        if let Some(n) = s
            .strip_prefix("solve:")
            .or_else(|| s.strip_prefix("solve(").and_then(|r| r.strip_suffix(')')))
        {
            return match n.trim().parse::<u32>() {
                Ok(n) if (1..=MAX_SWEEPS).contains(&n) => Ok(Method::Solve(n)),
                _ => Err(format!(
                    "method '{s}': the sweep count must be a whole number from 1 to {MAX_SWEEPS}"
                )),
            };
        }
        match s {
            "discrete" => Ok(Method::Discrete),
            "solve" => Ok(Method::Solve(solve::DEFAULT_SWEEPS)),
            "swept" => Ok(Method::Swept),
            "event" => Ok(Method::Event),
            "auto" => Ok(Method::Auto),
            _ => {
                let n = s
                    .strip_prefix("substep:")
                    .or_else(|| s.strip_prefix("substep(").and_then(|r| r.strip_suffix(')')))
                    .ok_or_else(|| format!("unknown method '{s}': {usage}"))?;
                match n.trim().parse::<u32>() {
                    Ok(n) if (1..=MAX_SUBSTEPS).contains(&n) => Ok(Method::Substep(n)),
                    _ => Err(format!(
                        "method '{s}': the substep count must be a whole number from 1 to {MAX_SUBSTEPS}"
                    )),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn methods_parse_and_print_round_trip() {
        for m in [
            Method::Discrete,
            Method::Substep(4),
            Method::Swept,
            Method::Event,
            Method::Solve(8),
            Method::Auto,
        ] {
            assert_eq!(m.to_string().parse::<Method>(), Ok(m));
        }
        assert_eq!("substep(3)".parse::<Method>(), Ok(Method::Substep(3)));
        assert_eq!("solve(3)".parse::<Method>(), Ok(Method::Solve(3)));
        assert_eq!(
            "solve".parse::<Method>(),
            Ok(Method::Solve(solve::DEFAULT_SWEEPS))
        );
        assert!("solve:0".parse::<Method>().is_err());
        assert!("substep:0".parse::<Method>().is_err());
        assert!("substep:x".parse::<Method>().is_err());
        assert!("fast".parse::<Method>().is_err());
    }
}
