//! `PolishProgram`: the datapath that runs [`crate::polish::program`] programs (a ROM of
//! several, [`crate::polish::program::Rom`], each started at its entry) over 64 x 128-bit
//! registers, the RTL twin of [`crate::polish::program::run`] (test:
//! `fpga/tests/polish_program.rs`, against the model on each of the polish's programs). The
//! ROM is synchronous (block RAM): its address is the next program counter, so the word
//! at the program counter is there when `fetch` needs it. No DSP48A1
//! and one 129-bit adder for every unit, `alu = A + (B ^ inv) + cin` with `A` one of
//! `x`, `acc`, `rem2`, 0 and `B` one of the second operand, `x`, `y`, 1: a shift-and-add
//! multiplier over the multiplier's magnitude (a clock a bit; a negative multiplier
//! subtracts), a restoring divider (128 clocks), shifts a bit a clock. An instruction takes
//! `fetch`, `operand`, `exec` and `write` (4 clocks for an add) plus its unit's clocks.

use crate::polish::program::{FIELD_A, FIELD_B, FIELD_D, FIELD_K, FIELD_LAST, PROGRAM_WORDS};
use rust_hdl::prelude::*;

/// Where the datapath is in an instruction.
#[derive(Copy, Clone, Debug, PartialEq, Eq, LogicState)]
pub enum ProgramState {
    /// Not running: `load` writes registers, `read_addr` reads them.
    Idle,
    /// Latch the instruction at the program counter; read its first operand.
    Fetch,
    /// Latch the first operand; read the second (held until the instruction ends).
    Operand,
    /// Execute: an add or subtract ends here; the others start their unit.
    Exec,
    /// Shift-and-add over the multiplier's magnitude.
    Mul,
    /// Arithmetic right shifts (a multiply's rounding, a shift).
    Round,
    /// Left shifts (a dividend's, a constant's).
    ShiftLeft,
    /// The dividend's magnitude.
    DivAbs,
    /// Restoring division, a quotient bit a clock; then the quotient's sign.
    Div,
    /// A clamp below its bound: `y = -bound` (a saturation's `-bound - 1`).
    ClampNeg,
    /// A clamp: the operand against `-bound`.
    ClampLow,
    /// A stop test: `2 r[a]` (in `acc`) against the bound.
    StopTest,
    /// `acc = 0 + B` for the `B` source in `take` (a clamp's or a constant's result).
    Take,
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
    /// While idle: add `add_data` to register `add_addr` (read on this clock, written on the
    /// next; no two adds to one register on consecutive clocks, no `load` on the clock after
    /// an add, no add with `go`). The pass accumulates its sums so, straight into the solve's inputs.
    pub add: Signal<In, Bit>,
    /// Register to add to.
    pub add_addr: Signal<In, Bits<6>>,
    /// Value to add (48-bit two's complement).
    pub add_data: Signal<In, Bits<48>>,
    /// While idle: run the program whose first instruction is at `entry`.
    pub go: Signal<In, Bit>,
    /// The program `go` starts ([`crate::polish::program::Rom::entry`]).
    pub entry: Signal<In, Bits<9>>,
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
    take: DFF<Bits<2>>,
    pend: DFF<Bit>,
    pend_addr: DFF<Bits<6>>,
    rf: RAM<Bits<128>, 6>,
    prog: SyncROM<Bits<30>, 9>,
    kind: Signal<Local, Bits<4>>,
    opb: Signal<Local, Bits<128>>,
    // The adder: its sources' selects, the operands (sign-extended to 129 bits; `y` is
    // zero-extended for a divisor), the sum and the sum shifted right.
    sel_a: Signal<Local, Bits<2>>,
    sel_b: Signal<Local, Bits<2>>,
    inv: Signal<Local, Bit>,
    cin: Signal<Local, Bit>,
    alu_a: Signal<Local, Bits<129>>,
    alu_b: Signal<Local, Bits<129>>,
    alu: Signal<Local, Bits<129>>,
    alu_sra: Signal<Local, Bits<128>>,
    acc_sra: Signal<Local, Bits<128>>,
    rem2: Signal<Local, Bits<129>>,
}

impl PolishProgram {
    /// The polish's ROM ([`crate::polish::programs::rom`]), the registers cleared.
    pub fn polish() -> Self {
        Self::new(&crate::polish::programs::rom().words())
    }

