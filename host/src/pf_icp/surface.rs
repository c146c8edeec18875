//! The model as a surface: a normal at every model point (principal axis of least spread
//! of its 8 nearest neighbours) and the distance of a point to that surface, for ranking
//! hypotheses, the polish and the uncertainty.
//!
//! **Distance** ([`Surface::distance2`]): with `p` the closest model point to `q`, `n` its
//! normal and `d = q - p`, the squared distance is `(n . d)^2 + max(0, |d_t| - h)^2`,
//! `d_t` the tangential part of `d` and `h` the model's point spacing (the median distance
//! of a model point to its nearest neighbour). Inside the footprint of a model point it is
//! the point-to-plane distance, which does not grow with the model's sampling: between
//! model points a point-to-point distance is mostly sampling (on the benchmark's parts at
//! 2,000 model points, 90% of the cost at the true pose), which drowns the few percent a
//! small symmetry-breaking feature adds. Beyond the footprint it grows as a point-to-point
//! distance, so sliding off an edge is not free. [`Surface::cost`] caps each term
//! (outliers, unmatched points).
//!
//! **Polish** ([`Surface::polish`]): point-to-plane ICP with scale, Gauss-Newton on the
//! linearised residuals `n . (q - p)` of the inliers (surface distance within 3 robust
//! standard deviations), which neither outliers nor the noise pull the way a
//! point-to-point least-squares scale is pulled. (With the tangential excess as a second
//! residual the scale of the benchmark's lidar scene came out 1.1 to 1.5% off; without it
//! 0.1 to 1.1%.) The inliers count alike ([`Weights::Equal`], the registration's polish), or
//! by Tukey's biweight of their residuals ([`Weights::Biweight`], the tracked frames'
//! polish), which falls smoothly to zero at the gate, so that clutter lying close to the
//! surface (a tool against the part) pulls less than the surface's own points.
//!
//! **Curvature** ([`Surface::curvature`]): the Gauss-Newton Hessian `J^T J` of those
//! residuals in local parameters about the estimate ([`LOCAL_NAMES`]), the residual variance, and
//! the parameters the scan cannot determine (a direction of `J^T J` with almost no
//! curvature: rotation about the line of a collinear scan, the in-plane motions of a
//! planar one).

use crate::geometry::{Pose, ScaleBounds};
use crate::nn::NearestNeighbours;
use nalgebra::{Matrix3, Point3, Rotation3, SMatrix, SVector, Vector3};
use rayon::prelude::*;

/// Neighbours of the normal estimate.
const NORMAL_NEIGHBOURS: usize = 8;
/// Cap of the surface cost ([`Surface::cost`]) wherever PF-ICP uses it, as a fraction of the
/// model's bounding-box diagonal.
pub const COST_CAP: f64 = 0.05;
/// Inlier gate of the polish and the curvature, in robust standard deviations.
const INLIER_SIGMAS: f64 = 3.0;

/// Models of more points than [`crate::pf_icp::LARGE_CLOUD`] get their normals when a
/// scan point first lands next to them (each the same as if computed up front) and their
/// spacing from every k-th of at most this many points.
pub const SPACING_POINTS: usize = 20_000;

/// How [`Surface::polish_weighted`] weighs its inliers' residuals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weights {
    /// Every inlier alike: least squares on the gated residuals ([`Surface::polish`]).
    Equal,
    /// Tukey's biweight `(1 - (r / c)^2)^2` of the residual `r`, 0 beyond `c`:
    /// [`INLIER_SIGMAS`] robust standard deviations of the inliers' residuals (1.4826 times
    /// their median magnitude). On the tracking benchmark's dev sequences (clutter blobs in
    /// front of the part) it took the tracked frames' median rotation error from 0.66,
    /// 1.31 and 0.68 deg to 0.60, 0.86 and 0.63 on dog_skull (seeds 1 to 3; docs/tracking.md).
    Biweight,
}

/// A model cloud with normals.
pub struct Surface<'a> {
    nn: &'a NearestNeighbours,
    normals: Normals,
    spacing: f64,
}

