//! The cycle-accurate sequencer model (`SequencerModel`) against the bit-exact functional
//! reference `pf::run`: the same poses sent to the pipeline in the same order, the same
//! particle set after every propagation and every resampling (reconstructed from the
//! particle RAM's write port, and read from the model's RAM), the same estimate, sigma,
//! centre and result; thresholds, the iteration cap, one particle, odd counts, resets in
//! the middle of a run; and the clocks of every phase.
//!
//! The pipeline is emulated by the functional reference: after `start`, a latency, then one
//! nearest-neighbour result per clock and the cost a clock after the last; `nn_ready` is
//! high whenever no evaluation is in flight (optionally after a random gap).

use pficp_fpga::common::format::{FxPoint, FxPose};
use pficp_fpga::filter::pf::{self, example_cloud, example_config, PfConfig, PfOutcome, PARAMS, SCALE_FRAC};
use pficp_fpga::filter::sequencer::{
    clocks_per_iteration, config_writes, resample_clocks, run_clocks, sum_clocks, temper_pass_clocks, unpack_pose,
    weight_clocks, IterationShape, PipelineStandIn, SeqInputs, SeqOutputs, SeqState, SequencerModel, MAX_TEMPER_PASSES,
    POSE_CLOCKS, PROPAGATE_CLOCKS,
};
use std::collections::HashMap;

/// The emulated pipeline's timing: latency from `start` to the first result in
/// `lat.0..=lat.1`, and `nn_ready` low for `0..=gap` clocks after each cost.
#[derive(Clone, Copy, Debug)]
struct Timing {
    lat: (u64, u64),
    gap: u64,
    seed: u32,
}

const FIXED: Timing = Timing { lat: (20, 20), gap: 0, seed: 1 };

/// The model, the emulated pipeline and what was seen.
struct Bench<'a> {
    seq: SequencerModel,
    model: &'a [FxPoint],
    scan: &'a [FxPoint],
    timing: Timing,
    rng: pf::Xorshift32,
    clock: u64,
    pipeline: PipelineStandIn,
    /// Clock from which `nn_ready` may be high again.
    ready_at: u64,
    poses: Vec<FxPose>,
    writes: Vec<(u16, u32)>,
    /// Clocks spent in each state (counted on the clock the state register holds it).
    per_state: HashMap<&'static str, u64>,
}

impl<'a> Bench<'a> {
    fn new(model: &'a [FxPoint], scan: &'a [FxPoint], timing: Timing) -> Self {
        Bench {
            seq: SequencerModel::new(),
            model,
            scan,
            timing,
            rng: pf::Xorshift32::new(timing.seed),
            clock: 0,
            pipeline: PipelineStandIn::default(),
            ready_at: 0,
            poses: Vec::new(),
            writes: Vec::new(),
            per_state: HashMap::new(),
        }
    }

    fn draw(&mut self, lo: u64, hi: u64) -> u64 {
        lo + self.rng.next() as u64 % (hi - lo + 1)
    }

    /// One clock: the pipeline's inputs (plus `extra`), the edge.
    fn clock(&mut self, extra: SeqInputs) -> SeqOutputs {
        let o = self.seq.outputs();
        if o.p_we {
            self.writes.push((o.p_waddr, o.p_wdata));
        }
        let now = self.clock;
        let mut i = extra;
        i.nn_ready = !self.pipeline.busy() && now >= self.ready_at && !o.start;
        if o.start {
            let pose = unpack_pose(&o.pose);
            self.poses.push(pose);
            let lat = self.draw(self.timing.lat.0, self.timing.lat.1);
            self.pipeline.start(now, lat, self.model, self.scan, &pose);
        }
        if self.pipeline.drive(now, &mut i) {
            self.ready_at = now + 1 + self.draw(0, self.timing.gap);
        }
        *self.per_state.entry(self.seq.state_name()).or_default() += 1;
        self.seq.step(&i);
        self.clock += 1;
        self.seq.outputs()
    }

    fn load(&mut self, cfg: &PfConfig) {
        for (a, w) in config_writes(cfg) {
            self.clock(SeqInputs { cfg_we: true, cfg_addr: a, cfg_data: w, ..Default::default() });
        }
    }

    /// Forget the emulated pipeline's evaluation in flight (it is reset with the sequencer).
    fn reset_pipeline(&mut self) {
        self.pipeline.reset();
        self.ready_at = 0;
    }
}

