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
}
