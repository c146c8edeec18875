//! PF-ICP with the particle filter on the board (`pficp register --board`, the default):
//! the host computes the start and the covariance (PF-ICP stages 1 and 2,
//! [`crate::pf_icp::prior`]), uploads the model gridded (sorted by cell, with its normals
//! and its cell table, [`pficp_fpga::search::grid::Grid`]; docs/board-modes.md) and a sample of
//! `board_points` scan points in Morton order ([`super::quantise::morton_sorted`]) followed by the
//! rest of the scan, sends the prior as a Run request ([`pf_config`]) with the polish's
//! starts ([`polish_request`]), polls Status, reads Result and polishes the board's pose
//! with ICP on the whole scan. The filter itself (steps 6 to 8 of Algorithm 6) runs on the
//! board, bit-exact with `pficp_fpga::filter::pf::run`, and so does the polish after it (protocol
//! 6: [`POLISH_STARTS`] starts, the winner polished further;
//! `pficp_fpga::protocol::run_request::execute`): the board's pose alone is the polished one.

use super::quantise::{
    binary_angle, board_grid, board_model, morton_sorted, normalised_pose, original_pose, param24, quantise_pose,
    sigma22, stored_normals, Normalisation,
};
use super::{BoardClient, BoardError, ClientStats, Upload, BOARD_MAX_PARTICLES, BOARD_MAX_STORE_POINTS};
use crate::geometry::{Pose, ScaleBounds};
use crate::nn::NearestNeighbours;
use crate::pf_icp::{prior, weight_sample, PfIcpResult, PfIcpSettings, Prior, StageTimes};
use crate::registration::icp::Registration;
use nalgebra::Point3;
use pficp_fpga::common::format::{FxPoint, DIST_FRAC};
use pficp_fpga::filter::pf::{Particle, PfConfig, PARAMS, PARAM_BITS, PARAM_TRANSLATION_FRAC, SCALE, SCALE_FRAC};
use pficp_fpga::polish::ScaleStep;
use pficp_fpga::protocol::messages::{Identity, ResultReply, RunState, MAX_D2_MASK, NO_COST};
use pficp_fpga::protocol::run_request::{PolishRequest, RunOutcome, RunRequest, MAX_STARTS};
use pficp_fpga::protocol::versions::{refusal, Mode};
use pficp_fpga::protocol::{Command, ErrorCode};
use pficp_fpga::search::grid::Grid;
use pficp_fpga::surface::FxNormal;
use std::time::{Duration, Instant};

/// The default number of scan points the on-board filter weighs each particle over
/// (docs/board-modes.md, "Scan points per weight"): the smallest of 300, 500 and 1,000
/// whose polished result matches the software mode's success on models 1 to 3 and the
/// realistic quick set (none of them makes the board's pose alone match it).
pub const DEFAULT_BOARD_POINTS: usize = 300;

/// Starts of the on-board polish: the filter's pose and the first seven of the hypotheses
/// the host's conclusion compares (docs/on-board-polish.md, "Eight starts, the winner polished
/// further": on three dev seeds eight starts with 5 steps each and the winner's 5 more
/// bring the board's pose alone level with the software mode, within the bench's 0.1 s).
pub const POLISH_STARTS: usize = 8;
/// Gauss-Newton steps of the on-board polish a start.
pub const POLISH_STEPS: u8 = 5;
/// Further steps for the winner among the starts, from its pose.
pub const POLISH_WINNER_STEPS: u8 = 5;
const _: () = assert!(POLISH_STARTS <= MAX_STARTS);

/// Steps of the on-board registration, for progress reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnBoardStep {
    /// A store being uploaded: (done, total), in points for the scan, in data bytes for
    /// the model and its cell table ([`BoardClient::load_grid`]).
    Upload(Upload),
    /// The filter running: (iterations done, the iteration cap).
    Filter,
    /// The board holds the model and its cell table already (Identify's model digest is
    /// the upload's, docs/protocol.md "Resident model"): nothing uploaded; (0, 0).
    Resident,
}

