//! The data layouts of the protocol's commands and replies (docs/protocol.md), shared by
//! the host's board client and the board reference. Everything is little-endian; points
//! are 6 bytes, poses 27 (the 216-bit word of [`FxPose::pack`]).

use crate::common::format::{FxPoint, FxPose, WeightScale, MAX_POINTS};
use crate::filter::pf::{Particle, PARAMS};
use crate::filter::weights::MAX_PARTICLES;
use crate::protocol::layout::{point_bytes, pose_bytes, pose_from_bytes, POINT_BYTES, POSE_BYTES};
use crate::protocol::VERSION;

/// Most points in one LoadModel / LoadScan frame.
pub const MAX_LOAD_POINTS: usize = 170;
/// Bytes of a cell-table entry on the wire (13 bits used).
pub const TABLE_ENTRY_BYTES: usize = 2;
/// Most entries in one LoadTable frame (as long as a full LoadModel frame).
pub const MAX_LOAD_ENTRIES: usize = MAX_LOAD_POINTS * POINT_BYTES / TABLE_ENTRY_BYTES;
/// Entries of the cell table: one a cell, and the point count.
pub const TABLE_ENTRIES: usize = crate::search::grid::CELLS + 1;
/// Mask of a stored table entry.
pub const TABLE_ENTRY_MASK: u16 = (1 << 13) - 1;
/// Most poses in one Evaluate frame.
pub const MAX_POSES: usize = 37;
/// Most results in one Nearest frame.
pub const MAX_NEAREST: usize = 144;
/// Data bytes of the Identify reply.
pub const IDENTITY_BYTES: usize = 30;
/// Bytes of the model digest (the Identify reply's last field).
pub const DIGEST_BYTES: usize = 4;
/// Evaluate flag: forget the stored costs first.
pub const FLAG_FIRST: u8 = 1;
/// Evaluate flag: weigh every stored cost afterwards.
pub const FLAG_LAST: u8 = 2;
/// Data bytes of the Run reply: the request's particles and iterations echoed.
pub const RUN_REPLY_BYTES: usize = 4;
/// Data bytes of the Status reply: state, iterations, best cost.
pub const STATUS_BYTES: usize = 1 + 2 + COST_BYTES;
/// Bytes of a cost (48 bits) on the wire.
pub const COST_BYTES: usize = 6;
/// Bytes of a squared distance (34 bits) on the wire.
pub const DIST_BYTES: usize = 5;
/// Bytes of a weight on the wire.
pub const WEIGHT_BYTES: usize = 2;
/// Bytes of an Evaluate reply's weight summary before its weights: count, min_cost, w_sum.
pub const WEIGHT_SUMMARY_BYTES: usize = 2 + COST_BYTES + 3;
/// Bytes of a Nearest reply before its results: first, count, cost.
pub const NEAREST_HEAD_BYTES: usize = TWO_U16_BYTES + COST_BYTES;
/// Bytes of one Nearest result: the model index, the squared distance.
pub const NEAREST_RESULT_BYTES: usize = 2 + DIST_BYTES;
/// Bytes of the Result reply before its parameters: iterations, cost, max_d2.
pub const RESULT_HEAD_BYTES: usize = 2 + COST_BYTES + DIST_BYTES;
/// Bytes of the Result reply's parameters (24 bits each).
pub const RESULT_PARAMS_BYTES: usize = 3 * PARAMS;
/// Bytes of the Result reply's filter part: head, parameters, the filter's pose.
pub const RESULT_FILTER_BYTES: usize = RESULT_HEAD_BYTES + RESULT_PARAMS_BYTES + POSE_BYTES;
/// Bytes of the Result reply's polish head: the winning start, its cost.
pub const RESULT_POLISH_HEAD_BYTES: usize = 1 + COST_BYTES;
/// Data bytes of the Result reply: the filter's part, the polish's head, the polished pose.
pub const RESULT_BYTES: usize = RESULT_FILTER_BYTES + RESULT_POLISH_HEAD_BYTES + POSE_BYTES;
/// Mask of the 24-bit `w_sum` field (the weight stage's accumulator).
pub const W_SUM_MASK: u32 = (1 << 24) - 1;
/// Data bytes of a Nearest request: first, count, pose.
pub const NEAREST_REQUEST_BYTES: usize = 4 + POSE_BYTES;
/// Data bytes of an Evaluate request before its poses: flags, pre_shift, q_mul, n.
pub const EVALUATE_HEADER_BYTES: usize = 6;
/// Data bytes of a load request before its points: offset, count.
pub const LOAD_HEADER_BYTES: usize = 4;
/// The best cost a Status reports before any run: `2^48 - 1`.
pub const NO_COST: u64 = crate::common::format::COST_MASK;
/// Mask of a best point distance in the Result reply (34 bits).
pub const MAX_D2_MASK: u64 = (1 << 34) - 1;

