//! The realistic benchmark (`pficp eval --suite realistic`): registration on shapes and
//! views nobody tuned for.
//!
//! **Shapes**: real scanned objects and CAD parts that public packages ship
//! ([`crate::real_shapes`], sources and licences in `host/data/realistic/SOURCES.md`) and
//! synthetic near-symmetric and exactly symmetric parts ([`crate::parts`]). Each shape is
//! either a development shape (tuning may look at it) or held out (looked at only to
//! report); the `dev` split draws only development shapes, the `test` split every shape,
//! with other seeds.
//!
//! **Families** ([`Family`]), each case under a random truth (scan to model):
//! - `real`: a real shape, a partial view (a plane cut keeping 60 to 80% of the surface,
//!   the kept side facing a random direction), Gaussian noise of 0.5% of the model's
//!   diagonal per coordinate, angles uniform in +-60 deg per axis, scale 0.7 to 1.3,
//!   translation in a ball of half the diagonal;
//! - `real-outliers`: the same plus 5% outliers (uniform in the view's bounding box grown
//!   by 10% of the diagonal);
//! - `parts`: a synthetic part, the whole surface sampled independently, 0.5% noise, the
//!   same transforms;
//! - `hard-180`: real shapes (partial) and parts (whole), any rotation (uniform on SO(3)).
//!
//! The model is 2,000 points of the surface, the scan about 1,000 points drawn
//! independently of them (disjoint points of a real shape's stored sample; fresh surface
//! samples of a part) before the cut, the noise and the outliers.
//!
//! **Scoring** ([`score`]): rotation within 2 deg (angle of the relative rotation),
//! translation within 2% of the diagonal, measured where it matters (the distance between
//! the scan's centroid mapped by the estimate and by the truth), scale within 1%. A shape
//! with exact symmetries is scored modulo its group: the case succeeds if the estimate is
//! within tolerance of any symmetric copy of the truth.
//!
//! Every case is a function of the seed, the split, the family and its index.

use super::text_table::TextTable;
use super::{median, mix};
use crate::cloud::{bbox_diagonal, centroid};
use crate::geometry::Pose;
use crate::methods::{run as run_method, Method, MethodSettings};
use crate::nn::NearestNeighbours;
use crate::parts::Part;
use crate::pf_icp::PfIcpSettings;
use crate::real_shapes::RealShape;
use anyhow::Context;
use nalgebra::{Matrix3, Point3, UnitQuaternion, Vector3};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Model points per case.
pub const MODEL_POINTS: usize = 2000;
/// Scan points per case (after the cut; the view is drawn from `SCAN_POINTS / visible`).
pub const SCAN_POINTS: usize = 1000;
/// Noise standard deviation per coordinate, as a fraction of the model's diagonal.
pub const NOISE_FRACTION: f64 = 0.005;
/// Outliers of the `real-outliers` family, as a fraction of the scan's points.
pub const OUTLIER_FRACTION: f64 = 0.05;
/// Visible fraction of a partial view.
pub const VISIBLE_RANGE: (f64, f64) = (0.6, 0.8);
/// Largest angle per axis of the `real` and `parts` families [deg].
pub const MAX_ANGLE_DEG: f64 = 60.0;
/// Scale range of the truths.
pub const SCALE_RANGE: (f64, f64) = (0.7, 1.3);

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

/// A case family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Family {
    /// Real shapes, partial views, noise.
    #[serde(rename = "real")]
    Real,
    /// The same with outliers.
    #[serde(rename = "real-outliers")]
    RealOutliers,
    /// Synthetic (near-)symmetric parts, whole surface, noise.
    #[serde(rename = "parts")]
    Parts,
    /// Any rotation, real shapes and parts.
    #[serde(rename = "hard-180")]
    Hard180,
}

impl Family {
    /// Every family, in report order.
    pub const ALL: [Family; 4] = [Family::Real, Family::RealOutliers, Family::Parts, Family::Hard180];

    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Family::Real => "real",
            Family::RealOutliers => "real-outliers",
            Family::Parts => "parts",
            Family::Hard180 => "hard-180",
        }
    }
}

/// Which shapes and seeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// Development shapes only, development seeds: what tuning may look at.
    Dev,
    /// Every shape (held-out ones included), other seeds: what is reported.
    Test,
}

