//! Lockstep co-simulation of the particle-filter sequencer: the Verilated `PfSequencer` and its
//! cycle-accurate mirror `SequencerModel` get the same inputs; every output port (start, pose,
//! status, best, parameters, the particle-RAM write port) must be equal after every clock.
//! Realistic runs with an emulated pipeline (random latencies, resets mid-run), and random
//! inputs on every port.

use pficp_fpga::common::format::FxPoint;
use pficp_fpga::filter::pf::{self, example_cloud, example_config, PfConfig, SCALE_FRAC};
use pficp_fpga::filter::sequencer::{config_writes, unpack_pose, PipelineStandIn, SeqInputs, SeqState, SequencerModel};
use pficp_sim::{SeqLockstep, VerilatedSequencer};

/// The RTL and the model through the common lockstep harness (every port after reset and
/// every clock; a VCD of the last clocks on a mismatch).
struct Both {
    ls: SeqLockstep,
}
impl Both {
    fn new() -> Both {
        Both { ls: SeqLockstep::from_rtl(VerilatedSequencer::new()) }
    }
    fn step(&mut self, i: &SeqInputs) {
        let before = self.ls.reference().state_name();
        if let Err(m) = self.ls.step(i) {
            panic!("{m} (model was in {before}, now {}), inputs {i:?}", self.ls.reference().state_name());
        }
    }
    fn m(&self) -> &SequencerModel {
        self.ls.reference()
    }
}

/// `lat`: the emulated pipeline's latency range after `start` (clocks).
fn realistic(
    cfg: &PfConfig,
    model: &[FxPoint],
    scan: &[FxPoint],
    seed: u32,
    reset_at: Option<u64>,
    lat: (u64, u64),
) -> u64 {
    let mut b = Both::new();
    let mut rng = pf::Xorshift32::new(seed);
    for (a, w) in config_writes(cfg) {
        b.step(&SeqInputs { cfg_we: true, cfg_addr: a, cfg_data: w, ..Default::default() });
    }
    b.step(&SeqInputs { go: true, ..Default::default() });
    let mut pipeline = PipelineStandIn::default();
    let mut ready_at = 0;
    let mut now = 0u64;
    loop {
        let o = b.m().outputs();
        let mut i = SeqInputs { nn_ready: !pipeline.busy() && now >= ready_at && !o.start, ..Default::default() };
        if o.start {
            let latency = lat.0 + rng.next() as u64 % (lat.1 - lat.0 + 1);
            pipeline.start(now, latency, model, scan, &unpack_pose(&o.pose));
        }
        if pipeline.drive(now, &mut i) {
            ready_at = now + 1 + (rng.next() % 4) as u64;
        }
        if Some(now) == reset_at {
            i.reset = true;
            pipeline.reset();
        }
        b.step(&i);
        now += 1;
        if b.m().outputs().finished {
            return now;
        }
        if reset_at.is_some() && now > reset_at.unwrap() + 50 {
            return now;
        }
        assert!(now < 5_000_000);
    }
}

#[test]
fn lockstep_realistic() {
    let model = example_cloud(60, [0, 0, 0], 0.0);
    let scan = example_cloud(30, [400, -200, 100], 0.05);
    println!("{}", realistic(&example_config(12, 5, 7), &model, &scan, 3, None, (0, 39)));
    println!("{}", realistic(&example_config(1, 3, 9), &model, &scan, 4, None, (0, 39)));
    // Evaluations longer and shorter than the next particle's propagation and pose (269
    // clocks): the sequencer waits for some in EvSync.
    println!("{}", realistic(&example_config(10, 3, 31), &model, &scan, 9, None, (100, 500)));
    let mut c = example_config(7, 4, 0);
    c.centre = [1000, -2000, 300, (1 << SCALE_FRAC) + 5000, 8_000_000, -8_300_000, 4_190_000];
    c.temper_exp = 40;
    println!("{}", realistic(&c, &model, &scan, 5, None, (0, 39)));
    let mut c = example_config(9, 3, 0xdead_beef);
    c.centre[3] = 3000;
    c.sigma0[3] = 1 << 14;
    println!("{}", realistic(&c, &model, &scan, 6, None, (0, 39)));
    for at in [3u64, 400, 2000, 9000, 17000] {
        realistic(&example_config(8, 4, 17), &model, &scan, 7, Some(at), (0, 39));
    }
    let mut c = example_config(10, 30, 21);
    c.thr_cost = 1 << 40;
    c.thr_max = (1 << 34) - 1;
    realistic(&c, &model, &scan, 8, None, (0, 39));
}

