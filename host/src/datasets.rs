//! Built-in models and their scans (paper section 4).
//!
//! - **Model 1**: 3-D continuous strings, spiral-like: four conical spiral strings wound
//!   around a vertical axis that is off the origin, their radius wobbling as it grows. Rotating by a quarter turn about that
//!   axis nearly maps the model onto itself, so ICP finds local minima in `psi`, `tx`, `ty`
//!   (Table 4); the strings differ in length, so the true pose is the only exact fit.
//! - **Model 2**: a 3-D surface mesh: an egg-crate height field on a rectangle (look-alikes
//!   under translation by one period and rotation by half a turn) with one bump that
//!   breaks the symmetry.
//! - **Model 3**: a bottle: a surface of revolution (body, shoulder, neck) with a raised
//!   label panel on one side and a slightly elliptic section; its scan is thin and uneven
//!   (Table 7).
//!
//! The truth pose maps scan to model (`d = s R m + T`); the scan is made by the inverse
//! of the truth, so a registration should return the Table 1 values themselves.
//! Two settings: the paper's (the scan is the model's own points, in the same order,
//! transformed) and the realistic one (the scan is sampled independently from the same
//! surface). Noise is the paper's: uniform in `(0, amplitude)` on every coordinate,
//! added in the scan frame.

use crate::geometry::Pose;
use nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{PI, TAU};

/// The built-in models.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ModelId {
    /// Spiral-like continuous strings.
    Model1,
    /// Surface mesh with symmetries and local look-alikes.
    Model2,
    /// Bottle with a thin, uneven scan.
    Model3,
}

impl ModelId {
    /// All models, in order.
    pub const ALL: [ModelId; 3] = [ModelId::Model1, ModelId::Model2, ModelId::Model3];

    /// `model-1`, `model-2`, `model-3`.
    pub fn name(self) -> &'static str {
        match self {
            ModelId::Model1 => "model-1",
            ModelId::Model2 => "model-2",
            ModelId::Model3 => "model-3",
        }
    }

    /// Parse `model-1`, `1`, `m1` and the like.
    pub fn parse(s: &str) -> Option<ModelId> {
        match s.trim().to_ascii_lowercase().trim_start_matches("model").trim_start_matches(['-', '_', 'm']) {
            "1" => Some(ModelId::Model1),
            "2" => Some(ModelId::Model2),
            "3" => Some(ModelId::Model3),
            _ => None,
        }
    }

    /// The Table 1 transform used with this model (scan-1 for model 1; scan-2 for models
    /// 2 and 3, as in Tables 5 and 7).
    pub fn table1_truth(self) -> Pose {
        let deg = |x: f64| x.to_radians();
        match self {
            ModelId::Model1 => {
                Pose::from_params(&[-0.9928, -0.5570, -0.4844, 0.7143, deg(-29.4659), deg(-18.6011), deg(-29.4659)])
            }
            ModelId::Model2 | ModelId::Model3 => {
                Pose::from_params(&[-2.2487, -1.6495, -3.3125, 0.8333, deg(5.2258), deg(-16.4071), deg(-17.9510)])
            }
        }
    }

    /// The model cloud with `n` points: evenly spread, deterministic (no seed).
    pub fn model_points(self, n: usize) -> Vec<Point3<f64>> {
        match self {
            ModelId::Model1 => spiral_strings_even(n),
            ModelId::Model2 => egg_crate_grid(n),
            ModelId::Model3 => {
                let mut rng = ChaCha8Rng::seed_from_u64(0x3b07_713e);
                (0..n).map(|_| bottle_sample(&mut rng)).collect()
            }
        }
    }

    /// `n` points drawn at random from the model's surface.
    pub fn sample_surface(self, n: usize, rng: &mut impl Rng) -> Vec<Point3<f64>> {
        (0..n)
            .map(|_| match self {
                ModelId::Model1 => spiral_string_point_random(rng),
                ModelId::Model2 => {
                    let (x, y) = (rng.gen_range(-EGG_HALF_X..EGG_HALF_X), rng.gen_range(-EGG_HALF_Y..EGG_HALF_Y));
                    Point3::new(x, y, egg_crate_height(x, y))
                }
                ModelId::Model3 => bottle_sample(rng),
            })
            .collect()
    }
}

