//! The weight stage (`WeightStage`): its wrapper and its compared ports.

use crate::core::*;
use crate::rtl::Rtl;
use pficp_fpga::designs;
use pficp_fpga::filter::weights::{WeightInputs, WeightModel, WeightOutputs};
use std::fmt;
use std::path::Path;

/// The Verilated weight stage alone (docs/weights.md).
pub struct VerilatedWeightStage {
    pub(crate) core: Core,
}

verilated_common!(VerilatedWeightStage, WeightInputs);

pub(crate) fn weight_outputs(o: &[u64]) -> WeightOutputs {
    WeightOutputs {
        busy: o[0] != 0,
        count: o[1] as u16,
        min_cost: o[2],
        w_valid: o[3] != 0,
        w_index: o[4] as u8,
        weight: o[5] as u16,
        w_done: o[6] != 0,
        w_sum: o[7] as u32,
    }
}

impl VerilatedWeightStage {
    /// The weight stage after reset.
    pub fn new() -> Self {
        VerilatedWeightStage { core: Core::new(designs::WEIGHT_STAGE.name, 0, 6, &WEIGHT_OUTPUT_PORTS) }
    }

    /// Drive the input ports (masked to the port widths).
    pub fn set_inputs(&mut self, i: &WeightInputs) {
        self.core.set_inputs(&[
            i.clear as u64,
            i.cost_valid as u64,
            i.cost,
            i.weigh as u64,
            i.pre_shift as u64,
            i.q_mul as u64,
        ])
    }

    /// The output ports now.
    pub fn outputs(&self) -> WeightOutputs {
        weight_outputs(&self.core.outputs::<8>())
    }
}

impl Default for VerilatedWeightStage {
    fn default() -> Self {
        Self::new()
    }
}

/// Output port names of the weight stage in the order [`WeightLockstep`](crate::WeightLockstep) compares them.
pub const WEIGHT_OUTPUT_PORTS: [&str; 8] = designs::outputs(designs::WEIGHT_STAGE.ports);

pub(crate) fn weight_port_values(o: &WeightOutputs) -> [u64; 8] {
    [
        o.busy as u64,
        o.count as u64,
        o.min_cost,
        o.w_valid as u64,
        o.w_index as u64,
        o.weight as u64,
        o.w_done as u64,
        o.w_sum as u64,
    ]
}

impl Rtl for VerilatedWeightStage {
    type Inputs = WeightInputs;
    type Outputs = WeightOutputs;
    type Reference = WeightModel;
    const OUTPUT_PORTS: &'static [&'static str] = &WEIGHT_OUTPUT_PORTS;
    fn port_values(o: &WeightOutputs) -> Vec<u64> {
        weight_port_values(o).to_vec()
    }
    fn new_reference(&self) -> WeightModel {
        WeightModel::new()
    }
    fn reference_outputs(r: &WeightModel) -> WeightOutputs {
        r.outputs()
    }
    fn reference_step(r: &mut WeightModel, i: &WeightInputs) {
        r.step(i)
    }
    fn fresh(&self) -> Self {
        Self::new()
    }
    rtl_common!(WeightInputs);
}
