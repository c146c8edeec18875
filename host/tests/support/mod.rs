//! A board served on a pseudo-terminal (the library's server, `pficp::board::pty`): a thread
//! reads the bytes the client writes to one end and answers through a handler (by default
//! the byte-level reference, `pficp_fpga::board::BoardModel`). The client gets the other
//! end, a real tty with a path. Also the clouds and the uploaded client the tests share.

#![allow(dead_code)]

use pficp::board::pty::{read_some, PtyBoard as Server};
use pficp_fpga::board::{BoardConfig, BoardModel};
use serialport::{SerialPort, TTYPort};
use std::io::{ErrorKind, Write};
use std::time::Duration;

pub use pficp::board::pty::Handler;

/// The library's pseudo-terminal server (`pficp::board::pty`), with the tests' defaults:
/// a failure to make a pseudo-terminal fails the test.
pub struct PtyBoard {
    server: Server,
    /// Its path (`/dev/pts/N`).
    pub path: String,
}

impl PtyBoard {
    fn wrap(server: std::io::Result<Server>) -> PtyBoard {
        let server = server.expect("a pseudo-terminal");
        PtyBoard { path: server.path.clone(), server }
    }

    /// Serve `handler` on a new pseudo-terminal.
    pub fn serve(handler: Handler) -> PtyBoard {
        PtyBoard::wrap(Server::serve(handler))
    }

    /// A line that sends `next()` every millisecond, whatever it is sent (which it drops):
    /// a babbling device.
    pub fn babbling(mut next: impl FnMut() -> Vec<u8> + Send + 'static) -> PtyBoard {
        let mut buf = [0u8; 4096];
        PtyBoard::wrap(Server::run(Duration::from_millis(1), move |port: &mut TTYPort| {
            if read_some(port, &mut buf).is_none() {
                return false;
            }
            match port.write_all(&next()) {
                Ok(()) => true,
                // The client does not read and the line is full: babble on.
                Err(e) => e.kind() == ErrorKind::TimedOut || e.kind() == ErrorKind::Interrupted,
            }
        }))
    }

    /// The reference board.
    pub fn reference() -> PtyBoard {
        PtyBoard::wrap(Server::reference(BoardConfig::default()))
    }

    /// The reference board of `config` on a line that ignores the baud rate (a
    /// pseudo-terminal), as [`Self::reference`].
    pub fn reference_of(config: BoardConfig) -> PtyBoard {
        PtyBoard::wrap(Server::reference(config))
    }

    /// The reference board of `config` on a line that keeps the baud rate: the rate the
    /// host set its end to (a pseudo-terminal's two ends share their settings, so the
    /// board's end reads it) carries the host's bytes to a UART at `config.baud` and the
    /// board's replies back ([`uart_resample`]): the board understands the host, and the
    /// host the board, only at `config.baud`, as on a real serial line.
    pub fn reference_at_rate(config: BoardConfig) -> PtyBoard {
        let mut board = BoardModel::new(config);
        let mut buf = [0u8; 4096];
        PtyBoard::wrap(Server::run(Duration::from_millis(20), move |port: &mut TTYPort| {
            let n = match read_some(port, &mut buf) {
                None => return false,
                Some(0) => return true,
                Some(n) => n,
            };
            let host = port.baud_rate().unwrap_or(0);
            let out = board.receive_all(&uart_resample(&buf[..n], host, config.baud));
            let out = uart_resample(&out, config.baud, host);
            out.is_empty() || port.write_all(&out).is_ok()
        }))
    }

    /// A client on this line (takes the client's end).
    pub fn client(&mut self) -> pficp::board::BoardClient {
        self.server.client().expect("one client per board")
    }
}

/// The bytes a UART at `to` baud receives from a line that carries `bytes` back to back at
/// `from` baud (8N1): it waits for a low line, checks the start bit half a bit later,
/// samples the data bits in their middles and drops a byte whose stop bit is low. `bytes`
/// when the rates are equal; at other rates, what a board or a host set to the wrong rate
/// reads (garbage, or nothing).
pub fn uart_resample(bytes: &[u8], from: u32, to: u32) -> Vec<u8> {
    if from == to {
        return bytes.to_vec();
    }
    if from == 0 || to == 0 {
        return Vec::new();
    }
    let bits: Vec<bool> =
        bytes.iter().flat_map(|&b| (0..10).map(move |i| ((b as u16) << 1 | 1 << 9) >> i & 1 != 0)).collect();
    let (from, bit) = (from as f64, 1.0 / to as f64);
    let level = |t: f64| bits.get((t * from).floor() as usize).copied().unwrap_or(true);
    let end = bits.len() as f64 / from;
    let (mut out, mut t) = (Vec::new(), 0.0f64);
    while t < end {
        // The next start: the line already low, or the next high-to-low boundary.
        let edge = if !level(t) {
            t
        } else {
            match ((t * from).floor() as usize + 1..bits.len()).find(|&k| !bits[k]) {
                Some(k) => k as f64 / from,
                None => break,
            }
        };
        if level(edge + 0.5 * bit) {
            t = edge + 0.5 * bit;
            continue;
        }
        let v = (1..=8).filter(|&j| level(edge + (j as f64 + 0.5) * bit)).fold(0u8, |v, j| v | 1 << (j - 1));
        if level(edge + 9.5 * bit) {
            out.push(v);
        }
        t = edge + 9.5 * bit;
    }
    out
}

