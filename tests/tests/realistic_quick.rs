//! The realistic benchmark's quick form (`pficp eval --suite realistic --quick`: 8 cases
//! per family, test split, seed 1) with a success floor, so that the global registration
//! cannot silently regress. The figures of the full benchmark (100 cases a family) are in
//! docs/benchmarks.md.

use pficp::eval::realistic::{self, Family, RealisticOptions};

#[test]
fn quick_realistic_benchmark_keeps_its_success_floor() {
    let opts =
        RealisticOptions { cases: 8, families: Family::PLANE_CUT.to_vec(), progress: false, ..Default::default() };
    let report = realistic::run(&opts).expect("the benchmark runs");
    print!("{}", report.render());
    let mut total = 0;
    for f in &report.families {
        let cell = &f.cells[0];
        assert_eq!(cell.method, "pf-icp");
        assert_eq!(cell.cases, 8);
        total += cell.successes;
        // At the time of writing: 7/8 in every family.
        let floor = if f.family == Family::Hard180 { 5 } else { 6 };
        assert!(cell.successes >= floor, "{}: {}/8 below the floor {floor}", f.family.name(), cell.successes);
        // Every successful case's truth lies in its reported 95% region but at most one.
        let inside = f
            .cases
            .iter()
            .filter(|c| c.results[0].score.success)
            .filter(|c| c.results[0].inside_95 == Some(true))
            .count();
        assert!(
            inside + 1 >= cell.successes,
            "{}: truth inside the 95% region in {inside}/{}",
            f.family.name(),
            cell.successes
        );
    }
    assert!(total >= 26, "{total}/32 below the floor 26");
}
