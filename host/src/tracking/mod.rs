//! Tracking: the pose of a moving part frame after frame ([`Tracker`], one
//! [`Tracker::update`] a frame), the particle filter carried from one frame to the next.
//!
//! - **Acquiring**: the first frame, and every frame while no track is held, is a global
//!   registration ([`crate::pf_icp::register`], the whole PF-ICP with its verdict). A result
//!   that is not `unreliable` starts the track.
//! - **Tracking**: every other frame starts from the track's estimate moved by the constant
//!   velocity of [`motion`], with a spread that follows the measured innovations; a short
//!   filter and one short polish ([`local`], [`FrameBudget`]), then the cheap checks; the
//!   frame's answer is then weighed against the prediction ([`motion::Motion::accept`]).
//! - **Lost**: a tracked frame that does not [`holds`] (the part hidden, a scan of something
//!   else, a jump beyond the spread) does not move the track: the answer is reported with
//!   its verdict, the state is `lost`, and the track keeps its last good pose.
//! - **Reacquired**: while lost, each frame first tries a wide local search about the last
//!   good pose ([`REACQUIRE_SPREAD`], [`REACQUIRE_BUDGET`]), then a global registration;
//!   the first that holds re-starts the track with no velocity.
//! - **Scale**: a rigid part does not change size. With `--scale` the scale is fixed
//!   throughout; otherwise the first [`SCALE_FRAMES`] tracked frames estimate it within
//!   [`SCALE_SETTLING`] of the acquisition's (and the user's `--scale-range`), and from
//!   then on it is fixed at their median, for re-acquisitions as well.
//! - **Ambiguity**: a near-symmetric part's alternatives at acquisition are carried as
//!   model-frame maps, polished and weighed on every frame; one the frames come to prefer
//!   becomes the answer, one that falls behind is dropped, each by the evidence summed over
//!   the frames ([`alternatives`]). A track acquired `ambiguous`
//!   stays at best `ambiguous` on every frame until a global registration (after a loss)
//!   is `confident`: on the benchmark's near-symmetric flange the per-frame test dropped
//!   the truth and the track slid along the part's near-symmetry while its frames said
//!   `confident`.
//! - **Verdict**: a frame is `confident` only when 95% of the errors its covariance
//!   describes lie within the tracking tolerance of 1 deg, 1% of the diagonal and 1% of
//!   scale ([`verdict`]); the track's hold ([`holds`]) keeps a registration's rules.

pub mod alternatives;
pub mod board;
pub mod local;
pub mod motion;
pub mod verdict;

use crate::board::{BoardClient, BoardError, BOARD_MAX_STORE_POINTS};
use crate::geometry::{Pose, ScaleBounds};
use crate::nn::NearestNeighbours;
use crate::pf_icp::conclusion::{Fit, Uncertainty};
use crate::pf_icp::evidence::Evidence;
use crate::pf_icp::surface::{Surface, Weights};
use crate::pf_icp::verdict::{Checks, Verdict};
use crate::pf_icp::{register, PfIcpSettings};
pub use local::FrameBudget;
use motion::{LocalDelta, Motion};
use nalgebra::Point3;
use serde::Serialize;
use std::time::Instant;

