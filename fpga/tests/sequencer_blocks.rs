//! The sequencer's blocks, each alone in rust_hdl's simulator against the
//! [`pficp_fpga::filter::pf`] function it implements: the pipelined multiplier against `i64`
//! products (one at a time and one a clock), the divider against `pf::div_signed`, the PRNG step against
//! `pf::Xorshift32`, the CORDIC against `pf::cordic`, the pose program against
//! `pf::run_program`, the propagation against `pf::propagate`, the estimate and spread
//! against `pf::estimate_param` and `pf::spread`, the translation against
//! `pf::translation`, the weight against `pf::weight` and `pf::temper`'s exponent, the
//! resampling sums against `pf::resample`, the parameter bank against plain arrays. The
//! whole sequencer is checked clock by clock in the sim crate.
#![cfg(feature = "rtl")]

use pficp_fpga::common::format::exp_table;
use pficp_fpga::common::pipe_mul_rtl::PipeMul;
use pficp_fpga::filter::cordic_rtl::Cordic;
use pficp_fpga::filter::estimate_rtl::Estimate;
use pficp_fpga::filter::param_bank_rtl::ParamBank;
use pficp_fpga::filter::pf::{self, CORDIC_STEPS, POSE_PROGRAM};
use pficp_fpga::filter::pose_program_rtl::PoseProgram;
use pficp_fpga::filter::propagate_rtl::Propagate;
use pficp_fpga::filter::resample_rtl::Resample;
use pficp_fpga::filter::serial_div_rtl::SerialDiv;
use pficp_fpga::filter::translation_rtl::Translation;
use pficp_fpga::filter::weight_rtl::Weight;
use pficp_fpga::filter::xorshift_rtl::Xorshift32;
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

/// What a bench is: it drives the block, checks it, pushes what differs to the list and
/// returns how many checks it made.
type Bench<U> = dyn Fn(&mut Sim<U>, Box<U>, &mut Vec<String>) -> Result<(Box<U>, usize), SimError>
    + Send
    + std::panic::RefUnwindSafe
    + std::panic::UnwindSafe;

/// Run `bench` on `uut` (with `clock` toggled every 5 time units, if any); the failures it
/// reports (or a simulator error) fail the test. Returns the count of checks it made.
fn run_bench<U: Block + Send + 'static>(mut uut: U, clock: Option<fn(&mut Box<U>)>, bench: Box<Bench<U>>) -> usize {
    let found = Arc::new(Mutex::new((Vec::<String>::new(), 0usize)));
    let out = found.clone();
    uut.connect_all();
    let mut sim = Simulation::new();
    if let Some(clock) = clock {
        sim.add_clock(5, move |x: &mut Box<U>| clock(x));
    }
    sim.add_testbench(move |mut sim: Sim<U>| {
        let x = sim.init()?;
        let mut errors = Vec::new();
        let (x, checks) = bench(&mut sim, x, &mut errors)?;
        *out.lock().unwrap() = (errors, checks);
        sim.done(x)
    });
    let run = sim.run(Box::new(uut), 100_000_000);
    let (errors, checks) = found.lock().unwrap().clone();
    assert!(errors.is_empty(), "{} mismatches, the first: {}", errors.len(), errors[0]);
    run.expect("simulation");
    checks
}

/// A block with a `clock` input.
trait Clocked {
    /// Toggle the clock.
    fn toggle(x: &mut Box<Self>);
}

macro_rules! clocked {
    ($($block:ty),*) => {
        $(impl Clocked for $block {
            fn toggle(x: &mut Box<Self>) {
                x.clock.next = !x.clock.val();
            }
        })*
    };
}

clocked!(PipeMul, SerialDiv, Cordic, PoseProgram, Weight, Resample, ParamBank);

/// [`run_bench`] on a clocked block.
fn run_clocked<U: Block + Clocked + Send + 'static>(
    uut: U,
    bench: impl Fn(&mut Sim<U>, Box<U>, &mut Vec<String>) -> Result<(Box<U>, usize), SimError>
        + Send
        + std::panic::RefUnwindSafe
        + std::panic::UnwindSafe
        + 'static,
) -> usize {
    run_bench(uut, Some(U::toggle), Box::new(bench))
}

/// [`run_bench`] on a combinational block (no clock; `sim.wait(1, x)` settles it).
fn run_comb<U: Block + Send + 'static>(
    uut: U,
    bench: impl Fn(&mut Sim<U>, Box<U>, &mut Vec<String>) -> Result<(Box<U>, usize), SimError>
        + Send
        + std::panic::RefUnwindSafe
        + std::panic::UnwindSafe
        + 'static,
) -> usize {
    run_bench(uut, None, Box::new(bench))
}

