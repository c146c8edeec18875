//! `NeighbourPipeline<P>`: the neighbour pipeline (docs/pipeline.md, "The neighbour
//! pipeline") with `P` lanes over the candidates of one scan point, register for register
//! the cycle-accurate reference [`crate::search::neighbour_pipeline::NeighbourPipelineModel`]: the
//! transform ([`Transform`]) into a point queue; a lookup stage that reads two of the point's
//! nine rows (a slot) a clock from two copies of the cell table (four 4096 x 13 block RAMs);
//! a queue of looked-up slots; the chunk issue (`P` consecutive addresses of each of the
//! slot's two ranges a clock; a point's last slot, the centre row, split over both sets,
//! even chunks A, odd chunks B, stride `2P`); `P` [`NeighbourLane`]s (A, range A, squares in
//! DSP48A1s) and `P` [`NeighbourLaneB`]s (B, range B, squares from block-RAM tables), each
//! with its bank of the model RAM (two copies, written together); a registered min-tree over `(d2, index)`
//! keys, four levels a side and one across; the per-point accumulator and the cost. Each
//! chunk's point (`c0_q`) rides a delay line beside the control bits (`ctl_q`, a shift
//! register) to the accumulator, where a point's last chunk registers it as `nn_point`.
//!
//! This file holds the ports, registers and sub-blocks; the clocked logic (one `update`)
//! is `neighbour_pipeline_kernel_rtl.rs`.

use crate::search::grid::CAP_D2;
use crate::search::neighbour_lane_rtl::{NeighbourLane, NeighbourLaneB};
use crate::search::neighbour_pipeline::{MAX_LANES, POINT_QUEUE, RANGE_QUEUE};
use crate::search::transform_rtl::Transform;
use rust_hdl::prelude::*;

#[path = "neighbour_pipeline_kernel_rtl.rs"]
mod kernel;

// The RTL's queues hold four entries.
const _: () = assert!(POINT_QUEUE == 4 && RANGE_QUEUE == 4);

