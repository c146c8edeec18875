//! The board client against the byte-level reference board served on a real
//! pseudo-terminal: results equal the functional references, corrupted exchanges are
//! resent, a silent or vanishing board is a clear error within the timeout, and PF-ICP with
//! the board's weights registers a reduced model-1.

mod support;

use pficp::board::{host_driven, Upload};
use pficp::board::{BoardClient, BoardError, DEFAULT_BAUD, MAX_RETRIES, PROBE_BAUDS};
use pficp::cloud::bbox_diagonal;
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::PfIcpSettings;
use pficp::registration::methods::{PoseError, Tolerance};
use pficp_fpga::board::BoardConfig;
use pficp_fpga::common::format::WeightScale;
use pficp_fpga::filter::weights::weights;
use pficp_fpga::protocol::messages::Identity;
use pficp_fpga::protocol::{Command, ErrorCode, Frame};
use pficp_fpga::search::grid::CAP_D2;
use pficp_fpga::surface::scored;
use std::time::{Duration, Instant};
use support::{cloud, grid, loaded, normals, poses, reference_handler, uart_resample, upload, PtyBoard};

#[test]
fn identify_reports_the_reference_board() {
    let mut board = PtyBoard::reference();
    let mut client = board.client();
    let id = client.identify().unwrap();
    let c = BoardConfig::default();
    assert_eq!(id, Identity::of_board(c.lanes as u8, c.clock_hz, c.baud, 0, 0, 0));
    assert_eq!(client.stats().resends, 0);
}

#[test]
fn load_evaluate_and_weigh_equal_the_references() {
    let (model, scan) = (cloud(700, 1), cloud(300, 2));
    let mut board = PtyBoard::reference();
    let mut client = board.client();
    client.identify().unwrap();
    let mut seen = Vec::new();
    client.load_model(&model, |done, total| seen.push((done, total))).unwrap();
    assert_eq!(seen.first(), Some(&(0, 700)));
    assert_eq!(seen.last(), Some(&(700, 700)));
    assert!(seen.windows(2).all(|w| w[0].0 < w[1].0), "progress grows: {seen:?}");
    assert_eq!(seen.len(), 1 + 700usize.div_ceil(170));
    // The protocol 4 board searches through the cell table: the model goes gridded with its
    // normals, its progress in data bytes over the points, the normals and the table.
    let g = grid(&model);
    let mut seen = Vec::new();
    client.load_grid(&g, &normals(&model), |done, total| seen.push((done, total))).unwrap();
    let total = 2 * 700 * 6 + 4097 * 2;
    assert_eq!((seen.first(), seen.last()), (Some(&(0, total)), Some(&(total, total))));
    assert!(seen.windows(2).all(|w| w[0].0 < w[1].0), "progress grows: {seen:?}");
    assert_eq!(seen.len(), 1 + 2 * 700usize.div_ceil(170) + 4097usize.div_ceil(510));
    client.load_scan(&scan, |_, _| {}).unwrap();
    client.set_sizes(model.len(), scan.len()).unwrap();
    let id = client.identify().unwrap();
    assert_eq!((id.model_count, id.scan_count), (700, 300));

    // 50 particles: two frames (37 + 13), then the weights.
    let ps = poses(50, 3);
    let n = normals(&model);
    let expected: Vec<u64> = ps.iter().map(|p| scored(&g, &n, &scan, p).cost).collect();
    let mut chosen = None;
    let (costs, summary) = client
        .costs_and_weights(&ps, |c| {
            let s = WeightScale::for_two_q(((c.iter().max().unwrap() - c.iter().min().unwrap()) / 4) as f64);
            chosen = Some(s);
            s
        })
        .unwrap();
    assert_eq!(costs, expected);
    let scale = chosen.unwrap();
    assert_eq!(summary.weights, weights(&expected, &scale));
    assert_eq!(summary.min_cost, *expected.iter().min().unwrap());
    assert_eq!(summary.w_sum as u64, summary.weights.iter().map(|&w| w as u64).sum::<u64>());

    // One frame with FIRST and LAST; then weigh the same costs again with another scale.
    let r = client.evaluate(true, true, scale, &ps[..5]).unwrap();
    assert_eq!(r.costs, expected[..5]);
    assert_eq!(r.summary.unwrap().weights, weights(&expected[..5], &scale));
    let other = WeightScale::for_two_q(1e9);
    assert_eq!(client.weigh(other).unwrap().weights, weights(&expected[..5], &other));
    assert_eq!(client.stats().resends, 0);
}

