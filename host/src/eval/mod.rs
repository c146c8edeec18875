//! The paper's experiments (section 4): Tables 2 to 7, success rates over random
//! transforms, and Figs. 9, 12 and 15, in one call: [`run`].
//!
//! - [`covariance_tables`]: Tables 2 and 3, the start and Algorithm 5's spread against the
//!   Hessian estimate (paper setting, plus the same for an independently sampled scan,
//!   since the paper setting makes the spread vanish).
//! - [`comparison`]: Tables 4 to 7, PF-ICP against the baselines on the Table 1 transforms.
//! - [`success`]: success rates of every method over random transforms and noise.
//! - [`plots`]: the SVG figures.
//!
//! Tables go to stdout, progress to stderr, numbers into [`EvalReport`] and
//! `out_dir/results.json`. Everything but the wall times is a function of the options.

pub mod comparison;
pub mod covariance_tables;
pub mod plots;
pub mod realistic;
pub mod success;
mod text_table;
pub mod tracking;

use crate::geometry::{param, Params, Pose};
use crate::nn::NearestNeighbours;
use crate::registration::methods::{run as run_method, Method, MethodSettings, Outcome, PoseError, Tolerance};
use anyhow::Context;
use nalgebra::Point3;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

pub use comparison::{ComparisonTable, MethodEstimate};
pub use covariance_tables::{Algorithm5Column, CovarianceTable};
pub use success::{SuccessCell, SuccessReport, SuccessRow, TrialMethodResult, TrialRecord};

/// What to run and where to write.
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Plots and `results.json` go here (created if missing).
    pub out_dir: PathBuf,
    /// Random transforms per model for the success rates.
    pub trials: usize,
    /// Points of each model cloud.
    pub model_points: usize,
    /// Points of each independently sampled scan (success rates, Table 2/3 second block).
    pub scan_points: usize,
    /// Seed of every random choice.
    pub seed: u64,
    /// Print Tables 2 to 7.
    pub tables: bool,
    /// Run the success-rate experiment.
    pub success: bool,
    /// Write the SVG figures.
    pub plots: bool,
    /// Methods in the success-rate table.
    pub methods: Vec<Method>,
    /// Also PF-ICP with the filter on the board in the success-rate table, the board's part
    /// by its bit-exact reference ([`BOARD_COLUMN`], [`BOARD_FILTER_COLUMN`]).
    pub board: bool,
    /// Scan points the on-board filter weighs each particle over, with `board`.
    pub board_points: usize,
}

/// Name of the on-board column: the board's filter and its on-board polish, then the host's
/// polish (`pficp register --board`'s pose).
pub const BOARD_COLUMN: &str = "pf-icp-board";
/// Name of the column of the board's pose alone: its filter and its on-board polish, no
/// polish on the host.
pub const BOARD_FILTER_COLUMN: &str = "pf-icp-board-filter";

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            out_dir: PathBuf::from("eval-out"),
            trials: 100,
            model_points: 2000,
            scan_points: 2000,
            seed: 1,
            tables: true,
            success: true,
            plots: true,
            methods: Method::ALL.to_vec(),
            board: false,
            board_points: crate::board::on_board::DEFAULT_BOARD_POINTS,
        }
    }
}

/// Everything [`run`] measured (also written to `out_dir/results.json`).
#[derive(Clone, Debug, Serialize)]
pub struct EvalReport {
    /// The seed used.
    pub seed: u64,
    /// Points of each model cloud.
    pub model_points: usize,
    /// Points of each independent scan.
    pub scan_points: usize,
    /// Tables 2 and 3 (paper setting, then independent scans).
    pub covariance_tables: Vec<CovarianceTable>,
    /// Tables 4 to 7.
    pub comparison_tables: Vec<ComparisonTable>,
    /// Success rates, when run.
    pub success: Option<SuccessReport>,
    /// Paths of the figures written.
    pub plots: Vec<String>,
    /// Path of `results.json`.
    pub results_path: String,
    /// Wall time of the whole run (s).
    pub seconds: f64,
}

impl EvalReport {
    /// The comparison table with this id (`"table4"` to `"table7"`).
    pub fn comparison(&self, id: &str) -> Option<&ComparisonTable> {
        self.comparison_tables.iter().find(|t| t.id == id)
    }

    /// The covariance table with this id (`"table2"`, `"table3"`, `"table2-independent"`,
    /// `"table3-independent"`).
    pub fn covariance(&self, id: &str) -> Option<&CovarianceTable> {
        self.covariance_tables.iter().find(|t| t.id == id)
    }
}

