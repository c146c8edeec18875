//! Covariance of an ICP estimate from the Hessian of the error (Censi 2007, "An accurate
//! closed-form estimate of ICP's covariance").
//!
//! ICP returns `x* = argmin_x J(z, x)`, a function of the measurements `z`. Censi
//! linearises the optimality condition `dJ/dx (z, x*) = 0` and obtains (his Eq. 5)
//!
//! ```text
//! cov(x*) = H^-1 (d2J/dz dx) cov(z) (d2J/dz dx)^T H^-1,     H = d2J/dx2,
//! ```
//!
//! which, unlike the older `2 sigma^2 H^-1` estimate, accounts for the way the
//! measurements enter `J`. Here `x = [a, b, c, s, phi, theta, psi]` (the 7 [`Params`])
//! and
//!
//! ```text
//! J(z, x) = sum_i r_i^T P_i r_i,     r_i = s R(phi, theta, psi) m_i + T - y_i,
//! ```
//!
//! with `m_i` the scan points, `y_i` their closest model points at the given (converged)
//! pose, held fixed, and `P_i` a fixed 3x3 projector ([`Metric`]):
//!
//! - [`Metric::PointToSurface`] (default): `P_i` projects onto the normal space of the
//!   model at `y_i`, estimated by PCA of its [`HessianSettings::neighbours`] nearest model
//!   points: `n n^T` on a surface, `I - t t^T` on a curve, `I` where the model is neither
//!   (isolated points, volumes). This is the second-order model of the squared distance
//!   from `s R m_i + T` to the model *surface*, i.e. of how point-to-point ICP on a densely
//!   sampled model behaves when the closest points are allowed to slide; it is the 3-D
//!   analogue of Censi's point-to-line metric. Motions along which the model slides onto
//!   itself (a turn of a circle about its axis, a shift along a plane) leave `J` unchanged
//!   and come out with (very) large variances.
//! - [`Metric::PointToPoint`]: `P_i = I`, i.e. literally point-to-point with the pairs
//!   frozen. The pairs then pin every parameter, so this variant cannot see
//!   sliding symmetries; it is the covariance of one SVD step with fixed pairs.
//!
//! All derivatives are analytic (first and second derivatives of `R = Rz Ry Rx` in the
//! Euler angles; the tests check them against central differences), including the
//! second-order residual terms of `H` and of `d2J/dz dx`.
//!
//! Noise: `cov(z) = sigma_z^2 I`. By default `sigma^2` is estimated from the residuals as
//! `sum_i r_i^T P_i r_i / sum_i trace(P_i)`, the mean squared residual per constrained
//! coordinate (for `P = I` exactly MSD / 3). With [`Measurements::Scan`] (default) the
//! measurements are the scan points, so all of that variance is attributed to them:
//! `sigma_m^2 = sigma^2 / s^2` in scan units. With [`Measurements::ScanAndModel`] the
//! paired model points are measurements too and the variance is split equally.
//!
//! Singular `H`: the Hessian is analysed in parameters scaled to lengths (translations
//! as they are, angles and relative scale times the RMS radius `L` of the transformed
//! scan). An eigen-direction is declared unobservable when its eigenvalue is below `1e-9`
//! of the largest (or negative: near-symmetric directions whose curvature is dominated
//! by the second-order residual terms), or when the sandwich variance along it would
//! exceed the "no information" level `(pi L)^2`. The sandwich formula is applied on the
//! observable subspace (a pseudo-inverse) and each unobservable direction gets exactly
//! that level: a standard deviation of `pi` rad for an angle, `pi L` for a translation
//! and `pi s` for the scale, i.e. "anything within the size of the problem". The cap
//! keeps the tiny tilts of a numerically null direction from leaking absurd variances
//! into the other parameters. The result is always finite and symmetric positive
//! semi-definite; degenerate inputs (fewer than 3 scan points, zero spread, non-finite
//! values) return that level on the whole diagonal.

use crate::geometry::{rotation_from_euler, Params, Pose};
use crate::nn::NearestNeighbours;
use nalgebra::{Matrix3, Point3, SMatrix, SymmetricEigen, Vector3};

