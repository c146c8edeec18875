//! `WeightStage`: the cost store, minimum-cost tracker and exp-table weight stage
//! (docs/weights.md), register for register the reference [`crate::filter::weights::WeightModel`].

use crate::common::format::exp_table;
use crate::search::mul18_rtl::Mul18;
use rust_hdl::prelude::*;

/// The weight stage: up to 256 costs, their minimum, one weight per clock.
#[derive(LogicBlock)]
pub struct WeightStage {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Forget every stored cost (priority over `cost_valid`; idle only).
    pub clear: Signal<In, Bit>,
    /// Store `cost` as the next particle's cost (idle only; ignored past 256).
    pub cost_valid: Signal<In, Bit>,
    /// A particle cost.
    pub cost: Signal<In, Bits<48>>,
    /// Start the weight pass (idle, at least one cost stored).
    pub weigh: Signal<In, Bit>,
    /// Right shift of the cost excess, sampled with `weigh`.
    pub pre_shift: Signal<In, Bits<6>>,
    /// Multiplier of the shifted excess (Q1.16), sampled with `weigh`.
    pub q_mul: Signal<In, Bits<17>>,
    /// The weight pass is running.
    pub busy: Signal<Out, Bit>,
    /// Costs stored.
    pub count: Signal<Out, Bits<9>>,
    /// Smallest stored cost (`2^48 - 1` when none).
    pub min_cost: Signal<Out, Bits<48>>,
    /// A weight is presented (one-clock strobe).
    pub w_valid: Signal<Out, Bit>,
    /// Its particle index.
    pub w_index: Signal<Out, Bits<8>>,
    /// The weight (Q0.16).
    pub weight: Signal<Out, Bits<16>>,
    /// One-clock strobe after the last weight.
    pub w_done: Signal<Out, Bit>,
    /// Sum of the weights of the last pass.
    pub w_sum: Signal<Out, Bits<24>>,
    excess_max: Constant<Bits<17>>,
    full: Constant<Bits<9>>,
    costs: RAM<Bits<48>, 8>,
    exp_rom: ROM<Bits<16>, 8>,
    count_r: DFF<Bits<9>>,
    /// The minimum, stored inverted so that the power-up value 0 reads as `2^48 - 1`.
    min_inv: DFF<Bits<48>>,
    min_val: Signal<Local, Bits<48>>,
    weighing: DFF<Bit>,
    pre: DFF<Bits<6>>,
    qmul: DFF<Bits<17>>,
    rd: DFF<Bits<9>>,
    valid: [DFF<Bit>; 5],
    index: [DFF<Bits<8>>; 5],
    b_excess: DFF<Bits<48>>,
    c_shifted: DFF<Bits<17>>,
    mul: Mul18,
    e_entry: DFF<Bits<8>>,
    sum: DFF<Bits<24>>,
    w_valid_r: DFF<Bit>,
    w_index_r: DFF<Bits<8>>,
    weight_r: DFF<Bits<16>>,
    w_done_r: DFF<Bit>,
    w_sum_r: DFF<Bits<24>>,
    issue: Signal<Local, Bit>,
    shifted: Signal<Local, Bits<48>>,
    /// `product >> 16`, 18 bits (the product is below 2^34).
    product_hi: Signal<Local, Bits<18>>,
}

impl Default for WeightStage {
    fn default() -> Self {
        Self::new()
    }
}

impl WeightStage {
    /// After reset: empty and idle, the exp table in ROM.
    pub fn new() -> Self {
        let table = exp_table();
        WeightStage {
            clock: Default::default(),
            clear: Default::default(),
            cost_valid: Default::default(),
            cost: Default::default(),
            weigh: Default::default(),
            pre_shift: Default::default(),
            q_mul: Default::default(),
            busy: Default::default(),
            count: Default::default(),
            min_cost: Default::default(),
            w_valid: Default::default(),
            w_index: Default::default(),
            weight: Default::default(),
            w_done: Default::default(),
            w_sum: Default::default(),
            excess_max: Constant::new(crate::common::format::EXCESS_MAX.into()),
            full: Constant::new((crate::filter::weights::MAX_PARTICLES as u64).into()),
            costs: Default::default(),
            exp_rom: table.iter().map(|&w| Bits::<16>::from(w as u64)).into(),
            count_r: Default::default(),
            min_inv: Default::default(),
            min_val: Default::default(),
            weighing: Default::default(),
            pre: Default::default(),
            qmul: Default::default(),
            rd: Default::default(),
            valid: Default::default(),
            index: Default::default(),
            b_excess: Default::default(),
            c_shifted: Default::default(),
            mul: Default::default(),
            e_entry: Default::default(),
            sum: Default::default(),
            w_valid_r: Default::default(),
            w_index_r: Default::default(),
            weight_r: Default::default(),
            w_done_r: Default::default(),
            w_sum_r: Default::default(),
            issue: Default::default(),
            shifted: Default::default(),
            product_hi: Default::default(),
        }
    }
}

