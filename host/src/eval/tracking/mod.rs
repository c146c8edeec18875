//! The tracking benchmark (`pficp eval --suite tracking`): [`crate::tracking::Tracker`] on
//! seeded sequences of a part moving in front of a depth camera ([`sequence`]).
//!
//! **Scoring**: a frame is right when its pose is within [`TOLERANCE`] of the truth (1 deg,
//! 1% of the diagonal at the scan's centroid, 1% of scale; an exactly symmetric shape
//! modulo its symmetries); confidently wrong when its verdict is `confident` and it is not
//! right. Per sequence: the share of frames right outside the hidden stretch and the
//! [`REACQUIRE_WINDOW`] frames after it, confidently wrong frames anywhere, frames after
//! the hidden stretch until the first right frame that holds the track again, the median
//! rotation error of the tracked frames, and the frames a second (the inverse of the
//! median frame time; tracked frames and all frames).
//!
//! **The single-frame floor**: per sequence, the median rotation error of a polish started
//! at the truth ([`FLOOR_ITERATIONS`] steps on the frame's scan, the tracked frames'
//! polish), over the frames that are not hidden. It is where one frame's objective has its
//! own minimum (noise, clutter close to the surface, the view's weak directions): no frame
//! answer is more accurate than it on that view, and the filter over the frames gets below
//! it only by averaging the frames' errors.
//!
//! **Shapes**: the `test` split runs the surgical and held-out shapes of [`TEST_SHAPES`]
//! (no setting was tuned on them), the `dev` split [`DEV_SHAPES`], each with its own seed.

pub mod sequence;

use crate::eval::realistic::{pose_errors, symmetric_truth, Shape, Split, Tolerance};
use crate::geometry::Pose;
use crate::nn::NearestNeighbours;
use crate::pf_icp::verdict::Verdict;
use crate::progress::Progress;
use crate::tracking::{TrackSettings, TrackState, Tracker};
use serde::Serialize;
use std::path::PathBuf;

/// A frame is right within 1 deg, 1% of the diagonal and 1% of scale (the tolerance a
/// frame's 95% region must lie within for it to be `confident`:
/// [`crate::tracking::verdict::TOLERANCE`]).
pub const TOLERANCE: Tolerance = {
    let [rotation_deg, translation_frac, scale_frac] = crate::tracking::verdict::TOLERANCE;
    Tolerance { rotation_deg, translation_frac, scale_frac }
};
/// Frames after the hidden stretch allowed for re-acquisition (not counted in the share
/// right).
pub const REACQUIRE_WINDOW: usize = 10;
/// The baud rates the board's frames a second are modelled at.
pub const BOARD_BAUDS: [u32; 2] = [3_000_000, 921_600];
/// Polish steps from the truth for the single-frame floor (converged: 10 more move the
/// dev split's medians by at most 0.003 deg).
pub const FLOOR_ITERATIONS: usize = 30;

/// The test split's shapes: two anatomical surfaces, a held-out scan, a held-out
/// near-symmetric part.
pub const TEST_SHAPES: [&str; 4] = ["dog_pelvis", "dog_vertebra", "armadillo", "flange-key"];
/// The dev split's shapes.
pub const DEV_SHAPES: [&str; 4] = ["dog_skull", "bunny", "fandisk", "near-cube-notch"];

/// What to run.
#[derive(Clone, Debug)]
pub struct TrackingOptions {
    /// Seed of the sequences (each sequence's is mixed from it, the split and its index).
    pub seed: u64,
    /// Shapes and seeds.
    pub split: Split,
    /// Frames per sequence (at most [`sequence::FRAMES`]; fewer cut the sequence short,
    /// the hidden stretch with it).
    pub frames: usize,
    /// Sequences (at most 4: one a shape).
    pub sequences: usize,
    /// The parts at scale 1 and the tracker told so (`--scale 1`: a metric camera and a
    /// model in the same units); else each part at a scale of its own, unknown to the
    /// tracker.
    pub metric: bool,
    /// Run each tracked frame's filter on the board (its bit-exact reference) and report
    /// the board's modelled frames a second ([`BOARD_BAUDS`]).
    pub board: bool,
    /// Register every `compare_register`-th tracked frame's scan from scratch too (the
    /// whole PF-ICP with the tracker's registration settings; 0: none), for
    /// [`SequenceReport::registered_median_rotation_deg`].
    pub compare_register: usize,
    /// The tracker's settings (the seed is replaced by each sequence's).
    pub settings: TrackSettings,
    /// Write `tracking.json`, `tracking.svg` and (feature `png`, on by default) `tracking.png` here.
    pub out_dir: Option<PathBuf>,
    /// Progress on stderr.
    pub progress: bool,
}

