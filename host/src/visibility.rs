//! What a sensor at a point sees of a point cloud sampled on a surface: a perspective view
//! ([`View`]) and a point z-buffer ([`DepthImage`]) in it.
//!
//! Pixels are angles: a pixel spans `width / distance` radians, `width` chosen by the
//! caller in a few sample spacings at the distance of interest so that a surface facing
//! the sensor covers every pixel it spans. A pixel that the near surface happens to leave
//! empty would show what lies behind it; [`DepthImage::front`] gives it its neighbours'
//! median depth when most of them (5 of 8) see surface nearer by more than a gap.
//! Used by the camera-view benchmark (making the views), by the visibility evidence
//! (`crate::pf_icp::evidence::hidden`) and by the search's view starts.

use nalgebra::{Point3, Vector3};
use std::collections::HashMap;

/// A perspective view from `eye` towards a target.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// The sensor's position.
    pub eye: Point3<f64>,
    u: Vector3<f64>,
    v: Vector3<f64>,
    w: Vector3<f64>,
    pixel: f64,
}

/// A pixel: its column and row.
pub type Pixel = (i64, i64);

impl View {
    /// From `eye` looking at `target`, pixels `width` wide at the target's distance
    /// (`None` when the two coincide or the width is not positive).
    pub fn new(eye: Point3<f64>, target: &Point3<f64>, width: f64) -> Option<View> {
        let axis = target - eye;
        let distance = axis.norm();
        if !(distance > 0.0 && width > 0.0 && distance.is_finite()) {
            return None;
        }
        let w = axis / distance;
        let helper = if w.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        let u = w.cross(&helper).normalize();
        let v = w.cross(&u);
        Some(View { eye, u, v, w, pixel: width / distance })
    }

    /// `p`'s image coordinates (tangents of its angles across the viewing direction) and
    /// depth along it; `None` behind the sensor.
    pub fn image(&self, p: &Point3<f64>) -> Option<(f64, f64, f64)> {
        let r = p - self.eye;
        let depth = r.dot(&self.w);
        (depth > 0.0).then(|| (r.dot(&self.u) / depth, r.dot(&self.v) / depth, depth))
    }

    /// `p`'s pixel and depth; `None` behind the sensor.
    pub fn project(&self, p: &Point3<f64>) -> Option<(Pixel, f64)> {
        self.image(p).map(|(x, y, d)| (((x / self.pixel).floor() as i64, (y / self.pixel).floor() as i64), d))
    }
}

/// The nearest depth in every pixel a cloud covers.
#[derive(Clone, Debug)]
pub struct DepthImage {
    view: View,
    depth: HashMap<Pixel, f64>,
    gap: f64,
}

impl DepthImage {
    /// `points` as `view` sees them; `gap` is the depth by which neighbours must be nearer
    /// to fill a pixel ([`DepthImage::front`]).
    pub fn new(view: View, points: &[Point3<f64>], gap: f64) -> Self {
        let mut depth: HashMap<Pixel, f64> = HashMap::new();
        for p in points {
            if let Some((px, d)) = view.project(p) {
                let z = depth.entry(px).or_insert(f64::INFINITY);
                *z = z.min(d);
            }
        }
        DepthImage { view, depth, gap }
    }

    /// The view.
    pub fn view(&self) -> &View {
        &self.view
    }

    /// The depth of the surface in front at `px`: its own nearest depth, or its
    /// neighbours' median when at least 5 of the 8 see surface nearer by more than the gap
    /// (or the pixel is empty); `None` where nothing is seen.
    pub fn front(&self, (i, j): Pixel) -> Option<f64> {
        let own = self.depth.get(&(i, j)).copied();
        let mut near: Vec<f64> = (-1..=1)
            .flat_map(|a| (-1..=1).map(move |b| (a, b)))
            .filter(|&(a, b)| (a, b) != (0, 0))
            .filter_map(|(a, b)| self.depth.get(&(i + a, j + b)).copied())
            .filter(|&n| own.is_none_or(|z| n < z - self.gap))
            .collect();
        if near.len() >= 5 {
            near.sort_by(f64::total_cmp);
            Some(near[near.len() / 2])
        } else {
            own
        }
    }

    /// Whether `p` is seen: within `tolerance` behind the front surface of its pixel.
    pub fn sees(&self, p: &Point3<f64>, tolerance: f64) -> bool {
        self.view.project(p).is_some_and(|(px, d)| self.front(px).is_none_or(|z| d <= z + tolerance))
    }
}

