//! The global search behind PF-ICP's start: many start poses, each refined by a short
//! trimmed ICP with scale, ranked by the capped surface cost, distinct ones kept.
//!
//! The k-means start (Algorithm 4, [`crate::pf_icp::init`]) is one pose; on partial views and
//! near-symmetric parts it often sits in a wrong basin (a flip, a turn about a
//! near-symmetry axis) that a filter spread around it never leaves. So the start is the
//! best of many hypotheses:
//! - the k-means start itself, unrefined (exact in the paper's setting), and every
//!   candidate the k-means stage refined (principal-frame flips and sweeps);
//! - a uniform set of rotations ([`rotation_grid`], super-Fibonacci samples of SO(3)),
//!   each with the centroids' translation and the ratio of RMS radii as scale;
//! - with the sensor's position known, the same rotations as the sensor would see the
//!   model ([`view_starts`]: the scan's centroid on the centroid of the seen part);
//! - feature-based proposals ([`crate::pf_icp::features`]: FPFH correspondences, RANSAC), which
//!   the caller adds to the starts.
//!
//! Three passes of trimmed ICP, each on the best distinct survivors of the one before:
//! every start [`SearchSettings::screen_iterations`] on [`SearchSettings::screen_points`]
//! scan points (ratio scale, which cannot collapse), the best
//! [`SearchSettings::screen_keep`] [`SearchSettings::coarse_iterations`] more on
//! [`SearchSettings::coarse_points`], the best [`SearchSettings::keep`]
//! [`SearchSettings::fine_iterations`] more on [`SearchSettings::fine_points`]
//! (least-squares scale); with the scale free, the screen and coarse passes also run with
//! each start's own scale held, and their best [`SearchSettings::held_keep`] distinct
//! survivors join the fine pass (on a small cluttered view a free scale drifts 25 to 40%
//! into a wrong basin within the first passes, while the radius ratio is within a few
//! percent of the truth; docs/global-registration.md, "Held-scale branch"); ranked by the
//! wide cost in the scan's units ([`Evidence::wide_cost`]) over the whole cost sample;
//! every scale within the user's bounds. Poses
//! count as distinct when they differ by more than 5 deg, 2% of the diagonal at the scan's
//! centroid or 2% in scale; a scale outside half to twice the median start's (the radius
//! ratio) is a collapse and dropped (which also bounds the views it handles: a view so
//! small that the radius ratio is more than twice the true scale, about a tenth of an
//! elongated part, is out of reach).

use crate::cloud::centroid;
use crate::geometry::{Pose, ScaleBounds};
use crate::nn::NearestNeighbours;
use crate::pf_icp::evidence::Evidence;
use crate::pf_icp::surface::Surface;
use crate::registration::svd_match::{match_pairs_within, ScaleRule};
use nalgebra::{Matrix3, Point3, UnitQuaternion};
use rayon::prelude::*;

/// Search settings.
#[derive(Clone, Debug)]
pub struct SearchSettings {
    /// Rotations of the uniform set.
    pub grid: usize,
    /// Scan points of the first coarse pass (every start).
    pub screen_points: usize,
    /// Trimmed ICP iterations of the first pass.
    pub screen_iterations: usize,
    /// Distinct starts the first pass keeps.
    pub screen_keep: usize,
    /// Scan points of the coarse stage.
    pub coarse_points: usize,
    /// Trimmed ICP iterations per start.
    pub coarse_iterations: usize,
    /// Distinct hypotheses refined further.
    pub keep: usize,
    /// Scan points of the fine stage.
    pub fine_points: usize,
    /// Trimmed ICP iterations per kept hypothesis.
    pub fine_iterations: usize,
    /// Fraction of pairs kept by each trimmed ICP iteration (the closest ones).
    pub trim: f64,
    /// With the scale free: distinct survivors of the held-scale screen and coarse passes
    /// (each start keeps its own scale) added to the fine pass; 0 turns the branch off.
    pub held_keep: usize,
    /// A second, wider search when the evidence rules out the answer
    /// ([`crate::pf_icp::rescue`]).
    pub rescue: bool,
}