impl Split {
    /// `dev` or `test`.
    pub fn name(self) -> &'static str {
        match self {
            Split::Dev => "dev",
            Split::Test => "test",
        }
    }
}

/// A shape of the benchmark.
#[derive(Clone, Copy, Debug)]
pub enum Shape {
    /// A real shape shipped by a public package.
    Real(&'static RealShape),
    /// A synthetic part.
    Part(Part),
}

impl Shape {
    /// Name in reports.
    pub fn name(&self) -> &'static str {
        match self {
            Shape::Real(s) => s.name,
            Shape::Part(p) => p.name(),
        }
    }

    /// Held out of tuning.
    pub fn held_out(&self) -> bool {
        match self {
            Shape::Real(s) => s.held_out,
            Shape::Part(p) => matches!(p, Part::FlangeKey | Part::ShaftFlat | Part::Plate),
        }
    }

    /// Rotations about [`Shape::centre`] mapping the shape onto itself, identity first.
    pub fn symmetries(&self) -> Vec<Matrix3<f64>> {
        match self {
            Shape::Real(s) => s.symmetries(),
            Shape::Part(p) => p.symmetries(),
        }
    }

    /// The centre of the symmetries (the origin of the shape's frame).
    pub fn centre(&self) -> Point3<f64> {
        Point3::origin()
    }

    /// `model` points and `scan` points of the surface, drawn independently of each other.
    fn draw(&self, model: usize, scan: usize, rng: &mut ChaCha8Rng) -> (Vec<Point3<f64>>, Vec<Point3<f64>>) {
        match self {
            Shape::Real(s) => {
                let pts = s.points();
                let mut idx: Vec<usize> = (0..pts.len()).collect();
                idx.shuffle(rng);
                let m = idx[..model].iter().map(|&i| pts[i]).collect();
                let d = idx[model..(model + scan).min(idx.len())].iter().map(|&i| pts[i]).collect();
                (m, d)
            }
            Shape::Part(p) => {
                let m = p.sample_surface(model, rng);
                (m, p.sample_surface(scan, rng))
            }
        }
    }
}

/// The shapes of a family in a split.
pub fn shapes(family: Family, split: Split) -> Vec<Shape> {
    let real = crate::real_shapes::all().iter().map(Shape::Real);
    let parts = Part::ALL.iter().map(|&p| Shape::Part(p));
    let all: Vec<Shape> = match family {
        Family::Real | Family::RealOutliers => real.collect(),
        Family::Parts => parts.collect(),
        Family::Hard180 => real.chain(parts).collect(),
    };
    all.into_iter().filter(|s| split == Split::Test || !s.held_out()).collect()
}

/// One benchmark case.
#[derive(Clone, Debug)]
pub struct Case {
    /// `family/shape/index`.
    pub id: String,
    /// Its family.
    pub family: Family,
    /// Its shape.
    pub shape: Shape,
    /// Seed of the case (and of the method run on it).
    pub seed: u64,
    /// Model cloud.
    pub model: Vec<Point3<f64>>,
    /// Scan cloud.
    pub scan: Vec<Point3<f64>>,
    /// Scan to model.
    pub truth: Pose,
    /// The model's bounding-box diagonal.
    pub diag: f64,
    /// Visible fraction of the surface (1 for a whole view).
    pub visible: f64,
    /// Outlier points in the scan.
    pub outliers: usize,
}

fn uniform_rotation(rng: &mut impl Rng) -> Matrix3<f64> {
    let n = Normal::new(0.0, 1.0).expect("unit normal");
    let q = nalgebra::Quaternion::new(n.sample(rng), n.sample(rng), n.sample(rng), n.sample(rng));
    UnitQuaternion::from_quaternion(q).to_rotation_matrix().into_inner()
}

fn unit_vector(rng: &mut impl Rng) -> Vector3<f64> {
    let n = Normal::new(0.0, 1.0).expect("unit normal");
    loop {
        let v = Vector3::new(n.sample(rng), n.sample(rng), n.sample(rng));
        if v.norm() > 1e-6 {
            return v.normalize();
        }
    }
}

