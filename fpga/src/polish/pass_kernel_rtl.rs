//! PolishPass's clocked logic: one `update` over the front, the product stage and the flush
//! (the ports, registers, multipliers and order ROMs are in `pass_rtl.rs`).

use super::*;
use crate::polish::programs::{FOUND, INLIERS, SUM_R2};

// Literals in the kernel (`#[hdl_gen]` takes no paths): the registers the pass adds to, the
// slots and the multipliers.
const _: () = assert!(SUM_B == 28 && SUM_R2 == 45 && FOUND == 46 && INLIERS == 47);
const _: () = assert!(PRODUCT_MULS == 3 && PRODUCT_SLOTS == 12 && ROW_PRODUCTS == 35);
const _: () = assert!(crate::polish::JACOBIAN_FRAC == 14 && crate::surface::NORMAL_FRAC == 14);
const _: () = assert!(crate::common::format::COORD_FRAC == 13 && crate::common::format::POSE_TRANSLATION_FRAC == 13);

impl Logic for PolishPass {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self, clock, run, k, img, n, s, inlier, acc, j0, j1, j2, pbusy, pk, pslot, fpend, fl, fslot, fmul, freg,
            fd, fdslot, fdmul, fdreg, fquiet
        );
        for i in 0..8 {
            self.row_j[i].clock.next = self.clock.val();
            self.row_j[i].d.next = self.row_j[i].q.val();
        }
        for m in 0..3 {
            self.pv[m].clock.next = self.clock.val();
            self.pv[m].d.next = false;
            self.mul[m].clock.next = self.clock.val();
            self.bank[m].read_clock.next = self.clock.val();
            self.bank[m].write_clock.next = self.clock.val();
        }
        self.ready.next = !self.run.q.val() && !self.fpend.q.val() && !self.fl.q.val() && !self.fd.q.val();
        self.idle.next = !self.run.q.val()
            && !self.pbusy.q.val()
            && !self.pv[0].q.val()
            && !self.pv[1].q.val()
            && !self.pv[2].q.val()
            && !self.fpend.q.val()
            && !self.fl.q.val()
            && !self.fd.q.val();
        // Sign extensions (a mux on the sign bit); x = q - t (19 bits, in the multiplicand's 26).
        self.q0e.next = bit_cast::<26, 16>(self.img.q.val().get_bits::<16>(0));
        if self.img.q.val().get_bit(15) {
            self.q0e.next = bit_cast::<26, 16>(self.img.q.val().get_bits::<16>(0)) | !bits::<26>(0xffff);
        }
        self.q1e.next = bit_cast::<26, 16>(self.img.q.val().get_bits::<16>(16));
        if self.img.q.val().get_bit(31) {
            self.q1e.next = bit_cast::<26, 16>(self.img.q.val().get_bits::<16>(16)) | !bits::<26>(0xffff);
        }
        self.q2e.next = bit_cast::<26, 16>(self.img.q.val().get_bits::<16>(32));
        if self.img.q.val().get_bit(47) {
            self.q2e.next = bit_cast::<26, 16>(self.img.q.val().get_bits::<16>(32)) | !bits::<26>(0xffff);
        }
        self.t0e.next = bit_cast::<26, 18>(self.t.val().get_bits::<18>(0));
        if self.t.val().get_bit(17) {
            self.t0e.next = bit_cast::<26, 18>(self.t.val().get_bits::<18>(0)) | !bits::<26>(0x3ffff);
        }
        self.t1e.next = bit_cast::<26, 18>(self.t.val().get_bits::<18>(18));
        if self.t.val().get_bit(35) {
            self.t1e.next = bit_cast::<26, 18>(self.t.val().get_bits::<18>(18)) | !bits::<26>(0x3ffff);
        }
        self.t2e.next = bit_cast::<26, 18>(self.t.val().get_bits::<18>(36));
        if self.t.val().get_bit(53) {
            self.t2e.next = bit_cast::<26, 18>(self.t.val().get_bits::<18>(36)) | !bits::<26>(0x3ffff);
        }
        self.x0.next = self.q0e.val() - self.t0e.val();
        self.x1.next = self.q1e.val() - self.t1e.val();
        self.x2.next = self.q2e.val() - self.t2e.val();
        self.n0.next = bit_cast::<18, 16>(self.n.q.val().get_bits::<16>(0));
        if self.n.q.val().get_bit(15) {
            self.n0.next = bit_cast::<18, 16>(self.n.q.val().get_bits::<16>(0)) | !bits::<18>(0xffff);
        }
        self.n1.next = bit_cast::<18, 16>(self.n.q.val().get_bits::<16>(16));
        if self.n.q.val().get_bit(31) {
            self.n1.next = bit_cast::<18, 16>(self.n.q.val().get_bits::<16>(16)) | !bits::<18>(0xffff);
        }
        self.n2.next = bit_cast::<18, 16>(self.n.q.val().get_bits::<16>(32));
        if self.n.q.val().get_bit(47) {
            self.n2.next = bit_cast::<18, 16>(self.n.q.val().get_bits::<16>(32)) | !bits::<18>(0xffff);
        }
        self.s18.next = bit_cast::<18, 13>(self.s.q.val());
        self.s26.next = bit_cast::<26, 13>(self.s.q.val());
        if self.s.q.val().get_bit(12) {
            self.s18.next = bit_cast::<18, 13>(self.s.q.val()) | !bits::<18>(0x1fff);
            self.s26.next = bit_cast::<26, 13>(self.s.q.val()) | !bits::<26>(0x1fff);
        }
        self.p48.next = bit_cast::<48, 44>(self.mul_product.val());
        if self.mul_product.val().get_bit(43) {
            self.p48.next = bit_cast::<48, 44>(self.mul_product.val()) | !bits::<48>(0xfff_ffff_ffff_u64);
        }
        self.p38.next = self.mul_product.val().get_bits::<38>(0);
        // rnd_13 of the accumulated sum: it starts at 2^12 (the rounding constant), so it is
        // its top 25 of 38 bits (arithmetic); then sat18: the top 8 of 25 bits all equal, else
        // the bound of the sign.
        self.r.next = self.acc.q.val().get_bits::<25>(13);
        self.jsat.next = self.r.val().get_bits::<18>(0);
        if (self.r.val().get_bits::<8>(17) != 0) && (self.r.val().get_bits::<8>(17) != 255) {
            self.jsat.next = 0x1_ffff.into();
            if self.r.val().get_bit(24) {
                self.jsat.next = 0x2_0000.into();
            }
        }
        // A sum starts from the rounding constant (at 4, 6, 8, 10), else goes on.
        self.acc_base.next = self.acc.q.val();
        if (self.k.q.val() == 4) || (self.k.q.val() == 6) || (self.k.q.val() == 8) || (self.k.q.val() == 10) {
            self.acc_base.next = 4096.into();
        }

        self.mul_go.next = false;
        self.mul_a.next = self.x0.val();
        self.mul_b.next = self.n0.val();
        self.add.next = false;
        self.add_addr.next = 0.into();
        self.add_data.next = self.p48.val();

        // The front.
        if !self.run.q.val() {
            if self.in_valid.val() && !self.fpend.q.val() && !self.fl.q.val() && !self.fd.q.val() {
                self.run.d.next = true;
                self.k.d.next = 0.into();
                self.img.d.next = self.in_q.val();
                self.n.d.next = self.in_n.val();
                self.s.d.next = self.in_s.val();
            }
        } else {
            self.k.d.next = self.k.q.val() + 1;
            // Products issued.
            if self.k.q.val() == 0 {
                self.mul_go.next = true;
                self.mul_a.next = self.s26.val();
                self.mul_b.next = self.s18.val();
            }
            if self.k.q.val() == 1 {
                self.mul_go.next = true;
                self.mul_a.next = self.x1.val();
                self.mul_b.next = self.n2.val();
            }
            if self.k.q.val() == 2 {
                self.mul_go.next = true;
                self.mul_a.next = self.x2.val();
                self.mul_b.next = self.n1.val();
            }
            if self.k.q.val() == 3 {
                self.mul_go.next = true;
                self.mul_a.next = self.x2.val();
                self.mul_b.next = self.n0.val();
            }
            if self.k.q.val() == 4 {
                self.mul_go.next = true;
                self.mul_a.next = self.x0.val();
                self.mul_b.next = self.n2.val();
            }
            if self.k.q.val() == 5 {
                self.mul_go.next = true;
                self.mul_a.next = self.x0.val();
                self.mul_b.next = self.n1.val();
            }
            if self.k.q.val() == 6 {
                self.mul_go.next = true;
                self.mul_a.next = self.x1.val();
                self.mul_b.next = self.n0.val();
            }
            if self.k.q.val() == 7 {
                self.mul_go.next = true;
                self.mul_a.next = self.x0.val();
                self.mul_b.next = self.n0.val();
            }
            if self.k.q.val() == 8 {
                self.mul_go.next = true;
                self.mul_a.next = self.x1.val();
                self.mul_b.next = self.n1.val();
            }
            if self.k.q.val() == 9 {
                self.mul_go.next = true;
                self.mul_a.next = self.x2.val();
                self.mul_b.next = self.n2.val();
            }
            // Products back.
            if self.k.q.val() == 3 {
                self.add.next = true;
                self.add_addr.next = 45.into();
                self.inlier.d.next = self.gated.val() && (self.mul_product.val().get_bits::<32>(0) <= self.tau2.val());
            }
            if self.k.q.val() == 4 {
                self.add.next = true;
                self.add_addr.next = 46.into();
                self.add_data.next = 1.into();
                if !self.inlier.q.val() {
                    self.run.d.next = false;
                }
            }
            if self.k.q.val() == 5 {
                self.add.next = true;
                self.add_addr.next = 47.into();
                self.add_data.next = 1.into();
            }
            // The cross sums (x1 n2 - x2 n1, x2 n0 - x0 n2, x0 n1 - x1 n0) and the dot product.
            if (self.k.q.val() >= 4) && (self.k.q.val() < 13) {
                self.acc.d.next = self.acc_base.val() + self.p38.val();
                if (self.k.q.val() == 5) || (self.k.q.val() == 7) || (self.k.q.val() == 9) {
                    self.acc.d.next = self.acc_base.val() - self.p38.val();
                }
            }
            if self.k.q.val() == 6 {
                self.j0.d.next = self.jsat.val();
            }
            if self.k.q.val() == 8 {
                self.j1.d.next = self.jsat.val();
            }
            if self.k.q.val() == 10 {
                self.j2.d.next = self.jsat.val();
            }
            // The row to the product stage (the dot product's entry straight from the sum).
            if self.k.q.val() == 13 {
                self.k.d.next = self.k.q.val();
                if !self.pbusy.q.val() {
                    self.run.d.next = false;
                    self.pbusy.d.next = true;
                    self.pk.d.next = 0.into();
                    self.row_j[0].d.next = self.j0.q.val();
                    self.row_j[1].d.next = self.j1.q.val();
                    self.row_j[2].d.next = self.j2.q.val();
                    self.row_j[3].d.next = self.n0.val();
                    self.row_j[4].d.next = self.n1.val();
                    self.row_j[5].d.next = self.n2.val();
                    self.row_j[6].d.next = self.jsat.val();
                    if self.scale_held.val() {
                        self.row_j[6].d.next = 0.into();
                    }
                    self.row_j[7].d.next = self.s18.val();
                }
            }
        }

        // The products sign-extended to the accumulators' 48 bits.
        for m in 0..3 {
            self.pw[m].next = unsigned_cast(self.mul[m].p.val());
        }
        self.pe[0].next = bit_cast::<48, 36>(self.pw[0].val());
        if self.pw[0].val().get_bit(35) {
            self.pe[0].next = bit_cast::<48, 36>(self.pw[0].val()) | !bits::<48>(0xf_ffff_ffff_u64);
        }
        self.pe[1].next = bit_cast::<48, 36>(self.pw[1].val());
        if self.pw[1].val().get_bit(35) {
            self.pe[1].next = bit_cast::<48, 36>(self.pw[1].val()) | !bits::<48>(0xf_ffff_ffff_u64);
        }
        self.pe[2].next = bit_cast::<48, 36>(self.pw[2].val());
        if self.pw[2].val().get_bit(35) {
            self.pe[2].next = bit_cast::<48, 36>(self.pw[2].val()) | !bits::<48>(0xf_ffff_ffff_u64);
        }
        // The product stage: slot `pk` on each multiplier, its accumulator read beside it;
        // the clock after, the product added to it and written back.
        for m in 0..3 {
            self.order[m].address.next = self.pk.q.val();
            self.word[m].next = self.order[m].data.val();
            self.row[m].next = self.word[m].val().get_bits::<3>(0);
            self.col[m].next = self.word[m].val().get_bits::<3>(3);
            self.ja[m].next = self.row_j[0].q.val();
            self.jb[m].next = self.row_j[0].q.val();
            if self.row[m].val() == 1 {
                self.ja[m].next = self.row_j[1].q.val();
            }
            if self.col[m].val() == 1 {
                self.jb[m].next = self.row_j[1].q.val();
            }
            if self.row[m].val() == 2 {
                self.ja[m].next = self.row_j[2].q.val();
            }
            if self.col[m].val() == 2 {
                self.jb[m].next = self.row_j[2].q.val();
            }
            if self.row[m].val() == 3 {
                self.ja[m].next = self.row_j[3].q.val();
            }
            if self.col[m].val() == 3 {
                self.jb[m].next = self.row_j[3].q.val();
            }
            if self.row[m].val() == 4 {
                self.ja[m].next = self.row_j[4].q.val();
            }
            if self.col[m].val() == 4 {
                self.jb[m].next = self.row_j[4].q.val();
            }
            if self.row[m].val() == 5 {
                self.ja[m].next = self.row_j[5].q.val();
            }
            if self.col[m].val() == 5 {
                self.jb[m].next = self.row_j[5].q.val();
            }
            if self.row[m].val() == 6 {
                self.ja[m].next = self.row_j[6].q.val();
            }
            if self.col[m].val() == 6 {
                self.jb[m].next = self.row_j[6].q.val();
            }
            if self.col[m].val() == 7 {
                self.jb[m].next = self.row_j[7].q.val();
            }
            self.mul[m].a.next = signed_cast(self.ja[m].val());
            self.mul[m].b.next = signed_cast(self.jb[m].val());
            self.bank[m].read_address.next = self.pk.q.val();
            if self.fl.q.val() {
                self.bank[m].read_address.next = self.fslot.q.val();
            }
            self.bank[m].write_enable.next = self.pv[m].q.val();
            self.bank[m].write_address.next = self.pslot.q.val();
            self.bank[m].write_data.next = self.bank[m].read_data.val() + self.pe[m].val();
            if self.pbusy.q.val() {
                self.pv[m].d.next = self.word[m].val().get_bit(6);
            }
        }
        if self.pbusy.q.val() {
            self.pslot.d.next = self.pk.q.val();
            self.pk.d.next = self.pk.q.val() + 1;
            if self.pk.q.val() == 11 {
                self.pbusy.d.next = false;
            }
        }

        // The flush: once both stages are empty, each accumulator read, then added and zeroed.
        if self.flush.val() {
            self.fpend.d.next = true;
        }
        if self.fpend.q.val()
            && !self.run.q.val()
            && !self.pbusy.q.val()
            && !self.pv[0].q.val()
            && !self.pv[1].q.val()
            && !self.pv[2].q.val()
        {
            self.fpend.d.next = false;
            self.fl.d.next = true;
            self.fquiet.d.next = false;
            self.fslot.d.next = 0.into();
            self.fmul.d.next = 0.into();
            self.freg.d.next = 0.into();
        }
        self.fd.d.next = self.fl.q.val();
        self.fdslot.d.next = self.fslot.q.val();
        self.fdmul.d.next = self.fmul.q.val();
        self.fdreg.d.next = self.freg.q.val();
        if self.fl.q.val() {
            self.freg.d.next = self.freg.q.val() + 1;
            self.fmul.d.next = self.fmul.q.val() + 1;
            if self.fmul.q.val() == 2 {
                self.fmul.d.next = 0.into();
                self.fslot.d.next = self.fslot.q.val() + 1;
            }
            if self.freg.q.val() == 34 {
                self.fl.d.next = false;
            }
        }
        self.fword.next = self.bank[0].read_data.val();
        if self.fdmul.q.val() == 1 {
            self.fword.next = self.bank[1].read_data.val();
        }
        if self.fdmul.q.val() == 2 {
            self.fword.next = self.bank[2].read_data.val();
        }
        if self.fd.q.val() {
            self.add.next = !self.fquiet.q.val();
            self.add_addr.next = self.fdreg.q.val();
            self.add_data.next = self.fword.val();
            if self.fdmul.q.val() == 0 {
                self.bank[0].write_enable.next = true;
                self.bank[0].write_address.next = self.fdslot.q.val();
                self.bank[0].write_data.next = 0.into();
            }
            if self.fdmul.q.val() == 1 {
                self.bank[1].write_enable.next = true;
                self.bank[1].write_address.next = self.fdslot.q.val();
                self.bank[1].write_data.next = 0.into();
            }
            if self.fdmul.q.val() == 2 {
                self.bank[2].write_enable.next = true;
                self.bank[2].write_address.next = self.fdslot.q.val();
                self.bank[2].write_data.next = 0.into();
            }
        }
        if self.reset.val() {
            self.run.d.next = false;
            self.pbusy.d.next = false;
            self.fpend.d.next = false;
            self.fl.d.next = true;
            self.fquiet.d.next = true;
            self.fslot.d.next = 0.into();
            self.fmul.d.next = 0.into();
            self.freg.d.next = 0.into();
            for m in 0..3 {
                self.pv[m].d.next = false;
            }
        }
    }
}
