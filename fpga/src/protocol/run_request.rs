//! The Run request of protocol 7 (docs/protocol.md, "Run"): the on-board filter's
//! configuration ([`PfConfig`]) and the on-board polish after it ([`PolishRequest`]), and
//! what the board does with it ([`execute`]): the filter over the first `scan_count`
//! stored scan points (SetSizes), then [`crate::polish::polish_winner_over`] over the first
//! `points` stored points from the filter's pose and the request's hypotheses.
//!
//! Layout: the filter's 150 bytes ([`PfConfig::encode`]) with its sixth byte the number of
//! starts (its low four bits; 0 is taken as 1), then the polish word (6 bytes: `points` u16,
//! `steps` in the low four bits of the next byte, `winner_steps` in the low four bits of
//! the next, the scale in bit 0 of the next ([`SCALE_HELD`]: set, the scale is held), a
//! zero byte), then `starts - 1`
//! hypothesis poses of 27 bytes ([`crate::protocol::layout::pose_bytes`]).

use crate::common::format::{FxPose, MAX_POINTS};
use crate::filter::pf::{ConfigError, PfConfig, PfOutcome, RUN_BYTES, RUN_WORD_BYTES};
use crate::polish::{polish_winner_over, ScaleStep};
use crate::protocol::layout::{pose_bytes, pose_from_bytes, POSE_BYTES};
use crate::surface::Search;

/// Most starts of the polish: the filter's pose and fourteen hypotheses (the Run's starts
/// field is four bits; the board keeps the hypotheses in a 16-word RAM).
pub const MAX_STARTS: usize = 15;
/// Bits of the Run's starts field (the low bits of [`STARTS_BYTE`]).
pub const STARTS_BITS: u32 = 4;
/// Most Gauss-Newton steps a start (four bits).
pub const MAX_STEPS: u8 = 15;
/// Data bytes of a Run request with one start (no hypothesis).
pub const RUN_BASE_BYTES: usize = RUN_BYTES + RUN_WORD_BYTES;
/// Byte of the Run request that holds the number of starts.
pub const STARTS_BYTE: usize = 5;
/// Byte of the Run request that holds the polish's scale flag (the polish word's fifth).
pub const SCALE_BYTE: usize = RUN_BYTES + 4;
/// The flag in [`SCALE_BYTE`]: the polish holds the scale ([`ScaleStep::Held`]); the
/// byte's other bits are ignored.
pub const SCALE_HELD: u8 = 1;

/// The data bytes of a Run request with `starts` starts (as the board takes the count:
/// the low four bits, 0 as 1).
pub fn run_bytes(starts_byte: u8) -> usize {
    RUN_BASE_BYTES + POSE_BYTES * (starts_of(starts_byte) - 1)
}

/// The starts a Run's sixth byte asks for: its low four bits, 0 taken as 1.
pub fn starts_of(b: u8) -> usize {
    ((b & ((1 << STARTS_BITS) - 1)) as usize).max(1)
}

/// The polish the board runs after its filter.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PolishRequest {
    /// Stored scan points the polish's passes go over, from the first (1 ..= 4,096; the
    /// filter's `scan_count` points are the first of them).
    pub points: u16,
    /// Gauss-Newton steps a start (0 ..= [`MAX_STEPS`]; the board takes the low four bits).
    pub steps: u8,
    /// Further steps for the winner among the starts, from its pose (0 ..= [`MAX_STEPS`];
    /// 0: none; the low four bits).
    pub winner_steps: u8,
    /// Whether the steps solve for the scale or hold it (from protocol 7 on).
    pub scale: ScaleStep,
    /// The starts after the filter's pose (at most `MAX_STARTS - 1`).
    pub hypotheses: Vec<FxPose>,
}

/// A Run request.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunRequest {
    /// The filter.
    pub filter: PfConfig,
    /// The polish after it.
    pub polish: PolishRequest,
}