/// What the on-board filter gets from the host: the clouds on the board and the Run
/// configuration, all derived from PF-ICP's prior ([`crate::pf_icp::prior`]).
#[derive(Clone, Debug)]
pub struct OnBoardPlan {
    /// The host's prior (start, covariance, sigmas, thresholds).
    pub prior: Prior,
    /// The model's normalisation (its centroid and radius).
    pub model_norm: Normalisation,
    /// The scan's normalisation.
    pub scan_norm: Normalisation,
    /// The model points for the board, normalised and quantised (the host's order).
    pub model: Vec<FxPoint>,
    /// `model` gridded: what the board stores (the points sorted by cell, the cell table)
    /// and searches; `grid.order` maps the board's model indices to `model`'s.
    pub grid: Grid,
    /// The normals of `grid.points` ([`stored_normals`]), for the surface residual.
    pub normals: Vec<FxNormal>,
    /// Whether the model was subsampled to fit the board.
    pub model_subsampled: bool,
    /// The scan points for the board (the weight sample of `board_points`), normalised,
    /// quantised and sorted by the Morton order of their cells ([`morton_sorted`]).
    pub scan: Vec<FxPoint>,
    /// The rest of the scan, normalised and quantised (every k-th when the whole scan does
    /// not fit the store): stored after `scan`, for the polish.
    pub rest: Vec<FxPoint>,
    /// The filter's part of the Run request.
    pub config: PfConfig,
    /// The polish's part ([`polish_request`]).
    pub polish: PolishRequest,
}

/// The board's 32-bit PRNG seed for a host seed: deterministic, never 0.
pub fn board_seed(seed: u64) -> u32 {
    // SplitMix64's finaliser on a stream of its own.
    let mut z = seed.wrapping_add(0x6f6e_626f_6172_6421);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    match (z ^ (z >> 32)) as u32 {
        0 => 1,
        s => s,
    }
}

/// The Run configuration for PF-ICP's prior, the clouds' normalisations and `scan_points`
/// scan points on the board (`S`). In normalised coordinates the centred frame is the
/// normalised pose, `d_n = (s r_scan / r_model) R m_n + t / r_model`, so:
/// - centre: `t / r_model` (Q5.19), `s r_scan / r_model` (Q3.21), the Euler angles as
///   binary angles (2^24 a turn);
/// - `sigma0` and `floor` the same way (translations `/ r_model`, the scale
///   `* r_scan / r_model`, angles in turns `* 2^24`), scaled by `region_sigmas / 2` (the
///   board's region is `+-2 sigma`), at least 1 LSB and at most `2^22 - 1`;
/// - `temper_exp = clamp(round(log2(2 Q_board)), 0, 63)`: the board's cost is the sum over
///   the `S` points of squared residuals in `2^-26` normalised units, so a cost in the
///   software's units (the MSD) is `S 2^26 / r_model^2` board LSBs, and so is `Q` (the
///   software weighs with `exp(-(c - c_min) / (2 Q))`, `Q` in the cost's units, exactly as
///   the host-driven mode converts it);
/// - `thr_cost = S (threshold_avg / r_model)^2 2^26`, `thr_max = (threshold_max /
///   r_model)^2 2^26` (at most `2^34 - 1`): since protocol 4 the board compares them with
///   the surface residuals (distances to the tangent planes), not the point distances the
///   software's thresholds measure; a residual is at most the point distance (rounding
///   aside), so the board may stop earlier than the software on the same data
///   (docs/board-modes.md, "The stop thresholds on residuals");
/// - the seed from [`board_seed`], particles and iterations from `settings`.
pub fn pf_config(
    prior: &Prior,
    model_norm: &Normalisation,
    scan_norm: &Normalisation,
    scan_points: usize,
    settings: &PfIcpSettings,
) -> PfConfig {
    let filter = FilterPrior {
        init_params: prior.init_params,
        sigma0: &prior.sigma0,
        floor: &prior.floor,
        q: prior.q,
        threshold_avg: prior.threshold_avg,
        threshold_max: prior.threshold_max,
    };
    filter_config(&filter, model_norm, scan_norm, scan_points, settings)
}

