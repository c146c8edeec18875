//! The polish's solve as a program: a short instruction set over a register file of 64
//! 128-bit integers, and [`solve_program`], the LDL^T solve of [`super::solve`]'s
//! specification written in it. [`run`] is the bit-exact reference of the RTL that runs it
//! (`crate::rtl::polish::program::PolishProgram`, a serial multiplier and divider behind
//! the register file): both compute modulo 2^128, where the program's values never reach
//! (the module doc of [`super`] bounds them by 2^96), so the program's results are the
//! specification's.
//!
//! One instruction set for the solve and, later, the update and the gate: the arithmetic
//! of a step is a few hundred serial operations, and a program in ROM keeps the
//! sequence in one place (this file) for model and RTL alike, as the filter's pose program
//! does ([`crate::pf::POSE_PROGRAM`]).

use super::{upper, PassSums, LAMBDA_FLOOR, STEP_FRAC, STEP_LIMIT, UNKNOWNS};

/// Registers of the file.
pub const REGISTERS: usize = 64;
/// Bits of a register (the arithmetic wraps at this width).
pub const REG_BITS: u32 = 128;
/// Instructions the program ROM holds.
pub const PROGRAM_WORDS: usize = 512;

/// One instruction. Register operands are indices below [`REGISTERS`]; shifts are below 128.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// `r[d] = r[a] + r[b]`.
    Add {
        /// Destination.
        d: u8,
        /// First operand.
        a: u8,
        /// Second operand.
        b: u8,
    },
    /// `r[d] = r[a] - r[b]`.
    Sub {
        /// Destination.
        d: u8,
        /// Minuend.
        a: u8,
        /// Subtrahend.
        b: u8,
    },
    /// `r[d] = rnd_k(r[a] r[b])` (`k = 0`: the product, modulo 2^128): `((p >> (k - 1)) +
    /// 1) >> 1` without overflow, which is `(p + 2^(k-1)) >> k`.
    Mul {
        /// Destination.
        d: u8,
        /// Multiplicand.
        a: u8,
        /// Multiplier (its magnitude's bit length sets the clocks).
        b: u8,
        /// Rounding shift.
        k: u8,
    },
    /// `r[d] = (r[a] << k) / r[b]`, truncated toward zero, `r[b]` taken as unsigned (a
    /// restoring divider; a zero divisor gives a quotient of all ones).
    Div {
        /// Destination.
        d: u8,
        /// Dividend.
        a: u8,
        /// Divisor.
        b: u8,
        /// Left shift of the dividend.
        k: u8,
    },
    /// `r[d] = r[a] >> k` (arithmetic).
    Shr {
        /// Destination.
        d: u8,
        /// Operand.
        a: u8,
        /// Shift.
        k: u8,
    },
    /// `r[d] = v << k`.
    Const {
        /// Destination.
        d: u8,
        /// Value, below 64.
        v: u8,
        /// Shift.
        k: u8,
    },
    /// `r[d] = r[b]` if `r[a] > r[b]`, else `-r[b]` if `r[a] < -r[b]`, else `r[a]`.
    Clamp {
        /// Destination.
        d: u8,
        /// Operand.
        a: u8,
        /// Bound.
        b: u8,
    },
    /// Stop the program, failed, if `2 r[a] < r[b]`.
    StopBelow {
        /// Tested value.
        a: u8,
        /// Bound.
        b: u8,
    },
}

/// Field positions of an encoded instruction: kind, `d`, `a`, `b`, `k` (the RTL decodes
/// by these; its kernel repeats them as literals, checked by a const assertion there).
pub const FIELD_D: u32 = 4;
/// See [`FIELD_D`].
pub const FIELD_A: u32 = 10;
/// See [`FIELD_D`].
pub const FIELD_B: u32 = 16;
/// See [`FIELD_D`].
pub const FIELD_K: u32 = 22;
/// The ROM word's flag of the program's last instruction.
pub const FIELD_LAST: u32 = 29;
/// Bits of a ROM word.
pub const WORD_BITS: usize = 30;

/// Instruction kinds as encoded.
pub mod kind {
    /// [`super::Op::Add`].
    pub const ADD: u32 = 0;
    /// [`super::Op::Sub`].
    pub const SUB: u32 = 1;
    /// [`super::Op::Mul`].
    pub const MUL: u32 = 2;
    /// [`super::Op::Div`].
    pub const DIV: u32 = 3;
    /// [`super::Op::Shr`].
    pub const SHR: u32 = 4;
    /// [`super::Op::Const`] (`v` in the `a` field).
    pub const CONST: u32 = 5;
    /// [`super::Op::Clamp`].
    pub const CLAMP: u32 = 6;
    /// [`super::Op::StopBelow`].
    pub const STOP_BELOW: u32 = 7;
}

