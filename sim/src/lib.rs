//! Verilator co-simulation of the nearest-neighbour pipeline (docs/pipeline.md) against the
//! bit-exact reference [`PipelineModel`].
//!
//! - [`VerilatedPipeline`]: the Verilated RTL (`pficp_fpga::rtl::pipeline_verilog(P)`, built by
//!   `build.rs` for the lane counts in [`verilated_lanes`]), one clock at a time, optional VCD.
//! - [`Lockstep`]: the RTL and a [`PipelineModel`] driven with the same inputs, every output
//!   port compared after reset and after every rising edge; the first difference is a
//!   [`Mismatch`] that names the cycle, the signal, both values and a VCD of the RTL run.
//!
//! Time in the VCDs: clock period 10; the state after reset is at time 0, the rising edge of
//! cycle `c` (`c` = 1, 2, ...) at time `10 c`, the falling edge before it (where the inputs
//! change) at `10 c - 5`. [`Mismatch::cycle`] `c` is therefore at VCD time `10 c`.
#![warn(missing_docs)]

use pficp_fpga::format::{pack_point, FxPoint, FxPose, MAX_POINTS};
use pficp_fpga::pipeline::{Evaluation, Inputs, Outputs, PipelineModel};
use std::ffi::CString;
use std::fmt;
use std::os::raw::{c_char, c_int, c_void};
use std::path::{Path, PathBuf};

/// One Verilated model in the archive (a table of its shim's entry points).
struct Model {
    lanes: usize,
    prefix: &'static str,
    verilog: &'static str,
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

/// Lane counts with a Verilated model (the build verilates 4 and 16 unless
/// `PFICP_SIM_LANES` says otherwise).
pub fn verilated_lanes() -> Vec<usize> {
    ffi::MODELS.iter().map(|m| m.lanes).collect()
}

/// The Verilog file that was verilated for `lanes`, if there is a model for it.
pub fn verilog_path(lanes: usize) -> Option<&'static Path> {
    ffi::MODELS.iter().find(|m| m.lanes == lanes).map(|m| Path::new(m.verilog))
}

/// The Verilated pipeline with its own `VerilatedContext` (instances are independent and
/// may live on different threads).
pub struct VerilatedPipeline {
    model: &'static Model,
    h: *mut c_void,
    cycle: u64,
    trace: Option<PathBuf>,
}

// The handle is owned exclusively; Verilator models with separate contexts may move between
// threads.
unsafe impl Send for VerilatedPipeline {}

impl VerilatedPipeline {
    /// A pipeline with `lanes` lanes after reset (all inputs low, evaluated once).
    ///
    /// Panics if no model was verilated for `lanes` (see [`verilated_lanes`]).
    pub fn new(lanes: usize) -> Self {
        let model = ffi::MODELS.iter().find(|m| m.lanes == lanes).unwrap_or_else(|| {
            panic!(
                "no Verilated model with {lanes} lanes (built: {:?}; rebuild with PFICP_SIM_LANES=...)",
                verilated_lanes()
            )
        });
        // SAFETY: the shim allocates and evaluates a fresh model.
        let h = unsafe { (model.new)() };
        assert!(!h.is_null());
        VerilatedPipeline { model, h, cycle: 0, trace: None }
    }

    /// Number of lanes.
    pub fn lanes(&self) -> usize {
        self.model.lanes
    }

