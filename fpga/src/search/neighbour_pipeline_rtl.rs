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

use crate::search::grid::CAP_D2;
use crate::search::neighbour_lane_rtl::{NeighbourLane, NeighbourLaneB};
use crate::search::neighbour_pipeline::{MAX_LANES, POINT_QUEUE, RANGE_QUEUE};
use crate::search::transform_rtl::Transform;
use rust_hdl::prelude::*;

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

impl<const P: usize> Logic for NeighbourPipeline<P> {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self,
            clock,
            run,
            last_taken,
            l1,
            l2,
            pq_rd,
            pq_wr,
            pq_n,
            lk_have,
            lk_q,
            lk_last,
            lk_slot,
            lk_x0,
            lk_x1,
            rd_valid,
            rd_in_a,
            rd_in_b,
            rd_last,
            rd_slast,
            rd_q,
            rq_rd,
            rq_wr,
            rq_n,
            is_have,
            is_addr,
            is_end,
            is_av,
            is_baddr,
            is_bend,
            is_bv,
            is_last,
            is_slast,
            is_q,
            c0_valid,
            c0_last,
            c0_slast,
            c0_q,
            t4,
            u4,
            t5,
            acc_used,
            acc,
            fin,
            cost_acc,
            nn_valid_r,
            nn_index_r,
            nn_dist_r,
            nn_point_r,
            cost_valid_r,
            cost_r
        );
        for j in 0..4 {
            self.pq_x[j].clock.next = self.clock.val();
            self.pq_x[j].d.next = self.pq_x[j].q.val();
            self.pq_l[j].clock.next = self.clock.val();
            self.pq_l[j].d.next = self.pq_l[j].q.val();
            self.rq_alo[j].clock.next = self.clock.val();
            self.rq_alo[j].d.next = self.rq_alo[j].q.val();
            self.rq_ahi[j].clock.next = self.clock.val();
            self.rq_ahi[j].d.next = self.rq_ahi[j].q.val();
            self.rq_blo[j].clock.next = self.clock.val();
            self.rq_blo[j].d.next = self.rq_blo[j].q.val();
            self.rq_bhi[j].clock.next = self.clock.val();
            self.rq_bhi[j].d.next = self.rq_bhi[j].q.val();
            self.rq_av[j].clock.next = self.clock.val();
            self.rq_av[j].d.next = self.rq_av[j].q.val();
            self.rq_bv[j].clock.next = self.clock.val();
            self.rq_bv[j].d.next = self.rq_bv[j].q.val();
            self.rq_last[j].clock.next = self.clock.val();
            self.rq_last[j].d.next = self.rq_last[j].q.val();
            self.rq_slast[j].clock.next = self.clock.val();
            self.rq_slast[j].d.next = self.rq_slast[j].q.val();
            self.rq_q[j].clock.next = self.clock.val();
            self.rq_q[j].d.next = self.rq_q[j].q.val();
            self.lk_mask[j].clock.next = self.clock.val();
            self.lk_mask[j].d.next = self.lk_mask[j].q.val();
        }
        for k in 0..3 {
            self.lk_vy[k].clock.next = self.clock.val();
            self.lk_vy[k].d.next = self.lk_vy[k].q.val();
            self.lk_vz[k].clock.next = self.clock.val();
            self.lk_vz[k].d.next = self.lk_vz[k].q.val();
            self.lk_y[k].clock.next = self.clock.val();
            self.lk_y[k].d.next = self.lk_y[k].q.val();
            self.lk_z[k].clock.next = self.clock.val();
            self.lk_z[k].d.next = self.lk_z[k].q.val();
        }
        for k in 0..10 {
            self.ctl_v[k].clock.next = self.clock.val();
            self.ctl_l[k].clock.next = self.clock.val();
            self.ctl_s[k].clock.next = self.clock.val();
            self.ctl_q[k].clock.next = self.clock.val();
        }
        for j in 0..8 {
            self.t1[j].clock.next = self.clock.val();
            self.u1[j].clock.next = self.clock.val();
        }
        for j in 0..4 {
            self.t2[j].clock.next = self.clock.val();
            self.u2[j].clock.next = self.clock.val();
        }
        for j in 0..2 {
            self.t3[j].clock.next = self.clock.val();
            self.u3[j].clock.next = self.clock.val();
        }
        self.transform.clock.next = self.clock.val();
        self.lo_a.read_clock.next = self.clock.val();
        self.lo_a.write_clock.next = self.clock.val();
        self.hi_a.read_clock.next = self.clock.val();
        self.hi_a.write_clock.next = self.clock.val();
        self.lo_b.read_clock.next = self.clock.val();
        self.lo_b.write_clock.next = self.clock.val();
        self.hi_b.read_clock.next = self.clock.val();
        self.hi_b.write_clock.next = self.clock.val();
        for b in 0..P {
            self.lanes[b].clock.next = self.clock.val();
            self.lanes[b].model_we.next = self.model_we.val();
            self.lanes[b].model_waddr.next = self.model_waddr.val();
            self.lanes[b].model_wdata.next = self.model_wdata.val();
            // The B lanes' banks: the model RAM's second copy, written by the same writes.
            self.lanes_b[b].clock.next = self.clock.val();
            self.lanes_b[b].model_we.next = self.model_we.val();
            self.lanes_b[b].model_waddr.next = self.model_waddr.val();
            self.lanes_b[b].model_wdata.next = self.model_wdata.val();
        }
        // Status and the scan input: room in the point queue for the points in the transform.
        if self.transform.t1_valid.val() && self.transform.t2_valid.val() {
            self.ready.next = self.pq_n.q.val() < 2;
        } else if self.transform.t1_valid.val() || self.transform.t2_valid.val() {
            self.ready.next = self.pq_n.q.val() < 3;
        } else {
            self.ready.next = self.pq_n.q.val() < 4;
        }
        self.ready.next = self.ready.val() && self.run.q.val() && !self.last_taken.q.val();
        self.take.next = self.ready.val() && self.scan_valid.val();
        self.scan_ready.next = self.ready.val();
        self.busy.next = self.run.q.val();
        // Transform (pose latched with an honoured start), the last flag beside it.
        self.transform.load.next = !self.run.q.val() && self.start.val();
        self.transform.pose.next = self.pose.val();
        self.transform.take.next = self.take.val();
        self.transform.point.next = self.scan_data.val();
        self.l1.d.next = self.take.val() && self.scan_last.val();
        self.l2.d.next = self.l1.q.val();
        // Cell table: two copies of `lo[c] = first[c]` and `hi[c] = first[c + 1]`.
        self.taddr_m1.next = self.table_waddr.val() - 1;
        self.lo_a.write_address.next = self.table_waddr.val().get_bits::<12>(0);
        self.lo_a.write_data.next = self.table_wdata.val();
        self.lo_a.write_enable.next = self.table_we.val() && !self.table_waddr.val().get_bit(12);
        self.lo_b.write_address.next = self.table_waddr.val().get_bits::<12>(0);
        self.lo_b.write_data.next = self.table_wdata.val();
        self.lo_b.write_enable.next = self.table_we.val() && !self.table_waddr.val().get_bit(12);
        self.hi_a.write_address.next = self.taddr_m1.val().get_bits::<12>(0);
        self.hi_a.write_data.next = self.table_wdata.val();
        self.hi_a.write_enable.next =
            self.table_we.val() && (self.table_waddr.val() != 0) && !self.taddr_m1.val().get_bit(12);
        self.hi_b.write_address.next = self.taddr_m1.val().get_bits::<12>(0);
        self.hi_b.write_data.next = self.table_wdata.val();
        self.hi_b.write_enable.next =
            self.table_we.val() && (self.table_waddr.val() != 0) && !self.taddr_m1.val().get_bit(12);
        // Point queue head and its cells: per axis `u = (c >> 10) + 32` (the cell is u - 24).
        self.pq_head.next = self.pq_x[0].q.val();
        self.pq_head_l.next = self.pq_l[0].q.val();
        for j in 1..4 {
            if self.pq_rd.q.val() == self.qid[j].val() {
                self.pq_head.next = self.pq_x[j].q.val();
                self.pq_head_l.next = self.pq_l[j].q.val();
            }
        }
        for k in 0..3 {
            self.hu[k].next = self.pq_head.val().get_bits::<6>(16 * k + 10) ^ self.c_off.val();
        }
        // x: 0 <= k_x + 1 and k_x - 1 <= 15; row y (z) = k + d inside 0..=15.
        self.h_vx.next = (self.hu[0].val() >= 23) && (self.hu[0].val() <= 40);
        self.h_vy[0].next = self.h_vx.val() && (self.hu[1].val() >= 25) && (self.hu[1].val() <= 40);
        self.h_vy[1].next = self.h_vx.val() && (self.hu[1].val() >= 24) && (self.hu[1].val() <= 39);
        self.h_vy[2].next = self.h_vx.val() && (self.hu[1].val() >= 23) && (self.hu[1].val() <= 38);
        self.h_vz[0].next = (self.hu[2].val() >= 25) && (self.hu[2].val() <= 40);
        self.h_vz[1].next = (self.hu[2].val() >= 24) && (self.hu[2].val() <= 39);
        self.h_vz[2].next = (self.hu[2].val() >= 23) && (self.hu[2].val() <= 38);
        // Slots 0..3 (rows (dz, dy)): (-1, -1) (-1, 0) | (-1, 1) (0, -1) | (0, 1) (1, -1) |
        // (1, 0) (1, 1); slot 4 is the centre row.
        self.h_mask[0].next = self.h_vz[0].val() && (self.h_vy[0].val() || self.h_vy[1].val());
        self.h_mask[1].next = (self.h_vz[0].val() && self.h_vy[2].val()) || (self.h_vz[1].val() && self.h_vy[0].val());
        self.h_mask[2].next = (self.h_vz[1].val() && self.h_vy[2].val()) || (self.h_vz[2].val() && self.h_vy[0].val());
        self.h_mask[3].next = self.h_vz[2].val() && (self.h_vy[1].val() || self.h_vy[2].val());
        self.h_first.next = 4.into();
        if self.h_mask[3].val() {
            self.h_first.next = 3.into();
        }
        if self.h_mask[2].val() {
            self.h_first.next = 2.into();
        }
        if self.h_mask[1].val() {
            self.h_first.next = 1.into();
        }
        if self.h_mask[0].val() {
            self.h_first.next = 0.into();
        }
        // Lookup: the current slot's rows A and B.
        self.ra_y.next = self.lk_y[1].q.val();
        self.ra_z.next = self.lk_z[1].q.val();
        self.ra_in.next = self.lk_vy[1].q.val() && self.lk_vz[1].q.val();
        self.rb_y.next = self.lk_y[1].q.val();
        self.rb_z.next = self.lk_z[1].q.val();
        self.rb_in.next = false;
        if self.lk_slot.q.val() == 0 {
            self.ra_y.next = self.lk_y[0].q.val();
            self.ra_z.next = self.lk_z[0].q.val();
            self.ra_in.next = self.lk_vy[0].q.val() && self.lk_vz[0].q.val();
            self.rb_y.next = self.lk_y[1].q.val();
            self.rb_z.next = self.lk_z[0].q.val();
            self.rb_in.next = self.lk_vy[1].q.val() && self.lk_vz[0].q.val();
        } else if self.lk_slot.q.val() == 1 {
            self.ra_y.next = self.lk_y[2].q.val();
            self.ra_z.next = self.lk_z[0].q.val();
            self.ra_in.next = self.lk_vy[2].q.val() && self.lk_vz[0].q.val();
            self.rb_y.next = self.lk_y[0].q.val();
            self.rb_z.next = self.lk_z[1].q.val();
            self.rb_in.next = self.lk_vy[0].q.val() && self.lk_vz[1].q.val();
        } else if self.lk_slot.q.val() == 2 {
            self.ra_y.next = self.lk_y[2].q.val();
            self.ra_z.next = self.lk_z[1].q.val();
            self.ra_in.next = self.lk_vy[2].q.val() && self.lk_vz[1].q.val();
            self.rb_y.next = self.lk_y[0].q.val();
            self.rb_z.next = self.lk_z[2].q.val();
            self.rb_in.next = self.lk_vy[0].q.val() && self.lk_vz[2].q.val();
        } else if self.lk_slot.q.val() == 3 {
            self.ra_y.next = self.lk_y[1].q.val();
            self.ra_z.next = self.lk_z[2].q.val();
            self.ra_in.next = self.lk_vy[1].q.val() && self.lk_vz[2].q.val();
            self.rb_y.next = self.lk_y[2].q.val();
            self.rb_z.next = self.lk_z[2].q.val();
            self.rb_in.next = self.lk_vy[2].q.val() && self.lk_vz[2].q.val();
        }
        self.lo_a.read_address.next = (bit_cast::<12, 4>(self.ra_z.val()) << 8)
            | (bit_cast::<12, 4>(self.ra_y.val()) << 4)
            | bit_cast::<12, 4>(self.lk_x0.q.val());
        self.hi_a.read_address.next = (bit_cast::<12, 4>(self.ra_z.val()) << 8)
            | (bit_cast::<12, 4>(self.ra_y.val()) << 4)
            | bit_cast::<12, 4>(self.lk_x1.q.val());
        self.lo_b.read_address.next = (bit_cast::<12, 4>(self.rb_z.val()) << 8)
            | (bit_cast::<12, 4>(self.rb_y.val()) << 4)
            | bit_cast::<12, 4>(self.lk_x0.q.val());
        self.hi_b.read_address.next = (bit_cast::<12, 4>(self.rb_z.val()) << 8)
            | (bit_cast::<12, 4>(self.rb_y.val()) << 4)
            | bit_cast::<12, 4>(self.lk_x1.q.val());
        // A slot is looked up while the range queue has room for it (the read slot counts).
        if self.rd_valid.q.val() {
            self.lookup.next = self.lk_have.q.val() && (self.rq_n.q.val() < 3);
        } else {
            self.lookup.next = self.lk_have.q.val() && (self.rq_n.q.val() < 4);
        }
        self.lk_next.next = 4.into();
        if self.lk_mask[3].q.val() && (self.lk_slot.q.val() < 3) {
            self.lk_next.next = 3.into();
        }
        if self.lk_mask[2].q.val() && (self.lk_slot.q.val() < 2) {
            self.lk_next.next = 2.into();
        }
        if self.lk_mask[1].q.val() && (self.lk_slot.q.val() < 1) {
            self.lk_next.next = 1.into();
        }
        self.rd_valid.d.next = self.lookup.val();
        self.rd_in_a.d.next = self.ra_in.val();
        self.rd_in_b.d.next = self.rb_in.val();
        self.rd_last.d.next = self.lk_slot.q.val() == 4;
        self.rd_slast.d.next = self.lk_last.q.val();
        self.rd_q.d.next = self.lk_q.q.val();
        self.lk_free.next = !self.lk_have.q.val() || (self.lookup.val() && (self.lk_slot.q.val() == 4));
        self.pq_pop.next = self.lk_free.val() && (self.pq_n.q.val() != 0);
        if self.lookup.val() && (self.lk_slot.q.val() != 4) {
            self.lk_slot.d.next = self.lk_next.val();
        }
        if self.lk_free.val() {
            self.lk_have.d.next = self.pq_n.q.val() != 0;
        }
        if self.pq_pop.val() {
            self.lk_q.d.next = self.pq_head.val();
            self.lk_last.d.next = self.pq_head_l.val();
            self.lk_slot.d.next = self.h_first.val();
            self.lk_x0.d.next = 0.into();
            if self.hu[0].val() >= 25 {
                self.lk_x0.d.next = self.hu[0].val().get_bits::<4>(0) - 9;
            }
            self.lk_x1.d.next = 15.into();
            if self.hu[0].val() <= 38 {
                self.lk_x1.d.next = self.hu[0].val().get_bits::<4>(0) - 7;
            }
            self.lk_y[0].d.next = self.hu[1].val().get_bits::<4>(0) + 7;
            self.lk_y[1].d.next = self.hu[1].val().get_bits::<4>(0) + 8;
            self.lk_y[2].d.next = self.hu[1].val().get_bits::<4>(0) + 9;
            self.lk_z[0].d.next = self.hu[2].val().get_bits::<4>(0) + 7;
            self.lk_z[1].d.next = self.hu[2].val().get_bits::<4>(0) + 8;
            self.lk_z[2].d.next = self.hu[2].val().get_bits::<4>(0) + 9;
            for k in 0..3 {
                self.lk_vy[k].d.next = self.h_vy[k].val();
                self.lk_vz[k].d.next = self.h_vz[k].val();
            }
            for j in 0..4 {
                self.lk_mask[j].d.next = self.h_mask[j].val();
            }
        }
        // Point queue: push the transformed point, pop into the lookup stage.
        if self.transform.t2_valid.val() {
            for j in 0..4 {
                if self.pq_wr.q.val() == self.qid[j].val() {
                    self.pq_x[j].d.next = self.transform.result.val();
                    self.pq_l[j].d.next = self.l2.q.val();
                }
            }
            self.pq_wr.d.next = self.pq_wr.q.val() + 1;
        }
        if self.pq_pop.val() {
            self.pq_rd.d.next = self.pq_rd.q.val() + 1;
        }
        if self.transform.t2_valid.val() && !self.pq_pop.val() {
            self.pq_n.d.next = self.pq_n.q.val() + 1;
        } else if !self.transform.t2_valid.val() && self.pq_pop.val() {
            self.pq_n.d.next = self.pq_n.q.val() - 1;
        }
        // The read slot joins the range queue: its rows in place, each flagged if non-empty
        // (neither: a marker, queued only for a point's last slot).
        self.ra_ok.next = self.rd_in_a.q.val() && (self.lo_a.read_data.val() < self.hi_a.read_data.val());
        self.rb_ok.next = self.rd_in_b.q.val() && (self.lo_b.read_data.val() < self.hi_b.read_data.val());
        self.push.next = self.rd_valid.q.val() && (self.ra_ok.val() || self.rb_ok.val() || self.rd_last.q.val());
        // A point's last slot (the centre row alone) is split: its row B is row A from
        // `lo + P` on (a 14-bit sum, no wrap), if that is below `hi`; both sides stride `2P`.
        self.split_lo.next = bit_cast::<14, 13>(self.lo_a.read_data.val()) + self.pc14.val();
        self.split_ok.next = self.ra_ok.val() && (self.split_lo.val() < bit_cast::<14, 13>(self.hi_a.read_data.val()));
        if self.push.val() {
            for j in 0..4 {
                if self.rq_wr.q.val() == self.qid[j].val() {
                    self.rq_alo[j].d.next = self.lo_a.read_data.val();
                    self.rq_ahi[j].d.next = self.hi_a.read_data.val();
                    self.rq_av[j].d.next = self.ra_ok.val();
                    if self.rd_last.q.val() {
                        self.rq_blo[j].d.next = self.split_lo.val().get_bits::<13>(0);
                        self.rq_bhi[j].d.next = self.hi_a.read_data.val();
                        self.rq_bv[j].d.next = self.split_ok.val();
                    } else {
                        self.rq_blo[j].d.next = self.lo_b.read_data.val();
                        self.rq_bhi[j].d.next = self.hi_b.read_data.val();
                        self.rq_bv[j].d.next = self.rb_ok.val();
                    }
                    self.rq_last[j].d.next = self.rd_last.q.val();
                    self.rq_slast[j].d.next = self.rd_slast.q.val();
                    self.rq_q[j].d.next = self.rd_q.q.val();
                }
            }
            self.rq_wr.d.next = self.rq_wr.q.val() + 1;
        }
        // Issue: one chunk of each range a clock, range A (`is_addr .. is_end`) through the A
        // lanes and range B (`is_baddr .. is_bend`) through the B lanes, each side stepping
        // by the stride (`P`, or `2P` in a point's last slot, the split centre row); a side
        // stops with its last chunk, the entry is done when both have (a marker at once), and
        // its last chunk pair takes the next entry.
        self.stride13.next = self.pc13.val();
        self.stride14.next = self.pc14.val();
        if self.is_last.q.val() {
            self.stride13.next = self.pc13x2.val();
            self.stride14.next = self.pc14x2.val();
        }
        self.span.next = bit_cast::<14, 13>(self.is_end.q.val()) - bit_cast::<14, 13>(self.is_addr.q.val());
        self.span_b.next = bit_cast::<14, 13>(self.is_bend.q.val()) - bit_cast::<14, 13>(self.is_baddr.q.val());
        for b in 0..P {
            self.lanes[b].issue.next = self.is_have.q.val() && self.is_av.q.val();
            self.lanes[b].addr.next = self.is_addr.q.val();
            self.lanes[b].span.next = self.span.val();
            self.lanes[b].q.next = self.c0_q.q.val();
            self.lanes_b[b].issue.next = self.is_have.q.val() && self.is_bv.q.val();
            self.lanes_b[b].addr.next = self.is_baddr.q.val();
            self.lanes_b[b].span.next = self.span_b.val();
            self.lanes_b[b].q.next = self.c0_q.q.val();
        }
        self.fin_a.next = self.span.val() <= self.stride14.val();
        self.fin_b.next = self.span_b.val() <= self.stride14.val();
        self.done.next = self.is_have.q.val()
            && (!self.is_av.q.val() || self.fin_a.val())
            && (!self.is_bv.q.val() || self.fin_b.val());
        self.ch_last.next = self.done.val() && self.is_last.q.val();
        if self.is_have.q.val() {
            if self.is_av.q.val() {
                if self.fin_a.val() {
                    self.is_av.d.next = false;
                } else {
                    self.is_addr.d.next = self.is_addr.q.val() + self.stride13.val();
                }
            }
            if self.is_bv.q.val() {
                if self.fin_b.val() {
                    self.is_bv.d.next = false;
                } else {
                    self.is_baddr.d.next = self.is_baddr.q.val() + self.stride13.val();
                }
            }
        }
        self.c0_valid.d.next = self.is_have.q.val();
        self.c0_last.d.next = self.ch_last.val();
        self.c0_slast.d.next = self.is_slast.q.val();
        self.c0_q.d.next = self.is_q.q.val();
        self.rq_pop.next = (!self.is_have.q.val() || self.done.val()) && (self.rq_n.q.val() != 0);
        if !self.is_have.q.val() || self.done.val() {
            self.is_have.d.next = self.rq_n.q.val() != 0;
        }
        if self.rq_pop.val() {
            for j in 0..4 {
                if self.rq_rd.q.val() == self.qid[j].val() {
                    self.is_addr.d.next = self.rq_alo[j].q.val();
                    self.is_end.d.next = self.rq_ahi[j].q.val();
                    self.is_av.d.next = self.rq_av[j].q.val();
                    self.is_baddr.d.next = self.rq_blo[j].q.val();
                    self.is_bend.d.next = self.rq_bhi[j].q.val();
                    self.is_bv.d.next = self.rq_bv[j].q.val();
                    self.is_last.d.next = self.rq_last[j].q.val();
                    self.is_slast.d.next = self.rq_slast[j].q.val();
                    self.is_q.d.next = self.rq_q[j].q.val();
                }
            }
            self.rq_rd.d.next = self.rq_rd.q.val() + 1;
        }
        if self.push.val() && !self.rq_pop.val() {
            self.rq_n.d.next = self.rq_n.q.val() + 1;
        } else if !self.push.val() && self.rq_pop.val() {
            self.rq_n.d.next = self.rq_n.q.val() - 1;
        }
        // Control beside the lanes (s1..s4, keys) and the tree (levels 1..5).
        self.ctl_v[0].d.next = self.c0_valid.q.val();
        self.ctl_l[0].d.next = self.c0_last.q.val();
        self.ctl_s[0].d.next = self.c0_slast.q.val();
        self.ctl_q[0].d.next = self.c0_q.q.val();
        for k in 1..10 {
            self.ctl_v[k].d.next = self.ctl_v[k - 1].q.val();
            self.ctl_l[k].d.next = self.ctl_l[k - 1].q.val();
            self.ctl_s[k].d.next = self.ctl_s[k - 1].q.val();
            self.ctl_q[k].d.next = self.ctl_q[k - 1].q.val();
        }
        // The min-tree over the A lanes' keys (padded to 16 leaves with the neutral key).
        for j in 0..(P / 2) {
            if self.lanes[2 * j + 1].key.val() < self.lanes[2 * j].key.val() {
                self.t1[j].d.next = self.lanes[2 * j + 1].key.val();
            } else {
                self.t1[j].d.next = self.lanes[2 * j].key.val();
            }
        }
        for j in (P / 2)..8 {
            self.t1[j].d.next = self.cap_key.val();
        }
        for j in 0..4 {
            if self.t1[2 * j + 1].q.val() < self.t1[2 * j].q.val() {
                self.t2[j].d.next = self.t1[2 * j + 1].q.val();
            } else {
                self.t2[j].d.next = self.t1[2 * j].q.val();
            }
        }
        for j in 0..2 {
            if self.t2[2 * j + 1].q.val() < self.t2[2 * j].q.val() {
                self.t3[j].d.next = self.t2[2 * j + 1].q.val();
            } else {
                self.t3[j].d.next = self.t2[2 * j].q.val();
            }
        }
        if self.t3[1].q.val() < self.t3[0].q.val() {
            self.t4.d.next = self.t3[1].q.val();
        } else {
            self.t4.d.next = self.t3[0].q.val();
        }
        // The B lanes' tree, the same.
        for j in 0..(P / 2) {
            if self.lanes_b[2 * j + 1].key.val() < self.lanes_b[2 * j].key.val() {
                self.u1[j].d.next = self.lanes_b[2 * j + 1].key.val();
            } else {
                self.u1[j].d.next = self.lanes_b[2 * j].key.val();
            }
        }
        for j in (P / 2)..8 {
            self.u1[j].d.next = self.cap_key.val();
        }
        for j in 0..4 {
            if self.u1[2 * j + 1].q.val() < self.u1[2 * j].q.val() {
                self.u2[j].d.next = self.u1[2 * j + 1].q.val();
            } else {
                self.u2[j].d.next = self.u1[2 * j].q.val();
            }
        }
        for j in 0..2 {
            if self.u2[2 * j + 1].q.val() < self.u2[2 * j].q.val() {
                self.u3[j].d.next = self.u2[2 * j + 1].q.val();
            } else {
                self.u3[j].d.next = self.u2[2 * j].q.val();
            }
        }
        if self.u3[1].q.val() < self.u3[0].q.val() {
            self.u4.d.next = self.u3[1].q.val();
        } else {
            self.u4.d.next = self.u3[0].q.val();
        }
        // The smaller side.
        if self.u4.q.val() < self.t4.q.val() {
            self.t5.d.next = self.u4.q.val();
        } else {
            self.t5.d.next = self.t4.q.val();
        }
        // Accumulate a point's chunks; its last presents the result.
        self.m.next = self.t5.q.val();
        if self.acc_used.q.val() && (self.acc.q.val() < self.t5.q.val()) {
            self.m.next = self.acc.q.val();
        }
        self.nn_d.next = bit_cast::<34, 21>(self.m.val().get_bits::<21>(12));
        self.nn_valid_r.d.next = false;
        self.cost_valid_r.d.next = false;
        if self.ctl_v[9].q.val() {
            if self.ctl_l[9].q.val() {
                self.nn_valid_r.d.next = true;
                self.nn_index_r.d.next = self.m.val().get_bits::<12>(0);
                self.nn_dist_r.d.next = self.nn_d.val();
                self.nn_point_r.d.next = self.ctl_q[9].q.val();
                self.acc_used.d.next = false;
                self.fin.d.next = self.ctl_s[9].q.val();
            } else {
                self.acc.d.next = self.m.val();
                self.acc_used.d.next = true;
            }
        }
        // The cost adds each result the edge after it is presented (off the accumulator's
        // compare path); the particle's end presents the sum with the last result.
        self.cost_sum.next = self.cost_acc.q.val() + bit_cast::<48, 34>(self.nn_dist_r.q.val());
        if self.nn_valid_r.q.val() {
            self.cost_acc.d.next = self.cost_sum.val();
        }
        // State: idle or running a particle.
        if !self.run.q.val() {
            if self.start.val() {
                self.run.d.next = true;
                self.cost_acc.d.next = 0.into();
                self.last_taken.d.next = false;
            }
        } else {
            if self.take.val() {
                self.last_taken.d.next = self.scan_last.val();
            }
            if self.fin.q.val() {
                self.cost_valid_r.d.next = true;
                self.cost_r.d.next = self.cost_sum.val();
                self.fin.d.next = false;
                self.run.d.next = false;
            }
        }
        self.nn_valid.next = self.nn_valid_r.q.val();
        self.nn_index.next = self.nn_index_r.q.val();
        self.nn_dist.next = self.nn_dist_r.q.val();
        self.nn_point.next = self.nn_point_r.q.val();
        self.cost_valid.next = self.cost_valid_r.q.val();
        self.cost.next = self.cost_r.q.val();
    }
}
