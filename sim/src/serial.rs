//! The host's end of the Verilated board's serial line, at the board's real bit timing:
//! [`SerialBoard`] shifts queued bytes onto `uart_rx` (8N1, `bit_clocks` clocks per bit,
//! back to back), decodes `uart_tx` by sampling each bit in its middle, and optionally runs
//! the byte-level reference ([`BoardModel`]) beside it, comparing every byte the board sends.

use crate::{BoardInputs, BoardPins, VerilatedBoard};
use pficp_fpga::board::{BoardConfig, BoardModel};
use std::collections::VecDeque;
use std::path::Path;

/// LED bit of the command engine's busy flag.
pub const LED_BUSY: u8 = 1 << 2;
/// LED bit of "the last answer was an error".
pub const LED_ERROR: u8 = 1 << 3;

/// The first byte where the board and the reference disagree.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ByteMismatch {
    /// Clock at which the board's byte was complete.
    pub clock: u64,
    /// Index of the byte among all the board sent.
    pub index: u64,
    /// What the reference sends there (`None`: nothing more).
    pub expected: Option<u8>,
    /// What the board sent (`None`: a framing error, stop bit low).
    pub actual: Option<u8>,
}

impl std::fmt::Display for ByteMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let show = |b: Option<u8>| b.map_or("nothing".to_string(), |b| format!("0x{b:02x}"));
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

#[derive(Clone, Copy, Debug)]
enum RxPhase {
    Idle,
    Start(u32),
    Data(u32, u8, u8),
    Stop(u32, u8),
}

/// The Verilated board with a serial line on each side and, optionally, the reference.
pub struct SerialBoard {
    board: VerilatedBoard,
    config: BoardConfig,
    bit: u32,
    inputs: BoardInputs,
    outgoing: VecDeque<u8>,
    /// The byte being shifted out to the board: 10 bits (start, data, stop), bit index,
    /// clocks left in the bit.
    shifting: Option<(u16, u32, u32)>,
    rx: RxPhase,
    received: Vec<u8>,
    sent_total: u64,
    received_total: u64,
    reference: Option<BoardModel>,
    expected: VecDeque<u8>,
    compared: u64,
    mismatch: Option<ByteMismatch>,
    quiet: u64,
    /// The board's bytes of the frame being received (compared at its delimiter).
    frame_bytes: Vec<Option<u8>>,
    /// Status replies of a running filter: not compared (a timeless reference cannot know
    /// the progress), and the reference's Status reply dropped.
    progress_frames: u64,
}

impl SerialBoard {
    /// The Verilated board for `config` (see [`VerilatedBoard::new`]), lines idle.
    pub fn new(config: BoardConfig) -> Self {
        let board = VerilatedBoard::new(&config);
        SerialBoard {
            board,
            config,
            bit: config.bit_clocks(),
            inputs: BoardInputs::default(),
            outgoing: VecDeque::new(),
            shifting: None,
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
            progress_frames: 0,
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
        self.quiet > 2 * self.bit as u64 && self.outgoing.is_empty()
    }

    /// One clock.
    pub fn step(&mut self) {
        // Host -> board.
        if self.shifting.is_none() {
            if let Some(b) = self.outgoing.pop_front() {
                self.shifting = Some(((b as u16) << 1 | 1 << 9, 0, self.bit));
                self.sent_total += 1;
                if let Some(r) = self.reference.as_mut() {
                    self.expected.extend(r.receive(b));
                }
            }
        }
        self.inputs.uart_rx = match self.shifting {
            Some((frame, i, _)) => frame >> i & 1 != 0,
            None => true,
        };
        self.board.set_inputs(&self.inputs);
        self.board.tick();
        if let Some((frame, i, left)) = self.shifting {
            self.shifting = if left > 1 {
                Some((frame, i, left - 1))
            } else if i < 9 {
                Some((frame, i + 1, self.bit))
            } else {
                None
            };
        }
        // Board -> host.
        let pins = self.board.pins();
        let line = pins.uart_tx;
        let half = self.bit / 2;
        self.rx = match self.rx {
            RxPhase::Idle if !line => RxPhase::Start(half),
            RxPhase::Idle => RxPhase::Idle,
            RxPhase::Start(1) => {
                if line {
                    RxPhase::Idle
                } else {
                    RxPhase::Data(self.bit, 0, 0)
                }
            }
            RxPhase::Start(n) => RxPhase::Start(n - 1),
            RxPhase::Data(1, k, v) => {
                let v = v | (line as u8) << k;
                if k == 7 {
                    RxPhase::Stop(self.bit, v)
                } else {
                    RxPhase::Data(self.bit, k + 1, v)
                }
            }
            RxPhase::Data(n, k, v) => RxPhase::Data(n - 1, k, v),
            RxPhase::Stop(1, v) => {
                self.byte_from_board(line.then_some(v));
                RxPhase::Idle
            }
            RxPhase::Stop(n, v) => RxPhase::Stop(n - 1, v),
        };
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
        self.frame_bytes.push(byte);
        if byte != Some(0) {
            return;
        }
        // A whole frame: a Status reply that says "running" is progress, not compared.
        let frame: Vec<u8> = self.frame_bytes.iter().map(|b| b.unwrap_or(0)).collect();
        let board_frames = std::mem::take(&mut self.frame_bytes);
        let progress = pficp_fpga::protocol::Frame::decode(&frame[..frame.len() - 1])
            .is_ok_and(|f| f.code == 0x88 && f.data.first() == Some(&1));
        if progress {
            self.progress_frames += 1;
            // Drop the reference's answer to the same request (up to its delimiter).
            while let Some(e) = self.expected.pop_front() {
                if e == 0 {
                    break;
                }
            }
            return;
        }
        let first_index = index + 1 - board_frames.len() as u64;
        for (k, actual) in board_frames.into_iter().enumerate() {
            let expected = self.expected.pop_front();
            self.compared += 1;
            if expected != actual && self.mismatch.is_none() {
                self.mismatch =
                    Some(ByteMismatch { clock: self.clocks(), index: first_index + k as u64, expected, actual });
            }
        }
    }

    /// Status replies of a running filter seen so far (not compared with the reference).
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
