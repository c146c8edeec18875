//! The host's end of the Verilated board's serial line, at the nominal bit timing:
//! [`SerialBoard`] shifts queued bytes onto `uart_rx` (8N1, back to back) and decodes
//! `uart_tx` by sampling each bit in its middle, and optionally runs the byte-level
//! reference ([`BoardModel`]) beside it.
//!
//! The host keeps exact rational time, independently of the RTL's phase accumulator: with
//! a bit period of `clocks / bits` ([`BitPeriod`]), a byte it starts at time `t` (in
//! 1/`bits` clock) drives bit `floor((c bits - t) / clocks)` at clock `c`, and back-to-back
//! bytes start exactly `10 clocks / bits` apart, so the board sees start edges at every
//! phase of its clock; a byte from the board is sampled `floor((2 j + 1) clocks / (2 bits))`
//! clocks after its falling edge (bit `j`, 0 the start bit). With the reference:
//! - every byte the board sends is compared with the reference's as it arrives, except
//!   the bytes of a Status reply, which are compared as a whole frame: equal to the
//!   reference's, or, when the board says "running" (a timeless reference cannot know
//!   the progress), a reply with the reference's sequence and command whose iteration
//!   count rises, stays within the run's total (the reference's) and whose best cost is
//!   no better than the run's final best ([`SerialBoard::progress_frames`] counts them);
//! - the LEDs are checked on every clock against their rule (docs/board.md): 0 the
//!   heartbeat, bit 26 of the clocks since power-up; 1 receive activity, lit from within a
//!   bit of the first start bit the board receives to between `2^21` clocks after the last
//!   stop bit (less, more: a bit period either way); 2 busy, lit whenever the board sends;
//!   3 the last reply was an error, checked as each reply frame ends.
//!
//! The first difference is a [`ByteMismatch`]; [`SerialBoard::comparison`] returns it,
//! and [`SerialBoard::expected_pending`] the reference's bytes the board has not sent.
use crate::{BoardInputs, BoardPins, VerilatedBoard};
use pficp_fpga::board::{BitPeriod, BoardConfig, BoardModel};
use pficp_fpga::protocol::messages::{RunState, StatusReply};
use pficp_fpga::protocol::{Command, Frame};
use std::collections::VecDeque;
use std::path::Path;

/// LED bit of the command engine's busy flag.
pub const LED_BUSY: u8 = 1 << 2;
/// LED bit of "the last answer was an error".
pub const LED_ERROR: u8 = 1 << 3;

/// The first place where the board and the reference disagree.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ByteMismatch {
    /// Clock at which it was seen.
    pub clock: u64,
    /// Index of the (first) byte concerned among all the board sent.
    pub index: u64,
    /// What the reference sends there (`None`: nothing more).
    pub expected: Option<u8>,
    /// What the board sent (`None`: a framing error, stop bit low).
    pub actual: Option<u8>,
    /// What is wrong, when it is more than a byte (a Status reply, an LED).
    pub problem: Option<String>,
}

impl std::fmt::Display for ByteMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let show = |b: Option<u8>| b.map_or("nothing".to_string(), |b| format!("0x{b:02x}"));
        if let Some(p) = &self.problem {
            return write!(f, "clock {}, after board byte {}: {p}", self.clock, self.index);
        }
        write!(
            f,
            "board byte {} (clock {}): the board sent {}, the reference {}",
            self.index,
            self.clock,
            show(self.actual),
            show(self.expected)
        )
    }
}

/// Clocks after the last received stop bit for which the receive LED stays lit
/// (`rx_glow` counts down from `2^22 - 1`; the LED is its bit 21).
pub const RX_GLOW_CLOCKS: u64 = 1 << 21;
/// The heartbeat LED's bit of the clock count.
pub const HEARTBEAT_BIT: u32 = 26;

