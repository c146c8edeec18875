//! `SurfaceResidual`: the residual stage (docs/pipeline.md, "The surface residual"), port
//! for port and clock for clock the reference [`crate::surface::surface_residual::SurfaceResidualModel`]:
//! each result of the neighbour pipeline gets the surface residual of
//! [`crate::surface::residual`], and the residuals are summed into the particle cost.
//!
//! No DSP48A1 (the board uses all 58): the three products `n_k (q_k - p_k)` are 30 gated
//! rows (3 axes x 10 magnitude bits of the differences, each row the normal sign-adjusted by
//! its difference's sign) summed by a registered adder tree, one carry chain a stage; the
//! square of the rounded projection is a block-RAM table (`y^2 >> 2`, [`SquareTable`]).
//!
//! Stages (edge 1 takes the inputs; every stage register advances every clock):
//! 1. A: the stores' synchronous read at `in_index` (read-first), the result registered;
//! 2. B: differences `q - p` both ways (17 bits), their 10-bit magnitudes and signs, the
//!    normals negated where the difference is negative (17 bits), the cap flag (`in_dist`
//!    at or above `CAP_D2`, or a magnitude of `2^10` or more);
//! 3. C: the 30 rows, summed in pairs (15 sums; the 16th is the rounding constant `2^13`);
//! 4. to 7. D, E, F, G: 16 -> 8 -> 4 -> 2 -> 1: `t = a + 2^13` (28 bits);
//! 8. H: `s = t >> 14`, `|s|` (14 bits), `|s| >= 2^10` into the cap flag; the table's read at
//!    `|s| mod 2^10`;
//! 9. I: the residual `CAP_D2` or `(table << 2) | (|s| & 1)`; the accumulator (split in two
//!    24-bit halves with a pending carry) adds it if valid, and on `cost_valid` hands its
//!    sum to a snapshot and restarts;
//! 10. out: the ports; `cost` = the snapshot's halves joined (on `cost_valid`).
//!
//! Beside the residual, for the polish's pass: the signed `s` (from H), the scan point `q`
//! and the stored normal `n` (from A and B, carried along), each with its result.

use crate::common::rtl::signed_bit_cast_safe;
use crate::search::grid::CAP_D2;
use crate::search::neighbour_lane_rtl::BankRam;
use rust_hdl::prelude::*;

/// A table of squares: word `y` (10 bits) holds `y^2 >> 2` (18 bits; the square's two low
/// bits are `0 | (y & 1)`), read through one registered port: 1024 x 18 bits, one RAMB16.
#[derive(LogicBlock, Default)]
pub struct SquareTable {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// The address.
    pub addr: Signal<In, Bits<10>>,
    /// `addr^2 >> 2` at the last edge.
    pub data: Signal<Out, Bits<18>>,
}

impl Logic for SquareTable {
    fn update(&mut self) {
        if self.clock.pos_edge() {
            let y = self.addr.val().to_u64();
            self.data.next = ((y * y) >> 2).into();
        }
    }

    fn connect(&mut self) {
        self.data.connect();
    }

    fn hdl(&self) -> Verilog {
        Verilog::Custom(
            "\
reg [17:0] mem[1023:0];
integer i;
/* verilator lint_off UNUSEDSIGNAL */
reg [19:0] sq;
/* verilator lint_on UNUSEDSIGNAL */
initial begin
   for (i = 0; i < 1024; i = i + 1) begin
      sq = i[9:0] * i[9:0];
      mem[i] = sq[19:2];
   end
end
always @(posedge clock) begin
   data <= mem[addr];
end
"
            .into(),
        )
    }
}

