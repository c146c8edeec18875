//! `pficp`: register point clouds with PF-ICP or a baseline, make the built-in data,
//! reproduce the paper's experiments.
//!
//! Results go to stdout; progress and errors to stderr. Any error exits non-zero with one
//! line naming the problem.

mod args;
mod eval;
mod register;
mod track;

use anyhow::{bail, Context, Result};
use args::*;
use clap::Parser;
use pficp::cloud::Cloud;
use pficp::datasets::{self, ModelId, Sampling, ScanSpec};
use pficp::io::{format_from_path, read_cloud, write_cloud};
use pficp::progress::{self, Progress};
use std::path::Path;

fn main() {
    let cli = Cli::parse();
    progress::set_quiet(cli.quiet);
    let result = match cli.command {
        Command::Demo(a) => demo(&a),
        Command::Register(a) => register::register(&a),
        Command::Track(a) => track::track(&a),
        Command::Gen(a) => gen(&a),
        Command::Eval(a) => eval::eval(&a),
        Command::Bench(a) => eval::bench(&a),
        Command::Board(BoardCommand::Info(a)) => board_info(&a),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

pub(crate) fn load(path: &Path, name: &str) -> Result<Cloud> {
    Ok(read_cloud(path, name)?)
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
