//! [`NeighbourPipelineModel`]: the neighbour pipeline's registers and next-state logic,
//! clock for clock the RTL (`NeighbourPipeline<P>`).

use super::{
    key, GridInputs, B_SQUARE_LIMIT, CAP_KEY, MAX_LANES, POINT_QUEUE, RANGE_QUEUE, SLOTS, TREE_LEAVES, TREE_LEVELS,
};
use crate::common::format::{unpack_point, FxPoint, FxPose, MAX_POINTS, POINT_WORD_BITS};
use crate::search::grid::{axis_cell, CAP_D2, CELLS, CELLS_PER_AXIS};
use crate::search::pipeline::{transform_products, transform_result, transform_sums, Outputs, StreamModel, COST_MASK};
use std::collections::VecDeque;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    Run,
}

/// The lookup stage: the point whose rows are being looked up.
#[derive(Clone, Copy, Debug, Default)]
struct Lookup {
    have: bool,
    q: FxPoint,
    last: bool,
    /// Cell coordinates (may lie outside the grid).
    k: [i32; 3],
    /// The slot to look up next.
    slot: usize,
}

/// A looked-up slot in the table's read registers.
#[derive(Clone, Copy, Debug, Default)]
struct Read {
    valid: bool,
    /// Row A, row B inside the grid.
    in_a: bool,
    in_b: bool,
    /// The point's last slot.
    last: bool,
    slast: bool,
    q: FxPoint,
}

/// A queued slot: its row A's range and its row B's, each if non-empty (neither: a marker).
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    a: Option<(u16, u16)>,
    b: Option<(u16, u16)>,
    last: bool,
    slast: bool,
    q: FxPoint,
}

/// The chunk issue: the entry being issued, range A (`a.0 .. a.1`, while `av`) through the A
/// lanes and range B (while `bv`) through the B lanes, one chunk of each a clock (in a
/// point's last slot, `last`, range B is the centre row from its second chunk on and both
/// step `2P`).
#[derive(Clone, Copy, Debug, Default)]
struct Issue {
    have: bool,
    a: (u16, u16),
    av: bool,
    b: (u16, u16),
    bv: bool,
    last: bool,
    slast: bool,
    q: FxPoint,
}

/// Per-chunk control through the lane and tree stages, and the chunk's transformed scan
/// point (`q`, presented as `nn_point` with the point's result: the RTL's delay line
/// beside the control bits).
#[derive(Clone, Copy, Debug, Default)]
struct Ctl {
    valid: bool,
    last: bool,
    slast: bool,
    q: FxPoint,
}

/// A lane stage's register: control, lane valid bits, bank rows, per-lane values (the `P`
/// A lanes, then the `P` B lanes).
type Stage<T> = (Ctl, Vec<bool>, Vec<u16>, Vec<T>);

/// The register state of the neighbour pipeline with `P` lanes a side (`P` a power of two up
/// to [`MAX_LANES`]): `P` A lanes and `P` B lanes.
#[derive(Clone, Debug)]
pub struct NeighbourPipelineModel {
    lanes: usize,
    log2: u32,
    /// The model RAM; the RTL holds it twice (the A lanes' banks and the B lanes'), both
    /// written by every write, so the copies are always equal.
    ram: Vec<u64>,
    lo_ram: Vec<u16>,
    hi_ram: Vec<u16>,
    state: State,
    pose: FxPose,
    last_taken: bool,
    t1: (bool, bool, [i64; 9]),
    t2: (bool, bool, [i64; 3]),
    points: VecDeque<(FxPoint, bool)>,
    lk: Lookup,
    rd: Read,
    /// The table's read registers: (lo, hi) of row A and of row B.
    tq: [(u16, u16); 2],
    queue: VecDeque<Entry>,
    is: Issue,
    /// Chunk register (c0): control, query, lane valid bits, bank rows (A lanes, then B);
    /// and the banks' read registers.
    c0: (Ctl, FxPoint, Vec<bool>, Vec<u16>),
    bank_q: Vec<u64>,
    s1: Stage<[i32; 3]>,
    s2: Stage<[u64; 3]>,
    s3: Stage<(u64, u64)>,
    s4: Stage<u64>,
    /// Clamped keys, then the tree's levels (each half the previous).
    tree: Vec<(Ctl, Vec<u64>)>,
    acc_used: bool,
    acc: u64,
    fin: bool,
    cost: u64,
    out: Outputs,
    chunks: u64,
    distances: u64,
}

