//! The surface residual stage (`SurfaceResidual`): its wrapper and its compared ports.

use crate::core::*;
use crate::rtl::Rtl;
use pficp_fpga::designs;
use pficp_fpga::surface::surface_residual::{SurfaceInputs, SurfaceOutputs, SurfaceResidualModel};
use std::fmt;
use std::path::Path;

/// The Verilated surface residual stage (`SurfaceResidual`) with its own `VerilatedContext`.
pub struct VerilatedSurfaceResidual {
    pub(crate) core: Core,
}

verilated_common!(VerilatedSurfaceResidual, SurfaceInputs);

impl VerilatedSurfaceResidual {
    /// The residual stage after reset.
    pub fn new() -> Self {
        VerilatedSurfaceResidual { core: Core::new(designs::SURFACE_RESIDUAL.name, 0, 11, &SURFACE_OUTPUT_PORTS) }
    }

    /// Drive the input ports (masked to the port widths).
    pub fn set_inputs(&mut self, i: &SurfaceInputs) {
        self.core.set_inputs(&[
            i.point_we as u64,
            i.point_waddr as u64,
            i.point_wdata,
            i.normal_we as u64,
            i.normal_waddr as u64,
            i.normal_wdata,
            i.in_valid as u64,
            i.in_index as u64,
            i.in_dist,
            i.in_point,
            i.in_cost_valid as u64,
        ])
    }

    /// The output ports now.
    pub fn outputs(&self) -> SurfaceOutputs {
        let o = self.core.outputs::<9>();
        SurfaceOutputs {
            nn_valid: o[0] != 0,
            nn_index: o[1] as u16,
            nn_dist: o[2],
            nn_resid: o[3] as u32,
            nn_s: o[4] as u16,
            nn_point: o[5],
            nn_normal: o[6],
            cost_valid: o[7] != 0,
            cost: o[8],
        }
    }
}

impl Default for VerilatedSurfaceResidual {
    fn default() -> Self {
        Self::new()
    }
}

/// Output port names of the surface residual stage in the order
/// [`SurfaceLockstep`](crate::SurfaceLockstep) compares them.
pub const SURFACE_OUTPUT_PORTS: [&str; 9] = designs::outputs(designs::SURFACE_RESIDUAL.ports);

impl Rtl for VerilatedSurfaceResidual {
    type Inputs = SurfaceInputs;
    type Outputs = SurfaceOutputs;
    type Reference = SurfaceResidualModel;
    const OUTPUT_PORTS: &'static [&'static str] = &SURFACE_OUTPUT_PORTS;
    fn port_values(o: &SurfaceOutputs) -> Vec<u64> {
        vec![
            o.nn_valid as u64,
            o.nn_index as u64,
            o.nn_dist,
            o.nn_resid as u64,
            o.nn_s as u64,
            o.nn_point,
            o.nn_normal,
            o.cost_valid as u64,
            o.cost,
        ]
    }
    fn new_reference(&self) -> SurfaceResidualModel {
        SurfaceResidualModel::new()
    }
    fn reference_outputs(r: &SurfaceResidualModel) -> SurfaceOutputs {
        r.outputs()
    }
    fn reference_step(r: &mut SurfaceResidualModel, i: &SurfaceInputs) {
        r.step(i)
    }
    fn fresh(&self) -> Self {
        Self::new()
    }
    rtl_common!(SurfaceInputs);
}
