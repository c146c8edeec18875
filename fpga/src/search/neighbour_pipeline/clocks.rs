//! What a particle takes on the neighbour pipeline: clocks, chunks and distances counted on
//! the cycle model, per point ([`chunks_of`], [`lookups_of`]), and the host's bound
//! ([`clocks_bound`]).

use super::{upload, GridInputs, NeighbourPipelineModel, SLOTS};
use crate::common::format::{FxPoint, FxPose};
use crate::search::grid::{axis_cell, Grid};
use crate::search::pipeline::{stream_particle, Evaluation};

/// What one particle took: the results, clocks from `start` to `cost_valid`, chunks issued
/// and distances computed in lanes holding a candidate.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NeighbourRun {
    /// Results and cost.
    pub evaluation: Evaluation,
    /// Clocks from the `start` edge to the `cost_valid` edge.
    pub clocks: u64,
    /// Chunks issued (marker chunks included).
    pub chunks: u64,
    /// Distances computed in lanes holding a candidate.
    pub distances: u64,
}

/// Drive a [`NeighbourPipelineModel`] (its model and table already written) through one
/// particle, offering a scan point on clocks where `gap(clock)` is false.
pub fn run_particle(
    pipe: &mut NeighbourPipelineModel,
    scan: &[FxPoint],
    pose: &FxPose,
    gap: impl FnMut(u64) -> bool,
) -> NeighbourRun {
    assert!(!scan.is_empty());
    let (chunks0, distances0) = (pipe.chunks(), pipe.distances());
    pipe.step(&GridInputs::start(pose));
    let (evaluation, clocks) = stream_particle(pipe, scan, gap);
    NeighbourRun { evaluation, clocks, chunks: pipe.chunks() - chunks0, distances: pipe.distances() - distances0 }
}

/// Clocks, chunks and distances of one particle with no gaps in the scan stream, counted on
/// the cycle model: `grid` uploaded, then one particle.
pub fn clocks_per_particle(grid: &Grid, scan: &[FxPoint], pose: &FxPose, lanes: usize) -> NeighbourRun {
    let mut pipe = NeighbourPipelineModel::new(lanes);
    for w in upload(grid) {
        pipe.step(&w);
    }
    run_particle(&mut pipe, scan, pose, |_| false)
}

/// The issue clocks a point's rows take (a lower bound of what it needs): over its slots
/// ([`SLOTS`]), `max(ceil(len_a / P), ceil(len_b / P))` (the slot's rows A and B go through
/// the A and B lanes in the same clocks; a row outside the grid or empty counts 0), and
/// `ceil(len / 2P)` for the last slot's centre row, split over both sides; summed; at least
/// one (a point whose last slot finds no range takes a marker chunk).
pub fn chunks_of(grid: &Grid, q: FxPoint, lanes: usize) -> usize {
    let k = q.map(axis_cell);
    let len = |(inside, lo, hi): (bool, usize, usize)| {
        if inside {
            (grid.first[hi + 1] as usize).saturating_sub(grid.first[lo] as usize)
        } else {
            0
        }
    };
    (0..SLOTS.len())
        .map(|s| {
            let per_chunk = if s == SLOTS.len() - 1 { 2 * lanes } else { lanes };
            NeighbourPipelineModel::slot_rows(k, s).map(|r| len(r).div_ceil(per_chunk)).into_iter().max().unwrap_or(0)
        })
        .sum::<usize>()
        .max(1)
}

/// Lookup clocks a point takes: its slots with a row inside the grid, and the last slot
/// (always looked up).
pub fn lookups_of(q: FxPoint) -> usize {
    let k = q.map(axis_cell);
    (0..SLOTS.len() - 1).filter(|&s| NeighbourPipelineModel::slot_rows(k, s).iter().any(|r| r.0)).count() + 1
}

/// Clocks a scan point may take beyond its chunks in [`clocks_bound`]: its five lookups,
/// the lookup's read and queue registers, and its marker chunk.
pub const BOUND_POINT_EXTRA: u64 = SLOTS.len() as u64 + 4 + 1;

/// Clocks of fill and drain in [`clocks_bound`]: the transform, the lookup, the chunk's
/// [`CHUNK_LATENCY`](super::CHUNK_LATENCY) and the cost, with room to spare.
pub const BOUND_FILL: u64 = 64;

/// An upper bound of [`clocks_per_particle`]'s count (start edge to `cost_valid` edge, no
/// gaps in the scan stream) for `scan_points` scan points under any pose, over any model of
/// `model_points` points uploaded as [`Grid::build`] stores it, on `lanes` lanes; for the
/// host's deadlines, where the data-dependent count is not worth running the cycle model.
///
/// A point's nine row ranges are disjoint ranges of the stored model, so its chunk pairs
/// (a slot costs its longer row, [`chunks_of`]) are at most its rows' chunks,
/// `sum over rows of ceil(len / P) <= ceil(model_points / P) + 9`; on top come its
/// lookups and their registers and a marker ([`BOUND_POINT_EXTRA`]), as if nothing of one
/// point overlapped the next, and [`BOUND_FILL`] once. `fpga/tests/neighbour_pipeline.rs`
/// checks it against the cycle model on dense, sparse and empty neighbourhoods.
pub fn clocks_bound(scan_points: usize, model_points: usize, lanes: usize) -> u64 {
    let lanes = lanes.max(1) as u64;
    let per_point = (model_points as u64).div_ceil(lanes) + 9 + BOUND_POINT_EXTRA;
    1 + scan_points as u64 * per_point + BOUND_FILL
}
