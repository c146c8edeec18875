//! `PolishPass`: one found point of a polish pass ([`crate::polish::PassSums::add_point`]
//! with [`crate::polish::jacobian`]), in two stages that overlap from one point to the next.
//!
//! **The front** forms the residual's square and the Jacobian row on a borrowed pipelined
//! multiplier (the sequencer's `PipeMul`, idle after the filter: `mul_*`, a product three
//! clocks after the clock that issues it) and adds the statistics into `PolishProgram`'s
//! register file (`add*`): `s^2` to `SUM_R2`, 1 to `FOUND`, and for an inlier (`gated` and
//! `s^2 <= tau2`) 1 to `INLIERS`. Schedule, clock `k` after the point is taken: `s s`
//! issued at 0; the nine products of `x = q - t` and `n` at 1 to 9; `s^2` back and added at
//! 3, `found` at 4 (an outlier ends there), `inliers` at 5; the cross and dot products
//! combined at 4 to 12 in one accumulator, each rounded and saturated into its Jacobian
//! entry as the next starts (at 6, 8, 10 and 13). At 13 an inlier's row `J` and `s` pass to
//! the product stage (waiting there while it is busy). A point takes 14 clocks if an inlier,
//! 5 if not, and `ready` the clock after.
//!
//! **The product stage** forms the row's 28 products `J_r J_c` (`a`) and 7 products `J_r s`
//! (`b`) on [`PRODUCT_MULS`] DSP48A1 multipliers ([`Mul18`]), product `i` (in the register
//! file's order, [`upper`] then `b`) on multiplier `i mod 3` at slot `i / 3` (12 slots),
//! and adds each into its own 48-bit accumulator: a 16-word bank per multiplier, read at
//! the slot and written with the sum the clock after. The sums are exact integers, so
//! accumulating them apart and adding them into the register file once gives the register
//! file's sums bit for bit.
//!
//! **The flush** (`flush`, once the pass's last point is in): once both stages are empty,
//! the 35 accumulators are added into registers 0 to 34, one a clock, and zeroed (37
//! clocks); `idle` rises when it is over. A reset zeroes the banks the same way, without the
//! adds. Tests: `fpga/tests/polish_pass.rs` and `sim/tests/polish_pass.rs`, against
//! `add_point` on random points.

use crate::polish::programs::{FOUND, INLIERS, SUM_B, SUM_R2};
use crate::polish::{upper, UNKNOWNS};
use crate::search::mul18_rtl::Mul18;
use rust_hdl::prelude::*;

/// The product stage's multipliers (DSP48A1s).
pub const PRODUCT_MULS: usize = 3;
/// Products of an inlier's row: `a`'s upper triangle and `b`.
pub const ROW_PRODUCTS: usize = SUM_B as usize + UNKNOWNS;
/// The product stage's slots: the row's products over the multipliers.
pub const PRODUCT_SLOTS: usize = ROW_PRODUCTS.div_ceil(PRODUCT_MULS);
/// Clocks of the flush: a read and an add for each accumulator, one behind the other.
pub const FLUSH_CLOCKS: u64 = ROW_PRODUCTS as u64 + 2;

