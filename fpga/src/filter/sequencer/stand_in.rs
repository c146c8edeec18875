//! A stand-in for the nearest-neighbour pipeline behind the sequencer: it answers `start`
//! with the functional reference's cost after a chosen latency (the tests' environment).

use super::SeqInputs;
use crate::common::format::{FxPoint, FxPose};

/// The pipeline's side of the sequencer's ports, functional, for tests and benches: on
/// `start` it evaluates the pose with [`crate::search::pipeline::evaluate`] and, from `latency`
/// clocks later, drives one nearest distance per clock, then the cost on the next.
#[derive(Clone, Debug, Default)]
pub struct PipelineStandIn {
    /// (clock the results begin, per-point distances, cost).
    pending: Option<(u64, Vec<u64>, u64)>,
}

impl PipelineStandIn {
    /// An evaluation is in flight (`nn_ready` must be low).
    pub fn busy(&self) -> bool {
        self.pending.is_some()
    }

    /// The sequencer raised `start` for `pose` at clock `now`: the results begin at
    /// `now + latency`. Panics if an evaluation is still in flight.
    pub fn start(&mut self, now: u64, latency: u64, model: &[FxPoint], scan: &[FxPoint], pose: &FxPose) {
        assert!(self.pending.is_none(), "start while an evaluation is in flight");
        let e = crate::search::pipeline::evaluate(model, scan, pose);
        self.pending = Some((now + latency, e.nearest.iter().map(|n| n.1).collect(), e.cost));
    }

    /// Drives `nn_valid`/`nn_dist` or `cost_valid`/`cost` of `i` for clock `now`. True on
    /// the clock the cost is driven; the evaluation is over then.
    pub fn drive(&mut self, now: u64, i: &mut SeqInputs) -> bool {
        let Some((t0, d, c)) = &self.pending else { return false };
        if now < *t0 {
            return false;
        }
        let k = (now - t0) as usize;
        if k < d.len() {
            i.nn_valid = true;
            i.nn_dist = d[k];
            return false;
        }
        i.cost_valid = true;
        i.cost = *c;
        self.pending = None;
        true
    }

    /// Forgets the evaluation in flight (a reset).
    pub fn reset(&mut self) {
        self.pending = None;
    }
}
