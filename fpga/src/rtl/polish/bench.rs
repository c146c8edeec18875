//! `PolishBench`: the pass ([`PolishPass`]), a [`PipeMul`] and the program's datapath
//! ([`PolishProgram`]) wired as the board will wire them: the pass's products on the
//! multiplier, its adds into the program's registers. On the board the multiplier is the
//! sequencer's, idle after the filter; here the bench has its own, so that the blocks can
//! be tested together in rust_hdl's simulator (`fpga/tests/polish_pass.rs`) and under
//! Verilator (`sim/tests/polish_pass.rs`, from [`crate::rtl::polish_bench_verilog`]).
//! A pass's points go in at `in_*`; the programs run on `go` at `entry`.

use super::{PolishPass, PolishProgram};
use crate::rtl::board::sequencer::PipeMul;
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
    /// The pass is idle: a point may come.
    pub ready: Signal<Out, Bit>,
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
            t: Default::default(),
            in_valid: Default::default(),
            in_q: Default::default(),
            in_n: Default::default(),
            in_s: Default::default(),
            ready: Default::default(),
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
        self.pass.t.next = self.t.val();
        self.pass.in_valid.next = self.in_valid.val();
        self.pass.in_q.next = self.in_q.val();
        self.pass.in_n.next = self.in_n.val();
        self.pass.in_s.next = self.in_s.val();
        self.ready.next = self.pass.ready.val();
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
