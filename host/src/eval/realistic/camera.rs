//! What a depth camera over an operating table sees of a part: the camera-view families'
//! scans ([`camera_view`]).
//!
//! 1. **The camera**: at [`CAMERA_DISTANCE`] diagonals from the shape's bounding-box centre
//!    in a random direction, looking at the centre (a perspective camera); the first of up
//!    to [`DIRECTION_TRIES`] random directions that sees at least the window's share of the
//!    surface (step 3), else the one that sees the most.
//! 2. **Self-occlusion**: a point z-buffer in the camera's image (a pixel that the near surface
//!    leaves empty takes its neighbours' depth). Pixels are
//!    [`PIXEL_SPACINGS`] times the surface samples' spacing wide at the shape's distance,
//!    so that the front surface covers every pixel it spans; a point is seen when its depth
//!    is within [`DEPTH_TOLERANCE`] spacings of the nearest depth in its pixel. Surfaces
//!    seen at a grazing angle lose points, as a depth camera's do.
//! 3. **The window**: of the seen points, those nearest (in the image) to a random seen
//!    point, until the view holds a fraction of the whole surface drawn from
//!    [`VISIBLE_RANGE`] (all the seen points when fewer).
//! 4. **Clutter**: [`CLUTTER_FRACTION`] of the scan's points, half of it in one to three
//!    compact blobs between the camera and the surface (the camera-facing half of a sphere
//!    of 3 to 6% of the diagonal, 8 to 30% of the diagonal in front of a seen point: a
//!    tool, a gloved hand), which hide the surface behind them, and half uniform in the
//!    view's bounding box grown by 10% of the diagonal.

use crate::visibility::{DepthImage, View};
use nalgebra::{Point3, Vector3};
use rand::seq::SliceRandom;
use rand::Rng;

/// Distance of the camera from the shape's centre, in bounding-box diagonals.
pub const CAMERA_DISTANCE: f64 = 2.0;
/// Width of a z-buffer pixel at the shape's distance, in spacings (the median distance of a
/// surface sample to its nearest neighbour, about half the samples' mean spacing: a pixel
/// facing the camera holds about six samples).
pub const PIXEL_SPACINGS: f64 = 5.0;
/// A point is seen within this many spacings behind the nearest depth of its pixel.
pub const DEPTH_TOLERANCE: f64 = 5.0;
/// Fraction of the whole surface a camera view keeps.
pub const VISIBLE_RANGE: (f64, f64) = (0.25, 0.5);
/// Clutter, as a fraction of the scan's points.
pub const CLUTTER_FRACTION: f64 = 0.10;
/// Share of the clutter in compact blobs in front of the surface (the rest uniform).
pub const BLOB_SHARE: f64 = 0.5;

/// A camera view of a shape, in the shape's (model) frame.
#[derive(Clone, Debug)]
pub struct CameraView {
    /// The seen surface points in the window, not occluded by clutter (before noise).
    pub surface: Vec<Point3<f64>>,
    /// Clutter points (blobs and uniform).
    pub clutter: Vec<Point3<f64>>,
    /// The camera's position.
    pub camera: Point3<f64>,
    /// Fraction of the surface in the view: the window's points over all the points given.
    pub visible: f64,
}

fn unit_vector(rng: &mut impl Rng) -> Vector3<f64> {
    loop {
        let v = Vector3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let n = v.norm();
        if n > 1e-3 && n <= 1.0 {
            return v / n;
        }
    }
}

/// The median distance of a point of `points` to its nearest other point.
pub fn spacing(points: &[Point3<f64>]) -> f64 {
    let nn = crate::nn::NearestNeighbours::new(points);
    let step = (points.len() / 2000).max(1);
    let gaps: Vec<f64> = points
        .iter()
        .step_by(step)
        .filter_map(|p| nn.nearest_k(p, 2).iter().find(|c| c.dist2 > 0.0).map(|c| c.dist2.sqrt()))
        .collect();
    crate::registration::icp::median(&gaps)
}

/// Directions tried for a camera that sees the window's share of the surface.
const DIRECTION_TRIES: usize = 20;

/// What a camera in one direction sees.
struct Sight {
    camera: Point3<f64>,
    view: View,
    /// The points it sees.
    seen: Vec<usize>,
}

/// The camera at [`CAMERA_DISTANCE`] diagonals from `centre` in direction `dir`, and the
/// points of `points` (spacing `h`) it sees.
fn look(points: &[Point3<f64>], centre: &Point3<f64>, diag: f64, h: f64, dir: &Vector3<f64>) -> Sight {
    let camera = centre + dir * (CAMERA_DISTANCE * diag);
    let view = View::new(camera, centre, PIXEL_SPACINGS * h).expect("the camera is away from the centre");
    let image = DepthImage::new(view, points, 2.0 * DEPTH_TOLERANCE * h);
    let seen = (0..points.len()).filter(|&i| image.sees(&points[i], DEPTH_TOLERANCE * h)).collect();
    Sight { camera, view, seen }
}