impl RunRequest {
    /// The request's data.
    pub fn encode(&self) -> Vec<u8> {
        assert!(self.polish.hypotheses.len() < MAX_STARTS, "at most {MAX_STARTS} starts");
        let mut out = self.filter.encode();
        out[STARTS_BYTE] = 1 + self.polish.hypotheses.len() as u8;
        out.extend(self.polish.points.to_le_bytes());
        out.push(self.polish.steps & MAX_STEPS);
        out.push(self.polish.winner_steps & MAX_STEPS);
        out.push(match self.polish.scale {
            ScaleStep::Solved => 0,
            ScaleStep::Held => SCALE_HELD,
        });
        out.extend([0; RUN_WORD_BYTES - 5]);
        for h in &self.polish.hypotheses {
            out.extend_from_slice(&pose_bytes(h));
        }
        out
    }

    /// Parse a Run request's data with the board's checks: the length (by the starts), then
    /// the filter's capacities, then the polish's points (1 to 4,096).
    pub fn decode(d: &[u8]) -> Result<RunRequest, ConfigError> {
        if d.len() <= STARTS_BYTE || d.len() != run_bytes(d[STARTS_BYTE]) {
            return Err(ConfigError::Length(d.len()));
        }
        let mut head = d[..RUN_BYTES].to_vec();
        head[STARTS_BYTE] = 0;
        let filter = PfConfig::decode(&head)?;
        let points = u16::from_le_bytes([d[RUN_BYTES], d[RUN_BYTES + 1]]);
        if points == 0 || points as usize > MAX_POINTS {
            return Err(ConfigError::Points(points));
        }
        let hypotheses = d[RUN_BASE_BYTES..].chunks_exact(POSE_BYTES).map(pose_from_bytes).collect();
        let (steps, winner_steps) = (d[RUN_BYTES + 2] & MAX_STEPS, d[RUN_BYTES + 3] & MAX_STEPS);
        let scale = if d[SCALE_BYTE] & SCALE_HELD != 0 { ScaleStep::Held } else { ScaleStep::Solved };
        Ok(RunRequest { filter, polish: PolishRequest { points, steps, winner_steps, scale, hypotheses } })
    }
}

/// Clocks of the control's own between two passes, at most, beside its programs: the
/// pose's load (12 clocks) and read back (13), and a few clocks of state a program.
pub const CONTROL_CLOCKS: u64 = 64;

/// Clocks between two passes of the polish, at most: the most its programs take between
/// two passes (between two gated passes: the solve, the update, the next gate and the
/// clear; the other gaps run fewer programs), by their instructions' bounds
/// ([`crate::polish::program::program_clocks_bound`], checked against the Verilated
/// datapath), and [`CONTROL_CLOCKS`].
pub fn program_clocks_bound() -> u64 {
    use crate::polish::program::program_clocks_bound as bound;
    use crate::polish::programs::Entry;
    let of = |entries: &[Entry]| entries.iter().map(|e| bound(&e.program())).sum::<u64>();
    let gaps = [
        of(&[Entry::Start, Entry::Clear]),
        of(&[Entry::Gate, Entry::Clear]),
        of(&[Entry::Solve, Entry::Update, Entry::Gate, Entry::Clear]),
        of(&[Entry::Solve, Entry::Update, Entry::Drift]),
    ];
    gaps.into_iter().max().unwrap_or(0) + CONTROL_CLOCKS
}

/// Clocks a pass spends on a point beyond the pipeline's evaluation of it, at most: the
/// pass's front, 14 clocks for an inlier and one to take the next, the queue's two clocks
/// and the launch.
pub const PASS_POINT_CLOCKS: u64 = 32;

/// Clocks from a pass's last point to its end, at most: the product stage's last row (13),
/// the engine's seven quiet clocks, the flush of the pass's accumulators into the
/// registers (37) and the hand-offs between them.
pub const PASS_END_CLOCKS: u64 = 64;

