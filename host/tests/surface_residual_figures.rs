//! What the surface residual (`pficp_fpga::surface`, protocol 4) changed on the board: the
//! board's pose alone (no host polish) with the protocol 3 board's cost (point-to-point,
//! capped) and with the residual along the nearest stored point's normal, on the realistic benchmark's
//! quick set (8 cases a family, seed 1), the board sample of `on_board::DEFAULT_BOARD_POINTS`
//! scan points. Both columns run `pficp_fpga::filter::pf::run`, the board's bit-exact filter, on the
//! same plan; only the cost differs.
//!
//! Slow (a minute or two): ignored by default. Run it with
//! `cargo test --release -p pficp-host --test surface_residual_figures -- --ignored --nocapture`
//! (`PFICP_SPLIT=test` for the test split, default dev; `PFICP_BOARD_POINTS=N` for another
//! sample size). The tables it printed are in docs/board-modes.md, "The surface residual".

use pficp::board::on_board::{self, plan};
use pficp::eval::realistic::{case, score, Family, Split};
use pficp::nn::NearestNeighbours;
use pficp::pf_icp::PfIcpSettings;
use rayon::prelude::*;

#[test]
#[ignore = "a minute or two in release; prints the table of docs/board-modes.md"]
fn the_board_alone_with_the_surface_residual() {
    let split = if std::env::var("PFICP_SPLIT").is_ok_and(|v| v == "test") { Split::Test } else { Split::Dev };
    let points =
        std::env::var("PFICP_BOARD_POINTS").ok().and_then(|v| v.parse().ok()).unwrap_or(on_board::DEFAULT_BOARD_POINTS);
    println!("split {split:?}, seed 1, 8 cases a family, {points} board points; the board's pose alone");
    println!("| family | point-to-point (protocol 3) | surface residual (the board) | + tangential excess (f64, not a board rule) |");
    println!("|---|---|---|---|");
    let mut totals = [0usize; 4];
    for family in Family::PLANE_CUT {
        let rows: Vec<(String, [bool; 3], [String; 3])> = (0..8)
            .into_par_iter()
            .map(|i| {
                let c = case(family, i, split, 1);
                let nn = NearestNeighbours::new(&c.model);
                let settings = PfIcpSettings { seed: c.seed, ..Default::default() };
                let plan = plan(&nn, &c.scan, &settings, points, pficp::board::BOARD_MAX_STORE_POINTS).expect("plan");
                let outs = [point_to_point_filter(&plan), plan.emulate_filter(), excess_filter(&plan, &plan.normals)];
                let scores =
                    outs.map(|o| score(&on_board::params_pose(&o.params, &plan.model_norm, &plan.scan_norm), &c));
                let ok = [scores[0].success, scores[1].success, scores[2].success];
                let text = scores.map(|s| {
                    format!(
                        "{:.2} deg, {:.2}% tr, {:.2}% sc",
                        s.rotation_deg,
                        100.0 * s.translation_frac,
                        100.0 * s.scale_frac
                    )
                });
                (c.id.clone(), ok, text)
            })
            .collect();
        let count = |k: usize| rows.iter().filter(|r| r.1[k]).count();
        println!("| {} | {}/8 | {}/8 | {}/8 |", family.name(), count(0), count(1), count(2));
        for r in &rows {
            if !(r.1[0] && r.1[1] && r.1[2]) {
                eprintln!(
                    "  {}: point-to-point {} ({}), surface {} ({}), + excess {} ({})",
                    r.0, r.1[0], r.2[0], r.1[1], r.2[1], r.1[2], r.2[2]
                );
            }
        }
        totals[0] += count(0);
        totals[1] += count(1);
        totals[2] += count(2);
        totals[3] += 8;
    }
    println!("| all | {}/{n} | {}/{n} | {}/{n} |", totals[0], totals[1], totals[2], n = totals[3]);
    // The residual is the better cost on this set or the change is wrong.
    assert!(totals[1] >= totals[0], "the surface residual lost cases: {} against {}", totals[1], totals[0]);
}

/// The protocol 3 board's filter: the cost the capped squared distances of the grid search
/// (`Grid::nearest`), the largest of them beside it.
fn point_to_point_filter(plan: &on_board::OnBoardPlan) -> pficp_fpga::filter::pf::PfOutcome {
    pficp_fpga::filter::pf::run(&plan.config, |pose| {
        let d2: Vec<u64> =
            plan.scan.iter().map(|&p| plan.grid.nearest(pficp_fpga::common::format::transform(pose, p)).d2).collect();
        let cost = d2.iter().fold(0u64, |c, &x| (c + x) & pficp_fpga::common::format::COST_MASK);
        pficp_fpga::filter::pf::Evaluated { cost, max_d2: d2.iter().copied().max().unwrap_or(0) }
    })
}

/// The filter with the software's surface distance (`pf_icp::surface`: the residual plus the
/// tangential excess beyond the model's spacing, `(|d_t| - h)^2`) in f64 on the same stores:
/// what a board rule with the excess term would approach (it needs a square root; not built).
fn excess_filter(
    plan: &on_board::OnBoardPlan,
    normals: &[pficp_fpga::surface::FxNormal],
) -> pficp_fpga::filter::pf::PfOutcome {
    use pficp_fpga::search::grid::{CAP_D2, NONE};
    let g = &plan.grid;
    let mut gaps: Vec<f64> = g
        .points
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let near = g
                .ranges(p)
                .into_iter()
                .flatten()
                .filter(|&j| j != i && g.points[j] != p)
                .map(|j| pficp_fpga::common::format::dist2(p, g.points[j]))
                .min()
                .unwrap_or(CAP_D2);
            (near as f64).sqrt()
        })
        .collect();
    gaps.sort_by(f64::total_cmp);
    let h = gaps[gaps.len() / 2];
    pficp_fpga::filter::pf::run(&plan.config, |pose| {
        let mut cost = 0u64;
        let mut max_d2 = 0u64;
        for &p in &plan.scan {
            let q = pficp_fpga::common::format::transform(pose, p);
            let nr = g.nearest(q);
            let r = if nr.index == NONE {
                CAP_D2
            } else {
                let m = g.points[nr.index as usize];
                let n = normals[nr.index as usize];
                let a: f64 = (0..3).map(|k| n[k] as f64 / 16384.0 * (q[k] as f64 - m[k] as f64)).sum();
                let t = (nr.d2 as f64 - a * a).max(0.0).sqrt();
                let e = (t - h).max(0.0);
                ((a * a + e * e) as u64).min(CAP_D2)
            };
            cost += r;
            max_d2 = max_d2.max(r);
        }
        pficp_fpga::filter::pf::Evaluated { cost, max_d2 }
    })
}
