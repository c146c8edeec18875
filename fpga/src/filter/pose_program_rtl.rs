//! `PoseProgram`: the datapath that runs [`crate::filter::pose_program::POSE_PROGRAM`] (in ROM) over a
//! 32 x 26-bit register file, the RTL twin of [`crate::filter::pose_program::run_program`] (test:
//! `fpga/tests/sequencer_blocks.rs`). The sequencer's states drive it a step at a time
//! (`fetch`, `latch`, `exec`, `retire`) and lend it the pipelined multiplier; the CORDIC's
//! cosines and sines and the scale come in through `load`. The nine `MulM` results (the
//! pose matrix, Q3.15) leave through `entry` instead of the register file.

use crate::filter::pose_program::{Op, POSE_PROGRAM};
use rust_hdl::prelude::*;

/// The pose program's datapath.
#[derive(LogicBlock)]
pub struct PoseProgram {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Write `load_data` to register `load_addr`.
    pub load: Signal<In, Bit>,
    /// Register to load.
    pub load_addr: Signal<In, Bits<5>>,
    /// Value to load (26-bit two's complement).
    pub load_data: Signal<In, Bits<26>>,
    /// Start from the first instruction.
    pub restart: Signal<In, Bit>,
    /// Fetch the instruction at the program counter and read its first operand.
    pub fetch: Signal<In, Bit>,
    /// Latch the first operand and read the second.
    pub latch: Signal<In, Bit>,
    /// Execute: an Add or Sub writes its result and advances; a multiply presents
    /// `mul_a`, `mul_b` to the multiplier.
    pub exec: Signal<In, Bit>,
    /// The multiplier's `product` is ready: a Mul16 writes it back; advance.
    pub retire: Signal<In, Bit>,
    /// The multiplier's product.
    pub product: Signal<In, Bits<44>>,
    /// The fetched instruction is an Add or Sub.
    pub arith: Signal<Out, Bit>,
    /// The fetched instruction is a MulM (its result is `entry`, not a register).
    pub to_pose: Signal<Out, Bit>,
    /// The multiply's wide operand.
    pub mul_a: Signal<Out, Bits<26>>,
    /// The multiply's 18-bit operand.
    pub mul_b: Signal<Out, Bits<18>>,
    /// `sat18((product + 2^21) >> 22)`: a pose matrix entry.
    pub entry: Signal<Out, Bits<18>>,
    /// The fetched instruction is the program's last.
    pub last: Signal<Out, Bit>,
    pc: DFF<Bits<5>>,
    op_kind: DFF<Bits<2>>,
    op_dst: DFF<Bits<5>>,
    op_b: DFF<Bits<5>>,
    opa: DFF<Bits<26>>,
    rf: RAM<Bits<26>, 5>,
    prog: ROM<Bits<17>, 5>,
    prog_word: Signal<Local, Bits<17>>,
    rf_b: Signal<Local, Bits<26>>,
    m_round16: Signal<Local, Bits<44>>,
    m_round22: Signal<Local, Bits<44>>,
    m_t22: Signal<Local, Bits<22>>,
}

impl Default for PoseProgram {
    fn default() -> Self {
        Self::new()
    }
}

impl PoseProgram {
    /// The program in ROM, the register file cleared.
    pub fn new() -> Self {
        PoseProgram {
            clock: Default::default(),
            load: Default::default(),
            load_addr: Default::default(),
            load_data: Default::default(),
            restart: Default::default(),
            fetch: Default::default(),
            latch: Default::default(),
            exec: Default::default(),
            retire: Default::default(),
            product: Default::default(),
            arith: Default::default(),
            to_pose: Default::default(),
            mul_a: Default::default(),
            mul_b: Default::default(),
            entry: Default::default(),
            last: Default::default(),
            pc: Default::default(),
            op_kind: Default::default(),
            op_dst: Default::default(),
            op_b: Default::default(),
            opa: Default::default(),
            rf: RAM::new((0..32u64).map(|a| (Bits::<5>::from(a), Bits::<26>::default())).collect()),
            prog: POSE_PROGRAM.iter().map(|op| Bits::<17>::from(op.encode() as u64)).into(),
            prog_word: Default::default(),
            rf_b: Default::default(),
            m_round16: Default::default(),
            m_round22: Default::default(),
            m_t22: Default::default(),
        }
    }
}

// Literals in the kernel (`#[hdl_gen]` takes no paths): the last instruction's address
// and the encoding's field positions ([`Op::encode`]).
const _: () = assert!(POSE_PROGRAM.len() == 28);
const _: () = assert!(Op::Sub { dst: 1, a: 2, b: 3 }.encode() == 3 | 1 << 2 | 2 << 7 | 3 << 12);

impl Logic for PoseProgram {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, pc, op_kind, op_dst, op_b, opa);
        self.rf.read_clock.next = self.clock.val();
        self.rf.write_clock.next = self.clock.val();
        self.prog.address.next = self.pc.q.val();
        self.prog_word.next = self.prog.data.val();
        self.rf_b.next = self.rf.read_data.val();
        self.arith.next = self.op_kind.q.val().get_bit(1);
        self.to_pose.next = self.op_kind.q.val().get_bit(0);
        self.mul_a.next = self.opa.q.val();
        self.mul_b.next = self.rf_b.val().get_bits::<18>(0);
        self.last.next = self.pc.q.val() == 27;
        self.m_round16.next = self.product.val() + bits::<44>(0x8000);
        self.m_round22.next = self.product.val() + bits::<44>(0x20_0000);
        self.m_t22.next = bit_cast::<22, 44>(self.m_round22.val() >> 22);
        self.entry.next = self.m_t22.val().get_bits::<18>(0);
        if (self.m_t22.val() ^ bits::<22>(0x20_0000)) > bits::<22>(0x21_ffff) {
            self.entry.next = bits::<18>(0x1_ffff);
        }
        if (self.m_t22.val() ^ bits::<22>(0x20_0000)) < bits::<22>(0x1e_0000) {
            self.entry.next = bits::<18>(0x2_0000);
        }

        self.rf.read_address.next = self.op_b.q.val();
        self.rf.write_enable.next = false;
        self.rf.write_address.next = self.op_dst.q.val();
        self.rf.write_data.next = self.load_data.val();
        if self.load.val() {
            self.rf.write_enable.next = true;
            self.rf.write_address.next = self.load_addr.val();
        }
        if self.restart.val() {
            self.pc.d.next = 0.into();
        }
        if self.fetch.val() {
            self.rf.read_address.next = self.prog_word.val().get_bits::<5>(7);
            self.op_kind.d.next = self.prog_word.val().get_bits::<2>(0);
            self.op_dst.d.next = self.prog_word.val().get_bits::<5>(2);
            self.op_b.d.next = self.prog_word.val().get_bits::<5>(12);
        }
        if self.latch.val() {
            self.opa.d.next = self.rf.read_data.val();
        }
        if self.exec.val() && self.op_kind.q.val().get_bit(1) {
            self.rf.write_enable.next = true;
            if self.op_kind.q.val().get_bit(0) {
                self.rf.write_data.next = self.opa.q.val() - self.rf_b.val();
            } else {
                self.rf.write_data.next = self.opa.q.val() + self.rf_b.val();
            }
            self.pc.d.next = self.pc.q.val() + 1;
        }
        if self.retire.val() {
            if !self.op_kind.q.val().get_bit(0) {
                self.rf.write_enable.next = true;
                self.rf.write_data.next = bit_cast::<26, 44>(self.m_round16.val() >> 16);
            }
            self.pc.d.next = self.pc.q.val() + 1;
        }
    }
}
