//! One typed wrapper a Verilated design, one file a design: its ports as the reference's
//! input and output structs, packed to and from the shim's words, and, for the designs the
//! lockstep harness runs, its [`Rtl`](crate::Rtl) implementation and compared ports. The
//! designs and their ports are the registry's (`pficp_fpga::designs`).

mod board;
mod neighbour_pipeline;
mod polish_bench;
mod polish_program;
mod polish_unit;
mod sequencer;
mod surface_residual;
mod weight_stage;

pub use board::*;
pub use neighbour_pipeline::*;
pub use polish_bench::*;
pub use polish_program::*;
pub use polish_unit::*;
pub use sequencer::*;
pub use surface_residual::*;
pub use weight_stage::*;
