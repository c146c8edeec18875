//! The engine's scan feeder alone in rust_hdl's simulator: for random ranges of a scan
//! store (the bench plays the store's one-clock read and the pipeline's `ready`), the
//! points taken are exactly `store[from..to]` in order, the last one flagged, at one a
//! clock while the pipeline takes them, and `streaming` falls when the range is done.
#![cfg(feature = "rtl")]

use pficp_fpga::board::scan_feeder_rtl::ScanFeeder;
use rust_hdl::prelude::*;
use std::sync::{Arc, Mutex};

fn lcg(seed: &mut u64) -> u64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *seed >> 11
}

#[test]
fn feeder_streams_each_range_in_order_at_one_point_a_clock() {
    let store: Vec<u64> = {
        let mut seed = 41u64;
        (0..4096).map(|_| lcg(&mut seed) & ((1 << 48) - 1)).collect()
    };
    let found = Arc::new(Mutex::new((Vec::<String>::new(), 0usize, 0usize)));
    let out = found.clone();
    let mut uut = ScanFeeder::new();
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<ScanFeeder>| x.clock.next = !x.clock.val());
    sim.add_testbench(move |mut sim: Sim<ScanFeeder>| {
        let mut x = sim.init()?;
        let (mut errors, mut points, mut full_speed) = (Vec::new(), 0usize, 0usize);
        let mut seed = 43u64;
        x.launch.next = false;
        x.ready.next = false;
        wait_clock_true!(sim, clock, x);
        for case in 0..120 {
            let from = (lcg(&mut seed) % 4096) as usize;
            let len = match case % 4 {
                0 => 1,
                1 => 2,
                _ => 1 + (lcg(&mut seed) % 300) as usize,
            };
            let to = (from + len).min(4096);
            // Every 3rd range at full speed, the others with the pipeline stalling at random.
            let stall = case % 3 != 0;
            x.from_index.next = Bits::<13>::from(from as u64);
            x.to_index.next = Bits::<13>::from(to as u64);
            x.launch.next = true;
            let mut addr = x.read_address.val().to_u64() as usize;
            wait_clock_cycle!(sim, clock, x);
            x.launch.next = false;
            let (mut taken, mut clocks, mut issued) = (Vec::new(), 0usize, 0usize);
            // Every 4th stalled range with the store's reads held at random too.
            let hold = stall && case % 4 == 1;
            while x.streaming.val() && clocks < 10 * len + 20 {
                x.read_data.next = Bits::<48>::from(store[addr]);
                x.ready.next = !stall || !lcg(&mut seed).is_multiple_of(3);
                x.hold.next = hold && lcg(&mut seed).is_multiple_of(2);
                x = sim.wait(1, x)?;
                issued += usize::from(x.issued.val());
                if x.hold.val() && x.issued.val() {
                    errors.push(format!("case {case}: a read while held"));
                }
                if x.valid.val() && x.ready.val() {
                    taken.push((x.data.val().to_u64(), x.last.val()));
                }
                addr = x.read_address.val().to_u64() as usize;
                wait_clock_cycle!(sim, clock, x);
                clocks += 1;
            }
            x.ready.next = false;
            x.hold.next = false;
            if issued != to - from {
                errors.push(format!("case {case}: range {from}..{to}: {issued} reads marked issued"));
            }
            let want: Vec<(u64, bool)> = (from..to).map(|i| (store[i], i + 1 == to)).collect();
            if taken != want {
                errors.push(format!(
                    "case {case}: range {from}..{to}: {} points taken, {} wanted",
                    taken.len(),
                    want.len()
                ));
            }
            if !stall && clocks > len + 3 {
                errors.push(format!("case {case}: {len} points took {clocks} clocks at full speed"));
            }
            full_speed += usize::from(!stall);
            points += taken.len();
        }
        *out.lock().unwrap() = (errors, points, full_speed);
        sim.done(x)
    });
    let run = sim.run(Box::new(uut), 100_000_000);
    let (errors, points, full_speed) = found.lock().unwrap().clone();
    assert!(errors.is_empty(), "{} mismatches, the first: {}", errors.len(), errors[0]);
    run.expect("simulation");
    assert!(points > 5_000 && full_speed == 40, "{points} points, {full_speed} full-speed ranges");
}