/// The residual stage: two 4096 x 48 stores, one result a clock, latency
/// [`crate::surface::surface_residual::SURFACE_LATENCY`].
#[derive(LogicBlock)]
pub struct SurfaceResidual {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Write the point store.
    pub point_we: Signal<In, Bit>,
    /// Point store write address.
    pub point_waddr: Signal<In, Bits<12>>,
    /// A stored model point (x | y | z).
    pub point_wdata: Signal<In, Bits<48>>,
    /// Write the normal store.
    pub normal_we: Signal<In, Bit>,
    /// Normal store write address.
    pub normal_waddr: Signal<In, Bits<12>>,
    /// A normal (x | y | z, Q1.14).
    pub normal_wdata: Signal<In, Bits<48>>,
    /// A result is presented.
    pub in_valid: Signal<In, Bit>,
    /// Its nearest stored index.
    pub in_index: Signal<In, Bits<12>>,
    /// Its squared distance.
    pub in_dist: Signal<In, Bits<34>>,
    /// The transformed scan point.
    pub in_point: Signal<In, Bits<48>>,
    /// End of a particle.
    pub in_cost_valid: Signal<In, Bit>,
    /// The result, `SURFACE_LATENCY` edges later.
    pub nn_valid: Signal<Out, Bit>,
    /// Its index.
    pub nn_index: Signal<Out, Bits<12>>,
    /// Its squared distance.
    pub nn_dist: Signal<Out, Bits<34>>,
    /// Its residual.
    pub nn_resid: Signal<Out, Bits<21>>,
    /// Its signed residual `s` before squaring (14 bits,
    /// [`crate::surface::surface_residual::block_signed_residual`]), for the polish's pass.
    pub nn_s: Signal<Out, Bits<14>>,
    /// Its transformed scan point `q` (`in_point` delayed), for the polish's pass.
    pub nn_point: Signal<Out, Bits<48>>,
    /// The normal stored at its index, for the polish's pass.
    pub nn_normal: Signal<Out, Bits<48>>,
    /// `in_cost_valid`, `SURFACE_LATENCY` edges later.
    pub cost_valid: Signal<Out, Bit>,
    /// The sum of the residuals since the previous `cost_valid` (48 bits, wrapping).
    pub cost: Signal<Out, Bits<48>>,
    cap_d2: Constant<Bits<21>>,
    one21: Constant<Bits<21>>,
    round: Constant<Bits<28>>,
    sx_mask: Constant<Bits<28>>,
    shift: [Constant<Bits<4>>; 10],
    pstore: BankRam,
    nstore: BankRam,
    squares: SquareTable,
    // Stages A (index 0, edge 1) to I (index 8, edge 9).
    pv: [DFF<Bit>; 9],
    pidx: [DFF<Bits<12>>; 9],
    pdist: [DFF<Bits<34>>; 9],
    pcv: [DFF<Bit>; 9],
    // Stages B (index 0) to H (index 6).
    pcap: [DFF<Bit>; 7],
    // The scan point and the normal, stages B (index 0) to I (index 7).
    pq: [DFF<Bits<48>>; 8],
    pn: [DFF<Bits<48>>; 8],
    a_q: DFF<Bits<48>>,
    b_mag: [DFF<Bits<10>>; 3],
    b_m: [DFF<Bits<17>>; 3],
    c_sum: [DFF<Bits<28>>; 16],
    d_sum: [DFF<Bits<28>>; 8],
    e_sum: [DFF<Bits<28>>; 4],
    f_sum: [DFF<Bits<28>>; 2],
    g_t: DFF<Bits<28>>,
    h_lsb: DFF<Bit>,
    h_s: DFF<Bits<14>>,
    i_r: DFF<Bits<21>>,
    i_s: DFF<Bits<14>>,
    acc_lo: DFF<Bits<24>>,
    acc_hi: DFF<Bits<24>>,
    acc_c: DFF<Bit>,
    snap_lo: DFF<Bits<24>>,
    snap_hi: DFF<Bits<24>>,
    snap_c: DFF<Bit>,
    o_v: DFF<Bit>,
    o_idx: DFF<Bits<12>>,
    o_dist: DFF<Bits<34>>,
    o_r: DFF<Bits<21>>,
    o_s: DFF<Bits<14>>,
    o_q: DFF<Bits<48>>,
    o_n: DFF<Bits<48>>,
    o_cv: DFF<Bit>,
    o_cost: DFF<Bits<48>>,
    qq: [Signal<Local, Signed<16>>; 3],
    pp: [Signal<Local, Signed<16>>; 3],
    nn: [Signal<Local, Signed<16>>; 3],
    dp: [Signal<Local, Signed<17>>; 3],
    dn: [Signal<Local, Signed<17>>; 3],
    nx: [Signal<Local, Signed<17>>; 3],
    udp: [Signal<Local, Bits<17>>; 3],
    udn: [Signal<Local, Bits<17>>; 3],
    nb: [Signal<Local, Bits<17>>; 3],
    mag17: [Signal<Local, Bits<17>>; 3],
    far: Signal<Local, Bit>,
    ms: [Signal<Local, Bits<28>>; 3],
    row: [Signal<Local, Bits<28>>; 30],
    s14: Signal<Local, Bits<14>>,
    smag: Signal<Local, Bits<14>>,
    r: Signal<Local, Bits<21>>,
    gx: Signal<Local, Bits<21>>,
    lo25: Signal<Local, Bits<25>>,
    hi_inc: Signal<Local, Bits<24>>,
    snap_sum: Signal<Local, Bits<24>>,
}