/// The host's receiver: idle, or in a byte whose falling edge was at clock `edge`, next
/// sampling bit `j` (0 the start bit, 9 the stop bit), the data so far `v`.
#[derive(Clone, Copy, Debug)]
enum RxPhase {
    Idle,
    Byte { edge: u64, j: u64, v: u8 },
}

/// The Verilated board with a serial line on each side and, optionally, the reference.
pub struct SerialBoard {
    board: VerilatedBoard,
    config: BoardConfig,
    period: BitPeriod,
    /// Whole clocks in a bit, rounded up (the slack of the idle and LED rules).
    bit: u64,
    inputs: BoardInputs,
    outgoing: VecDeque<u8>,
    /// The byte being shifted out to the board: 10 bits (start, data, stop) and the time its
    /// start bit began, in 1/`period.bits` clock.
    shifting: Option<(u16, u64)>,
    /// When the last byte's stop bit ended, in 1/`period.bits` clock.
    line_free: u64,
    rx: RxPhase,
    received: Vec<u8>,
    sent_total: u64,
    received_total: u64,
    reference: Option<BoardModel>,
    expected: VecDeque<u8>,
    compared: u64,
    mismatch: Option<ByteMismatch>,
    quiet: u64,
    /// The board's bytes of the frame being received.
    frame_bytes: Vec<Option<u8>>,
    /// The frame being received is a Status reply (by the reference's): compared whole.
    status_frame: bool,
    /// Status replies of a running filter, checked by the progress rule.
    progress_frames: u64,
    /// The iteration count of the last running Status (it must not go back).
    last_progress: u16,
    /// Clock of the last bit shifted to the board (receive LED).
    rx_last: Option<u64>,
    /// The clock the host began its latest byte, and the last clock of the byte before.
    rx_byte_start: Option<u64>,
    rx_prev_last: Option<u64>,
    /// The last reply frame was an error (the error LED's rule).
    last_error: bool,
}

impl SerialBoard {
    /// The Verilated board for `config` (see [`VerilatedBoard::new`]), lines idle.
    pub fn new(config: BoardConfig) -> Self {
        let board = VerilatedBoard::new(&config);
        SerialBoard {
            board,
            config,
            period: config.bit_period(),
            bit: config.bit_period().boundary(1),
            inputs: BoardInputs::default(),
            outgoing: VecDeque::new(),
            shifting: None,
            line_free: 0,
            rx: RxPhase::Idle,
            received: Vec::new(),
            sent_total: 0,
            received_total: 0,
            reference: None,
            expected: VecDeque::new(),
            compared: 0,
            mismatch: None,
            quiet: 0,
            frame_bytes: Vec::new(),
            status_frame: false,
            progress_frames: 0,
            last_progress: 0,
            rx_last: None,
            rx_byte_start: None,
            rx_prev_last: None,
            last_error: false,
        }
    }

    /// Also run the byte-level reference and compare every byte the board sends with it
    /// (for a host that waits for each answer: the reference does not model `Busy`).
    pub fn with_reference(mut self) -> Self {
        self.reference = Some(BoardModel::new(self.config));
        self
    }

    /// The configuration.
    pub fn config(&self) -> BoardConfig {
        self.config
    }

    /// Queue bytes for the board.
    pub fn send(&mut self, bytes: &[u8]) {
        self.outgoing.extend(bytes.iter().copied());
    }

    /// Hold the reset button (or let it go).
    pub fn set_reset(&mut self, pressed: bool) {
        self.inputs.reset_n = !pressed;
    }

    /// The pins now.
    pub fn pins(&self) -> BoardPins {
        self.board.pins()
    }

    /// Clocks so far.
    pub fn clocks(&self) -> u64 {
        self.board.cycle()
    }

    /// Bytes sent to the board and received from it so far.
    pub fn byte_counts(&self) -> (u64, u64) {
        (self.sent_total, self.received_total)
    }

