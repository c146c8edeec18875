//! The board's surface residual: the squared distance of a transformed scan point to the
//! tangent plane of its nearest stored model point, the bit-exact rule the residual stage
//! (`SurfaceResidual`, docs/pipeline.md "The surface residual") computes and the board's
//! costs sum in place of the point-to-point distance.
//!
//! **Why** (docs/board-modes.md, "The surface residual"): a point-to-point distance to a
//! model of 2,000 points is mostly the model's sampling (a scan point on the surface lies
//! up to half a spacing from the nearest sample), so the minimum of the board's cost lies a
//! fraction of a spacing from the truth: scale errors of 1 to 2.7% on the realistic set,
//! where the success tolerance is 1%. The distance along the nearest sample's normal does
//! not grow with the sampling.
//!
//! **Formats.** A normal is a unit vector times `2^14` in three `i16` ([`FxNormal`],
//! [`NORMAL_FRAC`]; packed into a 48-bit word like a point, [`crate::common::format::pack_point`]).
//! The residual is in the squared distance's format (Q8.26), at most [`CAP_D2`].
//!
//! **Rule** ([`residual`]). For a scan point `q` whose nearest stored point `p` (normal `n`)
//! lies at the squared distance `d2`:
//! - `d2 >= CAP_D2` (no model point within one cell: the search's capped result): `CAP_D2`;
//! - else `a = sum_k n_k (q_k - p_k)` (exact: `|q_k - p_k| < 2^10` since `d2 < 2^20`, so
//!   `|a| < 3 * 2^25`), `s = (a + 2^13) >> 14` (round half up, arithmetic shift: the
//!   coordinates' LSB), and the residual is `min(s^2, CAP_D2)`.
//!
//! Any stored normal is allowed (the host stores unit normals; a zero normal gives 0).

pub mod surface_residual;
#[cfg(feature = "rtl")]
pub mod surface_residual_rtl;

use crate::common::format::{transform, unpack_point, FxPoint, FxPose};
use crate::search::grid::{Grid, CAP_D2, NONE};

/// Fraction bits of a normal's component.
pub const NORMAL_FRAC: u32 = 14;

/// A fixed-point unit normal: `[x, y, z]` times `2^NORMAL_FRAC`.
pub type FxNormal = [i16; 3];

/// Bits of a residual (`CAP_D2 = 2^20` included).
pub const RESIDUAL_BITS: u32 = 21;

/// The module doc's rule: the capped squared distance of `q` to the tangent plane at `p`
/// (normal `n`), given the search's squared distance `d2` of `q` to `p`.
pub fn residual(q: FxPoint, p: FxPoint, n: FxNormal, d2: u64) -> u64 {
    if d2 >= CAP_D2 {
        return CAP_D2;
    }
    let s = signed_residual(q, p, n);
    ((s * s) as u64).min(CAP_D2)
}

/// The signed distance of `q` from the tangent plane at `p` with normal `n`, in coordinate
/// LSBs: `rnd_14(n . (q - p))` (round half up), which [`residual`] squares.
pub fn signed_residual(q: FxPoint, p: FxPoint, n: FxNormal) -> i64 {
    let a: i64 = (0..3).map(|k| n[k] as i64 * (q[k] as i64 - p[k] as i64)).sum();
    (a + (1 << (NORMAL_FRAC - 1))) >> NORMAL_FRAC
}

/// The residual of every scan point under `pose` over the gridded model with its normals
/// (`normals[i]` the normal of stored point `i`, [`Grid::points`]' order): the grid search's
/// nearest point ([`Grid::nearest`]), then [`residual`]. Equal to [`evaluate_stored`] over
/// the stores the upload writes (`crate::protocol::messages::grid_upload`).
pub fn scored(grid: &Grid, normals: &[FxNormal], scan: &[FxPoint], pose: &FxPose) -> Scored {
    assert_eq!(normals.len(), grid.points.len(), "one normal per stored model point");
    let (nearest, residuals) = scan
        .iter()
        .map(|&p| {
            let q = transform(pose, p);
            let nr = grid.nearest(q);
            if nr.index == NONE {
                ((0, CAP_D2), CAP_D2)
            } else {
                let i = nr.index as usize;
                ((nr.index, nr.d2), residual(q, grid.points[i], normals[i], nr.d2))
            }
        })
        .unzip();
    Scored::new(nearest, residuals)
}