/// What a run did.
#[derive(Debug, PartialEq, Eq)]
struct RunRecord {
    poses: Vec<FxPose>,
    writes: Vec<(u16, u32)>,
    out: SeqOutputs,
    clocks: u64,
}

/// Load, go, clock until `finished`; every iteration's snapshots checked against `reference`
/// on the way (the model's own registers and RAM).
fn run(b: &mut Bench, cfg: &PfConfig, reference: &PfOutcome) -> RunRecord {
    b.load(cfg);
    let (poses0, writes0) = (b.poses.len(), b.writes.len());
    let start = b.clock;
    let mut o = b.clock(SeqInputs { go: true, ..Default::default() });
    assert!(o.running && !o.finished, "running after go");
    let mut prev = b.seq.state();
    while !o.finished {
        o = b.clock(SeqInputs::default());
        let s = b.seq.state();
        if s != prev {
            snapshot(&b.seq, s, reference);
            prev = s;
        }
        assert!(o.finished || o.running, "running until finished");
        assert!(b.clock - start < 20_000_000, "the sequencer did not finish");
    }
    assert_eq!(b.seq.state(), SeqState::Idle);
    RunRecord {
        poses: b.poses[poses0..].to_vec(),
        writes: b.writes[writes0..].to_vec(),
        out: o,
        clocks: b.clock - start,
    }
}

/// The model's registers and particle RAM on entering `s`, against the reference history.
fn snapshot(seq: &SequencerModel, s: SeqState, r: &PfOutcome) {
    let k = seq.iteration() as usize;
    match s {
        SeqState::BestCheck => {
            assert_eq!(seq.particles(seq.half()), r.history[k].particles, "RAM: propagated set of iteration {k}");
        }
        SeqState::EstEval => {
            assert_eq!(seq.estimate(), r.history[k].estimate, "estimate of iteration {k}");
            assert_eq!(seq.sigma(), r.history[k].sigma, "sigma of iteration {k}");
        }
        SeqState::StopCheck => {
            assert_eq!(seq.centre(), r.history[k].centre, "centre after iteration {k}");
            assert_eq!(seq.outputs().best_cost, r.history[k].best_cost, "best cost after iteration {k}");
            assert_eq!(seq.outputs().iterations as usize, k + 1);
        }
        SeqState::IterBegin if k > 0 => {
            assert_eq!(
                seq.particles(seq.half()),
                r.history[k - 1].resampled,
                "RAM: resampled set of iteration {}",
                k - 1
            );
        }
        _ => {}
    }
}

fn params_of(out: &SeqOutputs) -> [i32; PARAMS] {
    std::array::from_fn(|d| {
        let at = 24 * d;
        let mut raw = out.params[at / 64] >> (at % 64);
        if at % 64 > 40 {
            raw |= out.params[at / 64 + 1] << (64 - at % 64);
        }
        pf::wrap24((raw & 0xff_ffff) as i64)
    })
}

/// `pf::run` with the poses it evaluates.
fn reference(cfg: &PfConfig, model: &[FxPoint], scan: &[FxPoint]) -> (PfOutcome, Vec<FxPose>) {
    let mut poses = Vec::new();
    let outcome = pf::run(cfg, |pose| {
        poses.push(*pose);
        // The sequencer does not depend on the search: the brute-force one will do.
        pf::Evaluated::of(&pficp_fpga::search::pipeline::evaluate(model, scan, pose))
    });
    (outcome, poses)
}

/// Run the model on `cfg` and check everything against `pf::run`; the run's record.
fn check(cfg: &PfConfig, model: &[FxPoint], scan: &[FxPoint], timing: Timing) -> RunRecord {
    let (outcome, ref_poses) = reference(cfg, model, scan);
    let mut b = Bench::new(model, scan, timing);
    let r = run(&mut b, cfg, &outcome);
    check_record(cfg, &r, &outcome, &ref_poses);
    r
}

