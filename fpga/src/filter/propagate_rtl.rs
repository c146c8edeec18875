//! `Propagate`: the datapath of a particle's propagation, combinational, the RTL twin of
//! [`crate::filter::propagate::propagate`] (test: `fpga/tests/sequencer_blocks.rs`). The sequencer's
//! states take `step` (after the multiplier's `sigma u`), then `clamped`, then `value`;
//! `diff` and `abs_diff` also serve the estimate's and the spread's weighted sums.

use rust_hdl::prelude::*;

/// Propagation arithmetic of one parameter.
#[derive(LogicBlock, Default)]
pub struct Propagate {
    /// The particle's parameter.
    pub x: Signal<In, Bits<24>>,
    /// The centre.
    pub centre: Signal<In, Bits<24>>,
    /// What `diff` is taken from (the centre, or the estimate for the spread).
    pub reference: Signal<In, Bits<24>>,
    /// The parameter's spread.
    pub sigma: Signal<In, Bits<22>>,
    /// `(sigma u) >> 14`, 27 bits (the multiplier's product's bits 14..41: `sigma u` is
    /// below 2^37 in magnitude).
    pub product: Signal<In, Bits<27>>,
    /// The first iteration (particles start at the centre, the step is doubled).
    pub first: Signal<In, Bit>,
    /// The offset so far (registered by the sequencer).
    pub off: Signal<In, Bits<26>>,
    /// The parameter is the scale (kept positive).
    pub scale: Signal<In, Bit>,
    /// `x - reference`, wrapped to 24 bits, sign-extended.
    pub diff: Signal<Out, Bits<26>>,
    /// `|diff|`.
    pub abs_diff: Signal<Out, Bits<26>>,
    /// The offset before the clamp: `sigma u >> 14` first, else `diff + sigma u >> 15`.
    pub step: Signal<Out, Bits<26>>,
    /// `off` within `+-2 sigma`.
    pub clamped: Signal<Out, Bits<26>>,
    /// `centre + off`, a scale of zero or below made 1.
    pub value: Signal<Out, Bits<24>>,
    diff24: Signal<Local, Bits<24>>,
    lim26: Signal<Local, Bits<26>>,
    neg_lim26: Signal<Local, Bits<26>>,
    v24: Signal<Local, Bits<24>>,
}

impl Propagate {
    /// The datapath.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for Propagate {
    #[hdl_gen]
    fn update(&mut self) {
        self.diff24.next = self.x.val() - self.reference.val();
        self.diff.next = bit_cast::<26, 24>(self.diff24.val());
        if self.diff24.val().get_bit(23) {
            self.diff.next = bit_cast::<26, 24>(self.diff24.val()) | bits::<26>(0x300_0000);
        }
        self.abs_diff.next = self.diff.val();
        if self.diff.val().get_bit(25) {
            self.abs_diff.next = bits::<26>(0) - self.diff.val();
        }
        self.step.next = self.diff.val() + self.product.val().get_bits::<26>(1);
        if self.first.val() {
            self.step.next = self.product.val().get_bits::<26>(0);
        }
        self.lim26.next = bit_cast::<26, 22>(self.sigma.val()) << 1;
        // Negations go through a Local: in a Verilog compare, `0 - x` would be 32 bits wide.
        self.neg_lim26.next = bits::<26>(0) - self.lim26.val();
        self.clamped.next = self.off.val();
        if (self.off.val() ^ bits::<26>(0x200_0000)) > (self.lim26.val() ^ bits::<26>(0x200_0000)) {
            self.clamped.next = self.lim26.val();
        }
        if (self.off.val() ^ bits::<26>(0x200_0000)) < (self.neg_lim26.val() ^ bits::<26>(0x200_0000)) {
            self.clamped.next = self.neg_lim26.val();
        }
        self.v24.next = self.centre.val() + self.off.val().get_bits::<24>(0);
        self.value.next = self.v24.val();
        if self.scale.val() && (self.v24.val().get_bit(23) || !self.v24.val().any()) {
            self.value.next = bits::<24>(1);
        }
    }
}
