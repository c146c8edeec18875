//! The on-board particle filter (PF-ICP Algorithm 6, steps 6 to 8) in bit-exact integer
//! arithmetic: the functional reference of the RTL sequencer (`filter::sequencer_rtl`)
//! and of the board's Run command (docs/sequencer.md).
//!
//! Everything here is integers with the formats below; the RTL computes the same values
//! with a pipelined multiplier, a serial divider and a CORDIC, and its cycle-accurate mirror
//! ([`crate::filter::sequencer`]) is checked against [`run`] and against the Verilated RTL.
//!
//! | quantity | bits | format |
//! |---|---|---|
//! | translation parameter `a, b, c` | 24 signed | Q5.19 |
//! | scale parameter `s` | 24 signed | Q3.21 |
//! | angle parameter `phi, theta, psi` | 24 | binary angle: a full turn is `2^24` (wraps) |
//! | sigma (per parameter) | 22 unsigned | the parameter's LSBs |
//! | sine, cosine | 18 signed | Q2.16 |
//! | weight | 16 unsigned | Q0.16 (the exp table of [`crate::common::format::exp_table`]) |
//!
//! Every parameter is handled modulo `2^24`: an offset from the region centre is the
//! wrapped 24-bit difference, which for angles is exactly the wrap-around-free offset the
//! circular mean needs (the region is never wider than half a turn).
//!
//! This file holds the Run's configuration, the loop and its records; each of the
//! sequencer's blocks has its model in its own file beside its RTL twin ([`super::cordic`],
//! [`super::xorshift`], [`super::pose_program`], [`super::translation`],
//! [`super::propagate`], [`super::serial_div`], [`super::estimate`], [`super::weight`],
//! [`super::resample`]), the parameters' formats in [`super::params`]; all are re-exported
//! here.

use crate::common::format::{exp_table, FxPose};

pub use super::cordic::{cordic, CORDIC_ATAN, CORDIC_FRAC, CORDIC_K, CORDIC_STEPS, TRIG_FRAC};
pub use super::estimate::{estimate_param, spread};
pub use super::params::{
    sat18, wrap24, Particle, PARAMS, PARAM_BITS, PARAM_TRANSLATION_FRAC, SCALE, SCALE_FRAC, SIGMA_BITS,
};
pub use super::pose_program::{
    operand18, pose_of, run_program, Op, POSE_PROGRAM, REG_BITS, REG_M, REG_SCALE, REG_ZERO,
};
pub use super::propagate::propagate;
pub use super::resample::resample;
pub use super::serial_div::div_signed;
pub use super::translation::translation;
pub use super::weight::{temper, weight, MIN_TEMPER_EXP};
pub use super::xorshift::Xorshift32;

pub use crate::common::format::MAX_PARTICLES;
/// Words of a Run request after its header (each [`RUN_WORD_BYTES`], little-endian).
pub const RUN_WORDS: usize = 24;
/// Data bytes of a Run request.
pub const RUN_BYTES: usize = RUN_HEADER_BYTES + RUN_WORD_BYTES * RUN_WORDS;
/// Bytes of a Run request's header: particles, iterations, temperature exponent.
pub const RUN_HEADER_BYTES: usize = 6;
/// Bytes of one Run word (48 bits).
pub const RUN_WORD_BYTES: usize = 6;

/// The Run parameters (the prior from the host's k-means start and ICP covariance).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PfConfig {
    /// Particles `n_p` (1..=256).
    pub particles: u16,
    /// Iteration cap (>= 1).
    pub iterations: u16,
    /// `e_Q`: the ICP variance as a power of two, `2 Q = 2^e_Q` cost LSBs (6 bits).
    pub temper_exp: u8,
    /// Centre of the first region (the start).
    pub centre: Particle,
    /// Initial sigma per parameter (22 bits; also the cap of the region update).
    pub sigma0: [u32; PARAMS],
    /// Smallest sigma per parameter (22 bits).
    pub floor: [u32; PARAMS],
    /// PRNG seed (0 is taken as 1).
    pub seed: u32,
    /// Stop when the best cost is at most this (cost LSBs) ...
    pub thr_cost: u64,
    /// ... and its largest squared point distance at most this (34 bits, distance LSBs).
    pub thr_max: u64,
}

