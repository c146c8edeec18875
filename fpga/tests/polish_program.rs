//! `PolishProgram` in rust_hdl's simulator against [`pficp_fpga::polish::program::run`]:
//! each of the polish's programs, started at its entry in the one ROM, on the files of
//! `polish::cases::program_cases` (noise around each program's inputs; the solve's
//! edge systems, the update's saturation, the gate without found points, the drift check
//! on both sides of its bounds). After each run every one of the 64 registers and the failed
//! flag must equal the model's; a short program takes every instruction through its edge
//! cases the same way, and the solve also runs on sums accumulated through the `add` port,
//! as the pass will.
#![cfg(feature = "rtl")]

use pficp_fpga::common::splitmix::SplitMix64;
use pficp_fpga::polish::cases::{gram, program_cases, random_rows};
use pficp_fpga::polish::program::{add_port, Op, Rom, REGISTERS};
use pficp_fpga::polish::program_rtl::PolishProgram;
use pficp_fpga::polish::programs::{inlier_adds, rom, solve_inputs, Entry};
use rust_hdl::prelude::*;
use std::sync::{Arc, Mutex};

/// `v` as a 128-bit word.
fn word(v: i128) -> Bits<128> {
    (0..128).fold(Bits::<128>::default(), |b, i| b.replace_bit(i, (v >> i) & 1 == 1))
}

/// A 128-bit word as a signed value.
fn value(b: Bits<128>) -> i128 {
    ((b.get_bits::<64>(64).to_u64() as u128) << 64 | b.get_bits::<64>(0).to_u64() as u128) as i128
}

/// A run: the register file loaded, then values added through the `add` port, then the
/// ROM's program `entry`.
struct Case {
    entry: usize,
    load: [i128; REGISTERS],
    adds: Vec<(usize, i64)>,
}

/// A case that loads `r0`, adds nothing and runs `entry`.
fn loaded(entry: usize, r0: [i128; REGISTERS]) -> Case {
    Case { entry, load: r0, adds: Vec::new() }
}

/// Run each case in `PolishProgram` with `rom`, and in the model; every register and the
/// failed flag must agree. Returns the clocks of each run.
fn check(rom: &Rom, cases: Vec<Case>) -> Vec<u64> {
    let expected: Vec<([i128; REGISTERS], bool)> = cases
        .iter()
        .map(|c| {
            let mut r = c.load;
            for &(addr, v) in &c.adds {
                r[addr] = add_port(r[addr], v);
            }
            let failed = rom.run(c.entry, &mut r).is_err();
            (r, failed)
        })
        .collect();
    let entries: Vec<u64> = cases.iter().map(|c| rom.entry(c.entry) as u64).collect();
    let found = Arc::new(Mutex::new(Vec::<String>::new()));
    let clocks = Arc::new(Mutex::new(Vec::<u64>::new()));
    let (out, out_clocks) = (found.clone(), clocks.clone());
    let mut uut = PolishProgram::new(&rom.words());
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<PolishProgram>| x.clock.next = !x.clock.val());
    sim.add_testbench(move |mut sim: Sim<PolishProgram>| {
        let mut x = sim.init()?;
        x.reset.next = false;
        wait_clock_true!(sim, clock, x);
        for (case, (c, (want, want_failed))) in cases.iter().zip(&expected).enumerate() {
            for (addr, &v) in c.load.iter().enumerate() {
                x.load.next = true;
                x.load_addr.next = (addr as u64).into();
                x.load_data.next = word(v);
                wait_clock_cycle!(sim, clock, x);
            }
            x.load.next = false;
            for &(addr, v) in &c.adds {
                x.add.next = true;
                x.add_addr.next = (addr as u64).into();
                x.add_data.next = Bits::<48>::from(v as u64 & ((1 << 48) - 1));
                wait_clock_cycle!(sim, clock, x);
            }
            x.add.next = false;
            wait_clock_cycle!(sim, clock, x);
            x.go.next = true;
            x.entry.next = entries[case].into();
            wait_clock_cycle!(sim, clock, x);
            x.go.next = false;
            let mut n = 0u64;
            while x.busy.val() && n < 200_000 {
                wait_clock_cycle!(sim, clock, x);
                n += 1;
            }
            out_clocks.lock().unwrap().push(n);
            if x.failed.val() != *want_failed {
                out.lock().unwrap().push(format!("case {case}: failed {} against {want_failed}", x.failed.val()));
            }
            for (addr, &w) in want.iter().enumerate() {
                x.read_addr.next = (addr as u64).into();
                wait_clock_cycle!(sim, clock, x);
                if value(x.read_data.val()) != w {
                    out.lock()
                        .unwrap()
                        .push(format!("case {case}: r{addr} = {}, the model {w}", value(x.read_data.val())));
                }
            }
        }
        sim.done(x)
    });
    sim.run(Box::new(uut), 1_000_000_000).expect("simulation");
    let errors = found.lock().unwrap();
    assert!(errors.is_empty(), "{} mismatches, the first: {}", errors.len(), errors[0]);
    let clocks = clocks.lock().unwrap().clone();
    clocks
}