/// What the on-board filter's Run configuration is made of: the start in the centred
/// frame of the clouds' normalisations, the sigmas, `Q` and the stop thresholds
/// (PF-ICP's [`Prior`], or a tracked frame's prediction and spread).
#[derive(Clone, Copy, Debug)]
pub struct FilterPrior<'a> {
    /// The start, in the frame centred on the clouds' normalisation centres.
    pub init_params: crate::geometry::Params,
    /// Initial sigma per state.
    pub sigma0: &'a [f64],
    /// Smallest sigma per state.
    pub floor: &'a [f64],
    /// The likelihood's `Q`.
    pub q: f64,
    /// Stop threshold on the average closest-point distance [units].
    pub threshold_avg: f64,
    /// Stop threshold on the largest closest-point distance [units].
    pub threshold_max: f64,
}

/// [`pf_config`] from a [`FilterPrior`].
pub fn filter_config(
    prior: &FilterPrior,
    model_norm: &Normalisation,
    scan_norm: &Normalisation,
    scan_points: usize,
    settings: &PfIcpSettings,
) -> PfConfig {
    let (rm, rs) = (model_norm.radius, scan_norm.radius);
    let p = &prior.init_params;
    let centre: Particle = [
        param24(p[0] / rm, PARAM_TRANSLATION_FRAC),
        param24(p[1] / rm, PARAM_TRANSLATION_FRAC),
        param24(p[2] / rm, PARAM_TRANSLATION_FRAC),
        param24(p[3] * rs / rm, SCALE_FRAC).max(1),
        binary_angle(p[4]),
        binary_angle(p[5]),
        binary_angle(p[6]),
    ];
    let widen = settings.region_sigmas / 2.0;
    let lsb = |d: usize, x: f64| -> u32 {
        let v = match d {
            0..=2 => x / rm * (1u64 << PARAM_TRANSLATION_FRAC) as f64,
            3 => x * rs / rm * (1u64 << SCALE_FRAC) as f64,
            _ => x / std::f64::consts::TAU * (1u64 << PARAM_BITS) as f64,
        };
        sigma22(v)
    };
    let sigma0: [u32; PARAMS] = std::array::from_fn(|d| lsb(d, prior.sigma0[d] * widen));
    let floor: [u32; PARAMS] = std::array::from_fn(|d| lsb(d, prior.floor[d] * widen));
    let per_msd = scan_points as f64 * (1u64 << DIST_FRAC) as f64 / (rm * rm);
    let two_q = 2.0 * prior.q * per_msd;
    let temper_exp = if two_q > 0.0 && two_q.is_finite() { two_q.log2().round().clamp(0.0, 63.0) as u8 } else { 0 };
    let dist = |x: f64| (x / rm).powi(2) * (1u64 << DIST_FRAC) as f64;
    let thr_cost = (scan_points as f64 * dist(prior.threshold_avg)).min(NO_COST as f64) as u64;
    let thr_max = dist(prior.threshold_max).min(MAX_D2_MASK as f64) as u64;
    PfConfig {
        particles: settings.particles.min(u16::MAX as usize) as u16,
        iterations: settings.iterations.min(u16::MAX as usize) as u16,
        temper_exp,
        centre,
        sigma0,
        floor,
        seed: board_seed(settings.seed),
        thr_cost,
        thr_max,
    }
}

/// The pose (scan to model, original frame) of the board's parameters.
pub fn params_pose(params: &Particle, model_norm: &Normalisation, scan_norm: &Normalisation) -> Pose {
    let t = |k: usize| params[k] as f64 / (1u64 << PARAM_TRANSLATION_FRAC) as f64;
    let a = |k: usize| params[k] as f64 / (1u64 << PARAM_BITS) as f64 * std::f64::consts::TAU;
    let s = params[SCALE] as f64 / (1u64 << SCALE_FRAC) as f64;
    let pose_n = Pose::from_params(&[t(0), t(1), t(2), s, a(4), a(5), a(6)]);
    original_pose(&pose_n, scan_norm, model_norm)
}

