//! The sequencer's arithmetic blocks, each alone in rust_hdl's simulator against the
//! [`pficp_fpga::pf`] function it implements: the serial multiplier against `i64`
//! products, the divider against `pf::div_signed`, the PRNG step against
//! `pf::Xorshift32`, the CORDIC against `pf::cordic`, the pose program against
//! `pf::run_program`. The whole sequencer is checked clock by clock in the sim crate.
#![cfg(feature = "rtl")]

use pficp_fpga::pf::{self, CORDIC_STEPS, POSE_PROGRAM};
use pficp_fpga::rtl::board::sequencer::{Cordic, PoseProgram, SerialDiv, SerialMul, Xorshift32};
use rust_hdl::prelude::*;
use std::sync::{Arc, Mutex};

/// A cheap deterministic generator.
fn lcg(seed: &mut u64) -> u64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *seed >> 11
}

/// `v` as an `N`-bit two's-complement word.
fn word<const N: usize>(v: i64) -> Bits<N> {
    Bits::<N>::from((v as u64) & ((1u64 << N) - 1))
}

/// An `N`-bit word as a signed value.
fn signed<const N: usize>(b: Bits<N>) -> i64 {
    ((b.to_u64() << (64 - N)) as i64) >> (64 - N)
}

/// Run `bench` on `uut` with a clock; the failures it reports (or a simulator error) fail
/// the test. Returns the count of checks the bench made.
fn run_clocked<U: Block>(
    mut uut: U,
    clock: fn(&mut Box<U>),
    bench: impl Fn(&mut Sim<U>, Box<U>, &mut Vec<String>) -> Result<(Box<U>, usize), SimError>
        + Send
        + std::panic::RefUnwindSafe
        + std::panic::UnwindSafe
        + 'static,
) -> usize
where
    U: Send + 'static,
{
    let found = Arc::new(Mutex::new((Vec::<String>::new(), 0usize)));
    let out = found.clone();
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, move |x: &mut Box<U>| clock(x));
    sim.add_testbench(move |mut sim: Sim<U>| {
        let x = sim.init()?;
        let mut errors = Vec::new();
        let (x, checks) = bench(&mut sim, x, &mut errors)?;
        *out.lock().unwrap() = (errors, checks);
        sim.done(x)
    });
    let run = sim.run(Box::new(uut), 10_000_000);
    let (errors, checks) = found.lock().unwrap().clone();
    assert!(errors.is_empty(), "{} mismatches, the first: {}", errors.len(), errors[0]);
    run.expect("simulation");
    checks
}

#[test]
fn serial_mul_matches_i64_products_in_18_clocks() {
    let checks = run_clocked(
        SerialMul::new(),
        |x| x.clock.next = !x.clock.val(),
        |sim, mut x, errors| {
            let mut seed = 7u64;
            let mut cases: Vec<(i64, i64)> = vec![
                (0, 0),
                (-(1 << 25), -(1 << 17)),
                ((1 << 25) - 1, (1 << 17) - 1),
                (-(1 << 25), (1 << 17) - 1),
                (1, -1),
            ];
            for _ in 0..1500 {
                cases.push((
                    signed::<26>(word::<26>(lcg(&mut seed) as i64)),
                    signed::<18>(word::<18>(lcg(&mut seed) as i64)),
                ));
            }
            x.reset.next = false;
            wait_clock_true!(sim, clock, x);
            for (n, &(a, b)) in cases.iter().enumerate() {
                x.go.next = true;
                x.a.next = word::<26>(a);
                x.b.next = word::<18>(b);
                wait_clock_cycle!(sim, clock, x);
                x.go.next = false;
                x.a.next = word::<26>(lcg(&mut seed) as i64);
                let mut clocks = 0;
                while x.busy.val() {
                    wait_clock_cycle!(sim, clock, x);
                    clocks += 1;
                    if clocks > 64 {
                        break;
                    }
                }
                let got = signed::<44>(x.product.val());
                if got != a * b || clocks != 18 {
                    errors.push(format!("case {n}: {a} * {b} = {}, rtl {got} after {clocks} clocks", a * b));
                }
            }
            // A reset stops a product in progress.
            x.go.next = true;
            wait_clock_cycle!(sim, clock, x);
            x.go.next = false;
            x.reset.next = true;
            wait_clock_cycle!(sim, clock, x);
            if x.busy.val() {
                errors.push("busy after reset".into());
            }
            Ok((x, cases.len() + 1))
        },
    );
    assert_eq!(checks, 1506);
}

