//! Verilator co-simulation of the generated designs against their bit-exact references:
//!
//! | RTL (`build.rs` verilates it) | wrapper | reference | lockstep |
//! |---|---|---|---|
//! | `pipeline_verilog(P)` (docs/pipeline.md), P in [`verilated_lanes`] | [`VerilatedPipeline`] | [`PipelineModel`] | [`Lockstep`] |
//! | `particle_weights_verilog(P)`, the same P | [`VerilatedParticleWeights`] | [`ParticleWeightModel`] | [`PwLockstep`] |
//! | `weight_stage_verilog()` (docs/weights.md) | [`VerilatedWeightStage`] | [`WeightModel`] | [`WeightLockstep`] |
//! | the sequencer `PfSequencer` alone (docs/sequencer.md) | [`VerilatedSequencer`] | [`SequencerModel`] | [`SeqLockstep`] |
//! | `board_verilog` (the whole board top, default and fast builds) | [`VerilatedBoard`] | `BoardModel` (byte level) | [`serial::SerialBoard`] |
//!
//! - The wrappers run the Verilated RTL one clock at a time, with an optional VCD.
//! - [`LockstepOf`] (the four lockstep types are its instances) drives the RTL and the
//!   reference with the same inputs and compares every output port after reset and after
//!   every rising edge; a difference is a [`Mismatch`] that names the cycle, the signal,
//!   both values and a VCD of the RTL run. By default the first one stops the run;
//!   [`LockstepOf::collect_all`] keeps going and keeps every one. The designs plug in
//!   through [`Rtl`].
//! - The board is compared at its pins instead: [`serial::SerialBoard`] drives its UART at
//!   the real bit timing and checks every byte, Status reply and LED against the byte-level
//!   reference; [`fuzz`] draws the frames for its fuzz test.
//!
//! Time in the VCDs: clock period 10; the state after reset is at time 0, the rising edge of
//! cycle `c` (`c` = 1, 2, ...) at time `10 c`, the falling edge before it (where the inputs
//! change) at `10 c - 5`. [`Mismatch::cycle`] `c` is therefore at VCD time `10 c`.
#![warn(missing_docs)]

pub mod fuzz;
pub mod serial;

use pficp_fpga::board::BoardConfig;
use pficp_fpga::format::{pack_point, FxPoint, FxPose, WeightScale, MAX_POINTS};
use pficp_fpga::particle_weights::{ParticleWeightModel, PwInputs, PwOutputs};
use pficp_fpga::pipeline::{Evaluation, Inputs, Outputs, PipelineModel};
use pficp_fpga::sequencer::{SeqInputs, SeqOutputs, SequencerModel};
use pficp_fpga::weights::{WeightInputs, WeightModel, WeightOutputs, MAX_PARTICLES};
use std::ffi::CString;
use std::fmt;
use std::os::raw::{c_char, c_int, c_void};
use std::path::{Path, PathBuf};

/// One Verilated model in the archive (a table of its shim's entry points).
struct Model {
    /// `pipeline`, `particle_weights` or `weight_stage`.
    design: &'static str,
    /// Lanes (0 for the weight stage).
    lanes: usize,
    prefix: &'static str,
    verilog: &'static str,
    /// `u64` words of the packed input array.
    in_words: usize,
    /// Output ports in the order of the packed output array (one `u64` each).
    outputs: &'static [&'static str],
    out_words: usize,
    new: unsafe extern "C" fn() -> *mut c_void,
    free: unsafe extern "C" fn(*mut c_void),
    tick: unsafe extern "C" fn(*mut c_void, u64),
    trace_open: unsafe extern "C" fn(*mut c_void, *const c_char, u64) -> c_int,
    trace_flush: unsafe extern "C" fn(*mut c_void),
    trace_close: unsafe extern "C" fn(*mut c_void),
    set_inputs: unsafe extern "C" fn(*mut c_void, *const u64),
    get_outputs: unsafe extern "C" fn(*mut c_void, *mut u64),
}

mod ffi {
    use super::Model;
    use std::os::raw::{c_char, c_int, c_void};
    include!(concat!(env!("OUT_DIR"), "/models.rs"));
}
pub use ffi::BUILD_REPORT;

const PIPELINE: &str = "pipeline";
const PARTICLE_WEIGHTS: &str = "particle_weights";
const WEIGHT_STAGE: &str = "weight_stage";
const BOARD: &str = "board";
const BOARD_FAST: &str = "board_fast";
const SEQUENCER: &str = "sequencer";

/// Lane counts with a Verilated pipeline (and particle-weight pipeline): the build verilates
/// 4 and 16 unless `PFICP_SIM_LANES` says otherwise.
pub fn verilated_lanes() -> Vec<usize> {
    ffi::MODELS.iter().filter(|m| m.design == PIPELINE).map(|m| m.lanes).collect()
}

/// Every Verilated model: (design, lanes, Verilator prefix), e.g. `("particle_weights", 16,
/// "Vpw16")`; the weight stage has 0 lanes.
pub fn verilated_models() -> Vec<(&'static str, usize, &'static str)> {
    ffi::MODELS.iter().map(|m| (m.design, m.lanes, m.prefix)).collect()
}

/// The Verilog file that was verilated for the `lanes`-lane pipeline, if there is a model.
pub fn verilog_path(lanes: usize) -> Option<&'static Path> {
    ffi::MODELS.iter().find(|m| m.design == PIPELINE && m.lanes == lanes).map(|m| Path::new(m.verilog))
}

/// A Verilated model with its own `VerilatedContext`, untyped (packed `u64` ports).
struct Core {
    model: &'static Model,
    h: *mut c_void,
    cycle: u64,
    trace: Option<PathBuf>,
}

