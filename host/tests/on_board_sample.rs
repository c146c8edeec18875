//! How many scan points the on-board filter needs per particle weight: PF-ICP with the
//! whole filter on the board (bit-exact: the grid search's `pficp_fpga::filter::pf::run`, which the
//! byte-level reference board runs for Run), its pose alone and after the host's polish,
//! for several board sample sizes, beside the software mode, on models 1 to 3 (Table 1
//! truths, 2,000 model points, an independent 1,000-point scan, 50 particles, 50
//! iterations, several seeds); and the board's search's (the neighbour pipeline's) clocks
//! with the sample in Morton order against the sampler's order.
//!
//! The figures are slow (minutes): ignored by default. Run them with
//! `cargo test --release -p pficp-host --test on_board_sample -- --ignored --nocapture`
//! (`PFICP_SAMPLE_SEEDS=N` for N seeds per model, default 10; `PFICP_SAMPLE_SIZES=300,500`
//! for other sample sizes, default 300, 500, 1,000; `PFICP_SAMPLE_NOISE_PERCENT=1` for
//! `U(0, 1%` of the diagonal`)` noise on every scan coordinate, default 0;
//! `PFICP_SAMPLE_UNCAPPED=1` to emulate the protocol 2 board instead: the brute-force
//! search, distances not capped, to see what the grid's cap changes). The board's cost is
//! the surface residual (protocol 4, `pficp_fpga::surface`). The tables they print are in
//! docs/board-modes.md.

use pficp::board::on_board;
use pficp::board::quantise::{normalised_pose, quantise_pose};
use pficp::cloud::bbox_diagonal;
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::{self, PfIcpSettings};
use pficp::registration::methods::{PoseError, Tolerance};
use pficp_fpga::board::BoardConfig;
use pficp_fpga::common::format::FxPoint;
use pficp_fpga::filter::pf;
use pficp_fpga::protocol::messages::ResultReply;
use pficp_fpga::search::neighbour_pipeline::{clocks_bound, clocks_per_particle};
use rayon::prelude::*;
use std::time::Duration;

/// One registration's outcome.
#[derive(Clone, Copy, Debug)]
struct Trial {
    ok: bool,
    error: PoseError,
    iterations: usize,
    /// Modelled board compute time of the filter [s] (0 for software).
    board_s: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

fn env_list(name: &str, default: &[usize]) -> Vec<usize> {
    std::env::var(name)
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| default.to_vec())
}