impl Default for TrackingOptions {
    fn default() -> Self {
        TrackingOptions {
            seed: 1,
            split: Split::Test,
            frames: sequence::FRAMES,
            sequences: 4,
            metric: true,
            board: false,
            compare_register: 0,
            settings: TrackSettings::default(),
            out_dir: None,
            progress: true,
        }
    }
}

/// One frame's record.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRecord {
    /// Frame index.
    pub frame: usize,
    /// The part is almost hidden.
    pub hidden: bool,
    /// Rotation error [deg], translation error [fraction of the diagonal], scale error.
    pub errors: [f64; 3],
    /// Within [`TOLERANCE`].
    pub right: bool,
    /// With the filter on the board: the board's pose alone (its filter's best, before the
    /// host's polish), its errors as `errors`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub board_errors: Option<[f64; 3]>,
    /// The verdict.
    pub verdict: Verdict,
    /// Its reasons.
    pub reasons: Vec<String>,
    /// One of the frame's alternatives is right.
    pub truth_in_alternatives: bool,
    /// The widest one-sigma rotation [deg], translation [fraction of the diagonal] and
    /// relative scale the verdict judged.
    pub widest_sigma: [f64; 3],
    /// The truth (its nearest symmetric pose) lies inside the frame's 95% region (`None`:
    /// no covariance to weigh it by).
    pub inside_95: Option<bool>,
    /// The track's state.
    pub state: TrackState,
    /// A global registration ran.
    pub global: bool,
    /// With [`TrackingOptions::compare_register`]: the errors of a registration from
    /// scratch of this frame's scan, as `errors`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub registered_errors: Option<[f64; 3]>,
    /// That registration's verdict.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub registered_verdict: Option<Verdict>,
    /// Wall time [s].
    pub seconds: f64,
}

/// One sequence's figures.
#[derive(Clone, Debug, Serialize)]
pub struct SequenceReport {
    /// `shape/seed`.
    pub id: String,
    /// Frames scored for the share right (outside the hidden stretch and the window after it).
    pub scored: usize,
    /// Of those, right.
    pub right: usize,
    /// Of those, right or honestly flagged (`unreliable`: a robot told not to act on the
    /// frame; or `ambiguous` with the truth among the alternatives), as the realistic
    /// benchmark counts them.
    pub right_or_flagged: usize,
    /// Of those, right and `confident` (a robot may act).
    pub confident_right: usize,
    /// Frames confidently wrong (anywhere).
    pub confidently_wrong: usize,
    /// Frames confident and off by more than the realistic benchmark's tolerance (2 deg, 2%
    /// of the diagonal, 1% of scale), the one the verdict's limits were set for.
    pub confidently_wrong_2deg: usize,
    /// Frames after the hidden stretch until the first right frame that holds the track
    /// (`None`: never within the sequence).
    pub reacquire_frames: Option<usize>,
    /// Median rotation error of the tracked frames [deg].
    pub median_rotation_deg: f64,
    /// The single-frame floor: the median rotation error of the polish started at the truth,
    /// over the frames not hidden [deg] (the module's doc).
    pub floor_rotation_deg: f64,
    /// Largest rotation error of the right-scored frames [deg].
    pub worst_scored_rotation_deg: f64,
    /// Frames a second: the inverse of the median time of a tracked frame.
    pub tracked_fps: f64,
    /// Median time of a tracked frame [s].
    pub tracked_median_seconds: f64,
    /// Frames a second over the whole sequence (global registrations included).
    pub overall_fps: f64,
    /// With the filter on the board: tracked frames a second at each of [`BOARD_BAUDS`],
    /// the inverse of the median of the board's modelled time (link and run) plus the
    /// host's measured part after the filter.
    pub board_fps: Option<[f64; 2]>,
    /// With the filter on the board: the median rotation error of the board's pose alone
    /// on the tracked frames [deg].
    pub board_median_rotation_deg: Option<f64>,
    /// With [`TrackingOptions::compare_register`]: the median rotation error of the frames
    /// registered from scratch, and of the same frames tracked [deg].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub registered_median_rotation_deg: Option<[f64; 2]>,
    /// Every frame.
    pub frames: Vec<FrameRecord>,
}

