//! The particle filter's objective over PF-ICP's seven parameters (Algorithm 6, steps 6
//! to 8): the cost of a state, its ICP refinement, the scale bounds, and where the weights
//! come from (software or the board).

use crate::geometry::{Centred, Pose, ScaleBounds};
use crate::pf_icp::hypotheses;
use crate::pf_icp::particle_filter::{self, Objective, WeighError, Weighed};
use crate::pf_icp::surface::Surface;
use crate::registration::icp::{icp, IcpSettings};
use nalgebra::Point3;

/// Where the filter's particle costs and weights come from when not from the host's
/// k-d tree (the board: `crate::board::host_driven::BoardWeights`).
pub trait ParticleWeights: Sync {
    /// Called once, before the filter, with the scan points the costs are taken over (the
    /// fixed weight sample).
    fn prepare(&self, sample: &[Point3<f64>]) -> Result<(), WeighError>;
    /// Costs of the particles' poses (MSD over the sample, in the clouds' units) and their
    /// normalised weights, `q` the filter's ICP variance (tempered as
    /// [`particle_filter::tempered_q`] does).
    fn weigh(&self, poses: &[Pose], q: f64) -> Result<Weighed, WeighError>;
}

/// The 7-state objective over a fixed scan subset, states in the centred frame. In
/// software the cost is the capped surface distance ([`Surface::cost`]: robust to
/// outliers, not dominated by the model's sampling) and the refinement trimmed ICP; with
/// the board's weights (`weights`) it is the board's MSD and plain ICP, so that every cost
/// the filter compares is in the board's units.
pub(crate) struct PoseObjective<'a> {
    pub(crate) surface: &'a Surface<'a>,
    pub(crate) sample: &'a [Point3<f64>],
    pub(crate) frame: Centred,
    pub(crate) refine_iterations: usize,
    pub(crate) weights: Option<&'a dyn ParticleWeights>,
    /// Distance cap of the software cost.
    pub(crate) cap: f64,
    /// Allowed scale range (a collapsed scan fits any surface; the user's bounds).
    pub(crate) scale_range: (f64, f64),
    /// The user's scale bounds.
    pub(crate) bounds: ScaleBounds,
}

/// Fraction of pairs the filter's trimmed ICP refinement keeps.
const REFINE_TRIM: f64 = 0.9;

impl PoseObjective<'_> {
    fn pose(&self, x: &[f64]) -> Pose {
        self.frame.pose(x.try_into().expect("7 states"))
    }
}

impl Objective for PoseObjective<'_> {
    fn dim(&self) -> usize {
        7
    }
    fn is_angle(&self, i: usize) -> bool {
        i >= 4
    }
    fn cost(&self, x: &[f64]) -> f64 {
        let pose = self.pose(x);
        if self.weights.is_some() {
            crate::registration::icp::msd(self.surface.nn(), self.sample, &pose)
        } else {
            self.surface.cost(self.sample, &pose, self.cap)
        }
    }
    fn distances(&self, x: &[f64]) -> (f64, f64) {
        let pose = self.pose(x);
        let images: Vec<Point3<f64>> = self.sample.iter().map(|p| pose.apply(p)).collect();
        // The distances in parallel, the sum in order (the same rounding on any thread count).
        let (mut sum, mut max) = (0.0f64, 0.0f64);
        for c in self.surface.nn().closest_all(&images) {
            let d = c.dist2.sqrt();
            sum += d;
            max = max.max(d);
        }
        (sum / self.sample.len() as f64, max)
    }
    fn refine(&self, x: &[f64]) -> Option<(Vec<f64>, f64)> {
        if self.refine_iterations == 0 {
            return None;
        }
        let start = self.pose(x);
        let pose = if self.weights.is_some() {
            let s =
                IcpSettings { max_iterations: self.refine_iterations, scale_bounds: self.bounds, ..Default::default() };
            icp(self.surface.nn(), self.sample, &start, &s).pose
        } else {
            hypotheses::trimmed_icp(
                self.surface.nn(),
                self.sample,
                &start,
                self.refine_iterations,
                REFINE_TRIM,
                crate::registration::svd_match::ScaleRule::LeastSquares,
                &self.bounds,
            )
        };
        let mut refined = self.frame.params(&pose).to_vec();
        self.constrain(&mut refined);
        let c = self.cost(&refined);
        Some((refined, c))
    }
    fn constrain(&self, x: &mut [f64]) {
        x[3] = x[3].clamp(self.scale_range.0, self.scale_range.1);
    }
    fn weigh(&self, particles: &[Vec<f64>], q: f64) -> Result<Weighed, WeighError> {
        match self.weights {
            None => Ok(particle_filter::weigh_in_software(self, particles, q)),
            Some(source) => {
                let poses: Vec<Pose> = particles.iter().map(|x| self.pose(x)).collect();
                source.weigh(&poses, q)
            }
        }
    }
}
