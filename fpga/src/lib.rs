//! PF-ICP hardware side: the formats, the bit-exact references, the wire protocol (always)
//! and the rust_hdl RTL (feature `rtl`).
//!
//! - [`format`]: the fixed-point formats shared by host, reference and RTL.
//! - [`grid`]: the model's cell grid and the grid search's bit-exact reference (capped at
//!   one cell).
//! - [`pipeline`]: what the nearest-neighbour search shares with its references (result
//!   ports, transform stages, scan-stream driver) and the plain brute-force reference.
//! - [`neighbour_pipeline`]: the cycle-accurate reference of the neighbour pipeline, the
//!   board's search (lanes over one scan point's candidates in its 27 cells), and its
//!   functional reference over the board's stores.
//! - [`surface`]: the surface residual (distance to the nearest model point's tangent
//!   plane), its normal format and bit-exact rule.
//! - [`surface_residual`]: the cycle-accurate reference of the residual stage
//!   (`SurfaceResidual`: the residual of each neighbour-pipeline result, and their sum).
//! - [`weights`]: the cycle-accurate reference of the weight stage (minimum cost, exp table).
//! - [`pf`]: the on-board particle filter's bit-exact functional reference (`pf::run`), its
//!   formats, CORDIC, pose program and PRNG.
//! - [`polish`]: the on-board polish's bit-exact reference (point-to-plane Gauss-Newton
//!   with scale over the board's stores); its arithmetic between passes is a set of
//!   programs ([`polish::programs`]) for the datapath that is the polish's first RTL block.
//! - [`sequencer`]: the cycle-accurate model of the filter's RTL (`PfSequencer`) and its
//!   clock formulas; [`seq_state`]: their one list of states.
//! - [`run_request`]: the Run request (the filter, then the polish) and what the board
//!   computes for it.
//! - [`protocol`]: the wire protocol (COBS framing, CRC-16, commands, error codes).
//! - [`messages`]: each command's data layout, encoded and decoded.
//! - [`board`]: the board's configuration and the byte-level reference board (`BoardModel`).
//! - [`splitmix`]: the seeded generator of the tests' and fuzzers' stimulus.
//! - [`designs`]: the one list of generated designs (name, Verilog generator, parameters,
//!   ports with their widths from the formats) that `hdl-gen` and the co-simulation read.
//! - `rtl` (feature `rtl`): the rust_hdl RTL of the board top and its blocks (the neighbour
//!   pipeline, the residual and weight stages, the sequencer, the polish), and their Verilog.
#![warn(missing_docs)]

pub mod board;
pub mod designs;
pub mod format;
pub mod grid;
pub mod messages;
pub mod neighbour_pipeline;
pub mod pf;
pub mod pipeline;
pub mod polish;
pub mod protocol;
#[cfg(feature = "rtl")]
pub mod rtl;
pub mod run_request;
pub mod seq_state;
pub mod sequencer;
pub mod splitmix;
pub mod surface;
pub mod surface_residual;
pub mod weights;
