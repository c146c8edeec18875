//! A tracked frame's filter and polish on the board, by the board's bit-exact reference,
//! and the board's time for it (the model resident).
//!
//! **What crosses the link a frame**: the frame's scan sample (normalised, quantised, in
//! the Morton order of its cells; LoadScan requests of at most
//! [`pficp_fpga::protocol::messages::MAX_LOAD_POINTS`] points), SetSizes (the sample's
//! count), a Run whose filter starts at the prediction with the motion's spread (the
//! centred Euler parameters of the on-board filter, the rotation vector's spread taken for
//! each angle's) and whose polish, once the track's scale is fixed (known, or settled), is
//! [`BOARD_POLISH_STEPS`] steps from the filter's pose with the scale held over the sample
//! and more of the frame's scan uploaded after it (up to [`BOARD_POLISH_POINTS`] in all, as
//! many as the frame's time allows: [`FrameRequest`]), and before that the smallest the
//! protocol takes (one start, no steps); Status polls while it runs, then Result. The
//! board's pose is the polish's (the filter's without steps); the host polishes and checks
//! it as a software frame does its filter's. Each request and reply is the framed message
//! ([`Frame::encode`]) at 10 bits a byte.
//!
//! **The board's time** ([`BoardFrame::seconds`]): the bytes before and after the run at
//! the baud rate; the run's clocks at the board's clock: the sequencer's schedule
//! ([`run_clocks_for`]) with every evaluation as long as the prediction's, counted on the
//! neighbour pipeline's cycle model ([`clocks_per_particle`], plus the residual stage's
//! latency; the particles lie within a few spreads of the prediction), and the polish's
//! model ([`polish_clocks_model`]); one Status round trip and half a poll period for the
//! poll that sees it done.

use crate::board::on_board::{evaluate, filter_config, params_pose, scale_step, FilterPrior};
use crate::board::quantise::{
    board_grid, board_model, morton_sorted, normalised_pose, original_pose, quantise_pose, restore_pose,
    stored_normals, Normalisation,
};
use crate::board::{run_clocks_for, BoardClient, BoardError, BOARD_MAX_STORE_POINTS, DEFAULT_POLL};
use crate::geometry::{Centred, Pose, ScaleBounds};
use crate::pf_icp::PfIcpSettings;
use nalgebra::Point3;
use pficp_fpga::board::BoardConfig;
use pficp_fpga::common::format::FxPoint;
use pficp_fpga::filter::pf::{Particle, PfConfig};
use pficp_fpga::polish::ScaleStep;
use pficp_fpga::protocol::messages::{
    load_request, two_u16, MAX_LOAD_POINTS, RESULT_BYTES, RUN_REPLY_BYTES, STATUS_BYTES,
};
use pficp_fpga::protocol::run_request::{execute, polish_clocks_model, PolishOutcome, PolishRequest, RunRequest};
use pficp_fpga::protocol::versions::{refusal, Mode};
use pficp_fpga::protocol::{Command, Frame};
use pficp_fpga::search::grid::Grid;
use pficp_fpga::search::neighbour_pipeline::clocks_per_particle;
use pficp_fpga::surface::surface_residual::SURFACE_LATENCY;
use pficp_fpga::surface::FxNormal;
use std::time::Duration;

/// Bits a byte on the wire (8N1).
const BITS_PER_BYTE: f64 = 10.0;

/// The board's polish steps a tracked frame once the track's scale is fixed: one start (the
/// filter's pose), the scale held (docs/tracking.md, "On the board").
pub const BOARD_POLISH_STEPS: u8 = 3;
/// Scan points the board's polish of a tracked frame goes over at most: the filter's sample
/// and the rest drawn from the frame's scan, as many of them as keep the frame's modelled
/// time on the board within [`BOARD_FRAME_SHARE`] of the frame period.
pub const BOARD_POLISH_POINTS: usize = 700;
/// The share of a frame's period (`1 / --fps`) the board's part may take (the link and the
/// run, as modelled); the rest is for the host's polish and checks.
pub const BOARD_FRAME_SHARE: f64 = 0.8;

/// The model as the board holds it, for a track's frames.
pub struct BoardModel {
    grid: Grid,
    normals: Vec<FxNormal>,
    model_norm: Normalisation,
    config: BoardConfig,
}