/// The benchmark's report.
#[derive(Clone, Debug, Serialize)]
pub struct TrackingReport {
    /// The seed.
    pub seed: u64,
    /// `dev` or `test`.
    pub split: &'static str,
    /// Parts at scale 1, the tracker told so.
    pub metric: bool,
    /// The tolerance of a right frame.
    pub tolerance: Tolerance,
    /// Per sequence.
    pub sequences: Vec<SequenceReport>,
}

/// The shapes of a split.
pub fn shapes(split: Split) -> Vec<Shape> {
    let names = match split {
        Split::Test => TEST_SHAPES,
        Split::Dev => DEV_SHAPES,
    };
    names
        .iter()
        .map(|n| {
            crate::real_shapes::all()
                .iter()
                .find(|s| s.name == *n)
                .map(Shape::Real)
                .or_else(|| crate::parts::Part::ALL.iter().find(|p| p.name() == *n).map(|&p| Shape::Part(p)))
                .expect("a known shape")
        })
        .collect()
}

/// The seed of sequence `index` of `split`.
pub fn sequence_seed(seed: u64, split: Split, index: usize) -> u64 {
    let split_code = match split {
        Split::Dev => 1,
        Split::Test => 2,
    };
    super::mix(super::mix(super::mix(seed, 0x0074_7261_636b), split_code), index as u64 + 1)
}

/// The errors of `pose` against the frame's truth modulo the shape's symmetries (the
/// nearest symmetric truth, returned with them), at the scan's centroid.
fn errors_of(seq: &sequence::Sequence, frame: &sequence::Frame, pose: &Pose) -> ([f64; 3], Pose) {
    let at = crate::cloud::centroid(&frame.scan);
    seq.shape
        .symmetries()
        .iter()
        .map(|g| {
            let t = symmetric_truth(&frame.truth, g, &seq.shape.centre());
            let e = pose_errors(pose, &t, &at, seq.diag);
            ([e.0, e.1, e.2], t)
        })
        .min_by(|a, b| a.0[0].total_cmp(&b.0[0]))
        .expect("the identity")
}

