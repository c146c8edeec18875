//! The tracker's motion model: constant velocity of the part in the camera's frame,
//! filtered, and a spread that follows how far the frames' answers land from the
//! predictions.
//!
//! A registration pose `T` maps the scan (the camera's frame) onto the model, so the part
//! sits in the camera's frame at `M = T^-1`. The part's motion in one frame is a
//! [`LocalDelta`] `v` about the image of the scan's centroid, and the prediction is the
//! last estimate moved by it ([`after`]); a steady motion measured exactly is predicted
//! exactly from the second tracked frame on.
//!
//! **The filter** ([`Motion::accept`]): per [`LocalDelta`] parameter a constant-velocity
//! Kalman filter of the estimate and its velocity. The measurement is the frame's answer,
//! its variance the answer's one-sigma from the curvature; the process noise a white
//! acceleration of [`ACCELERATION`]. A frame's answer carries the noise of its view (0.5%
//! of the diagonal on each point, fresh clutter), which varies from frame to frame more
//! than the part moves off a constant velocity: the track's estimate weighs the frame
//! against the motion so far.
//!
//! The **innovation** of a frame is its answer's [`LocalDelta`] from the prediction about
//! the image of the scan's centroid. The spread of the next frame's prior is
//! [`SPREAD_GAIN`] times the root mean square of the recent innovations (an exponential
//! average, weight [`INNOVATION_MEMORY`]), never below the floor (sensor noise, a
//! prediction's own error) nor above the cap (a larger motion is a lost track, found
//! again by a global registration).

use crate::geometry::Pose;
use nalgebra::{Point3, Rotation3, Vector3};

/// Weight of the newest frame's innovation in the running mean square.
pub const INNOVATION_MEMORY: f64 = 0.2;
/// The prior's spread in root-mean-square innovations (the filter draws within two spreads).
pub const SPREAD_GAIN: f64 = 2.0;
/// Least spread: translation [fraction of the diagonal], relative scale, rotation [deg].
pub const SPREAD_FLOOR: (f64, f64, f64) = (0.003, 0.003, 0.3);
/// Widest spread at [`CAP_FPS`] frames a second: translation [fraction of the diagonal],
/// relative scale, rotation [deg]; at another rate the translation and rotation caps scale
/// with the time between frames (a part moves farther between slower frames).
pub const SPREAD_CAP: (f64, f64, f64) = (0.05, 0.02, 5.0);
/// The frame rate [`SPREAD_CAP`] is given at.
pub const CAP_FPS: f64 = 30.0;

/// A small change of pose about a centre `at` (in the model's frame): translation of the
/// centre's image, relative scale `s - 1`, rotation vector; applied after a pose as
/// [`LocalDelta::after`].
pub type LocalDelta = [f64; 7];

/// `delta` applied after `pose` about the model-frame point `at`: the rotation and the
/// scale about `at`, then the translation.
pub fn after(pose: &Pose, delta: &[f64], at: &Point3<f64>) -> Pose {
    let omega = Vector3::new(delta[4], delta[5], delta[6]);
    let rotation = Rotation3::new(omega).into_inner();
    let s = 1.0 + delta[3];
    let t = Vector3::new(delta[0], delta[1], delta[2]);
    let step = Pose { scale: s, rotation, translation: at.coords + t - s * (rotation * at.coords) };
    step.compose(pose)
}

/// The [`LocalDelta`] that takes `from` to `to` about the model-frame point `at`
/// (the inverse of [`after`]).
pub fn delta_between(from: &Pose, to: &Pose, at: &Point3<f64>) -> LocalDelta {
    let step = to.compose(&from.inverse());
    let t = step.apply(at) - at;
    let r = crate::geometry::rotation_vector(&step.rotation);
    [t.x, t.y, t.z, step.scale - 1.0, r.x, r.y, r.z]
}

/// `pose` with its rotation made orthonormal again (the nearest rotation): a chain of
/// compositions and transposes, frame after frame, would let rounding grow without bound
/// (a transpose is the inverse of a rotation only).
pub fn orthonormal(pose: &Pose) -> Pose {
    Pose { rotation: Rotation3::from_matrix(&pose.rotation).into_inner(), ..*pose }
}

