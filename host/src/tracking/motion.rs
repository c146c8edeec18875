//! The tracker's motion model: constant velocity of the part in the camera's frame, and
//! a spread that follows how far the frames' answers land from the predictions.
//!
//! A registration pose `T` maps the scan (the camera's frame) onto the model, so the part
//! sits in the camera's frame at `M = T^-1`. With the last two answers `M_1` (the newer)
//! and `M_2`, the part moved by `D = M_1 M_2^-1` in one frame; the prediction is
//! `D M_1`, that is `T = T_1 T_2^-1 T_1` (the same scale as the answers: a rigid part).
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

/// Constant velocity with a measured spread.
#[derive(Clone, Debug)]
pub struct Motion {
    /// The last two answers the track holds (scan to model), the newest first.
    last: Option<Pose>,
    previous: Option<Pose>,
    /// Running mean square innovation per [`LocalDelta`] parameter.
    mean_square: [f64; 7],
}

impl Motion {
    /// No answer yet: no prediction.
    pub fn new() -> Self {
        Motion { last: None, previous: None, mean_square: [0.0; 7] }
    }

    /// Start again from `pose` with no velocity (a new or re-acquired track).
    pub fn restart(&mut self, pose: Pose) {
        *self = Motion { last: Some(orthonormal(&pose)), previous: None, mean_square: [0.0; 7] };
    }

    /// The newest answer the track holds.
    pub fn last(&self) -> Option<Pose> {
        self.last
    }

    /// The pose predicted for the next frame (`None` before the first answer).
    pub fn predict(&self) -> Option<Pose> {
        let last = self.last?;
        Some(orthonormal(&match self.previous {
            Some(previous) => last.compose(&previous.inverse()).compose(&last),
            None => last,
        }))
    }

    /// Take the frame's answer `pose`, which was predicted as `predicted`, `at` the image of
    /// the scan's centroid. (The answer is taken whole: an alpha-beta filter taking half the
    /// innovation changed the dev sequence's median error from 0.735 to 0.743 deg; the
    /// frames' errors are the view's bias, not noise from frame to frame.)
    pub fn accept(&mut self, pose: Pose, predicted: &Pose, at: &Point3<f64>) {
        let innovation = delta_between(predicted, &pose, at);
        for (m, d) in self.mean_square.iter_mut().zip(innovation) {
            *m = (1.0 - INNOVATION_MEMORY) * *m + INNOVATION_MEMORY * d * d;
        }
        self.previous = self.last;
        self.last = Some(orthonormal(&pose));
    }

    /// Standard deviations of the next frame's prior per [`LocalDelta`] parameter, for a
    /// model of diagonal `diag` at `fps` frames a second (the scale's 0 when `scale_fixed`).
    pub fn spread(&self, diag: f64, scale_fixed: bool, fps: f64) -> [f64; 7] {
        let bound =
            |k: usize, floor: f64, cap: f64| (SPREAD_GAIN * self.mean_square[k].sqrt()).clamp(floor, cap.max(floor));
        let (tf, sf, rf) = SPREAD_FLOOR;
        let per_frame = CAP_FPS / fps;
        let (tc, sc, rc) = (SPREAD_CAP.0 * per_frame, SPREAD_CAP.1, SPREAD_CAP.2 * per_frame);
        let mut s = [0.0; 7];
        for k in 0..3 {
            s[k] = bound(k, tf * diag, tc * diag);
            s[k + 4] = bound(k + 4, rf.to_radians(), rc.to_radians());
        }
        s[3] = if scale_fixed { 0.0 } else { bound(3, sf, sc) };
        s
    }
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
        let mut m = Motion::new();
        assert!(m.predict().is_none());
        m.restart(poses[0]);
        m.accept(poses[1], &poses[0], &at);
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
            m.accept(*pose, &m.predict().unwrap(), &at);
        }
        let s = m.spread(1.0, true, CAP_FPS);
        assert_eq!(s[3], 0.0);
        assert!(s[4] >= SPREAD_FLOOR.2.to_radians() && s[4] < 2.0 * SPREAD_GAIN * 0.02);
        // A jump far beyond the cap: the spread stops at the cap, twice as wide at half the
        // frame rate (twice the time between frames).
        let far = after(&poses[3], &[0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0], &at);
        m.accept(far, &m.predict().unwrap(), &at);
        let (at30, at15) = (m.spread(1.0, true, CAP_FPS), m.spread(1.0, true, CAP_FPS / 2.0));
        assert!((at30[5] - SPREAD_CAP.2.to_radians()).abs() < 1e-12, "{at30:?}");
        assert!((at15[5] - 2.0 * at30[5]).abs() < 1e-12 && (at15[0] - 2.0 * at30[0]).abs() < 1e-12);
    }
}