/// Score one sequence's frames.
fn score(seq: &sequence::Sequence, frames: &[crate::tracking::TrackFrame]) -> SequenceReport {
    let board_fps = {
        let on_board: Vec<&crate::tracking::TrackFrame> =
            frames.iter().filter(|f| f.state == TrackState::Tracking && f.board.is_some()).collect();
        (!on_board.is_empty()).then(|| {
            BOARD_BAUDS.map(|baud| {
                let t: Vec<f64> = on_board
                    .iter()
                    .filter_map(|f| f.board.as_ref().map(|b| b.seconds(baud) + f.host_seconds))
                    .collect();
                1.0 / crate::registration::icp::median(&t)
            })
        })
    };
    let records: Vec<FrameRecord> = frames
        .iter()
        .zip(&seq.frames)
        .map(|(f, truth)| {
            let at = crate::cloud::centroid(&truth.scan);
            let (errors, nearest) = errors_of(seq, truth, &f.pose);
            let inside_95 = crate::eval::realistic::mahalanobis2_of(&f.pose, &f.uncertainty, &nearest, &at)
                .map(|(d2, dof)| crate::eval::realistic::inside_95(d2, dof));
            let board_errors = f.board.as_ref().map(|b| errors_of(seq, truth, &b.pose).0);
            FrameRecord {
                frame: f.frame,
                board_errors,
                hidden: truth.hidden,
                errors,
                right: TOLERANCE.accepts((errors[0], errors[1], errors[2])),
                verdict: f.verdict,
                reasons: f.reasons.clone(),
                truth_in_alternatives: f.alternatives.iter().any(|a| {
                    let e = errors_of(seq, truth, a).0;
                    TOLERANCE.accepts((e[0], e[1], e[2]))
                }),
                widest_sigma: f.checks.widest_sigma,
                inside_95,
                state: f.state,
                global: f.global,
                registered_errors: None,
                registered_verdict: None,
                seconds: f.seconds,
            }
        })
        .collect();
    let hidden = sequence::HIDDEN;
    let after = hidden.end..hidden.end + REACQUIRE_WINDOW;
    let scored: Vec<&FrameRecord> =
        records.iter().filter(|r| !hidden.contains(&r.frame) && !after.contains(&r.frame)).collect();
    let holds = |r: &&FrameRecord| r.right && matches!(r.state, TrackState::Tracking | TrackState::Reacquired);
    let reacquire_frames =
        (records.len() > hidden.end).then(|| records[hidden.end..].iter().position(|r| holds(&r))).flatten();
    let tracked: Vec<&FrameRecord> = records.iter().filter(|r| r.state == TrackState::Tracking).collect();
    let median = |v: Vec<f64>| if v.is_empty() { f64::NAN } else { crate::registration::icp::median(&v) };
    let tracked_median_seconds = median(tracked.iter().map(|r| r.seconds).collect());
    let total: f64 = records.iter().map(|r| r.seconds).sum();
    SequenceReport {
        id: seq.id.clone(),
        scored: scored.len(),
        right: scored.iter().filter(|r| r.right).count(),
        right_or_flagged: scored
            .iter()
            .filter(|r| {
                r.right
                    || r.verdict == Verdict::Unreliable
                    || (r.verdict == Verdict::Ambiguous && r.truth_in_alternatives)
            })
            .count(),
        confident_right: scored.iter().filter(|r| r.right && r.verdict == Verdict::Confident).count(),
        confidently_wrong: records.iter().filter(|r| r.verdict == Verdict::Confident && !r.right).count(),
        confidently_wrong_2deg: records
            .iter()
            .filter(|r| {
                r.verdict == Verdict::Confident
                    && !crate::eval::realistic::TOLERANCE.accepts((r.errors[0], r.errors[1], r.errors[2]))
            })
            .count(),
        reacquire_frames,
        median_rotation_deg: median(tracked.iter().map(|r| r.errors[0]).collect()),
        floor_rotation_deg: f64::NAN,
        worst_scored_rotation_deg: scored.iter().map(|r| r.errors[0]).fold(0.0, f64::max),
        tracked_fps: 1.0 / tracked_median_seconds,
        tracked_median_seconds,
        overall_fps: records.len() as f64 / total.max(1e-300),
        board_fps,
        board_median_rotation_deg: {
            let e: Vec<f64> = tracked.iter().filter_map(|r| r.board_errors.map(|e| e[0])).collect();
            (!e.is_empty()).then(|| crate::registration::icp::median(&e))
        },
        registered_median_rotation_deg: None,
        frames: records,
    }
}

/// The single-frame floor of `seq` (the module's doc): the scale fixed at 1 when `metric`, else
/// free.
fn floor(seq: &sequence::Sequence, nn: &NearestNeighbours, metric: bool) -> f64 {
    let surface = crate::pf_icp::surface::Surface::new(nn);
    let bounds = if metric { crate::geometry::ScaleBounds::fixed(1.0) } else { crate::geometry::ScaleBounds::FREE };
    let errors: Vec<f64> = seq
        .frames
        .iter()
        .filter(|f| !f.hidden)
        .map(|f| {
            let polished = surface.polish_weighted(
                &f.scan,
                &f.truth,
                FLOOR_ITERATIONS,
                &bounds,
                crate::tracking::FRAME_BUDGET.polish_weights,
            );
            errors_of(seq, f, &polished).0[0]
        })
        .collect();
    if errors.is_empty() {
        f64::NAN
    } else {
        crate::registration::icp::median(&errors)
    }
}

