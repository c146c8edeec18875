//! The board side of the host: the client of the wire protocol, the two ways PF-ICP uses
//! the board, and the bridge between the host's f64 clouds and the board's formats.
//!
//! - [`client`]: [`BoardClient`], one request at a time over a serial port, every read
//!   bounded and every reply checked; [`error`]: [`BoardError`].
//! - [`on_board`]: PF-ICP with the particle filter on the board (Run, Status, Result), the
//!   default of `pficp register --board`.
//! - [`host_driven`]: PF-ICP on the host with each iteration's weights from the board
//!   (`--host-driven`, protocol version 1 boards).
//! - [`fixed`]: normalisation and quantisation of clouds and poses (docs/fixed-point.md).
//! - [`pty`]: a board served on a pseudo-terminal (the tests', the board bench's and
//!   `pficp-sim-board`'s one server).

pub mod client;
pub mod error;
pub mod fixed;
pub mod host_driven;
pub mod on_board;
pub mod pty;

pub use client::*;
pub use error::BoardError;

use nalgebra::Point3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

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

/// The model points that go to the board: all of them when they fit, else `max` of them
/// drawn without replacement with the seed, in their original order.
pub fn board_model(model: &[Point3<f64>], max: usize, seed: u64) -> Vec<Point3<f64>> {
    if model.len() <= max {
        return model.to_vec();
    }
    // A stream of its own, so the draw does not shift any other random choice.
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x626f_6172_645f_6d64);
    let mut picks = rand::seq::index::sample(&mut rng, model.len(), max).into_vec();
    picks.sort_unstable();
    picks.into_iter().map(|i| model[i]).collect()
}
