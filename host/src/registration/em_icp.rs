//! EM-ICP (Granger and Pennec 2002, "Multi-scale EM-ICP: A Fast and Robust Approach for
//! Surface Registration"), extended from rigid motions to similarities.
//!
//! ICP's hard closest-point pairing is replaced by soft correspondences. The scan point
//! `m_i` is a noisy observation of *some* model point `d_j`, with isotropic Gaussian
//! noise of standard deviation `sigma`; the unknown pairing is the hidden variable of an
//! EM algorithm:
//!
//! - **E-step**: with the current pose `x -> s R x + T`,
//!   `A_ij = exp(-|s R m_i + T - d_j|^2 / (2 sigma^2)) / sum_k exp(-|s R m_i + T - d_k|^2 / (2 sigma^2))`.
//!   The sums run over the [`EmIcpSettings::neighbours`] model points nearest to the
//!   transformed scan point (k-d tree), not over the whole model as in the paper; with
//!   `sigma` at most a few point spacings the neglected terms are negligible, and at large
//!   `sigma` the soft match is the (nearly uniform) mean of those `k` points.
//! - **M-step**: minimising `sum_ij A_ij |s R m_i + T - d_j|^2` is the same as the weighted
//!   least-squares similarity from `m_i` to the barycentre `b_i = sum_j A_ij d_j`, with
//!   weight `sum_j A_ij = 1` for every scan point ([`PointWeight::Unit`], the paper's
//!   criterion). [`PointWeight::Mass`] instead weights each scan point by the unnormalised
//!   sum `sum_j exp(-|s R m_i + T - d_j|^2 / (2 sigma^2))`, which fades out scan points far
//!   from the model (outliers, missing overlap) but also, at small `sigma`, points that
//!   are merely between model samples. The M-step is solved by [`match_pairs`].
//! - **Annealing** (the multi-scale part): `sigma` starts large, which smooths the
//!   criterion and widens the basin of convergence, and is multiplied by
//!   [`EmIcpSettings::annealing`] after every iteration down to `sigma_final`, where the
//!   iterations continue until the MSD settles. At small `sigma` EM-ICP becomes ICP.
//!
//! `sigma_final` plays the role of the paper's final noise level (its experiments end at
//! a variance of 0.1 mm on their data); it is exposed in model units as
//! [`EmIcpSettings::sigma_final`].

use crate::cloud::bbox_diagonal;
use crate::geometry::Pose;
use crate::nn::{Closest, NearestNeighbours};
use crate::registration::icp::Registration;
use crate::registration::svd_match::{match_pairs, ScaleRule};
use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

/// The M-step weight of each scan point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointWeight {
    /// Every scan point weighs 1 (normalised soft assignments; the paper's criterion).
    Unit,
    /// Each scan point weighs the unnormalised sum of its Gaussian weights, at most
    /// [`EmIcpSettings::neighbours`] (down-weights points far from the model).
    Mass,
}

/// EM-ICP settings. Distances are in the model's units; "diagonal" is the length of the
/// bounding-box diagonal of the scan times the start pose's scale (the scan's size in
/// model units).
#[derive(Clone, Copy, Debug)]
pub struct EmIcpSettings {
    /// Number `k` of nearest model points that share each scan point.
    pub neighbours: usize,
    /// Starting `sigma` [units]; `None` for `sigma0_fraction` x diagonal.
    pub sigma0: Option<f64>,
    /// Starting `sigma` as a fraction of the diagonal, when `sigma0` is `None`.
    pub sigma0_fraction: f64,
    /// Final `sigma` [units]; `None` for `sigma_final_fraction` x diagonal.
    pub sigma_final: Option<f64>,
    /// Final `sigma` as a fraction of the diagonal, when `sigma_final` is `None`.
    pub sigma_final_fraction: f64,
    /// Factor applied to `sigma` after each iteration (in `(0, 1]`).
    pub annealing: f64,
    /// Iteration cap (pose updates).
    pub max_iterations: usize,
    /// Once `sigma` has reached `sigma_final`, stop when the MSD changes by less than
    /// this fraction between iterations.
    pub relative_tolerance: f64,
    /// M-step weight of each scan point.
    pub weight: PointWeight,
    /// Scale estimation rule of the M-step.
    pub scale: ScaleRule,
}

