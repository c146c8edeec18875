//! `PolishControl`: the on-board polish's sequence, the RTL of [`crate::polish::polish_best`]
//! over its programs ([`crate::polish::programs::Entry`]) and its passes. For each of
//! `starts` starts (the pose at `start_pose` while `start_index` names it):
//! - load the pose at `POSE`; `Start` (`|M|^2` for the drift check); `Clear`; a statistics
//!   pass;
//! - up to `steps` times: `Gate` (a failure ends the steps), `TAU2` read back, `Clear`, a
//!   gated pass, `Solve` (a failure ends the steps), `Update`, the pose read back;
//! - `Drift`: a failure drops the start, or for the first start keeps its pose unpolished;
//! - a pass at the final pose for its cost (the residual stage's sum); the lowest cost
//!   wins, the earlier start on a tie;
//! - with `winner_steps` above 0, the winner's pose once more as a start of its own
//!   (`second`), with `winner_steps` steps; its drift failure keeps the winner's pose; its
//!   pose and cost are the result ([`crate::polish::polish_winner_over`]).
//!
//! A pass is a service of the board around the block: `pass_go` asks for one over the whole
//! scan at `pose` (held until `pass_done`), the points go to the pass block with `gated`
//! and `tau2`, and `pass_done` comes once every point's adds are in the registers, with the
//! pass's cost in `pass_cost`. The program's datapath is driven through `prog_*` (the pass
//! block adds into it on its own port).

use crate::polish::programs::{rom, Entry, POSE, TAU2};
use rust_hdl::prelude::*;

/// Where the control is.
#[derive(Copy, Clone, Debug, PartialEq, Eq, LogicState)]
pub enum ControlState {
    /// Not running (`done` says whether a result is held).
    Idle,
    /// Take the start pose at `start_index`.
    Begin,
    /// Take the winner's pose as the start of its further polish.
    Second,
    /// A clock for the next start's pose to follow `start_index` (the board reads it from
    /// a RAM); then `Begin`.
    Fetch,
    /// Load the pose's twelve fields at `POSE`; then `Start`.
    Load,
    /// Start the program at `entry`.
    Go,
    /// Wait for the program; then `after`.
    Wait,
    /// After `Start`: `Clear`, then the statistics pass.
    Started,
    /// Ask for a pass at `pose` (gated as `gate_on`).
    Pass,
    /// Wait for `pass_done`; then `pass_after`.
    PassWait,
    /// A step or the end: `Gate`, or `Drift` after the last step.
    Step,
    /// After `Gate`: a failure ends the steps; else read `TAU2`.
    Gated,
    /// `TAU2` is on `prog_read_data`: `Clear`, then the gated pass.
    Tau,
    /// After the gated pass: `Solve`.
    Passed,
    /// After `Solve`: a failure ends the steps; else `Update`.
    Solved,
    /// Read the updated pose back from `POSE` (12 reads, a clock behind).
    ReadBack,
    /// After `Drift`: drop the start or keep it, then the cost pass.
    Drifted,
    /// The cost is in: the choice; the next start or the end.
    Costed,
}

