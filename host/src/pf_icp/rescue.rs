//! The rescue: a second, wider global search when the verdict's own evidence rules out the
//! answer.
//!
//! A search of [`SearchSettings::grid`] rotations misses the basin of the truth on some small
//! one-sided views (a thin part, a cortex seen over 13% of its surface): no start lands close
//! enough for the trimmed ICP to reach it, and the answer then fits visibly badly. The
//! verdict sees it: too little of the scan explained within the noise, or too much of it
//! where the model would hide it from the sensor ([`not_ruled_out`] false). Only then, the
//! search runs again with [`wider`] settings (four times the rotations, twice the survivors
//! of each pass) and fresh feature proposals ([`PROPOSAL_SEED`]), its hypotheses join the
//! first search's ([`merge`]) and the conclusion compares them all again with the filter's
//! estimate. A pose the evidence does not rule out costs nothing more; the rescue's answer
//! is judged by the same rules as any other, so a rescue that finds nothing better still
//! says `unreliable`.
//!
//! On the realistic benchmark's dev split (the four camera-view families, 100 cases each,
//! seed 1) the rule fires on 16 of the 400 results, all of them wrong, and on none of the 339
//! right ones; the rescue turns 8 of the 16 right (docs/global-registration.md, "Rescue").

use crate::cloud::{bbox_diagonal, centroid};
use crate::geometry::Pose;
use crate::pf_icp::conclusion::Conclusion;
use crate::pf_icp::evidence::Evidence;
use crate::pf_icp::hypotheses::{distinct, Hypothesis, SearchSettings};
use crate::pf_icp::init::InitialPose;
use crate::pf_icp::surface::Surface;
use crate::pf_icp::verdict::not_ruled_out;
use crate::pf_icp::{PfIcpSettings, Prior};
use nalgebra::Point3;
use std::time::{Duration, Instant};

/// The rescue search has this many times the rotations of the first.
pub const GRID_FACTOR: usize = 4;
/// ... and keeps this many times the survivors of its screen and coarse passes.
pub const KEEP_FACTOR: usize = 2;
/// The rescue's feature proposals are drawn with the seed XOR this (fresh correspondences
/// and RANSAC triples, not the first search's again).
pub const PROPOSAL_SEED: u64 = 0x7265_7363;

/// Whether `conclusion`'s answer is ruled out by the verdict's evidence rules (explained
/// share, hidden share): the rescue's trigger.
pub fn needed(conclusion: &Conclusion) -> bool {
    !not_ruled_out(conclusion.checks.explained, conclusion.checks.hidden)
}

/// The rescue's search settings: [`GRID_FACTOR`] times the rotations, [`KEEP_FACTOR`] times
/// the survivors of the screen and coarse passes, the rest as `first`.
pub fn wider(first: &SearchSettings) -> SearchSettings {
    SearchSettings {
        grid: first.grid * GRID_FACTOR,
        screen_keep: first.screen_keep * KEEP_FACTOR,
        keep: first.keep * KEEP_FACTOR,
        ..first.clone()
    }
}

/// The distinct hypotheses of both searches, best first (both ranked by the same cost over
/// the same `sample`, whose centroid distinctness is judged at); of two that are the same
/// pose, the lower cost stays (the first search's on a tie).
pub fn merge(
    first: &[Hypothesis],
    second: &[Hypothesis],
    sample: &[Point3<f64>],
    model: &[Point3<f64>],
) -> Vec<Hypothesis> {
    let mut all: Vec<Hypothesis> = first.iter().chain(second).copied().collect();
    all.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    distinct(all, &centroid(sample), bbox_diagonal(model))
}