/// Register every `every`-th tracked frame's scan from scratch (the registration settings
/// of `settings`, seeded by the sequence's `seed`, scale 1 fixed when `metric`) and record
/// its errors beside the tracked frame's.
fn compare_with_registration(
    seq: &sequence::Sequence,
    nn: &NearestNeighbours,
    settings: &TrackSettings,
    seed: u64,
    metric: bool,
    every: usize,
    report: &mut SequenceReport,
) {
    let mut registration = settings.registration.clone();
    registration.seed = seed;
    if metric {
        registration.scale = crate::geometry::ScaleBounds::fixed(1.0);
    }
    let chosen: Vec<usize> = report
        .frames
        .iter()
        .filter(|r| r.state == TrackState::Tracking && !r.hidden)
        .map(|r| r.frame)
        .step_by(every)
        .collect();
    let mut pairs = Vec::new();
    for k in chosen {
        let frame = &seq.frames[k];
        let r = crate::pf_icp::register(nn, &frame.scan, &registration);
        report.frames[k].registered_verdict = Some(r.conclusion.verdict);
        let e = errors_of(seq, frame, &r.registration.pose).0;
        report.frames[k].registered_errors = Some(e);
        pairs.push((e[0], report.frames[k].errors[0]));
    }
    if !pairs.is_empty() {
        let median = |v: Vec<f64>| crate::registration::icp::median(&v);
        report.registered_median_rotation_deg =
            Some([median(pairs.iter().map(|p| p.0).collect()), median(pairs.iter().map(|p| p.1).collect())]);
    }
}

/// Run the benchmark.
pub fn run(opts: &TrackingOptions) -> anyhow::Result<TrackingReport> {
    anyhow::ensure!(
        (1..=sequence::FRAMES).contains(&opts.frames),
        "--frames must be 1 to {} (got {})",
        sequence::FRAMES,
        opts.frames
    );
    let shapes = shapes(opts.split);
    anyhow::ensure!(
        (1..=shapes.len()).contains(&opts.sequences),
        "--sequences must be 1 to {} (got {})",
        shapes.len(),
        opts.sequences
    );
    let mut reports = Vec::new();
    for (index, shape) in shapes.into_iter().take(opts.sequences).enumerate() {
        let seed = sequence_seed(opts.seed, opts.split, index);
        let mut seq = sequence::sequence(shape, seed, opts.metric);
        seq.frames.truncate(opts.frames);
        let nn = NearestNeighbours::new(&seq.model);
        let mut settings = opts.settings.clone();
        settings.registration.seed = seed;
        settings.board_reference = opts.board;
        if opts.metric {
            settings.registration.scale = crate::geometry::ScaleBounds::fixed(1.0);
        }
        let mut tracker = Tracker::new(&nn, settings)?;
        let bar =
            opts.progress.then(|| Progress::bar(&format!("tracking {}", seq.id), seq.frames.len() as u64, "frames"));
        let mut frames = Vec::with_capacity(seq.frames.len());
        for (k, f) in seq.frames.iter().enumerate() {
            frames.push(tracker.update(&f.scan)?);
            if let Some(b) = &bar {
                b.set(k as u64 + 1);
            }
        }
        let mut report = score(&seq, &frames);
        report.floor_rotation_deg = floor(&seq, &nn, opts.metric);
        if opts.compare_register > 0 {
            compare_with_registration(&seq, &nn, &opts.settings, seed, opts.metric, opts.compare_register, &mut report);
        }
        if let Some(b) = bar {
            b.finish(format_args!("tracked {}: {}/{} frames right", seq.id, report.right, report.scored));
        }
        reports.push(report);
    }
    let report = TrackingReport {
        seed: opts.seed,
        split: opts.split.name(),
        metric: opts.metric,
        tolerance: TOLERANCE,
        sequences: reports,
    };
    if let Some(dir) = &opts.out_dir {
        std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("cannot create {}: {e}", dir.display()))?;
        let json = dir.join("tracking.json");
        std::fs::write(&json, serde_json::to_string_pretty(&report)?)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", json.display()))?;
        let series: Vec<(String, Vec<(f64, f64)>)> = report
            .sequences
            .iter()
            .map(|s| (s.id.clone(), s.frames.iter().map(|r| (r.frame as f64, r.errors[0])).collect()))
            .collect();
        let subtitle = format!(
            "{} split, seed {}; hidden frames {}..{}, a jump of {} deg in their middle",
            report.split,
            report.seed,
            sequence::HIDDEN.start,
            sequence::HIDDEN.end,
            sequence::JUMP_DEG
        );
        super::plots::tracking_figure(&dir.join("tracking.svg"), &subtitle, &series, TOLERANCE.rotation_deg)?;
        #[cfg(feature = "png")]
        super::plots::render_png(&dir.join("tracking.svg"), &dir.join("tracking.png"))?;
    }
    Ok(report)
}

