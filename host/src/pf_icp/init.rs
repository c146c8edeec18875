//! The initial pose of PF-ICP (Algorithm 4 and Eq. 15): k-means on both clouds, pair the
//! clusters, SVD on the paired centroids.
//!
//! Two pairings (docs/algorithm.md, "Cluster pairing (Algorithm 4)"):
//! - [`Pairing::Index`], the paper's: cluster `i` of the scan with cluster `i` of the model.
//!   Valid when the scan is the model's own points in the same order.
//! - [`Pairing::Nearest`], for scans sampled independently of the model, where no index
//!   correspondence exists: candidate rotations from the principal axes of both clouds
//!   (sign flips, plus a sweep about an axis whose two partners have near-equal spread),
//!   centroids and the RMS-radius scale; each candidate is refined by ICP on the cluster
//!   centroids (each scan centroid paired with the nearest model centroid, SVD, repeat).
//!
//! With [`InitMode::Auto`] both are tried (Index only when the point counts match) and the
//! candidate with the lowest mean squared closest-point distance of the scan wins.

use crate::cloud::centroid;
use crate::geometry::Pose;
use crate::geometry::ScaleBounds;
use crate::nn::NearestNeighbours;
use crate::pf_icp::kmeans::{kmeans, kmeans_sampled, Clustering, KmeansSettings, Pairing};
use crate::registration::svd_match::{match_pairs_within, ScaleRule};
use nalgebra::{Matrix3, Point3, Rotation3, Unit, Vector3};
use rayon::prelude::*;

/// Which pairing to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitMode {
    /// Try both, keep the better.
    Auto,
    /// Only index pairing (paper setting).
    Index,
    /// Only geometric pairing (independent scans).
    Nearest,
}

impl InitMode {
    /// Every mode.
    pub const ALL: [InitMode; 3] = [InitMode::Auto, InitMode::Index, InitMode::Nearest];

    /// The CLI's name (`auto`, `index`, `nearest`).
    pub fn name(self) -> &'static str {
        match self {
            InitMode::Auto => "auto",
            InitMode::Index => "index",
            InitMode::Nearest => "nearest",
        }
    }

    /// Parse a CLI name.
    pub fn parse(s: &str) -> Option<InitMode> {
        InitMode::ALL.into_iter().find(|m| m.name() == s)
    }
}

impl std::fmt::Display for InitMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The result of the initialisation.
#[derive(Clone, Debug)]
pub struct InitialPose {
    /// The initial pose, scan to model.
    pub pose: Pose,
    /// The pairing that produced it.
    pub pairing: Pairing,
    /// Clusters of the scan (used again by the covariance estimate).
    pub scan_clusters: Clustering,
    /// Clusters of the model.
    pub model_clusters: Clustering,
    /// Mean squared closest-point distance of the cost sample at `pose`.
    pub cost: f64,
    /// Every candidate, in the order they were made (the pairings' poses after their
    /// centroid ICP), for the global search.
    pub candidates: Vec<Pose>,
}

/// Ratio of principal spreads under which two axes count as interchangeable.
const NEAR_EQUAL_SPREAD: f64 = 1.5;
/// Step of the sweep about an axis of near-symmetry [deg].
const SWEEP_STEP_DEG: f64 = 15.0;
/// Iterations of centroid ICP per candidate.
const CENTROID_ICP_ITERATIONS: usize = 15;

/// Principal axes (columns, descending spread) and spreads of a cloud.
fn principal_axes(points: &[Point3<f64>]) -> (Matrix3<f64>, Vector3<f64>) {
    let c = centroid(points);
    let mut cov = Matrix3::zeros();
    for p in points {
        let d = p - c;
        cov += d * d.transpose();
    }
    cov /= points.len() as f64;
    let eig = cov.symmetric_eigen();
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let axes = Matrix3::from_columns(&[
        eig.eigenvectors.column(idx[0]),
        eig.eigenvectors.column(idx[1]),
        eig.eigenvectors.column(idx[2]),
    ]);
    (axes, Vector3::new(eig.eigenvalues[idx[0]], eig.eigenvalues[idx[1]], eig.eigenvalues[idx[2]]).map(|v| v.max(0.0)))
}

