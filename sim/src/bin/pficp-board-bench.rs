//! `pficp-board-bench`: the modelled board time of one PF-ICP registration with the board
//! weighing the particles (the host-driven mode of `pficp register --board`), beside the
//! software mode's time on this machine.
//!
//! The registration really runs: the host client talks over a pseudo-terminal to the
//! byte-level reference (bit-exact with the Verilated board, see sim/tests/e2e_pty.rs),
//! which gives the exact bytes each way and the number of particle evaluations. The board
//! time is then modelled at the generated clock: UART = bytes x 10 bits / the baud
//! rate (the board's UART keeps the nominal rate exactly on average); compute = per evaluated particle the pipeline's
//! clocks as the brute-force pipeline counts them (`pipeline::clocks_per_particle`; since
//! protocol 3 the board searches the grid and takes several times fewer, so the compute
//! figure is an upper bound: `pficp-onboard-bench` counts the board's real clocks) plus the command
//! engine's per-pose work (fetching 27 bytes at 2 clocks each, emitting 6 cost bytes at 9
//! clocks each: 108 clocks). Request, compute and answer do not overlap (the board answers
//! each frame before the host sends the next).
//!
//! `pficp-board-bench [--model-points 2000] [--scan-points 1000] [--particles 50]
//! [--iterations 50] [--runs 3]`; run in release.

use anyhow::{Context, Result};
use clap::Parser;
use pficp::board::host_driven;
use pficp::board::pty::PtyBoard;
use pficp::board::BoardClient;
use pficp::cloud::bbox_diagonal;
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::{self, PfIcpSettings};
use pficp::registration::methods::PoseError;
use pficp_fpga::board::BoardConfig;
use pficp_fpga::search::pipeline::clocks_per_particle;
use std::time::{Duration, Instant};

/// The command engine's clocks per evaluated pose besides the pipeline's.
const ENGINE_CLOCKS_PER_POSE: u64 = 27 * 2 + 6 * 9;

#[derive(Parser, Debug)]
#[command(name = "pficp-board-bench", about = "Modelled board time of one registration beside the software mode")]
struct Args {
    #[arg(long, default_value_t = 2000)]
    model_points: usize,
    #[arg(long, default_value_t = 1000)]
    scan_points: usize,
    #[arg(long, default_value_t = 50)]
    particles: usize,
    #[arg(long, default_value_t = 50)]
    iterations: usize,
    /// Software-mode runs (the median is reported).
    #[arg(long, default_value_t = 3)]
    runs: usize,
}

fn main() -> Result<()> {
    let args = Args::parse();
    let config = BoardConfig::default();
    let id = ModelId::Model1;
    let truth = id.table1_truth();
    let spec = ScanSpec { sampling: Sampling::Independent { points: args.scan_points }, noise: 0.0, seed: 1 };
    let ds = make(id, args.model_points, &truth, &spec);
    let diag = bbox_diagonal(&ds.model);
    let nn = NearestNeighbours::new(&ds.model);
    let settings = PfIcpSettings {
        particles: args.particles,
        iterations: args.iterations,
        weight_points: args.scan_points,
        ..Default::default()
    };

    let mut soft_times = Vec::new();
    let mut soft = None;
    for _ in 0..args.runs.max(1) {
        let t = Instant::now();
        let r = pf_icp::register(&nn, &ds.scan, &settings);
        soft_times.push(t.elapsed().as_secs_f64());
        soft = Some(r);
    }
    soft_times.sort_by(f64::total_cmp);
    let soft = soft.unwrap();
    let soft_median = soft_times[soft_times.len() / 2];

    let mut board = PtyBoard::reference(config).context("a pseudo-terminal")?;
    let path = board.path.clone();
    let mut client = BoardClient::open(&path, config.baud, Duration::from_secs(10))?;
    let r = host_driven::register(&mut client, &nn, &ds.scan, &settings, &mut |_, _, _| {})?;
    board.stop();

    let poses = (r.board.iterations * args.particles) as u64;
    let bytes = (r.board.stats.bytes_sent + r.board.stats.bytes_received) as u64;
    let uart_s = bytes as f64 * 10.0 / config.baud as f64;
    let per_pose =
        clocks_per_particle(r.board.scan_points, r.board.model_points, config.lanes) + ENGINE_CLOCKS_PER_POSE;
    let compute_s = (poses * per_pose) as f64 / config.clock_hz as f64;
    let e_board = PoseError::between(&r.pf.registration.pose, &truth, diag);
    let e_soft = PoseError::between(&soft.registration.pose, &truth, diag);
    println!(
        "model-1: {} model points, {} scan points, {} particles, {} iterations run (cap {})",
        r.board.model_points, r.board.scan_points, args.particles, r.board.iterations, args.iterations
    );
    println!(
        "board (modelled at {} MHz, {} lanes, {} baud): UART {:.3} s ({} bytes), compute {:.3} s ({} poses x {} clocks), total {:.3} s",
        config.clock_hz / 1_000_000,
        config.lanes,
        config.baud,
        uart_s,
        bytes,
        compute_s,
        poses,
        per_pose,
        uart_s + compute_s
    );
    println!(
        "software mode on this machine: median {:.3} s of {} runs ({} iterations)",
        soft_median,
        soft_times.len(),
        soft.registration.iterations
    );
    println!(
        "errors vs truth: board rotation {:.3} deg, translation {:.4}% diag; software {:.3} deg, {:.4}%",
        e_board.rotation_deg,
        100.0 * e_board.translation_frac,
        e_soft.rotation_deg,
        100.0 * e_soft.translation_frac
    );
    Ok(())
}
