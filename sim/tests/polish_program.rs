//! The Verilated polish datapath (`PolishProgram` with the solve's program, the Verilog that
//! `pficp_fpga::rtl::polish_program_verilog` generates) against
//! `pficp_fpga::polish::program::run`: after each solve, every one of the 64 registers and
//! the failed flag equal the model's. The systems are `polish::program::solve_systems`:
//! random Gram systems (seed `PFICP_COSIM_SEED`, default 1; count `PFICP_POLISH_CASES`,
//! default 150) and the edge systems. rust_hdl's simulator runs the same block on fewer
//! systems and on every instruction's edge cases (`fpga/tests/polish_program.rs`); this test
//! checks the Verilog that synthesis and the board get. A second test accumulates the sums
//! of up to 4,096 rows through the `add` port, as the pass will, and solves them.

use pficp_fpga::polish::program::{
    gram, run, solve_inputs, solve_program, solve_systems, FOUND, INLIERS, REGISTERS, SUM_B, SUM_R2,
};
use pficp_fpga::polish::{upper, UNKNOWNS};
use pficp_fpga::splitmix::SplitMix64;
use pficp_sim::{ProgramInputs, VerilatedPolishProgram};

fn env_or(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

#[test]
fn the_verilated_solve_matches_the_model_register_for_register() {
    let seed = env_or("PFICP_COSIM_SEED", 1);
    let systems = solve_systems(seed, env_or("PFICP_POLISH_CASES", 150) as usize);
    let program = solve_program();
    let mut rtl = VerilatedPolishProgram::new();
    let mut idle = ProgramInputs { reset: true, ..Default::default() };
    rtl.step(&idle);
    idle.reset = false;
    let (mut stops, mut clocks) = (0, Vec::new());
    for (case, sums) in systems.iter().enumerate() {
        let inputs = solve_inputs(sums);
        let mut want = inputs;
        let want_failed = run(&program, &mut want).is_err();
        stops += want_failed as usize;
        for (addr, &v) in inputs.iter().enumerate() {
            rtl.step(&ProgramInputs { load: true, load_addr: addr as u8, load_data: v, ..idle });
        }
        rtl.step(&ProgramInputs { go: true, ..idle });
        let start = rtl.cycle();
        while rtl.outputs().busy {
            rtl.step(&idle);
            assert!(rtl.cycle() - start < 100_000, "seed {seed}, case {case}: still busy after 100,000 clocks");
        }
        clocks.push(rtl.cycle() - start);
        assert_eq!(rtl.outputs().failed, want_failed, "seed {seed}, case {case}: the failed flag");
        for (addr, &w) in want.iter().enumerate().take(REGISTERS) {
            rtl.step(&ProgramInputs { read_addr: addr as u8, ..idle });
            assert_eq!(rtl.outputs().read_data, w, "seed {seed}, case {case}: register {addr}");
        }
    }
    assert!(stops > 0 && stops < systems.len(), "both outcomes: {stops} stops of {}", systems.len());
    clocks.sort_unstable();
    eprintln!(
        "{} solves, clocks: min {}, median {}, max {}",
        clocks.len(),
        clocks[0],
        clocks[clocks.len() / 2],
        clocks[clocks.len() - 1]
    );
}

#[test]
fn sums_added_row_by_row_solve_as_the_model() {
    let seed = env_or("PFICP_COSIM_SEED", 1);
    let mut rng = SplitMix64(seed ^ 0xadd5);
    let program = solve_program();
    let mut rtl = VerilatedPolishProgram::new();
    let mut idle = ProgramInputs { reset: true, ..Default::default() };
    rtl.step(&idle);
    idle.reset = false;
    for case in 0..8 {
        let n_rows = 5 + rng.below(16) as usize;
        let repeat = 1 + rng.below(4096 / n_rows as u64) as i64;
        let mut entry = |bits: u32| (rng.next_u64() >> (64 - bits)) as i64 - (1 << (bits - 1));
        let rows: Vec<([i64; UNKNOWNS], i64)> =
            (0..n_rows).map(|_| (std::array::from_fn(|_| entry(18)), entry(13))).collect();
        let mut want = solve_inputs(&gram(&rows, repeat));
        let want_failed = run(&program, &mut want).is_err();
        for addr in 0..REGISTERS {
            rtl.step(&ProgramInputs { load: true, load_addr: addr as u8, load_data: 0, ..idle });
        }
        for _ in 0..repeat {
            for (j, s) in &rows {
                for r in 0..UNKNOWNS {
                    let products = (r..UNKNOWNS).map(|c| (upper(r, c), j[r] * j[c]));
                    for (addr, v) in products.chain([(SUM_B as usize + r, j[r] * s)]) {
                        rtl.step(&ProgramInputs { add: true, add_addr: addr as u8, add_data: v, ..idle });
                    }
                }
                // The statistics, as the pass adds them.
                for (addr, v) in [(SUM_R2, s * s), (FOUND, 1), (INLIERS, 1)] {
                    rtl.step(&ProgramInputs { add: true, add_addr: addr, add_data: v, ..idle });
                }
            }
        }
        rtl.step(&idle);
        rtl.step(&ProgramInputs { go: true, ..idle });
        while rtl.outputs().busy {
            rtl.step(&idle);
        }
        assert_eq!(rtl.outputs().failed, want_failed, "seed {seed}, case {case}: the failed flag");
        for (addr, &w) in want.iter().enumerate() {
            rtl.step(&ProgramInputs { read_addr: addr as u8, ..idle });
            assert_eq!(
                rtl.outputs().read_data,
                w,
                "seed {seed}, case {case} ({n_rows} rows x {repeat}): register {addr}"
            );
        }
    }
}
