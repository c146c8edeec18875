//! Boards that misbehave, served on a real pseudo-terminal: each ends in a clear, typed
//! error within the time the client documents (host/src/board/client.rs, "Every read is
//! bounded"), never a hang, a panic or a result built on bad numbers.

mod support;

use pficp::board::{BoardClient, BoardError, MAX_RETRIES};
use pficp_fpga::common::format::{FxPose, WeightScale};
use pficp_fpga::protocol::messages::{
    EvaluateReply, NearestReply, NearestRequest, ResultReply, RunState, StatusReply, FLAG_LAST,
};
use pficp_fpga::protocol::{Command, Frame};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::{Duration, Instant};
use support::{cloud, intercepting_handler, PtyBoard};

const TIMEOUT: Duration = Duration::from_millis(300);

fn pose(angle: f64) -> FxPose {
    let (c, s) = (angle.cos(), angle.sin());
    FxPose::from_f64(&[c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0], &[0.01, -0.02, 0.03])
}

fn client_of(board: &mut PtyBoard) -> BoardClient {
    let mut client = board.client();
    client.set_timeout(TIMEOUT);
    client
}

/// Identify, load, size: a client ready for Evaluate, Nearest and Run.
fn loaded(board: &mut PtyBoard, model: usize, scan: usize) -> BoardClient {
    let mut client = client_of(board);
    client.identify().unwrap();
    client.load_model(&cloud(model, 1), |_, _| {}).unwrap();
    client.load_scan(&cloud(scan, 2), |_, _| {}).unwrap();
    client.set_sizes(model, scan).unwrap();
    client
}

/// The reference's reply to `f`, with its data changed by `edit`.
fn edited(f: &Frame, b: &mut pficp_fpga::board::BoardModel, edit: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let mut reply = b.execute(f);
    edit(&mut reply.data);
    reply.encode()
}

/// `took` is within the documented bound (`bound`) plus a second for a loaded machine.
fn within(took: Duration, bound: Duration) {
    assert!(took < bound + Duration::from_secs(1), "took {took:?}, documented bound {bound:?}");
}

#[test]
fn an_echoing_port_is_named_at_once() {
    let mut board = PtyBoard::serve(Box::new(|bytes| Some(bytes.to_vec())));
    let mut client = client_of(&mut board);
    let t = Instant::now();
    let e = client.identify().unwrap_err();
    assert!(matches!(e, BoardError::Echo { command: Command::Identify, .. }), "{e:?}");
    assert!(e.to_string().contains("loopback") && e.to_string().contains(&board.path), "{e}");
    within(t.elapsed(), Duration::ZERO);
}

#[test]
fn a_babbling_port_is_an_error_after_the_retries() {
    // Random bytes (zeros among them end "frames" that never decode).
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut board = PtyBoard::babbling(move || (0..64).map(|_| rng.gen()).collect());
    let mut client = client_of(&mut board);
    let t = Instant::now();
    let e = client.identify().unwrap_err();
    assert!(
        matches!(e, BoardError::Retries { command: Command::Identify, attempts, .. } if attempts == MAX_RETRIES + 1),
        "{e:?}"
    );
    within(t.elapsed(), TIMEOUT * (MAX_RETRIES as u32 + 1));

    // Bytes without a delimiter: no frame ever ends; a timeout that says bytes came.
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let mut board = PtyBoard::babbling(move || (0..64).map(|_| rng.gen_range(1..=255u8)).collect());
    let mut client = client_of(&mut board);
    let t = Instant::now();
    let e = client.identify().unwrap_err();
    assert!(matches!(e, BoardError::Timeout { received, .. } if received > 0), "{e:?}");
    assert!(e.to_string().contains("no valid reply"), "{e}");
    within(t.elapsed(), TIMEOUT);
}

#[test]
fn a_board_that_truncates_its_replies_is_an_error() {
    // Cut before the delimiter: the CRC fails, the request is resent, and again.
    let mut board = PtyBoard::serve(intercepting_handler(|f, b| {
        let mut wire = b.execute(f).encode();
        wire.drain(wire.len() - 4..wire.len() - 1);
        Some(wire)
    }));
    let mut client = client_of(&mut board);
    let t = Instant::now();
    let e = client.identify().unwrap_err();
    assert!(matches!(e, BoardError::Retries { command: Command::Identify, .. }), "{e:?}");
    within(t.elapsed(), TIMEOUT * (MAX_RETRIES as u32 + 1));

    // Shortened data with a valid CRC: a malformed reply naming the length.
    let mut board = PtyBoard::serve(intercepting_handler(|f, b| {
        (f.code == Command::Status as u8).then(|| edited(f, b, |d| d.truncate(d.len() - 2)))
    }));
    let mut client = client_of(&mut board);
    let e = client.status().unwrap_err();
    assert!(matches!(e, BoardError::Reply { command: Command::Status, .. }), "{e:?}");
    assert!(e.to_string().contains("7 bytes, expected 9"), "{e}");
}

#[test]
fn a_reply_with_another_sequence_or_for_another_command_is_named() {
    for (code_of, seq_of, words) in [
        (None, Some(1u8), "with sequence"), // the right command, the sequence off by one
        (Some(Command::Status as u8 | 0x80), None, "to Status"), // our sequence, another command
    ] {
        let mut board = PtyBoard::serve(intercepting_handler(move |f, b| {
            let mut reply = b.execute(f);
            if let Some(c) = code_of {
                reply.code = c;
            }
            if let Some(d) = seq_of {
                reply.seq = reply.seq.wrapping_add(d);
            }
            Some(reply.encode())
        }));
        let mut client = client_of(&mut board);
        let t = Instant::now();
        let e = client.identify().unwrap_err();
        assert!(matches!(e, BoardError::Unexpected { command: Command::Identify, .. }), "{e:?}");
        assert!(e.to_string().contains(words), "{e}");
        assert!(t.elapsed() >= TIMEOUT, "waited for the real reply first");
        within(t.elapsed(), TIMEOUT);
    }
}

