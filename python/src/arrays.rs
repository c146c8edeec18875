//! NumPy arrays in and out: an `N x 3` array of `float32` or `float64` is a cloud; poses,
//! matrices and covariances go out as `float64` arrays.

use nalgebra::Point3;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pficp::cloud::Cloud;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The cloud `name` (`model`, `scan`) from an `N x 3` array: C-contiguous, `float32` or
/// `float64`, finite, within the library's limits ([`Cloud::new`]). Anything else is a
/// `ValueError` naming the problem and the fix.
pub fn cloud_from(array: &Bound<'_, PyAny>, name: &str) -> PyResult<Cloud> {
    let Ok(untyped) = array.cast::<PyUntypedArray>() else {
        let type_name = array.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
        return Err(PyValueError::new_err(format!(
            "{name}: expected a NumPy array of shape (N, 3), got {type_name} (np.asarray(pcd.points) gives one)"
        )));
    };
    let shape = untyped.shape().to_vec();
    // As NumPy writes a shape: (500, 2), (3,).
    let shown = match shape.as_slice() {
        [n] => format!("({n},)"),
        s => format!("({})", s.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")),
    };
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err(format!("{name}: expected an array of shape (N, 3), got shape {shown}")));
    }
    if shape[0] == 0 {
        return Err(PyValueError::new_err(format!("{name} cloud is empty (shape {shown})")));
    }
    if shape[0] > pficp::cloud::MAX_CLOUD_POINTS {
        // (Refused before the copy.)
        return Err(PyValueError::new_err(format!(
            "{name} cloud has {} points, more than the limit of {}",
            shape[0],
            pficp::cloud::MAX_CLOUD_POINTS
        )));
    }
    if !untyped.is_c_contiguous() {
        return Err(PyValueError::new_err(format!(
            "{name}: the array is not C-contiguous (a slice or a transpose?); pass np.ascontiguousarray({name})"
        )));
    }
    let coordinates: Vec<f64> = if let Ok(a) = array.cast::<PyArray2<f64>>() {
        a.readonly().as_slice().map_err(|e| PyValueError::new_err(format!("{name}: {e}")))?.to_vec()
    } else if let Ok(a) = array.cast::<PyArray2<f32>>() {
        let r = a.readonly();
        r.as_slice().map_err(|e| PyValueError::new_err(format!("{name}: {e}")))?.iter().map(|&v| v as f64).collect()
    } else {
        let dtype = untyped.dtype().str().map(|s| s.to_string()).unwrap_or_else(|_| "?".into());
        return Err(PyValueError::new_err(format!(
            "{name}: dtype {dtype} is not float32 or float64; pass {name}.astype(np.float64)"
        )));
    };
    let points = coordinates.chunks_exact(3).map(|c| Point3::new(c[0], c[1], c[2])).collect();
    Cloud::new(name, points).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Points as an `N x 3` `float64` array.
pub fn points_array<'py>(py: Python<'py>, points: &[Point3<f64>]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = points.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    PyArray1::from_vec(py, flat).reshape([points.len(), 3]).expect("N x 3 holds 3N values")
}

/// A row-major `R x C` matrix as a `float64` array.
pub fn matrix_array<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &[[f64; C]; R],
) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = m.iter().flatten().copied().collect();
    PyArray1::from_vec(py, flat).reshape([R, C]).expect("R x C holds R C values")
}

/// A vector as a `float64` array.
pub fn vector_array<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A covariance whose undetermined entries are `None` as a `7 x 7` array with NaN there.
pub fn covariance_array<'py>(py: Python<'py>, c: &[[Option<f64>; 7]; 7]) -> Bound<'py, PyArray2<f64>> {
    matrix_array(py, &c.map(|row| row.map(|v| v.unwrap_or(f64::NAN))))
}