/// A camera view of the surface sampled by `points` (uniform by area), `scan_points` points
/// in all (clutter included; fewer when the window holds fewer), drawn with `rng`.
pub fn camera_view(points: &[Point3<f64>], diag: f64, scan_points: usize, rng: &mut impl Rng) -> CameraView {
    let (lo, hi) = crate::cloud::bbox(points);
    let centre = nalgebra::center(&lo, &hi);
    let h = spacing(points);
    let target = (rng.gen_range(VISIBLE_RANGE.0..VISIBLE_RANGE.1) * points.len() as f64).round() as usize;
    // The first direction that sees at least the window's share of the surface (a folded
    // surface, or a plate seen edge on, may see less: the best of the tries then).
    let mut best: Option<Sight> = None;
    for _ in 0..DIRECTION_TRIES {
        let sight = look(points, &centre, diag, h, &unit_vector(rng));
        let enough = sight.seen.len() >= target;
        if best.as_ref().is_none_or(|b| sight.seen.len() > b.seen.len()) {
            best = Some(sight);
        }
        if enough {
            break;
        }
    }
    let Sight { camera, view, seen } = best.expect("at least one try");
    let image: Vec<(f64, f64)> =
        points.iter().map(|p| view.image(p).map_or((f64::INFINITY, f64::INFINITY), |(x, y, _)| (x, y))).collect();

    // The window: the seen points nearest a random seen point in the image.
    let mut window = seen;
    if window.len() > target {
        let &c = window.choose(rng).expect("a seen point");
        let (cx, cy) = (image[c].0, image[c].1);
        let d2 = |i: usize| (image[i].0 - cx).powi(2) + (image[i].1 - cy).powi(2);
        window.sort_by(|&a, &b| d2(a).total_cmp(&d2(b)).then(a.cmp(&b)));
        window.truncate(target);
    }
    let visible = window.len() as f64 / points.len().max(1) as f64;
    let mut surface: Vec<Point3<f64>> = window.iter().map(|&i| points[i]).collect();

    // Blobs in front of the surface, hiding what is behind them.
    let clutter_points = (CLUTTER_FRACTION * scan_points as f64).round() as usize;
    let blob_points = (BLOB_SHARE * clutter_points as f64).round() as usize;
    let blobs = rng.gen_range(1..=3usize);
    let mut clutter = Vec::with_capacity(clutter_points);
    for k in 0..blobs {
        let Some(&q) = surface.choose(rng) else { break };
        let toward = (camera - q).normalize();
        let b = q + toward * (rng.gen_range(0.08..0.30) * diag);
        let r = rng.gen_range(0.03..0.06) * diag;
        let n = blob_points / blobs + usize::from(k < blob_points % blobs);
        let facing = (camera - b).normalize();
        let mut added = 0;
        while added < n {
            let d = unit_vector(rng);
            if d.dot(&facing) > 0.0 {
                clutter.push(b + d * r);
                added += 1;
            }
        }
        let (to_b, dist_b) = ((b - camera).normalize(), (b - camera).norm());
        let half_angle = (r / dist_b).min(1.0).asin();
        surface.retain(|p| {
            let to_p = p - camera;
            to_p.norm() <= dist_b || to_p.normalize().dot(&to_b).clamp(-1.0, 1.0).acos() >= half_angle
        });
    }
    // Uniform clutter around the view.
    if !surface.is_empty() {
        let (lo, hi) = crate::cloud::bbox(&surface);
        let grow = Vector3::repeat(0.1 * diag);
        let (lo, hi) = (lo - grow, hi + grow);
        while clutter.len() < clutter_points {
            clutter.push(Point3::new(rng.gen_range(lo.x..hi.x), rng.gen_range(lo.y..hi.y), rng.gen_range(lo.z..hi.z)));
        }
    }
    // The scan's size: the surface subsampled to the rest.
    surface.shuffle(rng);
    surface.truncate(scan_points.saturating_sub(clutter.len()));
    CameraView { surface, clutter, camera, visible }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// A sphere seen from outside: a cap facing the camera (no point of the far side), the
    /// requested size, and clutter in the stated amount.
    #[test]
    fn a_sphere_shows_the_cap_that_faces_the_camera() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let pts: Vec<Point3<f64>> = (0..20_000).map(|_| Point3::from(unit_vector(&mut rng))).collect();
        let diag = crate::cloud::bbox_diagonal(&pts);
        for seed in 0..5 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let view = camera_view(&pts, diag, 1500, &mut rng);
            let to_camera = view.camera.coords.normalize();
            // Every surface point faces the camera (a sphere hides its far side; the
            // tolerance lets through only points within a few spacings of the rim).
            let facing = view.surface.iter().filter(|p| p.coords.dot(&to_camera) > -0.05).count();
            assert_eq!(facing, view.surface.len(), "seed {seed}");
            assert!((VISIBLE_RANGE.0 - 0.01..=0.5).contains(&view.visible), "{}", view.visible);
            assert_eq!(view.surface.len() + view.clutter.len(), 1500);
            assert_eq!(view.clutter.len(), 150);
        }
    }
}
