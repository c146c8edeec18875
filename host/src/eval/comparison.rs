//! Tables 4 to 7: PF-ICP against the baselines on the Table 1 transforms.
//!
//! - Table 4: model-1, paper setting; PF-ICP (K = 100, 50 particles, 50 iterations),
//!   Welsch, Cauchy and plain ICP.
//! - Table 5: model-2, paper setting; PF-ICP with K = 10.
//! - Table 6: model-1, paper setting plus noise `U(0, 0.1)` per coordinate; Sparse ICP.
//! - Table 7: model-3, thin scan of half as many points as the model; PF-ICP (K = 200,
//!   80 particles, 100 iterations) against EM-ICP (100 iterations).
//!
//! The baselines start from the identity and share PF-ICP's iteration cap
//! ([`crate::registration::methods::run`]). Each estimate is also checked against
//! [`Tolerance::PAPER`] and [`Tolerance::SUCCESS`].

use super::text_table::{num, TextTable};
use super::{judge, paper_order, EvalOptions, Judged, ROW_DECIMALS, ROW_LABELS};
use crate::cloud::bbox_diagonal;
use crate::datasets::{make, ModelId, Sampling, ScanSpec};
use crate::geometry::PoseRecord;
use crate::nn::NearestNeighbours;
use crate::pf_icp::PfIcpSettings;
use crate::registration::methods::{Method, MethodSettings, Tolerance};
use serde::Serialize;

/// One method's column.
#[derive(Clone, Debug, Serialize)]
pub struct MethodEstimate {
    /// CLI name of the method ([`Method::name`]).
    pub method: String,
    /// Column header.
    pub label: String,
    /// The estimate.
    pub pose: PoseRecord,
    /// The estimate in table order (angles in degrees).
    pub values: [f64; 7],
    /// MSD over the whole scan.
    pub msd: f64,
    /// Iterations.
    pub iterations: usize,
    /// Wall time (s).
    pub seconds: f64,
    /// Within [`Tolerance::PAPER`].
    pub within_paper: bool,
    /// Within [`Tolerance::SUCCESS`].
    pub within_success: bool,
    /// Angle of the relative rotation to the truth (deg).
    pub rotation_error_deg: f64,
    /// Largest Euler-angle error (deg).
    pub max_euler_error_deg: f64,
    /// Translation error over the diagonal.
    pub translation_error_frac: f64,
    /// Relative scale error.
    pub scale_error_frac: f64,
}

/// Table 4, 5, 6 or 7.
#[derive(Clone, Debug, Serialize)]
pub struct ComparisonTable {
    /// `table4` .. `table7`.
    pub id: String,
    /// Title line.
    pub title: String,
    /// Model name.
    pub model: String,
    /// Scan description.
    pub setting: String,
    /// Model points.
    pub model_points: usize,
    /// Scan points.
    pub scan_points: usize,
    /// Model bounding-box diagonal (for the tolerances).
    pub diagonal: f64,
    /// The truth.
    pub truth: PoseRecord,
    /// The truth in table order.
    pub truth_values: [f64; 7],
    /// Clusters PF-ICP actually used (its request clamped to a tenth of the smaller cloud).
    pub pf_clusters: usize,
    /// One column per method.
    pub estimates: Vec<MethodEstimate>,
}

/// One table to make.
struct Case {
    no: u32,
    model: ModelId,
    sampling: Sampling,
    noise: f64,
    clusters: usize,
    particles: usize,
    iterations: usize,
    methods: &'static [Method],
    paper: &'static str,
}

fn cases(opts: &EvalOptions) -> [Case; 4] {
    [
        Case {
            no: 4,
            model: ModelId::Model1,
            sampling: Sampling::Paper,
            noise: 0.0,
            clusters: 100,
            particles: 50,
            iterations: 50,
            methods: &[Method::PfIcp, Method::Welsch, Method::Cauchy, Method::Icp],
            paper: "PF-ICP vs ICP with Welsch / Cauchy weights (plain ICP added)",
        },
        Case {
            no: 5,
            model: ModelId::Model2,
            sampling: Sampling::Paper,
            noise: 0.0,
            clusters: 10,
            particles: 50,
            iterations: 50,
            methods: &[Method::PfIcp, Method::Welsch, Method::Cauchy, Method::Icp],
            paper: "PF-ICP vs ICP with Welsch / Cauchy weights (plain ICP added)",
        },
        Case {
            no: 6,
            model: ModelId::Model1,
            sampling: Sampling::Paper,
            noise: 0.1,
            clusters: 100,
            particles: 50,
            iterations: 50,
            methods: &[Method::PfIcp, Method::SparseIcp],
            paper: "PF-ICP vs Sparse ICP, noisy scan",
        },
        Case {
            no: 7,
            model: ModelId::Model3,
            sampling: Sampling::Thin { points: (opts.model_points / 2).max(30) },
            noise: 0.0,
            clusters: 200,
            particles: 80,
            iterations: 100,
            methods: &[Method::PfIcp, Method::EmIcp],
            paper: "PF-ICP vs EM-ICP, thin scan",
        },
    ]
}

fn label(m: Method, c: &Case) -> String {
    match m {
        Method::PfIcp => format!("PF-ICP K={} n={}", c.clusters, c.particles),
        Method::Icp => "ICP".into(),
        Method::Welsch => "ICP Welsch".into(),
        Method::Cauchy => "ICP Cauchy".into(),
        Method::SparseIcp => "Sparse ICP".into(),
        Method::EmIcp => "EM-ICP".into(),
    }
}

