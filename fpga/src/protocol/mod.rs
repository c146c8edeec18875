//! The wire protocol between the host and the board (docs/protocol.md), one module for
//! both sides: framing (COBS, `0x00` delimiter), CRC-16/CCITT-FALSE, and the messages.
//!
//! A frame on the wire is `COBS(body ++ crc16(body) as little-endian) ++ [0x00]` with
//! `body = [command, sequence, data...]`. Replies echo the sequence number and set bit 7
//! of the command; an error reply is command [`Command::Error`] `| 0x80` with one error
//! code byte and the offending command.

pub mod layout;
pub mod messages;
pub mod run_request;
pub mod versions;

/// Largest body (command, sequence and data) in bytes.
pub const MAX_BODY: usize = HEADER_BYTES
    + crate::protocol::messages::LOAD_HEADER_BYTES
    + crate::protocol::messages::MAX_LOAD_POINTS * crate::protocol::layout::POINT_BYTES;
/// Bytes of a frame's header: the command code, then the sequence number.
pub const HEADER_BYTES: usize = 2;
/// Data bytes of an error reply: the error code, then the failed command.
pub const ERROR_DATA_BYTES: usize = 2;
/// Bytes of a frame's CRC-16 (after its data).
pub const CRC_BYTES: usize = 2;
/// Largest encoded frame, delimiter included (COBS adds one byte per 254 plus one).
pub const MAX_FRAME: usize = MAX_BODY + 2 + (MAX_BODY + 2) / 254 + 2;
/// The frame delimiter.
pub const DELIMITER: u8 = 0x00;
/// Protocol version reported by `Identify`.
pub const VERSION: u16 = 7;

/// CRC-16/CCITT-FALSE: polynomial 0x1021, initial value 0xFFFF, no reflection, no final XOR.
pub fn crc16(data: &[u8]) -> u16 {
    let mut crc = 0xffffu16;
    for &b in data {
        crc ^= (b as u16) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 { (crc << 1) ^ 0x1021 } else { crc << 1 };
        }
    }
    crc
}

/// The model digest after power-up: nothing uploaded (docs/protocol.md, "Resident model").
pub const DIGEST_NONE: u32 = 0;
/// The model digest's restart value, taken by a LoadModel at offset 0.
pub const DIGEST_INIT: u32 = 0xffff_ffff;

/// The model digest continued over `data`: CRC-32/MPEG-2 (polynomial 0x04C11DB7, MSB first,
/// no reflection, no final XOR) from `state`.
pub fn digest_update(state: u32, data: &[u8]) -> u32 {
    let mut crc = state;
    for &b in data {
        crc ^= (b as u32) << 24;
        for _ in 0..8 {
            crc = if crc & 0x8000_0000 != 0 { (crc << 1) ^ 0x04c1_1db7 } else { crc << 1 };
        }
    }
    crc
}

/// COBS-encode `data` (no delimiter appended).
pub fn cobs_encode(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + data.len() / 254 + 2);
    let mut code_at = 0;
    out.push(0);
    let mut code = 1u8;
    for &b in data {
        if b == 0 {
            out[code_at] = code;
            code_at = out.len();
            out.push(0);
            code = 1;
        } else {
            out.push(b);
            code += 1;
            if code == 0xff {
                out[code_at] = code;
                code_at = out.len();
                out.push(0);
                code = 1;
            }
        }
    }
    out[code_at] = code;
    out
}

/// COBS-decode one frame's bytes (without the delimiter). `None` if malformed.
pub fn cobs_decode(data: &[u8]) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(data.len());
    let mut i = 0;
    while i < data.len() {
        let code = data[i] as usize;
        if code == 0 || i + code > data.len() {
            return None;
        }
        out.extend_from_slice(&data[i + 1..i + code]);
        i += code;
        if code < 0xff && i < data.len() {
            out.push(0);
        }
    }
    Some(out)
}

/// Commands (host to board). A reply carries the same code with bit 7 set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Command {
    /// Version and limits.
    Identify = 0x01,
    /// Write model points at an offset.
    LoadModel = 0x02,
    /// Write scan points at an offset.
    LoadScan = 0x03,
    /// Set the numbers of model and scan points in use.
    SetSizes = 0x04,
    /// Evaluate a batch of particle poses: costs and weights back.
    Evaluate = 0x05,
    /// Nearest model index and squared distance of every scan point for one pose.
    Nearest = 0x06,
    /// Start the on-board particle filter (`pf::PfConfig`); it runs in the background.
    Run = 0x07,
    /// The filter's state, iterations done and best cost so far (answered while running).
    Status = 0x08,
    /// The finished filter's best particle, its cost and pose.
    Result = 0x09,
    /// Write cell-table entries at an offset (the grid search's table, `grid::Grid::first`).
    LoadTable = 0x0a,
    /// Error reply (board to host only).
    Error = 0x7f,
}

