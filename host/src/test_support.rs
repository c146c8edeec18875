//! Fixtures shared by the unit tests of the registration modules.

use nalgebra::Point3;

/// A smooth, asymmetric 3-D spiral of `n` points: easy to register from a near start.
pub(crate) fn spiral(n: usize) -> Vec<Point3<f64>> {
    (0..n)
        .map(|i| {
            let t = i as f64 / n as f64 * 6.0;
            Point3::new(t.cos() * (1.0 + 0.2 * t), (1.7 * t).sin(), 0.3 * t)
        })
        .collect()
}
