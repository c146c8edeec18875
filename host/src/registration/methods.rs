//! The registration methods the CLI and the experiments offer, behind one call.
//!
//! The baselines start where Algorithm 1 starts (identity: `R = I`, `T = 0`, `s = 1`) and
//! every baseline uses the paper's scale formula there (least squares collapses from a far start);
//! PF-ICP makes its own start from the clusters. All methods get the same clouds and
//! return the pose scan-to-model, the MSD over the whole scan, iterations and the error
//! per iteration.

use crate::geometry::Pose;
use crate::nn::NearestNeighbours;
use crate::pf_icp::{register, PfIcpResult, PfIcpSettings};
use crate::registration::em_icp::{em_icp, EmIcpSettings};
use crate::registration::icp::{icp, IcpSettings, Registration};
use crate::registration::sparse_icp::{sparse_icp, SparseIcpSettings};
use crate::registration::svd_match::ScaleRule;
use nalgebra::Point3;
use std::time::{Duration, Instant};

/// A registration method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// PF-ICP (Algorithm 6).
    PfIcp,
    /// Plain ICP (Algorithm 1).
    Icp,
    /// ICP with Welsch weights.
    Welsch,
    /// ICP with Cauchy weights.
    Cauchy,
    /// Sparse ICP (Bouaziz et al. 2013).
    SparseIcp,
    /// EM-ICP (Granger and Pennec 2002).
    EmIcp,
}

impl Method {
    /// Every method, PF-ICP first.
    pub const ALL: [Method; 6] =
        [Method::PfIcp, Method::Icp, Method::Welsch, Method::Cauchy, Method::SparseIcp, Method::EmIcp];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Method::PfIcp => "pf-icp",
            Method::Icp => "icp",
            Method::Welsch => "welsch",
            Method::Cauchy => "cauchy",
            Method::SparseIcp => "sparse-icp",
            Method::EmIcp => "em-icp",
        }
    }

    /// Parse a CLI name.
    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Settings shared by the methods.
#[derive(Clone, Debug)]
pub struct MethodSettings {
    /// PF-ICP's settings (its iteration cap is also the baselines' cap).
    pub pf: PfIcpSettings,
}

/// One method's answer.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Pose, MSD, iterations and errors.
    pub registration: Registration,
    /// Wall time.
    pub elapsed: Duration,
    /// PF-ICP's intermediate results (start, covariance, stage times), when it ran.
    pub pf: Option<Box<PfIcpResult>>,
}

/// ICP as a baseline (Sparse ICP and EM-ICP likewise): from the identity with the paper's scale formula (Algorithm 2's
/// ratio of spreads). The least-squares scale, exact for good pairs, collapses towards zero
/// from a far start (the scan shrinks onto a patch of the model and the MSD with it).
fn baseline(settings: IcpSettings, cap: usize, bounds: crate::geometry::ScaleBounds) -> IcpSettings {
    IcpSettings { max_iterations: cap, scale: ScaleRule::Ratio, scale_bounds: bounds, ..settings }
}

/// Run `method` on `scan` against the model behind `nn`.
pub fn run(method: Method, nn: &NearestNeighbours, scan: &[Point3<f64>], settings: &MethodSettings) -> Outcome {
    let start = Instant::now();
    let cap = settings.pf.iterations;
    let id = Pose::identity();
    let (registration, pf) = match method {
        Method::PfIcp => {
            let r = register(nn, scan, &settings.pf);
            (r.registration.clone(), Some(Box::new(r)))
        }
        Method::Icp => (icp(nn, scan, &id, &baseline(IcpSettings::default(), cap, settings.pf.scale)), None),
        Method::Welsch => (icp(nn, scan, &id, &baseline(IcpSettings::welsch(), cap, settings.pf.scale)), None),
        Method::Cauchy => (icp(nn, scan, &id, &baseline(IcpSettings::cauchy(), cap, settings.pf.scale)), None),
        Method::SparseIcp => (
            sparse_icp(
                nn,
                scan,
                &id,
                &SparseIcpSettings { max_iterations: cap, scale: ScaleRule::Ratio, ..Default::default() },
            ),
            None,
        ),
        Method::EmIcp => (
            em_icp(
                nn,
                scan,
                &id,
                &EmIcpSettings { max_iterations: cap, scale: ScaleRule::Ratio, ..Default::default() },
            ),
            None,
        ),
    };
    Outcome { registration, elapsed: start.elapsed(), pf }
}

/// The success test of the experiments: rotation within `deg`, translation within
/// `t_frac` of the model's diagonal, scale within `s_frac`.
#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    /// Rotation [deg].
    pub deg: f64,
    /// Translation as a fraction of the diagonal.
    pub t_frac: f64,
    /// Relative scale error.
    pub s_frac: f64,
}

impl Tolerance {
    /// The success-rate tolerance: 2 deg, 2% of the diagonal, 1% scale.
    pub const SUCCESS: Tolerance = Tolerance { deg: 2.0, t_frac: 0.02, s_frac: 0.01 };
    /// The paper-setting tolerance: 0.5 deg, 0.5% of the diagonal, 0.5% scale.
    pub const PAPER: Tolerance = Tolerance { deg: 0.5, t_frac: 0.005, s_frac: 0.005 };

    /// Whether `estimate` is within tolerance of `truth` for a model of diagonal `diag`:
    /// both the angle of the relative rotation and each Euler angle within `deg`.
    pub fn accepts(&self, estimate: &Pose, truth: &Pose, diag: f64) -> bool {
        let e = PoseError::between(estimate, truth, diag);
        e.rotation_deg <= self.deg
            && e.max_euler_deg <= self.deg
            && e.translation_frac <= self.t_frac
            && e.scale_frac <= self.s_frac
    }
}

/// How far an estimate is from the truth.
#[derive(Clone, Copy, Debug)]
pub struct PoseError {
    /// Angle of the relative rotation [deg].
    pub rotation_deg: f64,
    /// Largest error of the three Euler angles [deg].
    pub max_euler_deg: f64,
    /// Translation error over the model's diagonal.
    pub translation_frac: f64,
    /// Relative scale error.
    pub scale_frac: f64,
}

impl PoseError {
    /// Errors of `estimate` against `truth`.
    pub fn between(estimate: &Pose, truth: &Pose, diag: f64) -> PoseError {
        let (a, b) = (estimate.euler_deg(), truth.euler_deg());
        let max_euler_deg = (0..3)
            .map(|i| crate::geometry::wrap_angle((a[i] - b[i]).to_radians()).to_degrees().abs())
            .fold(0.0, f64::max);
        PoseError {
            rotation_deg: estimate.rotation_angle_to(truth).to_degrees(),
            max_euler_deg,
            translation_frac: (estimate.translation - truth.translation).norm() / diag,
            scale_frac: (estimate.scale / truth.scale - 1.0).abs(),
        }
    }
}