/// A tracked frame's work: 16 particles, 3 iterations on 150 scan points, 10 polish
/// iterations on 1,000 (4 on 500 gave 62 of the dev sequence's first 100 frames right
/// against 78, at 2.9 against 4.7 ms a frame), the inliers weighed by Tukey's biweight so
/// that clutter in front of the part (a tool held against it) pulls less than the part's
/// surface (on the dev split, seeds 1 to 3: dog_skull's frames right 218, 82, 220 -> 248,
/// 178, 246 of 260; docs/tracking.md).
pub const FRAME_BUDGET: FrameBudget = FrameBudget {
    particles: 16,
    iterations: 3,
    weight_points: 150,
    polish_points: 1000,
    polish_iterations: 10,
    polish_weights: Weights::Biweight,
};
/// A lost track's local search about its last good pose. Its polish weighs the inliers
/// alike, as the registration's does: from a start up to the spread away the biweight's
/// basin is narrower (with it, dev seed 2's near-cube-notch was not found again after
/// its jump).
pub const REACQUIRE_BUDGET: FrameBudget = FrameBudget {
    particles: 64,
    iterations: 8,
    weight_points: 200,
    polish_points: 1000,
    polish_iterations: 10,
    polish_weights: Weights::Equal,
};
/// Its spread: translation [fraction of the diagonal], relative scale, rotation [deg].
pub const REACQUIRE_SPREAD: (f64, f64, f64) = (0.05, 0.02, 10.0);
/// Tracked frames that settle the scale before it is fixed.
pub const SCALE_FRAMES: usize = 10;
/// While the scale settles it stays within this relative distance of the acquisition's.
pub const SCALE_SETTLING: f64 = 0.05;
/// How much wider than the verdict's limits a one-sigma may be for a frame to hold the
/// track ([`holds`]). (Starting a track on any one-sigma up to 3 times the limits let a
/// hidden part's wrong pose start one; losing the track on every frame a hair over the
/// limits made it flicker between lost and reacquired.)
pub const HOLD_SIGMA_FACTOR: f64 = 3.0;
/// Default frame rate [Hz].
pub const DEFAULT_FPS: f64 = 30.0;
/// Most frames a second a tracker takes (`--fps`).
pub const MAX_FPS: f64 = 10_000.0;
/// Fewest points a frame needs.
pub const MIN_FRAME_POINTS: usize = 10;

/// Refuse a frame rate the tracker cannot take (`--fps`), with one line naming the flag.
pub fn check_fps(fps: f64) -> anyhow::Result<()> {
    anyhow::ensure!(
        fps.is_finite() && fps > 0.0 && fps <= MAX_FPS,
        "--fps must be a number above 0 and at most {MAX_FPS} (got {fps})"
    );
    Ok(())
}

/// The track's state after a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TrackState {
    /// No track held yet: the frame ran a global registration.
    Acquiring,
    /// The frame updated a held track.
    Tracking,
    /// The track is lost: do not act on the frame's pose.
    Lost,
    /// The frame found a lost track again.
    Reacquired,
}

impl TrackState {
    /// `acquiring`, `tracking`, `lost` or `reacquired`.
    pub fn name(self) -> &'static str {
        match self {
            TrackState::Acquiring => "acquiring",
            TrackState::Tracking => "tracking",
            TrackState::Lost => "lost",
            TrackState::Reacquired => "reacquired",
        }
    }
}

/// Tracker settings.
#[derive(Clone, Debug)]
pub struct TrackSettings {
    /// The global registrations' settings: seed, `scale` (the user's bounds), viewpoint.
    pub registration: PfIcpSettings,
    /// Frames a second: the time between frames, over which the prior's widest spread
    /// grows ([`motion::SPREAD_CAP`] is given at 30).
    pub fps: f64,
    /// A tracked frame's work.
    pub budget: FrameBudget,
    /// Run each tracked frame's filter on the board, by its bit-exact reference
    /// ([`board`]): the board's pose, its link bytes and clocks in [`TrackFrame::board`].
    pub board_reference: bool,
}

impl Default for TrackSettings {
    fn default() -> Self {
        TrackSettings {
            registration: PfIcpSettings::default(),
            fps: DEFAULT_FPS,
            budget: FRAME_BUDGET,
            board_reference: false,
        }
    }
}

