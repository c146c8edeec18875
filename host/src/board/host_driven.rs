//! PF-ICP with the board weighing (`pficp register --board --host-driven`): the
//! host-driven mode, for protocol version 1 boards.
//!
//! The host-driven pipeline is [`crate::pf_icp::register_with`]'s: k-means start, covariance, particle
//! filter, ICP refinement every iteration and the polish all run on the host in f64; only
//! step 2 of each filter iteration (costs and weights, Eq. 20, 21) runs on the board:
//!
//! 1. Both clouds are normalised by their own similarity ([`Normalisation::of`]) and
//!    quantised to Q3.13. The model goes to the model store (at most 4,096 points: a larger
//!    model is subsampled, the same points for the same seed): on a protocol 4 board
//!    gridded (sorted by cell, with its normals and cell table: [`BoardClient::load_grid`];
//!    its costs are surface residuals capped at `h^2`, `pficp_fpga::surface`), on a version
//!    1 or 2 board as it is (brute force). The
//!    weight sample (the scan points the software filter takes its costs over) goes to the
//!    scan store in Morton order ([`super::quantise::morton_sorted`]; the costs are sums, so the
//!    order changes no cost).
//! 2. Each iteration the particles' poses are normalised and quantised
//!    ([`normalised_pose`], [`quantise_pose`]) and sent in Evaluate frames without LAST; the
//!    board returns each cost (a sum of squared distances in Q8.26 units, normalised frame).
//! 3. The host turns the costs into the software filter's units (MSD of the sample in the
//!    clouds' units: `cost * r_model^2 / (n * 2^26)`), takes the tempered
//!    `Q_k = max(Q, median excess / 6)` from them ([`crate::pf_icp::particle_filter::tempered_q`])
//!    and weighs the stored costs on the board with
//!    [`WeightScale::for_two_q`]`(2 Q_k` in cost LSBs`)`.
//! 4. The board's weights, normalised to sum 1, drive the estimate and the resampling.
//!
//! The poses the filter carries, refines and reports are in the clouds' own frame, so
//! nothing has to be un-normalised at the end but the costs.

use super::on_board::OnBoardStep;
use super::quantise::{
    board_grid, board_model, morton_sorted, normalised_pose, quantise_pose, stored_normals, Normalisation,
};
use super::{BoardClient, BoardError, ClientStats, Upload, BOARD_MAX_PARTICLES, BOARD_MAX_STORE_POINTS};
use crate::geometry::Pose;
use crate::nn::NearestNeighbours;
use crate::pf_icp::particle_filter::{tempered_q, WeighError, Weighed};
use crate::pf_icp::{register_with, ParticleWeights, PfIcpResult, PfIcpSettings};
use nalgebra::Point3;
use pficp_fpga::common::format::{FxPoint, FxPose, WeightScale, DIST_FRAC};
use pficp_fpga::protocol::layout::POINT_BYTES;
use pficp_fpga::protocol::messages::Identity;
use pficp_fpga::protocol::versions::{capabilities, refusal, Mode};
use pficp_fpga::search::grid::Grid;
use pficp_fpga::surface::FxNormal;
use std::sync::Mutex;

/// What the board did during one registration.
#[derive(Clone, Debug)]
pub struct BoardReport {
    /// The board's Identify reply before the run.
    pub identity: Identity,
    /// Model points in the board's model store.
    pub model_points: usize,
    /// Whether the model was subsampled to fit.
    pub model_subsampled: bool,
    /// Scan points the costs are taken over (the weight sample).
    pub scan_points: usize,
    /// Filter iterations weighed on the board.
    pub iterations: usize,
    /// The client's traffic counters.
    pub stats: ClientStats,
}

/// PF-ICP's result and the board's part in it.
#[derive(Clone, Debug)]
pub struct BoardPfResult {
    /// As [`crate::pf_icp::register`] returns.
    pub pf: PfIcpResult,
    /// The board's part.
    pub board: BoardReport,
}

/// The board as the filter's [`ParticleWeights`] source.
struct BoardWeights<'a> {
    client: Mutex<&'a mut BoardClient>,
    progress: Mutex<&'a mut (dyn FnMut(OnBoardStep, usize, usize) + Send)>,
    /// The filter's iteration cap (the progress total).
    cap: usize,
    model_norm: Normalisation,
    scan_norm: Normalisation,
    model: Vec<FxPoint>,
    /// The model gridded with its normals, for a protocol 4 board (`None`: a brute-force
    /// board of version 1 or 2, which gets `model` as it is).
    grid: Option<(Grid, Vec<FxNormal>)>,
    /// Points in the scan store (set by `prepare`).
    sample: Mutex<usize>,
    iterations: Mutex<usize>,
}

impl BoardWeights<'_> {
    /// Cost LSBs to the software filter's units (MSD of the sample, clouds' units squared).
    fn to_msd(&self) -> f64 {
        let n = (*self.sample.lock().expect("not poisoned")).max(1) as f64;
        self.model_norm.radius * self.model_norm.radius / (n * (1u64 << DIST_FRAC) as f64)
    }
}