    /// `words` in ROM ([`crate::polish::program::Rom::words`]), the registers cleared.
    pub fn new(words: &[u32]) -> Self {
        assert!(words.len() <= PROGRAM_WORDS);
        PolishProgram {
            clock: Default::default(),
            reset: Default::default(),
            load: Default::default(),
            load_addr: Default::default(),
            load_data: Default::default(),
            read_addr: Default::default(),
            read_data: Default::default(),
            add: Default::default(),
            add_addr: Default::default(),
            add_data: Default::default(),
            go: Default::default(),
            entry: Default::default(),
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
            take: Default::default(),
            pend: Default::default(),
            pend_addr: Default::default(),
            rf: RAM::new((0..64u64).map(|a| (Bits::<6>::from(a), Bits::<128>::default())).collect()),
            prog: SyncROM::new(
                words
                    .iter()
                    .enumerate()
                    .map(|(a, &w)| (Bits::<9>::from(a as u64), Bits::<30>::from(w as u64)))
                    .collect(),
            ),
            kind: Default::default(),
            opb: Default::default(),
            sel_a: Default::default(),
            sel_b: Default::default(),
            inv: Default::default(),
            cin: Default::default(),
            alu_a: Default::default(),
            alu_b: Default::default(),
            alu: Default::default(),
            alu_sra: Default::default(),
            acc_sra: Default::default(),
            rem2: Default::default(),
        }
    }
}

// Literals in the kernel (`#[hdl_gen]` takes no paths): the fields' positions and the
// kinds' codes (`crate::polish::program::kind`).
const _: () = assert!(FIELD_D == 4 && FIELD_A == 10 && FIELD_B == 16 && FIELD_K == 22 && FIELD_LAST == 29);
const _: () = {
    use crate::polish::program::kind::*;
    assert!(
        ADD == 0
            && SUB == 1
            && MUL == 2
            && DIV == 3
            && SHR == 4
            && CONST == 5
            && CLAMP == 6
            && STOP_BELOW == 7
            && SAT == 8
    );
};

