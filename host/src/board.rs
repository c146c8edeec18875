//! The host's board client: the wire protocol of docs/protocol.md over a serial port
//! (`serialport`), one request at a time.
//!
//! Every request waits for its reply before the next is sent (so the board never answers
//! `Busy` in normal use). The rules:
//! - **Sequence numbers** run 1, 2, ..., 255, 1, ... (0 is skipped: the board answers a frame
//!   it cannot trust, a frame error, with sequence 0 and command 0).
//! - Each request is sent after a lone delimiter, which ends any partial frame left in the
//!   board's receiver (an empty frame is ignored by the board).
//! - **A reply** is the frame that echoes the sequence with `command | 0x80`; any other frame
//!   (a stale reply, a duplicate) is skipped. Bytes left from an earlier exchange (a reply
//!   that came too late, half a frame) are dropped before each request is sent.
//! - **Every read is bounded**: each reply must arrive within the timeout (default 2 s, at
//!   most [`MAX_TIMEOUT`]) plus the time the board needs for it, modelled from the bytes at
//!   the baud rate ([`MIN_BAUD`] to [`MAX_BAUD`]) and, for Evaluate and Nearest, the
//!   pipeline's clocks ([`pficp_fpga::pipeline::clocks_per_particle`]) on the board's
//!   lanes at its clock, never taken as slower than [`MIN_CLOCK_HZ`] whatever Identify says.
//!   A silent board is a [`BoardError::Timeout`] (saying how many bytes came that were no
//!   reply: a babbling line or a wrong baud rate), a port that goes away a
//!   [`BoardError::Io`], a board that only answers with another sequence number or for
//!   another command a [`BoardError::Unexpected`] at the same deadline, a port that sends
//!   back the request itself (a loopback adapter, a tty in echo mode) a
//!   [`BoardError::Echo`] at once.
//! - **Replies are checked**, not trusted: lengths and fields on decoding; acknowledged
//!   offsets, counts and sizes; Nearest's indices within the model and its cost the sum of
//!   its distances; the weights equal to [`pficp_fpga::weights::weights`] of the board's own
//!   costs (so weights that are all 0 or do not sum to `w_sum` are caught); a Status count
//!   that only rises and stays within the Run's; a Result whose pose is
//!   [`pficp_fpga::pf::pose_of`] its parameters. A failed check is a [`BoardError::Reply`]
//!   or [`BoardError::Filter`] naming the field.
//! - **Resends**: an error reply `BadCrc` or `Busy` for this request, a frame error (sequence
//!   0) or a reply frame that does not decode (bad CRC, bad COBS) sends the same request
//!   again with the same sequence, at most [`MAX_RETRIES`] times. A reply to an earlier copy
//!   is as good as one to the last. An Evaluate that appends to the stored costs (no FIRST,
//!   some poses) is not repeatable when the board may have executed it (a lost reply):
//!   then [`BoardError::ReplyLost`], and [`BoardClient::costs_and_weights`] starts the
//!   iteration over from its FIRST batch.
//! - Any other error reply is a [`BoardError::Board`] naming the code. `Busy` for Run or
//!   Result means the board is running a filter (docs/protocol.md, Running): it is not
//!   resent but reported as [`BoardError::Board`].
//! - **The on-board filter** ([`BoardClient::run`], [`BoardClient::status`],
//!   [`BoardClient::result`], [`BoardClient::wait_for_run`]): Run is answered at once, but
//!   a board that computes the whole filter before answering (the byte-level reference on
//!   a pseudo-terminal) is allowed the modelled run time ([`BoardClient::run_allowance`])
//!   for that answer too; the wait for the run's end is capped twice: no new iteration for
//!   the allowance, or more than the allowance times (iterations + 1) in all, is a
//!   [`BoardError::RunTimeout`]. A Run whose reply was lost is not simply sent again: Status
//!   tells whether the first copy is running; if not, Run is sent again (the filter is
//!   deterministic, so a repeated run gives the same result).

use pficp_fpga::format::{FxPoint, FxPose, WeightScale};
use pficp_fpga::messages::{
    load_request, parse_two_u16, two_u16, EvaluateReply, EvaluateRequest, Identity, MessageError, NearestReply,
    NearestRequest, ResultReply, RunState, StatusReply, WeightSummary, IDENTITY_BYTES, MAX_LOAD_POINTS, MAX_NEAREST,
    MAX_POSES, RESULT_BYTES, RUN_REPLY_BYTES, STATUS_BYTES,
};
use pficp_fpga::pf::PfConfig;
use pficp_fpga::pipeline::{clocks_per_particle, COST_MASK};
use pficp_fpga::protocol::{Command, Deframer, ErrorCode, Frame, FrameError, DELIMITER, VERSION};
use serialport::SerialPort;
use std::io::{ErrorKind, Read, Write};
use std::time::{Duration, Instant};

