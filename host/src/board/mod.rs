//! The board side of the host: the client of the wire protocol, the two ways PF-ICP uses
//! the board, and the bridge between the host's f64 clouds and the board's formats.
//!
//! - [`client`]: [`BoardClient`], one request at a time over a serial port, every read
//!   bounded and every reply checked; [`error`]: [`BoardError`].
//! - [`on_board`]: PF-ICP with the particle filter on the board (Run, Status, Result), the
//!   default of `pficp register --board`.
//! - [`host_driven`]: PF-ICP on the host with each iteration's weights from the board
//!   (`--host-driven`, protocol version 1 boards).
//! - [`quantise`]: the one quantise stage between the host's f64 clouds and the board's
//!   formats: normalisation, the Q formats of points, poses, normals and filter parameters,
//!   the model drawn for the board, its grid and stored normals, the scan's Morton order
//!   (docs/fixed-point.md).
//! - [`pty`]: a board served on a pseudo-terminal (the tests', the board bench's and
//!   `pficp-sim-board`'s one server).

pub mod client;
pub mod error;
pub mod host_driven;
pub mod on_board;
pub mod pty;
pub mod quantise;

pub use client::*;
pub use error::BoardError;

/// Which store an upload fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Upload {
    /// The model store.
    Model,
    /// The scan store (the weight sample).
    Scan,
}

impl Upload {
    /// Its name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Upload::Model => "model",
            Upload::Scan => "scan",
        }
    }
}
