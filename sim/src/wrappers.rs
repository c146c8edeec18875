//! One typed wrapper a Verilated design: its ports as the reference's input and output
//! structs, packed to and from the shim's words.

use crate::core::*;
use crate::lockstep::Rtl;
use crate::ports;
use pficp_fpga::board::BoardConfig;
use pficp_fpga::common::format::{pack_point, unpack_point};
use pficp_fpga::filter::sequencer::SequencerModel;
use pficp_fpga::filter::sequencer::{SeqInputs, SeqOutputs};
use pficp_fpga::filter::weights::WeightModel;
use pficp_fpga::filter::weights::{WeightInputs, WeightOutputs};
use pficp_fpga::search::neighbour_pipeline::{GridInputs, NeighbourPipelineModel};
use pficp_fpga::search::pipeline::Outputs;
use pficp_fpga::surface::surface_residual::SurfaceResidualModel;
use pficp_fpga::surface::surface_residual::{SurfaceInputs, SurfaceOutputs};
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
        VerilatedNeighbourPipeline { core: Core::new(NEIGHBOUR_PIPELINE, lanes, 14, &NEIGHBOUR_OUTPUT_PORTS) }
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

/// The Verilated board top (`BoardTop`, `fpga/src/board/top_rtl.rs`): pins only.
pub struct VerilatedBoard {
    pub(crate) core: Core,
}

/// The board's pins after an edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BoardPins {
    /// The serial line to the host.
    pub uart_tx: bool,
    /// The LEDs (0 heartbeat, 1 receive activity, 2 busy, 3 error).
    pub leds: u8,
}

/// The input pins of the board.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoardInputs {
    /// Reset, active low.
    pub reset_n: bool,
    /// The serial line from the host (high when idle).
    pub uart_rx: bool,
}

impl Default for BoardInputs {
    fn default() -> Self {
        BoardInputs { reset_n: true, uart_rx: true }
    }
}

verilated_common!(VerilatedBoard, BoardInputs);

impl VerilatedBoard {
    /// The board generated as `config` says: [`BoardConfig::default`] (the real board) or
    /// [`BoardConfig::FAST_SIM`] (the fast UART the fault tests use); pins idle.
    ///
    /// Panics for any other configuration (only those two are verilated).
    pub fn new(config: &BoardConfig) -> Self {
        let design = if *config == BoardConfig::default() {
            BOARD
        } else if *config == BoardConfig::FAST_SIM {
            BOARD_FAST
        } else {
            panic!("no Verilated board for {config:?}: only BoardConfig::default() and BoardConfig::FAST_SIM are built")
        };
        let mut b = VerilatedBoard { core: Core::new(design, 0, 2, &["uart_tx", "leds"]) };
        b.set_inputs(&BoardInputs::default());
        b
    }

    /// Drive the input pins.
    pub fn set_inputs(&mut self, i: &BoardInputs) {
        self.core.set_inputs(&[i.reset_n as u64, i.uart_rx as u64])
    }

    /// The output pins now.
    pub fn pins(&self) -> BoardPins {
        let o = self.core.outputs::<2>();
        BoardPins { uart_tx: o[0] != 0, leds: o[1] as u8 }
    }
}

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
pub(crate) const POLISH_PROGRAM_OUTPUT_WORDS: [&str; 4] = ports::output_words(ports::POLISH_PROGRAM_PORTS);

