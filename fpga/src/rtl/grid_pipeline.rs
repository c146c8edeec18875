//! `GridPipeline<P>`: the nearest-neighbour pipeline with the grid search (docs/pipeline.md,
//! "The grid pipeline") with `P` lanes, register for register the cycle-accurate reference
//! [`crate::grid_pipeline::GridPipelineModel`]: [`super::NnPipeline`]'s transform, lanes
//! (their minima reset to [`CAP_D2`]) and Reduce, with the model stored sorted by cell, a
//! cell table (two 4096 x 13 block RAMs: `first[c]` and `first[c + 1]`, one read each a row),
//! the batch's bounding box of query cells tracked in Load, and a Sweep over the rows of
//! cells around it.

use super::lane::Lane;
use super::pipeline::state;
use super::transform::Transform;
use crate::grid::CAP_D2;
use rust_hdl::prelude::*;

/// The grid pipeline with `P` lanes (1..=255).
#[derive(LogicBlock)]
pub struct GridPipeline<const P: usize> {
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
    /// Its squared distance (Q8.26).
    pub nn_dist: Signal<Out, Bits<34>>,
    /// `cost` holds the particle's cost (one-clock strobe).
    pub cost_valid: Signal<Out, Bit>,
    /// Sum of the squared distances (Q22.26).
    pub cost: Signal<Out, Bits<48>>,
    lanes_c: Constant<Bits<8>>,
    st_idle: Constant<Bits<2>>,
    st_load: Constant<Bits<2>>,
    st_sweep: Constant<Bits<2>>,
    st_reduce: Constant<Bits<2>>,
    c_off: Constant<Bits<6>>,
    c_lo_clip: Constant<Bits<6>>,
    c_lo_out: Constant<Bits<6>>,
    c_hi_clip: Constant<Bits<6>>,
    c_hi_out: Constant<Bits<6>>,
    c_lo_low: Constant<Bits<4>>,
    c_hi_low: Constant<Bits<4>>,
    state: DFF<Bits<2>>,
    taken: DFF<Bits<8>>,
    last_taken: DFF<Bit>,
    lane_wr: DFF<Bits<8>>,
    n_lanes: DFF<Bits<8>>,
    bmin: [DFF<Bits<6>>; 3],
    bmax: [DFF<Bits<6>>; 3],
    box_lo: [DFF<Bits<4>>; 3],
    box_hi: [DFF<Bits<4>>; 3],
    ry: DFF<Bits<4>>,
    rz: DFF<Bits<4>>,
    rmore: DFF<Bit>,
    tq_valid: DFF<Bit>,
    pv: DFF<Bit>,
    plo: DFF<Bits<13>>,
    phi: DFF<Bits<13>>,
    addr: DFF<Bits<13>>,
    end_r: DFF<Bits<13>>,
    s0_valid: DFF<Bit>,
    s0_index: DFF<Bits<12>>,
    sv: [DFF<Bit>; 4],
    si: [DFF<Bits<12>>; 4],
    reduce_at: DFF<Bits<8>>,
    cost_acc: DFF<Bits<48>>,
    nn_valid_r: DFF<Bit>,
    nn_index_r: DFF<Bits<12>>,
    nn_dist_r: DFF<Bits<34>>,
    cost_valid_r: DFF<Bit>,
    cost_r: DFF<Bits<48>>,
    ram: RAM<Bits<48>, 12>,
    lo_ram: RAM<Bits<13>, 12>,
    hi_ram: RAM<Bits<13>, 12>,
    transform: Transform,
    lanes: [Lane; P],
    ready: Signal<Local, Bit>,
    take: Signal<Local, Bit>,
    sweep: Signal<Local, Bit>,
    issue: Signal<Local, Bit>,
    last: Signal<Local, Bit>,
    consume: Signal<Local, Bit>,
    tq_full: Signal<Local, Bit>,
    tadv: Signal<Local, Bit>,
    lane_we: Signal<Local, Bit>,
    taddr_m1: Signal<Local, Bits<13>>,
    qc: [Signal<Local, Bits<6>>; 3],
    lo_sub: [Signal<Local, Bits<4>>; 3],
    hi_sub: [Signal<Local, Bits<4>>; 3],
    lo_n: [Signal<Local, Bits<4>>; 3],
    hi_n: [Signal<Local, Bits<4>>; 3],
    rows: Signal<Local, Bit>,
}

