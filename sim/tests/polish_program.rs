//! The Verilated polish datapath (`PolishProgram` with the polish's programs in ROM, the
//! Verilog that `pficp_fpga::common::verilog::polish_program_verilog` generates) against
//! `pficp_fpga::polish::program::run`: after each program, every one of the 64 registers
//! and the failed flag equal the model's. The files are `polish::cases::program_cases`
//! (seed `PFICP_COSIM_SEED`, default 1; `PFICP_POLISH_CASES` random cases a program,
//! default 150): noise around each program's inputs, the solve's random Gram systems and
//! edge systems, the update up to its saturation, the gate, the start, the clear and the
//! drift check on both sides of its bounds. rust_hdl's simulator runs the same block on
//! fewer cases and on every instruction's edge cases (`fpga/tests/polish_program.rs`); this
//! test checks the Verilog that synthesis and the board get. A second test accumulates the
//! sums of up to 4,096 rows through the `add` port, as the pass will, and solves them.

use pficp_fpga::common::splitmix::SplitMix64;
use pficp_fpga::polish::cases::{gram, program_cases, random_rows};
use pficp_fpga::polish::program::{program_clocks_bound, REGISTERS};
use pficp_fpga::polish::programs::{inlier_adds, rom, run, solve_inputs, Entry};
use pficp_sim::{ProgramInputs, VerilatedPolishProgram};

fn env_or(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// A reset datapath and its idle inputs.
fn datapath() -> (VerilatedPolishProgram, ProgramInputs) {
    let mut rtl = VerilatedPolishProgram::new();
    let mut idle = ProgramInputs { reset: true, ..Default::default() };
    rtl.step(&idle);
    idle.reset = false;
    (rtl, idle)
}

/// Run `entry` and wait for it (fails if it is still busy after `limit` clocks: the tests
/// pass one more than its [`program_clocks_bound`]); its clocks.
fn go(rtl: &mut VerilatedPolishProgram, idle: &ProgramInputs, entry: Entry, limit: u64, what: &str) -> u64 {
    rtl.step(&ProgramInputs { go: true, entry: rom().entry(entry as usize) as u16, ..*idle });
    let start = rtl.cycle();
    while rtl.outputs().busy {
        rtl.step(idle);
        assert!(rtl.cycle() - start < limit, "{what}: still busy after {limit} clocks");
    }
    rtl.cycle() - start
}

/// Every register and the failed flag against the model's.
fn compare(rtl: &mut VerilatedPolishProgram, idle: &ProgramInputs, want: &[i128; REGISTERS], failed: bool, what: &str) {
    assert_eq!(rtl.outputs().failed, failed, "{what}: the failed flag");
    for (addr, &w) in want.iter().enumerate() {
        rtl.step(&ProgramInputs { read_addr: addr as u8, ..*idle });
        assert_eq!(rtl.outputs().read_data, w, "{what}: register {addr}");
    }
}

#[test]
fn the_verilated_programs_match_the_model_register_for_register() {
    let seed = env_or("PFICP_COSIM_SEED", 1);
    let cases = program_cases(seed, env_or("PFICP_POLISH_CASES", 150) as usize);
    let (mut rtl, idle) = datapath();
    let mut clocks: Vec<(Entry, u64, bool)> = Vec::new();
    for (case, (entry, file)) in cases.iter().enumerate() {
        let what = format!("seed {seed}, case {case} ({entry:?})");
        let mut want = *file;
        let failed = run(*entry, &mut want).is_err();
        for (addr, &v) in file.iter().enumerate() {
            rtl.step(&ProgramInputs { load: true, load_addr: addr as u8, load_data: v, ..idle });
        }
        let bound = program_clocks_bound(&entry.program());
        let took = go(&mut rtl, &idle, *entry, bound + 1, &what);
        clocks.push((*entry, took, failed));
        compare(&mut rtl, &idle, &want, failed, &what);
    }
    for e in Entry::ALL {
        let mut of: Vec<u64> = clocks.iter().filter(|c| c.0 == e && !c.2).map(|c| c.1).collect();
        let stops = clocks.iter().filter(|c| c.0 == e && c.2).count();
        of.sort_unstable();
        eprintln!(
            "{e:?}: {} runs ({stops} failed), clocks of the rest: min {}, median {}, max {} (bound {})",
            of.len() + stops,
            of[0],
            of[of.len() / 2],
            of[of.len() - 1],
            program_clocks_bound(&e.program())
        );
    }
}

#[test]
fn sums_added_row_by_row_solve_as_the_model() {
    let seed = env_or("PFICP_COSIM_SEED", 1);
    let mut rng = SplitMix64(seed ^ 0xadd5);
    let (mut rtl, idle) = datapath();
    for case in 0..8 {
        let n_rows = 5 + rng.below(16) as usize;
        let repeat = 1 + rng.below(4096 / n_rows as u64) as i64;
        let rows = random_rows(&mut rng, n_rows);
        let mut want = solve_inputs(&gram(&rows, repeat));
        let failed = run(Entry::Solve, &mut want).is_err();
        for addr in 0..REGISTERS {
            rtl.step(&ProgramInputs { load: true, load_addr: addr as u8, load_data: 0, ..idle });
        }
        for _ in 0..repeat {
            for (j, s) in &rows {
                for (addr, v) in inlier_adds(j, *s) {
                    rtl.step(&ProgramInputs { add: true, add_addr: addr, add_data: v, ..idle });
                }
            }
        }
        rtl.step(&idle);
        let what = format!("seed {seed}, case {case} ({n_rows} rows x {repeat})");
        go(&mut rtl, &idle, Entry::Solve, program_clocks_bound(&Entry::Solve.program()) + 1, &what);
        compare(&mut rtl, &idle, &want, failed, &what);
    }
}
