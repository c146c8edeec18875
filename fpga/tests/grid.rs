//! The grid search against the brute-force capped search it must equal (`fpga::search::grid`'s
//! rule), on random models (surfaces, clumps on cell boundaries, the cube's corners) and
//! queries anywhere in the coordinate range; and the work it saves on two surfaces.

use pficp_fpga::common::format::{self, FxPoint};
use pficp_fpga::search::grid::{nearest_capped, Grid, CAP_D2, CELL_LSBS, NONE};
use proptest::prelude::*;

/// A coordinate inside the grid's cube, drawn near cell boundaries a third of the time.
fn inside_coord() -> impl Strategy<Value = i16> {
    prop_oneof![
        2 => -8192i16..=8192,
        1 => (0i16..=16, -3i16..3).prop_map(|(k, d)| (-8192 + k * CELL_LSBS as i16 + d).clamp(-8192, 8192)),
    ]
}

fn model() -> impl Strategy<Value = Vec<FxPoint>> {
    prop::collection::vec([inside_coord(), inside_coord(), inside_coord()], 1..300)
}

/// A query: anywhere, or within a few cells of a model point.
fn query(model_len: usize) -> impl Strategy<Value = (Option<usize>, FxPoint)> {
    prop_oneof![
        any::<[i16; 3]>().prop_map(|q| (None, q)),
        (0..model_len, [-2500i16..2500, -2500i16..2500, -2500i16..2500]).prop_map(|(i, d)| (Some(i), d)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn the_grid_search_equals_the_capped_brute_force(
        (m, qs) in model().prop_flat_map(|m| { let n = m.len(); (Just(m), prop::collection::vec(query(n), 1..40)) })
    ) {
        let g = Grid::build(&m).unwrap();
        for (near, q) in qs {
            let q = match near {
                Some(i) => {
                    let p = m[i];
                    [0, 1, 2].map(|k| p[k].saturating_add(q[k]))
                }
                None => q,
            };
            let got = g.nearest(q);
            prop_assert_eq!(got, nearest_capped(&g.points, q), "query {:?}", q);
            prop_assert!(got.d2 <= CAP_D2);
            prop_assert_eq!(got.index == NONE, got.d2 == CAP_D2);
        }
    }
}

#[test]
fn exact_points_and_far_points() {
    let model: Vec<FxPoint> = vec![[0, 0, 0], [1024, 0, 0], [0, 0, 0]];
    let g = Grid::build(&model).unwrap();
    // The duplicate point: the lower stored index wins.
    let n = g.nearest([0, 0, 0]);
    assert_eq!((n.d2, g.order[n.index as usize]), (0, 0));
    // Exactly one cell away along x is still found (d2 = h^2 is reported as the cap).
    assert_eq!(g.nearest([-1024, 0, 0]).d2, CAP_D2);
    assert_eq!(g.nearest([-1023, 0, 0]).d2, 1023 * 1023);
    // Far outside the cube: capped.
    assert_eq!(g.nearest([i16::MAX, i16::MIN, 0]).index, NONE);
}

/// The work the grid saves: mean candidates a query over brute force, on a sphere and a
/// plane of 2,000 points each (the queries are the model's own points).
#[test]
fn the_grid_reads_a_small_share_of_the_model() {
    for (name, model) in [("sphere", sphere(2000)), ("plane", plane(2000))] {
        let g = Grid::build(&model).unwrap();
        let mean = model.iter().map(|&q| g.candidates(q)).sum::<usize>() as f64 / model.len() as f64;
        eprintln!(
            "{name}: {mean:.1} candidates a point of {} ({:.1}%)",
            model.len(),
            100.0 * mean / model.len() as f64
        );
        assert!(mean < 0.2 * model.len() as f64, "{name}: {mean}");
    }
}

/// `n` points on the sphere of radius 0.9 (a Fibonacci lattice).
fn sphere(n: usize) -> Vec<FxPoint> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - y * y).sqrt();
            let a = golden * i as f64;
            format::point([0.9 * r * a.cos(), 0.9 * y, 0.9 * r * a.sin()])
        })
        .collect()
}

/// `n` points on a tilted square plane through the origin.
fn plane(n: usize) -> Vec<FxPoint> {
    let side = (n as f64).sqrt().ceil() as usize;
    (0..n)
        .map(|i| {
            let (u, v) = ((i % side) as f64 / side as f64 - 0.5, (i / side) as f64 / side as f64 - 0.5);
            format::point([1.2 * u, 0.6 * v, 0.3 * u + 0.8 * v])
        })
        .collect()
}