#[test]
#[ignore = "minutes in release; prints the table of docs/board-modes.md"]
fn scan_points_per_weight_on_the_board() {
    let seeds = env_list("PFICP_SAMPLE_SEEDS", &[10])[0] as u64;
    let noise_percent =
        std::env::var("PFICP_SAMPLE_NOISE_PERCENT").ok().and_then(|s| s.parse::<f64>().ok()).unwrap_or(0.0);
    let sizes = env_list("PFICP_SAMPLE_SIZES", &[300, 500, 1000]);
    let uncapped = std::env::var("PFICP_SAMPLE_UNCAPPED").is_ok_and(|v| v == "1");
    if uncapped {
        println!("the protocol 2 board: brute-force search, distances not capped");
    }
    println!("{seeds} seeds per model, noise {noise_percent}% of the diagonal, board samples {sizes:?}");
    let board = BoardConfig::default();
    // columns: software, then each board sample size: the board's pose alone, then polished
    let mut table: Vec<(ModelId, Vec<Vec<Trial>>)> = Vec::new();
    for id in ModelId::ALL {
        let mut columns: Vec<Vec<Trial>> = vec![Vec::new(); 1 + 2 * sizes.len()];
        for seed in 1..=seeds {
            let truth = id.table1_truth();
            let noise = noise_percent / 100.0 * bbox_diagonal(&id.model_points(2000));
            let spec = ScanSpec { sampling: Sampling::Independent { points: 1000 }, noise, seed };
            let ds = make(id, 2000, &truth, &spec);
            let diag = bbox_diagonal(&ds.model);
            let nn = NearestNeighbours::new(&ds.model);
            let settings = PfIcpSettings { seed, ..Default::default() };
            let soft = pf_icp::register(&nn, &ds.scan, &settings);
            let pose = &soft.registration.pose;
            columns[0].push(Trial {
                ok: Tolerance::SUCCESS.accepts(pose, &truth, diag),
                error: PoseError::between(pose, &truth, diag),
                iterations: soft.registration.iterations,
                board_s: 0.0,
            });
            let prior = pf_icp::prior(&nn, &ds.scan, &settings);
            let trials: Vec<[Trial; 2]> = sizes
                .par_iter()
                .map(|&s| {
                    let plan = on_board::plan_with_prior(prior.clone(), &nn, &ds.scan, &settings, s, 4096).unwrap();
                    let out = if uncapped {
                        pf::run(&plan.config, |p| {
                            pf::Evaluated::of(&pficp_fpga::search::pipeline::evaluate(&plan.model, &plan.scan, p))
                        })
                    } else {
                        plan.emulate_filter()
                    };
                    // As measured before the on-board polish: the filter's pose, unpolished.
                    let polish = pficp_fpga::protocol::run_request::PolishOutcome {
                        winner: 0,
                        pose: out.pose,
                        cost: out.best.cost,
                    };
                    let run = pficp_fpga::protocol::run_request::RunOutcome { filter: out.clone(), polish };
                    let r = on_board::finish(&plan, &nn, &ds.scan, &settings, &ResultReply::of(&run), Duration::ZERO);
                    let clocks = pficp::board::run_clocks_bound(
                        plan.config.particles,
                        out.iterations,
                        plan.scan.len(),
                        plan.model.len(),
                        board.lanes,
                    );
                    [&r.filter_pose, &r.registration.pose].map(|pose| Trial {
                        ok: Tolerance::SUCCESS.accepts(pose, &truth, diag),
                        error: PoseError::between(pose, &truth, diag),
                        iterations: out.iterations as usize,
                        board_s: clocks as f64 / board.clock_hz as f64,
                    })
                })
                .collect();
            let e0 = columns[0].last().unwrap().error;
            eprint!("{} seed {seed}: software {:.3} deg", id.name(), e0.rotation_deg);
            for (c, [alone, polished]) in trials.into_iter().enumerate() {
                eprint!(
                    ", S={} {:.3} deg alone, {:.3} polished ({} it)",
                    sizes[c], alone.error.rotation_deg, polished.error.rotation_deg, alone.iterations
                );
                columns[1 + 2 * c].push(alone);
                columns[2 + 2 * c].push(polished);
            }
            eprintln!();
        }
        table.push((id, columns));
    }
    println!(
        "\n| model | mode | success | median rotation error [deg] | median translation error [% diag] | median scale error [%] | worst rotation error [deg] | median iterations | modelled board filter time, bound [s] |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (id, columns) in &table {
        for (c, trials) in columns.iter().enumerate() {
            let mode = if c == 0 {
                "software (host filter + ICP)".to_string()
            } else if c % 2 == 1 {
                format!("board alone, S = {}", sizes[(c - 1) / 2])
            } else {
                format!("board + polish, S = {}", sizes[(c - 1) / 2])
            };
            let ok = trials.iter().filter(|t| t.ok).count();
            let rot = median(trials.iter().map(|t| t.error.rotation_deg).collect());
            let worst = trials.iter().map(|t| t.error.rotation_deg).fold(0.0, f64::max);
            let tr = median(trials.iter().map(|t| 100.0 * t.error.translation_frac).collect());
            let sc = median(trials.iter().map(|t| 100.0 * t.error.scale_frac).collect());
            let it = median(trials.iter().map(|t| t.iterations as f64).collect());
            let time = if c == 0 {
                "-".to_string()
            } else {
                format!("{:.2}", median(trials.iter().map(|t| t.board_s).collect()))
            };
            println!(
                "| {} | {mode} | {ok}/{} | {rot:.3} | {tr:.3} | {sc:.3} | {worst:.3} | {it:.0} | {time} |",
                id.name(),
                trials.len()
            );
        }
    }
}

