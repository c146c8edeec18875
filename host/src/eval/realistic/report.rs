//! The realistic benchmark's report: each method's result on each case, the families'
//! success and verdict tallies, and the table as text.

use super::camera;
use super::cases::*;
use super::scoring::*;
use crate::cloud::centroid;
use crate::eval::text_table::TextTable;
use crate::eval::BOARD_FILTER_COLUMN;
use crate::geometry::Pose;
use crate::pf_icp::conclusion::Conclusion;
use crate::pf_icp::surface::Surface;
use crate::pf_icp::verdict::Verdict;
use crate::registration::methods::Method;
use serde::Serialize;

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
    pub(super) fn plain(method: &str, case: &Case, pose: &Pose, seconds: f64, surface: &Surface) -> Self {
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
    pub(super) fn assessed(method: &str, case: &Case, c: &Conclusion, seconds: f64, surface: &Surface) -> Self {
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
