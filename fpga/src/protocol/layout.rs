//! The wire layout of a point (6 bytes, the 48-bit word of [`pack_point`]) and of a pose
//! (27 bytes, the 216-bit word of [`FxPose::pack`]), little-endian: what every message
//! that carries points or poses ([`super::messages`], [`super::run_request`]) shares.

use crate::common::format::{pack_point, unpack_point, FxPoint, FxPose, POSE_BITS};

/// Bytes of a point on the wire.
pub const POINT_BYTES: usize = 6;
/// Bytes of a pose on the wire.
pub const POSE_BYTES: usize = 27;
/// A point's 6 bytes.
pub fn point_bytes(p: FxPoint) -> [u8; POINT_BYTES] {
    let w = pack_point(p);
    std::array::from_fn(|k| (w >> (8 * k)) as u8)
}

/// The point of 6 bytes.
pub fn point_from_bytes(b: &[u8]) -> FxPoint {
    unpack_point(b[..POINT_BYTES].iter().rev().fold(0u64, |v, &x| v << 8 | x as u64))
}

/// A pose's 27 bytes.
pub fn pose_bytes(pose: &FxPose) -> [u8; POSE_BYTES] {
    let w = pose.pack();
    std::array::from_fn(|k| (w[k / 8] >> (8 * (k % 8))) as u8)
}

/// The pose of 27 bytes (fields sign-extended from 18 bits).
pub fn pose_from_bytes(b: &[u8]) -> FxPose {
    let field = |k: usize| -> i32 {
        let at = k * POSE_BITS as usize;
        let mut raw = 0u64;
        for bit in 0..POSE_BITS as usize {
            let i = at + bit;
            raw |= (((b[i / 8] >> (i % 8)) & 1) as u64) << bit;
        }
        (((raw << (64 - POSE_BITS)) as i64) >> (64 - POSE_BITS)) as i32
    };
    FxPose { m: std::array::from_fn(field), t: std::array::from_fn(|k| field(9 + k)) }
}
