//! The pipeline's design-point figures and Verilator's simulated clocks per second.
//!
//! First the design point: one particle of N_M = 1,000 scan points against N_D = 2,000
//! model points through the Verilated RTL (checked against the functional reference):
//! clocks per particle (measured, and the closed form of docs/pipeline.md), distances per
//! clock, lane utilisation and the time per particle at 100 MHz.
//!
//! Then `pficp-sim-bench [lanes] [seconds]` (default 16 lanes, 3 s): particles of 256 scan points
//! on a 1,024-point model, (1) the RTL alone, (2) in lockstep with the reference, (3) the
//! RTL alone writing a VCD. Run it in release: `cargo run --release -p pficp-sim --bin pficp-sim-bench`.
use pficp_fpga::format::{FxPoint, FxPose};
use pficp_fpga::pipeline::evaluate;
use pficp_sim::{Lockstep, VerilatedPipeline};
use std::time::{Duration, Instant};

fn lcg(seed: &mut u64) -> u64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *seed >> 33
}

fn cloud(n: usize, seed: &mut u64) -> Vec<FxPoint> {
    (0..n).map(|_| [0; 3].map(|_: i16| ((lcg(seed) % 40001) as i64 - 20000) as i16)).collect()
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let lanes: usize = args.first().map(|s| s.parse()).transpose()?.unwrap_or(16);
    let secs: f64 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(3.0);
    let budget = Duration::from_secs_f64(secs);
    let mut seed = 1;
    let model = cloud(1024, &mut seed);
    let scan = cloud(256, &mut seed);
    let pose = FxPose::from_f64(&[0.9, -0.3, 0.1, 0.3, 0.9, 0.0, -0.1, 0.05, 0.95], &[0.1, -0.2, 0.05]);
    let expected = evaluate(&model, &scan, &pose);
    // Design point.
    {
        let (n_m, n_d) = (1000usize, 2000usize);
        let mut seed = 7;
        let model = cloud(n_d, &mut seed);
        let scan = cloud(n_m, &mut seed);
        let mut rtl = VerilatedPipeline::new(lanes);
        rtl.load_model(&model);
        let t0 = Instant::now();
        let (got, clocks) = rtl.particle(model.len(), &scan, &pose, |_| false);
        let wall = t0.elapsed().as_secs_f64();
        anyhow::ensure!(got == evaluate(&model, &scan, &pose), "RTL result differs from the functional reference");
        let formula = pficp_fpga::pipeline::clocks_per_particle(n_m, n_d, lanes);
        anyhow::ensure!(clocks == formula, "measured {clocks} clocks, the closed form says {formula}");
        let per_clock = (n_m * n_d) as f64 / clocks as f64;
        println!("design point: P = {lanes}, N_M = {n_m} scan points, N_D = {n_d} model points");
        println!("  clocks per particle     {clocks} (measured in Verilator = closed form)");
        println!(
            "  distances per clock     {per_clock:.2} of {lanes} lanes ({:.1}% utilisation)",
            100.0 * per_clock / lanes as f64
        );
        println!("  time per particle       {:.3} ms at 100 MHz", clocks as f64 / 100e6 * 1e3);
        println!("  50 particles x 50 iter. {:.2} s at 100 MHz (compute only)", 2500.0 * clocks as f64 / 100e6);
        println!("  Verilator               {:.0} clocks/s on this particle", clocks as f64 / wall);
    }
    println!("P = {lanes}, model 1024 points, particles of 256 scan points, {secs} s per measurement");

    // (1) RTL alone.
    let mut rtl = VerilatedPipeline::new(lanes);
    rtl.load_model(&model);
    let (c0, t0) = (rtl.cycle(), Instant::now());
    let mut particles = 0;
    let mut per_particle = 0;
    while t0.elapsed() < budget {
        let (got, clocks) = rtl.particle(model.len(), &scan, &pose, |_| false);
        anyhow::ensure!(got == expected, "RTL result differs from the functional reference");
        per_particle = clocks;
        particles += 1;
    }
    let rate = (rtl.cycle() - c0) as f64 / t0.elapsed().as_secs_f64();
    println!(
        "Verilator (RTL alone):          {:>10.0} clocks/s  ({particles} particles, {per_particle} clocks each, {:.1} particles/s)",
        rate,
        rate / per_particle as f64
    );

    // (2) Lockstep with the reference.
    let mut ls = Lockstep::new(lanes);
    ls.load_model(&model)?;
    let (c0, t0) = (ls.clocks_compared(), Instant::now());
    while t0.elapsed() < budget {
        let (got, _) = ls.particle(model.len(), &scan, &pose, |_| false)?;
        anyhow::ensure!(got == expected, "lockstep result differs from the functional reference");
    }
    let rate = (ls.clocks_compared() - c0) as f64 / t0.elapsed().as_secs_f64();
    println!("lockstep (RTL + PipelineModel): {rate:>10.0} clocks/s");

    // (3) RTL alone with a VCD (one particle).
    let path = std::env::temp_dir().join(format!("pficp-sim-bench-{}.vcd", std::process::id()));
    let mut rtl = VerilatedPipeline::new(lanes);
    rtl.trace_to(&path)?;
    rtl.load_model(&model);
    let (c0, t0) = (rtl.cycle(), Instant::now());
    rtl.particle(model.len(), &scan, &pose, |_| false);
    let rate = (rtl.cycle() - c0) as f64 / t0.elapsed().as_secs_f64();
    drop(rtl);
    let size = std::fs::metadata(&path)?.len();
    let _ = std::fs::remove_file(&path);
    println!("Verilator writing a VCD:        {rate:>10.0} clocks/s  ({:.1} MB)", size as f64 / 1e6);
    Ok(())
}
