//! The cycle-accurate reference of the particle-filter sequencer
//! (`filter::sequencer_rtl::PfSequencer`, docs/sequencer.md): its ports, and
//! [`SequencerModel`], register for register and clock for clock the RTL, whose datapath
//! results are those of the functional reference [`crate::filter::pf::run`].
//!
//! [`SequencerModel::step`] is one rising edge (the input ports as they are before it:
//! every `DFF` takes its `d`, the RAMs read first and then write); [`SequencerModel::outputs`]
//! are the output ports after it (all from registers, except the particle RAM's write port
//! `p_we / p_waddr / p_wdata`, which is combinational from the state, the registers and the
//! RAM's read data, as in the RTL). Widths and wrap-arounds are the Verilog's: in particular
//! `i + 1 == n_part` is compared at 32 bits as the generated Verilog does (rust_hdl's own
//! simulation wraps `i + 1` at 9 bits; the two differ only for `n_part = 0`, which the
//! engine never loads: there the Verilog, and this model, never leave the propagation).
//!
//! # Clocks per phase
//!
//! Measured on the model and checked exactly by `tests/sequencer_model.rs` (`n` particles;
//! a state waiting for the pipelined multiplier spends 3 clocks in it, for the divider 25;
//! the streamed passes take one particle or cost a clock, plus their pipeline's latency):
//!
//! | phase | clocks | states |
//! |---|---|---|
//! | pose ([`POSE_CLOCKS`]) | 220 | 3 x (CorInit, 18 CorStep, CorCos, CorSin) = 63, PoseScale 1, 23 multiplies x 6 (OpFetch, OpA, OpB, 3 OpMul), 5 additions x 3, 3 PoseT |
//! | evaluation of the start and each estimate | 1 + pipeline | EvStart (1 when `nn_ready`), EvWait from `start` to the clock `cost_valid` is taken |
//! | evaluation of the particles, per iteration | 3n + the last one's (1 + pipeline + 1), or more | EvLaunch (1 when `nn_ready`) starts particle `i` and goes on propagating `i + 1`; EvSync waits until its cost is in (1 clock when the evaluation took less than the next particle's propagation and pose, 269 clocks), PartStore stores it, EvSync again launches the next or, after the last, waits for it and goes on to the temperature |
//! | propagation, per parameter ([`PROPAGATE_CLOCKS`]) | 7 | PropAddr, PropRead, 3 PropMul, PropClamp, PropWrite (49 per particle, + PartStore 1 for its evaluation; IterBegin 1 per iteration) |
//! | temperature, per pass ([`temper_pass_clocks`]) | n + 5 | TPass, TRun (n + 2: a cost a clock, 2 of RAM latency), TCheck, TMid; passes: a binary search over the bit length `p` in 0..=48 from 24, 5 or 6 ([`MAX_TEMPER_PASSES`]); then TSet 1 |
//! | weights ([`weight_clocks`]) | n + 4 | WRun (n + 3), BestCheck; + 9 when the best particle beats the best so far (BestRec, BestAddr, 7 BestData) |
//! | estimate, spread: per parameter ([`sum_clocks`]) | n + 33 | SumBegin, SumRun (n + 6: a particle a clock; RAM 2, operand register 1, multiplier 2, the last addition 1), SumDivGo, 25 SumDivWait; 7 parameters each: 14 (n + 33) |
//! | the estimate's evaluation, region, stop | 224 + evaluation | EstEval, pose, evaluation, EstDone, Centre, StopCheck |
//! | resampling, not after the last iteration ([`resample_clocks`]) | 9 + 10n + 7a | RsBegin, 3 RsL, RsWData, 3 RsWMul, RsDone; a = the last survivor's index: per advance RsLoop, RsWAddr, RsWWait, RsWData, 3 RsWMul; per survivor RsLoop, CpWait, 7 CpData, CpNext |
//! | a run ([`run_clocks`]) | 222 + start evaluation + iterations + 222 | go (Idle), pose, evaluation, StartDone; ...; Fin, pose, FinDone |
//!
//! [`clocks_per_iteration`] adds these up exactly. Without the pipeline's time an iteration
//! is `n (49 + 220 + 1) + 14 (n + 33) + passes (n + 5) + 11n + 7a + 248` clocks (with the best
//! copied): for 50 particles, 2,230 to 2,630 clocks besides the particles' propagation and
//! poses (13,500, hidden behind their evaluations when these take at least 269 clocks each),
//! against ~23,400 with the serial multiplier (18 clocks), the 48-step divider and the
//! unstreamed passes. `tests/sequencer_model.rs` (`fifty_particles_...`) measures it.