/// Rotation candidates mapping the scan's principal frame onto the model's.
fn rotation_candidates(scan: &[Point3<f64>], model: &[Point3<f64>]) -> Vec<Matrix3<f64>> {
    let (em, sm) = principal_axes(scan);
    let (ed, sd) = principal_axes(model);
    let mut out = Vec::new();
    for signs in [[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]] {
        let flip = Matrix3::from_diagonal(&Vector3::from(signs));
        let mut r = ed * flip * em.transpose();
        if r.determinant() < 0.0 {
            // Principal frames of opposite handedness: flip the last model axis.
            let mut fix = Matrix3::identity();
            fix[(2, 2)] = -1.0;
            r = ed * fix * flip * em.transpose();
        }
        out.push(r);
        // Sweep about an axis whose two partners have near-equal spread (in either cloud).
        for axis in 0..3 {
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let near = |s: &Vector3<f64>| s[a.min(b)] <= NEAR_EQUAL_SPREAD * s[a.max(b)].max(1e-300);
            if near(&sm) || near(&sd) {
                let u = Unit::new_normalize(ed.column(axis).into_owned());
                let steps = (360.0 / SWEEP_STEP_DEG) as usize;
                for k in 1..steps {
                    let rot = Rotation3::from_axis_angle(&u, (k as f64 * SWEEP_STEP_DEG).to_radians());
                    out.push(rot.into_inner() * r);
                }
            }
        }
    }
    out
}

/// Refine `pose` by ICP between cluster centroids (nearest-centroid pairing).
fn centroid_icp(scan_c: &[Point3<f64>], model_nn: &NearestNeighbours, mut pose: Pose, bounds: &ScaleBounds) -> Pose {
    for _ in 0..CENTROID_ICP_ITERATIONS {
        let targets: Vec<Point3<f64>> =
            scan_c.iter().map(|m| model_nn.points()[model_nn.closest(&pose.apply(m)).index]).collect();
        match match_pairs_within(scan_c, &targets, None, ScaleRule::Ratio, bounds) {
            Some(p) => pose = p,
            None => break,
        }
    }
    pose
}

/// Compute the initial pose. `cost_sample` is the subset of scan points used to rank the
/// candidates against the model's k-d tree `nn`; every candidate's scale lies in `bounds`.
pub fn initial_pose(
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    cost_sample: &[Point3<f64>],
    clusters: usize,
    seed: u64,
    mode: InitMode,
    bounds: &ScaleBounds,
) -> InitialPose {
    initial_pose_for(nn, nn.points(), scan, cost_sample, clusters, seed, mode, bounds)
}

