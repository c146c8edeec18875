//! `pficp.Tracker`: one model tracked over consecutive scans, one `update(scan)` a frame
//! (`pficp::tracking::Tracker`, as `pficp track` runs it).

use crate::arrays::cloud_from;
use crate::board::Board;
use crate::errors::{board_error, request_error};
use crate::result::TrackFrame;
use pficp::board::BoardClient;
use pficp::cli::TrackFrameReport;
use pficp::nn::NearestNeighbours;
use pficp::tracking::{self, TrackSettings, MIN_FRAME_POINTS};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::sync::Mutex;

/// The library's tracker with what it borrows: the model's search structure and, on a
/// board, the board's link (lent by the `Board` and given back on close).
#[ouroboros::self_referencing]
struct Owned {
    nn: NearestNeighbours,
    client: Option<BoardClient>,
    #[borrows(nn, mut client)]
    #[not_covariant]
    tracker: tracking::Tracker<'this>,
}

/// A tracker of one model over consecutive scans (`pficp track`): the first frame, and
/// every frame after the track is lost, is a global registration; the others start from
/// the previous pose moved by a constant-velocity motion model.
///
/// `fps` is the frame rate (`None`: 30 a second), the time between frames; `scale`, `scale_range`, `viewpoint` and `seed` are as
/// `register` takes them. With `board=`, the tracked frames' filter runs on the board (the
/// model is put on it now unless it holds it already); the tracker holds the board until
/// `close()`. Each `update(scan)` returns a `TrackFrame`: act on its pose only when its
/// verdict is `confident`.
#[pyclass(module = "pficp", frozen, name = "Tracker")]
pub struct Tracker {
    inner: Mutex<Option<Owned>>,
    board: Option<Py<Board>>,
    engine: &'static str,
}

#[pymethods]
impl Tracker {
    #[new]
    #[allow(clippy::too_many_arguments, clippy::result_large_err)]
    #[pyo3(signature = (model, *, fps = None, scale = None, scale_range = None, viewpoint = None, seed = None, board = None))]
    fn new(
        py: Python<'_>,
        model: &Bound<'_, PyAny>,
        fps: Option<f64>,
        scale: Option<f64>,
        scale_range: Option<Vec<f64>>,
        viewpoint: Option<Vec<f64>>,
        seed: Option<u64>,
        board: Option<Py<Board>>,
    ) -> PyResult<Self> {
        let fps = fps.unwrap_or(tracking::DEFAULT_FPS);
        tracking::check_fps(fps).map_err(request_error)?;
        let defaults = pficp::request::PfIcpOptions::default();
        let options = pficp::request::PfIcpOptions {
            seed: seed.unwrap_or(defaults.seed),
            scale,
            scale_range,
            viewpoint,
            ..defaults
        };
        let registration = options.settings().map_err(request_error)?;
        let model = cloud_from(model, "model")?;
        let settings = TrackSettings { registration, fps, ..Default::default() };
        let client = board.as_ref().map(|b| b.get().take_link(py, "a Tracker")).transpose()?;
        let built = py.detach(move || {
            let nn = NearestNeighbours::new(model.points());
            OwnedTryBuilder {
                nn,
                client,
                tracker_builder: |nn, client| match client.as_mut() {
                    Some(c) => tracking::Tracker::on_board(nn, settings, c).map(|(t, _uploaded)| t),
                    None => tracking::Tracker::new(nn, settings),
                },
            }
            .try_build_or_recover()
        });
        match built {
            Ok(owned) => Ok(Tracker {
                inner: Mutex::new(Some(owned)),
                engine: if board.is_some() { "board" } else { "software" },
                board,
            }),
            Err((e, heads)) => {
                give_back(board.as_ref(), heads.client);
                Err(board_error(e))
            }
        }
    }

    /// Track the next frame's scan (an N x 3 array of at least 10 points): the frame's
    /// pose, verdict and the track's state. A board's failure raises `pficp.BoardError`
    /// and keeps the track (the next frame may try again).
    fn update(&self, py: Python<'_>, scan: &Bound<'_, PyAny>) -> PyResult<TrackFrame> {
        let scan = cloud_from(scan, "scan")?;
        if scan.len() < MIN_FRAME_POINTS {
            return Err(PyValueError::new_err(format!(
                "scan: a frame needs at least {MIN_FRAME_POINTS} points (got {})",
                scan.len()
            )));
        }
        let frame = self
            .locked(py, |inner| inner.as_mut().map(|o| o.with_tracker_mut(|t| t.update(scan.points()))))?
            .ok_or_else(|| PyValueError::new_err("the tracker is closed"))?
            .map_err(board_error)?;
        let port = self.board.as_ref().map(|b| b.get().port_name().to_string());
        Ok(TrackFrame { report: TrackFrameReport::new("<array>", &frame, self.engine, port.as_deref()) })
    }

    /// Frames seen so far.
    #[getter]
    fn frames(&self, py: Python<'_>) -> PyResult<usize> {
        self.locked(py, |inner| inner.as_ref().map_or(0, |o| o.with_tracker(|t| t.frames())))
    }

    /// The scale the track holds fixed once it has settled (or as given), else `None`.
    #[getter]
    fn fixed_scale(&self, py: Python<'_>) -> PyResult<Option<f64>> {
        self.locked(py, |inner| inner.as_ref().and_then(|o| o.with_tracker(|t| t.fixed_scale())))
    }

    /// Stop tracking and give the board back.
    fn close(&self, py: Python<'_>) {
        py.detach(|| close(self));
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
        py.detach(|| close(self));
    }
}

impl Tracker {
    /// Run `f` on the tracker with the GIL released, waiting for another thread's call to
    /// finish first (without the GIL: a thread waiting with it would hold up the other's
    /// return for ever).
    fn locked<R: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut Option<Owned>) -> R + Send) -> PyResult<R> {
        py.detach(|| self.inner.lock().map(|mut inner| f(&mut inner)).map_err(|_| ()))
            .map_err(|_| PyValueError::new_err("a call failed while it held the tracker"))
    }
}

impl Drop for Tracker {
    fn drop(&mut self) {
        // (No other call can hold the tracker: it is being dropped.)
        close(self);
    }
}

/// Drop the tracker and give the board's link back to its `Board`.
fn close(t: &Tracker) {
    let owned = t.inner.lock().ok().and_then(|mut g| g.take());
    if let Some(owned) = owned {
        give_back(t.board.as_ref(), owned.into_heads().client);
    }
}

fn give_back(board: Option<&Py<Board>>, client: Option<BoardClient>) {
    if let (Some(b), Some(c)) = (board, client) {
        b.get().give_back(c);
    }
}
