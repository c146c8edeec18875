//! PF-ICP hardware side: the formats, the bit-exact references, the wire protocol (always)
//! and the rust_hdl RTL (feature `rtl`), one folder a concept. Each block's RTL twin lives
//! beside its model, in the same folder under the same name with `_rtl`
//! (`search/neighbour_pipeline.rs` and `search/neighbour_pipeline_rtl.rs`), behind the
//! feature `rtl`.
//!
//! The data path through the folders, as the board runs a Run request:
//! - [`protocol`]: the wire (COBS framing, CRC-16, the command table, error codes) and each
//!   message's layout ([`protocol::messages`], the Run request in [`protocol::run_request`]),
//!   and what each protocol version allows ([`protocol::versions`]);
//! - [`board`]: the board's configuration and the byte-level reference board
//!   ([`board::BoardModel`]) beside the RTL top and its blocks (UART, frame receiver, reply
//!   sender, command engine, ...), which take the frames in and send the replies;
//! - [`filter`]: the on-board particle filter: its functional reference ([`filter::pf`]),
//!   its cycle-accurate model ([`filter::sequencer`]) beside the sequencer's RTL and its
//!   arithmetic blocks, and the weight stage;
//! - [`search`]: the nearest-neighbour search each particle's pose is scored with: the cell
//!   grid, the transform and the neighbour pipeline (model and RTL);
//! - [`surface`]: the surface residual (distance to the nearest model point's tangent plane)
//!   and the residual stage after the search (model and RTL);
//! - [`polish`]: the on-board polish after the filter (point-to-plane Gauss-Newton with
//!   scale; its programs, its datapath, pass and control beside their models);
//! - [`designs`]: the one list of generated designs (name, Verilog generator, ports from
//!   the formats) that hdl-gen, the simulation's build script and the co-simulation read;
//! - [`common`]: the fixed-point formats, the stimulus generator, and the RTL's shared
//!   helpers and Verilog emission.
#![warn(missing_docs)]

pub mod board;
pub mod common;
pub mod designs;
pub mod filter;
pub mod polish;
pub mod protocol;
pub mod search;
pub mod surface;