impl Op {
    /// The instruction's word (without the last-instruction flag).
    pub const fn encode(self) -> u32 {
        let (kind, d, a, b, k) = match self {
            Op::Add { d, a, b } => (kind::ADD, d, a, b, 0),
            Op::Sub { d, a, b } => (kind::SUB, d, a, b, 0),
            Op::Mul { d, a, b, k } => (kind::MUL, d, a, b, k),
            Op::Div { d, a, b, k } => (kind::DIV, d, a, b, k),
            Op::Shr { d, a, k } => (kind::SHR, d, a, 0, k),
            Op::Const { d, v, k } => (kind::CONST, d, v, 0, k),
            Op::Clamp { d, a, b } => (kind::CLAMP, d, a, b, 0),
            Op::StopBelow { a, b } => (kind::STOP_BELOW, 0, a, b, 0),
        };
        kind | (d as u32) << FIELD_D | (a as u32) << FIELD_A | (b as u32) << FIELD_B | (k as u32) << FIELD_K
    }

    /// `r[d] = value` as a [`Op::Const`] (`value` a number below 64 shifted left).
    pub fn constant(d: u8, value: u128) -> Op {
        let k = if value == 0 { 0 } else { value.trailing_zeros() };
        let v = value >> k;
        assert!(v < 64, "{value} is not below 64 shifted left");
        Op::Const { d, v: v as u8, k: k as u8 }
    }
}

/// The program's ROM words: each instruction's encoding, the last one flagged.
pub fn rom_words(program: &[Op]) -> Vec<u32> {
    assert!(!program.is_empty() && program.len() <= PROGRAM_WORDS);
    let last = program.len() - 1;
    program.iter().enumerate().map(|(i, op)| op.encode() | ((i == last) as u32) << FIELD_LAST).collect()
}

/// `(p + 2^(k-1)) >> k` as the RTL forms it, `(u + 1) >> 1` for `u = p >> (k - 1)`
/// without overflow (`k = 0`: `p`).
fn round_half_up(p: i128, k: u8) -> i128 {
    if k == 0 {
        p
    } else {
        let u = p >> (k - 1);
        (u >> 1) + (u & 1)
    }
}