#[test]
fn serial_div_matches_div_signed_in_48_clocks() {
    let checks = run_clocked(
        SerialDiv::new(),
        |x| x.clock.next = !x.clock.val(),
        |sim, mut x, errors| {
            let mut seed = 11u64;
            let mut cases: Vec<(u64, u32)> =
                vec![(0, 1), ((1 << 48) - 1, 1), ((1 << 48) - 1, (1 << 24) - 1), (5, 7), (1 << 40, 3)];
            for _ in 0..1000 {
                let n = lcg(&mut seed) & ((1 << 48) - 1);
                let shift = lcg(&mut seed) % 24;
                let d = ((lcg(&mut seed) as u32) >> (8 + shift)).max(1);
                cases.push((n >> (lcg(&mut seed) % 40), d));
            }
            x.reset.next = false;
            wait_clock_true!(sim, clock, x);
            for (k, &(n, d)) in cases.iter().enumerate() {
                x.go.next = true;
                x.n.next = Bits::<48>::from(n);
                x.d.next = Bits::<24>::from(d as u64);
                wait_clock_cycle!(sim, clock, x);
                x.go.next = false;
                x.d.next = 0.into();
                let mut clocks = 0;
                while x.busy.val() && clocks <= 64 {
                    wait_clock_cycle!(sim, clock, x);
                    clocks += 1;
                }
                let want = pf::div_signed(n as i64, d) as u64;
                let got = x.quotient.val().to_u64();
                if got != want || clocks != 48 {
                    errors.push(format!("case {k}: {n} / {d} = {want}, rtl {got} after {clocks} clocks"));
                }
            }
            Ok((x, cases.len()))
        },
    );
    assert_eq!(checks, 1005);
}

#[test]
fn xorshift_step_matches_the_reference_prng() {
    let found = Arc::new(Mutex::new((Vec::<String>::new(), 0usize)));
    let out = found.clone();
    let mut uut = Xorshift32::new();
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_testbench(move |mut sim: Sim<Xorshift32>| {
        let mut x = sim.init()?;
        let (mut errors, mut n) = (Vec::new(), 0);
        for seed in [1u32, 0x8000_0000, 0xffff_ffff, 0x1234_5678] {
            let mut reference = pf::Xorshift32::new(seed);
            let mut state = reference.0;
            for _ in 0..500 {
                x.x.next = Bits::<32>::from(state as u64);
                x = sim.wait(1, x)?;
                let want = reference.next();
                let got = x.y.val().to_u64() as u32;
                if got != want {
                    errors.push(format!("after {state:#x}: {want:#x}, rtl {got:#x}"));
                }
                state = want;
                n += 1;
            }
        }
        *out.lock().unwrap() = (errors, n);
        sim.done(x)
    });
    let run = sim.run(Box::new(uut), 100_000);
    let (errors, n) = found.lock().unwrap().clone();
    assert!(errors.is_empty(), "{} mismatches, the first: {}", errors.len(), errors[0]);
    run.expect("simulation");
    assert_eq!(n, 2000);
}

