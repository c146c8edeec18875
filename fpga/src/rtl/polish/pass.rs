//! `PolishPass`: one found point of a polish pass ([`crate::polish::PassSums::add_point`]
//! with [`crate::polish::jacobian`]) as products on a borrowed pipelined multiplier (the
//! sequencer's `PipeMul`, idle after the filter: `mul_*`, a product three clocks after the
//! clock that issues it) and adds into `PolishProgram`'s register file (`add*`): `s^2` to
//! `SUM_R2`, 1 to `FOUND`; for an inlier (`gated` and `s^2 <= tau2`) the Jacobian row from
//! nine products, then its 28 products `J_r J_c` to `a` and 7 products `J_r s` to `b`, and
//! 1 to `INLIERS`. Test: `fpga/tests/polish_pass.rs`, against `add_point` on random points.
//!
//! Schedule, clock `k` after the point is taken (a product comes back three clocks after
//! the clock that issues it): `s s` issued at 0; the nine products of `x = q - t` and `n` at
//! 1 to 9; `s^2` back and added at 3, `found` at 4 (an outlier ends there); the cross and
//! dot products combined at 4 to 12 in one accumulator, each rounded and saturated into
//! its Jacobian entry as the next starts (at 6, 8, 10 and 13); `inliers` added at 15; the
//! 35 products issued at 14 to 48 and added at 17 to 51. An inlier takes 52 clocks, an
//! outlier 5, and `ready` the clock after.

use crate::polish::programs::{FOUND, INLIERS, SUM_B, SUM_R2};
use crate::polish::{upper, UNKNOWNS};
use rust_hdl::prelude::*;

/// The pass's per-point datapath.
#[derive(LogicBlock)]
pub struct PolishPass {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset: idle.
    pub reset: Signal<In, Bit>,
    /// Gate on: points with `s^2 <= tau2` are inliers (off: the statistics only).
    pub gated: Signal<In, Bit>,
    /// The gate.
    pub tau2: Signal<In, Bits<32>>,
    /// The pose's translation (3 x 18 bits, x low).
    pub t: Signal<In, Bits<54>>,
    /// Take a point (while `ready`).
    pub in_valid: Signal<In, Bit>,
    /// Its image (3 x 16 bits, x low, as `pack_point`).
    pub in_q: Signal<In, Bits<48>>,
    /// Its nearest stored point's normal (3 x 16 bits).
    pub in_n: Signal<In, Bits<48>>,
    /// Its signed residual (13 bits).
    pub in_s: Signal<In, Bits<13>>,
    /// Idle: a point may come.
    pub ready: Signal<Out, Bit>,
    /// Multiplier: take `mul_a`, `mul_b`.
    pub mul_go: Signal<Out, Bit>,
    /// Multiplicand (26-bit two's complement).
    pub mul_a: Signal<Out, Bits<26>>,
    /// Multiplier (18-bit two's complement).
    pub mul_b: Signal<Out, Bits<18>>,
    /// The product of the pair issued three clocks before.
    pub mul_product: Signal<In, Bits<44>>,
    /// Add `add_data` to register `add_addr`.
    pub add: Signal<Out, Bit>,
    /// Register.
    pub add_addr: Signal<Out, Bits<6>>,
    /// Value (48-bit two's complement).
    pub add_data: Signal<Out, Bits<48>>,
    run: DFF<Bit>,
    k: DFF<Bits<6>>,
    img: DFF<Bits<48>>,
    n: DFF<Bits<48>>,
    s: DFF<Bits<13>>,
    inlier: DFF<Bit>,
    /// The cross sums and the dot product, one after another.
    acc: DFF<Bits<38>>,
    j0: DFF<Bits<18>>,
    j1: DFF<Bits<18>>,
    j2: DFF<Bits<18>>,
    j6: DFF<Bits<18>>,
    order: ROM<Bits<6>, 6>,
    q0e: Signal<Local, Bits<26>>,
    q1e: Signal<Local, Bits<26>>,
    q2e: Signal<Local, Bits<26>>,
    t0e: Signal<Local, Bits<26>>,
    t1e: Signal<Local, Bits<26>>,
    t2e: Signal<Local, Bits<26>>,
    s26: Signal<Local, Bits<26>>,
    p48: Signal<Local, Bits<48>>,
    ja26: Signal<Local, Bits<26>>,
    x0: Signal<Local, Bits<26>>,
    x1: Signal<Local, Bits<26>>,
    x2: Signal<Local, Bits<26>>,
    n0: Signal<Local, Bits<18>>,
    n1: Signal<Local, Bits<18>>,
    n2: Signal<Local, Bits<18>>,
    s18: Signal<Local, Bits<18>>,
    p38: Signal<Local, Bits<38>>,
    acc_base: Signal<Local, Bits<38>>,
    r: Signal<Local, Bits<25>>,
    jsat: Signal<Local, Bits<18>>,
    i_prod: Signal<Local, Bits<6>>,
    row: Signal<Local, Bits<3>>,
    col: Signal<Local, Bits<3>>,
    ja: Signal<Local, Bits<18>>,
    jb: Signal<Local, Bits<18>>,
}

/// The `i`-th product of a row's 35 (`i` below 28: `a`'s upper triangle in [`upper`]'s
/// order; then `b`'s): its row and column (column 7: the residual), as the ROM word
/// `row | col << 3`.
fn product_order() -> Vec<u64> {
    let mut words = vec![0u64; 35];
    for r in 0..UNKNOWNS {
        for c in r..UNKNOWNS {
            words[upper(r, c)] = (r | c << 3) as u64;
        }
        words[SUM_B as usize + r] = (r | 7 << 3) as u64;
    }
    words
}

