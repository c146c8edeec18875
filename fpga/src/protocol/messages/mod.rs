//! The data layouts of the protocol's commands and replies (docs/protocol.md), shared by
//! the host's board client and the board reference. Everything is little-endian; points
//! are 6 bytes, poses 27 (the 216-bit word of
//! [`FxPose::pack`](crate::common::format::FxPose::pack)).
//!
//! One module a message ([`identify`], [`load`], [`evaluate`], [`nearest`], [`status`],
//! [`result`]; the Run request is [`crate::protocol::run_request`]), each re-exported here;
//! this file holds what they share: the fields' sizes, the two-u16 body, the parse error.

pub mod evaluate;
pub mod identify;
pub mod load;
pub mod nearest;
pub mod result;
pub mod status;

pub use evaluate::*;
pub use identify::*;
pub use load::*;
pub use nearest::*;
pub use result::*;
pub use status::*;

/// Data bytes of the Run reply: the request's particles and iterations echoed.
pub const RUN_REPLY_BYTES: usize = 4;
/// Bytes of a cost (48 bits) on the wire.
pub const COST_BYTES: usize = 6;
/// Bytes of a squared distance (34 bits) on the wire.
pub const DIST_BYTES: usize = 5;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::format::FxPose;
    use crate::protocol::layout::{
        point_bytes, point_from_bytes, pose_bytes, pose_from_bytes, POINT_BYTES, POSE_BYTES,
    };

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
