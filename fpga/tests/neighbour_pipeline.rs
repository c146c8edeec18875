//! The neighbour pipeline's cycle model (`fpga::search::neighbour_pipeline`) against its functional
//! reference over the raw stores (`evaluate_stored`, any table) and, with the model's own
//! table, against the capped search (`grid::evaluate_grid`, `Grid::nearest`): random
//! models in the cube, scans under poses that put points outside it, gaps in the scan
//! stream, particles back to back, model and table rewrites, tables of anything.

use pficp_fpga::common::format::{pack_point, transform, FxPoint, FxPose, MAX_POINTS};
use pficp_fpga::search::grid::{evaluate_grid, Grid, CAP_D2, CELLS, CELL_LSBS, NONE};
use pficp_fpga::search::neighbour_pipeline::{
    chunks_of, clocks_bound, clocks_per_particle, evaluate_stored, lookups_of, run_particle, upload, GridInputs,
    NeighbourPipelineModel, BOUND_FILL, BOUND_POINT_EXTRA,
};
use proptest::prelude::*;

fn inside_coord() -> impl Strategy<Value = i16> {
    prop_oneof![
        2 => -8192i16..=8192,
        1 => (0i16..=16, -3i16..3).prop_map(|(k, d)| (-8192 + k * CELL_LSBS as i16 + d).clamp(-8192, 8192)),
    ]
}

fn model() -> impl Strategy<Value = Vec<FxPoint>> {
    prop_oneof![
        prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 1..200),
        // Dense cells: long rows, many chunks a row.
        (prop::collection::vec([-600i16..600, -600i16..600, -600i16..600], 1..300))
    ]
}

fn pose() -> impl Strategy<Value = FxPose> {
    // Rotations about z by any angle with a translation of up to 1.5 (points leave the cube).
    (-3.2f64..3.2, [-1.5f64..1.5, -1.5f64..1.5, -1.5f64..1.5]).prop_map(|(a, t)| {
        let (s, c) = a.sin_cos();
        FxPose::from_f64(&[c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0], &t)
    })
}

fn stores(g: &Grid) -> (Vec<u64>, Vec<u16>) {
    let mut ram = vec![0u64; MAX_POINTS];
    for (a, &q) in g.points.iter().enumerate() {
        ram[a] = pack_point(q);
    }
    (ram, g.first.clone())
}

