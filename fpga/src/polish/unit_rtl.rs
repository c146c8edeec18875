//! `PolishUnit`: the on-board polish as the board instantiates it: the control
//! ([`PolishControl`]), the program's datapath ([`PolishProgram`]) and the pass
//! ([`PolishPass`]), wired to one another. Outside it: the multiplier (`mul_*`, the
//! sequencer's on the board), the pass service (`pass_go` at `pose`; the found points at
//! `in_*` while `ready`; `pass_done` with the cost once the last point is in) and the start
//! poses (`start_pose` for `start_index`). The unit holds `pass_done` back from the control
//! while the pass flushes its accumulators into the datapath's registers.

use super::control_rtl::PolishControl;
use super::pass_rtl::PolishPass;
use super::program_rtl::PolishProgram;
use rust_hdl::prelude::*;

/// The polish: control, datapath and pass.
#[derive(LogicBlock)]
pub struct PolishUnit {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset of all three.
    pub reset: Signal<In, Bit>,
    /// While idle: polish `starts` starts with up to `steps` steps each.
    pub go: Signal<In, Bit>,
    /// Starts (1 to 15; 0 taken as 1).
    pub starts: Signal<In, Bits<4>>,
    /// Steps a start.
    pub steps: Signal<In, Bits<4>>,
    /// The winner's further steps (0: none).
    pub winner_steps: Signal<In, Bits<4>>,
    /// The steps hold the scale ([`crate::polish::ScaleStep::Held`]; steady while busy).
    pub scale_held: Signal<In, Bit>,
    /// The start the unit takes next.
    pub start_index: Signal<Out, Bits<4>>,
    /// Its pose.
    pub start_pose: Signal<In, Bits<216>>,
    /// Ask for a pass over the scan at `pose`.
    pub pass_go: Signal<Out, Bit>,
    /// The pass's pose; once done, the winner's.
    pub pose: Signal<Out, Bits<216>>,
    /// The pass is over: its last point is in.
    pub pass_done: Signal<In, Bit>,
    /// The pass's cost.
    pub pass_cost: Signal<In, Bits<48>>,
    /// A found point of the pass (while `ready`).
    pub in_valid: Signal<In, Bit>,
    /// Its image.
    pub in_q: Signal<In, Bits<48>>,
    /// Its nearest stored point's normal.
    pub in_n: Signal<In, Bits<48>>,
    /// Its signed residual.
    pub in_s: Signal<In, Bits<13>>,
    /// The pass takes a point.
    pub ready: Signal<Out, Bit>,
    /// Multiplier: take `mul_a`, `mul_b`.
    pub mul_go: Signal<Out, Bit>,
    /// Multiplicand.
    pub mul_a: Signal<Out, Bits<26>>,
    /// Multiplier.
    pub mul_b: Signal<Out, Bits<18>>,
    /// The product of the pair issued three clocks before.
    pub mul_product: Signal<In, Bits<44>>,
    /// Polishing.
    pub busy: Signal<Out, Bit>,
    /// A result is held.
    pub done: Signal<Out, Bit>,
    /// The winning start.
    pub best_index: Signal<Out, Bits<4>>,
    /// Its cost.
    pub best_cost: Signal<Out, Bits<48>>,
    control: PolishControl,
    prog: PolishProgram,
    pass: PolishPass,
    /// A pass is over, its flush not yet.
    fwait: DFF<Bit>,
}

impl PolishUnit {
    /// The unit with the polish's ROM.
    pub fn new() -> Self {
        PolishUnit {
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
            mul_go: Default::default(),
            mul_a: Default::default(),
            mul_b: Default::default(),
            mul_product: Default::default(),
            busy: Default::default(),
            done: Default::default(),
            best_index: Default::default(),
            best_cost: Default::default(),
            control: PolishControl::new(),
            prog: PolishProgram::polish(),
            pass: PolishPass::new(),
            fwait: Default::default(),
        }
    }
}

impl Default for PolishUnit {
    fn default() -> Self {
        Self::new()
    }
}

impl Logic for PolishUnit {
    #[hdl_gen]
    fn update(&mut self) {
        self.control.clock.next = self.clock.val();
        self.prog.clock.next = self.clock.val();
        self.pass.clock.next = self.clock.val();
        self.control.reset.next = self.reset.val();
        self.prog.reset.next = self.reset.val();
        self.pass.reset.next = self.reset.val();
        // The control.
        self.control.go.next = self.go.val();
        self.control.starts.next = self.starts.val();
        self.control.steps.next = self.steps.val();
        self.control.winner_steps.next = self.winner_steps.val();
        self.start_index.next = self.control.start_index.val();
        self.control.start_pose.next = self.start_pose.val();
        self.pass_go.next = self.control.pass_go.val();
        self.pose.next = self.control.pose.val();
        // A pass's end: the pass flushes, then the control hears of it.
        self.fwait.clock.next = self.clock.val();
        self.fwait.d.next = self.fwait.q.val();
        self.pass.flush.next = self.pass_done.val();
        if self.pass_done.val() {
            self.fwait.d.next = true;
        }
        self.control.pass_done.next = false;
        if self.fwait.q.val() && self.pass.idle.val() {
            self.control.pass_done.next = true;
            self.fwait.d.next = false;
        }
        if self.reset.val() {
            self.fwait.d.next = false;
        }
        self.control.pass_cost.next = self.pass_cost.val();
        self.busy.next = self.control.busy.val();
        self.done.next = self.control.done.val();
        self.best_index.next = self.control.best_index.val();
        self.best_cost.next = self.control.best_cost.val();
        // The datapath, driven by the control, added to by the pass.
        self.prog.load.next = self.control.prog_load.val();
        self.prog.load_addr.next = self.control.prog_load_addr.val();
        self.prog.load_data.next = self.control.prog_load_data.val();
        self.prog.read_addr.next = self.control.prog_read_addr.val();
        self.control.prog_read_data.next = self.prog.read_data.val().get_bits::<32>(0);
        self.prog.go.next = self.control.prog_go.val();
        self.prog.entry.next = self.control.prog_entry.val();
        self.control.prog_busy.next = self.prog.busy.val();
        self.control.prog_failed.next = self.prog.failed.val();
        self.prog.add.next = self.pass.add.val();
        self.prog.add_addr.next = self.pass.add_addr.val();
        self.prog.add_data.next = self.pass.add_data.val();
        // The pass: the control's gate and the pose's translation (its top three fields).
        self.pass.gated.next = self.control.gated.val();
        self.pass.tau2.next = self.control.tau2.val();
        self.pass.scale_held.next = self.scale_held.val();
        self.pass.t.next = self.control.pose.val().get_bits::<54>(162);
        self.pass.in_valid.next = self.in_valid.val();
        self.pass.in_q.next = self.in_q.val();
        self.pass.in_n.next = self.in_n.val();
        self.pass.in_s.next = self.in_s.val();
        self.ready.next = self.pass.ready.val();
        self.mul_go.next = self.pass.mul_go.val();
        self.mul_a.next = self.pass.mul_a.val();
        self.mul_b.next = self.pass.mul_b.val();
        self.pass.mul_product.next = self.mul_product.val();
    }
}
