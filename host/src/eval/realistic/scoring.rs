//! Scoring a case: the tolerance, the distance to the nearest symmetric copy of the truth,
//! and the calibration of the reported covariance (Mahalanobis distance, chi-square).

use super::cases::Case;
use crate::cloud::centroid;
use crate::geometry::Pose;
use nalgebra::{Matrix3, Point3};
use serde::Serialize;

/// Success tolerance of the benchmark.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Tolerance {
    /// Relative rotation [deg].
    pub rotation_deg: f64,
    /// Error at the scan's centroid over the model's diagonal.
    pub translation_frac: f64,
    /// Relative scale error.
    pub scale_frac: f64,
}

/// 2 deg, 2% of the diagonal, 1% scale.
pub const TOLERANCE: Tolerance = Tolerance { rotation_deg: 2.0, translation_frac: 0.02, scale_frac: 0.01 };

/// How far an estimate is from the nearest symmetric copy of the truth.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Score {
    /// Relative rotation [deg].
    pub rotation_deg: f64,
    /// Distance of the scan centroid's images over the diagonal.
    pub translation_frac: f64,
    /// `|s / s_true - 1|`.
    pub scale_frac: f64,
    /// Index of the symmetry (0: the identity) the errors are taken against.
    pub symmetry: usize,
    /// Within [`TOLERANCE`] of some symmetric copy.
    pub success: bool,
}

/// The truth composed with symmetry `g` (a rotation about `centre` in the model frame).
pub fn symmetric_truth(truth: &Pose, g: &Matrix3<f64>, centre: &Point3<f64>) -> Pose {
    let about = Pose { scale: 1.0, rotation: *g, translation: centre.coords - g * centre.coords };
    about.compose(truth)
}

/// The errors of `estimate` against `truth` as the tolerance measures them: relative
/// rotation [deg], distance of the images of `at` (the scan's centroid) over `diag`, and
/// relative scale.
pub fn pose_errors(estimate: &Pose, truth: &Pose, at: &Point3<f64>, diag: f64) -> (f64, f64, f64) {
    (
        estimate.rotation_angle_to(truth).to_degrees(),
        (estimate.apply(at) - truth.apply(at)).norm() / diag,
        (estimate.scale / truth.scale - 1.0).abs(),
    )
}

impl Tolerance {
    /// Whether errors from [`pose_errors`] are within the tolerance.
    pub fn accepts(&self, (rotation_deg, translation_frac, scale_frac): (f64, f64, f64)) -> bool {
        rotation_deg <= self.rotation_deg && translation_frac <= self.translation_frac && scale_frac <= self.scale_frac
    }
}

/// Score `estimate` on `case` (the rule of the module's doc).
pub fn score(estimate: &Pose, case: &Case) -> Score {
    let p = centroid(&case.scan);
    let mut best: Option<Score> = None;
    for (i, g) in case.shape.symmetries().iter().enumerate() {
        let e = pose_errors(estimate, &symmetric_truth(&case.truth, g, &case.shape.centre()), &p, case.diag);
        let s = Score {
            rotation_deg: e.0,
            translation_frac: e.1,
            scale_frac: e.2,
            symmetry: i,
            success: TOLERANCE.accepts(e),
        };
        let better = match &best {
            None => true,
            Some(b) => (s.success && !b.success) || (s.success == b.success && s.rotation_deg < b.rotation_deg),
        };
        if better {
            best = Some(s);
        }
    }
    best.expect("the identity is always a symmetry")
}

/// 95% quantile of the chi-square distribution with 7 degrees of freedom.
pub const CHI2_7_95: f64 = 14.067;
/// 95% quantiles of the chi-square distribution with 1 to 7 degrees of freedom.
pub const CHI2_95: [f64; 7] = [3.841, 5.991, 7.815, 9.488, 11.070, 12.592, CHI2_7_95];
/// Most cases a family.
pub const MAX_CASES: usize = 100_000;

/// Whether a squared Mahalanobis distance over `dof` parameters lies inside the 95% region.
pub fn inside_95(d2: f64, dof: usize) -> bool {
    dof > 0 && d2 <= CHI2_95[dof.min(7) - 1]
}

/// Squared Mahalanobis distance of `truth` from the conclusion's pose under its covariance,
/// over the determined parameters, and their number (`None` if the covariance is not
/// positive definite).
pub fn mahalanobis2(c: &crate::pf_icp::conclusion::Conclusion, truth: &Pose, at: &Point3<f64>) -> Option<(f64, usize)> {
    mahalanobis2_of(&c.pose, &c.uncertainty, truth, at)
}

/// [`mahalanobis2`] of any pose and its uncertainty (a tracked frame's).
pub fn mahalanobis2_of(
    pose: &Pose,
    u: &crate::pf_icp::conclusion::Uncertainty,
    truth: &Pose,
    at: &Point3<f64>,
) -> Option<(f64, usize)> {
    let e = pose.local_error(truth, at);
    // A parameter the user fixed (sigma 0, the scale under `--scale`) has no error to weigh.
    let k: Vec<usize> = (0..7).filter(|&i| u.sigma[i].is_some_and(|s| s > 0.0)).collect();
    let n = k.len();
    let m = nalgebra::DMatrix::from_fn(n, n, |a, b| u.covariance[k[a]][k[b]].unwrap_or(0.0));
    let v = nalgebra::DVector::from_fn(n, |a, _| e[k[a]]);
    let inv = m.cholesky()?.inverse();
    Some(((v.transpose() * inv * v)[(0, 0)], n))
}
