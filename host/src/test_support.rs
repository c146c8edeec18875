//! Fixtures shared by the unit tests of the registration modules.

use crate::geometry::Pose;
use crate::registration::icp::Registration;
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

/// The rotation between two poses, in degrees.
pub(crate) fn rot_deg(p: &Pose, t: &Pose) -> f64 {
    p.rotation_angle_to(t).to_degrees()
}

/// The relative scale error of `p` against `t`.
pub(crate) fn scale_err(p: &Pose, t: &Pose) -> f64 {
    (p.scale / t.scale - 1.0).abs()
}

/// `run` twice gives the same pose, iterations and errors (to the bit).
pub(crate) fn assert_deterministic(run: impl Fn() -> Registration) {
    let (a, b) = (run(), run());
    assert_eq!(a.pose, b.pose);
    assert_eq!(a.iterations, b.iterations);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a.errors), bits(&b.errors));
}

/// `run` (a registration of a scan from the identity) on an empty scan takes no iteration,
/// and on a one-point scan returns a finite MSD: no panic either way. Returns the one-point
/// result for the method's own checks.
pub(crate) fn assert_degenerate_scans(run: impl Fn(&[Point3<f64>]) -> Registration) -> Registration {
    assert_eq!(run(&[]).iterations, 0);
    let r = run(&[Point3::new(0.1, 0.2, 0.3)]);
    assert!(r.msd.is_finite());
    r
}