/// The motion a track expects: the largest acceleration of the part, rotation [deg/s^2]
/// and translation [diagonals/s^2] (the scale's is 0: a rigid part). The process noise of
/// [`Motion`]'s filter, one standard deviation. The tracking benchmark's motion reaches
/// about 57 deg/s^2 and 0.1 diagonals/s^2; these are that with a margin (docs/tracking.md,
/// "Why the answers are filtered", has the dev split's errors at half to four times them).
pub const ACCELERATION: (f64, f64) = (90.0, 0.2);

/// An answer this many standard deviations from the prediction in some parameter is a
/// manoeuvre (a move faster than [`ACCELERATION`] allows): the track takes the answer
/// whole and measures the velocity again from it, so that the estimate never trails a
/// sudden move the answer has seen.
pub const MANOEUVRE_SIGMAS: f64 = 4.0;

/// Constant velocity, filtered: per [`LocalDelta`] parameter a Kalman filter over the
/// track's estimate and its velocity, the frames' answers its measurements (their
/// one-sigma values from the curvature), white acceleration of [`ACCELERATION`] its process
/// noise; and the spread of the next frame's prior from the innovations.
#[derive(Clone, Debug)]
pub struct Motion {
    /// The track's estimate (scan to model).
    last: Option<Pose>,
    /// The motion a frame, a [`LocalDelta`] about `centre`.
    velocity: LocalDelta,
    centre: Point3<f64>,
    /// Per parameter, the covariance of (estimate, velocity): `[var, cov, var]`.
    covariance: [[f64; 3]; 7],
    /// No velocity measured yet: the next answer gives it (two-point start).
    fresh: bool,
    /// Running mean square innovation per [`LocalDelta`] parameter.
    mean_square: [f64; 7],
}

/// A measurement's variance from its one-sigma value in the conclusion's local parameters
/// (the scale's absolute, here relative to `scale`); an undetermined one tells nothing.
fn variance(sigma: Option<f64>, k: usize, scale: f64) -> f64 {
    match sigma {
        Some(s) if s.is_finite() => {
            let s = if k == 3 { s / scale } else { s };
            s * s
        }
        _ => f64::INFINITY,
    }
}

impl Motion {
    /// No answer yet: no prediction.
    pub fn new() -> Self {
        Motion {
            last: None,
            velocity: [0.0; 7],
            centre: Point3::origin(),
            covariance: [[0.0; 3]; 7],
            fresh: false,
            mean_square: [0.0; 7],
        }
    }

    /// Start again from `pose` (one-sigma `sigma` per local parameter) with no velocity
    /// known: a new or re-acquired track of a model of diagonal `diag` at `fps` frames a
    /// second. The first tracked frame's answer gives the velocity (the difference of the
    /// two answers, as a two-point start does; an undetermined variance counts as the
    /// spread's cap).
    pub fn restart(&mut self, pose: Pose, sigma: &[Option<f64>; 7], diag: f64, fps: f64) {
        let cap = spread_cap(diag, fps);
        let mut covariance = [[0.0; 3]; 7];
        for (k, c) in covariance.iter_mut().enumerate() {
            c[0] = variance(sigma[k], k, pose.scale).min(cap[k] * cap[k]);
        }
        *self = Motion { last: Some(orthonormal(&pose)), covariance, fresh: true, ..Motion::new() };
    }

    /// Start again from `pose` as [`Motion::restart`] does, keeping the innovations'
    /// spread: the track's answer became another pose of a near-symmetric part (a carried
    /// alternative), which is no motion.
    pub fn rebase(&mut self, pose: Pose, sigma: &[Option<f64>; 7], diag: f64, fps: f64) {
        let mean_square = self.mean_square;
        self.restart(pose, sigma, diag, fps);
        self.mean_square = mean_square;
    }

    /// The newest estimate the track holds.
    pub fn last(&self) -> Option<Pose> {
        self.last
    }

    /// The pose predicted for the next frame (`None` before the first answer): the last
    /// estimate moved by the velocity.
    pub fn predict(&self) -> Option<Pose> {
        Some(orthonormal(&after(&self.last?, &self.velocity, &self.centre)))
    }

