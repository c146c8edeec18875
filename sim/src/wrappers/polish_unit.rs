//! The whole polish (`PolishUnit`): its wrapper and its port structs.

use crate::core::*;
use pficp_fpga::designs;
use std::fmt;
use std::path::Path;

/// The input ports of the whole polish (`PolishUnit`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UnitInputs {
    /// Synchronous reset.
    pub reset: bool,
    /// While idle: polish `starts` starts with `steps` steps each.
    pub go: bool,
    /// Starts (1 to 15; 0 taken as 1).
    pub starts: u8,
    /// Steps a start.
    pub steps: u8,
    /// The winner's further steps (0: none).
    pub winner_steps: u8,
    /// The steps hold the scale.
    pub scale_held: bool,
    /// The pose of start `start_index` ([`pficp_fpga::common::format::FxPose::pack`]).
    pub start_pose: [u64; 4],
    /// The pass is over.
    pub pass_done: bool,
    /// Its cost.
    pub pass_cost: u64,
    /// A found point (while `ready`).
    pub in_valid: bool,
    /// Its image.
    pub in_q: [i16; 3],
    /// Its nearest stored point's normal.
    pub in_n: [i16; 3],
    /// Its signed residual (13 bits).
    pub in_s: i64,
    /// The product of the pair issued three clocks before (44 bits).
    pub mul_product: u64,
}

/// The output ports of the whole polish.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UnitOutputs {
    /// The start the unit takes next.
    pub start_index: u8,
    /// Ask for a pass.
    pub pass_go: bool,
    /// The pass's pose ([`pficp_fpga::common::format::FxPose::pack`]).
    pub pose: [u64; 4],
    /// The pass takes a point.
    pub ready: bool,
    /// Multiplier: take `mul_a`, `mul_b`.
    pub mul_go: bool,
    /// Multiplicand (26 bits).
    pub mul_a: u64,
    /// Multiplier (18 bits).
    pub mul_b: u64,
    /// Polishing.
    pub busy: bool,
    /// A result is held.
    pub done: bool,
    /// The winning start.
    pub best_index: u8,
    /// Its cost.
    pub best_cost: u64,
}

/// The Verilated whole polish (`PolishUnit`), its multiplier outside.
pub struct VerilatedPolishUnit {
    pub(crate) core: Core,
}

verilated_common!(VerilatedPolishUnit, UnitInputs);

/// Output words of the polish unit, one name per `u64` (wide ports repeat).
pub(crate) const POLISH_UNIT_OUTPUT_WORDS: [&str; 14] = designs::output_words(designs::POLISH_UNIT.ports);

impl VerilatedPolishUnit {
    /// The unit after power-up (idle, no result).
    pub fn new() -> Self {
        VerilatedPolishUnit { core: Core::new(designs::POLISH_UNIT.name, 0, 17, &POLISH_UNIT_OUTPUT_WORDS) }
    }

    /// Drive the input ports (masked to the port widths).
    pub fn set_inputs(&mut self, i: &UnitInputs) {
        let p = i.start_pose;
        self.core.set_inputs(&[
            i.reset as u64,
            i.go as u64,
            i.starts as u64,
            i.steps as u64,
            i.winner_steps as u64,
            i.scale_held as u64,
            p[0],
            p[1],
            p[2],
            p[3],
            i.pass_done as u64,
            i.pass_cost,
            i.in_valid as u64,
            pficp_fpga::common::format::pack_point(i.in_q),
            pficp_fpga::common::format::pack_point(i.in_n),
            i.in_s as u64,
            i.mul_product,
        ])
    }

    /// The output ports now.
    pub fn outputs(&self) -> UnitOutputs {
        let o = self.core.outputs::<14>();
        UnitOutputs {
            start_index: o[0] as u8,
            pass_go: o[1] != 0,
            pose: [o[2], o[3], o[4], o[5]],
            ready: o[6] != 0,
            mul_go: o[7] != 0,
            mul_a: o[8],
            mul_b: o[9],
            busy: o[10] != 0,
            done: o[11] != 0,
            best_index: o[12] as u8,
            best_cost: o[13],
        }
    }
}

impl Default for VerilatedPolishUnit {
    fn default() -> Self {
        Self::new()
    }
}