// ---- Model 1: spiral strings -------------------------------------------------------

const STRINGS: usize = 4;
/// Axis of the near-symmetry, off the origin.
const SPIRAL_AXIS: [f64; 2] = [0.6, -0.4];

/// Angular length of string `k` [rad]: they differ, which breaks the quarter-turn symmetry.
fn string_length(k: usize) -> f64 {
    PI * (1.4 + 0.22 * k as f64)
}

/// Point at parameter `t` (0..string_length(k)) of string `k`.
fn spiral_point(k: usize, t: f64) -> Point3<f64> {
    let a = TAU * k as f64 / STRINGS as f64 + t;
    // Growing radius (spiral) with a wobble: sliding along a string costs distance.
    let r = 1.5 + 0.18 * t + 0.12 * (4.0 * t).sin();
    Point3::new(SPIRAL_AXIS[0] + r * a.cos(), SPIRAL_AXIS[1] + r * a.sin(), -1.4 + 0.5 * t)
}

fn spiral_strings_even(n: usize) -> Vec<Point3<f64>> {
    let total: f64 = (0..STRINGS).map(string_length).sum();
    let mut out = Vec::with_capacity(n);
    for k in 0..STRINGS {
        let len = string_length(k);
        let nk = if k + 1 == STRINGS { n - out.len() } else { ((n as f64) * len / total).round() as usize };
        for j in 0..nk {
            out.push(spiral_point(k, len * (j as f64 + 0.5) / nk as f64));
        }
    }
    out
}

fn spiral_string_point_random(rng: &mut impl Rng) -> Point3<f64> {
    let total: f64 = (0..STRINGS).map(string_length).sum();
    let mut u = rng.gen_range(0.0..total);
    for k in 0..STRINGS {
        let len = string_length(k);
        if u < len || k + 1 == STRINGS {
            return spiral_point(k, u.min(len));
        }
        u -= len;
    }
    unreachable!("the loop returns on its last string")
}

// ---- Model 2: egg-crate surface ----------------------------------------------------

const EGG_HALF_X: f64 = 3.0;
const EGG_HALF_Y: f64 = 2.0;

fn egg_crate_height(x: f64, y: f64) -> f64 {
    let bump = 0.9 * (-((x - 1.3).powi(2) + (y + 0.6).powi(2)) / 0.35).exp();
    0.45 * (PI * x / 1.0).cos() * (PI * y / 1.0).cos() + bump
}

fn egg_crate_grid(n: usize) -> Vec<Point3<f64>> {
    // nx / ny = 3 / 2, nx * ny ≈ n.
    let ny = ((n as f64) / 1.5).sqrt().round().max(2.0) as usize;
    let nx = (n as f64 / ny as f64).ceil() as usize;
    let mut out = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            if out.len() == n {
                break;
            }
            let x = -EGG_HALF_X + 2.0 * EGG_HALF_X * (i as f64 + 0.5) / nx as f64;
            let y = -EGG_HALF_Y + 2.0 * EGG_HALF_Y * (j as f64 + 0.5) / ny as f64;
            out.push(Point3::new(x, y, egg_crate_height(x, y)));
        }
    }
    out
}

// ---- Model 3: bottle ----------------------------------------------------------------

const BOTTLE_HEIGHT: f64 = 4.0;

/// Profile radius at height z (body, shoulder, neck).
fn bottle_radius(z: f64) -> f64 {
    let body = 1.0;
    let neck = 0.35;
    if z < 2.4 {
        body
    } else if z < 3.2 {
        let u = (z - 2.4) / 0.8;
        let s = u * u * (3.0 - 2.0 * u);
        body + (neck - body) * s
    } else {
        neck
    }
}

