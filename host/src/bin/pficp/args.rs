//! The command line: subcommands and their flags (clap).

use anyhow::Result;
use clap::{Parser, Subcommand, ValueEnum};
use pficp::board::BoardClient;
use pficp::datasets::ModelId;
use pficp::pf_icp::init::InitMode;
use pficp::pf_icp::PfIcpSettings;
use pficp::registration::methods::Method;
use pficp::request::PfIcpOptions;
use pficp_fpga::protocol::messages::Identity;
use std::path::PathBuf;

#[derive(Parser)]
#[command(name = "pficp", version, about = "PF-ICP point-cloud registration (particle filter + ICP + k-means)")]
pub(crate) struct Cli {
    /// No progress bars or progress lines on stderr (errors and warnings still print).
    #[arg(long, short, global = true)]
    pub(crate) quiet: bool,
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
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
    /// Track a moving part: register every scan of a sequence to the model, each frame from
    /// the last (`acquiring`, `tracking`, `lost`, `reacquired`), one line a frame.
    #[command(
        after_help = "Example:\n  pficp track --model part.ply --scans frames/ --json\n  camera-driver | pficp track --model part.ply --scans - --scale 1 --json"
    )]
    Track(TrackArgs),
    /// Reproduce the paper's Tables 2 to 7, the success rates and the figures, or run the
    /// realistic or the tracking benchmark.
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
pub(crate) enum BoardCommand {
    /// Print the board's Identify reply: protocol version, limits, clock, baud, sizes.
    #[command(after_help = "Example:\n  pficp board info --port /dev/ttyUSB0")]
    Info(BoardInfoArgs),
}

#[derive(clap::Args)]
pub(crate) struct LinkArgs {
    /// Serial line baud rate (the board's is set when it is generated) [default: the rate the
    /// board answers Identify at, trying 3000000, 921600, then 115200].
    #[arg(long)]
    pub(crate) baud: Option<u32>,
    /// Time allowed per reply in milliseconds (plus the board's modelled transfer and compute time).
    #[arg(long, default_value_t = pficp::board::DEFAULT_TIMEOUT.as_millis() as u64)]
    pub(crate) timeout_ms: u64,
}

impl LinkArgs {
    /// Open the port and identify the board (at --baud, or at the rate it answers).
    pub(crate) fn connect(&self, port: &str) -> Result<(BoardClient, Identity)> {
        BoardClient::connect_with(port, self.baud, self.timeout_ms)
    }

    /// [`Self::connect`], saying on stderr what answered (the commands that work with the
    /// board open its port before their work starts: a missing or silent board fails at
    /// once).
    pub(crate) fn open(&self, port: &str) -> Result<BoardClient> {
        let (client, id) = self.connect(port)?;
        pficp::progress::note(format_args!(
            "board on {port}: protocol {}, {} lanes at {} Hz, {} baud",
            id.version, id.lanes, id.clock_hz, id.baud
        ));
        Ok(client)
    }
}

#[derive(clap::Args)]
pub(crate) struct BoardInfoArgs {
    /// The board's serial port (e.g. /dev/ttyUSB0).
    #[arg(long)]
    pub(crate) port: String,
    #[command(flatten)]
    pub(crate) link: LinkArgs,
}

/// `--method`: the library's method names ([`Method::name`]), listed in the help.
fn method_parser() -> impl clap::builder::TypedValueParser<Value = Method> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(Method::ALL.map(Method::name))
        .map(|s| Method::parse(&s).expect("one of the listed names"))
}

/// `--init`: the library's pairing names ([`InitMode::name`]).
fn init_parser() -> impl clap::builder::TypedValueParser<Value = InitMode> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(InitMode::ALL.map(InitMode::name))
        .map(|s| InitMode::parse(&s).expect("one of the listed names"))
}