/// `first`, the conclusion over `hypotheses`; or, when the evidence rules its answer out
/// and the search's settings allow ([`needed`]), the conclusion over the hypotheses of both
/// `hypotheses` and a wider search (over `surface`, the search's). Returns the conclusion,
/// the hypotheses it was drawn from, and the rescue's time (zero when it did not run).
#[allow(clippy::too_many_arguments)]
pub fn conclude_or_rescue(
    first: Conclusion,
    hypotheses: Vec<Hypothesis>,
    conclude: impl Fn(&[Hypothesis]) -> Conclusion,
    surface: &Surface,
    scan: &[Point3<f64>],
    sample: &[Point3<f64>],
    initial: &InitialPose,
    settings: &PfIcpSettings,
    evidence: &Evidence,
) -> (Conclusion, Vec<Hypothesis>, Duration) {
    match settings.search.as_ref().filter(|s| s.rescue) {
        Some(search) if needed(&first) => {
            let t = Instant::now();
            // Its own feature proposals: with the first search's seed they would be the
            // first search's again.
            let fresh = PfIcpSettings { seed: settings.seed ^ PROPOSAL_SEED, ..settings.clone() };
            let more = crate::pf_icp::global_search(surface, scan, sample, initial, &wider(search), &fresh, evidence);
            let merged = merge(&hypotheses, &more, sample, surface.nn().points());
            (conclude(&merged), merged, t.elapsed())
        }
        _ => (first, hypotheses, Duration::ZERO),
    }
}

/// The conclusion of a pose the filter found elsewhere (the board's, `filter_pose`) from
/// the host's `prior` ([`crate::pf_icp::prior`]), with the rescue when it is needed:
/// the conclusion, the hypotheses it was drawn from and the rescue's time (zero when it
/// did not run). `surface` is the whole model's.
pub fn conclude_prior(
    surface: &Surface,
    scan: &[Point3<f64>],
    filter_pose: &Pose,
    prior: &Prior,
    settings: &PfIcpSettings,
) -> (Conclusion, Vec<Hypothesis>, Duration) {
    let conclude = |hypotheses: &[Hypothesis]| {
        crate::pf_icp::conclusion::conclude(
            surface,
            scan,
            filter_pose,
            hypotheses,
            settings.polish_iterations,
            &settings.scale,
            &prior.evidence,
        )
    };
    let first = conclude(&prior.hypotheses);
    if !needed(&first) {
        return (first, prior.hypotheses.clone(), Duration::ZERO);
    }
    // The rescue searches where the prior's search did (the model's subset in a large
    // registration).
    let subset = crate::pf_icp::search_model(surface.nn().points(), scan.len(), settings.seed);
    let subset_surface = subset.as_ref().map(Surface::new);
    conclude_or_rescue(
        first,
        prior.hypotheses.clone(),
        conclude,
        subset_surface.as_ref().unwrap_or(surface),
        scan,
        &prior.sample,
        &prior.initial,
        settings,
        &prior.evidence,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    fn hyp(angle_deg: f64, cost: f64) -> Hypothesis {
        let rotation = *nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), angle_deg.to_radians()).matrix();
        Hypothesis { pose: Pose { scale: 1.0, rotation, translation: Vector3::zeros() }, cost }
    }

    #[test]
    fn wider_multiplies_the_rotations_and_the_survivors_only() {
        let first = SearchSettings::default();
        let w = wider(&first);
        assert_eq!(w.grid, GRID_FACTOR * first.grid);
        assert_eq!(w.screen_keep, KEEP_FACTOR * first.screen_keep);
        assert_eq!(w.keep, KEEP_FACTOR * first.keep);
        assert_eq!((w.fine_points, w.held_keep, w.trim), (first.fine_points, first.held_keep, first.trim));
    }

    #[test]
    fn merge_ranks_both_and_keeps_the_cheaper_of_the_same_pose() {
        let sample = vec![Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.0)];
        let model = vec![Point3::origin(), Point3::new(1.0, 1.0, 1.0)];
        let first = [hyp(0.0, 2.0), hyp(90.0, 5.0)];
        let second = [hyp(1.0, 1.0), hyp(180.0, 3.0)];
        let m = merge(&first, &second, &sample, &model);
        let costs: Vec<f64> = m.iter().map(|h| h.cost).collect();
        // 1 deg and 0 deg are the same pose: the cheaper (the second search's) stays.
        assert_eq!(costs, vec![1.0, 3.0, 5.0]);
        assert_eq!(m[0].pose.rotation, hyp(1.0, 0.0).pose.rotation);
        assert_ne!(m[0].pose.rotation, Matrix3::identity());
    }
}
