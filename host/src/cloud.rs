//! Point clouds and their validation.

use nalgebra::{Point3, Vector3};
use thiserror::Error;

/// Why a cloud was rejected.
#[derive(Debug, Error, PartialEq)]
pub enum CloudError {
    /// No points at all.
    #[error("{0} cloud is empty")]
    Empty(String),
    /// A NaN or infinite coordinate.
    #[error("{name} cloud has a non-finite coordinate at point {index} ({value})")]
    NonFinite {
        /// Which cloud.
        name: String,
        /// Index of the offending point.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// More points than a limit allows.
    #[error("{name} cloud has {count} points, more than the limit of {limit}")]
    TooLarge {
        /// Which cloud.
        name: String,
        /// Points in the cloud.
        count: usize,
        /// The limit.
        limit: usize,
    },
    /// A coordinate beyond [`MAX_COORDINATE`] in magnitude.
    #[error("{name} cloud has a coordinate of {value:e} at point {index}, beyond the limit of {limit:e} in magnitude")]
    OutOfRange {
        /// Which cloud.
        name: String,
        /// Index of the offending point.
        index: usize,
        /// The offending value.
        value: f64,
        /// The limit.
        limit: f64,
    },
    /// A point far beyond the rest (a sensor's sentinel value, a unit error).
    #[error(
        "{name} cloud has point {index} at {distance:e} from the cloud's median point, more than {limit:e} times the \
         median distance ({spread:e}) of its points (a sensor's sentinel value?)"
    )]
    FarPoint {
        /// Which cloud.
        name: String,
        /// Index of the offending point.
        index: usize,
        /// Its distance from the median point.
        distance: f64,
        /// The median distance of the points from the median point.
        spread: f64,
        /// The allowed ratio.
        limit: f64,
    },
    /// All points coincide: no extent to register against.
    #[error("{0} cloud has no extent (all points coincide)")]
    Degenerate(String),
}

/// A validated, non-empty cloud of finite points.
#[derive(Clone, Debug, PartialEq)]
pub struct Cloud {
    points: Vec<Point3<f64>>,
}

/// Largest cloud the tool accepts (memory and run-time guard).
pub const MAX_CLOUD_POINTS: usize = 10_000_000;
/// Largest coordinate magnitude accepted (squared distances of such clouds stay far from
/// overflow).
pub const MAX_COORDINATE: f64 = 1e12;
/// A point may lie at most this many times the median distance of the points from the
/// median point away from it.
pub const MAX_SPREAD_RATIO: f64 = 1e6;

impl Cloud {
    /// Validate `points` (named `name` in errors): non-empty, at most [`MAX_CLOUD_POINTS`], finite,
    /// within [`MAX_COORDINATE`], no point beyond [`MAX_SPREAD_RATIO`] times the median
    /// distance from the median point, not all coincident.
    pub fn new(name: &str, points: Vec<Point3<f64>>) -> Result<Self, CloudError> {
        if points.is_empty() {
            return Err(CloudError::Empty(name.to_string()));
        }
        if points.len() > MAX_CLOUD_POINTS {
            return Err(CloudError::TooLarge { name: name.into(), count: points.len(), limit: MAX_CLOUD_POINTS });
        }
        for (index, p) in points.iter().enumerate() {
            for &value in p.coords.iter() {
                if !value.is_finite() {
                    return Err(CloudError::NonFinite { name: name.into(), index, value });
                }
            }
        }
        for (index, p) in points.iter().enumerate() {
            if let Some(&value) = p.coords.iter().find(|v| v.abs() > MAX_COORDINATE) {
                return Err(CloudError::OutOfRange { name: name.into(), index, value, limit: MAX_COORDINATE });
            }
        }
        if let Some((index, distance, spread)) = farthest_beyond(&points, MAX_SPREAD_RATIO) {
            return Err(CloudError::FarPoint { name: name.into(), index, distance, spread, limit: MAX_SPREAD_RATIO });
        }
        let c = Cloud { points };
        if c.diagonal() == 0.0 && c.len() > 1 {
            return Err(CloudError::Degenerate(name.to_string()));
        }
        Ok(c)
    }

    /// The points.
    pub fn points(&self) -> &[Point3<f64>] {
        &self.points
    }

    /// Take the points out.
    pub fn into_points(self) -> Vec<Point3<f64>> {
        self.points
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Always false for a validated cloud (kept for API symmetry).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Mean of the points.
    pub fn centroid(&self) -> Point3<f64> {
        centroid(&self.points)
    }

    /// Length of the axis-aligned bounding box's diagonal.
    pub fn diagonal(&self) -> f64 {
        bbox_diagonal(&self.points)
    }
}

/// The first point farther from the per-axis median point than `ratio` times the median
/// of those distances: `(index, distance, median distance)` (`None` when the median
/// distance is 0, i.e. most points coincide).
fn farthest_beyond(points: &[Point3<f64>], ratio: f64) -> Option<(usize, f64, f64)> {
    let median = |mut v: Vec<f64>| {
        let mid = v.len() / 2;
        *v.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    let m = Point3::new(
        median(points.iter().map(|p| p.x).collect()),
        median(points.iter().map(|p| p.y).collect()),
        median(points.iter().map(|p| p.z).collect()),
    );
    let d: Vec<f64> = points.iter().map(|p| (p - m).norm()).collect();
    let spread = median(d.clone());
    if spread.is_nan() || spread <= 0.0 {
        return None;
    }
    d.iter().position(|&x| x > ratio * spread).map(|i| (i, d[i], spread))
}

/// RMS distance of a non-empty slice of points from their centroid.
pub fn rms_radius(points: &[Point3<f64>]) -> f64 {
    let c = centroid(points);
    (points.iter().map(|p| (p - c).norm_squared()).sum::<f64>() / points.len() as f64).sqrt()
}

/// Mean of a non-empty slice of points.
pub fn centroid(points: &[Point3<f64>]) -> Point3<f64> {
    let sum: Vector3<f64> = points.iter().map(|p| p.coords).sum();
    Point3::from(sum / points.len() as f64)
}

/// Axis-aligned bounding box (lowest and highest corner) of a non-empty slice of points.
pub fn bbox(points: &[Point3<f64>]) -> (Point3<f64>, Point3<f64>) {
    let first = points.first().map_or(Vector3::zeros(), |p| p.coords);
    let (lo, hi) = points.iter().fold((first, first), |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)));
    (Point3::from(lo), Point3::from(hi))
}

/// Axis-aligned bounding-box diagonal of a slice of points (0 if empty).
pub fn bbox_diagonal(points: &[Point3<f64>]) -> f64 {
    let (lo, hi) = bbox(points);
    (hi - lo).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_clouds() {
        assert_eq!(Cloud::new("scan", vec![]), Err(CloudError::Empty("scan".into())));
        let e = Cloud::new("model", vec![Point3::new(0.0, f64::NAN, 0.0)]).unwrap_err();
        assert!(e.to_string().contains("non-finite"), "{e}");
        let e = Cloud::new("m", vec![Point3::new(1.0, 1.0, 1.0); 3]).unwrap_err();
        assert_eq!(e, CloudError::Degenerate("m".into()));
        let c = Cloud::new("m", vec![Point3::origin(), Point3::new(3.0, 4.0, 0.0)]).unwrap();
        assert_eq!(c.diagonal(), 5.0);
        assert_eq!(c.centroid(), Point3::new(1.5, 2.0, 0.0));
    }
}
