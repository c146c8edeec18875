//! `pficp`: register point clouds with PF-ICP or a baseline, make the built-in data,
//! reproduce the paper's experiments.
//!
//! Results go to stdout; progress and errors to stderr. Any error exits non-zero with one
//! line naming the problem.

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use pficp::board::BoardClient;
use pficp::cli::{Inputs, Provenance, RegisterReport, Settings};
use pficp::cloud::Cloud;
use pficp::datasets::{self, ModelId, Sampling, ScanSpec};
use pficp::geometry::ScaleBounds;
use pficp::io::{format_from_path, read_cloud, write_cloud};
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::init::InitMode;
use pficp::pf_icp::PfIcpSettings;
use pficp::progress::{self, note, Progress};
use pficp::registration::methods::Method;
use pficp::request::{BoardProgress, BoardRun, Engine, Registered, Request};
use pficp_fpga::messages::Identity;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(name = "pficp", version, about = "PF-ICP point-cloud registration (particle filter + ICP + k-means)")]
struct Cli {
    /// No progress bars or progress lines on stderr (errors and warnings still print).
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Register built-in model-1 twice: the paper's scan (the model's own points under the
    /// Table 1 transform) and a realistic one (independently sampled, partial, noisy), with
    /// PF-ICP and plain ICP against the truth, and PF-ICP's one-sigma uncertainty.
    #[command(after_help = "Example:\n  pficp demo")]
    Demo(DemoArgs),
    /// Register a scan to a model: the pose maps scan to model, d = s R m + T.
    #[command(after_help = "Example:\n  pficp register --model part.ply --scan scan.pcd --json > pose.json")]
    Register(RegisterArgs),
    /// Write a built-in model, its scan and the truth pose to files.
    #[command(after_help = "Example:\n  pficp gen --model model-2 --out-dir data --sampling independent --noise 0.1")]
    Gen(GenArgs),
    /// Reproduce the paper's Tables 2 to 7, the success rates and the figures, or run the
    /// realistic benchmark.
    #[command(after_help = "Example:\n  pficp eval --suite realistic --quick --out eval-out")]
    Eval(EvalArgs),
    /// Time one PF-ICP registration per stage (model-1, 2,000 + 2,000 points, K = 100,
    /// 50 particles, 50 iterations; --large: 200,000 + 100,000); build with --release.
    #[command(after_help = "Example:\n  pficp bench --runs 7\n  pficp bench --large --runs 3")]
    Bench(BenchArgs),
    /// Talk to the board over its serial port.
    #[command(subcommand)]
    Board(BoardCommand),
}

#[derive(Subcommand)]
enum BoardCommand {
    /// Print the board's Identify reply: protocol version, limits, clock, baud, sizes.
    #[command(after_help = "Example:\n  pficp board info --port /dev/ttyUSB0")]
    Info(BoardInfoArgs),
}

#[derive(clap::Args)]
struct LinkArgs {
    /// Serial line baud rate (the board's is set when it is generated) [default: the rate the
    /// board answers Identify at, trying 3000000, 921600, then 115200].
    #[arg(long)]
    baud: Option<u32>,
    /// Time allowed per reply in milliseconds (plus the board's modelled transfer and compute time).
    #[arg(long, default_value_t = pficp::board::DEFAULT_TIMEOUT.as_millis() as u64)]
    timeout_ms: u64,
}

impl LinkArgs {
    /// Open the port and identify the board (at --baud, or at the rate it answers).
    fn connect(&self, port: &str) -> Result<(BoardClient, Identity)> {
        use pficp::board::{MAX_BAUD, MAX_TIMEOUT, MIN_BAUD};
        if self.timeout_ms == 0 || self.timeout_ms > MAX_TIMEOUT.as_millis() as u64 {
            bail!("--timeout-ms {}: must be 1 to {}", self.timeout_ms, MAX_TIMEOUT.as_millis());
        }
        if let Some(baud) = self.baud.filter(|b| !(MIN_BAUD..=MAX_BAUD).contains(b)) {
            bail!("--baud {baud}: the client runs {MIN_BAUD} to {MAX_BAUD} baud");
        }
        Ok(BoardClient::connect(port, self.baud, Duration::from_millis(self.timeout_ms))?)
    }
}