/// Why a reply's data does not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MessageError {
    /// The data is not as long as the layout says.
    #[error("reply data is {got} bytes, expected {expected}")]
    Length {
        /// Bytes received.
        got: usize,
        /// Bytes the layout needs.
        expected: usize,
    },
    /// A field does not hold what the request asked for.
    #[error("reply field {field} is {got}, expected {expected}")]
    Field {
        /// Which field.
        field: &'static str,
        /// Its value.
        got: u64,
        /// What was asked for.
        expected: u64,
    },
}

fn need(data: &[u8], expected: usize) -> Result<(), MessageError> {
    if data.len() == expected {
        Ok(())
    } else {
        Err(MessageError::Length { got: data.len(), expected })
    }
}

fn le(data: &[u8]) -> u64 {
    data.iter().rev().fold(0u64, |v, &b| (v << 8) | b as u64)
}

fn put(out: &mut Vec<u8>, v: u64, bytes: usize) {
    out.extend((0..bytes).map(|k| (v >> (8 * k)) as u8));
}

/// The Identify reply: version, limits, clock, baud and the current sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Identity {
    /// Protocol version.
    pub version: u16,
    /// Pipeline lanes.
    pub lanes: u8,
    /// Largest model.
    pub max_model: u16,
    /// Largest scan.
    pub max_scan: u16,
    /// Most stored particle costs.
    pub max_particles: u16,
    /// Most poses per Evaluate frame.
    pub max_poses: u8,
    /// Most points per load frame.
    pub max_load: u8,
    /// Most results per Nearest frame.
    pub max_nearest: u8,
    /// Design clock in Hz.
    pub clock_hz: u32,
    /// Nominal UART baud rate.
    pub baud: u32,
    /// Model points in use.
    pub model_count: u16,
    /// Scan points in use.
    pub scan_count: u16,
    /// Particle costs stored.
    pub stored: u16,
    /// The model digest: [`crate::protocol::digest_update`] over every LoadModel and
    /// LoadTable request's data since the last LoadModel at offset 0 (docs/protocol.md,
    /// "Resident model"); [`crate::protocol::DIGEST_NONE`] after power-up.
    pub model_digest: u32,
}

impl Identity {
    /// The identity of a board with `lanes` lanes at `clock_hz` and `baud`, sizes given.
    pub fn of_board(lanes: u8, clock_hz: u32, baud: u32, model_count: u16, scan_count: u16, stored: u16) -> Self {
        Identity {
            version: VERSION,
            lanes,
            max_model: MAX_POINTS as u16,
            max_scan: MAX_POINTS as u16,
            max_particles: MAX_PARTICLES as u16,
            max_poses: MAX_POSES as u8,
            max_load: MAX_LOAD_POINTS as u8,
            max_nearest: MAX_NEAREST as u8,
            clock_hz,
            baud,
            model_count,
            scan_count,
            stored,
            model_digest: crate::protocol::DIGEST_NONE,
        }
    }

    /// The same with the model digest `d`.
    pub fn with_digest(self, d: u32) -> Self {
        Identity { model_digest: d, ..self }
    }

