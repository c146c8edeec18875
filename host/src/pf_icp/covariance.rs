//! ICP covariance by clustering (Algorithm 5, Eq. 16 and 17).
//!
//! `n_C` subsets of the scan are drawn, each with one uniformly chosen point from every
//! scan cluster; ICP registers each subset to the whole model from the initial pose; the
//! mean and variance of the 7 parameters over the runs approximate the ICP estimate's
//! distribution. Angle differences are taken relative to the initial pose and wrapped, so
//! the mean never suffers from the +-180 degree seam. The variance of the runs' MSD is
//! the `Q` of the likelihood (Eq. 20).

use crate::geometry::{wrap_angle, Centred, Params, Pose};
use crate::nn::NearestNeighbours;
use crate::pf_icp::kmeans::Clustering;
use crate::registration::icp::{icp, IcpSettings};
use nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Mean and variance of the ICP parameters over the subsets.
#[derive(Clone, Debug)]
pub struct IcpCovariance {
    /// Mean of `[a, b, c, s, phi, theta, psi]` (angles in radians).
    pub mean: Params,
    /// Variance of each parameter (angles in rad^2).
    pub variance: Params,
    /// Mean of the subset runs' MSD.
    pub msd_mean: f64,
    /// Variance of the subset runs' MSD (the likelihood's `Q`).
    pub msd_variance: f64,
    /// Number of subsets (`n_C`).
    pub runs: usize,
    /// The pose each subset's ICP returned.
    pub poses: Vec<Pose>,
}

impl IcpCovariance {
    /// Standard deviation of each parameter.
    pub fn std_dev(&self) -> Params {
        self.variance.map(f64::sqrt)
    }

    /// Mean and variance of the runs' parameters in the `frame` parameterisation, angles
    /// unwrapped about `reference`'s.
    pub fn stats_in(&self, frame: &Centred, reference: &Pose) -> (Params, Params) {
        let p0 = frame.params(reference);
        let params: Vec<Params> = self
            .poses
            .iter()
            .map(|pose| {
                let mut p = frame.params(pose);
                for a in 4..7 {
                    p[a] = p0[a] + wrap_angle(p[a] - p0[a]);
                }
                p
            })
            .collect();
        mean_variance(&params)
    }
}

fn mean_variance(params: &[Params]) -> (Params, Params) {
    let n = params.len() as f64;
    let mut mean = [0.0; 7];
    for p in params {
        for i in 0..7 {
            mean[i] += p[i] / n;
        }
    }
    let mut variance = [0.0; 7];
    for p in params {
        for i in 0..7 {
            variance[i] += (p[i] - mean[i]).powi(2) / (n - 1.0).max(1.0);
        }
    }
    (mean, variance)
}

/// Algorithm 5: `subsets` ICP runs on one-point-per-cluster subsets of `scan`.
pub fn approximate_icp_variance(
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    clusters: &Clustering,
    init: &Pose,
    subsets: usize,
    seed: u64,
    settings: &IcpSettings,
) -> IcpCovariance {
    let subsets = subsets.max(2);
    let runs: Vec<(Pose, f64)> = (0..subsets)
        .into_par_iter()
        .map(|j| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (0x9e37_79b9_7f4a_7c15u64.wrapping_mul(j as u64 + 1)));
            let subset: Vec<Point3<f64>> =
                clusters.members.iter().map(|m| scan[m[rng.gen_range(0..m.len())]]).collect();
            let r = icp(nn, &subset, init, settings);
            (r.pose, r.msd)
        })
        .collect();
    let n = runs.len() as f64;
    let msd_mean = runs.iter().map(|r| r.1).sum::<f64>() / n;
    let msd_variance = runs.iter().map(|r| (r.1 - msd_mean).powi(2)).sum::<f64>() / (n - 1.0);
    let mut out = IcpCovariance {
        mean: [0.0; 7],
        variance: [0.0; 7],
        msd_mean,
        msd_variance,
        runs: runs.len(),
        poses: runs.into_iter().map(|r| r.0).collect(),
    };
    (out.mean, out.variance) = out.stats_in(&Centred::origin(), init);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::datasets::{make, ModelId, Sampling, ScanSpec};
    use crate::pf_icp::kmeans::{kmeans, KmeansSettings};

    #[test]
    fn spread_grows_with_noise_and_is_deterministic() {
        let id = ModelId::Model2;
        let truth = id.table1_truth();
        let mut spreads = Vec::new();
        for noise in [0.0, 0.1] {
            let ds =
                make(id, 800, &truth, &ScanSpec { sampling: Sampling::Independent { points: 800 }, noise, seed: 2 });
            let nn = NearestNeighbours::new(&ds.model);
            let cl = kmeans(&ds.scan, &KmeansSettings { k: 40, max_iterations: 50, seed: 1 });
            let s = IcpSettings { max_iterations: 30, ..Default::default() };
            let a = approximate_icp_variance(&nn, &ds.scan, &cl, &truth, 12, 7, &s);
            let b = approximate_icp_variance(&nn, &ds.scan, &cl, &truth, 12, 7, &s);
            assert_eq!(a.variance, b.variance);
            assert!(a.variance.iter().all(|v| v.is_finite() && *v >= 0.0));
            assert!(a.mean[6].is_finite());
            spreads.push(a.msd_mean);
        }
        assert!(spreads[1] > spreads[0], "{spreads:?}");
    }
}
