//! The Verilated pipeline in lockstep with the reference, and proof that the checker fails
//! when the two differ.

use pficp_fpga::format::{FxPoint, FxPose};
use pficp_fpga::pipeline::{clocks_per_particle, evaluate, Inputs, Outputs, PipelineModel};
use pficp_sim::{verilated_lanes, Lockstep, TraceMode, VerilatedPipeline, OUTPUT_PORTS};

mod support;
use support::{assert_vcd, vcd};

/// The signals every VCD of a pipeline run has.
const TRACED: [&str; 3] = ["nn_dist", "scan_ready", "clock"];

fn lcg(seed: &mut u64) -> u64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *seed >> 33
}

fn cloud(n: usize, seed: &mut u64, range: i64) -> Vec<FxPoint> {
    (0..n).map(|_| [0; 3].map(|_: i16| ((lcg(seed) as i64 % (2 * range + 1)) - range) as i16)).collect()
}

fn pose() -> FxPose {
    FxPose::from_f64(&[0.9, -0.3, 0.1, 0.3, 0.9, 0.0, -0.1, 0.05, 0.95], &[0.1, -0.2, 0.05])
}

#[test]
fn both_lane_counts_are_verilated() {
    assert_eq!(verilated_lanes(), vec![4, 16]);
    println!("{}", pficp_sim::BUILD_REPORT);
}

#[test]
fn reset_state_and_start() {
    let mut p = VerilatedPipeline::new(4);
    assert_eq!(p.outputs(), Outputs::default());
    assert_eq!(p.cycle(), 0);
    p.set_inputs(&Inputs { start: true, model_count: 3, pose: pose(), ..Default::default() });
    // Nothing happens before the edge.
    assert_eq!(p.outputs(), Outputs::default());
    p.tick();
    assert_eq!(p.cycle(), 1);
    let o = p.outputs();
    assert!(o.busy && o.scan_ready && !o.nn_valid && !o.cost_valid, "{o:?}");
}

#[test]
fn smoke_tiny_model_p4() {
    let model: Vec<FxPoint> = vec![[0, 0, 0], [1000, 0, 0], [0, 2000, 0], [-3000, 0, 500], [100, 100, 100]];
    let scan: Vec<FxPoint> = vec![[990, 10, 0], [-2900, 20, 480], [0, 0, 0]];
    let pose = pose();
    let mut ls = Lockstep::new(4).vcd(vcd("smoke_p4"));
    let (got, clocks) = ls.run_particle(&model, &scan, &pose, |_| false).unwrap_or_else(|m| panic!("{m}"));
    assert_eq!(got, evaluate(&model, &scan, &pose));
    assert_eq!(clocks, clocks_per_particle(scan.len(), model.len(), 4));
    assert_eq!(ls.clocks_compared(), model.len() as u64 + clocks);
}

#[test]
fn lockstep_p16_two_batches_gaps_and_reuse() {
    let mut seed = 7;
    let model = cloud(40, &mut seed, 9000);
    let scan = cloud(21, &mut seed, 9000);
    let mut ls = Lockstep::new(16).vcd(vcd("p16_two_batches"));
    let pose_a = pose();
    let (got, clocks) = ls.run_particle(&model, &scan, &pose_a, |_| false).unwrap_or_else(|m| panic!("{m}"));
    assert_eq!(got, evaluate(&model, &scan, &pose_a));
    assert_eq!(clocks, clocks_per_particle(scan.len(), model.len(), 16));
    // A second particle on the loaded model, with gaps in the stream.
    let pose_b = FxPose::from_f64(&[0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0], &[-0.3, 0.2, 0.0]);
    let (got, gapped) = ls.particle(model.len(), &scan, &pose_b, |c| c % 3 == 1).unwrap_or_else(|m| panic!("{m}"));
    assert_eq!(got, evaluate(&model, &scan, &pose_b));
    assert!(gapped > clocks_per_particle(scan.len(), model.len(), 16));
}

