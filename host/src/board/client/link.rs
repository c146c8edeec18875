//! The wire under [`BoardClient`]: sequence numbers, the deadline of each reply, the frame
//! that is the reply (or a reason to resend, or an error), resends (the rules are the
//! client's module documentation).

use super::{BoardClient, BoardError, MAX_RETRIES, MIN_BAUD};
use pficp_fpga::protocol::messages::MessageError;
use pficp_fpga::protocol::{Command, Deframer, ErrorCode, Frame, FrameError, DELIMITER};
use std::io::{ErrorKind, Read, Write};
use std::time::{Duration, Instant};

/// How one read of a reply ended.
enum Read1 {
    /// The reply.
    Reply(Frame),
    /// Send again; `executed` when the board may have executed the request.
    Resend { reason: String, executed: bool },
}

/// What one frame means for the request waited for.
enum Judged {
    /// The reply, or a reason to resend.
    Outcome(Read1),
    /// A reply (or error reply) that is not for this request.
    Foreign { code: u8, seq: u8 },
    /// Nothing to note (a frame that is not a reply).
    Skip,
}

impl BoardClient {
    /// Time the board needs for a request of `request_bytes` on the wire, a reply of
    /// `reply_data` data bytes and `clocks` of compute.
    pub(super) fn board_time(&self, request_bytes: usize, reply_data: usize, clocks: u64) -> Duration {
        // Reply on the wire: body + CRC + COBS overhead + delimiter; 10 bits per byte (8N1).
        let reply_bytes = reply_data + 4 + (reply_data + 4) / 254 + 2;
        let wire = (request_bytes + reply_bytes) as f64 * 10.0 / self.baud.max(MIN_BAUD) as f64;
        Duration::from_secs_f64(wire + clocks as f64 / self.clock_hz())
    }

    fn next_seq(&mut self) -> u8 {
        self.seq = if self.seq == 255 { 1 } else { self.seq + 1 };
        self.seq
    }

    /// Send one request and wait for its reply (see the module documentation).
    pub(super) fn transact(
        &mut self,
        command: Command,
        data: Vec<u8>,
        reply_data: usize,
        clocks: u64,
        repeatable: bool,
    ) -> Result<Frame, BoardError> {
        self.transact_with(command, data, reply_data, Duration::ZERO, clocks, repeatable)
    }

    /// [`Self::transact`] with `extra` time allowed for the reply. Run and Result answered
    /// `Busy` are errors (the board runs a filter), not resent.
    pub(super) fn transact_with(
        &mut self,
        command: Command,
        data: Vec<u8>,
        reply_data: usize,
        extra: Duration,
        clocks: u64,
        repeatable: bool,
    ) -> Result<Frame, BoardError> {
        let seq = self.next_seq();
        let mut wire = vec![DELIMITER];
        wire.extend(Frame { code: command as u8, seq, data }.encode());
        let allowed = self.timeout + extra + self.board_time(wire.len(), reply_data, clocks);
        self.forget_received();
        let mut last = String::new();
        for attempt in 0..=MAX_RETRIES {
            if attempt > 0 {
                self.stats.resends += 1;
            }
            self.send(&wire, command, allowed)?;
            match self.read_reply(command, seq, allowed)? {
                Read1::Reply(f) => {
                    self.stats.requests += 1;
                    return Ok(f);
                }
                Read1::Resend { reason, executed } => {
                    if executed && !repeatable {
                        return Err(BoardError::ReplyLost { command, reason });
                    }
                    last = reason;
                }
            }
        }
        Err(BoardError::Retries { command, attempts: MAX_RETRIES + 1, last })
    }

    /// Drop what an earlier exchange left: half a frame in the deframer, bytes read but not
    /// looked at, bytes waiting in the port (a reply that came after its deadline).
    fn forget_received(&mut self) {
        self.deframer = Deframer::default();
        self.rx.clear();
        self.rx_at = 0;
        let _ = self.port.clear(serialport::ClearBuffer::Input);
    }

    pub(super) fn io_error(&self, during: String, source: std::io::Error) -> BoardError {
        BoardError::Io { port: self.name.clone(), during, error: source }
    }

    fn send(&mut self, wire: &[u8], command: Command, allowed: Duration) -> Result<(), BoardError> {
        let during = || format!("sending {command:?}");
        self.port.set_timeout(allowed).map_err(|e| self.io_error(during(), e.into()))?;
        match self.port.write_all(wire) {
            Ok(()) => {
                self.stats.bytes_sent += wire.len();
                Ok(())
            }
            Err(e) if e.kind() == ErrorKind::TimedOut => Err(BoardError::Timeout {
                port: self.name.clone(),
                command,
                waited: allowed,
                baud: self.baud,
                received: 0,
            }),
            Err(e) => Err(self.io_error(during(), e)),
        }
    }

