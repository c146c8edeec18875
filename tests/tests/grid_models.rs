//! The board's grid search (`pficp_fpga::search::grid`) on the paper's models 1 to 3 as the host
//! quantises them (`pficp::board::quantise`): every normalised model fits the grid, the search
//! equals the capped brute force on their scans at the truth and at poses off it, and the
//! work it does (candidates a scan point, points capped) is printed for the design
//! (docs/search.md, "The grid and the cap").

use pficp::board::quantise::{normalised_pose, quantise_pose, Normalisation};
use pficp::datasets::{make, ModelId, Sampling, ScanSpec};
use pficp::geometry::Pose;
use pficp_fpga::common::format::transform;
use pficp_fpga::search::grid::{nearest_capped, Grid, NONE};

#[test]
fn the_models_fit_the_grid_and_the_search_is_the_capped_brute_force() {
    for id in ModelId::ALL {
        let truth = id.table1_truth();
        let ds =
            make(id, 2000, &truth, &ScanSpec { sampling: Sampling::Independent { points: 300 }, noise: 0.0, seed: 3 });
        let (nm, nd) = (Normalisation::of(&ds.scan), Normalisation::of(&ds.model));
        let (scan_q, model_q) = (nm.quantise(&ds.scan), nd.quantise(&ds.model));
        let grid = Grid::build(&model_q).unwrap_or_else(|e| panic!("{}: {e}", id.name()));
        for (label, offset) in [("truth", [0.0; 7]), ("5 deg, 5% off", [0.05, 0.0, 0.0, 0.0, 0.087, 0.0, 0.0])] {
            let mut p = truth.to_params();
            for (x, d) in p.iter_mut().zip(offset) {
                *x += d;
            }
            let fx = quantise_pose(&normalised_pose(&Pose::from_params(&p), &nm, &nd));
            let (mut candidates, mut capped) = (0, 0);
            for &s in &scan_q {
                let q = transform(&fx, s);
                let got = grid.nearest(q);
                assert_eq!(got, nearest_capped(&grid.points, q), "{} at {label}: query {q:?}", id.name());
                candidates += grid.candidates(q);
                capped += usize::from(got.index == NONE);
            }
            eprintln!(
                "{} at {label}: {:.1} candidates a scan point of {} ({:.1}%), {capped} of {} capped",
                id.name(),
                candidates as f64 / scan_q.len() as f64,
                model_q.len(),
                100.0 * candidates as f64 / (scan_q.len() * model_q.len()) as f64,
                scan_q.len()
            );
        }
    }
}
