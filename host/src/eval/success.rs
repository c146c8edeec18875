//! Success rates over random transforms (not in the paper; the experiment).
//!
//! For each model and each noise level (none, and `U(0, 1%)` of the model's bounding-box
//! diagonal per coordinate), `trials` transforms are drawn with
//! [`crate::datasets::random_truth`] (angles within +-45 deg, scale in 0.7..1.3,
//! translation within half the diagonal) from a generator seeded by the seed and the
//! model, so both noise levels see the same transforms. Each trial scans the model
//! independently ([`Sampling::Independent`]) with its own seed and runs every method
//! ([`crate::registration::methods::run`], PF-ICP seeded by the trial). Success is
//! [`Tolerance::SUCCESS`]. Trials run one after another (the methods use rayon inside),
//! so the counts are a function of the seed.

use super::text_table::TextTable;
use super::{judge, median, mix, paper_order, EvalOptions, Judged, BOARD_COLUMN, BOARD_FILTER_COLUMN};
use crate::cloud::bbox_diagonal;
use crate::datasets::{make, random_truth, ModelId, Sampling, ScanSpec};
use crate::geometry::Pose;
use crate::nn::NearestNeighbours;
use crate::pf_icp::PfIcpSettings;
use crate::progress::Progress;
use crate::registration::methods::{MethodSettings, PoseError, Tolerance};
use anyhow::Context;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::time::Instant;

/// Largest angle of the random transforms (deg).
pub const MAX_ANGLE_DEG: f64 = 45.0;
/// Scale range of the random transforms.
pub const SCALE_RANGE: (f64, f64) = (0.7, 1.3);
/// Noise levels, as fractions of the model's diagonal.
pub const NOISE_FRACTIONS: [f64; 2] = [0.0, 0.01];

/// One method in one trial.
#[derive(Clone, Debug, Serialize)]
pub struct TrialMethodResult {
    /// Method name.
    pub method: String,
    /// Within [`Tolerance::SUCCESS`].
    pub success: bool,
    /// Angle of the relative rotation (deg).
    pub rotation_error_deg: f64,
    /// Largest Euler-angle error (deg).
    pub max_euler_error_deg: f64,
    /// Translation error over the diagonal.
    pub translation_error_frac: f64,
    /// Relative scale error.
    pub scale_error_frac: f64,
    /// Wall time (s).
    pub seconds: f64,
}

/// One trial.
#[derive(Clone, Debug, Serialize)]
pub struct TrialRecord {
    /// Seed of the scan and of PF-ICP.
    pub seed: u64,
    /// The truth, table order (angles in degrees).
    pub truth: [f64; 7],
    /// Noise amplitude in scan units.
    pub noise: f64,
    /// One entry per method.
    pub results: Vec<TrialMethodResult>,
}

/// One method's count in one row.
#[derive(Clone, Debug, Serialize)]
pub struct SuccessCell {
    /// Method name.
    pub method: String,
    /// Successful trials.
    pub successes: usize,
    /// Trials.
    pub trials: usize,
    /// `successes / trials`.
    pub rate: f64,
    /// Median wall time (s).
    pub median_seconds: f64,
}

/// One model and noise level.
#[derive(Clone, Debug, Serialize)]
pub struct SuccessRow {
    /// Model name.
    pub model: String,
    /// Noise as a fraction of the model's diagonal.
    pub noise_fraction: f64,
    /// One cell per method.
    pub cells: Vec<SuccessCell>,
    /// Every trial.
    pub trials: Vec<TrialRecord>,
}

/// The success-rate experiment.
#[derive(Clone, Debug, Serialize)]
pub struct SuccessReport {
    /// Trials per row.
    pub trials: usize,
    /// Points per model.
    pub model_points: usize,
    /// Points per scan.
    pub scan_points: usize,
    /// Methods, in column order.
    pub methods: Vec<String>,
    /// Rows: models x noise levels.
    pub rows: Vec<SuccessRow>,
    /// Median wall time per method over every trial (s).
    pub median_seconds: Vec<f64>,
}

/// The table's columns: the methods, then the board's two when asked for.
fn columns(opts: &EvalOptions) -> Vec<String> {
    let mut v: Vec<String> = opts.methods.iter().map(|m| m.name().to_string()).collect();
    if opts.board {
        v.extend([BOARD_COLUMN.to_string(), BOARD_FILTER_COLUMN.to_string()]);
    }
    v
}