#[test]
fn pipe_mul_matches_i64_products_in_2_clocks_one_a_clock() {
    let checks = run_clocked(PipeMul::new(), |sim, mut x, errors| {
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
            if got != a * b || clocks != 2 || !x.valid.val() {
                errors.push(format!("case {n}: {a} * {b} = {}, rtl {got} after {clocks} clocks", a * b));
            }
            // `valid` is one clock long.
            wait_clock_cycle!(sim, clock, x);
            if x.valid.val() || signed::<44>(x.product.val()) != a * b {
                errors.push(format!("case {n}: valid twice or the product not held"));
            }
        }
        // One pair a clock: every product comes out, in order, a `valid` clock each, two clocks
        // after its pair is taken.
        let mut out = Vec::new();
        for k in 0..cases.len() + 3 {
            x.go.next = k < cases.len();
            if let Some(&(a, b)) = cases.get(k) {
                x.a.next = word::<26>(a);
                x.b.next = word::<18>(b);
            }
            wait_clock_cycle!(sim, clock, x);
            if x.valid.val() {
                out.push((k, signed::<44>(x.product.val())));
            }
        }
        x.go.next = false;
        let want: Vec<(usize, i64)> = cases.iter().enumerate().map(|(k, &(a, b))| (k + 2, a * b)).collect();
        if out != want {
            let first = out.iter().zip(&want).position(|(o, w)| o != w);
            errors.push(format!(
                "streamed: {} products out of {}, first difference at {first:?}",
                out.len(),
                want.len()
            ));
        }
        // A reset stops a product in progress.
        x.go.next = true;
        wait_clock_cycle!(sim, clock, x);
        x.go.next = false;
        x.reset.next = true;
        wait_clock_cycle!(sim, clock, x);
        wait_clock_cycle!(sim, clock, x);
        x.reset.next = false;
        if x.busy.val() || x.valid.val() {
            errors.push("busy or valid after reset".into());
        }
        Ok((x, cases.len() + 1))
    });
    assert_eq!(checks, 1506);
}

#[test]
fn serial_div_matches_div_signed_in_24_clocks_for_quotients_below_2_24() {
    let checks = run_clocked(SerialDiv::new(), |sim, mut x, errors| {
        let mut seed = 11u64;
        // The domain: `n < d 2^24` (the filter's `|sum w x| <= 2^23 W`), its edges included.
        let mut cases: Vec<(u64, u32)> = vec![
            (0, 1),
            ((1 << 24) - 1, 1),
            ((1 << 48) - (1 << 24) - 1, (1 << 24) - 1),
            (5, 7),
            (1 << 40, 1 << 17),
            ((1 << 23) * 65_535 * 256, 65_535 * 256),
        ];
        for _ in 0..1000 {
            let shift = lcg(&mut seed) % 24;
            let d = ((lcg(&mut seed) as u32) >> (8 + shift)).max(1);
            let n = (lcg(&mut seed) & ((1 << 48) - 1)) % ((d as u64) << 24);
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
            let want = pf::div_signed(n as i64, d) as u64 & ((1 << 26) - 1);
            let got = x.quotient.val().to_u64();
            if got != want || clocks != 24 {
                errors.push(format!("case {k}: {n} / {d} = {want}, rtl {got} after {clocks} clocks"));
            }
        }
        Ok((x, cases.len()))
    });
    assert_eq!(checks, 1006);
}

#[test]
fn xorshift_step_matches_the_reference_prng() {
    let checks = run_comb(Xorshift32::new(), |sim, mut x, errors| {
        let mut n = 0;
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
        Ok((x, n))
    });
    assert_eq!(checks, 2000);
}

#[test]
fn cordic_matches_the_reference_at_every_angle_class() {
    let checks = run_clocked(Cordic::new(), |sim, mut x, errors| {
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
            let cos = signed::<26>(x.value.val()) as i32;
            x.sin.next = true;
            x = sim.wait(1, x)?;
            let sin = signed::<26>(x.value.val()) as i32;
            x.sin.next = false;
            let want = pf::cordic(angle);
            if (cos, sin) != want || steps != CORDIC_STEPS {
                errors.push(format!("case {n}: cordic({angle}) = {want:?}, rtl ({cos}, {sin}) in {steps} steps"));
            }
        }
        Ok((x, angles.len()))
    });
    assert_eq!(checks, 1013);
}