/// The polish's control.
#[derive(LogicBlock)]
pub struct PolishControl {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset: idle, no result.
    pub reset: Signal<In, Bit>,
    /// While idle: polish `starts` starts with up to `steps` steps each.
    pub go: Signal<In, Bit>,
    /// Starts (1 to 15; 0 taken as 1).
    pub starts: Signal<In, Bits<4>>,
    /// Steps a start (0 to 15).
    pub steps: Signal<In, Bits<4>>,
    /// The winner's further steps (0: none; up to 15).
    pub winner_steps: Signal<In, Bits<4>>,
    /// The start the control takes next.
    pub start_index: Signal<Out, Bits<4>>,
    /// The pose of start `start_index` (as the pipeline's pose word), held while the start
    /// runs (a failed drift check takes it again).
    pub start_pose: Signal<In, Bits<216>>,
    /// Ask for a pass over the scan at `pose` (a clock's pulse).
    pub pass_go: Signal<Out, Bit>,
    /// The pose of the pass (as the pipeline's pose word; held until `pass_done`); once
    /// done, the winner's.
    pub pose: Signal<Out, Bits<216>>,
    /// The pass's gate on.
    pub gated: Signal<Out, Bit>,
    /// The pass's gate.
    pub tau2: Signal<Out, Bits<32>>,
    /// The pass is over and its adds are in (a clock's pulse).
    pub pass_done: Signal<In, Bit>,
    /// The pass's cost (with `pass_done`).
    pub pass_cost: Signal<In, Bits<48>>,
    /// The datapath: load a register.
    pub prog_load: Signal<Out, Bit>,
    /// The register to load.
    pub prog_load_addr: Signal<Out, Bits<6>>,
    /// The value to load.
    pub prog_load_data: Signal<Out, Bits<128>>,
    /// The register to read.
    pub prog_read_addr: Signal<Out, Bits<6>>,
    /// The register read, its low 32 bits (a clock after its address; a pose field and
    /// `TAU2` fit them).
    pub prog_read_data: Signal<In, Bits<32>>,
    /// Run the program at `prog_entry`.
    pub prog_go: Signal<Out, Bit>,
    /// The program to run.
    pub prog_entry: Signal<Out, Bits<9>>,
    /// The program runs.
    pub prog_busy: Signal<In, Bit>,
    /// The last program failed.
    pub prog_failed: Signal<In, Bit>,
    /// Polishing.
    pub busy: Signal<Out, Bit>,
    /// A result is held (from the end of a polish to the next `go`).
    pub done: Signal<Out, Bit>,
    /// The winning start (its polished pose is `pose` once done).
    pub best_index: Signal<Out, Bits<4>>,
    /// Its cost.
    pub best_cost: Signal<Out, Bits<48>>,
    state: DFF<ControlState>,
    after: DFF<ControlState>,
    pass_after: DFF<ControlState>,
    entry: DFF<Bits<9>>,
    index: DFF<Bits<4>>,
    count: DFF<Bits<4>>,
    step_max: DFF<Bits<4>>,
    /// The winner's further steps, and whether they are running.
    more: DFF<Bits<4>>,
    second: DFF<Bit>,
    step: DFF<Bits<4>>,
    k: DFF<Bits<4>>,
    /// The pose: the pass's, rotated by a field a clock through a load or a read back, and
    /// the winner's once done.
    cur: DFF<Bits<216>>,
    keep: DFF<Bit>,
    cost: DFF<Bits<48>>,
    gate_on: DFF<Bit>,
    tau: DFF<Bits<32>>,
    have: DFF<Bit>,
    held: DFF<Bit>,
    b_index: DFF<Bits<4>>,
    b_pose: DFF<Bits<216>>,
    b_cost: DFF<Bits<48>>,
    e_start: Constant<Bits<9>>,
    e_clear: Constant<Bits<9>>,
    e_gate: Constant<Bits<9>>,
    e_solve: Constant<Bits<9>>,
    e_update: Constant<Bits<9>>,
    e_drift: Constant<Bits<9>>,
    field: Signal<Local, Bits<18>>,
    rot_in: Signal<Local, Bits<216>>,
    rot_out: Signal<Local, Bits<216>>,
    /// The start just costed beats the held winner (or is the first kept).
    better: Signal<Local, Bit>,
}

/// The entry of program `e` in the polish's ROM.
fn entry_of(e: Entry) -> Constant<Bits<9>> {
    Constant::new(Bits::<9>::from(rom().entry(e as usize) as u64))
}

// Literals in the kernel: the pose's registers and `TAU2`, the pose word's 18-bit fields.
const _: () = assert!(POSE == 48 && TAU2 == 60 && crate::common::format::POSE_BITS == 18);

impl PolishControl {
    /// The control of the polish's ROM ([`crate::polish::programs::rom`]).
    pub fn new() -> Self {
        PolishControl {
            clock: Default::default(),
            reset: Default::default(),
            go: Default::default(),
            starts: Default::default(),
            steps: Default::default(),
            winner_steps: Default::default(),
            start_index: Default::default(),
            start_pose: Default::default(),
            pass_go: Default::default(),
            pose: Default::default(),
            gated: Default::default(),
            tau2: Default::default(),
            pass_done: Default::default(),
            pass_cost: Default::default(),
            prog_load: Default::default(),
            prog_load_addr: Default::default(),
            prog_load_data: Default::default(),
            prog_read_addr: Default::default(),
            prog_read_data: Default::default(),
            prog_go: Default::default(),
            prog_entry: Default::default(),
            prog_busy: Default::default(),
            prog_failed: Default::default(),
            busy: Default::default(),
            done: Default::default(),
            best_index: Default::default(),
            best_cost: Default::default(),
            state: Default::default(),
            after: Default::default(),
            pass_after: Default::default(),
            entry: Default::default(),
            index: Default::default(),
            count: Default::default(),
            step_max: Default::default(),
            more: Default::default(),
            second: Default::default(),
            step: Default::default(),
            k: Default::default(),
            cur: Default::default(),
            keep: Default::default(),
            cost: Default::default(),
            gate_on: Default::default(),
            tau: Default::default(),
            have: Default::default(),
            held: Default::default(),
            b_index: Default::default(),
            b_pose: Default::default(),
            b_cost: Default::default(),
            e_start: entry_of(Entry::Start),
            e_clear: entry_of(Entry::Clear),
            e_gate: entry_of(Entry::Gate),
            e_solve: entry_of(Entry::Solve),
            e_update: entry_of(Entry::Update),
            e_drift: entry_of(Entry::Drift),
            field: Default::default(),
            rot_in: Default::default(),
            rot_out: Default::default(),
            better: Default::default(),
        }
    }
}

