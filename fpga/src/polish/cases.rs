//! The inputs the polish's RTL tests run on, from a seed, shared by the rust_hdl tests
//! (`fpga/tests/polish_*.rs`) and the Verilated ones (`sim/tests/polish_*.rs`): Gram
//! systems for the solve ([`solve_systems`]), files for every program
//! ([`program_cases`]) and passes of found points ([`pass_cases`]); and a surface to
//! polish on ([`surface`], [`pose`], [`window_scan`]) for the model's and the control's
//! tests.

use super::program::REGISTERS;
use super::programs::{load_pose, solve_inputs, Entry, F0, FOUND, SUM_B, SUM_R2};
use super::{upper, PassSums, STEP_LIMIT, UNKNOWNS};
use crate::common::format::{coord_to_f64, point, FxPoint, FxPose, COORD_FRAC, MATRIX_FRAC};
use crate::common::splitmix::SplitMix64;
use crate::search::grid::Grid;
use crate::surface::{FxNormal, NORMAL_FRAC};

/// The normal equations of `rows` (a Jacobian row and its residual each), each row counted
/// `repeat` times, every one an inlier ([`PassSums::add_point`]).
pub fn gram(rows: &[([i64; UNKNOWNS], i64)], repeat: i64) -> PassSums {
    let mut sums = PassSums::new();
    for _ in 0..repeat {
        for &(j, s) in rows {
            sums.add_point(s, Some(u64::MAX), || j);
        }
    }
    sums
}

/// `n` random rows, each a Jacobian row of 18-bit entries and a 13-bit residual.
pub fn random_rows(rng: &mut SplitMix64, n: usize) -> Vec<([i64; UNKNOWNS], i64)> {
    (0..n).map(|_| (std::array::from_fn(|_| rng.signed(18)), rng.signed(13))).collect()
}

/// The systems the RTL's tests solve: `random` Gram systems of 5 to 20 random rows (18-bit
/// entries, 13-bit residuals) repeated up to 4,096 rows in all, some of them rank-deficient,
/// from `seed`; then the widest (4,096 rows at full scale), a zero system, one with a
/// negative pivot (the program stops), one whose step the clamp bounds and one of six
/// rows (too few inliers: the program stops).
pub fn solve_systems(seed: u64, random: usize) -> Vec<PassSums> {
    let mut rng = SplitMix64(seed);
    let mut out = Vec::new();
    for _ in 0..random {
        let n_rows = 5 + rng.below(16) as usize;
        let repeat = 1 + rng.below(4096 / n_rows as u64) as i64;
        out.push(gram(&random_rows(&mut rng, n_rows), repeat));
    }
    let wide: Vec<_> = (0..8)
        .map(|r| {
            (
                std::array::from_fn(|c| if (r + c) % 3 == 0 { -(1 << 17) } else { (1 << 17) - 1 }),
                (1 << 12) - 1 - r as i64,
            )
        })
        .collect();
    out.push(gram(&wide, 512));
    let mut degenerate = gram(&[], 1);
    degenerate.inliers = UNKNOWNS as u32;
    out.push(degenerate.clone());
    degenerate.a[upper(2, 2)] = -100;
    out.push(degenerate);
    let mut big = gram(&[], 1);
    big.inliers = UNKNOWNS as u32;
    for i in 0..UNKNOWNS {
        big.a[upper(i, i)] = 1 << 20;
    }
    big.b = [1 << 40, -(1 << 40), 0, 0, 0, 0, 1];
    out.push(big);
    out.push(gram(&wide[..UNKNOWNS - 1], 1));
    out
}

/// A file of noise (any 128-bit values) with `set`'s inputs in place.
fn noise_with(rng: &mut SplitMix64, set: impl FnOnce(&mut [i128; REGISTERS])) -> [i128; REGISTERS] {
    let mut r: [i128; REGISTERS] =
        std::array::from_fn(|_| (rng.next_u64() as u128 | (rng.next_u64() as u128) << 64) as i128);
    set(&mut r);
    r
}

/// A pose from `rng`: with `scale = 0` any 18-bit entries, else a matrix of `scale` on the
/// diagonal and small random entries off it.
fn random_pose(rng: &mut SplitMix64, scale: f64) -> FxPose {
    let mut m: [i32; 9] = std::array::from_fn(|_| rng.signed(18) as i32);
    if scale > 0.0 {
        for (k, v) in m.iter_mut().enumerate() {
            *v = if k % 4 == 0 { (scale * (1 << MATRIX_FRAC) as f64) as i32 } else { *v / 64 };
        }
    }
    FxPose { m, t: std::array::from_fn(|_| rng.signed(18) as i32) }
}

