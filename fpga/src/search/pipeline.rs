//! What the board's nearest-neighbour search shares with its references (docs/pipeline.md):
//! the result ports ([`Outputs`]) and results ([`Evaluation`]), the transform's pipeline
//! stages, the one driver of a particle's scan stream ([`stream_particle`]), and the plain
//! functional reference, the brute-force nearest neighbour ([`evaluate`]). The search's
//! cycle model is [`crate::search::neighbour_pipeline::NeighbourPipelineModel`].
//!
//! [`clocks_per_particle`] is the closed-form clock count of the first, brute-force pipeline
//! (retired: no longer RTL or a model), kept as the yardstick the search's figures and the
//! host's deadline bound are quoted against.

use crate::common::format::{dist2, transform, unpack_point, FxPoint, FxPose, MATRIX_FRAC};

/// Squared distances are below this; [`evaluate`]'s minimum starts here.
pub const DIST_INIT: u64 = (1 << crate::common::format::DIST_BITS) - 1;
/// Mask of a 48-bit cost.
pub use crate::common::format::COST_MASK;

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
    /// The transformed scan point `q` of the result in `nn_index`/`nn_dist` (RTL port
    /// `nn_point`): registered on the same edges (so while `nn_valid` is low it holds the
    /// last result's point; `[0, 0, 0]` after reset).
    pub nn_point: FxPoint,
}

/// The transform pipeline's first stage (the edge after a take): the nine products
/// `m_ij * p_j` of the scan word `point` (docs/pipeline.md, the neighbour pipeline's scan
/// input); [`crate::common::format::transform`] is the same arithmetic at once.
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

/// A cycle model with the search's scan stream and result ports (the neighbour pipeline's,
/// with [`crate::search::neighbour_pipeline::GridInputs`]): one rising edge a
/// [`step`](StreamModel::step), the output ports after it.
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

/// Clocks per particle from `start` to `cost_valid` with no gaps in the scan stream on the
/// retired brute-force pipeline (`NnPipeline`, `lanes` scan points a batch, each batch
/// sweeping the whole model): the yardstick of the search's figures and of the host's
/// deadline bound (docs/pipeline.md).
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

    #[test]
    fn ties_go_to_the_lowest_index() {
        let model = vec![[100, 0, 0], [-100, 0, 0], [100, 0, 0]];
        let pose = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
        let e = evaluate(&model, &[[0, 0, 0], [200, 0, 0]], &pose);
        assert_eq!(e.nearest, vec![(0, 10000), (0, 10000)]);
    }
}