/// Why a Run request's data is not a [`PfConfig`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ConfigError {
    /// Not [`RUN_BYTES`] bytes.
    #[error("a Run request has {RUN_BYTES} data bytes, not {0}")]
    Length(usize),
    /// Particles not in 1..=256 or no iterations.
    #[error("{0} particles and {1} iterations (1..=256 particles, at least 1 iteration)")]
    Capacity(u16, u16),
    /// A polish over no points or more than the scan store holds
    /// ([`crate::protocol::run_request::RunRequest`]).
    #[error("a polish over {0} scan points (1..=4096)")]
    Points(u16),
}

fn le(b: &[u8]) -> u64 {
    b.iter().rev().fold(0u64, |a, &x| (a << 8) | x as u64)
}

impl PfConfig {
    /// The Run request's data: `particles` u16, `iterations` u16, `temper_exp` u8, a zero
    /// byte, then 24 words of 6 bytes: centre[7], sigma0[7], floor[7], seed, thr_cost,
    /// thr_max.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(RUN_BYTES);
        out.extend(self.particles.to_le_bytes());
        out.extend(self.iterations.to_le_bytes());
        out.push(self.temper_exp);
        out.push(0);
        let words = self
            .centre
            .iter()
            .map(|&c| c as u32 as u64 & 0xff_ffff)
            .chain(self.sigma0.iter().map(|&s| s as u64))
            .chain(self.floor.iter().map(|&s| s as u64))
            .chain([self.seed as u64, self.thr_cost, self.thr_max]);
        for w in words {
            out.extend(&w.to_le_bytes()[..RUN_WORD_BYTES]);
        }
        out
    }

    /// Parse a Run request's data, with the board's checks (length, then capacities).
    /// Fields are taken as the board takes them: sigma and floor masked to 22 bits, the
    /// temperature exponent to 6, the centre sign-extended from 24 bits, thr_max masked
    /// to 34 bits.
    pub fn decode(d: &[u8]) -> Result<PfConfig, ConfigError> {
        if d.len() != RUN_BYTES {
            return Err(ConfigError::Length(d.len()));
        }
        let particles = u16::from_le_bytes([d[0], d[1]]);
        let iterations = u16::from_le_bytes([d[2], d[3]]);
        if particles == 0 || particles as usize > MAX_PARTICLES || iterations == 0 {
            return Err(ConfigError::Capacity(particles, iterations));
        }
        let at = |i: usize| RUN_HEADER_BYTES + RUN_WORD_BYTES * i;
        let w = |i: usize| le(&d[at(i)..at(i + 1)]);
        let sigma = |i: usize| (w(i) & ((1 << SIGMA_BITS) - 1)) as u32;
        Ok(PfConfig {
            particles,
            iterations,
            temper_exp: d[4] & 63,
            centre: std::array::from_fn(|i| wrap24(w(i) as i64)),
            sigma0: std::array::from_fn(|i| sigma(PARAMS + i)),
            floor: std::array::from_fn(|i| sigma(2 * PARAMS + i)),
            seed: w(21) as u32,
            thr_cost: w(22),
            thr_max: w(23) & ((1 << 34) - 1),
        })
    }
}

/// What the pipeline gives for one pose: the cost and the largest squared point distance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Evaluated {
    /// Sum of squared nearest distances (48 bits).
    pub cost: u64,
    /// Largest squared nearest distance (34 bits).
    pub max_d2: u64,
}

impl Evaluated {
    /// The cost and the largest squared distance of a pipeline's evaluation.
    pub fn of(e: &crate::search::pipeline::Evaluation) -> Evaluated {
        Evaluated { cost: e.cost, max_d2: e.nearest.iter().map(|n| n.1).max().unwrap_or(0) }
    }
}

/// The board's answer for a pose, by the functional reference: the grid search over the
/// gridded model (the stored points and their table), every distance capped at
/// `grid::CAP_D2` (docs/pipeline.md, "The neighbour pipeline").
pub fn evaluate(grid: &crate::search::grid::Grid, scan: &[crate::common::format::FxPoint], pose: &FxPose) -> Evaluated {
    Evaluated::of(&crate::search::grid::evaluate_grid(grid, scan, pose))
}

/// One iteration, as the sequencer leaves it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IterationRecord {
    /// The propagated particles that were weighed.
    pub particles: Vec<Particle>,
    /// Their costs.
    pub costs: Vec<u64>,
    /// Temperature exponent `e_k` (`2 Q_k = 2^e_k`).
    pub temper: u32,
    /// Their weights.
    pub weights: Vec<u16>,
    /// Sum of the weights.
    pub w_sum: u32,
    /// The weighted estimate.
    pub estimate: Particle,
    /// Its evaluation.
    pub estimate_eval: Evaluated,
    /// Sigma after the region update.
    pub sigma: [u32; PARAMS],
    /// Best cost so far.
    pub best_cost: u64,
    /// The centre of the next iteration (the best particle or estimate so far).
    pub centre: Particle,
    /// The resampled set (empty after the last iteration).
    pub resampled: Vec<Particle>,
}

