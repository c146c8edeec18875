//! What the byte-level reference board's tests share: request builders, the snapshot of
//! everything a command may change, the test clouds and their hand-computed costs.
#![allow(dead_code, unused_imports)]

pub use pficp_fpga::board::*;
pub use pficp_fpga::common::format::{pack_point, FxPose};
pub use pficp_fpga::common::format::{unpack_point, FxPoint, WeightScale};
pub use pficp_fpga::filter::pf::{PfConfig, PfOutcome};
pub use pficp_fpga::filter::weights::{WeightInputs, WeightModel};
pub use pficp_fpga::protocol::layout::{point_bytes, pose_bytes};
pub use pficp_fpga::protocol::messages::IDENTITY_BYTES;
pub use pficp_fpga::protocol::messages::{Identity, ResultReply, StatusReply, FLAG_FIRST, FLAG_LAST, MAX_LOAD_POINTS};
pub use pficp_fpga::protocol::run_request::{PolishRequest, RunOutcome, RunRequest};
pub use pficp_fpga::protocol::{cobs_encode, crc16, FrameError, MAX_FRAME};
pub use pficp_fpga::protocol::{ErrorCode, Frame};

pub const IDENTIFY: u8 = 0x01;
pub const LOAD_MODEL: u8 = 0x02;
pub const LOAD_SCAN: u8 = 0x03;
pub const SET_SIZES: u8 = 0x04;
pub const EVALUATE: u8 = 0x05;
pub const NEAREST: u8 = 0x06;
pub const RUN: u8 = 0x07;
pub const STATUS: u8 = 0x08;
pub const RESULT: u8 = 0x09;
pub const LOAD_TABLE: u8 = 0x0a;
/// Q3.15 one (the identity matrix's diagonal).
pub const ONE: i32 = 1 << 15;

pub fn req(code: u8, seq: u8, data: Vec<u8>) -> Frame {
    Frame { code, seq, data }
}

/// Everything a command may change.
#[derive(Debug, PartialEq)]
pub struct Snapshot(pub Vec<u64>, pub Vec<u64>, pub (u16, u16), pub Vec<u64>, pub Option<RunOutcome>);

pub fn snap(b: &BoardModel) -> Snapshot {
    Snapshot(
        b.model_store().to_vec(),
        b.scan_store().to_vec(),
        b.sizes(),
        b.stored_costs().to_vec(),
        b.run_outcome().cloned(),
    )
}

/// Execute `f`, expect a normal reply; its data.
pub fn ok(b: &mut BoardModel, f: Frame) -> Vec<u8> {
    let r = b.execute(&f);
    assert_eq!((r.code, r.seq), (f.code | 0x80, f.seq), "{r:?} for command {:#04x}", f.code);
    r.data
}

/// Execute `f`, expect the error reply `e` and no change.
pub fn rejects(b: &mut BoardModel, f: Frame, e: ErrorCode) {
    let before = snap(b);
    let r = b.execute(&f);
    assert_eq!(r, Frame::error(f.seq, e, f.code), "command {:#04x}, {} data bytes", f.code, f.data.len());
    assert_eq!(r.code, 0xff);
    assert_eq!(r.data, vec![e as u8, f.code]);
    assert!(snap(b) == before, "a rejected command changed the board");
}

pub fn u16s(a: u16, b: u16) -> Vec<u8> {
    vec![a as u8, (a >> 8) as u8, b as u8, (b >> 8) as u8]
}

pub fn load_data(offset: u16, count: u16, points: &[FxPoint]) -> Vec<u8> {
    let mut d = u16s(offset, count);
    for &p in points {
        d.extend_from_slice(&point_bytes(p));
    }
    d
}

pub fn eval_data(flags: u8, pre_shift: u8, q_mul: u32, n: u8, poses: &[FxPose]) -> Vec<u8> {
    let mut d = vec![flags, pre_shift, q_mul as u8, (q_mul >> 8) as u8, (q_mul >> 16) as u8, n];
    for p in poses {
        d.extend_from_slice(&pose_bytes(p));
    }
    d
}

pub fn nearest_data(first: u16, count: u16, pose: &FxPose) -> Vec<u8> {
    let mut d = u16s(first, count);
    d.extend_from_slice(&pose_bytes(pose));
    d
}

