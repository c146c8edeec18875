//! The bit-exact, cycle-accurate reference of the grid pipeline (`GridPipeline<P>`,
//! docs/pipeline.md "The grid pipeline"): the nearest-neighbour pipeline of
//! [`crate::pipeline`] with the model stored sorted by cell ([`crate::grid::Grid`]) and a
//! batch's sweep restricted to the rows of cells around the batch's query cells.
//!
//! **Rule.** Each lane's minimum starts at [`CAP_D2`] with index 0 and keeps a strictly
//! smaller distance, the swept addresses increasing. A lane's result is therefore exactly
//! [`crate::grid::nearest_capped`] over the stored model, with a capped point reported as
//! index 0 and distance `CAP_D2` ("capped ⇔ `nn_dist == CAP_D2`"; the grid reference's
//! [`NONE`] maps to 0, [`evaluate_grid`]):
//!
//! - a model point with `d2 < CAP_D2 = h^2` from a lane's query `q` lies within `h` of `q`
//!   on every axis, so in one of the 27 cells around `q`'s cell (the grid module's rule,
//!   the `+1` edge included); each of those cells lies in a swept row, as the rows span
//!   the batch's query cells' bounding box grown by one cell on every side (clipped to the
//!   grid), `x` included. So every point that can win is swept;
//! - a swept point outside `q`'s 27 cells is farther than `h` on some axis, `d2 > CAP_D2`,
//!   and never passes the strictly-less compare against a minimum `<= CAP_D2`; no per-lane
//!   cell mask is needed (the cap does the masking);
//! - the rows are swept in cell order (`z`, then `y`), each row's range increasing, so the
//!   addresses increase and the strictly-less compare keeps the lowest index on ties, as
//!   `nearest_capped` does.
//!
//! [`GridPipelineModel::step`] is one rising edge, [`GridPipelineModel::outputs`] the
//! output ports after it, as for [`crate::pipeline::PipelineModel`].

use crate::format::{pack_point, transform, unpack_point, FxPoint, FxPose, MAX_POINTS};
use crate::grid::{nearest_capped, Grid, CAP_D2, CELLS, CELL_SHIFT, NONE};
use crate::pipeline::{
    stream_particle, transform_products, transform_result, transform_sums, Evaluation, Outputs, StreamModel, COST_MASK,
};

/// Input ports (before an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GridInputs {
    /// Write `model_wdata` at `model_waddr` (the model sorted by cell, [`Grid::points`]).
    pub model_we: bool,
    /// Model write address (12 bits).
    pub model_waddr: u16,
    /// Model write data (48 bits, [`pack_point`]).
    pub model_wdata: u64,
    /// Write `table_wdata` as cell-table entry `table_waddr` ([`Grid::first`]).
    pub table_we: bool,
    /// Cell-table entry, `0..=4096` (13 bits; larger values write nothing).
    pub table_waddr: u16,
    /// The entry (13 bits).
    pub table_wdata: u16,
    /// Begin a particle (when idle).
    pub start: bool,
    /// The pose, sampled with `start`.
    pub pose: FxPose,
    /// A scan point is offered.
    pub scan_valid: bool,
    /// The offered point (48 bits).
    pub scan_data: u64,
    /// The offered point is the last.
    pub scan_last: bool,
}

impl GridInputs {
    /// Begin a particle with `pose`.
    pub fn start(pose: &FxPose) -> GridInputs {
        GridInputs { start: true, pose: *pose, ..Default::default() }
    }

