//! The on-board polish: point-to-plane Gauss-Newton with scale over the board's own stores,
//! the bit-exact reference of what the board runs after its particle filter
//! (docs/on-board-polish.md; its RTL: docs/polish-datapath.md).
//! This model fixes the arithmetic the RTL must match, and the host's figures
//! (`host/tests/board_polish_figures.rs`) measure it. The arithmetic between passes (the
//! gate, the solve, the update, the drift check) runs as programs ([`programs`], in the
//! instruction set of [`program`]) on a datapath that is built
//! (`crate::polish::program_rtl::PolishProgram`), and a pass's point ([`PassSums::add_point`],
//! [`jacobian`]) has its RTL (`crate::polish::pass_rtl::PolishPass`), and so has the sequence of
//! [`polish_best`] (`crate::polish::control_rtl::PolishControl`); the board's engine runs them after
//! the filter.
//!
//! **Why.** The filter minimises its cost over 50 particles x 50 iterations; among those
//! 2,500 poses the lowest cost belongs to a pose a little off the truth (on 30 of the 32
//! dev cases the filter's best cost is below the cost at the true pose), and on a few
//! partial views that is more than the 1% scale tolerance, with 300 scan points or with
//! the whole scan, whatever the cost rule. A Gauss-Newton step solves for the centre of
//! the basin from the residuals' gradients instead; over the whole scan and with an inlier
//! gate it is what the host's polish does, on the board's quantised stores.
//!
//! The rules below are the specification the RTL follows. `rnd_k(v) = (v + 2^(k-1)) >> k`
//! (round half up, arithmetic shift); `v / d` truncates toward zero; where a formula rounds
//! inside a sum, each term is rounded before the sum.
//!
//! **A pass** ([`pass`]) over the scan points under the pose `(M, T)`, for each point:
//! - `q = transform(M, T, point)` ([`crate::common::format::transform`]), its nearest stored point
//!   `p` and `p`'s normal `n` ([`crate::search::grid::Grid::nearest`]); a capped point is skipped;
//! - `s = rnd_14(n . (q - p))`, the residual stage's signed residual in coordinate LSBs
//!   ([`crate::surface::residual`] squares it): `|s| < 2^10` for unit normals, `< 2^12`
//!   for any normal the format holds; the point adds `s^2` to `sum_r2` and 1 to `found`
//!   (`sum_r2 < 2^36`);
//! - an inlier (`s^2 <= tau2`) then takes `x = q - T` (19 bits) and the Jacobian row in
//!   Q3.14 (18 bits signed): `J = [sat18(rnd_13(x x n)) (3), n (3), sat18(rnd_13(n . x))]`
//!   (the saturation only bites for images farther than 8 from `T`), the derivatives of
//!   the residual by a small rotation about `T`, a translation and a relative scale; it
//!   adds `J_r J_c` to `a` (the upper triangle, 28 sums, each product at most 2^34) and
//!   `J_r s` to `b` (7 sums), all exact: `|a| <= 2^46`, `|b| < 2^42` for 4,096 points
//!   (48 bits signed).
//!
//! **The gate**: `tau2 = 9 sum_r2 / found` over the previous pass (three root-mean-square
//! residuals; below `9 * 2^24`). The first pass only gathers the statistics.
//!
//! **The solve** ([`solve`]), for sums from [`pass`] (a Gram matrix of at most 4,096 rows
//! of 18-bit entries; other sums may overflow): `lambda = (trace(a) >> 30) + 64`; for
//! `j = 0..7`: `v_k = rnd_30(L_jk D_k)` (`k < j`), `D_j = a_jj + lambda - sum_k
//! rnd_30(L_jk v_k)`; a pivot `2 D_j < lambda` (exactly `D_j >= lambda`; rounding only
//! takes a little) stops the polish; `L_ij = ((a_ij - sum_k rnd_30(L_ik v_k)) << 30) / D_j`
//! (`i > j`, Q.30). Then `y_i = -b_i - sum_{k<i} rnd_30(L_ik y_k)`, and from the last
//! unknown down `delta_i = (y_i << 31) / D_i - sum_{k>i} rnd_30(L_ki delta_k)` (`b` is in
//! units of 2^-27 and `a` of 2^-28, so `y 2^31 / D` is in Q.30: radians, the normalised
//! model's units, relative scale). Each `delta_i` is clamped to `+-2^27` (0.125) after the
//! substitution. Intermediates stay within 96 bits for such sums.
//!
//! **The update** ([`update`]): `W` the cross-product matrix of `delta_0..3` (Q.30);
//! `E = I + W + rnd_31(W W)` (Q.30, the square rounded per entry), `G_ij = rnd_30((2^30 +
//! delta_6) E_ij)`; `M'_ij = sat18(rnd_30(sum_c G_ic M_cj))`, `T'_k = sat18(T_k +
//! rnd_17(delta_(3+k)))` (Q.30 to the translation's Q5.13).
//!
//! **The loop** ([`polish`]): a statistics pass; then per step, while something was found:
//! a pass gated by the previous one, and if at least 7 points passed and the solve gives a
//! step, the update. [`polish_best`] chooses among starts and polishes the winner further.

