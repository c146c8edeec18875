//! `Estimate`: the datapath after a weighted sum, combinational, the RTL twin of
//! [`crate::filter::estimate::estimate_param`] and [`crate::filter::estimate::spread`] (test:
//! `fpga/tests/sequencer_blocks.rs`). The sum's magnitude goes to the divider; its quotient
//! comes back as the new estimate (`centre +- q`) or the new spread (`1.25 q` within
//! `[floor, cap]`).

use rust_hdl::prelude::*;

/// Estimate and spread arithmetic of one parameter.
#[derive(LogicBlock, Default)]
pub struct Estimate {
    /// The weighted sum (48-bit two's complement).
    pub acc: Signal<In, Bits<48>>,
    /// The divider's quotient `|acc| / W` (its low 26 bits).
    pub quotient: Signal<In, Bits<26>>,
    /// The centre.
    pub centre: Signal<In, Bits<24>>,
    /// The spread's floor.
    pub floor: Signal<In, Bits<22>>,
    /// The spread's cap.
    pub cap: Signal<In, Bits<22>>,
    /// The parameter is the scale (kept positive).
    pub scale: Signal<In, Bit>,
    /// `|acc|`, the divider's dividend.
    pub magnitude: Signal<Out, Bits<48>>,
    /// The estimate: `centre + q` with the sum's sign, a scale of zero or below made 1.
    pub value: Signal<Out, Bits<24>>,
    /// `q + q / 4` within `[floor, cap]`.
    pub spread: Signal<Out, Bits<22>>,
    mean26: Signal<Local, Bits<26>>,
    dev26: Signal<Local, Bits<26>>,
    est_v: Signal<Local, Bits<24>>,
}

impl Estimate {
    /// The datapath.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for Estimate {
    #[hdl_gen]
    fn update(&mut self) {
        self.magnitude.next = self.acc.val();
        self.mean26.next = self.quotient.val();
        if self.acc.val().get_bit(47) {
            self.magnitude.next = bits::<48>(0) - self.acc.val();
            self.mean26.next = bits::<26>(0) - self.quotient.val();
        }
        self.dev26.next = self.quotient.val() + (self.quotient.val() >> 2);
        self.spread.next = self.dev26.val().get_bits::<22>(0);
        if self.dev26.val() > bit_cast::<26, 22>(self.cap.val()) {
            self.spread.next = self.cap.val();
        }
        if self.dev26.val() < bit_cast::<26, 22>(self.floor.val()) {
            self.spread.next = self.floor.val();
        }
        self.est_v.next = self.centre.val() + bit_cast::<24, 26>(self.mean26.val());
        self.value.next = self.est_v.val();
        if self.scale.val() && (self.est_v.val().get_bit(23) || !self.est_v.val().any()) {
            self.value.next = bits::<24>(1);
        }
    }
}
