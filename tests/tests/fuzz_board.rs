//! Fuzzing the board's byte level: every reply decoder with random bytes and every message
//! round trip (proptest), and seeded random frames ([`pficp_sim::fuzz::FrameFuzzer`]: line
//! noise, truncated, bit-flipped, overlong, random codes, loads, sizes, evaluations, runs)
//! through the byte-level reference board. Each target runs a seeded share in every
//! `cargo test`; the full counts (10^5 decoder cases, 10^6 frames) with
//!
//! ```sh
//! cargo test --release -p pficp-tests --test fuzz_board -- --ignored --nocapture
//! ```

use pficp_fpga::board::{BoardConfig, BoardModel};
use pficp_fpga::format::{FxPose, MAX_POINTS};
use pficp_fpga::messages::*;
use pficp_fpga::pf::{PfConfig, MAX_PARTICLES};
use pficp_fpga::protocol::{Command, Deframer, Frame};
use pficp_sim::fuzz::{FrameFuzzer, KINDS, MAX_MODEL, MAX_SCAN};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::time::{Duration, Instant};

/// A proptest runner of `cases` cases with a fixed seed (no persistence, no forking).
fn runner(cases: u32, seed: u64) -> TestRunner {
    let mut s = [0u8; 32];
    s[..8].copy_from_slice(&seed.to_le_bytes());
    let config = Config { cases, failure_persistence: None, ..Config::default() };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &s))
}

fn pose() -> impl Strategy<Value = FxPose> {
    let f = -(1i32 << 17)..(1i32 << 17);
    (proptest::array::uniform9(f.clone()), proptest::array::uniform3(f)).prop_map(|(m, t)| FxPose { m, t })
}

/// Every decoder takes any bytes without panicking; every message survives encode then
/// decode unchanged.
fn fuzz_decoders(cases: u32, seed: u64) {
    let bytes = proptest::collection::vec(any::<u8>(), 0..400);
    runner(cases, seed)
        .run(&(bytes, 0usize..40, any::<bool>(), 0u16..200), |(d, n, last, count)| {
            let _ = Identity::decode(&d);
            let _ = EvaluateReply::decode(&d, n, last);
            let near = NearestRequest { first: 3, count, pose: FxPose { m: [0; 9], t: [0; 3] } };
            let _ = NearestReply::decode(&d, &near);
            let _ = StatusReply::decode(&d);
            let _ = ResultReply::decode(&d);
            let _ = PfConfig::decode(&d);
            let _ = parse_two_u16(&d);
            let _ = Frame::decode(&d);
            let mut deframer = Deframer::default();
            for &b in &d {
                let _ = deframer.push(b);
            }
            Ok(())
        })
        .unwrap();

    let status = (0u8..3, any::<u16>(), 0..=NO_COST);
    let result =
        (any::<u16>(), 0..=NO_COST, 0..=MAX_D2_MASK, proptest::array::uniform7(-(1i32 << 23)..(1i32 << 23)), pose());
    let nearest = (any::<u16>(), 0..=NO_COST, proptest::collection::vec((any::<u16>(), 0u64..1 << 40), 0..150));
    let evaluate = (
        proptest::collection::vec(0..=NO_COST, 0..38),
        proptest::option::of((0..=NO_COST, 0u32..1 << 24, proptest::collection::vec(any::<u16>(), 0..257))),
    );
    runner(cases, seed + 1)
        .run(&(status, result, nearest, evaluate), |(s, r, n, e)| {
            let s = StatusReply { state: RunState::from_byte(s.0).unwrap(), iterations: s.1, best_cost: s.2 };
            prop_assert_eq!(StatusReply::decode(&s.encode()).unwrap(), s);
            let r = ResultReply { iterations: r.0, cost: r.1, max_d2: r.2, params: r.3, pose: r.4 };
            prop_assert_eq!(ResultReply::decode(&r.encode()).unwrap(), r);
            let reply = NearestReply { first: n.0, cost: n.1, results: n.2 };
            let request = NearestRequest { first: n.0, count: reply.results.len() as u16, pose: r.pose };
            prop_assert_eq!(NearestReply::decode(&reply.encode(), &request).unwrap(), reply);
            let summary = e.1.map(|(min_cost, w_sum, weights)| WeightSummary { min_cost, w_sum, weights });
            let last = summary.is_some();
            let ev = EvaluateReply { costs: e.0, summary };
            prop_assert_eq!(EvaluateReply::decode(&ev.encode(), ev.costs.len(), last).unwrap(), ev);
            Ok(())
        })
        .unwrap();
}