/// The files the RTL's tests run each program on, from `seed`: noise around the program's
/// inputs (so that a program reading what it did not write would differ), `random` cases
/// a program plus the edges: the solve on [`solve_systems`]; the update on any pose and on
/// near-identity ones, steps up to the clamp, and a pose that saturates at both ends of 18
/// bits; the gate with found points (up to the widest `sum_r2`) and without; the start and
/// the clear; the drift check on both sides of both bounds.
pub fn program_cases(seed: u64, random: usize) -> Vec<(Entry, [i128; REGISTERS])> {
    let mut rng = SplitMix64(seed ^ 0x9e37_79b9_7f4a_7c15);
    let mut out = Vec::new();
    let inputs_of = |e: Entry, from: &[i128; REGISTERS], r: &mut [i128; REGISTERS]| {
        for a in e.inputs() {
            r[a as usize] = from[a as usize];
        }
    };
    for sums in solve_systems(seed, random) {
        let from = solve_inputs(&sums);
        out.push((Entry::Solve, noise_with(&mut rng, |r| inputs_of(Entry::Solve, &from, r))));
    }
    let (hi, lo) = ((1 << 17) - 1, -(1 << 17));
    let saturating = FxPose { m: [hi, 0, 0, 0, lo, 0, 0, 0, 1000], t: [hi, lo, 0] };
    for k in 0..random + 2 {
        let (pose, step): (FxPose, [i64; UNKNOWNS]) = match k {
            0 => (random_pose(&mut rng, 3.9), std::array::from_fn(|i| [STEP_LIMIT, -STEP_LIMIT][i % 2])),
            1 => (saturating, [0, 0, 0, STEP_LIMIT, -STEP_LIMIT, 0, STEP_LIMIT / 2]),
            _ => {
                let scale = [0.0, 1.0, 0.5, 2.0][k % 4];
                (random_pose(&mut rng, scale), std::array::from_fn(|_| (rng.next_u64() >> 36) as i64 - (1 << 27)))
            }
        };
        out.push((
            Entry::Update,
            noise_with(&mut rng, |r| {
                load_pose(r, &pose);
                for (i, &v) in step.iter().enumerate() {
                    r[SUM_B as usize + i] = v as i128;
                }
            }),
        ));
    }
    let mut stats = vec![(1u64 << 36) - 1, 1, 5, 0];
    stats.extend((0..random).flat_map(|_| [rng.next_u64() >> 28, 1 + rng.below(4096)]));
    for pair in stats.chunks(2) {
        let (sum_r2, found) = (pair[0], pair[1]);
        out.push((
            Entry::Gate,
            noise_with(&mut rng, |r| {
                r[SUM_R2 as usize] = sum_r2 as i128;
                r[FOUND as usize] = found as i128;
            }),
        ));
    }
    out.push((Entry::Clear, noise_with(&mut rng, |_| {})));
    for k in 0..random.max(1) {
        let start = random_pose(&mut rng, [1.0, 0.3, 3.0][k % 3]);
        out.push((Entry::Start, noise_with(&mut rng, |r| load_pose(r, &start))));
        let f0: i128 = start.m.iter().map(|&v| v as i128 * v as i128).sum();
        for scale in [0.79, 0.81, 1.0, 1.24, 1.26] {
            let polished = FxPose { m: start.m.map(|v| (v as f64 * scale).round() as i32), t: start.t };
            out.push((
                Entry::Drift,
                noise_with(&mut rng, |r| {
                    load_pose(r, &polished);
                    r[F0 as usize] = f0;
                }),
            ));
        }
    }
    out
}

/// A pass as the RTL's tests feed it: the pose's translation, the gate (`None`: statistics
/// only) and the found points (image, its nearest point's normal, signed residual).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PassCase {
    /// The pose's translation.
    pub t: [i32; 3],
    /// The gate.
    pub tau2: Option<u64>,
    /// The found points.
    pub points: Vec<(FxPoint, FxNormal, i64)>,
    /// The scale solved or held (the row's last entry).
    pub scale: super::ScaleStep,
}

impl PassCase {
    /// The pass's sums, as [`super::pass`] forms them ([`PassSums::add_point`]).
    pub fn sums(&self) -> PassSums {
        let mut sums = PassSums::new();
        for &(q, n, s) in &self.points {
            sums.add_point(s, self.tau2, || super::jacobian(q, self.t, n, self.scale));
        }
        sums
    }
}

