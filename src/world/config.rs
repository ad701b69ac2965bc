//! The settings a world is made with, and their checks.

use crate::border::Border;
use crate::broad_phase::BroadPhaseMode;
use crate::error::Error;
use crate::method::Method;
use crate::step::span::check_dt;
use crate::vector::fmt_vec;
use crate::vector::Vector;

/// The settings a world is made with.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldConfig<V: Vector> {
    /// Lower corner of the world box.
    pub min: V,
    /// Upper corner of the world box.
    pub max: V,
    /// What the box's edge does.
    pub border: Border,
    /// Uniform acceleration on every free critter.
    pub gravity: V,
    /// Time step.
    pub dt: f64,
    /// Seed of the world's generator.
    pub seed: u64,
    /// Broad-phase algorithm.
    pub broad_phase: BroadPhaseMode,
    /// Collision method (see [`crate::method`]).
    pub method: Method,
    /// Whether critters at rest may sleep under `solve:n` ([`crate::method::sleep`]).
    pub sleep: bool,
}

impl<V: Vector> WorldConfig<V> {
    /// A box from `min` to `max`, bouncing border, no gravity, dt = 1/60, seed 0.
    pub fn new(min: V, max: V) -> Self {
        WorldConfig {
            min,
            max,
            border: Border::Bounce,
            gravity: V::zero(),
            dt: 1.0 / 60.0,
            seed: 0,
            broad_phase: BroadPhaseMode::Auto,
            method: Method::Discrete,
            sleep: true,
        }
    }
    /// With collision method `m`.
    pub fn method(mut self, m: Method) -> Self {
        self.method = m;
        self
    }
    /// With border `b`.
    pub fn border(mut self, b: Border) -> Self {
        self.border = b;
        self
    }
    /// With gravity `g`.
    pub fn gravity(mut self, g: V) -> Self {
        self.gravity = g;
        self
    }
    /// With time step `dt`.
    pub fn dt(mut self, dt: f64) -> Self {
        self.dt = dt;
        self
    }
    /// With seed `seed`.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
    /// With broad-phase algorithm `mode`.
    pub fn broad_phase(mut self, mode: BroadPhaseMode) -> Self {
        self.broad_phase = mode;
        self
    }
    /// With sleep under `solve:n` allowed (the default) or not.
    pub fn sleep(mut self, on: bool) -> Self {
        self.sleep = on;
        self
    }

    pub(crate) fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, value: String, reason: &str| {
            Err(Error::InvalidWorld {
                field,
                value,
                reason: reason.to_string(),
            })
        };
        if !self.min.all_finite() || !self.max.all_finite() {
            return bad(
                "box",
                format!("{} to {}", fmt_vec(self.min), fmt_vec(self.max)),
                "corners must be finite",
            );
        }
        for axis in 0..V::DIM {
            let positive = self.max.get(axis) > self.min.get(axis); // false for NaN too
            if !positive {
                return bad(
                    "size",
                    fmt_vec(self.max - self.min),
                    "the world box must have a positive size along every axis",
                );
            }
        }
        if !self.gravity.all_finite() {
            return bad("gravity", fmt_vec(self.gravity), "must be finite");
        }
        check_dt(self.dt)
    }
}
