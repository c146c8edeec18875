//! The last stage of PF-ICP: the polish, the choice among the hypotheses, and what the
//! result says about itself (alternatives, uncertainty, fit).
//!
//! 1. **Polish and choice**: the filter's estimate and the best hypotheses of the global
//!    search ([`crate::pf_icp::hypotheses`]: the first [`ARBITRATED`] + 1, and any other within
//!    [`CANDIDATE_COST_FACTOR`] of the best's cost, [`MAX_CANDIDATES`] poses in all) are
//!    each polished on the scan ([`Surface::polish`]; on [`COMPARE_POINTS`] of a larger one,
//!    the winner then on all of it); the lowest tight cost in the scan's units wins
//!    ([`Evidence::tight_costs`]: 3 noise sigmas, points the model would hide from a known
//!    sensor at the cap). A filter that settled in a wrong basin loses to a hypothesis in
//!    the right one.
//! 2. **Alternatives** (ambiguity): every other polished hypothesis that differs from the
//!    answer by more than 5 deg, 2% of the diagonal at the scan's centroid or 2% in scale
//!    and fits as well within the noise: the mean of its per-point cost excess over the
//!    answer is below [`ALTERNATIVE_SIGMAS`] standard errors of that mean (a paired test
//!    over the same scan points). Neighbouring points' costs are correlated, so the test is
//!    liberal and a weakly resolved feature may hide an alternative; a cluster-robust
//!    standard error over spatial blocks was tried and dropped: a clearly seen small
//!    feature puts all the evidence in one block, and it then listed the flip of a block
//!    with a boss seen whole. An exactly symmetric shape lists its symmetric poses; a
//!    near-symmetric one whose breaking feature is clearly seen lists none. When some pose
//!    fits as well, the scan's ranking of the others is no firmer: every other polished
//!    pose the verdict's evidence rules would not rule out on its own
//!    ([`crate::pf_icp::verdict::not_ruled_out`]: explained share and hidden share) is
//!    listed after them (`fits_as_well` false), so that the truth is among the answer and
//!    its alternatives when a clutter blob over the breaking feature tipped the test (the
//!    verdict, `ambiguous` either way, does not change).
//! 3. **Uncertainty**: the covariance of the local parameters
//!    [`crate::pf_icp::surface::LOCAL_NAMES`] (translation of the scan centroid's image, scale,
//!    rotation vector in the model frame) is the cluster-robust (sandwich) covariance
//!    `k^2 H^-1 M H^-1` of the surface residuals ([`Surface::curvature`]: `H = J^T J`, `M`
//!    the residual gradients summed over spatial blocks, an eighth of the scan's diagonal
//!    wide, never below the independent residuals' `sigma^2 H^-1`), `k` =
//!    [`COVARIANCE_INFLATION`] (calibrated on the realistic benchmark's dev split,
//!    docs/global-registration.md, "Uncertainty"), plus the spread of where restarts of
//!    the polish about the answer end that fit as well ([`crate::pf_icp::probe`]: a bumpy
//!    surface's shallow minima a few degrees apart, which the curvature at one of them
//!    does not see); with the scale fixed, the scale is no parameter (its row and column
//!    0). Parameters the scan cannot determine are named, and their rows and
//!    columns are left out (`None`) instead of printed as a confident number.
//! 4. **Fit** (as Open3D's `fitness` and `inlier_rmse`, on the surface distance of
//!    [`Surface::distance2`] rather than to the nearest model point, so that it does not
//!    depend on the model's sampling): the fraction of scan points within
//!    [`INLIER_DISTANCE`] of the diagonal of the model's surface, and the RMS of their
//!    distances.
//! 5. **Verdict** ([`crate::pf_icp::verdict`]): the share of the scan explained within the
//!    noise, the share the model would hide from a known sensor, the alternatives, the
//!    undetermined parameters and the widest one-sigma values decide whether a robot may
//!    act on the pose.