/// A 7x7 covariance of `[a, b, c, s, phi, theta, psi]`.
pub type Covariance = SMatrix<f64, 7, 7>;

/// How each residual is measured in `J` (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Distance to the locally fitted model surface or curve (normal-space projector).
    PointToSurface,
    /// Distance to the paired model point, pairs frozen.
    PointToPoint,
}

/// Which quantities are treated as noisy measurements `z`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measurements {
    /// The scan points only (the model is the reference).
    Scan,
    /// The scan points and their paired model points, sharing the residual variance.
    ScanAndModel,
}

/// Settings of [`hessian_covariance_with`].
#[derive(Clone, Copy, Debug)]
pub struct HessianSettings {
    /// Residual metric.
    pub metric: Metric,
    /// Measurements with noise.
    pub measurements: Measurements,
    /// Residual variance per coordinate `sigma^2` [model units^2]; `None` to estimate it
    /// from the residuals.
    pub noise_variance: Option<f64>,
    /// Model points used to fit the local surface at each closest point
    /// ([`Metric::PointToSurface`]).
    pub neighbours: usize,
    /// PCA eigenvalue ratio below which a local direction counts as flat: a curve when
    /// `l2 <= flatness l1`, a surface when `l3 <= flatness l2` (`l1 >= l2 >= l3`).
    pub flatness: f64,
}

impl Default for HessianSettings {
    fn default() -> Self {
        Self {
            metric: Metric::PointToSurface,
            measurements: Measurements::Scan,
            noise_variance: None,
            neighbours: 8,
            flatness: 0.05,
        }
    }
}

/// Eigenvalues of the scaled Hessian below this fraction of the largest are unobservable.
const RELATIVE_EIGEN_FLOOR: f64 = 1e-9;

/// Standard deviation of an unobservable direction in scaled units (times the RMS
/// radius `L`): `pi` rad for an angle, about the object's size for a translation.
const UNOBSERVABLE_STD: f64 = std::f64::consts::PI;

/// `R`, its first derivatives and its second derivatives in `(phi, theta, psi)`.
struct RotationDerivatives {
    r: Matrix3<f64>,
    d: [Matrix3<f64>; 3],
    dd: [[Matrix3<f64>; 3]; 3],
}

/// Generators: `d/da Rx(a) = Gx Rx(a)`, and so on.
fn generators() -> [Matrix3<f64>; 3] {
    let gx = Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0);
    let gy = Matrix3::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0);
    let gz = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    [gx, gy, gz]
}

fn rotation_derivatives(phi: f64, theta: f64, psi: f64) -> RotationDerivatives {
    let [gx, gy, gz] = generators();
    let rx = rotation_from_euler(phi, 0.0, 0.0);
    let ry = rotation_from_euler(0.0, theta, 0.0);
    let rz = rotation_from_euler(0.0, 0.0, psi);
    // R = Rz Ry Rx; the generators commute with their own axis rotation.
    let f = [rx, ry, rz];
    let g = [gx, gy, gz];
    // Factor k of the product, differentiated `n` times.
    let factor = |k: usize, n: usize| -> Matrix3<f64> {
        match n {
            0 => f[k],
            1 => g[k] * f[k],
            _ => g[k] * g[k] * f[k],
        }
    };
    // Derivative counts per angle (phi, theta, psi) -> Rz^(n_psi) Ry^(n_theta) Rx^(n_phi).
    let product = |n: [usize; 3]| factor(2, n[2]) * factor(1, n[1]) * factor(0, n[0]);
    let mut d = [Matrix3::zeros(); 3];
    let mut dd = [[Matrix3::zeros(); 3]; 3];
    for j in 0..3 {
        let mut n = [0; 3];
        n[j] = 1;
        d[j] = product(n);
        for k in 0..3 {
            let mut n = [0; 3];
            n[j] += 1;
            n[k] += 1;
            dd[j][k] = product(n);
        }
    }
    RotationDerivatives { r: product([0; 3]), d, dd }
}