/// The neighbour pipeline with `P` lanes (a power of two, 2 to 16).
#[derive(LogicBlock)]
pub struct NeighbourPipeline<const P: usize> {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Write `model_wdata` to model RAM word `model_waddr` at this edge.
    pub model_we: Signal<In, Bit>,
    /// Model write address.
    pub model_waddr: Signal<In, Bits<12>>,
    /// Model write data (x | y | z, Q3.13).
    pub model_wdata: Signal<In, Bits<48>>,
    /// Write `table_wdata` as cell-table entry `table_waddr` at this edge.
    pub table_we: Signal<In, Bit>,
    /// Cell-table entry `0..=4096` (`first[c]`; larger addresses write nothing).
    pub table_waddr: Signal<In, Bits<13>>,
    /// The entry: the stored index of cell `table_waddr`'s first point.
    pub table_wdata: Signal<In, Bits<13>>,
    /// Begin a particle (honoured when idle).
    pub start: Signal<In, Bit>,
    /// `m[0..9]`, `t[0..3]`, 18-bit two's complement each; sampled with `start`.
    pub pose: Signal<In, Bits<216>>,
    /// A scan point is offered.
    pub scan_valid: Signal<In, Bit>,
    /// The offered point.
    pub scan_data: Signal<In, Bits<48>>,
    /// The offered point is the particle's last.
    pub scan_last: Signal<In, Bit>,
    /// The offered point is taken at this edge if `scan_valid`.
    pub scan_ready: Signal<Out, Bit>,
    /// Not idle.
    pub busy: Signal<Out, Bit>,
    /// `nn_index`/`nn_dist` hold the next scan point's result (one-clock strobe).
    pub nn_valid: Signal<Out, Bit>,
    /// Index of the nearest model point.
    pub nn_index: Signal<Out, Bits<12>>,
    /// Its squared distance (Q8.26), at most `CAP_D2`.
    pub nn_dist: Signal<Out, Bits<34>>,
    /// The transformed scan point `q` whose result `nn_index`/`nn_dist` hold (packed x | y | z,
    /// Q3.13), registered on the same edges (while `nn_valid` is low: the last result's).
    pub nn_point: Signal<Out, Bits<48>>,
    /// `cost` holds the particle's cost (one-clock strobe).
    pub cost_valid: Signal<Out, Bit>,
    /// Sum of the squared distances (Q22.26).
    pub cost: Signal<Out, Bits<48>>,
    pc13: Constant<Bits<13>>,
    pc14: Constant<Bits<14>>,
    pc13x2: Constant<Bits<13>>,
    pc14x2: Constant<Bits<14>>,
    c_off: Constant<Bits<6>>,
    cap_key: Constant<Bits<33>>,
    qid: [Constant<Bits<2>>; 4],
    run: DFF<Bit>,
    last_taken: DFF<Bit>,
    l1: DFF<Bit>,
    l2: DFF<Bit>,
    transform: Transform,
    // Point queue.
    pq_x: [DFF<Bits<48>>; 4],
    pq_l: [DFF<Bit>; 4],
    pq_rd: DFF<Bits<2>>,
    pq_wr: DFF<Bits<2>>,
    pq_n: DFF<Bits<3>>,
    // Lookup stage.
    lk_have: DFF<Bit>,
    lk_q: DFF<Bits<48>>,
    lk_last: DFF<Bit>,
    lk_slot: DFF<Bits<3>>,
    lk_vy: [DFF<Bit>; 3],
    lk_vz: [DFF<Bit>; 3],
    lk_y: [DFF<Bits<4>>; 3],
    lk_z: [DFF<Bits<4>>; 3],
    lk_x0: DFF<Bits<4>>,
    lk_x1: DFF<Bits<4>>,
    lk_mask: [DFF<Bit>; 4],
    lo_a: RAM<Bits<13>, 12>,
    hi_a: RAM<Bits<13>, 12>,
    lo_b: RAM<Bits<13>, 12>,
    hi_b: RAM<Bits<13>, 12>,
    rd_valid: DFF<Bit>,
    rd_in_a: DFF<Bit>,
    rd_in_b: DFF<Bit>,
    rd_last: DFF<Bit>,
    rd_slast: DFF<Bit>,
    rd_q: DFF<Bits<48>>,
    // Range queue.
    rq_alo: [DFF<Bits<13>>; 4],
    rq_ahi: [DFF<Bits<13>>; 4],
    rq_blo: [DFF<Bits<13>>; 4],
    rq_bhi: [DFF<Bits<13>>; 4],
    rq_av: [DFF<Bit>; 4],
    rq_bv: [DFF<Bit>; 4],
    rq_last: [DFF<Bit>; 4],
    rq_slast: [DFF<Bit>; 4],
    rq_q: [DFF<Bits<48>>; 4],
    rq_rd: DFF<Bits<2>>,
    rq_wr: DFF<Bits<2>>,
    rq_n: DFF<Bits<3>>,
    // Issue.
    is_have: DFF<Bit>,
    is_addr: DFF<Bits<13>>,
    is_end: DFF<Bits<13>>,
    is_av: DFF<Bit>,
    is_baddr: DFF<Bits<13>>,
    is_bend: DFF<Bits<13>>,
    is_bv: DFF<Bit>,
    is_last: DFF<Bit>,
    is_slast: DFF<Bit>,
    is_q: DFF<Bits<48>>,
    // Chunk register, then the control delay line: s1..s4, keys, tree levels 1..5.
    c0_valid: DFF<Bit>,
    c0_last: DFF<Bit>,
    c0_slast: DFF<Bit>,
    c0_q: DFF<Bits<48>>,
    ctl_v: [DFF<Bit>; 10],
    ctl_l: [DFF<Bit>; 10],
    ctl_s: [DFF<Bit>; 10],
    // The chunk's point beside the control (no enable, no logic: a shift register).
    ctl_q: [DFF<Bits<48>>; 10],
    lanes: [NeighbourLane; P],
    lanes_b: [NeighbourLaneB; P],
    // The min-tree: the A lanes' four levels (t), the B lanes' (u), then the smaller (t5).
    t1: [DFF<Bits<33>>; 8],
    t2: [DFF<Bits<33>>; 4],
    t3: [DFF<Bits<33>>; 2],
    t4: DFF<Bits<33>>,
    u1: [DFF<Bits<33>>; 8],
    u2: [DFF<Bits<33>>; 4],
    u3: [DFF<Bits<33>>; 2],
    u4: DFF<Bits<33>>,
    t5: DFF<Bits<33>>,
    acc_used: DFF<Bit>,
    acc: DFF<Bits<33>>,
    fin: DFF<Bit>,
    cost_acc: DFF<Bits<48>>,
    nn_valid_r: DFF<Bit>,
    nn_index_r: DFF<Bits<12>>,
    nn_dist_r: DFF<Bits<34>>,
    nn_point_r: DFF<Bits<48>>,
    cost_valid_r: DFF<Bit>,
    cost_r: DFF<Bits<48>>,
    // Combinational.
    ready: Signal<Local, Bit>,
    taddr_m1: Signal<Local, Bits<13>>,
    take: Signal<Local, Bit>,
    pq_head: Signal<Local, Bits<48>>,
    pq_head_l: Signal<Local, Bit>,
    hu: [Signal<Local, Bits<6>>; 3],
    h_vx: Signal<Local, Bit>,
    h_vy: [Signal<Local, Bit>; 3],
    h_vz: [Signal<Local, Bit>; 3],
    h_mask: [Signal<Local, Bit>; 4],
    h_first: Signal<Local, Bits<3>>,
    lk_next: Signal<Local, Bits<3>>,
    lookup: Signal<Local, Bit>,
    lk_free: Signal<Local, Bit>,
    pq_pop: Signal<Local, Bit>,
    ra_y: Signal<Local, Bits<4>>,
    ra_z: Signal<Local, Bits<4>>,
    ra_in: Signal<Local, Bit>,
    rb_y: Signal<Local, Bits<4>>,
    rb_z: Signal<Local, Bits<4>>,
    rb_in: Signal<Local, Bit>,
    ra_ok: Signal<Local, Bit>,
    rb_ok: Signal<Local, Bit>,
    split_lo: Signal<Local, Bits<14>>,
    split_ok: Signal<Local, Bit>,
    push: Signal<Local, Bit>,
    rq_pop: Signal<Local, Bit>,
    span: Signal<Local, Bits<14>>,
    span_b: Signal<Local, Bits<14>>,
    stride13: Signal<Local, Bits<13>>,
    stride14: Signal<Local, Bits<14>>,
    fin_a: Signal<Local, Bit>,
    fin_b: Signal<Local, Bit>,
    done: Signal<Local, Bit>,
    ch_last: Signal<Local, Bit>,
    m: Signal<Local, Bits<33>>,
    nn_d: Signal<Local, Bits<34>>,
    cost_sum: Signal<Local, Bits<48>>,
}