#[test]
fn pose_program_matches_run_program() {
    let checks = run_clocked(PoseProgram::new(), |sim, mut x, errors| {
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
    });
    assert_eq!(checks, 40);
}

#[test]
fn propagate_matches_pf_propagate() {
    let checks = run_comb(Propagate::new(), |sim, mut x, errors| {
        let mut seed = 13u64;
        let mut n = 0;
        for case in 0..3000 {
            let xv = signed::<24>(word::<24>(lcg(&mut seed) as i64)) as i32;
            let centre = signed::<24>(word::<24>(lcg(&mut seed) as i64)) as i32;
            // Spreads from tiny to the 22-bit maximum, draws over the whole 16-bit range.
            let sigma = ((lcg(&mut seed) as u32) & ((1 << 22) - 1)) >> (lcg(&mut seed) % 22);
            let u = signed::<16>(word::<16>(lcg(&mut seed) as i64));
            let (first, scale) = (case % 3 == 0, case % 7 == 3);
            x.x.next = word::<24>(xv as i64);
            x.centre.next = word::<24>(centre as i64);
            x.reference.next = word::<24>(centre as i64);
            x.sigma.next = Bits::<22>::from(sigma as u64);
            x.product.next = word::<27>((sigma as i64 * u) >> 14);
            x.first.next = first;
            x.scale.next = scale;
            x = sim.wait(1, x)?;
            x.off.next = x.step.val();
            x = sim.wait(1, x)?;
            x.off.next = x.clamped.val();
            x = sim.wait(1, x)?;
            let got = signed::<24>(x.value.val()) as i32;
            let want = pf::propagate(xv, centre, sigma, u, first, scale);
            let diff = pf::wrap24(xv as i64 - centre as i64) as i64;
            if got != want || signed::<26>(x.diff.val()) != diff || signed::<26>(x.abs_diff.val()) != diff.abs() {
                errors.push(format!(
                    "case {case}: propagate({xv}, {centre}, {sigma}, {u}, {first}, {scale}) = {want}, rtl {got}"
                ));
            }
            n += 1;
        }
        Ok((x, n))
    });
    assert_eq!(checks, 3000);
}

#[test]
fn estimate_matches_pf_estimate_and_spread() {
    let checks = run_comb(Estimate::new(), |sim, mut x, errors| {
        let mut seed = 17u64;
        let mut n = 0;
        for case in 0..3000 {
            // Sums of up to 256 particles' 24-bit offsets times 16-bit weights.
            let w_sum = ((lcg(&mut seed) % (1 << 24)) as u32).max(1);
            let s = (signed::<48>(word::<48>(lcg(&mut seed) as i64)) >> 1) / (1 + (lcg(&mut seed) % (1 << 20)) as i64);
            let s = s.clamp(-((w_sum as i64) << 23), (w_sum as i64) << 23);
            let centre = signed::<24>(word::<24>(lcg(&mut seed) as i64)) as i32;
            let floor = (lcg(&mut seed) as u32) & ((1 << 20) - 1);
            let cap = floor.max((lcg(&mut seed) as u32) & ((1 << 22) - 1));
            let scale = case % 5 == 2;
            x.acc.next = word::<48>(s);
            x.centre.next = word::<24>(centre as i64);
            x.floor.next = Bits::<22>::from(floor as u64);
            x.cap.next = Bits::<22>::from(cap as u64);
            x.scale.next = scale;
            x = sim.wait(1, x)?;
            let magnitude = x.magnitude.val().to_u64();
            x.quotient.next = word::<26>((magnitude / w_sum as u64) as i64);
            x = sim.wait(1, x)?;
            let (est, spread) = (signed::<24>(x.value.val()) as i32, x.spread.val().to_u64() as u32);
            let want_est = pf::estimate_param(centre, s, w_sum, scale);
            let want_spread = pf::spread(s.unsigned_abs(), w_sum, floor, cap);
            if magnitude != s.unsigned_abs() || est != want_est || spread != want_spread {
                errors.push(format!(
                    "case {case}: S {s}, W {w_sum}: estimate {want_est}, spread {want_spread}; rtl {est}, {spread} (|S| {magnitude})"
                ));
            }
            n += 1;
        }
        Ok((x, n))
    });
    assert_eq!(checks, 3000);
}

