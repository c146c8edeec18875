//! The neighbour pipeline (`NeighbourPipeline<P>`, the board's search): its wrapper and its
//! compared ports.

use crate::core::*;
use crate::rtl::Rtl;
use pficp_fpga::common::format::{pack_point, unpack_point};
use pficp_fpga::designs;
use pficp_fpga::search::neighbour_pipeline::{GridInputs, NeighbourPipelineModel};
use pficp_fpga::search::pipeline::Outputs;
use std::fmt;
use std::path::Path;

/// The neighbour pipeline's input ports as the shim's words.
pub(crate) fn neighbour_input_words(i: &GridInputs) -> [u64; 14] {
    let pose = i.pose.pack();
    [
        i.model_we as u64,
        i.model_waddr as u64,
        i.model_wdata,
        i.table_we as u64,
        i.table_waddr as u64,
        i.table_wdata as u64,
        i.start as u64,
        pose[0],
        pose[1],
        pose[2],
        pose[3],
        i.scan_valid as u64,
        i.scan_data,
        i.scan_last as u64,
    ]
}

/// The neighbour pipeline's outputs from the shim's words.
pub(crate) fn neighbour_outputs(o: &[u64; 8]) -> Outputs {
    Outputs {
        scan_ready: o[0] != 0,
        busy: o[1] != 0,
        nn_valid: o[2] != 0,
        nn_index: o[3] as u16,
        nn_dist: o[4],
        cost_valid: o[5] != 0,
        cost: o[6],
        nn_point: unpack_point(o[7]),
    }
}

/// The Verilated neighbour pipeline (`NeighbourPipeline<P>`: lanes over one scan point's
/// candidates; the board's search).
pub struct VerilatedNeighbourPipeline {
    pub(crate) core: Core,
}

verilated_common!(VerilatedNeighbourPipeline, GridInputs);

impl VerilatedNeighbourPipeline {
    /// The `lanes`-lane neighbour pipeline after reset.
    ///
    /// Panics if no model was verilated for `lanes` (see [`verilated_lanes`]).
    pub fn new(lanes: usize) -> Self {
        VerilatedNeighbourPipeline {
            core: Core::new(designs::NEIGHBOUR_PIPELINE.name, lanes, 14, &NEIGHBOUR_OUTPUT_PORTS),
        }
    }

    /// Number of lanes.
    pub fn lanes(&self) -> usize {
        self.core.model.lanes
    }

    /// Drive the input ports (masked to the port widths).
    pub fn set_inputs(&mut self, i: &GridInputs) {
        self.core.set_inputs(&neighbour_input_words(i))
    }

    /// The output ports now.
    pub fn outputs(&self) -> Outputs {
        neighbour_outputs(&self.core.outputs::<8>())
    }
}

/// Output port names of the neighbour pipeline in the order
/// [`NeighbourLockstep`](crate::NeighbourLockstep) compares them.
pub const NEIGHBOUR_OUTPUT_PORTS: [&str; 8] = designs::outputs(designs::NEIGHBOUR_PIPELINE.ports);

/// The neighbour pipeline's ports in [`NEIGHBOUR_OUTPUT_PORTS`] order (`nn_point` packed).
pub(crate) fn neighbour_port_values(o: &Outputs) -> [u64; 8] {
    [
        o.scan_ready as u64,
        o.busy as u64,
        o.nn_valid as u64,
        o.nn_index as u64,
        o.nn_dist,
        o.cost_valid as u64,
        o.cost,
        pack_point(o.nn_point),
    ]
}

impl Rtl for VerilatedNeighbourPipeline {
    type Inputs = GridInputs;
    type Outputs = Outputs;
    type Reference = NeighbourPipelineModel;
    const OUTPUT_PORTS: &'static [&'static str] = &NEIGHBOUR_OUTPUT_PORTS;
    fn port_values(o: &Outputs) -> Vec<u64> {
        neighbour_port_values(o).to_vec()
    }
    fn new_reference(&self) -> NeighbourPipelineModel {
        NeighbourPipelineModel::new(self.lanes())
    }
    fn reference_outputs(r: &NeighbourPipelineModel) -> Outputs {
        r.outputs()
    }
    fn reference_step(r: &mut NeighbourPipelineModel, i: &GridInputs) {
        r.step(i)
    }
    fn fresh(&self) -> Self {
        Self::new(self.lanes())
    }
    rtl_common!(GridInputs);
}