#[test]
fn cordic_matches_the_reference_at_every_angle_class() {
    let checks = run_clocked(
        Cordic::new(),
        |x| x.clock.next = !x.clock.val(),
        |sim, mut x, errors| {
            let mut seed = 3u64;
            // The quadrant boundaries (the half-turn flip), the extremes, then random angles.
            let mut angles: Vec<i32> = vec![0, 1, -1, 1 << 22, (1 << 22) + 1, -(1 << 22), -(1 << 22) - 1];
            angles.extend([(1 << 23) - 1, -(1 << 23), 1 << 21, -(1 << 21), 3 << 21, -(3 << 21)]);
            for _ in 0..1000 {
                angles.push(signed::<24>(word::<24>(lcg(&mut seed) as i64)) as i32);
            }
            x.load.next = false;
            x.step.next = false;
            x.sin.next = false;
            wait_clock_true!(sim, clock, x);
            for (n, &angle) in angles.iter().enumerate() {
                x.angle.next = word::<24>(angle as i64);
                x.load.next = true;
                wait_clock_cycle!(sim, clock, x);
                x.load.next = false;
                x.angle.next = word::<24>(lcg(&mut seed) as i64);
                x.step.next = true;
                let mut steps = 0;
                loop {
                    steps += 1;
                    let last = x.last.val();
                    wait_clock_cycle!(sim, clock, x);
                    if last || steps > 32 {
                        break;
                    }
                }
                x.step.next = false;
                x.sin.next = false;
                x = sim.wait(1, x)?;
                let cos = signed::<20>(x.value.val()) as i32;
                x.sin.next = true;
                x = sim.wait(1, x)?;
                let sin = signed::<20>(x.value.val()) as i32;
                x.sin.next = false;
                let want = pf::cordic(angle);
                if (cos, sin) != want || steps != CORDIC_STEPS {
                    errors.push(format!("case {n}: cordic({angle}) = {want:?}, rtl ({cos}, {sin}) in {steps} steps"));
                }
            }
            Ok((x, angles.len()))
        },
    );
    assert_eq!(checks, 1013);
}

#[test]
fn pose_program_matches_run_program() {
    let checks = run_clocked(
        PoseProgram::new(),
        |x| x.clock.next = !x.clock.val(),
        |sim, mut x, errors| {
            let mut seed = 5u64;
            for case in 0..40 {
                // Cosines and sines (Q2.16) in 0..6, the scale (Q3.21, 0.5 to 2) in 6, and
                // a first case at the extremes.
                let mut r = [0i64; 32];
                for v in r.iter_mut().take(6) {
                    *v = if case == 0 { 1 << 16 } else { (lcg(&mut seed) % (1 << 17)) as i64 - (1 << 16) };
                }
                r[6] = if case == 0 { (1 << 22) - 1 } else { (1 << 20) + (lcg(&mut seed) % (3 << 20)) as i64 };
                let mut want = r;
                pf::run_program(&mut want);
                x.restart.next = false;
                x.fetch.next = false;
                x.latch.next = false;
                x.exec.next = false;
                x.retire.next = false;
                for (a, &v) in r.iter().enumerate().take(7) {
                    x.load.next = true;
                    x.load_addr.next = Bits::<5>::from(a as u64);
                    x.load_data.next = word::<26>(v);
                    x.restart.next = a == 6;
                    wait_clock_cycle!(sim, clock, x);
                }
                x.load.next = false;
                x.restart.next = false;
                // Drive it as the sequencer's states do; the bench plays the multiplier.
                let mut entries = Vec::new();
                for step in 0..POSE_PROGRAM.len() {
                    x.fetch.next = true;
                    wait_clock_cycle!(sim, clock, x);
                    x.fetch.next = false;
                    x.latch.next = true;
                    wait_clock_cycle!(sim, clock, x);
                    x.latch.next = false;
                    x.exec.next = true;
                    x = sim.wait(1, x)?;
                    let (arith, last) = (x.arith.val(), x.last.val());
                    if last != (step + 1 == POSE_PROGRAM.len()) && !arith {
                        errors.push(format!("case {case}: `last` is {last} at step {step}"));
                    }
                    let product = signed::<26>(x.mul_a.val()) * signed::<18>(x.mul_b.val());
                    wait_clock_cycle!(sim, clock, x);
                    x.exec.next = false;
                    if !arith {
                        x.product.next = word::<44>(product);
                        x.retire.next = true;
                        x = sim.wait(1, x)?;
                        if x.to_pose.val() {
                            entries.push(signed::<18>(x.entry.val()));
                        }
                        wait_clock_cycle!(sim, clock, x);
                        x.retire.next = false;
                    }
                }
                if entries != want[21..30] {
                    errors.push(format!("case {case}: pose entries {:?}, rtl {entries:?}", &want[21..30]));
                }
            }
            Ok((x, 40))
        },
    );
    assert_eq!(checks, 40);
}
