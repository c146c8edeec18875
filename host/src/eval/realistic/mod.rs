//! The realistic benchmark (`pficp eval --suite realistic`): registration on shapes and
//! views nobody tuned for.
//!
//! **Shapes**: real scanned objects and CAD parts that public packages ship
//! ([`crate::real_shapes`], sources and licences in `host/data/realistic/SOURCES.md`) and
//! synthetic near-symmetric and exactly symmetric parts ([`crate::parts`]). Each shape is
//! either a development shape (tuning may look at it) or held out (looked at only to
//! report); the `dev` split draws only development shapes, the `test` split every shape,
//! with other seeds.
//!
//! **Families** ([`Family`]), each case under a random truth (scan to model):
//! - `real`: a real shape, a partial view (a plane cut keeping 60 to 80% of the surface,
//!   the kept side facing a random direction), Gaussian noise of 0.5% of the model's
//!   diagonal per coordinate, angles uniform in +-60 deg per axis, scale 0.7 to 1.3,
//!   translation in a ball of half the diagonal;
//! - `real-outliers`: the same plus 5% outliers (uniform in the view's bounding box grown
//!   by 10% of the diagonal);
//! - `parts`: a synthetic part, the whole surface sampled independently, 0.5% noise, the
//!   same transforms;
//! - `hard-180`: real shapes (partial) and parts (whole), any rotation (uniform on SO(3)).
//!
//! The model is 2,000 points of the surface, the scan about 1,000 points drawn
//! independently of them (disjoint points of a real shape's stored sample; fresh surface
//! samples of a part) before the cut, the noise and the outliers.
//!
//! **Scoring** ([`score`]): rotation within 2 deg (angle of the relative rotation),
//! translation within 2% of the diagonal, measured where it matters (the distance between
//! the scan's centroid mapped by the estimate and by the truth), scale within 1%. A shape
//! with exact symmetries is scored modulo its group: the case succeeds if the estimate is
//! within tolerance of any symmetric copy of the truth.
//!
//! Every case is a function of the seed, the split, the family and its index.

mod camera;
mod cases;
mod scoring;

pub use camera::{camera_view, CameraView};

pub use cases::*;
pub use scoring::*;

use super::text_table::TextTable;
use super::{median, mix};
use crate::cloud::centroid;
use crate::geometry::{Pose, ScaleBounds};
use crate::nn::NearestNeighbours;
use crate::pf_icp::conclusion::Conclusion;
use crate::pf_icp::surface::Surface;
use crate::pf_icp::verdict::Verdict;
use crate::pf_icp::PfIcpSettings;
use crate::progress::Progress;
use crate::registration::methods::{run as run_method, Method, MethodSettings};
use anyhow::Context;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to run.
#[derive(Clone, Debug)]
pub struct RealisticOptions {
    /// Cases per family.
    pub cases: usize,
    /// Seed of every case.
    pub seed: u64,
    /// Shapes and seeds.
    pub split: Split,
    /// Families to run.
    pub families: Vec<Family>,
    /// Methods to run on each case.
    pub methods: Vec<Method>,
    /// PF-ICP's settings (the seed is replaced by each case's).
    pub pf: PfIcpSettings,
    /// Also run PF-ICP with the filter on the board (column `pf-icp-board`): the host's
    /// prior and conclusion around `fpga::pf::run`, the bit-exact reference of the board's
    /// filter (what the board computes, byte for byte: the grid search over the gridded
    /// model), with `board_points` scan points and at most [`crate::board::BOARD_MAX_STORE_POINTS`]
    /// model points; and the board's pose alone, without the host's polish (column
    /// `pf-icp-board-filter`).
    pub board: bool,
    /// The board's scan sample with `board`
    /// ([`crate::board::on_board::DEFAULT_BOARD_POINTS`] by default).
    pub board_points: usize,
    /// Write `realistic.json` here (created if missing).
    pub out_dir: Option<PathBuf>,
    /// Export the cases (clouds and `cases.json`) for the peers' script here.
    pub export: Option<PathBuf>,
    /// Progress on stderr.
    pub progress: bool,
    /// Give PF-ICP the camera's position in the camera-view families (`--viewpoint`, as a
    /// depth camera's scans in its own frame give it).
    pub viewpoint: bool,
}

