//! The bit-exact, cycle-accurate reference of the weight stage (docs/weights.md): it
//! stores the particles' costs, tracks the minimum, and turns each cost into a weight
//! by the exp table (Eq. 20 with the minimum subtracted, docs/fixed-point.md).

use crate::common::format::{exp_table, WeightScale, EXCESS_MAX, EXP_ENTRIES};

pub use crate::common::format::MAX_PARTICLES;
/// Mask of a 48-bit cost; also the minimum after `clear`.
pub const COST_MAX: u64 = crate::common::format::COST_MASK;

/// Input ports (before an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WeightInputs {
    /// Forget every stored cost (has priority over `cost_valid`).
    pub clear: bool,
    /// Store `cost` as the next particle's cost (when idle; ignored when 256 are stored).
    pub cost_valid: bool,
    /// A particle cost (48 bits).
    pub cost: u64,
    /// Start the weight pass over the stored costs (when idle and at least one is stored).
    pub weigh: bool,
    /// Right shift of the cost excess (6 bits), sampled with `weigh`.
    pub pre_shift: u8,
    /// The 17-bit multiplier, sampled with `weigh`.
    pub q_mul: u32,
}

/// Output ports (after an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WeightOutputs {
    /// Not idle.
    pub busy: bool,
    /// Costs stored (0..=256).
    pub count: u16,
    /// Smallest stored cost (`2^48 - 1` when none).
    pub min_cost: u64,
    /// A weight is presented.
    pub w_valid: bool,
    /// Its particle index.
    pub w_index: u8,
    /// The weight (Q0.16).
    pub weight: u16,
    /// One-clock strobe after the last weight: `w_sum` holds the sum of the weights.
    pub w_done: bool,
    /// Sum of the weights of the last pass (24 bits).
    pub w_sum: u32,
}

#[derive(Clone, Copy, Debug, Default)]
struct Slot<T> {
    valid: bool,
    index: u8,
    value: T,
}

/// Register state of the weight stage.
#[derive(Clone, Debug)]
pub struct WeightModel {
    table: [u16; EXP_ENTRIES],
    costs: Vec<u64>,
    count: u16,
    min: u64,
    weighing: bool,
    scale: WeightScale,
    rd: u16,
    a: Slot<u64>,
    b: Slot<u64>,
    c: Slot<u64>,
    d: Slot<u64>,
    e: Slot<usize>,
    sum: u32,
    out: WeightOutputs,
}

impl Default for WeightModel {
    fn default() -> Self {
        Self::new()
    }
}

impl WeightModel {
    /// After reset: empty, idle.
    pub fn new() -> Self {
        WeightModel {
            table: exp_table(),
            costs: vec![0; MAX_PARTICLES],
            count: 0,
            min: COST_MAX,
            weighing: false,
            scale: WeightScale::default(),
            rd: 0,
            a: Slot::default(),
            b: Slot::default(),
            c: Slot::default(),
            d: Slot::default(),
            e: Slot::default(),
            sum: 0,
            out: WeightOutputs::default(),
        }
    }

    /// Output ports now.
    pub fn outputs(&self) -> WeightOutputs {
        WeightOutputs { busy: self.weighing, count: self.count, min_cost: self.min, ..self.out }
    }