/// The model's normals: all of them, or (a large model) each on first use.
enum Normals {
    All(Vec<Vector3<f64>>),
    OnUse(Vec<std::sync::OnceLock<Vector3<f64>>>),
}

/// One scan point against the surface.
#[derive(Clone, Copy, Debug)]
pub struct Contact {
    /// The closest model point.
    pub point: Point3<f64>,
    /// Its normal.
    pub normal: Vector3<f64>,
    /// [`Surface::distance2`].
    pub dist2: f64,
}

/// Images of points under a pose, their [`Contact`]s and the inlier mask
/// ([`Surface::contacts`]).
pub type Contacts = (Vec<Point3<f64>>, Vec<Contact>, Vec<bool>);

/// `J^T J` and what it says about the pose.
#[derive(Clone, Debug)]
pub struct Curvature {
    /// `J^T J` in the local parameters [`LOCAL_NAMES`].
    pub jtj: SMatrix<f64, 7, 7>,
    /// Variance of the point-to-plane residuals over the kept pairs.
    pub residual_variance: f64,
    /// The residuals' gradient outer products summed over spatial blocks,
    /// `sum_b (sum_{i in b} J_i r_i)(sum_{i in b} J_i r_i)^T` (blocks an eighth of the
    /// kept points' bounding-box diagonal wide): the middle of the cluster-robust
    /// (sandwich) covariance `H^-1 M H^-1`, which holds when neighbouring residuals are
    /// correlated or the model misfits a whole region; with independent residuals it is
    /// `sigma^2 J^T J`.
    pub meat: SMatrix<f64, 7, 7>,
    /// Pairs used.
    pub pairs: usize,
    /// What the scan does not determine.
    pub degeneracy: Degeneracy,
}

/// The directions `J^T J` has (almost) no curvature along.
#[derive(Clone, Debug, PartialEq)]
pub struct Degeneracy {
    /// The undetermined motions in words: a parameter name when the motion is along an
    /// axis (`tz`, `scale`, `rz`), else `translation along (x, y, z)`, `rotation about
    /// (x, y, z)`, or the plane a two-dimensional one lies in. Empty: all determined.
    pub motions: Vec<String>,
    /// Per parameter of [`LOCAL_NAMES`]: its variance is unbounded (it has a part along an
    /// undetermined motion).
    pub free: [bool; 7],
    /// The pseudo-inverse of `J^T J` over the determined directions.
    pub inverse: SMatrix<f64, 7, 7>,
}

/// Principal axis of least spread of `points` (unit; `z` if degenerate).
pub fn least_axis(points: &[Point3<f64>]) -> Vector3<f64> {
    let c = points.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / points.len().max(1) as f64;
    let mut cov = Matrix3::zeros();
    for p in points {
        let d = p.coords - c;
        cov += d * d.transpose();
    }
    let e = cov.symmetric_eigen();
    let i = e.eigenvalues.imin();
    let n = e.eigenvectors.column(i).into_owned();
    if n.norm() > 0.0 && n.iter().all(|v| v.is_finite()) {
        n.normalize()
    } else {
        Vector3::z()
    }
}

impl<'a> Surface<'a> {
    /// Normals and spacing of the model behind `nn` (a model of more than
    /// [`crate::pf_icp::LARGE_CLOUD`] points: [`SPACING_POINTS`]).
    pub fn new(nn: &'a NearestNeighbours) -> Self {
        let pts = nn.points();
        let local = |p: &Point3<f64>| {
            let near = nn.nearest_k(p, NORMAL_NEIGHBOURS + 1);
            let nb: Vec<Point3<f64>> = near.iter().map(|c| pts[c.index]).collect();
            // The first neighbour at a distance (duplicated points have several at 0).
            let gap = near.iter().find(|c| c.dist2 > 0.0).map_or(0.0, |c| c.dist2.sqrt());
            (least_axis(&nb), gap)
        };
        if pts.len() > crate::pf_icp::LARGE_CLOUD {
            let normals: Vec<std::sync::OnceLock<Vector3<f64>>> =
                (0..pts.len()).map(|_| std::sync::OnceLock::new()).collect();
            let step = pts.len().div_ceil(SPACING_POINTS).max(1);
            let gaps: Vec<f64> = (0..pts.len())
                .into_par_iter()
                .step_by(step)
                .map(|i| {
                    let (n, gap) = local(&pts[i]);
                    let _ = normals[i].set(n);
                    gap
                })
                .collect();
            let spacing = crate::registration::icp::median(&gaps);
            return Self { nn, normals: Normals::OnUse(normals), spacing };
        }
        let (normals, gaps): (Vec<Vector3<f64>>, Vec<f64>) = pts.par_iter().map(local).unzip();
        let spacing = crate::registration::icp::median(&gaps);
        Self { nn, normals: Normals::All(normals), spacing }
    }

