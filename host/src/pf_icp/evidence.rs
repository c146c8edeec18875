//! What the scan itself says about a pose, beyond its distance to the surface.
//!
//! - **Its noise** ([`scan_noise`]): the spread of each scan point's neighbourhood about
//!   its own best plane (the smallest principal spread of its [`NOISE_NEIGHBOURS`] nearest
//!   scan points), median over the scan: the sensor's noise in the scan's units, whatever
//!   the pose. It sets the inlier band of [`scan_cost`].
//! - **A cost in the scan's units** ([`scan_cost`]): each scan point's surface distance
//!   divided by the pose's scale (what the sensor measured), capped at [`SCAN_CAP_SIGMAS`]
//!   noise sigmas. In the model's units every distance shrinks with the scale, so a
//!   shrunk scan collapsed onto part of the model, clutter and all, costs less than the
//!   truth; in the scan's units it does not, and a cap a few noise sigmas wide leaves the
//!   clutter (10% of a camera view, 5% of the diagonal away) no pull.
//! - **Visibility** ([`hidden`]): with the sensor's position known (`--viewpoint`), a scan
//!   point that the model's surface would hide from the sensor (model surface in front of
//!   it, along the sensor's ray, by more than [`HIDDEN_DEPTH`] model spacings) could
//!   not have been seen: a pose that lays the scan on surface facing away from the sensor,
//!   or inside the part, is wrong. The model's surface as the sensor would see it is a
//!   surfel image ([`crate::visibility::SurfelImage`]: each model point a disc
//!   [`SURFEL_SPACINGS`] model spacings in radius in its normal's plane, pixels
//!   [`PIXEL_SPACINGS`] spacing wide at the scan's distance), and each scan point is
//!   compared with the surface's depth along its own ray. A point z-buffer (the nearest
//!   sample a pixel five spacings wide) put the surface up to a pixel's width times the
//!   tangent of the viewing angle in front of itself: on the right poses of the camera
//!   views' dev split it called 5 to 12% of the scan hidden that lies on the surface; the
//!   surfels 0.3 to 1.7% (discs 1.5 spacings wide leave a fifth of a randomly sampled
//!   surface uncovered, 2 spacings about 6%).

use crate::geometry::Pose;
use crate::nn::NearestNeighbours;
use crate::pf_icp::surface::Surface;
use crate::visibility::{SurfelImage, View};
use nalgebra::{Matrix3, Point3, Vector3};
use rayon::prelude::*;

/// Neighbours of the scan's noise estimate.
pub const NOISE_NEIGHBOURS: usize = 10;
/// Cap of [`scan_cost`], in noise sigmas.
pub const SCAN_CAP_SIGMAS: f64 = 3.0;
/// Width of a visibility pixel, in the model's spacings.
pub const PIXEL_SPACINGS: f64 = 1.0;
/// Radius of each model point's disc in the visibility image, in the model's spacings.
pub const SURFEL_SPACINGS: f64 = 2.0;
/// Most model points drawn into the visibility image.
pub const MAX_SURFELS: usize = 20_000;
/// A scan point is hidden when model surface lies this many model spacings in front of it.
pub const HIDDEN_DEPTH: f64 = 6.0;

/// The scan's noise: the median over its points of the root smallest principal spread of
/// each point's neighbourhood, times `sqrt(k / (k - 3))` (the plane's three degrees of
/// freedom). In the scan's units.
pub fn scan_noise(scan: &[Point3<f64>]) -> f64 {
    if scan.len() <= NOISE_NEIGHBOURS {
        return 0.0;
    }
    let nn = NearestNeighbours::new(scan);
    let step = (scan.len() / 2000).max(1);
    let spreads: Vec<f64> = scan
        .par_iter()
        .step_by(step)
        .map(|p| {
            let near = nn.nearest_k(p, NOISE_NEIGHBOURS + 1);
            let pts: Vec<Vector3<f64>> = near.iter().map(|c| scan[c.index].coords).collect();
            let c = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
            let cov = pts.iter().fold(Matrix3::zeros(), |a, q| a + (q - c) * (q - c).transpose()) / pts.len() as f64;
            cov.symmetric_eigenvalues().min().max(0.0).sqrt()
        })
        .collect();
    let k = (NOISE_NEIGHBOURS + 1) as f64;
    crate::registration::icp::median(&spreads) * (k / (k - 3.0)).sqrt()
}

/// The scan's own evidence for ranking poses: its noise, the caps of the cost in the scan's
/// units, the sensor's position if known.
#[derive(Clone, Copy, Debug)]
pub struct Evidence {
    /// [`scan_noise`] (scan units).
    pub noise: f64,
    /// Cap of the wide cost (scan units): [`crate::pf_icp::surface::COST_CAP`] of the
    /// model's diagonal at the scale guess, for ranking poses that have not converged.
    pub wide_cap: f64,
    /// Cap of the tight cost (scan units): [`SCAN_CAP_SIGMAS`] noise sigmas, at least one
    /// model spacing at the scale guess (a noise-free scan), for comparing converged poses.
    pub tight_cap: f64,
    /// The sensor's position in the scan's frame.
    pub viewpoint: Option<Point3<f64>>,
}

impl Evidence {
    /// From the scan, the model's surface and a scale guess (scan to model).
    pub fn new(surface: &Surface, scan: &[Point3<f64>], scale_guess: f64, viewpoint: Option<Point3<f64>>) -> Self {
        let s = scale_guess.max(1e-300);
        let diag = crate::cloud::bbox_diagonal(surface.nn().points());
        let noise = scan_noise(scan);
        Evidence {
            noise,
            wide_cap: crate::pf_icp::surface::COST_CAP * diag / s,
            tight_cap: (SCAN_CAP_SIGMAS * noise).max(surface.spacing() / s),
            viewpoint,
        }
    }