impl Default for SearchSettings {
    fn default() -> Self {
        Self {
            grid: 72,
            screen_points: 96,
            screen_iterations: 8,
            screen_keep: 48,
            coarse_points: 160,
            coarse_iterations: 12,
            keep: 16,
            fine_points: 300,
            fine_iterations: 20,
            trim: 0.85,
            held_keep: 8,
            rescue: true,
        }
    }
}

/// One hypothesis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hypothesis {
    /// Scan to model.
    pub pose: Pose,
    /// Its [`Surface::cost`] over the cost sample.
    pub cost: f64,
}

/// `n` rotations spread uniformly over SO(3) (Alexa's super-Fibonacci spiral,
/// CVPR 2022): deterministic, no seed.
pub fn rotation_grid(n: usize) -> Vec<Matrix3<f64>> {
    const PHI: f64 = std::f64::consts::SQRT_2;
    const PSI: f64 = 1.533_751_168_755_204_3;
    (0..n)
        .map(|i| {
            let s = i as f64 + 0.5;
            let (r, big_r) = ((s / n as f64).sqrt(), (1.0 - s / n as f64).sqrt());
            let (a, b) = (std::f64::consts::TAU * s / PHI, std::f64::consts::TAU * s / PSI);
            let q = nalgebra::Quaternion::new(big_r * b.cos(), r * a.sin(), r * a.cos(), big_r * b.sin());
            UnitQuaternion::from_quaternion(q).to_rotation_matrix().into_inner()
        })
        .collect()
}

/// Trimmed ICP: each iteration pairs every point with its closest model point and solves
/// the similarity over the `trim` fraction of closest pairs, its scale within `bounds`.
pub fn trimmed_icp(
    nn: &NearestNeighbours,
    points: &[Point3<f64>],
    start: &Pose,
    iterations: usize,
    trim: f64,
    rule: ScaleRule,
    bounds: &ScaleBounds,
) -> Pose {
    let model = nn.points();
    let mut pose = *start;
    let keep = ((points.len() as f64 * trim).ceil() as usize).clamp(3.min(points.len()), points.len());
    let mut d2: Vec<f64> = Vec::with_capacity(points.len());
    for _ in 0..iterations {
        let closest: Vec<_> = points.iter().map(|p| nn.closest(&pose.apply(p))).collect();
        d2.clear();
        d2.extend(closest.iter().map(|c| c.dist2));
        let threshold = if keep < d2.len() {
            let (_, t, _) = d2.select_nth_unstable_by(keep - 1, f64::total_cmp);
            *t
        } else {
            f64::INFINITY
        };
        let weights: Vec<f64> = closest.iter().map(|c| if c.dist2 <= threshold { 1.0 } else { 0.0 }).collect();
        let targets: Vec<Point3<f64>> = closest.iter().map(|c| model[c.index]).collect();
        match match_pairs_within(points, &targets, Some(&weights), rule, bounds) {
            Some(next) if next.scale.is_finite() && next.scale > 0.0 => {
                // Converged: the pairs no longer move the pose (a fixed point of ICP).
                let still = next.rotation_angle_to(&pose) < 1e-6
                    && (next.scale / pose.scale - 1.0).abs() < 1e-9
                    && (next.translation - pose.translation).norm() <= 1e-9 * (1.0 + pose.translation.norm());
                pose = next;
                if still {
                    break;
                }
            }
            _ => break,
        }
    }
    pose
}

/// Whether two poses count as the same hypothesis: within 5 deg, 2% of `diag` at `at`
/// (the scan's centroid) and 2% in scale.
pub fn same_pose(a: &Pose, b: &Pose, at: &Point3<f64>, diag: f64) -> bool {
    a.rotation_angle_to(b).to_degrees() <= 5.0
        && (a.apply(at) - b.apply(at)).norm() <= 0.02 * diag
        && (a.scale / b.scale - 1.0).abs() <= 0.02
}

