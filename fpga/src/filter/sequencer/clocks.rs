//! The sequencer's clock formulas, phase by phase (measured on the model;
//! `tests/sequencer_model.rs` checks them exactly): what the host's run-time bound and the
//! benches count with.

/// Clocks of one pose (`cur` to `pose`: three CORDICs, the scale, the 28-step program, the
/// translations), from entering `CorInit` to leaving the last `PoseT`.
pub const POSE_CLOCKS: u64 = 3 * (1 + 18 + 2) + 1 + 23 * MUL_OP_CLOCKS + 5 * 3 + 3;
/// Clocks of a multiply step of the pose program (fetch, two operands, 3 in `OpMul`).
const MUL_OP_CLOCKS: u64 = 3 + MUL_WAIT;
/// Clocks a state waiting for the pipelined multiplier spends in it (its two stages and the
/// clock that takes the product).
pub const MUL_WAIT: u64 = 3;
/// Clocks a state waiting for the serial divider spends in it (24 steps and the clock that
/// takes the quotient).
pub const DIV_WAIT: u64 = 25;
/// Clocks of the propagation of one parameter of one particle.
pub const PROPAGATE_CLOCKS: u64 = 4 + MUL_WAIT;

/// Clocks of one temperature pass over `n` costs (`TPass`, `TRun`: a cost a clock and two of
/// RAM latency, `TCheck`, `TMid`).
pub const fn temper_pass_clocks(n: u64) -> u64 {
    n + 5
}

/// The most temperature passes: a binary search over the 49 candidate bit lengths.
pub const MAX_TEMPER_PASSES: u64 = 6;

/// Clocks of one parameter of the estimate or of the spread over `n` particles (`SumBegin`,
/// `SumRun`: a particle a clock and six of RAM, register and multiplier latency,
/// `SumDivGo`, `SumDivWait`).
pub const fn sum_clocks(n: u64) -> u64 {
    n + 8 + DIV_WAIT
}

/// Clocks of the weights over `n` costs (`WRun`: a cost a clock and three of latency;
/// `BestCheck`), without the best's copy.
pub const fn weight_clocks(n: u64) -> u64 {
    n + 4
}

/// Clocks of a resampling of `n` particles whose pointer advances `a` times: `RsBegin`,
/// `RsL`, `RsWData` and `RsWMul` for `w_0`, `RsDone`; an advance: `RsLoop`, `RsWAddr`,
/// `RsWWait`, `RsWData`, `RsWMul`; a copy: `RsLoop`, `CpWait`, a `CpData` per parameter,
/// `CpNext`.
pub const fn resample_clocks(n: u64, a: u64) -> u64 {
    (3 + 2 * MUL_WAIT) + (4 + MUL_WAIT) * a + (3 + crate::filter::pf::PARAMS as u64) * n
}

/// What the clocks of an iteration depend on besides the particle count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IterationShape {
    /// Particles.
    pub particles: u64,
    /// Clocks in the states that wait for or launch the pipeline over the iteration:
    /// `EvLaunch` and `EvSync` for the particles, whose evaluations run while the next
    /// particle is propagated and posed (at least `3 n` plus the last one's evaluation, more
    /// when an evaluation outlasts a propagation and pose), and `EvStart` and `EvWait` for
    /// the estimate (`1 +` clocks from `start` to `cost_valid`, when ready).
    pub eval_clocks: u64,
    /// Temperature passes: the steps of the binary search for the bit length of the median
    /// excess (5 or 6, [`MAX_TEMPER_PASSES`]).
    pub temper_passes: u64,
    /// The best particle beat the best so far (its record and parameters are copied).
    pub best_copied: bool,
    /// `None` after the last iteration, else the resampling pointer's advances (the index
    /// of the last survivor).
    pub resample_advances: Option<u64>,
}

/// Clocks of one iteration, from entering `IterBegin` to entering the next `IterBegin`
/// (or `Fin`).
pub fn clocks_per_iteration(s: &IterationShape) -> u64 {
    let n = s.particles;
    let p = crate::filter::pf::PARAMS as u64;
    let propagate = 1 + n * (p * PROPAGATE_CLOCKS + POSE_CLOCKS + 1);
    let temper = s.temper_passes * temper_pass_clocks(n) + 1;
    let weights = weight_clocks(n) + if s.best_copied { 2 + p } else { 0 };
    let sums = 2 * p * sum_clocks(n);
    let estimate = 1 + POSE_CLOCKS + 3;
    let resample = s.resample_advances.map_or(0, |a| resample_clocks(n, a));
    propagate + s.eval_clocks + temper + weights + sums + estimate + resample
}

/// Clocks of a run, from the clock `go` is taken to the edge `finished` rises: the start's
/// pose and evaluation (`start_eval_clocks` in `EvStart` and `EvWait`), the iterations, the
/// best's pose.
pub fn run_clocks(start_eval_clocks: u64, iterations: &[IterationShape]) -> u64 {
    1 + POSE_CLOCKS + start_eval_clocks + 1 + iterations.iter().map(clocks_per_iteration).sum::<u64>() + 2 + POSE_CLOCKS
}