/// P = 4 over every batch shape up to 9 points (1, 2 or 3 batches, full or partial), small
/// models, stream patterns with and without back-pressure gaps, saturating poses and
/// extreme coordinates.
#[test]
fn lockstep_p4_many_shapes() {
    let mut seed = 11;
    let mut ls = Lockstep::new(4).vcd(vcd("p4_many"));
    let poses = [
        pose(),
        FxPose::from_f64(&[1.0; 9], &[3.9, -3.9, 0.0]),
        FxPose::from_f64(&[-2.0, 1.9, 0.0, 0.0, -2.0, 1.0, 0.5, 0.5, -2.0], &[-7.9, 7.9, 1.0]),
    ];
    let mut particles = 0;
    for n_model in [1usize, 2, 7] {
        let mut model = cloud(n_model, &mut seed, 32767);
        if n_model == 7 {
            model[3] = [i16::MIN, i16::MAX, i16::MIN];
        }
        ls.load_model(&model).unwrap_or_else(|m| panic!("{m}"));
        for n_scan in 1..=9 {
            let mut scan = cloud(n_scan, &mut seed, 32767);
            scan[0] = [i16::MAX, i16::MIN, i16::MAX];
            for (k, pose) in poses.iter().enumerate() {
                let pattern = (n_scan + k) % 3;
                let (got, _) = ls
                    .particle(n_model, &scan, pose, |c| match pattern {
                        0 => false,
                        1 => c % 2 == 0,
                        _ => (c / 3) % 2 == 1,
                    })
                    .unwrap_or_else(|m| panic!("{m}"));
                assert_eq!(got, evaluate(&model, &scan, pose), "N_D={n_model} N_M={n_scan} pose {k}");
                particles += 1;
            }
        }
    }
    println!("{particles} particles, {} clocks compared", ls.clocks_compared());
}

/// Noise on every input while the pipeline must ignore it (data without valid, start while
/// busy, model writes to unused addresses), all in lockstep.
#[test]
fn lockstep_p4_random_inputs() {
    let mut seed = 3;
    let mut ls = Lockstep::new(4).vcd(vcd("p4_random"));
    let model = cloud(12, &mut seed, 20000);
    ls.load_model(&model).unwrap_or_else(|m| panic!("{m}"));
    let (mut results, mut costs) = (0, 0);
    for _ in 0..20_000 {
        let r = lcg(&mut seed) as u32;
        let every = |n: u32| r.is_multiple_of(n);
        let i = Inputs {
            model_we: every(17),
            model_waddr: (lcg(&mut seed) % 4096) as u16 | 16,
            model_wdata: lcg(&mut seed) << 20 | lcg(&mut seed),
            model_count: 1 + (lcg(&mut seed) % 30) as u16,
            start: every(5),
            pose: FxPose {
                m: [0; 9].map(|_: i32| (lcg(&mut seed) % (1 << 18)) as i32 - (1 << 17)),
                t: [0; 3].map(|_: i32| (lcg(&mut seed) % (1 << 18)) as i32 - (1 << 17)),
            },
            scan_valid: !every(3),
            scan_data: lcg(&mut seed) << 24 | lcg(&mut seed),
            scan_last: every(7),
        };
        ls.step(&i).unwrap_or_else(|m| panic!("{m}"));
        let o = ls.outputs();
        results += o.nn_valid as usize;
        costs += o.cost_valid as usize;
    }
    assert_eq!(ls.clocks_compared(), 12 + 20_000);
    println!("{results} nearest-neighbour results, {costs} costs");
    assert!(results > 100 && costs > 20, "{results} results, {costs} costs");
}

