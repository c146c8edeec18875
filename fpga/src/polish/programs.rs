//! The polish's programs (in [`super::program`]'s instruction set) and the ROM that holds
//! them ([`rom`]): the arithmetic of [`super::polish`] between its passes, as the board
//! runs it. The board's control (`crate::polish::control_rtl::PolishControl`) loads a start's pose
//! at [`POSE`], runs [`Entry::Start`] and [`Entry::Clear`], lets a pass add its sums and
//! statistics, then per step runs [`Entry::Gate`] (and [`Entry::Clear`]), a gated pass,
//! [`Entry::Solve`] and [`Entry::Update`]; at the end [`Entry::Drift`]. A failed program
//! ends the steps (gate, solve) or drops the polish (drift). [`super::gate`],
//! [`super::solve`], [`super::update`] and [`super::within_drift`] run these programs, so
//! the programs are the reference; the module's tests hold them to the direct formulas of
//! [`super`]'s module doc.
//!
//! Every program writes its working registers before it reads them, so what an earlier
//! program left there does not matter (a test fills them with noise).

use super::program::{Op, Rom, REGISTERS};
use super::{upper, PassSums, GATE_MSR, LAMBDA_FLOOR, SCALE_DRIFT, STEP_FRAC, STEP_LIMIT, UNKNOWNS};
use crate::common::format::{FxPose, POSE_TRANSLATION_FRAC};
use std::sync::OnceLock;

/// The programs of the polish's ROM, in ROM order (`Entry as usize` is the index for
/// [`Rom::entry`] and [`Rom::run`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(usize)]
pub enum Entry {
    /// A start: `|M|^2` of the pose at [`POSE`] into [`F0`] ([`start_program`]).
    Start,
    /// Zero the sums and statistics a pass adds to ([`clear_program`]).
    Clear,
    /// The next pass's gate into [`TAU2`]; fails when nothing was found ([`gate_program`]).
    Gate,
    /// The step ([`solve_program`]).
    Solve,
    /// The pose after the step ([`update_program`]).
    Update,
    /// Fails when the pose's scale left [`super::SCALE_DRIFT`] of the start's
    /// ([`drift_program`]).
    Drift,
}

impl Entry {
    /// Every program, in ROM order.
    pub const ALL: [Entry; 6] = [Entry::Start, Entry::Clear, Entry::Gate, Entry::Solve, Entry::Update, Entry::Drift];

    /// The registers the program reads (what the control or a pass must have put there).
    pub fn inputs(self) -> Vec<u8> {
        let pose = POSE..POSE + 12;
        match self {
            Entry::Start => pose.take(9).collect(),
            Entry::Clear => Vec::new(),
            Entry::Gate => vec![SUM_R2, FOUND],
            Entry::Solve => (SUM_A..SUM_B + UNKNOWNS as u8).chain([INLIERS]).collect(),
            Entry::Update => (SUM_B..SUM_B + UNKNOWNS as u8).chain(pose).collect(),
            Entry::Drift => pose.take(9).chain([F0]).collect(),
        }
    }

    /// The registers the program leaves for what follows (besides its failed flag).
    pub fn outputs(self) -> Vec<u8> {
        match self {
            Entry::Start => vec![F0],
            Entry::Clear => (SUM_A..SUM_B + UNKNOWNS as u8).chain([SUM_R2, FOUND, INLIERS]).collect(),
            Entry::Gate => vec![TAU2],
            Entry::Solve => (SUM_B..SUM_B + UNKNOWNS as u8).collect(),
            Entry::Update => (POSE..POSE + 12).collect(),
            Entry::Drift => Vec::new(),
        }
    }

    /// The program's instructions.
    pub fn program(self) -> Vec<Op> {
        match self {
            Entry::Start => start_program(),
            Entry::Clear => clear_program(),
            Entry::Gate => gate_program(),
            Entry::Solve => solve_program(),
            Entry::Update => update_program(),
            Entry::Drift => drift_program(),
        }
    }
}

/// The polish's ROM: [`Entry::ALL`]'s programs in order.
pub fn rom() -> &'static Rom {
    static ROM: OnceLock<Rom> = OnceLock::new();
    ROM.get_or_init(|| Rom::new(Entry::ALL.iter().map(|e| e.program()).collect()))
}

/// Run `entry`'s program on `r`; `Err` when it failed.
pub fn run(entry: Entry, r: &mut [i128; REGISTERS]) -> Result<(), usize> {
    rom().run(entry as usize, r)
}

