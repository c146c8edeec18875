//! Result: the finished filter's best particle, its evaluation and pose, then the polish's
//! choice.

use super::{le, need, put, MessageError, COST_BYTES, DIST_BYTES, NO_COST};
use crate::common::format::FxPose;
use crate::filter::pf::{Particle, PARAMS};
use crate::protocol::layout::{pose_bytes, pose_from_bytes, POSE_BYTES};

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
/// Mask of a best point distance in the Result reply (34 bits).
pub const MAX_D2_MASK: u64 = (1 << 34) - 1;

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