/// One frame's filter on the board.
#[derive(Clone, Debug)]
pub struct BoardFrame {
    /// The board's pose (its polish's, its filter's best without steps; scan to model).
    pub pose: Pose,
    /// Bytes on the wire before the run (the scan, SetSizes, Run, their replies) and after
    /// it (Result and its reply).
    pub link_bytes: usize,
    /// The run's clocks (modelled: [`FrameRequest`]'s plan).
    pub clocks: u64,
    /// The board's clock [Hz].
    pub clock_hz: u32,
    /// The requests: the scan sample as the board stores it (the filter's points first,
    /// then the polish's others), and the Run.
    pub scan: Vec<FxPoint>,
    /// The filter's points: the first of [`Self::scan`] (SetSizes' scan count).
    pub filter_points: usize,
    /// The Run.
    pub run: RunRequest,
    /// The filter's best parameters (the board's Result's `params`).
    pub params: Particle,
    /// The polish's choice (the board's Result's `polish`).
    pub polish: PolishOutcome,
    /// The model's points on the board.
    pub model_points: usize,
}

impl BoardFrame {
    /// The board's time for the frame at `baud` (module doc).
    pub fn seconds(&self, baud: u32) -> f64 {
        board_seconds(self.link_bytes, self.clocks, self.clock_hz, baud)
    }
}

/// The board's time for a frame of `link_bytes` on the wire (but the polls) and a run of
/// `clocks` at `clock_hz`, at `baud` (module doc): one Status round trip and half a poll
/// period besides.
fn board_seconds(link_bytes: usize, clocks: u64, clock_hz: u32, baud: u32) -> f64 {
    let wire = |bytes: usize| bytes as f64 * BITS_PER_BYTE / baud as f64;
    wire(link_bytes)
        + clocks as f64 / clock_hz as f64
        + wire(round_trip(Command::Status, Vec::new(), STATUS_BYTES))
        + 0.5 * DEFAULT_POLL.as_secs_f64()
}

/// The bytes of a request with `data` and its reply of `reply` data bytes.
fn round_trip(command: Command, data: Vec<u8>, reply: usize) -> usize {
    let code = command as u8;
    Frame { code, seq: 0, data }.encode().len()
        + Frame { code: code | 0x80, seq: 0, data: vec![0; reply] }.encode().len()
}

/// What a tracked frame asks of the board: the filter from `predicted` with standard
/// deviations `spread` (translation, relative scale, rotation) over `sample` (the frame's
/// weighed scan points), `particles` and `iterations`, seeded by `seed`; with the track's
/// scale `bounds` fixed, [`BOARD_POLISH_STEPS`] steps of the polish holding it over the
/// sample and `extra`, otherwise the least polish.
#[derive(Clone, Copy, Debug)]
pub struct FrameRequest<'a> {
    /// The filter's points.
    pub sample: &'a [Point3<f64>],
    /// The polish's other points.
    pub extra: &'a [Point3<f64>],
    /// The prediction.
    pub predicted: &'a Pose,
    /// The motion's spread.
    pub spread: &'a [f64; 7],
    /// The track's scale bounds.
    pub bounds: &'a ScaleBounds,
    /// The frame period [s] (`1 / --fps`).
    pub frame_seconds: f64,
    /// Particles.
    pub particles: usize,
    /// Filter iterations.
    pub iterations: usize,
    /// The frame's seed.
    pub seed: u64,
}

/// A tracked frame's filter ([`BoardModel::filter_part`]).
struct FilterPart {
    scan_norm: Normalisation,
    /// The filter's points as the board stores them.
    sample: Vec<FxPoint>,
    filter: PfConfig,
    scale: ScaleStep,
    steps: u8,
    /// The pipeline's clocks for one evaluation of the sample at the prediction.
    evaluation: u64,
}

/// One tracked frame's requests: the scan sample as the board stores it and the Run, and
/// their modelled cost.
struct FrameRun {
    scan_norm: Normalisation,
    /// The filter's points, then (with polish steps) the polish's others.
    scan: Vec<FxPoint>,
    filter_points: usize,
    run: RunRequest,
    /// Bytes on the wire but the Status polls.
    link_bytes: usize,
    /// The run's clocks (modelled).
    clocks: u64,
}

impl BoardModel {
    /// The model on the shipped board ([`BoardConfig::default`]): at most `max` of its
    /// points (drawn with `seed`; at most [`BOARD_MAX_STORE_POINTS`]), normalised, gridded,
    /// with their normals.
    pub fn new(model: &[Point3<f64>], seed: u64, max: usize) -> Result<Self, BoardError> {
        let model_norm = Normalisation::of(model);
        let on_board = board_model(model, max.min(BOARD_MAX_STORE_POINTS), seed);
        let grid = board_grid(&model_norm.quantise(&on_board))?;
        Ok(BoardModel { normals: stored_normals(&grid), grid, model_norm, config: BoardConfig::default() })
    }

