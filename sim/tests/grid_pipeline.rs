//! The Verilated grid pipeline (`GridPipeline<P>`) in lockstep with `GridPipelineModel`,
//! every output port every clock (`GridLockstep`), on random cases: models in the cube
//! (clumps on cell boundaries, points at `+1`), poses that put scan points outside it (and
//! saturating ones), gaps in the scan stream, particles back to back, model and table
//! rewrites between particles, and writes during a particle (read-first collisions with the
//! table reads and the sweep). Each result also equals the capped search
//! (`evaluate_grid`) when nothing was written during the particle. The seed comes from
//! `PFICP_COSIM_SEED` (default 1), the number of cases from `PFICP_GRID_CASES` (default 60).

use pficp_fpga::format::{FxPoint, FxPose};
use pficp_fpga::grid::{Grid, CELL_LSBS};
use pficp_fpga::grid_pipeline::evaluate_grid;
use pficp_sim::{verilated_lanes, GridLockstep};

mod support;

use support::Rng;

/// A coordinate in `lo..=hi`.
fn between(r: &mut Rng, lo: i64, hi: i64) -> i16 {
    (lo + r.below((hi - lo + 1) as u64) as i64) as i16
}

/// A model coordinate in the cube: anywhere, near a cell boundary, or exactly +-1.
fn inside(r: &mut Rng) -> i16 {
    match r.below(8) {
        0 => {
            if r.below(2) == 0 {
                -8192
            } else {
                8192
            }
        }
        1 | 2 => {
            let k = r.below(17) as i64;
            (-8192 + k * CELL_LSBS as i64 + between(r, -3, 3) as i64).clamp(-8192, 8192) as i16
        }
        _ => between(r, -8192, 8192),
    }
}

/// A model: a uniform cloud, or a few clumps (dense cells, many empty rows).
fn random_model(r: &mut Rng) -> Vec<FxPoint> {
    let size = [8, 60, 400, 1500][r.below(4) as usize];
    let n = 1 + r.below(size) as usize;
    if r.below(2) == 0 {
        (0..n).map(|_| [inside(r), inside(r), inside(r)]).collect()
    } else {
        let centres: Vec<FxPoint> = (0..1 + r.below(5)).map(|_| [inside(r), inside(r), inside(r)]).collect();
        (0..n)
            .map(|k| centres[k % centres.len()].map(|v| (v as i64 + r.coord(1500) as i64).clamp(-8192, 8192) as i16))
            .collect()
    }
}

fn random_scan(r: &mut Rng) -> Vec<FxPoint> {
    let size = [5, 40, 120][r.below(3) as usize];
    let n = 1 + r.below(size) as usize;
    let range = [2000, 6000, 8192][r.below(3) as usize];
    (0..n).map(|_| [r.coord(range), r.coord(range), r.coord(range)]).collect()
}

/// A rotation about `y` and a translation of up to 1.5 (points leave the cube), or now and
/// then anything the 18-bit fields hold (the transform saturates).
fn random_pose(r: &mut Rng) -> FxPose {
    if r.below(12) == 0 {
        let max = (1i64 << 17) - 1;
        let m = [0; 9].map(|_| between(r, -max - 1, max) as i32);
        let t = [0; 3].map(|_| between(r, -max - 1, max) as i32);
        return FxPose { m, t };
    }
    let a = r.uniform(0.0, std::f64::consts::TAU);
    let t = [0; 3].map(|_| r.uniform(-1.5, 1.5));
    let (s, c) = a.sin_cos();
    FxPose::from_f64(&[c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c], &t)
}

#[test]
fn random_cases_in_lockstep() {
    let seed: u64 = std::env::var("PFICP_COSIM_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let cases: usize = std::env::var("PFICP_GRID_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(60);
    let mut rng = Rng::new(seed);
    let mut compared = 0;
    for lanes in verilated_lanes() {
        let mut ls = GridLockstep::new(lanes);
        for case in 0..cases {
            let ctx = format!("seed {seed} case {case} P = {lanes}");
            let grid = Grid::build(&random_model(&mut rng)).unwrap();
            ls.upload(&grid).unwrap_or_else(|m| panic!("{ctx}: {m}"));
            // Back to back particles on this model, with and without gaps.
            for k in 0..1 + rng.below(3) {
                let (scan, pose) = (random_scan(&mut rng), random_pose(&mut rng));
                let gaps = rng.below(3);
                let (got, _) = ls
                    .particle(&scan, &pose, |c| gaps > 0 && c % (gaps + 1) == 1, |_, _| {})
                    .unwrap_or_else(|m| panic!("{ctx} particle {k}: {m}"));
                assert_eq!(got, evaluate_grid(&grid, &scan, &pose), "{ctx} particle {k}");
            }
            // Now and then, writes during a particle: rubbish model words and table entries
            // (any address, the out-of-range ones included); the answer changes, the lockstep
            // still holds.
            if rng.below(4) == 0 {
                let (scan, pose) = (random_scan(&mut rng), random_pose(&mut rng));
                let mut r2 = Rng::new(rng.next());
                ls.particle(
                    &scan,
                    &pose,
                    |_| false,
                    |_, i| {
                        if r2.below(4) == 0 {
                            i.model_we = true;
                            i.model_waddr = r2.below(1 << 12) as u16;
                            i.model_wdata = r2.next();
                        }
                        if r2.below(4) == 0 {
                            i.table_we = true;
                            i.table_waddr = r2.below(1 << 13) as u16;
                            // (Small entries: rows stay short, the sweep quick.)
                            i.table_wdata = r2.below(1 << 6) as u16;
                        }
                    },
                )
                .unwrap_or_else(|m| panic!("{ctx} (writes during the particle): {m}"));
            }
        }
        compared += ls.clocks_compared();
    }
    eprintln!("grid pipeline: {compared} clocks compared in lockstep, seed {seed}");
}