    /// The reply data.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(IDENTITY_BYTES);
        put(&mut out, self.version as u64, 2);
        put(&mut out, self.lanes as u64, 1);
        put(&mut out, self.max_model as u64, 2);
        put(&mut out, self.max_scan as u64, 2);
        put(&mut out, self.max_particles as u64, 2);
        put(&mut out, self.max_poses as u64, 1);
        put(&mut out, self.max_load as u64, 1);
        put(&mut out, self.max_nearest as u64, 1);
        put(&mut out, self.clock_hz as u64, 4);
        put(&mut out, self.baud as u64, 4);
        put(&mut out, self.model_count as u64, 2);
        put(&mut out, self.scan_count as u64, 2);
        put(&mut out, self.stored as u64, 2);
        put(&mut out, self.model_digest as u64, DIGEST_BYTES);
        out
    }

    /// Parse the reply data.
    pub fn decode(d: &[u8]) -> Result<Self, MessageError> {
        // Boards before protocol 3 send no digest (26 bytes): it reads as `DIGEST_NONE`.
        let old = d.len() == IDENTITY_BYTES - DIGEST_BYTES && d.len() >= 2 && le(&d[0..2]) < 3;
        if !old {
            need(d, IDENTITY_BYTES)?;
        }
        Ok(Identity {
            version: le(&d[0..2]) as u16,
            lanes: d[2],
            max_model: le(&d[3..5]) as u16,
            max_scan: le(&d[5..7]) as u16,
            max_particles: le(&d[7..9]) as u16,
            max_poses: d[9],
            max_load: d[10],
            max_nearest: d[11],
            clock_hz: le(&d[12..16]) as u32,
            baud: le(&d[16..20]) as u32,
            model_count: le(&d[20..22]) as u16,
            scan_count: le(&d[22..24]) as u16,
            stored: le(&d[24..26]) as u16,
            model_digest: if old { crate::protocol::DIGEST_NONE } else { le(&d[26..30]) as u32 },
        })
    }
}

/// LoadModel / LoadScan request data: offset, count, points.
pub fn load_request(offset: u16, points: &[FxPoint]) -> Vec<u8> {
    let mut out = Vec::with_capacity(4 + POINT_BYTES * points.len());
    put(&mut out, offset as u64, 2);
    put(&mut out, points.len() as u64, 2);
    for &p in points {
        out.extend_from_slice(&point_bytes(p));
    }
    out
}

/// LoadTable request data: offset, count, entries.
pub fn table_request(offset: u16, entries: &[u16]) -> Vec<u8> {
    let mut out = Vec::with_capacity(LOAD_HEADER_BYTES + TABLE_ENTRY_BYTES * entries.len());
    put(&mut out, offset as u64, 2);
    put(&mut out, entries.len() as u64, 2);
    for &e in entries {
        put(&mut out, e as u64, TABLE_ENTRY_BYTES);
    }
    out
}

/// LoadModel's word offset of the normal store: words `0..MAX_POINTS` are the model points,
/// `NORMALS_OFFSET + i` the normal of stored point `i` (`crate::surface::FxNormal`, packed
/// as a point).
pub const NORMALS_OFFSET: usize = MAX_POINTS;
/// LoadModel's words: the points, then their normals.
pub const MODEL_WORDS: usize = 2 * MAX_POINTS;

/// The requests (command, data) that upload a gridded model: LoadModel frames of its
/// points as stored (sorted by cell), LoadModel frames of their normals (`normals[i]` the
/// normal of stored point `i`, from word [`NORMALS_OFFSET`]), then LoadTable frames of its
/// whole cell table.
pub fn grid_upload(
    grid: &crate::search::grid::Grid,
    normals: &[crate::surface::FxNormal],
) -> Vec<(crate::protocol::Command, Vec<u8>)> {
    use crate::protocol::Command;
    assert_eq!(normals.len(), grid.points.len(), "one normal per stored model point");
    let points = grid.points.chunks(MAX_LOAD_POINTS).enumerate();
    let normals = normals.chunks(MAX_LOAD_POINTS).enumerate();
    let entries = grid.first.chunks(MAX_LOAD_ENTRIES).enumerate();
    points
        .map(|(k, c)| (Command::LoadModel, load_request((k * MAX_LOAD_POINTS) as u16, c)))
        .chain(
            normals.map(|(k, c)| (Command::LoadModel, load_request((NORMALS_OFFSET + k * MAX_LOAD_POINTS) as u16, c))),
        )
        .chain(entries.map(|(k, c)| (Command::LoadTable, table_request((k * MAX_LOAD_ENTRIES) as u16, c))))
        .collect()
}