pub fn le_at(d: &[u8], at: usize, bytes: usize) -> u64 {
    (0..bytes).map(|k| (d[at + k] as u64) << (8 * k)).sum()
}

/// Identity rotation, translation `t` (Q5.13: the point's own scale), so a scan point
/// `s` goes exactly to `s + t`.
pub fn shift(t: [i32; 3]) -> FxPose {
    FxPose { m: [ONE, 0, 0, 0, ONE, 0, 0, 0, ONE], t }
}

/// The model: a 4 x 4 x 4 grid, 2,000 LSB apart (coordinates -3000, -1000, 1000, 3000),
/// `x` fastest, so already sorted by the search's cells (each point in a cell of its own).
pub fn grid() -> Vec<FxPoint> {
    let g = |v: usize| (-3000 + 2000 * v as i32) as i16;
    (0..64).map(|k| [g(k % 4), g(k / 4 % 4), g(k / 16)]).collect()
}

/// LoadTable requests that write the whole cell `table` (4,097 entries).
pub fn table_requests(table: &[u16]) -> Vec<Frame> {
    use pficp_fpga::protocol::messages::{table_request, MAX_LOAD_ENTRIES};
    table
        .chunks(MAX_LOAD_ENTRIES)
        .enumerate()
        .map(|(k, c)| req(LOAD_TABLE, k as u8, table_request((k * MAX_LOAD_ENTRIES) as u16, c)))
        .collect()
}

/// The tests' normal of stored point `i`: the unit axis `i mod 3` (`x`, `y`, `z` in turn),
/// so that every axis is seen by a third of the points.
pub fn test_normal(i: usize) -> pficp_fpga::surface::FxNormal {
    let mut n = [0; 3];
    n[i % 3] = 1 << pficp_fpga::surface::NORMAL_FRAC;
    n
}

/// The normals [`load_grid`] stores for `n` points.
pub fn test_normals(n: usize) -> Vec<pficp_fpga::surface::FxNormal> {
    (0..n).map(test_normal).collect()
}

/// Load `model` sorted by cell, its normals ([`test_normals`]) and its table, as the host
/// does (`messages::grid_upload`); the grid (its `order` maps stored indices back to
/// `model`'s).
pub fn load_grid(b: &mut BoardModel, model: &[FxPoint]) -> pficp_fpga::search::grid::Grid {
    let g = pficp_fpga::search::grid::Grid::build(model).expect("the test model fits the grid");
    for (k, chunk) in g.points.chunks(MAX_LOAD_POINTS).enumerate() {
        let off = (k * MAX_LOAD_POINTS) as u16;
        ok(b, req(LOAD_MODEL, 1, load_data(off, chunk.len() as u16, chunk)));
    }
    let normals = test_normals(g.points.len());
    for (k, chunk) in normals.chunks(MAX_LOAD_POINTS).enumerate() {
        let off = (pficp_fpga::protocol::messages::NORMALS_OFFSET + k * MAX_LOAD_POINTS) as u16;
        ok(b, req(LOAD_MODEL, 1, load_data(off, chunk.len() as u16, chunk)));
    }
    for f in table_requests(&g.first) {
        ok(b, f);
    }
    g
}

/// Scan point `i` sits at grid point `home(i)` plus `offset(i)` (each axis within 300).
pub fn home(i: usize) -> usize {
    (7 * i + 3) % 64
}
pub fn offset(i: usize) -> [i32; 3] {
    [(i * 37 % 601) as i32 - 300, (i * 53 % 601) as i32 - 300, (i * 71 % 601) as i32 - 300]
}
pub fn scan_cloud(n: usize) -> Vec<FxPoint> {
    let g = grid();
    (0..n).map(|i| std::array::from_fn(|a| (g[home(i)][a] as i32 + offset(i)[a]) as i16)).collect()
}
/// Translation of particle `k` (each axis within 300).
pub fn t_of(k: usize) -> [i32; 3] {
    [(k * 13 % 601) as i32 - 300, (k * 29 % 601) as i32 - 300, (k * 47 % 601) as i32 - 300]
}

