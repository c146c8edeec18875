//! Fuzzing the host's two doors to the outside: the point-cloud readers (proptest: valid
//! files of every format, PCD's binary_compressed and the PCD fixtures of independent
//! writers among them, then bytes flipped, set, inserted or cut, and pure noise) and
//! the board client's reply handling (seeded: the reference board on a real
//! pseudo-terminal whose replies are corrupted, cut, renumbered, readdressed, replaced,
//! echoed, doubled, preceded by noise or withheld, while the client makes random requests).
//! A seeded share runs in every `cargo test`; the full counts (10^5 each, and 10^5 of PCD
//! files only) with
//!
//! ```sh
//! cargo test --release -p pficp-host --test fuzz -- --ignored --nocapture
//! ```

mod support;

use nalgebra::Point3;
use pficp::board::BoardError;
use pficp::io::{read_points, write_points_to_bytes, Format, ParseError};
use pficp_fpga::common::format::{point, FxPoint, FxPose, WeightScale};
use pficp_fpga::filter::pf::{PfConfig, PARAMS, SCALE_FRAC};
use pficp_fpga::polish::ScaleStep;
use pficp_fpga::protocol::run_request::{PolishRequest, RunRequest};
use pficp_fpga::protocol::Frame;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

const FORMATS: [Format; 6] =
    [Format::PlyAscii, Format::PlyBinary, Format::Xyz, Format::Csv, Format::PcdAscii, Format::PcdBinary];
/// The point limit the readers get here (some generated files exceed it).
const LIMIT: usize = 40;
/// What a fuzz case starts from: a file of each of `FORMATS`, a binary_compressed PCD
/// made here, or one of the PCD fixtures of the independent writers.
const KINDS: usize = FORMATS.len() + 2;
/// The kinds that are PCD files.
const PCD_KINDS: std::ops::Range<usize> = 4..KINDS;
/// The PCD fixtures (`tests/data/pcd/SOURCES.md`): real LZF streams with back references.
const PCD_FIXTURES: [&str; 7] = [
    "open3d_ascii",
    "open3d_binary_normals_rgb",
    "open3d_compressed_normals_rgb",
    "pypcd4_fields_ascii",
    "pypcd4_padding_f8_compressed",
    "pypcd4_organised_nan_binary",
    "pypcd4_organised_nan_compressed",
];
/// The point limit for the fixtures (up to 200 points each).
const FIXTURE_LIMIT: usize = 400;

fn runner(cases: u32, seed: u64) -> TestRunner {
    let mut s = [0u8; 32];
    s[..8].copy_from_slice(&seed.to_le_bytes());
    let config = Config { cases, failure_persistence: None, ..Config::default() };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &s))
}

/// The PCD fixtures' bytes, read once.
fn pcd_fixtures() -> &'static [Vec<u8>] {
    static FILES: std::sync::OnceLock<Vec<Vec<u8>>> = std::sync::OnceLock::new();
    FILES.get_or_init(|| {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pcd");
        PCD_FIXTURES.iter().map(|n| std::fs::read(dir.join(format!("{n}.pcd"))).unwrap()).collect()
    })
}

/// `points` as a binary_compressed PCD: the binary writer's header made `F 8` (the writer
/// writes `F 4`), x y z field-major as doubles in an LZF block of literal runs and, for a
/// byte repeated 4 times or more, a back reference of one byte.
fn pcd_compressed(points: &[Point3<f64>]) -> Vec<u8> {
    let binary = write_points_to_bytes(points, Format::PcdBinary);
    let header_len = binary.len() - 12 * points.len();
    let header = String::from_utf8_lossy(&binary[..header_len])
        .replace("DATA binary\n", "DATA binary_compressed\n")
        .replace("\nSIZE 4 4 4\n", "\nSIZE 8 8 8\n");
    let data: Vec<u8> = (0..3).flat_map(|a| points.iter().flat_map(move |p| p[a].to_le_bytes())).collect();
    let (mut block, mut literal, mut i) = (Vec::new(), Vec::new(), 0);
    let flush = |block: &mut Vec<u8>, literal: &mut Vec<u8>| {
        for run in literal.chunks(32) {
            block.push(run.len() as u8 - 1);
            block.extend_from_slice(run);
        }
        literal.clear();
    };
    while i < data.len() {
        let run = data[i..].iter().take(257).take_while(|&&b| b == data[i]).count();
        literal.push(data[i]);
        if run < 4 {
            i += 1;
            continue;
        }
        flush(&mut block, &mut literal);
        let len = run - 1 - 2; // copies of the byte, less the 2 LZF adds
        if len < 7 {
            block.push((len << 5) as u8);
        } else {
            block.extend_from_slice(&[7 << 5, (len - 7) as u8]);
        }
        block.push(0); // one byte back
        i += run;
    }
    flush(&mut block, &mut literal);
    let mut out = header.into_bytes();
    out.extend_from_slice(&(block.len() as u32).to_le_bytes());
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(&block);
    out
}