    /// The normal of model point `i` (unit).
    #[inline]
    pub fn normal(&self, i: usize) -> Vector3<f64> {
        match &self.normals {
            Normals::All(n) => n[i],
            Normals::OnUse(n) => *n[i].get_or_init(|| {
                let near = self.nn.nearest_k(&self.nn.points()[i], NORMAL_NEIGHBOURS + 1);
                let nb: Vec<Point3<f64>> = near.iter().map(|c| self.nn.points()[c.index]).collect();
                least_axis(&nb)
            }),
        }
    }

    /// The model's k-d tree.
    pub fn nn(&self) -> &NearestNeighbours {
        self.nn
    }

    /// The model's point spacing (median nearest-neighbour distance).
    pub fn spacing(&self) -> f64 {
        self.spacing
    }

    /// The closest model point to `q`, its normal and the surface distance.
    pub fn contact(&self, q: &Point3<f64>) -> Contact {
        let c = self.nn.closest(q);
        let point = self.nn.points()[c.index];
        let normal = self.normal(c.index);
        let d = q - point;
        let along = normal.dot(&d);
        let tangential = (c.dist2 - along * along).max(0.0).sqrt();
        let excess = (tangential - self.spacing).max(0.0);
        Contact { point, normal, dist2: along * along + excess * excess }
    }

    /// Squared distance of `q` to the surface (the module's rule).
    pub fn distance2(&self, q: &Point3<f64>) -> f64 {
        self.contact(q).dist2
    }

    /// Mean of `min(distance2, cap^2)` over `points` under `pose`.
    pub fn cost(&self, points: &[Point3<f64>], pose: &Pose, cap: f64) -> f64 {
        let cap2 = cap * cap;
        points.iter().map(|p| self.distance2(&pose.apply(p)).min(cap2)).sum::<f64>() / points.len().max(1) as f64
    }

    /// Per-point capped distances (for paired comparisons of two poses).
    pub fn costs(&self, points: &[Point3<f64>], pose: &Pose, cap: f64) -> Vec<f64> {
        let cap2 = cap * cap;
        points.par_iter().map(|p| self.distance2(&pose.apply(p)).min(cap2)).collect()
    }

    /// Contacts of `points` under `pose` and the inlier mask: surface distance within
    /// [`INLIER_SIGMAS`] robust standard deviations (1.4826 times the median distance; at
    /// least half the spacing); the images of `points` first.
    pub fn contacts(&self, points: &[Point3<f64>], pose: &Pose) -> Contacts {
        let q: Vec<Point3<f64>> = points.iter().map(|p| pose.apply(p)).collect();
        let contacts: Vec<Contact> = q.par_iter().map(|x| self.contact(x)).collect();
        let d: Vec<f64> = contacts.iter().map(|c| c.dist2.sqrt()).collect();
        let sigma = 1.4826 * crate::registration::icp::median(&d);
        let tau = (INLIER_SIGMAS * sigma).max(0.5 * self.spacing);
        let mask = d.iter().map(|&x| x <= tau).collect();
        (q, contacts, mask)
    }

    /// Point-to-plane ICP with scale from `start`: Gauss-Newton on the linearised
    /// point-to-plane residuals of the inliers, at most `iterations` steps, the scale kept
    /// within `bounds` (a fixed scale is not a parameter of the step at all).
    pub fn polish(&self, points: &[Point3<f64>], start: &Pose, iterations: usize, bounds: &ScaleBounds) -> Pose {
        self.polish_weighted(points, start, iterations, bounds, Weights::Equal)
    }

