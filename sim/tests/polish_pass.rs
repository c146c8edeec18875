//! The Verilated polish blocks (`PolishBench`: the pass, a `PipeMul` and the program's
//! datapath, the Verilog that `pficp_fpga::common::verilog::polish_bench_verilog` generates) against
//! the model: the passes of `polish::cases::pass_cases` (seed `PFICP_COSIM_SEED`, default
//! 1; `PFICP_POLISH_POINTS` points a pass, default 200), fed back to back and with gaps;
//! after each pass and its flush the 38 registers it adds to equal `PassSums::add_point`'s sums, and
//! after the solve on them every register and the failed flag equal
//! `polish::programs::run`'s. rust_hdl's simulator runs the same block on fewer points
//! (`fpga/tests/polish_pass.rs`).

use pficp_fpga::polish::cases::pass_cases;
use pficp_fpga::polish::programs::{rom, run, solve_inputs, Entry, FOUND, INLIERS, SUM_R2};
use pficp_sim::{BenchInputs, VerilatedPolishBench};

fn env_or(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

#[test]
fn verilated_passes_add_the_models_sums_and_solve_as_the_model() {
    let seed = env_or("PFICP_COSIM_SEED", 1);
    let points = env_or("PFICP_POLISH_POINTS", 200) as usize;
    let mut rtl = VerilatedPolishBench::new();
    let mut idle = BenchInputs { reset: true, ..Default::default() };
    rtl.step(&idle);
    idle.reset = false;
    let mut solves = [0usize; 2];
    for (case, pass) in pass_cases(seed, points).iter().enumerate() {
        let what = format!("seed {seed}, pass {case}");
        let sums = solve_inputs(&pass.sums());
        for addr in 0..64 {
            rtl.step(&BenchInputs { load: true, load_addr: addr, ..idle });
        }
        let mut feed = BenchInputs {
            gated: pass.tau2.is_some(),
            tau2: pass.tau2.unwrap_or(0).min(u32::MAX as u64) as u32,
            scale_held: pass.scale == pficp_fpga::polish::ScaleStep::Held,
            t: pass.t,
            ..idle
        };
        let start = rtl.cycle();
        for (i, &(q, n, s)) in pass.points.iter().enumerate() {
            while !rtl.outputs().ready {
                rtl.step(&feed);
                assert!(rtl.cycle() - start < 100 * points as u64, "{what}: the pass never takes a point");
            }
            rtl.step(&BenchInputs { in_valid: true, in_q: q, in_n: n, in_s: s, ..feed });
            for _ in 0..(i % 3) {
                rtl.step(&feed);
            }
        }
        // The flush: the accumulators into the registers, `idle` once they are in.
        rtl.step(&BenchInputs { flush: true, ..feed });
        let flushed = rtl.cycle();
        while !rtl.outputs().idle {
            rtl.step(&feed);
            assert!(rtl.cycle() - flushed < 100, "{what}: the flush never ends");
        }
        let clocks = rtl.cycle() - start;
        feed = idle;
        for addr in (0..35).chain([SUM_R2, FOUND, INLIERS].map(|r| r as usize)) {
            rtl.step(&BenchInputs { read_addr: addr as u8, ..feed });
            assert_eq!(rtl.outputs().read_data, sums[addr], "{what}: register {addr} after the pass");
        }
        let mut want = sums;
        let failed = run(Entry::Solve, &mut want).is_err();
        solves[failed as usize] += 1;
        rtl.step(&BenchInputs { go: true, entry: rom().entry(Entry::Solve as usize) as u16, ..feed });
        while rtl.outputs().busy {
            rtl.step(&feed);
        }
        assert_eq!(rtl.outputs().failed, failed, "{what}: the solve's failed flag");
        for (addr, &w) in want.iter().enumerate() {
            rtl.step(&BenchInputs { read_addr: addr as u8, ..feed });
            assert_eq!(rtl.outputs().read_data, w, "{what}: register {addr} after the solve");
        }
        let s = pass.sums();
        eprintln!("{what}: {} points, {} inliers, {clocks} clocks", s.found, s.inliers);
    }
    assert!(solves[0] > 0 && solves[1] > 0, "both outcomes of the solve: {solves:?}");
}
