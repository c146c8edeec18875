//! The neighbour pipeline on the paper's models 1 to 3 as the host quantises them (2,000
//! model points): the Verilated `NeighbourPipeline<16>` in lockstep with its cycle model on
//! every clock, each result the capped search; and the figures (docs/pipeline.md, "The
//! neighbour pipeline"): clocks per particle, distances a clock and lane use, against the
//! brute-force pipeline's count, with the scan in random order and Morton-sorted.
//! `cargo test --release -p pficp-tests --test neighbour_pipeline_models -- --nocapture`

use pficp::board::quantise::{normalised_pose, quantise_pose, Normalisation};
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::geometry::Pose;
use pficp_fpga::common::format::{transform, FxPoint, FxPose};
use pficp_fpga::search::grid::{cell_of, evaluate_grid, Grid};
use pficp_fpga::search::neighbour_pipeline::{chunks_of, clocks_bound, clocks_per_particle, lookups_of};
use pficp_fpga::search::pipeline;
use pficp_sim::NeighbourLockstep;

const LANES: usize = 16;

/// Model `id` (2,000 points) and `n` scan points as the host quantises them, with the pose
/// at the truth and 5 deg and 0.05 off it.
fn case(id: ModelId, n: usize) -> (Grid, Vec<FxPoint>, [FxPose; 2]) {
    let truth = id.table1_truth();
    let ds = make(id, 2000, &truth, &ScanSpec { sampling: Sampling::Independent { points: n }, noise: 0.0, seed: 3 });
    let (nm, nd) = (Normalisation::of(&ds.scan), Normalisation::of(&ds.model));
    let (scan_q, model_q) = (nm.quantise(&ds.scan), nd.quantise(&ds.model));
    let grid = Grid::build(&model_q).unwrap_or_else(|e| panic!("{}: {e}", id.name()));
    let poses = [[0.0; 7], [0.05, 0.0, 0.0, 0.0, 0.087, 0.0, 0.0]].map(|offset| {
        let mut p = truth.to_params();
        for (x, d) in p.iter_mut().zip(offset) {
            *x += d;
        }
        quantise_pose(&normalised_pose(&Pose::from_params(&p), &nm, &nd))
    });
    (grid, scan_q, poses)
}

/// The scan sorted by the Morton (Z-order) key of its cell under `pose` (clipped to the grid).
fn sorted_by_morton(scan: &[FxPoint], pose: &FxPose) -> Vec<FxPoint> {
    let mut s = scan.to_vec();
    s.sort_by_key(|&p| {
        let k = cell_of(transform(pose, p)).map(|c| c.clamp(0, 15) as u32);
        (0..4).map(|b| ((k[0] >> b & 1) | (k[1] >> b & 1) << 1 | (k[2] >> b & 1) << 2) << (3 * b)).sum::<u32>()
    });
    s
}

/// A deterministic shuffle.
fn shuffled(scan: &[FxPoint]) -> Vec<FxPoint> {
    let mut s = scan.to_vec();
    let mut x = 0x2545_f491_4f6c_dd1du64;
    for i in (1..s.len()).rev() {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        s.swap(i, (x % (i as u64 + 1)) as usize);
    }
    s
}

#[test]
fn models_in_lockstep_at_16_lanes() {
    let mut ls = NeighbourLockstep::new(LANES);
    for id in ModelId::ALL {
        let (grid, scan, poses) = case(id, 300);
        ls.upload(&grid).unwrap_or_else(|m| panic!("{}: {m}", id.name()));
        for (k, pose) in poses.iter().enumerate() {
            for (order, s) in [("random", shuffled(&scan)), ("Morton", sorted_by_morton(&scan, &poses[0]))] {
                let (got, clocks) = ls
                    .particle(&s, pose, |c| k == 1 && c % 7 == 0, |_, _| {})
                    .unwrap_or_else(|m| panic!("{} pose {k} {order}: {m}", id.name()));
                assert_eq!(got, evaluate_grid(&grid, &s, pose), "{} pose {k} {order}", id.name());
                if k == 0 {
                    assert_eq!(clocks, clocks_per_particle(&grid, &s, pose, LANES).clocks);
                }
            }
        }
    }
    eprintln!("models 1-3: {} clocks compared in lockstep (P = 16)", ls.clocks_compared());
}

#[test]
fn figures() {
    eprintln!("P = {LANES} a side (A and B lanes); clocks from start to cost_valid, no gaps in the scan stream");
    eprintln!(
        "| model | N_S | pose | order | clocks | clocks/point | chunks/point | lookups/point | brute force | distances/clock | lane use | bound |"
    );
    eprintln!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for n in [300, 1000] {
        for id in ModelId::ALL {
            let (grid, scan, poses) = case(id, n);
            let brute = pipeline::clocks_per_particle(n, grid.points.len(), LANES);
            for (pose_name, pose) in [("truth", &poses[0]), ("off", &poses[1])] {
                let morton = sorted_by_morton(&scan, &poses[0]);
                for (order, s) in [("random", shuffled(&scan)), ("Morton", morton.clone())] {
                    let r = clocks_per_particle(&grid, &s, pose, LANES);
                    assert_eq!(r.evaluation, evaluate_grid(&grid, &s, pose));
                    let chunks: usize = s.iter().map(|&p| chunks_of(&grid, transform(pose, p), LANES)).sum();
                    let lookups: usize = s.iter().map(|&p| lookups_of(transform(pose, p))).sum();
                    let per_clock = r.distances as f64 / r.clocks as f64;
                    let bound = clocks_bound(n, grid.points.len(), LANES);
                    eprintln!(
                        "| {} | {n} | {pose_name} | {order} | {} | {:.2} | {:.2} | {:.2} | {brute} | {:.2} | {:.1}% | {bound} |",
                        id.name(),
                        r.clocks,
                        r.clocks as f64 / n as f64,
                        chunks as f64 / n as f64,
                        lookups as f64 / n as f64,
                        per_clock,
                        100.0 * r.distances as f64 / (r.chunks as f64 * 2.0 * LANES as f64),
                    );
                    assert!(r.clocks <= bound);
                    assert!(r.clocks as usize >= chunks.max(lookups));
                }
            }
        }
    }
}