impl NeighbourPipelineModel {
    /// A pipeline with `lanes` lanes a side (a power of two, 1 to 16), after reset: idle,
    /// model RAM and table all zero.
    pub fn new(lanes: usize) -> Self {
        assert!(lanes.is_power_of_two() && lanes <= MAX_LANES, "1, 2, 4, 8 or 16 lanes");
        let log2 = lanes.trailing_zeros();
        let z = |_| Ctl::default();
        let (lanes2, lanes) = (2 * lanes, lanes);
        NeighbourPipelineModel {
            lanes,
            log2,
            ram: vec![0; MAX_POINTS],
            lo_ram: vec![0; CELLS],
            hi_ram: vec![0; CELLS],
            state: State::Idle,
            pose: FxPose::default(),
            last_taken: false,
            t1: (false, false, [0; 9]),
            t2: (false, false, [0; 3]),
            points: VecDeque::new(),
            lk: Lookup::default(),
            rd: Read::default(),
            tq: [(0, 0); 2],
            queue: VecDeque::new(),
            is: Issue::default(),
            c0: (z(0), [0; 3], vec![false; lanes2], vec![0; lanes2]),
            bank_q: vec![0; lanes2],
            s1: (z(0), vec![false; lanes2], vec![0; lanes2], vec![[0; 3]; lanes2]),
            s2: (z(0), vec![false; lanes2], vec![0; lanes2], vec![[0; 3]; lanes2]),
            s3: (z(0), vec![false; lanes2], vec![0; lanes2], vec![(0, 0); lanes2]),
            s4: (z(0), vec![false; lanes2], vec![0; lanes2], vec![0; lanes2]),
            tree: (0..=TREE_LEVELS).map(|l| (z(0), vec![0; if l == 0 { lanes2 } else { TREE_LEAVES >> l }])).collect(),
            acc_used: false,
            acc: 0,
            fin: false,
            cost: 0,
            out: Outputs::default(),
            chunks: 0,
            distances: 0,
        }
    }

    /// Number of lanes a side (A and B: twice as many distances a clock).
    pub fn lanes(&self) -> usize {
        self.lanes
    }

    /// Issue clocks since reset: chunk pairs (a chunk of range A and one of range B, either
    /// possibly empty), marker chunks included.
    pub fn chunks(&self) -> u64 {
        self.chunks
    }

    /// Distances computed since reset in lanes (A and B) holding a candidate.
    pub fn distances(&self) -> u64 {
        self.distances
    }

    /// Output ports now.
    pub fn outputs(&self) -> Outputs {
        Outputs { scan_ready: self.scan_ready(), busy: self.state != State::Idle, ..self.out }
    }

    fn scan_ready(&self) -> bool {
        let queued = self.points.len() + self.t1.0 as usize + self.t2.0 as usize;
        self.state == State::Run && !self.last_taken && queued < POINT_QUEUE
    }

    /// The two rows of slot `s` for a point in cells `k`: (inside the grid, lo address, hi
    /// address) each; a missing row B is outside.
    pub(super) fn slot_rows(k: [i32; 3], s: usize) -> [(bool, usize, usize); 2] {
        let n = CELLS_PER_AXIS as i32;
        let (x0, x1) = ((k[0] - 1).max(0), (k[0] + 1).min(n - 1));
        let row = |r: Option<usize>| match r {
            None => (false, 0, 0),
            Some(r) => {
                let (dz, dy) = (r as i32 / 3 - 1, r as i32 % 3 - 1);
                let (y, z) = (k[1] + dy, k[2] + dz);
                let inside = (0..n).contains(&y) && (0..n).contains(&z) && x0 <= x1;
                let base = (((z & 15) << 8) | ((y & 15) << 4)) as usize;
                (inside, base | (x0 & 15) as usize, base | (x1 & 15) as usize)
            }
        };
        [row(Some(SLOTS[s].0)), row(SLOTS[s].1)]
    }

    /// The first slot at or after `from` with a row inside the grid; the last slot (4) is
    /// always visited.
    fn next_slot(k: [i32; 3], from: usize) -> usize {
        (from..4).find(|&s| Self::slot_rows(k, s).iter().any(|r| r.0)).unwrap_or(4)
    }

