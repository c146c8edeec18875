//! `pficp.Board`: a board on a serial port, opened and identified once, then used by
//! `register(..., board=...)` and `Tracker(..., board=...)`.

use crate::errors::{board_error, request_error};
use pficp::board::BoardClient;
use pficp_fpga::protocol::messages::Identity;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::Mutex;

/// A PF-ICP board on a serial port (a USB-serial bridge, or `pficp-sim-board`'s
/// pseudo-terminal). Opening it identifies it: a missing, silent or echoing board raises
/// `pficp.BoardError` at once. `baud=None` tries the board's rates in turn (3,000,000,
/// 921,600, 115,200); `timeout_ms` is the time allowed per reply (`None`: 2,000 ms), as
/// the CLI's flags.
///
/// A `Tracker` given the board holds it until the tracker is closed (`tracker.close()`, or
/// when it is garbage-collected); use as a context manager to close the port.
#[pyclass(module = "pficp", frozen, name = "Board")]
pub struct Board {
    port: String,
    /// The open link; `None` once closed or while a tracker holds it.
    client: Mutex<Option<BoardClient>>,
    /// What holds the link when it is not here.
    lent: Mutex<Option<&'static str>>,
}

/// Why the link is not at hand.
pub enum Unavailable {
    /// Closed, or held by this.
    Lent(Option<&'static str>),
    /// A call panicked while it held the link.
    Poisoned,
}

impl Board {
    /// Run `f` on the open link with the GIL released, waiting for another thread's call
    /// to finish first (without the GIL, so that the waiting thread cannot hold up the
    /// one that holds the link).
    pub fn with_link<R: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut BoardClient) -> R + Send) -> PyResult<R> {
        py.detach(|| {
            let mut guard = self.client.lock().map_err(|_| Unavailable::Poisoned)?;
            match guard.as_mut() {
                Some(client) => Ok(f(client)),
                None => Err(Unavailable::Lent(self.lent.lock().ok().and_then(|l| *l))),
            }
        })
        .map_err(|e| self.unavailable(e))
    }

    /// Take the link out of the board (a tracker's), waiting as [`Self::with_link`] does.
    pub fn take_link(&self, py: Python<'_>, holder: &'static str) -> PyResult<BoardClient> {
        py.detach(|| {
            let mut guard = self.client.lock().map_err(|_| Unavailable::Poisoned)?;
            let lent = self.lent.lock().ok().and_then(|l| *l);
            let client = guard.take().ok_or(Unavailable::Lent(lent))?;
            if let Ok(mut l) = self.lent.lock() {
                *l = Some(holder);
            }
            Ok(client)
        })
        .map_err(|e| self.unavailable(e))
    }

    /// Give a taken link back.
    pub fn give_back(&self, client: BoardClient) {
        if let Ok(mut link) = self.client.lock() {
            *link = Some(client);
        }
        if let Ok(mut lent) = self.lent.lock() {
            *lent = None;
        }
    }

    fn unavailable(&self, e: Unavailable) -> PyErr {
        PyValueError::new_err(match e {
            Unavailable::Lent(Some(h)) => format!("board {}: held by {h} (close it first)", self.port),
            Unavailable::Lent(None) => format!("board {}: closed", self.port),
            Unavailable::Poisoned => format!("board {}: a call failed while it held the link", self.port),
        })
    }

    /// The board's serial port.
    pub fn port_name(&self) -> &str {
        &self.port
    }
}

fn identity_dict<'py>(py: Python<'py>, id: &Identity) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("version", id.version)?;
    d.set_item("lanes", id.lanes)?;
    d.set_item("clock_hz", id.clock_hz)?;
    d.set_item("baud", id.baud)?;
    d.set_item("max_model", id.max_model)?;
    d.set_item("max_scan", id.max_scan)?;
    d.set_item("max_particles", id.max_particles)?;
    d.set_item("model_count", id.model_count)?;
    d.set_item("scan_count", id.scan_count)?;
    d.set_item("model_digest", id.model_digest)?;
    Ok(d)
}

#[pymethods]
impl Board {
    #[new]
    #[pyo3(signature = (port, *, baud = None, timeout_ms = None))]
    fn new(py: Python<'_>, port: String, baud: Option<u32>, timeout_ms: Option<u64>) -> PyResult<Self> {
        let timeout_ms = timeout_ms.unwrap_or(pficp::board::DEFAULT_TIMEOUT.as_millis() as u64);
        let (client, _) = py.detach(|| BoardClient::connect_with(&port, baud, timeout_ms)).map_err(request_error)?;
        Ok(Board { port, client: Mutex::new(Some(client)), lent: Mutex::new(None) })
    }

    /// The serial port.
    #[getter]
    fn port(&self) -> &str {
        &self.port
    }

    /// Ask the board who it is: protocol `version`, `lanes`, `clock_hz`, `baud`, its
    /// limits and what it holds (`model_count`, `model_digest`, ...).
    fn identify<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let id = self.with_link(py, |client| client.identify())?.map_err(board_error)?;
        identity_dict(py, &id)
    }

    /// Close the port (a tracker holding the board keeps it until it is closed).
    fn close(&self, py: Python<'_>) {
        py.detach(|| {
            if let Ok(mut c) = self.client.lock() {
                *c = None;
            }
        })
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    fn __exit__(
        &self,
        py: Python<'_>,
        _t: Option<Bound<'_, PyAny>>,
        _v: Option<Bound<'_, PyAny>>,
        _tb: Option<Bound<'_, PyAny>>,
    ) {
        self.close(py);
    }

    fn __repr__(&self) -> String {
        let open = self.client.lock().map(|c| c.is_some()).unwrap_or(false);
        format!("Board(port={:?}, open={open})", self.port)
    }
}