    /// The model's grid and normals as the board stores them.
    pub fn stores(&self) -> (&Grid, &[FxNormal]) {
        (&self.grid, &self.normals)
    }

    /// Put the model on the board behind `client` unless it holds it already (its digest);
    /// true when it uploaded. The board's lanes and clock from its Identify are used for
    /// the modelled time from then on.
    pub fn ensure_on(&mut self, client: &mut BoardClient) -> Result<bool, BoardError> {
        let id = client.identify()?;
        if let Some(why) = refusal(id.version, Mode::OnBoard) {
            return Err(BoardError::Limit(why));
        }
        if self.grid.points.len() > id.max_model as usize {
            return Err(BoardError::Limit(format!(
                "the model has {} points on the board; the board holds {}",
                self.grid.points.len(),
                id.max_model
            )));
        }
        self.config = BoardConfig { lanes: id.lanes as usize, clock_hz: id.clock_hz, baud: id.baud };
        client.ensure_grid(&self.grid, &self.normals, |_, _| {})
    }

    /// The frame's requests (module doc) with the polish over as many of `r.extra` as fit
    /// the frame's share ([`BOARD_FRAME_SHARE`]) at the board's baud rate: all when they
    /// fit; otherwise the share of them that the modelled time, linear in the points,
    /// leaves room for (none when the sample alone does not fit).
    fn planned(&self, r: &FrameRequest) -> FrameRun {
        let filter = self.filter_part(r);
        let full = self.frame_run(&filter, r.extra, r.extra.len());
        let budget = BOARD_FRAME_SHARE * r.frame_seconds;
        let seconds = |f: &FrameRun| board_seconds(f.link_bytes, f.clocks, self.config.clock_hz, self.config.baud);
        if full.run.polish.steps == 0 || seconds(&full) <= budget {
            return full;
        }
        let none = self.frame_run(&filter, r.extra, 0);
        let (s0, s1) = (seconds(&none), seconds(&full));
        let fits = ((budget - s0) / (s1 - s0) * r.extra.len() as f64).floor();
        self.frame_run(&filter, r.extra, if fits > 0.0 { (fits as usize).min(r.extra.len()) } else { 0 })
    }

    /// The frame's filter (the part of its requests that does not depend on the polish's
    /// points): the sample as the board stores it, the Run's filter, the polish's scale and
    /// steps, and the clocks of one evaluation at the prediction on the neighbour
    /// pipeline's cycle model.
    fn filter_part(&self, r: &FrameRequest) -> FilterPart {
        let FrameRequest { sample, predicted, spread, bounds, particles, iterations, seed, .. } = *r;
        let scan_norm = Normalisation::of(sample);
        let frame = Centred { scan: scan_norm.centre, model: self.model_norm.centre };
        let sigma0: Vec<f64> =
            spread.iter().enumerate().map(|(d, s)| if d == 3 { s * predicted.scale } else { *s }).collect();
        let floor: Vec<f64> = sigma0.iter().map(|s| 0.25 * s).collect();
        let prior = FilterPrior {
            init_params: frame.params(predicted),
            sigma0: &sigma0,
            floor: &floor,
            q: 0.0,
            threshold_avg: 0.0,
            threshold_max: 0.0,
        };
        let settings = PfIcpSettings { particles, iterations, seed, ..Default::default() };
        let sample: Vec<FxPoint> = morton_sorted(&scan_norm.quantise(sample));
        let filter = filter_config(&prior, &self.model_norm, &scan_norm, sample.len(), &settings);
        let scale = scale_step(bounds);
        let steps = if scale == ScaleStep::Held { BOARD_POLISH_STEPS } else { 0 };
        let at_prediction = quantise_pose(&normalised_pose(predicted, &scan_norm, &self.model_norm));
        let evaluation = clocks_per_particle(&self.grid, &sample, &at_prediction, self.config.lanes).clocks;
        FilterPart { scan_norm, sample, filter, scale, steps, evaluation }
    }

