//! One registration as a caller asks for it: the method, the engine that runs it and the
//! settings ([`Request`]). [`Request::check`] refuses what cannot run with one line naming
//! the problem (before any work or any board traffic); [`Request::run`] runs it on the
//! clouds. The CLI's `register` parses its flags into a `Request`, opens the board when the
//! engine needs one, and prints the [`Registered`] result.

use crate::board::host_driven::{self, BoardReport};
use crate::board::on_board::{self, OnBoardReport, OnBoardStep, DEFAULT_BOARD_POINTS};
use crate::board::{BoardClient, DEFAULT_POLL};
use crate::cloud::Cloud;
use crate::geometry::ScaleBounds;
use crate::nn::NearestNeighbours;
use crate::pf_icp::hypotheses::SearchSettings;
use crate::pf_icp::init::InitMode;
use crate::pf_icp::{PfIcpSettings, MAX_CLUSTERS, MAX_FILTER_PARTICLES, MAX_ITERATIONS};
use crate::registration::methods::{self, Method, MethodSettings, Outcome};
use anyhow::{bail, Result};
use std::time::{Duration, Instant};

/// The scan's bounding-box diagonal may be this many times the model's at least (and its
/// inverse at most): beyond it the clouds are in different units, or one is a point.
pub const MIN_EXTENT_RATIO: f64 = 1e-6;

/// PF-ICP's settings as a caller gives them (the CLI's flags, the Python package's
/// keywords), before they are checked: [`PfIcpOptions::settings`] refuses what cannot run,
/// with one line naming the CLI's flag.
#[derive(Clone, Debug)]
pub struct PfIcpOptions {
    /// Clusters K per cloud (`--clusters`).
    pub clusters: usize,
    /// Particles (`--particles`).
    pub particles: usize,
    /// Iteration cap (`--iterations`).
    pub iterations: usize,
    /// Seed of every random choice (`--seed`).
    pub seed: u64,
    /// Cluster pairing (`--init`).
    pub init: InitMode,
    /// The known scale (`--scale`).
    pub scale: Option<f64>,
    /// The scale's bounds `LO,HI` (`--scale-range`; any other count of numbers is refused).
    pub scale_range: Option<Vec<f64>>,
    /// The sensor's position in the scan's frame `X,Y,Z` (`--viewpoint`).
    pub viewpoint: Option<Vec<f64>>,
    /// The rescue search when the evidence rules out the first answer (`--no-rescue`
    /// turns it off: [`crate::pf_icp::rescue`]).
    pub rescue: bool,
}

impl Default for PfIcpOptions {
    fn default() -> Self {
        let d = PfIcpSettings::default();
        PfIcpOptions {
            clusters: d.clusters,
            particles: d.particles,
            iterations: d.iterations,
            seed: d.seed,
            init: d.init,
            scale: None,
            scale_range: None,
            viewpoint: None,
            rescue: true,
        }
    }
}