/// A board cost (sum over `scan_points` of surface residuals, Q8.26 normalised) in the
/// software's units (MSD in the clouds' units).
pub fn cost_msd(cost: u64, scan_points: usize, model_norm: &Normalisation) -> f64 {
    cost as f64 * model_norm.radius * model_norm.radius / (scan_points.max(1) as f64 * (1u64 << DIST_FRAC) as f64)
}

/// Plan the on-board registration: PF-ICP's prior on the host, the model for the board
/// (subsampled to `max_model` with the seed, as the host-driven mode does), the scan's
/// weight sample of `board_points` (drawn with the seed as [`weight_sample`] does), both
/// normalised by their own cloud and quantised, the model gridded ([`board_grid`]; a
/// model the grid refuses is a [`BoardError::Limit`]), the sample in Morton order
/// ([`morton_sorted`]), and the Run configuration ([`pf_config`]).
pub fn plan(
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &PfIcpSettings,
    board_points: usize,
    max_model: usize,
) -> Result<OnBoardPlan, BoardError> {
    plan_with_prior(prior(nn, scan, settings), nn, scan, settings, board_points, max_model)
}

/// [`plan`] with the prior already computed (it does not depend on `board_points`).
pub fn plan_with_prior(
    prior: Prior,
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &PfIcpSettings,
    board_points: usize,
    max_model: usize,
) -> Result<OnBoardPlan, BoardError> {
    let model = nn.points();
    let model_norm = Normalisation::of(model);
    let scan_norm = Normalisation::of(scan);
    let on_board = board_model(model, max_model, settings.seed);
    let sample = weight_sample(scan, &PfIcpSettings { weight_points: board_points, ..settings.clone() });
    let config = pf_config(&prior, &model_norm, &scan_norm, sample.len(), settings);
    let model_q = model_norm.quantise(&on_board);
    let grid = board_grid(&model_q)?;
    let rest = scan_norm.quantise(&rest_of(scan, &sample, BOARD_MAX_STORE_POINTS.saturating_sub(sample.len())));
    let polish = polish_request(&prior, &model_norm, &scan_norm, sample.len() + rest.len(), &settings.scale);
    Ok(OnBoardPlan {
        prior,
        normals: stored_normals(&grid),
        grid,
        model: model_q,
        model_subsampled: on_board.len() < model.len(),
        scan: morton_sorted(&scan_norm.quantise(&sample)),
        rest,
        model_norm,
        scan_norm,
        config,
        polish,
    })
}

/// The scan without the points of `sample` (each sample point removes one equal scan
/// point), every k-th of them when more than `room`.
fn rest_of(scan: &[Point3<f64>], sample: &[Point3<f64>], room: usize) -> Vec<Point3<f64>> {
    let key = |p: &Point3<f64>| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let mut taken: std::collections::HashMap<[u64; 3], usize> = std::collections::HashMap::new();
    for p in sample {
        *taken.entry(key(p)).or_default() += 1;
    }
    let rest: Vec<Point3<f64>> = scan
        .iter()
        .filter(|p| match taken.get_mut(&key(p)) {
            Some(n) if *n > 0 => {
                *n -= 1;
                false
            }
            _ => true,
        })
        .copied()
        .collect();
    let stride = rest.len().div_ceil(room.max(1)).max(1);
    rest.into_iter().step_by(stride).take(room).collect()
}

