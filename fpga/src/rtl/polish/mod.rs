//! The on-board polish's RTL ([`crate::polish`]), one block a file:
//! - [`program`]: `PolishProgram`, the serial datapath that runs the polish's programs
//!   ([`crate::polish::programs`]) over 64 x 128-bit registers;
//! - [`pass`]: `PolishPass`, a found point's statistics and Jacobian row as products on a
//!   borrowed multiplier, added into the program's registers;
//! - [`bench`]: `PolishBench`, the two wired with a multiplier of their own, the test top.

pub mod bench;
pub mod pass;
pub mod program;

pub use bench::PolishBench;
pub use pass::PolishPass;
pub use program::PolishProgram;