/// The distinct poses of `ranked` (sorted by cost), best first.
pub fn distinct(ranked: Vec<Hypothesis>, at: &Point3<f64>, diag: f64) -> Vec<Hypothesis> {
    let mut out: Vec<Hypothesis> = Vec::new();
    for h in ranked {
        if !out.iter().any(|k| same_pose(&k.pose, &h.pose, at, diag)) {
            out.push(h);
        }
    }
    out
}

/// The ratio of the clouds' RMS radii about their centroids: a scale guess (scan to
/// model), too large by up to about a third on a partial view.
pub fn radius_ratio(scan: &[Point3<f64>], model: &[Point3<f64>]) -> f64 {
    crate::cloud::rms_radius(model) / crate::cloud::rms_radius(scan).max(1e-300)
}

/// The start poses of the uniform set: each rotation with the centroids' translation and
/// the ratio of RMS radii as scale (moved into `bounds`).
pub fn grid_starts(scan: &[Point3<f64>], model: &[Point3<f64>], n: usize, bounds: &ScaleBounds) -> Vec<Pose> {
    let (mu_m, mu_d) = (centroid(scan), centroid(model));
    let s = bounds.clamp(radius_ratio(scan, model));
    rotation_grid(n)
        .into_iter()
        .map(|r| Pose { scale: s, rotation: r, translation: mu_d.coords - s * (r * mu_m.coords) })
        .collect()
}

/// Width of the view starts' pixels, in model spacings.
const VIEW_PIXEL_SPACINGS: f64 = 5.0;

/// The start poses as the sensor sees the part: for each rotation of the uniform set, the
/// model as a sensor in the scan's viewing direction (from `viewpoint` to the scan's
/// centroid, turned into the model's frame) would see it, the scan's centroid on the
/// centroid of that visible part and the ratio of their RMS radii as scale (moved into
/// `bounds`). A partial view's centroid lies on the seen side, not at the part's centre,
/// so these starts begin much nearer the truth than [`grid_starts`] on a one-sided view.
pub fn view_starts(
    surface: &Surface,
    scan: &[Point3<f64>],
    n: usize,
    bounds: &ScaleBounds,
    viewpoint: &Point3<f64>,
) -> Vec<Pose> {
    let model = surface.nn().points();
    let c_s = centroid(scan);
    let Some(toward) = (c_s - viewpoint).try_normalize(1e-300) else { return Vec::new() };
    let (lo, hi) = crate::cloud::bbox(model);
    let centre = nalgebra::center(&lo, &hi);
    let diag = (hi - lo).norm();
    let h = surface.spacing().max(1e-12 * diag);
    let scan_radius = crate::cloud::rms_radius(scan).max(1e-300);
    let distance = ((c_s - viewpoint).norm() * bounds.clamp(radius_ratio(scan, model))).max(diag);
    rotation_grid(n)
        .into_par_iter()
        .filter_map(|r| {
            let eye = centre - (r * toward) * distance;
            let view = crate::visibility::View::new(eye, &centre, VIEW_PIXEL_SPACINGS * h)?;
            let image = crate::visibility::DepthImage::new(view, model, 2.0 * VIEW_PIXEL_SPACINGS * h);
            let seen: Vec<Point3<f64>> =
                model.iter().filter(|p| image.sees(p, VIEW_PIXEL_SPACINGS * h)).copied().collect();
            if seen.len() < 3 {
                return None;
            }
            let c_v = centroid(&seen);
            let s = bounds.clamp(crate::cloud::rms_radius(&seen) / scan_radius);
            Some(Pose { scale: s, rotation: r, translation: c_v.coords - s * (r * c_s.coords) })
        })
        .collect()
}