fn row(id: ModelId, noise_fraction: f64, opts: &EvalOptions, bar: &Progress) -> anyhow::Result<SuccessRow> {
    let model_index = ModelId::ALL.iter().position(|&m| m == id).unwrap_or(0) as u64;
    let model_seed = mix(opts.seed, model_index + 1);
    let model = id.model_points(opts.model_points);
    let diag = bbox_diagonal(&model);
    let nn = NearestNeighbours::new(&model);
    let mut rng = ChaCha8Rng::seed_from_u64(model_seed);
    let start = Instant::now();
    let mut trials = Vec::with_capacity(opts.trials);
    for t in 0..opts.trials {
        let truth = random_truth(&mut rng, MAX_ANGLE_DEG, SCALE_RANGE, diag / 2.0);
        let seed = mix(model_seed, t as u64 + 1);
        let noise = noise_fraction * diag / truth.scale;
        let ds = make(
            id,
            opts.model_points,
            &truth,
            &ScanSpec { sampling: Sampling::Independent { points: opts.scan_points }, noise, seed },
        );
        let settings = MethodSettings { pf: PfIcpSettings { seed, ..Default::default() } };
        let result = |method: &str, pose: &Pose, seconds: f64| {
            let e = PoseError::between(pose, &truth, diag);
            TrialMethodResult {
                method: method.to_string(),
                success: Tolerance::SUCCESS.accepts(pose, &truth, diag),
                rotation_error_deg: e.rotation_deg,
                max_euler_error_deg: e.max_euler_deg,
                translation_error_frac: e.translation_frac,
                scale_error_frac: e.scale_frac,
                seconds,
            }
        };
        let mut results: Vec<TrialMethodResult> = opts
            .methods
            .iter()
            .map(|&m| {
                let Judged { outcome, .. } = judge(m, &nn, &ds.scan, &settings, &truth, diag);
                result(m.name(), &outcome.registration.pose, outcome.elapsed.as_secs_f64())
            })
            .collect();
        if opts.board {
            let t0 = Instant::now();
            let pf = crate::board::on_board::emulate_registration(&nn, &ds.scan, &settings.pf, opts.board_points)
                .with_context(|| format!("{} trial {t}: the board's emulation", id.name()))?;
            let seconds = t0.elapsed().as_secs_f64();
            results.push(result(BOARD_COLUMN, &pf.registration.pose, seconds));
            results.push(result(BOARD_FILTER_COLUMN, &pf.filter_pose, seconds));
        }
        trials.push(TrialRecord { seed, truth: paper_order(&truth.to_params()), noise, results });
        bar.inc();
        if t + 1 == opts.trials {
            bar.println(format_args!(
                "[eval] success {} noise {:.0}%: {} trials ({:.1} s)",
                id.name(),
                100.0 * noise_fraction,
                opts.trials,
                start.elapsed().as_secs_f64()
            ));
        }
    }
    let cells = columns(opts)
        .into_iter()
        .enumerate()
        .map(|(j, m)| {
            let successes = trials.iter().filter(|t| t.results[j].success).count();
            let times: Vec<f64> = trials.iter().map(|t| t.results[j].seconds).collect();
            SuccessCell {
                method: m,
                successes,
                trials: trials.len(),
                rate: successes as f64 / trials.len().max(1) as f64,
                median_seconds: median(&times),
            }
        })
        .collect();
    Ok(SuccessRow { model: id.name().to_string(), noise_fraction, cells, trials })
}

/// Run the experiment (progress on stderr). Fails only where the board's emulation refuses
/// a model (with `board`).
pub fn run(opts: &EvalOptions) -> anyhow::Result<SuccessReport> {
    let mut rows = Vec::new();
    let total = ModelId::ALL.len() * NOISE_FRACTIONS.len() * opts.trials;
    let bar = Progress::bar("[eval] success", total as u64, "trials");
    for id in ModelId::ALL {
        for noise in NOISE_FRACTIONS {
            bar.message(format!("{} noise {:.0}%", id.name(), 100.0 * noise));
            rows.push(row(id, noise, opts, &bar)?);
        }
    }
    bar.clear();
    let median_seconds = (0..columns(opts).len())
        .map(|j| {
            let times: Vec<f64> =
                rows.iter().flat_map(|r| r.trials.iter().map(move |t| t.results[j].seconds)).collect();
            median(&times)
        })
        .collect();
    Ok(SuccessReport {
        trials: opts.trials,
        model_points: opts.model_points,
        scan_points: opts.scan_points,
        methods: columns(opts),
        rows,
        median_seconds,
    })
}

impl SuccessReport {
    /// The table as text.
    pub fn render(&self) -> String {
        let mut header = vec!["model / noise".to_string()];
        header.extend(self.methods.iter().cloned());
        let mut t = TextTable::new(
            format!(
                "Success rates (not in the paper): {} random transforms per row (angles +-{MAX_ANGLE_DEG} deg, scale {}..{}, |T| <= diag/2), independent scans, {} model / {} scan points",
                self.trials, SCALE_RANGE.0, SCALE_RANGE.1, self.model_points, self.scan_points
            ),
            header,
        );
        for r in &self.rows {
            let mut row = vec![format!("{} / {:.0}% diag", r.model, 100.0 * r.noise_fraction)];
            row.extend(r.cells.iter().map(|c| format!("{}/{} ({:.0}%)", c.successes, c.trials, 100.0 * c.rate)));
            t.row(row);
        }
        let mut row = vec!["median time (s)".to_string()];
        row.extend(self.median_seconds.iter().map(|s| format!("{s:.3}")));
        t.row(row);
        t.note(format!(
            "success: within {} deg (relative rotation and each Euler angle), {}% of the diagonal, {}% scale; noise U(0, a) per coordinate",
            Tolerance::SUCCESS.deg,
            100.0 * Tolerance::SUCCESS.t_frac,
            100.0 * Tolerance::SUCCESS.s_frac
        ));
        t.render()
    }
}