    /// The frame's requests with the first `extra` of `points` after the sample (when the
    /// polish steps), and their cost: the bytes of every request and reply; the clocks of
    /// the filter's schedule with every evaluation as long as the prediction's, plus the
    /// residual stage, and of the polish's model ([`polish_clocks_model`]) with the
    /// pipeline's clocks over its points taken at the sample's per point (the sample is
    /// drawn from the same scan).
    fn frame_run(&self, f: &FilterPart, points: &[Point3<f64>], extra: usize) -> FrameRun {
        let filter_points = f.sample.len();
        let mut scan = f.sample.clone();
        if f.steps > 0 {
            scan.extend(morton_sorted(&f.scan_norm.quantise(&points[..extra])));
        }
        let polish = PolishRequest {
            points: scan.len() as u16,
            steps: f.steps,
            winner_steps: 0,
            scale: f.scale,
            hypotheses: Vec::new(),
        };
        let run = RunRequest { filter: f.filter.clone(), polish };
        let model_points = self.grid.points.len();
        let uploads: usize = scan
            .chunks(MAX_LOAD_POINTS)
            .scan(0usize, |offset, chunk| {
                let bytes = round_trip(Command::LoadScan, load_request(*offset as u16, chunk), 4);
                *offset += chunk.len();
                Some(bytes)
            })
            .sum();
        let link_bytes = uploads
            + round_trip(Command::SetSizes, two_u16(model_points as u16, filter_points as u16), 4)
            + round_trip(Command::Run, run.encode(), RUN_REPLY_BYTES)
            + round_trip(Command::Result, Vec::new(), RESULT_BYTES);
        let polish_pipeline = match run.polish.steps {
            0 => 0,
            _ => f.evaluation * scan.len() as u64 / filter_points.max(1) as u64 + SURFACE_LATENCY as u64,
        };
        let clocks = run_clocks_for(run.filter.particles, run.filter.iterations, f.evaluation + SURFACE_LATENCY as u64)
            + polish_clocks_model(&run.polish, polish_pipeline);
        FrameRun { scan_norm: f.scan_norm, scan, filter_points, run, link_bytes, clocks }
    }

    /// What the frame costs on the board and its pose: the `polish`'s pose after steps, the
    /// filter's `params` without (or when the polished matrix is no similarity).
    fn frame_of(&self, f: &FrameRun, params: &Particle, polish: &PolishOutcome) -> BoardFrame {
        let model_points = self.grid.points.len();
        let restored = restore_pose(&polish.pose).filter(|_| f.run.polish.steps > 0);
        BoardFrame {
            pose: match restored {
                Some(p) => original_pose(&p, &f.scan_norm, &self.model_norm),
                None => params_pose(params, &self.model_norm, &f.scan_norm),
            },
            link_bytes: f.link_bytes,
            clocks: f.clocks,
            clock_hz: self.config.clock_hz,
            scan: f.scan.clone(),
            filter_points: f.filter_points,
            run: f.run.clone(),
            params: *params,
            polish: *polish,
            model_points,
        }
    }

    /// The frame's filter and polish by the board's bit-exact reference.
    pub fn filter(&self, r: &FrameRequest) -> BoardFrame {
        let f = self.planned(r);
        let search = pficp_fpga::surface::GridSearch { grid: &self.grid, normals: &self.normals };
        let filtered = &f.scan[..f.filter_points];
        let outcome = execute(&f.run, |p| evaluate(&self.grid, &self.normals, filtered, p), &search, &f.scan);
        self.frame_of(&f, &outcome.filter.params, &outcome.polish)
    }

