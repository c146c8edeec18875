//! `PolishPass`: one found point of a polish pass ([`crate::polish::PassSums::add_point`]
//! with [`crate::polish::jacobian`]), in two stages that overlap from one point to the next.
//!
//! **The front** forms the residual's square and the Jacobian row on a borrowed pipelined
//! multiplier (the sequencer's `PipeMul`, idle after the filter: `mul_*`, a product three
//! clocks after the clock that issues it) and adds the statistics into `PolishProgram`'s
//! register file (`add*`): `s^2` to `SUM_R2`, 1 to `FOUND`, and for an inlier (`gated` and
//! `s^2 <= tau2`) 1 to `INLIERS`. Schedule, clock `k` after the point is taken: `s s`
//! issued at 0; the nine products of `x = q - t` and `n` at 1 to 9; `s^2` back and added at
//! 3, `found` at 4 (an outlier ends there), `inliers` at 5; the cross and dot products
//! combined at 4 to 12 in one accumulator, each rounded and saturated into its Jacobian
//! entry as the next starts (at 6, 8, 10 and 13). At 13 an inlier's row `J` and `s` pass to
//! the product stage (waiting there while it is busy). A point takes 14 clocks if an inlier,
//! 5 if not, and `ready` the clock after.
//!
//! **The product stage** forms the row's 28 products `J_r J_c` (`a`) and 7 products `J_r s`
//! (`b`) on [`PRODUCT_MULS`] DSP48A1 multipliers ([`Mul18`]), product `i` (in the register
//! file's order, [`upper`] then `b`) on multiplier `i mod 3` at slot `i / 3` (12 slots),
//! and adds each into its own 48-bit accumulator: a 16-word bank per multiplier, read at
//! the slot and written with the sum the clock after. The sums are exact integers, so
//! accumulating them apart and adding them into the register file once gives the register
//! file's sums bit for bit.
//!
//! **The flush** (`flush`, once the pass's last point is in): once both stages are empty,
//! the 35 accumulators are added into registers 0 to 34, one a clock, and zeroed (37
//! clocks); `idle` rises when it is over. A reset zeroes the banks the same way, without the
//! adds. Tests: `fpga/tests/polish_pass.rs` and `sim/tests/polish_pass.rs`, against
//! `add_point` on random points.
//!
//! This file holds the ports, registers and sub-blocks; the clocked logic (one `update`)
//! is `pass_kernel_rtl.rs`.

use crate::polish::programs::SUM_B;
use crate::polish::{upper, UNKNOWNS};
use crate::search::mul18_rtl::Mul18;
use rust_hdl::prelude::*;

#[path = "pass_kernel_rtl.rs"]
mod kernel;

/// The product stage's multipliers (DSP48A1s).
pub const PRODUCT_MULS: usize = 3;
/// Products of an inlier's row: `a`'s upper triangle and `b`.
pub const ROW_PRODUCTS: usize = SUM_B as usize + UNKNOWNS;
/// The product stage's slots: the row's products over the multipliers.
pub const PRODUCT_SLOTS: usize = ROW_PRODUCTS.div_ceil(PRODUCT_MULS);
/// Clocks of the flush: a read and an add for each accumulator, one behind the other.
pub const FLUSH_CLOCKS: u64 = ROW_PRODUCTS as u64 + 2;