impl Default for RealisticOptions {
    fn default() -> Self {
        Self {
            cases: 100,
            seed: 1,
            split: Split::Test,
            families: Family::ALL.to_vec(),
            methods: vec![Method::PfIcp],
            pf: PfIcpSettings::default(),
            board: false,
            board_points: crate::board::on_board::DEFAULT_BOARD_POINTS,
            out_dir: None,
            export: None,
            progress: true,
            viewpoint: true,
        }
    }
}

/// One method on one case.
#[derive(Clone, Debug, Serialize)]
pub struct CaseResult {
    /// Method name.
    pub method: String,
    /// Errors and verdict.
    pub score: Score,
    /// Wall time of the registration [s].
    pub seconds: f64,
    /// PF-ICP only: alternatives it reported.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alternatives: Option<usize>,
    /// PF-ICP only: squared Mahalanobis distance of the error (against the nearest
    /// symmetric truth) under the reported covariance, over the determined parameters.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mahalanobis2: Option<f64>,
    /// PF-ICP only: the number of determined parameters (the chi-square's degrees of freedom).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dof: Option<usize>,
    /// PF-ICP only: the truth lies inside the reported 95% region.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inside_95: Option<bool>,
    /// Capped surface cost of the estimate on the whole scan ([`crate::pf_icp::surface::Surface::cost`],
    /// cap 5% of the diagonal), to compare with the truth's.
    pub cost: f64,
    /// PF-ICP only: its verdict ([`crate::pf_icp::verdict`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verdict: Option<Verdict>,
    /// PF-ICP only: the verdict's reasons.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reasons: Option<Vec<String>>,
    /// PF-ICP only: what the verdict was judged on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub checks: Option<crate::pf_icp::verdict::Checks>,
    /// PF-ICP only: some alternative is within the tolerance of (a symmetric copy of) the truth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth_in_alternatives: Option<bool>,
}

impl CaseResult {
    /// A method without self-assessment.
    fn plain(method: &str, case: &Case, pose: &Pose, seconds: f64, surface: &Surface) -> Self {
        CaseResult {
            method: method.to_string(),
            score: score(pose, case),
            seconds,
            alternatives: None,
            mahalanobis2: None,
            dof: None,
            inside_95: None,
            cost: surface.cost(&case.scan, pose, 0.05 * case.diag),
            verdict: None,
            reasons: None,
            checks: None,
            truth_in_alternatives: None,
        }
    }

    /// PF-ICP's result with its conclusion (region, alternatives, verdict).
    fn assessed(method: &str, case: &Case, c: &Conclusion, seconds: f64, surface: &Surface) -> Self {
        let plain = Self::plain(method, case, &c.pose, seconds, surface);
        let g = case.shape.symmetries()[plain.score.symmetry];
        let truth = symmetric_truth(&case.truth, &g, &case.shape.centre());
        let md = mahalanobis2(c, &truth, &centroid(&case.scan));
        CaseResult {
            alternatives: Some(c.alternatives.len()),
            mahalanobis2: md.map(|m| m.0),
            dof: md.map(|m| m.1),
            inside_95: Some(md.is_some_and(|(d, k)| inside_95(d, k))),
            verdict: Some(c.verdict),
            reasons: Some(c.reasons.clone()),
            checks: Some(c.checks.clone()),
            truth_in_alternatives: Some(c.alternatives.iter().any(|a| score(&a.pose, case).success)),
            ..plain
        }
    }

    /// Right, or honestly flagged: `ambiguous` with the truth among the alternatives, or
    /// `unreliable` (`None` without a verdict).
    pub fn right_or_flagged(&self) -> Option<bool> {
        self.verdict.map(|v| {
            self.score.success
                || v == Verdict::Unreliable
                || (v == Verdict::Ambiguous && self.truth_in_alternatives == Some(true))
        })
    }

    /// Wrong and `confident`.
    pub fn confidently_wrong(&self) -> bool {
        self.verdict == Some(Verdict::Confident) && !self.score.success
    }
}

