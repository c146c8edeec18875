//! The camera-view families' quick form (`pficp eval --suite realistic --quick --family
//! camera,camera-any,camera-metric,camera-any-metric`: 8 cases a family, test split, seed 1)
//! with a success floor, no confidently wrong result, and a fixed scale that nothing moves.
//! The figures of the full benchmark (100 cases a family) are in docs/benchmarks.md.

use pficp::eval::realistic::{self, Family, RealisticOptions};

#[test]
fn quick_camera_benchmark_keeps_its_floor_and_never_says_confident_when_wrong() {
    let opts = RealisticOptions { cases: 8, families: Family::CAMERA.to_vec(), progress: false, ..Default::default() };
    let report = realistic::run(&opts).expect("the benchmark runs");
    print!("{}", report.render());
    let mut total = 0;
    for f in &report.families {
        let cell = &f.cells[0];
        assert_eq!((cell.method.as_str(), cell.cases), ("pf-icp", 8));
        total += cell.successes;
        // At the time of writing: 7/8, 8/8, 8/8, 8/8.
        assert!(cell.successes >= 6, "{}: {}/8 below the floor 6", f.family.name(), cell.successes);
        let v = cell.verdicts.expect("PF-ICP gives verdicts");
        assert_eq!(v.confident_wrong, 0, "{}: a confidently wrong pose", f.family.name());
        assert!(v.right_or_flagged >= 7, "{}: {} right or flagged", f.family.name(), v.right_or_flagged);
        // With the scale known (1), every result has exactly that scale.
        if f.family.known_scale().is_some() {
            for c in &f.cases {
                assert_eq!(c.results[0].score.scale_frac, 0.0, "{}: the fixed scale moved", c.id);
            }
        }
    }
    assert!(total >= 28, "{total}/32 below the floor 28");
}
