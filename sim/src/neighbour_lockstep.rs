//! The neighbour pipeline (`NeighbourPipeline<P>`) in lockstep with its cycle model:
//! [`NeighbourLockstep`] and its drivers (upload a gridded model, run a particle).

use crate::lockstep::{LockstepOf, Mismatch};
use crate::wrappers::VerilatedNeighbourPipeline;
use pficp_fpga::common::format::{FxPoint, FxPose};
use pficp_fpga::search::grid::Grid;
use pficp_fpga::search::neighbour_pipeline::{upload, GridInputs};
use pficp_fpga::search::pipeline::Evaluation;

/// The Verilated neighbour pipeline and `NeighbourPipelineModel` in lockstep.
pub type NeighbourLockstep = LockstepOf<VerilatedNeighbourPipeline>;

impl LockstepOf<VerilatedNeighbourPipeline> {
    /// The `lanes`-lane RTL and `NeighbourPipelineModel::new(lanes)`, both after reset.
    pub fn new(lanes: usize) -> Self {
        Self::from_rtl(VerilatedNeighbourPipeline::new(lanes))
    }

    /// Write the model (sorted by cell) and the cell table, one word a clock.
    pub fn upload(&mut self, grid: &Grid) -> Result<(), Mismatch> {
        upload(grid).iter().try_for_each(|w| self.step(w))
    }

    /// One particle: wait for `busy` to drop, `start` with `pose`, stream `scan` (offering a
    /// point on the clocks, counted from the start edge = 1, where `gap(clock)` is false),
    /// collect the results until `cost_valid`. `extra(clock, inputs)` may add model or
    /// table writes to any clock's inputs. Returns the evaluation and the clocks from `start`
    /// to `cost_valid`.
    pub fn particle(
        &mut self,
        scan: &[FxPoint],
        pose: &FxPose,
        gap: impl FnMut(u64) -> bool,
        extra: impl FnMut(u64, &mut GridInputs),
    ) -> Result<(Evaluation, u64), Mismatch> {
        self.particle_with_points(scan, pose, gap, extra).map(|(e, _, c)| (e, c))
    }

    /// [`particle`](Self::particle), also returning `nn_point` with each result (in
    /// result order: each result's transformed scan point).
    pub fn particle_with_points(
        &mut self,
        scan: &[FxPoint],
        pose: &FxPose,
        mut gap: impl FnMut(u64) -> bool,
        mut extra: impl FnMut(u64, &mut GridInputs),
    ) -> Result<(Evaluation, Vec<FxPoint>, u64), Mismatch> {
        assert!(!scan.is_empty());
        let mut wait = 0u64;
        while self.outputs().busy {
            self.step(&GridInputs::default())?;
            wait += 1;
            assert!(wait < 1 << 32, "the pipeline never became idle");
        }
        self.step(&GridInputs::start(pose))?;
        let (mut next, mut clocks) = (0, 1u64);
        let mut nearest = Vec::with_capacity(scan.len());
        let mut points = Vec::with_capacity(scan.len());
        // Generous bound, whatever the table holds: 256 rows of at most 8,191 addresses a point.
        let limit = 1000 + (scan.len() as u64 + 1) * (256 * 8192 + 300);
        loop {
            let offer = next < scan.len() && !gap(clocks);
            let mut inputs = GridInputs::offer(scan, next, offer);
            extra(clocks, &mut inputs);
            let took = offer && self.outputs().scan_ready;
            self.step(&inputs)?;
            clocks += 1;
            next += usize::from(took);
            let now = self.outputs();
            if now.nn_valid {
                nearest.push((now.nn_index, now.nn_dist));
                points.push(now.nn_point);
            }
            if now.cost_valid {
                return Ok((Evaluation { cost: now.cost, nearest }, points, clocks));
            }
            assert!(clocks < limit, "no cost_valid after {clocks} clocks ({next} of {} points taken)", scan.len());
        }
    }
}
