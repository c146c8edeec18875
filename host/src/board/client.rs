//! The board client: the wire protocol of docs/protocol.md over a serial port
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
//!   board's evaluation clocks bounded ([`pficp_fpga::surface::surface_residual::evaluation_clocks_bound`]:
//!   any pose, any model of that size; within 20% of the brute-force pipeline's) on the board's
//!   lanes at its clock, never taken as slower than [`MIN_CLOCK_HZ`] whatever Identify says.
//!   A silent board is a [`BoardError::Timeout`] (saying how many bytes came that were no
//!   reply: a babbling line or a wrong baud rate), a port that goes away a
//!   [`BoardError::Io`], a board that only answers with another sequence number or for
//!   another command a [`BoardError::Unexpected`] at the same deadline, a port that sends
//!   back the request itself (a loopback adapter, a tty in echo mode) a
//!   [`BoardError::Echo`] at once.
//! - **Replies are checked**, not trusted: lengths and fields on decoding; acknowledged
//!   offsets, counts and sizes; Nearest's indices within the model and its cost the sum of
//!   its distances; the weights equal to [`pficp_fpga::filter::weights::weights`] of the board's own
//!   costs (so weights that are all 0 or do not sum to `w_sum` are caught); a Status count
//!   that only rises and stays within the Run's; a Result whose pose is
//!   [`pficp_fpga::filter::pf::pose_of`] its parameters. A failed check is a [`BoardError::Reply`]
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

use super::BoardError;
use pficp_fpga::common::format::FxPose;
use pficp_fpga::protocol::messages::{
    Identity, MessageError, NearestReply, NearestRequest, IDENTITY_BYTES, MAX_NEAREST,
};
use pficp_fpga::protocol::versions::capabilities;
use pficp_fpga::protocol::{Command, Deframer, VERSION};
use pficp_fpga::search::grid::{Grid, CAP_D2};
use pficp_fpga::search::pipeline::COST_MASK;
use pficp_fpga::surface::surface_residual::evaluation_clocks_bound;
use pficp_fpga::surface::FxNormal;
use serialport::SerialPort;
use std::time::Duration;

/// The generated board's baud rate (`pficp_fpga::board::DEFAULT_BAUD`), the first the
/// client tries ([`PROBE_BAUDS`]).
pub const DEFAULT_BAUD: u32 = pficp_fpga::board::DEFAULT_BAUD;
/// The rates the client tries, in this order, when it is given none ([`BoardClient::connect`]):
/// the generated board's default, then 921,600 (the default of earlier boards) and 115,200
/// (the common rate of USB-serial bridges).
pub const PROBE_BAUDS: [u32; 3] = [DEFAULT_BAUD, 921_600, 115_200];
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
pub const BOARD_MAX_STORE_POINTS: usize = pficp_fpga::common::format::MAX_POINTS;
/// Most particles the board stores.
pub const BOARD_MAX_PARTICLES: usize = pficp_fpga::filter::weights::MAX_PARTICLES;
/// The modelled board time of a run is multiplied by this for the run's time limit.
pub const RUN_SAFETY: u32 = 4;
/// Time between two Status requests while a filter runs: the registration's latency waits
/// up to this long after the board is done (a run takes about 0.1 s, so 5 ms, the period
/// before, cost 2.5 ms on average), while a poll costs the line about 30 bytes (0.1 ms at
/// 3 Mbaud; at 115,200 baud its 2.6 ms exceed the period and the polls go back to back) and
/// the board nothing (Status is answered beside the running filter).
pub const DEFAULT_POLL: Duration = Duration::from_millis(1);

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
    /// Model uploads skipped: the board already held the model (its digest matched).
    pub resident: usize,
}

mod evaluate;
mod filter;
mod link;
mod load;