fn check(
    pipe: &mut NeighbourPipelineModel,
    g: &Grid,
    scan: &[FxPoint],
    pose: &FxPose,
    gaps: u64,
) -> Result<(), TestCaseError> {
    let want = evaluate_grid(g, scan, pose);
    let got = run_particle(pipe, scan, pose, |c| gaps > 0 && c % (gaps + 1) == 1).evaluation;
    prop_assert_eq!(&got, &want);
    let (ram, first) = stores(g);
    prop_assert_eq!(&evaluate_stored(&ram, &first, scan, pose), &want);
    for (k, &(i, d)) in got.nearest.iter().enumerate() {
        let n = g.nearest(transform(pose, scan[k]));
        prop_assert_eq!((if n.index == NONE { 0 } else { n.index }, n.d2), (i, d));
        prop_assert_eq!(d == CAP_D2, n.index == NONE);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 120, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn the_cycle_model_is_the_capped_search(
        lanes in prop::sample::select(vec![1usize, 2, 4, 16]),
        m1 in model(),
        m2 in model(),
        scan in prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 1..60),
        p1 in pose(),
        p2 in pose(),
        gaps in 0u64..4,
    ) {
        let mut pipe = NeighbourPipelineModel::new(lanes);
        let g1 = Grid::build(&m1).unwrap();
        for w in upload(&g1) {
            pipe.step(&w);
        }
        check(&mut pipe, &g1, &scan, &p1, 0)?;
        check(&mut pipe, &g1, &scan, &p2, gaps)?;
        let g2 = Grid::build(&m2).unwrap();
        for w in upload(&g2) {
            pipe.step(&w);
        }
        check(&mut pipe, &g2, &scan, &p2, 0)?;
        check(&mut pipe, &g2, &scan, &p1, gaps)?;
    }

    /// The functional reference over raw stores equals the cycle model on any store and any
    /// table (entries up to 8,191, ranges reversed or past the model, addresses wrapping).
    #[test]
    fn the_stored_reference_is_the_cycle_model_on_any_table(
        lanes in prop::sample::select(vec![1usize, 4, 8, 16]),
        m in model(),
        entries in prop::collection::vec((0usize..=CELLS, prop_oneof![0u16..300, 3900u16..4400, 0u16..8192]), 0..400),
        scan in prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 1..30),
        p in pose(),
    ) {
        let g = Grid::build(&m).unwrap();
        let mut pipe = NeighbourPipelineModel::new(lanes);
        for w in upload(&g) {
            pipe.step(&w);
        }
        let (mut ram, mut first) = stores(&g);
        for &(a, v) in &entries {
            pipe.step(&GridInputs { table_we: true, table_waddr: a as u16, table_wdata: v, ..Default::default() });
            first[a] = v;
        }
        // A write past the table writes nothing.
        pipe.step(&GridInputs { table_we: true, table_waddr: 4097 + (entries.len() as u16), table_wdata: 1, ..Default::default() });
        for (k, &(_, v)) in entries.iter().take(60).enumerate() {
            let a = (4096 - 1 - k * 7) % MAX_POINTS;
            let q = [v as i16 - 4096, (k as i16) * 100 - 3000, 17];
            pipe.step(&GridInputs { model_we: true, model_waddr: a as u16, model_wdata: pack_point(q), ..Default::default() });
            ram[a] = pack_point(q);
        }
        let got = run_particle(&mut pipe, &scan, &p, |c| c % 5 == 2).evaluation;
        prop_assert_eq!(&evaluate_stored(&ram, &first, &scan, &p), &got);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 150, failure_persistence: None, ..ProptestConfig::default() })]

    /// The issue takes `chunks_of` clocks a point (both rows of a slot in the same clocks),
    /// plus a marker where a point's last slot finds no range; and `clocks_bound` (for
    /// deadlines) is never below the cycle model's count.
    #[test]
    fn the_issue_takes_the_longer_row_of_a_slot_and_the_bound_holds(
        lanes in prop::sample::select(vec![1usize, 2, 4, 8, 16]),
        m in model(),
        scan in prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 1..60),
        p in pose(),
    ) {
        let g = Grid::build(&m).unwrap();
        let r = clocks_per_particle(&g, &scan, &p, lanes);
        let chunks: u64 = scan.iter().map(|&s| chunks_of(&g, transform(&p, s), lanes) as u64).sum();
        prop_assert!(r.chunks >= chunks && r.chunks <= chunks + scan.len() as u64, "{} issue clocks, chunks_of {chunks}", r.chunks);
        let lookups: u64 = scan.iter().map(|&s| lookups_of(transform(&p, s)) as u64).sum();
        prop_assert!(r.clocks >= chunks.max(lookups));
        let bound = clocks_bound(scan.len(), m.len(), lanes);
        prop_assert!(r.clocks <= bound, "{} clocks above the bound {bound}", r.clocks);
    }
}

/// Every point's five slots each holding one long row (the model in the five A rows around
/// one cell): four times a row's chunks a point and half of them for the split centre row,
/// within the bound.
#[test]
fn the_clock_bound_holds_on_long_rows() {
    let id = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
    // Rows (dz, dy) of slots 0..3's row A and slot 4's: (-1,-1) (-1,1) (0,1) (1,0) (0,0).
    let rows = [(-1, -1), (-1, 1), (0, 1), (1, 0), (0, 0)];
    for lanes in [1, 2, 4, 16] {
        for n in [5, 85, 400, 4000] {
            let per = n / rows.len();
            let model: Vec<FxPoint> = rows
                .iter()
                .flat_map(|&(dz, dy)| (0..per).map(move |i| [(i % 7) as i16 * 100, dy * 1024 + 500, dz * 1024 + 500]))
                .collect();
            let g = Grid::build(&model).unwrap();
            let scan = vec![[10, 510, 510]; 40];
            let r = clocks_per_particle(&g, &scan, &id, lanes);
            let bound = clocks_bound(scan.len(), model.len(), lanes);
            assert!(r.clocks <= bound, "{lanes} lanes, {n} points: {} clocks, bound {bound}", r.clocks);
            assert_eq!(r.chunks, 40 * chunks_of(&g, scan[0], lanes) as u64);
            assert_eq!(chunks_of(&g, scan[0], lanes), 4 * per.div_ceil(lanes) + per.div_ceil(2 * lanes));
        }
    }
}

