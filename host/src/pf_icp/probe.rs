//! The basin probe: how precisely the polish can pin the answer down on this scan.
//!
//! The curvature's covariance ([`crate::pf_icp::conclusion`], step 3) describes a smooth
//! bowl about the answer. A folded or bumpy surface seen in a small window (a brain's
//! gyri, 13% of it visible) has shallow local minima a few degrees apart whose costs the
//! noise cannot tell apart: the polish stops in one of them, and the curvature there is
//! as sharp as anywhere, so the covariance says a fraction of a degree on an answer
//! several degrees off. The probe restarts the polish from [`PROBES`] poses about the
//! answer (each rotated by [`PROBE_DEG`] about one of the cube's diagonals, moved by
//! [`PROBE_DIAG`] of the diagonal along it, the scale, where free, changed by
//! [`PROBE_SCALE`]), and keeps those that end fitting the scan as well as the answer
//! within the noise (the conclusion's paired test): the spread of where they end is
//! uncertainty the data leaves, and it is added to the covariance. On a smooth bowl every
//! probe returns to the answer and adds nothing.

use crate::geometry::{Pose, ScaleBounds};
use crate::pf_icp::evidence::Evidence;
use crate::pf_icp::surface::Surface;
use nalgebra::{Matrix3, Point3, Rotation3, Unit, Vector3};
use rayon::prelude::*;

/// Restarts about the answer.
pub const PROBES: usize = 4;
/// Each restart's rotation from the answer [deg].
pub const PROBE_DEG: f64 = 3.0;
/// Each restart's move of the scan centroid's image, as a fraction of the model's diagonal.
pub const PROBE_DIAG: f64 = 0.01;
/// Each restart's relative change of a free scale.
pub const PROBE_SCALE: f64 = 0.02;
/// Most polish iterations of a restart (a restart 3 deg off settles in its basin in a
/// few; the polish's step then flips between sets of contacts).
pub const PROBE_ITERATIONS: usize = 20;

/// `pose` rotated by `rotation` (a rotation vector, model frame) about the image of `at`,
/// that image moved by `offset` and the scale multiplied by `factor`.
pub fn perturbed(pose: &Pose, at: &Point3<f64>, rotation: &Vector3<f64>, offset: &Vector3<f64>, factor: f64) -> Pose {
    let image = pose.apply(at);
    let r: Matrix3<f64> = Rotation3::new(*rotation).into_inner() * pose.rotation;
    let s = pose.scale * factor;
    Pose { scale: s, rotation: r, translation: image.coords + offset - s * (r * at.coords) }
}

/// The restarts' starting poses about `pose` (the scale kept within `bounds`).
pub fn starts(pose: &Pose, at: &Point3<f64>, diag: f64, bounds: &ScaleBounds) -> Vec<Pose> {
    let diagonals = [
        Vector3::new(1.0, 1.0, 1.0),
        Vector3::new(1.0, 1.0, -1.0),
        Vector3::new(1.0, -1.0, 1.0),
        Vector3::new(-1.0, 1.0, 1.0),
    ];
    (0..PROBES)
        .map(|i| {
            let u = Unit::new_normalize(diagonals[i % 4]).into_inner() * if i < 4 { 1.0 } else { -1.0 };
            let factor = if i % 2 == 0 { 1.0 + PROBE_SCALE } else { 1.0 / (1.0 + PROBE_SCALE) };
            bounds.apply(&perturbed(pose, at, &(u * PROBE_DEG.to_radians()), &(u * PROBE_DIAG * diag), factor), at)
        })
        .collect()
}

/// The probe's result.
#[derive(Clone, Debug)]
pub struct Probe {
    /// Second moment of the kept restarts' local errors against the answer
    /// ([`Pose::local_error`]; model units, scale, rad).
    pub spread: nalgebra::SMatrix<f64, 7, 7>,
    /// Restarts that ended fitting as well as the answer.
    pub kept: usize,
}

/// Restart the polish about `pose` on `points` and measure where the restarts that fit as
/// well as `pose` end (`costs`: `pose`'s tight costs on `points`; `fits_as_well` the
/// conclusion's paired test).
#[allow(clippy::too_many_arguments)]
pub fn probe(
    surface: &Surface,
    evidence: &Evidence,
    points: &[Point3<f64>],
    pose: &Pose,
    costs: &[f64],
    iterations: usize,
    bounds: &ScaleBounds,
    at: &Point3<f64>,
    diag: f64,
    fits_as_well: impl Fn(&[f64], &[f64]) -> bool + Sync,
) -> Probe {
    let ends: Vec<Option<[f64; 7]>> = starts(pose, at, diag, bounds)
        .par_iter()
        .map(|p| {
            let q = surface.polish(points, p, iterations.min(PROBE_ITERATIONS), bounds);
            let c = evidence.tight_costs(surface, points, &q);
            fits_as_well(costs, &c).then(|| q.local_error(pose, at))
        })
        .collect();
    let mut spread = nalgebra::SMatrix::<f64, 7, 7>::zeros();
    let mut kept = 0;
    for e in ends.iter().flatten() {
        let v = nalgebra::SVector::<f64, 7>::from_column_slice(e);
        spread += v * v.transpose();
        kept += 1;
    }
    if kept > 0 {
        spread /= kept as f64;
    }
    Probe { spread, kept }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_restart_is_the_rotation_the_move_and_the_scale_it_was_given() {
        let pose = Pose::from_params(&[0.1, -0.05, 0.2, 1.1, 0.4, -0.3, 0.7]);
        let at = Point3::new(0.3, -0.2, 0.1);
        let r = Vector3::new(0.0, 0.02, 0.0);
        let t = Vector3::new(0.01, 0.0, -0.02);
        let q = perturbed(&pose, &at, &r, &t, 1.02);
        let e = q.local_error(&pose, &at);
        for (k, want) in [t.x, t.y, t.z, pose.scale * 0.02, r.x, r.y, r.z].iter().enumerate() {
            assert!((e[k] - want).abs() < 1e-12, "{k}: {} against {want}", e[k]);
        }
        // A fixed scale stays fixed.
        let fixed = ScaleBounds::fixed(pose.scale);
        assert!(starts(&pose, &at, 1.0, &fixed).iter().all(|p| p.scale == pose.scale));
        assert_eq!(starts(&pose, &at, 1.0, &ScaleBounds::FREE).len(), PROBES);
    }
}
