//! The one quantise stage between the host's f64 clouds and the board's fixed-point formats
//! (`pficp_fpga::common::format`, docs/fixed-point.md): the normalisation, the Q formats of points,
//! poses, normals and the filter's parameters, the model points that go to the board
//! ([`board_model`]), their grid ([`board_grid`]) and stored normals ([`stored_normals`]), and
//! the scan's Morton order ([`morton_sorted`]).
//!
//! Each cloud is normalised by its own similarity: `x_n = (x - c) / r`, with `c` the
//! centroid and `r` the largest distance from it, so every normalised point lies in the
//! unit ball (Q3.13 holds [-4, 4)). A pose `d = s R m + T` between the original clouds
//! becomes `d_n = (s r_m / r_d) R m_n + (s R c_m + T - c_d) / r_d` between the normalised
//! ones, and squared distances scale by `1 / r_d^2`.

use super::BoardError;
use crate::geometry::Pose;
use crate::nn::NearestNeighbours;
use nalgebra::{Point3, Vector3};
use pficp_fpga::common::format::{self, coord_to_f64, FxPoint, FxPose};
use pficp_fpga::filter::pf::{wrap24, PARAM_BITS, SIGMA_BITS};
use pficp_fpga::search::grid::{cell_of, Grid, CELLS_PER_AXIS, GRID_BITS};
use pficp_fpga::surface::FxNormal;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The similarity that normalises one cloud: `x_n = (x - centre) / radius`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normalisation {
    /// Centroid of the cloud.
    pub centre: Point3<f64>,
    /// Largest distance of a point from the centroid (> 0).
    pub radius: f64,
}

impl Normalisation {
    /// The normalisation of `points` (non-empty; a single point gets radius 1).
    pub fn of(points: &[Point3<f64>]) -> Self {
        let centre = crate::cloud::centroid(points);
        let radius = points.iter().map(|p| (p - centre).norm()).fold(0.0, f64::max);
        Normalisation { centre, radius: if radius > 0.0 { radius } else { 1.0 } }
    }

    /// Normalise and quantise a cloud to Q3.13.
    pub fn quantise(&self, points: &[Point3<f64>]) -> Vec<FxPoint> {
        points.iter().map(|p| format::point(((p - self.centre) / self.radius).into())).collect()
    }

    /// A quantised point back in the original frame.
    pub fn restore(&self, p: FxPoint) -> Point3<f64> {
        self.centre
            + Vector3::new(format::coord_to_f64(p[0]), format::coord_to_f64(p[1]), format::coord_to_f64(p[2]))
                * self.radius
    }
}

/// A unit normal in the board's format ([`pficp_fpga::surface::FxNormal`]): each component
/// times `2^NORMAL_FRAC`, rounded, clamped to `+-2^NORMAL_FRAC` (a non-finite component gives 0).
pub fn quantise_normal(n: &Vector3<f64>) -> pficp_fpga::surface::FxNormal {
    let one = (1u32 << pficp_fpga::surface::NORMAL_FRAC) as f64;
    n.map(|v| if v.is_finite() { (v * one).round().clamp(-one, one) as i16 } else { 0 }).into()
}

/// The pose between normalised clouds for a pose between the original ones.
pub fn normalised_pose(pose: &Pose, scan: &Normalisation, model: &Normalisation) -> Pose {
    Pose {
        scale: pose.scale * scan.radius / model.radius,
        rotation: pose.rotation,
        translation: (pose.scale * (pose.rotation * scan.centre.coords) + pose.translation - model.centre.coords)
            / model.radius,
    }
}

/// The pose between the original clouds for a pose between the normalised ones.
pub fn original_pose(pose_n: &Pose, scan: &Normalisation, model: &Normalisation) -> Pose {
    let scale = pose_n.scale * model.radius / scan.radius;
    Pose {
        scale,
        rotation: pose_n.rotation,
        translation: model.radius * pose_n.translation + model.centre.coords
            - scale * (pose_n.rotation * scan.centre.coords),
    }
}

/// Quantise a normalised pose: `M = s R` in Q3.15, `T` in Q5.13.
pub fn quantise_pose(pose_n: &Pose) -> FxPose {
    let m = pose_n.scale * pose_n.rotation;
    let rows = [m[(0, 0)], m[(0, 1)], m[(0, 2)], m[(1, 0)], m[(1, 1)], m[(1, 2)], m[(2, 0)], m[(2, 1)], m[(2, 2)]];
    let t = pose_n.translation;
    FxPose::from_f64(&rows, &[t.x, t.y, t.z])
}

