//! A board served on a pseudo-terminal: the one server behind the client's tests, the
//! board bench (the byte-level reference) and `pficp-sim-board` (the Verilated board).
//! The board's end of the line runs a *turn* closure again and again (read what the host
//! sent, answer) until it returns false or the server is stopped; the host opens the other
//! end by its path (`/dev/pts/N`) with the real serialport crate, or takes it as a port.

use serialport::{SerialPort, TTYPort};
use std::io::{ErrorKind, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

/// What a board does with the bytes it read: the bytes it answers, or `None` to close its
/// end of the line.
pub type Handler = Box<dyn FnMut(&[u8]) -> Option<Vec<u8>> + Send>;

/// A pseudo-terminal pair: the board's end and the host's (kept open, so a host closing
/// its end does not hang up the line and the next host can open the same path).
pub struct PtyLine {
    /// The board's end.
    pub board_end: TTYPort,
    /// The host's end, until taken.
    pub client_end: Option<TTYPort>,
    /// The host's end's path.
    pub path: String,
}

impl PtyLine {
    /// A new pair.
    pub fn new() -> std::io::Result<PtyLine> {
        let (board_end, client_end) = TTYPort::pair().map_err(std::io::Error::other)?;
        let path = client_end.name().ok_or_else(|| std::io::Error::other("the pseudo-terminal has no name"))?;
        Ok(PtyLine { board_end, client_end: Some(client_end), path })
    }

    /// Run `turn` on the board's end in this thread until it returns false or `stop` is
    /// set.
    pub fn serve_here(&mut self, stop: &AtomicBool, mut turn: impl FnMut(&mut TTYPort) -> bool) {
        while !stop.load(Ordering::Relaxed) && turn(&mut self.board_end) {}
    }
}

/// One read of at most `buf.len()` bytes: `Some(n)` (0 when the read timed out or was
/// interrupted), `None` when the line is closed.
pub fn read_some(port: &mut TTYPort, buf: &mut [u8]) -> Option<usize> {
    match port.read(buf) {
        Ok(0) => None,
        Ok(n) => Some(n),
        Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted) => Some(0),
        Err(_) => None,
    }
}

/// The board's end running in a thread, and the host's end.
pub struct PtyBoard {
    /// The host's end (a tty with a path), until taken.
    pub client_end: Option<TTYPort>,
    /// Its path (`/dev/pts/N`).
    pub path: String,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl PtyBoard {
    /// A new pseudo-terminal whose board end runs `turn` in a thread (reads time out after
    /// `read_timeout`) until it returns false or the board is dropped. Dropping the board's
    /// end at the end closes the line: the host's reads fail.
    pub fn run(
        read_timeout: Duration,
        turn: impl FnMut(&mut TTYPort) -> bool + Send + 'static,
    ) -> std::io::Result<PtyBoard> {
        let mut line = PtyLine::new()?;
        line.board_end.set_timeout(read_timeout).map_err(std::io::Error::other)?;
        let (client_end, path) = (line.client_end.take(), line.path.clone());
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let mut turn = turn;
        let thread = std::thread::spawn(move || line.serve_here(&flag, &mut turn));
        Ok(PtyBoard { client_end, path, stop, thread: Some(thread) })
    }

    /// Serve `handler`: every read's bytes in, its answer out.
    pub fn serve(mut handler: Handler) -> std::io::Result<PtyBoard> {
        let mut buf = [0u8; 4096];
        PtyBoard::run(Duration::from_millis(20), move |port| match read_some(port, &mut buf) {
            None => false,
            Some(0) => true,
            Some(n) => match handler(&buf[..n]) {
                Some(out) => out.is_empty() || port.write_all(&out).is_ok(),
                None => false,
            },
        })
    }

    /// The byte-level reference board ([`pficp_fpga::board::BoardModel`]) of `config`.
    pub fn reference(config: pficp_fpga::board::BoardConfig) -> std::io::Result<PtyBoard> {
        let mut board = pficp_fpga::board::BoardModel::new(config);
        PtyBoard::serve(Box::new(move |bytes| Some(board.receive_all(bytes))))
    }

    /// A client on this line (takes the host's end).
    pub fn client(&mut self) -> Option<super::BoardClient> {
        Some(super::BoardClient::from_port(Box::new(self.client_end.take()?)))
    }

    /// Stop the board's thread and wait for it.
    pub fn stop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for PtyBoard {
    fn drop(&mut self) {
        self.stop();
    }
}