impl<const P: usize> NeighbourPipeline<P> {
    /// After reset: idle, model RAM and table all zero.
    pub fn new() -> Self {
        assert!(P.is_power_of_two() && (2..=MAX_LANES).contains(&P), "2, 4, 8 or 16 lanes");
        NeighbourPipeline {
            clock: Default::default(),
            model_we: Default::default(),
            model_waddr: Default::default(),
            model_wdata: Default::default(),
            table_we: Default::default(),
            table_waddr: Default::default(),
            table_wdata: Default::default(),
            start: Default::default(),
            pose: Default::default(),
            scan_valid: Default::default(),
            scan_data: Default::default(),
            scan_last: Default::default(),
            scan_ready: Default::default(),
            busy: Default::default(),
            nn_valid: Default::default(),
            nn_index: Default::default(),
            nn_dist: Default::default(),
            nn_point: Default::default(),
            cost_valid: Default::default(),
            cost: Default::default(),
            pc13: Constant::new((P as u64).into()),
            pc14: Constant::new((P as u64).into()),
            pc13x2: Constant::new((2 * P as u64).into()),
            pc14x2: Constant::new((2 * P as u64).into()),
            c_off: Constant::new(32.into()),
            cap_key: Constant::new((CAP_D2 << 12).into()),
            qid: std::array::from_fn(|j| Constant::new((j as u64).into())),
            run: Default::default(),
            last_taken: Default::default(),
            l1: Default::default(),
            l2: Default::default(),
            transform: Default::default(),
            pq_x: Default::default(),
            pq_l: Default::default(),
            pq_rd: Default::default(),
            pq_wr: Default::default(),
            pq_n: Default::default(),
            lk_have: Default::default(),
            lk_q: Default::default(),
            lk_last: Default::default(),
            lk_slot: Default::default(),
            lk_vy: Default::default(),
            lk_vz: Default::default(),
            lk_y: Default::default(),
            lk_z: Default::default(),
            lk_x0: Default::default(),
            lk_x1: Default::default(),
            lk_mask: Default::default(),
            lo_a: Default::default(),
            hi_a: Default::default(),
            lo_b: Default::default(),
            hi_b: Default::default(),
            rd_valid: Default::default(),
            rd_in_a: Default::default(),
            rd_in_b: Default::default(),
            rd_last: Default::default(),
            rd_slast: Default::default(),
            rd_q: Default::default(),
            rq_alo: Default::default(),
            rq_ahi: Default::default(),
            rq_blo: Default::default(),
            rq_bhi: Default::default(),
            rq_av: Default::default(),
            rq_bv: Default::default(),
            rq_last: Default::default(),
            rq_slast: Default::default(),
            rq_q: Default::default(),
            rq_rd: Default::default(),
            rq_wr: Default::default(),
            rq_n: Default::default(),
            is_have: Default::default(),
            is_addr: Default::default(),
            is_end: Default::default(),
            is_av: Default::default(),
            is_baddr: Default::default(),
            is_bend: Default::default(),
            is_bv: Default::default(),
            is_last: Default::default(),
            is_slast: Default::default(),
            is_q: Default::default(),
            c0_valid: Default::default(),
            c0_last: Default::default(),
            c0_slast: Default::default(),
            c0_q: Default::default(),
            ctl_v: Default::default(),
            ctl_l: Default::default(),
            ctl_s: Default::default(),
            ctl_q: Default::default(),
            lanes: std::array::from_fn(|b| NeighbourLane::new(b, P)),
            lanes_b: std::array::from_fn(|b| NeighbourLaneB::new(b, P)),
            t1: Default::default(),
            t2: Default::default(),
            t3: Default::default(),
            t4: Default::default(),
            u1: Default::default(),
            u2: Default::default(),
            u3: Default::default(),
            u4: Default::default(),
            t5: Default::default(),
            acc_used: Default::default(),
            acc: Default::default(),
            fin: Default::default(),
            cost_acc: Default::default(),
            nn_valid_r: Default::default(),
            nn_index_r: Default::default(),
            nn_dist_r: Default::default(),
            nn_point_r: Default::default(),
            cost_valid_r: Default::default(),
            cost_r: Default::default(),
            ready: Default::default(),
            taddr_m1: Default::default(),
            take: Default::default(),
            pq_head: Default::default(),
            pq_head_l: Default::default(),
            hu: Default::default(),
            h_vx: Default::default(),
            h_vy: Default::default(),
            h_vz: Default::default(),
            h_mask: Default::default(),
            h_first: Default::default(),
            lk_next: Default::default(),
            lookup: Default::default(),
            lk_free: Default::default(),
            pq_pop: Default::default(),
            ra_y: Default::default(),
            ra_z: Default::default(),
            ra_in: Default::default(),
            rb_y: Default::default(),
            rb_z: Default::default(),
            rb_in: Default::default(),
            ra_ok: Default::default(),
            rb_ok: Default::default(),
            split_lo: Default::default(),
            split_ok: Default::default(),
            push: Default::default(),
            rq_pop: Default::default(),
            span: Default::default(),
            span_b: Default::default(),
            stride13: Default::default(),
            stride14: Default::default(),
            fin_a: Default::default(),
            fin_b: Default::default(),
            done: Default::default(),
            ch_last: Default::default(),
            m: Default::default(),
            nn_d: Default::default(),
            cost_sum: Default::default(),
        }
    }
}

impl<const P: usize> Default for NeighbourPipeline<P> {
    fn default() -> Self {
        Self::new()
    }
}