/// The polish the board runs after its filter: [`POLISH_STEPS`] steps over the `points`
/// stored scan points, then [`POLISH_WINNER_STEPS`] for the winner, from the filter's pose
/// and the first `POLISH_STARTS - 1` of the
/// hypotheses the host's conclusion would compare with it
/// ([`crate::pf_icp::conclusion::candidates`]), as the board holds poses; the steps hold
/// the scale when the user fixed it (`--scale`: every start is at that scale).
pub fn polish_request(
    prior: &Prior,
    model_norm: &Normalisation,
    scan_norm: &Normalisation,
    points: usize,
    scale: &ScaleBounds,
) -> PolishRequest {
    let hypotheses = crate::pf_icp::conclusion::candidates(&prior.start, &prior.hypotheses)
        .iter()
        .skip(1)
        .take(POLISH_STARTS - 1)
        .map(|p| quantise_pose(&normalised_pose(p, scan_norm, model_norm)))
        .collect();
    PolishRequest {
        points: points.min(BOARD_MAX_STORE_POINTS) as u16,
        steps: POLISH_STEPS,
        winner_steps: POLISH_WINNER_STEPS,
        scale: scale_step(scale),
        hypotheses,
    }
}

/// How the board's polish treats the scale under the user's `bounds`: held when they fix
/// it, solved otherwise (a range is imposed by the host after the board).
pub fn scale_step(bounds: &ScaleBounds) -> ScaleStep {
    match bounds.fixed_value() {
        Some(_) => ScaleStep::Held,
        None => ScaleStep::Solved,
    }
}

impl OnBoardPlan {
    /// The Run request: the filter, then the polish.
    pub fn run_request(&self) -> RunRequest {
        RunRequest { filter: self.config.clone(), polish: self.polish.clone() }
    }

    /// The scan store's contents: the filter's sample, then the rest.
    pub fn stored_scan(&self) -> Vec<FxPoint> {
        [&self.scan[..], &self.rest[..]].concat()
    }

    /// What the board computes for this plan's Run, by the bit-exact reference
    /// (`pficp_fpga::protocol::run_request::execute`: the filter over the grid search of
    /// [`Self::grid`] and [`Self::scan`] with the surface residual of [`Self::normals`],
    /// then the polish over [`Self::stored_scan`]): the software mode's board emulation,
    /// equal to the board's Result to the bit.
    pub fn emulate(&self) -> RunOutcome {
        let search = pficp_fpga::surface::GridSearch { grid: &self.grid, normals: &self.normals };
        let stored = self.stored_scan();
        pficp_fpga::protocol::run_request::execute(
            &self.run_request(),
            |p| evaluate(&self.grid, &self.normals, &self.scan, p),
            &search,
            &stored[..self.polish.points as usize],
        )
    }

    /// The filter's part of [`Self::emulate`] alone.
    pub fn emulate_filter(&self) -> pficp_fpga::filter::pf::PfOutcome {
        pficp_fpga::filter::pf::run(&self.config, |p| evaluate(&self.grid, &self.normals, &self.scan, p))
    }

    /// The board's pose alone (the polish's winner) in the original frame; the filter's
    /// pose when the polished matrix is no similarity.
    pub fn board_pose(&self, result: &ResultReply) -> Pose {
        match super::quantise::restore_pose(&result.polish.pose) {
            Some(p) => original_pose(&p, &self.scan_norm, &self.model_norm),
            None => params_pose(&result.params, &self.model_norm, &self.scan_norm),
        }
    }
}

/// The board's cost and largest residual for a pose ([`pficp_fpga::surface::evaluate`]: the
/// grid's own search, [`Grid::nearest`], then the surface residual), the same bit for bit as
/// the board's reference over its stores (`pficp_fpga::surface::evaluate_stored`;
/// `host/tests/board_filter.rs` checks the two equal), some 20 times faster on 2,000 points.
pub fn evaluate(
    grid: &Grid,
    normals: &[FxNormal],
    scan: &[FxPoint],
    pose: &pficp_fpga::common::format::FxPose,
) -> pficp_fpga::filter::pf::Evaluated {
    pficp_fpga::surface::evaluate(grid, normals, scan, pose)
}

