//! The on-board polish: point-to-plane Gauss-Newton with scale over the board's own stores,
//! the bit-exact reference of what the board is to run after its particle filter
//! (docs/decisions.md, "Why the board's pose alone misses, and the polish on the board").
//! No RTL twin yet: this model fixes the arithmetic the RTL must match, and the host's
//! figures (`host/tests/board_polish_figures.rs`) measure it.
//!
//! **Why.** The filter minimises its cost over 50 particles x 50 iterations; among those
//! 2,500 poses the lowest cost belongs to a pose a little off the truth (on 31 of the 32
//! dev cases the filter's best cost is below the cost at the true pose), and on a few
//! partial views that is more than the 1% scale tolerance, with 300 scan points or with
//! the whole scan, whatever the cost rule. A Gauss-Newton step solves for the centre of
//! the basin from the residuals' gradients instead; over the whole scan and with an inlier
//! gate it is what the host's polish does, on the board's quantised stores.
//!
//! **A pass** ([`pass`]) over the scan points under the pose `(M, T)`: each point's
//! transform `q` ([`crate::format::transform`]), the grid search's nearest stored point `p`
//! with its normal `n` ([`crate::grid::Grid::nearest`]; a capped point is skipped), the
//! residual stage's signed residual `s = (n . (q - p) + 2^13) >> 14` (coordinate LSBs,
//! `|s| < 2^10`, [`crate::surface::residual`] squares it) and the point's image about the
//! translation `x = q - T`. The Jacobian row in Q3.14 (18 bits signed):
//! `J = [sat18(round((x x n) / 2^13)) (3), n (3), sat18(round((n . x) / 2^13))]` (the
//! saturation only bites for images farther than 8 from `T`), the derivatives of
//! the residual by a small rotation about `T`, a translation and a relative scale. An
//! inlier (`s^2 <= tau2`) adds `J J^T` (28 sums, each product 36 bits) and `J s` (7 sums)
//! to the normal equations, all exact in 48 bits for up to 4,096 points; every found
//! point adds `s^2` and 1 to the statistics that set the next pass's gate.
//!
//! **The gate**: `tau2 = 9 sum(s^2) / count` (truncated) over the found points of the
//! previous pass: three root-mean-square residuals. The first pass only gathers the
//! statistics.
//!
//! **The solve** ([`solve`]): `A + lambda I` with `lambda = (trace A >> 30) + 1`, factored
//! `L D L^T` (`L` in Q.30, `D` in `A`'s units; a pivot `D_j <= 0` stops the polish), then
//! the step `delta = -(A + lambda I)^-1 b` in Q.30 (radians, the normalised model's
//! units, relative scale), each component clamped to `+-2^27` (0.125). Products are
//! exact (96 bits at most), shifts round half up, divisions truncate toward zero.
//!
//! **The update** ([`update`]): `G = (1 + sigma) (I + W + W^2 / 2)` in Q.30, `W` the
//! cross-product matrix of the rotation step; `M' = sat18(round(G M / 2^30))`,
//! `T' = sat18(T + round(t / 2^17))`.

use crate::format::{transform, FxPoint, FxPose};
use crate::grid::{Grid, NONE};
use crate::pf::sat18;
use crate::surface::{FxNormal, NORMAL_FRAC};

/// Unknowns of a step: a small rotation (3), a translation (3), a relative scale.
pub const UNKNOWNS: usize = 7;
/// Fraction bits of a Jacobian entry (Q3.14).
pub const JACOBIAN_FRAC: u32 = 14;
/// Fraction bits of the solver's `L` and of a step.
pub const STEP_FRAC: u32 = 30;
/// Largest step component (0.125 in Q.30).
pub const STEP_LIMIT: i64 = 1 << 27;
/// The gate in mean squared residuals (three root-mean-square residuals).
pub const GATE_MSR: u64 = 9;

