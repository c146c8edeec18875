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
use pficp_fpga::common::format::FxPoint;
use pficp_fpga::search::grid::{cell_of, Grid, CELLS_PER_AXIS, GRID_BITS};
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

/// The board's gridded model (protocol 3: the model store sorted by cell and the cell
/// table, `pficp_fpga::search::grid`) of the normalised, quantised model points. A model the grid
/// refuses (a point outside the cube `[-1, 1]^3`, more points than the board stores) is a
/// one-line [`BoardError::Limit`]; the host's normalisation puts every model point in the
/// unit ball, so it does not happen to a model planned by the host.
pub fn board_grid(model: &[FxPoint]) -> Result<Grid, BoardError> {
    Grid::build(model).map_err(|e| BoardError::Limit(format!("the board's grid refuses the model: {e}")))
}

/// The Morton key (Z order: the cell's bits interleaved, `x` lowest) of a point's grid
/// cell, each axis clipped to the grid.
pub fn morton_key(p: FxPoint) -> u32 {
    let k = cell_of(p).map(|c| c.clamp(0, CELLS_PER_AXIS as i32 - 1) as u32);
    (0..GRID_BITS).map(|b| ((k[0] >> b & 1) | (k[1] >> b & 1) << 1 | (k[2] >> b & 1) << 2) << (3 * b)).sum()
}

/// The scan sample sorted by the [`morton_key`] of each point's cell in the normalised scan
/// frame, ties in the given order (a stable sort). The first protocol-3 board's grid
/// pipeline swept the rows around batches of points and needed close points consecutive
/// (2.3 to 3.2 times fewer clocks); the neighbour pipeline that replaced it searches each
/// point's own rows, and the order changes its clocks by about 2% (docs/board-modes.md,
/// "The scan sample's order"). The
/// costs are sums over the sample, so the order changes no result.
pub fn morton_sorted(scan: &[FxPoint]) -> Vec<FxPoint> {
    let mut s = scan.to_vec();
    s.sort_by_key(|&p| morton_key(p));
    s
}