/// The board's nominal baud rate.
pub const DEFAULT_BAUD: u32 = 921_600;
/// The slowest baud rate the client opens a port at (below it a request takes minutes).
pub const MIN_BAUD: u32 = 9_600;
/// The fastest baud rate the client opens a port at (above any USB-serial bridge's).
pub const MAX_BAUD: u32 = 12_000_000;
/// Time allowed for each reply on top of the modelled transfer and compute time.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(2);
/// The longest time per reply the client accepts (`--timeout-ms`).
pub const MAX_TIMEOUT: Duration = Duration::from_secs(600);
/// The slowest clock the deadlines assume, whatever the board's Identify says (the design
/// runs at 50 MHz): a board that claims 1 Hz does not buy itself hours.
pub const MIN_CLOCK_HZ: u32 = 10_000_000;
/// Resends of one request after a corrupted exchange (so at most 3 attempts).
pub const MAX_RETRIES: usize = 2;
/// Largest model and scan the protocol addresses (12-bit indices).
pub const MAX_POINTS: usize = pficp_fpga::format::MAX_POINTS;
/// Most particles the board stores.
pub const MAX_PARTICLES: usize = pficp_fpga::weights::MAX_PARTICLES;
/// The modelled board time of a run is multiplied by this for the run's time limit.
pub const RUN_SAFETY: u32 = 4;
/// Time between two Status requests while a filter runs.
pub const DEFAULT_POLL: Duration = Duration::from_millis(50);

/// What went wrong talking to the board.
#[derive(Debug, thiserror::Error)]
pub enum BoardError {
    /// The serial port could not be opened.
    #[error("cannot open serial port {path}: {reason}")]
    Open {
        /// The path asked for.
        path: String,
        /// Why.
        reason: String,
    },
    /// Reading or writing the port failed (e.g. the adapter was unplugged).
    #[error("serial port {port}: {error} while {during} (was the board unplugged?)")]
    Io {
        /// The port.
        port: String,
        /// What the client was doing.
        during: String,
        /// The error (in the message only, so it is printed once).
        error: std::io::Error,
    },
    /// No reply within the time allowed.
    #[error(
        "the board on {port} did not answer {command:?} within {} ms{} (is it connected, configured and set to {baud} baud? \
         a board slower than its clock says, such as the simulated one, needs a larger --timeout-ms)",
        waited.as_millis(),
        noise_note(*.received)
    )]
    Timeout {
        /// The port.
        port: String,
        /// The request.
        command: Command,
        /// Time waited for the reply.
        waited: Duration,
        /// The port's baud rate.
        baud: u32,
        /// Bytes that arrived during the wait without making a reply.
        received: usize,
    },
    /// Only replies with another sequence number or for another command arrived in the time
    /// allowed (a board that numbers its replies wrongly, or another device on the port).
    #[error(
        "the board on {port} did not answer {command:?} (sequence {seq}) within {} ms; it sent a reply \
         {} with sequence {got_seq} instead",
        waited.as_millis(),
        reply_name(*.got_code)
    )]
    Unexpected {
        /// The port.
        port: String,
        /// The request.
        command: Command,
        /// The request's sequence number.
        seq: u8,
        /// The command code of the last reply that was not ours.
        got_code: u8,
        /// Its sequence number.
        got_seq: u8,
        /// Time waited.
        waited: Duration,
    },
    /// The port sent back the request itself: a loopback adapter or a tty in echo mode, not
    /// a board.
    #[error(
        "{port} sends back what is written to it ({command:?} came back as sent): a loopback adapter or a \
         terminal in echo mode, not the board"
    )]
    Echo {
        /// The port.
        port: String,
        /// The request that came back.
        command: Command,
    },
    /// The board answered with an error reply.
    #[error("the board answered {command:?} with error {code:?} ({})", *code as u8)]
    Board {
        /// The request.
        command: Command,
        /// The board's error code.
        code: ErrorCode,
    },
    /// Every attempt of a request ended in a corrupted exchange.
    #[error("no valid reply to {command:?} after {attempts} attempts (last: {last})")]
    Retries {
        /// The request.
        command: Command,
        /// Attempts made.
        attempts: usize,
        /// The last problem.
        last: String,
    },
    /// The reply to a request that is not repeatable was lost (the board may have executed it).
    #[error("the reply to {command:?} was lost ({reason}) and the request is not repeatable")]
    ReplyLost {
        /// The request.
        command: Command,
        /// What happened to the reply.
        reason: String,
    },
    /// A reply with a valid CRC whose contents do not fit the request.
    #[error("malformed reply to {command:?}: {problem}")]
    Reply {
        /// The request.
        command: Command,
        /// What does not fit (in the message only).
        problem: MessageError,
    },
    /// The request does not fit the board's limits (checked on the host).
    #[error("{0}")]
    Limit(String),
    /// The particle filter stopped for a reason of its own.
    #[error("the particle filter stopped: {0}")]
    Filter(String),
    /// The on-board filter stalled: the board answers Status and says "running", but its
    /// iteration count did not move for the whole allowance, or the run took longer than
    /// the allowance for every iteration.
    #[error(
        "the board on {port} did not finish the filter: no new iteration for {} ms, {} ms since Run \
         (allowed: {} ms without a new iteration, {} ms in all; {} ms modelled board time for the whole run); \
         last Status: {state:?}, {iterations} iterations",
        waited.as_millis(),
        total.as_millis(),
        stall_limit.as_millis(),
        overall_limit.as_millis(),
        modelled.as_millis()
    )]
    RunTimeout {
        /// The port.
        port: String,
        /// The time allowed without a new iteration.
        stall_limit: Duration,
        /// The time allowed in all.
        overall_limit: Duration,
        /// Time waited since the iteration count last changed (or since the wait began).
        waited: Duration,
        /// Time waited in all.
        total: Duration,
        /// The modelled board time of the run.
        modelled: Duration,
        /// The last Status state.
        state: RunState,
        /// Iterations the last Status reported.
        iterations: u16,
    },
}

