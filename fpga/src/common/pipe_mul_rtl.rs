//! `PipeMul`: the sequencer's multiplier, `product = a * b` (`a` 26 bits, `b` 18 bits, both
//! two's complement; `b`'s bit 17 weighs -2^17) in LUTs, pipelined: the operands are
//! registered on `go`, a carry-save tree (18 gated rows of `a` and a correction row reduced
//! to two by 17 3:2 compressors in 6 levels, no carry chain) is registered the clock
//! after, and their sum the clock after that. A product is ready two clocks after the clock
//! that takes `go`, and a new operand pair may be taken every clock. No DSP48A1 (all belong
//! to the pipeline and the weight stage). The reference multiplies in `i64` ([`crate::filter::pf`]);
//! the test is `fpga/tests/sequencer_blocks.rs`.

use rust_hdl::prelude::*;

/// The pipelined multiplier.
#[derive(LogicBlock, Default)]
pub struct PipeMul {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (forgets the products in flight: `busy` and `valid` low).
    pub reset: Signal<In, Bit>,
    /// Take `a` and `b` (one clock per pair, any number of consecutive clocks).
    pub go: Signal<In, Bit>,
    /// Multiplicand (26-bit two's complement).
    pub a: Signal<In, Bits<26>>,
    /// Multiplier (18-bit two's complement).
    pub b: Signal<In, Bits<18>>,
    /// The product of the last pair taken (44-bit two's complement), from the clock `busy`
    /// falls (two clocks after the clock that takes `go`) until the next `go` reaches it.
    pub product: Signal<Out, Bits<44>>,
    /// A product is on its way (two clocks from the clock after the last `go`).
    pub busy: Signal<Out, Bit>,
    /// `product` is a new one (one clock per pair taken, two clocks after it was taken).
    pub valid: Signal<Out, Bit>,
    m_a: DFF<Bits<44>>,
    m_b: DFF<Bits<18>>,
    m_s: DFF<Bits<44>>,
    m_c: DFF<Bits<44>>,
    m_acc: DFF<Bits<44>>,
    m_cnt: DFF<Bits<2>>,
    m_v: DFF<Bits<3>>,
    a_s44: Signal<Local, Bits<44>>,
    r0: Signal<Local, Bits<44>>,
    r1: Signal<Local, Bits<44>>,
    r2: Signal<Local, Bits<44>>,
    r3: Signal<Local, Bits<44>>,
    r4: Signal<Local, Bits<44>>,
    r5: Signal<Local, Bits<44>>,
    r6: Signal<Local, Bits<44>>,
    r7: Signal<Local, Bits<44>>,
    r8: Signal<Local, Bits<44>>,
    r9: Signal<Local, Bits<44>>,
    r10: Signal<Local, Bits<44>>,
    r11: Signal<Local, Bits<44>>,
    r12: Signal<Local, Bits<44>>,
    r13: Signal<Local, Bits<44>>,
    r14: Signal<Local, Bits<44>>,
    r15: Signal<Local, Bits<44>>,
    r16: Signal<Local, Bits<44>>,
    r17: Signal<Local, Bits<44>>,
    rk: Signal<Local, Bits<44>>,
    s1_0: Signal<Local, Bits<44>>,
    c1_0: Signal<Local, Bits<44>>,
    s1_1: Signal<Local, Bits<44>>,
    c1_1: Signal<Local, Bits<44>>,
    s1_2: Signal<Local, Bits<44>>,
    c1_2: Signal<Local, Bits<44>>,
    s1_3: Signal<Local, Bits<44>>,
    c1_3: Signal<Local, Bits<44>>,
    s1_4: Signal<Local, Bits<44>>,
    c1_4: Signal<Local, Bits<44>>,
    s1_5: Signal<Local, Bits<44>>,
    c1_5: Signal<Local, Bits<44>>,
    s2_0: Signal<Local, Bits<44>>,
    c2_0: Signal<Local, Bits<44>>,
    s2_1: Signal<Local, Bits<44>>,
    c2_1: Signal<Local, Bits<44>>,
    s2_2: Signal<Local, Bits<44>>,
    c2_2: Signal<Local, Bits<44>>,
    s2_3: Signal<Local, Bits<44>>,
    c2_3: Signal<Local, Bits<44>>,
    s3_0: Signal<Local, Bits<44>>,
    c3_0: Signal<Local, Bits<44>>,
    s3_1: Signal<Local, Bits<44>>,
    c3_1: Signal<Local, Bits<44>>,
    s3_2: Signal<Local, Bits<44>>,
    c3_2: Signal<Local, Bits<44>>,
    s4_0: Signal<Local, Bits<44>>,
    c4_0: Signal<Local, Bits<44>>,
    s4_1: Signal<Local, Bits<44>>,
    c4_1: Signal<Local, Bits<44>>,
    s5_0: Signal<Local, Bits<44>>,
    c5_0: Signal<Local, Bits<44>>,
    s6_0: Signal<Local, Bits<44>>,
    c6_0: Signal<Local, Bits<44>>,
}