    /// Read until the reply to (`command`, `seq`), a reason to resend, or the deadline.
    fn read_reply(&mut self, command: Command, seq: u8, allowed: Duration) -> Result<Read1, BoardError> {
        let start = Instant::now();
        let deadline = start + allowed;
        let during = || format!("waiting for the reply to {command:?}");
        let mut buf = [0u8; 512];
        // Replies that were not ours (the last one's code and sequence), bytes that came.
        let mut foreign = None;
        let mut received = 0;
        loop {
            while self.rx_at < self.rx.len() {
                let b = self.rx[self.rx_at];
                self.rx_at += 1;
                let Some(decoded) = self.deframer.push(b) else { continue };
                match self.judge(decoded, command, seq)? {
                    Judged::Outcome(outcome) => return Ok(outcome),
                    Judged::Foreign { code, seq } => foreign = Some((code, seq)),
                    Judged::Skip => {}
                }
            }
            self.rx.clear();
            self.rx_at = 0;
            let now = Instant::now();
            if now >= deadline {
                let (port, waited) = (self.name.clone(), now - start);
                return Err(match foreign {
                    Some((got_code, got_seq)) => {
                        BoardError::Unexpected { port, command, seq, got_code, got_seq, waited }
                    }
                    None => BoardError::Timeout { port, command, waited, baud: self.baud, received },
                });
            }
            self.port.set_timeout(deadline - now).map_err(|e| self.io_error(during(), e.into()))?;
            match self.port.read(&mut buf) {
                Ok(0) => {
                    let e = std::io::Error::new(ErrorKind::UnexpectedEof, "the port was closed");
                    return Err(self.io_error(during(), e));
                }
                Ok(n) => {
                    self.stats.bytes_received += n;
                    received += n;
                    self.rx.extend_from_slice(&buf[..n]);
                }
                Err(e) if e.kind() == ErrorKind::TimedOut || e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(self.io_error(during(), e)),
            }
        }
    }

    /// What a frame (or an undecodable one) means for the request (`command`, `seq`):
    /// the reply, a reason to resend, an error, a reply that is not ours (remembered for
    /// the timeout), or nothing (a stray frame, skipped).
    fn judge(&self, decoded: Result<Frame, FrameError>, command: Command, seq: u8) -> Result<Judged, BoardError> {
        let frame = match decoded {
            Ok(f) => f,
            // It may have been our reply (or a stale one): a repeatable request is resent.
            Err(e) => {
                let reason = format!("undecodable reply frame ({e:?})");
                return Ok(Judged::Outcome(Read1::Resend { reason, executed: true }));
            }
        };
        if frame.code == command as u8 && frame.seq == seq {
            // A board never sends a request: the port gave back what was written to it.
            return Err(BoardError::Echo { port: self.name.clone(), command });
        }
        if frame.code == command as u8 | 0x80 && frame.seq == seq {
            return Ok(Judged::Outcome(Read1::Reply(frame)));
        }
        if frame.code != Command::Error as u8 | 0x80 || frame.data.len() != 2 {
            return Ok(if frame.code & 0x80 != 0 {
                Judged::Foreign { code: frame.code, seq: frame.seq }
            } else {
                Judged::Skip
            });
        }
        let code = ErrorCode::from_byte(frame.data[0]);
        if frame.seq == seq && frame.data[1] == command as u8 {
            return match code {
                Some(ErrorCode::Busy) if matches!(command, Command::Run | Command::Result) => {
                    Err(BoardError::Board { command, code: ErrorCode::Busy })
                }
                Some(c @ (ErrorCode::BadCrc | ErrorCode::Busy)) => {
                    Ok(Judged::Outcome(Read1::Resend { reason: format!("error reply {c:?}"), executed: false }))
                }
                Some(code) => Err(BoardError::Board { command, code }),
                None => Err(BoardError::Reply {
                    command,
                    problem: MessageError::Field {
                        field: "error code",
                        got: frame.data[0] as u64,
                        expected: ErrorCode::BadCrc as u64,
                    },
                }),
            };
        }
        if frame.seq == 0 && frame.data[1] == 0 {
            // A frame error: our request arrived garbled, or line noise came before it (then
            // our request may still have run).
            let what = code.map_or_else(|| format!("code {}", frame.data[0]), |c| format!("{c:?}"));
            return Ok(Judged::Outcome(Read1::Resend { reason: format!("frame error {what}"), executed: true }));
        }
        Ok(Judged::Foreign { code: frame.code, seq: frame.seq })
    }
}
