//! The on-board filter's requests (Run, Status, Result; the polish after the filter since
//! protocol 5) and the time a run may take: the modelled board time from the sequencer's
//! clock count and the polish's bound, the allowance, the wait.

use super::{BoardClient, BoardError, MAX_RETRIES, MIN_CLOCK_HZ, RUN_SAFETY};
use pficp_fpga::protocol::messages::{
    parse_two_u16, MessageError, ResultReply, RunState, StatusReply, RESULT_BYTES, RUN_REPLY_BYTES, STATUS_BYTES,
};
use pficp_fpga::protocol::run_request::{polish_clocks_bound, RunRequest};
use pficp_fpga::protocol::Command;
use pficp_fpga::surface::surface_residual::evaluation_clocks_bound;
use std::time::{Duration, Instant};

impl BoardClient {
    /// The board's clocks for the Run `r` over the sizes in use: the filter's bound
    /// ([`run_clocks_bound`]) and the polish's ([`polish_clocks_bound`]) with the board's
    /// lanes (1 before Identify).
    pub fn run_clocks(&self, r: &RunRequest) -> u64 {
        let (model, scan, lanes) = (self.sizes.0 as usize, self.sizes.1 as usize, self.lanes());
        run_clocks_bound(r.filter.particles, r.filter.iterations, scan, model, lanes)
            + polish_clocks_bound(&r.polish, model, lanes)
    }

    /// The modelled board time of the on-board filter of `cfg` ([`Self::run_clocks`] at the
    /// board's clock; 100 MHz before Identify).
    pub fn modelled_run_time(&self, cfg: &RunRequest) -> Duration {
        Duration::from_secs_f64(self.run_clocks(cfg) as f64 / self.clock_hz())
    }

    /// The clock the deadlines assume: the board's (100 MHz before Identify), never below
    /// [`MIN_CLOCK_HZ`].
    pub(super) fn clock_hz(&self) -> f64 {
        self.identity.map_or(100e6, |i| i.clock_hz.max(MIN_CLOCK_HZ) as f64)
    }

    /// How long a run of `cfg` may take before it is an error: [`RUN_SAFETY`] times the
    /// modelled board time plus the timeout per reply.
    pub fn run_allowance(&self, cfg: &RunRequest) -> Duration {
        self.modelled_run_time(cfg) * RUN_SAFETY + self.timeout
    }

