//! The UART alone in rust_hdl's simulator, at bit periods that are not whole clocks
//! (50 MHz / 3 Mbaud = 16 2/3 clocks, 50 MHz / 921,600 baud = 54 25/288, 4 1/2 clocks),
//! and at a whole 4 clocks (the fast co-simulation board):
//! - `UartTx`, long runs of back-to-back bytes: every edge on the line lies at
//!   `ceil(k clocks / bits)` clocks after its byte's start edge (within one clock of the
//!   exact `k clocks / bits`, the error not accumulating over the byte), the stop bit lasts
//!   its whole period, and each byte reads back at the exact bit middles;
//! - `UartRx`, long runs of bytes from a host at the exact nominal timing on a continuous
//!   timeline (so each start edge falls at another phase of the clock), back to back and
//!   with random gaps, and from hosts 3 % fast and 3 % slow (16 2/3 clocks a bit): every
//!   byte arrives, in order, and nothing else.
//!
//! The host side here is independent of the RTL: it places edges at rational times and
//! samples at rational times. A UART that rounds 16 2/3 to 17 clocks fails both tests (the
//! transmitter's 9th edge is 3 clocks late; the receiver samples a fast host's stop bit
//! after it ended).
#![cfg(feature = "rtl")]

use pficp_fpga::board::uart_rtl::{UartRx, UartTx};
use pficp_fpga::board::BitPeriod;
use rust_hdl::prelude::*;
use std::sync::{Arc, Mutex};

fn lcg(seed: &mut u64) -> u64 {
    *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *seed >> 33
}

fn bytes(n: usize, seed: u64) -> Vec<u8> {
    let mut s = seed;
    // 0x00, 0xff and 0x55 / 0xaa first: no edges, and an edge at every boundary.
    [0x00, 0xff, 0x55, 0xaa].into_iter().chain((4..n).map(|_| lcg(&mut s) as u8)).take(n).collect()
}

/// The transmitter's line, one value a clock, sending `data` back to back (a new byte as
/// soon as it is not busy).
fn transmit(period: BitPeriod, data: &[u8]) -> Vec<bool> {
    let out = Arc::new(Mutex::new(Vec::new()));
    let seen = out.clone();
    let data = data.to_vec();
    let mut uut = UartTx::new(period);
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<UartTx>| x.clock.next = !x.clock.val());
    let clocks = period.boundary(10 * data.len() as u64) + 4 * data.len() as u64 + 100;
    sim.add_testbench(move |mut sim: Sim<UartTx>| {
        let mut x = sim.init()?;
        let mut line = Vec::new();
        let mut next = data.iter();
        x.reset.next = false;
        x.start.next = false;
        wait_clock_true!(sim, clock, x);
        for _ in 0..clocks {
            x.start.next = false;
            if !x.busy.val() {
                if let Some(&b) = next.next() {
                    x.start.next = true;
                    x.data.next = Bits::<8>::from(b as u64);
                }
            }
            wait_clock_cycle!(sim, clock, x);
            line.push(x.tx.val());
        }
        *seen.lock().unwrap() = line;
        sim.done(x)
    });
    sim.run(Box::new(uut), 20 * (clocks + 100)).expect("simulation");
    let line = out.lock().unwrap().clone();
    line
}

/// Check a transmitted line against the exact timing; the bytes read, or the first problem.
fn check_line(period: BitPeriod, line: &[bool]) -> Result<Vec<u8>, String> {
    let (n, d) = (period.clocks as u64, period.bits as u64);
    let mut got = Vec::new();
    let mut c = 0usize;
    while c < line.len() {
        if line[c] {
            c += 1;
            continue;
        }
        // A start edge at clock s: the line at s + t belongs to bit floor(t d / n) exactly
        // when every edge lies at ceil(k n / d).
        let s = c;
        let end = s + period.boundary(10) as usize;
        if end > line.len() {
            return Err(format!("the byte starting at clock {s} is cut off"));
        }
        let mut byte = 0u8;
        for t in 0..(end - s) {
            let bit = (t as u64 * d / n) as usize;
            let v = line[s + t];
            // The exact middle of each bit must read its value.
            let middle = ((2 * bit as u64 + 1) * n / (2 * d)) as usize == t;
            let want = match bit {
                0 => Some(false),
                9 => Some(true),
                _ => None,
            };
            if t > 0 && v != line[s + t - 1] && (t as u64) != period.boundary(bit as u64) {
                return Err(format!(
                    "an edge {t} clocks after the start edge at clock {s}: bit {bit}'s boundary is {} ({}/{} exactly)",
                    period.boundary(bit as u64),
                    bit as u64 * n,
                    d
                ));
            }
            if let Some(w) = want {
                if v != w {
                    return Err(format!(
                        "{} bit {t} clocks after the start edge at {s} is {v}",
                        ["start", "stop"][bit / 9]
                    ));
                }
            }
            if middle && (1..=8).contains(&bit) && v {
                byte |= 1 << (bit - 1);
            }
        }
        got.push(byte);
        c = end;
    }
    Ok(got)
}

