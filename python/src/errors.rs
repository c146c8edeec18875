//! The library's errors as Python exceptions, with the CLI's one-line messages: a
//! `ValueError` for bad input, an `OSError` for files, and `pficp.BoardError` (an `OSError`)
//! for the board and its port.

use pficp::board::BoardError as HostBoardError;
use pficp::io::IoError;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::PyErr;

pyo3::create_exception!(
    _pficp,
    BoardError,
    PyOSError,
    "The board or its serial port failed: missing, silent, echoing, a corrupted or refused frame, a timeout."
);

/// A file error: `OSError` when the file cannot be read or written, `ValueError` when its
/// contents or name are wrong.
pub fn io_error(e: IoError) -> PyErr {
    match e {
        IoError::Read { .. } | IoError::Write { .. } => PyOSError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// A board error.
pub fn board_error(e: HostBoardError) -> PyErr {
    BoardError::new_err(e.to_string())
}

/// A request's error: the board's as [`board_error`], anything else is bad input.
pub fn request_error(e: anyhow::Error) -> PyErr {
    match e.downcast::<HostBoardError>() {
        Ok(b) => board_error(b),
        // `e` and its causes on one line, as the CLI prints them.
        Err(e) => PyValueError::new_err(format!("{e:#}")),
    }
}