impl Core {
    /// A fresh model of `design` with `lanes` lanes; its ports must be `in_words` input words
    /// and the outputs `outputs` (what the typed wrapper packs and unpacks).
    fn new(design: &str, lanes: usize, in_words: usize, outputs: &[&str]) -> Core {
        let model = ffi::MODELS.iter().find(|m| m.design == design && m.lanes == lanes).unwrap_or_else(|| {
            panic!(
                "no Verilated {design} model with {lanes} lanes (built: {:?}; rebuild with PFICP_SIM_LANES=...)",
                verilated_models()
            )
        });
        assert!(
            model.in_words == in_words && model.out_words == outputs.len() && model.outputs == outputs,
            "{}: the shim's ports ({} input words, outputs {:?}) are not the wrapper's ({in_words}, {outputs:?})",
            model.prefix,
            model.in_words,
            model.outputs
        );
        // SAFETY: the shim allocates and evaluates a fresh model.
        let h = unsafe { (model.new)() };
        assert!(!h.is_null());
        Core { model, h, cycle: 0, trace: None }
    }

    fn set_inputs<const N: usize>(&mut self, words: &[u64; N]) {
        debug_assert_eq!(N, self.model.in_words);
        // SAFETY: the array has the length the shim reads (checked in `new`).
        unsafe { (self.model.set_inputs)(self.h, words.as_ptr()) }
    }

    fn outputs<const N: usize>(&self) -> [u64; N] {
        debug_assert_eq!(N, self.model.out_words);
        let mut o = [0u64; N];
        // SAFETY: the array has the length the shim writes (checked in `new`).
        unsafe { (self.model.get_outputs)(self.h, o.as_mut_ptr()) };
        o
    }

    fn tick(&mut self) {
        self.cycle += 1;
        // SAFETY: valid handle.
        unsafe { (self.model.tick)(self.h, 10 * self.cycle) }
    }

    fn trace_to(&mut self, path: &Path) -> std::io::Result<()> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        let c = CString::new(path.as_os_str().as_encoded_bytes())
            .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidInput, "NUL in the VCD path"))?;
        // SAFETY: valid handle and C string.
        if unsafe { (self.model.trace_open)(self.h, c.as_ptr(), 10 * self.cycle) } != 0 {
            self.trace = None;
            return Err(std::io::Error::other(format!("Verilator cannot open {}", path.display())));
        }
        self.trace = Some(path.to_path_buf());
        Ok(())
    }

    fn flush_trace(&mut self) {
        // SAFETY: valid handle.
        unsafe { (self.model.trace_flush)(self.h) }
    }

    fn close_trace(&mut self) {
        // SAFETY: valid handle.
        unsafe { (self.model.trace_close)(self.h) };
        self.trace = None;
    }
}

impl Drop for Core {
    fn drop(&mut self) {
        // SAFETY: the handle came from `new` and is freed once.
        unsafe { (self.model.free)(self.h) }
    }
}

// The handle is owned exclusively; Verilator models with separate contexts may move between
// threads.
unsafe impl Send for Core {}

/// The methods every wrapper has (on `self.core`).
macro_rules! verilated_common {
    ($ty:ident, $inputs:ty) => {
        impl $ty {
            /// The Verilator prefix of the model (`Vpipe16`, `Vpw4`, `Vweights`).
            pub fn prefix(&self) -> &'static str {
                self.core.model.prefix
            }

            /// The Verilog file that was verilated.
            pub fn verilog_path(&self) -> &'static Path {
                Path::new(self.core.model.verilog)
            }

            /// One clock: clock low, eval, clock high (the rising edge), eval; the VCD, if
            /// open, gets both phases.
            pub fn tick(&mut self) {
                self.core.tick()
            }

            /// Apply the inputs and tick.
            pub fn step(&mut self, i: &$inputs) {
                self.set_inputs(i);
                self.tick();
            }

            /// Rising edges so far.
            pub fn cycle(&self) -> u64 {
                self.core.cycle
            }

            /// Write a VCD of every signal from now on (the current state at time
            /// `10 * cycle`, then both phases of every clock). Replaces an open trace.
            pub fn trace_to(&mut self, path: impl AsRef<Path>) -> std::io::Result<()> {
                self.core.trace_to(path.as_ref())
            }

            /// The open VCD, if any.
            pub fn trace_path(&self) -> Option<&Path> {
                self.core.trace.as_deref()
            }

            /// Flush the VCD to disk (it is also flushed when closed or dropped).
            pub fn flush_trace(&mut self) {
                self.core.flush_trace()
            }

            /// Close the VCD.
            pub fn close_trace(&mut self) {
                self.core.close_trace()
            }
        }

        impl fmt::Debug for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.debug_struct(stringify!($ty))
                    .field("prefix", &self.core.model.prefix)
                    .field("cycle", &self.core.cycle)
                    .field("trace", &self.core.trace)
                    .finish()
            }
        }
    };
}

/// The Verilated pipeline with its own `VerilatedContext` (instances are independent and
/// may live on different threads).
pub struct VerilatedPipeline {
    core: Core,
}

verilated_common!(VerilatedPipeline, Inputs);