use crate::cloud::{bbox_diagonal, centroid};
use crate::geometry::{Pose, ScaleBounds};
use crate::pf_icp::evidence::Evidence;
use crate::pf_icp::hypotheses::{same_pose, Hypothesis};
use crate::pf_icp::surface::{Contact, Curvature, Surface, COST_CAP};
use crate::pf_icp::verdict::{judge, Checks, Verdict};
use nalgebra::Point3;
use nalgebra::SMatrix;
use rayon::prelude::*;

/// Hypotheses polished and compared at the end besides the filter's estimate: the best
/// `ARBITRATED + 1`.
pub const ARBITRATED: usize = 6;
/// A pose is an alternative when its mean cost excess is below this many standard errors.
pub const ALTERNATIVE_SIGMAS: f64 = 2.0;
/// Inflation of the covariance (see the module doc): on the realistic benchmark's dev split
/// (camera-view and plane-cut families, seed 1) the truth lies in the 95% region of 96% of
/// the right results with 2.5 (76% of the camera views' with 1.5).
pub const COVARIANCE_INFLATION: f64 = 2.5;
/// Inlier distance of `fitness` and `inlier_rmse`, as a fraction of the model's diagonal.
pub const INLIER_DISTANCE: f64 = 0.02;
/// Hypotheses polished besides the best [`ARBITRATED`] for alternatives: those whose cost in
/// the search is within this factor of the best's (at most [`MAX_CANDIDATES`] in all).
pub const CANDIDATE_COST_FACTOR: f64 = 2.0;
/// Scan points the candidates are polished and compared on (every k-th point of a larger
/// scan; the winner is polished again on the whole scan).
pub const COMPARE_POINTS: usize = 20_000;
/// In a large registration ([`crate::pf_icp::is_large`]): scan points the candidates are
/// polished and compared on, against the search's model subsample (every k-th point of a
/// larger scan; as many as a small registration's scan typically has).
pub const LARGE_COMPARE_POINTS: usize = 2_000;
/// In a large registration: scan points the winner is polished on at the end, against the
/// whole model (every k-th point of a larger scan).
pub const FINAL_POLISH_POINTS: usize = 10_000;
/// In a large registration: most iterations of the winner's final polish. It starts
/// converged on the model subset's surface and settles on the whole model's in a few (on
/// model-1 at 1,000,000 model points in 2; its step then flipped between two sets of
/// contacts, 1e-5 rad, for the other 48 of 50).
pub const FINAL_POLISH_ITERATIONS: usize = 20;
/// The polish may change a candidate's scale by these factors at most (0.8 and 1.25: the
/// on-board polish's bounds, `pficp_fpga::polish::SCALE_DRIFT`).
pub const SCALE_DRIFT: (f64, f64) = {
    let (a, b) = pficp_fpga::polish::SCALE_DRIFT;
    (a as f64 / b as f64, b as f64 / a as f64)
};
/// Most poses polished at the end.
pub const MAX_CANDIDATES: usize = 16;

/// Another pose that fits as well.
#[derive(Clone, Copy, Debug)]
pub struct Alternative {
    /// Scan to model.
    pub pose: Pose,
    /// Its capped surface cost over the whole scan.
    pub cost: f64,
    /// Its mean cost excess over the answer, in standard errors.
    pub excess_sigmas: f64,
    /// It fits as well as the answer (the paired test); else it is only not ruled out
    /// (module doc, step 2).
    pub fits_as_well: bool,
}

/// The share of per-point tight costs below `cap2` (the cap: a point beyond the noise, or
/// hidden from the sensor).
pub fn explained_share(costs: &[f64], cap2: f64) -> f64 {
    costs.iter().filter(|&&c| c < cap2).count() as f64 / costs.len().max(1) as f64
}

/// The pose's uncertainty.
#[derive(Clone, Debug)]
pub struct Uncertainty {
    /// Covariance of [`LOCAL_NAMES`] (model units, scale, rad); `None` in the rows and
    /// columns of undetermined parameters.
    pub covariance: [[Option<f64>; 7]; 7],
    /// One-sigma values (`None`: undetermined).
    pub sigma: [Option<f64>; 7],
    /// The motions the scan does not determine, in words
    /// ([`crate::pf_icp::surface::Degeneracy::motions`]).
    pub undetermined: Vec<String>,
}