/// The normal equations and the gate's statistics of one pass.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PassSums {
    /// `sum J J^T` over the inliers, the upper triangle row by row (28).
    pub a: Vec<i64>,
    /// `sum J s` over the inliers.
    pub b: [i64; UNKNOWNS],
    /// Inliers.
    pub inliers: u32,
    /// `sum s^2` over the found points.
    pub sum_r2: u64,
    /// Found points (not capped).
    pub found: u32,
}

/// `(x + 2^(k-1)) >> k`: round half up.
fn round_shift(x: i128, k: u32) -> i128 {
    (x + (1i128 << (k - 1))) >> k
}

/// `n / d` truncated toward zero (`d > 0`).
fn div_trunc(n: i128, d: i128) -> i128 {
    let q = n.abs() / d;
    if n < 0 {
        -q
    } else {
        q
    }
}

/// The index of `(i, j)`, `i <= j`, in [`PassSums::a`].
pub fn upper(i: usize, j: usize) -> usize {
    let (i, j) = if i <= j { (i, j) } else { (j, i) };
    i * UNKNOWNS - i * (i + 1) / 2 + j
}

/// One pass over `scan` under `pose` (module doc): the normal equations of the points whose
/// squared residual is at most `tau2` (`None`: none, statistics only).
pub fn pass(grid: &Grid, normals: &[FxNormal], scan: &[FxPoint], pose: &FxPose, tau2: Option<u64>) -> PassSums {
    let mut sums = PassSums { a: vec![0; UNKNOWNS * (UNKNOWNS + 1) / 2], ..Default::default() };
    for &p in scan {
        let q = transform(pose, p);
        let nr = grid.nearest(q);
        if nr.index == NONE {
            continue;
        }
        let m = grid.points[nr.index as usize];
        let n = normals[nr.index as usize].map(|v| v as i64);
        let a: i64 = (0..3).map(|k| n[k] * (q[k] as i64 - m[k] as i64)).sum();
        let s = (a + (1 << (NORMAL_FRAC - 1))) >> NORMAL_FRAC;
        let r2 = (s * s) as u64;
        sums.sum_r2 += r2;
        sums.found += 1;
        let Some(tau2) = tau2 else { continue };
        if r2 > tau2 {
            continue;
        }
        let x: [i64; 3] = std::array::from_fn(|k| q[k] as i64 - pose.t[k] as i64);
        let cross = [x[1] * n[2] - x[2] * n[1], x[2] * n[0] - x[0] * n[2], x[0] * n[1] - x[1] * n[0]];
        let shift = NORMAL_FRAC + crate::format::COORD_FRAC - JACOBIAN_FRAC;
        let dot: i64 = (0..3).map(|k| x[k] * n[k]).sum();
        let jac = |v: i64| sat18(round_shift(v as i128, shift) as i64) as i64;
        let j: [i64; UNKNOWNS] = [jac(cross[0]), jac(cross[1]), jac(cross[2]), n[0], n[1], n[2], jac(dot)];
        for r in 0..UNKNOWNS {
            for c in r..UNKNOWNS {
                sums.a[upper(r, c)] += j[r] * j[c];
            }
            sums.b[r] += j[r] * s;
        }
        sums.inliers += 1;
    }
    sums
}

/// The gate of the pass after `sums` (module doc); `None` when nothing was found.
pub fn gate(sums: &PassSums) -> Option<u64> {
    (sums.found > 0).then(|| GATE_MSR * sums.sum_r2 / sums.found as u64)
}