/// The filter's result.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PfOutcome {
    /// Best particle or estimate seen.
    pub params: Particle,
    /// Its pose.
    pub pose: FxPose,
    /// Its evaluation.
    pub best: Evaluated,
    /// Iterations run.
    pub iterations: u16,
    /// The start's evaluation.
    pub start: Evaluated,
    /// Per iteration.
    pub history: Vec<IterationRecord>,
}

/// Run the filter; `eval` is the pipeline (cost and largest squared distance of a pose).
pub fn run(cfg: &PfConfig, mut eval: impl FnMut(&FxPose) -> Evaluated) -> PfOutcome {
    let table = exp_table();
    let n = cfg.particles as usize;
    let mask = |s: u32| s & ((1 << SIGMA_BITS) - 1);
    let floor: [u32; PARAMS] = cfg.floor.map(mask);
    let cap: [u32; PARAMS] = std::array::from_fn(|d| mask(cfg.sigma0[d]).max(floor[d]));
    let mut sigma = cap;
    let mut centre = cfg.centre;
    let mut rng = Xorshift32::new(cfg.seed);
    let start = eval(&pose_of(&centre));
    let mut best = (start, centre);
    let mut particles = vec![[0i32; PARAMS]; n];
    let mut history = Vec::new();
    let mut iterations = 0;
    for k in 0..cfg.iterations {
        iterations = k + 1;
        let first = k == 0;
        let mut costs = Vec::with_capacity(n);
        let mut evals = Vec::with_capacity(n);
        for x in particles.iter_mut() {
            for d in 0..PARAMS {
                let u = rng.signed16() as i64;
                x[d] = propagate(x[d], centre[d], sigma[d], u, first, d == SCALE);
            }
            let e = eval(&pose_of(x));
            costs.push(e.cost);
            evals.push(e);
        }
        let (imin, cmin) =
            costs.iter().copied().enumerate().fold((0, u64::MAX), |a, (i, c)| if c < a.1 { (i, c) } else { a });
        let excess: Vec<u64> = costs.iter().map(|c| c - cmin).collect();
        let e = temper(&excess, cfg.temper_exp);
        let weights: Vec<u16> = excess.iter().map(|&x| weight(x, e, &table)).collect();
        let w_sum: u32 = weights.iter().map(|&w| w as u32).sum();
        if cmin < best.0.cost {
            best = (evals[imin], particles[imin]);
        }
        let mut estimate = [0i32; PARAMS];
        for d in 0..PARAMS {
            let s: i64 = particles
                .iter()
                .zip(&weights)
                .map(|(x, &w)| w as i64 * wrap24(x[d] as i64 - centre[d] as i64) as i64)
                .sum();
            estimate[d] = estimate_param(centre[d], s, w_sum, d == SCALE);
        }
        for d in 0..PARAMS {
            let dsum: u64 = particles
                .iter()
                .zip(&weights)
                .map(|(x, &w)| w as u64 * (wrap24(x[d] as i64 - estimate[d] as i64) as i64).unsigned_abs())
                .sum();
            sigma[d] = spread(dsum, w_sum, floor[d], cap[d]);
        }
        let estimate_eval = eval(&pose_of(&estimate));
        if estimate_eval.cost < best.0.cost {
            best = (estimate_eval, estimate);
        }
        centre = best.1;
        let mut record = IterationRecord {
            particles: particles.clone(),
            costs,
            temper: e,
            weights: weights.clone(),
            w_sum,
            estimate,
            estimate_eval,
            sigma,
            best_cost: best.0.cost,
            centre,
            resampled: Vec::new(),
        };
        let done = (best.0.cost <= cfg.thr_cost && best.0.max_d2 <= cfg.thr_max) || k + 1 == cfg.iterations;
        if !done {
            let picks = resample(&weights, w_sum, rng.unsigned16());
            particles = picks.iter().map(|&i| particles[i]).collect();
            record.resampled = particles.clone();
        }
        history.push(record);
        if done {
            break;
        }
    }
    PfOutcome { params: best.1, pose: pose_of(&best.1), best: best.0, iterations, start, history }
}