    /// If `offer`, offer scan point `next` of `scan` (`scan_last` on the last one);
    /// otherwise nothing.
    pub fn offer(scan: &[FxPoint], next: usize, offer: bool) -> GridInputs {
        let i = crate::pipeline::Inputs::offer(scan, next, offer);
        GridInputs { scan_valid: i.scan_valid, scan_data: i.scan_data, scan_last: i.scan_last, ..Default::default() }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    Load,
    Sweep,
    Reduce,
}

/// A coordinate's cell along one axis, less 8: `c >> 10` (six-bit signed, -32..=31).
fn shifted_cell(c: i16) -> i32 {
    (c >> CELL_SHIFT) as i32
}

/// The register state of the grid pipeline with `P` lanes.
#[derive(Clone, Debug)]
pub struct GridPipelineModel {
    lanes: usize,
    ram: Vec<u64>,
    /// `first[c]` for `c` in `0..4096` (the table's low read port).
    lo_ram: Vec<u16>,
    /// `first[c + 1]` for `c` in `0..4096` (the table's high read port).
    hi_ram: Vec<u16>,
    state: State,
    pose: FxPose,
    taken: usize,
    last_taken: bool,
    t1_valid: bool,
    t1_prod: [i64; 9],
    t2_valid: bool,
    t2_acc: [i64; 3],
    lane_wr: usize,
    lane_x: Vec<FxPoint>,
    n_lanes: usize,
    /// The batch's query cells (less 8), per axis min and max.
    bmin: [i32; 3],
    bmax: [i32; 3],
    /// The swept box of cells, per axis (inclusive, clipped to the grid).
    lo: [u16; 3],
    hi: [u16; 3],
    /// The next row to look up and whether there is one.
    ry: u16,
    rz: u16,
    rmore: bool,
    /// The table's read registers hold a looked-up row.
    tq_valid: bool,
    tq_lo: u16,
    tq_hi: u16,
    /// The pending (non-empty) row range.
    pv: bool,
    plo: u16,
    phi: u16,
    /// The range being swept (`addr .. end`).
    addr: u16,
    end: u16,
    ram_q: u64,
    s0_valid: bool,
    s0_index: u16,
    s1: (bool, u16, Vec<[i32; 3]>),
    s2: (bool, u16, Vec<[u64; 3]>),
    s3: (bool, u16, Vec<(u64, u64)>),
    s4: (bool, u16, Vec<u64>),
    lane_min: Vec<u64>,
    lane_arg: Vec<u16>,
    reduce_at: usize,
    cost: u64,
    out: Outputs,
    /// Model addresses issued so far and lane distances they fed (the batch's lanes each);
    /// for the utilisation figures, not registers.
    issued: u64,
    distances: u64,
}

impl GridPipelineModel {
    /// A pipeline with `lanes` lanes, after reset (idle, model RAM and table all zero).
    pub fn new(lanes: usize) -> Self {
        assert!((1..=64).contains(&lanes), "1 to 64 lanes");
        GridPipelineModel {
            lanes,
            ram: vec![0; MAX_POINTS],
            lo_ram: vec![0; CELLS],
            hi_ram: vec![0; CELLS],
            state: State::Idle,
            pose: FxPose::default(),
            taken: 0,
            last_taken: false,
            t1_valid: false,
            t1_prod: [0; 9],
            t2_valid: false,
            t2_acc: [0; 3],
            lane_wr: 0,
            lane_x: vec![[0; 3]; lanes],
            n_lanes: 0,
            bmin: [0; 3],
            bmax: [0; 3],
            lo: [0; 3],
            hi: [0; 3],
            ry: 0,
            rz: 0,
            rmore: false,
            tq_valid: false,
            tq_lo: 0,
            tq_hi: 0,
            pv: false,
            plo: 0,
            phi: 0,
            addr: 0,
            end: 0,
            ram_q: 0,
            s0_valid: false,
            s0_index: 0,
            s1: (false, 0, vec![[0; 3]; lanes]),
            s2: (false, 0, vec![[0; 3]; lanes]),
            s3: (false, 0, vec![(0, 0); lanes]),
            s4: (false, 0, vec![0; lanes]),
            lane_min: vec![0; lanes],
            lane_arg: vec![0; lanes],
            reduce_at: 0,
            cost: 0,
            out: Outputs::default(),
            issued: 0,
            distances: 0,
        }
    }