    /// The wide cost of `pose` over `points` (mean of [`scan_costs`] at [`Evidence::wide_cap`]).
    pub fn wide_cost(&self, surface: &Surface, points: &[Point3<f64>], pose: &Pose) -> f64 {
        scan_cost(surface, points, pose, self.wide_cap)
    }

    /// Per point: the tight cost ([`scan_costs`] at [`Evidence::tight_cap`]), a point the
    /// model would hide from the sensor ([`hidden`]) at the cap.
    pub fn tight_costs(&self, surface: &Surface, points: &[Point3<f64>], pose: &Pose) -> Vec<f64> {
        let mut c = scan_costs(surface, points, pose, self.tight_cap);
        if let Some(v) = &self.viewpoint {
            let cap2 = self.tight_cap * self.tight_cap;
            for (c, h) in c.iter_mut().zip(hidden(surface, points, pose, v)) {
                if h {
                    *c = cap2;
                }
            }
        }
        c
    }
}

/// Per scan point: `min((d / s)^2, cap^2)`, `d` the surface distance under `pose` (model
/// units), `s` its scale, `cap` in the scan's units.
pub fn scan_costs(surface: &Surface, scan: &[Point3<f64>], pose: &Pose, cap: f64) -> Vec<f64> {
    let s2 = pose.scale * pose.scale;
    let cap2 = cap * cap;
    scan.par_iter().map(|p| (surface.distance2(&pose.apply(p)) / s2).min(cap2)).collect()
}

/// Mean of [`scan_costs`].
pub fn scan_cost(surface: &Surface, scan: &[Point3<f64>], pose: &Pose, cap: f64) -> f64 {
    scan_costs(surface, scan, pose, cap).iter().sum::<f64>() / scan.len().max(1) as f64
}

/// Per scan point: whether the model's surface hides it from `viewpoint` (scan frame)
/// under `pose` (the module's rule). All `false` when the viewpoint is inside the model's
/// bounding box or the pose puts the scan behind it.
pub fn hidden(surface: &Surface, scan: &[Point3<f64>], pose: &Pose, viewpoint: &Point3<f64>) -> Vec<bool> {
    let q: Vec<Point3<f64>> = scan.iter().map(|p| pose.apply(p)).collect();
    if q.is_empty() {
        return Vec::new();
    }
    let h = surface.spacing().max(1e-12);
    let Some(view) = View::new(pose.apply(viewpoint), &crate::cloud::centroid(&q), PIXEL_SPACINGS * h) else {
        return vec![false; scan.len()];
    };
    // At most MAX_SURFELS of the model's points (every k-th, their discs sqrt(k) wider).
    let model = surface.nn().points();
    let stride = model.len().div_ceil(MAX_SURFELS).max(1);
    let (points, normals): (Vec<Point3<f64>>, Vec<Vector3<f64>>) =
        (0..model.len()).step_by(stride).map(|i| (model[i], surface.normal(i))).unzip();
    let image = SurfelImage::new(view, &points, &normals, SURFEL_SPACINGS * h * (stride as f64).sqrt(), &q);
    let tolerance = HIDDEN_DEPTH * h;
    q.iter().map(|p| matches!(image.front(p), Some((Some(z), d)) if z < d - tolerance)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parts::Part;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// The noise of a noisy box surface comes out near the noise put in.
    #[test]
    fn the_scan_noise_is_the_noise_put_in() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let pts = Part::Block.sample_surface(3000, &mut rng);
        for sigma in [0.002, 0.005] {
            let n = Normal::new(0.0, sigma).unwrap();
            let noisy: Vec<Point3<f64>> = pts
                .iter()
                .map(|p| p + Vector3::new(n.sample(&mut rng), n.sample(&mut rng), n.sample(&mut rng)))
                .collect();
            let est = scan_noise(&noisy);
            assert!((est / sigma - 1.0).abs() < 0.35, "{est} for {sigma}");
        }
    }

    /// The front of a box seen from its front is visible; the same points laid on the back
    /// face (a pose turned 180 degrees) are hidden.
    #[test]
    fn points_on_the_far_side_are_hidden() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let model = Part::Block.sample_surface(3000, &mut rng);
        let nn = NearestNeighbours::new(&model);
        let surface = Surface::new(&nn);
        let zmax = model.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
        let front: Vec<Point3<f64>> = model.iter().filter(|p| p.z > zmax - 1e-9).copied().collect();
        assert!(front.len() > 100);
        let eye = Point3::new(0.0, 0.0, 3.0);
        let seen = hidden(&surface, &front, &Pose::identity(), &eye);
        assert!(seen.iter().filter(|&&h| h).count() * 50 < front.len());
        let turn = Pose::from_params(&[0.0, 0.0, 0.0, 1.0, std::f64::consts::PI, 0.0, 0.0]);
        // The front face turned onto the back face, the eye staying above the front face.
        let back: Vec<Point3<f64>> = front.iter().map(|p| turn.apply(p)).collect();
        let flagged = hidden(&surface, &back, &Pose::identity(), &eye);
        assert!(
            flagged.iter().filter(|&&h| h).count() * 10 > 9 * back.len(),
            "{} of {}",
            flagged.iter().filter(|&&h| h).count(),
            back.len()
        );
    }
}