#[test]
fn every_program_of_the_polish_matches_the_model_register_for_register() {
    let cases = program_cases(0x5eed_0013, 4);
    for e in Entry::ALL {
        let outcomes: Vec<bool> = cases
            .iter()
            .filter(|c| c.0 == e)
            .map(|(_, r)| pficp_fpga::polish::programs::run(e, &mut r.clone()).is_err())
            .collect();
        eprintln!("{e:?}: {} cases, {} failed", outcomes.len(), outcomes.iter().filter(|&&f| f).count());
    }
    let entries: Vec<Entry> = cases.iter().map(|c| c.0).collect();
    let clocks = check(rom(), cases.into_iter().map(|(e, r)| loaded(e as usize, r)).collect());
    for e in Entry::ALL {
        let of: Vec<u64> = entries.iter().zip(&clocks).filter(|(&c, _)| c == e).map(|(_, &n)| n).collect();
        eprintln!("{e:?}: clocks {of:?}");
    }
}

/// The pass's way in: zero the file, add each row's products and statistics back to back
/// ([`inlier_adds`]), then run the solve; the registers must equal the model's solve of
/// the same rows ([`gram`]), a solve that takes a step.
#[test]
fn adds_accumulate_the_sums_the_solve_then_takes() {
    let mut rng = SplitMix64(0xadd5);
    let cases: Vec<Case> = [9, 14]
        .iter()
        .map(|&n| {
            let rows = random_rows(&mut rng, n);
            let adds: Vec<(usize, i64)> =
                rows.iter().flat_map(|(j, s)| inlier_adds(j, *s)).map(|(a, v)| (a as usize, v)).collect();
            // The adds sum to the model's sums of the rows, and those solve.
            let mut sums = solve_inputs(&gram(&rows, 1));
            assert!(pficp_fpga::polish::programs::run(Entry::Solve, &mut sums.clone()).is_ok());
            for &(addr, v) in &adds {
                sums[addr] -= v as i128;
            }
            assert!(sums.iter().all(|&v| v == 0));
            Case { entry: Entry::Solve as usize, load: [0; REGISTERS], adds }
        })
        .collect();
    check(rom(), cases);
}

/// Every kind of instruction on its edge cases: exact quotients (a remainder equal to the
/// divisor), negative dividends and products, the most negative value, wrapping, a zero
/// divisor, divisors of 64 bits and wider, rounding ties either side of zero, both sides of a clamp and a stop that does
/// and does not fire.
#[test]
fn each_instruction_matches_the_model_on_its_edge_cases() {
    let mut program = Vec::new();
    let mut d = 20u8;
    let mut next = || {
        d += 1;
        d - 1
    };
    for a in 0..6u8 {
        for b in 0..6u8 {
            program.push(Op::Add { d: next(), a, b });
            program.push(Op::Sub { d: next(), a, b });
            program.push(Op::Mul { d: next(), a, b, k: (a + b) % 3 });
            program.push(Op::Div { d: next(), a, b, k: a % 2 });
            program.push(Op::Clamp { d: next(), a, b });
            program.push(Op::Sat { d: next(), a, b });
        }
        program.push(Op::Shr { d: next(), a, k: 1 + a });
        program.push(Op::StopBelow { a, b: 6 });
    }
    // The destinations wrap around the file; the constants come last.
    for op in program.iter_mut() {
        match op {
            Op::Add { d, .. }
            | Op::Sub { d, .. }
            | Op::Mul { d, .. }
            | Op::Div { d, .. }
            | Op::Clamp { d, .. }
            | Op::Sat { d, .. }
            | Op::Shr { d, .. } => *d = 7 + *d % 57,
            _ => {}
        }
    }
    // A rounding whose `+ 1` would overflow 128 bits (the most positive product, k = 1).
    program.push(Op::constant(62, 1));
    program.push(Op::Mul { d: 61, a: 2, b: 62, k: 1 });
    program.push(Op::constant(63, 5 << 100));
    let files: Vec<[i128; REGISTERS]> = [
        [12, 3, -12, -3, 0, 1],
        [i128::MIN, -1, i128::MAX, 2, 7, -7],
        [-6, 4, 6, -4, 10, 5],
        [1 << 100, 3 << 98, -(1 << 64), 1 << 63, 99, -100],
        // Divisors at the divider's 64-bit limit and just over it, remainders of 64 bits.
        [(1 << 64) - 1, -(1 << 120) + 7, 1 << 64, (1 << 64) - 3, i128::MAX - 5, 3 << 62],
    ]
    .iter()
    .flat_map(|six| {
        // Once with a stop bound that lets every test pass, once with one that stops.
        [i128::MIN, 0].map(|bound| {
            let mut r = [0i128; REGISTERS];
            r[..6].copy_from_slice(six);
            r[6] = bound;
            r
        })
    })
    .collect();
    // Behind a one-word program, so that the entry is not zero.
    let rom = Rom::new(vec![vec![Op::constant(0, 1)], program]);
    check(&rom, files.into_iter().map(|r| loaded(1, r)).collect());
}
