//! When a pass over the critters or their pairs runs on all cores. Every such pass is cut into
//! fixed chunks joined in order, so its result does not depend on the number of threads.

/// Worlds with at least this many critters run the stages that allow it on all cores.
pub const PARALLEL_MIN: usize = 20_000;

/// Slots (or pairs) per chunk of the parallel passes: large enough to amortise a task, small
/// enough to stay in cache.
pub(crate) const INPUT_CHUNK: usize = 4096;

/// Steps with at least this many candidate pairs ask the rules and test the pairs in parallel
/// chunks when there is more than one thread (on one thread the chunks would only cost copies).
pub(crate) const PARALLEL_PAIRS: usize = 2 * INPUT_CHUNK;