    /// One rising edge with the given inputs.
    #[allow(clippy::needless_range_loop)] // register indices mirror the RTL's
    pub fn step(&mut self, i: &GridInputs) {
        let p = self.lanes;
        let take = self.scan_ready() && i.scan_valid;
        let mut ram = std::mem::take(&mut self.ram);
        let mut lo_ram = std::mem::take(&mut self.lo_ram);
        let mut hi_ram = std::mem::take(&mut self.hi_ram);
        let mut next = self.clone();
        // Transform pipeline; its result joins the point queue.
        next.t1 =
            (take, take && i.scan_last, if take { transform_products(&self.pose, i.scan_data) } else { self.t1.2 });
        next.t2 = (self.t1.0, self.t1.1, if self.t1.0 { transform_sums(&self.pose, &self.t1.2) } else { self.t2.2 });
        if self.t2.0 {
            next.points.push_back((transform_result(&self.t2.2), self.t2.1));
        }
        // Lookup: one slot (two rows) a clock while the range queue has room for it.
        let lookup = self.lk.have && self.queue.len() + (self.rd.valid as usize) < RANGE_QUEUE;
        let rows = Self::slot_rows(self.lk.k, self.lk.slot);
        next.tq = [0, 1].map(|r| (lo_ram[rows[r].1], hi_ram[rows[r].2]));
        next.rd = Read {
            valid: lookup,
            in_a: rows[0].0,
            in_b: rows[1].0,
            last: self.lk.slot == 4,
            slast: self.lk.last,
            q: self.lk.q,
        };
        let lk_free = !self.lk.have || (lookup && self.lk.slot == 4);
        if lookup && self.lk.slot < 4 {
            next.lk.slot = Self::next_slot(self.lk.k, self.lk.slot + 1);
        }
        if lk_free {
            next.lk.have = !self.points.is_empty();
            if let Some(&(q, last)) = self.points.front() {
                next.points.pop_front();
                let k = q.map(axis_cell);
                next.lk = Lookup { have: true, q, last, k, slot: Self::next_slot(k, 0) };
            }
        }
        // The read slot joins the range queue as one entry, its rows A and B in place (rows
        // outside the grid or empty left out); a slot without any is dropped, except a
        // point's last slot, which is queued as a marker.
        if self.rd.valid {
            let ra = (self.rd.in_a && self.tq[0].0 < self.tq[0].1).then_some(self.tq[0]);
            let mut rb = (self.rd.in_b && self.tq[1].0 < self.tq[1].1).then_some(self.tq[1]);
            if self.rd.last {
                // The centre row, split: the A lanes take its even chunks, the B lanes its
                // odd ones (from `lo + P`, 14-bit sum, so no wrap), both striding `2P`.
                rb = ra.and_then(|(lo, hi)| (lo as usize + p < hi as usize).then_some((lo + p as u16, hi)));
            }
            if ra.is_some() || rb.is_some() || self.rd.last {
                next.queue.push_back(Entry { a: ra, b: rb, last: self.rd.last, slast: self.rd.slast, q: self.rd.q });
            }
        }
        // Issue: one chunk of each range a clock, range A through the A lanes and range B
        // through the B lanes, `addr .. min(addr + P, end)` each; lane `b` of a side takes its
        // side's bank `b`, row `(addr >> log2 P) + (b < addr mod P)`, valid if the side's
        // range is still running and its address is below `end`. A side then steps on by the
        // stride (`P`; `2P` in a point's last slot, the split centre row); one whose next
        // chunk would start at or past its end stops; the entry is done when both have (a
        // marker: at once, one clock with no valid lane).
        let is = self.is;
        let stride = if is.last { 2 * p } else { p };
        let mut bank_row = Vec::with_capacity(2 * p);
        let mut lane_valid = Vec::with_capacity(2 * p);
        let mut fin = [false; 2];
        for (side, ((addr, end), v)) in [(is.a, is.av), (is.b, is.bv)].into_iter().enumerate() {
            let (base, off) = ((addr >> self.log2) as usize, addr as usize & (p - 1));
            bank_row.extend((0..p).map(|b| ((base + (b < off) as usize) % (MAX_POINTS / p)) as u16));
            let span = end as usize - (addr as usize).min(end as usize);
            lane_valid.extend((0..p).map(|b| is.have && v && (b + p - off) % p < span.min(p)));
            fin[side] = addr as usize + stride >= end as usize;
        }
        next.bank_q = (0..2 * p).map(|j| ram[((bank_row[j] as usize) << self.log2) | (j % p)]).collect();
        let done = is.have && (!is.av || fin[0]) && (!is.bv || fin[1]);
        if is.have {
            next.chunks += 1;
            next.distances += lane_valid.iter().filter(|&&v| v).count() as u64;
            next.is.av = is.av && !fin[0];
            next.is.bv = is.bv && !fin[1];
            if is.av && !fin[0] {
                next.is.a.0 = is.a.0 + stride as u16;
            }
            if is.bv && !fin[1] {
                next.is.b.0 = is.b.0 + stride as u16;
            }
        }
        next.c0 = (Ctl { valid: is.have, last: done && is.last, slast: is.slast, q: is.q }, is.q, lane_valid, bank_row);
        if !is.have || done {
            next.is.have = !self.queue.is_empty();
            if let Some(e) = self.queue.front() {
                next.queue.pop_front();
                next.is = Issue {
                    have: true,
                    a: e.a.unwrap_or((0, 0)),
                    av: e.a.is_some(),
                    b: e.b.unwrap_or((0, 0)),
                    bv: e.b.is_some(),
                    last: e.last,
                    slast: e.slast,
                    q: e.q,
                };
            }
        }
        // Lanes: difference, square, two sums. The B
        // lanes (`p..2p`) square magnitudes below `B_SQUARE_LIMIT` only; a larger one gives
        // a capped key anyway, which `CAP_D2` in its square's place keeps.
        let (c0, q, v0, r0) = &self.c0;
        let d1 = (0..2 * p)
            .map(|b| {
                let m = unpack_point(self.bank_q[b]);
                [0, 1, 2].map(|k| q[k] as i32 - m[k] as i32)
            })
            .collect();
        next.s1 = (*c0, v0.clone(), r0.clone(), d1);
        let (c1, v1, r1, d) = &self.s1;
        let square = |j: usize, v: i32| {
            let v = v as i64;
            if j >= p && v.abs() >= B_SQUARE_LIMIT {
                CAP_D2
            } else {
                (v * v) as u64
            }
        };
        next.s2 = (*c1, v1.clone(), r1.clone(), d.iter().enumerate().map(|(j, d)| d.map(|v| square(j, v))).collect());
        let (c2, v2, r2, sq) = &self.s2;
        next.s3 = (*c2, v2.clone(), r2.clone(), sq.iter().map(|s| (s[0] + s[1], s[2])).collect());
        let (c3, v3, r3, s) = &self.s3;
        next.s4 = (*c3, v3.clone(), r3.clone(), s.iter().map(|(a, b)| a + b).collect());
        // Clamp: a lane without a candidate, or at a distance of at least CAP_D2, is the
        // neutral (CAP_D2, 0); the index is the bank row and the lane number.
        let (c4, v4, r4, s4) = &self.s4;
        let keys = (0..2 * p)
            .map(|j| {
                if v4[j] && s4[j] < CAP_D2 {
                    key(s4[j], ((r4[j] as usize) << self.log2 | (j % p)) as u16)
                } else {
                    CAP_KEY
                }
            })
            .collect();
        next.tree[0] = (*c4, keys);
        // The tree has five levels whatever `P`: each side padded to 16 leaves with the
        // neutral key (A lanes in leaves 0..16, B lanes in 16..32), four levels a side, then
        // the smaller side.
        for l in 1..self.tree.len() {
            let (c, k) = &self.tree[l - 1];
            let padded: Vec<u64> = if l == 1 {
                (0..TREE_LEAVES)
                    .map(|j| {
                        let (side, b) = (j / MAX_LANES, j % MAX_LANES);
                        if b < p {
                            k[side * p + b]
                        } else {
                            CAP_KEY
                        }
                    })
                    .collect()
            } else {
                k.clone()
            };
            next.tree[l] = (*c, padded.chunks(2).map(|pair| pair[0].min(pair[1])).collect());
        }
        // Accumulate a point's chunks; its last chunk presents the result.
        let (ct, kt) = &self.tree[self.tree.len() - 1];
        next.out.nn_valid = false;
        next.out.cost_valid = false;
        if ct.valid {
            let m = if self.acc_used { self.acc.min(kt[0]) } else { kt[0] };
            if ct.last {
                next.out.nn_valid = true;
                next.out.nn_index = (m & 0xfff) as u16;
                next.out.nn_dist = m >> 12;
                next.out.nn_point = ct.q;
                next.acc_used = false;
                next.fin = ct.slast;
            } else {
                next.acc = m;
                next.acc_used = true;
            }
        }
        // The cost adds each result the edge after it is presented (off the accumulator's
        // compare path); the particle's end presents the sum with the last result.
        let cost_sum = (self.cost + self.out.nn_dist) & COST_MASK;
        if self.out.nn_valid {
            next.cost = cost_sum;
        }
        // Memories: read first (above), then written.
        if i.model_we {
            ram[(i.model_waddr as usize) % MAX_POINTS] = i.model_wdata & ((1 << POINT_WORD_BITS) - 1);
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
        // State machine.
        match self.state {
            State::Idle => {
                if i.start {
                    next.state = State::Run;
                    next.pose = i.pose;
                    next.cost = 0;
                    next.last_taken = false;
                }
            }
            State::Run => {
                if take {
                    next.last_taken = i.scan_last;
                }
                if self.fin {
                    next.out.cost_valid = true;
                    next.out.cost = cost_sum;
                    next.fin = false;
                    next.state = State::Idle;
                }
            }
        }
        *self = next;
    }
}

impl StreamModel for NeighbourPipelineModel {
    type Inputs = GridInputs;
    fn step(&mut self, inputs: &GridInputs) {
        NeighbourPipelineModel::step(self, inputs)
    }
    fn outputs(&self) -> Outputs {
        NeighbourPipelineModel::outputs(self)
    }
    fn offer(scan: &[FxPoint], next: usize, offer: bool) -> GridInputs {
        GridInputs::offer(scan, next, offer)
    }
}