/// One frame's answer.
#[derive(Clone, Debug)]
pub struct TrackFrame {
    /// Frame index from 0.
    pub frame: usize,
    /// The frame's pose (scan to model).
    pub pose: Pose,
    /// Its uncertainty.
    pub uncertainty: Uncertainty,
    /// Its fit.
    pub fit: Fit,
    /// What the verdict was judged on.
    pub checks: Checks,
    /// The verdict on this frame's pose.
    pub verdict: Verdict,
    /// The verdict's reasons.
    pub reasons: Vec<String>,
    /// Other poses that fit as well.
    pub alternatives: Vec<Pose>,
    /// The track's state after the frame.
    pub state: TrackState,
    /// Whether the frame ran a global registration.
    pub global: bool,
    /// Wall time of the frame [s].
    pub seconds: f64,
    /// A tracked frame's filter on the board (with [`TrackSettings::board_reference`]).
    pub board: Option<board::BoardFrame>,
    /// A tracked frame's host part after the filter [s] (0 for a global registration).
    pub host_seconds: f64,
}

/// What the track knows of the scale.
#[derive(Clone, Debug)]
struct Scale {
    /// The user's bounds.
    user: ScaleBounds,
    /// The bounds the frames work within.
    working: ScaleBounds,
    /// Tracked frames' scales while it settles.
    settling: Vec<f64>,
}

/// Whether a frame's checks hold the track: the verdict's rules, except that while the
/// scale settles its one-sigma may be up to [`HOLD_SIGMA_FACTOR`] times the verdict's
/// limit, and that a held track (`holding`) keeps a frame whose rotation and translation
/// one-sigma are within [`HOLD_SIGMA_FACTOR`] times theirs (the frame's own verdict stays
/// the strict one; a loosely determined frame must not start a track, nor lose one).
pub fn holds(c: &Checks, scale_settling: bool, holding: bool) -> bool {
    use crate::pf_icp::verdict::{judge, MAX_SIGMA_DEG, MAX_SIGMA_DIAG, MAX_SIGMA_SCALE};
    let mut relaxed = c.clone();
    let [deg, diag, scale] = relaxed.widest_sigma;
    if scale_settling && scale <= HOLD_SIGMA_FACTOR * MAX_SIGMA_SCALE {
        relaxed.widest_sigma[2] = 0.0;
    }
    if holding && deg <= HOLD_SIGMA_FACTOR * MAX_SIGMA_DEG && diag <= HOLD_SIGMA_FACTOR * MAX_SIGMA_DIAG {
        relaxed.widest_sigma[0] = 0.0;
        relaxed.widest_sigma[1] = 0.0;
    }
    judge(&relaxed).0 != Verdict::Unreliable
}

/// A tracker of one model over consecutive scans.
pub struct Tracker<'a> {
    surface: Surface<'a>,
    board: Option<board::BoardModel>,
    /// The board the tracked frames' filters run on (with [`Tracker::on_board`]).
    client: Option<&'a mut BoardClient>,
    settings: TrackSettings,
    diag: f64,
    motion: Motion,
    frames: usize,
    held: bool,
    ever_held: bool,
    evidence: Option<Evidence>,
    /// The carried alternatives.
    symmetries: Vec<alternatives::Carried>,
    /// The track was acquired `ambiguous`: its frames are at best `ambiguous` until a
    /// global registration is `confident` again.
    ambiguous: bool,
    scale: Scale,
}

impl<'a> Tracker<'a> {
    /// A tracker of the model behind `nn`; with [`TrackSettings::board_reference`] a model
    /// the board refuses is an error.
    pub fn new(nn: &'a NearestNeighbours, settings: TrackSettings) -> Result<Self, BoardError> {
        let user = settings.registration.scale;
        let board = match settings.board_reference {
            true => Some(board::BoardModel::new(nn.points(), settings.registration.seed, BOARD_MAX_STORE_POINTS)?),
            false => None,
        };
        Ok(Tracker {
            surface: Surface::new(nn),
            board,
            client: None,
            diag: crate::cloud::bbox_diagonal(nn.points()),
            settings,
            motion: Motion::new(),
            frames: 0,
            held: false,
            ever_held: false,
            evidence: None,
            symmetries: Vec::new(),
            ambiguous: false,
            scale: Scale { user, working: user, settling: Vec::new() },
        })
    }

