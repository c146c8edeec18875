//! What the on-board polish's parameters buy, on the shipped storage layout: for each case
//! of the realistic benchmark's dev split, the board's filter runs once (its bit-exact
//! reference, `OnBoardPlan::emulate_filter`), then the polish's reference
//! (`pficp_fpga::polish::polish_best_over` over the stored scan, as the board runs it) from
//! the filter's pose and a choice of the prior's hypotheses, with a number of steps, over
//! all stored points or at most `N` of them (the filter's sample, then every k-th of the
//! rest). A two-phase variant polishes every start over the filter's 300-point sample, then
//! its winner again over every stored point (each phase with its own steps); a halving
//! variant polishes every start over every stored point, then the best one or two again (the
//! shipped setting: eight starts, 5 steps, the winner 5 more). The software
//! mode, the shipped board alone and the board with the host's polish are scored beside
//! them.
//!
//! The board's time for a setting is the on-board bench's (`pficp-onboard-bench
//! --polish-steps S --polish-points N`). The tables are in docs/on-board-polish.md ("Eight
//! starts, the winner polished further" and "Alternatives measured").
//!
//! Slow (about 4 minutes for 100 cases a family): ignored by default. Run it with
//! `PFICP_CASES=100 PFICP_SEED=2 cargo test --release -p pficp-host --test
//! board_polish_variants -- --ignored --nocapture` (`PFICP_CASES` cases a family, default
//! 32; `PFICP_SEED` the benchmark's seed, default 1; `PFICP_VARIANTS=19,20` only those
//! variants and the shipped one; always the dev split: this is for choosing, not for
//! reporting).

use pficp::board::on_board::{self, plan, OnBoardPlan};
use pficp::board::quantise::{normalised_pose, original_pose, quantise_pose, restore_pose};
use pficp::eval::realistic::{case, score, Family, Split};
use pficp::geometry::Pose;
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::{self, PfIcpSettings};
use pficp_fpga::common::format::{FxPoint, FxPose};
use pficp_fpga::polish::ScaleStep;
use pficp_fpga::protocol::messages::ResultReply;
use rayon::prelude::*;
use std::time::Duration;

fn env_or(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// One setting of the polish.
struct Variant {
    name: &'static str,
    /// The prior's hypotheses (indices) that start beside the filter's pose.
    hypotheses: &'static [usize],
    /// Steps of the hypotheses' polish.
    steps: u32,
    /// Steps of the filter's pose's polish (two-phase: every start's steps over the sample).
    first_steps: u32,
    /// Most stored points the polish runs over (0: all).
    points: usize,
    /// Every start over the filter's sample first, then the winner over all.
    two_phase: bool,
    /// Successive halving: every start `first_steps` over the variant's points, then the
    /// best `keep` of them by cost `steps` more (0: not this kind).
    keep: usize,
}

const fn v(name: &'static str, hypotheses: &'static [usize], steps: u32, points: usize) -> Variant {
    Variant { name, hypotheses, steps, first_steps: steps, points, two_phase: false, keep: 0 }
}

/// Every start polished with `first` steps over every stored point, the best `keep` of them
/// by cost again with `steps` more (a new polish from the first phase's pose), the lowest
/// cost wins.
const fn halving(name: &'static str, hypotheses: &'static [usize], first: u32, keep: usize, steps: u32) -> Variant {
    Variant { name, hypotheses, steps, first_steps: first, points: 0, two_phase: false, keep }
}

/// Every start polished with `screen` steps over the filter's sample, the winner again with
/// `steps` over all the variant's points.
const fn two_phase(name: &'static str, hypotheses: &'static [usize], screen: u32, steps: u32) -> Variant {
    Variant { name, hypotheses, steps, first_steps: screen, points: 0, two_phase: true, keep: 0 }
}

/// The filter's pose polished with `first_steps`, the hypotheses with `steps`.
const fn uneven(name: &'static str, first_steps: u32, steps: u32) -> Variant {
    Variant { name, hypotheses: H2, steps, first_steps, points: 0, two_phase: false, keep: 0 }
}

const H2: &[usize] = &[0, 1];
const H4: &[usize] = &[0, 1, 2, 3];
const H7: &[usize] = &[0, 1, 2, 3, 4, 5, 6];
const H1_2: &[usize] = &[1, 2];
const H1_3: &[usize] = &[1, 2, 3];
const H3: &[usize] = &[0, 1, 2];
const H1_4: &[usize] = &[1, 2, 3, 4];
const H5: &[usize] = &[0, 1, 2, 3, 4];
const H15: &[usize] = &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14];