/// The step of the normal equations in Q.30 (module doc), or `None` at a pivot `<= 0`.
#[allow(clippy::needless_range_loop)]
pub fn solve(sums: &PassSums) -> Option<[i64; UNKNOWNS]> {
    let a = |i: usize, j: usize| sums.a[upper(i, j)] as i128;
    let trace: i128 = (0..UNKNOWNS).map(|i| a(i, i)).sum();
    let lambda = (trace >> 30) + 1;
    let one = 1i128 << STEP_FRAC;
    let mut l = [[0i128; UNKNOWNS]; UNKNOWNS];
    let mut d = [0i128; UNKNOWNS];
    for j in 0..UNKNOWNS {
        // v_k = L_jk D_k (A's units).
        let v: Vec<i128> = (0..j).map(|k| round_shift(l[j][k] * d[k], STEP_FRAC)).collect();
        d[j] = a(j, j) + lambda - (0..j).map(|k| round_shift(l[j][k] * v[k], STEP_FRAC)).sum::<i128>();
        if d[j] <= 0 {
            return None;
        }
        l[j][j] = one;
        for i in j + 1..UNKNOWNS {
            let num = a(i, j) - (0..j).map(|k| round_shift(l[i][k] * v[k], STEP_FRAC)).sum::<i128>();
            l[i][j] = div_trunc(num << STEP_FRAC, d[j]);
        }
    }
    // L y = -b; D z = y; L^T delta = z. `b` is in units of 2^-27 (J 2^-14 times s 2^-13)
    // and `A` of 2^-28, so a step in Q.30 is `y 2^31 / D`.
    let mut y = [0i128; UNKNOWNS];
    for i in 0..UNKNOWNS {
        y[i] = -(sums.b[i] as i128) - (0..i).map(|k| round_shift(l[i][k] * y[k], STEP_FRAC)).sum::<i128>();
    }
    let mut delta = [0i128; UNKNOWNS];
    for i in (0..UNKNOWNS).rev() {
        let z = div_trunc(y[i] << (STEP_FRAC + 1), d[i]);
        delta[i] = z - (i + 1..UNKNOWNS).map(|k| round_shift(l[k][i] * delta[k], STEP_FRAC)).sum::<i128>();
    }
    Some(delta.map(|v| v.clamp(-STEP_LIMIT as i128, STEP_LIMIT as i128) as i64))
}

/// The pose after a step (module doc).
pub fn update(pose: &FxPose, step: &[i64; UNKNOWNS]) -> FxPose {
    let one = 1i128 << STEP_FRAC;
    let [wx, wy, wz] = [step[0], step[1], step[2]].map(|v| v as i128);
    let w = [[0, -wz, wy], [wz, 0, -wx], [-wy, wx, 0]];
    let mut g = [[0i128; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let w2: i128 = (0..3).map(|k| w[i][k] * w[k][j]).sum();
            let e = if i == j { one } else { 0 } + w[i][j] + round_shift(w2, STEP_FRAC + 1);
            g[i][j] = round_shift((one + step[6] as i128) * e, STEP_FRAC);
        }
    }
    let m: [i32; 9] = std::array::from_fn(|k| {
        let (i, j) = (k / 3, k % 3);
        let v: i128 = (0..3).map(|c| g[i][c] * pose.m[3 * c + j] as i128).sum();
        sat18(round_shift(v, STEP_FRAC) as i64)
    });
    let t: [i32; 3] = std::array::from_fn(|k| {
        sat18(pose.t[k] as i64 + round_shift(step[3 + k] as i128, STEP_FRAC - crate::format::COORD_FRAC) as i64)
    });
    FxPose { m, t }
}

/// What the polish did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Polished {
    /// The polished pose.
    pub pose: FxPose,
    /// Steps taken.
    pub steps: u32,
    /// The last pass's sums (of the pose before the last step).
    pub last: PassSums,
}

/// Polish `start` with `steps` Gauss-Newton steps over `scan` (module doc): a statistics
/// pass, then per step a pass gated by the previous one, a solve and an update. Stops
/// early when nothing is found, fewer than 7 points pass the gate or a pivot is not
/// positive.
pub fn polish(grid: &Grid, normals: &[FxNormal], scan: &[FxPoint], start: &FxPose, steps: u32) -> Polished {
    let mut pose = *start;
    let mut last = pass(grid, normals, scan, &pose, None);
    let mut taken = 0;
    for _ in 0..steps {
        let Some(tau2) = gate(&last) else { break };
        let sums = pass(grid, normals, scan, &pose, Some(tau2));
        let enough = sums.inliers as usize >= UNKNOWNS;
        let step = if enough { solve(&sums) } else { None };
        last = sums;
        let Some(step) = step else { break };
        pose = update(&pose, &step);
        taken += 1;
    }
    Polished { pose, steps: taken, last }
}

