//! The board: its generation parameters and (below) the byte-level reference of the whole
//! board (docs/protocol.md): given the bytes in, the bytes out.

#[cfg(feature = "rtl")]
pub mod crc_rtl;
#[cfg(feature = "rtl")]
pub mod digest_rtl;
#[cfg(feature = "rtl")]
pub mod engine_rtl;
#[cfg(feature = "rtl")]
pub mod frame_rx_rtl;
#[cfg(feature = "rtl")]
pub mod pass_queue_rtl;
#[cfg(feature = "rtl")]
pub mod reply_tx_rtl;
#[cfg(feature = "rtl")]
pub mod request_check_rtl;
#[cfg(feature = "rtl")]
pub mod scan_feeder_rtl;
#[cfg(feature = "rtl")]
pub mod top_rtl;
#[cfg(feature = "rtl")]
pub mod uart_rtl;

/// The generated board's nominal UART baud rate: 3 Mbaud, what common USB-serial bridges
/// (FT232R, CP2102N, CH340) reach. The host opens the port at this rate first.
pub const DEFAULT_BAUD: u32 = 3_000_000;

/// The widest UART bit period the RTL's phase accumulator holds: the reduced period's
/// `2 clocks` must fit [`PHASE_BITS`] bits.
pub const PHASE_BITS: u32 = 24;

/// What a board is generated with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoardConfig {
    /// Pipeline lanes (one of the RTL's supported counts).
    pub lanes: usize,
    /// Design clock in Hz (the oscillator; no DCM).
    pub clock_hz: u32,
    /// UART baud rate; the bit timing is exact on average ([`BitPeriod`]).
    pub baud: u32,
}

/// The default board: 8 lanes (16 with the on-board polish pass 80% of the LUTs,
/// docs/resources.md, "Why 8 lanes"), the design clock straight from the default pin map's
/// 50 MHz oscillator (constraints/pinmap.toml: no DCM), [`DEFAULT_BAUD`] (16 2/3 clocks per
/// bit).
/// This is the board `hdl-gen` generates and `pficp-sim-board` serves.
impl Default for BoardConfig {
    fn default() -> Self {
        BoardConfig { lanes: 8, clock_hz: 50_000_000, baud: DEFAULT_BAUD }
    }
}

impl BoardConfig {
    /// The board the co-simulation's fault and fuzz tests use: 4 lanes and 4 clocks per
    /// UART bit (25 Mbaud at 100 MHz), 8 1/3 times faster on the wire than the default.
    pub const FAST_SIM: BoardConfig = BoardConfig { lanes: 4, clock_hz: 100_000_000, baud: 25_000_000 };

    /// The UART's bit period, `clock_hz / baud` clocks as a reduced fraction (the one
    /// place the UARTs and the simulated host take their timing from).
    pub fn bit_period(&self) -> BitPeriod {
        BitPeriod::new(self.clock_hz, self.baud)
    }

    /// Why the RTL's UART cannot run at this clock and baud, if it cannot: fewer than 4
    /// clocks per bit, or a reduced period too wide for the phase accumulator.
    pub fn uart_problem(&self) -> Option<String> {
        if self.baud == 0 || self.clock_hz == 0 {
            return Some(format!("a UART at {} baud and {} Hz", self.baud, self.clock_hz));
        }
        let p = self.bit_period();
        if (p.clocks as u64) < 4 * p.bits as u64 {
            return Some(format!(
                "{} baud is too fast for a {} Hz clock: the UART needs at least 4 clocks per bit",
                self.baud, self.clock_hz
            ));
        }
        if 2 * p.clocks as u64 >= 1 << PHASE_BITS {
            return Some(format!(
                "{} baud at {} Hz: the bit period {}/{} clocks does not reduce enough for the UART's \
                 {PHASE_BITS}-bit phase (its numerator must be below {}; a baud rate sharing more factors \
                 with the clock, e.g. a multiple of 100, does)",
                self.baud,
                self.clock_hz,
                p.clocks,
                p.bits,
                1u32 << (PHASE_BITS - 1)
            ));
        }
        None
    }
}