/// The pass's per-point datapath.
#[derive(LogicBlock)]
pub struct PolishPass {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset: idle, and the accumulators zeroed (`idle` low until they are).
    pub reset: Signal<In, Bit>,
    /// Gate on: points with `s^2 <= tau2` are inliers (off: the statistics only).
    pub gated: Signal<In, Bit>,
    /// The gate.
    pub tau2: Signal<In, Bits<32>>,
    /// The scale held ([`crate::polish::ScaleStep::Held`]): the row's scale entry is 0.
    pub scale_held: Signal<In, Bit>,
    /// The pose's translation (3 x 18 bits, x low).
    pub t: Signal<In, Bits<54>>,
    /// Take a point (while `ready`).
    pub in_valid: Signal<In, Bit>,
    /// Its image (3 x 16 bits, x low, as `pack_point`).
    pub in_q: Signal<In, Bits<48>>,
    /// Its nearest stored point's normal (3 x 16 bits).
    pub in_n: Signal<In, Bits<48>>,
    /// Its signed residual (13 bits).
    pub in_s: Signal<In, Bits<13>>,
    /// The front is free: a point may come.
    pub ready: Signal<Out, Bit>,
    /// The pass's points are all in: add the accumulators into the register file once both
    /// stages are empty (a pulse).
    pub flush: Signal<In, Bit>,
    /// Nothing in flight, no flush pending or running: the register file holds every sum.
    pub idle: Signal<Out, Bit>,
    /// Multiplier: take `mul_a`, `mul_b`.
    pub mul_go: Signal<Out, Bit>,
    /// Multiplicand (26-bit two's complement).
    pub mul_a: Signal<Out, Bits<26>>,
    /// Multiplier (18-bit two's complement).
    pub mul_b: Signal<Out, Bits<18>>,
    /// The product of the pair issued three clocks before.
    pub mul_product: Signal<In, Bits<44>>,
    /// Add `add_data` to register `add_addr`.
    pub add: Signal<Out, Bit>,
    /// Register.
    pub add_addr: Signal<Out, Bits<6>>,
    /// Value (48-bit two's complement).
    pub add_data: Signal<Out, Bits<48>>,
    run: DFF<Bit>,
    k: DFF<Bits<4>>,
    img: DFF<Bits<48>>,
    n: DFF<Bits<48>>,
    s: DFF<Bits<13>>,
    inlier: DFF<Bit>,
    /// The cross sums and the dot product, one after another.
    acc: DFF<Bits<38>>,
    j0: DFF<Bits<18>>,
    j1: DFF<Bits<18>>,
    j2: DFF<Bits<18>>,
    /// The product stage: its row (`J` 0 to 6, then `s`), busy, its slot.
    row_j: [DFF<Bits<18>>; 8],
    pbusy: DFF<Bit>,
    pk: DFF<Bits<4>>,
    /// Per multiplier: a product of the slot `pslot` comes out of it (the sum is written).
    pv: [DFF<Bit>; 3],
    pslot: DFF<Bits<4>>,
    /// Per multiplier: `row | col << 3 | valid << 6` of its product at each slot.
    order: [ROM<Bits<7>, 4>; 3],
    mul: [Mul18; 3],
    bank: [RAM<Bits<48>, 4>; 3],
    /// The flush: asked for; reading (`fslot`, `fmul`, register `freg`); adding the word
    /// read (`fd*`); without the adds (after a reset).
    fpend: DFF<Bit>,
    fl: DFF<Bit>,
    fslot: DFF<Bits<4>>,
    fmul: DFF<Bits<2>>,
    freg: DFF<Bits<6>>,
    fd: DFF<Bit>,
    fdslot: DFF<Bits<4>>,
    fdmul: DFF<Bits<2>>,
    fdreg: DFF<Bits<6>>,
    fquiet: DFF<Bit>,
    q0e: Signal<Local, Bits<26>>,
    q1e: Signal<Local, Bits<26>>,
    q2e: Signal<Local, Bits<26>>,
    t0e: Signal<Local, Bits<26>>,
    t1e: Signal<Local, Bits<26>>,
    t2e: Signal<Local, Bits<26>>,
    s26: Signal<Local, Bits<26>>,
    p48: Signal<Local, Bits<48>>,
    x0: Signal<Local, Bits<26>>,
    x1: Signal<Local, Bits<26>>,
    x2: Signal<Local, Bits<26>>,
    n0: Signal<Local, Bits<18>>,
    n1: Signal<Local, Bits<18>>,
    n2: Signal<Local, Bits<18>>,
    s18: Signal<Local, Bits<18>>,
    p38: Signal<Local, Bits<38>>,
    acc_base: Signal<Local, Bits<38>>,
    r: Signal<Local, Bits<25>>,
    jsat: Signal<Local, Bits<18>>,
    word: [Signal<Local, Bits<7>>; 3],
    row: [Signal<Local, Bits<3>>; 3],
    col: [Signal<Local, Bits<3>>; 3],
    ja: [Signal<Local, Bits<18>>; 3],
    jb: [Signal<Local, Bits<18>>; 3],
    pw: [Signal<Local, Bits<36>>; 3],
    pe: [Signal<Local, Bits<48>>; 3],
    fword: Signal<Local, Bits<48>>,
}