impl Default for SurfaceResidual {
    fn default() -> Self {
        Self::new()
    }
}

impl SurfaceResidual {
    /// After reset: stores zero, nothing in flight, cost 0.
    pub fn new() -> Self {
        SurfaceResidual {
            clock: Default::default(),
            point_we: Default::default(),
            point_waddr: Default::default(),
            point_wdata: Default::default(),
            normal_we: Default::default(),
            normal_waddr: Default::default(),
            normal_wdata: Default::default(),
            in_valid: Default::default(),
            in_index: Default::default(),
            in_dist: Default::default(),
            in_point: Default::default(),
            in_cost_valid: Default::default(),
            nn_valid: Default::default(),
            nn_index: Default::default(),
            nn_dist: Default::default(),
            nn_resid: Default::default(),
            nn_s: Default::default(),
            nn_point: Default::default(),
            nn_normal: Default::default(),
            cost_valid: Default::default(),
            cost: Default::default(),
            cap_d2: Constant::new(CAP_D2.into()),
            one21: Constant::new(1u64.into()),
            round: Constant::new((1u64 << (crate::surface::NORMAL_FRAC - 1)).into()),
            sx_mask: Constant::new((((1u64 << 28) - 1) & !((1u64 << 17) - 1)).into()),
            shift: std::array::from_fn(|j| Constant::new((j as u64).into())),
            pstore: BankRam::new(0),
            nstore: BankRam::new(0),
            squares: Default::default(),
            pv: Default::default(),
            pidx: Default::default(),
            pdist: Default::default(),
            pcv: Default::default(),
            pcap: Default::default(),
            pq: Default::default(),
            pn: Default::default(),
            a_q: Default::default(),
            b_mag: Default::default(),
            b_m: Default::default(),
            c_sum: Default::default(),
            d_sum: Default::default(),
            e_sum: Default::default(),
            f_sum: Default::default(),
            g_t: Default::default(),
            h_lsb: Default::default(),
            h_s: Default::default(),
            i_r: Default::default(),
            i_s: Default::default(),
            acc_lo: Default::default(),
            acc_hi: Default::default(),
            acc_c: Default::default(),
            snap_lo: Default::default(),
            snap_hi: Default::default(),
            snap_c: Default::default(),
            o_v: Default::default(),
            o_idx: Default::default(),
            o_dist: Default::default(),
            o_r: Default::default(),
            o_s: Default::default(),
            o_q: Default::default(),
            o_n: Default::default(),
            o_cv: Default::default(),
            o_cost: Default::default(),
            qq: Default::default(),
            pp: Default::default(),
            nn: Default::default(),
            dp: Default::default(),
            dn: Default::default(),
            nx: Default::default(),
            udp: Default::default(),
            udn: Default::default(),
            nb: Default::default(),
            mag17: Default::default(),
            far: Default::default(),
            ms: Default::default(),
            row: std::array::from_fn(|_| Default::default()),
            s14: Default::default(),
            smag: Default::default(),
            r: Default::default(),
            gx: Default::default(),
            lo25: Default::default(),
            hi_inc: Default::default(),
            snap_sum: Default::default(),
        }
    }
}

