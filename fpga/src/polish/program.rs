//! The polish's instruction set: nine instructions over a register file of 64 128-bit
//! integers, their ROM encoding and [`Rom`], several programs laid out in one ROM, each
//! run from its first word to its flagged last. [`run`] is the bit-exact reference of the
//! RTL that runs them (`crate::polish::program_rtl::PolishProgram`, a serial multiplier and
//! divider behind the register file): both compute modulo 2^128, where the polish's
//! programs never reach (the module doc of [`super`] bounds them by 2^96), so the
//! programs' results are the specification's. The programs themselves are in
//! [`super::programs`].
//!
//! One instruction set for the polish's arithmetic (the solve, the gate, the update, the
//! drift check): a step is a few hundred serial operations, and programs in ROM keep the
//! sequence in one place for model and RTL alike, as the filter's pose program does
//! ([`crate::filter::pf::POSE_PROGRAM`]).

/// Registers of the file.
pub const REGISTERS: usize = 64;
/// Bits of a register (the arithmetic wraps at this width).
pub const REG_BITS: u32 = 128;
/// Instructions the program ROM holds.
pub const PROGRAM_WORDS: usize = 512;
/// Bits of a divisor the divider takes (the programs' divisors are below 2^48: a pivot
/// `D_j` below 2^47, a count of found points below 2^13); the remainder then fits 65 bits.
pub const DIVISOR_BITS: u32 = 64;
/// Bits of the `add` port's arithmetic: `r = sext(r + v)` over the low [`ADD_BITS`] bits
/// ([`add_port`]); a pass's sums never leave them (`|a| <= 2^46` for 4,096 points).
pub const ADD_BITS: u32 = 48;

/// The `add` port: `r + v` over the low [`ADD_BITS`] bits, sign-extended (the pass adds
/// its terms so to zeroed sums, which stay within those bits).
pub fn add_port(r: i128, v: i64) -> i128 {
    let s = r.wrapping_add(v as i128);
    (s << (128 - ADD_BITS)) >> (128 - ADD_BITS)
}

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
    /// restoring divider over a divisor of at most [`DIVISOR_BITS`] bits: a zero divisor
    /// or a wider one gives a quotient of all ones).
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
    /// Two's complement saturation: `r[d] = r[b]` if `r[a] > r[b]`, else `-r[b] - 1` if
    /// `r[a] < -r[b] - 1`, else `r[a]` (`r[b] = 2^17 - 1`: the formats' `sat18`).
    Sat {
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
    /// [`super::Op::Sat`].
    pub const SAT: u32 = 8;
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
            Op::Sat { d, a, b } => (kind::SAT, d, a, b, 0),
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

/// Clocks the RTL's add takes at most (`alu`, then `flush` until no segment carry is
/// pending: a carry crosses the three segment boundaries one a clock, then a clock to see
/// none is left).
const ADD_CLOCKS: u64 = 1 + 4;

impl Op {
    /// The most clocks the RTL (`crate::polish::program_rtl::PolishProgram`) takes for
    /// this instruction, from its `fetch` to its `write` (or its stop test), whatever the
    /// operands: `fetch`, `operand` and `exec`, then
    /// - an add, a subtract, a stop test: one add and `write` (or the test);
    /// - a shift right by `k`: an add, [`shift_clocks`]`(k, 0)` shift clocks, the end of
    ///   `round` and `write`;
    /// - a constant shifted by `k`: [`shift_clocks`]`(k, 0)` shift clocks and the add's
    ///   issue, an add, `write`;
    /// - a product: two multiplier bits a clock over at most [`REG_BITS`] bits and the
    ///   clock that ends it, a flush, [`shift_clocks`]`(k, 1)` shift clocks and the rounding add,
    ///   `write`;
    /// - a quotient: the dividend's [`shift_clocks`]`(k, 0)` shift clocks and the add's
    ///   issue, an add (its magnitude), `div_start`, the skip's last clock (leading zeros
    ///   skip eight a clock), the first bit's low half, a clock a quotient bit over at most
    ///   [`REG_BITS`] bits, the sign's add, `write`;
    /// - a clamp or a saturation: up to three adds with their tests, `write`.
    ///
    /// The Verilated test (`sim/tests/polish_program.rs`) checks every measured program
    /// against the sum of its instructions' bounds ([`program_clocks_bound`]).
    pub const fn clocks_bound(self) -> u64 {
        const DECODE: u64 = 3;
        const WRITE: u64 = 1;
        DECODE
            + WRITE
            + match self {
                Op::Add { .. } | Op::Sub { .. } | Op::StopBelow { .. } => ADD_CLOCKS,
                Op::Shr { k, .. } => ADD_CLOCKS + shift_clocks(k, 0) + 1,
                Op::Const { k, .. } => shift_clocks(k, 0) + 1 + ADD_CLOCKS,
                Op::Mul { k, .. } => REG_BITS as u64 / 2 + 1 + (ADD_CLOCKS - 1) + shift_clocks(k, 1) + 1 + ADD_CLOCKS,
                Op::Div { k, .. } => shift_clocks(k, 0) + 1 + ADD_CLOCKS + 1 + 1 + 1 + REG_BITS as u64 + ADD_CLOCKS,
                Op::Clamp { .. } | Op::Sat { .. } => 3 * (ADD_CLOCKS + 1),
            }
    }
}

/// Clocks the RTL's shift right takes from `k` bits down to `stop` left: eight bits a
/// clock while more than eight remain, then one a clock. Its shift left, which takes eight
/// when eight remain, takes no more.
pub const fn shift_clocks(k: u8, stop: u8) -> u64 {
    let (mut left, mut clocks) = (k as u64, 0);
    while left > 8 {
        left -= 8;
        clocks += 1;
    }
    if left > stop as u64 {
        clocks += left - stop as u64;
    }
    clocks
}

/// The most clocks the RTL takes to run `program` from `go` to idle: its instructions'
/// [`Op::clocks_bound`] and the clock of `go`.
pub fn program_clocks_bound(program: &[Op]) -> u64 {
    1 + program.iter().map(|op| op.clocks_bound()).sum::<u64>()
}

/// A program's ROM words: each instruction's encoding, the last one flagged.
pub fn rom_words(program: &[Op]) -> Vec<u32> {
    assert!(!program.is_empty() && program.len() <= PROGRAM_WORDS);
    let last = program.len() - 1;
    program.iter().enumerate().map(|(i, op)| op.encode() | ((i == last) as u32) << FIELD_LAST).collect()
}

/// Programs laid out one after another in one ROM; the RTL starts one at its first word
/// (`entry`) and stops at its flagged last.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rom {
    programs: Vec<Vec<Op>>,
    starts: Vec<usize>,
}