impl VerilatedPolishProgram {
    /// The datapath after power-up (idle, registers zero).
    pub fn new() -> Self {
        VerilatedPolishProgram { core: Core::new(POLISH_PROGRAM, 0, 11, &POLISH_PROGRAM_OUTPUT_WORDS) }
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

/// The input ports of the polish's blocks with their multiplier (`PolishBench`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BenchInputs {
    /// Synchronous reset.
    pub reset: bool,
    /// The pass's gate on.
    pub gated: bool,
    /// The pass's gate.
    pub tau2: u32,
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
pub(crate) const POLISH_BENCH_OUTPUT_WORDS: [&str; 6] = ports::output_words(ports::POLISH_BENCH_PORTS);

impl VerilatedPolishBench {
    /// The blocks after power-up (idle, registers zero).
    pub fn new() -> Self {
        VerilatedPolishBench { core: Core::new(POLISH_BENCH, 0, 16, &POLISH_BENCH_OUTPUT_WORDS) }
    }

    /// Drive the input ports (masked to the port widths).
    pub fn set_inputs(&mut self, i: &BenchInputs) {
        self.core.set_inputs(&[
            i.reset as u64,
            i.gated as u64,
            i.tau2 as u64,
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
pub(crate) const POLISH_UNIT_OUTPUT_WORDS: [&str; 14] = ports::output_words(ports::POLISH_UNIT_PORTS);

impl VerilatedPolishUnit {
    /// The unit after power-up (idle, no result).
    pub fn new() -> Self {
        VerilatedPolishUnit { core: Core::new(POLISH_UNIT, 0, 16, &POLISH_UNIT_OUTPUT_WORDS) }
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

/// The Verilated particle-filter sequencer alone (`PfSequencer`, docs/sequencer.md).
pub struct VerilatedSequencer {
    pub(crate) core: Core,
}

verilated_common!(VerilatedSequencer, SeqInputs);

/// Output words of the sequencer, one name per `u64` (wide ports repeat).
pub(crate) const SEQUENCER_OUTPUT_WORDS: [&str; 17] = ports::output_words(ports::SEQUENCER_PORTS);

impl VerilatedSequencer {
    /// The sequencer after power-up (idle, no result).
    pub fn new() -> Self {
        VerilatedSequencer { core: Core::new(SEQUENCER, 0, 13, &SEQUENCER_OUTPUT_WORDS) }
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
        VerilatedWeightStage { core: Core::new(WEIGHT_STAGE, 0, 6, &WEIGHT_OUTPUT_PORTS) }
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

/// The Verilated surface residual stage (`SurfaceResidual`) with its own `VerilatedContext`.
pub struct VerilatedSurfaceResidual {
    pub(crate) core: Core,
}

verilated_common!(VerilatedSurfaceResidual, SurfaceInputs);

impl VerilatedSurfaceResidual {
    /// The residual stage after reset.
    pub fn new() -> Self {
        VerilatedSurfaceResidual { core: Core::new(SURFACE_RESIDUAL, 0, 11, &SURFACE_OUTPUT_PORTS) }
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
pub const SURFACE_OUTPUT_PORTS: [&str; 9] = ports::outputs(&[ports::SURFACE_RESIDUAL_PORTS]);

/// Output port names of the neighbour pipeline in the order
/// [`NeighbourLockstep`](crate::NeighbourLockstep) compares them.
pub const NEIGHBOUR_OUTPUT_PORTS: [&str; 8] = ports::outputs(&[ports::NEIGHBOUR_PIPELINE_PORTS]);

/// Output port names of the weight stage in the order [`WeightLockstep`](crate::WeightLockstep) compares them.
pub const WEIGHT_OUTPUT_PORTS: [&str; 8] = ports::outputs(&[ports::WEIGHT_STAGE_PORTS]);

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

// Each wrapper as an `Rtl`: its reference and its compared ports.

macro_rules! rtl_common {
    ($inputs:ty) => {
        fn set_inputs(&mut self, i: &$inputs) {
            Self::set_inputs(self, i)
        }
        fn outputs(&self) -> Self::Outputs {
            Self::outputs(self)
        }
        fn tick(&mut self) {
            self.core.tick()
        }
        fn cycle(&self) -> u64 {
            self.core.cycle
        }
        fn lanes(&self) -> usize {
            self.core.model.lanes
        }
        fn prefix(&self) -> &'static str {
            self.core.model.prefix
        }
        fn trace_to(&mut self, path: &Path) -> std::io::Result<()> {
            self.core.trace_to(path)
        }
        fn flush_trace(&mut self) {
            self.core.flush_trace()
        }
    };
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
