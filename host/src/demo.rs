//! `pficp demo`: built-in model-1 registered twice, with PF-ICP and plain ICP against the
//! truth.
//!
//! 1. The paper's setting: the scan is the model's own 2,000 points, in order, under the
//!    Table 1 transform. Index pairing of the clusters makes PF-ICP's start exact, so it
//!    ends in one iteration; this is the paper's experiment, not a test of robustness.
//! 2. A realistic scan of the same model: [`REALISTIC_POINTS`] points sampled
//!    independently of the model's, [`VISIBLE`] of the surface seen from one side
//!    ([`crate::datasets::cut_view`]), Gaussian noise of [`NOISE_FRACTION`] of the
//!    diagonal per coordinate, shuffled, under the same transform. PF-ICP has to find the
//!    pose here; the demo also prints its one-sigma uncertainty and whether the truth lies
//!    inside its 95% region.
//!
//! Both are scored with the realistic benchmark's tolerance
//! ([`crate::eval::realistic::TOLERANCE`]: 2 deg, 2% of the diagonal, 1% scale).

use crate::cli::{pose_table, Assessment};
use crate::cloud::{bbox_diagonal, centroid};
use crate::datasets::{self, ModelId, Sampling, ScanSpec};
use crate::eval::realistic::{inside_95, mahalanobis2, pose_errors, TOLERANCE};
use crate::geometry::Pose;
use crate::nn::NearestNeighbours;
use crate::pf_icp::PfIcpSettings;
use crate::registration::methods::{self, Method, MethodSettings, Outcome};
use nalgebra::{Point3, Vector3};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Model points of both cases.
pub const MODEL_POINTS: usize = 2000;
/// Points of the realistic scan (after the cut).
pub const REALISTIC_POINTS: usize = 1000;
/// Visible fraction of the surface in the realistic scan.
pub const VISIBLE: f64 = 0.7;
/// Noise standard deviation per coordinate in the realistic scan, as a fraction of the
/// model's diagonal (the realistic benchmark's).
pub const NOISE_FRACTION: f64 = crate::eval::realistic::NOISE_FRACTION;
/// The side the realistic scan is seen from (the cut keeps the points lowest along it).
pub const VIEW_DIRECTION: [f64; 3] = [1.0, 0.5, 0.25];

/// One case of the demo: its clouds, the truth and both methods' outcomes.
pub struct DemoCase {
    /// What the case is, in one line.
    pub title: String,
    /// Scan points.
    pub scan_points: usize,
    /// Scan to model.
    pub truth: Pose,
    /// PF-ICP's outcome.
    pub pf_icp: Outcome,
    /// Plain ICP's outcome.
    pub icp: Outcome,
    /// The scan's centroid (where translation errors are measured).
    pub at: Point3<f64>,
    /// The model's bounding-box diagonal.
    pub diag: f64,
}

/// The realistic scan of model `id` (whose cloud is `model`) under `truth`, seeded: see
/// the module doc.
pub fn realistic_scan(id: ModelId, model: &[Point3<f64>], truth: &Pose, seed: u64) -> Vec<Point3<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let drawn = (REALISTIC_POINTS as f64 / VISIBLE).ceil() as usize;
    let mut view = id.sample_surface(drawn, &mut rng);
    datasets::cut_view(&mut view, &Vector3::from(VIEW_DIRECTION).normalize(), VISIBLE);
    view.shuffle(&mut rng);
    let noise = Normal::new(0.0, NOISE_FRACTION * bbox_diagonal(model)).expect("positive sigma");
    let inv = truth.inverse();
    view.iter()
        .map(|p| {
            let q = p.coords.map(|c| c + noise.sample(&mut rng));
            inv.apply(&Point3::from(q))
        })
        .collect()
}

fn case(title: String, model: &[Point3<f64>], scan: &[Point3<f64>], truth: Pose, seed: u64) -> DemoCase {
    let nn = NearestNeighbours::new(model);
    let settings = MethodSettings { pf: PfIcpSettings { seed, ..PfIcpSettings::default() } };
    DemoCase {
        title,
        scan_points: scan.len(),
        truth,
        pf_icp: methods::run(Method::PfIcp, &nn, scan, &settings),
        icp: methods::run(Method::Icp, &nn, scan, &settings),
        at: centroid(scan),
        diag: bbox_diagonal(model),
    }
}

