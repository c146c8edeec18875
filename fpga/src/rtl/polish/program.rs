//! `PolishProgram`: the datapath that runs a [`crate::polish::program`] program (in ROM)
//! over 64 x 128-bit registers, the RTL twin of [`crate::polish::program::run`] (test:
//! `fpga/tests/polish_program.rs`, against the model on the solve's inputs). One adder
//! a unit, no DSP48A1: a shift-and-add multiplier (a clock a bit of the multiplier's
//! magnitude), a restoring divider (128 clocks), shifts a bit a clock. An instruction takes
//! `fetch`, `operand`, `exec` and `write` (4 clocks for an add) plus its unit's clocks.

use crate::polish::program::{rom_words, Op, FIELD_A, FIELD_B, FIELD_D, FIELD_K, FIELD_LAST};
use rust_hdl::prelude::*;

/// Where the datapath is in an instruction.
#[derive(Copy, Clone, Debug, PartialEq, Eq, LogicState)]
pub enum ProgramState {
    /// Not running: `load` writes registers, `read_addr` reads them.
    Idle,
    /// Latch the instruction at the program counter; read its first operand.
    Fetch,
    /// Latch the first operand; read the second.
    Operand,
    /// Execute: an add, subtract or clamp ends here; the others start their unit.
    Exec,
    /// Shift-and-add over the multiplier's magnitude.
    Mul,
    /// Arithmetic right shifts (a multiply's rounding, a shift).
    Round,
    /// Left shifts (a dividend's, a constant's).
    ShiftLeft,
    /// Restoring division, a quotient bit a clock.
    Div,
    /// Write the result; the next instruction or the end.
    Write,
}

/// The program's datapath.
#[derive(LogicBlock)]
pub struct PolishProgram {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset: stop, idle.
    pub reset: Signal<In, Bit>,
    /// While idle: write `load_data` to register `load_addr`.
    pub load: Signal<In, Bit>,
    /// Register to load.
    pub load_addr: Signal<In, Bits<6>>,
    /// Value to load (two's complement).
    pub load_data: Signal<In, Bits<128>>,
    /// While idle: the register `read_data` shows on the next clock.
    pub read_addr: Signal<In, Bits<6>>,
    /// The register read.
    pub read_data: Signal<Out, Bits<128>>,
    /// While idle: run the program from its first instruction.
    pub go: Signal<In, Bit>,
    /// Running.
    pub busy: Signal<Out, Bit>,
    /// The last run stopped at a `StopBelow` (until the next `go`).
    pub failed: Signal<Out, Bit>,
    state: DFF<ProgramState>,
    pc: DFF<Bits<9>>,
    ins: DFF<Bits<30>>,
    x: DFF<Bits<128>>,
    y: DFF<Bits<128>>,
    acc: DFF<Bits<128>>,
    rem: DFF<Bits<129>>,
    neg: DFF<Bit>,
    cnt: DFF<Bits<8>>,
    fail: DFF<Bit>,
    rf: RAM<Bits<128>, 6>,
    prog: ROM<Bits<30>, 9>,
    kind: Signal<Local, Bits<4>>,
    opb: Signal<Local, Bits<128>>,
    negb: Signal<Local, Bits<128>>,
    x_neg: Signal<Local, Bits<128>>,
    x_abs: Signal<Local, Bits<128>>,
    b_abs: Signal<Local, Bits<128>>,
    twice: Signal<Local, Bits<128>>,
    below: Signal<Local, Bit>,
    above: Signal<Local, Bit>,
    under: Signal<Local, Bit>,
    acc_inc: Signal<Local, Bits<128>>,
    acc_sra: Signal<Local, Bits<128>>,
    acc_inc_sra: Signal<Local, Bits<128>>,
    rem2: Signal<Local, Bits<129>>,
    y_wide: Signal<Local, Bits<129>>,
}

impl PolishProgram {
    /// `program` in ROM, the registers cleared.
    pub fn new(program: &[Op]) -> Self {
        let words = rom_words(program);
        PolishProgram {
            clock: Default::default(),
            reset: Default::default(),
            load: Default::default(),
            load_addr: Default::default(),
            load_data: Default::default(),
            read_addr: Default::default(),
            read_data: Default::default(),
            go: Default::default(),
            busy: Default::default(),
            failed: Default::default(),
            state: Default::default(),
            pc: Default::default(),
            ins: Default::default(),
            x: Default::default(),
            y: Default::default(),
            acc: Default::default(),
            rem: Default::default(),
            neg: Default::default(),
            cnt: Default::default(),
            fail: Default::default(),
            rf: RAM::new((0..64u64).map(|a| (Bits::<6>::from(a), Bits::<128>::default())).collect()),
            prog: ROM::new(
                words
                    .iter()
                    .enumerate()
                    .map(|(a, &w)| (Bits::<9>::from(a as u64), Bits::<30>::from(w as u64)))
                    .collect(),
            ),
            kind: Default::default(),
            opb: Default::default(),
            negb: Default::default(),
            x_neg: Default::default(),
            x_abs: Default::default(),
            b_abs: Default::default(),
            twice: Default::default(),
            below: Default::default(),
            above: Default::default(),
            under: Default::default(),
            acc_inc: Default::default(),
            acc_sra: Default::default(),
            acc_inc_sra: Default::default(),
            rem2: Default::default(),
            y_wide: Default::default(),
        }
    }
}

