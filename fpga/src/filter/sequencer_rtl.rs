//! `PfSequencer`: the on-board particle filter (docs/sequencer.md), the RTL of
//! [`crate::filter::pf::run`]. It owns the particle set (two halves of a 4,096 x 24 RAM), the
//! per-particle costs and weights and the state machine (its kernel in two parts: the wiring in
//! `sequencer_signals_rtl.rs`, the states' arms in `sequencer_kernel_rtl.rs`), and drives the
//! nearest-neighbour pipeline through `start` / `pose`. Its parameter vectors and its
//! arithmetic are one block a file, each the twin of the model of the same stem beside it
//! (`cordic_rtl.rs` and `cordic.rs`; tests: `fpga/tests/sequencer_blocks.rs`):
//! - [`param_bank`]: `ParamBank`, the centre, cap, floor, spread, estimate, best and current
//!   particle vectors;
//! - [`pipe_mul`]: `PipeMul`, 26 x 18 bits in LUTs, two clocks, one pair a clock;
//! - [`serial_div`]: `SerialDiv`, 48 / 24 bits (quotient below 2^24) in 24 clocks
//!   ([`crate::filter::serial_div::div_signed`]);
//! - [`xorshift`]: `Xorshift32`, the PRNG's step ([`crate::filter::xorshift::Xorshift32`]);
//! - [`cordic`]: `Cordic`, cosine and sine in 18 steps ([`crate::filter::cordic::cordic`]);
//! - [`pose_program`]: `PoseProgram`, [`crate::filter::pose_program::POSE_PROGRAM`] in ROM
//!   over a 32 x 26 register file ([`crate::filter::pose_program::run_program`]);
//! - [`propagate`]: `Propagate`, a particle's parameter moved and clamped
//!   ([`crate::filter::propagate::propagate`]);
//! - [`estimate`]: `Estimate`, the estimate and spread after a weighted sum
//!   ([`crate::filter::estimate::estimate_param`], [`crate::filter::estimate::spread`]);
//! - [`translation`]: `Translation`, a translation parameter to the pose's
//!   ([`crate::filter::translation::translation`]);
//! - [`weight`]: `Weight`, a cost excess to its weight through the exp table in ROM
//!   ([`crate::filter::weight::weight`], [`crate::filter::weight::temper`]'s exponent);
//! - [`resample`]: `Resample`, the pointer and cumulative sum of systematic resampling
//!   ([`crate::filter::resample::resample`]).
//!
//! Everything is sequential and small next to the pipeline's ~10^4 clocks per particle.
//! The cycle-accurate mirror is [`crate::filter::sequencer::SequencerModel`].

use rust_hdl::prelude::*;

#[path = "sequencer_kernel_rtl.rs"]
mod kernel;
#[path = "sequencer_signals_rtl.rs"]
mod signals;

use super::cordic_rtl::Cordic;
use super::estimate_rtl::Estimate;
use super::param_bank_rtl::ParamBank;
use super::pose_program_rtl::PoseProgram;
use super::propagate_rtl::Propagate;
use super::resample_rtl::Resample;
use super::serial_div_rtl::SerialDiv;
use super::translation_rtl::Translation;
use super::weight_rtl::Weight;
use super::xorshift_rtl::Xorshift32;
use crate::common::pipe_mul_rtl::PipeMul;

pub use crate::filter::seq_state::SeqState;