fn pipeline_input_words(i: &Inputs) -> [u64; 12] {
    let pose = i.pose.pack();
    [
        i.model_we as u64,
        i.model_waddr as u64,
        i.model_wdata,
        i.model_count as u64,
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

fn pipeline_outputs(o: &[u64]) -> Outputs {
    Outputs {
        scan_ready: o[0] != 0,
        busy: o[1] != 0,
        nn_valid: o[2] != 0,
        nn_index: o[3] as u16,
        nn_dist: o[4],
        cost_valid: o[5] != 0,
        cost: o[6],
    }
}

impl VerilatedPipeline {
    /// A pipeline with `lanes` lanes after reset (all inputs low, evaluated once).
    ///
    /// Panics if no model was verilated for `lanes` (see [`verilated_lanes`]).
    pub fn new(lanes: usize) -> Self {
        VerilatedPipeline { core: Core::new(PIPELINE, lanes, 12, &OUTPUT_PORTS) }
    }

    /// Number of lanes.
    pub fn lanes(&self) -> usize {
        self.core.model.lanes
    }

    /// Drive the input ports (sampled at the next [`tick`](Self::tick)'s rising edge).
    /// Values are masked to the port widths.
    pub fn set_inputs(&mut self, i: &Inputs) {
        self.core.set_inputs(&pipeline_input_words(i))
    }

    /// The output ports now.
    pub fn outputs(&self) -> Outputs {
        pipeline_outputs(&self.core.outputs::<7>())
    }
}

/// The Verilated particle-weight pipeline (`ParticleWeightPipeline<P>`: the nearest-neighbour
/// pipeline whose costs feed the weight stage).
pub struct VerilatedParticleWeights {
    core: Core,
}

verilated_common!(VerilatedParticleWeights, PwInputs);

impl VerilatedParticleWeights {
    /// The `lanes`-lane particle-weight pipeline after reset.
    ///
    /// Panics if no model was verilated for `lanes` (see [`verilated_lanes`]).
    pub fn new(lanes: usize) -> Self {
        VerilatedParticleWeights { core: Core::new(PARTICLE_WEIGHTS, lanes, 16, &PW_OUTPUT_PORTS) }
    }

    /// Number of lanes.
    pub fn lanes(&self) -> usize {
        self.core.model.lanes
    }

    /// Drive the input ports (masked to the port widths).
    pub fn set_inputs(&mut self, i: &PwInputs) {
        let nn = pipeline_input_words(&i.nn);
        let mut w = [0u64; 16];
        w[..12].copy_from_slice(&nn);
        w[12..].copy_from_slice(&[i.clear as u64, i.weigh as u64, i.pre_shift as u64, i.q_mul as u64]);
        self.core.set_inputs(&w)
    }

    /// The output ports now.
    pub fn outputs(&self) -> PwOutputs {
        let o = self.core.outputs::<15>();
        PwOutputs { nn: pipeline_outputs(&o[..7]), w: weight_outputs(&o[7..]) }
    }
}

/// The Verilated board top (`BoardTop`, `fpga/src/rtl/board/top.rs`): pins only.
pub struct VerilatedBoard {
    core: Core,
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

/// The Verilated particle-filter sequencer alone (`PfSequencer`, docs/sequencer.md).
pub struct VerilatedSequencer {
    core: Core,
}

verilated_common!(VerilatedSequencer, SeqInputs);

/// Output words of the sequencer, one name per `u64` (wide ports repeat).
const SEQUENCER_OUTPUT_WORDS: [&str; 16] = [
    "start",
    "pose",
    "pose",
    "pose",
    "pose",
    "running",
    "finished",
    "iterations",
    "best_cost",
    "best_max",
    "params",
    "params",
    "params",
    "p_we",
    "p_waddr",
    "p_wdata",
];

impl VerilatedSequencer {
    /// The sequencer after power-up (idle, no result).
    pub fn new() -> Self {
        VerilatedSequencer { core: Core::new(SEQUENCER, 0, 10, &SEQUENCER_OUTPUT_WORDS) }
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
        ])
    }

    /// The output ports now.
    pub fn outputs(&self) -> SeqOutputs {
        let o = self.core.outputs::<16>();
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
    core: Core,
}

verilated_common!(VerilatedWeightStage, WeightInputs);

fn weight_outputs(o: &[u64]) -> WeightOutputs {
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

/// Output port names of the pipeline in the order [`Lockstep`] compares them.
pub const OUTPUT_PORTS: [&str; 7] = ["scan_ready", "busy", "nn_valid", "nn_index", "nn_dist", "cost_valid", "cost"];

/// Output port names of the particle-weight pipeline in the order [`PwLockstep`] compares
/// them (the pipeline's, then the weight stage's).
pub const PW_OUTPUT_PORTS: [&str; 15] = [
    "scan_ready",
    "busy",
    "nn_valid",
    "nn_index",
    "nn_dist",
    "cost_valid",
    "cost",
    "w_busy",
    "w_count",
    "min_cost",
    "w_valid",
    "w_index",
    "weight",
    "w_done",
    "w_sum",
];

/// Output port names of the weight stage in the order [`WeightLockstep`] compares them.
pub const WEIGHT_OUTPUT_PORTS: [&str; 8] =
    ["busy", "count", "min_cost", "w_valid", "w_index", "weight", "w_done", "w_sum"];

fn port_values(o: &Outputs) -> [u64; 7] {
    [o.scan_ready as u64, o.busy as u64, o.nn_valid as u64, o.nn_index as u64, o.nn_dist, o.cost_valid as u64, o.cost]
}

fn weight_port_values(o: &WeightOutputs) -> [u64; 8] {
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

/// A Verilated design and its reference, as [`LockstepOf`] runs them (implemented by
/// [`VerilatedPipeline`], [`VerilatedParticleWeights`], [`VerilatedWeightStage`] and
/// [`VerilatedSequencer`]).
pub trait Rtl: Sized {
    /// The input ports.
    type Inputs: Copy + PartialEq + fmt::Debug;
    /// The output ports.
    type Outputs: Copy + PartialEq + fmt::Debug;
    /// The cycle-accurate reference.
    type Reference: Clone;
    /// Output port names, in the order they are compared.
    const OUTPUT_PORTS: &'static [&'static str];
    /// The output port values in [`OUTPUT_PORTS`](Self::OUTPUT_PORTS) order.
    fn port_values(o: &Self::Outputs) -> Vec<u64>;
    /// The reference after reset for this RTL.
    fn new_reference(&self) -> Self::Reference;
    /// The reference's outputs now.
    fn reference_outputs(r: &Self::Reference) -> Self::Outputs;
    /// One rising edge of the reference.
    fn reference_step(r: &mut Self::Reference, i: &Self::Inputs);
    /// A fresh instance of the same model, after reset.
    fn fresh(&self) -> Self;
    /// Drive the input ports.
    fn set_inputs(&mut self, i: &Self::Inputs);
    /// The output ports now.
    fn outputs(&self) -> Self::Outputs;
    /// One clock.
    fn tick(&mut self);
    /// Rising edges so far.
    fn cycle(&self) -> u64;
    /// Lanes (0 for the weight stage).
    fn lanes(&self) -> usize;
    /// The Verilator prefix.
    fn prefix(&self) -> &'static str;
    /// Trace to a VCD from now on.
    fn trace_to(&mut self, path: &Path) -> std::io::Result<()>;
    /// Flush the VCD.
    fn flush_trace(&mut self);
}

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

impl Rtl for VerilatedPipeline {
    type Inputs = Inputs;
    type Outputs = Outputs;
    type Reference = PipelineModel;
    const OUTPUT_PORTS: &'static [&'static str] = &OUTPUT_PORTS;
    fn port_values(o: &Outputs) -> Vec<u64> {
        port_values(o).to_vec()
    }
    fn new_reference(&self) -> PipelineModel {
        PipelineModel::new(self.lanes())
    }
    fn reference_outputs(r: &PipelineModel) -> Outputs {
        r.outputs()
    }
    fn reference_step(r: &mut PipelineModel, i: &Inputs) {
        r.step(i)
    }
    fn fresh(&self) -> Self {
        Self::new(self.lanes())
    }
    rtl_common!(Inputs);
}

impl Rtl for VerilatedParticleWeights {
    type Inputs = PwInputs;
    type Outputs = PwOutputs;
    type Reference = ParticleWeightModel;
    const OUTPUT_PORTS: &'static [&'static str] = &PW_OUTPUT_PORTS;
    fn port_values(o: &PwOutputs) -> Vec<u64> {
        port_values(&o.nn).into_iter().chain(weight_port_values(&o.w)).collect()
    }
    fn new_reference(&self) -> ParticleWeightModel {
        ParticleWeightModel::new(self.lanes())
    }
    fn reference_outputs(r: &ParticleWeightModel) -> PwOutputs {
        r.outputs()
    }
    fn reference_step(r: &mut ParticleWeightModel, i: &PwInputs) {
        r.step(i)
    }
    fn fresh(&self) -> Self {
        Self::new(self.lanes())
    }
    rtl_common!(PwInputs);
}

/// The sequencer's output words as [`Rtl::OUTPUT_PORTS`] (a wide port's words numbered).
pub const SEQUENCER_OUTPUT_PORTS: [&str; 16] = [
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
        v.extend([o.p_we as u64, o.p_waddr as u64, o.p_wdata as u64]);
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

/// The first difference between the RTL and the reference.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mismatch {
    /// Rising edges before the comparison (0: after reset); VCD time `10 * cycle`.
    pub cycle: u64,
    /// The first differing output port (in the design's output port order:
    /// [`OUTPUT_PORTS`], [`PW_OUTPUT_PORTS`] or [`WEIGHT_OUTPUT_PORTS`]).
    pub signal: &'static str,
    /// The reference's value.
    pub expected: u64,
    /// The RTL's value.
    pub actual: u64,
    /// Other ports that differ at the same cycle.
    pub also: Vec<&'static str>,
    /// Lanes of the RTL (0 for the weight stage).
    pub lanes: usize,
    /// The Verilator prefix of the RTL (`Vpipe4`, `Vpw16`, `Vweights`).
    pub prefix: &'static str,
    /// The VCD of the RTL run up to and including this cycle (`None` if it could not be
    /// written; the reason went to stderr).
    pub vcd: Option<PathBuf>,
    /// The first cycle in the VCD (see [`LockstepOf::vcd_window`]).
    pub vcd_from: u64,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "RTL {}", self.prefix)?;
        if self.lanes > 0 {
            write!(f, " (P = {})", self.lanes)?;
        }
        write!(
            f,
            " differs from the reference at cycle {} (VCD time {}): {} expected {} (0x{:x}), actual {} (0x{:x})",
            self.cycle,
            10 * self.cycle,
            self.signal,
            self.expected,
            self.expected,
            self.actual,
            self.actual
        )?;
        if !self.also.is_empty() {
            write!(f, "; also differing: {}", self.also.join(", "))?;
        }
        match &self.vcd {
            Some(p) => write!(f, "; VCD (cycles {}..={}): {}", self.vcd_from, self.cycle, p.display()),
            None => write!(f, "; no VCD"),
        }
    }
}

