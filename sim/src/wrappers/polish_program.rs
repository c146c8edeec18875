//! The polish's datapath (`PolishProgram`): its wrapper and its port structs.

use crate::core::*;
use pficp_fpga::designs;
use std::fmt;
use std::path::Path;

/// The input ports of the polish's datapath (`PolishProgram`; its reference is
/// `pficp_fpga::polish::program::run`, a functional one: no cycle model).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProgramInputs {
    /// Synchronous reset.
    pub reset: bool,
    /// While idle: write `load_data` to `load_addr`.
    pub load: bool,
    /// Register to load.
    pub load_addr: u8,
    /// Value to load.
    pub load_data: i128,
    /// While idle: the register `read_data` shows after the next clock.
    pub read_addr: u8,
    /// While idle: add `add_data` to `add_addr` (written on the next clock).
    pub add: bool,
    /// Register to add to.
    pub add_addr: u8,
    /// Value to add (48-bit two's complement).
    pub add_data: i64,
    /// Run the program at `entry`.
    pub go: bool,
    /// The first instruction of the program `go` runs.
    pub entry: u16,
}

/// The output ports of the polish's datapath.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProgramOutputs {
    /// The register read.
    pub read_data: i128,
    /// Running.
    pub busy: bool,
    /// The last run stopped at a `StopBelow`.
    pub failed: bool,
}

/// The Verilated polish datapath with the polish's programs (`PolishProgram::polish`).
pub struct VerilatedPolishProgram {
    pub(crate) core: Core,
}

verilated_common!(VerilatedPolishProgram, ProgramInputs);

/// Output words of the polish datapath, one name per `u64` (wide ports repeat).
pub(crate) const POLISH_PROGRAM_OUTPUT_WORDS: [&str; 4] = designs::output_words(designs::POLISH_PROGRAM.ports);

impl VerilatedPolishProgram {
    /// The datapath after power-up (idle, registers zero).
    pub fn new() -> Self {
        VerilatedPolishProgram { core: Core::new(designs::POLISH_PROGRAM.name, 0, 11, &POLISH_PROGRAM_OUTPUT_WORDS) }
    }

    /// Drive the input ports (masked to the port widths).
    pub fn set_inputs(&mut self, i: &ProgramInputs) {
        self.core.set_inputs(&[
            i.reset as u64,
            i.load as u64,
            i.load_addr as u64,
            i.load_data as u64,
            (i.load_data >> 64) as u64,
            i.read_addr as u64,
            i.add as u64,
            i.add_addr as u64,
            i.add_data as u64,
            i.go as u64,
            i.entry as u64,
        ])
    }

    /// The output ports now.
    pub fn outputs(&self) -> ProgramOutputs {
        let o = self.core.outputs::<4>();
        ProgramOutputs { read_data: (o[0] as u128 | (o[1] as u128) << 64) as i128, busy: o[2] != 0, failed: o[3] != 0 }
    }
}

impl Default for VerilatedPolishProgram {
    fn default() -> Self {
        Self::new()
    }
}