#[derive(clap::Args)]
struct BoardInfoArgs {
    /// The board's serial port (e.g. /dev/ttyUSB0).
    #[arg(long)]
    port: String,
    #[command(flatten)]
    link: LinkArgs,
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodArg {
    PfIcp,
    Icp,
    Welsch,
    Cauchy,
    SparseIcp,
    EmIcp,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Method {
        match m {
            MethodArg::PfIcp => Method::PfIcp,
            MethodArg::Icp => Method::Icp,
            MethodArg::Welsch => Method::Welsch,
            MethodArg::Cauchy => Method::Cauchy,
            MethodArg::SparseIcp => Method::SparseIcp,
            MethodArg::EmIcp => Method::EmIcp,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum InitArg {
    Auto,
    Index,
    Nearest,
}

impl From<InitMode> for InitArg {
    fn from(m: InitMode) -> InitArg {
        match m {
            InitMode::Auto => InitArg::Auto,
            InitMode::Index => InitArg::Index,
            InitMode::Nearest => InitArg::Nearest,
        }
    }
}

#[derive(clap::Args)]
struct PfArgs {
    /// Clusters K per cloud (PF-ICP).
    #[arg(long, default_value_t = PfIcpSettings::default().clusters)]
    clusters: usize,
    /// Particles (PF-ICP).
    #[arg(long, default_value_t = PfIcpSettings::default().particles)]
    particles: usize,
    /// Iteration cap (the filter's for PF-ICP, the method's own otherwise).
    #[arg(long, default_value_t = PfIcpSettings::default().iterations)]
    iterations: usize,
    /// Seed of every random choice.
    #[arg(long, default_value_t = PfIcpSettings::default().seed)]
    seed: u64,
    /// Cluster pairing for PF-ICP's start: index (scan = model's points in order),
    /// nearest (independent scan) or auto (try both).
    #[arg(long, value_enum, default_value_t = InitArg::from(PfIcpSettings::default().init))]
    init: InitArg,
    /// The scale (scan to model) when it is known: 1 when model and scan share their units
    /// (a metric depth camera and a model in the same units). Nothing then changes it.
    #[arg(long, value_name = "S", conflicts_with = "scale_range", allow_hyphen_values = true)]
    scale: Option<f64>,
    /// Bounds on the scale (scan to model): every estimate stays within LO to HI.
    #[arg(long, value_name = "LO,HI", value_delimiter = ',', num_args = 1, allow_hyphen_values = true)]
    scale_range: Vec<f64>,
    /// Where the sensor was, in the scan's coordinates (a depth camera's scans: the origin,
    /// 0,0,0): model surface that would face it inside the scan's view but has no scan point
    /// near it counts against a pose.
    #[arg(long, value_name = "X,Y,Z", value_delimiter = ',', num_args = 1, allow_hyphen_values = true)]
    viewpoint: Vec<f64>,
}

impl PfArgs {
    fn settings(&self) -> Result<PfIcpSettings> {
        if self.particles == 0 {
            bail!("--particles must be at least 1");
        }
        if self.iterations == 0 {
            bail!("--iterations must be at least 1");
        }
        if self.clusters == 0 {
            bail!("--clusters must be at least 1");
        }
        use pficp::pf_icp::{MAX_CLUSTERS, MAX_FILTER_PARTICLES, MAX_ITERATIONS};
        for (flag, value, limit) in [
            ("--particles", self.particles, MAX_FILTER_PARTICLES),
            ("--iterations", self.iterations, MAX_ITERATIONS),
            ("--clusters", self.clusters, MAX_CLUSTERS),
        ] {
            if value > limit {
                bail!("{flag} must be at most {limit} (got {value})");
            }
        }
        let scale = match (self.scale, self.scale_range.as_slice()) {
            (Some(s), _) => {
                if !(s.is_finite() && s > 0.0) {
                    bail!("--scale must be a positive finite number (got {s})");
                }
                ScaleBounds::fixed(s)
            }
            (None, []) => ScaleBounds::FREE,
            (None, &[lo, hi]) => {
                if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > 0.0) {
                    bail!("--scale-range takes two positive finite numbers LO,HI (got {lo},{hi})");
                }
                if lo > hi {
                    bail!("--scale-range LO,HI needs LO <= HI (got {lo},{hi})");
                }
                ScaleBounds::range(lo, hi)
            }
            (None, v) => bail!("--scale-range takes two numbers LO,HI (got {})", v.len()),
        };
        let viewpoint = match self.viewpoint.as_slice() {
            [] => None,
            &[x, y, z] => {
                if ![x, y, z].iter().all(|v| v.is_finite()) {
                    bail!("--viewpoint takes three finite numbers X,Y,Z (got {x},{y},{z})");
                }
                Some(nalgebra::Point3::new(x, y, z))
            }
            v => bail!("--viewpoint takes three numbers X,Y,Z (got {})", v.len()),
        };
        Ok(PfIcpSettings {
            clusters: self.clusters,
            particles: self.particles,
            iterations: self.iterations,
            seed: self.seed,
            init: match self.init {
                InitArg::Auto => InitMode::Auto,
                InitArg::Index => InitMode::Index,
                InitArg::Nearest => InitMode::Nearest,
            },
            scale,
            viewpoint,
            ..Default::default()
        })
    }
}

#[derive(clap::Args)]
struct RegisterArgs {
    /// Model cloud D (PLY, PCD, XYZ or CSV).
    #[arg(long)]
    model: PathBuf,
    /// Scan cloud M (PLY, PCD, XYZ or CSV).
    #[arg(long)]
    scan: PathBuf,
    /// Registration method.
    #[arg(long, value_enum, default_value_t = MethodArg::PfIcp)]
    method: MethodArg,
    #[command(flatten)]
    pf: PfArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Write the scan, transformed into the model frame, to this file.
    #[arg(long)]
    out_aligned: Option<PathBuf>,
    /// Run PF-ICP's particle filter on the board at this serial port (PF-ICP only): the
    /// start, covariance and polish on the host, the filter on the board.
    #[arg(long, value_name = "PORT")]
    board: Option<String>,
    /// With --board: the host runs the filter and the board only weighs each iteration's
    /// particles (the mode of protocol version 1 boards).
    #[arg(long)]
    host_driven: bool,
    /// With --board: scan points the on-board filter weighs each particle over [default: 300].
    #[arg(long, value_name = "N")]
    board_points: Option<usize>,
    #[command(flatten)]
    link: LinkArgs,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModelArg {
    #[value(name = "model-1")]
    Model1,
    #[value(name = "model-2")]
    Model2,
    #[value(name = "model-3")]
    Model3,
}

impl From<ModelArg> for ModelId {
    fn from(m: ModelArg) -> ModelId {
        match m {
            ModelArg::Model1 => ModelId::Model1,
            ModelArg::Model2 => ModelId::Model2,
            ModelArg::Model3 => ModelId::Model3,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum SamplingArg {
    /// The model's own points, same order (the paper's setting).
    Paper,
    /// Sampled independently from the same surface.
    Independent,
    /// Thin, uneven sampling (Table 7).
    Thin,
}

#[derive(clap::Args)]
struct GenArgs {
    /// Which built-in model.
    #[arg(long, value_enum)]
    model: ModelArg,
    /// Folder for <model>.ply, <model>-scan.ply and <model>-truth.json.
    #[arg(long)]
    out_dir: PathBuf,
    /// Model points.
    #[arg(long, default_value_t = 2000)]
    points: usize,
    /// Scan sampling.
    #[arg(long, value_enum, default_value_t = SamplingArg::Paper)]
    sampling: SamplingArg,
    /// Scan points (independent and thin sampling).
    #[arg(long, default_value_t = 2000)]
    scan_points: usize,
    /// Noise amplitude: U(0, noise) added to every scan coordinate.
    #[arg(long, default_value_t = 0.0)]
    noise: f64,
    /// Use a random transform (angles +-45 deg, scale 0.7..1.3) instead of Table 1's.
    #[arg(long)]
    random_transform: bool,
    /// Seed for sampling, noise and the random transform.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// File format: ply, pcd, xyz or csv (ply and pcd are written binary).
    #[arg(long, default_value = "ply")]
    format: String,
}

#[derive(clap::Args)]
struct EvalArgs {
    /// Folder for the figures and results.json.
    #[arg(long, default_value = "eval-out")]
    out: PathBuf,
    /// Random transforms per model for the success rates.
    #[arg(long, default_value_t = 100)]
    trials: usize,
    /// Model points.
    #[arg(long, default_value_t = 2000)]
    points: usize,
    /// Scan points of the independent scans.
    #[arg(long, default_value_t = 2000)]
    scan_points: usize,
    /// Seed of the random transforms.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Skip the success rates (the slow part).
    #[arg(long)]
    no_success: bool,
    /// Which experiments: the paper's (Tables 2 to 7, success rates, figures) or the
    /// realistic benchmark (real and synthetic near-symmetric shapes, partial views,
    /// noise, outliers; writes realistic.json).
    #[arg(long, value_enum, default_value_t = SuiteArg::Paper)]
    suite: SuiteArg,
    /// Realistic suite: cases per family [default: 100, or 8 with --quick].
    #[arg(long)]
    cases: Option<usize>,
    /// Realistic suite: the quick size (8 cases per family).
    #[arg(long)]
    quick: bool,
    /// Realistic suite: dev (development shapes and seeds, for tuning) or test (every shape,
    /// held-out ones included, other seeds: what is reported).
    #[arg(long, value_enum, default_value_t = SplitArg::Test)]
    split: SplitArg,
    /// Realistic suite: only these families (comma-separated) [default: all].
    #[arg(long, value_enum, value_delimiter = ',')]
    family: Vec<FamilyArg>,
    /// Realistic suite: also run these methods (comma-separated), beside pf-icp.
    #[arg(long, value_enum, value_delimiter = ',')]
    with: Vec<MethodArg>,
    /// Also run PF-ICP with the filter and its polish on the board, the board's part by its
    /// bit-exact reference (what the board computes): columns pf-icp-board (then the
    /// host's polish) and pf-icp-board-filter (the board's pose alone), in the realistic
    /// suite and in the paper suite's success rates.
    #[arg(long)]
    board_reference: bool,
    /// With --board-reference: scan points the on-board filter weighs each particle over
    /// [default: the register command's].
    #[arg(long, requires = "board_reference")]
    board_points: Option<usize>,
    /// Realistic suite: do not tell PF-ICP where the camera was in the camera-view families.
    #[arg(long)]
    without_viewpoint: bool,
    /// Realistic suite: export every case (model, scan, truth, symmetries) to this folder
    /// for the peers' script (tests/peers).
    #[arg(long, value_name = "DIR")]
    export: Option<PathBuf>,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum SuiteArg {
    Paper,
    Realistic,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum FamilyArg {
    Real,
    RealOutliers,
    Parts,
    #[value(name = "hard-180")]
    Hard180,
    Camera,
    CameraAny,
    CameraMetric,
    CameraAnyMetric,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum SplitArg {
    Dev,
    Test,
}

#[derive(clap::Args)]
struct DemoArgs {
    /// Seed of the realistic scan (sampling, view, noise) and of every method.
    #[arg(long, default_value_t = PfIcpSettings::default().seed)]
    seed: u64,
}

/// Most `bench --runs`.
const MAX_BENCH_RUNS: usize = 1000;

#[derive(clap::Args)]
struct BenchArgs {
    /// Repetitions (the median is reported; at most 1000).
    #[arg(long, default_value_t = 5)]
    runs: usize,
    /// Scan sampling: the paper's or an independent scan.
    #[arg(long, value_enum, default_value_t = SamplingArg::Independent)]
    sampling: SamplingArg,
    /// A large registration: 200,000 model points, a 100,000-point independent scan (the
    /// paper's: the model's own 200,000), noise 0.01 (PF-ICP's large-cloud path).
    #[arg(long)]
    large: bool,
}

fn main() {
    let cli = Cli::parse();
    progress::set_quiet(cli.quiet);
    let result = match cli.command {
        Command::Demo(a) => demo(&a),
        Command::Register(a) => register(&a),
        Command::Gen(a) => gen(&a),
        Command::Eval(a) => eval(&a),
        Command::Bench(a) => bench(&a),
        Command::Board(BoardCommand::Info(a)) => board_info(&a),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn load(path: &Path, name: &str) -> Result<Cloud> {
    Ok(read_cloud(path, name)?)
}

fn register(a: &RegisterArgs) -> Result<()> {
    let settings = a.pf.settings()?;
    let method: Method = a.method.into();
    let model = load(&a.model, "model")?;
    let scan = load(&a.scan, "scan")?;
    if let Some(out) = &a.out_aligned {
        format_from_path(out)?;
    }
    if a.board.is_none() && (a.host_driven || a.board_points.is_some()) {
        bail!("--host-driven and --board-points need --board PORT");
    }
    if a.host_driven && a.board_points.is_some() {
        bail!("--board-points sets the on-board filter's scan sample; --host-driven weighs the host's sample");
    }
    let engine = match (&a.board, a.host_driven) {
        (None, _) => Engine::Software,
        (Some(_), true) => Engine::HostDriven,
        (Some(_), false) => Engine::OnBoard {
            board_points: a.board_points.unwrap_or(pficp::board::on_board::DEFAULT_BOARD_POINTS),
            poll: pficp::board::DEFAULT_POLL,
        },
    };
    let request = Request { method, engine, settings };
    request.check(&model, &scan)?;
    // Open the port before the work starts: a missing or silent board fails at once.
    let mut client = match &a.board {
        Some(port) => {
            let (c, id) = a.link.connect(port)?;
            note(format_args!(
                "board on {port}: protocol {}, {} lanes at {} Hz, {} baud",
                id.version, id.lanes, id.clock_hz, id.baud
            ));
            Some(c)
        }
        None => None,
    };
    note(format_args!("registering {} scan points to {} model points with {}", scan.len(), model.len(), method.name()));
    let progress = BoardProgress { on_board: &mut on_board_progress() };
    let Registered { outcome, board } = request.run(&model, &scan, client.as_mut(), progress)?;
    match &board {
        Some(BoardRun::OnBoard(b)) => note(format_args!(
            "board: {} model points{}, {} scan points, {} iterations on the board (best cost {:.3e}), \
             {} Status polls, modelled board time {:.3} s, {} requests, {} resends",
            b.model_points,
            if b.model_subsampled { " (subsampled)" } else { "" },
            b.scan_points,
            b.result.iterations,
            b.cost_msd,
            b.polls,
            b.modelled.as_secs_f64(),
            b.stats.requests,
            b.stats.resends + b.stats.restarts
        )),
        Some(BoardRun::HostDriven(b)) => note(format_args!(
            "board: {} model points{}, {} scan points, {} iterations weighed, {} requests, {} resends",
            b.model_points,
            if b.model_subsampled { " (subsampled)" } else { "" },
            b.scan_points,
            b.iterations,
            b.stats.requests,
            b.stats.resends + b.stats.restarts
        )),
        None => {}
    }
    if let Some(pf) = &outcome.pf {
        let t = &pf.times;
        note(format_args!(
            "stages: clustering {:.3} s, covariance {:.3} s, filter {:.3} s, polish {:.3} s",
            t.clustering.as_secs_f64(),
            t.covariance.as_secs_f64(),
            t.filter.as_secs_f64(),
            t.polish.as_secs_f64()
        ));
    }
    let mut report = RegisterReport::new(method.name(), &outcome.registration, outcome.elapsed.as_secs_f64());
    if let Some(pf) = &outcome.pf {
        report = report.assessed(&pf.conclusion);
    }
    if let (Some(port), Some(run)) = (&a.board, &board) {
        report = report.on_board(port);
        if matches!(run, BoardRun::HostDriven(_)) {
            report = report.host_driven();
        }
    }
    let inputs = Inputs {
        model: a.model.display().to_string(),
        scan: a.scan.display().to_string(),
        model_points: model.len(),
        scan_points: scan.len(),
    };
    let recorded = Settings {
        seed: a.pf.seed,
        clusters: a.pf.clusters,
        particles: a.pf.particles,
        iterations: a.pf.iterations,
        init: a.pf.init.to_possible_value().map_or_else(String::new, |v| v.get_name().to_string()),
        scale: request.settings.scale.fixed_value(),
        scale_range: (!request.settings.scale.is_free() && request.settings.scale.fixed_value().is_none())
            .then_some([request.settings.scale.lo, request.settings.scale.hi]),
        viewpoint: request.settings.viewpoint.map(|v| [v.x, v.y, v.z]),
        board_points: match request.engine {
            Engine::OnBoard { board_points, .. } => Some(board_points),
            _ => None,
        },
    };
    report = report.produced_by(Provenance::new(method.name(), inputs, recorded, a.board.as_deref(), a.host_driven));
    if a.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        print!("{}", report.text());
    }
    if let Some(out) = &a.out_aligned {
        let aligned = outcome.registration.pose.apply_all(scan.points());
        write_cloud(out, &aligned, format_from_path(out)?)?;
        note(format_args!("wrote the aligned scan to {}", out.display()));
    }
    Ok(())
}

/// Upload progress on stderr: a bar per store on a terminal, one line per finished store
/// ([`pficp::progress`]).
fn upload_progress() -> impl FnMut(pficp::board::Upload, usize, usize) + Send {
    let mut bar: Option<Progress> = None;
    move |store, done, total| {
        // The model goes with its cell table (protocol 3), counted in data bytes.
        let unit = if store == pficp::board::Upload::Model { "bytes" } else { "points" };
        let b =
            bar.get_or_insert_with(|| Progress::bar(&format!("uploading the {}", store.name()), total as u64, unit));
        b.set(done as u64);
        if done == total {
            if let Some(b) = bar.take() {
                b.finish(format_args!("uploaded the {}: {total} {unit}", store.name()));
            }
        }
    }
}

/// A board registration's progress on stderr (either mode): the uploads as [`upload_progress`],
/// then a bar over the filter's iterations (one line when it is done).
fn on_board_progress() -> impl FnMut(pficp::board::on_board::OnBoardStep, usize, usize) + Send {
    use pficp::board::on_board::OnBoardStep;
    let mut uploads = upload_progress();
    let mut filter: Option<Progress> = None;
    move |step, done, total| match step {
        OnBoardStep::Upload(store) => uploads(store, done, total),
        OnBoardStep::Resident => {
            note(format_args!("the board holds the model already (its digest matches): not uploaded"))
        }
        OnBoardStep::Filter => {
            let b = filter.get_or_insert_with(|| Progress::bar("filter on the board", total as u64, "iterations"));
            b.set(done as u64);
            if done == total {
                if let Some(b) = filter.take() {
                    b.finish("filter on the board: done");
                }
            }
        }
    }
}

fn board_info(a: &BoardInfoArgs) -> Result<()> {
    let (_client, id) = a.link.connect(&a.port)?;
    print!("{}", pficp::board::identity_text(&a.port, &id));
    Ok(())
}

fn gen(a: &GenArgs) -> Result<()> {
    let id: ModelId = a.model.into();
    if a.points < 3 || a.scan_points < 3 {
        bail!("--points and --scan-points must be at least 3");
    }
    let limit = pficp::cloud::MAX_CLOUD_POINTS;
    if a.points > limit || a.scan_points > limit {
        bail!("--points and --scan-points must be at most {limit} (got {} and {})", a.points, a.scan_points);
    }
    if !(a.noise >= 0.0 && a.noise.is_finite()) {
        bail!("--noise must be a finite number >= 0 (got {})", a.noise);
    }
    let ext = match a.format.as_str() {
        "ply" | "pcd" | "xyz" | "csv" => a.format.as_str(),
        other => bail!("unknown --format {other:?}: use ply, pcd, xyz or csv"),
    };
    let truth = if a.random_transform {
        use rand::SeedableRng;
        let diag = pficp::cloud::bbox_diagonal(&id.model_points(a.points));
        datasets::random_truth(&mut rand_chacha::ChaCha8Rng::seed_from_u64(a.seed), 45.0, (0.7, 1.3), diag / 2.0)
    } else {
        id.table1_truth()
    };
    let sampling = match a.sampling {
        SamplingArg::Paper => Sampling::Paper,
        SamplingArg::Independent => Sampling::Independent { points: a.scan_points },
        SamplingArg::Thin => Sampling::Thin { points: a.scan_points },
    };
    let ds = datasets::make(id, a.points, &truth, &ScanSpec { sampling, noise: a.noise, seed: a.seed });
    std::fs::create_dir_all(&a.out_dir).with_context(|| format!("cannot create {}", a.out_dir.display()))?;
    let model_path = a.out_dir.join(format!("{}.{ext}", id.name()));
    let scan_path = a.out_dir.join(format!("{}-scan.{ext}", id.name()));
    let truth_path = a.out_dir.join(format!("{}-truth.json", id.name()));
    write_cloud(&model_path, &ds.model, format_from_path(&model_path)?)?;
    write_cloud(&scan_path, &ds.scan, format_from_path(&scan_path)?)?;
    let json = serde_json::to_string_pretty(&ds.truth.record())?;
    std::fs::write(&truth_path, json + "\n").with_context(|| format!("cannot write {}", truth_path.display()))?;
    for p in [&model_path, &scan_path, &truth_path] {
        println!("{}", p.display());
    }
    Ok(())
}

fn demo(a: &DemoArgs) -> Result<()> {
    let bar = Progress::spinner("registering model-1: the paper's scan and a realistic one");
    let cases = pficp::demo::run(a.seed);
    bar.clear();
    print!("{}", pficp::demo::text(&cases));
    Ok(())
}

fn eval(a: &EvalArgs) -> Result<()> {
    if a.suite == SuiteArg::Realistic {
        return eval_realistic(a);
    }
    let opts = pficp::eval::EvalOptions {
        out_dir: a.out.clone(),
        trials: a.trials,
        model_points: a.points,
        scan_points: a.scan_points,
        seed: a.seed,
        success: !a.no_success,
        board: a.board_reference,
        board_points: board_points(a)?,
        ..Default::default()
    };
    pficp::eval::run(&opts)?;
    Ok(())
}

/// `--board-points`, checked.
fn board_points(a: &EvalArgs) -> Result<usize> {
    let n = a.board_points.unwrap_or(pficp::board::on_board::DEFAULT_BOARD_POINTS);
    if n == 0 || n > pficp::board::BOARD_MAX_STORE_POINTS {
        bail!("--board-points must be 1 to {} (got {n})", pficp::board::BOARD_MAX_STORE_POINTS);
    }
    Ok(n)
}

fn eval_realistic(a: &EvalArgs) -> Result<()> {
    use pficp::eval::realistic::{self, Family, RealisticOptions, Split};
    let cases = a.cases.unwrap_or(if a.quick { 8 } else { 100 });
    if cases == 0 || cases > realistic::MAX_CASES {
        bail!("--cases must be 1 to {} (got {cases})", realistic::MAX_CASES);
    }
    let mut methods = vec![Method::PfIcp];
    methods.extend(a.with.iter().map(|&m| Method::from(m)).filter(|m| *m != Method::PfIcp));
    let opts = RealisticOptions {
        cases,
        seed: a.seed,
        split: if a.split == SplitArg::Dev { Split::Dev } else { Split::Test },
        methods,
        families: if a.family.is_empty() {
            Family::ALL.to_vec()
        } else {
            a.family
                .iter()
                .map(|f| match f {
                    FamilyArg::Real => Family::Real,
                    FamilyArg::RealOutliers => Family::RealOutliers,
                    FamilyArg::Parts => Family::Parts,
                    FamilyArg::Hard180 => Family::Hard180,
                    FamilyArg::Camera => Family::Camera,
                    FamilyArg::CameraAny => Family::CameraAny,
                    FamilyArg::CameraMetric => Family::CameraMetric,
                    FamilyArg::CameraAnyMetric => Family::CameraAnyMetric,
                })
                .collect()
        },
        out_dir: Some(a.out.clone()),
        export: a.export.clone(),
        board: a.board_reference,
        board_points: board_points(a)?,
        viewpoint: !a.without_viewpoint,
        ..Default::default()
    };
    let report = realistic::run(&opts)?;
    print!("{}", report.render());
    note(format_args!("wrote {}", a.out.join("realistic.json").display()));
    Ok(())
}

fn bench(a: &BenchArgs) -> Result<()> {
    if a.runs == 0 || a.runs > MAX_BENCH_RUNS {
        bail!("--runs must be 1 to {MAX_BENCH_RUNS} (got {})", a.runs);
    }
    if cfg!(debug_assertions) {
        eprintln!("warning: debug build; run `cargo run --release -p pficp-host -- bench` for real figures");
    }
    let id = ModelId::Model1;
    let truth = id.table1_truth();
    let (model_points, scan_points, noise) = if a.large { (200_000, 100_000, 0.01) } else { (2000, 2000, 0.0) };
    let sampling = match a.sampling {
        SamplingArg::Paper => Sampling::Paper,
        _ => Sampling::Independent { points: scan_points },
    };
    let ds = datasets::make(id, model_points, &truth, &ScanSpec { sampling, noise, seed: 1 });
    let settings = PfIcpSettings::default();
    println!(
        "bench: model-1, {} model points, {} scan points, K = {}, {} particles, {} iterations, {} threads",
        ds.model.len(),
        ds.scan.len(),
        settings.clusters,
        settings.particles,
        settings.iterations,
        rayon::current_num_threads()
    );
    let mut rows: Vec<[f64; 5]> = Vec::new();
    let bar = Progress::bar("bench", a.runs as u64, "runs");
    for run in 0..a.runs {
        let start = Instant::now();
        let nn = NearestNeighbours::new(&ds.model);
        let r = pficp::pf_icp::register(&nn, &ds.scan, &PfIcpSettings { seed: run as u64 + 1, ..settings.clone() });
        let total = start.elapsed().as_secs_f64();
        let t = r.times;
        let row = [
            t.clustering.as_secs_f64(),
            t.covariance.as_secs_f64(),
            t.filter.as_secs_f64(),
            t.polish.as_secs_f64(),
            total,
        ];
        bar.println(format_args!(
            "run {}: total {:.3} s, rotation error {:.3} deg, scale error {:.4}%",
            run + 1,
            total,
            r.registration.pose.rotation_angle_to(&truth).to_degrees(),
            100.0 * (r.registration.pose.scale / truth.scale - 1.0)
        ));
        bar.inc();
        rows.push(row);
    }
    bar.clear();
    let median = |i: usize| {
        let mut v: Vec<f64> = rows.iter().map(|r| r[i]).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!("median of {} runs [s]: clustering {:.3}, covariance {:.3}, filter {:.3}, polish {:.3}, whole registration {:.3}", a.runs, median(0), median(1), median(2), median(3), median(4));
    Ok(())
}