#[test]
fn translation_matches_pf_translation() {
    let checks = run_comb(Translation::new(), |sim, mut x, errors| {
        let mut seed = 19u64;
        let mut values: Vec<i32> = vec![
            0,
            -1,
            31,
            32,
            -32,
            -33,
            (1 << 23) - 1,
            -(1 << 23),
            131071 << 6,
            (131071 << 6) + 31,
            (131071 << 6) + 32,
        ];
        values.extend((0..3000).map(|_| signed::<24>(word::<24>(lcg(&mut seed) as i64)) as i32));
        for &v in &values {
            x.x.next = word::<24>(v as i64);
            x = sim.wait(1, x)?;
            let got = signed::<18>(x.t.val()) as i32;
            if got != pf::translation(v) {
                errors.push(format!("translation({v}) = {}, rtl {got}", pf::translation(v)));
            }
        }
        Ok((x, values.len()))
    });
    assert_eq!(checks, 3011);
}

#[test]
fn weight_matches_pf_weight_at_the_temper_exponent() {
    let checks = run_clocked(Weight::new(), |sim, mut x, errors| {
        let table = exp_table();
        let mut seed = 23u64;
        x.temper.next = false;
        x.latch.next = false;
        wait_clock_true!(sim, clock, x);
        let mut n = 0;
        for case in 0..1500 {
            let (p, tq) = ((lcg(&mut seed) % 49) as u32, (lcg(&mut seed) % 64) as u32);
            // The exponent rule of pf::temper, given the bit length p it found.
            let e = tq.max(p.saturating_sub(2)).max(pf::MIN_TEMPER_EXP);
            x.p.next = Bits::<6>::from(p as u64);
            x.tq.next = Bits::<6>::from(tq as u64);
            x.temper.next = true;
            wait_clock_cycle!(sim, clock, x);
            x.temper.next = false;
            for _ in 0..4 {
                let excess = (lcg(&mut seed) & ((1 << 48) - 1)) >> (lcg(&mut seed) % 48);
                x.excess.next = Bits::<48>::from(excess);
                x.latch.next = true;
                wait_clock_cycle!(sim, clock, x);
                x.latch.next = false;
                x.excess.next = 0.into();
                x = sim.wait(1, x)?;
                let got = x.value.val().to_u64() as u16;
                let want = pf::weight(excess, e, &table);
                if got != want {
                    errors.push(format!("case {case}: weight({excess}, e {e}) = {want}, rtl {got}"));
                }
                n += 1;
            }
        }
        Ok((x, n))
    });
    assert_eq!(checks, 6000);
}

#[test]
fn resample_sums_pick_what_pf_resample_picks() {
    let checks = run_clocked(Resample::new(), |sim, mut x, errors| {
        let mut seed = 29u64;
        let pulse = |x: &mut Box<Resample>, which: usize, on: bool| match which {
            0 => x.clear.next = on,
            1 => x.set_pointer.next = on,
            2 => x.add_weight.next = on,
            _ => x.advance.next = on,
        };
        for which in 0..4 {
            pulse(&mut x, which, false);
        }
        wait_clock_true!(sim, clock, x);
        for case in 0..60 {
            let n = 1 + (lcg(&mut seed) % 256) as usize;
            // Some weights zero (particles that cannot be picked), some all equal.
            let weights: Vec<u16> = (0..n)
                .map(|i| {
                    if case % 4 == 0 {
                        1000
                    } else if lcg(&mut seed).is_multiple_of(3) {
                        0
                    } else {
                        (lcg(&mut seed) as u16) | (i == 0) as u16
                    }
                })
                .collect();
            let w_sum: u32 = weights.iter().map(|&w| w as u32).sum::<u32>().max(1);
            let u0 = (lcg(&mut seed) % (1 << 16)) as u32;
            let want = pf::resample(&weights, w_sum, u0);
            x.w_sum.next = Bits::<24>::from(w_sum as u64);
            // As the sequencer's states drive it, the bench playing the multiplier.
            x.product.next = Bits::<44>::from(u0 as u64 * w_sum as u64);
            x.clear.next = true;
            x.set_pointer.next = true;
            wait_clock_cycle!(sim, clock, x);
            x.clear.next = false;
            x.set_pointer.next = false;
            let add = |x: &mut Box<Resample>, w: u16| {
                x.product.next = Bits::<44>::from(n as u64 * w as u64);
                x.add_weight.next = true;
            };
            add(&mut x, weights[0]);
            wait_clock_cycle!(sim, clock, x);
            x.add_weight.next = false;
            let (mut i, mut picks) = (0usize, Vec::new());
            while picks.len() < n {
                x = sim.wait(1, x)?;
                if x.beyond.val() && i + 1 < n {
                    i += 1;
                    add(&mut x, weights[i]);
                } else {
                    picks.push(i);
                    x.advance.next = true;
                }
                wait_clock_cycle!(sim, clock, x);
                x.add_weight.next = false;
                x.advance.next = false;
            }
            if picks != want {
                errors.push(format!("case {case} ({n} particles): picks differ from pf::resample"));
            }
        }
        Ok((x, 60))
    });
    assert_eq!(checks, 60);
}