/// The pass's per-point datapath.
#[derive(LogicBlock)]
pub struct PolishPass {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Synchronous reset: idle, and the accumulators zeroed (`idle` low until they are).
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
    /// The front is free: a point may come.
    pub ready: Signal<Out, Bit>,
    /// The pass's points are all in: add the accumulators into the register file once both
    /// stages are empty (a pulse).
    pub flush: Signal<In, Bit>,
    /// Nothing in flight, no flush pending or running: the register file holds every sum.
    pub idle: Signal<Out, Bit>,
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
    k: DFF<Bits<4>>,
    img: DFF<Bits<48>>,
    n: DFF<Bits<48>>,
    s: DFF<Bits<13>>,
    inlier: DFF<Bit>,
    /// The cross sums and the dot product, one after another.
    acc: DFF<Bits<38>>,
    j0: DFF<Bits<18>>,
    j1: DFF<Bits<18>>,
    j2: DFF<Bits<18>>,
    /// The product stage: its row (`J` 0 to 6, then `s`), busy, its slot.
    row_j: [DFF<Bits<18>>; 8],
    pbusy: DFF<Bit>,
    pk: DFF<Bits<4>>,
    /// Per multiplier: a product of the slot `pslot` comes out of it (the sum is written).
    pv: [DFF<Bit>; 3],
    pslot: DFF<Bits<4>>,
    /// Per multiplier: `row | col << 3 | valid << 6` of its product at each slot.
    order: [ROM<Bits<7>, 4>; 3],
    mul: [Mul18; 3],
    bank: [RAM<Bits<48>, 4>; 3],
    /// The flush: asked for; reading (`fslot`, `fmul`, register `freg`); adding the word
    /// read (`fd*`); without the adds (after a reset).
    fpend: DFF<Bit>,
    fl: DFF<Bit>,
    fslot: DFF<Bits<4>>,
    fmul: DFF<Bits<2>>,
    freg: DFF<Bits<6>>,
    fd: DFF<Bit>,
    fdslot: DFF<Bits<4>>,
    fdmul: DFF<Bits<2>>,
    fdreg: DFF<Bits<6>>,
    fquiet: DFF<Bit>,
    q0e: Signal<Local, Bits<26>>,
    q1e: Signal<Local, Bits<26>>,
    q2e: Signal<Local, Bits<26>>,
    t0e: Signal<Local, Bits<26>>,
    t1e: Signal<Local, Bits<26>>,
    t2e: Signal<Local, Bits<26>>,
    s26: Signal<Local, Bits<26>>,
    p48: Signal<Local, Bits<48>>,
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
    word: [Signal<Local, Bits<7>>; 3],
    row: [Signal<Local, Bits<3>>; 3],
    col: [Signal<Local, Bits<3>>; 3],
    ja: [Signal<Local, Bits<18>>; 3],
    jb: [Signal<Local, Bits<18>>; 3],
    pw: [Signal<Local, Bits<36>>; 3],
    pe: [Signal<Local, Bits<48>>; 3],
    fword: Signal<Local, Bits<48>>,
}

/// Multiplier `m`'s ROM: at slot `j`, product `i = 3 j + m` of a row (`i` below 28: `a`'s
/// upper triangle in [`upper`]'s order; then `b`'s) as `row | col << 3 | 1 << 6` (column
/// 7: the residual); 0 past the row's last product.
fn product_order(m: usize) -> Vec<u64> {
    let mut words = vec![0u64; ROW_PRODUCTS];
    for r in 0..UNKNOWNS {
        for c in r..UNKNOWNS {
            words[upper(r, c)] = (r | c << 3 | 1 << 6) as u64;
        }
        words[SUM_B as usize + r] = (r | 7 << 3 | 1 << 6) as u64;
    }
    (0..PRODUCT_SLOTS).map(|j| words.get(PRODUCT_MULS * j + m).copied().unwrap_or(0)).collect()
}

fn order_rom(m: usize) -> ROM<Bits<7>, 4> {
    ROM::new(
        product_order(m).iter().enumerate().map(|(j, &w)| (Bits::<4>::from(j as u64), Bits::<7>::from(w))).collect(),
    )
}

impl Default for PolishPass {
    fn default() -> Self {
        Self::new()
    }
}

impl PolishPass {
    /// Idle.
    pub fn new() -> Self {
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
            flush: Default::default(),
            idle: Default::default(),
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
            row_j: Default::default(),
            pbusy: Default::default(),
            pk: Default::default(),
            pv: Default::default(),
            pslot: Default::default(),
            order: [order_rom(0), order_rom(1), order_rom(2)],
            mul: Default::default(),
            bank: Default::default(),
            fpend: Default::default(),
            fl: Default::default(),
            fslot: Default::default(),
            fmul: Default::default(),
            freg: Default::default(),
            fd: Default::default(),
            fdslot: Default::default(),
            fdmul: Default::default(),
            fdreg: Default::default(),
            fquiet: Default::default(),
            q0e: Default::default(),
            q1e: Default::default(),
            q2e: Default::default(),
            t0e: Default::default(),
            t1e: Default::default(),
            t2e: Default::default(),
            s26: Default::default(),
            p48: Default::default(),
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
            word: Default::default(),
            row: Default::default(),
            col: Default::default(),
            ja: Default::default(),
            jb: Default::default(),
            pw: Default::default(),
            pe: Default::default(),
            fword: Default::default(),
        }
    }
}

// Literals in the kernel (`#[hdl_gen]` takes no paths): the registers the pass adds to, the
// slots and the multipliers.
const _: () = assert!(SUM_B == 28 && SUM_R2 == 45 && FOUND == 46 && INLIERS == 47);
const _: () = assert!(PRODUCT_MULS == 3 && PRODUCT_SLOTS == 12 && ROW_PRODUCTS == 35);
// The host's deadline allows for the flush (`run_request::PASS_END_CLOCKS`).
const _: () = assert!(FLUSH_CLOCKS + PRODUCT_SLOTS as u64 + 1 + 8 < crate::protocol::run_request::PASS_END_CLOCKS);
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