/// Run `program` on `r`, modulo 2^128 as the RTL. `Err(pc)`: a [`Op::StopBelow`] at `pc`
/// stopped it.
pub fn run(program: &[Op], r: &mut [i128; REGISTERS]) -> Result<(), usize> {
    for (pc, &op) in program.iter().enumerate() {
        match op {
            Op::Add { d, a, b } => r[d as usize] = r[a as usize].wrapping_add(r[b as usize]),
            Op::Sub { d, a, b } => r[d as usize] = r[a as usize].wrapping_sub(r[b as usize]),
            Op::Mul { d, a, b, k } => r[d as usize] = round_half_up(r[a as usize].wrapping_mul(r[b as usize]), k),
            Op::Div { d, a, b, k } => {
                let n = r[a as usize] << k;
                let divisor = r[b as usize] as u128;
                let q = n.unsigned_abs().checked_div(divisor).unwrap_or(u128::MAX) as i128;
                r[d as usize] = if n < 0 { q.wrapping_neg() } else { q };
            }
            Op::Shr { d, a, k } => r[d as usize] = r[a as usize] >> k,
            Op::Const { d, v, k } => r[d as usize] = (v as i128) << k,
            Op::Clamp { d, a, b } => {
                let (v, bound) = (r[a as usize], r[b as usize]);
                r[d as usize] = if v > bound {
                    bound
                } else if v < bound.wrapping_neg() {
                    bound.wrapping_neg()
                } else {
                    v
                };
            }
            Op::StopBelow { a, b } => {
                if r[a as usize].wrapping_add(r[a as usize]) < r[b as usize] {
                    return Err(pc);
                }
            }
        }
    }
    Ok(())
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

/// The register of `a(i, j)`, `L_ij` or `D_j`.
fn at(i: usize, j: usize) -> u8 {
    SUM_A + upper(i, j) as u8
}

/// The solve of [`super::solve`]'s specification as a program: the damping, the LDL^T
/// factorisation with its pivot test, the two substitutions and the clamp. Inputs: `a` at
/// [`SUM_A`], `b` at [`SUM_B`]; output: the step at [`SUM_B`]; fails at a pivot below
/// half the damping.
pub fn solve_program() -> Vec<Op> {
    let n = UNKNOWNS;
    let k30 = STEP_FRAC as u8;
    let mut p = vec![Op::Add { d: TEMP, a: at(0, 0), b: at(1, 1) }];
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

/// The systems the RTL's tests solve: `random` Gram systems of 5 to 20 random rows (18-bit
/// entries, 13-bit residuals) repeated up to 4,096 rows in all, some of them rank-deficient,
/// from `seed`; then the widest (4,096 rows at full scale), a zero system, one with a
/// negative pivot (the program stops) and one whose step the clamp bounds.
pub fn solve_systems(seed: u64, random: usize) -> Vec<PassSums> {
    let mut rng = crate::splitmix::SplitMix64(seed);
    let mut out = Vec::new();
    for _ in 0..random {
        let n_rows = 5 + rng.below(16) as usize;
        let repeat = 1 + rng.below(4096 / n_rows as u64) as i64;
        let mut entry = |bits: u32| (rng.next_u64() >> (64 - bits)) as i64 - (1 << (bits - 1));
        let rows: Vec<_> = (0..n_rows).map(|_| (std::array::from_fn(|_| entry(18)), entry(13))).collect();
        out.push(gram(&rows, repeat));
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
    out.push(degenerate.clone());
    degenerate.a[upper(2, 2)] = -100;
    out.push(degenerate);
    let mut big = gram(&[], 1);
    for i in 0..UNKNOWNS {
        big.a[upper(i, i)] = 1 << 20;
    }
    big.b = [1 << 40, -(1 << 40), 0, 0, 0, 0, 1];
    out.push(big);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_program_fits_its_rom_and_its_fields() {
        let p = solve_program();
        assert!(p.len() <= PROGRAM_WORDS, "{}", p.len());
        let words = rom_words(&p);
        assert!(words.iter().all(|&w| w < 1 << WORD_BITS));
        assert_eq!(words.iter().filter(|&&w| w >> FIELD_LAST == 1).count(), 1);
        // Registers used stay in the file.
        for op in p {
            let w = op.encode();
            for field in [FIELD_D, FIELD_A, FIELD_B] {
                assert!((w >> field) & 63 < REGISTERS as u32);
            }
        }
    }

    #[test]
    fn each_op_computes_as_documented() {
        let mut r = [0i128; REGISTERS];
        r[1] = -7;
        r[2] = 3;
        r[3] = i128::MAX;
        let prog = [
            Op::Add { d: 4, a: 1, b: 2 },
            Op::Sub { d: 5, a: 1, b: 2 },
            Op::Mul { d: 6, a: 1, b: 2, k: 0 },
            Op::Mul { d: 7, a: 1, b: 2, k: 1 }, // -21 / 2 rounds half up to -10
            Op::Mul { d: 8, a: 1, b: 2, k: 2 }, // -21 / 4 = -5.25 to -5
            Op::Div { d: 9, a: 1, b: 2, k: 0 }, // -7 / 3 truncates to -2
            Op::Div { d: 10, a: 1, b: 2, k: 2 },
            Op::Shr { d: 11, a: 1, k: 1 }, // -4 (arithmetic)
            Op::constant(12, 48 << 20),
            Op::Clamp { d: 13, a: 1, b: 2 },
            Op::Clamp { d: 14, a: 2, b: 12 },
            Op::Add { d: 15, a: 3, b: 3 },       // wraps
            Op::Div { d: 16, a: 2, b: 0, k: 0 }, // zero divisor: all ones
        ];
        run(&prog, &mut r).unwrap();
        assert_eq!(r[4..=14], [-4, -10, -21, -10, -5, -2, -9, -4, 48 << 20, -3, 3]);
        assert_eq!(r[15], -2);
        assert_eq!(r[16], -1);
        assert_eq!(run(&[Op::StopBelow { a: 1, b: 2 }], &mut r), Err(0));
        assert_eq!(run(&[Op::StopBelow { a: 2, b: 2 }], &mut r), Ok(()));
        assert_eq!(Op::constant(0, 0), Op::Const { d: 0, v: 0, k: 0 });
    }
}
