//! Similarity poses and the Euler-angle convention.
//!
//! A [`Pose`] maps a scan point `m` to the model frame: `d = s R m + T`.
//! Rotations use `R = Rz(psi) * Ry(theta) * Rx(phi)` (intrinsic z-y'-x'', the
//! paper's (phi, theta, psi) about x, y, z). The 7-parameter form used by the
//! particle filter is `[a, b, c, s, phi, theta, psi]` with `T = [a, b, c]` and
//! angles in radians.

use nalgebra::{Matrix3, Matrix4, Point3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

/// Index of each parameter in a [`Params`] vector.
pub mod param {
    /// Translation along x.
    pub const A: usize = 0;
    /// Translation along y.
    pub const B: usize = 1;
    /// Translation along z.
    pub const C: usize = 2;
    /// Scale factor.
    pub const S: usize = 3;
    /// Rotation about x [rad].
    pub const PHI: usize = 4;
    /// Rotation about y [rad].
    pub const THETA: usize = 5;
    /// Rotation about z [rad].
    pub const PSI: usize = 6;
    /// Names, in order, for tables.
    pub const NAMES: [&str; 7] = ["tx", "ty", "tz", "scale", "phi", "theta", "psi"];
}

/// The 7 registration parameters `[a, b, c, s, phi, theta, psi]` (angles in radians).
pub type Params = [f64; 7];

/// A similarity transform `x -> s R x + T` taking scan coordinates to model coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Scale factor `s` (> 0).
    pub scale: f64,
    /// Proper rotation `R` (det = +1).
    pub rotation: Matrix3<f64>,
    /// Translation `T`.
    pub translation: Vector3<f64>,
}

impl Default for Pose {
    fn default() -> Self {
        Self::identity()
    }
}

/// `R = Rz(psi) Ry(theta) Rx(phi)`.
pub fn rotation_from_euler(phi: f64, theta: f64, psi: f64) -> Matrix3<f64> {
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), phi);
    let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), theta);
    let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), psi);
    (rz * ry * rx).into_inner()
}

/// Inverse of [`rotation_from_euler`]: `(phi, theta, psi)` with theta in [-pi/2, pi/2].
pub fn euler_from_rotation(r: &Matrix3<f64>) -> (f64, f64, f64) {
    let theta = (-r[(2, 0)]).clamp(-1.0, 1.0).asin();
    if r[(2, 0)].abs() < 1.0 - 1e-12 {
        let phi = r[(2, 1)].atan2(r[(2, 2)]);
        let psi = r[(1, 0)].atan2(r[(0, 0)]);
        (phi, theta, psi)
    } else {
        // Gimbal lock: only phi -/+ psi is defined; put it all in phi.
        let psi = 0.0;
        let phi = (-r[(1, 2)]).atan2(r[(1, 1)]);
        (phi, theta, psi)
    }
}

/// Wrap an angle to (-pi, pi].
pub fn wrap_angle(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut x = a % two_pi;
    if x <= -std::f64::consts::PI {
        x += two_pi;
    } else if x > std::f64::consts::PI {
        x -= two_pi;
    }
    x
}

impl Pose {
    /// The identity transform.
    pub fn identity() -> Self {
        Self { scale: 1.0, rotation: Matrix3::identity(), translation: Vector3::zeros() }
    }

    /// Build from the 7 parameters `[a, b, c, s, phi, theta, psi]`.
    pub fn from_params(p: &Params) -> Self {
        Self {
            scale: p[param::S],
            rotation: rotation_from_euler(p[param::PHI], p[param::THETA], p[param::PSI]),
            translation: Vector3::new(p[param::A], p[param::B], p[param::C]),
        }
    }

    /// The 7 parameters `[a, b, c, s, phi, theta, psi]`.
    pub fn to_params(&self) -> Params {
        let (phi, theta, psi) = euler_from_rotation(&self.rotation);
        let t = self.translation;
        [t.x, t.y, t.z, self.scale, phi, theta, psi]
    }

