//! One tracked frame: a short particle filter about the predicted pose, one short polish,
//! and the cheap part of the conclusion (no global search, no basin probe).
//!
//! 1. **Filter**: the SIR filter of [`crate::pf_icp::particle_filter`] over a
//!    [`LocalDelta`] from the prediction (translation of the scan centroid's image, relative
//!    scale, rotation vector: no Euler angles, so no gimbal lock at any pose), the prior's
//!    spread from [`super::motion::Motion::spread`], the particles weighed by the capped
//!    surface cost on a seeded sample of the scan.
//! 2. **Polish**: point-to-plane ICP ([`Surface::polish_weighted`], the inliers weighed as
//!    the budget says) from the filter's estimate on a seeded subset of the scan.
//! 3. **Checks**: the contacts of the scan give the uncertainty
//!    ([`crate::pf_icp::conclusion::uncertainty_of`], the curvature's sandwich, no probe),
//!    the fit, the share explained within the acquisition's noise and, with a viewpoint,
//!    the share hidden; the carried alternatives (a near-symmetric part's other poses,
//!    moved with the track) are weighed against the answer by the conclusion's paired test.

use crate::board::{BoardClient, BoardError};
use crate::geometry::{Pose, ScaleBounds};
use crate::pf_icp::conclusion::{fit_of, paired_excess, uncertainty_of, widest_sigma, Fit, Uncertainty};
use crate::pf_icp::evidence::Evidence;
use crate::pf_icp::hypotheses::same_pose;
use crate::pf_icp::particle_filter::{self, FilterSettings, Objective};
use crate::pf_icp::surface::{Surface, Weights, COST_CAP};
use crate::pf_icp::verdict::{judge, Checks, Verdict};
use crate::tracking::alternatives::{Carried, Decision, Tally};
use crate::tracking::board::{BoardFrame, BoardModel, FrameRequest, BOARD_POLISH_POINTS};
use crate::tracking::motion::{after, LocalDelta};
use nalgebra::{Point3, SMatrix};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// How much work a tracked frame does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameBudget {
    /// Particles of the frame's filter.
    pub particles: usize,
    /// Filter iterations.
    pub iterations: usize,
    /// Scan points each particle is weighed on.
    pub weight_points: usize,
    /// Scan points the polish runs on.
    pub polish_points: usize,
    /// Polish iterations.
    pub polish_iterations: usize,
    /// How the polish weighs its inliers.
    pub polish_weights: Weights,
}

/// The filter's objective: a [`LocalDelta`] after the prediction, about `at`.
struct DeltaObjective<'a> {
    surface: &'a Surface<'a>,
    sample: &'a [Point3<f64>],
    predicted: Pose,
    at: Point3<f64>,
    cap: f64,
    bounds: ScaleBounds,
}

impl DeltaObjective<'_> {
    fn pose(&self, x: &[f64]) -> Pose {
        after(&self.predicted, x, &self.at)
    }
}

impl Objective for DeltaObjective<'_> {
    fn dim(&self) -> usize {
        7
    }
    fn is_angle(&self, _i: usize) -> bool {
        // (A rotation vector's components are no angles on a circle; the spread keeps them
        // far below pi.)
        false
    }
    fn cost(&self, x: &[f64]) -> f64 {
        self.surface.cost(self.sample, &self.pose(x), self.cap)
    }
    fn distances(&self, x: &[f64]) -> (f64, f64) {
        let pose = self.pose(x);
        let (mut sum, mut max) = (0.0f64, 0.0f64);
        for p in self.sample {
            let d = self.surface.distance2(&pose.apply(p)).sqrt();
            sum += d;
            max = max.max(d);
        }
        (sum / self.sample.len().max(1) as f64, max)
    }
    fn constrain(&self, x: &mut [f64]) {
        let s = self.predicted.scale * (1.0 + x[3]);
        x[3] = self.bounds.clamp(s) / self.predicted.scale - 1.0;
    }
}

/// Where a tracked frame's filter runs.
pub enum FrameFilter<'a> {
    /// On the host.
    Host,
    /// On the board, by its bit-exact reference.
    BoardReference(&'a BoardModel),
    /// On the board behind the client (the model on it), polled every so often.
    Board(&'a BoardModel, &'a mut BoardClient, std::time::Duration),
}

