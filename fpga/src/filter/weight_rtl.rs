//! `Weight`: a particle's weight from its cost excess, `EXP[min(255, excess >> (e - 5))]`,
//! the RTL twin of [`crate::filter::weight::weight`] with the exponent rule of [`crate::filter::weight::temper`]
//! (`e = max(tq, p - 2, 5)`, `p` the bit length the temperature pass found; test:
//! `fpga/tests/sequencer_blocks.rs`). The table is [`crate::common::format::exp_table`] in ROM.

use crate::common::format::{exp_table, EXP_ENTRIES};
use crate::filter::weight::MIN_TEMPER_EXP;
use rust_hdl::prelude::*;

/// The weight of one excess: `temper` sets the shift, `latch` takes an excess, and
/// `value` shows its table entry from the next clock on.
#[derive(LogicBlock)]
pub struct Weight {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Set the shift from `p` and `tq`.
    pub temper: Signal<In, Bit>,
    /// The bit length found by the temperature pass.
    pub p: Signal<In, Bits<6>>,
    /// The Run's temperature exponent.
    pub tq: Signal<In, Bits<6>>,
    /// Take `excess`.
    pub latch: Signal<In, Bit>,
    /// A cost minus the iteration's least cost.
    pub excess: Signal<In, Bits<48>>,
    /// The latched excess's weight.
    pub value: Signal<Out, Bits<16>>,
    pre: DFF<Bits<6>>,
    sh: DFF<Bits<48>>,
    exp_rom: ROM<Bits<16>, 8>,
    e_tmp: Signal<Local, Bits<6>>,
    t_entry: Signal<Local, Bits<8>>,
}

impl Default for Weight {
    fn default() -> Self {
        Self::new()
    }
}

impl Weight {
    /// The table in ROM.
    pub fn new() -> Self {
        Weight {
            clock: Default::default(),
            temper: Default::default(),
            p: Default::default(),
            tq: Default::default(),
            latch: Default::default(),
            excess: Default::default(),
            value: Default::default(),
            pre: Default::default(),
            sh: Default::default(),
            exp_rom: exp_table().iter().map(|&w| Bits::<16>::from(w as u64)).into(),
            e_tmp: Default::default(),
            t_entry: Default::default(),
        }
    }
}

// Literals in the kernel (`#[hdl_gen]` takes no paths).
const _: () = assert!(MIN_TEMPER_EXP == 5 && EXP_ENTRIES == 256);

impl Logic for Weight {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, pre, sh);
        self.e_tmp.next = self.tq.val();
        if (self.p.val() > 2) && ((self.p.val() - 2) > self.tq.val()) {
            self.e_tmp.next = self.p.val() - 2;
        }
        if self.temper.val() {
            self.pre.d.next = 0.into();
            if self.e_tmp.val() > 5 {
                self.pre.d.next = self.e_tmp.val() - 5;
            }
        }
        if self.latch.val() {
            self.sh.d.next = self.excess.val() >> self.pre.q.val();
        }
        self.t_entry.next = self.sh.q.val().get_bits::<8>(0);
        if self.sh.q.val() > 255 {
            self.t_entry.next = bits::<8>(255);
        }
        self.exp_rom.address.next = self.t_entry.val();
        self.value.next = self.exp_rom.data.val();
    }
}