/// Squared distance of scan point `i` shifted by `t` to its home, by hand: with every
/// axis off by at most 600 and the grid 2,000 apart, the home is the nearest point (and
/// within a cell on every axis, so the search finds it unless the cap applies).
pub fn hand_dist(i: usize, t: [i32; 3]) -> u64 {
    let d: u64 = (0..3).map(|a| ((offset(i)[a] + t[a]) as i64).pow(2) as u64).sum();
    d.min(pficp_fpga::search::grid::CAP_D2)
}
/// Its surface residual: the normal of the test grid's point `home(i)` is an axis
/// ([`test_normal`]), so it is that axis's offset squared, or the cap.
pub fn hand_resid(i: usize, t: [i32; 3]) -> u64 {
    let k = home(i) % 3;
    if hand_dist(i, t) >= pficp_fpga::search::grid::CAP_D2 {
        pficp_fpga::search::grid::CAP_D2
    } else {
        ((offset(i)[k] + t[k]) as i64).pow(2) as u64
    }
}
pub fn hand_cost(n_scan: usize, t: [i32; 3]) -> u64 {
    (0..n_scan).map(|i| hand_resid(i, t)).sum()
}

/// A board with the grid as model, `n_scan` scan points, sizes set.
pub fn loaded(n_scan: usize) -> BoardModel {
    let mut b = BoardModel::new(BoardConfig::default());
    let g = load_grid(&mut b, &grid());
    assert!(g.order.iter().enumerate().all(|(k, &o)| k == o as usize), "the test grid is stored as it is");
    let scan = scan_cloud(n_scan);
    for (k, chunk) in scan.chunks(MAX_LOAD_POINTS).enumerate() {
        let off = (k * MAX_LOAD_POINTS) as u16;
        ok(&mut b, req(LOAD_SCAN, 2, load_data(off, chunk.len() as u16, chunk)));
    }
    ok(&mut b, req(SET_SIZES, 3, u16s(64, n_scan as u16)));
    b
}

/// The weight stage's cycle-accurate model over `costs`: (weights, w_sum, min_cost).
pub fn weigh_cycles(costs: &[u64], pre_shift: u8, q_mul: u32) -> (Vec<u16>, u32, u64) {
    let mut m = WeightModel::new();
    m.step(&WeightInputs { clear: true, ..Default::default() });
    for &c in costs {
        m.step(&WeightInputs { cost_valid: true, cost: c, ..Default::default() });
    }
    let min = m.outputs().min_cost;
    m.step(&WeightInputs { weigh: true, pre_shift, q_mul, ..Default::default() });
    let mut w = Vec::new();
    for _ in 0..1000 {
        m.step(&WeightInputs::default());
        let o = m.outputs();
        if o.w_valid {
            w.push(o.weight);
        }
        if o.w_done {
            return (w, o.w_sum, min);
        }
    }
    panic!("the weight stage never finished");
}

/// Parse an Evaluate reply by hand: (costs, Some((stored, min, w_sum, weights))).
#[allow(clippy::type_complexity)]
pub fn parse_eval(d: &[u8], n: usize, last: bool) -> (Vec<u64>, Option<(usize, u64, u32, Vec<u16>)>) {
    let costs = (0..n).map(|k| le_at(d, 6 * k, 6)).collect();
    if !last {
        assert_eq!(d.len(), 6 * n);
        return (costs, None);
    }
    let at = 6 * n;
    let stored = le_at(d, at, 2) as usize;
    assert_eq!(d.len(), at + 2 + 6 + 3 + 2 * stored);
    let w = (0..stored).map(|k| le_at(d, at + 11 + 2 * k, 2) as u16).collect();
    (costs, Some((stored, le_at(d, at + 2, 6), le_at(d, at + 8, 3) as u32, w)))
}

/// Bytes on the wire for a body given as is (its CRC computed).
pub fn wire(body: &[u8]) -> Vec<u8> {
    let crc = crc16(body);
    let mut w = cobs_encode(&[body, &crc.to_le_bytes()].concat());
    w.push(0);
    w
}

pub fn identify_reply(b: &BoardModel, seq: u8) -> Vec<u8> {
    let (m, s) = b.sizes();
    let c = b.config();
    let id = Identity::of_board(c.lanes as u8, c.clock_hz, c.baud, m, s, b.stored_costs().len() as u16);
    Frame { code: 0x81, seq, data: id.with_digest(b.model_digest()).encode() }.encode()
}