/// The polish may change a start's scale by `SCALE_DRIFT.0 / SCALE_DRIFT.1` to
/// `SCALE_DRIFT.1 / SCALE_DRIFT.0` at most (0.8 to 1.25; the host's conclusion uses the
/// same bounds): a polish that runs further is a collapse onto part of the model, which
/// every one-sided cost rewards.
pub const SCALE_DRIFT: (u64, u64) = (4, 5);

/// The sum of the squared entries of `M`: `3 s^2` for a similarity of scale `s`.
fn frobenius2(p: &FxPose) -> u64 {
    p.m.iter().map(|&v| (v as i64 * v as i64) as u64).sum()
}

/// Whether `polished`'s scale is within [`SCALE_DRIFT`] of `start`'s (exact: the squared
/// ratio of the matrices' Frobenius norms between `(4/5)^2` and `(5/4)^2`).
pub fn within_drift(start: &FxPose, polished: &FxPose) -> bool {
    let (lo, hi) = (SCALE_DRIFT.0 * SCALE_DRIFT.0, SCALE_DRIFT.1 * SCALE_DRIFT.1);
    let (f0, f1) = (frobenius2(start) as u128, frobenius2(polished) as u128);
    f1 * hi as u128 >= f0 * lo as u128 && f1 * lo as u128 <= f0 * hi as u128
}