#[derive(clap::Args)]
pub(crate) struct PfArgs {
    /// Clusters K per cloud (PF-ICP).
    #[arg(long, default_value_t = PfIcpSettings::default().clusters)]
    pub(crate) clusters: usize,
    /// Particles (PF-ICP).
    #[arg(long, default_value_t = PfIcpSettings::default().particles)]
    pub(crate) particles: usize,
    /// Iteration cap (the filter's for PF-ICP, the method's own otherwise).
    #[arg(long, default_value_t = PfIcpSettings::default().iterations)]
    pub(crate) iterations: usize,
    /// Seed of every random choice.
    #[arg(long, default_value_t = PfIcpSettings::default().seed)]
    pub(crate) seed: u64,
    /// Cluster pairing for PF-ICP's start: index (scan = model's points in order),
    /// nearest (independent scan) or auto (try both).
    #[arg(long, value_parser = init_parser(), default_value_t = PfIcpSettings::default().init)]
    pub(crate) init: InitMode,
    /// The scale (scan to model) when it is known: 1 when model and scan share their units
    /// (a metric depth camera and a model in the same units). Nothing then changes it.
    #[arg(long, value_name = "S", conflicts_with = "scale_range", allow_hyphen_values = true)]
    pub(crate) scale: Option<f64>,
    /// Bounds on the scale (scan to model): every estimate stays within LO to HI.
    #[arg(long, value_name = "LO,HI", value_delimiter = ',', num_args = 1, allow_hyphen_values = true)]
    pub(crate) scale_range: Vec<f64>,
    /// Where the sensor was, in the scan's coordinates (a depth camera's scans: the origin,
    /// 0,0,0): scan points that the model's surface would hide from it count against a pose,
    /// and the search starts from the side of the model it faces.
    #[arg(long, value_name = "X,Y,Z", value_delimiter = ',', num_args = 1, allow_hyphen_values = true)]
    pub(crate) viewpoint: Vec<f64>,
    /// No rescue search: when the evidence rules out the first search's answer, PF-ICP
    /// searches again wider (about twice the time of that registration); without it the
    /// answer stays as found, `unreliable`, in bounded time.
    #[arg(long)]
    pub(crate) no_rescue: bool,
}

impl PfArgs {
    pub(crate) fn settings(&self) -> Result<PfIcpSettings> {
        PfIcpOptions {
            clusters: self.clusters,
            particles: self.particles,
            iterations: self.iterations,
            seed: self.seed,
            init: self.init,
            scale: self.scale,
            scale_range: (!self.scale_range.is_empty()).then(|| self.scale_range.clone()),
            viewpoint: (!self.viewpoint.is_empty()).then(|| self.viewpoint.clone()),
            rescue: !self.no_rescue,
        }
        .settings()
    }
}

#[derive(clap::Args)]
pub(crate) struct RegisterArgs {
    /// Model cloud D (PLY, PCD, XYZ or CSV).
    #[arg(long)]
    pub(crate) model: PathBuf,
    /// Scan cloud M (PLY, PCD, XYZ or CSV).
    #[arg(long)]
    pub(crate) scan: PathBuf,
    /// Registration method.
    #[arg(long, value_parser = method_parser(), default_value_t = Method::PfIcp)]
    pub(crate) method: Method,
    #[command(flatten)]
    pub(crate) pf: PfArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub(crate) json: bool,
    /// Write the scan, transformed into the model frame, to this file.
    #[arg(long)]
    pub(crate) out_aligned: Option<PathBuf>,
    /// Run PF-ICP's particle filter on the board at this serial port (PF-ICP only): the
    /// start, covariance and polish on the host, the filter on the board.
    #[arg(long, value_name = "PORT")]
    pub(crate) board: Option<String>,
    /// With --board: the host runs the filter and the board only weighs each iteration's
    /// particles (the mode of protocol version 1 boards).
    #[arg(long)]
    pub(crate) host_driven: bool,
    /// With --board: scan points the on-board filter weighs each particle over [default: 300].
    #[arg(long, value_name = "N")]
    pub(crate) board_points: Option<usize>,
    #[command(flatten)]
    pub(crate) link: LinkArgs,
}

