//! `SerialMul`: the sequencer's shift-and-add multiplier, `product = a * b` in 18 clocks
//! (`a` 26 bits, `b` 18 bits, both two's complement; `b`'s bit 17 weighs -2^17). The
//! reference multiplies in `i64` ([`crate::pf`]); the test is `fpga/tests/sequencer_blocks.rs`.

use rust_hdl::prelude::*;

/// The serial multiplier.
#[derive(LogicBlock, Default)]
pub struct SerialMul {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (stops a product in progress).
    pub reset: Signal<In, Bit>,
    /// Start on `a` and `b` (one clock); a start while busy restarts.
    pub go: Signal<In, Bit>,
    /// Multiplicand (26-bit two's complement).
    pub a: Signal<In, Bits<26>>,
    /// Multiplier (18-bit two's complement).
    pub b: Signal<In, Bits<18>>,
    /// The product (44-bit two's complement), valid from the clock `busy` falls.
    pub product: Signal<Out, Bits<44>>,
    /// A product is in progress (18 clocks from the clock after `go`).
    pub busy: Signal<Out, Bit>,
    m_a: DFF<Bits<44>>,
    m_b: DFF<Bits<18>>,
    m_acc: DFF<Bits<44>>,
    m_cnt: DFF<Bits<5>>,
    a_s44: Signal<Local, Bits<44>>,
    m_neg: Signal<Local, Bits<44>>,
}

impl SerialMul {
    /// Idle.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for SerialMul {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, m_a, m_b, m_acc, m_cnt);
        self.product.next = self.m_acc.q.val();
        self.busy.next = self.m_cnt.q.val().any();
        // The multiplicand, sign-extended (a mux on the sign bit).
        self.a_s44.next = bit_cast::<44, 26>(self.a.val());
        if self.a.val().get_bit(25) {
            self.a_s44.next = bit_cast::<44, 26>(self.a.val()) | !bits::<44>(0x3ff_ffff);
        }
        self.m_neg.next = bits::<44>(0) - self.m_a.q.val();
        if self.go.val() {
            self.m_a.d.next = self.a_s44.val();
            self.m_b.d.next = self.b.val();
            self.m_acc.d.next = 0.into();
            self.m_cnt.d.next = bits::<5>(18);
        } else if self.m_cnt.q.val().any() {
            if self.m_b.q.val().get_bit(0) {
                if self.m_cnt.q.val() == 1 {
                    self.m_acc.d.next = self.m_acc.q.val() + self.m_neg.val();
                } else {
                    self.m_acc.d.next = self.m_acc.q.val() + self.m_a.q.val();
                }
            }
            self.m_a.d.next = self.m_a.q.val() << 1;
            self.m_b.d.next = self.m_b.q.val() >> 1;
            self.m_cnt.d.next = self.m_cnt.q.val() - 1;
        }
        if self.reset.val() {
            self.m_cnt.d.next = 0.into();
        }
    }
}