impl Command {
    /// The command for a code (reply bit cleared).
    pub fn from_code(code: u8) -> Option<Command> {
        Some(match code & 0x7f {
            0x01 => Command::Identify,
            0x02 => Command::LoadModel,
            0x03 => Command::LoadScan,
            0x04 => Command::SetSizes,
            0x05 => Command::Evaluate,
            0x06 => Command::Nearest,
            0x07 => Command::Run,
            0x08 => Command::Status,
            0x09 => Command::Result,
            0x0a => Command::LoadTable,
            0x7f => Command::Error,
            _ => return None,
        })
    }
}

/// Error codes of an error reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum ErrorCode {
    /// The frame's CRC did not match.
    BadCrc = 1,
    /// The body's length does not fit the command (or the frame is too long).
    BadLength = 2,
    /// Unknown command code.
    UnknownCommand = 3,
    /// An offset, count or size beyond the board's stores.
    OverCapacity = 4,
    /// A command arrived while the board was busy (answering, or running the filter).
    Busy = 5,
    /// Malformed COBS.
    BadFrame = 6,
    /// Result asked before any filter run finished since power-up or reset.
    NoResult = 7,
}

impl ErrorCode {
    /// The code for a byte.
    pub fn from_byte(b: u8) -> Option<ErrorCode> {
        Some(match b {
            1 => ErrorCode::BadCrc,
            2 => ErrorCode::BadLength,
            3 => ErrorCode::UnknownCommand,
            4 => ErrorCode::OverCapacity,
            5 => ErrorCode::Busy,
            6 => ErrorCode::BadFrame,
            7 => ErrorCode::NoResult,
            _ => return None,
        })
    }
}

/// A decoded frame body.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame {
    /// Command code (bit 7 set on replies).
    pub code: u8,
    /// Sequence number, echoed by the reply.
    pub seq: u8,
    /// Data bytes.
    pub data: Vec<u8>,
}

/// Why bytes between two delimiters are not a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// Malformed COBS.
    BadFrame,
    /// Shorter than command, sequence and CRC, or longer than [`MAX_FRAME`].
    BadLength,
    /// CRC mismatch.
    BadCrc,
}

impl FrameError {
    /// The error code the board answers with.
    pub fn code(self) -> ErrorCode {
        match self {
            FrameError::BadFrame => ErrorCode::BadFrame,
            FrameError::BadLength => ErrorCode::BadLength,
            FrameError::BadCrc => ErrorCode::BadCrc,
        }
    }
}

impl Frame {
    /// The bytes on the wire, delimiter included.
    pub fn encode(&self) -> Vec<u8> {
        let mut body = Vec::with_capacity(self.data.len() + 4);
        body.push(self.code);
        body.push(self.seq);
        body.extend_from_slice(&self.data);
        let crc = crc16(&body);
        body.extend_from_slice(&crc.to_le_bytes());
        let mut out = cobs_encode(&body);
        out.push(DELIMITER);
        out
    }

    /// Decode the bytes between two delimiters.
    pub fn decode(raw: &[u8]) -> Result<Frame, FrameError> {
        if raw.len() > MAX_FRAME {
            return Err(FrameError::BadLength);
        }
        let body = cobs_decode(raw).ok_or(FrameError::BadFrame)?;
        if body.len() < 4 {
            return Err(FrameError::BadLength);
        }
        let (payload, crc) = body.split_at(body.len() - CRC_BYTES);
        if crc16(payload) != u16::from_le_bytes([crc[0], crc[1]]) {
            return Err(FrameError::BadCrc);
        }
        Ok(Frame { code: payload[0], seq: payload[1], data: payload[2..].to_vec() })
    }

    /// An error reply to a frame with sequence `seq` and command code `code`.
    pub fn error(seq: u8, error: ErrorCode, code: u8) -> Frame {
        Frame { code: Command::Error as u8 | 0x80, seq, data: vec![error as u8, code] }
    }
}

/// Splits a byte stream into frames at the delimiter; bytes past [`MAX_FRAME`] without a
/// delimiter are dropped (the frame is then reported too long when its delimiter comes).
#[derive(Clone, Debug, Default)]
pub struct Deframer {
    buf: Vec<u8>,
    overflow: bool,
}

