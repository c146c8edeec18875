//! The on-board particle filter: its functional reference, its cycle-accurate model and
//! their RTL twin, the sequencer, with its arithmetic blocks, and the weight stage.
//!
//! - [`pf`]: the filter's bit-exact functional reference ([`pf::run`]): the Run's
//!   configuration, the loop and its records (every block's model re-exported there);
//! - the model of each of the sequencer's blocks, beside its RTL twin of the same stem
//!   (tests: `fpga/tests/sequencer_blocks.rs`): [`cordic`] (`cordic_rtl`), [`xorshift`]
//!   (`xorshift_rtl`), [`pose_program`] (`pose_program_rtl`), [`translation`]
//!   (`translation_rtl`), [`propagate`] (`propagate_rtl`), [`serial_div`]
//!   (`serial_div_rtl`), [`estimate`] (`estimate_rtl`), [`weight`] (`weight_rtl`),
//!   [`resample`] (`resample_rtl`); [`params`]: the parameters' formats they share (the
//!   vectors of `param_bank_rtl` are [`pf::run`]'s);
//! - [`sequencer`]: the cycle-accurate model of the filter's RTL (`SequencerModel`) and its
//!   clock formulas; its RTL twin `sequencer_rtl` (`PfSequencer`, its kernel's wiring in
//!   `sequencer_signals_rtl.rs` and its states' arms in `sequencer_kernel_rtl.rs`, in the
//!   order of the model's step: `signals.rs`, then `states.rs`); [`seq_state`]: their one list of states;
//! - [`weights`]: the cycle-accurate reference of the weight stage (minimum cost, exp
//!   table); its RTL twin `weights_rtl` (`WeightStage`).

pub mod cordic;
#[cfg(feature = "rtl")]
pub mod cordic_rtl;
pub mod estimate;
#[cfg(feature = "rtl")]
pub mod estimate_rtl;
#[cfg(feature = "rtl")]
pub mod param_bank_rtl;
pub mod params;
pub mod pf;
pub mod pose_program;
#[cfg(feature = "rtl")]
pub mod pose_program_rtl;
pub mod propagate;
#[cfg(feature = "rtl")]
pub mod propagate_rtl;
pub mod resample;
#[cfg(feature = "rtl")]
pub mod resample_rtl;
pub mod seq_state;
pub mod sequencer;
#[cfg(feature = "rtl")]
pub mod sequencer_rtl;
pub mod serial_div;
#[cfg(feature = "rtl")]
pub mod serial_div_rtl;
pub mod translation;
#[cfg(feature = "rtl")]
pub mod translation_rtl;
pub mod weight;
#[cfg(feature = "rtl")]
pub mod weight_rtl;
pub mod weights;
#[cfg(feature = "rtl")]
pub mod weights_rtl;
pub mod xorshift;
#[cfg(feature = "rtl")]
pub mod xorshift_rtl;