    /// Start the on-board filter and the polish after it (Run) over the model and scan in
    /// use; they run in the background. Particles (1 to the board's most) and iterations (at
    /// least 1) are checked here; the board checks the sizes and the polish's points. A board
    /// already running answers `Busy`: [`BoardError::Board`].
    pub fn run(&mut self, request: &RunRequest) -> Result<(), BoardError> {
        let cfg = &request.filter;
        let (n, k) = (cfg.particles as usize, cfg.iterations);
        if n == 0 || n > self.max_particles() || k == 0 {
            return Err(BoardError::Limit(format!(
                "{n} particles and {k} iterations: the board runs 1 to {} particles, at least 1 iteration",
                self.max_particles()
            )));
        }
        self.run_iterations = Some(cfg.iterations);
        self.run_starts = Some(1 + request.polish.hypotheses.len());
        let data = request.encode();
        // A board that computes before it answers (the timeless reference) needs the run's time.
        let extra = self.run_allowance(request).saturating_sub(self.timeout);
        let mut lost = 0;
        loop {
            match self.transact_with(Command::Run, data.clone(), RUN_REPLY_BYTES, extra, 0, false) {
                Ok(reply) => {
                    if reply.data != data[..RUN_REPLY_BYTES] {
                        let (p, i) = parse_two_u16(&reply.data)
                            .map_err(|problem| BoardError::Reply { command: Command::Run, problem })?;
                        return Err(BoardError::Reply {
                            command: Command::Run,
                            problem: MessageError::Field {
                                field: "particles, iterations",
                                got: ((p as u64) << 16) | i as u64,
                                expected: ((cfg.particles as u64) << 16) | cfg.iterations as u64,
                            },
                        });
                    }
                    return Ok(());
                }
                Err(BoardError::ReplyLost { command, reason }) => {
                    // The board may have started it: then it is running now.
                    if self.status()?.state == RunState::Running {
                        self.stats.restarts += 1;
                        return Ok(());
                    }
                    lost += 1;
                    if lost > MAX_RETRIES {
                        return Err(BoardError::ReplyLost { command, reason });
                    }
                    self.stats.resends += 1;
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// The on-board filter's state, iterations done and best cost so far (Status).
    pub fn status(&mut self) -> Result<StatusReply, BoardError> {
        let reply = self.transact(Command::Status, Vec::new(), STATUS_BYTES, 0, true)?;
        StatusReply::decode(&reply.data).map_err(|problem| BoardError::Reply { command: Command::Status, problem })
    }

    /// The finished filter's best particle, cost and pose, and the polish's choice (Result).
    /// A board still running
    /// answers `Busy`, one that has run no filter since power-up or reset `NoResult`: both
    /// [`BoardError::Board`].
    ///
    /// The reply is checked: at least 1 iteration and no more than the last Run asked for,
    /// the largest point distance within the cost, the pose the one
    /// [`pficp_fpga::filter::pf::pose_of`] builds from the parameters, the winning start one of the
    /// last Run's.
    pub fn result(&mut self) -> Result<ResultReply, BoardError> {
        let reply = self.transact(Command::Result, Vec::new(), RESULT_BYTES, 0, true)?;
        let bad = |problem| BoardError::Reply { command: Command::Result, problem };
        let r = ResultReply::decode(&reply.data).map_err(bad)?;
        let cap = self.run_iterations.unwrap_or(u16::MAX);
        if r.iterations == 0 || r.iterations > cap {
            return Err(bad(MessageError::Field {
                field: "iterations",
                got: r.iterations as u64,
                expected: cap as u64,
            }));
        }
        if r.max_d2 > r.cost {
            return Err(bad(MessageError::Field { field: "max_d2 (above the cost)", got: r.max_d2, expected: r.cost }));
        }
        let starts = self.run_starts.unwrap_or(pficp_fpga::protocol::run_request::MAX_STARTS);
        if r.polish.winner as usize >= starts {
            return Err(bad(MessageError::Field {
                field: "winning start",
                got: r.polish.winner as u64,
                expected: starts as u64 - 1,
            }));
        }
        if r.pose != pficp_fpga::filter::pf::pose_of(&r.params) {
            return Err(BoardError::Filter(format!(
                "the board on {} returned a pose that is not the one its parameters {:?} give",
                self.name, r.params
            )));
        }
        Ok(r)
    }

    /// Poll Status every `every` until the filter is done (state 2); `progress` gets each
    /// reply. Returns the last reply and the number of polls. A board still running whose
    /// iteration count has not changed for `limit` (counted from the call, then from each
    /// change) is a [`BoardError::RunTimeout`] naming `modelled`: a hung board is caught
    /// after `limit`, while a slow one that keeps making progress (the simulated board runs
    /// about 40 times slower than real time) is waited for, up to `limit` times (the Run's
    /// iterations + 1) in all, since the count must rise and stay within the Run's (a count
    /// that goes back or passes it is a [`BoardError::Filter`] at once). One that reports no
    /// run (state 0: reset?) is a [`BoardError::Filter`]; one that stops answering a
    /// [`BoardError::Timeout`] within the timeout per reply.
    pub fn wait_for_run(
        &mut self,
        limit: Duration,
        modelled: Duration,
        every: Duration,
        mut progress: impl FnMut(&StatusReply),
    ) -> Result<(StatusReply, usize), BoardError> {
        let start = Instant::now();
        let mut since = start;
        let mut last_iterations = None;
        let mut polls = 0;
        let overall = limit * (self.run_iterations.map_or(1, |k| k as u32) + 1);
        loop {
            let s = self.status()?;
            polls += 1;
            progress(&s);
            // The count only rises and stays within the Run's cap; otherwise the time limit,
            // restarted at every new count, would never end for a board whose counter
            // oscillates or wraps.
            if let Some(last) = last_iterations {
                if s.iterations < last {
                    return Err(BoardError::Filter(format!(
                        "the board on {} reports {} iterations after {last}: its iteration count went back",
                        self.name, s.iterations
                    )));
                }
            }
            if let Some(cap) = self.run_iterations {
                if s.iterations > cap {
                    return Err(BoardError::Filter(format!(
                        "the board on {} reports {} iterations, more than the {cap} it was asked for",
                        self.name, s.iterations
                    )));
                }
            }
            if last_iterations != Some(s.iterations) {
                if last_iterations.is_some() {
                    since = Instant::now();
                }
                last_iterations = Some(s.iterations);
            }
            match s.state {
                RunState::Done => return Ok((s, polls)),
                RunState::Idle => {
                    return Err(BoardError::Filter(format!(
                        "the board on {} reports no filter run (was it reset?)",
                        self.name
                    )))
                }
                RunState::Running => {}
            }
            let waited = since.elapsed();
            if waited >= limit || start.elapsed() >= overall {
                return Err(BoardError::RunTimeout {
                    port: self.name.clone(),
                    stall_limit: limit,
                    overall_limit: overall,
                    waited,
                    total: start.elapsed(),
                    modelled,
                    state: s.state,
                    iterations: s.iterations,
                });
            }
            std::thread::sleep(every.min(limit - waited).min(overall.saturating_sub(start.elapsed())));
        }
    }
}

/// An upper bound on the on-board filter's clocks for `particles` and all `iterations` over
/// `scan_points` and `model_points` on `lanes` lanes: the sequencer's exact count
/// ([`pficp_fpga::filter::sequencer::run_clocks`]) with every data-dependent part at its largest
/// (the temperature's most passes, a new best every iteration, the resampling pointer advancing
/// through every particle) and each evaluation taking the neighbour pipeline's bound
/// [`evaluation_clocks_bound`] (any pose, any model of that size; the neighbour pipeline and
/// the residual stage) plus one clock:
/// `particles x iterations + iterations + 1` poses.
pub fn run_clocks_bound(particles: u16, iterations: u16, scan_points: usize, model_points: usize, lanes: usize) -> u64 {
    run_clocks_for(particles, iterations, evaluation_clocks_bound(scan_points, model_points, lanes.max(1)))
}

/// [`run_clocks_bound`] with every evaluation taking `evaluation_clocks` (the start edge to
/// the residual stage's `cost_valid`).
pub fn run_clocks_for(particles: u16, iterations: u16, evaluation_clocks: u64) -> u64 {
    use pficp_fpga::filter::sequencer::{run_clocks, IterationShape, MAX_TEMPER_PASSES};
    let n = particles as u64;
    let eval = 1 + evaluation_clocks;
    let shape = |last: bool| IterationShape {
        particles: n,
        // The particles' evaluations overlap the next particle's propagation: at most each
        // evaluation plus four clocks of launch, synchronisation and store.
        eval_clocks: (n + 1) * eval + 4 * n,
        temper_passes: MAX_TEMPER_PASSES,
        best_copied: true,
        resample_advances: (!last).then_some(n.saturating_sub(1)),
    };
    let k = iterations as usize;
    let shapes: Vec<IterationShape> = (0..k).map(|i| shape(i + 1 == k)).collect();
    run_clocks(eval, &shapes)
}