impl std::error::Error for Mismatch {}

/// How a [`LockstepOf`] keeps its VCD.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceMode {
    /// Trace only when needed: the inputs are recorded (run-length encoded) and, on a
    /// mismatch, replayed into a fresh RTL that is traced over the last
    /// [`vcd_window`](LockstepOf::vcd_window) cycles up to the mismatch. Full speed.
    OnMismatch,
    /// Trace the run as it goes (slower; the VCD covers the whole run).
    Always,
}

/// Cycles before a mismatch that [`TraceMode::OnMismatch`] puts in the VCD by default (a
/// 16-lane VCD takes about 12 kB a clock).
pub const DEFAULT_VCD_WINDOW: u64 = 5_000;

static RUN_COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// A Verilated design ([`Rtl`]) and its reference, clock for clock: every output port is
/// compared after reset and after every rising edge.
pub struct LockstepOf<R: Rtl> {
    rtl: R,
    reference: R::Reference,
    mode: TraceMode,
    vcd: PathBuf,
    vcd_window: Option<u64>,
    /// Inputs applied so far, run-length encoded (for the replay in [`TraceMode::OnMismatch`]).
    history: Vec<(R::Inputs, u64)>,
    reset_checked: bool,
    compared: u64,
    failed: Option<Mismatch>,
    /// Keep going after a mismatch ([`collect_all`](Self::collect_all)).
    keep_going: bool,
    /// Mismatching clocks recorded (at most [`MAX_RECORDED_MISMATCHES`]) and counted.
    mismatches: Vec<Mismatch>,
    mismatch_count: u64,
}

