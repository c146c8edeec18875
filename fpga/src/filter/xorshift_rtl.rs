//! `Xorshift32`: one step of the sequencer's PRNG, xorshift32 (13, 17, 5), combinational;
//! the RTL twin of [`crate::filter::xorshift::Xorshift32::next`] (test: `fpga/tests/sequencer_blocks.rs`).

use rust_hdl::prelude::*;

/// One xorshift32 step: `y` is the state after `x`.
#[derive(LogicBlock, Default)]
pub struct Xorshift32 {
    /// The state.
    pub x: Signal<In, Bits<32>>,
    /// The next state.
    pub y: Signal<Out, Bits<32>>,
    t1: Signal<Local, Bits<32>>,
    t2: Signal<Local, Bits<32>>,
}

impl Xorshift32 {
    /// The step.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Logic for Xorshift32 {
    #[hdl_gen]
    fn update(&mut self) {
        self.t1.next = self.x.val() ^ (self.x.val() << 13);
        self.t2.next = self.t1.val() ^ (self.t1.val() >> 17);
        self.y.next = self.t2.val() ^ (self.t2.val() << 5);
    }
}
