//! The cycle-accurate reference of the residual stage `SurfaceResidual` (docs/pipeline.md,
//! "The surface residual"): it takes the neighbour pipeline's results in scan order, adds to
//! each the surface residual of [`crate::surface::residual`] (the point and normal of the
//! result's stored index from two stores, copies of the model RAM and its normals), and sums
//! the residuals into a particle cost.
//!
//! **Timing.** Every input edge is a slot: the result (`in_valid`, `in_index`, `in_dist`,
//! `in_point`) and `in_cost_valid` presented before an edge come out [`SURFACE_LATENCY`]
//! edges later, whatever the valid bits say (the outputs pass the pipeline's registers
//! through: with `nn_valid` low, `nn_index`, `nn_dist` and `nn_resid` are those of whatever
//! was on the inputs). A result may arrive on every clock; no backpressure.
//!
//! **Stores.** Synchronous read (block RAM), read-first: the stores are read at the input
//! edge, at `in_index`; a write at the same edge to the same address is seen by the results
//! of the following edges, not by this one. Both stores hold zeros after reset.
//!
//! **Residual.** [`crate::surface::residual`]`(q, p, n, in_dist)`, except that a difference
//! `|q_k - p_k| >= 2^10` (impossible when `in_dist` is the squared distance of `q` to `p`
//! and below `CAP_D2`) also gives `CAP_D2`: the block keeps 10-bit magnitudes.
//!
//! **For the polish.** Beside each residual: the signed residual before squaring
//! ([`block_signed_residual`]), the transformed point and the normal stored at the index.
//!
//! **Cost.** An accumulator adds `nn_resid` at every edge that presents `nn_valid`; at an
//! edge that presents `cost_valid`, `cost` is the accumulator's sum including a result
//! presented at the same edge (mod 2^48), and the accumulator restarts from 0. `cost`
//! holds its value between `cost_valid` strobes (0 after reset). The neighbour pipeline
//! never presents a result with `cost_valid`: it strobes `cost_valid` the edge after the
//! last result.

use crate::common::format::{pack_point, unpack_point, FxPoint, COST_MASK};
use crate::search::grid::CAP_D2;
use crate::surface::{residual, FxNormal};
use std::collections::VecDeque;

/// Edges from an input to its outputs.
pub const SURFACE_LATENCY: usize = 10;

/// An upper bound on the board's clocks for one pose's evaluation (the start edge to the
/// stage's `cost_valid`): the neighbour pipeline's bound
/// ([`crate::search::neighbour_pipeline::clocks_bound`]) and the stage's [`SURFACE_LATENCY`]; the
/// host's deadlines and its bound on a filter run use it.
pub fn evaluation_clocks_bound(scan_points: usize, model_points: usize, lanes: usize) -> u64 {
    crate::search::neighbour_pipeline::clocks_bound(scan_points, model_points, lanes) + SURFACE_LATENCY as u64
}

/// Words of each store (12-bit addresses).
pub const STORE_WORDS: usize = 4096;

/// Input ports (before an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SurfaceInputs {
    /// Write `point_wdata` to the point store at `point_waddr`.
    pub point_we: bool,
    /// Point store write address (12 bits).
    pub point_waddr: u16,
    /// A stored model point, packed ([`crate::common::format::pack_point`], 48 bits).
    pub point_wdata: u64,
    /// Write `normal_wdata` to the normal store at `normal_waddr`.
    pub normal_we: bool,
    /// Normal store write address (12 bits).
    pub normal_waddr: u16,
    /// A normal ([`FxNormal`]), packed like a point (48 bits).
    pub normal_wdata: u64,
    /// A result is presented.
    pub in_valid: bool,
    /// Its nearest stored index (12 bits).
    pub in_index: u16,
    /// Its squared distance (34 bits; `>= CAP_D2`: capped).
    pub in_dist: u64,
    /// The transformed scan point `q`, packed (48 bits).
    pub in_point: u64,
    /// End of a particle (the pipeline's `cost_valid`).
    pub in_cost_valid: bool,
}

impl SurfaceInputs {
    /// Write the point store.
    pub fn write_point(addr: usize, p: FxPoint) -> Self {
        SurfaceInputs { point_we: true, point_waddr: addr as u16, point_wdata: pack_point(p), ..Default::default() }
    }

    /// Write the normal store.
    pub fn write_normal(addr: usize, n: FxNormal) -> Self {
        SurfaceInputs { normal_we: true, normal_waddr: addr as u16, normal_wdata: pack_point(n), ..Default::default() }
    }
}

/// Output ports (after an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SurfaceOutputs {
    /// A result is presented.
    pub nn_valid: bool,
    /// Its nearest stored index.
    pub nn_index: u16,
    /// Its squared distance (34 bits).
    pub nn_dist: u64,
    /// Its residual (21 bits, at most `CAP_D2`).
    pub nn_resid: u32,
    /// Its signed residual before squaring ([`block_signed_residual`], 14 bits two's
    /// complement).
    pub nn_s: u16,
    /// Its transformed scan point (`in_point`, 48 bits).
    pub nn_point: u64,
    /// The normal stored at its index (48 bits).
    pub nn_normal: u64,
    /// End of a particle: `cost` is its sum of residuals.
    pub cost_valid: bool,
    /// The last particle's cost (48 bits).
    pub cost: u64,
}

