//! `pficp._pficp`: PF-ICP for Python (PyO3). NumPy arrays in and out; the same library
//! calls as the `pficp` CLI, so the same seed gives the same pose to the last bit. The
//! registration runs with the GIL released; errors are Python exceptions carrying the CLI's
//! one-line messages ([`errors`]); no panic crosses into Python (PyO3 turns one into a
//! `PanicException`).
//!
//! - [`register`]: one registration ([`pficp::request::Request`], as `pficp register`).
//! - [`tracker::Tracker`]: a model tracked over frames (as `pficp track`).
//! - [`board::Board`]: a board on a serial port, for both.
//! - [`read_cloud`], [`write_cloud`]: PLY, PCD, XYZ and CSV files.

mod arrays;
mod board;
mod errors;
mod result;
mod tracker;

use arrays::{cloud_from, points_array};
use errors::{io_error, request_error};
use numpy::PyArray2;
use pficp::cli::{Inputs, RegisterReport, Settings};
use pficp::request::{BoardProgress, Engine, PfIcpOptions, Request};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Register `scan` to `model` (N x 3 arrays, float32 or float64): the pose that puts the
/// scan on the model, `d = s R m + T`, with PF-ICP's verdict on it.
///
/// `method` is `pf-icp` or a baseline (`icp`, `welsch`, `cauchy`, `sparse-icp`,
/// `em-icp`). `scale` fixes the scale (1 for a metric camera and a model in the same
/// units); `scale_range=(lo, hi)` bounds it; `viewpoint=(x, y, z)` is where the sensor was
/// in the scan's frame (a depth camera's scans: `(0, 0, 0)`). `seed`, `clusters`,
/// `particles`, `iterations` and `init` (`auto`, `index`, `nearest`) are the CLI's flags;
/// `None` takes the CLI's default. With `board=pficp.Board(port)` the particle filter runs
/// on the board (`board_points` scan points a particle) or, with `host_driven=True`, the
/// board weighs the host filter's particles. `rescue=False` skips the rescue search (a
/// second, wider search when the evidence rules out the first answer; the CLI's
/// `--no-rescue`): a bounded time, the ruled-out answer left `unreliable`.
///
/// Returns a `Registration`. Bad input raises `ValueError`; a board's failure
/// `pficp.BoardError` (an `OSError`).
#[pyfunction]
#[pyo3(signature = (model, scan, *, method = "pf-icp", scale = None, scale_range = None, viewpoint = None, seed = None, clusters = None, particles = None, iterations = None, init = "auto", board = None, board_points = None, host_driven = false, rescue = true))]
#[allow(clippy::too_many_arguments)]
fn register(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    scan: &Bound<'_, PyAny>,
    method: &str,
    scale: Option<f64>,
    scale_range: Option<Vec<f64>>,
    viewpoint: Option<Vec<f64>>,
    seed: Option<u64>,
    clusters: Option<usize>,
    particles: Option<usize>,
    iterations: Option<usize>,
    init: &str,
    board: Option<Py<board::Board>>,
    board_points: Option<usize>,
    host_driven: bool,
    rescue: bool,
) -> PyResult<result::Registration> {
    use pficp::pf_icp::init::InitMode;
    use pficp::registration::methods::Method;
    let Some(method) = Method::parse(method) else {
        let names: Vec<_> = Method::ALL.iter().map(|m| m.name()).collect();
        return Err(PyValueError::new_err(format!("unknown method {method:?}: use one of {}", names.join(", "))));
    };
    let Some(init) = InitMode::parse(init) else {
        return Err(PyValueError::new_err(format!("unknown init {init:?}: use auto, index or nearest")));
    };
    let d = PfIcpOptions::default();
    let options = PfIcpOptions {
        clusters: clusters.unwrap_or(d.clusters),
        particles: particles.unwrap_or(d.particles),
        iterations: iterations.unwrap_or(d.iterations),
        seed: seed.unwrap_or(d.seed),
        init,
        scale,
        scale_range,
        viewpoint,
        rescue,
    };
    let settings = options.settings().map_err(request_error)?;
    let engine = Engine::from_options(board.is_some(), host_driven, board_points).map_err(request_error)?;
    let model = cloud_from(model, "model")?;
    let scan = cloud_from(scan, "scan")?;
    let request = Request { method, engine, settings };
    request.check(&model, &scan).map_err(request_error)?;
    let board = board.as_ref().map(|b| b.get());
    let run = |client: Option<&mut pficp::board::BoardClient>| {
        let progress = BoardProgress { on_board: &mut |_, _, _| {} };
        request.run(&model, &scan, client, progress)
    };
    let registered = match board {
        Some(b) => b.with_link(py, |client| run(Some(client)))?,
        None => py.detach(|| run(None)),
    }
    .map_err(request_error)?;
    let report = RegisterReport::of(&request, &registered, board.map(|b| b.port_name()));
    let inputs = Inputs {
        model: "<array>".to_string(),
        scan: "<array>".to_string(),
        model_points: model.len(),
        scan_points: scan.len(),
    };
    let record = serde_json::json!({
        "version": env!("CARGO_PKG_VERSION"),
        "inputs": inputs,
        "settings": Settings::of(&request),
    });
    Ok(result::Registration { report, record })
}

/// Read a point cloud (PLY, PCD, XYZ, CSV; by the extension) as an N x 3 float64 array.
/// A missing or unreadable file raises `OSError`; a malformed one `ValueError`.
#[pyfunction]
fn read_cloud(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyArray2<f64>>> {
    let cloud = py.detach(|| pficp::io::read_cloud(&path, "cloud")).map_err(io_error)?;
    Ok(points_array(py, cloud.points()))
}

/// Write an N x 3 array as a point cloud; the extension picks the format (`.ply` and
/// `.pcd` binary, `.xyz` and `.csv` text; every format keeps float64 but PCD, which is
/// float32).
#[pyfunction]
fn write_cloud(py: Python<'_>, path: PathBuf, points: &Bound<'_, PyAny>) -> PyResult<()> {
    let cloud = cloud_from(points, "points")?;
    let format = pficp::io::format_from_path(&path).map_err(io_error)?;
    py.detach(|| pficp::io::write_cloud(&path, cloud.points(), format)).map_err(io_error)
}

#[pymodule]
fn _pficp(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(register, m)?)?;
    m.add_function(wrap_pyfunction!(read_cloud, m)?)?;
    m.add_function(wrap_pyfunction!(write_cloud, m)?)?;
    m.add_class::<result::Registration>()?;
    m.add_class::<result::TrackFrame>()?;
    m.add_class::<tracker::Tracker>()?;
    m.add_class::<board::Board>()?;
    m.add("BoardError", m.py().get_type::<errors::BoardError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