    /// Euler angles `[phi, theta, psi]` in degrees.
    pub fn euler_deg(&self) -> [f64; 3] {
        let (phi, theta, psi) = euler_from_rotation(&self.rotation);
        [phi.to_degrees(), theta.to_degrees(), psi.to_degrees()]
    }

    /// Apply to a point: `s R p + T`.
    #[inline]
    pub fn apply(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.scale * (self.rotation * p.coords) + self.translation)
    }

    /// Apply to every point of a slice.
    pub fn apply_all(&self, pts: &[Point3<f64>]) -> Vec<Point3<f64>> {
        pts.iter().map(|p| self.apply(p)).collect()
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn compose(&self, other: &Pose) -> Pose {
        Pose {
            scale: self.scale * other.scale,
            rotation: self.rotation * other.rotation,
            translation: self.scale * (self.rotation * other.translation) + self.translation,
        }
    }

    /// The inverse similarity.
    pub fn inverse(&self) -> Pose {
        let rt = self.rotation.transpose();
        Pose { scale: 1.0 / self.scale, rotation: rt, translation: -(rt * self.translation) / self.scale }
    }

    /// Homogeneous 4x4 matrix `[[sR, T], [0, 1]]`.
    pub fn matrix4(&self) -> Matrix4<f64> {
        let mut m = Matrix4::identity();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&(self.scale * self.rotation));
        m.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.translation);
        m
    }

    /// Angle of the relative rotation `R_a^T R_b` [rad].
    pub fn rotation_angle_to(&self, other: &Pose) -> f64 {
        let rel = self.rotation.transpose() * other.rotation;
        ((rel.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos()
    }

    /// The local parameter error of `self` against `reference`
    /// ([`crate::pf_icp::surface::LOCAL_NAMES`]: the translation of the image of `at`, the
    /// scale, the rotation vector of `R R_ref^T`).
    pub fn local_error(&self, reference: &Pose, at: &Point3<f64>) -> [f64; 7] {
        let t = self.apply(at) - reference.apply(at);
        let r = rotation_vector(&(self.rotation * reference.rotation.transpose()));
        [t.x, t.y, t.z, self.scale - reference.scale, r.x, r.y, r.z]
    }

    /// Rows of the rotation matrix, for JSON.
    pub fn rotation_rows(&self) -> [[f64; 3]; 3] {
        let r = &self.rotation;
        [[r[(0, 0)], r[(0, 1)], r[(0, 2)]], [r[(1, 0)], r[(1, 1)], r[(1, 2)]], [r[(2, 0)], r[(2, 1)], r[(2, 2)]]]
    }

    /// The JSON-facing record of this pose.
    pub fn record(&self) -> PoseRecord {
        PoseRecord {
            scale: self.scale,
            rotation: self.rotation_rows(),
            translation: [self.translation.x, self.translation.y, self.translation.z],
            euler_deg: self.euler_deg(),
        }
    }

    /// Rebuild from a JSON record (the rotation matrix wins over the angles).
    pub fn from_record(r: &PoseRecord) -> Pose {
        let m = Matrix3::from_fn(|i, j| r.rotation[i][j]);
        Pose { scale: r.scale, rotation: m, translation: Vector3::from(r.translation) }
    }
}

/// The rotation vector (axis times angle) of a rotation matrix, from its skew part and its
/// trace by `atan2`: finite and accurate near the identity even when rounding has put the
/// trace a hair above 3 (where nalgebra's `scaled_axis`, by `acos`, gives NaN).
pub fn rotation_vector(r: &Matrix3<f64>) -> Vector3<f64> {
    let v = 0.5 * Vector3::new(r[(2, 1)] - r[(1, 2)], r[(0, 2)] - r[(2, 0)], r[(1, 0)] - r[(0, 1)]);
    let (sin, cos) = (v.norm(), 0.5 * (r.trace() - 1.0));
    if sin < 1e-300 {
        return Vector3::zeros();
    }
    v * (sin.atan2(cos) / sin)
}

/// What the user knows of the scale (scan to model): the interval it lies in. `lo == hi`
/// fixes it (6 degrees of freedom: the clouds' units agree when it is 1); [`ScaleBounds::FREE`]
/// knows nothing. Every stage of PF-ICP keeps its scales inside (the search, the filter,
/// the polish; the board's run through the host's prior and polish).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ScaleBounds {
    /// Smallest scale.
    pub lo: f64,
    /// Largest scale.
    pub hi: f64,
}