fn setting_text(c: &Case) -> String {
    let s = match c.sampling {
        Sampling::Paper => "paper setting (scan = model points)".to_string(),
        Sampling::Independent { points } => format!("independent scan of {points} points"),
        Sampling::Thin { points } => format!("thin uneven scan of {points} points"),
    };
    if c.noise > 0.0 {
        format!("{s}, noise U(0, {})", c.noise)
    } else {
        s
    }
}

fn table(c: &Case, opts: &EvalOptions) -> ComparisonTable {
    let truth = c.model.table1_truth();
    let ds =
        make(c.model, opts.model_points, &truth, &ScanSpec { sampling: c.sampling, noise: c.noise, seed: opts.seed });
    let nn = NearestNeighbours::new(&ds.model);
    let diag = bbox_diagonal(&ds.model);
    let settings = MethodSettings {
        pf: PfIcpSettings {
            clusters: c.clusters,
            particles: c.particles,
            iterations: c.iterations,
            seed: opts.seed,
            ..Default::default()
        },
    };
    let estimates = c
        .methods
        .iter()
        .map(|&m| {
            let Judged { outcome: o, success, error: e } = judge(m, &nn, &ds.scan, &settings, &truth, diag);
            let p = o.registration.pose;
            MethodEstimate {
                method: m.name().to_string(),
                label: label(m, c),
                pose: p.record(),
                values: paper_order(&p.to_params()),
                msd: o.registration.msd,
                iterations: o.registration.iterations,
                seconds: o.elapsed.as_secs_f64(),
                within_paper: Tolerance::PAPER.accepts(&p, &truth, diag),
                within_success: success,
                rotation_error_deg: e.rotation_deg,
                max_euler_error_deg: e.max_euler_deg,
                translation_error_frac: e.translation_frac,
                scale_error_frac: e.scale_frac,
            }
        })
        .collect();
    let pf_clusters = c.clusters.min(ds.scan.len().min(ds.model.len()) / 10).max(3);
    ComparisonTable {
        id: format!("table{}", c.no),
        title: format!(
            "Table {}: {}, {}, {}, {} model / {} scan points",
            c.no,
            c.paper,
            c.model.name(),
            setting_text(c),
            ds.model.len(),
            ds.scan.len()
        ),
        model: c.model.name().to_string(),
        setting: setting_text(c),
        model_points: ds.model.len(),
        scan_points: ds.scan.len(),
        diagonal: diag,
        truth: truth.record(),
        truth_values: paper_order(&truth.to_params()),
        pf_clusters,
        estimates,
    }
}

/// Tables 4 to 7 (progress on stderr).
pub fn run(opts: &EvalOptions) -> Vec<ComparisonTable> {
    let cases = cases(opts);
    let start = std::time::Instant::now();
    let bar = crate::progress::Progress::bar("[eval] Tables 4-7", cases.len() as u64, "tables");
    let tables = cases
        .iter()
        .map(|c| {
            bar.message(format!("Table {} ({})", c.no, c.model.name()));
            let t = table(c, opts);
            bar.inc();
            t
        })
        .collect();
    bar.finish(format_args!("[eval] Tables 4 to 7 ({:.1} s)", start.elapsed().as_secs_f64()));
    tables
}

impl ComparisonTable {
    /// The table as text.
    pub fn render(&self) -> String {
        let mut header = vec!["parameter".to_string()];
        header.extend(self.estimates.iter().map(|e| e.label.clone()));
        header.push("truth".into());
        let mut t = TextTable::new(self.title.clone(), header);
        for i in 0..7 {
            let d = ROW_DECIMALS[i];
            let mut row = vec![ROW_LABELS[i].to_string()];
            row.extend(self.estimates.iter().map(|e| num(e.values[i], d)));
            row.push(num(self.truth_values[i], d));
            t.row(row);
        }
        let mut extra = |name: &str, f: &dyn Fn(&MethodEstimate) -> String| {
            let mut row = vec![name.to_string()];
            row.extend(self.estimates.iter().map(f));
            t.row(row);
        };
        let yes = |b: bool| if b { "yes" } else { "no" }.to_string();
        extra("MSD", &|e| format!("{:.3e}", e.msd));
        extra("iterations", &|e| e.iterations.to_string());
        extra("time (s)", &|e| format!("{:.3}", e.seconds));
        extra("max angle err (deg)", &|e| format!("{:.2}", e.max_euler_error_deg));
        extra("within PAPER tol", &|e| yes(e.within_paper));
        extra("within SUCCESS tol", &|e| yes(e.within_success));
        t.note(format!(
            "PAPER tol: {} deg, {}% of the diagonal ({:.3}), {}% scale; SUCCESS tol: {} deg, {}%, {}%",
            Tolerance::PAPER.deg,
            100.0 * Tolerance::PAPER.t_frac,
            self.diagonal,
            100.0 * Tolerance::PAPER.s_frac,
            Tolerance::SUCCESS.deg,
            100.0 * Tolerance::SUCCESS.t_frac,
            100.0 * Tolerance::SUCCESS.s_frac,
        ));
        t.note(format!(
            "PF-ICP used K = {} clusters (K is capped at a tenth of the smaller cloud); baselines start from the identity",
            self.pf_clusters
        ));
        t.render()
    }
}
