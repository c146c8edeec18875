//! Seeded random frames for the Verilated board (`sim/tests/board_faults.rs`, 10^4 frames
//! with `--ignored`): [`FrameFuzzer::next_wire`] draws one of [`KINDS`], from line noise to
//! well-formed requests that change the board's state, and the byte-level reference beside
//! the RTL says what each must get. (The reference alone is fuzzed deeper, with predicted
//! error codes, in `fpga/tests/board_fuzz.rs`.)
//!
//! Bounds (so that a fuzz run measures robustness, not the reference's compute time): the
//! reference computes a whole Run when its request arrives, so Run requests ask for at most
//! [`MAX_RUN_PARTICLES`] x [`MAX_RUN_ITERATIONS`]; sizes are at most [`MAX_MODEL`] model and
//! [`MAX_SCAN`] scan points (a SetSizes beyond them is still drawn, and refused or accepted
//! as the board decides, but the fuzzer then sizes the board back down, see
//! [`FrameFuzzer::resize`]); random-data frames carry at most 64 bytes (a Run request has
//! 150, so random data never starts a run).

use pficp_fpga::common::format::{FxPoint, FxPose, WeightScale};
use pficp_fpga::common::splitmix::SplitMix64;
use pficp_fpga::filter::pf::{PfConfig, PARAMS, SCALE_FRAC};
use pficp_fpga::polish::ScaleStep;
use pficp_fpga::protocol::messages::{self, EvaluateRequest, NearestRequest};
use pficp_fpga::protocol::run_request::{PolishRequest, RunRequest};
use pficp_fpga::protocol::{Command, Frame, MAX_FRAME};

/// Most particles a fuzzed Run asks for.
pub const MAX_RUN_PARTICLES: u16 = 6;
/// Most iterations a fuzzed Run asks for.
pub const MAX_RUN_ITERATIONS: u16 = 3;
/// Most model points the fuzzer keeps in use.
pub const MAX_MODEL: u16 = 96;
/// Most scan points the fuzzer keeps in use.
pub const MAX_SCAN: u16 = 24;

/// The kinds of wire a fuzzer draws, by name (the index is [`Drawn::kind`]).
pub const KINDS: [&str; 9] = [
    "random bytes",
    "truncated",
    "bit-flipped",
    "overlong",
    "random code and data",
    "load",
    "set sizes",
    "evaluate or nearest",
    "run, status or result",
];

/// One drawn wire.
#[derive(Clone, Debug)]
pub struct Drawn {
    /// Index into [`KINDS`].
    pub kind: usize,
    /// The bytes (ending with a delimiter).
    pub wire: Vec<u8>,
    /// The command of a well-formed request (kinds 5 to 8), if any.
    pub command: Option<Command>,
}

/// A seeded source of board frames.
pub struct FrameFuzzer {
    rng: SplitMix64,
    seq: u8,
}

impl FrameFuzzer {
    /// A fuzzer with `seed` (the same seed draws the same frames).
    pub fn new(seed: u64) -> Self {
        FrameFuzzer { rng: SplitMix64(seed ^ 0x9e37_79b9_7f4a_7c15), seq: 0 }
    }

    /// The next 64 random bits (SplitMix64).
    pub fn next_u64(&mut self) -> u64 {
        self.rng.next_u64()
    }

