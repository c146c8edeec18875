//! The model's cell grid for the board's nearest-neighbour search: the format the host
//! builds and the board stores (LoadModel, LoadTable), and the search's bit-exact
//! functional reference ([`Grid::nearest`], [`evaluate_grid`]; the RTL is the neighbour
//! pipeline, `crate::search::neighbour_pipeline`; docs/search.md).
//!
//! **Cells.** The grid covers the cube `[-1, 1]^3` of normalised units (the host normalises
//! the model into the unit ball, docs/fixed-point.md) with [`CELLS_PER_AXIS`] cells per
//! axis, each [`CELL_LSBS`] coordinate LSBs (`h = 1/8`) wide. A coordinate's cell along an
//! axis is `(c + 2^13) >> CELL_SHIFT`, an arithmetic shift; values outside `0..16` lie
//! outside the grid and hold no points, except that a model coordinate of exactly `+1`
//! (a point on the unit sphere's axis) is stored in the last cell ([`model_cell`]; the
//! rule below still holds, as a query within `h` of it lies in cell 15 or 16). Cells are
//! numbered `x` fastest: `cell = (k_z * 16 + k_y) * 16 + k_x`.
//!
//! **Store.** The model is stored sorted by cell (stably: upload order within a cell), and
//! the cell table holds for each cell the index of its first point, plus one entry more,
//! so that cell `c` holds points `first[c]..first[c + 1]` and a row of three `x`-neighbours
//! is one contiguous range `first[c - 1]..first[c + 2]` (clipped at the row's ends).
//! Indices the search reports are positions in the stored (sorted) model; the host keeps
//! the permutation ([`Grid::order`]).
//!
//! **Search and cap.** For a transformed scan point `q` the search reads the nine rows
//! around `q`'s cell (the 27 neighbour cells) and returns the nearest point among them,
//! ties to the lowest stored index, with its squared distance; a distance of [`CAP_D2`]
//! (`h^2`) or more is returned as `CAP_D2` with index [`NONE`]. Every model point within
//! `h` of `q` along each axis lies in those 27 cells, so this equals the brute-force
//! search over the stored model with the distance capped at `h^2`:
//! `min(d2_nearest, CAP_D2)` exactly, for every `q` in the coordinate range. The cap is
//! the same rule as the host's capped surface cost: a point farther than `h` from the
//! model (an outlier, a wrong pose) costs `h^2`, not its whole distance.

use crate::common::format::{dist2, transform, FxPoint, FxPose, COORD_FRAC, COST_MASK, MAX_POINTS};
use crate::search::pipeline::Evaluation;

/// Bits of a cell index along one axis.
pub const GRID_BITS: u32 = 4;
/// Cells per axis.
pub const CELLS_PER_AXIS: usize = 1 << GRID_BITS;
/// Cells in the grid.
pub const CELLS: usize = CELLS_PER_AXIS * CELLS_PER_AXIS * CELLS_PER_AXIS;
/// A coordinate's shift to its cell: the grid spans `2^(COORD_FRAC + 1)` LSBs (`[-1, 1)`).
pub const CELL_SHIFT: u32 = COORD_FRAC + 1 - GRID_BITS;
/// Width of a cell in coordinate LSBs.
pub const CELL_LSBS: i32 = 1 << CELL_SHIFT;
/// The capped squared distance, `h^2` in Q8.26.
pub const CAP_D2: u64 = 1 << (2 * CELL_SHIFT);
/// The index reported for a capped point.
pub const NONE: u16 = u16::MAX;

/// Why a model cannot be gridded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GridError {
    /// More points than the board stores.
    TooManyPoints(usize),
    /// A point outside `[-1, 1]^3` (upload order index).
    OutsideGrid(usize),
}

impl std::fmt::Display for GridError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GridError::TooManyPoints(n) => write!(f, "{n} model points: the grid holds at most {MAX_POINTS}"),
            GridError::OutsideGrid(i) => write!(f, "model point {i} lies outside the grid's cube [-1, 1]^3"),
        }
    }
}

impl std::error::Error for GridError {}

/// A point's cell along one axis (may lie outside `0..CELLS_PER_AXIS`).
pub fn axis_cell(c: i16) -> i32 {
    (c as i32 + (1 << COORD_FRAC)) >> CELL_SHIFT
}

/// A point's cell coordinates.
pub fn cell_of(p: FxPoint) -> [i32; 3] {
    [axis_cell(p[0]), axis_cell(p[1]), axis_cell(p[2])]
}

/// A model point's cell coordinates: [`cell_of`], with a coordinate of exactly `+1`
/// (`2^13`) in the last cell; `None` outside `[-1, 1]^3`.
pub fn model_cell(p: FxPoint) -> Option<[i32; 3]> {
    let k = p.map(|c| if c == 1 << COORD_FRAC { CELLS_PER_AXIS as i32 - 1 } else { axis_cell(c) });
    k.iter().all(|&a| inside(a)).then_some(k)
}

fn inside(k: i32) -> bool {
    (0..CELLS_PER_AXIS as i32).contains(&k)
}

/// A cell's number (`x` fastest), for cell coordinates inside the grid.
pub fn cell_index(k: [i32; 3]) -> usize {
    ((k[2] as usize * CELLS_PER_AXIS) + k[1] as usize) * CELLS_PER_AXIS + k[0] as usize
}

/// The gridded model: the stored points and the cell table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Grid {
    /// The model sorted by cell (the board's model store).
    pub points: Vec<FxPoint>,
    /// `first[c]`: index of cell `c`'s first point; `first[CELLS]` = the point count.
    pub first: Vec<u16>,
    /// `order[i]`: the upload index of stored point `i`.
    pub order: Vec<u16>,
}

