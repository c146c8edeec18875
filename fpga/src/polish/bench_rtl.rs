//! `PolishBench`: the pass ([`PolishPass`]), a [`PipeMul`] and the program's datapath
//! ([`PolishProgram`]) wired as the board will wire them: the pass's products on the
//! multiplier, its adds into the program's registers. On the board the multiplier is the
//! sequencer's, idle after the filter; here the bench has its own, so that the blocks can
//! be tested together in rust_hdl's simulator (`fpga/tests/polish_pass.rs`) and under
//! Verilator (`sim/tests/polish_pass.rs`, from [`crate::common::verilog::polish_bench_verilog`]).
//! A pass's points go in at `in_*`; the programs run on `go` at `entry`.

use super::pass_rtl::PolishPass;
use super::program_rtl::PolishProgram;
use super::unit_rtl::PolishUnit;
use crate::common::pipe_mul_rtl::PipeMul;
use rust_hdl::prelude::*;

/// The polish's blocks with their own multiplier.
#[derive(LogicBlock)]
pub struct PolishBench {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset of all three.
    pub reset: Signal<In, Bit>,
    /// The pass's gate on ([`PolishPass::gated`]).
    pub gated: Signal<In, Bit>,
    /// The pass's gate.
    pub tau2: Signal<In, Bits<32>>,
    /// The scale held ([`PolishPass::scale_held`]).
    pub scale_held: Signal<In, Bit>,
    /// The pose's translation (3 x 18 bits, x low).
    pub t: Signal<In, Bits<54>>,
    /// Take a point (while `ready`).
    pub in_valid: Signal<In, Bit>,
    /// Its image (3 x 16 bits).
    pub in_q: Signal<In, Bits<48>>,
    /// Its nearest stored point's normal (3 x 16 bits).
    pub in_n: Signal<In, Bits<48>>,
    /// Its signed residual (13 bits).
    pub in_s: Signal<In, Bits<13>>,
    /// The pass's front is free: a point may come.
    pub ready: Signal<Out, Bit>,
    /// The pass's points are all in: flush ([`PolishPass::flush`]).
    pub flush: Signal<In, Bit>,
    /// The pass is idle and flushed ([`PolishPass::idle`]).
    pub idle: Signal<Out, Bit>,
    /// While the program is idle: write `load_data` to register `load_addr`.
    pub load: Signal<In, Bit>,
    /// Register to load.
    pub load_addr: Signal<In, Bits<6>>,
    /// Value to load.
    pub load_data: Signal<In, Bits<128>>,
    /// While idle: the register `read_data` shows on the next clock.
    pub read_addr: Signal<In, Bits<6>>,
    /// The register read.
    pub read_data: Signal<Out, Bits<128>>,
    /// Run the program at `entry`.
    pub go: Signal<In, Bit>,
    /// The program `go` starts.
    pub entry: Signal<In, Bits<9>>,
    /// The program is running.
    pub busy: Signal<Out, Bit>,
    /// The last program failed.
    pub failed: Signal<Out, Bit>,
    pass: PolishPass,
    mul: PipeMul,
    prog: PolishProgram,
}

impl PolishBench {
    /// The blocks, the program's ROM the polish's ([`PolishProgram::polish`]).
    pub fn new() -> Self {
        PolishBench {
            clock: Default::default(),
            reset: Default::default(),
            gated: Default::default(),
            tau2: Default::default(),
            scale_held: Default::default(),
            t: Default::default(),
            in_valid: Default::default(),
            in_q: Default::default(),
            in_n: Default::default(),
            in_s: Default::default(),
            ready: Default::default(),
            flush: Default::default(),
            idle: Default::default(),
            load: Default::default(),
            load_addr: Default::default(),
            load_data: Default::default(),
            read_addr: Default::default(),
            read_data: Default::default(),
            go: Default::default(),
            entry: Default::default(),
            busy: Default::default(),
            failed: Default::default(),
            pass: PolishPass::new(),
            mul: PipeMul::new(),
            prog: PolishProgram::polish(),
        }
    }
}

impl Default for PolishBench {
    fn default() -> Self {
        Self::new()
    }
}

impl Logic for PolishBench {
    #[hdl_gen]
    fn update(&mut self) {
        self.pass.clock.next = self.clock.val();
        self.mul.clock.next = self.clock.val();
        self.prog.clock.next = self.clock.val();
        self.pass.reset.next = self.reset.val();
        self.mul.reset.next = self.reset.val();
        self.prog.reset.next = self.reset.val();
        self.pass.gated.next = self.gated.val();
        self.pass.tau2.next = self.tau2.val();
        self.pass.scale_held.next = self.scale_held.val();
        self.pass.t.next = self.t.val();
        self.pass.in_valid.next = self.in_valid.val();
        self.pass.in_q.next = self.in_q.val();
        self.pass.in_n.next = self.in_n.val();
        self.pass.in_s.next = self.in_s.val();
        self.ready.next = self.pass.ready.val();
        self.pass.flush.next = self.flush.val();
        self.idle.next = self.pass.idle.val();
        self.mul.go.next = self.pass.mul_go.val();
        self.mul.a.next = self.pass.mul_a.val();
        self.mul.b.next = self.pass.mul_b.val();
        self.pass.mul_product.next = self.mul.product.val();
        self.prog.add.next = self.pass.add.val();
        self.prog.add_addr.next = self.pass.add_addr.val();
        self.prog.add_data.next = self.pass.add_data.val();
        self.prog.load.next = self.load.val();
        self.prog.load_addr.next = self.load_addr.val();
        self.prog.load_data.next = self.load_data.val();
        self.prog.read_addr.next = self.read_addr.val();
        self.read_data.next = self.prog.read_data.val();
        self.prog.go.next = self.go.val();
        self.prog.entry.next = self.entry.val();
        self.busy.next = self.prog.busy.val();
        self.failed.next = self.prog.failed.val();
    }
}