/// Mismatches a [`LockstepOf::collect_all`] run records (later ones are only counted).
pub const MAX_RECORDED_MISMATCHES: usize = 1_000;

/// The nearest-neighbour pipeline in lockstep with [`PipelineModel`].
pub type Lockstep = LockstepOf<VerilatedPipeline>;
/// The particle-weight pipeline in lockstep with [`ParticleWeightModel`].
pub type PwLockstep = LockstepOf<VerilatedParticleWeights>;
/// The weight stage in lockstep with [`WeightModel`].
pub type WeightLockstep = LockstepOf<VerilatedWeightStage>;
/// The particle-filter sequencer in lockstep with [`SequencerModel`].
pub type SeqLockstep = LockstepOf<VerilatedSequencer>;

impl<R: Rtl> LockstepOf<R> {
    /// `rtl` (which must not have been clocked) against its reference after reset; VCD (on
    /// mismatch) under the system temp directory; see [`vcd`](Self::vcd).
    pub fn from_rtl(rtl: R) -> Self {
        assert_eq!(rtl.cycle(), 0, "LockstepOf::from_rtl needs an RTL that was not clocked");
        let n = RUN_COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let vcd = std::env::temp_dir().join(format!(
            "pficp-sim-{}-{}-{n}.vcd",
            rtl.prefix().to_lowercase(),
            std::process::id()
        ));
        LockstepOf {
            reference: rtl.new_reference(),
            rtl,
            mode: TraceMode::OnMismatch,
            vcd,
            vcd_window: Some(DEFAULT_VCD_WINDOW),
            history: Vec::new(),
            reset_checked: false,
            compared: 0,
            failed: None,
            keep_going: false,
            mismatches: Vec::new(),
            mismatch_count: 0,
        }
    }

    fn assert_fresh(&self, what: &str) {
        assert!(self.rtl.cycle() == 0 && !self.reset_checked, "Lockstep::{what} must be called before the first step");
    }

    /// Where the VCD goes.
    pub fn vcd(mut self, path: impl Into<PathBuf>) -> Self {
        self.assert_fresh("vcd");
        self.vcd = path.into();
        self
    }

    /// How the VCD is kept (default [`TraceMode::OnMismatch`]).
    pub fn trace_mode(mut self, mode: TraceMode) -> Self {
        self.assert_fresh("trace_mode");
        self.mode = mode;
        self
    }

    /// With [`TraceMode::OnMismatch`]: the VCD starts this many cycles before the mismatch
    /// (`None`: at reset). Default [`DEFAULT_VCD_WINDOW`].
    pub fn vcd_window(mut self, cycles: Option<u64>) -> Self {
        self.vcd_window = cycles;
        self
    }

    /// Compare against this reference instead of the one after reset (it may have a
    /// different configuration or state: a way to check that the checker catches errors).
    pub fn with_reference(mut self, reference: R::Reference) -> Self {
        self.assert_fresh("with_reference");
        self.reference = reference;
        self
    }

    /// Keep going after a mismatch: every clock on which a port differs is a [`Mismatch`]
    /// (cycle, first differing port, expected, actual, the other differing ports), recorded
    /// up to [`MAX_RECORDED_MISMATCHES`] and counted beyond; the VCD is written at the
    /// first. [`step`](Self::step) still returns each clock's mismatch; [`finish`](Self::finish)
    /// returns them all.
    pub fn collect_all(mut self) -> Self {
        self.assert_fresh("collect_all");
        self.keep_going = true;
        self
    }

    /// The mismatches recorded so far (all of them up to [`MAX_RECORDED_MISMATCHES`]).
    pub fn mismatches(&self) -> &[Mismatch] {
        &self.mismatches
    }

    /// Clocks on which some port differed.
    pub fn mismatch_count(&self) -> u64 {
        self.mismatch_count
    }

    /// The clocks compared, or every recorded mismatch.
    pub fn finish(&self) -> Result<u64, Vec<Mismatch>> {
        if self.mismatch_count == 0 {
            Ok(self.compared)
        } else {
            Err(self.mismatches.clone())
        }
    }

    /// The VCD path.
    pub fn vcd_path(&self) -> &Path {
        &self.vcd
    }

    /// The RTL.
    pub fn rtl(&self) -> &R {
        &self.rtl
    }

    /// The reference.
    pub fn reference(&self) -> &R::Reference {
        &self.reference
    }

