//! Why the board's filter alone misses where the software's succeeds, and what the on-board
//! polish (`pficp_fpga::polish`, its bit-exact reference) changes (the exploration of stops
//! 25 to 27; the shipped setting's figures are `board_accuracy` and `board_polish_variants`): on the
//! realistic benchmark's quick set (8 cases a family, seed 1) and on models 1 to 3 (Table 1
//! truths, 2,000 model points, an independent 1,000-point scan, seeds 1 to 10), the
//! successes of
//! - the software mode (`pf_icp::register`),
//! - the board's pose alone (`OnBoardPlan::emulate`, bit-exact with the board),
//! - that pose polished by the on-board polish's reference over the board's stores, on the
//!   board's 300-point sample and on the whole scan,
//! - that pose polished by the host (`on_board::finish`, the product's polish),
//!
//! and, on the realistic set, on how many cases the filter's best cost is below its cost at
//! the true pose (the filter found the minimum of its cost, and the minimum is off).
//!
//! Slow (a minute or two): ignored by default. Run it with
//! `cargo test --release -p pficp-host --test board_polish_figures -- --ignored --nocapture`
//! (`PFICP_SPLIT=test` for the test split, default dev; `PFICP_POLISH_STEPS` and
//! `PFICP_POLISH_STARTS` for fewer steps and starts; `PFICP_CASES` cases a family, default
//! 8). The tables are in
//! docs/on-board-polish.md.

use pficp::board::on_board::{self, plan, OnBoardPlan};
use pficp::board::quantise::{normalised_pose, original_pose, quantise_pose, restore_pose};
use pficp::cloud::bbox_diagonal;
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::eval::realistic::{case, score, Family, Split};
use pficp::geometry::Pose;
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::conclusion::candidates;
use pficp::pf_icp::{self, PfIcpSettings};
use pficp::registration::methods::Tolerance;
use pficp_fpga::protocol::messages::ResultReply;
use rayon::prelude::*;
use std::time::Duration;