/// Per-point pieces of the derivatives of `r^T P r`, with `r = s R m + T - y`.
struct PointTerms {
    /// `dJ_i/dx dx` (7x7).
    h: SMatrix<f64, 7, 7>,
    /// `dJ_i/dx dm_i` (7x3).
    b: SMatrix<f64, 7, 3>,
    /// `dJ_i/dx dy_i` (7x3).
    c: SMatrix<f64, 7, 3>,
}

fn point_terms(rd: &RotationDerivatives, s: f64, m: &Vector3<f64>, r: &Vector3<f64>, p: &Matrix3<f64>) -> PointTerms {
    // J = dr/dx (3x7).
    let mut jac = SMatrix::<f64, 3, 7>::zeros();
    jac.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
    jac.set_column(3, &(rd.r * m));
    for k in 0..3 {
        jac.set_column(4 + k, &(s * (rd.d[k] * m)));
    }
    let pr = p * r;
    let jt_p = jac.transpose() * p;
    // H_i = 2 (J^T P J + sum_c (P r)_c d2 r_c / dx2).
    let mut h = jt_p * jac;
    for k in 0..3 {
        let v = pr.dot(&(rd.d[k] * m));
        h[(3, 4 + k)] += v;
        h[(4 + k, 3)] += v;
        for l in 0..3 {
            h[(4 + k, 4 + l)] += s * pr.dot(&(rd.dd[k][l] * m));
        }
    }
    // B_i = 2 (J^T P s R + d(J^T)/dm . P r).
    let mut b = jt_p * (s * rd.r);
    let row_s = rd.r.transpose() * pr;
    for c in 0..3 {
        b[(3, c)] += row_s[c];
    }
    for k in 0..3 {
        let row = s * (rd.d[k].transpose() * pr);
        for c in 0..3 {
            b[(4 + k, c)] += row[c];
        }
    }
    PointTerms { h: 2.0 * h, b: 2.0 * b, c: -2.0 * jt_p }
}

/// Normal-space projector of the model at point `y` from the PCA of its neighbours.
fn surface_projector(nn: &NearestNeighbours, y: &Point3<f64>, k: usize, flat: f64) -> Matrix3<f64> {
    let near = nn.nearest_k(y, k);
    if near.len() < 3 {
        return Matrix3::identity();
    }
    let model = nn.points();
    let mean = near.iter().fold(Vector3::zeros(), |a, c| a + model[c.index].coords) / near.len() as f64;
    let cov = near.iter().fold(Matrix3::zeros(), |a, c| {
        let d = model[c.index].coords - mean;
        a + d * d.transpose()
    });
    let eig = SymmetricEigen::new(cov);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
    let l = order.map(|i| eig.eigenvalues[i].max(0.0));
    let e = order.map(|i| eig.eigenvectors.column(i).into_owned());
    if l[0] <= 0.0 || !l.iter().all(|v| v.is_finite()) {
        Matrix3::identity()
    } else if l[1] <= flat * l[0] {
        Matrix3::identity() - e[0] * e[0].transpose()
    } else if l[2] <= flat * l[1] {
        e[2] * e[2].transpose()
    } else {
        Matrix3::identity()
    }
}

/// Finite and strictly positive.
fn positive(x: f64) -> bool {
    x > 0.0 && x.is_finite()
}

/// Diagonal covariance with the "unobservable" variance on every parameter.
fn unobservable(length: f64, scale: f64) -> Covariance {
    let l = if positive(length) { length } else { 1.0 };
    let s = if positive(scale) { scale } else { 1.0 };
    let t = (UNOBSERVABLE_STD * l).powi(2);
    Covariance::from_diagonal(&SMatrix::<f64, 7, 1>::from_column_slice(&[
        t,
        t,
        t,
        (UNOBSERVABLE_STD * s).powi(2),
        UNOBSERVABLE_STD.powi(2),
        UNOBSERVABLE_STD.powi(2),
        UNOBSERVABLE_STD.powi(2),
    ]))
}