/// One slot on its way through the block.
#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    valid: bool,
    index: u16,
    dist: u64,
    resid: u32,
    s: u16,
    point: u64,
    normal: u64,
    cost_valid: bool,
}

/// The block's signed residual before squaring: `rnd_14(sum_k n_k (q_k - p_k))` with each
/// difference's magnitude taken modulo `2^10` (the block keeps 10-bit magnitudes), as 14
/// bits two's complement. For a result below `CAP_D2` it is
/// [`crate::surface::signed_residual`], the polish's `s`.
pub fn block_signed_residual(q: FxPoint, p: FxPoint, n: FxNormal) -> u16 {
    let t: i64 = (0..3)
        .map(|k| {
            let d = q[k] as i64 - p[k] as i64;
            d.signum() * (d.abs() & 0x3ff) * n[k] as i64
        })
        .sum::<i64>()
        + (1 << 13);
    ((t >> 14) & 0x3fff) as u16
}

/// The block's residual of `q` against the stored `p` and `n` (see the module doc): the
/// rule, and `CAP_D2` for a difference of `2^10` or more along an axis.
pub fn block_residual(q: FxPoint, p: FxPoint, n: FxNormal, d2: u64) -> u64 {
    if (0..3).any(|k| (q[k] as i64 - p[k] as i64).abs() >= 1 << 10) {
        CAP_D2
    } else {
        residual(q, p, n, d2)
    }
}

/// Register state of the residual stage.
#[derive(Clone, Debug)]
pub struct SurfaceResidualModel {
    points: Vec<u64>,
    normals: Vec<u64>,
    /// The slots in flight, newest at the back (`SURFACE_LATENCY - 1` between edges).
    line: VecDeque<Slot>,
    acc: u64,
    out: SurfaceOutputs,
}

impl Default for SurfaceResidualModel {
    fn default() -> Self {
        Self::new()
    }
}

impl SurfaceResidualModel {
    /// After reset: stores zero, nothing in flight.
    pub fn new() -> Self {
        SurfaceResidualModel {
            points: vec![0; STORE_WORDS],
            normals: vec![0; STORE_WORDS],
            line: std::iter::repeat_n(Slot::default(), SURFACE_LATENCY - 1).collect(),
            acc: 0,
            out: SurfaceOutputs::default(),
        }
    }

    /// Output ports now.
    pub fn outputs(&self) -> SurfaceOutputs {
        self.out
    }

    /// The point store's word at `addr`.
    pub fn point(&self, addr: usize) -> FxPoint {
        unpack_point(self.points[addr % STORE_WORDS])
    }

    /// The normal store's word at `addr`.
    pub fn normal(&self, addr: usize) -> FxNormal {
        unpack_point(self.normals[addr % STORE_WORDS])
    }

