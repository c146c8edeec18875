//! The reference of the whole particle-weight pipeline: the nearest-neighbour pipeline
//! ([`crate::pipeline`]) whose particle costs feed the weight stage ([`crate::weights`]),
//! wired exactly as the RTL top `ParticleWeightPipeline` (docs/pipeline.md, docs/weights.md).

use crate::pipeline::{Inputs, Outputs, PipelineModel};
use crate::weights::{WeightInputs, WeightModel, WeightOutputs};

/// Inputs of the whole pipeline: the nearest-neighbour pipeline's, and the weight stage's
/// controls (its `cost_valid`/`cost` come from the pipeline).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PwInputs {
    /// The nearest-neighbour pipeline's inputs.
    pub nn: Inputs,
    /// Forget the stored costs.
    pub clear: bool,
    /// Start the weight pass.
    pub weigh: bool,
    /// Weight scale: pre-shift.
    pub pre_shift: u8,
    /// Weight scale: multiplier.
    pub q_mul: u32,
}

/// Outputs of the whole pipeline.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PwOutputs {
    /// The nearest-neighbour pipeline's outputs.
    pub nn: Outputs,
    /// The weight stage's outputs.
    pub w: WeightOutputs,
}

/// The two references, wired: the weight stage stores every `cost_valid` of the pipeline.
#[derive(Clone, Debug)]
pub struct ParticleWeightModel {
    /// The nearest-neighbour pipeline.
    pub pipe: PipelineModel,
    /// The weight stage.
    pub weights: WeightModel,
}

impl ParticleWeightModel {
    /// After reset, with `lanes` lanes.
    pub fn new(lanes: usize) -> Self {
        ParticleWeightModel { pipe: PipelineModel::new(lanes), weights: WeightModel::new() }
    }

    /// Outputs now.
    pub fn outputs(&self) -> PwOutputs {
        PwOutputs { nn: self.pipe.outputs(), w: self.weights.outputs() }
    }

    /// One rising edge.
    pub fn step(&mut self, i: &PwInputs) {
        let nn_out = self.pipe.outputs();
        let wi = WeightInputs {
            clear: i.clear,
            cost_valid: nn_out.cost_valid,
            cost: nn_out.cost,
            weigh: i.weigh,
            pre_shift: i.pre_shift,
            q_mul: i.q_mul,
        };
        self.pipe.step(&i.nn);
        self.weights.step(&wi);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::{FxPose, WeightScale};
    use crate::pipeline::evaluate;
    use crate::weights::weights;

    #[test]
    fn costs_flow_into_the_weight_stage() {
        let model: Vec<[i16; 3]> = (0..20i16).map(|k| [k * 300, -k * 200, k * k]).collect();
        let scan: Vec<[i16; 3]> = (0..7).map(|k| [k * 500 - 1000, k * 100, 50]).collect();
        let mut m = ParticleWeightModel::new(4);
        for (a, &p) in model.iter().enumerate() {
            m.step(&PwInputs { nn: Inputs::write_model(a, p), ..Default::default() });
        }
        m.step(&PwInputs { clear: true, ..Default::default() });
        let poses: Vec<FxPose> = (0..3)
            .map(|k| FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.05 * k as f64, 0.0, 0.0]))
            .collect();
        let mut costs = Vec::new();
        for pose in &poses {
            m.step(&PwInputs { nn: Inputs::start(pose, 20), ..Default::default() });
            let mut next = 0;
            loop {
                let o = m.outputs();
                let offer = next < scan.len();
                let i = Inputs::offer(&scan, next, offer);
                if offer && o.nn.scan_ready {
                    next += 1;
                }
                m.step(&PwInputs { nn: i, ..Default::default() });
                if m.outputs().nn.cost_valid {
                    costs.push(m.outputs().nn.cost);
                    break;
                }
            }
        }
        m.step(&PwInputs::default()); // the last cost reaches the store
        assert_eq!(m.outputs().w.count, 3);
        for (c, pose) in costs.iter().zip(&poses) {
            assert_eq!(*c, evaluate(&model, &scan, pose).cost);
        }
        let scale = WeightScale::for_two_q(1e6);
        m.step(&PwInputs { weigh: true, pre_shift: scale.pre_shift as u8, q_mul: scale.q_mul, ..Default::default() });
        let mut w = Vec::new();
        while !m.outputs().w.w_done {
            m.step(&PwInputs::default());
            if m.outputs().w.w_valid {
                w.push(m.outputs().w.weight);
            }
        }
        assert_eq!(w, weights(&costs, &scale));
    }
}