/// How well the scan fits.
#[derive(Clone, Copy, Debug)]
pub struct Fit {
    /// Fraction of scan points within `inlier_distance` of the model's surface.
    pub fitness: f64,
    /// RMS distance of those points.
    pub inlier_rmse: f64,
    /// The inlier distance used (model units).
    pub inlier_distance: f64,
    /// Capped surface cost of the answer over the whole scan.
    pub cost: f64,
}

/// The answer and what it says about itself.
#[derive(Clone, Debug)]
pub struct Conclusion {
    /// The chosen pose (scan to model).
    pub pose: Pose,
    /// Whether it came from a hypothesis rather than the filter's estimate.
    pub from_hypothesis: bool,
    /// Other poses that fit as well, best first.
    pub alternatives: Vec<Alternative>,
    /// Its uncertainty.
    pub uncertainty: Uncertainty,
    /// Its fit.
    pub fit: Fit,
    /// What the verdict was judged on.
    pub checks: Checks,
    /// Whether to act on the pose.
    pub verdict: Verdict,
    /// The verdict's reasons in words (empty for `confident`).
    pub reasons: Vec<String>,
}

/// The mean per-point cost excess of `other` over `best`, in standard errors of that mean
/// (a paired test over the same scan points).
pub fn paired_excess(best: &[f64], other: &[f64]) -> f64 {
    let n = best.len().max(2) as f64;
    let d: Vec<f64> = other.iter().zip(best).map(|(a, b)| a - b).collect();
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    mean / (var / n).sqrt().max(1e-300)
}

/// The poses polished and compared at the end (step 1 of the module doc): the filter's
/// first, then the search's first [`ARBITRATED`] + 1 hypotheses and any other within
/// [`CANDIDATE_COST_FACTOR`] of the best's cost, [`MAX_CANDIDATES`] in all.
pub fn candidates(filter_pose: &Pose, hypotheses: &[Hypothesis]) -> Vec<Pose> {
    let top = hypotheses.first().map_or(0.0, |h| h.cost);
    std::iter::once(*filter_pose)
        .chain(
            hypotheses
                .iter()
                .enumerate()
                .filter(|(i, h)| *i <= ARBITRATED || h.cost <= CANDIDATE_COST_FACTOR * top)
                .take(MAX_CANDIDATES - 1)
                .map(|(_, h)| h.pose),
        )
        .collect()
}

/// The uncertainty of a pose from its [`Surface::curvature`] (module doc, step 3): the
/// cluster-robust sandwich `H^-1 M H^-1`, never tighter than the independent residuals'
/// `sigma^2 H^-1`, inflated by [`COVARIANCE_INFLATION`], plus `spread` (the basin probe's;
/// zero without it); undetermined parameters named and left out.
pub fn uncertainty_of(curv: &Curvature, diag: f64, spread: &SMatrix<f64, 7, 7>) -> Uncertainty {
    let k2 = COVARIANCE_INFLATION * COVARIANCE_INFLATION;
    let inv = &curv.degeneracy.inverse;
    let sandwich = inv * curv.meat * inv;
    // (The residuals' variance floored at float precision: an exact answer's one sigma is
    // its rounding, not 0.)
    let independent = inv * curv.residual_variance.max((1e-9 * diag).powi(2));
    let cov = if sandwich.trace() > independent.trace() { sandwich } else { independent } * k2;
    let cov = cov + spread;
    // (A parameter whose variance is not a finite number is reported as undetermined: a
    // NaN must never print as a confident 0.)
    let mut undetermined = curv.degeneracy.motions.clone();
    if (0..7).any(|k| !curv.degeneracy.free[k] && !cov[(k, k)].is_finite()) {
        undetermined.push("any parameter (the covariance is not a finite number)".to_string());
    }
    let known = |k: usize| !curv.degeneracy.free[k] && cov[(k, k)].is_finite();
    let mut covariance = [[None; 7]; 7];
    let mut sigma = [None; 7];
    for a in 0..7 {
        if known(a) {
            sigma[a] = Some(cov[(a, a)].max(0.0).sqrt());
            for b in 0..7 {
                if known(b) {
                    covariance[a][b] = Some(cov[(a, b)]);
                }
            }
        }
    }
    Uncertainty { covariance, sigma, undetermined }
}

