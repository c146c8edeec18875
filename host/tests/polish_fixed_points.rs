//! How many of the on-board polish's steps change anything: for each case of the realistic
//! benchmark's dev split (seed 1) and each of 8 starts (the filter's pose and the search's
//! first 7 hypotheses), the step after which the polish is at an exact fixed point (the
//! pose unchanged and the next gate equal to this one's, so every later step repeats this
//! one: stopping there gives the same pose to the bit). Prints the cumulative histogram by
//! family (index `k`: fixed after `k` steps; the last: not within 10) and the steps an exact
//! early stop would leave of 10 a start.
//!
//! Slow (about a minute for 25 cases a family): ignored by default. `PFICP_CASES=25 cargo
//! test --release -p pficp-host --test polish_fixed_points -- --ignored --nocapture`.

use pficp::board::on_board::{self, plan, OnBoardPlan};
use pficp::board::quantise::{normalised_pose, quantise_pose};
use pficp::eval::realistic::{case, Family, Split};
use pficp::geometry::Pose;
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::PfIcpSettings;
use pficp_fpga::common::format::FxPose;
use pficp_fpga::polish::{gate, pass_over, solve, update};
use pficp_fpga::surface::GridSearch;
use rayon::prelude::*;

fn on_board_pose(plan: &OnBoardPlan, pose: &Pose) -> FxPose {
    quantise_pose(&normalised_pose(pose, &plan.scan_norm, &plan.model_norm))
}

#[test]
#[ignore = "a minute in release; prints how many steps change the pose"]
fn the_steps_before_an_exact_fixed_point() {
    let cases: usize = std::env::var("PFICP_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(25);
    // hist[k]: starts whose exact fixed point came after k steps (11: not within 10), over
    // the families so far.
    let mut hist = [0usize; 12];
    let mut moved_last = 0usize;
    for family in Family::PLANE_CUT {
        let rows: Vec<Vec<usize>> = (0..cases)
            .into_par_iter()
            .map(|i| {
                let c = case(family, i, Split::Dev, 1);
                let nn = NearestNeighbours::new(&c.model);
                let settings = PfIcpSettings { seed: c.seed, ..Default::default() };
                let plan =
                    plan(&nn, &c.scan, &settings, on_board::DEFAULT_BOARD_POINTS, pficp::board::BOARD_MAX_STORE_POINTS)
                        .expect("a plan");
                let filter = plan.emulate_filter();
                let search = GridSearch { grid: &plan.grid, normals: &plan.normals };
                let stored = plan.stored_scan();
                let starts: Vec<FxPose> = std::iter::once(filter.pose)
                    .chain(plan.prior.hypotheses.iter().take(7).map(|h| on_board_pose(&plan, &h.pose)))
                    .collect();
                starts
                    .iter()
                    .map(|s| {
                        let mut pose = *s;
                        let mut last = pass_over(&search, &stored, &pose, None, pficp_fpga::polish::ScaleStep::Solved);
                        for k in 0..10 {
                            let Some(tau2) = gate(&last) else { return k };
                            let sums =
                                pass_over(&search, &stored, &pose, Some(tau2), pficp_fpga::polish::ScaleStep::Solved);
                            let Some(step) = solve(&sums) else { return k };
                            let next = update(&pose, &step);
                            let same = next == pose && gate(&sums) == Some(tau2);
                            last = sums;
                            pose = next;
                            if same {
                                return k;
                            }
                        }
                        11
                    })
                    .collect()
            })
            .collect();
        for r in rows {
            for k in r {
                hist[k] += 1;
                moved_last += (k == 11) as usize;
            }
        }
        println!("{}: {hist:?}", family.name());
    }
    let total: usize = hist.iter().sum();
    let runs = cases * Family::PLANE_CUT.len();
    assert!((runs..=8 * runs).contains(&total), "{total} starts over {runs} cases: 1 to 8 a case");
    let steps: usize = hist.iter().enumerate().map(|(k, n)| k.min(10) * n).sum();
    println!("starts {total}, steps needed {steps} of {}, not fixed within 10: {moved_last}", total * 10);
}
