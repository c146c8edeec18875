//! The answers: [`Registration`] (one `register` call) and [`TrackFrame`] (one tracked
//! frame), each holding the report the CLI prints with `--json`, so that `to_dict()` has
//! the CLI's keys and the attributes are read from the same values.

use crate::arrays::{covariance_array, matrix_array, vector_array};
use numpy::{PyArray1, PyArray2};
use pficp::cli::{RegisterReport, TrackFrameReport};
use pficp::geometry::PoseRecord;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// `value` as Python objects through its JSON (the CLI's keys and numbers, bit for bit:
/// serde_json writes the shortest text that reads back to the same float).
fn to_python<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// An alternative pose as a dict: `transformation` (4 x 4), `scale`, `rotation`,
/// `translation`, and the extra keys given.
fn pose_dict<'py>(py: Python<'py>, p: &PoseRecord) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let s = p.scale;
    let r = p.rotation;
    let t = p.translation;
    let m: [[f64; 4]; 4] = [
        [s * r[0][0], s * r[0][1], s * r[0][2], t[0]],
        [s * r[1][0], s * r[1][1], s * r[1][2], t[1]],
        [s * r[2][0], s * r[2][1], s * r[2][2], t[2]],
        [0.0, 0.0, 0.0, 1.0],
    ];
    d.set_item("transformation", matrix_array(py, &m))?;
    d.set_item("scale", s)?;
    d.set_item("rotation", matrix_array(py, &r))?;
    d.set_item("translation", vector_array(py, &t))?;
    Ok(d)
}

/// One registration's result: the pose (scan to model, `d = s R m + T`), what PF-ICP says
/// about it (verdict, alternatives, covariance, fit) and `to_dict()` with the keys of
/// `pficp register --json`.
///
/// `transformation` is the 4 x 4 matrix `[[s R, T], [0, 1]]`, as Open3D's
/// `RegistrationResult.transformation`: `scan @ T[:3, :3].T + T[:3, 3]` puts the scan on the
/// model. The covariance is 7 x 7 in `covariance_order` (model units, scale, radians), NaN
/// where the scan cannot determine a parameter. A baseline method (`icp`, ...) has no
/// verdict: `verdict`, `covariance` and `sigma` are then `None`.
#[pyclass(module = "pficp", frozen, name = "Registration")]
pub struct Registration {
    pub report: RegisterReport,
    /// The registration's settings and input sizes as `to_dict()` gives them.
    pub record: serde_json::Value,
}

#[pymethods]
impl Registration {
    /// The 4 x 4 matrix `[[s R, T], [0, 1]]` (scan to model).
    #[getter]
    fn transformation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_array(py, &self.report.matrix)
    }
    /// The scale `s` (scan to model).
    #[getter]
    fn scale(&self) -> f64 {
        self.report.scale
    }
    /// The rotation `R` (3 x 3).
    #[getter]
    fn rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_array(py, &self.report.rotation)
    }
    /// The translation `T` (3,).
    #[getter]
    fn translation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector_array(py, &self.report.translation)
    }
    /// The 7 x 7 covariance in `covariance_order`, NaN for undetermined parameters (PF-ICP).
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.report.assessment.as_ref().map(|a| covariance_array(py, &a.covariance))
    }
    /// The covariance's parameter names: `tx ty tz s rx ry rz`-style (see the docs).
    #[getter]
    fn covariance_order(&self) -> Vec<&'static str> {
        pficp::pf_icp::surface::LOCAL_NAMES.to_vec()
    }
    /// One-sigma values (7,) in `covariance_order`, NaN for undetermined parameters (PF-ICP).
    #[getter]
    fn sigma<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.report.assessment.as_ref().map(|a| vector_array(py, &a.sigma.map(|v| v.unwrap_or(f64::NAN))))
    }
    /// Share of scan points within `inlier_distance` of the model's surface (PF-ICP), or
    /// `None` for a baseline.
    #[getter]
    fn fitness(&self) -> Option<f64> {
        self.report.assessment.as_ref().map(|a| a.fitness)
    }
    /// RMS distance of those points (PF-ICP).
    #[getter]
    fn inlier_rmse(&self) -> Option<f64> {
        self.report.assessment.as_ref().map(|a| a.inlier_rmse)
    }
    /// `confident` (act on the pose), `ambiguous` (alternatives fit as well) or
    /// `unreliable` (do not act on it); `None` for a baseline.
    #[getter]
    fn verdict(&self) -> Option<&'static str> {
        self.report.assessment.as_ref().map(|a| a.verdict.name())
    }
    /// The verdict's reasons in words (empty for `confident`).
    #[getter]
    fn reasons(&self) -> Vec<String> {
        self.report.assessment.as_ref().map(|a| a.reasons.clone()).unwrap_or_default()
    }
    /// Other poses that fit as well within the noise, then (beside some of those) poses that
    /// fit worse but are not ruled out: dicts with `transformation`, `scale`, `rotation`,
    /// `translation`, `cost`, `excess_sigmas` and `fits_as_well`.
    #[getter]
    fn alternatives<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for a in self.report.assessment.iter().flat_map(|a| &a.alternatives) {
            let d = pose_dict(py, &a.pose)?;
            d.set_item("cost", a.cost)?;
            d.set_item("excess_sigmas", a.excess_sigmas)?;
            d.set_item("fits_as_well", a.fits_as_well)?;
            list.append(d)?;
        }
        Ok(list)
    }
    /// Mean squared closest-point distance over the whole scan.
    #[getter]
    fn msd(&self) -> f64 {
        self.report.msd
    }
    /// Iterations run.
    #[getter]
    fn iterations(&self) -> usize {
        self.report.iterations
    }
    /// Wall time of the registration [s].
    #[getter]
    fn seconds(&self) -> f64 {
        self.report.seconds
    }
    /// `software`, `board` or `board-host-driven`.
    #[getter]
    fn engine(&self) -> &str {
        &self.report.engine
    }
    /// The result as `pficp register --json` prints it (without the files and the command
    /// line, which arrays do not have).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let d = to_python(py, &self.report)?;
        d.call_method1("update", (to_python(py, &self.record)?,))?;
        Ok(d)
    }
    fn __repr__(&self) -> String {
        let verdict = self.report.assessment.as_ref().map_or("none", |a| a.verdict.name());
        let fitness = self.report.assessment.as_ref().map_or(String::from("none"), |a| format!("{:.3}", a.fitness));
        let [phi, theta, psi] = self.report.euler_deg;
        format!(
            "Registration(verdict={verdict}, scale={:.6}, euler_deg=({phi:.3}, {theta:.3}, {psi:.3}), fitness={fitness}, alternatives={})",
            self.report.scale,
            self.report.assessment.as_ref().map_or(0, |a| a.alternatives.len())
        )
    }
}