/// The fit (module doc, step 4) from the scan's contacts with the surface of a model of
/// diagonal `diag`.
pub fn fit_of(contacts: &[Contact], diag: f64) -> Fit {
    let cap = COST_CAP * diag;
    let inlier_distance = INLIER_DISTANCE * diag;
    let d: Vec<f64> = contacts.iter().map(|c| c.dist2.sqrt()).collect();
    let inliers: Vec<f64> = d.into_iter().filter(|&x| x <= inlier_distance).collect();
    Fit {
        fitness: inliers.len() as f64 / contacts.len().max(1) as f64,
        inlier_rmse: if inliers.is_empty() {
            0.0
        } else {
            (inliers.iter().map(|x| x * x).sum::<f64>() / inliers.len() as f64).sqrt()
        },
        inlier_distance,
        // (Surface::cost over the scan.)
        cost: contacts.iter().map(|c| c.dist2.min(cap * cap)).sum::<f64>() / contacts.len().max(1) as f64,
    }
}

/// The verdict's widest one-sigma values: rotation [deg], translation [fraction of the
/// diagonal], relative scale.
pub fn widest_sigma(sigma: &[Option<f64>; 7], diag: f64, scale: f64) -> [f64; 3] {
    let widest = |r: std::ops::Range<usize>, unit: f64| r.filter_map(|k| sigma[k]).fold(0.0f64, f64::max) / unit;
    [widest(4..7, 1f64.to_radians()), widest(0..3, diag), widest(3..4, scale)]
}

/// Conclude a registration: `filter_pose` from the filter, `hypotheses` of the search
/// (best first); every polish keeps the scale within `bounds`; `evidence` ranks the
/// candidates.
pub fn conclude(
    surface: &Surface,
    scan: &[Point3<f64>],
    filter_pose: &Pose,
    hypotheses: &[Hypothesis],
    polish_iterations: usize,
    bounds: &ScaleBounds,
    evidence: &Evidence,
) -> Conclusion {
    conclude_on(surface, evidence, surface, evidence, scan, filter_pose, hypotheses, polish_iterations, bounds)
}