impl Logic for WeightStage {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self, clock, count_r, min_inv, weighing, pre, qmul, rd, b_excess, c_shifted, e_entry, sum, w_valid_r,
            w_index_r, weight_r, w_done_r, w_sum_r
        );
        for s in 0..5 {
            self.valid[s].clock.next = self.clock.val();
            self.index[s].clock.next = self.clock.val();
        }
        self.mul.clock.next = self.clock.val();
        self.costs.read_clock.next = self.clock.val();
        self.costs.write_clock.next = self.clock.val();
        // Outputs.
        self.busy.next = self.weighing.q.val();
        self.count.next = self.count_r.q.val();
        self.min_val.next = !self.min_inv.q.val();
        self.min_cost.next = self.min_val.val();
        self.w_valid.next = self.w_valid_r.q.val();
        self.w_index.next = self.w_index_r.q.val();
        self.weight.next = self.weight_r.q.val();
        self.w_done.next = self.w_done_r.q.val();
        self.w_sum.next = self.w_sum_r.q.val();
        // Cost store: written at `count`, read at `rd` every clock.
        self.costs.write_address.next = self.count_r.q.val().get_bits::<8>(0);
        self.costs.write_data.next = self.cost.val();
        self.costs.write_enable.next = false;
        self.costs.read_address.next = self.rd.q.val().get_bits::<8>(0);
        // Idle: clear, store, or start the pass.
        if !self.weighing.q.val() {
            if self.clear.val() {
                self.count_r.d.next = 0.into();
                self.min_inv.d.next = 0.into();
            } else if self.cost_valid.val() && (self.count_r.q.val() < self.full.val()) {
                self.costs.write_enable.next = true;
                self.count_r.d.next = self.count_r.q.val() + 1;
                if self.cost.val() < self.min_val.val() {
                    self.min_inv.d.next = !self.cost.val();
                }
            } else if self.weigh.val() && self.count_r.q.val().any() {
                self.weighing.d.next = true;
                self.pre.d.next = self.pre_shift.val();
                self.qmul.d.next = self.q_mul.val();
                self.rd.d.next = 0.into();
                self.sum.d.next = 0.into();
            }
        }
        // The pass: a (RAM read), b (excess), c (shift, saturate), d (multiply), e (entry), out.
        self.issue.next = self.weighing.q.val() && (self.rd.q.val() < self.count_r.q.val());
        if self.issue.val() {
            self.rd.d.next = self.rd.q.val() + 1;
        }
        self.valid[0].d.next = self.issue.val();
        self.index[0].d.next = self.rd.q.val().get_bits::<8>(0);
        for s in 1..5 {
            self.valid[s].d.next = self.valid[s - 1].q.val();
            self.index[s].d.next = self.index[s - 1].q.val();
        }
        self.b_excess.d.next = self.costs.read_data.val() - self.min_val.val();
        self.shifted.next = self.b_excess.q.val() >> self.pre.q.val();
        if self.shifted.val().get_bits::<31>(17).any() {
            self.c_shifted.d.next = self.excess_max.val();
        } else {
            self.c_shifted.d.next = self.shifted.val().get_bits::<17>(0);
        }
        self.mul.a.next = signed_cast(bit_cast::<18, 17>(self.c_shifted.q.val()));
        self.mul.b.next = signed_cast(bit_cast::<18, 17>(self.qmul.q.val()));
        // Both factors are below 2^17, so the product fits 34 bits and `>> 16` fits 18: only
        // those bits are used (Yosys 0.23 leaves unused top bits of a DSP product undriven).
        self.product_hi.next = bit_cast::<18, 36>(unsigned_cast(self.mul.p.val()) >> 16);
        if self.product_hi.val().get_bits::<10>(8).any() {
            self.e_entry.d.next = 255.into();
        } else {
            self.e_entry.d.next = self.product_hi.val().get_bits::<8>(0);
        }
        self.exp_rom.address.next = self.e_entry.q.val();
        self.w_valid_r.d.next = false;
        self.w_done_r.d.next = false;
        if self.valid[4].q.val() {
            self.w_valid_r.d.next = true;
            self.w_index_r.d.next = self.index[4].q.val();
            self.weight_r.d.next = self.exp_rom.data.val();
            self.sum.d.next = self.sum.q.val() + bit_cast::<24, 16>(self.exp_rom.data.val());
        }
        if self.weighing.q.val()
            && !self.issue.val()
            && !self.valid[0].q.val()
            && !self.valid[1].q.val()
            && !self.valid[2].q.val()
            && !self.valid[3].q.val()
            && !self.valid[4].q.val()
        {
            self.weighing.d.next = false;
            self.w_done_r.d.next = true;
            self.w_sum_r.d.next = self.sum.q.val();
        }
    }
}
