//! Fuzzing the message layer: every reply decoder (and the Run request's, the frame's, the
//! deframer) takes any bytes without panicking, and every message survives encode then
//! decode unchanged (proptest, seeded). A share runs in every `cargo test`; 10^5 cases a
//! part with
//!
//! ```sh
//! cargo test --release -p pficp-fpga --test messages_fuzz -- --ignored --nocapture
//! ```
//!
//! Frames through the byte-level board are `board_fuzz.rs`'s, through the Verilated board
//! `sim/tests/board_faults.rs`'s.

use pficp_fpga::common::format::FxPose;
use pficp_fpga::filter::pf::PfConfig;
use pficp_fpga::protocol::messages::*;
use pficp_fpga::protocol::{Deframer, Frame};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

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
    let result = (
        (any::<u16>(), 0..=NO_COST, 0..=MAX_D2_MASK, proptest::array::uniform7(-(1i32 << 23)..(1i32 << 23)), pose()),
        (any::<u8>(), 0..=NO_COST, pose()),
    );
    let nearest = (any::<u16>(), 0..=NO_COST, proptest::collection::vec((any::<u16>(), 0u64..1 << 40), 0..150));
    let evaluate = (
        proptest::collection::vec(0..=NO_COST, 0..38),
        proptest::option::of((0..=NO_COST, 0u32..1 << 24, proptest::collection::vec(any::<u16>(), 0..257))),
    );
    runner(cases, seed + 1)
        .run(&(status, result, nearest, evaluate), |(s, (r, p), n, e)| {
            let s = StatusReply { state: RunState::from_byte(s.0).unwrap(), iterations: s.1, best_cost: s.2 };
            prop_assert_eq!(StatusReply::decode(&s.encode()).unwrap(), s);
            let polish = pficp_fpga::protocol::run_request::PolishOutcome { winner: p.0, cost: p.1, pose: p.2 };
            let r = ResultReply { iterations: r.0, cost: r.1, max_d2: r.2, params: r.3, pose: r.4, polish };
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