    /// A number below `n` (`n` > 0).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }

    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next_u64() as u8).collect()
    }

    fn seq(&mut self) -> u8 {
        self.seq = self.seq.wrapping_add(1).max(1);
        self.seq
    }

    fn points(&mut self, n: usize) -> Vec<FxPoint> {
        (0..n).map(|_| [0; 3].map(|_: i16| self.below(12001) as i16 - 6000)).collect()
    }

    fn pose(&mut self) -> FxPose {
        let a = self.below(6284) as f64 / 1000.0;
        let s = 0.8 + self.below(400) as f64 / 1000.0;
        let t = [0; 3].map(|_: i32| (self.below(200) as f64 - 100.0) / 1000.0);
        FxPose::from_f64(&[a.cos() * s, -a.sin() * s, 0.0, a.sin() * s, a.cos() * s, 0.0, 0.0, 0.0, s], &t)
    }

    fn request(&mut self, command: Command, data: Vec<u8>) -> Vec<u8> {
        let seq = self.seq();
        Frame { code: command as u8, seq, data }.encode()
    }

    /// A small Run request: a small filter, then a polish of 0 to 2 steps over up to the
    /// fuzzer's largest scan (beyond the sizes in use at times) from 1 to 4 starts, and 0 to
    /// 2 further steps for the winner, the scale solved or held.
    pub fn run_request(&mut self) -> Vec<u8> {
        let cfg = PfConfig {
            particles: 1 + self.below(MAX_RUN_PARTICLES as u64) as u16,
            iterations: 1 + self.below(MAX_RUN_ITERATIONS as u64) as u16,
            temper_exp: self.below(40) as u8,
            centre: [0, 0, 0, 1 << SCALE_FRAC, 0, 0, 0],
            sigma0: [0; PARAMS].map(|_: u32| 1 + self.below(1 << 16) as u32),
            floor: [0; PARAMS].map(|_: u32| 1 + self.below(64) as u32),
            seed: self.next_u64() as u32,
            thr_cost: if self.below(4) == 0 { self.below(1 << 20) } else { 0 },
            thr_max: 0,
        };
        let polish = PolishRequest {
            points: 1 + self.below(MAX_SCAN as u64) as u16,
            steps: self.below(3) as u8,
            winner_steps: self.below(3) as u8,
            scale: if self.below(2) == 0 { ScaleStep::Solved } else { ScaleStep::Held },
            hypotheses: (0..self.below(4)).map(|_| self.pose()).collect(),
        };
        self.request(Command::Run, RunRequest { filter: cfg, polish }.encode())
    }

    /// A SetSizes request within the fuzzer's bounds.
    pub fn resize(&mut self) -> Vec<u8> {
        let m = 1 + self.below(MAX_MODEL as u64) as u16;
        let s = 1 + self.below(MAX_SCAN as u64) as u16;
        self.request(Command::SetSizes, messages::two_u16(m, s))
    }

    /// The next wire.
    pub fn next_wire(&mut self) -> Drawn {
        let kind = self.below(KINDS.len() as u64) as usize;
        let mut command = None;
        let wire = match kind {
            0 => {
                let n = 1 + self.below(60) as usize;
                let mut w = self.bytes(n);
                w.push(0);
                w
            }
            1 => {
                let mut w = self.request(Command::Identify, vec![]);
                let cut = 1 + self.below(w.len() as u64 - 1) as usize;
                w.truncate(cut);
                w.push(0);
                w
            }
            2 => {
                // A bit flipped in a read-only request (an undetected flip cannot change state).
                let near =
                    NearestRequest { first: 0, count: 1 + self.below(MAX_SCAN as u64) as u16, pose: self.pose() };
                let mut w = self.request(Command::Nearest, near.encode());
                let i = self.below(w.len() as u64 - 1) as usize;
                w[i] ^= 1 << self.below(8);
                w
            }
            3 => {
                let n = MAX_FRAME + 1 + self.below(40) as usize;
                let mut w: Vec<u8> = (0..n).map(|_| 1 + self.below(255) as u8).collect();
                w.push(0);
                w
            }
            4 => {
                // A well-formed frame (valid CRC) with a random code and random data: mostly
                // command errors, sometimes a request with random contents.
                let code = self.next_u64() as u8;
                let n = self.below(65) as usize;
                let data = self.bytes(n);
                let seq = self.seq();
                Frame { code, seq, data }.encode()
            }
            5 if self.below(3) == 0 => {
                // Cell-table entries: mostly a stretch of a table of at most MAX_MODEL
                // points (increasing), sometimes anything up to 2 MAX_MODEL (ranges
                // reversed or past the model); sometimes a count or offset out of range.
                let range = if self.below(8) == 0 { 5000 } else { messages::TABLE_ENTRIES as u64 };
                let offset = self.below(range) as u16;
                let n = self.below(messages::MAX_LOAD_ENTRIES as u64 + 8) as usize;
                let mut at = self.below(MAX_MODEL as u64 / 2) as u16;
                let entries: Vec<u16> = (0..n)
                    .map(|_| {
                        at = (at + (self.below(8) == 0) as u16).min(MAX_MODEL);
                        if self.below(16) == 0 {
                            self.below(2 * MAX_MODEL as u64) as u16
                        } else {
                            at
                        }
                    })
                    .collect();
                command = Some(Command::LoadTable);
                self.request(Command::LoadTable, messages::table_request(offset, &entries))
            }
            5 => {
                let model = self.below(2) == 0;
                let range = if self.below(8) == 0 { 5000 } else { MAX_MODEL as u64 };
                let offset = self.below(range) as u16;
                let n = self.below(messages::MAX_LOAD_POINTS as u64 + 8) as usize;
                let points = self.points(n);
                let c = if model { Command::LoadModel } else { Command::LoadScan };
                command = Some(c);
                self.request(c, messages::load_request(offset, &points))
            }
            6 => {
                command = Some(Command::SetSizes);
                if self.below(4) == 0 {
                    let (m, s) = (self.next_u64() as u16 % 5000, self.next_u64() as u16 % 5000);
                    self.request(Command::SetSizes, messages::two_u16(m, s))
                } else {
                    self.resize()
                }
            }
            7 => {
                if self.below(2) == 0 {
                    let n = self.below(messages::MAX_POSES as u64 + 2) as usize;
                    let poses = (0..n).map(|_| self.pose()).collect();
                    let ev = EvaluateRequest {
                        first: self.below(2) == 0,
                        last: self.below(2) == 0,
                        scale: WeightScale::for_two_q((1 + self.below(1 << 30)) as f64),
                        poses,
                    };
                    command = Some(Command::Evaluate);
                    self.request(Command::Evaluate, ev.encode())
                } else {
                    let first = self.below(MAX_SCAN as u64 + 4) as u16;
                    let count = self.below(messages::MAX_NEAREST as u64 + 4) as u16;
                    let near = NearestRequest { first, count, pose: self.pose() };
                    command = Some(Command::Nearest);
                    self.request(Command::Nearest, near.encode())
                }
            }
            _ => {
                let c = [Command::Run, Command::Status, Command::Result, Command::Identify][self.below(4) as usize];
                command = Some(c);
                if c == Command::Run {
                    self.run_request()
                } else {
                    self.request(c, vec![])
                }
            }
        };
        Drawn { kind, wire, command }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_seed_draws_the_same_frames_and_every_kind_comes() {
        let (mut a, mut b) = (FrameFuzzer::new(3), FrameFuzzer::new(3));
        let mut seen = [0usize; KINDS.len()];
        for _ in 0..500 {
            let (x, y) = (a.next_wire(), b.next_wire());
            assert_eq!(x.wire, y.wire);
            assert_eq!(x.wire.last(), Some(&0), "every wire ends with a delimiter");
            seen[x.kind] += 1;
        }
        assert!(seen.iter().all(|&n| n > 20), "{seen:?}");
        assert_ne!(FrameFuzzer::new(4).next_wire().wire, FrameFuzzer::new(3).next_wire().wire);
    }
}