#[cfg(feature = "rtl")]
pub mod bench_rtl;
pub mod cases;
#[cfg(feature = "rtl")]
pub mod control_rtl;
#[cfg(feature = "rtl")]
pub mod pass_rtl;
pub mod program;
#[cfg(feature = "rtl")]
pub mod program_rtl;
pub mod programs;
#[cfg(feature = "rtl")]
pub mod unit_rtl;

use crate::common::format::{FxPoint, FxPose};
use crate::filter::pf::sat18;
use crate::search::grid::Grid;
use crate::surface::{signed_residual, FxNormal, GridSearch, Search, NORMAL_FRAC};
use programs::Entry;

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
/// The damping's floor: `lambda = (trace >> 30) + LAMBDA_FLOOR`, so that a pivot that
/// rounding takes below `lambda / 2` is a degenerate system, not a tiny positive number.
pub const LAMBDA_FLOOR: i128 = 64;

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

/// The index of `(i, j)`, `i <= j`, in [`PassSums::a`].
pub fn upper(i: usize, j: usize) -> usize {
    let (i, j) = if i <= j { (i, j) } else { (j, i) };
    i * UNKNOWNS - i * (i + 1) / 2 + j
}

impl PassSums {
    /// No points yet.
    pub fn new() -> Self {
        PassSums { a: vec![0; UNKNOWNS * (UNKNOWNS + 1) / 2], ..Default::default() }
    }

    /// Add a found point with signed residual `s` (module doc): to the statistics, and if
    /// `tau2` lets it in, its Jacobian row (`row`, called only then) to the normal equations.
    pub fn add_point(&mut self, s: i64, tau2: Option<u64>, row: impl FnOnce() -> [i64; UNKNOWNS]) {
        let r2 = (s * s) as u64;
        self.sum_r2 += r2;
        self.found += 1;
        if tau2.is_none_or(|tau2| r2 > tau2) {
            return;
        }
        let j = row();
        for r in 0..UNKNOWNS {
            for c in r..UNKNOWNS {
                self.a[upper(r, c)] += j[r] * j[c];
            }
            self.b[r] += j[r] * s;
        }
        self.inliers += 1;
    }
}

/// Whether a step solves for the scale (the Run's [`crate::protocol::run_request::PolishRequest::scale`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ScaleStep {
    /// The scale is the seventh unknown.
    #[default]
    Solved,
    /// The scale is held where the start has it (the user knows it: `--scale`): the
    /// Jacobian's scale entry is 0, so its row and column of the normal equations are 0, the
    /// damping alone is its pivot, and the solve's scale step is exactly 0 (the update's
    /// `G = E`). The other six unknowns are the six-parameter solve's.
    Held,
}

/// The Jacobian row (Q3.14, module doc) of a point whose image `q` lies under a pose with
/// translation `t`, its nearest stored point's normal `n`: `[sat18(rnd_13(x x n)), n,
/// sat18(rnd_13(n . x))]` with `x = q - t`; the last entry 0 when the scale is
/// [`ScaleStep::Held`].
pub fn jacobian(q: FxPoint, t: [i32; 3], n: FxNormal, scale: ScaleStep) -> [i64; UNKNOWNS] {
    let n = n.map(|v| v as i64);
    let x: [i64; 3] = std::array::from_fn(|k| q[k] as i64 - t[k] as i64);
    let cross = [x[1] * n[2] - x[2] * n[1], x[2] * n[0] - x[0] * n[2], x[0] * n[1] - x[1] * n[0]];
    let shift = NORMAL_FRAC + crate::common::format::COORD_FRAC - JACOBIAN_FRAC;
    let dot: i64 = (0..3).map(|k| x[k] * n[k]).sum();
    let jac = |v: i64| sat18(round_shift(v as i128, shift) as i64) as i64;
    let scale_entry = match scale {
        ScaleStep::Solved => jac(dot),
        ScaleStep::Held => 0,
    };
    [jac(cross[0]), jac(cross[1]), jac(cross[2]), n[0], n[1], n[2], scale_entry]
}

/// One pass over `scan` under `pose` (module doc): the normal equations of the points whose
/// squared residual is at most `tau2` (`None`: none, statistics only), with the scale
/// `scale`.
pub fn pass(
    grid: &Grid,
    normals: &[FxNormal],
    scan: &[FxPoint],
    pose: &FxPose,
    tau2: Option<u64>,
    scale: ScaleStep,
) -> PassSums {
    pass_over(&GridSearch { grid, normals }, scan, pose, tau2, scale)
}

/// [`pass`] over any [`Search`] (the board's raw stores: [`crate::surface::StoredSearch`]).
pub fn pass_over(
    search: &impl Search,
    scan: &[FxPoint],
    pose: &FxPose,
    tau2: Option<u64>,
    scale: ScaleStep,
) -> PassSums {
    let mut sums = PassSums::new();
    for (q, m, n) in search.found(scan, pose) {
        sums.add_point(signed_residual(q, m, n), tau2, || jacobian(q, pose.t, n, scale));
    }
    sums
}

