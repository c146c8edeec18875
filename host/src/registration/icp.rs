//! ICP (Algorithm 1): point-to-point, with scale, and the robust variants the paper
//! compares against (Welsch and Cauchy weights, Tables 4 and 5).
//!
//! Each iteration pairs every scan point, transformed by the current pose, with its
//! closest model point (k-d tree), then solves the weighted similarity from the *original*
//! scan points to those model points ([`svd_match::match_pairs`]). Solving in absolute
//! terms is the same as the paper's incremental update `R(k) = R* R(k-1)` and does not
//! accumulate rounding.

use crate::geometry::Pose;
use crate::nn::NearestNeighbours;
use crate::registration::svd_match::{match_pairs_within, ScaleRule};
use nalgebra::Point3;

/// Robust weighting of the residuals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Robust {
    /// Plain least squares (every pair weight 1).
    None,
    /// Welsch: `w = exp(-r^2 / (2 nu^2))`.
    Welsch,
    /// Cauchy: `w = 1 / (1 + r^2 / nu^2)`.
    Cauchy,
}

/// ICP settings. Distances are in the model's units.
#[derive(Clone, Copy, Debug)]
pub struct IcpSettings {
    /// Iteration cap (pose updates).
    pub max_iterations: usize,
    /// Stop when the MSD changes by less than this fraction between iterations.
    pub relative_tolerance: f64,
    /// Stop when the MSD is below this absolute threshold [units^2].
    pub msd_threshold: f64,
    /// Scale estimation rule.
    pub scale: ScaleRule,
    /// The interval the scale is kept in.
    pub scale_bounds: crate::geometry::ScaleBounds,
    /// Robust weight function.
    pub robust: Robust,
    /// Robust kernel width as a multiple of the median residual: `nu = k * median(r)`.
    pub robust_k: f64,
}

impl Default for IcpSettings {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            relative_tolerance: 1e-9,
            msd_threshold: 0.0,
            scale: ScaleRule::LeastSquares,
            scale_bounds: crate::geometry::ScaleBounds::FREE,
            robust: Robust::None,
            robust_k: 2.0,
        }
    }
}

impl IcpSettings {
    /// Settings for the Welsch-weighted variant.
    pub fn welsch() -> Self {
        Self { robust: Robust::Welsch, robust_k: 2.0, ..Self::default() }
    }
    /// Settings for the Cauchy-weighted variant.
    pub fn cauchy() -> Self {
        Self { robust: Robust::Cauchy, robust_k: 1.0, ..Self::default() }
    }
}

/// What a registration returns.
#[derive(Clone, Debug)]
pub struct Registration {
    /// Pose mapping scan to model.
    pub pose: Pose,
    /// Mean squared closest-point distance of the transformed scan, at `pose`.
    pub msd: f64,
    /// Iterations run.
    pub iterations: usize,
    /// MSD at the start of each iteration, then at the final pose.
    pub errors: Vec<f64>,
}

/// Changes in MSD below this are rounding noise (units^2).
const MSD_FLOOR: f64 = 1e-24;

/// Median of a slice (copied; `0.0` if empty).
pub(crate) fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    *m
}

/// Robust weights for residual lengths `r` (not squared).
pub(crate) fn robust_weights(r: &[f64], robust: Robust, k: f64) -> Option<Vec<f64>> {
    if robust == Robust::None {
        return None;
    }
    let nu = (k * median(r)).max(1e-12);
    let nu2 = nu * nu;
    Some(
        r.iter()
            .map(|&ri| match robust {
                Robust::Welsch => (-(ri * ri) / (2.0 * nu2)).exp(),
                Robust::Cauchy => 1.0 / (1.0 + ri * ri / nu2),
                Robust::None => 1.0,
            })
            .collect(),
    )
}

/// Mean squared closest-point distance of `scan` under `pose`.
pub fn msd(nn: &NearestNeighbours, scan: &[Point3<f64>], pose: &Pose) -> f64 {
    nn.sum_dist2(&pose.apply_all(scan)) / scan.len() as f64
}

/// Run ICP from `init`.
pub fn icp(nn: &NearestNeighbours, scan: &[Point3<f64>], init: &Pose, settings: &IcpSettings) -> Registration {
    let model = nn.points();
    let mut pose = *init;
    let mut errors: Vec<f64> = Vec::with_capacity(settings.max_iterations + 1);
    let mut iterations = 0;
    let mut targets = Vec::with_capacity(scan.len());
    loop {
        let closest = nn.closest_all(&pose.apply_all(scan));
        let e = closest.iter().map(|c| c.dist2).sum::<f64>() / scan.len() as f64;
        let converged = match errors.last() {
            Some(&prev) => (prev - e).abs() <= settings.relative_tolerance * prev + MSD_FLOOR,
            None => false,
        };
        errors.push(e);
        if converged || e <= settings.msd_threshold || iterations >= settings.max_iterations {
            return Registration { pose, msd: e, iterations, errors };
        }
        targets.clear();
        targets.extend(closest.iter().map(|c| model[c.index]));
        let r: Vec<f64> = closest.iter().map(|c| c.dist2.sqrt()).collect();
        let w = robust_weights(&r, settings.robust, settings.robust_k);
        match match_pairs_within(scan, &targets, w.as_deref(), settings.scale, &settings.scale_bounds) {
            Some(next) => pose = next,
            None => return Registration { pose, msd: e, iterations, errors },
        }
        iterations += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_support::spiral as curve;

    #[test]
    fn converges_from_a_near_start() {
        let model = curve(400);
        let truth = Pose::from_params(&[0.2, -0.1, 0.05, 0.9, 0.05, -0.04, 0.08]);
        let scan = truth.inverse().apply_all(&model);
        let nn = NearestNeighbours::new(&model);
        for s in [IcpSettings::default(), IcpSettings::welsch(), IcpSettings::cauchy()] {
            let r = icp(&nn, &scan, &Pose::identity(), &s);
            assert!(r.msd < 1e-12, "{:?}: msd {}", s.robust, r.msd);
            assert!(r.pose.rotation_angle_to(&truth) < 1e-5);
            assert!((r.pose.scale - truth.scale).abs() < 1e-6);
            assert!(r.errors.windows(2).all(|w| w[1] <= w[0] * (1.0 + 1e-9) + 1e-24), "{:?}", r.errors);
            assert_eq!(r.errors.len(), r.iterations + 1);
        }
    }

    #[test]
    fn iteration_cap_is_honoured() {
        let model = curve(200);
        let truth = Pose::from_params(&[1.0, 1.0, 0.0, 1.2, 0.3, 0.2, 0.5]);
        let scan = truth.inverse().apply_all(&model);
        let nn = NearestNeighbours::new(&model);
        let s = IcpSettings { max_iterations: 3, ..Default::default() };
        let r = icp(&nn, &scan, &Pose::identity(), &s);
        assert_eq!(r.iterations, 3);
    }

    #[test]
    fn robust_weights_downweight_far_points() {
        let r = [0.1, 0.1, 0.1, 5.0];
        for rb in [Robust::Welsch, Robust::Cauchy] {
            let w = robust_weights(&r, rb, 2.0).unwrap();
            assert!(w[3] < 0.1 * w[0], "{rb:?} {w:?}");
        }
        assert!(robust_weights(&r, Robust::None, 2.0).is_none());
    }
}