/// A UART bit period of `clocks / bits` clocks (a reduced fraction: `clock_hz / baud`
/// divided by their greatest common divisor). The RTL's UARTs place the `k`-th bit boundary
/// after a start edge at clock `ceil(k clocks / bits)`: within one clock of the exact time,
/// and the error never accumulates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BitPeriod {
    /// Clocks (numerator).
    pub clocks: u32,
    /// Bits (denominator).
    pub bits: u32,
}

impl BitPeriod {
    /// `clock_hz / baud`, reduced (both nonzero).
    pub fn new(clock_hz: u32, baud: u32) -> BitPeriod {
        assert!(clock_hz > 0 && baud > 0, "a bit period of {clock_hz} / {baud} clocks");
        let (mut a, mut b) = (clock_hz, baud);
        while b != 0 {
            (a, b) = (b, a % b);
        }
        BitPeriod { clocks: clock_hz / a, bits: baud / a }
    }

    /// Clocks per bit.
    pub fn clocks_per_bit(&self) -> f64 {
        self.clocks as f64 / self.bits as f64
    }

    /// Whole clocks in `k` bits, rounded up (the clock of the `k`-th bit boundary after a
    /// start edge at clock 0).
    pub fn boundary(&self, k: u64) -> u64 {
        (k * self.clocks as u64).div_ceil(self.bits as u64)
    }
}

impl std::fmt::Display for BitPeriod {
    /// `16 2/3` (or `4` when whole).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (whole, rest) = (self.clocks / self.bits, self.clocks % self.bits);
        if rest == 0 {
            write!(f, "{whole}")
        } else {
            write!(f, "{whole} {rest}/{}", self.bits)
        }
    }
}

use crate::common::format::{unpack_point, FxPoint, WeightScale, MAX_POINTS};
use crate::filter::pf::ConfigError;
use crate::filter::weights::{weights, COST_MAX, MAX_PARTICLES};
use crate::protocol::layout::{pose_from_bytes, POINT_BYTES, POSE_BYTES};
use crate::protocol::messages::{
    two_u16, EvaluateReply, Identity, NearestReply, ResultReply, RunState, StatusReply, WeightSummary,
    EVALUATE_HEADER_BYTES, FLAG_FIRST, FLAG_LAST, LOAD_HEADER_BYTES, MAX_LOAD_ENTRIES, MAX_LOAD_POINTS, MAX_NEAREST,
    MAX_POSES, MODEL_WORDS, NEAREST_REQUEST_BYTES, NORMALS_OFFSET, RUN_REPLY_BYTES, TABLE_ENTRIES, TABLE_ENTRY_BYTES,
    TABLE_ENTRY_MASK, TWO_U16_BYTES, W_SUM_MASK,
};
use crate::protocol::run_request::{execute, RunOutcome, RunRequest};
use crate::protocol::{digest_update, Command, Deframer, ErrorCode, Frame, DIGEST_INIT, DIGEST_NONE};
use crate::surface::{evaluate_stored, Scored, StoredSearch};

/// The byte-level reference of the whole board (docs/protocol.md): the receiver
/// ([`Deframer`]), the command engine, the model and scan stores (4,096 48-bit words each,
/// [`crate::common::format::pack_point`]), the sizes, the stored particle costs and the outcome of
/// the last on-board filter run. It models a host that waits for every answer, so the
/// board is always idle when a byte arrives and `Busy` never happens (the RTL tests check
/// the busy rules). Being timeless, it runs the whole filter ([`crate::filter::pf::run`]) when Run
/// arrives, and the polish after it ([`crate::protocol::run_request::execute`]), so it is never "running": Status says 0 or 2, never 1.
#[derive(Clone, Debug)]
pub struct BoardModel {
    config: BoardConfig,
    model: Vec<u64>,
    normals: Vec<u64>,
    table: Vec<u16>,
    scan: Vec<u64>,
    model_count: u16,
    scan_count: u16,
    costs: Vec<u64>,
    outcome: Option<RunOutcome>,
    digest: u32,
    deframer: Deframer,
}