/// [`conclude`] with the candidates polished and compared against `surface` (in a large
/// registration the search's model subset) by `evidence` (made for `surface`), and the
/// winner's final polish, its uncertainty, its fit and, in a large registration, the
/// verdict's share explained and share hidden against `full`, the whole model, by
/// `full_evidence` (made for `full`). In a large registration
/// ([`crate::pf_icp::is_large`]) the candidates are polished and compared on at most
/// [`LARGE_COMPARE_POINTS`] scan points and the winner is polished on at most
/// [`FINAL_POLISH_POINTS`]; the uncertainty and the fit still take every scan point.
#[allow(clippy::too_many_arguments)]
pub fn conclude_on(
    surface: &Surface,
    evidence: &Evidence,
    full: &Surface,
    full_evidence: &Evidence,
    scan: &[Point3<f64>],
    filter_pose: &Pose,
    hypotheses: &[Hypothesis],
    polish_iterations: usize,
    bounds: &ScaleBounds,
) -> Conclusion {
    let large = crate::pf_icp::is_large(full.nn().points().len(), scan.len());
    let nn = full.nn();
    let diag = bbox_diagonal(nn.points());
    let at = centroid(scan);
    // Every candidate starts inside the scale bounds (a fixed scale exactly).
    let starts: Vec<Pose> = candidates(filter_pose, hypotheses).iter().map(|p| bounds.apply(p, &at)).collect();
    // A polish whose scale runs away from its start is a collapse onto part of the model
    // (every one-sided cost rewards it): that candidate is dropped (the filter's estimate
    // stays, unpolished).
    // Candidates are polished and compared on at most COMPARE_POINTS scan points (every
    // k-th of a larger scan): memory and time stay bounded for huge scans.
    let stride = scan.len().div_ceil(if large { LARGE_COMPARE_POINTS } else { COMPARE_POINTS }).max(1);
    let compared: Vec<Point3<f64>> = scan.iter().step_by(stride).copied().collect();
    let mut polished: Vec<(Pose, Vec<f64>)> = starts
        .par_iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let q = surface.polish(&compared, p, polish_iterations, bounds);
            let ratio = q.scale / p.scale;
            let q = if (SCALE_DRIFT.0..=SCALE_DRIFT.1).contains(&ratio) {
                q
            } else if i == 0 {
                *p
            } else {
                return None;
            };
            let c = evidence.tight_costs(surface, &compared, &q);
            Some((q, c))
        })
        .collect();
    let mean = |c: &[f64]| c.iter().sum::<f64>() / c.len().max(1) as f64;
    let choose = |polished: &[(Pose, Vec<f64>)]| {
        (0..polished.len())
            .min_by(|&a, &b| mean(&polished[a].1).total_cmp(&mean(&polished[b].1)).then(a.cmp(&b)))
            .unwrap_or(0)
    };
    // The winner composed with the model's near-symmetries ([`crate::pf_icp::symmetry`]),
    // polished and compared as well: a near-symmetric part's other poses are weighed
    // whether or not the search held them.
    let first = polished[choose(&polished)].0;
    let symmetric: Vec<Pose> = crate::pf_icp::symmetry::near_symmetries(surface)
        .iter()
        .map(|g| bounds.apply(&g.compose(&first), &at))
        .filter(|p| !polished.iter().any(|(q, _)| same_pose(p, q, &at, diag)))
        .collect();
    polished.extend(
        symmetric
            .par_iter()
            .filter_map(|p| {
                let q = surface.polish(&compared, p, polish_iterations, bounds);
                (SCALE_DRIFT.0..=SCALE_DRIFT.1)
                    .contains(&(q.scale / p.scale))
                    .then(|| (q, evidence.tight_costs(surface, &compared, &q)))
            })
            .collect::<Vec<_>>(),
    );
    // Among the poses the tight cost cannot tell from the best (the best's alternatives,
    // below), the wide cost decides: a feature that misfits by more than the tight cap (a
    // notch, a boss, a keyway) costs the cap either way under the tight cost, but its
    // misfit's size still shows in the wide one.
    let best = {
        let first = choose(&polished);
        let tied: Vec<usize> = (0..polished.len())
            .filter(|&i| i == first || paired_excess(&polished[first].1, &polished[i].1) < ALTERNATIVE_SIGMAS)
            .collect();
        let wide: Vec<(usize, f64)> =
            tied.par_iter().map(|&i| (i, evidence.wide_cost(surface, &compared, &polished[i].0))).collect();
        wide.iter().min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0))).map_or(first, |w| w.0)
    };
    let (mut pose, costs) = (polished[best].0, polished[best].1.clone());
    if large {
        // The winner against the whole model, on every k-th scan point.
        let step = scan.len().div_ceil(FINAL_POLISH_POINTS).max(1);
        let fine: Vec<Point3<f64>> = scan.iter().step_by(step).copied().collect();
        let q = full.polish(&fine, &pose, polish_iterations.min(FINAL_POLISH_ITERATIONS), bounds);
        if (SCALE_DRIFT.0..=SCALE_DRIFT.1).contains(&(q.scale / pose.scale)) {
            pose = q;
        }
    } else if stride > 1 {
        // The winner on the whole scan.
        let q = surface.polish(scan, &pose, polish_iterations, bounds);
        if (SCALE_DRIFT.0..=SCALE_DRIFT.1).contains(&(q.scale / pose.scale)) {
            pose = q;
        }
    }
    let mut alternatives: Vec<Alternative> = Vec::new();
    for (i, (p, c)) in polished.iter().enumerate() {
        if i == best || same_pose(p, &pose, &at, diag) || alternatives.iter().any(|a| same_pose(&a.pose, p, &at, diag))
        {
            continue;
        }
        let z = paired_excess(&costs, c);
        if z < ALTERNATIVE_SIGMAS {
            alternatives.push(Alternative { pose: *p, cost: mean(c), excess_sigmas: z, fits_as_well: true });
        }
    }
    // A scan that cannot tell the answer from another pose cannot rank the rest either:
    // then every other polished pose the verdict's evidence checks would not rule out is
    // listed too, behind the ones that fit as well.
    let fit_as_well = alternatives.len();
    if fit_as_well > 0 {
        let cap2 = evidence.tight_cap * evidence.tight_cap;
        let others: Vec<Alternative> = polished
            .par_iter()
            .enumerate()
            .filter(|(i, (p, _))| {
                *i != best
                    && !same_pose(p, &pose, &at, diag)
                    && !alternatives.iter().any(|a| same_pose(&a.pose, p, &at, diag))
            })
            .filter_map(|(_, (p, c))| {
                let hidden = evidence.viewpoint.map(|v| {
                    crate::pf_icp::evidence::hidden(surface, &compared, p, &v).iter().filter(|&&h| h).count() as f64
                        / compared.len().max(1) as f64
                });
                crate::pf_icp::verdict::not_ruled_out(explained_share(c, cap2), hidden).then(|| Alternative {
                    pose: *p,
                    cost: mean(c),
                    excess_sigmas: paired_excess(&costs, c),
                    fits_as_well: false,
                })
            })
            .collect();
        for a in others {
            if !alternatives.iter().any(|b| same_pose(&a.pose, &b.pose, &at, diag)) {
                alternatives.push(a);
            }
        }
    }
    // Those that fit as well first, each kind best first.
    alternatives.sort_by(|a, b| b.fits_as_well.cmp(&a.fits_as_well).then(a.cost.total_cmp(&b.cost)));

    // Uncertainty: the curvature's, inflated. (The filter's last particle set is no
    // posterior: it spreads over the propagation region, a prior's width, and on an exact
    // answer it reported several degrees.)
    let image = pose.apply(&at);
    // One pass over the scan for the curvature and the fit.
    let contacts = full.contacts(scan, &pose);
    let curv = full.curvature_of(&contacts, &pose, &image, bounds.fixed_value().is_some());
    // The basin probe's spread: where restarts of the polish about the answer end that
    // fit the scan as well ([`crate::pf_icp::probe`]).
    let probe = crate::pf_icp::probe::probe(
        surface,
        evidence,
        &compared,
        &pose,
        &evidence.tight_costs(surface, &compared, &pose),
        polish_iterations,
        bounds,
        &at,
        diag,
        |best, other| paired_excess(best, other) < ALTERNATIVE_SIGMAS,
    );
    let uncertainty = uncertainty_of(&curv, diag, &probe.spread);
    let fit = fit_of(&contacts.1, diag);
    // The verdict's checks.
    // (In a large registration the answer's own, after its final polish, against the whole
    // model: a model subset's coarser surface leaves more of a scan outside the noise.)
    let (checked, evidence, costs) = if large {
        (full, full_evidence, full_evidence.tight_costs(full, &compared, &pose))
    } else {
        (surface, evidence, costs)
    };
    let cap2 = evidence.tight_cap * evidence.tight_cap;
    let explained = explained_share(&costs, cap2);
    let hidden = evidence.viewpoint.map(|v| {
        crate::pf_icp::evidence::hidden(checked, &compared, &pose, &v).iter().filter(|&&h| h).count() as f64
            / compared.len().max(1) as f64
    });
    let at_bound = |b: f64| b.is_finite() && (pose.scale / b - 1.0).abs() < 1e-9;
    let scale_at_bound = bounds.fixed_value().is_none() && (at_bound(bounds.lo) || at_bound(bounds.hi));
    let checks = Checks {
        explained,
        hidden,
        scale_at_bound,
        alternatives: fit_as_well,
        not_ruled_out: alternatives.len() - fit_as_well,
        undetermined: uncertainty.undetermined.clone(),
        widest_sigma: widest_sigma(&uncertainty.sigma, diag, pose.scale),
    };
    let (verdict, reasons) = judge(&checks);
    Conclusion { pose, from_hypothesis: best != 0, alternatives, uncertainty, fit, checks, verdict, reasons }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nn::NearestNeighbours;
    use crate::parts::Part;
    use crate::pf_icp::{register, PfIcpSettings};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn registered(model: &[Point3<f64>], scan_model: &[Point3<f64>], truth: &Pose) -> (Conclusion, Vec<Point3<f64>>) {
        let scan: Vec<Point3<f64>> = scan_model.iter().map(|p| truth.inverse().apply(p)).collect();
        let nn = NearestNeighbours::new(model);
        let r = register(&nn, &scan, &PfIcpSettings { seed: 3, ..Default::default() });
        (r.conclusion, scan)
    }

    /// A block (D2: four proper rotations) lists its three other symmetric poses, each the
    /// answer composed with a symmetry; the same block with a boss lists none.
    #[test]
    fn a_symmetric_shape_lists_its_symmetric_poses_and_an_asymmetric_one_none() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let truth = Pose::from_params(&[0.1, -0.05, 0.2, 1.1, 0.4, -0.3, 0.7]);
        let model = Part::Block.sample_surface(2000, &mut rng);
        let scan = Part::Block.sample_surface(1000, &mut rng);
        let (c, scan_pts) = registered(&model, &scan, &truth);
        let at = centroid(&scan_pts);
        assert_eq!(c.alternatives.len(), 3, "{:?}", c.alternatives);
        for a in &c.alternatives {
            let matched = Part::Block.symmetries().iter().skip(1).any(|g| {
                let copy = crate::eval::realistic::symmetric_truth(&c.pose, g, &Point3::origin());
                same_pose(&copy, &a.pose, &at, bbox_diagonal(&model))
            });
            assert!(matched, "an alternative that is no symmetric copy: {a:?}");
        }
        let model = Part::BlockBoss.sample_surface(2000, &mut rng);
        let scan = Part::BlockBoss.sample_surface(1000, &mut rng);
        let (c, _) = registered(&model, &scan, &truth);
        assert!(c.alternatives.is_empty(), "{:?}", c.alternatives);
        assert!(c.uncertainty.undetermined.is_empty());
        assert!(c.fit.fitness > 0.95, "{:?}", c.fit);
        assert!(
            c.uncertainty.sigma.iter().all(|s| s.is_some_and(|v| v.is_finite() && v > 0.0)),
            "{:?}",
            c.uncertainty.sigma
        );
    }
}

