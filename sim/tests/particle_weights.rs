//! The Verilated particle-weight pipeline (`particle_weights_verilog(P)`) and weight stage
//! (`weight_stage_verilog()`) in lockstep with their references, and proof that the checker
//! fails when the two differ.

use pficp_fpga::format::{FxPoint, FxPose, WeightScale};
use pficp_fpga::particle_weights::{ParticleWeightModel, PwInputs, PwOutputs};
use pficp_fpga::pipeline::{evaluate, Inputs};
use pficp_fpga::weights::{weights, WeightInputs, WeightModel, WeightOutputs, COST_MAX, MAX_PARTICLES};
use pficp_sim::{
    verilated_models, LockstepOf, PwLockstep, Rtl, TraceMode, VerilatedParticleWeights, VerilatedWeightStage,
    WeightLockstep, PW_OUTPUT_PORTS, WEIGHT_OUTPUT_PORTS,
};
use std::path::Path;
use std::time::Instant;

mod support;
use support::{assert_vcd, vcd, Rng};

/// A rotation by small angles about x, y, z (radians) and a translation (normalised units).
fn pose_near_identity(rng: &mut Rng) -> FxPose {
    let [a, b, c] = [0; 3].map(|_: i32| rng.uniform(-0.06, 0.06));
    let (sa, ca, sb, cb, sc, cc) = (a.sin(), a.cos(), b.sin(), b.cos(), c.sin(), c.cos());
    // Rz(c) * Ry(b) * Rx(a), row-major.
    let m = [
        cc * cb,
        cc * sb * sa - sc * ca,
        cc * sb * ca + sc * sa,
        sc * cb,
        sc * sb * sa + cc * ca,
        sc * sb * ca - cc * sa,
        -sb,
        cb * sa,
        cb * ca,
    ];
    let t = [0; 3].map(|_: i32| rng.uniform(-0.05, 0.05));
    FxPose::from_f64(&m, &t)
}