impl Default for PolishPass {
    fn default() -> Self {
        Self::new()
    }
}

impl PolishPass {
    /// Idle.
    pub fn new() -> Self {
        let order = product_order();
        PolishPass {
            clock: Default::default(),
            reset: Default::default(),
            gated: Default::default(),
            tau2: Default::default(),
            t: Default::default(),
            in_valid: Default::default(),
            in_q: Default::default(),
            in_n: Default::default(),
            in_s: Default::default(),
            ready: Default::default(),
            mul_go: Default::default(),
            mul_a: Default::default(),
            mul_b: Default::default(),
            mul_product: Default::default(),
            add: Default::default(),
            add_addr: Default::default(),
            add_data: Default::default(),
            run: Default::default(),
            k: Default::default(),
            img: Default::default(),
            n: Default::default(),
            s: Default::default(),
            inlier: Default::default(),
            acc: Default::default(),
            j0: Default::default(),
            j1: Default::default(),
            j2: Default::default(),
            j6: Default::default(),
            order: ROM::new(
                order.iter().enumerate().map(|(i, &w)| (Bits::<6>::from(i as u64), Bits::<6>::from(w))).collect(),
            ),
            q0e: Default::default(),
            q1e: Default::default(),
            q2e: Default::default(),
            t0e: Default::default(),
            t1e: Default::default(),
            t2e: Default::default(),
            s26: Default::default(),
            p48: Default::default(),
            ja26: Default::default(),
            x0: Default::default(),
            x1: Default::default(),
            x2: Default::default(),
            n0: Default::default(),
            n1: Default::default(),
            n2: Default::default(),
            s18: Default::default(),
            p38: Default::default(),
            acc_base: Default::default(),
            r: Default::default(),
            jsat: Default::default(),
            i_prod: Default::default(),
            row: Default::default(),
            col: Default::default(),
            ja: Default::default(),
            jb: Default::default(),
        }
    }
}

// Literals in the kernel (`#[hdl_gen]` takes no paths): the registers the pass adds to.
const _: () = assert!(SUM_B == 28 && SUM_R2 == 45 && FOUND == 46 && INLIERS == 47);
const _: () = assert!(crate::polish::JACOBIAN_FRAC == 14 && crate::surface::NORMAL_FRAC == 14);
const _: () = assert!(crate::format::COORD_FRAC == 13 && crate::format::POSE_TRANSLATION_FRAC == 13);

impl Logic for PolishPass {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, run, k, img, n, s, inlier, acc, j0, j1, j2, j6);
        self.ready.next = !self.run.q.val();
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
        // The row products: the ROM's row and column of product k - 14.
        self.i_prod.next = self.k.q.val() - 14;
        self.order.address.next = self.i_prod.val();
        self.row.next = self.order.data.val().get_bits::<3>(0);
        self.col.next = self.order.data.val().get_bits::<3>(3);
        self.ja.next = self.j0.q.val();
        if self.row.val() == 1 {
            self.ja.next = self.j1.q.val();
        }
        if self.row.val() == 2 {
            self.ja.next = self.j2.q.val();
        }
        if self.row.val() == 3 {
            self.ja.next = self.n0.val();
        }
        if self.row.val() == 4 {
            self.ja.next = self.n1.val();
        }
        if self.row.val() == 5 {
            self.ja.next = self.n2.val();
        }
        if self.row.val() == 6 {
            self.ja.next = self.j6.q.val();
        }
        self.jb.next = self.j0.q.val();
        if self.col.val() == 1 {
            self.jb.next = self.j1.q.val();
        }
        if self.col.val() == 2 {
            self.jb.next = self.j2.q.val();
        }
        if self.col.val() == 3 {
            self.jb.next = self.n0.val();
        }
        if self.col.val() == 4 {
            self.jb.next = self.n1.val();
        }
        if self.col.val() == 5 {
            self.jb.next = self.n2.val();
        }
        if self.col.val() == 6 {
            self.jb.next = self.j6.q.val();
        }
        if self.col.val() == 7 {
            self.jb.next = self.s18.val();
        }
        self.ja26.next = bit_cast::<26, 18>(self.ja.val());
        if self.ja.val().get_bit(17) {
            self.ja26.next = bit_cast::<26, 18>(self.ja.val()) | !bits::<26>(0x3ffff);
        }

        self.mul_go.next = false;
        self.mul_a.next = self.x0.val();
        self.mul_b.next = self.n0.val();
        self.add.next = false;
        self.add_addr.next = 0.into();
        self.add_data.next = self.p48.val();

        if !self.run.q.val() {
            if self.in_valid.val() {
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
            if (self.k.q.val() >= 14) && (self.k.q.val() < 49) {
                self.mul_go.next = true;
                self.mul_a.next = self.ja26.val();
                self.mul_b.next = self.jb.val();
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
            if self.k.q.val() == 13 {
                self.j6.d.next = self.jsat.val();
            }
            if self.k.q.val() == 15 {
                self.add.next = true;
                self.add_addr.next = 47.into();
                self.add_data.next = 1.into();
            }
            if (self.k.q.val() >= 17) && (self.k.q.val() < 52) {
                self.add.next = true;
                self.add_addr.next = self.k.q.val() - 17;
            }
            if self.k.q.val() == 51 {
                self.run.d.next = false;
            }
        }
        if self.reset.val() {
            self.run.d.next = false;
        }
    }
}