/// Cases a family of the realistic set (`PFICP_CASES`, default 8: the quick set).
fn cases_a_family() -> usize {
    std::env::var("PFICP_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(8)
}

/// Gauss-Newton steps of the on-board polish (`PFICP_POLISH_STEPS`, default 10).
fn steps() -> u32 {
    std::env::var("PFICP_POLISH_STEPS").ok().and_then(|v| v.parse().ok()).unwrap_or(10)
}

/// Most starts of the on-board polish's choice (`PFICP_POLISH_STARTS`, default all the
/// conclusion's candidates).
fn max_starts() -> usize {
    std::env::var("PFICP_POLISH_STARTS").ok().and_then(|v| v.parse().ok()).unwrap_or(usize::MAX)
}

const COLUMNS: [&str; 6] = [
    "software",
    "board alone",
    "+ board polish, 300 points",
    "+ board polish, whole scan",
    "+ board polish, whole scan, with the hypotheses",
    "+ host polish",
];

/// The six poses of [`COLUMNS`] for one registration, whether the filter's best cost is
/// below its cost at `truth`, and the on-board polish's starts.
fn poses(
    nn: &NearestNeighbours,
    scan: &[nalgebra::Point3<f64>],
    settings: &PfIcpSettings,
    truth: &Pose,
) -> ([Pose; 6], bool, usize) {
    let software = pf_icp::register(nn, scan, settings).registration.pose;
    let plan =
        plan(nn, scan, settings, on_board::DEFAULT_BOARD_POINTS, pficp::board::BOARD_MAX_STORE_POINTS).expect("plan");
    let out = plan.emulate_filter();
    let alone = on_board::params_pose(&out.params, &plan.model_norm, &plan.scan_norm);
    assert!(scan.len() <= pficp::board::BOARD_MAX_STORE_POINTS, "the whole scan fits the board");
    let whole = plan.scan_norm.quantise(scan);
    let polished = |points: &[pficp_fpga::common::format::FxPoint]| {
        restored(
            &plan,
            &pficp_fpga::polish::polish(
                &plan.grid,
                &plan.normals,
                points,
                &out.pose,
                steps(),
                pficp_fpga::polish::ScaleStep::Solved,
            )
            .pose,
        )
    };
    let host = on_board::finish(&plan, nn, scan, settings, &ResultReply::of(&unpolished(&out)), Duration::ZERO)
        .registration
        .pose;
    let at_truth = on_board::evaluate(&plan.grid, &plan.normals, &plan.scan, &on_board_pose(&plan, truth));
    // The starts the host's conclusion compares, the filter's pose exactly as the board has it.
    let starts: Vec<pficp_fpga::common::format::FxPose> = candidates(&alone, &plan.prior.hypotheses)
        .iter()
        .take(max_starts())
        .enumerate()
        .map(|(i, p)| if i == 0 { out.pose } else { on_board_pose(&plan, p) })
        .collect();
    let (_, best, _) = pficp_fpga::polish::polish_best(
        &plan.grid,
        &plan.normals,
        &whole,
        &starts,
        steps(),
        0,
        pficp_fpga::polish::ScaleStep::Solved,
    )
    .expect("a start");
    (
        [software, alone, polished(&plan.scan), polished(&whole), restored(&plan, &best.pose), host],
        out.best.cost < at_truth.cost,
        starts.len(),
    )
}

/// A filter's outcome with its pose as the polish's winner: the host's polish then starts
/// from the filter's pose, as before the polish was on the board.
fn unpolished(out: &pficp_fpga::filter::pf::PfOutcome) -> pficp_fpga::protocol::run_request::RunOutcome {
    let polish = pficp_fpga::protocol::run_request::PolishOutcome { winner: 0, pose: out.pose, cost: out.best.cost };
    pficp_fpga::protocol::run_request::RunOutcome { filter: out.clone(), polish }
}

/// A pose (original frame) as the board holds it.
fn on_board_pose(plan: &OnBoardPlan, pose: &Pose) -> pficp_fpga::common::format::FxPose {
    quantise_pose(&normalised_pose(pose, &plan.scan_norm, &plan.model_norm))
}

/// A board pose (a polish's result) in the original frame.
fn restored(plan: &OnBoardPlan, pose: &pficp_fpga::common::format::FxPose) -> Pose {
    original_pose(&restore_pose(pose).expect("the polish keeps a similarity"), &plan.scan_norm, &plan.model_norm)
}

fn row(name: &str, ok: &[[bool; 6]]) -> [usize; 6] {
    let counts: [usize; 6] = std::array::from_fn(|k| ok.iter().filter(|r| r[k]).count());
    println!("| {name} | {} |", counts.map(|c| format!("{c}/{}", ok.len())).join(" | "));
    counts
}

#[test]
#[ignore = "a minute or two in release; prints the tables of docs/on-board-polish.md"]
fn the_polish_on_the_board() {
    let split = if std::env::var("PFICP_SPLIT").is_ok_and(|v| v == "test") { Split::Test } else { Split::Dev };
    println!(
        "{} polish steps, at most {} starts; the board's sample {} points",
        steps(),
        max_starts(),
        on_board::DEFAULT_BOARD_POINTS
    );
    println!("| set | {} |", COLUMNS.join(" | "));
    println!("|---|---|---|---|---|---|---|");
    let mut totals = [0usize; 6];
    let mut below = 0;
    let mut starts = Vec::new();
    let mut cases = 0;
    for family in Family::PLANE_CUT {
        let rows: Vec<([bool; 6], bool, String, usize)> = (0..cases_a_family())
            .into_par_iter()
            .map(|i| {
                let c = case(family, i, split, 1);
                let nn = NearestNeighbours::new(&c.model);
                let settings = PfIcpSettings { seed: c.seed, ..Default::default() };
                let (p, under, n_starts) = poses(&nn, &c.scan, &settings, &c.truth);
                let scores = p.map(|p| score(&p, &c));
                let text = scores
                    .iter()
                    .map(|s| format!("{:.2} deg {:.2}% sc", s.rotation_deg, 100.0 * s.scale_frac))
                    .collect::<Vec<_>>()
                    .join(", ");
                (scores.map(|s| s.success), under, format!("{}: {text}", c.id), n_starts)
            })
            .collect();
        for r in rows.iter().filter(|r| r.0.iter().any(|&ok| !ok)) {
            eprintln!("  {}", r.2);
        }
        let ok: Vec<[bool; 6]> = rows.iter().map(|r| r.0).collect();
        let counts = row(&format!("{split:?} {}", family.name()), &ok);
        for k in 0..6 {
            totals[k] += counts[k];
        }
        below += rows.iter().filter(|r| r.1).count();
        starts.extend(rows.iter().map(|r| r.3));
        cases += rows.len();
    }
    println!("| {split:?} all | {} |", totals.map(|c| format!("{c}/{cases}")).join(" | "));
    println!("the filter's best cost below its cost at the truth: {below} of {cases} cases");
    starts.sort_unstable();
    println!(
        "the on-board polish's starts a case: {} to {}, median {}",
        starts[0],
        starts[starts.len() - 1],
        starts[starts.len() / 2]
    );
    let mut model_totals = [0usize; 6];
    for id in ModelId::ALL {
        let ok: Vec<[bool; 6]> = (1..=10u64)
            .into_par_iter()
            .map(|seed| {
                let truth = id.table1_truth();
                let spec = ScanSpec { sampling: Sampling::Independent { points: 1000 }, noise: 0.0, seed };
                let ds = make(id, 2000, &truth, &spec);
                let diag = bbox_diagonal(&ds.model);
                let nn = NearestNeighbours::new(&ds.model);
                let settings = PfIcpSettings { seed, ..Default::default() };
                poses(&nn, &ds.scan, &settings, &truth).0.map(|p| Tolerance::SUCCESS.accepts(&p, &truth, diag))
            })
            .collect();
        let counts = row(id.name(), &ok);
        for k in 0..6 {
            model_totals[k] += counts[k];
        }
    }
    // The polish exists to solve what the filter alone misses: it must not lose cases.
    assert!(
        totals[3] >= totals[1] && totals[4] >= totals[1] && model_totals[3] >= model_totals[1],
        "the on-board polish lost cases: {totals:?}, models {model_totals:?}"
    );
}