impl<const P: usize> GridPipeline<P> {
    /// After reset: idle, model RAM all zero.
    pub fn new() -> Self {
        assert!((1..=255).contains(&P), "1 to 255 lanes");
        GridPipeline {
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
            cost_valid: Default::default(),
            cost: Default::default(),
            lanes_c: Constant::new((P as u64).into()),
            st_idle: Constant::new(state::IDLE.into()),
            st_load: Constant::new(state::LOAD.into()),
            st_sweep: Constant::new(state::SWEEP.into()),
            st_reduce: Constant::new(state::REDUCE.into()),
            c_off: Constant::new(32.into()),
            c_lo_clip: Constant::new(25.into()),
            c_lo_out: Constant::new(40.into()),
            c_hi_clip: Constant::new(38.into()),
            c_hi_out: Constant::new(23.into()),
            c_lo_low: Constant::new(9.into()),
            c_hi_low: Constant::new(7.into()),
            state: Default::default(),
            taken: Default::default(),
            last_taken: Default::default(),
            lane_wr: Default::default(),
            n_lanes: Default::default(),
            bmin: Default::default(),
            bmax: Default::default(),
            box_lo: Default::default(),
            box_hi: Default::default(),
            ry: Default::default(),
            rz: Default::default(),
            rmore: Default::default(),
            tq_valid: Default::default(),
            pv: Default::default(),
            plo: Default::default(),
            phi: Default::default(),
            addr: Default::default(),
            end_r: Default::default(),
            s0_valid: Default::default(),
            s0_index: Default::default(),
            sv: Default::default(),
            si: Default::default(),
            reduce_at: Default::default(),
            cost_acc: Default::default(),
            nn_valid_r: Default::default(),
            nn_index_r: Default::default(),
            nn_dist_r: Default::default(),
            cost_valid_r: Default::default(),
            cost_r: Default::default(),
            ram: Default::default(),
            lo_ram: Default::default(),
            hi_ram: Default::default(),
            transform: Default::default(),
            lanes: std::array::from_fn(|i| Lane::with_init(i, CAP_D2)),
            ready: Default::default(),
            take: Default::default(),
            sweep: Default::default(),
            issue: Default::default(),
            last: Default::default(),
            consume: Default::default(),
            tq_full: Default::default(),
            tadv: Default::default(),
            lane_we: Default::default(),
            taddr_m1: Default::default(),
            qc: Default::default(),
            lo_sub: Default::default(),
            hi_sub: Default::default(),
            lo_n: Default::default(),
            hi_n: Default::default(),
            rows: Default::default(),
        }
    }
}

