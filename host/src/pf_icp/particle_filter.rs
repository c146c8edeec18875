//! The SIR particle filter (Algorithm 3) as PF-ICP runs it (Algorithm 6, steps 6 to 8),
//! over any state dimension: 7 states in 3-D, 4 in 2-D (Eq. 18, 19).
//!
//! One iteration:
//! 1. **Propagate**: every particle moves by a uniform step in `+-sigma_k` per state and is
//!    clamped into the propagation region `x_hat +- region_sigmas * sigma_k` (the first
//!    iteration draws uniformly over the whole region).
//! 2. **Weigh** (Eq. 20, 21; [`Objective::weigh`], in software unless the objective says
//!    otherwise): cost `c_i` (the MSD of the transformed scan),
//!    `w_i = exp(-(c_i - c_min) / (2 Q_k))`, normalised. Subtracting `c_min` only rescales
//!    the weights before normalisation (the hardware does the same). `Q_k` is the larger
//!    of the ICP variance `Q` and a sixth of the median cost excess `median(c_i - c_min)`:
//!    without that floor a noise-free `Q` near zero puts all weight on one particle.
//! 3. **Estimate** (Eq. 9): the weighted mean; angles by the circular mean, so that
//!    averaging never wraps wrongly.
//! 4. **Region update**: `sigma_{k+1}` is the weighted standard deviation of the particles
//!    about the estimate, kept between a floor and the initial sigma.
//! 5. **Refine** (optional): the objective may improve the estimate and the iteration's
//!    best particle (PF-ICP runs a few ICP iterations from each); the better of the
//!    results and the estimate is kept. The region is re-centred on the best state seen.
//! 6. **Resample**: systematic resampling (one uniform draw, `N` evenly spaced pointers
//!    along the CDF).
//! 7. **Stop** when the estimate's average and maximum point distances are under the
//!    thresholds, when the best cost has stalled (no fall of more than 0.1% for
//!    [`FilterSettings::patience`] iterations), or at the iteration cap. The best estimate
//!    seen is returned.
//!
//! The same seed gives the same result: the random draws are sequential from one
//! ChaCha8 stream; costs are evaluated in parallel but each is deterministic.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// What the filter optimises.
pub trait Objective: Sync {
    /// Number of states.
    fn dim(&self) -> usize;
    /// Whether state `i` is an angle (averaged on the circle).
    fn is_angle(&self, i: usize) -> bool;
    /// Cost of a state: the mean squared closest-point distance.
    fn cost(&self, x: &[f64]) -> f64;
    /// Average and maximum closest-point distance (not squared) at `x`, for the stop rule.
    fn distances(&self, x: &[f64]) -> (f64, f64);
    /// Optionally improve a state (e.g. ICP iterations); returns the new state and its cost.
    fn refine(&self, _x: &[f64]) -> Option<(Vec<f64>, f64)> {
        None
    }
    /// Bring a state back into its valid domain (e.g. positive scale).
    fn constrain(&self, _x: &mut [f64]) {}
    /// Costs and normalised weights (Eq. 20, 21) of one iteration's particles, `q` the
    /// filter's ICP variance. The default is [`weigh_in_software`]; an objective may get them
    /// elsewhere (PF-ICP with the board: `crate::board::host_driven`). An error stops the filter
    /// ([`try_run`]).
    fn weigh(&self, particles: &[Vec<f64>], q: f64) -> Result<Weighed, WeighError> {
        Ok(weigh_in_software(self, particles, q))
    }
}

/// Why a pluggable [`Objective::weigh`] failed (the software weights never fail).
pub type WeighError = Box<dyn std::error::Error + Send + Sync>;

/// One iteration's particle costs (the units of [`Objective::cost`]) and their normalised
/// weights.
#[derive(Clone, Debug, PartialEq)]
pub struct Weighed {
    /// Cost per particle.
    pub costs: Vec<f64>,
    /// Weight per particle, summing to 1.
    pub weights: Vec<f64>,
}

/// The lowest cost and its index (the first on ties).
pub fn lowest(costs: &[f64]) -> (usize, f64) {
    costs.iter().copied().enumerate().fold((0, f64::INFINITY), |a, (i, c)| if c < a.1 { (i, c) } else { a })
}