/// Where the solve keeps its values. `a`'s upper triangle comes in at [`SUM_A`] (in
/// [`upper`]'s order) and `L_ij` (`i > j`) replaces `a_ji`, `D_j` replaces `a_jj`; `b` comes
/// in at [`SUM_B`], becomes `y` and then the step.
pub const SUM_A: u8 = 0;
/// See [`SUM_A`].
pub const SUM_B: u8 = 28;
/// The pass's statistics, added beside the sums (`PolishPass`): `sum_r2`, `found`,
/// `inliers`.
pub const SUM_R2: u8 = 45;
/// See [`SUM_R2`].
pub const FOUND: u8 = 46;
/// See [`SUM_R2`].
pub const INLIERS: u8 = 47;
/// `v_k = rnd_30(L_jk D_k)` of the current column (6).
const V: u8 = 35;
/// The damping.
const LAMBDA: u8 = 41;
/// A product, the trace, a constant.
const TEMP: u8 = 42;
/// Zero.
const ZERO: u8 = 43;
/// The step's bound.
const LIMIT: u8 = 44;
/// The pose `(M, T)`: `M` row by row, then `T` (12 registers), where the update reads and
/// writes it and the start and drift check read `M`.
pub const POSE: u8 = 48;
/// The gate's `tau2`, which the gate program leaves for the next pass.
pub const TAU2: u8 = 60;
/// The start's `|M|^2` (the sum of its squared entries), which the drift check reads.
pub const F0: u8 = 61;

/// The register of `a(i, j)`, `L_ij` or `D_j`.
fn at(i: usize, j: usize) -> u8 {
    SUM_A + upper(i, j) as u8
}

/// The solve of [`super::solve`]'s specification as a program: the inlier count's test,
/// the damping, the LDL^T factorisation with its pivot test, the two substitutions and the
/// clamp. Inputs: `a` at [`SUM_A`], `b` at [`SUM_B`], the inliers at [`INLIERS`]; output:
/// the step at [`SUM_B`]; fails with fewer than [`UNKNOWNS`] inliers or at a pivot below
/// half the damping.
pub fn solve_program() -> Vec<Op> {
    let n = UNKNOWNS;
    let k30 = STEP_FRAC as u8;
    let mut p = vec![
        // Fewer than 7 inliers: 2 inliers < 14.
        Op::constant(TEMP, 2 * UNKNOWNS as u128),
        Op::StopBelow { a: INLIERS, b: TEMP },
        Op::Add { d: TEMP, a: at(0, 0), b: at(1, 1) },
    ];
    p.extend((2..n).map(|i| Op::Add { d: TEMP, a: TEMP, b: at(i, i) }));
    p.push(Op::Shr { d: LAMBDA, a: TEMP, k: 30 });
    p.push(Op::constant(TEMP, LAMBDA_FLOOR as u128));
    p.push(Op::Add { d: LAMBDA, a: LAMBDA, b: TEMP });
    for j in 0..n {
        let v = |k: usize| V + k as u8;
        p.extend((0..j).map(|k| Op::Mul { d: v(k), a: at(j, k), b: at(k, k), k: k30 }));
        p.push(Op::Add { d: at(j, j), a: at(j, j), b: LAMBDA });
        for k in 0..j {
            p.push(Op::Mul { d: TEMP, a: at(j, k), b: v(k), k: k30 });
            p.push(Op::Sub { d: at(j, j), a: at(j, j), b: TEMP });
        }
        p.push(Op::StopBelow { a: at(j, j), b: LAMBDA });
        for i in j + 1..n {
            for k in 0..j {
                p.push(Op::Mul { d: TEMP, a: at(i, k), b: v(k), k: k30 });
                p.push(Op::Sub { d: at(i, j), a: at(i, j), b: TEMP });
            }
            p.push(Op::Div { d: at(i, j), a: at(i, j), b: at(j, j), k: k30 });
        }
    }
    let y = |i: usize| SUM_B + i as u8;
    p.push(Op::constant(ZERO, 0));
    for i in 0..n {
        p.push(Op::Sub { d: y(i), a: ZERO, b: y(i) });
        for k in 0..i {
            p.push(Op::Mul { d: TEMP, a: at(i, k), b: y(k), k: k30 });
            p.push(Op::Sub { d: y(i), a: y(i), b: TEMP });
        }
    }
    for i in (0..n).rev() {
        p.push(Op::Div { d: y(i), a: y(i), b: at(i, i), k: k30 + 1 });
        for k in i + 1..n {
            p.push(Op::Mul { d: TEMP, a: at(k, i), b: y(k), k: k30 });
            p.push(Op::Sub { d: y(i), a: y(i), b: TEMP });
        }
    }
    p.push(Op::constant(LIMIT, STEP_LIMIT as u128));
    p.extend((0..n).map(|i| Op::Clamp { d: y(i), a: y(i), b: LIMIT }));
    p
}

