//! The Verilated weight stage (`weight_stage_verilog()`) in lockstep with its reference, and
//! proof that the checker fails when the two differ; which designs are verilated.

use pficp_fpga::common::format::WeightScale;
use pficp_fpga::filter::weights::{weights, WeightInputs, WeightModel, WeightOutputs, COST_MAX, MAX_PARTICLES};
use pficp_sim::{
    verilated_models, LockstepOf, Rtl, TraceMode, VerilatedNeighbourPipeline, VerilatedWeightStage, WeightLockstep,
    WEIGHT_OUTPUT_PORTS,
};
use std::path::Path;

mod support;
use support::{assert_vcd, vcd, Rng};

#[test]
fn every_design_is_verilated() {
    assert_eq!(
        verilated_models(),
        vec![
            ("neighbour_pipeline", 4, "Vnbr4"),
            ("neighbour_pipeline", 16, "Vnbr16"),
            ("weight_stage", 0, "Vweights"),
            ("surface_residual", 0, "Vsurf"),
            ("polish_program", 0, "Vpolish"),
            ("polish_bench", 0, "Vpbench"),
            ("polish_unit", 0, "Vpunit"),
            ("board", 0, "Vboard"),
            ("sequencer", 0, "Vseq"),
            ("board_fast", 0, "Vboardfast"),
        ]
    );
    let nbr = VerilatedNeighbourPipeline::new(16);
    assert_eq!((nbr.prefix(), nbr.lanes()), ("Vnbr16", 16));
    assert!(std::fs::read_to_string(nbr.verilog_path()).unwrap().contains("module top"));
    let ws = VerilatedWeightStage::new();
    assert_eq!(ws.prefix(), "Vweights");
    assert_eq!(ws.outputs(), WeightOutputs { min_cost: COST_MAX, ..Default::default() });
    println!("{}", pficp_sim::BUILD_REPORT);
}

/// Random `clear`, `cost_valid` (any 64-bit value), `weigh` (any scale bits) on the weight
/// stage alone for 30,000 clocks, in regimes that fill it past 256 costs, weigh while busy,
/// clear while busy and weigh while empty.
#[test]
fn weight_stage_random_lockstep() {
    const CLOCKS: u64 = 30_000;
    let mut rng = Rng::new(2024);
    let mut ls = WeightLockstep::new().vcd(vcd("weights_random"));
    #[derive(Default, Debug)]
    struct Seen {
        passes: u64,
        full_passes: u64,
        weigh_busy: u64,
        clear_busy: u64,
        cost_busy: u64,
        cost_full: u64,
        weigh_empty: u64,
        clears: u64,
        weights: u64,
    }
    let mut seen = Seen::default();
    let (mut p_cost, mut p_clear, mut p_weigh) = (0.5, 0.01, 0.05);
    for clock in 0..CLOCKS {
        if clock % 1000 == 0 {
            (p_cost, p_clear, p_weigh) = match rng.below(4) {
                0 => (0.95, 0.0, 0.002), // fill past 256
                1 => (0.5, 0.01, 0.05),
                2 => (0.2, 0.02, 0.3), // weigh (also while busy) and clear often
                _ => (0.5, 0.3, 0.5),
            };
        }
        let cost = match rng.below(8) {
            0 => rng.below(1000),
            1 => 0,
            2 => COST_MAX - rng.below(3),
            3 => rng.next(), // bits above 47 must be ignored
            4 => ls.outputs().min_cost.wrapping_add(rng.below(3)),
            _ => 1_000_000 + rng.below(1 << 24),
        };
        let i = WeightInputs {
            clear: rng.chance(p_clear),
            cost_valid: rng.chance(p_cost),
            cost,
            weigh: rng.chance(p_weigh),
            pre_shift: rng.next() as u8,
            q_mul: if rng.chance(0.5) { rng.next() as u32 } else { WeightScale::for_two_q(1e6).q_mul },
        };
        let now = ls.outputs();
        let busy = now.busy;
        seen.weigh_busy += (busy && i.weigh) as u64;
        seen.clear_busy += (busy && i.clear) as u64;
        seen.cost_busy += (busy && i.cost_valid) as u64;
        seen.cost_full += (!busy && !i.clear && i.cost_valid && now.count as usize == MAX_PARTICLES) as u64;
        seen.weigh_empty += (!busy && !i.clear && !i.cost_valid && i.weigh && now.count == 0) as u64;
        seen.clears += (!busy && i.clear) as u64;
        ls.step(&i).unwrap_or_else(|m| panic!("{m}"));
        let o = ls.outputs();
        seen.weights += o.w_valid as u64;
        if o.w_done {
            seen.passes += 1;
            seen.full_passes += (o.count as usize == MAX_PARTICLES) as u64;
        }
    }
    assert_eq!(ls.clocks_compared(), CLOCKS);
    println!("{CLOCKS} clocks compared: {seen:?}");
    assert!(seen.passes >= 50 && seen.full_passes >= 3 && seen.weights >= 5000, "{seen:?}");
    assert!(seen.weigh_busy > 100 && seen.clear_busy > 100 && seen.cost_busy > 100, "{seen:?}");
    assert!(seen.cost_full > 100 && seen.weigh_empty > 0 && seen.clears > 50, "{seen:?}");
}