/// The tempered `Q_k = max(Q, median(c_i - c_min) / 6)` of one iteration's costs.
pub fn tempered_q(costs: &[f64], q: f64) -> f64 {
    let (_, cmin) = lowest(costs);
    let excess: Vec<f64> = costs.iter().map(|c| c - cmin).collect();
    q.max(crate::registration::icp::median(&excess) / 6.0).max(1e-300)
}

/// The software weights: `w_i = exp(-(c_i - c_min) / (2 Q_k))`, normalised.
pub fn software_weights(costs: &[f64], q: f64) -> Vec<f64> {
    let (_, cmin) = lowest(costs);
    let q_k = tempered_q(costs, q);
    let mut w: Vec<f64> = costs.iter().map(|c| (-(c - cmin) / (2.0 * q_k)).exp()).collect();
    let total: f64 = w.iter().sum();
    w.iter_mut().for_each(|x| *x /= total);
    w
}

/// The default [`Objective::weigh`]: every particle's cost (in parallel), then
/// [`software_weights`].
pub fn weigh_in_software<O: Objective + ?Sized>(obj: &O, particles: &[Vec<f64>], q: f64) -> Weighed {
    let costs: Vec<f64> = particles.par_iter().map(|x| obj.cost(x)).collect();
    let weights = software_weights(&costs, q);
    Weighed { costs, weights }
}

/// Particle-count adaptation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// Fewest particles.
    pub min: usize,
    /// Most particles.
    pub max: usize,
}

/// Filter settings.
#[derive(Clone, Debug)]
pub struct FilterSettings {
    /// Number of particles `n_p`.
    pub particles: usize,
    /// Iteration cap.
    pub iterations: usize,
    /// Half-width of the propagation region in sigmas (the paper's 2).
    pub region_sigmas: f64,
    /// The ICP variance `Q` of Eq. 20 [units^4, as the cost is a squared distance].
    pub q: f64,
    /// Smallest sigma per state.
    pub sigma_floor: Vec<f64>,
    /// Stop when the average distance is below this [units].
    pub threshold_avg: f64,
    /// ... and the maximum distance is below this [units].
    pub threshold_max: f64,
    /// Optional particle-count adaptation on the effective sample size.
    pub adaptive: Option<Adaptive>,
    /// Stop when the best cost has not fallen by more than 0.1% for this many iterations
    /// (`None`: only the thresholds and the cap stop the filter).
    pub patience: Option<usize>,
    /// Seed.
    pub seed: u64,
}

/// Per-iteration record.
#[derive(Clone, Debug, PartialEq)]
pub struct IterationRecord {
    /// Cost of the estimate after the iteration.
    pub cost: f64,
    /// Lowest particle cost this iteration.
    pub best_particle_cost: f64,
    /// Effective sample size `1 / sum W^2`.
    pub ess: f64,
    /// Particles used.
    pub particles: usize,
    /// Propagation sigma after the iteration.
    pub sigma: Vec<f64>,
    /// The estimate after the iteration (the state whose cost is `cost`).
    pub estimate: Vec<f64>,
}

/// Filter output.
#[derive(Clone, Debug)]
pub struct FilterResult {
    /// Best estimate seen.
    pub estimate: Vec<f64>,
    /// Its cost.
    pub cost: f64,
    /// Iterations run.
    pub iterations: usize,
    /// One record per iteration.
    pub history: Vec<IterationRecord>,
    /// Final particle set.
    pub particles: Vec<Vec<f64>>,
}

/// Systematic resampling: indices of the survivors for normalised `weights`, given one
/// uniform draw `u0` in `[0, 1)`.
pub fn systematic_resample(weights: &[f64], u0: f64, count: usize) -> Vec<usize> {
    let mut out = Vec::with_capacity(count);
    let mut cdf = weights.first().copied().unwrap_or(0.0);
    let mut i = 0;
    for j in 0..count {
        let u = (u0 + j as f64) / count as f64;
        while u > cdf && i + 1 < weights.len() {
            i += 1;
            cdf += weights[i];
        }
        out.push(i);
    }
    out
}

fn weighted_estimate(obj: &dyn Objective, particles: &[Vec<f64>], w: &[f64]) -> Vec<f64> {
    let dim = obj.dim();
    (0..dim)
        .map(|d| {
            if obj.is_angle(d) {
                let (s, c) = particles
                    .iter()
                    .zip(w)
                    .fold((0.0, 0.0), |(s, c), (p, &wi)| (s + wi * p[d].sin(), c + wi * p[d].cos()));
                s.atan2(c)
            } else {
                particles.iter().zip(w).map(|(p, &wi)| wi * p[d]).sum()
            }
        })
        .collect()
}