/// The register file with a pass's sums loaded where [`solve_program`] takes them (and its
/// statistics where the pass adds them).
pub fn solve_inputs(sums: &PassSums) -> [i128; REGISTERS] {
    let mut r = [0i128; REGISTERS];
    for (k, &v) in sums.a.iter().enumerate() {
        r[SUM_A as usize + k] = v as i128;
    }
    for (i, &v) in sums.b.iter().enumerate() {
        r[SUM_B as usize + i] = v as i128;
    }
    r[SUM_R2 as usize] = sums.sum_r2 as i128;
    r[FOUND as usize] = sums.found as i128;
    r[INLIERS as usize] = sums.inliers as i128;
    r
}

/// The step [`solve_program`] leaves in `r` (the clamp keeps it within 2^27).
pub fn solve_output(r: &[i128; REGISTERS]) -> [i64; UNKNOWNS] {
    std::array::from_fn(|i| r[SUM_B as usize + i] as i64)
}

/// What an inlier with Jacobian row `j` and residual `s` adds to the register file
/// (register, value; `PolishPass` issues the same adds in its own order): `J_r J_c` to
/// `a`, `J_r s` to `b`, and its statistics.
pub fn inlier_adds(j: &[i64; UNKNOWNS], s: i64) -> Vec<(u8, i64)> {
    let mut adds = Vec::with_capacity(38);
    for r in 0..UNKNOWNS {
        adds.extend((r..UNKNOWNS).map(|c| (at(r, c), j[r] * j[c])));
        adds.push((SUM_B + r as u8, j[r] * s));
    }
    adds.extend([(SUM_R2, s * s), (FOUND, 1), (INLIERS, 1)]);
    adds
}

/// `r[d] = sum of the squares of M` (the pose at [`POSE`]), with `TEMP`.
fn frobenius(d: u8) -> Vec<Op> {
    let m = |i: usize| POSE + i as u8;
    let mut p = vec![Op::Mul { d, a: m(0), b: m(0), k: 0 }];
    for i in 1..9 {
        p.push(Op::Mul { d: TEMP, a: m(i), b: m(i), k: 0 });
        p.push(Op::Add { d, a: d, b: TEMP });
    }
    p
}

/// A start: `|M|^2` into [`F0`] for the drift check.
pub fn start_program() -> Vec<Op> {
    frobenius(F0)
}

/// Zero what a pass adds to: `a`, `b` and the statistics.
pub fn clear_program() -> Vec<Op> {
    let sums = (SUM_A..SUM_B + UNKNOWNS as u8).chain([SUM_R2, FOUND, INLIERS]);
    sums.map(|d| Op::constant(d, 0)).collect()
}

/// The gate ([`super::gate`]): fails when nothing was found (`2 found < 1`), else `tau2 =
/// 9 sum_r2 / found` into [`TAU2`].
pub fn gate_program() -> Vec<Op> {
    vec![
        Op::constant(TEMP, 1),
        Op::StopBelow { a: FOUND, b: TEMP },
        Op::constant(TEMP, GATE_MSR as u128),
        Op::Mul { d: TAU2, a: SUM_R2, b: TEMP, k: 0 },
        Op::Div { d: TAU2, a: TAU2, b: FOUND, k: 0 },
    ]
}