impl PipeMul {
    /// Idle.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for PipeMul {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, m_a, m_b, m_s, m_c, m_acc, m_cnt, m_v);
        self.product.next = self.m_acc.q.val();
        self.busy.next = self.m_cnt.q.val().any();
        self.valid.next = self.m_v.q.val().get_bit(2);
        // The multiplicand, sign-extended (a mux on the sign bit).
        self.a_s44.next = bit_cast::<44, 26>(self.a.val());
        if self.a.val().get_bit(25) {
            self.a_s44.next = bit_cast::<44, 26>(self.a.val()) | !bits::<44>(0x3ff_ffff);
        }
        // Stage 0: the operands.
        if self.go.val() {
            self.m_a.d.next = self.a_s44.val();
            self.m_b.d.next = self.b.val();
            self.m_cnt.d.next = bits::<2>(2);
        } else if self.m_cnt.q.val().any() {
            self.m_cnt.d.next = self.m_cnt.q.val() - 1;
        }
        self.m_v.d.next = self.m_v.q.val() << 1;
        if self.go.val() {
            self.m_v.d.next = (self.m_v.q.val() << 1) | bits::<3>(1);
        }
        // Stage 1: the rows and the carry-save tree.
        self.r0.next = 0.into();
        if self.m_b.q.val().get_bit(0) {
            self.r0.next = self.m_a.q.val();
        }
        self.r1.next = 0.into();
        if self.m_b.q.val().get_bit(1) {
            self.r1.next = self.m_a.q.val() << 1;
        }
        self.r2.next = 0.into();
        if self.m_b.q.val().get_bit(2) {
            self.r2.next = self.m_a.q.val() << 2;
        }
        self.r3.next = 0.into();
        if self.m_b.q.val().get_bit(3) {
            self.r3.next = self.m_a.q.val() << 3;
        }
        self.r4.next = 0.into();
        if self.m_b.q.val().get_bit(4) {
            self.r4.next = self.m_a.q.val() << 4;
        }
        self.r5.next = 0.into();
        if self.m_b.q.val().get_bit(5) {
            self.r5.next = self.m_a.q.val() << 5;
        }
        self.r6.next = 0.into();
        if self.m_b.q.val().get_bit(6) {
            self.r6.next = self.m_a.q.val() << 6;
        }
        self.r7.next = 0.into();
        if self.m_b.q.val().get_bit(7) {
            self.r7.next = self.m_a.q.val() << 7;
        }
        self.r8.next = 0.into();
        if self.m_b.q.val().get_bit(8) {
            self.r8.next = self.m_a.q.val() << 8;
        }
        self.r9.next = 0.into();
        if self.m_b.q.val().get_bit(9) {
            self.r9.next = self.m_a.q.val() << 9;
        }
        self.r10.next = 0.into();
        if self.m_b.q.val().get_bit(10) {
            self.r10.next = self.m_a.q.val() << 10;
        }
        self.r11.next = 0.into();
        if self.m_b.q.val().get_bit(11) {
            self.r11.next = self.m_a.q.val() << 11;
        }
        self.r12.next = 0.into();
        if self.m_b.q.val().get_bit(12) {
            self.r12.next = self.m_a.q.val() << 12;
        }
        self.r13.next = 0.into();
        if self.m_b.q.val().get_bit(13) {
            self.r13.next = self.m_a.q.val() << 13;
        }
        self.r14.next = 0.into();
        if self.m_b.q.val().get_bit(14) {
            self.r14.next = self.m_a.q.val() << 14;
        }
        self.r15.next = 0.into();
        if self.m_b.q.val().get_bit(15) {
            self.r15.next = self.m_a.q.val() << 15;
        }
        self.r16.next = 0.into();
        if self.m_b.q.val().get_bit(16) {
            self.r16.next = self.m_a.q.val() << 16;
        }
        // Bit 17 weighs -2^17: -(a 2^17) = !a 2^17 + 2^17 (the correction row).
        self.r17.next = 0.into();
        self.rk.next = 0.into();
        if self.m_b.q.val().get_bit(17) {
            self.r17.next = !self.m_a.q.val() << 17;
            self.rk.next = bits::<44>(0x2_0000);
        }
        self.s1_0.next = self.r0.val() ^ self.r1.val() ^ self.r2.val();
        self.c1_0.next =
            ((self.r0.val() & self.r1.val()) | (self.r0.val() & self.r2.val()) | (self.r1.val() & self.r2.val())) << 1;
        self.s1_1.next = self.r3.val() ^ self.r4.val() ^ self.r5.val();
        self.c1_1.next =
            ((self.r3.val() & self.r4.val()) | (self.r3.val() & self.r5.val()) | (self.r4.val() & self.r5.val())) << 1;
        self.s1_2.next = self.r6.val() ^ self.r7.val() ^ self.r8.val();
        self.c1_2.next =
            ((self.r6.val() & self.r7.val()) | (self.r6.val() & self.r8.val()) | (self.r7.val() & self.r8.val())) << 1;
        self.s1_3.next = self.r9.val() ^ self.r10.val() ^ self.r11.val();
        self.c1_3.next =
            ((self.r9.val() & self.r10.val()) | (self.r9.val() & self.r11.val()) | (self.r10.val() & self.r11.val()))
                << 1;
        self.s1_4.next = self.r12.val() ^ self.r13.val() ^ self.r14.val();
        self.c1_4.next =
            ((self.r12.val() & self.r13.val()) | (self.r12.val() & self.r14.val()) | (self.r13.val() & self.r14.val()))
                << 1;
        self.s1_5.next = self.r15.val() ^ self.r16.val() ^ self.r17.val();
        self.c1_5.next =
            ((self.r15.val() & self.r16.val()) | (self.r15.val() & self.r17.val()) | (self.r16.val() & self.r17.val()))
                << 1;
        self.s2_0.next = self.s1_0.val() ^ self.c1_0.val() ^ self.s1_1.val();
        self.c2_0.next = ((self.s1_0.val() & self.c1_0.val())
            | (self.s1_0.val() & self.s1_1.val())
            | (self.c1_0.val() & self.s1_1.val()))
            << 1;
        self.s2_1.next = self.c1_1.val() ^ self.s1_2.val() ^ self.c1_2.val();
        self.c2_1.next = ((self.c1_1.val() & self.s1_2.val())
            | (self.c1_1.val() & self.c1_2.val())
            | (self.s1_2.val() & self.c1_2.val()))
            << 1;
        self.s2_2.next = self.s1_3.val() ^ self.c1_3.val() ^ self.s1_4.val();
        self.c2_2.next = ((self.s1_3.val() & self.c1_3.val())
            | (self.s1_3.val() & self.s1_4.val())
            | (self.c1_3.val() & self.s1_4.val()))
            << 1;
        self.s2_3.next = self.c1_4.val() ^ self.s1_5.val() ^ self.c1_5.val();
        self.c2_3.next = ((self.c1_4.val() & self.s1_5.val())
            | (self.c1_4.val() & self.c1_5.val())
            | (self.s1_5.val() & self.c1_5.val()))
            << 1;
        self.s3_0.next = self.s2_0.val() ^ self.c2_0.val() ^ self.s2_1.val();
        self.c3_0.next = ((self.s2_0.val() & self.c2_0.val())
            | (self.s2_0.val() & self.s2_1.val())
            | (self.c2_0.val() & self.s2_1.val()))
            << 1;
        self.s3_1.next = self.c2_1.val() ^ self.s2_2.val() ^ self.c2_2.val();
        self.c3_1.next = ((self.c2_1.val() & self.s2_2.val())
            | (self.c2_1.val() & self.c2_2.val())
            | (self.s2_2.val() & self.c2_2.val()))
            << 1;
        self.s3_2.next = self.s2_3.val() ^ self.c2_3.val() ^ self.rk.val();
        self.c3_2.next = ((self.s2_3.val() & self.c2_3.val())
            | (self.s2_3.val() & self.rk.val())
            | (self.c2_3.val() & self.rk.val()))
            << 1;
        self.s4_0.next = self.s3_0.val() ^ self.c3_0.val() ^ self.s3_1.val();
        self.c4_0.next = ((self.s3_0.val() & self.c3_0.val())
            | (self.s3_0.val() & self.s3_1.val())
            | (self.c3_0.val() & self.s3_1.val()))
            << 1;
        self.s4_1.next = self.c3_1.val() ^ self.s3_2.val() ^ self.c3_2.val();
        self.c4_1.next = ((self.c3_1.val() & self.s3_2.val())
            | (self.c3_1.val() & self.c3_2.val())
            | (self.s3_2.val() & self.c3_2.val()))
            << 1;
        self.s5_0.next = self.s4_0.val() ^ self.c4_0.val() ^ self.s4_1.val();
        self.c5_0.next = ((self.s4_0.val() & self.c4_0.val())
            | (self.s4_0.val() & self.s4_1.val())
            | (self.c4_0.val() & self.s4_1.val()))
            << 1;
        self.s6_0.next = self.s5_0.val() ^ self.c5_0.val() ^ self.c4_1.val();
        self.c6_0.next = ((self.s5_0.val() & self.c5_0.val())
            | (self.s5_0.val() & self.c4_1.val())
            | (self.c5_0.val() & self.c4_1.val()))
            << 1;
        self.m_s.d.next = self.s6_0.val();
        self.m_c.d.next = self.c6_0.val();
        // Stage 2: the carry-propagate sum.
        self.m_acc.d.next = self.m_s.q.val() + self.m_c.q.val();
        if self.reset.val() {
            self.m_cnt.d.next = 0.into();
            self.m_v.d.next = 0.into();
        }
    }
}
