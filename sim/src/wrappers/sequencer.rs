//! The particle-filter sequencer (`PfSequencer`): its wrapper and its compared ports.

use crate::core::*;
use crate::rtl::Rtl;
use pficp_fpga::designs;
use pficp_fpga::filter::sequencer::{SeqInputs, SeqOutputs, SequencerModel};
use std::fmt;
use std::path::Path;

/// The Verilated particle-filter sequencer alone (`PfSequencer`, docs/sequencer.md).
pub struct VerilatedSequencer {
    pub(crate) core: Core,
}

verilated_common!(VerilatedSequencer, SeqInputs);

/// Output words of the sequencer, one name per `u64` (wide ports repeat).
pub(crate) const SEQUENCER_OUTPUT_WORDS: [&str; 17] = designs::output_words(designs::SEQUENCER.ports);

impl VerilatedSequencer {
    /// The sequencer after power-up (idle, no result).
    pub fn new() -> Self {
        VerilatedSequencer { core: Core::new(designs::SEQUENCER.name, 0, 13, &SEQUENCER_OUTPUT_WORDS) }
    }

    /// Drive the input ports (masked to the port widths).
    pub fn set_inputs(&mut self, i: &SeqInputs) {
        self.core.set_inputs(&[
            i.reset as u64,
            i.cfg_we as u64,
            i.cfg_addr as u64,
            i.cfg_data,
            i.go as u64,
            i.nn_ready as u64,
            i.cost_valid as u64,
            i.cost,
            i.nn_valid as u64,
            i.nn_dist,
            i.ext_go as u64,
            i.ext_a,
            i.ext_b,
        ])
    }

    /// The output ports now.
    pub fn outputs(&self) -> SeqOutputs {
        let o = self.core.outputs::<17>();
        SeqOutputs {
            start: o[0] != 0,
            pose: [o[1], o[2], o[3], o[4]],
            running: o[5] != 0,
            finished: o[6] != 0,
            iterations: o[7] as u16,
            best_cost: o[8],
            best_max: o[9],
            params: [o[10], o[11], o[12]],
            p_we: o[13] != 0,
            p_waddr: o[14] as u16,
            p_wdata: o[15] as u32,
            mul_product: o[16],
        }
    }
}

impl Default for VerilatedSequencer {
    fn default() -> Self {
        Self::new()
    }
}

/// The sequencer's output words as [`Rtl::OUTPUT_PORTS`] (a wide port's words numbered).
pub const SEQUENCER_OUTPUT_PORTS: [&str; 17] = [
    "start",
    "pose.0",
    "pose.1",
    "pose.2",
    "pose.3",
    "running",
    "finished",
    "iterations",
    "best_cost",
    "best_max",
    "params.0",
    "params.1",
    "params.2",
    "p_we",
    "p_waddr",
    "p_wdata",
    "mul_product",
];

impl Rtl for VerilatedSequencer {
    type Inputs = SeqInputs;
    type Outputs = SeqOutputs;
    type Reference = SequencerModel;
    const OUTPUT_PORTS: &'static [&'static str] = &SEQUENCER_OUTPUT_PORTS;
    fn port_values(o: &SeqOutputs) -> Vec<u64> {
        let mut v = vec![o.start as u64];
        v.extend(o.pose);
        v.extend([o.running as u64, o.finished as u64, o.iterations as u64, o.best_cost, o.best_max]);
        v.extend(o.params);
        v.extend([o.p_we as u64, o.p_waddr as u64, o.p_wdata as u64, o.mul_product]);
        v
    }
    fn new_reference(&self) -> SequencerModel {
        SequencerModel::new()
    }
    fn reference_outputs(r: &SequencerModel) -> SeqOutputs {
        r.outputs()
    }
    fn reference_step(r: &mut SequencerModel, i: &SeqInputs) {
        r.step(i)
    }
    fn fresh(&self) -> Self {
        Self::new()
    }
    rtl_common!(SeqInputs);
}