impl Logic for SurfaceResidual {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self, clock, a_q, g_t, h_lsb, h_s, i_r, i_s, acc_lo, acc_hi, acc_c, snap_lo, snap_hi, snap_c, o_v, o_idx,
            o_dist, o_r, o_s, o_q, o_n, o_cv, o_cost
        );
        for s in 0..9 {
            self.pv[s].clock.next = self.clock.val();
            self.pidx[s].clock.next = self.clock.val();
            self.pdist[s].clock.next = self.clock.val();
            self.pcv[s].clock.next = self.clock.val();
        }
        for s in 0..7 {
            self.pcap[s].clock.next = self.clock.val();
        }
        for s in 0..8 {
            self.pq[s].clock.next = self.clock.val();
            self.pn[s].clock.next = self.clock.val();
        }
        for k in 0..3 {
            self.b_mag[k].clock.next = self.clock.val();
            self.b_m[k].clock.next = self.clock.val();
        }
        for j in 0..16 {
            self.c_sum[j].clock.next = self.clock.val();
        }
        for j in 0..8 {
            self.d_sum[j].clock.next = self.clock.val();
        }
        for j in 0..4 {
            self.e_sum[j].clock.next = self.clock.val();
        }
        for j in 0..2 {
            self.f_sum[j].clock.next = self.clock.val();
        }
        self.pstore.clock.next = self.clock.val();
        self.nstore.clock.next = self.clock.val();
        self.squares.clock.next = self.clock.val();
        // Outputs.
        self.nn_valid.next = self.o_v.q.val();
        self.nn_index.next = self.o_idx.q.val();
        self.nn_dist.next = self.o_dist.q.val();
        self.nn_resid.next = self.o_r.q.val();
        self.nn_s.next = self.o_s.q.val();
        self.nn_point.next = self.o_q.q.val();
        self.nn_normal.next = self.o_n.q.val();
        self.cost_valid.next = self.o_cv.q.val();
        self.cost.next = self.o_cost.q.val();
        // The control fields, stage to stage.
        self.pv[0].d.next = self.in_valid.val();
        self.pidx[0].d.next = self.in_index.val();
        self.pdist[0].d.next = self.in_dist.val();
        self.pcv[0].d.next = self.in_cost_valid.val();
        for s in 1..9 {
            self.pv[s].d.next = self.pv[s - 1].q.val();
            self.pidx[s].d.next = self.pidx[s - 1].q.val();
            self.pdist[s].d.next = self.pdist[s - 1].q.val();
            self.pcv[s].d.next = self.pcv[s - 1].q.val();
        }
        for s in 1..6 {
            self.pcap[s].d.next = self.pcap[s - 1].q.val();
        }
        // The scan point and the normal, for the polish's pass.
        self.pq[0].d.next = self.a_q.q.val();
        self.pn[0].d.next = self.nstore.read_data.val();
        for s in 1..8 {
            self.pq[s].d.next = self.pq[s - 1].q.val();
            self.pn[s].d.next = self.pn[s - 1].q.val();
        }
        // A: the stores (read-first) and the scan point.
        self.pstore.read_address.next = self.in_index.val();
        self.pstore.write_enable.next = self.point_we.val();
        self.pstore.write_address.next = self.point_waddr.val();
        self.pstore.write_data.next = self.point_wdata.val();
        self.nstore.read_address.next = self.in_index.val();
        self.nstore.write_enable.next = self.normal_we.val();
        self.nstore.write_address.next = self.normal_waddr.val();
        self.nstore.write_data.next = self.normal_wdata.val();
        self.a_q.d.next = self.in_point.val();
        // B: differences both ways, magnitude and sign; the normal negated where negative.
        for k in 0..3 {
            self.qq[k].next = signed_cast(self.a_q.q.val().get_bits::<16>(16 * k));
            self.pp[k].next = signed_cast(self.pstore.read_data.val().get_bits::<16>(16 * k));
            self.nn[k].next = signed_cast(self.nstore.read_data.val().get_bits::<16>(16 * k));
            self.dp[k].next = signed_bit_cast_safe(self.qq[k].val()) - signed_bit_cast_safe(self.pp[k].val());
            self.dn[k].next = signed_bit_cast_safe(self.pp[k].val()) - signed_bit_cast_safe(self.qq[k].val());
            self.nx[k].next = signed_bit_cast_safe(self.nn[k].val());
            self.udp[k].next = unsigned_cast(self.dp[k].val());
            self.udn[k].next = unsigned_cast(self.dn[k].val());
            self.nb[k].next = unsigned_cast(self.nx[k].val());
            self.mag17[k].next = self.udp[k].val();
            self.b_m[k].d.next = self.nb[k].val();
            if self.udp[k].val().get_bit(16) {
                self.mag17[k].next = self.udn[k].val();
                self.b_m[k].d.next = !self.nb[k].val() + 1;
            }
            self.b_mag[k].d.next = self.mag17[k].val().get_bits::<10>(0);
        }
        self.far.next = self.mag17[0].val().get_bits::<7>(10).any()
            || self.mag17[1].val().get_bits::<7>(10).any()
            || self.mag17[2].val().get_bits::<7>(10).any();
        self.pcap[0].d.next = self.pdist[0].q.val().get_bits::<14>(20).any() || self.far.val();
        // C: the rows (the sign-adjusted normal, sign-extended to 28 bits, shifted by the
        // magnitude bit's weight), summed in pairs.
        self.ms[0].next = bit_cast::<28, 17>(self.b_m[0].q.val());
        if self.b_m[0].q.val().get_bit(16) {
            self.ms[0].next = bit_cast::<28, 17>(self.b_m[0].q.val()) | self.sx_mask.val();
        }
        self.ms[1].next = bit_cast::<28, 17>(self.b_m[1].q.val());
        if self.b_m[1].q.val().get_bit(16) {
            self.ms[1].next = bit_cast::<28, 17>(self.b_m[1].q.val()) | self.sx_mask.val();
        }
        self.ms[2].next = bit_cast::<28, 17>(self.b_m[2].q.val());
        if self.b_m[2].q.val().get_bit(16) {
            self.ms[2].next = bit_cast::<28, 17>(self.b_m[2].q.val()) | self.sx_mask.val();
        }
        for k in 0..3 {
            for j in 0..10 {
                self.row[10 * k + j].next = 0.into();
                if self.b_mag[k].q.val().get_bit(j) {
                    self.row[10 * k + j].next = self.ms[k].val() << self.shift[j].val();
                }
            }
        }
        for j in 0..15 {
            self.c_sum[j].d.next = self.row[2 * j].val() + self.row[2 * j + 1].val();
        }
        self.c_sum[15].d.next = self.round.val();
        // D to G: the tree.
        for j in 0..8 {
            self.d_sum[j].d.next = self.c_sum[2 * j].q.val() + self.c_sum[2 * j + 1].q.val();
        }
        for j in 0..4 {
            self.e_sum[j].d.next = self.d_sum[2 * j].q.val() + self.d_sum[2 * j + 1].q.val();
        }
        for j in 0..2 {
            self.f_sum[j].d.next = self.e_sum[2 * j].q.val() + self.e_sum[2 * j + 1].q.val();
        }
        self.g_t.d.next = self.f_sum[0].q.val() + self.f_sum[1].q.val();
        // H: `s = t >> 14` (arithmetic), its magnitude, the table's read.
        self.s14.next = self.g_t.q.val().get_bits::<14>(14);
        self.smag.next = self.s14.val();
        if self.s14.val().get_bit(13) {
            self.smag.next = !self.s14.val() + 1;
        }
        self.squares.addr.next = self.smag.val().get_bits::<10>(0);
        self.h_lsb.d.next = self.smag.val().get_bit(0);
        self.h_s.d.next = self.s14.val();
        self.pcap[6].d.next = self.pcap[5].q.val() || self.smag.val().get_bits::<4>(10).any();
        // I: the residual; the accumulator.
        self.r.next = (bit_cast::<21, 18>(self.squares.data.val()) << 2) | self.one21.val();
        if !self.h_lsb.q.val() {
            self.r.next = bit_cast::<21, 18>(self.squares.data.val()) << 2;
        }
        if self.pcap[6].q.val() {
            self.r.next = self.cap_d2.val();
        }
        self.i_r.d.next = self.r.val();
        self.i_s.d.next = self.h_s.q.val();
        self.gx.next = 0.into();
        if self.pv[7].q.val() {
            self.gx.next = self.r.val();
        }
        self.lo25.next = bit_cast::<25, 24>(self.acc_lo.q.val()) + bit_cast::<25, 21>(self.gx.val());
        self.hi_inc.next = self.acc_hi.q.val();
        if self.acc_c.q.val() {
            self.hi_inc.next = self.acc_hi.q.val() + 1;
        }
        if self.pcv[7].q.val() {
            self.snap_lo.d.next = self.lo25.val().get_bits::<24>(0);
            self.snap_c.d.next = self.lo25.val().get_bit(24);
            self.snap_hi.d.next = self.hi_inc.val();
            self.acc_lo.d.next = 0.into();
            self.acc_c.d.next = false;
            self.acc_hi.d.next = 0.into();
        } else {
            self.acc_lo.d.next = self.lo25.val().get_bits::<24>(0);
            self.acc_c.d.next = self.lo25.val().get_bit(24);
            self.acc_hi.d.next = self.hi_inc.val();
        }
        // Out.
        self.o_v.d.next = self.pv[8].q.val();
        self.o_idx.d.next = self.pidx[8].q.val();
        self.o_dist.d.next = self.pdist[8].q.val();
        self.o_r.d.next = self.i_r.q.val();
        self.o_s.d.next = self.i_s.q.val();
        self.o_q.d.next = self.pq[7].q.val();
        self.o_n.d.next = self.pn[7].q.val();
        self.o_cv.d.next = self.pcv[8].q.val();
        self.snap_sum.next = self.snap_hi.q.val();
        if self.snap_c.q.val() {
            self.snap_sum.next = self.snap_hi.q.val() + 1;
        }
        if self.pcv[8].q.val() {
            self.o_cost.d.next =
                (bit_cast::<48, 24>(self.snap_sum.val()) << 24) | bit_cast::<48, 24>(self.snap_lo.q.val());
        }
    }
}