/// Censi's covariance of the pose `pose` registering `scan` onto the model of `nn`, with
/// the default [`HessianSettings`] (point-to-surface metric, noisy scan, noise estimated
/// from the residuals). Order `[a, b, c, s, phi, theta, psi]`, angles in radians.
pub fn hessian_covariance(nn: &NearestNeighbours, scan: &[Point3<f64>], pose: &Pose) -> Covariance {
    hessian_covariance_with(nn, scan, pose, &HessianSettings::default())
}

/// Censi's covariance with explicit settings (see the module documentation).
pub fn hessian_covariance_with(
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    pose: &Pose,
    settings: &HessianSettings,
) -> Covariance {
    let s = pose.scale;
    let x = pose.apply_all(scan);
    let n = x.len();
    // RMS radius of the transformed scan: the length that puts angles on a par with shifts.
    let centroid = x.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n.max(1) as f64;
    let length = (x.iter().map(|p| (p.coords - centroid).norm_squared()).sum::<f64>() / n.max(1) as f64).sqrt();
    let fallback = unobservable(length, s);
    let params: Params = pose.to_params();
    if n < 3 || !positive(s) || !positive(length) || !params.iter().all(|v| v.is_finite()) {
        return fallback;
    }
    let rd = rotation_derivatives(params[4], params[5], params[6]);
    let model = nn.points();

    let mut h = Covariance::zeros();
    let mut bb = Covariance::zeros();
    let mut cc = Covariance::zeros();
    let (mut res2, mut dof) = (0.0, 0.0);
    for (m, xi) in scan.iter().zip(&x) {
        let y = model[nn.closest(xi).index];
        let p = match settings.metric {
            Metric::PointToPoint => Matrix3::identity(),
            Metric::PointToSurface => surface_projector(nn, &y, settings.neighbours, settings.flatness),
        };
        let r = xi - y;
        res2 += r.dot(&(p * r));
        dof += p.trace();
        let t = point_terms(&rd, s, &m.coords, &r, &p);
        h += t.h;
        bb += t.b * t.b.transpose();
        cc += t.c * t.c.transpose();
    }
    let sigma2 = settings.noise_variance.unwrap_or(if dof > 0.0 { res2 / dof } else { 0.0 });
    let (var_m, var_y) = match settings.measurements {
        Measurements::Scan => (sigma2 / (s * s), 0.0),
        Measurements::ScanAndModel => (sigma2 / (2.0 * s * s), sigma2 / 2.0),
    };
    let middle = bb * var_m + cc * var_y;

    // Scale the parameters to lengths: x~ = D x.
    let dscale = SMatrix::<f64, 7, 1>::from_column_slice(&[1.0, 1.0, 1.0, length / s, length, length, length]);
    let hs = Covariance::from_fn(|i, j| h[(i, j)] / (dscale[i] * dscale[j]));
    let ms = Covariance::from_fn(|i, j| middle[(i, j)] / (dscale[i] * dscale[j]));
    if !hs.iter().chain(ms.iter()).all(|v| v.is_finite()) {
        return fallback;
    }
    let eig = SymmetricEigen::new((hs + hs.transpose()) * 0.5);
    let lmax = eig.eigenvalues.max();
    if !positive(lmax) {
        return fallback;
    }
    // Observable eigen-directions: clearly positive curvature, and a sandwich variance
    // below the "no information" level. The others get exactly that level.
    let big = (UNOBSERVABLE_STD * length).powi(2);
    let mut hinv = Covariance::zeros();
    let mut null = Covariance::zeros();
    for k in 0..7 {
        let v = eig.eigenvectors.column(k);
        let l = eig.eigenvalues[k];
        let var = (v.transpose() * ms * v)[(0, 0)] / (l * l);
        if l > RELATIVE_EIGEN_FLOOR * lmax && var < big {
            hinv += v * v.transpose() / l;
        } else {
            null += v * v.transpose() * big;
        }
    }
    let cs = hinv * ms * hinv + null;
    let cov = Covariance::from_fn(|i, j| 0.5 * (cs[(i, j)] + cs[(j, i)]) / (dscale[i] * dscale[j]));
    if cov.iter().all(|v| v.is_finite()) {
        cov
    } else {
        fallback
    }
}