/// One case in the report.
#[derive(Clone, Debug, Serialize)]
pub struct CaseRecord {
    /// `family/shape/index`.
    pub id: String,
    /// Shape name.
    pub shape: String,
    /// Whether the shape is held out of tuning.
    pub held_out: bool,
    /// Seed.
    pub seed: u64,
    /// Visible fraction.
    pub visible: f64,
    /// Outliers.
    pub outliers: usize,
    /// Scan points.
    pub scan_points: usize,
    /// The truth, `[tx, ty, tz, s, phi, theta, psi]` (angles in degrees).
    pub truth: [f64; 7],
    /// Robust cost of the truth on the whole scan (as [`CaseResult::cost`]).
    pub truth_cost: f64,
    /// The same after the point-to-plane polish from the truth: what the true basin's
    /// optimum costs (an estimate below it fits the scan better than the truth's basin).
    pub truth_refined_cost: f64,
    /// One entry per method.
    pub results: Vec<CaseResult>,
}

/// One method's figures in one family.
#[derive(Clone, Debug, Serialize)]
pub struct FamilyCell {
    /// Method name.
    pub method: String,
    /// Successful cases.
    pub successes: usize,
    /// Cases.
    pub cases: usize,
    /// Successes among the held-out shapes' cases.
    pub held_out_successes: usize,
    /// Held-out shapes' cases.
    pub held_out_cases: usize,
    /// Median wall time [s].
    pub median_seconds: f64,
    /// Successful cases whose truth lies inside the reported 95% region (PF-ICP only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inside_95: Option<usize>,
    /// Cases that reported alternatives (PF-ICP only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub with_alternatives: Option<usize>,
    /// The verdicts against the outcome (PF-ICP only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verdicts: Option<VerdictTally>,
}

/// Verdict x outcome over a family's cases.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct VerdictTally {
    /// `confident` and right.
    pub confident_right: usize,
    /// `confident` and wrong: the case that must not happen.
    pub confident_wrong: usize,
    /// `ambiguous` and right.
    pub ambiguous_right: usize,
    /// `ambiguous`, wrong, the truth among the alternatives.
    pub ambiguous_truth_listed: usize,
    /// `ambiguous`, wrong, the truth not among the alternatives.
    pub ambiguous_wrong: usize,
    /// `unreliable` and right.
    pub unreliable_right: usize,
    /// `unreliable` and wrong.
    pub unreliable_wrong: usize,
    /// Right, or honestly flagged ([`CaseResult::right_or_flagged`]).
    pub right_or_flagged: usize,
}

impl VerdictTally {
    /// Count the results that carry a verdict.
    pub fn of<'a>(results: impl Iterator<Item = &'a CaseResult>) -> Self {
        let mut t = VerdictTally::default();
        for r in results {
            let Some(v) = r.verdict else { continue };
            let right = r.score.success;
            let slot = match (v, right) {
                (Verdict::Confident, true) => &mut t.confident_right,
                (Verdict::Confident, false) => &mut t.confident_wrong,
                (Verdict::Ambiguous, true) => &mut t.ambiguous_right,
                (Verdict::Ambiguous, false) if r.truth_in_alternatives == Some(true) => &mut t.ambiguous_truth_listed,
                (Verdict::Ambiguous, false) => &mut t.ambiguous_wrong,
                (Verdict::Unreliable, true) => &mut t.unreliable_right,
                (Verdict::Unreliable, false) => &mut t.unreliable_wrong,
            };
            *slot += 1;
            t.right_or_flagged += usize::from(r.right_or_flagged() == Some(true));
        }
        t
    }
}

/// One family.
#[derive(Clone, Debug, Serialize)]
pub struct FamilyReport {
    /// Family name.
    pub family: Family,
    /// One cell per method.
    pub cells: Vec<FamilyCell>,
    /// Every case.
    pub cases: Vec<CaseRecord>,
}

/// The whole benchmark.
#[derive(Clone, Debug, Serialize)]
pub struct RealisticReport {
    /// Seed.
    pub seed: u64,
    /// Split.
    pub split: Split,
    /// Cases per family.
    pub cases_per_family: usize,
    /// The tolerance.
    pub tolerance: Tolerance,
    /// Methods, in column order.
    pub methods: Vec<String>,
    /// One entry per family.
    pub families: Vec<FamilyReport>,
}

pub use super::{BOARD_COLUMN, BOARD_FILTER_COLUMN};

fn method_columns(opts: &RealisticOptions) -> Vec<String> {
    let mut v: Vec<String> = opts.methods.iter().map(|m| m.name().to_string()).collect();
    if opts.board {
        v.push(BOARD_COLUMN.to_string());
        v.push(BOARD_FILTER_COLUMN.to_string());
    }
    v
}