/// The Timeout message's note on bytes that came but made no reply.
fn noise_note(received: usize) -> String {
    if received == 0 {
        String::new()
    } else {
        format!(" ({received} bytes came that were no valid reply: line noise, a wrong baud rate or another device?)")
    }
}

/// A reply code by its command's name.
fn reply_name(code: u8) -> String {
    Command::from_code(code).map_or_else(|| format!("with code {code:#04x}"), |c| format!("to {c:?}"))
}

/// Counters of one client's traffic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClientStats {
    /// Requests answered.
    pub requests: usize,
    /// Resends after a corrupted exchange.
    pub resends: usize,
    /// Evaluate sequences started over after a lost reply.
    pub restarts: usize,
    /// Bytes written.
    pub bytes_sent: usize,
    /// Bytes read.
    pub bytes_received: usize,
}

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

/// A client of one board on one serial port.
pub struct BoardClient {
    port: Box<dyn SerialPort>,
    name: String,
    baud: u32,
    timeout: Duration,
    seq: u8,
    deframer: Deframer,
    /// Bytes read but not yet given to the deframer, from `rx_at` on.
    rx: Vec<u8>,
    rx_at: usize,
    identity: Option<Identity>,
    sizes: (u16, u16),
    stored: usize,
    stats: ClientStats,
    /// The iteration cap of the last Run sent (a Status beyond it is a broken board).
    run_iterations: Option<u16>,
}

impl std::fmt::Debug for BoardClient {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BoardClient")
            .field("port", &self.name)
            .field("baud", &self.baud)
            .field("timeout", &self.timeout)
            .field("identity", &self.identity)
            .finish()
    }
}

impl BoardClient {
    /// Open the serial port at `path` (8N1, no flow control) and drop whatever it had
    /// buffered. `timeout` is the time allowed per reply (plus the modelled board time).
    pub fn open(path: &str, baud: u32, timeout: Duration) -> Result<Self, BoardError> {
        let open_error = |reason: String| BoardError::Open { path: path.to_string(), reason };
        if !(MIN_BAUD..=MAX_BAUD).contains(&baud) {
            return Err(open_error(format!("baud rate {baud}: the client runs {MIN_BAUD} to {MAX_BAUD} baud")));
        }
        if timeout.is_zero() || timeout > MAX_TIMEOUT {
            return Err(open_error(format!(
                "a timeout of {} ms per reply: the client allows 1 to {} ms",
                timeout.as_millis(),
                MAX_TIMEOUT.as_millis()
            )));
        }
        if !std::path::Path::new(path).exists() {
            return Err(open_error("no such device (is the board plugged in? check the path)".into()));
        }
        let port = serialport::new(path, baud)
            .timeout(timeout)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .open()
            .map_err(|e| open_error(e.to_string()))?;
        // Stale bytes from before (a previous run cut short) would only be skipped later.
        let _ = port.clear(serialport::ClearBuffer::All);
        let mut client = Self::from_port(port);
        client.name = path.to_string();
        client.baud = baud;
        client.timeout = timeout;
        Ok(client)
    }