/// The choice among several starts (the filter's pose first, then the host's hypotheses),
/// as the host's conclusion chooses: each polished ([`polish`]); a polish beyond
/// [`within_drift`] is dropped (the first start then stays unpolished, with no steps); the
/// rest are scored by the board's cost over `scan` at their pose (the sum of the capped
/// residuals, [`crate::surface::evaluate`]) and the lowest wins, the earlier start on a
/// tie. Returns the winner's index, its polish and its cost; `None` without starts.
pub fn polish_best(
    grid: &Grid,
    normals: &[FxNormal],
    scan: &[FxPoint],
    starts: &[FxPose],
    steps: u32,
) -> Option<(usize, Polished, u64)> {
    starts
        .iter()
        .enumerate()
        .filter_map(|(i, start)| {
            let mut p = polish(grid, normals, scan, start, steps);
            if !within_drift(start, &p.pose) {
                if i > 0 {
                    return None;
                }
                p = Polished { pose: *start, steps: 0, last: p.last };
            }
            let cost = crate::surface::evaluate(grid, normals, scan, &p.pose).cost;
            Some((i, p, cost))
        })
        .min_by(|a, b| a.2.cmp(&b.2).then(a.0.cmp(&b.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::{point, MATRIX_FRAC};

    /// A bumpy height field's grid and unit normals (by finite differences of the field).
    fn surface() -> (Grid, Vec<FxNormal>) {
        let field = |x: f64, y: f64| 0.08 * (6.0 * x).sin() * (5.0 * y + 0.3).cos() + 0.1 * x * y;
        let mut pts = Vec::new();
        for i in -20..=20 {
            for j in -20..=20 {
                let (x, y) = (i as f64 * 0.03, j as f64 * 0.03);
                pts.push(point([x, y, field(x, y)]));
            }
        }
        let grid = Grid::build(&pts).unwrap();
        let normals = grid
            .points
            .iter()
            .map(|p| {
                let (x, y) = (crate::format::coord_to_f64(p[0]), crate::format::coord_to_f64(p[1]));
                let h = 1e-5;
                let (fx, fy) =
                    ((field(x + h, y) - field(x - h, y)) / (2.0 * h), (field(x, y + h) - field(x, y - h)) / (2.0 * h));
                let len = (fx * fx + fy * fy + 1.0).sqrt();
                [-fx / len, -fy / len, 1.0 / len].map(|v| (v * (1 << NORMAL_FRAC) as f64).round() as i16)
            })
            .collect();
        (grid, normals)
    }

    fn pose(scale: f64, angle_z: f64, t: [f64; 3]) -> FxPose {
        let (c, s) = (angle_z.cos(), angle_z.sin());
        let r = [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0];
        FxPose {
            m: r.map(|v| (v * scale * (1 << MATRIX_FRAC) as f64).round() as i32),
            t: t.map(|v| (v * (1 << crate::format::COORD_FRAC) as f64).round() as i32),
        }
    }

    /// The scan: the model's own points in a window (the identity is the truth).
    fn scan(grid: &Grid) -> Vec<FxPoint> {
        grid.points.iter().copied().filter(|p| p[0].abs() < 4000 && p[1].abs() < 4000).step_by(3).collect()
    }

    fn error(p: &FxPose) -> (f64, f64) {
        let one = (1 << MATRIX_FRAC) as f64;
        let scale = (p.m[0] as f64 * p.m[0] as f64 + p.m[3] as f64 * p.m[3] as f64 + p.m[6] as f64 * p.m[6] as f64)
            .sqrt()
            / one;
        let angle = (p.m[3] as f64).atan2(p.m[0] as f64).abs();
        ((scale - 1.0).abs(), angle)
    }

    #[test]
    fn the_polish_brings_a_perturbed_pose_back() {
        let (grid, normals) = surface();
        let scan = scan(&grid);
        let start = pose(1.02, 0.03, [0.01, -0.008, 0.004]);
        let (s0, a0) = error(&start);
        let out = polish(&grid, &normals, &scan, &start, 10);
        let (s1, a1) = error(&out.pose);
        assert!(out.steps >= 3, "{out:?}");
        assert!(s1 < s0 / 10.0 && a1 < a0 / 10.0, "scale {s0} -> {s1}, angle {a0} -> {a1}");
        for k in 0..3 {
            assert!(out.pose.t[k].abs() < 20, "{:?}", out.pose.t);
        }
    }

    #[test]
    fn the_truth_stays_put_and_the_gate_follows_the_residuals() {
        let (grid, normals) = surface();
        let scan = scan(&grid);
        let start = pose(1.0, 0.0, [0.0; 3]);
        let out = polish(&grid, &normals, &scan, &start, 3);
        for k in 0..9 {
            assert!((out.pose.m[k] - start.m[k]).abs() <= 4, "{:?}", out.pose.m);
        }
        let stats = pass(&grid, &normals, &scan, &start, None);
        assert_eq!(stats.found as usize, scan.len());
        assert_eq!(stats.inliers, 0);
        assert_eq!(gate(&stats), Some(GATE_MSR * stats.sum_r2 / stats.found as u64));
    }

    #[test]
    fn nothing_found_or_a_degenerate_scan_leaves_the_pose() {
        let (grid, normals) = surface();
        // Far outside the model: every point capped.
        let far = pose(1.0, 0.0, [3.0, 3.0, 0.0]);
        let out = polish(&grid, &normals, &scan(&grid), &far, 5);
        assert_eq!((out.pose, out.steps), (far, 0));
        // Fewer than seven points.
        let few: Vec<FxPoint> = scan(&grid).into_iter().take(5).collect();
        let start = pose(1.01, 0.0, [0.0; 3]);
        assert_eq!(polish(&grid, &normals, &few, &start, 5).pose, start);
    }

    #[test]
    fn the_solver_matches_floating_point_on_a_well_posed_system() {
        let (grid, normals) = surface();
        let start = pose(1.01, 0.02, [0.005, 0.0, -0.003]);
        let stats = pass(&grid, &normals, &scan(&grid), &start, None);
        let sums = pass(&grid, &normals, &scan(&grid), &start, gate(&stats));
        let step = solve(&sums).expect("positive pivots");
        let a = nalgebra::SMatrix::<f64, 7, 7>::from_fn(|i, j| sums.a[upper(i, j)] as f64);
        let b = nalgebra::SVector::<f64, 7>::from_fn(|i, _| sums.b[i] as f64);
        let want = -a.cholesky().unwrap().solve(&b) * 2f64.powi(31);
        for i in 0..UNKNOWNS {
            assert!((step[i] as f64 - want[i]).abs() < 1e-4 * want.amax() + 64.0, "{i}: {} vs {}", step[i], want[i]);
        }
    }

    #[test]
    fn the_best_start_wins_and_a_tie_keeps_the_first() {
        let (grid, normals) = surface();
        let scan = scan(&grid);
        // A start in another basin (a quarter turn) loses to one near the truth.
        let far = pose(1.0, 1.5, [0.0; 3]);
        let near = pose(1.01, 0.02, [0.0; 3]);
        let (i, p, cost) = polish_best(&grid, &normals, &scan, &[far, near], 5).unwrap();
        assert_eq!(i, 1);
        assert_eq!(cost, crate::surface::evaluate(&grid, &normals, &scan, &p.pose).cost);
        assert_eq!(polish_best(&grid, &normals, &scan, &[near, near], 5).unwrap().0, 0);
        assert!(polish_best(&grid, &normals, &scan, &[], 5).is_none());
    }

    #[test]
    fn the_drift_bounds_are_four_fifths_and_five_quarters() {
        let start = pose(1.0, 0.3, [0.0; 3]);
        assert!(within_drift(&start, &pose(0.81, 0.0, [0.0; 3])));
        assert!(within_drift(&start, &pose(1.24, 0.0, [0.0; 3])));
        assert!(!within_drift(&start, &pose(0.79, 0.0, [0.0; 3])));
        assert!(!within_drift(&start, &pose(1.26, 0.0, [0.0; 3])));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 48, failure_persistence: None, ..Default::default() })]

        /// Near the truth (2% in scale, 3 degrees, 2% of the radius) ten steps land within
        /// 0.1% and 0.05 degree of it.
        #[test]
        fn small_errors_converge(ds in -0.02f64..0.02, a in -0.05f64..0.05, t in proptest::array::uniform3(-0.02f64..0.02)) {
            let (grid, normals) = surface();
            let out = polish(&grid, &normals, &scan(&grid), &pose(1.0 + ds, a, t), 10);
            let (se, ae) = error(&out.pose);
            proptest::prop_assert!(se < 1e-3 && ae < 1e-3, "scale {se}, angle {ae}, {out:?}");
        }

        /// Any pose the format holds (a matrix of 18-bit entries, any translation): no
        /// overflow (the test profile checks), and the result is the start or a step from it.
        #[test]
        fn any_pose_is_safe(m in proptest::array::uniform9(-(1i32 << 17)..(1 << 17)), t in proptest::array::uniform3(-(1i32 << 17)..(1 << 17))) {
            let (grid, normals) = surface();
            let start = FxPose { m, t };
            let out = polish(&grid, &normals, &scan(&grid), &start, 2);
            proptest::prop_assert!(out.steps <= 2);
            if out.steps == 0 {
                proptest::prop_assert_eq!(out.pose, start);
            }
        }
    }

    #[test]
    fn upper_indexes_the_triangle_once() {
        let mut seen = [false; 28];
        for i in 0..UNKNOWNS {
            for j in i..UNKNOWNS {
                assert!(!seen[upper(i, j)]);
                seen[upper(i, j)] = true;
                assert_eq!(upper(i, j), upper(j, i));
            }
        }
        assert!(seen.iter().all(|&s| s));
    }
}
