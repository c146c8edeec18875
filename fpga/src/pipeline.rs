//! The bit-exact, cycle-accurate reference of the nearest-neighbour pipeline
//! (docs/pipeline.md), and the plain functional reference it must agree with.
//!
//! [`PipelineModel::step`] is one rising clock edge: it takes the input ports as they are
//! before the edge and updates every register as the RTL does; [`PipelineModel::outputs`]
//! gives the output ports after the edge. The co-simulation compares them with the
//! Verilated RTL on every clock.

use crate::format::{dist2, pack_point, transform, unpack_point, FxPoint, FxPose, MATRIX_FRAC, MAX_POINTS};

/// Squared distances are below this; a lane's minimum starts here.
pub const DIST_INIT: u64 = (1 << crate::format::DIST_BITS) - 1;
/// Mask of a 48-bit cost.
pub use crate::format::COST_MASK;

/// Input ports (before an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Inputs {
    /// Write `model_wdata` at `model_waddr`.
    pub model_we: bool,
    /// Model write address (12 bits).
    pub model_waddr: u16,
    /// Model write data (48 bits, [`pack_point`]).
    pub model_wdata: u64,
    /// Model points (1..=4096), sampled with `start`.
    pub model_count: u16,
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

impl Inputs {
    /// Write model point `p` at address `addr`.
    pub fn write_model(addr: usize, p: FxPoint) -> Inputs {
        Inputs { model_we: true, model_waddr: addr as u16, model_wdata: pack_point(p), ..Default::default() }
    }

    /// Begin a particle with `pose` on the first `model_count` model points.
    pub fn start(pose: &FxPose, model_count: usize) -> Inputs {
        Inputs { start: true, pose: *pose, model_count: model_count as u16, ..Default::default() }
    }

    /// If `offer`, offer scan point `next` of `scan` (`scan_last` on the last one);
    /// otherwise nothing.
    pub fn offer(scan: &[FxPoint], next: usize, offer: bool) -> Inputs {
        Inputs {
            scan_valid: offer,
            scan_data: if offer { pack_point(scan[next]) } else { 0 },
            scan_last: offer && next + 1 == scan.len(),
            ..Default::default()
        }
    }
}

/// Output ports (after an edge).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outputs {
    /// The pipeline takes an offered point at the next edge.
    pub scan_ready: bool,
    /// Not idle.
    pub busy: bool,
    /// A nearest-neighbour result is presented.
    pub nn_valid: bool,
    /// Its model index.
    pub nn_index: u16,
    /// Its squared distance (34 bits).
    pub nn_dist: u64,
    /// The particle's cost is presented (one clock).
    pub cost_valid: bool,
    /// The cost (48 bits).
    pub cost: u64,
    /// The neighbour pipeline's (`NeighbourPipelineModel`, RTL port `nn_point`) transformed
    /// scan point `q` of the result in `nn_index`/`nn_dist`: registered on the same edges
    /// (so while `nn_valid` is low it holds the last result's point; `[0, 0, 0]` after
    /// reset). The brute-force (`PipelineModel`) and grid (`GridPipelineModel`) pipelines
    /// have no such port: their models leave it `[0, 0, 0]` and their lockstep wrappers do
    /// not compare it.
    pub nn_point: FxPoint,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Idle,
    Load,
    Sweep,
    Reduce,
}

/// One stage of the sweep pipeline: valid bit, model index and per-lane data.
#[derive(Clone, Debug)]
struct Stage<T> {
    valid: bool,
    index: u16,
    lanes: Vec<T>,
}

impl<T: Clone + Default> Stage<T> {
    fn new(p: usize) -> Self {
        Stage { valid: false, index: 0, lanes: vec![T::default(); p] }
    }
}

/// The register state of the pipeline with `P` lanes.
#[derive(Clone, Debug)]
pub struct PipelineModel {
    lanes: usize,
    ram: Vec<u64>,
    state: State,
    pose: FxPose,
    model_count: u16,
    taken: usize,
    last_taken: bool,
    t1_valid: bool,
    t1_prod: [i64; 9],
    t2_valid: bool,
    t2_acc: [i64; 3],
    lane_wr: usize,
    lane_x: Vec<FxPoint>,
    n_lanes: usize,
    addr: u16,
    ram_q: u64,
    s0_valid: bool,
    s0_index: u16,
    s1: Stage<[i32; 3]>,
    s2: Stage<[u64; 3]>,
    s3: Stage<(u64, u64)>,
    s4: Stage<u64>,
    lane_min: Vec<u64>,
    lane_arg: Vec<u16>,
    reduce_at: usize,
    cost: u64,
    out: Outputs,
}

