//! `NnPipeline<P>`: the top of the nearest-neighbour pipeline (docs/pipeline.md) with `P`
//! lanes, register for register the cycle-accurate reference [`crate::pipeline::PipelineModel`].

use super::lane::Lane;
use super::transform::Transform;
use rust_hdl::prelude::*;

/// State encoding (a `Bits<2>` register rather than a rust_hdl enum: an enum's
/// `localparam`s are also emitted, unused, into the register's own module).
pub mod state {
    /// Waiting for `start`.
    pub const IDLE: u64 = 0;
    /// Taking up to `P` scan points through the transform.
    pub const LOAD: u64 = 1;
    /// One model address per clock through the lanes.
    pub const SWEEP: u64 = 2;
    /// One lane per clock to the outputs.
    pub const REDUCE: u64 = 3;
}

/// The nearest-neighbour pipeline with `P` lanes (1..=255).
#[derive(LogicBlock)]
pub struct NnPipeline<const P: usize> {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Write `model_wdata` to model RAM word `model_waddr` at this edge.
    pub model_we: Signal<In, Bit>,
    /// Model write address.
    pub model_waddr: Signal<In, Bits<12>>,
    /// Model write data (x | y | z, Q3.13).
    pub model_wdata: Signal<In, Bits<48>>,
    /// Number of model points (1..=4096), sampled with `start`.
    pub model_count: Signal<In, Bits<13>>,
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
    state: DFF<Bits<2>>,
    count_r: DFF<Bits<13>>,
    taken: DFF<Bits<8>>,
    last_taken: DFF<Bit>,
    lane_wr: DFF<Bits<8>>,
    n_lanes: DFF<Bits<8>>,
    addr: DFF<Bits<13>>,
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
    transform: Transform,
    lanes: [Lane; P],
    ready: Signal<Local, Bit>,
    take: Signal<Local, Bit>,
    issue: Signal<Local, Bit>,
    lane_we: Signal<Local, Bit>,
}

impl<const P: usize> NnPipeline<P> {
    /// After reset: idle, model RAM all zero.
    pub fn new() -> Self {
        assert!((1..=255).contains(&P), "1 to 255 lanes");
        NnPipeline {
            clock: Default::default(),
            model_we: Default::default(),
            model_waddr: Default::default(),
            model_wdata: Default::default(),
            model_count: Default::default(),
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
            state: Default::default(),
            count_r: Default::default(),
            taken: Default::default(),
            last_taken: Default::default(),
            lane_wr: Default::default(),
            n_lanes: Default::default(),
            addr: Default::default(),
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
            transform: Default::default(),
            lanes: std::array::from_fn(Lane::new),
            ready: Default::default(),
            take: Default::default(),
            issue: Default::default(),
            lane_we: Default::default(),
        }
    }
}

impl<const P: usize> Default for NnPipeline<P> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const P: usize> Logic for NnPipeline<P> {
    #[hdl_gen]
    fn update(&mut self) {
        dff_setup!(
            self,
            clock,
            state,
            count_r,
            taken,
            last_taken,
            lane_wr,
            n_lanes,
            addr,
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
        for i in 0..P {
            self.lanes[i].clock.next = self.clock.val();
        }
        // Status (combinational from the state registers).
        self.ready.next = (self.state.q.val() == self.st_load.val())
            && (self.taken.q.val() < self.lanes_c.val())
            && !self.last_taken.q.val();
        self.take.next = self.ready.val() && self.scan_valid.val();
        self.issue.next = (self.state.q.val() == self.st_sweep.val()) && (self.addr.q.val() < self.count_r.q.val());
        self.scan_ready.next = self.ready.val();
        self.busy.next = self.state.q.val() != self.st_idle.val();
        // Model RAM: synchronous read of the sweep address every clock, synchronous write.
        self.ram.read_address.next = self.addr.q.val().get_bits::<12>(0);
        self.ram.write_address.next = self.model_waddr.val();
        self.ram.write_data.next = self.model_wdata.val();
        self.ram.write_enable.next = self.model_we.val();
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
        // Sweep: address issue and the shared valid/index delay line (s0..s4).
        self.s0_valid.d.next = self.issue.val();
        self.s0_index.d.next = self.addr.q.val().get_bits::<12>(0);
        if self.issue.val() {
            self.addr.d.next = self.addr.q.val() + 1;
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
                self.count_r.d.next = self.model_count.val();
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
                self.addr.d.next = 0.into();
                self.n_lanes.d.next = self.lane_wr.q.val();
            }
        } else if self.state.q.val() == self.st_sweep.val() {
            if !self.issue.val()
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