impl ParticleWeights for BoardWeights<'_> {
    fn prepare(&self, sample: &[Point3<f64>]) -> Result<(), WeighError> {
        let mut client = self.client.lock().expect("not poisoned");
        let mut progress = self.progress.lock().expect("not poisoned");
        let max_scan = client.identity().map_or(BOARD_MAX_STORE_POINTS, |i| i.max_scan as usize);
        if sample.len() > max_scan {
            return Err(Box::new(BoardError::Limit(format!(
                "the weight sample has {} scan points; the board holds at most {max_scan}",
                sample.len()
            ))));
        }
        let scan = morton_sorted(&self.scan_norm.quantise(sample));
        let mut upload = |done, total| progress(OnBoardStep::Upload(Upload::Model), done, total);
        match &self.grid {
            Some((grid, normals)) => {
                if !client.ensure_grid(grid, normals, upload)? {
                    progress(OnBoardStep::Resident, 0, 0);
                }
            }
            // Progress in data bytes either way (6 a point).
            None => client.load_model(&self.model, |done, total| upload(done * POINT_BYTES, total * POINT_BYTES))?,
        }
        client.load_scan(&scan, |done, total| progress(OnBoardStep::Upload(Upload::Scan), done, total))?;
        client.set_sizes(self.model.len(), scan.len())?;
        *self.sample.lock().expect("not poisoned") = scan.len();
        Ok(())
    }

    fn weigh(&self, poses: &[Pose], q: f64) -> Result<Weighed, WeighError> {
        let fx: Vec<FxPose> =
            poses.iter().map(|p| quantise_pose(&normalised_pose(p, &self.scan_norm, &self.model_norm))).collect();
        let to_msd = self.to_msd();
        let mut client = self.client.lock().expect("not poisoned");
        let (raw, summary) = client.costs_and_weights(&fx, |raw| {
            let costs: Vec<f64> = raw.iter().map(|&c| c as f64 * to_msd).collect();
            WeightScale::for_two_q(2.0 * tempered_q(&costs, q) / to_msd)
        })?;
        let mut iterations = self.iterations.lock().expect("not poisoned");
        *iterations += 1;
        (self.progress.lock().expect("not poisoned"))(OnBoardStep::Filter, (*iterations).min(self.cap), self.cap);
        let total = summary.w_sum as f64;
        Ok(Weighed {
            costs: raw.iter().map(|&c| c as f64 * to_msd).collect(),
            weights: summary.weights.iter().map(|&w| w as f64 / total).collect(),
        })
    }
}

/// Register `scan` to the model behind `nn` with PF-ICP, the particle weights on the board
/// behind `client`. `progress(store, done, total)` reports the uploads.
pub fn register(
    client: &mut BoardClient,
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &PfIcpSettings,
    progress: &mut (dyn FnMut(Upload, usize, usize) + Send),
) -> Result<BoardPfResult, BoardError> {
    register_reporting(client, nn, scan, settings, &mut |step, done, total| {
        if let OnBoardStep::Upload(store) = step {
            progress(store, done, total)
        }
    })
}

/// [`register`], with the filter's iterations reported too: `progress(step, done, total)`
/// gets the uploads ([`OnBoardStep::Upload`]) and each weighed iteration
/// ([`OnBoardStep::Filter`], with the iteration cap as the total; the filter may stop
/// before it).
pub fn register_reporting(
    client: &mut BoardClient,
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &PfIcpSettings,
    progress: &mut (dyn FnMut(OnBoardStep, usize, usize) + Send),
) -> Result<BoardPfResult, BoardError> {
    let identity = client.identify()?;
    // Version 2 only added Run, Status and Result: the host-driven commands are version 1's;
    // version 3 searches the model through a cell table, which the host uploads with it;
    // version 4 adds the normals the surface residual needs (a version 3 board's costs are
    // point-to-point, which this host no longer models).
    if let Some(why) = refusal(identity.version, Mode::HostDriven) {
        return Err(BoardError::Limit(why));
    }
    let max_particles = (identity.max_particles as usize).min(BOARD_MAX_PARTICLES);
    let most = settings.adaptive.map_or(settings.particles, |a| a.max.max(settings.particles));
    if most == 0 || most > max_particles {
        return Err(BoardError::Limit(format!(
            "{most} particles: the board weighs 1 to {max_particles} per iteration"
        )));
    }
    let max_scan = (identity.max_scan as usize).min(BOARD_MAX_STORE_POINTS);
    let sample_len = scan.len().min(settings.weight_points);
    if sample_len > max_scan {
        return Err(BoardError::Limit(format!(
            "the weight sample has {sample_len} scan points; the board holds at most {max_scan} (lower weight_points)"
        )));
    }
    let model = nn.points();
    let max_model = (identity.max_model as usize).min(BOARD_MAX_STORE_POINTS);
    let board_points = board_model(model, max_model, settings.seed);
    let model_norm = Normalisation::of(model);
    let scan_norm = Normalisation::of(scan);
    let model_q = model_norm.quantise(&board_points);
    let grid = if capabilities(identity.version).grid_with_normals {
        let grid = board_grid(&model_q)?;
        let normals = stored_normals(&grid);
        Some((grid, normals))
    } else {
        None
    };
    let source = BoardWeights {
        model: model_q,
        grid,
        client: Mutex::new(client),
        progress: Mutex::new(progress),
        cap: settings.iterations,
        model_norm,
        scan_norm,
        sample: Mutex::new(0),
        iterations: Mutex::new(0),
    };
    let pf = register_with(nn, scan, settings, Some(&source)).map_err(|e| match e.downcast::<BoardError>() {
        Ok(b) => *b,
        Err(other) => BoardError::Filter(other.to_string()),
    })?;
    let BoardWeights { client, sample, iterations, .. } = source;
    let client = client.into_inner().expect("not poisoned");
    Ok(BoardPfResult {
        pf,
        board: BoardReport {
            identity,
            model_points: board_points.len(),
            model_subsampled: board_points.len() < model.len(),
            scan_points: sample.into_inner().expect("not poisoned"),
            iterations: iterations.into_inner().expect("not poisoned"),
            stats: client.stats(),
        },
    })
}