    /// [`Surface::polish`] with the inliers weighed by `weights`.
    pub fn polish_weighted(
        &self,
        points: &[Point3<f64>],
        start: &Pose,
        iterations: usize,
        bounds: &ScaleBounds,
        weights: Weights,
    ) -> Pose {
        let fixed = bounds.fixed_value().is_some();
        let mut pose = *start;
        for _ in 0..iterations {
            let (q, contacts, mask) = self.contacts(points, &pose);
            let kept: Vec<usize> = (0..q.len()).filter(|&i| mask[i]).collect();
            if kept.len() < 7 {
                break;
            }
            let c = kept.iter().fold(Vector3::zeros(), |a, &i| a + q[i].coords) / kept.len() as f64;
            let mut a = SMatrix::<f64, 7, 7>::zeros();
            let mut b = SVector::<f64, 7>::zeros();
            let residual = |i: usize| contacts[i].normal.dot(&(q[i] - contacts[i].point));
            let cutoff = match weights {
                Weights::Equal => None,
                Weights::Biweight => {
                    let magnitudes: Vec<f64> = kept.iter().map(|&i| residual(i).abs()).collect();
                    let c = INLIER_SIGMAS * 1.4826 * crate::registration::icp::median(&magnitudes);
                    // (Residuals all zero: nothing to weigh.)
                    (c > 0.0).then_some(c)
                }
            };
            for &i in &kept {
                let x = q[i].coords - c;
                let n = contacts[i].normal;
                let r = residual(i);
                let weight = cutoff.map_or(1.0, |cut| (1.0 - (r / cut).powi(2)).max(0.0).powi(2));
                let w = x.cross(&n);
                // The residual in the scan's units, r / s: a relative scale step d changes it by
                // n.x - r (to first order), so that the noise's share of the cost, s^2 sigma^2
                // a point in the model's units, does not pull the scale down.
                let j = SVector::<f64, 7>::from_column_slice(&[w.x, w.y, w.z, n.x, n.y, n.z, n.dot(&x) - r]);
                a += j * j.transpose() * weight;
                b += j * (r * weight);
            }
            if fixed {
                // The scale's row and column out of the system: its step is exactly 0.
                for k in 0..7 {
                    a[(6, k)] = 0.0;
                    a[(k, 6)] = 0.0;
                }
                a[(6, 6)] = 1.0;
                b[6] = 0.0;
            }
            // A little damping keeps undetermined directions (planar, collinear scans) still.
            let damp = 1e-9 * a.trace().max(1e-300);
            let a = a + SMatrix::<f64, 7, 7>::identity() * damp;
            let Some(step) = a.cholesky().map(|ch| -ch.solve(&b)) else { break };
            if step.iter().any(|v| !v.is_finite()) {
                break;
            }
            let omega = Vector3::new(step[0], step[1], step[2]);
            let rot = Rotation3::new(omega).into_inner();
            let s = (1.0 + step[6]).clamp(0.9, 1.1);
            let t = Vector3::new(step[3], step[4], step[5]);
            let delta = Pose { scale: s, rotation: rot, translation: c + t - s * (rot * c) };
            let next = delta.compose(&pose);
            pose = if fixed { next } else { bounds.apply(&next, &pose.inverse().apply(&Point3::from(c))) };
            if omega.norm() < 1e-8 && t.norm() < 1e-8 * self.spacing.max(1e-300) * 100.0 && step[6].abs() < 1e-8 {
                break;
            }
        }
        pose
    }

    /// `J^T J` of the inliers' point-to-plane residuals at `pose` in the local parameters
    /// [`LOCAL_NAMES`] about the image `at` of the scan's centroid, the residual variance and
    /// the undetermined parameters; with `scale_known` the scale is no parameter (its
    /// variance 0, the others' conditional on it).
    pub fn curvature(&self, points: &[Point3<f64>], pose: &Pose, at: &Point3<f64>, scale_known: bool) -> Curvature {
        self.curvature_of(&self.contacts(points, pose), pose, at, scale_known)
    }

