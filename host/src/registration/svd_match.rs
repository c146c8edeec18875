//! SVD similarity matching (Algorithm 2): the rotation, scale and translation
//! that best map paired scan points `m_i` onto model points `d_i`.
//!
//! Rotation: `C = sum w m_c d_c^T = U S V^T`, `R = V diag(1, 1, det(V U^T)) U^T`
//! (the sign fix keeps `R` a rotation, never a reflection).
//!
//! Scale, two rules (see docs/algorithm.md, "Scale (Algorithm 2)"):
//! - [`ScaleRule::LeastSquares`]: `s = sum w d_c . R m_c / sum w |m_c|^2`, the exact
//!   minimiser of Eq. 3 for the given pairs (Umeyama). Used inside ICP and its variants.
//! - [`ScaleRule::Ratio`]: `s = sqrt(sum w |d_c|^2 / sum w |m_c|^2)`, the paper's
//!   approximation (written there with the ratio the other way up, which is `1/s` in the
//!   `d = s R m + T` direction). It does not shrink when the pairing is poor, so it is
//!   used for the start from cluster centroids.

use crate::geometry::Pose;
use nalgebra::{Matrix3, Point3, Vector3};

/// How the scale of a similarity is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScaleRule {
    /// Exact least squares for the given pairs.
    LeastSquares,
    /// Ratio of RMS radii about the centroids (the paper's formula).
    Ratio,
    /// Keep `s = 1` (rigid).
    Fixed,
}

/// Similarity `d ≈ s R m + T` from pairs, optionally weighted. Returns `None` when the
/// pairs are degenerate (fewer than 3 effective points, zero weight or zero spread).
// `!(x > 0.0)` on purpose: it is also true for NaN.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn match_pairs(
    scan: &[Point3<f64>],
    model: &[Point3<f64>],
    weights: Option<&[f64]>,
    rule: ScaleRule,
) -> Option<Pose> {
    assert_eq!(scan.len(), model.len(), "match_pairs needs pairs");
    let w = |i: usize| weights.map_or(1.0, |w| w[i]);
    let mut wsum = 0.0;
    let mut mu_m = Vector3::zeros();
    let mut mu_d = Vector3::zeros();
    for i in 0..scan.len() {
        let wi = w(i);
        wsum += wi;
        mu_m += wi * scan[i].coords;
        mu_d += wi * model[i].coords;
    }
    if !(wsum > 0.0) || scan.len() < 3 {
        return None;
    }
    mu_m /= wsum;
    mu_d /= wsum;
    let mut c = Matrix3::zeros();
    let mut mm = 0.0;
    let mut dd = 0.0;
    for i in 0..scan.len() {
        let wi = w(i);
        let mc = scan[i].coords - mu_m;
        let dc = model[i].coords - mu_d;
        c += wi * mc * dc.transpose();
        mm += wi * mc.norm_squared();
        dd += wi * dc.norm_squared();
    }
    if !(mm > 0.0) || !(dd > 0.0) {
        return None;
    }
    let svd = c.svd(true, true);
    let u = svd.u?;
    let v = svd.v_t?.transpose();
    let mut fix = Matrix3::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        fix[(2, 2)] = -1.0;
    }
    let r = v * fix * u.transpose();
    let s = match rule {
        ScaleRule::LeastSquares => {
            let mut num = 0.0;
            for i in 0..scan.len() {
                let mc = scan[i].coords - mu_m;
                let dc = model[i].coords - mu_d;
                num += w(i) * dc.dot(&(r * mc));
            }
            num / mm
        }
        ScaleRule::Ratio => (dd / mm).sqrt(),
        ScaleRule::Fixed => 1.0,
    };
    if !(s > 0.0) || !s.is_finite() {
        return None;
    }
    Some(Pose { scale: s, rotation: r, translation: mu_d - s * (r * mu_m) })
}

/// [`match_pairs`] with the scale kept within `bounds` (the least-squares similarity under
/// the bound: the rotation is unchanged, the scale clamped, the translation taken through
/// the weighted centroids). Free bounds give exactly [`match_pairs`]' pose.
pub fn match_pairs_within(
    scan: &[Point3<f64>],
    model: &[Point3<f64>],
    weights: Option<&[f64]>,
    rule: ScaleRule,
    bounds: &crate::geometry::ScaleBounds,
) -> Option<Pose> {
    let pose = match_pairs(scan, model, weights, rule)?;
    if bounds.contains(pose.scale) {
        return Some(pose);
    }
    let w = |i: usize| weights.map_or(1.0, |w| w[i]);
    let wsum: f64 = (0..scan.len()).map(w).sum();
    let mu = (0..scan.len()).fold(Vector3::zeros(), |a, i| a + w(i) * scan[i].coords) / wsum;
    Some(bounds.apply(&pose, &Point3::from(mu)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<Point3<f64>> {
        (0..40)
            .map(|i| {
                let t = i as f64 * 0.37;
                Point3::new(t.cos() * 2.0, (1.3 * t).sin(), 0.1 * t * t - 1.0)
            })
            .collect()
    }

    #[test]
    fn recovers_similarity_both_rules() {
        let truth = Pose::from_params(&[0.5, -1.2, 2.0, 0.7143, -0.51, -0.32, -0.51]);
        let m = sample();
        let d = truth.apply_all(&m);
        for rule in [ScaleRule::LeastSquares, ScaleRule::Ratio] {
            let p = match_pairs(&m, &d, None, rule).unwrap();
            assert!((p.matrix4() - truth.matrix4()).norm() < 1e-10, "{rule:?}");
        }
    }

    #[test]
    fn never_returns_a_reflection() {
        let m = sample();
        let d: Vec<_> = m.iter().map(|p| Point3::new(-p.x, p.y, p.z)).collect();
        let p = match_pairs(&m, &d, None, ScaleRule::LeastSquares).unwrap();
        assert!((p.rotation.determinant() - 1.0).abs() < 1e-10);
    }

    #[test]
    fn weights_ignore_outliers() {
        let truth = Pose::from_params(&[1.0, 0.0, 0.0, 1.2, 0.1, 0.2, 0.3]);
        let m = sample();
        let mut d = truth.apply_all(&m);
        d[3] = Point3::new(50.0, 50.0, 50.0);
        let mut w = vec![1.0; m.len()];
        w[3] = 0.0;
        let p = match_pairs(&m, &d, Some(&w), ScaleRule::LeastSquares).unwrap();
        assert!((p.matrix4() - truth.matrix4()).norm() < 1e-10);
    }

    #[test]
    fn degenerate_is_none() {
        let m = vec![Point3::origin(); 5];
        assert!(match_pairs(&m, &m, None, ScaleRule::LeastSquares).is_none());
    }
}
