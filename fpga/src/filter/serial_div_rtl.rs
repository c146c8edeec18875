//! `SerialDiv`: the sequencer's restoring divider, `quotient = n / d` in 24 clocks (`n` 48
//! bits, `d` 24 bits, unsigned, `n < d 2^24`; the quotient's low 26 bits out), the magnitude
//! step of [`crate::filter::serial_div::div_signed`]; the test is `fpga/tests/sequencer_blocks.rs`.
//!
//! The filter's quotients are a mean offset or a mean absolute deviation of 24-bit
//! parameters: `|sum w x| <= 2^23 W`, so the quotient is at most `2^23` and its top 24 bits
//! are zero. A restoring divider finds no subtraction in those 24 steps and only shifts the
//! dividend's top half into the remainder: that half is loaded into the remainder at once and
//! the 24 steps left produce the quotient, bit-exact where `n < d 2^24`.

use rust_hdl::prelude::*;

/// The serial divider.
#[derive(LogicBlock, Default)]
pub struct SerialDiv {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset (stops a quotient in progress).
    pub reset: Signal<In, Bit>,
    /// Start on `n` and `d` (one clock).
    pub go: Signal<In, Bit>,
    /// Dividend.
    pub n: Signal<In, Bits<48>>,
    /// Divisor (non-zero).
    pub d: Signal<In, Bits<24>>,
    /// The quotient's low 26 bits, valid from the clock `busy` falls (the filter's
    /// quotients, a mean offset or spread of 24-bit parameters, are below 2^25).
    pub quotient: Signal<Out, Bits<26>>,
    /// A quotient is in progress (24 clocks from the clock after `go`).
    pub busy: Signal<Out, Bit>,
    dv_n: DFF<Bits<48>>,
    dv_d: DFF<Bits<24>>,
    dv_rem: DFF<Bits<25>>,
    dv_cnt: DFF<Bits<6>>,
    rem2: Signal<Local, Bits<25>>,
}

impl SerialDiv {
    /// Idle.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for SerialDiv {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, dv_n, dv_d, dv_rem, dv_cnt);
        self.quotient.next = self.dv_n.q.val().get_bits::<26>(0);
        self.busy.next = self.dv_cnt.q.val().any();
        self.rem2.next = (self.dv_rem.q.val() << 1) | bit_cast::<25, 1>(self.dv_n.q.val().get_bits::<1>(47));
        if self.go.val() {
            self.dv_n.d.next = self.n.val() << 24;
            self.dv_d.d.next = self.d.val();
            self.dv_rem.d.next = bit_cast::<25, 24>(self.n.val().get_bits::<24>(24));
            self.dv_cnt.d.next = bits::<6>(24);
        } else if self.dv_cnt.q.val().any() {
            if self.rem2.val() >= bit_cast::<25, 24>(self.dv_d.q.val()) {
                self.dv_rem.d.next = self.rem2.val() - bit_cast::<25, 24>(self.dv_d.q.val());
                self.dv_n.d.next = (self.dv_n.q.val() << 1) | bits::<48>(1);
            } else {
                self.dv_rem.d.next = self.rem2.val();
                self.dv_n.d.next = self.dv_n.q.val() << 1;
            }
            self.dv_cnt.d.next = self.dv_cnt.q.val() - 1;
        }
        if self.reset.val() {
            self.dv_cnt.d.next = 0.into();
        }
    }
}
