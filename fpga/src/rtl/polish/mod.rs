//! The on-board polish's RTL ([`crate::polish`]), one block a file:
//! - [`program`]: `PolishProgram`, the serial datapath that runs a
//!   [`crate::polish::program`] program over 64 x 128-bit registers.

pub mod program;

pub use program::PolishProgram;
