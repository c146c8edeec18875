//! Verilator co-simulation of the generated designs against their bit-exact references:
//!
//! | RTL (an entry of `pficp_fpga::designs::DESIGNS`; `build.rs` verilates each) | wrapper (`wrappers/<design>.rs`) | reference | lockstep |
//! |---|---|---|---|
//! | `neighbour_pipeline_verilog(P)` (docs/pipeline.md, the neighbour pipeline), P in [`verilated_lanes`] | [`VerilatedNeighbourPipeline`] | [`NeighbourPipelineModel`](pficp_fpga::search::neighbour_pipeline::NeighbourPipelineModel) | [`NeighbourLockstep`] |
//! | `weight_stage_verilog()` (docs/weights.md) | [`VerilatedWeightStage`] | [`WeightModel`](pficp_fpga::filter::weights::WeightModel) | [`WeightLockstep`] |
//! | `surface_residual_verilog()` (docs/pipeline.md, the surface residual) | [`VerilatedSurfaceResidual`] | [`SurfaceResidualModel`](pficp_fpga::surface::surface_residual::SurfaceResidualModel) | [`SurfaceLockstep`] |
//! | the sequencer `PfSequencer` alone (docs/sequencer.md) | [`VerilatedSequencer`] | [`SequencerModel`](pficp_fpga::filter::sequencer::SequencerModel) | [`SeqLockstep`] |
//! | `polish_program_verilog()` (the polish's datapath with the polish's programs) | [`VerilatedPolishProgram`] | `pficp_fpga::polish::program::run` (registers after each run; no cycle model) | none: `sim/tests/polish_program.rs` |
//! | `polish_bench_verilog()` (the pass, a multiplier and the polish's datapath) | [`VerilatedPolishBench`] | `PassSums::add_point` and the programs (registers after each pass and solve; no cycle model) | none: `sim/tests/polish_pass.rs` |
//! | `polish_unit_verilog()` (the whole polish: control, datapath, pass; the multiplier outside) | [`VerilatedPolishUnit`] | `polish_best` (the winner, its pose and cost, after each polish; no cycle model) | none: `sim/tests/polish_unit.rs` |
//! | `board_verilog` (the whole board top, default and fast builds) | [`VerilatedBoard`] | `BoardModel` (byte level) | [`serial::SerialBoard`] |
//!
//! - The wrappers run the Verilated RTL one clock at a time, with an optional VCD.
//! - [`LockstepOf`] (the lockstep types are its instances) drives the RTL and the
//!   reference with the same inputs and compares every output port after reset and after
//!   every rising edge; a difference is a [`Mismatch`] that names the cycle, the signal,
//!   both values and a VCD of the RTL run. By default the first one stops the run;
//!   [`LockstepOf::collect_all`] keeps going and keeps every one. The designs plug in
//!   through [`Rtl`].
//! - The board is compared at its pins instead: [`serial::SerialBoard`] drives its UART at
//!   the real bit timing and checks every byte, Status reply and LED against the byte-level
//!   reference; [`fuzz`] draws the frames for its fuzz test.
//!
//! Time in the VCDs: clock period 10; the state after reset is at time 0, the rising edge of
//! cycle `c` (`c` = 1, 2, ...) at time `10 c`, the falling edge before it (where the inputs
//! change) at `10 c - 5`. [`Mismatch::cycle`] `c` is therefore at VCD time `10 c`.
#![warn(missing_docs)]

#[macro_use]
mod core;
pub mod fuzz;
mod lockstep;
mod neighbour_lockstep;
#[macro_use]
mod rtl;
pub mod serial;
mod wrappers;

pub use crate::core::{verilated_lanes, verilated_models, BUILD_REPORT};
pub use lockstep::*;
pub use neighbour_lockstep::NeighbourLockstep;
pub use rtl::Rtl;
pub use wrappers::*;