impl Default for PolishControl {
    fn default() -> Self {
        Self::new()
    }
}

impl Logic for PolishControl {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self, clock, state, after, pass_after, entry, index, count, step_max, more, second, step, k, cur, keep,
            cost, gate_on, tau, have, held, b_index, b_pose, b_cost
        );
        self.start_index.next = self.index.q.val();
        self.pose.next = self.cur.q.val();
        self.gated.next = self.gate_on.q.val();
        self.tau2.next = self.tau.q.val();
        self.busy.next = self.state.q.val() != ControlState::Idle;
        self.done.next = self.held.q.val();
        self.best_index.next = self.b_index.q.val();
        self.best_cost.next = self.b_cost.q.val();
        self.pass_go.next = false;
        self.prog_go.next = false;
        self.prog_entry.next = self.entry.q.val();
        self.prog_load.next = false;
        self.prog_load_addr.next = bit_cast::<6, 4>(self.k.q.val()) + 48;
        // The pose word's fields go out of `cur` from the bottom and back in at the top (a
        // load: twelve rotations restore it), or come back from the registers at the top (a
        // read back), 18 bits at a time: no shifter, no second pose register.
        self.field.next = self.cur.q.val().get_bits::<18>(0);
        self.prog_load_data.next = bit_cast::<128, 18>(self.field.val());
        if self.field.val().get_bit(17) {
            self.prog_load_data.next = bit_cast::<128, 18>(self.field.val()) | ((!bits::<128>(0)) << 18);
        }
        self.prog_read_addr.next = bit_cast::<6, 4>(self.k.q.val()) + 48;
        self.rot_in.next =
            (self.cur.q.val() >> 18) | (bit_cast::<216, 18>(self.prog_read_data.val().get_bits::<18>(0)) << 198);
        self.rot_out.next = (self.cur.q.val() >> 18) | (bit_cast::<216, 18>(self.field.val()) << 198);
        self.better.next = self.keep.q.val() && (!self.have.q.val() || (self.cost.q.val() < self.b_cost.q.val()));

        match self.state.q.val() {
            ControlState::Idle => {
                if self.go.val() {
                    self.index.d.next = 0.into();
                    self.count.d.next = self.starts.val();
                    if !self.starts.val().any() {
                        self.count.d.next = 1.into();
                    }
                    self.step_max.d.next = self.steps.val();
                    self.more.d.next = self.winner_steps.val();
                    self.second.d.next = false;
                    self.have.d.next = false;
                    self.held.d.next = false;
                    self.state.d.next = ControlState::Begin;
                }
            }
            ControlState::Fetch => {
                self.state.d.next = ControlState::Begin;
            }
            ControlState::Second => {
                self.cur.d.next = self.b_pose.q.val();
                self.keep.d.next = true;
                self.k.d.next = 0.into();
                self.step.d.next = 0.into();
                self.state.d.next = ControlState::Load;
            }
            ControlState::Begin => {
                self.cur.d.next = self.start_pose.val();
                self.keep.d.next = true;
                self.k.d.next = 0.into();
                self.step.d.next = 0.into();
                self.state.d.next = ControlState::Load;
            }
            ControlState::Load => {
                self.prog_load.next = true;
                self.cur.d.next = self.rot_out.val();
                self.k.d.next = self.k.q.val() + 1;
                if self.k.q.val() == 11 {
                    self.entry.d.next = self.e_start.val();
                    self.after.d.next = ControlState::Started;
                    self.state.d.next = ControlState::Go;
                }
            }
            ControlState::Go => {
                self.prog_go.next = true;
                self.state.d.next = ControlState::Wait;
            }
            ControlState::Wait => {
                if !self.prog_busy.val() {
                    self.state.d.next = self.after.q.val();
                }
            }
            ControlState::Started => {
                self.entry.d.next = self.e_clear.val();
                self.gate_on.d.next = false;
                self.after.d.next = ControlState::Pass;
                self.pass_after.d.next = ControlState::Step;
                self.state.d.next = ControlState::Go;
            }
            ControlState::Pass => {
                self.pass_go.next = true;
                self.state.d.next = ControlState::PassWait;
            }
            ControlState::PassWait => {
                if self.pass_done.val() {
                    self.cost.d.next = self.pass_cost.val();
                    self.state.d.next = self.pass_after.q.val();
                }
            }
            ControlState::Step => {
                self.entry.d.next = self.e_gate.val();
                self.after.d.next = ControlState::Gated;
                if self.step.q.val() == self.step_max.q.val() {
                    self.entry.d.next = self.e_drift.val();
                    self.after.d.next = ControlState::Drifted;
                }
                self.state.d.next = ControlState::Go;
            }
            ControlState::Gated => {
                self.prog_read_addr.next = 60.into();
                self.state.d.next = ControlState::Tau;
                if self.prog_failed.val() {
                    self.entry.d.next = self.e_drift.val();
                    self.after.d.next = ControlState::Drifted;
                    self.state.d.next = ControlState::Go;
                }
            }
            ControlState::Tau => {
                self.tau.d.next = self.prog_read_data.val();
                self.gate_on.d.next = true;
                self.entry.d.next = self.e_clear.val();
                self.after.d.next = ControlState::Pass;
                self.pass_after.d.next = ControlState::Passed;
                self.state.d.next = ControlState::Go;
            }
            ControlState::Passed => {
                self.entry.d.next = self.e_solve.val();
                self.after.d.next = ControlState::Solved;
                self.state.d.next = ControlState::Go;
            }
            ControlState::Solved => {
                self.k.d.next = 0.into();
                self.entry.d.next = self.e_update.val();
                self.after.d.next = ControlState::ReadBack;
                if self.prog_failed.val() {
                    self.entry.d.next = self.e_drift.val();
                    self.after.d.next = ControlState::Drifted;
                }
                self.state.d.next = ControlState::Go;
            }
            ControlState::ReadBack => {
                // Register `POSE + k` is read now; `POSE + k - 1` is here.
                self.k.d.next = self.k.q.val() + 1;
                if self.k.q.val().any() {
                    self.cur.d.next = self.rot_in.val();
                }
                if self.k.q.val() == 12 {
                    self.step.d.next = self.step.q.val() + 1;
                    self.state.d.next = ControlState::Step;
                }
            }
            ControlState::Drifted => {
                // Beyond the drift bounds: the first start stays unpolished, another drops
                // (no cost pass).
                self.gate_on.d.next = false;
                self.pass_after.d.next = ControlState::Costed;
                self.state.d.next = ControlState::Pass;
                if self.prog_failed.val() {
                    // The start's pose, still at `start_pose` (it follows `start_index`), or
                    // the winner's in its further polish.
                    self.cur.d.next = self.start_pose.val();
                    if self.second.q.val() {
                        self.cur.d.next = self.b_pose.q.val();
                    } else if self.index.q.val().any() {
                        self.keep.d.next = false;
                        self.state.d.next = ControlState::Costed;
                    }
                }
            }
            ControlState::Costed => {
                if self.second.q.val() {
                    // The winner's further polish: its pose (in `cur`) and cost are the result.
                    self.b_pose.d.next = self.cur.q.val();
                    self.b_cost.d.next = self.cost.q.val();
                    self.held.d.next = true;
                    self.state.d.next = ControlState::Idle;
                } else {
                    if self.better.val() {
                        self.have.d.next = true;
                        self.b_index.d.next = self.index.q.val();
                        self.b_pose.d.next = self.cur.q.val();
                        self.b_cost.d.next = self.cost.q.val();
                    }
                    self.index.d.next = self.index.q.val() + 1;
                    self.state.d.next = ControlState::Fetch;
                    if (self.index.q.val() + 1) == self.count.q.val() {
                        if self.more.q.val().any() {
                            self.second.d.next = true;
                            self.step_max.d.next = self.more.q.val();
                            self.state.d.next = ControlState::Second;
                        } else {
                            // The winner's pose into `cur` (it is there if this start won).
                            if !self.better.val() {
                                self.cur.d.next = self.b_pose.q.val();
                            }
                            self.held.d.next = true;
                            self.state.d.next = ControlState::Idle;
                        }
                    }
                }
            }
        }
        if self.reset.val() {
            self.state.d.next = ControlState::Idle;
            self.held.d.next = false;
        }
    }
}