    /// Rising edges after which every output port was compared (the reset comparison is
    /// not counted).
    pub fn clocks_compared(&self) -> u64 {
        self.compared
    }

    /// The output ports (equal on both sides while no mismatch was found).
    pub fn outputs(&self) -> R::Outputs {
        self.rtl.outputs()
    }

    fn compare(&mut self) -> Result<(), Mismatch> {
        let (e, a) = (R::reference_outputs(&self.reference), self.rtl.outputs());
        if e == a {
            return Ok(());
        }
        let (ev, av) = (R::port_values(&e), R::port_values(&a));
        let differ: Vec<usize> = (0..R::OUTPUT_PORTS.len()).filter(|&k| ev[k] != av[k]).collect();
        let k = *differ.first().expect("outputs differ but no port value does");
        let first = self.mismatch_count == 0;
        self.mismatch_count += 1;
        let (vcd, vcd_from) = match self.mismatches.first() {
            Some(m0) if !first => (m0.vcd.clone(), m0.vcd_from),
            _ => self.finish_vcd(),
        };
        let m = Mismatch {
            cycle: self.rtl.cycle(),
            signal: R::OUTPUT_PORTS[k],
            expected: ev[k],
            actual: av[k],
            also: differ[1..].iter().map(|&j| R::OUTPUT_PORTS[j]).collect(),
            lanes: self.rtl.lanes(),
            prefix: self.rtl.prefix(),
            vcd,
            vcd_from,
        };
        if self.mismatches.len() < MAX_RECORDED_MISMATCHES {
            self.mismatches.push(m.clone());
        }
        if !self.keep_going {
            self.failed = Some(m.clone());
        }
        Err(m)
    }

    /// Leave a VCD of the RTL run up to now; returns it and its first cycle.
    fn finish_vcd(&mut self) -> (Option<PathBuf>, u64) {
        let (r, from) = match self.mode {
            TraceMode::Always => {
                self.rtl.flush_trace();
                (Ok(()), 0)
            }
            TraceMode::OnMismatch => {
                let from = self.vcd_window.map_or(0, |w| self.rtl.cycle().saturating_sub(w));
                (self.replay(from), from)
            }
        };
        match r {
            Ok(()) => (Some(self.vcd.clone()), from),
            Err(e) => {
                eprintln!("pficp-sim: cannot write the VCD {}: {e}", self.vcd.display());
                (None, from)
            }
        }
    }

    /// Replay the recorded inputs into a fresh RTL, traced from cycle `from`.
    fn replay(&self, from: u64) -> std::io::Result<()> {
        let mut replay = self.rtl.fresh();
        for (i, n) in &self.history {
            for _ in 0..*n {
                if replay.cycle() == from {
                    replay.trace_to(&self.vcd)?;
                }
                replay.set_inputs(i);
                replay.tick();
            }
        }
        if replay.cycle() == from {
            replay.trace_to(&self.vcd)?;
        }
        debug_assert_eq!(replay.cycle(), self.rtl.cycle());
        debug_assert_eq!(replay.outputs(), self.rtl.outputs());
        Ok(())
    }

    fn check_reset(&mut self) -> Result<(), Mismatch> {
        if let Some(m) = &self.failed {
            return Err(m.clone());
        }
        if !self.reset_checked {
            self.reset_checked = true;
            if self.mode == TraceMode::Always {
                if let Err(e) = self.rtl.trace_to(&self.vcd) {
                    eprintln!("pficp-sim: cannot write the VCD {}: {e}", self.vcd.display());
                }
            }
            let r = self.compare();
            if !self.keep_going {
                r?;
            }
        }
        Ok(())
    }

    /// One clock in lockstep: the same inputs to both, one rising edge each, every output
    /// port compared (the outputs after reset are compared before the first edge). After a
    /// mismatch every call returns it again.
    pub fn step(&mut self, i: &R::Inputs) -> Result<(), Mismatch> {
        self.check_reset()?;
        self.rtl.set_inputs(i);
        self.rtl.tick();
        R::reference_step(&mut self.reference, i);
        if self.mode == TraceMode::OnMismatch && self.mismatch_count == 0 {
            match self.history.last_mut() {
                Some((last, n)) if last == i => *n += 1,
                _ => self.history.push((*i, 1)),
            }
        }
        let r = self.compare();
        if r.is_ok() || self.keep_going {
            self.compared += 1;
        }
        r
    }
}

impl LockstepOf<VerilatedPipeline> {
    /// The `lanes`-lane RTL and `PipelineModel::new(lanes)`, both after reset; VCD (on
    /// mismatch) under the system temp directory; see [`vcd`](Self::vcd).
    pub fn new(lanes: usize) -> Self {
        Self::from_rtl(VerilatedPipeline::new(lanes))
    }

    /// Write the model RAM, one point a clock from address 0.
    pub fn load_model(&mut self, model: &[FxPoint]) -> Result<(), Mismatch> {
        load_model(|i| self.step(i), model)
    }

    /// One particle on the loaded model of `model_count` points: wait for `busy` to drop,
    /// `start` with `pose`, then stream `scan`, offering a point on the clocks (counted from
    /// the start edge = 1) where `gap(clock)` is false (the pipeline's `scan_ready` is the
    /// back-pressure); collect the results until `cost_valid`. Returns the evaluation and the
    /// clocks from `start` to `cost_valid` (as `pficp_fpga::pipeline::run_particle`).
    pub fn particle(
        &mut self,
        model_count: usize,
        scan: &[FxPoint],
        pose: &FxPose,
        gap: impl FnMut(u64) -> bool,
    ) -> Result<(Evaluation, u64), Mismatch> {
        self.check_reset()?;
        let now = self.outputs();
        drive_particle(
            |i| {
                self.step(i)?;
                Ok(self.outputs())
            },
            now,
            model_count,
            scan,
            pose,
            gap,
        )
    }

