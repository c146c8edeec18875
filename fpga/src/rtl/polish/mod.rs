//! The on-board polish's RTL ([`crate::polish`]), one block a file:
//! - [`program`]: `PolishProgram`, the serial datapath that runs the polish's programs
//!   ([`crate::polish::programs`]) over 64 x 128-bit registers;
//! - [`pass`]: `PolishPass`, a found point's statistics and Jacobian row as products on a
//!   borrowed multiplier, added into the program's registers;
//! - [`control`]: `PolishControl`, the sequence of starts, programs and passes and the
//!   choice among the starts;
//! - [`unit`]: `PolishUnit`, the three wired as the board instantiates them;
//! - [`bench`]: `PolishBench`, the datapath and the pass with a multiplier of their own, the
//!   test top.

pub mod bench;
pub mod control;
pub mod pass;
pub mod program;
pub mod unit;

pub use bench::{PolishBench, PolishUnitBench};
pub use control::PolishControl;
pub use pass::PolishPass;
pub use program::PolishProgram;
pub use unit::PolishUnit;