#[derive(clap::Args)]
pub(crate) struct TrackArgs {
    /// Model cloud (PLY, PCD, XYZ or CSV).
    #[arg(long)]
    pub(crate) model: PathBuf,
    /// The frames: every PLY, PCD, XYZ or CSV file in this folder in name order, or `-`:
    /// frames on standard input, each a block of `x y z` lines ended by an empty line or
    /// the end of the input.
    #[arg(long, value_name = "DIR")]
    pub(crate) scans: PathBuf,
    /// Frames a second: the time between frames, over which the prior's widest spread grows.
    #[arg(long, default_value_t = pficp::tracking::DEFAULT_FPS)]
    pub(crate) fps: f64,
    #[command(flatten)]
    pub(crate) pf: PfArgs,
    /// Print one JSON object a frame, one a line, as soon as the frame is done.
    #[arg(long)]
    pub(crate) json: bool,
    /// Run every tracked frame's filter on the board at this serial port (the model stays
    /// on it; a frame sends its scan sample and a Run from the prediction); the global
    /// registrations stay on the host.
    #[arg(long, value_name = "PORT")]
    pub(crate) board: Option<String>,
    #[command(flatten)]
    pub(crate) link: LinkArgs,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum ModelArg {
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
pub(crate) enum SamplingArg {
    /// The model's own points, same order (the paper's setting).
    Paper,
    /// Sampled independently from the same surface.
    Independent,
    /// Thin, uneven sampling (Table 7).
    Thin,
}

#[derive(clap::Args)]
pub(crate) struct GenArgs {
    /// Which built-in model.
    #[arg(long, value_enum)]
    pub(crate) model: ModelArg,
    /// Folder for <model>.ply, <model>-scan.ply and <model>-truth.json.
    #[arg(long)]
    pub(crate) out_dir: PathBuf,
    /// Model points.
    #[arg(long, default_value_t = 2000)]
    pub(crate) points: usize,
    /// Scan sampling.
    #[arg(long, value_enum, default_value_t = SamplingArg::Paper)]
    pub(crate) sampling: SamplingArg,
    /// Scan points (independent and thin sampling).
    #[arg(long, default_value_t = 2000)]
    pub(crate) scan_points: usize,
    /// Noise amplitude: U(0, noise) added to every scan coordinate.
    #[arg(long, default_value_t = 0.0)]
    pub(crate) noise: f64,
    /// Use a random transform (angles +-45 deg, scale 0.7..1.3) instead of Table 1's.
    #[arg(long)]
    pub(crate) random_transform: bool,
    /// Seed for sampling, noise and the random transform.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// File format: ply, pcd, xyz or csv (ply and pcd are written binary).
    #[arg(long, default_value = "ply")]
    pub(crate) format: String,
}

#[derive(clap::Args)]
pub(crate) struct EvalArgs {
    /// Folder for the figures and results.json.
    #[arg(long, default_value = "eval-out")]
    pub(crate) out: PathBuf,
    /// Random transforms per model for the success rates.
    #[arg(long, default_value_t = 100)]
    pub(crate) trials: usize,
    /// Model points.
    #[arg(long, default_value_t = 2000)]
    pub(crate) points: usize,
    /// Scan points of the independent scans.
    #[arg(long, default_value_t = 2000)]
    pub(crate) scan_points: usize,
    /// Seed of the random transforms.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Skip the success rates (the slow part).
    #[arg(long)]
    pub(crate) no_success: bool,
    /// Which experiments: the paper's (Tables 2 to 7, success rates, figures) or the
    /// realistic benchmark (real and synthetic near-symmetric shapes, partial views,
    /// noise, outliers; writes realistic.json).
    #[arg(long, value_enum, default_value_t = SuiteArg::Paper)]
    pub(crate) suite: SuiteArg,
    /// Realistic suite: cases per family [default: 100, or 8 with --quick].
    #[arg(long)]
    pub(crate) cases: Option<usize>,
    /// Realistic suite: the quick size (8 cases per family).
    #[arg(long)]
    pub(crate) quick: bool,
    /// Realistic suite: dev (development shapes and seeds, for tuning) or test (every shape,
    /// held-out ones included, other seeds: what is reported).
    #[arg(long, value_enum, default_value_t = SplitArg::Test)]
    pub(crate) split: SplitArg,
    /// Realistic suite: only these families (comma-separated) [default: all].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub(crate) family: Vec<FamilyArg>,
    /// Realistic suite: also run these methods (comma-separated), beside pf-icp.
    #[arg(long, value_parser = method_parser(), value_delimiter = ',')]
    pub(crate) with: Vec<Method>,
    /// Also run PF-ICP with the filter and its polish on the board, the board's part by its
    /// bit-exact reference (what the board computes): columns pf-icp-board (then the
    /// host's polish) and pf-icp-board-filter (the board's pose alone), in the realistic
    /// suite and in the paper suite's success rates; in the tracking suite every tracked
    /// frame's filter, with the board's modelled frames a second.
    #[arg(long)]
    pub(crate) board_reference: bool,
    /// With --board-reference: scan points the on-board filter weighs each particle over
    /// [default: the register command's].
    #[arg(long, requires = "board_reference")]
    pub(crate) board_points: Option<usize>,
    /// Realistic suite: do not tell PF-ICP where the camera was in the camera-view families.
    #[arg(long)]
    pub(crate) without_viewpoint: bool,
    /// Tracking suite: sequences (one a shape, at most 4) [default: 4, or 2 with --quick].
    #[arg(long)]
    pub(crate) sequences: Option<usize>,
    /// Tracking suite: frames a sequence (at most 300) [default: 300, or 200 with --quick].
    #[arg(long)]
    pub(crate) frames: Option<usize>,
    /// Tracking suite: each part at a scale of its own, not told to the tracker [default:
    /// scale 1, told as --scale 1].
    #[arg(long)]
    pub(crate) unknown_scale: bool,
    /// Tracking suite: also register every Nth tracked frame's scan from scratch (the whole
    /// PF-ICP), to compare the tracked frames' accuracy with a single registration's on the
    /// same frames [default: 0, none].
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub(crate) compare_register: usize,
    /// Realistic suite: export every case (model, scan, truth, symmetries) to this folder
    /// for the peers' script (tests/peers).
    #[arg(long, value_name = "DIR")]
    pub(crate) export: Option<PathBuf>,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum SuiteArg {
    Paper,
    Realistic,
    Tracking,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum FamilyArg {
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
pub(crate) enum SplitArg {
    Dev,
    Test,
}

#[derive(clap::Args)]
pub(crate) struct DemoArgs {
    /// Seed of the realistic scan (sampling, view, noise) and of every method.
    #[arg(long, default_value_t = PfIcpSettings::default().seed)]
    pub(crate) seed: u64,
}

/// Most `bench --runs`.
pub(crate) const MAX_BENCH_RUNS: usize = 1000;

#[derive(clap::Args)]
pub(crate) struct BenchArgs {
    /// Repetitions (the median is reported; at most 1000).
    #[arg(long, default_value_t = 5)]
    pub(crate) runs: usize,
    /// Scan sampling: the paper's or an independent scan.
    #[arg(long, value_enum, default_value_t = SamplingArg::Independent)]
    pub(crate) sampling: SamplingArg,
    /// A large registration: 200,000 model points, a 100,000-point independent scan (the
    /// paper's: the model's own 200,000), noise 0.01 (PF-ICP's large-cloud path).
    #[arg(long)]
    pub(crate) large: bool,
}