/// What one tracked frame found.
#[derive(Clone, Debug)]
pub struct Local {
    /// The answer (scan to model).
    pub pose: Pose,
    /// Its uncertainty (curvature only).
    pub uncertainty: Uncertainty,
    /// Its fit.
    pub fit: Fit,
    /// What the verdict was judged on.
    pub checks: Checks,
    /// The verdict.
    pub verdict: Verdict,
    /// Its reasons.
    pub reasons: Vec<String>,
    /// The carried alternatives not ruled out, as model-frame maps `G` (the alternative
    /// is `G T`) with their evidence.
    pub alternatives: Vec<Carried>,
    /// A carried alternative became the answer: the answer is another pose of a
    /// near-symmetric part, not the predicted one moved.
    pub swapped: bool,
    /// With the filter on the board: its pose, the link's bytes and the run's clocks.
    pub board: Option<BoardFrame>,
    /// Wall time of the host's part after the filter (the polish, the alternatives, the
    /// checks) [s].
    pub host_seconds: f64,
}

/// `count` points of `scan` drawn with `seed` (all of them, shuffled, when fewer).
pub(crate) fn sample(scan: &[Point3<f64>], count: usize, seed: u64) -> Vec<Point3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    scan.choose_multiple(&mut rng, count.min(scan.len())).copied().collect()
}

