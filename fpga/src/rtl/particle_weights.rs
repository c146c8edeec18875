//! `ParticleWeightPipeline<P>`: the nearest-neighbour pipeline whose particle costs feed
//! the weight stage; the unit the board instantiates. Reference:
//! [`crate::particle_weights::ParticleWeightModel`].

use super::pipeline::NnPipeline;
use super::weights::WeightStage;
use rust_hdl::prelude::*;

/// The whole particle-weight pipeline with `P` lanes.
#[derive(LogicBlock)]
pub struct ParticleWeightPipeline<const P: usize> {
    /// Clock.
    pub clock: Signal<In, Clock>,
    /// Model write enable.
    pub model_we: Signal<In, Bit>,
    /// Model write address.
    pub model_waddr: Signal<In, Bits<12>>,
    /// Model write data.
    pub model_wdata: Signal<In, Bits<48>>,
    /// Model points, sampled with `start`.
    pub model_count: Signal<In, Bits<13>>,
    /// Begin a particle.
    pub start: Signal<In, Bit>,
    /// The particle's pose.
    pub pose: Signal<In, Bits<216>>,
    /// A scan point is offered.
    pub scan_valid: Signal<In, Bit>,
    /// The offered point.
    pub scan_data: Signal<In, Bits<48>>,
    /// The offered point is the last.
    pub scan_last: Signal<In, Bit>,
    /// Forget the stored costs.
    pub clear: Signal<In, Bit>,
    /// Start the weight pass.
    pub weigh: Signal<In, Bit>,
    /// Weight scale: pre-shift.
    pub pre_shift: Signal<In, Bits<6>>,
    /// Weight scale: multiplier.
    pub q_mul: Signal<In, Bits<17>>,
    /// The pipeline takes the offered point.
    pub scan_ready: Signal<Out, Bit>,
    /// The pipeline is evaluating a particle.
    pub busy: Signal<Out, Bit>,
    /// Nearest-neighbour result strobe.
    pub nn_valid: Signal<Out, Bit>,
    /// Nearest model index.
    pub nn_index: Signal<Out, Bits<12>>,
    /// Its squared distance.
    pub nn_dist: Signal<Out, Bits<34>>,
    /// Particle cost strobe.
    pub cost_valid: Signal<Out, Bit>,
    /// The particle's cost.
    pub cost: Signal<Out, Bits<48>>,
    /// The weight pass is running.
    pub w_busy: Signal<Out, Bit>,
    /// Costs stored.
    pub w_count: Signal<Out, Bits<9>>,
    /// Smallest stored cost.
    pub min_cost: Signal<Out, Bits<48>>,
    /// Weight strobe.
    pub w_valid: Signal<Out, Bit>,
    /// Its particle index.
    pub w_index: Signal<Out, Bits<8>>,
    /// The weight.
    pub weight: Signal<Out, Bits<16>>,
    /// End of the weight pass.
    pub w_done: Signal<Out, Bit>,
    /// Sum of the weights.
    pub w_sum: Signal<Out, Bits<24>>,
    nn: NnPipeline<P>,
    ws: WeightStage,
}

impl<const P: usize> Default for ParticleWeightPipeline<P> {
    fn default() -> Self {
        ParticleWeightPipeline {
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
            clear: Default::default(),
            weigh: Default::default(),
            pre_shift: Default::default(),
            q_mul: Default::default(),
            scan_ready: Default::default(),
            busy: Default::default(),
            nn_valid: Default::default(),
            nn_index: Default::default(),
            nn_dist: Default::default(),
            cost_valid: Default::default(),
            cost: Default::default(),
            w_busy: Default::default(),
            w_count: Default::default(),
            min_cost: Default::default(),
            w_valid: Default::default(),
            w_index: Default::default(),
            weight: Default::default(),
            w_done: Default::default(),
            w_sum: Default::default(),
            nn: NnPipeline::new(),
            ws: WeightStage::new(),
        }
    }
}

impl<const P: usize> Logic for ParticleWeightPipeline<P> {
    #[hdl_gen]
    fn update(&mut self) {
        self.nn.clock.next = self.clock.val();
        self.ws.clock.next = self.clock.val();
        self.nn.model_we.next = self.model_we.val();
        self.nn.model_waddr.next = self.model_waddr.val();
        self.nn.model_wdata.next = self.model_wdata.val();
        self.nn.model_count.next = self.model_count.val();
        self.nn.start.next = self.start.val();
        self.nn.pose.next = self.pose.val();
        self.nn.scan_valid.next = self.scan_valid.val();
        self.nn.scan_data.next = self.scan_data.val();
        self.nn.scan_last.next = self.scan_last.val();
        self.scan_ready.next = self.nn.scan_ready.val();
        self.busy.next = self.nn.busy.val();
        self.nn_valid.next = self.nn.nn_valid.val();
        self.nn_index.next = self.nn.nn_index.val();
        self.nn_dist.next = self.nn.nn_dist.val();
        self.cost_valid.next = self.nn.cost_valid.val();
        self.cost.next = self.nn.cost.val();
        self.ws.clear.next = self.clear.val();
        self.ws.cost_valid.next = self.nn.cost_valid.val();
        self.ws.cost.next = self.nn.cost.val();
        self.ws.weigh.next = self.weigh.val();
        self.ws.pre_shift.next = self.pre_shift.val();
        self.ws.q_mul.next = self.q_mul.val();
        self.w_busy.next = self.ws.busy.val();
        self.w_count.next = self.ws.count.val();
        self.min_cost.next = self.ws.min_cost.val();
        self.w_valid.next = self.ws.w_valid.val();
        self.w_index.next = self.ws.w_index.val();
        self.weight.next = self.ws.weight.val();
        self.w_done.next = self.ws.w_done.val();
        self.w_sum.next = self.ws.w_sum.val();
    }
}