/// What the search finds for one query.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Nearest {
    /// Stored index of the nearest point, or [`NONE`] when capped.
    pub index: u16,
    /// Squared distance (Q8.26), at most [`CAP_D2`].
    pub d2: u64,
}

impl Grid {
    /// Sort `model` into the grid.
    pub fn build(model: &[FxPoint]) -> Result<Grid, GridError> {
        if model.len() > MAX_POINTS {
            return Err(GridError::TooManyPoints(model.len()));
        }
        let mut cells = Vec::with_capacity(model.len());
        for (i, &p) in model.iter().enumerate() {
            cells.push(cell_index(model_cell(p).ok_or(GridError::OutsideGrid(i))?));
        }
        let mut order: Vec<u16> = (0..model.len() as u16).collect();
        order.sort_by_key(|&i| cells[i as usize]);
        let mut first = vec![0u16; CELLS + 1];
        for &c in &cells {
            first[c + 1] += 1;
        }
        for c in 0..CELLS {
            first[c + 1] += first[c];
        }
        Ok(Grid { points: order.iter().map(|&i| model[i as usize]).collect(), first, order })
    }

    /// The stored index ranges the search reads for `q`: one a row of three cells, rows
    /// outside the grid left out.
    pub fn ranges(&self, q: FxPoint) -> Vec<std::ops::Range<usize>> {
        let k = cell_of(q);
        let mut out = Vec::with_capacity(9);
        for dz in -1..=1 {
            for dy in -1..=1 {
                let (y, z) = (k[1] + dy, k[2] + dz);
                let (x0, x1) = ((k[0] - 1).max(0), (k[0] + 1).min(CELLS_PER_AXIS as i32 - 1));
                if !inside(y) || !inside(z) || x0 > x1 {
                    continue;
                }
                let lo = self.first[cell_index([x0, y, z])] as usize;
                let hi = self.first[cell_index([x1, y, z]) + 1] as usize;
                out.push(lo..hi);
            }
        }
        out
    }

    /// The search (the module doc's rule).
    pub fn nearest(&self, q: FxPoint) -> Nearest {
        let mut best = Nearest { index: NONE, d2: CAP_D2 };
        for r in self.ranges(q) {
            for i in r {
                let d = dist2(q, self.points[i]);
                if d < best.d2 || (d == best.d2 && d < CAP_D2 && (i as u16) < best.index) {
                    best = Nearest { index: i as u16, d2: d };
                }
            }
        }
        best
    }

    /// Model points the search compares `q` with.
    pub fn candidates(&self, q: FxPoint) -> usize {
        self.ranges(q).iter().map(|r| r.len()).sum()
    }
}

/// The brute-force search the grid must equal: nearest stored point (lowest index on
/// ties), capped at [`CAP_D2`].
pub fn nearest_capped(points: &[FxPoint], q: FxPoint) -> Nearest {
    let mut best = Nearest { index: NONE, d2: CAP_D2 };
    for (i, &p) in points.iter().enumerate() {
        let d = dist2(q, p);
        if d < best.d2 {
            best = Nearest { index: i as u16, d2: d };
        }
    }
    best
}

/// The functional reference of the board's search: every transformed scan point's
/// [`nearest_capped`] over the stored model, a capped point as index 0 and distance
/// [`CAP_D2`]; the cost their sum.
pub fn evaluate_grid(grid: &Grid, scan: &[FxPoint], pose: &FxPose) -> Evaluation {
    let nearest: Vec<(u16, u64)> = scan
        .iter()
        .map(|&p| {
            let n = nearest_capped(&grid.points, transform(pose, p));
            (if n.index == NONE { 0 } else { n.index }, n.d2)
        })
        .collect();
    let cost = nearest.iter().fold(0u64, |c, n| (c + n.1) & COST_MASK);
    Evaluation { cost, nearest }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_split_the_cube_evenly() {
        assert_eq!(CELL_LSBS, 1024);
        assert_eq!(axis_cell(-8192), 0);
        assert_eq!(axis_cell(-8192 + 1023), 0);
        assert_eq!(axis_cell(-8192 + 1024), 1);
        assert_eq!(axis_cell(8191), 15);
        assert_eq!(axis_cell(8192), 16);
        assert_eq!(axis_cell(i16::MIN), -24);
        assert_eq!(cell_index([1, 2, 3]), (3 * 16 + 2) * 16 + 1);
    }

    #[test]
    fn a_model_outside_the_cube_or_too_big_is_refused() {
        assert_eq!(Grid::build(&[[0, 0, 0], [0, 8193, 0]]), Err(GridError::OutsideGrid(1)));
        assert_eq!(Grid::build(&[[-8193, 0, 0]]), Err(GridError::OutsideGrid(0)));
        assert_eq!(model_cell([8192, -8192, 8191]), Some([15, 0, 15]));
        assert_eq!(Grid::build(&vec![[0; 3]; MAX_POINTS + 1]), Err(GridError::TooManyPoints(MAX_POINTS + 1)));
        assert!(Grid::build(&[[-8192, -8192, -8192], [8191, 8191, 8191]]).is_ok());
    }

    #[test]
    fn the_table_counts_every_point_once_in_cell_order() {
        let model = [[5000, 0, 0], [-8000, 0, 0], [5001, 1, 1], [0, -8000, 7000]];
        let g = Grid::build(&model).unwrap();
        assert_eq!(g.first[CELLS] as usize, model.len());
        assert_eq!(g.order, vec![1, 0, 2, 3]);
        for (i, &p) in g.points.iter().enumerate() {
            let c = cell_index(model_cell(p).unwrap());
            assert!((g.first[c] as usize..g.first[c + 1] as usize).contains(&i));
        }
    }
}