    /// Number of lanes.
    pub fn lanes(&self) -> usize {
        self.lanes
    }

    /// Model addresses swept since reset.
    pub fn issued(&self) -> u64 {
        self.issued
    }

    /// Distances computed since reset in lanes that hold a scan point (a swept address
    /// counts once for each of its batch's points).
    pub fn distances(&self) -> u64 {
        self.distances
    }

    /// Output ports now.
    pub fn outputs(&self) -> Outputs {
        Outputs { scan_ready: self.scan_ready(), busy: self.state != State::Idle, ..self.out }
    }

    fn scan_ready(&self) -> bool {
        self.state == State::Load && self.taken < self.lanes && !self.last_taken
    }

    /// One rising edge with the given inputs.
    #[allow(clippy::needless_range_loop)] // register indices mirror the RTL's
    pub fn step(&mut self, i: &GridInputs) {
        let take = self.scan_ready() && i.scan_valid;
        let sweep = self.state == State::Sweep;
        // Memories: read first, then written (block RAM). The table reads the row in the
        // row registers every clock, `first[(rz, ry, x0)]` and `first[(rz, ry, x1) + 1]`.
        let mut ram = std::mem::take(&mut self.ram);
        let mut lo_ram = std::mem::take(&mut self.lo_ram);
        let mut hi_ram = std::mem::take(&mut self.hi_ram);
        let mut next = self.clone();
        next.ram_q = ram[(self.addr as usize) % MAX_POINTS];
        let row = ((self.rz as usize & 15) << 8) | ((self.ry as usize & 15) << 4);
        next.tq_lo = lo_ram[row | (self.lo[0] as usize & 15)];
        next.tq_hi = hi_ram[row | (self.hi[0] as usize & 15)];
        if i.model_we {
            ram[(i.model_waddr as usize) % MAX_POINTS] = i.model_wdata & ((1 << crate::format::POINT_WORD_BITS) - 1);
        }
        let (wa, wd) = (i.table_waddr as usize & 0x1fff, i.table_wdata & 0x1fff);
        if i.table_we && wa < CELLS {
            lo_ram[wa] = wd;
        }
        if i.table_we && (1..=CELLS).contains(&wa) {
            hi_ram[wa - 1] = wd;
        }
        next.ram = ram;
        next.lo_ram = lo_ram;
        next.hi_ram = hi_ram;
        // Transform pipeline (as the brute-force pipeline's).
        next.t1_valid = take;
        if take {
            next.t1_prod = transform_products(&self.pose, i.scan_data);
        }
        next.t2_valid = self.t1_valid;
        if self.t1_valid {
            next.t2_acc = transform_sums(&self.pose, &self.t1_prod);
        }
        if self.t2_valid && self.lane_wr < self.lanes {
            let x = transform_result(&self.t2_acc);
            next.lane_x[self.lane_wr] = x;
            next.lane_wr = self.lane_wr + 1;
            // The batch's bounding box of query cells (the first write of a batch sets it).
            for k in 0..3 {
                let c = shifted_cell(x[k]);
                let first = self.lane_wr == 0;
                next.bmin[k] = if first { c } else { self.bmin[k].min(c) };
                next.bmax[k] = if first { c } else { self.bmax[k].max(c) };
            }
        }
        // Row lookup and address generation (Sweep).
        let issue = sweep && self.addr < self.end;
        let last = issue && self.addr + 1 == self.end;
        let consume = self.pv && (!issue || last);
        let tq_full = self.tq_valid && self.tq_lo < self.tq_hi;
        let tadv = sweep && self.rmore && !tq_full && (!self.pv || consume);
        if issue {
            next.addr = self.addr + 1;
            next.issued += 1;
            next.distances += self.n_lanes as u64;
        }
        if consume {
            next.addr = self.plo;
            next.end = self.phi;
        }
        if tq_full {
            // The row goes to the pending slot (empty rows are dropped here).
            next.pv = true;
            next.plo = self.tq_lo;
            next.phi = self.tq_hi;
        } else if consume {
            next.pv = false;
        }
        next.tq_valid = tadv;
        if tadv {
            if self.ry < self.hi[1] {
                next.ry = self.ry + 1;
            } else {
                next.ry = self.lo[1];
                if self.rz < self.hi[2] {
                    next.rz = self.rz + 1;
                } else {
                    next.rmore = false;
                }
            }
        }
        // Sweep pipeline (as the brute-force pipeline's).
        next.s0_valid = issue;
        next.s0_index = self.addr & 0xfff;
        let d = unpack_point(self.ram_q);
        next.s1 = (
            self.s0_valid,
            self.s0_index,
            self.lane_x.iter().map(|x| [0, 1, 2].map(|k| x[k] as i32 - d[k] as i32)).collect(),
        );
        next.s2 = (self.s1.0, self.s1.1, self.s1.2.iter().map(|dx| dx.map(|v| (v as i64 * v as i64) as u64)).collect());
        next.s3 = (self.s2.0, self.s2.1, self.s2.2.iter().map(|sq| (sq[0] + sq[1], sq[2])).collect());
        next.s4 = (self.s3.0, self.s3.1, self.s3.2.iter().map(|(a, b)| a + b).collect());
        if self.s4.0 {
            for l in 0..self.lanes {
                if self.s4.2[l] < self.lane_min[l] {
                    next.lane_min[l] = self.s4.2[l];
                    next.lane_arg[l] = self.s4.1;
                }
            }
        }
        next.out.nn_valid = false;
        next.out.cost_valid = false;
        match self.state {
            State::Idle => {
                if i.start {
                    next.state = State::Load;
                    next.pose = i.pose;
                    next.cost = 0;
                    next.taken = 0;
                    next.last_taken = false;
                    next.lane_wr = 0;
                }
            }
            State::Load => {
                if take {
                    next.taken = self.taken + 1;
                    next.last_taken = self.last_taken || i.scan_last;
                }
                let closed = self.taken == self.lanes || self.last_taken;
                if closed && !self.t1_valid && !self.t2_valid {
                    next.state = State::Sweep;
                    next.n_lanes = self.lane_wr;
                    next.lane_min = vec![CAP_D2; self.lanes];
                    next.lane_arg = vec![0; self.lanes];
                    // The box: the query cells' box grown by one, clipped to the grid.
                    let mut rows = true;
                    for k in 0..3 {
                        let (lo, hi) = ((self.bmin[k] + 7).max(0), (self.bmax[k] + 9).min(15));
                        rows &= lo <= hi;
                        next.lo[k] = lo.clamp(0, 15) as u16;
                        next.hi[k] = hi.clamp(0, 15) as u16;
                    }
                    next.ry = next.lo[1];
                    next.rz = next.lo[2];
                    next.rmore = rows;
                    next.tq_valid = false;
                    next.pv = false;
                    next.addr = 0;
                    next.end = 0;
                }
            }
            State::Sweep => {
                let empty = !self.rmore
                    && !self.tq_valid
                    && !self.pv
                    && !issue
                    && !self.s0_valid
                    && !self.s1.0
                    && !self.s2.0
                    && !self.s3.0
                    && !self.s4.0;
                if empty {
                    next.state = State::Reduce;
                    next.reduce_at = 0;
                }
            }
            State::Reduce => {
                if self.reduce_at < self.n_lanes {
                    let l = self.reduce_at;
                    next.out.nn_valid = true;
                    next.out.nn_index = self.lane_arg[l];
                    next.out.nn_dist = self.lane_min[l];
                    next.cost = (self.cost + self.lane_min[l]) & COST_MASK;
                    next.reduce_at = l + 1;
                } else if self.last_taken {
                    next.out.cost_valid = true;
                    next.out.cost = self.cost;
                    next.state = State::Idle;
                } else {
                    next.state = State::Load;
                    next.taken = 0;
                    next.lane_wr = 0;
                }
            }
        }
        *self = next;
    }
}

/// The functional reference: every transformed scan point's [`nearest_capped`] over the
/// stored model, a capped point as index 0 and distance [`CAP_D2`]; the cost their sum.
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

/// The functional reference over the board's raw stores, whatever they hold: the model
/// RAM (`ram`, [`MAX_POINTS`] packed words) and the cell table as written (`first`, the
/// [`CELLS`]` + 1` entries of 13 bits; the RTL's low port reads `first[c]`, its high port
/// `first[c + 1]`). What the RTL computes, without its clocks: the scan in batches of
/// `lanes` points in order; per batch the box of its query cells grown by one and clipped;
/// its rows `z`, then `y`, each the range `first[(z, y, x_lo)] .. first[(z, y, x_hi) + 1]`
/// (empty unless the start is below the end), addresses taken modulo [`MAX_POINTS`]; each
/// lane keeps the first strictly smaller distance, starting at [`CAP_D2`] with index 0.
/// With a table built by [`Grid::build`] over the stored points this equals
/// [`evaluate_grid`] (the module doc's rule), whatever `lanes`; the board's byte-level
/// reference uses this so that it also agrees with the RTL on a table that does not
/// describe the model.
pub fn evaluate_stored(ram: &[u64], first: &[u16], lanes: usize, scan: &[FxPoint], pose: &FxPose) -> Evaluation {
    assert!(ram.len() == MAX_POINTS && first.len() == CELLS + 1 && lanes > 0);
    let mut nearest = Vec::with_capacity(scan.len());
    for batch in scan.chunks(lanes) {
        let queries: Vec<FxPoint> = batch.iter().map(|&p| transform(pose, p)).collect();
        let mut best: Vec<(u16, u64)> = vec![(0, CAP_D2); queries.len()];
        let mut lo = [0i32; 3];
        let mut hi = [0i32; 3];
        let mut rows = true;
        for k in 0..3 {
            let cmin = queries.iter().map(|q| shifted_cell(q[k])).min().unwrap_or(0);
            let cmax = queries.iter().map(|q| shifted_cell(q[k])).max().unwrap_or(0);
            lo[k] = (cmin + 7).max(0);
            hi[k] = (cmax + 9).min(15);
            rows &= lo[k] <= hi[k];
        }
        if rows {
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    let row = ((z as usize) << 8) | ((y as usize) << 4);
                    let (start, end) =
                        (first[row | lo[0] as usize] & 0x1fff, first[(row | hi[0] as usize) + 1] & 0x1fff);
                    for a in start..end {
                        let d = unpack_point(ram[a as usize % MAX_POINTS]);
                        for (b, q) in best.iter_mut().zip(&queries) {
                            let e = crate::format::dist2(*q, d);
                            if e < b.1 {
                                *b = (a & 0xfff, e);
                            }
                        }
                    }
                }
            }
        }
        nearest.extend(best);
    }
    let cost = nearest.iter().fold(0u64, |c, n| (c + n.1) & COST_MASK);
    Evaluation { cost, nearest }
}

