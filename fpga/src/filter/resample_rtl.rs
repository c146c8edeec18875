//! `Resample`: the two running sums of systematic resampling, the RTL twin of
//! [`crate::filter::resample::resample`] (test: `fpga/tests/sequencer_blocks.rs`). The pointer starts at
//! `u0 W` and moves by `W 2^16` a pick; the cumulative sum adds `n w_i 2^16` a particle;
//! the sequencer advances `i` while the pointer is `beyond` it. The products come from the
//! sequencer's pipelined multiplier (`PipeMul`).

use rust_hdl::prelude::*;

/// The pointer and the cumulative sum.
#[derive(LogicBlock, Default)]
pub struct Resample {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Clear the cumulative sum.
    pub clear: Signal<In, Bit>,
    /// Start the pointer at `product` (`u0 W`).
    pub set_pointer: Signal<In, Bit>,
    /// Add `product << 16` (`n w_i 2^16`) to the cumulative sum.
    pub add_weight: Signal<In, Bit>,
    /// Move the pointer by `w_sum << 16` (the next pick).
    pub advance: Signal<In, Bit>,
    /// The multiplier's product.
    pub product: Signal<In, Bits<44>>,
    /// The weights' sum `W`.
    pub w_sum: Signal<In, Bits<24>>,
    /// The pointer is strictly beyond the cumulative sum.
    pub beyond: Signal<Out, Bit>,
    lft: DFF<Bits<50>>,
    rgt: DFF<Bits<50>>,
}

impl Resample {
    /// Both sums zero.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for Resample {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, lft, rgt);
        self.beyond.next = self.lft.q.val() > self.rgt.q.val();
        if self.clear.val() {
            self.rgt.d.next = 0.into();
        }
        if self.set_pointer.val() {
            self.lft.d.next = bit_cast::<50, 44>(self.product.val());
        }
        if self.add_weight.val() {
            self.rgt.d.next = self.rgt.q.val() + (bit_cast::<50, 44>(self.product.val()) << 16);
        }
        if self.advance.val() {
            self.lft.d.next = self.lft.q.val() + (bit_cast::<50, 24>(self.w_sum.val()) << 16);
        }
    }
}