/// Raised label panel on one side: `+0.2` over 70 degrees of angle and 1.2 of height.
fn label_relief(angle: f64, z: f64) -> f64 {
    let a = crate::geometry::wrap_angle(angle - 0.3);
    if a.abs() < 35f64.to_radians() && (0.7..1.9).contains(&z) {
        0.2
    } else {
        0.0
    }
}

/// The body's cross-section is slightly elliptic (a look-alike at half a turn, which the
/// label breaks).
fn bottle_point(angle: f64, z: f64) -> Point3<f64> {
    let r = bottle_radius(z) * (1.0 + 0.25 * (2.0 * angle).cos()) + label_relief(angle, z);
    Point3::new(r * angle.cos(), r * angle.sin(), z)
}

/// Area-weighted random point on the side of the bottle (rejection on the radius).
fn bottle_sample(rng: &mut impl Rng) -> Point3<f64> {
    loop {
        let z = rng.gen_range(0.0..BOTTLE_HEIGHT);
        let a = rng.gen_range(-PI..PI);
        if rng.gen_range(0.0..1.0) <= bottle_radius(z) {
            return bottle_point(a, z);
        }
    }
}

/// Thin, uneven sampling of the bottle as a one-sided scanner sees it: density falls
/// from the front (angle `front`) to a tenth at the back.
pub fn bottle_thin_scan_points(n: usize, front: f64, rng: &mut impl Rng) -> Vec<Point3<f64>> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let p = bottle_sample(rng);
        let a = p.y.atan2(p.x);
        let keep = 0.1 + 0.9 * (0.5 + 0.5 * (a - front).cos()).powi(2);
        if rng.gen_range(0.0..1.0) < keep {
            out.push(p);
        }
    }
    out
}

// ---- Scans --------------------------------------------------------------------------

/// How the scan's points relate to the model's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sampling {
    /// The paper's setting: the model's own points, same order, transformed.
    Paper,
    /// Sampled independently from the same surface (`points` of them).
    Independent {
        /// Number of scan points.
        points: usize,
    },
    /// Model 3's thin, uneven scan (`points` of them), independent of the model's points.
    Thin {
        /// Number of scan points.
        points: usize,
    },
}

/// Everything needed to make a scan.
#[derive(Clone, Copy, Debug)]
pub struct ScanSpec {
    /// Point sampling.
    pub sampling: Sampling,
    /// Noise amplitude: each coordinate gets `U(0, noise)` added, in scan units.
    pub noise: f64,
    /// Seed for sampling and noise.
    pub seed: u64,
}

/// A model, its scan and the truth pose (scan to model).
#[derive(Clone, Debug)]
pub struct Dataset {
    /// Model cloud `D`.
    pub model: Vec<Point3<f64>>,
    /// Scan cloud `M`.
    pub scan: Vec<Point3<f64>>,
    /// The pose with `d = s R m + T`.
    pub truth: Pose,
}

/// Make a dataset: model `id` with `model_points` points, scanned under `truth`.
pub fn make(id: ModelId, model_points: usize, truth: &Pose, spec: &ScanSpec) -> Dataset {
    let model = id.model_points(model_points);
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let surface = match spec.sampling {
        Sampling::Paper => model.clone(),
        Sampling::Independent { points } => id.sample_surface(points, &mut rng),
        Sampling::Thin { points } => match id {
            ModelId::Model3 => bottle_thin_scan_points(points, 0.5, &mut rng),
            _ => thin_out(&id.sample_surface(points * 4, &mut rng), points, &mut rng),
        },
    };
    let inv = truth.inverse();
    let scan = surface
        .iter()
        .map(|p| {
            let mut q = inv.apply(p);
            if spec.noise > 0.0 {
                for c in q.coords.iter_mut() {
                    *c += rng.gen_range(0.0..spec.noise);
                }
            }
            q
        })
        .collect();
    Dataset { model, scan, truth: *truth }
}