impl Logic for PolishProgram {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, state, pc, ins, x, y, acc, rem, neg, cnt, fail, take, pend, pend_addr);
        self.rf.read_clock.next = self.clock.val();
        self.rf.write_clock.next = self.clock.val();
        self.prog.clock.next = self.clock.val();
        self.kind.next = self.ins.q.val().get_bits::<4>(0);
        self.opb.next = self.rf.read_data.val();
        self.read_data.next = self.rf.read_data.val();
        self.busy.next = self.state.q.val() != ProgramState::Idle;
        self.failed.next = self.fail.q.val();

        // The adder: A is x (0), acc (1), rem2 (2) or 0 (3); B is the second operand (0),
        // x (1), y (2) or 1 (3); each state below picks them.
        self.sel_a.next = 3.into();
        self.sel_b.next = 0.into();
        self.inv.next = false;
        self.cin.next = false;
        self.rem2.next = (self.rem.q.val() << 1) | bit_cast::<129, 1>(self.x.q.val().get_bits::<1>(127));

        self.rf.read_address.next = self.ins.q.val().get_bits::<6>(16);
        self.rf.write_enable.next = false;
        self.rf.write_address.next = self.ins.q.val().get_bits::<6>(4);
        self.rf.write_data.next = self.acc.q.val();

        match self.state.q.val() {
            ProgramState::Idle => {
                // An add: the register's value (read now) plus x (the value, latched now).
                self.sel_a.next = 0.into();
                self.rf.read_address.next = self.read_addr.val();
                if self.add.val() {
                    self.rf.read_address.next = self.add_addr.val();
                }
            }
            ProgramState::Fetch => {
                self.rf.read_address.next = self.prog.data.val().get_bits::<6>(10);
            }
            ProgramState::Exec => {
                if self.kind.val() == 0 {
                    self.sel_a.next = 0.into();
                }
                if self.kind.val() == 1 {
                    self.sel_a.next = 0.into();
                    self.inv.next = true;
                    self.cin.next = true;
                }
                if self.kind.val() == 2 {
                    self.inv.next = true;
                    self.cin.next = true;
                }
                if self.kind.val() == 4 {
                    self.sel_b.next = 1.into();
                }
                if (self.kind.val() == 6) || (self.kind.val() == 8) {
                    self.sel_a.next = 0.into();
                    self.inv.next = true;
                }
                if self.kind.val() == 7 {
                    self.sel_a.next = 0.into();
                    self.sel_b.next = 1.into();
                }
            }
            ProgramState::Mul => {
                self.sel_a.next = 1.into();
                self.sel_b.next = 1.into();
                self.inv.next = self.neg.q.val();
                self.cin.next = self.neg.q.val();
            }
            ProgramState::Round => {
                self.sel_a.next = 1.into();
                self.sel_b.next = 3.into();
            }
            ProgramState::DivAbs => {
                self.sel_b.next = 1.into();
                self.inv.next = true;
                self.cin.next = true;
            }
            ProgramState::Div => {
                if self.cnt.q.val().any() {
                    self.sel_a.next = 2.into();
                    self.sel_b.next = 2.into();
                    self.inv.next = true;
                    self.cin.next = true;
                } else {
                    self.sel_b.next = 1.into();
                    self.inv.next = self.neg.q.val();
                    self.cin.next = self.neg.q.val();
                }
            }
            ProgramState::ClampNeg => {
                // -B, or a saturation's ~B = -B - 1.
                self.inv.next = true;
                self.cin.next = self.kind.val() != 8;
            }
            ProgramState::ClampLow => {
                self.sel_a.next = 0.into();
                self.sel_b.next = 2.into();
                self.inv.next = true;
                self.cin.next = true;
            }
            ProgramState::StopTest => {
                self.sel_a.next = 1.into();
                self.inv.next = true;
                self.cin.next = true;
            }
            ProgramState::Take => {
                self.sel_b.next = self.take.q.val();
            }
            _ => {}
        }

        self.alu_a.next = 0.into();
        if self.sel_a.val() == 0 {
            self.alu_a.next =
                bit_cast::<129, 128>(self.x.q.val()) | (bit_cast::<129, 1>(self.x.q.val().get_bits::<1>(127)) << 128);
        }
        if self.sel_a.val() == 1 {
            self.alu_a.next = bit_cast::<129, 128>(self.acc.q.val())
                | (bit_cast::<129, 1>(self.acc.q.val().get_bits::<1>(127)) << 128);
        }
        if self.sel_a.val() == 2 {
            self.alu_a.next = self.rem2.val();
        }
        self.alu_b.next = 1.into();
        if self.sel_b.val() == 0 {
            self.alu_b.next =
                bit_cast::<129, 128>(self.opb.val()) | (bit_cast::<129, 1>(self.opb.val().get_bits::<1>(127)) << 128);
        }
        if self.sel_b.val() == 1 {
            self.alu_b.next =
                bit_cast::<129, 128>(self.x.q.val()) | (bit_cast::<129, 1>(self.x.q.val().get_bits::<1>(127)) << 128);
        }
        if self.sel_b.val() == 2 {
            // A divisor is unsigned; a clamp's `-bound` is not.
            self.alu_b.next = bit_cast::<129, 128>(self.y.q.val());
            if self.kind.val() != 3 {
                self.alu_b.next = bit_cast::<129, 128>(self.y.q.val())
                    | (bit_cast::<129, 1>(self.y.q.val().get_bits::<1>(127)) << 128);
            }
        }
        if self.inv.val() {
            self.alu_b.next = !self.alu_b.val();
        }
        self.alu.next = self.alu_a.val() + self.alu_b.val() + bit_cast::<129, 1>(self.cin.val().into());
        self.alu_sra.next = self.alu.val().get_bits::<128>(1);
        self.acc_sra.next = (self.acc.q.val() >> 1).replace_bit(127, self.acc.q.val().get_bit(127));

        self.pend.d.next = false;
        match self.state.q.val() {
            ProgramState::Idle => {
                if self.load.val() {
                    self.rf.write_enable.next = true;
                    self.rf.write_address.next = self.load_addr.val();
                    self.rf.write_data.next = self.load_data.val();
                }
                self.pend.d.next = self.add.val();
                if self.add.val() {
                    self.pend_addr.d.next = self.add_addr.val();
                    self.x.d.next = bit_cast::<128, 48>(self.add_data.val());
                    if self.add_data.val().get_bit(47) {
                        self.x.d.next = bit_cast::<128, 48>(self.add_data.val()) - (bits::<128>(1) << 48);
                    }
                }
                if self.pend.q.val() {
                    self.rf.write_enable.next = true;
                    self.rf.write_address.next = self.pend_addr.q.val();
                    self.rf.write_data.next = self.alu.val().get_bits::<128>(0);
                }
                if self.go.val() {
                    self.pc.d.next = self.entry.val();
                    self.fail.d.next = false;
                    self.state.d.next = ProgramState::Fetch;
                }
            }
            ProgramState::Fetch => {
                self.ins.d.next = self.prog.data.val();
                self.state.d.next = ProgramState::Operand;
            }
            ProgramState::Operand => {
                self.x.d.next = self.rf.read_data.val();
                self.state.d.next = ProgramState::Exec;
            }
            ProgramState::Exec => {
                self.cnt.d.next = bit_cast::<8, 7>(self.ins.q.val().get_bits::<7>(22));
                self.state.d.next = ProgramState::Write;
                if self.kind.val() < 2 {
                    self.acc.d.next = self.alu.val().get_bits::<128>(0);
                }
                if self.kind.val() == 2 {
                    // x times |B|, subtracting when B is negative.
                    self.neg.d.next = self.opb.val().get_bit(127);
                    self.y.d.next = self.opb.val();
                    if self.opb.val().get_bit(127) {
                        self.y.d.next = self.alu.val().get_bits::<128>(0);
                    }
                    self.acc.d.next = 0.into();
                    self.state.d.next = ProgramState::Mul;
                }
                if self.kind.val() == 3 {
                    self.y.d.next = self.opb.val();
                    self.state.d.next = ProgramState::ShiftLeft;
                }
                if self.kind.val() == 4 {
                    self.acc.d.next = self.alu.val().get_bits::<128>(0);
                    self.state.d.next = ProgramState::Round;
                }
                if self.kind.val() == 5 {
                    self.x.d.next = bit_cast::<128, 6>(self.ins.q.val().get_bits::<6>(10));
                    self.state.d.next = ProgramState::ShiftLeft;
                }
                if (self.kind.val() == 6) || (self.kind.val() == 8) {
                    // x + ~B = x - B - 1 is not negative: x > B, the result is B.
                    self.take.d.next = 0.into();
                    self.state.d.next = ProgramState::Take;
                    if self.alu.val().get_bit(128) {
                        self.state.d.next = ProgramState::ClampNeg;
                    }
                }
                if self.kind.val() == 7 {
                    self.acc.d.next = self.alu.val().get_bits::<128>(0);
                    self.state.d.next = ProgramState::StopTest;
                }
            }
            ProgramState::Mul => {
                if self.y.q.val().any() {
                    if self.y.q.val().get_bit(0) {
                        self.acc.d.next = self.alu.val().get_bits::<128>(0);
                    }
                    self.x.d.next = self.x.q.val() << 1;
                    self.y.d.next = self.y.q.val() >> 1;
                } else {
                    self.state.d.next = ProgramState::Round;
                }
            }
            ProgramState::Round => {
                if self.cnt.q.val().any() {
                    self.cnt.d.next = self.cnt.q.val() - 1;
                    self.acc.d.next = self.acc_sra.val();
                    if (self.cnt.q.val() == 1) && (self.kind.val() == 2) {
                        self.acc.d.next = self.alu_sra.val();
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
                    self.state.d.next = ProgramState::DivAbs;
                } else {
                    self.take.d.next = 1.into();
                    self.state.d.next = ProgramState::Take;
                }
            }
            ProgramState::DivAbs => {
                self.neg.d.next = self.x.q.val().get_bit(127);
                if self.x.q.val().get_bit(127) {
                    self.x.d.next = self.alu.val().get_bits::<128>(0);
                }
                self.rem.d.next = 0.into();
                self.cnt.d.next = 128.into();
                self.state.d.next = ProgramState::Div;
            }
            ProgramState::Div => {
                if self.cnt.q.val().any() {
                    self.cnt.d.next = self.cnt.q.val() - 1;
                    if self.alu.val().get_bit(128) {
                        self.rem.d.next = self.rem2.val();
                        self.x.d.next = self.x.q.val() << 1;
                    } else {
                        self.rem.d.next = self.alu.val();
                        self.x.d.next = (self.x.q.val() << 1) | bits::<128>(1);
                    }
                } else {
                    self.acc.d.next = self.alu.val().get_bits::<128>(0);
                    self.state.d.next = ProgramState::Write;
                }
            }
            ProgramState::ClampNeg => {
                self.y.d.next = self.alu.val().get_bits::<128>(0);
                self.state.d.next = ProgramState::ClampLow;
            }
            ProgramState::ClampLow => {
                // x - (-B) < 0: the result is -B, else x.
                self.take.d.next = 1.into();
                if self.alu.val().get_bit(128) {
                    self.take.d.next = 2.into();
                }
                self.state.d.next = ProgramState::Take;
            }
            ProgramState::StopTest => {
                if self.alu.val().get_bit(128) {
                    self.fail.d.next = true;
                    self.state.d.next = ProgramState::Idle;
                } else if self.ins.q.val().get_bit(29) {
                    self.state.d.next = ProgramState::Idle;
                } else {
                    self.pc.d.next = self.pc.q.val() + 1;
                    self.state.d.next = ProgramState::Fetch;
                }
            }
            ProgramState::Take => {
                self.acc.d.next = self.alu.val().get_bits::<128>(0);
                self.state.d.next = ProgramState::Write;
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
            self.pend.d.next = false;
        }
        // The ROM reads at the next program counter: the word at `pc` is there in `fetch`.
        self.prog.address.next = self.pc.d.val();
    }
}