fn le(data: &[u8]) -> u64 {
    data.iter().rev().fold(0u64, |v, &b| (v << 8) | b as u64)
}

impl BoardModel {
    /// The board after power-up: stores all zero, sizes 0, no stored costs, receiver idle.
    pub fn new(config: BoardConfig) -> Self {
        BoardModel {
            config,
            model: vec![0; MAX_POINTS],
            normals: vec![0; MAX_POINTS],
            table: vec![0; TABLE_ENTRIES],
            scan: vec![0; MAX_POINTS],
            model_count: 0,
            scan_count: 0,
            costs: Vec::with_capacity(MAX_PARTICLES),
            outcome: None,
            digest: DIGEST_NONE,
            deframer: Deframer::default(),
        }
    }

    /// What the board was generated with.
    pub fn config(&self) -> BoardConfig {
        self.config
    }

    /// `reset_n`: the receiver forgets a partial frame and the filter's outcome (Status
    /// state 0 again); stores, sizes and stored costs are kept.
    pub fn reset(&mut self) {
        self.deframer = Deframer::default();
        self.outcome = None;
    }

    /// One byte from the host (the board idle: a host that waits for every answer). Returns
    /// the bytes the board sends because of it: an encoded reply frame, delimiter included,
    /// when the byte is a delimiter that completes a frame; otherwise nothing.
    pub fn receive(&mut self, byte: u8) -> Vec<u8> {
        match self.deframer.push(byte) {
            None => Vec::new(),
            Some(Ok(frame)) => self.execute(&frame).encode(),
            Some(Err(e)) => Frame::error(0, e.code(), 0).encode(),
        }
    }

    /// [`Self::receive`] every byte in turn; the replies concatenated.
    pub fn receive_all(&mut self, bytes: &[u8]) -> Vec<u8> {
        bytes.iter().flat_map(|&b| self.receive(b)).collect()
    }

    /// Execute one frame that passed the receiver's checks (command, sequence, data) and
    /// return the reply: `command | 0x80` with the sequence echoed, or an error reply with
    /// the sequence and the command. A rejected command changes nothing.
    pub fn execute(&mut self, frame: &Frame) -> Frame {
        match self.run(frame) {
            Ok(data) => Frame { code: frame.code | 0x80, seq: frame.seq, data },
            Err(e) => Frame::error(frame.seq, e, frame.code),
        }
    }

    /// The model store (4,096 packed points).
    pub fn model_store(&self) -> &[u64] {
        &self.model
    }

    /// The normal store (4,096 packed normals, `crate::surface::FxNormal`; LoadModel's words
    /// from `messages::NORMALS_OFFSET`).
    pub fn normal_store(&self) -> &[u64] {
        &self.normals
    }

    /// The cell table (4,097 entries of 13 bits, `grid::Grid::first`).
    pub fn table_store(&self) -> &[u16] {
        &self.table
    }

    /// The scan store (4,096 packed points).
    pub fn scan_store(&self) -> &[u64] {
        &self.scan
    }

    /// The model digest (docs/protocol.md, "Resident model").
    pub fn model_digest(&self) -> u32 {
        self.digest
    }

    /// Model and scan points in use.
    pub fn sizes(&self) -> (u16, u16) {
        (self.model_count, self.scan_count)
    }

    /// The stored particle costs, in particle order (at most 256).
    pub fn stored_costs(&self) -> &[u64] {
        &self.costs
    }

    /// The outcome of the last Run (the filter and the polish) since power-up or reset.
    pub fn run_outcome(&self) -> Option<&RunOutcome> {
        self.outcome.as_ref()
    }

    /// What Status answers: state 0 before any run, else 2 with the outcome's iterations
    /// and best cost.
    pub fn status(&self) -> StatusReply {
        match &self.outcome {
            None => StatusReply::IDLE,
            Some(o) => {
                StatusReply { state: RunState::Done, iterations: o.filter.iterations, best_cost: o.filter.best.cost }
            }
        }
    }

