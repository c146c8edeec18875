//! The tracking benchmark's sequences: a part moving in front of a fixed depth camera.
//!
//! - **The part**: a shape of the realistic benchmark, scaled by a factor drawn in
//!   [`SCALE_RANGE`], starting [`CAMERA_DISTANCE`] diagonals in front of the camera (at the
//!   origin, looking along +z: the scans are in the camera's frame) under a random
//!   rotation.
//! - **The motion**: smooth; the angular velocity is a sum of three slow sinusoids (0.05 to
//!   0.3 Hz, random phases and axes) scaled so that it never exceeds [`MAX_DEG_PER_S`], the
//!   velocity likewise up to [`MAX_DIAG_PER_S`] diagonals a second, pulled back towards
//!   the start so that the part stays in view.
//! - **The view**: the exposed region (as through an incision, fixed on the part: the
//!   [`EXPOSED`] share of the surface nearest a point facing the camera at the start) as
//!   the camera sees it: self-occlusion by a point z-buffer (as the camera-view families'),
//!   so that 30 to 50% of the surface is in each scan; Gaussian noise of
//!   [`NOISE_FRACTION`] of the diagonal; clutter of [`CLUTTER_FRACTION`] of the scan's
//!   points, half in two blobs fixed in front of the part (a tool held still, hiding what
//!   is behind it), half uniform around the view.
//! - **The hidden stretch**: frames [`HIDDEN`] (a hand over the part) keep
//!   [`HIDDEN_SHARE`] of the part's points; in its middle the part jumps ([`JUMP_DEG`]
//!   about a random axis, [`JUMP_DIAG`] diagonals).
//!
//! Every sequence is a function of its seed and its shape.

use crate::eval::realistic::{unit_vector, Shape};
use crate::geometry::Pose;
use crate::visibility::{DepthImage, View};
use nalgebra::{Matrix3, Point3, Rotation3, Vector3};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Frames of a sequence.
pub const FRAMES: usize = 300;
/// Frame rate [Hz].
pub const FPS: f64 = 30.0;
/// Model points.
pub const MODEL_POINTS: usize = 3000;
/// Scan points (clutter included; fewer when the view holds fewer).
pub const SCAN_POINTS: usize = 1000;
/// Surface samples the views are cut from.
const SURFACE_POINTS: usize = 12_000;
/// The part's scale range.
pub const SCALE_RANGE: (f64, f64) = (0.8, 1.25);
/// The part's distance from the camera, in (scaled) diagonals.
pub const CAMERA_DISTANCE: f64 = 2.0;
/// Fastest rotation [deg/s].
pub const MAX_DEG_PER_S: f64 = 30.0;
/// Fastest translation [diagonals/s].
pub const MAX_DIAG_PER_S: f64 = 0.05;
/// Share of the surface exposed.
pub const EXPOSED: f64 = 0.55;
/// Noise, as a fraction of the diagonal.
pub const NOISE_FRACTION: f64 = 0.005;
/// Clutter, as a fraction of the scan's points.
pub const CLUTTER_FRACTION: f64 = 0.10;
/// The frames in which the part is almost hidden.
pub const HIDDEN: std::ops::Range<usize> = 150..180;
/// Share of the part's points left in a hidden frame.
pub const HIDDEN_SHARE: f64 = 0.05;
/// The jump in the middle of the hidden stretch: rotation [deg] ...
pub const JUMP_DEG: f64 = 40.0;
/// ... and translation [diagonals].
pub const JUMP_DIAG: f64 = 0.15;

/// One frame of a sequence.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The scan, in the camera's frame.
    pub scan: Vec<Point3<f64>>,
    /// Scan to model.
    pub truth: Pose,
    /// The part is almost hidden.
    pub hidden: bool,
}

/// A sequence.
#[derive(Clone, Debug)]
pub struct Sequence {
    /// `shape/seed`.
    pub id: String,
    /// The shape.
    pub shape: Shape,
    /// The model (the shape's frame).
    pub model: Vec<Point3<f64>>,
    /// The model's diagonal.
    pub diag: f64,
    /// The frames.
    pub frames: Vec<Frame>,
}

/// A smooth vector signal: three sinusoids of random axes, frequencies and phases, its
/// largest magnitude over the sequence scaled to `peak`.
struct Signal {
    parts: Vec<(Vector3<f64>, f64, f64)>,
    gain: f64,
}

impl Signal {
    fn new(rng: &mut impl Rng, peak: f64) -> Self {
        let parts: Vec<(Vector3<f64>, f64, f64)> = (0..3)
            .map(|_| (unit_vector(rng), rng.gen_range(0.05..0.3), rng.gen_range(0.0..std::f64::consts::TAU)))
            .collect();
        let mut s = Signal { parts, gain: 1.0 };
        let top = (0..FRAMES).map(|k| s.at(k as f64 / FPS).norm()).fold(0.0, f64::max);
        s.gain = peak / top.max(1e-12);
        s
    }
    fn at(&self, t: f64) -> Vector3<f64> {
        self.parts.iter().fold(Vector3::zeros(), |a, (v, f, p)| a + v * (std::f64::consts::TAU * f * t + p).sin())
            * self.gain
    }
}

