//! The Verilated neighbour pipeline (`NeighbourPipeline<P>`) in lockstep with
//! `NeighbourPipelineModel`, every output port every clock (`NeighbourLockstep`), at every
//! verilated lane count, on random cases: models in the cube (clumps: dense cells, long rows,
//! many chunks; points on cell boundaries and at `+1`), poses that put scan points outside it
//! (and saturating ones), gaps in the scan stream, particles back to back, model and table
//! rewrites between particles, writes during a particle, and tables of anything (entries up
//! to 8,191: reversed, overlapping and wrapping ranges). Each result also equals the
//! functional reference: `evaluate_grid` with the model's own table, `evaluate_stored` over
//! the stores as written otherwise, and each result's `nn_point` is its scan point
//! transformed (`transform(pose, scan[k])` for the k-th result). Seed `PFICP_COSIM_SEED` (default 1), cases
//! `PFICP_NBR_CASES` (default 40). And the B lanes' table squares at their limits
//! (magnitudes around 2^9 and 2^10), directed.

use pficp_fpga::common::format::{pack_point, transform, FxPoint, FxPose, MAX_POINTS};
use pficp_fpga::search::grid::{evaluate_grid, Grid, CELLS, CELL_LSBS};
use pficp_fpga::search::neighbour_pipeline::{evaluate_stored, GridInputs};
use pficp_sim::{verilated_lanes, NeighbourLockstep};

mod support;

use support::Rng;

fn between(r: &mut Rng, lo: i64, hi: i64) -> i16 {
    (lo + r.below((hi - lo + 1) as u64) as i64) as i16
}

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

fn random_model(r: &mut Rng) -> Vec<FxPoint> {
    let size = [8, 60, 400, 1500][r.below(4) as usize];
    let n = 1 + r.below(size) as usize;
    if r.below(2) == 0 {
        (0..n).map(|_| [inside(r), inside(r), inside(r)]).collect()
    } else {
        let centres: Vec<FxPoint> = (0..1 + r.below(5)).map(|_| [inside(r), inside(r), inside(r)]).collect();
        let spread = [300, 1500][r.below(2) as usize];
        (0..n)
            .map(|k| centres[k % centres.len()].map(|v| (v as i64 + r.coord(spread) as i64).clamp(-8192, 8192) as i16))
            .collect()
    }
}

fn random_scan(r: &mut Rng) -> Vec<FxPoint> {
    let size = [5, 40, 120][r.below(3) as usize];
    let n = 1 + r.below(size) as usize;
    let range = [2000, 6000, 8192][r.below(3) as usize];
    (0..n).map(|_| [r.coord(range), r.coord(range), r.coord(range)]).collect()
}

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

/// The transformed scan points the results must present as `nn_point`, in scan order.
fn transformed(scan: &[FxPoint], pose: &FxPose) -> Vec<FxPoint> {
    scan.iter().map(|&p| transform(pose, p)).collect()
}

#[test]
fn both_lane_counts_are_verilated() {
    assert_eq!(verilated_lanes(), vec![4, 16]);
    println!("{}", pficp_sim::BUILD_REPORT);
}

