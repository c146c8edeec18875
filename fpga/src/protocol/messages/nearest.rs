//! Nearest: scan points at a pose in, each one's nearest model point and distance out.

use super::{le, need, parse_two_u16, put, two_u16, MessageError, COST_BYTES, DIST_BYTES, TWO_U16_BYTES};
use crate::common::format::FxPose;
use crate::protocol::layout::{pose_bytes, POSE_BYTES};

/// Most results in one Nearest frame.
pub const MAX_NEAREST: usize = 144;
/// Data bytes of a Nearest request: first, count, pose.
pub const NEAREST_REQUEST_BYTES: usize = 4 + POSE_BYTES;
/// Bytes of a Nearest reply before its results: first, count, cost.
pub const NEAREST_HEAD_BYTES: usize = TWO_U16_BYTES + COST_BYTES;
/// Bytes of one Nearest result: the model index, the squared distance.
pub const NEAREST_RESULT_BYTES: usize = 2 + DIST_BYTES;

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