    /// Take the frame's answer `pose` (one-sigma `sigma` per local parameter), predicted as
    /// `predicted`, `at` the image of the scan's centroid, for a model of diagonal `diag`
    /// at `fps` frames a second; the track's new estimate. (Taking the answer whole, as the
    /// tracker did, left the frames' noise in the track: the dev split's median errors were
    /// 0.81, 0.30 and 0.22 deg against 0.66, 0.24 and 0.17 filtered.)
    #[allow(clippy::too_many_arguments)]
    pub fn accept(
        &mut self,
        pose: Pose,
        sigma: &[Option<f64>; 7],
        predicted: &Pose,
        at: &Point3<f64>,
        diag: f64,
        fps: f64,
    ) -> Pose {
        let innovation = delta_between(predicted, &pose, at);
        for (m, d) in self.mean_square.iter_mut().zip(innovation) {
            *m = (1.0 - INNOVATION_MEMORY) * *m + INNOVATION_MEMORY * d * d;
        }
        // The velocity about the new centre.
        let step = after(&Pose::identity(), &self.velocity, &self.centre);
        let mut velocity = delta_between(&Pose::identity(), &step, at);
        let cap = spread_cap(diag, fps);
        // Per parameter: the answer's variance and the prediction's covariance (x + v, v;
        // the white acceleration adds a/2 on x and a on v).
        let measured: [f64; 7] = std::array::from_fn(|k| variance(sigma[k], k, pose.scale));
        let dt2 = 1.0 / (fps * fps);
        let (deg, diags) = ACCELERATION;
        let predicted_covariance: [[f64; 3]; 7] = std::array::from_fn(|k| {
            let a = match k {
                0..=2 => diags * diag * dt2,
                3 => 0.0,
                _ => deg.to_radians() * dt2,
            };
            let q = a * a;
            let [p00, p01, p11] = self.covariance[k];
            [p00 + 2.0 * p01 + p11 + 0.25 * q, p01 + p11 + 0.5 * q, p11 + q]
        });
        // A manoeuvre: an answer more than `MANOEUVRE_SIGMAS` from the prediction in some
        // parameter, by the prediction's and the answer's variances together (the part
        // moved off its velocity faster than `ACCELERATION`, or the answer is far off).
        let manoeuvre = (0..7).any(|k| {
            let s = predicted_covariance[k][0] + measured[k];
            s.is_finite() && s > 0.0 && innovation[k] * innovation[k] > MANOEUVRE_SIGMAS * MANOEUVRE_SIGMAS * s
        });
        if self.fresh || manoeuvre {
            // Two-point start: the answer whole, the velocity from the last estimate to it.
            for k in 0..7 {
                let r = measured[k].min(cap[k] * cap[k]);
                velocity[k] += innovation[k];
                self.covariance[k] = [r, r, self.covariance[k][0] + r];
            }
            self.fresh = false;
            self.velocity = velocity;
            self.centre = *at;
            self.last = Some(orthonormal(&pose));
            return pose;
        }
        let mut correction = [0.0; 7];
        for k in 0..7 {
            let [p00, p01, p11] = predicted_covariance[k];
            let s = p00 + measured[k];
            // (An exact measurement, the fixed scale's among them, is taken whole; an
            // undetermined one not at all.)
            let (k0, k1) = match s {
                0.0 => (1.0, 0.0),
                s if s.is_finite() => (p00 / s, p01 / s),
                _ => (0.0, 0.0),
            };
            correction[k] = k0 * innovation[k];
            velocity[k] += k1 * innovation[k];
            self.covariance[k] = [(1.0 - k0) * p00, (1.0 - k0) * p01, p11 - k1 * p01];
        }
        let estimate = orthonormal(&after(predicted, &correction, at));
        self.velocity = velocity;
        self.centre = *at;
        self.last = Some(estimate);
        estimate
    }

    /// Standard deviations of the next frame's prior per [`LocalDelta`] parameter, for a
    /// model of diagonal `diag` at `fps` frames a second (the scale's 0 when `scale_fixed`).
    pub fn spread(&self, diag: f64, scale_fixed: bool, fps: f64) -> [f64; 7] {
        let bound =
            |k: usize, floor: f64, cap: f64| (SPREAD_GAIN * self.mean_square[k].sqrt()).clamp(floor, cap.max(floor));
        let (tf, sf, rf) = SPREAD_FLOOR;
        let cap = spread_cap(diag, fps);
        let mut s = [0.0; 7];
        for k in 0..3 {
            s[k] = bound(k, tf * diag, cap[k]);
            s[k + 4] = bound(k + 4, rf.to_radians(), cap[k + 4]);
        }
        s[3] = if scale_fixed { 0.0 } else { bound(3, sf, cap[3]) };
        s
    }
}

