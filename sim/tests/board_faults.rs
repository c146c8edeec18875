//! Faults through the Verilated board (fast-UART build, at its bit timing): random bytes,
//! truncated frames, bad CRCs, overlong frames and random requests, each answered exactly
//! as the byte-level reference answers (or dropped as it drops them); frames while busy;
//! reset in the middle of a command. The board never hangs (it is idle again within a
//! bound after every frame) and its stores are intact afterwards.

use pficp_fpga::board::{BoardConfig, BoardModel};
use pficp_fpga::common::format::{FxPoint, FxPose, WeightScale};
use pficp_fpga::protocol::messages::{self, EvaluateRequest, NearestRequest};
use pficp_fpga::protocol::{Command, ErrorCode, Frame, MAX_FRAME};
use pficp_sim::serial::SerialBoard;

/// Clocks any single frame may take on the fast board before the test calls it a hang.
const HANG: u64 = 5_000_000;

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0 >> 33
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next() as u8).collect()
    }
}

fn seed() -> u64 {
    std::env::var("PFICP_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(11)
}

fn cloud(n: usize, rng: &mut Rng) -> Vec<FxPoint> {
    (0..n).map(|_| [0; 3].map(|_: i16| rng.below(12001) as i16 - 6000)).collect()
}

fn pose(k: u64) -> FxPose {
    let a = 0.3 * k as f64;
    FxPose::from_f64(&[a.cos(), -a.sin(), 0.0, a.sin(), a.cos(), 0.0, 0.0, 0.0, 1.0], &[0.02, 0.0, -0.01])
}

fn frame(cmd: Command, seq: u8, data: Vec<u8>) -> Vec<u8> {
    Frame { code: cmd as u8, seq, data }.encode()
}

/// The requests that load 64 model and 16 scan points (drawn from `rng`) and set the sizes.
fn load_requests(rng: &mut Rng) -> [Vec<u8>; 3] {
    let model = cloud(64, rng);
    let scan = cloud(16, rng);
    [
        frame(Command::LoadModel, 1, messages::load_request(0, &model)),
        frame(Command::LoadScan, 2, messages::load_request(0, &scan)),
        frame(Command::SetSizes, 3, messages::two_u16(64, 16)),
    ]
}

/// A board (and its reference) with 64 model and 16 scan points loaded.
fn loaded(rng: &mut Rng) -> SerialBoard {
    let mut b = SerialBoard::new(BoardConfig::FAST_SIM).with_reference();
    for wire in load_requests(rng) {
        checked(&mut b, &wire);
    }
    b
}

/// The same board without the reference (for what the reference does not model).
fn loaded_unchecked(rng: &mut Rng) -> SerialBoard {
    let mut b = SerialBoard::new(BoardConfig::FAST_SIM);
    for wire in load_requests(rng) {
        b.exchange(&wire, HANG).expect("idle after a load");
    }
    b
}

/// Send bytes, wait until idle (or fail: a hang), check every byte against the reference.
fn checked(b: &mut SerialBoard, wire: &[u8]) -> Vec<u8> {
    let got = b.exchange(wire, HANG).unwrap_or_else(|c| panic!("the board did not go idle within {c} clocks"));
    let (n, m) = b.comparison();
    assert!(m.is_none(), "after {n} bytes: {}", m.unwrap());
    assert_eq!(b.expected_pending(), 0, "the board sent less than the reference");
    got
}

/// Send a request and run until its reply's delimiter (not until idle: a running filter
/// keeps the board busy), every byte checked against the reference.
fn reply_of(b: &mut SerialBoard, wire: &[u8]) -> Vec<u8> {
    b.send(wire);
    let mut got = Vec::new();
    let start = b.clocks();
    while !got.contains(&0) {
        b.step();
        got.extend(b.take_received());
        assert!(b.clocks() - start < HANG, "no reply within {HANG} clocks");
    }
    let (n, m) = b.comparison();
    assert!(m.is_none(), "after {n} bytes: {}", m.unwrap());
    got
}

fn stores(m: &BoardModel) -> (Vec<u64>, Vec<u64>, (u16, u16), Vec<u64>) {
    (m.model_store().to_vec(), m.scan_store().to_vec(), m.sizes(), m.stored_costs().to_vec())
}

#[test]
fn random_and_broken_frames_are_answered_as_the_reference_answers() {
    let mut rng = Rng(seed());
    let mut b = loaded(&mut rng);
    let before = stores(b.reference().unwrap());
    let mut counts = [0usize; 5];
    for round in 0..1000 {
        let kind = (round % 5) as usize;
        let wire: Vec<u8> = match kind {
            // Random bytes (rarely a zero), then a delimiter.
            0 => {
                let n = 1 + rng.below(60) as usize;
                let mut w = rng.bytes(n);
                w.push(0);
                w
            }
            // A valid request cut short.
            1 => {
                let w = frame(Command::Identify, rng.next() as u8, vec![]);
                let cut = 1 + rng.below(w.len() as u64 - 1) as usize;
                let mut t = w[..cut].to_vec();
                t.push(0);
                t
            }
            // A bit flipped in a read-only request (so an undetected flip cannot change state).
            2 => {
                let near = NearestRequest { first: 0, count: 16, pose: pose(round) };
                let mut w = frame(Command::Nearest, rng.next() as u8, near.encode());
                let i = rng.below(w.len() as u64 - 1) as usize;
                w[i] ^= 1 << rng.below(8);
                w
            }
            // Overlong: more than MAX_FRAME bytes before the delimiter.
            3 => {
                let mut w: Vec<u8> =
                    (0..MAX_FRAME + 1 + rng.below(40) as usize).map(|_| 1 + rng.below(255) as u8).collect();
                w.push(0);
                w
            }
            // A well-formed frame with a random command code and random data (valid CRC):
            // mostly command errors; loads and evaluations with random contents change state
            // exactly as in the reference, so only read-only codes and errors are drawn here.
            _ => {
                let code = [0x00, 0x01, 0x04, 0x05, 0x06, 0x07, 0x42, 0x7f, 0x81, 0xff][rng.below(10) as usize];
                let n = rng.below(40) as usize;
                let data = rng.bytes(n);
                let code = if code == 0x04 || code == 0x05 { code | 0x80 } else { code };
                Frame { code, seq: rng.next() as u8, data }.encode()
            }
        };
        counts[kind] += 1;
        // One frame at a time, as a host that waits for each answer sends them (a frame that
        // arrives while the board answers the previous one gets Busy, which the reference
        // does not model: that rule has its own test below).
        for segment in wire.split_inclusive(|&x| x == 0) {
            checked(&mut b, segment);
        }
    }
    let after = stores(b.reference().unwrap());
    assert!(before == after, "rejected frames left the reference's stores as they were");
    // The stores are intact on the board too: a full Nearest and an evaluation match.
    let near = NearestRequest { first: 0, count: 16, pose: pose(1) };
    checked(&mut b, &frame(Command::Nearest, 9, near.encode()));
    let ev = EvaluateRequest {
        first: true,
        last: true,
        scale: WeightScale::for_two_q(4.0e6),
        poses: vec![pose(2), pose(3)],
    };
    checked(&mut b, &frame(Command::Evaluate, 10, ev.encode()));
    eprintln!(
        "fuzz through the RTL (seed {}): {} random, {} truncated, {} bit-flipped, {} overlong, {} random requests; {} bytes compared, {} clocks",
        seed(),
        counts[0],
        counts[1],
        counts[2],
        counts[3],
        counts[4],
        b.comparison().0,
        b.clocks()
    );
}

#[test]
fn frames_while_busy_get_one_busy_answer_after_the_current_one() {
    let mut rng = Rng(seed() + 1);
    let b = loaded(&mut rng);
    // The reference of what follows, from the same state.
    let mut reference = b.reference().unwrap().clone();
    let ev = EvaluateRequest {
        first: true,
        last: true,
        scale: WeightScale::for_two_q(4.0e6),
        poses: (0..37).map(pose).collect(),
    };
    let ev_wire = frame(Command::Evaluate, 40, ev.encode());
    let mut expected = reference.receive_all(&ev_wire);
    expected.extend(Frame::error(41, ErrorCode::Busy, Command::Identify as u8).encode());
    // From here on the board is checked by hand (the reference does not model Busy).
    let mut b2 = loaded_unchecked(&mut Rng(seed() + 1));
    drop(b);
    // The Evaluate, then at once: an Identify (valid: Busy), a second valid frame and a
    // corrupted one (both dropped: only the first busy frame is answered).
    let mut burst = ev_wire.clone();
    burst.extend(frame(Command::Identify, 41, vec![]));
    burst.extend(frame(Command::Identify, 42, vec![]));
    let mut bad = frame(Command::Identify, 43, vec![]);
    bad[1] ^= 0x10;
    burst.extend(bad);
    let got = b2.exchange(&burst, HANG).expect("idle again");
    assert_eq!(got, expected, "the Evaluate's answer, then one Busy for sequence 41");
    // And afterwards the board is idle and answers normally.
    let id = b2.exchange(&frame(Command::Identify, 44, vec![]), HANG).unwrap();
    assert_eq!(id, reference.receive_all(&frame(Command::Identify, 44, vec![])));
}

#[test]
fn reset_in_the_middle_of_a_command_returns_to_idle_with_the_stores_kept() {
    let mut rng = Rng(seed() + 2);
    let b = loaded(&mut rng);
    let mut reference = b.reference().unwrap().clone();
    let near = NearestRequest { first: 0, count: 16, pose: pose(4) };
    let wire = frame(Command::Nearest, 50, near.encode());
    let mut unchecked = loaded_unchecked(&mut Rng(seed() + 2));
    drop(b);
    for cut in [200u64, 1_500, 2_500] {
        // Half a Nearest (still receiving, computing or answering), then reset.
        unchecked.send(&wire);
        unchecked.run(cut);
        unchecked.set_reset(true);
        unchecked.run(20);
        unchecked.set_reset(false);
        unchecked.run_until_idle(HANG).expect("idle after reset");
        unchecked.take_received();
        // A delimiter resynchronises the receiver after a frame cut by the reset.
        let got = unchecked.exchange(&[0], HANG).unwrap();
        assert!(got.is_empty() || got.ends_with(&[0]), "{got:?}");
        let again = unchecked.exchange(&wire, HANG).unwrap();
        assert_eq!(again, reference.receive_all(&wire), "cut at {cut}: the stores survived the reset");
    }
}

/// The board's stores, read back through the line and checked against the reference: the
/// sizes (Identify), every scan point's nearest model point (Nearest, in frames) and an
/// evaluation of every stored... of two poses (Evaluate with FIRST and LAST).
fn check_stores(b: &mut SerialBoard, seq: &mut u8) {
    let mut next = || {
        *seq = seq.wrapping_add(1).max(1);
        *seq
    };
    checked(b, &frame(Command::Identify, next(), vec![]));
    let (_, scan) = b.reference().unwrap().sizes();
    if scan > 0 {
        let near = NearestRequest { first: 0, count: scan.min(messages::MAX_NEAREST as u16), pose: pose(5) };
        checked(b, &frame(Command::Nearest, next(), near.encode()));
    }
    let ev =
        EvaluateRequest { first: true, last: true, scale: WeightScale::for_two_q(1e7), poses: vec![pose(6), pose(7)] };
    checked(b, &frame(Command::Evaluate, next(), ev.encode()));
}

/// `frames` drawn wires ([`pficp_sim::fuzz::FrameFuzzer`], state-changing requests among
/// them: loads, sizes, evaluations, runs) through the Verilated board beside the
/// reference, every byte compared; after an accepted Run the filter is polled with Status
/// until done (each running reply checked by the progress rule); the stores are read back
/// every 500 frames and at the end. Returns (frames per kind, runs, running Status seen).
fn fuzz_rtl(frames: usize, seed: u64) -> ([usize; pficp_sim::fuzz::KINDS.len()], usize, u64) {
    use pficp_sim::fuzz::{FrameFuzzer, MAX_MODEL, MAX_SCAN};
    let mut b = SerialBoard::new(BoardConfig::FAST_SIM).with_reference();
    let mut fuzz = FrameFuzzer::new(seed);
    let mut kinds = [0; pficp_sim::fuzz::KINDS.len()];
    let (mut runs, mut seq) = (0, 0u8);
    for n in 0..frames {
        let d = fuzz.next_wire();
        kinds[d.kind] += 1;
        if d.command == Some(Command::Run) {
            // A Run's reply comes at once, then the filter runs (the board is busy but
            // answers Status): poll until it is no longer running.
            runs += 1;
            let mut poll = d.wire;
            for polls in 0.. {
                let reply = reply_of(&mut b, &poll);
                let f = Frame::decode(&reply[..reply.len() - 1]).unwrap();
                if polls > 0 && f.data.first() != Some(&1) {
                    break;
                }
                assert!(polls < 100_000, "the filter did not finish");
                b.run(2_000);
                poll = frame(Command::Status, 200, vec![]);
            }
            b.run_until_idle(HANG).expect("idle after the run");
        } else {
            for segment in d.wire.split_inclusive(|&x| x == 0) {
                checked(&mut b, segment);
            }
        }
        let (m, s) = b.reference().unwrap().sizes();
        if m > MAX_MODEL || s > MAX_SCAN {
            checked(&mut b, &fuzz.resize());
        }
        if n % 500 == 499 {
            check_stores(&mut b, &mut seq);
        }
    }
    check_stores(&mut b, &mut seq);
    (kinds, runs, b.progress_frames())
}

#[test]
fn fuzzed_requests_that_change_state_are_answered_as_the_reference_answers() {
    let (kinds, runs, progress) = fuzz_rtl(1_200, seed());
    eprintln!("RTL fuzz (seed {}): {kinds:?}, {runs} runs, {progress} running Status", seed());
    assert!(kinds.iter().all(|&k| k > 50), "{kinds:?}");
    assert!(runs > 10 && progress > 0, "{runs} runs, {progress} running Status");
}

#[test]
#[ignore = "10^4 frames through the RTL: run in release with --ignored"]
fn fuzzed_requests_full() {
    let t = std::time::Instant::now();
    let (kinds, runs, progress) = fuzz_rtl(10_000, seed() + 100);
    eprintln!(
        "RTL fuzz (seed {}): 10000 frames {kinds:?}, {runs} runs, {progress} running Status, in {:.1} s",
        seed() + 100,
        t.elapsed().as_secs_f64()
    );
}

/// The LEDs by their rule, checked on every clock by the serial line beside the reference
/// (`sim::serial`): here each rule is also seen to change state.
#[test]
fn the_leds_follow_their_rule() {
    use pficp_sim::serial::{LED_ERROR, RX_GLOW_CLOCKS};
    let mut rng = Rng(seed() + 3);
    let mut b = loaded(&mut rng);
    let led = |b: &SerialBoard, bit: u8| b.pins().leds & bit != 0;
    assert!(led(&b, 2), "receive activity lit just after a request");
    assert!(!led(&b, LED_ERROR), "the last reply was no error");
    checked(&mut b, &frame(Command::Identify, 7, vec![1, 2, 3])); // BadLength
    assert!(led(&b, LED_ERROR), "the last reply was an error");
    checked(&mut b, &frame(Command::Identify, 8, vec![]));
    assert!(!led(&b, LED_ERROR));
    b.run(RX_GLOW_CLOCKS + 1_000);
    assert!(!led(&b, 2), "receive activity dark {} clocks after the last byte", RX_GLOW_CLOCKS + 1_000);
    let (n, m) = b.comparison();
    assert!(m.is_none(), "after {n} bytes: {}", m.unwrap());
}