/// What the board found, in the host's terms: the board's pose alone (its polish's winner,
/// as `filter_pose`), the host's conclusion and polish on the whole scan from it, and
/// PF-ICP's result as the software mode gives it (the filter history is empty: the board
/// reports only its best; `registration.errors` holds the board's best cost as an MSD of
/// the sample, then the polished MSD).
pub fn finish(
    plan: &OnBoardPlan,
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &PfIcpSettings,
    result: &ResultReply,
    filter_time: Duration,
) -> PfIcpResult {
    // The user's scale bounds imposed on the board's pose, the image of the scan's centroid
    // kept: a range the board's polish does not know; a fixed scale, which the board holds
    // to its formats' steps, exactly (the host's conclusion then polishes with it fixed).
    let filter_pose = settings.scale.apply(&plan.board_pose(result), &crate::cloud::centroid(scan));
    let t = Instant::now();
    let surface = crate::pf_icp::surface::Surface::new(nn);
    let (conclusion, hypotheses, rescue_time) =
        crate::pf_icp::rescue::conclude_prior(&surface, scan, &filter_pose, &plan.prior, settings);
    let polished = Registration {
        pose: conclusion.pose,
        msd: crate::registration::icp::msd(nn, scan, &conclusion.pose),
        iterations: result.iterations as usize,
        errors: Vec::new(),
    };
    let polish_time = t.elapsed();
    let errors = vec![cost_msd(result.cost, plan.scan.len(), &plan.model_norm), polished.msd];
    PfIcpResult {
        registration: Registration {
            pose: polished.pose,
            msd: polished.msd,
            iterations: result.iterations as usize,
            errors,
        },
        initial: plan.prior.initial.clone(),
        hypotheses,
        conclusion,
        covariance: plan.prior.covariance.clone(),
        filter_pose,
        times: StageTimes {
            clustering: plan.prior.clustering_time,
            covariance: plan.prior.covariance_time,
            filter: filter_time,
            polish: polish_time - rescue_time,
            rescue: rescue_time,
        },
        filter_history: Vec::new(),
        filter_poses: Vec::new(),
    }
}

/// PF-ICP with the filter and its polish on the board, the board's part by its bit-exact
/// reference ([`OnBoardPlan::emulate`], what the board computes and returns to the bit):
/// the software mode's emulation of `pficp register --board`, for the experiments'
/// `pf-icp-board` columns. [`PfIcpResult::filter_pose`] is the board's pose alone.
pub fn emulate_registration(
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &PfIcpSettings,
    board_points: usize,
) -> Result<PfIcpResult, BoardError> {
    let plan = plan(nn, scan, settings, board_points, crate::board::BOARD_MAX_STORE_POINTS)?;
    let reply = ResultReply::of(&plan.emulate());
    Ok(finish(&plan, nn, scan, settings, &reply, Duration::ZERO))
}

/// What the board did during one on-board registration.
#[derive(Clone, Debug)]
pub struct OnBoardReport {
    /// The board's Identify reply before the run.
    pub identity: Identity,
    /// Model points in the board's model store.
    pub model_points: usize,
    /// Whether the model was subsampled to fit.
    pub model_subsampled: bool,
    /// Scan points the board weighs each particle over.
    pub scan_points: usize,
    /// The Run request.
    pub request: RunRequest,
    /// The board's Result.
    pub result: ResultReply,
    /// The best cost as the software's MSD (of the board's scan points, clouds' units).
    pub cost_msd: f64,
    /// Status requests while the filter ran.
    pub polls: usize,
    /// The modelled board time of the run.
    pub modelled: Duration,
    /// Wall time from Run to Result.
    pub run_time: Duration,
    /// The client's traffic counters.
    pub stats: ClientStats,
}

/// PF-ICP's result with the filter on the board, and the board's part in it.
#[derive(Clone, Debug)]
pub struct OnBoardResult {
    /// As [`crate::pf_icp::register`] returns.
    pub pf: PfIcpResult,
    /// The board's part.
    pub board: OnBoardReport,
}