impl PfIcpOptions {
    /// The settings, or one line on the first option that cannot run.
    pub fn settings(&self) -> Result<PfIcpSettings> {
        for (flag, value, limit) in [
            ("--particles", self.particles, MAX_FILTER_PARTICLES),
            ("--iterations", self.iterations, MAX_ITERATIONS),
            ("--clusters", self.clusters, MAX_CLUSTERS),
        ] {
            if value == 0 {
                bail!("{flag} must be at least 1");
            }
            if value > limit {
                bail!("{flag} must be at most {limit} (got {value})");
            }
        }
        let scale = match (self.scale, self.scale_range.as_deref()) {
            (Some(_), Some(_)) => bail!("--scale and --scale-range cannot both be given (--scale fixes the scale)"),
            (Some(s), None) => {
                if !(s.is_finite() && s > 0.0) {
                    bail!("--scale must be a positive finite number (got {s})");
                }
                ScaleBounds::fixed(s)
            }
            (None, None) => ScaleBounds::FREE,
            (None, Some(&[lo, hi])) => {
                if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > 0.0) {
                    bail!("--scale-range takes two positive finite numbers LO,HI (got {lo},{hi})");
                }
                if lo > hi {
                    bail!("--scale-range LO,HI needs LO <= HI (got {lo},{hi})");
                }
                ScaleBounds::range(lo, hi)
            }
            (None, Some(v)) => bail!("--scale-range takes two numbers LO,HI (got {})", v.len()),
        };
        let viewpoint = match self.viewpoint.as_deref() {
            None => None,
            Some(&[x, y, z]) => {
                if ![x, y, z].iter().all(|v| v.is_finite()) {
                    bail!("--viewpoint takes three finite numbers X,Y,Z (got {x},{y},{z})");
                }
                Some(nalgebra::Point3::new(x, y, z))
            }
            Some(v) => bail!("--viewpoint takes three numbers X,Y,Z (got {})", v.len()),
        };
        let d = PfIcpSettings::default();
        Ok(PfIcpSettings {
            clusters: self.clusters,
            particles: self.particles,
            iterations: self.iterations,
            seed: self.seed,
            init: self.init,
            scale,
            viewpoint,
            search: d.search.map(|s| SearchSettings { rescue: self.rescue, ..s }),
            ..d
        })
    }
}

/// Where the registration runs.
#[derive(Clone, Debug, PartialEq)]
pub enum Engine {
    /// Everything on the host.
    Software,
    /// PF-ICP's filter on the board ([`on_board`]): the start, covariance and polish on the
    /// host; the board weighs each particle over `board_points` scan points and is polled
    /// every `poll`.
    OnBoard {
        /// Scan points the on-board filter weighs each particle over.
        board_points: usize,
        /// Status poll period.
        poll: Duration,
    },
    /// The host runs the filter; the board weighs each iteration's particles
    /// ([`host_driven`], the mode of protocol version 1 boards).
    HostDriven,
}

impl Engine {
    /// The engine a caller's options ask for: none without a board; with one, the
    /// host-driven mode or the on-board filter (over `board_points` scan points a particle,
    /// [`DEFAULT_BOARD_POINTS`] when not given). Options that do not go together are
    /// refused with one line naming the CLI's flags.
    pub fn from_options(board: bool, host_driven: bool, board_points: Option<usize>) -> Result<Engine> {
        if !board && (host_driven || board_points.is_some()) {
            bail!("--host-driven and --board-points need --board PORT");
        }
        if host_driven && board_points.is_some() {
            bail!("--board-points sets the on-board filter's scan sample; --host-driven weighs the host's sample");
        }
        Ok(match (board, host_driven) {
            (false, _) => Engine::Software,
            (true, true) => Engine::HostDriven,
            (true, false) => {
                Engine::OnBoard { board_points: board_points.unwrap_or(DEFAULT_BOARD_POINTS), poll: DEFAULT_POLL }
            }
        })
    }

    /// The on-board filter with its defaults.
    pub fn on_board() -> Engine {
        Engine::OnBoard { board_points: DEFAULT_BOARD_POINTS, poll: DEFAULT_POLL }
    }

    /// A board is needed.
    pub fn needs_board(&self) -> bool {
        *self != Engine::Software
    }
}

/// A registration request.
#[derive(Clone, Debug)]
pub struct Request {
    /// The method.
    pub method: Method,
    /// Where it runs.
    pub engine: Engine,
    /// PF-ICP's settings (the baselines take the iteration cap and the seed from them).
    pub settings: PfIcpSettings,
}

/// What the board did, for the report.
#[derive(Clone, Debug)]
pub enum BoardRun {
    /// The on-board filter.
    OnBoard(Box<OnBoardReport>),
    /// The host-driven filter.
    HostDriven(BoardReport),
}

/// A registration's result.
pub struct Registered {
    /// Pose, fit, iterations, time, and PF-ICP's intermediate results.
    pub outcome: Outcome,
    /// The board's part, when one ran.
    pub board: Option<BoardRun>,
}