impl TrackingReport {
    /// The table: one row a sequence.
    pub fn text(&self) -> String {
        let mut s = format!(
            "tracking benchmark, {} split, seed {}, {} (right: {} deg, {:.0}% of the diagonal, {:.0}% of scale)\n",
            self.split,
            self.seed,
            if self.metric { "scale known (1)" } else { "scale unknown" },
            self.tolerance.rotation_deg,
            100.0 * self.tolerance.translation_frac,
            100.0 * self.tolerance.scale_frac
        );
        s += &format!(
            "{:<34} {:>14} {:>9} {:>9} {:>10} {:>10} {:>9} {:>10} {:>10} {:>11} {:>11}\n",
            "sequence",
            "right",
            "or flag.",
            "conf.right",
            "conf.wrong",
            "(at 2 deg)",
            "reacquire",
            "median deg",
            "floor deg",
            "tracked fps",
            "overall fps"
        );
        for q in &self.sequences {
            s += &format!(
                "{:<34} {:>4}/{:<4} {:>4.0}% {:>8.0}% {:>8.0}% {:>10} {:>10} {:>9} {:>10.3} {:>10.3} {:>11.1} {:>11.1}\n",
                q.id,
                q.right,
                q.scored,
                100.0 * q.right as f64 / q.scored.max(1) as f64,
                100.0 * q.right_or_flagged as f64 / q.scored.max(1) as f64,
                100.0 * q.confident_right as f64 / q.scored.max(1) as f64,
                q.confidently_wrong,
                q.confidently_wrong_2deg,
                q.reacquire_frames.map_or("never".to_string(), |n| n.to_string()),
                q.median_rotation_deg,
                q.floor_rotation_deg,
                q.tracked_fps,
                q.overall_fps
            );
        }
        for q in &self.sequences {
            if let Some([registered, tracked]) = q.registered_median_rotation_deg {
                let from_scratch: Vec<&FrameRecord> =
                    q.frames.iter().filter(|r| r.registered_errors.is_some()).collect();
                let confident_wrong = from_scratch
                    .iter()
                    .filter(|r| {
                        r.registered_verdict == Some(Verdict::Confident)
                            && !r.registered_errors.is_some_and(|e| TOLERANCE.accepts((e[0], e[1], e[2])))
                    })
                    .count();
                s += &format!(
                    "{:<34} {} tracked frames registered from scratch: median rotation error {registered:.3} deg \
                     (tracked {tracked:.3}), {confident_wrong} of them confident beyond the tracking tolerance\n",
                    q.id,
                    from_scratch.len()
                );
            }
        }
        for q in self.sequences.iter().filter(|q| q.board_fps.is_some()) {
            let [a, b] = q.board_fps.unwrap_or_default();
            s += &format!(
                "{:<34} board (its filter by its bit-exact reference, the host's polish and checks): {:.1} frames/s \
                 at {} baud, {:.1} at {}; the board's pose alone {:.3} deg median\n",
                q.id,
                a,
                BOARD_BAUDS[0],
                b,
                BOARD_BAUDS[1],
                q.board_median_rotation_deg.unwrap_or(f64::NAN)
            );
        }
        s
    }
}