/// What the filter takes from the board for a pose ([`scored`]): the cost (the sum of the
/// residuals, wrapping at 48 bits) and the largest residual.
pub fn evaluate(grid: &Grid, normals: &[FxNormal], scan: &[FxPoint], pose: &FxPose) -> crate::filter::pf::Evaluated {
    scored(grid, normals, scan, pose).evaluated()
}

/// What the board computes for a pose over its raw stores, whatever they hold: the model
/// store `ram` and the normal store `normals` ([`crate::common::format::MAX_POINTS`] packed words
/// each) and the cell table `first`. The neighbour pipeline's results
/// ([`crate::search::neighbour_pipeline::evaluate_stored`]: `(index, d2)`, capped as `(0, CAP_D2)`),
/// then each result's [`residual`] against the stored point and normal at its index.
pub fn evaluate_stored(ram: &[u64], normals: &[u64], first: &[u16], scan: &[FxPoint], pose: &FxPose) -> Scored {
    assert_eq!(normals.len(), ram.len(), "a normal store as large as the model store");
    let nearest = crate::search::neighbour_pipeline::evaluate_stored(ram, first, scan, pose).nearest;
    let residuals: Vec<u64> = scan
        .iter()
        .zip(&nearest)
        .map(|(&p, &(i, d2))| {
            residual(transform(pose, p), unpack_point(ram[i as usize]), unpack_point(normals[i as usize]), d2)
        })
        .collect();
    Scored::new(nearest, residuals)
}

/// The board's search over its raw stores for the polish ([`Search`]): a
/// scan point is found when its squared distance from [`evaluate_stored`] is below
/// [`CAP_D2`]; its stored point and normal are the words at its index.
#[derive(Clone, Copy, Debug)]
pub struct StoredSearch<'a> {
    /// The model store.
    pub ram: &'a [u64],
    /// The normal store.
    pub normals: &'a [u64],
    /// The cell table.
    pub first: &'a [u16],
}

impl Search for StoredSearch<'_> {
    fn found(&self, scan: &[FxPoint], pose: &FxPose) -> Vec<(FxPoint, FxPoint, FxNormal)> {
        let nearest = crate::search::neighbour_pipeline::evaluate_stored(self.ram, self.first, scan, pose).nearest;
        scan.iter()
            .zip(&nearest)
            .filter(|(_, &(_, d2))| d2 < CAP_D2)
            .map(|(&p, &(i, _))| {
                (transform(pose, p), unpack_point(self.ram[i as usize]), unpack_point(self.normals[i as usize]))
            })
            .collect()
    }
    fn evaluate(&self, scan: &[FxPoint], pose: &FxPose) -> crate::filter::pf::Evaluated {
        evaluate_stored(self.ram, self.normals, self.first, scan, pose).evaluated()
    }
}

/// A pose's results with their residuals, as the residual stage presents them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Scored {
    /// Per scan point: the nearest stored index and squared distance (`(0, CAP_D2)` capped).
    pub nearest: Vec<(u16, u64)>,
    /// Per scan point: its residual.
    pub residuals: Vec<u64>,
    /// The sum of the residuals, wrapping at 48 bits (the board's cost).
    pub cost: u64,
}

impl Scored {
    /// The cost summed from the residuals.
    pub fn new(nearest: Vec<(u16, u64)>, residuals: Vec<u64>) -> Self {
        let cost = residuals.iter().fold(0u64, |c, &x| (c + x) & crate::common::format::COST_MASK);
        Scored { nearest, residuals, cost }
    }

    /// What the filter takes: the cost and the largest residual.
    pub fn evaluated(&self) -> crate::filter::pf::Evaluated {
        crate::filter::pf::Evaluated { cost: self.cost, max_d2: self.residuals.iter().copied().max().unwrap_or(0) }
    }
}

