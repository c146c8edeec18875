//! [`LockstepOf`], the one harness that runs a Verilated design and its reference clock for
//! clock and compares every output port (the designs plug in through [`Rtl`]).

use crate::rtl::Rtl;
use crate::wrappers::*;
use pficp_fpga::common::format::WeightScale;
use pficp_fpga::filter::weights::{WeightInputs, WeightOutputs, MAX_PARTICLES};
use std::fmt;
use std::path::{Path, PathBuf};

/// The first difference between the RTL and the reference.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mismatch {
    /// Rising edges before the comparison (0: after reset); VCD time `10 * cycle`.
    pub cycle: u64,
    /// The first differing output port (in the design's output port order, its
    /// [`Rtl::OUTPUT_PORTS`]: [`NEIGHBOUR_OUTPUT_PORTS`], [`WEIGHT_OUTPUT_PORTS`], ...).
    pub signal: &'static str,
    /// The reference's value.
    pub expected: u64,
    /// The RTL's value.
    pub actual: u64,
    /// Other ports that differ at the same cycle.
    pub also: Vec<&'static str>,
    /// Lanes of the RTL (0 for a design without lanes).
    pub lanes: usize,
    /// The Verilator prefix of the RTL (`Vnbr4`, `Vweights`, `Vseq`).
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

/// The weight stage in lockstep with [`WeightModel`](pficp_fpga::filter::weights::WeightModel).
pub type WeightLockstep = LockstepOf<VerilatedWeightStage>;
/// The surface residual stage in lockstep with
/// [`SurfaceResidualModel`](pficp_fpga::surface::surface_residual::SurfaceResidualModel).
pub type SurfaceLockstep = LockstepOf<VerilatedSurfaceResidual>;
/// The particle-filter sequencer in lockstep with
/// [`SequencerModel`](pficp_fpga::filter::sequencer::SequencerModel).
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

/// The weights of one weight pass, as [`WeightLockstep::weigh`] collects them.
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

impl LockstepOf<VerilatedWeightStage> {
    /// The weight-stage RTL and `WeightModel::new()`, both after reset; VCD (on mismatch)
    /// under the system temp directory; see [`vcd`](Self::vcd).
    pub fn new() -> Self {
        Self::from_rtl(VerilatedWeightStage::new())
    }

    /// For the drivers below, after the reset comparison: the outputs now, and a step that
    /// applies inputs for one clock in lockstep and returns the outputs after it.
    #[allow(clippy::type_complexity)] // (outputs, step): the two things every driver takes
    fn driver(
        &mut self,
    ) -> Result<(WeightOutputs, impl FnMut(&WeightInputs) -> Result<WeightOutputs, Mismatch> + '_), Mismatch> {
        self.check_reset()?;
        let now = self.outputs();
        Ok((now, move |i: &WeightInputs| {
            self.step(i)?;
            Ok(self.outputs())
        }))
    }

    /// Wait for the weight stage to be idle, then `clear` for one clock.
    pub fn clear(&mut self) -> Result<(), Mismatch> {
        let (now, step) = self.driver()?;
        drive_clear(step, now)
    }

    /// Wait for the weight stage to be idle, hold `weigh` with `scale` until the pass starts
    /// (a cost stored at the same edge has priority), and collect the weights until
    /// `w_done`. Panics if the pass does not start (no cost stored).
    pub fn weigh(&mut self, scale: &WeightScale) -> Result<WeightPass, Mismatch> {
        let (now, step) = self.driver()?;
        drive_weigh(step, now, scale)
    }

    /// Wait for the stage to be idle, then offer `cost` for one clock (stored unless 256
    /// costs are stored).
    pub fn push_cost(&mut self, cost: u64) -> Result<(), Mismatch> {
        let (now, mut step) = self.driver()?;
        wait_weight_idle(&mut step, now)?;
        step(&WeightInputs { cost_valid: true, cost, ..Default::default() })?;
        Ok(())
    }
}

impl LockstepOf<VerilatedSurfaceResidual> {
    /// The residual-stage RTL and `SurfaceResidualModel::new()`, both after reset; VCD (on
    /// mismatch) under the system temp directory; see [`vcd`](Self::vcd).
    pub fn new() -> Self {
        Self::from_rtl(VerilatedSurfaceResidual::new())
    }
}

impl Default for LockstepOf<VerilatedSurfaceResidual> {
    fn default() -> Self {
        Self::new()
    }
}

impl Default for LockstepOf<VerilatedWeightStage> {
    fn default() -> Self {
        Self::new()
    }
}

/// Step with no inputs while `busy`, then once with `clear` (`step` as in [`drive_weigh`]).
pub(crate) fn drive_clear<E>(
    mut step: impl FnMut(&WeightInputs) -> Result<WeightOutputs, E>,
    now: WeightOutputs,
) -> Result<(), E> {
    wait_weight_idle(&mut step, now)?;
    step(&WeightInputs { clear: true, ..Default::default() })?;
    Ok(())
}

/// Step with no inputs while `busy`; returns the outputs then.
pub(crate) fn wait_weight_idle<E>(
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
pub(crate) fn drive_weigh<E>(
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