impl Default for ScaleBounds {
    fn default() -> Self {
        Self::FREE
    }
}

impl ScaleBounds {
    /// Nothing known.
    pub const FREE: ScaleBounds = ScaleBounds { lo: 0.0, hi: f64::INFINITY };

    /// The scale is `s`.
    pub fn fixed(s: f64) -> Self {
        ScaleBounds { lo: s, hi: s }
    }

    /// The scale lies in `[lo, hi]`.
    pub fn range(lo: f64, hi: f64) -> Self {
        ScaleBounds { lo, hi }
    }

    /// The fixed scale, if the bounds fix it.
    pub fn fixed_value(&self) -> Option<f64> {
        (self.lo == self.hi).then_some(self.lo)
    }

    /// Whether anything is known.
    pub fn is_free(&self) -> bool {
        *self == Self::FREE
    }

    /// `s` moved into the bounds.
    pub fn clamp(&self, s: f64) -> f64 {
        s.max(self.lo).min(self.hi)
    }

    /// Whether `s` lies within the bounds.
    pub fn contains(&self, s: f64) -> bool {
        s >= self.lo && s <= self.hi
    }

    /// The tighter of these bounds and `[lo, hi]`, or the bounds themselves when the two do
    /// not meet.
    pub fn within(&self, lo: f64, hi: f64) -> ScaleBounds {
        let (a, b) = (self.lo.max(lo), self.hi.min(hi));
        if a <= b {
            ScaleBounds { lo: a, hi: b }
        } else {
            *self
        }
    }

    /// `pose` with its scale moved into the bounds, the image of `about` kept where it was
    /// (the least-squares similarity for fixed pairs under the bound: the rotation does not
    /// depend on the scale, and the cost is quadratic in it).
    pub fn apply(&self, pose: &Pose, about: &Point3<f64>) -> Pose {
        let s = self.clamp(pose.scale);
        if s == pose.scale {
            return *pose;
        }
        let image = pose.apply(about);
        Pose { scale: s, rotation: pose.rotation, translation: image.coords - s * (pose.rotation * about.coords) }
    }
}

/// Parameters about a pair of centres: `d = s R (m - c_scan) + c_model + t`, with
/// `x = [t, s, phi, theta, psi]`. Rotating about the clouds' centroids instead of the
/// origin decouples rotation from translation, which the particle filter samples per
/// parameter. With both centres at the origin this is the paper's parameterisation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Centred {
    /// Centre of the scan `c_scan`.
    pub scan: Point3<f64>,
    /// Centre of the model `c_model`.
    pub model: Point3<f64>,
}

impl Centred {
    /// The paper's parameterisation (centres at the origin).
    pub fn origin() -> Self {
        Self { scan: Point3::origin(), model: Point3::origin() }
    }

    /// Parameters of `pose` in this frame.
    pub fn params(&self, pose: &Pose) -> Params {
        let mut p = pose.to_params();
        let t = pose.translation - self.model.coords + pose.scale * (pose.rotation * self.scan.coords);
        p[param::A] = t.x;
        p[param::B] = t.y;
        p[param::C] = t.z;
        p
    }

    /// The pose with parameters `x` in this frame.
    pub fn pose(&self, x: &Params) -> Pose {
        let mut pose = Pose::from_params(x);
        pose.translation += self.model.coords - pose.scale * (pose.rotation * self.scan.coords);
        pose
    }
}