const VARIANTS: [Variant; 34] = [
    halving("8 starts, 5 steps over all, the winner 5 more (shipped)", H7, 5, 1, 5),
    v("3 starts, 5 steps (protocol 5's setting)", H2, 5, 0),
    v("3 starts, 8 steps", H2, 8, 0),
    v("3 starts, 15 steps", H2, 15, 0),
    v("3 starts, 5 steps, at most 500 points", H2, 5, 500),
    v("3 starts, 8 steps, at most 600 points", H2, 8, 600),
    v("3 starts, 10 steps, at most 600 points", H2, 10, 600),
    v("5 starts, 5 steps", H4, 5, 0),
    v("8 starts, 5 steps", H7, 5, 0),
    v("16 starts, 5 steps", H15, 5, 0),
    two_phase("16 starts over the sample, the winner over all, 5 + 5 steps", H15, 5, 5),
    two_phase("8 starts over the sample, the winner over all, 2 + 10 steps", H7, 2, 10),
    two_phase("8 starts over the sample, the winner over all, 3 + 10 steps", H7, 3, 10),
    two_phase("16 starts over the sample, the winner over all, 2 + 10 steps", H15, 2, 10),
    two_phase("16 starts over the sample, the winner over all, 3 + 10 steps", H15, 3, 10),
    v("8 starts, 10 steps", H7, 10, 0),
    v("16 starts, 10 steps", H15, 10, 0),
    two_phase("8 starts over the sample, the winner over all, 5 + 10 steps", H7, 5, 10),
    two_phase("16 starts over the sample, the winner over all, 5 + 10 steps", H15, 5, 10),
    two_phase("16 starts over the sample, the winner over all, 8 + 10 steps", H15, 8, 10),
    uneven("3 starts, the filter's pose 8 steps, the hypotheses 3", 8, 3),
    uneven("3 starts, the filter's pose 10 steps, the hypotheses 3", 10, 3),
    uneven("3 starts, the filter's pose 8 steps, the hypotheses 5", 8, 5),
    uneven("3 starts, the filter's pose 10 steps, the hypotheses 2", 10, 2),
    v("3 starts, hypotheses 2 and 3 (not the filter's start), 10 steps", H1_2, 10, 0),
    v("4 starts, hypotheses 2 to 4 (not the filter's start), 10 steps", H1_3, 10, 0),
    v("4 starts, 10 steps", H3, 10, 0),
    v("5 starts, 10 steps", H4, 10, 0),
    v("5 starts, hypotheses 2 to 5 (not the filter's start), 10 steps", H1_4, 10, 0),
    v("6 starts, 10 steps", H5, 10, 0),
    v("3 starts, 10 steps, all points (the 3-start setting)", H2, 10, 0),
    halving("8 starts, 5 steps over all, the best two 5 more", H7, 5, 2, 5),
    halving("16 starts, 3 steps over all, the best two 7 more", H15, 3, 2, 7),
    halving("8 starts, 4 steps over all, the best two 6 more", H7, 4, 2, 6),
];

/// Every start's polish with `steps` by the rules of
/// [`pficp_fpga::polish::polish_best_over`] (a first start beyond the drift bounds stays
/// unpolished, another is dropped), as (cost, index, pose), lowest cost first.
fn ranked(
    search: &impl pficp_fpga::surface::Search,
    scan: &[FxPoint],
    starts: &[FxPose],
    steps: u32,
) -> Vec<(u64, usize, FxPose)> {
    use pficp_fpga::polish::{polish_over, within_drift};
    let mut out: Vec<(u64, usize, FxPose)> = starts
        .iter()
        .enumerate()
        .filter_map(|(i, start)| {
            let p = polish_over(search, scan, start, steps, ScaleStep::Solved).pose;
            let pose = match (within_drift(start, &p), i) {
                (true, _) => p,
                (false, 0) => *start,
                (false, _) => return None,
            };
            Some((search.evaluate(scan, &pose).cost, i, pose))
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.cmp(&b.1)));
    out
}

/// [`pficp_fpga::polish::polish_best_over`] with the first start's steps apart (the same
/// rules: a first start beyond the drift bounds stays unpolished, another is dropped; the
/// lowest cost wins, the earlier on a tie).
fn polish_best_uneven(
    search: &impl pficp_fpga::surface::Search,
    scan: &[FxPoint],
    starts: &[FxPose],
    first_steps: u32,
    steps: u32,
) -> FxPose {
    use pficp_fpga::polish::{polish_over, within_drift};
    starts
        .iter()
        .enumerate()
        .filter_map(|(i, start)| {
            let p = polish_over(search, scan, start, if i == 0 { first_steps } else { steps }, ScaleStep::Solved).pose;
            let pose = match (within_drift(start, &p), i) {
                (true, _) => p,
                (false, 0) => *start,
                (false, _) => return None,
            };
            Some((i, pose, search.evaluate(scan, &pose).cost))
        })
        .min_by(|a, b| a.2.cmp(&b.2).then(a.0.cmp(&b.0)))
        .expect("a start")
        .1
}

fn on_board_pose(plan: &OnBoardPlan, pose: &Pose) -> FxPose {
    quantise_pose(&normalised_pose(pose, &plan.scan_norm, &plan.model_norm))
}

fn restored(plan: &OnBoardPlan, pose: &FxPose) -> Pose {
    original_pose(&restore_pose(pose).expect("the polish keeps a similarity"), &plan.scan_norm, &plan.model_norm)
}

