//! The Evaluate requests (the host-driven filter's costs and weights on the board): one
//! frame ([`BoardClient::evaluate`]), the weighing, and a whole iteration's costs and
//! weights, checked against the exp table of the board's own costs.

use super::{BoardClient, BoardError, MAX_RETRIES};
use pficp_fpga::common::format::{FxPose, WeightScale};
use pficp_fpga::protocol::messages::{EvaluateReply, EvaluateRequest, MessageError, WeightSummary, MAX_POSES};
use pficp_fpga::protocol::Command;
use pficp_fpga::surface::surface_residual::evaluation_clocks_bound;

impl BoardClient {
    /// One Evaluate frame: `poses` (at most [`MAX_POSES`]; none only with `last`) evaluated
    /// over the scan in use; with `first` the stored costs are forgotten first; with `last`
    /// every stored cost is weighed with `scale` afterwards.
    pub fn evaluate(
        &mut self,
        first: bool,
        last: bool,
        scale: WeightScale,
        poses: &[FxPose],
    ) -> Result<EvaluateReply, BoardError> {
        let n = poses.len();
        if n > MAX_POSES || (n == 0 && !last) {
            return Err(BoardError::Limit(format!(
                "an Evaluate frame carries 1 to {MAX_POSES} poses (or none to weigh), not {n}"
            )));
        }
        let after = if first { n } else { self.stored + n };
        if after == 0 || after > self.max_particles() {
            return Err(BoardError::Limit(format!(
                "{after} particle costs would be stored; the board holds 1 to {}",
                self.max_particles()
            )));
        }
        let request = EvaluateRequest { first, last, scale, poses: poses.to_vec() };
        let reply_bytes = 6 * n + if last { 11 + 2 * after } else { 0 };
        let clocks = n as u64 * evaluation_clocks_bound(self.sizes.1 as usize, self.sizes.0 as usize, self.lanes())
            + if last { after as u64 + 16 } else { 0 };
        // Appending costs twice would corrupt the iteration: only FIRST or weigh-only repeat.
        let repeatable = first || n == 0;
        let reply = self.transact(Command::Evaluate, request.encode(), reply_bytes, clocks, repeatable)?;
        let r = EvaluateReply::decode(&reply.data, n, last)
            .map_err(|problem| BoardError::Reply { command: Command::Evaluate, problem })?;
        self.stored = after;
        if let Some(s) = &r.summary {
            if s.weights.len() != after {
                return Err(BoardError::Reply {
                    command: Command::Evaluate,
                    problem: MessageError::Field {
                        field: "stored",
                        got: s.weights.len() as u64,
                        expected: after as u64,
                    },
                });
            }
        }
        Ok(r)
    }

    /// Weigh the stored costs with `scale` (Evaluate with no poses and LAST).
    pub fn weigh(&mut self, scale: WeightScale) -> Result<WeightSummary, BoardError> {
        let r = self.evaluate(false, true, scale, &[])?;
        Ok(r.summary.expect("decoded with LAST"))
    }

    /// The costs of `poses` (1 to 256), in frames of [`MAX_POSES`] without LAST (the first
    /// with FIRST): they become the stored costs. Started over (at most [`MAX_RETRIES`]
    /// times) when a reply is lost.
    pub fn costs(&mut self, poses: &[FxPose]) -> Result<Vec<u64>, BoardError> {
        if poses.is_empty() || poses.len() > self.max_particles() {
            return Err(BoardError::Limit(format!(
                "{} particles: the board weighs 1 to {}",
                poses.len(),
                self.max_particles()
            )));
        }
        let mut restarts = 0;
        'again: loop {
            let mut costs = Vec::with_capacity(poses.len());
            for (k, batch) in poses.chunks(MAX_POSES).enumerate() {
                match self.evaluate(k == 0, false, WeightScale::default(), batch) {
                    Ok(r) => costs.extend(r.costs),
                    Err(BoardError::ReplyLost { .. }) if restarts < MAX_RETRIES => {
                        restarts += 1;
                        self.stats.restarts += 1;
                        continue 'again;
                    }
                    Err(e) => return Err(e),
                }
            }
            return Ok(costs);
        }
    }

    /// One filter iteration on the board: the costs of `poses` ([`Self::costs`]), then
    /// `scale_fn(costs)` chooses the weight scale and the stored costs are weighed
    /// ([`Self::weigh`]). Returns the costs and the weights (checked: one per pose, `w_sum`
    /// their sum).
    pub fn costs_and_weights(
        &mut self,
        poses: &[FxPose],
        scale_fn: impl FnOnce(&[u64]) -> WeightScale,
    ) -> Result<(Vec<u64>, WeightSummary), BoardError> {
        let costs = self.costs(poses)?;
        let scale = scale_fn(&costs);
        let summary = self.weigh(scale)?;
        let sum: u64 = summary.weights.iter().map(|&w| w as u64).sum();
        if sum == 0 {
            // Normalising would divide by zero: every weight NaN.
            return Err(BoardError::Filter(format!(
                "the board on {} returned {} weights that are all 0 (the best particle always weighs 1)",
                self.name,
                summary.weights.len()
            )));
        }
        if sum != summary.w_sum as u64 {
            return Err(BoardError::Reply {
                command: Command::Evaluate,
                problem: MessageError::Field { field: "w_sum", got: summary.w_sum as u64, expected: sum },
            });
        }
        let min = costs.iter().copied().min().unwrap_or(0);
        if summary.min_cost != min {
            return Err(BoardError::Reply {
                command: Command::Evaluate,
                problem: MessageError::Field { field: "min_cost", got: summary.min_cost, expected: min },
            });
        }
        if summary.weights != pficp_fpga::filter::weights::weights(&costs, &scale) {
            return Err(BoardError::Filter(format!(
                "the board on {} returned weights that are not the exp table's for its own costs",
                self.name
            )));
        }
        Ok((costs, summary))
    }
}