    /// Bytes compared with the reference so far, and the first mismatch.
    pub fn comparison(&self) -> (u64, Option<&ByteMismatch>) {
        (self.compared, self.mismatch.as_ref())
    }

    /// Reference bytes the board has not sent (yet).
    pub fn expected_pending(&self) -> usize {
        self.expected.len()
    }

    /// The reference, if running.
    pub fn reference(&self) -> Option<&BoardModel> {
        self.reference.as_ref()
    }

    /// Write a VCD of the board from now on.
    pub fn trace_to(&mut self, path: impl AsRef<Path>) -> std::io::Result<()> {
        self.board.trace_to(path)
    }

    /// Take the bytes received since the last call.
    pub fn take_received(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.received)
    }

    /// Nothing queued or on either line, and the engine not busy, for at least two bit
    /// periods (a frame's last byte reaches the engine a bit period after its stop bit).
    pub fn idle(&self) -> bool {
        self.quiet > 2 * self.bit && self.outgoing.is_empty()
    }

    /// One clock.
    pub fn step(&mut self) {
        // Host -> board: the line at clock `now`, in exact time (module documentation).
        let (n, d) = (self.period.clocks as u64, self.period.bits as u64);
        let now = self.clocks();
        if let Some((_, start)) = self.shifting {
            if now * d >= start + 10 * n {
                self.line_free = start + 10 * n;
                self.shifting = None;
            }
        }
        if self.shifting.is_none() {
            if let Some(b) = self.outgoing.pop_front() {
                // Back to back when the line became free within the last clock.
                let start = if self.line_free + d > now * d { self.line_free } else { now * d };
                self.shifting = Some(((b as u16) << 1 | 1 << 9, start));
                self.sent_total += 1;
                if let Some(r) = self.reference.as_mut() {
                    self.expected.extend(r.receive(b));
                }
            }
        }
        self.inputs.uart_rx = match self.shifting {
            Some((frame, start)) => frame >> ((now * d - start) / n) & 1 != 0,
            None => true,
        };
        self.board.set_inputs(&self.inputs);
        self.board.tick();
        // Board -> host: sample bit j at edge + floor((2 j + 1) n / (2 d)).
        let pins = self.board.pins();
        let line = pins.uart_tx;
        let now = self.clocks();
        self.rx = match self.rx {
            RxPhase::Idle if !line => RxPhase::Byte { edge: now, j: 0, v: 0 },
            RxPhase::Byte { edge, j, v } if now == edge + (2 * j + 1) * n / (2 * d) => match j {
                0 if line => RxPhase::Idle,
                0 => RxPhase::Byte { edge, j: 1, v },
                1..=8 => RxPhase::Byte { edge, j: j + 1, v: v | (line as u8) << (j - 1) },
                _ => {
                    self.byte_from_board(line.then_some(v));
                    RxPhase::Idle
                }
            },
            rx => rx,
        };
        if self.shifting.is_some() {
            let now = self.clocks();
            // A new byte: the one before ended more than a clock ago.
            if self.rx_last.is_none_or(|l| l + 1 < now) {
                self.rx_prev_last = self.rx_last;
                self.rx_byte_start = Some(now);
            }
            self.rx_last = Some(now);
        }
        if self.reference.is_some() && self.mismatch.is_none() {
            self.check_leds(pins.leds);
        }
        let active = self.shifting.is_some()
            || !self.outgoing.is_empty()
            || !matches!(self.rx, RxPhase::Idle)
            || !line
            || pins.leds & LED_BUSY != 0;
        self.quiet = if active { 0 } else { self.quiet + 1 };
    }

    fn byte_from_board(&mut self, byte: Option<u8>) {
        if let Some(b) = byte {
            self.received.push(b);
        }
        let index = self.received_total;
        self.received_total += 1;
        if self.reference.is_none() {
            return;
        }
        if self.frame_bytes.is_empty() {
            // A new frame: a Status reply (by the reference's next frame) is compared whole.
            self.status_frame = self.expected_frame().is_some_and(|f| f.code == Command::Status as u8 | 0x80);
        }
        self.frame_bytes.push(byte);
        if !self.status_frame {
            let expected = self.expected.pop_front();
            self.compared += 1;
            if expected != byte {
                self.note(ByteMismatch { clock: self.clocks(), index, expected, actual: byte, problem: None });
            }
        }
        if byte != Some(0) {
            return;
        }
        let board_bytes = std::mem::take(&mut self.frame_bytes);
        let first_index = index + 1 - board_bytes.len() as u64;
        let frame: Vec<u8> = board_bytes.iter().map(|b| b.unwrap_or(0)).collect();
        let decoded = Frame::decode(&frame[..frame.len() - 1]).ok();
        if self.status_frame {
            self.status_frame = false;
            self.compare_status(&board_bytes, decoded.as_ref(), first_index);
        }
        if decoded.as_ref().is_some_and(|f| f.code == Command::Run as u8 | 0x80) {
            self.last_progress = 0; // a new run: its count starts again
        }
        // The error LED shows whether this reply was an error, from before its first byte.
        self.last_error = decoded.is_some_and(|f| f.code == Command::Error as u8 | 0x80);
        let led = self.board.pins().leds & LED_ERROR != 0;
        if led != self.last_error {
            let problem =
                format!("LED 3 (last answer an error) is {}, the reply just sent says {}", led, self.last_error);
            self.note(ByteMismatch {
                clock: self.clocks(),
                index,
                expected: None,
                actual: None,
                problem: Some(problem),
            });
        }
    }

    /// The reference's next frame (its bytes up to the first delimiter), decoded.
    fn expected_frame(&self) -> Option<Frame> {
        let end = self.expected.iter().position(|&b| b == 0)?;
        let raw: Vec<u8> = self.expected.iter().take(end).copied().collect();
        Frame::decode(&raw).ok()
    }

    /// A Status reply from the board (`bytes`, decoded `frame`) against the reference's:
    /// equal, or a running board's progress within what the reference knows.
    fn compare_status(&mut self, bytes: &[Option<u8>], frame: Option<&Frame>, first_index: u64) {
        let end = self.expected.iter().position(|&b| b == 0).map_or(self.expected.len(), |e| e + 1);
        let expected: Vec<u8> = self.expected.drain(..end).collect();
        self.compared += bytes.len() as u64;
        let mismatch = |k: usize, problem: Option<String>| ByteMismatch {
            clock: 0,
            index: first_index + k as u64,
            expected: expected.get(k).copied(),
            actual: bytes.get(k).copied().flatten(),
            problem,
        };
        let running = frame.and_then(|f| StatusReply::decode(&f.data).ok().map(|s| (f, s)));
        let Some((frame, status)) = running.filter(|(_, s)| s.state == RunState::Running) else {
            // Not running: every byte as the reference's.
            let same = bytes.len() == expected.len() && bytes.iter().zip(&expected).all(|(b, e)| *b == Some(*e));
            if !same {
                let k = bytes
                    .iter()
                    .zip(&expected)
                    .position(|(b, e)| *b != Some(*e))
                    .unwrap_or(bytes.len().min(expected.len()));
                self.note(ByteMismatch { clock: self.clocks(), ..mismatch(k, None) });
            }
            return;
        };
        let reference = Frame::decode(&expected[..expected.len().saturating_sub(1)]).ok();
        let reference = reference.and_then(|f| StatusReply::decode(&f.data).ok().map(|s| (f.seq, s)));
        let problem = match reference {
            None => Some("the board says running; the reference's reply is no Status".to_string()),
            Some((seq, _)) if seq != frame.seq => {
                Some(format!("running Status with sequence {}, not {seq}", frame.seq))
            }
            Some((_, r)) if r.state != RunState::Done => {
                Some(format!("the board says running; the reference (which runs a filter at once) says {:?}", r.state))
            }
            Some((_, r)) if status.iterations > r.iterations => {
                Some(format!("running Status at {} iterations, beyond the run's {}", status.iterations, r.iterations))
            }
            Some(_) if status.iterations < self.last_progress => Some(format!(
                "running Status at {} iterations after {}: the count went back",
                status.iterations, self.last_progress
            )),
            Some((_, r)) if status.best_cost < r.best_cost => Some(format!(
                "running Status with best cost {}, better than the run's final best {}",
                status.best_cost, r.best_cost
            )),
            Some(_) => None,
        };
        self.progress_frames += 1;
        self.last_progress = status.iterations;
        if let Some(p) = problem {
            self.note(ByteMismatch { clock: self.clocks(), ..mismatch(0, Some(p)) });
        }
    }

    /// The LEDs against their rule (module documentation), on this clock.
    fn check_leds(&mut self, leds: u8) {
        let now = self.clocks();
        let bit = self.bit;
        let heartbeat = (now >> HEARTBEAT_BIT) & 1 == 1;
        // Lit for sure: from a bit after a byte's start bit to a bit before its glow ends
        // (the latest byte's, or the glow the byte before left); dark for sure: before any
        // start bit, or a bit after the glow ends. Within a bit of a byte that starts after
        // a dark pause, either.
        let lit_latest = match (self.rx_byte_start, self.rx_last) {
            (Some(start), Some(last)) => now > start + bit && now + bit < last + RX_GLOW_CLOCKS,
            _ => false,
        };
        let lit_before = self.rx_prev_last.is_some_and(|last| now + bit < last + RX_GLOW_CLOCKS);
        let rx = match self.rx_last {
            _ if lit_latest || lit_before => Some(true),
            Some(last) if now > last + RX_GLOW_CLOCKS + bit => Some(false),
            None => Some(false),
            _ => None,
        };
        let sending = !matches!(self.rx, RxPhase::Idle);
        let problem = if (leds & 1 != 0) != heartbeat {
            Some(format!("LED 0 (heartbeat) is {}, bit {HEARTBEAT_BIT} of clock {now} is {heartbeat}", leds & 1))
        } else if rx.is_some_and(|lit| (leds & 2 != 0) != lit) {
            Some(format!("LED 1 (receive activity) is {}, expected {}", (leds >> 1) & 1, rx.unwrap() as u8))
        } else if sending && leds & LED_BUSY == 0 {
            Some("LED 2 (busy) is dark while the board sends".to_string())
        } else {
            None
        };
        if let Some(p) = problem {
            let index = self.received_total;
            self.note(ByteMismatch { clock: now, index, expected: None, actual: None, problem: Some(p) });
        }
    }

    /// Keep the first mismatch.
    fn note(&mut self, m: ByteMismatch) {
        if self.mismatch.is_none() {
            self.mismatch = Some(m);
        }
    }

    /// Status replies of a running filter seen so far (checked by the progress rule).
    pub fn progress_frames(&self) -> u64 {
        self.progress_frames
    }

    /// Run `clocks` clocks.
    pub fn run(&mut self, clocks: u64) {
        for _ in 0..clocks {
            self.step();
        }
    }

    /// Run until [`idle`](Self::idle); `Err` with the clocks run if that takes more than
    /// `max_clocks`.
    pub fn run_until_idle(&mut self, max_clocks: u64) -> Result<u64, u64> {
        let start = self.clocks();
        self.quiet = 0;
        while !self.idle() {
            if self.clocks() - start > max_clocks {
                return Err(self.clocks() - start);
            }
            self.step();
        }
        Ok(self.clocks() - start)
    }

    /// Send `bytes`, run until idle, return what the board sent.
    pub fn exchange(&mut self, bytes: &[u8], max_clocks: u64) -> Result<Vec<u8>, u64> {
        self.send(bytes);
        self.run_until_idle(max_clocks)?;
        Ok(self.take_received())
    }
}
