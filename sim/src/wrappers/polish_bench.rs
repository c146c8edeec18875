//! The polish's blocks with their multiplier (`PolishBench`): its wrapper and its port
//! structs.

use crate::core::*;
use pficp_fpga::designs;
use std::fmt;
use std::path::Path;

/// The input ports of the polish's blocks with their multiplier (`PolishBench`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BenchInputs {
    /// Synchronous reset.
    pub reset: bool,
    /// The pass's gate on.
    pub gated: bool,
    /// The pass's gate.
    pub tau2: u32,
    /// The scale held (the row's scale entry 0).
    pub scale_held: bool,
    /// The pose's translation.
    pub t: [i32; 3],
    /// Take a point (while `ready`).
    pub in_valid: bool,
    /// Its image.
    pub in_q: [i16; 3],
    /// Its nearest stored point's normal.
    pub in_n: [i16; 3],
    /// Its signed residual (13 bits).
    pub in_s: i64,
    /// The pass's points are all in: flush its accumulators.
    pub flush: bool,
    /// While the program is idle: write `load_data` to `load_addr`.
    pub load: bool,
    /// Register to load.
    pub load_addr: u8,
    /// Value to load.
    pub load_data: i128,
    /// While idle: the register `read_data` shows after the next clock.
    pub read_addr: u8,
    /// Run the program at `entry`.
    pub go: bool,
    /// The first instruction of the program `go` runs.
    pub entry: u16,
}

/// The output ports of the polish's blocks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BenchOutputs {
    /// The pass takes a point.
    pub ready: bool,
    /// The pass is idle and flushed.
    pub idle: bool,
    /// The register read.
    pub read_data: i128,
    /// The program is running.
    pub busy: bool,
    /// The last program failed.
    pub failed: bool,
}

/// The Verilated polish blocks with their multiplier (`PolishBench`).
pub struct VerilatedPolishBench {
    pub(crate) core: Core,
}

verilated_common!(VerilatedPolishBench, BenchInputs);

/// Output words of the polish bench, one name per `u64` (wide ports repeat).
pub(crate) const POLISH_BENCH_OUTPUT_WORDS: [&str; 6] = designs::output_words(designs::POLISH_BENCH.ports);

impl VerilatedPolishBench {
    /// The blocks after power-up (idle, registers zero).
    pub fn new() -> Self {
        VerilatedPolishBench { core: Core::new(designs::POLISH_BENCH.name, 0, 17, &POLISH_BENCH_OUTPUT_WORDS) }
    }

    /// Drive the input ports (masked to the port widths).
    pub fn set_inputs(&mut self, i: &BenchInputs) {
        self.core.set_inputs(&[
            i.reset as u64,
            i.gated as u64,
            i.tau2 as u64,
            i.scale_held as u64,
            pficp_fpga::common::format::pack_translation(i.t),
            i.in_valid as u64,
            pficp_fpga::common::format::pack_point(i.in_q),
            pficp_fpga::common::format::pack_point(i.in_n),
            i.in_s as u64,
            i.flush as u64,
            i.load as u64,
            i.load_addr as u64,
            i.load_data as u64,
            (i.load_data >> 64) as u64,
            i.read_addr as u64,
            i.go as u64,
            i.entry as u64,
        ])
    }

    /// The output ports now.
    pub fn outputs(&self) -> BenchOutputs {
        let o = self.core.outputs::<6>();
        BenchOutputs {
            ready: o[0] != 0,
            idle: o[1] != 0,
            read_data: (o[2] as u128 | (o[3] as u128) << 64) as i128,
            busy: o[4] != 0,
            failed: o[5] != 0,
        }
    }
}

impl Default for VerilatedPolishBench {
    fn default() -> Self {
        Self::new()
    }
}