/// A pose as written to JSON: the keys every `pficp` command uses.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PoseRecord {
    /// Scale factor.
    pub scale: f64,
    /// Rotation matrix, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Translation.
    pub translation: [f64; 3],
    /// `[phi, theta, psi]` in degrees.
    pub euler_deg: [f64; 3],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_round_trip() {
        for &(a, b, c) in &[(0.1, -0.3, 2.0), (-0.5143, -0.3246, -0.5143), (3.0, 1.2, -3.0)] {
            let r = rotation_from_euler(a, b, c);
            let (x, y, z) = euler_from_rotation(&r);
            assert!((x - a).abs() < 1e-12 && (y - b).abs() < 1e-12 && (z - c).abs() < 1e-12);
            assert!((r.determinant() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn convention_is_z_then_y_then_x() {
        // A pure psi rotation turns x into y.
        let r = rotation_from_euler(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let v = r * Vector3::x();
        assert!((v - Vector3::y()).norm() < 1e-12);
        // R = Rz Ry Rx: applied to a vector, Rx acts first.
        let r = rotation_from_euler(0.3, 0.2, 0.1);
        let rx = rotation_from_euler(0.3, 0.0, 0.0);
        let ry = rotation_from_euler(0.0, 0.2, 0.0);
        let rz = rotation_from_euler(0.0, 0.0, 0.1);
        assert!((r - rz * ry * rx).norm() < 1e-12);
    }

    #[test]
    fn compose_and_inverse() {
        let p = Pose::from_params(&[0.5, -1.0, 2.0, 0.7, 0.2, -0.4, 1.1]);
        let q = Pose::from_params(&[-0.3, 0.1, 0.0, 1.3, -0.1, 0.3, -0.7]);
        let x = Point3::new(0.3, -2.0, 1.5);
        assert!((p.compose(&q).apply(&x) - p.apply(&q.apply(&x))).norm() < 1e-12);
        assert!((p.inverse().apply(&p.apply(&x)) - x).norm() < 1e-12);
        let back = Pose::from_params(&p.to_params());
        assert!((back.matrix4() - p.matrix4()).norm() < 1e-12);
    }

    #[test]
    fn centred_parameters_round_trip() {
        let c = Centred { scan: Point3::new(1.0, 2.0, 3.0), model: Point3::new(-1.0, 0.5, 4.0) };
        let p = Pose::from_params(&[0.5, -1.0, 2.0, 0.7, 0.2, -0.4, 1.1]);
        let x = c.params(&p);
        assert!((c.pose(&x).matrix4() - p.matrix4()).norm() < 1e-12);
        // The scan centre lands on the model centre plus t.
        let t = nalgebra::Vector3::new(x[0], x[1], x[2]);
        assert!((p.apply(&c.scan) - (c.model + t)).norm() < 1e-12);
        assert_eq!(Centred::origin().params(&p), p.to_params());
    }

    #[test]
    fn wrap() {
        assert!((wrap_angle(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((wrap_angle(-0.5) + 0.5).abs() < 1e-15);
    }
}

#[cfg(test)]
mod rotation_vector_tests {
    use super::rotation_vector;
    use nalgebra::{Matrix3, Rotation3, Vector3};

    #[test]
    fn the_rotation_vector_is_finite_near_the_identity_and_exact_elsewhere() {
        for v in [Vector3::new(0.3, -0.2, 0.5), Vector3::new(1e-7, 0.0, -2e-7), Vector3::new(0.0, 2.5, 0.1)] {
            let r = Rotation3::new(v).into_inner();
            assert!((rotation_vector(&r) - v).norm() < 1e-12, "{v:?}");
        }
        // A near-identity matrix whose trace rounding put above 3.
        let mut r = Rotation3::new(Vector3::new(1e-9, 0.0, 0.0)).into_inner();
        r += Matrix3::identity() * 1e-12;
        assert!(r.trace() > 3.0);
        let e = rotation_vector(&r);
        assert!(e.iter().all(|x| x.is_finite()) && (e.x - 1e-9).abs() < 1e-12, "{e:?}");
    }
}