/// A file of every format (or of the PCD `kinds` only), mutated: no panic; at most the
/// limit's points; unmutated files read back exactly (or refuse the count); noise never
/// panics either.
fn fuzz_readers(cases: u32, seed: u64, kinds: std::ops::Range<usize>) {
    let coords = proptest::collection::vec(-1e6f64..1e6, 0..3 * (LIMIT + 10));
    let edits = proptest::collection::vec((0u8..4, any::<usize>(), any::<u8>()), 0..6);
    let noise = proptest::collection::vec(any::<u8>(), 0..300);
    runner(cases, seed)
        .run(&(kinds, coords, edits, noise, 0..PCD_FIXTURES.len()), |(kind, coords, edits, noise, fixture)| {
            let points: Vec<Point3<f64>> = coords.chunks_exact(3).map(|c| Point3::new(c[0], c[1], c[2])).collect();
            let (mut bytes, format, limit) = match FORMATS.get(kind) {
                Some(&format) => (write_points_to_bytes(&points, format), format, LIMIT),
                None if kind == FORMATS.len() => (pcd_compressed(&points), Format::PcdBinary, LIMIT),
                None => (pcd_fixtures()[fixture].clone(), Format::PcdBinary, FIXTURE_LIMIT),
            };
            // The PCD writers round to f32 (F 4); the compressed file here holds doubles.
            let written: Vec<Point3<f64>> = match FORMATS.get(kind) {
                Some(Format::PcdAscii | Format::PcdBinary) => {
                    points.iter().map(|p| p.map(|v| v as f32 as f64)).collect()
                }
                _ => points.clone(),
            };
            match read_points(&bytes[..], format, limit) {
                Ok(back) if limit == LIMIT => prop_assert_eq!(&back, &written),
                Ok(back) => prop_assert!(!back.is_empty()),
                Err(e) => prop_assert_eq!(e, ParseError::TooManyPoints { limit }),
            }
            for (kind, at, byte) in edits {
                let i = at % (bytes.len() + 1);
                match kind {
                    0 if i < bytes.len() => bytes[i] ^= 1 << (byte % 8),
                    1 if i < bytes.len() => bytes[i] = byte,
                    2 => bytes.insert(i, byte),
                    _ => bytes.truncate(i),
                }
            }
            for b in [&bytes, &noise] {
                for format in FORMATS {
                    if let Ok(p) = read_points(&b[..], format, limit) {
                        prop_assert!(p.len() <= limit);
                    }
                }
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn readers_survive_mutated_files() {
    fuzz_readers(3_000, 1, 0..KINDS);
}

#[test]
#[ignore = "10^5 cases: run in release with --ignored"]
fn readers_full() {
    let t = Instant::now();
    fuzz_readers(100_000, 2, 0..KINDS);
    eprintln!("readers: 100000 cases (seed 2) in {:.1} s, no panic", t.elapsed().as_secs_f64());
}

#[test]
#[ignore = "10^5 cases: run in release with --ignored"]
fn pcd_reader_full() {
    let t = Instant::now();
    fuzz_readers(100_000, 3, PCD_KINDS);
    eprintln!("PCD reader: 100000 cases (seed 3) in {:.1} s, no panic", t.elapsed().as_secs_f64());
}

/// How the fuzzing board treats one request.
#[derive(Clone, Copy, Debug)]
enum Treat {
    Plain,
    FlipBit,
    Cut,
    RandomData,
    Renumber,
    Readdress,
    Withhold,
    Echo,
    NoiseFirst,
    Double,
}

const TREATS: [(Treat, u32); 10] = [
    (Treat::Plain, 45),
    (Treat::FlipBit, 10),
    (Treat::Cut, 10),
    (Treat::RandomData, 10),
    (Treat::Renumber, 3),
    (Treat::Readdress, 3),
    (Treat::Withhold, 2),
    (Treat::Echo, 2),
    (Treat::NoiseFirst, 8),
    (Treat::Double, 7),
];

fn treat(rng: &mut ChaCha8Rng) -> Treat {
    let mut k = rng.gen_range(0..TREATS.iter().map(|t| t.1).sum::<u32>());
    for (t, w) in TREATS {
        if k < w {
            return t;
        }
        k -= w;
    }
    Treat::Plain
}

/// The reference board, its replies treated at random (seeded).
fn fuzzing_board(seed: u64) -> support::PtyBoard {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    support::PtyBoard::serve(support::intercepting_handler(move |f, b| {
        let reply = b.execute(f);
        let mut wire = reply.encode();
        let n = wire.len();
        Some(match treat(&mut rng) {
            Treat::Plain => wire,
            Treat::FlipBit => {
                let i = rng.gen_range(0..n - 1);
                wire[i] ^= 1 << rng.gen_range(0..8);
                wire
            }
            Treat::Cut => {
                wire.truncate(rng.gen_range(0..n));
                wire.push(0);
                wire
            }
            Treat::RandomData => {
                let len = rng.gen_range(0..reply.data.len() + 4);
                Frame { code: reply.code, seq: reply.seq, data: (0..len).map(|_| rng.gen()).collect() }.encode()
            }
            Treat::Renumber => Frame { seq: reply.seq.wrapping_add(rng.gen_range(1..255)), ..reply }.encode(),
            Treat::Readdress => Frame { code: 0x80 | rng.gen_range(1..10u8), ..reply }.encode(),
            Treat::Withhold => Vec::new(),
            Treat::Echo => f.encode(),
            Treat::NoiseFirst => {
                let mut w: Vec<u8> = (0..rng.gen_range(1..40)).map(|_| rng.gen()).collect();
                w.append(&mut wire);
                w
            }
            Treat::Double => {
                let mut w = wire.clone();
                w.append(&mut wire);
                w
            }
        })
    }))
}

fn cloud(n: usize, rng: &mut ChaCha8Rng) -> Vec<FxPoint> {
    (0..n).map(|_| point([rng.gen_range(-0.9..0.9), rng.gen_range(-0.9..0.9), rng.gen_range(-0.9..0.9)])).collect()
}

fn pose(rng: &mut ChaCha8Rng) -> FxPose {
    let a: f64 = rng.gen_range(-3.0..3.0);
    let t = [rng.gen_range(-0.1..0.1), rng.gen_range(-0.1..0.1), rng.gen_range(-0.1..0.1)];
    FxPose::from_f64(&[a.cos(), -a.sin(), 0.0, a.sin(), a.cos(), 0.0, 0.0, 0.0, 1.0], &t)
}

/// The outcome's name, for the tally.
fn outcome<T>(r: &Result<T, BoardError>) -> &'static str {
    match r {
        Ok(_) => "ok",
        Err(BoardError::Timeout { .. }) => "Timeout",
        Err(BoardError::Unexpected { .. }) => "Unexpected",
        Err(BoardError::Echo { .. }) => "Echo",
        Err(BoardError::Retries { .. }) => "Retries",
        Err(BoardError::ReplyLost { .. }) => "ReplyLost",
        Err(BoardError::Reply { .. }) => "Reply",
        Err(BoardError::Board { .. }) => "Board",
        Err(BoardError::Filter(_)) => "Filter",
        Err(BoardError::Limit(_)) => "Limit",
        Err(BoardError::RunTimeout { .. }) => "RunTimeout",
        Err(BoardError::Io { .. }) => "Io",
        Err(BoardError::Open { .. }) => "Open",
        Err(BoardError::NoAnswer { .. }) => "NoAnswer",
        Err(BoardError::BaudMismatch { .. }) => "BaudMismatch",
    }
}

/// `cases` random requests against the fuzzing board: each returns (a value or a typed
/// error) within its bound; the tally of outcomes and the slowest request.
fn fuzz_client(cases: usize, seed: u64) -> (BTreeMap<&'static str, usize>, Duration) {
    let mut board = fuzzing_board(seed);
    let mut client = board.client();
    let timeout = Duration::from_millis(5);
    client.set_timeout(timeout);
    let mut rng = ChaCha8Rng::seed_from_u64(seed + 1);
    let mut tally = BTreeMap::new();
    let mut slowest = Duration::ZERO;
    for _ in 0..cases {
        let t = Instant::now();
        let name = match rng.gen_range(0..9) {
            0 => outcome(&client.identify()),
            1 => outcome(&client.status()),
            2 => outcome(&client.result()),
            3 => {
                let n = rng.gen_range(1..120);
                outcome(&client.load_model(&cloud(n, &mut rng), |_, _| {}))
            }
            4 => {
                let n = rng.gen_range(1..60);
                outcome(&client.load_scan(&cloud(n, &mut rng), |_, _| {}))
            }
            5 => outcome(&client.set_sizes(rng.gen_range(1..120), rng.gen_range(1..60))),
            6 => {
                let poses: Vec<FxPose> = (0..rng.gen_range(1..12)).map(|_| pose(&mut rng)).collect();
                outcome(&client.evaluate(true, rng.gen(), WeightScale::for_two_q(1e6), &poses))
            }
            7 => {
                let (first, count) = (rng.gen_range(0..40), rng.gen_range(1..30));
                outcome(&client.nearest(first, count, &pose(&mut rng)))
            }
            _ => {
                let cfg = PfConfig {
                    particles: rng.gen_range(1..6),
                    iterations: rng.gen_range(1..3),
                    temper_exp: 12,
                    centre: [0, 0, 0, 1 << SCALE_FRAC, 0, 0, 0],
                    sigma0: [1 << 14; PARAMS],
                    floor: [50; PARAMS],
                    seed: rng.gen(),
                    thr_cost: 0,
                    thr_max: 0,
                };
                let polish = PolishRequest {
                    points: rng.gen_range(1..40),
                    steps: rng.gen_range(0..3),
                    winner_steps: rng.gen_range(0..2),
                    scale: if rng.gen() { ScaleStep::Held } else { ScaleStep::Solved },
                    hypotheses: vec![],
                };
                outcome(&client.run(&RunRequest { filter: cfg, polish }))
            }
        };
        *tally.entry(name).or_insert(0) += 1;
        slowest = slowest.max(t.elapsed());
        // The documented bound: 3 attempts of (timeout + modelled time), and for Run a
        // Status after a lost reply; the modelled time of these small requests is far
        // under a second.
        assert!(t.elapsed() < 4 * timeout + Duration::from_secs(2), "{name} took {:?}", t.elapsed());
    }
    (tally, slowest)
}

#[test]
fn the_client_survives_a_lying_board() {
    let (tally, slowest) = fuzz_client(1_500, 1);
    eprintln!("client fuzz (seed 1): 1500 requests, slowest {slowest:?}: {tally:?}");
    assert!(tally["ok"] > 300, "{tally:?}");
    for kind in ["Retries", "Reply", "Echo"] {
        assert!(tally.get(kind).is_some_and(|&n| n > 0), "no {kind} in {tally:?}");
    }
}

#[test]
#[ignore = "10^5 requests: run in release with --ignored"]
fn the_client_survives_a_lying_board_full() {
    let t = Instant::now();
    let (tally, slowest) = fuzz_client(100_000, 2);
    eprintln!(
        "client fuzz (seed 2): 100000 requests in {:.1} s, slowest {:?}: {tally:?}",
        t.elapsed().as_secs_f64(),
        slowest
    );
}