#[test]
fn weights_that_are_not_the_exp_tables_are_an_error() {
    // One weight changed by 1: the sum still matches (it is changed too), the table does not.
    let mut board = PtyBoard::serve(intercepting_handler(|f, b| {
        if f.code != Command::Evaluate as u8 || f.data.first().is_none_or(|&x| x & FLAG_LAST == 0) {
            return None;
        }
        let reply = b.execute(f);
        let mut r = EvaluateReply::decode(&reply.data, f.data[5] as usize, true).ok()?;
        let s = r.summary.as_mut()?;
        s.weights[0] ^= 1;
        s.w_sum = s.weights.iter().map(|&w| w as u32).sum();
        Some(Frame { code: reply.code, seq: f.seq, data: r.encode() }.encode())
    }));
    let mut client = loaded(&mut board, 200, 80);
    let poses: Vec<FxPose> = (0..8).map(|k| pose(0.1 * k as f64)).collect();
    let e = client.costs_and_weights(&poses, |_| WeightScale::for_two_q(1e6)).unwrap_err();
    assert!(matches!(&e, BoardError::Filter(m) if m.contains("exp table")), "{e:?}");
}

#[test]
fn a_nearest_reply_outside_the_model_or_with_a_wrong_sum_is_an_error() {
    for (edit, field) in [
        (Box::new(|r: &mut NearestReply| r.results[3].0 = 200) as Box<dyn Fn(&mut NearestReply) + Send>, "model index"),
        (Box::new(|r: &mut NearestReply| r.cost += 1), "cost"),
    ] {
        let mut board = PtyBoard::serve(intercepting_handler(move |f, b| {
            if f.code != Command::Nearest as u8 {
                return None;
            }
            let request = NearestRequest { first: 0, count: 20, pose: pose(0.2) };
            let reply = b.execute(f);
            let mut r = NearestReply::decode(&reply.data, &request).ok()?;
            edit(&mut r);
            Some(Frame { code: reply.code, seq: f.seq, data: r.encode() }.encode())
        }));
        let mut client = loaded(&mut board, 200, 80);
        let e = client.nearest(0, 20, &pose(0.2)).unwrap_err();
        assert!(matches!(&e, BoardError::Reply { command: Command::Nearest, .. }), "{e:?}");
        assert!(e.to_string().contains(field), "{e}");
    }
}

#[test]
fn a_result_whose_pose_or_numbers_do_not_fit_is_an_error() {
    type Edit = Box<dyn Fn(&mut ResultReply) + Send>;
    let cases: [(Edit, &str); 3] = [
        (Box::new(|r| r.pose.t[0] += 1), "not the one its parameters"),
        (Box::new(|r| r.iterations = 5), "iterations"),
        (Box::new(|r| r.max_d2 = r.cost + 1), "max_d2"),
    ];
    for (edit, words) in cases {
        let mut board = PtyBoard::serve(intercepting_handler(move |f, b| {
            if f.code != Command::Result as u8 {
                return None;
            }
            let reply = b.execute(f);
            let mut r = ResultReply::decode(&reply.data).ok()?;
            edit(&mut r);
            Some(Frame { code: reply.code, seq: f.seq, data: r.encode() }.encode())
        }));
        let mut client = loaded(&mut board, 200, 60);
        let cfg = support::run_config(8, 4, 7, 1, 0);
        client.run(&cfg).unwrap();
        client
            .wait_for_run(client.run_allowance(&cfg), client.modelled_run_time(&cfg), Duration::from_millis(5), |_| {})
            .unwrap();
        let e = client.result().unwrap_err();
        assert!(e.to_string().contains(words), "{e}");
    }
}

#[test]
fn a_creeping_board_ends_within_the_overall_cap() {
    // One new iteration just inside every stall limit up to the Run's cap, then no more:
    // the wait ends one stall limit after the last, within the overall cap (the stall
    // limit times iterations + 1), which a count that must rise cannot outlast. The
    // iterations come 250 ms apart against a 500 ms limit: a loaded machine's slow pty
    // replies (over 300 ms seen) must not pass for a stall.
    let limit = Duration::from_millis(500);
    let mut started: Option<Instant> = None;
    let mut board = PtyBoard::serve(intercepting_handler(move |f, b| {
        if f.code != Command::Status as u8 || b.run_outcome().is_none() {
            return None;
        }
        let t0 = *started.get_or_insert_with(Instant::now);
        let iterations = (t0.elapsed().as_millis() / 250).min(4) as u16;
        let s = StatusReply { state: RunState::Running, iterations, best_cost: 9 };
        Some(Frame { code: 0x88, seq: f.seq, data: s.encode() }.encode())
    }));
    let mut client = loaded(&mut board, 200, 60);
    client.run(&support::run_config(8, 4, 7, 1, 0)).unwrap();
    let t = Instant::now();
    let e = client.wait_for_run(limit, Duration::ZERO, Duration::from_millis(10), |_| {}).unwrap_err();
    let overall = limit * (support::run_config(8, 4, 7, 1, 0).filter.iterations as u32 + 1);
    assert!(
        matches!(e, BoardError::RunTimeout { overall_limit, iterations: 4, .. } if overall_limit == overall),
        "{e:?}"
    );
    assert!(t.elapsed() >= Duration::from_millis(4 * 250), "{:?}", t.elapsed());
    within(t.elapsed(), overall);
}