/// The gate of the pass after `sums` (module doc); `None` when nothing was found:
/// [`programs::gate_program`] as the board runs it.
pub fn gate(sums: &PassSums) -> Option<u64> {
    let mut r = programs::solve_inputs(sums);
    programs::run(Entry::Gate, &mut r).ok()?;
    Some(r[programs::TAU2 as usize] as u64)
}

/// The step of the normal equations in Q.30 (module doc), or `None` with fewer than
/// [`UNKNOWNS`] inliers or at a pivot below `lambda / 2`: [`programs::solve_program`] as
/// the board runs it. `sums` must come from [`pass`] (module doc: other sums may overflow).
pub fn solve(sums: &PassSums) -> Option<[i64; UNKNOWNS]> {
    let mut r = programs::solve_inputs(sums);
    programs::run(Entry::Solve, &mut r).ok()?;
    Some(programs::solve_output(&r))
}

/// The pose after a step (module doc): [`programs::update_program`] as the board runs it.
pub fn update(pose: &FxPose, step: &[i64; UNKNOWNS]) -> FxPose {
    let mut r = [0; program::REGISTERS];
    programs::load_pose(&mut r, pose);
    for (i, &v) in step.iter().enumerate() {
        r[programs::SUM_B as usize + i] = v as i128;
    }
    programs::run(Entry::Update, &mut r).expect("the update has no stop");
    programs::read_pose(&r)
}

/// What the polish did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Polished {
    /// The polished pose.
    pub pose: FxPose,
    /// Steps taken.
    pub steps: u32,
    /// The last pass's sums (taken at the pose before the last step; for a first start
    /// that [`polish_best`] kept unpolished, those of its rejected polish).
    pub last: PassSums,
}

/// Polish `start` with `steps` Gauss-Newton steps over `scan` (module doc): a statistics
/// pass, then per step a pass gated by the previous one, a solve and an update. Stops
/// early when nothing is found, fewer than 7 points pass the gate or the solve finds a
/// pivot below `lambda / 2`. With the scale [`ScaleStep::Held`] no step changes it beyond
/// the update's rounding.
pub fn polish(
    grid: &Grid,
    normals: &[FxNormal],
    scan: &[FxPoint],
    start: &FxPose,
    steps: u32,
    scale: ScaleStep,
) -> Polished {
    polish_over(&GridSearch { grid, normals }, scan, start, steps, scale)
}

