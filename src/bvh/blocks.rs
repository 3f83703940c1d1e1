//! Parallel passes over large primitive sets, split into fixed blocks and merged in block order:
//! min/max with NaN operands is not associative, so a thread-count-dependent reduction tree could
//! change the result on non-finite input.

use rayon::prelude::*;

/// Primitives per parallel task: large enough to amortise the task, small enough to balance 2+ cores.
pub(super) const BLOCK: usize = 16 * 1024;

/// `merge(map(block 0), map(block 1), ...)` in block order; inline when there is a single block.
pub(super) fn map_merge<I: Sync, T: Send>(
    items: &[I],
    map: impl Fn(&[I]) -> T + Sync + Send,
    mut merge: impl FnMut(&mut T, &T),
) -> T {
    if items.len() <= BLOCK {
        return map(items);
    }
    let parts: Vec<T> = items.par_chunks(BLOCK).map(map).collect();
    let mut parts = parts.into_iter();
    let mut acc = parts.next().expect("at least two blocks");
    parts.for_each(|p| merge(&mut acc, &p));
    acc
}
