//! The grid pipeline's cycle model (`fpga::grid_pipeline`) against the grid search's
//! reference: every scan point's result is `grid::nearest_capped` over the stored model
//! (capped as index 0, distance `CAP_D2`) and agrees with `Grid::nearest`; on random models
//! in the cube, scans under poses that put points outside it, gaps in the scan stream,
//! several particles back to back and model rewrites between them.

use pficp_fpga::format::{pack_point, MAX_POINTS};
use pficp_fpga::format::{FxPoint, FxPose};
use pficp_fpga::grid::{Grid, CAP_D2, CELLS, CELL_LSBS, NONE};
use pficp_fpga::grid_pipeline::{
    clocks_bound, clocks_per_particle, evaluate_grid, evaluate_stored, run_particle, upload, GridInputs,
    GridPipelineModel, MAX_ROWS,
};
use proptest::prelude::*;

fn inside_coord() -> impl Strategy<Value = i16> {
    prop_oneof![
        2 => -8192i16..=8192,
        1 => (0i16..=16, -3i16..3).prop_map(|(k, d)| (-8192 + k * CELL_LSBS as i16 + d).clamp(-8192, 8192)),
    ]
}

fn model() -> impl Strategy<Value = Vec<FxPoint>> {
    prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 1..200)
}

fn pose() -> impl Strategy<Value = FxPose> {
    // Rotations about z by any angle with a translation of up to 1.5 (points leave the cube).
    (-3.2f64..3.2, [-1.5f64..1.5, -1.5f64..1.5, -1.5f64..1.5]).prop_map(|(a, t)| {
        let (s, c) = a.sin_cos();
        FxPose::from_f64(&[c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0], &t)
    })
}

fn check(
    pipe: &mut GridPipelineModel,
    g: &Grid,
    scan: &[FxPoint],
    pose: &FxPose,
    gaps: bool,
) -> Result<(), TestCaseError> {
    let want = evaluate_grid(g, scan, pose);
    let got = run_particle(pipe, scan, pose, |c| gaps && c % 3 == 1).evaluation;
    prop_assert_eq!(&got, &want);
    for (k, &(i, d)) in got.nearest.iter().enumerate() {
        let n = g.nearest(pficp_fpga::format::transform(pose, scan[k]));
        prop_assert_eq!((if n.index == NONE { 0 } else { n.index }, n.d2), (i, d));
        prop_assert_eq!(d == CAP_D2, n.index == NONE);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 120, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn the_cycle_model_is_the_capped_search(
        lanes in prop::sample::select(vec![1usize, 3, 4, 16]),
        m1 in model(),
        m2 in model(),
        scan in prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 1..60),
        p1 in pose(),
        p2 in pose(),
    ) {
        let mut pipe = GridPipelineModel::new(lanes);
        let g1 = Grid::build(&m1).unwrap();
        for w in upload(&g1) {
            pipe.step(&w);
        }
        check(&mut pipe, &g1, &scan, &p1, false)?;
        check(&mut pipe, &g1, &scan, &p2, true)?;
        // Rewrite model and table, then back to back again.
        let g2 = Grid::build(&m2).unwrap();
        for w in upload(&g2) {
            pipe.step(&w);
        }
        check(&mut pipe, &g2, &scan, &p2, false)?;
        check(&mut pipe, &g2, &scan, &p1, false)?;
    }

    /// The board's reference over raw stores equals the cycle model on any store and any
    /// table (entries up to 8,191, ranges reversed or past the model, addresses wrapping),
    /// and equals the capped search when the table is the model's.
    #[test]
    fn the_stored_reference_is_the_cycle_model_on_any_table(
        lanes in prop::sample::select(vec![1usize, 3, 4, 16]),
        m in model(),
        entries in prop::collection::vec((0usize..=CELLS, prop_oneof![0u16..300, 3900u16..4400, 0u16..8192]), 0..400),
        scan in prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 1..40),
        p in pose(),
    ) {
        let g = Grid::build(&m).unwrap();
        let mut pipe = GridPipelineModel::new(lanes);
        let mut ram = vec![0u64; MAX_POINTS];
        let mut first = vec![0u16; CELLS + 1];
        for w in upload(&g) {
            pipe.step(&w);
        }
        for (a, &q) in g.points.iter().enumerate() {
            ram[a] = pack_point(q);
        }
        first.copy_from_slice(&g.first);
        let want = run_particle(&mut pipe, &scan, &p, |_| false).evaluation;
        prop_assert_eq!(&evaluate_stored(&ram, &first, lanes, &scan, &p), &want);
        prop_assert_eq!(&evaluate_grid(&g, &scan, &p), &want);
        // Overwrite table entries with anything, and some model words past the model.
        for &(a, v) in &entries {
            pipe.step(&GridInputs { table_we: true, table_waddr: a as u16, table_wdata: v, ..Default::default() });
            first[a] = v;
        }
        for (k, &(_, v)) in entries.iter().take(60).enumerate() {
            let a = (4096 - 1 - k * 7) % MAX_POINTS;
            let q = [v as i16 - 4096, (k as i16) * 100 - 3000, 17];
            pipe.step(&GridInputs { model_we: true, model_waddr: a as u16, model_wdata: pack_point(q), ..Default::default() });
            ram[a] = pack_point(q);
        }
        let got = run_particle(&mut pipe, &scan, &p, |c| c % 5 == 2).evaluation;
        prop_assert_eq!(&evaluate_stored(&ram, &first, lanes, &scan, &p), &got);
    }
}