/// Register `scan` to the model behind `nn` with PF-ICP, the whole particle filter and its
/// polish on the board behind `client` (protocol 7: Run, Status, Result): the start and the
/// covariance on the host ([`plan`]), the model uploaded unless resident, the scan stored
/// (the `board_points` of the filter's sample first), Run, Status polled every `poll`
/// (progress: [`OnBoardStep::Filter`] with the iterations done), Result, and the host's
/// conclusion and ICP polish on the whole scan ([`finish`]). A board whose
/// iteration count stands still for [`BoardClient::run_allowance`] is a
/// [`BoardError::RunTimeout`].
pub fn register_on_board(
    client: &mut BoardClient,
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &PfIcpSettings,
    board_points: usize,
    poll: Duration,
    progress: &mut (dyn FnMut(OnBoardStep, usize, usize) + Send),
) -> Result<OnBoardResult, BoardError> {
    let identity = client.identify()?;
    if let Some(why) = refusal(identity.version, Mode::OnBoard) {
        return Err(BoardError::Limit(why));
    }
    let max_particles = (identity.max_particles as usize).min(BOARD_MAX_PARTICLES);
    if settings.particles == 0 || settings.particles > max_particles {
        return Err(BoardError::Limit(format!(
            "{} particles: the board runs 1 to {max_particles}",
            settings.particles
        )));
    }
    if settings.iterations == 0 || settings.iterations > u16::MAX as usize {
        return Err(BoardError::Limit(format!("{} iterations: the board runs 1 to {}", settings.iterations, u16::MAX)));
    }
    if settings.adaptive.is_some() {
        return Err(BoardError::Limit("the on-board filter has a fixed particle count (no adaptation)".into()));
    }
    let max_scan = (identity.max_scan as usize).min(BOARD_MAX_STORE_POINTS);
    if board_points == 0 || board_points > max_scan {
        return Err(BoardError::Limit(format!("{board_points} board scan points: the board holds 1 to {max_scan}")));
    }
    let status = client.status().map_err(|e| match e {
        BoardError::Board { command: Command::Status, code: ErrorCode::UnknownCommand } => BoardError::Limit(format!(
            "the board on {} does not know Status: no on-board filter in this design (use --host-driven)",
            client.port_name()
        )),
        e => e,
    })?;
    if status.state == RunState::Running {
        return Err(BoardError::Filter(format!(
            "the board on {} is still running a filter started earlier ({} iterations done); wait for it or reset the board",
            client.port_name(),
            status.iterations
        )));
    }
    let max_model = (identity.max_model as usize).min(BOARD_MAX_STORE_POINTS);
    let plan = plan(nn, scan, settings, board_points, max_model)?;
    let start = Instant::now();
    if !client.ensure_grid(&plan.grid, &plan.normals, |done, total| {
        progress(OnBoardStep::Upload(Upload::Model), done, total)
    })? {
        progress(OnBoardStep::Resident, 0, 0);
    }
    client.load_scan(&plan.stored_scan(), |done, total| progress(OnBoardStep::Upload(Upload::Scan), done, total))?;
    client.set_sizes(plan.model.len(), plan.scan.len())?;
    let request = plan.run_request();
    let modelled = client.modelled_run_time(&request);
    let limit = client.run_allowance(&request);
    let run_start = Instant::now();
    client.run(&request)?;
    let cap = plan.config.iterations as usize;
    progress(OnBoardStep::Filter, 0, cap);
    let mut last = 0;
    let (_, polls) = client.wait_for_run(limit, modelled, poll, |s| {
        if s.iterations as usize != last || s.state == RunState::Done {
            last = s.iterations as usize;
            progress(OnBoardStep::Filter, if s.state == RunState::Done { cap } else { last.min(cap) }, cap);
        }
    })?;
    let result = client.result()?;
    let run_time = run_start.elapsed();
    let pf = finish(&plan, nn, scan, settings, &result, start.elapsed());
    Ok(OnBoardResult {
        board: OnBoardReport {
            identity,
            model_points: plan.model.len(),
            model_subsampled: plan.model_subsampled,
            scan_points: plan.scan.len(),
            cost_msd: cost_msd(result.cost, plan.scan.len(), &plan.model_norm),
            request,
            result,
            polls,
            modelled,
            run_time,
            stats: client.stats(),
        },
        pf,
    })
}