impl PipelineModel {
    /// A pipeline with `lanes` lanes, after reset (idle, model RAM all zero).
    pub fn new(lanes: usize) -> Self {
        assert!((1..=64).contains(&lanes), "1 to 64 lanes");
        PipelineModel {
            lanes,
            ram: vec![0; MAX_POINTS],
            state: State::Idle,
            pose: FxPose::default(),
            model_count: 0,
            taken: 0,
            last_taken: false,
            t1_valid: false,
            t1_prod: [0; 9],
            t2_valid: false,
            t2_acc: [0; 3],
            lane_wr: 0,
            lane_x: vec![[0; 3]; lanes],
            n_lanes: 0,
            addr: 0,
            ram_q: 0,
            s0_valid: false,
            s0_index: 0,
            s1: Stage::new(lanes),
            s2: Stage::new(lanes),
            s3: Stage::new(lanes),
            s4: Stage::new(lanes),
            lane_min: vec![0; lanes],
            lane_arg: vec![0; lanes],
            reduce_at: 0,
            cost: 0,
            out: Outputs::default(),
        }
    }

    /// Number of lanes.
    pub fn lanes(&self) -> usize {
        self.lanes
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
    pub fn step(&mut self, i: &Inputs) {
        let take = self.scan_ready() && i.scan_valid;
        // The registers are copied to compute the next state; the RAM is moved, not copied
        // (read first, then written, as the block RAM does).
        let mut ram = std::mem::take(&mut self.ram);
        let mut next = self.clone();
        next.ram_q = ram[(self.addr as usize) % MAX_POINTS];
        if i.model_we {
            ram[(i.model_waddr as usize) % MAX_POINTS] = i.model_wdata & ((1 << crate::format::POINT_WORD_BITS) - 1);
        }
        next.ram = ram;
        // Transform pipeline (runs in every state; only Load feeds it).
        next.t1_valid = take;
        if take {
            next.t1_prod = transform_products(&self.pose, i.scan_data);
        }
        next.t2_valid = self.t1_valid;
        if self.t1_valid {
            next.t2_acc = transform_sums(&self.pose, &self.t1_prod);
        }
        if self.t2_valid && self.lane_wr < self.lanes {
            next.lane_x[self.lane_wr] = transform_result(&self.t2_acc);
            next.lane_wr = self.lane_wr + 1;
        }
        // Sweep pipeline (stages advance every clock).
        let issue = self.state == State::Sweep && self.addr < self.model_count;
        next.s0_valid = issue;
        next.s0_index = self.addr;
        if issue {
            next.addr = self.addr + 1;
        }
        let d = unpack_point(self.ram_q);
        next.s1 = Stage {
            valid: self.s0_valid,
            index: self.s0_index,
            lanes: self.lane_x.iter().map(|x| [0, 1, 2].map(|k| x[k] as i32 - d[k] as i32)).collect(),
        };
        next.s2 = Stage {
            valid: self.s1.valid,
            index: self.s1.index,
            lanes: self.s1.lanes.iter().map(|dx| dx.map(|v| (v as i64 * v as i64) as u64)).collect(),
        };
        next.s3 = Stage {
            valid: self.s2.valid,
            index: self.s2.index,
            lanes: self.s2.lanes.iter().map(|sq| (sq[0] + sq[1], sq[2])).collect(),
        };
        next.s4 = Stage {
            valid: self.s3.valid,
            index: self.s3.index,
            lanes: self.s3.lanes.iter().map(|(a, b)| a + b).collect(),
        };
        if self.s4.valid {
            for l in 0..self.lanes {
                if self.s4.lanes[l] < self.lane_min[l] {
                    next.lane_min[l] = self.s4.lanes[l];
                    next.lane_arg[l] = self.s4.index;
                }
            }
        }
        // Outputs that strobe.
        next.out.nn_valid = false;
        next.out.cost_valid = false;
        // State machine.
        match self.state {
            State::Idle => {
                if i.start {
                    next.state = State::Load;
                    next.pose = i.pose;
                    next.model_count = i.model_count;
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
                    next.addr = 0;
                    next.n_lanes = self.lane_wr;
                    next.lane_min = vec![DIST_INIT; self.lanes];
                    next.lane_arg = vec![0; self.lanes];
                }
            }
            State::Sweep => {
                let empty =
                    !issue && !self.s0_valid && !self.s1.valid && !self.s2.valid && !self.s3.valid && !self.s4.valid;
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

/// The transform pipeline's first stage (the edge after a take): the nine products
/// `m_ij * p_j` of the scan word `point` (docs/pipeline.md, Load). Shared by the cycle
/// models of both pipelines; [`crate::format::transform`] is the same arithmetic at once.
pub fn transform_products(pose: &FxPose, point: u64) -> [i64; 9] {
    let p = unpack_point(point);
    std::array::from_fn(|k| pose.m[k] as i64 * p[k % 3] as i64)
}

/// The second stage: each row's sum with the translation and the rounding half.
pub fn transform_sums(pose: &FxPose, prod: &[i64; 9]) -> [i64; 3] {
    std::array::from_fn(|r| {
        prod[3 * r] + prod[3 * r + 1] + prod[3 * r + 2] + ((pose.t[r] as i64) << MATRIX_FRAC) + (1 << (MATRIX_FRAC - 1))
    })
}

/// The third stage: the shift and the saturation to a coordinate.
pub fn transform_result(acc: &[i64; 3]) -> FxPoint {
    acc.map(|a| (a >> MATRIX_FRAC).clamp(i16::MIN as i64, i16::MAX as i64) as i16)
}

/// What the pipeline computes for one particle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Evaluation {
    /// Sum of the squared distances (48-bit wrap, never reached for 4,096 points).
    pub cost: u64,
    /// Per scan point: nearest model index (lowest on ties) and squared distance.
    pub nearest: Vec<(u16, u64)>,
}

/// The functional reference: transform every scan point, brute-force nearest model point.
pub fn evaluate(model: &[FxPoint], scan: &[FxPoint], pose: &FxPose) -> Evaluation {
    let nearest: Vec<(u16, u64)> = scan
        .iter()
        .map(|&p| {
            let x = transform(pose, p);
            let mut best = (0u16, DIST_INIT);
            for (k, &d) in model.iter().enumerate() {
                let e = dist2(x, d);
                if e < best.1 {
                    best = (k as u16, e);
                }
            }
            best
        })
        .collect();
    let cost = nearest.iter().fold(0u64, |c, n| (c + n.1) & COST_MASK);
    Evaluation { cost, nearest }
}

/// Drive a [`PipelineModel`] through one particle: load the model, start, stream the scan
/// (offering a point on clocks where `gap(clock)` is false), collect the results. Returns
/// the evaluation and the number of clocks from `start` to `cost_valid`.
pub fn run_particle(
    pipe: &mut PipelineModel,
    model: &[FxPoint],
    scan: &[FxPoint],
    pose: &FxPose,
    gap: impl FnMut(u64) -> bool,
) -> (Evaluation, u64) {
    assert!(!scan.is_empty() && !model.is_empty() && model.len() <= MAX_POINTS);
    for (a, &p) in model.iter().enumerate() {
        pipe.step(&Inputs::write_model(a, p));
    }
    pipe.step(&Inputs::start(pose, model.len()));
    stream_particle(pipe, scan, gap)
}

/// A cycle model with the pipelines' scan stream and result ports (`NnPipeline`'s and, with
/// [`crate::grid_pipeline::GridInputs`], the grid and neighbour pipelines'): one rising
/// edge a [`step`](StreamModel::step), the output ports after it.
pub trait StreamModel {
    /// The input ports.
    type Inputs;
    /// One rising edge with these inputs.
    fn step(&mut self, inputs: &Self::Inputs);
    /// The output ports after the last edge.
    fn outputs(&self) -> Outputs;
    /// The inputs offering scan point `next` (or nothing, with `offer` false).
    fn offer(scan: &[FxPoint], next: usize, offer: bool) -> Self::Inputs;
}

impl StreamModel for PipelineModel {
    type Inputs = Inputs;
    fn step(&mut self, inputs: &Inputs) {
        PipelineModel::step(self, inputs)
    }
    fn outputs(&self) -> Outputs {
        PipelineModel::outputs(self)
    }
    fn offer(scan: &[FxPoint], next: usize, offer: bool) -> Inputs {
        Inputs::offer(scan, next, offer)
    }
}

/// The one driver of a particle's scan stream, for every [`StreamModel`]: from the edge after
/// `start` (the caller's, counted as the first clock), offer scan point after scan point on
/// clocks where `gap(clock)` is false, collect the results, and return them and the clocks
/// from the `start` edge to the `cost_valid` edge.
pub fn stream_particle<M: StreamModel>(
    pipe: &mut M,
    scan: &[FxPoint],
    mut gap: impl FnMut(u64) -> bool,
) -> (Evaluation, u64) {
    let mut next = 0;
    let mut nearest = Vec::with_capacity(scan.len());
    let mut clocks = 1u64;
    loop {
        let offer = next < scan.len() && !gap(clocks);
        let inputs = M::offer(scan, next, offer);
        let took = offer && pipe.outputs().scan_ready;
        pipe.step(&inputs);
        clocks += 1;
        next += took as usize;
        let o = pipe.outputs();
        if o.nn_valid {
            nearest.push((o.nn_index, o.nn_dist));
        }
        if o.cost_valid {
            return (Evaluation { cost: o.cost, nearest }, clocks);
        }
        assert!(clocks < 1 << 40, "pipeline never finished");
    }
}

/// Clocks per particle from `start` to `cost_valid` with no gaps in the scan stream.
pub fn clocks_per_particle(scan_points: usize, model_points: usize, lanes: usize) -> u64 {
    let mut clocks = 1u64; // the start edge
    let mut left = scan_points;
    while left > 0 {
        let batch = left.min(lanes);
        left -= batch;
        // load: batch takes + 2 transform edges + 1 to Sweep; sweep: N + 6 + 1 to Reduce;
        // reduce: batch + 1.
        clocks += (batch + 3) as u64 + (model_points + 6) as u64 + (batch + 1) as u64;
    }
    clocks
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(seed: &mut u64) -> u64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        *seed >> 33
    }

    fn cloud(n: usize, seed: &mut u64, range: i64) -> Vec<FxPoint> {
        (0..n).map(|_| [0; 3].map(|_: i16| ((lcg(seed) as i64 % (2 * range + 1)) - range) as i16)).collect()
    }

    #[test]
    fn cycle_model_equals_functional_reference() {
        let mut seed = 5;
        for (lanes, n_model, n_scan) in [(4, 37, 9), (16, 200, 33), (3, 1, 1), (8, 64, 8), (5, 10, 25)] {
            let model = cloud(n_model, &mut seed, 9000);
            let scan = cloud(n_scan, &mut seed, 9000);
            let pose = FxPose::from_f64(&[0.9, -0.3, 0.1, 0.3, 0.9, 0.0, -0.1, 0.05, 0.95], &[0.1, -0.2, 0.05]);
            let mut pipe = PipelineModel::new(lanes);
            let (got, clocks) = run_particle(&mut pipe, &model, &scan, &pose, |_| false);
            assert_eq!(got, evaluate(&model, &scan, &pose), "P={lanes} N_D={n_model} N_M={n_scan}");
            assert_eq!(clocks, clocks_per_particle(n_scan, n_model, lanes), "P={lanes} N_D={n_model} N_M={n_scan}");
            // Gaps in the stream change the timing, never the result.
            let mut pipe = PipelineModel::new(lanes);
            let (gapped, _) = run_particle(&mut pipe, &model, &scan, &pose, |c| c % 3 == 1);
            assert_eq!(gapped, got);
        }
    }

    #[test]
    fn ties_go_to_the_lowest_index() {
        let model = vec![[100, 0, 0], [-100, 0, 0], [100, 0, 0]];
        let pose = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
        let e = evaluate(&model, &[[0, 0, 0], [200, 0, 0]], &pose);
        assert_eq!(e.nearest, vec![(0, 10000), (0, 10000)]);
        let mut pipe = PipelineModel::new(2);
        assert_eq!(run_particle(&mut pipe, &model, &[[0, 0, 0], [200, 0, 0]], &pose, |_| false).0, e);
    }

    #[test]
    fn start_is_ignored_while_busy() {
        let mut pipe = PipelineModel::new(2);
        pipe.step(&Inputs { start: true, model_count: 5, ..Default::default() });
        assert!(pipe.outputs().busy && pipe.outputs().scan_ready);
        pipe.step(&Inputs { start: true, model_count: 9, ..Default::default() });
        assert_eq!(pipe.model_count, 5);
    }
}
