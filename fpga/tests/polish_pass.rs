//! `PolishBench` (the pass, a `PipeMul` and the program's datapath, wired as the board will
//! wire them) in rust_hdl's simulator against [`pficp_fpga::polish::PassSums::add_point`]
//! with [`pficp_fpga::polish::jacobian`]: the passes of `polish::cases::pass_cases` (gated
//! and not, rows saturating both ways), fed back to back and with gaps; after each pass and
//! its flush the 38 registers the pass adds to equal the model's sums, and after the solve that follows
//! (the program run on `go`) every register and the failed flag equal the model's.
#![cfg(feature = "rtl")]

use pficp_fpga::common::format::{pack_point, pack_translation};
use pficp_fpga::polish::bench_rtl::PolishBench;
use pficp_fpga::polish::cases::{pass_cases, PassCase};
use pficp_fpga::polish::programs::{rom, run, solve_inputs, Entry, FOUND, INLIERS, SUM_R2};
use rust_hdl::prelude::*;
use std::sync::{Arc, Mutex};

/// A 128-bit word as a signed value.
fn value(b: Bits<128>) -> i128 {
    ((b.get_bits::<64>(64).to_u64() as u128) << 64 | b.get_bits::<64>(0).to_u64() as u128) as i128
}

#[test]
fn a_pass_adds_the_models_sums_and_the_solve_takes_them() {
    let passes: Vec<PassCase> = pass_cases(0x9a55, 24);
    let sums: Vec<[i128; 64]> = passes.iter().map(|p| solve_inputs(&p.sums())).collect();
    let solved: Vec<([i128; 64], bool)> = sums
        .iter()
        .map(|r| {
            let mut r = *r;
            let failed = run(Entry::Solve, &mut r).is_err();
            (r, failed)
        })
        .collect();
    assert!(solved.iter().any(|s| s.1) && solved.iter().any(|s| !s.1), "both outcomes of the solve");
    let found = Arc::new(Mutex::new(Vec::<String>::new()));
    let out = found.clone();
    let mut uut = PolishBench::new();
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<PolishBench>| x.clock.next = !x.clock.val());
    sim.add_testbench(move |mut sim: Sim<PolishBench>| {
        let mut x = sim.init()?;
        wait_clock_true!(sim, clock, x);
        for (case, pass) in passes.iter().enumerate() {
            for addr in 0..64u64 {
                x.load.next = true;
                x.load_addr.next = addr.into();
                x.load_data.next = Bits::<128>::default();
                wait_clock_cycle!(sim, clock, x);
            }
            x.load.next = false;
            x.gated.next = pass.tau2.is_some();
            x.tau2.next = Bits::<32>::from(pass.tau2.unwrap_or(0).min(u32::MAX as u64));
            x.scale_held.next = pass.scale == pficp_fpga::polish::ScaleStep::Held;
            x.t.next = Bits::<54>::from(pack_translation(pass.t));
            for (i, &(q, n, s)) in pass.points.iter().enumerate() {
                while !x.ready.val() {
                    wait_clock_cycle!(sim, clock, x);
                }
                x.in_valid.next = true;
                x.in_q.next = Bits::<48>::from(pack_point(q));
                x.in_n.next = Bits::<48>::from(pack_point(n));
                x.in_s.next = Bits::<13>::from((s as u64) & 0x1fff);
                wait_clock_cycle!(sim, clock, x);
                x.in_valid.next = false;
                // A gap now and then.
                for _ in 0..(i % 3) {
                    wait_clock_cycle!(sim, clock, x);
                }
            }
            // The flush: the accumulators into the registers, `idle` once they are in.
            x.flush.next = true;
            wait_clock_cycle!(sim, clock, x);
            x.flush.next = false;
            wait_clock_cycle!(sim, clock, x);
            let mut waited = 0;
            while !x.idle.val() {
                wait_clock_cycle!(sim, clock, x);
                waited += 1;
                sim_assert!(sim, waited < 100, x);
            }
            for addr in (0..35).chain([SUM_R2, FOUND, INLIERS].map(|r| r as usize)) {
                x.read_addr.next = (addr as u64).into();
                wait_clock_cycle!(sim, clock, x);
                let got = value(x.read_data.val());
                if got != sums[case][addr] {
                    out.lock().unwrap().push(format!("pass {case}: r{addr} = {got}, the model {}", sums[case][addr]));
                }
            }
            // The solve on what the pass added.
            x.go.next = true;
            x.entry.next = (rom().entry(Entry::Solve as usize) as u64).into();
            wait_clock_cycle!(sim, clock, x);
            x.go.next = false;
            while x.busy.val() {
                wait_clock_cycle!(sim, clock, x);
            }
            let (want, want_failed) = &solved[case];
            if x.failed.val() != *want_failed {
                out.lock().unwrap().push(format!("pass {case}: the solve failed {}", x.failed.val()));
            }
            for (addr, &w) in want.iter().enumerate() {
                x.read_addr.next = (addr as u64).into();
                wait_clock_cycle!(sim, clock, x);
                if value(x.read_data.val()) != w {
                    out.lock().unwrap().push(format!("pass {case}, solved: r{addr}, the model {w}"));
                }
            }
        }
        sim.done(x)
    });
    sim.run(Box::new(uut), 1_000_000_000).expect("simulation");
    let errors = found.lock().unwrap();
    assert!(errors.is_empty(), "{} mismatches, the first: {}", errors.len(), errors[0]);
}
