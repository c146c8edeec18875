//! Evaluate: a batch of poses in, their costs out, and with LAST the weights of every
//! stored cost.

use super::{le, need, put, MessageError, COST_BYTES};
use crate::common::format::{FxPose, WeightScale};
use crate::protocol::layout::{pose_bytes, POSE_BYTES};

/// Most poses in one Evaluate frame.
pub const MAX_POSES: usize = 37;
/// Evaluate flag: forget the stored costs first.
pub const FLAG_FIRST: u8 = 1;
/// Evaluate flag: weigh every stored cost afterwards.
pub const FLAG_LAST: u8 = 2;
/// Data bytes of an Evaluate request before its poses: flags, pre_shift, q_mul, n.
pub const EVALUATE_HEADER_BYTES: usize = 6;
/// Bytes of a weight on the wire.
pub const WEIGHT_BYTES: usize = 2;
/// Bytes of an Evaluate reply's weight summary before its weights: count, min_cost, w_sum.
pub const WEIGHT_SUMMARY_BYTES: usize = 2 + COST_BYTES + 3;
/// Mask of the 24-bit `w_sum` field (the weight stage's accumulator).
pub const W_SUM_MASK: u32 = (1 << 24) - 1;

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