/// Multiplier `m`'s ROM: at slot `j`, product `i = 3 j + m` of a row (`i` below 28: `a`'s
/// upper triangle in [`upper`]'s order; then `b`'s) as `row | col << 3 | 1 << 6` (column
/// 7: the residual); 0 past the row's last product.
fn product_order(m: usize) -> Vec<u64> {
    let mut words = vec![0u64; ROW_PRODUCTS];
    for r in 0..UNKNOWNS {
        for c in r..UNKNOWNS {
            words[upper(r, c)] = (r | c << 3 | 1 << 6) as u64;
        }
        words[SUM_B as usize + r] = (r | 7 << 3 | 1 << 6) as u64;
    }
    (0..PRODUCT_SLOTS).map(|j| words.get(PRODUCT_MULS * j + m).copied().unwrap_or(0)).collect()
}

fn order_rom(m: usize) -> ROM<Bits<7>, 4> {
    ROM::new(
        product_order(m).iter().enumerate().map(|(j, &w)| (Bits::<4>::from(j as u64), Bits::<7>::from(w))).collect(),
    )
}

impl Default for PolishPass {
    fn default() -> Self {
        Self::new()
    }
}

impl PolishPass {
    /// Idle.
    pub fn new() -> Self {
        PolishPass {
            clock: Default::default(),
            reset: Default::default(),
            gated: Default::default(),
            tau2: Default::default(),
            scale_held: Default::default(),
            t: Default::default(),
            in_valid: Default::default(),
            in_q: Default::default(),
            in_n: Default::default(),
            in_s: Default::default(),
            ready: Default::default(),
            flush: Default::default(),
            idle: Default::default(),
            mul_go: Default::default(),
            mul_a: Default::default(),
            mul_b: Default::default(),
            mul_product: Default::default(),
            add: Default::default(),
            add_addr: Default::default(),
            add_data: Default::default(),
            run: Default::default(),
            k: Default::default(),
            img: Default::default(),
            n: Default::default(),
            s: Default::default(),
            inlier: Default::default(),
            acc: Default::default(),
            j0: Default::default(),
            j1: Default::default(),
            j2: Default::default(),
            row_j: Default::default(),
            pbusy: Default::default(),
            pk: Default::default(),
            pv: Default::default(),
            pslot: Default::default(),
            order: [order_rom(0), order_rom(1), order_rom(2)],
            mul: Default::default(),
            bank: Default::default(),
            fpend: Default::default(),
            fl: Default::default(),
            fslot: Default::default(),
            fmul: Default::default(),
            freg: Default::default(),
            fd: Default::default(),
            fdslot: Default::default(),
            fdmul: Default::default(),
            fdreg: Default::default(),
            fquiet: Default::default(),
            q0e: Default::default(),
            q1e: Default::default(),
            q2e: Default::default(),
            t0e: Default::default(),
            t1e: Default::default(),
            t2e: Default::default(),
            s26: Default::default(),
            p48: Default::default(),
            x0: Default::default(),
            x1: Default::default(),
            x2: Default::default(),
            n0: Default::default(),
            n1: Default::default(),
            n2: Default::default(),
            s18: Default::default(),
            p38: Default::default(),
            acc_base: Default::default(),
            r: Default::default(),
            jsat: Default::default(),
            word: Default::default(),
            row: Default::default(),
            col: Default::default(),
            ja: Default::default(),
            jb: Default::default(),
            pw: Default::default(),
            pe: Default::default(),
            fword: Default::default(),
        }
    }
}

// The host's deadline allows for the flush (`run_request::PASS_END_CLOCKS`).
const _: () = assert!(FLUSH_CLOCKS + PRODUCT_SLOTS as u64 + 1 + 8 < crate::protocol::run_request::PASS_END_CLOCKS);
