//! The Verilated particle-filter sequencer (`PfSequencer`) against the bit-exact functional
//! reference `pf::run`: the same poses sent to the pipeline in the same order, the same
//! particle set after every iteration (reconstructed from the particle RAM's write port),
//! the same result. The pipeline is emulated by the functional reference with a latency.

use pficp_fpga::common::format::{FxPoint, FxPose};
use pficp_fpga::filter::pf::{self, example_cloud, example_config, PfConfig, PARAMS, SCALE_FRAC};
use pficp_fpga::filter::sequencer::{config_writes, unpack_pose, PipelineStandIn, SeqInputs, SeqOutputs};
use pficp_sim::VerilatedSequencer;

/// What one run of the Verilated sequencer did.
struct RtlRun {
    poses: Vec<FxPose>,
    /// Particle RAM contents after every write, by half.
    writes: Vec<(u16, u32)>,
    out: SeqOutputs,
    clocks: u64,
}

/// Load `cfg`, go, emulate the pipeline (results `latency` clocks after `start`, one nearest
/// result per clock, the cost a clock after the last) until `finished`.
fn run_rtl(rtl: &mut VerilatedSequencer, cfg: &PfConfig, model: &[FxPoint], scan: &[FxPoint], latency: u64) -> RtlRun {
    for (a, w) in config_writes(cfg) {
        rtl.step(&SeqInputs { cfg_we: true, cfg_addr: a, cfg_data: w, ..Default::default() });
    }
    rtl.step(&SeqInputs { go: true, ..Default::default() });
    let mut poses = Vec::new();
    let mut writes = Vec::new();
    let mut pipeline = PipelineStandIn::default();
    let start_clock = rtl.cycle();
    loop {
        let o = rtl.outputs();
        if o.p_we {
            writes.push((o.p_waddr, o.p_wdata));
        }
        let now = rtl.cycle();
        let mut i = SeqInputs { nn_ready: !pipeline.busy() && !o.start, ..Default::default() };
        if o.start {
            let pose = unpack_pose(&o.pose);
            poses.push(pose);
            pipeline.start(now, latency, model, scan, &pose);
        }
        pipeline.drive(now, &mut i);
        rtl.step(&i);
        if rtl.outputs().finished {
            break;
        }
        assert!(rtl.cycle() - start_clock < 50_000_000, "the sequencer did not finish");
    }
    RtlRun { poses, writes, out: rtl.outputs(), clocks: rtl.cycle() - start_clock }
}

fn params_of(out: &SeqOutputs) -> [i32; PARAMS] {
    std::array::from_fn(|d| {
        let at = 24 * d;
        let raw = (out.params[at / 64] >> (at % 64))
            | if at % 64 > 40 { out.params[at / 64 + 1] << (64 - at % 64) } else { 0 };
        pf::wrap24((raw & 0xff_ffff) as i64)
    })
}

fn check(cfg: &PfConfig, model: &[FxPoint], scan: &[FxPoint], latency: u64) -> u64 {
    let mut ref_poses = Vec::new();
    let outcome = pf::run(cfg, |pose| {
        ref_poses.push(*pose);
        // The sequencer alone: any search will do, the brute-force one here.
        pf::Evaluated::of(&pficp_fpga::search::pipeline::evaluate(model, scan, pose))
    });
    let mut rtl = VerilatedSequencer::new();
    let r = run_rtl(&mut rtl, cfg, model, scan, latency);
    assert_eq!(r.poses.len(), ref_poses.len(), "number of pipeline runs");
    for (k, (a, b)) in r.poses.iter().zip(&ref_poses).enumerate() {
        assert_eq!(a, b, "pose of pipeline run {k}");
    }
    // The particle set after every iteration, from the write stream: propagation writes
    // every particle of the current half, resampling the other half.
    let n = cfg.particles as usize;
    let mut ram = vec![0i32; 4096];
    let mut w = r.writes.iter();
    let mut half = 0usize;
    for (k, h) in outcome.history.iter().enumerate() {
        for _ in 0..n * PARAMS {
            let (a, v) = w.next().expect("propagation writes");
            ram[*a as usize] = pf::wrap24(*v as i64);
        }
        let set = |ram: &[i32], half: usize| -> Vec<[i32; PARAMS]> {
            (0..n).map(|i| std::array::from_fn(|d| ram[(half << 11) | (i << 3) | d])).collect()
        };
        assert_eq!(set(&ram, half), h.particles, "propagated set of iteration {k}");
        if !h.resampled.is_empty() {
            for _ in 0..n * PARAMS {
                let (a, v) = w.next().expect("resampling writes");
                ram[*a as usize] = pf::wrap24(*v as i64);
            }
            half ^= 1;
            assert_eq!(set(&ram, half), h.resampled, "resampled set of iteration {k}");
        }
    }
    assert!(w.next().is_none(), "no writes after the last iteration");
    assert_eq!(r.out.iterations, outcome.iterations, "iterations");
    assert_eq!(r.out.best_cost, outcome.best.cost, "best cost");
    assert_eq!(r.out.best_max, outcome.best.max_d2, "best max d2");
    assert_eq!(params_of(&r.out), outcome.params, "best params");
    assert_eq!(unpack_pose(&r.out.pose), outcome.pose, "best pose");
    assert!(!r.out.running);
    r.clocks
}

#[test]
fn sequencer_matches_the_functional_reference() {
    let model = example_cloud(48, [0, 0, 0], 0.0);
    let scan = example_cloud(24, [400, -200, 100], 0.05);
    let clocks = check(&example_config(12, 5, 7), &model, &scan, 20);
    println!("12 particles, 5 iterations: {clocks} clocks");
    // One particle, an odd count, angles near the half turn, another seed.
    check(&example_config(1, 3, 9), &model, &scan, 3);
    let mut c = example_config(7, 4, 0);
    c.centre = [1000, -2000, 300, (1 << SCALE_FRAC) + 5000, 8_000_000, -8_300_000, 4_190_000];
    c.temper_exp = 40;
    check(&c, &model, &scan, 11);
}

#[test]
fn sequencer_stops_on_the_thresholds() {
    let model = example_cloud(40, [0, 0, 0], 0.0);
    let scan = example_cloud(20, [0, 0, 0], 0.0);
    let mut c = example_config(6, 50, 3);
    c.thr_cost = u64::MAX >> 16;
    c.thr_max = (1 << 34) - 1;
    check(&c, &model, &scan, 5);
}