pub use filter::{run_clocks_bound, run_clocks_for};

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
    /// The starts of the polish of the last Run sent (the Result's winner is one of them).
    run_starts: Option<usize>,
    /// `Grid::order` of the grid last uploaded whole ([`BoardClient::load_grid`]): the
    /// host's index of each stored model point. `None` after any other model or table write.
    grid_order: Option<Vec<u16>>,
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

    /// [`Self::connect`] with a caller's link options as given (`--baud`, `--timeout-ms`):
    /// options out of range are refused with one line naming the CLI's flag, before the
    /// port is opened.
    pub fn connect_with(path: &str, baud: Option<u32>, timeout_ms: u64) -> anyhow::Result<(Self, Identity)> {
        if timeout_ms == 0 || timeout_ms > MAX_TIMEOUT.as_millis() as u64 {
            anyhow::bail!("--timeout-ms {timeout_ms}: must be 1 to {}", MAX_TIMEOUT.as_millis());
        }
        if let Some(baud) = baud.filter(|b| !(MIN_BAUD..=MAX_BAUD).contains(b)) {
            anyhow::bail!("--baud {baud}: the client runs {MIN_BAUD} to {MAX_BAUD} baud");
        }
        Ok(Self::connect(path, baud, Duration::from_millis(timeout_ms))?)
    }

    /// Open `path` and identify the board. With `baud`, at that rate only. Without, at each
    /// rate of [`PROBE_BAUDS`] in turn (the port opened again each time) until Identify gets
    /// a valid reply, which must report that rate; if none answers,
    /// [`BoardError::NoAnswer`] naming the rates tried. A port that cannot be opened, that
    /// fails or echoes, ends the probe at once.
    pub fn connect(path: &str, baud: Option<u32>, timeout: Duration) -> Result<(Self, Identity), BoardError> {
        match baud {
            Some(b) => {
                let mut client = Self::open(path, b, timeout)?;
                let id = client.identify()?;
                Ok((client, id))
            }
            None => Self::probe(path, &PROBE_BAUDS, timeout),
        }
    }

    /// [`Self::connect`] without a baud rate, trying `bauds` in order.
    pub fn probe(path: &str, bauds: &[u32], timeout: Duration) -> Result<(Self, Identity), BoardError> {
        let mut tried = Vec::new();
        for &baud in bauds {
            let mut client = Self::open(path, baud, timeout)?;
            match client.identify() {
                Ok(id) if id.baud == baud => return Ok((client, id)),
                Ok(id) => {
                    return Err(BoardError::BaudMismatch { port: path.to_string(), opened: baud, reported: id.baud })
                }
                Err(e @ (BoardError::Open { .. } | BoardError::Io { .. } | BoardError::Echo { .. })) => return Err(e),
                Err(e) => tried.push((baud, no_answer(&e))),
            }
        }
        Err(BoardError::NoAnswer { port: path.to_string(), tried })
    }

    /// The baud rate the port was opened at.
    pub fn baud(&self) -> u32 {
        self.baud
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
            run_starts: None,
            grid_order: None,
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

    /// [`Self::load_grid`] unless the board already holds `grid` and `normals`: a fresh
    /// Identify whose model digest is the one this upload would leave
    /// (`messages::grid_digest`; docs/protocol.md, "Resident model"). True when it uploaded.
    pub fn ensure_grid(
        &mut self,
        grid: &Grid,
        normals: &[FxNormal],
        progress: impl FnMut(usize, usize),
    ) -> Result<bool, BoardError> {
        let id = self.identify()?;
        if capabilities(id.version).grid_with_normals
            && normals.len() == grid.points.len()
            && id.model_digest == pficp_fpga::protocol::messages::grid_digest(grid, normals)
        {
            self.grid_order = Some(grid.order.clone());
            self.stats.resident += 1;
            return Ok(false);
        }
        self.load_grid(grid, normals, progress)?;
        Ok(true)
    }

    /// Nearest model point and squared distance of scan points `first .. first + count` at
    /// `pose`, in frames of [`MAX_NEAREST`]; `cost` is the sum of their costs (before
    /// protocol 4 the distances, checked equal; since, the surface residuals, checked between
    /// the capped points' `CAP_D2` each and `CAP_D2` a point). The indices are the
    /// board's: positions in its model store (for a gridded model, the sorted points;
    /// [`Self::nearest_model`] gives the host's), and a protocol 3 board reports a point
    /// farther than the cap as index 0 at distance [`CAP_D2`].
    pub fn nearest(&mut self, first: usize, count: usize, pose: &FxPose) -> Result<NearestReply, BoardError> {
        if count == 0 || first + count > BOARD_MAX_STORE_POINTS {
            return Err(BoardError::Limit(format!(
                "scan points {first}..{}: the board holds points 0..{BOARD_MAX_STORE_POINTS}",
                first + count
            )));
        }
        let mut out = NearestReply { first: first as u16, cost: 0, results: Vec::with_capacity(count) };
        let mut at = first;
        while at < first + count {
            let n = (first + count - at).min(MAX_NEAREST);
            let request = NearestRequest { first: at as u16, count: n as u16, pose: *pose };
            let clocks = evaluation_clocks_bound(n, self.sizes.0 as usize, self.lanes());
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
            // Before protocol 4 the cost is the distances' sum. Since, it is the residuals'
            // sum, which the reply does not carry: each residual is at most CAP_D2 and a
            // capped point's is CAP_D2, so the cost lies between those bounds.
            if self.identity.is_some_and(|i| !capabilities(i.version).grid_with_normals) {
                let sum = r.results.iter().fold(0u64, |c, n| (c + n.1) & COST_MASK);
                if r.cost != sum {
                    return Err(bad(MessageError::Field { field: "cost", got: r.cost, expected: sum }));
                }
            } else {
                let capped = r.results.iter().filter(|n| n.1 >= CAP_D2).count() as u64;
                let (low, high) = (capped * CAP_D2, r.results.len() as u64 * CAP_D2);
                if r.cost < low || r.cost > high {
                    let expected = if r.cost < low { low } else { high };
                    return Err(bad(MessageError::Field { field: "cost", got: r.cost, expected }));
                }
            }
            out.cost += r.cost;
            out.results.extend(r.results);
            at += n;
        }
        Ok(out)
    }

    /// [`Self::nearest`] in the host's terms: for each scan point, the index of its nearest
    /// model point in the model as the host has it (before the grid's sort: through
    /// [`Grid::order`] of the last [`Self::load_grid`]) and the squared distance, or `None`
    /// when the distance is capped (`CAP_D2`, no point within `h`). After a plain
    /// [`Self::load_model`] (a board of protocol 1 or 2, brute force, no cap) the indices
    /// are the upload's as they are.
    pub fn nearest_model(
        &mut self,
        first: usize,
        count: usize,
        pose: &FxPose,
    ) -> Result<Vec<Option<(usize, u64)>>, BoardError> {
        let r = self.nearest(first, count, pose)?;
        let order = self.grid_order.as_deref();
        if let Some(o) = order {
            if let Some(&(i, _)) = r.results.iter().find(|&&(i, _)| i as usize >= o.len()) {
                return Err(BoardError::Reply {
                    command: Command::Nearest,
                    problem: MessageError::Field { field: "model index", got: i as u64, expected: o.len() as u64 },
                });
            }
        }
        Ok(upload_order(&r.results, order))
    }

    fn max_particles(&self) -> usize {
        self.identity.map_or(BOARD_MAX_PARTICLES, |i| i.max_particles as usize).min(BOARD_MAX_PARTICLES)
    }

    /// Lanes for the compute-time model: the board's once identified, else 1 (the slowest).
    fn lanes(&self) -> usize {
        self.identity.map_or(1, |i| i.lanes.max(1) as usize)
    }
}

/// Why Identify got no valid reply at one rate of the probe, in a few words.
fn no_answer(e: &BoardError) -> String {
    match e {
        BoardError::Timeout { waited, received: 0, .. } => format!("no reply within {} ms", waited.as_millis()),
        BoardError::Timeout { waited, received, .. } => {
            format!("{received} bytes but no valid reply within {} ms", waited.as_millis())
        }
        BoardError::Retries { attempts, .. } => format!("no valid reply in {attempts} attempts"),
        e => e.to_string(),
    }
}

/// Nearest results (stored index, squared distance) in the host's model order: through
/// `order` ([`Grid::order`]) with a capped distance as `None` when the model was gridded,
/// the indices as they are otherwise. Every index must lie within `order`.
pub fn upload_order(results: &[(u16, u64)], order: Option<&[u16]>) -> Vec<Option<(usize, u64)>> {
    results
        .iter()
        .map(|&(i, d2)| match order {
            Some(_) if d2 >= CAP_D2 => None,
            Some(o) => Some((o[i as usize] as usize, d2)),
            None => Some((i as usize, d2)),
        })
        .collect()
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