    /// [`Surface::curvature`] from the points' [`Surface::contacts`] under `pose`.
    pub fn curvature_of(&self, contacts: &Contacts, pose: &Pose, at: &Point3<f64>, scale_known: bool) -> Curvature {
        let (q, contacts, mask) = contacts;
        let mut jtj = SMatrix::<f64, 7, 7>::zeros();
        let (mut sum2, mut count) = (0.0, 0usize);
        let scale = pose.scale.abs().max(1e-12);
        let kept_points: Vec<Point3<f64>> = (0..q.len()).filter(|&i| mask[i]).map(|i| q[i]).collect();
        let (lo, _) = crate::cloud::bbox(&kept_points);
        let side = (crate::cloud::bbox_diagonal(&kept_points) / 8.0).max(1e-300);
        // A BTreeMap: the blocks summed in one order, so that the covariance repeats to the bit.
        let mut gradients: std::collections::BTreeMap<(i64, i64, i64), SVector<f64, 7>> =
            std::collections::BTreeMap::new();
        // Only the point-to-plane residual: the tangential excess is a penalty for leaving a
        // model point's footprint, not information about where the surface is.
        for i in (0..q.len()).filter(|&i| mask[i]) {
            let x = q[i] - at;
            let n = contacts[i].normal;
            let r = n.dot(&(q[i] - contacts[i].point));
            let w = x.cross(&n);
            let j = SVector::<f64, 7>::from_column_slice(&[n.x, n.y, n.z, n.dot(&x) / scale, w.x, w.y, w.z]);
            jtj += j * j.transpose();
            sum2 += r * r;
            count += 1;
            let b = (q[i] - lo) / side;
            *gradients
                .entry((b.x.floor() as i64, b.y.floor() as i64, b.z.floor() as i64))
                .or_insert(SVector::zeros()) += j * r;
        }
        let meat = gradients.values().fold(SMatrix::<f64, 7, 7>::zeros(), |m, g| m + g * g.transpose());
        let residual_variance = sum2 / (count as f64 - 7.0).max(1.0);
        // The scan image's RMS radius about `at`: a translation by it, a relative scale change
        // of 1 and a turn of 1 rad move the points by about as much.
        let kept: Vec<&Point3<f64>> = (0..q.len()).filter(|&i| mask[i]).map(|i| &q[i]).collect();
        let radius =
            (kept.iter().map(|p| (*p - at).norm_squared()).sum::<f64>() / kept.len().max(1) as f64).sqrt().max(1e-300);
        let degeneracy = degeneracy(&jtj, radius, scale, scale_known);
        Curvature { jtj, residual_variance, meat, pairs: count, degeneracy }
    }
}

/// Names of the local parameters of [`Surface::curvature`] and of the result's covariance:
/// the translation of the scan centroid's image (model units), the scale, and the small
/// rotation vector about the model frame's axes at that point (rad): a pose `(s, R, T)`
/// near the estimate `(s0, R0, T0)` has `t = s R c + T - (s0 R0 c + T0)` (`c` the scan's
/// centroid), `scale = s - s0`, `r = log(R R0^T)`.
pub const LOCAL_NAMES: [&str; 7] = ["tx", "ty", "tz", "scale", "rx", "ry", "rz"];

/// A direction counts as undetermined below this fraction of the largest curvature (in
/// units made comparable: translations in the scan image's RMS radius, scale relative,
/// radians).
const FLAT: f64 = 1e-6;