/// Model `id` (2,000 points), an independent scan of `scan_points` (seed 3), the plan of
/// `board_points` and the pose near the truth, quantised.
fn planned(
    id: ModelId,
    scan_points: usize,
    board_points: usize,
) -> (on_board::OnBoardPlan, pficp_fpga::common::format::FxPose) {
    let truth = id.table1_truth();
    let spec = ScanSpec { sampling: Sampling::Independent { points: scan_points }, noise: 0.0, seed: 3 };
    let ds = make(id, 2000, &truth, &spec);
    let nn = NearestNeighbours::new(&ds.model);
    let settings = PfIcpSettings { seed: 3, ..Default::default() };
    let plan = on_board::plan(&nn, &ds.scan, &settings, board_points, 4096).unwrap();
    let near = quantise_pose(&normalised_pose(&truth, &plan.scan_norm, &plan.model_norm));
    (plan, near)
}

/// The sample in the sampler's order (the plan's, before the Morton sort).
fn unsorted(plan: &on_board::OnBoardPlan, id: ModelId, scan_points: usize) -> Vec<FxPoint> {
    let truth = id.table1_truth();
    let spec = ScanSpec { sampling: Sampling::Independent { points: scan_points }, noise: 0.0, seed: 3 };
    let ds = make(id, 2000, &truth, &spec);
    let settings = PfIcpSettings { seed: 3, weight_points: plan.scan.len(), ..Default::default() };
    plan.scan_norm.quantise(&pf_icp::weight_sample(&ds.scan, &settings))
}

/// The deadlines' bound (`neighbour_pipeline::clocks_bound`) holds on models 1 to 3, in the
/// sampler's order and in Morton order, and is no looser than the brute-force count it
/// replaced by more than 20% (the deadlines stay what they were before the grid search).
#[test]
fn the_clock_bound_holds_on_models_1_to_3() {
    let lanes = BoardConfig::default().lanes;
    for id in ModelId::ALL {
        let (plan, near) = planned(id, 1000, 300);
        let start = pf::pose_of(&plan.config.centre);
        let bound = clocks_bound(300, plan.grid.points.len(), lanes);
        let brute = pficp_fpga::search::pipeline::clocks_per_particle(300, plan.grid.points.len(), lanes);
        assert!(bound <= brute + brute * 20 / 100, "{}: bound {bound}, brute force {brute}", id.name());
        let raw = unsorted(&plan, id, 1000);
        for pose in [start, near] {
            let slow = clocks_per_particle(&plan.grid, &raw, &pose, lanes).clocks;
            let sorted = clocks_per_particle(&plan.grid, &plan.scan, &pose, lanes).clocks;
            assert!(sorted <= bound && slow <= bound, "{}: {sorted} and {slow} clocks, bound {bound}", id.name());
        }
    }
}

/// The neighbour pipeline's clocks a particle with the board's sample in the sampler's order and
/// in Morton order (the plan's), at the plan's start pose and near the truth, on models 1
/// to 3 (2,000 model points, a 1,000-point scan, seed 3; 300 board points by default,
/// `PFICP_SAMPLE_SIZES` for others).
#[test]
#[ignore = "seconds in release; prints the table of docs/board-modes.md"]
fn morton_order_clocks() {
    let lanes = BoardConfig::default().lanes;
    println!(
        "| model | S | pose | sampler's order | Morton order | Morton at the start pose | brute force | bound | gain |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for s in env_list("PFICP_SAMPLE_SIZES", &[300]) {
        for id in ModelId::ALL {
            let (plan, near) = planned(id, 1000, s);
            let start = pf::pose_of(&plan.config.centre);
            let raw = unsorted(&plan, id, 1000);
            let mut at_start = raw.clone();
            at_start
                .sort_by_key(|&p| pficp::board::quantise::morton_key(pficp_fpga::common::format::transform(&start, p)));
            let brute = pficp_fpga::search::pipeline::clocks_per_particle(s, plan.grid.points.len(), lanes);
            let bound = clocks_bound(s, plan.grid.points.len(), lanes);
            for (name, pose) in [("start", start), ("truth", near)] {
                let a = clocks_per_particle(&plan.grid, &raw, &pose, lanes).clocks;
                let b = clocks_per_particle(&plan.grid, &plan.scan, &pose, lanes).clocks;
                let c = clocks_per_particle(&plan.grid, &at_start, &pose, lanes).clocks;
                println!(
                    "| {} | {s} | {name} | {a} | {b} | {c} | {brute} | {bound} | {:.2} |",
                    id.name(),
                    a as f64 / b as f64
                );
            }
        }
    }
}