/// Standard deviations (square roots of the diagonal; negative rounding clamped to 0,
/// non-finite entries reported as infinite).
pub fn std_devs(cov: &Covariance) -> [f64; 7] {
    std::array::from_fn(|i| {
        let v = cov[(i, i)];
        if v.is_finite() {
            v.max(0.0).sqrt()
        } else {
            f64::INFINITY
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::registration::icp::{icp, IcpSettings};
    use rand::{Rng, SeedableRng};
    use rand_distr::{Distribution, Normal};

    /// A smooth, curved, non-symmetric surface patch.
    fn surface_at(u: f64, v: f64) -> Point3<f64> {
        let w = 0.35 * (2.0 * u).sin() * (1.5 * v).cos() + 0.3 * u * u - 0.2 * u * v + 0.25 * v * v * v;
        Point3::new(1.3 * u, v, w)
    }

    /// Dense model grid over `[-1, 1]^2`.
    fn surface_model(side: usize) -> Vec<Point3<f64>> {
        let g = |i: usize| -1.0 + 2.0 * i as f64 / (side - 1) as f64;
        (0..side).flat_map(|i| (0..side).map(move |j| surface_at(g(i), g(j)))).collect()
    }

    /// `n` random points of the surface with Gaussian noise, mapped into the scan frame.
    fn surface_scan(n: usize, sigma: f64, truth: &Pose, seed: u64) -> Vec<Point3<f64>> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let normal = Normal::new(0.0, sigma).unwrap();
        let inv = truth.inverse();
        (0..n)
            .map(|_| {
                let p = surface_at(rng.gen_range(-0.9..0.9), rng.gen_range(-0.9..0.9));
                let e = Vector3::from_fn(|_, _| normal.sample(&mut rng));
                inv.apply(&(p + e))
            })
            .collect()
    }

    fn truth() -> Pose {
        Pose::from_params(&[0.1, -0.2, 0.05, 1.1, 0.05, -0.1, 0.2])
    }

    fn pp_settings() -> HessianSettings {
        HessianSettings { metric: Metric::PointToPoint, ..Default::default() }
    }

    #[test]
    fn analytic_derivatives_match_central_differences() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let mut v = || Vector3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let x0: Params = [0.3, -0.2, 0.1, 1.3, 0.4, -0.7, 1.1];
        let m = v();
        let y = v();
        let n = v().normalize();
        let t = v().normalize();
        for p in [Matrix3::identity(), n * n.transpose(), Matrix3::identity() - t * t.transpose()] {
            // J for one point as a function of the 7 parameters, m and y (13 variables).
            let j = |z: &[f64; 13]| {
                let x: Params = std::array::from_fn(|k| z[k]);
                let pose = Pose::from_params(&x);
                let mm = Point3::new(z[7], z[8], z[9]);
                let r = pose.apply(&mm).coords - Vector3::new(z[10], z[11], z[12]);
                r.dot(&(p * r))
            };
            let mut z0 = [0.0; 13];
            z0[..7].copy_from_slice(&x0);
            z0[7..10].copy_from_slice(m.as_slice());
            z0[10..13].copy_from_slice(y.as_slice());
            let hstep = 1e-4;
            let d2 = |a: usize, b: usize| {
                let at = |da: f64, db: f64| {
                    let mut z = z0;
                    z[a] += da;
                    z[b] += db;
                    j(&z)
                };
                (at(hstep, hstep) - at(hstep, -hstep) - at(-hstep, hstep) + at(-hstep, -hstep)) / (4.0 * hstep * hstep)
            };
            let rd = rotation_derivatives(x0[4], x0[5], x0[6]);
            let pose = Pose::from_params(&x0);
            let r = pose.apply(&Point3::from(m)).coords - y;
            let terms = point_terms(&rd, x0[3], &m, &r, &p);
            for a in 0..7 {
                for b in 0..7 {
                    let (num, ana) = (d2(a, b), terms.h[(a, b)]);
                    assert!((num - ana).abs() < 1e-5 * (1.0 + ana.abs()), "H[{a},{b}]: {num} vs {ana}");
                }
                for c in 0..3 {
                    let (num, ana) = (d2(a, 7 + c), terms.b[(a, c)]);
                    assert!((num - ana).abs() < 1e-5 * (1.0 + ana.abs()), "B[{a},{c}]: {num} vs {ana}");
                    let (num, ana) = (d2(a, 10 + c), terms.c[(a, c)]);
                    assert!((num - ana).abs() < 1e-5 * (1.0 + ana.abs()), "C[{a},{c}]: {num} vs {ana}");
                }
            }
        }
    }

    /// Censi's estimate agrees with the spread of ICP's estimates over repeated noisy scans;
    /// freezing the pairs (point-to-point) underestimates it.
    #[test]
    fn predicts_the_spread_of_icp_estimates() {
        let model = surface_model(60);
        let nn = NearestNeighbours::new(&model);
        let t = truth();
        let tp = t.to_params();
        let trials = 40;
        let mut sq_err = [0.0; 7];
        let mut pred = [0.0; 7];
        let mut pred_pp = [0.0; 7];
        for k in 0..trials {
            let scan = surface_scan(300, 0.01, &t, 100 + k);
            let r = icp(&nn, &scan, &t, &IcpSettings::default());
            let est = r.pose.to_params();
            let sd = std_devs(&hessian_covariance(&nn, &scan, &r.pose));
            let pp = std_devs(&hessian_covariance_with(&nn, &scan, &r.pose, &pp_settings()));
            for i in 0..7 {
                sq_err[i] += (est[i] - tp[i]).powi(2) / trials as f64;
                pred[i] += sd[i] / trials as f64;
                pred_pp[i] += pp[i] / trials as f64;
            }
        }
        for i in 0..7 {
            let ratio = pred[i] / sq_err[i].sqrt();
            assert!((0.6..1.7).contains(&ratio), "param {i}: predicted/empirical {ratio}");
            assert!(pred_pp[i] < 0.6 * pred[i], "param {i}: point-to-point {} vs {}", pred_pp[i], pred[i]);
        }
    }

    #[test]
    fn variances_are_positive_and_shrink_with_more_points() {
        let model = surface_model(50);
        let nn = NearestNeighbours::new(&model);
        let t = truth();
        for settings in [HessianSettings::default(), pp_settings()] {
            let few = surface_scan(100, 0.01, &t, 1);
            let many = surface_scan(800, 0.01, &t, 2);
            let a = hessian_covariance_with(&nn, &few, &t, &settings);
            let b = hessian_covariance_with(&nn, &many, &t, &settings);
            for i in 0..7 {
                assert!(a[(i, i)] > 0.0 && b[(i, i)] > 0.0, "{settings:?} {i}");
                // 8 times the points: about 1/8 of the variance.
                let ratio = b[(i, i)] / a[(i, i)];
                assert!(ratio < 0.35, "{settings:?} param {i}: ratio {ratio}");
            }
            assert!((a - a.transpose()).norm() <= 1e-12 * a.norm());
            assert!(SymmetricEigen::new(a).eigenvalues.min() > 0.0);
        }
        // Default entry point = default settings; noise-free scans give tiny variances.
        let exact = t.inverse().apply_all(&model);
        let c = hessian_covariance(&nn, &exact, &t);
        assert!(std_devs(&c).iter().all(|&v| v < 1e-6), "{:?}", std_devs(&c));
    }

    /// A ring about z: turning it about its axis (psi) slides it onto itself.
    #[test]
    fn ring_psi_is_much_less_certain_than_phi() {
        let ring = |n: usize, r: f64| -> Vec<Point3<f64>> {
            (0..n)
                .map(|i| {
                    let a = i as f64 / n as f64 * std::f64::consts::TAU;
                    Point3::new(r * a.cos(), r * a.sin(), 0.0)
                })
                .collect()
        };
        let model = ring(720, 1.0);
        let nn = NearestNeighbours::new(&model);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let normal = Normal::new(0.0, 0.005).unwrap();
        let scan: Vec<_> = (0..300)
            .map(|_| {
                let a: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
                let e = Vector3::from_fn(|_, _| normal.sample(&mut rng));
                Point3::new(a.cos(), a.sin(), 0.0) + e
            })
            .collect();
        let sd = std_devs(&hessian_covariance(&nn, &scan, &Pose::identity()));
        assert!(sd.iter().all(|v| v.is_finite() && *v > 0.0), "{sd:?}");
        assert!(sd[6] > 30.0 * sd[4], "psi {} phi {}", sd[6], sd[4]);
        assert!(sd[6] > 30.0 * sd[5], "psi {} theta {}", sd[6], sd[5]);
        // Frozen point-to-point pairs pin psi: the symmetry is invisible to that variant.
        let pp = std_devs(&hessian_covariance_with(&nn, &scan, &Pose::identity(), &pp_settings()));
        assert!(pp[6] < 3.0 * pp[4], "{pp:?}");
    }

    #[test]
    fn singular_hessian_gives_large_finite_variances() {
        // A plane: shifts along it and turns about its normal are unobservable.
        let plane: Vec<_> =
            (0..30).flat_map(|i| (0..30).map(move |j| Point3::new(i as f64 * 0.1, j as f64 * 0.1, 0.0))).collect();
        let nn = NearestNeighbours::new(&plane);
        let scan: Vec<_> = plane
            .iter()
            .step_by(3)
            .enumerate()
            .map(|(k, p)| p + Vector3::new(0.0, 0.0, if k % 2 == 0 { 1e-3 } else { -1e-3 }))
            .collect();
        let cov = hessian_covariance(&nn, &scan, &Pose::identity());
        assert!(cov.iter().all(|v| v.is_finite()));
        let sd = std_devs(&cov);
        // The "no information" level: pi L for shifts (L = 1.22 here), pi rad for the turn.
        assert!(sd[0] > 3.0 && sd[1] > 3.0, "{sd:?}");
        assert!((sd[6] - std::f64::consts::PI).abs() < 1e-6, "{sd:?}");
        // Scale is seen only through the +-1e-3 offsets: poorly determined, not singular.
        assert!(sd[3] > 0.05, "{sd:?}");
        for i in [2, 4, 5] {
            assert!(sd[i] < 0.01, "param {i}: {sd:?}");
        }
        // Degenerate inputs.
        for pts in [vec![], vec![Point3::new(0.5, 0.5, 0.0)], vec![Point3::new(0.5, 0.5, 0.0); 10]] {
            let cov = hessian_covariance(&nn, &pts, &Pose::identity());
            let sd = std_devs(&cov);
            assert!(cov.iter().all(|v| v.is_finite()) && sd.iter().all(|&v| v >= 1.0), "{sd:?}");
        }
        let mut bad = Covariance::identity();
        bad[(2, 2)] = f64::NAN;
        bad[(3, 3)] = -1e-30;
        let sd = std_devs(&bad);
        assert!(sd[2].is_infinite() && sd[3] == 0.0 && sd[0] == 1.0);
    }

    #[test]
    fn deterministic_and_measurement_split() {
        let model = surface_model(40);
        let nn = NearestNeighbours::new(&model);
        let t = truth();
        let scan = surface_scan(200, 0.01, &t, 5);
        let a = hessian_covariance(&nn, &scan, &t);
        let b = hessian_covariance(&nn, &scan, &t);
        assert_eq!(a, b);
        // Splitting the same residual variance between scan and model changes little
        // for a well-conditioned pose, and an explicit variance scales the result.
        let both = HessianSettings { measurements: Measurements::ScanAndModel, ..Default::default() };
        let c = hessian_covariance_with(&nn, &scan, &t, &both);
        for i in 0..7 {
            let ratio = c[(i, i)] / a[(i, i)];
            assert!((0.5..2.0).contains(&ratio), "param {i}: {ratio}");
        }
        let fixed = |v: f64| HessianSettings { noise_variance: Some(v), ..Default::default() };
        let d1 = hessian_covariance_with(&nn, &scan, &t, &fixed(1e-4));
        let d4 = hessian_covariance_with(&nn, &scan, &t, &fixed(4e-4));
        assert!((d4 - d1 * 4.0).norm() <= 1e-9 * d4.norm());
    }
}