/// Make case `index` of `family` on `shape`, seeded by `seed`.
pub fn make_case(family: Family, shape: Shape, index: usize, seed: u64) -> Case {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let partial = matches!(shape, Shape::Real(_));
    let visible = if partial { rng.gen_range(VISIBLE_RANGE.0..VISIBLE_RANGE.1) } else { 1.0 };
    let drawn = (SCAN_POINTS as f64 / visible).ceil() as usize;
    let (model, surface) = shape.draw(MODEL_POINTS, drawn, &mut rng);
    let diag = bbox_diagonal(&model);
    // The partial view: keep the `visible` fraction of points lowest along a random direction.
    let mut view = surface;
    if partial {
        let dir = unit_vector(&mut rng);
        let c = centroid(&view);
        view.sort_by(|a, b| (a - c).dot(&dir).total_cmp(&(b - c).dot(&dir)));
        view.truncate(((view.len() as f64) * visible).round() as usize);
        view.shuffle(&mut rng);
    }
    let noise = Normal::new(0.0, NOISE_FRACTION * diag).expect("positive sigma");
    for p in view.iter_mut() {
        for c in p.coords.iter_mut() {
            *c += noise.sample(&mut rng);
        }
    }
    let outliers =
        if family == Family::RealOutliers { (OUTLIER_FRACTION * view.len() as f64).round() as usize } else { 0 };
    if outliers > 0 {
        let grow = 0.1 * diag;
        let lo = view.iter().fold(Vector3::repeat(f64::INFINITY), |a, p| a.inf(&p.coords)).add_scalar(-grow);
        let hi = view.iter().fold(Vector3::repeat(f64::NEG_INFINITY), |a, p| a.sup(&p.coords)).add_scalar(grow);
        for _ in 0..outliers {
            view.push(Point3::new(rng.gen_range(lo.x..hi.x), rng.gen_range(lo.y..hi.y), rng.gen_range(lo.z..hi.z)));
        }
        view.shuffle(&mut rng);
    }
    let truth = if family == Family::Hard180 {
        let t = crate::datasets::random_truth(&mut rng, 1.0, SCALE_RANGE, diag / 2.0);
        Pose { rotation: uniform_rotation(&mut rng), ..t }
    } else {
        crate::datasets::random_truth(&mut rng, MAX_ANGLE_DEG, SCALE_RANGE, diag / 2.0)
    };
    let inv = truth.inverse();
    let scan = view.iter().map(|p| inv.apply(p)).collect();
    Case {
        id: format!("{}/{}/{index:04}", family.name(), shape.name()),
        family,
        shape,
        seed,
        model,
        scan,
        truth,
        diag,
        visible,
        outliers,
    }
}

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