#[test]
fn every_design_is_verilated() {
    assert_eq!(
        verilated_models(),
        vec![
            ("pipeline", 4, "Vpipe4"),
            ("pipeline", 16, "Vpipe16"),
            ("particle_weights", 4, "Vpw4"),
            ("particle_weights", 16, "Vpw16"),
            ("grid_pipeline", 4, "Vgrid4"),
            ("grid_pipeline", 16, "Vgrid16"),
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
    let pw = VerilatedParticleWeights::new(16);
    assert_eq!((pw.prefix(), pw.lanes()), ("Vpw16", 16));
    assert!(std::fs::read_to_string(pw.verilog_path()).unwrap().contains("module top"));
    assert_eq!(
        pw.outputs(),
        PwOutputs { w: WeightOutputs { min_cost: COST_MAX, ..Default::default() }, ..Default::default() }
    );
    let ws = VerilatedWeightStage::new();
    assert_eq!(ws.prefix(), "Vweights");
    assert_eq!(ws.outputs(), WeightOutputs { min_cost: COST_MAX, ..Default::default() });
    println!("{}", pficp_sim::BUILD_REPORT);
}

/// The whole flow in lockstep: model load, `clear`, 20 particles near identity (80 scan
/// points, gaps), then two weight passes with scales chosen from the costs; every cost
/// against `evaluate`, every weight against `weights`, `w_sum` against their sum.
fn whole_flow(lanes: usize) {
    let t0 = Instant::now();
    let mut rng = Rng::new(0x9f1c_0000 + lanes as u64);
    let model: Vec<FxPoint> = (0..300).map(|_| [rng.coord(12000), rng.coord(12000), rng.coord(6000)]).collect();
    let mut ls = PwLockstep::new(lanes).vcd(vcd(&format!("pw_flow_p{lanes}")));
    ls.load_model(&model).unwrap_or_else(|m| panic!("{m}"));
    // Costs left over from a first batch are forgotten by `clear`.
    let (first, _) = ls.particle(model.len(), &model[..5], &pose_near_identity(&mut rng), |_| false).unwrap();
    ls.step(&PwInputs::default()).unwrap_or_else(|m| panic!("{m}"));
    assert_eq!((ls.outputs().w.count, ls.outputs().w.min_cost), (1, first.cost));
    ls.clear().unwrap_or_else(|m| panic!("{m}"));
    assert_eq!((ls.outputs().w.count, ls.outputs().w.min_cost), (0, COST_MAX));

    let mut costs = Vec::new();
    for k in 0..20u64 {
        let pose = pose_near_identity(&mut rng);
        // Scan points: model points with noise, some far off.
        let scan: Vec<FxPoint> = (0..80)
            .map(|_| {
                let p = model[rng.below(model.len() as u64) as usize];
                let r = if rng.chance(0.1) { 3000 } else { 150 };
                p.map(|c| c.saturating_add(rng.coord(r)))
            })
            .collect();
        let (got, _) = ls
            .particle(model.len(), &scan, &pose, |c| (c + k) % 7 == 3 || (k % 4 == 1 && c % 2 == 0))
            .unwrap_or_else(|m| panic!("particle {k}: {m}"));
        assert_eq!(got, evaluate(&model, &scan, &pose), "particle {k}");
        costs.push(got.cost);
    }
    ls.step(&PwInputs::default()).unwrap_or_else(|m| panic!("{m}")); // the last cost reaches the store
    let (min, max) = (*costs.iter().min().unwrap(), *costs.iter().max().unwrap());
    assert_eq!((ls.outputs().w.count, ls.outputs().w.min_cost), (20, min));

    // Index j = 32 (c - c_min) / 2Q: the worst particle at j ~ 160, then at the clamp (255).
    for two_q in [(max - min) as f64 / 5.0, (max - min) as f64 / 10.0] {
        let scale = WeightScale::for_two_q(two_q);
        let pass = ls.weigh(&scale).unwrap_or_else(|m| panic!("{m}"));
        let expected = weights(&costs, &scale);
        assert_eq!(pass.indices, (0..20).collect::<Vec<u8>>());
        assert_eq!(pass.weights, expected, "2Q = {two_q}, {scale:?}");
        assert_eq!(pass.sum, expected.iter().map(|&w| w as u32).sum::<u32>());
        assert_eq!(pass.clocks, 20 + 6, "w_done n + 6 edges after the weigh edge");
        let distinct = {
            let mut w = expected.clone();
            w.sort_unstable();
            w.dedup();
            w.len()
        };
        assert!(distinct >= 10 && expected.contains(&65535), "weights not spread: {expected:?}");
        println!("P = {lanes}, 2Q = {two_q:.0}: weights {expected:?}, sum {}", pass.sum);
    }
    assert_eq!(ls.outputs().w.count, 20, "a weight pass keeps the costs");
    println!("P = {lanes}: {} clocks compared in {:.2} s", ls.clocks_compared(), t0.elapsed().as_secs_f64());
}

#[test]
fn whole_flow_in_lockstep_p16() {
    whole_flow(16);
}

#[test]
fn whole_flow_in_lockstep_p4() {
    whole_flow(4);
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

/// The weight stage against a reference with a wrong weight (particle 3's, last bit
/// flipped), plugged in through [`Rtl`]: caught on `weight` at the edge the documented
/// timing gives (`k + 6` after the weigh edge), VCD window of 5 cycles.
#[test]
fn checker_reports_a_wrong_weight() {
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

/// The 4-lane particle-weight RTL against a 16-lane reference, traced live: `scan_ready`
/// drops after 4 points in the RTL only (model writes, clear, start, 4 points taken).
#[test]
fn checker_reports_a_wrong_lane_count_pw() {
    let mut rng = Rng::new(9);
    let model: Vec<FxPoint> = (0..6).map(|_| [rng.coord(9000), rng.coord(9000), rng.coord(9000)]).collect();
    let scan: Vec<FxPoint> = (0..7).map(|_| [rng.coord(9000), rng.coord(9000), rng.coord(9000)]).collect();
    let mut ls = PwLockstep::new(4)
        .with_reference(ParticleWeightModel::new(16))
        .trace_mode(TraceMode::Always)
        .vcd(vcd("pw_wrong_lanes"));
    ls.load_model(&model).unwrap();
    ls.clear().unwrap();
    let m = ls.particle(model.len(), &scan, &pose_near_identity(&mut rng), |_| false).unwrap_err();
    println!("{m}");
    assert_eq!((m.cycle, m.signal, m.expected, m.actual), (model.len() as u64 + 1 + 1 + 4, "scan_ready", 1, 0));
    assert_eq!((m.prefix, m.lanes), ("Vpw4", 4));
    assert!(m.to_string().starts_with("RTL Vpw4 (P = 4) differs"), "{m}");
    assert_vcd(&m, &PW_OUTPUT_PORTS);
}

/// A particle-weight reference whose weight stage already holds a cost that the RTL's does
/// not: caught at reset on `w_count`.
#[test]
fn checker_compares_the_pw_reset_state() {
    let mut r = ParticleWeightModel::new(16);
    r.weights.step(&WeightInputs { cost_valid: true, cost: 7, ..Default::default() });
    let mut ls = PwLockstep::new(16).with_reference(r).vcd(vcd("pw_reset_state"));
    let m = ls.step(&PwInputs { nn: Inputs::default(), ..Default::default() }).unwrap_err();
    assert_eq!((m.cycle, m.signal, m.expected, m.actual), (0, "w_count", 1, 0));
    assert_eq!(m.also, vec!["min_cost"]);
}

/// Noise on every input of the particle-weight pipeline at P = 4 for 24,000 clocks: model
/// writes, `start` while busy, scan data without valid, and `clear`/`weigh` at random, so
/// that costs arrive while the weight stage is weighing (dropped), together with `clear`
/// (cleared), or past 256 (no `clear` and few `weigh` in the first half), all in lockstep.
#[test]
fn pw_random_inputs_lockstep_p4() {
    const CLOCKS: u64 = 24_000;
    let mut rng = Rng::new(77);
    let mut ls = PwLockstep::new(4).vcd(vcd("pw_random"));
    let model: Vec<FxPoint> = (0..12).map(|_| [rng.coord(20000), rng.coord(20000), rng.coord(20000)]).collect();
    ls.load_model(&model).unwrap_or_else(|m| panic!("{m}"));
    let (mut costs, mut dropped, mut with_clear, mut passes, mut full) = (0, 0, 0, 0, 0);
    for clock in 0..CLOCKS {
        let nn = Inputs {
            model_we: rng.chance(1.0 / 17.0),
            model_waddr: rng.below(4096) as u16 | 16,
            model_wdata: rng.next(),
            model_count: 1 + rng.below(12) as u16,
            start: rng.chance(0.3),
            pose: pose_near_identity(&mut rng),
            scan_valid: rng.chance(0.7),
            scan_data: rng.next(),
            scan_last: rng.chance(0.4),
        };
        let i = PwInputs {
            nn,
            clear: clock >= CLOCKS / 2 && rng.chance(0.004),
            weigh: rng.chance(if clock < CLOCKS / 2 { 0.001 } else { 0.03 }),
            pre_shift: rng.next() as u8,
            q_mul: rng.next() as u32,
        };
        let now = ls.outputs();
        if now.nn.cost_valid {
            costs += 1;
            dropped += now.w.busy as u64;
            with_clear += (!now.w.busy && i.clear) as u64;
            full += (!now.w.busy && now.w.count as usize == MAX_PARTICLES) as u64;
        }
        ls.step(&i).unwrap_or_else(|m| panic!("{m}"));
        passes += ls.outputs().w.w_done as u64;
    }
    assert_eq!(ls.clocks_compared(), model.len() as u64 + CLOCKS);
    println!("{costs} costs ({dropped} while weighing, {with_clear} with clear, {full} when full), {passes} passes");
    assert!(
        costs > 700 && dropped > 20 && with_clear > 0 && passes > 20 && full > 0,
        "{costs} {dropped} {passes} {full}"
    );
}
