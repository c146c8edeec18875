//! Property-style co-simulation: random models, scans, poses (saturating ones included),
//! gaps and back-pressure, in lockstep with the reference on every clock, and each result
//! against the functional reference. The seed comes from `PFICP_COSIM_SEED` (default 1)
//! and is printed on failure; the number of cases from `PFICP_COSIM_CASES` (default 1,000).

use pficp_fpga::format::{FxPoint, FxPose};
use pficp_fpga::pipeline::evaluate;
use pficp_sim::Lockstep;

mod support;
use support::Rng;

/// The random cases' points and poses.
impl Rng {
    fn point(&mut self) -> FxPoint {
        match self.below(20) {
            0 => [i16::MIN, i16::MAX, i16::MIN],
            1 => [i16::MAX; 3],
            _ => {
                let r = [200, 4000, 16000, 32767][self.below(4) as usize];
                [self.coord(r), self.coord(r), self.coord(r)]
            }
        }
    }
    fn pose(&mut self) -> FxPose {
        let max = (1i64 << 17) - 1;
        if self.below(10) == 0 {
            // Anything the 18-bit fields hold, saturating the transform.
            FxPose {
                m: [0; 9].map(|_| (self.below(2 * max as u64 + 2) as i64 - max - 1) as i32),
                t: [0; 3].map(|_| (self.below(2 * max as u64 + 2) as i64 - max - 1) as i32),
            }
        } else {
            let a = (self.below(6284) as f64) / 1000.0;
            let s = 0.5 + self.below(1000) as f64 / 1000.0;
            let (c, n) = (a.cos() * s, a.sin() * s);
            let t = [0; 3].map(|_| (self.below(2001) as f64 - 1000.0) / 1000.0);
            FxPose::from_f64(&[c, -n, 0.0, n, c, 0.0, 0.0, 0.0, s], &t)
        }
    }
}

fn env(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

#[test]
fn random_cases_in_lockstep() {
    let seed = env("PFICP_COSIM_SEED", 1);
    let cases = env("PFICP_COSIM_CASES", 1000);
    let mut rng = Rng::new(seed);
    let mut clocks = 0u64;
    let mut results = 0usize;
    for lanes in [4usize, 16] {
        let mut ls = Lockstep::new(lanes);
        let share = if lanes == 4 { cases * 4 / 5 } else { cases - cases * 4 / 5 };
        for case in 0..share {
            // A new model most of the time; sometimes reuse (and overwrite part of) the last.
            let bound = if rng.below(8) == 0 { 300 } else { 48 };
            let n_model = 1 + rng.below(bound) as usize;
            let model: Vec<FxPoint> = (0..n_model).map(|_| rng.point()).collect();
            let mut model = model;
            if rng.below(10) == 0 && n_model > 1 {
                model[1] = model[0]; // a tie
            }
            let n_scan = 1 + rng.below(3 * lanes as u64 + 5) as usize;
            let scan: Vec<FxPoint> = (0..n_scan).map(|_| rng.point()).collect();
            let pose = rng.pose();
            let gap_kind = rng.below(4);
            let gap_seed = rng.next();
            let gap = move |c: u64| match gap_kind {
                0 => false,
                1 => c.is_multiple_of(2),
                2 => (c.wrapping_mul(gap_seed) >> 7).is_multiple_of(3),
                _ => c % 7 < 4,
            };
            let outcome = ls.run_particle(&model, &scan, &pose, gap);
            let (got, _) = outcome.unwrap_or_else(|m| panic!("seed {seed}, P = {lanes}, case {case}: {m}"));
            assert_eq!(got, evaluate(&model, &scan, &pose), "seed {seed}, P = {lanes}, case {case}: result");
            results += got.nearest.len();
        }
        clocks += ls.clocks_compared();
    }
    eprintln!("co-simulation matched {cases} random cases: {clocks} clocks compared, {results} nearest-neighbour results (seed {seed})");
    assert!(clocks > cases * 20, "too few clocks compared: {clocks}");
}

#[test]
fn full_model_memory_and_format_limits() {
    // All 4,096 model words, extremes at both ends of the address range, one- and
    // seventeen-point scans, the identity and a saturating pose.
    let mut rng = Rng::new(11);
    let mut model: Vec<FxPoint> = (0..pficp_fpga::format::MAX_POINTS).map(|_| rng.point()).collect();
    model[0] = [i16::MIN; 3];
    model[4095] = [i16::MAX; 3];
    model[2048] = model[17]; // a tie far apart in the address range
    let identity = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
    let saturating = FxPose { m: [131071, -131072, 0, 0, 131071, 0, -131072, 0, 131071], t: [131071, -131072, 0] };
    let mut ls = Lockstep::new(16);
    ls.load_model(&model).expect("load in lockstep");
    for (scan, pose) in [
        (vec![model[4095]], identity),
        ([model[17], [i16::MAX, i16::MIN, 0], [0; 3]].repeat(6)[..17].to_vec(), identity),
        ((0..17).map(|_| rng.point()).collect::<Vec<_>>(), saturating),
    ] {
        let (got, _) = ls.particle(model.len(), &scan, &pose, |c| c % 3 == 0).unwrap_or_else(|m| panic!("{m}"));
        assert_eq!(got, evaluate(&model, &scan, &pose));
    }
    eprintln!("full memory: {} clocks compared", ls.clocks_compared());
}