/// The host's line for `data` at a bit period `host` (clocks / bits), one value a clock:
/// byte `i` starts at the rational time `start[i]` (in 1/`host.bits` clocks), the line at
/// clock `c` is the byte's bit `floor((c - start) / period)`.
fn host_line(host: BitPeriod, data: &[u8], gaps: bool, seed: u64) -> Vec<bool> {
    let (n, d) = (host.clocks as u64, host.bits as u64);
    let mut s = seed;
    // Start times in units of 1/d clock; the first a third of a clock after clock 5.
    let mut starts = Vec::new();
    let mut t = 5 * d + d / 3;
    for _ in data {
        if gaps && lcg(&mut s).is_multiple_of(3) {
            // An idle gap of up to 3 bits, any fraction of a clock.
            t += lcg(&mut s) % (3 * n);
        }
        starts.push(t);
        t += 10 * n;
    }
    let clocks = (t / d + 50) as usize;
    let mut line = vec![true; clocks];
    for (i, &b) in data.iter().enumerate() {
        let frame = (b as u16) << 1 | 1 << 9;
        let first = starts[i].div_ceil(d);
        for c in first..(starts[i] + 10 * n).div_ceil(d) {
            let bit = (c * d - starts[i]) / n;
            line[c as usize] = frame >> bit & 1 != 0;
        }
    }
    line
}

/// The receiver's bytes for `line`, one value a clock.
fn receive(period: BitPeriod, line: Vec<bool>) -> (Vec<u8>, usize) {
    let out = Arc::new(Mutex::new((Vec::new(), 0usize)));
    let seen = out.clone();
    let clocks = line.len();
    let mut uut = UartRx::new(period);
    uut.connect_all();
    let mut sim = Simulation::new();
    sim.add_clock(5, |x: &mut Box<UartRx>| x.clock.next = !x.clock.val());
    sim.add_testbench(move |mut sim: Sim<UartRx>| {
        let mut x = sim.init()?;
        let (mut got, mut active) = (Vec::new(), 0usize);
        x.reset.next = false;
        x.rx.next = true;
        wait_clock_true!(sim, clock, x);
        for &v in &line {
            x.rx.next = v;
            wait_clock_cycle!(sim, clock, x);
            if x.valid.val() {
                got.push(x.data.val().to_u64() as u8);
            }
            active += usize::from(x.active.val());
        }
        *seen.lock().unwrap() = (got, active);
        sim.done(x)
    });
    sim.run(Box::new(uut), 20 * (clocks as u64 + 100)).expect("simulation");
    let r = out.lock().unwrap().clone();
    r
}

const PERIODS: [(u32, u32); 4] =
    [(50_000_000, 3_000_000), (50_000_000, 921_600), (45_000_000, 10_000_000), (100_000_000, 25_000_000)];

#[test]
fn the_transmitter_places_every_edge_within_a_clock_of_the_exact_time() {
    for (k, (hz, baud)) in PERIODS.into_iter().enumerate() {
        let period = BitPeriod::new(hz, baud);
        let n = if period.clocks > 1000 { 60 } else { 300 };
        let data = bytes(n, 7 + k as u64);
        let line = transmit(period, &data);
        let got =
            check_line(period, &line).unwrap_or_else(|e| panic!("{hz} Hz, {baud} baud ({period} clocks a bit): {e}"));
        assert_eq!(got, data, "{hz} Hz, {baud} baud: the bytes read back at the exact bit middles");
        // Back to back: at most a clock more than 10 exact bits a byte (the stop bit's end
        // rounds up, the next start waits a clock for `busy`), so nothing accumulates.
        let last_end = line.iter().rposition(|&v| !v).unwrap() as u64;
        let exact = 10 * n as u64 * period.clocks as u64 / period.bits as u64;
        assert!(
            last_end < exact + 2 * n as u64,
            "{hz} Hz, {baud} baud: {n} bytes took {last_end} clocks, {exact} exactly"
        );
        eprintln!("{hz} Hz, {baud} baud ({period} clocks a bit): {n} bytes, every edge on time");
    }
}

#[test]
fn the_receiver_takes_long_runs_at_the_exact_timing() {
    for (k, (hz, baud)) in PERIODS.into_iter().enumerate() {
        let period = BitPeriod::new(hz, baud);
        let n = if period.clocks > 1000 { 60 } else { 300 };
        for gaps in [false, true] {
            let data = bytes(n, 11 + k as u64);
            let (got, active) = receive(period, host_line(period, &data, gaps, 5 + k as u64));
            assert_eq!(got, data, "{hz} Hz, {baud} baud ({period} clocks a bit), gaps {gaps}");
            assert!(active > 0);
        }
    }
}

#[test]
fn the_receiver_tolerates_hosts_three_percent_off_at_16_2_3_clocks() {
    let period = BitPeriod::new(50_000_000, 3_000_000);
    for host_baud in [3_090_000, 2_910_000] {
        let host = BitPeriod::new(50_000_000, host_baud);
        for gaps in [false, true] {
            let data = bytes(300, host_baud as u64);
            let (got, _) = receive(period, host_line(host, &data, gaps, 3));
            assert_eq!(got, data, "a host at {host_baud} baud ({host} clocks a bit), gaps {gaps}");
        }
    }
}

#[test]
fn bit_periods_reduce_and_place_boundaries() {
    assert_eq!(BitPeriod::new(50_000_000, 3_000_000), BitPeriod { clocks: 50, bits: 3 });
    assert_eq!(BitPeriod::new(50_000_000, 921_600), BitPeriod { clocks: 15_625, bits: 288 });
    assert_eq!(BitPeriod::new(100_000_000, 25_000_000), BitPeriod { clocks: 4, bits: 1 });
    let p = BitPeriod::new(50_000_000, 3_000_000);
    assert_eq!((0..=10).map(|k| p.boundary(k)).collect::<Vec<_>>(), [0, 17, 34, 50, 67, 84, 100, 117, 134, 150, 167]);
    assert_eq!(p.to_string(), "16 2/3");
    assert_eq!(BitPeriod::new(100_000_000, 25_000_000).to_string(), "4");
}