#[test]
fn nearest_in_frames_equals_the_reference() {
    let (model, scan) = (cloud(400, 4), cloud(350, 5));
    let (_board, mut client) = loaded(&model, &scan);
    let pose = poses(1, 6)[0];
    let r = client.nearest(10, 320, &pose).unwrap();
    let g = grid(&model);
    let e = scored(&g, &normals(&model), &scan[10..330], &pose);
    assert_eq!(r.first, 10);
    assert_eq!(r.results, e.nearest);
    assert_eq!(r.cost, e.cost);
    // In the host's terms: the index in the model as given (before the grid's sort), a
    // capped point none; each distance is that model point's.
    let near = client.nearest_model(10, 320, &pose).unwrap();
    assert_eq!(near.len(), 320);
    let mut found = 0;
    for (k, (n, &(i, d))) in near.iter().zip(&e.nearest).enumerate() {
        let q = pficp_fpga::common::format::transform(&pose, scan[10 + k]);
        match *n {
            None => assert_eq!(d, CAP_D2),
            Some((j, d2)) => {
                found += 1;
                assert_eq!((j, d2), (g.order[i as usize] as usize, d));
                assert_eq!(pficp_fpga::common::format::dist2(q, model[j]), d);
            }
        }
    }
    // Both kinds: 400 points in the cube are sparser than the cap (h = 1/8).
    assert!(found > 50 && found < 320, "{found} of 320 within the cap");
    // Past the scan in use: the board's own error, named.
    match client.nearest(300, 100, &pose) {
        Err(BoardError::Board { command: Command::Nearest, code: ErrorCode::OverCapacity }) => {}
        other => panic!("{other:?}"),
    }
}

#[test]
fn board_errors_are_typed() {
    let mut board = PtyBoard::reference();
    let mut client = board.client();
    // Nothing loaded, no sizes: Evaluate is over capacity.
    let e = client.evaluate(true, false, WeightScale::default(), &poses(1, 1)).unwrap_err();
    assert!(matches!(e, BoardError::Board { command: Command::Evaluate, code: ErrorCode::OverCapacity }), "{e:?}");
    assert!(e.to_string().contains("OverCapacity"), "{e}");
    // Host-side limits never reach the wire.
    assert!(matches!(client.load_model(&cloud(4097, 1), |_, _| {}), Err(BoardError::Limit(_))));
    assert!(matches!(client.costs(&poses(257, 1)), Err(BoardError::Limit(_))));
}

/// Flip one bit of the byte before the delimiter of the `which`-th reply (0-based).
fn corrupt_replies(which: impl Fn(usize) -> bool + Send + 'static) -> PtyBoard {
    let mut reference = reference_handler();
    let mut replies = 0;
    PtyBoard::serve(Box::new(move |bytes| {
        let mut out = Vec::new();
        for &b in bytes {
            let mut r = reference(&[b])?;
            if !r.is_empty() {
                if which(replies) {
                    let k = r.len() - 2;
                    r[k] ^= if r[k] == 1 { 2 } else { 1 };
                }
                replies += 1;
            }
            out.extend(r);
        }
        Some(out)
    }))
}

#[test]
fn a_corrupted_reply_is_resent() {
    let mut board = corrupt_replies(|k| k == 0);
    let mut client = board.client();
    let id = client.identify().unwrap();
    assert_eq!(id.version, pficp_fpga::protocol::VERSION);
    assert_eq!(client.stats().resends, 1);
}

#[test]
fn a_corrupted_request_is_resent() {
    // The board sees a bad CRC and answers with a frame error (sequence 0): the client resends.
    let mut reference = reference_handler();
    let mut corrupted = false;
    let mut board = PtyBoard::serve(Box::new(move |bytes| {
        let mut b = bytes.to_vec();
        if !corrupted {
            if let Some(i) = b.iter().rposition(|&x| x > 2) {
                b[i] ^= 1;
                corrupted = true;
            }
        }
        reference(&b)
    }));
    let mut client = board.client();
    client.identify().unwrap();
    assert_eq!(client.stats().resends, 1);
}