mod clocks;
mod model;
mod stand_in;

pub use crate::filter::seq_state::SeqState;
pub use clocks::*;
pub use model::SequencerModel;
pub use stand_in::PipelineStandIn;

use crate::common::format::FxPose;

/// Input ports (before an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SeqInputs {
    /// Synchronous reset.
    pub reset: bool,
    /// Configuration write.
    pub cfg_we: bool,
    /// Configuration word address (5 bits).
    pub cfg_addr: u8,
    /// Configuration word (48 bits).
    pub cfg_data: u64,
    /// Start a run.
    pub go: bool,
    /// The pipeline may be started.
    pub nn_ready: bool,
    /// The pipeline's cost is presented.
    pub cost_valid: bool,
    /// The cost (48 bits).
    pub cost: u64,
    /// A nearest-neighbour result is presented.
    pub nn_valid: bool,
    /// Its squared distance (34 bits).
    pub nn_dist: u64,
    /// While no run is in progress: the lent multiplier takes `ext_a`, `ext_b`.
    pub ext_go: bool,
    /// The lent multiplier's multiplicand (26 bits).
    pub ext_a: u64,
    /// The lent multiplier's multiplier (18 bits).
    pub ext_b: u64,
}

/// Output ports (after an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SeqOutputs {
    /// Start the pipeline (one clock).
    pub start: bool,
    /// The pose (216 bits, [`FxPose::pack`]).
    pub pose: [u64; 4],
    /// A run is in progress.
    pub running: bool,
    /// A run has finished.
    pub finished: bool,
    /// Iterations completed.
    pub iterations: u16,
    /// Best cost so far.
    pub best_cost: u64,
    /// Its largest squared distance.
    pub best_max: u64,
    /// The best parameters, 24 bits each from bit 0 (168 bits).
    pub params: [u64; 3],
    /// Particle RAM write enable.
    pub p_we: bool,
    /// Its address `{half, particle, parameter}` (12 bits).
    pub p_waddr: u16,
    /// Its data (24 bits).
    pub p_wdata: u32,
    /// The multiplier's product (44 bits).
    pub mul_product: u64,
}

/// The configuration writes that load a [`crate::filter::pf::PfConfig`] (word address, 48-bit word),
/// in the order the board's engine writes them.
pub fn config_writes(cfg: &crate::filter::pf::PfConfig) -> Vec<(u8, u64)> {
    let mut w: Vec<(u8, u64)> = Vec::with_capacity(25);
    for d in 0..crate::filter::pf::PARAMS {
        w.push((d as u8, cfg.centre[d] as u32 as u64 & 0xff_ffff));
    }
    for d in 0..crate::filter::pf::PARAMS {
        w.push((7 + d as u8, cfg.sigma0[d] as u64));
    }
    for d in 0..crate::filter::pf::PARAMS {
        w.push((14 + d as u8, cfg.floor[d] as u64));
    }
    w.push((21, cfg.seed as u64));
    w.push((22, cfg.thr_cost));
    w.push((23, cfg.thr_max));
    w.push((24, cfg.particles as u64 | (cfg.iterations as u64) << 16 | (cfg.temper_exp as u64 & 63) << 32));
    w
}

/// The pose of a packed 216-bit pose word.
pub fn unpack_pose(w: &[u64; 4]) -> FxPose {
    let field = |k: usize| -> i32 {
        let at = 18 * k;
        let (word, off) = (at / 64, at % 64);
        let mut raw = w[word] >> off;
        if off + 18 > 64 {
            raw |= w[word + 1] << (64 - off);
        }
        (((raw & 0x3_ffff) << 46) as i64 >> 46) as i32
    };
    FxPose { m: std::array::from_fn(field), t: std::array::from_fn(|k| field(9 + k)) }
}