fn check_record(cfg: &PfConfig, r: &RunRecord, outcome: &PfOutcome, ref_poses: &[FxPose]) {
    assert_eq!(r.poses.len(), ref_poses.len(), "number of pipeline runs");
    for (k, (a, b)) in r.poses.iter().zip(ref_poses).enumerate() {
        assert_eq!(a, b, "pose of pipeline run {k}");
    }
    // The particle set after every iteration, from the write stream: propagation writes
    // every particle of the current half, resampling the other half.
    let n = cfg.particles as usize;
    let mut ram = vec![0i32; 4096];
    let mut w = r.writes.iter();
    let mut half = 0usize;
    let set = |ram: &[i32], half: usize| -> Vec<[i32; PARAMS]> {
        (0..n).map(|i| std::array::from_fn(|d| ram[(half << 11) | (i << 3) | d])).collect()
    };
    for (k, h) in outcome.history.iter().enumerate() {
        for _ in 0..n * PARAMS {
            let (a, v) = w.next().expect("propagation writes");
            assert_eq!((*a as usize) >> 11, half, "propagation writes the current half");
            ram[*a as usize] = pf::wrap24(*v as i64);
        }
        assert_eq!(set(&ram, half), h.particles, "write port: propagated set of iteration {k}");
        if !h.resampled.is_empty() {
            for _ in 0..n * PARAMS {
                let (a, v) = w.next().expect("resampling writes");
                assert_eq!((*a as usize) >> 11, half ^ 1, "resampling writes the other half");
                ram[*a as usize] = pf::wrap24(*v as i64);
            }
            half ^= 1;
            assert_eq!(set(&ram, half), h.resampled, "write port: resampled set of iteration {k}");
        }
    }
    assert!(w.next().is_none(), "no writes after the last iteration");
    assert!(r.out.finished && !r.out.running);
    assert_eq!(r.out.iterations, outcome.iterations, "iterations");
    assert_eq!(r.out.best_cost, outcome.best.cost, "best cost");
    assert_eq!(r.out.best_max, outcome.best.max_d2, "best max d2");
    assert_eq!(params_of(&r.out), outcome.params, "best params");
    assert_eq!(unpack_pose(&r.out.pose), outcome.pose, "best pose");
}

fn data() -> (Vec<FxPoint>, Vec<FxPoint>) {
    (example_cloud(60, [0, 0, 0], 0.0), example_cloud(30, [400, -200, 100], 0.05))
}

#[test]
fn the_model_matches_the_functional_reference() {
    let (model, scan) = data();
    let r = check(&example_config(12, 5, 7), &model, &scan, FIXED);
    assert_eq!(r.out.iterations, 5);
    println!("12 particles, 5 iterations, latency 20: {} clocks", r.clocks);
}

#[test]
fn one_particle_odd_counts_wrapping_angles_and_random_latencies() {
    let (model, scan) = data();
    check(&example_config(1, 3, 9), &model, &scan, Timing { lat: (0, 7), gap: 3, seed: 5 });
    let mut c = example_config(7, 4, 0);
    c.centre = [1000, -2000, 300, (1 << SCALE_FRAC) + 5000, 8_000_000, -8_300_000, 4_190_000];
    c.temper_exp = 40;
    check(&c, &model, &scan, Timing { lat: (1, 40), gap: 5, seed: 11 });
    // A small scale that the propagation pushes to zero or below (clamped to 1).
    let mut c = example_config(9, 3, 0xdead_beef);
    c.centre[3] = 3000;
    c.sigma0[3] = 1 << 14;
    check(&c, &model, &scan, Timing { lat: (30, 60), gap: 0, seed: 2 });
    for (seed, n) in [(1u32, 16u16), (2, 5), (3, 13)] {
        check(&example_config(n, 4, seed * 7919), &model, &scan, Timing { lat: (2, 45), gap: 4, seed });
    }
    // Evaluations longer and shorter than a propagation and pose (269 clocks): the next
    // particle waits in EvSync for some, not for others.
    check(&example_config(11, 3, 77), &model, &scan, Timing { lat: (100, 500), gap: 3, seed: 21 });
}

#[test]
fn stops_on_the_thresholds_before_the_cap() {
    let (model, scan) = data();
    // The best cost after the second iteration as the threshold: it stops there.
    let free = example_config(10, 30, 21);
    let (probe, _) = reference(&free, &model, &scan);
    let mut c = free.clone();
    c.thr_cost = probe.history[1].best_cost;
    c.thr_max = (1 << 34) - 1;
    let (outcome, _) = reference(&c, &model, &scan);
    assert!(outcome.iterations <= 2, "the reference stops on the thresholds");
    let r = check(&c, &model, &scan, Timing { lat: (10, 30), gap: 2, seed: 8 });
    assert!(r.out.iterations < c.iterations);
    // The start is already good enough: one iteration.
    let mut c = example_config(6, 50, 3);
    c.thr_cost = u64::MAX >> 16;
    c.thr_max = (1 << 34) - 1;
    assert_eq!(check(&c, &model, &scan, FIXED).out.iterations, 1);
}