fn weighted_sigma(obj: &dyn Objective, particles: &[Vec<f64>], w: &[f64], centre: &[f64]) -> Vec<f64> {
    (0..obj.dim())
        .map(|d| {
            let v: f64 = particles
                .iter()
                .zip(w)
                .map(|(p, &wi)| {
                    let mut e = p[d] - centre[d];
                    if obj.is_angle(d) {
                        e = crate::geometry::wrap_angle(e);
                    }
                    wi * e * e
                })
                .sum();
            v.sqrt()
        })
        .collect()
}

/// Run the filter from `init` with initial standard deviations `sigma0`. Panics if the
/// objective's [`Objective::weigh`] fails (the software one never does): see [`try_run`].
pub fn run(obj: &dyn Objective, init: &[f64], sigma0: &[f64], settings: &FilterSettings) -> FilterResult {
    try_run(obj, init, sigma0, settings).unwrap_or_else(|e| panic!("particle weights failed: {e}"))
}

/// [`run`], stopping at the first error of the objective's [`Objective::weigh`].
pub fn try_run(
    obj: &dyn Objective,
    init: &[f64],
    sigma0: &[f64],
    settings: &FilterSettings,
) -> Result<FilterResult, WeighError> {
    let dim = obj.dim();
    assert_eq!(init.len(), dim);
    assert_eq!(sigma0.len(), dim);
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let floor = |d: usize| settings.sigma_floor.get(d).copied().unwrap_or(0.0);
    let sigma_cap: Vec<f64> = (0..dim).map(|d| sigma0[d].max(floor(d))).collect();
    let mut sigma = sigma_cap.clone();
    let mut centre = init.to_vec();
    let mut n = settings.particles.max(1);
    let half = |sigma: &[f64], d: usize| settings.region_sigmas * sigma[d];
    // First draw: uniform over the region.
    let mut particles: Vec<Vec<f64>> = (0..n)
        .map(|_| {
            let mut x: Vec<f64> = (0..dim).map(|d| centre[d] + half(&sigma, d) * rng.gen_range(-1.0..=1.0)).collect();
            obj.constrain(&mut x);
            x
        })
        .collect();
    let mut best = (obj.cost(init), init.to_vec());
    let mut history = Vec::with_capacity(settings.iterations);
    let mut iterations = 0;
    let (mut stalled, mut reference) = (0usize, best.0);
    for k in 0..settings.iterations {
        iterations = k + 1;
        if k > 0 {
            for x in particles.iter_mut() {
                for d in 0..dim {
                    let step = sigma[d] * rng.gen_range(-1.0..=1.0);
                    let lo = centre[d] - half(&sigma, d);
                    let hi = centre[d] + half(&sigma, d);
                    let mut v = x[d] + step;
                    if obj.is_angle(d) {
                        v = centre[d] + crate::geometry::wrap_angle(v - centre[d]);
                    }
                    x[d] = v.clamp(lo, hi);
                }
                obj.constrain(x);
            }
        }
        // Weigh.
        let Weighed { costs, weights: w } = obj.weigh(&particles, settings.q)?;
        if costs.len() != particles.len() || w.len() != particles.len() {
            return Err(
                format!("{} costs and {} weights for {} particles", costs.len(), w.len(), particles.len()).into()
            );
        }
        let (imin, cmin) = lowest(&costs);
        let ess = 1.0 / w.iter().map(|x| x * x).sum::<f64>();
        if cmin < best.0 {
            best = (cmin, particles[imin].clone());
        }
        // Estimate and region update.
        let mut estimate = weighted_estimate(obj, &particles, &w);
        obj.constrain(&mut estimate);
        let spread = weighted_sigma(obj, &particles, &w, &estimate);
        // Refine both the weighted estimate and this iteration's best particle: a particle
        // that landed in a better basin is carried to its minimum and becomes the centre.
        // (The estimate's cost and the two refinements run side by side; the choice below
        // takes them in this order.)
        let (mut est_cost, refined) = rayon::join(
            || obj.cost(&estimate),
            || rayon::join(|| obj.refine(&estimate), || obj.refine(&particles[imin])),
        );
        for (refined, c) in [refined.0, refined.1].into_iter().flatten() {
            if c < est_cost {
                estimate = refined;
                est_cost = c;
            }
        }
        if est_cost < best.0 {
            best = (est_cost, estimate.clone());
        }
        for d in 0..dim {
            sigma[d] = spread[d].clamp(floor(d), sigma_cap[d]);
        }
        centre = best.1.clone();
        history.push(IterationRecord {
            cost: est_cost,
            best_particle_cost: cmin,
            ess,
            particles: n,
            sigma: sigma.clone(),
            estimate: estimate.clone(),
        });
        let (avg, max) = obj.distances(&best.1);
        if avg < settings.threshold_avg && max < settings.threshold_max {
            break;
        }
        if best.0 < reference * (1.0 - 1e-3) {
            (stalled, reference) = (0, best.0);
        } else {
            stalled += 1;
        }
        if settings.patience.is_some_and(|p| stalled >= p) {
            break;
        }
        // Resample (and adapt the count).
        if let Some(a) = settings.adaptive {
            n = if ess < 0.1 * n as f64 {
                (2 * n).min(a.max)
            } else if ess > 0.5 * n as f64 {
                (n / 2).max(a.min)
            } else {
                n
            };
        }
        let picks = systematic_resample(&w, rng.gen_range(0.0..1.0), n);
        particles = picks.into_iter().map(|i| particles[i].clone()).collect();
    }
    Ok(FilterResult { estimate: best.1, cost: best.0, iterations, history, particles })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2-state bowl with a false minimum, for testing the filter alone.
    struct Bowl;
    impl Objective for Bowl {
        fn dim(&self) -> usize {
            2
        }
        fn is_angle(&self, i: usize) -> bool {
            i == 1
        }
        fn cost(&self, x: &[f64]) -> f64 {
            let a = (x[0] - 1.0).powi(2) + crate::geometry::wrap_angle(x[1] - 3.0).powi(2);
            let b = 0.3 + 0.5 * ((x[0] + 1.0).powi(2) + x[1].powi(2));
            a.min(b)
        }
        fn distances(&self, x: &[f64]) -> (f64, f64) {
            let c = self.cost(x).sqrt();
            (c, c)
        }
    }

    fn settings(seed: u64) -> FilterSettings {
        FilterSettings {
            particles: 60,
            iterations: 40,
            region_sigmas: 2.0,
            q: 0.0,
            sigma_floor: vec![1e-4, 1e-4],
            threshold_avg: 1e-3,
            patience: None,
            threshold_max: 1e-3,
            adaptive: None,
            seed,
        }
    }

    #[test]
    fn escapes_the_false_minimum_and_wraps_angles() {
        // Start in the false basin; 3.0 rad and -3.0 rad are close on the circle.
        let r = run(&Bowl, &[-1.0, -3.2], &[1.5, 1.5], &settings(1));
        assert!((r.estimate[0] - 1.0).abs() < 0.05, "{:?}", r.estimate);
        assert!(crate::geometry::wrap_angle(r.estimate[1] - 3.0).abs() < 0.05, "{:?}", r.estimate);
        assert!(r.iterations < 40, "threshold stop expected");
    }

    #[test]
    fn same_seed_same_result() {
        let a = run(&Bowl, &[0.0, 0.0], &[1.0, 1.0], &settings(9));
        let b = run(&Bowl, &[0.0, 0.0], &[1.0, 1.0], &settings(9));
        assert_eq!(a.estimate, b.estimate);
        assert_eq!(a.history, b.history);
    }

    #[test]
    fn systematic_resampling_follows_the_weights() {
        let w = [0.5, 0.0, 0.25, 0.25];
        assert_eq!(systematic_resample(&w, 0.5, 4), vec![0, 0, 2, 3]);
        let picks = systematic_resample(&[0.1, 0.9], 0.05, 10);
        assert_eq!(picks.iter().filter(|&&i| i == 1).count(), 9);
    }

    #[test]
    fn adaptive_count_stays_in_range() {
        let mut s = settings(3);
        s.adaptive = Some(Adaptive { min: 20, max: 120 });
        s.threshold_avg = 0.0;
        let r = run(&Bowl, &[0.5, 2.5], &[1.0, 1.0], &s);
        assert!(r.history.iter().all(|h| (20..=120).contains(&h.particles)));
    }
}