/// Weight-stage timing as docs/weights.md gives it: the weight of particle `k` `k + 6` edges
/// after the weigh edge; `w_done` (with `w_sum`) one edge after the last weight.
#[test]
fn weight_stage_pass_timing() {
    let mut ls = WeightLockstep::new().vcd(vcd("weights_timing"));
    let costs: Vec<u64> = (0..MAX_PARTICLES as u64 + 10).map(|k| 5_000_000 + (k * 7919 % 263) * 9_000).collect();
    for &c in &costs {
        ls.push_cost(c).unwrap_or_else(|m| panic!("{m}"));
    }
    assert_eq!(ls.outputs().count as usize, MAX_PARTICLES, "costs past 256 are dropped");
    let scale = WeightScale::for_two_q(300_000.0);
    let weigh =
        WeightInputs { weigh: true, pre_shift: scale.pre_shift as u8, q_mul: scale.q_mul, ..Default::default() };
    ls.step(&weigh).unwrap_or_else(|m| panic!("{m}"));
    let weigh_edge = ls.rtl().cycle();
    let expected = weights(&costs[..MAX_PARTICLES], &scale);
    let mut got = Vec::new();
    loop {
        // weigh (and clear) while busy are ignored.
        ls.step(&WeightInputs { weigh: true, clear: got.len() % 3 == 0, ..weigh }).unwrap_or_else(|m| panic!("{m}"));
        let (o, edge) = (ls.outputs(), ls.rtl().cycle() - weigh_edge);
        if o.w_valid {
            assert_eq!((o.w_index as u64, edge), (got.len() as u64, got.len() as u64 + 6));
            got.push(o.weight);
        }
        if o.w_done {
            assert_eq!(edge, MAX_PARTICLES as u64 + 6);
            assert_eq!(o.w_sum, expected.iter().map(|&w| w as u32).sum::<u32>());
            break;
        }
    }
    assert_eq!(got, expected);
    assert!(!ls.outputs().busy);
}

/// A weight-stage reference that is not after reset: caught by the comparison after reset.
#[test]
fn checker_compares_the_weight_stage_reset_state() {
    let mut loaded = WeightModel::new();
    loaded.step(&WeightInputs { cost_valid: true, cost: 1234, ..Default::default() });
    let mut ls = WeightLockstep::new().with_reference(loaded).vcd(vcd("weights_reset_state"));
    let m = ls.step(&WeightInputs::default()).unwrap_err();
    println!("{m}");
    assert_eq!((m.cycle, m.signal, m.expected, m.actual), (0, "count", 1, 0));
    assert_eq!(m.also, vec!["min_cost"]);
    assert_eq!((m.prefix, m.lanes), ("Vweights", 0));
    assert_eq!(ls.clocks_compared(), 0);
    assert_vcd(&m, &WEIGHT_OUTPUT_PORTS);
    assert!(m.to_string().starts_with("RTL Vweights differs from the reference at cycle 0"), "{m}");
}

/// The weight stage whose reference flips bit 0 of particle 3's weight.
struct Faulty(VerilatedWeightStage);
#[derive(Clone)]
struct FaultyRef(WeightModel);
impl Rtl for Faulty {
    type Inputs = WeightInputs;
    type Outputs = WeightOutputs;
    type Reference = FaultyRef;
    const OUTPUT_PORTS: &'static [&'static str] = &WEIGHT_OUTPUT_PORTS;
    fn port_values(o: &WeightOutputs) -> Vec<u64> {
        VerilatedWeightStage::port_values(o)
    }
    fn new_reference(&self) -> FaultyRef {
        FaultyRef(WeightModel::new())
    }
    fn reference_outputs(r: &FaultyRef) -> WeightOutputs {
        let mut o = r.0.outputs();
        if o.w_valid && o.w_index == 3 {
            o.weight ^= 1;
        }
        o
    }
    fn reference_step(r: &mut FaultyRef, i: &WeightInputs) {
        r.0.step(i)
    }
    fn fresh(&self) -> Self {
        Faulty(VerilatedWeightStage::new())
    }
    fn set_inputs(&mut self, i: &WeightInputs) {
        self.0.set_inputs(i)
    }
    fn outputs(&self) -> WeightOutputs {
        self.0.outputs()
    }
    fn tick(&mut self) {
        self.0.tick()
    }
    fn cycle(&self) -> u64 {
        self.0.cycle()
    }
    fn lanes(&self) -> usize {
        0
    }
    fn prefix(&self) -> &'static str {
        self.0.prefix()
    }
    fn trace_to(&mut self, path: &Path) -> std::io::Result<()> {
        self.0.trace_to(path)
    }
    fn flush_trace(&mut self) {
        self.0.flush_trace()
    }
}