/// The inputs `drive` produces for a particle when run on the reference alone (the same
/// driver as `Lockstep::run_particle`, so the sequences are identical up to a mismatch).
fn particle_inputs(lanes: usize, model: &[FxPoint], scan: &[FxPoint], pose: &FxPose) -> Vec<Inputs> {
    let mut seq: Vec<Inputs> = model.iter().enumerate().map(|(a, &p)| Inputs::write_model(a, p)).collect();
    let mut m = PipelineModel::new(lanes);
    for i in &seq {
        m.step(i);
    }
    let start = Inputs::start(pose, model.len());
    m.step(&start);
    seq.push(start);
    let mut next = 0;
    while !m.outputs().cost_valid {
        let offer = next < scan.len();
        let i = Inputs::offer(scan, next, offer);
        if offer && m.outputs().scan_ready {
            next += 1;
        }
        m.step(&i);
        seq.push(i);
    }
    seq
}

/// First (cycle, port, a, b) where `a` and `b` differ when both are driven with `seq`.
fn first_difference(
    mut a: PipelineModel,
    mut b: PipelineModel,
    seq: &[Inputs],
) -> Option<(u64, &'static str, u64, u64)> {
    let values = |o: Outputs| {
        [
            o.scan_ready as u64,
            o.busy as u64,
            o.nn_valid as u64,
            o.nn_index as u64,
            o.nn_dist,
            o.cost_valid as u64,
            o.cost,
        ]
    };
    for cycle in 0..=seq.len() {
        if cycle > 0 {
            a.step(&seq[cycle - 1]);
            b.step(&seq[cycle - 1]);
        }
        let (va, vb) = (values(a.outputs()), values(b.outputs()));
        if let Some(k) = (0..7).find(|&k| va[k] != vb[k]) {
            return Some((cycle as u64, OUTPUT_PORTS[k], va[k], vb[k]));
        }
    }
    None
}

/// The reference holds a model point the RTL never got: the first nearest-neighbour result
/// that uses it differs, at the cycle and on the port the two references predict.
#[test]
fn checker_reports_a_wrong_model() {
    let model: Vec<FxPoint> = vec![[0, 0, 0], [4000, 0, 0], [0, 4000, 0], [0, 0, 4000]];
    let scan: Vec<FxPoint> = vec![[3000, 3000, 3000], [100, 0, 0], [-200, 50, 0]];
    let id = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
    // The reference's RAM also has address 4 = the first scan point; run with model_count 5
    // so the sweep reads it (the RTL reads 0 there).
    let mut wrong = PipelineModel::new(4);
    wrong.step(&Inputs::write_model(4, scan[0]));
    let mut model5 = model.clone();
    model5.push([0, 0, 0]); // what the RTL holds at address 4 (reset value)
    let seq = particle_inputs(4, &model5, &scan, &id);
    // Lockstep writes only the first 4 points, then runs with model_count 5: the same
    // sequence without the write to address 4.
    let seq: Vec<Inputs> = seq.into_iter().filter(|i| !(i.model_we && i.model_waddr == 4)).collect();
    let (cycle, signal, expected, actual) = first_difference(wrong.clone(), PipelineModel::new(4), &seq).unwrap();
    assert_eq!(signal, "nn_index");
    assert_eq!(expected, 4);

    let mut ls = Lockstep::new(4).with_reference(wrong).vcd(vcd("wrong_model"));
    ls.load_model(&model).unwrap();
    let m = ls.particle(5, &scan, &id, |_| false).unwrap_err();
    println!("{m}");
    assert_eq!((m.cycle, m.signal, m.expected, m.actual), (cycle, signal, expected, actual));
    assert_eq!(m.also, vec!["nn_dist"]);
    assert_eq!(m.lanes, 4);
    assert_eq!(ls.clocks_compared(), cycle - 1);
    let text = m.to_string();
    for part in
        [format!("cycle {cycle}"), "nn_index".into(), format!("expected {expected}"), format!("actual {actual}")]
    {
        assert!(text.contains(&part), "{text:?} lacks {part:?}");
    }
    assert_eq!(m.vcd_from, 0);
    assert_vcd(&m, &TRACED);
    // A failed lockstep stays failed.
    assert_eq!(ls.step(&Inputs::default()).unwrap_err(), m);

    // The same with a 5-cycle VCD window.
    let mut wrong = PipelineModel::new(4);
    wrong.step(&Inputs::write_model(4, scan[0]));
    let mut ls2 = Lockstep::new(4).with_reference(wrong).vcd(vcd("wrong_model_window")).vcd_window(Some(5));
    ls2.load_model(&model).unwrap();
    let m2 = ls2.particle(5, &scan, &id, |_| false).unwrap_err();
    assert_eq!((m2.cycle, m2.signal, m2.vcd_from), (cycle, signal, cycle - 5));
    assert_vcd(&m2, &TRACED);
}