/// The particle-filter sequencer.
#[derive(LogicBlock)]
pub struct PfSequencer {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (idle, no result).
    pub reset: Signal<In, Bit>,
    /// Write `cfg_data` to configuration word `cfg_addr` (0..7 centre, 7..14 sigma0,
    /// 14..21 floor, 21 seed, 22 thr_cost, 23 thr_max, 24 the header: particles in bits
    /// 0..16, iterations 16..32, temperature exponent 32..38).
    pub cfg_we: Signal<In, Bit>,
    /// Configuration word address.
    pub cfg_addr: Signal<In, Bits<5>>,
    /// Configuration word.
    pub cfg_data: Signal<In, Bits<48>>,
    /// Start a run (when idle).
    pub go: Signal<In, Bit>,
    /// The pipeline may be started.
    pub nn_ready: Signal<In, Bit>,
    /// The pipeline's cost is presented.
    pub cost_valid: Signal<In, Bit>,
    /// The cost.
    pub cost: Signal<In, Bits<48>>,
    /// A nearest-neighbour result is presented.
    pub nn_valid: Signal<In, Bit>,
    /// Its squared distance.
    pub nn_dist: Signal<In, Bits<34>>,
    /// Start the pipeline on `pose` (one clock).
    pub start: Signal<Out, Bit>,
    /// The pose (during a run: the particle's; after it: the best's).
    pub pose: Signal<Out, Bits<216>>,
    /// A run is in progress.
    pub running: Signal<Out, Bit>,
    /// A run has finished (until the next `go` or reset).
    pub finished: Signal<Out, Bit>,
    /// Iterations completed.
    pub iterations: Signal<Out, Bits<16>>,
    /// Best cost so far.
    pub best_cost: Signal<Out, Bits<48>>,
    /// Its largest squared distance.
    pub best_max: Signal<Out, Bits<34>>,
    /// The best parameters, 24 bits each, `[a, b, c, s, phi, theta, psi]` from bit 0.
    pub params: Signal<Out, Bits<168>>,
    /// While no run is in progress, the multiplier is lent out: take `ext_a`, `ext_b`
    /// (the polish's pass, after the filter).
    pub ext_go: Signal<In, Bit>,
    /// The lent multiplier's multiplicand.
    pub ext_a: Signal<In, Bits<26>>,
    /// The lent multiplier's multiplier.
    pub ext_b: Signal<In, Bits<18>>,
    /// The multiplier's product ([`PipeMul`]'s `product`).
    pub mul_product: Signal<Out, Bits<44>>,
    /// Particle RAM write enable (observed by the co-simulation).
    pub p_we: Signal<Out, Bit>,
    /// Particle RAM write address `{half, particle, parameter}`.
    pub p_waddr: Signal<Out, Bits<12>>,
    /// Particle RAM write data.
    pub p_wdata: Signal<Out, Bits<24>>,
    // Configuration and filter state.
    n_part: DFF<Bits<9>>,
    n_iter: DFF<Bits<16>>,
    tq: DFF<Bits<6>>,
    seed: DFF<Bits<32>>,
    thr_cost: DFF<Bits<48>>,
    thr_max: DFF<Bits<34>>,
    state: DFF<SeqState>,
    ret: DFF<SeqState>,
    ret2: DFF<SeqState>,
    rng: DFF<Bits<32>>,
    k: DFF<Bits<16>>,
    iter_done: DFF<Bits<16>>,
    run_r: DFF<Bit>,
    fin_r: DFF<Bit>,
    first: DFF<Bit>,
    half: DFF<Bits<1>>,
    i: DFF<Bits<9>>,
    /// The particle whose evaluation is in flight or awaits its store.
    ie: DFF<Bits<9>>,
    /// An evaluation started by `EvLaunch` has not delivered its cost yet.
    inflight: DFF<Bit>,
    /// A delivered evaluation awaits its store (`PartStore`).
    havep: DFF<Bit>,
    j: DFF<Bits<9>>,
    pd: DFF<Bits<3>>,
    spread: DFF<Bit>,
    pa: DFF<Bits<12>>,
    cra: DFF<Bits<8>>,
    wra: DFF<Bits<8>>,
    x_r: DFF<Bits<24>>,
    /// The weight taken with `x_r` in a streamed weighted sum.
    w_r: DFF<Bits<16>>,
    /// A streamed pass's pipeline: bit 0 an address issued, bit 1 its RAM data out, bit 2
    /// (sums and weights) the next stage's operands registered.
    sq: DFF<Bits<3>>,
    off: DFF<Bits<26>>,
    start_r: DFF<Bit>,
    pose_r: DFF<Bits<216>>,
    maxd: DFF<Bits<34>>,
    costr: DFF<Bits<48>>,
    cmin: DFF<Bits<48>>,
    imin: DFF<Bits<8>>,
    best_cost_r: DFF<Bits<48>>,
    best_max_r: DFF<Bits<34>>,
    p: DFF<Bits<6>>,
    /// The temperature's binary search interval for `p`, `lo..=hi`.
    lo: DFF<Bits<6>>,
    hi: DFF<Bits<6>>,
    mask: DFF<Bits<48>>,
    cnt: DFF<Bits<9>>,
    w_sum: DFF<Bits<24>>,
    acc: DFF<Bits<48>>,
    cj: DFF<Bits<2>>,
    all48: Constant<Bits<48>>,
    sign44: Constant<Bits<44>>,
    sign48_44: Constant<Bits<48>>,
    // Memories.
    pram: RAM<Bits<24>, 12>,
    cram: RAM<Bits<82>, 8>,
    wram: RAM<Bits<16>, 8>,
    // The parameter vectors and the arithmetic, one block each.
    bank: ParamBank,
    mul: PipeMul,
    div: SerialDiv,
    xorshift: Xorshift32,
    cordic: Cordic,
    pose_prog: PoseProgram,
    propagate: Propagate,
    estimate: Estimate,
    translation: Translation,
    weight: Weight,
    resample: Resample,
    // Combinational helpers.
    mul_go: Signal<Local, Bit>,
    mul_a_in: Signal<Local, Bits<26>>,
    mul_b_in: Signal<Local, Bits<18>>,
    div_go: Signal<Local, Bit>,
    div_n_in: Signal<Local, Bits<48>>,
    rng_next: Signal<Local, Bits<32>>,
    u_hi: Signal<Local, Bits<16>>,
    ex_now: Signal<Local, Bits<48>>,
    ex_masked: Signal<Local, Bits<48>>,
    t_mid: Signal<Local, Bits<6>>,
    // Sign extensions, as a mux on the sign bit (no carry chain).
    u_hi_s18: Signal<Local, Bits<18>>,
    scale_s26: Signal<Local, Bits<26>>,
    maxd_next: Signal<Local, Bits<34>>,
}