/// A small deterministic case for tests and examples: `n` points on a smooth 3-D curve
/// inside the unit ball (Q3.13), phase-shifted by `phase` and translated by `-shift` LSBs.
pub fn example_cloud(n: usize, shift: [i16; 3], phase: f64) -> Vec<crate::common::format::FxPoint> {
    (0..n)
        .map(|i| {
            let t = i as f64 * 0.37 + phase;
            let p = crate::common::format::point([0.6 * t.sin(), 0.5 * (1.7 * t).cos(), 0.4 * (0.5 * t).sin()]);
            [p[0] - shift[0], p[1] - shift[1], p[2] - shift[2]]
        })
        .collect()
}

/// `n` points of a smooth, asymmetric height field over a disc of radius 0.6 (golden-angle
/// sampling from `phase`), each less `shift` (LSB): a surface, so its normals are well
/// defined, for tests of the surface residual ([`crate::surface`]); `example_cloud` is a
/// space curve, whose normals are not.
pub fn example_surface(n: usize, shift: [i16; 3], phase: f64) -> Vec<crate::common::format::FxPoint> {
    (0..n)
        .map(|i| {
            let r = 0.6 * ((i as f64 + 0.5) / n as f64).sqrt();
            let a = i as f64 * 2.399_963 + phase;
            let (x, y) = (r * a.cos(), r * a.sin());
            let z = 0.06 * (9.0 * x).sin() * (7.0 * y + 0.4).cos() + 0.12 * x * y + 0.05 * y;
            let p = crate::common::format::point([x, y, z]);
            [p[0] - shift[0], p[1] - shift[1], p[2] - shift[2]]
        })
        .collect()
}

/// The configuration that goes with [`example_cloud`]: identity start, sigmas of 0.25 in
/// translation, 1.6% in scale, 1.4 degrees in angle, no thresholds.
pub fn example_config(particles: u16, iterations: u16, seed: u32) -> PfConfig {
    PfConfig {
        particles,
        iterations,
        temper_exp: 5,
        centre: [0, 0, 0, 1 << SCALE_FRAC, 0, 0, 0],
        sigma0: [1 << 17, 1 << 17, 1 << 17, 1 << 15, 1 << 16, 1 << 16, 1 << 16],
        floor: [1 << 10, 1 << 10, 1 << 10, 1 << 10, 1 << 9, 1 << 9, 1 << 9],
        seed,
        thr_cost: 0,
        thr_max: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_round_trips_and_checks() {
        let cfg = PfConfig {
            particles: 50,
            iterations: 40,
            temper_exp: 33,
            centre: [1, -2, 3, 1 << 21, -(1 << 23), 5, 6],
            sigma0: [100, 200, 300, 400, 500, 600, 700],
            floor: [1, 2, 3, 4, 5, 6, 7],
            seed: 0xdead_beef,
            thr_cost: (1 << 47) + 5,
            thr_max: (1 << 33) + 1,
        };
        let bytes = cfg.encode();
        assert_eq!(bytes.len(), RUN_BYTES);
        assert_eq!(PfConfig::decode(&bytes), Ok(cfg.clone()));
        assert_eq!(PfConfig::decode(&bytes[1..]), Err(ConfigError::Length(RUN_BYTES - 1)));
        let mut bad = bytes.clone();
        bad[0] = 0;
        bad[1] = 0;
        assert_eq!(PfConfig::decode(&bad), Err(ConfigError::Capacity(0, 40)));
    }

    #[test]
    fn the_filter_finds_a_shifted_cloud() {
        // A small model and the same points shifted: the filter must bring the cost down.
        let model = crate::search::grid::Grid::build(&example_cloud(60, [0, 0, 0], 0.0)).unwrap();
        let shift = 400i16;
        let scan = example_cloud(60, [shift, 0, 0], 0.0);
        let cfg = example_config(24, 15, 7);
        let out = run(&cfg, |pose| evaluate(&model, &scan, pose));
        assert!(out.best.cost * 20 < out.start.cost, "{} vs {}", out.best.cost, out.start.cost);
        // The translation found is near +shift (in Q5.13 coordinates: 400 LSB).
        let t = translation(out.params[0]);
        assert!((t - shift as i32).abs() < 80, "t {t}");
        let again = run(&cfg, |pose| evaluate(&model, &scan, pose));
        assert_eq!(out, again);
    }
}
