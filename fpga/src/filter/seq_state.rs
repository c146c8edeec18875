//! The particle-filter sequencer's states, shared by the RTL ([`crate::common::rtl`]'s
//! `PfSequencer`, feature `rtl`, where it is a `LogicState`: the state register's value is
//! the index in [`SeqState::ALL`]) and the cycle-accurate model
//! ([`crate::filter::sequencer::SequencerModel`]). One list: an edit reaches both.

#[cfg(feature = "rtl")]
use rust_hdl::prelude::*;

macro_rules! seq_states {
    ($($(#[$doc:meta])* $name:ident),* $(,)?) => {
        /// The sequencer's states, in the order of the RTL's state register (`Idle` is 0).
        #[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
        #[cfg_attr(feature = "rtl", derive(LogicState))]
        #[cfg_attr(not(feature = "rtl"), derive(Default))]
        pub enum SeqState {
            #[cfg_attr(not(feature = "rtl"), default)]
            $($(#[$doc])* $name),*
        }

        impl SeqState {
            /// Every state, in the RTL's order (the index is the state register's value).
            pub const ALL: &'static [SeqState] = &[$(SeqState::$name),*];

            /// The state's name in the RTL.
            pub fn name(self) -> &'static str {
                match self {
                    $(SeqState::$name => stringify!($name)),*
                }
            }
        }
    };
}

seq_states! {
    /// Waiting for `go`.
    Idle,
    /// Pose: reduce the next angle and load the CORDIC.
    CorInit,
    /// Pose: one CORDIC step.
    CorStep,
    /// Pose: write the cosine.
    CorCos,
    /// Pose: write the sine.
    CorSin,
    /// Pose: write the scale.
    PoseScale,
    /// Pose: fetch the next program step, read its first operand.
    OpFetch,
    /// Pose: take the first operand, read the second.
    OpA,
    /// Pose: take the second operand; add, subtract or start the multiply.
    OpB,
    /// Pose: wait for the product, write it.
    OpMul,
    /// Pose: the translation fields.
    PoseT,
    /// Evaluate: start the pipeline when it is ready.
    EvStart,
    /// Evaluate: wait for the cost.
    EvWait,
    /// Particles: wait for the evaluation in flight; store it; start the next or finish.
    EvSync,
    /// Particles: start the pipeline on this particle's pose and go on propagating the
    /// next while it runs.
    EvLaunch,
    /// The start's evaluation is in: it is the first best.
    StartDone,
    /// A new iteration.
    IterBegin,
    /// Propagate: address parameter `d` of particle `i`, draw.
    PropAddr,
    /// Propagate: start the step's multiply.
    PropRead,
    /// Propagate: wait for the step, add the offset.
    PropMul,
    /// Propagate: clamp into the region.
    PropClamp,
    /// Propagate: write the parameter.
    PropWrite,
    /// The particle's cost is in: store it.
    PartStore,
    /// Temperature: a pass over the costs.
    TPass,
    /// Temperature: address cost `i`, count excesses below `2^p` (streamed, one a clock).
    TRun,
    /// Temperature: enough counted? Halve the search interval.
    TCheck,
    /// Temperature: the interval's middle is the next pass's `p`, or the search is done.
    TMid,
    /// Temperature: the exponent.
    TSet,
    /// Weights: address cost `i`, shift the excess, look up, store and sum (streamed).
    WRun,
    /// Best: a better particle?
    BestCheck,
    /// Best: read its cost record.
    BestRec,
    /// Best: take its cost, address the next parameter.
    BestAddr,
    /// Best: take parameter `d` (one a clock).
    BestData,
    /// Estimate / spread: begin parameter `d`.
    SumBegin,
    /// Estimate / spread: address particle `i`, multiply and accumulate (streamed, one a
    /// clock through the pipelined multiplier).
    SumRun,
    /// Estimate / spread: start the division.
    SumDivGo,
    /// Estimate / spread: wait for it, write the result.
    SumDivWait,
    /// The estimate is in: evaluate it.
    EstEval,
    /// The estimate's cost is in.
    EstDone,
    /// The region's centre becomes the best.
    Centre,
    /// Stop rule.
    StopCheck,
    /// Resample: draw `u0`, start `u0 W`.
    RsBegin,
    /// Resample: take `L`, read `w_0`.
    RsL,
    /// Resample: RAM latency / start `n w_i`.
    RsWAddr,
    /// Resample: RAM latency.
    RsWWait,
    /// Resample: start `n w_i`.
    RsWData,
    /// Resample: add `n w_i 2^16` to `R`.
    RsWMul,
    /// Resample: advance the pointer or copy.
    RsLoop,
    /// Resample: address the survivor's next parameter.
    CpWait,
    /// Resample: write parameter `d` (one a clock).
    CpData,
    /// Resample: the next survivor.
    CpNext,
    /// The set is resampled: swap halves.
    RsDone,
    /// Done: the best's pose.
    Fin,
    /// Done: result ready.
    FinDone,
}
