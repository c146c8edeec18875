//! hdl-gen: writes the PF-ICP Verilog (and, for the board, its UCF and ISE script), lints it
//! with Verilator and estimates its Spartan-6 XC6SLX45 resources and logic depth with Yosys.
//!
//! - [`lint`]: the written file (header, Verilator waivers) and `verilator --lint-only -Wall`;
//! - [`synth`]: Yosys `synth_xilinx -family xc6s -flatten`, `stat -json`, `ltp`, `sta`;
//! - [`report`]: [`Resources`] against the device, the Markdown/JSON report, limits;
//! - [`device`]: the XC6SLX45's capacity;
//! - [`ucf`]: the board pin map (`constraints/pinmap.toml`) and the UCF written from it;
//! - [`top_ports`]: the ports of the Verilog top, which the UCF pins;
//! - [`ise`]: the ISE 14.7 `xtclsh` build script (Vivado does not support Spartan-6).
//!
//! The tools are required: a missing `verilator`/`yosys` is an error that says
//! `apt-get install -y verilator yosys`.
#![warn(missing_docs)]

pub mod device;
pub mod ise;
pub mod lint;
pub mod report;
pub mod synth;
pub mod tools;
pub mod top_ports;
pub mod ucf;

pub use lint::{lint, lint_file, prepare_verilog, write_verilog, LintMessage, LintReport, TOP, VERILOG_FILE};
pub use report::{Limits, PathStep, Resources};
pub use synth::{synthesise, SynthOptions};
pub use tools::INSTALL_HINT;
pub use ucf::{PinMap, Port, UCF_FILE};
