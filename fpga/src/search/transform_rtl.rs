//! `Transform`: the pose register and the three-edge transform pipeline of a scan point
//! (docs/pipeline.md, the neighbour pipeline's scan input): edge `k` registers the 9 products
//! `m_ij * p_j` (9 [`Mul18`]), edge `k+1` registers `sum_j + (t_i << 15) + 2^14`, and
//! `result` (combinational from that register) is `>> 15` saturated to 16 bits, taken at
//! edge `k+2` (into the neighbour pipeline's point queue).

use crate::common::rtl::signed_bit_cast_safe;
use crate::search::mul18_rtl::Mul18;
use rust_hdl::prelude::*;

/// Pose register + transform pipeline.
#[derive(LogicBlock, Default)]
pub struct Transform {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Latch `pose` at this edge.
    pub load: Signal<In, Bit>,
    /// `m[0..9]`, `t[0..3]`, 18-bit two's complement each.
    pub pose: Signal<In, Bits<216>>,
    /// A point enters the pipeline at this edge.
    pub take: Signal<In, Bit>,
    /// The point (x | y | z, Q3.13).
    pub point: Signal<In, Bits<48>>,
    /// The products register holds a point.
    pub t1_valid: Signal<Out, Bit>,
    /// The sums register holds a point; `result` is valid.
    pub t2_valid: Signal<Out, Bit>,
    /// The transformed, rounded, saturated point (x | y | z).
    pub result: Signal<Out, Bits<48>>,
    m: [DFF<Bits<18>>; 9],
    t: [DFF<Bits<18>>; 3],
    mul: [Mul18; 9],
    v1: DFF<Bit>,
    v2: DFF<Bit>,
    acc: [DFF<Bits<21>>; 3],
    // Combinational intermediates.
    pw: [Signal<Local, Bits<36>>; 9],
    pn: [Signal<Local, Signed<34>>; 9],
    ps: [Signal<Local, Signed<36>>; 9],
    tsx: [Signal<Local, Signed<36>>; 3],
    tc: [Signal<Local, Bits<36>>; 3],
    sum: [Signal<Local, Bits<36>>; 3],
    sat: [Signal<Local, Bits<16>>; 3],
}

impl Logic for Transform {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, v1, v2);
        for k in 0..9 {
            self.m[k].clock.next = self.clock.val();
            self.m[k].d.next = self.m[k].q.val();
            self.mul[k].clock.next = self.clock.val();
        }
        for r in 0..3 {
            self.t[r].clock.next = self.clock.val();
            self.t[r].d.next = self.t[r].q.val();
            self.acc[r].clock.next = self.clock.val();
        }
        // The pose register.
        if self.load.val() {
            for k in 0..9 {
                self.m[k].d.next = self.pose.val().get_bits::<18>(18 * k);
            }
            for r in 0..3 {
                self.t[r].d.next = self.pose.val().get_bits::<18>(162 + 18 * r);
            }
        }
        // Edge k: the nine products (registered inside the multipliers).
        for r in 0..3 {
            for c in 0..3 {
                self.mul[3 * r + c].a.next = signed_cast(self.m[3 * r + c].q.val());
                self.mul[3 * r + c].b.next = signed_bit_cast_safe(signed_cast(self.point.val().get_bits::<16>(16 * c)));
            }
        }
        self.v1.d.next = self.take.val();
        // Edge k+1: sums + (t << 15) + 2^14, 36-bit two's complement (never overflows:
        // |sum| <= 3 * 2^32, |t << 15| <= 2^32); only bits 35..15 (the arithmetic `>> 15`)
        // are registered. A product fits 34 bits (|m p| <= 2^32): its bits 33..0 are
        // sign-extended (leaving the multipliers' top bits unused keeps Yosys 0.23 from
        // packing a 34-bit DSP48A1 product into a 36-bit register wrongly).
        for k in 0..9 {
            self.pw[k].next = unsigned_cast(self.mul[k].p.val());
        }
        // (`bit_cast` is evaluated when the Verilog is generated: no loop index inside.)
        self.pn[0].next = signed_cast(bit_cast::<34, 36>(self.pw[0].val()));
        self.pn[1].next = signed_cast(bit_cast::<34, 36>(self.pw[1].val()));
        self.pn[2].next = signed_cast(bit_cast::<34, 36>(self.pw[2].val()));
        self.pn[3].next = signed_cast(bit_cast::<34, 36>(self.pw[3].val()));
        self.pn[4].next = signed_cast(bit_cast::<34, 36>(self.pw[4].val()));
        self.pn[5].next = signed_cast(bit_cast::<34, 36>(self.pw[5].val()));
        self.pn[6].next = signed_cast(bit_cast::<34, 36>(self.pw[6].val()));
        self.pn[7].next = signed_cast(bit_cast::<34, 36>(self.pw[7].val()));
        self.pn[8].next = signed_cast(bit_cast::<34, 36>(self.pw[8].val()));
        for k in 0..9 {
            self.ps[k].next = signed_bit_cast_safe(self.pn[k].val());
        }
        for r in 0..3 {
            self.tsx[r].next = signed_bit_cast_safe(signed_cast(self.t[r].q.val()));
            self.tc[r].next = (unsigned_cast(self.tsx[r].val()) << 15) | 16384;
            self.sum[r].next = unsigned_cast(self.ps[3 * r].val())
                + unsigned_cast(self.ps[3 * r + 1].val())
                + unsigned_cast(self.ps[3 * r + 2].val())
                + self.tc[r].val();
        }
        self.acc[0].d.next = bit_cast::<21, 36>(self.sum[0].val() >> 15);
        self.acc[1].d.next = bit_cast::<21, 36>(self.sum[1].val() >> 15);
        self.acc[2].d.next = bit_cast::<21, 36>(self.sum[2].val() >> 15);
        self.v2.d.next = self.v1.q.val();
        // Result: the 21-bit `>> 15` fits 16 bits iff its bits 20..15 are all zeros or all
        // ones; else saturate by the sign.
        for r in 0..3 {
            if (self.acc[r].q.val().get_bits::<6>(15) == 0) || (self.acc[r].q.val().get_bits::<6>(15) == 63) {
                self.sat[r].next = self.acc[r].q.val().get_bits::<16>(0);
            } else if self.acc[r].q.val().get_bit(20) {
                self.sat[r].next = 32768.into();
            } else {
                self.sat[r].next = 32767.into();
            }
        }
        self.result.next = bit_cast::<48, 16>(self.sat[0].val())
            | (bit_cast::<48, 16>(self.sat[1].val()) << 16)
            | (bit_cast::<48, 16>(self.sat[2].val()) << 32);
        self.t1_valid.next = self.v1.q.val();
        self.t2_valid.next = self.v2.q.val();
    }
}
