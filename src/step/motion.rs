//! The move stage: gravity, straight-line motion over `h`, then the border (bounce, wrap or
//! clamp). Each critter moves on its own, so any split over threads gives the same bits.

use super::pairs::{ChunkCheck, MoveCheck, MoveReport};
use crate::critter::Critter;
use crate::parallel::{INPUT_CHUNK, PARALLEL_MIN};
use crate::prefetch::prefetch;
use crate::step::state::State;
use crate::vector::Vector;

/// How many slots ahead the move asks for the next critters to be loaded: the move streams
/// through every record and would otherwise wait on each one.
const MOVE_AHEAD: usize = 32;

/// Moves every live, awake critter by `h`. `still` marks sleepers by slot (empty when none
/// sleeps): they stay where they are, unpulled. Each chunk of slots also runs the pairs stage's
/// `check` on its critters while they are in cache.
pub(crate) fn run<V: Vector>(
    state: &mut State<V>,
    h: f64,
    still: &[bool],
    check: &MoveCheck<'_, V>,
) -> MoveReport {
    run_watching::<V, false>(state, h, still, check).0
}

/// A critter that moved farther than its radius: its slot and how far it moved.
pub(crate) type Far = Option<(usize, f64)>;

/// [`run`], and with `WATCH` the lowest slot of a critter that moved farther than its radius
/// (so it may have passed through a wall or a critter) and how far: a comparison per critter
/// on what the move computes anyway, and none without `WATCH`.
pub(crate) fn run_watching<V: Vector, const WATCH: bool>(
    state: &mut State<V>,
    h: f64,
    still: &[bool],
    check: &MoveCheck<'_, V>,
) -> (MoveReport, Far) {
    let (g, topo) = (state.gravity, state.topo);
    let dv = g * h;
    // The squared distance moved when farther than the radius, else 0.
    let step = move |i: usize, c: &mut Critter<V>| -> f64 {
        if !c.in_play() || c.is_wall() || still.get(i).copied().unwrap_or(false) {
            return 0.0;
        }
        if !c.fixed {
            c.vel += dv;
        }
        let shift = c.vel * h;
        let far = if WATCH && shift.length_squared() > c.radius * c.radius {
            shift.length_squared()
        } else {
            0.0
        };
        let moved = c.pos + shift;
        // Restitution (in the critter's traits) is read only at an edge.
        if topo.clear_of_edges(moved, c.radius) {
            c.pos = moved;
        } else {
            (c.pos, c.vel) = topo.apply_at_edges(moved, c.vel, c.radius, c.restitution());
        }
        far
    };
    use rayon::prelude::*;
    let parallel = state.critters.len() >= PARALLEL_MIN;
    let slots = state.critters.slots_mut_moving();
    let pass = |(k, chunk): (usize, &mut [Option<Critter<V>>])| {
        let mut seen = check.chunk(chunk.len(), &topo);
        let mut far = None;
        for j in 0..chunk.len() {
            prefetch(chunk.get(j + MOVE_AHEAD));
            let i = k * INPUT_CHUNK + j;
            match &mut chunk[j] {
                None => seen.empty(i),
                Some(c) => {
                    let d2 = step(i, c);
                    if d2 > 0.0 && far.is_none() {
                        far = Some((i, d2.sqrt()));
                    }
                    seen.moved(i, c);
                }
            }
        }
        (seen, far)
    };
    // Below `PARALLEL_MIN` critters the chunks are taken in turn on this thread.
    let chunks: Vec<(ChunkCheck<'_, V>, Far)> = if parallel {
        slots
            .par_chunks_mut(INPUT_CHUNK)
            .enumerate()
            .map(pass)
            .collect()
    } else {
        slots
            .chunks_mut(INPUT_CHUNK)
            .enumerate()
            .map(pass)
            .collect()
    };
    let far = chunks.iter().find_map(|c| c.1);
    let chunks: Vec<ChunkCheck<'_, V>> = chunks.into_iter().map(|c| c.0).collect();
    (MoveCheck::report(chunks), far)
}