#[cfg(test)]
mod large_scan_tests {
    use super::*;
    use crate::nn::NearestNeighbours;
    use crate::parts::Part;
    use crate::pf_icp::{register, PfIcpSettings};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// A scan larger than COMPARE_POINTS is compared on a stride sample and polished in full:
    /// the pose is still right and the fit is taken over every point.
    #[test]
    fn a_scan_larger_than_the_comparison_sample_registers() {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let truth = Pose::from_params(&[0.05, 0.1, -0.1, 0.9, -0.3, 0.2, 0.5]);
        let model = Part::NearCubeNotch.sample_surface(2000, &mut rng);
        let scan: Vec<Point3<f64>> = Part::NearCubeNotch
            .sample_surface(COMPARE_POINTS + 5000, &mut rng)
            .iter()
            .map(|p| truth.inverse().apply(p))
            .collect();
        let nn = NearestNeighbours::new(&model);
        let r = register(&nn, &scan, &PfIcpSettings { seed: 2, ..Default::default() });
        let c = &r.conclusion;
        assert!(c.pose.rotation_angle_to(&truth).to_degrees() < 1.0, "{:?}", c.pose.euler_deg());
        assert!((c.pose.scale / truth.scale - 1.0).abs() < 0.01);
        assert!(c.alternatives.is_empty() && c.fit.fitness > 0.95);
    }
}