/// The normalised pose of a board pose ([`quantise_pose`]'s inverse up to its rounding):
/// `M = s R` with `s = det(M)^(1/3)` and `R` the rotation nearest `M / s`, `T` as it is.
/// A matrix with `det(M) <= 0` (no similarity) gives `None`.
pub fn restore_pose(p: &FxPose) -> Option<Pose> {
    let m = nalgebra::Matrix3::from_row_slice(&p.m.map(|v| v as f64 / (1u64 << format::MATRIX_FRAC) as f64));
    let det = m.determinant();
    if !(det > 0.0 && det.is_finite()) {
        return None;
    }
    let scale = det.cbrt();
    let rotation = nalgebra::Rotation3::from_matrix(&(m / scale)).into_inner();
    let t = p.t.map(|v| v as f64 / (1u64 << format::POSE_TRANSLATION_FRAC) as f64);
    Some(Pose { scale, rotation, translation: nalgebra::Vector3::new(t[0], t[1], t[2]) })
}

/// Bound on the error of one transformed, quantised point against the exact transform of
/// the exact normalised point, per coordinate (normalised units), for a pose of scale
/// `s` (normalised) and points in the unit ball: the scan point's quantisation through
/// `M` (`s * 3 * 2^-14`), `M`'s (`3 * 2^-16`), `T`'s (`2^-14`) and the output rounding
/// (`2^-14`), plus the model point's quantisation (`2^-14`).
pub fn coordinate_error_bound(s: f64) -> f64 {
    let half = |frac: u32| 0.5 / (1u64 << frac) as f64;
    s * 3.0 * half(format::COORD_FRAC)
        + 3.0 * half(format::MATRIX_FRAC)
        + half(format::POSE_TRANSLATION_FRAC)
        + half(format::COORD_FRAC)
        + half(format::COORD_FRAC)
}

/// Bound on `|cost_fixed - cost_exact|` (normalised units squared) for scan points whose
/// exact nearest distances are `distances`: each point's squared distance moves by at
/// most `2 d e + e^2` with `e = sqrt(3) * coordinate_error_bound(s)` (the minimum over
/// the model moves no more than the largest move of its candidates).
pub fn cost_error_bound(distances: &[f64], s: f64) -> f64 {
    let e = 3f64.sqrt() * coordinate_error_bound(s);
    distances.iter().map(|d| 2.0 * d * e + e * e).sum()
}

// The filter's parameters.

/// `x * 2^frac` rounded and saturated to a 24-bit signed parameter.
pub fn param24(x: f64, frac: u32) -> i32 {
    let v = (x * (1u64 << frac) as f64).round();
    v.clamp(-(1i64 << 23) as f64, ((1i64 << 23) - 1) as f64) as i32
}

/// An angle in radians as a binary angle (2^24 a turn, wrapped).
pub fn binary_angle(rad: f64) -> i32 {
    let turns = crate::geometry::wrap_angle(rad) / std::f64::consts::TAU;
    wrap24((turns * (1u64 << PARAM_BITS) as f64).round() as i64)
}

/// A sigma in parameter LSBs: rounded, at least 1, at most `2^22 - 1`.
pub fn sigma22(x: f64) -> u32 {
    let v = x.round();
    if v.is_nan() {
        return 1;
    }
    v.clamp(1.0, ((1u64 << SIGMA_BITS) - 1) as f64) as u32
}

// The model on the board: its points, grid and normals; the scan's order.

/// The model points that go to the board: all of them when they fit, else `max` of them
/// drawn without replacement with the seed, in their original order.
pub fn board_model(model: &[Point3<f64>], max: usize, seed: u64) -> Vec<Point3<f64>> {
    if model.len() <= max {
        return model.to_vec();
    }
    // A stream of its own, so the draw does not shift any other random choice.
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x626f_6172_645f_6d64);
    let mut picks = rand::seq::index::sample(&mut rng, model.len(), max).into_vec();
    picks.sort_unstable();
    picks.into_iter().map(|i| model[i]).collect()
}

/// The board's gridded model (protocol 3: the model store sorted by cell and the cell
/// table, `pficp_fpga::search::grid`) of the normalised, quantised model points. A model the grid
/// refuses (a point outside the cube `[-1, 1]^3`, more points than the board stores) is a
/// one-line [`BoardError::Limit`]; the host's normalisation puts every model point in the
/// unit ball, so it does not happen to a model planned by the host.
pub fn board_grid(model: &[FxPoint]) -> Result<Grid, BoardError> {
    Grid::build(model).map_err(|e| BoardError::Limit(format!("the board's grid refuses the model: {e}")))
}

/// The Morton key (Z order: the cell's bits interleaved, `x` lowest) of a point's grid
/// cell, each axis clipped to the grid.
pub fn morton_key(p: FxPoint) -> u32 {
    let k = cell_of(p).map(|c| c.clamp(0, CELLS_PER_AXIS as i32 - 1) as u32);
    (0..GRID_BITS).map(|b| ((k[0] >> b & 1) | (k[1] >> b & 1) << 1 | (k[2] >> b & 1) << 2) << (3 * b)).sum()
}

/// The scan sample sorted by the [`morton_key`] of each point's cell in the normalised scan
/// frame, ties in the given order (a stable sort). The first protocol-3 board's grid
/// pipeline swept the rows around batches of points and needed close points consecutive
/// (2.3 to 3.2 times fewer clocks); the neighbour pipeline that replaced it searches each
/// point's own rows, and the order changes its clocks by about 2% (docs/board-modes.md,
/// "The scan sample's order"). The
/// costs are sums over the sample, so the order changes no result.
pub fn morton_sorted(scan: &[FxPoint]) -> Vec<FxPoint> {
    let mut s = scan.to_vec();
    s.sort_by_key(|&p| morton_key(p));
    s
}