/// Refine `starts` and return the distinct hypotheses, best first by the wide cost in the
/// scan's units ([`Evidence::wide_cost`]: a scan shrunk onto part of the model gains
/// nothing), empty when every one is implausible (the caller keeps its own start then). `exact` poses are ranked as they
/// are, without refinement. `sample` is the cost sample (a random subset of the scan, in
/// random order); distinctness is judged at its centroid. Every refined scale lies in
/// `bounds`; a pose outside them is implausible.
pub fn search(
    surface: &Surface,
    sample: &[Point3<f64>],
    exact: &[Pose],
    starts: &[Pose],
    settings: &SearchSettings,
    bounds: &ScaleBounds,
    evidence: &Evidence,
) -> Vec<Hypothesis> {
    let nn = surface.nn();
    let diag = crate::cloud::bbox_diagonal(nn.points());
    let at = centroid(sample);
    let coarse_pts = &sample[..settings.coarse_points.min(sample.len())];
    let fine_pts = &sample[..settings.fine_points.min(sample.len())];
    let screen_pts = &sample[..settings.screen_points.min(sample.len())];
    // The scale guess: the median start's (the grid's starts all carry the radius ratio).
    let s0 = {
        let mut v: Vec<f64> = starts.iter().map(|p| p.scale).filter(|s| s.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    // A scale far from the radii's ratio is a scan collapsed onto part of the model.
    let plausible = |h: &Hypothesis| {
        h.cost.is_finite()
            && bounds.contains(h.pose.scale)
            && (s0 == 0.0 || bounds.fixed_value().is_some() || (h.pose.scale > 0.5 * s0 && h.pose.scale < 2.0 * s0))
    };
    // One pass: trimmed ICP from each pose, ranked by the cost over `cost_pts`, implausible
    // scales dropped, best first. `held` keeps each pose's own scale.
    let pass = |from: &[Pose],
                pts: &[Point3<f64>],
                iterations: usize,
                rule: ScaleRule,
                cost_pts: &[Point3<f64>],
                held: bool| {
        let mut out: Vec<Hypothesis> = from
            .par_iter()
            .map(|s| {
                let within = if held { bounds.within(s.scale, s.scale) } else { *bounds };
                let pose = trimmed_icp(nn, pts, s, iterations, settings.trim, rule, &within);
                Hypothesis { pose, cost: evidence.wide_cost(surface, cost_pts, &pose) }
            })
            .collect();
        out.retain(plausible);
        out.sort_by(|a, b| a.cost.total_cmp(&b.cost));
        out
    };
    let best = |ranked: Vec<Hypothesis>, n: usize| -> Vec<Pose> {
        distinct(ranked, &at, diag).into_iter().take(n).map(|h| h.pose).collect()
    };
    // The screen and coarse passes (ratio scale), the best `n` distinct survivors.
    let coarse_stage = |held: bool, n: usize| {
        let screened = pass(starts, screen_pts, settings.screen_iterations, ScaleRule::Ratio, screen_pts, held);
        let coarse = pass(
            &best(screened, settings.screen_keep),
            coarse_pts,
            settings.coarse_iterations,
            ScaleRule::Ratio,
            coarse_pts,
            held,
        );
        best(coarse, n)
    };
    let mut fine_from = coarse_stage(false, settings.keep);
    if bounds.fixed_value().is_none() && settings.held_keep > 0 {
        let held = coarse_stage(true, settings.held_keep);
        let new: Vec<Pose> =
            held.into_iter().filter(|p| !fine_from.iter().any(|q| same_pose(p, q, &at, diag))).collect();
        fine_from.extend(new);
    }
    let mut fine = pass(&fine_from, fine_pts, settings.fine_iterations, ScaleRule::LeastSquares, sample, false);
    // The exact poses, unrefined, join the last ranking (a stable sort: ties keep the
    // refined ones first, as before).
    fine.extend(
        exact.iter().map(|p| Hypothesis { pose: *p, cost: evidence.wide_cost(surface, sample, p) }).filter(plausible),
    );
    fine.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    distinct(fine, &at, diag)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_covers_the_rotations() {
        let grid = rotation_grid(72);
        // Other rotations are all within 50 degrees of a grid rotation (the gap the coarse
        // stage's trimmed ICP has to close).
        for r in rotation_grid(500).iter().skip(1).step_by(7) {
            let best = grid
                .iter()
                .map(|g| ((g.transpose() * r).trace() - 1.0).clamp(-2.0, 2.0) / 2.0)
                .fold(-1.0f64, f64::max)
                .acos()
                .to_degrees();
            assert!(best < 50.0, "{best}");
        }
    }
}