/// Progress of a board engine, `(step, done, total)`: the uploads and the filter's
/// iterations, in both modes (the host-driven filter may stop before the iteration cap).
pub struct BoardProgress<'a> {
    /// The steps of the run.
    pub on_board: &'a mut (dyn FnMut(OnBoardStep, usize, usize) + Send),
}

impl Request {
    /// Software PF-ICP with the default settings.
    pub fn new(method: Method) -> Request {
        Request { method, engine: Engine::Software, settings: PfIcpSettings::default() }
    }

    /// Refuse what cannot run on these clouds: too few points for the clusters, fewer than
    /// three points, extents in different units, a board engine for a baseline.
    pub fn check(&self, model: &Cloud, scan: &Cloud) -> Result<()> {
        if self.method == Method::PfIcp {
            for (name, c) in [("model", model), ("scan", scan)] {
                if c.len() < self.settings.clusters {
                    bail!(
                        "{name} has {} points, fewer than the {} clusters asked for (--clusters)",
                        c.len(),
                        self.settings.clusters
                    );
                }
            }
        }
        if scan.len() < 3 || model.len() < 3 {
            bail!("registration needs at least 3 points in each cloud (model {}, scan {})", model.len(), scan.len());
        }
        let extent_ratio = scan.diagonal() / model.diagonal();
        if !(MIN_EXTENT_RATIO..=1.0 / MIN_EXTENT_RATIO).contains(&extent_ratio) {
            bail!(
                "the scan's extent is {extent_ratio:e} times the model's: beyond {MIN_EXTENT_RATIO:e} to {:e} (different units?)",
                1.0 / MIN_EXTENT_RATIO
            );
        }
        let scale_given = !self.settings.scale.is_free();
        if scale_given && matches!(self.method, Method::SparseIcp | Method::EmIcp) {
            bail!(
                "--scale and --scale-range apply to pf-icp, icp, welsch and cauchy (got --method {})",
                self.method.name()
            );
        }
        if self.settings.viewpoint.is_some() && self.method != Method::PfIcp {
            bail!("--viewpoint applies to pf-icp (got --method {})", self.method.name());
        }
        if self.engine.needs_board() && self.method != Method::PfIcp {
            bail!("--board runs PF-ICP only (got --method {})", self.method.name());
        }
        if let Engine::OnBoard { board_points: 0, .. } = self.engine {
            bail!("--board-points must be at least 1");
        }
        Ok(())
    }

    /// Run the request (after [`Request::check`]); `client` is the open board for a board
    /// engine.
    pub fn run(
        &self,
        model: &Cloud,
        scan: &Cloud,
        client: Option<&mut BoardClient>,
        progress: BoardProgress,
    ) -> Result<Registered> {
        self.check(model, scan)?;
        let nn = NearestNeighbours::new(model.points());
        let start = Instant::now();
        let board_outcome = |pf: crate::pf_icp::PfIcpResult| Outcome {
            registration: pf.registration.clone(),
            elapsed: start.elapsed(),
            pf: Some(Box::new(pf)),
        };
        Ok(match (&self.engine, client) {
            (Engine::Software, _) => Registered {
                outcome: methods::run(self.method, &nn, scan.points(), &MethodSettings { pf: self.settings.clone() }),
                board: None,
            },
            (_, None) => bail!("the {:?} engine needs an open board", self.engine),
            (Engine::OnBoard { board_points, poll }, Some(c)) => {
                let r = on_board::register_on_board(
                    c,
                    &nn,
                    scan.points(),
                    &self.settings,
                    *board_points,
                    *poll,
                    progress.on_board,
                )?;
                Registered { board: Some(BoardRun::OnBoard(Box::new(r.board))), outcome: board_outcome(r.pf) }
            }
            (Engine::HostDriven, Some(c)) => {
                let r = host_driven::register_reporting(c, &nn, scan.points(), &self.settings, progress.on_board)?;
                Registered { board: Some(BoardRun::HostDriven(r.board)), outcome: board_outcome(r.pf) }
            }
        })
    }
}