    /// The Verilator prefix of the model (`Vpipe16`).
    pub fn prefix(&self) -> &'static str {
        self.model.prefix
    }

    /// Drive the input ports (sampled at the next [`tick`](Self::tick)'s rising edge).
    /// Values are masked to the port widths.
    pub fn set_inputs(&mut self, i: &Inputs) {
        let pose = i.pose.pack();
        let words: [u64; ffi::IN_WORDS] = [
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
        ];
        // SAFETY: the array has the length the shim reads.
        unsafe { (self.model.set_inputs)(self.h, words.as_ptr()) }
    }

    /// One clock: clock low, eval, clock high (the rising edge), eval; the VCD, if open,
    /// gets both phases.
    pub fn tick(&mut self) {
        self.cycle += 1;
        // SAFETY: valid handle.
        unsafe { (self.model.tick)(self.h, 10 * self.cycle) }
    }

    /// The output ports now.
    pub fn outputs(&self) -> Outputs {
        let mut o = [0u64; ffi::OUT_WORDS];
        // SAFETY: the array has the length the shim writes.
        unsafe { (self.model.get_outputs)(self.h, o.as_mut_ptr()) };
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

    /// Rising edges so far.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// Write a VCD of every signal from now on (the current state at time `10 * cycle`, then
    /// both phases of every clock). Replaces an open trace.
    pub fn trace_to(&mut self, path: impl AsRef<Path>) -> std::io::Result<()> {
        let path = path.as_ref();
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

    /// The open VCD, if any.
    pub fn trace_path(&self) -> Option<&Path> {
        self.trace.as_deref()
    }

    /// Flush the VCD to disk (it is also flushed when closed or dropped).
    pub fn flush_trace(&mut self) {
        // SAFETY: valid handle.
        unsafe { (self.model.trace_flush)(self.h) }
    }

    /// Close the VCD.
    pub fn close_trace(&mut self) {
        // SAFETY: valid handle.
        unsafe { (self.model.trace_close)(self.h) };
        self.trace = None;
    }
}

impl Drop for VerilatedPipeline {
    fn drop(&mut self) {
        // SAFETY: the handle came from `new` and is freed once.
        unsafe { (self.model.free)(self.h) }
    }
}

impl fmt::Debug for VerilatedPipeline {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("VerilatedPipeline")
            .field("prefix", &self.model.prefix)
            .field("cycle", &self.cycle)
            .field("trace", &self.trace)
            .finish()
    }
}

/// Output port names in the order [`Lockstep`] compares them.
pub const OUTPUT_PORTS: [&str; 7] = ["scan_ready", "busy", "nn_valid", "nn_index", "nn_dist", "cost_valid", "cost"];

fn port_values(o: &Outputs) -> [u64; 7] {
    [o.scan_ready as u64, o.busy as u64, o.nn_valid as u64, o.nn_index as u64, o.nn_dist, o.cost_valid as u64, o.cost]
}

/// The first difference between the RTL and the reference.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mismatch {
    /// Rising edges before the comparison (0: after reset); VCD time `10 * cycle`.
    pub cycle: u64,
    /// The first differing output port (in [`OUTPUT_PORTS`] order).
    pub signal: &'static str,
    /// The reference's value.
    pub expected: u64,
    /// The RTL's value.
    pub actual: u64,
    /// Other ports that differ at the same cycle.
    pub also: Vec<&'static str>,
    /// Lanes of the RTL.
    pub lanes: usize,
    /// The VCD of the RTL run up to and including this cycle (`None` if it could not be
    /// written; the reason went to stderr).
    pub vcd: Option<PathBuf>,
    /// The first cycle in the VCD (see [`Lockstep::vcd_window`]).
    pub vcd_from: u64,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "RTL (P = {}) differs from the reference at cycle {} (VCD time {}): {} expected {} (0x{:x}), actual {} (0x{:x})",
            self.lanes,
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

/// How [`Lockstep`] keeps its VCD.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceMode {
    /// Trace only when needed: the inputs are recorded (run-length encoded) and, on a
    /// mismatch, replayed into a fresh RTL that is traced over the last
    /// [`vcd_window`](Lockstep::vcd_window) cycles up to the mismatch. Full speed.
    OnMismatch,
    /// Trace the run as it goes (slower; the VCD covers the whole run).
    Always,
}

/// Cycles before a mismatch that [`TraceMode::OnMismatch`] puts in the VCD by default (a
/// 16-lane VCD takes about 12 kB a clock).
pub const DEFAULT_VCD_WINDOW: u64 = 5_000;