/// The normals of the stored model points (the grid's order), in the board's format: each
/// point's principal axis of least spread over itself and its 8 nearest stored neighbours,
/// as the host's surface computes them (`pf_icp::surface`), from the quantised points the
/// board stores, so they depend on nothing but the store.
pub fn stored_normals(grid: &Grid) -> Vec<FxNormal> {
    let pts: Vec<Point3<f64>> =
        grid.points.iter().map(|p| Point3::new(coord_to_f64(p[0]), coord_to_f64(p[1]), coord_to_f64(p[2]))).collect();
    let nn = NearestNeighbours::new(&pts);
    pts.iter()
        .map(|p| {
            let near: Vec<Point3<f64>> = nn.nearest_k(p, 9).iter().map(|c| pts[c.index]).collect();
            quantise_normal(&crate::pf_icp::surface::least_axis(&near))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_round_trips_through_normalisation() {
        let scan = Normalisation { centre: Point3::new(1.0, -2.0, 0.5), radius: 3.0 };
        let model = Normalisation { centre: Point3::new(-0.3, 0.2, 4.0), radius: 5.0 };
        let pose = Pose::from_params(&[0.4, -1.0, 2.0, 0.8, 0.1, -0.3, 0.6]);
        let n = normalised_pose(&pose, &scan, &model);
        let back = original_pose(&n, &scan, &model);
        assert!((back.matrix4() - pose.matrix4()).norm() < 1e-12);
        // Normalised scan point maps to the normalised model point.
        let m = Point3::new(0.7, 0.1, -1.2);
        let d = pose.apply(&m);
        let m_n = Point3::from((m - scan.centre) / scan.radius);
        let d_n = Point3::from((d - model.centre) / model.radius);
        assert!((n.apply(&m_n) - d_n).norm() < 1e-12);
    }

    #[test]
    fn a_board_pose_restores_to_its_similarity() {
        let pose = Pose::from_params(&[0.4, -1.0, 2.0, 0.8, 0.1, -0.3, 0.6]);
        let back = restore_pose(&quantise_pose(&pose)).expect("a similarity");
        assert!((back.scale - 0.8).abs() < 1e-4, "{}", back.scale);
        assert!((back.rotation - pose.rotation).norm() < 1e-4);
        assert!((back.translation - pose.translation).norm() < 1e-4);
        assert!((back.rotation.determinant() - 1.0).abs() < 1e-12);
        // A reflection or a zero matrix is no similarity.
        let mut bad = quantise_pose(&pose);
        bad.m = [0; 9];
        assert!(restore_pose(&bad).is_none());
        bad.m = [-32768, 0, 0, 0, 32768, 0, 0, 0, 32768];
        assert!(restore_pose(&bad).is_none());
    }

    #[test]
    fn normals_quantise_to_the_board_format() {
        assert_eq!(quantise_normal(&Vector3::new(0.6, -0.8, 0.0)), [9830, -13107, 0]);
        assert_eq!(quantise_normal(&Vector3::new(1.5, -2.0, f64::NAN)), [16384, -16384, 0]);
    }

    #[test]
    fn normalised_cloud_fits_the_unit_ball() {
        let pts: Vec<_> = (0..50).map(|i| Point3::new(i as f64, (i * i) as f64 * 0.1, -3.0)).collect();
        let n = Normalisation::of(&pts);
        for q in n.quantise(&pts) {
            let r = q.iter().map(|&c| format::coord_to_f64(c).powi(2)).sum::<f64>().sqrt();
            assert!(r <= 1.0 + 1e-3);
        }
        let p = n.restore(n.quantise(&pts)[7]);
        assert!((p - pts[7]).norm() <= n.radius * 2e-4);
    }

    #[test]
    fn stored_normals_of_a_tilted_patch_are_its_normal() {
        // A patch of the plane z = 0.5 x, in the board's format; its unit normal is
        // (-0.5, 0, 1) / |.|, either sign.
        let mut model = Vec::new();
        for i in -12..12 {
            for j in -12..12 {
                let (x, y) = (i as f64 * 0.03, j as f64 * 0.027);
                model.push(pficp_fpga::common::format::point([x, y, 0.5 * x]));
            }
        }
        let grid = Grid::build(&model).unwrap();
        let normals = stored_normals(&grid);
        assert_eq!(normals.len(), grid.points.len());
        let want = nalgebra::Vector3::new(-0.5, 0.0, 1.0).normalize() * 16384.0;
        for n in normals {
            let n = nalgebra::Vector3::new(n[0] as f64, n[1] as f64, n[2] as f64);
            assert!((n.dot(&want).abs() - 16384.0 * 16384.0).abs() < 16384.0 * 40.0, "{n:?}");
        }
    }
}