/// The byte-level reference as a handler.
pub fn reference_handler() -> Handler {
    let mut board = BoardModel::new(BoardConfig::default());
    Box::new(move |bytes| Some(board.receive_all(bytes)))
}

/// The reference, frame by frame, with a say of its own: `intercept(frame, board)` returns
/// `Some(bytes)` to answer a valid frame with those bytes instead (empty: stay silent), or
/// `None` to let the reference execute it. Frame errors are answered as the reference does.
pub fn intercepting_handler(
    mut intercept: impl FnMut(&pficp_fpga::protocol::Frame, &mut BoardModel) -> Option<Vec<u8>> + Send + 'static,
) -> Handler {
    use pficp_fpga::protocol::{Deframer, Frame};
    let mut board = BoardModel::new(BoardConfig::default());
    let mut deframer = Deframer::default();
    Box::new(move |bytes| {
        let mut out = Vec::new();
        for &b in bytes {
            match deframer.push(b) {
                None => {}
                Some(Ok(frame)) => match intercept(&frame, &mut board) {
                    Some(bytes) => out.extend(bytes),
                    None => out.extend(board.execute(&frame).encode()),
                },
                Some(Err(e)) => out.extend(Frame::error(0, e.code(), 0).encode()),
            }
        }
        Some(out)
    })
}

// ---- Clouds, poses and an uploaded board, for the client's tests.

use pficp::board::BoardClient;
use pficp_fpga::common::format::{point, FxPoint, FxPose};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub fn cloud(n: usize, seed: u64) -> Vec<FxPoint> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| point([rng.gen_range(-0.9..0.9), rng.gen_range(-0.9..0.9), rng.gen_range(-0.9..0.9)])).collect()
}

pub fn poses(n: usize, seed: u64) -> Vec<FxPose> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let (a, s) = (rng.gen_range(-0.3..0.3f64), rng.gen_range(0.9..1.1));
            let t = [rng.gen_range(-0.1..0.1), rng.gen_range(-0.1..0.1), rng.gen_range(-0.1..0.1)];
            let (c, si) = (a.cos() * s, a.sin() * s);
            FxPose::from_f64(&[c, -si, 0.0, si, c, 0.0, 0.0, 0.0, s], &t)
        })
        .collect()
}

/// The model gridded as the host uploads it.
/// The normals the host uploads with `grid(model)` (`quantise::stored_normals`).
pub fn normals(model: &[FxPoint]) -> Vec<pficp_fpga::surface::FxNormal> {
    pficp::board::quantise::stored_normals(&grid(model))
}

pub fn grid(model: &[FxPoint]) -> pficp_fpga::search::grid::Grid {
    pficp_fpga::search::grid::Grid::build(model).expect("a model in the cube")
}

/// What the board computes for `run` after [`upload`] of `model` and `scan`: the filter
/// over `scan`, the polish over its first `run.polish.points` points.
pub fn run_reference(
    model: &[FxPoint],
    scan: &[FxPoint],
    run: &pficp_fpga::protocol::run_request::RunRequest,
) -> pficp_fpga::protocol::run_request::RunOutcome {
    let (g, n) = (grid(model), normals(model));
    let search = pficp_fpga::surface::GridSearch { grid: &g, normals: &n };
    let polish_scan = &scan[..run.polish.points as usize];
    pficp_fpga::protocol::run_request::execute(
        run,
        |p| pficp_fpga::surface::evaluate(&g, &n, scan, p),
        &search,
        polish_scan,
    )
}

/// A client on the reference with the model and scan loaded and sized.
pub fn loaded(model: &[FxPoint], scan: &[FxPoint]) -> (PtyBoard, BoardClient) {
    let mut board = PtyBoard::reference();
    let mut client = board.client();
    upload(&mut client, model, scan);
    (board, client)
}

/// Identify, load the model gridded (protocol 4: sorted by cell, with its normals and cell table; the
/// board's indices are then the grid's, `grid(model).order` maps them to `model`'s) and
/// the scan, set the sizes.
pub fn upload(client: &mut BoardClient, model: &[FxPoint], scan: &[FxPoint]) {
    client.identify().unwrap();
    let g = grid(model);
    client.load_grid(&g, &pficp::board::quantise::stored_normals(&g), |_, _| {}).unwrap();
    client.load_scan(scan, |_, _| {}).unwrap();
    client.set_sizes(model.len(), scan.len()).unwrap();
}

/// A Run over the first 30 stored scan points: the filter of `particles`, `iterations`,
/// `seed` about the identity, then a polish of `steps` steps from its pose alone and
/// `winner_steps` more, the scale solved.
pub fn run_config(
    particles: u16,
    iterations: u16,
    seed: u32,
    steps: u8,
    winner_steps: u8,
) -> pficp_fpga::protocol::run_request::RunRequest {
    let filter = pficp_fpga::filter::pf::PfConfig {
        particles,
        iterations,
        temper_exp: 12,
        centre: [0, 0, 0, 1 << pficp_fpga::filter::pf::SCALE_FRAC, 0, 0, 0],
        sigma0: [20_000, 20_000, 20_000, 1 << 14, 1 << 15, 1 << 15, 1 << 15],
        floor: [50; 7],
        seed,
        thr_cost: 0,
        thr_max: 0,
    };
    let polish = pficp_fpga::protocol::run_request::PolishRequest {
        points: 30,
        steps,
        winner_steps,
        scale: pficp_fpga::polish::ScaleStep::Solved,
        hypotheses: vec![],
    };
    pficp_fpga::protocol::run_request::RunRequest { filter, polish }
}