#[test]
fn a_lone_point_and_an_empty_box() {
    let g = Grid::build(&[[0, 0, 0]]).unwrap();
    let mut pipe = GridPipelineModel::new(4);
    for w in upload(&g) {
        pipe.step(&w);
    }
    let id = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
    // Near, exactly one cell away (capped), and far outside the cube (no rows at all).
    let scan = [[100, 0, 0], [1024, 0, 0], [-1023, 0, 0], [30000, -30000, 30000]];
    let r = run_particle(&mut pipe, &scan, &id, |_| false);
    assert_eq!(r.evaluation.nearest, vec![(0, 10000), (0, CAP_D2), (0, 1023 * 1023), (0, CAP_D2)]);
    assert_eq!(r.evaluation, evaluate_grid(&g, &scan, &id));
    // A batch entirely outside: no row, no address.
    let r = run_particle(&mut pipe, &[[30000, 30000, 30000]], &id, |_| false);
    assert_eq!((r.evaluation.nearest.clone(), r.swept), (vec![(0, CAP_D2)], 0));
    // start while busy is ignored.
    pipe.step(&GridInputs { start: true, pose: id, ..Default::default() });
    assert!(pipe.outputs().busy);
    pipe.step(&GridInputs { start: true, ..Default::default() });
    assert!(pipe.outputs().scan_ready);
}

/// A model point in cell `(x, y, z)`, `d` LSBs into it.
fn in_cell(x: i16, y: i16, z: i16, d: i16) -> FxPoint {
    [x, y, z].map(|k| -8192 + k * CELL_LSBS as i16 + d)
}

/// A model of 0 to 3 points in a random cell of each row (the rows that stall most: empty
/// and one-point ones), or points anywhere.
fn row_model() -> impl Strategy<Value = Vec<FxPoint>> {
    prop_oneof![
        prop::collection::vec((0i16..16, 0usize..4, 0i16..1024), 256).prop_map(|rows| {
            let mut m = Vec::new();
            for (r, &(x, count, d)) in rows.iter().enumerate() {
                for k in 0..count {
                    m.push(in_cell(x, (r % 16) as i16, (r / 16) as i16, (d + 97 * k as i16) % 1024));
                }
            }
            if m.is_empty() {
                m.push([0; 3]);
            }
            m
        }),
        model(),
    ]
}

/// A scan whose batches span the whole grid (two opposite corners first), then points
/// anywhere, inside the cube or not.
fn spanning_scan() -> impl Strategy<Value = Vec<FxPoint>> {
    prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 0..70).prop_map(|mut s| {
        s.insert(0, [8000, 8000, 8000]);
        s.insert(0, [-8100, -8100, -8100]);
        s
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, failure_persistence: None, ..ProptestConfig::default() })]

    /// `clocks_bound` (the host's deadlines) is never below the cycle model's count.
    #[test]
    fn the_clock_bound_holds(
        lanes in prop::sample::select(vec![1usize, 2, 3, 4, 16]),
        m in row_model(),
        scan in spanning_scan(),
        p in prop_oneof![Just(identity()), pose()],
    ) {
        let g = Grid::build(&m).unwrap();
        let r = clocks_per_particle(&g, &scan, &p, lanes);
        let bound = clocks_bound(scan.len(), m.len(), lanes);
        prop_assert!(r.clocks <= bound, "{} clocks above the bound {bound}", r.clocks);
    }
}

fn identity() -> FxPose {
    FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3])
}

/// The bound's worst cases: every row of the grid swept, each holding one point (two
/// clocks for one address) or none with one-point rows between (one clock of lookup each);
/// the bound is within a clock a row of them, and is the brute-force count plus
/// `MAX_ROWS + 3` a batch.
#[test]
fn the_clock_bound_is_tight_on_rows_that_stall() {
    let corners = [[-8100, -8100, -8100], [8000, 8000, 8000]];
    let every_row: Vec<FxPoint> = (0..256).map(|r| in_cell(7, r % 16, r / 16, 500)).collect();
    let every_other: Vec<FxPoint> = (0..256).step_by(2).map(|r| in_cell(3, r % 16, r / 16, 9)).collect();
    for (name, m) in [("every row", every_row), ("every other row", every_other)] {
        let g = Grid::build(&m).unwrap();
        for lanes in [2, 16] {
            let r = clocks_per_particle(&g, &corners, &identity(), lanes);
            let bound = clocks_bound(2, m.len(), lanes);
            eprintln!("{name}, {lanes} lanes: {} clocks, bound {bound}", r.clocks);
            assert!(r.clocks <= bound && bound - r.clocks <= 16, "{name}: {} clocks, bound {bound}", r.clocks);
        }
    }
    assert_eq!(
        clocks_bound(300, 2000, 16),
        pficp_fpga::pipeline::clocks_per_particle(300, 2000, 16) + 19 * (MAX_ROWS + 3)
    );
    assert_eq!(clocks_bound(0, 2000, 16), 1);
}