    /// One rising edge.
    pub fn step(&mut self, i: &SurfaceInputs) {
        const A: u16 = (STORE_WORDS - 1) as u16;
        const W48: u64 = (1 << 48) - 1;
        // Read first (the stores as before this edge's writes).
        let index = i.in_index & A;
        let q = unpack_point(i.in_point & W48);
        let dist = i.in_dist & ((1 << 34) - 1);
        let p = unpack_point(self.points[index as usize]);
        let n = unpack_point(self.normals[index as usize]);
        let slot = Slot {
            valid: i.in_valid,
            index,
            dist,
            resid: block_residual(q, p, n, dist) as u32,
            s: block_signed_residual(q, p, n),
            point: i.in_point & W48,
            normal: self.normals[index as usize],
            cost_valid: i.in_cost_valid,
        };
        if i.point_we {
            self.points[(i.point_waddr & A) as usize] = i.point_wdata & W48;
        }
        if i.normal_we {
            self.normals[(i.normal_waddr & A) as usize] = i.normal_wdata & W48;
        }
        self.line.push_back(slot);
        let s = self.line.pop_front().expect("the line holds SURFACE_LATENCY slots here");
        self.out.nn_valid = s.valid;
        self.out.nn_index = s.index;
        self.out.nn_dist = s.dist;
        self.out.nn_resid = s.resid;
        self.out.nn_s = s.s;
        self.out.nn_point = s.point;
        self.out.nn_normal = s.normal;
        self.out.cost_valid = s.cost_valid;
        if s.valid {
            self.acc = (self.acc + s.resid as u64) & COST_MASK;
        }
        if s.cost_valid {
            self.out.cost = self.acc;
            self.acc = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::format::dist2;
    use crate::surface::NORMAL_FRAC;

    const ONE: i16 = 1 << NORMAL_FRAC;

    fn result(index: usize, q: FxPoint, d2: u64) -> SurfaceInputs {
        SurfaceInputs {
            in_valid: true,
            in_index: index as u16,
            in_dist: d2,
            in_point: pack_point(q),
            ..Default::default()
        }
    }

    #[test]
    fn results_come_out_after_the_latency_with_their_residual_and_cost() {
        let mut m = SurfaceResidualModel::new();
        let p = [100, -50, 7];
        m.step(&SurfaceInputs::write_point(5, p));
        m.step(&SurfaceInputs::write_normal(5, [0, 0, ONE]));
        let qs: [FxPoint; 3] = [[110, -50, 37], [100, -60, -13], [900, 900, 900]];
        let mut ins: Vec<SurfaceInputs> = qs.iter().map(|&q| result(5, q, dist2(q, p).min(CAP_D2))).collect();
        ins.push(SurfaceInputs { in_cost_valid: true, ..Default::default() });
        let mut outs = Vec::new();
        for k in 0..ins.len() + SURFACE_LATENCY {
            m.step(ins.get(k).unwrap_or(&SurfaceInputs::default()));
            outs.push(m.outputs());
        }
        for (k, o) in outs.iter().enumerate() {
            let from = k + 1;
            let expect_valid = from >= SURFACE_LATENCY && from - SURFACE_LATENCY < 3;
            assert_eq!(o.nn_valid, expect_valid, "edge {from}");
            assert_eq!(o.cost_valid, from == SURFACE_LATENCY + 3, "edge {from}");
        }
        let r: Vec<u32> = outs.iter().filter(|o| o.nn_valid).map(|o| o.nn_resid).collect();
        assert_eq!(r, vec![900, 400, CAP_D2 as u32]);
        // Beside each residual, its signed s, its point and the stored normal.
        let valid: Vec<&SurfaceOutputs> = outs.iter().filter(|o| o.nn_valid).collect();
        let s: Vec<u16> = valid.iter().map(|o| o.nn_s).collect();
        assert_eq!(s[..2], [30, (-20i16 as u16) & 0x3fff]);
        for (o, q) in valid.iter().zip(qs) {
            assert_eq!((o.nn_point, o.nn_normal), (pack_point(q), pack_point([0, 0, ONE])));
        }
        let last = outs.last().unwrap();
        assert_eq!(last.cost, 1300 + CAP_D2);
    }

    #[test]
    fn stores_read_before_write_and_far_differences_cap() {
        let mut m = SurfaceResidualModel::new();
        m.step(&SurfaceInputs::write_normal(9, [ONE, 0, 0]));
        // Same edge: the write of point 9 and a result at 9 (reads the old point, 0).
        let mut i = result(9, [20, 0, 0], 400);
        i.point_we = true;
        i.point_waddr = 9;
        i.point_wdata = pack_point([10, 0, 0]);
        m.step(&i);
        m.step(&result(9, [20, 0, 0], 100));
        // Inconsistent: d2 below the cap but a difference of 2^10.
        m.step(&result(9, [10 + 1024, 0, 0], 5));
        let mut r = Vec::new();
        for _ in 0..SURFACE_LATENCY {
            m.step(&SurfaceInputs::default());
            if m.outputs().nn_valid {
                r.push(m.outputs().nn_resid);
            }
        }
        assert_eq!(r, vec![400, 100, CAP_D2 as u32]);
        assert_eq!(m.point(9), [10, 0, 0]);
    }

    #[test]
    fn a_result_with_cost_valid_counts_in_the_closing_cost() {
        let mut m = SurfaceResidualModel::new();
        m.step(&SurfaceInputs::write_normal(0, [ONE, 0, 0]));
        m.step(&result(0, [3, 0, 0], 9));
        let mut i = result(0, [4, 0, 0], 16);
        i.in_cost_valid = true;
        m.step(&i);
        m.step(&result(0, [5, 0, 0], 25));
        m.step(&SurfaceInputs { in_cost_valid: true, ..Default::default() });
        let mut costs = Vec::new();
        for _ in 0..SURFACE_LATENCY {
            m.step(&SurfaceInputs::default());
            if m.outputs().cost_valid {
                costs.push(m.outputs().cost);
            }
        }
        assert_eq!(costs, vec![9 + 16, 25]);
        assert_eq!(m.outputs().cost, 25, "cost holds between strobes");
    }

    #[test]
    fn the_block_rule_is_the_surface_rule_for_consistent_results() {
        let mut r = crate::common::splitmix::SplitMix64(7);
        for _ in 0..20_000 {
            let p: FxPoint = [0; 3].map(|_| r.next_u64() as i16);
            let q: FxPoint = std::array::from_fn(|k| p[k].wrapping_add((r.below(2047) as i64 - 1023) as i16));
            let n: FxNormal = [0; 3].map(|_| r.next_u64() as i16);
            let d2 = dist2(q, p);
            assert_eq!(block_residual(q, p, n, d2), residual(q, p, n, d2));
            if d2 < CAP_D2 {
                let s = crate::surface::signed_residual(q, p, n);
                assert_eq!(block_signed_residual(q, p, n), (s as u16) & 0x3fff, "{q:?} {p:?} {n:?}");
            }
        }
    }
}