/// The update of [`super`]'s module doc: the step at [`SUM_B`] applied to the pose at
/// [`POSE`], in place. `W W = w w^T - |w|^2 I` exactly, so `E`'s square term takes six
/// products; `M'` is written a column at a time, once the column's three sums are formed
/// from the old one. Works in the solve's registers (`L`, `D`, `v`), which it no longer
/// needs.
pub fn update_program() -> Vec<Op> {
    let (one, c30, bound, norm, scale) = (V, V + 1, V + 2, V + 3, V + 4);
    let w = |i: usize| SUM_B + i as u8;
    // w_i^2, then (W W)_ii; w_i w_j (i < j); their roundings; E; G (over the first nine
    // once E is formed); a column's new entries.
    let sq = |i: usize| i as u8;
    let pair = |i: usize, j: usize| 2 + (i + j) as u8;
    let r_sq = |i: usize| 6 + i as u8;
    let r_pair = |i: usize, j: usize| 8 + (i + j) as u8;
    let e = |i: usize, j: usize| 12 + (3 * i + j) as u8;
    let g = |i: usize, j: usize| (3 * i + j) as u8;
    let x = |i: usize| 21 + i as u8;
    let m = |i: usize, j: usize| POSE + (3 * i + j) as u8;
    let t = |k: usize| POSE + 9 + k as u8;
    let k30 = STEP_FRAC as u8;
    let mut p = vec![
        Op::constant(one, 1),
        Op::constant(c30, 1 << STEP_FRAC),
        Op::constant(bound, 1 << 17),
        Op::Sub { d: bound, a: bound, b: one },
    ];
    p.extend((0..3).map(|i| Op::Mul { d: sq(i), a: w(i), b: w(i), k: 0 }));
    p.push(Op::Add { d: norm, a: sq(0), b: sq(1) });
    p.push(Op::Add { d: norm, a: norm, b: sq(2) });
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        p.push(Op::Mul { d: pair(i, j), a: w(i), b: w(j), k: 0 });
        p.push(Op::Mul { d: r_pair(i, j), a: pair(i, j), b: one, k: k30 + 1 });
    }
    for i in 0..3 {
        p.push(Op::Sub { d: sq(i), a: sq(i), b: norm });
        p.push(Op::Mul { d: r_sq(i), a: sq(i), b: one, k: k30 + 1 });
        p.push(Op::Add { d: e(i, i), a: r_sq(i), b: c30 });
    }
    // W = [[0, -w2, w1], [w2, 0, -w0], [-w1, w0, 0]].
    for (i, j, k, plus) in
        [(0, 1, 2, false), (1, 0, 2, true), (0, 2, 1, true), (2, 0, 1, false), (1, 2, 0, false), (2, 1, 0, true)]
    {
        let r = r_pair(i.min(j), i.max(j));
        p.push(if plus { Op::Add { d: e(i, j), a: r, b: w(k) } } else { Op::Sub { d: e(i, j), a: r, b: w(k) } });
    }
    p.push(Op::Add { d: scale, a: c30, b: w(6) });
    for i in 0..3 {
        for j in 0..3 {
            p.push(Op::Mul { d: g(i, j), a: scale, b: e(i, j), k: k30 });
        }
    }
    for j in 0..3 {
        for i in 0..3 {
            p.push(Op::Mul { d: x(i), a: g(i, 0), b: m(0, j), k: 0 });
            for c in 1..3 {
                p.push(Op::Mul { d: TEMP, a: g(i, c), b: m(c, j), k: 0 });
                p.push(Op::Add { d: x(i), a: x(i), b: TEMP });
            }
            p.push(Op::Mul { d: x(i), a: x(i), b: one, k: k30 });
        }
        p.extend((0..3).map(|i| Op::Sat { d: m(i, j), a: x(i), b: bound }));
    }
    for k in 0..3 {
        p.push(Op::Mul { d: TEMP, a: w(3 + k), b: one, k: (STEP_FRAC - POSE_TRANSLATION_FRAC) as u8 });
        p.push(Op::Add { d: TEMP, a: TEMP, b: t(k) });
        p.push(Op::Sat { d: t(k), a: TEMP, b: bound });
    }
    p
}

/// The drift check ([`super::within_drift`]): with `f1 = |M|^2` and the start's `f0`, fails
/// when `25 f1 < 16 f0` (as `2 (25 f1) < 32 f0`) or `16 f1 > 25 f0` (as `2 (25 f0) < 32 f1`).
pub fn drift_program() -> Vec<Op> {
    let (f1, hi, lo2, u, v) = (V, V + 1, V + 2, V + 3, V + 4);
    let (lo, up) = (SCALE_DRIFT.0 * SCALE_DRIFT.0, SCALE_DRIFT.1 * SCALE_DRIFT.1);
    let mut p = frobenius(f1);
    p.extend([
        Op::constant(hi, up as u128),
        Op::constant(lo2, 2 * lo as u128),
        Op::Mul { d: u, a: f1, b: hi, k: 0 },
        Op::Mul { d: v, a: F0, b: lo2, k: 0 },
        Op::StopBelow { a: u, b: v },
        Op::Mul { d: u, a: F0, b: hi, k: 0 },
        Op::Mul { d: v, a: f1, b: lo2, k: 0 },
        Op::StopBelow { a: u, b: v },
    ]);
    p
}