/// Cut a partial view: keep the `visible` fraction of `points` lowest along `dir` (measured
/// from their centroid), as a range sensor sees a part from one side. The order of the
/// kept points is the sorted one; shuffle them if the order must not tell anything.
pub fn cut_view(points: &mut Vec<Point3<f64>>, dir: &nalgebra::Vector3<f64>, visible: f64) {
    let c = crate::cloud::centroid(points);
    points.sort_by(|a, b| (a - c).dot(dir).total_cmp(&(b - c).dot(dir)));
    points.truncate(((points.len() as f64) * visible).round() as usize);
}

/// Keep `n` points with a density that falls along x (uneven thinning for models 1, 2).
fn thin_out(points: &[Point3<f64>], n: usize, rng: &mut impl Rng) -> Vec<Point3<f64>> {
    let (lo, hi) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.x), hi.max(p.x)));
    let mut out = Vec::with_capacity(n);
    let mut i = 0;
    while out.len() < n {
        let p = points[i % points.len()];
        let u = (p.x - lo) / (hi - lo).max(1e-12);
        if rng.gen_range(0.0..1.0) < 0.1 + 0.9 * u {
            out.push(p);
        }
        i += 1;
    }
    out
}

/// A random transform for the success-rate experiment: each angle uniform in +-`max_angle_deg`,
/// scale in `scale_range`, translation uniform in a ball of radius `max_translation`.
pub fn random_truth(rng: &mut impl Rng, max_angle_deg: f64, scale_range: (f64, f64), max_translation: f64) -> Pose {
    let a = max_angle_deg.to_radians();
    let t = loop {
        let v = nalgebra::Vector3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        if v.norm_squared() <= 1.0 {
            break v * max_translation;
        }
    };
    Pose::from_params(&[
        t.x,
        t.y,
        t.z,
        rng.gen_range(scale_range.0..scale_range.1),
        rng.gen_range(-a..a),
        rng.gen_range(-a..a),
        rng.gen_range(-a..a),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::bbox_diagonal;

    #[test]
    fn models_have_the_requested_size_and_are_deterministic() {
        for id in ModelId::ALL {
            let a = id.model_points(1234);
            assert_eq!(a.len(), 1234, "{id:?}");
            assert_eq!(a, id.model_points(1234));
            let d = bbox_diagonal(&a);
            assert!(d > 4.0 && d < 12.0, "{id:?} diagonal {d}");
        }
    }

    #[test]
    fn paper_scan_maps_back_exactly() {
        let truth = ModelId::Model1.table1_truth();
        let spec = ScanSpec { sampling: Sampling::Paper, noise: 0.0, seed: 1 };
        let ds = make(ModelId::Model1, 500, &truth, &spec);
        for (m, d) in ds.scan.iter().zip(&ds.model) {
            assert!((truth.apply(m) - d).norm() < 1e-12);
        }
    }

    #[test]
    fn noise_is_uniform_zero_to_amplitude() {
        let truth = Pose::identity();
        let spec = ScanSpec { sampling: Sampling::Paper, noise: 0.1, seed: 9 };
        let ds = make(ModelId::Model2, 800, &truth, &spec);
        let deltas: Vec<f64> =
            ds.scan.iter().zip(&ds.model).flat_map(|(m, d)| (m - d).iter().copied().collect::<Vec<_>>()).collect();
        assert!(deltas.iter().all(|&x| (0.0..0.1).contains(&x)));
        let mean = deltas.iter().sum::<f64>() / deltas.len() as f64;
        assert!((mean - 0.05).abs() < 0.005, "{mean}");
    }

    #[test]
    fn parse_names() {
        assert_eq!(ModelId::parse("model-2"), Some(ModelId::Model2));
        assert_eq!(ModelId::parse("3"), Some(ModelId::Model3));
        assert_eq!(ModelId::parse("model-9"), None);
    }
}