/// Case `index` of `family` in the options' split.
pub fn case(family: Family, index: usize, split: Split, seed: u64) -> Case {
    let shapes = shapes(family, split);
    let shape = shapes[index % shapes.len()];
    let split_code = match split {
        Split::Dev => 1,
        Split::Test => 2,
    };
    let family_code = Family::ALL.iter().position(|&f| f == family).unwrap_or(0) as u64 + 1;
    let case_seed = mix(mix(mix(seed, split_code), family_code), index as u64 + 1);
    make_case(family, shape, index, case_seed)
}

/// Run the benchmark.
pub fn run(opts: &RealisticOptions) -> anyhow::Result<RealisticReport> {
    let mut exported = Vec::new();
    let mut families = Vec::new();
    let bar = opts.progress.then(|| Progress::bar("[realistic]", (opts.families.len() * opts.cases) as u64, "cases"));
    for &family in &opts.families {
        let start = Instant::now();
        if let Some(b) = &bar {
            b.message(family.name());
        }
        let mut cases = Vec::with_capacity(opts.cases);
        for i in 0..opts.cases {
            let c = case(family, i, opts.split, opts.seed);
            if let Some(dir) = &opts.export {
                exported.push(export_case(dir, &c)?);
            }
            let nn = NearestNeighbours::new(&c.model);
            let surface = crate::pf_icp::surface::Surface::new(&nn);
            // The scale as the family's user knows it.
            let scale = c.known_scale.map_or(opts.pf.scale, ScaleBounds::fixed);
            let viewpoint = if opts.viewpoint { c.viewpoint } else { None };
            let settings = MethodSettings { pf: PfIcpSettings { seed: c.seed, scale, viewpoint, ..opts.pf.clone() } };
            let mut results: Vec<CaseResult> = opts
                .methods
                .iter()
                .map(|&m| {
                    let o = run_method(m, &nn, &c.scan, &settings);
                    let seconds = o.elapsed.as_secs_f64();
                    match &o.pf {
                        Some(pf) => CaseResult::assessed(m.name(), &c, &pf.conclusion, seconds, &surface),
                        None => CaseResult::plain(m.name(), &c, &o.registration.pose, seconds, &surface),
                    }
                })
                .collect();
            if opts.board {
                let t = Instant::now();
                let pf = crate::board::on_board::emulate_registration(&nn, &c.scan, &settings.pf, opts.board_points)
                    .with_context(|| format!("case {}", c.id))?;
                let seconds = t.elapsed().as_secs_f64();
                results.push(CaseResult::assessed(BOARD_COLUMN, &c, &pf.conclusion, seconds, &surface));
                // The board's pose alone: no polish, no conclusion (so no region, no verdict).
                results.push(CaseResult::plain(BOARD_FILTER_COLUMN, &c, &pf.filter_pose, seconds, &surface));
            }
            let mut truth = c.truth.to_params();
            for a in &mut truth[4..] {
                *a = a.to_degrees();
            }
            cases.push(CaseRecord {
                id: c.id.clone(),
                shape: c.shape.name().to_string(),
                held_out: c.shape.held_out(),
                seed: c.seed,
                visible: c.visible,
                outliers: c.outliers,
                scan_points: c.scan.len(),
                truth,
                truth_cost: surface.cost(&c.scan, &c.truth, 0.05 * c.diag),
                truth_refined_cost: {
                    let bounds = c.known_scale.map_or(ScaleBounds::FREE, ScaleBounds::fixed);
                    let p = surface.polish(&c.scan, &c.truth, 30, &bounds);
                    surface.cost(&c.scan, &p, 0.05 * c.diag)
                },
                results,
            });
            if let Some(b) = &bar {
                b.inc();
                if i + 1 == opts.cases {
                    b.println(format!(
                        "[realistic] {}: {} cases ({:.1} s)",
                        family.name(),
                        opts.cases,
                        start.elapsed().as_secs_f64()
                    ));
                }
            }
        }
        let columns = method_columns(opts);
        let cells = columns
            .iter()
            .enumerate()
            .map(|(j, m)| {
                let held: Vec<&CaseRecord> = cases.iter().filter(|c| c.held_out).collect();
                let pf = m.starts_with(Method::PfIcp.name()) && m != BOARD_FILTER_COLUMN;
                FamilyCell {
                    method: m.clone(),
                    successes: cases.iter().filter(|c| c.results[j].score.success).count(),
                    cases: cases.len(),
                    held_out_successes: held.iter().filter(|c| c.results[j].score.success).count(),
                    held_out_cases: held.len(),
                    median_seconds: median(&cases.iter().map(|c| c.results[j].seconds).collect::<Vec<_>>()),
                    inside_95: pf.then(|| {
                        cases
                            .iter()
                            .filter(|c| c.results[j].score.success)
                            .filter(|c| c.results[j].inside_95 == Some(true))
                            .count()
                    }),
                    with_alternatives: pf
                        .then(|| cases.iter().filter(|c| c.results[j].alternatives.is_some_and(|a| a > 0)).count()),
                    verdicts: pf.then(|| VerdictTally::of(cases.iter().map(|c| &c.results[j]))),
                }
            })
            .collect();
        families.push(FamilyReport { family, cells, cases });
    }
    let report = RealisticReport {
        seed: opts.seed,
        split: opts.split,
        cases_per_family: opts.cases,
        tolerance: TOLERANCE,
        methods: method_columns(opts),
        families,
    };
    if let Some(dir) = &opts.export {
        let doc = serde_json::json!({
            "suite": "realistic", "split": opts.split.name(), "seed": opts.seed,
            "tolerance": TOLERANCE, "cases": exported,
        });
        let path = dir.join("cases.json");
        std::fs::write(&path, serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(dir) = &opts.out_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let path = dir.join("realistic.json");
        std::fs::write(&path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(report)
}

fn export_case(dir: &Path, c: &Case) -> anyhow::Result<serde_json::Value> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let stem = c.id.replace('/', "-");
    let (model, scan) = (format!("{stem}-model.ply"), format!("{stem}-scan.ply"));
    crate::io::write_cloud(&dir.join(&model), &c.model, crate::io::Format::PlyBinary)?;
    crate::io::write_cloud(&dir.join(&scan), &c.scan, crate::io::Format::PlyBinary)?;
    let centre = c.shape.centre();
    let symmetries: Vec<serde_json::Value> = c
        .shape
        .symmetries()
        .iter()
        .map(|g| {
            let rows: Vec<[f64; 3]> = (0..3).map(|i| [g[(i, 0)], g[(i, 1)], g[(i, 2)]]).collect();
            serde_json::json!({ "rotation": rows, "centre": [centre.x, centre.y, centre.z] })
        })
        .collect();
    let p = centroid(&c.scan);
    let t = c.truth.record();
    Ok(serde_json::json!({
        "id": c.id, "family": c.family.name(), "shape": c.shape.name(), "held_out": c.shape.held_out(),
        "seed": c.seed, "model": model, "scan": scan,
        "truth": { "scale": t.scale, "rotation": t.rotation, "translation": t.translation },
        "diag": c.diag, "reference_point": [p.x, p.y, p.z], "symmetries": symmetries,
        "known_scale": c.known_scale, "viewpoint": c.viewpoint.map(|v| [v.x, v.y, v.z]),
        "visible": c.visible, "outliers": c.outliers,
    }))
}

impl RealisticReport {
    /// The table as text.
    pub fn render(&self) -> String {
        let mut header = vec!["family".to_string()];
        for m in &self.methods {
            header.push(format!("{m} success"));
            header.push(format!("{m} held-out"));
            header.push(format!("{m} median s"));
            if m.starts_with(Method::PfIcp.name()) && m != BOARD_FILTER_COLUMN {
                header.push("truth in 95% region".to_string());
                header.push("ambiguous".to_string());
            }
        }
        let mut t = TextTable::new(
            format!(
                "Realistic benchmark ({} split, seed {}): {} cases per family",
                self.split.name(),
                self.seed,
                self.cases_per_family
            ),
            header,
        );
        for f in &self.families {
            let mut row = vec![f.family.name().to_string()];
            for c in &f.cells {
                row.push(format!(
                    "{}/{} ({:.0}%)",
                    c.successes,
                    c.cases,
                    100.0 * c.successes as f64 / c.cases.max(1) as f64
                ));
                row.push(format!("{}/{}", c.held_out_successes, c.held_out_cases));
                row.push(format!("{:.3}", c.median_seconds));
                if let (Some(inside), Some(alt)) = (c.inside_95, c.with_alternatives) {
                    row.push(format!("{inside}/{}", c.successes));
                    row.push(format!("{alt}/{}", c.cases));
                }
            }
            t.row(row);
        }
        t.note(format!(
            "success: within {} deg, {}% of the diagonal at the scan centroid, {}% scale, modulo the shape's symmetries",
            TOLERANCE.rotation_deg,
            100.0 * TOLERANCE.translation_frac,
            100.0 * TOLERANCE.scale_frac,
        ));
        t.note(format!(
            "plane-cut families: {MODEL_POINTS} model / ~{SCAN_POINTS} scan points, views keep {:.0} to {:.0}% of the surface, noise {}% of the diagonal, outliers {}%",
            100.0 * VISIBLE_RANGE.0,
            100.0 * VISIBLE_RANGE.1,
            100.0 * NOISE_FRACTION,
            100.0 * OUTLIER_FRACTION
        ));
        t.note(format!(
            "camera families: {CAMERA_MODEL_POINTS} model / {CAMERA_SCAN_POINTS} scan points, self-occluded views keep {:.0} to {:.0}% of the surface, {:.0}% clutter (half in blobs), noise {}%; -metric: scale 1 and known",
            100.0 * camera::VISIBLE_RANGE.0,
            100.0 * camera::VISIBLE_RANGE.1,
            100.0 * camera::CLUTTER_FRACTION,
            100.0 * NOISE_FRACTION,
        ));
        let mut out = t.render();
        for (j, m) in self.methods.iter().enumerate() {
            if self.families.iter().all(|f| f.cells[j].verdicts.is_none()) {
                continue;
            }
            let mut v = TextTable::new(
                format!("Verdicts of {m} against the outcome"),
                [
                    "family",
                    "confident right",
                    "confident WRONG",
                    "ambiguous right",
                    "ambiguous, truth listed",
                    "ambiguous, truth missing",
                    "unreliable right",
                    "unreliable wrong",
                    "right or flagged",
                ]
                .map(String::from)
                .to_vec(),
            );
            for f in &self.families {
                let Some(x) = f.cells[j].verdicts else { continue };
                let n = f.cells[j].cases;
                v.row(vec![
                    f.family.name().to_string(),
                    format!("{}/{n}", x.confident_right),
                    format!("{}/{n}", x.confident_wrong),
                    x.ambiguous_right.to_string(),
                    x.ambiguous_truth_listed.to_string(),
                    x.ambiguous_wrong.to_string(),
                    x.unreliable_right.to_string(),
                    x.unreliable_wrong.to_string(),
                    format!("{}/{n}", x.right_or_flagged),
                ]);
            }
            v.note("right or flagged: right, or ambiguous with the truth among the alternatives, or unreliable");
            out += "\n";
            out += &v.render();
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn the_truth_scores_zero_and_a_symmetric_copy_counts_as_right() {
        let c = case(Family::Parts, 7, Split::Test, 5); // Part::Nut, D6
        assert_eq!(c.shape.name(), "nut");
        let s = score(&c.truth, &c);
        assert!(s.success && s.rotation_deg < 1e-9 && s.symmetry == 0);
        let g = c.shape.symmetries()[3];
        let copy = symmetric_truth(&c.truth, &g, &c.shape.centre());
        let s = score(&copy, &c);
        assert!(s.success && s.symmetry == 3, "{s:?}");
        // A near-symmetric part's flipped copy is wrong.
        let c = case(Family::Parts, 0, Split::Test, 5);
        let half = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI).into_inner();
        assert!(!score(&symmetric_truth(&c.truth, &half, &c.shape.centre()), &c).success);
    }

    #[test]
    fn cases_are_a_function_of_the_seed() {
        let a = case(Family::RealOutliers, 3, Split::Dev, 9);
        let b = case(Family::RealOutliers, 3, Split::Dev, 9);
        assert_eq!(a.scan, b.scan);
        assert_eq!(a.truth, b.truth);
        assert!(a.outliers > 0);
        let c = case(Family::RealOutliers, 3, Split::Test, 9);
        assert_ne!(a.scan, c.scan);
    }

    #[test]
    fn dev_split_has_no_held_out_shape() {
        for f in Family::ALL {
            assert!(shapes(f, Split::Dev).iter().all(|s| !s.held_out()));
            assert!(shapes(f, Split::Test).iter().any(|s| s.held_out()));
        }
    }
}