#[test]
fn runs_to_the_cap() {
    let (model, scan) = data();
    let mut c = example_config(8, 6, 99);
    c.thr_cost = 1;
    c.thr_max = 1;
    assert_eq!(check(&c, &model, &scan, FIXED).out.iterations, 6);
}

#[test]
fn reset_in_the_middle_of_a_run() {
    let (model, scan) = data();
    let cfg = example_config(8, 4, 17);
    let (outcome, ref_poses) = reference(&cfg, &model, &scan);
    let mut fresh = Bench::new(&model, &scan, FIXED);
    let want = run(&mut fresh, &cfg, &outcome);
    check_record(&cfg, &want, &outcome, &ref_poses);
    // Resets in the pose program, in an evaluation (results streaming in), in the
    // propagation, the temperature, the weights, a weighted sum with products in flight, the
    // divider, the resampling, the final pose, and after the end: `(state, its n-th entry,
    // clocks after entering it)`.
    let points: [(&str, usize, u64); 12] = [
        ("CorStep", 1, 3),
        ("OpMul", 5, 1),
        ("EvWait", 3, 25),
        ("PropMul", 20, 1),
        ("TRun", 10, 5),
        ("WRun", 2, 6),
        ("SumRun", 5, 9),
        ("SumDivWait", 9, 10),
        ("RsWMul", 2, 1),
        ("CpData", 12, 0),
        ("Fin", 1, 100),
        ("Idle", 1, 50),
    ];
    for (target, nth, after) in points {
        let mut b = Bench::new(&model, &scan, FIXED);
        b.load(&cfg);
        b.clock(SeqInputs { go: true, ..Default::default() });
        let (mut seen, mut prev) = (0, b.seq.state());
        while seen < nth {
            b.clock(SeqInputs::default());
            let s = b.seq.state();
            if s != prev && s.name() == target {
                seen += 1;
            }
            prev = s;
            assert!(b.clock < 1_000_000, "{target} entered {nth} times");
        }
        for _ in 0..after {
            b.clock(SeqInputs::default());
        }
        let was = b.seq.state_name();
        let o = b.clock(SeqInputs { reset: true, ..Default::default() });
        b.reset_pipeline();
        assert_eq!(b.seq.state(), SeqState::Idle, "idle after a reset in {was}");
        assert!(!o.running && !o.finished, "neither running nor finished after a reset in {was}");
        // It stays idle (stray pipeline results are ignored).
        for k in 0..30 {
            let o = b.clock(SeqInputs {
                cost_valid: k % 3 == 0,
                cost: 5,
                nn_valid: true,
                nn_dist: 9,
                ..Default::default()
            });
            assert!(!o.running && !o.finished && !o.start);
            assert_eq!(b.seq.state(), SeqState::Idle);
        }
        // A new run (the configuration loaded again: the run moves the region centre).
        let again = run(&mut b, &cfg, &outcome);
        assert_eq!(again, want, "a run after a reset in {was} ({target} {nth} + {after})");
    }
}

#[test]
fn power_up_is_idle_and_a_second_run_repeats_the_first() {
    let (model, scan) = data();
    let m = SequencerModel::new();
    assert_eq!(m.outputs(), SeqOutputs::default());
    assert_eq!(m.state_name(), "Idle");
    let cfg = example_config(5, 3, 4);
    let (outcome, _) = reference(&cfg, &model, &scan);
    let mut b = Bench::new(&model, &scan, FIXED);
    let first = run(&mut b, &cfg, &outcome);
    // `finished` holds until the next go; the result stays on the outputs.
    for _ in 0..10 {
        assert_eq!(b.clock(SeqInputs::default()), first.out);
    }
    let second = run(&mut b, &cfg, &outcome);
    assert_eq!(second, first);
}