/// [`SPREAD_CAP`] per [`LocalDelta`] parameter for a model of diagonal `diag` at `fps`
/// frames a second (translation and rotation scale with the time between frames).
fn spread_cap(diag: f64, fps: f64) -> LocalDelta {
    let per_frame = CAP_FPS / fps;
    let (t, s, r) = (SPREAD_CAP.0 * per_frame * diag, SPREAD_CAP.1, (SPREAD_CAP.2 * per_frame).to_radians());
    [t, t, t, s, r, r, r]
}

impl Default for Motion {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A part turning and sliding at a constant rate is predicted exactly; a delta and its
    /// inverse round-trip.
    #[test]
    fn constant_velocity_predicts_a_steady_motion() {
        let start = Pose::from_params(&[0.1, -0.2, 0.3, 1.2, 0.3, -0.2, 0.5]);
        let at = Point3::new(0.2, 0.1, -0.3);
        let step = [0.01, -0.02, 0.005, 0.0, 0.01, 0.02, -0.015];
        // The part's motion in the camera frame: M_{k+1} = D M_k, so T_{k+1} = T_k D^-1.
        let d = after(&Pose::identity(), &step, &Point3::origin());
        let poses: Vec<Pose> = (0..4).scan(start, |t, _| Some(std::mem::replace(t, t.compose(&d.inverse())))).collect();
        // Exact answers: one-sigma values far below the motion's.
        let exact = [Some(1e-12); 7];
        let mut m = Motion::new();
        assert!(m.predict().is_none());
        m.restart(poses[0], &exact, 1.0, CAP_FPS);
        m.accept(poses[1], &exact, &poses[0], &at, 1.0, CAP_FPS);
        let p = m.predict().unwrap();
        assert!(p.rotation_angle_to(&poses[2]) < 1e-12);
        assert!((p.translation - poses[2].translation).norm() < 1e-12);
        assert!((p.scale - poses[2].scale).abs() < 1e-12);
        let back = delta_between(&poses[1], &after(&poses[1], &step, &at), &at);
        for (a, b) in back.iter().zip(step) {
            assert!((a - b).abs() < 1e-12, "{back:?}");
        }
        // A steady motion's innovation after the first frame is zero: the spread falls to
        // its floor.
        for pose in &poses[2..4] {
            m.accept(*pose, &exact, &m.predict().unwrap(), &at, 1.0, CAP_FPS);
        }
        let s = m.spread(1.0, true, CAP_FPS);
        assert_eq!(s[3], 0.0);
        assert!(s[4] >= SPREAD_FLOOR.2.to_radians() && s[4] < 2.0 * SPREAD_GAIN * 0.02);
        // A jump far beyond the cap: the spread stops at the cap, twice as wide at half the
        // frame rate (twice the time between frames).
        let far = after(&poses[3], &[0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], &at);
        m.accept(far, &exact, &m.predict().unwrap(), &at, 1.0, CAP_FPS);
        let (at30, at15) = (m.spread(1.0, true, CAP_FPS), m.spread(1.0, true, CAP_FPS / 2.0));
        assert!((at30[5] - SPREAD_CAP.2.to_radians()).abs() < 1e-12, "{at30:?}");
        assert!((at15[5] - 2.0 * at30[5]).abs() < 1e-12 && (at15[0] - 2.0 * at30[0]).abs() < 1e-12);
    }

