//! The one margin the engine allows for rounding.

/// A relative margin far above the rounding of a few operations on f64s (about 1e-16 each) and
/// far below any length or time a scene resolves: bounds that must hold whatever the rounding
/// (cells, shells, boxes, horizons) are widened by it, and a spawn may touch a wall by it.
pub(crate) const ROUNDING_MARGIN: f64 = 1e-9;