/// Clocks per state group over a run, against the documented phase clocks, and the whole
/// run against `run_clocks`.
#[test]
fn phase_clocks() {
    let (model, scan) = data();
    let lat = 20u64;
    // EvStart (one clock: the pipeline is ready) and EvWait (latency, one result per clock,
    // the cost a clock after the last).
    let eval_each = 2 + lat + scan.len() as u64;
    for (n, iters, seed) in [(12u16, 5u16, 7u32), (1, 3, 9), (7, 4, 0)] {
        let cfg = example_config(n, iters, seed);
        let (outcome, ref_poses) = reference(&cfg, &model, &scan);
        let mut b = Bench::new(&model, &scan, Timing { lat: (lat, lat), gap: 0, seed: 1 });
        b.load(&cfg);
        b.per_state.clear();
        let r = run(&mut b, &cfg, &outcome);
        check_record(&cfg, &r, &outcome, &ref_poses);
        let c = |names: &[&str]| -> u64 { names.iter().map(|s| b.per_state.get(s).copied().unwrap_or(0)).sum() };
        let evals = ref_poses.len() as u64;
        let its = outcome.iterations as u64;
        let n = n as u64;
        let p = PARAMS as u64;
        let pose =
            c(&["CorInit", "CorStep", "CorCos", "CorSin", "PoseScale", "OpFetch", "OpA", "OpB", "OpMul", "PoseT"]);
        // Every pipeline run and the final pose.
        assert_eq!(pose, POSE_CLOCKS * (evals + 1), "pose clocks");
        // The start and the estimates wait for their evaluations (EvStart, EvWait); the
        // particles' run while the next particle is propagated (EvLaunch, EvSync): a launch
        // each, one EvSync clock for the first, two for each later one (before and after
        // storing the previous), and the last's whole evaluation plus its store's return.
        let (its_n, sync_evals) = (outcome.iterations as u64, evals - n * outcome.iterations as u64);
        assert_eq!(c(&["EvStart", "EvWait"]), eval_each * sync_evals, "evaluation clocks");
        let overlapped = 3 * n + eval_each;
        assert!(eval_each < 7 * PROPAGATE_CLOCKS + POSE_CLOCKS, "no particle waits for the one before");
        assert_eq!(c(&["EvLaunch", "EvSync"]), overlapped * its_n, "overlapped evaluation clocks");
        let prop = c(&["PropAddr", "PropRead", "PropMul", "PropClamp", "PropWrite"]);
        assert_eq!(prop, PROPAGATE_CLOCKS * p * n * its, "propagation clocks");
        let sums = c(&["SumBegin", "SumRun", "SumDivGo", "SumDivWait"]);
        assert_eq!(sums, 2 * p * sum_clocks(n) * its, "estimate and spread clocks");
        let weights = c(&["WRun", "BestCheck"]);
        assert_eq!(weights, weight_clocks(n) * its, "weight clocks");
        // The whole run, iteration by iteration: the temperature passes, whether the best
        // particle is copied and the resampling pointer's advances from the reference (the
        // PRNG replayed for `u0`).
        let mut rng = pf::Xorshift32::new(cfg.seed);
        let mut best = outcome.start.cost;
        let mut shapes = Vec::new();
        let (mut passes_total, mut advances_total) = (0, 0);
        for h in &outcome.history {
            for _ in 0..n * p {
                rng.next();
            }
            let cmin = *h.costs.iter().min().unwrap();
            let excess: Vec<u64> = h.costs.iter().map(|&c| c - cmin).collect();
            let passes = temper_passes(&excess);
            let best_copied = cmin < best;
            best = best.min(cmin).min(h.estimate_eval.cost);
            let advances = (!h.resampled.is_empty()).then(|| {
                let picks = pf::resample(&h.weights, h.w_sum, rng.unsigned16());
                assert!(picks.iter().map(|&i| h.particles[i]).eq(h.resampled.iter().copied()));
                *picks.last().unwrap() as u64
            });
            passes_total += passes;
            advances_total += advances.unwrap_or(0);
            shapes.push(IterationShape {
                particles: n,
                eval_clocks: overlapped + eval_each,
                temper_passes: passes,
                best_copied,
                resample_advances: advances,
            });
        }
        let temper = c(&["TPass", "TRun", "TCheck", "TMid"]);
        assert_eq!(temper, passes_total * temper_pass_clocks(n), "temperature clocks");
        let resampling = c(&[
            "RsBegin", "RsL", "RsWAddr", "RsWWait", "RsWData", "RsWMul", "RsLoop", "CpWait", "CpData", "CpNext",
            "RsDone",
        ]);
        let resamplings = shapes.iter().filter(|s| s.resample_advances.is_some()).count() as u64;
        assert_eq!(
            resampling,
            resamplings * resample_clocks(n, 0) + (resample_clocks(n, 1) - resample_clocks(n, 0)) * advances_total,
            "resampling clocks"
        );
        let copies = c(&["BestRec", "BestAddr", "BestData"]);
        let copied = shapes.iter().filter(|s| s.best_copied).count() as u64;
        assert_eq!(copies, copied * (2 + p), "best copy clocks");
        assert_eq!(r.clocks, run_clocks(eval_each, &shapes), "run clocks ({n} particles)");
        println!(
            "{n} particles x {its} iterations: {} clocks (pose {pose}, evaluation {}, propagation {prop}, \
             temperature {temper} in {passes_total} passes, weights {}, estimate and spread {sums}, resampling \
             {resampling})",
            r.clocks,
            eval_each * sync_evals + overlapped * its,
            weights
        );
    }
}