/// The input words that upload `grid` (model words, then the 4,097 table entries), one a
/// clock, as the co-simulation and the benches drive them.
pub fn upload(grid: &Grid) -> Vec<GridInputs> {
    let mut v: Vec<GridInputs> = grid
        .points
        .iter()
        .enumerate()
        .map(|(a, &p)| GridInputs {
            model_we: true,
            model_waddr: a as u16,
            model_wdata: pack_point(p),
            ..Default::default()
        })
        .collect();
    v.extend(grid.first.iter().enumerate().map(|(a, &f)| GridInputs {
        table_we: true,
        table_waddr: a as u16,
        table_wdata: f,
        ..Default::default()
    }));
    v
}

/// What one particle took: the results, clocks from `start` to `cost_valid`, the model
/// addresses swept and the distances computed in the lanes that hold a point.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GridRun {
    /// Results and cost.
    pub evaluation: Evaluation,
    /// Clocks from the `start` edge to the `cost_valid` edge.
    pub clocks: u64,
    /// Model addresses swept.
    pub swept: u64,
    /// Distances computed in lanes holding a scan point (`swept` times the batch's points).
    pub distances: u64,
}

/// Drive a [`GridPipelineModel`] (its model and table already written) through one
/// particle, offering a scan point on clocks where `gap(clock)` is false.
pub fn run_particle(
    pipe: &mut GridPipelineModel,
    scan: &[FxPoint],
    pose: &FxPose,
    gap: impl FnMut(u64) -> bool,
) -> GridRun {
    assert!(!scan.is_empty());
    let (issued0, distances0) = (pipe.issued, pipe.distances);
    pipe.step(&GridInputs::start(pose));
    let (evaluation, clocks) = stream_particle(pipe, scan, gap);
    GridRun { evaluation, clocks, swept: pipe.issued - issued0, distances: pipe.distances - distances0 }
}