/// The sequence of `shape` drawn with `seed`; `metric`: the part at scale 1 (a metric
/// camera and a model in the same units), else at a scale drawn in [`SCALE_RANGE`].
pub fn sequence(shape: Shape, seed: u64, metric: bool) -> Sequence {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (model, surface) = shape.draw(MODEL_POINTS, SURFACE_POINTS, &mut rng);
    let diag = crate::cloud::bbox_diagonal(&model);
    let centre = crate::cloud::centroid(&surface);
    let drawn = rng.gen_range(SCALE_RANGE.0..SCALE_RANGE.1);
    let scale = if metric { 1.0 } else { drawn };
    let size = scale * diag;
    let home = Vector3::new(0.0, 0.0, CAMERA_DISTANCE * size);
    // The part's pose in the camera's frame: x -> s R (x - c) + p.
    let mut rotation =
        Rotation3::from_scaled_axis(unit_vector(&mut rng) * rng.gen_range(0.0..std::f64::consts::PI)).into_inner();
    let mut position = home;
    let spin = Signal::new(&mut rng, MAX_DEG_PER_S.to_radians());
    let drift = Signal::new(&mut rng, MAX_DIAG_PER_S * size);
    let jump_axis = unit_vector(&mut rng);
    let jump_shift = unit_vector(&mut rng) * (JUMP_DIAG * size);
    let h = crate::eval::realistic::spacing(&surface) * scale;
    let noise = Normal::new(0.0, NOISE_FRACTION * size).expect("positive sigma");
    // The exposed region: the surface nearest a point facing the camera at the start.
    let placed = |rotation: &Matrix3<f64>, position: &Vector3<f64>, p: &Point3<f64>| {
        Point3::from(scale * (rotation * (p - centre)) + position)
    };
    let facing = surface
        .iter()
        .min_by(|a, b| placed(&rotation, &position, a).z.total_cmp(&placed(&rotation, &position, b).z))
        .copied()
        .expect("a surface");
    let mut order: Vec<usize> = (0..surface.len()).collect();
    order.sort_by(|&a, &b| (surface[a] - facing).norm().total_cmp(&(surface[b] - facing).norm()).then(a.cmp(&b)));
    let exposed: Vec<Point3<f64>> =
        order[..(EXPOSED * surface.len() as f64) as usize].iter().map(|&i| surface[i]).collect();
    // Two blobs in front of the part, fixed in the camera's frame.
    let blobs: Vec<(Point3<f64>, f64)> = (0..2)
        .map(|_| {
            let q = placed(&rotation, &position, exposed.choose(&mut rng).expect("exposed points"));
            (q - q.coords * rng.gen_range(0.08..0.3) * size / q.coords.norm(), rng.gen_range(0.03..0.05) * size)
        })
        .collect();

    let clutter_points = (CLUTTER_FRACTION * SCAN_POINTS as f64).round() as usize;
    let camera = Point3::origin();
    let dt = 1.0 / FPS;
    let mut frames = Vec::with_capacity(FRAMES);
    for k in 0..FRAMES {
        let t = k as f64 * dt;
        if k == (HIDDEN.start + HIDDEN.end) / 2 {
            rotation = Rotation3::from_scaled_axis(jump_axis * JUMP_DEG.to_radians()).into_inner() * rotation;
            position += jump_shift;
        }
        let in_camera: Vec<Point3<f64>> = exposed.iter().map(|p| placed(&rotation, &position, p)).collect();
        let target = Point3::from(position);
        let view = View::new(camera, &target, 5.0 * h).expect("the part is in front of the camera");
        let image = DepthImage::new(view, &in_camera, 10.0 * h);
        let mut seen: Vec<Point3<f64>> = in_camera.iter().filter(|p| image.sees(p, 5.0 * h)).copied().collect();
        for (b, r) in &blobs {
            let (to_b, dist_b) = ((b - camera).normalize(), (b - camera).norm());
            let half_angle = (r / dist_b).min(1.0).asin();
            seen.retain(|p| {
                let to_p = p - camera;
                to_p.norm() <= dist_b || to_p.normalize().dot(&to_b).clamp(-1.0, 1.0).acos() >= half_angle
            });
        }
        let hidden = HIDDEN.contains(&k);
        seen.shuffle(&mut rng);
        let keep = if hidden {
            (HIDDEN_SHARE * SCAN_POINTS as f64) as usize
        } else {
            SCAN_POINTS.saturating_sub(clutter_points)
        };
        seen.truncate(keep);
        let mut scan: Vec<Point3<f64>> =
            seen.iter().map(|p| p + Vector3::from_fn(|_, _| noise.sample(&mut rng))).collect();
        // Clutter: the blobs' camera-facing halves and uniform points around the view.
        for (i, (b, r)) in blobs.iter().enumerate() {
            let n = clutter_points / 4 + usize::from(i == 0) * (clutter_points / 2 - 2 * (clutter_points / 4));
            let facing = (camera - b).normalize();
            let mut added = 0;
            while added < n {
                let d = unit_vector(&mut rng);
                if d.dot(&facing) > 0.0 {
                    scan.push(b + d * *r);
                    added += 1;
                }
            }
        }
        let (lo, hi) = crate::cloud::bbox(&in_camera);
        let grow = Vector3::repeat(0.1 * size);
        let (lo, hi) = (lo - grow, hi + grow);
        for _ in 0..clutter_points - clutter_points / 2 {
            scan.push(Point3::new(rng.gen_range(lo.x..hi.x), rng.gen_range(lo.y..hi.y), rng.gen_range(lo.z..hi.z)));
        }
        scan.shuffle(&mut rng);
        // Scan to model: the inverse of x -> s R (x - c) + p.
        let part = Pose { scale, rotation, translation: position - scale * (rotation * centre.coords) };
        frames.push(Frame { scan, truth: part.inverse(), hidden });
        // The motion to the next frame, pulled back towards home.
        let omega = spin.at(t);
        rotation = Rotation3::from_scaled_axis(omega * dt).into_inner() * rotation;
        position += (drift.at(t) + (home - position) * 0.2) * dt;
    }
    Sequence { id: format!("{}/{seed}", shape.name()), shape, model, diag, frames }
}
