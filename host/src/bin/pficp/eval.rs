//! `pficp eval` (the paper's experiments, the realistic benchmark) and `pficp bench`.

use crate::args::*;
use anyhow::{bail, Result};
use pficp::datasets::{self, ModelId, Sampling, ScanSpec};
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::PfIcpSettings;
use pficp::progress::{note, Progress};
use pficp::registration::methods::Method;
use std::time::Instant;

pub(crate) fn eval(a: &EvalArgs) -> Result<()> {
    match a.suite {
        SuiteArg::Realistic => return eval_realistic(a),
        SuiteArg::Tracking => return eval_tracking(a),
        SuiteArg::Paper => {}
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
pub(crate) fn board_points(a: &EvalArgs) -> Result<usize> {
    let n = a.board_points.unwrap_or(pficp::board::on_board::DEFAULT_BOARD_POINTS);
    if n == 0 || n > pficp::board::BOARD_MAX_STORE_POINTS {
        bail!("--board-points must be 1 to {} (got {n})", pficp::board::BOARD_MAX_STORE_POINTS);
    }
    Ok(n)
}

pub(crate) fn eval_tracking(a: &EvalArgs) -> Result<()> {
    use pficp::eval::realistic::Split;
    use pficp::eval::tracking::{self, TrackingOptions};
    let opts = TrackingOptions {
        seed: a.seed,
        split: if a.split == SplitArg::Dev { Split::Dev } else { Split::Test },
        sequences: a.sequences.unwrap_or(if a.quick { 2 } else { 4 }),
        frames: a.frames.unwrap_or(if a.quick { 200 } else { tracking::sequence::FRAMES }),
        metric: !a.unknown_scale,
        board: a.board_reference,
        compare_register: a.compare_register,
        out_dir: Some(a.out.clone()),
        ..Default::default()
    };
    let report = tracking::run(&opts)?;
    print!("{}", report.text());
    note(format_args!(
        "wrote {}, {} and {}",
        a.out.join("tracking.json").display(),
        a.out.join("tracking.svg").display(),
        a.out.join("tracking.png").display()
    ));
    Ok(())
}

pub(crate) fn eval_realistic(a: &EvalArgs) -> Result<()> {
    use pficp::eval::realistic::{self, Family, RealisticOptions, Split};
    let cases = a.cases.unwrap_or(if a.quick { 8 } else { 100 });
    if cases == 0 || cases > realistic::MAX_CASES {
        bail!("--cases must be 1 to {} (got {cases})", realistic::MAX_CASES);
    }
    let mut methods = vec![Method::PfIcp];
    methods.extend(a.with.iter().copied().filter(|m| *m != Method::PfIcp));
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

pub(crate) fn bench(a: &BenchArgs) -> Result<()> {
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