impl StreamModel for GridPipelineModel {
    type Inputs = GridInputs;
    fn step(&mut self, inputs: &GridInputs) {
        GridPipelineModel::step(self, inputs)
    }
    fn outputs(&self) -> Outputs {
        GridPipelineModel::outputs(self)
    }
    fn offer(scan: &[FxPoint], next: usize, offer: bool) -> GridInputs {
        GridInputs::offer(scan, next, offer)
    }
}

/// Rows a batch sweeps at most: every `(y, z)` of the grid.
pub const MAX_ROWS: u64 = (crate::grid::CELLS_PER_AXIS * crate::grid::CELLS_PER_AXIS) as u64;

/// An upper bound of [`clocks_per_particle`]'s count (start edge to `cost_valid` edge, no
/// gaps in the scan stream) for `scan_points` scan points under any pose, over any model of
/// `model_points` points uploaded as [`Grid::build`] stores it, on `lanes` lanes; for
/// deadlines, where the data-dependent count is not worth running the cycle model.
///
/// Per batch of `n_b` points, as [`crate::pipeline::clocks_per_particle`] with the sweep
/// bounded: `(n_b + 3)` to load, at most `model_points + MAX_ROWS + 9` to sweep, `(n_b + 1)`
/// to reduce; plus the start edge. The sweep (docs/pipeline.md, "The grid pipeline") is
/// `S_b + 9 + stalls`: the batch's swept addresses `S_b` are disjoint row ranges of the
/// stored model (at most `model_points`), and each of its rows (at most [`MAX_ROWS`], the
/// box being clipped to the grid) stalls at most one clock: an empty row looked up while
/// no range runs, or a one-point row (two clocks for its one address). So the bound is
/// the brute-force count plus `MAX_ROWS + 3` a batch; a batch whose box misses the grid
/// sweeps nothing and stays below it.
pub fn clocks_bound(scan_points: usize, model_points: usize, lanes: usize) -> u64 {
    let lanes = lanes.max(1) as u64;
    let (n, m) = (scan_points as u64, model_points as u64);
    let batches = n.div_ceil(lanes);
    // Loads and reduces: every point twice, plus 3 + 1 a batch; sweeps: m + rows + 9 a batch.
    1 + 2 * n + batches * (4 + m + MAX_ROWS + 9)
}

/// Clocks and swept addresses of one particle with no gaps in the scan stream, counted on
/// the cycle model (the sweep's length depends on the data): `grid` uploaded, then one
/// particle.
pub fn clocks_per_particle(grid: &Grid, scan: &[FxPoint], pose: &FxPose, lanes: usize) -> GridRun {
    let mut pipe = GridPipelineModel::new(lanes);
    for w in upload(grid) {
        pipe.step(&w);
    }
    run_particle(&mut pipe, scan, pose, |_| false)
}