    /// A client on a port opened elsewhere (e.g. one end of a pseudo-terminal), with the
    /// default timeout.
    pub fn from_port(port: Box<dyn SerialPort>) -> Self {
        let name = port.name().unwrap_or_else(|| "(unnamed port)".to_string());
        let baud = port.baud_rate().ok().filter(|&b| b > 0).unwrap_or(DEFAULT_BAUD);
        BoardClient {
            port,
            name,
            baud,
            timeout: DEFAULT_TIMEOUT,
            seq: 0,
            deframer: Deframer::default(),
            rx: Vec::new(),
            rx_at: 0,
            identity: None,
            sizes: (0, 0),
            stored: 0,
            stats: ClientStats::default(),
            run_iterations: None,
        }
    }

    /// Set the time allowed per reply (on top of the modelled board time; at most
    /// [`MAX_TIMEOUT`]).
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout.min(MAX_TIMEOUT);
    }

    /// The time allowed per reply (on top of the modelled board time).
    pub fn timeout(&self) -> Duration {
        self.timeout
    }

    /// The port's name.
    pub fn port_name(&self) -> &str {
        &self.name
    }

    /// The last identity read ([`Self::identify`]).
    pub fn identity(&self) -> Option<Identity> {
        self.identity
    }

    /// Traffic counters.
    pub fn stats(&self) -> ClientStats {
        self.stats
    }

    /// Version, limits, clock, baud and the current sizes.
    pub fn identify(&mut self) -> Result<Identity, BoardError> {
        let reply = self.transact(Command::Identify, Vec::new(), IDENTITY_BYTES, 0, true)?;
        let id = Identity::decode(&reply.data)
            .map_err(|problem| BoardError::Reply { command: Command::Identify, problem })?;
        self.identity = Some(id);
        self.sizes = (id.model_count, id.scan_count);
        self.stored = id.stored as usize;
        Ok(id)
    }

    /// Write the model store from point 0, in frames of [`MAX_LOAD_POINTS`], each
    /// acknowledged; `progress(done, total)` after each. Sizes are not changed.
    pub fn load_model(&mut self, points: &[FxPoint], progress: impl FnMut(usize, usize)) -> Result<(), BoardError> {
        self.load(Command::LoadModel, points, progress)
    }

    /// Write the scan store from point 0, as [`Self::load_model`].
    pub fn load_scan(&mut self, points: &[FxPoint], progress: impl FnMut(usize, usize)) -> Result<(), BoardError> {
        self.load(Command::LoadScan, points, progress)
    }

    fn load(
        &mut self,
        command: Command,
        points: &[FxPoint],
        mut progress: impl FnMut(usize, usize),
    ) -> Result<(), BoardError> {
        let what = if command == Command::LoadModel { "model" } else { "scan" };
        let max = self.max_points(command);
        if points.is_empty() || points.len() > max {
            return Err(BoardError::Limit(format!(
                "the {what} has {} points; the board holds 1 to {max}",
                points.len()
            )));
        }
        progress(0, points.len());
        let mut offset = 0;
        for chunk in points.chunks(MAX_LOAD_POINTS) {
            let reply = self.transact(command, load_request(offset as u16, chunk), 4, 0, true)?;
            let ack = parse_two_u16(&reply.data).map_err(|problem| BoardError::Reply { command, problem })?;
            if ack != (offset as u16, chunk.len() as u16) {
                return Err(BoardError::Reply {
                    command,
                    problem: MessageError::Field {
                        field: "offset, count",
                        got: ((ack.0 as u64) << 16) | ack.1 as u64,
                        expected: ((offset as u64) << 16) | chunk.len() as u64,
                    },
                });
            }
            offset += chunk.len();
            progress(offset, points.len());
        }
        Ok(())
    }

    fn max_points(&self, command: Command) -> usize {
        let id = self.identity;
        match command {
            Command::LoadModel => id.map_or(MAX_POINTS, |i| i.max_model as usize),
            _ => id.map_or(MAX_POINTS, |i| i.max_scan as usize),
        }
        .min(MAX_POINTS)
    }

    /// Set the numbers of model and scan points in use (1 to 4,096 each).
    pub fn set_sizes(&mut self, model: usize, scan: usize) -> Result<(), BoardError> {
        for (what, n, command) in [("model", model, Command::LoadModel), ("scan", scan, Command::LoadScan)] {
            if n == 0 || n > self.max_points(command) {
                return Err(BoardError::Limit(format!(
                    "{what} size {n}: the board holds 1 to {}",
                    self.max_points(command)
                )));
            }
        }
        let data = two_u16(model as u16, scan as u16);
        let reply = self.transact(Command::SetSizes, data.clone(), 4, 0, true)?;
        if reply.data != data {
            let got = parse_two_u16(&reply.data)
                .map_err(|problem| BoardError::Reply { command: Command::SetSizes, problem })?;
            return Err(BoardError::Reply {
                command: Command::SetSizes,
                problem: MessageError::Field {
                    field: "sizes",
                    got: ((got.0 as u64) << 16) | got.1 as u64,
                    expected: ((model as u64) << 16) | scan as u64,
                },
            });
        }
        self.sizes = (model as u16, scan as u16);
        Ok(())
    }

    /// One Evaluate frame: `poses` (at most [`MAX_POSES`]; none only with `last`) evaluated
    /// over the scan in use; with `first` the stored costs are forgotten first; with `last`
    /// every stored cost is weighed with `scale` afterwards.
    pub fn evaluate(
        &mut self,
        first: bool,
        last: bool,
        scale: WeightScale,
        poses: &[FxPose],
    ) -> Result<EvaluateReply, BoardError> {
        let n = poses.len();
        if n > MAX_POSES || (n == 0 && !last) {
            return Err(BoardError::Limit(format!(
                "an Evaluate frame carries 1 to {MAX_POSES} poses (or none to weigh), not {n}"
            )));
        }
        let after = if first { n } else { self.stored + n };
        if after == 0 || after > self.max_particles() {
            return Err(BoardError::Limit(format!(
                "{after} particle costs would be stored; the board holds 1 to {}",
                self.max_particles()
            )));
        }
        let request = EvaluateRequest { first, last, scale, poses: poses.to_vec() };
        let reply_bytes = 6 * n + if last { 11 + 2 * after } else { 0 };
        let clocks = n as u64 * clocks_per_particle(self.sizes.1 as usize, self.sizes.0 as usize, self.lanes())
            + if last { after as u64 + 16 } else { 0 };
        // Appending costs twice would corrupt the iteration: only FIRST or weigh-only repeat.
        let repeatable = first || n == 0;
        let reply = self.transact(Command::Evaluate, request.encode(), reply_bytes, clocks, repeatable)?;
        let r = EvaluateReply::decode(&reply.data, n, last)
            .map_err(|problem| BoardError::Reply { command: Command::Evaluate, problem })?;
        self.stored = after;
        if let Some(s) = &r.summary {
            if s.weights.len() != after {
                return Err(BoardError::Reply {
                    command: Command::Evaluate,
                    problem: MessageError::Field {
                        field: "stored",
                        got: s.weights.len() as u64,
                        expected: after as u64,
                    },
                });
            }
        }
        Ok(r)
    }

    /// Weigh the stored costs with `scale` (Evaluate with no poses and LAST).
    pub fn weigh(&mut self, scale: WeightScale) -> Result<WeightSummary, BoardError> {
        let r = self.evaluate(false, true, scale, &[])?;
        Ok(r.summary.expect("decoded with LAST"))
    }

    /// The costs of `poses` (1 to 256), in frames of [`MAX_POSES`] without LAST (the first
    /// with FIRST): they become the stored costs. Started over (at most [`MAX_RETRIES`]
    /// times) when a reply is lost.
    pub fn costs(&mut self, poses: &[FxPose]) -> Result<Vec<u64>, BoardError> {
        if poses.is_empty() || poses.len() > self.max_particles() {
            return Err(BoardError::Limit(format!(
                "{} particles: the board weighs 1 to {}",
                poses.len(),
                self.max_particles()
            )));
        }
        let mut restarts = 0;
        'again: loop {
            let mut costs = Vec::with_capacity(poses.len());
            for (k, batch) in poses.chunks(MAX_POSES).enumerate() {
                match self.evaluate(k == 0, false, WeightScale::default(), batch) {
                    Ok(r) => costs.extend(r.costs),
                    Err(BoardError::ReplyLost { .. }) if restarts < MAX_RETRIES => {
                        restarts += 1;
                        self.stats.restarts += 1;
                        continue 'again;
                    }
                    Err(e) => return Err(e),
                }
            }
            return Ok(costs);
        }
    }

    /// One filter iteration on the board: the costs of `poses` ([`Self::costs`]), then
    /// `scale_fn(costs)` chooses the weight scale and the stored costs are weighed
    /// ([`Self::weigh`]). Returns the costs and the weights (checked: one per pose, `w_sum`
    /// their sum).
    pub fn costs_and_weights(
        &mut self,
        poses: &[FxPose],
        scale_fn: impl FnOnce(&[u64]) -> WeightScale,
    ) -> Result<(Vec<u64>, WeightSummary), BoardError> {
        let costs = self.costs(poses)?;
        let scale = scale_fn(&costs);
        let summary = self.weigh(scale)?;
        let sum: u64 = summary.weights.iter().map(|&w| w as u64).sum();
        if sum == 0 {
            // Normalising would divide by zero: every weight NaN.
            return Err(BoardError::Filter(format!(
                "the board on {} returned {} weights that are all 0 (the best particle always weighs 1)",
                self.name,
                summary.weights.len()
            )));
        }
        if sum != summary.w_sum as u64 {
            return Err(BoardError::Reply {
                command: Command::Evaluate,
                problem: MessageError::Field { field: "w_sum", got: summary.w_sum as u64, expected: sum },
            });
        }
        let min = costs.iter().copied().min().unwrap_or(0);
        if summary.min_cost != min {
            return Err(BoardError::Reply {
                command: Command::Evaluate,
                problem: MessageError::Field { field: "min_cost", got: summary.min_cost, expected: min },
            });
        }
        if summary.weights != pficp_fpga::weights::weights(&costs, &scale) {
            return Err(BoardError::Filter(format!(
                "the board on {} returned weights that are not the exp table's for its own costs",
                self.name
            )));
        }
        Ok((costs, summary))
    }

    /// Nearest model point and squared distance of scan points `first .. first + count` at
    /// `pose`, in frames of [`MAX_NEAREST`]; `cost` is their sum.
    pub fn nearest(&mut self, first: usize, count: usize, pose: &FxPose) -> Result<NearestReply, BoardError> {
        if count == 0 || first + count > MAX_POINTS {
            return Err(BoardError::Limit(format!(
                "scan points {first}..{}: the board holds points 0..{MAX_POINTS}",
                first + count
            )));
        }
        let mut out = NearestReply { first: first as u16, cost: 0, results: Vec::with_capacity(count) };
        let mut at = first;
        while at < first + count {
            let n = (first + count - at).min(MAX_NEAREST);
            let request = NearestRequest { first: at as u16, count: n as u16, pose: *pose };
            let clocks = clocks_per_particle(n, self.sizes.0 as usize, self.lanes());
            let reply = self.transact(Command::Nearest, request.encode(), 10 + 7 * n, clocks, true)?;
            let bad = |problem| BoardError::Reply { command: Command::Nearest, problem };
            let r = NearestReply::decode(&reply.data, &request).map_err(bad)?;
            if let Some(&(i, _)) = r.results.iter().find(|&&(i, _)| i >= self.sizes.0) {
                return Err(bad(MessageError::Field {
                    field: "model index",
                    got: i as u64,
                    expected: self.sizes.0 as u64,
                }));
            }
            let sum = r.results.iter().fold(0u64, |c, n| (c + n.1) & COST_MASK);
            if r.cost != sum {
                return Err(bad(MessageError::Field { field: "cost", got: r.cost, expected: sum }));
            }
            out.cost += r.cost;
            out.results.extend(r.results);
            at += n;
        }
        Ok(out)
    }

    /// The board's clocks for the on-board filter of `cfg` over the sizes in use: the
    /// bound of [`run_clocks_bound`] with the board's lanes (1 before Identify).
    pub fn run_clocks(&self, cfg: &PfConfig) -> u64 {
        run_clocks_bound(cfg.particles, cfg.iterations, self.sizes.1 as usize, self.sizes.0 as usize, self.lanes())
    }

    /// The modelled board time of the on-board filter of `cfg` ([`Self::run_clocks`] at the
    /// board's clock; 100 MHz before Identify).
    pub fn modelled_run_time(&self, cfg: &PfConfig) -> Duration {
        Duration::from_secs_f64(self.run_clocks(cfg) as f64 / self.clock_hz())
    }

    /// The clock the deadlines assume: the board's (100 MHz before Identify), never below
    /// [`MIN_CLOCK_HZ`].
    fn clock_hz(&self) -> f64 {
        self.identity.map_or(100e6, |i| i.clock_hz.max(MIN_CLOCK_HZ) as f64)
    }

    /// How long a run of `cfg` may take before it is an error: [`RUN_SAFETY`] times the
    /// modelled board time plus the timeout per reply.
    pub fn run_allowance(&self, cfg: &PfConfig) -> Duration {
        self.modelled_run_time(cfg) * RUN_SAFETY + self.timeout
    }

    /// Start the on-board filter (Run) over the model and scan in use; it runs in the
    /// background. Particles (1 to the board's most) and iterations (at least 1) are checked
    /// here; the board checks the sizes. A board already running a filter answers `Busy`:
    /// [`BoardError::Board`].
    pub fn run(&mut self, cfg: &PfConfig) -> Result<(), BoardError> {
        let (n, k) = (cfg.particles as usize, cfg.iterations);
        if n == 0 || n > self.max_particles() || k == 0 {
            return Err(BoardError::Limit(format!(
                "{n} particles and {k} iterations: the board runs 1 to {} particles, at least 1 iteration",
                self.max_particles()
            )));
        }
        self.run_iterations = Some(cfg.iterations);
        let data = cfg.encode();
        // A board that computes before it answers (the timeless reference) needs the run's time.
        let extra = self.run_allowance(cfg).saturating_sub(self.timeout);
        let mut lost = 0;
        loop {
            match self.transact_with(Command::Run, data.clone(), RUN_REPLY_BYTES, extra, 0, false) {
                Ok(reply) => {
                    if reply.data != data[..RUN_REPLY_BYTES] {
                        let (p, i) = parse_two_u16(&reply.data)
                            .map_err(|problem| BoardError::Reply { command: Command::Run, problem })?;
                        return Err(BoardError::Reply {
                            command: Command::Run,
                            problem: MessageError::Field {
                                field: "particles, iterations",
                                got: ((p as u64) << 16) | i as u64,
                                expected: ((cfg.particles as u64) << 16) | cfg.iterations as u64,
                            },
                        });
                    }
                    return Ok(());
                }
                Err(BoardError::ReplyLost { command, reason }) => {
                    // The board may have started it: then it is running now.
                    if self.status()?.state == RunState::Running {
                        self.stats.restarts += 1;
                        return Ok(());
                    }
                    lost += 1;
                    if lost > MAX_RETRIES {
                        return Err(BoardError::ReplyLost { command, reason });
                    }
                    self.stats.resends += 1;
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// The on-board filter's state, iterations done and best cost so far (Status).
    pub fn status(&mut self) -> Result<StatusReply, BoardError> {
        let reply = self.transact(Command::Status, Vec::new(), STATUS_BYTES, 0, true)?;
        StatusReply::decode(&reply.data).map_err(|problem| BoardError::Reply { command: Command::Status, problem })
    }

    /// The finished filter's best particle, cost and pose (Result). A board still running
    /// answers `Busy`, one that has run no filter since power-up or reset `NoResult`: both
    /// [`BoardError::Board`].
    ///
    /// The reply is checked: at least 1 iteration and no more than the last Run asked for,
    /// the largest point distance within the cost, the pose the one
    /// [`pficp_fpga::pf::pose_of`] builds from the parameters.
    pub fn result(&mut self) -> Result<ResultReply, BoardError> {
        let reply = self.transact(Command::Result, Vec::new(), RESULT_BYTES, 0, true)?;
        let bad = |problem| BoardError::Reply { command: Command::Result, problem };
        let r = ResultReply::decode(&reply.data).map_err(bad)?;
        let cap = self.run_iterations.unwrap_or(u16::MAX);
        if r.iterations == 0 || r.iterations > cap {
            return Err(bad(MessageError::Field {
                field: "iterations",
                got: r.iterations as u64,
                expected: cap as u64,
            }));
        }
        if r.max_d2 > r.cost {
            return Err(bad(MessageError::Field { field: "max_d2 (above the cost)", got: r.max_d2, expected: r.cost }));
        }
        if r.pose != pficp_fpga::pf::pose_of(&r.params) {
            return Err(BoardError::Filter(format!(
                "the board on {} returned a pose that is not the one its parameters {:?} give",
                self.name, r.params
            )));
        }
        Ok(r)
    }

    /// Poll Status every `every` until the filter is done (state 2); `progress` gets each
    /// reply. Returns the last reply and the number of polls. A board still running whose
    /// iteration count has not changed for `limit` (counted from the call, then from each
    /// change) is a [`BoardError::RunTimeout`] naming `modelled`: a hung board is caught
    /// after `limit`, while a slow one that keeps making progress (the simulated board runs
    /// about 40 times slower than real time) is waited for, up to `limit` times (the Run's
    /// iterations + 1) in all, since the count must rise and stay within the Run's (a count
    /// that goes back or passes it is a [`BoardError::Filter`] at once). One that reports no
    /// run (state 0: reset?) is a [`BoardError::Filter`]; one that stops answering a
    /// [`BoardError::Timeout`] within the timeout per reply.
    pub fn wait_for_run(
        &mut self,
        limit: Duration,
        modelled: Duration,
        every: Duration,
        mut progress: impl FnMut(&StatusReply),
    ) -> Result<(StatusReply, usize), BoardError> {
        let start = Instant::now();
        let mut since = start;
        let mut last_iterations = None;
        let mut polls = 0;
        let overall = limit * (self.run_iterations.map_or(1, |k| k as u32) + 1);
        loop {
            let s = self.status()?;
            polls += 1;
            progress(&s);
            // The count only rises and stays within the Run's cap; otherwise the time limit,
            // restarted at every new count, would never end for a board whose counter
            // oscillates or wraps.
            if let Some(last) = last_iterations {
                if s.iterations < last {
                    return Err(BoardError::Filter(format!(
                        "the board on {} reports {} iterations after {last}: its iteration count went back",
                        self.name, s.iterations
                    )));
                }
            }
            if let Some(cap) = self.run_iterations {
                if s.iterations > cap {
                    return Err(BoardError::Filter(format!(
                        "the board on {} reports {} iterations, more than the {cap} it was asked for",
                        self.name, s.iterations
                    )));
                }
            }
            if last_iterations != Some(s.iterations) {
                if last_iterations.is_some() {
                    since = Instant::now();
                }
                last_iterations = Some(s.iterations);
            }
            match s.state {
                RunState::Done => return Ok((s, polls)),
                RunState::Idle => {
                    return Err(BoardError::Filter(format!(
                        "the board on {} reports no filter run (was it reset?)",
                        self.name
                    )))
                }
                RunState::Running => {}
            }
            let waited = since.elapsed();
            if waited >= limit || start.elapsed() >= overall {
                return Err(BoardError::RunTimeout {
                    port: self.name.clone(),
                    stall_limit: limit,
                    overall_limit: overall,
                    waited,
                    total: start.elapsed(),
                    modelled,
                    state: s.state,
                    iterations: s.iterations,
                });
            }
            std::thread::sleep(every.min(limit - waited).min(overall.saturating_sub(start.elapsed())));
        }
    }

    fn max_particles(&self) -> usize {
        self.identity.map_or(MAX_PARTICLES, |i| i.max_particles as usize).min(MAX_PARTICLES)
    }

    /// Lanes for the compute-time model: the board's once identified, else 1 (the slowest).
    fn lanes(&self) -> usize {
        self.identity.map_or(1, |i| i.lanes.max(1) as usize)
    }

    /// Time the board needs for a request of `request_bytes` on the wire, a reply of
    /// `reply_data` data bytes and `clocks` of compute.
    fn board_time(&self, request_bytes: usize, reply_data: usize, clocks: u64) -> Duration {
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
    fn transact(
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
    fn transact_with(
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

    fn io_error(&self, during: String, source: std::io::Error) -> BoardError {
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

/// An upper bound on the on-board filter's clocks for `particles` and all `iterations` over
/// `scan_points` and `model_points` on `lanes` lanes: the sequencer's exact count
/// ([`pficp_fpga::sequencer::run_clocks`]) with every data-dependent part at its largest
/// (49 temperature passes, a new best every iteration, the resampling pointer advancing
/// through every particle) and each evaluation taking the pipeline's
/// [`clocks_per_particle`] plus one clock: `particles x iterations + iterations + 1` poses.
pub fn run_clocks_bound(particles: u16, iterations: u16, scan_points: usize, model_points: usize, lanes: usize) -> u64 {
    use pficp_fpga::sequencer::{run_clocks, IterationShape};
    let n = particles as u64;
    let eval = 1 + clocks_per_particle(scan_points, model_points, lanes.max(1));
    let shape = |last: bool| IterationShape {
        particles: n,
        eval_clocks: (n + 1) * eval,
        temper_passes: 49,
        best_copied: true,
        resample_advances: (!last).then_some(n.saturating_sub(1)),
    };
    let k = iterations as usize;
    let shapes: Vec<IterationShape> = (0..k).map(|i| shape(i + 1 == k)).collect();
    run_clocks(eval, &shapes)
}

/// The Identify fields, one per line (`pficp board info`).
pub fn identity_text(port: &str, id: &Identity) -> String {
    let mut s = String::new();
    s += &format!("port              {port}\n");
    s += &format!(
        "protocol version  {}{}\n",
        id.version,
        if id.version == VERSION { String::new() } else { format!(" (this host speaks {VERSION})") }
    );
    s += &format!("lanes             {}\n", id.lanes);
    s += &format!("max model points  {}\n", id.max_model);
    s += &format!("max scan points   {}\n", id.max_scan);
    s += &format!("max particles     {}\n", id.max_particles);
    s += &format!("poses per frame   {}\n", id.max_poses);
    s += &format!("points per load   {}\n", id.max_load);
    s += &format!("nearest per frame {}\n", id.max_nearest);
    s += &format!("clock             {} Hz\n", id.clock_hz);
    s += &format!("baud              {}\n", id.baud);
    s += &format!("model points      {}\n", id.model_count);
    s += &format!("scan points       {}\n", id.scan_count);
    s += &format!("stored costs      {}\n", id.stored);
    s
}