/// An upper bound on the board's clocks for the polish of `p` over a model of
/// `model_points` on `lanes` lanes: each start takes at most `steps + 2` passes (the
/// statistics, the steps, the cost) and as many program runs, the winner's further polish
/// `winner_steps + 2`; a point takes at most one
/// evaluation of one point ([`crate::surface::surface_residual::evaluation_clocks_bound`]; the pass
/// lets several into the pipeline, which only overlaps them) and [`PASS_POINT_CLOCKS`],
/// and a pass ends within [`PASS_END_CLOCKS`] of its last point.
pub fn polish_clocks_bound(p: &PolishRequest, model_points: usize, lanes: usize) -> u64 {
    let point =
        crate::surface::surface_residual::evaluation_clocks_bound(1, model_points, lanes.max(1)) + PASS_POINT_CLOCKS;
    polish_passes(p) * (p.points as u64 * point + PASS_END_CLOCKS + program_clocks_bound())
}

/// The passes of the polish of `p`, at most: each start's `steps + 2` (the statistics,
/// the steps, the cost), and the winner's further polish `winner_steps + 2`.
fn polish_passes(p: &PolishRequest) -> u64 {
    let starts = 1 + p.hypotheses.len() as u64;
    let winner = match p.winner_steps.min(MAX_STEPS) {
        0 => 0,
        w => w as u64 + 2,
    };
    starts * (p.steps.min(MAX_STEPS) as u64 + 2) + winner
}

/// Clocks the pass's front spends on an inlier ([`crate::polish::pass_rtl`]'s schedule: 14
/// clocks, and one to take the next point).
pub const PASS_INLIER_CLOCKS: u64 = 15;

/// A model of the board's clocks for the polish of `p` (the estimate of a tracked frame's
/// time, not a deadline: [`polish_clocks_bound`] is that) when the pipeline takes
/// `pipeline` clocks over its points at the start's pose (the neighbour pipeline's cycle
/// model): each pass the pipeline's clocks, then the front's [`PASS_INLIER_CLOCKS`] for
/// every point as if each were an inlier and none overlapped the pipeline, and
/// [`PASS_END_CLOCKS`]; between passes the programs' bounds ([`program_clocks_bound`]).
pub fn polish_clocks_model(p: &PolishRequest, pipeline: u64) -> u64 {
    polish_passes(p) * (pipeline + p.points as u64 * PASS_INLIER_CLOCKS + PASS_END_CLOCKS + program_clocks_bound())
}

/// What the polish chose.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PolishOutcome {
    /// The winning start (0 the filter's pose).
    pub winner: u8,
    /// Its pose.
    pub pose: FxPose,
    /// Its cost over the polish's points.
    pub cost: u64,
}

/// What a Run computes: the filter's outcome and the polish's choice.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunOutcome {
    /// The filter.
    pub filter: PfOutcome,
    /// The polish.
    pub polish: PolishOutcome,
}

/// Run `request` as the board does: the filter with `evaluate` (the search over the
/// filter's points), then the polish over `polish_scan` (the first `points` stored points)
/// with `search`.
pub fn execute(
    request: &RunRequest,
    evaluate: impl FnMut(&FxPose) -> crate::filter::pf::Evaluated,
    search: &impl Search,
    polish_scan: &[crate::common::format::FxPoint],
) -> RunOutcome {
    let filter = crate::filter::pf::run(&request.filter, evaluate);
    let starts: Vec<FxPose> = std::iter::once(filter.pose).chain(request.polish.hypotheses.iter().copied()).collect();
    let (winner, polished, cost) = polish_winner_over(
        search,
        polish_scan,
        &starts,
        request.polish.steps as u32,
        request.polish.winner_steps as u32,
        request.polish.scale,
    )
    .expect("one start at least");
    RunOutcome { filter, polish: PolishOutcome { winner: winner as u8, pose: polished.pose, cost } }
}

