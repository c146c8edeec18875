//! The Verilated board top against the byte-level reference, through its serial pins at
//! the UART's bit timing: every byte the board sends must equal the reference's.

use pficp_fpga::board::BoardConfig;
use pficp_fpga::common::format::{FxPoint, FxPose, WeightScale};
use pficp_fpga::protocol::messages::{self, EvaluateRequest, NearestRequest};
use pficp_fpga::protocol::{Command, Frame};
use pficp_sim::serial::SerialBoard;

fn lcg(s: &mut u64) -> u64 {
    *s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    *s >> 33
}

fn cloud(n: usize, s: &mut u64) -> Vec<FxPoint> {
    (0..n).map(|_| [0; 3].map(|_: i16| (lcg(s) % 16001) as i16 - 8000)).collect()
}

fn pose(k: u64) -> FxPose {
    let a = 0.1 * k as f64;
    let (c, s) = (a.cos(), a.sin());
    FxPose::from_f64(&[c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0], &[0.01 * k as f64, -0.02, 0.03])
}

/// Send one request, run to idle, check the board's bytes against the reference.
fn exchange(b: &mut SerialBoard, frame: &Frame) -> Frame {
    let wire = frame.encode();
    let got = b.exchange(&wire, 50_000_000).expect("the board went quiet");
    let (compared, mismatch) = b.comparison();
    assert!(mismatch.is_none(), "after {compared} bytes: {}", mismatch.unwrap());
    assert_eq!(b.expected_pending(), 0, "the board sent less than the reference");
    assert_eq!(*got.last().expect("an answer"), 0, "ends with the delimiter");
    Frame::decode(&got[..got.len() - 1]).expect("a well-formed reply")
}

fn req(cmd: Command, seq: u8, data: Vec<u8>) -> Frame {
    Frame { code: cmd as u8, seq, data }
}

#[test]
fn every_command_matches_the_reference_byte_for_byte() {
    let mut b = SerialBoard::new(BoardConfig::FAST_SIM).with_reference();
    b.run(100);
    let id = exchange(&mut b, &req(Command::Identify, 1, vec![]));
    let ident = messages::Identity::decode(&id.data).unwrap();
    assert_eq!((ident.lanes, ident.baud), (4, 25_000_000));
    let mut s = 7;
    let model = cloud(300, &mut s);
    let scan = cloud(45, &mut s);
    let mut seq = 2u8;
    // The model sorted by cell, its normals as the host computes them, its table (LoadModel,
    // LoadTable), then the scan.
    let grid = pficp_fpga::search::grid::Grid::build(&model).unwrap();
    let normals = pficp::board::quantise::stored_normals(&grid);
    let scan_loads = scan.chunks(messages::MAX_LOAD_POINTS).enumerate();
    let loads = messages::grid_upload(&grid, &normals).into_iter().chain(
        scan_loads.map(|(k, c)| (Command::LoadScan, messages::load_request((k * messages::MAX_LOAD_POINTS) as u16, c))),
    );
    for (cmd, data) in loads {
        let r = exchange(&mut b, &req(cmd, seq, data));
        assert_eq!(r.code, cmd as u8 | 0x80);
        seq = seq.wrapping_add(1);
    }
    // The model digest after the upload (the RTL's CRC-32 against the reference's).
    let id = messages::Identity::decode(&exchange(&mut b, &req(Command::Identify, seq, vec![])).data).unwrap();
    assert_eq!(id.model_digest, messages::grid_digest(&grid, &normals));
    exchange(&mut b, &req(Command::SetSizes, seq, messages::two_u16(300, 45)));
    let scale = WeightScale::for_two_q(1.0e6);
    let first = EvaluateRequest { first: true, last: false, scale, poses: (0..5).map(pose).collect() };
    let r = exchange(&mut b, &req(Command::Evaluate, 20, first.encode()));
    assert_eq!(r.data.len(), 30);
    let last = EvaluateRequest { first: false, last: true, scale, poses: (5..8).map(pose).collect() };
    let r = exchange(&mut b, &req(Command::Evaluate, 21, last.encode()));
    let reply = messages::EvaluateReply::decode(&r.data, 3, true).unwrap();
    assert_eq!(reply.summary.unwrap().weights.len(), 8);
    let weigh = EvaluateRequest { first: false, last: true, scale: WeightScale::for_two_q(1.0e8), poses: vec![] };
    exchange(&mut b, &req(Command::Evaluate, 22, weigh.encode()));
    let near = NearestRequest { first: 3, count: 40, pose: pose(2) };
    let r = exchange(&mut b, &req(Command::Nearest, 23, near.encode()));
    let results = messages::NearestReply::decode(&r.data, &near).unwrap().results;
    assert_eq!(results.len(), 40);
    // The search ran: some points found a model point within the cap, some did not.
    let capped = results.iter().filter(|r| r.1 == pficp_fpga::search::grid::CAP_D2).count();
    assert!((1..40).contains(&capped), "{capped} of 40 capped");
    eprintln!("{} bytes compared in {} clocks", b.comparison().0, b.clocks());
}

/// The generated board (8 lanes, 50 MHz, 3 Mbaud: 16 2/3 clocks a bit, the UART's timing
/// fractional) with the host at the exact nominal timing (`SerialBoard` keeps rational time:
/// back-to-back bytes start at every phase of the clock): long frames each way, byte for
/// byte as the reference, the LEDs by their rule.
#[test]
fn the_generated_board_at_16_2_3_clocks_a_bit_matches_the_reference() {
    let config = BoardConfig::default();
    assert_eq!(config.bit_period().to_string(), "16 2/3");
    let mut b = SerialBoard::new(config).with_reference();
    b.run(100);
    let id = exchange(&mut b, &req(Command::Identify, 1, vec![]));
    let ident = messages::Identity::decode(&id.data).unwrap();
    assert_eq!((ident.lanes, ident.baud, ident.clock_hz), (8, pficp_fpga::board::DEFAULT_BAUD, 50_000_000));
    let mut s = 11;
    let model = cloud(340, &mut s);
    let scan = cloud(200, &mut s);
    let mut seq = 2u8;
    for (cmd, pts) in [(Command::LoadModel, &model), (Command::LoadScan, &scan)] {
        for (k, chunk) in pts.chunks(messages::MAX_LOAD_POINTS).enumerate() {
            let r = exchange(&mut b, &req(cmd, seq, messages::load_request((k * 170) as u16, chunk)));
            assert_eq!(r.code, cmd as u8 | 0x80);
            seq += 1;
        }
    }
    exchange(&mut b, &req(Command::SetSizes, seq, messages::two_u16(340, 200)));
    // The longest reply: 144 results of 7 bytes.
    let near = NearestRequest { first: 10, count: 144, pose: pose(3) };
    let r = exchange(&mut b, &req(Command::Nearest, seq + 1, near.encode()));
    assert_eq!(messages::NearestReply::decode(&r.data, &near).unwrap().results.len(), 144);
    let (sent, received) = b.byte_counts();
    assert!(sent > 3_000 && received > 1_000, "{sent} bytes in, {received} out");
    eprintln!("{} bytes compared in {} clocks", b.comparison().0, b.clocks());
}