/// Write `pose` at [`POSE`].
pub fn load_pose(r: &mut [i128; REGISTERS], pose: &FxPose) {
    for (k, &v) in pose.m.iter().chain(&pose.t).enumerate() {
        r[POSE as usize + k] = v as i128;
    }
}

/// The pose at [`POSE`] (each entry within 18 bits after [`update_program`]).
pub fn read_pose(r: &[i128; REGISTERS]) -> FxPose {
    let at = |k: usize| r[POSE as usize + k] as i32;
    FxPose { m: std::array::from_fn(at), t: std::array::from_fn(|k| at(9 + k)) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::splitmix::SplitMix64;
    use crate::polish::cases::{gram, program_cases};
    use crate::polish::program::{FIELD_A, FIELD_B, FIELD_D, FIELD_LAST, PROGRAM_WORDS, WORD_BITS};

    #[test]
    fn the_rom_fits_and_its_fields_hold_the_registers() {
        let words = rom().words();
        assert!(words.len() <= PROGRAM_WORDS, "{}", words.len());
        assert!(words.iter().all(|&w| w < 1 << WORD_BITS));
        assert_eq!(words.iter().filter(|&&w| w >> FIELD_LAST == 1).count(), Entry::ALL.len());
        for w in words {
            for field in [FIELD_D, FIELD_A, FIELD_B] {
                assert!((w >> field) & 63 < REGISTERS as u32);
            }
        }
        for (i, e) in Entry::ALL.iter().enumerate() {
            assert_eq!(*e as usize, i);
            assert_eq!(rom().program(i), e.program());
        }
    }

    /// Each program run on its inputs in a file of noise leaves the same outputs and the
    /// same outcome as on a clean file: it reads nothing an earlier program left. Writing a
    /// read-before-written register into a program fails this.
    #[test]
    fn each_program_reads_only_its_inputs() {
        let mut rng = SplitMix64(0x5eed_0014);
        for e in Entry::ALL {
            for _ in 0..32 {
                let mut clean = [0i128; REGISTERS];
                let mut noisy: [i128; REGISTERS] = std::array::from_fn(|_| rng.next_u64() as i128 - (1 << 63));
                for &a in &e.inputs() {
                    let v = (rng.next_u64() >> 44) as i128 - (1 << 19);
                    clean[a as usize] = v;
                    noisy[a as usize] = v;
                }
                let (rc, rn) = (run(e, &mut clean), run(e, &mut noisy));
                assert_eq!(rc.is_ok(), rn.is_ok(), "{e:?}");
                if rc.is_ok() {
                    for &a in &e.outputs() {
                        assert_eq!(clean[a as usize], noisy[a as usize], "{e:?}: register {a}");
                    }
                }
            }
        }
    }

    #[test]
    fn an_inliers_adds_sum_to_its_normal_equations() {
        let rows = [([3, -5, 7, 11, -13, 17, 19], -23), ([1 << 17, -(1 << 17), 2, 3, 4, 5, 6], 4095)];
        let mut r = [0i128; REGISTERS];
        for (j, s) in &rows {
            for (a, v) in inlier_adds(j, *s) {
                r[a as usize] += v as i128;
            }
        }
        assert_eq!(r, solve_inputs(&gram(&rows, 1)));
    }

    /// The RTL's cases take every program, and both outcomes of each that can fail.
    #[test]
    fn the_rtl_cases_take_every_program_both_ways() {
        let cases = program_cases(1, 4);
        for e in Entry::ALL {
            let failed: Vec<bool> =
                cases.iter().filter(|c| c.0 == e).map(|(_, r)| run(e, &mut r.clone()).is_err()).collect();
            assert!(failed.contains(&false), "{e:?}");
            let can_fail = e.program().iter().any(|op| matches!(op, Op::StopBelow { .. }));
            assert_eq!(failed.contains(&true), can_fail, "{e:?}");
        }
    }

    #[test]
    fn clear_zeroes_what_a_pass_adds_to_and_only_that() {
        let mut r = [7i128; REGISTERS];
        run(Entry::Clear, &mut r).unwrap();
        for (a, &v) in r.iter().enumerate() {
            assert_eq!(v == 0, Entry::Clear.outputs().contains(&(a as u8)), "register {a}");
        }
    }
}