    fn points(store: &[u64], range: std::ops::Range<usize>) -> Vec<FxPoint> {
        store[range].iter().map(|&w| unpack_point(w)).collect()
    }

    /// The grid search and the surface residual over the stores as they are
    /// (docs/pipeline.md, "The neighbour pipeline" and "The surface residual"): what the RTL
    /// computes for `scan` at `pose`, whatever the stores hold.
    fn search(&self, scan: &[FxPoint], pose: &crate::common::format::FxPose) -> Scored {
        evaluate_stored(&self.model, &self.normals, &self.table, scan, pose)
    }

    /// The command engine: checks in the order of docs/protocol.md (code, lengths,
    /// capacities), then the effect and the reply data.
    fn run(&mut self, f: &Frame) -> Result<Vec<u8>, ErrorCode> {
        use ErrorCode::{BadLength, OverCapacity, UnknownCommand};
        // Only the request codes 0x01..=0x0A: not 0x00, not Error (0x7F), not bit 7 set.
        // (Never running a filter, the model never answers Busy; the RTL does, while one runs.)
        let command = match f.code {
            0x01..=0x0a => Command::from_code(f.code).ok_or(UnknownCommand)?,
            _ => return Err(UnknownCommand),
        };
        let d = &f.data[..];
        match command {
            Command::Identify => {
                if !d.is_empty() {
                    return Err(BadLength);
                }
                let c = self.config;
                let id = Identity::of_board(
                    c.lanes as u8,
                    c.clock_hz,
                    c.baud,
                    self.model_count,
                    self.scan_count,
                    self.costs.len() as u16,
                );
                Ok(id.with_digest(self.digest).encode())
            }
            Command::LoadModel | Command::LoadScan => {
                if d.len() < LOAD_HEADER_BYTES {
                    return Err(BadLength);
                }
                let (offset, count) = (le(&d[0..2]) as usize, le(&d[2..4]) as usize);
                if count == 0 || count > MAX_LOAD_POINTS || d.len() != LOAD_HEADER_BYTES + POINT_BYTES * count {
                    return Err(BadLength);
                }
                let words = if command == Command::LoadModel { MODEL_WORDS } else { MAX_POINTS };
                if offset + count > words {
                    return Err(OverCapacity);
                }
                for (k, p) in d[LOAD_HEADER_BYTES..].chunks_exact(POINT_BYTES).enumerate() {
                    let a = offset + k;
                    match command {
                        Command::LoadScan => self.scan[a] = le(p),
                        _ if a < NORMALS_OFFSET => self.model[a] = le(p),
                        _ => self.normals[a - NORMALS_OFFSET] = le(p),
                    }
                }
                if command == Command::LoadModel {
                    if offset == 0 {
                        self.digest = DIGEST_INIT;
                    }
                    self.digest = digest_update(self.digest, d);
                }
                Ok(two_u16(offset as u16, count as u16))
            }
            Command::LoadTable => {
                if d.len() < LOAD_HEADER_BYTES {
                    return Err(BadLength);
                }
                let (offset, count) = (le(&d[0..2]) as usize, le(&d[2..4]) as usize);
                if count == 0 || count > MAX_LOAD_ENTRIES || d.len() != LOAD_HEADER_BYTES + TABLE_ENTRY_BYTES * count {
                    return Err(BadLength);
                }
                if offset + count > TABLE_ENTRIES {
                    return Err(OverCapacity);
                }
                for (k, e) in d[LOAD_HEADER_BYTES..].chunks_exact(TABLE_ENTRY_BYTES).enumerate() {
                    self.table[offset + k] = le(e) as u16 & TABLE_ENTRY_MASK;
                }
                self.digest = digest_update(self.digest, d);
                Ok(two_u16(offset as u16, count as u16))
            }
            Command::SetSizes => {
                if d.len() != TWO_U16_BYTES {
                    return Err(BadLength);
                }
                let (m, s) = (le(&d[0..2]) as usize, le(&d[2..4]) as usize);
                if !(1..=MAX_POINTS).contains(&m) || !(1..=MAX_POINTS).contains(&s) {
                    return Err(OverCapacity);
                }
                (self.model_count, self.scan_count) = (m as u16, s as u16);
                Ok(d.to_vec())
            }
            Command::Evaluate => {
                if d.len() < EVALUATE_HEADER_BYTES {
                    return Err(BadLength);
                }
                let (flags, n) = (d[0], d[5] as usize);
                let (first, last) = (flags & FLAG_FIRST != 0, flags & FLAG_LAST != 0);
                if n > MAX_POSES || d.len() != EVALUATE_HEADER_BYTES + POSE_BYTES * n || (n == 0 && !last) {
                    return Err(BadLength);
                }
                let after = if first { n } else { self.costs.len() + n };
                if self.model_count == 0 || self.scan_count == 0 || after == 0 || after > MAX_PARTICLES {
                    return Err(OverCapacity);
                }
                if first {
                    self.costs.clear();
                }
                let mut costs = Vec::with_capacity(n);
                if n > 0 {
                    let scan = Self::points(&self.scan, 0..self.scan_count as usize);
                    for p in d[EVALUATE_HEADER_BYTES..].chunks_exact(POSE_BYTES) {
                        costs.push(self.search(&scan, &pose_from_bytes(p)).cost & COST_MAX);
                    }
                }
                self.costs.extend_from_slice(&costs);
                let summary = last.then(|| {
                    let scale = WeightScale { pre_shift: (d[1] & 63) as u32, q_mul: le(&d[2..5]) as u32 & 0x1_ffff };
                    let w = weights(&self.costs, &scale);
                    WeightSummary {
                        min_cost: self.costs.iter().copied().min().unwrap_or(COST_MAX),
                        w_sum: w.iter().fold(0u32, |s, &x| (s + x as u32) & W_SUM_MASK),
                        weights: w,
                    }
                });
                Ok(EvaluateReply { costs, summary }.encode())
            }
            Command::Nearest => {
                if d.len() != NEAREST_REQUEST_BYTES {
                    return Err(BadLength);
                }
                let (first, count) = (le(&d[0..2]) as usize, le(&d[2..4]) as usize);
                if count == 0 || count > MAX_NEAREST {
                    return Err(BadLength);
                }
                if self.model_count == 0 || self.scan_count == 0 || first + count > self.scan_count as usize {
                    return Err(OverCapacity);
                }
                let scan = Self::points(&self.scan, first..first + count);
                let e = self.search(&scan, &pose_from_bytes(&d[4..]));
                Ok(NearestReply { first: first as u16, cost: e.cost, results: e.nearest }.encode())
            }
            Command::Run => {
                // The length, the filter's capacities and the sizes (the checks of every
                // command), then the polish's points (the engine's, after them).
                let request = RunRequest::decode(d);
                if let Err(ConfigError::Length(_)) = request {
                    return Err(BadLength);
                }
                if matches!(request, Err(ConfigError::Capacity(..))) || self.model_count == 0 || self.scan_count == 0 {
                    return Err(OverCapacity);
                }
                let request = request.map_err(|_| OverCapacity)?;
                let scan = Self::points(&self.scan, 0..self.scan_count as usize);
                let polish_scan = Self::points(&self.scan, 0..request.polish.points as usize);
                let search = StoredSearch { ram: &self.model, normals: &self.normals, first: &self.table };
                let outcome = execute(&request, |pose| self.search(&scan, pose).evaluated(), &search, &polish_scan);
                self.outcome = Some(outcome);
                Ok(d[..RUN_REPLY_BYTES].to_vec())
            }
            Command::Status => {
                if !d.is_empty() {
                    return Err(BadLength);
                }
                Ok(self.status().encode())
            }
            Command::Result => {
                if !d.is_empty() {
                    return Err(BadLength);
                }
                let o = self.outcome.as_ref().ok_or(ErrorCode::NoResult)?;
                Ok(ResultReply::of(o).encode())
            }
            Command::Error => Err(UnknownCommand),
        }
    }
}