static RUN_COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// The Verilated RTL and the reference, clock for clock.
pub struct Lockstep {
    rtl: VerilatedPipeline,
    reference: PipelineModel,
    mode: TraceMode,
    vcd: PathBuf,
    vcd_window: Option<u64>,
    /// Inputs applied so far, run-length encoded (for the replay in [`TraceMode::OnMismatch`]).
    history: Vec<(Inputs, u64)>,
    reset_checked: bool,
    compared: u64,
    failed: Option<Mismatch>,
}

impl Lockstep {
    /// The `lanes`-lane RTL and `PipelineModel::new(lanes)`, both after reset; VCD (on
    /// mismatch) under the system temp directory; see [`vcd`](Self::vcd).
    pub fn new(lanes: usize) -> Self {
        let n = RUN_COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let vcd = std::env::temp_dir().join(format!("pficp-sim-p{lanes}-{}-{n}.vcd", std::process::id()));
        Lockstep {
            rtl: VerilatedPipeline::new(lanes),
            reference: PipelineModel::new(lanes),
            mode: TraceMode::OnMismatch,
            vcd,
            vcd_window: Some(DEFAULT_VCD_WINDOW),
            history: Vec::new(),
            reset_checked: false,
            compared: 0,
            failed: None,
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

    /// Compare against this reference instead of `PipelineModel::new(lanes)` (it may have
    /// a different lane count or state: a way to check that the checker catches errors).
    pub fn with_reference(mut self, reference: PipelineModel) -> Self {
        self.assert_fresh("with_reference");
        self.reference = reference;
        self
    }

    /// The VCD path.
    pub fn vcd_path(&self) -> &Path {
        &self.vcd
    }

    /// The RTL.
    pub fn rtl(&self) -> &VerilatedPipeline {
        &self.rtl
    }

    /// The reference.
    pub fn reference(&self) -> &PipelineModel {
        &self.reference
    }

    /// Rising edges after which every output port was compared (the reset comparison is
    /// not counted).
    pub fn clocks_compared(&self) -> u64 {
        self.compared
    }

    /// The output ports (equal on both sides while no mismatch was found).
    pub fn outputs(&self) -> Outputs {
        self.rtl.outputs()
    }

    fn compare(&mut self) -> Result<(), Mismatch> {
        let (e, a) = (self.reference.outputs(), self.rtl.outputs());
        if e == a {
            return Ok(());
        }
        let (ev, av) = (port_values(&e), port_values(&a));
        let differ: Vec<usize> = (0..OUTPUT_PORTS.len()).filter(|&k| ev[k] != av[k]).collect();
        let k = differ[0];
        let (vcd, vcd_from) = self.finish_vcd();
        let m = Mismatch {
            cycle: self.rtl.cycle(),
            signal: OUTPUT_PORTS[k],
            expected: ev[k],
            actual: av[k],
            also: differ[1..].iter().map(|&j| OUTPUT_PORTS[j]).collect(),
            lanes: self.rtl.lanes(),
            vcd,
            vcd_from,
        };
        self.failed = Some(m.clone());
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
        let mut replay = VerilatedPipeline::new(self.rtl.lanes());
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
            self.compare()?;
        }
        Ok(())
    }

    /// One clock in lockstep: the same inputs to both, one rising edge each, every output
    /// port compared (the outputs after reset are compared before the first edge). After a
    /// mismatch every call returns it again.
    pub fn step(&mut self, i: &Inputs) -> Result<(), Mismatch> {
        self.check_reset()?;
        self.rtl.set_inputs(i);
        self.rtl.tick();
        self.reference.step(i);
        if self.mode == TraceMode::OnMismatch {
            match self.history.last_mut() {
                Some((last, n)) if last == i => *n += 1,
                _ => self.history.push((*i, 1)),
            }
        }
        self.compare()?;
        self.compared += 1;
        Ok(())
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

impl VerilatedPipeline {
    /// Apply the inputs and tick.
    pub fn step(&mut self, i: &Inputs) {
        self.set_inputs(i);
        self.tick();
    }

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

/// The particle driver shared by [`Lockstep`] and [`VerilatedPipeline`]: `step` applies
/// inputs for one edge and returns the outputs after it; `now` are the outputs before.
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

impl fmt::Debug for Lockstep {
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