    /// Answers with noise about a steady motion: the filtered estimates are closer to the
    /// truth than the answers, and a steady motion stays predicted (no lag).
    #[test]
    fn the_filter_takes_the_noise_out_of_the_answers() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let start = Pose::from_params(&[0.1, -0.2, 0.3, 1.0, 0.3, -0.2, 0.5]);
        let at = Point3::new(0.2, 0.1, -0.3);
        // 15 deg/s and 0.03 diagonals/s at 30 frames a second (diagonal 1).
        let step = [0.001, -0.0005, 0.0, 0.0, 0.004, -0.006, 0.003];
        let d = after(&Pose::identity(), &step, &Point3::origin());
        // Noise of 0.5 deg and 0.3% of the diagonal on each answer.
        let (sr, st) = (0.5f64.to_radians(), 0.003);
        let sigma = [Some(st), Some(st), Some(st), Some(0.0), Some(sr), Some(sr), Some(sr)];
        let (nr, nt) = (Normal::new(0.0, sr).unwrap(), Normal::new(0.0, st).unwrap());
        let mut truth = start;
        let mut m = Motion::new();
        m.restart(start, &sigma, 1.0, CAP_FPS);
        let (mut answers, mut estimates) = (0.0, 0.0);
        for k in 0..90 {
            truth = truth.compose(&d.inverse());
            let noise = [
                nt.sample(&mut rng),
                nt.sample(&mut rng),
                nt.sample(&mut rng),
                0.0,
                nr.sample(&mut rng),
                nr.sample(&mut rng),
                nr.sample(&mut rng),
            ];
            let answer = after(&truth, &noise, &at);
            let estimate = m.accept(answer, &sigma, &m.predict().unwrap(), &at, 1.0, CAP_FPS);
            if k >= 30 {
                answers += answer.rotation_angle_to(&truth).powi(2);
                estimates += estimate.rotation_angle_to(&truth).powi(2);
            }
        }
        assert!(estimates < 0.5 * answers, "mean square rotation errors: estimates {estimates}, answers {answers}");
    }

    /// A sudden change of the motion (a part turned the other way within a frame): the
    /// estimate is the answer on that frame, not a lagging mix of it and the prediction,
    /// and the next frame's prediction follows the new motion.
    #[test]
    fn a_manoeuvre_is_taken_whole() {
        let at = Point3::new(0.2, 0.1, -0.3);
        let sigma = [Some(1e-4), Some(1e-4), Some(1e-4), Some(0.0), Some(1e-3), Some(1e-3), Some(1e-3)];
        let turn = |deg_per_frame: f64| {
            let r = deg_per_frame.to_radians();
            after(&Pose::identity(), &[0.0, 0.0, 0.0, 0.0, 0.6 * r, 0.0, 0.8 * r], &Point3::origin())
        };
        let mut truth = Pose::from_params(&[0.1, -0.2, 0.3, 1.0, 0.3, -0.2, 0.5]);
        let mut m = Motion::new();
        m.restart(truth, &sigma, 1.0, CAP_FPS);
        for k in 0..30 {
            // 0.5 deg a frame, then 1 deg a frame the other way.
            let step = if k < 20 { turn(0.5) } else { turn(-1.0) };
            truth = truth.compose(&step.inverse());
            let predicted = m.predict().unwrap();
            let estimate = m.accept(truth, &sigma, &predicted, &at, 1.0, CAP_FPS);
            let off = estimate.rotation_angle_to(&truth).to_degrees();
            assert!(off < 1e-6 || (k != 20 && off < 0.2), "frame {k}: the estimate is {off} deg off the answer");
        }
    }

    /// Another pose of a near-symmetric part (a carried alternative that became the
    /// answer): the filter starts again from it, with no velocity and the same spread.
    #[test]
    fn a_rebase_is_no_motion() {
        let at = Point3::new(0.2, 0.1, -0.3);
        let sigma = [Some(1e-3); 7];
        let step = after(&Pose::identity(), &[0.002, 0.0, 0.0, 0.0, 0.0, 0.01, 0.0], &Point3::origin());
        let mut pose = Pose::from_params(&[0.1, -0.2, 0.3, 1.0, 0.3, -0.2, 0.5]);
        let mut m = Motion::new();
        m.restart(pose, &sigma, 1.0, CAP_FPS);
        for _ in 0..5 {
            pose = pose.compose(&step.inverse());
            m.accept(pose, &sigma, &m.predict().unwrap(), &at, 1.0, CAP_FPS);
        }
        let spread = m.spread(1.0, false, CAP_FPS);
        // The part's other pose: turned 60 deg about the model's z axis.
        let g = after(&Pose::identity(), &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 60f64.to_radians()], &Point3::origin());
        let other = g.compose(&pose);
        m.rebase(other, &sigma, 1.0, CAP_FPS);
        let p = m.predict().unwrap();
        // (The angle between two rotations is read through an arccosine: 1e-6 rad is its
        // rounding, against the 0.01 rad a frame the part was turning.)
        assert!(p.rotation_angle_to(&other) < 1e-6 && (p.translation - other.translation).norm() < 1e-12);
        assert_eq!(m.spread(1.0, false, CAP_FPS), spread);
    }
}
