//! The polish pass's queue alone in rust_hdl's simulator: random writes (never beyond its
//! entries, as the engine's credits keep them) and random takes; the heads taken are the
//! points written, in order, none lost or doubled; a reset drops what is queued.
#![cfg(feature = "rtl")]

use pficp_fpga::board::pass_queue_rtl::{PassQueue, PASS_QUEUE};
use rust_hdl::prelude::*;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

fn lcg(seed: &mut u64) -> u64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *seed >> 11
}

fn to_bits(w: u128) -> Bits<109> {
    (Bits::<109>::from((w >> 64) as u64) << 64) | Bits::<109>::from(w as u64)
}

fn from_bits(b: Bits<109>) -> u128 {
    (b.get_bits::<45>(64).to_u64() as u128) << 64 | b.get_bits::<64>(0).to_u64() as u128
}

#[test]
fn the_queue_gives_back_what_was_written_in_order() {
    let found = Arc::new(Mutex::new((Vec::<String>::new(), 0usize)));
    let out = found.clone();
    let mut uut = PassQueue::default();
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<PassQueue>| x.clock.next = !x.clock.val());
    sim.add_testbench(move |mut sim: Sim<PassQueue>| {
        let mut x = sim.init()?;
        let (mut errors, mut taken) = (Vec::new(), 0usize);
        let mut seed = 7u64;
        let mut model: VecDeque<u128> = VecDeque::new();
        wait_clock_true!(sim, clock, x);
        for clock in 0..20_000 {
            // Phases: writes faster than takes, then slower; a reset now and then.
            let write_odds = if (clock / 500) % 2 == 0 { 2 } else { 5 };
            let reset = clock % 4_999 == 4_000;
            let write = !reset && model.len() < PASS_QUEUE && lcg(&mut seed).is_multiple_of(write_odds);
            let take = !reset && x.valid.val() && lcg(&mut seed).is_multiple_of(3);
            let word = (lcg(&mut seed) as u128) << 64 | lcg(&mut seed) as u128;
            let word = word & ((1u128 << 109) - 1);
            x.reset.next = reset;
            x.write.next = write;
            x.take.next = take;
            x.data_in.next = to_bits(word);
            if take {
                let got = from_bits(x.data_out.val());
                let want = model.pop_front();
                if Some(got) != want && errors.len() < 5 {
                    errors.push(format!("clock {clock}: took {got:x}, wrote {want:x?}"));
                }
                taken += 1;
            }
            if write {
                model.push_back(word);
            }
            if reset {
                model.clear();
            }
            wait_clock_cycle!(sim, clock, x);
            if !x.valid.val() && !model.is_empty() {
                // The head comes within three clocks of the last take or write.
                let mut waited = 0;
                x.write.next = false;
                x.take.next = false;
                x.reset.next = false;
                while !x.valid.val() && waited < 4 {
                    wait_clock_cycle!(sim, clock, x);
                    waited += 1;
                }
                if !x.valid.val() && errors.len() < 5 {
                    errors.push(format!("clock {clock}: {} queued, no head", model.len()));
                }
            }
        }
        *out.lock().unwrap() = (errors, taken);
        sim.done(x)
    });
    sim.run(Box::new(uut), 10_000_000).expect("simulation");
    let (errors, taken) = &*found.lock().unwrap();
    assert!(errors.is_empty(), "{errors:?}");
    assert!(*taken > 2_000, "only {taken} takes");
}