impl Deframer {
    /// Feed one byte; returns the bytes of a completed frame (possibly empty, which callers
    /// ignore: two delimiters in a row) or `None`.
    pub fn push(&mut self, b: u8) -> Option<Result<Frame, FrameError>> {
        if b != DELIMITER {
            if self.buf.len() < MAX_FRAME {
                self.buf.push(b);
            } else {
                self.overflow = true;
            }
            return None;
        }
        let raw = std::mem::take(&mut self.buf);
        let overflow = std::mem::replace(&mut self.overflow, false);
        if raw.is_empty() && !overflow {
            return None;
        }
        Some(if overflow { Err(FrameError::BadLength) } else { Frame::decode(&raw) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_matches_the_standard_check_value() {
        assert_eq!(crc16(b"123456789"), 0x29b1);
    }

    #[test]
    fn cobs_round_trips_and_has_no_zero() {
        let cases: Vec<Vec<u8>> = vec![
            vec![],
            vec![0],
            vec![0, 0],
            vec![1, 2, 0, 3],
            (1..=254).collect(),
            (0..=255).collect(),
            vec![7; 1000],
            vec![0; 600],
        ];
        for c in cases {
            let e = cobs_encode(&c);
            assert!(!e.contains(&0), "{c:?}");
            assert_eq!(cobs_decode(&e).as_deref(), Some(&c[..]));
        }
        assert_eq!(cobs_encode(&[0x11, 0x22, 0x00, 0x33]), vec![0x03, 0x11, 0x22, 0x02, 0x33]);
    }

    #[test]
    fn frames_round_trip_through_the_deframer() {
        let f = Frame { code: Command::LoadModel as u8, seq: 9, data: vec![0, 1, 0, 0, 255, 3] };
        let mut d = Deframer::default();
        let mut got = Vec::new();
        for &b in [vec![0, 0], f.encode(), f.encode()].concat().iter() {
            if let Some(r) = d.push(b) {
                got.push(r);
            }
        }
        assert_eq!(got, vec![Ok(f.clone()), Ok(f)]);
    }

    #[test]
    fn corruption_is_detected() {
        let f = Frame { code: 0x05, seq: 1, data: (0..40).collect() };
        let wire = f.encode();
        let mut bad_crc = 0;
        for i in 0..wire.len() - 1 {
            for bit in 0..8 {
                let mut w = wire.clone();
                w[i] ^= 1 << bit;
                if w[i] == 0 {
                    continue; // becomes a delimiter: a different framing case
                }
                let r = Frame::decode(&w[..w.len() - 1]);
                assert_ne!(r, Ok(f.clone()), "flip at byte {i} bit {bit} went unnoticed");
                bad_crc += (r == Err(FrameError::BadCrc)) as usize;
            }
        }
        assert!(bad_crc > 0);
    }

    #[test]
    fn random_bytes_never_panic_and_overlong_frames_are_reported() {
        let mut s = 0x1234_5678u64;
        let mut d = Deframer::default();
        for _ in 0..200_000 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let b = if (s >> 60) == 0 { 0 } else { (s >> 33) as u8 };
            if let Some(Ok(f)) = d.push(b) {
                // Random bytes rarely pass the CRC; when they do the frame is well-formed.
                assert!(f.data.len() + 4 <= MAX_FRAME);
            }
        }
        let mut d = Deframer::default();
        for _ in 0..MAX_FRAME + 10 {
            assert_eq!(d.push(1), None);
        }
        assert_eq!(d.push(0), Some(Err(FrameError::BadLength)));
        let f = Frame { code: 1, seq: 2, data: vec![] };
        let r: Vec<_> = f.encode().into_iter().filter_map(|b| d.push(b)).collect();
        assert_eq!(r, vec![Ok(f)], "the deframer recovers after an overlong frame");
    }

    #[test]
    fn error_replies() {
        let e = Frame::error(7, ErrorCode::Busy, 0x05);
        assert_eq!(e.code, 0xff);
        assert_eq!(ErrorCode::from_byte(e.data[0]), Some(ErrorCode::Busy));
        assert_eq!(Command::from_code(e.data[1]), Some(Command::Evaluate));
        assert_eq!(Command::from_code(0x85), Some(Command::Evaluate));
        assert_eq!(Command::from_code(0x42), None);
        for (code, c) in
            [(0x07, Command::Run), (0x08, Command::Status), (0x09, Command::Result), (0x0a, Command::LoadTable)]
        {
            assert_eq!(Command::from_code(code), Some(c));
            assert_eq!(Command::from_code(code | 0x80), Some(c));
            assert_eq!(c as u8, code);
        }
        assert_eq!(Command::from_code(0x0b), None);
        // CRC-32/MPEG-2's check value; continuing over a split equals one pass.
        assert_eq!(digest_update(DIGEST_INIT, b"123456789"), 0x0376_e6e7);
        assert_eq!(digest_update(digest_update(DIGEST_INIT, b"1234"), b"56789"), 0x0376_e6e7);
        assert_eq!(ErrorCode::from_byte(7), Some(ErrorCode::NoResult));
        assert_eq!(ErrorCode::from_byte(8), None);
    }
}