/// A request for tests and examples: [`crate::filter::pf::example_config`]'s filter, then a polish
/// of 2 steps over `points` stored points from the filter's pose and one hypothesis (the
/// identity moved by 64 LSB along x), and one more step for the winner.
pub fn example_request(particles: u16, iterations: u16, seed: u32, points: u16) -> RunRequest {
    let one = 1 << crate::common::format::MATRIX_FRAC;
    let moved = FxPose { m: [one, 0, 0, 0, one, 0, 0, 0, one], t: [64, 0, 0] };
    RunRequest {
        filter: crate::filter::pf::example_config(particles, iterations, seed),
        polish: PolishRequest { points, steps: 2, winner_steps: 1, scale: ScaleStep::Solved, hypotheses: vec![moved] },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(hyps: usize) -> RunRequest {
        let filter = PfConfig {
            particles: 50,
            iterations: 40,
            temper_exp: 20,
            centre: [1, -2, 3, 1 << 21, 5, -6, 7],
            sigma0: [100; 7],
            floor: [3; 7],
            seed: 9,
            thr_cost: 1000,
            thr_max: 50,
        };
        let pose = |k: i32| FxPose { m: [k, -k, 2, -2, 131071, -131072, 0, 5, -5], t: [7, -7, 100 + k] };
        RunRequest {
            filter,
            polish: PolishRequest {
                points: 1000,
                steps: 5,
                winner_steps: hyps as u8 % 3,
                scale: if hyps % 2 == 1 { ScaleStep::Held } else { ScaleStep::Solved },
                hypotheses: (0..hyps as i32).map(pose).collect(),
            },
        }
    }

    /// The model of a polish's clocks stays within the deadline's bound when the pipeline
    /// takes its bound for every point, and grows with the points and the steps.
    #[test]
    fn the_polish_model_is_within_the_bound() {
        for (h, points, steps) in [(0, 150u16, 3u8), (0, 700, 3), (2, 1000, 5), (7, 4096, 15)] {
            let mut r = request(h).polish;
            (r.points, r.steps) = (points, steps);
            let (model, lanes) = (2000, 8);
            let per_point = crate::surface::surface_residual::evaluation_clocks_bound(1, model, lanes);
            let worst = polish_clocks_model(&r, per_point * points as u64);
            assert!(worst <= polish_clocks_bound(&r, model, lanes), "{h} {points} {steps}");
            let more = PolishRequest { points: points + 1, steps: steps.min(14) + 1, ..r.clone() };
            assert!(polish_clocks_model(&more, 1000) > polish_clocks_model(&r, 1000));
        }
    }

    #[test]
    fn run_requests_round_trip_with_their_lengths() {
        for h in 0..MAX_STARTS {
            let r = request(h);
            let d = r.encode();
            assert_eq!(d.len(), 156 + 27 * h);
            assert_eq!(d.len(), run_bytes(d[STARTS_BYTE]));
            assert_eq!(RunRequest::decode(&d), Ok(r));
            assert_eq!(RunRequest::decode(&d[..d.len() - 1]), Err(ConfigError::Length(d.len() - 1)));
        }
        // The scale flag is bit 0 of its byte; the other bits are ignored.
        for (byte, scale) in [(0xfe, ScaleStep::Solved), (0xff, ScaleStep::Held), (SCALE_HELD, ScaleStep::Held)] {
            let mut d = request(2).encode();
            d[SCALE_BYTE] = byte;
            assert_eq!(RunRequest::decode(&d).map(|r| r.polish.scale), Ok(scale));
        }
        // Starts 0 is taken as 1: the length of one start.
        let mut d = request(0).encode();
        d[STARTS_BYTE] = 16;
        assert_eq!(RunRequest::decode(&d).map(|r| r.polish.hypotheses.len()), Ok(0));
        for bad in [0u16, 4097] {
            let mut d = request(1).encode();
            d[RUN_BYTES..RUN_BYTES + 2].copy_from_slice(&bad.to_le_bytes());
            assert_eq!(RunRequest::decode(&d), Err(ConfigError::Points(bad)));
        }
    }
}