/// Random inputs on every port, random configuration words.
#[test]
fn lockstep_random_inputs() {
    let mut all_states = std::collections::HashSet::new();
    for seed in 1..=10u32 {
        let mut rng = pf::Xorshift32::new(seed.wrapping_mul(2654435761));
        let mut r = || rng.next() as u64;
        let mut b = Both::new();
        let clocks = 200_000;
        let mut hist = std::collections::HashMap::new();
        let mut fins = 0u64;
        for c in 0..clocks {
            let x = r() | r() << 32;
            let cfg_we = c < 30 || (b.m().state_name() == "Idle" && x % 16 == 0) || x % 7000 == 0;
            let mut cfg_addr = (r() % 32) as u8;
            let mut cfg_data = r() | r() << 32;
            if c < 30 {
                cfg_addr = (c % 25) as u8;
            }
            if cfg_addr == 24 && x % 50 != 0 {
                // Mostly small particle counts and few iterations.
                cfg_data = (r() % 12 + 1) | (r() % 4 + 1) << 16 | (r() % 64) << 32;
            }
            let i = SeqInputs {
                cfg_we,
                cfg_addr,
                cfg_data,
                go: (x >> 8) % 64 == 0,
                nn_ready: (x >> 16) % 4 != 0,
                cost_valid: (x >> 20) % 8 == 0,
                cost: r() & if x % 5 == 0 { u64::MAX } else { 0xffff_ffff },
                nn_valid: (x >> 24) % 2 == 0,
                nn_dist: r(),
                ext_go: (x >> 40) % 2 == 0,
                ext_a: r(),
                ext_b: r(),
                reset: (x >> 32) % 20_000 == 0,
            };
            b.step(&i);
            *hist.entry(b.m().state_name()).or_insert(0u64) += 1;
            all_states.insert(b.m().state_name());
            if b.m().outputs().finished {
                fins += 1;
            }
        }
        println!("{} states visited, finished clocks {fins}", hist.len());
        println!("seed {seed}: state {} iterations {}", b.m().state_name(), b.m().outputs().iterations);
    } // The random inputs reach (nearly) every state of the sequencer.
    assert!(all_states.len() + 1 >= SeqState::ALL.len(), "{} states visited: {all_states:?}", all_states.len());
}

/// The harness can fail, and in `collect_all` mode keeps every mismatch: a reference that
/// was started (`go`) while the RTL was not differs on `running` from the first clock on;
/// each clock is named with its cycle, port, expected and actual, and the first has a VCD.
#[test]
fn a_diverging_sequencer_is_caught_with_every_mismatch_and_a_vcd() {
    let mut started = SequencerModel::new();
    for (a, w) in config_writes(&example_config(4, 2, 3)) {
        started.step(&SeqInputs { cfg_we: true, cfg_addr: a, cfg_data: w, ..Default::default() });
    }
    started.step(&SeqInputs { go: true, ..Default::default() });
    let mut ls = SeqLockstep::from_rtl(VerilatedSequencer::new()).with_reference(started).collect_all();
    for _ in 0..50 {
        let _ = ls.step(&SeqInputs::default());
    }
    let all = ls.finish().unwrap_err();
    assert!(all.len() >= 50 && ls.mismatch_count() as usize == all.len(), "{} of {}", all.len(), ls.mismatch_count());
    let first = &all[0];
    assert_eq!(first.cycle, 0, "{first}");
    assert!(all.iter().all(|m| m.signal == "running" || m.also.contains(&"running")), "{first}");
    assert_eq!((all[1].expected, all[1].actual), (1, 0), "{}", all[1]);
    let vcd = first.vcd.as_ref().expect("a VCD");
    assert!(std::fs::metadata(vcd).is_ok_and(|m| m.len() > 0), "{}", vcd.display());
    assert_eq!(ls.clocks_compared(), 50);
}