impl Default for EmIcpSettings {
    fn default() -> Self {
        Self {
            neighbours: 8,
            sigma0: None,
            sigma0_fraction: 0.1,
            sigma_final: None,
            sigma_final_fraction: 0.002,
            annealing: 0.9,
            max_iterations: 100,
            relative_tolerance: 1e-9,
            weight: PointWeight::Unit,
            scale: ScaleRule::LeastSquares,
        }
    }
}

/// Below this many queries, the neighbour search runs on one thread.
const PARALLEL_MIN: usize = 512;

/// Changes in MSD below this are rounding noise (units^2).
const MSD_FLOOR: f64 = 1e-24;

/// The `k` nearest model points of every query (deterministic; parallel for big batches).
fn neighbours_all(nn: &NearestNeighbours, queries: &[Point3<f64>], k: usize) -> Vec<Vec<Closest>> {
    if queries.len() < PARALLEL_MIN {
        queries.iter().map(|q| nn.nearest_k(q, k)).collect()
    } else {
        queries.par_iter().map(|q| nn.nearest_k(q, k)).collect()
    }
}

/// E-step for one scan point: the barycentre of its neighbours under normalised Gaussian
/// weights, and the unnormalised weight sum. `inv_2s2 = 1 / (2 sigma^2)`.
fn soft_match(model: &[Point3<f64>], near: &[Closest], inv_2s2: f64) -> (Point3<f64>, f64) {
    let d0 = near[0].dist2;
    let mut wsum = 0.0;
    let mut acc = Vector3::zeros();
    for c in near {
        // Shifted by the nearest distance: the largest weight is exactly 1, no underflow.
        let w = (-(c.dist2 - d0) * inv_2s2).exp();
        wsum += w;
        acc += w * model[c.index].coords;
    }
    (Point3::from(acc / wsum), (-d0 * inv_2s2).exp() * wsum)
}