    /// [`load_model`](Self::load_model) then [`particle`](Self::particle), all in lockstep.
    pub fn run_particle(
        &mut self,
        model: &[FxPoint],
        scan: &[FxPoint],
        pose: &FxPose,
        gap: impl FnMut(u64) -> bool,
    ) -> Result<(Evaluation, u64), Mismatch> {
        self.load_model(model)?;
        self.particle(model.len(), scan, pose, gap)
    }
}

/// The weights of one weight pass, as [`PwLockstep::weigh`] and [`WeightLockstep::weigh`]
/// collect them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WeightPass {
    /// `w_index` of every `w_valid`, in order.
    pub indices: Vec<u8>,
    /// `weight` of every `w_valid`, in order.
    pub weights: Vec<u16>,
    /// `w_sum` at `w_done`.
    pub sum: u32,
    /// Rising edges after the edge that started the pass (the first with `busy`) up to and
    /// including the `w_done` edge.
    pub clocks: u64,
}

impl LockstepOf<VerilatedParticleWeights> {
    /// The `lanes`-lane particle-weight RTL and `ParticleWeightModel::new(lanes)`, both after
    /// reset; VCD (on mismatch) under the system temp directory; see [`vcd`](Self::vcd).
    pub fn new(lanes: usize) -> Self {
        Self::from_rtl(VerilatedParticleWeights::new(lanes))
    }

    /// Write the model RAM, one point a clock from address 0 (weight controls low).
    pub fn load_model(&mut self, model: &[FxPoint]) -> Result<(), Mismatch> {
        load_model(|i| self.step(&PwInputs { nn: *i, ..Default::default() }), model)
    }

    /// [`Lockstep::particle`] with the weight controls low: the particle's cost goes into
    /// the weight stage at the edge after `cost_valid` (if the stage is idle and not full).
    pub fn particle(
        &mut self,
        model_count: usize,
        scan: &[FxPoint],
        pose: &FxPose,
        gap: impl FnMut(u64) -> bool,
    ) -> Result<(Evaluation, u64), Mismatch> {
        self.check_reset()?;
        let now = self.outputs().nn;
        drive_particle(
            |i| {
                self.step(&PwInputs { nn: *i, ..Default::default() })?;
                Ok(self.outputs().nn)
            },
            now,
            model_count,
            scan,
            pose,
            gap,
        )
    }

    /// Wait for the weight stage to be idle, then `clear` for one clock.
    pub fn clear(&mut self) -> Result<(), Mismatch> {
        self.check_reset()?;
        let now = self.outputs().w;
        drive_clear(
            |i| {
                self.step(&PwInputs { clear: i.clear, ..Default::default() })?;
                Ok(self.outputs().w)
            },
            now,
        )
    }

    /// Wait for the weight stage to be idle, hold `weigh` with `scale` until the pass starts
    /// (a cost stored at the same edge has priority), and collect the weights until
    /// `w_done`. Panics if the pass does not start (no cost stored).
    pub fn weigh(&mut self, scale: &WeightScale) -> Result<WeightPass, Mismatch> {
        self.check_reset()?;
        let now = self.outputs().w;
        drive_weigh(
            |i| {
                self.step(&PwInputs { weigh: i.weigh, pre_shift: i.pre_shift, q_mul: i.q_mul, ..Default::default() })?;
                Ok(self.outputs().w)
            },
            now,
            scale,
        )
    }
}

impl LockstepOf<VerilatedWeightStage> {
    /// The weight-stage RTL and `WeightModel::new()`, both after reset; VCD (on mismatch)
    /// under the system temp directory; see [`vcd`](Self::vcd).
    pub fn new() -> Self {
        Self::from_rtl(VerilatedWeightStage::new())
    }

    /// Wait for the stage to be idle, then `clear` for one clock.
    pub fn clear(&mut self) -> Result<(), Mismatch> {
        self.check_reset()?;
        let now = self.outputs();
        drive_clear(
            |i| {
                self.step(i)?;
                Ok(self.outputs())
            },
            now,
        )
    }

    /// Wait for the stage to be idle, then offer `cost` for one clock (stored unless 256
    /// costs are stored).
    pub fn push_cost(&mut self, cost: u64) -> Result<(), Mismatch> {
        self.check_reset()?;
        let now = self.outputs();
        let mut step = |i: &WeightInputs| {
            self.step(i)?;
            Ok(self.outputs())
        };
        wait_weight_idle(&mut step, now)?;
        step(&WeightInputs { cost_valid: true, cost, ..Default::default() })?;
        Ok(())
    }

    /// As [`PwLockstep::weigh`].
    pub fn weigh(&mut self, scale: &WeightScale) -> Result<WeightPass, Mismatch> {
        self.check_reset()?;
        let now = self.outputs();
        drive_weigh(
            |i| {
                self.step(i)?;
                Ok(self.outputs())
            },
            now,
            scale,
        )
    }
}

impl Default for LockstepOf<VerilatedWeightStage> {
    fn default() -> Self {
        Self::new()
    }
}

/// Step with no inputs while `busy`, then once with `clear` (`step` as in [`drive_weigh`]).
fn drive_clear<E>(
    mut step: impl FnMut(&WeightInputs) -> Result<WeightOutputs, E>,
    now: WeightOutputs,
) -> Result<(), E> {
    wait_weight_idle(&mut step, now)?;
    step(&WeightInputs { clear: true, ..Default::default() })?;
    Ok(())
}

