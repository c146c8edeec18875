//! The bit-exact, cycle-accurate reference of the neighbour pipeline
//! (`NeighbourPipeline<P>`, docs/pipeline.md "The neighbour pipeline"), and its functional
//! reference over the raw stores ([`evaluate_stored`]).
//!
//! The board's search puts **the candidates of one scan point in the lanes**: scan points go
//! through one at a time, each looks up the nine rows of its own 27-cell neighbourhood (a *slot* of two
//! rows, A and B, a clock, from two copies of the cell table) and sends the slot's two
//! stored ranges through two sets of `P` lanes **in the same clocks**, `P` consecutive
//! addresses of range A through the A lanes and of range B through the B lanes a clock (a
//! *chunk* each), the model RAM held twice (one copy a set) and banked `P` ways by address
//! so that any `P` consecutive addresses are one read of each bank. A slot costs
//! `max(ceil(len_a / P), ceil(len_b / P))` clocks. The last slot holds the centre row alone
//! (the row most likely to be long) and splits it: the A lanes take its even chunks, the B
//! lanes its odd ones, `ceil(len / 2P)` clocks. The B lanes use no DSP48A1: a difference
//! of `2^10` or more along an axis gives a capped key anyway, so they square 10-bit
//! magnitudes from block-RAM tables ([`B_SQUARE_LIMIT`]). A pipelined min-tree reduces a
//! chunk pair to one `(d2, index)`, an accumulator the chunks of a point.
//!
//! **Rule** ([`evaluate_stored`]). For a transformed scan point `q`: the candidates are the
//! addresses of the nine row ranges of [`crate::search::grid::Grid::ranges`], read from the stored
//! table (`first[(z, y, x0)] .. first[(z, y, x1) + 1]`, 13-bit entries, a range empty unless
//! its start is below its end, addresses modulo 4,096); the result is the lexicographic
//! minimum of `(CAP_D2, 0)` and of every candidate's `(d2, address & 0xfff)`. The order the
//! rows and chunks are visited in therefore does not matter (the lanes need no order). With
//! a table built by [`Grid::build`] the ranges are disjoint, increasing and inside the model,
//! so this is the nearest stored point with the lowest index on ties, capped: exactly
//! [`crate::search::grid::nearest_capped`] (capped ⇔ `nn_dist == CAP_D2`, index 0), i.e.
//! [`crate::search::grid::evaluate_grid`], whatever `P`. On a table that does not describe
//! the model it differs from "the first strictly smaller distance in visiting order" only
//! where a range wraps past 4,095 or the ranges overlap or go backwards: then the lowest
//! index still wins a tie.
//!
//! [`NeighbourPipelineModel::step`] is one rising edge: it takes the input ports
//! ([`GridInputs`]) as they are before the edge and updates every register as the RTL does;
//! [`NeighbourPipelineModel::outputs`] gives the output ports
//! ([`Outputs`](crate::search::pipeline::Outputs), with
//! [`Outputs::nn_point`](crate::search::pipeline::Outputs::nn_point): each result's
//! transformed scan point, registered with it) after the edge. The co-simulation compares
//! them with the Verilated RTL on every clock.
//!
//! This file holds the ports, the constants and the functional reference; the cycle model
//! is `neighbour_pipeline/model.rs`, the clock counts and bounds `neighbour_pipeline/clocks.rs`.

use crate::common::format::{dist2, pack_point, transform, unpack_point, FxPoint, FxPose, MAX_POINTS};
use crate::search::grid::{axis_cell, Grid, CAP_D2, CELLS, CELLS_PER_AXIS};
use crate::search::pipeline::{Evaluation, COST_MASK};

mod clocks;
mod model;

pub use clocks::*;
pub use model::NeighbourPipelineModel;

/// Depth of the queue of transformed scan points waiting for their row lookups.
pub const POINT_QUEUE: usize = 4;
/// Depth of the queue of looked-up row pairs waiting for the chunk issue.
pub const RANGE_QUEUE: usize = 4;
/// The lookup slots: the rows (`(dz + 1) * 3 + (dy + 1)`) each slot reads, two a clock (the
/// table's two copies); the centre row, the one most likely to hold points, comes last so
/// that a point's last slot seldom finds nothing (which costs a marker chunk).
pub const SLOTS: [(usize, Option<usize>); 5] = [(0, Some(1)), (2, Some(3)), (5, Some(6)), (7, Some(8)), (4, None)];
/// The most lanes a side (A or B) has.
pub const MAX_LANES: usize = 16;
/// Levels of the min-tree (registered each), whatever `P`: each side's lanes are padded to
/// [`MAX_LANES`] with the neutral key, four levels reduce each side, the fifth takes the
/// smaller of the two sides.
pub const TREE_LEVELS: usize = 5;
/// Leaves of the min-tree: the A lanes' [`MAX_LANES`], then the B lanes'.
pub const TREE_LEAVES: usize = 1 << TREE_LEVELS;
/// Edges from a chunk pair's issue to its result leaving the accumulator: bank read,
/// difference, square, two sums, clamp, the tree's levels, accumulate.
pub const CHUNK_LATENCY: usize = 7 + TREE_LEVELS;
/// A B lane's squares are exact only below this magnitude (`h`, the cell width): a
/// difference of `2^10` or more along any axis gives a distance of at least
/// `CAP_D2 = 2^20`, the capped key whatever the other axes, so the B lanes square 10-bit
/// magnitudes only (a block-RAM table of `x^2 >> 2`, no DSP).
pub const B_SQUARE_LIMIT: i64 = 1 << 10;