/// Run EM-ICP from `init`.
///
/// [`Registration::msd`] is the plain mean squared closest-point distance at the final
/// pose; [`Registration::errors`] holds that MSD at the start of each iteration, then at
/// the final pose (`errors.len() == iterations + 1`). It is not monotone while `sigma`
/// is large, since EM-ICP minimises a smoothed criterion.
pub fn em_icp(nn: &NearestNeighbours, scan: &[Point3<f64>], init: &Pose, settings: &EmIcpSettings) -> Registration {
    let model = nn.points();
    let n = scan.len();
    let mut pose = *init;
    let mut errors: Vec<f64> = Vec::with_capacity(settings.max_iterations + 1);
    if n == 0 {
        return Registration { pose, msd: 0.0, iterations: 0, errors: vec![0.0] };
    }
    let k = settings.neighbours.max(1);
    let diagonal = bbox_diagonal(scan) * init.scale.abs();
    let sigma_final = settings.sigma_final.unwrap_or(settings.sigma_final_fraction * diagonal);
    let sigma0 = settings.sigma0.unwrap_or(settings.sigma0_fraction * diagonal).max(sigma_final);
    let annealing = if settings.annealing > 0.0 && settings.annealing <= 1.0 { settings.annealing } else { 1.0 };
    let mut sigma = sigma0;
    // Whether the pose now in hand came from an M-step at sigma_final.
    let mut at_final = false;
    let mut iterations = 0;
    let mut targets: Vec<Point3<f64>> = Vec::with_capacity(n);
    let mut weights: Vec<f64> = Vec::with_capacity(n);
    loop {
        let near = neighbours_all(nn, &pose.apply_all(scan), k);
        let e = near.iter().map(|c| c[0].dist2).sum::<f64>() / n as f64;
        let converged = at_final
            && match errors.last() {
                Some(&prev) => (prev - e).abs() <= settings.relative_tolerance * prev + MSD_FLOOR,
                None => false,
            };
        errors.push(e);
        if converged || iterations >= settings.max_iterations {
            break;
        }
        // E-step. A zero or non-finite sigma degenerates to ICP's hard assignment.
        let inv_2s2 = 1.0 / (2.0 * sigma * sigma);
        targets.clear();
        weights.clear();
        for c in &near {
            if inv_2s2.is_finite() {
                let (b, mass) = soft_match(model, c, inv_2s2);
                targets.push(b);
                weights.push(mass);
            } else {
                targets.push(model[c[0].index]);
                weights.push(1.0);
            }
        }
        // M-step. If every mass underflowed, fall back to unit weights.
        let w = match settings.weight {
            PointWeight::Mass if weights.iter().any(|&w| w > 0.0) => Some(weights.as_slice()),
            _ => None,
        };
        match match_pairs(scan, &targets, w, settings.scale) {
            Some(next) => pose = next,
            None => break,
        }
        iterations += 1;
        at_final = sigma <= sigma_final;
        sigma = (sigma * annealing).max(sigma_final);
    }
    Registration { pose, msd: *errors.last().unwrap_or(&0.0), iterations, errors }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registration::icp::{icp, IcpSettings};
    use nalgebra::{Rotation3, Unit};
    use rand::{Rng, SeedableRng};

    use crate::test_support::spiral as curve;
    use crate::test_support::{assert_degenerate_scans, assert_deterministic, rot_deg, scale_err};

    fn random_unit(rng: &mut impl Rng) -> Vector3<f64> {
        Vector3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)).normalize()
    }

    /// Every second model point, mapped into the scan frame, plus uniform noise.
    fn scan_of(model: &[Point3<f64>], truth: &Pose, noise: f64, seed: u64) -> Vec<Point3<f64>> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let inv = truth.inverse();
        model
            .iter()
            .step_by(2)
            .map(|p| inv.apply(&(p + noise * random_unit(&mut rng) * rng.gen_range(0.0..1.0))))
            .collect()
    }

    /// A similarity whose rotation is `deg` degrees about a random axis.
    fn truth_at(deg: f64, rng: &mut impl Rng) -> Pose {
        let axis = Unit::new_normalize(random_unit(rng));
        Pose {
            scale: 1.05,
            rotation: Rotation3::from_axis_angle(&axis, deg.to_radians()).into_inner(),
            translation: Vector3::new(0.1, -0.05, 0.08),
        }
    }

    #[test]
    fn recovers_a_similarity_from_a_near_start() {
        let model = curve(400);
        let nn = NearestNeighbours::new(&model);
        let t = Pose::from_params(&[0.1, -0.08, 0.06, 1.08, 0.04, -0.03, 0.05]);
        let s = EmIcpSettings::default();
        let r = em_icp(&nn, &scan_of(&model, &t, 0.0, 1), &Pose::identity(), &s);
        assert!(rot_deg(&r.pose, &t) < 0.01, "{}", rot_deg(&r.pose, &t));
        assert!(scale_err(&r.pose, &t) < 1e-4);
        assert!((r.pose.translation - t.translation).norm() < 1e-3);
        assert!(r.iterations < s.max_iterations, "did not settle");
        assert_eq!(r.errors.len(), r.iterations + 1);
        assert_eq!(r.msd, *r.errors.last().unwrap());

        let r = em_icp(&nn, &scan_of(&model, &t, 0.02, 2), &Pose::identity(), &s);
        assert!(rot_deg(&r.pose, &t) < 0.5, "{}", rot_deg(&r.pose, &t));
        assert!(scale_err(&r.pose, &t) < 0.005, "{}", scale_err(&r.pose, &t));
    }

    #[test]
    fn from_20_degrees_at_least_as_good_as_icp() {
        let model = curve(400);
        let nn = NearestNeighbours::new(&model);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (mut em_total, mut icp_total) = (0.0, 0.0);
        for (trial, noise) in [0.0, 0.0, 0.0, 0.01, 0.01].into_iter().enumerate() {
            let t = truth_at(20.0, &mut rng);
            let scan = scan_of(&model, &t, noise, 10 + trial as u64);
            let e = em_icp(&nn, &scan, &Pose::identity(), &EmIcpSettings::default());
            let i = icp(&nn, &scan, &Pose::identity(), &IcpSettings::default());
            let (e_rot, i_rot) = (rot_deg(&e.pose, &t), rot_deg(&i.pose, &t));
            assert!(e_rot < 0.5, "trial {trial}: EM-ICP {e_rot} deg");
            assert!(scale_err(&e.pose, &t) < 0.005, "trial {trial}");
            assert!(e_rot <= i_rot + 0.05, "trial {trial}: EM-ICP {e_rot} deg, ICP {i_rot} deg");
            em_total += e_rot;
            icp_total += i_rot;
        }
        assert!(em_total <= icp_total, "{em_total} vs {icp_total}");
    }

    #[test]
    fn mass_weights_resist_outliers() {
        let model = curve(400);
        let nn = NearestNeighbours::new(&model);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let t = truth_at(10.0, &mut rng);
        let mut scan = scan_of(&model, &t, 0.0, 5);
        for p in scan.iter_mut().skip(2).step_by(5) {
            *p = Point3::from(random_unit(&mut rng) * rng.gen_range(1.5..3.0));
        }
        let s = EmIcpSettings { weight: PointWeight::Mass, ..Default::default() };
        let r = em_icp(&nn, &scan, &Pose::identity(), &s);
        assert!(rot_deg(&r.pose, &t) < 0.5, "{}", rot_deg(&r.pose, &t));
        assert!(scale_err(&r.pose, &t) < 0.005);
        let unit = em_icp(&nn, &scan, &Pose::identity(), &EmIcpSettings::default());
        assert!(rot_deg(&unit.pose, &t) > 1.0, "unit weights are not robust");
    }

    #[test]
    fn sigma_follows_the_data_scale() {
        let model = curve(300);
        let t = Pose::from_params(&[0.1, -0.08, 0.06, 1.08, 0.04, -0.03, 0.05]);
        let scan = scan_of(&model, &t, 0.0, 6);
        let k = 40.0;
        let big: Vec<_> = model.iter().map(|p| p * k).collect();
        let s = EmIcpSettings { max_iterations: 6, ..Default::default() };
        let a = em_icp(&NearestNeighbours::new(&model), &scan, &Pose::identity(), &s);
        let init = Pose { scale: k, ..Pose::identity() };
        let b = em_icp(&NearestNeighbours::new(&big), &scan, &init, &s);
        assert!(rot_deg(&a.pose, &t) > 1e-3, "not a trivial comparison");
        assert!(a.pose.rotation_angle_to(&b.pose) < 1e-9);
        assert!((b.pose.scale / (k * a.pose.scale) - 1.0).abs() < 1e-9);
        // Explicit sigmas in model units override the fractions.
        let explicit =
            EmIcpSettings { sigma0: Some(0.1), sigma_final: Some(0.1), max_iterations: 3, ..Default::default() };
        let c = em_icp(&NearestNeighbours::new(&model), &scan, &Pose::identity(), &explicit);
        assert!(c.pose.rotation_angle_to(&a.pose) > 1e-9);
    }

    #[test]
    fn deterministic() {
        let model = curve(400);
        let nn = NearestNeighbours::new(&model);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        let scan = scan_of(&model, &truth_at(20.0, &mut rng), 0.01, 9);
        let s = EmIcpSettings::default();
        assert_deterministic(|| em_icp(&nn, &scan, &Pose::identity(), &s));
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let model = curve(50);
        let nn = NearestNeighbours::new(&model);
        let s = EmIcpSettings::default();
        let r = assert_degenerate_scans(|scan| em_icp(&nn, scan, &Pose::identity(), &s));
        assert_eq!(r.iterations, 0);
        let zero_sigma = EmIcpSettings { sigma0: Some(0.0), sigma_final: Some(0.0), ..Default::default() };
        let r = em_icp(&nn, &model, &Pose::identity(), &zero_sigma);
        assert!(r.msd < 1e-20);
    }
}
