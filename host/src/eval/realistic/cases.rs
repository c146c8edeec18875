//! The benchmark's cases: families, splits, shapes, and each case as a function of the
//! seed, the split, the family and its index (the parent module's documentation says what
//! each family is).

use crate::cloud::bbox_diagonal;
use crate::geometry::{Pose, ScaleBounds};
use crate::parts::Part;
use crate::pf_icp::PfIcpSettings;
use crate::real_shapes::RealShape;
use nalgebra::{Matrix3, Point3, UnitQuaternion, Vector3};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;

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
    /// Camera views ([`super::camera`]) with clutter, rotations up to 90 deg about a random
    /// axis, unknown scale.
    #[serde(rename = "camera")]
    Camera,
    /// Camera views at any rotation, unknown scale.
    #[serde(rename = "camera-any")]
    CameraAny,
    /// Camera views, rotations up to 90 deg, scale 1 and known (a metric sensor and a model
    /// in the same units).
    #[serde(rename = "camera-metric")]
    CameraMetric,
    /// Camera views at any rotation, scale 1 and known.
    #[serde(rename = "camera-any-metric")]
    CameraAnyMetric,
}

impl Family {
    /// The plane-cut families (partial views that keep 60 to 80% of the surface, or the
    /// whole surface).
    pub const PLANE_CUT: [Family; 4] = [Family::Real, Family::RealOutliers, Family::Parts, Family::Hard180];
    /// The camera-view families.
    pub const CAMERA: [Family; 4] = [Family::Camera, Family::CameraAny, Family::CameraMetric, Family::CameraAnyMetric];
    /// Every family, in report order (a family's position here is part of its cases' seeds).
    pub const ALL: [Family; 8] = [
        Family::Real,
        Family::RealOutliers,
        Family::Parts,
        Family::Hard180,
        Family::Camera,
        Family::CameraAny,
        Family::CameraMetric,
        Family::CameraAnyMetric,
    ];

    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Family::Real => "real",
            Family::RealOutliers => "real-outliers",
            Family::Parts => "parts",
            Family::Hard180 => "hard-180",
            Family::Camera => "camera",
            Family::CameraAny => "camera-any",
            Family::CameraMetric => "camera-metric",
            Family::CameraAnyMetric => "camera-any-metric",
        }
    }

    /// A camera-view family.
    pub fn is_camera(self) -> bool {
        Family::CAMERA.contains(&self)
    }

    /// The scale the user knows for this family's cases (`None`: unknown, estimated).
    pub fn known_scale(self) -> Option<f64> {
        matches!(self, Family::CameraMetric | Family::CameraAnyMetric).then_some(1.0)
    }

    /// Any rotation (uniform on SO(3)) rather than a bounded one.
    fn any_rotation(self) -> bool {
        matches!(self, Family::Hard180 | Family::CameraAny | Family::CameraAnyMetric)
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
    pub fn draw(&self, model: usize, scan: usize, rng: &mut ChaCha8Rng) -> (Vec<Point3<f64>>, Vec<Point3<f64>>) {
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
    // The plane-cut families keep their original shapes (their figures stay comparable).
    let real = crate::real_shapes::all().iter().filter(|s| !s.camera_only).map(Shape::Real);
    let parts = Part::ALL.iter().map(|&p| Shape::Part(p));
    let all: Vec<Shape> = match family {
        Family::Real | Family::RealOutliers => real.collect(),
        Family::Parts => parts.collect(),
        Family::Hard180 => real.chain(parts).collect(),
        Family::Camera | Family::CameraAny | Family::CameraMetric | Family::CameraAnyMetric => {
            crate::real_shapes::all().iter().map(Shape::Real).chain(parts).collect()
        }
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
    /// Outlier points in the scan (clutter in the camera-view families).
    pub outliers: usize,
    /// The camera's position in the scan's frame (camera-view families).
    pub viewpoint: Option<Point3<f64>>,
    /// The scale the user knows ([`Family::known_scale`]).
    pub known_scale: Option<f64>,
}

impl Case {
    /// `base` told what the case's user knows: the case's seed, the known scale (fixed) and
    /// the camera's position.
    pub fn pf_settings(&self, base: &PfIcpSettings) -> PfIcpSettings {
        PfIcpSettings {
            seed: self.seed,
            scale: self.known_scale.map_or(base.scale, ScaleBounds::fixed),
            viewpoint: self.viewpoint,
            ..base.clone()
        }
    }
}

fn uniform_rotation(rng: &mut impl Rng) -> Matrix3<f64> {
    let n = Normal::new(0.0, 1.0).expect("unit normal");
    let q = nalgebra::Quaternion::new(n.sample(rng), n.sample(rng), n.sample(rng), n.sample(rng));
    UnitQuaternion::from_quaternion(q).to_rotation_matrix().into_inner()
}

/// A direction uniform on the sphere.
pub fn unit_vector(rng: &mut impl Rng) -> Vector3<f64> {
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
    if family.is_camera() {
        return make_camera_case(family, shape, index, seed);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let partial = matches!(shape, Shape::Real(_));
    let visible = if partial { rng.gen_range(VISIBLE_RANGE.0..VISIBLE_RANGE.1) } else { 1.0 };
    let drawn = (SCAN_POINTS as f64 / visible).ceil() as usize;
    let (model, surface) = shape.draw(MODEL_POINTS, drawn, &mut rng);
    let diag = bbox_diagonal(&model);
    // The partial view: keep the `visible` fraction of points lowest along a random direction.
    let mut view = surface;
    if partial {
        crate::datasets::cut_view(&mut view, &unit_vector(&mut rng), visible);
        view.shuffle(&mut rng);
    }
    add_noise(&mut view, NOISE_FRACTION * diag, &mut rng);
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
    let truth = if family.any_rotation() {
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
        viewpoint: None,
        known_scale: None,
    }
}

/// Model points of a camera-view case.
pub const CAMERA_MODEL_POINTS: usize = 3000;
/// Scan points of a camera-view case (clutter included).
pub const CAMERA_SCAN_POINTS: usize = 1500;
/// Surface points a camera view is cut from (the rest of a real shape's stored sample).
const CAMERA_SURFACE_POINTS: usize = 17_000;
/// Scale range of the camera-view truths when the scale is unknown.
pub const CAMERA_SCALE_RANGE: (f64, f64) = (0.8, 1.25);
/// Largest rotation of the bounded camera-view families (about a random axis) [deg].
pub const CAMERA_MAX_ANGLE_DEG: f64 = 90.0;

/// Gaussian noise of standard deviation `sigma` on every coordinate, point by point.
fn add_noise(points: &mut [Point3<f64>], sigma: f64, rng: &mut ChaCha8Rng) {
    let noise = Normal::new(0.0, sigma).expect("positive sigma");
    for p in points.iter_mut() {
        for c in p.coords.iter_mut() {
            *c += noise.sample(rng);
        }
    }
}

/// A camera-view case ([`super::camera::camera_view`]): the view, 0.5% noise, the truth.
fn make_camera_case(family: Family, shape: Shape, index: usize, seed: u64) -> Case {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (model, surface) = shape.draw(CAMERA_MODEL_POINTS, CAMERA_SURFACE_POINTS, &mut rng);
    let diag = bbox_diagonal(&model);
    let view = super::camera::camera_view(&surface, diag, CAMERA_SCAN_POINTS, &mut rng);
    let mut points = view.surface;
    add_noise(&mut points, NOISE_FRACTION * diag, &mut rng);
    let outliers = view.clutter.len();
    points.extend(view.clutter);
    points.shuffle(&mut rng);
    let rotation = if family.any_rotation() {
        uniform_rotation(&mut rng)
    } else {
        let axis = nalgebra::Unit::new_normalize(unit_vector(&mut rng));
        let angle = rng.gen_range(0.0..CAMERA_MAX_ANGLE_DEG).to_radians();
        nalgebra::Rotation3::from_axis_angle(&axis, angle).into_inner()
    };
    let scale = family.known_scale().unwrap_or_else(|| rng.gen_range(CAMERA_SCALE_RANGE.0..CAMERA_SCALE_RANGE.1));
    let translation = loop {
        let v = Vector3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        if v.norm_squared() <= 1.0 {
            break v * (diag / 2.0);
        }
    };
    let truth = Pose { scale, rotation, translation };
    let inv = truth.inverse();
    Case {
        id: format!("{}/{}/{index:04}", family.name(), shape.name()),
        family,
        shape,
        seed,
        model,
        scan: points.iter().map(|p| inv.apply(p)).collect(),
        truth,
        diag,
        visible: view.visible,
        outliers,
        viewpoint: Some(inv.apply(&view.camera)),
        known_scale: family.known_scale(),
    }
}