impl<const P: usize> Default for GridPipeline<P> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const P: usize> Logic for GridPipeline<P> {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self,
            clock,
            state,
            taken,
            last_taken,
            lane_wr,
            n_lanes,
            ry,
            rz,
            rmore,
            tq_valid,
            pv,
            plo,
            phi,
            addr,
            end_r,
            s0_valid,
            s0_index,
            reduce_at,
            cost_acc,
            nn_valid_r,
            nn_index_r,
            nn_dist_r,
            cost_valid_r,
            cost_r
        );
        for s in 0..4 {
            self.sv[s].clock.next = self.clock.val();
            self.si[s].clock.next = self.clock.val();
        }
        self.transform.clock.next = self.clock.val();
        self.ram.read_clock.next = self.clock.val();
        self.ram.write_clock.next = self.clock.val();
        self.lo_ram.read_clock.next = self.clock.val();
        self.lo_ram.write_clock.next = self.clock.val();
        self.hi_ram.read_clock.next = self.clock.val();
        self.hi_ram.write_clock.next = self.clock.val();
        for k in 0..3 {
            self.bmin[k].clock.next = self.clock.val();
            self.bmin[k].d.next = self.bmin[k].q.val();
            self.bmax[k].clock.next = self.clock.val();
            self.bmax[k].d.next = self.bmax[k].q.val();
            self.box_lo[k].clock.next = self.clock.val();
            self.box_lo[k].d.next = self.box_lo[k].q.val();
            self.box_hi[k].clock.next = self.clock.val();
            self.box_hi[k].d.next = self.box_hi[k].q.val();
        }
        for i in 0..P {
            self.lanes[i].clock.next = self.clock.val();
        }
        // Status (combinational from the state registers).
        self.ready.next = (self.state.q.val() == self.st_load.val())
            && (self.taken.q.val() < self.lanes_c.val())
            && !self.last_taken.q.val();
        self.take.next = self.ready.val() && self.scan_valid.val();
        self.sweep.next = self.state.q.val() == self.st_sweep.val();
        self.issue.next = self.sweep.val() && (self.addr.q.val() < self.end_r.q.val());
        self.scan_ready.next = self.ready.val();
        self.busy.next = self.state.q.val() != self.st_idle.val();
        // Model RAM: synchronous read of the sweep address every clock, synchronous write.
        self.ram.read_address.next = self.addr.q.val().get_bits::<12>(0);
        self.ram.write_address.next = self.model_waddr.val();
        self.ram.write_data.next = self.model_wdata.val();
        self.ram.write_enable.next = self.model_we.val();
        // Cell table: `lo_ram[c] = first[c]` (entries 0..4096), `hi_ram[c] = first[c + 1]`
        // (entries 1..=4096); each reads the row in the row registers every clock.
        self.taddr_m1.next = self.table_waddr.val() - 1;
        self.lo_ram.write_address.next = self.table_waddr.val().get_bits::<12>(0);
        self.lo_ram.write_data.next = self.table_wdata.val();
        self.lo_ram.write_enable.next = self.table_we.val() && !self.table_waddr.val().get_bit(12);
        self.hi_ram.write_address.next = self.taddr_m1.val().get_bits::<12>(0);
        self.hi_ram.write_data.next = self.table_wdata.val();
        self.hi_ram.write_enable.next =
            self.table_we.val() && (self.table_waddr.val() != 0) && !self.taddr_m1.val().get_bit(12);
        self.lo_ram.read_address.next = (bit_cast::<12, 4>(self.rz.q.val()) << 8)
            | (bit_cast::<12, 4>(self.ry.q.val()) << 4)
            | bit_cast::<12, 4>(self.box_lo[0].q.val());
        self.hi_ram.read_address.next = (bit_cast::<12, 4>(self.rz.q.val()) << 8)
            | (bit_cast::<12, 4>(self.ry.q.val()) << 4)
            | bit_cast::<12, 4>(self.box_hi[0].q.val());
        // Transform pipeline (pose latched with an honoured start).
        self.transform.load.next = (self.state.q.val() == self.st_idle.val()) && self.start.val();
        self.transform.pose.next = self.pose.val();
        self.transform.take.next = self.take.val();
        self.transform.point.next = self.scan_data.val();
        // Lane write.
        self.lane_we.next = self.transform.t2_valid.val() && (self.lane_wr.q.val() < self.lanes_c.val());
        if self.lane_we.val() {
            self.lane_wr.d.next = self.lane_wr.q.val() + 1;
        }
        // The batch's box of query cells: per axis `(c >> 10) + 32` (six bits, unsigned; the
        // cell less 8 offset by 32), min and max, set by the batch's first write.
        for k in 0..3 {
            self.qc[k].next = self.transform.result.val().get_bits::<6>(16 * k + 10) ^ self.c_off.val();
            if self.lane_we.val() && ((self.lane_wr.q.val() == 0) || (self.qc[k].val() < self.bmin[k].q.val())) {
                self.bmin[k].d.next = self.qc[k].val();
            }
            if self.lane_we.val() && ((self.lane_wr.q.val() == 0) || (self.qc[k].val() > self.bmax[k].q.val())) {
                self.bmax[k].d.next = self.qc[k].val();
            }
        }
        // The swept box, grown by one cell and clipped to the grid: cell = u - 24, so
        // lo = max(u_min - 25, 0) and hi = min(u_max - 23, 15); no rows unless every axis
        // has u_max >= 23 and u_min <= 40.
        self.rows.next = true;
        for k in 0..3 {
            // (u - 25 and u - 23 modulo 16, from the low four bits.)
            self.lo_sub[k].next = self.bmin[k].q.val().get_bits::<4>(0) - self.c_lo_low.val();
            self.hi_sub[k].next = self.bmax[k].q.val().get_bits::<4>(0) - self.c_hi_low.val();
            if self.bmin[k].q.val() <= self.c_lo_clip.val() {
                self.lo_n[k].next = 0.into();
            } else {
                self.lo_n[k].next = self.lo_sub[k].val();
            }
            if self.bmax[k].q.val() >= self.c_hi_clip.val() {
                self.hi_n[k].next = 15.into();
            } else {
                self.hi_n[k].next = self.hi_sub[k].val();
            }
            if (self.bmax[k].q.val() < self.c_hi_out.val()) || (self.bmin[k].q.val() > self.c_lo_out.val()) {
                self.rows.next = false;
            }
        }
        for i in 0..P {
            self.lanes[i].wr_en.next = self.lane_we.val();
            self.lanes[i].wr_sel.next = self.lane_wr.q.val();
            self.lanes[i].point.next = self.transform.result.val();
            self.lanes[i].model.next = self.ram.read_data.val();
            self.lanes[i].model_valid.next = self.s0_valid.q.val();
            self.lanes[i].s4_valid.next = self.sv[3].q.val();
            self.lanes[i].s4_index.next = self.si[3].q.val();
            // The minima are reset on every Load edge (the reference resets them on the edge
            // Load -> Sweep; nothing reads them in Load) and shift on every Reduce edge (after
            // the last lane nothing reads them before the next reset): the same ports, and
            // each lane's control is a decode of the state register alone.
            self.lanes[i].init.next = self.state.q.val() == self.st_load.val();
            self.lanes[i].shift.next = self.state.q.val() == self.st_reduce.val();
        }
        for i in 0..(P - 1) {
            self.lanes[i].shift_min.next = self.lanes[i + 1].min.val();
            self.lanes[i].shift_arg.next = self.lanes[i + 1].arg.val();
        }
        for i in (P - 1)..P {
            self.lanes[i].shift_min.next = 0.into();
            self.lanes[i].shift_arg.next = 0.into();
        }
        // Sweep: row lookup, pending range, address issue (`addr .. end_r`) and the shared
        // valid/index delay line (s0..s4). A looked-up row (the table's read registers,
        // `tq_valid`) goes to the pending slot the next edge, an empty one is dropped; the
        // pending range is taken as the current one ends (or none runs); a row is looked up
        // only if the pending slot is free after this edge.
        self.last.next = self.issue.val() && ((self.addr.q.val() + 1) == self.end_r.q.val());
        self.consume.next = self.pv.q.val() && (!self.issue.val() || self.last.val());
        self.tq_full.next = self.tq_valid.q.val() && (self.lo_ram.read_data.val() < self.hi_ram.read_data.val());
        self.tadv.next =
            self.sweep.val() && self.rmore.q.val() && !self.tq_full.val() && (!self.pv.q.val() || self.consume.val());
        self.s0_valid.d.next = self.issue.val();
        self.s0_index.d.next = self.addr.q.val().get_bits::<12>(0);
        if self.issue.val() {
            self.addr.d.next = self.addr.q.val() + 1;
        }
        if self.consume.val() {
            self.addr.d.next = self.plo.q.val();
            self.end_r.d.next = self.phi.q.val();
        }
        if self.tq_full.val() {
            self.pv.d.next = true;
            self.plo.d.next = self.lo_ram.read_data.val();
            self.phi.d.next = self.hi_ram.read_data.val();
        } else if self.consume.val() {
            self.pv.d.next = false;
        }
        self.tq_valid.d.next = self.tadv.val();
        if self.tadv.val() {
            if self.ry.q.val() < self.box_hi[1].q.val() {
                self.ry.d.next = self.ry.q.val() + 1;
            } else {
                self.ry.d.next = self.box_lo[1].q.val();
                if self.rz.q.val() < self.box_hi[2].q.val() {
                    self.rz.d.next = self.rz.q.val() + 1;
                } else {
                    self.rmore.d.next = false;
                }
            }
        }
        self.sv[0].d.next = self.s0_valid.q.val();
        self.si[0].d.next = self.s0_index.q.val();
        for s in 1..4 {
            self.sv[s].d.next = self.sv[s - 1].q.val();
            self.si[s].d.next = self.si[s - 1].q.val();
        }
        // Strobes.
        self.nn_valid_r.d.next = false;
        self.cost_valid_r.d.next = false;
        // State machine (Idle, Load, Sweep, Reduce).
        if self.state.q.val() == self.st_idle.val() {
            if self.start.val() {
                self.state.d.next = self.st_load.val();
                self.cost_acc.d.next = 0.into();
                self.taken.d.next = 0.into();
                self.last_taken.d.next = false;
                self.lane_wr.d.next = 0.into();
            }
        } else if self.state.q.val() == self.st_load.val() {
            if self.take.val() {
                self.taken.d.next = self.taken.q.val() + 1;
                self.last_taken.d.next = self.last_taken.q.val() || self.scan_last.val();
            }
            if ((self.taken.q.val() == self.lanes_c.val()) || self.last_taken.q.val())
                && !self.transform.t1_valid.val()
                && !self.transform.t2_valid.val()
            {
                self.state.d.next = self.st_sweep.val();
                self.n_lanes.d.next = self.lane_wr.q.val();
                for k in 0..3 {
                    self.box_lo[k].d.next = self.lo_n[k].val();
                    self.box_hi[k].d.next = self.hi_n[k].val();
                }
                self.ry.d.next = self.lo_n[1].val();
                self.rz.d.next = self.lo_n[2].val();
                self.rmore.d.next = self.rows.val();
                self.tq_valid.d.next = false;
                self.pv.d.next = false;
                self.addr.d.next = 0.into();
                self.end_r.d.next = 0.into();
            }
        } else if self.state.q.val() == self.st_sweep.val() {
            if !self.issue.val()
                && !self.rmore.q.val()
                && !self.tq_valid.q.val()
                && !self.pv.q.val()
                && !self.s0_valid.q.val()
                && !self.sv[0].q.val()
                && !self.sv[1].q.val()
                && !self.sv[2].q.val()
                && !self.sv[3].q.val()
            {
                self.state.d.next = self.st_reduce.val();
                self.reduce_at.d.next = 0.into();
            }
        } else if self.reduce_at.q.val() < self.n_lanes.q.val() {
            // Reduce: lane 0 holds the next lane's result (the chain shifts every Reduce edge).
            self.nn_valid_r.d.next = true;
            self.nn_index_r.d.next = self.lanes[0].arg.val();
            self.nn_dist_r.d.next = self.lanes[0].min.val();
            self.cost_acc.d.next = self.cost_acc.q.val() + bit_cast::<48, 34>(self.lanes[0].min.val());
            self.reduce_at.d.next = self.reduce_at.q.val() + 1;
        } else if self.last_taken.q.val() {
            // Reduce done, the particle's last batch.
            self.cost_valid_r.d.next = true;
            self.cost_r.d.next = self.cost_acc.q.val();
            self.state.d.next = self.st_idle.val();
        } else {
            // Reduce done, more scan points to come.
            self.state.d.next = self.st_load.val();
            self.taken.d.next = 0.into();
            self.lane_wr.d.next = 0.into();
        }
        // Registered outputs.
        self.nn_valid.next = self.nn_valid_r.q.val();
        self.nn_index.next = self.nn_index_r.q.val();
        self.nn_dist.next = self.nn_dist_r.q.val();
        self.cost_valid.next = self.cost_valid_r.q.val();
        self.cost.next = self.cost_r.q.val();
    }
}
