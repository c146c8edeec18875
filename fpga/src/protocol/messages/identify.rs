//! The Identify reply: the board's version, limits, clock, baud, sizes and model digest.

use super::{le, need, put, MessageError, MAX_LOAD_POINTS, MAX_NEAREST, MAX_POSES};
use crate::common::format::MAX_POINTS;
use crate::filter::weights::MAX_PARTICLES;
use crate::protocol::VERSION;

/// Data bytes of the Identify reply.
pub const IDENTITY_BYTES: usize = 30;
/// Bytes of the model digest (the Identify reply's last field).
pub const DIGEST_BYTES: usize = 4;

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