/// The whole polish ([`PolishUnit`]) with a multiplier of its own: the test top of the
/// control (`fpga/tests/polish_control.rs`), the pass service and the start poses played by
/// the test.
#[derive(LogicBlock)]
pub struct PolishUnitBench {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset.
    pub reset: Signal<In, Bit>,
    /// While idle: polish.
    pub go: Signal<In, Bit>,
    /// Starts (1 to 15; 0 taken as 1).
    pub starts: Signal<In, Bits<4>>,
    /// Steps a start.
    pub steps: Signal<In, Bits<4>>,
    /// The winner's further steps (0: none).
    pub winner_steps: Signal<In, Bits<4>>,
    /// The scale held ([`PolishUnit::scale_held`]).
    pub scale_held: Signal<In, Bit>,
    /// The start taken next.
    pub start_index: Signal<Out, Bits<4>>,
    /// Its pose.
    pub start_pose: Signal<In, Bits<216>>,
    /// Ask for a pass at `pose`.
    pub pass_go: Signal<Out, Bit>,
    /// The pass's pose; once done, the winner's.
    pub pose: Signal<Out, Bits<216>>,
    /// The pass is over.
    pub pass_done: Signal<In, Bit>,
    /// Its cost.
    pub pass_cost: Signal<In, Bits<48>>,
    /// A found point (while `ready`).
    pub in_valid: Signal<In, Bit>,
    /// Its image.
    pub in_q: Signal<In, Bits<48>>,
    /// Its normal.
    pub in_n: Signal<In, Bits<48>>,
    /// Its signed residual.
    pub in_s: Signal<In, Bits<13>>,
    /// The pass takes a point.
    pub ready: Signal<Out, Bit>,
    /// Polishing.
    pub busy: Signal<Out, Bit>,
    /// A result is held.
    pub done: Signal<Out, Bit>,
    /// The winning start.
    pub best_index: Signal<Out, Bits<4>>,
    /// Its cost.
    pub best_cost: Signal<Out, Bits<48>>,
    unit: PolishUnit,
    mul: PipeMul,
}

impl PolishUnitBench {
    /// The unit and a multiplier.
    pub fn new() -> Self {
        PolishUnitBench {
            clock: Default::default(),
            reset: Default::default(),
            go: Default::default(),
            starts: Default::default(),
            steps: Default::default(),
            winner_steps: Default::default(),
            scale_held: Default::default(),
            start_index: Default::default(),
            start_pose: Default::default(),
            pass_go: Default::default(),
            pose: Default::default(),
            pass_done: Default::default(),
            pass_cost: Default::default(),
            in_valid: Default::default(),
            in_q: Default::default(),
            in_n: Default::default(),
            in_s: Default::default(),
            ready: Default::default(),
            busy: Default::default(),
            done: Default::default(),
            best_index: Default::default(),
            best_cost: Default::default(),
            unit: PolishUnit::new(),
            mul: PipeMul::new(),
        }
    }
}

impl Default for PolishUnitBench {
    fn default() -> Self {
        Self::new()
    }
}

impl Logic for PolishUnitBench {
    #[hdl_gen]
    fn update(&mut self) {
        self.unit.clock.next = self.clock.val();
        self.mul.clock.next = self.clock.val();
        self.unit.reset.next = self.reset.val();
        self.mul.reset.next = self.reset.val();
        self.unit.go.next = self.go.val();
        self.unit.starts.next = self.starts.val();
        self.unit.steps.next = self.steps.val();
        self.unit.winner_steps.next = self.winner_steps.val();
        self.unit.scale_held.next = self.scale_held.val();
        self.start_index.next = self.unit.start_index.val();
        self.unit.start_pose.next = self.start_pose.val();
        self.pass_go.next = self.unit.pass_go.val();
        self.pose.next = self.unit.pose.val();
        self.unit.pass_done.next = self.pass_done.val();
        self.unit.pass_cost.next = self.pass_cost.val();
        self.unit.in_valid.next = self.in_valid.val();
        self.unit.in_q.next = self.in_q.val();
        self.unit.in_n.next = self.in_n.val();
        self.unit.in_s.next = self.in_s.val();
        self.ready.next = self.unit.ready.val();
        self.mul.go.next = self.unit.mul_go.val();
        self.mul.a.next = self.unit.mul_a.val();
        self.mul.b.next = self.unit.mul_b.val();
        self.unit.mul_product.next = self.mul.product.val();
        self.busy.next = self.unit.busy.val();
        self.done.next = self.unit.done.val();
        self.best_index.next = self.unit.best_index.val();
        self.best_cost.next = self.unit.best_cost.val();
    }
}