/// [`initial_pose`] for the model `model`, its candidates ranked on the k-d tree `nn`
/// (the model's own or, in a large registration, its search subsample:
/// [`crate::pf_icp::SEARCH_MODEL_POINTS`]). In a large registration
/// ([`crate::pf_icp::is_large`]) each cloud is clustered on a seeded subset of at most
/// [`crate::pf_icp::KMEANS_POINTS`] points, every point then assigned to its nearest
/// centroid ([`kmeans_sampled`]).
#[allow(clippy::too_many_arguments)]
pub fn initial_pose_for(
    nn: &NearestNeighbours,
    model: &[Point3<f64>],
    scan: &[Point3<f64>],
    cost_sample: &[Point3<f64>],
    clusters: usize,
    seed: u64,
    mode: InitMode,
    bounds: &ScaleBounds,
) -> InitialPose {
    let ks = KmeansSettings { k: clusters, max_iterations: 100, seed };
    let cluster = |points: &[Point3<f64>]| {
        if crate::pf_icp::is_large(model.len(), scan.len()) {
            kmeans_sampled(points, &ks, crate::pf_icp::KMEANS_POINTS)
        } else {
            kmeans(points, &ks)
        }
    };
    let (scan_clusters, model_clusters) = rayon::join(|| cluster(scan), || cluster(model));
    let cost = |p: &Pose| nn.sum_dist2(&p.apply_all(cost_sample)) / cost_sample.len() as f64;
    let mut candidates: Vec<(Pose, Pairing)> = Vec::new();
    if mode != InitMode::Nearest
        && scan.len() == model.len()
        && scan_clusters.centroids.len() == model_clusters.centroids.len()
    {
        if let Some(p) =
            match_pairs_within(&scan_clusters.centroids, &model_clusters.centroids, None, ScaleRule::Ratio, bounds)
        {
            candidates.push((p, Pairing::Index));
        }
    }
    if mode != InitMode::Index || candidates.is_empty() {
        let centroid_nn = NearestNeighbours::new(&model_clusters.centroids);
        let (mu_m, mu_d) = (centroid(scan), centroid(model));
        let s = bounds.clamp(crate::pf_icp::hypotheses::radius_ratio(scan, model));
        let starts: Vec<Pose> = rotation_candidates(scan, model)
            .into_iter()
            .map(|r| Pose { scale: s, rotation: r, translation: mu_d.coords - s * (r * mu_m.coords) })
            .collect();
        let refined: Vec<Pose> =
            starts.par_iter().map(|p| centroid_icp(&scan_clusters.centroids, &centroid_nn, *p, bounds)).collect();
        candidates.extend(refined.into_iter().map(|p| (p, Pairing::Nearest)));
    }
    let scored: Vec<(f64, usize)> = candidates.par_iter().enumerate().map(|(i, (p, _))| (cost(p), i)).collect();
    let (best_cost, best) = scored
        .into_iter()
        .filter(|(c, _)| c.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .unwrap_or((f64::INFINITY, 0));
    let (pose, pairing) = candidates.get(best).copied().unwrap_or((Pose::identity(), Pairing::Nearest));
    let candidates = candidates.into_iter().map(|(p, _)| p).collect();
    InitialPose { pose, pairing, scan_clusters, model_clusters, cost: best_cost, candidates }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::datasets::{make, ModelId, Sampling, ScanSpec};

    #[test]
    fn index_pairing_is_exact_in_the_paper_setting() {
        let id = ModelId::Model1;
        let ds = make(id, 600, &id.table1_truth(), &ScanSpec { sampling: Sampling::Paper, noise: 0.0, seed: 1 });
        let nn = NearestNeighbours::new(&ds.model);
        let init = initial_pose(&nn, &ds.scan, &ds.scan, 30, 5, InitMode::Auto, &ScaleBounds::FREE);
        assert_eq!(init.pairing, Pairing::Index);
        assert!(init.pose.rotation_angle_to(&ds.truth) < 1e-6);
        assert!((init.pose.scale - ds.truth.scale).abs() < 1e-9);
    }

    #[test]
    fn nearest_pairing_lands_near_the_truth_on_an_independent_scan() {
        let id = ModelId::Model2;
        let ds = make(
            id,
            1500,
            &id.table1_truth(),
            &ScanSpec { sampling: Sampling::Independent { points: 1200 }, noise: 0.0, seed: 3 },
        );
        let nn = NearestNeighbours::new(&ds.model);
        let init = initial_pose(&nn, &ds.scan, &ds.scan[..400], 60, 5, InitMode::Auto, &ScaleBounds::FREE);
        assert_eq!(init.pairing, Pairing::Nearest);
        assert!(init.pose.rotation_angle_to(&ds.truth).to_degrees() < 10.0, "{:?}", init.pose.euler_deg());
    }
}