/// What a pass needs of the board's search: under a pose, each scan point's image `q` with
/// its nearest stored point and that point's normal, capped points left out; and the pose's
/// evaluation (the residual stage's cost, wrapping at 48 bits, and largest residual).
pub trait Search {
    /// `(q, p, n)` of every found scan point, in scan order.
    fn found(&self, scan: &[FxPoint], pose: &FxPose) -> Vec<(FxPoint, FxPoint, FxNormal)>;
    /// The evaluation of `scan` under `pose`.
    fn evaluate(&self, scan: &[FxPoint], pose: &FxPose) -> crate::filter::pf::Evaluated;
}

/// The search over a [`Grid`] and its normals ([`Grid::nearest`], [`evaluate`]).
#[derive(Clone, Copy, Debug)]
pub struct GridSearch<'a> {
    /// The model by cell.
    pub grid: &'a Grid,
    /// One normal per stored point.
    pub normals: &'a [FxNormal],
}

impl Search for GridSearch<'_> {
    fn found(&self, scan: &[FxPoint], pose: &FxPose) -> Vec<(FxPoint, FxPoint, FxNormal)> {
        scan.iter()
            .filter_map(|&p| {
                let q = transform(pose, p);
                let nr = self.grid.nearest(q);
                (nr.index != NONE).then(|| (q, self.grid.points[nr.index as usize], self.normals[nr.index as usize]))
            })
            .collect()
    }
    fn evaluate(&self, scan: &[FxPoint], pose: &FxPose) -> crate::filter::pf::Evaluated {
        evaluate(self.grid, self.normals, scan, pose)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::format::dist2;

    const ONE: i16 = 1 << NORMAL_FRAC;

    #[test]
    fn the_residual_is_the_distance_along_the_normal() {
        let p = [100, -200, 300];
        // 37 LSBs along z, 500 along x: only z counts with the normal +z.
        let q = [600, -200, 337];
        assert_eq!(residual(q, p, [0, 0, ONE], dist2(q, p)), 37 * 37);
        assert_eq!(residual(q, p, [0, 0, -ONE], dist2(q, p)), 37 * 37);
        assert_eq!(residual(q, p, [ONE, 0, 0], dist2(q, p)), 500 * 500);
    }

    #[test]
    fn the_residual_rounds_half_up_and_never_exceeds_the_cap() {
        let p = [0, 0, 0];
        // n = (0.5, 0.5, 0): a = 2^13 (1 + 2) = 1.5 LSB -> 2 (half up); -1.5 -> -1.
        let n = [ONE / 2, ONE / 2, 0];
        assert_eq!(residual([1, 2, 0], p, n, 5), 4);
        assert_eq!(residual([-1, -2, 0], p, n, 5), 1);
        // The largest normal the format holds, at the largest uncapped difference.
        let q = [1023, 0, 0];
        assert_eq!(residual(q, p, [i16::MAX, 0, 0], dist2(q, p)), CAP_D2);
        assert_eq!(residual(q, p, [i16::MIN, 0, 0], dist2(q, p)), CAP_D2);
        // Capped by the search: the cap whatever the normal says.
        assert_eq!(residual([0, 0, 0], p, [0, 0, ONE], CAP_D2), CAP_D2);
    }

    #[test]
    fn evaluate_sums_the_residuals_of_the_grid_search() {
        // A flat patch at z = 0 with normals +z: a scan lifted by 50 LSBs costs 50^2 a
        // point, whatever the sampling within the patch; a far point costs the cap.
        let mut model = Vec::new();
        for i in 0..20i16 {
            for j in 0..20i16 {
                model.push([i * 97 - 900, j * 89 - 800, 0]);
            }
        }
        let grid = Grid::build(&model).unwrap();
        let normals = vec![[0, 0, ONE]; grid.points.len()];
        let scan: Vec<FxPoint> = vec![[13, 29, 50], [-400, 300, 50], [5000, 5000, 5000]];
        let id = FxPose { m: [1 << 15, 0, 0, 0, 1 << 15, 0, 0, 0, 1 << 15], t: [0; 3] };
        let e = evaluate(&grid, &normals, &scan, &id);
        assert_eq!(e.cost, 2 * 2500 + CAP_D2);
        assert_eq!(e.max_d2, CAP_D2);
        // The point-to-point distance of the same scan does grow with the sampling.
        let p2p: u64 = scan[..2].iter().map(|&q| grid.nearest(q).d2).sum();
        assert!(p2p > 2 * 2500);
    }
}