/// Describe the null directions of a 3 x 3 block (`kind`: "translation" or "rotation",
/// `names` the axis parameters).
fn describe_block(m: &nalgebra::Matrix3<f64>, top: f64, kind: &str, names: [&str; 3], out: &mut Vec<String>) {
    let e = m.symmetric_eigen();
    let null: Vec<Vector3<f64>> =
        (0..3).filter(|&k| e.eigenvalues[k] < FLAT * top).map(|k| e.eigenvectors.column(k).into_owned()).collect();
    let axis = |v: &Vector3<f64>| (0..3).find(|&i| v[i].abs() > (1f64).to_radians().cos());
    let show = |v: &Vector3<f64>| {
        let v = if v[v.iamax()] < 0.0 { -v } else { *v };
        format!("({:.2}, {:.2}, {:.2})", v.x, v.y, v.z)
    };
    match null.len() {
        0 => {}
        1 => out.push(match axis(&null[0]) {
            Some(i) => names[i].to_string(),
            None => format!("{kind} {} {}", if kind == "rotation" { "about" } else { "along" }, show(&null[0])),
        }),
        2 => {
            let normal = null[0].cross(&null[1]);
            match axis(&normal) {
                Some(i) => out.extend((0..3).filter(|&j| j != i).map(|j| names[j].to_string())),
                None => out.push(format!("{kind} perpendicular to {}", show(&normal))),
            }
        }
        _ => out.extend(names.iter().map(|n| n.to_string())),
    }
}

