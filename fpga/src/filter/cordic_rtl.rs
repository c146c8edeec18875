//! `Cordic`: cosine and sine of a binary angle (Q2.16) in 18 rotation steps, the RTL twin
//! of [`crate::filter::cordic::cordic`] (test: `fpga/tests/sequencer_blocks.rs`). Angles beyond a
//! quarter turn are turned by half a turn first and the result negated; the result is
//! rounded from Q2.18 to Q2.16.

use crate::filter::cordic::{CORDIC_ATAN, CORDIC_K, CORDIC_STEPS};
use rust_hdl::prelude::*;

/// The CORDIC: `load` (one clock), then `step` for 18 clocks (`last` on the 18th); `value`
/// is then the cosine, or the sine while `sin` is high.
#[derive(LogicBlock)]
pub struct Cordic {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Load `angle` (and the gain-compensated unit vector).
    pub load: Signal<In, Bit>,
    /// One rotation step.
    pub step: Signal<In, Bit>,
    /// Present the sine (else the cosine).
    pub sin: Signal<In, Bit>,
    /// The angle (24-bit two's complement, Q2.16 binary angle: 2^22 is a quarter turn).
    pub angle: Signal<In, Bits<24>>,
    /// This step is the last (the 18th).
    pub last: Signal<Out, Bit>,
    /// Cosine or sine (Q2.16, sign-extended to the pose program's 26 bits).
    pub value: Signal<Out, Bits<26>>,
    cx: DFF<Bits<22>>,
    cy: DFF<Bits<22>>,
    cz: DFF<Bits<25>>,
    ci: DFF<Bits<5>>,
    cflip: DFF<Bit>,
    atan: ROM<Bits<22>, 5>,
    gain: Constant<Bits<22>>,
    ang_x: Signal<Local, Bits<24>>,
    ang_s25: Signal<Local, Bits<25>>,
    ang_x_s25: Signal<Local, Bits<25>>,
    sel_atan: Signal<Local, Bits<22>>,
    ones22: Signal<Local, Bits<22>>,
    cx_sh: Signal<Local, Bits<22>>,
    cy_sh: Signal<Local, Bits<22>>,
    cor_out: Signal<Local, Bits<22>>,
    cor_sum: Signal<Local, Bits<22>>,
    cor_r: Signal<Local, Bits<20>>,
    cor_v: Signal<Local, Bits<20>>,
}

impl Default for Cordic {
    fn default() -> Self {
        Self::new()
    }
}

impl Cordic {
    /// The angle table in ROM.
    pub fn new() -> Self {
        Cordic {
            clock: Default::default(),
            load: Default::default(),
            step: Default::default(),
            sin: Default::default(),
            angle: Default::default(),
            last: Default::default(),
            value: Default::default(),
            cx: Default::default(),
            cy: Default::default(),
            cz: Default::default(),
            ci: Default::default(),
            cflip: Default::default(),
            atan: CORDIC_ATAN.iter().map(|&t| Bits::<22>::from(t as u64)).into(),
            gain: Constant::new(Bits::<22>::from(CORDIC_K as u64)),
            ang_x: Default::default(),
            ang_s25: Default::default(),
            ang_x_s25: Default::default(),
            sel_atan: Default::default(),
            ones22: Default::default(),
            cx_sh: Default::default(),
            cy_sh: Default::default(),
            cor_out: Default::default(),
            cor_sum: Default::default(),
            cor_r: Default::default(),
            cor_v: Default::default(),
        }
    }
}

// The last step's index is a literal in the kernel (`#[hdl_gen]` takes no paths).
const _: () = assert!(CORDIC_STEPS == 18);

impl Logic for Cordic {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, cx, cy, cz, ci, cflip);
        self.ang_x.next = self.angle.val() ^ bits::<24>(0x80_0000);
        self.ang_s25.next = bit_cast::<25, 24>(self.angle.val());
        if self.angle.val().get_bit(23) {
            self.ang_s25.next = bit_cast::<25, 24>(self.angle.val()) | bits::<25>(0x100_0000);
        }
        self.ang_x_s25.next = bit_cast::<25, 24>(self.ang_x.val());
        if self.ang_x.val().get_bit(23) {
            self.ang_x_s25.next = bit_cast::<25, 24>(self.ang_x.val()) | bits::<25>(0x100_0000);
        }
        self.atan.address.next = self.ci.q.val();
        self.sel_atan.next = self.atan.data.val();
        self.ones22.next = bits::<22>(0x3f_ffff);
        self.cx_sh.next = self.cx.q.val() >> self.ci.q.val();
        if self.cx.q.val().get_bit(21) {
            self.cx_sh.next = (self.cx.q.val() >> self.ci.q.val()) | !(self.ones22.val() >> self.ci.q.val());
        }
        self.cy_sh.next = self.cy.q.val() >> self.ci.q.val();
        if self.cy.q.val().get_bit(21) {
            self.cy_sh.next = (self.cy.q.val() >> self.ci.q.val()) | !(self.ones22.val() >> self.ci.q.val());
        }
        self.cor_out.next = self.cx.q.val();
        if self.sin.val() {
            self.cor_out.next = self.cy.q.val();
        }
        self.cor_sum.next = self.cor_out.val() + 2;
        self.cor_r.next = bit_cast::<20, 22>(self.cor_sum.val() >> 2);
        self.cor_v.next = self.cor_r.val();
        if self.cflip.q.val() {
            self.cor_v.next = bits::<20>(0) - self.cor_r.val();
        }
        self.value.next = bit_cast::<26, 20>(self.cor_v.val());
        if self.cor_v.val().get_bit(19) {
            self.value.next = bit_cast::<26, 20>(self.cor_v.val()) | bits::<26>(0x3f0_0000);
        }
        self.last.next = self.ci.q.val() == 17;

        if self.load.val() {
            self.cx.d.next = self.gain.val();
            self.cy.d.next = 0.into();
            self.ci.d.next = 0.into();
            self.cflip.d.next = false;
            self.cz.d.next = self.ang_s25.val();
            if (self.ang_x.val() > bits::<24>(0xc0_0000)) || (self.ang_x.val() < bits::<24>(0x40_0000)) {
                self.cflip.d.next = true;
                self.cz.d.next = self.ang_x_s25.val();
            }
        }
        if self.step.val() {
            if !self.cz.q.val().get_bit(24) {
                self.cx.d.next = self.cx.q.val() - self.cy_sh.val();
                self.cy.d.next = self.cy.q.val() + self.cx_sh.val();
                self.cz.d.next = self.cz.q.val() - bit_cast::<25, 22>(self.sel_atan.val());
            } else {
                self.cx.d.next = self.cx.q.val() + self.cy_sh.val();
                self.cy.d.next = self.cy.q.val() - self.cx_sh.val();
                self.cz.d.next = self.cz.q.val() + bit_cast::<25, 22>(self.sel_atan.val());
            }
            self.ci.d.next = self.ci.q.val() + 1;
        }
    }
}