    /// One rising edge.
    pub fn step(&mut self, i: &WeightInputs) {
        let mut n = self.clone();
        n.out.w_valid = false;
        n.out.w_done = false;
        if !self.weighing {
            if i.clear {
                n.count = 0;
                n.min = COST_MAX;
            } else if i.cost_valid && (self.count as usize) < MAX_PARTICLES {
                let c = i.cost & COST_MAX;
                n.costs[self.count as usize] = c;
                n.count = self.count + 1;
                n.min = self.min.min(c);
            } else if i.weigh && self.count > 0 {
                n.weighing = true;
                n.scale = WeightScale { pre_shift: (i.pre_shift & 63) as u32, q_mul: i.q_mul & ((1 << 17) - 1) };
                n.rd = 0;
                n.sum = 0;
            }
        }
        // The weight pipeline (advances every clock).
        let issue = self.weighing && self.rd < self.count;
        n.a = Slot { valid: issue, index: self.rd as u8, value: self.costs[(self.rd as usize) % MAX_PARTICLES] };
        if issue {
            n.rd = self.rd + 1;
        }
        n.b = Slot { valid: self.a.valid, index: self.a.index, value: self.a.value.wrapping_sub(self.min) & COST_MAX };
        n.c = Slot {
            valid: self.b.valid,
            index: self.b.index,
            value: (self.b.value >> self.scale.pre_shift.min(63)).min(EXCESS_MAX),
        };
        n.d = Slot { valid: self.c.valid, index: self.c.index, value: self.c.value * self.scale.q_mul as u64 };
        n.e = Slot {
            valid: self.d.valid,
            index: self.d.index,
            value: ((self.d.value >> 16) as usize).min(EXP_ENTRIES - 1),
        };
        if self.e.valid {
            let w = self.table[self.e.value];
            n.out.w_valid = true;
            n.out.w_index = self.e.index;
            n.out.weight = w;
            n.sum = self.sum + w as u32;
        }
        if self.weighing && !issue && !self.a.valid && !self.b.valid && !self.c.valid && !self.d.valid && !self.e.valid
        {
            n.weighing = false;
            n.out.w_done = true;
            n.out.w_sum = self.sum;
        }
        *self = n;
    }
}

/// The functional reference: each cost's weight, `EXP[index(c - c_min)]`.
pub fn weights(costs: &[u64], scale: &WeightScale) -> Vec<u16> {
    let table = exp_table();
    let min = costs.iter().copied().min().unwrap_or(0);
    costs.iter().map(|&c| table[scale.index(c - min)]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Push costs, weigh, collect (weights, sum, clocks from weigh to done).
    fn run(m: &mut WeightModel, costs: &[u64], scale: WeightScale) -> (Vec<u16>, u32, u64) {
        m.step(&WeightInputs { clear: true, ..Default::default() });
        for &c in costs {
            m.step(&WeightInputs { cost_valid: true, cost: c, ..Default::default() });
        }
        m.step(&WeightInputs {
            weigh: true,
            pre_shift: scale.pre_shift as u8,
            q_mul: scale.q_mul,
            ..Default::default()
        });
        let mut out = Vec::new();
        let mut clocks = 1;
        loop {
            m.step(&WeightInputs::default());
            clocks += 1;
            let o = m.outputs();
            if o.w_valid {
                assert_eq!(o.w_index as usize, out.len());
                out.push(o.weight);
            }
            if o.w_done {
                return (out, o.w_sum, clocks);
            }
            assert!(clocks < 10_000);
        }
    }

    #[test]
    fn cycle_model_equals_functional_reference() {
        let mut m = WeightModel::new();
        let costs: Vec<u64> = (0..50u64).map(|k| 1_000_000 + (k * 7919 % 97) * 40_000).collect();
        let scale = WeightScale::for_two_q(400_000.0);
        let (w, sum, clocks) = run(&mut m, &costs, scale);
        assert_eq!(w, weights(&costs, &scale));
        assert_eq!(sum, w.iter().map(|&x| x as u32).sum::<u32>());
        assert_eq!(clocks, 50 + 7);
        assert_eq!(m.outputs().min_cost, *costs.iter().min().unwrap());
        // The best particle gets the full weight.
        let best = costs.iter().position(|&c| c == 1_000_000).unwrap();
        assert_eq!(w[best], 65535);
    }

    #[test]
    fn extremes_saturate() {
        let mut m = WeightModel::new();
        let costs = [COST_MAX, 0, 5];
        let (w, _, _) = run(&mut m, &costs, WeightScale { pre_shift: 0, q_mul: (1 << 17) - 1 });
        assert_eq!(w, vec![exp_table()[255], 65535, exp_table()[((5 * ((1u64 << 17) - 1)) >> 16) as usize]]);
    }

    #[test]
    fn holds_at_most_256_and_ignores_weigh_when_empty() {
        let mut m = WeightModel::new();
        m.step(&WeightInputs { weigh: true, ..Default::default() });
        assert!(!m.outputs().busy);
        for k in 0..300u64 {
            m.step(&WeightInputs { cost_valid: true, cost: k, ..Default::default() });
        }
        assert_eq!(m.outputs().count, 256);
    }
}