/// What `J^T J` leaves undetermined, and its pseudo-inverse over the rest (with
/// `scale_known`, over the parameters besides the scale, whose rows and columns are 0).
fn degeneracy(jtj: &SMatrix<f64, 7, 7>, radius: f64, scale: f64, scale_known: bool) -> Degeneracy {
    let unit = [radius, radius, radius, scale, 1.0, 1.0, 1.0];
    let d = SMatrix::<f64, 7, 7>::from_diagonal(&SVector::<f64, 7>::from_column_slice(&unit));
    let mut m = d * jtj * d;
    if scale_known {
        // The scale decoupled, at the largest curvature of the rest: never flat, and its
        // entries of the inverse cleared below.
        for k in 0..7 {
            m[(3, k)] = 0.0;
            m[(k, 3)] = 0.0;
        }
        m[(3, 3)] = m.symmetric_eigen().eigenvalues.max().max(1e-300);
    }
    let e = m.symmetric_eigen();
    let top = e.eigenvalues.max().max(1e-300);
    let mut inverse = SMatrix::<f64, 7, 7>::zeros();
    let mut null = SMatrix::<f64, 7, 7>::zeros();
    for k in 0..7 {
        let v = e.eigenvectors.column(k);
        if e.eigenvalues[k] < FLAT * top {
            null += v * v.transpose();
        } else {
            inverse += v * v.transpose() / e.eigenvalues[k];
        }
    }
    let free = std::array::from_fn(|k| null.column(k).norm() > 0.1);
    let mut motions = Vec::new();
    describe_block(&m.fixed_view::<3, 3>(0, 0).into_owned(), top, "translation", ["tx", "ty", "tz"], &mut motions);
    if m[(3, 3)] < FLAT * top {
        motions.push("scale".to_string());
    }
    describe_block(&m.fixed_view::<3, 3>(4, 4).into_owned(), top, "rotation", ["rx", "ry", "rz"], &mut motions);
    if motions.is_empty() && free.iter().any(|&f| f) {
        motions.push("a combined motion".to_string());
    }
    let mut inverse = d * inverse * d;
    if scale_known {
        for k in 0..7 {
            inverse[(3, k)] = 0.0;
            inverse[(k, 3)] = 0.0;
        }
    }
    Degeneracy { motions, free, inverse }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parts::Part;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn normals_of_a_box_face_point_out_of_the_face() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let pts = Part::Block.sample_surface(3000, &mut rng);
        let nn = NearestNeighbours::new(&pts);
        let s = Surface::new(&nn);
        // Points in the middle of the top face (z = 0.15).
        let top: Vec<usize> = (0..pts.len())
            .filter(|&i| (pts[i].z - 0.15).abs() < 1e-9 && pts[i].x.abs() < 0.3 && pts[i].y.abs() < 0.15)
            .collect();
        assert!(top.len() > 50);
        assert!(top.iter().all(|&i| s.normal(i).z.abs() > 0.99));
        // Above the face by 0.01: the surface distance is 0.01 whatever the sampling.
        let q = Point3::new(0.05, 0.02, 0.16);
        assert!((s.distance2(&q).sqrt() - 0.01).abs() < 1e-3);
    }

    #[test]
    fn the_polish_recovers_a_small_offset_with_scale() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let model = Part::NearCubeNotch.sample_surface(3000, &mut rng);
        let scan_model = Part::NearCubeNotch.sample_surface(800, &mut rng);
        let truth = Pose::from_params(&[0.1, -0.2, 0.05, 1.1, 0.3, -0.2, 0.4]);
        let scan: Vec<Point3<f64>> = scan_model.iter().map(|p| truth.inverse().apply(p)).collect();
        let nn = NearestNeighbours::new(&model);
        let s = Surface::new(&nn);
        let off = Pose::from_params(&[0.12, -0.18, 0.04, 1.13, 0.33, -0.17, 0.43]);
        let p = s.polish(&scan, &off, 30, &ScaleBounds::FREE);
        assert!(p.rotation_angle_to(&truth).to_degrees() < 0.3);
        assert!((p.scale / truth.scale - 1.0).abs() < 3e-3);
    }

    #[test]
    fn the_biweight_lets_clutter_against_the_surface_pull_less() {
        use rand::Rng;
        use rand_distr::{Distribution, Normal};
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let model = Part::Block.sample_surface(3000, &mut rng);
        let diag = crate::cloud::bbox_diagonal(&model);
        let noise = Normal::new(0.0, 0.005 * diag).unwrap();
        // The view: the block's points facing +z and +x, with noise.
        let mut scan: Vec<Point3<f64>> = Part::Block
            .sample_surface(3000, &mut rng)
            .into_iter()
            .filter(|p| p.z > 0.1 || p.x > 0.25)
            .map(|p| p + Vector3::new(noise.sample(&mut rng), noise.sample(&mut rng), noise.sample(&mut rng)))
            .collect();
        // A blob held in front of one end of the top face (z = 0.15), 2 to 5 noise sigmas
        // above it: half of it inside the polish's gate (3 robust sigmas).
        let blob = scan.len() / 10;
        for _ in 0..blob {
            let (x, y) = (rng.gen_range(-0.3..-0.2), rng.gen_range(-0.05..0.05));
            scan.push(Point3::new(x, y, 0.15 + rng.gen_range(2.0..5.0) * 0.005 * diag));
        }
        let nn = NearestNeighbours::new(&model);
        let s = Surface::new(&nn);
        let error = |scan: &[Point3<f64>], weights: Weights| {
            let p = s.polish_weighted(scan, &Pose::identity(), 30, &ScaleBounds::fixed(1.0), weights);
            p.rotation_angle_to(&Pose::identity()).to_degrees()
        };
        // Measured: 0.55 deg with equal weights, 0.10 with the biweight; 0.07 and 0.09
        // without the blob.
        let (equal, biweight) = (error(&scan, Weights::Equal), error(&scan, Weights::Biweight));
        assert!(biweight < 0.5 * equal, "the blob tilts the biweight's pose {biweight} deg, the equal's {equal} deg");
        let alone = error(&scan[..scan.len() - blob], Weights::Biweight);
        assert!(alone < 0.15, "without the blob the biweight's pose is {alone} deg off");
    }

    #[test]
    fn a_planar_scan_leaves_in_plane_motion_undetermined() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        use rand::Rng;
        let model: Vec<Point3<f64>> =
            (0..2000).map(|_| Point3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), 0.0)).collect();
        let scan: Vec<Point3<f64>> =
            (0..500).map(|_| Point3::new(rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5), 0.0)).collect();
        let nn = NearestNeighbours::new(&model);
        let s = Surface::new(&nn);
        let c = s.curvature(&scan, &Pose::identity(), &crate::cloud::centroid(&scan), false);
        assert_eq!(c.degeneracy.motions, ["tx", "ty", "scale", "rz"]);
        assert_eq!(c.degeneracy.free, [true, true, false, true, false, false, true]);
        // A box is determined.
        let model = Part::NearCubeNotch.sample_surface(3000, &mut rng);
        let nn = NearestNeighbours::new(&model);
        let s = Surface::new(&nn);
        let c = s.curvature(&model[..800], &Pose::identity(), &crate::cloud::centroid(&model[..800]), false);
        assert!(c.degeneracy.motions.is_empty() && c.degeneracy.free.iter().all(|f| !f));
    }
}