/// Run the experiments selected in `opts`: print the tables, write the figures and
/// `results.json`, return the numbers.
pub fn run(opts: &EvalOptions) -> anyhow::Result<EvalReport> {
    anyhow::ensure!(
        opts.model_points >= 30 && opts.scan_points >= 30,
        "model_points and scan_points must be at least 30"
    );
    let start = Instant::now();
    std::fs::create_dir_all(&opts.out_dir).with_context(|| format!("creating {}", opts.out_dir.display()))?;
    let mut report = EvalReport {
        seed: opts.seed,
        model_points: opts.model_points,
        scan_points: opts.scan_points,
        covariance_tables: Vec::new(),
        comparison_tables: Vec::new(),
        success: None,
        plots: Vec::new(),
        results_path: String::new(),
        seconds: 0.0,
    };
    if opts.tables {
        for t in covariance_tables::run(opts) {
            println!("{}", t.render());
            report.covariance_tables.push(t);
        }
        for t in comparison::run(opts) {
            println!("{}", t.render());
            report.comparison_tables.push(t);
        }
    }
    if opts.success && opts.trials > 0 && (!opts.methods.is_empty() || opts.board) {
        let s = success::run(opts)?;
        println!("{}", s.render());
        report.success = Some(s);
    }
    if opts.plots {
        report.plots = plots::run(opts)?;
        for p in &report.plots {
            crate::progress::note(format_args!("wrote {p}"));
        }
    }
    let path = opts.out_dir.join("results.json");
    report.results_path = path.display().to_string();
    report.seconds = start.elapsed().as_secs_f64();
    let json = serde_json::to_string_pretty(&report)?;
    std::fs::write(&path, json).with_context(|| format!("writing {}", path.display()))?;
    crate::progress::note(format_args!("wrote {}", path.display()));
    Ok(report)
}

/// Row labels of the paper's tables, in their order.
pub const ROW_LABELS: [&str; 7] = ["phi (deg)", "theta (deg)", "psi (deg)", "tx", "ty", "tz", "scale"];

/// Decimals printed per row.
pub(crate) const ROW_DECIMALS: [usize; 7] = [3, 3, 3, 4, 4, 4, 4];

/// Parameters `[a, b, c, s, phi, theta, psi]` (radians) in the tables' order
/// `[phi, theta, psi, tx, ty, tz, scale]`, angles in degrees. Also right for standard
/// deviations.
pub fn paper_order(p: &Params) -> [f64; 7] {
    [
        p[param::PHI].to_degrees(),
        p[param::THETA].to_degrees(),
        p[param::PSI].to_degrees(),
        p[param::A],
        p[param::B],
        p[param::C],
        p[param::S],
    ]
}

/// One method's run on a scan, judged against the truth (as the tables and the trials
/// record it).
pub(crate) struct Judged {
    /// The run.
    pub outcome: Outcome,
    /// Within [`Tolerance::SUCCESS`].
    pub success: bool,
    /// The estimate's errors.
    pub error: PoseError,
}

/// Run `method` on `scan` and judge its pose against `truth` (`diag`: the model's diagonal).
pub(crate) fn judge(
    method: Method,
    nn: &NearestNeighbours,
    scan: &[Point3<f64>],
    settings: &MethodSettings,
    truth: &Pose,
    diag: f64,
) -> Judged {
    let outcome = run_method(method, nn, scan, settings);
    let p = outcome.registration.pose;
    Judged { success: Tolerance::SUCCESS.accepts(&p, truth, diag), error: PoseError::between(&p, truth, diag), outcome }
}

/// Mix two numbers into a seed (splitmix64 of their combination).
pub(crate) fn mix(a: u64, b: u64) -> u64 {
    let mut z = a.wrapping_mul(0x9e37_79b9_7f4a_7c15).wrapping_add(b).wrapping_add(0x632b_e59b_d9b4_e019);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Median of a slice (`NaN` if empty).
pub(crate) fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Pose;
    use crate::registration::methods::Tolerance;

    #[test]
    fn tiny_run_reproduces_the_papers_point() {
        let dir = tempfile::tempdir().unwrap();
        let opts = EvalOptions {
            out_dir: dir.path().join("out"),
            trials: 2,
            model_points: 600,
            scan_points: 600,
            seed: 1,
            ..Default::default()
        };
        let report = run(&opts).unwrap();

        let t4 = report.comparison("table4").expect("table 4");
        let truth = Pose::from_record(&t4.truth);
        let est = |m: Method| {
            t4.estimates.iter().find(|e| e.method == m.name()).unwrap_or_else(|| panic!("{} in table 4", m.name()))
        };
        let pf = Pose::from_record(&est(Method::PfIcp).pose);
        assert!(
            Tolerance::PAPER.accepts(&pf, &truth, t4.diagonal),
            "PF-ICP {:?} vs truth {:?}",
            pf.euler_deg(),
            truth.euler_deg()
        );
        for m in [Method::Welsch, Method::Icp] {
            let psi = Pose::from_record(&est(m).pose).euler_deg()[2];
            let err = (psi - truth.euler_deg()[2]).abs();
            assert!(err > 2.0, "{} psi {psi} is within 2 deg of the truth", m.name());
        }

        let s = report.success.as_ref().expect("success rates");
        assert_eq!(s.rows.len(), 6);
        assert!(s.rows.iter().all(|r| r.cells.len() == Method::ALL.len()));

        for name in
            ["fig15_error_per_iteration.svg", "fig9_distance_vs_drift_model1.svg", "fig12_distance_vs_drift_model2.svg"]
        {
            let text = std::fs::read_to_string(opts.out_dir.join(name)).unwrap();
            assert!(text.trim_start().starts_with("<svg"), "{name}");
        }
        let json = std::fs::read_to_string(opts.out_dir.join("results.json")).unwrap();
        let v: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert!(v["comparison_tables"].as_array().unwrap().len() == 4);
    }
}