/// Five passes of `points` found points each, from `seed`: statistics only; a gate of
/// 2^12 on residuals of 8 bits (some in, some out); a gate of 2^24 - 1 (every point in);
/// a gate of 2^20 with images and translations near the formats' extremes (`x = q - t`
/// reaches 19 bits and the Jacobian saturates); a gate of 2^24 - 1 with the scale held.
/// Normals of any 16-bit size, residuals of 13 bits but in the second; the second and
/// third passes also hold a point whose row rounds on ties (one more point).
pub fn pass_cases(seed: u64, points: usize) -> Vec<PassCase> {
    let mut rng = SplitMix64(seed);
    let mut out = Vec::new();
    for case in 0..5 {
        let wide = case == 3;
        let t: [i32; 3] = std::array::from_fn(|_| if wide { rng.signed(18) as i32 } else { rng.signed(14) as i32 });
        let mut points: Vec<(FxPoint, FxNormal, i64)> = (0..points)
            .map(|_| {
                let q = std::array::from_fn(|_| if wide { rng.signed(16) as i16 } else { rng.signed(14) as i16 });
                let n = std::array::from_fn(|_| rng.signed(16) as i16);
                (q, n, rng.signed(if case == 1 { 8 } else { 13 }))
            })
            .collect();
        let tau2 = [None, Some(1 << 12), Some(u64::MAX >> 40), Some(1 << 20), Some(u64::MAX >> 40)][case];
        let scale = if case == 4 { super::ScaleStep::Held } else { super::ScaleStep::Solved };
        if case == 1 || case == 2 {
            // Rounding ties: x = (1, 1, 1) and n = (0, 0, 2^12) give the cross product
            // (2^12, -2^12, 0) and the dot product 2^12, each half an LSB of the row.
            points.insert(points.len() / 2, (t.map(|c| c as i16 + 1), [0, 0, 1 << 12], 1));
        }
        out.push(PassCase { t, tau2, points, scale });
    }
    out
}

/// A bumpy height field's grid (41 x 41 points over `[-0.6, 0.6]^2`) and its unit normals
/// (by finite differences of the field): a surface the polish converges on.
pub fn surface() -> (Grid, Vec<FxNormal>) {
    let field = |x: f64, y: f64| 0.08 * (6.0 * x).sin() * (5.0 * y + 0.3).cos() + 0.1 * x * y;
    let mut pts = Vec::new();
    for i in -20..=20 {
        for j in -20..=20 {
            let (x, y) = (i as f64 * 0.03, j as f64 * 0.03);
            pts.push(point([x, y, field(x, y)]));
        }
    }
    let grid = Grid::build(&pts).expect("a grid of the surface");
    let normals = grid
        .points
        .iter()
        .map(|p| {
            let (x, y) = (coord_to_f64(p[0]), coord_to_f64(p[1]));
            let h = 1e-5;
            let (fx, fy) =
                ((field(x + h, y) - field(x - h, y)) / (2.0 * h), (field(x, y + h) - field(x, y - h)) / (2.0 * h));
            let len = (fx * fx + fy * fy + 1.0).sqrt();
            [-fx / len, -fy / len, 1.0 / len].map(|v| (v * (1 << NORMAL_FRAC) as f64).round() as i16)
        })
        .collect();
    (grid, normals)
}

/// A pose: `scale` times a rotation by `angle_z` about z, then `t` (model units).
pub fn pose(scale: f64, angle_z: f64, t: [f64; 3]) -> FxPose {
    let (c, s) = (angle_z.cos(), angle_z.sin());
    let r = [c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0];
    FxPose {
        m: r.map(|v| (v * scale * (1 << MATRIX_FRAC) as f64).round() as i32),
        t: t.map(|v| (v * (1 << COORD_FRAC) as f64).round() as i32),
    }
}

/// A scan of the surface: its own points in a window, every third (the identity is the
/// truth).
pub fn window_scan(grid: &Grid) -> Vec<FxPoint> {
    grid.points.iter().copied().filter(|p| p[0].abs() < 4000 && p[1].abs() < 4000).step_by(3).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pass cases let some points in and keep some out, and some rows saturate both
    /// ways.
    #[test]
    fn the_pass_cases_take_the_gate_and_the_saturation_both_ways() {
        let cases = pass_cases(0x9a55, 24);
        let sums: Vec<PassSums> = cases.iter().map(PassCase::sums).collect();
        assert!(sums.iter().any(|s| s.inliers > 0 && s.inliers < s.found), "{sums:?}");
        assert!(sums.iter().any(|s| s.inliers == s.found) && sums[0].inliers == 0);
        let rows: Vec<[i64; UNKNOWNS]> = cases
            .iter()
            .flat_map(|c| c.points.iter().map(|&(q, n, _)| super::super::jacobian(q, c.t, n, c.scale)))
            .collect();
        assert!(rows.iter().any(|j| j.contains(&((1 << 17) - 1))) && rows.iter().any(|j| j.contains(&-(1 << 17))));
        // The held scale's pass: every point in, its scale column and entry of `b` zero.
        let held = &sums[4];
        assert!(held.inliers == held.found && held.found > 0 && held.b[6] == 0);
        assert!((0..UNKNOWNS).all(|k| held.a[super::upper(k, 6)] == 0) && sums[2].b[6] != 0);
    }
}