#[test]
fn a_lost_evaluate_reply_starts_the_iteration_over() {
    let (model, scan) = (cloud(200, 7), cloud(100, 8));
    // Replies: 0 identify, 1-2 model (170 + 30 points), 3-4 their normals, 5-13 cell table
    // (9 frames of up to 510 entries), 14 scan, 15 sizes, 16 first batch (FIRST), 17 second
    // batch (no FIRST: lost once, not repeatable), 18.. the batches again.
    let mut board = corrupt_replies(|k| k == 17);
    let mut client = board.client();
    upload(&mut client, &model, &scan);
    let ps = poses(45, 9);
    let scale = WeightScale::for_two_q(1e6);
    let (costs, summary) = client.costs_and_weights(&ps, |_| scale).unwrap();
    let (g, n) = (grid(&model), normals(&model));
    let expected: Vec<u64> = ps.iter().map(|p| scored(&g, &n, &scan, p).cost).collect();
    assert_eq!(costs, expected, "no costs stored twice");
    assert_eq!(summary.weights, weights(&expected, &scale));
    assert_eq!(client.stats().restarts, 1);
}

#[test]
fn a_board_that_always_garbles_is_an_error_after_the_retries() {
    let mut board = corrupt_replies(|_| true);
    let mut client = board.client();
    match client.identify() {
        Err(BoardError::Retries { command: Command::Identify, attempts, .. }) => assert_eq!(attempts, MAX_RETRIES + 1),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_silent_board_is_an_error_within_the_timeout() {
    let mut board = PtyBoard::serve(Box::new(|_| Some(Vec::new())));
    let mut client = board.client();
    client.set_timeout(Duration::from_millis(300));
    let start = Instant::now();
    let e = client.identify().unwrap_err();
    let took = start.elapsed();
    assert!(matches!(e, BoardError::Timeout { command: Command::Identify, .. }), "{e:?}");
    assert!(e.to_string().contains(&board.path), "{e}");
    assert!(took >= Duration::from_millis(300), "{took:?}");
    assert!(took < Duration::from_secs(5), "{took:?}");
}

#[test]
fn a_board_that_goes_away_mid_transfer_is_a_clear_error() {
    let mut reference = reference_handler();
    let mut replies = 0;
    // Answers identify and two load frames, then closes its end of the line.
    let mut board = PtyBoard::serve(Box::new(move |bytes| {
        let out = reference(bytes)?;
        replies += out.iter().filter(|&&b| b == 0).count();
        (replies <= 3).then_some(out)
    }));
    let mut client = board.client();
    client.identify().unwrap();
    let start = Instant::now();
    let e = client.load_model(&cloud(2000, 1), |_, _| {}).unwrap_err();
    assert!(matches!(e, BoardError::Io { .. }), "{e:?}");
    assert!(e.to_string().contains(&board.path), "{e}");
    assert!(start.elapsed() < Duration::from_secs(5));
}

#[test]
fn a_missing_port_is_named() {
    let e = BoardClient::open("/dev/does-not-exist-pficp", DEFAULT_BAUD, Duration::from_secs(1)).unwrap_err();
    assert!(matches!(e, BoardError::Open { .. }), "{e:?}");
    assert!(e.to_string().contains("/dev/does-not-exist-pficp"), "{e}");
    let e = BoardClient::open("/dev/null", DEFAULT_BAUD, Duration::from_secs(1)).unwrap_err();
    assert!(e.to_string().contains("/dev/null"), "{e}");
}

/// The line model the rate tests rely on: a UART reads a line at its own rate, within a few
/// per cent, and not at another common rate.
#[test]
fn the_line_model_reads_only_at_the_right_rate() {
    let bytes: Vec<u8> = (0..=255).collect();
    assert_eq!(uart_resample(&bytes, 921_600, 921_600), bytes);
    assert_eq!(uart_resample(&bytes, 3_000_000, 3_060_000), bytes);
    assert_eq!(uart_resample(&bytes, 3_000_000, 2_940_000), bytes);
    for (from, to) in [(3_000_000, 921_600), (921_600, 3_000_000), (921_600, 115_200), (115_200, 3_000_000)] {
        let got = uart_resample(&bytes, from, to);
        assert!(got.len() < 200 || got.iter().zip(&bytes).filter(|(a, b)| a == b).count() < 50, "{from} -> {to}");
    }
}

/// Without a rate the client opens the port at each rate of PROBE_BAUDS in turn and uses the
/// one Identify answers at; the board's line keeps the rate (`reference_at_rate`), so a
/// wrong rate really gets no valid reply.
#[test]
fn without_a_baud_rate_the_client_uses_the_rate_the_board_answers_at() {
    assert_eq!(PROBE_BAUDS, [BoardConfig::default().baud, 921_600, 115_200]);
    let timeout = Duration::from_millis(300);
    for baud in PROBE_BAUDS {
        let board = PtyBoard::reference_at_rate(BoardConfig { baud, ..BoardConfig::default() });
        let start = Instant::now();
        let (mut client, id) = BoardClient::connect(&board.path, None, timeout).unwrap();
        let took = start.elapsed();
        assert_eq!((client.baud(), id.baud), (baud, baud));
        // The rates before it were tried first (each a timeout or failed attempts long).
        let before = PROBE_BAUDS.iter().position(|&b| b == baud).unwrap() as u32;
        assert!(took >= timeout * before, "{baud} baud found after {took:?}");
        // The client works at that rate.
        client.load_model(&cloud(300, 1), |_, _| {}).unwrap();
    }
    // With a rate, that rate only.
    let board = PtyBoard::reference_at_rate(BoardConfig { baud: 921_600, ..BoardConfig::default() });
    let e = BoardClient::connect(&board.path, Some(DEFAULT_BAUD), timeout).unwrap_err();
    assert!(matches!(e, BoardError::Timeout { .. } | BoardError::Retries { .. }), "{e:?}");
    let (client, _) = BoardClient::connect(&board.path, Some(921_600), timeout).unwrap();
    assert_eq!(client.baud(), 921_600);
}

#[test]
fn a_board_at_no_probed_rate_is_an_error_naming_the_rates_tried() {
    let board = PtyBoard::reference_at_rate(BoardConfig { baud: 57_600, ..BoardConfig::default() });
    let e = BoardClient::connect(&board.path, None, Duration::from_millis(300)).unwrap_err();
    assert!(matches!(e, BoardError::NoAnswer { .. }), "{e:?}");
    let text = e.to_string();
    assert!(!text.contains('\n') && text.contains(&board.path), "{text}");
    let at = |b: &str| text.find(b).unwrap_or_else(|| panic!("{b} not in {text}"));
    assert!(at("3000000 (") < at("921600 (") && at("921600 (") < at("115200 ("), "{text}");
    // A silent line: the same, each rate a timeout.
    let board = PtyBoard::serve(Box::new(|_| Some(Vec::new())));
    let e = BoardClient::connect(&board.path, None, Duration::from_millis(200)).unwrap_err();
    assert!(e.to_string().contains("115200 (no reply within"), "{e}");
}

/// A line that ignores the rate (a pseudo-terminal) to a board generated for another: the
/// probe's first rate answers, but the board says it runs at its own; refused.
#[test]
fn a_board_that_reports_another_rate_than_it_answered_at_is_refused() {
    let board = PtyBoard::reference_of(BoardConfig { baud: 2_000_000, ..BoardConfig::default() });
    let e = BoardClient::connect(&board.path, None, Duration::from_secs(1)).unwrap_err();
    assert!(matches!(e, BoardError::BaudMismatch { opened: DEFAULT_BAUD, reported: 2_000_000, .. }), "{e:?}");
    assert!(e.to_string().contains("--baud 2000000"), "{e}");
    // Given its rate, it is used.
    let (_, id) = BoardClient::connect(&board.path, Some(2_000_000), Duration::from_secs(1)).unwrap();
    assert_eq!(id.baud, 2_000_000);
}

#[test]
fn open_by_path_and_identify() {
    let board = PtyBoard::reference();
    let mut client = BoardClient::open(&board.path, DEFAULT_BAUD, Duration::from_secs(2)).unwrap();
    assert_eq!(client.identify().unwrap().lanes, BoardConfig::default().lanes as u8);
}

#[test]
fn pf_icp_with_the_board_weights_registers_a_reduced_model_1() {
    // An independent, noisy scan (so the filter really iterates), 400 + 300 points.
    let id = ModelId::Model1;
    let truth = id.table1_truth();
    let diag = bbox_diagonal(&id.model_points(400));
    let spec = ScanSpec { sampling: Sampling::Independent { points: 300 }, noise: 0.005 * diag, seed: 3 };
    let ds = make(id, 400, &truth, &spec);
    let nn = NearestNeighbours::new(&ds.model);
    let settings = PfIcpSettings { clusters: 25, particles: 40, iterations: 30, seed: 3, ..Default::default() };
    let mut board = PtyBoard::reference();
    let mut client = board.client();
    let mut uploads = Vec::new();
    let start = Instant::now();
    let r = host_driven::register(&mut client, &nn, &ds.scan, &settings, &mut |u, done, total| {
        uploads.push((u, done, total))
    })
    .unwrap();
    let took = start.elapsed();
    let pose = &r.pf.registration.pose;
    let e = PoseError::between(pose, &truth, diag);
    eprintln!("board PF-ICP: {e:?}, {} iterations, {took:?}, {:?}", r.board.iterations, r.board.stats);
    assert!(Tolerance::SUCCESS.accepts(pose, &truth, diag), "{e:?}");
    assert_eq!((r.board.model_points, r.board.model_subsampled, r.board.scan_points), (400, false, 300));
    assert_eq!(r.board.iterations, r.pf.registration.iterations);
    assert!(r.board.iterations > 5, "the filter iterated on the board's weights");
    assert_eq!(r.board.stats.resends, 0);
    assert_eq!(uploads.last(), Some(&(Upload::Scan, 300, 300)));
    let model_bytes = 2 * 400 * 6 + 4097 * 2;
    assert!(uploads.contains(&(Upload::Model, model_bytes, model_bytes)));
}

#[test]
fn a_model_too_big_for_the_board_is_subsampled_with_the_seed() {
    let model: Vec<_> = (0..5000).map(|i| nalgebra::Point3::new(i as f64, (i * i % 7) as f64, 0.5)).collect();
    let a = pficp::board::quantise::board_model(&model, 4096, 1);
    assert_eq!(a.len(), 4096);
    assert_eq!(a, pficp::board::quantise::board_model(&model, 4096, 1), "same seed, same points");
    assert_ne!(a, pficp::board::quantise::board_model(&model, 4096, 2));
    assert!(a.windows(2).all(|w| w[0].x < w[1].x), "original order kept");
    assert_eq!(pficp::board::quantise::board_model(&model[..100], 4096, 1), model[..100].to_vec());
}

// ---------------------------------------------------------------------------------------
// The on-board filter: Run, Status, Result.
// ---------------------------------------------------------------------------------------

/// A board whose weights are all 0 (their sum 0, so the sum check alone passes) is an error,
/// not NaN weights later.
#[test]
fn all_zero_weights_are_an_error() {
    use pficp_fpga::protocol::messages::{EvaluateReply, FLAG_LAST};
    let (model, scan) = (cloud(300, 71), cloud(100, 72));
    let mut board = PtyBoard::serve(support::intercepting_handler(|f, b| {
        if f.code != Command::Evaluate as u8 || f.data.first().is_none_or(|&x| x & FLAG_LAST == 0) {
            return None;
        }
        let reply = b.execute(f);
        let mut r = EvaluateReply::decode(&reply.data, f.data[5] as usize, true).ok()?;
        let s = r.summary.as_mut()?;
        s.weights.iter_mut().for_each(|w| *w = 0);
        s.w_sum = 0;
        Some(Frame { code: reply.code, seq: f.seq, data: r.encode() }.encode())
    }));
    let mut client = board.client();
    upload(&mut client, &model, &scan);
    let e = client.costs_and_weights(&poses(10, 73), |_| WeightScale::for_two_q(1e6)).unwrap_err();
    assert!(matches!(&e, BoardError::Filter(m) if m.contains("all 0")), "{e:?}");
}