impl Default for PfSequencer {
    fn default() -> Self {
        Self::new()
    }
}

impl PfSequencer {
    /// After reset: idle, no result; the pose program, CORDIC angles and exp table in ROM.
    pub fn new() -> Self {
        PfSequencer {
            clock: Default::default(),
            reset: Default::default(),
            cfg_we: Default::default(),
            cfg_addr: Default::default(),
            cfg_data: Default::default(),
            go: Default::default(),
            nn_ready: Default::default(),
            cost_valid: Default::default(),
            cost: Default::default(),
            nn_valid: Default::default(),
            nn_dist: Default::default(),
            start: Default::default(),
            pose: Default::default(),
            running: Default::default(),
            finished: Default::default(),
            iterations: Default::default(),
            best_cost: Default::default(),
            best_max: Default::default(),
            params: Default::default(),
            ext_go: Default::default(),
            ext_a: Default::default(),
            ext_b: Default::default(),
            mul_product: Default::default(),
            p_we: Default::default(),
            p_waddr: Default::default(),
            p_wdata: Default::default(),
            n_part: Default::default(),
            n_iter: Default::default(),
            tq: Default::default(),
            seed: Default::default(),
            thr_cost: Default::default(),
            thr_max: Default::default(),
            state: Default::default(),
            ret: Default::default(),
            ret2: Default::default(),
            rng: Default::default(),
            k: Default::default(),
            iter_done: Default::default(),
            run_r: Default::default(),
            fin_r: Default::default(),
            first: Default::default(),
            half: Default::default(),
            i: Default::default(),
            ie: Default::default(),
            inflight: Default::default(),
            havep: Default::default(),
            j: Default::default(),
            pd: Default::default(),
            spread: Default::default(),
            pa: Default::default(),
            cra: Default::default(),
            wra: Default::default(),
            x_r: Default::default(),
            w_r: Default::default(),
            sq: Default::default(),
            off: Default::default(),
            start_r: Default::default(),
            pose_r: Default::default(),
            maxd: Default::default(),
            costr: Default::default(),
            cmin: Default::default(),
            imin: Default::default(),
            best_cost_r: Default::default(),
            best_max_r: Default::default(),
            p: Default::default(),
            lo: Default::default(),
            hi: Default::default(),
            mask: Default::default(),
            cnt: Default::default(),
            w_sum: Default::default(),
            acc: Default::default(),
            cj: Default::default(),
            all48: Constant::new(Bits::<48>::from((1u64 << 48) - 1)),
            sign44: Constant::new(Bits::<44>::from(1u64 << 43)),
            sign48_44: Constant::new(Bits::<48>::from(1u64 << 43)),
            pram: Default::default(),
            cram: Default::default(),
            wram: Default::default(),
            bank: ParamBank::new(),
            mul: PipeMul::new(),
            div: SerialDiv::new(),
            xorshift: Xorshift32::new(),
            cordic: Cordic::new(),
            pose_prog: PoseProgram::new(),
            propagate: Propagate::new(),
            estimate: Estimate::new(),
            translation: Translation::new(),
            weight: Weight::new(),
            resample: Resample::new(),
            mul_go: Default::default(),
            mul_a_in: Default::default(),
            mul_b_in: Default::default(),
            div_go: Default::default(),
            div_n_in: Default::default(),
            rng_next: Default::default(),
            u_hi: Default::default(),
            ex_now: Default::default(),
            ex_masked: Default::default(),
            t_mid: Default::default(),
            u_hi_s18: Default::default(),
            scale_s26: Default::default(),
            maxd_next: Default::default(),
        }
    }
}