/// Ties: two stored points at the same distance in one chunk (lane order is not index
/// order when the chunk starts mid-bank) and in two rows; the lowest index wins.
#[test]
fn ties_go_to_the_lowest_index() {
    let id = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
    // Cell (8, 8, 8) holds four points, two of them tied; a point in the row above ties too.
    let model = vec![[10, 10, 10], [50, 0, 0], [-50, 0, 0], [0, 0, 50], [0, 1030, 0], [0, -50, 0]];
    let g = Grid::build(&model).unwrap();
    for lanes in [1, 2, 4, 16] {
        let mut pipe = NeighbourPipelineModel::new(lanes);
        for w in upload(&g) {
            pipe.step(&w);
        }
        let r = run_particle(&mut pipe, &[[0, 0, 0], [0, 1030, 0], [5000, 5000, 5000]], &id, |_| false);
        assert_eq!(r.evaluation, evaluate_grid(&g, &[[0, 0, 0], [0, 1030, 0], [5000, 5000, 5000]], &id));
        assert_eq!(r.evaluation.nearest[2], (0, CAP_D2));
    }
    let mut ram = vec![0u64; MAX_POINTS];
    let mut first = vec![0u16; CELLS + 1];
    // Cell 0's range wraps: addresses 4094, 4095, 0, 1 hold the same point: index 0 wins.
    for a in [4094, 4095, 0, 1] {
        ram[a] = pack_point([-8000, -8000, -8000]);
    }
    first[1..].iter_mut().for_each(|f| *f = 4098);
    first[0] = 4094;
    let scan = [[-8000, -8000, -8001]];
    let e = evaluate_stored(&ram, &first, &scan, &id);
    assert_eq!(e.nearest, vec![(0, 1)]);
    for lanes in [1, 4, 16] {
        let mut pipe = NeighbourPipelineModel::new(lanes);
        for (a, &w) in ram.iter().enumerate() {
            pipe.step(&GridInputs { model_we: true, model_waddr: a as u16, model_wdata: w, ..Default::default() });
        }
        for (a, &f) in first.iter().enumerate() {
            pipe.step(&GridInputs { table_we: true, table_waddr: a as u16, table_wdata: f, ..Default::default() });
        }
        assert_eq!(run_particle(&mut pipe, &scan, &id, |_| false).evaluation, e);
    }
}

#[test]
fn start_while_busy_is_ignored_and_an_empty_model_caps_everything() {
    let mut pipe = NeighbourPipelineModel::new(4);
    let id = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
    let r = run_particle(&mut pipe, &[[0, 0, 0], [30000, -30000, 0]], &id, |_| false);
    assert_eq!(r.evaluation.nearest, vec![(0, CAP_D2); 2]);
    assert_eq!(r.evaluation.cost, 2 * CAP_D2);
    pipe.step(&GridInputs { start: true, pose: id, ..Default::default() });
    assert!(pipe.outputs().busy && pipe.outputs().scan_ready);
    pipe.step(&GridInputs { start: true, ..Default::default() });
    assert!(pipe.outputs().scan_ready);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 150, failure_persistence: None, ..ProptestConfig::default() })]

    /// `clocks_bound` (the host's deadlines) is never below the cycle model's count: dense
    /// and sparse models, scans inside, on and outside the grid, any lane count.
    #[test]
    fn the_clock_bound_holds(
        lanes in prop::sample::select(vec![2usize, 4, 8, 16]),
        m in model(),
        scan in prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 1..80),
        p in pose(),
    ) {
        let g = Grid::build(&m).unwrap();
        let r = clocks_per_particle(&g, &scan, &p, lanes);
        let bound = clocks_bound(scan.len(), m.len(), lanes);
        prop_assert!(r.clocks <= bound, "{} clocks above the bound {bound}", r.clocks);
    }
}

/// The bound's worst case: every model point in one cell, every scan point in the next cell
/// along `y` (one long row a point, not the centre row, which is split over both sides; the
/// others empty); the bound is above the count by at most the per-point extra and the rows'
/// rounding, and the fill. An empty neighbourhood (markers only) too.
#[test]
fn the_clock_bound_is_tight_on_one_dense_cell() {
    let id = FxPose::from_f64(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], &[0.0; 3]);
    let dense: Vec<FxPoint> = (0..2000).map(|i| [10 + (i % 40) as i16, 10 + (i / 40) as i16, 300]).collect();
    let g = Grid::build(&dense).unwrap();
    let near: Vec<FxPoint> = (0..50).map(|i| [20 + i as i16, 30 + 1024, 200]).collect();
    let far: Vec<FxPoint> = (0..50).map(|i| [-8000 + i as i16, 8000, -8000]).collect();
    for lanes in [2, 16] {
        for (name, scan) in [("dense", &near), ("empty", &far)] {
            let r = clocks_per_particle(&g, scan, &id, lanes);
            let bound = clocks_bound(scan.len(), dense.len(), lanes);
            eprintln!("{name}, {lanes} lanes: {} clocks, bound {bound}", r.clocks);
            assert!(r.clocks <= bound, "{name}: {} clocks above the bound {bound}", r.clocks);
            if name == "dense" {
                let slack = scan.len() as u64 * (BOUND_POINT_EXTRA + 9) + BOUND_FILL + 1;
                assert!(bound - r.clocks <= slack, "{name}: {} clocks, bound {bound}", r.clocks);
            }
        }
    }
    assert_eq!(clocks_bound(0, 2000, 16), 1 + BOUND_FILL);
}