    /// The frame's filter on the board behind `client` (the model on it:
    /// [`Self::ensure_on`]): LoadScan, SetSizes, Run, Status every `poll`, Result. The
    /// board's parameters are the reference's to the bit.
    pub fn filter_on(
        &self,
        client: &mut BoardClient,
        r: &FrameRequest,
        poll: Duration,
    ) -> Result<BoardFrame, BoardError> {
        let f = self.planned(r);
        client.load_scan(&f.scan, |_, _| {})?;
        client.set_sizes(self.grid.points.len(), f.filter_points)?;
        let modelled = client.modelled_run_time(&f.run);
        let limit = client.run_allowance(&f.run);
        client.run(&f.run)?;
        client.wait_for_run(limit, modelled, poll, |_| {})?;
        let result = client.result()?;
        Ok(self.frame_of(&f, &result.params, &result.polish))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::board::run_clocks_bound;
    use crate::eval::realistic::{pose_errors, Shape};
    use crate::eval::tracking::sequence::sequence;
    use crate::geometry::ScaleBounds;

    /// From a prediction a little off the truth, the board's filter (its bit-exact
    /// reference) and the host's polish after it land as near the truth as the polish from
    /// the prediction does; the modelled clocks are within the host's bound and the bytes
    /// hold at least the scan sample.
    #[test]
    fn the_boards_filter_then_the_polish_lands_on_the_truth() {
        let bunny = crate::real_shapes::all().iter().find(|s| s.name == "bunny").expect("the bunny");
        let seq = sequence(Shape::Real(bunny), 5, true);
        let board = BoardModel::new(&seq.model, 1, BOARD_MAX_STORE_POINTS).unwrap();
        let nn = crate::nn::NearestNeighbours::new(&seq.model);
        let surface = crate::pf_icp::surface::Surface::new(&nn);
        let fixed = ScaleBounds::fixed(1.0);
        for k in [20, 40, 60] {
            let f = &seq.frames[k];
            let at = crate::cloud::centroid(&f.scan);
            let step = [0.01 * seq.diag, 0.0, -0.005 * seq.diag, 0.0, 0.0, 0.02, -0.01];
            let off = crate::tracking::motion::after(&f.truth, &step, &f.truth.apply(&at));
            let d = 0.01 * seq.diag;
            let spread = [d, d, d, 0.0, 0.02, 0.02, 0.02];
            // (A random sample, as the tracker weighs on.)
            let sample = crate::tracking::local::sample(&f.scan, 150, k as u64);
            let extra = crate::tracking::local::sample(&f.scan, BOARD_POLISH_POINTS - 150, 100 + k as u64);
            let request = FrameRequest {
                sample: &sample,
                extra: &extra,
                predicted: &off,
                spread: &spread,
                bounds: &fixed,
                frame_seconds: 1.0 / 30.0,
                particles: 16,
                iterations: 3,
                seed: 7,
            };
            let b = board.filter(&request);
            let polish = |p: &Pose| surface.polish(&f.scan, &fixed.apply(p, &at), 10, &fixed);
            let from_board = pose_errors(&polish(&b.pose), &f.truth, &at, seq.diag);
            let from_prediction = pose_errors(&polish(&off), &f.truth, &at, seq.diag);
            assert!(
                from_board.0 <= from_prediction.0 + 0.2 && from_board.1 <= from_prediction.1 + 0.002,
                "frame {k}: from the board's pose {from_board:?}, from the prediction {from_prediction:?}"
            );
            assert!(from_board.0 < 1.0 && from_board.1 < 0.01, "frame {k}: {from_board:?}");
            let bound = run_clocks_bound(16, 3, sample.len(), seq.model.len(), 8);
            assert!(b.clocks > 0 && b.clocks < bound, "frame {k}: {} clocks, bound {bound}", b.clocks);
            // The polish's points: as many as fit the board's share of a frame at 30 a
            // second; all of them in a second, the sample's alone in a millisecond.
            assert_eq!((b.filter_points, b.run.polish.points as usize), (150, b.scan.len()));
            let on_board = b.seconds(3_000_000);
            assert!(on_board <= BOARD_FRAME_SHARE / 30.0 || b.scan.len() == 150, "frame {k}: {on_board} s");
            let slow = board.filter(&FrameRequest { frame_seconds: 1.0, ..request });
            let fast = board.filter(&FrameRequest { frame_seconds: 0.001, ..request });
            assert_eq!((slow.scan.len(), fast.scan.len()), (BOARD_POLISH_POINTS, 150));
            eprintln!("frame {k}: {} polish points, {on_board:.4} s on the board", b.scan.len());
            assert!(b.link_bytes > b.scan.len() * pficp_fpga::protocol::layout::POINT_BYTES);
            assert!(b.seconds(921_600) > b.seconds(3_000_000));
            // A scale not yet fixed: the filter alone, its pose the filter's parameters (the
            // same filter: the same seed and spread).
            let free = board.filter(&FrameRequest { extra: &[], bounds: &ScaleBounds::FREE, ..request });
            assert_eq!((free.run.polish.steps, free.run.polish.scale), (0, ScaleStep::Solved));
            assert_eq!(free.pose, params_pose(&free.params, &board.model_norm, &Normalisation::of(&sample)));
            // The board's pose alone with the scale known: its polish held the scale, and its
            // steps brought the filter's pose nearer the truth.
            let alone = pose_errors(&b.pose, &f.truth, &at, seq.diag);
            let filtered = pose_errors(&free.pose, &f.truth, &at, seq.diag);
            eprintln!(
                "frame {k}: the board's polish {alone:?}, its filter {filtered:?}, the host's polish {from_board:?}"
            );
            assert_eq!(b.run.polish.steps, BOARD_POLISH_STEPS);
            assert!(alone.2 < 1e-4, "frame {k}: the board's scale {alone:?}");
            assert!(alone.0 < filtered.0 && alone.0 < 1.0, "frame {k}: {alone:?} against the filter's {filtered:?}");
        }
    }
}