/// RTL with 4 lanes against a 16-lane reference: `scan_ready` drops after 4 points in the
/// RTL only. Traced live (TraceMode::Always).
#[test]
fn checker_reports_a_wrong_lane_count() {
    let mut seed = 5;
    let model = cloud(6, &mut seed, 9000);
    let scan = cloud(7, &mut seed, 9000);
    let seq = particle_inputs(16, &model, &scan, &pose());
    let (cycle, signal, expected, actual) =
        first_difference(PipelineModel::new(16), PipelineModel::new(4), &seq).unwrap();
    assert_eq!((signal, expected, actual), ("scan_ready", 1, 0));
    assert_eq!(cycle, model.len() as u64 + 1 + 4, "model writes, start, 4 points taken");

    let mut ls =
        Lockstep::new(4).with_reference(PipelineModel::new(16)).trace_mode(TraceMode::Always).vcd(vcd("wrong_lanes"));
    let m = ls.run_particle(&model, &scan, &pose(), |_| false).unwrap_err();
    println!("{m}");
    assert_eq!((m.cycle, m.signal, m.expected, m.actual), (cycle, signal, expected, actual));
    assert_vcd(&m, &TRACED);
}

/// A reference that is already busy: caught by the comparison after reset (cycle 0).
#[test]
fn checker_compares_the_reset_state() {
    let mut busy = PipelineModel::new(16);
    busy.step(&Inputs { start: true, model_count: 1, ..Default::default() });
    let mut ls = Lockstep::new(16).with_reference(busy).vcd(vcd("reset_state"));
    let m = ls.step(&Inputs::default()).unwrap_err();
    println!("{m}");
    assert_eq!((m.cycle, m.signal, m.expected, m.actual), (0, "scan_ready", 1, 0));
    assert_eq!(m.also, vec!["busy"]);
    assert_eq!(ls.clocks_compared(), 0);
    assert_eq!(ls.rtl().cycle(), 0, "no edge before the reset comparison");
    assert_vcd(&m, &TRACED);
}

#[test]
fn trace_to_writes_both_clock_phases() {
    let path = vcd("trace_to");
    let mut p = VerilatedPipeline::new(4);
    p.trace_to(&path).unwrap();
    for _ in 0..3 {
        p.tick();
    }
    drop(p);
    let text = std::fs::read_to_string(&path).unwrap();
    let times: Vec<&str> = text.lines().filter(|l| l.starts_with('#')).collect();
    assert_eq!(times, ["#0", "#5", "#10", "#15", "#20", "#25", "#30"]);
}

/// The design point: 16 lanes, a 1,024-point model, 40 scan points (3 batches), a gap
/// pattern with back-pressure, all in lockstep.
#[test]
fn lockstep_p16_design_point() {
    let mut seed = 21;
    let model = cloud(1024, &mut seed, 30000);
    let scan = cloud(40, &mut seed, 30000);
    let mut ls = Lockstep::new(16).vcd(vcd("p16_design_point"));
    let (got, clocks) = ls.run_particle(&model, &scan, &pose(), |c| c % 5 == 2).unwrap_or_else(|m| panic!("{m}"));
    assert_eq!(got, evaluate(&model, &scan, &pose()));
    println!("{clocks} clocks, {} compared", ls.clocks_compared());
}