/// The model digest a board reports after [`grid_upload`]'s requests (the first a LoadModel
/// at offset 0): what a host compares with Identify's to skip the upload.
pub fn grid_digest(grid: &crate::search::grid::Grid, normals: &[crate::surface::FxNormal]) -> u32 {
    grid_upload(grid, normals)
        .iter()
        .fold(crate::protocol::DIGEST_INIT, |d, (_, data)| crate::protocol::digest_update(d, data))
}

/// Bytes of two u16 fields.
pub const TWO_U16_BYTES: usize = 4;

/// Two u16 fields (LoadModel / LoadScan replies, SetSizes request and reply).
pub fn two_u16(a: u16, b: u16) -> Vec<u8> {
    let mut out = Vec::with_capacity(TWO_U16_BYTES);
    put(&mut out, a as u64, 2);
    put(&mut out, b as u64, 2);
    out
}

/// Parse two u16 fields.
pub fn parse_two_u16(d: &[u8]) -> Result<(u16, u16), MessageError> {
    need(d, TWO_U16_BYTES)?;
    Ok((le(&d[0..2]) as u16, le(&d[2..4]) as u16))
}

/// An Evaluate request.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EvaluateRequest {
    /// Forget the stored costs first.
    pub first: bool,
    /// Weigh every stored cost afterwards.
    pub last: bool,
    /// The weight scale (used with `last`).
    pub scale: WeightScale,
    /// The poses (0 ..= [`MAX_POSES`]; none only with `last`: weigh the stored costs).
    pub poses: Vec<FxPose>,
}

impl EvaluateRequest {
    /// The request data.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(6 + POSE_BYTES * self.poses.len());
        out.push(if self.first { FLAG_FIRST } else { 0 } | if self.last { FLAG_LAST } else { 0 });
        out.push(self.scale.pre_shift as u8);
        put(&mut out, self.scale.q_mul as u64, 3);
        out.push(self.poses.len() as u8);
        for p in &self.poses {
            out.extend_from_slice(&pose_bytes(p));
        }
        out
    }
}

/// The weights that come with the last batch.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WeightSummary {
    /// Smallest stored cost.
    pub min_cost: u64,
    /// Sum of the weights (24 bits).
    pub w_sum: u32,
    /// Every stored particle's weight, in order.
    pub weights: Vec<u16>,
}

/// An Evaluate reply.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EvaluateReply {
    /// This batch's costs.
    pub costs: Vec<u64>,
    /// With LAST: the weights of every stored particle.
    pub summary: Option<WeightSummary>,
}

impl EvaluateReply {
    /// The reply data.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::new();
        for &c in &self.costs {
            put(&mut out, c, COST_BYTES);
        }
        if let Some(s) = &self.summary {
            put(&mut out, s.weights.len() as u64, 2);
            put(&mut out, s.min_cost, COST_BYTES);
            put(&mut out, s.w_sum as u64, 3);
            for &w in &s.weights {
                put(&mut out, w as u64, WEIGHT_BYTES);
            }
        }
        out
    }

    /// Parse the reply to a request of `n` poses, with or without LAST.
    pub fn decode(d: &[u8], n: usize, last: bool) -> Result<Self, MessageError> {
        let costs_len = COST_BYTES * n;
        let least = costs_len + if last { WEIGHT_SUMMARY_BYTES } else { 0 };
        if d.len() < least {
            return Err(MessageError::Length { got: d.len(), expected: least });
        }
        let costs = d[..costs_len].chunks(COST_BYTES).map(le).collect();
        if !last {
            need(d, costs_len)?;
            return Ok(EvaluateReply { costs, summary: None });
        }
        let s = &d[costs_len..];
        let stored = le(&s[0..2]) as usize;
        need(s, WEIGHT_SUMMARY_BYTES + WEIGHT_BYTES * stored)?;
        let summary = WeightSummary {
            min_cost: le(&s[2..2 + COST_BYTES]),
            w_sum: le(&s[2 + COST_BYTES..WEIGHT_SUMMARY_BYTES]) as u32,
            weights: s[WEIGHT_SUMMARY_BYTES..].chunks(WEIGHT_BYTES).map(|c| le(c) as u16).collect(),
        };
        Ok(EvaluateReply { costs, summary: Some(summary) })
    }
}