/// The weight stage against a reference with a wrong weight (particle 3's, last bit
/// flipped), plugged in through [`Rtl`]: caught on `weight` at the edge the documented
/// timing gives (`k + 6` after the weigh edge), VCD window of 5 cycles.
#[test]
fn checker_reports_a_wrong_weight() {
    let costs = [900_000u64, 400_000, 2_000_000, 650_000, 1_200_000, 400_000];
    let scale = WeightScale::for_two_q(500_000.0);
    let mut ls = LockstepOf::from_rtl(Faulty(VerilatedWeightStage::new())).vcd(vcd("wrong_weight")).vcd_window(Some(5));
    let clear = WeightInputs { clear: true, ..Default::default() };
    ls.step(&clear).unwrap();
    for &cost in &costs {
        ls.step(&WeightInputs { cost_valid: true, cost, ..Default::default() }).unwrap();
    }
    ls.step(&WeightInputs { weigh: true, pre_shift: scale.pre_shift as u8, q_mul: scale.q_mul, ..Default::default() })
        .unwrap();
    let weigh_edge = ls.rtl().cycle();
    assert_eq!(weigh_edge, 1 + costs.len() as u64 + 1);
    let m = loop {
        if let Err(m) = ls.step(&WeightInputs::default()) {
            break m;
        }
        assert!(ls.rtl().cycle() < weigh_edge + 20, "the wrong weight was not caught");
    };
    println!("{m}");
    let w3 = weights(&costs, &scale)[3] as u64;
    assert_eq!((m.cycle, m.signal, m.expected, m.actual), (weigh_edge + 3 + 6, "weight", w3 ^ 1, w3));
    assert!(m.also.is_empty(), "{:?}", m.also);
    assert_eq!(ls.clocks_compared(), m.cycle - 1);
    assert_eq!(m.vcd_from, m.cycle - 5);
    assert_vcd(&m, &WEIGHT_OUTPUT_PORTS);
    // A failed lockstep stays failed.
    assert_eq!(ls.step(&clear).unwrap_err(), m);
}

/// The same wrong weight traced live (`TraceMode::Always`): caught at the same edge, the VCD
/// covering the whole run from reset.
#[test]
fn checker_traces_a_wrong_weight_live() {
    let costs = [900_000u64, 400_000, 2_000_000, 650_000, 1_200_000, 400_000];
    let scale = WeightScale::for_two_q(500_000.0);
    let mut ls = LockstepOf::from_rtl(Faulty(VerilatedWeightStage::new()))
        .trace_mode(TraceMode::Always)
        .vcd(vcd("wrong_weight_live"));
    ls.step(&WeightInputs { clear: true, ..Default::default() }).unwrap();
    for &cost in &costs {
        ls.step(&WeightInputs { cost_valid: true, cost, ..Default::default() }).unwrap();
    }
    ls.step(&WeightInputs { weigh: true, pre_shift: scale.pre_shift as u8, q_mul: scale.q_mul, ..Default::default() })
        .unwrap();
    let weigh_edge = ls.rtl().cycle();
    let m = loop {
        if let Err(m) = ls.step(&WeightInputs::default()) {
            break m;
        }
        assert!(ls.rtl().cycle() < weigh_edge + 20, "the wrong weight was not caught");
    };
    println!("{m}");
    assert_eq!((m.cycle, m.signal), (weigh_edge + 3 + 6, "weight"));
    assert_eq!(m.vcd_from, 0);
    assert_vcd(&m, &WEIGHT_OUTPUT_PORTS);
}

#[test]
fn trace_to_writes_both_clock_phases() {
    let path = vcd("trace_to");
    let mut w = VerilatedWeightStage::new();
    w.trace_to(&path).unwrap();
    for _ in 0..3 {
        w.tick();
    }
    drop(w);
    let text = std::fs::read_to_string(&path).unwrap();
    let times: Vec<&str> = text.lines().filter(|l| l.starts_with('#')).collect();
    assert_eq!(times, ["#0", "#5", "#10", "#15", "#20", "#25", "#30"]);
}