// Literals in the kernel (`#[hdl_gen]` takes no paths): the fields' positions and the
// kinds' codes (`crate::polish::program::kind`).
const _: () = assert!(FIELD_D == 4 && FIELD_A == 10 && FIELD_B == 16 && FIELD_K == 22 && FIELD_LAST == 29);
const _: () = {
    use crate::polish::program::kind::*;
    assert!(ADD == 0 && SUB == 1 && MUL == 2 && DIV == 3 && SHR == 4 && CONST == 5 && CLAMP == 6 && STOP_BELOW == 7);
};

impl Logic for PolishProgram {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, state, pc, ins, x, y, acc, rem, neg, cnt, fail);
        self.rf.read_clock.next = self.clock.val();
        self.rf.write_clock.next = self.clock.val();
        self.prog.address.next = self.pc.q.val();
        self.kind.next = self.ins.q.val().get_bits::<4>(0);
        self.opb.next = self.rf.read_data.val();
        self.read_data.next = self.rf.read_data.val();
        self.busy.next = self.state.q.val() != ProgramState::Idle;
        self.failed.next = self.fail.q.val();

        // The units' combinational parts.
        self.negb.next = bits::<128>(0) - self.opb.val();
        self.x_neg.next = bits::<128>(0) - self.x.q.val();
        self.x_abs.next = self.x.q.val();
        if self.x.q.val().get_bit(127) {
            self.x_abs.next = self.x_neg.val();
        }
        self.b_abs.next = self.opb.val();
        if self.opb.val().get_bit(127) {
            self.b_abs.next = self.negb.val();
        }
        // Signed comparisons: by the sign bits where they differ, else unsigned.
        self.twice.next = self.x.q.val() + self.x.q.val();
        self.below.next = self.twice.val() < self.opb.val();
        if self.twice.val().get_bit(127) != self.opb.val().get_bit(127) {
            self.below.next = self.twice.val().get_bit(127);
        }
        self.above.next = self.x.q.val() > self.opb.val();
        if self.x.q.val().get_bit(127) != self.opb.val().get_bit(127) {
            self.above.next = self.opb.val().get_bit(127);
        }
        self.under.next = self.x.q.val() < self.negb.val();
        if self.x.q.val().get_bit(127) != self.negb.val().get_bit(127) {
            self.under.next = self.x.q.val().get_bit(127);
        }
        self.acc_inc.next = self.acc.q.val() + 1;
        self.acc_sra.next = (self.acc.q.val() >> 1).replace_bit(127, self.acc.q.val().get_bit(127));
        self.acc_inc_sra.next = (self.acc_inc.val() >> 1).replace_bit(127, self.acc_inc.val().get_bit(127));
        self.rem2.next = (self.rem.q.val() << 1) | bit_cast::<129, 1>(self.x.q.val().get_bits::<1>(127));
        self.y_wide.next = bit_cast::<129, 128>(self.y.q.val());

        self.rf.read_address.next = self.read_addr.val();
        self.rf.write_enable.next = false;
        self.rf.write_address.next = self.ins.q.val().get_bits::<6>(4);
        self.rf.write_data.next = self.acc.q.val();

        match self.state.q.val() {
            ProgramState::Idle => {
                if self.load.val() {
                    self.rf.write_enable.next = true;
                    self.rf.write_address.next = self.load_addr.val();
                    self.rf.write_data.next = self.load_data.val();
                }
                if self.go.val() {
                    self.pc.d.next = 0.into();
                    self.fail.d.next = false;
                    self.state.d.next = ProgramState::Fetch;
                }
            }
            ProgramState::Fetch => {
                self.ins.d.next = self.prog.data.val();
                self.rf.read_address.next = self.prog.data.val().get_bits::<6>(10);
                self.state.d.next = ProgramState::Operand;
            }
            ProgramState::Operand => {
                self.x.d.next = self.rf.read_data.val();
                self.rf.read_address.next = self.ins.q.val().get_bits::<6>(16);
                self.state.d.next = ProgramState::Exec;
            }
            ProgramState::Exec => {
                self.cnt.d.next = bit_cast::<8, 7>(self.ins.q.val().get_bits::<7>(22));
                self.state.d.next = ProgramState::Write;
                if self.kind.val() == 0 {
                    self.acc.d.next = self.x.q.val() + self.opb.val();
                }
                if self.kind.val() == 1 {
                    self.acc.d.next = self.x.q.val() - self.opb.val();
                }
                if self.kind.val() == 2 {
                    self.neg.d.next = self.x.q.val().get_bit(127) ^ self.opb.val().get_bit(127);
                    self.x.d.next = self.x_abs.val();
                    self.y.d.next = self.b_abs.val();
                    self.acc.d.next = 0.into();
                    self.state.d.next = ProgramState::Mul;
                }
                if self.kind.val() == 3 {
                    self.y.d.next = self.opb.val();
                    self.state.d.next = ProgramState::ShiftLeft;
                }
                if self.kind.val() == 4 {
                    self.acc.d.next = self.x.q.val();
                    self.state.d.next = ProgramState::Round;
                }
                if self.kind.val() == 5 {
                    self.x.d.next = bit_cast::<128, 6>(self.ins.q.val().get_bits::<6>(10));
                    self.state.d.next = ProgramState::ShiftLeft;
                }
                if self.kind.val() == 6 {
                    self.acc.d.next = self.x.q.val();
                    if self.above.val() {
                        self.acc.d.next = self.opb.val();
                    } else if self.under.val() {
                        self.acc.d.next = self.negb.val();
                    }
                }
                if self.kind.val() == 7 {
                    if self.below.val() {
                        self.fail.d.next = true;
                        self.state.d.next = ProgramState::Idle;
                    } else if self.ins.q.val().get_bit(29) {
                        self.state.d.next = ProgramState::Idle;
                    } else {
                        self.pc.d.next = self.pc.q.val() + 1;
                        self.state.d.next = ProgramState::Fetch;
                    }
                }
            }
            ProgramState::Mul => {
                if self.y.q.val().any() {
                    if self.y.q.val().get_bit(0) {
                        self.acc.d.next = self.acc.q.val() + self.x.q.val();
                    }
                    self.x.d.next = self.x.q.val() << 1;
                    self.y.d.next = self.y.q.val() >> 1;
                } else {
                    if self.neg.q.val() {
                        self.acc.d.next = bits::<128>(0) - self.acc.q.val();
                    }
                    self.state.d.next = ProgramState::Round;
                }
            }
            ProgramState::Round => {
                if self.cnt.q.val().any() {
                    self.cnt.d.next = self.cnt.q.val() - 1;
                    self.acc.d.next = self.acc_sra.val();
                    if (self.cnt.q.val() == 1) && (self.kind.val() == 2) {
                        self.acc.d.next = self.acc_inc_sra.val();
                    }
                } else {
                    self.state.d.next = ProgramState::Write;
                }
            }
            ProgramState::ShiftLeft => {
                if self.cnt.q.val().any() {
                    self.cnt.d.next = self.cnt.q.val() - 1;
                    self.x.d.next = self.x.q.val() << 1;
                } else if self.kind.val() == 3 {
                    self.neg.d.next = self.x.q.val().get_bit(127);
                    self.x.d.next = self.x_abs.val();
                    self.rem.d.next = 0.into();
                    self.cnt.d.next = 128.into();
                    self.state.d.next = ProgramState::Div;
                } else {
                    self.acc.d.next = self.x.q.val();
                    self.state.d.next = ProgramState::Write;
                }
            }
            ProgramState::Div => {
                if self.cnt.q.val().any() {
                    self.cnt.d.next = self.cnt.q.val() - 1;
                    if self.rem2.val() >= self.y_wide.val() {
                        self.rem.d.next = self.rem2.val() - self.y_wide.val();
                        self.x.d.next = (self.x.q.val() << 1) | bits::<128>(1);
                    } else {
                        self.rem.d.next = self.rem2.val();
                        self.x.d.next = self.x.q.val() << 1;
                    }
                } else {
                    self.acc.d.next = self.x.q.val();
                    if self.neg.q.val() {
                        self.acc.d.next = self.x_neg.val();
                    }
                    self.state.d.next = ProgramState::Write;
                }
            }
            ProgramState::Write => {
                self.rf.write_enable.next = true;
                if self.ins.q.val().get_bit(29) {
                    self.state.d.next = ProgramState::Idle;
                } else {
                    self.pc.d.next = self.pc.q.val() + 1;
                    self.state.d.next = ProgramState::Fetch;
                }
            }
        }
        if self.reset.val() {
            self.state.d.next = ProgramState::Idle;
            self.fail.d.next = false;
        }
    }
}