/// A Nearest request: scan points `first .. first + count` at `pose`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NearestRequest {
    /// First scan point.
    pub first: u16,
    /// Scan points (1 ..= [`MAX_NEAREST`]).
    pub count: u16,
    /// The pose.
    pub pose: FxPose,
}

impl NearestRequest {
    /// The request data.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = two_u16(self.first, self.count);
        out.extend_from_slice(&pose_bytes(&self.pose));
        out
    }
}

/// A Nearest reply.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NearestReply {
    /// First scan point.
    pub first: u16,
    /// Sum of the squared distances of these points.
    pub cost: u64,
    /// Per point: nearest model index and squared distance (Q8.26).
    pub results: Vec<(u16, u64)>,
}

impl NearestReply {
    /// The reply data.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = two_u16(self.first, self.results.len() as u16);
        put(&mut out, self.cost, COST_BYTES);
        for &(i, d) in &self.results {
            put(&mut out, i as u64, 2);
            put(&mut out, d, DIST_BYTES);
        }
        out
    }

    /// Parse the reply to `request`.
    pub fn decode(d: &[u8], request: &NearestRequest) -> Result<Self, MessageError> {
        need(d, NEAREST_HEAD_BYTES + NEAREST_RESULT_BYTES * request.count as usize)?;
        let (first, count) = parse_two_u16(&d[..TWO_U16_BYTES])?;
        if first != request.first {
            return Err(MessageError::Field { field: "first", got: first as u64, expected: request.first as u64 });
        }
        if count != request.count {
            return Err(MessageError::Field { field: "count", got: count as u64, expected: request.count as u64 });
        }
        Ok(NearestReply {
            first,
            cost: le(&d[TWO_U16_BYTES..NEAREST_HEAD_BYTES]),
            results: d[NEAREST_HEAD_BYTES..]
                .chunks(NEAREST_RESULT_BYTES)
                .map(|c| (le(&c[..2]) as u16, le(&c[2..])))
                .collect(),
        })
    }
}

/// The on-board filter's state in a Status reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum RunState {
    /// No run since power-up or reset.
    Idle = 0,
    /// A filter is running.
    Running = 1,
    /// The last run finished; its result is ready.
    Done = 2,
}

impl RunState {
    /// The state of a byte.
    pub fn from_byte(b: u8) -> Option<RunState> {
        Some(match b {
            0 => RunState::Idle,
            1 => RunState::Running,
            2 => RunState::Done,
            _ => return None,
        })
    }
}

/// A Status reply: state, iterations completed, best cost so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StatusReply {
    /// The filter's state.
    pub state: RunState,
    /// Iterations completed (0 when idle).
    pub iterations: u16,
    /// Best cost so far (48 bits; [`NO_COST`] when idle).
    pub best_cost: u64,
}

impl StatusReply {
    /// The reply of a board that has not run the filter since power-up or reset.
    pub const IDLE: StatusReply = StatusReply { state: RunState::Idle, iterations: 0, best_cost: NO_COST };

    /// The reply data.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(STATUS_BYTES);
        out.push(self.state as u8);
        put(&mut out, self.iterations as u64, 2);
        put(&mut out, self.best_cost, COST_BYTES);
        out
    }

    /// Parse the reply data (length and state checked).
    pub fn decode(d: &[u8]) -> Result<Self, MessageError> {
        need(d, STATUS_BYTES)?;
        let state = RunState::from_byte(d[0]).ok_or(MessageError::Field {
            field: "state",
            got: d[0] as u64,
            expected: RunState::Done as u64,
        })?;
        Ok(StatusReply { state, iterations: le(&d[1..3]) as u16, best_cost: le(&d[3..9]) })
    }
}

