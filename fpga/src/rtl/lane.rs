//! `Lane`: one scan point's share of the sweep (docs/pipeline.md, Sweep and Reduce).
//!
//! The lane holds the transformed point `x` (written by the transform stage when `wr_en`
//! and `wr_sel` equals the lane's number), and runs the distance pipeline against the model
//! word broadcast to every lane: s1 differences (17-bit), s2 squares (3 [`Mul18`]),
//! s3 `dx^2 + dy^2` and `dz^2`, s4 the sum; the compare edge keeps the strictly smaller
//! distance and its index (from the shared valid/index delay line of the top). For Reduce
//! the minima form a shift chain: on `shift` every lane takes its upper neighbour's
//! minimum and index, so lane 0 presents the lanes in order.

use super::mul18::Mul18;
use super::signed_bit_cast_safe;
use crate::pipeline::DIST_INIT;
use rust_hdl::prelude::*;

/// One lane of the nearest-neighbour sweep.
#[derive(LogicBlock)]
pub struct Lane {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// A transformed point is written this edge (into the lane numbered `wr_sel`).
    pub wr_en: Signal<In, Bit>,
    /// The lane being written.
    pub wr_sel: Signal<In, Bits<8>>,
    /// The transformed point (x | y | z).
    pub point: Signal<In, Bits<48>>,
    /// The model word read from RAM (x | y | z), broadcast to all lanes.
    pub model: Signal<In, Bits<48>>,
    /// `model` is a swept model point (the s0 valid bit of the shared delay line).
    pub model_valid: Signal<In, Bit>,
    /// Reset the minimum to its initial value (`2^34 - 1`, or the grid pipeline's cap) and
    /// its index to 0 at this edge (has priority).
    pub init: Signal<In, Bit>,
    /// The s4 stage holds a distance (shared delay line).
    pub s4_valid: Signal<In, Bit>,
    /// The model index of the s4 stage (shared delay line).
    pub s4_index: Signal<In, Bits<12>>,
    /// Take `shift_min`/`shift_arg` at this edge (Reduce; has priority over the compare).
    pub shift: Signal<In, Bit>,
    /// The upper neighbour's minimum.
    pub shift_min: Signal<In, Bits<34>>,
    /// The upper neighbour's index.
    pub shift_arg: Signal<In, Bits<12>>,
    /// The lane's minimum squared distance.
    pub min: Signal<Out, Bits<34>>,
    /// Its model index.
    pub arg: Signal<Out, Bits<12>>,
    id: Constant<Bits<8>>,
    dist_init: Constant<Bits<34>>,
    x: [DFF<Signed<16>>; 3],
    d1: [DFF<Signed<17>>; 3],
    d1b: [DFF<Signed<17>>; 3],
    mul: [Mul18; 3],
    s3a: DFF<Bits<34>>,
    s3b: DFF<Bits<34>>,
    s4: DFF<Bits<34>>,
    min_r: DFF<Bits<34>>,
    arg_r: DFF<Bits<12>>,
    mq: [Signal<Local, Signed<16>>; 3],
    sq: [Signal<Local, Bits<36>>; 3],
}

impl Lane {
    /// Lane number `id` (its position in scan order within a batch), minimum reset to
    /// `2^34 - 1` ([`DIST_INIT`]).
    pub fn new(id: usize) -> Lane {
        Lane::with_init(id, DIST_INIT)
    }

    /// Lane number `id` whose minimum is reset to `init` (the grid pipeline's
    /// [`crate::grid::CAP_D2`]): a distance `>= init` never updates it.
    pub fn with_init(id: usize, init: u64) -> Lane {
        assert!(id < 256, "lane number fits 8 bits");
        assert!(init <= DIST_INIT, "the initial minimum fits 34 bits");
        Lane {
            clock: Default::default(),
            wr_en: Default::default(),
            wr_sel: Default::default(),
            point: Default::default(),
            model: Default::default(),
            init: Default::default(),
            model_valid: Default::default(),
            s4_valid: Default::default(),
            s4_index: Default::default(),
            shift: Default::default(),
            shift_min: Default::default(),
            shift_arg: Default::default(),
            min: Default::default(),
            arg: Default::default(),
            id: Constant::new((id as u64).into()),
            dist_init: Constant::new(init.into()),
            x: Default::default(),
            d1: Default::default(),
            d1b: Default::default(),
            mul: Default::default(),
            s3a: Default::default(),
            s3b: Default::default(),
            s4: Default::default(),
            min_r: Default::default(),
            arg_r: Default::default(),
            mq: Default::default(),
            sq: Default::default(),
        }
    }
}

impl Logic for Lane {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(self, clock, s3a, s3b, s4, min_r, arg_r);
        for k in 0..3 {
            self.x[k].clock.next = self.clock.val();
            self.x[k].d.next = self.x[k].q.val();
            self.d1[k].clock.next = self.clock.val();
            self.d1b[k].clock.next = self.clock.val();
            self.d1b[k].d.next = self.d1b[k].q.val();
            self.mul[k].clock.next = self.clock.val();
        }
        // The lane's point.
        if self.wr_en.val() && (self.wr_sel.val() == self.id.val()) {
            for k in 0..3 {
                self.x[k].d.next = signed_cast(self.point.val().get_bits::<16>(16 * k));
            }
        }
        // s1: differences (17-bit, exact), twice: `d1b` (loaded only with valid data, so equal
        // to `d1` whenever the stage is valid) gives the multiplier's B input its own register.
        // With A and B from one register, Yosys 0.23 packs the subtraction into the DSP48A1
        // pre-adder of B and leaves A undriven (a wrong netlist); two registers both go into
        // the DSP (A1REG, B1REG) and the pre-adder is not used.
        for k in 0..3 {
            self.mq[k].next = signed_cast(self.model.val().get_bits::<16>(16 * k));
            self.d1[k].d.next = signed_bit_cast_safe(self.x[k].q.val()) - signed_bit_cast_safe(self.mq[k].val());
            if self.model_valid.val() {
                self.d1b[k].d.next = signed_bit_cast_safe(self.x[k].q.val()) - signed_bit_cast_safe(self.mq[k].val());
            }
        }
        // s2: squares (registered in the multipliers).
        for k in 0..3 {
            self.mul[k].a.next = signed_bit_cast_safe(self.d1[k].q.val());
            self.mul[k].b.next = signed_bit_cast_safe(self.d1b[k].q.val());
            self.sq[k].next = unsigned_cast(self.mul[k].p.val());
        }
        // s3, s4: the sum of the squares (each < 2^32, the sum < 2^34).
        self.s3a.d.next = bit_cast::<34, 36>(self.sq[0].val()) + bit_cast::<34, 36>(self.sq[1].val());
        self.s3b.d.next = bit_cast::<34, 36>(self.sq[2].val());
        self.s4.d.next = self.s3a.q.val() + self.s3b.q.val();
        // Compare (strictly less: the lowest index wins ties), init, Reduce shift.
        if self.init.val() {
            self.min_r.d.next = self.dist_init.val();
            self.arg_r.d.next = 0.into();
        } else if self.shift.val() {
            self.min_r.d.next = self.shift_min.val();
            self.arg_r.d.next = self.shift_arg.val();
        } else if self.s4_valid.val() && (self.s4.q.val() < self.min_r.q.val()) {
            self.min_r.d.next = self.s4.q.val();
            self.arg_r.d.next = self.s4_index.val();
        }
        self.min.next = self.min_r.q.val();
        self.arg.next = self.arg_r.q.val();
    }
}
