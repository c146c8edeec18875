//! The on-board particle filter: its functional reference, its cycle-accurate model and
//! their RTL twin, the sequencer, with its arithmetic blocks, and the weight stage.
//!
//! - [`pf`]: the filter's bit-exact functional reference ([`pf::run`]), its formats,
//!   CORDIC, pose program and PRNG; the model of each of the sequencer's blocks
//!   (`cordic_rtl`, `pose_program_rtl`, `propagate_rtl`, `estimate_rtl`,
//!   `translation_rtl`, `weight_rtl`, `resample_rtl`, `serial_div_rtl`, `xorshift_rtl`,
//!   `param_bank_rtl`; tests: `fpga/tests/sequencer_blocks.rs`);
//! - [`sequencer`]: the cycle-accurate model of the filter's RTL (`SequencerModel`) and its
//!   clock formulas; its RTL twin `sequencer_rtl` (`PfSequencer`, its state machine in
//!   `sequencer_kernel_rtl.rs`); [`seq_state`]: their one list of states;
//! - [`weights`]: the cycle-accurate reference of the weight stage (minimum cost, exp
//!   table); its RTL twin `weights_rtl` (`WeightStage`).

#[cfg(feature = "rtl")]
pub mod cordic_rtl;
#[cfg(feature = "rtl")]
pub mod estimate_rtl;
#[cfg(feature = "rtl")]
pub mod param_bank_rtl;
pub mod pf;
#[cfg(feature = "rtl")]
pub mod pose_program_rtl;
#[cfg(feature = "rtl")]
pub mod propagate_rtl;
#[cfg(feature = "rtl")]
pub mod resample_rtl;
pub mod seq_state;
pub mod sequencer;
#[cfg(feature = "rtl")]
pub mod sequencer_rtl;
#[cfg(feature = "rtl")]
pub mod serial_div_rtl;
#[cfg(feature = "rtl")]
pub mod translation_rtl;
#[cfg(feature = "rtl")]
pub mod weight_rtl;
pub mod weights;
#[cfg(feature = "rtl")]
pub mod weights_rtl;
#[cfg(feature = "rtl")]
pub mod xorshift_rtl;
