//! The move stage: gravity, straight-line motion over `h`, then the border (bounce, wrap or
//! clamp). Each critter moves on its own, so any split over threads gives the same bits.

use super::pairs::{ChunkCheck, MoveCheck, MoveReport};
use crate::critter::Critter;
use crate::parallel::{INPUT_CHUNK, PARALLEL_MIN};
use crate::prefetch::prefetch;
use crate::vector::Vector;
use crate::world::state::State;

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
    let (g, topo) = (state.gravity, state.topo);
    let dv = g * h;
    let step = move |i: usize, c: &mut Critter<V>| {
        if !c.alive || c.is_wall() || still.get(i).copied().unwrap_or(false) {
            return;
        }
        if !c.fixed {
            c.vel += dv;
        }
        let moved = c.pos + c.vel * h;
        // Restitution (in the critter's traits) is read only at an edge.
        if topo.clear_of_edges(moved, c.radius) {
            c.pos = moved;
        } else {
            (c.pos, c.vel) = topo.apply_at_edges(moved, c.vel, c.radius, c.restitution());
        }
    };
    use rayon::prelude::*;
    let parallel = state.critters.len() >= PARALLEL_MIN;
    let slots = state.critters.slots_mut_moving();
    let pass = |(k, chunk): (usize, &mut [Option<Critter<V>>])| {
        let mut seen = check.chunk(chunk.len(), &topo);
        for j in 0..chunk.len() {
            prefetch(chunk.get(j + MOVE_AHEAD));
            let i = k * INPUT_CHUNK + j;
            match &mut chunk[j] {
                None => seen.empty(i),
                Some(c) => {
                    step(i, c);
                    seen.moved(i, c);
                }
            }
        }
        seen
    };
    // Below `PARALLEL_MIN` critters the chunks are taken in turn on this thread.
    let chunks: Vec<ChunkCheck<'_, V>> = if parallel {
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
    MoveCheck::report(chunks)
}