/// One tracked frame: the track's `state` (`acquiring`, `tracking`, `lost`, `reacquired`),
/// the frame's pose and verdict, and `to_dict()` with the keys of one line of
/// `pficp track --json`. Act on a frame's pose only when `verdict == "confident"`.
#[pyclass(module = "pficp", frozen, name = "TrackFrame")]
pub struct TrackFrame {
    pub report: TrackFrameReport,
}

#[pymethods]
impl TrackFrame {
    /// Frame index from 0.
    #[getter]
    fn frame(&self) -> usize {
        self.report.frame
    }
    /// The track's state after the frame.
    #[getter]
    fn state(&self) -> &'static str {
        self.report.state.name()
    }
    /// The verdict on this frame's pose.
    #[getter]
    fn verdict(&self) -> &'static str {
        self.report.verdict.name()
    }
    /// The verdict's reasons in words.
    #[getter]
    fn reasons(&self) -> Vec<String> {
        self.report.reasons.clone()
    }
    /// The 4 x 4 matrix `[[s R, T], [0, 1]]` (scan to model).
    #[getter]
    fn transformation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_array(py, &self.report.matrix)
    }
    /// The scale.
    #[getter]
    fn scale(&self) -> f64 {
        self.report.scale
    }
    /// The rotation (3 x 3).
    #[getter]
    fn rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix_array(py, &self.report.rotation)
    }
    /// The translation (3,).
    #[getter]
    fn translation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector_array(py, &self.report.translation)
    }
    /// The 7 x 7 covariance, NaN for undetermined parameters.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        covariance_array(py, &self.report.covariance)
    }
    /// One-sigma values (7,), NaN for undetermined parameters.
    #[getter]
    fn sigma<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector_array(py, &self.report.sigma.map(|v| v.unwrap_or(f64::NAN)))
    }
    /// Share of scan points within the inlier distance of the model's surface.
    #[getter]
    fn fitness(&self) -> f64 {
        self.report.fitness
    }
    /// RMS distance of those points.
    #[getter]
    fn inlier_rmse(&self) -> f64 {
        self.report.inlier_rmse
    }
    /// Other poses that fit as well: dicts with `transformation`, `scale`, `rotation`,
    /// `translation`.
    #[getter]
    fn alternatives<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for a in &self.report.alternatives {
            list.append(pose_dict(py, a)?)?;
        }
        Ok(list)
    }
    /// Whether the frame ran a global registration.
    #[getter]
    fn global_registration(&self) -> bool {
        self.report.global
    }
    /// Wall time of the frame [s].
    #[getter]
    fn seconds(&self) -> f64 {
        self.report.seconds
    }
    /// The frame as one line of `pficp track --json` prints it.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.report)
    }
    fn __repr__(&self) -> String {
        format!(
            "TrackFrame(frame={}, state={}, verdict={}, scale={:.6}, fitness={:.3})",
            self.report.frame,
            self.report.state.name(),
            self.report.verdict.name(),
            self.report.scale,
            self.report.fitness
        )
    }
}
