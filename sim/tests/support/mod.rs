//! What the co-simulation tests share: the seeded generator, the VCD paths and the check of
//! a mismatch's VCD.
#![allow(dead_code)]

use pficp_fpga::common::splitmix::SplitMix64;
use pficp_sim::Mismatch;
use std::path::PathBuf;

/// The tests' generator (SplitMix64).
pub struct Rng(pub SplitMix64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(SplitMix64(seed))
    }
    pub fn next(&mut self) -> u64 {
        self.0.next_u64()
    }
    pub fn below(&mut self, n: u64) -> u64 {
        self.0.below(n)
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }
    pub fn uniform(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn coord(&mut self, range: i64) -> i16 {
        (self.below(2 * range as u64 + 1) as i64 - range) as i16
    }
}

/// Where a test's VCD named `name` goes.
pub fn vcd(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}.vcd"))
}

/// `m`'s VCD exists, has the `signals`, starts at `vcd_from` and ends at the mismatch, and
/// `m` says where it is.
pub fn assert_vcd(m: &Mismatch, signals: &[&str]) {
    let path = m.vcd.as_ref().expect("a VCD");
    let text = std::fs::read_to_string(path).unwrap();
    for s in signals {
        assert!(text.contains(&format!(" {s} ")), "{path:?} lacks {s}");
    }
    let times: Vec<u64> = text.lines().filter_map(|l| l.strip_prefix('#')).map(|t| t.parse().unwrap()).collect();
    assert_eq!(times[0], 10 * m.vcd_from, "the VCD starts at vcd_from");
    assert_eq!(*times.last().unwrap(), 10 * m.cycle, "the VCD ends at the mismatch");
    let text = m.to_string();
    assert!(text.contains(&format!("VCD (cycles {}..={}): {}", m.vcd_from, m.cycle, path.display())), "{text}");
}