impl Rom {
    /// `programs` in this order. Panics if one is empty or they overflow [`PROGRAM_WORDS`].
    pub fn new(programs: Vec<Vec<Op>>) -> Rom {
        let mut starts = Vec::with_capacity(programs.len());
        let mut at = 0;
        for p in &programs {
            assert!(!p.is_empty(), "an empty program");
            starts.push(at);
            at += p.len();
        }
        assert!(at <= PROGRAM_WORDS, "{at} instructions, the ROM holds {PROGRAM_WORDS}");
        Rom { programs, starts }
    }

    /// Program `i`.
    pub fn program(&self, i: usize) -> &[Op] {
        &self.programs[i]
    }

    /// The address of program `i`'s first instruction.
    pub fn entry(&self, i: usize) -> usize {
        self.starts[i]
    }

    /// The ROM's words: every program's [`rom_words`], in order.
    pub fn words(&self) -> Vec<u32> {
        self.programs.iter().flat_map(|p| rom_words(p)).collect()
    }

    /// Run program `i` on `r` ([`run`]).
    pub fn run(&self, i: usize, r: &mut [i128; REGISTERS]) -> Result<(), usize> {
        run(&self.programs[i], r)
    }
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

/// `hi` if `v > hi`, else `lo` if `v < lo`, else `v`.
fn clamp(v: i128, hi: i128, lo: i128) -> i128 {
    if v > hi {
        hi
    } else if v < lo {
        lo
    } else {
        v
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
                let q = if divisor >> DIVISOR_BITS != 0 {
                    u128::MAX
                } else {
                    n.unsigned_abs().checked_div(divisor).unwrap_or(u128::MAX)
                } as i128;
                r[d as usize] = if n < 0 { q.wrapping_neg() } else { q };
            }
            Op::Shr { d, a, k } => r[d as usize] = r[a as usize] >> k,
            Op::Const { d, v, k } => r[d as usize] = (v as i128) << k,
            Op::Clamp { d, a, b } => r[d as usize] = clamp(r[a as usize], r[b as usize], r[b as usize].wrapping_neg()),
            Op::Sat { d, a, b } => r[d as usize] = clamp(r[a as usize], r[b as usize], !r[b as usize]),
            Op::StopBelow { a, b } => {
                if r[a as usize].wrapping_add(r[a as usize]) < r[b as usize] {
                    return Err(pc);
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
            Op::constant(23, 1 << 64),
            Op::Div { d: 24, a: 2, b: 23, k: 0 }, // a divisor over 64 bits: all ones
            Op::Div { d: 25, a: 1, b: 23, k: 0 }, // negated: 1
            Op::Sat { d: 17, a: 1, b: 2 },        // -7 below -3 - 1
            Op::Sat { d: 18, a: 2, b: 2 },        // 3 is the bound
            Op::constant(19, 4),
            Op::Sat { d: 20, a: 19, b: 2 }, // 4 above 3
            Op::Sub { d: 21, a: 1, b: 1 },
            Op::Sub { d: 21, a: 21, b: 2 },
            Op::Sat { d: 22, a: 21, b: 2 }, // -3 within -4..=3
        ];
        run(&prog, &mut r).unwrap();
        assert_eq!(r[4..=14], [-4, -10, -21, -10, -5, -2, -9, -4, 48 << 20, -3, 3]);
        assert_eq!(r[15], -2);
        assert_eq!(r[16], -1);
        assert_eq!([r[17], r[18], r[20], r[22]], [-4, 3, 3, -3]);
        assert_eq!([r[24], r[25]], [-1, 1]);
        assert_eq!([add_port(5, -7), add_port((1 << 47) - 1, 1), add_port(1 << 60, 3)], [-2, -(1 << 47), 3]);
        assert_eq!(run(&[Op::StopBelow { a: 1, b: 2 }], &mut r), Err(0));
        assert_eq!(run(&[Op::StopBelow { a: 2, b: 2 }], &mut r), Ok(()));
        assert_eq!(Op::constant(0, 0), Op::Const { d: 0, v: 0, k: 0 });
    }

    #[test]
    fn a_rom_lays_programs_out_in_order_each_with_its_last_flagged() {
        let add = Op::Add { d: 1, a: 2, b: 3 };
        let rom = Rom::new(vec![vec![add; 3], vec![add], vec![add; 2]]);
        assert_eq!([rom.entry(0), rom.entry(1), rom.entry(2)], [0, 3, 4]);
        let last: Vec<usize> =
            rom.words().iter().enumerate().filter(|(_, &w)| w >> FIELD_LAST == 1).map(|(i, _)| i).collect();
        assert_eq!(last, [2, 3, 5]);
        assert!(std::panic::catch_unwind(|| Rom::new(vec![vec![add; PROGRAM_WORDS], vec![add]])).is_err());
    }
}