/// A Result reply: the finished filter's best particle and its evaluation, then the
/// polish's choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResultReply {
    /// Iterations run.
    pub iterations: u16,
    /// Its cost (48 bits).
    pub cost: u64,
    /// Its largest squared point distance (34 bits).
    pub max_d2: u64,
    /// Its parameters `[a, b, c, s, phi, theta, psi]` (24-bit two's complement each).
    pub params: Particle,
    /// Its pose as the board built it ([`crate::filter::pf::pose_of`]).
    pub pose: FxPose,
    /// The polish's choice: the winning start (0 the filter's pose), its polished pose and
    /// its cost over the polish's points.
    pub polish: crate::protocol::run_request::PolishOutcome,
}

impl ResultReply {
    /// The reply for a Run's outcome.
    pub fn of(outcome: &crate::protocol::run_request::RunOutcome) -> Self {
        let f = &outcome.filter;
        ResultReply {
            iterations: f.iterations,
            cost: f.best.cost,
            max_d2: f.best.max_d2,
            params: f.params,
            pose: f.pose,
            polish: outcome.polish,
        }
    }

    /// The reply data: iterations u16, cost u48, max_d2 u40 (34 bits), the 7 parameters
    /// as 3 bytes each, the filter's pose (27 bytes); the winning start u8, its cost u48,
    /// its polished pose (27 bytes).
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(RESULT_BYTES);
        put(&mut out, self.iterations as u64, 2);
        put(&mut out, self.cost & NO_COST, 6);
        put(&mut out, self.max_d2 & MAX_D2_MASK, 5);
        for &p in &self.params {
            put(&mut out, p as u32 as u64 & 0xff_ffff, 3);
        }
        out.extend_from_slice(&pose_bytes(&self.pose));
        out.push(self.polish.winner);
        put(&mut out, self.polish.cost & NO_COST, COST_BYTES);
        out.extend_from_slice(&pose_bytes(&self.polish.pose));
        out
    }

    /// Parse the reply data (length checked; parameters sign-extended from 24 bits).
    pub fn decode(d: &[u8]) -> Result<Self, MessageError> {
        need(d, RESULT_BYTES)?;
        let max_d2 = le(&d[8..13]);
        if max_d2 > MAX_D2_MASK {
            return Err(MessageError::Field { field: "max_d2", got: max_d2, expected: MAX_D2_MASK });
        }
        let p = RESULT_FILTER_BYTES;
        Ok(ResultReply {
            iterations: le(&d[0..2]) as u16,
            cost: le(&d[2..8]),
            max_d2,
            params: std::array::from_fn(|k| crate::filter::pf::wrap24(le(&d[13 + 3 * k..16 + 3 * k]) as i64)),
            pose: pose_from_bytes(&d[13 + 3 * PARAMS..p]),
            polish: crate::protocol::run_request::PolishOutcome {
                winner: d[p],
                cost: le(&d[p + 1..p + RESULT_POLISH_HEAD_BYTES]),
                pose: pose_from_bytes(&d[p + RESULT_POLISH_HEAD_BYTES..]),
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::layout::point_from_bytes;

    #[test]
    fn points_and_poses_round_trip() {
        for p in [[0, 0, 0], [-1, 32767, -32768], [1234, -4321, 7]] {
            assert_eq!(point_from_bytes(&point_bytes(p)), p);
        }
        let pose = FxPose { m: [1, -1, 2, -2, 131071, -131072, 0, 5, -5], t: [7, -7, 100] };
        assert_eq!(pose_from_bytes(&pose_bytes(&pose)), pose);
        assert_eq!(pose_bytes(&pose)[0], 1, "m[0] = 1 sits in byte 0's low bits");
    }

    #[test]
    fn replies_round_trip() {
        let id = Identity::of_board(16, 100_000_000, 921_600, 2000, 1000, 50);
        assert_eq!(id.encode().len(), IDENTITY_BYTES);
        assert_eq!(Identity::decode(&id.encode()), Ok(id));
        // A protocol 2 board's 26 bytes read with no digest; a version 3 reply must have 30.
        let old = Identity { version: 2, ..id.with_digest(0x1234_5678) };
        let bytes = old.encode();
        assert_eq!(Identity::decode(&bytes[..26]), Ok(old.with_digest(crate::protocol::DIGEST_NONE)));
        assert!(Identity::decode(&id.encode()[..26]).is_err());
        let r = EvaluateReply {
            costs: vec![1, (1 << 48) - 1],
            summary: Some(WeightSummary { min_cost: 1, w_sum: 65535, weights: vec![65535, 0, 7] }),
        };
        assert_eq!(EvaluateReply::decode(&r.encode(), 2, true), Ok(r.clone()));
        let short = EvaluateReply { costs: vec![5], summary: None };
        assert_eq!(EvaluateReply::decode(&short.encode(), 1, false), Ok(short));
        let e = r.encode();
        assert!(EvaluateReply::decode(&e[..e.len() - 1], 2, true).is_err());
        let q = NearestRequest { first: 3, count: 2, pose: FxPose::default() };
        assert_eq!(q.encode().len(), 31);
        let n = NearestReply { first: 3, cost: 99, results: vec![(4095, (1 << 34) - 1), (0, 0)] };
        assert_eq!(NearestReply::decode(&n.encode(), &q), Ok(n));
    }

    #[test]
    fn status_and_result_round_trip_with_length_checks() {
        for s in [
            StatusReply::IDLE,
            StatusReply { state: RunState::Running, iterations: 7, best_cost: 123_456_789 },
            StatusReply { state: RunState::Done, iterations: 65535, best_cost: NO_COST },
        ] {
            let d = s.encode();
            assert_eq!(d.len(), STATUS_BYTES);
            assert_eq!(StatusReply::decode(&d), Ok(s));
            assert!(matches!(StatusReply::decode(&d[1..]), Err(MessageError::Length { got: 8, expected: 9 })));
        }
        assert_eq!(StatusReply::IDLE.encode(), vec![0, 0, 0, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff]);
        let mut bad = StatusReply::IDLE.encode();
        bad[0] = 3;
        assert!(matches!(StatusReply::decode(&bad), Err(MessageError::Field { field: "state", got: 3, .. })));
        let r = ResultReply {
            iterations: 513,
            cost: (1 << 48) - 2,
            max_d2: (1 << 34) - 1,
            params: [-1, 1, -(1 << 23), (1 << 23) - 1, 0, 12345, -54321],
            pose: FxPose { m: [1, -1, 2, -2, 131071, -131072, 0, 5, -5], t: [7, -7, 100] },
            polish: crate::protocol::run_request::PolishOutcome {
                winner: 2,
                cost: (1 << 48) - 3,
                pose: FxPose { m: [3, -3, 2, -2, 131071, -131072, 0, 5, -5], t: [-7, 7, -100] },
            },
        };
        let d = r.encode();
        assert_eq!(d.len(), RESULT_BYTES);
        assert_eq!(RESULT_BYTES, 95);
        assert_eq!(d[61], 2, "the winner after the filter's 61 bytes");
        assert_eq!(&d[13..16], &[0xff, 0xff, 0xff], "-1 as 24-bit two's complement");
        assert_eq!(&d[19..22], &[0, 0, 0x80]);
        assert_eq!(ResultReply::decode(&d), Ok(r));
        assert!(matches!(ResultReply::decode(&d[..94]), Err(MessageError::Length { got: 94, expected: 95 })));
        assert!(ResultReply::decode(&[d.clone(), vec![0]].concat()).is_err());
        let mut wide = d.clone();
        wide[12] = 0x04; // bit 34 of max_d2
        assert!(matches!(ResultReply::decode(&wide), Err(MessageError::Field { field: "max_d2", .. })));
    }

    // The frame limits, checked at compile time.
    const _: () = {
        use crate::protocol::MAX_BODY;
        assert!(2 + 4 + POINT_BYTES * MAX_LOAD_POINTS <= MAX_BODY);
        assert!(2 + 6 + POSE_BYTES * MAX_POSES <= MAX_BODY);
        assert!(2 + 6 + POSE_BYTES * (MAX_POSES + 1) > MAX_BODY);
        assert!(2 + 10 + 7 * MAX_NEAREST <= MAX_BODY);
        assert!(2 + 10 + 7 * (MAX_NEAREST + 1) > MAX_BODY);
    };
}
