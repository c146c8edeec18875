//! PF-ICP hardware side.
//!
//! - [`format`]: the fixed-point formats shared by host, reference and RTL.
//! - [`pipeline`]: the cycle-accurate reference of the nearest-neighbour pipeline.
//! - [`weights`]: the cycle-accurate reference of the weight stage (minimum cost, exp table).
//! - [`particle_weights`]: the two wired together, as the RTL top.
//! - [`protocol`]: the wire protocol (COBS framing, CRC-16, commands), shared with the host.
//! - `rtl` (feature `rtl`): the rust_hdl RTL of the pipeline and its Verilog.
//!
//! The bit-exact reference of the pipeline, the wire protocol and (behind the `rtl`
//! feature) the rust_hdl RTL land with the hardware issues.
#![warn(missing_docs)]

pub mod board;
pub mod format;
pub mod messages;
pub mod particle_weights;
pub mod pf;
pub mod pipeline;
pub mod protocol;
#[cfg(feature = "rtl")]
pub mod rtl;
pub mod sequencer;
pub mod weights;