    /// A tracker whose tracked frames run their filter on the board behind `client`
    /// (protocol 7): the model put on it now unless it holds it already (true in the
    /// second value when it was uploaded). The global registrations stay on the host.
    pub fn on_board(
        nn: &'a NearestNeighbours,
        settings: TrackSettings,
        client: &'a mut BoardClient,
    ) -> Result<(Self, bool), BoardError> {
        let id = client.identify()?;
        let max = (id.max_model as usize).min(BOARD_MAX_STORE_POINTS);
        let mut model = board::BoardModel::new(nn.points(), settings.registration.seed, max)?;
        let uploaded = model.ensure_on(client)?;
        let mut tracker = Tracker::new(nn, TrackSettings { board_reference: false, ..settings })?;
        tracker.board = Some(model);
        tracker.client = Some(client);
        Ok((tracker, uploaded))
    }

    /// The model as the board holds it (with the filter on the board or its reference).
    pub fn board_model(&self) -> Option<&board::BoardModel> {
        self.board.as_ref()
    }

    /// Frames seen so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The scale the track holds fixed, once settled.
    pub fn fixed_scale(&self) -> Option<f64> {
        self.scale.working.fixed_value()
    }

    /// Take the next frame's scan (at least a few points; the caller validates it). Only a
    /// board's failure is an error (the track is kept: the next frame may try again).
    pub fn update(&mut self, scan: &[Point3<f64>]) -> Result<TrackFrame, BoardError> {
        let t0 = Instant::now();
        let index = self.frames;
        self.frames += 1;
        let seed = self.settings.registration.seed ^ (index as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        let mut frame = if self.held { self.tracked(scan, seed)? } else { self.find(scan, seed)? };
        frame.frame = index;
        frame.seconds = t0.elapsed().as_secs_f64();
        Ok(frame)
    }

    /// A held track's frame.
    fn tracked(&mut self, scan: &[Point3<f64>], seed: u64) -> Result<TrackFrame, BoardError> {
        let predicted = self.motion.predict().expect("a held track has an answer");
        let spread = self.motion.spread(self.diag, self.scale.working.fixed_value().is_some(), self.settings.fps);
        let budget = self.settings.budget;
        let local = self.local(scan, &predicted, &spread, &budget, seed)?;
        if !holds(&local.checks, self.settling(), true) {
            self.held = false;
            return Ok(self.frame_of(local, TrackState::Lost, false));
        }
        let centroid = crate::cloud::centroid(scan);
        let at = predicted.apply(&centroid);
        let measured = local.pose;
        let (sigma, fps) = (&local.uncertainty.sigma, self.settings.fps);
        // (A carried alternative that became the answer is another pose of the part, not a
        // motion: the filter starts again from it.)
        let estimate = if local.swapped {
            self.motion.rebase(measured, sigma, self.diag, fps);
            measured
        } else {
            self.motion.accept(measured, sigma, &predicted, &at, self.diag, fps)
        };
        let mut local = local;
        // (Within the track's scale bounds: a fixed scale stays fixed.)
        local.pose = self.scale.working.apply(&estimate, &centroid);
        self.symmetries = local.alternatives.clone();
        self.settle_scale(measured.scale);
        Ok(self.frame_of(local, TrackState::Tracking, false))
    }

    /// A frame without a held track: the wide local search about the last good pose,
    /// then a global registration.
    fn find(&mut self, scan: &[Point3<f64>], seed: u64) -> Result<TrackFrame, BoardError> {
        if let (Some(last), Some(_)) = (self.motion.last(), self.evidence) {
            let (t, s, r) = REACQUIRE_SPREAD;
            let (t, r) = (t * self.diag, r.to_radians());
            let s = if self.scale.working.fixed_value().is_some() { 0.0 } else { s };
            let local = self.local(scan, &last, &[t, t, t, s, r, r, r], &REACQUIRE_BUDGET, seed)?;
            if holds(&local.checks, self.settling(), false) {
                self.hold(local.pose, &local.uncertainty.sigma, local.alternatives.clone());
                return Ok(self.frame_of(local, TrackState::Reacquired, false));
            }
        }
        let mut settings = PfIcpSettings { scale: self.scale.working, seed, ..self.settings.registration.clone() };
        // The rescue search (`crate::pf_icp::rescue`, unless the user turned it off) only
        // before the first track: a view the first search misses is missed on the next
        // frames as well (the test split's armadillo: its first 8 frames, 5 with the rescue),
        // while a lost track's frames are mostly a hidden part, which no search finds, and
        // the next frame is a camera period away.
        if let Some(search) = &mut settings.search {
            search.rescue &= !self.ever_held;
        }
        let r = register(self.surface.nn(), scan, &settings);
        let c = r.conclusion;
        let held = holds(&c.checks, self.scale.user.fixed_value().is_none(), false);
        let state = match (held, self.ever_held) {
            (true, true) => TrackState::Reacquired,
            (false, true) => TrackState::Lost,
            (_, false) => TrackState::Acquiring,
        };
        if held {
            self.evidence = Some(Evidence::new(&self.surface, scan, c.pose.scale, settings.viewpoint));
            // (The track carries every alternative, those that fit as well and those only
            // not ruled out: the frames' evidence decides, `alternatives`.)
            let maps =
                c.alternatives.iter().map(|a| alternatives::Carried::new(a.pose.compose(&c.pose.inverse()))).collect();
            if self.scale.working.fixed_value().is_none() {
                let s = c.pose.scale;
                self.scale.working = self.scale.user.within(s * (1.0 - SCALE_SETTLING), s * (1.0 + SCALE_SETTLING));
                self.scale.settling.clear();
            }
            self.hold(c.pose, &c.uncertainty.sigma, maps);
            // (Poses that fit as well make the track ambiguous whatever the verdict: one
            // held while its scale settles may be `unreliable` with alternatives.)
            self.ambiguous = c.verdict == Verdict::Ambiguous || c.checks.alternatives > 0;
        }
        let (verdict, reasons) = verdict::frame_verdict(&c.checks, &c.uncertainty, self.diag);
        Ok(TrackFrame {
            frame: 0,
            pose: c.pose,
            uncertainty: c.uncertainty,
            fit: c.fit,
            checks: c.checks,
            verdict,
            reasons,
            alternatives: c.alternatives.iter().map(|a| a.pose).collect(),
            state,
            global: true,
            seconds: 0.0,
            board: None,
            host_seconds: 0.0,
        })
    }

    /// Whether the scale is still settling (free and not fixed yet).
    fn settling(&self) -> bool {
        self.scale.working.fixed_value().is_none()
    }

    /// Start (or re-start) the track at `pose` (one-sigma `sigma`) with no velocity known.
    fn hold(&mut self, pose: Pose, sigma: &[Option<f64>; 7], symmetries: Vec<alternatives::Carried>) {
        self.held = true;
        self.ever_held = true;
        self.motion.restart(pose, sigma, self.diag, self.settings.fps);
        self.symmetries = symmetries;
    }

    /// A tracked frame's scale while the scale settles; fixed at the median after
    /// [`SCALE_FRAMES`].
    fn settle_scale(&mut self, s: f64) {
        if self.scale.working.fixed_value().is_some() {
            return;
        }
        self.scale.settling.push(s);
        if self.scale.settling.len() >= SCALE_FRAMES {
            let median = crate::registration::icp::median(&self.scale.settling);
            self.scale.working = ScaleBounds::fixed(self.scale.user.clamp(median));
        }
    }

    fn local(
        &mut self,
        scan: &[Point3<f64>],
        predicted: &Pose,
        spread: &LocalDelta,
        budget: &FrameBudget,
        seed: u64,
    ) -> Result<local::Local, BoardError> {
        let evidence = self.evidence.expect("a track has the acquisition's evidence");
        let predicted = self.scale.working.apply(predicted, &crate::cloud::centroid(scan));
        let filter = match (&self.board, &mut self.client) {
            (Some(b), Some(c)) => local::FrameFilter::Board(b, c, crate::board::DEFAULT_POLL),
            (Some(b), None) => local::FrameFilter::BoardReference(b),
            _ => local::FrameFilter::Host,
        };
        local::track_frame(
            &self.surface,
            scan,
            &predicted,
            spread,
            &self.scale.working,
            &self.scale.user,
            &evidence,
            &self.symmetries,
            budget,
            1.0 / self.settings.fps,
            seed,
            filter,
        )
    }

    fn frame_of(&self, local: local::Local, state: TrackState, global: bool) -> TrackFrame {
        let mut local = local;
        (local.verdict, local.reasons) = verdict::frame_verdict(&local.checks, &local.uncertainty, self.diag);
        if self.ambiguous && local.verdict == Verdict::Confident {
            // (The carried alternatives are weighed on one frame's view; a near-symmetric
            // part's flip can win that test by clutter or bias, and a track can slide along
            // a near-symmetry: only a global registration clears the doubt.)
            local.verdict = Verdict::Ambiguous;
            local.reasons.push("the track was acquired ambiguous and has not been confirmed since".to_string());
        }
        TrackFrame {
            frame: 0,
            pose: local.pose,
            alternatives: local.alternatives.iter().map(|g| g.map.compose(&local.pose)).collect(),
            uncertainty: local.uncertainty,
            fit: local.fit,
            checks: local.checks,
            verdict: local.verdict,
            reasons: local.reasons,
            state,
            global,
            seconds: 0.0,
            board: local.board,
            host_seconds: local.host_seconds,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::realistic::{pose_errors, Shape};
    use crate::eval::tracking::sequence::sequence;
    use rand::{Rng, SeedableRng};

    /// A part moving smoothly is acquired, then tracked frame by frame; a scan of something
    /// else loses the track (never a confident pose); the part seen again is re-acquired.
    /// The same seed gives the same poses.
    #[test]
    fn a_track_is_held_lost_on_a_foreign_scan_and_reacquired() {
        let bunny = crate::real_shapes::all().iter().find(|s| s.name == "bunny").expect("the bunny");
        let seq = sequence(Shape::Real(bunny), 5, true);
        let nn = NearestNeighbours::new(&seq.model);
        let settings = TrackSettings {
            registration: PfIcpSettings { scale: ScaleBounds::fixed(1.0), seed: 5, ..Default::default() },
            ..Default::default()
        };
        let mut tracker = Tracker::new(&nn, settings.clone()).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let (lo, hi) = crate::cloud::bbox(&seq.frames[0].scan);
        let foreign: Vec<Point3<f64>> = (0..800)
            .map(|_| Point3::new(rng.gen_range(lo.x..hi.x), rng.gen_range(lo.y..hi.y), rng.gen_range(lo.z..hi.z)))
            .collect();
        let error = |k: usize, f: &TrackFrame| {
            let at = crate::cloud::centroid(&seq.frames[k].scan);
            pose_errors(&f.pose, &seq.frames[k].truth, &at, seq.diag)
        };
        let mut frames = Vec::new();
        for k in 0..40 {
            let scan = if (26..29).contains(&k) { &foreign } else { &seq.frames[k].scan };
            frames.push(tracker.update(scan).unwrap());
        }
        // Never a confident pose that is wrong (at the tracking tolerance).
        for (k, f) in frames.iter().enumerate() {
            let e = error(k, f);
            let [deg, diag, _] = verdict::TOLERANCE;
            assert!(f.verdict != Verdict::Confident || (e.0 < deg && e.1 < diag), "frame {k}: {e:?}");
        }
        // The track starts on the last acquiring frame before the first tracked one.
        let first_tracked = frames.iter().position(|f| f.state == TrackState::Tracking).expect("a tracked frame");
        let acquired = first_tracked.checked_sub(1).expect("acquired first");
        assert!(acquired < 12, "acquired at frame {acquired}");
        assert!(frames[..=acquired].iter().all(|f| f.global && f.state == TrackState::Acquiring));
        let tracked: Vec<usize> = (acquired + 1..26).filter(|&k| frames[k].state == TrackState::Tracking).collect();
        assert!(10 * tracked.len() >= 9 * (25 - acquired), "{} of {} frames tracked", tracked.len(), 25 - acquired);
        for &k in &tracked {
            let e = error(k, &frames[k]);
            assert!(e.0 < 2.0 && e.1 < 0.02, "frame {k}: {e:?}");
            assert!(!frames[k].global);
        }
        for f in &frames[26..29] {
            assert_eq!(f.state, TrackState::Lost, "frame {}", f.frame);
            assert_eq!(f.verdict, Verdict::Unreliable, "frame {}", f.frame);
        }
        let back = (29..40).find(|&k| frames[k].state == TrackState::Reacquired).expect("re-acquired");
        assert!(back <= 31, "re-acquired at frame {back}");
        let e = error(back, &frames[back]);
        assert!(e.0 < 2.0 && e.1 < 0.02, "re-acquired at frame {back}: {e:?}");
        // The same seed, the same poses.
        let mut again = Tracker::new(&nn, settings).unwrap();
        for (k, f) in frames.iter().enumerate().take(4) {
            assert_eq!(again.update(&seq.frames[k].scan).unwrap().pose, f.pose, "frame {k}");
        }
    }

    /// A near-symmetric part whose view never shows what breaks its symmetry (the dev
    /// split's near-cube-notch at seed 1: the notch outside the exposed region): the poses
    /// that fit as well stay among the frames' alternatives, so an `ambiguous` frame that is
    /// wrong lists the truth. A test of each frame alone dropped the truth at frame 107
    /// ([`alternatives`]).
    #[test]
    fn a_near_symmetric_track_keeps_the_truth_among_its_alternatives() {
        use crate::eval::realistic::Split;
        let seed = crate::eval::tracking::sequence_seed(1, Split::Dev, 3);
        let seq = sequence(Shape::Part(crate::parts::Part::NearCubeNotch), seed, true);
        let nn = NearestNeighbours::new(&seq.model);
        let settings = TrackSettings {
            registration: PfIcpSettings { scale: ScaleBounds::fixed(1.0), seed, ..Default::default() },
            ..Default::default()
        };
        let mut tracker = Tracker::new(&nn, settings).unwrap();
        let [deg, diag, _] = verdict::TOLERANCE;
        let right = |k: usize, p: &Pose| {
            let at = crate::cloud::centroid(&seq.frames[k].scan);
            let e = pose_errors(p, &seq.frames[k].truth, &at, seq.diag);
            e.0 < deg && e.1 < diag
        };
        let mut listed = 0;
        for k in 0..crate::eval::tracking::sequence::HIDDEN.start {
            let f = tracker.update(&seq.frames[k].scan).unwrap();
            assert!(f.verdict != Verdict::Confident || right(k, &f.pose), "frame {k}: confidently wrong");
            if f.verdict == Verdict::Ambiguous && !right(k, &f.pose) {
                assert!(
                    f.alternatives.iter().any(|a| right(k, a)),
                    "frame {k}: the truth is not among the alternatives"
                );
                listed += 1;
            }
        }
        // (The test means something only if the track holds a wrong pose beside the truth.)
        assert!(listed >= 50, "{listed} ambiguous wrong frames");
    }
}