/// Score `estimate` on `case` (the rule of the module's doc).
pub fn score(estimate: &Pose, case: &Case) -> Score {
    let p = centroid(&case.scan);
    let errors = |truth: &Pose| {
        (
            estimate.rotation_angle_to(truth).to_degrees(),
            (estimate.apply(&p) - truth.apply(&p)).norm() / case.diag,
            (estimate.scale / truth.scale - 1.0).abs(),
        )
    };
    let within = |(r, t, s): (f64, f64, f64)| {
        r <= TOLERANCE.rotation_deg && t <= TOLERANCE.translation_frac && s <= TOLERANCE.scale_frac
    };
    let mut best: Option<Score> = None;
    for (i, g) in case.shape.symmetries().iter().enumerate() {
        let e = errors(&symmetric_truth(&case.truth, g, &case.shape.centre()));
        let s = Score { rotation_deg: e.0, translation_frac: e.1, scale_frac: e.2, symmetry: i, success: within(e) };
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
pub fn mahalanobis2(c: &crate::conclusion::Conclusion, truth: &Pose, at: &Point3<f64>) -> Option<(f64, usize)> {
    let e = crate::conclusion::local_error(&c.pose, truth, at);
    let k: Vec<usize> = (0..7).filter(|&i| c.uncertainty.sigma[i].is_some()).collect();
    let n = k.len();
    let m = nalgebra::DMatrix::from_fn(n, n, |a, b| c.uncertainty.covariance[k[a]][k[b]].unwrap_or(0.0));
    let v = nalgebra::DVector::from_fn(n, |a, _| e[k[a]]);
    let inv = m.cholesky()?.inverse();
    Some(((v.transpose() * inv * v)[(0, 0)], n))
}

/// What to run.
#[derive(Clone, Debug)]
pub struct RealisticOptions {
    /// Cases per family.
    pub cases: usize,
    /// Seed of every case.
    pub seed: u64,
    /// Shapes and seeds.
    pub split: Split,
    /// Families to run.
    pub families: Vec<Family>,
    /// Methods to run on each case.
    pub methods: Vec<Method>,
    /// PF-ICP's settings (the seed is replaced by each case's).
    pub pf: PfIcpSettings,
    /// Also run PF-ICP with the filter on the board (column `pf-icp-board`): the host's
    /// prior and conclusion around `fpga::pf::run`, the bit-exact reference of the board's
    /// filter (what the Verilated board computes, byte for byte), with the default board
    /// sample ([`crate::board::on_board::DEFAULT_BOARD_POINTS`]) and at most
    /// [`crate::board::MAX_POINTS`] model points.
    pub board: bool,
    /// Write `realistic.json` here (created if missing).
    pub out_dir: Option<PathBuf>,
    /// Export the cases (clouds and `cases.json`) for the peers' script here.
    pub export: Option<PathBuf>,
    /// Progress on stderr.
    pub progress: bool,
}

impl Default for RealisticOptions {
    fn default() -> Self {
        Self {
            cases: 100,
            seed: 1,
            split: Split::Test,
            families: Family::ALL.to_vec(),
            methods: vec![Method::PfIcp],
            pf: PfIcpSettings::default(),
            board: false,
            out_dir: None,
            export: None,
            progress: true,
        }
    }
}

/// One method on one case.
#[derive(Clone, Debug, Serialize)]
pub struct CaseResult {
    /// Method name.
    pub method: String,
    /// Errors and verdict.
    pub score: Score,
    /// Wall time of the registration [s].
    pub seconds: f64,
    /// PF-ICP only: alternatives it reported.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alternatives: Option<usize>,
    /// PF-ICP only: squared Mahalanobis distance of the error (against the nearest
    /// symmetric truth) under the reported covariance, over the determined parameters.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mahalanobis2: Option<f64>,
    /// PF-ICP only: the number of determined parameters (the chi-square's degrees of freedom).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dof: Option<usize>,
    /// PF-ICP only: the truth lies inside the reported 95% region.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inside_95: Option<bool>,
    /// Capped surface cost of the estimate on the whole scan ([`crate::surface::Surface::cost`],
    /// cap 5% of the diagonal), to compare with the truth's.
    pub cost: f64,
}

/// One case in the report.
#[derive(Clone, Debug, Serialize)]
pub struct CaseRecord {
    /// `family/shape/index`.
    pub id: String,
    /// Shape name.
    pub shape: String,
    /// Whether the shape is held out of tuning.
    pub held_out: bool,
    /// Seed.
    pub seed: u64,
    /// Visible fraction.
    pub visible: f64,
    /// Outliers.
    pub outliers: usize,
    /// Scan points.
    pub scan_points: usize,
    /// The truth, `[tx, ty, tz, s, phi, theta, psi]` (angles in degrees).
    pub truth: [f64; 7],
    /// Robust cost of the truth on the whole scan (as [`CaseResult::cost`]).
    pub truth_cost: f64,
    /// The same after the point-to-plane polish from the truth: what the true basin's
    /// optimum costs (an estimate below it fits the scan better than the truth's basin).
    pub truth_refined_cost: f64,
    /// One entry per method.
    pub results: Vec<CaseResult>,
}

/// One method's figures in one family.
#[derive(Clone, Debug, Serialize)]
pub struct FamilyCell {
    /// Method name.
    pub method: String,
    /// Successful cases.
    pub successes: usize,
    /// Cases.
    pub cases: usize,
    /// Successes among the held-out shapes' cases.
    pub held_out_successes: usize,
    /// Held-out shapes' cases.
    pub held_out_cases: usize,
    /// Median wall time [s].
    pub median_seconds: f64,
    /// Successful cases whose truth lies inside the reported 95% region (PF-ICP only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inside_95: Option<usize>,
    /// Cases that reported alternatives (PF-ICP only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub with_alternatives: Option<usize>,
}

/// One family.
#[derive(Clone, Debug, Serialize)]
pub struct FamilyReport {
    /// Family name.
    pub family: Family,
    /// One cell per method.
    pub cells: Vec<FamilyCell>,
    /// Every case.
    pub cases: Vec<CaseRecord>,
}

/// The whole benchmark.
#[derive(Clone, Debug, Serialize)]
pub struct RealisticReport {
    /// Seed.
    pub seed: u64,
    /// Split.
    pub split: Split,
    /// Cases per family.
    pub cases_per_family: usize,
    /// The tolerance.
    pub tolerance: Tolerance,
    /// Methods, in column order.
    pub methods: Vec<String>,
    /// One entry per family.
    pub families: Vec<FamilyReport>,
}

/// Name of the on-board column.
pub const BOARD_COLUMN: &str = "pf-icp-board";

fn method_columns(opts: &RealisticOptions) -> Vec<String> {
    let mut v: Vec<String> = opts.methods.iter().map(|m| m.name().to_string()).collect();
    if opts.board {
        v.push(BOARD_COLUMN.to_string());
    }
    v
}

/// PF-ICP with the filter on the board, the board's part by its bit-exact reference.
fn on_board_reference(
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &PfIcpSettings,
) -> crate::pf_icp::PfIcpResult {
    use crate::board::on_board::{finish, plan, DEFAULT_BOARD_POINTS};
    use pficp_fpga::pf;
    let plan = plan(nn, scan, settings, DEFAULT_BOARD_POINTS, crate::board::MAX_POINTS);
    let out = pf::run(&plan.config, |p| pf::evaluate(&plan.model, &plan.scan, p));
    let reply = pficp_fpga::messages::ResultReply::of(&out);
    finish(&plan, nn, scan, settings, &reply, std::time::Duration::ZERO)
}

/// Case `index` of `family` in the options' split.
pub fn case(family: Family, index: usize, split: Split, seed: u64) -> Case {
    let shapes = shapes(family, split);
    let shape = shapes[index % shapes.len()];
    let split_code = match split {
        Split::Dev => 1,
        Split::Test => 2,
    };
    let family_code = Family::ALL.iter().position(|&f| f == family).unwrap_or(0) as u64 + 1;
    let case_seed = mix(mix(mix(seed, split_code), family_code), index as u64 + 1);
    make_case(family, shape, index, case_seed)
}

/// Run the benchmark.
pub fn run(opts: &RealisticOptions) -> anyhow::Result<RealisticReport> {
    let mut exported = Vec::new();
    let mut families = Vec::new();
    for &family in &opts.families {
        let start = Instant::now();
        let mut cases = Vec::with_capacity(opts.cases);
        for i in 0..opts.cases {
            let c = case(family, i, opts.split, opts.seed);
            if let Some(dir) = &opts.export {
                exported.push(export_case(dir, &c)?);
            }
            let nn = NearestNeighbours::new(&c.model);
            let surface = crate::surface::Surface::new(&nn);
            let settings = MethodSettings { pf: PfIcpSettings { seed: c.seed, ..opts.pf.clone() } };
            let mut results: Vec<CaseResult> = opts
                .methods
                .iter()
                .map(|&m| {
                    let o = run_method(m, &nn, &c.scan, &settings);
                    let sc = score(&o.registration.pose, &c);
                    let md = o.pf.as_ref().and_then(|pf| {
                        let g = c.shape.symmetries()[sc.symmetry];
                        let truth = symmetric_truth(&c.truth, &g, &c.shape.centre());
                        mahalanobis2(&pf.conclusion, &truth, &centroid(&c.scan))
                    });
                    CaseResult {
                        method: m.name().to_string(),
                        alternatives: o.pf.as_ref().map(|pf| pf.conclusion.alternatives.len()),
                        mahalanobis2: md.map(|m| m.0),
                        dof: md.map(|m| m.1),
                        inside_95: o.pf.as_ref().map(|_| md.is_some_and(|(d, k)| inside_95(d, k))),
                        score: sc,
                        seconds: o.elapsed.as_secs_f64(),
                        cost: surface.cost(&c.scan, &o.registration.pose, 0.05 * c.diag),
                    }
                })
                .collect();
            if opts.board {
                let t = Instant::now();
                let pf = on_board_reference(&nn, &c.scan, &settings.pf);
                let seconds = t.elapsed().as_secs_f64();
                let sc = score(&pf.registration.pose, &c);
                let g = c.shape.symmetries()[sc.symmetry];
                let truth = symmetric_truth(&c.truth, &g, &c.shape.centre());
                let md = mahalanobis2(&pf.conclusion, &truth, &centroid(&c.scan));
                results.push(CaseResult {
                    method: BOARD_COLUMN.to_string(),
                    alternatives: Some(pf.conclusion.alternatives.len()),
                    mahalanobis2: md.map(|m| m.0),
                    dof: md.map(|m| m.1),
                    inside_95: Some(md.is_some_and(|(d, k)| inside_95(d, k))),
                    score: sc,
                    seconds,
                    cost: surface.cost(&c.scan, &pf.registration.pose, 0.05 * c.diag),
                });
            }
            let mut truth = c.truth.to_params();
            for a in &mut truth[4..] {
                *a = a.to_degrees();
            }
            cases.push(CaseRecord {
                id: c.id.clone(),
                shape: c.shape.name().to_string(),
                held_out: c.shape.held_out(),
                seed: c.seed,
                visible: c.visible,
                outliers: c.outliers,
                scan_points: c.scan.len(),
                truth,
                truth_cost: surface.cost(&c.scan, &c.truth, 0.05 * c.diag),
                truth_refined_cost: {
                    let p = surface.polish(&c.scan, &c.truth, 30);
                    surface.cost(&c.scan, &p, 0.05 * c.diag)
                },
                results,
            });
            if opts.progress && ((i + 1) % 10 == 0 || i + 1 == opts.cases) {
                eprintln!(
                    "[realistic] {} {}/{} cases ({:.1} s)",
                    family.name(),
                    i + 1,
                    opts.cases,
                    start.elapsed().as_secs_f64()
                );
            }
        }
        let columns = method_columns(opts);
        let cells = columns
            .iter()
            .enumerate()
            .map(|(j, m)| {
                let held: Vec<&CaseRecord> = cases.iter().filter(|c| c.held_out).collect();
                let pf = m.starts_with(Method::PfIcp.name());
                FamilyCell {
                    method: m.clone(),
                    successes: cases.iter().filter(|c| c.results[j].score.success).count(),
                    cases: cases.len(),
                    held_out_successes: held.iter().filter(|c| c.results[j].score.success).count(),
                    held_out_cases: held.len(),
                    median_seconds: median(&cases.iter().map(|c| c.results[j].seconds).collect::<Vec<_>>()),
                    inside_95: pf.then(|| {
                        cases
                            .iter()
                            .filter(|c| c.results[j].score.success)
                            .filter(|c| c.results[j].inside_95 == Some(true))
                            .count()
                    }),
                    with_alternatives: pf
                        .then(|| cases.iter().filter(|c| c.results[j].alternatives.is_some_and(|a| a > 0)).count()),
                }
            })
            .collect();
        families.push(FamilyReport { family, cells, cases });
    }
    let report = RealisticReport {
        seed: opts.seed,
        split: opts.split,
        cases_per_family: opts.cases,
        tolerance: TOLERANCE,
        methods: method_columns(opts),
        families,
    };
    if let Some(dir) = &opts.export {
        let doc = serde_json::json!({
            "suite": "realistic", "split": opts.split.name(), "seed": opts.seed,
            "tolerance": TOLERANCE, "cases": exported,
        });
        let path = dir.join("cases.json");
        std::fs::write(&path, serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(dir) = &opts.out_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let path = dir.join("realistic.json");
        std::fs::write(&path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(report)
}

fn export_case(dir: &Path, c: &Case) -> anyhow::Result<serde_json::Value> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let stem = c.id.replace('/', "-");
    let (model, scan) = (format!("{stem}-model.ply"), format!("{stem}-scan.ply"));
    crate::io::write_cloud(&dir.join(&model), &c.model, crate::io::Format::PlyBinary)?;
    crate::io::write_cloud(&dir.join(&scan), &c.scan, crate::io::Format::PlyBinary)?;
    let centre = c.shape.centre();
    let symmetries: Vec<serde_json::Value> = c
        .shape
        .symmetries()
        .iter()
        .map(|g| {
            let rows: Vec<[f64; 3]> = (0..3).map(|i| [g[(i, 0)], g[(i, 1)], g[(i, 2)]]).collect();
            serde_json::json!({ "rotation": rows, "centre": [centre.x, centre.y, centre.z] })
        })
        .collect();
    let p = centroid(&c.scan);
    let t = c.truth.record();
    Ok(serde_json::json!({
        "id": c.id, "family": c.family.name(), "shape": c.shape.name(), "held_out": c.shape.held_out(),
        "seed": c.seed, "model": model, "scan": scan,
        "truth": { "scale": t.scale, "rotation": t.rotation, "translation": t.translation },
        "diag": c.diag, "reference_point": [p.x, p.y, p.z], "symmetries": symmetries,
    }))
}

impl RealisticReport {
    /// The table as text.
    pub fn render(&self) -> String {
        let mut header = vec!["family".to_string()];
        for m in &self.methods {
            header.push(format!("{m} success"));
            header.push(format!("{m} held-out"));
            header.push(format!("{m} median s"));
            if m.starts_with(Method::PfIcp.name()) {
                header.push("truth in 95% region".to_string());
                header.push("ambiguous".to_string());
            }
        }
        let mut t = TextTable::new(
            format!(
                "Realistic benchmark ({} split, seed {}): {} cases per family, {MODEL_POINTS} model / ~{SCAN_POINTS} scan points",
                self.split.name(),
                self.seed,
                self.cases_per_family
            ),
            header,
        );
        for f in &self.families {
            let mut row = vec![f.family.name().to_string()];
            for c in &f.cells {
                row.push(format!(
                    "{}/{} ({:.0}%)",
                    c.successes,
                    c.cases,
                    100.0 * c.successes as f64 / c.cases.max(1) as f64
                ));
                row.push(format!("{}/{}", c.held_out_successes, c.held_out_cases));
                row.push(format!("{:.3}", c.median_seconds));
                if let (Some(inside), Some(alt)) = (c.inside_95, c.with_alternatives) {
                    row.push(format!("{inside}/{}", c.successes));
                    row.push(format!("{alt}/{}", c.cases));
                }
            }
            t.row(row);
        }
        t.note(format!(
            "success: within {} deg, {}% of the diagonal at the scan centroid, {}% scale, modulo the shape's symmetries; partial views keep {:.0} to {:.0}% of the surface; noise {}% of the diagonal; outliers {}%",
            TOLERANCE.rotation_deg,
            100.0 * TOLERANCE.translation_frac,
            100.0 * TOLERANCE.scale_frac,
            100.0 * VISIBLE_RANGE.0,
            100.0 * VISIBLE_RANGE.1,
            100.0 * NOISE_FRACTION,
            100.0 * OUTLIER_FRACTION
        ));
        t.render()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_truth_scores_zero_and_a_symmetric_copy_counts_as_right() {
        let c = case(Family::Parts, 7, Split::Test, 5); // Part::Nut, D6
        assert_eq!(c.shape.name(), "nut");
        let s = score(&c.truth, &c);
        assert!(s.success && s.rotation_deg < 1e-9 && s.symmetry == 0);
        let g = c.shape.symmetries()[3];
        let copy = symmetric_truth(&c.truth, &g, &c.shape.centre());
        let s = score(&copy, &c);
        assert!(s.success && s.symmetry == 3, "{s:?}");
        // A near-symmetric part's flipped copy is wrong.
        let c = case(Family::Parts, 0, Split::Test, 5);
        let half = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI).into_inner();
        assert!(!score(&symmetric_truth(&c.truth, &half, &c.shape.centre()), &c).success);
    }

    #[test]
    fn cases_are_a_function_of_the_seed() {
        let a = case(Family::RealOutliers, 3, Split::Dev, 9);
        let b = case(Family::RealOutliers, 3, Split::Dev, 9);
        assert_eq!(a.scan, b.scan);
        assert_eq!(a.truth, b.truth);
        assert!(a.outliers > 0);
        let c = case(Family::RealOutliers, 3, Split::Test, 9);
        assert_ne!(a.scan, c.scan);
    }

    #[test]
    fn dev_split_has_no_held_out_shape() {
        for f in Family::ALL {
            assert!(shapes(f, Split::Dev).iter().all(|s| !s.held_out()));
            assert!(shapes(f, Split::Test).iter().any(|s| s.held_out()));
        }
    }
}
