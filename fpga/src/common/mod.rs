//! What every concept shares: the fixed-point formats, the tests' stimulus generator, and
//! (feature `rtl`) the RTL's shared helpers, the Verilog of each design and the pipelined
//! multiplier the filter and the polish share.
//!
//! - [`format`]: the fixed-point formats shared by host, reference and RTL;
//! - [`splitmix`]: the seeded generator of the tests' and fuzzers' stimulus;
//! - `rtl` (feature `rtl`): sign extension, the pose word, Verilog post-processing;
//! - `verilog` (feature `rtl`): the `*_verilog` functions, the Verilog of each design;
//! - `pipe_mul_rtl` (feature `rtl`): `PipeMul`, 26 x 18 bits in LUTs, two clocks, one pair
//!   a clock (the sequencer's and the polish pass's multiplier; its model is the plain
//!   product inside [`crate::filter::sequencer::SequencerModel`]).

pub mod format;
#[cfg(feature = "rtl")]
pub mod pipe_mul_rtl;
#[cfg(feature = "rtl")]
pub mod rtl;
pub mod splitmix;
#[cfg(feature = "rtl")]
pub mod verilog;