/// Track one frame: the filter from `predicted` with standard deviations `spread`, the
/// polish, the checks; the scale within `bounds` (the track's), judged at a bound against
/// the user's `user_bounds`. `evidence` is the acquisition's (the sensor's noise), `symmetries`
/// the carried alternatives' model-frame maps, `seed` this frame's; `filter` says where the
/// frame's filter runs, and `frame_seconds` (the frame period) bounds the board's part of
/// it ([`FrameRequest`]). Only a board's failure is an error.
#[allow(clippy::too_many_arguments)]
pub fn track_frame(
    surface: &Surface,
    scan: &[Point3<f64>],
    predicted: &Pose,
    spread: &LocalDelta,
    bounds: &ScaleBounds,
    user_bounds: &ScaleBounds,
    evidence: &Evidence,
    symmetries: &[Carried],
    budget: &FrameBudget,
    frame_seconds: f64,
    seed: u64,
    filter: FrameFilter,
) -> Result<Local, BoardError> {
    let diag = crate::cloud::bbox_diagonal(surface.nn().points());
    let centroid = crate::cloud::centroid(scan);
    let at = predicted.apply(&centroid);
    let weighed = sample(scan, budget.weight_points, seed);
    // The board's polish goes over the filter's points and these (the board frame's doc).
    let polish_extra = match filter {
        FrameFilter::Host => Vec::new(),
        _ => sample(scan, BOARD_POLISH_POINTS.saturating_sub(weighed.len()), seed.wrapping_add(3)),
    };
    let board_request = FrameRequest {
        sample: &weighed,
        extra: &polish_extra,
        predicted,
        spread,
        bounds,
        frame_seconds,
        particles: budget.particles,
        iterations: budget.iterations,
        seed,
    };
    let objective =
        DeltaObjective { surface, sample: &weighed, predicted: *predicted, at, cap: COST_CAP * diag, bounds: *bounds };
    let floor: Vec<f64> = spread.iter().map(|s| 0.25 * s).collect();
    let settings = FilterSettings {
        particles: budget.particles,
        iterations: budget.iterations,
        region_sigmas: 2.0,
        q: 0.0,
        sigma_floor: floor,
        threshold_avg: 0.0,
        threshold_max: 0.0,
        adaptive: None,
        patience: None,
        seed: seed.wrapping_add(1),
    };
    let (filter_pose, board) = match filter {
        FrameFilter::Host => {
            (objective.pose(&particle_filter::run(&objective, &[0.0; 7], spread, &settings).estimate), None)
        }
        FrameFilter::BoardReference(b) => {
            let f = b.filter(&board_request);
            (f.pose, Some(f))
        }
        FrameFilter::Board(b, client, poll) => {
            let f = b.filter_on(client, &board_request, poll)?;
            (f.pose, Some(f))
        }
    };
    let host = std::time::Instant::now();
    // (Inside the track's scale bounds: the board's scale parameter holds a fixed scale to
    // its least step only, and a polish keeps a fixed scale where it starts.)
    let filter_pose = bounds.apply(&filter_pose, &centroid);
    let polished_on = sample(scan, budget.polish_points, seed.wrapping_add(2));
    let polish =
        |p: &Pose| surface.polish_weighted(&polished_on, p, budget.polish_iterations, bounds, budget.polish_weights);
    let mut pose = polish(&filter_pose);
    if !pose.scale.is_finite() || !bounds.contains(pose.scale) {
        pose = filter_pose;
    }

    // The carried alternatives: each `G T`, polished as the answer is, against the answer
    // over the same points (the conclusion's paired test), the evidence summed over the
    // frames ([`super::alternatives`]).
    let tight = |p: &Pose| evidence.tight_costs(surface, &polished_on, p);
    let mut costs = tight(&pose);
    let mut maps: Vec<Carried> = symmetries.to_vec();
    let mut kept: Vec<Carried> = Vec::new();
    let mut swaps = 0;
    // An alternative the frames clearly prefer becomes the answer (the old answer, clearly
    // behind, is dropped); one clearly behind the answer is dropped.
    while let Some(g) = maps.pop() {
        let other = polish(&g.map.compose(&pose));
        // (An alternative that polishes into the answer, or into one already kept, is no
        // other pose.)
        if same_pose(&other, &pose, &centroid, diag)
            || kept.iter().any(|h| same_pose(&other, &h.map.compose(&pose), &centroid, diag))
        {
            continue;
        }
        let c = tight(&other);
        let (tally, decision) = g.tally.after(paired_excess(&costs, &c));
        match decision {
            Decision::Swap if swaps < symmetries.len() => {
                swaps += 1;
                // The others relative to the new answer: an alternative `H T` is `(H B) T'`,
                // `B` the map from the new answer `T'` back to the old one; their evidence
                // was against the old answer, so it starts again.
                let back = pose.compose(&other.inverse());
                maps = maps
                    .iter()
                    .chain(&kept)
                    .map(|h| Carried { map: h.map.compose(&back), tally: Tally::default() })
                    .collect();
                kept.clear();
                pose = other;
                costs = c;
            }
            Decision::Drop => {}
            // (Kept as the map to the polished alternative.)
            _ => kept.push(Carried { map: other.compose(&pose.inverse()), tally }),
        }
    }
    let alternatives = kept;

    let contacts = surface.contacts(scan, &pose);
    let image = pose.apply(&centroid);
    let curv = surface.curvature_of(&contacts, &pose, &image, bounds.fixed_value().is_some());
    let uncertainty = uncertainty_of(&curv, diag, &SMatrix::zeros());
    let fit = fit_of(&contacts.1, diag);
    let cap2 = evidence.tight_cap * evidence.tight_cap;
    let s2 = pose.scale * pose.scale;
    let hidden_mask = evidence.viewpoint.map(|v| crate::pf_icp::evidence::hidden(surface, scan, &pose, &v));
    let explained = contacts
        .1
        .iter()
        .enumerate()
        .filter(|(i, c)| c.dist2 / s2 < cap2 && !hidden_mask.as_ref().is_some_and(|h| h[*i]))
        .count() as f64
        / scan.len().max(1) as f64;
    let hidden = hidden_mask.map(|h| h.iter().filter(|&&x| x).count() as f64 / scan.len().max(1) as f64);
    let at_bound = |b: f64| b.is_finite() && (pose.scale / b - 1.0).abs() < 1e-9;
    let checks = Checks {
        explained,
        hidden,
        scale_at_bound: user_bounds.fixed_value().is_none() && (at_bound(user_bounds.lo) || at_bound(user_bounds.hi)),
        alternatives: alternatives.len(),
        not_ruled_out: 0,
        undetermined: uncertainty.undetermined.clone(),
        widest_sigma: widest_sigma(&uncertainty.sigma, diag, pose.scale),
    };
    let (verdict, reasons) = judge(&checks);
    let host_seconds = host.elapsed().as_secs_f64();
    let swapped = swaps > 0;
    Ok(Local { pose, uncertainty, fit, checks, verdict, reasons, alternatives, swapped, board, host_seconds })
}