/// A `(d2, index)` pair as one lexicographic key: `d2 << 12 | index` (`d2 <= CAP_D2`).
fn key(d2: u64, index: u16) -> u64 {
    (d2 << 12) | index as u64
}

/// The neutral key: the capped result.
const CAP_KEY: u64 = CAP_D2 << 12;

/// Input ports (before an edge): the write ports of the grid's stores (the model RAM and the
/// cell table), `start` with the pose, and the scan stream.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GridInputs {
    /// Write `model_wdata` at `model_waddr` (the model sorted by cell, [`Grid::points`]).
    pub model_we: bool,
    /// Model write address (12 bits).
    pub model_waddr: u16,
    /// Model write data (48 bits, [`pack_point`]).
    pub model_wdata: u64,
    /// Write `table_wdata` as cell-table entry `table_waddr` ([`Grid::first`]).
    pub table_we: bool,
    /// Cell-table entry, `0..=4096` (13 bits; larger values write nothing).
    pub table_waddr: u16,
    /// The entry (13 bits).
    pub table_wdata: u16,
    /// Begin a particle (when idle).
    pub start: bool,
    /// The pose, sampled with `start`.
    pub pose: FxPose,
    /// A scan point is offered.
    pub scan_valid: bool,
    /// The offered point (48 bits).
    pub scan_data: u64,
    /// The offered point is the last.
    pub scan_last: bool,
}

impl GridInputs {
    /// Begin a particle with `pose`.
    pub fn start(pose: &FxPose) -> GridInputs {
        GridInputs { start: true, pose: *pose, ..Default::default() }
    }

    /// If `offer`, offer scan point `next` of `scan` (`scan_last` on the last one);
    /// otherwise nothing.
    pub fn offer(scan: &[FxPoint], next: usize, offer: bool) -> GridInputs {
        GridInputs {
            scan_valid: offer,
            scan_data: if offer { pack_point(scan[next]) } else { 0 },
            scan_last: offer && next + 1 == scan.len(),
            ..Default::default()
        }
    }
}

/// The input words that upload `grid` (model words, then the 4,097 table entries), one a
/// clock, as the co-simulation and the benches drive them.
pub fn upload(grid: &Grid) -> Vec<GridInputs> {
    let mut v: Vec<GridInputs> = grid
        .points
        .iter()
        .enumerate()
        .map(|(a, &p)| GridInputs {
            model_we: true,
            model_waddr: a as u16,
            model_wdata: pack_point(p),
            ..Default::default()
        })
        .collect();
    v.extend(grid.first.iter().enumerate().map(|(a, &f)| GridInputs {
        table_we: true,
        table_waddr: a as u16,
        table_wdata: f,
        ..Default::default()
    }));
    v
}

/// The functional reference over the board's raw stores, whatever they hold (the module
/// doc's rule): the model RAM (`ram`, [`MAX_POINTS`] packed words) and the cell table as
/// written (`first`, the [`CELLS`]` + 1` entries of 13 bits). Each transformed scan point's
/// lexicographic minimum `(d2, address & 0xfff)` over its nine row ranges, starting at
/// `(CAP_D2, 0)`; the cost the sum of the distances. Independent of the lane count. With a
/// table built by [`Grid::build`] this is [`crate::search::grid::evaluate_grid`].
pub fn evaluate_stored(ram: &[u64], first: &[u16], scan: &[FxPoint], pose: &FxPose) -> Evaluation {
    assert!(ram.len() == MAX_POINTS && first.len() == CELLS + 1);
    let n = CELLS_PER_AXIS as i32;
    let nearest: Vec<(u16, u64)> = scan
        .iter()
        .map(|&p| {
            let q = transform(pose, p);
            let k = q.map(axis_cell);
            let mut best = CAP_KEY;
            let (x0, x1) = ((k[0] - 1).max(0), (k[0] + 1).min(n - 1));
            for dz in -1..=1 {
                for dy in -1..=1 {
                    let (y, z) = (k[1] + dy, k[2] + dz);
                    if !(0..n).contains(&y) || !(0..n).contains(&z) || x0 > x1 {
                        continue;
                    }
                    let row = ((z * n + y) * n) as usize;
                    let (lo, hi) = (first[row + x0 as usize] & 0x1fff, first[row + x1 as usize + 1] & 0x1fff);
                    for a in lo..hi {
                        let d = dist2(q, unpack_point(ram[a as usize % MAX_POINTS]));
                        if d < CAP_D2 {
                            best = best.min(key(d, a & 0xfff));
                        }
                    }
                }
            }
            ((best & 0xfff) as u16, best >> 12)
        })
        .collect();
    let cost = nearest.iter().fold(0u64, |c, n| (c + n.1) & COST_MASK);
    Evaluation { cost, nearest }
}