/// The stored points a variant polishes over: all, or the filter's sample and every k-th
/// of the rest (as `on_board::plan` thins the rest to fit).
fn points_of(plan: &OnBoardPlan, most: usize) -> Vec<FxPoint> {
    let stored = plan.stored_scan();
    if most == 0 || most >= stored.len() {
        return stored;
    }
    let room = most.saturating_sub(plan.scan.len()).max(1);
    let stride = plan.rest.len().div_ceil(room).max(1);
    plan.scan.iter().chain(plan.rest.iter().step_by(stride).take(room)).copied().collect()
}

/// Whether variant `i` runs: all, or those `PFICP_VARIANTS` lists (indices, comma-separated;
/// the shipped variant 0 always).
fn selected(i: usize) -> bool {
    match std::env::var("PFICP_VARIANTS") {
        Ok(list) => i == 0 || list.split(',').any(|v| v.trim().parse() == Ok(i)),
        Err(_) => true,
    }
}

#[test]
#[ignore = "minutes in release; prints the tables of docs/on-board-polish.md"]
fn the_polish_settings_on_the_dev_split() {
    let cases = env_or("PFICP_CASES", 32) as usize;
    let seed = env_or("PFICP_SEED", 1);
    println!("dev split, seed {seed}, {cases} cases a family");
    let columns = VARIANTS.len() + 3;
    let mut totals = vec![0usize; columns];
    let mut all = 0;
    for family in Family::PLANE_CUT {
        // Per case: software, each variant, the shipped board alone, board + host polish.
        let rows: Vec<Vec<bool>> = (0..cases)
            .into_par_iter()
            .map(|i| {
                let c = case(family, i, Split::Dev, seed);
                let nn = NearestNeighbours::new(&c.model);
                let settings = PfIcpSettings { seed: c.seed, ..Default::default() };
                let soft = pf_icp::register(&nn, &c.scan, &settings).registration.pose;
                let plan =
                    plan(&nn, &c.scan, &settings, on_board::DEFAULT_BOARD_POINTS, pficp::board::BOARD_MAX_STORE_POINTS)
                        .expect("a plan");
                let filter = plan.emulate_filter();
                let search = pficp_fpga::surface::GridSearch { grid: &plan.grid, normals: &plan.normals };
                let hyps = &plan.prior.hypotheses;
                let mut ok = vec![score(&soft, &c).success];
                for (vi, var) in VARIANTS.iter().enumerate() {
                    if !selected(vi) {
                        ok.push(false);
                        continue;
                    }
                    let starts: Vec<FxPose> = std::iter::once(filter.pose)
                        .chain(
                            var.hypotheses.iter().filter_map(|&i| hyps.get(i)).map(|h| on_board_pose(&plan, &h.pose)),
                        )
                        .collect();
                    let pts = points_of(&plan, var.points);
                    let pose = if var.keep > 0 {
                        let kept: Vec<FxPose> = ranked(&search, &pts, &starts, var.first_steps)
                            .iter()
                            .take(var.keep)
                            .map(|r| r.2)
                            .collect();
                        pficp_fpga::polish::polish_best_over(&search, &pts, &kept, var.steps, ScaleStep::Solved)
                            .expect("a start")
                            .1
                            .pose
                    } else if var.two_phase {
                        let (_, first, _) = pficp_fpga::polish::polish_best_over(
                            &search,
                            &plan.scan,
                            &starts,
                            var.first_steps,
                            ScaleStep::Solved,
                        )
                        .expect("a start");
                        pficp_fpga::polish::polish_best_over(&search, &pts, &[first.pose], var.steps, ScaleStep::Solved)
                            .expect("a start")
                            .1
                            .pose
                    } else if var.first_steps != var.steps && starts.len() > 1 {
                        polish_best_uneven(&search, &pts, &starts, var.first_steps, var.steps)
                    } else {
                        pficp_fpga::polish::polish_best_over(&search, &pts, &starts, var.steps, ScaleStep::Solved)
                            .expect("a start")
                            .1
                            .pose
                    };
                    ok.push(score(&restored(&plan, &pose), &c).success);
                }
                let reply = ResultReply::of(&plan.emulate());
                let fin = on_board::finish(&plan, &nn, &c.scan, &settings, &reply, Duration::ZERO);
                ok.push(score(&fin.filter_pose, &c).success);
                ok.push(score(&fin.registration.pose, &c).success);
                ok
            })
            .collect();
        let counts: Vec<usize> = (0..columns).map(|k| rows.iter().filter(|r| r[k]).count()).collect();
        println!("{}: {counts:?}", family.name());
        for (t, c) in totals.iter_mut().zip(&counts) {
            *t += c;
        }
        all += rows.len();
    }
    let names = std::iter::once("software")
        .chain(VARIANTS.iter().map(|v| v.name))
        .chain(["board alone as shipped (plan.emulate)", "board + host polish"]);
    for (k, (name, t)) in names.zip(&totals).enumerate() {
        if k == 0 || k > VARIANTS.len() || selected(k - 1) {
            println!("| {name} | {t}/{all} |");
        }
    }
    // The variant that repeats the shipped setting must score as the shipped board does.
    assert_eq!(totals[1], totals[VARIANTS.len() + 1], "the shipped variant differs from plan.emulate");
}
