//! How many scan points the on-board filter needs per particle weight: PF-ICP with the
//! whole filter on the board (bit-exact: `pficp_fpga::pf::run`, which the byte-level
//! reference board runs for Run) and the host's polish, for several board sample sizes,
//! beside the software mode, on models 1 to 3 (Table 1 truths, 2,000 model points, an
//! independent 1,000-point scan, 50 particles, 50 iterations, several seeds).
//!
//! Slow (minutes): ignored by default. Run it with
//! `cargo test --release -p pficp-host --test on_board_sample -- --ignored --nocapture`
//! (`PFICP_SAMPLE_SEEDS=N` for N seeds per model, default 10; `PFICP_SAMPLE_SIZES=50,100`
//! for other sample sizes; `PFICP_SAMPLE_NOISE_PERCENT=1` for `U(0, 1%` of the diagonal`)`
//! noise on every scan coordinate, default 0). The tables it prints are in
//! docs/decisions.md.

use pficp::board::on_board;
use pficp::cloud::bbox_diagonal;
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::{self, PfIcpSettings};
use pficp::registration::methods::{PoseError, Tolerance};
use pficp_fpga::board::BoardConfig;
use pficp_fpga::messages::ResultReply;
use pficp_fpga::pf;
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
#[ignore = "minutes in release; prints the table of docs/decisions.md"]
fn scan_points_per_weight_on_the_board() {
    let seeds = env_list("PFICP_SAMPLE_SEEDS", &[10])[0] as u64;
    let noise_percent =
        std::env::var("PFICP_SAMPLE_NOISE_PERCENT").ok().and_then(|s| s.parse::<f64>().ok()).unwrap_or(0.0);
    let sizes = env_list("PFICP_SAMPLE_SIZES", &[50, 100, 150, 200]);
    println!("{seeds} seeds per model, noise {noise_percent}% of the diagonal, board samples {sizes:?}");
    let board = BoardConfig::default();
    // columns: software, then each board sample size
    let mut table: Vec<(ModelId, Vec<Vec<Trial>>)> = Vec::new();
    for id in ModelId::ALL {
        let mut columns: Vec<Vec<Trial>> = vec![Vec::new(); 1 + sizes.len()];
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
            let trials: Vec<Trial> = sizes
                .par_iter()
                .map(|&s| {
                    let plan = on_board::plan_with_prior(prior.clone(), &nn, &ds.scan, &settings, s, 4096);
                    let out = pf::run(&plan.config, |p| pf::evaluate(&plan.model, &plan.scan, p));
                    let r = on_board::finish(&plan, &nn, &ds.scan, &settings, &ResultReply::of(&out), Duration::ZERO);
                    let pose = &r.registration.pose;
                    let clocks = pficp::board::run_clocks_bound(
                        plan.config.particles,
                        out.iterations,
                        plan.scan.len(),
                        plan.model.len(),
                        board.lanes,
                    );
                    Trial {
                        ok: Tolerance::SUCCESS.accepts(pose, &truth, diag),
                        error: PoseError::between(pose, &truth, diag),
                        iterations: out.iterations as usize,
                        board_s: clocks as f64 / board.clock_hz as f64,
                    }
                })
                .collect();
            let e0 = columns[0].last().unwrap().error;
            eprint!("{} seed {seed}: software {:.3} deg", id.name(), e0.rotation_deg);
            for (c, t) in trials.into_iter().enumerate() {
                eprint!(", S={} {:.3} deg ({} it)", sizes[c], t.error.rotation_deg, t.iterations);
                columns[c + 1].push(t);
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
            } else {
                format!("board, S = {}", sizes[c - 1])
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