#[test]
fn param_bank_moves_vectors_as_the_filter_does() {
    let checks = run_clocked(ParamBank::new(), |sim, mut x, errors| {
        let mut seed = 31u64;
        // The reference: plain arrays [centre, cap, floor, sigma, est, best, cur].
        let mut r = [[0i64; 7]; 7];
        let (centre, cap, floor, sigma, est, best, cur) = (0, 1, 2, 3, 4, 5, 6);
        let widths = [24, 22, 22, 22, 24, 24, 24];
        wait_clock_true!(sim, clock, x);
        let mut n = 0;
        for step in 0..4000 {
            let op = lcg(&mut seed) % 12;
            let pd = (lcg(&mut seed) % 7) as usize;
            let data = (lcg(&mut seed) & 0xff_ffff) as i64;
            let sigma_in = (lcg(&mut seed) & 0x3f_ffff) as i64;
            let cfg_addr = (lcg(&mut seed) % 25) as usize;
            let cfg_data = lcg(&mut seed) & ((1 << 48) - 1);
            x.cfg_we.next = op == 0;
            x.cfg_addr.next = Bits::<5>::from(cfg_addr as u64);
            x.cfg_data.next = Bits::<24>::from(cfg_data & 0xff_ffff);
            x.pd.next = Bits::<3>::from(pd as u64);
            x.data.next = Bits::<24>::from(data as u64);
            x.sigma_in.next = Bits::<22>::from(sigma_in as u64);
            x.axis.next = Bits::<2>::from(lcg(&mut seed) % 3);
            x.init.next = op == 1;
            x.cur_put.next = op == 2;
            x.best_put.next = op == 3;
            x.est_put.next = op == 4;
            x.sigma_put.next = op == 5;
            x.cur_from_est.next = op == 6;
            x.best_from_est.next = op == 7;
            x.best_from_cur.next = op == 8;
            x.cur_from_best.next = op == 9;
            x.centre_from_best.next = op == 10;
            x = sim.wait(1, x)?;
            let axis = x.axis.val().to_u64() as usize;
            let shown = [
                (x.sel_centre.val().to_u64() as i64, r[centre][pd]),
                (x.sel_cap.val().to_u64() as i64, r[cap][pd]),
                (x.sel_floor.val().to_u64() as i64, r[floor][pd]),
                (x.sel_sigma.val().to_u64() as i64, r[sigma][pd]),
                (x.sel_est.val().to_u64() as i64, r[est][pd]),
                (x.angle.val().to_u64() as i64, r[cur][4 + axis]),
                (x.translation.val().to_u64() as i64, r[cur][axis]),
                (x.scale.val().to_u64() as i64, r[cur][3]),
            ];
            if let Some(k) = shown.iter().position(|(got, want)| got != want) {
                errors.push(format!("step {step}: output {k} is {}, the arrays say {}", shown[k].0, shown[k].1));
            }
            let params = x.params.val();
            for (q, &b) in r[best].iter().enumerate() {
                if params.get_bits::<24>(24 * q).to_u64() as i64 != b {
                    errors.push(format!("step {step}: params word {q}"));
                }
            }
            wait_clock_cycle!(sim, clock, x);
            let before = r;
            match op {
                0 if cfg_addr < 21 => {
                    let (v, q) = (cfg_addr / 7, cfg_addr % 7);
                    r[[centre, cap, floor][v]][q] = (cfg_data & ((1 << widths[[centre, cap, floor][v]]) - 1)) as i64;
                }
                1 => {
                    for q in 0..7 {
                        r[cap][q] = before[cap][q].max(before[floor][q]);
                        r[sigma][q] = r[cap][q];
                        r[cur][q] = before[centre][q];
                    }
                }
                2 => r[cur][pd] = data,
                3 => r[best][pd] = data,
                4 => r[est][pd] = data,
                5 => r[sigma][pd] = sigma_in,
                6 => r[cur] = before[est],
                7 => r[best] = before[est],
                8 => r[best] = before[cur],
                9 => r[cur] = before[best],
                10 => r[centre] = before[best],
                _ => {}
            }
            n += 1;
        }
        Ok((x, n))
    });
    assert_eq!(checks, 4000);
}