#[test]
fn random_cases_in_lockstep() {
    let seed: u64 = std::env::var("PFICP_COSIM_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let cases: usize = std::env::var("PFICP_NBR_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(40);
    let mut rng = Rng::new(seed);
    let mut compared = 0;
    for lanes in verilated_lanes() {
        let mut ls = NeighbourLockstep::new(lanes);
        // The model RAM as written (words past a model keep what earlier cases wrote).
        let mut ram = vec![0u64; MAX_POINTS];
        for case in 0..cases {
            let ctx = format!("seed {seed} case {case} P = {lanes}");
            let grid = Grid::build(&random_model(&mut rng)).unwrap();
            ls.upload(&grid).unwrap_or_else(|m| panic!("{ctx}: {m}"));
            for (a, &p) in grid.points.iter().enumerate() {
                ram[a] = pack_point(p);
            }
            let mut first = grid.first.clone();
            // Back to back particles on this model, with and without gaps.
            for k in 0..1 + rng.below(3) {
                let (scan, pose) = (random_scan(&mut rng), random_pose(&mut rng));
                let gaps = rng.below(3);
                let (got, points, _) = ls
                    .particle_with_points(&scan, &pose, |c| gaps > 0 && c % (gaps + 1) == 1, |_, _| {})
                    .unwrap_or_else(|m| panic!("{ctx} particle {k}: {m}"));
                assert_eq!(got, evaluate_grid(&grid, &scan, &pose), "{ctx} particle {k}");
                assert_eq!(points, transformed(&scan, &pose), "{ctx} particle {k}: nn_point");
            }
            // Now and then a table of anything and model words past the model, between
            // particles: the answer is the stored reference's.
            if rng.below(3) == 0 {
                let mut r2 = Rng::new(rng.next());
                for _ in 0..r2.below(300) {
                    let (a, v) = (r2.below(CELLS as u64 + 1) as usize, r2.below(1 << 13) as u16);
                    let v = if r2.below(2) == 0 { v % 64 + first[a] } else { v };
                    ls.step(&GridInputs {
                        table_we: true,
                        table_waddr: a as u16,
                        table_wdata: v,
                        ..Default::default()
                    })
                    .unwrap_or_else(|m| panic!("{ctx} (table): {m}"));
                    first[a] = v & 0x1fff;
                }
                for _ in 0..r2.below(100) {
                    let a = 4095 - r2.below(200) as usize;
                    let w = pack_point([inside(&mut r2), inside(&mut r2), inside(&mut r2)]);
                    ls.step(&GridInputs {
                        model_we: true,
                        model_waddr: a as u16,
                        model_wdata: w,
                        ..Default::default()
                    })
                    .unwrap_or_else(|m| panic!("{ctx} (model): {m}"));
                    ram[a] = w;
                }
                let (scan, pose) = (random_scan(&mut rng), random_pose(&mut rng));
                let (got, points, _) = ls
                    .particle_with_points(&scan, &pose, |c| c % 4 == 3, |_, _| {})
                    .unwrap_or_else(|m| panic!("{ctx} (any table): {m}"));
                assert_eq!(got, evaluate_stored(&ram, &first, &scan, &pose), "{ctx} (any table)");
                assert_eq!(points, transformed(&scan, &pose), "{ctx} (any table): nn_point");
            }
            // Now and then writes during a particle: the lockstep still holds.
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
                            ram[i.model_waddr as usize] = i.model_wdata & ((1 << 48) - 1);
                        }
                        if r2.below(4) == 0 {
                            i.table_we = true;
                            i.table_waddr = r2.below(1 << 13) as u16;
                            i.table_wdata = r2.below(1 << 13) as u16;
                        }
                    },
                )
                .unwrap_or_else(|m| panic!("{ctx} (writes during the particle): {m}"));
            }
        }
        compared += ls.clocks_compared();
    }
    eprintln!("neighbour pipeline: {compared} clocks compared in lockstep, seed {seed}");
}

/// The B lanes square magnitudes `x = 512 t + y < 2^10` from tables of `y^2 >> 2` and call
/// anything larger capped: one model point, queries at every combination of offsets around
/// 2^9 and 2^10 (and small ones) along each axis, so that the point falls in every row of
/// the queries' neighbourhoods (the B rows among them) at those distances; the point sits at
/// three places in its cell. Every port every clock, and each result the capped search.
#[test]
fn b_lane_squares_at_their_limits() {
    let id = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
    let offsets: [i16; 13] = [0, 1, -1, 511, -511, 512, -512, 513, -513, 1023, -1023, 1024, -1024];
    for lanes in verilated_lanes() {
        let mut ls = NeighbourLockstep::new(lanes);
        for m in [[5, 1030, -3000], [1020, -4100, 2050], [-2560, 3584, 7]] {
            // A few other points far away, so that the point is not alone in its bank row.
            let grid = Grid::build(&[[-7000, -7000, -7000], m, [7000, 7000, 7000]]).unwrap();
            ls.upload(&grid).unwrap_or_else(|e| panic!("{m:?}, P = {lanes}: {e}"));
            let mut scan: Vec<FxPoint> = Vec::new();
            for a in offsets {
                for b in offsets {
                    scan.extend(offsets.iter().map(|&c| [m[0] + a, m[1] + b, m[2] + c]));
                }
            }
            let (got, points, _) = ls
                .particle_with_points(&scan, &id, |_| false, |_, _| {})
                .unwrap_or_else(|e| panic!("{m:?}, P = {lanes}: {e}"));
            let want = evaluate_grid(&grid, &scan, &id);
            assert_eq!(got, want, "{m:?}, P = {lanes}");
            assert_eq!(points, transformed(&scan, &id), "{m:?}, P = {lanes}: nn_point");
            assert!(want.nearest.iter().filter(|n| n.1 < pficp_fpga::search::grid::CAP_D2).count() == 783);
        }
    }
}