/// Step with no inputs while `busy`; returns the outputs then.
fn wait_weight_idle<E>(
    step: &mut impl FnMut(&WeightInputs) -> Result<WeightOutputs, E>,
    mut now: WeightOutputs,
) -> Result<WeightOutputs, E> {
    let mut wait = 0;
    while now.busy {
        now = step(&WeightInputs::default())?;
        wait += 1;
        assert!(wait <= MAX_PARTICLES + 16, "the weight stage never became idle");
    }
    Ok(now)
}

/// The weight-pass driver: `step` applies the weight stage's controls (`weigh`,
/// `pre_shift`, `q_mul` of the argument) for one edge and returns the stage's outputs after
/// it; `now` are the outputs before.
fn drive_weigh<E>(
    mut step: impl FnMut(&WeightInputs) -> Result<WeightOutputs, E>,
    mut now: WeightOutputs,
    scale: &WeightScale,
) -> Result<WeightPass, E> {
    now = wait_weight_idle(&mut step, now)?;
    let weigh =
        WeightInputs { weigh: true, pre_shift: scale.pre_shift as u8, q_mul: scale.q_mul, ..Default::default() };
    let mut tries = 0;
    while !now.busy {
        // A cost arriving at the same edge has priority over `weigh`: hold it.
        assert!(tries < 4, "weigh did not start the pass (no cost stored?)");
        now = step(&weigh)?;
        tries += 1;
    }
    let mut pass = WeightPass { indices: vec![], weights: vec![], sum: 0, clocks: 0 };
    loop {
        now = step(&WeightInputs::default())?;
        pass.clocks += 1;
        if now.w_valid {
            pass.indices.push(now.w_index);
            pass.weights.push(now.weight);
        }
        if now.w_done {
            pass.sum = now.w_sum;
            return Ok(pass);
        }
        assert!(pass.clocks <= MAX_PARTICLES as u64 + 16, "no w_done after {} clocks", pass.clocks);
    }
}

impl VerilatedPipeline {
    /// Write the model RAM, one point a clock from address 0 (RTL only, no reference).
    pub fn load_model(&mut self, model: &[FxPoint]) {
        let r: Result<(), std::convert::Infallible> = load_model(
            |i| {
                self.step(i);
                Ok(())
            },
            model,
        );
        r.unwrap()
    }

    /// [`Lockstep::particle`] on the RTL alone (no reference; for speed measurements and
    /// long runs checked against `pficp_fpga::pipeline::evaluate`).
    pub fn particle(
        &mut self,
        model_count: usize,
        scan: &[FxPoint],
        pose: &FxPose,
        gap: impl FnMut(u64) -> bool,
    ) -> (Evaluation, u64) {
        let now = self.outputs();
        let r: Result<_, std::convert::Infallible> = drive_particle(
            |i| {
                self.step(i);
                Ok(self.outputs())
            },
            now,
            model_count,
            scan,
            pose,
            gap,
        );
        r.unwrap()
    }
}

fn load_model<E>(mut step: impl FnMut(&Inputs) -> Result<(), E>, model: &[FxPoint]) -> Result<(), E> {
    assert!(model.len() <= MAX_POINTS);
    for (a, &p) in model.iter().enumerate() {
        step(&Inputs { model_we: true, model_waddr: a as u16, model_wdata: pack_point(p), ..Default::default() })?;
    }
    Ok(())
}

/// The particle driver shared by the lockstep types and [`VerilatedPipeline`]: `step`
/// applies inputs for one edge and returns the outputs after it; `now` are the outputs
/// before.
fn drive_particle<E>(
    mut step: impl FnMut(&Inputs) -> Result<Outputs, E>,
    mut now: Outputs,
    model_count: usize,
    scan: &[FxPoint],
    pose: &FxPose,
    mut gap: impl FnMut(u64) -> bool,
) -> Result<(Evaluation, u64), E> {
    assert!(!scan.is_empty() && (1..=MAX_POINTS).contains(&model_count));
    let mut wait = 0u64;
    while now.busy {
        now = step(&Inputs::default())?;
        wait += 1;
        assert!(wait < 1 << 32, "the pipeline never became idle");
    }
    now = step(&Inputs { start: true, pose: *pose, model_count: model_count as u16, ..Default::default() })?;
    let mut next = 0;
    let mut nearest = Vec::with_capacity(scan.len());
    let mut clocks = 1u64;
    // Generous bound: every batch sweeps the model once.
    let limit = 1000 + (scan.len() as u64 + 1) * (model_count as u64 + 100) * 4;
    loop {
        let offer = next < scan.len() && !gap(clocks);
        let inputs = Inputs {
            scan_valid: offer,
            scan_data: if offer { pack_point(scan[next]) } else { 0 },
            scan_last: offer && next + 1 == scan.len(),
            ..Default::default()
        };
        let took = offer && now.scan_ready;
        now = step(&inputs)?;
        clocks += 1;
        if took {
            next += 1;
        }
        if now.nn_valid {
            nearest.push((now.nn_index, now.nn_dist));
        }
        if now.cost_valid {
            return Ok((Evaluation { cost: now.cost, nearest }, clocks));
        }
        assert!(clocks < limit, "no cost_valid after {clocks} clocks ({next} of {} points taken)", scan.len());
    }
}

impl<R: Rtl + fmt::Debug> fmt::Debug for LockstepOf<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Lockstep")
            .field("rtl", &self.rtl)
            .field("mode", &self.mode)
            .field("vcd", &self.vcd)
            .field("clocks_compared", &self.compared)
            .field("failed", &self.failed)
            .finish()
    }
}
