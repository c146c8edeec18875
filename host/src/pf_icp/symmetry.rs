//! The model's near-symmetries: rotations about its centroid that map most of its surface
//! onto itself ([`near_symmetries`]). A near-symmetric part seen from the side that does
//! not show its breaking feature fits its answer composed with such a rotation as well as
//! the answer itself; the conclusion polishes those poses too, so that the ambiguity is
//! reported with the other poses among the alternatives whether or not the search's
//! hypotheses happened to hold them.
//!
//! Candidates: turns by multiples of [`STEP_DEG`] about each principal axis through the
//! centroid, and each of those followed by a half turn about another principal axis (the
//! flips of a box, of a nut about any of its cross axes). A candidate counts when at least
//! [`MIN_MATCHED`] of the model's points land within [`MATCH_SPACINGS`] spacings of its
//! surface; at most [`MAX_SYMMETRIES`], best matched first, [`DISTINCT_DEG`] apart.

use crate::cloud::centroid;
use crate::geometry::Pose;
use crate::pf_icp::surface::Surface;
use nalgebra::{Matrix3, Point3, Rotation3, Unit};
use rayon::prelude::*;

/// Step of the candidate turns [deg].
pub const STEP_DEG: f64 = 15.0;
/// Least share of the model's points a near-symmetry maps onto its surface.
pub const MIN_MATCHED: f64 = 0.85;
/// A point is matched within this many model spacings of the surface.
pub const MATCH_SPACINGS: f64 = 2.0;
/// Most near-symmetries kept (a cube's group has 23 besides the identity).
pub const MAX_SYMMETRIES: usize = 23;
/// Least angle between two kept near-symmetries [deg].
pub const DISTINCT_DEG: f64 = 10.0;
/// Model points each candidate is tested on.
const TEST_POINTS: usize = 600;

/// The near-symmetries of the model behind `surface`, as poses of the model frame onto
/// itself (rotations about the centroid), best matched first; never the identity.
pub fn near_symmetries(surface: &Surface) -> Vec<Pose> {
    let model = surface.nn().points();
    if model.len() < 10 {
        return Vec::new();
    }
    let c = centroid(model);
    let axes = principal_axes(model, &c);
    let steps = (360.0 / STEP_DEG).round() as usize;
    let turns: Vec<Matrix3<f64>> =
        axes.iter().flat_map(|a| (1..steps).map(move |k| rotation(a, k as f64 * STEP_DEG))).collect();
    let mut candidates: Vec<Matrix3<f64>> = turns.clone();
    for (j, b) in axes.iter().enumerate() {
        let flip = rotation(b, 180.0);
        for (i, a) in axes.iter().enumerate() {
            if i != j {
                candidates.extend((0..steps).map(|k| flip * rotation(a, k as f64 * STEP_DEG)));
            }
        }
    }
    let step = (model.len() / TEST_POINTS).max(1);
    let tested: Vec<Point3<f64>> = model.iter().step_by(step).copied().collect();
    let tolerance2 = (MATCH_SPACINGS * surface.spacing()).powi(2);
    let mut scored: Vec<(f64, Pose)> = candidates
        .par_iter()
        .map(|g| {
            let pose = Pose { scale: 1.0, rotation: *g, translation: c.coords - g * c.coords };
            let matched = tested.iter().filter(|p| surface.distance2(&pose.apply(p)) <= tolerance2).count();
            (matched as f64 / tested.len() as f64, pose)
        })
        .filter(|(m, p)| *m >= MIN_MATCHED && p.rotation_angle_to(&Pose::identity()).to_degrees() > DISTINCT_DEG)
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut kept: Vec<Pose> = Vec::new();
    for (_, p) in scored {
        if kept.len() >= MAX_SYMMETRIES {
            break;
        }
        if kept.iter().all(|k| k.rotation_angle_to(&p).to_degrees() > DISTINCT_DEG) {
            kept.push(p);
        }
    }
    kept
}

fn rotation(axis: &nalgebra::Vector3<f64>, deg: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Unit::new_normalize(*axis), deg.to_radians()).into_inner()
}

/// The principal axes of `points` about `c`.
fn principal_axes(points: &[Point3<f64>], c: &Point3<f64>) -> [nalgebra::Vector3<f64>; 3] {
    let cov = points.iter().fold(Matrix3::zeros(), |a, p| a + (p - c) * (p - c).transpose());
    let e = cov.symmetric_eigen();
    std::array::from_fn(|k| e.eigenvectors.column(k).into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nn::NearestNeighbours;
    use crate::parts::Part;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// A block (D2) has its three half turns; a bunny-like asymmetric shape (a block with
    /// a boss and a notch would still be near-symmetric) has none.
    #[test]
    fn a_block_has_its_half_turns_and_an_asymmetric_cloud_none() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let model = Part::Block.sample_surface(3000, &mut rng);
        let nn = NearestNeighbours::new(&model);
        let s = near_symmetries(&Surface::new(&nn));
        assert!(s.len() >= 3, "{}", s.len());
        for g in Part::Block.symmetries().iter().skip(1) {
            let want = Pose { scale: 1.0, rotation: *g, translation: nalgebra::Vector3::zeros() };
            let nearest = s.iter().map(|p| p.rotation_angle_to(&want).to_degrees()).fold(f64::INFINITY, f64::min);
            assert!(nearest < 8.0, "missing {g}: nearest {nearest} deg");
        }
        let bunny = crate::real_shapes::all().iter().find(|r| r.name == "bunny").unwrap();
        let pts: Vec<Point3<f64>> = bunny.points().iter().step_by(7).copied().collect();
        let nn = NearestNeighbours::new(&pts);
        assert!(near_symmetries(&Surface::new(&nn)).is_empty());
    }
}