/// Run both cases with `seed` (the realistic scan's and the methods').
pub fn run(seed: u64) -> Vec<DemoCase> {
    let id = ModelId::Model1;
    let truth = id.table1_truth();
    let paper = datasets::make(id, MODEL_POINTS, &truth, &ScanSpec { sampling: Sampling::Paper, noise: 0.0, seed });
    let scan = realistic_scan(id, &paper.model, &truth, seed);
    vec![
        case(
            format!(
                "the paper's setting: model-1, {MODEL_POINTS} points; the scan is the model's own points in order \
                 under the Table 1 transform (index pairing makes PF-ICP's start exact)"
            ),
            &paper.model,
            &paper.scan,
            truth,
            seed,
        ),
        case(
            format!(
                "a realistic scan of the same model: {REALISTIC_POINTS} points sampled independently, {:.0}% of the \
                 surface seen from one side, noise {:.1}% of the diagonal, shuffled, same transform (seed {seed})",
                100.0 * VISIBLE,
                100.0 * NOISE_FRACTION
            ),
            &paper.model,
            &scan,
            truth,
            seed,
        ),
    ]
}

impl DemoCase {
    /// Whether `outcome`'s pose is within the tolerance of the truth.
    pub fn success(&self, outcome: &Outcome) -> bool {
        TOLERANCE.accepts(self.errors(outcome))
    }

    /// `outcome`'s errors: rotation [deg], translation over the diagonal, relative scale.
    pub fn errors(&self, outcome: &Outcome) -> (f64, f64, f64) {
        pose_errors(&outcome.registration.pose, &self.truth, &self.at, self.diag)
    }

    /// Whether the truth lies inside PF-ICP's 95% region, with the squared Mahalanobis
    /// distance and the degrees of freedom (`None` when PF-ICP reported no covariance).
    pub fn truth_inside_95(&self) -> Option<(bool, f64, usize)> {
        let pf = self.pf_icp.pf.as_ref()?;
        let (d2, dof) = mahalanobis2(&pf.conclusion, &self.truth, &self.at)?;
        Some((inside_95(d2, dof), d2, dof))
    }

    /// The case as text: pose table, errors, MSD, iterations, time, PF-ICP's uncertainty.
    pub fn text(&self) -> String {
        let (pf, icp) = (&self.pf_icp, &self.icp);
        let mut s = format!("{}\n", self.title);
        s += &pose_table(&[("truth", &self.truth), ("pf-icp", &pf.registration.pose), ("icp", &icp.registration.pose)]);
        let row =
            |label: &str, f: &dyn Fn(&Outcome) -> String| format!("{label:<12}{:>14}{:>14}{:>14}\n", "", f(pf), f(icp));
        s += &row("rot err deg", &|o| format!("{:.3}", self.errors(o).0));
        s += &row("trans err %", &|o| format!("{:.3}", 100.0 * self.errors(o).1));
        s += &row("scale err %", &|o| format!("{:.3}", 100.0 * self.errors(o).2));
        s += &row("success", &|o| if self.success(o) { "yes" } else { "no" }.to_string());
        s += &row("MSD", &|o| format!("{:.3e}", o.registration.msd));
        s += &row("iterations", &|o| o.registration.iterations.to_string());
        s += &row("seconds", &|o| format!("{:.3}", o.elapsed.as_secs_f64()));
        if let Some(c) = pf.pf.as_ref().map(|r| &r.conclusion) {
            let a = Assessment::new(c);
            for line in a.verdict_line().lines().chain(a.text().lines()) {
                s += &format!("pf-icp  {line}\n");
            }
            match self.truth_inside_95() {
                Some((inside, d2, dof)) => {
                    s += &format!(
                        "pf-icp  truth        {} its 95% region (squared Mahalanobis distance {d2:.2}, {dof} dof)\n",
                        if inside { "inside" } else { "outside" }
                    )
                }
                None => s += "pf-icp  truth        no covariance for the truth to be judged against\n",
            }
        }
        s
    }
}

/// The whole demo's text: both cases and the tolerance.
pub fn text(cases: &[DemoCase]) -> String {
    let mut s = format!(
        "PF-ICP and plain ICP on built-in model-1 (K = {}, {} particles); success: within {} deg, {}% of the \
         diagonal (translation error at the scan's centroid) and {}% scale\n",
        PfIcpSettings::default().clusters,
        PfIcpSettings::default().particles,
        TOLERANCE.rotation_deg,
        100.0 * TOLERANCE.translation_frac,
        100.0 * TOLERANCE.scale_frac
    );
    for (i, c) in cases.iter().enumerate() {
        s += &format!("\n{}. {}", i + 1, c.text());
    }
    s
}