/// [`polish`] over any [`Search`].
pub fn polish_over(search: &impl Search, scan: &[FxPoint], start: &FxPose, steps: u32, scale: ScaleStep) -> Polished {
    let mut pose = *start;
    let mut last = pass_over(search, scan, &pose, None, scale);
    let mut taken = 0;
    for _ in 0..steps {
        let Some(tau2) = gate(&last) else { break };
        let sums = pass_over(search, scan, &pose, Some(tau2), scale);
        let step = solve(&sums);
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

/// Whether `polished`'s scale is within [`SCALE_DRIFT`] of `start`'s (exact: the squared
/// ratio of the matrices' Frobenius norms between `(4/5)^2` and `(5/4)^2`):
/// [`programs::start_program`] on `start`, then [`programs::drift_program`] on `polished`,
/// as the board runs them.
pub fn within_drift(start: &FxPose, polished: &FxPose) -> bool {
    let mut r = [0; program::REGISTERS];
    programs::load_pose(&mut r, start);
    programs::run(Entry::Start, &mut r).expect("the start has no stop");
    programs::load_pose(&mut r, polished);
    programs::run(Entry::Drift, &mut r).is_ok()
}

/// The choice among several starts (the filter's pose first, then the host's hypotheses),
/// as the host's conclusion chooses: each polished ([`polish`]); a polish beyond
/// [`within_drift`] is dropped (the first start then stays unpolished, with no steps); the
/// rest are scored by the board's cost over `scan` at their pose (the sum of the capped
/// residuals, [`crate::surface::evaluate`]) and the lowest wins, the earlier start on a
/// tie. Then, with `winner_steps` above 0, the winner is polished again from its pose
/// ([`polish_winner_over`]). Returns the winner's index, its polish and its cost; `None`
/// without starts.
pub fn polish_best(
    grid: &Grid,
    normals: &[FxNormal],
    scan: &[FxPoint],
    starts: &[FxPose],
    steps: u32,
    winner_steps: u32,
    scale: ScaleStep,
) -> Option<(usize, Polished, u64)> {
    polish_winner_over(&GridSearch { grid, normals }, scan, starts, steps, winner_steps, scale)
}

/// What the board runs after its filter: the choice among `starts` with `steps` steps each
/// ([`polish_best_over`]), then, with `winner_steps` above 0, the winner's pose polished
/// again as a start of its own (a statistics pass, `winner_steps` steps, the drift bounds
/// from that pose: beyond them it stays as it was) and costed again. Many starts with a few
/// steps each and the winner's further steps cost less than every start's steps in full
/// (docs/on-board-polish.md, "Eight starts, the winner polished further"). Returns the winner's
/// index, its final polish (its steps the second polish's) and its final cost.
pub fn polish_winner_over(
    search: &impl Search,
    scan: &[FxPoint],
    starts: &[FxPose],
    steps: u32,
    winner_steps: u32,
    scale: ScaleStep,
) -> Option<(usize, Polished, u64)> {
    let (winner, polished, cost) = polish_best_over(search, scan, starts, steps, scale)?;
    if winner_steps == 0 {
        return Some((winner, polished, cost));
    }
    let (_, again, cost) = polish_best_over(search, scan, &[polished.pose], winner_steps, scale)?;
    Some((winner, again, cost))
}

/// [`polish_best`]'s choice (without the winner's further steps) over any [`Search`].
pub fn polish_best_over(
    search: &impl Search,
    scan: &[FxPoint],
    starts: &[FxPose],
    steps: u32,
    scale: ScaleStep,
) -> Option<(usize, Polished, u64)> {
    starts
        .iter()
        .enumerate()
        .filter_map(|(i, start)| {
            let mut p = polish_over(search, scan, start, steps, scale);
            if !within_drift(start, &p.pose) {
                if i > 0 {
                    return None;
                }
                p = Polished { pose: *start, steps: 0, last: p.last };
            }
            let cost = search.evaluate(scan, &p.pose).cost;
            Some((i, p, cost))
        })
        .min_by(|a, b| a.2.cmp(&b.2).then(a.0.cmp(&b.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::format::transform;

    /// The solve as the module doc writes it, in `i128` (the test profile checks overflow):
    /// the oracle of the program.
    #[allow(clippy::needless_range_loop)]
    fn solve_direct(sums: &PassSums) -> Option<[i64; UNKNOWNS]> {
        if (sums.inliers as usize) < UNKNOWNS {
            return None;
        }
        let a = |i: usize, j: usize| sums.a[upper(i, j)] as i128;
        let trace: i128 = (0..UNKNOWNS).map(|i| a(i, i)).sum();
        let lambda = (trace >> 30) + LAMBDA_FLOOR;
        let one = 1i128 << STEP_FRAC;
        let mut l = [[0i128; UNKNOWNS]; UNKNOWNS];
        let mut d = [0i128; UNKNOWNS];
        for j in 0..UNKNOWNS {
            // v_k = L_jk D_k (A's units).
            let v: Vec<i128> = (0..j).map(|k| round_shift(l[j][k] * d[k], STEP_FRAC)).collect();
            d[j] = a(j, j) + lambda - (0..j).map(|k| round_shift(l[j][k] * v[k], STEP_FRAC)).sum::<i128>();
            if 2 * d[j] < lambda {
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

    /// The update as the module doc writes it: the oracle of [`programs::update_program`].
    fn update_direct(pose: &FxPose, step: &[i64; UNKNOWNS]) -> FxPose {
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
            sat18(
                pose.t[k] as i64
                    + round_shift(step[3 + k] as i128, STEP_FRAC - crate::common::format::POSE_TRANSLATION_FRAC) as i64,
            )
        });
        FxPose { m, t }
    }

    /// The gate as the module doc writes it.
    fn gate_direct(sums: &PassSums) -> Option<u64> {
        (sums.found > 0).then(|| GATE_MSR * sums.sum_r2 / sums.found as u64)
    }

    /// The drift check as its doc writes it.
    fn within_drift_direct(start: &FxPose, polished: &FxPose) -> bool {
        let frobenius2 = |p: &FxPose| p.m.iter().map(|&v| (v as i64 * v as i64) as u128).sum::<u128>();
        let (lo, hi) = (SCALE_DRIFT.0 as u128 * SCALE_DRIFT.0 as u128, SCALE_DRIFT.1 as u128 * SCALE_DRIFT.1 as u128);
        let (f0, f1) = (frobenius2(start), frobenius2(polished));
        f1 * hi >= f0 * lo && f1 * lo <= f0 * hi
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

    /// The program agrees with the direct solve on `sums`.
    fn agree(sums: &PassSums) {
        assert_eq!(solve(sums), solve_direct(sums), "{sums:?}");
    }

    use crate::common::format::MATRIX_FRAC;
    use cases::{pose, surface, window_scan as scan};

    fn error(p: &FxPose) -> (f64, f64) {
        let one = (1 << MATRIX_FRAC) as f64;
        let scale = (p.m[0] as f64 * p.m[0] as f64 + p.m[3] as f64 * p.m[3] as f64 + p.m[6] as f64 * p.m[6] as f64)
            .sqrt()
            / one;
        let angle = (p.m[3] as f64).atan2(p.m[0] as f64).abs();
        ((scale - 1.0).abs(), angle)
    }

    /// The board's search over its raw stores finds what the grid finds, so the polish over
    /// either is the same; a store whose table names no cell finds nothing.
    #[test]
    fn the_stored_search_is_the_grid_search() {
        use crate::common::format::{pack_point, MAX_POINTS};
        use crate::surface::StoredSearch;
        let (grid, normals) = surface();
        let scan = scan(&grid);
        let pad = |v: Vec<u64>| [v, vec![0; MAX_POINTS]].concat()[..MAX_POINTS].to_vec();
        let ram = pad(grid.points.iter().map(|&p| pack_point(p)).collect());
        let nrm = pad(normals.iter().map(|&n| pack_point(n)).collect());
        let stored = StoredSearch { ram: &ram, normals: &nrm, first: &grid.first };
        let gridded = GridSearch { grid: &grid, normals: &normals };
        let mut found = 0;
        for at in [pose(1.0, 0.0, [0.0; 3]), pose(1.03, 0.1, [0.02, -0.01, 0.0]), pose(0.9, 1.5, [0.3, 0.0, 0.1])] {
            let f = stored.found(&scan, &at);
            assert_eq!(f, gridded.found(&scan, &at));
            assert_eq!(stored.evaluate(&scan, &at), gridded.evaluate(&scan, &at));
            found += f.len();
        }
        assert!(found > scan.len(), "the poses find points");
        let start = pose(1.02, 0.03, [0.01, -0.008, 0.004]);
        assert_eq!(
            polish_over(&stored, &scan, &start, 3, ScaleStep::Solved),
            polish(&grid, &normals, &scan, &start, 3, ScaleStep::Solved)
        );
        let empty = vec![0u16; grid.first.len()];
        let nothing = StoredSearch { first: &empty, ..stored };
        assert!(nothing.found(&scan, &start).is_empty());
    }

    #[test]
    fn the_polish_brings_a_perturbed_pose_back() {
        let (grid, normals) = surface();
        let scan = scan(&grid);
        let start = pose(1.02, 0.03, [0.01, -0.008, 0.004]);
        let (s0, a0) = error(&start);
        let out = polish(&grid, &normals, &scan, &start, 10, ScaleStep::Solved);
        let (s1, a1) = error(&out.pose);
        assert!(out.steps >= 3, "{out:?}");
        assert!(s1 < s0 / 10.0 && a1 < a0 / 10.0, "scale {s0} -> {s1}, angle {a0} -> {a1}");
        for k in 0..3 {
            assert!(out.pose.t[k].abs() < 20, "{:?}", out.pose.t);
        }
    }

    /// With the scale held, a start at the true scale comes back in rotation and
    /// translation as with the scale solved, every step's scale entry is exactly 0, and a
    /// start off in scale keeps its scale (the update's rounding only) where the solved
    /// polish corrects it.
    #[test]
    fn a_held_scale_stays_and_the_rest_is_polished() {
        let (grid, normals) = surface();
        let scan = scan(&grid);
        let start = pose(1.0, 0.03, [0.01, -0.008, 0.004]);
        let (_, a0) = error(&start);
        let held = polish(&grid, &normals, &scan, &start, 10, ScaleStep::Held);
        let (s1, a1) = error(&held.pose);
        assert!(held.steps >= 3 && a1 < a0 / 10.0 && s1 < 1e-4, "scale {s1}, angle {a0} -> {a1}");
        let stats = pass(&grid, &normals, &scan, &start, None, ScaleStep::Held);
        let sums = pass(&grid, &normals, &scan, &start, gate(&stats), ScaleStep::Held);
        assert!(sums.inliers > 100 && sums.b[6] == 0 && (0..UNKNOWNS).all(|k| sums.a[upper(k, 6)] == 0));
        assert_eq!(solve(&sums).map(|step| step[6]), Some(0));
        let off = pose(1.02, 0.03, [0.01, -0.008, 0.004]);
        let (s0, _) = error(&off);
        let (kept, _) = error(&polish(&grid, &normals, &scan, &off, 10, ScaleStep::Held).pose);
        let (solved, _) = error(&polish(&grid, &normals, &scan, &off, 10, ScaleStep::Solved).pose);
        assert!((kept - s0).abs() < 1e-4 && solved < s0 / 10.0, "held {s0} -> {kept}, solved -> {solved}");
    }

    #[test]
    fn the_truth_stays_put_and_outliers_fail_the_gate() {
        let (grid, normals) = surface();
        let mut scan = scan(&grid);
        let clean = scan.len();
        // Outliers a tenth of the radius above the surface: found (within one cell), far
        // beyond three RMS residuals.
        scan.extend(grid.points.iter().step_by(97).take(12).map(|p| [p[0], p[1], p[2] + 800]));
        let start = pose(1.0, 0.0, [0.0; 3]);
        let out = polish(&grid, &normals, &scan, &start, 3, ScaleStep::Solved);
        assert_eq!(out.steps, 3);
        for k in 0..9 {
            assert!((out.pose.m[k] - start.m[k]).abs() <= 4, "{:?}", out.pose.m);
        }
        for k in 0..3 {
            assert!(out.pose.t[k].abs() <= 2, "{:?}", out.pose.t);
        }
        let stats = pass(&grid, &normals, &scan, &start, None, ScaleStep::Solved);
        assert_eq!((stats.found as usize, stats.inliers), (clean + 12, 0));
        let gated = pass(&grid, &normals, &scan, &start, gate(&stats), ScaleStep::Solved);
        assert_eq!(gated.inliers as usize, clean, "every clean point in, every outlier out");
    }

    #[test]
    fn nothing_found_or_a_degenerate_scan_leaves_the_pose() {
        let (grid, normals) = surface();
        // Far outside the model: every point capped.
        let far = pose(1.0, 0.0, [3.0, 3.0, 0.0]);
        let out = polish(&grid, &normals, &scan(&grid), &far, 5, ScaleStep::Solved);
        assert_eq!((out.pose, out.steps), (far, 0));
        // Fewer than seven points.
        let few: Vec<FxPoint> = scan(&grid).into_iter().take(5).collect();
        let start = pose(1.01, 0.0, [0.0; 3]);
        assert_eq!(polish(&grid, &normals, &few, &start, 5, ScaleStep::Solved).pose, start);
    }

    #[test]
    fn the_solver_matches_floating_point_on_a_well_posed_system() {
        let (grid, normals) = surface();
        let start = pose(1.01, 0.02, [0.005, 0.0, -0.003]);
        let stats = pass(&grid, &normals, &scan(&grid), &start, None, ScaleStep::Solved);
        let sums = pass(&grid, &normals, &scan(&grid), &start, gate(&stats), ScaleStep::Solved);
        let step = solve(&sums).expect("positive pivots");
        agree(&sums);
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
        let (i, p, cost) = polish_best(&grid, &normals, &scan, &[far, near], 5, 0, ScaleStep::Solved).unwrap();
        assert_eq!(i, 1);
        assert_eq!(cost, crate::surface::evaluate(&grid, &normals, &scan, &p.pose).cost);
        assert_eq!(polish_best(&grid, &normals, &scan, &[near, near], 5, 0, ScaleStep::Solved).unwrap().0, 0);
        assert!(polish_best(&grid, &normals, &scan, &[], 5, 0, ScaleStep::Solved).is_none());
        assert!(polish_best(&grid, &normals, &scan, &[], 5, 3, ScaleStep::Solved).is_none());
    }

    #[test]
    fn the_winner_polished_further_is_a_second_polish_from_its_pose() {
        let (grid, normals) = surface();
        let scan = scan(&grid);
        let starts = [pose(1.0, 1.5, [0.0; 3]), pose(0.9, 0.2, [0.05, 0.0, 0.0])];
        let (i, first, _) = polish_best(&grid, &normals, &scan, &starts, 1, 0, ScaleStep::Solved).unwrap();
        let (j, again, cost) = polish_best(&grid, &normals, &scan, &starts, 1, 3, ScaleStep::Solved).unwrap();
        assert_eq!(i, j, "the winner's index is the choice's");
        let want = polish(&grid, &normals, &scan, &first.pose, 3, ScaleStep::Solved);
        assert!(within_drift(&first.pose, &want.pose));
        assert!(want.steps > 0 && want.pose != first.pose, "the further steps move the pose");
        assert_eq!(again, want);
        assert_eq!(cost, crate::surface::evaluate(&grid, &normals, &scan, &want.pose).cost);
    }

    #[test]
    fn the_drift_bounds_are_four_fifths_and_five_quarters_exactly() {
        let diag = |v: i32| FxPose { m: [v, 0, 0, 0, v, 0, 0, 0, v], t: [0; 3] };
        let start = diag(25_000);
        assert!(within_drift(&start, &diag(20_000)));
        assert!(!within_drift(&start, &diag(19_999)));
        assert!(within_drift(&start, &diag(31_250)));
        assert!(!within_drift(&start, &diag(31_251)));
    }

    #[test]
    fn the_update_rounds_as_specified() {
        let p = pose(1.0, 0.2, [0.1, -0.2, 0.3]);
        // Saturation at both ends of 18 bits.
        let big = FxPose { m: [(1 << 17) - 1, 0, 0, 0, -(1 << 17), 0, 0, 0, 1], t: [(1 << 17) - 1, -(1 << 17), 0] };
        let out = update(&big, &[0, 0, 0, 1 << 27, -(1 << 27), 0, 1 << 26]);
        assert_eq!(out, update_direct(&big, &[0, 0, 0, 1 << 27, -(1 << 27), 0, 1 << 26]));
        assert_eq!((out.m[0], out.m[4], out.t[0], out.t[1]), ((1 << 17) - 1, -(1 << 17), (1 << 17) - 1, -(1 << 17)));
        assert_eq!(update(&p, &[0; UNKNOWNS]), p);
        // A translation of exactly half an LSB rounds up; minus half rounds to zero.
        let half = 1i64 << (STEP_FRAC - crate::common::format::POSE_TRANSLATION_FRAC - 1);
        let up = update(&p, &[0, 0, 0, half, -half, half - 1, 0]);
        assert_eq!(up.t, [p.t[0] + 1, p.t[1], p.t[2]]);
        assert_eq!(up.m, p.m);
        // A scale step of 2^-4 multiplies the matrix by 17/16 (exact on these entries).
        let s = update(&diag16(), &[0, 0, 0, 0, 0, 0, 1 << 26]);
        assert_eq!(s.m, diag16().m.map(|v| v / 16 * 17));
        // A step of 0.125 rad about z, to second order: E = [[1 - w^2/2, -w], [w, 1 - w^2/2]].
        let w = 1i64 << 27;
        let r = update(&diag16(), &[0, 0, w, 0, 0, 0, 0]);
        let c = 16384 - ((16384 * ((w * w) >> 31)) >> 30) as i32; // 1 - 1/128 of 2^14
        assert_eq!([r.m[0], r.m[1], r.m[3], r.m[4], r.m[8]], [c, -2048, 2048, c, 16384]);
    }

    fn diag16() -> FxPose {
        FxPose { m: [16384, 0, 0, 0, 16384, 0, 0, 0, 16384], t: [0; 3] }
    }

    #[test]
    fn a_pivot_below_half_the_damping_stops_the_solve() {
        let mut sums = PassSums::new();
        // Too few inliers.
        sums.inliers = UNKNOWNS as u32 - 1;
        assert_eq!(solve(&sums), None);
        agree(&sums);
        // A zero system: every pivot is lambda, the step zero.
        sums.inliers = UNKNOWNS as u32;
        assert_eq!(solve(&sums), Some([0; UNKNOWNS]));
        // A negative diagonal entry (no Gram matrix has one): its pivot is below lambda / 2.
        sums.a[upper(2, 2)] = -100;
        assert_eq!(solve(&sums), None);
        agree(&sums);
        // The clamp: a huge right-hand side on a unit system gives +-2^27.
        let mut big = PassSums { inliers: UNKNOWNS as u32, ..PassSums::new() };
        for i in 0..UNKNOWNS {
            big.a[upper(i, i)] = 1 << 20;
        }
        big.b = [1 << 40, -(1 << 40), 0, 0, 0, 0, 1];
        let step = solve(&big).unwrap();
        assert_eq!((step[0], step[1], step[2]), (-STEP_LIMIT, STEP_LIMIT, 0));
        agree(&big);
    }

    /// The Jacobian is the residual's derivative: a small step in one unknown moves each
    /// point's residual by its column times the step (within the rounding), for every
    /// column; a column off by a factor fails.
    #[test]
    fn the_jacobian_predicts_the_residuals_change() {
        let (grid, normals) = surface();
        let scan = scan(&grid);
        let start = pose(1.0, 0.1, [0.02, -0.01, 0.0]);
        let rows = |pose: &FxPose| -> Vec<(u16, i64, [i64; UNKNOWNS])> {
            scan.iter()
                .map(|&p| {
                    let one = pass(&grid, &normals, &[p], pose, Some(u64::MAX), ScaleStep::Solved);
                    let nr = grid.nearest(transform(pose, p));
                    let j: [i64; UNKNOWNS] = std::array::from_fn(|k| one.b[k]);
                    // b = J s for one point: recover s from the translation column (J = n).
                    let s = if one.a[upper(3, 3)] + one.a[upper(4, 4)] + one.a[upper(5, 5)] == 0 {
                        0
                    } else {
                        (j[3] * normals[nr.index as usize][0] as i64
                            + j[4] * normals[nr.index as usize][1] as i64
                            + j[5] * normals[nr.index as usize][2] as i64)
                            / (one.a[upper(3, 3)] + one.a[upper(4, 4)] + one.a[upper(5, 5)])
                    };
                    let jac: [i64; UNKNOWNS] = std::array::from_fn(|k| if s == 0 { 0 } else { j[k] / s });
                    (nr.index, s, jac)
                })
                .collect()
        };
        let before = rows(&start);
        for k in 0..UNKNOWNS {
            let mut step = [0i64; UNKNOWNS];
            step[k] = 1 << 22; // 0.0039: a few LSBs of residual over the unit disc
            let after = rows(&update(&start, &step));
            let (mut err, mut size) = (0i64, 0i64);
            for (b, a) in before.iter().zip(&after) {
                if b.0 != a.0 || b.1 == 0 {
                    continue; // another nearest point, or no column to read
                }
                // J (2^-14) times the step (2^-30), in the residual's 2^-13.
                let predicted = (b.2[k] * step[k]) >> 31;
                err += (a.1 - b.1 - predicted).abs();
                size += predicted.abs();
            }
            assert!(size > 0 && err * 3 < size, "column {k}: error {err} against {size}");
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 48, failure_persistence: None, ..Default::default() })]

        /// Near the truth (2% in scale, 3 degrees, 2% of the radius) ten steps land within
        /// 0.1% and 0.05 degree of it.
        #[test]
        fn small_errors_converge(ds in -0.02f64..0.02, a in -0.05f64..0.05, t in proptest::array::uniform3(-0.02f64..0.02)) {
            let (grid, normals) = surface();
            let out = polish(&grid, &normals, &scan(&grid), &pose(1.0 + ds, a, t), 10, ScaleStep::Solved);
            let (se, ae) = error(&out.pose);
            proptest::prop_assert!(se < 1e-3 && ae < 1e-3, "scale {se}, angle {ae}, {out:?}");
        }

        /// The program and the direct solve agree on Gram systems of up to 4,096 rows of
        /// 18-bit entries (a few distinct rows, repeated), rank-deficient ones among them.
        #[test]
        fn the_program_is_the_direct_solve(
            rows in proptest::collection::vec((proptest::array::uniform7(-(1i64 << 17)..(1 << 17)), -(1i64 << 12)..(1 << 12)), 1..12),
            repeat in 1i64..=341,
        ) {
            let sums = cases::gram(&rows, repeat);
            proptest::prop_assert_eq!(solve(&sums), solve_direct(&sums));
        }

        /// The update program is the update's formula, on any pose the format holds and any
        /// step the solve's clamp lets through.
        #[test]
        fn the_update_program_is_the_formula(
            m in proptest::array::uniform9(-(1i32 << 17)..(1 << 17)),
            t in proptest::array::uniform3(-(1i32 << 17)..(1 << 17)),
            step in proptest::array::uniform7(-STEP_LIMIT..=STEP_LIMIT),
        ) {
            let pose = FxPose { m, t };
            proptest::prop_assert_eq!(update(&pose, &step), update_direct(&pose, &step));
        }

        /// The gate and drift programs are their formulas.
        #[test]
        fn the_gate_and_drift_programs_are_their_formulas(
            sum_r2 in 0u64..(1 << 36),
            found in 0u32..=4096,
            m0 in proptest::array::uniform9(-(1i32 << 17)..(1 << 17)),
            m1 in proptest::array::uniform9(-(1i32 << 17)..(1 << 17)),
            near in 0.7f64..1.4,
        ) {
            let sums = PassSums { sum_r2, found, ..PassSums::new() };
            proptest::prop_assert_eq!(gate(&sums), gate_direct(&sums));
            let (p0, p1) = (FxPose { m: m0, t: [0; 3] }, FxPose { m: m1, t: [0; 3] });
            proptest::prop_assert_eq!(within_drift(&p0, &p1), within_drift_direct(&p0, &p1));
            // A scaled copy, so that both outcomes come up near the bounds.
            let scaled = FxPose { m: m0.map(|v| (v as f64 * near).round() as i32), t: [0; 3] };
            proptest::prop_assert_eq!(within_drift(&p0, &scaled), within_drift_direct(&p0, &scaled));
        }

        /// Any pose the format holds (a matrix of 18-bit entries, any translation): no
        /// overflow (the test profile checks), and the result is the start or a step from it.
        #[test]
        fn any_pose_is_safe(m in proptest::array::uniform9(-(1i32 << 17)..(1 << 17)), t in proptest::array::uniform3(-(1i32 << 17)..(1 << 17))) {
            let (grid, normals) = surface();
            let start = FxPose { m, t };
            let out = polish(&grid, &normals, &scan(&grid), &start, 2, ScaleStep::Solved);
            if out.steps == 0 {
                proptest::prop_assert_eq!(out.pose, start);
            }
        }
    }

    /// The widest inputs the formats allow: 4,096 points all found and all inliers, their
    /// images about 15 from `T` (the largest matrix and translation), normals of the
    /// largest magnitude the format holds: the Jacobian saturates, the sums stay within
    /// their stated bounds and the test profile's overflow checks stay quiet.
    #[test]
    fn the_widest_inputs_stay_within_the_stated_bounds() {
        let (grid, _) = surface();
        let normals: Vec<FxNormal> = grid.points.iter().map(|_| [i16::MAX, i16::MIN, i16::MAX]).collect();
        let m = 130_000i32; // 3.97 in Q3.15
        let t = 122_880i32; // 15 in Q5.13
        let pose = FxPose { m: [m, 0, 0, 0, m, 0, 0, 0, m], t: [t; 3] };
        // Scan points whose images land on model points: p = (q - T) / M.
        let scan: Vec<FxPoint> = grid
            .points
            .iter()
            .cycle()
            .take(4096)
            .map(|q| q.map(|c| (((c as i64 - t as i64) << 15) as f64 / m as f64).round() as i16))
            .collect();
        let sums = pass(&grid, &normals, &scan, &pose, Some(u64::MAX), ScaleStep::Solved);
        assert_eq!(sums.inliers, 4096);
        assert_eq!(sums.a[upper(0, 0)], 4096 * (1i64 << 17) * (1 << 17), "the rotation column saturates");
        assert!(sums.a.iter().all(|v| v.abs() <= 1 << 46));
        assert!(sums.b.iter().all(|v| v.abs() < 1 << 42));
        assert!(sums.sum_r2 < 1 << 36);
        agree(&sums);
        let out = polish(&grid, &normals, &scan, &pose, 2, ScaleStep::Solved);
        assert!(out.steps <= 2);
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