/// The depth of a surface given as oriented samples (surfels: a point, its unit normal and
/// a disc of `radius` about it in the normal's plane), pixel by pixel: each pixel's ray is
/// cut with the planes of the discs that project near it, and the nearest cut inside its
/// disc is the pixel's depth. Unlike [`DepthImage`]'s nearest sample a pixel wide, the
/// depth is the surface's along the ray itself, on a face seen at a grazing angle as well
/// as on one facing the sensor.
#[derive(Clone, Debug)]
pub struct SurfelImage {
    view: View,
    origin: Pixel,
    columns: usize,
    depth: Vec<f64>,
    /// The plane (a point and its normal) of each pixel's nearest cut.
    plane: Vec<(Point3<f64>, Vector3<f64>)>,
}

/// Most pixels of a [`SurfelImage`] a side (a larger extent gets wider pixels).
pub const SURFEL_IMAGE_SIDE: usize = 1024;

/// Most pixels a disc reaches from its centre's pixel.
pub const MAX_SURFEL_REACH: usize = 16;

/// A ray more than this far from perpendicular to a disc's plane (cosine below) does not
/// cut it: a disc seen edge-on covers no area.
const GRAZING_COSINE: f64 = 0.05;

impl SurfelImage {
    /// The surfels `points` (with `normals`, unit) of `radius` as `view` sees them, in the
    /// pixels about where `queries` (the points [`SurfelImage::front`] will be asked about)
    /// project.
    pub fn new(
        view: View,
        points: &[Point3<f64>],
        normals: &[Vector3<f64>],
        radius: f64,
        queries: &[Point3<f64>],
    ) -> Self {
        let extent = |pts: &[Point3<f64>], pixel: f64| {
            let (mut lo, mut hi) = ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN));
            for (x, y, _) in pts.iter().filter_map(|p| view.image(p)) {
                let (i, j) = ((x / pixel).floor() as i64, (y / pixel).floor() as i64);
                lo = (lo.0.min(i), lo.1.min(j));
                hi = (hi.0.max(i), hi.1.max(j));
            }
            (lo, hi)
        };
        let (lo, hi) = extent(queries, view.pixel);
        if lo.0 > hi.0 {
            return SurfelImage { view, origin: (0, 0), columns: 0, depth: Vec::new(), plane: Vec::new() };
        }
        // (Wider pixels when the extent would exceed the side.)
        let side = (hi.0 - lo.0).max(hi.1 - lo.1) as usize + 1;
        let view = if side > SURFEL_IMAGE_SIDE {
            View { pixel: view.pixel * side as f64 / SURFEL_IMAGE_SIDE as f64, ..view }
        } else {
            view
        };
        let margin = 2;
        let cell = |x: f64| (x / view.pixel).floor() as i64;
        let (lo, hi) = extent(queries, view.pixel);
        let projected: Vec<Option<(f64, f64, f64)>> = points.iter().map(|p| view.image(p)).collect();
        let origin = (lo.0 - margin, lo.1 - margin);
        let columns = (hi.0 - lo.0 + 1 + 2 * margin) as usize;
        let rows = (hi.1 - lo.1 + 1 + 2 * margin) as usize;
        let mut depth = vec![f64::INFINITY; columns * rows];
        let mut plane = vec![(Point3::origin(), Vector3::zeros()); columns * rows];
        for ((p, n), image) in points.iter().zip(normals).zip(&projected) {
            let Some((x, y, d)) = image else { continue };
            // Pixels the disc may cover: its radius at its depth about its centre's image
            // (at most MAX_SURFEL_REACH pixels away: a disc next to the sensor would cover
            // the image).
            let r = (radius / d * (1.0 + x * x + y * y)).min(MAX_SURFEL_REACH as f64 * view.pixel);
            let offset = (p - view.eye).dot(n);
            for i in cell(x - r).max(origin.0)..=cell(x + r).min(origin.0 + columns as i64 - 1) {
                for j in cell(y - r).max(origin.1)..=cell(y + r).min(origin.1 + rows as i64 - 1) {
                    let ray =
                        view.w + view.u * ((i as f64 + 0.5) * view.pixel) + view.v * ((j as f64 + 0.5) * view.pixel);
                    let along = ray.dot(n);
                    if along.abs() < GRAZING_COSINE * ray.norm() {
                        continue;
                    }
                    // The cut at eye + t ray; its depth along w is t (ray.w = 1).
                    let t = offset / along;
                    if t <= 0.0 || (view.eye + ray * t - p).norm() > radius {
                        continue;
                    }
                    let k = (j - origin.1) as usize * columns + (i - origin.0) as usize;
                    if t < depth[k] {
                        depth[k] = t;
                        plane[k] = (*p, *n);
                    }
                }
            }
        }
        SurfelImage { view, origin, columns, depth, plane }
    }

    /// The view (its pixels as wide as the image made them).
    pub fn view(&self) -> &View {
        &self.view
    }

    /// The surface's depth along `p`'s own ray (cut with the plane of the nearest disc of
    /// its pixel; the pixel's depth when that ray grazes the plane) and `p`'s depth; `None`
    /// behind the sensor, the surface's depth `None` where no disc covers the pixel.
    pub fn front(&self, p: &Point3<f64>) -> Option<(Option<f64>, f64)> {
        let ((i, j), d) = self.view.project(p)?;
        let (a, b) = (i - self.origin.0, j - self.origin.1);
        let inside = self.columns > 0 && a >= 0 && b >= 0 && (a as usize) < self.columns;
        let Some(k) = inside.then(|| b as usize * self.columns + a as usize).filter(|&k| k < self.depth.len()) else {
            return Some((None, d));
        };
        if !self.depth[k].is_finite() {
            return Some((None, d));
        }
        let (q, n) = self.plane[k];
        let ray = (p - self.view.eye) / d;
        let along = ray.dot(&n);
        let t = (q - self.view.eye).dot(&n) / along;
        Some((Some(if along.abs() >= GRAZING_COSINE * ray.norm() && t > 0.0 { t } else { self.depth[k] }), d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two parallel planes: the near one is seen, the far one behind it is not.
    #[test]
    fn the_far_plane_is_hidden_behind_the_near_one() {
        let grid = |z: f64| -> Vec<Point3<f64>> {
            (0..60).flat_map(|i| (0..60).map(move |j| Point3::new(i as f64 * 0.01, j as f64 * 0.01, z))).collect()
        };
        let (near, far) = (grid(0.0), grid(-0.2));
        let all: Vec<Point3<f64>> = near.iter().chain(&far).copied().collect();
        let view = View::new(Point3::new(0.3, 0.3, 2.0), &Point3::new(0.3, 0.3, 0.0), 0.03).unwrap();
        let image = DepthImage::new(view, &all, 0.05);
        let inner = |p: &&Point3<f64>| (0.05..0.55).contains(&p.x) && (0.05..0.55).contains(&p.y);
        assert!(near.iter().filter(inner).all(|p| image.sees(p, 0.02)));
        assert!(far.iter().filter(inner).all(|p| !image.sees(p, 0.02)));
    }

    /// A plane seen at 80 degrees from its normal: the surfel image gives every sample its
    /// own depth (the nearest sample a pixel wide would be up to a pixel's width times
    /// tan 80 degrees nearer), and a point behind the plane along a ray is behind it.
    #[test]
    fn a_plane_seen_at_a_grazing_angle_has_its_own_depth() {
        let tilt = 80f64.to_radians();
        let n = Vector3::new(0.0, tilt.sin(), tilt.cos());
        let along = Vector3::new(0.0, tilt.cos(), -tilt.sin());
        let plane: Vec<Point3<f64>> = (0..80)
            .flat_map(|i| {
                (0..80).map(move |j| {
                    Point3::origin() + Vector3::x() * (i as f64 * 0.01 - 0.4) + along * (j as f64 * 0.01 - 0.4)
                })
            })
            .collect();
        let normals = vec![n; plane.len()];
        let view = View::new(Point3::new(0.0, 0.0, 3.0), &Point3::origin(), 0.01).unwrap();
        let image = SurfelImage::new(view, &plane, &normals, 0.015, &plane);
        let inner: Vec<&Point3<f64>> =
            plane.iter().filter(|p| p.x.abs() < 0.3 && p.coords.dot(&along).abs() < 0.3).collect();
        let mut worst = 0.0f64;
        for p in &inner {
            let (front, d) = image.front(p).unwrap();
            worst = worst.max((front.expect("covered") - d).abs());
        }
        // (The depth varies by 0.01 tan 80 = 0.057 across a pixel.)
        assert!(worst < 1e-9, "{worst}");
        let behind = Point3::new(0.05, 0.0, -0.3);
        let (front, d) = image.front(&behind).unwrap();
        assert!(front.unwrap() < d - 0.2);
    }
}