#[test]
fn decoders_take_any_bytes_and_messages_round_trip() {
    fuzz_decoders(2_000, 1);
}

#[test]
#[ignore = "10^5 cases a part: run in release with --ignored"]
fn decoders_full() {
    fuzz_decoders(100_000, 2);
    eprintln!("decoders: 2 x 100000 cases (seeds 2, 3), no panic");
}

/// What a fuzz run through the reference saw.
#[derive(Debug, Default)]
struct Seen {
    kinds: [usize; KINDS.len()],
    frames: usize,
    replies: usize,
    error_replies: usize,
    resizes: usize,
    slowest: Duration,
}

/// `frames` drawn wires through the byte-level reference: no panic; every reply a valid
/// frame with the reply bit; a well-formed request answered exactly once, with its own
/// sequence and its command (or an error reply naming it); the stores within their limits.
fn fuzz_reference(frames: usize, seed: u64) -> Seen {
    let mut board = BoardModel::new(BoardConfig::default());
    let mut fuzz = FrameFuzzer::new(seed);
    let mut seen = Seen::default();
    let exchange = |board: &mut BoardModel, wire: &[u8], seen: &mut Seen| -> Vec<Frame> {
        let t = Instant::now();
        let out = board.receive_all(wire);
        seen.slowest = seen.slowest.max(t.elapsed());
        let mut deframer = Deframer::default();
        let replies: Vec<Frame> = out
            .iter()
            .filter_map(|&b| deframer.push(b))
            .map(|r| r.unwrap_or_else(|e| panic!("the reference sent an undecodable frame ({e:?}) for {wire:02x?}")))
            .collect();
        let sent = wire.split(|&b| b == 0).filter(|f| !f.is_empty()).count();
        assert!(replies.len() <= sent, "{} replies to {sent} frames: {wire:02x?}", replies.len());
        for r in &replies {
            assert!(r.code & 0x80 != 0, "a reply without the reply bit: {r:?}");
            seen.error_replies += (r.code == Command::Error as u8 | 0x80) as usize;
        }
        seen.replies += replies.len();
        replies
    };
    for _ in 0..frames {
        let d = fuzz.next_wire();
        seen.kinds[d.kind] += 1;
        seen.frames += 1;
        let replies = exchange(&mut board, &d.wire, &mut seen);
        if let Some(c) = d.command {
            let body = pficp_fpga::protocol::cobs_decode(&d.wire[..d.wire.len() - 1]).unwrap();
            assert_eq!(replies.len(), 1, "{c:?} answered {} times", replies.len());
            let r = &replies[0];
            if d.wire.len() > pficp_fpga::protocol::MAX_FRAME + 1 {
                // Too long for the board's receiver (a load of more than 170 points): a
                // frame error, sequence 0.
                assert!(r.code == Command::Error as u8 | 0x80 && r.seq == 0, "{c:?} too long, answered {r:?}");
                continue;
            }
            assert_eq!(r.seq, body[1], "{c:?}: the reply's sequence");
            let named = r.code == Command::Error as u8 | 0x80 && r.data.get(1) == Some(&(c as u8));
            assert!(r.code == c as u8 | 0x80 || named, "{c:?} answered with {r:?}");
        }
        let (m, s) = board.sizes();
        assert!(m as usize <= MAX_POINTS && s as usize <= MAX_POINTS, "sizes {m}, {s}");
        assert!(board.stored_costs().len() <= MAX_PARTICLES);
        if m > MAX_MODEL || s > MAX_SCAN {
            seen.resizes += 1;
            let wire = fuzz.resize();
            assert_eq!(exchange(&mut board, &wire, &mut seen).len(), 1);
        }
    }
    seen
}

#[test]
fn random_frames_through_the_reference() {
    let seen = fuzz_reference(20_000, 1);
    assert!(seen.kinds.iter().all(|&k| k > 1000), "{seen:?}");
    assert!(seen.replies > 10_000 && seen.error_replies > 1000, "{seen:?}");
}

#[test]
#[ignore = "10^6 frames: run in release with --ignored"]
fn random_frames_through_the_reference_full() {
    let t = Instant::now();
    let seen = fuzz_reference(1_000_000, 2);
    eprintln!("reference fuzz (seed 2): {seen:?} in {:.1} s", t.elapsed().as_secs_f64());
    for (name, n) in KINDS.iter().zip(seen.kinds) {
        eprintln!("  {n:>7} {name}");
    }
}
