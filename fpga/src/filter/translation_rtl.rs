//! `Translation`: a translation parameter (Q5.19) to the pose's translation (Q5.13,
//! saturated to 18 bits), combinational, the RTL twin of [`crate::filter::translation::translation`]
//! (test: `fpga/tests/sequencer_blocks.rs`).

use rust_hdl::prelude::*;

/// `t = sat18((x + 2^5) >> 6)`.
#[derive(LogicBlock, Default)]
pub struct Translation {
    /// The parameter (24-bit two's complement, Q5.19).
    pub x: Signal<In, Bits<24>>,
    /// The pose's translation (18-bit two's complement, Q5.13).
    pub t: Signal<Out, Bits<18>>,
    x_s25: Signal<Local, Bits<25>>,
    y: Signal<Local, Bits<25>>,
    t19: Signal<Local, Bits<19>>,
}

impl Translation {
    /// The datapath.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for Translation {
    #[hdl_gen]
    fn update(&mut self) {
        self.x_s25.next = bit_cast::<25, 24>(self.x.val());
        if self.x.val().get_bit(23) {
            self.x_s25.next = bit_cast::<25, 24>(self.x.val()) | bits::<25>(0x100_0000);
        }
        self.y.next = self.x_s25.val() + bits::<25>(32);
        self.t19.next = bit_cast::<19, 25>(self.y.val() >> 6);
        self.t.next = self.t19.val().get_bits::<18>(0);
        if (self.t19.val() ^ bits::<19>(0x4_0000)) > bits::<19>(0x5_ffff) {
            self.t.next = bits::<18>(0x1_ffff);
        }
        if (self.t19.val() ^ bits::<19>(0x4_0000)) < bits::<19>(0x2_0000) {
            self.t.next = bits::<18>(0x2_0000);
        }
    }
}