/// The closed form in the module documentation.
#[test]
fn the_documented_iteration_formula() {
    for (n, passes, a) in [(1u64, 5u64, 0u64), (12, 6, 7), (256, 6, 255)] {
        let s = IterationShape {
            particles: n,
            eval_clocks: 0,
            temper_passes: passes,
            best_copied: true,
            resample_advances: Some(a),
        };
        let want = n * (49 + 220 + 1) + 14 * (n + 33) + passes * (n + 5) + 11 * n + 7 * a + 248;
        assert_eq!(clocks_per_iteration(&s), want);
        let last = IterationShape { resample_advances: None, best_copied: false, ..s };
        assert_eq!(clocks_per_iteration(&last), want - (9 + 10 * n + 7 * a) - 9);
    }
}

/// Temperature passes: the steps of a binary search over `p` in `0..=48` for the first `p`
/// with more than half the excesses below `2^p`, from `p = 24`.
fn temper_passes(excess: &[u64]) -> u64 {
    let k = excess.len() / 2;
    let enough = |p: u32| excess.iter().filter(|&&e| p == 48 || e < (1u64 << p)).count() > k;
    let (mut lo, mut hi, mut p, mut passes) = (0u32, 48u32, 24u32, 0u64);
    loop {
        passes += 1;
        if enough(p) {
            hi = p;
        } else {
            lo = p + 1;
        }
        if lo == hi {
            break;
        }
        p = (lo + hi) / 2;
    }
    // The linear search's answer.
    assert_eq!(Some(lo), (0..=48u32).find(|&p| enough(p)));
    assert!((5..=MAX_TEMPER_PASSES).contains(&passes));
    passes
}

/// Fifty particles, the board's design point: the clocks of an iteration outside the
/// evaluations (temperature, weights, best copy, estimate and spread, the estimate's pose,
/// resampling; everything but the particles' propagation, poses and evaluations and the
/// start's and the end's), and a particle's propagation and pose, measured on the model.
/// `cargo test -p pficp-fpga --test sequencer_model fifty -- --nocapture` prints them.
#[test]
fn fifty_particles_clocks_outside_the_evaluations() {
    let (model, scan) = data();
    let cfg = example_config(50, 4, 5);
    let (outcome, ref_poses) = reference(&cfg, &model, &scan);
    let mut b = Bench::new(&model, &scan, FIXED);
    let r = run(&mut b, &cfg, &outcome);
    check_record(&cfg, &r, &outcome, &ref_poses);
    let (n, its) = (cfg.particles as u64, outcome.iterations as u64);
    let not_outside = [
        "Idle",
        "StartDone",
        "Fin",
        "FinDone",
        "EvStart",
        "EvWait",
        "EvLaunch",
        "EvSync",
        "PartStore",
        "PropAddr",
        "PropRead",
        "PropMul",
        "PropClamp",
        "PropWrite",
    ];
    let all: u64 = b.per_state.values().sum();
    let excluded: u64 = not_outside.iter().map(|s| b.per_state.get(s).copied().unwrap_or(0)).sum();
    let outside = all - excluded - POSE_CLOCKS * (n * its + 2);
    let prop: u64 = ["PropAddr", "PropRead", "PropMul", "PropClamp", "PropWrite"].iter().map(|s| b.per_state[s]).sum();
    let per_particle = prop / (n * its) + POSE_CLOCKS;
    println!(
        "{n} particles, {its} iterations: {} clocks outside the evaluations per iteration; propagation and pose \
         {per_particle} clocks per particle",
        outside / its
    );
    assert_eq!(per_particle, PARAMS as u64 * PROPAGATE_CLOCKS + POSE_CLOCKS);
    assert!(outside / its < 3_000, "{} clocks outside the evaluations per iteration", outside / its);
}
